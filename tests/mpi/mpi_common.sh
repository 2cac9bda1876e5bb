# Sourced by the MPI tests (label mpi, docs/mpi.md): the helpers of
# tests/cli/common.sh (a scratch folder, pass/fail counters), mpirun as CI
# runs it (two cores, so --oversubscribe; root allowed in containers), one
# OpenMP thread per rank, and a time limit on every run so that a hang
# fails instead of waiting for CTest's.
. "$src/tests/cli/common.sh"
export OMP_NUM_THREADS=1 OMP_WAIT_POLICY=PASSIVE OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
# mpi NP ARGS...: capdem on NP ranks (stderr: rank 0's)
mpi() { local np=$1; shift; timeout 120 mpirun --oversubscribe -np "$np" "$capdem" "$@"; }
# same A B [EXCLUDE...]: h5diff finds the two run files equal (it compares
# values exactly unless given a tolerance), and so does same_bytes.py byte
# for byte (-0 against +0 and NaN payloads included, which h5diff lets
# pass), but for the paths given; the build's commit attribute is the same
# binary's
same() {
  local a=$1 b=$2; shift 2
  local ex=() bx=()
  for p in "$@"; do ex+=(--exclude-path "$p"); bx+=(--exclude "$p"); done
  h5diff "${ex[@]}" "$a" "$b" > diff.txt 2>&1 && /usr/bin/python3 "$src/tests/mpi/same_bytes.py" "${bx[@]}" "$a" "$b" > diff.txt 2>&1
}
# last_rows FILE GROUP: rows of GROUP (contacts, wall_contacts) in the last snapshot
last_rows() {
  h5dump -d "/$2/offset" "$1" | sed -n 's/^ *([0-9]*): *//p' | head -1 | tr -d ' ' | awk -F, '{print $NF - $(NF-1)}'
}
# migrated_with_ghosts LABEL: rank 0's closing line in err says that the
# run migrated particles (at least 10 times) and had ghosts, or the
# comparison of its file proves little
migrated_with_ghosts() {
  local line migrations ghosts
  line=$(grep 'capdem: MPI:' err)
  # "capdem: MPI: R ranks, M migrations ...; per rank now a..b owned particles and c..d ghosts"
  migrations=$(sed -n 's/.* \([0-9]*\) migrations.*/\1/p' <<< "$line")
  ghosts=$(sed -n 's/.*and [0-9]*\.\.\([0-9]*\) ghosts.*/\1/p' <<< "$line")
  if [ "${migrations:-0}" -ge 10 ] && [ "${ghosts:-0}" -ge 1 ]; then ok
  else bad "$1: expected migrations and ghosts, got: $line"; fi
}
# blows_up_as_serial LABEL NP ARGS...: the 2D crosses with a dt far above
# t_col/5 (forced) blow up on NP ranks as on one process: exit status 3
# and the serial program's diagnosis, once
blows_up_as_serial() {
  local label=$1 np=$2 rc stop_serial stop_mpi
  shift 2
  sed 's/^  dt: .*/  dt: 1.5e-4\n  force_dt: true/' "$src/tests/mpi/crosses_2d.yaml" > blowup.yaml
  rm -f blowup1.h5 blowup$np.h5
  "$capdem" run blowup.yaml --output blowup1.h5 --quiet "$@" 2> serial.err
  mpi "$np" run blowup.yaml --output "blowup$np.h5" --quiet "$@" > out 2> err
  rc=$?
  stop_serial=$(grep 'run stopped' serial.err) stop_mpi=$(grep 'run stopped' err)
  if [ $rc -eq 3 ] && [ -n "$stop_serial" ] && [ "$stop_serial" = "$stop_mpi" ]; then ok
  else bad "$label: exit status $rc (expected 3), serial says '$stop_serial', $np ranks say '$stop_mpi'"; fi
}
