"""Polar forms (blossoms) of B-spline segments (course §2-2..2-3, §2-7..2-10).

The blossom ``f(x_1, ..., x_p)`` of a degree-``p`` polynomial piece is the unique symmetric,
multi-affine map whose diagonal is the piece: ``f(u, ..., u) = C(u)``. For a B-spline with knots
``t`` the control points are blossom values at consecutive knots (course §2-9),

.. math::

    P_i = f_\\mu(t_{i+1}, \\ldots, t_{i+p}) \\quad \\text{for every non-empty span } \\mu \\in [i, i+p],

which is the whole theory behind knot insertion (Oslo / Boehm), degree raising and conversion to
Bézier form. Here the blossom is computed as weights on the control points: the de Boor recurrence
run on the basis functions with a different argument at every level.

References
----------
L. Ramshaw, "Blossoms are polar forms", CAGD 6 (1989). H.-P. Seidel, "A new multiaffine approach
to B-splines", CAGD 6 (1989). Course notes C25, Bartels, §2.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = ["blossom_basis", "blossom_rows", "blossom_poles"]


def blossom_basis(
    knots: NDArray[np.float64], degree: int, span: NDArray[np.intp], args: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Weights of the ``degree + 1`` control points in the blossom of the piece on ``span``.

    Parameters
    ----------
    knots : ndarray, shape (n + degree + 1,)
    degree : int
    span : ndarray of int, shape (m,)
        Index ``mu`` of a non-empty knot span ``[t_mu, t_{mu+1})``; ``degree <= mu <= n - 1``.
    args : ndarray, shape (m, degree)
        Blossom arguments (any real values; the blossom is a polynomial in each).

    Returns
    -------
    ndarray, shape (m, degree + 1)
        ``A`` with ``f_mu(args_i) = sum_k A[i, k] P[mu_i - degree + k]``. With all arguments equal
        to ``u`` this is the basis-function vector at ``u`` (A2.2); with the arguments of a refined
        knot vector it is a row of the Oslo refinement matrix (discrete B-splines).
    """
    return blossom_rows(knots, degree, span, args).T.copy()


def blossom_rows(
    knots: NDArray[np.float64], degree: int, span: NDArray[np.intp], args: NDArray[np.float64]
) -> NDArray[np.float64]:
    """:func:`blossom_basis` transposed, shape ``(degree + 1, m)``: row ``k`` the weights of pole
    ``mu_i - degree + k`` (the layout the recurrence builds, without the transposing copy)."""
    m = span.shape[0]
    p = degree
    N = np.zeros((p + 1, m))
    N[0] = 1.0
    if p == 0:
        return N
    # The knots the recurrence reads, once: lo_all[k] = t[span - p + 1 + k], hi_all[r] = t[span + 1 + r].
    offsets = np.arange(1 - p, p + 1)
    ks = knots[span[None, :] + offsets[:, None]]
    lo_all, hi_all = ks[:p], ks[p:]
    X = args.T
    for j in range(1, p + 1):
        # The inner loop over r = 0..j-1 as whole rows (as in basis_functions): every temp comes from
        # the old N[r], and N[r] = saved + (hi - x) temp[r] with saved = (x - lo) temp[r-1] (0 for
        # r = 0), N[j] = the last saved. The right terms are written into N[:j], then the saved
        # ones added: the same sums (one addition each, commutative) and signs of zero (0 + -0 is +0
        # in row 0, and row j is the saved term itself, as in the loop).
        x = X[j - 1]
        lo = lo_all[p - j:]
        hi = hi_all[:j]
        temp = N[:j] / (hi - lo)
        lt = (x - lo) * temp
        np.multiply(hi - x, temp, out=N[:j])
        N[0] += 0.0
        N[1:j] += lt[:j - 1]
        N[j] = lt[j - 1]
    return N


def blossom_poles(
    knots: NDArray[np.float64],
    degree: int,
    poles: NDArray[np.float64],
    span: NDArray[np.intp],
    args: NDArray[np.float64],
) -> NDArray[np.float64]:
    """Blossom values ``f_mu(args)`` of a spline with the given poles (any trailing shape).

    Parameters
    ----------
    poles : ndarray, shape (n, ...)
        Control points; homogeneous ones give the homogeneous blossom.
    span, args : see :func:`blossom_basis`.

    Returns
    -------
    ndarray, shape (m, ...)
    """
    A = blossom_basis(knots, degree, span, args)
    idx = span[:, None] - degree + np.arange(degree + 1)
    return np.einsum("mk,mk...->m...", A, poles[idx])
