#!/usr/bin/python3
"""Draws one snapshot of a capdem run file as a PNG (docs/visualization.md).

    capdem render RUN.h5 [--snapshot N] -o PICTURE.png [--mode arms|forces]
                  [--color particle|height|shape|speed|plastic] [--view ELEV,AZIM]
                  [--width INCHES] [--dpi D] [--title TEXT]

mode arms    every arm as a shaded capsule (spherocylinder), coloured by
             particle (default), height, shape or speed;
mode forces  the contact network: a line between the centres of every pair
             of touching particles, width and colour by the normal force,
             over faint arms.

A run file of the material point method (solver mpm) is drawn by
host/render_mpm.py: every material point as its deformed square, coloured
by particle, plastic (equivalent plastic strain) or speed, and the walls.

Runs with Debian's python3-matplotlib, python3-h5py and python3-numpy.  A 2D
run (every arm end at one z) is drawn in the x-y plane; a 3D run with an
orthographic camera (y up), the capsules as polygon meshes, back faces
dropped and the rest painted far to near.

Exit status: 0 picture written, 2 bad input (file, snapshot, option) or a
missing Python module, 1 other failures.
"""
import argparse
import os
import sys

# capdem render runs this script isolated (python3 -I), without its folder
# on the import path: capdem_h5 lies beside it.
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
try:
    import numpy as np
    import capdem_h5
    import matplotlib
    matplotlib.use("Agg")  # no display needed, and none is wanted in tests
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection, PolyCollection
    from matplotlib import colors as mcolors
    from mpl_toolkits.axes_grid1 import make_axes_locatable
    import render_mpm
except ImportError as e:  # the caller maps 2 to "install the Debian packages"
    sys.stderr.write("capdem render: %s (needs python3-matplotlib, python3-h5py and "
                     "python3-numpy: apt-get install python3-matplotlib python3-h5py "
                     "python3-numpy)\n" % e)
    sys.exit(2)


BadInput = render_mpm.BadInput  # one kind of bad input for both readers


# ---------------------------------------------------------------- reading

def render_read(path, snapshot):
    """Everything one picture needs, from snapshot `snapshot` (negative:
    counted from the end) of the run file.  A run file of the material
    point method (root attribute solver = "mpm") is read by render_mpm."""
    try:
        f = capdem_h5.open_run(path)
    except capdem_h5.LayoutError as e:
        raise BadInput(str(e))
    except OSError as e:
        raise BadInput("%s: cannot open (%s)" % (path, e))
    with f:
        solver = f.attrs.get("solver", b"")
        if (solver.decode() if isinstance(solver, bytes) else str(solver)) == "mpm":
            return dict(render_mpm.read(f, path, snapshot), solver="mpm")
        H = capdem_h5
        need = [H.COLUMN[c][0] for c in ("prim_a", "prim_b", "prim_radius", "prim_particle", "position")]
        need += [H.PATH[p] for p in ("snap_step", "snap_time", "c_offset", "w_offset")]
        for name in need:
            if name not in f:
                raise BadInput("%s: not a capdem run file (no %s)" % (path, name))
        # docs/output.md: the committed count, never rows beyond it.
        n = min(H.snapshot_count(f), H.column_dataset(f, "prim_a").shape[0], H.column_dataset(f, "position").shape[0])
        k = render_mpm.snapshot_index(path, snapshot, n)
        d = {"k": k, "n": n, "path": path}
        d["a"] = H.column(f, "prim_a", k)
        d["b"] = H.column(f, "prim_b", k)
        d["radius"] = H.column(f, "prim_radius")
        d["owner"] = H.column(f, "prim_particle").astype(np.int64)
        d["pos"] = H.column(f, "position", k)
        d["vel"] = H.column(f, "velocity", k) if H.has_column(f, "velocity") else None
        d["shape"] = H.column(f, "shape") if H.has_column(f, "shape") else None
        d["time"] = H.time(f, k)
        d["step"] = H.step(f, k)
        c0, c1 = H.rows(f, k)
        if c1 > c0 and H.PATH["c_particle_i"] in f:
            d["ci"] = H.snapshot_rows(f, "c_particle_i", k).astype(np.int64)
            d["cj"] = H.snapshot_rows(f, "c_particle_j", k).astype(np.int64)
            d["fn"] = H.column(f, "pair_fn", k) if H.has_column(f, "pair_fn") else np.ones(c1 - c0)
        else:
            d["ci"] = d["cj"] = np.zeros(0, np.int64)
            d["fn"] = np.zeros(0)
        d["walls"] = H.walls(f, k)
        d["name"] = os.path.splitext(os.path.basename(path))[0]
    return d


# ---------------------------------------------------------------- colours

def render_base_colors(d, how):
    """One RGB per arm."""
    owner = d["owner"]
    npart = len(d["pos"])
    if how == "particle":
        # Neighbouring ids are often neighbours in space (lattice placement):
        # a fixed scrambling of the ids keeps adjacent particles apart in hue.
        pal = plt.get_cmap("tab20")(np.arange(20))[:, :3]
        idx = (owner * 7 + owner // 20 * 3) % 20
        return pal[idx]
    if how == "shape" and d["shape"] is not None:
        pal = plt.get_cmap("tab10")(np.arange(10))[:, :3]
        return pal[d["shape"][owner] % 10]
    if how == "speed" and d["vel"] is not None:
        v = np.linalg.norm(d["vel"], axis=1)
        norm = mcolors.Normalize(0, max(v.max(), 1e-30))
        return plt.get_cmap("plasma")(norm(v[owner]))[:, :3], ("speed [m/s]", norm, "plasma")
    # height (y is up)
    y = d["pos"][:, 1] if npart else np.zeros(0)
    lo, hi = (y.min(), y.max()) if npart else (0, 1)
    norm = mcolors.Normalize(lo, hi if hi > lo else lo + 1)
    return plt.get_cmap("viridis")(norm(y[owner]))[:, :3], ("height y [m]", norm, "viridis")


# ---------------------------------------------------------------- 3D camera

class Camera:
    """Orthographic camera looking at the origin; y is up.  elev, azim in
    degrees: azim turns about y (0 looks along -z), elev tilts down onto the
    scene."""

    def __init__(self, elev, azim):
        el, az = np.radians(elev), np.radians(azim)
        self.eye = np.array([np.cos(el) * np.sin(az), np.sin(el), np.cos(el) * np.cos(az)])
        up = np.array([0.0, 1.0, 0.0])
        right = np.cross(up, self.eye)
        if np.linalg.norm(right) < 1e-9:  # looking straight down
            right = np.array([1.0, 0.0, 0.0])
        self.right = right / np.linalg.norm(right)
        self.up = np.cross(self.eye, self.right)
        # Light from the upper left, a little from the viewer's side.
        light = -0.45 * self.right + 0.75 * self.up + 0.5 * self.eye
        self.light = light / np.linalg.norm(light)
        half = self.light + self.eye
        self.half = half / np.linalg.norm(half)

    def project(self, p):
        return np.stack([p @ self.right, p @ self.up], axis=-1)

    def depth(self, p):
        return p @ self.eye  # larger: nearer to the viewer


def render_capsule_mesh(a, b, r, m, nlat):
    """Quads of P capsules: vertices (P, F, 4, 3) and outward normals at the
    vertices (P, F, 4, 3).  Each capsule is a surface of revolution: a
    hemisphere at a, the cylinder, a hemisphere at b, with m points around
    and nlat latitude bands per hemisphere."""
    P = len(a)
    axis = b - a
    L = np.linalg.norm(axis, axis=1)
    t = np.where(L[:, None] > 1e-300, axis / np.maximum(L, 1e-300)[:, None], np.array([0.0, 1.0, 0.0]))
    helper = np.where(np.abs(t[:, :1]) < 0.9, np.array([[1.0, 0.0, 0.0]]), np.array([[0.0, 1.0, 0.0]]))
    n1 = np.cross(t, helper)
    n1 /= np.linalg.norm(n1, axis=1)[:, None]
    n2 = np.cross(t, n1)
    # Profile: latitude th from -90 (pole at a) to +90 (pole at b); the
    # equator appears twice, once at each end of the cylinder.
    th = np.concatenate([np.linspace(-np.pi / 2, 0, nlat + 1), np.linspace(0, np.pi / 2, nlat + 1)])
    at_b = np.concatenate([np.zeros(nlat + 1), np.ones(nlat + 1)])
    phi = np.linspace(0, 2 * np.pi, m, endpoint=False)
    cphi, sphi = np.cos(phi), np.sin(phi)
    radial = cphi[None, :, None] * n1[:, None, :] + sphi[None, :, None] * n2[:, None, :]  # (P, m, 3)
    # vertex normal and position, (P, rings, m, 3)
    nrm = (np.sin(th)[None, :, None, None] * t[:, None, None, :] +
           np.cos(th)[None, :, None, None] * radial[:, None, :, :])
    centre = a[:, None, :] + (at_b[None, :] * L[:, None])[:, :, None] * t[:, None, :]
    pts = centre[:, :, None, :] + r[:, None, None, None] * nrm
    j1 = (np.arange(m) + 1) % m
    rings = len(th)
    quads_p = np.stack([pts[:, :-1, :, :], pts[:, :-1, j1, :], pts[:, 1:, j1, :], pts[:, 1:, :, :]], axis=3)
    quads_n = np.stack([nrm[:, :-1, :, :], nrm[:, :-1, j1, :], nrm[:, 1:, j1, :], nrm[:, 1:, :, :]], axis=3)
    F = (rings - 1) * m
    return quads_p.reshape(P, F, 4, 3), quads_n.reshape(P, F, 4, 3)


def render_mesh_resolution(P):
    """Points around and latitude bands: fine enough to look round, coarse
    enough that matplotlib draws it in seconds."""
    if P <= 3000:
        return 20, 4
    if P <= 12000:
        return 10, 2
    return 6, 1


def render_capsules_3d(ax, cam, a, b, r, rgb, faint=False, zorder=2):
    """Shaded capsules, painted far to near; returns the 2D extent.  faint:
    washed out towards white (opaque: see-through polygons would show every
    facet edge), as a backdrop for the contact network."""
    m, nlat = render_mesh_resolution(len(a))
    quads, normals = render_capsule_mesh(a, b, r, m, nlat)
    P, F = quads.shape[:2]
    fn = normals.sum(axis=2)
    fn /= np.maximum(np.linalg.norm(fn, axis=2), 1e-300)[:, :, None]
    facing = fn @ cam.eye
    keep = facing > -0.05  # back faces of a closed surface are hidden anyway
    q = quads[keep]
    n = fn[keep]
    col = np.broadcast_to(rgb[:, None, :], (P, F, 3))[keep]
    diffuse = np.clip(n @ cam.light, 0, None)
    spec = np.clip(n @ cam.half, 0, None) ** 40
    shade = 0.30 + 0.70 * diffuse
    col = np.clip(col * shade[:, None] + 0.35 * spec[:, None], 0, 1)
    if faint:
        col = 1.0 - 0.35 * (1.0 - col)
    order = np.argsort(cam.depth(q.mean(axis=1)), kind="stable")
    verts = cam.project(q[order])
    rgba = np.concatenate([col[order], np.ones((len(order), 1))], axis=1)
    pc = PolyCollection(verts, facecolors=rgba, edgecolors=rgba, linewidths=0.15, zorder=zorder)
    ax.add_collection(pc)
    flat = cam.project(quads.reshape(-1, 3))
    return flat.min(axis=0), flat.max(axis=0)


def render_walls_3d(ax, cam, d, lo3, hi3, front):
    """Faint outlines of cylinder and ball walls, back halves behind the
    particles, front halves over them.  Returns the 2D points drawn (for the
    extent of the picture)."""
    drawn = [np.zeros((0, 2))]
    if d["walls"] is None:
        return drawn[0]
    walls = d["walls"]
    floor = None
    for w in walls:
        if int(w["type"]) == capdem_h5.WALL_PLANE and abs(w["normal"][1]) > 0.99 and w["normal"][1] > 0:
            floor = float(w["point"][1])
    phi = np.linspace(0, 2 * np.pi, 241)
    for w in walls:
        typ = int(w["type"])
        R = float(w["radius"])
        p = np.asarray(w["point"], float)
        if typ == capdem_h5.WALL_CYLINDER and R > 0:  # vertical cylinder (axis along y in capdem's set-ups)
            ylo = floor if floor is not None else lo3[1]
            yhi = max(hi3[1], ylo)
            for y in (ylo, yhi):
                ring = np.stack([p[0] + R * np.cos(phi), np.full_like(phi, y), p[2] + R * np.sin(phi)], axis=1)
                dep = (ring - p) @ cam.eye
                sel = dep >= 0 if front else dep < 0
                xy = cam.project(ring)
                drawn.append(xy.copy())
                xy[~sel] = np.nan
                ax.plot(xy[:, 0], xy[:, 1], color="0.35", lw=0.8 if front else 0.6,
                        alpha=0.55 if front else 0.35, zorder=3 if front else 1)
            if front:
                # silhouette lines: where the wall is tangent to the view
                side = np.cross(np.array([0.0, 1.0, 0.0]), cam.eye)
                if np.linalg.norm(side) > 1e-9:
                    side /= np.linalg.norm(side)
                    for s in (-1, 1):
                        e = p + s * R * side
                        seg = cam.project(np.array([[e[0], ylo, e[2]], [e[0], yhi, e[2]]]))
                        ax.plot(seg[:, 0], seg[:, 1], color="0.35", lw=0.8, alpha=0.55, zorder=3)
        elif typ == capdem_h5.WALL_SPHERE and R > 0 and front:
            c = cam.project(p)
            ax.plot(c[0] + R * np.cos(phi), c[1] + R * np.sin(phi), color="0.35", lw=0.8, alpha=0.5, zorder=3)
            drawn.append(np.stack([c[0] + R * np.cos(phi), c[1] + R * np.sin(phi)], axis=1))
    return np.concatenate(drawn)


def render_axes_triad(ax, cam, origin, size):
    """Small x, y, z arrows so that a 3D picture says which way is up."""
    for vec, name in ((np.eye(3)[0], "x"), (np.eye(3)[1], "y"), (np.eye(3)[2], "z")):
        d2 = cam.project(vec) * size
        ax.annotate("", xy=(origin[0] + d2[0], origin[1] + d2[1]), xytext=origin,
                    arrowprops=dict(arrowstyle="-|>", color="0.2", lw=0.8), zorder=5)
        ax.text(origin[0] + 1.25 * d2[0], origin[1] + 1.25 * d2[1], name, fontsize=8,
                ha="center", va="center", color="0.2", zorder=5)


def render_scale_bar(ax, lo, hi, dim2):
    """A bar of a round length in the lower right corner."""
    span = hi[0] - lo[0]
    raw = span / 5
    p10 = 10 ** np.floor(np.log10(raw))
    length = max(v * p10 for v in (1, 2, 5) if v * p10 <= raw)
    x1 = hi[0] - 0.04 * span
    y0 = lo[1] + 0.04 * (hi[1] - lo[1])
    ax.plot([x1 - length, x1], [y0, y0], color="0.1", lw=2.5, solid_capstyle="butt", zorder=6)
    label = ("%g mm" % (length * 1e3)) if length < 0.1 else ("%g m" % length)
    ax.text(x1 - length / 2, y0 + 0.015 * (hi[1] - lo[1]), label, ha="center", va="bottom", fontsize=8, zorder=6)


# ---------------------------------------------------------------- 2D

def render_capsule_outline_2d(a, b, r, n=10):
    """Closed outlines of capsules in the x-y plane, (P, 2n+2, 2)."""
    axis = b - a
    L = np.linalg.norm(axis, axis=1)
    t = np.where(L[:, None] > 1e-300, axis / np.maximum(L, 1e-300)[:, None], np.array([1.0, 0.0]))
    nrm = np.stack([-t[:, 1], t[:, 0]], axis=1)
    ang = np.linspace(-np.pi / 2, np.pi / 2, n + 1)
    # half circle around b (from -normal through +t to +normal), then around a
    cb = np.cos(ang)[None, :, None] * t[:, None, :] + np.sin(ang)[None, :, None] * nrm[:, None, :]
    ca = -cb
    pb = b[:, None, :] + r[:, None, None] * cb
    pa = a[:, None, :] + r[:, None, None] * ca
    return np.concatenate([pb, pa], axis=1)


def render_walls_2d(ax, d, lo, hi):
    if d["walls"] is None:
        return
    for w in d["walls"]:
        if int(w["type"]) != capdem_h5.WALL_PLANE:
            continue
        nx, ny, nz = (float(v) for v in w["normal"])
        if abs(nz) > 0.5:
            continue  # the z walls of a 2D box are the plane of the picture
        p = np.asarray(w["point"], float)
        tx, ty = -ny, nx
        big = 4 * max(hi[0] - lo[0], hi[1] - lo[1])
        ax.plot([p[0] - big * tx, p[0] + big * tx], [p[1] - big * ty, p[1] + big * ty],
                color="0.3", lw=1.2, zorder=1)


# ---------------------------------------------------------------- picture

def render_picture(d, args):
    a, b, r = d["a"], d["b"], d["radius"]
    pts = np.concatenate([a, b]) if len(a) else np.zeros((1, 3))
    zs = pts[:, 2]
    extent = max(np.ptp(pts[:, 0]), np.ptp(pts[:, 1]), 1e-300)
    dim2 = np.ptp(zs) <= 1e-9 * extent
    forces = args.mode == "forces"
    colored = render_base_colors(d, args.color if not forces else "particle")
    if isinstance(colored, tuple):
        rgb, cbar = colored
    else:
        rgb, cbar = colored, None
    if forces:
        rgb = np.full((len(a), 3), 0.70)  # grey arms under the network
        cbar = None

    # The height follows the picture's aspect once it is known (below).
    fig, ax = plt.subplots(figsize=(args.width, args.width), dpi=args.dpi)
    ax.set_aspect("equal")

    if dim2:
        ab2 = render_capsule_outline_2d(a[:, :2], b[:, :2], r)
        # Outline pass (slightly fatter, dark) under a fill pass: the outline
        # shows only on the outside of each particle, not where its own arms
        # overlap at the centre.
        edge = render_capsule_outline_2d(a[:, :2], b[:, :2], r + 0.06 * np.median(r))
        alpha = 0.35 if forces else 1.0
        ax.add_collection(PolyCollection(edge, facecolors=(0.15, 0.15, 0.15, alpha), edgecolors="none", zorder=1))
        ax.add_collection(PolyCollection(ab2, facecolors=np.concatenate([rgb, np.full((len(rgb), 1), alpha)], 1),
                                         edgecolors="none", zorder=2))
        lo = (np.minimum(a, b) - r[:, None]).min(axis=0)[:2]
        hi = (np.maximum(a, b) + r[:, None]).max(axis=0)[:2]
        proj_pos = d["pos"][:, :2]
        # Walls bound the view sideways and below, not above (the particles'
        # top is the interesting edge).
        vlo, vhi = lo.copy(), hi.copy()
        if d["walls"] is not None:
            for wl in d["walls"]:
                if int(wl["type"]) == capdem_h5.WALL_PLANE and abs(wl["normal"][2]) < 0.5:
                    p = wl["point"]
                    if abs(wl["normal"][0]) > 0.99:
                        vlo[0], vhi[0] = min(vlo[0], p[0]), max(vhi[0], p[0])
                    if wl["normal"][1] > 0.99:
                        vlo[1] = min(vlo[1], p[1])
        render_walls_2d(ax, d, vlo, vhi)
        lo, hi = vlo, vhi
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
        cam = None
    else:
        cam = Camera(*args.view)
        centre = 0.5 * (pts.min(axis=0) + pts.max(axis=0))
        lo3 = pts.min(axis=0)
        hi3 = pts.max(axis=0)
        shifted = (a - centre, b - centre)
        local = dict(d, walls=_shift_walls(d["walls"], centre))
        render_walls_3d(ax, cam, local, lo3 - centre, hi3 - centre, front=False)
        lo, hi = render_capsules_3d(ax, cam, shifted[0], shifted[1], r, rgb, faint=forces)
        wall_xy = render_walls_3d(ax, cam, local, lo3 - centre, hi3 - centre, front=True)
        if len(wall_xy):
            lo = np.minimum(lo, wall_xy.min(axis=0))
            hi = np.maximum(hi, wall_xy.max(axis=0))
        proj_pos = cam.project(d["pos"] - centre)
        ax.set_axis_off()

    network = render_network(ax, d, proj_pos, cam, dim2) if forces else None

    pad = 0.04 * max(hi[0] - lo[0], hi[1] - lo[1])
    lo = lo - pad
    hi = hi + pad
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    if not dim2:
        render_axes_triad(ax, cam, (lo[0] + 0.08 * (hi[0] - lo[0]), lo[1] + 0.08 * (hi[1] - lo[1])),
                          0.06 * max(hi[0] - lo[0], hi[1] - lo[1]))
        render_scale_bar(ax, lo, hi, dim2)

    # The axes fill the figure, whose height follows the picture's aspect;
    # labels, title and colour bar lie outside and the tight bounding box at
    # saving takes them in.
    if network is not None:
        cbar = ("normal force [N]",) + network
    render_fit_figure(fig, ax, args.width, lo, hi, cbar)

    nc = len(d["fn"])
    title = args.title or ("%s  snapshot %d of %d  t = %.4g s  %d particles, %d arms, %d contacts"
                           % (d["name"], d["k"], d["n"], d["time"], len(d["pos"]), len(a), nc))
    ax.set_title(title, fontsize=9)
    # tight: the equal-aspect axes leave margins that depend on the picture
    fig.savefig(args.output, dpi=args.dpi, bbox_inches="tight", pad_inches=0.08)
    plt.close(fig)


def render_fit_figure(fig, ax, width, lo, hi, cbar):
    """The figure's height from the picture's aspect (the axes fill it) and
    the colour bar (label, norm, colormap) at the right, if any."""
    aspect = (hi[1] - lo[1]) / (hi[0] - lo[0])
    frac = 0.94 if cbar else 1.0
    fig.set_size_inches(width, min(max(width * frac * aspect, 1.5), 2.0 * width))
    fig.subplots_adjust(left=0, right=1, bottom=0, top=1)
    if cbar:
        label, norm, cmap = cbar
        cax = make_axes_locatable(ax).append_axes("right", size="2.5%", pad=0.1)
        fig.colorbar(plt.cm.ScalarMappable(norm=norm, cmap=cmap), cax=cax, label=label)


def _shift_walls(walls, centre):
    if walls is None:
        return None
    w = walls.copy()
    w["point"] = w["point"] - centre
    return w


def render_network(ax, d, proj_pos, cam, dim2):
    """Lines between the centres of touching particles; width and colour by
    the normal force (largest force: thickest, darkest).  Returns the colour
    scale (norm, colormap) for the colour bar."""
    ci, cj, fn = d["ci"], d["cj"], np.asarray(d["fn"], float)
    N = len(d["pos"])
    ok = (ci >= 0) & (cj >= 0) & (ci < N) & (cj < N) & (ci != cj)
    ci, cj, fn = ci[ok], cj[ok], fn[ok]
    fmax = fn.max() if len(fn) and fn.max() > 0 else 1.0
    norm = mcolors.Normalize(0, fmax)
    cmap = plt.get_cmap("inferno_r")
    if len(fn):
        seg = np.stack([proj_pos[ci], proj_pos[cj]], axis=1)
        # draw weak contacts first so that the strong chains stay on top
        order = np.argsort(fn, kind="stable")
        if not dim2:
            depth = cam.depth(0.5 * (d["pos"][ci] + d["pos"][cj]))
            order = np.lexsort((depth, fn))
        widths = 0.4 + 4.6 * np.clip(fn[order] / fmax, 0, 1)
        lc = LineCollection(seg[order], linewidths=widths, colors=cmap(norm(fn[order])), capstyle="round",
                            zorder=4)
        ax.add_collection(lc)
    return norm, cmap


def render_parse(argv):
    p = argparse.ArgumentParser(prog="capdem render", description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("run", help="capdem run file (HDF5)")
    p.add_argument("-o", "--output", required=True, help="PNG to write")
    p.add_argument("--snapshot", type=int, default=-1, help="snapshot index; negative counts from the end (default -1: last)")
    p.add_argument("--mode", choices=("arms", "forces"), default="arms")
    p.add_argument("--color", choices=("particle", "height", "shape", "speed", "plastic"), default="particle",
                   help="arm colours in mode arms (default particle); material point runs: particle, "
                   "plastic (equivalent plastic strain) or speed")
    p.add_argument("--view", default="22,-35", help="3D camera elevation,azimuth in degrees (default 22,-35)")
    p.add_argument("--width", type=float, default=7.0, help="picture width in inches (default 7; height follows)")
    p.add_argument("--dpi", type=int, default=110)
    p.add_argument("--title", default=None)
    args = p.parse_args(argv)
    try:
        args.view = tuple(float(v) for v in args.view.split(","))
        if len(args.view) != 2 or args.width <= 0 or args.dpi <= 0:
            raise ValueError
    except ValueError:
        p.error("--view takes two numbers separated by a comma, --width and --dpi positive numbers")
    if not args.output.lower().endswith(".png"):
        p.error("-o %s: the picture is a PNG, name it *.png" % args.output)
    return args


def main(argv):
    args = render_parse(argv)  # argparse exits with 2 on bad options
    try:
        d = render_read(args.run, args.snapshot)
    except BadInput as e:
        sys.stderr.write("capdem render: %s\n" % e)
        return 2
    try:
        if d.get("solver") == "mpm":
            render_mpm.draw(d, args, render_fit_figure)
        elif args.color == "plastic":
            raise BadInput("--color plastic: only material point runs (solver mpm) have a plastic strain")
        else:
            render_picture(d, args)
    except BadInput as e:
        sys.stderr.write("capdem render: %s: %s\n" % (args.run, e))
        return 2
    except OSError as e:
        sys.stderr.write("capdem render: %s: cannot write (%s)\n" % (args.output, e))
        return 1
    print("capdem render: wrote %s (snapshot %d of %d, mode %s)" % (args.output, d["k"], d["n"], args.mode))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
