"""Trimming loops as polylines, and points classified against them (the kernels of :mod:`.trimmed`).

A loop of p-curves becomes a closed polyline within a chordal tolerance (:func:`loop_polyline`,
sampled per knot span and bisected where a chord strays); :func:`classify_points` tells points
inside, on or outside a region bounded by such polylines by the crossing number (even-odd rule),
vectorised in blocks of bounded memory; :func:`grid_inside` is the same rule, exact (no boundary
band), for the nodes of a grid, one grid row at a time.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import _validate as V
from .. import tolerances
from ..errors import InvalidGeometryError
from .curve import BSplineCurve

__all__ = ["INSIDE", "ON", "OUTSIDE", "classify_points", "SegmentBands", "segment_bands", "loop_polyline", "curve_polyline", "span_samples",
           "signed_area", "Loop", "grid_inside"]

Array = NDArray[np.float64]
Loop = tuple[BSplineCurve, ...]

#: Values of :meth:`.trimmed.TrimmedSurface.classify` (OCC's ``TopAbs_IN`` / ``TopAbs_ON`` / ``TopAbs_OUT``).
INSIDE, ON, OUTSIDE = 1, 0, -1

_PAIR_BLOCK = 1 << 22  # point-segment pairs tested at once by the classifier (bounded memory)


def signed_area(P: Array) -> float:
    """Shoelace area of a closed polygon ``(k, 2)`` (last point may repeat the first)."""
    x, y = P[:, 0], P[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def span_samples(c: BSplineCurve, per_span: int) -> Array:
    """``per_span`` equally spaced parameters in every non-empty knot span, and the domain end."""
    k = np.unique(c.knots[c.degree:c.n_poles + 1])
    a, b = k[:-1], k[1:]
    t = (a[:, None] + (b - a)[:, None] * (np.arange(per_span) / per_span)).ravel()
    return np.r_[t, k[-1]]


def curve_polyline(c: BSplineCurve, tol: float) -> Array:
    """Points of ``c`` whose polyline stays within ``tol`` of it (midpoint test, refined where it
    fails, at most ``tolerances.TRIM_POLYLINE_LEVELS`` halvings)."""
    t = span_samples(c, 2 * (c.degree + 1))
    P = c.evaluate(t)
    for _ in range(int(tolerances.TRIM_POLYLINE_LEVELS)):
        tm = 0.5 * (t[:-1] + t[1:])
        Pm = c.evaluate(tm)
        bad = _point_segment_distance(Pm, P[:-1], P[1:]) > tol
        if not bad.any():
            break
        # refused before the refined arrays exist: t, P, their midpoints and the sort (~10 floats a point)
        V.check_size((t.size + int(bad.sum()), 10), f"tol = {tol:.3g}: a p-curve's polyline within tol")
        order = np.argsort(np.r_[t, tm[bad]], kind="stable")
        t = np.r_[t, tm[bad]][order]
        P = np.r_[P, Pm[bad]][order]
    return P


def loop_polyline(loop: Loop, tol: float) -> Array:
    pts = np.concatenate([curve_polyline(c, tol)[:-1] if i < len(loop) - 1 else curve_polyline(c, tol)
                          for i, c in enumerate(loop)])
    return np.r_[pts, pts[:1]]


def _point_segment_distance(P: Array, A: Array, B: Array) -> Array:
    """Distance from ``P[i]`` to segment ``A[i] B[i]`` (all ``(m, 2)``)."""
    d = B - A
    L2 = np.einsum("ij,ij->i", d, d)
    with np.errstate(invalid="ignore", divide="ignore"):
        t = np.where(L2 > 0, np.einsum("ij,ij->i", P - A, d) / L2, 0.0)
    t = np.clip(t, 0.0, 1.0)
    return np.linalg.norm(P - (A + t[:, None] * d), axis=1)


#: Entries (a segment in one of its bands) placed at a time by :func:`segment_bands`.
_BAND_BLOCK = 1 << 20


@dataclass(frozen=True)
class SegmentBands:
    """Segments binned into horizontal bands for :func:`classify_points` (:func:`segment_bands`):
    what depends on the segments and ``tol`` only, so a region classified many times (the sections
    of a face with hundreds of holes: ~1e6 segments) bins them once."""

    A: Array
    B: Array
    tol: float
    y0: float
    y1: float
    h: float
    nb: int
    seg_sorted: NDArray[np.integer]  # int32 where the entries fit
    start: NDArray[np.intp]


def segment_bands(seg_a: ArrayLike, seg_b: ArrayLike, tol: float = 0.0, *, keep: ArrayLike | None = None
                  ) -> SegmentBands:
    """The segments ``seg_a[i] -> seg_b[i]`` (shape (k, 2) each) binned into ``k`` horizontal bands
    of their ``v`` range, each segment in every band its ``v`` range widened by ``tol`` meets.

    ``keep`` (bool, shape (k,)): the segments to bin, the others left out as if absent (the bands
    and their entries those of the kept segments alone, the entries numbering them among all):
    ``seg_a = P[:-1]``, ``seg_b = P[1:]`` over polylines laid end to end in ``P`` are views of one
    array, the step from one polyline's last point to the next one's first left out."""
    A = np.asarray(seg_a, float).reshape(-1, 2)
    B = np.asarray(seg_b, float).reshape(-1, 2)
    idx = None
    if keep is not None:
        mask = np.asarray(keep)
        if mask.dtype != np.bool_ or mask.shape != (A.shape[0],):
            raise InvalidGeometryError(f"keep: expected a bool mask of shape ({A.shape[0]},), one per segment, got "
                                       f"{mask.dtype} of shape {mask.shape}")
        idx = np.flatnonzero(mask).astype(np.int32 if A.shape[0] < 2 ** 31 - 1 else np.int64)
    k = A.shape[0] if idx is None else idx.size
    if k == 0:
        empty = np.zeros(0, np.intp)
        return SegmentBands(A, B, float(tol), 0.0, 0.0, 1.0, 1, empty, np.zeros(2, np.intp))
    av, bv = (A[:, 1], B[:, 1]) if idx is None else (A[idx, 1], B[idx, 1])
    ylo = np.minimum(av, bv) - tol
    yhi = np.maximum(av, bv) + tol
    del av, bv
    y0, y1 = float(ylo.min()), float(yhi.max())
    # As many bands as segments, but no more than keep the entries (a segment once per band it
    # meets) within ~4 k: a face with hundreds of small holes has short, steep segments, each of
    # which met ~22 of k bands (34 M entries, 300 MB, for the 1e6 segments of a 361-hole plate).
    # Fewer, taller bands hold as many segments per band there; the answers do not depend on it.
    extent = float((yhi - ylo).sum())
    nb = k if extent <= 0 else min(k, int(3.0 * k * (y1 - y0) / extent) + 1)
    nb = int(np.clip(nb, 1, 1 << 20))
    h = (y1 - y0) / nb if y1 > y0 else 1.0
    b0 = np.clip(((ylo - y0) / h).astype(np.int64), 0, nb - 1)
    b1 = np.clip(((yhi - y0) / h).astype(np.int64), 0, nb - 1)
    del ylo, yhi
    cnt = b1 - b0 + 1
    n = int(cnt.sum())
    # Band j's entries are its segments in increasing order (a stable sort of the entries by band):
    # each band's count from where the segments' runs of bands start and end, and the entries
    # placed into their bands block by block of segments (_BAND_BLOCK entries at a time), each
    # block's after the blocks before it. A face with 361 holes has ~6e6 entries for 1.5e6
    # segments: sorting the entries all at once took +224 MB of temporaries beside the 24 MB kept
    # (the 1089-face plate of benchmarks/bench_check.py, whose check's peak it set); now +120 MB,
    # mostly the segments' own arrays (their bands' range, counts and ends, 8 bytes each a segment).
    it: type[np.signedinteger[Any]] = np.int32 if max(n, A.shape[0], nb) < 2 ** 31 - 1 else np.int64
    per_band = np.cumsum(np.bincount(b0, minlength=nb + 1) - np.bincount(b1 + 1, minlength=nb + 1))[:nb]
    start = np.zeros(nb + 1, np.intp)
    np.cumsum(per_band, out=start[1:])
    seg_sorted = np.empty(n, it)
    free = start[:-1].copy()  # each band's next place
    ends = np.cumsum(cnt)
    s0 = 0
    while s0 < k:
        s1 = max(s0 + 1, int(np.searchsorted(ends, (ends[s0 - 1] if s0 else 0) + _BAND_BLOCK, side="right")))
        c = cnt[s0:s1]
        m = int(c.sum())
        seg = np.repeat(np.arange(s0, s1, dtype=it) if idx is None else idx[s0:s1].astype(it), c)
        band = np.arange(m, dtype=np.intp) - np.repeat(np.cumsum(c) - c, c) + np.repeat(b0[s0:s1], c)
        order = np.argsort(band, kind="stable")
        band, seg = band[order], seg[order]
        rank = np.arange(m) - np.searchsorted(band, band)  # the entry's place among its band's in this block
        seg_sorted[free[band] + rank] = seg
        free += np.bincount(band, minlength=nb)
        s0 = s1
    return SegmentBands(A, B, float(tol), y0, y1, h, nb, seg_sorted, start)


def classify_points(points: ArrayLike, seg_a: ArrayLike | None = None, seg_b: ArrayLike | None = None,
                    tol: float = 0.0, *, bands: SegmentBands | None = None) -> NDArray[np.int8]:
    """Crossing-number point-in-polygon test against a set of segments, vectorised.

    Parameters
    ----------
    points : array_like, shape (m, 2)
    seg_a, seg_b : array_like, shape (k, 2)
        Segment ends; the segments of all closed loops of the region (even-odd rule).
    tol : float
        Points within ``tol`` of a segment are :data:`ON`.
    bands : SegmentBands, optional
        The segments already binned (:func:`segment_bands`; its segments and ``tol`` are used, and
        ``seg_a``, ``seg_b``, ``tol`` are ignored): the same result, without binning them again.

    Returns
    -------
    ndarray of int8, shape (m,)
        :data:`INSIDE`, :data:`ON` or :data:`OUTSIDE`.

    Notes
    -----
    A ray from each point towards ``+u`` crosses a segment ``(a, b)`` when ``(a_v > p_v) !=
    (b_v > p_v)`` and the crossing lies right of the point (half-open rule: a vertex on the ray
    is counted once). Segments are binned into at most ``k`` horizontal bands of the ``v`` range
    (a segment in every band its ``v`` range, widened by ``tol``, meets; fewer bands where the
    segments are steep, :func:`segment_bands`); each point meets only the segments of its band, in
    blocks of at most ``2**22`` point-segment pairs.
    """
    if bands is None:
        if seg_a is None or seg_b is None:
            raise InvalidGeometryError("seg_a, seg_b: expected the segments' ends (or bands=segment_bands(...))")
        bands = segment_bands(seg_a, seg_b, tol)
    P = np.asarray(points, float).reshape(-1, 2)
    A, B, tol = bands.A, bands.B, bands.tol
    m, k = P.shape[0], A.shape[0]
    state = np.full(m, OUTSIDE, np.int8)
    if m == 0 or k == 0:
        return state
    y0, y1, h, nb, seg_sorted, start = bands.y0, bands.y1, bands.h, bands.nb, bands.seg_sorted, bands.start
    in_range = (P[:, 1] >= y0) & (P[:, 1] <= y1)
    idx = np.flatnonzero(in_range)
    pb = np.clip(((P[idx, 1] - y0) / h).astype(np.int64), 0, nb - 1)
    n_pairs = start[pb + 1] - start[pb]
    lo = 0
    csum = np.cumsum(n_pairs)
    while lo < idx.size:
        hi = int(np.searchsorted(csum, (csum[lo - 1] if lo else 0) + _PAIR_BLOCK, side="right"))
        hi = max(hi, lo + 1)
        _classify_block(P, A, B, tol, idx[lo:hi], start[pb[lo:hi]], n_pairs[lo:hi], seg_sorted, state)
        lo = hi
    return state


def _classify_block(P: Array, A: Array, B: Array, tol: float, pts: NDArray[np.intp], first: NDArray[np.intp],
                    count: NDArray[np.intp], seg_sorted: NDArray[np.integer], state: NDArray[np.int8]) -> None:
    total = int(count.sum())
    if total == 0:
        return
    local = np.repeat(np.arange(pts.size), count)
    offs = np.arange(total) - np.repeat(np.cumsum(count) - count, count)
    seg = seg_sorted[np.repeat(first, count) + offs]
    at = pts[local]
    pu, pv = P[at, 0], P[at, 1]
    au, av, bu, bv = A[seg, 0], A[seg, 1], B[seg, 0], B[seg, 1]
    cross = np.flatnonzero((av > pv) != (bv > pv))  # the pairs whose segment straddles the point's ray
    with np.errstate(invalid="ignore", divide="ignore"):
        x = au[cross] + (pv[cross] - av[cross]) * (bu[cross] - au[cross]) / (bv[cross] - av[cross])
    crossings = np.bincount(local[cross], weights=pu[cross] < x, minlength=pts.size)
    inside = (crossings.astype(np.int64) % 2) == 1
    on = np.zeros(pts.size, bool)
    if tol > 0:  # distances only where the point lies in the segment's box widened by 2 tol (the others are farther than tol)
        w = 2.0 * tol
        box = np.flatnonzero((pu >= np.minimum(au, bu) - w) & (pu <= np.maximum(au, bu) + w))
        ab = seg[box]
        near = _point_segment_distance(np.c_[pu[box], pv[box]], A[ab], B[ab]) <= tol
        on[local[box[near]]] = True
    state[pts] = np.where(on, ON, np.where(inside, INSIDE, OUTSIDE))


def grid_inside(polygon: Array, gx: Array, gy: Array) -> NDArray[np.bool_]:
    """Which nodes ``(gx[i], gy[j])`` of a grid lie inside the closed ``polygon`` (m, 2), shape
    ``(len(gx), len(gy))``, by the crossing number: the edges ``a -> b`` with ``(a_y > y) != (b_y > y)``
    whose crossing ``x`` lies right of the node, counted odd.

    A grid row shares its ``y``: the edges it straddles and their crossings are found once per row
    and the nodes counted by a sorted search, where testing every node against every edge (4 000
    nodes x 2 000 edges, 0.1 s a hole) made arrays of both at once. The crossings are the same
    floating-point numbers and the comparisons the same, so the answer is the same, node for node."""
    a, b = polygon, np.roll(polygon, -1, axis=0)
    straddle = (a[None, :, 1] > gy[:, None]) != (b[None, :, 1] > gy[:, None])  # (rows, edges)
    inside = np.zeros((len(gx), len(gy)), bool)
    for j in np.flatnonzero(straddle.any(axis=1)):  # a loop over grid rows, each vectorised
        k = np.flatnonzero(straddle[j])
        cross_x = np.sort(a[k, 0] + (b[k, 0] - a[k, 0]) * (gy[j] - a[k, 1]) / (b[k, 1] - a[k, 1]))
        inside[:, j] = (k.size - np.searchsorted(cross_x, gx, side="right")) % 2 == 1
    return inside
