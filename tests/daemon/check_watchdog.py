#!/usr/bin/env python3
"""vcan_e2e.sh phase D, on the host: mcad was SIGKILLed mid-task; from the candump of both buses (decoded
with cantools and config/can/mca.dbc) and each emulator's --stats / --log, check that each arm's watchdog
braked it and ended in FAULT WATCHDOG, in firmware cycles (one feedback frame per firmware cycle).
  check_watchdog.py DBC CANDUMP WATCHDOG_CYCLES DEC_LIMIT PERIOD_US OUT_DIR
                                           (OUT_DIR/armsim{0,1}D.txt, armlog{0,1}D.txt)
PERIOD_US: the emulators' firmware cycle (--period-us); the per-cycle deceleration step is DEC_LIMIT * PERIOD.
The checks per bus are tests/can/check_bus.py's case c (the vcan suite's controller-killed case): after the
cycle that took the last command, WATCHDOG_CYCLES - 1 more SERVOING cycles and BRAKING in the next one,
per-cycle velocity steps <= DEC_LIMIT * PERIOD (+ one 1e-4 rad/s feedback step), |v| never grows, FAULT with
fault code WATCHDOG and zero velocities, state/fault frames as the emulator logged them. Added here: the
arm moved when the commands stopped (max |v| >= 0.1 rad/s), and the ramp has the minimum length
ceil(max |v0| / (DEC_LIMIT PERIOD)) (+-1: the feedback's 1e-4 rad/s velocity step).
Prints one line per check, starting 'ok   ' or 'FAIL ', and a summary line 'E2E phase D: vcanN: ...';
exit 1 if any check fails."""
import math
import os
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'can'))
import check_bus  # noqa: E402
import cantools  # noqa: E402

BASE = check_bus.BASE


def figures(db, dump, wd, dec):
    """(v at the last command, cycles to BRAKING, BRAKING cycles, minimum ramp length)"""
    fr = check_bus.decode_all(db, check_bus.read_candump(dump))
    cmds = [x[4] for x in fr if x[1] == BASE and x[4]]
    fbs = [x[4] for x in fr if x[1] == BASE + 1 and x[4]]
    if not cmds or not fbs:
        return None
    last = cmds[-1]['FrameId']
    k0 = next((k for k, d in enumerate(fbs) if d['FrameId'] == last), None)
    if k0 is None:
        return None
    v0 = max(abs(fbs[k0][f'Vel{j}']) for j in range(6))
    rest = [int(d['State']) for d in fbs[k0 + 1:]]
    to_brk = next((k + 1 for k, s in enumerate(rest) if s == 3), None)
    nbrk = sum(1 for s in rest if s == 3)
    # the last SERVOING cycle's velocity is where the ramp starts
    kb = k0 + (to_brk or 1) - 1
    vb = max(abs(fbs[kb][f'Vel{j}']) for j in range(6))
    # the ramp: the BRAKING cycles and the one that reaches 0 (it reports FAULT already); the feedback's
    # velocity is rounded to 1e-4 rad/s, so the minimum length is known to within that
    step = dec * 1e-3
    return v0, to_brk, nbrk + 1, vb, math.ceil((vb - 5e-5) / step - 1e-9), math.ceil((vb + 5e-5) / step - 1e-9)


def main():
    dbc, dump, wd, out = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[6]
    # case c takes the limit per 1 ms cycle: the same step per cycle of PERIOD_US (+ 1e-9 rad/s per cycle:
    # floating-point slack, the two rounded feedback velocities can differ by exactly step + 1e-4)
    dec = float(sys.argv[4]) * int(sys.argv[5]) / 1000.0 + 1e-6
    db = cantools.database.load_file(dbc, strict=True)
    with open(dump) as f:
        lines = f.readlines()
    for i in (0, 1):
        n0 = len(check_bus.FAILS)
        with tempfile.NamedTemporaryFile('w', suffix='.candump', delete=False) as t:
            t.writelines(ln for ln in lines if f' vcan{i} ' in ln)
        print(f'-- vcan{i}')
        check_bus.case_c(db, t.name, wd, dec, os.path.join(out, f'armsim{i}D.txt'),
                         os.path.join(out, f'armlog{i}D.txt'))
        fg = figures(db, t.name, wd, dec)
        os.unlink(t.name)
        if fg is None:
            check_bus.check(False, f'vcan{i}: no command answered on the bus')
            continue
        v0, to_brk, nramp, vb, lo, hi = fg
        check_bus.check(v0 >= 0.1, f'vcan{i}: arm moving when the commands stopped: max |v| {v0:.4f} rad/s >= 0.1')
        check_bus.check(to_brk == wd, f'vcan{i}: BRAKING in cycle {to_brk} without a command (watchdog {wd})')
        check_bus.check(lo <= nramp <= hi, f'vcan{i}: ramp {nramp} cycles to zero (BRAKING + the one reaching 0), '
                                           f'minimum ceil({vb:.4f} / {dec * 1e-3:g}) = {lo}..{hi}')
        print(f'E2E phase D: vcan{i}: last command taken at max |v| {v0:.4f} rad/s; BRAKING in cycle {to_brk} '
              f'without a command (watchdog {wd}); velocity 0 after {nramp} cycles from {vb:.4f} rad/s '
              f'(minimum {lo}{"" if lo == hi else ".." + str(hi)}, step {float(sys.argv[4]) * int(sys.argv[5]) * 1e-6:g} rad/s per cycle), in FAULT '
              f'WATCHDOG; checks failed: {len(check_bus.FAILS) - n0}')
    return 1 if check_bus.FAILS else 0


if __name__ == '__main__':
    sys.exit(main())
