#!/usr/bin/python3
"""capdem's contact law written in LAMMPS's `pair_style granular` terms.

capdem (docs/references.md, Contact law, kernels/contact_law.h), per contact between bodies of
effective mass m = m_i m_j / (m_i + m_j):

    F_n = max(0, (k_n/2) delta_n - eta_n sqrt(2 m k_n) v_n)
    F_t = -(k_t/2) delta_t - eta_t sqrt(2 m k_t) v_t,  |F_t| <= mu F_n  (friction_limit: total)

LAMMPS 29Sep2021 `pair_style granular`, `hooke kn e' tangential linear_history
kt x mu damping tsuji limit_damping`:

    F_n = max(0, kn delta_n - a(e') sqrt(m kn) v_n)          (limit_damping: no attraction)
    F_t = -kt xi - x a(e') sqrt(m kn) v_t,  |F_t| <= mu |F_n|

with a(e') = 1.2728 - 4.2783 e' + 11.087 e'^2 - 22.348 e'^3 + 27.467 e'^4
- 18.022 e'^5 + 4.8218 e'^6 (Tsuji's polynomial, applied by LAMMPS to the
number given after kn).  The two laws are the same function of (delta, v, m)
when

    kn = k_n / 2,  kt = k_t / 2,
    a(e') sqrt(m k_n/2) = eta_n sqrt(2 m k_n)   ->  a(e') = 2 eta_n,
    x a(e') sqrt(m k_n/2) = eta_t sqrt(2 m k_t) ->  x = (eta_t / eta_n) sqrt(k_t / k_n),

for every m, so polydisperse pairs and walls (m = m_i) match too.  e' is not
the restitution: it is the number whose Tsuji polynomial is 2 eta_n (0.4403
for eta_n = 0.2).  The restitution of both laws is e = 0.527 unclipped,
0.572 with the max(0, .) (docs/contacts.md); check_restitution() integrates
a head-on collision with the LAMMPS constants to confirm it.

`gran/hooke/history` (damping m_eff gamma_n v_n, gamma_n in 1/s) cannot
reproduce eta_n sqrt(2 m k_n) for more than one value of m, so it is not used.

    /usr/bin/python3 bench/lammps/lammps_law.py [--kn 1e5 --kt 5e4 --eta-n 0.2 --eta-t 0.2 --mu 0.5] [--check]
"""
import argparse
import json
import math
import sys


def tsuji_alpha(e):
    """LAMMPS's damping tsuji: the prefactor a of sqrt(m kn) for coefficient e."""
    return (1.2728 - 4.2783 * e + 11.087 * e ** 2 - 22.348 * e ** 3 + 27.467 * e ** 4
            - 18.022 * e ** 5 + 4.8218 * e ** 6)


def tsuji_input_for(alpha):
    """The number e' in [0, 1] with tsuji_alpha(e') = alpha (bisection; the
    polynomial falls monotonically from 1.2728 to 0.0003 on [0, 1])."""
    if not tsuji_alpha(1.0) <= alpha <= tsuji_alpha(0.0):
        raise ValueError("damping prefactor %g outside Tsuji's range [%g, %g]" % (alpha, tsuji_alpha(1.0), tsuji_alpha(0.0)))
    lo, hi = 0.0, 1.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if tsuji_alpha(mid) > alpha:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def lammps_constants(kn, kt, eta_n, eta_t, mu):
    """pair_style granular coefficients equivalent to capdem's material."""
    alpha = 2.0 * eta_n
    return {
        "kn": 0.5 * kn,
        "kt": 0.5 * kt,
        "tsuji_e": tsuji_input_for(alpha),
        "tsuji_alpha": alpha,
        "xgammat": (eta_t / eta_n) * math.sqrt(kt / kn) if eta_n > 0 else 0.0,
        "mu": mu,
    }


def hertz_constants(E, nu, eta_n, eta_t, mu):
    """pair_style granular coefficients equivalent to capdem's Hertz-Mindlin
    law (docs/contacts.md).  LAMMPS's hertz/material takes E and nu for
    E* = E / (2 (1 - nu^2)) and F_n = (4/3) E* a delta, its damping tsuji is
    alpha sqrt(m (4/3) E* a) v_n; capdem's 2 sqrt(5/6) eta_n sqrt(2 E* a m)
    is that with alpha = sqrt(5) eta_n.  tangential mindlin NULL gives
    k_t = 8 G* a, and its damping x times the normal one; capdem's
    gamma_t / gamma_n = (eta_t / eta_n) sqrt(8 G* / (2 E*))."""
    e_star = E / (2 * (1 - nu * nu))
    g_star = E / (4 * (2 - nu) * (1 + nu))
    alpha = math.sqrt(5.0) * eta_n
    return {
        "law": "hertz_mindlin", "E": E, "nu": nu,
        "tsuji_e": tsuji_input_for(alpha), "tsuji_alpha": alpha,
        "xgammat": (eta_t / eta_n) * 2 * math.sqrt(g_star / e_star) if eta_n > 0 else 0.0,
        "mu": mu,
    }


def pair_coeff_args(c, mu=None):
    """The model keywords of pair_coeff / fix wall/gran granular."""
    if c.get("law") == "hertz_mindlin":
        return ("hertz/material %.10g %.15g %.10g tangential mindlin NULL %.15g %.10g damping tsuji limit_damping"
                % (c["E"], c["tsuji_e"], c["nu"], c["xgammat"], c["mu"] if mu is None else mu))
    return ("hooke %.10g %.15g tangential linear_history %.10g %.15g %.10g damping tsuji limit_damping"
            % (c["kn"], c["tsuji_e"], c["kt"], c["xgammat"], c["mu"] if mu is None else mu))


def restitution(kn_contact, alpha, m, clip, v0=0.1, steps_per_period=2000):
    """Head-on collision of two bodies of effective mass m with the LAMMPS
    normal law F = kn d - alpha sqrt(m kn) v_n (clipped at 0 if clip):
    velocity Verlet on the relative coordinate; returns e = v_out / v_in."""
    omega = math.sqrt(kn_contact / m)
    dt = 2 * math.pi / omega / steps_per_period
    c = alpha * math.sqrt(m * kn_contact)
    d, v = 0.0, v0  # overlap and its rate (approach speed > 0)

    def force(d, v):  # repulsive force along the overlap; v = d' = -v_n
        f = kn_contact * d + c * v
        return max(f, 0.0) if clip else f

    a = -force(d, v) / m
    while True:
        v_half = v + 0.5 * dt * a
        d += dt * v_half
        if d <= 0.0:
            return -v_half / v0
        a = -force(d, v_half) / m
        v = v_half + 0.5 * dt * a


def hertz_restitution(c, R, m, v0=0.1, steps=4000):
    """Head-on collision with the LAMMPS hertz/material normal law and tsuji
    damping, F = (4/3) E* a d + alpha sqrt(m (4/3) E* a) v (a = sqrt(R d)),
    clipped at 0 (limit_damping): velocity Verlet on the relative
    coordinate, about `steps` steps per contact; returns e = v_out / v_in."""
    e_star = c["E"] / (2 * (1 - c["nu"] ** 2))
    alpha = tsuji_alpha(c["tsuji_e"])  # what LAMMPS computes from the e' it is given
    t_c = 2.87 * (m * m / (R * e_star * e_star * v0)) ** 0.2
    dt = t_c / steps

    def force(d, v):
        k = 4.0 / 3.0 * e_star * math.sqrt(R * d)
        return max(k * d + alpha * math.sqrt(m * k) * v, 0.0)

    d, v = 0.0, v0
    a = 0.0
    while True:
        v_half = v + 0.5 * dt * a
        d += dt * v_half
        if d <= 0.0:
            return -v_half / v0
        a = -force(d, v_half) / m
        v = v_half + 0.5 * dt * a


def check_restitution(kn=1e5, kt=5e4, eta_n=0.2, eta_t=0.2, mu=0.5, masses=(1e-5, 3e-4)):
    """Restitution of the LAMMPS law with the derived constants, against
    capdem's: e = exp(-pi eta / sqrt(1 - eta^2)) unclipped; clipped, the
    exact value of docs/contacts.md (0.572 at eta 0.2)."""
    c = lammps_constants(kn, kt, eta_n, eta_t, mu)
    expected = math.exp(-math.pi * eta_n / math.sqrt(1 - eta_n ** 2))
    rows = []
    for m in masses:
        alpha = tsuji_alpha(c["tsuji_e"])  # what LAMMPS computes from the e' it is given
        rows.append({"m": m, "e_unclipped": restitution(c["kn"], alpha, m, False),
                     "e_clipped": restitution(c["kn"], alpha, m, True), "e_formula": expected})
    return c, rows


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--kn", type=float, default=1e5)
    ap.add_argument("--kt", type=float, default=5e4)
    ap.add_argument("--eta-n", type=float, default=0.2)
    ap.add_argument("--eta-t", type=float, default=None)
    ap.add_argument("--mu", type=float, default=0.5)
    ap.add_argument("--check", action="store_true", help="integrate collisions; exit 1 unless e matches capdem's")
    a = ap.parse_args()
    eta_t = a.eta_n if a.eta_t is None else a.eta_t
    c = lammps_constants(a.kn, a.kt, a.eta_n, eta_t, a.mu)
    c["pair_coeff"] = pair_coeff_args(c)
    print(json.dumps(c))
    if a.check:
        _, rows = check_restitution(a.kn, a.kt, a.eta_n, eta_t, a.mu)
        ok = True
        for r in rows:
            print(json.dumps(r))
            ok &= abs(r["e_unclipped"] - r["e_formula"]) < 0.01 * r["e_formula"]
            ok &= abs(tsuji_alpha(c["tsuji_e"]) - 2 * a.eta_n) < 1e-12
            if abs(a.eta_n - 0.2) < 1e-12:  # docs/contacts.md: clipped law e = 0.572
                ok &= abs(r["e_clipped"] - 0.572) < 0.005
        # Hertz-Mindlin: capdem's restitution is the clipped linear law's
        # (docs/contacts.md); the LAMMPS constants must give it too, for any
        # mass, radius or modulus.
        for E, R, m in ((1e7, 1.25e-3, 3e-5), (7e10, 5e-4, 1e-6)):
            h = hertz_constants(E, 0.3, a.eta_n, eta_t, a.mu)
            r = {"law": "hertz_mindlin", "E": E, "R": R, "m": m, "e_clipped": hertz_restitution(h, R, m),
                 "pair_coeff": pair_coeff_args(h)}
            print(json.dumps(r))
            ok &= abs(tsuji_alpha(h["tsuji_e"]) - math.sqrt(5.0) * a.eta_n) < 1e-12
            if abs(a.eta_n - 0.2) < 1e-12:  # docs/contacts.md: e = 0.57174 at eta 0.2
                ok &= abs(r["e_clipped"] - 0.57174) < 1e-4  # Verlet with 4000 steps: ~1e-5
        print("restitution check:", "ok" if ok else "FAILED")
        return 0 if ok else 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
