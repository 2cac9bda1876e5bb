#!/bin/bash
# The deposit-and-compress driver of studies 2-4 (host/validate.py study2,
# docs/validation.md) end to end at toy size: 30 alpha-3 crosses in a box of
# 5 L run to the end of the protocol, are analysed, land in results.json and
# in a Markdown table between markers; a second invocation finds the case
# done and runs nothing (resumability).
# usage: test_deposit_driver.sh BUILD_DIR SOURCE_DIR
set -euo pipefail
build=$1 src=$2
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
drive() {
    /usr/bin/python3 "$src/host/validate.py" study2 --build "$build" --out "$out" --psis 0.754 --seeds 9 \
        --n 30 --width-l 5 --threads 1 "$@"
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
print("PASS results.json: k %.2f, type %s, %.2f contacts per pair" % (row["k"], row["pf_type"],
                                                                    row["contacts_per_pair"]))
PY
doc="$out/page.md"
printf 'before\n<!-- study2-table:begin -->\nold\n<!-- study2-table:end -->\nafter\n' >"$doc"
log=$(drive --no-run --markdown-into "$doc")
grep -q "^| 0.754 (3) | 30 | 9 |" "$doc" || { cat "$doc"; echo "FAIL: no table row in $doc"; exit 1; }
grep -q "^old$" "$doc" && { echo "FAIL: the old table was kept"; exit 1; }
log=$(drive)
grep -q "starting\|resuming" <<<"$log" && { echo "$log"; echo "FAIL: a finished case ran again"; exit 1; }
echo "PASS: run, analysis, table, no second run"
