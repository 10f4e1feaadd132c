"""The neighbours along the hole's edges: their normals and traces, and side curves that follow them.

A hole edge is a trimming curve of its neighbour, which meets the model's edge curve only within
the edge's tolerance. :func:`edge_normals` gives the points and oriented normals along an edge that a
side's cross field is fitted to (the neighbour's where the original joint was tangent-continuous,
the removed face's own at a sharp edge); :func:`trace` the neighbour's points along the edge (its
p-curve on the neighbour) with their parameters and distances on the side curve.
:func:`follow_traces` replaces a side curve that lies off its traces by a cubic fitted to them
(:func:`_fit_points`), pinned (:func:`_pin_end`) to the points where two neighbours' traces meet
(:func:`_corner_point`); :func:`unwrap_seam` keeps a closed side's samples on the right end.
Part of the refill of :mod:`.refill` (course §8-3 on real, trimmed models; chord-length fitting §7-2).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from OCP.BRep import BRep_Tool
from OCP.BRepClass import BRepClass_FaceClassifier
from OCP.gp import gp_Pnt, gp_Pnt2d, gp_Vec
from OCP.TopAbs import TopAbs_IN, TopAbs_OUT

from occsurf.algorithms import tolerances
from occsurf.algorithms.errors import InvalidGeometryError
from occsurf.algorithms.topology.nsided import closest_parameters
from occsurf.algorithms.topology.nsided_sides import fit_boundary, smoothstep

from .refill_loop import G1_EDGE_DEG, edge_params, joint_angle, normals_on

__all__ = ["edge_normals", "trace", "follow_traces", "unwrap_seam", "FIT_SAMPLES", "CORNER_SLOPE",
           "TRACE_SAMPLES_PER_POLE", "TRACE_MAX_SAMPLES", "TRACE_MAX_RESAMPLED"]

#: Samples of the neighbour's normal per edge for the cross-field fit (plus clustered end samples).
FIT_SAMPLES: int = 81
#: Where a side that follows its neighbour's trace must be moved across it at a corner (the two
#: neighbours' traces do not quite meet: :func:`_corner_point`), the move is spread over a length
#: that turns the side by this many radians on average (5.7e-3 deg; at most half the side: :func:`_pin_end`).
CORNER_SLOPE: float = 1e-4
#: Samples of a neighbour's trace per pole of the side curve it is fitted to (:func:`trace`).
TRACE_SAMPLES_PER_POLE: int = 16
#: Most samples of one neighbour's trace by default (:func:`trace`), and when the side's fit asks
#: for more because it is short of them (:func:`follow_traces`: 4 times as many per round).
TRACE_MAX_SAMPLES: int = 4001
TRACE_MAX_RESAMPLED: int = 16001


def _side_of(face: Any, uv: Any, direction: np.ndarray) -> int:
    """+1 if stepping from ``uv`` along the 3-D ``direction`` enters ``face``, -1 if it leaves."""
    s = BRep_Tool.Surface_s(face)
    p, du, dv = gp_Pnt(), gp_Vec(), gp_Vec()
    s.D1(uv.X(), uv.Y(), p, du, dv)
    J = np.c_[du.Coord(), dv.Coord()]
    d, *_ = np.linalg.lstsq(J, direction, rcond=None)
    scale = np.linalg.norm(d)
    if scale == 0:
        return 1
    growth = tolerances.FILL_SIDE_STEP_GROWTH
    for k in range(int(tolerances.FILL_SIDE_STEP_TRIES)):  # 1e-4, 1e-3, 1e-2 by default
        eps = tolerances.FILL_SIDE_STEP * growth ** k
        q = gp_Pnt2d(uv.X() + eps * d[0] / scale, uv.Y() + eps * d[1] / scale)
        st = BRepClass_FaceClassifier(face, q, tolerances.FILL_SIDE_CLASSIFY_TOL).State()
        if st == TopAbs_IN:
            return 1
        if st == TopAbs_OUT:
            return -1
    return 1


def edge_normals(e: Any, nb: Any, own: Any, curve: Any) -> tuple[np.ndarray, np.ndarray, bool]:
    """Points and oriented normals along edge ``e`` (G1 edge: the neighbour's; sharp: the owner's).

    Without an owner (a hole of the model itself, no removed face) the neighbour's plane is all
    there is: G1 to it is asked."""
    tangent = own is None or joint_angle(e, own, nb) <= G1_EDGE_DEG
    src = nb if tangent or own is None else own
    P, N, uvs = normals_on(e, src, edge_params(e, src, FIT_SAMPLES))
    k = len(P) // 2
    s, _ = closest_parameters(curve, P[k:k + 1])  # the middle point's only: it orients the normals
    T = curve.derivatives(s, 1)[0, 1]
    into = np.cross(T, N[k])  # must point into nb (G1 edge) or out of the removed face (sharp edge)
    if _side_of(src, uvs[k], into) != (1 if src is nb else -1):
        N = -N
    return P, N, bool(tangent)


def trace(edge: Any, nb: Any, curve: Any, samples: int | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The neighbour's points along ``edge`` (from its p-curve), their parameters on ``curve`` and
    their distances from it: ``samples`` of them, by default :data:`TRACE_SAMPLES_PER_POLE` per pole
    of ``curve`` (at least ``FIT_SAMPLES``, at most :data:`TRACE_MAX_SAMPLES`): :func:`fit_boundary`
    refines a span only while it holds 8 samples, and a trace as detailed as a 24-pole edge curve
    stopped 5e-5 off with 81 (linkrods face 20). Where that is still too few for the side's fit
    (:func:`_fit_points`), :func:`follow_traces` asks for more."""
    k = min(max(FIT_SAMPLES, TRACE_SAMPLES_PER_POLE * len(curve.control_points)), TRACE_MAX_SAMPLES) \
        if samples is None else int(samples)
    P, _, _ = normals_on(edge, nb, edge_params(edge, nb, k), uv_points=False)
    s, d = closest_parameters(curve, P)
    return P, unwrap_seam(curve, s, [len(P)]), d


def _along(trace: tuple[np.ndarray, np.ndarray, np.ndarray]) -> np.ndarray:
    """A neighbour's trace points (:func:`trace`), shape (m, 3), in the direction of its side.

    The samples come in the p-curve's order; whether that runs with the side is read off the
    middle half of their side parameters (near the ends, samples beyond the side curve's end all
    have its end parameter, so sorting by it would scramble them)."""
    P, s, _ = trace
    m = len(s)
    return P if float(np.median(np.diff(s[m // 4: 3 * m // 4 + 1]))) >= 0 else P[::-1]


def _drop_repeats(P: np.ndarray) -> np.ndarray:
    """``P`` (m, 3) without points closer than ``FILL_TRACE_REPEAT`` (1e-12) of the polyline's length
    to the one before (the parameters of :func:`fit_boundary` must increase); the first and last
    points stay."""
    step = np.linalg.norm(np.diff(P, axis=0), axis=1)
    eps = tolerances.FILL_TRACE_REPEAT * max(float(step.sum()), 1e-300)
    keep = np.r_[True, step > eps]
    keep[-1] = True
    idx = np.flatnonzero(keep)
    if len(idx) > 2 and np.linalg.norm(P[idx[-1]] - P[idx[-2]]) <= eps:
        keep[idx[-2]] = False
    return P[keep]


def _corner_point(p0: np.ndarray, t0: np.ndarray, p1: np.ndarray, t1: np.ndarray) -> np.ndarray:
    """Where a side ending at ``p0`` (unit tangent ``t0``) should meet the next one starting at
    ``p1`` (unit tangent ``t1``): the midpoint of the closest points of the rays ``p0 + a t0`` and
    ``p1 - b t1`` (``a, b >= 0``).

    ``p0``, ``p1`` are the ends of two neighbours' traces at a joint of the hole's edges. The
    model's edges meet at a vertex, but each lies off its neighbour by up to its tolerance, so the
    two traces end micrometres apart (bearing face 5: 4.7e-6, edge tolerance 4.9e-6), mostly
    *along* one of them: one trace stops short of the other, or runs past it. Prolonged along
    their tangents the two traces meet within ~1e-9 (the skew of their lines), and that corner is
    G0 to both; the midpoint of ``p0`` and ``p1`` (:func:`.refill_sides._snap_ends`) is off each by half the gap.
    A trace that runs past the other's line cannot be shortened for free: its points beyond the
    corner are off the fill by their distance from it; the midpoint of the rays' closest points
    makes the larger of the two sides' distances least (half the rays' distance: the distance
    to a convex set is convex). Between parallel tangents (a flat joint inside a side) the rays
    give the midpoint of an overlap, or of a gap where they overlap only with one another.
    """
    d = p1 - p0
    cands = [(max(0.0, float(d @ t0)), 0.0), (0.0, max(0.0, float(d @ t1))), (0.0, 0.0)]
    c = float(t0 @ t1)
    if 1.0 - c * c > tolerances.FILL_TRACE_PARALLEL:  # not parallel: a corner between sides
        a, b = np.linalg.solve(np.array([[1.0, c], [c, 1.0]]), np.array([d @ t0, d @ t1]))
        if a >= 0 and b >= 0:
            cands.append((float(a), float(b)))
    gaps = [np.linalg.norm(p0 + a * t0 - (p1 - b * t1)) for a, b in cands]
    a, b = cands[int(np.argmin(gaps))]
    return 0.5 * (p0 + a * t0 + p1 - b * t1)


def _pin_end(P: np.ndarray, X: np.ndarray, T: np.ndarray) -> np.ndarray:
    """Samples ``P`` (m, 3) of a trace, made to end at the joint ``X`` (the trace's unit tangent
    there ``T``): prolonged along ``T`` to ``X``, or cut there when the trace runs past it. What is
    left across ``T`` (the traces' skew, a trace running past the corner: :func:`_corner_point`)
    is spread over the samples near the end with a C2 smoothstep, over the length on which it
    would turn the side by :data:`CORNER_SLOPE` radians on average (15/8 of it at the steepest;
    at most half the trace, which then turns more): moving the end alone
    would turn the side's end tangent by the gap over the first leg (bearing face 181: 0.32 deg)."""
    end = P[-1]
    along = float((X - end) @ T)
    if along < 0:  # the trace runs past the joint: cut its tail there (only the tail: a trace that
        # turns, a helix turn, has samples far behind its end that also lie "past" it along T)
        before = np.flatnonzero((P - end) @ T < along)
        P = P[:before[-1] + 1] if before.size else P[:0]
        if len(P) < 2:
            raise InvalidGeometryError("a neighbour's trace runs past both ends of its hole edge")
    P = np.r_[P, [end + along * T]]
    h = X - P[-1]
    dist = np.r_[np.cumsum(np.linalg.norm(np.diff(P, axis=0), axis=1)[::-1])[::-1], 0.0]
    length = min(0.5 * float(dist[0]), float(np.linalg.norm(h)) / CORNER_SLOPE)
    if length > 0:
        P = P + (1.0 - smoothstep(dist / length))[:, None] * h
    P[-1] = X
    return P


def _fit_points(P: np.ndarray, tol: float, max_spans: int | None = None) -> tuple[Any, float]:
    """One cubic through ordered samples ``P`` (m, 3) of a side, aiming at ``tol`` (chord length,
    :func:`fit_boundary`: the ends interpolated; at most ``max_spans`` knot spans), and how far it
    is from the samples: the larger of its distance at them and half-way between them.

    ``fit_boundary`` checks the samples only. Half-way between two samples the fit is compared with
    the cubic through the four samples around them (Lagrange, at the same chord-length parameter:
    a parametric distance, which bounds the geometric one). That cubic's own error is O(h^4) on a
    smooth trace (against the neighbour's points at the midpoints: 0.01 tol on bearing face 185's
    traces with 1281 samples per edge) but not near a trace's kinks (linkrods face 20: 0.5 tol
    with 5121), where the distance reported may be too large by that. Too few samples for the
    fit's spans let it swing between them: the M6 screw's thread side, 55 samples per helix turn
    (:func:`_pin_end` had cut the rest), was within 1.1e-6 at every sample and 2 mm off between them.
    """
    P = _drop_repeats(P)
    arc = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(P, axis=0), axis=1))]
    s = arc / arc[-1]
    c, err = fit_boundary(s, P, tol, max_spans=max_spans)
    m = len(s)
    idx = np.clip(np.arange(m - 1) - 1, 0, m - 4)[:, None] + np.arange(4)  # 4 samples around each gap
    x, mid = s[idx], 0.5 * (s[:-1] + s[1:])
    L = np.ones((m - 1, 4))
    for a in range(4):  # Lagrange weights at the midpoints (4 x 3 vectorised products)
        for b in range(4):
            if a != b:
                L[:, a] *= (mid - x[:, b]) / (x[:, a] - x[:, b])
    between = np.linalg.norm(c.evaluate(mid) - np.einsum("ja,jad->jd", L, P[idx]), axis=1)
    return c, max(float(err), float(between.max()))


def follow_traces(bounds: list[Any], groups: list[list[int]], curves: list[Any],
                   traces: list[list[tuple[np.ndarray, np.ndarray, np.ndarray]]], tol: float,
                   retrace: Any = None) -> list[Any]:
    """The side curves that follow the neighbours' traces (``traces`` per side, from :func:`trace`).

    At each joint of two hole edges (a corner between sides, a flat joint inside one) the two
    neighbours' traces meet at :func:`_corner_point` (tangents from the model's edge ``curves``);
    a side whose model curve (``bounds``) lies within ``tol`` of its traces and of both its corners
    is kept, any other becomes the cubic within ``tol`` of its traces (at and between their
    samples, :func:`_fit_points`; up to ``FILL_FIT_MAX_SPANS`` knot spans per edge of the side),
    each pinned to its two joints (:func:`_pin_end`), so that the sides meet where both neighbours
    do. Where the fit stops short of ``tol`` with fewer spans than that (its spans hold too few
    samples to be split), ``retrace(k, curve, n)`` (edge ``k``'s trace with ``n`` samples:
    :func:`trace`) gives 4 times as many, up to :data:`TRACE_MAX_RESAMPLED` per edge: linkrods
    face 20's traces on a 47-pole p-curve need about 4000 where the 20-pole edge curve asked 336.

    Warns
    -----
    RuntimeWarning
        A side's fit still misses ``tol`` (the message gives the distance, spans and samples): the
        side is then the closer to the traces of that fit and the model's edge curve (``bounds``).
        The old cut in :func:`_pin_end` gave the M6 screw's thread side a fit 2 mm off (its edge
        curve: 1e-4), screw face 24 a side that doubles back along its straight edge (1.7 mm between
        samples; edge curve within tol); on linkrods faces 22 and 35 a trace with a 3 deg kink
        stays 1.6 tol off at 16016 samples (edge curves 50 tol off): refusing the followed variant
        there cost G0 6.7e-6 -> 5.8e-4.
    """
    order = [k for g in groups for k in g]
    P = {k: _along(t) for g, tr in zip(groups, traces) for k, t in zip(g, tr)}
    tan = {k: [d / np.linalg.norm(d) for d in (curves[k].derivatives(np.array([curves[k].domain[e]]), 1)[0, 1]
                                               for e in (0, 1))] for k in order}
    nxt = {k: order[(m + 1) % len(order)] for m, k in enumerate(order)}
    prv = {v: k for k, v in nxt.items()}
    joint = {k: _corner_point(P[k][-1], tan[k][1], P[nxt[k]][0], tan[nxt[k]][0]) for k in order}
    out = []
    for j, (g, c, tr) in enumerate(zip(groups, bounds, traces)):
        x0, x1 = joint[prv[g[0]]], joint[g[-1]]
        ends = max(np.linalg.norm(c.evaluate(c.domain[0]) - x0), np.linalg.norm(c.evaluate(c.domain[1]) - x1))
        if ends <= tol and max(float(d.max()) for _, _, d in tr) <= tol:
            out.append(c)
            continue
        cap = int(tolerances.FILL_FIT_MAX_SPANS) * len(g)
        while True:
            pieces = [_pin_end(_pin_end(P[k], joint[k], tan[k][1])[::-1], joint[prv[k]], -tan[k][0])[::-1] for k in g]
            fit, dev = _fit_points(np.concatenate(pieces), tol, cap)
            if dev <= tol:
                break
            spans, n = int(np.unique(fit.knots).size) - 1, {k: len(P[k]) for k in g}
            if retrace is None or spans >= cap or all(v >= TRACE_MAX_RESAMPLED for v in n.values()):
                break
            grow = int(tolerances.FILL_TRACE_RESAMPLE_FACTOR)
            P.update({k: _along(retrace(k, c, min(grow * n[k], TRACE_MAX_RESAMPLED))) for k in g})
        if dev > tol:  # never silently: the closer of the fit and the model's edge curve, with a warning
            import warnings

            edge_dev = max(float(ends), max(float(d.max()) for _, _, d in tr))
            what = (f"kept (the model's edge curve is {edge_dev:.3g} off)" if dev < edge_dev else
                    f"the model's edge curve ({edge_dev:.3g} off) is used instead")
            warnings.warn(f"refill side {j}: the cubic fitted to its neighbours' traces stays {dev:.3g} off them "
                          f"(tolerance {tol:.3g}; {spans} knot spans on {sum(n.values())} samples); {what}",
                          RuntimeWarning, stacklevel=2)
            fit = fit if dev < edge_dev else c
        out.append(fit)
    return out


def unwrap_seam(curve: Any, s: np.ndarray, counts: list[int]) -> np.ndarray:
    """On a closed side (a round hole: the curve starts where it ends) a sample at the seam is as close
    to the curve's start as to its end; put each on the end its neighbours along the edge say
    (samples come ordered along each edge, ``counts`` per edge), so the fitted field sees the normals
    at the seam at both ends of the side, not swapped."""
    lo, hi = curve.domain
    if len(counts) != 1 or np.linalg.norm(curve.evaluate(lo) - curve.evaluate(hi)) > tolerances.FILL_SEAM_TOL * max(
            1.0, float(np.abs(curve.control_points).max())):
        return s
    m = len(s)
    mid = s[m // 4: 3 * m // 4]
    rising = float(np.median(np.diff(mid))) >= 0
    span = hi - lo
    head, tail = np.arange(m) < m // 2, np.arange(m) >= m // 2
    s = s.copy()
    w = tolerances.FILL_SEAM_WINDOW  # 1 - 0.25 is 0.75 exactly
    if rising:  # the first samples belong near lo, the last near hi
        s[head & (s > lo + (1 - w) * span)] = lo
        s[tail & (s < lo + w * span)] = hi
    else:
        s[head & (s < lo + w * span)] = hi
        s[tail & (s > lo + (1 - w) * span)] = lo
    return s


