#!/usr/bin/env python3
"""Checks of the vcan suite on a candump -L capture, decoded with python cantools and config/can/mca.dbc.
  check_bus.py DBC a   CANDUMP CTL_LOG CTL_STATS ARMSIM_STATS           sent/received values vs the bus
  check_bus.py DBC b   CANDUMP CTL_STATS LOST_CYCLES                    lost feedback -> controller stops
  check_bus.py DBC c   CANDUMP WATCHDOG_CYCLES DEC_LIMIT ARMSIM_STATS   watchdog braking on the bus
  check_bus.py DBC d   CANDUMP CTL_STATS ARMSIM_STATS                   injected frames counted, not applied
Prints one line per check, exit 1 if any fails."""
import sys

import cantools

BASE = 0x100
FAILS = []


def check(ok, what):
    print(('ok   ' if ok else 'FAIL ') + what)
    if not ok:
        FAILS.append(what)


def read_candump(path):
    """[(t, can_id, fd, bytes)] in bus order."""
    out = []
    with open(path) as f:
        for line in f:
            p = line.split()
            if len(p) < 3 or '#' not in p[2]:
                continue
            t = float(p[0].strip('()'))
            ident, _, rest = p[2].partition('#')
            fd = rest.startswith('#')
            data = bytes.fromhex(rest[2:] if fd else rest)
            out.append((t, int(ident, 16), fd, data))
    return out


def stats(path):
    with open(path) as f:
        return {k: v for k, v in (w.split('=', 1) for w in f.read().split())}


def decode_all(db, frames):
    """Decode frames whose id and length the DBC knows; others are left undecoded (None)."""
    res = []
    for t, ident, fd, data in frames:
        try:
            m = db.get_message_by_frame_id(ident)
        except KeyError:
            res.append((t, ident, fd, data, None))
            continue
        ok = fd == m.is_fd and len(data) == m.length
        res.append((t, ident, fd, data, m.decode(data, decode_choices=False) if ok else None))
    return res


def seq_sim(frames, ident, length, fd=True):
    """Independent re-implementation of the receive rule: returns (accepted, bad_length, bad_counter)."""
    synced, last, cand = False, 0, None
    acc = badlen = badctr = 0
    for t, i, f, data, dec in frames:
        if i != ident:
            continue
        if f != fd or len(data) != length:
            badlen += 1
            continue
        c = data[0]
        if not synced or c == (last + 1) % 256 or (cand is not None and c == (cand + 1) % 256):
            synced, last, cand = True, c, None
            acc += 1
        else:
            cand = c
            badctr += 1
    return acc, badlen, badctr


def complete(fr, arm_stats, ctl_stats, what):
    """The capture holds every frame both programs sent (candump can drop frames when starved)."""
    a, c = stats(arm_stats), stats(ctl_stats)
    for ident, n, who in ((BASE + 1, int(a['tx_feedback']), 'feedback'), (BASE + 2, int(a['tx_state']), 'state'),
                          (BASE + 3, int(a['tx_fault']), 'fault')):
        got = sum(1 for x in fr if x[1] == ident)
        if got < n:
            check(False, f'{what}: capture incomplete: {got} of {n} {who} frames (candump dropped frames)')
            return False
    got = sum(1 for x in fr if x[1] == BASE)
    if got < int(c['commands_sent']):
        check(False, f'{what}: capture incomplete: {got} of {c["commands_sent"]} command frames (candump dropped)')
        return False
    return True


def case_a(db, dump, log, ctl_stats, arm_stats):
    fr = decode_all(db, read_candump(dump))
    if not complete(fr, arm_stats, ctl_stats, 'a'):
        return
    cmds = [d for t, i, f, data, d in fr if i == BASE and d]
    fbs = [d for t, i, f, data, d in fr if i == BASE + 1 and d]
    tx, rx = [], []
    with open(log) as f:
        for line in f:
            p = line.split()
            (tx if p[0] == 'tx' else rx).append([float(x) for x in p[1:]])
    n = (len(tx[0]) - 2) if tx else 0
    check(len(tx) > 1500, f'a: controller sent {len(tx)} commands in 2 s (> 1500)')
    # every logged command is on the bus once (last one is the braking request, not logged)
    bus_by_id = {}
    for d in cmds:
        bus_by_id.setdefault(int(d['FrameId']), []).append(d)
    missing = [r for r in tx if int(r[1]) & 0xFFFF not in bus_by_id]
    check(not missing, f'a: all {len(tx)} logged commands found on the bus (missing {len(missing)})')
    maxerr = 0.0
    for r in tx:
        for d in bus_by_id.get(int(r[1]) & 0xFFFF, []):
            for j in range(n):
                maxerr = max(maxerr, abs(d[f'Vel{j}'] - r[2 + j]))
    check(maxerr <= 0.5e-6 + 1e-12, f'a: cantools-decoded command velocities = sent values (max err {maxerr:.2e} <= 5e-7)')
    # each feedback the controller used is a bus frame, in bus order, with equal values
    k, matched, worst = 0, 0, 0.0
    for r in rx:
        while k < len(fbs):
            d = fbs[k]
            k += 1
            if int(d['FrameId']) == int(r[1]) & 0xFFFF and all(abs(d[f'Pos{j}'] - r[4 + j]) <= 1e-7 for j in range(n)):
                worst = max(worst, max(abs(d[f'Vel{j}'] - r[4 + n + j]) for j in range(n)))
                matched += 1
                break
    check(len(rx) > 1500 and matched == len(rx) and worst <= 1e-5,
          f'a: {matched}/{len(rx)} feedbacks read by the controller = cantools-decoded bus frames, in order')
    moved = max(abs(fbs[-1][f'Pos{j}'] - fbs[0][f'Pos{j}']) for j in range(n)) if fbs else 0
    check(moved > 0.05, f'a: the arm moved ({moved:.3f} rad max joint travel)')
    servo = sum(1 for d in fbs if d['State'] == 2)
    check(servo > 1500, f'a: {servo} feedback frames in SERVOING')
    cs, asx = stats(ctl_stats), stats(arm_stats)
    bad = {k: v for k, v in list(cs.items()) + list(asx.items()) if k.startswith('rx_bad') and v != '0'}
    check(not bad, f'a: no bad frames on either side {bad or ""}')


def case_b(db, dump, ctl_stats, lost):
    fr = decode_all(db, read_candump(dump))
    cs = stats(ctl_stats)
    lost_at, last_fb = int(cs['lost_at']), int(cs['last_fb_cycle'])
    check(lost_at >= 0, f'b: controller reported lost feedback (lost_at={lost_at})')
    check(lost_at - last_fb == lost, f'b: detected {lost_at - last_fb} cycles after the last feedback (= {lost})')
    idx_last_fb = max(k for k, x in enumerate(fr) if x[1] == BASE + 1)
    after = sum(1 for x in fr[idx_last_fb + 1:] if x[1] == BASE)
    check(after <= lost + 1, f'b: {after} commands on the bus after the last feedback frame (<= {lost + 1}), then none')
    bus_cmds = sum(1 for x in fr if x[1] == BASE)
    check(bus_cmds == int(cs['commands_sent']), f'b: bus commands {bus_cmds} = controller commands_sent {cs["commands_sent"]}')


def case_c(db, dump, wd, dec, arm_stats):
    fr = decode_all(db, read_candump(dump))
    a = stats(arm_stats)
    got = sum(1 for x in fr if x[1] == BASE + 1)
    if got < int(a['tx_feedback']):
        check(False, f'c: capture incomplete: {got} of {a["tx_feedback"]} feedback frames (candump dropped frames)')
        return
    cmds = [x[4] for x in fr if x[1] == BASE and x[4]]
    if not cmds:
        check(False, 'c: no command frame on the bus')
        return
    last_cmd = cmds[-1]
    idx_last_cmd = max(k for k, x in enumerate(fr) if x[1] == BASE)
    # the feedback frames from the firmware cycle that took the last command on (it answers its FrameId)
    allfb = [(k, x[4]) for k, x in enumerate(fr) if x[1] == BASE + 1 and x[4]]
    first = next((k for k, (i, d) in enumerate(allfb) if d['FrameId'] == last_cmd['FrameId']), None)
    if first is None or allfb[first][1]['State'] != 2:
        check(False, f'c: the last command (frame {last_cmd["FrameId"]}) was not taken on in SERVOING '
                     '(an earlier watchdog trip while the controller was preempted?)')
        return
    fbs = [d for i, d in allfb[first + 1:]]
    states = [int(d['State']) for d in fbs]
    nserv = 0
    while nserv < len(states) and states[nserv] == 2:
        nserv += 1
    check(nserv == wd - 1 and nserv < len(states) and states[nserv] == 3,
          f'c: after the cycle that took the last command: {nserv} SERVOING cycles, then BRAKING in cycle {nserv + 1}'
          f' (watchdog {wd} cycles)')
    brk = [d for d in fbs[nserv:] if d['State'] == 3]
    check(len(brk) > 2, f'c: {len(brk)} BRAKING feedback frames')
    first_fault = next((k for k, s in enumerate(states) if s == 4), None)
    check(first_fault is not None and all(s == 3 for s in states[nserv:first_fault]),
          'c: BRAKING -> FAULT with nothing in between')
    n = 6
    prev = fbs[nserv - 1] if nserv else allfb[first][1]
    worst = 0.0
    grew = False
    for d in fbs[nserv:first_fault + 1 if first_fault is not None else None]:
        if prev is not None:
            for j in range(n):
                dv = abs(d[f'Vel{j}'] - prev[f'Vel{j}'])
                worst = max(worst, dv)
                grew |= abs(d[f'Vel{j}']) > abs(prev[f'Vel{j}']) + 1e-4
        prev = d
    lim = dec * 1e-3 + 1e-4  # decel limit per cycle + one feedback velocity step (1e-4 rad/s)
    check(worst <= lim and not grew, f'c: velocity ramp max |dv| {worst:.4f} rad/s per cycle <= {lim:.4f}, |v| never grows')
    if first_fault is not None:
        d = fbs[first_fault]
        check(int(d['FaultCode']) == 1 and all(abs(d[f'Vel{j}']) < 1e-9 for j in range(n)),
              f'c: FAULT frame: fault code {int(d["FaultCode"])} (WATCHDOG = 1), all velocities 0')
    sts = [int(x[4]['State']) for x in fr[idx_last_cmd + 1:] if x[1] == BASE + 2 and x[4]]
    check(3 in sts and 4 in sts and sts.index(3) < sts.index(4), f'c: state frames show BRAKING then FAULT {sts[:6]}...')
    flt = [x[4] for x in fr[idx_last_cmd + 1:] if x[1] == BASE + 3 and x[4]]
    check(any(int(d['FaultCode']) == 1 for d in flt), 'c: fault frame with fault code WATCHDOG')


def case_d(db, dump, ctl_stats, arm_stats):
    fr = decode_all(db, read_candump(dump))
    if not complete(fr, arm_stats, ctl_stats, 'd'):
        return
    cs, asx = stats(ctl_stats), stats(arm_stats)
    # arm side: command stream; everything else in the block is unknown to it
    acc, badlen, badctr = seq_sim(fr, BASE, 64)
    unk_arm = sum(1 for x in fr if x[1] != BASE)
    arm_ours = int(asx['tx_feedback']) + int(asx['tx_state']) + int(asx['tx_fault'])  # own frames: not received
    want_arm = {'rx_bad_length': badlen, 'rx_bad_counter': badctr, 'rx_unknown_id': unk_arm - arm_ours,
                'cmd_accepted': acc}
    got_arm = {k: int(asx[k]) for k in want_arm}
    check(got_arm == want_arm, f'd: arm-side counters {got_arm} = bus replay {want_arm}')
    check(badlen >= 2 and badctr >= 1 and want_arm['rx_unknown_id'] >= 4, 'd: the injections reached the arm')
    # controller side: feedback stream (+ state/fault streams), commands from others and unknown ids
    acc_fb, bl_fb, bc_fb = seq_sim(fr, BASE + 1, 64)
    _, bl_st, bc_st = seq_sim(fr, BASE + 2, 8)
    _, bl_ft, bc_ft = seq_sim(fr, BASE + 3, 20)
    injected_cmds = sum(1 for x in fr if x[1] == BASE) - int(cs['commands_sent'])
    unk_ctl = sum(1 for x in fr if x[1] not in (BASE, BASE + 1, BASE + 2, BASE + 3)) + injected_cmds
    want_ctl = {'rx_bad_length': bl_fb + bl_st + bl_ft, 'rx_bad_counter': bc_fb + bc_st + bc_ft,
                'rx_unknown_id': unk_ctl}
    got_ctl = {k: int(cs[k]) for k in want_ctl}
    check(got_ctl == want_ctl, f'd: controller counters {got_ctl} = bus replay {want_ctl}')
    # not applied: the genuine commands all servo; no feedback carries an injected value
    fbs = [x[4] for x in fr if x[1] == BASE + 1 and x[4]]
    first = next(k for k, d in enumerate(fbs) if d['State'] == 2)
    last = max(k for k, d in enumerate(fbs) if d['State'] == 2)
    check(all(d['State'] == 2 for d in fbs[first:last + 1]),
          'd: arm stayed SERVOING through the injections (the injected flags=0 command was not applied)')
    check(int(asx['cmd_accepted']) == acc and acc <= int(cs['commands_sent']) + 0,
          f'd: arm accepted {acc} commands <= {cs["commands_sent"]} sent by the controller (none injected)')
    check(int(cs['bus_errors']) == 2 and int(cs['eio']) >= 1,
          f'e: 2 injected error frames counted by the controller (bus_errors={cs["bus_errors"]}, '
          f'EIO returned {cs["eio"]} times)')
    check(int(asx['bus_errors']) == 2, f'e: arm side counted bus_errors={asx["bus_errors"]}')


def main():
    db = cantools.database.load_file(sys.argv[1], strict=True)
    case = sys.argv[2]
    {'a': case_a, 'b': case_b, 'c': case_c, 'd': case_d}[case](
        db, *[int(a) if a.isdigit() else (float(a) if a.replace('.', '', 1).isdigit() else a) for a in sys.argv[3:]])
    return 1 if FAILS else 0


if __name__ == '__main__':
    sys.exit(main())
