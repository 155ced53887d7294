"""Render one snapshot of an `mdem export --format vtk` compression result with ParaView.

Usage: xvfb-run -a pvbatch scripts/render_grains.py RESULT.pvd OUT.png [SNAPSHOT [WIDTH HEIGHT]]
Grains are translucent spheres of their radius coloured by the net force on them (nN); the bond
network is drawn as tubes coloured by bond state (0 intact, 1 yielded, 2 broken);
platens are translucent discs. SNAPSHOT is the snapshot index (default: the last).
"""
import sys
import os
import re

from paraview.simple import (ColorBy, GetActiveViewOrCreate, GetColorTransferFunction, GetScalarBar,
                             Glyph, Render, SaveScreenshot, Show, Tube, XMLPolyDataReader)

if len(sys.argv) < 3:
    sys.exit("usage: pvbatch render_grains.py RESULT.pvd OUT.png [SNAPSHOT]")
pvd, out = sys.argv[1], sys.argv[2]
text = open(pvd).read()
files = re.findall(r'name="(\w+)" file="([^"]+)"', text)
parts = {}
for name, f in files:
    parts.setdefault(name, []).append(os.path.join(os.path.dirname(pvd), f))
if "elements" not in parts:
    sys.exit(f"{pvd}: no 'elements' part; is it an `mdem export --format vtk` collection?")
k = int(sys.argv[3]) if len(sys.argv) > 3 else len(parts["elements"]) - 1
size = [int(sys.argv[4]), int(sys.argv[5])] if len(sys.argv) > 5 else [1400, 1000]
if not 0 <= k < len(parts["elements"]):
    sys.exit(f"snapshot {k} out of range 0..{len(parts['elements']) - 1}")

view = GetActiveViewOrCreate("RenderView")


def style_bar(lut, title):
    bar = GetScalarBar(lut, view)
    bar.Title = title
    bar.ComponentTitle = ""
    bar.TitleColor = [0, 0, 0]
    bar.LabelColor = [0, 0, 0]
    bar.TitleFontSize = 20
    bar.LabelFontSize = 18


view.ViewSize = size
view.UseColorPaletteForBackground = 0
view.Background = [1, 1, 1]
view.OrientationAxesVisibility = 0

grains = XMLPolyDataReader(FileName=[parts["elements"][k]])
spheres = Glyph(Input=grains, GlyphType="Sphere")
spheres.ScaleArray = ["POINTS", "radius"]
spheres.ScaleFactor = 2.0  # the sphere source has diameter 1
spheres.GlyphMode = "All Points"
spheres.GlyphType.ThetaResolution = 24
spheres.GlyphType.PhiResolution = 24
sd = Show(spheres, view)
ColorBy(sd, ("POINTS", "force_nN"))
sd.SetScalarBarVisibility(view, True)
sd.Opacity = 0.35
lut = GetColorTransferFunction("force_nN")
lut.ApplyPreset("Viridis (matplotlib)", True)
style_bar(lut, "net force on grain |F| (nN)")
sd.LookupTable.RescaleTransferFunctionToDataRange(True)

if "bonds" in parts:
    bonds = XMLPolyDataReader(FileName=[parts["bonds"][k]])
    tubes = Tube(Input=bonds)
    tubes.Radius = 0.25
    tubes.NumberofSides = 12
    bd = Show(tubes, view)
    ColorBy(bd, ("CELLS", "state"))
    blut = GetColorTransferFunction("state")
    blut.InterpretValuesAsCategories = 1
    blut.Annotations = ["0", "intact", "1", "yielded", "2", "broken"]
    blut.IndexedColors = [0.2, 0.2, 0.8, 1.0, 0.6, 0.0, 0.9, 0.0, 0.0]
    bd.SetScalarBarVisibility(view, True)
    style_bar(blut, "bond state")

for name in ("platens", "walls"):
    if name in parts:
        w = XMLPolyDataReader(FileName=[parts[name][k]])
        wd = Show(w, view)
        wd.Opacity = 0.25
        wd.DiffuseColor = [0.5, 0.5, 0.5]
        wd.ColorArrayName = [None, ""]

# Look across the loading axis (the platens' normal), so the platens are seen edge-on.
axis = 2
if "platens" in parts:
    from paraview import servermanager
    data = servermanager.Fetch(XMLPolyDataReader(FileName=[parts["platens"][k]]))
    n = data.GetCellData().GetArray("normal").GetTuple3(0)
    axis = max(range(3), key=lambda a: abs(n[a]))
side = [(1, 0, 0), (0, 1, 0), (0, 0, 1)][(axis + 1) % 3]
up = [(1, 0, 0), (0, 1, 0), (0, 0, 1)][axis]
view.CameraFocalPoint = [0, 0, 0]
view.CameraPosition = [10 * c for c in side]
view.CameraViewUp = list(up)
view.ResetCamera()
view.GetActiveCamera().Azimuth(20)
view.GetActiveCamera().Elevation(10)
view.ResetCamera()
Render(view)
SaveScreenshot(out, view, ImageResolution=size)
print(f"wrote {out} (snapshot {k} of {len(parts['elements'])})")
