#!/bin/bash
# The deposit-and-compress driver of studies 2-4 (host/validate.py study2,
# docs/validation.md) end to end at toy size: 30 alpha-3 crosses in a box of
# 5 L run to the end of the protocol, are analysed, land in results.json and
# in a Markdown table between markers and in the run's record; a second
# invocation finds the case done and runs nothing (resumability); with the
# run folder gone, the table is regenerated from the record alone.
# usage: test_deposit_driver.sh BUILD_DIR SOURCE_DIR
set -euo pipefail
build=$1 src=$2
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
drive() {
    /usr/bin/python3 "$src/host/validate.py" study2 --build "$build" --out "$out" --psis 0.754 --seeds 9 \
        --n 30 --width-l 5 --threads 1 --records "$out/records" "$@"
}
log=$(drive)
echo "$log"
grep -q "cross2d_psi0p754_n30_s9: starting" <<<"$log" || { echo "FAIL: the case did not start"; exit 1; }
grep -q "study2: 1 of 1 cases finished" <<<"$log" || { echo "FAIL: the case did not finish"; exit 1; }
/usr/bin/python3 - "$out/study2/results.json" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))["runs"]
assert len(r) == 1, r
row = r[0]
for key in ("k", "pf_type", "pair_type", "contacts_per_pair", "height_over_width", "phi_container"):
    assert row.get(key) is not None, "results.json lacks %s" % key
assert row["pf_type"] in "AB" and row["pair_type"] in "AB"
# a cross has two spherocylinders: a touching pair makes 1 to 4 contacts
assert 1.0 <= row["contacts_per_pair"] <= 4.0, row["contacts_per_pair"]
assert 0.0 < row["phi_container"] < 1.0, row["phi_container"]
# the template stops the piston (piston_hold: position): it ends with some load, and the
# run's last time-series row is the step the relaxation test passed (ratio below 1e-6)
assert row["load_end"] > 0, row["load_end"]
assert row["ke_over_eel_end"] < 1e-6, row["ke_over_eel_end"]
print("PASS results.json: k %.2f, type %s, %.2f contacts per pair, load %.1f N, KE/E_el %.2g at the end"
      % (row["k"], row["pf_type"], row["contacts_per_pair"], row["load_end"], row["ke_over_eel_end"]))
PY
doc="$out/page.md"
printf 'before\n<!-- study2-table:begin -->\nold\n<!-- study2-table:end -->\nafter\n' >"$doc"
log=$(drive --no-run --markdown-into "$doc")
grep -q "^| 0.754 (3) | 30 | 9 |" "$doc" || { cat "$doc"; echo "FAIL: no table row in $doc"; exit 1; }
grep -q "^old$" "$doc" && { echo "FAIL: the old table was kept"; exit 1; }
log=$(drive)
grep -q "starting\|resuming" <<<"$log" && { echo "$log"; echo "FAIL: a finished case ran again"; exit 1; }
record="$out/records/study2/cross2d_psi0p754_n30_s9.json"
[ -s "$record" ] || { echo "FAIL: no record $record"; exit 1; }
row_before=$(grep "^| 0.754 (3) | 30 | 9 |" "$doc")
# the run folder is lost (a new machine): the table comes back from the record, the same row
rm -rf "$out/study2/cross2d_psi0p754_n30_s9"
printf 'before\n<!-- study2-table:begin -->\nold\n<!-- study2-table:end -->\nafter\n' >"$doc"
log=$(drive --no-run --markdown-into "$doc" --figures "$out/figures")
echo "$log"
grep -q "1 cases from their records" <<<"$log" || { echo "FAIL: the record was not read"; exit 1; }
[ "$(grep "^| 0.754 (3) | 30 | 9 |" "$doc")" = "$row_before" ] ||
    { cat "$doc"; echo "FAIL: the row from the record differs from the run's"; exit 1; }
[ -s "$out/figures/study2_pf.png" ] || { echo "FAIL: no P(f) figure from the record"; exit 1; }
# a record of another set-up (here: another count) is refused, not mixed into the table
sed -i 's/"n": 30,/"n": 31,/' "$record"
if drive --no-run >/dev/null 2>"$out/err"; then echo "FAIL: a record of another count was accepted"; exit 1; fi
grep -q "a record of another set-up" "$out/err" || { cat "$out/err"; echo "FAIL: no reason given"; exit 1; }
echo "PASS: run, analysis, table, record, no second run"
