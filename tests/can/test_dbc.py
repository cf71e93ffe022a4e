#!/usr/bin/env python3
"""DBC cross-check: config/can/mca.dbc (python cantools) against the C codec (can-vectors).
Every frame the C codec makes must decode, with cantools and the DBC, to the values put in (within half a
resolution step) and cantools must encode those values back to the same bytes (a second, independent
implementation of the layout). Also checks the DBC declares CAN FD frames of the protocol's lengths.
Usage: test_dbc.py DBC CAN_VECTORS_BINARY"""
import subprocess
import sys

import cantools

SCALE = {'Vel': None, 'PosRef': 1e-5, 'Pos': 1e-6, 'Tau': 0.1}


def main():
    dbc, vec = sys.argv[1], sys.argv[2]
    db = cantools.database.load_file(dbc, strict=True)
    want = {'MCA_Command': (0x100, 64), 'MCA_Feedback': (0x101, 64), 'MCA_State': (0x102, 8),
            'MCA_Fault': (0x103, 20)}
    fails = 0
    for name, (fid, length) in want.items():
        m = db.get_message_by_name(name)
        if m.frame_id != fid or m.length != length or not m.is_fd:
            print(f'FAIL {name}: id {m.frame_id:#x} len {m.length} fd {m.is_fd}, want {fid:#x} {length} fd')
            fails += 1
    out = subprocess.run([vec], check=True, capture_output=True, text=True).stdout.splitlines()
    checked = 0
    for line in out:
        parts = line.split()
        msg = db.get_message_by_name(parts[0])
        data = bytes.fromhex(parts[1])
        vals = {k: float(v) for k, v in (p.split('=') for p in parts[2:])}
        dec = msg.decode(data, decode_choices=False)
        exact = {}
        for sig in msg.signals:
            v = vals[sig.name]
            tol = sig.scale / 2 * (1 + 1e-6) if sig.scale != 1 else 0
            if abs(dec[sig.name] - v) > tol + 1e-12:
                print(f'FAIL {parts[0]} {sig.name}: cantools {dec[sig.name]} vs C input {v}')
                fails += 1
            exact[sig.name] = dec[sig.name]
        # cantools encodes the (rounded) values to the same bytes as the C codec
        enc = msg.encode({k: (round(vals[k] / msg.get_signal_by_name(k).scale) * msg.get_signal_by_name(k).scale
                              if msg.get_signal_by_name(k).scale != 1 else int(vals[k])) for k in exact},
                         scaling=True, strict=True)
        if enc != data:
            print(f'FAIL {parts[0]}: cantools encode {enc.hex()} != C {data.hex()}')
            fails += 1
        checked += 1
    print(f'{checked} frames checked, {fails} failures')
    return 1 if fails or checked < 200 else 0


if __name__ == '__main__':
    sys.exit(main())
