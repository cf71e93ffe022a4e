#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""bench.harness: bench_tick and bench/report.py on a short run (see CMakeLists.txt). Exit 0 when all pass."""
import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile

import numpy as np

FAILS = []


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what)
    if not cond:
        FAILS.append(what)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--bench-tick", required=True)
    ap.add_argument("--source", required=True)
    a = ap.parse_args()
    sys.path.insert(0, os.path.join(a.source, "bench"))
    import report  # noqa: PLC0415

    out = tempfile.mkdtemp(prefix="mca-bench-test-")
    raw = os.path.join(out, "raw")
    os.makedirs(raw)

    # 1. task mode: 400 ticks of task 1, QP blocks of 5 every 100 ticks
    qd = os.path.join(raw, "qp_cross_circles")
    tj = os.path.join(raw, "tick_cross_circles.json")
    r = subprocess.run([a.bench_tick, "task", "--scenario", os.path.join(a.source, "config/scenarios/cross_circles.yaml"),
                        "--ticks", "400", "--qp-dir", qd, "--qp-every", "100", "--qp-block", "5", "--out", tj],
                       capture_output=True, text=True, timeout=60)
    check(r.returncode == 0, f"bench_tick task exits 0 ({r.stderr.strip()[:200]})")
    d = json.load(open(tj))
    run = d["run"]
    check(run["ticks"] == 400 and run["faults"] == 0, f"400 ticks, no fault (got {run['ticks']}, {run['faults']})")
    check([run["n_vars"], run["n_eq"], run["n_ineq"]] == [16, 6, 18],
          f"dual PA10+ QP is 16 vars, 6 eq, 18 ineq (normal form, 9 links per arm): {run['n_vars']}, "
          f"{run['n_eq']}, {run['n_ineq']}")
    check(run["step_mismatch"] == 0, "the out-of-tick PDNN solve from the tick's own start state takes the tick's "
          f"steps on every tick (mismatches {run['step_mismatch']})")
    check(run["steps"]["p50"] + run["exact_solves"]["p50"] >= 1,
          "the solver's work per tick recorded: network steps p50 %d, the polish's exact solves p50 %d" %
          (run["steps"]["p50"], run["exact_solves"]["p50"]))
    for k in ("tick", "fk", "distances", "assembly", "pdnn"):
        s = run[f"{k}_ns"]
        check(0 < s["min"] <= s["p50"] <= s["p99"] <= s["max"], f"{k}: 0 < min <= p50 <= p99 <= max")
    rows = open(os.path.join(qd, "pdnn.csv")).read().splitlines()
    check(rows[0].startswith("file,block,idx,warm_ns,steps,cold_ns"), "pdnn.csv header")
    check(len(rows) - 1 == d["qp_dumped"] and d["qp_dumped"] >= 10, f"{d['qp_dumped']} QPs dumped, one row each")
    firsts = [x for x in rows[1:] if x.split(",")[2] == "0"]
    check(all(int(x.split(",")[5]) > 0 for x in firsts), "every block's first QP has a cold PDNN time")

    # 1b. pair mode: task 1 alone and in its whole cell, alternating; the cell's body and self rows counted
    pj = os.path.join(raw, "tick_cell_pairs.json")
    r = subprocess.run([a.bench_tick, "pair", "--scenario", os.path.join(a.source, "config/scenarios/cross_circles.yaml"),
                        "--scenario-b", os.path.join(a.source, "config/scenarios/cross_circles_cell.yaml"),
                        "--pairs", "2", "--out", pj], capture_output=True, text=True, timeout=120)
    check(r.returncode == 0, f"bench_tick pair exits 0 ({r.stderr.strip()[:200]})")
    pr = json.load(open(pj))["runs"]
    check([x["which"] for x in pr] == ["a", "b", "a", "b"] and [x["pair"] for x in pr] == [0, 0, 1, 1],
          "pair: runs alternate a b a b")
    pa, pb = pr[0]["run"], pr[1]["run"]
    check(pa["name"] == "cross_circles" and pb["name"] == "cross_circles_cell" and pa["ticks"] == pb["ticks"] == 10000
          and pa["faults"] == pb["faults"] == 0, "pair: both tasks whole, no fault")
    check(pa["body_rows"]["max"] == 0 and pa["self_rows"]["max"] == 0, "pair: task 1 alone has no body or self rows")
    check(pb["body_rows"]["ticks_any"] > 0 and pb["self_rows"]["ticks_any"] > 0 and
          pb["body_rows"]["max"] + pb["self_rows"]["max"] <= pb["active_rows"]["max"],
          f"pair: the cell's body rows ({pb['body_rows']}) and self rows ({pb['self_rows']}) reach the PDNN, "
          "among its active rows")
    # callgrind's summary line, as valgrind prints it, into instructions per tick
    for k, n in (("cross_circles", 3000000), ("cross_circles_cell", 4500000)):
        with open(os.path.join(raw, f"callgrind_{k}.err"), "w") as f:
            f.write(f"==1== Events    : Ir\n==1== Collected : {n}\n==1==\n==1== I   refs:      {n}\n")
        shutil.copy(tj if k == "cross_circles" else pj, os.path.join(raw, f"tick_callgrind_{k}.json"))
    with open(os.path.join(raw, "tick_callgrind_cross_circles_cell.json"), "w") as f:
        json.dump({"run": pb}, f)
    cr = report.cell_row(raw)
    check(cr.get("ir_per_tick") == {"cross_circles": 3000000 / 400, "cross_circles_cell": 4500000 / 10000},
          f"instructions per tick from callgrind's count and the run's ticks: {cr.get('ir_per_tick')}")
    check(cr.get("pairs") == 2 and len(cr.get("p99_ratios", [])) == 2, "pair: one p99 ratio per pair")

    # 2. OSQP on those QPs: same answers (an independent solver)
    o = report.osqp_compare(qd, 1e-9)
    check("warm" in o and o["warm"]["max_dphi"] < 1e-6,
          f"OSQP agrees with the PDNN on the dumped QPs (max |dphi| {o.get('warm', {}).get('max_dphi')})")

    # 3. scaling mode: QP layout per (arms, joints) from the scheme's definition
    sj = os.path.join(raw, "scaling.json")
    r = subprocess.run([a.bench_tick, "scaling", "--urdf-dir", os.path.join(a.source, "config/robots"), "--quick",
                        "--ticks", "60", "--out", sj], capture_output=True, text=True, timeout=60)
    check(r.returncode == 0, "bench_tick scaling exits 0")
    sc = json.load(open(sj))
    ok = True
    for run in sc["runs"]:
        na, dof = run["n_arms"], run["dof"][0]
        ok &= run["n_vars"] == na * dof and run["n_eq"] == 3 * na and run["n_ineq"] == na * (dof + 1)
        ok &= run["dof"] == [dof] * na and run["ticks"] + run["faults"] == 60
    check(ok and len(sc["runs"]) == 7, f"scaling: {len(sc['runs'])} configs, vars = arms x joints, eq = 3 arms, "
          "ineq = arms x links, ticks + faulted ticks = 60")

    # 4. cyclictest histogram: percentiles = upper edge of the 1 us bin, against numpy on the samples
    rng = np.random.default_rng(3)
    samples = np.concatenate([rng.integers(2, 40, 9000), rng.integers(40, 900, 990), [1500] * 10])
    hist = np.bincount(samples, minlength=2000)[:2000]
    over = int((samples >= 2000).sum())
    text = "# /dev/cpu_dma_latency set to 0us\n# Histogram\n" + "".join(
        f"{i:06d} {c:06d}\n" for i, c in enumerate(hist)) + (
        f"# Total: {len(samples):09d}\n# Min Latencies: {samples.min():05d}\n# Avg Latencies: 00010\n"
        f"# Max Latencies: {samples.max():05d}\n# Histogram Overflows: {over:05d}\n")
    cs = report.cyclictest_stats(text)
    srt = np.sort(samples)

    def truth(p):
        return float(min(srt[int(np.ceil(p * len(srt))) - 1] + 1, srt[-1]))

    check(cs is not None and all(cs[k] == truth(p) for k, p in (("p50_us", .5), ("p99_us", .99), ("p999_us", .999)))
          and cs["max_us"] == 1500.0 and cs["samples"] == 10000,
          f"cyclictest percentiles {cs and [cs['p50_us'], cs['p99_us'], cs['p999_us']]} == "
          f"{[truth(.5), truth(.99), truth(.999)]}")

    # 5. mcad summary lines (format of mca_daemon_print_summary)
    m = report.mcad_summary(
        "<6>mcad: summary: state stopped, ticks 19977, overruns 24 (skipped periods 25), SCHED_FIFO yes, memory "
        "locked yes\n<6>mcad: summary: wake-up jitter p50 30.0 us, p99 86.0 us, p99.9 1069.0 us, max 2855.9 us\n"
        "<6>mcad: summary: compute time (whole tick) p50 19.0 us, p99 35.0 us, max 133.4 us; controller tick p50 "
        "17.0 us, p99 30.0 us, max 131.3 us\n")
    check(m is not None and (m["ticks"], m["overruns"], m["p50_us"], m["p99_us"], m["p999_us"], m["max_us"],
                             m["compute_p50_us"], m["ctrl_p99_us"]) == (19977, 24, 30.0, 86.0, 1069.0, 2855.9, 19.0,
                                                                       30.0), "mcad summary parsed")
    m = report.mcad_summary(
        "<6>mcad: summary: state stopped, ticks 15002, overruns 0 (skipped periods 0), SCHED_FIFO yes, memory "
        "locked yes\n<6>mcad: summary: wake-up jitter p50 22.0 us, p99 57.0 us, p99.9 108.0 us, max 215.5 us\n"
        "<6>mcad: summary: dds on/off (blocks of 500 ticks): whole tick publishing off p50 18.0 us, p99 33.0 us, "
        "mean 18.38 us (7501 ticks); on p50 21.0 us, p99 31.0 us, mean 20.00 us (7500 ticks); ratio on/off p50 "
        "1.167, p99 0.939, mean 1.088\n")
    ab = (m or {}).get("dds_ab") or {}
    check((ab.get("block"), ab.get("off_p50"), ab.get("off_mean"), ab.get("off_n"), ab.get("on_p99"),
           ab.get("on_mean"), ab.get("on_n")) == (500, 18.0, 18.38, 7501, 31.0, 20.0, 7500),
          "mcad --dds-ab summary line parsed")

    # 6. the table: measured rows carry figures, the others say "not measured"
    with open(os.path.join(raw, "machine.txt"), "w") as f:
        f.write("date: test\nkernel: x\nModel name: test cpu\nCPU(s): 2\n")
    r = subprocess.run([sys.executable, os.path.join(a.source, "bench/report.py"), out], capture_output=True,
                       text=True, timeout=120)
    check(r.returncode == 0, f"report.py exits 0 ({r.stderr.strip()[-300:]})")
    tab = open(os.path.join(out, "table.md")).read()
    check("| 1. tick compute, dual PA10+" in tab and "| 1. tick compute, JACO2" in tab and "not measured" in tab,
          "table: task 1 row measured, missing rows say 'not measured'")
    check("| 4. wake-up jitter | not measured" in tab, "no jitter figure invented")
    check("| 1d. whole cell, dual PA10+ task 1 with 8 bodies and self pairs | 0.5 k instructions/tick" in tab,
          "table: the whole-cell row with its instructions per tick")
    check(os.path.exists(os.path.join(out, "scaling.png")), "scaling.png written")
    shutil.rmtree(out, ignore_errors=True)
    print(f"{len(FAILS)} failing")
    return 1 if FAILS else 0


if __name__ == "__main__":
    sys.exit(main())
