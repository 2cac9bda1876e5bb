#!/usr/bin/env bash
# Checks a GPU bundle (bench/gpu_bundle.sh) on a machine without a GPU, with
# everything outside the bundle hidden as well as one can without a
# container: an empty environment (env -i), a library path that points only
# into the bundle (and the folder its compressed libraries unpack into),
# no OpenCL ICD for the link check.
#
#   bench/gpu/check_bundle.sh BUNDLE [PART...]
#
# 1. ldd of every binary and offload plugin: each library must resolve into
#    the bundle, or be one of glibc's (libc, libm, libpthread, libdl, librt,
#    libresolv, ld-linux) that the GPU machine has; nothing "not found".
# 2. LD_DEBUG=files of `capdem --version` of each build (which makes the
#    OpenMP runtimes dlopen their CUDA plugins, and these libLLVM-16) and of
#    an OpenCL start: every object loaded must come from the same places.
#    libcuda.so.1 (the driver) is the one allowed miss.
# 3. run_on_gpu.sh PART... with CAPDEM_BUNDLE_HOST=1 (OMP_TARGET_OFFLOAD=
#    DISABLED: the offload builds run on the host here); default parts:
#    info tests tests-gcc opencl (PoCL), a one-entry ladder, the dry run of
#    part kernels (bench/gpu/kernel_profile.sh --dry-run) and part mpm (its
#    throughput runs shortened to 5 steps).  Its status is this script's.
set -euo pipefail
[ $# -ge 1 ] || { echo "usage: check_bundle.sh BUNDLE [PART...]" >&2; exit 2; }
B=$(cd "$1" && pwd)
shift
[ -e "$B/MANIFEST.txt" ] && [ -e "$B/run_on_gpu.sh" ] || { echo "check_bundle.sh: $B is not a bundle" >&2; exit 2; }
KEY=$(cksum <"$B/MANIFEST.txt" | cut -d' ' -f1)
UNPACK=$(mktemp -d /tmp/capdem-bundle-check.XXXXXX)
trap 'rm -rf "$UNPACK"' EXIT
fail=0

# Unpacks the payload archives the way run_on_gpu.sh does (the first thing it
# does; `info` alone is cheap, so run it for that).
U=$UNPACK/u
env -i PATH=/usr/bin:/bin HOME="$UNPACK" CAPDEM_BUNDLE_HOST=1 CAPDEM_BUNDLE_UNPACK="$U" OUT="$UNPACK/out0" \
    bash "$B/run_on_gpu.sh" info >/dev/null 2>&1 || true
[ -e "$U/.complete" ] || { echo "check_bundle.sh: run_on_gpu.sh did not unpack the bundle" >&2; exit 1; }
if ls "$B"/payload*.tar.xz >/dev/null 2>&1; then R=$U; else R=$B; fi
BIN=$R/bin
LP=$R/lib:$R/lib.cxx # lib.cxx last: run_on_gpu.sh adds it only where the machine's libstdc++ is older

allowed() { # path of a loaded library -> 0 if inside the bundle or glibc's
    case $1 in
    "$B"/* | "$UNPACK"/*) return 0 ;;
    /lib/x86_64-linux-gnu/* | /usr/lib/x86_64-linux-gnu/* | /lib64/* | /usr/lib64/*)
        # glibc's own (the GPU machine's glibc 2.39 provides them)
        case $(basename "$1") in ld-linux-x86-64.so.* | libc.so.* | libm.so.* | libpthread.so.* | libdl.so.* | librt.so.* | \
            libresolv.so.* | libutil.so.* | libanl.so.* | libnss_*) return 0 ;; esac ;;
    esac
    return 1
}

echo "== 1. ldd, env -i, LD_LIBRARY_PATH=$LP"
n=0
for f in "$BIN"/*/* "$R"/tools/* "$R"/lib/*.so*; do
    [ -L "$f" ] && continue
    out=$(env -i PATH=/usr/bin:/bin LD_LIBRARY_PATH="$LP" ldd "$f" 2>&1) || { echo "ldd $f failed: $out"; fail=1; continue; }
    case $f in */bin/*/capdem) echo "  ${f#"$R"/}: $(grep -c '=>' <<<"$out") libraries; resolved outside the bundle (must be glibc's): $(grep '=>' <<<"$out" | grep -v -e "$R" | awk '{print $1}' | tr '\n' ' ')" ;; esac
    while read -r name arrow path _; do
        [ "$arrow" = "=>" ] || continue
        if [ "$path" = not ]; then echo "NOT FOUND: $name (needed by ${f#"$B"/})"; fail=1
        elif ! allowed "$path"; then echo "OUTSIDE: ${f#"$B"/} -> $name => $path"; fail=1; fi
    done <<<"$out"
    n=$((n + 1))
done
echo "$n files checked"
v=$(cd "$BIN" && ls | head -1)
echo "ldd $v/capdem:"
env -i PATH=/usr/bin:/bin LD_LIBRARY_PATH="$LP" ldd "$BIN/$v/capdem" | sed "s|$B|<bundle>|; s|$U|<unpacked>|"

echo "== 2. objects loaded at run time (LD_DEBUG=files)"
for v in $(cd "$BIN" && ls); do
    for args in "--version" ; do
        log=$UNPACK/ld-$v.log
        env -i PATH=/usr/bin:/bin LD_LIBRARY_PATH="$LP" OCL_ICD_VENDORS=/nonexistent LD_DEBUG=files LD_DEBUG_OUTPUT="$log" \
            "$BIN/$v/capdem" $args >/dev/null 2>&1 || { echo "capdem $args ($v) failed"; fail=1; }
        # OpenCL too: the ICD loader starts (and finds no ICD: hidden).
        env -i PATH=/usr/bin:/bin LD_LIBRARY_PATH="$LP" OCL_ICD_VENDORS=/nonexistent LD_DEBUG=files LD_DEBUG_OUTPUT="$log.cl" \
            "$BIN/$v/capdem-bench" --case spheres --n 50 --settle-steps 1 --steps 1 --repeat 1 --backend opencl >/dev/null 2>&1 || true
        loaded=$(cat "$log".* | sed -n 's/.*calling init: //p' | sort -u)
        # libcuda.so.1 is the driver's; libgomp probes optional plugin
        # symbols ("symbol lookup error"), harmless.
        missing=$(cat "$log".* | grep -E 'cannot open|error' | grep -v -e 'libcuda\.so' -e 'symbol lookup error' || true)
        bad=0
        for p in $loaded; do allowed "$p" || { echo "LOADED OUTSIDE ($v): $p"; bad=1; fail=1; }; done
        [ -z "$missing" ] || { echo "$missing"; }
        echo "$v: $(echo "$loaded" | wc -l) objects loaded, $( [ $bad = 0 ] && echo 'all inside the bundle or glibc' || echo 'SOME OUTSIDE'); plugins: $(echo "$loaded" | grep -oE '(libomptarget\.rtl\.[a-z0-9_.]*|libgomp-plugin-nvptx[.a-z0-9]*|libLLVM[-.0-9a-z]*|libOpenCL[.0-9a-z]*)' | sort -u | tr '\n' ' ')"
    done
done

echo "== 3. run_on_gpu.sh on the host (CAPDEM_BUNDLE_HOST=1)"
[ $# -gt 0 ] || set -- info tests tests-gcc opencl ladder kernels mpm
OUTDIR=${CHECK_OUT:-$UNPACK/out}
rc=0
mapfile -t pass < <(env | grep '^CAPDEM_BUNDLE_' || true) # the caller's settings of run_on_gpu.sh go through
env -i PATH=/usr/bin:/bin HOME="$UNPACK" CAPDEM_BUNDLE_JOBS=2 CAPDEM_BUNDLE_LADDER=h1e4 CAPDEM_BUNDLE_STEPS=20 CAPDEM_BUNDLE_MPM_STEPS=5 \
    CAPDEM_BUNDLE_BUDGET_S=1500 CAPDEM_BUNDLE_TESTS_CAP=600 "${pass[@]}" CAPDEM_BUNDLE_HOST=1 CAPDEM_BUNDLE_UNPACK="$U" OUT="$OUTDIR" \
    POCL_CACHE_DIR="$UNPACK/pocl" nice bash "$B/run_on_gpu.sh" "$@" || rc=$?
echo "run_on_gpu.sh exit status $rc; files back: $(ls "$OUTDIR" | tr '\n' ' ')"
[ $rc = 0 ] || fail=1
[ $fail = 0 ] && echo "check_bundle.sh: OK" || echo "check_bundle.sh: FAILED"
exit $fail
