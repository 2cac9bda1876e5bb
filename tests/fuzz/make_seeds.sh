#!/usr/bin/env bash
# Remakes the seed corpora of the fuzz targets (docs/testing.md,
# "Sanitizers and fuzzing"): corpus_runfile/seed_tiny*.h5 from a run of
# seed_run.yaml, shrunk (shrink_run.py) in HDF5's earliest and latest file
# formats, and config.dict from the key table of docs/config.md.  The
# config seeds are copies of shipped configs and the docs' example.
# usage: tests/fuzz/make_seeds.sh CAPDEM
set -euo pipefail
capdem=$1
here=$(cd "$(dirname "$0")" && pwd)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
"$capdem" run "$here/seed_run.yaml" --output "$tmp/run.h5" --quiet
/usr/bin/python3 "$here/shrink_run.py" "$tmp/run.h5" "$here/corpus_runfile/seed_tiny.h5"
/usr/bin/python3 "$here/shrink_run.py" "$tmp/run.h5" "$here/corpus_runfile/seed_tiny_latest.h5" latest
{
  echo '# libFuzzer dictionary for fuzz_config: the key names of docs/config.md'
  echo '# (each part of each key of its table) and YAML punctuation and values.'
  grep -oE '^\| `[^`]+`' "$here/../../docs/config.md" | sed 's/^| `//; s/`$//' | tr '.' '\n' | sed 's/\[\]//' |
    sort -u | awk '{printf "\"%s:\"\n", $0}'
  for t in '- ' '[' ']' '{' '}' ', ' ': ' '\x0a  ' '&a ' '*a' '!!' '1e308' '-1' 'nan' '.inf' 'true' 'sphere' 'rod' \
           'cross' 'hexapod' 'segments' 'box' 'cylinder' 'ball' 'none' 'plane' 'lattice' 'random' \
           'deposit_compress' 'radial_compaction' 'bulk_modulus' 'total' 'elastic' 'position'; do
    printf '"%s"\n' "$t"
  done
} > "$here/config.dict"
