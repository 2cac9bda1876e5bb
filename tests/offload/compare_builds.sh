#!/usr/bin/env bash
# Runs CI-size protocol twins (configs/protocols/ci/), to the end of their
# protocol or for a few thousand steps, on two capdem binaries and compares the run files bit for bit with
# h5diff (docs/offload.md, "Host offload devices in CI").
#
# usage: compare_builds.sh REF_CAPDEM OFFLOAD_CAPDEM SOURCE_DIR [same|differ]
#   same   (default): every dataset and attribute must be equal (the
#          creator's commit attribute aside); the offload binary must really
#          launch its kernels on offload device 0 and copy data back
#          (LIBOMPTARGET_INFO), so a silent host fallback fails too.
#   differ: OFFLOAD_CAPDEM is a build with a planted mapping bug; every run
#          must finish, and the particle positions of at least one case must
#          differ -- then the check above catches the bug.  Stops at the
#          first case that differs.
#   fallback: OFFLOAD_CAPDEM is the GCC nvptx build on a machine without a
#          GPU (libgomp's host fallback, one memory: docs/offload.md,
#          "Without a GPU"); it must say so, and its run files must equal
#          the reference's as in `same`, on short cuts (--steps) after
#          reorders and mid-run snapshots.
set -u
ref=$1 off=$2 src=$3 mode=${4:-same}
export OMP_WAIT_POLICY=PASSIVE
[ "$mode" = fallback ] || export OMP_TARGET_OFFLOAD=MANDATORY
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail=0 caught=0
# twin:steps[:resumed_to] -- 2D crosses deposited and compressed by a piston
# (to the end of their protocol), hexapods deposited in a cylinder (to the
# end), and a radial compaction of alpha-2 hexapods in a sphere (moving
# walls, wall loads every step) stopped at step 3000 and resumed to 6000.
# Together: Verlet rebuilds as packings form, protocol phase changes,
# moving walls, resume.
# (steps "full": the twin's own run.steps cap, which its protocol ends before)
cases="deposit_2d_crosses:full deposit_cylinder_D6L:full radial_hexapods_a2:3000:6000"
# fallback (a name with a / is a config under configs/): the hexapod drop cut
# after two snapshots, the 1000-hexapod radial compaction cut at 1500 steps
# (its last observation after the final sync); about 1 s a run
if [ "$mode" = fallback ]; then
  cases="./hexapod_drop:12000 protocols/radial_hexapods_a3:1500"
  if ! "$off" --version 2>&1 | grep -q "no offload device found"; then
    echo "skipped: $off finds an offload device; this check is for the host fallback"; exit 77
  fi
fi

if [ "$mode" = same ]; then
  # The kernels must run on an offload device, and data must move.
  LIBOMPTARGET_INFO=$((0x1 | 0x20)) "$off" run "$src/configs/protocols/ci/deposit_pseudo2d_T1L.yaml" --steps 20 \
    --output "$work/info.h5" --quiet > "$work/info.log" 2>&1
  launches=$(grep -c "device 0 info: Entering OpenMP kernel" "$work/info.log")
  copies=$(grep -c "device 0 info: Copying data from device to host" "$work/info.log")
  echo "LIBOMPTARGET_INFO, 20 steps: $launches kernel launches and $copies device-to-host copies on device 0"
  if [ "$launches" -lt 20 ] || [ "$copies" -lt 1 ]; then
    echo "FAIL: the offload binary did not run its kernels on offload device 0"; fail=1
  fi
fi

for c in $cases; do
  IFS=: read -r name steps resumed <<< "$c"
  cfg="$src/configs/protocols/ci/$name.yaml"
  case $name in */*) cfg="$src/configs/$name.yaml" name=$(basename "$name") ;; esac
  for b in ref off; do
    bin=$ref; [ $b = off ] && bin=$off
    start=$(date +%s%N)
    steps_opt=(--steps "$steps"); [ "$steps" = full ] && steps_opt=()
    "$bin" run "$cfg" "${steps_opt[@]}" --output "$work/$name-$b.h5" --quiet > "$work/$name-$b.log" 2>&1
    rc=$?
    if [ $rc -eq 0 ] && [ -n "$resumed" ]; then
      "$bin" run "$cfg" --resume "$work/$name-$b.h5" --steps "$resumed" --quiet >> "$work/$name-$b.log" 2>&1
      rc=$?
    fi
    echo "$name ($([ "$steps" = full ] && echo "to the end" || echo "$steps steps")${resumed:+, resumed to $resumed}) on $b: exit $rc after $(( ($(date +%s%N) - start) / 1000000 )) ms"
    [ $rc -eq 0 ] || { sed 's/^/    /' "$work/$name-$b.log"; echo "FAIL: $bin exited $rc"; fail=1; }
  done
  [ -f "$work/$name-ref.h5" ] && [ -f "$work/$name-off.h5" ] || continue
  h5diff --exclude-attribute /h5md/creator "$work/$name-ref.h5" "$work/$name-off.h5" > "$work/$name.diff" 2>&1
  hrc=$?
  if [ "$mode" != differ ]; then
    if [ $hrc -eq 0 ]; then
      echo "ok   $name: run files equal bit for bit"
    else
      grep -B1 "differences found" "$work/$name.diff" | grep -v -- '^--' | head -40 | sed 's/^/    /'
      echo "FAIL: $name: run files differ (h5diff exit $hrc)"; fail=1
    fi
  else
    if h5diff "$work/$name-ref.h5" "$work/$name-off.h5" /particles/all/position/value > /dev/null 2>&1; then
      echo "     $name: the planted bug left the positions unchanged"
    else
      caught=$((caught + 1))
      n=$(h5diff -r "$work/$name-ref.h5" "$work/$name-off.h5" /particles/all/position/value 2>/dev/null | grep -o '^[0-9]* differences' | head -1)
      echo "ok   $name: the planted bug changed the positions ($n of the particle position values); the same-bits check fails on it"
    fi
    # one case that catches it is the proof: spare CI the others
    [ "$caught" -gt 0 ] && break
  fi
done
if [ "$mode" = differ ] && [ "$caught" -eq 0 ]; then
  echo "FAIL: the planted bug changed no run: the same-bits check would not catch it"; fail=1
fi
exit $fail
