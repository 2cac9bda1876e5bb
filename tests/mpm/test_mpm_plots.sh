#!/usr/bin/env bash
# host/plot_run.py draws the paper's Figs. 1, 3, 4 and 5 from capdem mpm
# runs (docs/mpm.md "Figures"): a diametral run (the small plastic disk of
# test_mpm_cli, 100 steps) and the CI packing, elastic and H = 1 MPa, to
# step 900 (ln(h_i/h) ~ 0.1), each analysed by `capdem analyze --phi-c 0.7`;
# the four PNGs exist and are not trivial, and the numbers drawn (the JSON
# beside each PNG) are those of the analyses (`capdem analyze --json`), to
# 1e-14 relative: copied, to the 15 digits of analyze's JSON, or computed
# (eq. (5)'s line offset + M_eff x, Z - Z_c) to round-off.  Needs
# /usr/bin/python3 (or $PYTHON), the Python `capdem render` runs, with
# h5py, numpy and matplotlib (the README's python3-h5py, python3-matplotlib):
# without them it fails, as every test of a dependency the README lists.
# usage: test_mpm_plots.sh CAPDEM SOURCE_DIR
set -u
capdem=$1 src=$2
. "$src/tests/cli/common.sh"
cfg=$src/configs/mpm/ci
py=${PYTHON:-/usr/bin/python3}

"$py" -c 'import h5py, numpy, matplotlib' 2> err && ok \
  || { bad "$py cannot import h5py, numpy and matplotlib (apt-get install python3-h5py python3-matplotlib; or set PYTHON)"; exit 1; }

printf '%s\n' 'solver: mpm' 'run: {dt: 2.0e-6, steps: 100, snapshot_every: 50, thermo_every: 10}' \
  'mpm: {cells_per_diameter: 8, wall_speed: 10, material: {model: von_mises, yield_stress: 4.0e5, hardening: 1.0e6}}' > disk.yaml
"$capdem" run disk.yaml --output disk.h5 --quiet > out 2> err && ok || bad "diametral run: exit status $?"
"$capdem" run "$cfg/deposit_disks.yaml" --quiet > out 2> err && [ -f deposit_disks_ci.h5 ] && ok || bad "the DEM deposit did not run"
for m in elastic plastic_h1; do
  "$capdem" run "$cfg/packing_$m.yaml" --steps 900 --output "$m.h5" --quiet > out 2> err && ok || bad "packing $m: exit status $?"
done
for f in disk elastic plastic_h1; do
  "$capdem" analyze "$f.h5" --phi-c 0.7 > out 2> err && ok || bad "analyze $f.h5: exit status $?"
  "$capdem" analyze "$f.h5" --phi-c 0.7 --no-write --json > "$f.json" 2> err && ok || bad "analyze --json $f.h5: exit status $?"
done

if "$py" "$src/host/plot_run.py" disk.h5 elastic.h5 plastic_h1.h5 -o plots > out 2> err; then ok; else bad "plot_run.py: exit status $?"; fi
for n in 1 3 4 5; do
  [ "$(stat -c %s "plots/fig$n.png" 2> /dev/null || echo 0)" -gt 10000 ] && [ -s "plots/fig$n.json" ] && ok \
    || bad "plots/fig$n.png missing or under 10 kB, or no fig$n.json"
done

# the numbers drawn against the analyses'
"$py" - > msg 2>&1 << 'EOF' && ok || bad "the figures' numbers are not those of capdem analyze: $(cat msg)"
import json, math, sys
def load(p):
    with open(p) as f:
        return json.load(f)
def col(rep, group, table, name):
    c = rep[group]["curves"][table]
    k = c["columns"].index(name)
    return [row[k] for row in c["data"]]
def same(a, b, what, tol=1e-14, allow_empty=False):
    a = [math.nan if x is None else x for x in a]
    b = [math.nan if x is None else x for x in b]
    if len(a) != len(b) or (len(a) == 0 and not allow_empty):
        sys.exit(f"{what}: {len(a)} values drawn, {len(b)} analysed")
    for x, y in zip(a, b):
        if not (x == y or (math.isnan(x) and math.isnan(y)) or abs(x - y) <= tol * abs(y)):
            sys.exit(f"{what}: drawn {x}, analysed {y}")
rep = {f: load(f + ".json") for f in ("disk", "elastic", "plastic_h1")}
label = {"disk": "H = 1 MPa", "elastic": "elastic", "plastic_h1": "H = 1 MPa"}
fig = {n: load(f"plots/fig{n}.json") for n in (1, 3, 4, 5)}
same(fig[1]["H = 1 MPa"]["f_over_d"], col(rep["disk"], "mpm_disk", "curve", "f_over_d"), "fig1 F/D")
same(fig[1]["H = 1 MPa"]["strain"], col(rep["disk"], "mpm_disk", "curve", "strain"), "fig1 eps_yy")
for f in ("elastic", "plastic_h1"):
    r, l = rep[f], label[f]
    same(fig[3][l]["phi"], col(r, "mpm", "series", "phi"), f"fig3 {f} Phi")
    same(fig[3][l]["sigma"], col(r, "mpm", "series", "sigma"), f"fig3 {f} sigma")
    same(fig[3][l]["kappa_d"], col(r, "mpm", "snapshots", "kappa_d"), f"fig3 {f} kappa <d>")
    same(fig[3][l]["snapshot_sigma"], col(r, "mpm", "snapshots", "sigma"), f"fig3 {f} snapshots' sigma")
    model = "mpm_eq6" if f == "elastic" else "mpm_eq10"
    if fig[4][l]["model"] != model:
        sys.exit(f"fig4 {f}: model {fig[4][l]['model']}, expected {model}")
    for c in ("phi", "sigma", "sigma_fit", "sigma_paper"):
        same(fig[4][l][c], col(r, model, "curve", c), f"fig4 {f} {c}")
    g5 = r["mpm_eq5"]
    x = fig[4][l]["excess_strain"]
    same(fig[4][l]["eq5_line"], [g5["offset"] + g5["m_eff"] * v for v in x], f"fig4 {f} eq. (5)", 1e-12)
    g17 = r["mpm_eq17"]
    phi, z = col(r, "mpm", "series", "phi"), col(r, "mpm", "series", "z")
    keep = [(p - g17["phi_c"], q - g17["z_c"]) for p, q in zip(phi, z) if p - g17["phi_c"] > 0 and q - g17["z_c"] > 0]
    # (the short CI runs' Z need not rise: the H = 1 MPa one fits a negative amplitude, Z - Z_c < 0)
    same(fig[5][l]["excess_phi"], [a for a, _ in keep], f"fig5 {f} Phi - Phi_c", 1e-12, True)
    same(fig[5][l]["excess_z"], [b for _, b in keep], f"fig5 {f} Z - Z_c", 1e-12, True)
    drawn5 = drawn5 + len(keep) if f != "elastic" else len(keep)
if drawn5 == 0:
    sys.exit("fig5: no point drawn")
print("the figures' numbers are those of capdem analyze")
EOF
cat msg

echo "test_mpm_plots: $pass passed, $fails failed"
[ $fails = 0 ]
