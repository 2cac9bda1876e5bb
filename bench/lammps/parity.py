#!/usr/bin/python3
"""Physics parity of the sphere case: capdem and LAMMPS settle the same
initial states and their packings are compared.

    /usr/bin/python3 bench/lammps/parity.py [--build build] [--n 1000] [--seeds 1,2,3,4]
        [--settle 30000] [--threads 2] [--work build/bench-work/parity] [--json parity.json]

For each seed capdem-bench writes the initial lattice deposit of N spheres
(default material of docs/references.md, Contact law; d = 5 mm +- 20 %, friction limit mu F_n as in LAMMPS) and
settles it for --settle steps under 50 g in its box (the weight of the
column compresses the packing); LAMMPS settles the very same initial state
(positions, sizes, masses, velocities) with the equivalent law
(lammps_law.py), the same walls, gravity, dt and step count.  Both packings'
contacts (particle pairs that overlap) and normal forces go through one
estimator, here:

  Z  = 2 N_c / N*, N* the particles with at least one particle contact
       (rattlers with none excluded; docs/references.md, Analysis);
  k  = tail exponent of P(f), f = F_n / <F_n>, for f > 1: maximum-likelihood
       fit of P(f) ~ exp(-k f) on f > 1, k = 1 / mean(f - 1).

Error: the standard error of the mean over seeds (independent packings),
which holds both the sampling noise of one packing and the packing-to-packing
spread; each run also gets a 95 % bootstrap interval over its contacts
(1000 resamples).  The codes agree when |difference| < 2 x the combined
standard error.  capdem's own estimator (`capdem analyze --json`,
normal_forces.k) is reported beside it for capdem's packings.
"""
import argparse
import json
import math
import os
import subprocess
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "..", "..", "host"))  # capdem_h5
import capdem_h5  # noqa: E402
import capdem_to_lammps  # noqa: E402
import compare  # noqa: E402


def measures(i, j, fn, n, rng):
    i, j, fn = np.asarray(i, int), np.asarray(j, int), np.asarray(fn, float)
    deg = np.bincount(np.concatenate([i, j]), minlength=n)
    f = fn / fn.mean()
    tail = f[f > 1] - 1

    def k_of(t):
        return 1.0 / t.mean()

    boot = []
    for _ in range(1000):
        g = rng.choice(f, size=len(f))
        boot.append(k_of(g[g > 1] - 1))
    return {
        "n_contacts": int(len(fn)), "N_star": int((deg > 0).sum()),
        "Z": 2.0 * len(fn) / max(1, (deg > 0).sum()), "Z_all": 2.0 * len(fn) / n,
        "k": k_of(tail), "k_lo": float(np.percentile(boot, 2.5)), "k_hi": float(np.percentile(boot, 97.5)),
        "tail_n": int(len(tail)), "mean_fn": float(fn.mean()),
    }


def capdem_contacts(path):
    """Particle ids and F_n of the contacts of the last snapshot, and N."""
    with capdem_h5.open_run(path) as f:
        n = capdem_h5.column_dataset(f, "mass").shape[0]
        k = capdem_h5.snapshot_count(f) - 1
        return (capdem_h5.snapshot_rows(f, "c_particle_i", k), capdem_h5.snapshot_rows(f, "c_particle_j", k),
                capdem_h5.column(f, "pair_fn", k), n)


def lammps_contacts(path):
    d = np.loadtxt(path, skiprows=9, ndmin=2)
    return d[:, 0].astype(int) - 1, d[:, 1].astype(int) - 1, d[:, 2]


def mean_se(xs):
    xs = np.asarray(xs, float)
    return float(xs.mean()), float(xs.std(ddof=1) / math.sqrt(len(xs))) if len(xs) > 1 else float("nan")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--build", default="build")
    ap.add_argument("--n", type=int, default=1000)
    ap.add_argument("--seeds", default="1,2,3,4")
    ap.add_argument("--settle", type=int, default=30000)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--work", default="build/bench-work/parity")
    ap.add_argument("--json", help="write the summary here")
    args = ap.parse_args()
    args.steps, args.repeat = 1, 1
    compare.ensure_lammps()
    os.makedirs(args.work, exist_ok=True)
    rng = np.random.default_rng(1)
    runs = []
    for seed in [int(s) for s in args.seeds.split(",")]:
        w = os.path.join(args.work, "spheres_%d_s%d" % (args.n, seed))
        common = ["--case", "spheres", "--n", str(args.n), "--seed", str(seed), "--friction-limit", "total", "--repeat", "0"]
        compare.capdem_bench(args, common + ["--settle-steps", "0", "--save-settled", w + "_init.h5"])
        compare.capdem_bench(args, common + ["--settle-steps", str(args.settle), "--save-settled", w + "_capdem.h5"])
        meta = capdem_to_lammps.convert(capdem_to_lammps.read_run(w + "_init.h5"), w + ".data")
        compare.run_lammps(args, w + ".data", meta, w + ".lammps.log", args.settle, 0, contacts=w + "_lammps.contacts",
                           nsteps=1, nrepeat=1)
        ci, cj, cf, n = capdem_contacts(w + "_capdem.h5")
        li, lj, lf = lammps_contacts(w + "_lammps.contacts")
        an = subprocess.run([os.path.join(args.build, "capdem"), "analyze", w + "_capdem.h5", "--json"],
                            capture_output=True, text=True)
        k_capdem_analyze = json.loads(an.stdout).get("normal_forces", {}).get("k") if an.returncode == 0 else None
        r = {"seed": seed, "N": n, "capdem": measures(ci, cj, cf, n, rng), "lammps": measures(li, lj, lf, n, rng),
             "capdem_analyze_k": k_capdem_analyze}
        print(json.dumps(r), flush=True)
        runs.append(r)
    summary = {"N": args.n, "seeds": len(runs), "settle_steps": args.settle, "estimator_error": "SE of the mean over seeds"}
    for key in ("Z", "Z_all", "k"):
        c = mean_se([r["capdem"][key] for r in runs])
        l = mean_se([r["lammps"][key] for r in runs])
        se = math.hypot(c[1], l[1])
        summary[key] = {"capdem": c[0], "capdem_se": c[1], "lammps": l[0], "lammps_se": l[1], "difference": c[0] - l[0],
                        "combined_se": se, "agree_within_2se": abs(c[0] - l[0]) < 2 * se}
    print(json.dumps(summary))
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"runs": runs, "summary": summary}, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
