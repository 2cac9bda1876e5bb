#!/usr/bin/python3
"""Draws the figures of `capdem analyze` from a run file's /analysis group.

usage: host/plot_run.py RUN.h5 [-o DIR] [--step STEP]
       host/plot_run.py MPM_RUN.h5 [MPM_RUN.h5 ...] [-o DIR]

Reads /analysis/snapshot_<step> (the latest analysed snapshot unless --step
is given), /analysis/compaction and /analysis/jamming, and writes PNGs into
DIR (default: next to the run file, in <run>_plots/):

  pf.png            P(f) of normal contact forces, log scale, with the tail
                    fit exp(-k f) and Mueth's fit
  bond_forces.png   PDF of bond forces over their mean, with the cascade fit
  rdf.png           G(r) and the cumulative rho(r) against r/L
  stress.png        P(i), i = I1 / <I1>
  branch.png        PDF of branch lengths l/L
  connectivity.png  P_c (contacts per particle) and P_b (neighbours per particle)
  valence.png       P_k and the mean bond force F_k against valence k
  compaction.png    the time series: stress or load, coordination, packing
                    fraction; and Z against Phi with the jamming fit

Run files of solver mpm (docs/mpm.md), one or several, each analysed by
`capdem analyze` first: the paper's figures (Nezamabadi et al. 2022), one
curve per run, labelled by its material; each PNG with a JSON of the
numbers drawn beside it (fig1.json, ...), taken from the analyses as they
are (DIR default: next to the first run file, in <run>_plots/):

  fig1.png  diametral runs: F/D against eps_yy (mpm_disk/curve)
  fig3.png  packing runs: kappa <d> against sigma at the snapshots
            (mpm/snapshots), Phi against sigma (mpm/series)
  fig4.png  sigma - sigma_c against Phi, with eq. (6) or (10) fitted and
            with the paper's parameters (mpm_eq6/curve, mpm_eq10/curve),
            and against eps - eps_c with eq. (5) (mpm_eq5, mpm/series)
  fig5.png  Z - Z_c against Phi - Phi_c (mpm/series, mpm_eq17), log-log,
            with the slope 1/2 of eq. (17)

Figures whose data the file lacks are skipped with a note.  Needs Debian's
python3-matplotlib, python3-h5py and python3-numpy.  The layout of
/analysis is in docs/analysis.md.
"""
import argparse
import json
import os
import re
import sys

import capdem_h5
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def table(group, name):
    """A table of /analysis as a dict column name -> array, or None."""
    if group is None or name not in group:
        return None
    d = group[name]
    cols = d.attrs["columns"]
    cols = cols.decode() if isinstance(cols, bytes) else str(cols)
    data = np.asarray(d[()])
    return {c: data[:, k] for k, c in enumerate(cols.split(","))}


def attr(group, name, default=None):
    if group is None or name not in group.attrs:
        return default
    return float(group.attrs[name])


def save(fig, outdir, name, made):
    path = os.path.join(outdir, name)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    made.append(path)


def plot_pf(snap, outdir, made):
    g = snap.get("normal_forces")
    t = table(g, "pdf")
    if t is None:
        return "no normal_forces/pdf"
    fig, ax = plt.subplots(figsize=(5, 4))
    keep = t["P"] > 0
    ax.semilogy(t["f"][keep], t["P"][keep], "o", ms=4, label="P(f)")
    k = attr(g, "k")
    if k is not None:
        # MLE tail: the samples above f = 1 (a fraction tail_n / n of all)
        # have density k exp(-k (f - 1)) among themselves
        frac = attr(g, "tail_n") / attr(g, "n_contacts")
        f = np.linspace(1, 10, 100)
        lo, hi = attr(g, "k_lo"), attr(g, "k_hi")
        ax.semilogy(f, frac * k * np.exp(-k * (f - 1)), "-", label=f"tail: k = {k:.3f} [{lo:.3f}, {hi:.3f}]")
    m = table(g, "mueth_fit")
    if m is not None:
        ax.semilogy(m["f"], m["P"], "--", label=f"Mueth: beta = {attr(g, 'mueth_beta'):.3f}")
    ax.set_xlabel("f = F_n / <F_n>")
    ax.set_ylabel("P(f)")
    ax.set_ylim(bottom=max(1e-6, 0.5 * t["P"][keep].min()))
    ax.legend(fontsize=8)
    save(fig, outdir, "pf.png", made)


def plot_bonds(snap, outdir, made):
    g = snap.get("bond_forces")
    t = table(g, "pdf_mean1")
    if t is None:
        return "no bond_forces/pdf_mean1"
    fig, ax = plt.subplots(figsize=(5, 4))
    keep = t["P"] > 0
    ax.semilogy(t["f_over_mean"][keep], t["P"][keep], "o", ms=4, label="bond forces")
    c = table(g, "cascade_fit")
    if c is not None:
        ax.semilogy(c["f"], c["P"], "-",
                    label=f"cascade: gamma = {attr(g, 'cascade_gamma'):.3f}, beta = {attr(g, 'cascade_beta'):.3f}")
    ax.set_xlabel("f = |F_bond| / <|F_bond|>")
    ax.set_ylabel("P(f)")
    ax.set_ylim(bottom=max(1e-6, 0.5 * t["P"][keep].min()))
    ax.legend(fontsize=8)
    save(fig, outdir, "bond_forces.png", made)


def plot_rdf(snap, outdir, made):
    t = table(snap.get("rdf"), "rdf")
    if t is None:
        return "no rdf/rdf"
    fig, ax = plt.subplots(figsize=(5, 4))
    ax.plot(t["r_over_L"], t["G"], "-", label="G(r)")
    ax.axhline(1, color="grey", lw=0.5)
    ax.set_xlabel("r / L")
    ax.set_ylabel("G(r)")
    ax2 = ax.twinx()
    ax2.plot(t["r_over_L"], t["rho"], "--", color="C1", label="rho(r) = N(r)/N_inf")
    ax2.set_ylabel("rho(r)")
    fig.legend(loc="upper right", fontsize=8)
    save(fig, outdir, "rdf.png", made)


def plot_density(snap, outdir, made, group, name, xcol, xlabel, fname):
    t = table(snap.get(group), name)
    if t is None:
        return f"no {group}/{name}"
    fig, ax = plt.subplots(figsize=(5, 4))
    keep = t["P"] > 0
    ax.semilogy(t[xcol][keep], t["P"][keep], "o-", ms=3)
    ax.set_xlabel(xlabel)
    ax.set_ylabel("P")
    save(fig, outdir, fname, made)


def plot_connectivity(snap, outdir, made):
    g = snap.get("network")
    pc, pb = table(g, "contacts_per_particle"), table(g, "neighbours_per_particle")
    if pc is None or pb is None:
        return "no network tables"
    fig, ax = plt.subplots(figsize=(5, 4))
    ax.plot(pc["c"], pc["P_c"], "o-", ms=3, label=f"P_c (Z_c = {attr(g, 'Z_c'):.2f})")
    ax.plot(pb["b"], pb["P_b"], "s-", ms=3, label=f"P_b (Z = {attr(g, 'Z'):.2f})")
    ax.set_xlabel("c, b")
    ax.set_ylabel("proportion of particles")
    ax.legend(fontsize=8)
    save(fig, outdir, "connectivity.png", made)


def plot_valence(snap, outdir, made):
    g = snap.get("network")
    t = table(g, "valence")
    if t is None:
        return "no network/valence"
    fig, ax = plt.subplots(figsize=(5, 4))
    ax.bar(t["k"], t["P_k"], color="C0", alpha=0.5, label=f"P_k (valence {attr(g, 'valence'):.2f})")
    ax.set_xlabel("valence k (contacts per bond)")
    ax.set_ylabel("P_k")
    ax2 = ax.twinx()
    ax2.plot(t["k"], t["F_k"], "o-", color="C3", label="F_k / <F_n>")
    ax2.set_ylabel("F_k / <F_n>")
    fig.legend(loc="upper right", fontsize=8)
    save(fig, outdir, "valence.png", made)


def plot_compaction(root, outdir, made):
    t = table(root.get("compaction"), "curve")
    if t is None:
        return "no /analysis/compaction"

    def varies(c):
        v = t[c][np.isfinite(t[c])]
        return v.size > 1 and v.max() > v.min()

    # one stress-like, one coordination, one packing-fraction panel, each
    # the first column of its kind that changes during the run
    kinds = (("axial_stress", "pressure", "wall_load", "piston_force", "elastic_energy"),
             ("coordination", "contacts"), ("packing_fraction", "phi_walls"))
    panels = []
    for kind in kinds:
        found = [c for c in kind if c in t and varies(c)]
        if found:
            panels.append(found[0])
    # docs/references.md, Analysis: stress and Z against the packing fraction
    phi = next((c for c in kinds[2] if c in panels), None)
    against = [c for c in panels if c != phi] if phi else []
    jam = table(root.get("jamming"), "data")
    n = len(panels) + len(against) + (jam is not None)
    fig, axes = plt.subplots(n, 1, figsize=(5, 2.6 * n), squeeze=False)
    for ax, c in zip(axes[:, 0], panels):
        ax.plot(t["time"], t[c], "-")
        ax.set_ylabel(c)
        ax.set_xlabel("time [s]")
    for ax, c in zip(axes[len(panels):, 0], against):
        ax.plot(t[phi], t[c], ".", ms=2)
        ax.set_ylabel(c)
        ax.set_xlabel(phi)
    if jam is not None:
        ax = axes[-1, 0]
        ax.plot(jam["phi"], jam["z"], ".", ms=3, label="data")
        keep = np.isfinite(jam["z_fit"])
        g = root["jamming"]
        ax.plot(jam["phi"][keep], jam["z_fit"][keep], "-",
                label=f"Z_c + A (Phi - Phi_c)^1/2: Phi_c = {attr(g, 'phi_c'):.4f}, Z_c = {attr(g, 'z_c'):.2f}")
        ax.set_xlabel("Phi")
        ax.set_ylabel("Z")
        ax.legend(fontsize=7)
    save(fig, outdir, "compaction.png", made)


# ---- the material point method (docs/mpm.md): the paper's Figs. 1, 3, 4, 5 ----

def mpm_label(f):
    """The run's material from its echoed config: 'elastic' or 'H = x MPa'."""
    text = f["/parameters/config"][()] if "/parameters/config" in f else b""
    text = text.decode() if isinstance(text, bytes) else str(text)
    if re.search(r"model:\s*von_mises", text):
        h = re.search(r"hardening:\s*([-+0-9.eE]+)", text)
        return "H = %g MPa" % (float(h.group(1)) / 1e6 if h else 0)
    return "elastic"


def mpm_runs(paths):
    """Each run's label and the groups of its latest analysed snapshot, as dicts of arrays and
    numbers: {group: {"attrs": {...}, table name: {column: array}}}."""
    prefix = capdem_h5.NAME["analysis_snapshot"]
    runs = []
    for path in paths:
        with capdem_h5.open_run(path) as f:
            root = capdem_h5.analysis(f)
            steps = sorted(int(k[len(prefix):]) for k in root if k.startswith(prefix)) if root is not None else []
            if not steps:
                raise SystemExit(f"plot_run.py: {path} has no analysed snapshot: run `capdem analyze {path}` first")
            snap = root[f"{prefix}{steps[-1]}"]
            groups = {}
            for name, g in snap.items():
                d = {"attrs": {k: (v.decode() if isinstance(v, bytes) else v.item() if hasattr(v, "item") else v)
                               for k, v in g.attrs.items()}}
                for t in g:
                    d[t] = table(g, t)
                groups[name] = d
            runs.append({"path": path, "label": mpm_label(f), "groups": groups})
    return runs


def save_mpm(fig, outdir, name, data, made):
    """The figure and, beside it, the numbers drawn (name.json)."""
    save(fig, outdir, name + ".png", made)
    with open(os.path.join(outdir, name + ".json"), "w") as out:
        json.dump(data, out, indent=1, allow_nan=True,
                  default=lambda a: [None if not np.isfinite(x) else float(x) for x in a])


def mpm_fig1(runs, outdir, made):
    disks = [r for r in runs if "mpm_disk" in r["groups"]]
    if not disks:
        return "fig1: no diametral run"
    fig, ax = plt.subplots(figsize=(5, 4))
    data = {}
    for r in disks:
        c = r["groups"]["mpm_disk"]["curve"]
        ax.plot(c["strain"], c["f_over_d"] / 1e6, "-", label=r["label"])
        data[r["label"]] = {"strain": c["strain"], "f_over_d": c["f_over_d"]}
    ax.set_xlabel("eps_yy = (D - gap) / D")
    ax.set_ylabel("F / D [MPa]")
    ax.legend(fontsize=8)
    save_mpm(fig, outdir, "fig1", data, made)


def mpm_packings(runs):
    return [r for r in runs if "mpm" in r["groups"] and "series" in r["groups"]["mpm"]]


def mpm_fig3(runs, outdir, made):
    packs = mpm_packings(runs)
    if not packs:
        return "fig3: no packing run"
    fig, (a, b) = plt.subplots(1, 2, figsize=(9, 4))
    data = {}
    for r in packs:
        sn, se = r["groups"]["mpm"]["snapshots"], r["groups"]["mpm"]["series"]
        a.plot(sn["sigma"] / 1e6, sn["kappa_d"], "o-", ms=4, label=r["label"])
        b.plot(se["sigma"] / 1e6, se["phi"], "-", label=r["label"])
        data[r["label"]] = {"snapshot_sigma": sn["sigma"], "kappa_d": sn["kappa_d"], "sigma": se["sigma"],
                            "phi": se["phi"]}
    a.set_xlabel("sigma [MPa]")
    a.set_ylabel("kappa <d>")
    b.set_xlabel("sigma [MPa]")
    b.set_ylabel("Phi")
    a.legend(fontsize=8)
    save_mpm(fig, outdir, "fig3", data, made)


def mpm_fig4(runs, outdir, made):
    packs = [r for r in mpm_packings(runs) if "mpm_eq5" in r["groups"] and "sigma_c" in r["groups"]["mpm_eq5"]["attrs"]]
    if not packs:
        return "fig4: no packing run with eq. (5) fitted (give --phi-c to capdem analyze)"
    fig, (a, b) = plt.subplots(1, 2, figsize=(9, 4))
    data = {}
    for k, r in enumerate(packs):
        g5 = r["groups"]["mpm_eq5"]["attrs"]
        sc, ec, pc = g5["sigma_c"], g5["strain_c"], g5["phi_c"]
        model = "mpm_eq10" if "curve" in r["groups"].get("mpm_eq10", {}) else "mpm_eq6"
        d = {"sigma_c": sc, "strain_c": ec, "phi_c": pc, "model": model}
        col = f"C{k}"
        c = r["groups"].get(model, {}).get("curve")
        if c is not None:
            a.plot(c["phi"], (c["sigma"] - sc) / 1e6, ".", ms=2, color=col, label=r["label"])
            a.plot(c["phi"], (c["sigma_fit"] - sc) / 1e6, "-", color=col)
            a.plot(c["phi"], (c["sigma_paper"] - sc) / 1e6, "--", color=col, lw=0.8)
            d.update(phi=c["phi"], sigma=c["sigma"], sigma_fit=c["sigma_fit"], sigma_paper=c["sigma_paper"])
        se = r["groups"]["mpm"]["series"]
        keep = se["phi"] >= pc
        x = se["strain"][keep] - ec
        b.plot(x, (se["sigma"][keep] - sc) / 1e6, ".", ms=2, color=col, label=r["label"])
        line = g5["offset"] + g5["m_eff"] * x
        b.plot(x, line / 1e6, "-", color=col, label=f"M_eff = {g5['m_eff'] / 1e6:.2f} MPa")
        d.update(excess_strain=x, excess_sigma=se["sigma"][keep] - sc, eq5_line=line)
        data[r["label"]] = d
    a.set_xlabel("Phi")
    a.set_ylabel("sigma - sigma_c [MPa]")
    a.set_title("points: runs; -: eq. (6)/(10) fitted; --: the paper's parameters", fontsize=7)
    b.set_xlabel("eps - eps_c (ln(h_i/h))")
    b.set_ylabel("sigma - sigma_c [MPa]")
    a.legend(fontsize=7)
    b.legend(fontsize=7)
    save_mpm(fig, outdir, "fig4", data, made)


def mpm_fig5(runs, outdir, made):
    packs = [r for r in mpm_packings(runs) if "z_c" in r["groups"].get("mpm_eq17", {}).get("attrs", {})]
    if not packs:
        return "fig5: no packing run with eq. (17) fitted (give --phi-c to capdem analyze)"
    fig, ax = plt.subplots(figsize=(5, 4))
    data = {}
    for r in packs:
        g = r["groups"]["mpm_eq17"]["attrs"]
        se = r["groups"]["mpm"]["series"]
        x, y = se["phi"] - g["phi_c"], se["z"] - g["z_c"]
        keep = (x > 0) & (y > 0)
        ax.loglog(x[keep], y[keep], ".", ms=3, label=f"{r['label']}: Z_c = {g['z_c']:.2f}")
        data[r["label"]] = {"phi_c": g["phi_c"], "z_c": g["z_c"], "amplitude": g["amplitude"],
                            "excess_phi": x[keep], "excess_z": y[keep]}
    xs = np.logspace(-3, 0, 50)
    a0 = np.median([data[k]["amplitude"] for k in data])
    ax.loglog(xs, a0 * np.sqrt(xs), "k-", lw=0.8, label=f"{a0:.2f} (Phi - Phi_c)^1/2")
    ax.set_xlabel("Phi - Phi_c")
    ax.set_ylabel("Z - Z_c")
    ax.legend(fontsize=7)
    save_mpm(fig, outdir, "fig5", data, made)


def report(made, notes):
    """The figures made on stdout, the skipped ones on stderr; the exit status."""
    for p in made:
        print(p)
    for n in notes:
        print(f"plot_run.py: skipped: {n}", file=sys.stderr)
    return 0 if made else 2


def main_mpm(paths, outdir):
    runs = mpm_runs(paths)
    made, notes = [], []
    for job in (mpm_fig1, mpm_fig3, mpm_fig4, mpm_fig5):
        note = job(runs, outdir, made)
        if note:
            notes.append(note)
    return report(made, notes)


def is_mpm(path):
    with capdem_h5.open_run(path) as f:
        s = f.attrs.get("solver", b"")
        return (s.decode() if isinstance(s, bytes) else str(s)) == "mpm"


def main(argv=None):
    ap = argparse.ArgumentParser(description="Figures of capdem analyze from RUN.h5/analysis")
    ap.add_argument("runs", nargs="+", metavar="run", help="a run file; several: mpm run files")
    ap.add_argument("-o", "--outdir", default=None)
    ap.add_argument("--step", type=int, default=None, help="analysed snapshot step (default: the latest)")
    a = ap.parse_args(argv)
    a.run = a.runs[0]
    outdir = a.outdir or os.path.splitext(a.run)[0] + "_plots"
    os.makedirs(outdir, exist_ok=True)
    mpm = [is_mpm(p) for p in a.runs]
    if any(mpm):
        if not all(mpm):
            print("plot_run.py: mpm and dem run files mixed", file=sys.stderr)
            return 2
        return main_mpm(a.runs, outdir)
    if len(a.runs) > 1:
        print("plot_run.py: several run files are for solver mpm only", file=sys.stderr)
        return 2
    made, notes = [], []
    prefix = capdem_h5.NAME["analysis_snapshot"]
    with capdem_h5.open_run(a.run) as f:
        root = capdem_h5.analysis(f)
        if root is None:
            print(f"plot_run.py: {a.run} has no {capdem_h5.PATH['analysis']} group: run `capdem analyze {a.run}` first",
                  file=sys.stderr)
            return 2
        steps = sorted(int(k[len(prefix):]) for k in root if k.startswith(prefix))
        snap = None
        if a.step is not None and a.step not in steps:
            print(f"plot_run.py: {a.run}: no {root.name}/{prefix}{a.step} (analysed: {steps})", file=sys.stderr)
            return 2
        if steps:
            snap = root[f"{prefix}{a.step if a.step is not None else steps[-1]}"]
            jobs = [
                lambda: plot_pf(snap, outdir, made),
                lambda: plot_bonds(snap, outdir, made),
                lambda: plot_rdf(snap, outdir, made),
                lambda: plot_density(snap, outdir, made, "stress", "pdf", "i", "i = I1 / <I1>", "stress.png"),
                lambda: plot_density(snap, outdir, made, "branch", "pdf", "l_over_L", "l / L", "branch.png"),
                lambda: plot_connectivity(snap, outdir, made),
                lambda: plot_valence(snap, outdir, made),
            ]
            for job in jobs:
                note = job()
                if note:
                    notes.append(note)
        note = plot_compaction(root, outdir, made)
        if note:
            notes.append(note)
    return report(made, notes)


if __name__ == "__main__":
    sys.exit(main())
