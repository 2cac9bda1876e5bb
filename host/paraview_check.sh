#!/usr/bin/env bash
# Checks that ParaView reads what `capdem export` writes, and makes pictures
# with it (docs/visualization.md, "How the export was checked").  Not part of
# the test suite: ParaView is a large install (about 0.8 GB with its
# dependencies) and needs an X server, a virtual one (xvfb) here.
#
# usage: host/paraview_check.sh [--install] CAPDEM RUN.h5 OUTDIR
#   --install  first installs Debian's paraview, python3-paraview (pvpython),
#              xvfb and xauth with apt-get (root or sudo)
#   CAPDEM     the capdem binary (used for `capdem export RUN.h5`)
#   RUN.h5     a run file; its last snapshot is drawn
#   OUTDIR     receives paraview_arms.png (arms as tubes with the radius from
#              the data, spherical caps as sphere glyphs, coloured by
#              particle), paraview_forces.png (the contact network as tubes,
#              thickness and colour by normal force, over faint arms) and
#              paraview_report.txt (version, which readers loaded the file,
#              what each grid held) and paraview_log.txt (ParaView's output)
# Exit status: 0 all three ParaView XDMF readers loaded the file and both
# pictures were written, 1 otherwise, 2 bad arguments.
set -u
install=0
if [ "${1:-}" = "--install" ]; then install=1; shift; fi
if [ $# -ne 3 ]; then
  sed -n '2,19p' "$0" | sed 's/^# \{0,1\}//'
  exit 2
fi
capdem=$1 run=$2 out=$3
mkdir -p "$out" || exit 2
out=$(cd "$out" && pwd)

if [ $install -eq 1 ]; then
  SUDO=""
  [ "$(id -u)" -ne 0 ] && SUDO=sudo
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends \
    paraview python3-paraview xvfb xauth || exit 1
fi
for tool in pvpython xvfb-run; do
  if ! command -v $tool > /dev/null; then
    echo "paraview_check: $tool is missing (run with --install, or apt-get install paraview python3-paraview xvfb xauth)" >&2
    exit 1
  fi
done

"$capdem" export "$run" || exit 1
case "$run" in
  *.h5) xmf=${run%.h5}.xmf ;;
  *.hdf5) xmf=${run%.hdf5}.xmf ;;
  *) xmf=$run.xmf ;;
esac
# Absolute path: ParaView's Xdmf3 readers resolve the HDF5 file name wrongly
# when the .xmf is given without a folder.
xmf=$(cd "$(dirname "$xmf")" && pwd)/$(basename "$xmf")

script=$(mktemp --suffix=.py)
trap 'rm -f "$script"' EXIT
cat > "$script" <<'EOF'
import sys
from paraview.simple import *
from paraview import servermanager as sm

xmf, out = sys.argv[1], sys.argv[2]
report = open(out + "/paraview_report.txt", "w")
def say(*words):
    line = " ".join(str(w) for w in words)
    print(line)
    report.write(line + "\n")

import paraview
say("ParaView", getattr(paraview, "__version__", GetParaViewVersion()))
say("file", xmf)

# 1. Every XDMF reader ParaView offers for .xmf loads the file, at the last
#    time step, with the three grids.
def blocks(data, path=""):
    if data is None:
        return []
    if data.IsA("vtkDataSet"):
        return [(path, data)]
    found = []
    n = data.GetNumberOfBlocks() if data.IsA("vtkMultiBlockDataSet") else data.GetNumberOfPieces()
    for i in range(n):
        child = data.GetBlock(i) if data.IsA("vtkMultiBlockDataSet") else data.GetPiece(i)
        name = str(i)
        if data.IsA("vtkMultiBlockDataSet") and data.HasMetaData(i) and data.GetMetaData(i).Has(data.NAME()):
            name = data.GetMetaData(i).Get(data.NAME())
        found += blocks(child, path + "/" + name)
    return found

readers = {"XDMF Reader (XDMF2)": lambda: XDMFReader(FileNames=[xmf]),
           "Xdmf3 Reader S": lambda: Xdmf3ReaderS(FileName=[xmf]),
           "Xdmf3 Reader T": lambda: Xdmf3ReaderT(FileName=[xmf])}
loaded = 0
for name, make in readers.items():
    r = make()
    r.UpdatePipelineInformation()
    times = list(r.TimestepValues)
    r.UpdatePipeline(times[-1])
    found = blocks(sm.Fetch(r))
    say("%s: %d time steps, t_last = %.6g s" % (name, len(times), times[-1]))
    for path, ds in found:
        pd, cd = ds.GetPointData(), ds.GetCellData()
        say("   %-12s %7d points %7d cells  point data: %s  cell data: %s" % (
            path, ds.GetNumberOfPoints(), ds.GetNumberOfCells(),
            ",".join(pd.GetArrayName(j) for j in range(pd.GetNumberOfArrays())),
            ",".join(cd.GetArrayName(j) for j in range(cd.GetNumberOfArrays()))))
    ok = len(found) == 3 and found[0][1].GetNumberOfCells() > 0 and found[1][1].GetNumberOfPoints() > 0
    loaded += ok
    say("   ->", "loaded" if ok else "NOT loaded")
    Delete(r)

# 2. Pictures with the XDMF2 reader, the one the documentation recommends.
run = XDMFReader(FileNames=[xmf])
run.UpdatePipelineInformation()
t = run.TimestepValues[-1]
arms = ExtractBlock(Input=run, Selectors=["/Root/arms"])
contacts = ExtractBlock(Input=run, Selectors=["/Root/contacts"])
# The Tube filter takes polygonal data only: Merge Blocks + Extract Surface
# turn the arms block (an unstructured grid of lines) into it.
arms_lines = ExtractSurface(Input=MergeBlocks(Input=arms))
# Neighbouring particle ids sit next to each other (lattice placement):
# a scrambled key gives neighbours different colours.
keyed = PythonCalculator(Input=arms_lines, Expression="(inputs[0].PointData['particle'] * 7) % 12",
                         ArrayName="colour_key")
tube = Tube(Input=keyed)
tube.Scalars = ["POINTS", "radius"]
tube.VaryRadius = "By Absolute Scalar"   # tube radius = the arm radius, in m
tube.NumberofSides = 24
tube.Capping = 0
caps = Glyph(Input=keyed, GlyphType="Sphere")
caps.OrientationArray = ["POINTS", "No orientation array"]
caps.ScaleArray = ["POINTS", "radius"]
caps.ScaleFactor = 2.0                    # the sphere source has radius 0.5
caps.GlyphMode = "All Points"
caps.GlyphType.ThetaResolution = 24
caps.GlyphType.PhiResolution = 16

view = CreateView("RenderView")
view.ViewSize = [720, 540]
view.OrientationAxesVisibility = 1
view.Background = [1, 1, 1]
try:
    view.UseColorPaletteForBackground = 0
except AttributeError:
    pass
view.ViewTime = t

def show(src, array, lut_name, opacity=1.0):
    d = Show(src, view)
    ColorBy(d, ("POINTS", array))
    lut = GetColorTransferFunction(array)
    try:
        lut.ApplyPreset(lut_name, True)
    except Exception:
        pass
    d.Opacity = opacity
    return d, lut

def place_camera():
    # y is up; the same view as `capdem render` (elevation 22, azimuth -35).
    # ResetCamera takes effect at the next Render, hence the Render before
    # the zoom (the reset would undo it).
    view.ResetCamera()
    Render(view)
    cam = view.GetActiveCamera()
    cam.SetViewUp(0, 1, 0)
    b = arms_lines.GetDataInformation().GetBounds()
    flat = b[5] - b[4] <= 1e-9 * max(b[1] - b[0], b[3] - b[2])   # a 2D run is seen face on
    if not flat:
        cam.Azimuth(-35)
        cam.Elevation(22)
    cam.OrthogonalizeViewUp()
    view.ResetCamera()
    Render(view)
    cam.Zoom(1.1 if flat else 1.5)

d1, lut = show(tube, "colour_key", "Turbo")
d2, _ = show(caps, "colour_key", "Turbo")
lut.RescaleTransferFunction(0.0, 11.0)
lut.Discretize = 1
lut.NumberOfTableValues = 12
HideScalarBarIfNotNeeded(lut, view)
GetScalarBar(lut, view).Visibility = 0
place_camera()
Render(view)
SaveScreenshot(out + "/paraview_arms.png", view, ImageResolution=[720, 540])
say("wrote", out + "/paraview_arms.png")

# Contact network: Shrink (factor 1) gives every line its own two points, so
# that Cell Data to Point Data copies each contact's force onto its own ends
# and the Tube filter can vary the radius by it.
d1.Opacity = 0.15
ColorBy(d1, None)
d1.AmbientColor = d1.DiffuseColor = [0.6, 0.6, 0.6]
Hide(caps, view)
own = Shrink(Input=MergeBlocks(Input=contacts))
own.ShrinkFactor = 1.0
per_point = ExtractSurface(Input=CellDatatoPointData(Input=own))
force_tube = Tube(Input=per_point)
force_tube.Scalars = ["POINTS", "pair_fn"]
force_tube.VaryRadius = "By Scalar"
force_tube.Radius = 0.00025              # m, for the weakest contact
force_tube.RadiusFactor = 6              # the strongest is 6 times as thick
force_tube.NumberofSides = 12
d3, lut = show(force_tube, "pair_fn", "Inferno (matplotlib)")
lut.InvertTransferFunction() if hasattr(lut, "InvertTransferFunction") else None
bar = GetScalarBar(lut, view)
bar.Title = "normal force [N]"
bar.ComponentTitle = ""
bar.Visibility = 1
bar.WindowLocation = "Upper Right Corner"
bar.TitleColor = bar.LabelColor = [0, 0, 0]
Render(view)
SaveScreenshot(out + "/paraview_forces.png", view, ImageResolution=[720, 540])
say("wrote", out + "/paraview_forces.png")
say("readers that loaded the file: %d of %d" % (loaded, len(readers)))
report.close()
sys.stdout.flush()
# Leave without tearing down the render window: under xvfb that teardown
# ends in "X Error: GLXBadContext" and a non-zero status after the work is
# done.
import os
os._exit(0 if loaded == len(readers) else 1)
EOF

# pvpython of Debian's ParaView renders through X: a virtual X server
# serves it.  Offscreen rendering without X is not built into that package.
# A second try when the virtual X server was not ready ("bad X server
# connection", seen once in a few dozen runs).
for attempt in 1 2; do
  xvfb-run -a -s "-screen 0 1600x1200x24" pvpython --force-offscreen-rendering "$script" "$xmf" "$out" 2>&1 |
    tee "$out/paraview_log.txt"
  rc=${PIPESTATUS[0]}
  [ $rc -eq 0 ] || ! grep -q "bad X server connection" "$out/paraview_log.txt" && break
done
if [ $rc -eq 0 ] && [ -s "$out/paraview_arms.png" ] && [ -s "$out/paraview_forces.png" ]; then
  echo "paraview_check: ok ($out)"
  exit 0
fi
echo "paraview_check: FAILED (status $rc); see $out/paraview_report.txt" >&2
exit 1
