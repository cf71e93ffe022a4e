#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""mca-record of the demo, read back by an independent reader.

The shipped cell config/cells/cross_circles_sim.yaml (the demo's: loopback.xml, domain 0, DDS at 100 Hz),
run for STOP_S seconds instead of 11 (and with a high overrun limit: a stalled VM must not end the run), by
the real mcad with --csv, in a network namespace of its own (netns.sh: the demo's domain 0 stays private).
mca-record --cell records it and is stopped with SIGINT. rosbags (PyPI) opens the MCAP file and decodes every
message with the definitions the file carries (its typestore built from the ros2msg schemas), and the mcap
package checks the file's structure and CRCs. Then:
  - every ROS 2 schema defines its types field for field as rosbags' own ROS 2 Jazzy type store does;
  - per topic, no sample missing after the first received one, in order: the mca/ topics by their tick
    (every DIVISOR-th tick of the CSV, then mcad's final snapshot as it closes: tick = the number of ticks
    run, the state after the last one, stamped when it was sent), the ROS 2 joint states and markers by
    their header stamps (the tick's wake-up in the CSV plus one constant offset, the bridge's CLOCK_REALTIME
    - CLOCK_MONOTONIC; the final snapshot's later), /diagnostics and mca/controller_status by the tick they
    carry (the same statuses on both), the latched topics once each (URDF text, one transform per arm);
  - JointState positions (ROS 2 and mca/) equal the CSV's at their tick (printed with %.17g: exactly).
usage: test_record.py MCA_RECORD MCAD SOURCE_DIR
"""
import csv
import os
import re
import signal
import subprocess
import sys
import tempfile
import time
from collections import defaultdict
from pathlib import Path

from mcap.reader import make_reader
from rosbags.highlevel import AnyReader
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

RECORD, MCAD, SRC = sys.argv[1], sys.argv[2], sys.argv[3]
STOP_S = 4
DIVISOR = 10  # the cell's publish_divisor
NS = "cross_circles_sim"
ARMS = ["left", "right"]

failures = []


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what, flush=True)
    if not cond:
        failures.append(what)


def make_cell(tmp):
    src = open(os.path.join(SRC, "config", "cells", "cross_circles_sim.yaml")).read()
    for what, old, new in (("relative paths (../)", r"\.\./", os.path.join(SRC, "config") + "/"),
                           ("stop_after", r"(?m)^stop_after: *\d+", f"stop_after: {STOP_S}"),
                           ("rt.overrun_limit", r"(?m)^  overrun_limit: *\d+", "  overrun_limit: 100000")):
        check(re.search(old, src) is not None, f"the shipped cell has {what}")
        src = re.sub(old, new, src)
    path = os.path.join(tmp, "cross_circles_sim.yaml")
    with open(path, "w") as f:
        f.write(src)
    return path


def stamp_ns(h):
    return h.stamp.sec * 1_000_000_000 + h.stamp.nanosec


def sequence_check(name, got, expected):
    """got: the sequence numbers received in order; expected: every one that was sent, in order. None
    missing after the first received one, none out of order, none twice."""
    if not got:
        check(False, f"{name}: received nothing")
        return
    first = got[0]
    want = [k for k in expected if k >= first]
    missing = sorted(set(want) - set(got))
    extra = sorted(set(got) - set(expected))
    check(got == want and not extra,
          f"{name}: {len(got)} samples, from {first} on {len(missing)} missing, in order"
          + (f" (missing {missing[:10]}, not sent {extra[:10]}, got {got[:5]}...)" if got != want else ""))


def main():
    with tempfile.TemporaryDirectory(prefix="mca-record-") as tmp:
        cell = make_cell(tmp)
        out = os.path.join(tmp, "demo.mcap")
        out_csv = os.path.join(tmp, "mcad.csv")
        rec = subprocess.Popen([RECORD, "--cell", cell, "--output", out, "--progress", "1"],
                               stderr=subprocess.PIPE, text=True)
        time.sleep(1.0)  # its discovery reader exists before mcad's writers
        t0 = time.monotonic()
        mcad = subprocess.run([MCAD, "--csv", out_csv, cell], stderr=subprocess.PIPE, text=True, timeout=60)
        print(f"mcad ran {time.monotonic() - t0:.1f} s, exit {mcad.returncode}")
        check(mcad.returncode == 0, f"mcad exit status {mcad.returncode}")
        if mcad.returncode != 0:
            print(mcad.stderr)
        time.sleep(1.0)  # the last samples
        rec.send_signal(signal.SIGINT)
        _, rec_err = rec.communicate(timeout=30)
        print(rec_err, end="")
        check(rec.returncode == 0, f"mca-record exit status {rec.returncode} after SIGINT")
        progress = [ln for ln in rec_err.splitlines() if " s, " in ln and " messages, " in ln]
        check(len(progress) >= 3, f"{len(progress)} progress lines (one a second, and the last)")
        rows = list(csv.DictReader(open(out_csv)))
        read_back(out, rows)
    print(f"{len(failures)} failed" if failures else "all passed")
    return 1 if failures else 0


def read_back(out, rows):
    # the file's structure, independently of rosbags: the mcap package with CRC checks
    with open(out, "rb") as f:
        rd = make_reader(f, validate_crcs=True)
        summary = rd.get_summary()
        n_iter = sum(1 for _ in rd.iter_messages())
    check(n_iter == summary.statistics.message_count and n_iter > 0,
          f"mcap: {n_iter} messages in {len(summary.chunk_indexes)} chunks, CRCs valid, = the statistics' count")
    check(all(s.encoding == "ros2msg" for s in summary.schemas.values())
          and all(c.message_encoding == "cdr" for c in summary.channels.values()),
          f"mcap: {len(summary.channels)} channels of encoding cdr, {len(summary.schemas)} ros2msg schemas")

    jazzy = get_typestore(Stores.ROS2_JAZZY)
    for s in summary.schemas.values():
        if s.name.startswith("mca_dds/"):
            continue
        types = get_types_from_msg(s.data.decode(), s.name)
        same = all(jazzy.fielddefs.get(t) is not None and jazzy.fielddefs[t][1] == d[1] and
                   sorted(jazzy.fielddefs[t][0]) == sorted(d[0]) for t, d in types.items())
        check(same, f"schema {s.name}: its {len(types)} definitions as ROS 2 Jazzy's")

    n_ticks = len(rows)
    final = n_ticks  # the final snapshot's tick: the ticks run; its state: the last row's
    published = list(range(0, n_ticks, DIVISOR)) + [final]
    wake = {int(r["wake_ns"]): k for k, r in enumerate(rows)}

    def row(tick):
        return rows[min(tick, n_ticks - 1)]

    by = defaultdict(list)
    with AnyReader([Path(out)]) as r:
        topics = {c.topic: c.msgtype for c in r.connections}
        for conn, _, raw in r.messages():
            by[conn.topic].append(r.deserialize(raw, conn.msgtype))
    print("recorded: " + ", ".join(f"{t} {len(v)}" for t, v in by.items()))
    want = {f"/{NS}/{a}/{leaf}" for a in ARMS for leaf in ("joint_states", "robot_description")} | {
        f"/{NS}/distance_markers", "/tf_static", "/diagnostics", "mca/joint_state", "mca/joint_command",
        "mca/distances", "mca/controller_status"}
    check(set(topics) == want, f"the {len(want)} topics of the cell: {sorted(set(topics) ^ want) or 'all'}")

    worst = 0.0
    # mca/ topics: by tick
    for ai, a in enumerate(ARMS):
        js = [m for m in by["mca/joint_state"] if m.arm_id == ai]
        sequence_check(f"mca/joint_state arm {a}", [m.tick for m in js], published)
        for m in js:
            ref = [float(row(m.tick)[f"q{ai}_{j}"]) for j in range(len(m.position))]
            worst = max(worst, max(abs(x - y) for x, y in zip(m.position, ref)))
        bad = [m.tick for m in js if m.tick != final and m.stamp_ns != int(rows[m.tick]["wake_ns"])]
        check(not bad, f"mca/joint_state arm {a}: each stamp_ns = the CSV's wake_ns at its tick ({bad[:5]})")
        jc = [m for m in by["mca/joint_command"] if m.arm_id == ai]
        sequence_check(f"mca/joint_command arm {a}", [m.tick for m in jc], published)
    dist = by["mca/distances"]
    sequence_check("mca/distances", [m.tick for m in dist], published)
    bad_d = [m.tick for m in dist if m.min_distance != float(row(m.tick)["min_d"])]
    check(not bad_d, f"mca/distances: min_distance = the CSV's min_d at every tick ({bad_d[:5]})")

    # ROS 2 joint states and markers: by header stamp = wake_ns + one offset
    # the offset: the first sample's stamp minus the wake-up of the tick nearest to it on this host's
    # CLOCK_REALTIME - CLOCK_MONOTONIC (the bridge took the same difference; ticks are 10 ms apart)
    first = by[f"/{NS}/left/joint_states"][0] if by[f"/{NS}/left/joint_states"] else None
    offset = None
    if first is not None:
        est = time.time_ns() - time.monotonic_ns()
        s0 = stamp_ns(first.header)
        k = min(published[:-1], key=lambda k: abs(int(rows[k]["wake_ns"]) + est - s0))
        if abs(int(rows[k]["wake_ns"]) + est - s0) < 4_000_000:  # < half the spacing: one candidate
            offset = s0 - int(rows[k]["wake_ns"])
    check(offset is not None, "the first /left/joint_states is stamped with a published tick's wake-up "
          "(within 4 ms on CLOCK_REALTIME - CLOCK_MONOTONIC)")
    if offset is None:
        return

    last_wake = int(rows[-1]["wake_ns"]) + offset

    def tick_of(stamp):
        return wake.get(stamp - offset, final if stamp > last_wake else -1)

    for ai, a in enumerate(ARMS):
        msgs = by[f"/{NS}/{a}/joint_states"]
        ticks = [tick_of(stamp_ns(m.header)) for m in msgs]
        check(-1 not in ticks, f"/{NS}/{a}/joint_states: every stamp is a tick's wake-up + the offset "
              "(or the final snapshot's, later)")
        sequence_check(f"/{NS}/{a}/joint_states", ticks, published)
        for m, k in zip(msgs, ticks):
            ref = [float(row(k)[f"q{ai}_{j}"]) for j in range(len(m.position))]
            worst = max(worst, max(abs(x - y) for x, y in zip(m.position, ref)))
    check(worst <= 0.0, f"JointState positions (ROS 2 and mca/) = mcad's tick CSV: max |q - CSV| {worst:.3g} rad")

    markers = by[f"/{NS}/distance_markers"]
    ticks = []
    for m in markers:
        st = {stamp_ns(x.header) for x in m.markers}
        ticks.append(tick_of(st.pop()) if len(st) == 1 else -1)
    check(-1 not in ticks, f"/{NS}/distance_markers: one stamp per array, a tick's wake-up + the offset")
    sequence_check(f"/{NS}/distance_markers", ticks, published)

    # statuses: /diagnostics and mca/controller_status carry the same ticks (both written per status)
    diag = [int({kv.key: kv.value for kv in m.status[0].values}["tick"]) for m in by["/diagnostics"]]
    stat = [m.tick for m in by["mca/controller_status"]]
    both = max(diag[0], stat[0]) if diag and stat else 0
    check(len(diag) >= 3 and [t for t in diag if t >= both] == [t for t in stat if t >= both],
          f"/diagnostics {len(diag)} and mca/controller_status {len(stat)}: the same statuses from tick {both} on")

    # the last status is mcad's final one: its fields after the strings decode to the run's figures
    fin = by["mca/controller_status"][-1] if by["mca/controller_status"] else None
    min_d = min(float(x["min_d"]) for x in rows)
    check(fin is not None and fin.ticks == n_ticks and fin.state == 4 and fin.fault_code == 0
          and fin.min_distance_so_far == min_d and fin.snapshots_dropped == 0,
          f"mca/controller_status, the final one: {n_ticks} ticks, STOPPED, min_distance_so_far {min_d} "
          "= the CSV's smallest min_d, 0 snapshots dropped")

    # latched topics
    for ai, a in enumerate(ARMS):
        d = by[f"/{NS}/{a}/robot_description"]
        check(len(d) == 1 and "<robot" in d[0].data, f"/{NS}/{a}/robot_description: one URDF ({len(d)})")
    tf = by["/tf_static"]
    check(len(tf) == 1 and sorted(t.child_frame_id.split("/")[0] for t in tf[0].transforms) == ARMS,
          f"/tf_static: one message, one transform per arm")


sys.exit(main())
