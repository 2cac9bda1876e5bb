#!/usr/bin/env bash
# MPI runs bit for bit the serial program's (docs/mpi.md, "Determinism"):
# a settling hexapod pile (3D, a cylinder: sub-domains across x and z) and
# a 2D cross deposit (a box: sub-domains across x) on 1 process and on 2,
# 3 and 4 ranks; h5diff finds every snapshot (particles, primitives,
# contacts with their history, wall contacts), every observable and the
# echoed config equal; sub-domains stacked along gravity, one of which
# the settling pile leaves empty; crosses dragged across 4 sub-domains by
# a sliding floor.  The runs must have contacts at the last snapshot,
# particles that changed owner, and ghosts, or the comparison proves
# little.
# usage: test_mpi_bitwise.sh CAPDEM SOURCE_DIR
set -u
capdem=$1 src=$2
. "$src/tests/mpi/mpi_common.sh"

for case in hexapod_pile crosses_2d; do
  cfg="$src/tests/mpi/$case.yaml"
  if ! "$capdem" run "$cfg" --output serial.h5 --quiet 2> err; then bad "$case: the serial run failed"; continue; fi
  pairs=$(last_rows serial.h5 contacts) walls=$(last_rows serial.h5 wall_contacts)
  if [ "${pairs:-0}" -ge 10 ] && [ "${walls:-0}" -ge 10 ]; then ok
  else bad "$case: $pairs contacts and $walls wall contacts at the last snapshot, expected at least 10 of each"; fi
  for np in 2 3 4; do
    if ! mpi "$np" run "$cfg" --output "mpi$np.h5" --quiet 2> err; then bad "$case: $np ranks: the run failed"; continue; fi
    if same serial.h5 "mpi$np.h5"; then ok
    else bad "$case: $np ranks: the run file differs from the serial one"; head -20 diff.txt; fi
    # "capdem: MPI: R ranks, M migrations; per rank now a..b owned particles and c..d ghosts"
    line=$(grep 'capdem: MPI:' err)
    migrations=$(sed -n 's/.* \([0-9]*\) migrations.*/\1/p' <<< "$line")
    ghosts=$(sed -n 's/.*and [0-9]*\.\.\([0-9]*\) ghosts.*/\1/p' <<< "$line")
    if [ "${migrations:-0}" -ge 10 ] && [ "${ghosts:-0}" -ge 1 ]; then ok
    else bad "$case: $np ranks: expected migrations and ghosts, got: $line"; fi
  done
  rm -f ./*.h5
done
# Sub-domains stacked along gravity (mpi.grid [1, 3, 1]): the top one
# empties as the crosses settle; a rank without particles builds no list
# and has no say in the rebuild, and the run still has the serial bits.
{ printf 'mpi:\n  grid: [1, 3, 1]\n'; cat "$src/tests/mpi/crosses_2d.yaml"; } > stacked.yaml
rm -f ./*.h5
"$capdem" run stacked.yaml --output serial.h5 --quiet 2> err || bad "stacked: the serial run failed"
if mpi 3 run stacked.yaml --output mpi3.h5 --quiet 2> err && same serial.h5 mpi3.h5; then ok
else bad "stacked: 3 ranks: failed or differs from the serial run"; head -20 diff.txt; fi
if grep -q 'per rank now 0\.\.' err; then ok; else bad "stacked: expected a rank without particles: $(grep 'MPI:' err)"; fi
# Migration under shear: a sliding floor drags 2D crosses across 4
# sub-domains; at least 5 of them end in another sub-domain (x slabs of
# the start box) than they began in, with their contacts.
rm -f ./*.h5
"$capdem" run "$src/tests/mpi/crosses_shear.yaml" --output serial.h5 --quiet 2> err || bad "shear: the serial run failed"
if mpi 4 run "$src/tests/mpi/crosses_shear.yaml" --output mpi4.h5 --quiet 2> err && same serial.h5 mpi4.h5; then ok
else bad "shear: 4 ranks: failed or differs from the serial run"; head -20 diff.txt; fi
moved=$(/usr/bin/python3 -c "
import h5py, numpy as np
x = h5py.File('serial.h5', 'r')['/particles/all/position/value'][:, :, 0]
lo, hi = x[0].min(), x[0].max()
slab = np.clip(np.floor((x - lo) / ((hi - lo) / 4)), 0, 3)
print(int((slab[-1] != slab[0]).sum()))")
if [ "${moved:-0}" -ge 5 ]; then ok; else bad "shear: $moved particles changed sub-domain, expected at least 5"; fi
echo "test_mpi_bitwise: $pass passed, $fails failed"
[ $fails -eq 0 ]
