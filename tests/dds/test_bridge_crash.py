#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""The peer that crashes libddsc 0.10.2 (docs/dds.md, "A peer that crashes Cyclone 0.10.2"), present for a while
against a running mcad: it must not take the loop down.

mcad runs the shipped cross-circles sim cell (DDS at 100 Hz, --csv, SCHED_FIFO as the cell says) long enough for
the peer to be there PEER_S seconds (--peer-seconds, default 12; the issue's 60 s by hand) and for the run to go
on after it left. ~3 s after mcad runs, the peer joins: a Python subscriber of mca/distances whose type was
written from dds/mca_dds.idl with plain uint8 keys and no must-understand (tests/dds/crash_peer.py, PyPI
cyclonedds 11.0.1). libddsc 0.10.2 (Debian 12) asks it for its type object and crashes on the reply in its
type-lookup thread (a NULL member type in xt_validate_impl, ddsi_typewrap.c: the reply's uint8 members are
TK_UINT8, a type kind 0.10.2 does not know). That thread is in mca-dds-bridge, not in mcad, so the crash cannot take the loop with it.

Plain cell (config/dds/loopback.xml; default), asserted:
  - the bridge dies of SIGSEGV within 10 s of the peer joining ("the crash REPRODUCED"; if not, a Cyclone without
    the bug: said plainly, the bridge is killed with SIGSEGV once so that the restart path runs all the same);
  - while the peer is there the bridge keeps dying and mcad keeps restarting it: at least 3 deaths, each
    restarted, the logged back-offs 0.1, 0.2, 0.4, 0.8, 1.6 s (capped at 2 s), never "stays down"; the summary
    counts as many restarts as deaths and says the bridge was up at the end;
  - after the peer left it publishes again: this test's own Distances reader (the wheel's libddsc 11.0.1 lives
    through the peer) receives again within 2.5 s and to the end, a mca-monitor started after the peer left
    receives to the end and knows the state at once; the status reader gets the final STOPPED;
  - the tools there from the start, a mca-monitor --csv and (--record) mca-record of the mca/ topics,
    /diagnostics and /tf_static, live through the peer: the peer kills their DDS child (libddsc 0.10.2), not
    them (mca/dds_child.h); each exits 0, says its child's deaths and restarts, and receives every Distances
    sample before the peer joined and from 3 s after it left to mcad's last publishing tick; the recording is
    one valid MCAP (the mcap package: CRCs, message count = statistics) that rosbags reads, its metadata
    "mca-record" has as many gaps as mca-record said, the statuses are in order and end STOPPED, and the
    latched /tf_static is not recorded twice though each restarted child receives it again.
Secure cell (--secure; in a network namespace, tests/ros2/netns.sh: config/dds/secure.xml, monitoring
protected, files from config/security/make_security.sh), asserted:
  - the bridge never dies (summary: died 0 times), the peer (no credentials, config/dds/ros2.xml) lives and
    receives nothing;
  - mca-monitor with the 'monitor' identity receives every Distances sample after its first (ticks 10 apart,
    none missing) up to mcad's last;
  - the bridge's Cyclone trace (the shipped secure.xml plus a <Tracing> element) shows why: the peer's
    discovery writers and its type-lookup reply writer are "not allowed" (non-secure), and the bridge sent no
    type-lookup request (no "tl-req" line): an unauthenticated peer never reaches type lookup.
Both: mcad exits 0 in state stopped with no fault (0 faults), and 0 overruns that the machine does not explain:
the loop is pinned to the last CPU (rt.cpu) and cyclictest runs on that CPU at the loop's priority for the whole
run (tools/mca-sweep/cyclic_late.py, sweep_rt.py's correlator: this VM's host freezes its vCPUs for 1-15 ms a few
times a minute); each of the summary's N overruns, taken to be the run's N longest command gaps, must have a
cyclictest wake-up at least 100 us late whose stall lies within 2 ms of the gap.
Printed: deaths, back-offs, restart times, the loop's command gap and compute per phase.

usage: test_bridge_crash.py MCAD MONITOR SOURCE_DIR DOMAIN [--peer-seconds S] [--secure] [--record MCA_RECORD]"""
import argparse
import csv
import os
import re
import signal
import subprocess
import sys
import tempfile
import threading
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import mca_types as m  # noqa: E402

sys.path.insert(0, os.path.join(HERE, "..", "..", "tools", "mca-sweep"))
import cyclic_late  # noqa: E402  (the one correlator of mcad's ticks with cyclictest, as sweep_rt.py's)

ap = argparse.ArgumentParser()
ap.add_argument("mcad")
ap.add_argument("monitor")
ap.add_argument("src")
ap.add_argument("domain", type=int)
ap.add_argument("--peer-seconds", type=float, default=12.0)
ap.add_argument("--secure", action="store_true")
ap.add_argument("--record", help="mca-record: records the run beside the first mca-monitor (plain cell)")
A = ap.parse_args()
MCAD, MONITOR, SRC, DOMAIN, PEER_S, SECURE = A.mcad, A.monitor, A.src, A.domain, A.peer_seconds, A.secure
XML = os.path.join(SRC, "config", "dds", "secure.xml" if SECURE else "loopback.xml")
PEER_XML = os.path.join(SRC, "config", "dds", "ros2.xml" if SECURE else "loopback.xml")  # no credentials
if not SECURE:
    os.environ["CYCLONEDDS_URI"] = "file://" + XML
DIVISOR = 10  # the cell's dds.publish_divisor
LOOP_PRIO = 80  # the cell's rt.priority
LOOP_CPU = (os.cpu_count() or 1) - 1  # the loop pinned here (rt.cpu), cyclictest beside it on the same CPU
STATES = ["INIT", "READY", "RUNNING", "BRAKING", "STOPPED", "FAULT"]
DEATH = r"dds bridge \(pid (\d+)\) died: (.*?); restart (\d+) in ([\d.]+) s"

failures = []


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what, flush=True)
    if not cond:
        failures.append(what)


def monitor_rows(path):
    """Whole rows of a mca-monitor CSV (a monitor killed by the peer may leave its last line cut short)."""
    try:
        with open(path) as f:
            return [r for r in csv.DictReader(f) if None not in r.values() and r.get("state")]
    except OSError:
        return []


def pct(xs, q):
    xs = sorted(xs)
    return xs[min(len(xs) - 1, int(q * len(xs)))] if xs else float("nan")


class Lines:
    """mcad's stderr, each line with the CLOCK_MONOTONIC time it was read."""

    def __init__(self, stream):
        self.lines = []
        self.lock = threading.Lock()
        self.t = threading.Thread(target=self._run, args=(stream,), daemon=True)
        self.t.start()

    def _run(self, stream):
        for line in stream:
            with self.lock:
                self.lines.append((time.monotonic(), line.rstrip("\n")))

    def all(self, pattern):
        with self.lock:
            return [(t, mm) for t, line in self.lines for mm in [re.search(pattern, line)] if mm]

    def wait(self, pattern, timeout, after=0.0):
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            hits = [x for x in self.all(pattern) if x[0] >= after]
            if hits:
                return hits[0]
            time.sleep(0.005)
        return None, None

    def text(self):
        with self.lock:
            return "\n".join(line for _, line in self.lines)


def start_monitor(out_csv, env):
    cmd = [MONITOR, "--domain", str(DOMAIN), "--config", XML, "--csv", out_csv, "--no-color"]
    if os.geteuid() == 0:
        cmd += ["--priority", "5"]  # a monitor that must see every sample (docs/dds.md)
    return subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, env=env)


def stop_proc(p):
    if p.poll() is None:
        p.send_signal(signal.SIGINT)
    try:
        return p.communicate(timeout=20)[1] or ""
    except subprocess.TimeoutExpired:
        p.kill()
        return p.communicate()[1] or ""

CHILD_DEATH = r"DDS child \(pid (\d+)\) died: (.*?); restart (\d+) in ([\d.]+) s"


def tick_holes(ticks, k0, k1):
    """Publishing ticks (every DIVISOR-th) in [k0, k1] that are not in ticks."""
    have = set(ticks)
    return [k for k in range(k0 - k0 % DIVISOR + (DIVISOR if k0 % DIVISOR else 0), k1 + 1, DIVISOR) if k not in have]


def check_tools(mon, mon_err, mon1_dead, mon_csv, rec, rec_err, rec_out, k_peer, k_left, last_pub, reproduced):
    """mca-monitor and mca-record, both there from before the peer joined until after mcad ended: each lives
    through the peer (its DDS child dies, the process does not), receives again after the peer left, and the
    recording is one valid MCAP that rosbags reads, with its gaps counted in the file."""
    after = k_left + 3000  # the child's back-off (at most 2 s) and discovery after the peer left
    m_deaths = [x for x in re.finditer(CHILD_DEATH, mon_err)]  # the first 5 of a series, then thinned out
    ms = re.search(r"DDS child: died (\d+) times, restarted (\d+) times", mon_err)
    ticks = [int(r["tick"]) for r in monitor_rows(mon_csv)]
    holes = tick_holes(ticks, after, last_pub)
    before = [k for k in ticks if k < k_peer]
    check(not mon1_dead and mon.returncode == 0 and len(before) > 100 and not holes and max(ticks, default=0) >= last_pub,
          f"the mca-monitor there from the start lived through the peer (exit {mon.returncode}; its DDS child died "
          f"{ms.group(1) if ms else 0} times: {sorted(set(x.group(2) for x in m_deaths))}) and received every Distances sample "
          f"from 3 s after the peer left to mcad's last publishing tick {last_pub} ({len(before)} before the peer, "
          f"{sum(1 for k in ticks if k > k_left)} after it left, missing after {after}: {holes[:5]})")
    if reproduced:
        check(len(m_deaths) >= 1 and all("SIGSEGV" in x.group(2) for x in m_deaths) and ms is not None
              and ms.group(1) == ms.group(2),
              f"the peer killed the monitor's DDS child ({ms.group(1) if ms else 0} deaths, the first "
              f"{len(m_deaths)} said one by one, all SIGSEGV), it was restarted each time")
    if rec is None:
        return
    r_deaths = [x for x in re.finditer(CHILD_DEATH, rec_err)]
    rs = re.search(r"DDS child: died (\d+) times, restarted (\d+) times; (\d+) gaps, ([\d.]+) s", rec_err)
    check(rec.returncode == 0 and (not reproduced or (len(r_deaths) >= 1 and rs is not None
                                                      and rs.group(1) == rs.group(2))),
          f"mca-record lived through the peer (exit {rec.returncode}); its DDS child died "
          f"{rs.group(1) if rs else 0} times, restarted {rs.group(2) if rs else 0} times, "
          f"{rs.group(3) if rs else 0} gaps, {rs.group(4) if rs else 0} s without a participant")
    from mcap.reader import make_reader
    from rosbags.highlevel import AnyReader
    from pathlib import Path
    try:
        with open(rec_out, "rb") as f:
            rd = make_reader(f, validate_crcs=True)
            summary = rd.get_summary()
            n_iter = sum(1 for _ in rd.iter_messages())
            meta = {}
            for mr in rd.iter_metadata():
                meta[mr.name] = dict(mr.metadata)
        ok = n_iter == summary.statistics.message_count and n_iter > 0
    except Exception as e:  # a file cut short: no summary, no footer
        ok, n_iter, meta = False, 0, {}
        print(f"mcap: {e!r}")
    m = meta.get("mca-record", {})
    gaps = [tuple(int(x) for x in v.split()) for k, v in sorted(m.items()) if k.startswith("gap_") and k[4:].isdigit()]
    check(ok and m.get("dds_child_deaths") == (rs.group(1) if rs else "0") and int(m.get("gaps", -1)) == len(gaps)
          and (rs is None or int(rs.group(3)) == len(gaps)) and all(a < b for a, b, _ in gaps),
          f"the recording is one valid MCAP (CRCs, {n_iter} messages = the statistics' count) and says its gaps: "
          f"metadata mca-record {m.get('dds_child_deaths')} deaths, {m.get('gaps')} gaps "
          f"({', '.join(f'{(b - a) / 1e9:.2f} s' for a, b, _ in gaps[:8])})")
    by = {}
    try:
        with AnyReader([Path(rec_out)]) as r:
            for conn, _, raw in r.messages():
                by.setdefault(conn.topic, []).append((raw, r.deserialize(raw, conn.msgtype)))
    except Exception as e:
        print(f"rosbags: {e!r}")
    dticks = [x.tick for _, x in by.get("mca/distances", [])]
    holes_r = tick_holes(dticks, after, last_pub)
    holes_quiet = tick_holes(dticks, min(dticks, default=0), k_peer - 1)  # before the peer: nothing lost
    check(len(dticks) > 100 and not holes_r and not holes_quiet and max(dticks, default=0) >= last_pub,
          f"rosbags read the recording: mca/distances {len(dticks)} samples, none missing before the peer joined "
          f"({holes_quiet[:5]}) nor from 3 s after it left to mcad's last publishing tick {last_pub} "
          f"({holes_r[:5]}); {sum(1 for k in dticks if k_peer <= k <= k_left)} recorded while it was there")
    st = [x.tick for _, x in by.get("mca/controller_status", [])]
    check(bool(st) and st == sorted(st) and by.get("mca/controller_status")[-1][1].state == STATES.index("STOPPED"),
          f"mca/controller_status: {len(st)} statuses in order, the last STOPPED")
    tf = [raw for raw, _ in by.get("/tf_static", [])]
    check(len(tf) >= 1 and len(tf) == len(set(bytes(x) for x in tf)),
          f"/tf_static (latched): {len(tf)} messages, none recorded twice though each restarted child received it "
          f"again ({len(set(bytes(x) for x in tf))} distinct)")


def main():
    tmp_obj = tempfile.TemporaryDirectory(prefix="mca-bridge-crash-")
    tmp = tmp_obj.name
    env = dict(os.environ)
    env_mcad, env_mon = env, env
    xml_mcad = XML
    trace = os.path.join(tmp, "bridge_trace.log")
    if SECURE:
        sec = os.path.join(tmp, "security")
        r = subprocess.run([os.path.join(SRC, "config", "security", "make_security.sh"), sec], capture_output=True,
                           text=True)
        check(r.returncode == 0, f"make_security.sh made the files ({r.stderr.strip()[-300:]})")
        env = dict(os.environ, MCA_SECURITY_DIR=sec)
        env.pop("CYCLONEDDS_URI", None)
        env_mcad, env_mon = dict(env, MCA_DDS_IDENTITY="mcad"), dict(env, MCA_DDS_IDENTITY="monitor")
        # the shipped secure.xml plus a trace of the bridge's Cyclone (finest: the type-lookup lines too)
        xml_mcad = os.path.join(tmp, "secure_traced.xml")
        with open(XML) as f:
            x = f.read()
        with open(xml_mcad, "w") as f:
            f.write(x.replace("</Domain>", f"  <Tracing><Verbosity>finest</Verbosity><OutputFile>{trace}"
                                           "</OutputFile><AppendToFile>true</AppendToFile></Tracing>\n  </Domain>"))

    with open(os.path.join(SRC, "config", "cells", "cross_circles_sim.yaml")) as f:
        cell_text = f.read()
    cell_text = cell_text.replace("../", os.path.join(SRC, "config") + "/")
    cell_text = re.sub(r"domain: *\d+", f"domain: {DOMAIN}", cell_text)
    cell_text = re.sub(r"config: *\S+", f"config: {xml_mcad}", cell_text)
    assert f"publish_divisor: {DIVISOR}" in cell_text
    cell_text, n_cpu = re.subn(r"(?m)^  cpu: *-?\d+", f"  cpu: {LOOP_CPU}", cell_text)
    assert n_cpu == 1
    run_s = 3.0 + PEER_S + (6.0 if SECURE else 9.0)  # task time: peer at ~3 s, then the run after it left
    cell, mcad_csv, mon_csv, mon2_csv = (os.path.join(tmp, n)
                                          for n in ("cell.yaml", "mcad.csv", "monitor.csv", "monitor2.csv"))
    with open(cell, "w") as f:
        f.write(cell_text)

    statuses, dist_rx = [], []  # (rx monotonic, tick, state) / (rx monotonic, tick)
    stop_reader = threading.Event()
    reader = None
    if not SECURE:  # the wheel's participants cannot authenticate (no security plugins in it)
        from cyclonedds.domain import DomainParticipant
        from cyclonedds.sub import DataReader
        from cyclonedds.topic import Topic
        dp = DomainParticipant(DOMAIN)
        rs = DataReader(dp, Topic(dp, m.TOPIC_STATUS, m.ControllerStatus, qos=m.status_qos()), qos=m.status_qos())
        # a Distances reader on the wheel's own libddsc (11.0.1), which lives through the peer
        rdist = DataReader(dp, Topic(dp, m.TOPIC_DISTANCES, m.Distances, qos=m.stream_qos()), qos=m.stream_qos())

        def read():
            while not stop_reader.is_set():
                for s in rs.take(N=100):
                    if isinstance(s, m.ControllerStatus):
                        statuses.append((time.monotonic(), s.tick, s.state))
                for s in rdist.take(N=1000):
                    if isinstance(s, m.Distances):
                        dist_rx.append((time.monotonic(), s.tick))
                time.sleep(0.002)

        reader = threading.Thread(target=read, daemon=True)
        reader.start()
    mon = start_monitor(mon_csv, env_mon)
    rec, rec_out = None, os.path.join(tmp, "run.mcap")
    if A.record and not SECURE:
        # the mca/ topics, /diagnostics and the latched /tf_static (a restarted child receives it again)
        rec = subprocess.Popen([A.record, "--config", XML, "--domain", str(DOMAIN), "--output", rec_out, "--topic",
                                "mca/*", "--topic", "/diagnostics", "--topic", "/tf_static", "--progress", "2",
                                "--quiet"], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, env=env)
    time.sleep(1.0)

    # the machine's own stalls: cyclictest on the loop's CPU at its priority for the whole run (-v: every wake-up)
    cyc_path = os.path.join(tmp, "cyclictest_v.txt")
    cyc, cyc_launch, cyc_f = cyclic_late.launch(int((run_s + 60) * 1000), LOOP_CPU, LOOP_PRIO, cyc_path)
    time.sleep(1.2)  # past cyclictest's first wake-up (the next whole second): it covers mcad's whole span
    t_start = time.monotonic()
    mcad = subprocess.Popen([MCAD, "--csv", mcad_csv, "--stop-after", f"{run_s:.0f}", cell], stderr=subprocess.PIPE,
                            text=True, env=env_mcad)
    log = Lines(mcad.stderr)
    _, mm = log.wait(r"dds bridge: pid (\d+)", 30)
    check(mm is not None, "mcad started its DDS bridge process")
    if mm is None:
        mcad.kill()
        print(log.text())
        return 1
    bridge0 = int(mm.group(1))
    spawns = []  # (CLOCK_MONOTONIC, pid) of each bridge process seen as mcad's child (the log is thinned out)

    def watch_children():
        last = None
        while mcad.poll() is None:
            try:
                with open(f"/proc/{mcad.pid}/task/{mcad.pid}/children") as f:
                    kids = f.read().split()
            except OSError:
                kids = []
            cur = kids[0] if kids else None
            if cur != last and cur is not None:
                spawns.append((time.monotonic(), int(cur)))
            last = cur
            time.sleep(0.01)

    threading.Thread(target=watch_children, daemon=True).start()
    t_running, _ = log.wait(r"running: 2 arms", 30)
    time.sleep(3.0)

    # the peer joins, stays PEER_S, leaves
    t_peer = time.monotonic()
    peer = subprocess.Popen([sys.executable, os.path.join(HERE, "crash_peer.py"), str(DOMAIN), PEER_XML],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env)
    t_death, dm = log.wait(DEATH, min(10.0, PEER_S))
    reproduced = dm is not None
    if not reproduced and not SECURE:
        print(f"the crash did NOT reproduce: the bridge (pid {bridge0}) lived {min(10.0, PEER_S):.0f} s with the "
              "peer; killing it with SIGSEGV instead", flush=True)
        os.kill(bridge0, signal.SIGSEGV)
        t_death, dm = log.wait(DEATH, 5)
    time.sleep(max(0.0, t_peer + PEER_S - time.monotonic()))
    peer_alive = peer.poll() is None
    peer.kill()
    t_left = time.monotonic()
    peer_out = peer.communicate()[0]
    print(f"crash peer: present {t_left - t_peer:.1f} s, alive until then: {peer_alive}; its output: "
          + " | ".join(peer_out.strip().splitlines()[-3:]), flush=True)
    # mca-monitor links libddsc 0.10.2: the peer kills a running one too. A second one joins after the peer
    # left, as an operator (or systemd) would start it again.
    time.sleep(0.5)
    mon1_dead = mon.poll() is not None
    mon2 = start_monitor(mon2_csv, env_mon)
    t_mon2 = time.monotonic()

    try:
        mcad.wait(timeout=run_s + 60)
    except subprocess.TimeoutExpired:
        mcad.kill()
        mcad.wait()
    log.t.join(timeout=5)
    t_end = time.monotonic()
    cyc_rc = cyclic_late.stop(cyc, cyc_f)
    time.sleep(1.5)  # the final status and the last samples reach the readers
    stop_reader.set()
    if reader:
        reader.join(timeout=5)
    mon_err, mon2_err = stop_proc(mon), stop_proc(mon2)
    rec_err = stop_proc(rec) if rec else ""
    text = log.text()
    print("mcad:\n  " + "\n  ".join(line for line in text.splitlines() if "bridge" in line or "summary" in line))
    print(f"mca-monitor (from the start): exit {mon.returncode}:\n  " + "\n  ".join(mon_err.strip().splitlines()[-12:]))
    if rec:
        print(f"mca-record (from the start): exit {rec.returncode}:\n  "
              + "\n  ".join(x for x in rec_err.strip().splitlines() if " messages, " not in x or "recorded" in x))
    print(f"mca-monitor (joined after the peer left): exit {mon2.returncode}: "
          + mon2_err.strip().replace("\n", " | ")[:300])

    check(mcad.returncode == 0, f"mcad exit status {mcad.returncode} (0: it ran its time and stopped)")
    check("summary: state stopped" in text, "mcad ended in state stopped")
    check("summary: faults: none" in text, "no fault")
    sm = re.search(r"summary: dds bridge: died (\d+) times, restarted (\d+) times.*; at the end (\w+)", text)
    died, restarted, at_end = (int(sm.group(1)), int(sm.group(2)), sm.group(3)) if sm else (-1, -1, "?")
    om = re.search(r"summary: state \w+, ticks (\d+), overruns (\d+) \(skipped periods (\d+)\)", text)
    deaths = log.all(DEATH)
    with open(mcad_csv) as f:
        rows = [(round(float(r["t"]) * 1000), float(r["cmd_gap_us"]), int(r["compute_ns"]), int(r["state"]),
                 int(r["wake_ns"])) for r in csv.DictReader(f)]
    last_ref = max(r[0] for r in rows)

    if SECURE:
        check(sm is not None and died == 0 and not deaths and at_end == "up",
              f"the bridge never died with the unauthenticated peer there for {t_left - t_peer:.0f} s (summary: "
              f"died {died} times, at the end {at_end})")
        check(peer_alive and "first sample" not in peer_out,
              "the peer (no credentials) lived the whole time and received no sample")
        # every Distances sample after the monitor's first, from the monitor that was there all along
        ticks = [int(r["tick"]) for r in monitor_rows(mon_csv)]
        steps = [b - a for a, b in zip(ticks, ticks[1:])]
        # the last may be the final snapshot, pushed at the stop (its tick need not be a publishing one)
        missing = [(a, b) for a, b in zip(ticks, ticks[1:])
                   if b - a != DIVISOR and not (b == ticks[-1] and 0 <= b - a < DIVISOR)]
        last_pub = last_ref - last_ref % DIVISOR
        check(mon.returncode == 0 and len(ticks) > 100 and not missing and max(ticks) >= last_pub,
              f"the authenticated monitor ('monitor' identity) received every Distances sample after its first: "
              f"{len(ticks)} samples, ticks {min(ticks, default=0)}..{max(ticks, default=0)} (mcad's last tick "
              f"{last_ref}), steps {sorted(set(steps))}, gaps {missing[:5]}")
        with open(trace, errors="replace") as f:
            tr = f.read()
        refused = set(re.findall(r"Non secure remote (?:reader|writer) \S+?:(\w+) is not allowed", tr))
        n_req = len(re.findall(r"tl-req", tr))
        n_rep = len(re.findall(r"tl-reply-add-types", tr))
        print(f"bridge trace: {len(tr) / 1e6:.1f} MB; the peer's endpoints refused as non-secure (entity ids): "
              f"{sorted(refused)}; type-lookup requests sent {n_req}, replies handled {n_rep}", flush=True)
        # 4c2: SEDP subscriptions writer (its reader of mca/distances is never announced to the bridge),
        # 301c3: type-lookup reply writer (no reply of its can reach the bridge)
        check({"4c2", "301c3"} <= refused and n_req == 0 and n_rep == 0,
              "the bridge refused the peer's discovery and type-lookup endpoints (non-secure) and never sent "
              "or handled a type-lookup message: the unauthenticated peer did not reach type lookup")
    else:
        check(dm is not None, "mcad logged the bridge's death")
        if dm is not None:
            print(f"the crash {'REPRODUCED' if reproduced else 'did not reproduce'}: bridge pid {dm.group(1)} died "
                  f"{t_death - t_peer:.2f} s after the peer joined: {dm.group(2)}", flush=True)
            check(int(dm.group(1)) == bridge0 and "signal 11 (SIGSEGV)" in dm.group(2),
                  f"the first bridge died of SIGSEGV ({dm.group(2)})")
        while_there = [(t, x) for t, x in deaths if t <= t_left + 0.5]
        print("deaths logged (s after the peer joined: cause, restart n in s): " + ", ".join(
            f"{t - t_peer:.2f}: {x.group(2)}, {x.group(3)} in {x.group(4)}" for t, x in deaths), flush=True)
        print(f"summary: died {died}, restarted {restarted}, at the end {at_end}; overruns "
              f"{om.group(2) if om else '?'}", flush=True)
        if reproduced:
            want = [min(0.1 * 2 ** k, 2.0) for k in range(len(deaths))]
            got = [float(x.group(4)) for _, x in deaths]
            check(died >= 3 and all("SIGSEGV" in x.group(2) for _, x in while_there) and got == want,
                  f"the bridge kept dying while the peer was there ({died} deaths in {t_left - t_peer:.0f} s, the "
                  f"first {len(deaths)} logged) and each was followed by a restart after {got} s (capped doubling)")
        check(sm is not None and restarted == died and at_end == "up" and "stays down" not in text,
              f"no give-up: restarted as often as it died ({restarted} of {died}), up at the end")
        if died > 5:
            t_up, um = log.wait(r"dds bridge up again: pid \d+ \(restart (\d+)\) has lived", 0.1)
            check(um is not None and t_up > t_left, "after the thinned-out restarts the log says it is up again"
                  + (f" ({t_up - t_left:.1f} s after the peer left)" if um else ""))
        # publishing again after the peer left: the wheel's reader (alive throughout) ...
        back = [t for t, _ in dist_rx if t > t_left]
        gaps_after = [b - a for a, b in zip(back, back[1:])]
        check(bool(back) and back[0] - t_left < 2.5 and max(gaps_after, default=9) < 1.0
              and max((k for _, k in dist_rx), default=0) >= last_ref - 200,
              f"Distances again after the peer left: the first {back[0] - t_left if back else -1:.2f} s after it, "
              f"then {len(back)} samples with no gap over {max(gaps_after, default=0):.2f} s up to tick "
              f"{max((k for _, k in dist_rx), default=0)} (mcad's last {last_ref}); before: "
              f"{sum(1 for t, _ in dist_rx if t_peer <= t <= t_left)} received while the peer was there")
        # ... and a mca-monitor (libddsc 0.10.2) started after it left
        rows2 = monitor_rows(mon2_csv)
        ticks2 = [int(r["tick"]) for r in rows2]
        check(mon2.returncode == 0 and len(ticks2) > 300 and max(ticks2, default=0) >= last_ref - 200,
              f"the mca-monitor that joined after the peer left received {len(ticks2)} samples, ticks "
              f"{min(ticks2, default=0)}..{max(ticks2, default=0)} (mcad's last {last_ref}; exit {mon2.returncode})")
        st2 = [r["state"] for r in rows2[:50]]
        known = [x for x in st2 if x != "?"]
        check(bool(known) and all(x == "RUNNING" for x in known) and len(st2) - len(known) <= 10,
              f"it knew the current state (RUNNING) from its first samples: {sorted(set(st2))}")
        if ticks2:
            print(f"monitor 2: started {t_mon2 - t_left:.2f} s after the peer left, its first sample "
                  f"{rows2 and (int(rows2[0]['rx_ns']) / 1e9 - t_left):.2f} s after it", flush=True)
        # the tools that were there from the start: their participant is a supervised child (mca/dds_child.h)
        off = rows[0][4] / 1e6 - rows[0][0]  # wake_ns (ms) - tick
        k_peer, k_left = int(t_peer * 1e3 - off), int(t_left * 1e3 - off)
        last_pub = last_ref - last_ref % DIVISOR
        check_tools(mon, mon_err, mon1_dead, mon_csv, rec, rec_err, rec_out, k_peer, k_left, last_pub,
                    reproduced)
        check(bool(statuses) and STATES[statuses[-1][2]] == "STOPPED", "the final status (STOPPED) arrived")

    # the loop: no overrun and no stall of the bridge's making
    running = [r for r in rows if STATES[r[3]] == "RUNNING"]
    # an overrun: a tick ended after the next one was due (compute being ~15 us: a wake-up a whole period late),
    # which leaves one of the longest command gaps of the run; mcad's summary counts them: its N overruns are
    # taken to be the N longest gaps, and each is judged as sweep_rt.py judges a slow tick (cyclic_late): the
    # machine's when cyclictest, on the same CPU at the same priority, was held up (a wake-up at least 100 us
    # late) within 2 ms of that tick's gap
    n_over = int(om.group(2)) if om else 0
    late = sorted(rows, key=lambda r: -r[1])[:n_over]
    wk = cyclic_late.wakeups(cyc_path, cyc_launch)
    cyc_late = cyclic_late.late_dues(wk)
    covered = cyclic_late.covers(wk, min(r[4] for r in rows), max(r[4] for r in rows))
    check(cyc_rc == 0 and covered,
          f"cyclictest ran beside the loop on CPU {LOOP_CPU} at priority {LOOP_PRIO} (exit {cyc_rc}) over mcad's "
          f"whole run: {len(wk)} wake-ups, {len(cyc_late)} of them >= {cyclic_late.CYC_LATE_US} us late, the "
          f"latest {max((us for _, us in wk), default=0) / 1e3:.2f} ms")
    unexplained = [r for r in late if not cyclic_late.explained(r[4], cyc_late, span_ns=int(r[1] * 1000))]
    for r in late:
        near = [(d, us) for d, us in wk
                if r[4] - r[1] * 1000 - cyclic_late.CYC_WINDOW_NS <= d <= r[4] + cyclic_late.CYC_WINDOW_NS]
        x = max(near, key=lambda y: y[1]) if near else None
        sp = min(spawns, key=lambda y: abs(y[0] - r[4] / 1e9), default=None)
        print(f"late tick {r[0]}: command gap {r[1] / 1e3:.2f} ms; " + (
            f"cyclictest's latest wake-up due in the gap or 2 ms around it ({(x[0] - r[4]) / 1e6:+.2f} ms from the "
            f"tick's wake-up) was {x[1]} us late" if x else "no cyclictest wake-up due near it") + (
            f"; the nearest bridge start {sp[0] - r[4] / 1e9:+.2f} s from it" if sp and len(spawns) > 1 else ""),
            flush=True)
    k0 = min(r[0] for r in running)
    off_ms = (running[0][4] / 1e6) - running[0][0]  # wake_ns (ms) - tick: tick -> CLOCK_MONOTONIC

    def tick_at(t_mono):
        return int(t_mono * 1e3 - off_ms)

    k_peer, k_left = tick_at(t_peer), tick_at(t_left)
    phases = {"before the peer": [r for r in running if k0 + 1000 <= r[0] < k_peer],
              "peer present": [r for r in running if k_peer <= r[0] < k_left],
              "after it left": [r for r in running if r[0] >= k_left]}
    for name, rr in phases.items():
        gaps = [r[1] for r in rr]
        comp = [r[2] / 1e3 for r in rr]
        print(f"loop {name:16s}: {len(rr):5d} ticks, command gap p50 {pct(gaps, 0.5):.0f} us, p99 "
              f"{pct(gaps, 0.99):.0f} us, max {max(gaps, default=0):.0f} us, gaps > 1.5 periods "
              f"{sum(1 for g in gaps if g > 1500)}; compute p50 {pct(comp, 0.5):.1f} us, p99 {pct(comp, 0.99):.1f} "
              f"us, max {max(comp, default=0):.1f} us", flush=True)
    print(f"mcad's summary: overruns {om.group(2) if om else '?'} (skipped periods {om.group(3) if om else '?'}); "
          f"the {len(late)} longest command gaps ({', '.join(f'{r[1] / 1e3:.2f}' for r in late)} ms), "
          f"{len(late) - len(unexplained)} of them with cyclictest late at the same moment (the machine's)",
          flush=True)
    if om is not None and n_over == 0:
        why = "none at all (summary: overruns 0)"
    elif not unexplained:
        why = f"{n_over} in the summary, each the machine's (cyclictest late beside it)"
    else:
        why = f"{len(unexplained)} of the {n_over} without a late cyclictest wake-up: " + ", ".join(
            f"tick {r[0]} gap {r[1] / 1e3:.2f} ms" for r in unexplained[:8])
    check(om is not None and covered and not unexplained,
          "0 overruns that cyclictest does not also see as a late wake-up (>= 100 us, within 2 ms): " + why)
    ups = [t - t_peer for t, _ in spawns[1:]]
    print(f"bridge processes seen starting after the first (mcad's children, polled every 10 ms: a short-lived "
          f"one can be missed): {len(ups)}, at " + ", ".join(f"{x:.2f}" for x in ups) + " s after the peer joined",
          flush=True)
    print(f"run: {t_end - t_start:.1f} s; mcad 'running' at +{(t_running or t_start) - t_start:.2f} s; peer present "
          f"{t_left - t_peer:.1f} s")
    return 1 if failures else 0


if __name__ == "__main__":
    rc = main()
    print("FAILED: " + "; ".join(failures) if failures else "PASS")
    sys.exit(rc)
