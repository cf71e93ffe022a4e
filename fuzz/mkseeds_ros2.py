#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Seed corpus of fuzz_ros2_target (fuzz/corpus/ros2_target/): TwistStamped and PoseStamped as a ROS 2 node
sends them, serialized by the PyPI cyclonedds binding with the types of tests/ros2/ros2_types.py (XCDR1, the
4-byte encapsulation header dropped), in both byte orders. First byte as fuzz_ros2_target.c reads it.
Run: .venv/bin/python fuzz/mkseeds_ros2.py"""
import os
import sys

from cyclonedds.idl import Endianness

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "tests", "ros2"))
from ros2_types import (Header_, Point_, Pose_, PoseStamped_, Quaternion_, Time_, Twist_,  # noqa: E402
                        TwistStamped_, Vector3_)

OUT = os.path.join(HERE, "corpus", "ros2_target")


def hdr(frame):
    return Header_(Time_(1796300000, 123456789), frame)


seeds = {
    "twist_ok": (0, TwistStamped_(hdr("world"), Twist_(Vector3_(0.1, -0.05, 0.0), Vector3_(0, 0, 0)))),
    "twist_fast": (0, TwistStamped_(hdr("world"), Twist_(Vector3_(0.5, 0.0, 0.0), Vector3_(0, 0, 0)))),
    "twist_frame": (0, TwistStamped_(hdr("base_link"), Twist_(Vector3_(0.1, 0.0, 0.0), Vector3_(0, 0, 0)))),
    "twist_nan": (0, TwistStamped_(hdr("world"), Twist_(Vector3_(float("nan"), 0.0, 0.0), Vector3_(0, 0, 0)))),
    "pose_ok": (1, PoseStamped_(hdr("world"), Pose_(Point_(0.3, -0.2, 0.9), Quaternion_(0, 0, 0, 1)))),
    "pose_box": (1, PoseStamped_(hdr("world"), Pose_(Point_(5.0, 0.0, 0.5), Quaternion_(0, 0, 0, 1)))),
    "pose_empty_frame": (1, PoseStamped_(hdr(""), Pose_(Point_(0.0, 0.0, 0.5), Quaternion_(0, 0, 0, 1)))),
}
os.makedirs(OUT, exist_ok=True)
for name, (kind, msg) in seeds.items():
    for endian, flag in (("le", 0), ("be", 2)):
        data = msg.serialize(endianness=Endianness.Big if endian == "be" else Endianness.Little, use_version_2=False)
        with open(os.path.join(OUT, f"{name}_{endian}"), "wb") as f:
            f.write(bytes([kind | flag]) + data[4:])
print(f"{2 * len(seeds)} seeds in {OUT}")
