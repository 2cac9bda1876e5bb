#!/usr/bin/env bash
# Bad input is refused with exit status 2 and a message naming the file and
# the key; a good short run writes a readable file.
# usage: test_cli_errors.sh CAPDEM SOURCE_DIR
set -u
capdem=$1
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fails=0
pass=0

# expect_refusal NAME KEY_REGEX  (config text on stdin)
expect_refusal() {
  local name=$1 pattern=$2 file="$work/$1.yaml"
  cat > "$file"
  "$capdem" run "$file" --quiet > "$work/out" 2> "$work/err"
  local rc=$?
  if [ $rc -ne 2 ]; then
    echo "FAIL $name: exit status $rc, expected 2"; cat "$work/err"; fails=$((fails+1)); return
  fi
  if ! grep -q "$name.yaml" "$work/err" || ! grep -Eq "$pattern" "$work/err"; then
    echo "FAIL $name: message does not name the file and /$pattern/:"; cat "$work/err"; fails=$((fails+1)); return
  fi
  pass=$((pass+1))
}

base='particles: [{shape: sphere, diameter: 0.005, count: 8}]
domain: {type: box, width: 0.05, height: 0.05, thickness: 0.05}'

expect_refusal unknown_key 'material\.stiffness' < <(printf '%s\nmaterial: {stiffness: 1e5}\n' "$base")
expect_refusal wrong_type 'run\.steps' < <(printf '%s\nrun: {steps: many}\n' "$base")
expect_refusal negative_stiffness 'material\.kn' < <(printf '%s\nmaterial: {kn: -1.0e5}\n' "$base")
expect_refusal negative_friction 'material\.friction' < <(printf '%s\nmaterial: {friction: -0.1}\n' "$base")
expect_refusal restitution_above_one 'material\.restitution' < <(printf '%s\nmaterial: {restitution: 1.2}\n' "$base")
expect_refusal dt_above_fifth_of_collision_time 'run\.dt' < <(printf '%s\nrun: {dt: 1.0e-4}\n' "$base")
expect_refusal particles_do_not_fit 'particles.*do not fit' < <(printf 'particles: [{shape: hexapod, aspect: 3, diameter: 0.005, count: 500}]\ndomain: {type: box, width: 0.05, height: 0.05, thickness: 0.05}\n')

# A sphere on springs far too soft for its weight (kn 0.5 N/m: static overlap
# m g / (kn/2) = 0.51 d) overlaps the floor beyond half its diameter: exit 3
# with the limit named; with run.max_overlap 2 the same run ends normally.
soft='particles: [{shape: sphere, diameter: 0.005, count: 1}]
domain: {type: box, width: 0.02, height: 0.02, thickness: 0.02}
material: {kn: 0.5, kt: 0.25}
init: {speed: 0}'
printf '%s\nrun: {dt: 1.0e-4, steps: 3000, thermo_every: 10, output: %s}\n' "$soft" "$work/soft.h5" > "$work/soft.yaml"
"$capdem" run "$work/soft.yaml" --quiet 2> "$work/err"
rc=$?
if [ $rc -eq 3 ] && grep -q "run.max_overlap = 0.5" "$work/err" && h5dump -H "$work/soft.h5" > /dev/null 2>&1; then
  pass=$((pass+1))
else
  echo "FAIL overlap limit: exit status $rc, expected 3 naming run.max_overlap, file readable"; cat "$work/err"; fails=$((fails+1))
fi
printf '%s\nrun: {dt: 1.0e-4, steps: 3000, thermo_every: 10, max_overlap: 2, output: %s}\n' "$soft" "$work/soft2.h5" > "$work/soft2.yaml"
if "$capdem" run "$work/soft2.yaml" --quiet 2> "$work/err"; then
  pass=$((pass+1))
else
  echo "FAIL overlap limit 2: the run stopped"; cat "$work/err"; fails=$((fails+1))
fi

# dt above t_col/5 runs when forced (with a warning)
printf '%s\nrun: {dt: 1.0e-4, steps: 10, force_dt: true, output: %s}\n' "$base" "$work/forced.h5" > "$work/forced.yaml"
if "$capdem" run "$work/forced.yaml" --quiet 2> "$work/err" && grep -q warning "$work/err"; then
  pass=$((pass+1))
else
  echo "FAIL forced dt"; cat "$work/err"; fails=$((fails+1))
fi

# a good run writes a file h5dump can read, with the config echoed
printf '%s\nrun: {steps: 200, snapshot_every: 100, output: %s}\n' "$base" "$work/good.h5" > "$work/good.yaml"
if "$capdem" run "$work/good.yaml" --quiet 2> "$work/err" && h5dump -d /parameters/config "$work/good.h5" | grep -q 'shape: sphere'; then
  pass=$((pass+1))
else
  echo "FAIL good run"; cat "$work/err"; fails=$((fails+1))
fi

# the run file names the commit capdem was built from, the one --version
# prints; in a git checkout it is a commit of the checkout's history (HEAD
# when built after the last commit; -dirty when tracked files differed)
commit=$("$capdem" --version | sed -n 's/^capdem .* (commit \(.*\))$/\1/p')
in_file=$(h5dump -a /h5md/creator/commit "$work/good.h5" 2>/dev/null | sed -n 's/^ *(0): "\(.*\)"$/\1/p')
if git -C "$2" rev-parse --git-dir > /dev/null 2>&1; then
  git -C "$2" merge-base --is-ancestor "${commit%-dirty}" HEAD 2>/dev/null && known=yes || known=no
else
  [ "$commit" = unknown ] && known=yes || known=no
fi
if [ -n "$commit" ] && [ "$commit" = "$in_file" ] && [ $known = yes ]; then
  pass=$((pass+1))
else
  echo "FAIL commit: --version '$commit', run file '$in_file', in the checkout's history: $known"; fails=$((fails+1))
fi

# shape JSON has the documented keys
ok=1
"$capdem" shape hexapod --aspect 3 --diameter 0.005 --density 1000 --json > "$work/shape.json" || ok=0
for k in volume area sphericity mass inertia; do grep -q "\"$k\"" "$work/shape.json" || ok=0; done
if [ $ok -eq 1 ]; then pass=$((pass+1)); else echo "FAIL shape --json"; cat "$work/shape.json"; fails=$((fails+1)); fi

"$capdem" shape hexapod --aspect 0.5 > /dev/null 2>&1
if [ $? -eq 2 ]; then pass=$((pass+1)); else echo "FAIL shape with aspect < 1 not refused"; fails=$((fails+1)); fi

echo "$pass passed, $fails failed"
[ $fails -eq 0 ]
