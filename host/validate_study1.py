"""Study 1 of docs/validation.md, run by host/validate.py study1.

Study 1 (Tran et al. 2024): hexapods of aspect ratio alpha under radial compaction
at p L / k_n = 1e-5, frictionless, and alpha = 3, 9 again at mu = 0.4.  For
each case (alpha, mu, seed) the driver

  1. writes OUT/study1/a<alpha>_mu<mu>_n<N>_s<seed>/config.yaml from
     configs/validation/study1/radial_compaction.yaml;
  2. runs `capdem run` there, or, when run.h5 exists and its last snapshot
     is not in phase 7 (done, /walls/control slot 0), resumes it with
     `capdem run config.yaml --resume run.h5 --steps CAP` (CAP doubled, up
     to --max-steps, when the previous cap was reached); a case whose lock
     file names a live process is left to that process;
  3. when the protocol is done, `capdem analyze run.h5 --json` (all
     measures, written into run.h5 too) into analysis.json, and
     `capdem analyze run.h5 --measures packing --margins 1,1 --no-write
     --json` into packing_m1.json (a core region 1 L from the ball; the
     default 3 L leaves almost nothing of a 1000-particle ball);
  4. records every invocation's wall time, CPU time, steps and load average
     in timing.json.

Then it collects every finished case under OUT/study1 (not only the
selection) into OUT/study1/results.json (mean and standard error over seeds for each alpha, mu, N), prints the selection's table
(Markdown with --markdown), draws the figures into --figures DIR, and with
--check asserts the bands of the CI smoke test (docs/validation.md, "Smoke
test"); exit 1 when a check fails.

Everything is resumable: run it again with the same arguments and it skips
what is done, resumes what was interrupted and analyses what is new.  Every
number comes from `capdem analyze`; the driver only adds the paper's
references and Z_c counted with the ball's contacts (2 (N_c + N_w) / N_p*).
"""
import json
import math
import os
import re
import shutil
import string
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from validate_runs import (PHASE_DONE, REPO, RunCase, advance, lock_holder, markdown_into, now,
                           parse_list, peek, pm, ref, run_state, say, shape_props, wait_for)

TEMPLATE1 = os.path.join(REPO, "configs", "validation", "study1", "radial_compaction.yaml")

# alpha -> (shape, dt): the time steps of configs/protocols/radial_hexapods_a*.yaml
STUDY1_SHAPES = {1.0: ("sphere", 4.0e-6), 1.5: ("hexapod", 6.5e-6), 2.0: ("hexapod", 8.5e-6),
                 3.0: ("hexapod", 1.0e-5), 5.0: ("hexapod", 1.5e-5), 7.0: ("hexapod", 2.0e-5),
                 9.0: ("hexapod", 2.0e-5)}

# Tran et al. 2024, as its text states them (figures are not in
# the extracted text; only the numbers the text gives are used).
PAPER1 = {
    "n_particles": 8385,
    "Z": {1.0: 6.0, 1.5: 7.0, 2.0: 7.0, 3.0: 7.0, 9.0: 8.5},
    "Z_note": "~7 for alpha <= 3 (spheres: Z = Z_c ~ 6), rising to ~8.5 for thin hexapods",
    "Z_c": {1.0: 6.0, 1.5: 12.0, 2.0: 12.0, 3.0: 13.0, 5.0: 12.0, 7.0: 12.0, 9.0: 12.0},
    "valence": {1.0: 1.0, 1.5: 1.75, 2.0: 1.75, 3.0: 1.8, 9.0: 1.5},
    "valence_note": "1 for spheres, 1.7-1.8 for thick hexapods, above 1.8 at alpha = 3, 1.5 for thin",
    "lambda": {1.0: 0.0, 9.0: 0.5},
    "phi_text": {1.0: 0.62, 2.0: 0.68, 9.0: 0.25},
    "beta": {1.0: 1.64, 9.0: 1.13},
}


def eta_of(alpha):
    """Tran et al. 2024, eq. (4): eta = 1 - 1/alpha."""
    return 1.0 - 1.0 / alpha


def phi_fit(eta):
    """Tran et al. 2024, eq. (6) with a = 0.85, b = 1.5, Phi_0 = 0.62."""
    return 0.62 + 0.85 * eta ** 2 - 1.5 * eta ** 3


def fmt_alpha(a):
    return ("%g" % a).replace(".", "p")


def fmt_mu(m):
    return ("%g" % m).replace(".", "p")


START_RADIUS_FACTOR = 1.5  # starting ball radius over that of the expected packing (docs/validation.md)


class Case(RunCase):
    """One study-1 run: OUT/a<alpha>_mu<mu>_n<N>_s<seed>[_ci]."""

    def __init__(self, alpha, mu, seed, n, out, ci=False, capdem=None):
        self.alpha, self.mu, self.n, self.ci, self.capdem = alpha, mu, n, ci, capdem
        RunCase.__init__(self, "a%s_mu%s_n%d_s%d%s" % (fmt_alpha(alpha), fmt_mu(mu), n, seed, "_ci" if ci else ""),
                         out, seed)
        self.packing_m1 = os.path.join(self.dir, "packing_m1.json")

    def write_config(self, steps):
        shape, dt = STUDY1_SHAPES[self.alpha]
        # Start: 1.5 x the radius at which the particles would fill the ball to
        # Tran et al. 2024's fit Phi(eta) (solid fraction Phi / 3.4), placed at random
        # with only their arms kept apart (init.exclusion: shape).
        v = shape_props(self.capdem, shape, self.alpha)["volume"]
        radius = START_RADIUS_FACTOR * (3.0 * self.n * v / (4.0 * math.pi * phi_fit(eta_of(self.alpha)))) ** (1.0 / 3.0)
        with open(TEMPLATE1) as f:
            text = string.Template(f.read()).substitute(
                name=self.name, seed=self.seed, dt="%.3g" % dt, steps=steps, mu="%g" % self.mu,
                shape=shape, aspect="" if shape == "sphere" else "aspect: %g," % self.alpha,
                n=self.n, radius="%.6g" % radius,
                energy_tolerance="1.0e-3" if self.ci else "1.0e-4", check_every=2000 if self.ci else 5000)
        os.makedirs(self.dir, exist_ok=True)
        with open(self.config, "w") as f:
            f.write(text)


def analyse(case, capdem, force=False):
    """analysis.json and packing_m1.json of a finished case (kept when newer than run.h5)."""
    fresh = (os.path.exists(case.analysis) and os.path.exists(case.packing_m1)
             and os.path.getmtime(case.packing_m1) >= os.path.getmtime(case.analysis) - 1)
    if fresh and not force:
        with open(case.analysis) as f:
            d = json.load(f)
        st = run_state(case.h5)
        if st and d.get("step") == st[1]:
            return True
    t0 = time.time()
    r = subprocess.run([capdem, "analyze", "run.h5", "--json", "--quiet"], cwd=case.dir, capture_output=True,
                       text=True)
    if r.returncode != 0:
        say("  %s: capdem analyze failed (%d): %s" % (case.name, r.returncode, r.stderr.strip()))
        return False
    with open(case.analysis, "w") as f:
        f.write(r.stdout)
    r = subprocess.run([capdem, "analyze", "run.h5", "--measures", "packing", "--margins", "1,1", "--no-write",
                        "--json", "--quiet"], cwd=case.dir, capture_output=True, text=True)
    if r.returncode != 0:
        say("  %s: capdem analyze --margins 1,1 failed (%d): %s" % (case.name, r.returncode, r.stderr.strip()))
        return False
    with open(case.packing_m1, "w") as f:
        f.write(r.stdout)
    say("  %s: analysed in %.1f s" % (case.name, time.time() - t0))
    return True


# ----------------------------------------------------------------------- results

def ball_radius(pk):
    """Ball radius [m] from capdem analyze's container volume."""
    return (3.0 * pk["container_volume"] / (4.0 * math.pi)) ** (1.0 / 3.0)


def inner_contact_density(pk):
    """Contacts per volume within half the ball radius over the ball's mean,
    from capdem analyze's contact-density profile (counts per radial bin):
    Tran et al. 2024 (Fig. 3b) find n_c nearly constant from one particle size out
    of the centre to the wall, so a homogeneous packing gives about 1; a
    hollow shell of particles jammed at the wall (the ball swept them up
    faster than they could fill the inside) gives about 0."""
    rows = pk["curves"]["contact_density"]["data"]
    R = ball_radius(pk)
    total = sum(r[2] for r in rows)
    inner = sum(r[2] for r in rows if r[0] < 0.5 * R)
    return inner / total / 0.125 if total > 0 else None


def metrics(case):
    """The numbers of one finished case, straight from capdem analyze."""
    with open(case.analysis) as f:
        d = json.load(f)
    with open(case.packing_m1) as f:
        m1 = json.load(f)
    net, pk, br, bf, nf = d["network"], d["packing"], d["branch"], d["bond_forces"], d["normal_forces"]
    npc = net["n_particles_in_contact"]
    iso_dof = 3.0 if case.alpha == 1.0 else 6.0  # spheres: translations only
    timing = []
    if os.path.exists(case.timing):
        with open(case.timing) as f:
            timing = json.load(f)
    p_applied = 1.0e-5 * 1.0e5 / d["sample"]["L"]
    return {
        "nc_inner": inner_contact_density(pk),
        "alpha": case.alpha, "eta": eta_of(case.alpha), "mu": case.mu, "seed": case.seed, "n": case.n, "ci": case.ci,
        "case": case.name, "step": d["step"], "time_s": d["time"],
        "n_particles_in_contact": npc, "n_rattlers": net["n_rattlers"],
        "n_contacts": net["n_contacts"], "n_wall_contacts": net["n_wall_contacts"], "n_bonds": net["n_bonds"],
        "phi_container": pk["phi_container"],
        "phi_core_3L": pk.get("phi_core"), "phi_core_3L_err": pk.get("phi_core_error"),
        "phi_core_1L": m1["packing"].get("phi_core"), "phi_core_1L_err": m1["packing"].get("phi_core_error"),
        "lambda": br["lambda"],
        "Z": net["Z"], "Z_c": net["Z_c"],
        "Z_c_walls": 2.0 * (net["n_contacts"] + net["n_wall_contacts"]) / npc,
        "Z_c_isostatic": 2.0 * iso_dof * (1.0 - 1.0 / npc),
        "valence": net["valence"],
        "cascade_beta": bf.get("cascade_beta"), "cascade_beta_lo": bf.get("cascade_beta_lo"),
        "cascade_beta_hi": bf.get("cascade_beta_hi"), "cascade_gamma": bf.get("cascade_gamma"),
        "k_tail": nf.get("k"), "k_tail_lo": nf.get("k_lo"), "k_tail_hi": nf.get("k_hi"),
        "pressure_over_p": d["stress"]["container_pressure"] / p_applied,
        "run_wall_s": round(sum(t["wall_s"] for t in timing), 1),
        "run_cpu_s": round(sum(t["cpu_s"] or 0 for t in timing), 1),
        "run_segments": len(timing),
        "run_max_loadavg": max([t[k] for t in timing for k in ("loadavg_start", "loadavg_end")
                                if t.get(k) is not None] or [0]),
    }


AGG_KEYS = ["phi_container", "phi_core_1L", "phi_core_3L", "lambda", "Z", "Z_c", "Z_c_walls", "Z_c_isostatic",
            "valence", "cascade_beta", "k_tail", "nc_inner", "n_particles_in_contact", "n_rattlers", "pressure_over_p",
            "step", "run_wall_s"]


def aggregate(rows):
    """Mean and standard error over seeds for each (alpha, mu, N, CI settings)."""
    groups = {}
    for r in rows:
        groups.setdefault((r["alpha"], r["mu"], r["n"], r["ci"]), []).append(r)
    out = []
    for (a, mu, n, ci), rs in sorted(groups.items()):
        g = {"alpha": a, "eta": eta_of(a), "mu": mu, "n": n, "ci": ci, "seeds": sorted(r["seed"] for r in rs)}
        for k in AGG_KEYS:
            v = np.array([r[k] for r in rs if r.get(k) is not None], dtype=float)
            g[k] = float(v.mean()) if len(v) else None
            g[k + "_se"] = float(v.std(ddof=1) / math.sqrt(len(v))) if len(v) >= 2 else None
        g["phi_fit_paper"] = phi_fit(g["eta"])
        g["phi_text_paper"] = PAPER1["phi_text"].get(a)
        g["lambda_paper"] = PAPER1["lambda"].get(a)
        g["Z_paper"] = PAPER1["Z"].get(a) if mu == 0 else None
        g["Z_c_paper"] = PAPER1["Z_c"].get(a) if mu == 0 else None
        g["valence_paper"] = PAPER1["valence"].get(a) if mu == 0 else None
        g["beta_paper"] = PAPER1["beta"].get(a) if mu == 0 else None
        out.append(g)
    return out


FS_KEYS = ["phi_container", "Z", "Z_c", "Z_c_walls", "valence", "lambda"]


def finite_size(agg_all):
    """Each of FS_KEYS against N^(-1/3), for each frictionless alpha with three
    or more N: least squares X = X_inf + c N^(-1/3) over the per-N means (the
    share of particles in a wall layer of fixed thickness falls as the ball's
    surface over its volume, ~ N^(-1/3)), and the line at the paper's
    N = 8385 and at N -> infinity, with standard errors from the residuals.
    At each N the study's relaxation check is used where it ran, else the
    smoke test's (--ci): Phi stops changing long before either check is met,
    but Z and Z_c creep up until the end, so a --ci point may sit low."""
    out = []
    by_alpha = {}
    for g in agg_all:
        if g["mu"] == 0:
            by_alpha.setdefault(g["alpha"], []).append(g)
    x8 = PAPER1["n_particles"] ** (-1.0 / 3.0)
    for a, gs in sorted(by_alpha.items()):
        per_n = {}
        for g in sorted(gs, key=lambda g: not g["ci"]):  # the study's settings win over --ci at one N
            per_n[g["n"]] = g
        gs = [per_n[n] for n in sorted(per_n)]
        if len(gs) < 3:
            continue
        x = np.array([g["n"] ** (-1.0 / 3.0) for g in gs])
        A = np.c_[np.ones_like(x), x]
        r = {"alpha": a, "eta": eta_of(a), "n": [int(g["n"]) for g in gs], "ci": [bool(g["ci"]) for g in gs],
             "phi_fit_paper": phi_fit(eta_of(a))}
        for key in FS_KEYS:
            y = np.array([g[key] for g in gs], dtype=float)
            coef, *_ = np.linalg.lstsq(A, y, rcond=None)
            dof = len(x) - 2
            s2 = float(np.sum((y - A @ coef) ** 2) / dof) if dof > 0 else float("nan")
            cov = s2 * np.linalg.inv(A.T @ A)
            v8 = np.array([1.0, x8])
            r[key] = {"values": y.tolist(), "inf": float(coef[0]), "inf_se": float(math.sqrt(cov[0, 0])),
                      "slope": float(coef[1]), "at_8385": float(v8 @ coef),
                      "at_8385_se": float(math.sqrt(v8 @ cov @ v8))}
        # kept for the figure
        r["phi_inf"], r["slope"] = r["phi_container"]["inf"], r["phi_container"]["slope"]
        out.append(r)
    return out


def markdown(agg):
    lines = []
    lines.append("| α | η | μ | N | seeds | Φ ball (paper fit; text) | Φ core 1 L | λ (paper) | Z (paper) "
                 "| Z_c (paper) | Z_c with wall contacts / isostatic | valence (paper) | cascade β (paper) | n_c inner / mean |")
    lines.append("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for g in agg:
        fric = g["mu"] > 0  # the paper's fit and the isostatic count are frictionless references
        lines.append("| %g | %.3f | %g | %d | %s | %s (%s; %s) | %s | %s (%s) | %s (%s) | %s (%s) | %s / %s | %s (%s) | %s (%s) | %s |" % (
            g["alpha"], g["eta"], g["mu"], g["n"], ",".join(str(s) for s in g["seeds"]),
            pm(g, "phi_container"), "—" if fric else "%.3f" % g["phi_fit_paper"],
            "—" if fric else ref(g["phi_text_paper"]),
            pm(g, "phi_core_1L"), pm(g, "lambda"), ref(g["lambda_paper"], 1), pm(g, "Z", 2), ref(g["Z_paper"], 1),
            pm(g, "Z_c", 2), ref(g["Z_c_paper"], 0), pm(g, "Z_c_walls", 2),
            "—" if fric else "%.2f" % g["Z_c_isostatic"],
            pm(g, "valence", 2), ref(g["valence_paper"]), pm(g, "cascade_beta", 2), ref(g["beta_paper"]),
            pm(g, "nc_inner", 2)))
    return "\n".join(lines)


def print_table(agg):
    hdr = "%5s %5s %4s %5s %5s  %-15s %-6s %-15s %-15s %-13s %-13s %-13s %-13s %-13s %s" % (
        "alpha", "eta", "mu", "N", "seeds", "phi_ball", "fit", "phi_core_1L", "lambda", "Z", "Z_c", "Z_c+walls",
        "valence", "beta", "wall_s")
    print(hdr)
    for g in agg:
        print("%5g %5.3f %4g %5d %5d  %-15s %-6.3f %-15s %-15s %-13s %-13s %-13s %-13s %-13s %s" % (
            g["alpha"], g["eta"], g["mu"], g["n"], len(g["seeds"]), pm(g, "phi_container"), g["phi_fit_paper"],
            pm(g, "phi_core_1L"), pm(g, "lambda"), pm(g, "Z", 2), pm(g, "Z_c", 2), pm(g, "Z_c_walls", 2),
            pm(g, "valence", 2), pm(g, "cascade_beta", 2), pm(g, "run_wall_s", 0)))


def write_results(out, rows, agg):
    fs = finite_size(agg)
    with open(os.path.join(out, "results.json"), "w") as f:
        paper = {k: {str(a): v for a, v in t.items()} if isinstance(t, dict) else t for k, t in PAPER1.items()}
        json.dump({"generated": now(), "paper": paper,
                   "runs": rows, "cases": agg, "finite_size": fs}, f, indent=1)
    for r in fs:
        print("finite size, alpha %g, N = %s (X = X_inf + c N^(-1/3)):" % (
            r["alpha"], ",".join("%d%s" % (n, " (ci)" if c else "") for n, c in zip(r["n"], r["ci"]))))
        for key in FS_KEYS:
            q = r[key]
            print("  %-14s %s  ->  %.3f +- %.3f at N = 8385, %.3f +- %.3f for N -> infinity" % (
                key, " ".join("%.3f" % v for v in q["values"]), q["at_8385"], q["at_8385_se"], q["inf"],
                q["inf_se"]))


def figures(outdir, cases, agg, n, agg_all=None):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    os.makedirs(outdir, exist_ok=True)
    et = np.linspace(0, 0.92, 200)
    styles = {0.0: ("o", "C0", "μ = 0"), 0.4: ("s", "C3", "μ = 0.4")}

    def series(key, mu):
        gs = [g for g in agg if g["mu"] == mu and g.get(key) is not None]
        x = np.array([g["eta"] for g in gs])
        y = np.array([g[key] for g in gs])
        e = np.array([g[key + "_se"] if g.get(key + "_se") is not None else 0.0 for g in gs])
        return x, y, e

    def paper_points(ax, table, label):
        pts = sorted((eta_of(a), v) for a, v in table.items())
        if pts:
            ax.plot([p[0] for p in pts], [p[1] for p in pts], "k*", ms=10, label=label)

    written = []

    def save(fig, fname):
        fig.tight_layout()
        fig.savefig(os.path.join(outdir, fname), dpi=110)
        plt.close(fig)
        written.append(fname)

    # packing fraction
    fig, ax = plt.subplots(figsize=(5.5, 4))
    ax.plot(et, phi_fit(et), "k--", label="Tran et al. 2024 fit 0.62 + 0.85η² − 1.5η³")
    paper_points(ax, PAPER1["phi_text"], "Tran et al. 2024 text")
    for mu, (m, c, lab) in styles.items():
        x, y, e = series("phi_container", mu)
        if len(x):
            ax.errorbar(x, y, e, fmt=m, color=c, label="capdem, ball, " + lab, capsize=3)
        x, y, e = series("phi_core_1L", mu)
        if len(x):
            ax.errorbar(x, y, e, fmt=m, mfc="none", color=c, label="capdem, core 1 L, " + lab, capsize=3)
    ax.set_xlabel("η = 1 − 1/α")
    ax.set_ylabel("packing fraction Φ")
    ax.set_title("Study 1: Φ(η), N = %d (paper: 8385)" % n)
    ax.legend(fontsize=7)
    save(fig, "study1_phi.png")
    # interlocking and valence: one capdem series per friction against the paper's points

    def eta_figure(key, paper, paper_label, ylabel, fname):
        fig, ax = plt.subplots(figsize=(5.5, 4))
        paper_points(ax, paper, paper_label)
        for mu, (m, c, lab) in styles.items():
            x, y, e = series(key, mu)
            if len(x):
                ax.errorbar(x, y, e, fmt=m, color=c, label="capdem, " + lab, capsize=3)
        ax.set_xlabel("η = 1 − 1/α")
        ax.set_ylabel(ylabel)
        ax.legend(fontsize=8)
        save(fig, fname)

    eta_figure("lambda", PAPER1["lambda"], "Tran et al. 2024 text (α = 1, 9)", "interlocking λ = 1 − <l>/L", "study1_lambda.png")
    eta_figure("valence", PAPER1["valence"], "Tran et al. 2024 text", "valence Z_c / Z", "study1_valence.png")
    # coordination
    fig, ax = plt.subplots(figsize=(5.5, 4))
    paper_points(ax, PAPER1["Z_c"], "Tran et al. 2024 Z_c (text)")
    zs = sorted((eta_of(a), v) for a, v in PAPER1["Z"].items())
    ax.plot([p[0] for p in zs], [p[1] for p in zs], "kx", ms=9, label="Tran et al. 2024 Z (text)")
    for mu, (m, c, lab) in styles.items():
        for key, fill, name in (("Z_c", "full", "Z_c"), ("Z_c_walls", "none", "Z_c with wall contacts"),
                                ("Z", "full", "Z")):
            x, y, e = series(key, mu)
            if len(x):
                ax.errorbar(x, y, e, fmt=m if key != "Z" else "^", mfc=None if fill == "full" else "none",
                            color=c, label="capdem %s, %s" % (name, lab), capsize=3)
    ax.axhline(12, color="gray", lw=0.8)
    ax.set_xlabel("η = 1 − 1/α")
    ax.set_ylabel("coordination")
    ax.legend(fontsize=6.5, loc="center left", bbox_to_anchor=(0.04, 0.55))
    save(fig, "study1_coordination.png")
    # bond-force PDFs with the cascade fits (first seed of each frictionless alpha)
    fig, ax = plt.subplots(figsize=(5.5, 4))
    seen = set()
    for k, case in enumerate(sorted(cases, key=lambda c: (c.alpha, c.seed))):
        if case.mu != 0 or case.alpha in seen:
            continue
        seen.add(case.alpha)
        with open(case.analysis) as f:
            cv = json.load(f)["bond_forces"]["curves"]
        pdf = np.array(cv["pdf_mean1"]["data"])
        fit = np.array(cv["cascade_fit"]["data"]) if "cascade_fit" in cv else None
        col = "C%d" % (len(seen) - 1)
        good = pdf[:, 1] > 0
        ax.semilogy(pdf[good, 0], pdf[good, 1], "o", ms=3, color=col, label="α = %g" % case.alpha)
        if fit is not None:
            ax.semilogy(fit[:, 0], fit[:, 1], "-", color=col, lw=1)
    ax.set_xlabel("bond force / mean bond force")
    ax.set_ylabel("PDF")
    ax.set_title("bond forces and cascade fits (seed 1 of each α)")
    ax.legend(fontsize=8)
    save(fig, "study1_bond_forces.png")
    # contact density against the distance from the ball centre (seed 1 of each case):
    # flat for a homogeneous packing (Tran et al. 2024 Fig. 3b), zero inside for a hollow shell
    fig, ax = plt.subplots(figsize=(5.5, 4))
    firsts = {}
    for case in sorted(cases, key=lambda c: (c.mu, c.alpha, c.seed)):
        firsts.setdefault((case.mu, case.alpha), case)
    for k, case in enumerate(firsts.values()):
        with open(case.analysis) as f:
            pk = json.load(f)["packing"]
        rows = np.array(pk["curves"]["contact_density"]["data"])
        R = ball_radius(pk)
        ax.plot(rows[:, 0] / R, rows[:, 1] / pk["contact_density_mean"], marker="o", ms=3, lw=1,
                ls="-" if case.mu == 0 else "--", label="α = %g, μ = %g" % (case.alpha, case.mu))
    ax.axvline(0.5, color="0.6", lw=0.8)
    ax.set_xlabel("r / R (ball radius)")
    ax.set_ylabel("contact density / mean")
    ax.set_title("contact density profiles (seed 1), N = %d" % n)
    ax.legend(fontsize=7)
    save(fig, "study1_contact_density.png")
    # finite size: Phi of the ball and of the core against N^(-1/3), every N of OUT
    by_alpha = {}
    for g in agg_all or []:
        if g["mu"] == 0:
            by_alpha.setdefault(g["alpha"], []).append(g)
    by_alpha = {a: gs for a, gs in by_alpha.items() if len({g["n"] for g in gs}) >= 2}
    if by_alpha:
        fig, ax = plt.subplots(figsize=(5.5, 4))
        for k, (a, gs) in enumerate(sorted(by_alpha.items())):
            gs = sorted(gs, key=lambda g: g["n"])
            x = np.array([g["n"] ** (-1.0 / 3.0) for g in gs])
            col = "C%d" % k
            for key, mfc, name in (("phi_container", None, "ball"), ("phi_core_1L", "none", "core 1 L")):
                y = np.array([g[key] for g in gs])
                e = np.array([g[key + "_se"] or 0.0 for g in gs])
                ax.errorbar(x, y, e, fmt="o", mfc=mfc, color=col, capsize=3, label="α = %g, %s" % (a, name))
            ax.axhline(phi_fit(eta_of(a)), color=col, ls="--", lw=0.8)
            for r in finite_size(gs):
                xx = np.linspace(0, x.max(), 50)
                ax.plot(xx, r["phi_inf"] + r["slope"] * xx, ":", color=col, lw=1)
            ax.axvline(PAPER1["n_particles"] ** (-1.0 / 3.0), color="gray", lw=0.8)
            for g in gs:
                ax.annotate("%d%s" % (g["n"], " ci" if g["ci"] else ""), (g["n"] ** (-1.0 / 3.0), g["phi_container"]),
                            textcoords="offset points", xytext=(3, -10), fontsize=7)
        ax.set_xlabel("N^(-1/3) (grey line: the paper's N = 8385)")
        ax.set_ylabel("packing fraction Φ")
        ax.set_title("finite size (dashed: Tran et al. 2024 fit; dotted: line through the ball's Φ)", fontsize=9)
        ax.legend(fontsize=7)
        save(fig, "study1_phi_finite_size.png")
    print("figures: %s (%s)" % (outdir, ", ".join(written)))


# -------------------------------------------------------------------- smoke check

def check_bands(rows):
    """The CI smoke test's assertions (docs/validation.md, "Smoke test")."""
    ok = True
    for r in rows:
        iso = r["Z_c_isostatic"]
        lo_z, hi_z = 0.97 * iso, 1.09 * iso
        fit = phi_fit(r["eta"])
        tests = [
            ("Z_c with wall contacts %.3f in [%.3f, %.3f] (0.97 .. 1.09 x isostatic %.3f)"
             % (r["Z_c_walls"], lo_z, hi_z, iso), lo_z <= r["Z_c_walls"] <= hi_z),
            ("Phi core (1 L from the ball) %.4f within 0.06 of the paper's fit %.4f"
             % (r["phi_core_1L"], fit), r["phi_core_1L"] is not None and abs(r["phi_core_1L"] - fit) <= 0.06),
            ("Phi of the ball %.4f below Phi of the core %.4f (wall depletion)"
             % (r["phi_container"], r["phi_core_1L"]), r["phi_container"] < r["phi_core_1L"]),
            ("ball pressure / p = %.4f within 1 %%" % r["pressure_over_p"], abs(r["pressure_over_p"] - 1) < 0.01),
            ("contact density within R/2 over the mean %.2f above 0.5 (no hollow shell)" % (r["nc_inner"] or 0),
             r["nc_inner"] is not None and r["nc_inner"] > 0.5),
        ]
        for text, good in tests:
            print("%s %s: %s" % ("PASS" if good else "FAIL", r["case"], text))
            ok = ok and good
    return ok


# --------------------------------------------------------------------------- main

def finished_cases_in(out):
    """Every case folder under OUT/study1 whose run is done and analysed."""
    found = []
    for name in sorted(os.listdir(out)):
        m = re.fullmatch(r"a([0-9p]+)_mu([0-9p]+)_n(\d+)_s(\d+)(_ci)?", name)
        if not m:
            continue
        c = Case(float(m.group(1).replace("p", ".")), float(m.group(2).replace("p", ".")), int(m.group(4)),
                 int(m.group(3)), out, bool(m.group(5)))
        if c.name == name and os.path.exists(c.analysis) and os.path.exists(c.packing_m1) \
                and lock_holder(c) is None:
            found.append(c)
    return found


def study1(args):
    capdem = os.path.join(os.path.abspath(args.build), "capdem")
    if not os.access(capdem, os.X_OK):
        sys.exit("validate.py: %s not found; build first (README)" % capdem)
    out = os.path.join(os.path.abspath(args.out), "study1")
    os.makedirs(out, exist_ok=True)
    alphas, seeds = parse_list(args.alphas), parse_list(args.seeds, int)
    for a in alphas + parse_list(args.friction_alphas):
        if a not in STUDY1_SHAPES:
            sys.exit("validate.py: alpha %g is not one of study 1's (%s)"
                     % (a, ", ".join("%g" % x for x in STUDY1_SHAPES)))
    cases = [Case(a, 0.0, s, args.n, out, args.ci, capdem) for a in alphas for s in seeds]
    cases += [Case(a, args.friction_mu, s, args.n, out, args.ci, capdem)
              for a in parse_list(args.friction_alphas) for s in seeds]
    if args.fresh:
        for c in cases:
            if lock_holder(c) is None and os.path.isdir(c.dir):
                shutil.rmtree(c.dir)
    print("study 1: %d cases, N = %d, %d thread(s) per run, %d job(s), output %s" % (
        len(cases), args.n, args.threads, args.jobs, out), flush=True)
    t_all = time.time()

    def one(c):
        holder = lock_holder(c)
        if holder is not None and args.wait:
            say("  %s: being run by process %d (%s); waiting for it" % (c.name, holder, peek(c.h5)))
            wait_for(c, holder)
            holder = None
        if holder is not None:
            say("  %s: being run by process %d (%s); skipped" % (c.name, holder, peek(c.h5)))
            return False
        done = run_state(c.h5)
        done = done is not None and done[2] == PHASE_DONE
        while not done and not args.no_run:
            res = advance(c, args, capdem)
            done = res == "done"
            if res != "capped":
                break
        if done:
            return analyse(c, capdem, force=args.reanalyse)
        if args.no_run:
            st = run_state(c.h5)
            say("  %s: %s" % (c.name, "not started" if st is None else
                              "stopped at step %d in phase %d (resumable)" % (st[1], st[2])))
        return False

    if args.jobs > 1:
        with ThreadPoolExecutor(args.jobs) as ex:
            finished = list(ex.map(one, cases))
    else:
        finished = [one(c) for c in cases]
    done_cases = [c for c, f in zip(cases, finished) if f]
    pending = [c.name for c, f in zip(cases, finished) if not f]
    print("study 1: %d of %d cases finished (%.1f s this invocation)%s" % (
        len(done_cases), len(cases), time.time() - t_all, ("; pending: " + ", ".join(pending)) if pending else ""))
    rows = [metrics(c) for c in done_cases]
    for r in rows:
        print("  %-22s %8d steps  %7.1f s wall (%d segment(s))  N_p* %d" % (
            r["case"], r["step"], r["run_wall_s"], r["run_segments"], r["n_particles_in_contact"]))
    agg = aggregate(rows)
    every = [metrics(c) for c in finished_cases_in(out)]  # results.json: every finished case of OUT
    agg_all = aggregate(every)
    write_results(out, every, agg_all)
    if agg:
        print_table(agg)
        if args.markdown:
            print()
            print(markdown(agg))
        if args.markdown_into:
            markdown_into(args.markdown_into, markdown(agg), "study1-table")
    if args.figures and done_cases:
        figures(args.figures, done_cases, agg, args.n, agg_all)
    if args.check:
        if pending:
            print("FAIL: cases not finished: " + ", ".join(pending))
            return 1
        return 0 if check_bands(rows) else 1
    return 0
