#!/usr/bin/env bash
# MPI ranks on the OpenCL backend (docs/mpi.md, "GPUs"; PoCL's CPU device
# here): every rank steps its local state on the OpenCL device of its
# node-local rank, the halo packed and unpacked there, the state reloaded
# after each migration, the wall loads and observations read there and
# summed in the serial order.  Bit for bit the serial --backend opencl run
# (which is the serial omp run on PoCL, docs/opencl.md "Parity"): the
# settling hexapod pile and the 2D cross deposit on 2 and 3 ranks; the 2D
# deposit protocol (its piston fed back by the wall load every step) on 3;
# the pile written with 3 ranks and continued with 2.  The ranks must have
# migrated particles and held ghosts, and the first line must name each
# rank's OpenCL device.  No OpenCL platform: refused once, exit 2.  A run
# that blows up stops on every rank with the serial program's exit status
# and diagnosis.  Registered in builds with
# OpenCL only; POCL_CACHE_DIR (set by CTest) keeps the compiled kernels:
# the serial run compiles them, the ranks find them.
# usage: test_mpi_opencl.sh CAPDEM SOURCE_DIR
set -u
capdem=$1 src=$2
. "$src/tests/mpi/mpi_common.sh"
cl=(--backend opencl --quiet)

for case in hexapod_pile crosses_2d; do
  cfg="$src/tests/mpi/$case.yaml"
  if ! "$capdem" run "$cfg" --output serial.h5 "${cl[@]}" 2> err; then bad "$case: the serial OpenCL run failed"; cat err; continue; fi
  for np in 2 3; do
    if ! mpi "$np" run "$cfg" --output "mpi$np.h5" "${cl[@]}" 2> err; then bad "$case: $np OpenCL ranks: the run failed"; tail -5 err; continue; fi
    if same serial.h5 "mpi$np.h5"; then ok
    else bad "$case: $np OpenCL ranks: the run file differs from the serial OpenCL one"; head -20 diff.txt; fi
    migrated_with_ghosts "$case: $np OpenCL ranks"
    # "rank r: OpenCL device i of n '...' (node-local rank r)" for every rank
    first=$(head -1 err) named=0
    for ((r = 0; r < np; r++)); do
      grep -q "rank $r: OpenCL device [0-9]* of [0-9]* '[^']*' (node-local rank $r)" <<< "$first" && named=$((named + 1))
    done
    if [ "$named" -eq "$np" ]; then ok; else bad "$case: $np OpenCL ranks: the first line does not name each rank's device: $first"; fi
  done
  rm -f ./*.h5
done

# The deposit's piston follows the wall load every step (a reduction of
# the F_n each rank reads from its device) and starts from the packing's
# top (the gathered state).
deposit="$src/tests/mpi/deposit_2d.yaml"
"$capdem" run "$deposit" --output serial.h5 "${cl[@]}" 2> err || bad "deposit: the serial OpenCL run failed"
if grep -q "reached in protocol phase 'hold'" err; then ok; else bad "deposit: the serial OpenCL run did not reach the hold phase"; fi
if mpi 3 run "$deposit" --output mpi3.h5 "${cl[@]}" 2> err && same serial.h5 mpi3.h5; then ok
else bad "deposit: 3 OpenCL ranks: failed or differs from the serial OpenCL run"; head -20 diff.txt; fi

# Written with 3 OpenCL ranks to step 6000, continued with 2: the serial
# OpenCL run resumed at the same step.
pile="$src/tests/mpi/hexapod_pile.yaml"
rm -f ./*.h5
"$capdem" run "$pile" --output serial.h5 --steps 6000 "${cl[@]}" 2> err &&
  "$capdem" run "$pile" --resume serial.h5 "${cl[@]}" 2> err || bad "pile: the serial OpenCL resume failed"
if mpi 3 run "$pile" --output from3.h5 --steps 6000 "${cl[@]}" 2> err &&
   mpi 2 run "$pile" --resume from3.h5 "${cl[@]}" 2> err && same serial.h5 from3.h5; then ok
else bad "pile: 3 OpenCL ranks to step 6000, resumed with 2: failed or differs from the serial OpenCL resume"; head -20 diff.txt; fi

# No OpenCL device for the ranks (docs/opencl.md, "Messages"): refused on
# every rank at the start, exit 2, the message once, no run file.
rm -f ./*.h5
CAPDEM_OPENCL_PLATFORM=nonexistent mpi 2 run "$pile" --output none.h5 "${cl[@]}" > out 2> err
rc=$?
if [ $rc -eq 2 ] && [ "$(grep -c 'CAPDEM_OPENCL_PLATFORM=nonexistent matches no platform' err)" -eq 1 ] && [ ! -e none.h5 ]; then ok
else bad "no platform on 2 ranks: exit status $rc (expected 2), the message once and no file: $(head -3 err)"; fi

# A blow-up (dt far above t_col/5, forced): exit status 3 and the serial
# diagnosis, once, on 3 OpenCL ranks.
blows_up_as_serial "blowup: 3 OpenCL ranks" 3 --backend opencl
echo "test_mpi_opencl: $pass passed, $fails failed"
[ $fails -eq 0 ]
