#!/usr/bin/env bash
# MPI ranks on offload devices (docs/mpi.md, "GPUs"), in a build with
# CAPDEM_OFFLOAD=host and CAPDEM_MPI=ON: LLVM's x86-64 offload devices
# have memory of their own, so a halo row that is not packed on the device
# or not written back there gives other bits.  Each rank must take the
# device of its node-local rank (the run's first line names them), and the
# run files must equal the serial program's of the default build
# (REF_CAPDEM) bit for bit: the settling hexapod pile on 3 ranks
# (sub-domains across x and z, migrations), the sheared crosses on 4
# (particles dragged across the sub-domains with their contacts) and the
# 2D deposit on 3 (settling, piston, compression, hold: a wall load at
# every step, read from the wall candidates on the devices, and the
# observations of its relaxation checks, from the columns they read).
# `capdem --version` on 3 ranks names each rank's device.
#
# usage: mpi_same_bits.sh REF_CAPDEM OFFLOAD_MPI_CAPDEM SOURCE_DIR
set -u
ref=$1 off=$2 src=$3
export OMP_TARGET_OFFLOAD=MANDATORY OMP_WAIT_POLICY=PASSIVE OMP_NUM_THREADS=1 OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail=0
devices=$("$off" --version | sed -n 's/.*, \([0-9]*\) offload device(s).*/\1/p')
echo "offload devices of this build: ${devices:-none}"
[ "${devices:-0}" -ge 1 ] || { echo "FAIL: no offload device (docs/offload.md)"; exit 1; }
# `capdem --version` under mpirun names the device each rank will take
versions=$(timeout 120 mpirun --oversubscribe -np 3 "$off" --version 2> /dev/null)
for ((r = 0; r < 3; r++)); do
  want="rank $r: host offload device $((r % devices)) of $devices (node-local rank $r) on "
  if [[ "$versions" != *"$want"* ]]; then echo "FAIL: --version on 3 ranks does not say '$want': $versions"; fail=1; fi
done
[ "$(grep -c '^capdem ' <<< "$versions")" = 1 ] || { echo "FAIL: --version on 3 ranks: not one version line"; fail=1; }
for c in hexapod_pile:3 crosses_shear:4 deposit_2d:3; do
  IFS=: read -r name np <<< "$c"
  cfg="$src/tests/mpi/$name.yaml"
  "$ref" run "$cfg" --output "$work/$name-serial.h5" --quiet 2> "$work/$name-serial.log" ||
    { echo "FAIL: $name: the serial run failed"; fail=1; continue; }
  timeout 300 mpirun --oversubscribe -np "$np" "$off" run "$cfg" --output "$work/$name-mpi.h5" \
    > "$work/$name-mpi.log" 2>&1 || { sed 's/^/    /' "$work/$name-mpi.log"; echo "FAIL: $name: $np ranks failed"; fail=1; continue; }
  # every rank its device: node-local rank r on device r mod the devices
  first=$(grep -m1 'backend mpi on' "$work/$name-mpi.log")
  for ((r = 0; r < np; r++)); do
    want="rank $r: host offload device $((r % devices)) of $devices (node-local rank $r)"
    if [[ "$first" != *"$want"* ]]; then echo "FAIL: $name: the first line does not say '$want': $first"; fail=1; fi
  done
  if h5diff --exclude-attribute /h5md/creator "$work/$name-serial.h5" "$work/$name-mpi.h5" > "$work/$name.diff" 2>&1; then
    echo "ok   $name: $np ranks on offload devices, run file equal to the serial one bit for bit"
  else
    grep -B1 "differences found" "$work/$name.diff" | grep -v -- '^--' | head -20 | sed 's/^/    /'
    echo "FAIL: $name: $np ranks differ from the serial run"; fail=1
  fi
  grep -E '^capdem: MPI(:| traffic)' "$work/$name-mpi.log" | sed 's/^/    /'
done
exit $fail
