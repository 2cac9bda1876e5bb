#!/usr/bin/env bash
# The C and OpenCL C sources (src/, kernels/, host/, tests/, bench/) are
# formatted by the repository's .clang-format (clang-format 14, Debian's).
# Fails, not skips, without clang-format-14 (a README dependency): a
# formatting drift would otherwise land unseen.
# usage: test_c_format.sh CAPDEM SOURCE_DIR
set -u
src=$2
command -v clang-format-14 > /dev/null || { echo "FAIL clang-format-14 is not installed (apt install clang-format-14; README)"; exit 1; }
cd "$src" || exit 1
mapfile -t files < <(find src kernels host tests bench \( -name '*.c' -o -name '*.h' -o -name '*.cl' \) \
    -not -path '*/build*' -not -path 'tests/fuzz/corpus*' -not -path 'tests/fuzz/hdf5_defects*' | sort)
[ "${#files[@]}" -ge 100 ] || { echo "FAIL only ${#files[@]} C files found"; exit 1; }
clang-format-14 --dry-run --Werror "${files[@]}" 2>&1 | head -40
[ "${PIPESTATUS[0]}" -eq 0 ] || { echo "FAIL files above differ from .clang-format (clang-format-14 -i FILE)"; exit 1; }
echo "clang-format-14: ${#files[@]} C files formatted"
