#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""python-canopen (an independent CANopen stack) as NMT master and SDO client of mca-drivesim.

Usage: py_master.py IFACE EDS NODE OUT_JSON

With mca-drivesim running on IFACE (node NODE, --watchdog-cycles large: the RPDO here is python's own
periodic sender, not in step with its SYNC), this checks, each as an "ok"/"FAIL" line:
  - NMT reset communication -> boot-up; every readable object of the EDS is uploaded over SDO, and the
    static ones (identity, device type, names, PDO parameters, modes) equal the EDS defaults; the device
    name comes by segmented upload;
  - SDO aborts with the CiA 301 codes: missing object, write to a read-only object, value out of range;
  - heartbeat producer after writing 0x1017;
  - PDO mapping written with python-canopen's own PDO code (TPDO2 remapped, RPDO1 re-saved) and read back;
  - the CiA 402 state machine driven by canopen.profiles.p402.BaseNode402 to OPERATION ENABLED with
    python's SYNC producer, the drive moved in CSV: every TPDO1 step of the position equals
    target velocity * interpolation period exactly (in counts);
  - quick stop -> QUICK STOP ACTIVE at velocity 0; fault injected over SDO (0x2000) -> EMCY 0xFF00 and
    FAULT; fault reset -> SWITCH ON DISABLED and EMCY 0x0000 (error reset).
Exit 0 only if every check passed. The results also go to OUT_JSON, and what this side did on the bus (each SDO
transfer with its data or abort code, each NMT command, each EMCY received) to OUT.bus.json (OUT_JSON without
".json"), which check_suite.py compares with the candump capture.
"""
import json
import sys
import time
import types

import can
import canopen
from canopen.profiles.p402 import BaseNode402
from canopen.sdo.exceptions import SdoAbortedError

IFACE, EDS, NODE, OUT = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4]
PERIOD = 0.010  # SYNC and RPDO period [s]; the drive's interpolation period is set to the same
VEL = 200000  # target velocity [counts/s] = 0.2 rad/s at the emulator's 1e6 counts/rad

results = []


def check(name, cond, detail=""):
    results.append({"check": name, "ok": bool(cond), "detail": str(detail)})
    print(("ok   " if cond else "FAIL ") + name + (": " + str(detail) if detail else ""), flush=True)
    return cond


def wait_until(pred, timeout):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if pred():
            return True
        time.sleep(0.01)
    return pred()


def abort_code(fn):
    try:
        fn()
    except SdoAbortedError as e:
        return e.code
    return None


net = canopen.Network()
net.connect(interface="socketcan", channel=IFACE)
# python-can's socketcan bus sends periodic frames with the kernel's broadcast manager (can-bcm), which the
# test guest does not load: use python-can's own thread-based periodic sender instead.
net.bus._send_periodic_internal = types.MethodType(can.BusABC._send_periodic_internal, net.bus)

node = BaseNode402(NODE, EDS)
# TCG guest: generous waits for each state change (python-canopen's defaults are 0.4 / 0.8 s)
node.TIMEOUT_SWITCH_STATE_SINGLE = 3.0
node.TIMEOUT_SWITCH_STATE_FINAL = 10.0
node.TIMEOUT_CHECK_TPDO = 1.0
# an SDO answer can wait seconds for the guest's single vCPU while the host is loaded (CI: one upload of
# the 143 lost its answer at 2 s, two at 5 s on a host running builds beside CI): generous, as the waits above
node.sdo.RESPONSE_TIMEOUT = 10.0
net.add_node(node)

# What this side did on the bus, for the comparison with the candump capture (check_suite.py): every SDO
# transfer with its data or abort code, every NMT command, every EMCY received; written to OUT.bus.json
bus_log = {"sdo": [], "nmt": [], "emcy": []}


def logged(kind, fn):
    def call(index, subindex, *args):
        rec = {"op": kind, "index": index, "sub": subindex}
        if kind == "down":
            rec["data"] = bytes(args[0]).hex()
        try:
            out = fn(index, subindex, *args)
            if kind == "up":
                rec["data"] = bytes(out).hex()
            return out
        except SdoAbortedError as e:
            rec["abort"] = e.code
            raise
        except canopen.SdoCommunicationError:
            rec["timeout"] = True
            raise
        finally:
            bus_log["sdo"].append(rec)
    return call


node.sdo.upload = logged("up", node.sdo.upload)
node.sdo.download = logged("down", node.sdo.download)
_nmt_send = node.nmt.send_command
node.nmt.send_command = lambda code: (bus_log["nmt"].append(code), _nmt_send(code))[1]
node.emcy.add_callback(lambda e: bus_log["emcy"].append(e.code))

try:
    # --- NMT boot-up (collected by a heartbeat callback registered before the reset: the emulator answers
    #     faster than python-canopen's wait_for_bootup() starts waiting) ---
    hb = []
    node.nmt.add_heartbeat_callback(lambda st: hb.append(st))
    node.nmt.state = "RESET COMMUNICATION"
    booted = wait_until(lambda: 0 in hb, 10)
    check("nmt: boot-up after RESET COMMUNICATION", booted, hb[:3])

    # --- the whole object dictionary over SDO, against the EDS ---
    STATIC = {0x1000, 0x1008, 0x1009, 0x100A, 0x1017, 0x1018, 0x1400, 0x1401, 0x1600, 0x1601, 0x1800,
              0x1801, 0x1A00, 0x1A01, 0x6060, 0x6061, 0x60C2, 0x6502, 0x2000}
    n_read, bad, mism = 0, [], []
    for obj in node.object_dictionary.values():
        subs = list(obj.values()) if hasattr(obj, "subindices") else [obj]
        for var in subs:
            if not var.readable:
                continue
            try:
                raw = node.sdo.upload(var.index, var.subindex)
                val = var.decode_raw(raw)
                n_read += 1
            except Exception as e:  # noqa: BLE001
                bad.append(f"0x{var.index:04X}:{var.subindex} {e}")
                continue
            if var.index in STATIC and var.default is not None and val != var.default:
                mism.append(f"0x{var.index:04X}:{var.subindex} {val!r} != EDS {var.default!r}")
    check(f"sdo: all {n_read} readable EDS entries uploaded", n_read >= 60 and not bad, bad)
    check("sdo: static entries equal the EDS defaults (identity, names, PDO parameters, modes)", not mism, mism)
    name = node.sdo["Manufacturer device name"].raw
    check("sdo: segmented upload of 0x1008", name == "mca-drivesim", repr(name))
    check("sdo: identity serial number = node id", node.sdo[0x1018][4].raw == NODE)

    # --- aborts ---
    c = abort_code(lambda: node.sdo.upload(0x1234, 0))
    check("sdo abort: missing object -> 0x06020000", c == 0x06020000, hex(c or 0))
    c = abort_code(lambda: node.sdo.upload(0x1018, 9))
    check("sdo abort: missing sub-index -> 0x06090011", c == 0x06090011, hex(c or 0))
    c = abort_code(lambda: node.sdo.download(0x6041, 0, b"\x05\x00"))
    check("sdo abort: write to read-only 0x6041 -> 0x06010002", c == 0x06010002, hex(c or 0))
    c = abort_code(lambda: node.sdo.download(0x6060, 0, b"\x03"))
    check("sdo abort: mode 3 out of range -> 0x06090030", c == 0x06090030, hex(c or 0))

    # --- heartbeat ---
    node.sdo[0x1017].raw = 50
    hb.clear()
    wait_until(lambda: len(hb) >= 3, 5)
    check("heartbeat: produced after writing 0x1017 = 50 ms, state PRE-OPERATIONAL", len(hb) >= 3
          and hb[-1] == 0x7F, hb[:5])

    # --- PDO mapping with python-canopen's PDO code ---
    node.sdo[0x60C2][1].raw = int(PERIOD * 1000)
    node.sdo[0x60C2][2].raw = -3
    node.tpdo.read()
    node.rpdo.read()
    names = [v.name for v in node.tpdo[1].map]
    check("pdo: TPDO1 mapping read = EDS default", names == ["Statusword", "Position actual value"], names)
    node.tpdo[2].clear()
    node.tpdo[2].add_variable("Velocity actual value")
    node.tpdo[2].add_variable("Statusword")
    node.tpdo[2].trans_type = 1
    node.tpdo[2].enabled = True
    node.rpdo[1].clear()
    node.rpdo[1].add_variable("Controlword")
    node.rpdo[1].add_variable("Target velocity")
    node.rpdo[1].trans_type = 1
    node.rpdo[1].enabled = True
    node.tpdo.save()
    node.rpdo.save()
    check("pdo: TPDO2 remapped over SDO (0x1A01 = 606C0020, 60410010)",
          node.sdo[0x1A01][0].raw == 2 and node.sdo[0x1A01][1].raw == 0x606C0020
          and node.sdo[0x1A01][2].raw == 0x60410010)
    c = abort_code(lambda: node.sdo.download(0x1A00, 1, (0x12340020).to_bytes(4, "little")))
    check("pdo: mapping change while the PDO is enabled is refused (0x08000022)", c == 0x08000022, hex(c or 0))
    node.setup_402_state_machine(read_pdos=True)

    # --- operational: SYNC, periodic RPDO, CiA 402 walk by BaseNode402 ---
    steps = []
    last = {}

    def on_tpdo1(m):
        p = m["Position actual value"].raw
        if "p" in last:
            steps.append(p - last["p"])
        last["p"] = p

    node.tpdo[1].add_callback(on_tpdo1)
    node.nmt.state = "OPERATIONAL"
    node.rpdo[1]["Controlword"].raw = 0
    node.rpdo[1]["Target velocity"].raw = 0
    node.rpdo[1].start(PERIOD)
    net.sync.start(PERIOD)
    wait_until(lambda: len(hb) and hb[-1] == 0x05, 5)
    check("nmt: OPERATIONAL in the heartbeat", hb[-1] == 0x05, hex(hb[-1]))
    try:
        node.state = "OPERATION ENABLED"
        walked = node.state
    except Exception as e:  # noqa: BLE001
        walked = f"{node.state}: {e}"
    check("cia402: BaseNode402 walks the drive to OPERATION ENABLED", walked == "OPERATION ENABLED", walked)

    node.rpdo[1]["Target velocity"].raw = VEL
    time.sleep(0.3)  # ramp (acc limit) done within a few cycles
    steps.clear()
    time.sleep(1.5)
    want = round(VEL * PERIOD)
    exact = sum(1 for s in steps if s == want)
    check(f"csv: position steps per TPDO1 = {want} counts (0.2 rad/s * 10 ms)", len(steps) >= 20
          and exact >= 0.9 * len(steps), f"{exact} of {len(steps)} steps exact, others {sorted(set(steps))[:6]}")
    v = node.tpdo[2]["Velocity actual value"].raw
    check("csv: velocity actual = target (TPDO2)", v == VEL, v)

    # --- quick stop ---
    node.rpdo[1]["Controlword"].raw = 0x0002
    ok = wait_until(lambda: node.state == "QUICK STOP ACTIVE" and node.tpdo[2]["Velocity actual value"].raw == 0, 5)
    check("cia402: quick stop -> QUICK STOP ACTIVE, velocity 0", ok,
          f"{node.state} v={node.tpdo[2]['Velocity actual value'].raw}")

    # --- fault injection, EMCY, fault reset ---
    node.state = "OPERATION ENABLED"
    node.emcy.reset()
    try:
        node.sdo[0x2000].raw = 1
    except canopen.SdoCommunicationError as exc:
        # seen once in CI: the drive took the write (it faulted, sent its EMCY and its SDO answer, tx_fail 0)
        # but python-canopen in the starved guest saw no answer within 2 s; the checks below still demand
        # the fault's EMCY, statusword and 0x603F
        print(f"note: the fault-injection write got no SDO answer in time ({exc}); judging by its effects")
    e = next((x for x in node.emcy.log if x.code == 0xFF00), None)
    if e is None:
        try:
            e = node.emcy.wait(0xFF00, timeout=5)
        except Exception:  # noqa: BLE001
            e = None
    check("emcy: injected drive fault -> EMCY 0xFF00", e is not None and e.code == 0xFF00, e)
    ok = wait_until(lambda: node.state == "FAULT", 5)
    check("cia402: statusword FAULT, 0x603F = 0xFF00", ok and node.sdo[0x603F].raw == 0xFF00,
          f"{node.state} 0x603F={node.sdo[0x603F].raw:#x}")
    node.rpdo[1]["Target velocity"].raw = 0
    node.rpdo[1]["Controlword"].raw = 0x0000
    time.sleep(0.1)
    node.rpdo[1]["Controlword"].raw = 0x0080  # rising edge: fault reset
    # generous: in a starved guest python-canopen's receive thread has lagged the bus by seconds (CI 2026-12-06:
    # the drive's EMCY 0x0000 was on the bus, its TPDO not yet read, after 5 s)
    ok = wait_until(lambda: node.state == "SWITCH ON DISABLED", 20)
    got_reset = wait_until(lambda: any(x.code == 0 for x in node.emcy.log), 10)
    check("cia402: fault reset -> SWITCH ON DISABLED, EMCY 0x0000 (error reset)", ok and got_reset,
          f"{node.state} emcy={[hex(x.code) for x in node.emcy.log]}")
except Exception as exc:  # noqa: BLE001
    # a step that raised (an SDO answer lost on a starved guest, say) is a failing check with its line, and
    # the files below are still written: the checker then names it instead of finding nothing
    import traceback
    tb = [f for f in traceback.extract_tb(exc.__traceback__) if f.filename.endswith("py_master.py")][-1]
    check(f"no exception (raised at py_master.py:{tb.lineno}: {tb.line})", False, repr(exc))
finally:
    try:
        net.sync.stop()
        node.rpdo[1].stop()
        node.nmt.state = "STOPPED"
        time.sleep(0.1)
    except Exception:  # noqa: BLE001
        pass
    net.disconnect()

with open(OUT, "w") as f:
    json.dump(results, f, indent=1)
with open(OUT.replace(".json", "") + ".bus.json", "w") as f:
    json.dump(bus_log, f)
fails = [r for r in results if not r["ok"]]
print(f"py_master: {len(results) - len(fails)} ok, {len(fails)} failing", flush=True)
sys.exit(1 if fails or not results else 0)
