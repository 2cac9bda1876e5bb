#!/usr/bin/env bash
# The key table of docs/config.md is the one the code's key table prints
# (`capdem run --help-markdown`): a key added, removed or changed in
# src/config/config_schema.c without the documentation fails here.
# usage: test_docs_keys.sh CAPDEM SOURCE_DIR
set -u
capdem=$1 src=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$capdem" run --help-markdown > "$work/code" || { echo "FAIL: capdem run --help-markdown"; exit 1; }
sed -n '/^| key | type and range | unit | default | meaning |$/,/^[^|]/p' "$src/docs/config.md" | grep '^|' > "$work/docs"
if diff -u "$work/docs" "$work/code"; then
  echo "ok   docs/config.md lists the $(($(wc -l < "$work/code") - 2)) keys of the code"
else
  echo "FAIL: docs/config.md's key table differs from capdem run --help-markdown (above: - docs, + code);"
  echo "      regenerate it with build/capdem run --help-markdown"
  exit 1
fi
