#!/usr/bin/env bash
# `cmake --install` gives a usable prefix (issue 19 item 5): the programs,
# the shipped configs, the Python tools and the docs land in it; the
# installed capdem runs an installed config; the installed Python tools
# read a run file through the installed capdem_h5.py; `capdem render` from
# the prefix uses the prefix's own render.py (a stand-in script there, which
# leaves a mark, shows which one ran).
# usage: test_install.sh CAPDEM SOURCE_DIR
set -u
capdem=$1 src=$2
build=$(cd "$(dirname "$capdem")" && pwd)
. "$(dirname "${BASH_SOURCE[0]}")/common.sh"
prefix=$work/prefix
if cmake --install "$build" --prefix "$prefix" > install.log 2> err; then ok; else bad "cmake --install: exit $?"; fi
for f in bin/capdem bin/capdem-bench share/capdem/host/render.py share/capdem/host/plot_run.py \
         share/capdem/host/capdem_h5.py share/capdem/configs/hexapod_drop.yaml share/doc/capdem/README.md \
         share/doc/capdem/offload.md; do
  if [ -e "$prefix/$f" ]; then ok; else bad "not installed: $f"; fi
done
if "$prefix/bin/capdem" run "$prefix/share/capdem/configs/hexapod_drop.yaml" --steps 50 --output run.h5 --quiet \
     > out 2> err && [ -s run.h5 ]; then ok; else bad "the installed capdem did not run the installed hexapod_drop.yaml"; fi
# the installed Python tools open run files through the installed capdem_h5
if /usr/bin/python3 -c 'import sys; sys.path.insert(0, sys.argv[1]); import capdem_h5
with capdem_h5.open_run("run.h5") as f:
    assert capdem_h5.snapshot_count(f) >= 1 and capdem_h5.column(f, "position", -1).shape[1] == 3' \
     "$prefix/share/capdem/host" > out 2> err; then ok; else bad "the installed capdem_h5.py cannot read run.h5: $(tail -1 err)"; fi
cat > "$prefix/share/capdem/host/render.py" <<'PY'
import sys
open("installed-render-ran", "w").write(" ".join(sys.argv[1:]))
PY
"$prefix/bin/capdem" render run.h5 --output pic.png > out 2> err
if [ -f installed-render-ran ]; then ok; else bad "capdem render from the prefix did not use the prefix's render.py"; fi
echo "$pass passed, $fails failed"
[ $fails -eq 0 ]
