"""Helpers shared by the fitting modules: sparse collocation, difference penalties, data checks,
and point projection onto a surface (the measured distance of a fit, parameter correction).

Course ch. 7 (§7-4 Kronecker products, §7-5 least squares); the penalty is the P-spline
difference penalty of P. Eilers and B. Marx, "Flexible smoothing with B-splines and penalties",
Statistical Science 11 (1996) 89-121.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from .. import tolerances
from ..errors import InvalidGeometryError
from ..kernel.basis import basis_derivatives, find_span

__all__ = ["sparse_collocation", "difference_penalty", "project_points", "clamped_uniform_knots"]

Array = NDArray[np.float64]


def sparse_collocation(knots: Array, degree: int, n: int, params: Array, order: int = 0) -> sp.csr_matrix:
    """``B[i, j] = d^order N_j(params[i]) / du^order`` as a CSR matrix with ``degree + 1`` entries per row.

    Returns
    -------
    scipy.sparse.csr_matrix, shape (len(params), n)
    """
    m = params.shape[0]
    span = find_span(knots, degree, n, params)
    D = basis_derivatives(knots, degree, span, params, order)[:, order, :]  # (m, p+1)
    cols = span[:, None] - degree + np.arange(degree + 1)
    indptr = np.arange(0, m * (degree + 1) + 1, degree + 1)
    return sp.csr_matrix((D.ravel(), cols.ravel(), indptr), shape=(m, n))


def difference_penalty(n: int, order: int = 2) -> Array:
    """``D^T D`` for the ``order``-th difference matrix ``D`` of ``n`` poles (Eilers–Marx), ``(n, n)``.

    Its null space holds the polynomial pole sequences of degree < ``order`` (for ``order = 2``:
    constant and linear ones), which a smoothing term therefore never changes.
    """
    k = min(order, n - 1)
    D = np.diff(np.eye(n), n=k, axis=0)
    return D.T @ D


def clamped_uniform_knots(lo: float, hi: float, n: int, degree: int) -> Array:
    """Clamped knots with ``n - degree`` equal spans on ``[lo, hi]``, shape ``(n + degree + 1,)``."""
    inner = np.linspace(lo, hi, n - degree + 1)[1:-1]
    return np.concatenate((np.full(degree + 1, lo), inner, np.full(degree + 1, hi)))


def project_points(surface: Any, points: Array, u: Array, v: Array, *, max_iter: int | None = None
                   ) -> tuple[Array, Array, Array]:
    """Foot points of ``points`` on ``surface`` by damped Newton from ``(u, v)`` (vectorised).

    Minimises ``f(u, v) = |S(u, v) - X|^2 / 2`` with the exact Hessian
    ``[[S_u.S_u + r.S_uu, S_u.S_v + r.S_uv], [., S_v.S_v + r.S_vv]]`` (``r = S - X``), falling back
    to the Gauss-Newton matrix where that is not positive definite; each step is halved until
    ``f`` does not increase (a distance never gets worse than at the start), and parameters stay
    in the domain (a foot point on the boundary is a boundary minimum). Stops when every step is
    below :data:`~occsurf.algorithms.tolerances.FIT_PROJECTION_STEP` times the domain size.

    Parameters
    ----------
    surface : BSplineSurface or HierarchicalSurface
        Anything with ``domain``, ``evaluate`` and ``derivatives(u, v, order=2)``.
    points : ndarray, shape (k, 3)
    u, v : ndarray, shape (k,)
        Starting parameters (e.g. the data parameters of a fit).
    max_iter : int, optional
        Default :data:`~occsurf.algorithms.tolerances.FIT_PROJECTION_MAX_ITER`.

    Returns
    -------
    u, v : ndarray, shape (k,)
        The foot points' parameters.
    distance : ndarray, shape (k,)
        ``|S(u, v) - X|`` there: the measured distance from each point to the surface (a local
        minimum near the start, which for a fit is the nearest point).
    """
    X = np.asarray(points, float)
    if X.ndim != 2 or X.shape[1] != 3:
        raise InvalidGeometryError(f"points: expected shape (k, 3), got {X.shape}")
    (u0, u1), (v0, v1) = surface.domain
    size = max(u1 - u0, v1 - v0)
    it = int(tolerances.FIT_PROJECTION_MAX_ITER) if max_iter is None else int(max_iter)
    a = np.clip(np.asarray(u, float).copy(), u0, u1)
    b = np.clip(np.asarray(v, float).copy(), v0, v1)
    D = surface.derivatives(a, b, 2)
    f = np.einsum("ij,ij->i", D[:, 0, 0] - X, D[:, 0, 0] - X)
    active = np.arange(a.size)
    for _ in range(it):
        if active.size == 0:
            break
        Da = D[active]
        r = Da[:, 0, 0] - X[active]
        Su, Sv = Da[:, 1, 0], Da[:, 0, 1]
        g = np.stack([np.einsum("ij,ij->i", r, Su), np.einsum("ij,ij->i", r, Sv)], -1)
        h11 = np.einsum("ij,ij->i", Su, Su)
        h12 = np.einsum("ij,ij->i", Su, Sv)
        h22 = np.einsum("ij,ij->i", Sv, Sv)
        e11 = h11 + np.einsum("ij,ij->i", r, Da[:, 2, 0])
        e12 = h12 + np.einsum("ij,ij->i", r, Da[:, 1, 1])
        e22 = h22 + np.einsum("ij,ij->i", r, Da[:, 0, 2])
        pd = (e11 > 0) & (e11 * e22 - e12 * e12 > 0)
        h11, h12, h22 = np.where(pd, e11, h11), np.where(pd, e12, h12), np.where(pd, e22, h22)
        det = h11 * h22 - h12 * h12
        det = np.where(np.abs(det) > 1e-300, det, 1e-300)
        du = -(h22 * g[:, 0] - h12 * g[:, 1]) / det
        dv = -(h11 * g[:, 1] - h12 * g[:, 0]) / det
        step = np.ones(active.size)
        acc = np.zeros(active.size, bool)
        na, nb = a[active], b[active]
        for _half in range(8):  # halve until f does not increase
            todo = ~acc
            if not np.any(todo):
                break
            ta = np.clip(a[active] + step * du, u0, u1)
            tb = np.clip(b[active] + step * dv, v0, v1)
            P = surface.evaluate(ta[todo], tb[todo])
            ft = np.einsum("ij,ij->i", P - X[active][todo], P - X[active][todo])
            ok = ft <= f[active][todo]
            idx = np.flatnonzero(todo)[ok]
            na[idx], nb[idx] = ta[todo][ok], tb[todo][ok]
            acc[idx] = True
            f[active[idx]] = ft[ok]
            step[todo] *= 0.5
        moved = np.maximum(np.abs(na - a[active]), np.abs(nb - b[active]))
        a[active], b[active] = na, nb
        keep = acc & (moved > tolerances.FIT_PROJECTION_STEP * size)
        active = active[keep]
        if active.size:
            D[active] = surface.derivatives(a[active], b[active], 2)
    return a, b, np.sqrt(np.maximum(f, 0.0))
