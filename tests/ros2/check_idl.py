#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""dds/ros2_msgs.idl against the IDL that rosidl generated for ROS 2 Jazzy (share/<pkg>/msg/<Type>.idl in
the venv's ROS 2 wheels): every struct has the same fields, same types, same order (after mapping our
pkg::msg::dds_::Type_ names back to pkg::msg::Type). tf2_msgs has no wheel: TFMessage is checked against
its definition in ROS 2's tf2_msgs/msg/TFMessage.msg (TransformStamped[] transforms).
usage: check_idl.py OUR_IDL VENV"""
import os
import re
import sys

ours_path, venv = sys.argv[1], sys.argv[2]
failures = []


FIELD = re.compile(r"^\s*((?:sequence<[^>]+>|[\w:]+)(?:<\d+>)?)\s+(\w+)\s*;\s*$")


def fields_of(body):
    """Field declarations: one per line, `type name;` (annotations and their texts are on other lines)."""
    out = []
    for line in body.replace("; ", ";\n").splitlines():
        m = FIELD.match(line.split("//")[0])
        if m:
            out.append((re.sub(r"\s+", "", m.group(1)), m.group(2)))
    return out


def norm(ty):
    return re.sub(r"::dds_::(\w+)_\b", r"::\1", ty).replace("unsignedlong", "uint32")


text = open(ours_path).read()
text = re.sub(r"//[^\n]*", "", text)
ours = {}
starts = list(re.finditer(r"module\s+(\w+)\s*\{\s*module\s+msg\s*\{\s*module\s+dds_\s*\{", text))
for i, mod in enumerate(starts):
    part = text[mod.end():starts[i + 1].start() if i + 1 < len(starts) else len(text)]
    for st in re.finditer(r"struct\s+(\w+)_\s*\{(.*?)\};", part, re.S):
        ours[(mod.group(1), st.group(1))] = [(norm(t), n) for t, n in fields_of(st.group(2))]
n_structs = len(re.findall(r"\bstruct\s+\w+", text))
if len(ours) != n_structs:
    failures.append(f"read {len(ours)} of the {n_structs} structs in {ours_path}")

share = None
for root, dirs, _ in os.walk(venv):
    if os.path.isdir(os.path.join(root, "sensor_msgs", "msg")) and root.endswith("share"):
        share = root
        break
if share is None:
    print("FAIL: no ROS 2 message wheels under", venv)
    sys.exit(1)

for (pkg, name), fields in sorted(ours.items()):
    path = os.path.join(share, pkg, "msg", f"{name}.idl")
    if pkg == "tf2_msgs" and name == "TFMessage":
        ref = [("sequence<geometry_msgs::msg::TransformStamped>", "transforms")]
        src = "tf2_msgs/msg/TFMessage.msg (no wheel)"
    elif not os.path.exists(path):
        failures.append(f"{pkg}/{name}: no {path}")
        continue
    else:
        t = open(path).read()
        m = re.search(r"struct\s+" + name + r"\s*\{(.*?)\};", t, re.S)
        ref = [(re.sub(r"\s+", "", ty), n) for ty, n in fields_of(m.group(1))]
        src = path
    ok = fields == ref
    print(("ok   " if ok else "FAIL ") + f"{pkg}/msg/{name}: {len(fields)} fields as {src}")
    if not ok:
        print("     ours:", fields, "\n     rosidl:", ref)
        failures.append(f"{pkg}/{name}")
print(f"{len(ours)} types; " + ("FAILED: " + ", ".join(failures) if failures else "PASSED"))
sys.exit(1 if failures else 0)
