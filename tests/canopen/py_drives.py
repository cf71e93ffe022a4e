#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""CiA 402 drives built on python-canopen LocalNode (an independent CANopen stack) from the same EDS as
mca-drivesim, for our master (mca-co-ctl) to run.

Usage: py_drives.py IFACE EDS FIRST_NODE N OUT_JSON

Each drive: python-canopen's LocalNode serves SDO from the EDS (its own SDO server) and its NMT slave and
heartbeat producer; this script adds what LocalNode leaves to the application: boot-up after a remote NMT
reset, the RPDOs and TPDOs as configured over SDO by the master (COB-ids and mappings read back from the
LocalNode's own object dictionary at each frame), and a CiA 402 state machine written here from the
CiA 402 tables (not mca's code), with an ideal velocity axis: position += target velocity * period per SYNC
in CSV mode. Runs until SIGTERM, then writes OUT_JSON: per node the objects the master configured, the
controlwords seen in order (deduplicated), every RPDO target applied, the final position, SYNCs handled.
"""
import json
import signal
import sys
import threading
import time
import types

import can
import canopen

IFACE, EDS, FIRST, N, OUT = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4]), sys.argv[5]

# CiA 402 statusword patterns (bits 0..6) and controlword commands, from the profile's tables
SW = {"SWITCH ON DISABLED": 0x40, "READY TO SWITCH ON": 0x31, "SWITCHED ON": 0x33, "OPERATION ENABLED": 0x37,
      "QUICK STOP ACTIVE": 0x17, "FAULT": 0x08}


def next_state(state, cw, prev_cw):
    shutdown = (cw & 0x87) == 0x06
    switch_on = (cw & 0x8F) == 0x07
    enable = (cw & 0x8F) == 0x0F
    disable_voltage = (cw & 0x82) == 0x00
    quick_stop = (cw & 0x86) == 0x02
    if state == "FAULT":
        return "SWITCH ON DISABLED" if (cw & 0x80) and not (prev_cw & 0x80) else state
    if state == "SWITCH ON DISABLED":
        return "READY TO SWITCH ON" if shutdown else state
    if state == "READY TO SWITCH ON":
        if switch_on:
            return "SWITCHED ON"
        return "SWITCH ON DISABLED" if disable_voltage or quick_stop else state
    if state == "SWITCHED ON":
        if enable:
            return "OPERATION ENABLED"
        if shutdown:
            return "READY TO SWITCH ON"
        return "SWITCH ON DISABLED" if disable_voltage or quick_stop else state
    if state == "OPERATION ENABLED":
        if switch_on:
            return "SWITCHED ON"
        if shutdown:
            return "READY TO SWITCH ON"
        if quick_stop:
            return "QUICK STOP ACTIVE"
        return "SWITCH ON DISABLED" if disable_voltage else state
    if state == "QUICK STOP ACTIVE":
        if enable:
            return "OPERATION ENABLED"
        return "SWITCH ON DISABLED" if disable_voltage else state
    return state


class Drive:
    def __init__(self, net, node_id):
        self.net = net
        self.id = node_id
        self.node = canopen.LocalNode(node_id, EDS)
        net.add_node(self.node)
        self.state = "SWITCH ON DISABLED"
        self.prev_cw = 0
        self.pos = 0.0  # counts (float: exact integration of integer velocities)
        self.cws = []
        self.targets = []
        self.syncs = 0
        self.lock = threading.Lock()
        self.pdo_cfg = None  # (rpdos, tpdos) read from the OD; dropped whenever the master writes 0x1400..0x1BFF
        self.node.add_write_callback(self.on_write)
        net.subscribe(0x000, self.on_nmt)
        for k in range(2):
            net.subscribe(0x200 + 0x100 * k + node_id, self.on_rpdo)
        self.put(0x6041, 0, SW[self.state])

    def get(self, index, sub):
        var = self.node.object_dictionary[index]
        if hasattr(var, "subindices"):
            var = var[sub]
        return var.decode_raw(self.node.get_data(index, sub))

    def put(self, index, sub, value):
        var = self.node.object_dictionary[index]
        if hasattr(var, "subindices"):
            var = var[sub]
        self.node.set_data(index, sub, var.encode_raw(value))

    def mapping(self, map_index):
        out = []
        for i in range(1, self.get(map_index, 0) + 1):
            e = self.get(map_index, i)
            out.append((e >> 16, (e >> 8) & 0xFF, (e & 0xFF) // 8))
        return out

    def on_write(self, index, subindex, od, data):
        if 0x1400 <= index <= 0x1BFF:
            self.pdo_cfg = None

    def pdos(self):
        """[(cob, type, [(index, sub, bytes)])] for RPDO1..2 and TPDO1..2, from the object dictionary."""
        if self.pdo_cfg is None:
            rx = [(self.get(0x1400 + k, 1), 0, self.mapping(0x1600 + k)) for k in range(2)]
            tx = [(self.get(0x1800 + k, 1), self.get(0x1800 + k, 2), self.mapping(0x1A00 + k)) for k in range(2)]
            self.pdo_cfg = (rx, tx)
        return self.pdo_cfg

    def on_nmt(self, can_id, data, ts):
        cmd, target = data[0], data[1]
        if target not in (0, self.id) or cmd not in (0x81, 0x82):
            return
        # LocalNode's NMT slave changes its state but sends no boot-up on a remote reset: do it here
        if cmd == 0x81:
            self.node.data_store.clear()  # application reset: every object back to the EDS default
        else:
            for index in [i for i in self.node.data_store if 0x1000 <= i <= 0x1FFF]:
                del self.node.data_store[index]
        self.node.nmt.send_command(cmd)  # INITIALISING: boot-up message
        self.node.nmt.send_command(0x80)  # PRE-OPERATIONAL (heartbeat from 0x1017)

    def on_rpdo(self, can_id, data, ts):
        if self.node.nmt.state != "OPERATIONAL":
            return
        for cob, _, mapping in self.pdos()[0]:
            if cob & 0x80000000 or (cob & 0x7FF) != can_id:
                continue
            off = 0
            with self.lock:
                for index, sub, size in mapping:
                    self.node.set_data(index, sub, bytes(data[off:off + size]))
                    off += size

    def on_sync(self):
        if self.node.nmt.state != "OPERATIONAL":
            return
        with self.lock:
            self.syncs += 1
            cw = self.get(0x6040, 0)
            if not self.cws or self.cws[-1] != cw:
                self.cws.append(cw)
            self.state = next_state(self.state, cw, self.prev_cw)
            self.prev_cw = cw
            period = self.get(0x60C2, 1) * 10.0 ** self.get(0x60C2, 2)
            vel = 0
            if self.state == "OPERATION ENABLED" and self.get(0x6060, 0) == 9:
                vel = self.get(0x60FF, 0)
                self.targets.append(vel)
            self.pos += vel * period
            self.put(0x6041, 0, SW[self.state] | 0x0200)
            self.put(0x6064, 0, int(round(self.pos)))
            self.put(0x606C, 0, vel)
            self.put(0x6077, 0, 0)
            self.put(0x6061, 0, self.get(0x6060, 0))
            frames = []
            for cob, ttype, mapping in self.pdos()[1]:
                if cob & 0x80000000 or not 1 <= ttype <= 240 or self.syncs % ttype:
                    continue
                payload = b"".join(self.node.get_data(i, s) for i, s, _ in mapping)
                frames.append((cob & 0x7FF, payload))
        for cob, payload in frames:
            self.net.send_message(cob, payload)

    def report(self):
        return {
            "node": self.id,
            "state": self.state,
            "nmt": self.node.nmt.state,
            "syncs": self.syncs,
            "pos_counts": int(round(self.pos)),
            "controlwords": self.cws,
            "targets": self.targets,
            "heartbeat_ms": self.get(0x1017, 0),
            "mode": self.get(0x6060, 0),
            "interp": [self.get(0x60C2, 1), self.get(0x60C2, 2)],
            "rpdo1_cob": self.get(0x1400, 1),
            "rpdo1_map": [f"{self.get(0x1600, i):08X}" for i in range(1, self.get(0x1600, 0) + 1)],
            "tpdo1_map": [f"{self.get(0x1A00, i):08X}" for i in range(1, self.get(0x1A00, 0) + 1)],
            "tpdo2_map": [f"{self.get(0x1A01, i):08X}" for i in range(1, self.get(0x1A01, 0) + 1)],
            "tpdo_types": [self.get(0x1800, 2), self.get(0x1801, 2)],
        }


net = canopen.Network()
net.connect(interface="socketcan", channel=IFACE)
# heartbeats: python-can's thread-based periodic sender (the guest kernel has no can-bcm loaded)
net.bus._send_periodic_internal = types.MethodType(can.BusABC._send_periodic_internal, net.bus)
drives = [Drive(net, FIRST + j) for j in range(N)]
net.subscribe(0x080, lambda can_id, data, ts: [d.on_sync() for d in drives])
for d in drives:
    d.node.nmt.send_command(0x82)  # power-on boot-up
    d.node.nmt.send_command(0x80)
print(f"py_drives: {N} LocalNode drives, nodes {FIRST}..{FIRST + N - 1} on {IFACE}", flush=True)

stop = threading.Event()
signal.signal(signal.SIGTERM, lambda *a: stop.set())
signal.signal(signal.SIGINT, lambda *a: stop.set())
open(OUT + ".ready", "w").close()
while not stop.wait(0.2):
    pass
for d in drives:
    d.node.nmt.stop_heartbeat()
time.sleep(0.3)  # the thread-based heartbeat senders end their last period
net.disconnect()
with open(OUT, "w") as f:
    json.dump([d.report() for d in drives], f, indent=1)
print("py_drives: " + " ".join(f"node{d.id}={d.state}/{d.syncs}" for d in drives), flush=True)
