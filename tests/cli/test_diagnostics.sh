#!/usr/bin/env bash
# Diagnostics name the real cause: particles that start across a wall are
# refused at set-up (exit 2, naming the wall and the particle) instead of
# an overlap at the first step; a run that blows up (time step far too
# large) stops with exit 3 as a blow-up, never as "out of memory".
# usage: test_diagnostics.sh CAPDEM SOURCE_DIR
set -u
capdem=$1
. "$(dirname "${BASH_SOURCE[0]}")/common.sh"

# expect CODE REGEX NAME CONFIG_TEXT: capdem run exits CODE, stderr matches REGEX
expect() {
  local code=$1 pattern=$2 name=$3
  printf '%s\n' "$4" > "$name.yaml"
  "$capdem" run "$name.yaml" --quiet --output "$name.h5" > out 2> err
  local rc=$?
  if [ $rc -ne "$code" ]; then
    echo "FAIL $name: exit status $rc, expected $code"; sed 's/^/    /' err; fails=$((fails+1)); return 1
  fi
  if ! grep -Eq -- "$pattern" err; then
    echo "FAIL $name: message does not match /$pattern/:"; sed 's/^/    /' err; fails=$((fails+1)); return 1
  fi
  pass=$((pass+1))
}

box='particles: [{shape: sphere, diameter: 0.005, count: 8}]
run: {steps: 100}'
# an extra wall through the lattice of a box
expect 2 'wall_through_box.yaml: domain.walls\[0\] \(point \[0, 0.01, 0\] m, normal \[0, 1, 0\]\) cuts through the start positions: 8 particles reach across it, the deepest particle 0 \(particles\[0\]' \
  wall_through_box "$box
domain: {type: box, width: 0.05, height: 0.05, thickness: 0.05, walls: [{type: plane, point: [0, 0.01, 0], normal: [0, 1, 0]}]}"
[ ! -e wall_through_box.h5 ] && pass=$((pass+1)) || { echo "FAIL wall_through_box: a refused set-up wrote its output"; fails=$((fails+1)); }
# a floor whose normal points away from the particles
expect 2 'domain.walls\[0\] .*normal \[0, -1, 0\]\) cuts through the start positions: 8 particles reach across it' \
  wall_facing_away "$box
domain: {type: none, walls: [{type: plane, point: [0, -1, 0], normal: [0, -1, 0]}]}"
# the same floor facing the particles is fine
expect 0 '' wall_facing_in "$box
domain: {type: none, walls: [{type: plane, point: [0, -1, 0], normal: [0, 1, 0]}]}"

# a time step 250 times t_col/1 (forced): a blow-up, exit 3, named as one
if expect 3 'run stopped: (non-finite position or velocity|runaway velocity).*the run blew up' blowup \
  'particles: [{shape: sphere, diameter: 0.005, count: 27}]
domain: {type: box, width: 0.02, height: 0.02, thickness: 0.02}
run: {steps: 2000, dt: 1.0e-3, force_dt: true}
init: {clearance: 1.0}'; then
  if grep -q 'out of memory' err; then
    echo "FAIL blowup: reported as out of memory"; fails=$((fails+1))
  fi
fi

echo "$pass passed, $fails failed"
[ $fails -eq 0 ]
