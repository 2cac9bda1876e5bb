"""Run machinery of the validation studies (host/validate.py): one case is one
run folder, run or resumed once by advance(), with a lock against a second
process, a FAILED marker when capdem exits with an error, and every
invocation's wall time, CPU time, steps and load average in timing.json.
Shared by study 1 (validate_study1.py) and studies 2-4 (validate_deposit.py),
with the helpers of their tables (pm, ref, markdown_into)."""
import datetime
import json
import os
import resource
import subprocess
import threading
import time

import capdem_h5

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ARM_D = 0.005  # arm diameter [m] (docs/references.md, Contact law)
PHASE_DONE = 7  # the protocols' last phase (/walls/control slot 0): the run is done


def now():
    return datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")


def shape_props(capdem, shape, alpha, density=1000.0):
    """`capdem shape ... --json` of a shape of arm diameter ARM_D (volume [m^3],
    tip_length [m], mass [kg], ...): capdem's own mass properties."""
    cmd = [capdem, "shape", shape, "--diameter", "%g" % ARM_D, "--density", "%g" % density, "--json"]
    if shape != "sphere":
        cmd[3:3] = ["--aspect", "%g" % alpha]
    return json.loads(subprocess.run(cmd, capture_output=True, text=True, check=True).stdout)


class RunCase:
    """The folder OUT/NAME of one run: config.yaml (written by the subclass's
    write_config), run.h5, run.log, timing.json, analysis.json and the lock
    naming the processes that run it."""

    def __init__(self, name, out, seed):
        self.name, self.seed = name, seed
        self.dir = os.path.join(out, name)
        self.config = os.path.join(self.dir, "config.yaml")
        self.h5 = os.path.join(self.dir, "run.h5")
        self.log = os.path.join(self.dir, "run.log")
        self.timing = os.path.join(self.dir, "timing.json")
        self.analysis = os.path.join(self.dir, "analysis.json")
        self.lock = os.path.join(self.dir, "lock")

    def write_config(self, steps):
        """Writes config.yaml with a step cap of `steps`."""
        raise NotImplementedError


def run_state(h5path, locking=True):
    """(complete snapshots, last step, last phase) of a run file, or None.
    locking=False reads a file another process is writing (only committed
    snapshots count) and stays silent when it cannot."""
    if not os.path.exists(h5path):
        return None
    try:
        with capdem_h5.open_run(h5path, locking=locking) as f:
            control = capdem_h5.dataset(f, "control_value")
            n = min(capdem_h5.snapshot_count(f), len(control))
            if n == 0:
                return (0, 0, -1)
            return (n, capdem_h5.step(f, n - 1), int(round(float(control[n - 1][0]))))
    except (OSError, KeyError, TypeError, ValueError, capdem_h5.LayoutError) as e:
        if locking:
            print("  %s: unreadable (%s)" % (h5path, e), flush=True)
        return None


def peek(h5path):
    """Progress of a run file another process is writing."""
    st = run_state(h5path, locking=False)
    if st is None:
        return "run file not readable now"
    return "last snapshot at step %d" % st[1] if st[0] else "no snapshot yet"


def lock_holder(case):
    """PID of a live process that holds the case (the driver that took it, or
    its capdem child, which outlives a killed driver), or None: stale locks
    are ignored."""
    try:
        with open(case.lock) as f:
            pids = [int(w.split("=")[1]) for w in f.read().split() if w.startswith("pid=")]
    except (OSError, ValueError, IndexError):
        return None
    for pid in pids:
        if pid == os.getpid():
            continue
        try:
            os.kill(pid, 0)
        except OSError:
            continue
        return pid
    return None


def cpu_seconds(pid):
    """User + system CPU time of a live process [s] (Linux /proc), or None."""
    try:
        with open("/proc/%d/stat" % pid) as f:
            fields = f.read().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
    except (OSError, ValueError, IndexError):
        return None


def wait_for(case, pid):
    """Wait until no live process holds the case.  When the process was a
    capdem whose driver was stopped (its driver's line is the lock's first),
    its segment goes into timing.json: start from the lock file, end and CPU
    time from the last poll (at most 5 s late)."""
    try:
        with open(case.lock) as f:
            lock_text = f.read()
        start = lock_text.split()[1]
    except (OSError, IndexError):
        lock_text, start = "", None
    st0 = run_state(case.h5, locking=False)
    cpu = None
    while lock_holder(case) is not None:
        c = cpu_seconds(pid)
        cpu = c if c is not None else cpu
        time.sleep(5)
    st1 = run_state(case.h5)
    if "pid=%d capdem" % pid in lock_text and start:
        t0 = datetime.datetime.strptime(start, "%Y-%m-%dT%H:%M:%SZ").replace(tzinfo=datetime.timezone.utc)
        wall = (datetime.datetime.now(datetime.timezone.utc) - t0).total_seconds()
        record_timing(case, {"start": start, "end": now(), "wall_s": round(wall, 1), "cpu_s": cpu, "rc": None,
                             "step_from": None, "step_to": st1[1] if st1 else None,
                             "phase": st1[2] if st1 else None, "threads": None, "loadavg_start": None,
                             "loadavg_end": os.getloadavg()[0], "cores": os.cpu_count(),
                             "note": "run by a driver that was stopped; waited for by process %d; wall time "
                                     "from the lock file, up to 5 s late; first step after %s" % (
                                         os.getpid(), st0[1] if st0 else "?")})


def record_timing(case, entry):
    rows = []
    if os.path.exists(case.timing):
        with open(case.timing) as f:
            rows = json.load(f)
    rows.append(entry)
    with open(case.timing, "w") as f:
        json.dump(rows, f, indent=1)


def capdem_version(capdem):
    try:
        return subprocess.run([capdem, "--version"], capture_output=True, text=True).stdout.splitlines()[0]
    except (OSError, IndexError):
        return "?"


def git_head():
    try:
        return subprocess.run(["git", "-C", REPO, "rev-parse", "--short", "HEAD"], capture_output=True,
                              text=True).stdout.strip()
    except OSError:
        return "?"


_print_lock = threading.Lock()


def say(*a):
    with _print_lock:
        print(*a, flush=True)


def advance(case, args, capdem):
    """Run or resume one case once.  Returns 'done', 'capped' (step cap reached,
    not done), 'failed' (capdem exit status not 0: FAILED marker written) or
    'skipped' (held by another process, failed before, or beyond --max-steps)."""
    os.makedirs(case.dir, exist_ok=True)
    holder = lock_holder(case)
    if holder is not None:
        say("  %s: being run by process %d; skipped" % (case.name, holder))
        return "skipped"
    st = run_state(case.h5)
    if st is not None and st[2] == PHASE_DONE:
        return "done"
    failed = os.path.join(case.dir, "FAILED")
    if os.path.exists(failed):
        with open(failed) as f:
            say("  %s: failed before (%s); see run.log, delete FAILED to retry" % (case.name, f.read().strip()))
        return "skipped"
    with open(case.lock, "w") as f:
        f.write("pid=%d %s\n" % (os.getpid(), now()))
    try:
        cap = args.steps
        if st is not None and st[0] > 0 and st[1] >= cap:
            cap = st[1] * 2
        if cap > args.max_steps:
            say("  %s: step %d, not done, cap %d would pass --max-steps %d; skipped"
                % (case.name, st[1], cap, args.max_steps))
            return "skipped"
        case.write_config(cap)
        cmd = [capdem, "run", "config.yaml", "--output", "run.h5", "--steps", str(cap), "--threads",
               str(args.threads), "--quiet"]
        if st is not None and st[0] > 0:
            cmd[3:3] = ["--resume", "run.h5"]
            say("  %s: resuming at step %d (phase %d), cap %d" % (case.name, st[1], st[2], cap))
        else:
            if os.path.exists(case.h5):
                os.remove(case.h5)  # no complete snapshot: start again
            say("  %s: starting" % case.name)
        load0 = os.getloadavg()
        ru0 = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.time()
        start = now()
        with open(case.log, "a") as log:
            log.write("# %s %s\n" % (start, " ".join(cmd)))
            log.flush()
            proc = subprocess.Popen(cmd, cwd=case.dir, stdout=log, stderr=log)
            with open(case.lock, "a") as f:
                f.write("pid=%d capdem\n" % proc.pid)
            rc = proc.wait()
        wall = time.time() - t0
        ru1 = resource.getrusage(resource.RUSAGE_CHILDREN)  # with --jobs > 1, includes runs that ended meanwhile
        st1 = run_state(case.h5)
        entry = {"start": start, "end": now(), "wall_s": round(wall, 2),
                 "cpu_s": round(ru1.ru_utime + ru1.ru_stime - ru0.ru_utime - ru0.ru_stime, 2),
                 "rc": rc, "step_from": st[1] if st else 0, "step_to": st1[1] if st1 else None,
                 "phase": st1[2] if st1 else None, "threads": args.threads, "loadavg_start": load0[0],
                 "loadavg_end": os.getloadavg()[0], "cores": os.cpu_count(), "capdem": capdem_version(capdem),
                 "git": git_head(), "niceness": os.nice(0)}
        record_timing(case, entry)
        say("  %s: rc %d, %.1f s wall, %.1f s CPU, steps %s -> %s, phase %s"
            % (case.name, rc, wall, entry["cpu_s"], entry["step_from"], entry["step_to"], entry["phase"]))
        if rc < 0:
            return "skipped"  # killed by a signal: resumable, not a failure of the run
        if rc != 0:
            with open(failed, "w") as f:
                f.write("capdem exit status %d at %s\n" % (rc, now()))
            return "failed"
        if st1 is not None and st1[2] == PHASE_DONE:
            return "done"
        return "capped"
    finally:
        try:
            os.remove(case.lock)
        except OSError:
            pass


def pm(g, k, digits=3):
    v = g.get(k)
    if v is None:
        return "—"
    se = g.get(k + "_se")
    f = "%%.%df" % digits
    return (f % v) + ((" ± " + f % se) if se is not None else " (1 seed)")


def ref(v, digits=2):
    return "—" if v is None else ("%%.%df" % digits) % v


def markdown_into(spec, table, default_marker):
    """Replaces the lines between <!-- MARKER:begin --> and <!-- MARKER:end -->
    of FILE (spec FILE or FILE:MARKER) with the table, so that docs tables are
    regenerated, not copied by hand."""
    path, _, marker = spec.partition(":")
    marker = marker or default_marker
    begin, end = "<!-- %s:begin -->" % marker, "<!-- %s:end -->" % marker
    with open(path) as f:
        text = f.read()
    if begin not in text or end not in text:
        raise SystemExit("validate.py: %s has no %s ... %s" % (path, begin, end))
    head, rest = text.split(begin, 1)
    _, tail = rest.split(end, 1)
    with open(path, "w") as f:
        f.write(head + begin + "\n" + table + "\n" + end + tail)
    print("table written into %s (%s)" % (path, marker))


def parse_list(s, typ=float):
    return [typ(x) for x in s.split(",") if x.strip()] if s else []
