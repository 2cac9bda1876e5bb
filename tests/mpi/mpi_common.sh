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
