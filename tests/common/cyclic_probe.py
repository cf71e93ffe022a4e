# SPDX-License-Identifier: MIT
"""The machine's own stalls, timed: cyclictest beside a real-time test, for telling "the product stalled"
from "this VM froze its vCPUs" (1-15 ms a few times a minute here, ~100 ms when both vCPUs are busy).

cyclictest runs one thread per CPU at the priority of the loop under test, 1 ms interval, and records every
wake-up later than spike_us with its CLOCK_MONOTONIC time; a stall of the loop that cyclictest saw at the
same moment is the machine's. Used by tests/daemon/test_sigusr1.py (time lost to stalls); overruns are judged by
tools/mca-sweep/cyclic_late.py (sweep_rt.py, tests/dds/test_bridge_crash.py)."""
import os
import re
import signal
import subprocess


class CyclicProbe:
    def __init__(self, prio, spike_us=2000):
        self.ncpu = os.cpu_count() or 1
        self.spike_us = spike_us
        self.spikes = []  # (cpu, latency us, wake-up CLOCK_MONOTONIC us)
        self.rc = None
        self.out = ""
        self.p = subprocess.Popen(["cyclictest", "-m", "-q", "-p", str(prio), "-i", "1000", "-d", "0",
                                   "-t", str(self.ncpu), "-a", f"0-{self.ncpu - 1}", f"--spike={spike_us}",
                                   "--spike-nodes=100000"],
                                  stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)

    def stop(self):
        """End cyclictest; returns True if it ran (then self.spikes holds what it saw)."""
        self.p.send_signal(signal.SIGINT)
        try:
            self.out = self.p.communicate(timeout=20)[0]
        except subprocess.TimeoutExpired:
            self.p.kill()
            self.out = self.p.communicate()[0]
        self.rc = self.p.returncode
        # "T: 1 Spike:    1082: TS:  11682978928"
        self.spikes = [(int(c), int(lat), int(ts)) for c, lat, ts in
                       re.findall(r"T:\s*(\d+) Spike:\s*(\d+): TS:\s*(\d+)", self.out)]
        return self.rc == 0 and "T: 0" in self.out

    def describe(self):
        return (f"cyclictest ran beside it (exit {self.rc}): {len(self.spikes)} wake-ups later than "
                f"{self.spike_us} us on {self.ncpu} CPUs, the longest "
                f"{max((x[1] for x in self.spikes), default=0) / 1e3:.2f} ms"
                + ("" if self.rc == 0 else ": " + self.out.strip()[-300:]))

    def near(self, end_us, gap_us, slack_us=20000):
        """Spikes that explain a loop gap of gap_us ending at end_us (CLOCK_MONOTONIC): within slack_us of
        the stalled interval, at least half the gap's excess over a 1 ms period late."""
        return [x for x in self.spikes if end_us - gap_us - slack_us <= x[2] <= end_us + slack_us
                and x[1] >= (gap_us - 1000) / 2]

    def stalled_us(self, t0_us=None, t1_us=None):
        """The most time one CPU's cyclictest thread lost to late wake-ups (sum of its spikes) in [t0, t1]."""
        per = {}
        for c, lat, ts in self.spikes:
            if (t0_us is None or ts >= t0_us) and (t1_us is None or ts <= t1_us):
                per[c] = per.get(c, 0) + lat
        return max(per.values(), default=0)
