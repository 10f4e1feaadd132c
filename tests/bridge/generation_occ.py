"""OpenCascade's own constructions of the surfaces of :mod:`occsurf.algorithms.construction.generation` and
:mod:`occsurf.algorithms.construction.sweeping`, and the distance between two surfaces by point projection.

Used by ``tests/bridge/test_generation_vs_occ.py``, ``benchmarks/bench_generation.py`` and the
demo. Each builder checks ``IsDone()`` and re-raises OCC failures as :class:`KernelError`.

* revolution: ``Geom_SurfaceOfRevolution`` and ``BRepPrimAPI_MakeRevol`` (+ optionally
  ``BRepBuilderAPI_NurbsConvert``);
* extrusion: ``Geom_SurfaceOfLinearExtrusion`` (trimmed) and ``BRepPrimAPI_MakePrism``;
* ruled: ``GeomFill::Surface`` and ``BRepFill::Face``;
* sweeps: ``BRepOffsetAPI_MakePipeShell`` (corrected Frenet, Frenet or a fixed trihedron, with a
  ``Law_Interpol`` scaling law);
* :func:`max_distance`: our dense sample points projected onto OCC's face
  (``GeomAPI_ProjectPointOnSurf`` inside the face's UV bounds) and OCC's face points projected onto
  our surface.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from OCP.BRep import BRep_Tool
from OCP.BRepBuilderAPI import (
    BRepBuilderAPI_GTransform,
    BRepBuilderAPI_MakeFace,
    BRepBuilderAPI_MakeVertex,
    BRepBuilderAPI_MakeWire,
    BRepBuilderAPI_NurbsConvert,
)
from OCP.BRepExtrema import BRepExtrema_DistShapeShape
from OCP.BRepFill import BRepFill
from OCP.BRepOffsetAPI import BRepOffsetAPI_MakePipeShell
from OCP.BRepPrimAPI import BRepPrimAPI_MakePrism, BRepPrimAPI_MakeRevol
from OCP.BRepTools import BRepTools
from OCP.Geom import (
    Geom_RectangularTrimmedSurface,
    Geom_Surface,
    Geom_SurfaceOfLinearExtrusion,
    Geom_SurfaceOfRevolution,
)
from OCP.GeomAPI import GeomAPI_ProjectPointOnSurf
from OCP.GeomFill import GeomFill
from OCP.gp import gp_Ax1, gp_Ax2, gp_Dir, gp_GTrsf, gp_Mat, gp_Pnt, gp_Pnt2d, gp_Vec, gp_XYZ
from OCP.Law import Law_Interpol
from OCP.ShapeAnalysis import ShapeAnalysis_Surface
from OCP.TColgp import TColgp_Array1OfPnt2d
from OCP.TopAbs import TopAbs_FACE
from OCP.TopExp import TopExp_Explorer
from OCP.TopoDS import TopoDS, TopoDS_Face, TopoDS_Shape

from occsurf.algorithms import BSplineCurve, BSplineSurface
from occsurf.algorithms.errors import KernelError
from occsurf.bridge import _occ
from occsurf.bridge.conversion.splines import make_edge, to_occ

__all__ = [
    "revolution_surface",
    "revolution_face",
    "extrusion_surface",
    "prism_face",
    "ruled_surface",
    "ruled_face",
    "pipe_shell_face",
    "stretched_revolution_face",
    "single_face",
    "nurbs_face",
    "max_distance",
]

Array = NDArray[np.float64]

#: Parameter grid (per direction) that seeds the local projections of :func:`max_distance`.
_SEED_GRID = 101
#: A local projection is accepted without a global search when it lands this close (relative to the
#: point's coordinates): the surfaces coincide there. Otherwise a converged local foot point may be
#: a stationary point of a folded surface that is not the nearest one (seen on a rational ruled
#: surface: a local foot at 2e-3 where the global one is at 6e-16), so the global search decides.
_NEGLIGIBLE = 1e-13


def _ax1(origin: ArrayLike, direction: ArrayLike) -> gp_Ax1:
    return gp_Ax1(gp_Pnt(*map(float, origin)), gp_Dir(*map(float, direction)))


def single_face(shape: TopoDS_Shape) -> TopoDS_Face:
    """The one face of ``shape`` (KernelError if it has none or several)."""
    ex = TopExp_Explorer(shape, TopAbs_FACE)
    faces = []
    while ex.More():
        faces.append(TopoDS.Face_s(ex.Current()))
        ex.Next()
    if len(faces) != 1:
        raise KernelError(f"expected one face from OCC, got {len(faces)}")
    return faces[0]


def nurbs_face(face: TopoDS_Face) -> TopoDS_Face:
    """``BRepBuilderAPI_NurbsConvert``: the face with its surface converted to a B-spline."""
    with _occ.kernel_errors("BRepBuilderAPI_NurbsConvert"):
        nc = BRepBuilderAPI_NurbsConvert(face, True)
        if not nc.IsDone():
            raise KernelError("BRepBuilderAPI_NurbsConvert failed")
        return single_face(nc.Shape())


# ---------------------------------------------------------------------------------- revolution
def revolution_surface(profile: BSplineCurve, origin: ArrayLike, direction: ArrayLike, angle: float) -> Geom_Surface:
    """``Geom_SurfaceOfRevolution`` trimmed to ``U in [0, angle]`` (U = angle, V = profile)."""
    with _occ.kernel_errors("Geom_SurfaceOfRevolution"):
        s = Geom_SurfaceOfRevolution(to_occ(profile), _ax1(origin, direction))
        a = float(angle)
        u0, u1 = (0.0, a) if a > 0 else (2 * np.pi + a, 2 * np.pi)
        return Geom_RectangularTrimmedSurface(s, u0, u1, *profile.domain)


def revolution_face(profile: BSplineCurve, origin: ArrayLike, direction: ArrayLike, angle: float) -> TopoDS_Face:
    """``BRepPrimAPI_MakeRevol`` of the profile edge."""
    with _occ.kernel_errors("BRepPrimAPI_MakeRevol"):
        mk = BRepPrimAPI_MakeRevol(make_edge(profile), _ax1(origin, direction), float(angle), True)
        mk.Build()
        if not mk.IsDone():
            raise KernelError("BRepPrimAPI_MakeRevol failed")
        return single_face(mk.Shape())


def stretched_revolution_face(profile: BSplineCurve, origin: ArrayLike, stretch_y: float) -> TopoDS_Face:
    """A full revolution about the z axis through ``origin``, then the affinity ``y -> origin_y +
    stretch_y (y - origin_y)`` (``BRepBuilderAPI_GTransform``): the swung surface of the profile
    with an ellipse trajectory of semi-axes ``(a, stretch_y a)``."""
    face = revolution_face(profile, origin, (0, 0, 1), 2 * np.pi)
    o = np.asarray(origin, float)
    with _occ.kernel_errors("BRepBuilderAPI_GTransform"):
        g = gp_GTrsf()
        g.SetVectorialPart(gp_Mat(1, 0, 0, 0, float(stretch_y), 0, 0, 0, 1))
        g.SetTranslationPart(gp_XYZ(0.0, float(o[1] * (1 - stretch_y)), 0.0))
        gt = BRepBuilderAPI_GTransform(face, g, True)
        if not gt.IsDone():
            raise KernelError("BRepBuilderAPI_GTransform failed")
        return single_face(gt.Shape())


# ---------------------------------------------------------------------------------- extrusion, ruled
def extrusion_surface(curve: BSplineCurve, vector: ArrayLike) -> Geom_Surface:
    """``Geom_SurfaceOfLinearExtrusion`` trimmed to ``V in [0, |d|]``."""
    d = np.asarray(vector, float)
    with _occ.kernel_errors("Geom_SurfaceOfLinearExtrusion"):
        s = Geom_SurfaceOfLinearExtrusion(to_occ(curve), gp_Dir(*d))
        return Geom_RectangularTrimmedSurface(s, *curve.domain, 0.0, float(np.linalg.norm(d)))


def prism_face(curve: BSplineCurve, vector: ArrayLike) -> TopoDS_Face:
    """``BRepPrimAPI_MakePrism`` of the curve edge."""
    with _occ.kernel_errors("BRepPrimAPI_MakePrism"):
        mk = BRepPrimAPI_MakePrism(make_edge(curve), gp_Vec(*map(float, vector)), True)
        mk.Build()
        if not mk.IsDone():
            raise KernelError("BRepPrimAPI_MakePrism failed")
        return single_face(mk.Shape())


def ruled_surface(c1: BSplineCurve, c2: BSplineCurve) -> Geom_Surface:
    """``GeomFill::Surface(c1, c2)``: the ruled surface (OCC makes the curves compatible itself)."""
    with _occ.kernel_errors("GeomFill::Surface"):
        return GeomFill.Surface_s(to_occ(c1), to_occ(c2))


def ruled_face(c1: BSplineCurve, c2: BSplineCurve) -> TopoDS_Face:
    """``BRepFill::Face(e1, e2)``: the ruled face between two edges."""
    with _occ.kernel_errors("BRepFill::Face"):
        return BRepFill.Face_s(make_edge(c1), make_edge(c2))


# ---------------------------------------------------------------------------------- sweeps
def _wire(curve: BSplineCurve):
    with _occ.kernel_errors("BRepBuilderAPI_MakeWire"):
        mw = BRepBuilderAPI_MakeWire(make_edge(curve))
        if not mw.IsDone():
            raise KernelError("BRepBuilderAPI_MakeWire failed")
        return mw.Wire()


def pipe_shell_face(
    profile: BSplineCurve,
    path: BSplineCurve,
    *,
    mode: str = "corrected_frenet",
    scale: Callable[[Array], Array] | None = None,
    law_samples: int = 65,
    tol: float = 1e-8,
) -> TopoDS_Face:
    """``BRepOffsetAPI_MakePipeShell``: the profile wire swept along the path wire.

    Parameters
    ----------
    mode : {"corrected_frenet", "frenet", "discrete", "fixed"}
        ``SetMode(False)`` (corrected Frenet, OCC's default; on a helix it drifts from the true
        rotation-minimising frame by 0.17 rad over 1.5 turns), ``SetMode(True)`` (Frenet),
        ``SetDiscreteMode()`` (``GeomFill_DiscreteTrihedron``, within 3e-3 rad of the RMF there),
        or ``SetMode(gp_Ax2)`` (a fixed trihedron: a translational sweep).
    scale : callable of t in [0, 1], optional
        A scaling law, handed to OCC as a ``Law_Interpol`` through ``law_samples`` values over the
        path's parameter (``SetLaw``).
    tol : float
        ``SetTolerance(tol, tol, 1e-4)``: OCC's approximation tolerance (3-D and boundary).
    """
    spine = _wire(path)
    section = _wire(profile)
    with _occ.kernel_errors("BRepOffsetAPI_MakePipeShell"):
        ms = BRepOffsetAPI_MakePipeShell(spine)
        if mode == "corrected_frenet":
            ms.SetMode(False)
        elif mode == "frenet":
            ms.SetMode(True)
        elif mode == "discrete":
            ms.SetDiscreteMode()
        elif mode == "fixed":
            ms.SetMode(gp_Ax2(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1)))
        else:
            raise ValueError(f"mode: expected 'corrected_frenet', 'frenet', 'discrete' or 'fixed', got {mode!r}")
        ms.SetTolerance(tol, tol, 1e-4)
        if scale is None:
            ms.Add(section, False, False)
        else:
            v0, v1 = path.domain
            t = np.linspace(0.0, 1.0, law_samples)
            vals = np.asarray(scale(t), float)
            pts = TColgp_Array1OfPnt2d(1, law_samples)
            for i, (a, b) in enumerate(zip(v0 + (v1 - v0) * t, vals)):
                pts.SetValue(i + 1, gp_Pnt2d(float(a), float(b)))
            law = Law_Interpol()
            law.Set(pts, False)
            ms.SetLaw(section, law, False, False)
        ms.Build()
        if not ms.IsDone():
            raise KernelError("BRepOffsetAPI_MakePipeShell failed")
        return single_face(ms.Shape())


# ---------------------------------------------------------------------------------- distance
def _as_bounded(occ: Any) -> tuple[Geom_Surface, tuple[float, float, float, float]]:
    if isinstance(occ, TopoDS_Face):
        return BRep_Tool.Surface_s(occ), tuple(BRepTools.UVBounds_s(occ))
    if isinstance(occ, Geom_Surface):
        return occ, tuple(occ.Bounds())
    if isinstance(occ, BSplineSurface):
        (a, b), (c, d) = occ.domain
        return to_occ(occ), (a, b, c, d)
    raise TypeError(f"expected a TopoDS_Face, Geom_Surface or BSplineSurface, got {type(occ).__name__}")


def _project_all(points: Array, surf: Geom_Surface, bounds: tuple[float, float, float, float],
                 accept: float = 0.0) -> Array:
    """Distance of each point to the bounded surface.

    A local projection (``ShapeAnalysis_Surface::NextValueOfUV``) seeded at the nearest point of a
    dense parameter grid, accepted if it lands on the point (:data:`_NEGLIGIBLE`) or within
    ``accept`` of it (a distance to an actual surface point, so an upper bound of the true one:
    accepting it never hides a larger deviation than ``accept``); else a global
    ``GeomAPI_ProjectPointOnSurf`` (one sampling of the surface reused for all points), and where
    that finds no orthogonal projection (a point on a degenerate edge such as a sphere's pole)
    ``BRepExtrema_DistShapeShape`` (vertex to face). The smallest of these distances to actual
    surface points is returned, so the result never underestimates.
    """
    from scipy.spatial import cKDTree

    n = _SEED_GRID
    u0, u1, v0, v1 = bounds
    us, vs = np.linspace(u0, u1, n), np.linspace(v0, v1, n)
    ref = _seed_grid(surf, bounds, n)
    dist0, idx = cKDTree(ref).query(points)
    sas = ShapeAnalysis_Surface(surf)
    out = np.empty(points.shape[0])
    proj = None
    face = None
    for k, p in enumerate(points):
        P = gp_Pnt(*map(float, p))
        i, j = divmod(int(idx[k]), n)
        uv = sas.NextValueOfUV(gp_Pnt2d(float(us[i]), float(vs[j])), P, 1e-13, -1.0)
        uu = min(max(uv.X(), u0), u1)
        vv = min(max(uv.Y(), v0), v1)
        d = P.Distance(surf.Value(uu, vv))
        if d <= max(accept, _NEGLIGIBLE * max(1.0, float(np.abs(p).max()))):
            out[k] = d
            continue
        if proj is None:
            proj = GeomAPI_ProjectPointOnSurf()
            proj.Init(surf, *bounds)
        proj.Perform(P)
        if proj.IsDone() and proj.NbPoints():
            out[k] = min(proj.LowerDistance(), d, dist0[k])
            continue
        if face is None:
            face = BRepBuilderAPI_MakeFace(surf, *bounds, 1e-7).Face()
        dss = BRepExtrema_DistShapeShape(BRepBuilderAPI_MakeVertex(P).Vertex(), face)
        out[k] = min(dss.Value(), d, dist0[k]) if dss.IsDone() else min(d, dist0[k])
    return out


def _params(lo: float, hi: float, n: int, knots: Array | None = None) -> Array:
    """``n`` uniform parameters on ``[lo, hi]``, plus points close to both ends (boundaries and
    seams: relative offsets 1e-6, 1e-4, 1e-2) and the distinct knots (segment joints) if given."""
    w = hi - lo
    near = np.array([1e-6, 1e-4, 1e-2]) * w
    extra = [near + lo, hi - near]
    if knots is not None:
        k = np.unique(knots[(knots >= lo) & (knots <= hi)])
        if k.shape[0] <= 2 * n:  # finely refined directions (sweeps) are covered by the uniform grid
            extra.append(k)
    return np.unique(np.concatenate([np.linspace(lo, hi, n)] + extra))


def _grid(surf: Geom_Surface, bounds, n: int) -> Array:
    u0, u1, v0, v1 = bounds
    return np.array([surf.Value(float(u), float(v)).Coord()
                     for u in _params(u0, u1, n) for v in _params(v0, v1, n)])


def _seed_grid(surf: Geom_Surface, bounds, n: int) -> Array:
    u0, u1, v0, v1 = bounds
    return np.array([surf.Value(float(u), float(v)).Coord()
                     for u in np.linspace(u0, u1, n) for v in np.linspace(v0, v1, n)])


def max_distance(ours: BSplineSurface, occ: Any, samples: int = 31, accept: float = 0.0) -> tuple[float, float]:
    """Largest distance between the surfaces, both ways, by point projection.

    Our surface is sampled on a grid over its domain (``samples`` uniform values per direction,
    plus values 1e-6, 1e-4 and 1e-2 of the range from each boundary, and every distinct knot:
    boundaries, seams and segment joints) and each point projected onto OCC's face / surface
    (inside its UV bounds); then OCC's surface is sampled the same way (without knots) and
    projected onto ours. ``accept``: local projections landing within this distance are kept
    without a global search (see :func:`_project_all`); pass a fraction of the tolerance that
    will be asserted, for surfaces that agree only approximately (sweeps). Points whose projection fails (none found, e.g. exactly on a
    degenerate edge) fall back on ``BRepExtrema_DistShapeShape``; if that fails too for more than
    2 % of the points a KernelError is raised (the rest are left out).

    Returns
    -------
    (forward, backward) : (float, float)
        ``max_p dist(p, OCC)`` over our points and ``max_q dist(q, ours)`` over OCC's.
    """
    surf, bounds = _as_bounded(occ)
    (a, b), (c, d) = ours.domain
    P = ours.evaluate_grid(_params(a, b, samples, ours.knots[0]), _params(c, d, samples, ours.knots[1])).reshape(-1, 3)
    fwd = _project_all(P, surf, bounds, accept)
    Q = _grid(surf, bounds, samples)
    bwd = _project_all(Q, to_occ(ours), (a, b, c, d), accept)
    for name, arr in (("ours -> OCC", fwd), ("OCC -> ours", bwd)):
        if np.isnan(arr).mean() > 0.02:
            raise KernelError(f"max_distance: {np.isnan(arr).sum()} of {arr.size} projections failed ({name})")
    return float(np.nanmax(fwd)), float(np.nanmax(bwd))
