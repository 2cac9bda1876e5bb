# Sourced by the CLI tests of issue 18 (test_cli_numbers, test_diagnostics,
# test_io_faults, test_output_safety): a scratch folder, removed at exit,
# as the working directory; pass/fail counters and their helpers; the
# snapshot count of a run file.  A test that needs more at exit sets its
# own trap after sourcing (and removes "$work" itself).
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work" || exit 1
fails=0
pass=0
ok() { pass=$((pass+1)); }
bad() { echo "FAIL $1"; [ -f err ] && sed 's/^/    /' err; fails=$((fails+1)); }
snapshots() { h5dump -a /n_snapshots "$1" 2> /dev/null | sed -n 's/^ *(0): *//p'; }
