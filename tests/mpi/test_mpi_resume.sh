#!/usr/bin/env bash
# A run written with 3 MPI ranks resumes with 2 ranks and with 1 process
# (docs/mpi.md, "Resume"): each continued file equals, bit for bit, the
# serial run resumed at the same step, and equals the uninterrupted serial
# run but for the primitives' reference ends of the last neighbour-list
# build (prim_a_ref, prim_b_ref), which a resume rebuilds at its first
# step (the serial program's own resume does the same; checked here).
# A file of the serial writer resumed on several ranks: refused (parallel
# output) or continued by rank 0's writer (mpi.output = rank0).
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
  # each rank read its own particles and ghosts (docs/mpi.md, "Resume")
  if [ "$np" -gt 1 ]; then
    if grep -q 'capdem: MPI set-up: each rank built or read the rows of [0-9]*\.\.[0-9]* of the 40 particles' err; then ok
    else bad "resume with $np ranks: expected each rank to read its own rows: $(grep 'MPI set-up' err)"; fi
  fi
  if same serial.h5 "from3to$np.h5"; then ok; else bad "3 ranks, then $np: differs from the serial resume"; head diff.txt; fi
  if same whole.h5 "from3to$np.h5" "${whole_only[@]}"; then ok; else bad "3 ranks, then $np: differs from the whole run"; fi
done
# A file of the serial writer (one process here) gets its chunks as it is
# written, which HDF5 1.10 cannot append to from several ranks (docs/mpi.md,
# "Resume"; it hung before the check): refused on 2 ranks as bad input
# (exit 2), once, the file as it was; with mpi.output: rank0 (the serial
# writer on rank 0) it resumes and equals the whole run but for the
# reference ends.
"$capdem" run "$cfg" --output one.h5 --steps 2000 --quiet 2> err || bad "the serial run to step 2000 failed"
cp one.h5 one_kept.h5
mpi 2 run "$cfg" --resume one.h5 --quiet 2> err
rc=$?
if [ $rc -ne 2 ]; then bad "a serially written file resumed on 2 ranks: exit status $rc, expected 2 (refused)"; cat err
elif [ "$(grep -c 'was written by one process' err)" -eq 1 ] && cmp -s one.h5 one_kept.h5; then ok
else bad "a serially written file on 2 ranks: expected one message and the file unchanged"; cat err; fi
{ printf 'mpi:\n  output: rank0\n'; cat "$cfg"; } > rank0.yaml
if mpi 2 run rank0.yaml --resume one.h5 --quiet 2> err && same whole.h5 one.h5 "${whole_only[@]}"; then ok
else bad "a serially written file resumed on 2 ranks with mpi.output = rank0: failed or differs from the whole run"; head diff.txt; fi
echo "test_mpi_resume: $pass passed, $fails failed"
[ $fails -eq 0 ]
