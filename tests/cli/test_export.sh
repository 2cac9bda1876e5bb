#!/usr/bin/env bash
# `capdem export` writes a well-formed XDMF file whose every data item names
# an existing HDF5 dataset of the declared shape and type, with grids that
# are consistent (connectivity within the points, attributes as long as the
# points or cells they sit on), and whose helper datasets hold the run's own
# numbers; `capdem render` writes non-trivial PNGs.  A check that cannot
# run because a dependency the README lists is missing (python3-h5py,
# python3-matplotlib, hdf5-tools) fails; the read-only case, which as root
# needs `nobody` to reach the binary, is reported as skipped (exit 77,
# CTest's SKIP_RETURN_CODE; CI fails on any skip).
# usage: test_export.sh CAPDEM SOURCE_DIR
set -u
capdem=$1
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
pass=0
fails=0
skips=0
ok() { pass=$((pass+1)); echo "ok   $1"; }
bad() { fails=$((fails+1)); echo "FAIL $1"; [ -f "$work/err" ] && sed 's/^/     /' "$work/err" | tail -20; }
skip() { skips=$((skips+1)); echo "skip $1"; }
PY=/usr/bin/python3

# A small 3D run (40 hexapods poured into a cylinder; snapshots 0, 200, 400,
# 600, the first without contacts) and a small 2D run (crosses in a box).
cat > "$work/hex.yaml" <<'EOF'
run: {name: hex, seed: 3, dt: 1.0e-5, steps: 600, snapshot_every: 200, thermo_every: 100}
physics: {dimension: 3}
particles: [{shape: hexapod, aspect: 3, diameter: 0.005, count: 40}]
domain: {type: cylinder, diameter: 0.06, height: 0.2}
init: {placement: lattice, clearance: 1.0, speed: 1.0}
EOF
cat > "$work/cross.yaml" <<'EOF'
run: {name: cross, seed: 4, dt: 1.0e-5, steps: 600, snapshot_every: 300, thermo_every: 100}
physics: {dimension: 2}
particles: [{shape: cross, aspect: 3, diameter: 0.005, count: 30}]
domain: {type: box, width: 0.1, height: 0.12, thickness: 0.015}
init: {placement: lattice, clearance: 1.0, speed: 1.0}
EOF
for r in hex cross; do
  if "$capdem" run "$work/$r.yaml" --quiet --output "$work/$r.h5" > "$work/out" 2> "$work/err"; then
    ok "run $r"
  else
    bad "run $r (cannot test the export without it)"
    echo "$pass passed, $fails failed, $skips skipped"
    exit 1
  fi
done

# The checker: the XML is parsed with Python's standard library, the shapes
# come from h5ls (hdf5-tools); when h5py is there too it also compares the
# types and the helper datasets' values with the run's datasets.
cat > "$work/check_xmf.py" <<'EOF'
import os, re, subprocess, sys
import xml.etree.ElementTree as ET

xmf = sys.argv[1]
folder = os.path.dirname(os.path.abspath(xmf))
problems = []
tree = ET.parse(xmf)  # raises on malformed XML
root = tree.getroot()
if root.tag != "Xdmf":
    problems.append("root element is %s, not Xdmf" % root.tag)

shapes = {}
def h5shapes(path):
    if path not in shapes:
        out = subprocess.run(["h5ls", "-r", path], capture_output=True, text=True)
        table = {}
        for line in out.stdout.splitlines():
            m = re.match(r"^(\S+)\s+Dataset\s+\{([^}]*)\}", line)
            if m:
                dims = m.group(2).strip()
                table[m.group(1)] = () if dims == "SCALAR" else tuple(int(x.split("/")[0]) for x in dims.split(","))
        shapes[path] = table
    return shapes[path]

def item_ref(item):
    text = item.text.strip()
    fname, dset = text.split(":", 1)
    return os.path.join(folder, fname), dset

def item_dims(item):
    return tuple(int(x) for x in item.get("Dimensions").split())

items = root.iter("DataItem")
nitems = 0
for item in root.iter("DataItem"):
    nitems += 1
    if item.get("Format") != "HDF":
        problems.append("data item with Format %s" % item.get("Format"))
        continue
    fname, dset = item_ref(item)
    if not os.path.exists(fname):
        problems.append("%s: file %s missing" % (item.text.strip(), fname))
        continue
    table = h5shapes(fname)
    if dset not in table:
        problems.append("%s: no such dataset" % item.text.strip())
    elif table[dset] != item_dims(item):
        problems.append("%s: dataset is %s, the XDMF says %s" % (item.text.strip(), table[dset], item_dims(item)))

def rows(el):
    return item_dims(el.find("DataItem"))[0]

collections = [g for g in root.find("Domain").findall("Grid")]
names = [g.get("Name") for g in collections]
if names != ["arms", "particles", "contacts"]:
    problems.append("top-level grids are %s" % names)
counts = set()
for coll in collections:
    if coll.get("CollectionType") != "Temporal":
        problems.append("%s is not a temporal collection" % coll.get("Name"))
    grids = coll.findall("Grid")
    counts.add(len(grids))
    times = [float(g.find("Time").get("Value")) for g in grids]
    if times != sorted(times):
        problems.append("%s: times not increasing" % coll.get("Name"))
    for k, g in enumerate(grids):
        topo, geo = g.find("Topology"), g.find("Geometry")
        nel = int(topo.get("NumberOfElements"))
        npts = rows(geo)
        if geo.get("GeometryType") != "XYZ" or item_dims(geo.find("DataItem"))[1:] != (3,):
            problems.append("%s[%d]: geometry is not XYZ (n, 3)" % (g.get("Name"), k))
        conn = topo.find("DataItem")
        if conn is None:
            if nel != 0:
                problems.append("%s[%d]: %d elements without connectivity" % (g.get("Name"), k, nel))
        else:
            per = int(topo.get("NodesPerElement"))
            want = (nel, per) if per > 1 else (nel,)
            if item_dims(conn) != want:
                problems.append("%s[%d]: connectivity %s, expected %s" % (g.get("Name"), k, item_dims(conn), want))
        for a in g.findall("Attribute"):
            n = rows(a)
            want = npts if a.get("Center") == "Node" else nel
            if n != want:
                problems.append("%s[%d] attribute %s (%s): %d rows, expected %d"
                                % (g.get("Name"), k, a.get("Name"), a.get("Center"), n, want))
        if g.get("Name") == "arms":
            got = {(a.get("Name"), a.get("Center")) for a in g.findall("Attribute")}
            for need in (("radius", "Node"), ("radius", "Cell"), ("particle", "Cell")):
                if need not in got:
                    problems.append("arms[%d]: no %s attribute on %s" % (k, need[0], need[1]))
if len(counts) != 1:
    problems.append("the collections have different numbers of snapshots: %s" % counts)

try:
    import h5py, numpy as np
except ImportError:
    h5py = None
if h5py is not None and problems:
    print("h5py: values not checked (the problems below come first)")
elif h5py is not None:
    kinds = {"Float": "f", "Int": "i", "UInt": "u", "Char": "i", "UChar": "u"}
    for item in root.iter("DataItem"):
        fname, dset = item_ref(item)
        with h5py.File(fname, "r") as f:
            if dset in f:
                dt = f[dset].dtype
                if dt.kind != kinds[item.get("NumberType")] or dt.itemsize != int(item.get("Precision")):
                    problems.append("%s: type %s, the XDMF says %s %s" % (dset, dt, item.get("NumberType"), item.get("Precision")))
    # The run file and the file holding /visualization (the same, or the
    # sidecar of a read-only run file), as the XDMF names them.
    refs = {item_ref(i)[1]: item_ref(i)[0] for i in root.iter("DataItem")}
    run, viz = refs["/particles/prims/prim_radius"], refs["/visualization/arm_cells"]
    with h5py.File(run, "r") as f, h5py.File(viz, "r") as v:
        S = min(int(f.attrs["n_snapshots"]), len(f["walls/time"]))
        if counts != {S}:
            problems.append("%s snapshots in the XDMF, %d in the run file" % (counts, S))
        P = f["particles/prims/prim_radius"].shape[0]
        off = f["contacts/offset"][:S + 1]
        contacts_seen = 0
        for k in range(S):
            g = "visualization/snapshots/%d/" % k
            ap = v[g + "arm_points"][:]
            if not (np.array_equal(ap[:P], f["particles/prims/prim_a/value"][k]) and
                    np.array_equal(ap[P:], f["particles/prims/prim_b/value"][k])):
                problems.append("snapshot %d: arm_points are not prim_a, prim_b of that snapshot" % k)
            if not np.array_equal(v[g + "position"][:], f["particles/all/position/value"][k]):
                problems.append("snapshot %d: position is not that snapshot's" % k)
            c0, c1 = int(off[k]), int(off[k + 1])
            if c1 > c0:
                contacts_seen += c1 - c0
                cells = v[g + "contact_cells"][:]
                want = np.stack([f["contacts/particle_i"][c0:c1], f["contacts/particle_j"][c0:c1]], 1)
                if not np.array_equal(cells, want):
                    problems.append("snapshot %d: contact_cells are not particle_i, particle_j of rows %d..%d" % (k, c0, c1 - 1))
                if not np.array_equal(v[g + "pair_fn"][:], f["contacts/pair_fn"][c0:c1]):
                    problems.append("snapshot %d: pair_fn is not rows %d..%d" % (k, c0, c1 - 1))
            if abs(float(collections[0].findall("Grid")[k].find("Time").get("Value")) - float(f["walls/time"][k])) > 0:
                problems.append("snapshot %d: time differs from /walls/time" % k)
        # every connectivity index names one of the grid's points
        for coll in collections:
            for k, g in enumerate(coll.findall("Grid")):
                conn = g.find("Topology").find("DataItem")
                if conn is not None:
                    cfile, cpath = item_ref(conn)
                    with h5py.File(cfile, "r") as c:
                        idx = c[cpath][()]
                    if idx.size and (idx.min() < 0 or idx.max() >= rows(g.find("Geometry"))):
                        problems.append("%s[%d]: connectivity outside 0..%d" % (coll.get("Name"), k, rows(g.find("Geometry")) - 1))
        r2 = v["visualization/arm_point_radius"][:]
        if not (np.array_equal(r2[:P], f["particles/prims/prim_radius"][:]) and np.array_equal(r2[P:], r2[:P])):
            problems.append("arm_point_radius is not prim_radius twice")
        print("values checked with h5py (%d contact rows)" % contacts_seen)
else:
    print("h5py missing: shapes checked, values not")
for p in problems:
    print("problem:", p)
print("%d data items, %d problems" % (nitems, len(problems)))
sys.exit(1 if problems else 0)
EOF

for r in hex cross; do
  if "$capdem" export "$work/$r.h5" > "$work/out" 2> "$work/err" && [ -s "$work/$r.xmf" ]; then
    ok "export $r writes $r.xmf"
  else
    bad "export $r"; continue
  fi
  # well-formed XML: xmllint where installed (libxml2-utils), else Python's parser
  if command -v xmllint > /dev/null; then
    if xmllint --noout "$work/$r.xmf" 2> "$work/err"; then ok "xmllint: $r.xmf is well-formed"; else bad "xmllint $r.xmf"; fi
  elif "$PY" -c 'import sys, xml.etree.ElementTree as E; E.parse(sys.argv[1])' "$work/$r.xmf" 2> "$work/err"; then
    ok "$r.xmf is well-formed (Python's XML parser)"
  else
    bad "$r.xmf is not well-formed XML"
  fi
  if [ -x "$PY" ] && command -v h5ls > /dev/null; then
    if "$PY" "$work/check_xmf.py" "$work/$r.xmf" > "$work/err" 2>&1; then
      ok "$r.xmf: every data item exists with the declared shape; grids consistent ($(tail -1 "$work/err"); $(grep -m1 'h5py' "$work/err"))"
    else
      bad "$r.xmf checks"
    fi
  else
    bad "$r.xmf shape checks cannot run: /usr/bin/python3 with h5py and h5ls are needed (README's dependencies)"
  fi
done

# A second export keeps the helper datasets: same file size, same XDMF.
cp "$work/hex.xmf" "$work/hex.first.xmf"
size1=$(stat -c %s "$work/hex.h5")
if "$capdem" export "$work/hex.h5" > "$work/out" 2> "$work/err" && [ "$(stat -c %s "$work/hex.h5")" = "$size1" ] &&
   cmp -s "$work/hex.xmf" "$work/hex.first.xmf"; then
  ok "second export adds nothing to the run file"
else
  echo "size $size1 -> $(stat -c %s "$work/hex.h5")" >> "$work/err"; bad "second export"
fi

# -o elsewhere: the XDMF names the run file by its absolute path.
mkdir -p "$work/elsewhere"
if "$capdem" export "$work/hex.h5" -o "$work/elsewhere/view.xmf" > "$work/out" 2> "$work/err" &&
   grep -q ">$work/hex.h5:/visualization/arm_cells<" "$work/elsewhere/view.xmf"; then
  ok "export -o elsewhere names the run file by its absolute path"
else
  bad "export -o elsewhere"
fi

# A read-only run file: the helpers go to a sidecar next to it.  Root may
# write to any file, so as root the export runs as nobody (setpriv), when
# nobody can reach the binary.
mkdir -p "$work/ro"
"$capdem" run "$work/hex.yaml" --quiet --output "$work/ro/ro.h5" > /dev/null 2>&1
chmod a-w "$work/ro/ro.h5"
runas=()
if [ "$(id -u)" = 0 ]; then
  if command -v setpriv > /dev/null && id nobody > /dev/null 2>&1; then
    runas=(setpriv --reuid="$(id -u nobody)" --regid="$(id -g nobody)" --clear-groups)
    chmod 711 "$work"
    chmod 777 "$work/ro"
    "${runas[@]}" test -x "$capdem" || runas=(none)
  else
    runas=(none)
  fi
fi
if [ "${runas[0]:-}" = none ]; then
  skip "read-only run file (running as root, and nobody cannot run $capdem)"
elif "${runas[@]}" "$capdem" export "$work/ro/ro.h5" > "$work/out" 2> "$work/err" && [ -s "$work/ro/ro.viz.h5" ] &&
     grep -q 'ro.viz.h5:/visualization' "$work/ro/ro.xmf" && grep -q '>ro.h5:/particles/prims/prim_radius<' "$work/ro/ro.xmf" &&
     { [ ! -x "$PY" ] || "$PY" "$work/check_xmf.py" "$work/ro/ro.xmf" > "$work/err" 2>&1; }; then
  ok "read-only run file: helpers in ro.viz.h5, XDMF consistent${runas:+ (as nobody)}"
else
  bad "read-only run file"
fi
chmod u+w "$work/ro/ro.h5"

# Bad input: exit status 2 and a message naming the file.
expect2() {
  local name=$1; shift
  "$capdem" "$@" > "$work/out" 2> "$work/err"
  local rc=$?
  if [ $rc -eq 2 ] && [ -s "$work/err" ]; then ok "$name: exit 2"; else echo "exit status $rc" >> "$work/err"; bad "$name"; fi
}
expect2 "export without a file" export
expect2 "export of a missing file" export "$work/nothing.h5"
echo "not hdf5" > "$work/text.h5"
expect2 "export of a text file" export "$work/text.h5"
if grep -q "text.h5" "$work/err"; then ok "message names the file"; else bad "message names the file"; fi
if command -v h5copy > /dev/null; then
  h5copy -i "$work/hex.h5" -o "$work/partial.h5" -s /walls -d /walls > /dev/null 2>&1
  expect2 "export of an HDF5 file without particles" export "$work/partial.h5"
else
  bad "export of an HDF5 file without particles cannot be tested: h5copy is missing (hdf5-tools, README's dependencies)"
fi

# render: only where /usr/bin/python3 has matplotlib.
png_ok() {  # PNG signature, at least 200x150 pixels, at least 10 kB, not one flat colour
  "$PY" - "$1" <<'EOF'
import struct, sys
import matplotlib.image as mpimg
data = open(sys.argv[1], "rb").read()
assert data[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
w, h = struct.unpack(">II", data[16:24])
assert w >= 200 and h >= 150, "only %dx%d pixels" % (w, h)
assert len(data) > 10000, "only %d bytes" % len(data)
img = mpimg.imread(sys.argv[1])
assert img[..., :3].std() > 0.05, "nearly one colour"
print("%dx%d, %d bytes" % (w, h, len(data)))
EOF
}
if [ -x "$PY" ] && "$PY" -c 'import matplotlib, numpy, h5py' 2> /dev/null; then
  for r in hex cross; do
    for mode in arms forces; do
      if "$capdem" render "$work/$r.h5" -o "$work/$r-$mode.png" --mode $mode > "$work/out" 2> "$work/err" &&
         png_ok "$work/$r-$mode.png" > "$work/out" 2> "$work/err"; then
        ok "render $r --mode $mode: $(cat "$work/out")"
      else
        bad "render $r --mode $mode"
      fi
    done
  done
  if "$capdem" render "$work/hex.h5" --snapshot 0 --color height -o "$work/first.png" > "$work/out" 2> "$work/err" &&
     png_ok "$work/first.png" > /dev/null 2> "$work/err"; then
    ok "render --snapshot 0 --color height"
  else
    bad "render --snapshot 0"
  fi
  expect2 "render of a snapshot the file does not have" render "$work/hex.h5" --snapshot 99 -o "$work/x.png"
  expect2 "render with an unknown mode" render "$work/hex.h5" --mode glitter -o "$work/x.png"
  expect2 "render of a missing file" render "$work/nothing.h5" -o "$work/x.png"
else
  bad "render cannot be tested: /usr/bin/python3 cannot import matplotlib, numpy and h5py (apt-get install python3-matplotlib python3-h5py)"
  expect2 "render without matplotlib" render "$work/hex.h5" -o "$work/x.png"
  if grep -q "python3-matplotlib" "$work/err"; then ok "the message names python3-matplotlib"; else bad "the message names python3-matplotlib"; fi
fi

echo "$pass passed, $fails failed, $skips skipped"
[ $fails -eq 0 ] || exit 1
[ $skips -eq 0 ] || exit 77
