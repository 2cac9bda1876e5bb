#!/usr/bin/env bash
# No interpenetration at contacts beyond one cell (issue 23; docs/mpm.md
# "Contact between particles"): the elastic CI compaction
# (configs/mpm/ci/packing_elastic.yaml) continued to step 3,400,
# ln(h_i/h) = 0.43, Phi ~ 0.96 under ~3 MPa, where the contact that tested
# only the line through each node let sliding contacts creep into each
# other past one cell (1.39 h at step 3,200-3,400; 1.26 h already at
# 2,800-3,200).
#
# Two measures, both on the run file:
#  - the contact's own: /mpm/series/penetration, the deepest overlap of two
#    bodies' material along the normal at a contact node, every 20 steps:
#    below one cell h in every row (measured at most 0.50 h, at step 580, with the
#    contact's lines, 1.39 h before);
#  - a geometric one that does not use the contact's chords: at the last
#    snapshot, the points that have a point of another body closer than
#    half their reference side l = sqrt(V / det F).  Two points that close
#    overlap each other (the packing's points are nowhere compressed below
#    0.60 l: their same-body nearest neighbour).  Measured 20 of 2,358
#    points (0.8 %) with the contact's lines, 155 (6.6 %) before; the limit
#    is the geometric middle, 2.3 % (54 points).
# usage: test_mpm_interpenetration.sh CAPDEM SOURCE_DIR
set -u
capdem=$1 src=$2
. "$src/tests/cli/common.sh"
cfg=$src/configs/mpm/ci

. "$src/tests/mpm/mpm_series.sh"
# last NAME FILE COLUMNS: the last snapshot of /mpm/snapshots/NAME, one point a line
last() {
  local n points
  n=$(h5dump -H -d "/mpm/snapshots/$1" "$2" | sed -n 's/.*DATASPACE *SIMPLE { ( \([0-9]*\), \([0-9]*\).*/\1 \2/p')
  points=${n#* } n=${n% *}
  if [ "$3" = 1 ]; then sel="-s $((n - 1)),0 -c 1,$points"; else sel="-s $((n - 1)),0,0 -c 1,$points,$3"; fi
  # shellcheck disable=SC2086
  h5dump -w 0 -A 0 -m %.17g -d "/mpm/snapshots/$1" $sel "$2" | sed -n 's/^ *([0-9,]*): *//p' | tr -d ' ' |
    tr ',' '\n' | sed '/^$/d' | paste -d' ' $(for _ in $(seq "$3"); do printf -- '- '; done)
}

"$capdem" run "$cfg/deposit_disks.yaml" --quiet > out 2> err && [ -f deposit_disks_ci.h5 ] && ok \
  || { bad "the DEM deposit did not run"; echo "test_mpm_interpenetration: $pass passed, $fails failed"; exit 1; }
if "$capdem" run "$cfg/packing_elastic.yaml" --steps 3400 --output run.h5 > out 2> err; then ok; else
  bad "packing run to step 3400: exit status $?"; fi
h=$(sed -n 's/.*(h = \([0-9.e+-]*\) m).*/\1/p' err)
awk -v h="$h" 'BEGIN { exit !(h > 0) }' && ok || bad "no cell size h in the start line"

paste <(series step run.h5) <(series strain run.h5) <(series penetration run.h5) > pen
rows=$(wc -l < pen)
[ "$rows" = 171 ] && ok || bad "$rows series rows, expected 171 (steps 0, 20, ..., 3400)"
awk -v h="$h" '$3 > m { m = $3; s = $1; e = $2 } END { printf "deepest overlap %.3f h at step %d (ln(h_i/h) = %.3f)\n", m / h, s, e }' pen
awk -v h="$h" '$3 >= h { print "step " $1 " (ln(h_i/h) = " $2 "): " $3 / h " h"; bad = 1 } END { exit bad }' pen > msg \
  && ok || bad "two particles overlap by a cell or more: $(head -3 msg)"
tail -1 pen | awk '{ exit !($2 > 0.43) }' && ok || bad "the run did not reach ln(h_i/h) = 0.43: $(tail -1 pen)"

# the geometric measure at the last snapshot
paste -d' ' <(h5dump -w 0 -A 0 -d /mpm/points/particle run.h5 | sed -n 's/^ *([0-9,]*): *//p' | tr -d ' ' |
  tr ',' '\n' | sed '/^$/d') <(last position run.h5 2) <(last volume run.h5 1) <(last deformation_gradient run.h5 4) > pts
awk '{ b[NR] = $1; x[NR] = $2; y[NR] = $3; l[NR] = sqrt($4 / ($5 * $8 - $6 * $7)); near[NR] = 1e300; same[NR] = 1e300 }
     END {
       n = NR
       for (i = 1; i <= n; i++)
         for (j = i + 1; j <= n; j++) {
           d = (x[i] - x[j])^2 + (y[i] - y[j])^2
           if (b[i] != b[j]) { if (d < near[i]) near[i] = d; if (d < near[j]) near[j] = d }
           else { if (d < same[i]) same[i] = d; if (d < same[j]) same[j] = d }
         }
       close_ = 0; smin = 1e300
       for (i = 1; i <= n; i++) { close_ += sqrt(near[i]) < 0.5 * l[i]; r = sqrt(same[i]) / l[i]; if (r < smin) smin = r }
       printf "%d %d %.3f\n", close_, n, smin
     }' pts > geo
read -r close n smin < geo
echo "last snapshot: $close of $n points have a point of another body within half their side; same-body nearest $smin l"
awk -v c="$close" -v n="$n" -v s="$smin" 'BEGIN { exit !(n == 2358 && s > 0.5 && s < 1 && c <= 0.023 * n) }' && ok \
  || bad "interleaved points: $close of $n (limit 2.3 %), same-body nearest $smin l (expected 0.5-1)"

echo "test_mpm_interpenetration: $pass passed, $fails failed"
[ $fails = 0 ]
