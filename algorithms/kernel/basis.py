"""B-spline basis functions, vectorised over many parameters (course §2-9, basis splines).

The kernels here loop over the degree only (a few iterations), never over parameters: every
statement acts on arrays of ``m`` parameter values at once (:func:`band_product` loops over the
groups of parameters that share a knot span, one matrix product each). They trust their input;
validation happens once in the public classes.

References
----------
L. Piegl, W. Tiller, *The NURBS Book*, 2nd ed., Springer 1997: A2.1 (span), A2.2 (basis
functions), A2.3 (derivatives). C. de Boor, *A Practical Guide to Splines*, 1978.
"""

from __future__ import annotations

import functools

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "gauss_legendre",
    "gram_bands",
    "gram_band_index",
    "find_span",
    "basis_functions",
    "basis_derivatives",
    "basis_matrix",
    "span_groups",
    "band_product",
    "greville",
]


def find_span(knots: NDArray[np.float64], degree: int, n_poles: int, u: NDArray[np.float64]) -> NDArray[np.intp]:
    """Index ``s`` of the non-empty knot span ``[t_s, t_{s+1})`` holding each parameter (A2.1).

    Parameters
    ----------
    knots : ndarray, shape (n_poles + degree + 1,)
        Full knot vector.
    degree : int
    n_poles : int
    u : ndarray, shape (m,)
        Parameters inside the domain ``[t_p, t_n]``.

    Returns
    -------
    ndarray of intp, shape (m,)
        ``degree <= s <= n_poles - 1``. The domain's right end belongs to the last non-empty span,
        so evaluation there is a limit from the left, as in OCC.
    """
    s = np.searchsorted(knots, u, side="right") - 1
    # The last non-empty span of the domain: largest s <= n-1 with t_s < t_n; the first: the last knot
    # equal to t_p. Where the domain's end spans are not empty (clamped knots) those are n-1 and p
    # themselves, which two comparisons say (two searches of ~3 us each otherwise).
    if knots[n_poles - 1] < knots[n_poles]:
        last = n_poles - 1
    else:
        last = int(np.searchsorted(knots, knots[n_poles], side="left")) - 1
    if knots[degree] < knots[degree + 1]:
        first = degree
    else:
        first = int(np.searchsorted(knots, knots[degree], side="right")) - 1
    return np.minimum(np.maximum(s, first), last)  # np.clip's integer result, without its wrapper's ~4 us


def _left_right(knots: NDArray[np.float64], p: int, span: NDArray[np.intp], u: NDArray[np.float64]
                ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The knot differences of A2.2/A2.3, shape (p + 1, m) each (row 0 unused):
    ``left[j] = u - t[span + 1 - j]``, ``right[j] = t[span + j] - u`` for ``j = 1..p``."""
    j = np.arange(1, p + 1)[:, None]
    left = np.empty((p + 1, u.shape[0]))
    right = np.empty((p + 1, u.shape[0]))
    left[1:] = u - knots[span + 1 - j]
    right[1:] = knots[span + j] - u
    return left, right


def basis_functions(
    knots: NDArray[np.float64], degree: int, span: NDArray[np.intp], u: NDArray[np.float64]
) -> NDArray[np.float64]:
    """The ``degree + 1`` non-zero basis functions at each parameter (A2.2, Cox–de Boor).

    Returns
    -------
    ndarray, shape (m, degree + 1)
        ``N[i, k] = N_{span_i - degree + k, degree}(u_i)``.
    """
    m = u.shape[0]
    p = degree
    N = np.zeros((p + 1, m))
    N[0] = 1.0
    left, right = _left_right(knots, p, span, u)
    for j in range(1, p + 1):
        # A2.2's inner loop over r = 0..j-1 as whole rows: every temp comes from the old N[r], and
        # N[r] = saved + right[r+1] temp[r] with saved = left[j-r+1] temp[r-1] (0 for r = 0)
        temp = N[:j] / (right[1:j + 1] + left[j:0:-1])
        rt = right[1:j + 1] * temp
        lt = left[j:0:-1] * temp
        N[j] = lt[j - 1]
        N[1:j] = lt[:j - 1] + rt[1:]
        N[0] = rt[0] + 0.0
    return N.T.copy()


def basis_derivatives(
    knots: NDArray[np.float64], degree: int, span: NDArray[np.intp], u: NDArray[np.float64], order: int
) -> NDArray[np.float64]:
    """Basis functions and their derivatives up to ``order`` (A2.3).

    Returns
    -------
    ndarray, shape (m, order + 1, degree + 1)
        ``D[i, k, j] = d^k/du^k N_{span_i - degree + j, degree}(u_i)``; rows ``k > degree`` are zero.
    """
    p = degree
    m = u.shape[0]
    n = min(order, p)
    ndu = np.empty((p + 1, p + 1, m))
    ndu[0, 0] = 1.0
    left, right = _left_right(knots, p, span, u)
    for j in range(1, p + 1):  # the triangle of A2.2, r = 0..j-1 as whole rows (see basis_functions)
        ndu[j, :j] = right[1:j + 1] + left[j:0:-1]
        temp = ndu[:j, j - 1] / ndu[j, :j]
        rt = right[1:j + 1] * temp
        lt = left[j:0:-1] * temp
        ndu[j, j] = lt[j - 1]
        ndu[1:j, j] = lt[:j - 1] + rt[1:]
        ndu[0, j] = rt[0] + 0.0
    ders = np.zeros((order + 1, p + 1, m))
    ders[0] = ndu[:, p]
    if n:
        # A2.3's coefficients a[s, j, r] for every r at once. For derivative k, term j is present for
        # a contiguous run of r: j = 0 for r >= k, 0 < j < k for k - j <= r <= p - j, j = k for
        # r <= p - k; each r's terms are added in A2.3's order (j increasing), its first replacing 0.
        a = np.empty((2, p + 1, p + 1, m))
        a[0, 0] = 1.0
        s1, s2 = 0, 1
        for k in range(1, n + 1):
            pk = p - k
            a1, a2 = a[s1], a[s2]
            d = np.zeros((p + 1, m))
            a2[0, k:] = a1[0, k:] / ndu[pk + 1, :p + 1 - k]
            d[k:] = a2[0, k:] * ndu[:p + 1 - k, pk]
            for j in range(1, k):
                lo, hi = k - j, p - j + 1  # r in [lo, hi); ndu's rows r - k + j
                a2[j, lo:hi] = (a1[j, lo:hi] - a1[j - 1, lo:hi]) / ndu[pk + 1, lo - k + j:hi - k + j]
                d[lo:hi] = d[lo:hi] + a2[j, lo:hi] * ndu[lo - k + j:hi - k + j, pk]
            a2[k, :pk + 1] = -a1[k - 1, :pk + 1] / ndu[pk + 1, :pk + 1]
            d[:pk + 1] = d[:pk + 1] + a2[k, :pk + 1] * ndu[:pk + 1, pk]
            ders[k] = d
            s1, s2 = s2, s1
    factor = float(p)
    for k in range(1, n + 1):
        ders[k] *= factor
        factor *= p - k
    return ders.transpose(2, 0, 1).copy()


def basis_matrix(
    knots: NDArray[np.float64], degree: int, n_poles: int, u: NDArray[np.float64], order: int = 0
) -> NDArray[np.float64]:
    """Dense collocation matrices ``B[k, i, j] = d^k/du^k N_j(u_i)`` for ``k = 0..order``.

    Used for the linear systems of fitting and knot removal. Grid evaluation multiplies by these
    matrices without forming them (:func:`band_product`).

    Returns
    -------
    ndarray, shape (order + 1, m, n_poles)
    """
    m = u.shape[0]
    span = find_span(knots, degree, n_poles, u)
    D = basis_derivatives(knots, degree, span, u, order)  # (m, order+1, p+1)
    B = np.zeros((order + 1, m, n_poles))
    cols = span[:, None] - degree + np.arange(degree + 1)  # (m, p+1)
    rows = np.broadcast_to(np.arange(m)[:, None], cols.shape)
    for k in range(order + 1):
        B[k, rows, cols] = D[:, k, :]
    return B


def span_groups(span: NDArray[np.intp]) -> list[tuple[slice | NDArray[np.intp], int]]:
    """Parameters sharing a knot span, as ``(selection, span)`` pairs covering ``0..m-1`` once.

    Runs of equal consecutive spans come back as slices (sorted parameters, the usual case);
    if the spans change more than twice as often as there are distinct spans, the parameters
    are grouped by span instead (index arrays, one per distinct span).
    """
    m = span.shape[0]
    if m == 0:
        return []
    change = np.flatnonzero(span[1:] != span[:-1]) + 1
    distinct = np.unique(span).shape[0]
    if change.shape[0] + 1 <= 2 * distinct:
        bounds = [0, *change.tolist(), m]
        return [(slice(a, b), int(span[a])) for a, b in zip(bounds[:-1], bounds[1:])]
    order = np.argsort(span, kind="stable")
    ss = span[order]
    cuts = [0, *(np.flatnonzero(ss[1:] != ss[:-1]) + 1).tolist(), m]
    return [(order[a:b], int(ss[a])) for a, b in zip(cuts[:-1], cuts[1:])]


def band_product(
    D: NDArray[np.float64], span: NDArray[np.intp], degree: int, M: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Product of a banded collocation matrix with a matrix of poles, without forming it.

    ``R[a, i, :] = sum_t D[a, i, t] M[span[a] - degree + t, :]``: the ``degree + 1`` non-zeros
    of each row of :func:`basis_matrix` times ``M``, as one small matrix product per group of
    parameters sharing a span (:func:`span_groups`). It equals ``basis_matrix(...)[i] @ M`` at
    ``(degree + 1) / n`` of the dense cost.

    Parameters
    ----------
    D : ndarray, shape (m, r, degree + 1)
        Basis functions (or derivatives) from :func:`basis_derivatives`, C-contiguous.
    span : ndarray of intp, shape (m,)
    M : ndarray, shape (n, Y), C-contiguous

    Returns
    -------
    ndarray, shape (m, r, Y)
    """
    m, r, p1 = D.shape
    Y = M.shape[1]
    R = np.empty((m, r, Y))
    for sel, s in span_groups(span):
        rows = M[s - degree : s + 1]
        if isinstance(sel, slice):
            g = sel.stop - sel.start
            np.matmul(D[sel].reshape(g * r, p1), rows, out=R[sel].reshape(g * r, Y))
        else:
            R[sel] = (D[sel].reshape(-1, p1) @ rows).reshape(-1, r, Y)
    return R


def greville(knots: ArrayLike, degree: int) -> NDArray[np.float64]:
    """Greville abscissae ``(t_{i+1} + ... + t_{i+p}) / p``, one per control point.

    Returns
    -------
    ndarray, shape (len(knots) - degree - 1,)
    """
    t = np.asarray(knots, dtype=float)
    n = t.shape[0] - degree - 1
    c = np.concatenate(([0.0], np.cumsum(t)))
    return (c[degree + 1 : degree + 1 + n] - c[1 : 1 + n]) / degree


@functools.lru_cache(maxsize=16)
def gauss_legendre(m: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Gauss-Legendre nodes and weights of order ``m`` on ``[-1, 1]`` (``numpy``'s), made once per
    order and shared read-only: the Gram matrices of the fill patches and of the plate ask for them
    on every knot vector."""
    x, w = np.polynomial.legendre.leggauss(m)
    x.flags.writeable = False
    w.flags.writeable = False
    return x, w


def gram_bands(knots: ArrayLike, degree: int, top: int = 2) -> NDArray[np.float64]:
    """The Gram matrices ``G_k[i, j] = int N_i^(k)(t) N_j^(k)(t) dt`` of a B-spline basis, k = 0 ..
    ``top``, in band form: ``out[k, i, d] = G_k[i, i + d - degree]`` (0 where that index leaves the
    basis; ``|i - j| <= degree`` holds every non-zero). :func:`gram_band_index` places the entries.

    Exact for the piecewise polynomials: ``degree + 1`` Gauss-Legendre points per knot span of the
    domain ``[t_p, t_n]``. These are the fills' energies (course §8-3: the thin-plate energy of the
    central split's fairing and of the plate, the curvature variation of the G2 plate, sums of
    Kronecker products of these). The basis and its derivatives are evaluated once at all points
    (:func:`basis_derivatives`); each entry is summed straight into its band place by
    ``np.bincount``, which adds in input order: the terms ``(w_q N_i^(k)(t_q)) N_j^(k)(t_q)`` over
    the points ``t_q`` in increasing order, i.e. what the sparse product ``B^T diag(w) B`` of the
    collocation matrices sums, bit for bit, without forming it.

    Parameters
    ----------
    knots : array_like, shape (n + degree + 1,)
        Non-decreasing; the integral runs over the domain ``[knots[degree], knots[n]]``.
    degree : int
        The degree ``p`` of the basis.
    top : int
        Highest derivative order (a matrix of order above ``degree`` is zero).

    Returns
    -------
    ndarray, shape (top + 1, n, 2 degree + 1)
        ``out[k]``: the band of ``G_k``, row ``i`` holding ``G_k[i, i - degree .. i + degree]``.
    """
    knots = np.asarray(knots, dtype=float)
    n = knots.size - degree - 1
    brk = np.unique(knots[degree:n + 1])
    x, w = gauss_legendre(degree + 1)
    a, b = brk[:-1, None], brk[1:, None]
    t = (0.5 * (a + b) + 0.5 * (b - a) * x).ravel()
    wt = (0.5 * (b - a) * w).ravel()
    span = find_span(knots, degree, n, t)
    D = basis_derivatives(knots, degree, span, t, top)  # (m, top+1, degree+1): the non-zero values
    cols = span[:, None] - degree + np.arange(degree + 1)
    h = 2 * degree + 1
    slot = (cols[:, :, None] * h + (cols[:, None, :] - cols[:, :, None] + degree)).ravel()  # point-major
    out = np.empty((top + 1, n, h))
    for k in range(top + 1):
        Dk = D[:, k]
        out[k] = np.bincount(slot, weights=((wt[:, None] * Dk)[:, :, None] * Dk[:, None, :]).ravel(),
                             minlength=n * h).reshape(n, h)
    return out


def gram_band_index(n: int, degree: int) -> tuple[NDArray[np.intp], NDArray[np.intp], NDArray[np.bool_]]:
    """Where the entries of :func:`gram_bands`' bands (raveled, shape ``(n (2 degree + 1),)``) stand
    in the ``n x n`` matrix: ``(row, col, inside)``, ``inside`` false for the band places that leave
    the matrix (the first and last ``degree`` rows' overhang)."""
    row = np.repeat(np.arange(n), 2 * degree + 1)
    col = row + np.tile(np.arange(-degree, degree + 1), n)
    return row, col, (col >= 0) & (col < n)
