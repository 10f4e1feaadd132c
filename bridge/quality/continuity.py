"""Continuity across the edges of a model: G0 gap, G1 angle, G2 and G3 jumps (course ch. 9, 11-2).

For every edge shared by two faces of a shell (``TopExp.MapShapesAndAncestors_s``), every seam,
and, with ``loose=True``, every pair of loose faces whose boundary edges coincide within
``match_tol`` (as Rhino's ``GlobalEdgeContinuity`` does for IGES data), :func:`edge_continuity`
samples the edge densely (Chebyshev-Lobatto points, which cluster at the ends where faces usually
misbehave), evaluates both faces at the ``(u, v)`` their p-curves give, and refines each measure's
worst point by a bounded golden-section search between the samples around the largest one.
Where the edge has no p-curve on one face, that face's ``(u, v)`` are the feet of the other face's
points on it (Gauss-Newton); for a geometrically matched pair, side 2's parameter on its own edge
is the foot of side 1's point on that edge, so ``g0`` is the distance between the two boundaries.

Speed: all faces and p-curves of the model are evaluated together (:mod:`._batch`: B-spline faces
stacked by degree, or numba's compiled per-surface kernel when available; elementary surfaces in
closed form, :mod:`~occsurf.bridge.conversion.occ_evaluators`), so the per-point cost is that of
NumPy arithmetic, not of a Python call per point. ``benchmarks/bench_continuity.py`` compares it with
``LocalAnalysis_SurfaceContinuity`` on the same points.

Measures at a point of the edge (``P_k``, oriented unit normal ``n_k`` of face ``k``; ``T`` the
edge tangent):

``g0``
    ``|P_1 - P_2|`` (model units).
``g1``
    the angle between ``n_1`` and ``n_2`` in degrees, the normals oriented as the faces are in the
    shell (``TopAbs_REVERSED`` flips ``S_u x S_v``). If the two faces run along the edge in the
    same direction their orientations disagree: that is reported as a *normal flip* and ``n_2`` is
    reversed before the angle is taken. (OCC's ``LocalAnalysis_SurfaceContinuity::G1Angle`` folds
    angles above 90 degrees instead; :func:`occ_fold` gives that value.)
``g2``
    ``|k_1 - k_2|``, where ``k_k`` is the normal curvature of face ``k`` across the edge, in the
    direction ``b_k = n_k x T`` (1/model units). For a G1 joint this is the only curvature that can
    jump: the normal curvature along ``T`` and the geodesic torsion are fixed by the shared edge and
    normals. ``g2_rel`` is CATIA's Connect Checker percentage ``100 |k_1 - k_2| / max(|k_1|, |k_2|)``
    (0 where both are below ``tolerances.CONTINUITY_CURVATURE_FLOOR`` / model size).
``g3``
    ``|k'_1 - k'_2|``, the jump of the derivative of that cross curvature along ``b``
    (1/model units^2), with ``g3=True`` only.

Both ``k_k`` and ``k'_k`` come from the normal section of face ``k`` in the plane ``(P, n_k, b_k)``:
writing it as a height ``h(x)`` over ``x`` along ``b_k``, ``k = h''(0)`` and ``k' = h'''(0)``,
obtained exactly from the partials of the surface by implicit differentiation (order by order in
``x``: ``J w_1 = (0, 1)``, ``Q_2 = S_ww(w_1, w_1)``, ``h'' = n.Q_2``;
``J w_2 = -(T.Q_2, b.Q_2)``, ``h''' = n.(3 S_ww(w_1, w_2) + S_www(w_1, w_1, w_1))``, where ``J`` is
the matrix of ``(T, b) . (S_u, S_v)``).

OCC's ``G2CurvatureGap`` is a different measure (half the jump of the principal curvatures when the
principal frames agree, with a rotation term); it is reported too, as ``g2_gap_occ``, computed from
our principal curvatures with OCC's formula: that is what the cross-validation against
``LocalAnalysis_SurfaceContinuity`` compares, on the same points.

Classification of an edge (the :class:`~.thresholds.Thresholds` of the chosen preset; the presets and
the classification are in :mod:`.thresholds`):

==============  ======================================================================
``degenerate``  a degenerated edge (collapsed side, pole), or one that could not be evaluated
                (``error`` says why)
``seam``        the same face on both sides (the measures are still those across the seam)
``gap``         ``g0 > g0`` tolerance: the faces do not meet
``sharp``       ``g1 >= sharp_deg``: a crease by design
``G0``          position continuous, tangency broken by less than ``sharp_deg`` but more than ``g1``
``G1``          tangent continuous, curvature jump above ``g2_rel`` (or ``g2_abs``)
``G2``          curvature continuous within the tolerances
==============  ======================================================================
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from occsurf.algorithms import tolerances
from occsurf.algorithms._validate import check_size
from occsurf.algorithms.errors import InvalidGeometryError

from ._engine import Engine, occ_fold
from ._pairs import Pair
from ._setup import build_engine
from .thresholds import Thresholds, classify_edge, resolve_thresholds, worst_measure

Array = NDArray[np.float64]

__all__ = [
    "EdgeReport",
    "Violation",
    "ContinuityResult",
    "edge_continuity",
    "check_edges",
    "occ_fold",
    "CLASSES",
]

# Defaults read at call time from the tolerance registry (override with
# ``occsurf.algorithms.tolerances.override(CONTINUITY_...=...)`` or the keywords):
# ``CONTINUITY_SAMPLES`` (33 dense samples per edge), ``CONTINUITY_REFINE_ITERATIONS`` (6
# golden-section steps per measure), ``CONTINUITY_MATCH_RTOL`` (``match_tol`` = 1e-4 of the model's
# bounding-box diagonal) and ``CONTINUITY_CURVATURE_FLOOR`` (curvatures below 1e-6 / model size
# count as zero for ``g2_rel``).
#: Every classification label, in decreasing order of severity.
CLASSES: tuple[str, ...] = ("degenerate", "gap", "sharp", "G0", "G1", "G2", "seam")

_MEASURES = ("g0", "g1", "g2", "g2_rel", "g3")


# ======================================================================================= reports
def _vec(x: Any) -> list[float] | None:
    if x is None:
        return None
    a = np.asarray(x, dtype=float)
    return [float(c) for c in a] if np.all(np.isfinite(a)) else None


def _num(x: float | None) -> float | None:
    return None if x is None or not math.isfinite(x) else float(x)


@dataclass(frozen=True)
class EdgeReport:
    """The continuity of one edge between two faces.

    Attributes
    ----------
    index : int
        Position in the list :func:`edge_continuity` returns.
    faces : (int, int)
        The two faces, numbered as ``occsurf inspect`` numbers them (equal for a seam).
    midpoint : ndarray, shape (3,)
        The edge's point at the middle of its parameter range.
    matched : str
        ``'topology'`` (a shared edge of the shell) or ``'geometry'`` (two loose faces' edges that
        coincide within ``match_tol``).
    g0_max : float
        Largest gap, model units.
    g1_max_deg : float
        Largest angle between the oriented normals, degrees.
    g2_max : float
        Largest jump of the cross normal curvature, 1/model units.
    g2_max_rel : float
        Largest relative jump in percent (CATIA's Connect Checker).
    g3_max : float or None
        Largest jump of the cross curvature's derivative, 1/model units^2 (``g3=True``).
    g2_gap_occ_max : float
        Largest value of OCC's ``G2CurvatureGap`` formula (for comparison with OCC).
    worst_point : ndarray, shape (3,)
        Where the measure that most exceeds its tolerance (of the preset given) is largest.
    worst_points : dict
        Per measure (``'g0'``, ``'g1'``, ``'g2'``, ``'g2_rel'``, ``'g3'``) its worst point.
    classification : str
        One of :data:`CLASSES` (see the module docstring).
    samples : int
        Points evaluated on this edge (dense samples plus the worst-point searches).
    normal_flip : bool
        The two faces' orientations disagree along the edge (their normals point to opposite
        sides): ``g1`` is measured with one of them reversed.
    length : float
        Length of the edge (polyline of the samples), model units.
    evaluators : (str, str)
        How each face was evaluated: ``'bspline'``, ``'analytic'`` or ``'occ'``.
    match_distance : float or None
        For ``matched == 'geometry'``: the largest distance found when matching.
    error : str or None
        Why nothing (or only part) could be measured.
    """

    index: int
    faces: tuple[int, int]
    midpoint: Array
    matched: str
    g0_max: float
    g1_max_deg: float
    g2_max: float
    g2_max_rel: float
    g3_max: float | None
    g2_gap_occ_max: float
    worst_point: Array
    worst_points: dict[str, Array] = field(repr=False)
    classification: str
    samples: int
    normal_flip: bool
    length: float
    evaluators: tuple[str, str]
    match_distance: float | None = None
    error: str | None = None
    edges: tuple[Any, Any] = field(default=(None, None), repr=False, compare=False)

    def to_json(self) -> dict[str, Any]:
        """The issue's report keys (``faces``, ``midpoint``, ``matched``, ``g0_max``, ``g1_max_deg``,
        ``g2_max``, ``g2_max_rel``, ``worst_point``) plus the other fields; non-finite numbers
        become ``null``."""
        return {
            "faces": [int(self.faces[0]), int(self.faces[1])],
            "midpoint": _vec(self.midpoint),
            "matched": self.matched,
            "g0_max": _num(self.g0_max),
            "g1_max_deg": _num(self.g1_max_deg),
            "g2_max": _num(self.g2_max),
            "g2_max_rel": _num(self.g2_max_rel),
            "worst_point": _vec(self.worst_point),
            "index": self.index,
            "g3_max": _num(self.g3_max),
            "g2_gap_occ_max": _num(self.g2_gap_occ_max),
            "classification": self.classification,
            "normal_flip": self.normal_flip,
            "samples": self.samples,
            "length": _num(self.length),
            "evaluators": list(self.evaluators),
            "match_distance": _num(self.match_distance),
            "worst_points": {k: _vec(v) for k, v in self.worst_points.items()},
            "error": self.error,
        }


@dataclass(frozen=True)
class Violation:
    """One edge breaking one tolerance of a :class:`~.thresholds.Thresholds`.

    ``measure`` is ``'g0'``, ``'g1'``, ``'g2_rel'``, ``'g2'``, ``'g3'`` or ``'normal_flip'``.
    """

    edge: int
    faces: tuple[int, int]
    measure: str
    value: float
    limit: float
    point: Array
    message: str

    def to_json(self) -> dict[str, Any]:
        return {"edge": self.edge, "faces": list(self.faces), "measure": self.measure, "value": _num(self.value),
                "limit": _num(self.limit), "point": _vec(self.point), "message": self.message}


class ContinuityResult(list):
    """The list of :class:`EdgeReport` :func:`edge_continuity` returns, with what it found on the way.

    Attributes
    ----------
    warnings : list of str
        E.g. "no shared edges and no edges matched within 0.01: nothing to check", faces that
        could not be evaluated, non-manifold edges.
    match_tol : float or None
        The matching tolerance used (``None`` when ``loose=False``).
    thresholds : Thresholds
    stats : dict
        Counts (edges by topology/geometry, free edges left unmatched) and timings (seconds).
    points : list of dict or None
        Per report, the dense samples it was measured on (``None`` if none): ``'t'`` (the edge's
        parameters on face ``faces[0]``), ``'s'`` (on the other edge, for geometric matches),
        ``'uv1'``, ``'uv2'`` ``(n, 2)``: the parameters on both faces, ``'P'`` ``(n, 3)`` the points
        on ``faces[0]``, and the measures there (``'g0'``, ``'g1'``, ``'g2'``, ``'g2_rel'``,
        ``'gap'``, with ``g3=True`` ``'g3'``), for cross-checks with OCC.
    """

    warnings: list[str]
    match_tol: float | None
    thresholds: Thresholds
    stats: dict[str, Any]
    points: list[dict[str, Array] | None]

    def to_json(self) -> list[dict[str, Any]]:
        return [r.to_json() for r in self]


# ======================================================================================= driver
def _chebyshev(n: int) -> Array:
    """``n`` Chebyshev-Lobatto points of [0, 1]: denser towards both ends."""
    return 0.5 * (1.0 - np.cos(np.pi * np.arange(n) / (n - 1)))


def _check_args(samples: Any, match_tol: Any) -> tuple[int, float | None]:
    if isinstance(samples, bool) or not isinstance(samples, (int, np.integer)) or samples < 3:
        raise InvalidGeometryError(f"samples: expected an integer >= 3, got {samples!r}")
    check_size((int(samples), 64), f"samples = {int(samples)}")  # per sample of an edge: both sides' partials
    if match_tol is not None:
        if isinstance(match_tol, bool) or not isinstance(match_tol, (int, float)) or not math.isfinite(match_tol) or match_tol <= 0:
            raise InvalidGeometryError(f"match_tol: expected a finite number > 0 (model units) or None, got {match_tol!r}")
        match_tol = float(match_tol)
    return int(samples) | 1, match_tol  # odd: the middle of the edge is a sample


def edge_continuity(model: Any, *, samples: int | None = None, g3: bool = False, loose: bool = True,
                    match_tol: float | None = None, preset: str | Thresholds = "catia",
                    refine: int | None = None, face_pairs: Any = None, model_size: float | None = None) -> ContinuityResult:
    """G0/G1/G2 (and G3) continuity of every edge between two faces of a model.

    Parameters
    ----------
    model : ImportedModel or TopoDS_Shape (or a build123d / cadquery shape)
        From :func:`~occsurf.bridge.read_step` / :func:`~occsurf.bridge.read_iges` (faces are
        numbered as there, i.e. as ``occsurf inspect`` prints them), or any shape (faces numbered in
        ``TopExp_Explorer`` order, each once).
    samples : int, optional
        Dense samples per edge (Chebyshev-Lobatto; made odd so that the middle is one), before the
        worst-point search. Default ``tolerances.CONTINUITY_SAMPLES`` (33).
    g3 : bool, optional
        Also measure the jump of the curvature derivative (needs third derivatives).
    loose : bool, optional
        Match the free edges of loose faces geometrically (IGES, face-by-face STEP exports).
    match_tol : float, optional
        Matching tolerance in model units; default ``tolerances.CONTINUITY_MATCH_RTOL`` (1e-4) times
        the diagonal of the model's bounding box. Stated in the result (``.match_tol``).
    preset : str or Thresholds, optional
        ``'catia'`` (default), ``'class-a'``, ``'mechanical'`` (see :data:`~.thresholds.PRESETS`) or your own
        :class:`~.thresholds.Thresholds`: used for ``classification`` and ``worst_point``.
    refine : int, optional
        Golden-section iterations of the worst-point search per measure (default
        ``tolerances.CONTINUITY_REFINE_ITERATIONS``, 6; 0 keeps the dense samples only).
    face_pairs : iterable of (int, int), optional
        Only the edges between these pairs of faces (in either order), e.g. chosen pairs of loose
        faces; default every pair.
    model_size : float, optional
        The diagonal the tolerances above are relative to; default :func:`~._setup.shape_size` of the shape
        as it is now (OCC's bounding box: of the triangulation where the faces are meshed, else of
        the geometry, a little larger).

    Returns
    -------
    ContinuityResult
        A list of :class:`EdgeReport` (topology pairs first, then geometric matches), with
        ``warnings``, ``match_tol``, ``thresholds`` and ``stats``. A face that cannot be evaluated
        makes its edges ``'degenerate'`` with an ``error``; the others are still measured.

    Raises
    ------
    InvalidGeometryError
        Bad ``samples``, ``match_tol``, ``preset``, ``refine``, ``face_pairs`` (not pairs of face
        indices of the model), or a ``model`` that is not a shape.
    """
    samples, match_tol = _check_args(tolerances.CONTINUITY_SAMPLES if samples is None else samples, match_tol)
    thresholds = resolve_thresholds(preset)
    iterations = tolerances.CONTINUITY_REFINE_ITERATIONS if refine is None else refine
    if isinstance(iterations, bool) or not isinstance(iterations, (int, np.integer)) or iterations < 0:
        raise InvalidGeometryError(f"refine: expected an integer >= 0, got {iterations!r}")
    clock = time.perf_counter()
    setup = build_engine(model, g3=g3, loose=loose, match_tol=match_tol, face_pairs=face_pairs, model_size=model_size)
    engine, faces, pairs, free, warnings = setup.engine, setup.faces, setup.pairs, setup.free, setup.warnings
    n_topology, tol, size, t_match = setup.n_topology, setup.match_tol, setup.size, setup.seconds_matching
    result = ContinuityResult()
    result.match_tol, result.thresholds = tol, thresholds
    t_measure = time.perf_counter()
    reports, result.points = _measure_all(engine, samples, int(iterations), thresholds)
    t_measure = time.perf_counter() - t_measure
    result.extend(reports)
    matched_free = {id(p.side1) for p in pairs if p.matched == "geometry"} | {id(p.side2) for p in pairs if p.matched == "geometry"}
    unmatched = sum(1 for s in free if id(s) not in matched_free)
    if not result:
        warnings.append("no shared edges" + (f" and no edges matched within {tol:.3g}" if loose else
                        " (loose=False: free edges were not matched)") + ": nothing to check")
    warnings += sorted(set(engine.face_errors.values()) - set(warnings))
    result.warnings = warnings
    result.stats = {"faces": len(faces), "topology": n_topology, "geometry": len(pairs) - n_topology,
                    "free_edges": len(free), "unmatched_free_edges": unmatched, "model_size": size,
                    "seconds": time.perf_counter() - clock, "seconds_matching": t_match,
                    "seconds_measuring": t_measure, "points": int(engine.evaluated.sum()),
                    "occ_evaluated_faces": sum(f.kind == "occ" for f in faces)}
    return result


_PHI = (math.sqrt(5.0) - 1.0) / 2.0


def _why_not(engine: Engine, p: Pair) -> str | None:
    """Why a pair cannot be measured, or ``None``."""
    if p.degenerate:
        return p.note or "degenerated edge"
    for side in (p.side1, p.side2):
        fd = engine.faces[side.face]
        if fd.evaluator is None:
            return fd.error
    if p.side1.pcurve is None:  # topology_pairs puts a lone p-curve on side 1
        return f"the edge has no p-curve on face {p.side1.face} nor on face {p.side2.face}"
    if p.side2.pcurve is None and p.matched == "geometry":
        return f"the edge has no p-curve on face {p.side2.face}"
    return None


def _golden(engine: Engine, pid: NDArray[np.intp], meas: list[str], which: NDArray[np.intp],
            a: Array, b: Array, iterations: int, best: dict[str, Array]) -> None:
    """Batched golden-section maximisation of measure ``meas[which[k]]`` of pair ``pid[k]`` on
    ``[a[k], b[k]]``; every evaluated point updates ``best`` (value, t, point per bracket)."""
    if iterations <= 0 or pid.size == 0:
        return
    rows = np.arange(pid.size)

    def f(x: Array) -> Array:
        M = engine.measure(pid, x)
        v = np.stack([M[m] for m in meas], axis=1)[rows, which]
        better = np.nan_to_num(v, nan=-np.inf) > np.nan_to_num(best["value"], nan=-np.inf)
        best["value"] = np.where(better, v, best["value"])
        best["t"] = np.where(better, x, best["t"])
        best["P"] = np.where(better[:, None], M["P"], best["P"])
        return np.nan_to_num(v, nan=-np.inf)

    c, d = b - _PHI * (b - a), a + _PHI * (b - a)
    fc, fd = f(c), f(d)
    for _ in range(iterations - 1):
        left = fc >= fd
        a, b = np.where(left, a, c), np.where(left, d, b)
        x = np.where(left, b - _PHI * (b - a), a + _PHI * (b - a))
        fx = f(x)
        c, d, fc, fd = (np.where(left, x, d), np.where(left, c, x), np.where(left, fx, fd), np.where(left, fc, fx))


def _measure_all(engine: Engine, samples: int, refine: int, th: Thresholds) -> tuple[list[EdgeReport], list]:
    pairs = engine.pairs
    why = [_why_not(engine, p) for p in pairs]
    good = np.array([i for i, w in enumerate(why) if w is None], dtype=np.intp)
    meas = ["g0", "g1", "g2", "g2_rel"] + (["g3"] if engine.third else [])
    s01 = _chebyshev(samples)
    first = np.array([pairs[i].first for i in good])
    last = np.array([pairs[i].last for i in good])
    T = first[:, None] + (last - first)[:, None] * s01[None, :]
    pid = np.repeat(good, samples)
    M = engine.measure(pid, T.reshape(-1), set_flip=True, gap=True) if good.size else {}
    n = good.size
    for r, i in enumerate(good):  # the dense samples start the projections of the refinement
        if pairs[i].matched == "geometry":
            pairs[i].t_table, pairs[i].s_table = T[r], M["s"][r * samples:(r + 1) * samples]
    grid = {k: M[k].reshape(n, samples) for k in meas + ["gap"]} if n else {}
    P = M["P"].reshape(n, samples, 3) if n else np.zeros((0, samples, 3))
    best = {}
    for m in meas:
        V = np.nan_to_num(grid[m], nan=-np.inf) if n else np.zeros((0, samples))
        i = V.argmax(axis=1) if n else np.zeros(0, dtype=np.intp)
        rows = np.arange(n)
        best[m] = {"value": grid[m][rows, i] if n else np.zeros(0), "t": T[rows, i] if n else np.zeros(0),
                   "P": P[rows, i] if n else np.zeros((0, 3)),
                   "a": T[rows, np.maximum(i - 1, 0)] if n else np.zeros(0),
                   "b": T[rows, np.minimum(i + 1, samples - 1)] if n else np.zeros(0)}
    if n and refine > 0:
        which = np.repeat(np.arange(len(meas)), n)
        allbest = {k: np.concatenate([best[m][k] for m in meas]) for k in ("value", "t", "P")}
        _golden(engine, np.tile(good, len(meas)), meas, which,
                np.concatenate([best[m]["a"] for m in meas]), np.concatenate([best[m]["b"] for m in meas]),
                refine, allbest)
        for j, m in enumerate(meas):
            for k in ("value", "t", "P"):
                best[m][k] = allbest[k][j * n:(j + 1) * n]
    row_of = {int(p): r for r, p in enumerate(good)}
    reports, points = [], []
    for idx, p in enumerate(pairs):
        row = row_of.get(idx)
        reports.append(_report(engine, idx, p, why[idx], row, best, grid, P, samples, th, meas))
        points.append(None if row is None else {
            "t": T[row], "s": M["s"].reshape(n, samples)[row], "uv1": M["uv1"].reshape(n, samples, 2)[row],
            "uv2": M["uv2"].reshape(n, samples, 2)[row], "P": P[row], **{k: grid[k][row] for k in grid}})
    return reports, points


def _report(engine: Engine, idx: int, p: Pair, why: str | None, r: int | None, best: dict, grid: dict,
            P: Array, samples: int, th: Thresholds, meas: list[str]) -> EdgeReport:
    faces = (p.side1.face, p.side2.face)
    kinds = (engine.faces[faces[0]].kind, engine.faces[faces[1]].kind)
    err = why
    if r is not None:
        bad = [engine.face_errors[f] for f in faces if f in engine.face_errors]
        if bad:
            err = "; ".join(bad)
    if r is None or err is not None or not np.any(np.isfinite(grid["g0"][r])):
        nan = float("nan")
        mid = _midpoint_fallback(p)
        return EdgeReport(idx, faces, mid, p.matched, nan, nan, nan, nan, None, nan, mid, {}, "degenerate", 0,
                          False, nan, kinds, p.match_distance, err or "no point of the edge could be evaluated",
                          (p.side1.edge, p.side2.edge))
    val = {m: float(best[m]["value"][r]) for m in meas}
    pts = {m: best[m]["P"][r] for m in meas}
    flip = bool(engine.flip[idx] < 0) if not p.seam else False
    length = float(np.nansum(np.linalg.norm(np.diff(P[r], axis=0), axis=1)))
    cls = classify_edge(p, val, th)
    worst = pts[worst_measure(val, th, cls)]
    g3 = val.get("g3") if engine.third else None
    return EdgeReport(idx, faces, P[r, samples // 2].copy(), p.matched, val["g0"], val["g1"], val["g2"],
                      val["g2_rel"], g3, float(np.nanmax(grid["gap"][r])) if np.any(np.isfinite(grid["gap"][r])) else float("nan"),
                      worst, pts, cls, int(engine.evaluated[idx]), flip, length, kinds, p.match_distance, None,
                      (p.side1.edge, p.side2.edge))


def _midpoint_fallback(p: Pair) -> Array:
    """The middle of the edge's 3-D curve through OCC (for edges that could not be measured)."""
    try:
        from OCP.BRepAdaptor import BRepAdaptor_Curve

        c = BRepAdaptor_Curve(p.side1.edge)
        return np.array(c.Value(0.5 * (c.FirstParameter() + c.LastParameter())).Coord())
    except Exception:  # noqa: BLE001
        return np.full(3, np.nan)


def check_edges(reports: list[EdgeReport], thresholds: str | Thresholds = "catia") -> list[Violation]:
    """Every tolerance of ``thresholds`` that an edge breaks.

    Rules: a gap above ``g0`` and a normal flip are always violations; an angle above ``g1_deg``
    is one unless the edge is a crease (``g1 >= sharp_deg``, by design); curvature (``g2_rel``,
    ``g2_abs``) and ``g3`` are checked on tangent-continuous edges only (a crease has no curvature
    continuity to keep). Degenerate edges (nothing measured) are skipped.

    Parameters
    ----------
    reports : list of EdgeReport
    thresholds : str or Thresholds
        A :data:`~.thresholds.PRESETS` name or your own.

    Returns
    -------
    list of Violation
        In edge order, then measure order.
    """
    th = resolve_thresholds(thresholds)
    out: list[Violation] = []
    for r in reports:
        if r.classification == "degenerate":
            continue
        val = {"g0": r.g0_max, "g1": r.g1_max_deg, "g2": r.g2_max, "g2_rel": r.g2_max_rel, "g3": r.g3_max}
        crease = not r.g1_max_deg < th.sharp_deg
        tangent = r.g1_max_deg <= th.g1_deg
        checks = [("g0", th.g0, True), ("g1", th.g1_deg, not crease), ("g2_rel", th.g2_rel, tangent),
                  ("g2", th.g2_abs, tangent), ("g3", th.g3, tangent)]
        units = {"g0": "", "g1": " deg", "g2_rel": " %", "g2": " /unit", "g3": " /unit^2"}
        for m, lim, applies in checks:
            v = val[m]
            if lim is None or v is None or not applies or not math.isfinite(v) or v <= lim:
                continue
            point = r.worst_points.get(m, r.worst_point)
            out.append(Violation(r.index, r.faces, m, float(v), float(lim), point,
                                 f"edge {r.index} (faces {r.faces[0]}-{r.faces[1]}): {m} {v:.4g}{units[m]} > "
                                 f"{lim:g}{units[m]} ({th.name})"))
        if r.normal_flip:
            out.append(Violation(r.index, r.faces, "normal_flip", 1.0, 0.0, r.midpoint,
                                 f"edge {r.index} (faces {r.faces[0]}-{r.faces[1]}): the faces' normals point to "
                                 "opposite sides (inconsistent orientation)"))
    return out
