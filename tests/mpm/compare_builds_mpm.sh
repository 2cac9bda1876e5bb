#!/usr/bin/env bash
# The material point method on two capdem binaries (docs/offload.md, "Host
# offload devices in CI"; docs/mpm.md, "Work items" and "Reading nothing
# between steps"): first the offload binary must really launch the step's
# loops on offload device 0 (LIBOMPTARGET_INFO), so a silent host fallback
# fails, and read nothing back between steps: the CI packing with neither
# series rows nor snapshots between its first and last step, run to steps
# 20 and 60, must differ by the launches of 40 steps (at least 15 a step;
# 18 on the CI packing) and by no device-to-host copy; then the plastic CI
# disk (300 steps) and
# the CI elastic packing (600 steps, stopped at 300 and resumed) run on a
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
sed 's/snapshot_every: 400/snapshot_every: 1000/; s/thermo_every: 20/thermo_every: 1000/' \
  "$src/configs/mpm/ci/packing_elastic.yaml" > quiet.yaml
count() { # log -> launches, device-to-host copies, host-to-device copies
  echo "$(grep -c "device 0 info: Entering OpenMP kernel" "$1") $(grep -c "device 0 info: Copying data from device to host" "$1")" \
    "$(grep -c "device 0 info: Copying data from host to device" "$1")"
}
for steps in 20 60; do
  LIBOMPTARGET_INFO=$((0x1 | 0x20)) "$off" run quiet.yaml --steps $steps --output info$steps.h5 --quiet \
    > info$steps.log 2>&1 || { echo "FAIL: the offload binary's run of $steps steps"; tail -3 info$steps.log; exit 1; }
done
set -- $(count info20.log) $(count info60.log)
launches=$(($4 - $1)) d2h=$(($5 - $2)) h2d=$(($6 - $3))
echo "LIBOMPTARGET_INFO, steps 21-60 of the CI packing (no output between): $launches kernel launches," \
  "$d2h device-to-host copies, $h2d host-to-device copies"
if [ "$launches" -lt 600 ]; then
  echo "FAIL: the offload binary did not run the mpm step's loops on offload device 0"; fail=1
fi
if [ "$d2h" -ne 0 ]; then
  echo "FAIL: the offload step read something back between steps"; fail=1
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
