"""Degree raising of B-splines through the symmetric blossom (course §2-6, §2-7).

The degree-``p+1`` blossom of a degree-``p`` polynomial is the average of the degree-``p`` blossom
over the ``p+1`` ways of dropping one argument,

.. math::

    F(x_1, \\ldots, x_{p+1}) = \\frac{1}{p+1} \\sum_{i=1}^{p+1}
        f(x_1, \\ldots, \\widehat{x_i}, \\ldots, x_{p+1}),

and the raised spline, whose knot vector repeats every distinct knot once more (continuity is
kept), has control points ``Q_j = F(tau_{j+1}, ..., tau_{j+p+1})``. All ``Q_j`` are computed in
one vectorised pass; no Bézier decomposition and recomposition, so no knot-removal round-off.

References
----------
H. Prautzsch, "Degree elevation of B-spline curves", CAGD 1 (1984); the blossoming formulation
follows Seidel (1989) and the course's §2-6.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
from numpy.typing import NDArray

from .blossom import blossom_basis
from .knots import clamp_poles, distinct_knots, support_span

__all__ = ["elevate_poles"]

Array = NDArray[np.float64]


@lru_cache(maxsize=32)
def _dropped(p: int) -> NDArray[np.intp]:
    """Row ``i``: the argument columns ``0..p`` without ``i`` (read-only, kept per degree)."""
    drop = np.array([[c for c in range(p + 1) if c != i] for i in range(p + 1)], dtype=np.intp)
    drop.flags.writeable = False
    return drop


def elevate_poles(knots: Array, degree: int, poles: Array, times: int = 1) -> tuple[Array, Array]:
    """Raise the degree by ``times``; the spline (clamped first if needed) is unchanged.

    Returns
    -------
    knots : ndarray
        Every distinct knot with its multiplicity increased by ``times``.
    poles : ndarray, shape (n2, ...)
    """
    knots, poles = clamp_poles(knots, degree, poles)
    p = degree
    for _ in range(times):
        vals, mult = distinct_knots(knots)
        tau = np.repeat(vals, mult + 1)
        n2 = tau.shape[0] - (p + 1) - 1
        j = np.arange(n2)
        args = tau[j[:, None] + 1 + np.arange(p + 1)[None, :]]  # (n2, p+1)
        mu = support_span(knots, tau, j)  # clamped: a domain span, p <= mu < len(poles)
        idx = mu[:, None] - p + np.arange(p + 1)
        gathered = poles[idx]  # (n2, p+1, ...)
        # The p + 1 blossoms with one argument dropped, in one call (row by row, so the same values
        # as one call per dropped argument): drop[i] lists the argument columns without i.
        drop = _dropped(p)
        A_all = blossom_basis(knots, p, np.tile(mu, p + 1), args[:, drop].transpose(1, 0, 2).reshape((p + 1) * n2, p))
        acc = np.zeros((n2,) + poles.shape[1:])
        for i in range(p + 1):
            acc += np.einsum("mk,mk...->m...", A_all[i * n2:(i + 1) * n2], gathered)
        poles = acc / (p + 1)
        knots = tau
        p += 1
    return knots, poles
