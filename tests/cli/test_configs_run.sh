#!/usr/bin/env bash
# Every run file shipped in configs/ runs: each one, shortened to 20 steps,
# sets up and steps with exit status 0 (a README config that stopped at
# set-up went unnoticed before, issue 18).  configs/validation/ holds
# templates ($seed, ...) that host/validate.py fills in; the validation
# tests run those.  The files are counted, so that an empty or moved
# folder fails instead of passing.
# usage: test_configs_run.sh CAPDEM SOURCE_DIR
set -u
capdem=$1 src=$2
. "$(dirname "${BASH_SOURCE[0]}")/common.sh"
n=0
while IFS= read -r cfg; do
  n=$((n+1))
  rel=${cfg#"$src"/}
  out=(--output "$work/run.h5")
  # the DEM deposits the mpm packing configs after them read (mpm.packing) keep their own names
  case $rel in configs/mpm/*deposit_*.yaml) out=();; esac
  if "$capdem" run "$cfg" "${out[@]}" --overwrite --steps 20 --quiet > out 2> err; then
    ok
  else
    bad "$rel: exit $?"
  fi
done < <(find "$src/configs" -name '*.yaml' -not -path "$src/configs/validation/*" | sort)
[ "$n" -ge 29 ] || bad "only $n run files found under $src/configs (expected at least 29)"
echo "$pass passed, $fails failed ($n run files)"
[ $fails -eq 0 ]
