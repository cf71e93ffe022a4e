#!/bin/bash
# SPDX-License-Identifier: MIT
# Issue 13's benchmark rows, one run each, with the other CPU quiet and then loaded (a busy loop pinned there):
#   1. mcad's wake-up jitter (loop pinned to CPU 1, SCHED_FIFO 80, DDS on as shipped, mca-monitor subscribed)
#      against cyclictest on the same CPU, same priority, same length, at the same time (a quarter period apart);
#   2. DDS latency tick stamp -> mca-monitor receipt (the run of 1), with ddsperf's ping/pong round trip on the
#      same loopback config beside it (one-way = RTT / 2);
#   3. mcad's whole tick with DDS publishing vs without (mcad --dds-ab 500: publishing only in every other
#      block of 500 ticks), one run as shipped (publish_divisor 10, 100 Hz) and one publishing every tick.
# usage: bench/rt/issue13.sh BUILD_DIR [SECONDS (20)] [OUT_DIR (out/bench-issue13)] [MODES ("quiet busy")]
# Needs root (SCHED_FIFO, mlockall) and 2 CPUs; prints one table (markdown) on stdout, raw outputs in OUT_DIR.
set -u
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
B=$(cd "${1:?usage: issue13.sh BUILD_DIR [SECONDS] [OUT_DIR] [MODES]}" && pwd) || exit 1
DUR=${2:-20}
OUT=${3:-$ROOT/out/bench-issue13}
MODES=${4:-quiet busy}
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
    # runs
    cell "$R/cell.yaml" 10
    aux "$MON" --domain $DOM --config "$XML" --duration $((DUR + 12)) >/dev/null 2>"$R/monitor.err" &
    mon=$!
    aux ddsperf -i $((DOM + 1)) -D $((DUR + 10)) pong >"$R/pong.txt" 2>&1 &
    pong=$!
    aux ddsperf -i $((DOM + 1)) -D $((DUR + 8)) ping 100Hz >"$R/ping.txt" 2>&1 &
    ping=$!
    sleep 2
    "$MCAD" --stop-after $((DUR + 3)) "$R/cell.yaml" >/dev/null 2>"$R/mcad.err" &
    mcad=$!
    for _ in $(seq 100); do
        grep -q "mcad: running" "$R/mcad.err" && break
        sleep 0.1
    done
    cyclictest -m -p 80 -a 1 -i 1000 --secaligned=250 -l $((DUR * 1000)) -q -h 200000 >"$R/cyclictest.txt" 2>&1
    wait $mcad
    kill -INT $mon 2>/dev/null
    wait $mon $ping $pong 2>/dev/null
    # 3: publishing on/off in one run, as shipped (every 10th tick, 100 Hz) and every tick (1 kHz)
    for div in 10 1; do
        cell "$R/cell_ab$div.yaml" $div
        aux "$MON" --domain $DOM --config "$XML" --duration $((DUR + 6)) >/dev/null 2>"$R/monitor_ab$div.err" &
        mon=$!
        sleep 1
        "$MCAD" --dds-ab 500 --stop-after "$DUR" "$R/cell_ab$div.yaml" >/dev/null 2>"$R/mcad_ab$div.err"
        kill -INT $mon 2>/dev/null
        wait $mon 2>/dev/null
    done
    [ -n "$busy" ] && kill "$busy" && wait "$busy" 2>/dev/null
done

python3 - "$OUT" $MODES <<'PYEOF'
import re, sys
out, modes = sys.argv[1], sys.argv[2:]
def f(path):
    try:
        return open(path, errors="replace").read()
    except OSError:
        return ""
def cyc(txt):
    hist, over = {}, 0
    for line in txt.splitlines():
        m = re.match(r"^(\d+)\s+(\d+)\s*$", line)
        if m:
            hist[int(m.group(1))] = int(m.group(2))
        m = re.match(r"# Histogram Overflows:\s*(\d+)", line)
        if m:
            over = int(m.group(1))
    n = sum(hist.values()) + over
    def pct(p):
        k, acc = int(p * n), 0
        for us in sorted(hist):
            acc += hist[us]
            if acc > k:
                return us
        return float("nan")
    mx = re.search(r"# Max Latencies:\s*(\d+)", txt)
    return pct(0.5), pct(0.99), pct(0.999), int(mx.group(1)) if mx else float("nan"), n
print("| row | other CPU | measured | against | ratio | notes |")
print("|---|---|---|---|---|---|")
for mode in modes:
    R = f"{out}/{mode}"
    m = f(R + "/mcad.err")
    j = re.search(r"jitter p50 ([\d.]+) us, p99 ([\d.]+) us, p99.9 ([\d.]+) us, max ([\d.]+) us", m)
    tk = re.search(r"ticks (\d+), overruns (\d+) \(skipped periods (\d+)\)", m)
    c = cyc(f(R + "/cyclictest.txt"))
    if j:
        mj = [float(x) for x in j.groups()]
        print(f"| 1. wake-up jitter, mcad (CPU 1, FIFO 80, DDS 100 Hz + monitor) | {mode} | p50 {mj[0]:.0f} / p99 {mj[1]:.0f} / "
              f"p99.9 {mj[2]:.0f} / max {mj[3]:.0f} us | cyclictest -a 1 -p 80: p50 {c[0]} / p99 {c[1]} / p99.9 {c[2]} / max {c[3]} us | "
              f"p99 {mj[1] / c[1]:.2f}, p99.9 {mj[2] / c[2]:.2f} | mcad {tk.group(1) if tk else '?'} ticks, overruns {tk.group(2) if tk else '?'}; cyclictest {c[4]} wake-ups |")
    lat = re.search(r"p50 ([\d.]+) us.*?p99 ([\d.]+) us.*?max ([\d.]+) us", f(R + "/monitor.err").replace("\n", " "))
    ping = f(R + "/ping.txt")
    # ddsperf ping lines: "... rtt mean XXus min XXus 50% XXus 90% XXus 99% XXus max XXus"
    rtts = re.findall(r"50%\s+([\d.]+)us\s+90%\s+([\d.]+)us\s+99%\s+([\d.]+)us", ping)
    dp = ""
    if rtts:
        p50 = sorted(float(r[0]) for r in rtts)[len(rtts) // 2]
        p99 = sorted(float(r[2]) for r in rtts)[len(rtts) // 2]
        dp = f"ddsperf ping/pong 100 Hz: RTT p50 {p50:.0f} / p99 {p99:.0f} us (median of {len(rtts)} 1-s lines), one-way ~{p50 / 2:.0f} / {p99 / 2:.0f} us"
    mon_line = " ".join(l for l in f(R + "/monitor.err").splitlines() if "latency" in l)
    if lat:
        print(f"| 2. DDS latency tick -> mca-monitor | {mode} | p50 {float(lat.group(1)):.0f} / p99 {float(lat.group(2)):.0f} / max {float(lat.group(3)):.0f} us | "
              f"{dp or 'ddsperf: no figures (see ping.txt)'} | - | {mon_line[:160]} |")
    else:
        print(f"| 2. DDS latency tick -> mca-monitor | {mode} | (no latency line: see monitor.err) | {dp} | - | |")
    for div, what in (("10", "as shipped (100 Hz)"), ("1", "every tick (1 kHz)")):
        ab = re.search(r"off p50 ([\d.]+) us, p99 ([\d.]+) us, mean ([\d.]+) us \((\d+) ticks\); on p50 ([\d.]+) us, p99 ([\d.]+) us, "
                       r"mean ([\d.]+) us \((\d+) ticks\); ratio on/off p50 ([\d.]+), p99 ([\d.]+), mean ([\d.]+)", f(f"{R}/mcad_ab{div}.err"))
        if ab:
            g = ab.groups()
            print(f"| 3. whole tick, DDS publishing {what} vs none (mcad --dds-ab 500) | {mode} | on p50 {g[4]} / p99 {g[5]} / mean {g[6]} us | "
                  f"off p50 {g[0]} / p99 {g[1]} / mean {g[2]} us | mean {g[10]}, p50 {g[8]}, p99 {g[9]} | {g[7]} vs {g[3]} ticks, 1 us bins: read the mean |")
        else:
            print(f"| 3. whole tick, DDS publishing {what} vs none | {mode} | (no dds-ab line: see mcad_ab{div}.err) | | | |")
PYEOF
