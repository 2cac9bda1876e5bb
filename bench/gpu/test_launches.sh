#!/usr/bin/env bash
# Kernel launches and host<->device copies of whole test programs on an
# LLVM offload build (the clang-14 host-offload build: every launch and copy
# goes through libomptarget as on a GPU), and the time they would take on a
# GPU whose launches and copies are bound by latency: launches x L + copies
# x C (docs/gpu_bundle.md, "The test part on a GPU").  L = 8 us (an H100's
# synchronous launch through LLVM 16, LIBOMPTARGET_PROFILE of the second GPU
# run), C = 10 us (a small synchronous copy; the first GPU run's 0.1 ms a
# step of 7 launches and 3 copies); CAPDEM_LAUNCH_US and CAPDEM_COPY_US
# change them.  The kernels' own work is left out: these tests step systems
# of 1 to a few hundred particles, whose kernels are shorter than a launch.
#
#   bench/gpu/test_launches.sh BUILD_DIR [TEST...]    (default: the tests
#                              that did not finish on the last H100 run)
#
# Prints one line per test: launches, copies each way, the estimate [s],
# and the host-offload run's own wall time (noise on a shared machine).
set -u
build=$(cd "$1" && pwd)
shift
[ $# -gt 0 ] || set -- test_conservation test_coulomb_sliding test_determinism test_protocols test_reorder test_rest \
    test_rotation_order
src=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
L=${CAPDEM_LAUNCH_US:-8}
C=${CAPDEM_COPY_US:-10}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
printf '%-22s %10s %10s %10s %12s %10s %6s\n' test launches to_device from_device estimate_s host_s rc
for t in "$@"; do
    exe=$build/tests/$t
    [ -x "$exe" ] || { echo "$t: no $exe" >&2; continue; }
    mkdir -p "$tmp/$t"
    s=$(date +%s.%N)
    # the counting reads the trace as it comes (a test makes millions of lines)
    (cd "$tmp/$t" && CAPDEM_SOURCE_DIR=$src OMP_WAIT_POLICY=PASSIVE OMP_TARGET_OFFLOAD=MANDATORY \
        LIBOMPTARGET_INFO=$((0x1 | 0x20)) "$exe" 2>&1 >/dev/null; echo "rc $?") |
        awk -v L="$L" -v C="$C" -v t="$t" -v s="$s" '
            /Entering OpenMP kernel/ { k++ }
            /Copying data from host to device/ { h++ }
            /Copying data from device to host/ { d++ }
            /^rc [0-9]+$/ { rc = $2 }
            END {
                "date +%s.%N" | getline e
                printf "%-22s %10d %10d %10d %12.1f %10.1f %6s\n", t, k, h, d, (k * L + (h + d) * C) / 1e6, e - s, rc
            }'
done
