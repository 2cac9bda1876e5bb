"""Checks a `capdem render` picture of an mpm run file (docs/visualization.md,
"Material point runs") against the run file, pixel by pixel.

usage: /usr/bin/python3 check_mpm_render.py PICTURE.png RUN.h5 SNAPSHOT particle|plastic

- the PNG carries the text chunk capdem:axes (the axes' pixel box and data
  limits); the box has the data's aspect (equal axes) to 1 %;
- the pixel at each material point's position has the point's colour, for
  at least 90 % of the points of each kind (a point's centre can lie under
  a square of another particle drawn later where two particles meet):
  particle: its particle's colour, tab20 with the ids scrambled as
  (id * 7 + id // 20 * 3) mod 20; plastic: RGB 204, 204, 204 where the
  plastic strain is 0, else plasma at LogNorm(max / 10^3, max, clipped) of
  it, the documented scale; each within 3 of 255 per channel;
- plastic: the plastic-coloured pixels (channels spread by more than 40)
  inside the axes number none when no point has yielded;
- each wall's line is drawn: one of the 3 x 3 pixels at its middle between
  the box's corners (or at its point, the diametral walls) has the walls'
  grey, RGB 64, 64, 64 (the particles' dark edge is 31).
Prints one line per failure and exits 1 if any."""
import sys

import h5py
import numpy as np
from PIL import Image
import matplotlib
from matplotlib import colors as mcolors

png, run, k, how = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4]
fails = []

im = Image.open(png)
box = im.text.get("capdem:axes")
if box is None:
    sys.exit("%s: no capdem:axes text chunk" % png)
x0, y0, x1, y1, xmin, xmax, ymin, ymax = (float(v) for v in box.split())
rgb = np.asarray(im.convert("RGB")).astype(int)
rows, cols = rgb.shape[:2]
aspect_px = (x1 - x0) / (y1 - y0)
aspect_data = (xmax - xmin) / (ymax - ymin)
if abs(aspect_px / aspect_data - 1) > 0.01:
    fails.append("axes box %.1f x %.1f px for %.4g x %.4g m: not equal axes"
                 % (x1 - x0, y1 - y0, xmax - xmin, ymax - ymin))


def pixel(xy):
    """The image pixels (row, col) at data points xy (N, 2), clipped to the image."""
    c = np.floor(x0 + (xy[:, 0] - xmin) / (xmax - xmin) * (x1 - x0)).astype(int)
    r = np.floor(y0 + (ymax - xy[:, 1]) / (ymax - ymin) * (y1 - y0)).astype(int)
    return np.clip(r, 0, rows - 1), np.clip(c, 0, cols - 1)


with h5py.File(run, "r") as f:
    pos = f["/mpm/snapshots/position"][k]
    eps = f["/mpm/snapshots/plastic_strain"][k]
    owner = f["/mpm/points/particle"][()].astype(np.int64)
    wall_p = f["/mpm/snapshots/wall_position"][k]
    wall_n = f["/mpm/walls/normal"][()]

r, c = pixel(pos)
got = rgb[r, c]
if how == "particle":
    pal = matplotlib.colormaps["tab20"](np.arange(20))[:, :3]
    want = np.round(255 * pal[(owner * 7 + owner // 20 * 3) % 20]).astype(int)
    groups = {"points": np.ones(len(pos), bool)}
else:
    want = np.full((len(pos), 3), 204)
    top = eps.max()
    if top > 0:
        norm = mcolors.LogNorm(top / 1e3, top, clip=True)
        y = eps > 0
        want[y] = np.round(255 * matplotlib.colormaps["plasma"](norm(eps[y]))[:, :3]).astype(int)
    groups = {"elastic points": eps == 0, "plastic points": eps > 0}
match = np.abs(got - want).max(axis=1) <= 3
for name, sel in groups.items():
    if sel.sum() and match[sel].mean() < 0.9:
        fails.append("%s: %d of %d have their colour at their pixel (want 90 %%)"
                     % (name, match[sel].sum(), sel.sum()))
print("%s: %s" % (png, ", ".join("%s %d/%d" % (n, match[s].sum(), s.sum()) for n, s in groups.items())))

if how == "plastic" and not (eps > 0).any():
    inside = rgb[int(y0) + 2:int(y1) - 1, int(x0) + 2:int(x1) - 1]
    n = int(((inside.max(axis=2) - inside.min(axis=2)) > 40).sum())
    if n:
        fails.append("no point has yielded, yet %d pixels have a plastic colour" % n)

# walls: the middle of each wall's segment between the other walls' lines
for w in range(len(wall_n)):
    t = np.array([-wall_n[w, 1], wall_n[w, 0]])
    cuts = [(wall_n[v] @ (wall_p[v] - wall_p[w])) / (wall_n[v] @ t) for v in range(len(wall_n))
            if v != w and abs(wall_n[v] @ t) > 1e-9]
    mid = wall_p[w] + (0.5 * (min(cuts) + max(cuts)) if len(cuts) >= 2 else 0.0) * t
    rr, cc = pixel(mid[None, :])
    near = rgb[max(rr[0] - 1, 0):rr[0] + 2, max(cc[0] - 1, 0):cc[0] + 2].reshape(-1, 3)  # a line 2 points wide
    if not (np.abs(near - 64).max(axis=1) <= 3).any():
        fails.append("wall %d: none of the pixels next to (%d, %d), its middle, has its grey 64: %s"
                     % (w, rr[0], cc[0], near.tolist()))

for m in fails:
    print("FAIL", m)
sys.exit(1 if fails else 0)
