#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Bench row 5d (docs/ros2.md): latency from a tick's wake-up (JointState header stamp) to an rclpy
callback, mcad running the cross circles task for SECONDS with ROS 2 joint states only (markers and
diagnostics off, so the rclpy executor does nothing else) at 100 Hz. Run inside tests/ros2/netns.sh.
Prints "ros2 latency tick->rclpy p50 X us p99 Y us max Z us (n=N)".
usage: latency.py MCAD SOURCE_DIR SECONDS"""
import os
import subprocess
import sys
import tempfile
import threading
import time

MCAD, SRC, SECONDS = sys.argv[1], sys.argv[2], float(sys.argv[3])
os.environ["ROS_DOMAIN_ID"] = "45"
import rclpy  # noqa: E402
from rclpy.executors import SingleThreadedExecutor  # noqa: E402
from rclpy.node import Node  # noqa: E402
from rclpy.qos import QoSProfile  # noqa: E402
from sensor_msgs.msg import JointState  # noqa: E402

CELL = f"""name: ros2_latency
task: {{scenario: {SRC}/config/scenarios/cross_circles.yaml, duration: {SECONDS}}}
scheme: mca-ts
arms: [{{name: left, backend: sim}}, {{name: right, backend: sim}}]
dds:
  enabled: true
  domain: 45
  config: {SRC}/config/dds/ros2.xml
  publish_divisor: 10
  ros2: {{markers: false, diagnostics: false}}
rt: {{period_us: 1000, priority: 80, overrun_limit: 100000, pdnn_budget_us: 1000000}}
stop_after: {SECONDS}
"""

rclpy.init()
node = Node("mca_ros2_latency")
lat = []


def cb(m):
    lat.append(time.time_ns() - (m.header.stamp.sec * 1_000_000_000 + m.header.stamp.nanosec))


node.create_subscription(JointState, "/ros2_latency/left/joint_states", cb, QoSProfile(depth=200))
ex = SingleThreadedExecutor()
ex.add_node(node)
threading.Thread(target=ex.spin, daemon=True).start()
time.sleep(2.0)
with tempfile.NamedTemporaryFile("w", suffix=".yaml") as f:
    f.write(CELL)
    f.flush()
    run = subprocess.run([MCAD, f.name], stderr=subprocess.PIPE, text=True)
    rc = run.returncode
    if rc != 0:
        print(run.stderr[-600:])
time.sleep(1.0)
ex.shutdown()
rclpy.try_shutdown()
lat = sorted(lat[20:])  # past discovery
if rc != 0 or not lat:
    print(f"ros2 latency: not measured (mcad exit {rc}, {len(lat)} samples)", flush=True)
    os._exit(1)
print(f"ros2 latency tick->rclpy p50 {lat[len(lat) // 2] / 1e3:.0f} us p99 {lat[int(len(lat) * 0.99)] / 1e3:.0f} us "
      f"max {lat[-1] / 1e3:.0f} us (n={len(lat)})", flush=True)
os._exit(0)  # not through rclpy's C++ teardown with its executor thread still alive
