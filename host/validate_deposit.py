"""Studies 2-4 of docs/validation.md (Conzelmann et al.): deposit and compress.

Used by host/validate.py (`validate.py study2|study3|study4 ...`); the run,
resume, lock and timing machinery is validate_runs.py's (shared with study
1), only the configs, the references and the figures differ.

  study2  2D crosses in a box of width 30 L, psi 0.995, 0.754, 0.585, 0.473
  study3  3D stars (hexapods) in a cylinder of diameter 6 L, psi 0.995, 0.702, 0.526, 0.419
  study4  spheres, 2D box of width 30 d_p and cylinder of diameter 10 d_p (Conzelmann et al.'s references)

The aspect ratio of each psi is Conzelmann et al.'s Table S1.  The count follows the
paper's rule (compressed packing at least twice as high as the box is wide,
or as the cylinder's diameter) with an upper estimate of the packing
fraction (PHI_GUESS below), so that the rule holds; each run's H/W is
reported and checked afterwards.
"""
import json
import math
import os
import string
import subprocess

import capdem_h5
import numpy as np

import validate_runs as vr
from validate_study1 import eta_of, phi_fit

REPO = vr.REPO
ARM_D = vr.ARM_D
DENSITY = 1000.0  # [kg/m^3], the templates' material.density

# Table S1 of Conzelmann et al.: sphericity -> aspect ratio L / d_p.
STUDIES = {
    "study2": {"dim": 2, "shape": "cross", "domain": "box", "size_L": 30.0,
               "psis": [(0.995, 1.1), (0.754, 3.0), (0.585, 6.0), (0.473, 11.0)],
               "template": "configs/validation/study2/deposit_2d.yaml"},
    "study3": {"dim": 3, "shape": "hexapod", "domain": "cylinder", "size_L": 6.0,
               "psis": [(0.995, 1.1), (0.702, 3.0), (0.526, 6.0), (0.419, 11.0)],
               "template": "configs/validation/study3/deposit_cylinder.yaml"},
    "study4": {"cases": [("2d", {"dim": 2, "shape": "sphere", "domain": "box", "size_L": 30.0,
                                 "template": "configs/validation/study2/deposit_2d.yaml"}),
                         ("3d", {"dim": 3, "shape": "sphere", "domain": "cylinder", "size_L": 10.0,
                                 "template": "configs/validation/study3/deposit_cylinder.yaml"})]},
}

# Mueth, Jaeger, Nagel, PRE 57 (1998) 3164, fit of eq. (1) of Conzelmann et al. to
# their 3D glass-sphere packings: a = 3.0, b = 0.75, beta = 1.5 (the values
# are from Mueth et al., not from Conzelmann et al.'s text).
MUETH = {"a": 3.0, "b": 0.75, "beta": 1.5}


def k_paper_2d(psi):
    """Conzelmann et al., Fig. 6a's caption: linear fit to the 2D tail exponents (the
    issue's reference).  It rises as psi falls (1.43 to 1.52 over the study's
    psi), against the paper's own text (k_paper_2d_text)."""
    return 0.18 * (1.0 - psi) + 1.43


# Conzelmann et al.'s text: "In 2D packings, k decreases slightly with decreasing psi,
# i.e. k = 1.42 for psi = 0.995 and k = 1.32 for psi = 0.47" (psi, k).
K_TEXT_2D = ((0.995, 1.42), (0.47, 1.32))


def k_paper_2d_text(psi):
    """The straight line through Conzelmann et al.'s two 2D values in its text (the
    caption's fit with the sign of its slope turned: 1.43 - 0.18 (1 - psi)
    is within 0.02 of it)."""
    (p1, k1), (p0, k0) = K_TEXT_2D
    return k0 + (k1 - k0) * (psi - p0) / (p1 - p0)


def k_paper_3d(psi):
    """Conzelmann et al.: k = 1.38 +- 0.14 for psi >= 0.7, else the fit -2.03 (1 - psi)^2.43 + 1.29."""
    return 1.38 if psi >= 0.7 else -2.03 * (1.0 - psi) ** 2.43 + 1.29


def rdf_peaks_paper(alpha):
    """Conzelmann et al. eq. (11) in units of L: D_1 = sqrt(d^2 + ((L + d)/2)^2), D_2 = 2 D_1, D_3 = 3 D_1."""
    L, d = alpha, 1.0
    d1 = math.sqrt(d * d + ((L + d) / 2.0) ** 2) / L
    return [d1, 2 * d1, 3 * d1]


def polydispersity(dim, psi):
    """Conzelmann et al. (section II): 2D 0.3 for psi > 0.88, 0.15 for 0.88 >= psi (the
    paper states 0.15 down to 0.75 and nothing below: the default 0.15 of docs/references.md, Particles, is kept);
    3D 0.2 (stated for psi > 0.86; the default 0.2 below)."""
    if dim == 2:
        return 0.3 if psi > 0.88 else 0.15
    return 0.2


# 2D crosses: area fractions capdem measured in a box of 10 L (250 crosses,
# the study-2 protocol; 2026-11-22): alpha 3 0.75 (the CI twin of
# deposit_2d_crosses), alpha 6 0.60 (compressed), alpha 11 0.40 (settled
# 0.36, less the 10 % the piston took off the height at alpha 6).  The
# count uses 1.2 x these (walls take a larger share of a 10 L box than of
# 30 L), capped at 0.91.  Conzelmann et al. Fig. S1 gives the trend (a figure only).
PHI_2D_CROSSES = {3: 0.75, 6: 0.60, 11: 0.40}


def phi_guess(dim, shape, alpha):
    """Upper estimate of the compressed packing fraction, for the count rule:
    2D discs and near-discs (alpha 1.1): 0.91, the hexagonal packing of
    equal discs (0.907) rounded up (0.84, random close packing, was too
    low: capdem's polydisperse discs of study 4 reached 0.909 and only
    H/W = 1.85); thinner crosses pack looser (Conzelmann et al. Fig. S1): 1.2 x
    capdem's pilot values (PHI_2D_CROSSES), which halves the count at
    alpha = 11 where 0.91 gave H/W near 4; 3D stars: Tran et al. 2024's
    frictionless fit at eta = 1 - 1/alpha (friction only lowers it);
    spheres 0.64."""
    if dim == 2:
        measured = PHI_2D_CROSSES.get(alpha) if shape == "cross" else None
        return min(0.91, round(1.2 * measured, 3)) if measured else 0.91
    if shape == "sphere":
        return 0.64
    return phi_fit(eta_of(alpha))


def area_2d(shape, alpha, n=1500):
    """Area of the particle's cut in its plane (union of capsules), on a grid [m^2]."""
    L, r = alpha * ARM_D, 0.5 * ARM_D
    h = 0.5 * L - r  # half-length of the axis
    x = (np.arange(n) + 0.5) / n * L - 0.5 * L
    X, Y = np.meshgrid(x, x)
    if shape == "sphere":
        inside = X ** 2 + Y ** 2 <= r * r
    else:
        a1 = (np.clip(X, -h, h) - X) ** 2 + Y ** 2 <= r * r
        a2 = (np.clip(Y, -h, h) - Y) ** 2 + X ** 2 <= r * r
        inside = a1 | a2
    return inside.mean() * L * L


class DepositCase(vr.RunCase):
    def __init__(self, study, tag, spec, psi, alpha, seed, n, out, capdem, size_l=None):
        self.study, self.spec, self.psi, self.capdem = study, spec, psi, capdem
        self.alpha, self.mu, self.ci = alpha, 0.5, False  # default friction (docs/references.md, Contact law)
        self.dim, self.shape = spec["dim"], spec["shape"]
        self.poly = 0.2 if self.shape == "sphere" else polydispersity(self.dim, psi)
        props = vr.shape_props(capdem, self.shape, alpha, DENSITY)
        self.L = props["tip_length"]
        self.volume = props["volume"]
        self.size = (size_l or spec["size_L"]) * self.L  # W or D [m]
        es2, es3 = 1 + self.poly ** 2 / 3.0, 1 + self.poly ** 2
        phi = phi_guess(self.dim, self.shape, alpha)
        if self.dim == 2:
            self.area = area_2d(self.shape, alpha)
            n_rule = 2 * self.size ** 2 * phi / (self.area * es2)
        else:
            n_rule = 2 * self.size * math.pi * self.size ** 2 / 4 * phi / (self.volume * es3)
        self.n_rule, self.phi_guess = int(math.ceil(n_rule)), phi
        self.n = n if n else self.n_rule
        name = "%s_%s_n%d_s%d" % (tag, ("psi%s" % ("%g" % psi).replace(".", "p")) if psi else "ref", self.n, seed)
        vr.RunCase.__init__(self, name, out, seed)

    def write_config(self, steps):
        fields = dict(name=self.name, seed=self.seed, steps=steps, shape=self.shape,
                      aspect="" if self.shape == "sphere" else "aspect: %g," % self.alpha, n=self.n,
                      poly="%g" % self.poly)
        if self.dim == 2:
            fields.update(width="%.6g" % self.size, thickness="%.6g" % self.L)
        else:
            fields.update(diameter="%.6g" % self.size)
        with open(os.path.join(REPO, self.spec["template"])) as f:
            text = string.Template(f.read()).substitute(fields)
        os.makedirs(self.dir, exist_ok=True)
        with open(self.config, "w") as f:
            f.write(text)


def make_cases(args, capdem, out):
    seeds = vr.parse_list(args.seeds, int)
    cases = []
    if args.study in ("study2", "study3"):
        spec = STUDIES[args.study]
        psis = vr.parse_list(args.psis) if args.psis else [p for p, _ in spec["psis"]]
        table = dict(spec["psis"])
        for psi in psis:
            if psi not in table:
                raise SystemExit("validate.py: psi %g is not one of %s's (%s)"
                                 % (psi, args.study, ", ".join("%g" % p for p in table)))
            for s in seeds:
                cases.append(DepositCase(args.study, "cross2d" if spec["dim"] == 2 else "star3d", spec, psi,
                                         table[psi], s, args.n, out, capdem, args.width_l))
    else:
        for tag, spec in STUDIES["study4"]["cases"]:
            for s in seeds:
                cases.append(DepositCase("study4", "sphere" + tag, spec, None, 1.0, s, args.n, out, capdem,
                                         args.width_l))
    return cases


def analyse(case, capdem, force=False):
    if os.path.exists(case.analysis) and not force:
        with open(case.analysis) as f:
            d = json.load(f)
        st = vr.run_state(case.h5)
        if st and d.get("step") == st[1]:
            return True
    r = subprocess.run([capdem, "analyze", "run.h5", "--json", "--quiet"], cwd=case.dir, capture_output=True,
                       text=True)
    if r.returncode != 0:
        vr.say("  %s: capdem analyze failed (%d): %s" % (case.name, r.returncode, r.stderr.strip()))
        return False
    with open(case.analysis, "w") as f:
        f.write(r.stdout)
    return True


def pdf_type(pdf):
    """'A' when P(f) has its maximum at 0.5 <= f <= 1.5 and rises to it from the
    first bin (a peak near f = 1, Conzelmann et al. Fig. 1), else 'B'."""
    f, p = pdf[:, 0], pdf[:, 1]
    sel = f <= 3.0
    k = int(np.argmax(p[sel]))
    return "A" if 0.5 <= f[sel][k] <= 1.5 and p[sel][k] > 1.1 * p[0] else "B"


def rdf_peaks(rdf, count=3, window=0.15):
    """First maxima of G(r) in r/L: G smoothed by a 5-bin running mean, a peak
    is the largest value within +-window (in L) and above 1.05.  A reading of
    capdem analyze's G(r) table, not a measure of capdem analyze (which has
    no peak finder)."""
    r, g = rdf[:, 0], rdf[:, 1]
    gs = np.convolve(g, np.ones(5) / 5, mode="same")
    peaks = []
    for i in range(len(gs)):
        near = np.abs(r - r[i]) <= window
        if gs[i] > 1.05 and gs[i] >= gs[near].max():
            peaks.append(float(r[i]))
        if len(peaks) == count:
            break
    return peaks


END_WINDOW = 20000  # [steps] the run's last stretch: longer than the packings' slowest swings (10,000-16,000 steps)


def end_state(case):
    """The end of the run from its time series: the load on the piston [N]
    at the last row (with protocol.piston_hold = position it is what the
    relaxed packing exerts, not the target), the kinetic energy of the
    particles in contact over the elastic energy at the last row (the
    relaxation test's ratio, the piston's share left out), and the largest
    of that ratio and the load's range [N] over the last END_WINDOW steps: a
    packing that still swings passes the test when a check falls where its
    kinetic energy goes through zero, and these say by how much it swings."""
    with capdem_h5.open_run(case.h5) as f:
        step, _, eel = capdem_h5.observable(f, "elastic_energy")
        load = capdem_h5.observable(f, "wall_load")[2]
        ke = capdem_h5.observable(f, "kinetic_energy_in_contact")[2]
    last = step >= step[-1] - END_WINDOW
    ratio = np.where(eel > 0, ke / np.where(eel > 0, eel, 1), np.nan)
    return {"load_end": float(load[-1]), "ke_over_eel_end": float(ratio[-1]),
            "ke_over_eel_end_max": float(np.nanmax(ratio[last])),
            "load_end_range": float(load[last].max() - load[last].min())}


def metrics(case):
    with open(case.analysis) as f:
        d = json.load(f)
    nf, st, bf = d["normal_forces"], d["stress"], d["bond_forces"]
    pdf = np.array(nf["curves"]["pdf"]["data"])
    row = {"study": case.study, "case": case.name, "psi": case.psi, "alpha": case.alpha, "seed": case.seed,
           "n": case.n, "n_rule": case.n_rule, "phi_guess": case.phi_guess, "step": d["step"],
           "k": nf.get("k"), "k_lo": nf.get("k_lo"), "k_hi": nf.get("k_hi"), "k_wls": nf.get("k_wls"),
           "mueth_a": nf.get("mueth_a"), "mueth_b": nf.get("mueth_b"), "mueth_beta": nf.get("mueth_beta"),
           "pf_type": pdf_type(pdf), "stress_tail_k": st.get("tail_k"),
           # P(i), the first stress invariant over its mean: the same type test, and its first bin
           # (Conzelmann et al.: a pronounced peak at i = 1 for 2D crosses above psi_crit that disappears
           # below it "as lim_{i -> 0} P(i) increases with decreasing psi")
           "stress_type": pdf_type(np.array(st["curves"]["pdf"]["data"])),
           "stress_p0": float(st["curves"]["pdf"]["data"][0][1]),
           # the same test on the forces between particles (capdem's bond forces: the vector sum
           # of a touching pair's spherocylinder contacts, over its own mean), and how many
           # spherocylinder contacts make one particle contact
           "pair_type": pdf_type(np.array(bf["curves"]["pdf_mean1"]["data"])),
           "contacts_per_pair": nf["n_contacts"] / bf["n_bonds"],
           "phi_container": d["packing"].get("phi_container"),
           "height_over_width": d["packing"]["container_height"] / case.size}
    if "rdf" in d:
        row["rdf_peaks"] = rdf_peaks(np.array(d["rdf"]["curves"]["rdf"]["data"]))
    row.update(end_state(case))
    timing = []
    if os.path.exists(case.timing):
        with open(case.timing) as f:
            timing = json.load(f)
    row["run_wall_s"] = round(sum(t["wall_s"] for t in timing), 1)
    row["run_cpu_s"] = round(sum(t["cpu_s"] or 0 for t in timing), 1)
    row["capdem"] = timing[-1].get("capdem") if timing else None
    row["git"] = timing[-1].get("git") if timing else None
    row["pdf"] = pdf.tolist()  # P(f) of the normal forces, for the figures
    return row


# A record is one finished run's row of the tables (metrics() above: every
# number of the study's table, its P(f) for the figures, the run time and
# the capdem commit), kept as one small JSON file per run in a folder of the
# repository (--records).  The run folders are large and live outside the
# repository, on a machine that a session may lose; the records are what the
# tables and figures of docs/validation.md are regenerated from, so that a
# study whose runs take longer than one session accumulates across sessions.
RECORD_VERSION = 1


def record_path(records, case):
    return os.path.join(records, case.study, case.name + ".json")


def write_record(records, case, row):
    path = record_path(records, case)
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(case.config) as f:
        config = f.read()
    with open(path, "w") as f:
        json.dump({"record_version": RECORD_VERSION, "written": vr.now(), "row": row, "config": config}, f,
                  indent=1)
        f.write("\n")


def read_record(records, case):
    """The row of a case's record, or None when there is none.  A record of
    another format, or one whose case differs from what the driver would run
    now (count, aspect ratio, seed), is refused with the reason."""
    path = record_path(records, case)
    if not os.path.exists(path):
        return None
    with open(path) as f:
        rec = json.load(f)
    if rec.get("record_version") != RECORD_VERSION:
        raise SystemExit("validate.py: %s: record_version %r, this driver reads %d"
                         % (path, rec.get("record_version"), RECORD_VERSION))
    row = rec["row"]
    for key, want in (("n", case.n), ("alpha", case.alpha), ("seed", case.seed), ("psi", case.psi)):
        if row.get(key) != want:
            raise SystemExit("validate.py: %s: %s is %r, the case has %r (a record of another set-up: move it)"
                             % (path, key, row.get(key), want))
    return row


def aggregate(rows):
    groups = {}
    for r in rows:
        groups.setdefault((r["study"], r["case"].rsplit("_s", 1)[0]), []).append(r)
    out = []
    for (study, key), rs in sorted(groups.items()):
        g = {"study": study, "key": key, "psi": rs[0]["psi"], "alpha": rs[0]["alpha"], "n": rs[0]["n"],
             "n_rule": rs[0]["n_rule"], "seeds": sorted(r["seed"] for r in rs),
             "types": "".join(r["pf_type"] for r in rs), "pair_types": "".join(r["pair_type"] for r in rs),
             "stress_types": "".join(r.get("stress_type", "?") for r in rs)}
        for k in ("k", "k_wls", "mueth_a", "mueth_b", "mueth_beta", "stress_tail_k", "phi_container",
                  "height_over_width", "run_wall_s", "step", "contacts_per_pair", "load_end", "stress_p0",
                  "ke_over_eel_end_max"):
            vals = np.array([r[k] for r in rs if r.get(k) is not None], dtype=float)
            g[k] = float(vals.mean()) if len(vals) else None
            g[k + "_se"] = float(vals.std(ddof=1) / math.sqrt(len(vals))) if len(vals) >= 2 else None
        peaks = [r["rdf_peaks"] for r in rs if r.get("rdf_peaks")]
        if peaks:
            m = min(len(p) for p in peaks)
            arr = np.array([p[:m] for p in peaks])
            g["rdf_peaks"] = arr.mean(axis=0).tolist()
            g["rdf_peaks_se"] = (arr.std(axis=0, ddof=1) / math.sqrt(len(arr))).tolist() if len(arr) >= 2 else None
        if study == "study2":
            g["k_paper"] = k_paper_2d(g["psi"])
            g["k_paper_text"] = k_paper_2d_text(g["psi"])
            g["rdf_peaks_paper"] = rdf_peaks_paper(g["alpha"]) if g["psi"] < 0.9 else [1.0, 1.91]
        elif study == "study3":
            g["k_paper"] = k_paper_3d(g["psi"])
        elif study == "study4":  # Conzelmann et al.: its 2D fit at psi = 1; Murphy et al.'s 3D spheres
            g["k_paper"] = k_paper_2d(1.0) if key.startswith("sphere2d") else 1.4
        out.append(g)
    return out


def print_table(agg):
    for g in agg:
        line = "%-24s N %5d (rule %5d)  seeds %-6s  k %s (paper %s)  k_wls %s  P(f) type %s (particle pairs %s)  H/W %s" % (
            g["key"], g["n"], g["n_rule"], ",".join(map(str, g["seeds"])), vr.pm(g, "k", 2),
            vr.ref(g.get("k_paper")), vr.pm(g, "k_wls", 2), g["types"], g["pair_types"],
            vr.pm(g, "height_over_width", 2))
        if g.get("rdf_peaks"):
            line += "  G(r) peaks %s (paper %s)" % (
                ", ".join("%.2f" % p for p in g["rdf_peaks"]),
                ", ".join("%.2f" % p for p in g.get("rdf_peaks_paper", [])))
        if g["study"] == "study4":
            line += "  Mueth a, b, beta = %s, %s, %s (Mueth 1998: 3.0, 0.75, 1.5)" % (
                vr.pm(g, "mueth_a", 2), vr.pm(g, "mueth_b", 2), vr.pm(g, "mueth_beta", 2))
        print(line)


def markdown(agg):
    """The table of docs/validation.md for one study (mean +- standard error
    over seeds; one seed: its value)."""
    cols = ["ψ (α)", "N", "seeds", "H / W", "Φ", "k, max. likelihood", "k, least squares", "Conzelmann et al. k",
            "P(f) type", "type, particle pairs", "contacts / touching pair", "P(i) tail k"]
    study = agg[0]["study"] if agg else ""
    if study == "study2":  # after "Conzelmann et al. k" (the caption's fit); P(i)'s type and first bin
        cols.insert(cols.index("Conzelmann et al. k") + 1, "Conzelmann et al. k, text")
        cols += ["P(i) type", "P(i) first bin"]
    if study == "study2" or study == "study4":
        cols += ["G(r) peaks / L (Conzelmann et al.)"]
    if study == "study4":
        cols += ["Mueth a, b, β (Mueth: 3.0, 0.75, 1.5)"]
    if study == "study2":
        cols += ["piston load at the end / N", "KE / E_el, largest of the last 20,000 steps"]
    cols += ["steps (mean)", "wall per run"]
    lines = ["| " + " | ".join(cols) + " |", "|" + "---|" * len(cols)]
    for g in sorted(agg, key=lambda g: -(g["psi"] or 0)):
        shape = ("%.3f (%g)" % (g["psi"], g["alpha"])) if g["psi"] else g["key"].split("_")[0]
        cells = [shape, "%d" % g["n"], ",".join(map(str, g["seeds"])), vr.pm(g, "height_over_width", 2),
                 vr.pm(g, "phi_container", 3), vr.pm(g, "k", 2), vr.pm(g, "k_wls", 2), vr.ref(g.get("k_paper")),
                 ", ".join(g["types"]), ", ".join(g["pair_types"]), vr.pm(g, "contacts_per_pair", 2),
                 vr.pm(g, "stress_tail_k", 2)]
        if study == "study2":
            cells.insert(cols.index("Conzelmann et al. k, text"), vr.ref(g.get("k_paper_text")))
            cells += [", ".join(g["stress_types"]), vr.pm(g, "stress_p0", 2)]
        if study in ("study2", "study4"):
            peaks = g.get("rdf_peaks") or []
            cells.append("%s (%s)" % (", ".join("%.2f" % p for p in peaks) or "—",
                                      ", ".join("%.2f" % p for p in g.get("rdf_peaks_paper", [])) or "—"))
        if study == "study4":
            cells.append("%s; %s; %s" % (vr.pm(g, "mueth_a", 2), vr.pm(g, "mueth_b", 2), vr.pm(g, "mueth_beta", 2)))
        if study == "study2":
            cells.append(vr.pm(g, "load_end", 0))
            cells.append("%.1e" % g["ke_over_eel_end_max"] if g.get("ke_over_eel_end_max") is not None else "—")
        cells += ["%.0f" % g["step"] if g.get("step") else "—",
                  "%.0f s" % g["run_wall_s"] if g.get("run_wall_s") else "—"]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def figures(outdir, rows, agg, study):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    os.makedirs(outdir, exist_ok=True)
    fig, ax = plt.subplots(figsize=(5.5, 4))
    seen = set()
    for r in sorted(rows, key=lambda r: (-(r["psi"] or 1), r["seed"])):
        key = r["case"].rsplit("_s", 1)[0]
        if key in seen:
            continue
        seen.add(key)
        pdf = np.array(r["pdf"])
        good = pdf[:, 1] > 0
        ax.semilogy(pdf[good, 0], pdf[good, 1], "o-", ms=3, lw=0.8, label=key)
    f = np.linspace(0, 6, 200)
    ax.semilogy(f, MUETH["a"] * (1 - MUETH["b"] * np.exp(-f ** 2)) * np.exp(-MUETH["beta"] * f), "k--",
                label="Mueth et al. 1998")
    ax.set_xlabel("f = F_n / <F_n>")
    ax.set_ylabel("P(f)")
    ax.set_ylim(1e-4, 3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(outdir, "%s_pf.png" % study), dpi=110)
    plt.close(fig)
    written = ["%s_pf.png" % study]
    if study in ("study2", "study3"):
        fig, ax = plt.subplots(figsize=(5.5, 4))
        ps = np.linspace(0.4, 1.0, 100)
        ax.plot(ps, [k_paper_2d(p) if study == "study2" else k_paper_3d(p) for p in ps], "k--",
                label="Conzelmann et al. fit" + (" (Fig. 6a caption)" if study == "study2" else ""))
        if study == "study2":
            ax.plot(ps, [k_paper_2d_text(p) for p in ps], ":", color="grey",
                    label="Conzelmann et al. text: k = 1.42 at 0.995, 1.32 at 0.47")
            ax.plot(*zip(*K_TEXT_2D), "kx")
        gs = [g for g in agg if g["study"] == study and g.get("k") is not None]
        ax.errorbar([g["psi"] for g in gs], [g["k"] for g in gs], [g["k_se"] or 0 for g in gs], fmt="o",
                    capsize=3, label="capdem, k (maximum likelihood)")
        ax.errorbar([g["psi"] for g in gs], [g["k_wls"] for g in gs], [g["k_wls_se"] or 0 for g in gs], fmt="s",
                    mfc="none", capsize=3, label="capdem, k (least squares, as the paper)")
        ax.set_xlabel("sphericity ψ")
        ax.set_ylabel("tail exponent k")
        ax.legend(fontsize=7)
        fig.tight_layout()
        fig.savefig(os.path.join(outdir, "%s_k.png" % study), dpi=110)
        plt.close(fig)
        written.append("%s_k.png" % study)
    print("figures: %s (%s)" % (outdir, ", ".join(written)))


def run_study(args):
    capdem = os.path.join(os.path.abspath(args.build), "capdem")
    if not os.access(capdem, os.X_OK):
        raise SystemExit("validate.py: %s not found; build first (README)" % capdem)
    out = os.path.join(os.path.abspath(args.out), args.study)
    cases = make_cases(args, capdem, out)
    print("%s: %d cases, output %s" % (args.study, len(cases), out))
    for c in cases:  # capdem picks the height (lattice fit) and dt (run.steps_per_collision: 20)
        print("  %-26s alpha %-4g N %5d (rule %5d, phi guess %.3f)  %s %.4g m  poly %g"
              % (c.name, c.alpha, c.n, c.n_rule, c.phi_guess, "W" if c.dim == 2 else "D", c.size, c.poly))
    if args.plan:
        return 0
    os.makedirs(out, exist_ok=True)
    finished = []
    for c in cases:
        holder = vr.lock_holder(c)
        if holder is not None:  # another driver's: report, do not open the file it writes
            vr.say("  %s: being run by process %d (%s)" % (c.name, holder, vr.peek(c.h5)))
            continue
        done = vr.run_state(c.h5)
        done = done is not None and done[2] == vr.PHASE_DONE
        while not done and not args.no_run:
            res = vr.advance(c, args, capdem)
            done = res == "done"
            if res != "capped":
                break
        if done and analyse(c, capdem, args.reanalyse):
            finished.append(c)
    rows = [metrics(c) for c in finished]
    recorded = []
    if args.records:
        for c, row in zip(finished, rows):
            write_record(args.records, c, row)
        for c in cases:
            if c not in finished:
                row = read_record(args.records, c)
                if row is not None:
                    recorded.append(row)
        if recorded:
            print("%s: %d cases from their records in %s (run folders not here)"
                  % (args.study, len(recorded), args.records))
    rows += recorded
    agg = aggregate(rows)
    with open(os.path.join(out, "results.json"), "w") as f:
        json.dump({"generated": vr.now(), "runs": rows, "cases": agg}, f, indent=1)
    print("%s: %d of %d cases finished" % (args.study, len(rows), len(cases)))
    print_table(agg)
    if args.markdown:
        print(markdown(agg))
    if args.markdown_into and agg:
        vr.markdown_into(args.markdown_into, markdown(agg), args.study + "-table")
    if args.figures and rows:
        figures(args.figures, rows, agg, args.study)
    return 0
