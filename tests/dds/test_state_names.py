# SPDX-License-Identifier: MIT
"""The controller states have one numbering, dds/mca_dds.idl's ControllerState; the places that must write
it out again agree with it: mca_dds_state_t (dds/include/mca/dds_bridge.h; dds_bridge.c also asserts it
against the IDL at compile time), the states' names (mca_dds_state_name in dds/src/dds_bridge.c, which
/diagnostics and the bridge send), and the ROS 2 message definition mca-record writes into its MCAP files
(tools/mca-record/msgdefs.c, "int32 STATE_X=N"). The Python tests read the IDL (tests/dds/idl_enums.py).
usage: test_state_names.py SOURCE_DIR (each file under it at its usual place)"""
import os
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import idl_enums  # noqa: E402


def main():
    src = sys.argv[1]
    idl = idl_enums.controller_states(os.path.join(src, "dds", "mca_dds.idl"))
    want = [(n, v) for n, v in idl]
    names = idl_enums.controller_state_names(os.path.join(src, "dds", "mca_dds.idl"))
    print("IDL ControllerState:", ", ".join(f"{n}={v}" for n, v in want))
    fails = []

    hdr = open(os.path.join(src, "dds", "include", "mca", "dds_bridge.h")).read()
    got = [(f"STATE_{n}", int(v)) for n, v in re.findall(r"\bMCA_DDS_STATE_(\w+)\s*=\s*(-?\d+)", hdr)]
    if got != want:
        fails.append(f"dds_bridge.h mca_dds_state_t: {got}")

    c = open(os.path.join(src, "dds", "src", "dds_bridge.c")).read()
    m = re.search(r"mca_dds_state_name\(int state\)\s*\{.*?names\[\]\s*=\s*\{(.*?)\}", c, re.S)
    got_names = re.findall(r'"(\w+)"', m.group(1)) if m else None
    if got_names != names:
        fails.append(f"dds_bridge.c mca_dds_state_name: {got_names} (want {names})")

    md = open(os.path.join(src, "tools", "mca-record", "msgdefs.c")).read()
    m = re.search(r'"mca_dds/msg/ControllerStatus",(.*?)\{NULL\}', md, re.S)
    text = "".join(re.findall(r'"((?:[^"\\]|\\.)*)"', m.group(1))) if m else ""
    got = [(n, int(v)) for n, v in re.findall(r"int32 (STATE_\w+)=(-?\d+)", text)]
    if got != want:
        fails.append(f"msgdefs.c ControllerStatus constants: {got}")

    # the pair kinds: mca_dds_pair_kind_t and mca_dds_pair_kind_name (dds/src/dds_pairs.c) against PairKind
    kinds = idl_enums.idl_enum("PairKind", os.path.join(src, "dds", "mca_dds.idl"))
    print("IDL PairKind:", ", ".join(f"{n}={v}" for n, v in kinds))
    got = [(f"PAIR_{n}", int(v)) for n, v in re.findall(r"\bMCA_DDS_PAIR_(\w+)\s*=\s*(-?\d+)", hdr)]
    if got != kinds:
        fails.append(f"dds_bridge.h mca_dds_pair_kind_t: {got}")
    c = open(os.path.join(src, "dds", "src", "dds_pairs.c")).read()
    m = re.search(r"mca_dds_pair_kind_name\(int kind\)\s*\{.*?names\[\]\s*=\s*\{(.*?)\}", c, re.S)
    got_names = re.findall(r'\[MCA_DDS_(PAIR_\w+)\]\s*=\s*"([\w-]+)"', m.group(1)) if m else None
    want_names = [(n, n.removeprefix("PAIR_").lower().replace("_", "-")) for n, _ in sorted(kinds, key=lambda e: e[1])]
    if got_names != want_names:
        fails.append(f"dds_pairs.c mca_dds_pair_kind_name: {got_names} (want {want_names})")

    for f in fails:
        print("DIFFERENT:", f)
    if fails:
        raise SystemExit(f"FAIL: {len(fails)} place(s) disagree with dds/mca_dds.idl's ControllerState or PairKind")
    print("PASS: dds_bridge.h, dds_bridge.c, dds_pairs.c and msgdefs.c agree with the IDL")


if __name__ == "__main__":
    main()
