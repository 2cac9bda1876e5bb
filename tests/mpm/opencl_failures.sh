#!/usr/bin/env bash
# Failures seen late (docs/mpm.md, "Reading nothing between steps"): the
# step reads nothing back, so a step that fails is found at the run's next
# look (a series row, 20 steps on here) and the host goes back to that
# step's start.  Each case below must end on the OpenCL backend as on the
# omp loops of the same binary (which look late as well, on their own
# code): exit status 3, the same "run stopped" message (point, position,
# step, time, the same digits) and run files equal bit for bit (h5diff
# /mpm).  The cases are planted into the last snapshot (step 100) of a CI
# elastic packing, then resumed to step 200:
#   blew_up   a point's velocity NaN: not finite at step 101;
#   left      a point moved 1 m away: its stencil leaves the mesh at step 101;
#   crowded   one point of each of 9 bodies moved onto one spot: 9 bodies at
#             a common node, more than the contact's 8, at step 101;
#   overflow  every body shrunk to 0.3 of its size about its centre and sent
#             outwards at 10^5 /s times its former extent: at the resume's
#             first step the body-node columns get room
#             for 1.25 times its body-nodes + 64; the bodies grow back in
#             about 14 steps, past that room, so the run goes back to the
#             step that overflowed and runs on from there; exit status,
#             message and run files must still be equal (checked: the
#             bodies' windows outgrew the room, from the points' extents in
#             the snapshots written every 20 steps).
# Registered in OpenCL builds, labels backend and mpm.  With a third
# argument, the host-offload build's capdem (mpm_offload_failures, label
# mpm), whose omp loops read nothing back between steps either, stands
# where the OpenCL backend does: its runs are checked against CAPDEM's omp
# (the default build's) in the same way.
# usage: opencl_failures.sh CAPDEM SOURCE_DIR [OFFLOAD_CAPDEM]
set -u
capdem=$1 src=$2 late=opencl
run_late() { "$capdem" "$@" --backend opencl; }
if [ $# -gt 2 ]; then
  late=offload
  offload=$3
  export OMP_TARGET_OFFLOAD=MANDATORY
  run_late() { "$offload" "$@" --backend omp; }
fi
export OMP_WAIT_POLICY=PASSIVE
. "$src/tests/cli/common.sh"

sed 's/snapshot_every: 400/snapshot_every: 20/' "$src/configs/mpm/ci/packing_elastic.yaml" > pack.yaml
sed 's/young_modulus: 1.0e7/young_modulus: 1.0e4/' pack.yaml > soft.yaml
"$capdem" run "$src/configs/mpm/ci/deposit_disks.yaml" --quiet > log 2>&1 && ok || bad "the CI deposit"
"$capdem" run pack.yaml --steps 100 --output base.h5 --quiet > log 2>&1 && ok || bad "the packing to step 100"

plant() { # plant NAME PYTHON: a copy of base.h5 with the last snapshot changed by PYTHON (x, y, vx, vy, body)
  cp base.h5 "$1.h5"
  /usr/bin/python3 -c "
import h5py, numpy as np
f = h5py.File('$1.h5', 'r+')
S = '/mpm/snapshots/'
k = f[S + 'position'].shape[0] - 1
x = f[S + 'position'][k]; v = f[S + 'velocity'][k]; body = f['/mpm/points/particle'][()]
$2
f[S + 'position'][k] = x; f[S + 'velocity'][k] = v" || bad "planting $1"
}
plant blew_up "v[5, 0] = np.nan"
plant left "x[7, 0] += 1.0"
plant crowded "
spot = x[np.argmax(body == 0)]
for b in range(9): x[np.argmax(body == b)] = spot"
plant overflow "
for b in np.unique(body):
    c = x[body == b].mean(0); d = x[body == b] - c
    x[body == b] = c + 0.3 * d; v[body == b] = 1e5 * d"

for case in blew_up left crowded overflow; do
  for b in omp $late; do
    cp "$case.h5" "${case}_$b.h5"
    cfg=pack.yaml
    [ $case = overflow ] && cfg="soft.yaml --allow-change mpm.material.young_modulus"
    if [ $b = omp ]; then
      "$capdem" run $cfg --steps 200 --resume "${case}_$b.h5" --backend omp > "${case}_$b.log" 2>&1
    else
      run_late run $cfg --steps 200 --resume "${case}_$b.h5" > "${case}_$b.log" 2>&1
    fi
    echo $? > "${case}_$b.rc"
    grep -v "^capdem: mpm:\|^step " "${case}_$b.log" | sed "s/${case}_$b\.h5/RUN.h5/g" > "${case}_$b.msg"
  done
  want=3
  [ $case = overflow ] && want=$(cat overflow_omp.rc)
  [ "$(cat ${case}_omp.rc)" = $want ] && [ "$(cat ${case}_$late.rc)" = $want ] && ok \
    || bad "$case: exit status omp $(cat ${case}_omp.rc), $late $(cat ${case}_$late.rc), expected $want"
  cmp -s "${case}_omp.msg" "${case}_$late.msg" && ok \
    || { bad "$case: the messages differ"; diff "${case}_omp.msg" "${case}_$late.msg" | head -6; }
  h5diff "${case}_omp.h5" "${case}_$late.h5" /mpm > diff 2>&1 && ok \
    || { bad "$case: the run files differ"; head -5 diff; }
done
# the way back to a failing step, checked apart from the comparison (both sides take it): the
# walls' positions and the time of every series row as stepping gives them, x_0 + v t and t = step dt
for f in *_omp.h5 *_$late.h5; do
  /usr/bin/python3 -c "
import h5py, numpy as np
f = h5py.File('$f', 'r')
S = '/mpm/series/'
x, t, step = f[S + 'wall_position'][()], f[S + 'time'][()], f[S + 'step'][()]
v = f['/mpm/walls/velocity'][()]
dt = t[1] / step[1]
walls = np.abs(x - x[0] - v[None] * t[:, None, None]).max()
clock = np.abs(t - step * dt).max() / t[-1]
print('$f: walls off x_0 + v t by %.2g m at most, time off step dt by %.2g' % (walls, clock))
raise SystemExit(0 if walls < 1e-12 and clock < 1e-12 else 1)
" && ok || bad "$f: a series row's walls or time are not those of its step"
done
grep -q "run stopped: material point [0-9]* is not finite .* at step 101 " blew_up_omp.msg && ok \
  || bad "blew_up: not the message expected: $(cat blew_up_omp.msg)"
grep -q "run stopped: material point 7 at .* step 100) left the background mesh" left_omp.msg && ok \
  || bad "left: not the message expected: $(cat left_omp.msg)"
grep -q "run stopped: common node .* at step 101: 9 bodies meet there" crowded_omp.msg && ok \
  || bad "crowded: not the message expected: $(cat crowded_omp.msg)"
grep -q "keeps the snapshots written before step 100" crowded_$late.msg && ok \
  || bad "crowded on OpenCL: not back at step 100: $(cat crowded_$late.msg)"
# the overflow case: the bodies' windows (their points' extent in cells + 3 for the stencil) at the
# resumed step and at the largest snapshot after it, against the room the first step gave them
h=$(sed -n 's/.*(h = \([0-9.e+-]*\) m).*/\1/p' overflow_omp.log)
/usr/bin/python3 -c "
import h5py, numpy as np
f = h5py.File('overflow_omp.h5', 'r')
S = '/mpm/snapshots/'
h = float('$h')  # the cell [m], from the run's first line
n = int(f.attrs['n_snapshots']); body = f['/mpm/points/particle'][()]; step = f[S + 'step'][:n]
def nodes(k):
    x = f[S + 'position'][k]
    return sum(np.prod(np.floor((x[body == b].max(0) - x[body == b].min(0)) / h) + 4) for b in np.unique(body))
k0 = int(np.flatnonzero(step == 100)[0])
first, most = nodes(k0), max(nodes(k) for k in range(k0 + 1, n))
print('about %d body-nodes at step 100, up to %d at steps %s' % (first, most, list(step[k0 + 1:n])))
raise SystemExit(0 if most > 1.25 * first + 64 + 2 * len(np.unique(body)) * 8 else 1)
" > grew 2>&1 && ok || bad "overflow: the windows did not outgrow the buffers' room: $(cat grew)"
cat grew
echo "opencl_failures: $pass passed, $fails failed"
[ $fails = 0 ]
