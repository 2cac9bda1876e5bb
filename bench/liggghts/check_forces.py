#!/usr/bin/python3
"""One state, two codes: LIGGGHTS evaluates the contact forces of a sphere
packing capdem settled, and the normal forces are compared pair by pair.

    build/capdem-bench --case spheres --n 1000 --friction-limit total --repeat 0 --save-settled S.h5
    /usr/bin/python3 bench/liggghts/check_forces.py S.h5 [--work build/bench-work] [--tolerance 1e-2]

LIGGGHTS reads the packing (liggghts_bench.convert), takes no step (`run
0`) and dumps every touching pair with its normal force (compute
pair/gran/local id force_normal).  Prints the contact counts and the
largest and median |F_n(capdem) - F_n(LIGGGHTS)| / <F_n>.  Exit 1 if the
contact sets differ or the largest difference exceeds the tolerance.  The
elastic parts are the same function (kn = k_n/2); the damping term differs
by the velocities, which are half a step apart in the two codes, and by the
mass bins' damping (within 1.3 %, liggghts_law.py) of a term that is a
small part of F_n in a settled packing.
"""
import argparse
import json
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "..", "lammps"))
import liggghts_bench  # noqa: E402
import liggghts_law  # noqa: E402
import capdem_to_lammps  # noqa: E402
import parity  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("run")
    ap.add_argument("--work", default="build/bench-work")
    ap.add_argument("--tolerance", type=float, default=1e-2)
    a = ap.parse_args()
    liggghts_law.ensure_liggghts()
    os.makedirs(a.work, exist_ok=True)
    base = os.path.join(a.work, "liggghts_check_forces")
    meta = liggghts_bench.convert(capdem_to_lammps.read_run(a.run), base)
    liggghts_bench.run(meta, base + ".log", 1, contacts=base + ".contacts")
    ci, cj, cf, _ = parity.capdem_contacts(a.run)
    d = np.loadtxt(base + ".contacts", skiprows=9, ndmin=2)  # id_i id_j Fn_x Fn_y Fn_z
    li, lj, lf = d[:, 0].astype(int) - 1, d[:, 1].astype(int) - 1, np.linalg.norm(d[:, 2:5], axis=1)
    cd = {(min(p, q), max(p, q)): f for p, q, f in zip(ci, cj, cf)}
    lm = {(min(p, q), max(p, q)): f for p, q, f in zip(li, lj, lf)}
    common = sorted(set(cd) & set(lm))
    if not common:
        print(json.dumps({"capdem_contacts": len(cd), "liggghts_contacts": len(lm), "common": 0}))
        return 1
    diff = np.array([abs(cd[k] - lm[k]) for k in common]) / np.mean(list(cd.values()))
    out = {"capdem_contacts": len(cd), "liggghts_contacts": len(lm), "common": len(common),
           "max_rel_diff": float(diff.max()), "median_rel_diff": float(np.median(diff)),
           "mean_fn": float(np.mean(list(cd.values()))), "tolerance": a.tolerance}
    print(json.dumps(out))
    return 0 if len(cd) == len(lm) == len(common) and diff.max() < a.tolerance else 1


if __name__ == "__main__":
    sys.exit(main())
