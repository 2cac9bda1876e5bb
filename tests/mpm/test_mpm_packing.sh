#!/usr/bin/env bash
# The mpm set-up packing end to end (docs/mpm.md): the CI deposit of 12
# disks by the DEM solver (configs/mpm/ci/deposit_disks.yaml), its run file
# read through mpm.packing, and the elastic CI compaction
# (configs/mpm/ci/packing_elastic.yaml) run part of the way: the packing
# fraction rises, the applied stress is positive, the strain is ln(h_i/h)
# of the walls' positions, particles touch (Z > 0), no two interpenetrate
# by a cell or more; a resume from the run file gives the same bits as the
# run without a stop; a bad packing file or key is refused with exit 2.
# usage: test_mpm_packing.sh CAPDEM SOURCE_DIR
set -u
capdem=$1 src=$2
. "$src/tests/cli/common.sh"
cfg=$src/configs/mpm/ci

. "$src/tests/mpm/mpm_series.sh"

"$capdem" run "$cfg/deposit_disks.yaml" --quiet > out 2> err && [ -f deposit_disks_ci.h5 ] && ok \
  || { bad "the DEM deposit did not run"; echo "test_mpm_packing: $pass passed, $fails failed"; exit 1; }

# 900 of the preset's 1,800 steps: ln(h_i/h) ~ 0.1
if "$capdem" run "$cfg/packing_elastic.yaml" --steps 900 --output run.h5 > out 2> err; then ok; else bad "packing run: exit status $?"; fi
grep -q "phi .* sigma .* Z " err && ok || bad "packing run: no progress line with phi, sigma and Z"
h=$(sed -n 's/.*(h = \([0-9.e+-]*\) m).*/\1/p' err)
series packing_fraction run.h5 > phi
series stress run.h5 > sigma
series strain run.h5 > eps
series coordination run.h5 > z
series penetration run.h5 > pen
h5dump -w 0 -A 0 -m %.17g -d /mpm/series/wall_position run.h5 | sed -n 's/^ *([0-9,]*): *//p' | tr -d ' ' | paste -d, - - - - > walls
rows=$(wc -l < phi)
[ "$rows" = 46 ] && ok || bad "packing run: $rows series rows, expected 46 (steps 0, 20, ..., 900)"
# phi rises: overall by the box's shrinking (a third of it at least), and row to row within 0.002: the
# points' own volume rings with the stress waves of the undamped compression (pressure ringing of
# 0.1 MPa against a bulk modulus of 34 MPa, 0.3 % of the solid area)
awk 'NR == 1 { first = $1 } NR > 1 && $1 < prev - 0.002 { print "dip at row " NR ": " prev " -> " $1; bad = 1 }
     { prev = $1 } END { if (prev < first + 0.03) { print "phi " first " -> " prev; bad = 1 } exit bad }' phi > msg \
  && ok || bad "packing fraction does not rise: $(cat msg)"
awk 'NR > 1 && !($1 > 0) { print "row " NR ": " $1; bad = 1 } END { exit bad }' sigma > msg && ok \
  || bad "applied stress not positive after step 0: $(head -3 msg)"
awk 'NR > 1 && !($1 > 0) { print "row " NR ": " $1; bad = 1 } END { exit bad }' z > msg && ok \
  || bad "no contact (Z = 0) after step 0: $(head -3 msg)"
awk -v h="$h" '$1 >= h { print "row " NR ": " $1 " m, h = " h " m"; bad = 1 } END { exit bad }' pen > msg && ok \
  || bad "two particles overlap by a cell or more: $(head -3 msg)"
# the strain is ln(h_i / h) of walls 0 (bottom) and 1 (top): wall_position rows are x0,y0,x1,y1,...
paste -d, walls eps | awk -F, 'NR == 1 { h0 = $4 - $2 }
     { e = log(h0 / ($4 - $2)); if (e - $9 > 1e-12 || $9 - e > 1e-12) { print "row " NR ": " $9 " vs " e; bad = 1 } }
     END { exit bad }' > msg && ok || bad "strain is not ln(h_i/h): $(head -3 msg)"
for d in packing_fraction:1 stress:Pa strain:1 coordination:1 penetration:m; do
  name=${d%%:*} unit=${d#*:}
  h5dump -a "/mpm/series/$name/unit" run.h5 2> /dev/null | grep -qF "\"$unit\"" && ok || bad "/mpm/series/$name has no unit $unit"
done

# capdem analyze (docs/mpm.md "Analysis"): Phi, sigma, strain and Z of the series' last row; an elastic
# material has no plastic point; the disks' kappa <d> is at least 2 (a convex outline's largest turning
# over an arc is at least its mean, 2 pi / perimeter); the report goes into the run file; the DEM
# deposit is refused for measure mpm
cp run.h5 an.h5
if "$capdem" analyze an.h5 > out 2> err; then ok; else bad "analyze of the packing run: exit status $?"; fi
val() { awk -v k="$1" '$1 == k { print $2; exit }' out; }
awk -v a="$(val phi)" -v b="$(tail -1 phi)" 'BEGIN { exit !(a != "" && (a - b)^2 < 1e-10) }' && ok \
  || bad "analyze: phi $(val phi), the series ends at $(tail -1 phi)"
awk -v a="$(val z)" -v b="$(tail -1 z)" 'BEGIN { exit !(a != "" && (a - b)^2 < 1e-10) }' && ok \
  || bad "analyze: z $(val z), the series ends at $(tail -1 z)"
[ "$(val f_p)" = 0 ] && ok || bad "analyze: f_p = $(val f_p) for an elastic material, expected 0"
awk -v k="$(val kappa_d)" 'BEGIN { exit !(k >= 2 && k < 20) }' && ok || bad "analyze: kappa_d = $(val kappa_d)"
h5ls -r an.h5 | grep -q "^/analysis/snapshot_[0-9]*/mpm/snapshots *Dataset" && ok \
  || bad "analyze wrote no /analysis/snapshot_*/mpm/snapshots into the run file"
# eq. (5) with Phi_c given: a positive modulus M_eff inside its interval
"$capdem" analyze an.h5 --no-write --phi-c 0.7 > out 2> err && awk '$1 == "m_eff" { m = $2 } $1 == "m_eff_lo" { lo = $2 }
    $1 == "m_eff_hi" { hi = $2 } END { exit !(m > 0 && lo < m && m < hi) }' out && ok || bad "analyze --phi-c 0.7: no M_eff"
# eqs. (6)-(9) on an elastic material: the paper's curve against the series rows beyond Phi_c (the fit of
# f_E, f_G, c1 needs more of the compaction than these 900 steps, Phi 0.70-0.75: it says so; the synthetic
# runs of test_mpm_analysis check the fit)
"$capdem" analyze an.h5 --no-write --phi-c 0.7 > out 2> err && awk '/^\[mpm_eq6\]/ { g = 1 } /^\[mpm_eq10\]/ { g = 0 }
    g && $1 == "rms_residual_paper" { p = $2 } g && $1 == "curve" { c = 1 } g && ($1 == "f_e" || $1 == "fit") { f = 1 }
    END { exit !(p > 0 && c && f) }' out && ok || bad "analyze --phi-c 0.7: no eq. (6) group: $(sed -n '/mpm_eq6/,$p' out)"
"$capdem" analyze an.h5 --no-write --elastic-model 1.2,0.2 > out 2> err; rc=$?
[ $rc = 2 ] && grep -q -- "--elastic-model" err && ok || bad "analyze --elastic-model 1.2,0.2: exit status $rc, expected 2"
"$capdem" analyze an.h5 --no-write --phi-c 1.5 > out 2> err; rc=$?
[ $rc = 2 ] && grep -q -- "--phi-c" err && ok || bad "analyze --phi-c 1.5: exit status $rc, expected 2"
"$capdem" analyze deposit_disks_ci.h5 --measures mpm > out 2> err; rc=$?
[ $rc = 2 ] && grep -q "not a run file of solver mpm" err && ok || bad "analyze --measures mpm of a DEM run: exit $rc"

# resume, bit for bit: 400 steps, then on to 900, against the run above
"$capdem" run "$cfg/packing_elastic.yaml" --steps 400 --output part.h5 --quiet > out 2> err &&
  "$capdem" run "$cfg/packing_elastic.yaml" --steps 900 --resume part.h5 --quiet > out 2> err && ok \
  || bad "resume: exit status $?"
grep -q "resuming part.h5 at step 400" err && ok || bad "resume: no 'resuming part.h5 at step 400' line"
for g in snapshots series; do
  h5diff run.h5 part.h5 "/mpm/$g" > diff 2>&1 && ok || bad "resume: /mpm/$g differs from the run without a stop: $(head -5 diff)"
done
h5dump -a /parameters/resumes/0/step part.h5 2> /dev/null | grep -q "(0): 400" && ok \
  || bad "resume: no /parameters/resumes/0 with step 400"

# bad input: exit 2 naming the file and the key, nothing written
. "$src/tests/mpm/expect_refusal.sh"
expect_refusal no_packing_file 'mpm\.packing = nothing\.h5: cannot open' <<< 'solver: mpm
run: {dt: 5.0e-7, steps: 10}
mpm: {setup: packing, packing: nothing.h5}'
expect_refusal packing_missing 'mpm\.packing: missing' <<< 'solver: mpm
mpm: {setup: packing}'
expect_refusal diameter_in_packing 'mpm\.diameter = 0\.06: does not apply' <<< 'solver: mpm
mpm: {setup: packing, packing: deposit_disks_ci.h5, diameter: 0.06}'
expect_refusal packing_of_mpm_file 'mpm\.packing = run\.h5: no committed snapshot of particle positions' <<< 'solver: mpm
run: {dt: 5.0e-7, steps: 10}
mpm: {setup: packing, packing: run.h5}'
# a resume of a packing run whose packing file changed since is refused: the points differ
cp part.h5 part2.h5
"$capdem" run "$src/configs/mpm/ci/deposit_disks.yaml" --overwrite --steps 30000 --quiet > out 2> err
"$capdem" run "$cfg/packing_elastic.yaml" --steps 1000 --resume part2.h5 --quiet > out 2> err; rc=$?
[ $rc = 2 ] && grep -q "differ from those the config sets up now" err && ok \
  || bad "resume with another packing: exit status $rc, expected 2 naming the change"

echo "test_mpm_packing: $pass passed, $fails failed"
[ $fails = 0 ]
