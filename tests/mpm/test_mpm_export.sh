#!/usr/bin/env bash
# `capdem export` of mpm run files (docs/visualization.md, "Material point
# runs"): a diametral run (2 walls) and the CI packing (4 walls, 12
# particles) stopped at step 50, exported, resumed to step 100 and exported
# again; tests/mpm/check_mpm_export.py checks each .xmf against its run file
# (datasets, shapes, the run's own numbers, walls on their lines and at the
# box's corners, outlines the convex hulls of the points' squares).  A
# second export changes neither file; a planted wrong outline vertex fails
# the check; a run file without a column is refused with exit 2 naming it.
# usage: test_mpm_export.sh CAPDEM SOURCE_DIR
set -u
capdem=$1 src=$2
. "$src/tests/cli/common.sh"
check() { /usr/bin/python3 "$src/tests/mpm/check_mpm_export.py" "$@" > msg 2>&1; }

printf '%s\n' 'solver: mpm' 'run: {dt: 2.0e-6, steps: 100, snapshot_every: 50, thermo_every: 10}' \
  'mpm: {cells_per_diameter: 8, wall_speed: 10, material: {model: von_mises, yield_stress: 4.0e5, hardening: 1.0e6}}' \
  > disk.yaml
"$capdem" run disk.yaml --output disk.h5 --quiet > out 2> err && ok || bad "diametral run: exit status $?"
"$capdem" export disk.h5 > out 2> err && [ -f disk.xmf ] && grep -q "3 snapshots, 208 material points, 2 walls" out && ok \
  || bad "export of the diametral run: exit status $?, $(cat out)"
# well-formed XML: xmllint where installed (libxml2-utils); check_mpm_export.py parses it in any case
if command -v xmllint > /dev/null; then xmllint --noout disk.xmf 2> err && ok || bad "disk.xmf: not well-formed XML"; fi
check disk.xmf disk.h5 && ok || bad "disk.xmf: $(cat msg)"

"$capdem" run "$src/configs/mpm/ci/deposit_disks.yaml" --quiet > out 2> err && ok || bad "the CI deposit did not run"
sed 's/steps: 1800/steps: 100/; s/snapshot_every: 400/snapshot_every: 50/' "$src/configs/mpm/ci/packing_elastic.yaml" \
  > pack.yaml
"$capdem" run pack.yaml --output pack.h5 --steps 50 --quiet > out 2> err && ok || bad "packing run: exit status $?"
"$capdem" export pack.h5 > out 2> err && check pack.xmf pack.h5 box && ok || bad "packing at step 50: $(cat out msg)"
"$capdem" run pack.yaml --resume pack.h5 --quiet > out 2> err && ok || bad "packing resumed: exit status $?"
"$capdem" export pack.h5 > out 2> err && grep -q "3 snapshots" out && check pack.xmf pack.h5 box && ok \
  || bad "packing resumed to step 100: $(cat out msg)"
# a second export of an unchanged file changes neither the run file's size nor the .xmf
size=$(stat -c %s pack.h5)
cp pack.xmf first.xmf
"$capdem" export pack.h5 > out 2> err && [ "$(stat -c %s pack.h5)" = "$size" ] && cmp -s pack.xmf first.xmf && ok \
  || bad "second export: size $size -> $(stat -c %s pack.h5), or the .xmf changed"
# the check can fail: an outline vertex moved by a micrometre
cp pack.h5 planted.h5
sed 's/pack\.h5:/planted.h5:/g' pack.xmf > planted.xmf
/usr/bin/python3 -c "
import h5py; f = h5py.File('planted.h5', 'r+'); d = f['/visualization/snapshots/2/outline_points']; d[3, 0] += 1e-6" \
  && ! check planted.xmf planted.h5 box && grep -q "particle .*outline" msg && ok \
  || bad "a planted wrong outline vertex passed the check: $(cat msg)"
# bad input: a column missing is refused by name (exit 2), nothing written
cp disk.h5 broken.h5
/usr/bin/python3 -c "import h5py; f = h5py.File('broken.h5', 'r+'); del f['/mpm/snapshots/volume']"
"$capdem" export broken.h5 > out 2> err; rc=$?
[ $rc = 2 ] && grep -q "broken.h5: /mpm/snapshots/volume" err && [ ! -e broken.xmf ] && ok \
  || bad "export of a file without /mpm/snapshots/volume: exit status $rc, expected 2 naming it"
echo "test_mpm_export: $pass passed, $fails failed"
[ $fails = 0 ]
