#!/usr/bin/env bash
# Each rank sets up its own particles and its ghosts only (docs/mpi.md,
# "Set-up"), with the serial program's bits: crosses placed at random with
# their arms apart (init.exclusion = shape: every place tested against all
# crosses placed before it, one random stream) and with bounding spheres
# apart (bounding_sphere), on 2 and 3 ranks, against the serial run; the
# lattice pile of test_mpi_bitwise on 3.  The closing line must show that
# no rank built every particle; so must the radial compaction of spheres
# on 2 ranks and the deposit in a frictionless cylinder on 3, whose begin
# sums every particle's motion.  A run whose start reads every particle
# (domain.walls: the sheared crosses) still builds them all, and says so.
# usage: test_mpi_setup.sh CAPDEM SOURCE_DIR
set -u
capdem=$1 src=$2
. "$src/tests/mpi/mpi_common.sh"

# built_part N: rank 0's "MPI set-up" line in err says each rank built
# fewer than N particles (its own and its ghosts), and at least one
built_part() {
  local line lo hi
  line=$(grep 'capdem: MPI set-up:' err)
  read -r lo hi <<< "$(sed -n 's/.*built or read the rows of \([0-9]*\)\.\.\([0-9]*\) of the .*/\1 \2/p' <<< "$line")"
  if [ -n "${hi:-}" ] && [ "$hi" -lt "$1" ] && [ "$lo" -ge 1 ]; then ok
  else bad "expected each rank to build fewer than $1 particles, got: $line"; fi
}

cfg="$src/tests/mpi/random_crosses.yaml"
sed 's/exclusion: shape/exclusion: bounding_sphere/; s/count: 40/count: 15/' "$cfg" > spheres_apart.yaml
for case in "$cfg" spheres_apart.yaml; do
  name=$(basename "$case" .yaml)
  n=$(sed -n 's/^ *count: \([0-9]*\).*/\1/p' "$case")
  if ! "$capdem" run "$case" --output "$name.serial.h5" --quiet 2> err; then bad "$name: the serial run failed"; continue; fi
  for np in 2 3; do
    if ! mpi "$np" run "$case" --output "$name.$np.h5" --quiet 2> err; then bad "$name: $np ranks: the run failed"; cat err; continue; fi
    if same "$name.serial.h5" "$name.$np.h5"; then ok
    else bad "$name: $np ranks: the run file differs from the serial one"; head -20 diff.txt; fi
    built_part "$n"
  done
done

pile="$src/tests/mpi/hexapod_pile.yaml"
"$capdem" run "$pile" --output pile.serial.h5 --steps 600 --quiet 2> err || bad "pile: the serial run failed"
if mpi 3 run "$pile" --output pile.3.h5 --steps 600 --quiet 2> err && same pile.serial.h5 pile.3.h5; then ok
else bad "pile: 3 ranks: failed or differs from the serial run"; head -20 diff.txt; fi
built_part 40

# Protocols whose begin sums every particle's motion (the ball's net
# motion and rotation, radial compaction and bulk probe; the rotation about
# a frictionless cylinder's axis): rank 0 sums the rows it gathers in
# particle order, each rank changes its own particles and ghosts, and no
# rank builds every particle.  The velocities set there reach the files.
for twin in radial_spheres:2:150 deposit_cylinder_D6L:3:60; do
  IFS=: read -r name np n <<< "$twin"
  cfg="$src/configs/protocols/ci/$name.yaml"
  "$capdem" run "$cfg" --output "$name.serial.h5" --steps 300 --quiet 2> err || bad "$name: the serial run failed"
  if mpi "$np" run "$cfg" --output "$name.$np.h5" --steps 300 --quiet 2> err && same "$name.serial.h5" "$name.$np.h5"; then ok
  else bad "$name: $np ranks: failed or differs from the serial run"; cat err; head -20 diff.txt; fi
  built_part "$n"
done

if mpi 2 run "$src/tests/mpi/crosses_shear.yaml" --output shear.h5 --steps 50 --quiet 2> err &&
  grep -q 'capdem: MPI set-up: every rank built all' err; then ok
else bad "crosses_shear (domain.walls): expected every rank to build all particles: $(grep 'MPI set-up' err)"; fi
echo "test_mpi_setup: $pass passed, $fails failed"
[ $fails -eq 0 ]
