"""Loop geometry of a hole (course §8-3): closest points, arc length, self-intersection, mean plane.

Helpers of :func:`occsurf.algorithms.topology.nsided.fill_hole` that look at the hole's boundary as
a whole rather than at one side: :func:`closest_parameters` (vectorised point inversion on a curve),
:func:`arc_length_parameters` (where a round hole is cut), :func:`check_simple_loop` (a boundary that
crosses or touches itself is refused before any construction), :func:`mean_plane`,
:func:`turns_inward` (the global orientation check that guards the centre's fallback) and
:func:`inner_point` (the point of a hole farthest from its boundary: the centre of a crescent).

References
----------
C. Ericson, Real-Time Collision Detection (2005), 5.1.9 (closest points of two segments).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidGeometryError
from ..kernel.curve import BSplineCurve
from ..kernel.point_in_loops import grid_inside

__all__ = ["closest_parameters", "nearest_samples", "arc_length_parameters", "check_simple_loop", "mean_plane", "turns_inward",
           "inner_point", "harmonic_centre", "harmonic_picture", "HarmonicPicture"]

Array = NDArray[np.float64]


def _unit(v: Array) -> Array:
    return v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-300)


def closest_parameters(curve: BSplineCurve, points: Array, samples: int = 401,
                       iterations: int = 8, t0: Array | None = None) -> tuple[Array, Array]:
    """Parameters of the points of ``curve`` closest to ``points`` (m, dim), vectorised.

    The nearest of ``samples`` uniform parameters (or ``t0``, when given: a start known to be
    near) starts Newton's iteration on ``(C(t) - p) . C'(t) = 0`` (clamped to the domain), all
    points at once.

    Returns
    -------
    t : ndarray, shape (m,)
    distance : ndarray, shape (m,)
        ``|C(t) - p|``, for the caller to check.
    """
    P = np.atleast_2d(np.asarray(points, float))
    lo, hi = curve.domain
    if t0 is not None:
        t = np.asarray(t0, float)
    else:
        grid = np.linspace(lo, hi, samples)
        t = grid[nearest_samples(P, curve.evaluate(grid))]
    for _ in range(iterations):
        D = curve.derivatives(t, 2)
        r = D[:, 0] - P
        g = np.einsum("md,md->m", r, D[:, 1])
        h = np.einsum("md,md->m", D[:, 1], D[:, 1]) + np.einsum("md,md->m", r, D[:, 2])
        t_new = np.clip(t - np.where(h > 0, g / np.where(h > 0, h, 1.0), 0.0), lo, hi)
        done = np.abs(t_new - t).max() <= 1e-15 * (hi - lo)
        t = t_new
        if done:
            break
    return t, np.linalg.norm(curve.evaluate(t) - P, axis=1)



#: Points x samples below which :func:`nearest_samples` compares every pair (a k-d tree's set-up
#: costs more there).
NEAREST_BRUTE_PAIRS = 1 << 14
#: Candidates :func:`nearest_samples` takes from the k-d tree per point.
NEAREST_CANDIDATES = 4


def _sq_distances(P: Array, Q: Array) -> Array:
    """``|P[i] - Q[i, k]|^2`` for ``P`` (m, d) and ``Q`` (m, k, d), one arithmetic for every caller
    (the first of equal minima is then the same whichever set of samples is scored)."""
    diff = P[:, None, :] - Q
    return np.einsum("mkd,mkd->mk", diff, diff)


def nearest_samples(P: Array, dense: Array) -> NDArray[np.intp]:
    """Index of the sample of ``dense`` (k, d) nearest to each point of ``P`` (m, d): the first of
    those at the least squared distance, as ``argmin`` over every sample gives it.

    The few nearest samples of each point come from a k-d tree (:class:`scipy.spatial.cKDTree`) and
    are scored by the same arithmetic as every sample would be; where the tree's candidates all lie
    within 1e-9 (relative) of the nearest distance (repeated samples: a closed curve's ends, a
    degenerate side), or fewer than four are found (distances that overflow), or the point is not
    finite, the point is scored against every sample. So the index is the one the full comparison
    picks, bit for bit, at ``O(m log k)`` instead of ``O(m k)`` (a 16 000-point trace against 401
    samples: most of :func:`closest_parameters`' time before). Both arrays are taken as float64
    rows (the sum of a point's squared differences then has one order; the comparison before this
    function summed a Fortran-ordered array of points in another, 2026-12-07 review).
    """
    from scipy.spatial import cKDTree

    P = np.ascontiguousarray(P, dtype=float)  # float64 rows (the tree's arithmetic; see above)
    dense = np.ascontiguousarray(dense, dtype=float)
    m, k = len(P), len(dense)
    out = np.empty(m, dtype=np.intp)
    if m * k <= NEAREST_BRUTE_PAIRS or k <= NEAREST_CANDIDATES or not np.isfinite(dense).all():
        full = np.arange(m)
    else:
        finite = np.isfinite(P).all(axis=1)
        at = np.flatnonzero(finite)  # (the tree takes finite points only; the others: every sample)
        dist, cand = cKDTree(dense).query(P[at], k=NEAREST_CANDIDATES)
        # index k stands for a neighbour not found: fewer than four at a finite distance (squares
        # that overflow)
        lost = (cand >= k).any(axis=1)
        cand = np.sort(np.where(cand >= k, 0, cand), axis=1)  # the first of equal scores: the lowest index
        out[at] = cand[np.arange(at.size), np.argmin(_sq_distances(P[at], dense[cand]), axis=1)]
        tied = ~(dist[:, -1] > dist[:, 0] * (1.0 + 1e-9))  # candidates within round-off of one another
        full = np.sort(np.r_[np.flatnonzero(~finite), at[tied | lost]])
    step = max(1, (1 << 18) // (k * P.shape[1]))  # points a block: ~2 MB of differences, in cache
    for a in range(0, full.size, step):  # (16 000 points x 401 samples at once were 150 MB a temporary)
        rows = full[a:a + step]
        out[rows] = np.argmin(_sq_distances(P[rows], dense[None]), axis=1)
    return out


def _segment_distances(a0: Array, a1: Array, b0: Array, b1: Array) -> tuple[Array, Array, Array]:
    """Distances between segments ``[a0, a1]`` and ``[b0, b1]`` (each (m, 3)) and the parameters
    ``s, t`` in [0, 1] of the closest points (Ericson, Real-Time Collision Detection, 5.1.9), vectorised."""
    d1, d2, r = a1 - a0, b1 - b0, a0 - b0
    a, e = np.einsum("ij,ij->i", d1, d1), np.einsum("ij,ij->i", d2, d2)
    f, c, b = np.einsum("ij,ij->i", d2, r), np.einsum("ij,ij->i", d1, r), np.einsum("ij,ij->i", d1, d2)
    den = a * e - b * b
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.where(den > 1e-300, np.clip((b * f - c * e) / den, 0, 1), 0.0)
        t = np.where(e > 1e-300, (b * s + f) / e, 0.0)
        s = np.where(t < 0, np.clip(-c / np.where(a > 0, a, 1), 0, 1), np.where(t > 1, np.clip((b - c) / np.where(a > 0, a, 1), 0, 1), s))
    t = np.clip(t, 0, 1)
    return np.linalg.norm(a0 + s[:, None] * d1 - b0 - t[:, None] * d2, axis=1), s, t


#: Target length of a segment of the loop's polyline in :func:`check_simple_loop`, as a fraction of
#: the loop's size (bounding-box diagonal): far apart turns of a long side (a helix) are then no
#: candidates of each other. A sampling parameter, not a tolerance: the decision is made on the curves.
LOOP_SEGMENT_FRACTION = 1.0 / 128
#: Largest chord deviation (at the midpoint) of a segment, as a fraction of its length: a segment
#: turns by at most ~14 deg, so a side's own nearby segments are no candidates of each other.
LOOP_FLATNESS = 1.0 / 32
#: Cap on the polyline's segments (all sides): bisection stops refining there.
LOOP_MAX_SEGMENTS = 1 << 18


def _side_polyline(curve: BSplineCurve, samples: int, seg_len: float, budget: int,
                   start: Array | None = None) -> tuple[Array, Array, Array]:
    """Parameters (N+1,), points (N+1, 3) and midpoint chord deviations (N,) of one side's polyline:
    ``samples`` uniform parameters, segments bisected (all of a round at once) until each is at most
    ``seg_len`` long and deviates from the curve at its midpoint by at most ``LOOP_FLATNESS`` of its
    length (or the segment budget is spent, or a segment's parameter width reaches round-off).
    ``start``: the curve's points at those ``samples`` parameters, where the caller has them."""
    t = np.linspace(0.0, 1.0, samples)
    p = curve.evaluate(t) if start is None else start
    while True:
        tm = 0.5 * (t[1:] + t[:-1])
        pm = curve.evaluate(tm)
        length = np.linalg.norm(p[1:] - p[:-1], axis=1)
        dev = np.linalg.norm(pm - 0.5 * (p[1:] + p[:-1]), axis=1)
        bad = ((length > seg_len) | (dev > LOOP_FLATNESS * length)) & (np.diff(t) > 1e-12)
        k = np.flatnonzero(bad)
        if len(k) == 0 or len(t) - 1 + len(k) > budget:
            return t, p, dev
        t = np.insert(t, k + 1, tm[k])
        p = np.insert(p, k + 1, pm[k], axis=0)


def _side_derivatives(curves: list[BSplineCurve], side: NDArray[np.intp], t: Array, order: int) -> Array:
    """``curves[side[m]].derivatives(t[m], order)`` for all m, (m, order+1, 3): one call per side."""
    out = np.empty((t.shape[0], order + 1, curves[0].dim))
    for k in np.unique(side):
        sel = side == k
        out[sel] = curves[k].derivatives(t[sel], order)
    return out


def _project(curves: list[BSplineCurve], side: NDArray[np.intp], P: Array, lo: Array, hi: Array,
             t: Array | None = None, grid: int = 17, iterations: int = 8) -> Array:
    """Parameters of the points of ``curves[side]`` restricted to ``[lo, hi]`` closest to ``P`` (m, 3),
    all at once: the nearest of ``grid`` parameters on each stretch (unless a start ``t`` is given),
    then Newton's iteration on ``(C(t) - p) . C'(t) = 0`` clamped to the stretch."""
    if t is None:
        U = lo[:, None] + (hi - lo)[:, None] * np.linspace(0.0, 1.0, grid)
        pts = _side_derivatives(curves, np.repeat(side, grid), U.ravel(), 0)[:, 0].reshape(len(P), grid, -1)
        t = U[np.arange(len(P)), np.argmin(((pts - P[:, None]) ** 2).sum(-1), axis=1)]
    for _ in range(iterations):
        D = _side_derivatives(curves, side, t, 2)
        r = D[:, 0] - P
        g = np.einsum("md,md->m", r, D[:, 1])
        h = np.einsum("md,md->m", D[:, 1], D[:, 1]) + np.einsum("md,md->m", r, D[:, 2])
        t_new = np.clip(t - np.where(h > 0, g / np.where(h > 0, h, 1.0), 0.0), lo, hi)
        done = np.abs(t_new - t).max() <= 1e-15
        t = t_new
        if done:
            break
    return t


def _closest_pairs(curves: list[BSplineCurve], sa: NDArray[np.intp], sb: NDArray[np.intp], ta: Array, tb: Array,
                   stretch_a: tuple[Array, Array], stretch_b: tuple[Array, Array]) -> tuple[Array, Array, Array]:
    """Nearest pairs of points of ``curves[sa]`` on ``stretch_a`` and ``curves[sb]`` on ``stretch_b``
    (each ``(lo, hi)``, (m,)), from the starts ``ta, tb`` (m,), all pairs at once.

    Four rounds of alternating closest points (each point projected onto the other stretch; the
    distance never grows), then Newton's iteration on both parameters for ``|A(s) - B(t)|^2``
    (clamped to the stretches, a step kept only where it brings the points closer): it converges
    fast where alternating projections crawl (curves crossing at a small angle).

    Returns
    -------
    ta, tb, distance : ndarray, shape (m,)
    """
    (la, ha), (lb, hb) = stretch_a, stretch_b
    for it in range(4):
        first = it == 0
        tb = _project(curves, sb, _side_derivatives(curves, sa, ta, 0)[:, 0], lb, hb, None if first else tb)
        ta = _project(curves, sa, _side_derivatives(curves, sb, tb, 0)[:, 0], la, ha, None if first else ta)
    dist = np.linalg.norm(_side_derivatives(curves, sa, ta, 0)[:, 0] - _side_derivatives(curves, sb, tb, 0)[:, 0],
                          axis=1)
    for _ in range(16):
        A, B = _side_derivatives(curves, sa, ta, 2), _side_derivatives(curves, sb, tb, 2)
        r = A[:, 0] - B[:, 0]
        g1, g2 = np.einsum("md,md->m", r, A[:, 1]), -np.einsum("md,md->m", r, B[:, 1])
        h11 = np.einsum("md,md->m", A[:, 1], A[:, 1]) + np.einsum("md,md->m", r, A[:, 2])
        h22 = np.einsum("md,md->m", B[:, 1], B[:, 1]) - np.einsum("md,md->m", r, B[:, 2])
        h12 = -np.einsum("md,md->m", A[:, 1], B[:, 1])
        det = h11 * h22 - h12 * h12
        ok = (h11 > 0) & (det > 1e-12 * np.abs(h11 * h22))
        det = np.where(ok, det, 1.0)
        ta_new = np.clip(ta - np.where(ok, (h22 * g1 - h12 * g2) / det, 0.0), la, ha)
        tb_new = np.clip(tb - np.where(ok, (h11 * g2 - h12 * g1) / det, 0.0), lb, hb)
        d_new = np.linalg.norm(_side_derivatives(curves, sa, ta_new, 0)[:, 0]
                               - _side_derivatives(curves, sb, tb_new, 0)[:, 0], axis=1)
        better = ok & (d_new < dist)
        if not better.any():
            break
        ta, tb, dist = np.where(better, ta_new, ta), np.where(better, tb_new, tb), np.where(better, d_new, dist)
    return ta, tb, dist


def check_simple_loop(unit: list, tol: float, samples: int = 65) -> None:
    """Refuse a loop that touches or crosses itself (bad input: no surface bounded by it is a disk).

    Each side (on the unit domain) is sampled as a polyline: ``samples`` uniform parameters, then
    segments bisected until each is at most ``LOOP_SEGMENT_FRACTION`` of the loop's size long and
    nearly straight (midpoint chord deviation at most ``LOOP_FLATNESS`` of its length), so that the
    segments are short against the loop and far apart stretches of a long side (the turns of a
    helix) are not candidates of each other. Pairs of segments that are not neighbours along the
    loop (not within six segments of each other along it) and come within ``tol`` plus twice
    their chord deviations of each other are candidates (a k-d tree over segment midpoints, then
    the segments' exact distance, Ericson 5.1.9), all confirmed at once on the curves themselves,
    each on its own stretch of two segments either side (:func:`_closest_pairs`): a distance
    within ``tol`` is a self-intersection, except where two consecutive sides meet at their
    shared corner.

    Parameters
    ----------
    unit : list of HoleSide, length n
        The sides in loop order, each ``curve`` a 3-D curve on ``[0, 1]``.
    tol : float
        Distance at which two points of the loop count as touching.
    samples : int
        Uniform samples per side that the bisection starts from.

    Raises
    ------
    InvalidGeometryError
        Naming the two sides, the parameters and the distance (the closest offending pair).
    """
    from scipy.spatial import cKDTree

    n = len(unit)
    curves = [sd.curve for sd in unit]
    uniform = [c.evaluate(np.linspace(0.0, 1.0, samples)) for c in curves]
    size = float(np.linalg.norm(np.ptp(np.concatenate(uniform), axis=0)))
    if not size > 0:
        return
    budget = LOOP_MAX_SEGMENTS // n
    lines = [_side_polyline(c, samples, LOOP_SEGMENT_FRACTION * size, budget, u) for c, u in zip(curves, uniform)]
    T0 = np.concatenate([t[:-1] for t, _, _ in lines])
    T1 = np.concatenate([t[1:] for t, _, _ in lines])
    lo = np.concatenate([t[np.maximum(np.arange(len(t) - 1) - 2, 0)] for t, _, _ in lines])
    hi = np.concatenate([t[np.minimum(np.arange(len(t) - 1) + 3, len(t) - 1)] for t, _, _ in lines])
    A0 = np.concatenate([p[:-1] for _, p, _ in lines])
    A1 = np.concatenate([p[1:] for _, p, _ in lines])
    dev = np.concatenate([d for _, _, d in lines])
    side = np.concatenate([np.full(len(t) - 1, k) for k, (t, _, _) in enumerate(lines)])
    m = len(A0)
    reach = float(np.linalg.norm(A1 - A0, axis=1).max()) + 4 * float(dev.max()) + tol
    pairs = cKDTree(0.5 * (A0 + A1)).query_pairs(reach, output_type="ndarray")
    if len(pairs) == 0:
        return
    i, j = pairs[:, 0], pairs[:, 1]
    gap = np.abs(i - j)
    # not within six segments of each other along the loop: the two stretches (two segments either
    # side) are then apart by two segments at least, so they cannot slide into each other and find
    # the same point, and at most one of them reaches a corner (at a zero-angle corner the sides
    # approach each other only there: the nearest pair would creep towards it, never reach it)
    keep = np.minimum(gap, m - gap) > 6
    i, j = i[keep], j[keep]
    d, si, sj = _segment_distances(A0[i], A1[i], A0[j], A1[j])
    cand = d <= tol + 2 * (dev[i] + dev[j])
    if not cand.any():
        return
    i, j, si, sj = i[cand], j[cand], si[cand], sj[cand]
    sa, sb = side[i], side[j]
    ta, tb, dist = _closest_pairs(curves, sa, sb, T0[i] + si * (T1[i] - T0[i]), T0[j] + sj * (T1[j] - T0[j]),
                                  (lo[i], hi[i]), (lo[j], hi[j]))
    # consecutive sides meet at their shared corner (the end of one, the start of the next)
    at_corner = (((sb == (sa + 1) % n) & (np.abs(ta - 1) + tb < 1e-9))
                 | ((sa == (sb + 1) % n) & (ta + np.abs(tb - 1) < 1e-9)))
    bad = np.flatnonzero((dist <= tol) & ~at_corner)
    if len(bad):
        k = bad[np.argmin(dist[bad])]
        raise InvalidGeometryError(
            f"sides: the loop crosses itself: side {sa[k]} at parameter {ta[k]:.4g} comes within {dist[k]:.3g} of "
            f"side {sb[k]} at {tb[k]:.4g} (tolerance {tol:.3g}); a hole's boundary must be a simple loop")


def arc_length_parameters(curve: BSplineCurve, fractions: Array, samples: int = 1025) -> Array:
    """Parameters (on the curve's domain) at the given fractions (m,) of its arc length (chords of
    ``samples`` points; accurate to ~1e-6 of the length, plenty for choosing split points)."""
    t = np.linspace(*curve.domain, samples)
    cum = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(curve.evaluate(t), axis=0), axis=1))]
    return np.interp(np.asarray(fractions, float) * cum[-1], cum, t)



def mean_plane(loop: Array, normals: Array) -> tuple[Array, Array, Array, Array]:
    """Origin, unit normal and in-plane axes of a hole's mean plane: through the mean of ``loop``
    (m, 3), normal to the mean of the neighbours' unit ``normals`` (n, 3), or to the loop's
    smallest principal axis when those nearly cancel (a hole wrapping around)."""
    o = loop.mean(0)
    nh = normals.mean(0)
    if np.linalg.norm(nh) < 0.3:
        nh = np.linalg.svd(loop - o, full_matrices=False)[2][-1]
    nh = _unit(nh)
    e1 = _unit(np.cross(nh, np.eye(3)[int(np.argmin(np.abs(nh)))]))
    return o, nh, e1, np.cross(nh, e1)


def turns_inward(loop: Array, normals: Array) -> bool:
    """Whether the cross fields point out of the hole, judged globally: the neighbours' normals
    ``B' x X`` (n, 3) and the loop (m, 3) projected into the mean plane must turn the other way
    (negative signed area about the mean normal). Only then may :func:`occsurf.algorithms.topology.nsided_centre.centre` move the centre or
    turn the internal edges; a flipped field is left for :func:`occsurf.algorithms.topology.nsided_corners.check_inward` to refuse."""
    o, nh, e1, e2 = mean_plane(loop, normals)
    if np.linalg.norm(normals.mean(0)) < 0.3:
        return False  # no trustworthy mean plane: no fallback
    xy = (loop - o) @ np.stack([e1, e2], 1)
    area = 0.5 * float(np.sum(xy[:, 0] * np.roll(xy[:, 1], -1) - np.roll(xy[:, 0], -1) * xy[:, 1]))
    return area < 0


def inner_point(loop: Array, normals: Array, grid: int = 61) -> tuple[Array, Array] | None:
    """The point of a hole farthest from its boundary, in the hole's mean plane.

    The plane: through the mean of ``loop`` (m, 3), normal to the mean of the neighbours' unit
    ``normals`` (n, 3) (their smallest principal axis when those nearly cancel). The loop is
    projected into it, a ``grid`` x ``grid`` lattice over its box is tested for inside (even-odd
    rule), and the inside point farthest from the projected boundary is returned with the plane's
    unit normal, or ``None`` when no lattice point is inside (a degenerate projection). Vectorised:
    ``grid**2 * m`` pairs (a few million at most).
    """
    o, nh, e1, e2 = mean_plane(loop, normals)
    xy = (loop - o) @ np.stack([e1, e2], 1)
    gx, gy = (np.linspace(lo, hi, grid)[1:-1] for lo, hi in zip(xy.min(0), xy.max(0)))
    G = np.stack(np.meshgrid(gx, gy, indexing="ij"), -1).reshape(-1, 2)
    a, b = xy, np.roll(xy, -1, axis=0)
    px, py = G[:, :1], G[:, 1:]
    with np.errstate(divide="ignore", invalid="ignore"):
        cross_x = a[:, 0] + (b[:, 0] - a[:, 0]) * (py - a[:, 1]) / (b[:, 1] - a[:, 1])
    crossing = ((a[:, 1] > py) != (b[:, 1] > py)) & (px < cross_x)
    inside = crossing.sum(1) % 2 == 1
    if not inside.any():
        return None
    dist = np.sqrt(((G[inside][:, None] - xy[None]) ** 2).sum(-1)).min(1)
    x, y = G[inside][int(np.argmax(dist))]
    return o + x * e1 + y * e2, nh


class HarmonicPicture:
    """A discrete harmonic map of a hole (projected into its mean plane) onto a convex domain polygon.

    Built by :func:`harmonic_picture`; :meth:`preimage` inverts it at domain points. Attributes:
    ``origin``, ``normal`` (3,) of the mean plane, ``to3`` (3, 2) grid coordinates -> 3-D, ``h``
    the grid spacing, ``lo`` (2,) the grid's corner, ``values`` (k, 2) the map at the ``nodes`` (k, 2)
    (grid indices) inside the hole, ``index`` the node number of each grid point (-1 outside).
    """

    def __init__(self, origin: Array, normal: Array, to3: Array, h: float, lo: Array, nodes: NDArray[np.intp],
                 values: Array, index: NDArray[np.intp]) -> None:
        from scipy.spatial import cKDTree

        self.origin, self.normal, self.to3, self.h, self.lo = origin, normal, to3, h, lo
        self.nodes, self.values, self.index = nodes, values, index
        self._tree = cKDTree(values)

    def _value(self, i: NDArray[np.intp], j: NDArray[np.intp]) -> tuple[Array, NDArray[np.bool_]]:
        nx, ny = self.index.shape
        ok = (i >= 0) & (i < nx) & (j >= 0) & (j < ny)
        k = np.full(i.shape, -1)
        k[ok] = self.index[i[ok], j[ok]]
        ok = k >= 0
        return self.values[np.where(ok, k, 0)], ok

    def preimage(self, uv: Array) -> tuple[Array, Array, NDArray[np.bool_]]:
        """Points of the hole (m, 3, in the mean plane) mapped to the domain points ``uv`` (m, 2), the
        inverse map's Jacobians there (m, 3, 2) and whether each was found (a non-singular
        central- or one-sided-difference Jacobian at the nearest node)."""
        uv = np.atleast_2d(np.asarray(uv, float))
        k = self._tree.query(uv)[1]
        i0, j0 = self.nodes[k, 0], self.nodes[k, 1]
        U0 = self.values[k]
        cols = []
        ok = np.ones(len(uv), bool)
        for di, dj in ((1, 0), (0, 1)):
            fwd, okf = self._value(i0 + di, j0 + dj)
            bwd, okb = self._value(i0 - di, j0 - dj)
            d = np.where((okf & okb)[:, None], (fwd - bwd) / 2, np.where(okf[:, None], fwd - U0, U0 - bwd)) / self.h
            ok &= okf | okb
            cols.append(d)
        Jac = np.stack(cols, 2)  # (m, 2 domain, 2 grid)
        det = np.linalg.det(Jac)
        ok &= np.abs(det) > 1e-12 * np.abs(Jac).max(axis=(1, 2)) ** 2
        Jinv = np.linalg.inv(np.where(ok[:, None, None], Jac, np.eye(2)))
        step = np.einsum("mij,mj->mi", Jinv, uv - U0)
        size = np.linalg.norm(step, axis=1, keepdims=True)
        step = np.where(size > 2 * self.h, step * 2 * self.h / np.maximum(size, 1e-300), step)
        p = self.lo + self.h * np.c_[i0, j0] + step
        return self.origin + p @ self.to3.T, np.einsum("ag,mgd->mad", self.to3, Jinv), ok


def harmonic_picture(loop: Array, targets: Array, normals: Array, cells: int = 4000) -> HarmonicPicture | None:
    """The discrete harmonic map of a hole onto the fill's domain polygon (course §8-3 central split).

    The loop (m, 3), sampled densely and in order, is projected into the hole's mean plane
    (:func:`mean_plane`); a square grid of about ``cells`` nodes inside it, aligned with the
    projection's principal axes (so that a long thin hole is resolved across its width), carries the
    discrete harmonic map (5-point Laplacian) whose boundary values are ``targets`` (m, 2), the
    loop samples' positions on the boundary of the convex domain polygon (each grid neighbour outside
    the hole takes the value of its nearest loop sample). A harmonic map onto a convex domain is
    one-to-one (Radó–Kneser–Choquet; Floater's discrete analogue), so the preimages of the domain's
    centre and of the segments from it to the split points lie inside the hole, spread along its
    length: where a long curved hole or a sliver wants the centre and the internal edges.

    Returns
    -------
    HarmonicPicture or None
        ``None`` when no grid node lies inside the projected loop (a degenerate projection).

    References
    ----------
    M. S. Floater, "One-to-one piecewise linear mappings over triangulations", Math. Comp. 72 (2003);
    P. Joshi et al., "Harmonic coordinates for character articulation", SIGGRAPH 2007.
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.linalg import spsolve
    from scipy.spatial import cKDTree

    o, nh, e1, e2 = mean_plane(loop, normals)
    xy = (loop - o) @ np.stack([e1, e2], 1)
    axes = np.linalg.svd(xy - xy.mean(0), full_matrices=False)[2]  # principal axes of the projection
    q = xy @ axes.T
    lo, hi = q.min(0), q.max(0)
    area = 0.5 * abs(float(np.sum(q[:, 0] * np.roll(q[:, 1], -1) - np.roll(q[:, 0], -1) * q[:, 1])))
    if not area > 0:
        return None
    h = max(np.sqrt(area / cells), float((hi - lo).max()) / 400.0)
    nx, ny = (np.floor((hi - lo) / h).astype(int) + 1)
    gx, gy = lo[0] + h * np.arange(nx + 1), lo[1] + h * np.arange(ny + 1)
    inside = grid_inside(q, gx, gy)
    if not inside.any():
        return None
    shape = (nx + 1, ny + 1)
    index = np.full(shape, -1)
    index[inside] = np.arange(int(inside.sum()))
    I, J = np.nonzero(inside)
    rows, cols, rhs = [np.arange(len(I))], [np.arange(len(I))], np.zeros((len(I), 2))
    vals = [np.full(len(I), 4.0)]
    tree = cKDTree(q)
    for di, dj in ((1, 0), (-1, 0), (0, 1), (0, -1)):
        ii, jj = I + di, J + dj
        ok = (ii >= 0) & (ii <= nx) & (jj >= 0) & (jj <= ny)
        nb = np.full(len(I), -1)
        nb[ok] = index[ii[ok], jj[ok]]
        interior = nb >= 0
        rows.append(np.flatnonzero(interior))
        cols.append(nb[interior])
        vals.append(np.full(int(interior.sum()), -1.0))
        out = np.flatnonzero(~interior)
        if out.size:
            pts = np.c_[lo[0] + h * ii[out], lo[1] + h * jj[out]]
            rhs[out] += targets[tree.query(pts)[1]]
    A = coo_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(len(I), len(I))).tocsc()
    U = np.asarray(spsolve(A, rhs)).reshape(len(I), 2)
    to3 = np.stack([e1, e2], 1) @ axes.T  # grid coordinates -> 3-D
    return HarmonicPicture(o, nh, to3, h, lo, np.c_[I, J], U, index)


def harmonic_centre(loop: Array, targets: Array, normals: Array, cells: int = 4000
                    ) -> tuple[Array, Array, Array] | None:
    """The point of a hole that the harmonic map of :func:`harmonic_picture` sends to the domain's
    centre (the origin), with the plane's unit normal (3,) and the inverse map's Jacobian (3, 2)
    there; ``None`` for a degenerate projection or a singular map."""
    hp = harmonic_picture(loop, targets, normals, cells)
    if hp is None:
        return None
    P, Jinv, ok = hp.preimage(np.zeros((1, 2)))
    return (P[0], hp.normal, Jinv[0]) if ok[0] else None
