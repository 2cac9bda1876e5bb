#!/usr/bin/python3
"""Cost per particle-step of capdem from 1e3 to 1e5 particles (issue 21).

    /usr/bin/python3 bench/ladder.py [--build build] [--cases spheres,hexapods_a3]
        [--tiles 1x1,3x1,5x2,6x5,10x10] [--base 1000] [--threads 1] [--rounds 3]
        [--work build/bench-work] [--reuse] [--reorder cells,none] > ladder.jsonl
    /usr/bin/python3 bench/ladder.py --plot ladder.jsonl -o ladder.png

For each case, capdem-bench settles --base particles once (the case's
settling under 50 g, --friction-limit total as in bench/lammps/compare.py);
each rung is KX x KZ copies of that packing side by side (capdem-bench
--tile, the box KX x KZ times as wide and deep, same height), relaxed for
20 ms (--relax steps) under the same load and saved, so that every rung is a
settled bed of the same material and depth, only wider.  The rung 1x1 is
the base packing itself.  The rungs are then timed in --rounds rounds, each
round visiting every rung once (one capdem-bench process per rung and
round, 20 untimed steps first): a load that drifts on a shared machine is
spread over the rungs instead of falling on one.  The timed segment has
about --target particle-steps (at least 20 steps).

--reorder cells,none times every rung with each memory order in turn
(capdem-bench --reorder; the same packing and bits, src/backend/omp/reorder.c), so
that the two are compared in the same round.

Prints one JSON line per timed segment: capdem-bench's line plus `tile`,
`round`, `ns_per_particle_step` (wall) and `cpu_ns_per_particle_step`
(the process's CPU time: other jobs disturb it less).  --plot draws the
median of both against N, one panel per case.
"""
import argparse
import collections
import json
import os
import statistics
import subprocess
import sys


# a tiled packing has lost its tangential springs and needs about 20 ms to
# find its contacts again (bench/lammps/compare.py, RELAX)
RELAX = {"spheres": 10000, "hexapods_a3": 2000, "hexapods_a9": 2000, "crosses2d": 3333}


def bench(args, extra, threads=None):
    cmd = [os.path.join(args.build, "capdem-bench"), "--threads", str(threads or args.threads)] + extra
    env = dict(os.environ, OMP_WAIT_POLICY="PASSIVE")
    p = subprocess.run(cmd, capture_output=True, text=True, env=env)
    if p.returncode:
        raise SystemExit("ladder: %s failed (%d): %s" % (" ".join(cmd), p.returncode, p.stderr))
    return [json.loads(l) for l in p.stdout.splitlines() if l.startswith("{")]


def rungs(args, case):
    """Settles the base packing and writes one relaxed file per tile; returns [(tile, file)]."""
    base = os.path.join(args.work, "ladder_%s_%d.h5" % (case, args.base))
    if not (args.reuse and os.path.exists(base)):
        bench(args, ["--case", case, "--n", str(args.base), "--friction-limit", "total", "--gravity", "490.5",
                     "--seed", str(args.seed), "--repeat", "0", "--save-settled", base], args.prep_threads)
    out = []
    for tile in args.tiles.split(","):
        kx, kz = (int(k) for k in tile.split("x"))
        if kx * kz == 1:
            out.append((tile, base))
            continue
        f = os.path.join(args.work, "ladder_%s_%d_%s.h5" % (case, args.base, tile))
        if not (args.reuse and os.path.exists(f)):
            relax = str(RELAX[case] if args.relax is None else args.relax)
            bench(args, ["--load-settled", base, "--tile", "%d,%d" % (kx, kz), "--relax-steps", relax,
                         "--repeat", "0", "--save-settled", f], args.prep_threads)
        out.append((tile, f))
    return out


def plot(paths, output):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    rows = [json.loads(l) for p in paths for l in open(p) if l.startswith("{")]
    cases = sorted({r["case"] for r in rows})
    fig, axes = plt.subplots(1, len(cases), figsize=(5 * len(cases), 4), squeeze=False)
    for ax, case in zip(axes[0], cases):
        by = collections.defaultdict(list)
        for r in rows:
            if r["case"] == case:
                by[(r.get("reorder", ""), r["N"])].append(r)
        for order in sorted({o for o, n in by}):
            ns = sorted(n for o, n in by if o == order)
            for key, label in (("ns_per_particle_step", "wall"), ("cpu_ns_per_particle_step", "CPU")):
                med = [statistics.median(r[key] for r in by[(order, n)]) for n in ns]
                lo = [m - min(r[key] for r in by[(order, n)]) for m, n in zip(med, ns)]
                hi = [max(r[key] for r in by[(order, n)]) - m for m, n in zip(med, ns)]
                ax.errorbar(ns, med, yerr=[lo, hi], marker="o", capsize=3,
                            label=label + (", reorder " + order if order else ""))
        ax.set_xscale("log")
        ax.set_ylim(bottom=0)
        ax.set_xlabel("particles N")
        ax.set_ylabel("ns per particle-step (1 thread)")
        ax.set_title(case)
        ax.legend()
    fig.tight_layout()
    fig.savefig(output, dpi=110)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--build", default="build")
    ap.add_argument("--cases", default="spheres,hexapods_a3")
    ap.add_argument("--tiles", default="1x1,3x1,5x2,6x5,10x10")
    ap.add_argument("--base", type=int, default=1000)
    ap.add_argument("--relax", type=int, default=None, help="relaxation steps of a tiled rung (default: 20 ms)")
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--prep-threads", type=int, default=2, help="threads of the untimed settling and relaxation")
    ap.add_argument("--target", type=float, default=2e6, help="particle-steps per timed segment")
    ap.add_argument("--seed", type=int, default=5)
    ap.add_argument("--work", default="build/bench-work")
    ap.add_argument("--reuse", action="store_true", help="reuse settled and tiled files of an earlier run")
    ap.add_argument("--reorder", default=None, help="comma-separated memory orders to time each rung with (cells, none)")
    ap.add_argument("--plot", nargs="+", metavar="JSONL", help="plot these results instead of measuring")
    ap.add_argument("-o", "--output", default="ladder.png")
    args = ap.parse_args()
    if args.plot:
        plot(args.plot, args.output)
        return 0
    os.makedirs(args.work, exist_ok=True)
    ladder = [(case, tile, f) for case in args.cases.split(",") for tile, f in rungs(args, case)]
    for r in range(args.rounds):
        for case, tile, f in ladder:
            kx, kz = (int(k) for k in tile.split("x"))
            steps = max(20, int(args.target / (args.base * kx * kz)))
            for order in args.reorder.split(",") if args.reorder else [None]:
                extra = ["--reorder", order] if order else []
                for line in bench(args, ["--load-settled", f, "--gravity", "490.5", "--steps", str(steps), "--repeat",
                                         "1"] + extra):
                    line.update(tile=tile, round=r, ns_per_particle_step=1e9 * line["wall_s"] / (line["N"] * steps),
                                cpu_ns_per_particle_step=1e9 * line["cpu_s"] / (line["N"] * steps))
                    print(json.dumps(line), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
