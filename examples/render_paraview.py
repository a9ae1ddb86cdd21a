"""A ParaView picture of a VTK series: the last frame, warped by its displacement, coloured by a cell field,
with a colour bar. A ParaView Python script, run by ParaView's ``pvbatch`` (off screen); started with another
Python (the package's), it runs itself again under ``pvbatch`` from the PATH, on a virtual screen (``Xvfb``)
where there is none (a ParaView built for one, as Debian's ``paraview`` package, needs it even off screen)::

    python examples/bracket.py /tmp/bracket
    python examples/render_paraview.py /tmp/bracket/bracket.pvd von_mises docs/images/bracket_paraview.png --warp 50

It is the pipeline one clicks together in ParaView's window: open the ``.pvd`` collection, go to its
last time, "Cell Data to Point Data" is not applied (each tetrahedron keeps its own value), "Warp By Vector"
on the point field ``displacement`` scaled by ``--warp``, shown as "Surface With Edges", coloured by the cell
field in ParaView's default map ("Cool to Warm"), in MPa for a stress (a Calculator divides by 10⁶), with its colour bar, and save a
screenshot. ``examples/render_vtk.py`` draws the same picture with the ``vtk`` wheel alone, for a machine
without ParaView.
"""
import os
import shutil
import subprocess
import sys


def render(series, field, png, warp=1.0, size=(900, 700), scale=1e-6, unit="MPa"):
    """Render the last frame of ``series`` coloured by ``field`` × ``scale`` (in ``unit``), warped by ``warp`` ×
    the point field ``displacement``; write ``png``. Returns the field's range (unscaled)."""
    from paraview import simple as pv

    reader = pv.OpenDataFile(str(series))
    times = list(reader.TimestepValues) if hasattr(reader.TimestepValues, "__len__") else [reader.TimestepValues]
    view = pv.CreateView("RenderView")
    view.ViewSize = list(size)
    view.OrientationAxesVisibility = 0
    view.ViewTime = times[-1]
    reader.UpdatePipeline(times[-1])
    info = reader.CellData[field] if field in reader.CellData.keys() else None
    if info is None:
        raise ValueError(f"{series} has no cell field {field!r}; it has {list(reader.CellData.keys())}")
    lo, hi = info.GetRange()
    label = f"{field} ({unit})"
    scaled = pv.Calculator(Input=reader, AttributeType="Cell Data", ResultArrayName=label,
                           Function=f"{field}*{scale!r}")
    warped = pv.WarpByVector(Input=scaled, Vectors=["POINTS", "displacement"], ScaleFactor=warp)
    display = pv.Show(warped, view)
    display.SetRepresentationType("Surface With Edges")
    pv.ColorBy(display, ("CELLS", label))
    lut = pv.GetColorTransferFunction(label)
    lut.ApplyPreset("Cool to Warm", True)
    lut.RescaleTransferFunction(lo * scale, hi * scale)
    display.SetScalarBarVisibility(view, True)
    bar = pv.GetScalarBar(lut, view)
    bar.Title = label
    bar.ComponentTitle = ""
    view.CameraPosition = [1.0, -0.8, 0.9]
    view.CameraFocalPoint = [0.0, 0.0, 0.0]
    view.CameraViewUp = [0.0, 0.0, 1.0]
    view.ResetCamera()
    pv.SaveScreenshot(str(png), view, ImageResolution=list(size))
    return lo, hi


def run_under_pvbatch(argv):
    """This script with ``argv`` under ParaView's ``pvbatch``; without a screen, on a virtual one (``Xvfb``,
    which picks a free display number itself and says it: no race between runs). Returns the exit status."""
    pvbatch = shutil.which("pvbatch")
    if pvbatch is None:
        raise SystemExit("render_paraview: ParaView's pvbatch is not on the PATH: install ParaView (Debian: apt "
                         "install paraview), or draw the picture with examples/render_vtk.py")
    command = [pvbatch, "--force-offscreen-rendering", os.path.abspath(__file__), *argv]
    if os.environ.get("DISPLAY") or not shutil.which("Xvfb"):
        return subprocess.run(command).returncode
    # a 24-bit screen: OpenGL finds no visual on Xvfb's default 8 bits
    server = subprocess.Popen(["Xvfb", "-displayfd", "1", "-screen", "0", "1280x1024x24", "-nolisten", "tcp"],
                              stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    try:
        display = server.stdout.readline().strip()
        if not display:
            raise SystemExit("render_paraview: Xvfb did not start (no screen for pvbatch)")
        return subprocess.run(command, env=dict(os.environ, DISPLAY=f":{display}")).returncode
    finally:
        server.terminate()
        server.wait()


if __name__ == "__main__":
    try:
        import paraview.simple  # noqa: F401  (ParaView's own Python: pvbatch or pvpython)
    except ImportError:
        raise SystemExit(run_under_pvbatch(sys.argv[1:]))
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))     # its sibling, under pvbatch too
    from render_vtk import arguments
    args = arguments(__doc__.splitlines()[0])
    lo, hi = render(args.series, args.field, args.png, warp=args.warp)
    print(f"{args.field}: {lo:.6g} to {hi:.6g}; wrote {args.png}")
