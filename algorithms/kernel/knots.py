"""Knot insertion, refinement, removal, clamping and Bézier extraction (course §2-10, §2-11).

All functions act on *poles* of any trailing shape ``(n, ...)``: Cartesian points, homogeneous
points (rational splines, weight last) or whole rows of a surface net, so surfaces reuse them
along either direction without copying code. They trust their input (validated by the classes).

References
----------
W. Boehm, "Inserting new knots into B-spline curves", CAD 12 (1980) — single knot.
E. Cohen, T. Lyche, R. Riesenfeld, "Discrete B-splines and subdivision techniques", CGIP 14
(1980) — the Oslo algorithm for knot refinement. Piegl & Tiller, *The NURBS Book*, 2nd ed.,
A5.1 (insertion), A5.8 (removal), A5.6 (decomposition into Bézier segments).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from .._validate import check_size, knot_tol
from ..errors import InvalidGeometryError, ParameterError
from .basis import find_span
from .blossom import blossom_basis

__all__ = [
    "refinement_knots",
    "multiplicity",
    "distinct_knots",
    "snap_knot",
    "snap_knots",
    "insert_knot_boehm",
    "refinement_matrix",
    "refine_poles",
    "most_repeated",
    "remove_knot_lsq",
    "clamp_poles",
    "bezier_poles",
    "split_poles",
    "rescale_knots",
]

Array = NDArray[np.float64]

#: Floats gathered at a time by :func:`refine_poles` (16 MB): its old pole rows, p + 1 for each new pole.
REFINE_BLOCK = 1 << 21


def distinct_knots(knots: Array) -> tuple[Array, NDArray[np.intp]]:
    """Distinct knot values and multiplicities (exact equality, as OCC's ``BSplCLib::Knots``).

    ``knots`` is a knot vector (non-decreasing): the runs of equal values are found by one
    comparison of neighbours, where ``np.unique`` sorted a copy first; the same values and counts."""
    new = np.empty(knots.shape[0], dtype=bool)
    new[0] = True
    np.not_equal(knots[1:], knots[:-1], out=new[1:])
    first = np.flatnonzero(new)
    counts = np.empty_like(first)
    counts[:-1] = first[1:] - first[:-1]  # np.diff(np.r_[first, n]) without the two wrappers (~20 us)
    counts[-1] = knots.shape[0] - first[-1]
    return knots[first], counts


def multiplicity(knots: Array, u: float) -> int:
    """How many times ``u`` occurs in ``knots`` (within the knot-equality tolerance)."""
    return int(np.count_nonzero(np.abs(knots - u) <= knot_tol(knots)))


def snap_knot(knots: Array, u: float) -> float:
    """Return the existing knot equal to ``u`` within tolerance, else ``u`` itself."""
    i = int(np.argmin(np.abs(knots - u)))
    return float(knots[i]) if abs(knots[i] - u) <= knot_tol(knots) else float(u)


def snap_knots(knots: Array, values: Array) -> Array:
    """Vectorised :func:`snap_knot`: each value replaced by an existing knot within tolerance."""
    tol = knot_tol(knots)
    i = np.minimum(np.maximum(np.searchsorted(knots, values), 1), knots.shape[0] - 1)  # np.clip without its wrapper
    left, right = knots[i - 1], knots[i]
    nearest = np.where(np.abs(values - left) <= np.abs(right - values), left, right)
    return np.where(np.abs(nearest - values) <= tol, nearest, values)


def insert_knot_boehm(knots: Array, degree: int, poles: Array, u: float, times: int) -> tuple[Array, Array]:
    """Insert ``u`` ``times`` times by Boehm's algorithm (NURBS Book A5.1).

    Requires ``multiplicity(u) + times <= degree + 1`` and ``u`` inside the domain.

    Returns
    -------
    knots : ndarray, shape (n + degree + 1 + times,)
    poles : ndarray, shape (n + times, ...)
    """
    p = degree
    n = poles.shape[0]
    k = int(find_span(knots, p, n, np.array([u]))[0])
    s = int(np.count_nonzero(knots == u))
    r = times
    # If u equals the right end of the span found (domain end), A5.1's span is the one ending there.
    new_knots = np.concatenate((knots[: k + 1], np.full(r, u), knots[k + 1 :]))
    Q = np.empty((n + r,) + poles.shape[1:])
    Q[: k - p + 1] = poles[: k - p + 1]
    Q[k - s + r :] = poles[k - s :]
    R = poles[k - p : k - s + 1].copy()
    L = k - p
    for j in range(1, r + 1):
        L = k - p + j
        i = np.arange(p - j - s + 1)
        alpha = (u - knots[L + i]) / (knots[i + k + 1] - knots[L + i])
        alpha = alpha.reshape((-1,) + (1,) * (poles.ndim - 1))
        R[: p - j - s + 1] = alpha * R[1 : p - j - s + 2] + (1.0 - alpha) * R[: p - j - s + 1]
        Q[L] = R[0]
        Q[k + r - j - s] = R[p - j - s]
    for jj in range(L + 1, k - s):
        Q[jj] = R[jj - L]
    return new_knots, Q


def refinement_matrix(knots: Array, degree: int, new_knots: Array) -> Array:
    """Oslo knot-refinement matrix ``T`` with ``new_poles = T @ poles`` (discrete B-splines).

    Parameters
    ----------
    knots : ndarray, shape (n + degree + 1,)
    new_knots : ndarray, shape (n2 + degree + 1,)
        A refinement of ``knots`` (every old knot present at least as often), with the same
        first and last knots.

    Returns
    -------
    ndarray, shape (n2, n)
        Row ``i`` holds the blossom weights ``f(tau_{i+1}, ..., tau_{i+p})`` (course §2-10): the
        discrete B-splines ``alpha_j(i)``, exact on the whole knot range ``[t_0, t_last]``, so the
        outer poles of an unclamped spline (those whose basis functions miss the domain) are
        refined correctly too.
    """
    p = degree
    n = knots.shape[0] - p - 1
    n2 = new_knots.shape[0] - p - 1
    i = np.arange(n2)
    mu, args, A = _oslo_rows(knots, p, new_knots)
    T = np.zeros((n2, n))
    if A is not None:
        T[i[:, None], mu[:, None] - p + np.arange(p + 1)] = A
        return T
    # Outside the domain a span has fewer than p + 1 basis functions: pad the knot vector with p
    # copies of each end knot so that every span has p + 1 columns, and drop the padding's
    # columns. Each column is one basis function's blossom, unaffected by the padding; every
    # denominator of the recurrence contains the non-empty span mu, so none vanishes.
    padded = np.concatenate((np.full(p, knots[0]), knots, np.full(p, knots[-1])))
    A = blossom_basis(padded, p, mu + p, args)
    cols = mu[:, None] - p + np.arange(p + 1)
    real = (cols >= 0) & (cols < n)
    T[np.broadcast_to(i[:, None], cols.shape)[real], cols[real]] = A[real]
    return T


def _oslo_rows(knots: Array, degree: int, new_knots: Array) -> tuple[NDArray[np.intp], Array, Array | None]:
    """For each new pole ``i`` of the refinement: the old span ``mu`` whose blossom gives it
    (:func:`support_span`), the blossom arguments ``new_knots[i+1 .. i+degree]`` (n2, degree), and,
    where every ``mu`` lies in the domain (a clamped knot vector's case), the ``degree + 1``
    weights on the old poles ``mu - degree .. mu`` (n2, degree + 1); ``None`` otherwise."""
    p = degree
    n = knots.shape[0] - p - 1
    i = np.arange(new_knots.shape[0] - p - 1)
    args = new_knots[i[:, None] + 1 + np.arange(p)[None, :]]  # (n2, p)
    mu = support_span(knots, new_knots, i)  # 0 <= mu <= n + p - 1, maybe outside [p, n - 1]
    if mu[0] >= p and mu[-1] <= n - 1:  # mu is non-decreasing in i
        return mu, args, blossom_basis(knots, p, mu, args)
    return mu, args, None


def support_span(knots: Array, new_knots: Array, i: NDArray[np.intp]) -> NDArray[np.intp]:
    """A non-empty old span ``[t_mu, t_{mu+1})`` inside the support of each new basis function ``i``.

    ``new_knots`` refines ``knots`` (or, for degree raising, has the same distinct values), so
    every non-empty new span lies in one old span. The result may lie outside the domain
    ``[p, n - 1]`` when the new basis function misses the domain (unclamped knot vectors).
    Used by knot refinement (:func:`refinement_matrix`) and degree raising
    (:func:`occsurf.algorithms.kernel.degree.elevate_poles`) to pick the span whose blossom
    gives a new pole.

    Parameters
    ----------
    knots : ndarray, shape (n + p + 1,)
        The old knot vector.
    new_knots : ndarray, shape (n2 + p2 + 1,)
        The new knot vector (a refinement of ``knots``, or the same distinct values).
    i : ndarray of int, shape (m,)
        Indices of new basis functions.

    Returns
    -------
    ndarray of int, shape (m,)
        ``mu`` with ``knots[mu] < knots[mu + 1]``.
    """
    # First non-empty new span at or after tau_i: last index k with tau_k <= tau_i.
    k = np.searchsorted(new_knots, new_knots[i], side="right") - 1
    k = np.minimum(k, new_knots.shape[0] - 2)
    mid = 0.5 * (new_knots[k] + new_knots[k + 1])
    return np.searchsorted(knots, mid, side="right") - 1


def refine_poles(knots: Array, degree: int, poles: Array, new_knots: Array) -> Array:
    """Poles on ``new_knots`` (a refinement of ``knots``) describing the same spline.

    Each new pole is the blossom of one piece at its knots (course §2-10): ``degree + 1`` weights on
    consecutive old poles, so where every piece needed lies in the domain (a clamped knot vector)
    the weights multiply those rows directly, ``(degree + 1) x`` the work of the output instead of
    the dense product with :func:`refinement_matrix` (new x old poles, mostly zeros). The same
    values to round-off: the non-zero terms of each row in the same order, summed by a batched
    matmul instead of BLAS's blocked product, neither of which promises an order.
    """
    p = degree
    n2 = new_knots.shape[0] - p - 1
    mu, _, A = _oslo_rows(knots, p, new_knots)
    flat = poles.reshape(poles.shape[0], -1)
    if A is not None:  # every piece in the domain
        # each new pole: its p + 1 weights times its p + 1 old pole rows, as one batched matmul, in
        # blocks of rows so that the gathered rows stay within REFINE_BLOCK floats (at most p + 1
        # times the output otherwise, which the callers' size checks do not count)
        rows = max(1, REFINE_BLOCK // ((p + 1) * max(flat.shape[1], 1)))
        out = np.empty((n2, flat.shape[1]))
        for r0 in range(0, n2, rows):
            sl = slice(r0, min(r0 + rows, n2))
            out[sl] = np.matmul(A[sl, None, :], flat[(mu[sl] - p)[:, None] + np.arange(p + 1)])[:, 0]
    else:
        out = refinement_matrix(knots, p, new_knots) @ flat
    return out.reshape((n2,) + poles.shape[1:])


def refinement_knots(knots: Array, degree: int, n_poles: int, width: int, x: Array) -> Array:
    """The refined knot vector for inserting the values ``x`` (not empty), with the refinement's
    checks: its arrays within ``tolerances.MAX_ARRAY_BYTES`` (``width``: floats per pole), every
    value strictly inside the domain, each snapped to an existing knot within the knot tolerance,
    and no knot above multiplicity ``degree + 1``. What :meth:`BSplineCurve.refine` inserts.

    Raises
    ------
    ParameterError
        A value on or outside the domain.
    InvalidGeometryError
        A knot would exceed multiplicity ``degree + 1``.
    """
    # The Oslo matrix (dense: new poles x old poles), the refined poles and the merge's work arrays.
    check_size((n_poles + x.size, max(n_poles, width + 4)), f"refine with {x.size} knots")
    lo, hi = float(knots[degree]), float(knots[n_poles])
    if x.min() <= lo or x.max() >= hi:
        bad = float(x.min() if x.min() <= lo else x.max())
        raise ParameterError(f"knots: {bad!r} must lie strictly inside the domain ({lo!r}, {hi!r})")
    tau = merge_knots(knots, snap_knots(knots, x))
    excess = most_repeated(tau, degree + 1)
    if excess is not None:
        raise InvalidGeometryError(
            f"knots: knot {excess[0]!r} would get multiplicity {excess[1]}, above degree + 1 = {degree + 1}"
        )
    return tau


def merge_knots(knots: Array, extra: Array) -> Array:
    """The knot vector with ``extra`` values added (sorted merge)."""
    return np.sort(np.concatenate((knots, extra)), kind="stable")


def most_repeated(knots: Array, limit: int) -> tuple[float, int] | None:
    """The knot value of a sorted knot vector repeated more than ``limit`` times, and its count.

    ``None`` when no value exceeds ``limit``. In a sorted vector a value occurs more than ``limit``
    times exactly where ``t[i] == t[i + limit]``, one comparison per knot; the counts (a sort of
    their own) are taken only for the message of a vector that fails.
    """
    if knots.shape[0] <= limit or not np.any(knots[limit:] == knots[:-limit]):
        return None
    vals, counts = np.unique(knots, return_counts=True)
    i = int(np.argmax(counts))
    return float(vals[i]), int(counts[i])


def remove_knot_lsq(
    knots: Array, degree: int, poles: Array, u: float, times: int, deviation: Callable[[Array, Array], float]
) -> tuple[Array, Array, float]:
    """Remove ``times`` copies of the knot ``u``; the new poles are the least-squares solution.

    The spline after removal, re-expressed on the original knots, is ``T @ Q`` with ``T`` the Oslo
    matrix; ``Q`` minimises ``||T Q - P||`` over the few poles that removal can change. The
    returned deviation is ``deviation(T @ Q, P)``, the largest movement of any pole of the
    original representation, which bounds the movement of the curve (convex-hull property).
    Exactly removable knots come back exactly (to round-off); the caller compares the deviation
    with its tolerance.

    Returns
    -------
    new_knots, new_poles, deviation
    """
    p = degree
    n = poles.shape[0]
    idx = np.flatnonzero(knots == u)
    keep = np.ones(knots.shape[0], bool)
    keep[idx[:times]] = False
    reduced = knots[keep]
    n2 = n - times
    T = refinement_matrix(reduced, p, knots)  # (n, n2)
    flat = poles.reshape(n, -1)
    # Columns whose basis function changes when u is re-inserted: a window around u.
    k = int(find_span(reduced, p, n2, np.array([u]))[0])
    s = int(np.count_nonzero(reduced == u))
    c0 = max(k - p, 0)
    c1 = min(k - s, n2 - 1)
    r0 = c0
    r1 = min(k - s + times, n - 1)
    Q = np.empty((n2, flat.shape[1]))
    Q[:c0] = flat[:c0]
    Q[c1 + 1 :] = flat[c1 + 1 + times :]
    rows = slice(r0, r1 + 1)
    cols = slice(c0, c1 + 1)
    rhs = flat[rows] - T[rows, : c0] @ Q[:c0] - T[rows, c1 + 1 :] @ Q[c1 + 1 :]
    sol, *_ = np.linalg.lstsq(T[rows, cols], rhs, rcond=None)
    Q[cols] = sol
    refined = T @ Q
    dev = float(deviation(refined.reshape(poles.shape), poles))
    return reduced, Q.reshape((n2,) + poles.shape[1:]), dev


def clamp_poles(knots: Array, degree: int, poles: Array) -> tuple[Array, Array]:
    """Equivalent clamped representation on the domain ``[t_p, t_n]`` (ends of multiplicity p+1)."""
    p = degree
    n = poles.shape[0]
    a, b = knots[p], knots[n]
    if knots[0] == a and knots[-1] == b:  # non-decreasing knots: p + 1 copies of each end already
        return knots, poles
    extra = np.concatenate((np.full(max(p + 1 - int(np.count_nonzero(knots == a)), 0), a),
                            np.full(max(p + 1 - int(np.count_nonzero(knots == b)), 0), b)))
    tau = merge_knots(knots, extra)
    Q = refine_poles(knots, p, poles, tau)
    # Keep the part between the (p+1)-fold end knots.
    first = int(np.searchsorted(tau, a, side="left"))
    last = int(np.searchsorted(tau, b, side="right"))  # one past the last b
    new_knots = tau[first:last]
    return new_knots, Q[first : first + new_knots.shape[0] - p - 1]


def bezier_poles(knots: Array, degree: int, poles: Array) -> tuple[Array, Array]:
    """Bézier control points of every non-empty span (course §2-11; NURBS Book A5.6).

    Returns
    -------
    breaks : ndarray, shape (n_seg + 1,)
        Distinct knots of the domain.
    segments : ndarray, shape (n_seg, degree + 1, ...)
    """
    p = degree
    knots, poles = clamp_poles(knots, p, poles)
    vals, mult = distinct_knots(knots)
    add = np.repeat(vals[1:-1], np.maximum(p - mult[1:-1], 0))
    if add.size:
        tau = merge_knots(knots, add)
        poles = refine_poles(knots, p, poles, tau)
        knots = tau
    # Segment j is the span ending at the last copy of vals[j]; its poles are k-p .. k.
    k = np.searchsorted(knots, vals[:-1], side="right") - 1
    idx = k[:, None] - p + np.arange(p + 1)[None, :]
    return vals, poles[idx]


def split_poles(knots: Array, degree: int, poles: Array, u: float) -> tuple[tuple[Array, Array], tuple[Array, Array]]:
    """Split at the interior parameter ``u``: insert it up to multiplicity ``degree + 1``.

    Returns
    -------
    (left_knots, left_poles), (right_knots, right_poles)
        Clamped representations of the pieces on ``[a, u]`` and ``[u, b]``.
    """
    p = degree
    t, H = clamp_poles(knots, p, poles)
    s = int(np.count_nonzero(t == u))
    if s < p + 1:
        tau = merge_knots(t, np.full(p + 1 - s, u))
        H = refine_poles(t, p, H, tau)
        t = tau
    a = int(np.searchsorted(t, u, side="left"))
    return (t[: a + p + 1], H[:a]), (t[a:], H[a:])


def check_rescaled(t: Array, knots: Array, new: tuple[float, float], what: str) -> Array:
    """Refuse a rescaled knot vector that lost the knots' structure: overflow (``b - a`` beyond the
    largest double made every knot ``inf`` or ``nan``, or an unclamped vector's knots outside the
    domain went past it) or distinct knots merged by rounding."""
    if not math.isfinite(new[1] - new[0]):
        raise ParameterError(f"{what}: the domain {new!r} is too long for doubles (its length overflows)")
    if not np.isfinite(t).all():
        raise ParameterError(f"{what}: the domain {new!r} is too long for doubles (the knots outside it, "
                             "scaled with it, overflow)")
    if np.count_nonzero(t[1:] > t[:-1]) != np.count_nonzero(knots[1:] > knots[:-1]):  # np.diff's > 0, unwrapped
        raise ParameterError(f"{what}: the domain {new!r} is too short to keep the distinct knots apart")
    tol = knot_tol(t)
    if new[1] - new[0] <= tol:
        raise ParameterError(f"{what}: the domain {new!r} is no longer than the knot tolerance {tol:.3g} "
                             "(tolerances.KNOT_EQUALITY): its ends would count as one knot")
    return t


def rescale_knots(knots: Array, old: tuple[float, float], new: tuple[float, float]) -> Array:
    """Map knots affinely from the domain ``old`` to ``new``, keeping the vector non-decreasing.

    Every copy of an old domain end becomes the new end exactly; the rest go through
    ``a + (t - lo) (b - a) / (hi - lo)``, which rounding keeps monotone, and interior knots are
    clipped into ``[a, b]`` (a product can round one ulp past an end).
    """
    (lo, hi), (a, b) = (float(x) for x in old), (float(x) for x in new)
    scale = (b - a) / (hi - lo)  # Python floats: an overflow gives inf, not an error
    reach = max(abs(float(knots[0]) - lo), abs(float(knots[-1]) - lo)) * abs(scale)  # the largest |knots - lo| scaled
    if math.isfinite(scale) and abs(a) + reach < 1e307:  # no value can overflow
        t = a + (knots - lo) * scale
    else:
        with np.errstate(over="ignore", invalid="ignore"):  # an overflowing b - a: check_rescaled says so
            t = a + (knots - lo) * scale
    inside = (knots > lo) & (knots < hi)
    # np.clip's values, by its two ufuncs without the wrapper
    t[inside] = np.minimum(np.maximum(t[inside], a), b)
    t[knots == lo] = a
    t[knots == hi] = b
    return t
