#!/usr/bin/env python3
"""mca-sim on bad command lines and bad scenario files: clear message naming the problem, non-zero exit,
no crash. usage: test_cli.py MCA_SIM SCENARIO_DIR"""
import os
import subprocess
import sys
import tempfile

FAILS = []


def expect(args, code, words):
    p = subprocess.run(args, capture_output=True, text=True, timeout=120)
    ok = p.returncode == code and all(w in p.stderr for w in words)
    print(("ok   " if ok else "FAIL ") + " ".join(args[1:]) + " -> %d: %s" % (p.returncode, p.stderr.strip()[:300]))
    if not ok:
        FAILS.append(args)


def expect_at(path, text, needle, words, nth=0):
    """Write text to path; mca-sim must exit 1 with an error naming path:LINE: (LINE: the nth line holding
    needle, counted here) and every word, and start nothing (no table on stdout)."""
    open(path, "w").write(text)
    line = [i + 1 for i, l in enumerate(text.split("\n")) if needle in l][nth]
    args = [sim_bin, "--scenario", path]
    p = subprocess.run(args, capture_output=True, text=True, timeout=120)
    want = "mca-sim: %s:%d: " % (path, line)
    ok = p.returncode == 1 and p.stderr.startswith(want) and all(w in p.stderr for w in words) and not p.stdout
    print(("ok   " if ok else "FAIL ") + "%s (line %d) -> %d: %s" % (needle, line, p.returncode, p.stderr.strip()[:300]))
    if not ok:
        FAILS.append(args + [needle])


def replace_nth(text, old, new, nth):
    """text with the nth (0-based) occurrence of old replaced by new"""
    at = -1
    for _ in range(nth + 1):
        at = text.index(old, at + 1)
    return text[:at] + new + text[at + len(old):]


sim_bin = None


def main():
    global sim_bin
    sim, sdir = sys.argv[1:3]
    sim_bin = sim
    good = os.path.join(sdir, "negative.yaml")
    expect([sim], 2, ["--scenario is required"])
    expect([sim, "--scenario"], 2, ["needs a value"])
    expect([sim, "--scenario", good, "--scheme", "foo"], 2, ["'foo'"])
    expect([sim, "--scenario", good, "--form", "diag"], 2, ["'diag'"])
    expect([sim, "--scenario", good, "--bogus", "1"], 2, ["unknown option"])
    expect([sim, "--scenario", good, "--dump-every", "x"], 2, ["--dump-every"])
    expect([sim, "--scenario", "/nonexistent.yaml"], 1, ["/nonexistent.yaml"])
    with tempfile.TemporaryDirectory() as tmp:
        bad = os.path.join(tmp, "bad.yaml")
        robots = os.path.join(os.path.dirname(os.path.abspath(sdir)), "robots") + "/"
        text = open(good).read().replace("../robots/", robots)
        open(bad, "w").write(text.replace("d2: 0.12", "d2: 0.01"))
        expect([sim, "--scenario", bad], 1, [bad, "d1/d2"])
        btext = text.replace("kind: hold", "kind: hold\n      radius: [1]")
        open(bad, "w").write(btext)
        # file:line:column of the value, then the field (the cell loader's form)
        blines = btext.split("\n")
        bl = next(i for i, ln in enumerate(blines) if "radius: [1]" in ln)
        barm = sum(1 for ln in blines[:bl] if ln.lstrip().startswith("- name:")) - 1
        expect([sim, "--scenario", bad], 1,
               ["%s:%d:%d: arms[%d].path.radius: " % (bad, bl + 1, blines[bl].index("[") + 1, barm)])
        open(bad, "w").write(text.replace("pa10plus.urdf", "nothere.urdf"))
        expect([sim, "--scenario", bad], 1, ["nothere.urdf"])
        open(bad, "w").write(text.replace("q0: [0.0, 0.785", "q0: [0.785"))
        expect([sim, "--scenario", bad], 1, ["q0", "7 values"])
        open(bad, "w").write("name: x\nduration: [\n")
        expect([sim, "--scenario", bad], 1, [bad])
        # an empty or comment-only file: named, not a NULL dereference (SIGSEGV)
        open(bad, "w").write("")
        expect([sim, "--scenario", bad], 1, [bad + ":0: (document): empty document"])
        open(bad, "w").write("# a scenario\n\n  # to be written\n")
        expect([sim, "--scenario", bad], 1, [bad + ":0: (document): empty document"])
        # a line over 1023 characters (a reader that fgets would split it) must not shift the line numbers of range errors
        # (d1 >= d2 names the line of d1)
        expect_at(bad, "# " + "x" * 3000 + "\n" + text.replace("d2: 0.12", "d2: 0.01"), "d1: 0.05", ["d1/d2"])
        # every number has a range (docs/scheme.md section 3), named with file, line and field
        for old_, new_, field, why in (
                ("duration: 8.0", "duration: 1e7", "duration", "must be in (0, 3600] s (got 10000000)"),
                ("dt: 0.001", "dt: 1e-12", "dt", "must be in [0.0001, 0.1] s (got 1e-12)"),
                ("dt: 0.001", "dt: 1", "dt", "must be in [0.0001, 0.1] s (got 1)"),
                ("d1: 0.05", "d1: -1", "d1", "must be in [0, 1] m (got -1)"),
                ("d2: 0.12", "d2: 1e308", "d2", "must be in (0, 2] m (got 1e+308)"),
                ("K: 20", "K: 1e308", "K", "must be in [0, 1000] 1/s (got 1e+308)"),
                ("epsilon: 5", "epsilon: 1e308", "epsilon", "must be in (0, 1000] 1/s (got 1e+308)"),
                ("K: 20", "K: 20\nv_normal: 1e308", "v_normal", "must be in (0, 10] m/s (got 1e+308)"),
                ("K: 20", "K: 20\nv_floor: -0.5", "v_floor", "must be in [0, 10] m/s (got -0.5)"),
                ("sample_times: [0, 2, 4, 6, 8]", "sample_times: [0, 2, 1e9]", "sample_times[2]",
                 "must be in [0, 3600] s (got 1000000000)"),
                ("base_xyz: [0.15556349186143745, -0.7, 0.0]", "base_xyz: [0.15556349186143745, -0.7, 1e308]",
                 "arms[1].base_xyz[2]", "must be in [-100, 100] m (got 1e+308)"),
                ("- [0.0, 0.8, 0.0]", "- [0.0, 1e300, 0.0]", "arms[1].path.points[0][1]",
                 "must be in [-100, 100] m (got 1e+300)"),
                ("durations: [6.0]", "durations: [1e9]", "arms[1].path.durations[0]",
                 "must be in (0, 3600] s (got 1000000000)"),
                ("      relative: true", "      relative: true\n      t0: -3", "arms[1].path.t0",
                 "must be in [0, 3600] s (got -3)")):
            new_line = new_.split("\n")[-1]
            expect_at(bad, text.replace(old_, new_), new_line, ["%s: %s" % (field, why)])
        # the tick count: an hour at 0.1 ms is 36 million ticks
        expect_at(bad, text.replace("duration: 8.0", "duration: 3000").replace("dt: 0.001", "dt: 0.0001"),
                  "duration: 3000", ["duration: 3000 s at a tick of 0.0001 s is 30000000 ticks, more than 3600000"])
        # the circles of task 1: the second arm's keys are found on the second arm's lines
        circles = open(os.path.join(sdir, "cross_circles.yaml")).read().replace("../robots/", robots)
        for old_, new_, field, why in (
                ("radius: 0.2", "radius: 1e308", "arms[1].path.radius", "must be in (0, 10] m (got 1e+308)"),
                ("period: 10.0", "period: 1e7", "arms[1].path.period", "must be in (0, 3600] s (got 10000000)"),
                ("      v: [-0.5", "      turns: 1e9\n      v: [-0.5", "arms[1].path.turns",
                 "must be in (0, 1000] (got 1000000000)")):
            nth = 1 if circles.count(old_) > 1 else 0
            needle = new_.split("\n")[0]
            expect_at(bad, replace_nth(circles, old_, new_, nth), needle, ["%s: %s" % (field, why)])
        rpy = circles.replace("    base_xyz: [0.45, -0.5, 0.0]\n", "    base_xyz: [0.45, -0.5, 0.0]\n    base_rpy: [0, 7, 0]\n")
        expect_at(bad, rpy, "base_rpy: [0, 7, 0]", ["arms[1].base_rpy[1]: must be in [-6.28319, 6.28319] rad (got 7)"])
    # a --duration override gets the same range and tick count as the file's (exit 2: a bad command line)
    expect([sim, "--scenario", good, "--duration", "1e7"], 2, ["--duration: must be in (0, 3600] s (got 10000000)"])
    # --csv naming: one scheme writes OUT as given; several write OUT-<scheme>.csv, with or without a .csv
    # suffix on OUT (docs/scheme.md section 6)
    with tempfile.TemporaryDirectory() as tmp:
        for out, schemes, expect_files in (("one.csv", "mca", ["one.csv"]),
                                           ("two.csv", "mvn,mca", ["two-mvn.csv", "two-mca.csv"]),
                                           ("three", "mvn,mca", ["three-mvn.csv", "three-mca.csv"])):
            p = subprocess.run([sim, "--scenario", good, "--scheme", schemes, "--duration", "0.05", "--csv",
                                os.path.join(tmp, out)], capture_output=True, text=True, timeout=120)
            made = sorted(os.listdir(tmp))
            ok = p.returncode == 0 and all(f in made for f in expect_files)
            ok = ok and all(open(os.path.join(tmp, f)).readline().startswith("t,") for f in expect_files)
            print(("ok   " if ok else "FAIL ") + "--scheme %s --csv %s -> %s (files: %s)" % (schemes, out,
                                                                                          expect_files, made))
            if not ok:
                FAILS.append("--csv " + out)
            for f in made:
                os.remove(os.path.join(tmp, f))
    # a good run succeeds and prints the table
    p = subprocess.run([sim, "--scenario", good, "--scheme", "mca", "--duration", "0.5"], capture_output=True,
                       text=True, timeout=120)
    ok = p.returncode == 0 and "Table I" in p.stdout
    print(("ok   " if ok else "FAIL ") + "short good run")
    if not ok:
        FAILS.append("good run")
    return 1 if FAILS else 0


if __name__ == "__main__":
    sys.exit(main())
