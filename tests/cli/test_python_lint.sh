#!/usr/bin/env bash
# The Python tools (host/, bench/, tests/) pass flake8 with the
# repository's .flake8.  Fails, not skips, without flake8 (a README
# dependency).
# usage: test_python_lint.sh CAPDEM SOURCE_DIR
set -u
src=$2
command -v flake8 > /dev/null || { echo "FAIL flake8 is not installed (apt install flake8; README)"; exit 1; }
cd "$src" || exit 1
mapfile -t files < <(find host bench tests -name '*.py' -not -path '*/build*' | sort)
[ "${#files[@]}" -ge 10 ] || { echo "FAIL only ${#files[@]} Python files found"; exit 1; }
flake8 --config "$src/.flake8" "${files[@]}" || { echo "FAIL flake8 findings above"; exit 1; }
echo "flake8: ${#files[@]} Python files clean"
