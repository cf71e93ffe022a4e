#!/usr/bin/env python3
"""Checks of the vcan suite on a candump -L capture, decoded with python cantools and config/can/mca.dbc.
  check_bus.py DBC a   CANDUMP CTL_LOG CTL_STATS ARMSIM_STATS ARMSIM_LOG  sent/received values vs the bus
  check_bus.py DBC b   CANDUMP CTL_STATS LOST_CYCLES                      lost feedback -> controller stops
  check_bus.py DBC c   CANDUMP WATCHDOG_CYCLES DEC_LIMIT ARMSIM_STATS ARMSIM_LOG  watchdog braking on the bus
  check_bus.py DBC d   CANDUMP CTL_STATS ARMSIM_STATS                     injected frames counted, not applied
  check_bus.py DBC e   CANDUMP CTL_STATS CTL_LOG                          error frames: EIO and bus-off timing
  check_bus.py DBC g   CTL_OUTPUT                                         round trip: kernel stamps, RTT > 0
CTL_LOG: mca-can-ctl --log (tx/rx/er lines), ARMSIM_LOG: mca-armsim --log (st/ft lines).
Prints one line per check, exit 1 if any fails."""
import sys

import cantools

BASE = 0x100
CAN_ERR_FLAG = 0x20000000
HEARTBEAT = 10  # MCA_CAN_HEARTBEAT_CYCLES
# reads an error frame may be counted late when the kernel delivers it late (case_e): seen 2 in CI, 4 on a host
# running builds beside CI; the bug the check catches holds the bus-off frame until the emulator's next
# feedback, about 50 reads later (it is stopped for 50 ms)
DELIVERY_LAG = 12
FAILS = []


def check(ok, what):
    print(('ok   ' if ok else 'FAIL ') + what)
    if not ok:
        FAILS.append(what)


def read_candump(path):
    """[(t, can_id, fd, bytes)] in bus order, without candump_stop's end marker (0x7FF, no data)."""
    out = []
    with open(path) as f:
        for line in f:
            p = line.split()
            if len(p) < 3 or '#' not in p[2]:
                continue
            t = float(p[0].strip('()'))
            ident, _, rest = p[2].partition('#')
            if int(ident, 16) == 0x7FF:
                continue
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
    synced, last, cand, run = False, 0, 0, 0
    acc = badlen = badctr = 0
    for t, i, f, data, dec in frames:
        if i != ident:
            continue
        if f != fd or len(data) != length:
            badlen += 1
            continue
        c = data[0]
        if not synced or c == (last + 1) % 256:
            synced, last, run = True, c, 0
            acc += 1
            continue
        # a run of 3 consecutive other counters resyncs (MCA_CAN_SEQ_RESYNC_RUN)
        run = run + 1 if run > 0 and c == (cand + 1) % 256 else 1
        cand = c
        if run >= 3:
            last, run = c, 0
            acc += 1
        else:
            badctr += 1
    return acc, badlen, badctr


def read_ctl_log(path):
    """mca-can-ctl --log: (tx, rx, er) lists of number lists."""
    out = {'tx': [], 'rx': [], 'er': []}
    with open(path) as f:
        for line in f:
            p = line.split()
            if p and p[0] in out:
                out[p[0]].append([float(x) for x in p[1:]])
    return out['tx'], out['rx'], out['er']


def read_arm_log(path):
    """mca-armsim --log: (state records, fault records) as int lists [cycle, counter, ...]."""
    st, ft = [], []
    with open(path) as f:
        for line in f:
            p = line.split()
            if p and p[0] in ('st', 'ft'):
                (st if p[0] == 'st' else ft).append([int(x) for x in p[1:]])
    return st, ft


def state_fault_vs_sent(fr, arm_log, what):
    """Every state (heartbeat) and fault frame on the bus, decoded with the DBC, equals what the emulator
    logged as sent, in order; heartbeats every HEARTBEAT cycles plus one per state change; fault frames on
    a change and with every heartbeat while a fault (code or flags) is set."""
    st, ft = read_arm_log(arm_log)
    bst = [d for t, i, f, data, d in fr if i == BASE + 2]
    bft = [d for t, i, f, data, d in fr if i == BASE + 3]
    ok = len(bst) == len(st) and all(d is not None for d in bst)
    bad = 0
    if ok:
        for d, r in zip(bst, st):
            want = {'Counter': r[1], 'State': r[2], 'FaultCode': r[3], 'Missed': r[4], 'NJoints': r[5], 'RxErrors': r[6]}
            bad += any(int(d[k]) != v for k, v in want.items())
    check(ok and bad == 0 and len(st) > 0,
          f'{what}: {len(bst)} state frames on the bus = {len(st)} sent (Counter, State, FaultCode, Missed, NJoints,'
          f' RxErrors), {bad} differ')
    ok = len(bft) == len(ft) and all(d is not None for d in bft)
    bad = 0
    if ok:
        for d, r in zip(bft, ft):
            want = {'Counter': r[1], 'State': r[2], 'FaultCode': r[3]}
            want.update({f'FaultFlags{j}': r[4 + j] for j in range(8)})
            bad += any(int(d[k]) != v for k, v in want.items())
    check(ok and bad == 0,
          f'{what}: {len(bft)} fault frames on the bus = {len(ft)} sent (Counter, State, FaultCode, FaultFlags0..7),'
          f' {bad} differ')
    # heartbeat rule, from the sender's cycle numbers (fw cycle = completed cycles)
    if st:
        cyc = [r[0] for r in st]
        beats = {c for c in cyc if c % HEARTBEAT == 0}
        want = set(range(-(-cyc[0] // HEARTBEAT) * HEARTBEAT, cyc[-1] + 1, HEARTBEAT))
        extra_ok = all(r[0] % HEARTBEAT == 0 or r[2] != p[2] for p, r in zip(st, st[1:]))
        check(beats == want and extra_ok,
              f'{what}: a state frame every {HEARTBEAT} firmware cycles ({len(beats)} heartbeats, {len(want - beats)} '
              f'missing) and the others on state changes ({len(st) - len(beats)})')
    if ft:
        fc = {r[0]: r for r in ft}
        changes = sum(1 for p, r in zip([None] + ft, ft) if p is None or p[3:] != r[3:])
        repeats = [r for p, r in zip([None] + ft, ft) if p is not None and p[3:] == r[3:]]
        rep_ok = all(r[0] % HEARTBEAT == 0 and (r[3] or any(r[4:])) for r in repeats)
        # while a fault is set, every heartbeat cycle carries a fault frame
        missing = 0
        for a, b in zip(ft, ft[1:] + [None]):
            if a[3] or any(a[4:]):
                end = b[0] if b else (st[-1][0] if st else a[0])
                missing += sum(1 for c in range(a[0] + 1, end) if c % HEARTBEAT == 0 and c not in fc
                               and (not st or c <= st[-1][0]))
        check(rep_ok and missing == 0,
              f'{what}: fault frames: {changes} on a change, {len(repeats)} repeats, all on heartbeats while a fault is'
              f' set ({missing} heartbeats without one)')
    return st, ft


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


def case_a(db, dump, log, ctl_stats, arm_stats, arm_log):
    fr = decode_all(db, read_candump(dump))
    if not complete(fr, arm_stats, ctl_stats, 'a'):
        return
    cmds = [d for t, i, f, data, d in fr if i == BASE and d]
    fbs = [d for t, i, f, data, d in fr if i == BASE + 1 and d]
    tx, rx, _ = read_ctl_log(log)
    n = (len(tx[0]) - 2) // 3 if tx else 0  # tx: cycle frame_id flags[n] vel[n] posref[n]
    check(len(tx) > 1500, f'a: controller sent {len(tx)} commands in 2 s (> 1500)')
    # every logged command is on the bus once (last one is the braking request, not logged)
    bus_by_id = {}
    for d in cmds:
        bus_by_id.setdefault(int(d['FrameId']), []).append(d)
    missing = [r for r in tx if int(r[1]) & 0xFFFF not in bus_by_id]
    check(not missing, f'a: all {len(tx)} logged commands found on the bus (missing {len(missing)})')
    maxerr = maxpr = 0.0
    badflags = badn = 0
    flagset = set()
    for r in tx:
        for d in bus_by_id.get(int(r[1]) & 0xFFFF, []):
            badn += int(d['NJoints']) != n
            for j in range(n):
                maxerr = max(maxerr, abs(d[f'Vel{j}'] - r[2 + n + j]))
                maxpr = max(maxpr, abs(d[f'PosRef{j}'] - r[2 + 2 * n + j]))
                badflags += int(d[f'Flags{j}']) != int(r[2 + j])
                flagset.add(int(r[2 + j]))
            badflags += sum(int(d[f'Flags{j}']) != 0 for j in range(n, 8))  # unused joints: no flags
    check(maxerr <= 0.5e-6 + 1e-12, f'a: cantools-decoded command velocities = sent values (max err {maxerr:.2e} <= 5e-7)')
    # position_ref = last feedback position + v dt (joint 1, 2 near 3.14 rad): 1e-5 rad wire step
    check(maxpr <= 0.5e-5 + 1e-9 and max(abs(r[2 + 2 * n + j]) for r in tx for j in range(n)) > 1,
          f'a: cantools-decoded command PosRef = sent values (max err {maxpr:.2e} <= 5e-6)')
    check(badflags == 0 and badn == 0,
          f'a: cantools-decoded command Flags0..7 and NJoints = sent ({badflags} flag and {badn} NJoints mismatches;'
          f' flag values sent {sorted(flagset)})')
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
    check(asx.get('log_lost') == '0', f'a: emulator log complete (log_lost={asx.get("log_lost")})')
    st, ft = state_fault_vs_sent(fr, arm_log, 'a')
    # the VEL_SAT burst of joint 0 (mca-can-ctl --sat-*) put fault frames on the bus: flag set, then cleared
    sat = [r for r in ft if r[4] & 4]
    check(len(sat) >= 2 and any(not any(r[4:]) for r in ft if r[0] > sat[-1][0]),
          f'a: {len(sat)} fault frames with VEL_SAT on joint 0, then one with the flags cleared')


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


def case_c(db, dump, wd, dec, arm_stats, arm_log):
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
    # decel limit per cycle + one feedback velocity step (1e-4 rad/s), + 1e-9 for the float difference of two
    # quantized values (seen: 0.0051 > 0.0051 by the last bit)
    lim = dec * 1e-3 + 1e-4 + 1e-9
    check(worst <= lim and not grew, f'c: velocity ramp max |dv| {worst:.4f} rad/s per cycle <= {lim:.4f}, |v| never grows')
    if first_fault is not None:
        d = fbs[first_fault]
        check(int(d['FaultCode']) == 1 and all(abs(d[f'Vel{j}']) < 1e-9 for j in range(n)),
              f'c: FAULT frame: fault code {int(d["FaultCode"])} (WATCHDOG = 1), all velocities 0')
    sts = [int(x[4]['State']) for x in fr[idx_last_cmd + 1:] if x[1] == BASE + 2 and x[4]]
    check(3 in sts and 4 in sts and sts.index(3) < sts.index(4), f'c: state frames show BRAKING then FAULT {sts[:6]}...')
    flt = [x[4] for x in fr[idx_last_cmd + 1:] if x[1] == BASE + 3 and x[4]]
    check(any(int(d['FaultCode']) == 1 for d in flt), 'c: fault frame with fault code WATCHDOG')
    st, ft = state_fault_vs_sent(fr, arm_log, 'c')
    wdf = [r for r in ft if r[3] == 1]
    check(len(wdf) >= 3, f'c: {len(wdf)} fault frames with WATCHDOG (on the change, then with every heartbeat)')


def case_d(db, dump, ctl_stats, arm_stats):
    fr = decode_all(db, read_candump(dump))
    if not complete(fr, arm_stats, ctl_stats, 'd'):
        return
    cs, asx = stats(ctl_stats), stats(arm_stats)
    # arm side: command stream; everything else in the block is unknown to it
    acc, badlen, badctr = seq_sim(fr, BASE, 64)
    fr = [x for x in fr if not x[1] & CAN_ERR_FLAG]  # error frames (case e) are not data frames
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


def case_e(db, dump, ctl_stats, log):
    """Error frames injected in run d: a bus-off (while the emulator was stopped, so no feedback clears it at
    once) and a controller problem. Timing in controller cycles (cycle k reads, then writes frame id k + 1),
    against the read contract of mca/arm.h: a read with new feedback returns it and leaves an error pending;
    the next read without new feedback returns MCA_EIO; while bus-off every read without feedback does."""
    fr = decode_all(db, read_candump(dump))
    cs = stats(ctl_stats)
    errs = [(k, x[1]) for k, x in enumerate(fr) if x[1] & CAN_ERR_FLAG]
    check([i for k, i in errs] == [0x20000040, 0x20000004],
          f'e: the two injected error frames are on the capture {[hex(i) for k, i in errs]} (bus-off, controller)')
    check(int(cs['bus_errors']) == 2, f'e: 2 injected error frames counted by the controller (bus_errors={cs["bus_errors"]})')
    check(int(cs['bus_off_events']) == 1 and int(cs['bus_off']) == 0 and int(cs['link_fault']) == 0,
          f'e: one bus-off event, cleared at the end (bus_off_events={cs["bus_off_events"]} bus_off={cs["bus_off"]}'
          f' link_fault={cs["link_fault"]})')
    if len(errs) != 2:
        return
    tx, rx, er = read_ctl_log(log)
    erc = {int(r[0]): [int(x) for x in r[1:]] for r in er}  # cycle -> eio bus_off bus_off_events bus_errors link_fault
    fresh = {int(r[0]) for r in rx}  # cycles whose read returned new feedback
    eio_cycles = {c for c, r in erc.items() if r[0]}
    check(len(eio_cycles) == int(cs['eio']), f'e: {len(eio_cycles)} EIO cycles logged = eio {cs["eio"]}')
    counted = []
    for n_err, (k, ident) in enumerate(errs, 1):
        # newest genuine command before the error frame (replays carry older frame ids)
        ids = [int(x[4]['FrameId']) for x in fr[:k] if x[1] == BASE and x[4]]
        F = max(ids) if ids else -1
        c = min((c for c, r in erc.items() if r[3] >= n_err), default=None)
        counted.append(c)
        # the first read after the frame: cycle F (it arrived after command F), or F + 1 if it arrived between
        # that cycle's read and its write. The capture's order is the order in which the kernel delivered the
        # frames to the sockets; on a starved guest that delivery (softirq, then ksoftirqd, below the FIFO
        # programs) can lag the writes by a cycle or two (seen: counted in F + 2 under host load). Up to
        # DELIVERY_LAG reads later passes; an error frame held until later feedback (the bug this catches:
        # the emulator is stopped for ~50 cycles after the bus-off frame) does not.
        check(c is not None and F <= c <= F + 1 + DELIVERY_LAG,
              f'e: error frame {hex(ident)} after command {F} on the bus: counted by the read of cycle {c} '
              f'(the first read after it: {F} or {F + 1}, up to {DELIVERY_LAG} more when delivery lags)')
    if None in counted:
        return
    cb = counted[0]
    check(erc[cb][2] == 1 and erc[cb][1] == 1 and erc[cb][4] == 5,
          f'e: bus_off went 0 -> 1 in cycle {cb} (bus_off={erc[cb][1]}, bus_off_events={erc[cb][2]}, link_fault='
          f'{erc[cb][4]}: 5 = BUS)')
    kb = errs[0][0]
    g = next((int(x[4]['FrameId']) for x in fr[kb + 1:] if x[1] == BASE + 1 and x[4]), None)
    r = next((int(x[0]) for x in rx if int(x[0]) > cb and (int(x[1]) & 0xFFFF) >= (g if g is not None else 1 << 17)), None)
    if r is None:
        check(False, f'e: no feedback read after the bus-off frame (first on the bus after it: {g})')
        return
    held = [c for c in range(cb, r) if c in erc and erc[c][1] == 1 and erc[c][4] == 5]
    check(len(held) == r - cb and not (fresh & set(range(cb + 1, r))),
          f'e: bus_off = 1 and link_fault = BUS after every read of cycles {cb}..{r - 1} ({len(held)}/{r - cb}), no '
          f'feedback in between (emulator stopped)')
    after = [c for c, x in erc.items() if c >= r and x[1]]
    check(erc.get(r, [0, 0])[1] == 0 and not after,
          f'e: bus_off cleared in cycle {r}, the read of the first feedback after the bus-off frame (frame {g}); stays 0')
    # expected MCA_EIO cycles from the contract, cycle by cycle
    pending, want = False, set()
    for c in range(min(int(x[0]) for x in tx), max(int(x[0]) for x in tx) + 1):
        if c in counted:
            pending = True
        bus_off = erc.get(c, [0, 0])[1]
        if c not in fresh and (pending or bus_off):
            want.add(c)
            pending = False
    first = [min((c for c in want if c >= cc), default=None) for cc in counted]
    check(eio_cycles == want and len(want) > 0,
          f'e: MCA_EIO in exactly the {len(want)} cycles the read contract gives: first for the bus-off frame in '
          f'cycle {first[0]}, then every read while bus-off (to {r - 1}); for the controller-problem frame (counted '
          f'in {counted[1]}) in cycle {first[1]}, the first read without new feedback after it '
          f'(extra {sorted(eio_cycles - want)[:5]}, missing {sorted(want - eio_cycles)[:5]})')


def case_g(db, out):
    """Round trip figures from mca-can-ctl --mode lockstep."""
    import re
    txt = open(out).read()
    m = re.search(r'rtt_us p50=([0-9.]+) p99=([0-9.]+) max=([0-9.]+) n=(\d+) min=(-?[0-9.]+) '
                  r'kernel_stamped=(\d+) user_stamped=(\d+)', txt)
    if not m:
        check(False, f'g: no rtt_us line in {out}')
        return
    n, mn, ks, us = int(m.group(4)), float(m.group(5)), int(m.group(6)), int(m.group(7))
    check(ks == n and us == 0, f'g: all {n} measured feedback frames carried a kernel receive stamp '
                               f'(kernel {ks}, user-space fallback {us})')
    check(mn > 0, f'g: every round trip > 0 (min {mn} us)')


def main():
    db = cantools.database.load_file(sys.argv[1], strict=True)
    case = sys.argv[2]
    {'a': case_a, 'b': case_b, 'c': case_c, 'd': case_d, 'e': case_e, 'g': case_g}[case](
        db, *[int(a) if a.isdigit() else (float(a) if a.replace('.', '', 1).isdigit() else a) for a in sys.argv[3:]])
    return 1 if FAILS else 0


if __name__ == '__main__':
    sys.exit(main())
