"""capdem render of material point run files (solver mpm, docs/mpm.md):
host/render.py calls draw() when the run file's root attribute `solver` is
"mpm" (docs/visualization.md, "Material point runs").

Each material point is drawn as its deformed square, x_p + F_p [-l/2, l/2]^2
with l its initial side sqrt(V_p / det F_p) (the square the export's and the
analysis' outlines are the convex hull of), filled in its colour over a
darker, slightly wider pass of the same squares (RGB 31): the dark shows only
on the outside of each particle's area, so the particles' boundaries read as
lines.  The walls are lines 2 points wide in RGB 64, across the box (the
packings) or across the points' extent plus a tenth (the diametral test's
two walls).

Colours (--color): particle (default, as the DEM render's palette), plastic
(the equivalent plastic strain on a log scale; points that never yielded,
plastic strain exactly 0, light grey RGB 204, 204, 204), speed.  Squares and
walls are drawn without antialiasing, so every pixel of a point's square has
its point's colour exactly (tests/mpm/check_mpm_render.py reads them back).  The
PNG's text chunk `capdem:axes` holds the axes' pixel box in the written
image and their data limits, `x0 y0 x1 y1 xmin xmax ymin ymax` (pixels from
the top-left corner, metres), so that a reader can find the point at a
pixel.
"""
import os

import numpy as np
import matplotlib.pyplot as plt
from matplotlib.collections import PolyCollection
from matplotlib import colors as mcolors

ELASTIC_GREY = 0.8  # RGB of points whose plastic strain is 0 (204 of 255)
EDGE_GREY = 0.12  # the dark pass under the particles
PLASTIC_CMAP = "plasma"  # purple (little) to yellow (much): never grey
PLASTIC_DECADES = 3  # the log scale spans max / 10^3 .. max; less is its lowest colour


class BadInput(Exception):
    """Bad input (file, snapshot, option): exit status 2 (host/render.py)."""


def snapshot_index(path, snapshot, n):
    """The index of --snapshot `snapshot` (negative: from the end) among n
    committed snapshots (host/render.py's DEM reader uses it too)."""
    if n <= 0:
        raise BadInput("%s: the run file holds no complete snapshot" % path)
    k = snapshot if snapshot >= 0 else n + snapshot
    if not 0 <= k < n:
        raise BadInput("%s: --snapshot %d: the file holds snapshots 0..%d (or -1..-%d from the end)"
                       % (path, snapshot, n - 1, n))
    return k


def read(f, path, snapshot):
    """Snapshot `snapshot` (negative: from the end) of an open mpm run file."""
    need = ["/mpm/points/particle", "/mpm/walls/normal", "/mpm/snapshots/step", "/mpm/snapshots/time",
            "/mpm/snapshots/position", "/mpm/snapshots/velocity", "/mpm/snapshots/volume",
            "/mpm/snapshots/plastic_strain", "/mpm/snapshots/deformation_gradient", "/mpm/snapshots/wall_position"]
    for name in need:
        if name not in f:
            raise BadInput("%s: %s is missing (a run file of solver mpm must have it: docs/mpm.md)" % (path, name))
    # The committed snapshots (root attribute n_snapshots, docs/mpm.md), never rows beyond them.
    n = min(len(f[name]) for name in need[2:])
    if "n_snapshots" in f.attrs:
        n = min(n, int(f.attrs["n_snapshots"]))
    k = snapshot_index(path, snapshot, n)
    S = "/mpm/snapshots/"
    d = {"k": k, "n": n, "path": path, "name": os.path.splitext(os.path.basename(path))[0]}
    d["particle"] = f["/mpm/points/particle"][()].astype(np.int64)
    d["pos"] = f[S + "position"][k]  # (N, 2) m
    d["vel"] = f[S + "velocity"][k]  # (N, 2) m/s
    d["volume"] = f[S + "volume"][k]  # (N) m^3/m
    d["eps_p"] = f[S + "plastic_strain"][k]  # (N) 1
    d["F"] = f[S + "deformation_gradient"][k]  # (N, 4): xx, xy, yx, yy
    d["wall_normal"] = f["/mpm/walls/normal"][()]  # (W, 2)
    d["wall_position"] = f[S + "wall_position"][k]  # (W, 2) m: a point of each wall's line
    d["step"] = int(f[S + "step"][k])
    d["time"] = float(f[S + "time"][k])
    N = len(d["particle"])
    for key in ("pos", "vel", "volume", "eps_p", "F"):
        if len(d[key]) != N:
            raise BadInput("%s: %s%s has %d rows, /mpm/points/particle %d" % (path, S, key, len(d[key]), N))
    return d


def squares(d):
    """The deformed squares of the points, (N, 4, 2) m, counter-clockwise."""
    F = d["F"]
    det = F[:, 0] * F[:, 3] - F[:, 1] * F[:, 2]
    half = 0.5 * np.sqrt(np.maximum(d["volume"], 0) / np.where(det > 0, det, 1.0))
    unit = np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])
    # F c for each corner c = half * unit: (F_xx c_x + F_xy c_y, F_yx c_x + F_yy c_y)
    cx = half[:, None] * unit[None, :, 0]
    cy = half[:, None] * unit[None, :, 1]
    off = np.stack([F[:, None, 0] * cx + F[:, None, 1] * cy, F[:, None, 2] * cx + F[:, None, 3] * cy], axis=2)
    return d["pos"][:, None, :] + off


def colors(d, how):
    """One RGB per point, and the colour bar (label, norm, colormap) or None."""
    if how == "particle":
        # the DEM render's palette and scrambling (host/render.py)
        owner = d["particle"]
        pal = plt.get_cmap("tab20")(np.arange(20))[:, :3]
        return pal[(owner * 7 + owner // 20 * 3) % 20], None
    if how == "speed":
        v = np.linalg.norm(d["vel"], axis=1)
        norm = mcolors.Normalize(0, max(v.max(), 1e-30))
        return plt.get_cmap("viridis")(norm(v))[:, :3], ("speed [m/s]", norm, plt.get_cmap("viridis"))
    # plastic
    eps = d["eps_p"]
    rgb = np.full((len(eps), 3), ELASTIC_GREY)
    top = float(eps.max()) if len(eps) else 0.0
    cmap = plt.get_cmap(PLASTIC_CMAP)
    if top <= 0:
        return rgb, None  # nothing yielded: all grey, no scale to show
    norm = mcolors.LogNorm(top / 10**PLASTIC_DECADES, top, clip=True)
    yielded = eps > 0
    rgb[yielded] = cmap(norm(eps[yielded]))[:, :3]
    return rgb, ("equivalent plastic strain (grey: 0)", norm, cmap)


def wall_segments(d, lo, hi):
    """Each wall's line as a segment: ended where it crosses another wall's
    line inside the points' extent grown by a tenth (the box's corners),
    else at that extent."""
    n = d["wall_normal"]
    p = d["wall_position"]
    pad = 0.1 * (hi - lo)
    glo, ghi = lo - pad, hi + pad
    segs = []
    for w in range(len(n)):
        t = np.array([-n[w, 1], n[w, 0]])
        # the parameters s where p + s t leaves the grown extent
        s_lo, s_hi = -np.inf, np.inf
        for ax in (0, 1):
            if abs(t[ax]) > 1e-12:
                a, b = (glo[ax] - p[w, ax]) / t[ax], (ghi[ax] - p[w, ax]) / t[ax]
                s_lo, s_hi = max(s_lo, min(a, b)), min(s_hi, max(a, b))
        cuts = []
        for v in range(len(n)):
            den = n[v] @ t
            if v != w and abs(den) > 1e-9:
                s = (n[v] @ (p[v] - p[w])) / den
                if s_lo <= s <= s_hi:
                    cuts.append(s)
        if len(cuts) >= 2:
            s_lo, s_hi = min(cuts), max(cuts)
        segs.append([p[w] + s_lo * t, p[w] + s_hi * t])
    return np.array(segs).reshape(-1, 2, 2)


def draw(d, args, fit_figure):
    """The picture of snapshot d["k"] as args.output (PNG); fit_figure is
    host/render.py's (the figure's height from the aspect, the colour bar)."""
    if args.mode != "arms":
        raise BadInput("--mode %s: a material point run file holds no contact network; "
                       "draw its points (the default mode)" % args.mode)
    if args.color not in ("particle", "plastic", "speed"):
        raise BadInput("--color %s: a material point run is coloured by particle, plastic or speed" % args.color)
    quads = squares(d)
    rgb, cbar = colors(d, args.color)
    lo = quads.reshape(-1, 2).min(axis=0) if len(quads) else np.zeros(2)
    hi = quads.reshape(-1, 2).max(axis=0) if len(quads) else np.ones(2)
    walls = wall_segments(d, lo, hi)
    if len(walls):
        lo = np.minimum(lo, walls.reshape(-1, 2).min(axis=0))
        hi = np.maximum(hi, walls.reshape(-1, 2).max(axis=0))
    pad = 0.03 * max(hi[0] - lo[0], hi[1] - lo[1], 1e-300)
    lo, hi = lo - pad, hi + pad

    fig, ax = plt.subplots(figsize=(args.width, args.width), dpi=args.dpi)
    ax.set_aspect("equal")
    # The dark pass: each square drawn with a dark edge a point wide; the fill
    # pass (its squares with a hairline of their own colour, which closes the
    # seams between neighbouring squares) covers it except outside a
    # particle's area.
    ax.add_collection(PolyCollection(quads, facecolors=(EDGE_GREY,) * 3, edgecolors=(EDGE_GREY,) * 3,
                                     linewidths=1.6, antialiaseds=False, zorder=1))
    ax.add_collection(PolyCollection(quads, facecolors=rgb, edgecolors=rgb, linewidths=0.25, antialiaseds=False,
                                     zorder=2))
    for seg in walls:
        ax.plot(seg[:, 0], seg[:, 1], color="0.25", lw=2.0, solid_capstyle="butt", antialiased=False, zorder=3)
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    fit_figure(fig, ax, args.width, lo, hi, cbar)
    npart = len(np.unique(d["particle"]))
    title = args.title or ("%s  snapshot %d of %d  step %d  t = %.4g s  %d material points, %d particle%s"
                           % (d["name"], d["k"], d["n"], d["step"], d["time"], len(quads), npart,
                              "" if npart == 1 else "s"))
    ax.set_title(title, fontsize=9)

    # The tight box is computed here (as savefig's bbox_inches="tight" does)
    # so that the axes' place in the written image is known for the text chunk.
    renderer = fig.canvas.get_renderer()
    box = fig.get_tightbbox(renderer).padded(0.08)
    ext = ax.get_window_extent(renderer)
    x0 = (ext.x0 / fig.dpi - box.x0) * args.dpi
    x1 = (ext.x1 / fig.dpi - box.x0) * args.dpi
    y0 = (box.y1 - ext.y1 / fig.dpi) * args.dpi  # image rows count from the top
    y1 = (box.y1 - ext.y0 / fig.dpi) * args.dpi
    axes = "%.3f %.3f %.3f %.3f %.17g %.17g %.17g %.17g" % (x0, y0, x1, y1, lo[0], hi[0], lo[1], hi[1])
    fig.savefig(args.output, dpi=args.dpi, bbox_inches=box, metadata={"capdem:axes": axes})
    plt.close(fig)
