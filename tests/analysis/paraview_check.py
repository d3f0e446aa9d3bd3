"""Run by pvpython (ParaView's own Python): loads a snapshot series (hopper.pvd) with the README's
ParaView recipe (its pvpython block, run as printed but for the series' path) and a field map
(.vti) with ParaView's native readers, checks what they hold and renders each to a PNG
(paraview.sh fails a render of fewer than 10 colours: the flat colour of a recipe that leaves
"Use Scale Function" on).
usage: pvpython paraview_check.py SERIES.pvd FRAMES POINTS R_MIN R_MAX FIELD.vti CELLS
                                  SPEED_MIN SPEED_MAX OUT_DIR README.md"""
import math
import os
import sys

from paraview.simple import (ColorBy, CreateRenderView, GetAnimationScene, OpenDataFile,
                             ResetCamera, SaveScreenshot, Show, UpdatePipeline)  # noqa: F401

pvd, frames, points, r_min, r_max, vti, cells, s_min, s_max, out, readme = sys.argv[1:12]
bad = []
MARKER = "<!-- paraview recipe: tests/analysis/paraview_check.py runs this block -->"


def close(a, b, what):
    if not math.isclose(a, b, rel_tol=1e-9, abs_tol=1e-15):
        bad.append("%s: ParaView reads %r, expected %r" % (what, a, b))


# the README's recipe: the python block after the marker
text = open(readme).read()
if MARKER not in text:
    sys.exit("%s has no ParaView recipe (the line '%s')" % (readme, MARKER))
block = text[text.index(MARKER):].split("```python\n", 1)[1].split("```", 1)[0]
if '"frames/hopper.pvd"' not in block:
    sys.exit("the README's recipe does not open \"frames/hopper.pvd\"")
recipe = {}
exec(block.replace('"frames/hopper.pvd"', repr(pvd)), recipe)
series, view, disp = recipe["series"], recipe["view"], recipe["disks"]
times = list(series.TimestepValues)
if len(times) != int(frames):
    bad.append("the series has %d time steps, expected %d" % (len(times), int(frames)))
UpdatePipeline(time=times[0], proxy=series)
info = series.GetDataInformation()
if info.GetNumberOfPoints() != int(points):
    bad.append("first frame: %d points, expected %d" % (info.GetNumberOfPoints(), int(points)))
for name in ("id", "type", "radius", "velocity", "angular_velocity", "contact_force"):
    if name not in series.PointData.keys():
        bad.append("no point array '%s' (has %s)" % (name, series.PointData.keys()))
lo, hi = series.PointData["radius"].GetRange()
close(lo, float(r_min), "smallest radius")
close(hi, float(r_max), "largest radius")
if "contact_force" in series.PointData.keys():
    # the first frame is the fill lattice (no contacts), the last an empty hopper; in between
    # the packing has contacts
    peak = 0.0
    for t in times:
        UpdatePipeline(time=t, proxy=series)
        peak = max(peak, series.PointData["contact_force"].GetRange()[1])
    if not peak > 0:
        bad.append("contact_force is zero everywhere in every frame (a packing has contacts)")
    UpdatePipeline(time=times[0], proxy=series)
if series.PointData["velocity"].GetNumberOfComponents() != 3:
    bad.append("velocity is not a 3-vector")

# the recipe's view and display, as the README leaves them; only the picture's size is set here
view.ViewSize = [600, 800]
view.OrientationAxesVisibility = 0
GetAnimationScene().UpdateAnimationUsingDataTimeSteps()
view.ViewTime = times[-1]
ResetCamera(view)
SaveScreenshot(out + "/snapshot_last_frame.png", view, ImageResolution=[600, 800])

field = OpenDataFile(vti)
UpdatePipeline(proxy=field)
if field.GetDataInformation().GetNumberOfCells() != int(cells):
    bad.append("field map: %d cells, expected %d" % (field.GetDataInformation().GetNumberOfCells(),
                                                     int(cells)))
lo, hi = field.CellData["mean_speed"].GetRange()
close(lo, float(s_min), "mean_speed minimum")
close(hi, float(s_max), "mean_speed maximum")
view2 = CreateRenderView()
view2.ViewSize = [400, 600]
view2.OrientationAxesVisibility = 0
d2 = Show(field, view2)
d2.SetRepresentationType("Surface")
ColorBy(d2, ("CELLS", "mean_speed"))
d2.RescaleTransferFunctionToDataRange(True)
ResetCamera(view2)
SaveScreenshot(out + "/field_mean_speed.png", view2, ImageResolution=[400, 600])

for b in bad:
    print("FAIL: " + b)
print("paraview_check: %d problems" % len(bad))
sys.stdout.flush()
# os._exit: ParaView's teardown of the offscreen X context can fail after everything is written
# (GLXBadContext under xvfb), which must not decide the outcome.
os._exit(1 if bad else 0)
