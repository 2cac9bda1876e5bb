#!/usr/bin/env bash
# `capdem render` of mpm run files (docs/visualization.md, "Material point
# runs"): the CI packing (H = 1 MPa, 900 steps) at its last snapshot
# coloured by plastic strain and by particle, and at snapshot 0 (nothing
# yielded), and a diametral run (2 walls); tests/mpm/check_mpm_render.py
# reads the pixel at every material point back and compares it with the
# point's colour from the run file, and finds each wall's line.  Checked to
# fail: the same picture against another snapshot's numbers, and a run file
# whose most plastic particles (a quarter of the plastic points) were planted
# elastic.  Refused with exit 2: --mode forces,
# --color height on an mpm file, --color plastic on a DEM file, a snapshot
# the file does not hold.  Needs /usr/bin/python3 with h5py, numpy and
# matplotlib (the README's packages), as `capdem render` does.
# usage: test_mpm_render.sh CAPDEM SOURCE_DIR
set -u
capdem=$1 src=$2
. "$src/tests/cli/common.sh"
check() { /usr/bin/python3 "$src/tests/mpm/check_mpm_render.py" "$@" > msg 2>&1; }
png_width() { /usr/bin/python3 -c "from PIL import Image; print(Image.open('$1').size[0])"; }

"$capdem" run "$src/configs/mpm/ci/deposit_disks.yaml" --quiet > out 2> err && ok || bad "the CI deposit did not run"
"$capdem" run "$src/configs/mpm/ci/packing_plastic_h1.yaml" --steps 900 --output pack.h5 --quiet > out 2> err && ok \
  || bad "CI packing: exit status $?"
last=$(( $(snapshots pack.h5) - 1 ))

"$capdem" render pack.h5 --color plastic -o plastic.png > out 2> err && check plastic.png pack.h5 "$last" plastic && ok \
  || bad "plastic strain at the last snapshot: $(cat out msg)"
grep -q "plastic points [0-9]*/[1-9]" msg && ok || bad "the CI packing's last snapshot has no plastic point: $(cat msg)"
# the size follows --width and --dpi: the axes, labels and colour bar span 1.0-1.4 widths
w=$(png_width plastic.png)
[ "$w" -ge 770 ] && [ "$w" -le 1078 ] && ok || bad "plastic.png is $w pixels wide for --width 7 --dpi 110"
"$capdem" render pack.h5 --color plastic --width 4 --dpi 60 -o small.png > out 2> err && w=$(png_width small.png) \
  && [ "$w" -ge 240 ] && [ "$w" -le 336 ] && check small.png pack.h5 "$last" plastic && ok \
  || bad "--width 4 --dpi 60: $w pixels wide, $(cat msg)"
"$capdem" render pack.h5 -o particle.png > out 2> err && check particle.png pack.h5 "$last" particle && ok \
  || bad "coloured by particle: $(cat out msg)"
"$capdem" render pack.h5 --snapshot 0 --color plastic -o first.png > out 2> err && check first.png pack.h5 0 plastic && ok \
  || bad "snapshot 0 (nothing yielded): $(cat out msg)"

# the check can fail: a picture against another snapshot's numbers, particles planted elastic
! check plastic.png pack.h5 1 plastic && grep -q "plastic points" msg && ok \
  || bad "the last snapshot's picture passed as snapshot 1's: $(cat msg)"
cp pack.h5 planted.h5
/usr/bin/python3 -c "
import h5py, numpy as np
f = h5py.File('planted.h5', 'r+'); d = f['/mpm/snapshots/plastic_strain']; e = d[$last]
body = f['/mpm/points/particle'][()]; most = np.argsort(-np.bincount(body[e > 0]))
planted = most[:np.searchsorted(np.cumsum(np.bincount(body[e > 0])[most]), 0.25 * (e > 0).sum()) + 1]
e[np.isin(body, planted)] = 0; d[$last] = e"
"$capdem" render planted.h5 --color plastic -o planted.png > out 2> err && ! check planted.png pack.h5 "$last" plastic \
  && grep -q "FAIL plastic points" msg && ok || bad "particles planted elastic passed: $(cat msg)"

printf '%s\n' 'solver: mpm' 'run: {dt: 2.0e-6, steps: 100, snapshot_every: 50, thermo_every: 10}' \
  'mpm: {cells_per_diameter: 8, wall_speed: 10, material: {model: von_mises, yield_stress: 4.0e5, hardening: 1.0e6}}' \
  > disk.yaml
"$capdem" run disk.yaml --output disk.h5 --quiet > out 2> err && ok || bad "diametral run: exit status $?"
"$capdem" render disk.h5 --snapshot 1 -o disk.png > out 2> err && check disk.png disk.h5 1 particle && ok \
  || bad "diametral run coloured by particle: $(cat out msg)"

# refusals: exit 2, the reason named, no picture
refused() { # FILE EXPECTED_TEXT OPTIONS...
  local file=$1 text=$2
  shift 2
  rm -f no.png
  "$capdem" render "$file" "$@" -o no.png > out 2> err
  local rc=$?
  [ $rc = 2 ] && grep -q -- "$text" err && [ ! -e no.png ] && ok || bad "render $file $*: exit status $rc, expected 2 and '$text'"
}
refused pack.h5 "holds no contact network" --mode forces
refused pack.h5 "coloured by particle, plastic or speed" --color height
refused pack.h5 "the file holds snapshots 0..$last" --snapshot 99
refused deposit_disks_ci.h5 "only material point runs" --color plastic
echo "test_mpm_render: $pass passed, $fails failed"
[ $fails = 0 ]
