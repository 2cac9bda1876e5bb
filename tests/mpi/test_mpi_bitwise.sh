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
# little.  The same with recursive coordinate bisection.  On 4 slabs the
# ranks talk to their neighbours only and the migrations send only what
# changes; every migration forced through all ranks (the fallback) keeps
# the bits.
# usage: test_mpi_bitwise.sh CAPDEM SOURCE_DIR
set -u
capdem=$1 src=$2
. "$src/tests/mpi/mpi_common.sh"

# Point to point (docs/mpi.md, "Communication"): the crosses on 4 slabs
# across x, each with at most 2 neighbours: no rank sends more than 2
# messages per step or per migration (an exchange with all ranks: 3), and
# the migrations send the particles that change owner and the ghost copies
# that appear: under one particle record per migration and rank (the
# crosses settle, few cross a cut; re-sending every owned particle with
# its ghost copies would be 10 to 20).
traffic_checks() {
  local t
  t=$(grep 'capdem: MPI traffic:' err)
  # "per step A, B messages and C, D bytes; per migration E, F messages and G, H bytes, I, J particle records"
  read -r step_max mig_max records <<< "$(sed -n 's/.*per step [0-9.e+-]*, \([0-9.e+-]*\) messages.*per migration [0-9.e+-]*, \([0-9.e+-]*\) messages.*bytes, \([0-9.e+-]*\), [0-9.e+-]* particle records.*/\1 \2 \3/p' <<< "$t")"
  if awk -v a="${step_max:-9}" -v b="${mig_max:-9}" -v c="${records:-99}" 'BEGIN { exit !(a <= 2 && b <= 2 && c < 1) }'; then ok
  else bad "crosses_2d: 4 ranks: expected at most 2 messages per step and per migration and under 1 record per migration, got: $t"; fi
}

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
    migrated_with_ghosts "$case: $np ranks"
    [ "$case.$np" = crosses_2d.4 ] && traffic_checks
  done
  # The migrations' fallback through all ranks (a particle beyond the
  # neighbours; forced here for every migration): the same bits.
  if [ "$case" = crosses_2d ]; then
    if CAPDEM_MPI_ALL_RANKS=1 mpi 3 run "$cfg" --output all3.h5 --quiet 2> err && same serial.h5 all3.h5; then ok
    else bad "$case: 3 ranks, every migration through all ranks: failed or differs from the serial run"; head -20 diff.txt; fi
    if grep -q 'capdem: MPI: 3 ranks, \([0-9]*\) migrations (\1 through all ranks)' err; then ok
    else bad "$case: expected every migration through all ranks: $(grep 'MPI:' err)"; fi
  fi
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
# Recursive coordinate bisection (mpi.decomposition: rcb): the hexapod
# pile on 3 ranks, the crosses on 4, with the serial bits.
for c in hexapod_pile.3 crosses_2d.4; do
  case=${c%.*} np=${c#*.}
  { printf 'mpi:\n  decomposition: rcb\n'; cat "$src/tests/mpi/$case.yaml"; } > rcb.yaml
  rm -f ./*.h5
  "$capdem" run rcb.yaml --output serial.h5 --quiet 2> err || bad "rcb $case: the serial run failed"
  if mpi "$np" run rcb.yaml --output rcb.h5 --quiet 2> err && same serial.h5 rcb.h5; then ok
  else bad "rcb $case: $np ranks: failed or differs from the serial run"; head -20 diff.txt; fi
  if grep -q 'sub-domains by recursive coordinate bisection' err; then ok
  else bad "rcb $case: not cut by rcb: $(head -1 err)"; fi
done
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
