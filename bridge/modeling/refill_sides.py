"""The hole's sides: curves and fitted cross fields handed to the fill (course §8-3, §7-2).

:func:`refill_sides` turns the hole's loop of edges into the sides of
:func:`occsurf.algorithms.topology.nsided.fill_hole` and of the plates: the edge curves oriented
along the loop and made to meet exactly (:func:`_oriented_curves`, :func:`_snap_ends`); edges meeting
at flat corners grouped into one side (:func:`_groups`) and joined into one curve (:func:`_joined`,
else fitted: :func:`_merged_curve`); a side off its neighbours' traces replaced by one that follows
them (:func:`.refill_traces.follow_traces`); a side of uneven parameter speed re-fitted by arc length
(:func:`_even_speed`); the cross fields fitted to the neighbours' normals
(:func:`~occsurf.algorithms.topology.nsided_sides.side_from_normals`) after the corners' treatment
(:func:`_corner_treatment`). Part of the refill of :mod:`.refill`.
"""

from __future__ import annotations

from typing import Any, cast

import numpy as np

from occsurf.algorithms import tolerances
from occsurf.algorithms.errors import InvalidGeometryError
from occsurf.algorithms.kernel.curve import BSplineCurve
from occsurf.algorithms.topology.nsided import closest_parameters
from occsurf.algorithms.topology.nsided_sides import (
    blend_normals,
    corner_normals,
    fit_boundary,
    side_from_normals,
    turn_end_tangent,
)

from ..conversion.splines import from_occ
from .refill_traces import TRACE_SAMPLES_PER_POLE, edge_normals, follow_traces, trace, unwrap_seam

__all__ = ["refill_sides", "EVEN_SPEED_RATIO"]

#: A side curve whose parameter speed ``|C'(t)|`` varies by more than this factor is re-fitted by
#: arc length (:func:`_even_speed`): the central split's patches take their u-parameter and knots
#: from the side, so a side crawling over half its domain and racing over the rest (a 152-pole
#: degree-7 thread edge of the M6 screw: 13.9) crowds the patch's iso-lines and spans at one end.
#: The folds first blamed on this came from the cross field keeping knot spans that hold no
#: sample (fixed in ``nsided_sides._sampled_knots``); the re-fit stays because it leaves far fewer
#: poles (screw 26: 152 -> 35, its fill 9x faster) and evenly spaced iso-lines.
EVEN_SPEED_RATIO: float = 3.0


def _oriented_curves(edges: list[Any]) -> list[Any]:
    """The loop's edge curves, each running from the previous one's end: the first ends where the
    next one touches it, every later one starts where the one before it ends (a walk along the
    chain). Deciding each curve by its next neighbour alone cannot work on a two-edge loop (a line
    and an arc: both ends of each touch the other), where both curves kept their direction and the
    sides were mm off their traces (screw face 24)."""
    curves = [cast(BSplineCurve, from_occ(e)) for e in edges]  # an edge's curve
    n = len(curves)
    ends = [(c.evaluate(c.domain[0]), c.evaluate(c.domain[1])) for c in curves]
    a0, a1 = ends[0]
    b0, b1 = ends[1 % n]
    d_end = min(np.linalg.norm(a1 - b0), np.linalg.norm(a1 - b1))
    d_start = min(np.linalg.norm(a0 - b0), np.linalg.norm(a0 - b1))
    out = [curves[0] if d_end <= d_start else curves[0].reverse()]
    for k in range(1, n):
        prev = out[-1].evaluate(out[-1].domain[1])
        c0, c1 = ends[k]
        out.append(curves[k] if np.linalg.norm(c0 - prev) <= np.linalg.norm(c1 - prev) else curves[k].reverse())
    return _snap_ends([c.clamp() for c in out])


def _snap_ends(curves: list[Any]) -> list[Any]:
    """Make consecutive curves meet exactly: the end pole of each curve and the start pole of the
    next move to their midpoint (the gap is the model's vertex tolerance; the curves move by half
    of it at most, at their ends only). A curve of 4 or more poles moves its second (last but one)
    pole with its end pole, so its end tangent keeps its direction: moving the end pole alone turns
    it by the gap over the first leg (bearing face 181: 8.4e-7 over 8.4e-6, 0.32 deg out of the
    neighbour's plane at the corner, where no fill can then be G1)."""
    n = len(curves)
    P = [np.array(c.control_points, float) for c in curves]
    for k in range(n):
        j = (k + 1) % n
        mid = 0.5 * (P[k][-1] + P[j][0])
        if len(P[k]) >= 4:
            P[k][-2] += mid - P[k][-1]
        if len(P[j]) >= 4:
            P[j][1] += mid - P[j][0]
        P[k][-1], P[j][0] = mid, mid
    return [type(c)(c.degree, c.knots, p, c.weights) for c, p in zip(curves, P)]


def _groups(curves: list[Any]) -> list[list[int]]:
    """Consecutive edges meeting at flat corners (tangents within FILL_MIN_CORNER_ANGLE) as one side."""
    n = len(curves)
    flat = []
    for k in range(n):
        a, b = curves[k], curves[(k + 1) % n]
        ta = a.derivatives(np.array([a.domain[1]]), 1)[0, 1]
        tb = b.derivatives(np.array([b.domain[0]]), 1)[0, 1]
        cosang = float(ta @ tb / max(np.linalg.norm(ta) * np.linalg.norm(tb), 1e-300))
        flat.append(np.degrees(np.arccos(np.clip(cosang, -1, 1))) < tolerances.FILL_MIN_CORNER_ANGLE)
    if all(flat):
        return [list(range(n))]
    start = next(k for k in range(n) if not flat[k - 1])  # a real corner precedes edge `start`
    groups: list[list[int]] = []
    for j in range(n):
        k = (start + j) % n
        if groups and flat[k - 1]:
            groups[-1].append(k)
        else:
            groups.append([k])
    return groups


def _merged_curve(curves: list[Any], size: float) -> tuple[Any, float]:
    """One cubic through a chain of tangent-continuous curves, aiming at FILL_FIT_G0 * size, and
    its largest distance from their samples (:data:`TRACE_SAMPLES_PER_POLE` per pole of each, at
    least ``FILL_MERGE_MIN_SAMPLES``, 121; up to ``FILL_FIT_MAX_SPANS`` knot spans per curve). The M6 screw's thread root, 8
    helix turns of 51..65 poles each, was 1e-4 off with 121 samples and 256 spans for all of them."""
    joined = _joined(curves, tolerances.FILL_FIT_G0 * size)
    if joined is not None:
        return joined, 0.0
    pts: list[np.ndarray] = []
    par: list[np.ndarray] = []
    s0 = 0.0
    for c in curves:
        lo, hi = c.domain
        count = max(int(tolerances.FILL_MERGE_MIN_SAMPLES), TRACE_SAMPLES_PER_POLE * len(c.control_points))
        t = np.linspace(lo, hi, count)
        p = c.evaluate(t)
        arc = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))]
        keep = slice(1, None) if pts else slice(None)
        pts.append(p[keep])
        par.append(s0 + arc[keep])
        s0 += arc[-1]
    return fit_boundary(np.concatenate(par), np.concatenate(pts), tolerances.FILL_FIT_G0 * size,
                        max_spans=int(tolerances.FILL_FIT_MAX_SPANS) * len(curves))


def _joined(curves: list[Any], tol: float) -> Any | None:
    """A chain of curves as one B-spline, exactly (None when two do not meet within ``FILL_JOIN_GAP * tol``,
    ``1e-3 * tol``).

    Each is raised to the highest degree ``p`` and mapped to a parameter interval as long as its arc
    length (so the speed of the whole is as even as its pieces'); rational pieces keep their
    weights, scaled so that the pole shared at a joint has one weight (a rational curve is unchanged
    by scaling all its weights); the joints become knots of multiplicity ``p`` (the chain is
    tangent-continuous geometrically: a flat corner). Fitting one cubic through such a chain
    instead left bearing pair [9, 24]'s merged sides 4.1e-9 off exact arcs that OCC's filler
    reproduced to 2e-17."""
    p = max(c.degree for c in curves)
    parts = [c.elevate_degree(p - c.degree) if c.degree < p else c for c in curves]
    for a, b in zip(parts, parts[1:]):
        if np.linalg.norm(a.evaluate(a.domain[1]) - b.evaluate(b.domain[0])) > tolerances.FILL_JOIN_GAP * tol:
            return None
    lengths = []
    for c in parts:
        lo, hi = c.domain
        P = c.evaluate(np.linspace(lo, hi, int(tolerances.FILL_JOIN_LENGTH_SAMPLES)))
        lengths.append(float(np.linalg.norm(np.diff(P, axis=0), axis=1).sum()) or 1.0)
    bounds = np.r_[0.0, np.cumsum(lengths)] / sum(lengths)
    parts = [c.reparametrize(float(lo), float(hi)) for c, lo, hi in zip(parts, bounds[:-1], bounds[1:])]
    rational = any(c.is_rational for c in parts)
    knots = [parts[0].knots[:-1]]
    poles = [parts[0].control_points]
    weights = [parts[0].weights if parts[0].is_rational else np.ones(len(parts[0].control_points))]
    for c in parts[1:]:
        w = c.weights if c.is_rational else np.ones(len(c.control_points))
        w = w * (weights[-1][-1] / w[0])
        knots.append(c.knots[p + 1:-1] if c is not parts[-1] else c.knots[p + 1:])
        poles.append(c.control_points[1:])
        weights.append(w[1:])
    if len(parts) == 1:
        knots = [parts[0].knots]
    K = np.concatenate(knots)
    return BSplineCurve(p, K, np.concatenate(poles), np.concatenate(weights) if rational else None)


def _even_speed(curve: Any, tol: float, ratio: float = EVEN_SPEED_RATIO) -> Any:
    """``curve`` re-fitted as a cubic of its arc length where its speed is uneven (course §7-2,
    chord-length/arc-length parametrisation; least squares :func:`fit_boundary`).

    The arc length comes from ``FILL_SPEED_GAUSS_POINTS``-point (5) Gauss-Legendre on the speed between
    dense samples (at least ``FILL_SPEED_SAMPLES``, 1024, and ``FILL_SPEED_SAMPLES_PER_SPAN``, 16, per
    knot span); the cubic, on ``[0, 1]``, interpolates both ends exactly (the sides still
    meet) and is accepted only when it lies within ``tol`` of the curve at the samples *and*
    half-way between them (compared at equal arc length: a parametric distance, which bounds the
    geometric one). Otherwise, or when the speed varies by at most ``ratio``, the curve is
    returned unchanged.
    """
    lo, hi = curve.domain
    spans = max(int(np.unique(curve.knots).size) - 1, 1)
    count = max(int(tolerances.FILL_SPEED_SAMPLES), int(tolerances.FILL_SPEED_SAMPLES_PER_SPAN) * spans)
    t = np.unique(np.r_[np.linspace(lo, hi, count + 1), curve.knots[(curve.knots > lo) & (curve.knots < hi)]])
    speed = np.linalg.norm(curve.derivatives(t, 1)[:, 1], axis=1)
    if speed.max() <= ratio * speed.min():
        return curve
    x, w = np.polynomial.legendre.leggauss(int(tolerances.FILL_SPEED_GAUSS_POINTS))
    h = 0.5 * np.diff(t)
    q = (0.5 * (t[:-1] + t[1:]))[:, None] + h[:, None] * x[None, :]
    dq = np.linalg.norm(curve.derivatives(q.ravel(), 1)[:, 1], axis=1).reshape(q.shape)
    arc = np.r_[0.0, np.cumsum(h * (dq @ w))]
    keep = np.r_[True, np.diff(arc) > tolerances.FILL_SPEED_ZERO * arc[-1]]  # a zero-speed stretch adds no sample
    s, P = arc[keep] / arc[-1], curve.evaluate(t[keep])
    try:
        fit, err = fit_boundary(s, P, tol)
    except InvalidGeometryError:
        return curve
    tm = 0.5 * (t[keep][:-1] + t[keep][1:])
    hm = 0.5 * (tm - t[keep][:-1])
    qm = (0.5 * (t[keep][:-1] + tm))[:, None] + hm[:, None] * x[None, :]
    dqm = np.linalg.norm(curve.derivatives(qm.ravel(), 1)[:, 1], axis=1).reshape(qm.shape)
    sm = (arc[keep][:-1] + hm * (dqm @ w)) / arc[-1]
    between = np.linalg.norm(fit.evaluate(sm) - curve.evaluate(tm), axis=1)
    if err > tol or between.max() > tol:
        return curve
    return fit


def _corner_treatment(curves: list[Any], fields: list[tuple[np.ndarray, np.ndarray]],
                      g1: list[tuple[bool, bool]] | None = None, tol: float = 0.0
                      ) -> tuple[list[Any], list[tuple[np.ndarray, np.ndarray]]]:
    """Where a side's normal at a hole corner leaves the corner's plane (spanned by the two side
    tangents: the only plane a fill can have there), turn it into that plane over
    ``tolerances.FILL_CORNER_BLEND`` of the side (:func:`blend_normals`). This happens at the
    corners of sharp sides taken from two different removed faces, and where two neighbours meet
    at a sharp edge at the corner: no surface is G1 to both there, and the G1 lost near that corner
    is what the per-edge measurement reports. Elsewhere the fields are left as they are.

    Before that, at a corner between a side asking G1 and one asking only G0 (``g1``: per side,
    whether its first and its last edge ask G1), the G0 side's end tangent is turned into the G1
    neighbour's plane (:func:`turn_end_tangent`), the side moving by at most
    ``tolerances.FILL_CORNER_TURN_G0 * tol`` (``tol``: the G0 target): the corner plane is then the
    neighbour's and the G1 side keeps its neighbour's normals up to the corner. Left as they were,
    the M6 screw's faces [22, 23] and [23, 26] cost 0.767 deg at such a corner (the tangent's angle
    out of the plane: no fill through the curves does better; OCC's MakeFilling, 2e-3 off the
    boundary, 0.70 / 0.67); turned, 0.0017 / 0.0016 deg, the G0 side 2.7e-7 off (1.9e-6 allowed).

    Returns the (possibly turned) curves and the treated fields."""
    n = len(curves)
    curves = list(curves)
    if g1 is not None and tol > 0 and n > 1:
        budget = tolerances.FILL_CORNER_TURN_G0 * tol
        for i in range(n):
            j = (i + 1) % n  # the corner where side i ends and side j starts
            if g1[i][1] and not g1[j][0]:
                curves[j] = turn_end_tangent(curves[j], 0, fields[i][1][-1], budget)[0]
            elif g1[j][0] and not g1[i][1]:
                curves[i] = turn_end_tangent(curves[i], 1, fields[j][1][0], budget)[0]
    t_end = [c.derivatives(np.array([c.domain[1]]), 1)[0, 1] for c in curves]
    t_start = [c.derivatives(np.array([c.domain[0]]), 1)[0, 1] for c in curves]
    out = []
    for i, (c, (s, N)) in enumerate(zip(curves, fields)):
        lo, hi = c.domain
        ref = 0.5 * (N[0] + fields[i - 1][1][-1])
        start = corner_normals(t_end[i - 1], t_start[i], ref)[0]
        ref = 0.5 * (N[-1] + fields[(i + 1) % n][1][0])
        end = corner_normals(t_end[i], t_start[(i + 1) % n], ref)[0]
        off = max(_angle(N[0], start), _angle(N[-1], end))
        tol_deg = tolerances.FILL_CORNER_NORMAL_DEG
        if off > tol_deg:
            N = blend_normals((s - lo) / (hi - lo), N, start if _angle(N[0], start) > tol_deg else N[0],
                              end if _angle(N[-1], end) > tol_deg else N[-1], tolerances.FILL_CORNER_BLEND)
        out.append((s, N))
    return curves, out


def _angle(a: np.ndarray, b: np.ndarray) -> float:
    """Angle (degrees) between two directions, sign-free."""
    return float(np.degrees(np.arctan2(np.linalg.norm(np.cross(a, b)), abs(float(a @ b)))))


def refill_sides(edges: list[Any], nbs: list[Any], owners: list[Any], size: float, follow_neighbour: bool = True
                 ) -> tuple[list[Any], list[int], list[bool], list[float]]:
    """HoleSide data of the hole, fitted cross fields; edges at flat corners merged into one side.

    With ``follow_neighbour`` a side whose edge curve lies farther than ``FILL_FIT_G0 * size`` from
    its neighbour's trace (the model's edge tolerance), or whose corners do, follows the traces (a
    fitted cubic) instead, and the sides meet where the neighbours' traces do
    (:func:`follow_traces`).

    Returns
    -------
    sides : list of HoleSide
    side_of_edge : list of int
        The side each edge lies on.
    g1 : list of bool
        Per edge: G1 to the neighbour asked (the original joint was tangent-continuous).
    fit : list of float
        Per side: the fitted field's angle to the neighbours' planes (degrees).
    """
    curves, groups, side_of_edge, bounds, traces = _side_curves(edges, nbs, size)
    if follow_neighbour:
        bounds = _followed(edges, nbs, size, curves, groups, bounds, traces)
    return _finish(edges, nbs, owners, size, groups, side_of_edge, bounds)


def refill_side_variants(edges: list[Any], nbs: list[Any], owners: list[Any], size: float
                         ) -> list[tuple[bool, tuple[list[Any], list[int], list[bool], list[float]] | InvalidGeometryError]]:
    """:func:`refill_sides` with ``follow_neighbour`` ``True`` then ``False``, sharing the work both do.

    The side curves and the neighbours' traces are computed once. Where following the traces keeps
    every side curve (each lies within ``FILL_FIT_G0 * size`` of its traces and corners: every
    G0-exact hole), the two variants are the same sides, and only the first is returned: its fills
    would be built, measured and scored twice for nothing (screw pair [8, 22]: 2 x 40 s of wrapped
    plate).

    Returns
    -------
    list of (follow_neighbour, result or error)
        :func:`refill_sides`' result per variant, or the :class:`InvalidGeometryError` it raised.
    """
    curves, groups, side_of_edge, bounds, traces = _side_curves(edges, nbs, size)
    out: list[tuple[bool, Any]] = []
    try:
        followed = _followed(edges, nbs, size, curves, groups, bounds, traces)
    except InvalidGeometryError as err:
        out.append((True, err))
        followed = None
    same = followed is not None and all(a is b for a, b in zip(followed, bounds))
    for follow, bs in ((True, followed), (False, bounds)):
        if bs is None or (follow is False and same):
            continue
        try:
            out.append((follow, _finish(edges, nbs, owners, size, groups, side_of_edge, bs)))
        except InvalidGeometryError as err:
            out.append((follow, err))
    return out


def _side_curves(edges: list[Any], nbs: list[Any], size: float) -> tuple[list[Any], list[list[int]], list[int],
                                                                          list[Any], list[Any]]:
    """The model's side curves (exact where an edge lies on its neighbour, else fitted), their
    grouping into sides and the neighbours' traces along them."""
    curves = _oriented_curves(edges)
    groups = _groups(curves)  # one or two groups (a round hole, a slot end): fill_hole splits them
    side_of_edge = [gi for gi, group in enumerate(groups) for _ in group]
    order = [k for group in groups for k in group]
    side_of_edge = [side_of_edge[order.index(k)] for k in range(len(edges))]
    bounds: list[Any] = []
    traces: list[list[tuple[np.ndarray, np.ndarray, np.ndarray]]] = []
    for group in groups:  # 1. the side curves: exact where the edge lies on its neighbour, else fitted
        c = curves[group[0]] if len(group) == 1 else _merged_curve([curves[k] for k in group], size)[0]
        bounds.append(c)
        traces.append([trace(edges[k], nbs[k], c) for k in group])
    return curves, groups, side_of_edge, bounds, traces


def _followed(edges: list[Any], nbs: list[Any], size: float, curves: list[Any], groups: list[list[int]],
              bounds: list[Any], traces: list[Any]) -> list[Any]:
    """The side curves that follow the neighbours' traces (:func:`follow_traces`; a kept side is the
    same object)."""
    tol = tolerances.FILL_FIT_G0 * size
    return follow_traces(bounds, groups, curves, traces, tol, lambda k, c, n: trace(edges[k], nbs[k], c, n))


def _finish(edges: list[Any], nbs: list[Any], owners: list[Any], size: float, groups: list[list[int]],
            side_of_edge: list[int], bounds: list[Any]) -> tuple[list[Any], list[int], list[bool], list[float]]:
    """Steps 2 and 3 of :func:`refill_sides` on the side curves ``bounds``."""
    tol = tolerances.FILL_FIT_G0 * size
    bounds = [_even_speed(c, tol) for c in _snap_ends(bounds)]  # uneven speed: by arc length, within tol
    g1 = [False] * len(edges)
    fields = []
    for group, c in zip(groups, bounds):  # 2. the neighbours' (or the removed faces') normals
        P_all, N_all = [], []
        for k in group:
            P, N, g1[k] = edge_normals(edges[k], nbs[k], owners[k], c)
            P_all.append(P)
            N_all.append(N)
        P, N = np.concatenate(P_all), np.concatenate(N_all)
        s, _ = closest_parameters(c, P)
        s = unwrap_seam(c, s, [len(p) for p in P_all])
        by_s = np.argsort(s, kind="stable")
        fields.append((s[by_s], N[by_s]))
    bounds, fields = _corner_treatment(bounds, fields, [(g1[g[0]], g1[g[-1]]) for g in groups], tol)
    sides: list[Any] = []
    fit: list[float] = []
    for c, (s, N) in zip(bounds, fields):  # 3. the cross fields
        res = side_from_normals(c, s, N)
        sides.append(res.side)
        fit.append(res.angle)
    return sides, side_of_edge, g1, fit
