"""Helpers shared by the fitting modules: sparse collocation, difference penalties, data checks,
and point projection onto a surface (the measured distance of a fit, parameter correction).

Course ch. 7 (§7-4 Kronecker products, §7-5 least squares); the penalty is the P-spline
difference penalty of P. Eilers and B. Marx, "Flexible smoothing with B-splines and penalties",
Statistical Science 11 (1996) 89-121.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from .. import _numba_kernels as _nk
from .. import _validate as V
from .. import tolerances
from ..errors import InvalidGeometryError
from ..kernel.basis import basis_derivatives, find_span
from ..kernel.surface import BSplineSurface

if TYPE_CHECKING:
    from ..hierarchical.surface import HierarchicalSurface

__all__ = ["sparse_collocation", "difference_penalty", "sparse_difference_penalty", "check_fit_size", "project_points",
           "clamped_uniform_knots"]

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


def sparse_difference_penalty(n: int, order: int = 2) -> sp.csr_matrix:
    """:func:`difference_penalty` as a sparse matrix, built without the dense ``(n, n)`` identity
    (``2 order + 1`` diagonals; the same integer entries).

    Returns
    -------
    scipy.sparse.csr_matrix, shape (n, n)
    """
    D = sp.identity(n, format="csr")
    for _ in range(min(order, n - 1)):
        D = D[1:] - D[:-1]
    return (D.T @ D).tocsr()


def check_fit_size(n_poles: tuple[int, int], degree: tuple[int, int], name: str) -> None:
    """Refuse, before any work, a penalised scattered fit whose sparse normal equations and LU
    factors would exceed ``tolerances.MAX_ARRAY_BYTES``.

    SuperLU's factors of the ``(n_u n_v)``-square system held about ``(p + q + 2) / 2 * min(n_u, n_v)``
    entries per unknown in a measurement (cubic, 20 000 points: 131, 203, 336 and 476 per unknown at
    20, 40, 80 and 120 poles a side), 12 bytes each (value and index); the system itself adds
    ``(2p + 1)(2q + 1)`` per unknown.
    """
    (nu, nv), (p, q) = n_poles, degree
    per_unknown = (p + q + 2) // 2 * min(nu, nv) + (2 * p + 1) * (2 * q + 1)
    V.check_size((nu * nv, per_unknown), f"{name} = ({nu}, {nv}): the penalised normal equations and their LU "
                 "factors", itemsize=12)


def clamped_uniform_knots(lo: float, hi: float, n: int, degree: int) -> Array:
    """Clamped knots with ``n - degree`` equal spans on ``[lo, hi]``, shape ``(n + degree + 1,)``."""
    inner = np.linspace(lo, hi, n - degree + 1)[1:-1]
    return np.concatenate((np.full(degree + 1, lo), inner, np.full(degree + 1, hi)))


def project_points(surface: BSplineSurface | HierarchicalSurface, points: Array, u: Array, v: Array, *, max_iter: int | None = None,
                   initial: Array | None = None) -> tuple[Array, Array, Array]:
    """Foot points of ``points`` on ``surface`` by damped Newton from ``(u, v)`` (vectorised).

    Minimises ``f(u, v) = |S(u, v) - X|^2 / 2`` with the exact Hessian
    ``[[S_u.S_u + r.S_uu, S_u.S_v + r.S_uv], [., S_v.S_v + r.S_vv]]`` (``r = S - X``), falling back
    to the Gauss-Newton matrix where that is not positive definite; each step is halved until
    ``f`` does not increase (a distance never gets worse than at the start), and parameters stay
    in the domain (a foot point on the boundary is a boundary minimum). A point stops when its
    proposed Newton step, or the move made, is below
    :data:`~occsurf.algorithms.tolerances.FIT_PROJECTION_STEP` times the domain size. Each iteration
    works on the points still moving only (compacted arrays), and tries the full step with the
    partials there, which are the next iteration's when it is accepted (one evaluation per
    iteration; halving, rare near a fit, costs point evaluations).

    Parameters
    ----------
    surface : BSplineSurface or HierarchicalSurface
        Anything with ``domain``, ``evaluate`` and ``derivatives(u, v, order=2)``.
    points : ndarray, shape (k, 3)
    u, v : ndarray, shape (k,)
        Starting parameters (e.g. the data parameters of a fit).
    max_iter : int, optional
        Default :data:`~occsurf.algorithms.tolerances.FIT_PROJECTION_MAX_ITER`.
    initial : ndarray, shape (k, 3, 3, 3), optional
        ``surface.derivatives(u, v, 2)`` when the caller has them cheaper (e.g. on a grid, by
        :meth:`derivatives_grid`); ``u, v`` must then lie in the domain.

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
    with _nk.batch(X.shape[0]):  # the later iterations, on fewer points, keep the kernels
        return _project(surface, X, u, v, max_iter, initial)


def _project(surface: BSplineSurface | HierarchicalSurface, X: Array, u: Array, v: Array, max_iter: int | None,
             initial: Array | None) -> tuple[Array, Array, Array]:
    """:func:`project_points` on checked points."""
    (u0, u1), (v0, v1) = surface.domain
    size = max(u1 - u0, v1 - v0)
    it = int(tolerances.FIT_PROJECTION_MAX_ITER) if max_iter is None else int(max_iter)
    a = np.clip(np.asarray(u, float), u0, u1)
    b = np.clip(np.asarray(v, float), v0, v1)
    Da = surface.derivatives(a, b, 2) if initial is None else initial
    stop = tolerances.FIT_PROJECTION_STEP * size
    if isinstance(surface, BSplineSurface) and surface.dim == 3 and _nk.applies(a.size):
        # the same iteration per point, fused (no temporaries per step, no re-gathering of the
        # points still moving): the same results to round-off
        out = np.empty((a.size, 3))
        if _nk.run("surface_project", *surface._kernel_args(), surface.is_rational, X, a, b, np.asarray(Da, float),
                   np.array([u0, u1, v0, v1]), it, float(stop), out):
            return out[:, 0].copy(), out[:, 1].copy(), np.sqrt(np.maximum(out[:, 2], 0.0))
    r = Da[:, 0, 0] - X
    f = np.einsum("ij,ij->i", r, r)
    act = np.arange(a.size)
    Xa, fa = X, f.copy()
    for _ in range(it):
        if act.size == 0:
            break
        du, dv = _newton_step(Da, Xa)
        aa, bb = a[act], b[act]
        # a proposed step below the threshold: converged where it stands (the step would change
        # the distance by O(step^2)), no evaluation
        go = np.flatnonzero(np.maximum(np.abs(du), np.abs(dv)) > stop)
        act, Xa, fa, aa, bb, du, dv = act[go], Xa[go], fa[go], aa[go], bb[go], du[go], dv[go]
        if act.size == 0:
            break
        # the full step first, with the partials there (the next iteration's, when accepted)
        ta, tb = np.clip(aa + du, u0, u1), np.clip(bb + dv, v0, v1)
        Dt = surface.derivatives(ta, tb, 2)
        e = Dt[:, 0, 0] - Xa
        ft = np.einsum("ij,ij->i", e, e)
        acc = ft <= fa
        full = acc.copy()
        na, nb = np.where(acc, ta, aa), np.where(acc, tb, bb)
        fa = np.where(acc, ft, fa)
        todo = np.flatnonzero(~acc)
        step = np.full(todo.size, 0.5)
        for _half in range(7):  # halve until f does not increase
            if todo.size == 0:
                break
            ta = np.clip(aa[todo] + step * du[todo], u0, u1)
            tb = np.clip(bb[todo] + step * dv[todo], v0, v1)
            e = surface.evaluate(ta, tb) - Xa[todo]
            ft = np.einsum("ij,ij->i", e, e)
            ok = ft <= fa[todo]
            idx = todo[ok]
            na[idx], nb[idx], fa[idx], acc[idx] = ta[ok], tb[ok], ft[ok], True
            todo, step = todo[~ok], step[~ok] * 0.5
        moved = np.maximum(np.abs(na - aa), np.abs(nb - bb))
        a[act], b[act], f[act] = na, nb, fa
        keep = acc & (moved > stop)
        act, Xa, fa = act[keep], Xa[keep], fa[keep]
        if act.size:  # the partials at the new parameters: computed already where the full step was taken
            Da = Dt[keep]
            halved = np.flatnonzero(~full[keep])
            if halved.size:
                Da[halved] = surface.derivatives(a[act[halved]], b[act[halved]], 2)
    return a, b, np.sqrt(np.maximum(f, 0.0))


def _newton_step(D: Array, X: Array) -> tuple[Array, Array]:
    """The (damped-later) Newton step of ``|S - X|^2 / 2`` from partials ``D`` (k, 3, 3, 3)."""
    r = D[:, 0, 0] - X
    Su, Sv = D[:, 1, 0], D[:, 0, 1]
    g1, g2 = np.einsum("ij,ij->i", r, Su), np.einsum("ij,ij->i", r, Sv)
    h11 = np.einsum("ij,ij->i", Su, Su)
    h12 = np.einsum("ij,ij->i", Su, Sv)
    h22 = np.einsum("ij,ij->i", Sv, Sv)
    e11 = h11 + np.einsum("ij,ij->i", r, D[:, 2, 0])
    e12 = h12 + np.einsum("ij,ij->i", r, D[:, 1, 1])
    e22 = h22 + np.einsum("ij,ij->i", r, D[:, 0, 2])
    pd = (e11 > 0) & (e11 * e22 - e12 * e12 > 0)
    h11, h12, h22 = np.where(pd, e11, h11), np.where(pd, e12, h12), np.where(pd, e22, h22)
    det = h11 * h22 - h12 * h12
    det = np.where(np.abs(det) > 1e-300, det, 1e-300)
    return -(h22 * g1 - h12 * g2) / det, -(h11 * g2 - h12 * g1) / det
