# SPDX-License-Identifier: MIT
"""A peer that must not take the controller down: a subscriber of mca/distances whose type
a new user wrote from dds/mca_dds.idl in the obvious way, plain uint8 keys and no must-understand
annotation. Its XTypes type identifiers differ from idlc's (tests/dds/mca_types.py has the matching
definition), so libddsc 0.10.2 asks this (PyPI cyclonedds 11.x) side for the type object and, on the
reply, crashes in its type-lookup thread (docs/dds.md). Runs until killed; prints what it receives.
usage: crash_peer.py DOMAIN CYCLONE_XML"""
import os
import sys
import time
from dataclasses import dataclass

os.environ["CYCLONEDDS_URI"] = "file://" + os.path.abspath(sys.argv[2])

from cyclonedds.domain import DomainParticipant  # noqa: E402
from cyclonedds.idl import IdlStruct  # noqa: E402
from cyclonedds.idl.annotations import final, key  # noqa: E402
from cyclonedds.sub import DataReader  # noqa: E402
from cyclonedds.topic import Topic  # noqa: E402
import cyclonedds.idl.types as t  # noqa: E402


@final
@dataclass
class Distances(IdlStruct, typename="mca::dds::Distances"):
    pair_id: t.uint8
    key("pair_id")
    arm_a: t.uint8
    arm_b: t.uint8
    tick: t.uint64
    stamp_ns: t.int64
    min_distance: t.float64
    p: t.array[t.float64, 3]
    e: t.array[t.float64, 3]
    link_a: t.int16
    link_b: t.int16
    d1: t.float64
    d2: t.float64
    brake_factor: t.float64
    link_distance_a: t.sequence[t.float64, 9]
    link_distance_b: t.sequence[t.float64, 9]


dp = DomainParticipant(int(sys.argv[1]))
rd = DataReader(dp, Topic(dp, "mca/distances", Distances))
print("crash peer: reader of mca/distances with uint8 keys, no must-understand", flush=True)
n = 0
while True:
    for s in rd.take(N=100):
        n += 1
        if n == 1:
            print(f"crash peer: first sample, tick {s.tick}", flush=True)
    time.sleep(0.05)
