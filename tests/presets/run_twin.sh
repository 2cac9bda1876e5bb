#!/usr/bin/env bash
# One CI-size protocol twin (configs/protocols/ci/NAME.yaml) runs to the end
# of its protocol within its run.steps cap: exit status 0, the protocol
# reaches its 'done' phase, no "run.steps reached" warning, and the run file
# holds a final snapshot in phase 7 (done).  CTest runs one of these per twin
# (label presets); tests/protocols checks the physics of three of them.
# usage: run_twin.sh CAPDEM SOURCE_DIR NAME
set -u
capdem=$1 src=$2 name=$3
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cfg="$src/configs/protocols/ci/$name.yaml"
start=$(date +%s%N)
"$capdem" run "$cfg" --output "$work/$name.h5" > "$work/log" 2>&1
rc=$?
ms=$(( ($(date +%s%N) - start) / 1000000 ))
tr '\r' '\n' < "$work/log" | grep -v '^step ' | sed 's/^/    /'
echo "$name: exit $rc after $((ms / 1000)).$(printf %03d $((ms % 1000))) s"
[ "$rc" -eq 0 ] || { echo "FAIL: exit status $rc"; exit 1; }
grep -q "protocol phase done" "$work/log" || { echo "FAIL: the protocol did not reach its done phase"; exit 1; }
if grep -q "reached in protocol phase" "$work/log"; then echo "FAIL: stopped by the run.steps cap"; exit 1; fi
# slot 0 of the last row of /walls/control (h5dump prints rows as "(k,0): v0, v1, ...")
phase=$(h5dump -d /walls/control "$work/$name.h5" | grep -E '^ *\([0-9]+,0\):' | tail -1 | sed 's/.*): *//; s/,.*//')
echo "final phase in the run file: $phase"
case "$phase" in 7|7.0) ;; *) echo "FAIL: last snapshot's phase is '$phase', expected 7 (done)"; exit 1 ;; esac
echo "ok   $name"
