#!/usr/bin/python3
"""Cost per particle-step of capdem from 1e3 to 1e5 particles (issue 21).

    /usr/bin/python3 bench/ladder.py [--build build] [--cases spheres,hexapods_a3]
        [--tiles 1x1,5x2,6x5,10x10] [--base 1000] [--base-file CASE=FILE] [--threads 1] [--rounds 3]
        [--relax CASE=STEPS] [--max-relax CASE=STEPS] [--counters auto|perf|cachegrind|none]
        [--work build/bench-work] [--reuse] [--reorder cells,none] > ladder.jsonl
    /usr/bin/python3 bench/ladder.py --plot ladder.jsonl -o ladder.png
    /usr/bin/python3 bench/ladder.py --table ladder.jsonl

For each case, capdem-bench settles --base particles once (the case's
settling under 50 g, --friction-limit total as in bench/lammps/compare.py),
or --base-file copies a packing settled elsewhere.  Each rung is KX x KZ
copies of that packing side by side (capdem-bench --tile: the box KX x KZ
times as wide and deep, same height), so that every rung is a settled bed of
the same material and depth, only wider.  The rung 1x1 is the base itself.

Beds at rest.  A tiled packing has lost its tangential springs (bench_tile.c
drops the contact history) and its copies meet where walls stood: it slips
and springs back before it comes to rest.  So each rung is relaxed under the
same 50 g until its list stops rebuilding: --relax CASE=STEPS steps after
tiling, then a probe of PROBE steps in the same process (history kept);
while the probe rebuilds more than once, the saved packing is loaded again
(history kept) and relaxed STEPS more, up to --max-relax steps in all.  What
each rung took is kept beside it (FILE.relax.json: steps, list builds while
relaxing, probe rebuilds, at_rest) and printed on stderr; the timed lines
give the rebuilds of each segment, so that a rung still flowing shows.
(Session 17's tiled hexapod beds flowed because copies 1.. had other
particles' arms, fixed in bench_tile.c; 20 ms bring a correct one to rest.)

The rungs are then timed in --rounds rounds, each round visiting every rung
once (one capdem-bench process per rung and round, 20 untimed steps first):
a load that drifts on a shared machine is spread over the rungs instead of
falling on one.  The timed segment has about --target particle-steps (at
least 20 steps).  --reorder cells,none times every rung with each memory
order in turn (capdem-bench --reorder; same packing, same bits).

Prints one JSON line per timed segment: capdem-bench's line (with
`neighbor_builds_timed`, the rebuilds of the segment: a flowing rung shows
there) plus `tile`, `round`, `ns_per_particle_step` (wall) and
`cpu_ns_per_particle_step` (the process's CPU time: other jobs disturb it
less).  --counters adds one line per rung (`"counters": ...`, bench/ladder_counters.py):
instructions and cycles per particle-step from `perf stat` where the machine
has hardware counters, else instructions and simulated cache misses from
cachegrind; both as the difference of two runs of different length, so that
loading and warm-up cancel.  --plot draws the median CPU and wall times
against N, one panel per case, and the counters below when present.
"""
import argparse
import collections
import json
import os
import shutil
import statistics
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import ladder_counters  # noqa: E402

# Relaxation after tiling, steps (20 ms: spheres dt 2 us, hexapods 10 us),
# and the most steps in all before a rung is timed as it is (still flowing,
# which its rebuilds then show).
RELAX = {"spheres": 10000, "hexapods_a3": 2000, "hexapods_a9": 2000, "crosses2d": 3333}
MAX_RELAX = {k: 4 * v for k, v in RELAX.items()}
PROBE = 200  # steps after the relaxation that must not rebuild more than once


def bench(args, extra, threads=None):
    cmd = [os.path.join(args.build, "capdem-bench"), "--threads", str(threads or args.threads)] + extra
    env = dict(os.environ, OMP_WAIT_POLICY="PASSIVE")
    p = subprocess.run(cmd, capture_output=True, text=True, env=env)
    if p.returncode:
        raise SystemExit("ladder: %s failed (%d): %s" % (" ".join(cmd), p.returncode, p.stderr))
    return [json.loads(l) for l in p.stdout.splitlines() if l.startswith("{")]


def per_case(spec, defaults, kind=int):
    """CASE=VALUE,CASE=VALUE over a table of defaults."""
    out = dict(defaults)
    for item in (spec or "").split(","):
        if item:
            case, value = item.split("=", 1)
            out[case] = kind(value)
    return out


def relax_rung(args, case, src, tile, f):
    """Tiles src (tile = (kx, kz)) into f and relaxes it until the list stops rebuilding."""
    step, most = per_case(args.relax, RELAX)[case], per_case(args.max_relax, MAX_RELAX)[case]
    done, builds, load, cut = 0, 0, src, ["--tile", "%d,%d" % tile]
    while True:
        line = bench(args, ["--load-settled", load] + cut + ["--relax-steps", str(step), "--gravity", "490.5",
                                                             "--steps", str(PROBE), "--repeat", "1",
                                                             "--save-settled", f + ".tmp"], args.prep_threads)[0]
        os.replace(f + ".tmp", f)  # the packing saved before the probe, with its springs
        done += step
        builds += line["neighbor_builds"] - line["neighbor_builds_timed"]
        probe = line["neighbor_builds_timed"]
        if probe <= 1 or done >= most:
            break
        load, cut = f, []
    info = dict(case=case, file=os.path.basename(f), source=os.path.basename(src), tile="%dx%d" % tile,
                relax_steps=done, relax_builds=builds, probe_steps=PROBE, probe_builds=probe,
                contacts_per_particle=line["contacts_per_particle"], at_rest=probe <= 1)
    with open(f + ".relax.json", "w") as out:
        json.dump(info, out)
    return info


def rungs(args, case):
    """Settles the base packing and writes one relaxed file per tile; returns [(tile, file)]."""
    base = os.path.join(args.work, "ladder_%s_%d.h5" % (case, args.base))
    given = per_case(args.base_file, {}, str).get(case)
    if not (args.reuse and os.path.exists(base)):
        if given:
            shutil.copyfile(given, base)
        else:
            bench(args, ["--case", case, "--n", str(args.base), "--friction-limit", "total", "--gravity", "490.5",
                         "--seed", str(args.seed), "--repeat", "0", "--save-settled", base], args.prep_threads)
    out = []
    for tile in args.tiles.split(","):
        kx, kz = (int(k) for k in tile.split("x"))
        if kx * kz == 1:
            out.append((tile, base))
            continue
        f = os.path.join(args.work, "ladder_%s_%d_%s.h5" % (case, args.base, tile))
        if args.reuse and os.path.exists(f + ".relax.json"):
            info = json.load(open(f + ".relax.json"))
        else:
            info = relax_rung(args, case, base, (kx, kz), f)
        print("ladder: %s %s: %s" % (case, tile, json.dumps(info)), file=sys.stderr, flush=True)
        out.append((tile, f))
    return out


def plot(paths, output):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    rows = [json.loads(l) for p in paths for l in open(p) if l.startswith("{")]
    timed = [r for r in rows if "counters" not in r]
    counted = [r for r in rows if "counters" in r]
    cases = sorted({r["case"] for r in timed})
    fig, axes = plt.subplots(2 if counted else 1, len(cases), figsize=(5 * len(cases), 8 if counted else 4),
                             squeeze=False)
    for ax, case in zip(axes[0], cases):
        by = collections.defaultdict(list)
        for r in timed:
            if r["case"] == case:
                by[(r.get("reorder", ""), r["N"])].append(r)
        orders = sorted({o for o, n in by})
        for order in orders:
            ns = sorted(n for o, n in by if o == order)
            for key, label in (("ns_per_particle_step", "wall"), ("cpu_ns_per_particle_step", "CPU")):
                med = [statistics.median(r[key] for r in by[(order, n)]) for n in ns]
                lo = [m - min(r[key] for r in by[(order, n)]) for m, n in zip(med, ns)]
                hi = [max(r[key] for r in by[(order, n)]) - m for m, n in zip(med, ns)]
                ax.errorbar(ns, med, yerr=[lo, hi], marker="o", capsize=3,
                            label=label + (", reorder " + order if len(orders) > 1 else ""))
        ax.set_xscale("log")
        ax.set_ylim(bottom=0)
        ax.set_xlabel("particles N")
        ax.set_ylabel("ns per particle-step (1 thread)")
        ax.set_title(case)
        ax.legend()
    if counted:
        for ax, case in zip(axes[1], cases):
            ladder_counters.plot_panel(ax, [r for r in counted if r["case"] == case], case)
    fig.tight_layout()
    fig.savefig(output, dpi=110)


def table(paths):
    """Markdown tables of a run: the timed rungs, and the counters when present."""
    rows = [json.loads(l) for p in paths for l in open(p) if l.startswith("{")]
    timed = [r for r in rows if "counters" not in r]
    print("| case | N | steps | wall ns/p-step (median) | CPU ns/p-step (median (range)) | CPU vs 1e3 | "
          "rebuilds per segment | contacts per particle | state B per particle |")
    print("|---|---|---|---|---|---|---|---|---|")
    by = collections.defaultdict(list)
    for r in timed:
        by[(r["case"], r.get("reorder", ""), r["N"])].append(r)
    first = {}
    for key in sorted(by):
        rs, (case, order, n) = by[key], key
        cpu = [r["cpu_ns_per_particle_step"] for r in rs]
        med = statistics.median(cpu)
        first.setdefault((case, order), med)
        print("| %s%s | %d | %d | %.0f | %.0f (%.0f-%.0f) | %.2f | %s | %.2f | %d |" % (
            case, ", " + order if order else "", n, rs[0]["steps"],
            statistics.median(r["ns_per_particle_step"] for r in rs), med, min(cpu), max(cpu),
            med / first[(case, order)], ", ".join(str(r["neighbor_builds_timed"]) for r in rs),
            rs[0]["contacts_per_particle"], rs[0]["bytes_per_particle"]))
    counted = sorted((r for r in rows if "counters" in r), key=lambda r: (r["case"], r["N"]))
    if counted:
        print()
        ladder_counters.table(counted)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--build", default="build")
    ap.add_argument("--cases", default="spheres,hexapods_a3")
    ap.add_argument("--tiles", default="1x1,5x2,6x5,10x10")
    ap.add_argument("--base", type=int, default=1000)
    ap.add_argument("--base-file", default=None, help="CASE=FILE,...: a settled base packing to copy instead of settling")
    ap.add_argument("--relax", default=None, help="CASE=STEPS,...: relaxation steps after tiling (and per extra round)")
    ap.add_argument("--max-relax", default=None, help="CASE=STEPS,...: most relaxation steps of a rung")
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--prep-threads", type=int, default=2, help="threads of the untimed settling and relaxation")
    ap.add_argument("--target", type=float, default=2e6, help="particle-steps per timed segment")
    ap.add_argument("--seed", type=int, default=5)
    ap.add_argument("--work", default="build/bench-work")
    ap.add_argument("--reuse", action="store_true", help="reuse settled and relaxed files of an earlier run")
    ap.add_argument("--reorder", default=None, help="comma-separated memory orders to time each rung with (cells, none)")
    ap.add_argument("--counters", default="none", choices=["auto", "perf", "cachegrind", "none"],
                    help="count instructions and cycles (perf) or cache misses (cachegrind) once per rung")
    ap.add_argument("--prepare-only", action="store_true", help="settle, tile and relax; time nothing")
    ap.add_argument("--plot", nargs="+", metavar="JSONL", help="plot these results instead of measuring")
    ap.add_argument("--table", nargs="+", metavar="JSONL", help="print these results as markdown tables")
    ap.add_argument("-o", "--output", default="ladder.png")
    args = ap.parse_args()
    if args.plot:
        plot(args.plot, args.output)
        return 0
    if args.table:
        table(args.table)
        return 0
    os.makedirs(args.work, exist_ok=True)
    ladder = [(case, tile, f) for case in args.cases.split(",") for tile, f in rungs(args, case)]
    if args.prepare_only:
        return 0
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
    if args.counters != "none":
        tool = ladder_counters.choose(args.counters)
        for case, tile, f in ladder:
            kx, kz = (int(k) for k in tile.split("x"))
            n = args.base * kx * kz
            line = ladder_counters.count(tool, os.path.join(args.build, "capdem-bench"), f, n, args.target)
            line.update(case=case, tile=tile, N=n)
            print(json.dumps(line), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
