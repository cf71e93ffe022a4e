#!/usr/bin/env python3
"""Writes the binary seed corpora of the CAN fuzz targets (fuzz/corpus/{can_link,armsim_rx}/) and the
crafted regression inputs of issue 16 (fuzz/regress/...), in the record format of fuzz/frames.h.
Run from the repository root: python3 fuzz/mkseeds.py (the files are committed; rerun only to remake)."""
import os
import struct

HERE = os.path.dirname(os.path.abspath(__file__))


def frame(off, data, classic=False):
    return bytes([0, (off & 0xF) | (0x80 if classic else 0), len(data)]) + bytes(data)


def err(bits):
    return bytes([1]) + struct.pack('<I', bits)


def step(arg=0):
    return bytes([2, arg])


def tick(tenths_ms):
    return bytes([3, tenths_ms])


def feedback(ctr, frame_id, q, state=2, code=0):
    b = bytearray(64)
    b[0] = ctr & 0xFF
    b[1] = (state & 0xF) | ((code & 0xF) << 4)
    struct.pack_into('<H', b, 2, frame_id & 0xFFFF)
    for j, v in enumerate(q):
        raw = max(-2**31, min(2**31 - 1, round(v / 1e-6)))
        struct.pack_into('<i', b, 4 + 4 * j, raw)
    return bytes(b)


def state(ctr, st, n, code=0, missed=0, rxe=0):
    return bytes([ctr & 0xFF, st]) + struct.pack('<HHBB', code, missed, n, rxe)


def fault(ctr, st, code, flags):
    return bytes([ctr & 0xFF, st]) + struct.pack('<H', code) + struct.pack('<8H', *flags)


def command(ctr, frame_id, n, vel, flags=3):
    b = bytearray(64)
    b[0] = ctr & 0xFF
    b[1] = n
    struct.pack_into('<H', b, 2, frame_id & 0xFFFF)
    for j in range(n):
        b[4 + j // 2] |= (flags & 0xF) << (4 * (j % 2))
        struct.pack_into('<i', b, 8 + 4 * j, round(vel[j] / 1e-6))
    return bytes(b)


def write(sub, name, data):
    d = os.path.join(HERE, sub)
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, name), 'wb') as f:
        f.write(data)


# controller side: first byte = joint count - 1 (6 joints)
def ctl(records, n=6):
    return bytes([n - 1]) + b''.join(records)


q = [0.1 * j for j in range(6)]
normal = [frame(2, state(0, 1, 6))]
for k in range(20):
    normal += [step(0), tick(10), frame(1, feedback(k, k + 1, [x + 1e-4 * k for x in q]))]
    if k % 10 == 0:
        normal.append(frame(2, state(k // 10 + 1, 2, 6)))
normal += [frame(3, fault(0, 2, 0, [0, 8, 0, 0, 0, 0, 0, 0])), step(0)]
write('corpus/can_link', 'normal-6j', ctl(normal))
write('corpus/can_link', 'errors', ctl([frame(1, feedback(0, 0, q)), step(0), err(0x40), step(0), err(0x100 | 0x04),
                                         step(0), tick(50), frame(1, feedback(1, 1, q)), step(0)]))
write('corpus/can_link', 'bad-frames', ctl([frame(1, feedback(0, 0, q)[:8], classic=True), frame(1, feedback(0, 0, q)[:48]),
                                             frame(5, b'\x01\x02'), frame(0, command(0, 1, 6, [0] * 6)),
                                             frame(2, state(3, 7, 6)), step(1)]))
# issue 16 regressions (the link must refuse these; the fuzz target checks what it returns)
write('regress/can_link', 'feedback-2147rad', ctl([step(0), frame(1, feedback(0, 1, [2147.483647] + q[1:])), step(0),
                                                   frame(1, feedback(1, 1, [-2147.483648] + q[1:])), step(0)]))
write('regress/can_link', 'jump-2147-to-minus1', ctl([step(0), frame(1, feedback(0, 1, [2147.0] + q[1:])), step(0), tick(10),
                                                      frame(1, feedback(1, 2, [-1.0] + q[1:])), step(0)]))
write('regress/can_link', 'frame-ahead', ctl([step(0), frame(1, feedback(0, 1, q)), step(0),
                                              frame(1, feedback(1, 1000, q)), step(0)]))
write('regress/can_link', 'heartbeat-7-joints', ctl([frame(2, state(0, 1, 7)), frame(1, feedback(0, 0, q)), step(0)]))
write('regress/can_link', 'busoff-restarted', ctl([frame(1, feedback(0, 0, q)), step(0), err(0x40 | 0x100), step(0), step(0)]))
write('regress/can_link', 'forged-counter-pair', ctl([frame(1, feedback(0, 0, q)), step(0), frame(1, feedback(77, 1, [3.0] * 6)),
                                                      frame(1, feedback(78, 1, [3.0] * 6)), step(0),
                                                      frame(1, feedback(1, 1, q)), step(0)]))

# emulator side (id base 0x110; offsets as above)
v = [0.01] * 6
emu = []
for k in range(20):
    emu += [frame(0, command(k, k + 1, 6, v)), step(0)]
write('corpus/armsim_rx', 'normal-6j', b''.join(emu))
write('corpus/armsim_rx', 'superseded-and-bad', b''.join([frame(0, command(0, 1, 6, v)), frame(0, command(1, 2, 6, v)), step(0),
                                                           frame(0, command(2, 3, 9, v + [0, 0, 0])), frame(0, command(2, 3, 6, v)[:48]),
                                                           frame(1, feedback(0, 0, q)), err(0x40), step(0)]))
write('regress/armsim_rx', 'forged-frame-id-plus-32767', b''.join(
    [frame(0, command(0, 100, 6, v)), step(0), frame(0, command(1, 100 + 32767, 6, [-0.6] * 6, 0)),
     frame(0, command(1, 101, 6, v)), step(0)] + [x for k in range(30) for x in (frame(0, command(2 + k, 102 + k, 6, v)), step(0))]))
write('regress/armsim_rx', 'flood', b''.join([frame(0, command(k % 256, 5, 6, v)) for k in range(300)] + [step(0)]))

# injection text: first byte = joint count
for i, t in enumerate(['actuator@5000:1', 'freeze@7000+50', 'silent@9000+20', 'drop-rx@12000+30', 'actuator@0:0']):
    write('corpus/inject', f'seed{i}', bytes([6]) + t.encode())
write('regress/inject', 'huge-cycle', bytes([6]) + b'freeze@99999999999999999999999+1')
write('regress/inject', 'joint-out-of-range', bytes([6]) + b'actuator@5:6')
write('regress/inject', 'no-joints', bytes([0]) + b'actuator@5:0')

# parsers: empty and comment-only files, a URDF nested 50 000 deep (issue 16)
write('regress/cell', 'empty', b'')
write('regress/cell', 'comment-only', b'# nothing here\n')
write('regress/cell', 'long-line', b'name: x\n# ' + b'y' * 3000 + b'\nbogus: 1\n')
write('regress/scenario', 'empty', b'')
write('regress/scenario', 'comment-only', b'# nothing here\n')
write('regress/scenario', 'huge-duration', b'name: x\nduration: 1e7\ndt: 0.001\narms: []\n')
write('regress/urdf', 'nested-50000', b'<robot name="r">' + b'<a>' * 50000 + b'</a>' * 50000 + b'</robot>\n')
write('regress/urdf', 'velocity-1e300', open(os.path.join(HERE, '../config/robots/jaco2.urdf'), 'rb').read()
      .replace(b'velocity="', b'velocity="1e300" x="', 1))
