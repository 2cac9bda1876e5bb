#!/usr/bin/env bash
# bench/lammps/lammps_law.py: the LAMMPS constants derived from capdem's law
# (kn/2, kt/2, Tsuji damping prefactor 2 eta_n, tangential ratio
# (eta_t/eta_n) sqrt(kt/kn)) reproduce capdem's restitution: 0.527 unclipped
# (the formula), 0.572 clipped (docs/contacts.md) for light and heavy pairs;
# so do those of the Hertz-Mindlin law (hertz/material, tsuji alpha =
# sqrt(5) eta_n, tangential mindlin NULL) for a soft and a stiff pair.
# No LAMMPS needed: the LAMMPS force law is integrated in Python.
#   test_lammps_law.sh CAPDEM_BENCH SOURCE_DIR
set -euo pipefail
/usr/bin/python3 "$2/bench/lammps/lammps_law.py" --check
/usr/bin/python3 - "$2/bench/lammps" <<'PY'
import sys
sys.path.insert(0, sys.argv[1])
import lammps_law as L
c = L.lammps_constants(kn=2e5, kt=1e5, eta_n=0.3, eta_t=0.1, mu=0.4)
assert c["kn"] == 1e5 and c["kt"] == 5e4 and c["mu"] == 0.4
assert abs(L.tsuji_alpha(c["tsuji_e"]) - 0.6) < 1e-12
assert abs(c["xgammat"] - (0.1 / 0.3) * 0.5 ** 0.5) < 1e-15
assert "damping tsuji limit_damping" in L.pair_coeff_args(c)
print("ok: constants for a non-default material")
# Hertz-Mindlin: alpha = sqrt(5) eta_n, x = (eta_t/eta_n) 2 sqrt(G*/E*)
h = L.hertz_constants(E=7e10, nu=0.22, eta_n=0.3, eta_t=0.1, mu=0.4)
assert abs(L.tsuji_alpha(h["tsuji_e"]) - 5 ** 0.5 * 0.3) < 1e-12
gs, es = 7e10 / (4 * 1.78 * 1.22), 7e10 / (2 * (1 - 0.22 ** 2))
assert abs(h["xgammat"] - (0.1 / 0.3) * 2 * (gs / es) ** 0.5) < 1e-15
assert L.pair_coeff_args(h).startswith("hertz/material 7e+10 ")
assert "tangential mindlin NULL" in L.pair_coeff_args(h) and "damping tsuji limit_damping" in L.pair_coeff_args(h)
print("ok: Hertz-Mindlin constants")
PY
