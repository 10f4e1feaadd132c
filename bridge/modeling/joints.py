"""Measuring a joint between a hole's neighbour and its fill with OCC, shared by the fill and refill.

:func:`assess_joint` samples an edge evenly plus clusters at its ends and takes OCC's
``LocalAnalysis_SurfaceContinuity`` (order G1) at each point; :func:`edge_face_map` maps every edge
of a shape to the faces it bounds.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
from OCP.BRep import BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Curve
from OCP.GeomAbs import GeomAbs_Shape
from OCP.GeomAPI import GeomAPI_ProjectPointOnSurf
from OCP.gp import gp_Pnt, gp_Pnt2d
from OCP.LocalAnalysis import LocalAnalysis_SurfaceContinuity
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE
from OCP.TopExp import TopExp
from OCP.TopoDS import TopoDS_Shape
from OCP.TopTools import TopTools_IndexedDataMapOfShapeListOfShape

from occsurf.algorithms.errors import InvalidGeometryError, KernelError
from occsurf.algorithms.topology.nsided import CONTINUITIES as NSIDED_CONTINUITIES

__all__ = ["assess_joint", "assess_curvature", "CONTINUITIES", "check_continuity", "hole_continuity", "filling_order", "edge_samples", "edge_curve_points", "surface_feet", "surfaces_joint", "edge_face_map", "unique_faces", "SEW_TOLERANCE", "ASSESS_SAMPLES", "ASSESS_END_SAMPLES"]

#: Tolerance of ``BRepBuilderAPI_Sewing`` (model units), for finding free edges and for the result.
SEW_TOLERANCE: float = 1e-5
#: Points per boundary edge at which OCC's ``LocalAnalysis_SurfaceContinuity`` is evaluated: this
#: many evenly spaced, plus :data:`ASSESS_END_SAMPLES` clustered towards each end.
ASSESS_SAMPLES: int = 41
#: Extra samples at each end of an edge, at 1e-5 .. 5e-2 of its length (geometric): the corners of a
#: hole are where fills go wrong (a confined twist span, a neighbour's pole), and evenly spaced
#: samples step over them (41 of them reported 1.6e-9 deg where 401 found 1.8e-2 deg).
ASSESS_END_SAMPLES: int = 16
#: Tolerance of the projections onto a fill that :func:`assess_joint` makes without ``locate``
#: (``Precision::Confusion()``, OCC's default for ``GeomAPI_ProjectPointOnSurf``).
PROJECTION_TOLERANCE: float = 1e-7
#: What :func:`assess_joint` takes as ``locate``: boundary points ``(m, 3)`` -> the fill's
#: ``(surface index, u, v)`` of each.
Locator = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray, np.ndarray]]

def edge_samples(edge: Any, face: Any, samples: int) -> tuple[Any, list[Any], np.ndarray]:
    """The neighbour's surface, its (u, v) at ``samples`` points of ``edge`` (from the p-curve) and
    the points themselves, shape (samples, 3)."""
    s_n = BRep_Tool.Surface_s(face)
    pc = BRep_Tool.CurveOnSurface_s(edge, face, 0.0, 0.0)
    a, b = BRep_Tool.Range_s(edge, face)
    uvs = [pc.Value(a + t * (b - a)) for t in _fractions(samples)]
    pts = np.array([s_n.Value(uv.X(), uv.Y()).Coord() for uv in uvs])
    return s_n, uvs, pts


def _local_analysis(s_n: Any, uv: Any, s_f: Any, u: float, v: float) -> tuple[float, float]:
    la = LocalAnalysis_SurfaceContinuity(s_n, uv.X(), uv.Y(), s_f, u, v, GeomAbs_Shape.GeomAbs_G1)
    if not la.IsDone():
        if "NormalNotDefined" in str(la.StatusError()):  # a pole (fillet corner): no tangent plane to compare
            return s_n.Value(uv.X(), uv.Y()).Distance(s_f.Value(u, v)), 0.0
        raise KernelError(f"LocalAnalysis_SurfaceContinuity failed ({la.StatusError()})")
    ang = la.G1Angle()
    return la.C0Value(), math.degrees(min(ang, math.pi - ang))


def _projector(surface: Any) -> Any:
    """A ``GeomAPI_ProjectPointOnSurf`` set up once for ``surface`` over its bounds, to ``Perform``
    point after point: its sampling grid of the surface is built at the first point and kept, where
    ``Init(point, surface)`` rebuilt it at every point (0.9 of the time measuring OCC's fill of a
    lens hole). The tolerance is passed (``Precision::Confusion``, 1e-7, what ``Init(point,
    surface)`` uses): without it this overload's projections differ from ``Init(point, surface)``'s
    by up to 1e-13 (lens face 1); with it they are the same numbers."""
    pr = GeomAPI_ProjectPointOnSurf()
    pr.Init(surface, *surface.Bounds(), PROJECTION_TOLERANCE)
    return pr


def assess_joint(edge: Any, face: Any, fill_surfaces: list[Any], samples: int = ASSESS_SAMPLES,
                 locate: Locator | None = None) -> tuple[float, float]:
    """Max ``C0Value`` gap and ``G1Angle`` (degrees) of OCC's LocalAnalysis (order G1) along ``edge``
    between its neighbour ``face`` and the fill (Geom surfaces ``fill_surfaces``).

    ``locate(points) -> (surface index, u, v)`` gives the fill's parameters of the boundary points
    when the fill knows them (ours: from its construction, :meth:`HoleFill.locate`); OCC then
    evaluates the fill there, so a wrong parameter shows up as a gap. Without it (OCC's filler)
    each point is projected onto every surface (``GeomAPI_ProjectPointOnSurf``), the nearest kept.
    ``edge`` and ``face`` may be build123d / cadquery objects (:mod:`occsurf.bridge.conversion.shapes`).
    """
    from ..conversion.shapes import as_edge, as_face

    edge, face = as_edge(edge, "edge"), as_face(face, "face")
    s_n, uvs, pts = edge_samples(edge, face, samples)
    g0 = g1 = 0.0
    if locate is not None:
        idx, us, vs = locate(pts)
        for uv, k, u, v in zip(uvs, idx, us, vs):
            gap, ang = _local_analysis(s_n, uv, fill_surfaces[int(k)], float(u), float(v))
            g0, g1 = max(g0, gap), max(g1, ang)
        return g0, g1
    projs = [_projector(s_f) for s_f in fill_surfaces]
    for uv, p in zip(uvs, pts):
        best = None
        for s_f, pr in zip(fill_surfaces, projs):
            pr.Perform(gp_Pnt(*p))
            if pr.NbPoints() == 0:
                continue
            d = pr.LowerDistance()
            if best is None or d < best[0]:
                best = (d, s_f, *pr.LowerDistanceParameters())
        if best is None:
            raise KernelError("cannot project a boundary point onto the fill")
        gap, ang = _local_analysis(s_n, uv, best[1], best[2], best[3])
        g0, g1 = max(g0, gap), max(g1, ang)
    return g0, g1


def assess_curvature(edge: Any, face: Any, fill_surfaces: list[Any], floor: float, samples: int = ASSESS_SAMPLES,
                     locate: Locator | None = None, *, gap: bool = True) -> tuple[float, float]:
    """Curvature continuity (G2) along ``edge`` between its neighbour ``face`` and the fill, by OCC:
    the largest relative jump of the normal curvature across the edge, and the largest
    ``G2CurvatureGap`` of ``LocalAnalysis_SurfaceContinuity`` at order G2.

    The relative jump is CATIA's G2 ratio ``|k1 - k2| / max(|k1|, |k2|)`` (a fraction; 0 where both
    curvatures are below ``floor``), each ``k`` the normal curvature in the direction ``n x T``
    across the edge (``T`` the edge's tangent), by Euler's formula from OCC's principal curvatures
    and directions (``GeomLProp_SLProps``), the fill's normal turned to agree with the neighbour's.
    OCC's ``G2CurvatureGap`` is another measure (of the principal curvatures and frames); both are
    reported, the gap only with ``gap`` (else 0: a ``LocalAnalysis`` per sample that callers wanting
    the jump alone do not pay for). ``locate`` as for :func:`assess_joint` (without it, the points
    are projected).

    OCC is asked per sample (its properties are the measure); the arithmetic on what it returns
    (the edge's tangent, the direction across it, Euler's formula, the ratios) runs on all samples
    at once.
    """
    from OCP.GeomLProp import GeomLProp_SLProps
    from OCP.gp import gp_Dir, gp_Vec2d

    from ..conversion.shapes import as_edge, as_face

    edge, face = as_edge(edge, "edge"), as_face(face, "face")
    s_n, uvs, pts = edge_samples(edge, face, samples)
    pc = BRep_Tool.CurveOnSurface_s(edge, face, 0.0, 0.0)
    a, b = BRep_Tool.Range_s(edge, face)
    idx, us, vs = locate(pts) if locate is not None else _nearest_feet(fill_surfaces, pts)
    worst_gap = 0.0
    p2, d2, dmax, dmin = gp_Pnt2d(), gp_Vec2d(), gp_Dir(), gp_Dir()
    rows: list[tuple[float, ...]] = []  # per sample with both curvatures defined: see the columns below
    for t, uv, k, u, v in zip(_fractions(samples), uvs, idx, us, vs):
        s_f = fill_surfaces[int(k)]
        pn = GeomLProp_SLProps(s_n, uv.X(), uv.Y(), 2, 1e-9)
        pf = GeomLProp_SLProps(s_f, float(u), float(v), 2, 1e-9)
        if not (pn.IsNormalDefined() and pf.IsNormalDefined() and pn.IsCurvatureDefined() and pf.IsCurvatureDefined()):
            continue  # a pole or an umbilic OCC cannot resolve: no curvature to compare there
        pc.D1(a + t * (b - a), p2, d2)
        row = [*pn.D1U().Coord(), *pn.D1V().Coord(), d2.X(), d2.Y(), *pn.Normal().Coord(), *pf.Normal().Coord()]
        for pr in (pn, pf):  # Euler's formula's data: umbilic (mean), else the principal frame
            if pr.IsUmbilic():  # a sphere's point: every direction bends alike (and has no principal frame)
                row += [1.0, float(pr.MeanCurvature()), 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
            else:
                pr.CurvatureDirections(dmax, dmin)
                row += [0.0, 0.0, *dmax.Coord(), *dmin.Coord(), pr.MaxCurvature(), pr.MinCurvature()]
        rows.append(tuple(row))
        if gap:
            la = LocalAnalysis_SurfaceContinuity(s_n, uv.X(), uv.Y(), s_f, float(u), float(v), GeomAbs_Shape.GeomAbs_G2)
            if la.IsDone():
                worst_gap = max(worst_gap, la.G2CurvatureGap())
    if not rows:
        return 0.0, worst_gap
    R = np.array(rows)
    T = R[:, 0:3] * R[:, 6:7] + R[:, 3:6] * R[:, 7:8]  # the edge's tangent: S_u du + S_v dv
    nn, nf = R[:, 8:11], R[:, 11:14]
    sign = np.where(np.einsum("ij,ij->i", nn, nf) >= 0, 1.0, -1.0)
    across = np.cross(nn, T)
    across /= np.maximum(np.linalg.norm(across, axis=1), 1e-300)[:, None]
    kn, kf = (_normal_curvatures(R[:, c:c + 10], across) for c in (14, 24))
    kf = kf * sign
    big = np.maximum(np.abs(kn), np.abs(kf))
    rel = np.abs(kn - kf) / np.maximum(big, floor)
    worst_rel = float(rel[big >= floor].max(initial=0.0))
    return worst_rel, worst_gap


def _nearest_feet(surfaces: list[Any], pts: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(surface index, u, v)`` of each point's nearest foot on the Geom ``surfaces`` (OCC's fill)."""
    projs = [_projector(s) for s in surfaces]
    out = np.zeros((len(pts), 3))
    for k, p in enumerate(pts):
        best = None
        for j, pr in enumerate(projs):
            pr.Perform(gp_Pnt(*p))
            if pr.NbPoints() and (best is None or pr.LowerDistance() < best[0]):
                best = (pr.LowerDistance(), j, *pr.LowerDistanceParameters())
        if best is None:
            raise KernelError("cannot project a boundary point onto the fill")
        out[k] = best[1:]
    return out[:, 0].astype(int), out[:, 1], out[:, 2]


def _normal_curvatures(props: np.ndarray, direction: np.ndarray) -> np.ndarray:
    """Euler's formula on rows of OCC's curvature data ``(umbilic, mean, dmax (3), dmin (3), k_max,
    k_min)`` (:func:`assess_curvature`): the normal curvature in each unit tangent ``direction``,
    ``k_max cos^2 + k_min sin^2`` of its angle to the maximum direction (the mean curvature at an
    umbilic, where every direction bends alike); signed by the surface's own normal."""
    c = np.einsum("ij,ij->i", direction, props[:, 2:5])
    s = np.einsum("ij,ij->i", direction, props[:, 5:8])
    euler = props[:, 8] * c * c + props[:, 9] * s * s
    return np.where(props[:, 0] > 0, props[:, 1], euler)


#: What ``continuity`` takes (``fill_model``, ``fill_loop``, ``refill_faces``, ``occsurf fill --continuity``):
#: ``'auto'`` (the default: per edge what the original model gave, issue 31) and the algorithms' own
#: (:data:`occsurf.algorithms.topology.nsided.CONTINUITIES`, ``fill_hole``'s).
CONTINUITIES: tuple[str, ...] = ("auto", *NSIDED_CONTINUITIES)


def check_continuity(continuity: object) -> str:
    """``continuity`` if it is one of :data:`CONTINUITIES`, else an ``InvalidGeometryError`` naming them.

    ``'auto'`` asks per edge what the original model gave: a refill is G2 where the removed face met
    its neighbour curvature continuously (within :data:`.refill_g2.G2_REL`, the ``catia`` preset's
    ``g2_rel``), else G1 where tangent, else G0 (as ``'G2'`` asks); a hole of the model, where
    nothing was there to ask, is filled G1 (as ``'G1'`` asks)."""
    if continuity not in CONTINUITIES:
        raise InvalidGeometryError(f"continuity: expected one of {', '.join(CONTINUITIES)}, got {continuity!r}")
    return str(continuity)


def filling_order(continuity: str) -> Any:
    """The ``GeomAbs_Shape`` that asks ``BRepOffsetAPI_MakeFilling`` for ``continuity`` along an edge
    with its face ('G1', 'G2'). OCC defect: ``BRepFill_Filling`` hands the enum's value on as the
    constraint's order (0..2), so ``GeomAbs_G2`` (3) throws "The continuity is not G0 G1 or G2";
    ``GeomAbs_C1`` (2) is its curvature constraint (tests/bridge/test_fill_g2.py keeps the literal G2
    as a strict xfail)."""
    return GeomAbs_Shape.GeomAbs_C1 if check_continuity(continuity) == "G2" else GeomAbs_Shape.GeomAbs_G1


def hole_continuity(continuity: str) -> str:
    """What ``continuity`` asks of a hole of the model (no removed faces to follow): ``'auto'`` is
    ``'G1'`` there (:func:`check_continuity`)."""
    return "G1" if check_continuity(continuity) == "auto" else continuity


def _fractions(samples: int) -> np.ndarray:
    ends = np.geomspace(1e-5, 5e-2, ASSESS_END_SAMPLES)
    return np.unique(np.concatenate((np.linspace(0.0, 1.0, samples), ends, 1.0 - ends)))


def edge_curve_points(edge: Any, samples: int = ASSESS_SAMPLES) -> np.ndarray:
    """Points of ``edge``'s 3-D curve, shape (k, 3): ``samples`` evenly spaced in its parameter,
    plus :data:`ASSESS_END_SAMPLES` clustered towards each end (as :func:`edge_samples`)."""
    c = BRepAdaptor_Curve(edge)
    a, b = c.FirstParameter(), c.LastParameter()
    return np.array([c.Value(a + t * (b - a)).Coord() for t in _fractions(samples)])


def surface_feet(surface: Any, points: np.ndarray) -> np.ndarray:
    """``(u, v)`` of the feet of ``points`` (k, 3) on the Geom surface ``surface``
    (``GeomAPI_ProjectPointOnSurf``, the nearest solution), shape (k, 2)."""
    pr = _projector(surface)
    out = np.empty((len(points), 2))
    for k, p in enumerate(points):
        pr.Perform(gp_Pnt(*p))
        if pr.NbPoints() == 0:
            raise KernelError("cannot project a point of the edge onto the surface")
        out[k] = pr.LowerDistanceParameters()
    return out


def surfaces_joint(s_a: Any, uv_a: np.ndarray, s_b: Any, uv_b: np.ndarray) -> tuple[float, float]:
    """Max ``C0Value`` gap and ``G1Angle`` (degrees) of OCC's LocalAnalysis (order G1) between Geom
    surfaces ``s_a`` at ``uv_a`` and ``s_b`` at ``uv_b`` (each (k, 2), paired)."""
    g0 = g1 = 0.0
    for (ua, va), (ub, vb) in zip(uv_a, uv_b):
        gap, ang = _local_analysis(s_a, gp_Pnt2d(ua, va), s_b, float(ub), float(vb))
        g0, g1 = max(g0, gap), max(g1, ang)
    return g0, g1


def edge_face_map(shape: TopoDS_Shape) -> TopTools_IndexedDataMapOfShapeListOfShape:
    """Every edge of ``shape`` mapped to the faces it bounds (``TopExp.MapShapesAndAncestors_s``).

    Look an edge's faces up with :func:`neighbour_face`; a free edge has one face, an edge
    shared by two sewn faces two. ``shape``: anything :func:`~occsurf.bridge.conversion.shapes.as_shape` takes.
    """
    from ..conversion.shapes import as_shape

    shape = as_shape(shape, "shape")
    m = TopTools_IndexedDataMapOfShapeListOfShape()
    TopExp.MapShapesAndAncestors_s(shape, TopAbs_EDGE, TopAbs_FACE, m)
    return m


def unique_faces(faces: list[Any]) -> list[Any]:
    """``faces`` each once (``IsSame``), in their order; ``None`` entries left out (a hole's neighbours)."""
    out: list[Any] = []
    for f in faces:
        if f is not None and not any(f.IsSame(g) for g in out):
            out.append(f)
    return out
