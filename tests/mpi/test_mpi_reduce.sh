#!/usr/bin/env bash
# The observables as reductions (docs/mpi.md, "Reductions"): the thermo
# lines of an MPI run are summed without gathering the state, block by
# block on the blocks' ranks, and equal the serial program's bit for bit
# (the whole file: h5diff and byte for byte), with several blocks of every
# kind spread over the ranks (tests/mpi/sphere_blocks.yaml); and each rank
# sends each of its rows once per reduction, not the state to every rank
# (measured: 3.6-5.2 MB per rank and observation with the gather, 0.17-0.22
# MB with the reduction, on 2-4 ranks; the bound below is 0.5 MB).  The
# wall loads' reduction is checked by the protocols (test_mpi_protocols).
# usage: test_mpi_reduce.sh CAPDEM SOURCE_DIR
set -u
capdem=$1 src=$2
. "$src/tests/mpi/mpi_common.sh"
cfg="$src/tests/mpi/sphere_blocks.yaml"

"$capdem" run "$cfg" --output serial.h5 --quiet 2> err || bad "the serial run failed"
for np in 2 3; do
  if ! mpi "$np" run "$cfg" --output "mpi$np.h5" --quiet 2> err; then bad "$np ranks: the run failed"; continue; fi
  if same serial.h5 "mpi$np.h5"; then ok; else bad "$np ranks: differs from the serial run"; cat diff.txt; fi
  line=$(grep 'MPI reductions' err)
  n=$(echo "$line" | sed -n 's/.*wall loads): \([0-9]*\), .*/\1/p')
  mean=$(echo "$line" | sed -n 's/.*(mean, max) \([0-9.e+]*\), .*/\1/p')
  if [ "${n:-0}" -ge 30 ] && awk -v m="${mean:-1e99}" 'BEGIN { exit !(m > 0 && m < 500000) }'; then ok
  else bad "$np ranks: expected >= 30 reductions of 0 to 0.5 MB per rank: '$line'"; fi
done
# The ranks merge more levels of the tree themselves at scale (docs/mpi.md,
# "Reductions": as many as leave 4 items a rank; here 751 leaves on 3 ranks
# keep 1): forced to 2 (3 items of 256 leaves, one a rank, rank 0 merging
# the 3) and to 3 (the whole tree on rank 0), the same bits.
for levels in 2 3; do
  if CAPDEM_MPI_MERGE_LEVELS=$levels mpi 3 run "$cfg" --output "lv$levels.h5" --quiet 2> err &&
     same serial.h5 "lv$levels.h5"; then ok
  else bad "3 ranks, $levels merge levels on the ranks: failed or differs from the serial run"; cat diff.txt; fi
done
echo "test_mpi_reduce: $pass passed, $fails failed"
[ $fails -eq 0 ]
