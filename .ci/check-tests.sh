#!/usr/bin/env bash
# CI: the tests CTest registered in BUILD are the ones the tree defines
# (tests/CMakeLists.txt), so that a missing dependency cannot drop tests
# silently (OpenCL: the backend tests), and no test of BUILD's CTest log
# was skipped (a check that could not run, SKIP_RETURN_CODE).
# usage: .ci/check-tests.sh BUILD [CTEST_LOG]  (from the source root; BUILD with CAPDEM_OPENCL=ON, and
# CAPDEM_MPI=ON or not)
set -euo pipefail
build=$1 log=${2:-}
names() { for f in "$@"; do [ -e "$f" ] && basename "${f%.*}"; done; }
{
  names tests/{unit,physics,config,regression,analysis,protocols,offload,mpm}/test_*.c tests/cli/test_*.sh \
        tests/bench/test_*.sh tests/backend/test_*.c tests/backend/test_*.sh tests/mpm/test_*.sh
  # the MPI tests in MPI builds only (-DCAPDEM_MPI=ON, docs/mpi.md)
  grep -q '^CAPDEM_MPI:BOOL=ON$' "$build/CMakeCache.txt" && names tests/mpi/test_*.sh
  names tests/physics/test_*.c tests/regression/test_*.c | sed 's/$/_opencl/'
  names configs/protocols/ci/*.yaml | grep -vxE 'deposit_2d_crosses|radial_hexapods_a3|radial_spheres|bulk_modulus_hexapods_a3' |
    sed 's/^/preset_/'
  echo preset_twins_exist; echo validation_study1_smoke; echo validation_deposit_driver
  echo mpm_opencl_same_bits mpm_opencl_failures | tr " " "\n" # tests/mpm/opencl_{same_bits,failures}.sh, in OpenCL builds
} | sort > "$build/tests-expected.txt"
ctest --test-dir "$build" -N | sed -n 's/^ *Test *#[0-9]*: //p' | sort > "$build/tests-registered.txt"
if ! diff "$build/tests-expected.txt" "$build/tests-registered.txt" > "$build/tests-diff.txt"; then
  echo "CI: the registered tests differ from the tree's (< expected only, > registered only):"
  cat "$build/tests-diff.txt"
  exit 1
fi
echo "CI: $(wc -l < "$build/tests-registered.txt") tests registered, as the tree defines"
# Tests of an optional dependency (README: "optional"), which CI does not
# install, may skip: test_liggghts_law (LIGGGHTS pulls in VTK and Qt).
optional='test_liggghts_law'
if [ -n "$log" ] && grep -E '\*\*\*Skipped|Not Run|\*\*\*Disabled' "$log" | grep -vE "($optional) "; then
  echo "CI: the tests above were skipped or not run"
  exit 1
fi
exit 0
