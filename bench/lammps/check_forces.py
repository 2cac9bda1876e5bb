#!/usr/bin/python3
"""One state, two codes: LAMMPS evaluates the contact forces of a packing
capdem settled (spheres), and the normal forces are compared pair by pair.

    build/capdem-bench --case spheres --n 1000 --friction-limit total --repeat 0 --save-settled S.h5
    /usr/bin/python3 bench/lammps/check_forces.py S.h5 [--work build/bench-work]

LAMMPS reads the packing (capdem_to_lammps.py), takes no step (`run 0`) and
dumps every touching pair with its normal force (compute pair/local force).
A run of `material.law: hertz_mindlin` (its config must give
young_modulus, poisson_ratio, damping_normal and friction) is evaluated with
LAMMPS's hertz/material and tangential mindlin (lammps_law.hertz_constants);
any other run with the linear law of the bench cases.
Prints the contact counts and the largest and median |F_n(capdem) -
F_n(LAMMPS)| / <F_n>.  Exit 1 if the contact sets differ or the largest
difference exceeds 1e-2 (the damping term sees velocities half a step
apart in the two codes; the elastic parts are identical).
"""
import argparse
import json
import os
import re
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import capdem_to_lammps  # noqa: E402
import compare  # noqa: E402
import lammps_law  # noqa: E402
import parity  # noqa: E402


def law_of(cfg):
    """LAMMPS constants for the run's law: Hertz-Mindlin from its config, or
    None (compare.py's linear MATERIAL)."""
    if not re.search(r"\blaw:\s*hertz_mindlin\b", cfg):
        return None
    E, nu = capdem_to_lammps.config_value(cfg, "young_modulus"), capdem_to_lammps.config_value(cfg, "poisson_ratio")
    eta_n, mu = capdem_to_lammps.config_value(cfg, "damping_normal"), capdem_to_lammps.config_value(cfg, "friction")
    return lammps_law.hertz_constants(E, nu, eta_n, eta_n, mu)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("run")
    ap.add_argument("--work", default="build/bench-work")
    ap.add_argument("--threads", type=int, default=2)
    a = ap.parse_args()
    a.steps, a.repeat = 1, 0
    compare.ensure_lammps()
    os.makedirs(a.work, exist_ok=True)
    base = os.path.join(a.work, "check_forces")
    run = capdem_to_lammps.read_run(a.run)
    meta = capdem_to_lammps.convert(run, base + ".data")
    if meta["rigid"]:
        raise SystemExit("check_forces: spheres only (glued clusters are not capdem's shapes)")
    compare.run_lammps(a, base + ".data", meta, base + ".lammps.log", 0, 0, contacts=base + ".contacts", nrepeat=0,
                       law=law_of(run["config"]))
    ci, cj, cf, _ = parity.capdem_contacts(a.run)
    li, lj, lf = parity.lammps_contacts(base + ".contacts")
    cd = {(min(p, q), max(p, q)): f for p, q, f in zip(ci, cj, cf)}
    lm = {(min(p, q), max(p, q)): f for p, q, f in zip(li, lj, lf)}
    common = sorted(set(cd) & set(lm))
    diff = np.array([abs(cd[k] - lm[k]) for k in common]) / np.mean(list(cd.values()))
    out = {"capdem_contacts": len(cd), "lammps_contacts": len(lm), "common": len(common),
           "max_rel_diff": float(diff.max()), "median_rel_diff": float(np.median(diff))}
    print(json.dumps(out))
    return 0 if len(cd) == len(lm) == len(common) and diff.max() < 1e-2 else 1


if __name__ == "__main__":
    sys.exit(main())
