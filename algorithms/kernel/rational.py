"""Homogeneous coordinates and the quotient rule for rational derivatives (course §12).

A rational spline is a polynomial spline in homogeneous space, ``C^w = (w x, w)``, projected by
division. Kernels evaluate ``C^w`` and its derivatives, then recover the Cartesian derivatives by
the Leibniz rule on ``A = w C``:

.. math::

    C^{(k)} = \\frac{1}{w}\\Big(A^{(k)} - \\sum_{i=1}^{k} \\binom{k}{i} w^{(i)} C^{(k-i)}\\Big)

(The NURBS Book, 2nd ed., A4.2 for curves, A4.4 for surfaces.)
"""

from __future__ import annotations

from math import comb

import numpy as np
from numpy.typing import NDArray

__all__ = ["to_homogeneous", "from_homogeneous", "pole_deviation", "curve_quotient_rule", "surface_quotient_rule"]

Array = NDArray[np.float64]


def to_homogeneous(points: Array, weights: Array) -> Array:
    """``(..., d)`` points and ``(...)`` weights to ``(..., d + 1)`` as ``(w x, w)``."""
    return np.concatenate((points * weights[..., None], weights[..., None]), axis=-1)


def from_homogeneous(hpoints: Array) -> tuple[Array, Array]:
    """Inverse of :func:`to_homogeneous`: ``(points, weights)``."""
    w = hpoints[..., -1]
    return hpoints[..., :-1] / w[..., None], w


def pole_deviation(a: Array, b: Array, rational: bool) -> float:
    """Largest Cartesian distance between corresponding poles ``a`` and ``b`` (any leading shape).

    For homogeneous poles (``rational``) the weights must agree too: their relative difference,
    scaled by the poles' size, also counts, so that a small result bounds the movement of the
    rational spline as well.
    """
    if not rational:
        return float(np.max(np.linalg.norm(a - b, axis=-1)))
    pa, wa = from_homogeneous(a)
    pb, wb = from_homogeneous(b)
    dp = float(np.max(np.linalg.norm(pa - pb, axis=-1)))
    dw = float(np.max(np.abs(wa - wb) / wb))
    return max(dp, dw * max(float(np.max(np.abs(pb))), 1.0))


def curve_quotient_rule(hders: Array) -> Array:
    """Cartesian derivatives from homogeneous ones (A4.2).

    Parameters
    ----------
    hders : ndarray, shape (m, r + 1, d + 1)

    Returns
    -------
    ndarray, shape (m, r + 1, d)
    """
    A = hders[..., :-1]
    w = hders[..., -1]
    r = hders.shape[1] - 1
    out = np.empty_like(A)
    inv_w = 1.0 / w[:, 0, None]
    for k in range(r + 1):
        v = A[:, k].copy()
        for i in range(1, k + 1):
            v -= comb(k, i) * w[:, i, None] * out[:, k - i]
        out[:, k] = v * inv_w
    return out


def surface_quotient_rule(hders: Array) -> Array:
    """Cartesian partials from homogeneous ones (A4.4).

    Parameters
    ----------
    hders : ndarray, shape (..., r + 1, r + 1, d + 1)
        ``[k, l]`` is ``d^{k+l} / du^k dv^l``.

    Returns
    -------
    ndarray, shape (..., r + 1, r + 1, d)
    """
    A = hders[..., :-1]
    w = hders[..., -1]
    r = hders.shape[-2] - 1
    out = np.empty_like(A)
    inv_w = 1.0 / w[..., 0, 0, None]
    for k in range(r + 1):
        for l in range(r + 1):
            v = A[..., k, l, :].copy()
            for j in range(1, l + 1):
                v -= comb(l, j) * w[..., 0, j, None] * out[..., k, l - j, :]
            for i in range(1, k + 1):
                v -= comb(k, i) * w[..., i, 0, None] * out[..., k - i, l, :]
                for j in range(1, l + 1):
                    v -= comb(k, i) * comb(l, j) * w[..., i, j, None] * out[..., k - i, l - j, :]
            out[..., k, l, :] = v * inv_w
    return out
