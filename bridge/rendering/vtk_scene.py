"""Offscreen 3-D pictures with VTK: shaded meshes coloured per vertex, lines, arrows, a legend.

Course ch. 9 (§9-8, graphical display of curvature and of reflection lines) and ch. 10 (lighting):
a real depth-buffered renderer (VTK's OpenGL pipeline, offscreen through EGL when there is no
display), not a painter's algorithm. One :class:`Scene` collects

* meshes (:meth:`Scene.add_mesh`): triangles with per-vertex normals and either a scalar mapped
  through a colour map (``'diverging'`` blue-white-red, ``'rainbow'`` blue-green-red as CAD
  systems show curvature, ``'stripes'`` black/white for zebra and isophotes, ``'grey'``) or
  per-vertex RGB colours. Scalars are interpolated across each triangle *before* they are
  mapped (VTK's ``InterpolateScalarsBeforeMapping``), so zebra stripes and isophotes stay sharp
  per pixel instead of smearing over large triangles; NaN (degenerate points) is drawn in
  magenta, never in a colour of the scale;
* polylines (:meth:`Scene.add_lines`: sections, combs, iso-curves, edges), points
  (:meth:`Scene.add_points`: flag locations, inflections) and hedgehogs
  (:meth:`Scene.add_hedgehog`: normals);
* one legend (:meth:`Scene.set_legend`, a scalar bar with its title) and a title;

and renders them from a camera preset (:data:`~.cameras.CAMERAS`: ``'iso'``, ``'top'``, ``'front'``,
``'right'``, any other of :data:`~.cameras.VIEWS`, or an explicit direction) to a PNG of a given size
(:meth:`Scene.render`) or to an array (:meth:`Scene.render_array`).

This module is also the one offscreen-window and camera code path of every VTK picture: the
per-pixel Warn renderer of course ch. 10 (:mod:`.lighting`) draws through the same
:func:`window` cache, frames with the same :func:`~.cameras.fit_camera` into the same
:class:`~.cameras.Camera`, puts it on VTK with :func:`~.cameras.apply_camera` (all three in
:mod:`.cameras`) and reads pixels back with :func:`read_pixels`.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

# the cameras live in .cameras since 2026-12-06; importable from here as before
from .cameras import CAMERAS, VIEW_ANGLE, VIEWS, Camera, apply_camera, fit_camera, vtk_matrix  # noqa: F401

if TYPE_CHECKING:
    from vtkmodules.vtkCommonDataModel import vtkPolyData
    from vtkmodules.vtkRenderingCore import vtkRenderWindow

__all__ = ["Scene", "window", "new_window", "read_pixels", "COLORMAPS", "colormap_rgb", "render_available", "polydata",
           "merged_meshes"]

#: Colour maps by name: control colours (RGB in [0, 1]) spread evenly over the scale.
COLORMAPS: dict[str, tuple[tuple[float, float, float], ...]] = {
    "diverging": ((0.23, 0.30, 0.75), (0.55, 0.69, 0.99), (0.87, 0.87, 0.87), (0.96, 0.60, 0.48), (0.71, 0.02, 0.15)),
    "rainbow": ((0.0, 0.0, 0.9), (0.0, 0.75, 1.0), (0.0, 0.85, 0.2), (1.0, 0.9, 0.0), (0.95, 0.1, 0.0)),
    "sequential": ((0.27, 0.0, 0.33), (0.23, 0.32, 0.55), (0.13, 0.57, 0.55), (0.37, 0.79, 0.38), (0.99, 0.91, 0.14)),
    "grey": ((0.78, 0.80, 0.84), (0.78, 0.80, 0.84)),
}
#: Per-pixel stripe shaders (GLSL replacing VTK's lighting): the stripe coordinate from the
#: view-space normal, anti-aliased by its screen-space derivative (``fwidth``). The camera looks
#: along -z in view coordinates; zebra: the angle of the reflected ray from the plane spanned by
#: the view-up and view directions (light tubes parallel to the view-up axis at infinity, Klass
#: 1980: a plane reflects one uniform shade, no seam or pole in the pattern); isophote: ``n . v``.
PIXEL_SHADERS: dict[str, str] = {
    "zebra": """
  vec3 zn = normalize(normalVCVSOutput);
  if (!gl_FrontFacing) { zn = -zn; }
  vec3 zr = reflect(vec3(0.0, 0.0, -1.0), zn);
  float zs = asin(clamp(zr.x, -1.0, 1.0)) / 3.14159265 * 2.0 * PAIRS + 0.25;
""",
    "isophote": """
  vec3 zn = normalize(normalVCVSOutput);
  if (!gl_FrontFacing) { zn = -zn; }
  float zs = zn.z * PAIRS + 0.25;
""",
}
_STRIPE_TAIL = """
  float zw = max(fwidth(zs), 1e-4);
  float zf = fract(zs);
  float za = smoothstep(0.5 - zw, 0.5 + zw, zf) - smoothstep(1.0 - zw, 1.0 + zw, zf) + 1.0 - smoothstep(-zw, zw, zf);
  gl_FragData[0] = vec4(vec3(mix(0.96, 0.06, clamp(za, 0.0, 1.0))), 1.0);
"""
PIXEL_SHADERS = {k: v + _STRIPE_TAIL for k, v in PIXEL_SHADERS.items()}
#: Colour of NaN scalars (degenerate points): a colour no scale uses.
NAN_COLOR = (1.0, 0.0, 1.0)
_TABLE = 256


def render_available() -> bool:
    """True when VTK can open an offscreen render window here."""
    try:
        new_window(8, 8).Finalize()
        return True
    except Exception:  # noqa: BLE001
        return False


def colormap_rgb(values: np.ndarray, lo: float, hi: float, cmap: str = "diverging") -> np.ndarray:
    """Map ``values (...)`` onto RGB ``(..., 3)`` uint8 with a named colour map on ``[lo, hi]``.

    Values outside are clipped; NaN maps to :data:`NAN_COLOR`. The same table as the renderer's.
    """
    table = _table(cmap, 2)
    v = np.asarray(values, float)
    t = np.clip((v - lo) / (hi - lo if hi > lo else 1.0), 0.0, 1.0)
    idx = np.minimum((np.nan_to_num(t) * len(table)).astype(int), len(table) - 1)
    rgb = table[idx]
    rgb[~np.isfinite(v)] = NAN_COLOR
    return np.round(rgb * 255).astype(np.uint8)


def _table(cmap: str, stripes: int) -> np.ndarray:
    """``(k, 3)`` RGB table of a colour map; ``'stripes'`` alternates black and white ``stripes`` times."""
    if cmap == "stripes":
        return np.tile(np.array([[0.05, 0.05, 0.05], [0.97, 0.97, 0.97]]), (max(1, stripes), 1))
    if cmap not in COLORMAPS:
        raise ValueError(f"cmap: expected one of {', '.join([*COLORMAPS, 'stripes'])}, got {cmap!r}")
    ctrl = np.array(COLORMAPS[cmap], float)
    x = np.linspace(0.0, 1.0, len(ctrl))
    t = np.linspace(0.0, 1.0, _TABLE)
    return np.column_stack([np.interp(t, x, ctrl[:, k]) for k in range(3)])


def _lut(cmap: str, lo: float, hi: float, stripes: int = 1) -> Any:
    """A ``vtkLookupTable`` of ``cmap`` over ``[lo, hi]``. Its RGBA bytes are set at once
    (``SetTable``), rounded as ``SetTableValue`` rounds (``255 x + 0.5``, truncated): the same
    colours for every value, NaN and out of range, as the 256 ``SetTableValue`` calls made one by
    one (0.39 ms a table; a report of the bearing builds 662)."""
    from vtkmodules.util.numpy_support import numpy_to_vtk
    from vtkmodules.vtkCommonCore import VTK_UNSIGNED_CHAR, vtkLookupTable

    table = _table(cmap, stripes)
    lut = vtkLookupTable()
    lut.SetNumberOfTableValues(len(table))
    rgba = np.floor(np.c_[table, np.ones(len(table))] * 255.0 + 0.5).astype(np.uint8)
    lut.SetTable(numpy_to_vtk(rgba, deep=True, array_type=VTK_UNSIGNED_CHAR))
    lut.SetRange(float(lo), float(hi) if hi > lo else float(lo) + 1.0)
    lut.SetNanColor(*NAN_COLOR, 1.0)
    lut.Build()
    return lut


def new_window(width: int, height: int, *, multisamples: int = 0) -> vtkRenderWindow:
    """An offscreen render window: EGL (no display needed) when the build has it, else the default.

    ``multisamples=0`` (the scene's choice: FXAA on the renderer instead, half the read-back time of
    4x MSAA); the error maps of ``occsurf fit`` ask for 4.
    """
    check_pixels(width, height, multisamples)  # too large for MAX_ARRAY_BYTES: refused first
    import vtkmodules.vtkRenderingOpenGL2  # noqa: F401  (registers the OpenGL factories)
    from vtkmodules.vtkCommonCore import vtkLogger, vtkObject
    from vtkmodules.vtkRenderingCore import vtkRenderWindow

    vtkObject.GlobalWarningDisplayOff()
    vtkLogger.SetStderrVerbosity(vtkLogger.VERBOSITY_ERROR)
    try:
        from vtkmodules.vtkRenderingOpenGL2 import vtkEGLRenderWindow

        win: vtkRenderWindow = vtkEGLRenderWindow()
    except ImportError:
        win = vtkRenderWindow()
    win.SetOffScreenRendering(1)
    win.SetSize(int(width), int(height))
    win.SetMultiSamples(int(multisamples))
    return win


_WINDOWS: dict[tuple[int, int, int], vtkRenderWindow] = {}

def check_pixels(width: int, height: int, multisamples: int = 0) -> None:
    """Refuse, before the window exists, a picture whose buffers (8 bytes per multisample, 24 more per
    pixel: resolved buffers, the copies read back) exceed ``tolerances.MAX_ARRAY_BYTES``."""
    from occsurf.algorithms._validate import check_size

    w, h, s = int(width), int(height), int(multisamples)
    check_size((h, w, 8 * max(s, 1) + 24), f"size: a {w} x {h} picture with {s} samples", itemsize=1)


def window(width: int, height: int, multisamples: int = 0) -> vtkRenderWindow:
    """The cached offscreen window of this size and multisampling (:func:`new_window`; creating an
    OpenGL context costs ~50 ms per picture). Callers add their renderer, render, read the pixels
    and remove the renderer again."""
    key = (int(width), int(height), int(multisamples))
    win = _WINDOWS.get(key)
    if win is None:
        win = _WINDOWS[key] = new_window(*key[:2], multisamples=key[2])
    return win


def read_pixels(win: vtkRenderWindow, width: int, height: int, *, depth: bool = False) -> tuple[np.ndarray, np.ndarray | None]:
    """The back buffer just rendered: RGB ``(height, width, 3)`` uint8 with row 0 at the top, and
    (``depth=True``) the OpenGL depth ``(height, width)`` float32 in [0, 1] (1: background)."""
    from vtkmodules.util.numpy_support import vtk_to_numpy
    from vtkmodules.vtkCommonCore import vtkFloatArray, vtkUnsignedCharArray

    buf = vtkUnsignedCharArray()
    win.GetPixelData(0, 0, width - 1, height - 1, 0, buf, 0)  # back buffer: a third faster than
    rgb = vtk_to_numpy(buf).reshape(height, width, -1)[::-1, :, :3].copy()  # vtkWindowToImageFilter
    if not depth:
        return rgb, None
    zf = vtkFloatArray()
    win.GetZbufferData(0, 0, width - 1, height - 1, zf)
    return rgb, vtk_to_numpy(zf).reshape(height, width)[::-1].copy()


def merged_meshes(sizes: Sequence[int], mesh: Callable[[int], tuple[Any, ...]],
                  limit: int) -> Iterator[tuple[Any, ...]]:
    """Meshes concatenated in their order, in groups of at most ``limit`` vertices (a mesh is never
    split), for a scene that draws one actor per group instead of one per mesh.

    ``sizes[k]`` is mesh ``k``'s vertex count and ``mesh(k)`` its ``(points, triangles, per-vertex
    arrays...)``, asked for only when its group is made; a per-vertex array that is None in a
    group's first mesh is None in the group. The meshes share no vertices, so a NaN normal's
    fallback from its own triangles is the same in a group; the picture is the same to
    rasterisation round-off (VTK shifts and scales each mesh's float32 vertex buffer about its own
    bounds). Used by the report's pictures and ``render_panels``.
    """
    group: list[int] = []
    count = 0

    def pack(ks: list[int]) -> tuple[Any, ...]:
        if len(ks) == 1:
            return mesh(ks[0])
        parts = [mesh(k) for k in ks]
        starts = np.cumsum([0] + [sizes[k] for k in ks[:-1]])
        rest = tuple(None if parts[0][j] is None else np.concatenate([q[j] for q in parts])
                     for j in range(2, len(parts[0])))
        return (np.concatenate([q[0] for q in parts]),
                np.concatenate([np.asarray(q[1], np.int64) + s for q, s in zip(parts, starts)]), *rest)

    for k, n in enumerate(sizes):
        if group and count + n > limit:
            yield pack(group)
            group, count = [], 0
        group.append(k)
        count += n
    if group:
        yield pack(group)


def polydata(points: np.ndarray, cells: np.ndarray | Sequence[np.ndarray], kind: str, *,
             ids32: bool = False) -> vtkPolyData:
    """vtkPolyData from points ``(n, 3)`` and cells (triangles ``(m, 3)`` or polylines of indices).

    ``ids32``: triangles stored with 32-bit offsets and indices where they fit (VTK's compact cell
    storage: half the memory of the 64-bit ids; the same cells, the same picture)."""
    from vtkmodules.util.numpy_support import numpy_to_vtk, numpy_to_vtkIdTypeArray
    from vtkmodules.vtkCommonCore import vtkPoints
    from vtkmodules.vtkCommonDataModel import vtkCellArray, vtkPolyData

    pts = vtkPoints()
    pts.SetData(numpy_to_vtk(np.ascontiguousarray(points, float), deep=True))
    arr = vtkCellArray()
    if kind == "triangles":
        tri = np.ascontiguousarray(cells, np.int64).reshape(-1, 3)
        offsets = np.arange(0, 3 * len(tri) + 1, 3, dtype=np.int64)
        if ids32 and 3 * len(tri) < 2 ** 31 and (not tri.size or int(tri.max()) < 2 ** 31):
            arr.SetData(_int32_array(offsets), _int32_array(tri.ravel()))
        else:
            arr.SetData(numpy_to_vtkIdTypeArray(offsets, deep=True), numpy_to_vtkIdTypeArray(tri.ravel(), deep=True))
    else:
        lens = np.array([len(c) for c in cells], np.int64)
        offsets = np.concatenate([[0], np.cumsum(lens)]).astype(np.int64)
        conn = np.concatenate(cells).astype(np.int64) if len(cells) else np.zeros(0, np.int64)
        arr.SetData(numpy_to_vtkIdTypeArray(offsets, deep=True), numpy_to_vtkIdTypeArray(conn, deep=True))
    pd = vtkPolyData()
    pd.SetPoints(pts)
    (pd.SetPolys if kind == "triangles" else pd.SetLines)(arr)
    return pd


def _int32_array(values: np.ndarray) -> Any:
    """A ``vtkTypeInt32Array`` holding ``values`` (what ``vtkCellArray.SetData`` takes for 32-bit storage)."""
    from vtkmodules.util.numpy_support import vtk_to_numpy
    from vtkmodules.vtkCommonCore import vtkTypeInt32Array

    a = vtkTypeInt32Array()
    a.SetNumberOfTuples(len(values))
    vtk_to_numpy(a)[:] = values
    return a


def _extent(P: np.ndarray) -> np.ndarray:
    """The corners ``[min, max]`` (shape (2, 3)) of finite points ``P``, what framing needs of them:
    a prop's points are not kept for it (1.8 million for a 1089-face model, with a copy when framed)."""
    return np.stack([P.min(axis=0), P.max(axis=0)]) if len(P) else np.zeros((0, 3))


@dataclass
class _Legend:
    title: str
    lo: float
    hi: float
    cmap: str
    stripes: int
    labels: int


class Scene:
    """Meshes, lines, points and a legend, rendered offscreen by VTK to PNG.

    Examples
    --------
    >>> s = Scene()                                                   # doctest: +SKIP
    >>> s.add_mesh(points, triangles, normals=n, scalars=k, cmap="diverging", scale=(-1, 1))
    >>> s.set_legend("mean curvature H [1/mm]", -1, 1)
    >>> s.render("face.png", size=(800, 600), camera="iso")
    """

    def __init__(self, *, background: tuple[float, float, float] = (1.0, 1.0, 1.0)) -> None:
        import vtkmodules.vtkRenderingOpenGL2  # noqa: F401  (before the renderer: else a first scene gets
        from vtkmodules.vtkRenderingCore import vtkRenderer  # VTK's generic renderer, which draws nothing)

        self._renderer = vtkRenderer()
        self._renderer.SetBackground(*background)
        self._renderer.SetBackground2(0.86, 0.89, 0.93)
        self._renderer.GradientBackgroundOn()
        self._renderer.UseFXAAOn()
        self._legend: _Legend | None = None
        self._title: str | None = None
        self._bounds: list[np.ndarray] = []
        self._lights: list[tuple[tuple[float, ...], float]] | None = None

    # ------------------------------------------------------------------------------ content
    def add_mesh(self, points: np.ndarray, triangles: np.ndarray, *, normals: np.ndarray | None = None,
                 scalars: np.ndarray | None = None, colors: np.ndarray | None = None, cmap: str = "grey",
                 scale: tuple[float, float] | None = None, stripes: int = 1, opacity: float = 1.0,
                 specular: float = 0.25, edges: bool = False, shader: str | None = None) -> None:
        """Add a triangle mesh.

        Parameters
        ----------
        points : ndarray, shape (n, 3)
        triangles : ndarray, shape (m, 3), int
        normals : ndarray, shape (n, 3), optional
            Per-vertex normals for smooth shading (NaN rows are replaced by VTK's own).
        scalars : ndarray, shape (n,), optional
            Mapped through ``cmap`` on ``scale`` (default: min/max of the finite values).
        colors : ndarray, shape (n, 3), optional
            Per-vertex RGB (uint8 or floats in [0, 1]); overrides ``scalars``.
        cmap : str
            A key of :data:`COLORMAPS` or ``'stripes'`` (``stripes`` black/white pairs over ``scale``).
        shader : {"zebra", "isophote"}, optional
            Per-pixel stripes from the interpolated normal, fixed to the view (:data:`PIXEL_SHADERS`):
            ``'zebra'``, reflection lines of light tubes parallel to the view-up axis at infinity
            (``stripes`` light/dark pairs per half turn of the reflected ray); ``'isophote'``, bands of equal
            ``n . v`` (``stripes`` pairs over [-1, 1]). Needs ``normals``; overrides colours.
        """
        from vtkmodules.util.numpy_support import numpy_to_vtk
        from vtkmodules.vtkRenderingCore import vtkActor, vtkPolyDataMapper

        P = np.asarray(points, float)
        T = np.asarray(triangles, np.int64)
        if P.ndim != 2 or P.shape[1] != 3 or T.ndim != 2 or T.shape[1] != 3:
            raise ValueError(f"points (n, 3) and triangles (m, 3) expected, got {P.shape} and {T.shape}")
        pd = polydata(P, T, "triangles", ids32=True)
        if normals is not None:
            N = np.asarray(normals, float).copy()
            bad = ~np.all(np.isfinite(N), axis=1)
            if bad.any():
                N[bad] = _vertex_normals(P, T, bad)[bad]
            # as float32: what the renderer uploads anyway (the same rounding), at half the memory
            pd.GetPointData().SetNormals(numpy_to_vtk(N.astype(np.float32), deep=True))
        mapper = vtkPolyDataMapper()
        mapper.SetInputData(pd)
        if colors is not None:
            C = np.asarray(colors)
            C = C if C.dtype == np.uint8 else np.round(np.clip(C, 0, 1) * 255).astype(np.uint8)
            arr = numpy_to_vtk(np.ascontiguousarray(C), deep=True)
            arr.SetName("rgb")
            pd.GetPointData().SetScalars(arr)
            mapper.SetColorModeToDirectScalars()
            mapper.ScalarVisibilityOn()
        elif scalars is not None:
            S = np.asarray(scalars, float).ravel()
            if S.shape[0] != P.shape[0]:
                raise ValueError(f"scalars: expected {P.shape[0]} values (one per point), got {S.shape[0]}")
            lo, hi = scale if scale is not None else _finite_range(S)
            arr = numpy_to_vtk(np.ascontiguousarray(S), deep=True)
            arr.SetName("value")
            pd.GetPointData().SetScalars(arr)
            mapper.SetLookupTable(_lut(cmap, lo, hi, stripes))
            mapper.SetScalarRange(lo, hi if hi > lo else lo + 1.0)
            mapper.UseLookupTableScalarRangeOn()
            mapper.InterpolateScalarsBeforeMappingOn()
            mapper.ScalarVisibilityOn()
        else:
            mapper.ScalarVisibilityOff()
        actor = vtkActor()
        actor.SetMapper(mapper)
        prop = actor.GetProperty()
        prop.SetInterpolationToPhong()
        prop.SetOpacity(opacity)
        prop.SetSpecular(specular)
        prop.SetSpecularPower(30.0)
        prop.SetDiffuse(0.8)
        prop.SetAmbient(0.25)
        if colors is None and scalars is None:
            prop.SetColor(*COLORMAPS["grey"][0])
        if cmap == "stripes":  # reflection lines: no specular highlight over the stripes
            prop.SetSpecular(0.0)
            prop.SetAmbient(0.6)
            prop.SetDiffuse(0.4)
        if shader is not None:
            if shader not in PIXEL_SHADERS:
                raise ValueError(f"shader: expected one of {', '.join(PIXEL_SHADERS)}, got {shader!r}")
            if normals is None:
                raise ValueError("shader: per-pixel stripes need normals")
            mapper.ScalarVisibilityOff()
            code = PIXEL_SHADERS[shader].replace("PAIRS", f"{float(max(1, stripes)):.1f}")
            actor.GetShaderProperty().AddFragmentShaderReplacement("//VTK::Light::Impl", True, code, False)
        if edges:
            prop.EdgeVisibilityOn()
            prop.SetEdgeColor(0.3, 0.3, 0.3)
        self._renderer.AddActor(actor)
        self._bounds.append(_extent(P[np.all(np.isfinite(P), axis=1)]))

    def add_lines(self, polylines: Sequence[np.ndarray], *, color: tuple[float, float, float] = (0.0, 0.0, 0.0),
                  width: float = 2.0, opacity: float = 1.0) -> None:
        """Add polylines, each ``(k, 3)`` with ``k >= 2`` (shorter ones are skipped)."""
        from vtkmodules.vtkRenderingCore import vtkActor, vtkPolyDataMapper

        lines = [np.asarray(p, float) for p in polylines]
        lines = [p[np.all(np.isfinite(p), axis=1)] for p in lines if p.ndim == 2 and p.shape[1] == 3]
        lines = [p for p in lines if len(p) >= 2]
        if not lines:
            return
        P = np.concatenate(lines)
        starts = np.concatenate([[0], np.cumsum([len(p) for p in lines])[:-1]])
        cells = [np.arange(s, s + len(p)) for s, p in zip(starts, lines)]
        mapper = vtkPolyDataMapper()
        mapper.SetInputData(polydata(P, cells, "lines"))
        # lines on a surface (edges, sections) are pulled towards the eye so the surface never hides them
        mapper.SetRelativeCoincidentTopologyLineOffsetParameters(-2.0, -2000.0)
        actor = vtkActor()
        actor.SetMapper(mapper)
        prop = actor.GetProperty()
        prop.SetColor(*color)
        prop.SetLineWidth(width)
        prop.RenderLinesAsTubesOn()  # offscreen (EGL) wide lines are honoured only this way: else 1 px
        prop.SetOpacity(opacity)
        prop.LightingOff()
        self._renderer.AddActor(actor)
        self._bounds.append(_extent(P))

    def add_points(self, points: np.ndarray, *, color: tuple[float, float, float] = (0.9, 0.1, 0.1),
                   size: float = 9.0) -> None:
        """Add points ``(n, 3)`` drawn as round sprites of ``size`` pixels (flags, inflections)."""
        from vtkmodules.vtkRenderingCore import vtkActor, vtkPolyDataMapper

        P = np.asarray(points, float).reshape(-1, 3)
        P = P[np.all(np.isfinite(P), axis=1)]
        if not len(P):
            return
        pd = polydata(P, [np.array([k]) for k in range(len(P))], "lines")
        from vtkmodules.vtkCommonDataModel import vtkCellArray

        verts = vtkCellArray()
        for k in range(len(P)):
            verts.InsertNextCell(1)
            verts.InsertCellPoint(k)
        pd.SetLines(vtkCellArray())
        pd.SetVerts(verts)
        mapper = vtkPolyDataMapper()
        mapper.SetInputData(pd)
        actor = vtkActor()
        actor.SetMapper(mapper)
        prop = actor.GetProperty()
        prop.SetColor(*color)
        prop.SetPointSize(size)
        prop.RenderPointsAsSpheresOn()
        self._renderer.AddActor(actor)
        self._bounds.append(_extent(P))  # framed like every other prop (VTK's ResetCamera counted them)

    def add_hedgehog(self, points: np.ndarray, vectors: np.ndarray, *, length: float | None = None,
                     color: tuple[float, float, float] = (0.1, 0.1, 0.6), width: float = 1.5) -> None:
        """Add line segments from ``points (n, 3)`` along ``vectors (n, 3)`` (normals, comb teeth).

        ``length`` scales unit directions (default: the vectors as given).
        """
        P = np.asarray(points, float).reshape(-1, 3)
        V = np.asarray(vectors, float).reshape(-1, 3)
        if length is not None:
            with np.errstate(all="ignore"):
                V = V / np.linalg.norm(V, axis=1, keepdims=True) * length
        ok = np.all(np.isfinite(P), axis=1) & np.all(np.isfinite(V), axis=1)
        segs = np.stack([P[ok], P[ok] + V[ok]], axis=1)
        self.add_lines(list(segs), color=color, width=width)

    def frame(self, points: np.ndarray) -> None:
        """Frame ``points (n, 3)`` too (nothing is drawn): panels that share a box compare at one scale."""
        P = np.asarray(points, float).reshape(-1, 3)
        P = P[np.all(np.isfinite(P), axis=1)]
        if len(P):
            self._bounds.append(_extent(P))

    def set_legend(self, title: str, lo: float, hi: float, *, cmap: str = "diverging", stripes: int = 1,
                   labels: int = 5) -> None:
        """Show a scalar bar for ``cmap`` on ``[lo, hi]`` with ``title`` (units included by the caller)."""
        self._legend = _Legend(title, float(lo), float(hi), cmap, stripes, labels)

    def set_title(self, text: str) -> None:
        """A line of text at the top left of the picture."""
        self._title = text

    def set_lights(self, lights: Sequence[tuple[tuple[float, float, float], float]] | None) -> None:
        """Directional lights ``[(direction towards the light, intensity), ...]`` fixed to the camera;
        ``None`` keeps VTK's headlight kit."""
        self._lights = None if lights is None else [(tuple(d), float(i)) for d, i in lights]

    # ------------------------------------------------------------------------------ output
    def render_array(self, *, size: tuple[int, int] = (800, 600), camera: str | Sequence[float] = "iso",
                     zoom: float = 1.0, up: Sequence[float] | None = None) -> np.ndarray:
        """Render and return the image as ``(height, width, 3)`` uint8 (row 0 at the top). ``up``:
        the direction shown upwards with a ``camera`` direction (:func:`~.cameras.fit_camera`)."""
        width, height = int(size[0]), int(size[1])
        if width < 16 or height < 16:
            raise ValueError(f"size: expected at least 16 x 16 pixels, got {size!r}")
        win = window(width, height)
        try:
            win.AddRenderer(self._renderer)
            self._decorate()
            self._place_camera(camera, zoom, width / height, up)
            win.Render()
            arr, _ = read_pixels(win, width, height)
        finally:
            win.RemoveRenderer(self._renderer)
        return arr

    def render(self, path: str | Path, *, size: tuple[int, int] = (800, 600), camera: str | Sequence[float] = "iso",
               zoom: float = 1.0) -> Path:
        """Render to a PNG file at ``path`` (written atomically, zlib level 1: fast); returns the path."""
        from .png import write_png_file

        return write_png_file(path, self.render_array(size=size, camera=camera, zoom=zoom), level=1)

    # ------------------------------------------------------------------------------ steps
    def _decorate(self) -> None:
        """Legend, title and lights (once per render)."""
        from vtkmodules.vtkRenderingAnnotation import vtkScalarBarActor
        from vtkmodules.vtkRenderingCore import vtkActor2D, vtkLight, vtkTextActor

        for a in list(self._renderer.GetViewProps()):  # type: ignore[call-overload]  # iterable; its stub lacks __iter__
            if isinstance(a, (vtkScalarBarActor, vtkTextActor)) or type(a) is vtkActor2D:
                self._renderer.RemoveViewProp(a)
        if self._legend is not None:
            lg = self._legend
            bar = vtkScalarBarActor()
            bar.SetLookupTable(_lut(lg.cmap, lg.lo, lg.hi, lg.stripes))
            bar.SetTitle(lg.title)
            bar.SetNumberOfLabels(lg.labels if lg.cmap != "stripes" else 0)
            bar.SetLabelFormat("%-#8.3g")
            bar.SetPosition(0.84, 0.1)
            bar.SetWidth(0.12)
            bar.SetHeight(0.8)
            bar.SetBarRatio(0.3)
            bar.UnconstrainedFontSizeOn()
            for tp in (bar.GetTitleTextProperty(), bar.GetLabelTextProperty()):
                tp.SetColor(0.1, 0.1, 0.1)
                tp.ShadowOff()
                tp.BoldOff()
                tp.ItalicOff()
                tp.SetFontSize(14)
            bar.GetTitleTextProperty().SetFontSize(15)
            self._renderer.AddViewProp(bar)
        if self._title:
            text = vtkTextActor()
            text.SetInput(self._title)
            text.GetTextProperty().SetFontSize(16)
            text.GetTextProperty().SetColor(0.1, 0.1, 0.1)
            text.SetDisplayPosition(10, 10)
            self._renderer.AddViewProp(text)
        if self._lights is not None:
            self._renderer.RemoveAllLights()
            for direction, intensity in self._lights:
                light = vtkLight()
                light.SetLightTypeToCameraLight()
                light.SetPosition(*direction)
                light.SetFocalPoint(0.0, 0.0, 0.0)
                light.SetIntensity(intensity)
                self._renderer.AddLight(light)

    def _place_camera(self, camera: str | Sequence[float], zoom: float, aspect: float = 4 / 3,
                      up: Sequence[float] | None = None) -> None:
        """Look at the bounding box from the preset direction and zoom so its eight corners fill the
        frame (the legend's strip on the right kept free): :func:`~.cameras.fit_camera` with
        ``keep_distance``."""
        from occsurf.algorithms.errors import InvalidGeometryError

        if isinstance(camera, str) and camera not in VIEWS:
            raise ValueError(f"camera: expected one of {', '.join(VIEWS)} or a direction, got {camera!r}")
        pts = np.concatenate(self._bounds) if self._bounds else np.zeros((1, 3))
        legend = self._legend is not None
        try:
            cam = fit_camera(camera, pts.min(axis=0), pts.max(axis=0), aspect, keep_distance=True,
                             width_share=0.80 if legend else 0.94,  # the scalar bar takes the right ~16 %
                             shift_left=legend, zoom=zoom, up=None if isinstance(camera, str) else up)
        except InvalidGeometryError as err:
            raise ValueError(str(err)) from None
        apply_camera(self._renderer, cam)


def _finite_range(values: np.ndarray) -> tuple[float, float]:
    v = values[np.isfinite(values)]
    if not len(v):
        return 0.0, 1.0
    lo, hi = float(v.min()), float(v.max())
    return (lo, hi) if hi > lo else (lo - 0.5, lo + 0.5)


def _vertex_normals(P: np.ndarray, T: np.ndarray, at: np.ndarray | None = None) -> np.ndarray:
    """Area-weighted vertex normals of a triangle mesh ``(n, 3)`` (fallback for degenerate points).

    ``at``: a mask of the vertices wanted (the degenerate ones); then only the triangles touching
    them are summed, and only the rows of ``at`` are meaningful. Each wanted row is the same sum,
    in the same order, as over the whole mesh: the triangles' normals are added vertex by vertex
    in triangle order, first corner, then second, then third (``np.bincount`` adds its weights in
    input order, as ``np.add.at`` did), so the rows come out bit for bit alike (the bearing's
    model pictures summed 3.6 million triangles for a few degenerate vertices, 35 ms a picture)."""
    if at is not None:
        T = T[np.asarray(at, bool)[T].any(axis=1)]
    fn = np.cross(P[T[:, 1]] - P[T[:, 0]], P[T[:, 2]] - P[T[:, 0]])
    corners = T.T.ravel()  # every triangle's first corner, then the second ones, then the third
    N = np.stack([np.bincount(corners, weights=np.tile(fn[:, c], 3), minlength=len(P)) for c in range(3)], axis=1)
    length = np.linalg.norm(N, axis=1, keepdims=True)
    with np.errstate(all="ignore"):
        N = np.where(length > 0, N / length, np.array([0.0, 0.0, 1.0]))
    return N
