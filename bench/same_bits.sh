#!/usr/bin/env bash
# Same bits between two capdem binaries: the CI twins (every protocol preset
# of configs/protocols/ci/, run to the end of its protocol, and the example
# configs spheres_box and crosses_2d to their end) on each backend, both run
# files compared with h5diff, the creator's commit attribute aside.  It is
# the check a change that claims "the same trajectory bits" runs before it
# lands (docs/performance.md, "Same bits between two binaries").
#
# usage: bench/same_bits.sh REF_CAPDEM NEW_CAPDEM [OUTDIR] [BACKENDS]
#   OUTDIR    where the run files, logs and diffs stay (default: a new
#             folder under /tmp); the report is OUTDIR/report.txt
#   BACKENDS  comma-separated, default "omp,opencl" (opencl needs a build
#             with -DCAPDEM_OPENCL=ON; PoCL on a machine without a GPU)
# env: SAME_BITS_JOBS (default 2) runs at once, each with OMP_NUM_THREADS=1
#      so that two jobs fit two cores; SAME_BITS_CASES overrides the list
#      (config paths relative to the source tree).
# Exit status: 0 every pair equal, 1 any difference or a failed run.
set -u
ref=$(readlink -f "$1") new=$(readlink -f "$2")
out=${3:-$(mktemp -d /tmp/same_bits.XXXXXX)}
backends=${4:-omp,opencl}
src=$(cd "$(dirname "$0")/.." && pwd)
jobs=${SAME_BITS_JOBS:-2}
mkdir -p "$out"
cases=${SAME_BITS_CASES:-$(cd "$src" && ls configs/protocols/ci/*.yaml configs/spheres_box.yaml configs/crosses_2d.yaml)}
export OMP_NUM_THREADS=1 OMP_WAIT_POLICY=PASSIVE

# one run: BINARY_TAG CONFIG BACKEND -> OUTDIR/NAME-BACKEND-TAG.h5 and .log
run_one() {
  local tag=$1 cfg=$2 be=$3 bin name
  bin=$ref; [ "$tag" = new ] && bin=$new
  name=$(basename "$cfg" .yaml)-$be-$tag
  "$bin" run "$src/$cfg" --backend "$be" --output "$out/$name.h5" --overwrite --quiet > "$out/$name.log" 2>&1
  echo $? > "$out/$name.rc"
}
export -f run_one
export ref new out src

start=$(date +%s)
for cfg in $cases; do
  for be in ${backends//,/ }; do
    for tag in ref new; do echo "$tag $cfg $be"; done
  done
done | xargs -P "$jobs" -L 1 bash -c 'run_one "$0" "$1" "$2"'

{
  echo "same_bits: ref $ref"
  echo "           new $new"
  echo "           $(date -u +%FT%TZ), $(($(date +%s) - start)) s, load $(cut -d' ' -f1-3 /proc/loadavg)"
  for cfg in $cases; do
    for be in ${backends//,/ }; do
      name=$(basename "$cfg" .yaml)-$be
      rr=$(cat "$out/$name-ref.rc" 2>/dev/null || echo none) rn=$(cat "$out/$name-new.rc" 2>/dev/null || echo none)
      if [ "$rr" != 0 ] || [ "$rn" != 0 ]; then
        echo "FAIL $name: exit ref $rr, new $rn (logs in $out)"; continue
      fi
      if h5diff --exclude-attribute /h5md/creator "$out/$name-ref.h5" "$out/$name-new.h5" > "$out/$name.diff" 2>&1; then
        echo "ok   $name: equal bit for bit"
      else
        echo "DIFF $name: $(grep -c 'differences found' "$out/$name.diff") datasets differ:" \
          "$(grep -B1 'differences found' "$out/$name.diff" | grep -o '<[^>]*>' | sort -u | head -8 | tr '\n' ' ')"
      fi
    done
  done
} | tee "$out/report.txt"
# (the loop ran in a pipeline: its verdict is read back from the report)
grep -q "^FAIL\|^DIFF" "$out/report.txt" && exit 1
exit 0
