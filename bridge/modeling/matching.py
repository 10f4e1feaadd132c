"""Match two faces of a model along their shared edge: G0-G3 (issue 29; course ch. 3-4).

:func:`match_faces` is CATIA's Match Surface / NX's Matching Edge on a model: face ``face`` (numbered
as ``occsurf check`` and ``inspect`` number them) is changed by
:func:`occsurf.algorithms.manipulation.match_surface` so that it meets face ``target`` with the asked
continuity along their shared edge, and is put back in place of the old face with its own wires.
:class:`FaceMatcher` does the same one edge after another on one :class:`.model_edits.ModelEdits`
(``occsurf repair``), keeping what does not change between attempts:

1. the model is sewn once; the shared edge(s) found;
2. the edge is sampled on the target face (its p-curve), and OCC's ``LocalAnalysis`` gives the
   angle before: an edge at or above ``sharp_deg`` is a crease by design and is refused;
3. the face's surface (converted exactly when it is not a B-spline, and raised in degree then when
   the order needs it), or its piece on the face's UV box (cut exactly), has a side along the
   edge; where it has none (a face trimmed across its surface, as most faces of solid modellers'
   files are), the face is matched G0 or G1 along the edge inside its surface
   (:func:`~occsurf.algorithms.manipulation.match_along`, at the edge's p-curve on a B-spline face,
   at the edge's points projected onto the exact conversion of an analytic one; G2 and G3 are
   refused there, with the reason); the target is the target face's surface
   where the edge runs along one of its sides too, else samples of it along the edge
   (:class:`~occsurf.algorithms.manipulation.MatchTarget`: points, normals, cross curvatures from
   OCC's second derivatives);
4. the new surface is measured by OCC's ``LocalAnalysis`` along the matched edge and along the
   face's other edges against their neighbours (``opposite_g1_max_deg``), not by our own code;
5. the new face is the new surface bounded by the *old wires*
   (:func:`.model_edits.replace_surface`), so the topology and the neighbours are untouched, and
   is checked by ``BRepCheck_Analyzer`` (:func:`match_faces`: the whole model too).

With ``strict=True`` (the repair) a match that moves the face more than ``max_change``, misses
its tolerances, leaves the face's other edges worse, or gives an invalid face is not made, and
each of these is decided before the work the next one needs.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np
from OCP.BRep import BRep_Tool
from OCP.BRepCheck import BRepCheck_Analyzer
from OCP.BRepTools import BRepTools
from OCP.gp import gp_Pnt, gp_Vec
from OCP.TopAbs import TopAbs_REVERSED

from occsurf.algorithms import tolerances
from occsurf.algorithms.errors import InvalidGeometryError
from occsurf.algorithms.fitting import project_points
from occsurf.algorithms.kernel.surface import BSplineSurface
from occsurf.algorithms.manipulation import MatchTarget, match_along, match_surface
from occsurf.algorithms.manipulation.match_targets import height_jets
from occsurf.algorithms.manipulation.matching import CONTINUITIES, side_along
from occsurf.algorithms.threads import blas_threads

from .. import _occ
from ..conversion.splines import to_occ
from .joints import assess_joint, edge_curve_points, edge_samples, surface_feet, surfaces_joint
from .model_edits import ModelEdits

__all__ = ["FaceMatch", "FaceMatcher", "match_faces", "MATCH_SHARP_DEG", "SIDE_RTOL"]
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
#: BLAS threads while a surface is matched: its systems are small dense SVDs (100..1000 rows,
#: 50..250 columns), which one thread does faster than two (300 x 80: 1.35 against 2.53 ms on the
#: 2-core test machine; the whole OCCT bearing's repair 63.6 s against 91.7 s, the same results).
MATCH_BLAS_THREADS: int = 1
#: Samples along the shared edge (plus 16 clustered at each end, as :func:`.joints.assess_joint`).
EDGE_SAMPLES: int = 81


@dataclass
class FaceMatch:
    """What :func:`match_faces` did, measured by OCC after the change.

    ``g0_max`` / ``g1_max_deg``: OCC's ``LocalAnalysis`` (``C0Value``, ``G1Angle``) along the shared
    edge after the change (``*_before``: the same before); ``g2_max_rel``: the relative curvature
    jump across the edge from the match itself (fraction; OCC has no such measure, its
    ``G2CurvatureGap`` differs); ``opposite_g1_max_deg``: the worst OCC G1 angle along the changed
    face's other shared edges against their neighbours after the change, at points of each edge's
    3-D curve projected onto both faces (``..._before``: before);
    ``faces_out``: the numbers of the changed face and the target in the returned model (sewing the
    model renumbers its faces); ``met``: the tolerances hold by the match's own measures and by
    OCC's along the edge (G0 within the larger of the tolerance and the edge's own); ``valid``:
    ``BRepCheck_Analyzer`` finds the new face (:func:`match_faces`: the whole model) valid. The
    measures a refused match did not reach are NaN.
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
    #: How far the face now lies from its surface before any change in this model (several
    #: matches of one face add up; :meth:`.model_edits.ModelEdits.change`); NaN where not reached.
    total_change: float = math.nan
    faces_out: tuple[int, int] | None = None
    converted: str | None = None
    target_moved: bool = False
    notes: list[str] = field(default_factory=list)
    #: Why the match was not made (``strict`` matches only; ``None``: the face was replaced).
    refused: str | None = None

    #: For each face of the input, its number in the returned model (-1: not found); not serialised.
    _numbering: list[int] = field(default_factory=list, repr=False)

    def to_dict(self) -> dict[str, Any]:
        out = asdict(self)
        out.pop("_numbering", None)
        for k, v in out.items():
            if isinstance(v, float) and not math.isfinite(v):
                out[k] = None
        return out


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


def _distinct(pts: np.ndarray) -> np.ndarray:
    """Mask of the samples ``pts`` (k, 3) that are not within round-off of the one before (an edge
    that stalls at a pole carries nothing there); refused where fewer than two are left."""
    step = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    keep = np.concatenate([[True], step > 1e-9 * max(float(np.ptp(pts, axis=0).max()), 1e-300)])
    if keep.sum() < 2:
        raise InvalidGeometryError("the shared edge is degenerate on the target face (all its samples coincide)")
    return keep


def _sampled_target(face: Any, edge: Any) -> MatchTarget:
    """The target face along ``edge``: points, oriented normals and curvature across the edge, from
    OCC's derivatives of its surface at the edge's p-curve."""
    s, uvs, pts = edge_samples(edge, face, EDGE_SAMPLES)
    keep = _distinct(pts)
    uvs, pts = [uv for uv, k in zip(uvs, keep) if k], pts[keep]
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


def _feet_on(surface: BSplineSurface, points: np.ndarray, start: np.ndarray, tol: float) -> np.ndarray:
    """``(u, v)`` of ``points`` on our ``surface`` (the exact conversion of an analytic face: the
    same parameter box as OCC's, another parametrisation inside it): Newton's projection from the
    face's own (u, v) ``start`` and from the nearest of a 48 x 48 grid, the nearer foot of the two
    (from the grid alone, points beside a periodic surface's seam stopped on its other side)."""
    (u0, u1), (v0, v1) = surface.domain
    us, vs = np.linspace(u0, u1, 48), np.linspace(v0, v1, 48)
    grid = surface.evaluate_grid(us, vs).reshape(-1, 3)
    k = np.argmin(((points[:, None, :] - grid[None]) ** 2).sum(-1), axis=1)
    a = project_points(surface, points, np.clip(start[:, 0], u0, u1), np.clip(start[:, 1], v0, v1))
    b = project_points(surface, points, us[k // 48], vs[k % 48])
    near = a[2] <= b[2]
    u, v, d = (np.where(near, x, y) for x, y in zip(a, b))
    if np.max(d) > tol:
        raise InvalidGeometryError(f"the shared edge lies {float(np.max(d)):.3g} off the face's converted surface "
                                   f"(more than {tol:.3g}); it cannot be matched inside it")
    return np.stack([u, v], 1)


def _inside_samples(face: Any, target: Any, edges: list[Any], converted: BSplineSurface | None = None
                    ) -> tuple[np.ndarray, MatchTarget]:
    """The shared ``edges`` sampled at the same parameters on both faces (their p-curves; a sewn
    edge is same-parameter): the (u, v) on ``face``'s surface and the target face's points and
    oriented normals there, consecutive samples closer than round-off dropped. ``converted``: our
    exact conversion of an analytic face, on which the points of ``face`` are found by projection
    (its parameters are not the p-curve's)."""
    uv, pts, nrm = [], [], []
    for e in edges:
        _, uvs_i, p_i = edge_samples(e, face, EDGE_SAMPLES)
        uv_i = np.array([[q.X(), q.Y()] for q in uvs_i])
        if converted is not None:
            tol = max(10.0 * BRep_Tool.Tolerance_s(e), 1e-9 * float(np.ptp(p_i, axis=0).max()))
            uv_i = _feet_on(converted, p_i, uv_i, tol)
        s, uvs_j, p = edge_samples(e, target, EDGE_SAMPLES)
        n = np.zeros_like(p)
        for k, q in enumerate(uvs_j):
            pt, du, dv = gp_Pnt(), gp_Vec(), gp_Vec()
            s.D1(q.X(), q.Y(), pt, du, dv)
            n[k] = du.Crossed(dv).Coord()
        n /= np.maximum(np.linalg.norm(n, axis=1), 1e-300)[:, None]
        uv.append(uv_i)
        pts.append(p)
        nrm.append(-n if target.Orientation() == TopAbs_REVERSED else n)
    UV, P, N = np.concatenate(uv), np.concatenate(pts), np.concatenate(nrm)
    keep = _distinct(P)
    return UV[keep], MatchTarget(P[keep], N[keep])


@dataclass
class _Pair:
    """What matching face i to face j needs that does not depend on the continuity asked."""

    edges: list[Any]
    error: InvalidGeometryError | None = None
    etol: float = 0.0
    g0_before: float = 0.0
    g1_before: float = 0.0
    surface: BSplineSurface | None = None
    side: str | None = None
    converted: str | None = None
    target_surface: BSplineSurface | None = None
    target_side: str | None = None
    sampled: MatchTarget | None = None
    #: A face trimmed across its surface: the edge's parameters on it and the target along it.
    inside: tuple[np.ndarray, MatchTarget] | None = None
    notes: list[str] = field(default_factory=list)


class FaceMatcher:
    """Faces of one model matched one edge after another (``occsurf repair``; course ch. 3-4).

    What an attempt learns about a pair of faces that the continuity asked does not change (the
    shared edges, the angle before, which side of each surface runs along the edge, the sampled
    target, the face's other edges before) is kept until either face, or a neighbour, is
    replaced: the repair tries G2 then G1, each face in turn, on the same pair.

    Parameters
    ----------
    edits : ModelEdits
        The model; :meth:`match` replaces its faces.
    """

    def __init__(self, edits: ModelEdits) -> None:
        self.edits = edits
        self._pairs: dict[tuple[int, ...], _Pair] = {}
        self._opposite: dict[tuple[int, ...], np.ndarray] = {}
        self._feet: dict[tuple[Any, int, int], tuple[np.ndarray, Any, np.ndarray]] = {}

    def _pair(self, i: int, j: int, order: int) -> _Pair:
        ed = self.edits
        conv_i, conv_j = ed.surface(i)[1], ed.surface(j)[1]
        key = (i, j, order if (conv_i or conv_j) else -1, ed.version[i], ed.version[j])
        if key in self._pairs:
            return self._pairs[key]
        edges = ed.shared_edges(i, j)
        pair = _Pair(edges)
        self._pairs[key] = pair
        if not edges:
            pair.error = InvalidGeometryError(f"faces {i} and {j} share no edge")
            return pair
        fi, fj = ed.faces[i], ed.faces[j]
        geom_i = BRep_Tool.Surface_s(fi)
        for e in edges:
            a, b = assess_joint(e, fj, [geom_i])
            pair.g0_before, pair.g1_before = max(pair.g0_before, a), max(pair.g1_before, b)
        pts = np.concatenate([edge_samples(e, fj, EDGE_SAMPLES)[2] for e in edges])
        pair.etol = max(BRep_Tool.Tolerance_s(e) for e in edges)
        tol_side = max(SIDE_RTOL * ed.size, 10.0 * pair.etol)
        S, side, dist, cover = _along(_elevated(*ed.surface(i), order), fi, pts, tol_side)
        pair.converted = conv_i
        if side is None:
            # trimmed across its surface: matched along the edge inside it (G0, G1)
            pair.surface, pair.side = ed.surface(i)[0], "inside"
            try:
                pair.inside = _inside_samples(fi, fj, edges, None if conv_i is None else pair.surface)
            except InvalidGeometryError as err:
                pair.error = err
                return pair
            pair.notes.append(f"the edge runs inside face {i}'s surface ({dist:.3g} from its nearest side): matched "
                              "along it (G0, G1)")
            return pair
        if cover < 1.0 - COVER_SLACK:
            pair.error = InvalidGeometryError(
                f"the edge between faces {i} and {j} covers {100 * cover:.3g} % of side {side} of face {i}'s "
                f"surface: the side runs on past the edge, and matching only part of a side is not supported")
            return pair
        pair.surface, pair.side = S, side
        T, side_j, _, cover_j = _along(_elevated(*ed.surface(j), order), fj, pts, tol_side)
        if side_j is not None and cover_j < 1.0 - COVER_SLACK:
            side_j = None  # the target's side runs on past the edge: samples of it along the edge instead
        pair.target_surface, pair.target_side = T, side_j
        if side_j is None:
            pair.notes.append(f"the edge is not a whole side of face {j}'s surface: matched to samples of it along "
                              "the edge")
        return pair

    def _others(self, i: int, j: int) -> list[tuple[Any, int]]:
        """(edge, neighbour) for the edges of face ``i`` shared with faces other than ``j``."""
        return [(e, k) for e in self.edits.edges(i) for k in self.edits.neighbours(e, i) if k != j]

    def _edges_g1(self, others: list[tuple[Any, int]], geom: Any) -> np.ndarray:
        """OCC's G1 angle (degrees, the worst of each edge) between the Geom surface ``geom`` and
        the neighbours along ``others``, at points of each edge's 3-D curve projected onto both
        surfaces: the same points before and after a change, whichever face's p-curve moved
        (sampled on one face's p-curve instead, the bearing's edge 75/193 measured 0.246 deg one
        way and 0.257 the other before any change). The points and their feet on each neighbour
        are kept until the neighbour is replaced."""
        kept = []
        for e, k in others:
            key = (e.TShape(), k, self.edits.version[k])
            if key not in self._feet:
                pts = edge_curve_points(e)
                s_k = BRep_Tool.Surface_s(self.edits.faces[k])
                self._feet[key] = (pts, s_k, surface_feet(s_k, pts))
            kept.append(self._feet[key])
        if not kept:
            return np.zeros(0)
        # every edge's points onto geom at once: one projector for the surface, not one per edge
        uv = np.split(surface_feet(geom, np.concatenate([pts for pts, _, _ in kept])),
                      np.cumsum([len(pts) for pts, _, _ in kept])[:-1])
        return np.array([surfaces_joint(s_k, uv_k, geom, uv_g)[1] for (_, s_k, uv_k), uv_g in zip(kept, uv)])

    def _others_before(self, i: int, others: list[tuple[Any, int]]) -> np.ndarray:
        ed = self.edits
        key = (i, *sorted({k for _, k in others}), *(ed.version[k] for k in sorted({i} | {k for _, k in others})))
        if key not in self._opposite:
            self._opposite[key] = self._edges_g1(others, BRep_Tool.Surface_s(ed.faces[i]))
        return self._opposite[key]

    @_occ.quiet_messages()
    def match(self, face: int, target: int, continuity: str = "G1", *, preserve_opposite: str = "G1",
              average: bool = False, tol_g0: float | None = None, tol_g1_deg: float = 0.01,
              tol_g2_rel: float = 0.01, refine: bool = True, sharp_deg: float = MATCH_SHARP_DEG,
              strict: bool = False, max_change: float | None = None, others_deg: float = 0.0,
              max_poles: int | None = None) -> FaceMatch:
        """Match face ``face`` to face ``target`` along their shared edge and replace it.

        Parameters as :func:`match_faces`, and:

        strict : bool
            Make the change only when it moves the face no more than ``max_change``, meets the
            tolerances (OCC's measure too), leaves the face's other edges no worse than they were
            or than ``others_deg`` (degrees, whichever is larger; 1e-6 deg of slack), and gives a
            face valid for ``BRepCheck_Analyzer``; else ``refused`` says which failed first.
        max_change : float, optional
            With ``strict``: the largest change allowed (model units), of this match and of the
            face's changes before it together (``total_change``).
        others_deg : float
            With ``strict``: the G1 angle the face's other edges may reach in any case.
        max_poles : int, optional
            The most poles along the side the match's refinement may reach
            (:func:`~occsurf.algorithms.manipulation.match_surface`).

        Returns
        -------
        FaceMatch
            ``faces_out`` and the numbering are not set: :meth:`ModelEdits.shape` makes the model.
        """
        if isinstance(continuity, str) and continuity not in CONTINUITIES:
            raise InvalidGeometryError(f"continuity: expected one of {', '.join(CONTINUITIES)}, got {continuity!r}")
        order = CONTINUITIES.get(continuity, 0) if isinstance(continuity, str) else 0
        ed = self.edits
        i, j = ed.index(face, "face"), ed.index(target, "target")
        if i == j:
            raise InvalidGeometryError(f"face and target are the same face ({i})")
        pair = self._pair(i, j, order)
        if pair.error is not None and not pair.edges:
            raise pair.error
        if order >= 1 and pair.g1_before >= sharp_deg:
            raise InvalidGeometryError(
                f"the edge between faces {i} and {j} is sharp: its tangent planes meet at {pair.g1_before:.3g} deg "
                f"(>= {sharp_deg:g}), a crease by design; asking it to be {continuity} needs a larger sharp_deg")
        if pair.error is not None:
            raise pair.error
        assert pair.surface is not None and pair.side is not None
        fj = ed.faces[j]
        if pair.inside is not None:
            if order >= 2 or average:
                raise InvalidGeometryError(
                    f"the edge between faces {i} and {j} runs inside face {i}'s surface (trimmed across it): "
                    + ("matching both faces (average) needs it along a side of each" if average else
                       f"{continuity} needs it along a side of the surface; G0 and G1 are matched inside"))
            tgt: BSplineSurface | MatchTarget = pair.inside[1]
        elif pair.target_side is None:
            if average:
                raise InvalidGeometryError(f"average needs the edge along a side of face {j}'s surface too; it is "
                                           "trimmed across it")
            if pair.sampled is None:
                pair.sampled = _sampled_target(fj, max(pair.edges, key=lambda e: BRep_Tool.Tolerance_s(e)))
            tgt = pair.sampled
        else:
            assert pair.target_surface is not None
            tgt = pair.target_surface
        # asked for 1e-7 of the size (or tol_g0), accepted within the edge's own tolerance where that
        # is larger: the model's own gaps are its edges' tolerances, and samples of a trimmed target
        # are interpolated to ~1e-7. Asked for the edge tolerance instead, the refinement stops
        # refining where the side is close enough and not where it turns: the bearing's face 75 to
        # face 193 ended at G1 0.0092 deg with 11 knots, asked for 1.6e-8 it meets 0.0004 with 7
        g0_ask = tol_g0 if tol_g0 is not None else tolerances.MATCH_G0_RTOL * ed.size
        g0_tol = max(pair.etol, g0_ask)
        # one BLAS thread: the systems are small, and threads cost more than they save (MATCH_BLAS_THREADS)
        with blas_threads(MATCH_BLAS_THREADS):
            if pair.inside is not None:
                assert isinstance(tgt, MatchTarget)
                res = match_along(pair.surface, tgt, pair.inside[0], continuity, tol_g0=g0_ask, tol_g1_deg=tol_g1_deg,
                                  refine=refine, max_poles=max_poles)
            else:
                res = match_surface(pair.surface, tgt, pair.side, continuity, preserve_opposite=preserve_opposite,
                                    average=average, tol_g0=g0_ask, tol_g1_deg=tol_g1_deg, tol_g2_rel=tol_g2_rel,
                                    refine=refine, max_poles=max_poles)
        # the match's own measures, G0 within the accepted tolerance
        own_met = bool(res.g0_max <= g0_tol and (order < 1 or res.g1_max_deg <= tol_g1_deg)
                       and (order < 2 or np.nan_to_num(res.g2_max_rel) <= tol_g2_rel))
        nan = math.nan
        report = FaceMatch(
            face=i, target=j, continuity=continuity, side=pair.side, target_side=pair.target_side, g0_max=nan,
            g1_max_deg=nan, g2_max_rel=res.g2_max_rel, max_change=res.max_change, knots_added=res.knots_added,
            met=False, valid=False, opposite_g1_max_deg=nan, g0_before=pair.g0_before,
            g1_before_deg=pair.g1_before, opposite_g1_before_deg=nan, converted=pair.converted,
            notes=list(pair.notes))
        # the face may have been changed before (another of its edges): the limit is on the sum
        report.total_change = max(res.max_change, ed.change(i, res.surface))
        if strict and max_change is not None and report.total_change > max_change:
            report.refused = (f"would move by {res.max_change:.3g} > {max_change:.3g}" if res.max_change > max_change
                              else f"would move it by {report.total_change:.3g} in all > {max_change:.3g} (changed "
                              f"before by {ed.change(i):.3g})")
            return report
        fit_tol = max(pair.etol, res.max_change, 1e-7)
        surfaces = {i: res.surface}
        if average and isinstance(res.target, BSplineSurface):
            surfaces[j] = res.target
            report.target_moved = True
        geoms = {k: to_occ(s) for k, s in surfaces.items()}
        others = self._others(i, j)
        if report.target_moved:
            # the edge is sampled on the target face: the moved one, made first (the face's other
            # edges measured before that, on its old surface)
            before = self._others_before(i, others)
            report.valid = ed.replace(surfaces, fit_tol, geoms=geoms, keep_invalid=True)
        g0 = g1 = 0.0
        for e in pair.edges:
            a, b = assess_joint(e, ed.faces[j], [geoms[i]])
            g0, g1 = max(g0, a), max(g1, b)
        # met: by the match's own measures *and* by OCC's along the real edge
        met = own_met and g0 <= g0_tol and (order < 1 or g1 <= tol_g1_deg)
        report.g0_max, report.g1_max_deg, report.met = g0, g1, met
        if own_met and not met:
            report.notes.append(f"the match meets its tolerances on the surface's side, but OCC measures G0 "
                                f"{g0:.3g} / G1 {g1:.3g} deg along the edge")
        if strict and not met:
            report.refused = f"tolerances not met (G1 {g1:.3g} deg)"
            return report
        if not report.target_moved:
            before = self._others_before(i, others)
        after = self._edges_g1(others, geoms[i])
        report.opposite_g1_before_deg = float(before.max(initial=0.0))
        report.opposite_g1_max_deg = float(after.max(initial=0.0))
        worse = np.flatnonzero(after > np.maximum(before, others_deg) + 1e-6)
        if strict and worse.size:
            # a repair never makes a smooth edge worse than it was (or than the preset allows); each
            # edge on its own (the bearing's face 84: its edge to face 85 went from 0.0087 to 0.14 deg
            # while the worst of its edges stayed 0.234)
            n = int(worse[np.argmax(after[worse] - before[worse])])
            report.refused = (f"its edge to face {others[n][1]} would go from {before[n]:.3g} to {after[n]:.3g} deg"
                              + (f" ({worse.size} edges worse)" if worse.size > 1 else ""))
            return report
        if not report.target_moved:
            report.valid = ed.replace(surfaces, fit_tol, geoms=geoms, keep_invalid=not strict)
            if not report.valid and strict:
                report.refused = "the result is not valid (BRepCheck)"
        return report


def _elevated(surface: BSplineSurface, converted: str | None, order: int) -> BSplineSurface:
    """A converted surface raised to degree ``order`` where it is lower (a B-spline one as it is)."""
    if converted is not None:
        for ax, d in enumerate(surface.degree):
            if d < order:
                surface = surface.elevate_degree(order - d, direction="uv"[ax])  # type: ignore[arg-type]
    return surface


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
        The report and the model with the face(s) replaced (same topology), whatever the measures;
        ``valid`` is ``BRepCheck_Analyzer`` on the whole model.

    Raises
    ------
    InvalidGeometryError
        A face number out of range, the same face twice, faces that share no edge, a sharp edge, G2
        or G3 (or ``average``) along an edge inside the face's surface, a side that runs on past the
        edge; from the match: a continuity the degree cannot carry.
    """
    if isinstance(continuity, str) and continuity not in CONTINUITIES:
        raise InvalidGeometryError(f"continuity: expected one of {', '.join(CONTINUITIES)}, got {continuity!r}")
    edits = ModelEdits(shape)
    report = FaceMatcher(edits).match(
        face, target, continuity, preserve_opposite=preserve_opposite, average=average, tol_g0=tol_g0,
        tol_g1_deg=tol_g1_deg, tol_g2_rel=tol_g2_rel, refine=refine, sharp_deg=sharp_deg)
    out, numbering = edits.shape()
    report.valid = report.valid and bool(BRepCheck_Analyzer(out).IsValid())
    report._numbering = numbering
    report.faces_out = (numbering[report.face], numbering[report.target])
    return report, out
