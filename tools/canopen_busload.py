#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Bus-load budget of the CANopen backend (docs/canopen.md prints this script's table).

Per SYNC cycle with N drives the bus carries: one SYNC (0 bytes), and per drive one RPDO1
(controlword + target, 6 bytes), one TPDO1 (statusword + position, 6 bytes) and one TPDO2 (velocity +
torque, 6 bytes). Heartbeats (1 byte per drive per 100 ms) and EMCY/SDO traffic are extra, hence the 60 %
ceiling used to choose the SYNC period.

Bits per frame, 11-bit identifiers, worst-case bit stuffing (ISO 11898-1):
  classic CAN, n data bytes: 47 + 8n fixed-form bits, + floor((34 + 8n - 1) / 4) stuff bits
  CAN FD with bit-rate switch, n data bytes (n <= 16: CRC-17):
    nominal rate: 17 arbitration bits + floor(16 / 4) stuff bits + 13 (CRC delimiter, ACK, EOF, IFS)
    data rate:    ESI + DLC + 8n (+ floor((5 + 8n - 1) / 4) stuff bits) + 4 stuff count + 17 CRC + 6 fixed
                  stuff bits
With CAN FD the drive's two TPDOs are one 12-byte PDO (CANopen FD, CiA 1301): the table's FD rows use
RPDO 6 bytes + TPDO 12 bytes per drive.

Usage: canopen_busload.py [--markdown]
"""
import sys


def classic_bits(n):
    return 47 + 8 * n + (34 + 8 * n - 1) // 4


def fd_time_us(n, nominal, data):
    nominal_bits = 17 + 16 // 4 + 13
    data_bits = 1 + 4 + 8 * n + (5 + 8 * n - 1) // 4 + 4 + 17 + 6
    return nominal_bits / nominal + data_bits / data, nominal_bits, data_bits


def cycle_classic(nd):
    bits = classic_bits(0) + nd * 3 * classic_bits(6)
    return bits, bits / 1.0  # us at 1 Mbit/s


def cycle_fd(nd, data_mbit):
    t0, _, _ = fd_time_us(0, 1.0, data_mbit)
    t6, _, _ = fd_time_us(6, 1.0, data_mbit)
    t12, _, _ = fd_time_us(12, 1.0, data_mbit)
    return t0 + nd * (t6 + t12)


PERIODS_US = [1000, 2000, 4000, 5000, 10000]


def pick(t_us, ceiling=0.6):
    for p in PERIODS_US:
        if t_us <= ceiling * p:
            return p
    return None


def main():
    md = "--markdown" in sys.argv
    rows = []
    for nd in (1, 2, 3, 4, 6, 8):
        bits, t = cycle_classic(nd)
        row = [str(nd), f"{bits}", f"{t:.0f}", f"{100 * t / 1000:.0f} %", f"{100 * t / 4000:.0f} %"]
        for r in (2.0, 5.0, 8.0):
            tf = cycle_fd(nd, r)
            row.append(f"{tf:.0f}")
        p_c = pick(t)
        p_f = pick(cycle_fd(nd, 5.0))
        row += [f"{p_c / 1000:g} ms" if p_c else "-", f"{p_f / 1000:g} ms" if p_f else "-"]
        rows.append(row)
    head = ["drives", "classic bits/cycle", "classic us/cycle @1M", "load @1 ms", "load @4 ms",
            "FD us @1M/2M", "FD us @1M/5M", "FD us @1M/8M", "SYNC period classic", "SYNC period FD 1M/5M"]
    if md:
        print("| " + " | ".join(head) + " |")
        print("|" + "---|" * len(head))
        for r in rows:
            print("| " + " | ".join(r) + " |")
    else:
        print("\t".join(head))
        for r in rows:
            print("\t".join(r))
    print()
    print(f"frame bits (worst-case stuffing): classic SYNC {classic_bits(0)}, 6-byte PDO {classic_bits(6)}; "
          f"FD 6-byte {fd_time_us(6, 1, 5)[1]}+{fd_time_us(6, 1, 5)[2]}, 12-byte "
          f"{fd_time_us(12, 1, 5)[1]}+{fd_time_us(12, 1, 5)[2]} (nominal + data bits)")


if __name__ == "__main__":
    main()
