#!/usr/bin/env bash
# Builds the GPU bundle (docs/gpu_bundle.md): one self-contained folder that
# runs capdem's offload builds, tests and throughput ladder on a machine
# that has only the NVIDIA driver and CUDA (no Debian packages, no network,
# one folder of at most 64 MiB per command).
#
#   bench/gpu_bundle.sh [--work DIR] [--out DIR] [--no-gcc] [--no-clang]
#                       [--settled-n N] [--resettle] [--no-check]
#
# --work   build folder (default <repo>/build-gpu): the private LLVM 16
#          OpenMP prefix, the CMake builds, the settled packings (kept:
#          settling 1e4 hexapods costs minutes of this machine)
# --out    the bundle (default <work>/bundle; must be inside the repository
#          and ignored by git to travel with the device tool's `carry`)
# --no-gcc / --no-clang  leave one offload build out
# --settled-n N  particles of each settled packing: 1000 (default; about a
#                CPU-minute each here) or 10000 (20-40 CPU-minutes of hexapods)
# --resettle     settle again even when the packings exist
# --no-check     skip bench/gpu/check_bundle.sh at the end
#
# Needs here: clang-16 and clang-tools-16 (apt; they do not pull
# libomp-16-dev), gcc-offload-nvptx (for the GCC build), the CUDA toolkit at
# /usr/local/cuda (clang's ptxas/nvlink), the capdem build dependencies,
# apt-get download access (libomp-16-dev and libomp5-16 are unpacked into
# the work folder, never installed: libomp-16-dev conflicts with the
# libomp-14-dev that CI's host-device offload job needs), xz.
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
WORK=$ROOT/build-gpu
OUT=
WANT_GCC=1
WANT_CLANG=1
SETTLED_N=1000
RESETTLE=0
CHECK=1
while [ $# -gt 0 ]; do
    case $1 in
    --work) WORK=$(realpath -m "$2"); shift 2 ;;
    --out) OUT=$(realpath -m "$2"); shift 2 ;;
    --no-gcc) WANT_GCC=0; shift ;;
    --no-clang) WANT_CLANG=0; shift ;;
    --settled-n) SETTLED_N=$2; shift 2 ;;
    --resettle) RESETTLE=1; shift ;;
    --no-check) CHECK=0; shift ;;
    -h | --help) sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//'; exit 0 ;;
    *) echo "gpu_bundle.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
    esac
done
[ -n "$OUT" ] || OUT=$WORK/bundle
[ $WANT_GCC = 1 ] || [ $WANT_CLANG = 1 ] || { echo "gpu_bundle.sh: --no-gcc and --no-clang leave nothing to build" >&2; exit 2; }
JOBS=${JOBS:-2} # the development machine has 2 cores shared by several people
say() { printf '\n== %s\n' "$*" >&2; }
die() { echo "gpu_bundle.sh: $*" >&2; exit 1; }
mkdir -p "$WORK"

# ---------------------------------------------------------------- tools
CUDA=${CUDA_PATH:-/usr/local/cuda}
[ -x "$CUDA/bin/ptxas" ] || die "no CUDA toolkit at $CUDA (set CUDA_PATH): clang-16 needs its ptxas and nvlink"
if [ $WANT_CLANG = 1 ]; then
    command -v clang-16 >/dev/null || die "clang-16 missing: apt-get install clang-16 clang-tools-16 (check with -s that it does not pull libomp-16-dev)"
    [ -x /usr/lib/llvm-16/bin/clang-offload-packager ] || die "clang-offload-packager missing: apt-get install clang-tools-16"
fi
if [ $WANT_GCC = 1 ]; then
    [ -x "$(gcc -print-prog-name=mkoffload 2>/dev/null)" ] || ls /usr/lib/gcc/x86_64-linux-gnu/*/accel/nvptx-none/mkoffload >/dev/null 2>&1 ||
        die "GCC nvptx offload compiler missing: apt-get install gcc-offload-nvptx (or pass --no-gcc)"
    [ -e /usr/lib/x86_64-linux-gnu/libgomp-plugin-nvptx.so.1 ] || die "libgomp-plugin-nvptx.so.1 missing (gcc-offload-nvptx)"
fi
command -v xz >/dev/null || die "xz missing (xz-utils)"

# ----------------------------------------- LLVM 16 OpenMP, private prefix
# libomp-16-dev holds libomptarget, its CUDA plugins and the nvptx device
# runtime; libomp5-16 holds libomp.so.5.  Unpacked, not installed (see top).
LLVM=$WORK/llvm16/usr/lib/llvm-16/lib
if [ $WANT_CLANG = 1 ] && [ ! -e "$LLVM/libomptarget-nvptx-sm_90.bc" ]; then
    say "unpacking libomp-16-dev and libomp5-16 into $WORK/llvm16"
    mkdir -p "$WORK/debs"
    (cd "$WORK/debs" && apt-get download libomp-16-dev libomp5-16) || die "apt-get download libomp-16-dev libomp5-16 failed"
    rm -rf "$WORK/llvm16"
    for d in "$WORK"/debs/libomp-16-dev_*.deb "$WORK"/debs/libomp5-16_*.deb; do dpkg -x "$d" "$WORK/llvm16"; done
    [ -e "$LLVM/libomptarget.so.16" ] && [ -e "$LLVM/libomptarget.rtl.cuda.nextgen.so.16" ] || die "unpacked LLVM prefix lacks libomptarget"
fi

# ---------------------------------------------------------------- builds
# The test programs that matter on a GPU (physics, regression, protocols
# with its resume cases, the omp/OpenCL parity test) and the cheap unit and
# config tests; analysis is host-only code.
TESTS=()
for d in physics regression protocols unit config mpm; do
    for f in "$ROOT"/tests/$d/test_*.c; do TESTS+=("$(basename "$f" .c)"); done
done
TESTS+=(test_parity test_drift_bound)

# CMAKE_SKIP_RPATH: no path of this machine may be baked into a binary that
# travels (the bundle sets LD_LIBRARY_PATH to its own lib folder).
build() { # name cmake-args...
    local name=$1; shift
    say "building the $name offload variant in $WORK/$name"
    nice cmake -S "$ROOT" -B "$WORK/$name" -DCMAKE_BUILD_TYPE=Release -DCAPDEM_OFFLOAD=nvptx -DCMAKE_SKIP_RPATH=ON "$@" >"$WORK/$name.configure.log" 2>&1 ||
        { tail -30 "$WORK/$name.configure.log" >&2; die "configure of $name failed (log: $WORK/$name.configure.log)"; }
    nice cmake --build "$WORK/$name" -j"$JOBS" --target capdem capdem-bench "${TESTS[@]}" >"$WORK/$name.build.log" 2>&1 ||
        { grep -E 'error|Error' "$WORK/$name.build.log" | head -30 >&2; die "build of $name failed (log: $WORK/$name.build.log)"; }
}
VARIANTS=()
if [ $WANT_CLANG = 1 ]; then
    # Clang 16 maps OpenMP threads to GPU lanes (SPMD kernels), the build the
    # issue asks for.  omp.h and the device runtime come from the private
    # prefix; FindOpenMP is told where libomp is, since it is not installed.
    # -gline-tables-only: source locations in libomptarget's messages and
    # profile (kernels named by line); no effect on the generated code.
    CC=clang-16 build clang \
        -DCMAKE_C_FLAGS="-gline-tables-only -I$LLVM/clang/16/include --libomptarget-nvptx-bc-path=$LLVM/libomptarget-nvptx-sm_90.bc --cuda-path=$CUDA -Wno-unknown-cuda-version" \
        -DCMAKE_EXE_LINKER_FLAGS="-L$LLVM --cuda-path=$CUDA" \
        -DOpenMP_C_FLAGS=-fopenmp -DOpenMP_C_LIB_NAMES=omp -DOpenMP_omp_LIBRARY="$LLVM/libomp.so"
    VARIANTS+=(clang)
fi
if [ $WANT_GCC = 1 ]; then
    # GCC 12 nvptx (sm_80, JIT to Hopper by the driver): one warp per OpenMP
    # thread, kept for comparison and as the fallback if Clang's fails there.
    CC=gcc build gcc
    VARIANTS+=(gcc)
fi

# ------------------------------------------------------ settled packings
# Settled here once (host fallback of an offload build: no GPU here), tiled
# there with --load-settled --tile.  A packing settled under 50 g is timed
# under the same load (docs/performance.md).
SETTLED=$WORK/settled
mkdir -p "$SETTLED"
HOSTBIN=$WORK/${VARIANTS[-1]}/capdem-bench # GCC's host fallback runs 1 team x 2 threads
# (mix_spheres_hexapods: half spheres, half hexapods, the ladder's rows
# visited by kind, docs/performance.md "Session 18, rows visited by kind")
for c in hexapods_a3 spheres mix_spheres_hexapods; do
    f=$SETTLED/${c}_n$SETTLED_N.h5
    if [ $RESETTLE = 1 ] || [ ! -s "$f" ]; then
        say "settling $SETTLED_N $c (once; niced; minutes)"
        rm -f "$f"
        env LD_LIBRARY_PATH="$LLVM" OMP_TARGET_OFFLOAD=DISABLED OMP_WAIT_POLICY=PASSIVE \
            nice "$HOSTBIN" --case $c --n "$SETTLED_N" --repeat 0 --save-settled "$f.tmp" >"$SETTLED/${c}_n$SETTLED_N.log" 2>&1 ||
            { tail "$SETTLED/${c}_n$SETTLED_N.log" >&2; die "settling $c failed"; }
        mv "$f.tmp" "$f"
    fi
done
# The full-size MPM compaction's packing (run_on_gpu.sh part mpm): the
# 300 disks of configs/mpm/deposit_disks.yaml deposited by the DEM solver
# (250,000 steps, a few CPU-minutes here, once).
if [ $RESETTLE = 1 ] || [ ! -s "$SETTLED/deposit_disks.h5" ]; then
    say "depositing the 300 disks of the full-size MPM packing (once; niced; minutes)"
    (cd "$SETTLED" && rm -f deposit_disks.h5 &&
        env LD_LIBRARY_PATH="$LLVM" OMP_TARGET_OFFLOAD=DISABLED OMP_WAIT_POLICY=PASSIVE \
            nice "$WORK/${VARIANTS[-1]}/capdem" run "$ROOT/configs/mpm/deposit_disks.yaml" --quiet >deposit_disks.log 2>&1) ||
        { tail "$SETTLED/deposit_disks.log" >&2; die "the MPM deposit failed"; }
fi

# ------------------------------------------------------------- assemble
say "assembling $OUT"
case $OUT/ in "$ROOT"/*) git -C "$ROOT" check-ignore -q "$OUT" || die "$OUT is inside the repository but not ignored by git" ;; esac
# The programs, libraries and packings are staged, then travel as xz
# archives (payload-*.tar.xz; run_on_gpu.sh unpacks them outside the bundle):
# libLLVM-16 alone is 118 MiB raw, 21 MiB packed, and the 14 programs of a
# build, which share most of their code, pack 25 to 1.
STAGE=$WORK/stage
rm -rf "$OUT" "$STAGE"
mkdir -p "$OUT/src" "$STAGE"/{bin,lib,lib.cxx,inputs,tools}
for v in "${VARIANTS[@]}"; do
    mkdir -p "$STAGE/bin/$v"
    cp "$WORK/$v/capdem" "$WORK/$v/capdem-bench" "$STAGE/bin/$v/"
    for t in "${TESTS[@]}"; do cp "$WORK/$v/tests/$t" "$STAGE/bin/$v/"; done
done
# HDF5's command-line tools, which the MPM shell tests read run files with
# (their libraries are collected below with the programs').
cp -L "$(command -v h5dump)" "$(command -v h5diff)" "$STAGE/tools/" || die "h5dump/h5diff missing (hdf5-tools)"
# What the runtimes open with dlopen, not as DT_NEEDED: the CUDA offload
# plugins (and, through them, libLLVM-16) and the OpenCL ICD loader (the
# NVIDIA ICD itself comes from the driver).  libomptarget's host-device
# (x86_64) plugins stay behind: nothing here is built for them.
DLOPENED=()
if [ $WANT_CLANG = 1 ]; then
    for f in libomptarget.rtl.cuda.nextgen.so.16 libomptarget.rtl.cuda.so.16; do
        cp "$LLVM/$f" "$STAGE/lib/"
        ln -s "$f" "$STAGE/lib/${f%.16}" # libomptarget opens the plugins by their unversioned names
        DLOPENED+=("$STAGE/lib/$f")
    done
fi
if [ $WANT_GCC = 1 ]; then
    cp -L /usr/lib/x86_64-linux-gnu/libgomp-plugin-nvptx.so.1 "$STAGE/lib/"
    DLOPENED+=("$STAGE/lib/libgomp-plugin-nvptx.so.1")
fi
# glibc's own libraries come from the GPU machine (glibc 2.39 >= 2.36 here);
# the driver's too.  Everything else found by ldd (recursive) travels.
is_system() {
    case $1 in
    linux-vdso.so.* | ld-linux* | libc.so.* | libm.so.* | libpthread.so.* | libdl.so.* | librt.so.* | libutil.so.* | libresolv.so.* | \
        libcuda.so.* | libnvidia-*) return 0 ;;
    esac
    return 1
}
declare -A SEEN=()
collect() { # binary-or-library
    local line name path
    while read -r line; do
        case $line in *"=> not found"*) die "ldd $1: $line" ;; esac
        name=$(awk '{print $1}' <<<"$line")
        path=$(awk '$2 == "=>" {print $3}' <<<"$line")
        [ -n "$path" ] || continue
        is_system "$name" && continue
        [ -n "${SEEN[$name]:-}" ] && continue
        SEEN[$name]=$path
    done < <(LD_LIBRARY_PATH="$LLVM${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}" ldd "$1")
}
for f in "$STAGE"/bin/*/* "$STAGE"/tools/* "${DLOPENED[@]}"; do collect "$f"; done
SEEN[libOpenCL.so.1]=${SEEN[libOpenCL.so.1]:-/usr/lib/x86_64-linux-gnu/libOpenCL.so.1}
for name in "${!SEEN[@]}"; do
    case $name in
    # The GPU machine's own C++ runtime is newer: run_on_gpu.sh uses these
    # only where it has none as new (an older libstdc++ ahead of the
    # system's would break driver libraries that need the newer one).
    libstdc++.so.* | libgcc_s.so.*) cp -L "${SEEN[$name]}" "$STAGE/lib.cxx/$name" ;;
    *) [ -e "$STAGE/lib/$name" ] || cp -L "${SEEN[$name]}" "$STAGE/lib/$name" ;;
    esac
done
cp "$SETTLED"/*_n"$SETTLED_N".h5 "$SETTLED/deposit_disks.h5" "$STAGE/inputs/"
# Two archives: the libraries (220 MiB raw, several minutes of xz -9
# here) are packed again only when one of them changed; the programs and
# inputs (they change with every commit: capdem --version names it) pack in
# a minute.
pack() { # archive folders...
    local a=$1 sum
    shift
    sum=$(cd "$STAGE" && find "$@" \( -type f -o -type l \) | sort | xargs sha256sum | sha256sum | cut -c1-32)
    if [ -e "$WORK/$a" ] && [ "$(cat "$WORK/$a.sum" 2>/dev/null)" = "$sum" ]; then
        say "$a: unchanged, reused"
    else
        say "packing $a ($(cd "$STAGE" && du -scm "$@" | tail -1 | cut -f1) MiB raw; xz -9)"
        rm -f "$WORK/$a.sum"
        tar -C "$STAGE" -cf - "$@" | nice xz -9 -T"$JOBS" >"$WORK/$a"
        echo "$sum" >"$WORK/$a.sum"
    fi
    cp "$WORK/$a" "$OUT/$a"
}
pack payload-lib.tar.xz lib lib.cxx
pack payload-bin.tar.xz bin inputs tools

# The part of the source tree the tests read through CAPDEM_SOURCE_DIR
# (presets, example configs, kernels, and host/capdem_h5.py and
# docs/output.md, which test_runfile_layout checks against the C tables), unpacked: small, and
# readable there.
cp -r "$ROOT/configs" "$ROOT/kernels" "$OUT/src/"
mkdir -p "$OUT/src/host" && cp "$ROOT/host/capdem_h5.py" "$OUT/src/host/"
mkdir -p "$OUT/src/docs" && cp "$ROOT/docs/output.md" "$OUT/src/docs/" # test_runfile_layout checks its table too
# the MPM shell tests and what they source or call (part mpm)
mkdir -p "$OUT/src/tests/mpm" "$OUT/src/tests/cli" && cp "$ROOT"/tests/mpm/*.sh "$ROOT"/tests/mpm/*.py "$OUT/src/tests/mpm/" &&
    cp "$ROOT/tests/cli/common.sh" "$OUT/src/tests/cli/"
cp "$ROOT/bench/gpu/run_on_gpu.sh" "$ROOT/bench/gpu/kernel_profile.sh" "$ROOT/bench/gpu/ncu_table.py" "$OUT/"
chmod +x "$OUT/run_on_gpu.sh" "$OUT/kernel_profile.sh"
{
    echo "capdem GPU bundle"
    echo "commit: $(git -C "$ROOT" rev-parse HEAD)$(git -C "$ROOT" diff --quiet HEAD -- src kernels host CMakeLists.txt 'bench/*.[ch]' 'tests/*.[ch]' || echo ' (with uncommitted changes to the code)')"
    echo "built: $(date -u +%Y-%m-%dT%H:%M:%SZ) on $(uname -srm), $(ldd --version | head -1)"
    echo "variants: ${VARIANTS[*]}"
    [ $WANT_CLANG = 1 ] && echo "clang: $(clang-16 --version | head -1); -fopenmp -fopenmp-targets=nvptx64-nvidia-cuda --offload-arch=sm_90; LLVM OpenMP (libomp-16-dev) $(zcat "$WORK"/llvm16/usr/share/doc/libomp-16-dev/changelog.Debian.gz | head -1 | cut -d' ' -f2)"
    [ $WANT_GCC = 1 ] && echo "gcc: $(gcc --version | head -1); -foffload=nvptx-none -misa=sm_80"
    echo "cuda (build): $("$CUDA"/bin/ptxas --version | tail -1)"
    echo "settled: $(cd "$STAGE/inputs" && ls | tr '\n' ' ')"
    echo "tests: ${TESTS[*]}"
    echo
    for a in payload-lib.tar.xz payload-bin.tar.xz; do echo "$a: $(stat -c %s "$OUT/$a") bytes, sha256 $(sha256sum "$OUT/$a" | cut -c1-16)"; done
    echo "unpacked (bytes, sha256):"
    (cd "$STAGE" && find . -type f | sort | while read -r f; do echo "$(stat -c %s "$f") $(sha256sum "$f" | cut -c1-16) $f"; done)
} >"$OUT/MANIFEST.txt"
size=$(du -sb "$OUT" | cut -f1)
say "bundle: $OUT, $((size / 1024 / 1024)) MiB ($size bytes)"
[ "$size" -le $((60 * 1024 * 1024)) ] || die "the bundle is over 60 MiB: it would not travel with room to spare"

if [ $CHECK = 1 ]; then
    say "checking the bundle with everything outside it hidden"
    # Its run_on_gpu.sh files stay in <work>/check-out for a look.
    rm -rf "$WORK/check-out"
    CHECK_OUT=$WORK/check-out bash "$ROOT/bench/gpu/check_bundle.sh" "$OUT"
fi
