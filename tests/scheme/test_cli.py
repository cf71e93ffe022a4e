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


def expect_at(path, text, needle, words):
    """Write text to path; mca-sim must exit 1 with an error naming path:LINE: (LINE: the first line holding
    needle, counted here) and every word."""
    open(path, "w").write(text)
    line = next(i + 1 for i, l in enumerate(text.split("\n")) if needle in l)
    expect([sim_bin, "--scenario", path], 1, ["%s:%d: " % (path, line)] + words)


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
        open(bad, "w").write(text.replace("kind: hold", "kind: hold\n      radius: [1]"))
        expect([sim, "--scenario", bad], 1, [bad, "radius", "line"])
        open(bad, "w").write(text.replace("pa10plus.urdf", "nothere.urdf"))
        expect([sim, "--scenario", bad], 1, ["nothere.urdf"])
        open(bad, "w").write(text.replace("q0: [0.0, 0.785", "q0: [0.785"))
        expect([sim, "--scenario", bad], 1, ["q0", "7 values"])
        open(bad, "w").write("name: x\nduration: [\n")
        expect([sim, "--scenario", bad], 1, [bad])
        # issue 16: an empty or comment-only file was a NULL dereference (SIGSEGV)
        open(bad, "w").write("")
        expect([sim, "--scenario", bad], 1, [bad + ": empty document"])
        open(bad, "w").write("# a scenario\n\n  # to be written\n")
        expect([sim, "--scenario", bad], 1, [bad + ": empty document"])
        # issue 16: a line over 1023 characters (fgets split it) shifted the line numbers of range errors
        expect_at(bad, "# " + "x" * 3000 + "\n" + text.replace("d2: 0.12", "d2: 0.01"), "d2: 0.01", ["d1/d2"])
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
