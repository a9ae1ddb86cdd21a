"""A picture of a VTK series as ParaView shows it: the last frame, warped by its displacement, coloured by a
cell field, with a colour bar; rendered off screen with VTK (the library ParaView renders with).

The series is what a run writes with ``output=VTKSeries(out, name)`` (a ``.pvd`` collection of ``.vtu``
files, :mod:`skfem_flex.io.output`); the script reads its last file with VTK's own XML reader, so the
picture shows exactly what ParaView would open::

    python examples/bracket.py /tmp/bracket
    python examples/render_vtk.py /tmp/bracket/bracket.pvd von_mises docs/images/bracket_von_mises.png --warp 50

``--warp`` scales the point field ``displacement`` (ParaView's "Warp By Vector"); the colours are ParaView's
default map ("Cool to Warm", blue to red) over the field's range, in MPa for a stress (Pa / 10⁶). Needs the
``vtk`` package (``pip install ".[test]"``) and an off-screen OpenGL (EGL or OSMesa), as its wheels bring.
"""
import argparse
import xml.etree.ElementTree as ET
from pathlib import Path


def last_file(path):
    """The .vtu of the last frame of a .pvd collection (or the .vtu itself)."""
    path = Path(path)
    if path.suffix != ".pvd":
        return path
    sets = ET.parse(path).getroot().iter("DataSet")
    last = max(sets, key=lambda d: float(d.get("timestep")))
    return path.parent / last.get("file")


def field_range(path, field):
    """(min, max) of a cell field of a .vtu file."""
    import vtk
    reader = vtk.vtkXMLUnstructuredGridReader()
    reader.SetFileName(str(path))
    reader.Update()
    array = reader.GetOutput().GetCellData().GetArray(field)
    if array is None:
        raise ValueError(f"{path} has no cell field {field!r}")
    return array.GetRange()


def render(series, field, png, warp=1.0, size=(900, 700), scale=1e-6, unit="MPa"):
    """Render the last frame of ``series`` coloured by the cell field ``field`` (times ``scale``, in ``unit``),
    warped by ``warp`` × its point field ``displacement``; write ``png``. Returns the field's range (unscaled)."""
    import vtk
    path = last_file(series)
    reader = vtk.vtkXMLUnstructuredGridReader()
    reader.SetFileName(str(path))
    reader.Update()
    grid = reader.GetOutput()
    values = grid.GetCellData().GetArray(field)
    if values is None:
        raise ValueError(f"{path} has no cell field {field!r}")
    lo, hi = values.GetRange()
    scaled = vtk.vtkDoubleArray()
    scaled.SetName(f"{field} ({unit})")
    for i in range(values.GetNumberOfTuples()):
        scaled.InsertNextValue(values.GetValue(i) * scale)
    grid.GetCellData().AddArray(scaled)
    source = grid
    if grid.GetPointData().GetArray("displacement") is not None and warp != 0.0:
        grid.GetPointData().SetActiveVectors("displacement")
        warped = vtk.vtkWarpVector()
        warped.SetInputData(grid)
        warped.SetScaleFactor(warp)
        warped.Update()
        source = warped.GetOutput()
    surface = vtk.vtkDataSetSurfaceFilter()
    surface.SetInputData(source)
    lut = vtk.vtkColorTransferFunction()        # ParaView's default "Cool to Warm"
    lut.SetColorSpaceToDiverging()
    lut.AddRGBPoint(lo * scale, 0.231, 0.298, 0.753)
    lut.AddRGBPoint(hi * scale, 0.706, 0.016, 0.150)
    mapper = vtk.vtkDataSetMapper()
    mapper.SetInputConnection(surface.GetOutputPort())
    mapper.SetScalarModeToUseCellFieldData()
    mapper.SelectColorArray(f"{field} ({unit})")
    mapper.SetLookupTable(lut)
    mapper.SetScalarRange(lo * scale, hi * scale)
    actor = vtk.vtkActor()
    actor.SetMapper(mapper)
    actor.GetProperty().EdgeVisibilityOn()
    actor.GetProperty().SetEdgeColor(0.2, 0.2, 0.2)
    actor.GetProperty().SetLineWidth(0.5)
    bar = vtk.vtkScalarBarActor()
    bar.SetLookupTable(lut)
    bar.SetTitle(f"{field} ({unit})")
    bar.SetNumberOfLabels(5)
    bar.GetTitleTextProperty().SetColor(0.1, 0.1, 0.1)
    bar.GetLabelTextProperty().SetColor(0.1, 0.1, 0.1)
    renderer = vtk.vtkRenderer()
    renderer.SetBackground(1.0, 1.0, 1.0)
    renderer.AddActor(actor)
    renderer.AddViewProp(bar)
    window = vtk.vtkRenderWindow()
    window.SetOffScreenRendering(1)
    window.SetSize(*size)
    window.AddRenderer(renderer)
    camera = renderer.GetActiveCamera()
    camera.SetPosition(1.0, -0.8, 0.9)
    camera.SetFocalPoint(0.0, 0.0, 0.0)
    camera.SetViewUp(0.0, 0.0, 1.0)
    renderer.ResetCamera()
    window.Render()
    shot = vtk.vtkWindowToImageFilter()
    shot.SetInput(window)
    shot.Update()
    writer = vtk.vtkPNGWriter()
    Path(png).parent.mkdir(parents=True, exist_ok=True)
    writer.SetFileName(str(png))
    writer.SetInputConnection(shot.GetOutputPort())
    writer.Write()
    return lo, hi


def arguments(description, argv=None):
    """The command line of a picture script (this one and ``render_paraview.py``): series, field, png, --warp."""
    ap = argparse.ArgumentParser(description=description)
    ap.add_argument("series", help="a .pvd collection (its last frame) or a .vtu file")
    ap.add_argument("field", help="the cell field to colour by (von_mises)")
    ap.add_argument("png", help="the picture to write")
    ap.add_argument("--warp", type=float, default=1.0, help="scale of the displacement (1: true shape)")
    return ap.parse_args(argv)


if __name__ == "__main__":
    args = arguments(__doc__.splitlines()[0])
    lo, hi = render(args.series, args.field, args.png, args.warp)
    print(f"wrote {args.png}: {args.field} from {lo / 1e6:.3g} to {hi / 1e6:.3g} MPa on the last frame of "
          f"{args.series}")
