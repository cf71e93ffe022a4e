# SPDX-License-Identifier: MIT
"""A Python subscriber (PyPI cyclonedds, types written in Python: mca_types.py) receives a 10 s, 1 kHz
stream that mca-dds-synth publishes through the real ring + publisher thread, and checks:
  - >= 99.9 % of the 10 000 Distances samples and of the 2 x 10 000 JointState samples arrive,
  - every received sample is EQUAL to what was published (the pattern is recomputed here),
  - ticks arrive strictly increasing, no duplicates; stamps strictly increasing,
  - JointCommand values and frame id, and the final ControllerStatus (ticks, drop count),
and prints the end-to-end latency tick stamp -> Python receipt (p50, p99; same host, CLOCK_MONOTONIC).
usage: test_python_sub.py --synth PATH --config XML --domain N [--ticks 10000]"""
import argparse
import os
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mca_types as m  # noqa: E402


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--synth", required=True)
    ap.add_argument("--config", required=True)
    ap.add_argument("--domain", type=int, required=True)
    ap.add_argument("--ticks", type=int, default=10000)
    a = ap.parse_args()
    os.environ["CYCLONEDDS_URI"] = "file://" + os.path.abspath(a.config)

    from cyclonedds.domain import DomainParticipant
    from cyclonedds.sub import DataReader
    from cyclonedds.topic import Topic

    from cyclonedds.qos import Policy, Qos
    from cyclonedds.sub import Subscriber

    # A partition of our own: other tests' publishers (mcad, ...) may share the domain.
    partition = f"mca-test-pysub-{os.getpid()}"
    dp = DomainParticipant(a.domain)
    sub = Subscriber(dp, qos=Qos(Policy.Partition(partitions=[partition])))
    rd = DataReader(sub, Topic(dp, m.TOPIC_DISTANCES, m.Distances, qos=m.stream_qos()), qos=m.stream_qos())
    rj = DataReader(sub, Topic(dp, m.TOPIC_JOINT_STATE, m.JointState, qos=m.stream_qos()), qos=m.stream_qos())
    rc = DataReader(sub, Topic(dp, m.TOPIC_JOINT_COMMAND, m.JointCommand, qos=m.stream_qos()),
                    qos=m.stream_qos())
    rs = DataReader(sub, Topic(dp, m.TOPIC_STATUS, m.ControllerStatus, qos=m.status_qos()), qos=m.status_qos())

    pub = subprocess.Popen([a.synth, "--domain", str(a.domain), "--config", a.config, "--ticks", str(a.ticks),
                            "--wait-readers", "1", "--wait-timeout", "20000", "--partition", partition,
                            # 4 s of ring: a loaded CI machine may starve the publisher thread for
                            # a few hundred ms (seen under ASan with make -j); drops would be counted
                            "--ring", "4096"],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    dist, js, jc, status = [], [], [], []
    latency = []
    errors = []
    t_exit = None
    last_rx = time.monotonic()
    while True:
        got = 0
        for s in rd.take(N=1000):
            if isinstance(s, m.Distances):
                latency.append(time.monotonic_ns() - s.stamp_ns)
                dist.append(s)
                got += 1
        for s in rj.take(N=1000):
            if isinstance(s, m.JointState):
                js.append(s)
                got += 1
        for s in rc.take(N=1000):
            if isinstance(s, m.JointCommand):
                jc.append(s)
                got += 1
        for s in rs.take(N=100):
            if isinstance(s, m.ControllerStatus):
                status.append(s)
        now = time.monotonic()
        if got:
            last_rx = now
        if t_exit is None and pub.poll() is not None:
            t_exit = now
        if t_exit is not None:
            # The publisher has finished (its destroy waited for acknowledgements): drain what this
            # process still holds; on a loaded machine Python may be seconds behind.
            complete = len(dist) >= a.ticks and len(js) >= 2 * a.ticks and len(jc) >= 2 * a.ticks
            if complete or now - last_rx > 3.0 or now - t_exit > 60.0:
                break
        if got == 0:
            time.sleep(0.002)
    out, err = pub.communicate()
    print(out.strip())
    if pub.returncode != 0:
        print(err)
        raise SystemExit(f"FAIL: mca-dds-synth exited with {pub.returncode}")
    stats = dict(zip(out.split()[1::2], map(int, out.split()[2::2])))

    n = a.ticks
    need = int(n * 0.999 + 0.999999)
    # Distances: count, order, equality of every field.
    ticks = [s.tick for s in dist]
    if any(b <= a_ for a_, b in zip(ticks, ticks[1:])):
        errors.append("Distances ticks not strictly increasing (duplicate or reordered sample)")
    stamps = [s.stamp_ns for s in dist]
    if any(b <= a_ for a_, b in zip(stamps, stamps[1:])):
        errors.append("Distances stamps not strictly increasing")
    for s in dist:
        errors += m.check_distances(s)
    missing = sorted(set(range(n)) - set(ticks))
    if missing:
        print(f"Distances missing ticks ({len(missing)}): {missing[:20]}")
    if len(set(ticks)) < need:
        errors.append(f"Distances: received {len(set(ticks))} of {n}, need >= {need}")
    # JointState: per arm.
    for arm in (0, 1):
        t_arm = [s.tick for s in js if s.arm_id == arm]
        if len(set(t_arm)) < need:
            errors.append(f"JointState arm {arm}: received {len(set(t_arm))} of {n}, need >= {need}")
    for s in js:
        errors += m.check_joint_state(s)
    # JointCommand: values and frame id.
    for s in jc:
        _, _, _, vsp, pref = m.expected_arm(s.tick, s.arm_id)
        if list(s.velocity_setpoint) != vsp or list(s.position_reference) != pref or s.frame_id != "world":
            errors.append(f"JointCommand tick {s.tick} arm {s.arm_id} differs")
    if len({(s.tick, s.arm_id) for s in jc}) < 2 * need:
        errors.append(f"JointCommand: received {len(jc)} of {2 * n}")
    # Status: the last one is the final status published by mca_dds_bridge_destroy().
    if not status:
        errors.append("no ControllerStatus received")
    else:
        last = status[-1]
        if last.ticks != n or last.tick != n - 1:
            errors.append(f"final status ticks {last.ticks} tick {last.tick}, want {n} and {n - 1}")
        if last.snapshots_dropped != stats.get("dropped", -1):
            errors.append(f"final status dropped {last.snapshots_dropped} != publisher's {stats.get('dropped')}")
        if last.min_distance_so_far != 0.02 or last.state not in (m.ControllerState.STATE_RUNNING,
                                                                  m.ControllerState.STATE_BRAKING):
            errors.append(f"final status {last}")
    if stats.get("published", 0) + stats.get("dropped", 0) != n:
        errors.append(f"publisher: published + dropped != {n}: {stats}")

    latency.sort()
    if latency:
        p = lambda q: latency[min(len(latency) - 1, int(q * (len(latency) - 1)))] / 1e3  # noqa: E731
        print(f"received: distances {len(dist)}, joint states {len(js)}, joint commands {len(jc)}, "
              f"status {len(status)}; publisher dropped {stats.get('dropped')}")
        slow = sum(1 for x in latency if x > 10_000_000)
        print(f"samples later than 10 ms: {slow}")
        print(f"latency tick stamp -> Python receipt: p50 {p(0.5):.0f} us, p99 {p(0.99):.0f} us, "
              f"max {latency[-1] / 1e3:.0f} us (includes the Python polling loop)")
    if errors:
        for e in errors[:20]:
            print("FAIL:", e)
        raise SystemExit(f"FAIL: {len(errors)} problem(s)")
    print("PASS")


if __name__ == "__main__":
    main()
