#!/usr/bin/env bash
# Every number on the command line is parsed strictly (one helper,
# cd_parse_cli_int / cd_parse_cli_real in src/config/config_cli.c): garbage,
# negatives, trailing characters and overflow are refused with exit status 2
# and a message naming the option, the value and what was expected; nothing
# is written.  capdem run, capdem shape and capdem-bench.
# usage: test_cli_numbers.sh CAPDEM SOURCE_DIR
set -u
capdem=$1
bench=$(dirname "$capdem")/capdem-bench
. "$(dirname "${BASH_SOURCE[0]}")/common.sh"

# expect CODE REGEX NAME -- command: exit status CODE, stderr matching REGEX
expect() {
  local code=$1 pattern=$2 name=$3
  shift 4
  "$@" > out 2> err
  local rc=$?
  if [ $rc -ne "$code" ]; then
    echo "FAIL $name: exit status $rc, expected $code"; sed 's/^/    /' err; fails=$((fails+1)); return
  fi
  if ! grep -Eq -- "$pattern" err; then
    echo "FAIL $name: message does not match /$pattern/:"; sed 's/^/    /' err; fails=$((fails+1)); return
  fi
  pass=$((pass+1))
}

printf 'particles: [{shape: sphere, diameter: 0.005, count: 8}]\ndomain: {type: box, width: 0.05, height: 0.05, thickness: 0.05}\nrun: {steps: 20}\n' > a.yaml

for v in -5 abc 1e3 20x '' ' 7' 0x10 99999999999999999999; do
  expect 2 "^capdem run: --steps $v: (out of range, )?expected an integer >= 0$" "run --steps '$v'" -- \
    "$capdem" run a.yaml --quiet --output n.h5 --steps "$v"
done
for v in 0 -1 2x 1.5 '' 5000; do
  expect 2 "^capdem run: --threads $v: expected an integer in \[1, 4096\]$" "run --threads '$v'" -- \
    "$capdem" run a.yaml --quiet --output n.h5 --threads "$v"
done
[ ! -e n.h5 ] && pass=$((pass+1)) || { echo "FAIL: a refused command line wrote n.h5"; fails=$((fails+1)); }
# good numbers still work
expect 0 'output g.h5' "run --steps 10 --threads 1" -- "$capdem" run a.yaml --quiet --output g.h5 --steps 10 --threads 1
# capdem analyze --snapshot: last or an integer (negative from the end), nothing else
for v in 1e3 2x '' ' 1' 1.0; do
  expect 2 "^capdem analyze: --snapshot $v: expected an integer in .* \(or last\)$" "analyze --snapshot '$v'" -- \
    "$capdem" analyze g.h5 --snapshot "$v" --no-write --quiet
done
for v in 3x nan inf ''; do
  expect 2 "^capdem: --aspect $v: expected a finite number$" "shape --aspect '$v'" -- "$capdem" shape rod --aspect "$v"
done

# capdem-bench: refused before any set-up
for opt in --n --steps --settle-steps --relax-steps --repeat --seed --threads; do
  for v in -1 abc 10x 99999999999999999999; do
    expect 2 "^capdem-bench: $opt $v: (out of range, )?expected an integer" "bench $opt '$v'" -- "$bench" $opt "$v"
  done
done
expect 2 '^capdem-bench: --gravity -9.81: expected a number >= 0' "bench --gravity -9.81" -- "$bench" --gravity -9.81
expect 2 '^capdem-bench: --gravity 9.81g: expected a number >= 0' "bench --gravity 9.81g" -- "$bench" --gravity 9.81g
for v in 2 2,0 2,3x x,2 ,2; do
  expect 2 "^capdem-bench: --tile $v: expected KX,KZ" "bench --tile '$v'" -- "$bench" --tile "$v"
done
expect 2 '^capdem-bench: --backend NAME:THREADS 1x: expected an integer in \[1, 4096\]' "bench --backend omp:1x" -- \
  "$bench" --case spheres --n 8 --settle-steps 1 --steps 1 --repeat 1 --backend omp:1x

echo "$pass passed, $fails failed"
[ $fails -eq 0 ]
