#!/usr/bin/env bash
# The material point method on the OpenCL backend (docs/mpm.md, "The
# OpenCL backend"), against the omp backend of the same binary: the plastic
# CI disk (300 steps: stencils, walls, return mapping) and the CI elastic
# packing (600 steps, stopped at 300 and resumed: the contact, its count Z,
# the resume) must give run files equal bit for bit under h5diff (/mpm and
# /parameters): the kernels are the omp loops' items, every sum in a fixed
# order, and sqrt, +, *, / round correctly in OpenCL C as on the host
# (FP_CONTRACT off both sides).  Also: an omp run resumed on OpenCL equals
# the omp run, the first line names the OpenCL device (no silent omp run),
# and a platform that does not exist is refused with exit 2.  Registered
# with the OpenCL tests (label backend) and label mpm, in OpenCL builds.
# usage: opencl_same_bits.sh CAPDEM SOURCE_DIR
set -u
capdem=$1 src=$2
export OMP_WAIT_POLICY=PASSIVE
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work" || exit 1
fail=0
run() { # run NAME BACKEND CONFIG [options]: the log in NAME.log
  local name=$1 backend=$2 cfg=$3
  shift 3
  "$capdem" run "$src/configs/mpm/ci/$cfg.yaml" --backend "$backend" "$@" > "$name.log" 2>&1 ||
    { echo "FAIL: run $name ($backend $cfg $*)"; cat "$name.log"; fail=1; }
}
same() { # same A B: the two run files' /mpm and /parameters are equal
  for g in /mpm /parameters; do
    if h5diff "$1" "$2" $g > diff 2>&1; then echo "$1 = $2 ($g)"
    else echo "FAIL: $1 and $2 differ in $g"; head -8 diff; fail=1; fi
  done
}
"$capdem" run "$src/configs/mpm/ci/deposit_disks.yaml" --quiet > log 2>&1 || { echo "FAIL: the CI deposit"; cat log; exit 1; }
for b in omp opencl; do
  run disk_$b $b disk_plastic_h1 --steps 300 --output disk_$b.h5
  run pack_$b $b packing_elastic --steps 300 --output pack_$b.h5 --quiet
  [ $b = omp ] && cp pack_omp.h5 cross.h5
  run pack_${b}_resumed $b packing_elastic --steps 600 --resume pack_$b.h5 --quiet
done
run cross opencl packing_elastic --steps 600 --resume cross.h5 --quiet
if ! grep -q "backend opencl on OpenCL device" disk_opencl.log; then
  echo "FAIL: the OpenCL run does not name its OpenCL device:"; head -3 disk_opencl.log; fail=1
fi
grep -q "backend omp on host" disk_omp.log || { echo "FAIL: the omp run's first line"; head -3 disk_omp.log; fail=1; }
same disk_omp.h5 disk_opencl.h5
same pack_omp.h5 pack_opencl.h5
same pack_omp.h5 cross.h5
# the series must have seen contacts, or the packing compared nothing of the contact
z=$(h5dump -d /mpm/series/coordination -y -w 0 pack_opencl.h5 | sed -n '/DATA {/,/}/p' | tr -d ' {}' | tr ',' '\n' |
  grep -E '^[0-9.e+-]+$' | sort -g | tail -1)
awk -v z="$z" 'BEGIN { exit !(z > 1) }' || { echo "FAIL: largest Z of the OpenCL packing is '$z', expected > 1 (12 disks in contact)"; fail=1; }
echo "largest Z of the packing's series: $z"
CAPDEM_OPENCL_PLATFORM=no-such-platform "$capdem" run "$src/configs/mpm/ci/disk_elastic.yaml" --backend opencl \
  --output refused.h5 --quiet > refused.log 2>&1
rc=$?
if [ $rc -ne 2 ] || ! grep -q "CAPDEM_OPENCL_PLATFORM=no-such-platform matches no platform" refused.log; then
  echo "FAIL: a platform that does not exist: exit $rc, expected 2 with the platform named:"; cat refused.log; fail=1
fi
[ -e refused.h5 ] && { echo "FAIL: the refused run wrote refused.h5"; fail=1; }
exit $fail
