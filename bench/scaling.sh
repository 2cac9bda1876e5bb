#!/usr/bin/env bash
# Throughput of the step against N and thread count (docs/performance.md).
#   bench/scaling.sh [BUILD_DIR] [CASE] > results.jsonl
#   SIZES="1000 10000" BACKENDS=omp:2,omp:1 bench/scaling.sh build spheres
# For each N, capdem-bench deposits the case's particles (default hexapods,
# alpha 3) into a box under 50 g, settles them for the case's settling
# steps, keeps them under that load (a settled packing at 50 g) and times
# the step with every entry of BACKENDS on that one packing (one JSON line per
# timed repeat).  With fewer settling steps the tall columns are still
# falling and list rebuilds dominate.  Each line reports the contacts per
# particle so that packings of different density can be told apart.
#
# The 1e5 point settles once, niced, into SETTLED_DIR (default build/bench-work)
# and is timed from that file (--load-settled) on a later invocation when the
# file exists: the settle is ~30-60 min of two cores, the timing a minute.
set -euo pipefail
build=${1:-build}
case=${2:-hexapods_a3}
bench="$build/capdem-bench"
sizes=${SIZES:-"1000 10000 100000"}
backends=${BACKENDS:-omp:2,omp:1,omp:2,omp:1}
dir=${SETTLED_DIR:-$build/bench-work}
mkdir -p "$dir"
steps_for() { if [ "$1" -le 1000 ]; then echo 1000; elif [ "$1" -le 10000 ]; then echo 200; else echo 30; fi; }
export OMP_WAIT_POLICY=PASSIVE
for n in $sizes; do
  steps=$(steps_for "$n")
  if [ "$n" -ge 100000 ]; then
    f="$dir/${case}_${n}_settled.h5"
    if [ ! -f "$f" ]; then
      nice -n 5 "$bench" --case "$case" --n "$n" --relax-steps 500 --repeat 0 --save-settled "$f"
    fi
    "$bench" --load-settled "$f" --steps "$steps" --repeat 2 --backend "$backends"
  else
    "$bench" --case "$case" --n "$n" --relax-steps 500 --steps "$steps" --repeat 2 --backend "$backends"
  fi
done
