#!/usr/bin/env bash
# No run destroys data it did not create, and resumes are checked
# (docs/output.md, "Output safety" and "Resume from the command line"):
# an existing output, the config itself or a file another run is writing
# is refused with exit status 2 and left byte for byte as it was;
# --overwrite replaces a file only with a run that wrote its first
# snapshot; --resume refuses a config that changes the physics unless
# --allow-change names the key, and refuses --steps behind the file.
# usage: test_output_safety.sh CAPDEM SOURCE_DIR
set -u
capdem=$1
. "$(dirname "${BASH_SOURCE[0]}")/common.sh"
pid1=
trap '[ -n "$pid1" ] && kill -CONT "$pid1" 2> /dev/null && kill "$pid1" 2> /dev/null; rm -rf "$work"' EXIT

# expect CODE REGEX NAME -- capdem args: exit status CODE and a message matching REGEX
expect() {
  local code=$1 pattern=$2 name=$3
  shift 4
  "$capdem" "$@" > out 2> err
  local rc=$?
  if [ $rc -ne "$code" ]; then bad "$name: exit status $rc, expected $code"; return 1; fi
  if ! grep -Eq -- "$pattern" err; then bad "$name: message does not match /$pattern/"; return 1; fi
  ok
}

base='particles: [{shape: sphere, diameter: 0.005, count: 8}]
domain: {type: box, width: 0.05, height: 0.05, thickness: 0.05}'
printf '%s\nrun: {steps: 200, snapshot_every: 100}\n' "$base" > a.yaml
printf '%s\nrun: {steps: 100, snapshot_every: 100}\n' "$base" > short.yaml

# ---- existing outputs ----------------------------------------------------------
"$capdem" run a.yaml --quiet --output r.h5 2> err && [ "$(snapshots r.h5)" = 3 ] && ok || bad "first run"
cp r.h5 r.copy
cp a.yaml a.copy
expect 2 'output r.h5 exists: refused' "existing output" -- run short.yaml --quiet --output r.h5
cmp -s r.h5 r.copy && ok || bad "existing output: the file changed"
expect 2 'output a.yaml is the same file as the input a.yaml' "output = config" -- run a.yaml --quiet --output a.yaml --overwrite
ln -s a.yaml link.yaml
expect 2 'output link.yaml is the same file as the input a.yaml' "output = link to config" -- run a.yaml --quiet --output link.yaml --overwrite
ln a.yaml hard.yaml
expect 2 'output hard.yaml is the same file as the input a.yaml' "output = hard link to config" -- run a.yaml --quiet --output hard.yaml --overwrite
cmp -s a.yaml a.copy && ok || bad "output = config: the config changed"
mkdir dir.h5
expect 2 'dir.h5 exists and is not a regular file' "output is a folder" -- run a.yaml --quiet --output dir.h5 --overwrite
expect 2 'folder no_such_dir does not exist' "missing folder" -- run a.yaml --quiet --output no_such_dir/r.h5

# --overwrite replaces the file (3 snapshots -> 2), nothing is left beside it
"$capdem" run short.yaml --quiet --output r.h5 --overwrite 2> err && [ "$(snapshots r.h5)" = 2 ] && ok || bad "--overwrite"
[ -z "$(ls -A | grep '^\.r\.h5\.')" ] && ok || bad "--overwrite left a file beside the output: $(ls -A)"

# ---- a second run on the file of a running one -----------------------------------
# The first run is stopped (SIGSTOP) as soon as its file exists, so that the
# second one surely meets it running, then continued to its end.
printf '%s\nrun: {steps: 100000, snapshot_every: 20000}\n' "$base" > long.yaml
# marked FILE: capdem's read lock on FILE (io_h5_target.c cdh5_mark: an
# open file description lock, or a POSIX one) shows in /proc/locks
marked() {
  local ino
  ino=$(stat -c %i "$1" 2> /dev/null) || return 1
  grep -Eq "(OFDLCK|POSIX) +ADVISORY +READ .*:$ino " /proc/locks
}
# start_first FILE [ENV=VALUE]: the first run, stopped once FILE exists and
# carries its mark (a fixed pause after the file appeared was too short on
# a loaded machine: the run could be stopped between creating and marking)
start_first() {
  env ${2:-} "$capdem" run long.yaml --quiet --output "$1" 2> err1 &
  pid1=$!
  for _ in $(seq 6000); do marked "$1" && break; sleep 0.01; done
  kill -STOP "$pid1" 2> /dev/null
  sleep 0.05 # past HDF5's open-then-flock
}
# finish_first FILE NAME: continued, it ends with exit 0 and all its snapshots (0, 20000, ..., 100000)
finish_first() {
  kill -CONT "$pid1" 2> /dev/null
  wait "$pid1"; local rc=$?; pid1=
  [ $rc -eq 0 ] && [ "$(snapshots "$1")" = 6 ] && ok || { bad "$2: exit $rc, $(snapshots "$1") snapshots, expected 0 and 6"; cat err1; }
}
start_first same.h5
kill -0 "$pid1" 2> /dev/null && ok || bad "the first run ended before it could be stopped"
expect 2 'output same.h5 exists: refused' "second run, no --overwrite" -- run short.yaml --quiet --output same.h5 --steps 10
expect 2 'same.h5 is in use by another process' "second run, --overwrite" -- run short.yaml --quiet --output same.h5 --steps 10 --overwrite
expect 2 'same.h5 is in use by another process' "resume of a running run" -- run long.yaml --quiet --resume same.h5
finish_first same.h5 "first run"

# the same with HDF5's own file locking switched off: capdem's lock holds
start_first nolock.h5 HDF5_USE_FILE_LOCKING=FALSE
HDF5_USE_FILE_LOCKING=FALSE expect 2 'nolock.h5 is in use by another process' "second run, --overwrite, HDF5 locking off" -- \
  run short.yaml --quiet --output nolock.h5 --steps 10 --overwrite
finish_first nolock.h5 "first run, HDF5 locking off"

# ---- checked resumes -------------------------------------------------------------
cp r.h5 before.h5
printf '%s\nrun: {steps: 400, snapshot_every: 100}\nmaterial: {kn: 2.0e5, friction: 0.9}\n' "$base" > changed.yaml
expect 2 'material\.kn: 100000 in the run file, 200000 given' "resume with changed kn" -- run changed.yaml --quiet --resume r.h5
grep -q 'material\.friction: 0\.5 in the run file, 0\.9 given' err && ok || bad "resume with changed friction: not named"
cmp -s r.h5 before.h5 && ok || bad "refused resume: the run file changed"
expect 2 'material\.kt: 50000 in the run file, 100000 given' "resume allowing kn, friction only" -- \
  run changed.yaml --quiet --resume r.h5 --allow-change material.kn --allow-change material.friction
expect 2 'did you mean material\.friction' "--allow-change of an unknown key" -- run changed.yaml --quiet --resume r.h5 --allow-change material.fricton
expect 2 '--allow-change material.kn: only a --resume' "--allow-change without --resume" -- run a.yaml --quiet --output x.h5 --allow-change material.kn
expect 2 'a resume appends to the file it resumes' "--resume with another --output" -- run short.yaml --quiet --resume r.h5 --output other.h5
expect 2 '--steps 50: the run file r.h5 is at step 100 already' "--steps behind the resumed step" -- run short.yaml --quiet --resume r.h5 --steps 50
cmp -s r.h5 before.h5 && ok || bad "refused resumes: the run file changed"
printf '%s\nrun: {steps: 100, snapshot_every: 50, thermo_every: 10}\n' "$base" > cadence.yaml
if "$capdem" run cadence.yaml --resume r.h5 --steps 300 2> err && grep -q 'run.snapshot_every: 100 in the run file, 50 given' err \
   && [ "$(snapshots r.h5)" = 6 ]; then ok; else bad "resume with another cadence and --steps 300: $(snapshots r.h5) snapshots, expected 6"; fi
if "$capdem" run changed.yaml --quiet --resume r.h5 --allow-change material.kn --allow-change material.kt \
     --allow-change material.friction 2> err && [ "$(snapshots r.h5)" = 7 ]; then ok; else bad "resume with allowed changes"; fi
# the allowed changes are recorded (/parameters/resumes/<k>), and the next
# resume is compared with them: the same config needs no --allow-change
h5dump -a /parameters/resumes/1/step r.h5 2> /dev/null | grep -q '(0): 300' && ok || bad "resume not recorded under /parameters/resumes/1"
if "$capdem" run changed.yaml --quiet --resume r.h5 --steps 500 2> err && [ "$(snapshots r.h5)" = 8 ]; then ok
else bad "second resume with the config of the last one"; fi
expect 2 'material\.kn: 200000 in the run file, 100000 given' "back to the first config" -- run short.yaml --quiet --resume r.h5 --steps 600
grep -q '/parameters/resumes/2 in the run file' err && ok || bad "the refusal does not name the config compared with"
expect 2 'missing.h5: no such run file' "resume of a missing file" -- run a.yaml --quiet --resume missing.h5

echo "$pass passed, $fails failed"
[ $fails -eq 0 ]
