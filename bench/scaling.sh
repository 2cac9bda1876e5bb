#!/usr/bin/env bash
# Throughput of the step against N and thread count (docs/performance.md).
#   bench/scaling.sh [BUILD_DIR] > results.jsonl
# For each N, capdem-bench deposits hexapods (alpha 3) into a box under 50 g,
# settles them, keeps them under that load (a settled packing at 50 g) and
# times the step with 1 and 2 threads (one JSON line per
# timed repeat).  15,000 settling steps at every N: with fewer the tall
# columns are still falling and list rebuilds dominate.  Each line reports the
# contacts per particle so that packings of different density can be told
# apart.
set -euo pipefail
build=${1:-build}
bench="$build/capdem-bench"
run() { # N SETTLE STEPS THREADS
  "$bench" --n "$1" --settle-steps "$2" --relax-steps 500 --gravity 490.5 --steps "$3" --threads "$4" --repeat 2
}
for threads in 1 2; do
  run 1000 15000 1000 "$threads"
  run 10000 15000 200 "$threads"
done
run 100000 15000 30 2
