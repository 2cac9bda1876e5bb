#!/usr/bin/env bash
# Protocols on several MPI ranks (docs/mpi.md, "Protocols"): the walls
# move under feedback from the wall load, which the ranks sum in the
# serial order, and the deposit's piston starts from the packing's top,
# which every rank reads from the gathered state.  Bit for bit the serial
# run: the deposit on 2D crosses through settling, compression and hold
# (2 and 3 ranks), radial compaction of the spheres' CI twin for 6000
# steps (3 ranks), and a deposit written with 3 ranks in its compression
# phase and resumed with 2, against the serial resume; the bulk-modulus
# probe (shortened: tests/mpi/bulk_hexapods.yaml), whose every window
# restarts from the base state, on 3 ranks and resumed in a probe window
# with 2.
# usage: test_mpi_protocols.sh CAPDEM SOURCE_DIR
set -u
capdem=$1 src=$2
. "$src/tests/mpi/mpi_common.sh"
deposit="$src/tests/mpi/deposit_2d.yaml" radial="$src/configs/protocols/ci/radial_spheres.yaml"

"$capdem" run "$deposit" --output serial.h5 --quiet 2> err || bad "deposit: the serial run failed"
if grep -q "reached in protocol phase 'hold'" err; then ok; else bad "deposit: the serial run did not reach the hold phase"; fi
for np in 2 3; do
  if mpi "$np" run "$deposit" --output "mpi$np.h5" --quiet 2> err && same serial.h5 "mpi$np.h5"; then ok
  else bad "deposit: $np ranks: failed or differs from the serial run"; head -20 diff.txt; fi
done

"$capdem" run "$radial" --output radial1.h5 --steps 6000 --quiet 2> err || bad "radial: the serial run failed"
if mpi 3 run "$radial" --output radial3.h5 --steps 6000 --quiet 2> err && same radial1.h5 radial3.h5; then ok
else bad "radial: 3 ranks: failed or differs from the serial run"; head -20 diff.txt; fi

# resumed_equal NAME CONFIG STEP: written to STEP with 3 ranks and resumed
# with 2 equals the serial run written to STEP and resumed
resumed_equal() {
  "$capdem" run "$2" --output "$1-1.h5" --steps "$3" --quiet 2> err &&
    "$capdem" run "$2" --resume "$1-1.h5" --quiet 2> err || { bad "$1: the serial resume failed"; return; }
  if mpi 3 run "$2" --output "$1-3.h5" --steps "$3" --quiet 2> err &&
     mpi 2 run "$2" --resume "$1-3.h5" --quiet 2> err && same "$1-1.h5" "$1-3.h5"; then ok
  else bad "$1: 3 ranks to step $3, resumed with 2: failed or differs from the serial resume"; head -20 diff.txt; fi
}
resumed_equal deposit "$deposit" 11000 # in the compression

bulk="$src/tests/mpi/bulk_hexapods.yaml"
"$capdem" run "$bulk" --output bulk1.h5 --quiet 2> err || bad "bulk: the serial run failed"
if ! grep -q "reached in protocol phase" err; then ok; else bad "bulk: the serial run did not finish its probes"; fi
if mpi 3 run "$bulk" --output bulk3.h5 --quiet 2> err && same bulk1.h5 bulk3.h5; then ok
else bad "bulk: 3 ranks: failed or differs from the serial run"; head -20 diff.txt; fi
resumed_equal bulk "$bulk" 20700 # in the first strained window
echo "test_mpi_protocols: $pass passed, $fails failed"
[ $fails -eq 0 ]
