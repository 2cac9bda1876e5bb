#!/usr/bin/env bash
# A run written with 3 MPI ranks resumes with 2 ranks and with 1 process
# (docs/mpi.md, "Resume"): each continued file equals, bit for bit, the
# serial run resumed at the same step, and equals the uninterrupted serial
# run but for the primitives' reference ends of the last neighbour-list
# build (prim_a_ref, prim_b_ref), which a resume rebuilds at its first
# step (the serial program's own resume does the same; checked here).
# usage: test_mpi_resume.sh CAPDEM SOURCE_DIR
set -u
capdem=$1 src=$2
. "$src/tests/mpi/mpi_common.sh"
cfg="$src/tests/mpi/hexapod_pile.yaml"
refs=(/particles/prims/prim_a_ref /particles/prims/prim_b_ref)
# a resumed file notes its resumes (/parameters/resumes) where the whole run has none
whole_only=("${refs[@]}" /parameters/resumes)

"$capdem" run "$cfg" --output whole.h5 --quiet 2> err || bad "the serial run failed"
"$capdem" run "$cfg" --output serial.h5 --steps 6000 --quiet 2> err &&
  "$capdem" run "$cfg" --resume serial.h5 --quiet 2> err || bad "the serial resume failed"
if same whole.h5 serial.h5 "${whole_only[@]}"; then ok; else bad "serial resume: differs from the whole run"; head diff.txt; fi
if same whole.h5 serial.h5 /parameters/resumes; then bad "serial resume: expected other reference ends than the whole run's"; else ok; fi
for np in 2 1; do
  if ! mpi 3 run "$cfg" --output "from3to$np.h5" --steps 6000 --quiet 2> err; then bad "3 ranks: the run failed"; continue; fi
  if [ "$np" -eq 1 ]; then "$capdem" run "$cfg" --resume "from3to$np.h5" --quiet 2> err
  else mpi "$np" run "$cfg" --resume "from3to$np.h5" --quiet 2> err; fi
  if [ $? -ne 0 ]; then bad "resume of a 3-rank file with $np: failed"; continue; fi
  if same serial.h5 "from3to$np.h5"; then ok; else bad "3 ranks, then $np: differs from the serial resume"; head diff.txt; fi
  if same whole.h5 "from3to$np.h5" "${whole_only[@]}"; then ok; else bad "3 ranks, then $np: differs from the whole run"; fi
done
echo "test_mpi_resume: $pass passed, $fails failed"
[ $fails -eq 0 ]
