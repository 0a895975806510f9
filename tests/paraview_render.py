"""Renders the last snapshot of a run folder with ParaView (run by pvbatch, see test_paraview.py):
grains coloured by their axial stress, bonds by their breakage index, cracks as discs oriented
by their normals and sized by their radii. Prints the arrays' ranges as JSON for the test to
check, then saves the picture.

    pvbatch tests/paraview_render.py RUN_FOLDER/snapshots OUT.png
"""
import json
import os
import sys

from paraview import servermanager
from paraview.simple import (ColorBy, CreateView, Glyph, Render, ResetCamera, SaveScreenshot,
                             Show, XMLUnstructuredGridReader)

folder, png = sys.argv[1], sys.argv[2]
last = sorted(f for f in os.listdir(folder) if f.startswith("particles_"))[-1]
name = last[len("particles_"):]
grains = XMLUnstructuredGridReader(FileName=[os.path.join(folder, last)])
bonds = XMLUnstructuredGridReader(FileName=[os.path.join(folder, "bonds_" + name)])
cracks = XMLUnstructuredGridReader(FileName=[os.path.join(folder, "cracks_" + name)])
discs = Glyph(Input=cracks, GlyphType="Cylinder")
discs.OrientationArray = ["POINTS", "normal"]
discs.ScaleArray = ["POINTS", "radius_m"]
discs.ScaleFactor = 2.0
discs.GlyphType.Height = 0.1  # a thin cylinder along the normal: a disc in the crack plane
# ParaView's cylinder lies along y; turn it so that its axis follows the orientation array.
discs.GlyphTransform.Rotate = [0.0, 0.0, -90.0]

view = CreateView("RenderView")
view.ViewSize = [640, 480]
shown = Show(grains, view)
shown.SetRepresentationType("Points")
ColorBy(shown, ("POINTS", "stress_pa", "8"))
ColorBy(Show(bonds, view), ("CELLS", "breakage_index"))
ColorBy(Show(discs, view), ("POINTS", "mode"))
ResetCamera(view)
Render(view)
SaveScreenshot(png, view)


def point_range(source, array, component=-1):
    data = servermanager.Fetch(source)
    return list(data.GetPointData().GetArray(array).GetRange(component))


def cell_range(source, array):
    data = servermanager.Fetch(source)
    return list(data.GetCellData().GetArray(array).GetRange(0))


print(json.dumps({
    "stress_zz_pa": point_range(grains, "stress_pa", 8),
    "rotation_rad": point_range(grains, "rotation", -1),
    "breakage_index": cell_range(bonds, "breakage_index"),
    "bonds": servermanager.Fetch(bonds).GetNumberOfCells(),
    "cracks": servermanager.Fetch(cracks).GetNumberOfPoints(),
    "disc_points": servermanager.Fetch(discs).GetNumberOfPoints(),
}))
