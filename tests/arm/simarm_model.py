#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Second implementation of the simulated arm firmware, written from docs/arm-interface.md, replaying
an mca-simarm-trace CSV (commands in) and checking every feedback field it printed (out).

Usage: simarm_model.py TRACE_TOOL [tool options...]   (runs the tool, replays, exits 1 on mismatch)
"""
import math
import subprocess
import sys

READY, SERVOING, BRAKING, FAULT = 1, 2, 3, 4
F_NONE, F_WATCHDOG, F_LIMIT, F_VELOCITY, F_INJECTED = 0, 1, 2, 3, 4
ON = 1 | 2
CLEAR = 4
LIM_LOW, LIM_HIGH, VEL_SAT, ACTUATOR = 1, 2, 4, 16
M64 = (1 << 64) - 1


class Rng:
    """splitmix64 + Box-Muller, as documented."""

    def __init__(self, seed):
        self.s = seed & M64

    def next(self):
        self.s = (self.s + 0x9E3779B97F4A7C15) & M64
        z = self.s
        z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & M64
        z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & M64
        return z ^ (z >> 31)

    def gauss(self):
        u1 = ((self.next() >> 11) + 1.0) * (1.0 / 9007199254740992.0)
        u2 = (self.next() >> 11) * (1.0 / 9007199254740992.0)
        return math.sqrt(-2.0 * math.log(u1)) * math.cos(2.0 * 3.14159265358979323846 * u2)


def step_to(v0, target, lim):
    dv = target - v0
    if abs(dv) <= lim * (1.0 + 1e-9):
        return target
    return v0 + lim if dv > 0 else v0 - lim


def rate_limit(v0, target, acc, dec, dt):
    dv = target - v0
    if dv == 0.0:
        return target
    if v0 == 0.0 or (v0 > 0) == (dv > 0):
        return step_to(v0, target, acc * dt)
    if abs(dv) <= abs(v0):
        return step_to(v0, target, dec * dt)
    t0 = abs(v0) / dec
    if t0 >= dt * (1.0 - 1e-9):
        return step_to(v0, 0.0, dec * dt)
    mag = min(abs(target), acc * (dt - t0))
    return mag if target > 0 else -mag


def parse(lines):
    cfg, joints, inject, rows, header = {}, [], [], [], None
    for line in lines:
        if line.startswith("# joint"):
            joints.append({k: float(v) for k, v in (t.split("=") for t in line.split()[3:])})
        elif line.startswith("# inject"):
            inject.append({k: int(v) for k, v in (t.split("=") for t in line.split()[2:])})
        elif line.startswith("#"):
            cfg = dict(t.split("=") for t in line[1:].split())
        elif header is None:
            header = line.strip().split(",")
        elif line.strip():
            rows.append(dict(zip(header, line.strip().split(","))))
    return cfg, joints, inject, rows


def replay(cfg, J, inject, rows):
    n, dt = int(cfg["n"]), float(cfg["dt"])
    tau_lag, L, W = float(cfg["lag_tau"]), int(cfg["latency"]), int(cfg["watchdog"])
    sp, sv = float(cfg["noise_pos"]), float(cfg["noise_vel"])
    rng = Rng(int(cfg["seed"]))
    q = [j["q0"] for j in J]
    v, r, u = [0.0] * n, [0.0] * n, [0.0] * n
    flt = [0] * n
    state, fault, last_id, have_id, missed = READY, F_NONE, 0, False, 0
    line = [None] * (L + 1)
    last_fb = None
    bad = 0

    def raise_fault(code):
        nonlocal state, fault
        if fault == F_NONE:
            fault = code
        if state == SERVOING:
            state = BRAKING
        elif state not in (BRAKING, FAULT):
            state = FAULT

    for k, row in enumerate(rows):
        state_in = state
        freeze = silent = drop = False
        for inj in inject:
            active = k >= inj["at"] and (inj["duration"] == 0 or k - inj["at"] < inj["duration"])
            if inj["kind"] == 1 and k == inj["at"]:
                flt[inj["joint"]] |= ACTUATOR
                raise_fault(F_INJECTED)
            freeze |= inj["kind"] == 2 and active
            silent |= inj["kind"] == 3 and active
            drop |= inj["kind"] == 4 and active
        cmd = None
        if row["has_cmd"] == "1" and not drop:
            cmd = {"id": int(row["cmd_id"]), "n": int(row["cmd_n"]),
                   "flags": [int(row[f"flags{j}"]) for j in range(n)],
                   "u": [float(row[f"u{j}"]) for j in range(n)]}
        line[k % (L + 1)] = cmd
        d = line[(k - L) % (L + 1)] if k >= L else None
        line[(k - L) % (L + 1)] = None
        valid = False
        if d is not None and d["n"] == n and all(math.isfinite(x) for x in d["u"]):
            diff = (d["id"] - last_id) & 0xFFFFFFFF
            if not have_id or (diff != 0 and diff < 0x80000000):
                valid, last_id, have_id = True, d["id"], True

        def take(c):
            for j in range(n):
                flt[j] &= ~VEL_SAT
                if abs(c["u"][j]) > J[j]["vel"]:
                    flt[j] |= VEL_SAT
                u[j] = max(-J[j]["vel"], min(J[j]["vel"], c["u"][j]))

        if state == state_in:
            enabled = valid and all((f & ON) == ON for f in d["flags"])
            if state == READY and enabled:
                state, missed = SERVOING, 0
                r[:] = v[:]
                take(d)
            elif state == SERVOING:
                if valid:
                    missed = 0
                    if enabled:
                        take(d)
                    else:
                        state = BRAKING
                else:
                    missed += 1
                    if missed >= W:
                        raise_fault(F_WATCHDOG)
            elif state == FAULT and valid and any(f & CLEAR for f in d["flags"]):
                state, fault = READY, F_NONE
                flt = [0] * n
        lag = 1.0 - math.exp(-dt / tau_lag) if tau_lag > 0 else 1.0
        hit = False
        tau = [0.0] * n
        for j in range(n):
            v0 = v[j]
            if state == SERVOING:
                r[j] += (u[j] - r[j]) * lag
                v1 = rate_limit(v0, r[j], J[j]["acc"], J[j]["dec"], dt)
            elif state == BRAKING:
                v1 = rate_limit(v0, 0.0, J[j]["acc"], J[j]["dec"], dt)
                r[j], u[j] = v1, 0.0
            else:
                v1, r[j], u[j] = 0.0, 0.0, 0.0
            q1 = q[j] + 0.5 * dt * (v0 + v1)
            if q1 > J[j]["upper"]:
                q1, v1, hit = J[j]["upper"], 0.0, True
                flt[j] |= LIM_HIGH
            elif q1 < J[j]["lower"]:
                q1, v1, hit = J[j]["lower"], 0.0, True
                flt[j] |= LIM_LOW
            q[j], v[j] = q1, v1
            tau[j] = J[j]["inertia"] * (v1 - v0) / dt + J[j]["damping"] * v1
        if hit:
            raise_fault(F_LIMIT)
        if state == BRAKING and all(x == 0.0 for x in v):
            state = FAULT if fault != F_NONE else READY
        qm, vm = list(q), list(v)
        for j in range(n):
            if sp > 0:
                qm[j] += sp * rng.gauss()
            if sv > 0:
                vm[j] += sv * rng.gauss()
        fb = (last_id, state, fault, qm, vm, list(tau), list(flt))
        if not freeze or last_fb is None:
            last_fb = fb
        if silent:
            if row["rc"] != "-12":
                print(f"cycle {k}: expected no feedback (rc -12), trace has rc {row['rc']}")
                bad += 1
            continue
        fid, st, fc, qq, vv, tt, ff = last_fb
        got = (int(row["fb_id"]), int(row["state"]), int(row["fault"]))
        if got != (fid, st, fc) or row["rc"] != "0":
            print(f"cycle {k}: (frame, state, fault) trace {got} rc {row['rc']}, model {(fid, st, fc)}")
            bad += 1
        for j in range(n):
            for name, want in (("q", qq[j]), ("v", vv[j]), ("tau", tt[j])):
                x = float(row[f"{name}{j}"])
                if not abs(x - want) <= 1e-9 * (1 + abs(want)):
                    print(f"cycle {k}: {name}{j} trace {x!r} model {want!r}")
                    bad += 1
            if int(row[f"flt{j}"]) != ff[j]:
                print(f"cycle {k}: flt{j} trace {row[f'flt{j}']} model {ff[j]}")
                bad += 1
        if bad > 20:
            break
    return bad, state


def main():
    out = subprocess.run(sys.argv[1:], check=True, capture_output=True, text=True).stdout
    cfg, joints, inject, rows = parse(out.splitlines())
    bad, _ = replay(cfg, joints, inject, rows)
    states = sorted({int(r["state"]) for r in rows if r["rc"] == "0"})
    print(f"{cfg['profile']}: {len(rows)} cycles replayed, states seen {states}, mismatches {bad}")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
