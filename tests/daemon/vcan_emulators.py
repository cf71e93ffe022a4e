# SPDX-License-Identifier: MIT
"""The firmware emulators of a shipped vcan cell, for tests that run mcad on the CAN backend in the guest:
each socketcan arm's vcan made and mca-armsim started on it in lockstep at the scenario's start position."""
import os
import re
import subprocess
import time


def arm_blocks(text):
    """The per-arm blocks ("  - name: ...") of a shipped cell or scenario file (no YAML module needed)."""
    return re.split(r"\n  - name: ", "\n" + text.split("\narms:\n", 1)[1])[1:]


def start_emulators(armsim, cell_src, tmp, extra=None, fifo=None, tag=""):
    """Each socketcan arm of the cell: its vcan (made here, as root in the guest) and mca-armsim in lockstep
    at the scenario's start position; extra: {arm index: [more mca-armsim arguments]}; fifo: SCHED_FIFO
    priority of the emulators (above mcad's loop on a 1-CPU guest, so that each command is answered at once,
    as real firmware would, instead of the emulators starving behind the loop); logs tmp/armsim<tag><k>.log."""
    cell = open(cell_src).read()
    scn_path = os.path.normpath(os.path.join(os.path.dirname(cell_src),
                                             re.search(r"scenario: *(\S+)", cell).group(1)))
    scn_arms = arm_blocks(open(scn_path).read())
    procs = []
    for k, arm in enumerate(arm_blocks(cell)):
        iface = re.search(r"interface: *(\S+)", arm).group(1)
        id_base = re.search(r"id_base: *(\S+)", arm).group(1)
        dec = re.search(r"dec_limit: *(\S+)", arm).group(1)
        if subprocess.run(["ip", "link", "show", iface], capture_output=True).returncode != 0:
            subprocess.run(["ip", "link", "add", "dev", iface, "type", "vcan"], check=True)
        subprocess.run(["ip", "link", "set", iface, "mtu", "72", "up"], check=True)
        urdf = os.path.normpath(os.path.join(os.path.dirname(scn_path),
                                             re.search(r"urdf: *(\S+)", scn_arms[k]).group(1)))
        q0 = re.search(r"q0: *\[([^\]]*)\]", scn_arms[k]).group(1).replace(" ", "")
        cmd = [armsim, "--iface", iface, "--robot", urdf, "--id-base", id_base, "--dec-limit", dec, "--q0", q0,
               "--lockstep"] + (extra or {}).get(k, [])
        procs.append(subprocess.Popen((["chrt", "-f", str(fifo)] if fifo else []) + cmd,
                                      stdout=open(os.path.join(tmp, f"armsim{tag}{k}.log"), "w"),
                                      stderr=subprocess.STDOUT))
        print(f"emulator {k}: {iface} id base {id_base}, {os.path.basename(urdf)}, q0 {q0}")
    time.sleep(1.0)
    return procs
