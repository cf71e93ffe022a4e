#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Issue 13: every system call of mcad's real-time thread, against the allow-list of docs/daemon.md.

Runs mcad (sim backend) on the negative task for 10 s: running ticks, the controller's fault (PDNN not
converged at 3.078 s), braking, then FAULT until the stop; DDS on (100 Hz, no subscriber needed) and the
CSV writer on, so every ring the loop feeds is in use. strace attaches to the loop thread alone
("mcad-loop", found in /proc) right after start-up and records each of its system calls until it exits.

Allowed while the loop runs: clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, ...) (the period),
futex(..., FUTEX_WAKE, 1) (waking the DDS publisher when a late tick found it parked instead of asleep
on the loop's grid; at most once per published tick) and
one restart_syscall (the sleep strace's attach interrupted). Allowed only after the last clock_nanosleep
(the thread ending: glibc's thread exit): rt_sigprocmask, madvise, exit. Anything else fails the test.

With two or more CPUs the cell sets rt.cpu: 1, and the test also checks the threads' CPU affinity: the loop
on CPU 1 alone, every other thread (supervisor/drainer, DDS publisher, Cyclone's) off CPU 1. The cell also
sets dds.priority: 10: the DDS bridge process's publisher (its main thread) must run SCHED_FIFO 10 and every
other thread of it (Cyclone's, which handle what peers send) SCHED_OTHER; with --no-rt, which mcad passes on
to the publisher, all SCHED_OTHER.

--can ARMSIM (in the vcan guest, tests/daemon/rt_syscalls_can.sh): the same on the CAN backend, cell
negative_vcan (no DDS): each arm's CAN FD bus a vcan answered by mca-armsim in lockstep (no watchdog, so the
slowness strace and TCG add cannot trip one). Allowed besides: sendto (the command) and recvmmsg (the
feedback), both required. The fault may then be the PDNN's or an overrun's (strace slows every call of an
emulated CPU); the loop must still make no other call.

Tracer: strace on the host. In the guest (--can) the kernel's own syscall tracepoints (ftrace,
raw_syscalls:sys_enter filtered to the loop's thread id, read from tracefs after the run): strace there
could not attach to the loop thread (PTRACE_SEIZE: ESRCH, or attached and recorded nothing in a 1-CPU TCG
guest whose CPU the SCHED_FIFO loop holds), while the tracepoints record in the kernel, stop nothing and
need no CPU time of a tracer process during the run.

usage: test_rt_syscalls.py MCAD SOURCE_DIR DOMAIN [--can ARMSIM] [mcad options, e.g. --no-rt]
exit 0 pass, 1 fail, 77 skipped (no strace)."""
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from vcan_emulators import start_emulators  # noqa: E402

STEADY = {"clock_nanosleep", "futex", "restart_syscall"}
CAN_CALLS = {"sendto", "recvmmsg"}
THREAD_EXIT = {"rt_sigprocmask", "madvise", "exit"}
SECONDS = 10


def fail(msg):
    print("FAIL: " + msg)
    sys.exit(1)


def threads(pid):
    out = {}
    for tid in os.listdir(f"/proc/{pid}/task"):
        try:
            name = open(f"/proc/{pid}/task/{tid}/comm").read().strip()
            cpus = re.search(r"Cpus_allowed_list:\s*(\S+)", open(f"/proc/{pid}/task/{tid}/status").read()).group(1)
        except (OSError, AttributeError):
            continue
        out[int(tid)] = (name, cpus)
    return out


def sched_of(pid, tid):
    """(policy, rt priority) of a thread: /proc stat fields 41 and 40 (1 = SCHED_FIFO)."""
    try:
        f = open(f"/proc/{pid}/task/{tid}/stat").read().rsplit(")", 1)[1].split()
        return int(f[38]), int(f[37])
    except (OSError, IndexError, ValueError):
        return None


def cpu_list(s):
    cpus = set()
    for part in s.split(","):
        a, _, b = part.partition("-")
        cpus.update(range(int(a), int(b or a) + 1))
    return cpus


NOTHING_TRACED = 75


def ns_of(pid):
    try:
        return os.readlink(f"/proc/{pid}/ns/pid")
    except OSError as e:
        return f"? ({e.strerror})"


TRACEFS = "/sys/kernel/tracing"


def syscall_names():
    """{number: name} of this machine's system calls (the kernel headers of the build)."""
    names = {}
    for hdr in ("/usr/include/x86_64-linux-gnu/asm/unistd_64.h", "/usr/include/asm/unistd_64.h"):
        try:
            for m in re.finditer(r"#define __NR_(\w+) (\d+)", open(hdr).read()):
                names[int(m.group(2))] = m.group(1)
            return names
        except OSError:
            continue
    return names


class Ftrace:
    """raw_syscalls:sys_enter of one thread, recorded by the kernel into the tracefs ring buffer."""

    def __init__(self):
        if not os.path.isdir(os.path.join(TRACEFS, "events")):
            os.makedirs(TRACEFS, exist_ok=True)
            subprocess.run(["mount", "-t", "tracefs", "nodev", TRACEFS], check=False)
        self.ev = os.path.join(TRACEFS, "events/raw_syscalls/sys_enter")
        if not os.path.isdir(self.ev):
            raise OSError(f"no {self.ev} (kernel without syscall tracepoints or no tracefs)")
        self.w("tracing_on", "0")
        self.w("trace", "")
        self.w("buffer_size_kb", "65536")  # per CPU: 10 s of ~3 calls a tick need ~6 MB

    def w(self, name, val, base=TRACEFS):
        with open(os.path.join(base, name), "w") as f:
            f.write(val)

    def start(self, tid):
        self.w("filter", f"common_pid == {tid}", self.ev)
        self.w("enable", "1", self.ev)
        self.w("tracing_on", "1")

    def stop(self, out):
        self.w("tracing_on", "0")
        self.w("enable", "0", self.ev)
        self.w("filter", "0", self.ev)
        with open(os.path.join(TRACEFS, "trace")) as f, open(out, "w") as o:
            o.write(f.read())
        lost = 0
        for cpu in os.listdir(os.path.join(TRACEFS, "per_cpu")):
            with open(os.path.join(TRACEFS, "per_cpu", cpu, "stats")) as f:
                m = re.search(r"overrun: (\d+)", f.read())
            lost += int(m.group(1)) if m else 0
        return lost


def ftrace_calls(path, names):
    """[(name, strace-like line)] from a tracefs trace of sys_enter events ("NR 230 (1, 1, ...)")."""
    calls = []
    for line in open(path):
        m = re.search(r"sys_enter: NR (\d+) \(([^)]*)\)", line)
        if not m:
            continue
        nr = int(m.group(1))
        args = [int(a, 16) for a in m.group(2).split(",")]
        name = names.get(nr, f"syscall_{nr}")
        if name == "clock_nanosleep":
            text = f"clock_nanosleep({'CLOCK_MONOTONIC' if args[0] == 1 else args[0]}, " \
                   f"{'TIMER_ABSTIME' if args[1] == 1 else args[1]}, ...)"
        elif name == "futex":
            op = {1: "FUTEX_WAKE", 129: "FUTEX_WAKE_PRIVATE"}.get(args[1], hex(args[1]))
            text = f"futex({args[0]:#x}, {op}, {args[2]})"
        else:
            text = f"{name}({', '.join(hex(a) for a in args)})"
        calls.append((name, text))
    return calls


def main():
    mcad, src, domain = sys.argv[1], os.path.abspath(sys.argv[2]), sys.argv[3]
    extra = sys.argv[4:]
    armsim = None
    if "--can" in extra:
        i = extra.index("--can")
        armsim = extra[i + 1]
        del extra[i:i + 2]
    ftrace = None
    strace = shutil.which("strace")
    if armsim:
        try:
            ftrace = Ftrace()
        except OSError as e:
            fail(f"the guest kernel's syscall tracepoints are not usable: {e}")
    elif not strace:
        print("SKIP: strace not installed")
        return 77
    pin = (os.cpu_count() or 1) >= 2
    tmp = tempfile.mkdtemp(prefix="mca-rt-syscalls-")
    cell = os.path.join(tmp, "cell.yaml")
    cell_src = os.path.join(src, "config/cells", "negative_vcan.yaml" if armsim else "negative_sim.yaml")
    emulators = start_emulators(armsim, cell_src, tmp) if armsim else []
    if armsim:
        extra = extra + ["--no-dds"]
    text = open(cell_src).read()
    text = text.replace("../", os.path.join(src, "config") + "/")
    text = re.sub(r"domain: *\d+", f"domain: {domain}", text)
    if pin:
        text = re.sub(r"cpu: *-?\d+", "cpu: 1", text)
    # dds.priority: the publisher thread SCHED_FIFO 10, below the loop's 80; Cyclone's threads SCHED_OTHER
    dds_fifo = not armsim and "--no-rt" not in extra
    text = re.sub(r"(\n  publish_divisor: *\d+[^\n]*)", r"\1\n  priority: 10", text, count=1)
    if armsim:
        # strace stops the loop at every call of an emulated CPU: the longest supervision limits, so that
        # the task runs a while before a fault (seen with the cell's 20 cycles: lost feedback at 0.12 s)
        text = re.sub(r"lost_feedback_cycles: *\d+", "lost_feedback_cycles: 1000", text)
        text = re.sub(r"overrun_limit: *\d+", "overrun_limit: 1000", text)
    open(cell, "w").write(text)
    trace = os.path.join(tmp, "loop.strace")
    err = open(os.path.join(tmp, "mcad.err"), "w+")
    p = subprocess.Popen([mcad, "--csv", os.path.join(tmp, "run.csv"), "--stop-after", str(SECONDS)] + extra + [cell],
                         stderr=err, stdout=subprocess.DEVNULL)
    loop = None
    t0 = time.time()
    while loop is None and time.time() - t0 < 30 and p.poll() is None:
        seen = threads(p.pid)
        loop = next((tid for tid, (name, _) in seen.items() if name == "mcad-loop"), None)
        time.sleep(0.01)
    found_in = {tid: name for tid, (name, _) in seen.items()} if loop else {}
    if loop is None:
        p.kill()
        err.seek(0)
        fail("no mcad-loop thread appeared: " + err.read()[-2000:])
    # strace's attach once failed in a starved guest (PTRACE_SEIZE: No such process, for a thread that ran on
    # for 10 s): an attach that fails is tried again, with the thread looked up afresh, and said so
    st = None
    for attempt in range(0 if ftrace else 3):
        st = subprocess.Popen([strace, "-qq", "-p", str(loop), "-o", trace], stderr=subprocess.PIPE, text=True)
        time.sleep(1.0)
        if st.poll() is None or p.poll() is not None:
            break
        print(f"strace could not attach to thread {loop} (attempt {attempt + 1}): {st.stderr.read().strip()}")
        loop = next((tid for tid, (name, _) in threads(p.pid).items() if name == "mcad-loop"), loop)
    if ftrace:
        ftrace.start(loop)
    affinity = threads(p.pid)
    # the DDS bridge is a child process of mcad's main thread; its threads must be off the loop's CPU too
    try:
        children = open(f"/proc/{p.pid}/task/{p.pid}/children").read().split()
    except OSError:
        children = []
    policies = {}
    for child in children:
        affinity.update({tid: ("bridge:" + name, cpus) for tid, (name, cpus) in threads(int(child)).items()})
        policies.update({tid: (name, sched_of(int(child), tid), tid == int(child))
                         for tid, (name, _) in threads(int(child)).items()})
    mcad_ns = ns_of(p.pid)  # while it runs (diagnostics when strace traces nothing)
    rc = p.wait(timeout=300)
    lost = 0
    if ftrace:
        lost = ftrace.stop(trace)
    else:
        st.wait(timeout=60)
    for e in emulators:
        e.terminate()
        e.wait(timeout=30)
    err.seek(0)
    log = err.read()
    print("\n".join(l for l in log.splitlines() if "summary" in l or "<3>" in l or "<4>" in l))
    bad = []
    if armsim:
        if rc != 3 or "fault" not in log:
            bad.append(f"mcad: exit {rc}, expected 3 with a fault (the PDNN's, or overruns under strace)")
    elif rc != 3 or "PDNN residual" not in log:
        bad.append(f"mcad: exit {rc}, expected 3 with the PDNN fault of the negative task")

    if pin:
        for tid, (name, cpus) in sorted(affinity.items()):
            c = cpu_list(cpus)
            ok = c == {1} if name == "mcad-loop" else 1 not in c
            print(f"thread {tid} {name:16s} CPUs {cpus}{'' if ok else '   <- wrong'}")
            if not ok:
                bad.append(f"thread {name} on CPUs {cpus} (rt.cpu 1: the loop alone on 1, every other thread off it)")

    if not armsim:
        if len(policies) < 2:
            bad.append(f"{len(policies)} threads of the DDS bridge process found (the publisher and Cyclone's)")
        for tid, (name, sp, publisher) in sorted(policies.items()):
            want = (1, 10) if dds_fifo and publisher else (0, 0)
            what = "publisher" if publisher else "other"
            print(f"bridge thread {tid} {name:16s} ({what}) policy/priority {sp}{'' if sp == want else '   <- wrong'}")
            if sp != want:
                bad.append(f"bridge thread {name} ({what}): policy/priority {sp}, expected {want} (dds.priority 10"
                           f"{'' if dds_fifo else ', but --no-rt'})")

    calls = []
    if ftrace:
        calls = ftrace_calls(trace, syscall_names())
        if lost:
            bad.append(f"the trace buffer lost {lost} events: not every call was seen")
    else:
        for line in open(trace):
            m = re.match(r"(\w+)\((.*)", line)
            if m:
                calls.append((m.group(1), line.strip()))
            elif line.strip() and not line.startswith("+++"):
                bad.append(f"unexpected trace line: {line.strip()}")
    counts = {}
    for name, _ in calls:
        counts[name] = counts.get(name, 0) + 1
    print(f"loop thread system calls ({'kernel tracepoints' if ftrace else 'strace'}):", ", ".join(f"{k} {v}" for k, v in sorted(counts.items())))
    if not calls and not ftrace:
        # strace recorded not one call of a loop that ran (seen twice in CI, in a guest starved by a busy host,
        # once with PTRACE_SEIZE failing): a tracer failure, not a verdict on mcad
        def first_line(path):
            try:
                return open(path).read().splitlines()[0]
            except (OSError, IndexError):
                return "?"
        sv = subprocess.run([strace, "-V"], capture_output=True, text=True).stdout.splitlines()
        print(f"strace traced nothing (its stderr: {st.stderr.read().strip() if st.stderr else ''!r}; "
              f"load {open('/proc/loadavg').read().split()[0]}; {sv[0] if sv else 'strace -V ?'}; "
              f"yama ptrace_scope {first_line('/proc/sys/kernel/yama/ptrace_scope')}; "
              f"{first_line('/proc/version')[:60]}; loop tid {loop}, pid {p.pid}; threads when found {found_in}; "
              f"after the run {affinity and {t: n for t, (n, _) in affinity.items()}}; pid namespace of mcad "
              f"{mcad_ns}, of this test {ns_of(os.getpid())})")
        return NOTHING_TRACED
    sleeps = [i for i, (n, _) in enumerate(calls) if n == "clock_nanosleep"]
    last_sleep = sleeps[-1] if sleeps else -1
    restarts = 0
    for i, (name, line) in enumerate(calls):
        if name == "clock_nanosleep":
            if "CLOCK_MONOTONIC, TIMER_ABSTIME" not in line:
                bad.append(f"clock_nanosleep not absolute on CLOCK_MONOTONIC: {line}")
        elif name == "futex":
            # shared (not _PRIVATE): the word is in the memfd mcad shares with mca-dds-bridge
            if "FUTEX_WAKE, 1)" not in line:
                bad.append(f"futex other than one FUTEX_WAKE: {line}")
        elif name == "restart_syscall":
            restarts += 1
            if restarts > 1 or "clock_nanosleep" not in line:
                bad.append(f"restart_syscall other than the one sleep strace interrupted: {line}")
        elif armsim and name in CAN_CALLS:
            pass
        elif name in THREAD_EXIT:
            if i < last_sleep:
                bad.append(f"{name} while the loop runs (allowed only as the thread ends): {line}")
        else:
            bad.append(f"not on the allow-list (docs/daemon.md): {line}")
    n_sleep = len(sleeps)
    # on the emulated CPU under strace the loop skips periods (each call is stopped and resumed): fewer
    want_sleeps = 1000 if armsim else (SECONDS - 2) * 1000
    if n_sleep < want_sleeps:
        bad.append(f"only {n_sleep} clock_nanosleep calls traced (expected at least {want_sleeps})")
    for c in sorted(CAN_CALLS) if armsim else []:
        if counts.get(c, 0) < n_sleep // 2:
            bad.append(f"{counts.get(c, 0)} {c} calls for {n_sleep} ticks: the CAN backend should make about one a tick")
    n_wake = counts.get("futex", 0)
    if n_wake > n_sleep // 10 + 2:
        bad.append(f"{n_wake} futex wakes for {n_sleep} ticks: more than one per published tick (divisor 10)")
    for b in bad[:20]:
        print("FAIL: " + b)
    if bad:
        print(f"trace kept in {trace}")
        return 1
    shutil.rmtree(tmp, ignore_errors=True)
    can = f", {counts.get('sendto', 0)} sendto, {counts.get('recvmmsg', 0)} recvmmsg (CAN)" if armsim else ""
    print(f"OK: {n_sleep} clock_nanosleep, {n_wake} futex wakes (one per published tick at most){can}, nothing "
          "else while the loop ran")
    return 0


if __name__ == "__main__":
    rc = main()
    if rc == NOTHING_TRACED:
        print("the tracer traced nothing: the whole run once more")
        rc = main()
    if rc == NOTHING_TRACED:
        print("SKIP: strace traced nothing on two runs (a starved guest's tracer): the system calls are not judged")
        rc = 77
    sys.exit(rc)
