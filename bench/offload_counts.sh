#!/bin/sh
# Launches and host<->device copies of the omp offload variant, per step
# and per neighbour-list build (docs/offload.md, "Per-step copies" and "The
# build's arguments on the device").  Runs capdem-bench twice on the same
# packing, A and B timed steps, with LIBOMPTARGET_INFO=0x21 (every kernel
# launch and every copy; LLVM's offload runtime, e.g. the clang-14 host
# offload build), and prints what run B did more than run A: the steps
# B - A and the builds among them, kernel launches, copies and bytes each way.
#
#   bench/offload_counts.sh BUILD_DIR [A B [capdem-bench options...]]
#
# default options: --case hexapods_a3 --n 300 --settle-steps 1000 --threads 1
# (a pile still falling: about one build every 3-4 steps).  Per build:
# (launches - steps x launches per step without a build) / builds; copies
# to the device: a step without a build makes none (test_offload_args).
set -eu
bench="$1/capdem-bench"
A="${2:-200}"
B="${3:-400}"
[ $# -gt 3 ] && shift 3 || set --
[ $# -gt 0 ] || set -- --case hexapods_a3 --n 300 --settle-steps 1000 --threads 1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
for steps in "$A" "$B"; do
    OMP_TARGET_OFFLOAD=MANDATORY LIBOMPTARGET_INFO=$((0x1 | 0x20)) "$bench" "$@" --steps "$steps" --repeat 1 \
        >"$tmp/out$steps" 2>"$tmp/log$steps"
done
count() { # log -> launches h2d_copies h2d_bytes d2h_copies d2h_bytes builds
    awk -v json="$2" '
        /Entering OpenMP kernel/ { launches++ }
        /Copying data from host to device/ { split($0, s, "Size="); h++; hb += s[2] + 0 }
        /Copying data from device to host/ { split($0, s, "Size="); d++; db += s[2] + 0 }
        END {
            while ((getline line < json) > 0)
                if (match(line, /"neighbor_builds": [0-9]+/)) b = substr(line, RSTART + 19, RLENGTH - 19)
            print launches + 0, h + 0, hb + 0, d + 0, db + 0, b + 0
        }' "$1"
}
set -- $(count "$tmp/log$A" "$tmp/out$A") $(count "$tmp/log$B" "$tmp/out$B")
steps=$((B - A)) builds=$((${12} - $6))
launches=$((${7} - $1)) h2d=$((${8} - $2)) h2d_bytes=$((${9} - $3)) d2h=$((${10} - $4)) d2h_bytes=$((${11} - $5))
echo "steps $steps, builds $builds: launches $launches, to device $h2d copies $h2d_bytes B, from device $d2h copies $d2h_bytes B"
awk -v s=$steps -v b=$builds -v l=$launches -v h=$h2d -v hb=$h2d_bytes -v d=$d2h -v db=$d2h_bytes 'BEGIN {
    printf "per step: %.2f launches, to device %.2f copies %.1f B, from device %.2f copies %.1f B\n", l / s, h / s, hb / s, d / s, db / s
    if (b > 0) printf "per build: %.1f launches beyond 3 a step, to device %.2f copies %.1f B\n", (l - 3 * s) / b, h / b, hb / b
}'
