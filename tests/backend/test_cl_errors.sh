#!/usr/bin/env bash
# The OpenCL backend's refusals (docs/opencl.md, "Messages"): no platform,
# no matching platform, no double precision, a bad device request, kernel
# sources that are missing or do not build.  Each ends `capdem run` with exit
# status 2 and the documented message, never a crash; a good short run on
# the backend works.
# usage: test_cl_errors.sh CAPDEM SOURCE_DIR
set -u
capdem=$1
src=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fails=0
pass=0

cat > "$work/run.yaml" <<EOF
run: {steps: 20, output: $work/run.h5}
particles: [{shape: hexapod, aspect: 3, diameter: 0.005, count: 8}]
domain: {type: box, width: 0.05, height: 0.05, thickness: 0.05}
EOF

# expect_refusal NAME MESSAGE_REGEX [ENV=VALUE ...] -- [capdem run options]
expect_refusal() {
  local name=$1 pattern=$2
  shift 2
  local envs=()
  while [ $# -gt 0 ] && [ "$1" != "--" ]; do envs+=("$1"); shift; done
  shift
  env "${envs[@]}" "$capdem" run "$work/run.yaml" --quiet --backend opencl "$@" > "$work/out" 2> "$work/err"
  local rc=$?
  if [ $rc -ne 2 ]; then
    echo "FAIL $name: exit status $rc, expected 2"; cat "$work/err"; fails=$((fails+1)); return
  fi
  if ! grep -Eq -e "$pattern" "$work/err"; then
    echo "FAIL $name: message does not match /$pattern/:"; cat "$work/err"; fails=$((fails+1)); return
  fi
  pass=$((pass+1))
}

# ocl-icd reads the driver list from OCL_ICD_VENDORS: an empty folder means
# no platform at all.
mkdir -p "$work/no_vendors"
expect_refusal no_platform 'OpenCL: no platform found.*--backend omp' OCL_ICD_VENDORS="$work/no_vendors" --
expect_refusal platform_not_matching 'CAPDEM_OPENCL_PLATFORM=nonexistent matches no platform' \
  CAPDEM_OPENCL_PLATFORM=nonexistent --
expect_refusal no_fp64 'has no double precision \(cl_khr_fp64\)' CAPDEM_OPENCL_PRETEND_NO_FP64=1 --
expect_refusal bad_device '--device banana: expected cpu, gpu or auto' -- --device banana
expect_refusal bad_device_env 'CAPDEM_OPENCL_DEVICE=tpu: expected cpu, gpu or auto' CAPDEM_OPENCL_DEVICE=tpu --
expect_refusal kernel_dir_missing "kernel source '.*' not found under CAPDEM_KERNEL_DIR" \
  CAPDEM_KERNEL_DIR="$work/nowhere" --

# A kernel that does not compile: the compiler's build log is printed.
mkdir -p "$work/tree"
cp -r "$src/kernels" "$work/tree/kernels"
printf '\n__kernel void cd_cl_broken(void) { this is not C; }\n' >> "$work/tree/kernels/cl/step.cl"
expect_refusal build_failure 'kernels failed to build' CAPDEM_KERNEL_DIR="$work/tree/kernels" POCL_CACHE_DIR="$work/pocl" --
if ! grep -q 'OpenCL build log' "$work/err" || ! grep -q 'step.cl' "$work/err"; then
  echo "FAIL build_failure: no build log naming step.cl:"; cat "$work/err"; fails=$((fails+1))
fi

# The intact sources from the same folder build and run.
if CAPDEM_KERNEL_DIR="$src/kernels" "$capdem" run "$work/run.yaml" --quiet --backend opencl --device cpu \
     > "$work/out" 2> "$work/err" && [ -s "$work/run.h5" ] && grep -q 'backend opencl on OpenCL device' "$work/err"; then
  pass=$((pass+1))
else
  echo "FAIL good_run: exit status or output:"; cat "$work/err"; fails=$((fails+1))
fi

echo "test_cl_errors: $pass passed, $fails failed"
[ $fails -eq 0 ]
