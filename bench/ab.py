#!/usr/bin/python3
"""Two or more capdem-bench variants timed in turn on one settled packing.

    /usr/bin/python3 bench/ab.py --load F.h5 --variant old=build-old/capdem-bench \\
        --variant "new=build/capdem-bench --reorder cells" --variant "none=build/capdem-bench --reorder none" \\
        [--threads 1,2] [--rounds 5] [--steps 300] > ab.jsonl

Each round runs every (variant, thread count) once, in the order given
(one capdem-bench process each, --repeat 1, 20 untimed steps first), so a
load that drifts on a shared machine falls on all of them alike.  Prints
capdem-bench's JSON line per segment with `variant`, `round` and the
machine's load average before it, then a table of medians (range) of the
particle-steps per second of the wall clock and of the process's CPU time,
with the ratio to the first variant.  OMP_WAIT_POLICY=PASSIVE as in
bench/lammps/compare.py and bench/ladder.py.
"""
import argparse
import json
import os
import shlex
import statistics
import subprocess
import sys


def run(cmd):
    env = dict(os.environ, OMP_WAIT_POLICY="PASSIVE")
    p = subprocess.run(cmd, capture_output=True, text=True, env=env)
    if p.returncode:
        raise SystemExit("ab: %s failed (%d): %s" % (" ".join(cmd), p.returncode, p.stderr))
    return [json.loads(l) for l in p.stdout.splitlines() if l.startswith("{")]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--load", required=True, help="settled packing (capdem-bench --save-settled)")
    ap.add_argument("--variant", action="append", required=True, help="NAME=BINARY [options]")
    ap.add_argument("--threads", default="1,2")
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--steps", type=int, default=300)
    args = ap.parse_args()
    variants = []
    for v in args.variant:
        name, _, cmd = v.partition("=")
        variants.append((name, shlex.split(cmd)))
    rows = []
    for r in range(args.rounds):
        for t in args.threads.split(","):
            for name, cmd in variants:
                load = os.getloadavg()[0]
                for line in run(cmd[:1] + ["--load-settled", args.load, "--gravity", "490.5", "--steps",
                                           str(args.steps), "--repeat", "1", "--threads", t] + cmd[1:]):
                    line.update(variant=name, round=r, loadavg=load,
                                cpu_particle_steps_per_s=line["N"] * line["steps"] / line["cpu_s"])
                    rows.append(line)
                    print(json.dumps(line), flush=True)
    first = variants[0][0]
    print("| variant | threads | p-steps/s, wall: median (range) | ratio to %s | p-steps per CPU s | ratio | load avg |"
          % first)
    print("|---|---|---|---|---|---|---|")
    for t in args.threads.split(","):
        base = {}
        for name, _ in variants:
            sel = [x for x in rows if x["variant"] == name and str(x["threads"]) == t]
            w = [x["particle_steps_per_s"] for x in sel]
            c = [x["cpu_particle_steps_per_s"] for x in sel]
            mw, mc = statistics.median(w), statistics.median(c)
            base.setdefault("w", mw)
            base.setdefault("c", mc)
            print("| %s | %s | %.3g (%.3g-%.3g) | %.2f | %.3g | %.2f | %.1f-%.1f |"
                  % (name, t, mw, min(w), max(w), mw / base["w"], mc, mc / base["c"],
                     min(x["loadavg"] for x in sel), max(x["loadavg"] for x in sel)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
