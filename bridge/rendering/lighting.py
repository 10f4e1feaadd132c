"""Per-pixel images under Warn's lights (course ch. 10): a VTK fragment shader, offscreen.

The lighting model is :mod:`occsurf.algorithms.lighting` (the NumPy reference, formulas in
:mod:`occsurf.algorithms.lighting.shading`). This module writes the same formulas as GLSL into
VTK's fragment shader (``vtkShaderProperty``: the ``//VTK::Light::Impl`` block of
``vtkOpenGLPolyDataMapper`` is replaced), so every pixel is shaded at its own interpolated world
position and normal, in one render pass:

* world position ``P`` = inverse view matrix x VTK's ``vertexVC``; normal ``N`` = the rotation of
  the inverse view matrix x the interpolated vertex normal (VTK's back-face flip undone),
  normalised per pixel; eye = the camera position;
* every light, the material and the ambient light are baked into the shader as constants (a new
  shader per setup and camera: compiling costs a few ms);
* the result is written unclipped to the 8-bit colour buffer (clipped by OpenGL, as
  ``numpy.clip(shade(...), 0, 1)``).

Why a shader and not NumPy over rasterised buffers: measured on this 2-core machine (Mesa
llvmpipe, no GPU, under load), the NumPy design needs the world normals in float buffers
(``vtkValuePass``: one pass per component) plus a pass for the depth, 0.6-0.9 s at 1600 x 1200
for a 100k-triangle mesh before any shading, then :func:`~occsurf.algorithms.lighting.shade` on
the covered pixels; one shaded pass of the same mesh takes 0.19 s (0.8 s with 4x multisampling).
``benchmarks/bench_lighting.py`` times both.

Cameras (:class:`Camera`): a named view of :data:`VIEWS` (``top`` looks down -z at the whole
model) framed on the model's bounding box, or an explicit position / target / up. The window
cache, the cameras and the pixel read-back are those of :mod:`.vtk_scene` (one offscreen
window and camera code path for every VTK picture).
Entry points: :func:`render_lit` (a mesh -> :class:`LitImage` with colours, depth and camera),
:func:`render_surfaces_lit` (B-spline surfaces), :func:`render_model_lit` (an imported STEP/IGES
model, through :func:`mesh_of_model`), :func:`write_png` (atomic), :func:`pixel_world_points`
(the depth buffer back to world points, for comparisons with the reference).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from occsurf.algorithms.errors import InvalidGeometryError
from occsurf.algorithms.lighting import LightingSetup, WarnLight

from .cameras import VIEW_ANGLE, VIEWS, Camera, apply_camera, fit_camera, vtk_matrix
from .vtk_scene import _vertex_normals, polydata, read_pixels, render_available
from .vtk_scene import window as _window

if TYPE_CHECKING:
    from occsurf.algorithms import BSplineSurface

    from ..exchange.step_iges import ImportedModel

__all__ = ["VIEWS", "Camera", "LitImage", "camera_for_view", "render_lit", "render_model_lit", "mesh_of_model",
           "write_png", "pixel_world_points", "render_surfaces_lit", "render_available", "VIEW_ANGLE"]

#: Background colour (RGB in [0, 1]): Warn's studio pictures are on black; a dark grey keeps the
#: silhouette of unlit parts visible.
BACKGROUND = (0.08, 0.08, 0.09)


def camera_for_view(view: str, lo: Sequence[float], hi: Sequence[float], aspect: float = 4 / 3,
                    *, margin: float = 1.06) -> Camera:
    """The camera of a named view (:data:`VIEWS`) that shows the whole box ``[lo, hi]``.

    The camera looks at the box's centre from the view's direction, at the smallest distance at
    which all eight corners of the box lie inside the picture (both openings divided by
    ``margin``): a long part fills the frame instead of a fraction of its bounding sphere.
    (:func:`~occsurf.bridge.rendering.cameras.fit_camera`, the framing of every VTK picture.)
    """
    if not isinstance(view, str) or view not in VIEWS:
        raise InvalidGeometryError(f"view: expected one of {', '.join(VIEWS)}, got {view!r}")
    return fit_camera(view, lo, hi, aspect, margin=margin)


@dataclass
class LitImage:
    """A rendered picture.

    Attributes
    ----------
    rgb : ndarray, shape (height, width, 3), uint8
        Row 0 at the top.
    depth : ndarray, shape (height, width), float32
        OpenGL depth in [0, 1] (1: background), same orientation.
    camera : Camera
    matrix : ndarray, shape (4, 4)
        World -> normalised device coordinates (VTK's composite projection at this aspect).
    seconds : float
        Wall-clock time of the render and read-back.
    """

    rgb: np.ndarray
    depth: np.ndarray
    camera: Camera
    matrix: np.ndarray
    seconds: float = 0.0

    @property
    def covered(self) -> np.ndarray:
        """``(height, width)`` bool: pixels showing the model."""
        return self.depth < 1.0


def pixel_world_points(image: LitImage) -> np.ndarray:
    """World positions ``(height, width, 3)`` of the pixel centres from the depth buffer (NaN on
    the background): the inverse of the projection used for the picture."""
    h, w = image.depth.shape
    ys, xs = np.nonzero(image.covered)
    ndc = ((xs + 0.5) * (2.0 / w) - 1, 1 - (ys + 0.5) * (2.0 / h), image.depth[ys, xs].astype(np.float64) * 2.0 - 1)
    inv = np.linalg.inv(image.matrix)
    # the 4 x 4 product written out: a BLAS matmul of (n, 4) by (4, 4) stalls on a busy machine
    hom = [inv[k, 0] * ndc[0] + inv[k, 1] * ndc[1] + inv[k, 2] * ndc[2] + inv[k, 3] for k in range(4)]
    pts = np.full((h, w, 3), np.nan)
    pts[ys, xs] = np.stack([hom[0] / hom[3], hom[1] / hom[3], hom[2] / hom[3]], axis=-1)
    return pts


# ---------------------------------------------------------------------------------------- GLSL
def _f(x: float) -> str:
    return f"{float(x):.9e}"


def _v3(v: Sequence[float] | np.ndarray) -> str:
    return f"vec3({_f(v[0])}, {_f(v[1])}, {_f(v[2])})"


_BIG = 3.0e38  # an open flap side (float32 max is 3.4e38)

_FUNCTIONS = """
float warnPow(float x, float s) { return s == 0.0 ? 1.0 : pow(max(x, 0.0), s); }
float warnCone(float cosg, float theta, float delta) {
  if (theta <= 0.0) return 1.0;
  if (delta <= 0.0) return cosg >= cos(theta) ? 1.0 : 0.0;
  float t = clamp((theta - acos(clamp(cosg, -1.0, 1.0))) / delta, 0.0, 1.0);
  return t * t * (3.0 - 2.0 * t);
}
float warnFlaps(vec3 rel, mat3 frameT, vec3 lo, vec3 hi, float e) {
  vec3 q = frameT * rel;
  if (e <= 0.0) return all(greaterThanEqual(q, lo)) && all(lessThanEqual(q, hi)) ? 1.0 : 0.0;
  vec3 a = clamp((q - lo) / e, 0.0, 1.0);
  vec3 b = clamp((hi - q) / e, 0.0, 1.0);
  a = a * a * (3.0 - 2.0 * a);
  b = b * b * (3.0 - 2.0 * b);
  return a.x * a.y * a.z * b.x * b.y * b.z;
}
vec3 warnLight(vec3 P, vec3 N, vec3 V, float NV, bool directional, vec3 pos, vec3 dir, mat3 frameT,
               vec3 lo, vec3 hi, float flapEdge, vec3 rgb, float conc, float theta, float delta, float fallK, float d0,
               vec3 kd, vec3 ks, float shin) {
  vec3 L; float factor = 1.0; float dist = 0.0;
  if (directional) { L = -dir; }
  else {
    vec3 toL = pos - P; dist = length(toL);
    if (dist <= 0.0) return vec3(0.0);
    L = toL / dist;
    float cosg = -dot(L, dir);
    if (conc > 0.0) factor *= warnPow(cosg, conc);
    factor *= warnCone(cosg, theta, delta);
    if (fallK > 0.0) factor *= pow(d0 / max(dist, d0), fallK);
  }
  factor *= warnFlaps(P - (directional ? vec3(0.0) : pos), frameT, lo, hi, flapEdge);
  float NL = dot(N, L);
  if (NL <= 0.0 || factor <= 0.0) return vec3(0.0);
  float RV = max(2.0 * NL * NV - dot(L, V), 0.0);
  return factor * rgb * (kd * NL + ks * warnPow(RV, shin));
}
"""


def _light_call(light: WarnLight) -> str:
    """One GLSL call of ``warnLight`` with the light's constants."""
    F = light.frame
    lo = [max(-_BIG, b[0]) for b in light.flaps]
    hi = [min(_BIG, b[1]) for b in light.flaps]
    theta = math.radians(light.cone_angle_deg) if light.cone_angle_deg is not None else 0.0
    fall = {"none": 0.0, "inverse": 1.0, "inverse_square": 2.0}[light.falloff]
    pos = light.origin
    # mat3 is column-major: columns = the frame's rows, transposed, so frameT * rel = F @ rel.
    frameT = f"transpose(mat3({_v3(F[0])}, {_v3(F[1])}, {_v3(F[2])}))"
    return (f"warnLight(P, N, V, NV, {'true' if light.position is None else 'false'}, {_v3(pos)}, "
            f"{_v3(light.direction)}, {frameT}, {_v3(lo)}, {_v3(hi)}, {_f(light.flap_edge)}, {_v3(light.rgb)}, "
            f"{_f(light.concentration)}, "
            f"{_f(theta)}, {_f(math.radians(light.cone_edge_deg))}, {_f(fall)}, "
            f"{_f(light.falloff_distance or 1.0)}, kd, ks, shin)")


def _shader_impl(setup: LightingSetup, inv_view: np.ndarray, eye: Sequence[float]) -> str:
    """The ``//VTK::Light::Impl`` replacement: Warn's model in world coordinates."""
    m = setup.material
    kd = m.diffuse * np.asarray(m.color)
    ks = m.specular * np.asarray(m.specular_color)
    amb = np.asarray(setup.ambient) * np.asarray(m.color)
    cols = ", ".join(_f(inv_view[r, c]) for c in range(4) for r in range(4))  # column-major
    lines = [
        f"  mat4 warnInvView = mat4({cols});",
        "  vec3 P = (warnInvView * vec4(vertexVC.xyz, 1.0)).xyz;",
        # VTK's Normal::Impl turned the normal of back-facing triangles (its local normalVCVSOutput);
        # turn it back: the mesh's own normal, as the reference gets it (tests/bridge check both sides)
        "  vec3 N = normalize(mat3(warnInvView) * (gl_FrontFacing ? normalVCVSOutput : -normalVCVSOutput));",
        f"  vec3 V = normalize({_v3(eye)} - P);",
        "  float NV = dot(N, V);",
    ]
    if setup.two_sided:
        lines.append("  if (NV < 0.0) { N = -N; NV = -NV; }")
    lines += [f"  vec3 kd = {_v3(kd)};", f"  vec3 ks = {_v3(ks)};", f"  float shin = {_f(m.shininess)};",
              f"  vec3 warnColor = {_v3(amb)};"]
    lines += [f"  warnColor += {_light_call(light)};" for light in setup.lights]
    lines.append("  gl_FragData[0] = vec4(warnColor, opacity);")
    return "\n".join(lines) + "\n"


# ---------------------------------------------------------------------------------------- VTK
def _actor(points: np.ndarray, triangles: np.ndarray, normals: np.ndarray) -> Any:
    """A VTK actor of the mesh with per-vertex normals."""
    from vtkmodules.util.numpy_support import numpy_to_vtk
    from vtkmodules.vtkRenderingCore import vtkActor, vtkPolyDataMapper

    pd = polydata(points, triangles, "triangles")
    pd.GetPointData().SetNormals(numpy_to_vtk(np.ascontiguousarray(normals, np.float32), deep=True))
    mapper = vtkPolyDataMapper()
    mapper.SetInputData(pd)
    mapper.ScalarVisibilityOff()
    actor = vtkActor()
    actor.SetMapper(mapper)
    prop = actor.GetProperty()
    prop.SetInterpolationToPhong()
    prop.LightingOn()
    prop.BackfaceCullingOff()
    return actor


def _check_mesh(points: Any, triangles: Any, normals: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    P = np.asarray(points, float)
    T = np.asarray(triangles)
    if P.ndim != 2 or P.shape[1] != 3 or not len(P):
        raise InvalidGeometryError(f"points: expected shape (n, 3) with n > 0, got {P.shape}")
    if T.ndim != 2 or T.shape[1] != 3 or not len(T) or not np.issubdtype(T.dtype, np.integer):
        raise InvalidGeometryError(f"triangles: expected integer indices of shape (m, 3), m > 0, got {T.shape} {T.dtype}")
    if T.min() < 0 or T.max() >= len(P):
        raise InvalidGeometryError(f"triangles: indices must lie in [0, {len(P) - 1}], got [{T.min()}, {T.max()}]")
    if not np.all(np.isfinite(P)):
        raise InvalidGeometryError("points: expected finite coordinates")
    if normals is None:
        N = _vertex_normals(P, T)
    else:
        N = np.array(normals, float)
        if N.shape != P.shape:
            raise InvalidGeometryError(f"normals: expected shape {P.shape} (one per point), got {N.shape}")
        bad = ~np.all(np.isfinite(N), axis=1) | (np.linalg.norm(np.nan_to_num(N), axis=1) == 0)
        if bad.any():  # degenerate points (a sphere's pole): the mesh's own normal there
            N[bad] = _vertex_normals(P, T, bad)[bad]
    return P, T.astype(np.int64), N


def render_lit(points: np.ndarray, triangles: np.ndarray, setup: LightingSetup, *, normals: np.ndarray | None = None,
               size: tuple[int, int] = (1600, 1200), view: str = "iso", camera: Camera | None = None,
               background: Sequence[float] = BACKGROUND, samples: int = 4) -> LitImage:
    """Render a triangle mesh under ``setup``'s Warn lights, per pixel, offscreen.

    Parameters
    ----------
    points : ndarray, shape (n, 3)
    triangles : ndarray, shape (m, 3), int
    setup : LightingSetup
        Lights, ambient, material (:mod:`occsurf.algorithms.lighting`).
    normals : ndarray, shape (n, 3), optional
        Vertex normals (default: area-weighted from the triangles; NaN rows are replaced so).
    size : (int, int)
        Width and height in pixels, each 16 .. 16384.
    view : str
        A key of :data:`VIEWS`, framed on the mesh's bounding box; ignored when ``camera`` is given.
    camera : Camera, optional
        An explicit camera.
    background : (3,) floats
    samples : int
        Multisampling (antialiased edges): 0 (off) .. 16. On a CPU renderer (Mesa llvmpipe) 4
        samples cost about 4x a render without (1600 x 1200, 100k triangles: ~0.25 s -> ~1 s under
        load); interior pixels are shaded once either way and do not change.

    Returns
    -------
    LitImage
    """
    import time

    if not isinstance(setup, LightingSetup):
        raise InvalidGeometryError(f"setup: expected a LightingSetup, got {type(setup).__name__}")
    width, height = _size(size)
    if isinstance(samples, bool) or not isinstance(samples, int) or not 0 <= samples <= 16:
        raise InvalidGeometryError(f"samples: expected an integer from 0 to 16, got {samples!r}")
    P, T, N = _check_mesh(points, triangles, normals)
    if camera is None:
        camera = camera_for_view(view, P.min(axis=0), P.max(axis=0), width / height)
    t0 = time.perf_counter()
    rgb, depth, matrix = _draw(P, T, N, setup, camera, (width, height, samples), background)
    return LitImage(rgb=rgb, depth=depth, camera=camera, matrix=matrix, seconds=time.perf_counter() - t0)


def _size(size: Sequence[int]) -> tuple[int, int]:
    try:
        width, height = (int(v) for v in size)
    except (TypeError, ValueError):
        raise InvalidGeometryError(f"size: expected (width, height) in pixels, got {size!r}") from None
    if not (16 <= width <= 16384 and 16 <= height <= 16384):
        raise InvalidGeometryError(f"size: expected 16 .. 16384 pixels each way, got {width} x {height}")
    return width, height


def _draw(P: np.ndarray, T: np.ndarray, N: np.ndarray, setup: LightingSetup, camera: Camera,
          window: tuple[int, int, int], background: Sequence[float]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One shaded pass; returns ``(rgb (h, w, 3) uint8, depth (h, w) float32, world->NDC (4, 4))``."""
    width, height, _ = window
    win = _window(*window)  # first: loads the OpenGL factories (vtkShaderProperty's override)
    from vtkmodules.vtkRenderingCore import vtkLight, vtkRenderer

    renderer = vtkRenderer()
    renderer.SetBackground(*background)
    renderer.AutomaticLightCreationOff()
    light = vtkLight()  # a positional scene light makes VTK declare vertexVC; its effect is replaced
    light.SetPositional(True)
    light.SetLightTypeToSceneLight()
    renderer.AddLight(light)
    actor = _actor(P, T, N)
    renderer.AddActor(actor)
    cam = apply_camera(renderer, camera, _padded_bounds(P))
    view = vtk_matrix(cam.GetViewTransformMatrix())
    actor.GetShaderProperty().AddFragmentShaderReplacement("//VTK::Light::Dec", True,
                                                           "//VTK::Light::Dec\n" + _FUNCTIONS, False)
    actor.GetShaderProperty().AddFragmentShaderReplacement(
        "//VTK::Light::Impl", True, _shader_impl(setup, np.linalg.inv(view), camera.position), False)
    win.AddRenderer(renderer)
    try:
        win.Render()
        rgb, depth = read_pixels(win, width, height, depth=True)
        matrix = vtk_matrix(cam.GetCompositeProjectionTransformMatrix(width / height, -1, 1))
    finally:
        win.RemoveRenderer(renderer)
    return rgb, depth, matrix  # type: ignore[return-value]


def _padded_bounds(P: np.ndarray) -> list[float]:
    lo, hi = P.min(axis=0), P.max(axis=0)
    pad = 0.01 * max(float(np.linalg.norm(hi - lo)), 1e-9)
    return [lo[0] - pad, hi[0] + pad, lo[1] - pad, hi[1] + pad, lo[2] - pad, hi[2] + pad]


_matrix = vtk_matrix  # the name benchmarks/bench_lighting.py and older callers use


# ---------------------------------------------------------------------------------------- models
def mesh_of_model(model: ImportedModel) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One triangle mesh ``(points (n, 3), triangles (m, 3), normals (n, 3))`` of every face of an
    imported model: OCC's trimmed triangulation with positions and normals evaluated on our
    converted surfaces (:mod:`occsurf.bridge.rendering.tessellation`). ``model`` may also be any
    build123d / cadquery / OCC shape (:func:`~occsurf.bridge.exchange.object_import.as_model`)."""
    from ..exchange.object_import import as_model
    from .tessellation import mesh_face, mesh_model

    model = as_model(model)
    size = mesh_model(model)
    pts, tris, nrms = [], [], []
    offset = 0
    for face in model.faces:
        if face.surface is None:
            continue
        mesh = mesh_face(face, size)
        pts.append(mesh.points)
        nrms.append(mesh.normals)
        tris.append(mesh.triangles + offset)
        offset += mesh.n_vertices
    if not pts:
        raise InvalidGeometryError("model: no face could be converted and meshed")
    return np.concatenate(pts), np.concatenate(tris), np.concatenate(nrms)


def render_surfaces_lit(surfaces: BSplineSurface | Sequence[BSplineSurface], setup: LightingSetup, *, resolution: int = 161, **kw: Any) -> LitImage:
    """:func:`render_lit` of one or several :class:`~occsurf.algorithms.BSplineSurface` (each on its
    whole parameter box, a ``resolution x resolution`` grid of exact points and normals)."""
    from occsurf.algorithms import BSplineSurface

    from .tessellation import grid_mesh

    items = [surfaces] if isinstance(surfaces, BSplineSurface) else list(surfaces)
    if not items or not all(isinstance(s, BSplineSurface) for s in items):
        raise InvalidGeometryError("surfaces: expected a BSplineSurface or a non-empty list of them")
    if isinstance(resolution, bool) or not isinstance(resolution, int) or not 2 <= resolution <= 2049:
        raise InvalidGeometryError(f"resolution: expected an integer from 2 to 2049, got {resolution!r}")
    meshes = [grid_mesh(s, resolution) for s in items]
    offsets = np.cumsum([0] + [m.n_vertices for m in meshes[:-1]])
    P = np.concatenate([m.points for m in meshes])
    T = np.concatenate([m.triangles + o for m, o in zip(meshes, offsets)])
    N = np.concatenate([m.normals for m in meshes])
    return render_lit(P, T, setup, normals=N, **kw)


def render_model_lit(model: ImportedModel, setup: LightingSetup, **kw: Any) -> LitImage:
    """:func:`render_lit` of :func:`mesh_of_model` (keywords as :func:`render_lit`)."""
    P, T, N = mesh_of_model(model)
    return render_lit(P, T, setup, normals=N, **kw)


def write_png(path: str | Path, image: LitImage | np.ndarray) -> Path:
    """Write the picture as a PNG, atomically (:func:`.png.write_png_file`)."""
    from .png import write_png_file

    return write_png_file(path, image.rgb if isinstance(image, LitImage) else np.asarray(image))
