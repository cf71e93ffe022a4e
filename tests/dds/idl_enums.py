# SPDX-License-Identifier: MIT
"""The enums of dds/mca_dds.idl read from the IDL itself, so that the Python tests never hold a copy of a
numbering (an IDL enum's enumerators are numbered 0, 1, ... in order unless @value says otherwise)."""
import os
import re

IDL = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "dds", "mca_dds.idl")


def idl_enum(name, path=IDL):
    """[(enumerator, value), ...] of enum `name` in the IDL at `path`."""
    src = re.sub(r"//[^\n]*|/\*.*?\*/", "", open(path).read(), flags=re.S)
    m = re.search(r"\benum\s+%s\s*\{(.*?)\}" % re.escape(name), src, re.S)
    if not m:
        raise SystemExit(f"FAIL: no enum {name} in {path}")
    out, value = [], 0
    for item in (s.strip() for s in m.group(1).split(",")):
        if not item:
            continue
        v = re.match(r"@value\s*\(\s*(-?\d+)\s*\)\s*(\w+)$", item)
        if v:
            value, item = int(v.group(1)), v.group(2)
        out.append((item, value))
        value += 1
    return out


def controller_states(path=IDL):
    """ControllerState's [(name, value)]: ("STATE_INIT", 0), ..."""
    return idl_enum("ControllerState", path)


def controller_state_names(path=IDL):
    """The states' names as the bridge and /diagnostics give them: ["init", "ready", ...] by value."""
    return [n.removeprefix("STATE_").lower() for n, _ in sorted(controller_states(path), key=lambda e: e[1])]
