#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""A Python subscriber of a running mcad (PyPI cyclonedds, the types of mca_types.py, byte-identical to idlc's):
mca/distances and mca/controller_status for DURATION seconds, one CSV row per sample received
(rx_ns = CLOCK_MONOTONIC at receipt, tick, min_distance, state = the last status state received before it).
usage: py_watch.py CONFIG_XML DOMAIN DURATION OUT_CSV"""
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mca_types as m  # noqa: E402

config, domain, duration, out = sys.argv[1], int(sys.argv[2]), float(sys.argv[3]), sys.argv[4]
os.environ["CYCLONEDDS_URI"] = "file://" + os.path.abspath(config)
from cyclonedds.domain import DomainParticipant  # noqa: E402
from cyclonedds.sub import DataReader  # noqa: E402
from cyclonedds.topic import Topic  # noqa: E402

dp = DomainParticipant(domain)
rd = DataReader(dp, Topic(dp, m.TOPIC_DISTANCES, m.Distances, qos=m.stream_qos()), qos=m.stream_qos())
rs = DataReader(dp, Topic(dp, m.TOPIC_STATUS, m.ControllerStatus, qos=m.status_qos()), qos=m.status_qos())
state = ""
t_end = time.monotonic() + duration
with open(out, "w") as f:
    f.write("rx_ns,tick,min_distance,state\n")
    while time.monotonic() < t_end:
        got = 0
        for s in rs.take(N=100):
            if isinstance(s, m.ControllerStatus):
                state = m.ControllerState(s.state).name.replace("STATE_", "")
        for s in rd.take(N=1000):
            if isinstance(s, m.Distances):
                f.write(f"{time.monotonic_ns()},{s.tick},{s.min_distance!r},{state}\n")
                got += 1
        if not got:
            time.sleep(0.005)
        f.flush()
print(f"py_watch: done, last state {state or '-'}")
