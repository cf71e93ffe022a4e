# SPDX-License-Identifier: MIT
"""mca-monitor shows what a running publisher sends: run mca-dds-synth and `mca-monitor --csv FILE
--count N`, then check every CSV row against the published pattern (recomputed here, mca_types.py):
distances, margins to d1/d2, S(d), critical links and points, strictly increasing ticks, >= 99.9 % of
the N consecutive ticks. Also the monitor's command-line errors and its clean exit on SIGINT; as root,
--priority: every thread of the recording monitor (Cyclone's too) SCHED_FIFO at that priority, and as
nobody (setpriv) a refusal that says so.
usage: test_monitor_csv.py --synth PATH --monitor PATH --config XML --domain N"""
import argparse
import csv
import os
import select
import signal
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mca_types as m  # noqa: E402

COUNT = 3000
STATE_LAG = 50  # ticks, as in tests/daemon/test_monitor_mcad.py
# ticks (ms) from the first distance to the first status: the status is its own topic, matched on its own; on a
# loaded machine it came 70 ms after the distances (CI, 2026-12-06)
STATUS_WAIT = 1000
FIRST_TICK_SLACK = 100  # ticks (ms): as in tests/daemon/test_monitor_mcad.py


def synth_state(k):
    """The synthetic controller's state at tick k (dds/src/dds_synth.c)."""
    return "BRAKING" if m.expected_min_distance(k) <= m.D1 else "RUNNING"


def check_rows(rows):
    errors = []
    ticks = [int(r["tick"]) for r in rows]
    if any(b <= a for a, b in zip(ticks, ticks[1:])):
        errors.append("ticks not strictly increasing")
    span = ticks[-1] - ticks[0] + 1
    if len(rows) < 0.999 * span:
        errors.append(f"{span - len(rows)} of {span} ticks missing")
    first = next((int(r["tick"]) for r in rows if r["state"] != "?"), None)
    if first is None or first - ticks[0] > STATUS_WAIT:
        errors.append(f"no controller status within {STATUS_WAIT} ticks of the first distance (first at "
                      f"{first if first is None else first - ticks[0]})")
    for r in rows:
        k = int(r["tick"])
        want = m.expected_distances(k)
        d = float(r["min_distance"])
        got = dict(pair_id=int(r["pair_id"]), arm_a=int(r["arm_a"]), arm_b=int(r["arm_b"]), tick=k,
                   min_distance=d, p=[float(r[c]) for c in ("px", "py", "pz")],
                   e=[float(r[c]) for c in ("ex", "ey", "ez")], link_a=int(r["link_a"]),
                   link_b=int(r["link_b"]), d1=float(r["d1"]), d2=float(r["d2"]))
        for key, val in got.items():
            if val != want[key]:
                errors.append(f"tick {k} {key}: csv {val!r} published {want[key]!r}")
        if float(r["margin_d1"]) != d - m.D1 or float(r["margin_d2"]) != d - m.D2:
            errors.append(f"tick {k}: margins {r['margin_d1']} {r['margin_d2']}")
        if abs(float(r["brake_factor"]) - m.brake_factor(d, m.D1, m.D2)) > 1e-12:
            errors.append(f"tick {k}: S {r['brake_factor']} != {m.brake_factor(d, m.D1, m.D2)}")
        # the synthetic controller brakes while d <= d1 and publishes a status on every change; a row shows
        # the state of its own tick or, while that status is on its way, of a tick at most STATE_LAG
        # earlier: never one of a later tick
        # "?": no status received yet, which the monitor says as it is; allowed only before its first
        # status (checked below to come within STATUS_WAIT), never after one
        ok = {synth_state(j) for j in range(max(0, k - STATE_LAG), k + 1)}
        if r["state"] not in ok and not (r["state"] == "?" and (first is None or k < first)):
            errors.append(f"tick {k}: state {r['state']}, the publisher's {sorted(ok)}")
        if int(r["rx_ns"]) < int(r["stamp_ns"]):
            errors.append(f"tick {k}: received before it was stamped")
    return errors


PRIORITY = 5
MONITOR = None  # the binary under test (main)


def check_threads_fifo(pid, prio):
    """Every thread of pid and of its DDS child (the participant's process, mca/dds_child.h) SCHED_FIFO at prio
    once Cyclone's threads exist (its receive thread takes the samples); /proc/PID/task/TID/stat fields 40 and
    41 are rt_priority and policy (1: SCHED_FIFO)."""
    threads = {}
    for _ in range(100):  # up to 10 s for the participant's threads on a loaded machine
        threads = {}
        try:
            with open(f"/proc/{pid}/task/{pid}/children") as f:
                pids = [pid] + [int(x) for x in f.read().split()]
        except OSError:
            pids = [pid]
        for tid in [f"{p}/task/{t}" for p in pids for t in os.listdir(f"/proc/{p}/task")]:
            try:
                with open(f"/proc/{tid}/stat") as f:
                    stat = f.read()
                with open(f"/proc/{tid}/comm") as f:
                    name = f.read().strip()
            except OSError:
                continue
            fields = stat[stat.rindex(")") + 2:].split()  # from field 3 on
            threads[name] = (int(fields[40 - 3]), int(fields[41 - 3]))
        if any(n.startswith("recv") for n in threads):
            break
        time.sleep(0.1)
    print(f"monitor threads (rt_priority, policy): {threads}")
    if not any(n.startswith("recv") for n in threads):
        return [f"no Cyclone receive thread in the monitor after 10 s: {threads}"]
    wrong = {n: v for n, v in threads.items() if v != (prio, 1)}
    errors = [f"--priority {prio}: threads not SCHED_FIFO {prio}: {wrong}"] if wrong else []
    refused = subprocess.run(["setpriv", "--reuid", "65534", "--regid", "65534", "--clear-groups", "--inh-caps=-all",
                              MONITOR, "--priority", str(prio), "--duration", "1"], capture_output=True, text=True, timeout=20)
    if refused.returncode != 1 or "cannot run SCHED_FIFO" not in refused.stderr:
        errors.append(f"--priority as nobody: exit {refused.returncode}, stderr {refused.stderr!r}")
    return errors


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--synth", required=True)
    ap.add_argument("--monitor", required=True)
    ap.add_argument("--config", required=True)
    ap.add_argument("--domain", type=int, required=True)
    a = ap.parse_args()
    global MONITOR
    MONITOR = a.monitor
    dom = ["--domain", str(a.domain), "--config", a.config]
    # A partition of our own: other tests' publishers (mcad, ...) may share the domain.
    part = ["--partition", f"mca-test-monitor-{os.getpid()}"]
    errors = []

    # Command-line errors: clear message, non-zero exit, no crash.
    for args, code, text in ((["--domain", "999"], 2, "--domain"), (["--count", "x"], 2, "--count"),
                             (["--bogus"], 2, "usage"), (["--duration", "-1"], 2, "--duration"),
                             (dom + ["--csv", "/nonexistent/dir/x.csv"], 1, "/nonexistent/dir/x.csv"),
                             (["--config", "/nonexistent.xml", "--count", "1"], 1, "/nonexistent.xml"),
                             (["--priority", "99"], 2, "--priority"), (["--priority", "x"], 2, "--priority")):
        p = subprocess.run([a.monitor] + args, capture_output=True, text=True, timeout=20)
        if p.returncode != code or text not in p.stderr:
            errors.append(f"mca-monitor {' '.join(args)}: exit {p.returncode} (want {code}), stderr {p.stderr!r}")
    if subprocess.run([a.monitor, "--help"], capture_output=True, timeout=20).returncode != 0:
        errors.append("--help does not exit 0")

    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "d.csv")
        root = os.geteuid() == 0
        prio = ["--priority", str(PRIORITY)] if root else []
        mon = subprocess.Popen([a.monitor, "--csv", path, "--count", str(COUNT), "--no-color"] + prio + dom + part,
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        if root:
            errors += check_threads_fifo(mon.pid, PRIORITY)
        else:
            print("SKIP: --priority (not root): the recording monitor runs SCHED_OTHER")
        pub = subprocess.Popen([a.synth, "--ticks", str(COUNT + 1000), "--wait-readers", "1", "--wait-topic",
                                "mca/distances", "--wait-timeout", "20000", "--ring", "4096"] + dom + part,
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        mout, merr = mon.communicate(timeout=60)
        pout, perr = pub.communicate(timeout=60)
        print(pout.strip())
        print(merr.strip())
        if mon.returncode != 0 or pub.returncode != 0:
            errors.append(f"exit codes monitor {mon.returncode} publisher {pub.returncode}: {merr} {perr}")
        with open(path) as f:
            rows = list(csv.DictReader(f))
        if len(rows) != COUNT:
            errors.append(f"CSV has {len(rows)} rows, want {COUNT} (--count)")
        elif int(rows[0]["tick"]) > FIRST_TICK_SLACK:
            # The publisher starts once its writer has matched the monitor's reader, but discovery is
            # not symmetric: the reader may learn of the writer a few ms later, and a volatile reader
            # does not get what was written before that (seen: first row tick 1 on a loaded CI run).
            errors.append(f"first row is tick {rows[0]['tick']} > {FIRST_TICK_SLACK}: the monitor "
                          "missed the start of a stream that waited for it")
        if rows:
            errors += check_rows(rows)
        if "ALARM" not in mout and "WARN" not in mout and "OK" not in mout:
            errors.append(f"no live line on stdout: {mout[-300:]!r}")

        # Ctrl-C: clean exit 0, CSV closed with its header.
        path2 = os.path.join(tmp, "e.csv")
        mon = subprocess.Popen([a.monitor, "--csv", path2] + dom, stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True)
        # Signal only once it is up (its first status line is printed after the handler is set):
        # on a loaded machine start-up can take longer than any fixed sleep.
        ready, _, _ = select.select([mon.stdout], [], [], 30.0)
        if not ready or not mon.stdout.readline():
            errors.append("mca-monitor printed nothing within 30 s")
        mon.send_signal(signal.SIGINT)
        _, merr = mon.communicate(timeout=20)
        if mon.returncode != 0 or not open(path2).readline().startswith("rx_ns,tick,"):
            errors.append(f"SIGINT: exit {mon.returncode}, stderr {merr!r}")

    if errors:
        for e in errors[:20]:
            print("FAIL:", e)
        raise SystemExit(f"FAIL: {len(errors)} problem(s)")
    print(f"PASS: {COUNT} CSV rows equal to the published values")


if __name__ == "__main__":
    main()
