#!/bin/bash
# SPDX-License-Identifier: MIT
# The real-time benchmark rows (docs/benchmarks.md: wake-up jitter, DDS latency, publishing's cost), one run each, with the other CPU quiet and then loaded (a busy loop pinned there):
#   1. mcad's wake-up jitter (loop pinned to CPU 1, SCHED_FIFO 80, DDS on as shipped, mca-monitor subscribed)
#      against cyclictest on the same CPU, same priority, same length, at the same time (a quarter period apart);
#   2. DDS latency tick stamp -> mca-monitor receipt (the run of 1), with ddsperf's ping/pong round trip on the
#      same loopback config beside it (one-way = RTT / 2);
#   3. mcad's whole tick with DDS publishing vs without (mcad --dds-ab 500: publishing only in every other
#      block of 500 ticks), one run as shipped (publish_divisor 10, 100 Hz) and one publishing every tick.
# Rows 1 and 2 run MCA_BENCH_ROUNDS times (default 3) per mode: this VM's host disturbs the guest at a fixed
# phase for tens of seconds (late wake-ups every 10 ms, wherever mcad's or cyclictest's wake-up falls), so
# one 20-s run says which of the two it hit; each round's ratio is printed, and the ratio of the rounds'
# histograms pooled (mcad --histogram and cyclictest -h, read by one reader).
# usage: bench/rt/jitter_dds.sh BUILD_DIR [SECONDS (20)] [OUT_DIR (out/bench-jitter-dds)] [MODES ("quiet busy")]
# Needs root (SCHED_FIFO, mlockall) and 2 CPUs; prints one table (markdown) on stdout, raw outputs in OUT_DIR.
set -u
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
B=$(cd "${1:?usage: jitter_dds.sh BUILD_DIR [SECONDS] [OUT_DIR] [MODES]}" && pwd) || exit 1
DUR=${2:-20}
OUT=${3:-$ROOT/out/bench-jitter-dds}
MODES=${4:-quiet busy}
ROUNDS=${MCA_BENCH_ROUNDS:-3}
# mca-monitor's priority: above the DDS publisher's (10, on the same CPU), so its receive thread takes a
# sample when it arrives rather than when the publisher has written the tick's other topics (0: SCHED_OTHER)
MON_PRIO=${MCA_BENCH_MONITOR_PRIORITY:-20}
MCAD=$B/daemon/mcad
MON=$B/tools/mca-monitor/mca-monitor
XML=$ROOT/config/dds/loopback.xml
DOM=${MCA_BENCH_DOMAIN:-96}
# The bench's own helpers (mca-monitor, ddsperf) run where a controller's other work would: off the loop's
# CPU (MCA_BENCH_AUX_CPUS, default 0; "any" lets them run anywhere, as before 2026-12-05)
AUX_CPUS=${MCA_BENCH_AUX_CPUS:-0}
aux() {
    if [ "$AUX_CPUS" = any ]; then "$@"; else taskset -c "$AUX_CPUS" "$@"; fi
}
mkdir -p "$OUT"
export CYCLONEDDS_URI=file://$XML

cell() { # cell FILE DIVISOR: cross circles on the sim arms, loop on CPU 1, the DDS publisher SCHED_FIFO 10 off
    #   CPU 1 (docs/daemon.md "CPUs": the isolated-core set-up), our domain
    sed -e "s#\.\./#$ROOT/config/#" -e "s#domain: .*#domain: $DOM#" \
        -e "s#publish_divisor: .*#publish_divisor: $2\n  priority: 10#" \
        -e "s#cpu: .*#cpu: 1#" "$ROOT/config/cells/cross_circles_sim.yaml" >"$1"
}

for mode in $MODES; do
    R=$OUT/$mode
    mkdir -p "$R"
    busy=
    if [ "$mode" = busy ]; then
        taskset -c 0 sh -c 'while :; do :; done' &
        busy=$!
    fi
    {
        echo "mode $mode: $(date -u +%FT%TZ), git $(git -C "$ROOT" rev-parse --short HEAD), aux CPUs $AUX_CPUS, $(uptime)"
    } >"$R/machine.txt"
    # 1 + 2: mcad as shipped (100 Hz on DDS), mca-monitor subscribed, ddsperf ping/pong beside it; cyclictest
    # at the same time on the loop's CPU at its priority, a quarter period before mcad's grid (mcad wakes at
    # whole ms + 500 us of CLOCK_MONOTONIC, cyclictest --secaligned at whole seconds + 250 us: both clear of
    # the kernel's tick on whole ms): both see the same stalls of this VM, and neither wakes while the other
    # runs. cyclictest starts first and ends last, and prints every wake-up (-v); the table takes those due
    # in the span of mcad's --histogram (its first to its last wake-up): the same milliseconds for both.
    cell "$R/cell.yaml" 10
    for round in $(seq "$ROUNDS"); do
        Q=$R/round$round
        mkdir -p "$Q"
        aux "$MON" --priority "$MON_PRIO" --domain $DOM --config "$XML" --duration $((DUR + 14)) >/dev/null 2>"$Q/monitor.err" &
        mon=$!
        aux ddsperf -i $((DOM + 1)) -D $((DUR + 12)) pong >"$Q/pong.txt" 2>&1 &
        pong=$!
        aux ddsperf -i $((DOM + 1)) -D $((DUR + 10)) ping 100Hz >"$Q/ping.txt" 2>&1 &
        ping=$!
        sleep 2
        # launched between whole seconds, so that its first wake-up is due at the next whole second + 250 us
        python3 -c 'import time; t = time.clock_gettime(time.CLOCK_MONOTONIC) % 1; time.sleep((1.1 - t) % 1)'
        python3 -c 'import time; print(time.clock_gettime_ns(time.CLOCK_MONOTONIC))' >"$Q/cyclictest_launch_ns.txt"
        cyclictest -m -p 80 -a 1 -i 1000 --secaligned=250 -l $(((DUR + 7) * 1000)) -q -v >"$Q/cyclictest_v.txt" 2>&1 &
        cyc=$!
        sleep 1
        "$MCAD" --stop-after $((DUR + 3)) --histogram "$Q/mcad_hist.txt" "$R/cell.yaml" >/dev/null 2>"$Q/mcad.err"
        wait $cyc
        kill -INT $mon 2>/dev/null
        wait $mon $ping $pong 2>/dev/null
    done
    # 3: publishing on/off in one run, as shipped (every 10th tick, 100 Hz) and every tick (1 kHz)
    # 3 as shipped in ROUNDS runs (pooled: the rounds' means of on and of off), every tick in one
    for div in 10 1; do
        cell "$R/cell_ab$div.yaml" $div
        n=$ROUNDS
        [ "$div" = 1 ] && n=1
        for round in $(seq "$n"); do
            aux "$MON" --priority "$MON_PRIO" --domain $DOM --config "$XML" --duration $((DUR + 6)) >/dev/null 2>"$R/monitor_ab${div}_$round.err" &
            mon=$!
            sleep 1
            "$MCAD" --dds-ab 500 --stop-after "$DUR" "$R/cell_ab$div.yaml" >/dev/null 2>"$R/mcad_ab${div}_$round.err"
            kill -INT $mon 2>/dev/null
            wait $mon 2>/dev/null
        done
    done
    [ -n "$busy" ] && kill "$busy" && wait "$busy" 2>/dev/null
done

MON_PRIO=$MON_PRIO python3 - "$OUT" "$ROUNDS" $MODES <<'PYEOF'
import os, re, sys
out, rounds, modes = sys.argv[1], int(sys.argv[2]), sys.argv[3:]
def f(path):
    try:
        return open(path, errors="replace").read()
    except OSError:
        return ""
def hist(txt):
    """cyclictest -h output or mcad --histogram: {lower bin edge us: count}, overflows, max us"""
    h, over = {}, 0
    for line in txt.splitlines():
        m = re.match(r"^(\d+)\s+(\d+)\s*$", line)
        if m:
            h[int(m.group(1))] = h.get(int(m.group(1)), 0) + int(m.group(2))
        m = re.match(r"# Histogram Overflows:\s*(\d+)", line)
        if m:
            over = int(m.group(1))
    mx = re.search(r"# Max Latencies:\s*(\d+)", txt)
    return h, over, int(mx.group(1)) if mx else 0
def cyc_in_span(Q):
    """cyclictest -v's wake-ups due within mcad's span, as a histogram; wake-up i was due at the whole
    second after the launch + 250 us + i ms"""
    span = re.search(r"due from (\d+) to (\d+) ns", f(Q + "/mcad_hist.txt"))
    launch = f(Q + "/cyclictest_launch_ns.txt").strip()
    if not span or not launch:
        return {}, 0, 0
    first, last = int(span.group(1)), int(span.group(2))
    t0 = (int(launch) // 10**9 + 1) * 10**9 + 250000
    h, n_all, lo, hi = {}, 0, None, None
    for line in f(Q + "/cyclictest_v.txt").splitlines():
        m = re.match(r"^\s*0:\s*(\d+):\s*(\d+)\s*$", line)
        if not m:
            continue
        due = t0 + int(m.group(1)) * 10**6
        lo, hi = due if lo is None else lo, due
        if first - 10**6 < due <= last:
            h[int(m.group(2))] = h.get(int(m.group(2)), 0) + 1
            n_all += 1
    if lo is None or lo > first - 10**6 or hi < last:
        print(f"<!-- {Q}: cyclictest's wake-ups ({lo}..{hi}) do not cover mcad's span ({first}..{last}) -->")
        return {}, 0, 0
    return h, 0, max(h) if h else 0
def pooled(hs):
    h, over, mx = {}, 0, 0
    for hh, o, m in hs:
        for k, v in hh.items():
            h[k] = h.get(k, 0) + v
        over, mx = over + o, max(mx, m)
    return h, over, mx
def stats(hs):
    """p50, p99, p99.9 (lower bin edges, overflows count as the largest), max, n"""
    h, over, mx = hs
    n = sum(h.values()) + over
    def pct(p):
        k, acc = int(p * n), 0
        for us in sorted(h):
            acc += h[us]
            if acc > k:
                return us
        return float("inf")
    return pct(0.5), pct(0.99), pct(0.999), mx, n
def row1(label, mode, m, c, note):
    print(f"| 1. wake-up jitter{label} | {mode} | mcad: p50 {m[0]} / p99 {m[1]} / p99.9 {m[2]} / max {m[3]} us | "
          f"cyclictest -a 1 -p 80: p50 {c[0]} / p99 {c[1]} / p99.9 {c[2]} / max {c[3]} us | "
          f"p99 {m[1] / c[1]:.2f}, p99.9 {m[2] / c[2]:.2f} | {note} |")
print("| row | other CPU | measured | against | ratio | notes |")
print("|---|---|---|---|---|---|")
for mode in modes:
    R = f"{out}/{mode}"
    all_m, all_c = [], []
    for r in range(1, rounds + 1):
        Q = f"{R}/round{r}"
        me = f(Q + "/mcad.err")
        tk = re.search(r"ticks (\d+), overruns (\d+) \(skipped periods (\d+)\)", me)
        hm, hc = hist(f(Q + "/mcad_hist.txt")), cyc_in_span(Q)
        if hm[0] and hc[0]:
            all_m.append(hm)
            all_c.append(hc)
            m, c = stats(hm), stats(hc)
            row1(f", round {r} of {rounds} (CPU 1, FIFO 80, DDS 100 Hz + monitor)", mode, m, c,
                 f"{m[4]} vs {c[4]} wake-ups; mcad overruns {tk.group(2) if tk else '?'}")
        else:
            print(f"| 1. wake-up jitter, round {r} | {mode} | (no histogram: see {Q}/mcad.err, cyclictest.txt) | | | |")
        lat = re.search(r"p50 ([\d.]+) us.*?p99 ([\d.]+) us.*?max ([\d.]+) us", f(Q + "/monitor.err").replace("\n", " "))
        # ddsperf ping lines: "... rtt mean XXus min XXus 50% XXus 90% XXus 99% XXus max XXus"
        rtts = re.findall(r"50%\s+([\d.]+)us\s+90%\s+([\d.]+)us\s+99%\s+([\d.]+)us", f(Q + "/ping.txt"))
        dp = "ddsperf: no figures (see ping.txt)"
        if rtts:
            p50 = sorted(float(x[0]) for x in rtts)[len(rtts) // 2]
            p99 = sorted(float(x[2]) for x in rtts)[len(rtts) // 2]
            dp = f"ddsperf ping/pong 100 Hz: RTT p50 {p50:.0f} / p99 {p99:.0f} us (median of {len(rtts)} 1-s lines), one-way ~{p50 / 2:.0f} / {p99 / 2:.0f} us"
        if lat:
            print(f"| 2. DDS latency tick -> mca-monitor (--priority {os.environ.get('MON_PRIO', '?')}), round {r} | {mode} | p50 {float(lat.group(1)):.0f} / p99 {float(lat.group(2)):.0f} / "
                  f"max {float(lat.group(3)):.0f} us | {dp} | - | |")
        else:
            print(f"| 2. DDS latency tick -> mca-monitor, round {r} | {mode} | (no latency line: see {Q}/monitor.err) | {dp} | - | |")
    if all_m:
        m, c = stats(pooled(all_m)), stats(pooled(all_c))
        row1(f", {len(all_m)} rounds pooled", mode, m, c, f"{m[4]} vs {c[4]} wake-ups")
    for div, what, n in (("10", "as shipped (100 Hz)", rounds), ("1", "every tick (1 kHz)", 1)):
        on_sum = off_sum = son_sum = soff_sum = 0.0
        on_n = off_n = son_n = soff_n = 0
        for r in range(1, n + 1):
            ab = re.search(r"off p50 ([\d.]+) us, p99 ([\d.]+) us, mean ([\d.]+) us \((\d+) ticks\); on p50 ([\d.]+) us, p99 ([\d.]+) us, "
                           r"mean ([\d.]+) us \((\d+) ticks\); ratio on/off p50 ([\d.]+), p99 ([\d.]+), mean ([\d.]+)", f(f"{R}/mcad_ab{div}_{r}.err"))
            # the same ticks without those of half a period or more (this machine's stalls)
            sab = re.search(r"shorter than half a period: off mean ([\d.]+) us \((\d+) ticks\), on mean ([\d.]+) us \((\d+) ticks\); "
                            r"ratio on/off mean ([\d.]+)", f(f"{R}/mcad_ab{div}_{r}.err"))
            label = f", round {r} of {n}" if n > 1 else ""
            if ab:
                g = ab.groups()
                off_sum, off_n = off_sum + float(g[2]) * int(g[3]), off_n + int(g[3])
                on_sum, on_n = on_sum + float(g[6]) * int(g[7]), on_n + int(g[7])
                stall_free = "?"
                if sab:
                    h = sab.groups()
                    soff_sum, soff_n = soff_sum + float(h[0]) * int(h[1]), soff_n + int(h[1])
                    son_sum, son_n = son_sum + float(h[2]) * int(h[3]), son_n + int(h[3])
                    stall_free = f"{h[4]} ({int(g[3]) + int(g[7]) - int(h[1]) - int(h[3])} stalled ticks left out)"
                print(f"| 3. whole tick, DDS publishing {what} vs none (mcad --dds-ab 500){label} | {mode} | on p50 {g[4]} / p99 {g[5]} / mean {g[6]} us | "
                      f"off p50 {g[0]} / p99 {g[1]} / mean {g[2]} us | mean {g[10]}, p50 {g[8]}, p99 {g[9]}; stall-free mean {stall_free} | "
                      f"{g[7]} vs {g[3]} ticks, 1 us bins: read the means |")
            else:
                print(f"| 3. whole tick, DDS publishing {what}{label} | {mode} | (no dds-ab line: see mcad_ab{div}_{r}.err) | | | |")
        if n > 1 and on_n and off_n and son_n and soff_n:
            print(f"| 3. whole tick, DDS publishing {what} vs none, {n} rounds pooled | {mode} | on mean {on_sum / on_n:.2f} us, "
                  f"stall-free {son_sum / son_n:.2f} us | off mean {off_sum / off_n:.2f} us, stall-free {soff_sum / soff_n:.2f} us | "
                  f"mean {on_sum / on_n / (off_sum / off_n):.3f}, stall-free {son_sum / son_n / (soff_sum / soff_n):.3f} | "
                  f"{on_n} vs {off_n} ticks; {on_n + off_n - son_n - soff_n} of half a period or more left out of the stall-free means |")
PYEOF
