#!/usr/bin/env bash
# solver: mpm from the command line (docs/mpm.md): bad configs refused with
# exit status 2 naming the file, the key and the value, nothing written; a
# short run of the CI disk writes the documented datasets with their units;
# the run's own numbers (the walls' forces) are those of the time series;
# a resume gives the same bits.
# usage: test_mpm_cli.sh CAPDEM SOURCE_DIR
set -u
capdem=$1 src=$2
. "$src/tests/cli/common.sh"

. "$src/tests/mpm/expect_refusal.sh"
good='solver: mpm
run: {dt: 2.0e-6, steps: 100, snapshot_every: 50, thermo_every: 10}
mpm: {cells_per_diameter: 8, wall_speed: 10, material: {model: von_mises, yield_stress: 4.0e5, hardening: 1.0e6}}'

expect_refusal bad_solver 'solver = mps.*one of dem, mpm' <<< "solver: mps"
expect_refusal negative_E 'mpm\.material\.young_modulus = -1e7.*> 0' <<< "$(printf '%s\n' "$good" | sed 's/model: von_mises/model: von_mises, young_modulus: -1e7/')"
expect_refusal poisson_half 'mpm\.material\.poisson_ratio = 0\.5.*in \(-1, 0\.5\)' <<< "$(printf '%s\n' "$good" | sed 's/model: von_mises/model: von_mises, poisson_ratio: 0.5/')"
expect_refusal no_yield 'mpm\.material\.yield_stress: missing.*von_mises' <<< 'solver: mpm
mpm: {material: {model: von_mises}}'
expect_refusal hardening_elastic 'mpm\.material\.hardening = 1e6: does not apply to .*model = elastic' <<< 'solver: mpm
mpm: {material: {hardening: 1e6}}'
expect_refusal unknown_mpm_key 'mpm\.cell_size' <<< 'solver: mpm
mpm: {cell_size: 0.001}'
expect_refusal dem_section_in_mpm 'material = .*does not apply to solver = mpm' <<< 'solver: mpm
material: {kn: 1e5}'
expect_refusal mpm_section_in_dem 'mpm = .*does not apply to solver = dem' <<< 'particles: [{shape: sphere, diameter: 0.005, count: 8}]
mpm: {diameter: 0.06}'
expect_refusal dt_unstable 'run\.dt = 0\.001: above the explicit step.s stability limit' <<< 'solver: mpm
run: {dt: 1.0e-3, steps: 10}'
expect_refusal cells_few 'mpm\.cells_per_diameter = 2.*in \[4, 2000\]' <<< 'solver: mpm
mpm: {cells_per_diameter: 2}'

# a good run: exit 0, progress on stderr, the layout of docs/mpm.md
printf '%s\n' "$good" > good.yaml
if "$capdem" run good.yaml --output good.h5 > out 2> err; then ok; else bad "good run: exit status $?"; fi
grep -q "material points" err && grep -q "step 100/100" err && ok || bad "good run: no start line or progress on stderr"
[ "$(snapshots good.h5)" = 3 ] && ok || bad "good run: $(snapshots good.h5) snapshots, expected 3 (steps 0, 50, 100)"
for d in snapshots/position:m snapshots/volume:m^3/m snapshots/stress:Pa snapshots/plastic_strain:1 \
         snapshots/wall_force:N/m series/wall_force:N/m series/time:s points/particle:; do
  name=${d%%:*} unit=${d#*:}
  if ! h5dump -H -d "/mpm/$name" good.h5 > /dev/null 2>&1; then bad "good run: no /mpm/$name"; continue; fi
  if [ -n "$unit" ] && ! h5dump -a "/mpm/$name/unit" good.h5 2> /dev/null | grep -qF "\"$unit\""; then
    bad "good run: /mpm/$name has no unit $unit"; continue; fi
  ok
done
h5dump -H -d /mpm/snapshots/stress good.h5 | grep -q "( 3, [0-9]*, 4 )" && ok || bad "good run: stress is not (3, points, 4)"
# the plastic branch ran, and the top wall pushes down on the disk: its force on the wall is up (> 0)
n=$(h5dump -H -d /mpm/points/particle good.h5 | sed -n 's/.*SIMPLE { ( \([0-9]*\) ).*/\1/p')
h5dump -w 0 -d /mpm/snapshots/plastic_strain -s "2,0" -c "1,$n" good.h5 | sed -n 's/^ *([0-9,]*): *//p' | tr ',' '\n' |
  awk '$1 > m { m = $1 } END { exit !(m > 1e-4) }' && ok || bad "good run: no plastic strain > 1e-4 at step 100"
fy=$(h5dump -d /mpm/snapshots/wall_force -s "2,1,1" -c "1,1,1" good.h5 | sed -n 's/^ *(2,1,1): *//p')
awk -v f="$fy" 'BEGIN { exit !(f > 0) }' && ok || bad "good run: top wall force '$fy' N/m, expected > 0"
# an existing output is refused without --overwrite, replaced with it
"$capdem" run good.yaml --output good.h5 --quiet > out 2> err; rc=$?
[ $rc = 2 ] && ok || bad "existing output: exit status $rc, expected 2"
"$capdem" run good.yaml --output good.h5 --overwrite --quiet > out 2> err && [ "$(snapshots good.h5)" = 3 ] && ok \
  || bad "--overwrite: not replaced"
# resume (the packing's in test_mpm_packing): 50 steps, then on to 100, the same bits as good.h5
"$capdem" run good.yaml --output half.h5 --steps 50 --quiet > out 2> err &&
  "$capdem" run good.yaml --resume half.h5 --quiet > out 2> err && h5diff good.h5 half.h5 /mpm > out 2>&1 && ok \
  || bad "--resume: not the same bits as the run without a stop"
# a resume asked to go back is refused
"$capdem" run good.yaml --resume half.h5 --steps 60 --quiet > out 2> err; rc=$?
[ $rc = 2 ] && grep -q "at step 100 already" err && ok || bad "--resume --steps 60: exit status $rc, expected 2"

# analyze of a diametral run (docs/mpm.md "Analysis"): the strain (D - gap)/D and F/D, the mean of the two
# walls' forces over D, of the series' last row (wall_position and wall_force rows: x0,y0,x1,y1), to the
# 6 digits of the text report
if "$capdem" analyze good.h5 --no-write > out 2> err; then ok; else bad "analyze of a diametral run: exit status $?"; fi
last_row() { h5dump -w 0 -A 0 -m %.17g -d "/mpm/series/$1" good.h5 | sed -n 's/^ *([0-9,]*): *//p' | tr -d ' ' |
  tr ',' '\n' | sed '/^$/d' | paste -d, - - - - | sed -n "\$p"; }
first_row() { h5dump -w 0 -A 0 -m %.17g -d /mpm/series/wall_position good.h5 | sed -n 's/^ *([0-9,]*): *//p' |
  tr -d ' ' | tr ',' '\n' | sed '/^$/d' | paste -d, - - - - | head -1; }
awk -F, -v p0="$(first_row)" -v p="$(last_row wall_position)" -v f="$(last_row wall_force)" \
  -v e="$(awk '$1 == "strain" { print $2 }' out)" -v s="$(awk '$1 == "f_over_d" { print $2 }' out)" 'BEGIN {
    split(p0, a, ","); split(p, b, ","); split(f, c, ","); D = a[4] - a[2]
    es = (D - (b[4] - b[2])) / D; fs = (-c[2] + c[4]) / 2 / D
    exit !(D > 0 && e != "" && s > 0 && ((e - es) / es)^2 < 1e-11 && ((s - fs) / fs)^2 < 1e-11) }' && ok \
  || bad "analyze of a diametral run: strain/F/D not those of the series: $(cat out)"
"$capdem" analyze good.h5 --measures forces > out 2> err; rc=$?
[ $rc = 2 ] && grep -q "its only measure is mpm" err && ok || bad "analyze --measures forces of an mpm run: exit $rc"

echo "test_mpm_cli: $pass passed, $fails failed"
[ $fails = 0 ]
