#!/usr/bin/env bash
# Runs capdem's GPU bundle (docs/gpu_bundle.md) on a machine with only the
# NVIDIA driver and CUDA: the bundle folder is self-contained (binaries of
# the Clang 16 and GCC 12 nvptx offload builds, every non-driver shared
# library they load, settled packings, the presets the tests read).
#
#   run_on_gpu.sh [PART...]          (default: all)
#
# PARTS (`all` runs info tests ladder opencl profile tests-gcc, in that
# order; each part goes on when another one fails; a part that the time
# budget no longer allows is skipped and says so):
#   info        nvidia-smi, glibc, ldd of the binaries, capdem --version of
#               each build (>= 1 offload device, or the part fails), one
#               short run with LIBOMPTARGET_INFO / GOMP_DEBUG showing the
#               kernels launched on the GPU (SPMD mode, blocks x threads)
#   tests       tests-clang: physics, regression, protocol (resume
#               included), unit, config tests with OMP_TARGET_OFFLOAD=MANDATORY
#   opencl      if an OpenCL ICD is there (the NVIDIA one, or one made from
#               the driver's libnvidia-opencl.so.1): physics and regression
#               tests on the OpenCL backend, the omp/OpenCL parity test
#               (omp on the host and omp on the GPU against OpenCL) and
#               test_drift_bound (host maths against the GPU's, bounded)
#   ladder      throughput: settled hexapods alpha 3 at 1e4, 1e5 and 1e6
#               (tiled), spheres 1e6 and the sphere-hexapod mixture 1e5,
#               Clang build, omp (and opencl when there): JSON lines in
#               $OUT/ladder.jsonl
#   profile     time per launch kind on 1e6 hexapods: libomptarget's own
#               profile (LIBOMPTARGET_PROFILE) summarised per kernel line,
#               then nsys if on PATH, else ncu (kernel time, DRAM bytes)
#   kernels     bench/gpu/kernel_profile.sh: ncu per kernel on the omp
#               offload build (pass 5 per primitive and per particle) and
#               on OpenCL at 1e5 hexapods, side by side (time, registers,
#               occupancy, local memory), about 110 s; not in `all`
#   mpm         the material point method (docs/mpm.md) on the Clang build:
#               its test programs and shell tests (label mpm, but the two
#               that draw with matplotlib) with OMP_TARGET_OFFLOAD=MANDATORY,
#               mpm_opencl_same_bits (omp on the host against OpenCL on the
#               GPU, bit for bit) when an ICD is there, and the throughput
#               of the full-size compaction (300 disks, about 121,000
#               points, configs/mpm/packing_elastic.yaml) shortened to
#               CAPDEM_BUNDLE_MPM_STEPS steps on omp and OpenCL: JSON lines
#               in ladder.jsonl; at most about 5 minutes by its caps; not
#               in `all`
#   tests-gcc   the tests on the GCC 12 nvptx build
#   ladder-gcc  the ladder on the GCC build
# Also: tests-clang, all, quick (info tests-clang ladder).
#
# Environment:
#   OUT                        where results go (default ./bundle-out); at most 6 files
#   CAPDEM_BUNDLE_BUDGET_S     seconds for the whole call (default 560: the
#                              device tool's limit is 600 per command)
#   CAPDEM_BUNDLE_HOST=1       a check without a GPU (bench/gpu/check_bundle.sh):
#                              OMP_TARGET_OFFLOAD=DISABLED, any OpenCL ICD
#   CAPDEM_BUNDLE_JOBS         tests run at once without a GPU (CAPDEM_BUNDLE_HOST:
#                              default 4)
#   CAPDEM_BUNDLE_GPU_JOBS     tests run at once on a GPU (default 1: they
#                              share the device; see run_tests)
#   CAPDEM_BUNDLE_TESTS_CAP    seconds for one test part (default 240)
#   CAPDEM_BUNDLE_ONLY         regular expression: only the test programs it matches
#   CAPDEM_BUNDLE_MPM_STEPS    steps of the full-size MPM throughput run (default 200)
#   CAPDEM_BUNDLE_MPM_CAP      seconds for the mpm tests (default 150); the
#                              OpenCL comparison gets 90, each throughput run 60
#                              (CAPDEM_BUNDLE_MPM_RATE_CAP)
#   CAPDEM_BUNDLE_MPM_BACKENDS the throughput runs' backends (default "omp opencl")
#   CAPDEM_BUNDLE_LADDER       ladder entries (default "h1e4 h1e5 h1e6 s1e6")
#   CAPDEM_BUNDLE_STEPS        timed steps per repeat (default 200; 100 at 1e6)
#   CAPDEM_BUNDLE_TILES        "KX,KZ KX,KZ KX,KZ": the copies of the settled
#                              packing for the 1e4, 1e5, 1e6 entries (default
#                              from its N: 1e3 -> 5,2 10,10 40,25)
#   CAPDEM_BUNDLE_UNPACK       where payload-*.tar.xz are unpacked
#                              (default /tmp/capdem-bundle-<manifest cksum>,
#                              outside the bundle so that it stays small)
#
# Exit status: 0 when every step passed or was skipped for lack of an ICD or
# profiler, 1 when any failed or ran out of time.
set -u -o pipefail

B=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
T0=$SECONDS
BUDGET=${CAPDEM_BUNDLE_BUDGET_S:-560}
OUT=${OUT:-$PWD/bundle-out}
mkdir -p "$OUT"
HOST=${CAPDEM_BUNDLE_HOST:-0}
# Host work at once (the GPU's tests: CAPDEM_BUNDLE_GPU_JOBS, run_tests).
NCPU=$(nproc 2>/dev/null || echo 4)
[ "$NCPU" -gt 16 ] && NCPU=16
[ "$HOST" = 1 ] && NCPU=4 # the shared development machine
JOBS=${CAPDEM_BUNDLE_JOBS:-$NCPU}

# ------------------------------------------------------------- internals
# `_test BINDIR TEST DIR BACKEND` runs one test program (xargs -P calls the
# script again for each); its status line goes to DIR/status.
if [ "${1:-}" = _test ]; then
    bindir=$2 t=$3 d=$4 be=$5
    mkdir -p "$d" && cd "$d" || exit 1
    s=$SECONDS
    # a test program of the build, or a shell test of tests/mpm (they take
    # capdem and the source folder, as their CTest entries do)
    cmd=("$bindir/$t")
    [ -x "$bindir/$t" ] || cmd=(bash "$CAPDEM_SOURCE_DIR/tests/mpm/$t.sh" "$bindir/capdem" "$CAPDEM_SOURCE_DIR")
    CAPDEM_TEST_BACKEND=$be timeout -k 5 "${CAPDEM_BUNDLE_TEST_TIMEOUT:-300}" "${cmd[@]}" >log 2>&1
    rc=$?
    w=$((SECONDS - s))
    if [ $rc = 0 ]; then st=PASS; elif [ $rc = 124 ] || [ $rc = 137 ]; then st=TIMEOUT; else st="FAIL(rc=$rc)"; fi
    echo "$st $t ${w}s" >status
    exit 0
fi

W=$(mktemp -d /tmp/capdem-bundle-run.XXXXXX)
trap 'rm -rf "$W"' EXIT # what matters is copied to $OUT at the end
LOGS=$W/logs
mkdir -p "$LOGS"
SUMMARY=$W/summary.txt
INFO=$W/info.txt
PROFILE=$W/profile.txt
: >"$SUMMARY"
: >"$INFO"
: >"$PROFILE"
note() { echo "$*" | tee -a "$SUMMARY"; }
left() { echo $((BUDGET - (SECONDS - T0))); }

# Runs one step under the time left: step NAME CAP_S COMMAND...  (output in
# logs/NAME.log).  Records PASS, FAIL(rc), TIMEOUT or SKIP(no time).
step() {
    local name=$1 cap=$2 t rc s
    shift 2
    t=$(left)
    t=$((t - 10))
    [ "$t" -gt "$cap" ] && t=$cap
    if [ "$t" -lt 15 ]; then note "SKIP(no time) $name"; return 0; fi
    s=$SECONDS
    timeout -k 5 "$t" "$@" >"$LOGS/$name.log" 2>&1
    rc=$?
    if [ $rc = 0 ]; then note "PASS $name $((SECONDS - s))s"
    elif [ $rc = 124 ] || [ $rc = 137 ]; then note "TIMEOUT $name after $((SECONDS - s))s (cap ${t}s)"
    else note "FAIL(rc=$rc) $name $((SECONDS - s))s: $(tail -3 "$LOGS/$name.log" | tr '\n' ' ' | cut -c1-300)"; fi
    return 0
}

# ------------------------------------------------- binaries and libraries
# bin/, lib/, lib.cxx/ and inputs/ travel as xz archives (libLLVM-16 is
# 118 MiB raw; the 14 programs of a build share most of their code): they
# are unpacked once per machine, outside the bundle (which must stay small
# enough to travel), into a folder keyed by the bundle's manifest.  A bundle
# without payload archives holds those folders unpacked (the CTest fixture).
KEY=$(cksum <"$B/MANIFEST.txt" | cut -d' ' -f1)
U=${CAPDEM_BUNDLE_UNPACK:-/tmp/capdem-bundle-$KEY}
if ls "$B"/payload*.tar.xz >/dev/null 2>&1; then
    if [ ! -e "$U/.complete" ]; then
        mkdir -p "$U"
        for a in "$B"/payload*.tar.xz; do
            if command -v xz >/dev/null; then
                xz -dc "$a" | tar -C "$U" -xf -
            else # Python reads .xz where xz-utils is absent
                python3 -c 'import sys, tarfile; tarfile.open(sys.argv[1], "r:xz").extractall(sys.argv[2])' "$a" "$U"
            fi || { echo "run_on_gpu.sh: cannot unpack $a into $U" >&2; exit 1; }
        done
        touch "$U/.complete"
    fi
    R=$U
else
    R=$B
fi
BIN=$R/bin
INPUTS=$R/inputs
LIBPATH=$R/lib
# The bundle's libstdc++/libgcc_s (GCC 12) only where the machine's own do
# not cover them: an older C++ runtime ahead of the system's would break
# driver libraries that need a newer one.
need=$(grep -ao 'GLIBCXX_3\.4\.[0-9]*' "$R/lib.cxx/libstdc++.so.6" 2>/dev/null | sort -uV | tail -1)
LDCONFIG=$(command -v ldconfig || echo /sbin/ldconfig) # /sbin may be off a user's PATH
sys=$({ "$LDCONFIG" -p 2>/dev/null | awk '/libstdc\+\+\.so\.6 .*x86-64/ {print $NF}'
    ls /usr/lib/x86_64-linux-gnu/libstdc++.so.6 /lib/x86_64-linux-gnu/libstdc++.so.6 2>/dev/null; } | head -1)
if [ -e "$R/lib.cxx/libstdc++.so.6" ] && ! { [ -n "$sys" ] && grep -qa "$need" "$sys"; }; then
    LIBPATH=$LIBPATH:$R/lib.cxx
    CXXNOTE="bundle's ($need)"
else
    CXXNOTE="system's ${sys:-?}"
fi
# The machine's own LD_LIBRARY_PATH stays behind ours: GPU images often
# find libcuda.so.1 through it (/usr/local/nvidia/lib64), not ldconfig.
export LD_LIBRARY_PATH=$LIBPATH${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
export CAPDEM_SOURCE_DIR=$B/src
# HDF5's h5dump and h5diff travel in tools/ (the MPM shell tests read run
# files with them); the GPU machine has none.
[ -d "$R/tools" ] && export PATH=$R/tools:$PATH
# no clang on GPU machines: test_geometry_opencl_c leaves its OpenCL C check to the
# device compiler (part opencl) instead of failing for want of clang
command -v clang-14 >/dev/null || command -v clang >/dev/null || export CAPDEM_TEST_NO_CLANG=1
export OMP_WAIT_POLICY=PASSIVE
if [ "$HOST" = 1 ]; then
    export OMP_TARGET_OFFLOAD=DISABLED
    # LLVM 16's libomp aborts ("Assertion failure at kmp_runtime.cpp(1128)")
    # or hangs when a target region with if(parallel: false) falls back to
    # the host and a host parallel loop follows, as CD_STEP_FOR does below
    # wide_min_ rows; one thread avoids it.  Only the host fallback: on a
    # GPU the target regions never run on the host.
    export OMP_NUM_THREADS=${OMP_NUM_THREADS:-1}
else
    export OMP_TARGET_OFFLOAD=MANDATORY
fi
VARIANTS=$(cd "$BIN" && ls)
has() { [ -x "$BIN/$1/capdem" ]; }

# OpenCL: where the driver's libnvidia-opencl.so.1 is there but no ICD
# names it (the first GPU machine had only PoCL's ICD in
# /etc/OpenCL/vendors: no NVIDIA platform), a folder with an ICD for it
# alone (PoCL loads its own libLLVM, which crashed next to libomptarget's
# libLLVM-16 in one process).  ocl-icd (the bundle's libOpenCL.so.1) reads
# every *.icd of the folder OCL_ICD_VENDORS names.
ICD=
VENDORS=${OCL_ICD_VENDORS:-/etc/OpenCL/vendors}
NVCL=$({ "$LDCONFIG" -p 2>/dev/null | awk '/libnvidia-opencl\.so\.1 / {print $NF}'
    ls /usr/local/nvidia/lib64/libnvidia-opencl.so.1 /usr/lib/x86_64-linux-gnu/libnvidia-opencl.so.1 2>/dev/null; } | head -1)
if [ -n "$NVCL" ] && ! cat "$VENDORS"/*.icd 2>/dev/null | grep -q nvidia; then
    mkdir -p "$W/vendors"
    echo "$NVCL" >"$W/vendors/nvidia.icd"
    export OCL_ICD_VENDORS=$W/vendors
    VENDORS=$W/vendors
fi
ls "$VENDORS"/*.icd >/dev/null 2>&1 && ICD=$(cat "$VENDORS"/*.icd 2>/dev/null | tr '\n' ' ')
# The NVIDIA platform on a GPU machine when its ICD is there (else the
# OpenCL parts run on whatever platform is, and say which).
if [ "$HOST" != 1 ] && echo "$ICD" | grep -q nvidia; then export CAPDEM_OPENCL_PLATFORM=${CAPDEM_OPENCL_PLATFORM:-NVIDIA}; fi

# ---------------------------------------------------------------- parts
part_info() {
    {
        echo "== bundle"; sed -n '1,/^$/p' "$B/MANIFEST.txt"
        echo "== machine"; date -u; uname -a; ldd --version 2>&1 | head -1; nproc
        echo "C++ runtime used: $CXXNOTE"; echo "OpenCL ICDs ($VENDORS): ${ICD:-none}; libnvidia-opencl: ${NVCL:-not found}"
        echo "compute-sanitizer: $(command -v compute-sanitizer || ls /usr/local/cuda/bin/compute-sanitizer 2>/dev/null || echo none)"
        echo "nsys: $(command -v nsys || echo none); ncu: $(command -v ncu || echo none)"
        echo "== nvidia-smi"; nvidia-smi 2>&1 || echo "nvidia-smi: not available"
        nvidia-smi --query-gpu=name,memory.total,driver_version,clocks.max.sm,clocks.max.mem --format=csv 2>&1
        command -v nvcc >/dev/null && nvcc --version | tail -2
        for v in $VARIANTS; do
            echo "== ldd bin/$v/capdem"; ldd "$BIN/$v/capdem"
        done
        echo "== ldd of the offload plugins"
        for f in "$R"/lib/libomptarget.rtl.cuda.nextgen.so.16 "$R"/lib/libgomp-plugin-nvptx.so.1; do [ -e "$f" ] && ldd "$f"; done
    } >>"$INFO" 2>&1
    for v in $VARIANTS; do
        step "version_$v" 30 bash -c "'$BIN/$v/capdem' --version; [ '$HOST' = 1 ] || '$BIN/$v/capdem' --version | grep -Eq ', [1-9][0-9]* offload device'"
        { echo "== capdem --version ($v, OMP_TARGET_OFFLOAD=$OMP_TARGET_OFFLOAD)"; cat "$LOGS/version_$v.log"; } >>"$INFO"
    done
    # Clang 16's runtime tries its "nextgen" CUDA plugin first; should that
    # one see no device under this driver, say why and try the older plugin
    # for the rest of the run.
    if [ "$HOST" != 1 ] && has clang && grep -q '^FAIL.* version_clang' "$SUMMARY"; then
        {
            echo "== clang build sees no device: LIBOMPTARGET_INFO=-1, then the older plugin"
            LIBOMPTARGET_INFO=-1 timeout 30 "$BIN/clang/capdem" --version 2>&1 | head -50
            LIBOMPTARGET_NEXTGEN_PLUGINS=0 timeout 30 "$BIN/clang/capdem" --version 2>&1
        } >>"$INFO"
        if LIBOMPTARGET_NEXTGEN_PLUGINS=0 timeout 30 "$BIN/clang/capdem" --version 2>&1 | grep -Eq ', [1-9][0-9]* offload device'; then
            export LIBOMPTARGET_NEXTGEN_PLUGINS=0
            note "NOTE clang: the nextgen CUDA plugin saw no device, the older one does: LIBOMPTARGET_NEXTGEN_PLUGINS=0 from here on"
        fi
    fi
    # Kernel launches, once per build: a few steps of a small case.
    local small=(--case hexapods_a3 --n 300 --settle-steps 20 --steps 10 --repeat 1)
    if has clang; then
        # 0x10: the plugin's line per launch (kernel, SPMD/generic mode,
        # blocks x threads); 0x20: every host<->device copy.
        step launches_clang 60 env LIBOMPTARGET_INFO=$((0x10 | 0x20)) "$BIN/clang/capdem-bench" "${small[@]}"
        {
            echo "== launches, clang (LIBOMPTARGET_INFO=0x30; capdem-bench ${small[*]})"
            echo "kernel launches: $(grep -c 'Launching kernel' "$LOGS/launches_clang.log")"
            grep 'Launching kernel' "$LOGS/launches_clang.log" | sed 's/.*Launching kernel //' | sort | uniq -c | sort -rn | head -20
            echo "copies: $(grep -c -i 'copying data' "$LOGS/launches_clang.log") lines"
            # per direction, with bytes (docs/offload.md, "Per-step copies")
            awk '/[Cc]opying data from host to device/ {n++; if (match($0, /Size=[0-9]+/)) b += substr($0, RSTART + 5, RLENGTH - 5)}
                 /[Cc]opying data from device to host/ {m++; if (match($0, /Size=[0-9]+/)) c += substr($0, RSTART + 5, RLENGTH - 5)}
                 END {printf "host to device: %d copies, %d B; device to host: %d copies, %d B\n", n, b, m, c}' "$LOGS/launches_clang.log"
        } >>"$INFO"
        [ "$HOST" = 1 ] || grep -q 'Launching kernel' "$LOGS/launches_clang.log" || note "FAIL launches_clang: no kernel launched on a device (LIBOMPTARGET_INFO)"
    fi
    if has gcc; then
        step launches_gcc 60 env GOMP_DEBUG=1 "$BIN/gcc/capdem-bench" "${small[@]}"
        {
            echo "== launches, gcc (GOMP_DEBUG=1)"
            echo "kernel launches: $(grep -c 'GOMP_OFFLOAD_run: kernel' "$LOGS/launches_gcc.log")"
            grep -E 'GOMP_OFFLOAD_run|nvptx_exec|launch' "$LOGS/launches_gcc.log" | sed 's/0x[0-9a-f]*/0x_/g' | sort | uniq -c | sort -rn | head -20
        } >>"$INFO"
        # GCC 12 runs on the host when it finds no GPU, even under MANDATORY.
        [ "$HOST" = 1 ] || grep -q 'GOMP_OFFLOAD_run' "$LOGS/launches_gcc.log" || note "FAIL launches_gcc: no kernel launched on a device (GOMP_DEBUG)"
        head -c 2000000 "$LOGS/launches_gcc.log" >"$LOGS/launches_gcc.log.cut" && mv "$LOGS/launches_gcc.log.cut" "$LOGS/launches_gcc.log"
    fi
}

# Runs the test programs of a variant, JOBS at a time, each in its own folder.
run_tests() { # variant backend label tests...
    local v=$1 be=$2 label=$3 t s
    shift 3
    has "$v" || { note "SKIP $label: no $v build in the bundle"; return 0; }
    local d=$W/$label t0=$SECONDS cap
    cap=$(($(left) - 10))
    # A hung test must not eat the ladder's time: CAPDEM_BUNDLE_TESTS_CAP
    # (default 240 s) bounds a whole test part.
    [ "$cap" -gt "${CAPDEM_BUNDLE_TESTS_CAP:-240}" ] && cap=${CAPDEM_BUNDLE_TESTS_CAP:-240}
    if [ "$cap" -lt 30 ]; then note "SKIP(no time) $label"; return 0; fi
    mkdir -p "$d"
    # On a GPU the tests share one device, and CUDA contexts of separate
    # processes take turns on it: the H100 runs with 4 and 16 tests at a
    # time left tests unfinished in 300 s that need 3-50 s alone by their
    # launches and copies (docs/gpu_bundle.md, "The test part on a GPU"), so
    # there they run CAPDEM_BUNDLE_GPU_JOBS at a time, shortest first.
    local jobs=$JOBS
    [ "$HOST" = 1 ] || jobs=${CAPDEM_BUNDLE_GPU_JOBS:-1}
    printf '%s\n' "$@" | CAPDEM_BUNDLE_TEST_TIMEOUT=$((cap < 300 ? cap : 300)) \
        timeout -k 5 "$cap" xargs -P "$jobs" -I{} bash "$B/run_on_gpu.sh" _test "$BIN/$v" {} "$d/{}" "$be"
    for t in "$@"; do
        if [ -e "$d/$t/status" ]; then s=$(cat "$d/$t/status"); else s="TIMEOUT $t (not finished)"; fi
        note "${s%% *} $label/${s#* }"
        case $s in PASS*) ;; *) { echo "== $label/$t"; tail -40 "$d/$t/log" 2>/dev/null; } >>"$LOGS/failures.log" ;; esac
        cp "$d/$t/log" "$LOGS/$label.$t.log" 2>/dev/null
    done
    note "-- $label took $((SECONDS - t0))s"
}
# Estimated seconds of each test program on a GPU alone, bound by launch
# and copy latency (bench/gpu/test_launches.sh on the clang-14 host-offload
# build: launches x 8 us + copies x 10 us; docs/gpu_bundle.md, "The test
# part on a GPU"); programs not listed step little.  The test part starts
# them shortest first, so that a capped call reports as many as it can.
GPU_ESTIMATE_S="test_pair_output:1 test_wall_out:3 test_coulomb_sliding:3 test_hertz_mindlin:4 test_reorder:6 test_determinism:7 test_rest:8 test_conservation:10 test_rotation_order:48 test_protocols:83"
by_estimate() { # test programs -> the same, shortest estimate first (unlisted first, in name order)
    local t e
    for t in "$@"; do
        e=$(printf '%s\n' $GPU_ESTIMATE_S | sed -n "s/^$t:\([0-9]*\)$/\1/p")
        echo "${e:-0} $t"
    done | sort -s -n -k1,1 | cut -d' ' -f2
}
# shellcheck disable=SC2046
ALL_TESTS=$(by_estimate $(cd "$BIN/$(echo "$VARIANTS" | head -1)" && ls test_* | grep -vE '^test_(parity|drift_bound|mpm_.*)$' | grep -E "${CAPDEM_BUNDLE_ONLY:-.}"))
part_tests() { # variant
    # shellcheck disable=SC2086
    run_tests "$1" omp "tests-$1" $ALL_TESTS
}

# The material point method: tests, OpenCL against the host, throughput.
# The mpm test programs of the build and the shell tests of tests/mpm
# (label mpm) but test_mpm_plots and test_mpm_render (matplotlib, which
# the GPU machines lack).
MPM_TESTS=$( (cd "$BIN/$(echo "$VARIANTS" | head -1)" && ls test_mpm_* 2>/dev/null)
    for f in "$B"/src/tests/mpm/test_mpm_*.sh; do [ -e "$f" ] && basename "$f" .sh; done | grep -vE '^test_mpm_(plots|render)$')
# One throughput run of the full-size compaction: mpm_rate VARIANT BACKEND
# (the settled deposit of configs/mpm/deposit_disks.yaml travels as
# inputs/deposit_disks.h5; the progress line's rate is over the run's
# steps, snapshots included, and is what the JSON line reports).
mpm_rate() {
    local v=$1 be=$2 d=$W/mpm-rate-$2 n rate gpu dev=()
    [ "$be" = opencl ] && dev=(--device gpu)
    [ "$HOST" = 1 ] && dev=()
    mkdir -p "$d" && ln -sf "$INPUTS/deposit_disks.h5" "$d/deposit_disks.h5"
    step "mpm_rate_$be" "${CAPDEM_BUNDLE_MPM_RATE_CAP:-60}" bash -c "cd '$d' && '$BIN/$v/capdem' run '$B/src/configs/mpm/packing_elastic.yaml' \
        --steps '${CAPDEM_BUNDLE_MPM_STEPS:-200}' --backend $be ${dev[*]} --output rate.h5 --overwrite; rc=\$?; rm -f rate.h5; exit \$rc"
    n=$(sed -n 's/^capdem: mpm: \([0-9]*\) material points.*/\1/p' "$LOGS/mpm_rate_$be.log" | head -1)
    rate=$(grep -o '[0-9.e+-]* point-steps/s' "$LOGS/mpm_rate_$be.log" | tail -1 | cut -d' ' -f1)
    gpu=$(nvidia-smi --query-gpu=name --format=csv,noheader 2>/dev/null | head -1)
    [ -n "$n" ] && [ -n "$rate" ] || return 0
    printf '{"build": "%s", "gpu": "%s", "entry": "mpm_packing_elastic", "backend": "%s", "N": %s, "steps": %s, "point_steps_per_s": %s, "particle_steps_per_s": %s, "device": "%s"}\n' \
        "$v" "${gpu:-none}" "$be" "$n" "${CAPDEM_BUNDLE_MPM_STEPS:-200}" "$rate" "$rate" \
        "$(sed -n 's/.*backend [a-z]* on \(.*\), output .*/\1/p' "$LOGS/mpm_rate_$be.log" | head -1 | tr -d '"')" >>"$W/ladder.jsonl"
}
part_mpm() {
    local v=clang
    has "$v" || v=$(echo "$VARIANTS" | head -1)
    # shellcheck disable=SC2086
    CAPDEM_BUNDLE_TESTS_CAP=${CAPDEM_BUNDLE_MPM_CAP:-150} run_tests "$v" omp "mpm-$v" $MPM_TESTS
    if [ -n "$ICD" ] && [ -e "$B/src/tests/mpm/opencl_same_bits.sh" ]; then
        # omp on the host (one thread: LLVM 16's host fallback, see
        # CAPDEM_BUNDLE_HOST) against OpenCL on the GPU: the MPM step is
        # sqrt, +, -, *, / only, rounded alike everywhere, so the same bits
        step mpm_opencl_same_bits 90 env OMP_TARGET_OFFLOAD=DISABLED OMP_NUM_THREADS=1 bash -c "mkdir -p '$W/mpm-cl' && cd '$W/mpm-cl' && bash '$B/src/tests/mpm/opencl_same_bits.sh' '$BIN/$v/capdem' '$B/src'"
    else
        note "SKIP mpm_opencl_same_bits: no OpenCL ICD, or no tests/mpm in the bundle"
    fi
    if [ -e "$INPUTS/deposit_disks.h5" ]; then
        local be
        for be in ${CAPDEM_BUNDLE_MPM_BACKENDS:-omp opencl}; do
            [ "$be" = opencl ] && [ -z "$ICD" ] && { note "SKIP mpm_rate_opencl: no OpenCL ICD"; continue; }
            mpm_rate "$v" "$be"
        done
    else
        note "SKIP mpm_rate: no inputs/deposit_disks.h5 in the bundle"
    fi
    return 0
}

part_opencl() {
    if [ -z "$ICD" ]; then note "SKIP opencl: no OpenCL ICD (no /etc/OpenCL/vendors/*.icd, no libnvidia-opencl.so.1)"; return 0; fi
    # The Clang build on a GPU (its omp side then runs there too).  Without
    # one the GCC build: a Clang build loads libLLVM-16 (libomptarget), and
    # with PoCL's libLLVM-15 in the same process it crashed here.
    local v=${CAPDEM_BUNDLE_CL_BUILD:-clang}
    [ "$HOST" = 1 ] && v=${CAPDEM_BUNDLE_CL_BUILD:-gcc}
    has "$v" || v=$(echo "$VARIANTS" | head -1)
    step "opencl_version" 30 "$BIN/$v/capdem-bench" --case spheres --n 200 --settle-steps 10 --steps 10 --repeat 1 --backend opencl --device "${CAPDEM_BUNDLE_CL_DEVICE:-auto}"
    { echo "== OpenCL (ICD: $ICD; CAPDEM_OPENCL_PLATFORM=${CAPDEM_OPENCL_PLATFORM:-})"; cat "$LOGS/opencl_version.log"; } >>"$INFO"
    # test_parity: omp against OpenCL; with the omp side on the host first
    # (the documented bitwise parity), then with it on the GPU.
    # (one host thread: LLVM 16's host fallback with several aborts, see
    # CAPDEM_BUNDLE_HOST above; the first GPU machine's 16 threads did)
    step parity_omp_host 300 env OMP_TARGET_OFFLOAD=DISABLED OMP_NUM_THREADS=1 bash -c "mkdir -p '$W/parity-host' && cd '$W/parity-host' && '$BIN/$v/test_parity'"
    [ "$HOST" = 1 ] || step parity_omp_gpu 300 bash -c "mkdir -p '$W/parity-gpu' && cd '$W/parity-gpu' && '$BIN/$v/test_parity'"
    # test_drift_bound: host maths (omp on the host) against the GPU's
    # (OpenCL on it), trajectories within k sum S (docs/offload.md, "Which
    # maths can differ"); its line gives the measured difference and bound.
    step drift_host_gpu 200 env OMP_TARGET_OFFLOAD=DISABLED OMP_NUM_THREADS=1 bash -c "mkdir -p '$W/drift' && cd '$W/drift' && '$BIN/$v/test_drift_bound'"
    # shellcheck disable=SC2046
    run_tests "$v" opencl "opencl-$v" $(printf '%s\n' $ALL_TESTS | grep -E '^test_(binary_collision|conservation|coulomb_sliding|plane2d|rest|determinism|neighbors)$')
}

# One ladder entry: ladder_entry VARIANT NAME FILE TILE RELAX STEPS REPEAT CAP
ladder_entry() {
    local v=$1 name=$2 file=$3 tile=$4 relax=$5 steps=$6 rep=$7 cap=$8 be=omp gpu
    [ -n "$ICD" ] && [ "$HOST" != 1 ] && be=omp,opencl
    gpu=$(nvidia-smi --query-gpu=name --format=csv,noheader 2>/dev/null | head -1)
    step "ladder_${v}_$name" "$cap" "$BIN/$v/capdem-bench" --load-settled "$INPUTS/$file" --tile "$tile" \
        --relax-steps "$relax" --steps "$steps" --repeat "$rep" --backend "$be" --device gpu
    # capdem-bench prints one JSON object per line: tag each with the build,
    # the GPU and the entry, keep every line (also those of a failed entry).
    grep '^{' "$LOGS/ladder_${v}_$name.log" |
        sed "s/^{/{\"build\": \"$v\", \"gpu\": \"${gpu:-none}\", \"entry\": \"$name\", \"tile\": \"$tile\", \"relax_steps\": $relax, /" >>"$W/ladder.jsonl"
}
part_ladder() { # variant
    local v=$1 e s hex sph mix
    has "$v" || { note "SKIP ladder-$v: no $v build"; return 0; }
    hex=$(cd "$INPUTS" && ls hexapods_a3_n*.h5 | head -1)
    sph=$(cd "$INPUTS" && ls spheres_n*.h5 | head -1)
    mix=$(cd "$INPUTS" && ls mix_spheres_hexapods_n*.h5 2>/dev/null | head -1) || true
    s=${CAPDEM_BUNDLE_STEPS:-200}
    # Copies of the settled packing (KX,KZ) for 1e4, 1e5 and 1e6 particles:
    # gpu_bundle.sh settles 1e3 (default) or 1e4.
    local n t4 t5 t6
    n=$(echo "$hex" | sed 's/.*_n\([0-9]*\)\.h5/\1/')
    case $n in
    1000) t4=5,2 t5=10,10 t6=40,25 ;;
    10000) t4=1,1 t5=5,2 t6=10,10 ;;
    *) [ -n "${CAPDEM_BUNDLE_TILES:-}" ] || { note "FAIL ladder-$v: no tile factors for settled packings of $n particles (1000 or 10000; or set CAPDEM_BUNDLE_TILES)"; return 0; } ;;
    esac
    [ -z "${CAPDEM_BUNDLE_TILES:-}" ] || read -r t4 t5 t6 <<<"$CAPDEM_BUNDLE_TILES"
    for e in ${CAPDEM_BUNDLE_LADDER:-h1e4 h1e5 h1e6 s1e6 m1e5}; do
        case $e in
        h1e4) ladder_entry "$v" hex_1e4 "$hex" $t4 1000 "$s" 3 90 ;;
        h1e5) ladder_entry "$v" hex_1e5 "$hex" $t5 1000 "$s" 3 150 ;;
        h1e6) ladder_entry "$v" hex_1e6 "$hex" $t6 300 $((s / 2)) 2 240 ;;
        s1e6) ladder_entry "$v" sph_1e6 "$sph" $t6 300 $((s / 2)) 2 200 ;;
        m1e5) # the mixture: its rows visited by kind (a bundle made before session 18 has none)
            if [ -n "$mix" ]; then ladder_entry "$v" mix_1e5 "$mix" $t5 1000 "$s" 3 150; else note "SKIP ladder-$v mix_1e5: no settled mixture among the inputs"; fi ;;
        *) note "FAIL ladder: unknown entry '$e' (h1e4 h1e5 h1e6 s1e6 m1e5)" ;;
        esac
    done
}

part_profile() {
    has clang || { note "SKIP profile: no clang build"; return 0; }
    local hex args tile
    hex=$(cd "$INPUTS" && ls hexapods_a3_n*.h5 | head -1)
    case $hex in *_n1000.h5) tile=40,25 ;; *) tile=10,10 ;; esac # 1e6 particles
    tile=${CAPDEM_BUNDLE_PROFILE_TILE:-$tile}
    args=(--load-settled "$INPUTS/$hex" --tile $tile --relax-steps 10 --steps 40 --repeat 1 --device gpu)
    # libomptarget's own trace (Chrome trace JSON), always there: LLVM 16
    # keeps per-call events only above 500 us (so 1e6 particles, where a
    # launch, synchronous without nowait, lasts that long) with their source
    # line, and a "Total" per runtime call (count, time) for all.
    step profile_omptarget 120 env LIBOMPTARGET_PROFILE="$W/omptarget_profile.json" "$BIN/clang/capdem-bench" "${args[@]}"
    {
        echo "== LIBOMPTARGET_PROFILE, clang, hexapods tiled $tile, 10+40 steps (host-side spans: total, count, mean)"
        python3 - "$W/omptarget_profile.json" <<'EOF' 2>&1
import json, sys, collections
ev = json.load(open(sys.argv[1]))
ev = ev.get("traceEvents", ev) if isinstance(ev, dict) else ev
tot = collections.defaultdict(lambda: [0.0, 0])
for e in ev:
    if e.get("ph") != "X": continue
    a = e.get("args", {})
    key = e.get("name", "?") + " | " + str(a.get("detail", ""))[:90]
    tot[key][0] += e.get("dur", 0); tot[key][1] += a.get("count", 1) # "Total X" events carry their count
for k, (d, n) in sorted(tot.items(), key=lambda kv: -kv[1][0])[:40]:
    print(f"{d/1e3:12.1f} ms {n:8d} {d/max(n,1):10.1f} us  {k}")
EOF
    } >>"$PROFILE"
    if command -v nsys >/dev/null; then
        step profile_nsys 200 nsys profile --force-overwrite true -o "$W/capdem" --stats=true "$BIN/clang/capdem-bench" "${args[@]}"
        { echo "== nsys --stats (clang, 1e6)"; grep -v '^{' "$LOGS/profile_nsys.log" | head -300; } >>"$PROFILE"
    elif command -v ncu >/dev/null; then
        # Every kernel's time over the first launches (--launch-count), summed
        # per kernel (source line), then DRAM bytes of 24 launches after the
        # warm-up: where a step's time goes, and the bytes moved per
        # particle-step against the bandwidth bound.
        step profile_ncu_time 200 ncu --launch-count "${CAPDEM_BUNDLE_NCU_LAUNCHES:-1500}" --metrics gpu__time_duration.sum --csv \
            "$BIN/clang/capdem-bench" "${args[@]}"
        {
            echo "== ncu kernel time (clang, tile $tile; first ${CAPDEM_BUNDLE_NCU_LAUNCHES:-1500} launches), summed per kernel"
            python3 - "$LOGS/profile_ncu_time.log" <<'EOF' 2>&1
import csv, sys, collections
rows = [l for l in open(sys.argv[1], errors="replace") if l.startswith('"')]
tot = collections.defaultdict(lambda: [0.0, 0])
for r in csv.DictReader(rows):
    if r.get("Metric Name") != "gpu__time_duration.sum": continue
    v = float(r["Metric Value"].replace(",", "")) * {"nsecond": 1e-3, "ns": 1e-3, "usecond": 1, "us": 1, "msecond": 1e3, "ms": 1e3, "second": 1e6, "s": 1e6}.get(r["Metric Unit"], 1)
    k = r["Kernel Name"][:90]
    tot[k][0] += v; tot[k][1] += 1
all_us = sum(t for t, n in tot.values())
print(f"{all_us/1e3:.1f} ms in {sum(n for t, n in tot.values())} launches")
for k, (t, n) in sorted(tot.items(), key=lambda kv: -kv[1][0])[:40]:
    print(f"{t/1e3:10.2f} ms {n:6d} {t/n:10.1f} us  {k}")
EOF
        } >>"$PROFILE"
        step profile_ncu 200 ncu --launch-skip 200 --launch-count 24 --metrics gpu__time_duration.sum,dram__bytes_read.sum,dram__bytes_write.sum \
            "$BIN/clang/capdem-bench" "${args[@]}"
        { echo "== ncu (clang, tile $tile; 24 launches after 200)"; grep -v '^{' "$LOGS/profile_ncu.log" | head -400; } >>"$PROFILE"
    else
        note "SKIP profile_nsys: neither nsys nor ncu on PATH"
    fi
}

# Per-kernel registers, occupancy and local memory of the omp offload
# build against OpenCL's (docs/performance.md, "The omp offload kernels on
# sm_90, read from the compiler"), into profile.txt; without a GPU
# (CAPDEM_BUNDLE_HOST=1) its dry run: arguments, tools, the table's parser.
part_kernels() {
    has clang || { note "SKIP kernels: no clang build"; return 0; }
    local hex tile dry=()
    hex=$(cd "$INPUTS" && ls hexapods_a3_n*.h5 | head -1)
    case $hex in *_n1000.h5) tile=10,10 ;; *) tile=1,10 ;; esac # 1e5 particles
    [ "$HOST" = 1 ] && dry=(--dry-run)
    [ -n "$ICD" ] || note "NOTE kernels: no OpenCL ICD: its opencl run will fail"
    step kernels "${CAPDEM_BUNDLE_KERNELS_CAP:-125}" env CAPDEM_KERNELS_TILE="${CAPDEM_KERNELS_TILE:-$tile}" \
        bash "$B/kernel_profile.sh" "${dry[@]}" "$BIN/clang/capdem-bench" "$INPUTS/$hex" "$W/kernels"
    { echo "== kernels (bench/gpu/kernel_profile.sh, clang build and OpenCL, hexapods tiled ${CAPDEM_KERNELS_TILE:-$tile})"
        grep -v '^"' "$LOGS/kernels.log" | grep -v '^==PROF==' | head -300; } >>"$PROFILE"
    mkdir -p "$LOGS/kernels" && cp "$W"/kernels/* "$LOGS/kernels/" 2>/dev/null
}

# compute-sanitizer's memcheck on a few steps of the Clang build (the first
# GPU run met an illegal address at 1e6 hexapods, reorder.c, the cell keys):
# the faulting kernel, source line and address.
part_sanitize() {
    has clang || { note "SKIP sanitize: no clang build"; return 0; }
    local cs hex tile
    cs=$(command -v compute-sanitizer || ls /usr/local/cuda/bin/compute-sanitizer 2>/dev/null | head -1)
    [ -n "$cs" ] || { note "SKIP sanitize: no compute-sanitizer"; return 0; }
    hex=$(cd "$INPUTS" && ls hexapods_a3_n*.h5 | head -1)
    tile=${CAPDEM_BUNDLE_SANITIZE_TILE:-40,25}
    step sanitize_memcheck "${CAPDEM_BUNDLE_SANITIZE_CAP:-240}" "$cs" --tool memcheck --print-limit 20 --error-exitcode 99 \
        "$BIN/clang/capdem-bench" --load-settled "$INPUTS/$hex" --tile "$tile" --relax-steps 2 --steps 2 --repeat 1 --device gpu
    { echo "== compute-sanitizer memcheck (clang, hexapods tiled $tile)"; grep -v '^{' "$LOGS/sanitize_memcheck.log" | head -150; } >>"$PROFILE"
}

# ------------------------------------------------------------------ main
[ $# -gt 0 ] || set -- all
PARTS=()
for p in "$@"; do
    case $p in
    # The ladder before OpenCL: the throughput figures are what a first
    # call on a GPU is for, after the tests that say they can be trusted.
    all) PARTS+=(info tests-clang ladder-clang opencl profile tests-gcc) ;;
    quick) PARTS+=(info tests-clang ladder) ;;
    tests) PARTS+=(tests-clang) ;;
    ladder) PARTS+=(ladder-clang) ;;
    info | tests-clang | tests-gcc | opencl | ladder-clang | ladder-gcc | profile | kernels | sanitize | mpm) PARTS+=("$p") ;;
    *) echo "run_on_gpu.sh: unknown part '$p' (info tests tests-gcc opencl ladder ladder-gcc profile kernels sanitize mpm all quick)" >&2; exit 2 ;;
    esac
done
note "capdem GPU bundle: parts ${PARTS[*]}; OMP_TARGET_OFFLOAD=$OMP_TARGET_OFFLOAD; budget ${BUDGET}s; $(nvidia-smi -L 2>/dev/null | head -1 || true)"
for p in "${PARTS[@]}"; do
    case $p in
    info) part_info ;;
    tests-clang) part_tests clang ;;
    tests-gcc) part_tests gcc ;;
    opencl) part_opencl ;;
    ladder-clang) part_ladder clang ;;
    ladder-gcc) part_ladder gcc ;;
    profile) part_profile ;;
    kernels) part_kernels ;;
    sanitize) part_sanitize ;;
    mpm) part_mpm ;;
    esac
done

# ----------------------------------------------------------- summary
fails=$(grep -cE '^(FAIL|TIMEOUT)' "$SUMMARY")
passes=$(grep -c '^PASS' "$SUMMARY")
note "== summary: $passes passed, $fails failed or timed out, $(grep -c '^SKIP' "$SUMMARY") skipped, $((SECONDS - T0))s"
if [ -s "$W/ladder.jsonl" ]; then
    python3 - "$W/ladder.jsonl" <<'EOF' 2>&1 | tee -a "$SUMMARY"
import json, sys
for line in open(sys.argv[1]):
    r = json.loads(line)
    unit = "point-steps/s" if "point_steps_per_s" in r else "particle-steps/s"
    print("ladder %s %-8s %-6s N=%8d %.3g %s (%s)" % (r["build"], r["entry"], r["backend"], r["N"],
          r["particle_steps_per_s"], unit, r.get("device", "")))
EOF
fi
# At most 6 files come back (the device tool returns 8).
cp "$SUMMARY" "$INFO" "$PROFILE" "$OUT/"
[ -s "$W/ladder.jsonl" ] && cp "$W/ladder.jsonl" "$OUT/"
[ -s "$W/omptarget_profile.json" ] && gzip -c "$W/omptarget_profile.json" | head -c 15000000 >"$OUT/omptarget_profile.json.gz"
tar -C "$W" -czf "$OUT/logs.tar.gz" logs
[ "$fails" = 0 ]
