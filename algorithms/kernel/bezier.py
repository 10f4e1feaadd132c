"""Bernstein–Bézier segments: Bernstein basis, de Casteljau, subdivision, blossom, degree raising.

Course §2-1..2-6. Control points of a degree-``n`` segment on ``[a, b]`` are blossom values
``P_i = f(a, ..., a, b, ..., b)`` (``n - i`` copies of ``a``, ``i`` of ``b``); de Casteljau's
algorithm evaluates the blossom by repeated affine interpolation, and its intermediate points
are the control points of the two halves (subdivision).

All functions take control points of shape ``(n + 1, ...)`` and are vectorised over parameters.
"""

from __future__ import annotations

from math import comb

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["bernstein", "de_casteljau", "bezier_blossom", "subdivide", "elevate_bezier"]

Array = NDArray[np.float64]


def bernstein(degree: int, t: ArrayLike) -> Array:
    """Bernstein polynomials ``B_{i,n}(t) = C(n,i) t^i (1-t)^{n-i}`` on ``[0, 1]`` (course §2-1).

    Returns
    -------
    ndarray, shape (m, degree + 1)
    """
    t = np.atleast_1d(np.asarray(t, dtype=float))
    i = np.arange(degree + 1)
    binom = np.array([comb(degree, k) for k in range(degree + 1)], dtype=float)  # exact, then rounded once
    return binom * t[:, None] ** i * (1.0 - t[:, None]) ** (degree - i)


def de_casteljau(control_points: ArrayLike, t: ArrayLike) -> Array:
    """Evaluate a Bézier segment on ``[0, 1]`` by de Casteljau's algorithm (course §2-4).

    Parameters
    ----------
    control_points : array_like, shape (n + 1, d)
    t : array_like, shape (m,) or scalar

    Returns
    -------
    ndarray, shape (m, d) (or (d,) for scalar ``t``)
    """
    t_arr = np.asarray(t, dtype=float)
    args = np.repeat(np.atleast_1d(t_arr)[:, None], np.asarray(control_points).shape[0] - 1, axis=1)
    out = bezier_blossom(control_points, args)
    return out[0] if t_arr.ndim == 0 else out


def bezier_blossom(control_points: ArrayLike, args: ArrayLike) -> Array:
    """Blossom (polar form) of a Bézier segment on ``[0, 1]`` (course §2-3).

    ``f(x_1, ..., x_n)`` by de Casteljau with a different argument at each level.

    Parameters
    ----------
    control_points : array_like, shape (n + 1, d)
    args : array_like, shape (m, n)

    Returns
    -------
    ndarray, shape (m, d)
    """
    P = np.asarray(control_points, dtype=float)
    x = np.atleast_2d(np.asarray(args, dtype=float))
    n = P.shape[0] - 1
    if x.shape[-1] != n:
        raise ValueError(f"args: expected {n} arguments per blossom (the degree), got {x.shape[-1]}")
    m = x.shape[0]
    b = np.broadcast_to(P, (m,) + P.shape).copy()
    tail = (1,) * (P.ndim - 1)
    for r in range(n):
        xr = x[:, r].reshape((m, 1) + tail)
        b = (1.0 - xr) * b[:, :-1] + xr * b[:, 1:]
    return b[:, 0]


def subdivide(control_points: ArrayLike, t: float = 0.5) -> tuple[Array, Array]:
    """Split a Bézier segment at ``t`` into two (course §2-4, subdivision).

    Returns
    -------
    left, right : ndarray, shape (n + 1, d) each
        The left half runs over ``[0, t]``, the right over ``[t, 1]``, both re-parametrised to [0, 1].
    """
    b = np.asarray(control_points, dtype=float).copy()
    n = b.shape[0] - 1
    left = [b[0].copy()]
    right = [b[n].copy()]
    for _ in range(n):
        b = (1.0 - t) * b[:-1] + t * b[1:]
        left.append(b[0].copy())
        right.append(b[-1].copy())
    return np.array(left), np.array(right[::-1])


def elevate_bezier(control_points: ArrayLike, times: int = 1) -> Array:
    """Raise the degree of a Bézier segment (course §2-6).

    ``Q_i = (i / (n+1)) P_{i-1} + (1 - i / (n+1)) P_i`` for ``i = 0..n+1``, applied ``times`` times.

    Returns
    -------
    ndarray, shape (n + 1 + times, ...)
    """
    P = np.asarray(control_points, dtype=float)
    for _ in range(times):
        n = P.shape[0] - 1
        a = (np.arange(n + 2) / (n + 1)).reshape((-1,) + (1,) * (P.ndim - 1))
        ext_lo = np.concatenate((P[:1], P))  # P_{i-1}, with P_{-1} unused (a_0 = 0)
        ext_hi = np.concatenate((P, P[-1:]))  # P_i, with P_{n+1} unused (1 - a_{n+1} = 0)
        P = a * ext_lo + (1.0 - a) * ext_hi
    return P
