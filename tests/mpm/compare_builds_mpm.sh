#!/usr/bin/env bash
# The material point method on two capdem binaries (docs/offload.md, "Host
# offload devices in CI"; docs/mpm.md, "Work items"): first the offload
# binary must really launch the step's loops on offload device 0 and copy
# data back (LIBOMPTARGET_INFO: 15 kernels a step on the CI packing), so a
# silent host fallback fails; then the plastic CI disk (300 steps) and the
# CI elastic packing (600 steps, stopped at 300 and resumed) run on a
# default build's capdem and on the host-offload build's, and their run
# files must be equal bit for bit under h5diff (/mpm and /parameters; the
# creator attribute names the build).
# usage: compare_builds_mpm.sh REF_CAPDEM OFFLOAD_CAPDEM SOURCE_DIR
set -u
ref=$1 off=$2 src=$3
export OMP_TARGET_OFFLOAD=MANDATORY OMP_WAIT_POLICY=PASSIVE
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work" || exit 1
fail=0
"$ref" run "$src/configs/mpm/ci/deposit_disks.yaml" --quiet > log 2>&1 || { echo "FAIL: the CI deposit"; exit 1; }
LIBOMPTARGET_INFO=$((0x1 | 0x20)) "$off" run "$src/configs/mpm/ci/packing_elastic.yaml" --steps 20 --output info.h5 \
  --quiet > info.log 2>&1
launches=$(grep -c "device 0 info: Entering OpenMP kernel" info.log)
copies=$(grep -c "device 0 info: Copying data from device to host" info.log)
echo "LIBOMPTARGET_INFO, 20 steps of the CI packing: $launches kernel launches, $copies device-to-host copies"
if [ "$launches" -lt 250 ] || [ "$copies" -lt 20 ]; then
  echo "FAIL: the offload binary did not run the mpm step's loops on offload device 0"; fail=1
fi
for b in ref off; do
  bin=$ref; [ $b = off ] && bin=$off
  "$bin" run "$src/configs/mpm/ci/disk_plastic_h1.yaml" --steps 300 --output disk_$b.h5 --quiet > log 2>&1 &&
    "$bin" run "$src/configs/mpm/ci/packing_elastic.yaml" --steps 300 --output pack_$b.h5 --quiet > log 2>&1 &&
    "$bin" run "$src/configs/mpm/ci/packing_elastic.yaml" --steps 600 --resume pack_$b.h5 --quiet > log 2>&1 ||
    { echo "FAIL: the $b binary's runs"; cat log; fail=1; }
done
for r in disk pack; do
  for g in /mpm /parameters; do
    if h5diff "${r}_ref.h5" "${r}_off.h5" $g > diff 2>&1; then echo "$r $g: equal"
    else echo "FAIL: $r $g differs"; head -5 diff; fail=1; fi
  done
done
exit $fail
