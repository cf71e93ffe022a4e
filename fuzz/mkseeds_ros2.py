#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Seed corpus of fuzz_ros2_target (fuzz/corpus/ros2_target/): TwistStamped and PoseStamped as a ROS 2 node
sends them, serialized by the PyPI cyclonedds binding (XCDR1, the 4-byte encapsulation header dropped), in
both byte orders. First byte as fuzz_ros2_target.c reads it. Run: .venv/bin/python fuzz/mkseeds_ros2.py"""
import os
from dataclasses import dataclass

from cyclonedds.idl import Endianness, IdlStruct
from cyclonedds.idl.annotations import final
import cyclonedds.idl.types as t

OUT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "corpus", "ros2_target")


@final
@dataclass
class Time_(IdlStruct, typename="builtin_interfaces::msg::dds_::Time_"):
    sec: t.int32
    nanosec: t.uint32


@final
@dataclass
class Header_(IdlStruct, typename="std_msgs::msg::dds_::Header_"):
    stamp: Time_
    frame_id: str


@final
@dataclass
class Vector3_(IdlStruct, typename="geometry_msgs::msg::dds_::Vector3_"):
    x: t.float64
    y: t.float64
    z: t.float64


@final
@dataclass
class Twist_(IdlStruct, typename="geometry_msgs::msg::dds_::Twist_"):
    linear: Vector3_
    angular: Vector3_


@final
@dataclass
class TwistStamped_(IdlStruct, typename="geometry_msgs::msg::dds_::TwistStamped_"):
    header: Header_
    twist: Twist_


@final
@dataclass
class Point_(IdlStruct, typename="geometry_msgs::msg::dds_::Point_"):
    x: t.float64
    y: t.float64
    z: t.float64


@final
@dataclass
class Quaternion_(IdlStruct, typename="geometry_msgs::msg::dds_::Quaternion_"):
    x: t.float64
    y: t.float64
    z: t.float64
    w: t.float64


@final
@dataclass
class Pose_(IdlStruct, typename="geometry_msgs::msg::dds_::Pose_"):
    position: Point_
    orientation: Quaternion_


@final
@dataclass
class PoseStamped_(IdlStruct, typename="geometry_msgs::msg::dds_::PoseStamped_"):
    header: Header_
    pose: Pose_


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
