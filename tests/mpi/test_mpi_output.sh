#!/usr/bin/env bash
# One run file written by every MPI rank through parallel HDF5 (docs/mpi.md,
# "One file"): each rank writes data into the file (the closing "MPI output"
# line), and the file is the serial program's, value for value (h5diff) and
# byte for byte (same_bytes.py), as is the file of mpi.output = rank0 (rank
# 0 writes, journaled); the output safety of docs/output.md holds
# under the MPI-IO driver: an existing output is refused and left as it
# was, --overwrite replaces it (written aside, renamed, nothing left
# beside it), a file an MPI run is writing is in use for another capdem
# and for HDF5 readers, and a run file deleted during an MPI run stops
# it with exit status 1 on every rank.  Every rank writes from its local
# state: a run without a protocol gathers the state never.  `capdem
# --version` under mpirun names each rank's device once.
# usage: test_mpi_output.sh CAPDEM SOURCE_DIR
set -u
capdem=$1 src=$2
. "$src/tests/mpi/mpi_common.sh"
cfg="$src/tests/mpi/hexapod_pile.yaml"

"$capdem" run "$cfg" --output serial.h5 --quiet 2> err || bad "the serial run failed"

# every rank writes: the smallest rank's share is data, not nothing
if mpi 3 run "$cfg" --output mpi3.h5 --quiet 2> err; then
  least=$(sed -n 's/^capdem: MPI output: .*(MPI-IO): \([0-9]*\)\.\.[0-9]*$/\1/p' err)
  if [ -n "$least" ] && [ "$least" -gt 0 ]; then ok; else bad "3 ranks: a rank wrote no data into the file ('$least')"; fi
  if same serial.h5 mpi3.h5; then ok; else bad "3 ranks: the file differs from the serial one"; cat diff.txt; fi
  # from the local states: a run without a protocol never gathers the whole state
  if grep -q 'MPI output: each rank wrote its rows from its local state; the whole state gathered 0 times;' err; then ok
  else bad "3 ranks: the state was gathered for the snapshots ($(grep 'MPI output' err))"; fi
else
  bad "3 ranks: the run failed"
fi

# mpi.output = rank0: rank 0 alone writes, with the serial writer's
# journaled commits; the same file
{ printf 'mpi:\n  output: rank0\n'; cat "$cfg"; } > rank0.yaml
"$capdem" run rank0.yaml --output serial0.h5 --quiet 2> err || bad "the serial run of rank0.yaml failed"
if mpi 3 run rank0.yaml --output rank0.h5 --quiet 2> err && grep -q 'MPI output: rank 0 wrote the run file' err &&
   same serial0.h5 rank0.h5; then ok
else bad "mpi.output = rank0 on 3 ranks: expected rank 0's file, equal to the serial one"; cat diff.txt; fi

# an existing output is refused (exit 2, once) and left byte for byte
cp serial.h5 exists.h5 && cp serial.h5 exists.orig
mpi 2 run "$cfg" --output exists.h5 --quiet > out 2> err
rc=$?
if [ $rc -eq 2 ] && [ "$(grep -c 'exists.h5 exists: refused, the file is left as it is' err)" -eq 1 ] &&
   cmp -s exists.h5 exists.orig; then ok
else bad "existing output on 2 ranks: exit $rc, expected 2, one refusal and the file untouched"; fi

# --overwrite: the old file replaced by the new run, nothing left beside it
cp mpi3.h5 replaced.h5
if mpi 2 run "$cfg" --output replaced.h5 --overwrite --steps 4000 --quiet 2> err &&
   [ "$(snapshots replaced.h5)" = 3 ] && [ -z "$(ls -A | grep '^\.replaced\.h5\.')" ]; then ok
else bad "--overwrite on 2 ranks: expected the new run's 3 snapshots in replaced.h5 and no file beside it"; fi

# in use: while 3 ranks write busy.h5, neither another capdem nor an HDF5
# reader gets it (the run is stopped then: it has served)
mpi 3 run "$cfg" --output busy.h5 --steps 200000 --quiet 2> busy.err &
writer=$!
for _ in $(seq 1 200); do [ -s busy.h5 ] && break; sleep 0.1; done
"$capdem" run "$cfg" --output busy.h5 --overwrite --quiet > out 2> err
rc=$?
if [ $rc -eq 2 ] && grep -q 'busy.h5 is in use by another process' err; then ok
else bad "a serial run onto the file 3 ranks write: exit $rc, expected 2 and 'in use'"; fi
if h5dump -H busy.h5 > /dev/null 2>&1; then bad "h5dump opened the file 3 ranks are writing"; else ok; fi
kill "$writer"
wait "$writer" 2> /dev/null

# deleted during the run: every rank stops with exit 1, one message
mpi 3 run "$cfg" --output gone.h5 --steps 60000 --quiet 2> err &
writer=$!
# (the poll reads past the writer's lock)
for _ in $(seq 1 300); do [ "$(HDF5_USE_FILE_LOCKING=FALSE snapshots gone.h5)" = 2 ] && break; sleep 0.1; done
rm -f gone.h5
wait "$writer"
rc=$?
if [ $rc -eq 1 ] && [ "$(grep -c 'gone.h5 was deleted during the run' err)" -eq 1 ]; then ok
else bad "a file deleted under 3 ranks: exit $rc, expected 1 and one message"; fi

# --version on 3 ranks: rank 0 prints, once, and names every rank's device
if mpi 3 --version > out 2> err && [ "$(grep -c '^capdem ' out)" -eq 1 ] &&
   grep -q '^MPI: 3 ranks, each with the device it takes in a run: rank 0: .*; rank 1: .*; rank 2: ' out; then ok
else bad "--version on 3 ranks: expected one version line and one naming ranks 0-2"; cat out; fi

echo "test_mpi_output: $pass passed, $fails failed"
[ $fails -eq 0 ]
