#!/usr/bin/python3
"""capdem's contact law in LIGGGHTS 3.8 terms (`pair_style gran model
hooke/stiffness tangential history`), and the files LIGGGHTS reads.

capdem (docs/references.md, Contact law, kernels/contact_law.h), per contact of effective mass
m = m_i m_j / (m_i + m_j) (m = m_i against a wall):

    F_n = max(0, (k_n/2) delta_n - eta_n sqrt(2 m k_n) v_n)
    F_t = -(k_t/2) delta_t - eta_t sqrt(2 m k_t) v_t,  |F_t| <= mu F_n  (friction_limit: total)

LIGGGHTS `model hooke/stiffness tangential history absolute_damping on
limitForce on` (its documentation, gran_model_hooke_stiffness):

    F_n = max(0, kn delta_n - gamman_abs v_n)
    F_t = -kt xi - gammat_abs v_t  (sticking; sliding: |kt xi| capped at mu F_n, no damping)

with kn, kt, gamman_abs, gammat_abs and coefficientFriction given per pair of
atom types (`fix property/global ... peratomtypepair`).  So kn = k_n/2 and
kt = k_t/2 exactly, but the damping coefficient is a constant per type pair
while capdem's grows with sqrt(m): with absolute_damping off LIGGGHTS takes
m gamman (linear in m), which is no better.  The spheres are polydisperse, so
each sphere gets the type of its mass bin (K bins, equal in log m between the
lightest and heaviest sphere) and each type pair the damping of the bins'
geometric-centre masses.  A sphere's mass is within a factor r^(1/2) of its
bin's (r = (m_max/m_min)^(1/K)), so the damping coefficient is within a
factor r^(1/4): 1.3 % for K = 24 and the bench's +-20 % diameters (mass ratio
3.4).  One more type is the walls' (frictionless, m = m_i).

Differences of the tangential part, both only while sliding or turning:
capdem caps the spring plus damping at mu F_n, LIGGGHTS the spring alone and
then drops the damping; capdem rotates the spring into the new tangent plane
keeping its length, LIGGGHTS projects it.  A sticking contact feels the same
force in both.

    /usr/bin/python3 bench/liggghts/liggghts_law.py [--kn 1e5 --kt 5e4 --eta-n 0.2 --eta-t 0.2 --mu 0.5]
        [--check]   # two-sphere and sphere-wall collisions in LIGGGHTS: e = 0.572 (docs/contacts.md)
"""
import argparse
import json
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
MATERIAL = dict(kn=1e5, kt=5e4, eta_n=0.2, eta_t=0.2, mu=0.5)  # docs/references.md, Contact law; walls frictionless
N_TYPES = 24  # mass bins; the damping error bound is r^(1/4) - 1, r = (m_max/m_min)^(1/K)


def ensure_liggghts():
    """Debian's liggghts (3.8) with apt-get when `liggghts` is missing."""
    if shutil.which("liggghts"):
        return
    print("liggghts not found; installing Debian's liggghts package", file=sys.stderr)
    env = dict(os.environ, DEBIAN_FRONTEND="noninteractive")
    sudo = [] if os.geteuid() == 0 else ["sudo"]
    subprocess.run(sudo + ["apt-get", "update"], check=True, env=env)
    subprocess.run(sudo + ["apt-get", "install", "-y", "--no-install-recommends", "liggghts", "openmpi-bin"],
                   check=True, env=env)


def liggghts_version():
    out = subprocess.run(["liggghts", "-log", "none", "-h"], capture_output=True, text=True).stdout  # no log.liggghts left behind
    m = re.search(r"LIGGGHTS \(Version ([^,)]*)", out)
    return m.group(1).strip() if m else "unknown"


def mass_bins(masses, k=N_TYPES):
    """(types 1..k of each mass, representative mass of each type [kg], bound
    on the relative error of sqrt(m) that a type's damping carries)."""
    lo, hi = min(masses), max(masses)
    if hi <= lo * (1 + 1e-12):
        return [1] * len(masses), [lo] * k, 0.0
    width = math.log(hi / lo) / k
    types = [min(k, 1 + int(math.log(m / lo) / width)) for m in masses]
    reps = [lo * math.exp((t + 0.5) * width) for t in range(k)]
    return types, reps, math.exp(width / 4) - 1


def damping(eta, stiffness, m):
    """capdem's damping coefficient eta sqrt(2 m k) [N s/m]."""
    return eta * math.sqrt(2.0 * m * stiffness)


def material_lines(reps, kn, kt, eta_n, eta_t, mu):
    """The fix property/global commands: types 1..K spheres of mass reps[t-1],
    type K+1 the walls (m = m_i, mu = 0)."""
    k = len(reps)
    n = k + 1

    def m_eff(a, b):  # a, b in 0..k; index k is the wall
        if a == k and b == k:
            return reps[-1]  # wall-wall: never used, any positive value
        if a == k or b == k:
            return reps[min(a, b)]
        return reps[a] * reps[b] / (reps[a] + reps[b])

    def matrix(f):
        return " ".join("%.12g" % f(a, b) for a in range(n) for b in range(n))

    return [
        "fix m_kn all property/global kn peratomtypepair %d %s" % (n, matrix(lambda a, b: 0.5 * kn)),
        "fix m_kt all property/global kt peratomtypepair %d %s" % (n, matrix(lambda a, b: 0.5 * kt)),
        "fix m_gn all property/global gamman_abs peratomtypepair %d %s" % (n, matrix(lambda a, b: damping(eta_n, kn, m_eff(a, b)))),
        "fix m_gt all property/global gammat_abs peratomtypepair %d %s" % (n, matrix(lambda a, b: damping(eta_t, kt, m_eff(a, b)))),
        "fix m_mu all property/global coefficientFriction peratomtypepair %d %s"
        % (n, matrix(lambda a, b: 0.0 if k in (a, b) else mu)),
    ]


def write_inputs(spheres, box, out_base, material=MATERIAL, k=N_TYPES):
    """Writes OUT.data (atom_style granular: id type diameter density x y z,
    then velocities) and OUT.material (the property/global commands).
    spheres: list of (diameter [m], mass [kg], x, v, omega); box: (lo, hi) per
    axis [m].  Returns the metadata (types, damping error bound)."""
    types, reps, err = mass_bins([s[1] for s in spheres], k)
    with open(out_base + ".data", "w") as f:
        f.write("capdem packing for LIGGGHTS\n\n%d atoms\n%d atom types\n\n" % (len(spheres), k + 1))
        for (lo, hi), ax in zip(box, "xyz"):
            f.write("%.9g %.9g %slo %shi\n" % (lo, hi, ax, ax))
        f.write("\nAtoms\n\n")
        for i, ((d, m, x, _, _), t) in enumerate(zip(spheres, types)):
            rho = m / (math.pi / 6 * d ** 3)
            f.write("%d %d %.12g %.12g %.12g %.12g %.12g\n" % (i + 1, t, d, rho, x[0], x[1], x[2]))
        f.write("\nVelocities\n\n")
        for i, (_, _, _, v, w) in enumerate(spheres):
            f.write("%d %.12g %.12g %.12g %.12g %.12g %.12g\n" % (i + 1, v[0], v[1], v[2], w[0], w[1], w[2]))
    with open(out_base + ".material", "w") as f:
        f.write("\n".join(material_lines(reps, **material)) + "\n")
    return {"types": k, "wall_type": k + 1, "damping_rel_error_bound": err}


def run_liggghts(var, log, ranks=1, yield_when_idle=True, script="in.capdem.liggghts"):
    """Runs a script of this folder with -var k v; returns the log's text."""
    cmd = ["mpirun", "--allow-run-as-root"] + (["--mca", "mpi_yield_when_idle", "1"] if yield_when_idle else []) + [
        "-np", str(ranks), "liggghts", "-in", os.path.join(HERE, script), "-log", log, "-screen", "none"]
    for key, val in var.items():
        cmd += ["-var", key, str(val)]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode:
        tail = open(log).read()[-1500:] if os.path.exists(log) else ""
        raise SystemExit("LIGGGHTS failed (%d), see %s: %s" % (p.returncode, log, tail + p.stdout[-1500:] + p.stderr[-1500:]))
    return open(log).read()


def collision(m_pair, wall, work, material=MATERIAL):
    """Head-on collision in LIGGGHTS (no gravity): two spheres of masses
    m_pair, or the first one against a wall; returns v_out / v_in."""
    d, v0 = 5e-3, 0.1  # [m], [m/s]
    m1, m2 = m_pair
    k = N_TYPES
    # each sphere's type carries exactly its mass, so that the check sees the
    # law and not the mass bins' damping error
    reps = [m1] * k if wall else [min(m1, m2)] * (k // 2) + [max(m1, m2)] * (k - k // 2)
    types = [1] if wall else ([1, k] if m1 <= m2 else [k, 1])
    base = os.path.join(work, "collision_%s" % ("wall" if wall else "pair"))
    spheres = [(d, m1, (0.02, 0.02, 0.02), (-v0 if wall else v0, 0, 0), (0, 0, 0))]
    if not wall:
        spheres.append((d, m2, (0.02 + d * 1.001, 0.02, 0.02), (0, 0, 0), (0, 0, 0)))
    k_c = 0.5 * material["kn"]
    t_c = math.pi / math.sqrt(k_c / (m1 * m2 / (m1 + m2) if not wall else m1))
    dt = t_c / 2000
    steps = int(3 * t_c / dt) + int(0.001 * d / v0 / dt)
    write_inputs_typed(spheres, types, reps, ((0, 0.05),) * 3, base, material)
    text = run_liggghts({"data": base + ".data", "material": base + ".material", "dt": dt, "steps": steps,
                         "wall": int(wall), "wallx": 0.02 - 0.5 * d * 1.001, "walltype": k + 1},
                        base + ".log", script="in.collision.liggghts")
    rows = re.findall(r"^\s*%d\s+(\S+)\s+(\S+)\s*$" % steps, text, re.M)
    if not rows:
        raise SystemExit("liggghts_law: no final velocities in %s.log" % base)
    va, vb = (float(x) for x in rows[-1])
    return abs(va) / v0 if wall else (vb - va) / v0


def write_inputs_typed(spheres, types, reps, box, out_base, material):
    """write_inputs with given types and representative masses (the collision test)."""
    with open(out_base + ".data", "w") as f:
        f.write("collision\n\n%d atoms\n%d atom types\n\n" % (len(spheres), len(reps) + 1))
        for (lo, hi), ax in zip(box, "xyz"):
            f.write("%.9g %.9g %slo %shi\n" % (lo, hi, ax, ax))
        f.write("\nAtoms\n\n")
        for i, ((d, m, x, _, _), t) in enumerate(zip(spheres, types)):
            f.write("%d %d %.12g %.12g %.12g %.12g %.12g\n" % (i + 1, t, d, m / (math.pi / 6 * d ** 3), x[0], x[1], x[2]))
        f.write("\nVelocities\n\n")
        for i, (_, _, _, v, w) in enumerate(spheres):
            f.write("%d %.12g %.12g %.12g %.12g %.12g %.12g\n" % (i + 1, v[0], v[1], v[2], w[0], w[1], w[2]))
    with open(out_base + ".material", "w") as f:
        f.write("\n".join(material_lines(reps, **material)) + "\n")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--kn", type=float, default=1e5)
    ap.add_argument("--kt", type=float, default=5e4)
    ap.add_argument("--eta-n", type=float, default=0.2)
    ap.add_argument("--eta-t", type=float, default=0.2)
    ap.add_argument("--mu", type=float, default=0.5)
    ap.add_argument("--check", action="store_true",
                    help="collide two spheres and a sphere with a wall in LIGGGHTS; exit 1 unless e = 0.572")
    ap.add_argument("--work", default=None)
    a = ap.parse_args()
    material = dict(kn=a.kn, kt=a.kt, eta_n=a.eta_n, eta_t=a.eta_t, mu=a.mu)
    print(json.dumps({"kn": 0.5 * a.kn, "kt": 0.5 * a.kt, "types": N_TYPES + 1,
                      "pair_style": "gran model hooke/stiffness tangential history absolute_damping on limitForce on"}))
    if not a.check:
        return 0
    work = a.work or tempfile.mkdtemp(prefix="liggghts-law.")
    ok = True
    # light, heavy and unequal pairs and a wall: every m the bench's spheres have
    for masses, wall in (((3.4e-5, 3.4e-5), False), ((1.1e-4, 1.1e-4), False), ((3.4e-5, 1.1e-4), False),
                         ((6.5e-5, None), True)):
        e = collision(masses, wall, work, material)
        good = abs(e - 0.572) < 0.005 if abs(a.eta_n - 0.2) < 1e-12 else True
        ok &= good
        print(json.dumps({"masses": masses, "wall": wall, "e": e, "expected": 0.572, "ok": good}))
    print("LIGGGHTS restitution check:", "ok" if ok else "FAILED")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
