"""Opens a sphdem run's frames.xdmf with ParaView's Python (pvpython) and checks what a user
would see: the number of time steps, the points of the last frame (fluid + walls) and the arrays.
Optionally renders the last frame to a PNG.

Usage: pvpython app/paraview_check.py OUT/frames.xdmf FRAMES POINTS [picture.png]
Exit status 0 when the counts match, 1 otherwise (with a message).
"""
import sys

from paraview.simple import GetActiveViewOrCreate, Render, SaveScreenshot, Show, XDMFReader
from paraview.simple import ColorBy, ResetCamera


def main():
    path, frames, points = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
    reader = XDMFReader(FileNames=[path])
    times = list(reader.TimestepValues)
    if len(times) != frames:
        print(f"{path}: {len(times)} time steps, expected {frames}")
        return 1
    reader.UpdatePipeline(times[-1])
    n = reader.GetDataInformation().GetNumberOfPoints()
    arrays = sorted(reader.PointData[i].GetName() for i in range(len(reader.PointData)))
    print(f"{path}: {len(times)} time steps, {n} points at t = {times[-1]:.4g}, arrays {arrays}")
    if n != points:
        print(f"expected {points} points")
        return 1
    for a in ("press", "vel"):
        if a not in arrays:
            print(f"array '{a}' missing")
            return 1
    if len(sys.argv) > 4:
        view = GetActiveViewOrCreate("RenderView")
        view.ViewSize = [1000, 500]
        display = Show(reader, view)
        display.SetRepresentationType("Points")
        display.PointSize = 3
        ColorBy(display, ("POINTS", "press"))
        display.RescaleTransferFunctionToDataRange(True)
        view.CameraPosition = [0.3, -1.5, 0.15]
        view.CameraFocalPoint = [0.3, 0, 0.15]
        view.CameraViewUp = [0, 0, 1]
        ResetCamera(view)
        Render(view)
        SaveScreenshot(sys.argv[4], view, ImageResolution=[1000, 500])
    return 0


if __name__ == "__main__":
    sys.exit(main())
