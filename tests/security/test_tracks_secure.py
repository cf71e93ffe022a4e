#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""dds.tracks_secure: streamed bodies reach the rows only from an authenticated writer (docs/scheme.md
section 14, docs/dds.md "Streamed bodies in").

In a network namespace of its own (tests/ros2/netns.sh), with the files of config/security/make_security.sh:
mcad runs config/cells/tracks_secure_sim.yaml (DDS Security, config/dds/secure.xml; lost_after 2 s). The
commander identity streams a sphere 8 m away (mca-target-pub --sphere) for 4 s: mcad's CSV has the sphere as
the body of least margin, at the distance that sphere has. A participant without credentials streams a
sphere 1 m from the arms from mcad's start to the end: none of its samples is taken (no row's body is that
near), and once the commander stops, the stale track grows (its distance falls) and after lost_after the
arms stop as the fault "streamed bodies lost", while that participant is still sending.

usage: test_tracks_secure.py MCAD TARGET_PUB SOURCE_DIR DOMAIN"""
import csv
import os
import signal
import subprocess
import sys
import tempfile
import time

MCAD, PUB, SRC, DOMAIN = sys.argv[1:5]
NS = "tracks_secure_sim"
TOPIC = f"rt/{NS}/tracked_bodies"
FAILS = []


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what, flush=True)
    if not cond:
        FAILS.append(what)


def pub(env, config, sphere, seconds, match_timeout):
    return subprocess.Popen([PUB, "--domain", DOMAIN, "--config", config, "--topic", TOPIC, "--sphere", sphere,
                             "--hz", "50", "--duration", str(seconds), "--match-timeout", str(match_timeout)],
                            env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def main():
    tmp = tempfile.mkdtemp(prefix="mca-tracks-")
    sec = os.path.join(tmp, "security")
    r = subprocess.run([os.path.join(SRC, "config", "security", "make_security.sh"), sec], capture_output=True,
                       text=True)
    check(r.returncode == 0, f"make_security.sh made the files ({r.stderr.strip()[-300:]})")
    env = dict(os.environ, MCA_SECURITY_DIR=sec)
    env.pop("CYCLONEDDS_URI", None)
    secure = os.path.join(SRC, "config", "dds", "secure.xml")
    plain = os.path.join(SRC, "config", "dds", "ros2.xml")
    cell = open(os.path.join(SRC, "config", "cells", "tracks_secure_sim.yaml")).read()
    cell = (cell.replace("../scenarios/", f"{SRC}/config/scenarios/")
            .replace("config: ../dds/secure.xml", f"config: {secure}")
            .replace("domain: 0", f"domain: {DOMAIN}").replace("priority: 80", "priority: 60")
            .replace("lost_after: 0.5 ", "lost_after: 2.0 "))
    cell_path = os.path.join(tmp, "cell.yaml")
    csv_path = os.path.join(tmp, "mcad.csv")
    with open(cell_path, "w") as f:
        f.write(cell)
    # the commander first, waiting for mcad's reader; then mcad; the participant without credentials beside
    cmd = pub(dict(env, MCA_DDS_IDENTITY="commander"), secure, "8.0,0.0,0.9,0.3", 4.0, 40)
    time.sleep(0.5)
    m = subprocess.Popen([MCAD, "--csv", csv_path, cell_path], env=dict(env, MCA_DDS_IDENTITY="mcad"),
                         stderr=subprocess.PIPE, text=True)
    rogue = pub(env, plain, "1.0,0.0,0.9,0.3", 20.0, 1.0)
    out, err = cmd.communicate(timeout=60)
    print("     commander: " + " | ".join(out.strip().splitlines()))
    check(cmd.returncode == 0, f"the commander's sphere matched mcad's reader and was sent (exit {cmd.returncode})")
    # lost_after (2 s) after its last sample, plus margin
    t_end = time.monotonic() + 8.0
    while time.monotonic() < t_end and m.poll() is None:
        time.sleep(0.2)
    rogue_alive = rogue.poll() is None
    m.send_signal(signal.SIGTERM)
    try:
        _, merr = m.communicate(timeout=30)
    except subprocess.TimeoutExpired:
        m.kill()
        _, merr = m.communicate()
    rogue.kill()
    rogue.communicate()
    lines = merr.splitlines()
    for l in lines:
        if "fault" in l or "streamed" in l or "summary" in l[:20]:
            print("     mcad: " + l)
    check(rogue_alive, "the participant without credentials was still sending when mcad was stopped")
    lost = [l for l in lines if "streamed bodies lost" in l]
    check(len(lost) > 0, "mcad stopped the arms as 'streamed bodies lost' while the unauthenticated one sent")
    check(m.returncode == 3, f"mcad exited 3 (a fault; got {m.returncode})")
    with open(csv_path) as f:
        rows = list(csv.DictReader(f))
    withb = [(float(r["t"]), float(r["body_d"])) for r in rows if r["body_kind"] == "sphere"]
    check(len(withb) > 100, f"the commander's sphere reached the rows ({len(withb)} ticks with it)")
    if withb:
        near = min(d for _, d in withb)
        first = withb[0][1]
        # the rogue's sphere at 1 m would be within ~0.5 m of a link; the commander's is ~7 m away, and its
        # growth after the commander stopped takes it down by at most a few metres before the stop
        check(first > 6.0, f"the first body is the commander's 8 m sphere (link distance {first:.3f} m)")
        check(near > 1.0, f"no tick saw the unauthenticated sphere 1 m away (least body distance {near:.3f} m)")
        check(first - near > 1.0, f"the stale track grew before the stop ({first:.3f} m -> {near:.3f} m)")
    print("PASS" if not FAILS else f"FAIL: {len(FAILS)} check(s): {FAILS}")
    return 1 if FAILS else 0


if __name__ == "__main__":
    sys.exit(main())
