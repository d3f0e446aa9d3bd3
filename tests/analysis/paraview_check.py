"""Run by pvpython (ParaView's own Python): loads a snapshot series (hopper.pvd) and a field map
(.vti) with ParaView's native readers, checks what they hold and renders each to a PNG.
usage: pvpython paraview_check.py SERIES.pvd FRAMES POINTS R_MIN R_MAX FIELD.vti CELLS
                                  SPEED_MIN SPEED_MAX OUT_DIR"""
import math
import os
import sys

from paraview.simple import (ColorBy, CreateRenderView, GetAnimationScene, OpenDataFile,
                             ResetCamera, SaveScreenshot, Show, UpdatePipeline)

pvd, frames, points, r_min, r_max, vti, cells, s_min, s_max, out = sys.argv[1:11]
bad = []


def close(a, b, what):
    if not math.isclose(a, b, rel_tol=1e-9, abs_tol=1e-15):
        bad.append("%s: ParaView reads %r, expected %r" % (what, a, b))


series = OpenDataFile(pvd)
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

view = CreateRenderView()
view.ViewSize = [600, 800]
view.OrientationAxesVisibility = 0
disp = Show(series, view)
disp.SetRepresentationType("Point Gaussian")
disp.ScaleByArray = 1
disp.SetScaleArray = ["POINTS", "radius"]
disp.UseScaleFunction = 0
disp.GaussianRadius = 1.0
ColorBy(disp, ("POINTS", "velocity", "Magnitude"))
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
