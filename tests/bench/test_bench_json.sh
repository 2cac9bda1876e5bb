#!/usr/bin/env bash
# capdem-bench (bench/bench_step.c, docs/performance.md): every case prints
# JSON lines with every key of issue 7 and sane values; a settled packing
# saved with --save-settled loads back with --load-settled (same case and N);
# capdem_to_lammps.py turns it into a LAMMPS data file with the glued-sphere
# count of a hexapod (13 at alpha 3).  Tiny cases: a few seconds on 2 cores.
#   test_bench_json.sh CAPDEM_BENCH SOURCE_DIR
set -euo pipefail
bench=$1
src=$2
py=/usr/bin/python3
dir=$(mktemp -d bench-test.XXXXXX)
trap 'rm -rf "$dir"' EXIT

check() { # CASE N STEPS FILE: every line of FILE is a valid report of CASE
  "$py" - "$@" <<'PY'
import json, sys
case, n, steps, path = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), sys.argv[4]
keys = ["case", "N", "backend", "device", "threads", "steps", "wall_s", "particle_steps_per_s",
        "contact_updates_per_s", "contacts_per_particle", "bytes_per_particle",
        "bytes_moved_per_particle_step", "kernel_bytes_read_written"]
lines = [l for l in open(path) if l.strip()]
assert lines, "no JSON line"
for l in lines:
    r = json.loads(l)
    missing = [k for k in keys if k not in r]
    assert not missing, "missing keys %s in %s" % (missing, l)
    assert r["case"] == case and r["N"] == n and r["steps"] == steps, l
    assert r["backend"] and r["device"] and r["threads"] >= 1, l
    assert r["wall_s"] > 0, l
    rate = r["N"] * r["steps"] / r["wall_s"]
    assert abs(r["particle_steps_per_s"] - rate) <= 2e-3 * rate + 1e-3 * r["N"] / r["wall_s"], l
    assert r["contact_updates_per_s"] >= 0 and 0 <= r["contacts_per_particle"] < 40, l
    assert 100 < r["bytes_per_particle"] < 1e5, l
    # the traffic model: every loop of the step, read and written bytes per
    # particle-step, adding up to the total (each rounded to 1 B)
    kb = r["kernel_bytes_read_written"]
    assert len(kb) >= 5 and all(len(v) == 2 and v[0] >= 0 and v[1] >= 0 for v in kb.values()), l
    total = sum(v[0] + v[1] for v in kb.values())
    assert abs(total - r["bytes_moved_per_particle_step"]) <= 2 * len(kb), l
    assert 200 < r["bytes_moved_per_particle_step"] < 2e4, l
    # the pair rows' kinds: in the pair pass's visiting order (a mixture's
    # rows grouped by kind) at most the two kind boundaries split a warp
    rows = r["rows"]
    assert sum(rows["pair_rows_by_kind"]) == rows["pair_rows"], l
    assert rows["mixed_warps_visited"][1] == rows["mixed_warps"][1], l
    if rows["visit_order"]:
        assert rows["mixed_warps_visited"][0] <= 2, l
    else:
        assert rows["mixed_warps_visited"] == rows["mixed_warps"], l
    # the host threads' sweep: a row's two particles lie at most sweep_span
    # slots apart in memory; it waits sweep_lag slots, the span or (a state
    # that fits the cache) N; both 0 where the step does not sweep
    assert 0 <= rows["sweep_span"] < r["N"] and 0 <= rows["sweep_lag"] <= r["N"], l
    if r["device"].startswith("host, ") and rows["pair_rows"] > 0:  # host threads
        assert rows["sweep_span"] > 0 and rows["sweep_lag"] in (rows["sweep_span"], r["N"]), l
print("ok", case, len(lines), "lines")
PY
}

for case in spheres crosses2d hexapods_a3 hexapods_a9 mix_spheres_hexapods; do
  "$bench" --case "$case" --n 40 --settle-steps 300 --steps 20 --repeat 2 --threads 1 > "$dir/$case.jsonl" 2> "$dir/$case.err"
  check "$case" 40 20 "$dir/$case.jsonl"
done

# save, then load: same case and N, thread rounds on one packing
"$bench" --case hexapods_a3 --n 60 --settle-steps 500 --repeat 0 --threads 1 --save-settled "$dir/settled.h5" \
  > "$dir/save.jsonl" 2> /dev/null
test ! -s "$dir/save.jsonl" || { echo "--repeat 0 printed a timing"; exit 1; }
"$bench" --load-settled "$dir/settled.h5" --steps 10 --repeat 1 --backend omp:1,omp:2 > "$dir/load.jsonl" 2> /dev/null
check hexapods_a3 60 10 "$dir/load.jsonl"
test "$(wc -l < "$dir/load.jsonl")" -eq 2

# --tile: 2 x 1 copies of the loaded packing, relaxed, then timed
"$bench" --load-settled "$dir/settled.h5" --tile 2,1 --relax-steps 50 --steps 10 --repeat 1 --threads 1 \
  > "$dir/tile.jsonl" 2> /dev/null
check hexapods_a3 120 10 "$dir/tile.jsonl"
# each copy keeps its particles' arms: the second copy's body-frame arm ends
# equal the first's (they came from the tiled box's own deposit, of other
# sizes, before bench_tile.c derived the arms anew)
"$bench" --load-settled "$dir/settled.h5" --tile 2,1 --relax-steps 0 --repeat 0 --threads 1 \
  --save-settled "$dir/tiled.h5" > /dev/null 2>&1
for c in scale prim_a_body prim_b_body; do
  g=all; [ "$c" = scale ] || g=prims
  h5dump -y -w 0 -o "$dir/$c.txt" -d "/particles/$g/$c" "$dir/tiled.h5" > /dev/null
  "$py" - "$dir/$c.txt" "$c" <<'PY'
import sys
v = open(sys.argv[1]).read().replace(",", " ").split()
half = len(v) // 2
assert half and v[:half] == v[half:], "%s: the second copy differs from the first" % sys.argv[2]
PY
done

# bad input: exit status 2 and a message naming the cases
# an unknown case: exit 2 exactly (a crash, 139 or 134, is not a refusal) naming the case and the known ones
rc=0
"$bench" --case tetrahedra --n 10 2> "$dir/bad.err" || rc=$?
if [ $rc -ne 2 ]; then echo "unknown case: exit $rc, expected 2"; cat "$dir/bad.err"; exit 1; fi
grep -q -- "--case tetrahedra: expected one of .*hexapods_a9" "$dir/bad.err"

# the settled packing as LAMMPS glued-sphere clusters
"$py" "$src/bench/lammps/capdem_to_lammps.py" "$dir/settled.h5" "$dir/settled.data" > "$dir/meta.json"
"$py" - "$dir/meta.json" "$dir/settled.data" <<'PY'
import json, sys
m = json.load(open(sys.argv[1]))
assert m["particles"] == 60 and m["rigid"] and m["atoms"] == 13 * 60, m
head = open(sys.argv[2]).read()
assert "780 atoms" in head and "Atoms # hybrid" in head and "Velocities" in head
print("ok converter", m["atoms"], "spheres")
PY
echo "capdem-bench: all checks passed"
