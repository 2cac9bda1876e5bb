#!/usr/bin/env bash
# I/O faults end cleanly (docs/output.md, "Full disks and write errors"): a
# file size limit (ulimit -f, the way to test a full disk without root)
# ends the run with exit status 1 and one message, never a signal; the
# file keeps every committed snapshot, stays readable, and --resume
# continues from the last one; --overwrite that fails before its first
# snapshot leaves the old file as it was.
# usage: test_io_faults.sh CAPDEM SOURCE_DIR
set -u
capdem=$1
. "$(dirname "${BASH_SOURCE[0]}")/common.sh"
limited() { local kib=$1; shift; (ulimit -f "$kib"; exec "$capdem" "$@"); }

# 200 spheres, a snapshot every 100 steps: about 2.7 MB with the first snapshot, 30 KB more a snapshot
printf 'particles: [{shape: sphere, diameter: 0.005, count: 200}]\ndomain: {type: box, width: 0.05, height: 0.1, thickness: 0.05}\nrun: {steps: 6000, snapshot_every: 100, thermo_every: 10}\n' > run.yaml

limited 3600 run run.yaml --quiet --output full.h5 2> err
rc=$?
n=$(snapshots full.h5)
if [ $rc -eq 1 ] && [ "$(grep -c 'no room to write' err)" -eq 1 ] && grep -q 'File too large' err \
   && grep -q "keeps its complete snapshots, the last at step $(( (n - 1) * 100 ))" err && [ -n "$n" ] && [ "$n" -ge 2 ] \
   && [ "$n" -lt 61 ]; then ok; else bad "file size limit: exit $rc, $n snapshots, expected exit 1, one message, 2..60 snapshots"; fi
h5dump -H full.h5 > /dev/null 2>&1 && ok || bad "file size limit: h5dump cannot read the file"
"$capdem" recover full.h5 | grep -q 'nothing to recover' && ok || bad "recover after the file size limit: the commit was not whole"
"$capdem" recover no_such.h5 2> /dev/null; [ $? -eq 2 ] && ok || bad "recover of a missing file: exit 2 expected"
if "$capdem" run run.yaml --quiet --resume full.h5 2> err && [ "$(snapshots full.h5)" = 61 ]; then ok
else bad "resume after the file size limit: $(snapshots full.h5) snapshots, expected 61"; fi

# the limit reached while resuming: the resumed file keeps what it had
cp full.h5 again.h5
limited $(( $(stat -c %s again.h5) / 1024 + 300 )) run run.yaml --quiet --resume again.h5 --steps 9000 2> err
rc=$?
n=$(snapshots again.h5)
[ $rc -eq 1 ] && [ "$n" -ge 61 ] && [ "$n" -lt 91 ] && ok || bad "limit during a resume: exit $rc, $n snapshots, expected 1 and 61..90"
"$capdem" run run.yaml --quiet --resume again.h5 --steps 9000 2> err && [ "$(snapshots again.h5)" = 91 ] && ok \
  || bad "second resume: $(snapshots again.h5) snapshots, expected 91"

# no room for the first snapshot: exit 1, said so
limited 400 run run.yaml --quiet --output tiny.h5 2> err
rc=$?
[ $rc -eq 1 ] && grep -q 'the run stops before its first snapshot' err && ok || bad "no room for the first snapshot: exit $rc"

# --overwrite that fails before its first snapshot: the old file as it was, nothing beside it
cp full.h5 keep.h5
limited 400 run run.yaml --quiet --output full.h5 --overwrite 2> err
rc=$?
[ $rc -eq 1 ] && cmp -s full.h5 keep.h5 && ok || bad "--overwrite under the limit: exit $rc, old file changed?"
[ -z "$(ls -A | grep '^\.full\.h5\.')" ] && ok || bad "--overwrite under the limit left $(ls -A | grep '^\.full')"

# the output's folder removed during the run: exit 1, said so, no signal
mkdir gone
printf 'particles: [{shape: sphere, diameter: 0.005, count: 8}]\ndomain: {type: box, width: 0.05, height: 0.05, thickness: 0.05}\nrun: {steps: 400000, snapshot_every: 2000}\n' > long.yaml
"$capdem" run long.yaml --quiet --output gone/run.h5 2> err &
pid=$!
for _ in $(seq 100); do [ -f gone/run.h5 ] && break; sleep 0.05; done
rm -rf gone
wait $pid
rc=$?
[ $rc -eq 1 ] && grep -q 'gone/run.h5 was deleted during the run' err && ok || bad "folder removed during the run: exit $rc"

echo "$pass passed, $fails failed"
[ $fails -eq 0 ]
