#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Shipped cells as they are, seen by ROS 2 nodes as a user runs them (docs/ros2.md "Network"): two
network namespaces joined by a veth pair stand for two machines, each with lo as a real host has it (no
multicast flag) and a network interface eth1 (controller 192.168.10.2, monitoring host .3, a default route).
For each cell given: mcad runs the shipped file unchanged (its dds.config, domain 0) in the controller
namespace, with --csv; three rclpy nodes (Fast DDS) run tests/ros2/test_ros2.py's `listen` mode, started
before mcad:
  same      on the controller host, no ROS_*, RMW_*, CYCLONEDDS_* or FAST* variables at all;
  monitor   on the other host with the documented configuration, ROS_STATIC_PEERS=192.168.10.2 only;
  stranger  on the other host with no variables, at the same time.
mcad runs until `same` and `monitor` both have 200 JointStates of every arm (2 s at the cells' 100 Hz after
discovery; at most 40 s), then gets SIGTERM. Checks (in the listeners, against mcad's CSV): same and
monitor got every JointState as a published tick (matched by stamp), >= 99.9 % of those published from the
first received, >= 99 % of the MarkerArrays, and diagnostics; stranger got nothing and never saw a publisher
of the cell's topics. mcad exits 0 (3 for the negative example, which ends in its fault by design).
usage: test_hosts.py MCAD SOURCE_DIR CELL [CELL...]   (root; exit 77 without)"""
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time

MCAD, SRC, CELLS = sys.argv[1], sys.argv[2], sys.argv[3:]
HERE = os.path.dirname(os.path.abspath(__file__))
TAG = f"mca{os.getpid() % 100000}"
NS_C, NS_M = f"{TAG}-ctl", f"{TAG}-mon"
CTL_ADDR = "192.168.10.2"
WANT = 200  # JointStates of every arm at `same` and `monitor` before mcad is stopped
failures = []


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what, flush=True)
    if not cond:
        failures.append(what)


def sh(*cmd, ns=None, check_rc=True):
    full = (["ip", "netns", "exec", ns] if ns else []) + list(cmd)
    r = subprocess.run(full, capture_output=True, text=True)
    if check_rc and r.returncode != 0:
        raise RuntimeError(f"{' '.join(full)}: {r.stderr.strip()}")
    return r


def setup():
    sh("ip", "netns", "add", NS_C)
    sh("ip", "netns", "add", NS_M)
    sh("ip", "link", "add", "eth1", "netns", NS_C, "type", "veth", "peer", "name", "eth1", "netns", NS_M)
    for ns, addr in ((NS_C, CTL_ADDR), (NS_M, "192.168.10.3")):
        sh("ip", "link", "set", "lo", "up", ns=ns)
        sh("ip", "addr", "add", addr + "/24", "dev", "eth1", ns=ns)
        sh("ip", "link", "set", "eth1", "up", ns=ns)
        sh("ip", "route", "add", "default", "via", "192.168.10.1", "dev", "eth1", "onlink", ns=ns)


def teardown():
    for ns in (NS_C, NS_M):
        sh("ip", "netns", "del", ns, check_rc=False)


def read_status(work, role):
    try:
        with open(os.path.join(work, role + ".status")) as f:
            return json.load(f)
    except (OSError, ValueError):
        return None


def run_cell(cell, tmp):
    name = os.path.splitext(os.path.basename(cell))[0]
    work = os.path.join(tmp, name)
    os.makedirs(work)
    print(f"== {name}", flush=True)
    # the user's environment: nothing of ROS or DDS (HOME for rclpy's log files)
    base = {"PATH": os.environ.get("PATH", "/usr/bin:/bin"), "HOME": work, "LANG": "C.UTF-8"}
    roles = (("same", NS_C, {}, "all"), ("monitor", NS_M, {"ROS_STATIC_PEERS": CTL_ADDR}, "all"),
             ("stranger", NS_M, {}, "none"))
    listeners = {}
    for role, ns, extra, expect in roles:
        out = open(os.path.join(work, role + ".out"), "w+")
        listeners[role] = (subprocess.Popen(
            ["ip", "netns", "exec", ns, "env", "-i"] + [f"{k}={v}" for k, v in {**base, **extra}.items()] +
            [sys.executable, os.path.join(HERE, "test_ros2.py"), "listen", SRC, cell, work, role, expect],
            stdout=out, stderr=subprocess.STDOUT), out)
    t_end = time.monotonic() + 60
    while time.monotonic() < t_end and not all(read_status(work, r) for r in listeners):
        if any(p.poll() is not None for p, _ in listeners.values()):
            break
        time.sleep(0.1)
    check(all(read_status(work, r) for r in listeners), "the three ROS 2 nodes are up")
    err_f = open(os.path.join(work, "mcad.err"), "w+")
    t0 = time.monotonic()
    mcad = subprocess.Popen(["ip", "netns", "exec", NS_C, MCAD, "--csv", os.path.join(work, "mcad.csv"), cell],
                            stderr=err_f)
    t_first = {}
    while mcad.poll() is None and time.monotonic() - t0 < 40:
        st = {r: read_status(work, r) or {"js": 0} for r in ("same", "monitor")}
        for r, s in st.items():
            if s["js"] > 0:
                t_first.setdefault(r, time.monotonic() - t0)
        if all(s["js"] >= WANT for s in st.values()):
            break
        time.sleep(0.1)
    print(f"first JointState {', '.join(f'{r} {t:.2f} s' for r, t in t_first.items())} after mcad started; "
          f"stopped at {time.monotonic() - t0:.2f} s", flush=True)
    if mcad.poll() is None:
        mcad.send_signal(signal.SIGTERM)
    try:
        rc = mcad.wait(timeout=60)
    except subprocess.TimeoutExpired:
        mcad.kill()
        rc = mcad.wait()
    err_f.seek(0)
    err = err_f.read()
    ok_rc = (0, 3) if name.startswith("negative") else (0,)
    check(rc in ok_rc, f"mcad exit status {rc} ({' or '.join(map(str, ok_rc))})")
    if rc not in ok_rc:
        print(err[-3000:])
    open(os.path.join(work, "done"), "w").close()
    for role, (p, out) in listeners.items():
        try:
            p.wait(timeout=90)
        except subprocess.TimeoutExpired:
            p.kill()
            p.wait()
        out.seek(0)
        text = out.read()
        print("".join(f"  {line}\n" for line in text.splitlines() if line.startswith(("ok", "FAIL", role))
                      or "missing" in line or "matches no" in line), end="", flush=True)
        check(p.returncode == 0, f"{name}: {role} passed (exit {p.returncode})")
        if p.returncode != 0 and "PASSED" not in text and "FAILED" not in text:
            print(text[-3000:])


def main():
    if os.geteuid() != 0:
        print("SKIP: network namespaces need root")
        return 77
    teardown()
    setup()
    tmp = tempfile.mkdtemp(prefix="mca-hosts-")
    try:
        for cell in CELLS:
            run_cell(os.path.abspath(cell), tmp)
    finally:
        teardown()
    if failures:
        print(f"kept: {tmp} (each cell's mcad.csv, mcad.err and the nodes' output)")
    else:
        shutil.rmtree(tmp, ignore_errors=True)
    print("FAILED: " + "; ".join(failures) if failures else "PASSED", flush=True)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
