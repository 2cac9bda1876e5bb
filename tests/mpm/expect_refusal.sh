# Sourced by the mpm command-line tests (after tests/cli/common.sh):
# expect_refusal NAME REGEX, the config text on stdin: `capdem run` of it
# exits 2 naming the file and /REGEX/, and writes no output file.
expect_refusal() {
  cat > "$1.yaml"
  "$capdem" run "$1.yaml" --output "$1.h5" --quiet > out 2> err
  local rc=$?
  if [ $rc -ne 2 ]; then bad "$1: exit status $rc, expected 2"; return; fi
  if ! grep -q "$1.yaml" err || ! grep -Eq "$2" err; then bad "$1: message does not name the file and /$2/"; return; fi
  if [ -e "$1.h5" ]; then bad "$1: an output file was written"; return; fi
  ok
}
