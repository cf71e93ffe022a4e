#!/bin/sh
# ctest entry of daemon_rt_syscalls_can: test_rt_syscalls.py --can (mcad on the CAN backend, the loop thread's
# system calls from the kernel's tracepoints against the allow-list of docs/daemon.md) in one QEMU guest boot.
# Usage: rt_syscalls_can.sh BUILD_DIR SOURCE_DIR PYTHON
B=$(cd "$1" && pwd) S=$(cd "$2" && pwd)
exec sh "$S/tests/daemon/in_guest.sh" "$B" "$S" rt-syscalls-can 1 "$3" "$S/tests/daemon/test_rt_syscalls.py" \
    "$B/daemon/mcad" "$S" 0 --can "$B/sim_backend/armsim_can/mca-armsim"
