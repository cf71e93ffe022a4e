#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Collect the figures of one `make bench` run and print ONE table.

usage: report.py OUT_DIR
       report.py osqp QP_DIR OUT.json   (only the OSQP comparison; bench/run.sh runs it under SCHED_FIFO like
                                         the PDNN's timing)

OUT_DIR (written by bench/run.sh) holds raw/ with every program's own output; this script parses them
(robustly: a missing or malformed output gives a row that says "not measured" and why, never a figure),
runs OSQP on the QPs dumped from the tasks, and writes
  OUT_DIR/bench.json   every figure, with the command that produced it
  OUT_DIR/table.md     the table (also printed)
  OUT_DIR/scaling.png  tick time against arms, joints and critical points (log-log fits)
"""
import json
import math
import os
import re
import sys

import numpy as np

PERIOD_NS = 1e6  # the 1 ms control period


def read(path):
    try:
        with open(path, encoding="utf-8", errors="replace") as f:
            return f.read()
    except OSError:
        return None


def load_json(path):
    txt = read(path)
    if txt is None:
        return None
    try:
        return json.loads(txt)
    except ValueError:
        return None


def num(pattern, text, group=1, cast=float):
    if text is None:
        return None
    m = re.search(pattern, text)
    if not m:
        return None
    try:
        return cast(m.group(group))
    except (TypeError, ValueError):
        return None


def ratio(a, b):
    ok = all(isinstance(x, (int, float)) and math.isfinite(x) for x in (a, b))
    return f"{a / b:.2f}" if ok and b else "-"


def clean(x):
    """JSON has no infinity: write it as a string."""
    if isinstance(x, dict):
        return {k: clean(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [clean(v) for v in x]
    if isinstance(x, float) and not math.isfinite(x):
        return str(x)
    return x


def us(ns):
    return None if ns is None else ns / 1e3


def fmt(x, nd=1, unit=""):
    if isinstance(x, float) and x == float("inf"):
        return "> histogram range (overflow)"
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "-"
    return f"{x:.{nd}f}{unit}"


# ---- 1. controller tick ---------------------------------------------------------------------------------------
def tick_rows(raw):
    out = {}
    for key, label in (("cross_circles", "dual PA10+ (n=8), task 1 cross circles"),
                       ("cup_stacking_dual_jaco2", "dual JACO2 (n=6), task 3 with a JACO2 in the MICO2's place"),
                       ("cup_stacking", "JACO2 + MICO2 (n=6), task 3 cup stacking")):
        d = load_json(os.path.join(raw, f"tick_{key}.json"))
        if not d or "run" not in d:
            out[key] = {"label": label, "error": f"raw/tick_{key}.json missing or malformed"}
            continue
        r = d["run"]
        t = r["tick_ns"]
        split = {k: r[f"{k}_ns"]["p50"] for k in ("fk", "distances", "assembly", "pdnn")}
        out[key] = {
            "label": label, "ticks": r["ticks"], "faults": r["faults"], "sched_fifo": d.get("sched_fifo", 0),
            "p50_us": us(t["p50"]), "p99_us": us(t["p99"]), "max_us": us(t["max"]), "mean_us": us(t["mean"]),
            "p50_frac": t["p50"] / PERIOD_NS, "p99_frac": t["p99"] / PERIOD_NS, "max_frac": t["max"] / PERIOD_NS,
            "split_p50_us": {k: us(v) for k, v in split.items()},
            "pdnn_share_p50": split["pdnn"] / t["p50"] if t["p50"] else None,
            "steps": r["steps"], "capped": r["capped"], "step_mismatch": r["step_mismatch"],
            "active_rows": r["active_rows"], "qp": [r["n_vars"], r["n_eq"], r["n_ineq"]],
        }
    return out


# ---- 1d. the whole cell ----------------------------------------------------------------------------------------
def callgrind_ir(path):
    """Instructions collected in a callgrind run (valgrind's own summary line on stderr)."""
    return num(r"Collected\s*:\s*(\d+)", read(path), cast=int)


def cell_row(raw):
    """Task 1 plain against the whole cell: instructions per tick, p99 of paired runs, PDNN steps, rows."""
    d = load_json(os.path.join(raw, "tick_cell_pairs.json"))
    if not d or "runs" not in d:
        return {"error": "raw/tick_cell_pairs.json missing or malformed"}
    a = [r["run"] for r in d["runs"] if r["which"] == "a"]
    b = [r["run"] for r in d["runs"] if r["which"] == "b"]
    if not a or len(a) != len(b):
        return {"error": "raw/tick_cell_pairs.json: runs do not pair"}
    ratios = sorted((y["tick_ns"]["p99"] / x["tick_ns"]["p99"], i) for i, (x, y) in enumerate(zip(a, b)))
    med = ratios[len(ratios) // 2][1]
    out = {"pairs": len(a), "p99_ratios": [round(x, 3) for x, _ in ratios], "median_pair": med,
           "plain": a[med], "cell": b[med], "sched_fifo": d.get("sched_fifo", 0)}
    ir = {}
    for k in ("cross_circles", "cross_circles_cell"):
        n = callgrind_ir(os.path.join(raw, f"callgrind_{k}.err"))
        t = load_json(os.path.join(raw, f"tick_callgrind_{k}.json"))
        calls = t["run"]["ticks"] + t["run"]["resets"] if t and "run" in t else None
        ir[k] = n / calls if n and calls else None
    out["ir_per_tick"] = ir
    return out


def mcad_summary(text):
    if not text:
        return None
    s = {
        "ticks": num(r"ticks (\d+), overruns", text, cast=int),
        "overruns": num(r"overruns (\d+)", text, cast=int),
        "sched_fifo": num(r"SCHED_FIFO (yes|no)", text, cast=str),
        "p50_us": num(r"wake-up jitter p50 ([0-9.]+) us", text),
        "p99_us": num(r"wake-up jitter p50 [0-9.]+ us, p99 ([0-9.]+) us", text),
        "p999_us": num(r"p99\.9 ([0-9.]+) us", text),
        "max_us": num(r"p99\.9 [0-9.]+ us, max ([0-9.]+) us", text),
        "compute_p50_us": num(r"compute time \(whole tick\) p50 ([0-9.]+) us", text),
        "compute_p99_us": num(r"compute time \(whole tick\) p50 [0-9.]+ us, p99 ([0-9.]+) us", text),
        "compute_max_us": num(r"compute time \(whole tick\) p50 [0-9.]+ us, p99 [0-9.]+ us, max ([0-9.]+) us", text),
        "ctrl_p50_us": num(r"controller tick p50 ([0-9.]+) us", text),
        "ctrl_p99_us": num(r"controller tick p50 [0-9.]+ us, p99 ([0-9.]+) us", text),
        "ctrl_max_us": num(r"controller tick p50 [0-9.]+ us, p99 [0-9.]+ us, max ([0-9.]+) us", text),
        "state": num(r"summary: state (\w+)", text, cast=str),
    }
    ab = re.search(r"dds on/off \(blocks of (\d+) ticks\): whole tick publishing off p50 ([0-9.]+) us, p99 ([0-9.]+) us, "
                   r"mean ([0-9.]+) us \((\d+) ticks\); on p50 ([0-9.]+) us, p99 ([0-9.]+) us, mean ([0-9.]+) us "
                   r"\((\d+) ticks\)", text)
    if ab:
        g = ab.groups()
        s["dds_ab"] = {"block": int(g[0]), "off_p50": float(g[1]), "off_p99": float(g[2]), "off_mean": float(g[3]),
                       "off_n": int(g[4]), "on_p50": float(g[5]), "on_p99": float(g[6]), "on_mean": float(g[7]),
                       "on_n": int(g[8])}
    return s if s["p50_us"] is not None else None


# ---- 2. PDNN vs OSQP --------------------------------------------------------------------------------------------
def load_qp(path):
    with open(path, encoding="utf-8") as f:
        d = json.load(f)
    n, ne, ni = d["n"], d["n_eq"], d["n_ineq"]
    G = np.array(d["G"], float).reshape(ne, n)
    U = np.array(d["U"], float).reshape(ni, n) if ni else np.zeros((0, n))
    lb = np.array([-np.inf if v is None else v for v in d["lb"]], float)
    ub = np.array([np.inf if v is None else v for v in d["ub"]], float)
    A = np.vstack([G, U, np.eye(n)])
    lo = np.concatenate([np.array(d["alpha"], float), np.full(ni, -np.inf), lb])
    hi = np.concatenate([np.array(d["alpha"], float), np.array(d["beta"], float), ub])
    return n, A, lo, hi, np.array(d["phi"], float)


def osqp_compare(qpdir, eps):
    """Blocks of consecutive ticks: OSQP cold (setup + solve) on the first QP of each block against the PDNN
    from a fresh state; then OSQP warm (update + warm-started solve) against the PDNN's warm solve of the
    tick (the controller's own warm start). One sparsity pattern per block (union of the block's nonzeros),
    so that every update keeps the factorisation structure."""
    import osqp  # noqa: PLC0415 (only this part needs it)
    from scipy import sparse  # noqa: PLC0415

    csvp = os.path.join(qpdir, "pdnn.csv")
    txt = read(csvp)
    if not txt:
        return {"error": f"{csvp} missing"}
    rows = [dict(zip(txt.splitlines()[0].split(","), line.split(","))) for line in txt.splitlines()[1:] if line]
    if not rows:
        return {"error": f"no QPs dumped in {qpdir} (run shorter than the dump interval?)"}
    blocks = {}
    for r in rows:
        blocks.setdefault(int(r["block"]), []).append(r)
    res = {k: {"pdnn": [], "solve": [], "run": [], "polish": [], "delta": [], "iters": [], "bad": 0}
           for k in ("cold", "warm")}
    settings = dict(eps_abs=eps, eps_rel=eps, polishing=True, max_iter=100000, verbose=False)
    for _, blk in sorted(blocks.items()):
        blk.sort(key=lambda r: int(r["idx"]))
        qps = [load_qp(os.path.join(qpdir, r["file"])) for r in blk]
        n = qps[0][0]
        mask = np.zeros_like(qps[0][1], bool)
        for q in qps:
            mask |= q[1] != 0.0
        rows_i, cols_i = np.nonzero(mask.T)  # column-major order for CSC
        indptr = np.concatenate([[0], np.cumsum(mask.sum(axis=0))])
        prob = None
        for r, (_, A, lo, hi, phi) in zip(blk, qps):
            data = A.T[mask.T]
            Acsc = sparse.csc_matrix((data, cols_i, indptr), shape=A.shape)
            if prob is None:
                prob = osqp.OSQP()
                prob.setup(sparse.identity(n, format="csc"), np.zeros(n), Acsc, lo, hi, **settings)
                kind, pdnn_ns = "cold", float(r["cold_ns"])
            else:
                prob.update(Ax=data, l=lo, u=hi)
                kind, pdnn_ns = "warm", float(r["warm_ns"])
            sol = prob.solve()
            d = res[kind]
            status = getattr(sol.info, "status", "")
            if "solved" not in str(status).lower() or "inaccurate" in str(status).lower():
                d["bad"] += 1
                continue
            d["pdnn"].append(pdnn_ns / 1e3)
            d["solve"].append(sol.info.solve_time * 1e6)
            d["run"].append(sol.info.run_time * 1e6)
            d["polish"].append(sol.info.polish_time * 1e6)
            d["iters"].append(sol.info.iter)
            d["delta"].append(float(np.max(np.abs(sol.x - phi))))
    out = {"eps": eps, "qps": len(rows), "blocks": len(blocks)}
    for kind, d in res.items():
        if not d["pdnn"]:
            continue
        p = lambda v, q: float(np.percentile(v, q))  # noqa: E731
        out[kind] = {
            "n": len(d["pdnn"]), "osqp_failed": d["bad"],
            "pdnn_p50_us": p(d["pdnn"], 50), "pdnn_p99_us": p(d["pdnn"], 99),
            "osqp_solve_p50_us": p(d["solve"], 50), "osqp_solve_p99_us": p(d["solve"], 99),
            "osqp_run_p50_us": p(d["run"], 50), "osqp_run_p99_us": p(d["run"], 99),
            "osqp_polish_p50_us": p(d["polish"], 50),
            "osqp_iter_p50": p(d["iters"], 50), "osqp_iter_max": max(d["iters"]),
            "ratio_p50_solve": p(d["pdnn"], 50) / p(d["solve"], 50),
            "ratio_p50_run": p(d["pdnn"], 50) / p(d["run"], 50),
            "max_dphi": max(d["delta"]),
        }
    return out


def osqp_guarded(qpdir, eps):
    try:
        return osqp_compare(qpdir, eps)
    except Exception as e:  # noqa: BLE001 (report, never crash the table)
        return {"error": f"{type(e).__name__}: {e}"}


# ---- 4. cyclictest ----------------------------------------------------------------------------------------------
def cyclictest_stats(text):
    """Histogram (-h) output: 'NNNNNN CCCCCC' per 1 us bin. Percentiles as the UPPER edge of the bin (the
    convention of mcad's histogram, mca/rtstats.h), capped at the exact max."""
    if not text:
        return None
    bins = []
    for line in text.splitlines():
        m = re.match(r"^(\d+)\s+(\d+)\s*$", line)
        if m:
            bins.append((int(m.group(1)), int(m.group(2))))
    mx = num(r"# Max Latencies:\s*(\d+)", text, cast=int)
    ov = num(r"# Histogram Overflows:\s*(\d+)", text, cast=int) or 0
    if not bins or mx is None:
        return None
    total = sum(c for _, c in bins) + ov

    top = bins[-1][0] + 1  # histogram range [us]; beyond it cyclictest only counts overflows

    def pct(p):
        need = math.ceil(p * total)
        acc = 0
        for v, c in bins:
            acc += c
            if acc >= need:
                return float(min(v + 1, mx))
        return float("inf")  # in the overflow count: only "> top" is known

    return {"samples": total, "p50_us": pct(0.5), "p99_us": pct(0.99), "p999_us": pct(0.999), "max_us": float(mx),
            "overflows": ov, "range_us": top, "avg_us": num(r"# Avg Latencies:\s*(\d+)", text)}


# ---- table ------------------------------------------------------------------------------------------------------
def main():
    if len(sys.argv) == 4 and sys.argv[1] == "osqp":
        with open(sys.argv[3], "w", encoding="utf-8") as f:
            json.dump(osqp_guarded(sys.argv[2], 1e-9), f, indent=1)
        return 0
    if len(sys.argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    out_dir = sys.argv[1]
    if not os.path.isdir(out_dir):
        print(f"report.py: {out_dir}: not a folder (bench/run.sh writes OUT_DIR/raw/ first)", file=sys.stderr)
        return 2
    raw = os.path.join(out_dir, "raw")
    R = {"machine": {}, "notes": []}
    mach = read(os.path.join(raw, "machine.txt")) or ""
    R["machine"] = {
        "cpu": num(r"Model name:\s*(.+)", mach, cast=str),
        "cores": num(r"(?m)^CPU\(s\):\s*(\d+)", mach, cast=int),
        "kernel": num(r"kernel:\s*(\S+)", mach, cast=str),
        "load_before": num(r"load average: ([0-9., ]+)", mach, cast=str),
        "date": num(r"date:\s*(.+)", mach, cast=str),
        "git": num(r"git:\s*(\S+)", mach, cast=str),
        "mode": num(r"mode:\s*(\S+)", mach, cast=str),
    }
    rows = []  # (item, measured, peer / limit, ratio, note)

    # 1
    ticks = tick_rows(raw)
    R["tick"] = ticks
    for key in ("cross_circles", "cup_stacking_dual_jaco2", "cup_stacking"):
        t = ticks[key]
        if "error" in t:
            rows.append((f"1. tick compute, {t['label']}", "not measured", "1 ms period", "-", t["error"]))
            continue
        sp = t["split_p50_us"]
        rows.append((
            f"1. tick compute, {t['label']}",
            f"p50 {fmt(t['p50_us'])} / p99 {fmt(t['p99_us'])} / max {fmt(t['max_us'])} us",
            "1 ms period",
            f"{t['p50_frac'] * 100:.2f} % / {t['p99_frac'] * 100:.2f} % / {t['max_frac'] * 100:.1f} %",
            f"{t['ticks']} ticks, virtual time, {'SCHED_FIFO' if t['sched_fifo'] else 'SCHED_OTHER'}; p50 split: "
            f"FK {fmt(sp['fk'])}, distances {fmt(sp['distances'])}, Jacobians+QP {fmt(sp['assembly'])}, "
            f"PDNN {fmt(sp['pdnn'])} us; PDNN steps/tick p50 {t['steps']['p50']} p99 {t['steps']['p99']} "
            f"max {t['steps']['max']}; capped {t['capped']}; faults {t['faults']}"))
    cell = cell_row(raw)
    R["cell"] = cell
    if "error" in cell:
        rows.append(("1d. whole cell, dual PA10+ task 1 with 8 bodies and self pairs", "not measured", "task 1 alone",
                     "-", cell["error"]))
    else:
        p, c, ir = cell["plain"], cell["cell"], cell["ir_per_tick"]
        ir_p, ir_c = ir["cross_circles"], ir["cross_circles_cell"]
        rows.append((
            "1d. whole cell, dual PA10+ task 1 with 8 bodies and self pairs",
            f"{fmt(ir_c / 1e3 if ir_c else None)} k instructions/tick; p99 {fmt(us(c['tick_ns']['p99']))} us",
            f"task 1 alone: {fmt(ir_p / 1e3 if ir_p else None)} k/tick; p99 {fmt(us(p['tick_ns']['p99']))} us",
            f"{ratio(ir_c, ir_p)} (instructions; target <= 1.5) / {ratio(c['tick_ns']['p99'], p['tick_ns']['p99'])} "
            "(p99)",
            f"callgrind over the whole task, mca_controller_tick alone; p99: the median of {cell['pairs']} pairs of "
            f"whole runs alternating plain / cell (p99 ratios {', '.join(str(x) for x in cell['p99_ratios'])}), "
            f"{'SCHED_FIFO' if cell['sched_fifo'] else 'SCHED_OTHER'}; PDNN steps/tick p50 {c['steps']['p50']} "
            f"p99 {c['steps']['p99']} max {c['steps']['max']} (plain {p['steps']['p50']} / {p['steps']['p99']} / "
            f"{p['steps']['max']}), exact solves p50 {c['exact_solves']['p50']} max {c['exact_solves']['max']}; "
            f"rows to the PDNN per tick: bodies mean {c['body_rows']['mean']:.3f} max {c['body_rows']['max']} "
            f"({c['body_rows']['ticks_any']} ticks), self mean {c['self_rows']['mean']:.3f} max "
            f"{c['self_rows']['max']} ({c['self_rows']['ticks_any']} ticks); faults {c['faults']}"))
    jit_m = mcad_summary(read(os.path.join(raw, "mcad_jitter.log")))
    if jit_m and jit_m.get("ctrl_p50_us") is not None:
        rows.append(("1b. tick compute inside mcad (real 1 kHz loop, PA10+ task 1)",
                     f"p50 {fmt(jit_m['ctrl_p50_us'])} / p99 {fmt(jit_m['ctrl_p99_us'])} / max "
                     f"{fmt(jit_m['ctrl_max_us'])} us", "1 ms period",
                     f"{jit_m['ctrl_p50_us'] / 10:.2f} % / {jit_m['ctrl_p99_us'] / 10:.2f} % / "
                     f"{jit_m['ctrl_max_us'] / 10:.1f} %",
                     f"mca_controller_tick alone, from mcad's summary; whole tick incl. arm I/O p50 "
                     f"{fmt(jit_m['compute_p50_us'])} us"))

    pairs = []  # (mca, mca-ts) summaries of each alternating pair
    for k in (1, 2, 3, 4, 5):
        a = mcad_summary(read(os.path.join(raw, f"mcad_scheme_mca_{k}.log")))
        b = mcad_summary(read(os.path.join(raw, f"mcad_scheme_mca-ts_{k}.log")))
        if a and b and a.get("ctrl_p99_us") and b.get("ctrl_p99_us"):
            pairs.append((a, b))
    if pairs:
        by = sorted(pairs, key=lambda ab: ab[1]["ctrl_p99_us"] / ab[0]["ctrl_p99_us"])
        ts_a, ts_b = by[len(by) // 2]  # the median pair (five pairs)
        each = ", ".join(ratio(b["ctrl_p99_us"], a["ctrl_p99_us"]) for a, b in pairs)
        rows.append(("1c. tick compute inside mcad, mca-ts vs mca (task 1, same run length)",
                     f"p50 {fmt(ts_b['ctrl_p50_us'])} / p99 {fmt(ts_b['ctrl_p99_us'])} us",
                     f"p50 {fmt(ts_a['ctrl_p50_us'])} / p99 {fmt(ts_a['ctrl_p99_us'])} us",
                     f"{ratio(ts_b['ctrl_p50_us'], ts_a['ctrl_p50_us'])} / "
                     f"{ratio(ts_b['ctrl_p99_us'], ts_a['ctrl_p99_us'])}",
                     f"the target is p99 <= 1.3x; the median of {len(pairs)} pairs run at the same time, one per "
                     f"CPU, CPUs swapped every other pair (p99 ratios {each}); mca_controller_tick alone, from "
                     "mcad's summary"))

    # 2
    R["osqp"] = {}
    for key in ("cross_circles", "cup_stacking"):
        qd = os.path.join(raw, f"qp_{key}")
        if not os.path.isdir(qd):
            rows.append((f"2. PDNN vs OSQP, {key}", "not measured", "OSQP", "-", f"{qd} missing"))
            continue
        o = load_json(os.path.join(raw, f"osqp_{key}.json"))  # `report.py osqp` run by bench/run.sh
        if o is None:
            o = osqp_guarded(qd, 1e-9)
        R["osqp"][key] = o
        if "error" in o:
            rows.append((f"2. PDNN vs OSQP, {key}", "not measured", "OSQP", "-", o["error"]))
            continue
        for kind in ("warm", "cold"):
            if kind not in o:
                continue
            c = o[kind]
            rows.append((
                f"2. PDNN vs OSQP, {key}, {kind} ({c['n']} QPs)",
                f"PDNN p50 {fmt(c['pdnn_p50_us'], 2)} / p99 {fmt(c['pdnn_p99_us'], 2)} us",
                f"OSQP solve_time p50 {fmt(c['osqp_solve_p50_us'], 2)} / p99 {fmt(c['osqp_solve_p99_us'], 2)} us "
                f"(run_time p50 {fmt(c['osqp_run_p50_us'], 2)}, of it polish p50 "
                f"{fmt(c.get('osqp_polish_p50_us'), 2)})",
                f"{c['ratio_p50_solve']:.2f} (vs run_time {c['ratio_p50_run']:.2f})",
                f"PDNN/OSQP at p50; OSQP eps 1e-9 + polish, ADMM iterations p50 {c['osqp_iter_p50']:.0f} max "
                f"{c['osqp_iter_max']}; "
                f"max |dphi| {c['max_dphi']:.1e}; OSQP failed on {c['osqp_failed']}"))
    qc = read(os.path.join(raw, "qpcheck.txt"))
    if qc is not None:
        rc = num(r"exit (\d+)", qc, cast=int)
        R["qpcheck_rc"] = rc
        rows.append(("2b. tools/qp-check/osqp_check.py on the dumped QPs", "pass" if rc == 0 else f"exit {rc}",
                     "OSQP 1e-10", "-", "every PDNN answer within 1e-6 of OSQP's (pdnn engineer's checker)"))

    # 2c. PDNN vs DAQP (bench/daqp/run.sh)
    dq = read(os.path.join(raw, "daqp.txt"))
    if dq is not None and "skipped" in dq:
        rows.append(("2c. PDNN vs DAQP, consecutive ticks of the hardest sweep tasks", "skipped: daqp not available",
                     "PDNN p99 <= 2x DAQP p99", "-", "see raw/daqp.txt, raw/daqp_build.err"))
    elif dq is not None and "ratio PDNN p99" in dq:
        d = {"pdnn_p50_us": num(r"PDNN us p50 ([0-9.]+)", dq), "pdnn_p99_us": num(r"PDNN us p50 [0-9.]+ p99 ([0-9.]+)", dq),
             "pdnn_max_us": num(r"PDNN us p50 [0-9.]+ p99 [0-9.]+ max ([0-9.]+)", dq),
             "daqp_p50_us": num(r"DAQP us p50 ([0-9.]+)", dq), "daqp_p99_us": num(r"DAQP us p50 [0-9.]+ p99 ([0-9.]+)", dq),
             "daqp_max_us": num(r"DAQP us p50 [0-9.]+ p99 [0-9.]+ max ([0-9.]+)", dq),
             "ratio_p99": num(r"ratio PDNN p99 / DAQP p99 ([0-9.]+)", dq),
             "dphi_pdnn_daqp": num(r"\(both solved\) ([0-9.eE+-]+)", dq),
             "n": num(r"(\d+) QPs \(", dq.split("daqp ", 1)[-1], cast=int)}
        oq = read(os.path.join(raw, "daqp_osqp.txt")) or ""
        d["dphi_pdnn_osqp"] = num(r"max \|phi_pdnn - phi_osqp\| ([0-9.eE+-]+)", oq)
        d["dphi_daqp_osqp"] = num(r"max \|phi_daqp - phi_osqp\| ([0-9.eE+-]+)", oq)
        d["kkt_pdnn"] = num(r"KKT residual on all \d+: PDNN ([0-9.eE+-]+)", oq)
        d["kkt_daqp"] = num(r"KKT residual on all \d+: PDNN [0-9.eE+-]+ \(.*?\), DAQP ([0-9.eE+-]+)", oq)
        d["osqp_rc"] = num(r"exit (\d+)", oq, cast=int)
        R["daqp"] = d
        rows.append((
            f"2c. PDNN vs DAQP, every tick of 3 hardest sweep tasks, both warm ({d['n']} QPs)",
            f"PDNN p99 {fmt(d['pdnn_p99_us'], 2)} / max {fmt(d['pdnn_max_us'])} us; DAQP p99 "
            f"{fmt(d['daqp_p99_us'], 2)} / max {fmt(d['daqp_max_us'])} us",
            "PDNN p99 / DAQP p99 <= 2", f"{fmt(d['ratio_p99'], 2)}",
            f"median of 3 passes; max |phi_pdnn - phi_daqp| {d['dphi_pdnn_daqp']}; every 50th QP: KKT residual "
            f"PDNN {d['kkt_pdnn']}, DAQP {d['kkt_daqp']}; vs OSQP 1e-10 where it is a reference: PDNN "
            f"{d['dphi_pdnn_osqp']}, DAQP {d['dphi_daqp_osqp']}; check "
            f"{'pass' if d['osqp_rc'] == 0 else 'exit ' + str(d['osqp_rc'])} (raw/daqp_osqp.txt)"))

    # 3
    sd = read(os.path.join(raw, "segdist.txt"))
    seg = {}
    if sd:
        for line in sd.splitlines():
            cells = [c.strip() for c in line.strip().strip("|").split("|")]
            if len(cells) == 5 and re.match(r"^[0-9.]+$", cells[1] or ""):
                seg[cells[0]] = {"ns": float(cells[1]), "ratio": float(cells[2]), "max_err": cells[3],
                                 "iter": cells[4]}
    R["segdist"] = seg
    closed = next((v for k, v in seg.items() if k.startswith("closed")), None)
    for k, v in seg.items():
        if k.startswith("closed") or "yes/no" in k:
            continue
        rows.append((f"3. segment distance: {k}", f"{v['ns']:.1f} ns/pair",
                     f"closed form {closed['ns']:.1f} ns/pair" if closed else "-", f"{v['ratio']:.2f}",
                     f"max |d - d_closed| {v['max_err']} m, mean iterations {v['iter']}"
                     + ("; our GJK distance loop on libccd's vectors and support functions (libccd 2.x has "
                        "no distance query, only intersection and penetration)" if "GJK" in k else "")))
    if not seg:
        rows.append(("3. segment distance", "not measured", "-", "-", "raw/segdist.txt missing or unparsable"))

    # 4
    cyc = cyclictest_stats(read(os.path.join(raw, "cyclictest.txt")))
    R["jitter"] = {"mcad": jit_m, "cyclictest": cyc}
    if jit_m and cyc:
        rows.append((
            "4. wake-up jitter, mcad loop (task 1 on sim arms)",
            f"p50 {fmt(jit_m['p50_us'])} / p99 {fmt(jit_m['p99_us'])} / p99.9 {fmt(jit_m['p999_us'])} / max "
            f"{fmt(jit_m['max_us'])} us",
            f"cyclictest p50 {fmt(cyc['p50_us'])} / p99 {fmt(cyc['p99_us'])} / p99.9 {fmt(cyc['p999_us'])} / max "
            f"{fmt(cyc['max_us'])} us",
            " / ".join(ratio(jit_m[k], cyc[k]) for k in ("p50_us", "p99_us", "p999_us",
                                                                            "max_us")),
            f"mcad/cyclictest; {jit_m['ticks']} vs {cyc['samples']} wake-ups, SCHED_FIFO 80, 1 ms, mlockall, "
            f"cpu_dma_latency 0; mcad overruns {jit_m['overruns']}"))
        cyc2 = cyclictest_stats(read(os.path.join(raw, "cyclictest_concurrent.txt")))
        jm2 = mcad_summary(read(os.path.join(raw, "mcad_concurrent.log")))
        R["jitter"]["concurrent"] = {"mcad": jm2, "cyclictest": cyc2}
        if cyc2 and jm2:
            rows.append((
                "4b. the same, mcad and cyclictest running at the same time",
                f"p50 {fmt(jm2['p50_us'])} / p99 {fmt(jm2['p99_us'])} / p99.9 {fmt(jm2['p999_us'])} / max "
                f"{fmt(jm2['max_us'])} us",
                f"cyclictest p50 {fmt(cyc2['p50_us'])} / p99 {fmt(cyc2['p99_us'])} / p99.9 {fmt(cyc2['p999_us'])} / "
                f"max {fmt(cyc2['max_us'])} us",
                " / ".join(ratio(jm2[k], cyc2[k]) for k in ("p50_us", "p99_us", "p999_us",
                                                                                "max_us")),
                f"same host disturbances for both; mcad overruns {jm2['overruns']}"))
    else:
        rows.append(("4. wake-up jitter", "not measured", "cyclictest", "-",
                     "mcad or cyclictest output missing: see raw/mcad_jitter.log, raw/cyclictest.txt"))

    # 5
    bd = read(os.path.join(raw, "bench_dds.txt"))
    dds = {}
    if bd:
        dds = {
            "off_p50": num(r"publishing OFF: p50\s+([0-9.]+)", bd), "on_p50": num(r"publishing ON : p50\s+([0-9.]+)", bd),
            "ratio_p50": num(r"ratio ON/OFF\s+p50 ([0-9.]+)", bd), "ratio_p99": num(r"ratio ON/OFF\s+p50 [0-9.]+\s+p99 ([0-9.]+)", bd),
            "push_p50": num(r"push call alone\s*: p50\s+([0-9.]+)", bd),
            "offered": num(r"offered (\d+)", bd, cast=int), "dropped": num(r"dropped (\d+)", bd, cast=int),
        }
    on = mcad_summary(read(os.path.join(raw, "mcad_dds_on.log")))
    lat = read(os.path.join(raw, "dds_latency.txt"))
    dds["latency"] = {"p50": num(r"latency stamp->receipt p50 ([0-9.]+) us", lat),
                      "p99": num(r"latency stamp->receipt p50 [0-9.]+ us p99 ([0-9.]+) us", lat),
                      "max": num(r"max ([0-9.]+) us \(n=", lat), "n": num(r"\(n=(\d+)\)", lat, cast=int)}
    dds["mcad_on"] = on
    R["dds"] = dds
    if dds.get("ratio_p50") is not None:
        rows.append(("5. DDS on vs off: bench/dds (100 us synthetic tick, every tick published, ON/OFF blocks interleaved)",
                     f"on p50 {fmt(dds['on_p50'])} us, push {fmt(dds['push_p50'], 2)} us",
                     f"off p50 {fmt(dds['off_p50'])} us", f"{dds['ratio_p50']:.3f} / {dds['ratio_p99']:.3f}",
                     f"dropped {dds['dropped']} of {dds['offered']} snapshots"))
    ab = (on or {}).get("dds_ab")
    if ab:
        rows.append(("5b. DDS on vs off: mcad whole tick (task 1, real 1 kHz loop, one run, alternate blocks)",
                     f"on p50 {fmt(ab['on_p50'])} / p99 {fmt(ab['on_p99'])} / mean {ab['on_mean']:.2f} us",
                     f"off p50 {fmt(ab['off_p50'])} / p99 {fmt(ab['off_p99'])} / mean {ab['off_mean']:.2f} us",
                     f"{ab['on_p50'] / ab['off_p50']:.2f} / {ab['on_p99'] / ab['off_p99']:.2f} / "
                     f"{ab['on_mean'] / ab['off_mean']:.3f}",
                     f"on/off at p50 / p99 / mean; mcad --dds-ab {ab['block']}: every tick published in every other "
                     f"block ({ab['on_n']} vs {ab['off_n']} ticks), mca-monitor subscribed; 1 us histogram bins, so "
                     f"read the mean ratio"))
    if dds["latency"]["p50"] is not None:
        L = dds["latency"]
        rows.append(("5c. DDS latency tick stamp -> mca-monitor receipt", f"p50 {fmt(L['p50'])} / p99 "
                     f"{fmt(L['p99'])} / max {fmt(L['max'])} us", "1 ms period", "-",
                     f"{L['n']} samples, mca-dds-synth 1 kHz, loopback config, SCHED_OTHER"))
    if not (on or dds.get("ratio_p50") is not None):
        rows.append(("5. DDS on vs off", "not measured", "-", "-", "bench_dds / mcad outputs missing"))
    r2 = read(os.path.join(raw, "ros2_latency.txt"))
    r2l = {"p50": num(r"tick->rclpy p50 ([0-9.]+) us", r2), "p99": num(r"us p99 ([0-9.]+) us", r2),
           "max": num(r"max ([0-9.]+) us \(n=", r2), "n": num(r"\(n=(\d+)\)", r2, cast=int)}
    R["ros2_latency"] = r2l
    if r2l["p50"] is not None:
        rows.append(("5d. ROS 2 latency tick wake-up -> rclpy callback (JointState, Fast DDS)",
                     f"p50 {fmt(r2l['p50'])} / p99 {fmt(r2l['p99'])} / max {fmt(r2l['max'])} us", "1 ms period",
                     "-", f"{r2l['n']} samples at 100 Hz, mcad SCHED_FIFO, rclpy executor in Python, own netns"))
    else:
        rows.append(("5d. ROS 2 latency tick -> rclpy", "not measured", "-", "-",
                     ((r2 or "").strip().splitlines() or ["raw/ros2_latency.txt missing"])[-1][:80]))

    # 6
    vc = load_json(os.path.join(out_dir, "vcan.json"))
    R["vcan"] = vc
    if vc and vc.get("p50_us") is not None:
        rows.append(("6. vcan command -> feedback round trip (QEMU guest)",
                     f"p50 {fmt(vc['p50_us'])} / p99 {fmt(vc['p99_us'])} / max {fmt(vc['max_us'])} us",
                     "1 ms period", f"{vc['p50_us'] / 10:.1f} % at p50",
                     f"{vc['n']} lockstep cycles, mca-can-ctl <-> mca-armsim over vcan0 in the guest (TCG, 1 vCPU, "
                     f"kernel {vc.get('kernel', '?')}); {vc.get('source', '')}"))
    else:
        why = (vc or {}).get("error", "no figure (guest not booted and no cached figure)")
        rows.append(("6. vcan round trip", "not measured", "1 ms period", "-", why))

    # scaling
    sc = load_json(os.path.join(raw, "scaling.json"))
    R["scaling"] = scaling_report(sc, out_dir) if sc else {"error": "raw/scaling.json missing"}

    R["rows"] = [dict(zip(("item", "measured", "against", "ratio", "note"), r)) for r in rows]
    lines = ["| item | measured | against | ratio | notes |", "|---|---|---|---|---|"]
    lines += ["| " + " | ".join(str(c).replace("|", "\\|") for c in r) + " |" for r in rows]
    m = R["machine"]
    head = (f"mca bench ({m.get('mode') or 'full'}), {m.get('date')}, git {m.get('git')}: {m.get('cpu')}, "
            f"{m.get('cores')} cores, kernel {m.get('kernel')}, load average before {m.get('load_before')}")
    sc_lines = R["scaling"].get("table", []) if isinstance(R["scaling"], dict) else []
    legend = ("ratio = measured / against: below 1 we are faster (or lower) than the peer; rows 1 and 6 give the "
              "fraction of the 1 ms period. Times in us unless marked.")
    text = head + "\n\n" + "\n".join(lines) + "\n\n" + legend + "\n"
    if sc_lines:
        text += "\nHow the tick cost grows (bench_tick scaling; p50 us):\n\n" + "\n".join(sc_lines) + "\n"
        text += "\n" + R["scaling"].get("fits_text", "") + "\n"
    with open(os.path.join(out_dir, "table.md"), "w", encoding="utf-8") as f:
        f.write(text)
    with open(os.path.join(out_dir, "bench.json"), "w", encoding="utf-8") as f:
        json.dump(clean(R), f, indent=1, default=str)
    print(text)
    return 0


def fit(x, y):
    x, y = np.log(np.asarray(x, float)), np.log(np.asarray(y, float))
    if len(x) < 2 or np.ptp(x) == 0:
        return None
    return float(np.polyfit(x, y, 1)[0])


def scaling_report(sc, out_dir):
    runs = sc.get("runs", [])
    table = ["| arms x joints | d2 [m] | QP vars / eq / ineq | active rows mean | tick p50 | FK | distances | "
             "Jacobians+QP | PDNN | PDNN steps mean | faults |", "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in runs:
        dof = r["dof"][0]
        table.append(
            f"| {r['n_arms']} x {dof} | {r['d2']:g} | {r['n_vars']} / {r['n_eq']} / {r['n_ineq']} | "
            f"{r['active_rows']['mean']:.1f} | {r['tick_ns']['p50'] / 1e3:.1f} | {r['fk_ns']['p50'] / 1e3:.2f} | "
            f"{r['distances_ns']['p50'] / 1e3:.2f} | {r['assembly_ns']['p50'] / 1e3:.2f} | "
            f"{r['pdnn_ns']['p50'] / 1e3:.1f} | {r['steps']['mean']:.1f} | {r['faults']} |")
    ad = [r for r in runs if r["name"].startswith("arms_dof")]
    d2 = [r for r in runs if r["name"].startswith("d2")]
    fits = {}
    # exponents: tick p50 against arms at fixed joints, against joints at fixed arms; distances against
    # link pairs; PDNN against QP size
    for dof in sorted({r["dof"][0] for r in ad}):
        sel = sorted((r for r in ad if r["dof"][0] == dof), key=lambda r: r["n_arms"])
        e = fit([r["n_arms"] for r in sel], [r["tick_ns"]["p50"] for r in sel])
        if e is not None:
            fits[f"tick_vs_arms_dof{dof}"] = e
    for na in sorted({r["n_arms"] for r in ad}):
        sel = sorted((r for r in ad if r["n_arms"] == na), key=lambda r: r["dof"][0])
        e = fit([r["dof"][0] for r in sel], [r["tick_ns"]["p50"] for r in sel])
        if e is not None:
            fits[f"tick_vs_dof_arms{na}"] = e
    if ad:
        pairs = [r["n_arms"] * (r["n_arms"] - 1) / 2 * (r["dof"][0] + 1) ** 2 for r in ad]
        fits["distances_vs_link_pairs"] = fit(pairs, [r["distances_ns"]["p50"] for r in ad])
        fits["pdnn_vs_vars"] = fit([r["n_vars"] for r in ad], [r["pdnn_ns"]["p50"] for r in ad])
        fits["tick_vs_vars"] = fit([r["n_vars"] for r in ad], [r["tick_ns"]["p50"] for r in ad])
    if len(d2) >= 2 and all(r["active_rows"]["mean"] > 0 for r in d2):
        fits["tick_vs_active_rows"] = fit([r["active_rows"]["mean"] for r in d2], [r["tick_ns"]["p50"] for r in d2])
    ft = ("Log-log fits (tick p50 ~ x^e): " + ", ".join(f"{k} e = {v:.2f}" for k, v in fits.items()
                                                        if v is not None))
    png = os.path.join(out_dir, "scaling.png")
    try:
        import matplotlib  # noqa: PLC0415

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt  # noqa: PLC0415
        import matplotlib.ticker  # noqa: PLC0415

        fig, axs = plt.subplots(1, 3, figsize=(15, 4.5))
        for dof in sorted({r["dof"][0] for r in ad}):
            sel = sorted((r for r in ad if r["dof"][0] == dof), key=lambda r: r["n_arms"])
            axs[0].loglog([r["n_arms"] for r in sel], [r["tick_ns"]["p50"] / 1e3 for r in sel], "o-",
                          label=f"{dof} joints/arm")
        axs[0].set_xlabel("arms")
        axs[0].set_ylabel("tick p50 [us]")
        axs[0].set_xticks([2, 3, 4], ["2", "3", "4"])
        axs[0].yaxis.set_major_formatter(matplotlib.ticker.ScalarFormatter())
        axs[0].yaxis.set_minor_formatter(matplotlib.ticker.ScalarFormatter())
        axs[0].legend(fontsize=8)
        axs[0].set_title("tick vs arms")
        for key, lab in (("tick_ns", "whole tick"), ("pdnn_ns", "PDNN"), ("distances_ns", "distances"),
                         ("assembly_ns", "Jacobians+QP"), ("fk_ns", "FK")):
            xs = sorted(ad, key=lambda r: r["n_vars"])
            axs[1].loglog([r["n_vars"] for r in xs], [r[key]["p50"] / 1e3 for r in xs], "o", label=lab)
        axs[1].set_xlabel("QP variables (arms x joints)")
        axs[1].set_ylabel("p50 [us]")
        axs[1].legend(fontsize=8)
        axs[1].set_title("stages vs problem size")
        if d2:
            axs[2].plot([r["active_rows"]["mean"] for r in d2], [r["tick_ns"]["p50"] / 1e3 for r in d2], "o-",
                        label="tick p50")
            axs[2].plot([r["active_rows"]["mean"] for r in d2], [r["pdnn_ns"]["p50"] / 1e3 for r in d2], "s-",
                        label="PDNN p50")
            axs[2].set_xlabel("active collision rows (mean), 2 x 8 joints, d2 swept")
            axs[2].set_ylabel("p50 [us]")
            axs[2].legend(fontsize=8)
            axs[2].set_title("tick vs critical points in the band")
        fig.tight_layout()
        fig.savefig(png, dpi=90)
        plt.close(fig)
    except Exception as e:  # noqa: BLE001
        png = f"not written: {e}"
    return {"runs": len(runs), "fits": fits, "fits_text": ft, "table": table, "png": png}


if __name__ == "__main__":
    sys.exit(main())
