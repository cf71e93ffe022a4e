#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Verdicts of the CANopen vcan suite (tests/canopen/suite.sh run wrote OUT_DIR).

Usage: check_suite.py SOURCE_DIR OUT_DIR
Prints one "CANOPEN-SUITE ok|FAIL <case>" line per case (with what was seen) and exits 0 only if all pass.
The candump captures are decoded here (CiA 301 predefined connection set, the PDO layout the master
configures) and compared with what each program logged.
"""
import json
import os
import re
import sys
from collections import defaultdict

S, OUT = sys.argv[1], sys.argv[2]
fails = 0
lines = []


def verdict(case, ok, seen=""):
    global fails
    line = f"CANOPEN-SUITE {'ok  ' if ok else 'FAIL'} {case}" + (f" [{seen}]" if seen else "")
    print(line, flush=True)
    lines.append(line)
    if not ok:
        fails += 1


def read(name):
    try:
        with open(os.path.join(OUT, name)) as f:
            return f.read()
    except OSError:
        return ""


status = {}
for ln in read("status.env").split():
    k, _, v = ln.partition("=")
    status[k] = int(v) if v.lstrip("-").isdigit() else v


def rc(key):
    return status.get(key, "missing")


def ctl(name):
    """key=value pairs, per-node lines and the fault of one mca-co-ctl output."""
    txt = read(name)
    kv, nodes = {}, {}
    for ln in txt.splitlines():
        m = re.match(r"node(\d+) state=(\S+) q=(\S+) v=(\S+)", ln)
        if m:
            nodes[int(m.group(1))] = (m.group(2), float(m.group(3)), float(m.group(4)))
            continue
        for part in re.findall(r"(\w+)=(\S+)", ln) if not ln.startswith(("fault=", "err=")) else []:
            kv.setdefault(part[0], part[1])
        if ln.startswith(("fault=", "err=")):
            kv[ln.split("=", 1)[0]] = ln.split("=", 1)[1]
    return kv, nodes, txt


def candump(name):
    """[(t, id, bytes)] of a candump -L capture (classic frames), without candump_stop's end marker (0x7FF)."""
    out = []
    for ln in read(name).splitlines():
        m = re.match(r"\((\d+\.\d+)\) \S+ ([0-9A-Fa-f]+)#([0-9A-Fa-f]*)$", ln)
        if m and int(m.group(2), 16) != 0x7FF:
            out.append((float(m.group(1)), int(m.group(2), 16), bytes.fromhex(m.group(3))))
    return out


def dslog(name):
    """{node: [(sync, state, q, v)]} from mca-drivesim --log."""
    d = defaultdict(list)
    for ln in read(name).splitlines():
        p = ln.split()
        if len(p) == 6 and p[0] == "s":
            d[int(p[1])].append((int(p[2]), p[3], float(p[4]), float(p[5])))
    return d


def i32(b):
    return int.from_bytes(b, "little", signed=True)


def u16(b):
    return int.from_bytes(b, "little")


if rc("SETUP") == 1:
    verdict("setup (see run.txt)", False, read("run.txt").strip()[-300:])

# (a) python-canopen master against mca-drivesim
try:
    res = json.loads(read("a.json") or "[]")
except ValueError:
    res = []
bad = [r["check"] + ": " + r["detail"] for r in res if not r["ok"]]
verdict(f"a: python-canopen NMT master + SDO client drives mca-drivesim through the EDS ({len(res)} checks: "
        "OD read-back, aborts, heartbeat, PDO remap, BaseNode402 to OPERATION ENABLED, CSV steps, quick stop, "
        "EMCY fault + reset)", rc("A_RC") == 0 and len(res) >= 20 and not bad,
        f"rc {rc('A_RC')}; failing: {bad}; py_master's last lines: {read('a.out').strip().splitlines()[-4:]}"
        if bad or rc("A_RC") != 0 else f"{len(res)} ok")



def sdo_transfers(frames, node):
    """The SDO transfers of one server on the bus, decoded from a capture (CiA 301 7.2.4: expedited and
    segmented upload and download, aborts from either side): [{op, index, sub, data | abort | open}]."""
    out, cur = [], None
    for _, cid, b in frames:
        if len(b) != 8 or cid not in (0x600 + node, 0x580 + node):
            continue
        cs = b[0] >> 5
        if cid == 0x600 + node:  # client -> server
            if b[0] == 0x80:  # abort by the client
                if cur:
                    cur["abort"] = i32(b[4:8]) & 0xFFFFFFFF
                    out.append(cur)
                cur = None
            elif cs in (1, 2):  # initiate download / upload
                if cur:  # the previous one never finished (no answer on the bus)
                    cur["open"] = True
                    out.append(cur)
                cur = {"op": "down" if cs == 1 else "up", "index": u16(b[1:3]), "sub": b[3], "buf": b"",
                       "expedited": bool(b[0] & 0x02)}
                if cs == 1 and cur["expedited"]:  # the data is in this frame
                    n = (b[0] >> 2) & 3 if b[0] & 0x01 else 0
                    cur["buf"] = b[4:8 - n]
            elif cs == 0 and cur and cur["op"] == "down":  # download segment
                cur["buf"] += b[1:8 - ((b[0] >> 1) & 7)]
                cur["last"] = b[0] & 0x01
            continue
        if not cur:  # server -> client with nothing open
            continue
        if b[0] == 0x80:
            cur["abort"] = i32(b[4:8]) & 0xFFFFFFFF
        elif cur["op"] == "up" and cs == 2:  # initiate upload response
            if b[0] & 0x02:
                n = (b[0] >> 2) & 3 if b[0] & 0x01 else 0
                cur["buf"] = b[4:8 - n]
            else:
                continue  # segmented: the segments follow
        elif cur["op"] == "up" and cs == 0:  # upload segment
            cur["buf"] += b[1:8 - ((b[0] >> 1) & 7)]
            if not b[0] & 0x01:
                continue
        elif cur["op"] == "down" and cs == 3:  # initiate download response
            if not cur["expedited"]:
                continue  # segmented: the segments follow
        elif cur["op"] == "down" and cs == 1:  # download segment response
            if not cur.get("last"):
                continue
        else:
            continue
        if "abort" not in cur:
            cur["data"] = cur["buf"].hex()
        out.append({k: v for k, v in cur.items() if k not in ("buf", "expedited", "last")})
        cur = None
    if cur:
        cur["open"] = True
        out.append(cur)
    return out


def same_transfer(py, bus):
    if (py["op"], py["index"], py["sub"]) != (bus["op"], bus["index"], bus["sub"]):
        return False
    if py.get("timeout"):  # python-canopen gave up waiting: the request was on the bus, the answer may be too
        return True
    if "abort" in py or "abort" in bus:
        return py.get("abort") == bus.get("abort")
    if py["op"] == "up" and bus.get("data") is not None and py.get("data") is not None:
        # python-canopen cuts an upload to the object's size in its EDS (a drive may send 4 bytes for a U16)
        return bus["data"].startswith(py["data"]) and len(py["data"]) > 0
    return py.get("data") == bus.get("data")


try:
    abus = json.loads(read("a.bus.json") or "{}")
except ValueError:
    abus = {}
fr = candump("a.candump")
NODE_A = 5
seen = sdo_transfers(fr, NODE_A)
py_sdo = abus.get("sdo", [])
diff = [f"#{i}: python {p} / bus {b}" for i, (p, b) in enumerate(zip(py_sdo, seen)) if not same_transfer(p, b)]
if len(py_sdo) != len(seen):
    diff.append(f"python logged {len(py_sdo)} SDO transfers, the capture holds {len(seen)}")
nmt = [b[0] for _, cid, b in fr if cid == 0 and len(b) == 2 and b[1] in (NODE_A, 0)]
emcy = [u16(b[0:2]) for _, cid, b in fr if cid == 0x80 + NODE_A and len(b) == 8]
n_up = sum(1 for t in seen if t["op"] == "up")
n_abort = sum(1 for t in seen if "abort" in t)
n_seg = sum(1 for t in seen if len(bytes.fromhex(t.get("data", ""))) > 4)
verdict(f"a: candump decoded: every SDO transfer (index, sub-index, data or abort code) = what python-canopen "
        "did, in order; NMT commands and EMCYs = python-canopen's",
        len(fr) > 0 and len(py_sdo) >= 60 and not diff and nmt == abus.get("nmt") and emcy == abus.get("emcy"),
        f"{len(fr)} frames; {len(seen)} SDO transfers ({n_up} uploads, {n_seg} over 4 bytes, {n_abort} aborts); "
        f"NMT {[hex(c) for c in nmt]} vs {[hex(c) for c in abus.get('nmt', [])]}; EMCY {[hex(c) for c in emcy]} vs "
        f"{[hex(c) for c in abus.get('emcy', [])]}" + (f"; differences: {diff[:4]}" if diff else ""))

# (b) our master against python-canopen LocalNode drives
kv, nodes, txt = ctl("b.out")
try:
    pyd = {d["node"]: d for d in json.loads(read("b.json") or "[]")}
except ValueError:
    pyd = {}
problems = []
for n in range(1, 7):
    d = pyd.get(n)
    if not d:
        problems.append(f"node {n}: no report from the python drive")
        continue
    want = {"rpdo1_map": ["60400010", "60FF0020"], "tpdo1_map": ["60410010", "60640020"],
            "tpdo2_map": ["606C0020", "60770010"], "tpdo_types": [1, 1], "mode": 9, "interp": [40, -3],
            "heartbeat_ms": 100, "controlwords": [0, 6, 7, 15, 2], "rpdo1_cob": 0x200 + n}
    for k, v in want.items():
        if d.get(k) != v:
            problems.append(f"node {n}: {k} {d.get(k)} != {v}")
    if n in nodes and abs(round(nodes[n][1] * 1e6) - d["pos_counts"]) > 1:
        problems.append(f"node {n}: master reads q {nodes[n][1]} , drive has {d['pos_counts']} counts")
verdict("b: our master configures six python-canopen LocalNode drives over SDO (PDO maps, types, mode 9, "
        "0x60C2 = 40 ms, heartbeat), walks them 0 -> 6 -> 7 -> F, moves them, quick-stops (2); final "
        "positions agree", rc("B_RC") == 0 and not problems and "name1=mca-drivesim" in txt,
        f"ctl rc {rc('B_RC')}; {problems[:6]}" + ("" if rc("B_RC") == 0 else
                                                   f"; mca-co-ctl's last lines: {txt.strip().splitlines()[-8:]}"))

fr = candump("b.candump")
prob = []
syncs = sum(1 for _, i, _ in fr if i == 0x080)
if str(syncs) != kv.get("syncs"):
    prob.append(f"{syncs} SYNC frames on the bus, master counted {kv.get('syncs')}")
nmt = [(b[0], b[1]) for _, i, b in fr if i == 0 and len(b) == 2]
for n in range(1, 7):
    for cmd in (0x82, 0x01):
        if (cmd, n) not in nmt:
            prob.append(f"no NMT 0x{cmd:02X} to node {n}")
if (0x02, 0) not in nmt:
    prob.append("no NMT stop at the end")
req = sum(1 for _, i, _ in fr if 0x601 <= i <= 0x67F)
ans = sum(1 for _, i, _ in fr if 0x581 <= i <= 0x5FF)
aborts = [(hex(i), b.hex()) for _, i, b in fr if (0x581 <= i <= 0x67F) and b[:1] == b"\x80"]
if req != ans or req < 6 * 20 or aborts:
    prob.append(f"SDO: {req} requests, {ans} answers, aborts {aborts[:3]}")
for n in range(1, 7):
    bus_targets = [i32(b[2:6]) for _, i, b in fr if i == 0x200 + n and len(b) == 6 and u16(b[:2]) == 0x0F]
    bus_targets = [t for t in bus_targets if t]
    d = pyd.get(n, {})
    py_targets = [t for t in d.get("targets", []) if t]
    if bus_targets != py_targets:
        prob.append(f"node {n}: {len(bus_targets)} non-zero RPDO targets on the bus, drive applied "
                    f"{len(py_targets)} (first differing at {next((k for k, (a, b) in enumerate(zip(bus_targets, py_targets)) if a != b), None)})")
    tp = [i32(b[2:6]) for _, i, b in fr if i == 0x180 + n and len(b) == 6]
    if not tp or tp[-1] != d.get("pos_counts"):
        prob.append(f"node {n}: last TPDO1 position {tp[-1] if tp else None} != drive {d.get('pos_counts')}")
verdict("b: candump decoded: SYNCs = master's count, NMT reset/start/stop per node, every SDO request answered "
        "without abort, every RPDO target on the bus applied by the python drive in order, last TPDO1 = drive "
        "position", not prob and len(fr) > 0, f"{len(fr)} frames, {syncs} SYNCs; {prob[:5]}")

# (c) our master against mca-drivesim: trajectory vs the in-process sim arm, candump vs the emulator's log
kv, nodes, txt = ctl("c.out")
ds = dslog("c.dslog")
ref = {}
for ln in read("c.ref").splitlines():
    p = ln.split()
    if p and p[0] == "r":
        ref[int(p[1])] = [float(x) for x in p[2:]]
by = {n: {s: (st, q, v) for s, st, q, v in recs} for n, recs in ds.items()}
dmax, cnt = 0.0, 0
for s, qs in ref.items():
    for j, q in enumerate(qs):
        r = by.get(j + 1, {}).get(s)
        if r:
            dmax = max(dmax, abs(r[1] - q))
            cnt += 1
moved = max((abs(v[-1] - v[0]) for v in [[r[2] for r in ds[n]] for n in ds] if v), default=0)
verdict("c: our master (mca-co-ctl) + six mca-drivesim JACO2 drives at 4 ms: joint trajectory within 1e-5 rad of "
        "the sim backend's arm model, SYNC by SYNC", rc("C_RC") == 0 and cnt >= 6 * 400 and dmax < 1e-5
        and moved > 0.05 and all(f"name{n}=mca-drivesim" in txt for n in range(1, 7)),
        f"ctl rc {rc('C_RC')}, {cnt} samples, max |dq| {dmax:.3g} rad, largest joint travel {moved:.3f} rad")
fr = candump("c.candump")
prob = []
ST_SW = {"SWITCH_ON_DISABLED": 0x40, "READY_TO_SWITCH_ON": 0x31, "SWITCHED_ON": 0x33, "OPERATION_ENABLED": 0x37,
         "QUICK_STOP_ACTIVE": 0x17, "FAULT_REACTION_ACTIVE": 0x1F, "FAULT": 0x08}
ncmp = 0
for n in range(1, 7):
    tp = [b for _, i, b in fr if i == 0x180 + n and len(b) == 6]
    recs = ds.get(n, [])
    if len(tp) != len(recs):
        prob.append(f"node {n}: {len(tp)} TPDO1 on the bus, {len(recs)} cycles logged")
    for k, (b, (s, st, q, v)) in enumerate(zip(tp, recs)):
        ncmp += 1
        # the log prints q to 1e-9 rad: a position within 1e-9 of a half count may round either way
        if abs(i32(b[2:6]) - q * 1e6) > 0.5 + 1e-3 or (u16(b[:2]) & 0x7F) != ST_SW.get(st):
            prob.append(f"node {n} sync {s}: bus {u16(b[:2]):#06x} {i32(b[2:6])}, log {st} {round(q * 1e6)}")
            break
syncs = sum(1 for _, i, _ in fr if i == 0x080)
if str(syncs) != kv.get("syncs"):
    prob.append(f"{syncs} SYNCs on the bus, master counted {kv.get('syncs')}")
verdict("c: candump decoded: every TPDO1 (statusword, position) = the emulator's logged state and position of "
        "that SYNC (to the count); SYNC count = master's", not prob and ncmp >= 6 * 400, f"{ncmp} TPDO1 compared; {prob[:4]}")

# (d) named faults
cases = [("d1", "DRIVE_FAULT", 3, "drive fault injected (actuator) in node 3"),
         ("d2", "EMCY", 2, "EMCY 0x4210 from node 2"),
         ("d3", "HEARTBEAT", 4, "heartbeat of node 4 stops"),
         ("d4", "PDO_TIMEOUT", 5, "TPDOs of node 5 stop"),
         ("d5", "SDO_ABORT", 6, "node 6 aborts the SDO write of 0x60C2 at start-up")]
for tag, kind, node, what in cases:
    kv, nodes, txt = ctl(f"{tag}.out")
    fault = kv.get("fault", "")
    ok = rc(tag.upper() + "_RC") == 0 and kv.get("fault_kind") == kind and fault.startswith(f"node {node}:")
    extra = ""
    if tag == "d2":
        ok = ok and "0x4210" in fault and "temperature" in fault
    if tag == "d5":
        err = kv.get("err", "")
        ok = ok and "0x60C2" in err and "0x08000022" in err and "present device state" in err
        extra = err
    else:
        ok = ok and "stopped=1" in txt
        last = {n: recs[-1] for n, recs in dslog(f"{tag}.dslog").items()}
        moving = {n: r[3] for n, r in last.items() if abs(r[3]) > 1e-9}
        ok = ok and len(last) == 6 and not moving
        extra = f"drives still moving at the end: {moving}" if moving else "every drive at v = 0"
    outcome = "start-up refused" if tag == "d5" else "every drive braked to standstill"
    verdict(f"{tag}: {what} -> named fault {kind} of node {node}, {outcome}", ok,
            f"rc {rc(tag.upper() + '_RC')}, fault '{fault}', {extra}")


def ramp_ok(recs, dec, dt, states):
    worst = 0.0
    for (s0, st0, q0, v0), (s1, st1, q1, v1) in zip(recs, recs[1:]):
        if st1 in states:
            worst = max(worst, abs(v1 - v0) / dt)
    return worst <= dec * (1 + 1e-9), worst


# (e) SIGTERM: quick stop within the deceleration limit
kv, nodes, txt = ctl("e.out")
ds = dslog("e.dslog")
worst, ok = 0.0, len(ds) == 6
for n, recs in ds.items():
    good, w = ramp_ok(recs, 5.0, 0.004, {"QUICK_STOP_ACTIVE"})
    worst = max(worst, w)
    ok = ok and good and recs[-1][1] == "QUICK_STOP_ACTIVE" and abs(recs[-1][3]) < 1e-12
verdict("e: SIGTERM mid-task -> quick stop, every drive decelerates within 5 rad/s^2 to standstill, exit 0",
        rc("E_RC") == 0 and "sigterm=1" in txt and "stopped=1" in txt and ok,
        f"rc {rc('E_RC')}, worst deceleration {worst:.4f} rad/s^2")

# (f) controller killed: drives brake on their own clock, FAULT + EMCY 0x8250
err = read("f.ds.err")
ds = dslog("f.dslog")
worst, ok = 0.0, len(ds) == 6
for n, recs in ds.items():
    good, w = ramp_ok(recs, 5.0, 0.004, {"FAULT_REACTION_ACTIVE", "FAULT"})
    worst = max(worst, w)
    ok = ok and good and recs[-1][1] == "FAULT" and abs(recs[-1][3]) < 1e-12
own = err.count("braking on its own clock")
faulted = len(re.findall(r"state=FAULT .*emcy=1 faults=1", err))
verdict("f: controller killed (SYNCs stop) -> each drive brakes on its own clock within 5 rad/s^2, FAULT, "
        "EMCY 0x8250", ok and own == 6 and faulted == 6,
        f"{own} drives braked on their own clock, {faulted} in FAULT with one EMCY, worst {worst:.4f} rad/s^2")

# (g), (h) the backend through the arm interface
for m in ("csv", "csp"):
    kv, _, txt = ctl(f"g{m}.out")
    verdict(f"g: mca/arm.h `canopen` backend, 1 kHz control, SYNC 4 ms, {m.upper()}: SERVOING, joint travel = "
            "commanded integral within 1e-4 rad, READY at rest after the brake request",
            rc(f"G{m.upper()}_RC") == 0 and kv.get("backend") == "canopen" and "state=READY" in txt,
            f"rc {rc(f'G{m.upper()}_RC')}, travel_err {kv.get('travel_err')}, reads ok/again "
            f"{kv.get('reads_ok')}/{kv.get('reads_again')}")
kv, _, txt = ctl("h.out")
verdict("h: EMCY of node 4 through mca/arm.h: fb.state FAULT, fault EMCY, every joint at rest, the backend "
        "names node and code", rc("H_RC") == 0 and "expected_fault=EMCY seen" in txt
        and "why=node 4: EMCY 0x4210" in txt, f"rc {rc('H_RC')}, {kv.get('why', '')}")

print(f"CANOPEN-SUITE done: {fails} failing", flush=True)
with open(os.path.join(OUT, "results.txt"), "w") as f:
    f.write("\n".join(lines) + "\n")
sys.exit(1 if fails else 0)
