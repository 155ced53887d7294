"""Render one snapshot of an `mdem export --format vtk` result with ParaView (pvbatch).

Usage: xvfb-run -a pvbatch scripts/render_snapshot.py RESULT.pvd OUT.png [SNAPSHOT [WIDTH HEIGHT]]

What it draws, from the export's parts (docs/results.md):
- CNTs (kind 0): each tube's polyline through its segments as a tube of the (10,10) radius,
  0.678 nm, coloured by tube number;
- nanoparticles (kind 1) and grains (kind 2): translucent spheres of their radius, coloured by the
  net force on the element (|F|, nN);
- the bond network of a compression job, when exported: tubes coloured by bond state
  (intact, yielded, broken);
- platens: translucent discs, the camera looking across their normal (edge-on).
Without platens the camera looks across the longest extent of the elements (a rope from the side,
a film from above is `--view top`: give 'top' as the 6th argument).
SNAPSHOT is the snapshot index (default: the last).
"""
import os
import re
import sys

from paraview.simple import (ColorBy, GetActiveViewOrCreate, GetColorTransferFunction, GetScalarBar,
                             Glyph, Render, SaveScreenshot, Show, Threshold, Tube, XMLPolyDataReader)
from paraview import servermanager

CNT_RADIUS_NM = 0.678  # (10,10) tube radius, model.md

if len(sys.argv) < 3:
    sys.exit(__doc__)
pvd, out = sys.argv[1], sys.argv[2]
text = open(pvd).read()
parts = {}
for name, f in re.findall(r'name="(\w+)" file="([^"]+)"', text):
    parts.setdefault(name, []).append(os.path.join(os.path.dirname(pvd), f))
if "elements" not in parts:
    sys.exit(f"{pvd}: no 'elements' part; is it an `mdem export --format vtk` collection?")
n = len(parts["elements"])
k = int(sys.argv[3]) if len(sys.argv) > 3 else n - 1
if not 0 <= k < n:
    sys.exit(f"snapshot {k} out of range 0..{n - 1}")
size = [int(sys.argv[4]), int(sys.argv[5])] if len(sys.argv) > 5 else [1400, 1000]
top_view = len(sys.argv) > 6 and sys.argv[6] == "top"

view = GetActiveViewOrCreate("RenderView")
view.ViewSize = size
view.UseColorPaletteForBackground = 0
view.Background = [1, 1, 1]
view.OrientationAxesVisibility = 0


def style_bar(lut, title):
    bar = GetScalarBar(lut, view)
    bar.Title = title
    bar.ComponentTitle = ""
    bar.TitleColor = [0, 0, 0]
    bar.LabelColor = [0, 0, 0]
    bar.TitleFontSize = 20
    bar.LabelFontSize = 18


elements = XMLPolyDataReader(FileName=[parts["elements"][k]])
data = servermanager.Fetch(elements)
kinds = data.GetPointData().GetArray("kind")
present = {int(kinds.GetTuple1(i)) for i in range(data.GetNumberOfPoints())}

if 0 in present:  # CNT polylines
    tubes = Tube(Input=elements)
    tubes.Radius = CNT_RADIUS_NM
    tubes.NumberofSides = 16
    td = Show(tubes, view)
    ColorBy(td, ("POINTS", "tube"))
    tlut = GetColorTransferFunction("tube")
    tlut.ApplyPreset("Rainbow Uniform", True)
    td.LookupTable.RescaleTransferFunctionToDataRange(True)
    td.SetScalarBarVisibility(view, True)
    style_bar(tlut, "tube")

if present & {1, 2}:  # spheres: NPs and grains
    balls = Threshold(Input=elements)
    balls.Scalars = ["POINTS", "kind"]
    balls.LowerThreshold = 1
    balls.UpperThreshold = 2
    spheres = Glyph(Input=balls, GlyphType="Sphere")
    spheres.ScaleArray = ["POINTS", "radius"]
    spheres.ScaleFactor = 2.0  # the sphere source has diameter 1
    spheres.GlyphMode = "All Points"
    spheres.GlyphType.ThetaResolution = 24
    spheres.GlyphType.PhiResolution = 24
    sd = Show(spheres, view)
    ColorBy(sd, ("POINTS", "force_nN"))
    sd.Opacity = 0.35 if "bonds" in parts else 0.8
    flut = GetColorTransferFunction("force_nN")
    flut.ApplyPreset("Viridis (matplotlib)", True)
    sd.LookupTable.RescaleTransferFunctionToDataRange(True)
    sd.SetScalarBarVisibility(view, True)
    style_bar(flut, "net force (nN)")

if "bonds" in parts:
    bonds = Tube(Input=XMLPolyDataReader(FileName=[parts["bonds"][k]]))
    bonds.Radius = 0.25
    bonds.NumberofSides = 12
    bd = Show(bonds, view)
    ColorBy(bd, ("CELLS", "state"))
    blut = GetColorTransferFunction("state")
    blut.InterpretValuesAsCategories = 1
    blut.Annotations = ["0", "intact", "1", "yielded", "2", "broken"]
    blut.IndexedColors = [0.2, 0.2, 0.8, 1.0, 0.6, 0.0, 0.9, 0.0, 0.0]
    bd.SetScalarBarVisibility(view, True)
    style_bar(blut, "bond state")

# The axis the camera looks across: the platens' normal, else the elements' longest extent.
b = data.GetBounds()
extent = [b[1] - b[0], b[3] - b[2], b[5] - b[4]]
axis = max(range(3), key=lambda a: extent[a])
if "platens" in parts:
    walls = XMLPolyDataReader(FileName=[parts["platens"][k]])
    wd = Show(walls, view)
    wd.Opacity = 0.25
    wd.DiffuseColor = [0.5, 0.5, 0.5]
    wd.ColorArrayName = [None, ""]
    normal = servermanager.Fetch(walls).GetCellData().GetArray("normal").GetTuple3(0)
    axis = max(range(3), key=lambda a: abs(normal[a]))
unit = [(1, 0, 0), (0, 1, 0), (0, 0, 1)]
centre = [(b[0] + b[1]) / 2, (b[2] + b[3]) / 2, (b[4] + b[5]) / 2]
if top_view:  # look down the thinnest axis
    thin = min(range(3), key=lambda a: extent[a])
    eye, up = unit[thin], unit[(thin + 1) % 3]
else:
    eye, up = unit[(axis + 1) % 3], unit[axis]
    if extent[(axis + 1) % 3] > extent[(axis + 2) % 3]:
        eye = unit[(axis + 2) % 3]
view.CameraFocalPoint = centre
view.CameraPosition = [c + 10 * e for c, e in zip(centre, eye)]
view.CameraViewUp = list(up)
view.ResetCamera()
if not top_view:
    view.GetActiveCamera().Azimuth(20)
    view.GetActiveCamera().Elevation(10)
    view.ResetCamera()
Render(view)
SaveScreenshot(out, view, ImageResolution=size)
print(f"wrote {out} (snapshot {k} of {n})")
