"""Match two faces of a model along their shared edge: G0-G3 (issue 29; course ch. 3-4).

:func:`match_faces` is CATIA's Match Surface / NX's Matching Edge on a model: face ``face`` (numbered
as ``occsurf check`` and ``inspect`` number them) is changed by
:func:`occsurf.algorithms.manipulation.match_surface` so that it meets face ``target`` with the asked
continuity along their shared edge, and is put back in place of the old face with its own wires:

1. the model is sewn once (:class:`.refill_loop.SewnModel`); the shared edge(s) found;
2. the edge is sampled on the target face (its p-curve), and OCC's ``LocalAnalysis`` gives the
   angle before: an edge at or above ``sharp_deg`` is a crease by design and is refused;
3. the face's surface (converted exactly when it is not a B-spline, and raised in degree then when
   the order needs it), or its piece on the face's UV box (cut exactly), must have a side along the
   edge (a trimmed face whose edge crosses its surface's interior is refused, with the distance);
   the target is the target face's surface
   where the edge runs along one of its sides too, else samples of it along the edge
   (:class:`~occsurf.algorithms.manipulation.MatchTarget`: points, normals, cross curvatures from
   OCC's second derivatives);
4. the new face is the new surface bounded by the *old wires* (``BRep_Builder``; ``ShapeFix_Edge``
   adds the p-curves on the new surface, ``BRepLib::SameParameter`` sets the edges' tolerances),
   so the topology and the neighbours are untouched, and it replaces the old face
   (``BRepTools_ReShape``);
5. the result is checked by ``BRepCheck_Analyzer`` and measured by OCC's ``LocalAnalysis`` along the
   matched edge and along the face's other edges against their neighbours (``opposite_g1_max_deg``),
   not by our own code.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np
from OCP.BRep import BRep_Builder, BRep_Tool
from OCP.BRepCheck import BRepCheck_Analyzer
from OCP.BRepLib import BRepLib
from OCP.BRepTools import BRepTools, BRepTools_ReShape
from OCP.Geom import Geom_BSplineSurface
from OCP.gp import gp_Pnt, gp_Vec
from OCP.ShapeFix import ShapeFix_Edge
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_FORWARD, TopAbs_REVERSED, TopAbs_WIRE
from OCP.TopExp import TopExp, TopExp_Explorer
from OCP.TopLoc import TopLoc_Location
from OCP.TopoDS import TopoDS, TopoDS_Face
from OCP.TopTools import TopTools_IndexedMapOfShape

from occsurf.algorithms import tolerances
from occsurf.algorithms.errors import ArgumentTypeError, InvalidGeometryError
from occsurf.algorithms.kernel.surface import BSplineSurface
from occsurf.algorithms.kernel.trimmed import TrimmedSurface
from occsurf.algorithms.manipulation import MatchTarget, match_surface
from occsurf.algorithms.manipulation.match_targets import height_jets
from occsurf.algorithms.manipulation.matching import CONTINUITIES, side_along

from .. import _occ
from ..conversion.splines import from_occ, to_occ
from .joints import _edge_samples, assess_joint
from .refill_loop import SewnModel

__all__ = ["FaceMatch", "match_faces", "MATCH_SHARP_DEG", "SIDE_RTOL"]

#: An edge whose tangent planes meet at this angle (degrees) or more is a crease by design:
#: :func:`match_faces` refuses to make it G1 or smoother unless told a larger ``sharp_deg``. The
#: report's presets call edges sharp from 0.5 deg (CATIA) or 5 deg (mechanical); a match is asked
#: for explicitly, so only what no designer would call a kink is refused.
MATCH_SHARP_DEG: float = 15.0
#: A face's surface runs along the shared edge when every sample of the edge lies within this much
#: of one of its sides (relative to the model's size), or within 10x the edge's tolerance.
SIDE_RTOL: float = 1e-6
#: The shared edge must run from one end of the changed face's side to the other, to this fraction
#: of the side's parameter range (its ends sit within the model's tolerance of the corners, not on
#: them): a side that runs on past the edge (along other faces) would be matched to the target over
#: its whole length.
COVER_SLACK: float = 1e-3
#: Samples along the shared edge (plus 16 clustered at each end, as :func:`.joints.assess_joint`).
EDGE_SAMPLES: int = 81


@dataclass
class FaceMatch:
    """What :func:`match_faces` did, measured by OCC after the change.

    ``g0_max`` / ``g1_max_deg``: OCC's ``LocalAnalysis`` (``C0Value``, ``G1Angle``) along the shared
    edge after the change (``*_before``: the same before); ``g2_max_rel``: the relative curvature
    jump across the edge from the match itself (fraction; OCC has no such measure, its
    ``G2CurvatureGap`` differs); ``opposite_g1_max_deg``: the worst OCC G1 angle along the changed
    face's other shared edges against their neighbours after the change (``..._before``: before);
    ``faces_out``: the numbers of the changed face and the target in the returned model (sewing the
    model renumbers its faces); ``met``: the tolerances hold by the match's own measures and by
    OCC's along the edge (G0 within the larger of the tolerance and the edge's own).
    """

    face: int
    target: int
    continuity: str
    side: str
    target_side: str | None
    g0_max: float
    g1_max_deg: float
    g2_max_rel: float
    max_change: float
    knots_added: int
    met: bool
    valid: bool
    opposite_g1_max_deg: float
    g0_before: float
    g1_before_deg: float
    opposite_g1_before_deg: float
    faces_out: tuple[int, int] | None = None
    converted: str | None = None
    target_moved: bool = False
    notes: list[str] = field(default_factory=list)

    #: For each face of the input, its number in the returned model (-1: not found); not serialised.
    _numbering: list[int] = field(default_factory=list, repr=False)

    def to_dict(self) -> dict[str, Any]:
        out = asdict(self)
        out.pop("_numbering", None)
        for k, v in out.items():
            if isinstance(v, float) and not math.isfinite(v):
                out[k] = None
        return out


def _index(value: object, n: int, name: str) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise ArgumentTypeError(f"{name}: expected a face number, got {type(value).__name__}")
    i = int(value)
    if not 0 <= i < n:
        raise InvalidGeometryError(f"{name}: face {i} is out of range: the model has {n} faces (0..{n - 1})")
    return i


def _face_edges(model: SewnModel, i: int) -> list[Any]:
    """The edges of face ``i``, each once, degenerated ones left out."""
    out: list[Any] = []
    ex = TopExp_Explorer(model.faces[i], TopAbs_EDGE)
    while ex.More():
        e = TopoDS.Edge_s(ex.Current())
        ex.Next()
        if not BRep_Tool.Degenerated_s(e) and not any(e.IsSame(s) for s in out):
            out.append(e)
    return out


def _shared_edges(model: SewnModel, i: int, j: int) -> list[Any]:
    """The edges faces ``i`` and ``j`` share."""
    return [e for e in _face_edges(model, i) if any(f.IsSame(model.faces[j]) for f in model.edge_faces(e))]


def _other_edges(model: SewnModel, i: int, j: int) -> list[tuple[Any, Any]]:
    """(edge, neighbour face) for the edges of face ``i`` shared with faces other than ``j``."""
    return [(e, f) for e in _face_edges(model, i) for f in model.edge_faces(e)
            if not f.IsSame(model.faces[i]) and not f.IsSame(model.faces[j])]


def _surface_of(face: Any, order: int) -> tuple[BSplineSurface, TrimmedSurface | None, str | None]:
    """The face's surface as ours (and its trim), and what it was converted from if not a B-spline;
    a converted surface is raised to degree ``order`` where it is lower."""
    geom = BRep_Tool.Surface_s(face)
    conv = from_occ(face)
    trimmed = conv if isinstance(conv, TrimmedSurface) else None
    surface = conv.surface if isinstance(conv, TrimmedSurface) else conv
    assert isinstance(surface, BSplineSurface)
    converted = None if isinstance(geom, Geom_BSplineSurface) else type(geom).__name__.replace("Geom_", "")
    if converted is not None:
        for ax, d in enumerate(surface.degree):
            if d < order:
                surface = surface.elevate_degree(order - d, direction="uv"[ax])  # type: ignore[arg-type]
    return surface, trimmed, converted


def _restricted(surface: BSplineSurface, face: Any) -> BSplineSurface:
    """``surface`` cut (exactly, by knot insertion) to the face's UV box: a face trimmed a little
    inside its surface along iso-parameter lines then has its edges on the sides of the piece."""
    box = BRepTools.UVBounds_s(face)
    s = surface
    for ax, (lo, hi) in enumerate(((box[0], box[1]), (box[2], box[3]))):
        d = "uv"[ax]
        a, b = s.domain[ax]
        eps = 1e-9 * (b - a)
        if lo > a + eps and lo < b - eps:
            s = s.split(lo, direction=d)[1]  # type: ignore[arg-type]
        a, b = s.domain[ax]
        if hi < b - eps and hi > a + eps:
            s = s.split(hi, direction=d)[0]  # type: ignore[arg-type]
    return s


def _along(surface: BSplineSurface, face: Any, pts: np.ndarray, tol: float
           ) -> tuple[BSplineSurface, str | None, float, float]:
    """The surface (or its piece on the face's UV box) with a side along ``pts``, that side, the
    distance and the fraction of the side the points cover (the side is ``None`` when neither has
    one)."""
    side, dist, cover = side_along(surface, pts, tol)
    if side is not None and cover >= 1.0 - COVER_SLACK:
        return surface, side, dist, cover
    piece = _restricted(surface, face)
    if piece is surface:
        return surface, side, dist, cover
    side2, dist2, cover2 = side_along(piece, pts, tol)
    if side2 is not None and (side is None or cover2 > cover):
        return piece, side2, dist2, cover2
    return surface, side, min(dist, dist2), cover


def _sampled_target(face: Any, edge: Any) -> MatchTarget:
    """The target face along ``edge``: points, oriented normals and curvature across the edge, from
    OCC's derivatives of its surface at the edge's p-curve."""
    s, uvs, pts = _edge_samples(edge, face, EDGE_SAMPLES)
    # samples closer than round-off to the previous one (an edge that stalls at a pole) carry nothing
    step = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    keep = np.concatenate([[True], step > 1e-9 * max(float(np.ptp(pts, axis=0).max()), 1e-300)])
    uvs, pts = [uv for uv, k in zip(uvs, keep) if k], pts[keep]
    if len(pts) < 2:
        raise InvalidGeometryError("the shared edge is degenerate on the target face (all its samples coincide)")
    D = np.zeros((len(uvs), 3, 3, 3))
    for k, uv in enumerate(uvs):
        p, du, dv, duu, dvv, duv = gp_Pnt(), gp_Vec(), gp_Vec(), gp_Vec(), gp_Vec(), gp_Vec()
        s.D2(uv.X(), uv.Y(), p, du, dv, duu, dvv, duv)
        D[k, 0, 0], D[k, 1, 0], D[k, 0, 1] = p.Coord(), du.Coord(), dv.Coord()
        D[k, 2, 0], D[k, 1, 1], D[k, 0, 2] = duu.Coord(), duv.Coord(), dvv.Coord()
    n = np.cross(D[:, 1, 0], D[:, 0, 1])
    n /= np.linalg.norm(n, axis=1)[:, None]
    if face.Orientation() == TopAbs_REVERSED:
        n = -n
    t = np.gradient(pts, axis=0)
    t -= np.einsum("mc,mc->m", t, n)[:, None] * n
    t /= np.linalg.norm(t, axis=1)[:, None]
    E = np.stack([t, np.cross(n, t)], axis=1)
    H2, _ = height_jets(D, n, E)
    return MatchTarget(pts, n, H2[:, 1, 1])


def _replace_surface(face: Any, surface: BSplineSurface, tol: float) -> Any:
    """A face on ``surface`` bounded by ``face``'s own wires (same edges), oriented as ``face``.

    The face is made by ``BRep_Builder`` with the wires as the old face holds them (their stored
    orientations): ``BRepBuilderAPI_MakeFace(surface, wire, inside)`` re-orients the wire and the
    face then fails ``BRepCheck`` with ``BadOrientationOfSubshape``. Each edge gets its p-curve on
    the new surface by projection (``ShapeFix_Edge::FixAddPCurve``); ``BRepLib::SameParameter``
    then sets the edge tolerances to what the new surface needs."""
    geom = to_occ(surface)
    fwd = TopoDS.Face_s(face.Oriented(TopAbs_FORWARD))
    b = BRep_Builder()
    new = TopoDS_Face()
    with _occ.kernel_errors("rebuilding the matched face"):
        b.MakeFace(new, geom, TopLoc_Location(), BRep_Tool.Tolerance_s(fwd))
        ex = TopExp_Explorer(fwd, TopAbs_WIRE)
        while ex.More():
            b.Add(new, ex.Current())
            ex.Next()
        fix = ShapeFix_Edge()
        ex = TopExp_Explorer(new, TopAbs_EDGE)
        while ex.More():
            e = TopoDS.Edge_s(ex.Current())
            ex.Next()
            if not BRep_Tool.Degenerated_s(e):
                fix.FixAddPCurve(e, new, False, tol)
        BRepLib.SameParameter_s(new, tol, True)
    return TopoDS.Face_s(new.Reversed()) if face.Orientation() == TopAbs_REVERSED else new


def _worst_g1(pairs: list[tuple[Any, Any]], geom: Any) -> float:
    worst = 0.0
    for e, nb in pairs:
        _, g1 = assess_joint(e, nb, [geom])
        worst = max(worst, g1)
    return worst


@_occ.quiet_messages()
def match_faces(shape: Any, face: int, target: int, continuity: str = "G1", *, preserve_opposite: str = "G1",
                average: bool = False, tol_g0: float | None = None, tol_g1_deg: float = 0.01,
                tol_g2_rel: float = 0.01, refine: bool = True, sharp_deg: float = MATCH_SHARP_DEG
                ) -> tuple[FaceMatch, Any]:
    """Match face ``face`` of ``shape`` to face ``target`` along their shared edge.

    Parameters
    ----------
    shape : TopoDS_Shape or a build123d / cadquery shape
        The model; faces numbered as ``occsurf check`` / ``inspect`` number them.
    face, target : int
        The face to change and the face to match it to.
    continuity, preserve_opposite, average, tol_g0, tol_g1_deg, tol_g2_rel, refine
        As :func:`occsurf.algorithms.manipulation.match_surface` (``average=True`` changes both).
    sharp_deg : float
        Refuse edges whose tangent planes meet at this angle or more (a crease by design).

    Returns
    -------
    (FaceMatch, TopoDS_Shape)
        The report and the model with the face(s) replaced (same topology).

    Raises
    ------
    InvalidGeometryError
        A face number out of range, the same face twice, faces that share no edge, a sharp edge, an
        edge that does not run along a side of the face's surface; from the match: a continuity the
        degree cannot carry.
    """
    if isinstance(continuity, str) and continuity not in CONTINUITIES:
        raise InvalidGeometryError(f"continuity: expected one of {', '.join(CONTINUITIES)}, got {continuity!r}")
    order = CONTINUITIES.get(continuity, 0) if isinstance(continuity, str) else 0
    model = SewnModel(shape)
    n = len(model.faces)
    i, j = _index(face, n, "face"), _index(target, n, "target")
    if i == j:
        raise InvalidGeometryError(f"face and target are the same face ({i})")
    edges = _shared_edges(model, i, j)
    if not edges:
        raise InvalidGeometryError(f"faces {i} and {j} share no edge")
    fi, fj = model.faces[i], model.faces[j]
    geom_i = BRep_Tool.Surface_s(fi)
    g0_before = g1_before = 0.0
    for e in edges:
        a, b = assess_joint(e, fj, [geom_i])
        g0_before, g1_before = max(g0_before, a), max(g1_before, b)
    if order >= 1 and g1_before >= sharp_deg:
        raise InvalidGeometryError(
            f"the edge between faces {i} and {j} is sharp: its tangent planes meet at {g1_before:.3g} deg "
            f"(>= {sharp_deg:g}), a crease by design; asking it to be {continuity} needs a larger sharp_deg")
    pts = np.concatenate([_edge_samples(e, fj, EDGE_SAMPLES)[2] for e in edges])
    etol = max(BRep_Tool.Tolerance_s(e) for e in edges)
    tol_side = max(SIDE_RTOL * model.size, 10.0 * etol)
    S, _, converted = _surface_of(fi, order)
    S, side, dist, cover = _along(S, fi, pts, tol_side)
    if side is None:
        raise InvalidGeometryError(
            f"the edge between faces {i} and {j} does not run along a side of face {i}'s surface (it lies "
            f"{dist:.3g} from the nearest side, more than {tol_side:.3g}): the face is trimmed across its surface")
    if cover < 1.0 - COVER_SLACK:
        raise InvalidGeometryError(
            f"the edge between faces {i} and {j} covers {100 * cover:.3g} % of side {side} of face {i}'s surface: "
            f"the side runs on past the edge, and matching only part of a side is not supported")
    T, _, _ = _surface_of(fj, order)
    T, side_j, _, cover_j = _along(T, fj, pts, tol_side)
    if side_j is not None and cover_j < 1.0 - COVER_SLACK:
        side_j = None  # the target's side runs on past the edge: samples of it along the edge instead
    notes = []
    if side_j is None:
        if average:
            raise InvalidGeometryError(f"average needs the edge along a side of face {j}'s surface too; it is trimmed "
                                       "across it")
        tgt: BSplineSurface | MatchTarget = _sampled_target(fj, max(edges, key=lambda e: BRep_Tool.Tolerance_s(e)))
        notes.append(f"the edge is not a whole side of face {j}'s surface: matched to samples of it along the edge")
    else:
        tgt = T
    # a model's own gaps are its edges' tolerances: asking a match for less than that (1e-7 of the
    # size by default) only buys knots, or misses against samples interpolated to ~1e-7
    g0_tol = max(etol, tol_g0 if tol_g0 is not None else tolerances.MATCH_G0_RTOL * model.size)
    res = match_surface(S, tgt, side, continuity, preserve_opposite=preserve_opposite, average=average,
                        tol_g0=g0_tol, tol_g1_deg=tol_g1_deg, tol_g2_rel=tol_g2_rel, refine=refine)
    fit_tol = max(etol, res.max_change, 1e-7)
    new_i = _replace_surface(fi, res.surface, fit_tol)
    rs = BRepTools_ReShape()
    rs.Replace(fi, new_i)
    new_j = None
    if average and isinstance(res.target, BSplineSurface):
        new_j = _replace_surface(fj, res.target, fit_tol)
        rs.Replace(fj, new_j)
    with _occ.kernel_errors("replacing the matched face"):
        out = rs.Apply(model.shape)
    valid = bool(BRepCheck_Analyzer(out).IsValid())
    geom_new = BRep_Tool.Surface_s(new_i)
    nb = new_j if new_j is not None else fj
    g0 = g1 = 0.0
    for e in edges:
        a, b = assess_joint(e, nb, [geom_new])
        g0, g1 = max(g0, a), max(g1, b)
    # met: by the match's own measures *and* by OCC's along the real edge
    met = res.met and g0 <= g0_tol and (order < 1 or g1 <= tol_g1_deg)
    if res.met and not met:
        notes.append(f"the match meets its tolerances on the surface's side, but OCC measures G0 {g0:.3g} / G1 "
                     f"{g1:.3g} deg along the edge")
    others = _other_edges(model, i, j)
    index = TopTools_IndexedMapOfShape()
    TopExp.MapShapes_s(out, TopAbs_FACE, index)
    now = [new_i if k == i else new_j if (k == j and new_j is not None) else f for k, f in enumerate(model.faces)]
    numbering = [index.FindIndex(f) - 1 for f in now]
    pos = [numbering[i], numbering[j]]
    report = FaceMatch(
        face=i, target=j, continuity=continuity, side=side, target_side=side_j, g0_max=g0, g1_max_deg=g1,
        g2_max_rel=res.g2_max_rel, max_change=res.max_change, knots_added=res.knots_added, met=met,
        valid=valid, opposite_g1_max_deg=_worst_g1(others, geom_new), g0_before=g0_before,
        g1_before_deg=g1_before, opposite_g1_before_deg=_worst_g1(others, geom_i), converted=converted,
        target_moved=new_j is not None, notes=notes, faces_out=(pos[0], pos[1]))
    report._numbering = numbering
    return report, out
