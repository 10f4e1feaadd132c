"""The reference plane of a plate fill (:func:`.plate_fill.fill_plate`, course §8-3): the plane over
which a hole's loop is a height field, chosen among the loop's vector-area (Newell) normal, the
mean neighbour normal, the principal-axes normal and, where none of those passes, the axis of the
smallest cap holding the neighbour normals (:func:`plate_plane`, described in :mod:`.plate_fill`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import tolerances
from ..errors import InvalidGeometryError

__all__ = ["plate_plane"]

Array = NDArray[np.float64]


# ===================================================================================== the plane
def _crossings(Q: Array) -> tuple[int, int] | None:
    """A pair of non-adjacent segments of the closed polyline ``Q`` (shape (m, 2)) that cross, or None:
    the first ``(i, j)``, ``i < j``, in lexicographic order.

    Candidate pairs come from a uniform grid (cells about twice the median segment long): each
    segment is entered in every cell its bounding box touches, and only segments sharing a cell are
    compared (boxes that overlap share a cell). The all-pairs box test it replaces cost O(m^2):
    0.4 s a plane for the 2048-point loop, 90 % of a small plate fill (three planes are judged)."""
    A, B = Q, np.roll(Q, -1, axis=0)
    m = len(Q)
    lo, hi = np.minimum(A, B), np.maximum(A, B)
    ext = float(np.max(hi.max(axis=0) - lo.min(axis=0)))
    seg = np.linalg.norm(B - A, axis=1)
    h = 2.0 * float(np.median(seg))
    if not (h > 0 and np.isfinite(h)):
        h = ext if ext > 0 else 1.0
    h = max(h, ext / 4096.0)  # at most 4096 cells a side
    origin = lo.min(axis=0)
    c0 = np.floor((lo - origin) / h).astype(np.int64)
    c1 = np.floor((hi - origin) / h).astype(np.int64)
    nx, ny = c1[:, 0] - c0[:, 0] + 1, c1[:, 1] - c0[:, 1] + 1
    count = nx * ny
    owner = np.repeat(np.arange(m), count)
    k = np.arange(count.sum()) - np.repeat(np.cumsum(count) - count, count)  # index within the segment's cells
    cx = c0[owner, 0] + k % nx[owner]
    cy = c0[owner, 1] + k // nx[owner]
    cell = cx * (int(c1[:, 1].max()) + 2) + cy
    order = np.lexsort((owner, cell))
    cell, owner = cell[order], owner[order]
    start = np.r_[0, np.flatnonzero(np.diff(cell)) + 1]
    size = np.diff(np.r_[start, cell.size])
    grp_end = np.repeat(start + size, size)
    pos = np.arange(cell.size)
    later = grp_end - pos - 1  # members after this one in its cell
    first = np.repeat(pos, later)
    second = first + 1 + (np.arange(later.sum()) - np.repeat(np.cumsum(later) - later, later))
    i, j = owner[first], owner[second]
    i, j = np.minimum(i, j), np.maximum(i, j)
    key = np.unique(i * m + j)
    i, j = key // m, key % m
    gap = j - i
    keep = (gap > 1) & (gap < m - 1) & np.all((lo[i] <= hi[j]) & (lo[j] <= hi[i]), axis=1)
    i, j = i[keep], j[keep]

    def orient(p: Array, q: Array, r: Array) -> Array:
        return (q[..., 0] - p[..., 0]) * (r[..., 1] - p[..., 1]) - (q[..., 1] - p[..., 1]) * (r[..., 0] - p[..., 0])

    a, b, c, d = A[i], B[i], A[j], B[j]
    hit = (orient(a, b, c) * orient(a, b, d) < 0) & (orient(c, d, a) * orient(c, d, b) < 0)
    if not hit.any():
        return None
    n = int(np.argmax(hit))  # keys are sorted: the first hit is the lexicographically first pair
    return int(i[n]), int(j[n])


def _widest_cap_axis(M: Array, iterations: int = 400) -> Array:
    """The axis of the smallest spherical cap holding the unit vectors ``M`` (shape (m, 3)): the
    direction that the most-leaning of them leans least from (the minimax plane normal).

    Badoiu and Clarkson's core-set iteration for the smallest enclosing ball ("Smaller core-sets for
    balls", SODA 2003: step towards the farthest point by 1/(k+1)); for points on the unit sphere
    within a hemisphere the ball's centre points along the cap's axis. Error ~ 1/iterations of the
    cap's radius: a candidate plane, judged afterwards like the others."""
    c = M.mean(axis=0)
    for k in range(1, iterations + 1):
        far = M[int(np.argmax(np.einsum("ij,ij->i", M - c, M - c)))]
        c = c + (far - c) / (k + 1)
    return c


def _judge(P: Array, Q: Array, M: Array, g1: NDArray[np.bool_], N: Array, newell: Array
           ) -> tuple[tuple[Array, Array, Array, Array, float] | None, str]:
    """One candidate plane normal ``N``: ``(frame, "")`` when the hole is a height field over it
    (loop simple in projection, every G1 normal leaning less than ``FILL_PLATE_MAX_TILT``), else
    ``(None, why)``."""
    length = float(np.linalg.norm(N))
    if not np.isfinite(length) or length == 0:
        return None, "no direction"
    N = N / length
    if float(newell @ N) < 0:
        N = -N  # the loop runs counter-clockwise about the normal
    e1, e2 = _in_plane_axes(Q, N)
    uv = np.c_[Q @ e1, Q @ e2]
    area = 0.5 * float(np.sum(uv[:, 0] * np.roll(uv[:, 1], -1) - np.roll(uv[:, 0], -1) * uv[:, 1]))
    scale = float(np.ptp(uv, axis=0).max()) or 1.0
    if area <= 1e-9 * scale * scale:
        return None, "the loop encloses no area in projection (it winds back over itself)"
    max_tilt = tolerances.FILL_PLATE_MAX_TILT
    cosines = M[g1] @ N if g1.any() else np.ones(1)
    lean = float(np.degrees(np.arccos(np.clip(cosines.min(), -1.0, 1.0))))
    if lean >= max_tilt:
        k = int(np.flatnonzero(g1)[np.argmin(cosines)])
        return None, (f"a neighbour's tangent plane stands at {lean:.1f} deg to it (at "
                      f"{np.array2string(P[k], precision=4)}; at most {max_tilt:g} deg, "
                      "tolerances.FILL_PLATE_MAX_TILT; beyond 90 it turns back over the hole)")
    hit = _crossings(uv)
    if hit is not None:
        return None, (f"the loop crosses itself in projection (samples {hit[0]} and {hit[1]} of {len(P)}, "
                      f"near {np.array2string(P[hit[0]], precision=4)})")
    return (P.mean(axis=0), e1, e2, N, lean), ""


def plate_plane(points: Array, normals: Array, g1: NDArray[np.bool_] | None = None,
                normal: ArrayLike | None = None) -> tuple[Array, Array, Array, Array, float]:
    """The reference plane of a hole over which its fill is a height field.

    Parameters
    ----------
    points : ndarray, shape (m, 3)
        The loop, densely sampled, in order (closed implicitly).
    normals : ndarray, shape (m, 3)
        Neighbour normals ``cross x tangent`` at the samples (any length; the orientation the
        loop gives: for a loop running counter-clockwise about the fill's normal they point to
        the fill's side).
    g1 : ndarray of bool, shape (m,), optional
        Samples whose neighbour normal must lean less than ``tolerances.FILL_PLATE_MAX_TILT``
        from the plane normal (default: all).

    Returns
    -------
    (origin, e1, e2, normal, lean)
        The frame and the largest lean (degrees) of a G1 normal from ``normal``.

    Notes
    -----
    Candidates, in order: the loop's vector area (Newell), the mean neighbour normal, the principal
    axes' normal; of those that pass, the one with the least lean. Only when none passes, the axis
    of the smallest cap holding the G1 normals (:func:`_widest_cap_axis`: the least lean any plane
    can have) and that axis tilted towards the Newell normal (1/3, 2/3 of the way: a plane between
    the two trades lean for a simpler projection) are tried, in that order (the first that passes
    is kept), so that the holes the first three fill keep their fill.

    Raises
    ------
    InvalidGeometryError
        No candidate plane has the loop project one-to-one with every G1 normal leaning less than
        the limit; the message says why for each candidate.
    """
    P = np.asarray(points, float)
    M = np.asarray(normals, float)
    M = M / np.maximum(np.linalg.norm(M, axis=1, keepdims=True), 1e-300)
    g1 = np.ones(len(P), bool) if g1 is None else np.asarray(g1, bool)
    o = P.mean(axis=0)
    Q = P - o
    newell = 0.5 * np.cross(Q, np.roll(Q, -1, axis=0)).sum(axis=0)
    if normal is not None:
        frame, reason = _judge(P, Q, M, g1, np.asarray(normal, float).ravel(), newell)
        if frame is None:
            raise InvalidGeometryError(f"plate fill: not a height field over the plane asked: {reason}")
        return frame
    mean_n = M.sum(axis=0)
    _, _, Vt = np.linalg.svd(Q, full_matrices=False)
    best, why = None, []
    for name, N in (("vector area", newell), ("mean neighbour normal", mean_n), ("principal axes", Vt[2])):
        frame, reason = _judge(P, Q, M, g1, N, newell)
        if frame is None:
            why.append(f"{name}: {reason}")
        elif best is None or frame[4] < best[4]:
            best = frame
    if best is not None:
        return best
    G = M[g1] if g1.any() else M
    axis = _widest_cap_axis(G)
    nn = newell / max(float(np.linalg.norm(newell)), 1e-300)
    axis = axis / max(float(np.linalg.norm(axis)), 1e-300)
    for name, N in (("widest-cap axis", axis), ("cap axis 1/3 towards the vector area", 2 * axis + nn),
                    ("cap axis 2/3 towards the vector area", axis + 2 * nn)):
        frame, reason = _judge(P, Q, M, g1, N, newell)
        if frame is not None:
            return frame
        why.append(f"{name}: {reason}")
    raise InvalidGeometryError("plate fill: not a height field over any plane tried (" + "; ".join(why) + ")")


def _in_plane_axes(Q: Array, N: Array) -> tuple[Array, Array]:
    """``e1``: the principal axis of the points ``Q`` projected onto the plane of normal ``N`` (the
    bounding box then hugs the loop, and the frame turns with the data: rigid motions commute with
    the fill); ``e2 = N x e1``."""
    F = Q - np.outer(Q @ N, N)
    _, _, Vt = np.linalg.svd(F, full_matrices=False)
    e1 = Vt[0] - (Vt[0] @ N) * N
    e1 /= np.linalg.norm(e1)
    return e1, np.cross(N, e1)
