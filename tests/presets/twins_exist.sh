#!/usr/bin/env bash
# Every full-size preset in configs/protocols names its CI-size twin in its
# header ("CI-size twin: ci/NAME.yaml"), that twin exists, and every twin is
# the twin of some full-size preset.
# usage: twins_exist.sh SOURCE_DIR
set -u
dir=$1/configs/protocols
fails=0
declare -A claimed
for full in "$dir"/*.yaml; do
  twin=$(grep -o 'CI-size twin: ci/[A-Za-z0-9_]*\.yaml' "$full" | head -1 | sed 's/CI-size twin: //')
  if [ -z "$twin" ]; then echo "FAIL $(basename "$full"): no 'CI-size twin: ci/NAME.yaml' line"; fails=$((fails+1)); continue; fi
  if [ ! -f "$dir/$twin" ]; then echo "FAIL $(basename "$full"): its twin $twin does not exist"; fails=$((fails+1)); continue; fi
  claimed[$twin]=1
  echo "ok   $(basename "$full") -> $twin"
done
for t in "$dir"/ci/*.yaml; do
  [ -n "${claimed[ci/$(basename "$t")]:-}" ] || { echo "FAIL ci/$(basename "$t") is no full-size preset's twin"; fails=$((fails+1)); }
done
[ "$fails" -eq 0 ]
