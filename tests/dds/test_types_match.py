# SPDX-License-Identifier: MIT
"""The DDS types written in Python (tests/dds/mca_types.py) must produce XTypes type objects that are
byte-identical to the ones idlc generated from dds/mca_dds.idl (the TYPE_MAP_CDR_* arrays in the
generated C file). Then the type identifiers (hashes) agree, and the C side (libddsc 0.10.2) never
needs a type-lookup exchange with the Python side (11.x): that exchange crashed 0.10.2 when they
differed. usage: test_types_match.py build/dds/mca_dds.c"""
import os
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mca_types as m  # noqa: E402


def c_bytes(src, macro):
    mm = re.search(r"#define %s \(unsigned char \[\]\)\{(.*?)\}" % re.escape(macro), src, re.S)
    if not mm:
        raise SystemExit(f"FAIL: {macro} not found in the generated C file")
    return bytes(int(x, 16) for x in re.findall(r"0x([0-9a-fA-F]{2})", mm.group(1)))


def main():
    src = open(sys.argv[1]).read()
    failures = 0
    for name in ("JointState", "JointCommand", "Distances", "ControllerStatus", "PairDistance",
                 "PairDistances"):
        cls = getattr(m, name)
        c_map = c_bytes(src, f"TYPE_MAP_CDR_mca_dds_{name}")
        c_info = c_bytes(src, f"TYPE_INFO_CDR_mca_dds_{name}")
        py_map = cls.__idl__.get_type_mapping().serialize()[4:]  # drop the CDR encapsulation header
        py_info = cls.__idl__.get_type_info().serialize()[4:]
        ok = c_map == py_map and c_info == py_info
        print(f"{name:18s} type map {len(c_map)} B, type info {len(c_info)} B: {'equal' if ok else 'DIFFERENT'}")
        if not ok:
            failures += 1
            diff = [i for i in range(min(len(c_map), len(py_map))) if c_map[i] != py_map[i]]
            print(f"  first differing bytes at {diff[:8]} (lengths {len(c_map)} vs {len(py_map)})")
    if failures:
        raise SystemExit(f"FAIL: {failures} type(s) differ between dds/mca_dds.idl and mca_types.py")
    print("PASS")


if __name__ == "__main__":
    main()
