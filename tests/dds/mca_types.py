# SPDX-License-Identifier: MIT
"""mca DDS types written in Python (the structs independent of dds/mca_dds.idl and its C code, so that
test_types_match.py compares two writings): same fully qualified names, same keys, same field order, all
@final; the state numbering (an int32 on the wire, no part of the types) is the IDL's, read from it. Also the deterministic synthetic pattern of
dds/include/mca/dds_synth.h, reimplemented here so a subscriber can check every field it receives.
Topic names and QoS as in docs/dds.md."""
import enum
import math
from dataclasses import dataclass

from cyclonedds.idl import IdlStruct
from cyclonedds.idl.annotations import final, key, must_understand
import cyclonedds.idl.types as t

import idl_enums

MAX_DOF = 8
MAX_LINKS = 9

TOPIC_JOINT_STATE = "mca/joint_state"
TOPIC_JOINT_COMMAND = "mca/joint_command"
TOPIC_DISTANCES = "mca/distances"
TOPIC_STATUS = "mca/controller_status"
TOPIC_PAIR_DISTANCES = "mca/pair_distances"
MAX_PAIR_ENTRIES = 26


@final
@dataclass
class JointState(IdlStruct, typename="mca::dds::JointState"):
    arm_id: t.byte
    key("arm_id")
    must_understand("arm_id")  # idlc 0.10 marks keys must-understand
    tick: t.uint64
    stamp_ns: t.int64
    position: t.sequence[t.float64, MAX_DOF]
    velocity: t.sequence[t.float64, MAX_DOF]
    effort: t.sequence[t.float64, MAX_DOF]


@final
@dataclass
class JointCommand(IdlStruct, typename="mca::dds::JointCommand"):
    arm_id: t.byte
    key("arm_id")
    must_understand("arm_id")  # idlc 0.10 marks keys must-understand
    tick: t.uint64
    stamp_ns: t.int64
    velocity_setpoint: t.sequence[t.float64, MAX_DOF]
    position_reference: t.sequence[t.float64, MAX_DOF]
    frame_id: t.bounded_str[32]


@final
@dataclass
class Distances(IdlStruct, typename="mca::dds::Distances"):
    pair_id: t.byte
    key("pair_id")
    must_understand("pair_id")  # idlc 0.10 marks keys must-understand
    arm_a: t.byte
    arm_b: t.byte
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
    link_distance_a: t.sequence[t.float64, MAX_LINKS]
    link_distance_b: t.sequence[t.float64, MAX_LINKS]


# Values of PairDistance.kind (sent as int32): the IDL's own numbering, read from dds/mca_dds.idl.
PairKind = enum.IntEnum("PairKind", idl_enums.idl_enum("PairKind"))


@final
@dataclass
class PairDistance(IdlStruct, typename="mca::dds::PairDistance"):
    kind: t.int32
    arm: t.int16
    link: t.int16
    other_arm: t.int16
    other_link: t.int16
    body: t.int16
    name: t.bounded_str[32]
    distance: t.float64
    clearance: t.float64
    p: t.array[t.float64, 3]
    q: t.array[t.float64, 3]


@final
@dataclass
class PairDistances(IdlStruct, typename="mca::dds::PairDistances"):
    controller_id: t.byte
    key("controller_id")
    must_understand("controller_id")  # idlc 0.10 marks keys must-understand
    tick: t.uint64
    stamp_ns: t.int64
    pairs: t.sequence[PairDistance, MAX_PAIR_ENTRIES]


# Values of ControllerStatus.state (sent as int32): the IDL's own numbering, read from dds/mca_dds.idl.
ControllerState = enum.IntEnum("ControllerState", idl_enums.controller_states())


@final
@dataclass
class ControllerStatus(IdlStruct, typename="mca::dds::ControllerStatus"):
    controller_id: t.byte
    key("controller_id")
    must_understand("controller_id")  # idlc 0.10 marks keys must-understand
    tick: t.uint64
    stamp_ns: t.int64
    state: t.int32
    fault_code: t.int32
    fault_text: t.bounded_str[64]
    ticks: t.uint64
    overruns: t.uint64
    skipped_periods: t.uint64
    compute_p50_ns: t.int64
    compute_p99_ns: t.int64
    compute_max_ns: t.int64
    jitter_p50_ns: t.int64
    jitter_p99_ns: t.int64
    jitter_p999_ns: t.int64
    jitter_max_ns: t.int64
    pdnn_steps: t.uint32
    pdnn_residual: t.float64
    min_distance_so_far: t.float64
    min_distance_stamp_ns: t.int64
    snapshots_dropped: t.uint64
    pdnn_budget_hits: t.uint64


def stream_qos():
    """QoS of a READER of the 1 kHz streams. The writers are reliable keep-last 16 (docs/dds.md); a
    reader may keep all (history is not part of QoS matching), so a Python process that falls seconds
    behind on a loaded machine still loses nothing once the samples have reached it."""
    from cyclonedds.qos import Policy, Qos
    from cyclonedds.util import duration
    return Qos(Policy.Reliability.Reliable(duration(milliseconds=100)), Policy.History.KeepAll,
               Policy.Durability.Volatile)


def status_qos():
    from cyclonedds.qos import Policy, Qos
    from cyclonedds.util import duration
    return Qos(Policy.Reliability.Reliable(duration(milliseconds=100)), Policy.History.KeepLast(1),
               Policy.Durability.TransientLocal)


# ---- the synthetic pattern (dds/include/mca/dds_synth.h), second implementation ----
DOF = (7, 6)
D1, D2 = 0.05, 0.12


def brake_factor(d, d1, d2):
    """Paper eq. (13)."""
    if d >= d2:
        return 1.0
    if d <= d1:
        return 0.0
    return math.sin(math.pi / 2 * (d - d1) / (d2 - d1)) ** 2


def expected_arm(k, i):
    n = DOF[i]
    pos = [0.001 * k + 0.1 * j + i for j in range(n)]
    vel = [0.5 * j - 0.25 * i + 1e-6 * k for j in range(n)]
    eff = [-0.01 * (k % 97) + j for j in range(n)]
    vsp = [0.9 * v for v in vel]
    pref = [x + 0.0005 for x in pos]
    return pos, vel, eff, vsp, pref


def expected_min_distance(k):
    tri = abs((k % 2000) - 1000) / 1000.0
    return 0.02 + 0.16 * tri


def expected_distances(k):
    """Dict of the Distances fields for tick k (brake_factor separately: it goes through sin)."""
    d = expected_min_distance(k)
    p = [0.3 + 0.001 * (k % 100), -0.1, 0.5]
    e = [p[0], p[1] + d, p[2]]
    return dict(pair_id=0, arm_a=0, arm_b=1, tick=k, min_distance=d, p=p, e=e, link_a=k % 8,
                link_b=(k // 8) % 7, d1=D1, d2=D2,
                link_distance_a=[d + 0.01 * l for l in range(DOF[0] + 1)],
                link_distance_b=[d + 0.02 * l for l in range(DOF[1] + 1)])


def check_distances(s):
    """List of mismatches between a received Distances sample and the pattern (empty = equal)."""
    bad = []
    for name, want in expected_distances(s.tick).items():
        got = getattr(s, name)
        if isinstance(want, list):
            got = list(got)
        if got != want:
            bad.append(f"tick {s.tick} {name}: got {got!r} want {want!r}")
    want_s = brake_factor(s.min_distance, s.d1, s.d2)
    if abs(s.brake_factor - want_s) > 1e-12:
        bad.append(f"tick {s.tick} brake_factor: got {s.brake_factor!r} want {want_s!r}")
    return bad


def check_joint_state(s):
    pos, vel, eff, _, _ = expected_arm(s.tick, s.arm_id)
    bad = []
    for name, want in (("position", pos), ("velocity", vel), ("effort", eff)):
        if list(getattr(s, name)) != want:
            bad.append(f"tick {s.tick} arm {s.arm_id} {name}: got {list(getattr(s, name))!r} want {want!r}")
    return bad
