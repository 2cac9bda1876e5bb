#!/usr/bin/env bash
# The GPU bundle's scripts (docs/gpu_bundle.md) without a GPU, clang-16 or
# network: a miniature bundle made of this build's host binaries (standing
# in for the "clang" offload build), its shared libraries and two tiny
# settled packings, packed as gpu_bundle.sh packs them (payload-*.tar.xz);
# then bench/gpu/check_bundle.sh on it: ldd and LD_DEBUG find nothing
# outside the bundle but glibc, and run_on_gpu.sh (info, tests, ladder,
# the dry run of kernels, mpm with one test program and a 5-step
# throughput run on the CI deposit;
# CAPDEM_BUNDLE_HOST=1) unpacks the payload, passes, and leaves at most 8
# files in OUT with valid JSON lines.
# About 20 s on 2 cores.
#   test_gpu_bundle.sh CAPDEM_BENCH SOURCE_DIR
set -euo pipefail
bench=$(realpath "$1")
src=$2
build=$(dirname "$bench")
dir=$(realpath "$(mktemp -d gpu-bundle-test.XXXXXX)")
trap 'rm -rf "$dir"' EXIT
B=$dir/bundle
S=$dir/stage # what goes into the payload archives
mkdir -p "$B/src" "$S"/{bin/clang,lib,lib.cxx,inputs,tools}

cp "$build/capdem" "$bench" "$build/tests/test_walls" "$build/tests/test_mpm_material" "$S/bin/clang/"
cp -L "$(command -v h5dump)" "$(command -v h5diff)" "$S/tools/"
# Libraries as gpu_bundle.sh collects them: ldd, minus glibc.
ldd "$S"/bin/clang/* "$S"/tools/* | awk '$2 == "=>" && $3 ~ /^\// {print $1, $3}' | sort -u | while read -r name path; do
    case $name in ld-linux* | libc.so.* | libm.so.* | libpthread.so.* | libdl.so.* | librt.so.*) continue ;; esac
    case $name in
    libstdc++.so.* | libgcc_s.so.*) cp -L "$path" "$S/lib.cxx/$name" ;;
    *) cp -L "$path" "$S/lib/$name" ;;
    esac
done
# libgomp opens its offload plugin by name where one is installed (CI
# installs gcc-offload-nvptx): it travels too, as in gpu_bundle.sh.
if [ -e "$S/lib/libgomp.so.1" ] && p=$(ls /usr/lib/x86_64-linux-gnu/libgomp-plugin-nvptx.so.1 2>/dev/null); then cp -L "$p" "$S/lib/"; fi
[ -e "$S/lib/libyaml-0.so.2" ] || { echo "libyaml-0.so.2 is not among the libraries ldd found"; exit 1; }
cp -r "$src/configs" "$src/kernels" "$B/src/"
mkdir -p "$B/src/host" && cp "$src/host/capdem_h5.py" "$B/src/host/"
"$bench" --case hexapods_a3 --n 40 --settle-steps 200 --repeat 0 --threads 1 --save-settled "$S/inputs/hexapods_a3_n40.h5" >/dev/null 2>&1
"$bench" --case spheres --n 40 --settle-steps 200 --repeat 0 --threads 1 --save-settled "$S/inputs/spheres_n40.h5" >/dev/null 2>&1
"$bench" --case mix_spheres_hexapods --n 40 --settle-steps 200 --repeat 0 --threads 1 --save-settled "$S/inputs/mix_spheres_hexapods_n40.h5" >/dev/null 2>&1
tar -C "$S" -cf - lib lib.cxx | xz -0 -T2 >"$B/payload-lib.tar.xz"
# part mpm's throughput input: here the CI deposit (12 disks) under the
# full-size deposit's name
(cd "$dir" && "$build/capdem" run "$src/configs/mpm/ci/deposit_disks.yaml" --quiet >/dev/null 2>&1) &&
    mv "$dir/deposit_disks_ci.h5" "$S/inputs/deposit_disks.h5"
tar -C "$S" -cf - bin inputs tools | xz -0 -T2 >"$B/payload-bin.tar.xz"
cp "$src/bench/gpu/run_on_gpu.sh" "$src/bench/gpu/kernel_profile.sh" "$src/bench/gpu/ncu_table.py" "$B/"
echo "capdem GPU bundle (test fixture: host build as 'clang')" >"$B/MANIFEST.txt"

out=$dir/out
CHECK_OUT=$out CAPDEM_BUNDLE_LADDER="h1e4 s1e6 m1e5" CAPDEM_BUNDLE_STEPS=4 CAPDEM_BUNDLE_BUDGET_S=240 \
    CAPDEM_BUNDLE_TILES="1,1 2,1 2,2" CAPDEM_BUNDLE_MPM_BACKENDS=omp \
    bash "$src/bench/gpu/check_bundle.sh" "$B" info tests ladder kernels mpm
n=$(ls "$out" | wc -l)
[ "$n" -le 8 ] || { echo "run_on_gpu.sh left $n files in OUT: the device tool returns at most 8"; exit 1; }
for f in summary.txt info.txt ladder.jsonl logs.tar.gz; do [ -s "$out/$f" ] || { echo "missing $f in OUT"; exit 1; }; done
grep -q '^PASS tests-clang/test_walls' "$out/summary.txt" || { echo "test_walls did not pass"; cat "$out/summary.txt"; exit 1; }
# part kernels without a GPU: its dry run (arguments, the ncu table's self-test)
grep -q '^PASS kernels' "$out/summary.txt" || { echo "part kernels (dry run) did not pass"; cat "$out/summary.txt"; exit 1; }
# part mpm: its test programs, not among part tests', and its throughput run
grep -q '^PASS mpm-clang/test_mpm_material' "$out/summary.txt" || { echo "part mpm: test_mpm_material did not pass"; cat "$out/summary.txt"; exit 1; }
! grep -q 'tests-clang/test_mpm_' "$out/summary.txt" || { echo "part tests ran an mpm test"; exit 1; }
grep -q '^PASS mpm_rate_omp' "$out/summary.txt" || { echo "part mpm: the throughput run did not pass"; cat "$out/summary.txt"; exit 1; }
grep -q 'libyaml-0.so.2 => /tmp/capdem-bundle-check[^ ]*/u/lib/' "$out/info.txt" || { echo "libyaml was not loaded from the unpacked payload"; exit 1; }
/usr/bin/python3 - "$out/ladder.jsonl" <<'PY'
import json, sys
rows = [json.loads(l) for l in open(sys.argv[1])]
mpm = [r for r in rows if r["entry"] == "mpm_packing_elastic"]
rows = [r for r in rows if r not in mpm]
entries = sorted({(r["entry"], r["N"]) for r in rows})
assert entries == [("hex_1e4", 40), ("mix_1e5", 80), ("sph_1e6", 160)], entries
assert len(mpm) == 1 and mpm[0]["backend"] == "omp" and mpm[0]["N"] > 1000 and mpm[0]["steps"] == 5, mpm
assert mpm[0]["point_steps_per_s"] > 0 and mpm[0]["build"] == "clang", mpm
for r in rows:
    assert r["build"] == "clang" and r["steps"] == (2 if r["entry"] == "sph_1e6" else 4) and r["particle_steps_per_s"] > 0, r
print("ok: ladder", entries, len(rows), "lines")
PY
