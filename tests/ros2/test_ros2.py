#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""mcad's ROS 2 topics against real ROS 2 nodes (rclpy on Fast DDS, another DDS vendor than mcad's Cyclone),
run inside a network namespace of its own (tests/ros2/netns.sh). docs/ros2.md.

topics: an rclpy node subscribes to every topic with rclpy's default QoS (reliable, volatile) but a history
  of 1000 instead of 10 (the whole run: a Python executor on a loaded 2-CPU machine fell 2.4-3.7 s behind,
  and a history of 200 lost what it had not taken), then mcad runs 5 s of the cross
  circles task (paper task 1) with --csv at 100 Hz on DDS. Every JointState, MarkerArray and DiagnosticArray
  received must be mcad's CSV at one tick: each JointState's positions equal one published tick's (ticks
  0, 10, 20, ...) within 1e-9, ticks in order; >= 99 % of the published ticks from the first one received.
  Markers of a stamp are the tick of the JointState with that stamp: the closest-point segment is the
  CSV's P and E, its text the CSV's distance, its colour the zone of that distance, the capsules form one
  chain from the base to the CSV's end effector. Diagnostics: the tick's state and the smallest distance
  of the CSV up to that tick. A node that joins 2 s late (transient-local QoS) gets each arm's URDF text;
  /tf_static (tf2_msgs has no rclpy wheel here) is read with the Cyclone Python binding, also late: one
  transform per arm, world -> <arm>/<root link>, at the scenario's base placement.
stream: mcad runs config/cells/stream_sim.yaml (left follows a TwistStamped, right a PoseStamped); an rclpy
  node finds the tool tips in the first MarkerArray and drives them at each other for 4 s (left at
  0.15 m/s towards right's tip, right's pose target on left's tip): every tick of mcad's CSV >= d1, and
  they came within d2 (the yield was needed). Then the stream backs off (left away, right to its start):
  the distance grows past d2 and left's reference moves at the commanded speed again. Meanwhile bad
  targets, each sent once: NaN, a frame_id that is not "world", a twist above max_speed, a pose outside
  the workspace box: rejected, counted on /diagnostics with the last reason, and nothing moved by them.
  Finally left's stream goes silent: its reference holds after hold_after, and after brake_after mcad
  brakes both arms and exits 3 naming the stale stream; every tick >= d1 to the end.
graph: mcad runs 3 s and links no ROS library (ldd); a second rclpy node sees the topics and types a ROS 2 user would see
  (get_topic_names_and_types), the publishers' QoS (reliable; transient-local for the latched ones), and a
  sensor-data (best-effort) subscriber receives JointState too.
With a fifth argument (topics), the MarkerArray received at the tick of the smallest distance is written there
as JSON: tools/plots/ros2_markers.py draws it (the README's picture).
restart: mcad's DDS bridge process is killed with SIGSEGV after its first /diagnostics (12 s run): it says
  dds_bridge_restarts 0 before and 1 from the restarted bridge, JointState flows again, mcad exits 0.
listen (for test_hosts.py, which runs it in network namespaces and then mcad): a node with the environment it
  is given subscribes to a cell's JointStates, markers and diagnostics, writes WORK/ROLE.status as it goes
  and, once WORK/done exists, checks what it got against mcad's CSV WORK/mcad.csv: EXPECT "all" = every
  JointState one published tick, >= 99.9 % of them from the first received, >= 99 % of the MarkerArrays,
  diagnostics came;
  EXPECT "none" = no sample and never a publisher of the cell's topics in its graph.
usage: test_ros2.py topics|graph|stream|restart MCAD SOURCE_DIR DOMAIN [MARKERS_JSON]
       test_ros2.py listen SOURCE_DIR CELL WORK ROLE all|none"""
import json
import csv
import math
import os
import re
import signal
import subprocess
import sys
import tempfile
import threading
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "dds"))
import idl_enums  # noqa: E402  the states' names by their IDL numbering

MODE = sys.argv[1]
if MODE == "listen":  # as a user's node: the environment as given (test_hosts.py gives no ROS_* variables)
    SRC, CELL_FILE, WORK, ROLE, EXPECT = sys.argv[2:7]
    MCAD, DOMAIN = None, 0
else:
    MCAD, SRC, DOMAIN = sys.argv[2], sys.argv[3], int(sys.argv[4])
    os.environ["ROS_DOMAIN_ID"] = str(DOMAIN)
    os.environ.setdefault("RMW_IMPLEMENTATION", "rmw_fastrtps_cpp")

import rclpy  # noqa: E402  (after ROS_DOMAIN_ID)
from rclpy.executors import SingleThreadedExecutor  # noqa: E402
from rclpy.node import Node  # noqa: E402
from rclpy.qos import (QoSProfile, DurabilityPolicy, ReliabilityPolicy, HistoryPolicy,  # noqa: E402
                       qos_profile_sensor_data)
from diagnostic_msgs.msg import DiagnosticArray  # noqa: E402
from geometry_msgs.msg import PoseStamped, TwistStamped  # noqa: E402
from sensor_msgs.msg import JointState  # noqa: E402
from std_msgs.msg import String  # noqa: E402
from visualization_msgs.msg import Marker, MarkerArray  # noqa: E402

NS = "ros2_check"
ARMS = ["left", "right"]
D1, D2 = 0.05, 0.12
DIVISOR = 10
XML = os.path.join(SRC, "config", "dds", "ros2.xml")
RUN_S = 5.0  # the late readers (transient-local) join 1 s in: 4 s for discovery on a loaded machine

CELL = f"""name: ros2-check
task:
  scenario: {SRC}/config/scenarios/cross_circles.yaml
  duration: {RUN_S}
scheme: mca
d1: {D1}
d2: {D2}
arms:
  - name: left
    backend: sim
  - name: right
    backend: sim
dds:
  enabled: true
  domain: {DOMAIN}
  config: {XML}
  publish_divisor: {DIVISOR}
  ros2: {{namespace: {NS}}}
rt: {{period_us: 1000, priority: 60, overrun_limit: 100000, pdnn_budget_us: 1000000}}
stop_after: {RUN_S}
"""

failures = []


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what, flush=True)
    if not cond:
        failures.append(what)


def stamp_ns(h):
    return h.stamp.sec * 1_000_000_000 + h.stamp.nanosec


def topic(leaf, arm=None):
    return f"/{NS}/{arm}/{leaf}" if arm else f"/{NS}/{leaf}"


class Collector(Node):
    def __init__(self, name, qos=QoSProfile(depth=1000)):
        super().__init__(name)
        self.js = {a: [] for a in ARMS}
        self.markers, self.diag, self.desc = [], [], {}
        self.latency_ns = []  # JointState: receipt (CLOCK_REALTIME) - header stamp (the tick's wake-up)
        self.lock = threading.Lock()
        for a in ARMS:
            self.create_subscription(JointState, topic("joint_states", a), self._add(self.js[a]), qos)

    def _add(self, lst):
        def cb(m):
            with self.lock:
                lst.append(m)
                if isinstance(m, JointState):
                    self.latency_ns.append(time.time_ns() - stamp_ns(m.header))
        return cb

    def all_topics(self):
        self.create_subscription(MarkerArray, topic("distance_markers"), self._add(self.markers), QoSProfile(depth=1000))
        self.create_subscription(DiagnosticArray, "/diagnostics", self._add(self.diag), QoSProfile(depth=1000))

    def received(self):
        with self.lock:
            return sum(len(v) for v in self.js.values()) + len(self.markers) + len(self.diag)

    def descriptions(self):
        latched = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                             durability=DurabilityPolicy.TRANSIENT_LOCAL, history=HistoryPolicy.KEEP_LAST)
        for a in ARMS:
            def cb(m, a=a):
                self.desc[a] = m.data
            self.create_subscription(String, topic("robot_description", a), cb, latched)


def settle(collector, extra=None, quiet=1.5, most=30.0):
    """After mcad has exited: wait until the collector got nothing new for `quiet` s (at most `most` s):
    the executor may be seconds behind on a loaded machine. `extra` is called on each poll."""
    t_end, last, t_last = time.monotonic() + most, -1, time.monotonic()
    while time.monotonic() < t_end:
        if extra:
            extra()
        n = collector.received()
        if n != last:
            last, t_last = n, time.monotonic()
        elif time.monotonic() - t_last >= quiet:
            return
        time.sleep(0.1)


def run_mcad(tmp, cell_text=None):
    cell, out_csv = os.path.join(tmp, "cell.yaml"), os.path.join(tmp, "mcad.csv")
    with open(cell, "w") as f:
        f.write(cell_text or CELL)
    return subprocess.Popen([MCAD, "--csv", out_csv, cell], stderr=subprocess.PIPE, text=True), out_csv


def read_csv(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def quat_rpy(r, p, y):
    cr, sr, cp, sp, cy, sy = (math.cos(r / 2), math.sin(r / 2), math.cos(p / 2), math.sin(p / 2),
                              math.cos(y / 2), math.sin(y / 2))
    return (sr * cp * cy - cr * sp * sy, cr * sp * cy + sr * cp * sy, cr * cp * sy - sr * sp * cy,
            cr * cp * cy + sr * sp * sy)


def zone_color(d):
    return (0.2, 0.75, 0.3) if not d < D2 else (1.0, 0.6, 0.0) if d >= D1 else (1.0, 0.0, 0.0)


def tf_static_reader():
    """/tf_static through the Cyclone Python binding (types written here, not from mcad's IDL)."""
    from cyclonedds.domain import DomainParticipant
    from cyclonedds.topic import Topic
    from cyclonedds.sub import DataReader
    from cyclonedds.core import Qos, Policy
    from ros2_types import TFMessage_

    dp = DomainParticipant(DOMAIN)
    qos = Qos(Policy.Reliability.Reliable(max_blocking_time=1_000_000_000), Policy.Durability.TransientLocal,
              Policy.History.KeepLast(1))
    return DataReader(dp, Topic(dp, "rt/tf_static", TFMessage_, qos=qos), qos=qos)


def spin_in_background(*nodes):
    ex = SingleThreadedExecutor()
    for n in nodes:
        ex.add_node(n)
    th = threading.Thread(target=ex.spin, daemon=True)
    th.start()
    return ex


def published_ticks(rows, divisor):
    """The ticks of mcad's CSV that went out on DDS: every divisor-th, and the final snapshot mcad sends as it
    closes (the last tick's state again; a second sample of it when the last tick is itself a divisor-th)."""
    return [k for k in range(len(rows)) if k % divisor == 0] + [len(rows) - 1]


def check_joint_states(a, ai, msgs, rows, published, tick_of_stamp, share_min):
    """Arm a (number ai in the CSV's q<ai>_<j> columns): each JointState is one published tick, ticks in order,
    positions equal within 1e-9; at least share_min of the ticks published from the first one received. The
    tick comes from the stamp (positions alone are ambiguous while an arm stands still): the bridge stamps a
    tick's samples with its wake-up (the CSV's wake_ns) plus one offset, ROS time minus CLOCK_MONOTONIC taken
    once; the offset is the one that puts the first samples' stamps on published wake-ups (the final snapshot
    is stamped when mcad closes, after its last tick). Fills tick_of_stamp
    (header stamp -> tick). Returns (received, expected)."""
    names = [f"q{ai}_{j}" for j in range(len(msgs[0].position))] if msgs else []
    tick_of_wake = {int(rows[k]["wake_ns"]): k for k in set(published)}
    offset = 0
    if msgs:
        s0 = stamp_ns(msgs[0].header)
        offset = max((s0 - w for w in tick_of_wake),
                     key=lambda c: sum(1 for m in msgs[:50] if stamp_ns(m.header) - c in tick_of_wake))
    matched, worst, bad = [], 0.0, 0
    for m in msgs:
        k = tick_of_wake.get(stamp_ns(m.header) - offset)
        if k is None and stamp_ns(m.header) - offset > int(rows[-1]["wake_ns"]):
            k = len(rows) - 1  # the final snapshot, sent as mcad closes: the last tick's state, stamped then
        dq = max(abs(x - float(rows[k][n])) for x, n in zip(m.position, names)) if k is not None else math.inf
        if k is None or dq > 1e-9 or (matched and k < matched[-1]):
            bad += 1
            print(f"{a}: a JointState (stamp {stamp_ns(m.header)}) is no published tick after "
                  f"{matched[-1] if matched else None} (tick {k}, |dq| {dq:.1e})")
            continue
        worst = max(worst, dq)
        matched.append(k)
        tick_of_stamp.setdefault(stamp_ns(m.header), k)
    expected = [k for k in published if matched and k >= matched[0]]
    missing = sorted(set(expected) - set(matched))
    if missing:
        print(f"{a}: first received tick {matched[0]}, missing ticks {missing[:20]}")
    share = len(matched) / len(expected) if expected else 0.0
    check(bad == 0 and len(matched) > 0,
          f"{a}: {len(matched)} JointState samples, each one tick of mcad's CSV by its stamp, in order "
          f"(max |dq| {worst:.1e} rad; {bad} matched none)")
    check(share >= share_min, f"{a}: {len(matched)} of the {len(expected)} ticks published from the first "
          f"received ({100 * share:.2f} % >= {100 * share_min:g} %)")
    return len(matched), len(expected)


def mode_topics(tmp):
    main = Collector("mca_ros2_check")
    main.all_topics()
    ex = spin_in_background(main)
    time.sleep(2.0)  # our readers exist before mcad's writers
    proc, out_csv = run_mcad(tmp)
    time.sleep(1.0)  # mcad wrote its URDFs and TF as it started: these two join later
    late = Collector("mca_ros2_late")
    late.descriptions()
    ex.add_node(late)
    tf_reader = tf_static_reader()
    tfs = []
    while proc.poll() is None:
        tfs += tf_reader.take(N=10)
        time.sleep(0.05)
    _, err = proc.communicate(timeout=120)
    settle(main, extra=lambda: tfs.extend(tf_reader.take(N=10)))  # the last samples
    ex.shutdown()
    check(proc.returncode == 0, f"mcad exit status {proc.returncode}")
    if proc.returncode != 0:
        print(err)
    rows = read_csv(out_csv)
    published = published_ticks(rows, DIVISOR)
    print(f"mcad: {len(rows)} ticks in its CSV, {len(published)} published")

    # JointState: each sample is one published tick, in order
    tick_of_stamp = {}
    for ai, a in enumerate(ARMS):
        check_joint_states(a, ai, main.js[a], rows, published, tick_of_stamp, 0.99)
        urdf_joints = ["S1", "S2", "S3", "E1", "E2", "W1", "W2", "T"]
        check(all(list(m.name) == urdf_joints for m in main.js[a]), f"{a}: joint names are the URDF's")

    lat = sorted(main.latency_ns)
    if lat:
        print(f"latency tick wake-up -> rclpy callback (JointState, {len(lat)} samples): "
              f"p50 {lat[len(lat) // 2] / 1e3:.0f} us, p99 {lat[int(len(lat) * 0.99)] / 1e3:.0f} us, "
              f"max {lat[-1] / 1e3:.0f} us")

    # Markers
    n_mk, n_tick = 0, 0
    mk_fail, mk_ticks = [], []
    for ma in main.markers:
        n_mk += 1
        st = stamp_ns(ma.markers[0].header) if ma.markers else None
        k = tick_of_stamp.get(st)
        if k is None:
            continue
        n_tick += 1
        mk_ticks.append(k)
        r = rows[k]
        by_ns = {}
        for m in ma.markers:
            by_ns.setdefault(m.ns, []).append(m)
        line = by_ns.get("closest_points", [None])[0]
        text = by_ns.get("distances", [None])[0]
        if line is None or text is None or len(line.points) != 2:
            mk_fail.append(f"tick {k}: no closest-point segment or text")
            continue
        p, e = line.points
        pe_ref = [float(r[c]) for c in ("p_x", "p_y", "p_z", "e_x", "e_y", "e_z")]
        dpe = max(abs(x - y) for x, y in zip((p.x, p.y, p.z, e.x, e.y, e.z), pe_ref))
        d = float(text.text.split()[-2])
        d_ref = float(r["min_d"])
        col = (round(line.color.r, 2), round(line.color.g, 2), round(line.color.b, 2))
        if dpe > 1e-12 or abs(d - d_ref) > 1e-12 or col != tuple(round(c, 2) for c in zone_color(d_ref)):
            mk_fail.append(f"tick {k}: |PE - CSV| {dpe:.1e}, d {d!r} vs {d_ref!r}, colour {col}")
        for ai, a in enumerate(ARMS):
            links = sorted((m for m in by_ns.get(f"{a}/links", []) if m.type == Marker.SPHERE_LIST),
                           key=lambda m: m.id)
            pts = [(q.x, q.y, q.z) for m in links for q in m.points]
            chain_ok = all(math.dist(pts[i], pts[i + 1]) < 1e-12 for i in range(1, len(pts) - 1, 2))
            for cyl in (m for m in by_ns.get(f"{a}/links", []) if m.type == Marker.CYLINDER):
                caps = [m for m in links if m.id == cyl.id + 1]
                o, c0 = cyl.pose.orientation, cyl.pose.position
                # the cylinder's z axis (the quaternion applied to (0, 0, 1)) times half its length
                z = (2 * (o.x * o.z + o.w * o.y), 2 * (o.y * o.z - o.w * o.x), 1 - 2 * (o.x * o.x + o.y * o.y))
                h = cyl.scale.z / 2
                ends = [(c0.x - h * z[0], c0.y - h * z[1], c0.z - h * z[2]),
                        (c0.x + h * z[0], c0.y + h * z[1], c0.z + h * z[2])]
                if not caps or any(math.dist(ends[i], (caps[0].points[i].x, caps[0].points[i].y,
                                                      caps[0].points[i].z)) > 1e-9 for i in range(2)):
                    mk_fail.append(f"tick {k}: {a} cylinder {cyl.id} does not span its end caps")
            ee = tuple(float(r[f"ee{ai}_{c}"]) for c in "xyz")
            if not links or not chain_ok or math.dist(pts[-1], ee) > 1e-12:
                mk_fail.append(f"tick {k}: {a}'s capsules are not one chain ending at the CSV's end effector")
    if len(sys.argv) > 5 and mk_ticks:
        closest = min(range(len(mk_ticks)), key=lambda i: float(rows[mk_ticks[i]]["min_d"]))
        ma = [m for m in main.markers if m.markers and stamp_ns(m.markers[0].header) in tick_of_stamp][closest]
        with open(sys.argv[5], "w") as f:
            json.dump({"tick": mk_ticks[closest], "d1": D1, "d2": D2, "markers": [
                {"ns": m.ns, "id": m.id, "type": m.type, "text": m.text, "scale": [m.scale.x, m.scale.y, m.scale.z],
                 "color": [m.color.r, m.color.g, m.color.b, m.color.a],
                 "points": [[q.x, q.y, q.z] for q in m.points],
                 "position": [m.pose.position.x, m.pose.position.y, m.pose.position.z]} for m in ma.markers]}, f)
        print(f"markers of tick {mk_ticks[closest]} (the smallest distance received) in {sys.argv[5]}")
    check(n_mk > 0 and n_tick >= 0.99 * n_mk and not mk_fail,
          f"{n_mk} MarkerArrays, {n_tick} at a tick whose JointState came; closest points, distance, zone colour "
          f"and capsule chain as mcad's CSV" + (f": {mk_fail[:3]}" if mk_fail else ""))
    n_exp = len({k for k in published if mk_ticks and k >= mk_ticks[0]})
    check(n_exp and len(set(mk_ticks)) >= 0.99 * n_exp,
          f"MarkerArrays: {len(set(mk_ticks))} of the {n_exp} ticks published from the first received (>= 99 %)")

    # Diagnostics
    states = idl_enums.controller_state_names()
    dg_fail, n_dg, seen = [], 0, set()
    for da in main.diag:
        for s in da.status:
            kv = {v.key: v.value for v in s.values}
            if s.hardware_id != NS or "tick" not in kv:
                continue
            n_dg += 1
            # the final status (sent as mcad closes) says the number of ticks run: its state is the last tick's
            k = min(int(kv["tick"]), len(rows) - 1)
            seen.add(kv["state"])
            min_so_far = min(float(rows[i]["min_d"]) for i in range(k + 1))
            if kv["state"] != states[int(rows[k]["state"])] or abs(float(kv["min_distance_so_far_m"]) - min_so_far) > 1e-12:
                dg_fail.append(f"tick {k}: state {kv['state']} min {kv['min_distance_so_far_m']} vs CSV "
                               f"{states[int(rows[k]['state'])]} {min_so_far!r}")
            if stamp_ns(da.header) in tick_of_stamp and tick_of_stamp[stamp_ns(da.header)] != k:
                dg_fail.append(f"stamp of tick {kv['tick']} is the stamp of tick {tick_of_stamp[stamp_ns(da.header)]}")
    check(n_dg >= 3 and not dg_fail, f"{n_dg} diagnostics: state and minimum distance so far as mcad's CSV at "
          f"their tick" + (f": {dg_fail[:3]}" if dg_fail else ""))
    check({"running", "stopped"} <= seen, f"diagnostics went through running and stopped ({sorted(seen)})")

    # Late joiners: descriptions over rclpy, TF over Cyclone
    for a in ARMS:
        with open(os.path.join(SRC, "config", "robots", "pa10plus.urdf")) as f:
            urdf = f.read()
        check(late.desc.get(a) == urdf, f"late node: {topic('robot_description', a)} is the URDF text "
              f"({len(late.desc.get(a, ''))} of {len(urdf)} bytes)")
    tf = [s for s in tfs if getattr(s, "transforms", None)]
    check(len(tf) == 1, f"late Cyclone reader: {len(tf)} /tf_static sample (transient-local, one)")
    if tf:
        bases = scenario_placements()
        got = {x.child_frame_id: x for x in tf[0].transforms}
        for a in ARMS:
            x = got.get(f"{a}/base_link")
            xyz, rpy = bases[a]
            q = quat_rpy(*rpy)
            ok = x is not None and x.header.frame_id == "world"
            if ok:
                tr, ro = x.transform.translation, x.transform.rotation
                ok = math.dist((tr.x, tr.y, tr.z), xyz) < 1e-12 and (
                    math.dist((ro.x, ro.y, ro.z, ro.w), q) < 1e-12 or
                    math.dist((ro.x, ro.y, ro.z, ro.w), tuple(-c for c in q)) < 1e-12)
            check(ok, f"/tf_static: world -> {a}/base_link at xyz {xyz} rpy {rpy} "
                  f"(have {sorted(got)})")


def scenario_placements():
    """base_xyz / base_rpy of each arm, read from the scenario YAML with PyYAML-free parsing."""
    out, arm = {}, None
    with open(os.path.join(SRC, "config", "scenarios", "cross_circles.yaml")) as f:
        for line in f:
            s = line.split("#")[0].strip()
            if s.startswith("- name:"):
                arm = s.split(":", 1)[1].strip()
                out[arm] = [(0.0, 0.0, 0.0), (0.0, 0.0, 0.0)]
            for i, k in enumerate(("base_xyz:", "base_rpy:")):
                if arm and s.startswith(k):
                    out[arm][i] = tuple(float(v) for v in s.split(":", 1)[1].strip(" []").split(","))
    return {a: tuple(v) for a, v in out.items()}


def mode_restart(tmp):
    """Issue 16: mcad's DDS bridge process killed (SIGSEGV) mid-run: /diagnostics says dds_bridge_restarts 0
    before and 1 from the restarted bridge, JointState flows again, mcad runs its task to the end (exit 0).
    /diagnostics comes once a second: the kill waits for the first one."""
    main = Collector("mca_ros2_restart")
    main.all_topics()
    ex = spin_in_background(main)
    time.sleep(2.0)  # our readers exist before mcad's writers
    run_s = 12.0  # the kill waits for the first /diagnostics: up to 8 s when the executor is behind
    proc, _ = run_mcad(tmp, CELL.replace(f"duration: {RUN_S}", f"duration: {run_s}")
                       .replace(f"stop_after: {RUN_S}", f"stop_after: {run_s}"))
    t_end = time.monotonic() + 8.0
    while time.monotonic() < t_end:  # until the first bridge's /diagnostics reached us
        with main.lock:
            if any(st.hardware_id == NS for da in main.diag for st in da.status):
                break
        time.sleep(0.05)
    time.sleep(0.3)
    try:
        children = open(f"/proc/{proc.pid}/task/{proc.pid}/children").read().split()
    except OSError:
        children = []
    check(len(children) == 1, f"mcad has one child, its DDS bridge ({children})")
    t_kill = time.time_ns()
    if children:
        os.kill(int(children[0]), signal.SIGSEGV)
    _, err = proc.communicate(timeout=120)
    settle(main)  # the last samples
    ex.shutdown()
    print("\n".join(line for line in err.splitlines() if "bridge" in line))
    check(proc.returncode == 0, f"mcad exit status {proc.returncode}")
    # (an ASan build's bridge turns the SIGSEGV into a report and an exit: the cause is printed above)
    check("died: " in err and "restart 1 in 0.1 s" in err and "dds bridge restarted" in err,
          "mcad logged the bridge's death and its restart")
    restarts = []  # (receipt, state, dds_bridge_restarts)
    health = []  # the restarted bridge's: (level, message, deaths, last death, back-off)
    with main.lock:
        diag = list(main.diag)
        js_after = [m for m in main.js["left"] if stamp_ns(m.header) > t_kill]
    for da in diag:
        for st in da.status:
            kv = {v.key: v.value for v in st.values}
            if st.hardware_id == NS and "dds_bridge_restarts" in kv:
                restarts.append((stamp_ns(da.header), kv["state"], kv["dds_bridge_restarts"]))
                if kv["dds_bridge_restarts"] == "1":
                    health.append((st.level, st.message, kv.get("dds_bridge_deaths"), kv.get("dds_bridge_last_death"),
                                   kv.get("dds_bridge_backoff_s")))
    print("diagnostics (stamp, state, dds_bridge_restarts):",
          [(round((t - t_kill) / 1e9, 3), s, r) for t, s, r in restarts])
    check(any(r == "0" and t < t_kill for t, _, r in restarts), "/diagnostics before the kill: dds_bridge_restarts 0")
    check(any(r == "1" and s == "running" for _, s, r in restarts),
          "/diagnostics from the restarted bridge: dds_bridge_restarts 1, running")
    # the death is said on /diagnostics too: a WARN (the controller is fine; its monitoring was down), the
    # count, the cause and the back-off
    h = health[0] if health else None
    lvl = None if h is None else (h[0][0] if isinstance(h[0], (bytes, bytearray)) else int(h[0]))
    check(lvl == 1, f"/diagnostics from the restarted bridge: level WARN (1) while its death is recent: {h}")
    check(h is not None and h[2] == "1" and h[3] and h[4] == "0.1" and "dds bridge restarted 1 times" in h[1],
          "/diagnostics from the restarted bridge: dds_bridge_deaths 1, its cause, back-off 0.1 s, said in the "
          f"message: {h}")
    check(len(js_after) > 100, f"{len(js_after)} JointState samples of arm left stamped after the kill")
    print(f"JointState of arm left: {len(main.js['left']) - len(js_after)} before the kill, {len(js_after)} after")


def mode_graph(tmp):
    node = Node("mca_ros2_graph")
    best_effort = []
    node.create_subscription(JointState, topic("joint_states", "left"), best_effort.append, qos_profile_sensor_data)
    ex = spin_in_background(node)
    time.sleep(2.0)
    # the right arm turned about all three axes (yaw past 90 deg: the other branches of the rotation ->
    # quaternion conversion than an identity base); /tf_static must carry exactly that rotation
    rpy = (0.3, -0.2, 2.8)
    proc, _ = run_mcad(tmp, CELL.replace("  - name: right\n    backend: sim",
                                         f"  - name: right\n    backend: sim\n    base_rpy: [{rpy[0]}, {rpy[1]}, {rpy[2]}]"))
    tf_reader = tf_static_reader()
    time.sleep(1.5)
    tfs = []
    for _ in range(40):
        tfs += [x for s in tf_reader.take(N=10) if getattr(s, "transforms", None) for x in s.transforms]
        if tfs:
            break
        time.sleep(0.05)
    got = {x.child_frame_id: x.transform.rotation for x in tfs}
    q = quat_rpy(*rpy)
    ro = got.get("right/base_link")
    err = min(math.dist((ro.x, ro.y, ro.z, ro.w), q), math.dist((ro.x, ro.y, ro.z, ro.w), [-c for c in q])) \
        if ro else 1.0
    check(err < 1e-12, f"/tf_static: right/base_link turned by rpy {rpy}: quaternion within {err:.1e} of "
          f"the one computed here from the rpy")
    names = dict(node.get_topic_names_and_types())
    want = {topic("joint_states", a): "sensor_msgs/msg/JointState" for a in ARMS}
    want.update({topic("robot_description", a): "std_msgs/msg/String" for a in ARMS})
    want.update({"/tf_static": "tf2_msgs/msg/TFMessage", topic("distance_markers"): "visualization_msgs/msg/MarkerArray",
                 "/diagnostics": "diagnostic_msgs/msg/DiagnosticArray"})
    for n, ty in want.items():
        check(names.get(n) == [ty], f"graph: {n} [{ty}] (seen {names.get(n)})")
    extra = [n for n in names if n.startswith(f"/{NS}/") and n not in want]
    check(not extra, f"graph: no other topics under /{NS}/ ({extra})")
    for n in want:
        infos = node.get_publishers_info_by_topic(n)
        latched = n.endswith("robot_description") or n == "/tf_static"
        ok = len(infos) == 1 and infos[0].qos_profile.reliability == ReliabilityPolicy.RELIABLE and (
            infos[0].qos_profile.durability ==
            (DurabilityPolicy.TRANSIENT_LOCAL if latched else DurabilityPolicy.VOLATILE))
        check(ok, f"graph: {n}: one publisher, reliable, {'transient-local' if latched else 'volatile'} "
              f"({[(i.qos_profile.reliability.name, i.qos_profile.durability.name) for i in infos]})")
    _, err = proc.communicate(timeout=120)
    time.sleep(0.5)
    ex.shutdown()
    check(proc.returncode == 0, f"mcad exit status {proc.returncode}")
    libs = subprocess.run(["ldd", MCAD], capture_output=True, text=True).stdout
    ros_libs = [ln.split()[0] for ln in libs.splitlines() if any(w in ln for w in ("rcl", "rmw", "fastr", "ros"))]
    check("libddsc" in libs and not ros_libs, f"mcad links Cyclone DDS and no ROS library (ldd: {ros_libs})")
    check(len(best_effort) >= 50, f"sensor-data QoS (best effort) subscriber: {len(best_effort)} JointStates "
          f"in {RUN_S} s at 100 Hz")


def tips_of(ma):
    """Tool tip of each arm: the last end cap of its last link."""
    tips = {}
    for a in ARMS:
        caps = sorted((m for m in ma.markers if m.ns == f"{a}/links" and m.type == Marker.SPHERE_LIST),
                      key=lambda m: m.id)
        if caps:
            q = caps[-1].points[-1]
            tips[a] = (q.x, q.y, q.z)
    return tips


def mode_stream(tmp):
    global NS
    NS = "stream_sim"
    src_cell = open(os.path.join(SRC, "config", "cells", "stream_sim.yaml")).read()
    cell_text = (src_cell.replace("../scenarios/", f"{SRC}/config/scenarios/").replace("../dds/", f"{SRC}/config/dds/")
                 .replace("domain: 0", f"domain: {DOMAIN}").replace("priority: 80", "priority: 60")
                 .replace("stop_after: 0 ", "stop_after: 60 "))
    cell, out_csv = os.path.join(tmp, "cell.yaml"), os.path.join(tmp, "mcad.csv")
    with open(cell, "w") as f:
        f.write(cell_text)
    node = Collector("mca_ros2_stream")
    node.all_topics()
    pub_l = node.create_publisher(TwistStamped, topic("target_twist", "left"), 10)
    pub_r = node.create_publisher(PoseStamped, topic("target_pose", "right"), 10)
    ex = spin_in_background(node)
    time.sleep(2.0)
    proc = subprocess.Popen([MCAD, "--csv", out_csv, cell], stderr=subprocess.PIPE, text=True)
    t_end = time.monotonic() + 20
    while not node.markers and time.monotonic() < t_end:
        time.sleep(0.05)
    check(bool(node.markers), "mcad's markers arrived (the tool tips)")
    tips0 = tips_of(node.markers[-1])
    print("tool tips at start:", {a: tuple(round(x, 3) for x in p) for a, p in tips0.items()})

    def twist(v, frame="world"):
        m = TwistStamped()
        m.header.frame_id = frame
        m.header.stamp = node.get_clock().now().to_msg()
        m.twist.linear.x, m.twist.linear.y, m.twist.linear.z = v
        return m

    def pose(p, frame="world"):
        m = PoseStamped()
        m.header.frame_id = frame
        m.header.stamp = node.get_clock().now().to_msg()
        m.pose.position.x, m.pose.position.y, m.pose.position.z = p
        m.pose.orientation.w = 1.0
        return m

    def drive(seconds, v_left, p_right, bad=None):
        t0 = time.monotonic()
        k = 0
        while time.monotonic() - t0 < seconds:
            if bad and k == 10:
                bad()
            pub_l.publish(twist(v_left))
            pub_r.publish(pose(p_right))
            sent_l.append(time.monotonic())
            k += 1
            time.sleep(0.02)  # 50 Hz

    sent_bad = []
    sent_l = []  # when each of left's twists went out

    def bad_inputs():
        pub_l.publish(twist((float("nan"), 0.0, 0.0)))
        pub_l.publish(twist((0.05, 0.0, 0.0), frame="base_link"))
        pub_l.publish(twist((0.5, 0.0, 0.0)))
        pub_r.publish(pose((5.0, 0.0, 0.5)))
        sent_bad.extend(["nan", "frame", "speed", "box"])

    L, R = tips0["left"], tips0["right"]
    gap = [r - l for l, r in zip(L, R)]
    n = math.sqrt(sum(g * g for g in gap))
    toward = [0.15 * g / n for g in gap]
    t_phase = {}
    t_phase["drive"] = time.time_ns()
    drive(4.0, toward, L)                        # A: at each other
    t_phase["back"] = time.time_ns()
    drive(3.0, [-x for x in toward], R, bad_inputs)  # B: back off (right back to its start), bad inputs
    t_phase["silent"] = time.time_ns()
    # C: left silent; right keeps streaming its start (only left's stream goes stale)
    t0 = time.monotonic()

    def faulted():
        with node.lock:
            return any(kv.value == "fault" for da in node.diag[-3:] for st in da.status for kv in st.values
                       if kv.key == "state")

    while proc.poll() is None and time.monotonic() - t0 < 10 and not faulted():
        pub_r.publish(pose(R))
        time.sleep(0.02)
    silent_s = time.monotonic() - sent_l[-1]
    gaps = [b - a for a, b in zip(sent_l, sent_l[1:])]
    print(f"left: {len(sent_l)} twists sent, largest gap {max(gaps) * 1e3:.0f} ms")
    proc.send_signal(signal.SIGTERM)  # a faulted mcad holds the arms braked until it is told to go
    try:
        _, err = proc.communicate(timeout=30)
    except subprocess.TimeoutExpired:
        proc.kill()
        _, err = proc.communicate()
    time.sleep(1.5)
    ex.shutdown()
    print("mcad stderr (last lines):", "\n".join(err.strip().splitlines()[-6:]))
    check(faulted() and 1.0 <= silent_s <= 3.0,
          f"/diagnostics said fault {silent_s:.2f} s after left's last twist went out (brake_after 1 s; "
          f"<= 3 s with delivery on a loaded machine)")
    check(proc.returncode == 3, f"mcad exit status {proc.returncode} after SIGTERM (3: ended in a fault)")
    check("no target on its stream" in err and "left" in err, "the fault names the stale stream and the arm")
    rows = read_csv(out_csv)
    d = [float(r["min_d"]) for r in rows]
    states = [int(r["state"]) for r in rows]
    st = dict(idl_enums.controller_states())
    check(min(d) >= D1, f"every one of {len(rows)} ticks at or above d1 = {D1} m (min {min(d):.4f} m)")
    # phases in the CSV: mcad's t is task time from its first tick; map by the ticks the diagnostics stamped
    running = [i for i, s_ in enumerate(states) if s_ == st["STATE_RUNNING"]]
    check(min(d[i] for i in running) < D2, f"the tips came within d2 = {D2} m while driven at each other "
          f"(min {min(d[i] for i in running):.4f} m): the yield was needed")
    brake_from = next((i for i, s_ in enumerate(states) if s_ in (st["STATE_BRAKING"], st["STATE_FAULT"])), None)
    check(brake_from is not None and states[-1] == st["STATE_FAULT"], "mcad braked and ended in FAULT")
    # B: the distance grew past d2 again before the stale fault
    if brake_from:
        i_min = min(running, key=lambda i: d[i])
        check(max(d[i_min:brake_from]) > D2, f"after backing off the distance grew to "
              f"{max(d[i_min:brake_from]):.3f} m > d2 (the arms resumed)")
        # left's reference held (rd0 constant) for the last (brake_after - hold_after - 0.1) s before braking
        held = 0
        while held < brake_from and all(rows[brake_from - 1 - held][c] == rows[brake_from - 1][c]
                                        for c in ("rd0_x", "rd0_y", "rd0_z")):
            held += 1
        check(700 <= held <= 950, f"left's reference held {held} ticks before the brake: from hold_after (0.1 s) "
              f"to brake_after (1 s) of silence")
        # during back-off left's reference moved at the commanded 0.15 m/s at some point (sigma ~ 1)
        speeds = [math.dist((float(rows[i]["rd0_x"]), float(rows[i]["rd0_y"]), float(rows[i]["rd0_z"])),
                            (float(rows[i + 100]["rd0_x"]), float(rows[i + 100]["rd0_y"]),
                             float(rows[i + 100]["rd0_z"]))) / 0.1 for i in range(i_min, brake_from - 800, 50)]
        check(speeds and abs(max(speeds) - 0.15) < 0.01,
              f"backing off, left's reference reached the commanded 0.15 m/s (max {max(speeds or [0]):.3f})")
    # bad inputs: counted and reported
    last = None
    for da in node.diag:
        for st in da.status:
            kv = {v.key: v.value for v in st.values}
            if "stream_rejected" in kv:
                last = kv
    check(last is not None and int(last["stream_rejected"]) == len(sent_bad),
          f"/diagnostics: stream_rejected {last and last['stream_rejected']} = {len(sent_bad)} bad targets sent, "
          f"last reason '{last and last['stream_last_reject']}'")
    check(last is not None and "workspace" in last["stream_last_reject"],
          "the last reason names the out-of-box pose")
    check(last is not None and int(last["stream_accepted"]) > 300, f"accepted {last and last['stream_accepted']}")


def cell_topics(path):
    """A cell file's ROS 2 namespace (dds.ros2.namespace, or its name with other characters as '_'), arm names
    and dds.publish_divisor, read line by line (the cells' block and flow styles)."""
    name, ns, arms, divisor, in_arms = None, None, [], 1, False
    with open(path) as f:
        for line in f:
            s = line.split("#")[0].rstrip()
            if not s.strip():
                continue
            if not s.startswith(" "):
                in_arms = s.startswith("arms:")
                if s.startswith("name:"):
                    name = s.split(":", 1)[1].strip()
            m = re.search(r"name:\s*([A-Za-z0-9_]+)", s)
            if in_arms and s.lstrip().startswith("- ") and m:
                arms.append(m.group(1))
            m = re.search(r"namespace:\s*([A-Za-z0-9_]+)", s)
            ns = m.group(1) if m else ns
            m = re.search(r"publish_divisor:\s*([0-9]+)", s)
            divisor = int(m.group(1)) if m else divisor
    return ns or re.sub(r"[^A-Za-z0-9_]", "_", name), arms, divisor


def mode_listen(tmp):
    """A user's node on some host (test_hosts.py): see the module's docstring."""
    global NS, ARMS
    NS, ARMS, divisor = cell_topics(CELL_FILE)
    env = sorted(k for k in os.environ if k.startswith(("ROS_", "RMW_", "CYCLONEDDS", "FASTRTPS", "FASTDDS")))
    node = Collector(f"mca_listen_{ROLE}")
    node.all_topics()
    ex = SingleThreadedExecutor()  # spun here: the graph queries below stay in this one thread
    ex.add_node(node)
    print(f"{ROLE}: rmw {rclpy.get_rmw_implementation_identifier()}, environment: "
          f"{', '.join(f'{k}={os.environ[k]}' for k in env) or 'no ROS_*, RMW_*, CYCLONEDDS_*, FAST* variables'}")
    mine = [topic("joint_states", a) for a in ARMS] + [topic("distance_markers"), "/diagnostics"]
    pubs = dict.fromkeys(mine, 0)  # the most publishers seen on each topic while mcad ran
    t_end, t_status = time.monotonic() + 300, 0.0
    while not os.path.exists(os.path.join(WORK, "done")) and time.monotonic() < t_end:
        ex.spin_once(timeout_sec=0.02)
        if time.monotonic() - t_status < 0.1:
            continue
        t_status = time.monotonic()
        for t in mine:
            pubs[t] = max(pubs[t], node.count_publishers(t))
        st = {"js": min(len(v) for v in node.js.values()), "markers": len(node.markers), "diag": len(node.diag)}
        with open(os.path.join(WORK, ROLE + ".tmp"), "w") as f:
            json.dump(st, f)
        os.replace(os.path.join(WORK, ROLE + ".tmp"), os.path.join(WORK, ROLE + ".status"))
    # mcad has exited: take what is still queued, until nothing new came for 1.5 s (at most 30 s)
    t_end, last, t_last = time.monotonic() + 30, -1, time.monotonic()
    while time.monotonic() < t_end and time.monotonic() - t_last < 1.5:
        ex.spin_once(timeout_sec=0.05)
        if node.received() != last:
            last, t_last = node.received(), time.monotonic()
    ex.shutdown()
    diag = [st for da in node.diag for st in da.status if st.hardware_id == NS]
    if EXPECT == "none":
        got = {a: len(node.js[a]) for a in ARMS}
        check(not any(got.values()) and not node.markers and not diag,
              f"{ROLE}: nothing of /{NS} received (JointState {got}, {len(node.markers)} MarkerArrays, "
              f"{len(diag)} diagnostics)")
        check(not any(pubs.values()), f"{ROLE}: no publisher of /{NS}'s topics ever in the graph ({pubs})")
        return
    rows = read_csv(os.path.join(WORK, "mcad.csv"))
    published = published_ticks(rows, divisor)
    print(f"{ROLE}: mcad: {len(rows)} ticks in its CSV, {len(published)} published")
    tick_of_stamp, got = {}, []
    for ai, a in enumerate(ARMS):
        got.append(check_joint_states(f"{ROLE}: {a}", ai, node.js[a], rows, published, tick_of_stamp, 0.999))
    check(min(n for n, _ in got) >= 100, f"{ROLE}: >= 100 JointStates of each arm ({[n for n, _ in got]})")
    mk = sorted({tick_of_stamp[stamp_ns(ma.markers[0].header)] for ma in node.markers
                 if ma.markers and stamp_ns(ma.markers[0].header) in tick_of_stamp})
    n_mk = len({k for k in published if mk and k >= mk[0]})  # distinct: the final snapshot may repeat a tick
    check(len(mk) >= 0.99 * n_mk > 0, f"{ROLE}: {len(node.markers)} MarkerArrays; {len(mk)} of the {n_mk} ticks "
          f"published from the first received ({100 * len(mk) / max(n_mk, 1):.2f} % >= 99 %)")
    check(len(diag) > 0, f"{ROLE}: {len(diag)} diagnostics of mcad: {NS} (states "
          f"{sorted({kv.value for st in diag for kv in st.values if kv.key == 'state'})})")
    check(all(pubs[t] == 1 for t in mine), f"{ROLE}: one publisher on each of the cell's topics ({pubs})")


rclpy.init()
with tempfile.TemporaryDirectory(prefix="mca-ros2-") as tmp:
    {"topics": mode_topics, "graph": mode_graph, "stream": mode_stream, "restart": mode_restart,
     "listen": mode_listen}[MODE](tmp)
rclpy.try_shutdown()
print("FAILED: " + "; ".join(failures) if failures else "PASSED", flush=True)
sys.exit(1 if failures else 0)
