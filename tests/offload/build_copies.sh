#!/bin/bash
# The neighbour-list build's launches read the device-resident argument
# block (docs/offload.md, "The build's arguments on the device"): on LLVM's
# host offload devices (CAPDEM_OFFLOAD=host), counted with LIBOMPTARGET_INFO
# by bench/offload_counts.sh over 200 steps of a falling pile of 300
# hexapods (about 66 builds), a build copies at most 8 small items to the
# device (the changed span of the block's head, the candidate-count and
# reorder reductions' scalars) and at most 256 B in all.  With firstprivate
# structs per launch it copied 26 items, 11 kB (session 13's build).
# usage: build_copies.sh BUILD_DIR SOURCE_DIR
set -euo pipefail
build=$1 src=$2
out=$(bash "$src/bench/offload_counts.sh" "$build")
echo "$out"
line=$(echo "$out" | grep '^per build:')
copies=$(echo "$line" | sed -n 's/.*to device \([0-9.]*\) copies.*/\1/p')
bytes=$(echo "$line" | sed -n 's/.*copies \([0-9.]*\) B$/\1/p')
builds=$(echo "$out" | sed -n 's/^steps [0-9]*, builds \([0-9]*\):.*/\1/p')
[ -n "$copies" ] && [ -n "$bytes" ] && [ -n "$builds" ] || { echo "FAIL: could not read the counts"; exit 1; }
[ "$builds" -ge 10 ] || { echo "FAIL: only $builds builds in the window: the pile did not move as expected"; exit 1; }
awk -v c="$copies" -v b="$bytes" 'BEGIN { exit !(c <= 8 && b <= 256) }' ||
    { echo "FAIL: a build copies $copies items, $bytes B to the device (at most 8 and 256 B expected)"; exit 1; }
echo "ok: per build $copies copies, $bytes B to the device"
