#!/usr/bin/python3
"""Two or more capdem-bench variants timed in turn on settled packings.

    /usr/bin/python3 bench/ab.py --load F.h5 [--load G.h5 ...] --variant old=build-old/capdem-bench \\
        --variant "new=build/capdem-bench --reorder cells" --variant "none=build/capdem-bench --reorder none" \\
        [--threads 1,2] [--rounds 5] [--steps 300 | --target 2e6] [--omp-wait-policy default] > ab.jsonl

Each round runs every (packing, thread count, variant) once, in the order
given (one capdem-bench process each, --repeat 1, 20 untimed steps first),
so a load that drifts on a shared machine falls on all of them alike.
--target sets each packing's steps to about that many particle-steps (at
least 20; its particle count read from a 1-step run of the first variant)
in place of --steps: packings of 1e3 to 1e5 particles (bench/ladder.py's
rungs) then take about the same time.  Prints capdem-bench's JSON line per
segment with `variant`, `load`, `round` and the machine's load average
before it, then a table of medians (range) of the particle-steps per
second of the wall clock and of the process's CPU time, with the ratio to
the first variant on the same packing and thread count.
--omp-wait-policy: OMP_WAIT_POLICY of the runs; default leaves it unset
(libgomp's own, what a user gets), as bench/lammps/compare.py does since
session 20 (PASSIVE cost 14-19 % at two threads; docs/performance.md,
"Session 20, spheres").
"""
import argparse
import json
import os
import shlex
import statistics
import subprocess
import sys


def run(cmd, policy):
    env = dict(os.environ)
    env.pop("OMP_WAIT_POLICY", None)
    if policy != "default":
        env["OMP_WAIT_POLICY"] = policy.upper()
    p = subprocess.run(cmd, capture_output=True, text=True, env=env)
    if p.returncode:
        raise SystemExit("ab: %s failed (%d): %s" % (" ".join(cmd), p.returncode, p.stderr))
    return [json.loads(l) for l in p.stdout.splitlines() if l.startswith("{")]


def segment(cmd, load, steps, threads, policy):
    return run(cmd[:1] + ["--load-settled", load, "--gravity", "490.5", "--steps", str(steps), "--repeat", "1",
                          "--threads", threads] + cmd[1:], policy)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--load", action="append", required=True,
                    help="settled packing (capdem-bench --save-settled); repeat for several")
    ap.add_argument("--variant", action="append", required=True, help="NAME=BINARY [options]")
    ap.add_argument("--threads", default="1,2")
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--steps", type=int, default=300)
    ap.add_argument("--target", type=float, default=0, help="particle-steps a segment (sets the steps per packing)")
    ap.add_argument("--omp-wait-policy", default="default", choices=("default", "passive", "active"))
    args = ap.parse_args()
    variants = []
    for v in args.variant:
        name, _, cmd = v.partition("=")
        variants.append((name, shlex.split(cmd)))
    threads = args.threads.split(",")
    steps = {}
    for load in args.load:
        steps[load] = args.steps
        if args.target > 0:
            n = segment(variants[0][1], load, 1, threads[0], args.omp_wait_policy)[-1]["N"]
            steps[load] = max(20, int(args.target / n))
    rows = []
    for r in range(args.rounds):
        for load in args.load:
            for t in threads:
                for name, cmd in variants:
                    avg = os.getloadavg()[0]
                    for line in segment(cmd, load, steps[load], t, args.omp_wait_policy):
                        line.update(variant=name, load=load, round=r, loadavg=avg,
                                    cpu_particle_steps_per_s=line["N"] * line["steps"] / line["cpu_s"])
                        rows.append(line)
                        print(json.dumps(line), flush=True)
    first = variants[0][0]
    print("| packing | N | variant | threads | p-steps/s, wall: median (range) | ratio to %s | p-steps per CPU s "
          "| ratio | load avg |" % first)
    print("|---|---|---|---|---|---|---|---|---|")
    for load in args.load:
        for t in threads:
            base = {}
            for name, _ in variants:
                sel = [x for x in rows if x["variant"] == name and x["load"] == load and str(x["threads"]) == t]
                w = [x["particle_steps_per_s"] for x in sel]
                c = [x["cpu_particle_steps_per_s"] for x in sel]
                mw, mc = statistics.median(w), statistics.median(c)
                base.setdefault("w", mw)
                base.setdefault("c", mc)
                print("| %s | %d | %s | %s | %.3g (%.3g-%.3g) | %.3f | %.3g | %.3f | %.1f-%.1f |"
                      % (os.path.basename(load), sel[0]["N"], name, t, mw, min(w), max(w), mw / base["w"], mc,
                         mc / base["c"], min(x["loadavg"] for x in sel), max(x["loadavg"] for x in sel)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
