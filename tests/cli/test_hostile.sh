#!/usr/bin/env bash
# Hostile files are refused, never obeyed (issue 18 item 8; docs/output.md,
# "Hostile files"): each case below takes a small real run file, rewrites
# one dataset with h5py into a shape or type the layout does not allow
# (the recipe is the case's Python line; HDF5 writes valid checksums, so
# only the readers' shape checks stop it), and runs the readers on it.
# A refusal is exit 2 with a message naming the dataset; a crash (exit
# >= 128, e.g. 139 for SIGSEGV), any other exit or a missing name fails.
# Cases marked "tolerated" may also exit 0 (the value is ignored), but
# must never crash.  At the end, what capdem starts and writes: render's
# Python runs isolated, export never writes through a planted link or into
# a file it did not write (the XDMF's temporary name, the sidecar).
# usage: test_hostile.sh CAPDEM SOURCE_DIR
set -u
capdem=$1 src=$2
. "$(dirname "${BASH_SOURCE[0]}")/common.sh"
py=/usr/bin/python3
"$py" -c 'import h5py, numpy' 2> err || { bad "h5py and numpy are needed to craft the files"; exit 1; }
cfg="$src/configs/protocols/ci/radial_spheres.yaml"
"$capdem" run "$cfg" --output ref.h5 --steps 200 --quiet 2> err || { bad "the reference run failed"; exit 1; }

# craft NAME 'PYTHON' : copy of ref.h5 as NAME.h5, PYTHON run with f open
# read-write; helper re(path, data) replaces a dataset, keeping its attributes.
craft() {
  cp ref.h5 "$1.h5"
  "$py" - "$1.h5" "$2" <<'EOF' || { bad "crafting $1 failed"; return 1; }
import sys, h5py, numpy as np
f = h5py.File(sys.argv[1], "r+")
def re(path, data):
    attrs = dict(f[path].attrs)
    del f[path]
    d = f.create_dataset(path, data=data)
    for k, v in attrs.items():
        d.attrs[k] = v
exec(sys.argv[2])
f.close()
EOF
}

# expect NAME WHAT DATASET MODE -- COMMAND...: MODE refuse (exit 2 and
# DATASET named on stderr) or tolerate (that, or exit 0).
expect() {
  local name=$1 what=$2 dset=$3 mode=$4
  shift 5
  timeout 120 "$@" > out 2> err
  local rc=$?
  if [ $rc -eq 2 ] && grep -qF -- "$dset" err; then
    ok; echo "ok   $name, $what: exit 2: $(head -c 300 err | head -n 1)"
  elif [ $rc -eq 0 ] && [ "$mode" = tolerate ]; then
    ok; echo "ok   $name, $what: exit 0 (tolerated)"
  else
    bad "$name, $what: exit $rc, expected a refusal (exit 2) naming $dset"
  fi
}

resume() { expect "$1" "run --resume" "$2" "$3" -- "$capdem" run "$cfg" --resume "$1.h5" --steps 400 --quiet; }
analyze() { expect "$1" analyze "$2" "$3" -- "$capdem" analyze "$1.h5" --measures compaction,rdf --no-write --quiet; }
export_() { expect "$1" export "$2" "$3" -- "$capdem" export "$1.h5" -o "$1.xmf"; }

# the intact file passes every reader (exit 0; "(none)" is never named)
for c in resume analyze export_; do
  cp ref.h5 intact.h5
  $c intact "(none)" tolerate
done

# /walls/control with 4096 columns (was: SIGSEGV on --resume, control[32])
craft control_wide 're("/walls/control", np.zeros((2, 4096)))' &&
  { resume control_wide /walls/control refuse; analyze control_wide /walls/control refuse; }
# /walls/control as integers of rank 1
craft control_rank1 're("/walls/control", np.zeros(4096, dtype=np.int64))' &&
  { resume control_rank1 /walls/control refuse; analyze control_rank1 /walls/control refuse; }
# /walls/control of the right shape whose slots used as indices are out of range (wall 1e9, probes -5)
craft control_values 'c = f["/walls/control"][()]; c[:, 2] = 1e9; c[:, 9] = -5; re("/walls/control", c)' &&
  resume control_values /walls/control refuse
# /wall_contacts/index of rank 2, 4096 columns (was: heap overflow, a buffer for one column)
craft windex_rank2 're("/wall_contacts/index", np.zeros((1, 4096), dtype=np.int64))' &&
  { resume windex_rank2 /wall_contacts/index refuse; analyze windex_rank2 /wall_contacts/index refuse; }
# /parameters/config as 4096 fixed-length strings (was: SIGSEGV in analyze)
craft config_array 're("/parameters/config", np.array([f["/parameters/config"][()]] * 4096))' &&
  { resume config_array /parameters/config refuse; analyze config_array /parameters/config refuse; }
# /parameters/config as 4096 variable-length strings
craft config_vlen 're("/parameters/config", np.array(["x"] * 4096, dtype=h5py.string_dtype()))' &&
  { resume config_vlen /parameters/config refuse; analyze config_vlen /parameters/config refuse; }
# /parameters/config as numbers
craft config_float 're("/parameters/config", np.zeros(4))' &&
  { resume config_float /parameters/config refuse; analyze config_float /parameters/config refuse; }
# /observables/*/time and step longer than value (was: invalid write)
craft obs_clock 're("/observables/contacts/time", np.zeros(4096)); re("/observables/contacts/step", np.zeros(4096, dtype=np.int64))' &&
  analyze obs_clock /observables/contacts/time refuse
# /observables/*/value of rank 3
craft obs_rank3 're("/observables/contacts/value", np.zeros((2, 64, 64)))' &&
  analyze obs_rank3 /observables/contacts/value refuse
# a unit attribute of 256 strings: ignored, never read into a short buffer (tolerated)
craft unit_array 'f["/observables/contacts/value"].attrs["unit"] = np.array([b"m" * 8] * 256); f["/particles/all/position/value"].attrs["unit"] = np.array([b"m" * 8] * 256)' &&
  { analyze unit_array /observables/contacts/value tolerate; export_ unit_array /particles/all/position/value tolerate; }
# /walls/step of rank 2 (a clock read one value per snapshot)
craft step_rank2 're("/walls/step", np.zeros((2, 4096), dtype=np.int64))' &&
  { resume step_rank2 /walls/step refuse; export_ step_rank2 /walls/step refuse; }
# /contacts/offset of rank 2
craft offset_rank2 're("/contacts/offset", np.zeros((3, 4096), dtype=np.int64))' &&
  { resume offset_rank2 /contacts/offset refuse; export_ offset_rank2 /contacts/offset refuse; }
# /contacts/offset claiming 2^62 contact rows (sizes multiplied from it must not overflow)
craft offset_huge 're("/contacts/offset", np.array([0, 1 << 61, 1 << 62], dtype=np.int64))' &&
  { resume offset_huge /contacts/ refuse; export_ offset_huge /contacts/ refuse; }
# the commit record n_snapshots as 4096 numbers (was read into one long long)
craft commit_array 'f.attrs["n_snapshots"] = np.full(4096, 2, dtype=np.int64)' &&
  { resume commit_array /n_snapshots refuse; analyze commit_array /n_snapshots refuse; export_ commit_array /n_snapshots refuse; }
# the shape catalogue's count as 4096 numbers (was read into one int32)
craft shapes_count 'f["/parameters/shapes"].attrs["count"] = np.full(4096, 1, dtype=np.int32)' &&
  analyze shapes_count "/parameters/shapes count" refuse
# /walls/value as plain doubles instead of wall records
craft walls_float 're("/walls/value", np.zeros((2, 1)))' &&
  resume walls_float /walls/value refuse

# ---- what capdem starts and writes (issue 18 item 8) ----
# render starts Python isolated: an h5py.py in the current folder or on
# PYTHONPATH never runs (it would leave "planted" behind).
mkdir -p plant/cwd plant/path
for d in cwd path; do
  printf 'open(%s, "w").write("ran")\nraise ImportError("planted")\n' "'$work/plant/$d/ran'" > "plant/$d/h5py.py"
done
(cd plant/cwd && PYTHONPATH="$work/plant/path" "$capdem" render "$work/ref.h5" -o "$work/plant/r.png" > /dev/null 2> "$work/err")
if [ ! -e plant/cwd/ran ] && [ ! -e plant/path/ran ]; then
  ok; echo "ok   render: a planted h5py.py in the current folder or on PYTHONPATH does not run"
else
  bad "render ran a planted h5py.py ($(ls plant/*/ran))"
fi
# export's XDMF goes through an unpredictable temporary name: a link
# planted at the name the process id would give is not written through.
echo victim > victim.txt
sh -c 'ln -s "$1/victim.txt" "$1/x.xmf.tmp$$"; exec "$2" export "$1/ref.h5" -o "$1/x.xmf"' sh "$work" "$capdem" \
  > /dev/null 2> err
if [ "$(cat victim.txt)" = victim ] && [ -f x.xmf ] && [ ! -L x.xmf ] && grep -q '<Xdmf' x.xmf; then
  ok; echo "ok   export: a link at the predictable temporary name is not followed"
else
  bad "export wrote through a link at its temporary name (victim: $(head -c 40 victim.txt))"
fi
# The sidecar of a read-only run file (root writes any file: as root the
# export runs as nobody): a link planted at its name, dangling or to a
# writable file or HDF5 file, and an existing file that is not a sidecar,
# are refused (exit 2, naming the sidecar) and nothing is written.
runas=()
if [ "$(id -u)" = 0 ]; then
  runas=(setpriv --reuid="$(id -u nobody)" --regid="$(id -g nobody)" --clear-groups)
  chmod 711 "$work"
  "${runas[@]}" test -x "$capdem" || { bad "nobody cannot run $capdem (the sidecar cases need a user without root)"; runas=(false); }
fi
sidecar() {  # NAME SETUP: a read-only copy of ref.h5 in ro_NAME/, SETUP run there, export as nobody
  local name=$1
  mkdir -p "ro_$name" && chmod 777 "ro_$name" && cp ref.h5 "ro_$name/r.h5" && chmod 444 "ro_$name/r.h5"
  (cd "ro_$name" && eval "$2")
  "${runas[@]}" "$capdem" export "$work/ro_$name/r.h5" -o "$work/ro_$name/r.xmf" > out 2> err
  local rc=$?
  if [ $rc -eq 2 ] && grep -q 'r.viz.h5' err && [ ! -e "ro_$name/r.xmf" ]; then
    ok; echo "ok   export sidecar $name: exit 2: $(head -n 1 err | head -c 200)"
    return 0
  fi
  bad "export sidecar $name: exit $rc, expected a refusal (exit 2) naming r.viz.h5"
  return 1
}
sidecar link_file 'echo victim > victim.txt; chmod 666 victim.txt; ln -s victim.txt r.viz.h5' &&
  { [ "$(cat ro_link_file/victim.txt)" = victim ] || bad "export sidecar link_file: the link's target was written"; }
sidecar link_dangling 'ln -s made_through_link.h5 r.viz.h5' &&
  { [ ! -e ro_link_dangling/made_through_link.h5 ] || bad "export sidecar link_dangling: a file was made through the link"; }
sidecar link_hdf5 'cp ../ref.h5 other.h5; chmod 666 other.h5; ln -s other.h5 r.viz.h5' &&
  { cmp -s ro_link_hdf5/other.h5 ref.h5 || bad "export sidecar link_hdf5: the link's target was changed"; }
sidecar not_sidecar 'echo notes > r.viz.h5; chmod 666 r.viz.h5' &&
  { [ "$(cat ro_not_sidecar/r.viz.h5)" = notes ] || bad "export sidecar not_sidecar: the file was truncated"; }
sidecar other_hdf5 'cp ../ref.h5 r.viz.h5; chmod 666 r.viz.h5' &&
  { cmp -s ro_other_hdf5/r.viz.h5 ref.h5 || bad "export sidecar other_hdf5: the file was changed"; }
# the intact case: a new sidecar, then the same sidecar used again
mkdir -p ro_ok && chmod 777 ro_ok && cp ref.h5 ro_ok/r.h5 && chmod 444 ro_ok/r.h5
for i in 1 2; do
  if "${runas[@]}" "$capdem" export "$work/ro_ok/r.h5" > out 2> err && [ -s ro_ok/r.viz.h5 ] && grep -q 'r.viz.h5:/visualization' ro_ok/r.xmf; then
    ok; echo "ok   export of a read-only run file, run $i: helpers in r.viz.h5"
  else
    bad "export of a read-only run file, run $i"
  fi
done

# Files on which libhdf5 itself divides by zero or reads a wild address
# while opening a dataset (found by fuzz_runfile; tests/fuzz/hdf5_defects):
# a refusal naming the signal (src/io/io_h5_guard.c), the file unchanged.
for defect in chunk-layout-division-by-zero:SIGFPE group-btree-read-segv:SIGSEGV; do
  name=${defect%%:*} sig=${defect##*:}
  cp "$src/tests/fuzz/hdf5_defects/$name.h5" "$name.h5"
  analyze "$name" "stopped by $sig" refuse
  export_ "$name" "stopped by $sig" refuse
  cmp -s "$name.h5" "$src/tests/fuzz/hdf5_defects/$name.h5" || bad "$name: the file was changed"
done

echo "$pass passed, $fails failed"
[ $fails -eq 0 ]
