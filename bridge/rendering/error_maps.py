"""Error maps of fitted surfaces, rendered offscreen with VTK (course ch. 7 fits, ch. 9 display).

:func:`render_error_maps` draws one or more panels side by side, each a sampled surface shaded by
VTK's OpenGL pipeline (Phong, depth-buffered) and coloured by a per-vertex error on a logarithmic
scale shared by all panels, with optional polylines on top (overlay borders) and a title per
panel; one scalar bar, a figure title, written atomically to PNG. The window is offscreen (EGL
when the VTK build has it), so no display is needed.
"""

from __future__ import annotations

import io
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .vtk_scene import new_window

__all__ = ["ErrorPanel", "render_error_maps"]

#: Error colours, low to high (blue, cyan, green, yellow, red); values above the tolerance are red.
_COLOURS = ((0.05, 0.15, 0.65), (0.0, 0.65, 0.95), (0.1, 0.8, 0.3), (0.98, 0.85, 0.1), (0.85, 0.1, 0.05))


@dataclass
class ErrorPanel:
    """One picture of a sampled surface coloured by an error.

    Attributes
    ----------
    points : ndarray, shape (r, s, 3)
        The surface on a parameter grid (the data parameters of a gridded fit).
    errors : ndarray, shape (r, s)
        The error at each sample (NaN: no data there, drawn grey).
    title : str
    lines : list of ndarray, each (k, 3)
        Polylines drawn on top (e.g. the borders of the overlays of this level).
    """

    points: np.ndarray
    errors: np.ndarray
    title: str = ""
    lines: list[np.ndarray] = field(default_factory=list)


def _grid_polydata(P: np.ndarray, E: np.ndarray) -> Any:
    from vtkmodules.util.numpy_support import numpy_to_vtk, numpy_to_vtkIdTypeArray
    from vtkmodules.vtkCommonCore import vtkPoints
    from vtkmodules.vtkCommonDataModel import vtkCellArray, vtkPolyData

    r, s = P.shape[:2]
    k = np.arange(r * s).reshape(r, s)
    a, b, c, d = k[:-1, :-1].ravel(), k[1:, :-1].ravel(), k[1:, 1:].ravel(), k[:-1, 1:].ravel()
    tri = np.concatenate([np.column_stack([a, b, c]), np.column_stack([a, c, d])]).astype(np.int64)
    pts = vtkPoints()
    pts.SetData(numpy_to_vtk(np.ascontiguousarray(P.reshape(-1, 3), float), deep=True))
    cells = vtkCellArray()
    cells.SetData(numpy_to_vtkIdTypeArray(np.arange(0, 3 * len(tri) + 1, 3, dtype=np.int64), deep=True),
                  numpy_to_vtkIdTypeArray(tri.ravel(), deep=True))
    pd = vtkPolyData()
    pd.SetPoints(pts)
    pd.SetPolys(cells)
    arr = numpy_to_vtk(np.ascontiguousarray(E.reshape(-1), float), deep=True)
    arr.SetName("log10 error")
    pd.GetPointData().SetScalars(arr)
    return pd


def _lines_actor(lines: Sequence[np.ndarray]) -> Any:
    """Black polylines (each (k, 3), k >= 2), drawn over the surface."""
    from vtkmodules.util.numpy_support import numpy_to_vtk, numpy_to_vtkIdTypeArray
    from vtkmodules.vtkCommonCore import vtkPoints
    from vtkmodules.vtkCommonDataModel import vtkCellArray, vtkPolyData
    from vtkmodules.vtkRenderingCore import vtkActor, vtkPolyDataMapper

    ls = [np.asarray(x, float) for x in lines if len(x) >= 2]
    P = np.concatenate(ls)
    lens = np.array([len(x) for x in ls], np.int64)
    pts = vtkPoints()
    pts.SetData(numpy_to_vtk(np.ascontiguousarray(P), deep=True))
    cells = vtkCellArray()
    cells.SetData(numpy_to_vtkIdTypeArray(np.concatenate([[0], np.cumsum(lens)]).astype(np.int64), deep=True),
                  numpy_to_vtkIdTypeArray(np.arange(len(P), dtype=np.int64), deep=True))
    pd = vtkPolyData()
    pd.SetPoints(pts)
    pd.SetLines(cells)
    mapper = vtkPolyDataMapper()
    mapper.SetInputData(pd)
    mapper.SetResolveCoincidentTopologyToPolygonOffset()
    actor = vtkActor()
    actor.SetMapper(mapper)
    actor.GetProperty().SetColor(0.05, 0.05, 0.05)
    actor.GetProperty().SetLineWidth(1.6)
    actor.GetProperty().LightingOff()
    return actor


def _lookup(lo: float, hi: float) -> Any:
    from vtkmodules.vtkCommonCore import vtkLookupTable

    ctrl = np.array(_COLOURS)
    t = np.linspace(0, 1, 256)
    x = np.linspace(0, 1, len(ctrl))
    lut = vtkLookupTable()
    lut.SetNumberOfTableValues(256)
    for i, ti in enumerate(t):
        r, g, b = (float(np.interp(ti, x, ctrl[:, c])) for c in range(3))
        lut.SetTableValue(i, r, g, b, 1.0)
    lut.SetRange(lo, hi)
    lut.SetNanColor(0.7, 0.7, 0.7, 1.0)
    lut.Build()
    return lut


def _text(renderer: Any, text: str, size: int, y: float) -> None:
    from vtkmodules.vtkRenderingCore import vtkTextActor

    t = vtkTextActor()
    t.SetInput(text)
    t.GetTextProperty().SetFontSize(size)
    t.GetTextProperty().SetColor(0.1, 0.1, 0.1)
    t.GetTextProperty().SetJustificationToCentered()
    t.GetPositionCoordinate().SetCoordinateSystemToNormalizedViewport()
    t.SetPosition(0.5, y)
    renderer.AddViewProp(t)


def _panel(panel: ErrorPanel, lut: Any, lo: float, hi: float, floor: float, camera: tuple[float, float, float]) -> Any:
    from vtkmodules.vtkRenderingCore import vtkActor, vtkPolyDataMapper, vtkRenderer

    P = np.asarray(panel.points, float)
    E = np.asarray(panel.errors, float)
    logE = np.where(np.isfinite(E), np.log10(np.maximum(E, floor)), np.nan)
    ren = vtkRenderer()
    ren.SetBackground(1.0, 1.0, 1.0)
    ren.SetBackground2(0.86, 0.89, 0.93)
    ren.GradientBackgroundOn()
    mapper = vtkPolyDataMapper()
    mapper.SetInputData(_grid_polydata(P, logE))
    mapper.SetLookupTable(lut)
    mapper.SetScalarRange(lo, hi)
    mapper.UseLookupTableScalarRangeOn()
    mapper.InterpolateScalarsBeforeMappingOn()
    actor = vtkActor()
    actor.SetMapper(mapper)
    prop = actor.GetProperty()
    prop.SetInterpolationToPhong()
    prop.SetAmbient(0.3)
    prop.SetDiffuse(0.75)
    prop.SetSpecular(0.15)
    ren.AddActor(actor)
    if panel.lines:
        ren.AddActor(_lines_actor(panel.lines))
    if panel.title:
        _text(ren, panel.title, 15, 0.93)
    finite = P[np.all(np.isfinite(P), axis=-1)]
    centre = 0.5 * (finite.min(axis=0) + finite.max(axis=0))
    radius = float(np.linalg.norm(finite.max(axis=0) - finite.min(axis=0))) or 1.0
    cam = ren.GetActiveCamera()
    d = np.asarray(camera, float) / np.linalg.norm(camera)
    cam.SetFocalPoint(*centre)
    cam.SetPosition(*(centre + 3.0 * radius * d))
    up = np.array([0.0, 0.0, 1.0]) if abs(d[2]) < 0.95 else np.array([0.0, 1.0, 0.0])
    cam.SetViewUp(*up)
    ren.ResetCamera()
    cam.Zoom(1.25)
    ren.ResetCameraClippingRange()
    return ren


def render_error_maps(path: str | Path, panels: Sequence[ErrorPanel], *, tol: float | None = None,
                      title: str | None = None, label: str = "distance",
                      panel_size: tuple[int, int] = (520, 460), columns: int = 3,
                      camera: tuple[float, float, float] = (0.9, -1.3, 1.1)) -> Path:
    """Write a PNG of surfaces coloured by their error, one panel per item (course ch. 7, 9).

    Parameters
    ----------
    path : path-like
        The PNG (written atomically).
    panels : sequence of ErrorPanel
    tol : float, optional
        The tolerance: the colour scale runs from ``tol / 100`` to ``max(errors, tol)`` on a
        log10 axis, so green-yellow is "within", red "above" it; without ``tol`` it spans three
        decades below the largest error.
    title : str, optional
        A line above all panels.
    label : str
        The scalar bar's title (``log10`` is added).
    panel_size : (int, int)
        Pixels per panel.
    columns : int
        Panels per row.
    camera : (float, float, float)
        Direction from the surface to the camera.

    Returns
    -------
    Path
    """
    from vtkmodules.vtkRenderingAnnotation import vtkScalarBarActor
    from vtkmodules.vtkRenderingCore import vtkRenderer, vtkWindowToImageFilter

    from ..exchange.files import atomic_write

    if not panels:
        raise ValueError("panels: expected at least one panel")
    emax = max(float(np.nanmax(p.errors)) if np.isfinite(p.errors).any() else 0.0 for p in panels)
    top = max(emax, tol or 0.0) or 1.0
    floor = (tol / 100.0) if tol else top / 1e3
    lo, hi = np.log10(floor), np.log10(top)
    if hi <= lo:
        hi = lo + 1.0
    lut = _lookup(lo, hi)
    ncol = max(1, min(int(columns), len(panels)))
    nrow = -(-len(panels) // ncol)
    bar_w = 170
    head = 50 if title else 0
    W, H = ncol * panel_size[0] + bar_w, nrow * panel_size[1] + head
    win = new_window(W, H, multisamples=4)
    for k, panel in enumerate(panels):
        r, c = divmod(k, ncol)
        ren = _panel(panel, lut, lo, hi, floor, camera)
        x0, x1 = c * panel_size[0] / W, (c + 1) * panel_size[0] / W
        y1 = 1.0 - (head + r * panel_size[1]) / H
        y0 = 1.0 - (head + (r + 1) * panel_size[1]) / H
        ren.SetViewport(x0, y0, x1, y1)
        win.AddRenderer(ren)
    for k in range(len(panels), nrow * ncol):  # empty cells of the last row: background
        r, c = divmod(k, ncol)
        blank = vtkRenderer()
        blank.SetBackground(1.0, 1.0, 1.0)
        blank.SetViewport(c * panel_size[0] / W, 1.0 - (head + (r + 1) * panel_size[1]) / H,
                          (c + 1) * panel_size[0] / W, 1.0 - (head + r * panel_size[1]) / H)
        win.AddRenderer(blank)
    side = vtkRenderer()
    side.SetViewport(ncol * panel_size[0] / W, 0.0, 1.0, 1.0 - head / H)
    side.SetBackground(1.0, 1.0, 1.0)
    bar = vtkScalarBarActor()
    bar.SetLookupTable(lut)
    bar.SetTitle(f"log10 {label}" + (f"\ntol {tol:.3g} = {np.log10(tol):.2f}" if tol else ""))
    bar.SetNumberOfLabels(6)
    bar.SetLabelFormat("%.1f")
    bar.UnconstrainedFontSizeOn()
    for tp, size in ((bar.GetTitleTextProperty(), 13), (bar.GetLabelTextProperty(), 14)):
        tp.SetColor(0.1, 0.1, 0.1)
        tp.ItalicOff()
        tp.BoldOff()
        tp.ShadowOff()
        tp.SetFontSize(size)
    bar.SetPosition(0.18, 0.08)
    bar.SetWidth(0.55)
    bar.SetHeight(0.84)
    side.AddViewProp(bar)
    win.AddRenderer(side)
    if title:
        band = vtkRenderer()
        band.SetViewport(0.0, 1.0 - head / H, 1.0, 1.0)
        band.SetBackground(1.0, 1.0, 1.0)
        _text(band, title, 17, 0.3)
        win.AddRenderer(band)
    win.Render()
    grab = vtkWindowToImageFilter()
    grab.SetInput(win)
    grab.ReadFrontBufferOff()
    grab.Update()
    from vtkmodules.util.numpy_support import vtk_to_numpy

    img = grab.GetOutput()
    w, h, _ = img.GetDimensions()
    arr = vtk_to_numpy(img.GetPointData().GetScalars()).reshape(h, w, -1)[::-1, :, :3]
    win.Finalize()
    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray(np.ascontiguousarray(arr)).save(buf, format="PNG")
    return atomic_write(path, buf.getvalue())
