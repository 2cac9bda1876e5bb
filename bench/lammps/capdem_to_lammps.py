#!/usr/bin/python3
"""A capdem run file (last snapshot) as a LAMMPS data file.

    /usr/bin/python3 bench/lammps/capdem_to_lammps.py RUN.h5 OUT.data [--meta OUT.json]

Spheres become one LAMMPS sphere each (diameter 2 r, the particle's mass and
velocities).  Particles with arms (hexapods, rods, crosses) become rigid
clusters of glued spheres, the usual stand-in for non-spherical particles in
a code without spherocylinders: spheres of the arm diameter with centres on
each arm's axis segment, spaced at most d/2 (end points included, so the
tips of the cluster are those of the spherocylinder and the surface is
bumpy between spheres by at most 1 - sqrt(3)/2 = 13 % of r); spheres shared
by several arms (the centre of a hexapod) are kept once.  All spheres of one
particle get its molecule ID (for `fix rigid/small molecule`) and a density
that gives the cluster capdem's mass; sphere velocities are v + w x (x_s - x)
of the particle, so the rigid body starts with its momentum and (up to the
clusters' inertia, which differs a little from the spherocylinders') its
angular velocity.

The metadata (JSON) gives the box, the time step, the particle and sphere
counts and the largest body extent (for LAMMPS's ghost cut-off).
"""
import argparse
import json
import math
import os
import re
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "host"))  # capdem_h5
import capdem_h5  # noqa: E402


def config_value(text, key):
    m = re.search(r"\b%s:\s*([-+0-9.eE]+)" % key, text)
    if not m:
        raise SystemExit("capdem_to_lammps: no %s in the run file's config" % key)
    return float(m.group(1))


def read_run(path):
    with capdem_h5.open_run(path) as f:
        cfg = capdem_h5.config_text(f)
        k = capdem_h5.snapshot_count(f) - 1  # the last snapshot

        def column(name):
            return capdem_h5.column(f, name, k)
        run = {
            "config": cfg,
            "x": column("position"), "v": column("velocity"), "w": column("angvel"),
            "mass": column("mass"), "prim_first": column("prim_first"), "prim_count": column("prim_count"),
            "a": column("prim_a"), "b": column("prim_b"), "r": column("prim_radius").reshape(-1),
            "step": capdem_h5.step(f, k),
        }
    if "dimension: 2" in cfg:
        raise SystemExit("capdem_to_lammps: 2D runs are not converted (the comparison runs 3D cases)")
    return run


def glued_spheres(a, b, r):
    """Centres along segment a-b spaced at most r (= d/2), ends included."""
    length = np.linalg.norm(b - a)
    k = int(math.ceil(length / r - 1e-9)) if length > 0 else 0
    return [a + (b - a) * (i / k) for i in range(k + 1)] if k else [a]


def convert(run, out_path):
    x, v, w, mass = run["x"], run["v"], run["w"], run["mass"]
    n = len(mass)
    rigid = bool(np.any(run["prim_count"] > 1) or np.any(np.linalg.norm(run["b"] - run["a"], axis=1) > 0))
    atoms, vels = [], []
    extent = 0.0
    for p in range(n):
        first, count = int(run["prim_first"][p]), int(run["prim_count"][p])
        centres, radius = [], run["r"][first]
        for q in range(first, first + count):
            for c in glued_spheres(run["a"][q], run["b"][q], run["r"][q]):
                if all(np.linalg.norm(c - o) > 1e-9 * radius for o in centres):
                    centres.append(c)
        d = 2 * radius
        rho = mass[p] / (len(centres) * math.pi / 6 * d ** 3)
        for c in centres:
            extent = max(extent, 2 * np.linalg.norm(c - x[p]) + d)
            atoms.append((p + 1, d, rho, c))
            vels.append(v[p] + np.cross(w[p], c - x[p]))
    cfg = run["config"]
    W, T, H = config_value(cfg, "width"), config_value(cfg, "thickness"), config_value(cfg, "height")
    margin = 2 * max(a[1] for a in atoms)
    with open(out_path, "w") as f:
        f.write("capdem run file (step %d) as %s\n\n" % (run["step"], "rigid glued-sphere clusters" if rigid else "spheres"))
        f.write("%d atoms\n1 atom types\n\n" % len(atoms))
        f.write("%.9g %.9g xlo xhi\n%.9g %.9g ylo yhi\n%.9g %.9g zlo zhi\n\n" % (
            -margin, W + margin, -margin, H + margin, -margin, T + margin))
        if rigid:
            f.write("Atoms # hybrid\n\n")  # id type x y z diameter density molecule
            for i, (mol, d, rho, c) in enumerate(atoms):
                f.write("%d 1 %.12g %.12g %.12g %.12g %.12g %d\n" % (i + 1, c[0], c[1], c[2], d, rho, mol))
        else:
            f.write("Atoms # sphere\n\n")  # id type diameter density x y z
            for i, (mol, d, rho, c) in enumerate(atoms):
                f.write("%d 1 %.12g %.12g %.12g %.12g %.12g\n" % (i + 1, d, rho, c[0], c[1], c[2]))
        f.write("\nVelocities\n\n")
        for i, ((mol, _, _, _), u) in enumerate(zip(atoms, vels)):
            wp = w[mol - 1]
            f.write("%d %.12g %.12g %.12g %.12g %.12g %.12g\n" % (i + 1, u[0], u[1], u[2], wp[0], wp[1], wp[2]))
    return {
        "particles": n, "atoms": len(atoms), "rigid": rigid, "spheres_per_particle": len(atoms) / n,
        "width": W, "height": H, "thickness": T, "dt": config_value(cfg, "dt"),
        "max_body_extent": extent, "min_diameter": float(2 * run["r"].min()), "step": run["step"],
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("run")
    ap.add_argument("out")
    ap.add_argument("--meta", help="write the metadata JSON here too")
    a = ap.parse_args()
    meta = convert(read_run(a.run), a.out)
    if a.meta:
        with open(a.meta, "w") as f:
            json.dump(meta, f)
    print(json.dumps(meta))
    return 0


if __name__ == "__main__":
    sys.exit(main())
