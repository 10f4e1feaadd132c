"""Find and fill the holes of a model (course §8-3), assessed by OCC and compared with OCC's filler.

:func:`fill_model` sews the model's faces into shells, finds every closed loop of free edges
(``ShapeAnalysis_FreeBounds``), and per loop

1. extracts each edge's neighbour face (an edge -> face map, ``TopExp.MapShapesAndAncestors_s``), its
   surface through :func:`occsurf.bridge.conversion.splines.from_occ` (exact for B-spline faces) and the iso-boundary
   the edge lies on, giving :class:`occsurf.algorithms.topology.nsided.HoleSide` data with the exact cross
   derivative (:func:`occsurf.algorithms.topology.nsided.side_from_surface`); where an edge is a
   trimming curve (not an iso-line), or the exact sides cannot be filled, the sides are fitted to the
   neighbours' normals along the edges' p-curves instead (:func:`occsurf.bridge.modeling.refill.fitted_fill`,
   G1 to ``tolerances.FILL_FIT_ANGLE``; :attr:`HoleReport.construction` says which);
2. fills it with :func:`occsurf.algorithms.topology.nsided.fill_hole` (n patches, G1 by construction);
3. measures every boundary with OCC's ``LocalAnalysis_SurfaceContinuity`` (order G1: ``C0Value`` gap
   and ``G1Angle``) at :data:`ASSESS_SAMPLES` points per edge, the neighbour's parameters taken from
   the edge's p-curve and the fill's from ``GeomAPI_ProjectPointOnSurf``; and with our own dense
   measurement (:func:`occsurf.algorithms.topology.nsided.measure_fill`);
4. runs OCC's ``BRepOffsetAPI_MakeFilling`` (what cadquery's ``makeNSidedSurface`` and build123d's
   ``make_surface`` call) on the same edges with the neighbour faces as G1 constraints, with
   cadquery's default settings, times it, catches its failures and measures it the same way.

Finally the original faces and all fills are sewn into one shell (``BRepBuilderAPI_Sewing``).

Which loops are holes: in a shell with more than one free loop, the loop with the largest
bounding box is the shell's outer boundary and is not filled (``all_loops=True`` fills it too). A
shell with a single free loop is topologically a disk: whether that loop is a hole (a closed body
with one opening) or an outer boundary cannot be told from topology; it is filled.
A loop that cannot be filled (an edge on a trimmed face that is not an iso-parametric boundary, a
missing neighbour, a degenerate corner, ...) gets its reason; the others are still filled.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from OCP.BRep import BRep_Builder, BRep_Tool
from OCP.BRepBuilderAPI import BRepBuilderAPI_Sewing
from OCP.BRepOffsetAPI import BRepOffsetAPI_MakeFilling
from OCP.BRepTools import BRepTools, BRepTools_WireExplorer
from OCP.ShapeAnalysis import ShapeAnalysis_FreeBounds
from OCP.TopAbs import TopAbs_FACE, TopAbs_SHELL, TopAbs_WIRE
from OCP.TopExp import TopExp_Explorer
from OCP.TopoDS import TopoDS, TopoDS_Shape, TopoDS_Shell
from OCP.TopTools import TopTools_IndexedDataMapOfShapeListOfShape

from occsurf.algorithms.errors import InvalidGeometryError, KernelError, OccsurfError
from occsurf.algorithms.kernel.surface import BSplineSurface
from occsurf.algorithms.topology.nsided import (
    HoleFill,
    HoleSide,
    boundary_curve,
    closest_parameters,
    fill_hole,
    measure_fill,
    side_from_surface,
)
from occsurf.algorithms.topology.plate_fill import PlateFill

from .. import _occ
from ..conversion.shapes import as_edge, as_face, as_shape
from ..conversion.splines import from_occ, make_face
from ..messages import one_line
from .joints import (  # noqa: F401 - re-exported
    ASSESS_END_SAMPLES,
    ASSESS_SAMPLES,
    CONTINUITIES,
    SEW_TOLERANCE,
    Locator,
    _local_analysis,
    assess_joint,
    check_continuity,
    edge_face_map,
    edge_samples,
    filling_order,
    hole_continuity,
    unique_faces,
)
from .refill_g2 import edge_classes

__all__ = ["HoleReport", "FillResult", "fill_model", "ModelHoles", "model_holes", "fill_loop", "sew_fills",
           "hole_neighbours", "find_loops", "hole_sides", "assess_joint",
           "occ_fill", "sew_faces", "edge_face_map", "neighbour_face", "SEW_TOLERANCE", "ASSESS_SAMPLES",
           "ASSESS_END_SAMPLES", "ISO_TOLERANCE", "CONTINUITIES", "check_continuity"]

#: How close (relative to the edge's length) an edge must lie to an iso-boundary of its face.
ISO_TOLERANCE: float = 1e-7
#: cadquery's ``makeNSidedSurface`` defaults for ``BRepOffsetAPI_MakeFilling``.
OCC_FILL_DEFAULTS = dict(degree=3, nb_pts_on_cur=15, nb_iter=2, anisotropy=False, tol2d=1e-5, tol3d=1e-4,
                         tol_ang=1e-2, tol_curv=0.1, max_deg=8, max_segments=9)


@dataclass
class HoleReport:
    """One free loop: what was done and how good it is (JSON-safe values; angles in degrees)."""

    index: int
    sides: int
    status: str  # 'filled', 'failed', 'outer'
    reason: str | None = None
    # our fill's construction: sides, patches or plate, OCC faces (as occ_seconds is OCC's Add +
    # Build), not the OCC measurement of the result made for this report afterwards; a fitted fill
    # measures its candidates to choose one, and that counts
    seconds: float | None = None
    g0: float | None = None  # OCC LocalAnalysis, max over the boundary
    g1: float | None = None
    own_g0: float | None = None  # our dense measurement
    own_g1: float | None = None
    internal_g1: float | None = None
    side_g0: list[float] = field(default_factory=list)
    side_g1: list[float] = field(default_factory=list)
    construction: str | None = None  # 'iso' (exact cross derivatives) or 'fitted' (trimming-curve edges)
    method: str | None = None  # 'central' (fill_hole's n patches), 'plate' (one trimmed plate, fill_plate) or 'wrap' (a plate about an axis, fill_wrapped_plate)
    fit_g1: list[float] = field(default_factory=list)  # fitted sides: the fields' angle to the neighbours
    folds: int | None = None  # grid pairs where a patch turns back over itself (0: sound; FillQuality.folds)
    occ_status: str | None = None  # 'ok', 'failed', None (not run)
    occ_reason: str | None = None
    occ_seconds: float | None = None
    occ_g0: float | None = None
    occ_g1: float | None = None
    continuity: str = "auto"  # asked: 'auto' (a hole: G1), 'G1' or 'G2' (issue 31)
    g2: float | None = None  # G2 asked: largest relative curvature jump across the boundary (OCC's principal curvatures)
    side_g2: list[float] = field(default_factory=list)  # ... per side
    occ_g2_gap: float | None = None  # ... and OCC LocalAnalysis' G2CurvatureGap, max over the boundary
    occ_g2: float | None = None  # G2 asked: OCC's filler's relative curvature jump (measured as g2)
    corner_g2: list[float | None] = field(default_factory=list)  # G2 asked: the neighbours' own curvature mismatch per corner (PlateFill.corner_g2)
    edge_asked: list[str] = field(default_factory=list)  # per edge: 'G2', 'G1' or 'G0' (G0: no neighbour face)
    edge_continuity: list[str] = field(default_factory=list)  # per edge: what the fill reached (refill_g2.edge_classes)


@dataclass
class FillResult:
    shape: Any  # the sewn shell (original faces + fills)
    holes: list[HoleReport]
    fills: list[HoleFill | PlateFill | None]  # PlateFill: a plate (or a wrapped plate) where the central split failed
    free_loops_after: int


# ---------------------------------------------------------------------------------------- topology
def _faces(shape: TopoDS_Shape) -> list[Any]:
    out, ex = [], TopExp_Explorer(shape, TopAbs_FACE)
    while ex.More():
        out.append(TopoDS.Face_s(ex.Current()))
        ex.Next()
    return out


def sew_faces(shapes: list[Any], tol: float | None = None) -> TopoDS_Shape:
    """Sew faces (and shells) into shells with ``BRepBuilderAPI_Sewing``.

    Parameters
    ----------
    shapes : list of TopoDS_Shape
        Faces, shells or compounds of them; coincident edges within ``tol`` are merged.
    tol : float, optional
        Sewing tolerance, model units; default :data:`SEW_TOLERANCE` (read at call time).

    Returns
    -------
    TopoDS_Shape
        ``SewedShape()``: a shell, a face (a single face has nothing to sew to) or a compound of
        shells.

    Raises
    ------
    KernelError
        OCC failed inside ``Perform``.
    """
    sew = BRepBuilderAPI_Sewing(SEW_TOLERANCE if tol is None else tol)
    for s in shapes:
        sew.Add(s)
    with _occ.kernel_errors("sewing"):
        sew.Perform()
    return sew.SewedShape()


def _bbox_diag(points: np.ndarray) -> float:
    return float(np.linalg.norm(np.ptp(points, axis=0))) if len(points) else 0.0


def _edge_points(edge: Any, k: int = 9) -> np.ndarray:
    curve = BRep_Tool.Curve_s(edge, 0.0, 0.0)
    a, b = BRep_Tool.Range_s(edge)
    if curve is None:
        raise InvalidGeometryError("a hole edge has no 3-D curve")
    return np.array([curve.Value(t).Coord() for t in np.linspace(a, b, k)])


def find_loops(shape: TopoDS_Shape, all_loops: bool = False) -> list[tuple[list[Any], bool]]:
    """Closed loops of free edges, each ``(ordered edges, is_outer)``, shell by shell (a face that
    belongs to no shell counts as a shell of its own). ``shape``: anything
    :func:`~occsurf.bridge.conversion.shapes.as_shape` takes (build123d / cadquery Shells, Solids...)."""
    shape = as_shape(shape, "shape")
    loops: list[tuple[list[Any], bool]] = []
    shells = []
    ex = TopExp_Explorer(shape, TopAbs_SHELL)
    while ex.More():
        shells.append(ex.Current())
        ex.Next()
    # faces outside every shell (a lone face, or loose faces beside shells): each is its own shell
    fex = TopExp_Explorer(shape, TopAbs_FACE, TopAbs_SHELL)
    builder = BRep_Builder()
    while fex.More():
        lone = TopoDS_Shell()
        builder.MakeShell(lone)
        builder.Add(lone, fex.Current())
        shells.append(lone)
        fex.Next()
    for shell in shells:
        fb = ShapeAnalysis_FreeBounds(shell, SEW_TOLERANCE, False, True)
        wires = fb.GetClosedWires()
        found = []
        wex = TopExp_Explorer(wires, TopAbs_WIRE)
        while wex.More():
            wire = TopoDS.Wire_s(wex.Current())
            edges, we = [], BRepTools_WireExplorer(wire)
            while we.More():
                edges.append(we.Current())
                we.Next()
            pts = np.concatenate([_edge_points(e) for e in edges])
            found.append((edges, _bbox_diag(pts)))
            wex.Next()
        outer = max(range(len(found)), key=lambda k: found[k][1]) if len(found) > 1 and not all_loops else -1
        loops += [(edges, k == outer) for k, (edges, _) in enumerate(found)]
    return loops



# ---------------------------------------------------------------------------------------- sides
def _iso_side(surf: BSplineSurface, pts: np.ndarray) -> HoleSide:
    """The iso-boundary of ``surf`` on which the edge points ``pts`` lie, as a HoleSide."""
    length = max(float(np.linalg.norm(np.diff(pts, axis=0), axis=1).sum()), 1e-300)
    side = side_from_surface(surf, _nearest_boundary(surf, pts))  # on a coarse sampling ...
    t, dist = closest_parameters(side.curve, pts)  # ... then its exact distances
    worst = float(dist.max())
    if worst > max(ISO_TOLERANCE * length, 1e-7):
        raise InvalidGeometryError(
            f"a hole edge is not an iso-parametric boundary of its face (off by {worst:.3g}): trimmed "
            "neighbour faces are not supported")
    lo, hi = side.curve.domain
    t0, t1 = float(t.min()), float(t.max())
    eps = 1e-9 * (hi - lo)
    if t0 > lo + eps or t1 < hi - eps:  # the edge covers part of the boundary: that part is the side
        t0, t1 = (lo if t0 <= lo + eps else t0), (hi if t1 >= hi - eps else t1)
        side = HoleSide(side.curve.segment(t0, t1), side.cross.segment(t0, t1),
                        None if side.cross2 is None else side.cross2.segment(t0, t1))
    return side


def _nearest_boundary(surf: BSplineSurface, pts: np.ndarray) -> str:
    """Which iso-boundary of ``surf`` (``'u0'``, ``'u1'``, ``'v0'``, ``'v1'``) the points ``pts`` (m, 3)
    lie nearest to on a coarse sampling: the largest distance of a point from 201 samples of the
    boundary, the least over the four (the first of equals), as :func:`_iso_side` chooses.

    A boundary is sampled only where it could win: it lies (with its samples) in its poles' box, so
    the farthest point's distance to that box is a lower bound of its number; boundaries are taken
    by that bound and the rest left once it exceeds the best number (the 66 hole edges of the ring
    models, n = 3..8, polynomial and rational: one of the four sampled for each)."""
    order = ("u0", "u1", "v0", "v1")
    curves = {e: boundary_curve(surf, e) for e in order}  # side_from_surface's curves alone
    bound = {e: _box_distance(c.control_points, pts) for e, c in curves.items()}
    best: tuple[float, int] | None = None
    for e in sorted(order, key=lambda e: bound[e]):
        if best is not None and bound[e] > best[0]:
            break  # this boundary and the rest are farther than the best one: none can win
        c = curves[e]
        dense = c.evaluate(np.linspace(*c.domain, 201))
        coarse = float(np.sqrt(((pts[:, None] - dense[None]) ** 2).sum(-1).min(axis=1)).max())
        if best is None or (coarse, order.index(e)) < best:
            best = (coarse, order.index(e))
    assert best is not None
    return order[best[1]]


def _box_distance(poles: np.ndarray, pts: np.ndarray) -> float:
    """The largest distance of the points ``pts`` (m, 3) from the axis-aligned box of ``poles`` (n, 3)."""
    lo, hi = poles.min(axis=0), poles.max(axis=0)
    return float(np.linalg.norm(np.maximum(lo - pts, 0.0) + np.maximum(pts - hi, 0.0), axis=1).max())


def hole_sides(edges: list[Any], faces: list[Any | None]) -> list[HoleSide]:
    """HoleSide data of a loop: ``edges`` in loop order, ``faces[k]`` the neighbour of ``edges[k]``.

    Raises
    ------
    InvalidGeometryError
        A missing neighbour face (``None``), a neighbour that does not convert, an edge that is not
        an iso-boundary of its face, or a loop that is not closed.
    """
    if len(edges) != len(faces):
        raise InvalidGeometryError(f"faces: expected one neighbour face per edge ({len(edges)}), got {len(faces)}")
    sides = []
    for k, (e, f) in enumerate(zip(edges, faces)):
        if f is None:
            raise InvalidGeometryError(f"edge {k} of the hole has no neighbour face: its tangent plane is unknown")
        e, f = as_edge(e, f"edges[{k}]"), as_face(f, f"faces[{k}]")  # build123d / cadquery objects too
        surf = from_occ(f, BRepTools.UVBounds_s(f))  # the part of the surface the face uses
        if not isinstance(surf, BSplineSurface):  # a face converted on bounds is its surface
            raise TypeError(f"from_occ gave a {type(surf).__name__} for face {k}")
        sides.append(_iso_side(surf, _edge_points(e)))
    n = len(sides)
    ends = [(s.curve.evaluate(s.curve.domain[0]), s.curve.evaluate(s.curve.domain[1])) for s in sides]
    out = []
    for k in range(n):
        a0, a1 = ends[k]
        b0, b1 = ends[(k + 1) % n]
        # the end of side k is its endpoint closest to side k+1
        d_end = min(np.linalg.norm(a1 - b0), np.linalg.norm(a1 - b1))
        d_start = min(np.linalg.norm(a0 - b0), np.linalg.norm(a0 - b1))
        s = sides[k]
        out.append(s if d_end <= d_start else HoleSide(s.curve.reverse(), s.cross.reverse(),
                                                        None if s.cross2 is None else s.cross2.reverse()))
    return out


# ---------------------------------------------------------------------------------------- assessment
def occ_fill(edges: list[Any], faces: list[Any], continuity: str = "G1") -> Any:
    """OCC's ``BRepOffsetAPI_MakeFilling`` on the hole (G1, or curvature with ``continuity='G2'``, to
    the faces: :func:`.joints.filling_order`), cadquery's defaults."""
    order = filling_order(continuity)  # GeomAbs_C1 for G2: an OCC defect, see there
    o = OCC_FILL_DEFAULTS
    mk = BRepOffsetAPI_MakeFilling(o["degree"], o["nb_pts_on_cur"], o["nb_iter"], o["anisotropy"], o["tol2d"],
                                   o["tol3d"], o["tol_ang"], o["tol_curv"], o["max_deg"], o["max_segments"])
    with _occ.kernel_errors("BRepOffsetAPI_MakeFilling"):
        for k, (e, f) in enumerate(zip(edges, faces)):
            mk.Add(as_edge(e, f"edges[{k}]"), as_face(f, f"faces[{k}]"), order, True)
        mk.Build()
        if not mk.IsDone():
            raise KernelError("BRepOffsetAPI_MakeFilling: not done")
        return TopoDS.Face_s(mk.Shape())


def neighbour_face(m: TopTools_IndexedDataMapOfShapeListOfShape, edge: Any) -> Any | None:
    """The (first) face that ``edge`` bounds in the map ``m`` of :func:`edge_face_map`.

    For a free edge of a hole this is its neighbour face; ``None`` if the edge is not in the map or
    bounds no face.
    """
    idx = m.FindIndex(as_edge(edge, "edge"))
    if idx == 0:
        return None
    lst = m.FindFromIndex(idx)
    return TopoDS.Face_s(lst.First()) if lst.Size() >= 1 else None


def _locator(fill: HoleFill | PlateFill, side: int) -> Locator:
    def locate(points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        idx, u, v, _ = fill.locate_input(side, points)  # the distance is judged by OCC's C0Value
        return idx, u, v
    return locate


def _model_size(shape: Any) -> float:
    from OCP.Bnd import Bnd_Box
    from OCP.BRepBndLib import BRepBndLib

    box = Bnd_Box()
    BRepBndLib.Add_s(shape, box)
    return math.sqrt(box.SquareExtent()) if not box.IsVoid() else 1.0


def _fill_loop(edges: list[Any], nb: list[Any | None], size: float, samples: int,
               rep: HoleReport, continuity: str = "G1", started: float | None = None
               ) -> tuple[HoleFill | PlateFill, list[Any]]:
    """Fill one loop: exactly from the neighbours' iso-boundaries when every edge is one, else with
    sides fitted to the neighbours along the edges' p-curves (trimming curves; G1 to 0.01 deg,
    :func:`occsurf.bridge.modeling.refill.fitted_fill`). Records the per-edge OCC measurements and
    the construction (``'iso'``, ``'fitted'``) on ``rep``; returns the fill and its OCC faces.
    With ``started`` (a ``time.perf_counter()`` value), ``rep.seconds`` is set once the fill and its
    faces exist, before the measurements made only for the report.

    ``continuity='G2'``: curvature continuous to the neighbours (issue 31), by the plate with the
    neighbours' curvature across each side (:func:`_g2_fill`), where every edge is an iso-boundary
    (the exact second cross derivative); elsewhere the fill is G1 and ``rep.reason`` says why."""
    sides: list[HoleSide] | OccsurfError  # the exact sides, made once for the G2 plate and the central split
    try:
        sides = hole_sides(edges, nb)
    except OccsurfError as err:  # trimmed neighbours: no exact sides (raised again below where they are needed)
        sides = err
    if continuity == "G2":
        try:
            if isinstance(sides, OccsurfError):
                raise sides
            return _g2_fill(edges, nb, sides, size, samples, rep, started)
        except OccsurfError as err:  # trimmed neighbours (no exact S_tt), or no plane the hole is a height over
            rep.reason = f"G2 not available, filled G1: {one_line(err, expected=(OccsurfError,))}"
            rep.side_g2, rep.g2, rep.occ_g2_gap, rep.corner_g2 = [], None, None, []
    try:
        if isinstance(sides, OccsurfError):
            raise sides
        fill = fill_hole(sides)
    except InvalidGeometryError as exact_err:
        if any(f is None for f in nb):
            raise
        from .refill import fill_method, fitted_fill

        try:
            occ_faces, _, fit, s0, s1, fill, _ = fitted_fill(edges, nb, [None] * len(edges), size, samples)
        except InvalidGeometryError as err:
            raise InvalidGeometryError(f"{err} (exact sides: {exact_err})") from err
        rep.construction, rep.fit_g1 = "fitted", [float(a) for a in fit]
        rep.method = fill_method(fill)  # fitted_fill falls back to the plate where the central split fails
        rep.side_g0, rep.side_g1 = [float(a) for a in s0], [float(a) for a in s1]
        return fill, occ_faces
    occ_faces = [make_face(p, 1e-7) for p in fill.patches]
    if started is not None:
        rep.seconds = time.perf_counter() - started
    occ_surfs = [BRep_Tool.Surface_s(f) for f in occ_faces]
    per = [assess_joint(e, f, occ_surfs, samples, locate=_locator(fill, i)) for i, (e, f) in enumerate(zip(edges, nb))]
    rep.side_g0, rep.side_g1 = [p[0] for p in per], [p[1] for p in per]
    rep.construction, rep.method = "iso", "central"
    return fill, occ_faces


def _g2_fill(edges: list[Any], nb: list[Any | None], sides: list[HoleSide], size: float, samples: int,
             rep: HoleReport, started: float | None = None) -> tuple[PlateFill, list[Any]]:
    """The G2 plate of a loop with exact sides (:func:`occsurf.algorithms.topology.plate_fill.fill_plate`
    with ``g2``), its face, and the OCC measures per edge: G0, G1 (:func:`.joints.assess_joint`) and
    the curvature jump (:func:`.joints.assess_curvature`)."""
    from occsurf.algorithms import tolerances

    from .joints import assess_curvature
    from .plate import plate_fill_faces

    g0_tol = min(tolerances.FILL_FIT_G0 * size, tolerances.FILL_PLATE_SEW_SHARE * SEW_TOLERANCE)
    flags = [True] * len(sides)
    fill, occ_faces = plate_fill_faces(sides, flags, g0_tol, gap=max(BRep_Tool.Tolerance_s(e) for e in edges),
                                       g2=flags)
    if started is not None:
        rep.seconds = time.perf_counter() - started
    surfs = [BRep_Tool.Surface_s(f) for f in occ_faces]
    floor = tolerances.CONTINUITY_CURVATURE_FLOOR / size
    per, curv = [], []
    for i, (e, f) in enumerate(zip(edges, nb)):
        loc = _locator(fill, i)
        per.append(assess_joint(e, f, surfs, samples, locate=loc))
        curv.append(assess_curvature(e, f, surfs, floor, samples, locate=loc))
    rep.side_g0, rep.side_g1 = [p[0] for p in per], [p[1] for p in per]
    rep.side_g2 = [c[0] for c in curv]
    rep.g2, rep.occ_g2_gap = max(rep.side_g2), max(c[1] for c in curv)
    rep.corner_g2 = [None if np.isnan(c) else float(c) for c in fill.corner_g2]
    rep.construction, rep.method = "iso", "plate"
    return fill, occ_faces


@dataclass
class ModelHoles:
    """A model sewn into shells and its free loops, ready to fill one by one (:func:`model_holes`).

    ``loops[k]`` is ``(edges, outer)``: hole ``k``'s edges in order, and whether it is a shell's outer
    boundary (left open unless ``all_loops``). The same file read again gives the same loops in the
    same order, so a worker process can fill hole ``k`` of its own copy (``occsurf fill --jobs``).
    """

    sewn: Any
    e2f: Any
    size: float
    loops: list[tuple[list[Any], bool]]


def model_holes(shape: Any, all_loops: bool = False) -> ModelHoles:
    """Sew ``shape``'s faces into shells and find its free loops (the first steps of :func:`fill_model`).

    Raises
    ------
    InvalidGeometryError
        The shape has no faces.
    """
    faces = _faces(shape)
    if not faces:
        raise InvalidGeometryError("shape: the model has no faces")
    sewn = sew_faces(faces)
    return ModelHoles(sewn, edge_face_map(sewn), _model_size(sewn), find_loops(sewn, all_loops))


def _check_samples(samples: object) -> int:
    """``samples`` per joint: an integer >= 2 whose arrays (points, normals, feet and OCC's values,
    ~64 floats a sample) fit ``tolerances.MAX_ARRAY_BYTES``; refused before any hole is filled."""
    from occsurf.algorithms._validate import check_count

    return check_count(samples, "samples", 64, minimum=2)


@_occ.quiet_messages()
def fill_loop(holes: ModelHoles, k: int, *, compare_occ: bool = True, samples: int = ASSESS_SAMPLES,
              continuity: str = "auto") -> tuple[HoleReport, HoleFill | PlateFill | None, list[Any]]:
    """Fill hole ``k`` of ``holes`` and measure it (and OCC's filler on it with ``compare_occ``).

    ``continuity``: ``'G1'`` (tangent continuous) or ``'G2'`` (curvature continuous, where the
    neighbours' edges are iso-boundaries: :func:`_fill_loop`); OCC's filler is then asked for
    ``GeomAbs_G2`` on every edge. ``'auto'`` (the default) is ``'G1'`` for a hole of the model: no
    removed face says what the joint was (:func:`.joints.hole_continuity`).

    Never raises for the hole: a failure is the report's ``status``/``reason``.

    Returns
    -------
    (HoleReport, fill or None, list of TopoDS_Face)
        The report; our fill and its OCC faces (``None`` and ``[]`` unless filled).
    """
    _check_samples(samples)  # a bad argument, not a failure of the hole
    asked, continuity = continuity, hole_continuity(continuity)
    edges, outer = holes.loops[k]
    rep = HoleReport(index=k, sides=len(edges), status="outer" if outer else "failed", continuity=asked)
    if outer:
        rep.reason = "outer boundary of its shell (not filled; use --all-loops)"
        return rep, None, []
    nb = [neighbour_face(holes.e2f, e) for e in edges]
    fill: HoleFill | PlateFill | None = None
    occ_faces: list[Any] = []
    try:
        t0 = time.perf_counter()
        fill, occ_faces = _fill_loop(edges, nb, holes.size, samples, rep, continuity, started=t0)
        if rep.seconds is None:  # a fitted fill: its measurements chose it
            rep.seconds = time.perf_counter() - t0
        if isinstance(fill, PlateFill):  # rep.method 'plate' or 'wrap'
            from .plate import plate_quality

            rep.own_g0, rep.own_g1, rep.internal_g1, rep.folds = plate_quality(fill)
        else:
            q = measure_fill(fill)
            rep.own_g0, rep.own_g1 = float(q.boundary_gap.max()), float(q.boundary_angle.max())
            rep.internal_g1 = float(max(q.internal_angle.max(), q.center_angle))
            rep.folds = int(q.folds.sum())
        rep.g0, rep.g1 = max(rep.side_g0), max(rep.side_g1)
        rep.status = "filled"
        rep.edge_asked = ["G0" if f is None else continuity for f in nb]
        rep.edge_continuity = edge_classes(list(rep.side_g1), list(rep.side_g2))
        # for pictures; not dataclass fields, so asdict() leaves them out
        rep._fill_faces, rep._neighbours = occ_faces, unique_faces(nb)  # type: ignore[attr-defined]
    except Exception as err:  # noqa: BLE001 - one hole's failure must not stop the others
        rep.status, rep.reason = "failed", one_line(err, expected=(OccsurfError,))
        rep.seconds, fill, occ_faces = None, None, []
    if compare_occ and all(f is not None for f in nb):
        try:
            t0 = time.perf_counter()
            of = occ_fill(edges, nb, continuity)
            rep.occ_seconds = time.perf_counter() - t0
            s_o = BRep_Tool.Surface_s(of)
            per = [assess_joint(e, f, [s_o], samples) for e, f in zip(edges, nb)]
            rep.occ_g0, rep.occ_g1 = max(p[0] for p in per), max(p[1] for p in per)
            if continuity == "G2":
                from occsurf.algorithms import tolerances

                from .joints import assess_curvature

                floor = tolerances.CONTINUITY_CURVATURE_FLOOR / holes.size
                rep.occ_g2 = max(assess_curvature(e, f, [s_o], floor, samples, gap=False)[0] for e, f in zip(edges, nb))
            rep.occ_status = "ok"
        except Exception as err:  # noqa: BLE001
            rep.occ_status, rep.occ_reason = "failed", one_line(err, expected=(OccsurfError,))
            if rep.occ_seconds is None:
                rep.occ_seconds = time.perf_counter() - t0
    return rep, fill, occ_faces


def hole_neighbours(holes: ModelHoles, k: int) -> list[Any]:
    """The faces around hole ``k``, each once (for its pictures)."""
    return unique_faces([neighbour_face(holes.e2f, e) for e in holes.loops[k][0]])


def sew_fills(holes: ModelHoles, new_faces: list[Any]) -> tuple[Any, int]:
    """The model with ``new_faces`` sewn in (once), and the number of free loops left."""
    result = sew_faces([holes.sewn] + new_faces) if new_faces else holes.sewn
    return result, sum(1 for _ in find_loops(result, all_loops=True))


@_occ.quiet_messages()  # OCC's printers at the caller's levels again afterwards
def fill_model(shape: Any, *, all_loops: bool = False, compare_occ: bool = True,
               samples: int = ASSESS_SAMPLES, as_: str | None = None, continuity: str = "auto") -> FillResult:
    """Fill every hole of ``shape``; see the module.

    Parameters
    ----------
    shape : TopoDS_Shape, or a build123d / cadquery object
        Faces, a Shell, Solid or Compound, a Workplane, an Assembly...
        (:func:`occsurf.bridge.conversion.shapes.as_shape`).
    as_ : {None, 'build123d', 'cadquery'}
        The type of ``FillResult.shape``: OCC's ``TopoDS_Shape`` (default), or a build123d / cadquery
        object, a ``Solid`` when the filled shell is closed, else a ``Shell`` (a ``Compound`` when the
        faces sew into several shells); :func:`occsurf.bridge.exchange.objects.shape_object`.
    continuity : {'auto', 'G1', 'G2'}
        Tangent or curvature continuity to the neighbours (:func:`fill_loop`); ``'auto'`` (default)
        is tangent: a hole has no original joint to follow (:func:`.joints.check_continuity`).

    Returns
    -------
    FillResult
        ``shape`` is the sewn shell with the fills (as ``as_`` asks); one :class:`HoleReport` per free loop.
    """
    from ..conversion.shapes import as_shape
    from ..exchange.objects import check_as, shape_object

    check_as(as_)
    _check_samples(samples)
    check_continuity(continuity)
    holes = model_holes(as_shape(shape, "shape"), all_loops)
    reports: list[HoleReport] = []
    fills: list[HoleFill | PlateFill | None] = []
    new_faces: list[Any] = []
    for k in range(len(holes.loops)):
        rep, fill, occ_faces = fill_loop(holes, k, compare_occ=compare_occ, samples=samples, continuity=continuity)
        reports.append(rep)
        fills.append(fill)
        new_faces += occ_faces
    result, after = sew_fills(holes, new_faces)
    return FillResult(result if as_ is None else shape_object(result, as_), reports, fills, after)
