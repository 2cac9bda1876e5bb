"""Counters per particle-step for bench/ladder.py: what grows with N, apart from load noise.

Each rung is run twice under the counting tool, with S and 2 S timed steps
(capdem-bench --steps, --repeat 1, one thread); the difference of the two
runs' counts is S steps of the step alone (loading, list build, warm-up and
the report's sync cancel).  Divided by N S:

  perf        `perf stat` (where the machine has hardware counters):
              instructions and cycles per particle-step (cycles grow where
              memory traffic does; instructions should stay flat), and
              cache misses.
  cachegrind  (where it has not, e.g. a virtual machine): instructions and
              simulated misses of D1 (32 KiB, 8-way) and of a last level of
              LL_BYTES (default 32 MiB, 16-way: this machine's L3 as lscpu
              reports it; CAPDEM_LADDER_LL=1048576 makes it the 1 MiB L2
              of one core), in all and per function (the step's passes), so
              that a pass whose misses grow shows.  About 50 times slower
              than native: S is a tenth of ladder.py's segment (at least 10).
"""
import collections
import os
import re
import subprocess
import tempfile

LL_BYTES = int(os.environ.get("CAPDEM_LADDER_LL", 32 << 20))  # bytes of the simulated last level
EVENTS = ["cycles", "instructions", "cache-misses"]


def perf_works():
    try:
        p = subprocess.run(["perf", "stat", "-x", ",", "-e", "instructions", "true"], capture_output=True, text=True)
    except OSError:
        return False
    return p.returncode == 0 and "<not supported>" not in p.stderr and "instructions" in p.stderr


def choose(tool):
    if tool == "auto":
        return "perf" if perf_works() else "cachegrind"
    if tool == "perf" and not perf_works():
        raise SystemExit("ladder: --counters perf: perf stat has no hardware counters here (try cachegrind)")
    return tool


def bench_cmd(bench, f, steps):
    return [bench, "--threads", "1", "--load-settled", f, "--gravity", "490.5", "--steps", str(steps), "--repeat", "1"]


def run_perf(bench, f, steps):
    p = subprocess.run(["perf", "stat", "-x", ",", "-e", ",".join(EVENTS)] + bench_cmd(bench, f, steps),
                       capture_output=True, text=True, env=dict(os.environ, OMP_WAIT_POLICY="PASSIVE"))
    if p.returncode:
        raise SystemExit("ladder: perf stat failed: %s" % p.stderr[-2000:])
    out = {}
    for line in p.stderr.splitlines():
        parts = line.split(",")
        if len(parts) > 2 and parts[2] in EVENTS and parts[0].strip().isdigit():
            out[parts[2]] = float(parts[0])
    return {"total": out}


def parse_cachegrind(path):
    """Totals and per-function sums of a cachegrind.out file."""
    events, per_fn, fn = None, collections.defaultdict(lambda: None), "?"
    names = {}
    for line in open(path):
        if line.startswith("events:"):
            events = line.split()[1:]
        elif line.startswith("fn="):
            m = re.match(r"fn=(?:\((\d+)\))?\s*(.*)", line.strip())
            ident, name = m.group(1), m.group(2)
            if ident and not name:
                name = names[ident]
            elif ident:
                names[ident] = name
            fn = name
        elif line[:1].isdigit():
            counts = [float(x) for x in line.split()[1:]]
            acc = per_fn[fn]
            if acc is None:
                acc = per_fn[fn] = [0.0] * len(events)
            for k, c in enumerate(counts):
                acc[k] += c
    total = [sum(v[k] for v in per_fn.values()) for k in range(len(events))]
    return ({e: t for e, t in zip(events, total)},
            {fn: {e: c for e, c in zip(events, v)} for fn, v in per_fn.items()})


def run_cachegrind(bench, f, steps):
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "cg.out")
        cmd = ["valgrind", "--tool=cachegrind", "--cache-sim=yes", "--I1=32768,8,64", "--D1=32768,8,64",
               "--LL=%d,16,64" % LL_BYTES, "--cachegrind-out-file=" + out] + bench_cmd(bench, f, steps)
        p = subprocess.run(cmd, capture_output=True, text=True, env=dict(os.environ, OMP_WAIT_POLICY="PASSIVE"))
        if p.returncode:
            raise SystemExit("ladder: cachegrind failed: %s" % p.stderr[-2000:])
        total, per_fn = parse_cachegrind(out)
    return {"total": total, "per_function": per_fn}


def count(tool, bench, f, n, target):
    """Counters per particle-step of the rung's step (difference of S and 2 S steps)."""
    steps = max(10, int(target / (10 * n))) if tool == "cachegrind" else max(20, int(target / n))
    run = run_perf if tool == "perf" else run_cachegrind
    short, long_ = run(bench, f, steps), run(bench, f, 2 * steps)
    scale = 1.0 / (n * steps)
    out = {"tool": tool, "steps": steps, "ll_bytes": LL_BYTES if tool == "cachegrind" else None,
           "counters": {e: (long_["total"][e] - short["total"].get(e, 0)) * scale for e in long_["total"]}}
    if "per_function" in long_:
        per = {}
        for fn, c in long_["per_function"].items():
            s = short["per_function"].get(fn, {})
            d = {e: (c[e] - s.get(e, 0)) * scale for e in c}
            if d.get("Ir", 0) > 0.5:  # at least half an instruction per particle-step
                per[fn] = d
        out["per_function"] = per
    return out


def plot_panel(ax, rows, case):
    """Counters per particle-step against N: instructions, and cycles or misses."""
    rows = sorted(rows, key=lambda r: r["N"])
    ns = [r["N"] for r in rows]
    c = [r["counters"] for r in rows]
    if rows and rows[0]["tool"] == "perf":
        series = [("instructions", "instructions"), ("cycles", "cycles"), ("cache-misses", "cache misses x 100")]
        scale = {"cache-misses": 100}
    else:
        for x in c:
            x["Dmiss"] = x.get("D1mr", 0) + x.get("D1mw", 0)
            x["LLmiss"] = x.get("DLmr", 0) + x.get("DLmw", 0)
        series = [("Ir", "instructions"), ("Dmiss", "D1 misses x 10"), ("LLmiss", "LL misses x 100")]
        scale = {"Dmiss": 10, "LLmiss": 100}
    for key, label in series:
        ax.plot(ns, [x.get(key, 0) * scale.get(key, 1) for x in c], marker="o", label=label)
    ax.set_xscale("log")
    ax.set_ylim(bottom=0)
    ax.set_xlabel("particles N")
    ax.set_ylabel("per particle-step (%s)" % (rows[0]["tool"] if rows else ""))
    ax.set_title(case + ", counters")
    ax.legend()


def table(rows, top=6):
    """Markdown: counters per particle-step of each rung, then the passes (functions) of the largest."""
    cg = rows[0]["tool"] == "cachegrind"
    keys = [("Ir", "instructions"), ("D1", "D1 misses"), ("LL", "LL misses")] if cg else \
        [("instructions", "instructions"), ("cycles", "cycles"), ("cache-misses", "cache misses")]

    def val(c, k):
        if k == "D1":
            return c.get("D1mr", 0) + c.get("D1mw", 0)
        if k == "LL":
            return c.get("DLmr", 0) + c.get("DLmw", 0)
        return c.get(k, 0)
    print("| case | N | steps counted | " + " | ".join(label + " per p-step" for _, label in keys) + " |")
    print("|---" * (3 + len(keys)) + "|")
    for r in rows:
        print("| %s | %d | %d | " % (r["case"], r["N"], r["steps"]) +
              " | ".join("%.2f" % val(r["counters"], k) for k, _ in keys) + " |")
    if not cg:
        return
    for case in sorted({r["case"] for r in rows}):
        rs = [r for r in rows if r["case"] == case]
        big = max(rs, key=lambda r: r["N"])
        fns = sorted(big["per_function"], key=lambda f: -big["per_function"][f]["Ir"])[:top]
        print()
        print("%s, per pass: instructions / D1 misses / LL misses per particle-step" % case)
        print()
        print("| pass | " + " | ".join("N = %d" % r["N"] for r in rs) + " |")
        print("|---" * (1 + len(rs)) + "|")
        for fn in fns:
            cells = []
            for r in rs:
                c = r["per_function"].get(fn, {})
                cells.append("%.0f / %.1f / %.2f" % (c.get("Ir", 0), val(c, "D1"), val(c, "LL")))
            print("| %s | %s |" % (fn, " | ".join(cells)))
