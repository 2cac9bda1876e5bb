"""Checks `capdem export` of an mpm run file (docs/visualization.md,
"Material point runs") against the run file itself.

usage: /usr/bin/python3 check_mpm_export.py RUN.xmf RUN.h5 [box]

- the .xmf parses; its top-level grids are the temporal collections points,
  walls, outlines with one grid per committed snapshot, at the run's times;
- every data item names a dataset that exists with the declared dimensions,
  number type and precision; topologies and attributes have the lengths of
  their grid's points and cells;
- the numbers are the run's: positions and velocities (z = 0), volume,
  plastic strain, stress and its components, deformation gradient, particle
  ids, mass, walls' forces;
- each wall's segment lies on the wall's line; with `box`, its ends are the
  corners the four walls make;
- each particle's outline is a closed loop of its own, the convex hull of
  the corners of its points' deformed squares, computed here independently.
Prints one line per failure and exits 1 if any."""
import sys
import xml.etree.ElementTree as ET

import h5py
import numpy as np

xmf, run = sys.argv[1], sys.argv[2]
box = len(sys.argv) > 3 and sys.argv[3] == "box"
fails = []


def bad(msg):
    fails.append(msg)


f = h5py.File(run, "r")
S = int(f.attrs["n_snapshots"])
N = f["/mpm/points/particle"].shape[0]
W = f["/mpm/walls/normal"].shape[0]
tree = ET.parse(xmf)
domain = tree.getroot().find("Domain")
grids = {g.get("Name"): g for g in domain.findall("Grid")}
if sorted(grids) != ["outlines", "points", "walls"]:
    bad(f"top-level grids {sorted(grids)}, expected outlines, points, walls")

NUMPY = {("Float", 8): "f8", ("Float", 4): "f4", ("Int", 4): "i4", ("Int", 8): "i8"}


def item(el):
    """The dataset a DataItem names, after checking its shape and type."""
    dims = tuple(int(d) for d in el.get("Dimensions").split())
    name, path = el.text.strip().split(":", 1)
    h = f if name == run.split("/")[-1] else h5py.File(name, "r")
    if path not in h:
        bad(f"{path}: named by the .xmf, not in {name}")
        return None
    d = h[path]
    if d.shape != dims:
        bad(f"{path}: shape {d.shape}, the .xmf says {dims}")
    want = NUMPY.get((el.get("NumberType"), int(el.get("Precision"))))
    if want is None or np.dtype(d.dtype).str[1:] != want:
        bad(f"{path}: type {d.dtype}, the .xmf says {el.get('NumberType')} {el.get('Precision')}")
    return d[()]


def same(a, b, what):
    if a is None or b is None or np.shape(a) != np.shape(b) or not np.array_equal(a, b):
        bad(f"{what}: not the run file's numbers")


time = f["/mpm/snapshots/time"][:S]
pos_run, vel_run = f["/mpm/snapshots/position"], f["/mpm/snapshots/velocity"]
particle = f["/mpm/points/particle"][:]
for gname in ("points", "walls", "outlines"):
    coll = grids.get(gname)
    if coll is None:
        continue
    if coll.get("CollectionType") != "Temporal":
        bad(f"{gname}: not a temporal collection")
    steps = coll.findall("Grid")
    if len(steps) != S:
        bad(f"{gname}: {len(steps)} grids for {S} snapshots")
    for k, g in enumerate(steps):
        if float(g.find("Time").get("Value")) != time[k]:
            bad(f"{gname}[{k}]: time {g.find('Time').get('Value')} is not /mpm/snapshots/time {time[k]!r}")
        topo = g.find("Topology")
        ncell = int(topo.get("NumberOfElements"))
        cells = item(topo.find("DataItem"))
        pts = item(g.find("Geometry").find("DataItem"))
        if g.find("Geometry").get("GeometryType") != "XYZ" or pts is None or pts.shape[1] != 3:
            bad(f"{gname}[{k}]: geometry is not XYZ")
            continue
        if cells is None or cells.reshape(ncell, -1).max(initial=-1) >= len(pts) or cells.min(initial=0) < 0:
            bad(f"{gname}[{k}]: connectivity out of the points")
        attrs = {}
        for a in g.findall("Attribute"):
            v = item(a.find("DataItem"))
            rows = len(pts) if a.get("Center") == "Node" else ncell
            if v is None or len(v) != rows:
                bad(f"{gname}[{k}].{a.get('Name')}: not one value per {a.get('Center').lower()}")
            attrs[a.get("Name")] = v
        if np.any(pts[:, 2] != 0):
            bad(f"{gname}[{k}]: z is not 0")
        if gname == "points":
            same(pts[:, :2], pos_run[k], f"points[{k}] position")
            same(attrs.get("velocity", np.zeros((0, 3)))[:, :2], vel_run[k], f"points[{k}] velocity")
            if np.any(attrs.get("velocity", np.ones((1, 3)))[:, 2] != 0):
                bad(f"points[{k}]: velocity z is not 0")
            for name in ("volume", "plastic_strain", "stress", "deformation_gradient"):
                same(attrs.get(name), f["/mpm/snapshots/" + name][k], f"points[{k}] {name}")
            for c, name in enumerate(("stress_xx", "stress_yy", "stress_xy", "stress_zz")):
                same(attrs.get(name), f["/mpm/snapshots/stress"][k][:, c], f"points[{k}] {name}")
            same(attrs.get("particle"), particle, f"points[{k}] particle")
            same(attrs.get("mass"), f["/mpm/points/mass"][:], f"points[{k}] mass")
            same(attrs.get("point"), np.arange(N), f"points[{k}] point")
        elif gname == "walls":
            if ncell != W:
                bad(f"walls[{k}]: {ncell} lines for {W} walls")
                continue
            force = attrs.get("wall_force")
            same(None if force is None else force[:, :2], f["/mpm/snapshots/wall_force"][k], f"walls[{k}] force")
            wp, nrm = f["/mpm/snapshots/wall_position"][k], f["/mpm/walls/normal"][:]
            ends = pts[cells.reshape(W, 2)][:, :, :2]  # (W, 2 ends, xy)
            scale = np.ptp(pos_run[k], axis=0).max()
            for w in range(W):
                off = (ends[w] - wp[w]) @ nrm[w]
                if np.abs(off).max() > 1e-12 * scale or np.linalg.norm(ends[w][1] - ends[w][0]) <= 0:
                    bad(f"walls[{k}]: wall {w}'s segment {ends[w].tolist()} is not on its line")
            if box:  # walls 0 bottom, 1 top, 2 left, 3 right: the segments meet at the corners
                x0, x1, y0, y1 = wp[2][0], wp[3][0], wp[0][1], wp[1][1]
                corners = {(x0, y0), (x1, y0), (x0, y1), (x1, y1)}
                got = {(float(e[0]), float(e[1])) for e in ends.reshape(-1, 2)}
                if not all(min(abs(a - c[0]) + abs(b - c[1]) for c in corners) < 1e-15 for a, b in got):
                    bad(f"walls[{k}]: segment ends {sorted(got)} are not the box's corners {sorted(corners)}")
        else:  # outlines
            owner = attrs.get("particle")
            if owner is None:
                continue
            x, vol, F = pos_run[k], f["/mpm/snapshots/volume"][k], f["/mpm/snapshots/deformation_gradient"][k]
            J = F[:, 0] * F[:, 3] - F[:, 1] * F[:, 2]
            s = 0.5 * np.sqrt(vol / J)
            e = cells.reshape(ncell, 2)
            if set(owner.tolist()) != set(particle.tolist()):
                bad(f"outlines[{k}]: particles {sorted(set(owner.tolist()))[:5]}..., not every one of the run's")
            for b in np.unique(particle):
                mine = np.nonzero(owner == b)[0]
                poly = pts[e[mine, 0], :2]
                # a closed loop: each edge ends where the next begins
                if not np.array_equal(e[mine, 1], np.roll(e[mine, 0], -1)):
                    bad(f"outlines[{k}]: particle {b}'s edges are not one closed loop")
                    continue
                idx = np.nonzero(particle == b)[0]
                cx, cy = np.array([-1, 1, 1, -1]), np.array([-1, -1, 1, 1])
                qx = (x[idx, 0, None] + s[idx, None] * (F[idx, 0, None] * cx + F[idx, 1, None] * cy)).ravel()
                qy = (x[idx, 1, None] + s[idx, None] * (F[idx, 2, None] * cx + F[idx, 3, None] * cy)).ravel()
                corners = np.stack([qx, qy], axis=1)
                # every corner inside the counter-clockwise polygon or on it; every vertex one of them
                a, d = poly, np.roll(poly, -1, axis=0) - poly
                rel = corners[:, None, :] - a[None, :, :]
                crossv = d[None, :, 0] * rel[:, :, 1] - d[None, :, 1] * rel[:, :, 0]
                size = np.ptp(corners, axis=0).max()
                if crossv.min() < -1e-12 * size * size:
                    bad(f"outlines[{k}]: particle {b}: a corner lies outside its outline (convex, counter-clockwise)")
                near = np.abs(poly[:, None, :] - corners[None, :, :]).sum(axis=2).min(axis=1)
                if near.max() > 1e-15:
                    bad(f"outlines[{k}]: particle {b}: an outline vertex is not a corner of its points' squares")
for m in fails[:20]:
    print("check_mpm_export:", m)
print(f"check_mpm_export: {S} snapshots, {N} points, {W} walls: {len(fails)} failures")
sys.exit(1 if fails else 0)
