#!/bin/sh
# Boot the vcan guest once and run JOB (a shell script on the host tree, same path in the guest chroot).
# The job's exit status comes back as this script's exit status (marker line on the serial console).
# Usage: run.sh CACHE_DIR JOB [TIMEOUT_S]
#   env: MCA_GUEST_LOG=file (serial console copy), MCA_GUEST_SMP=vCPUs (default 2)
#        MCA_GUEST_SYSTEMD=RESULTS_DIR: boot the host's systemd instead (init.sh, mcainit=systemd): the host /
#        shared read-only under a tmpfs overlay, RESULTS_DIR shared writable at /mca-results; JOB prepares the
#        overlay root and its units print the MCA-GUEST-EXIT= marker on /dev/ttyS0 and power off
set -eu
cache=${1:?usage: run.sh CACHE_DIR JOB [TIMEOUT_S]}
job=${2:?usage: run.sh CACHE_DIR JOB [TIMEOUT_S]}
tmo=${3:-600}
here=$(cd "$(dirname "$0")" && pwd)
command -v qemu-system-x86_64 >/dev/null 2>&1 || { echo "vcan-guest: qemu-system-x86_64 missing (apt-get install qemu-system-x86)" >&2; exit 1; }
"$here/build-image.sh" "$cache"
cache=$(cd "$cache" && pwd)
case "$job" in /*) ;; *) job="$(pwd)/$job" ;; esac
[ -r "$job" ] || { echo "vcan-guest: job $job not readable" >&2; exit 1; }
log=${MCA_GUEST_LOG:-$cache/console.log}
share=local,path=/,mount_tag=host,security_model=passthrough,id=host,multidevs=remap
append=
results=
if [ -n "${MCA_GUEST_SYSTEMD:-}" ]; then
    mkdir -p "$MCA_GUEST_SYSTEMD"
    share=$share,readonly=on
    append=" mcainit=systemd"
    results="-virtfs local,path=$(cd "$MCA_GUEST_SYSTEMD" && pwd),mount_tag=results,security_model=passthrough,id=results"
fi
# TCG (KVM hangs on these hosts); 9p shares the host / so the guest runs the build tree in place.
timeout -k 10 "$tmo" qemu-system-x86_64 -machine q35 -accel tcg -cpu max -m 1024 -smp "${MCA_GUEST_SMP:-2}" \
    -nographic -no-reboot -nodefaults -serial stdio -net none \
    -kernel "$cache/vmlinuz" -initrd "$cache/initrd.gz" \
    -append "console=ttyS0 quiet loglevel=3 panic=-1 mcajob=$job$append" \
    -virtfs "$share" $results \
    </dev/null >"$log" 2>&1 || true
cat "$log"
rc=$(sed -n 's/.*MCA-GUEST-EXIT=\([0-9]*\).*/\1/p' "$log" | tail -n 1)
if [ -z "$rc" ]; then
    echo "vcan-guest: FAIL: the guest did not report an exit status (timeout ${tmo}s or boot failure; see $log)" >&2
    exit 1
fi
exit "$rc"
