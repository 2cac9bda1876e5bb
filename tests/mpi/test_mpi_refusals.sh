#!/usr/bin/env bash
# Bad input to an MPI run (docs/mpi.md): refused before anything is
# written, with exit status 2 and one message (rank 0's) that names the
# file, the key or the limit, and without a hang (every rank reads the
# same input and refuses at the same point; mpi() times out otherwise).
# A run that blows up stops on every rank as the serial one does.  An
# unknown backend is refused (every backend runs decomposed).
# usage: test_mpi_refusals.sh CAPDEM SOURCE_DIR
set -u
capdem=$1 src=$2
. "$src/tests/mpi/mpi_common.sh"
base="$src/tests/mpi/crosses_2d.yaml"

# refused NAME NP REGEX: the config NAME.yaml on NP ranks: exit 2, /REGEX/ once, no run file
refused() {
  mpi "$2" run "$1.yaml" --output "$1.h5" --quiet > out 2> err
  local rc=$?
  if [ $rc -ne 2 ]; then bad "$1: exit status $rc on $2 ranks, expected 2"; return; fi
  local n
  n=$(grep -Ec "$3" err)
  if [ "$n" -ne 1 ]; then bad "$1: /$3/ printed $n times, expected once (rank 0)"; return; fi
  if [ -e "$1.h5" ]; then bad "$1: a run file was written"; return; fi
  ok
}

{ printf 'mpi:\n  decomposition: metis\n'; cat "$base"; } > unknown_decomposition.yaml
refused unknown_decomposition 3 'unknown_decomposition\.yaml:2: mpi\.decomposition = metis: expected one of cartesian, rcb'
{ printf 'mpi:\n  decomposition: rcb\n  grid: [3, 1, 1]\n'; cat "$base"; } > rcb_grid.yaml
refused rcb_grid 3 'rcb_grid\.yaml: mpi\.grid = \[3, 1, 1\] with mpi\.decomposition = rcb: expected no mpi\.grid'

# one column of three crosses: centres 2 lattice spacings apart in y, none in x
sed 's/count: 30/count: 3/; s/width: 0.15/width: 0.025/' "$base" > too_many_ranks.yaml
refused too_many_ranks 3 'too_many_ranks\.yaml: 3 MPI ranks: more than the domain can be split into.*at most 1 x 2 x 1'
# rcb cuts the column between the first and second cross: the lower
# sub-domain holds half a spacing of centres, under the interaction range;
# and it has one rank per particle at most
{ printf 'mpi:\n  decomposition: rcb\n'; cat too_many_ranks.yaml; } > rcb_narrow.yaml
refused rcb_narrow 2 'rcb_narrow\.yaml: 2 MPI ranks with mpi\.decomposition = rcb: more than the domain can be split into: the sub-domain of rank 0 spans 0\.0117 m along y'
refused rcb_narrow 4 'rcb_narrow\.yaml: 4 MPI ranks with mpi\.decomposition = rcb: expected at most 256 ranks and at most one per particle \(3 particles\)'

{ printf 'mpi:\n  grid: [2, 2, 1]\n'; cat "$base"; } > grid_product.yaml
refused grid_product 3 'grid_product\.yaml: mpi\.grid = \[2, 2, 1\] makes 4 sub-domains, but the run has 3 MPI ranks'

{ printf 'mpi:\n  grid: [1, 1, 2]\n'; cat "$base"; } > grid_2d.yaml
refused grid_2d 2 'grid_2d\.yaml: mpi\.grid = \[1, 1, 2\]: 2 sub-domains along z.*at most 1 along z in 2D'

# An unknown backend (every backend runs under MPI: omp, opencl where
# built, test_mpi_opencl)
cp "$base" backend.yaml
mpi 2 run backend.yaml --output backend.h5 --backend cuda --quiet > out 2> err
if [ $? -eq 2 ] && [ "$(grep -Ec -- '--backend cuda: expected omp or opencl' err)" -eq 1 ] &&
   [ ! -e backend.h5 ]; then ok; else bad "backend: --backend cuda on 2 ranks not refused once with exit 2"; cat err; fi

# the same configs are fine on one process (the refusals are the decomposition's)
if "$capdem" run too_many_ranks.yaml --output one.h5 --steps 10 --quiet 2> err; then ok
else bad "too_many_ranks.yaml: refused on one process too"; fi
# A run that blows up (dt far above t_col/5, forced) stops on every rank
# at once with the serial program's exit status 3 and its diagnosis, once.
blows_up_as_serial blowup 3
echo "test_mpi_refusals: $pass passed, $fails failed"
[ $fails -eq 0 ]
