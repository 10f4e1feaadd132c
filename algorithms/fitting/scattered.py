"""Least-squares fitting of scattered points (course ch. 7): sparse normal equations with a
smoothing penalty, and parameter correction by point projection.

A cloud of points ``X_k`` with parameters ``(u_k, v_k)`` is fitted by a tensor-product spline of
given poles: each point contributes one row with ``(p+1)(q+1)`` non-zeros to the sparse
collocation matrix ``A``, so ``A^T A`` (``N_u N_v`` square, banded in blocks) and ``A^T X`` are
formed directly and the system

.. math::

    (A^T A + λ c\\, (D_u^T D_u ⊗ I + I ⊗ D_v^T D_v))\\, P = A^T X

is solved by sparse LU. The difference penalty (Eilers–Marx P-splines, scaled by
``c = trace(A^T A) / trace(penalty)``) keeps poles over holes in the data defined: they follow
the smoothest continuation (second differences minimised), so empty cells never make the system
singular. Parameters come from the caller, from projection onto a base surface (a scan over a CAD
face), or from the best-fit plane of the points (principal axes); each parameter correction then
projects the points onto the fitted surface (:func:`~._common.project_points`) and fits again
(Hoschek's intrinsic parametrisation, "Intrinsic parametrization for approximation", CAGD 5
(1988) 27-31).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from numpy.typing import ArrayLike, NDArray

from .. import _validate as V
from .. import tolerances
from ..errors import InvalidGeometryError, ParameterError
from ..kernel.basis import basis_functions, find_span
from ..kernel.surface import BSplineSurface
from ._common import check_fit_size, clamped_uniform_knots, project_points, sparse_difference_penalty
from .gridded import _pair_of

__all__ = ["ScatteredFit", "fit_scattered", "scattered_collocation", "plane_parameters", "base_parameters"]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class ScatteredFit:
    """Result of :func:`fit_scattered`.

    Attributes
    ----------
    surface : BSplineSurface
    u, v : ndarray, shape (k,)
        Final parameters of the points (after the corrections: their foot points).
    distance : ndarray, shape (k,)
        Distance of each point to the surface, measured by projection (``measure=False``: the
        deviation at the point's parameters, an upper bound).
    max_error, rms_error : float
    smoothing : float
    corrections : int
        Parameter-correction steps made.
    """

    surface: BSplineSurface
    u: Array
    v: Array
    distance: Array
    max_error: float
    rms_error: float
    smoothing: float
    corrections: int


def _local(knots: tuple[Array, Array], degree: tuple[int, int], n_poles: tuple[int, int], u: Array, v: Array
           ) -> tuple[Array, NDArray[np.intp], NDArray[np.intp]]:
    """Per point its ``(p+1)(q+1)`` non-zero basis products, their pole columns and its cell id."""
    (tu, tv), (p, q), (nu, nv) = knots, degree, n_poles
    su, sv = find_span(tu, p, nu, u), find_span(tv, q, nv, v)
    Bu, Bv = basis_functions(tu, p, su, u), basis_functions(tv, q, sv, v)  # (k, p+1), (k, q+1)
    vals = (Bu[:, :, None] * Bv[:, None, :]).reshape(u.size, -1)
    cols = ((su[:, None] - p + np.arange(p + 1))[:, :, None] * nv
            + (sv[:, None] - q + np.arange(q + 1))[:, None, :]).reshape(u.size, -1)
    return vals, cols, su * nv + sv


def scattered_collocation(knots: tuple[Array, Array], degree: tuple[int, int], n_poles: tuple[int, int],
                          u: Array, v: Array) -> sp.csr_matrix:
    """The sparse collocation matrix ``A[k, i N_v + j] = N_i(u_k) M_j(v_k)``, shape (k, N_u N_v),
    ``(p+1)(q+1)`` entries per row."""
    vals, cols, _ = _local(knots, degree, n_poles, u, v)
    k = vals.shape[1]
    return sp.csr_matrix((vals.ravel(), cols.ravel(), np.arange(0, u.size * k + 1, k)),
                         shape=(u.size, n_poles[0] * n_poles[1]))


def _normal_equations(knots: tuple[Array, Array], degree: tuple[int, int], n_poles: tuple[int, int], u: Array,
                      v: Array, X: Array) -> tuple[sp.csr_matrix, Array]:
    """``A^T A`` (sparse) and ``A^T X`` without forming ``A``: the points are grouped by knot cell
    (all points of a cell share their pole columns), each cell's local Gram matrix ``W_c^T W_c``
    is one small BLAS product, and the blocks are summed into the global matrix."""
    vals, cols, cell = _local(knots, degree, n_poles, u, v)
    order = np.argsort(cell, kind="stable")
    cs = cell[order]
    starts = np.flatnonzero(np.r_[True, cs[1:] != cs[:-1]])
    ends = np.r_[starts[1:], cs.size]
    W, C, Xs = vals[order], cols[order], X[order]
    k = vals.shape[1]
    blocks = np.empty((starts.size, k, k))
    rhs_blocks = np.empty((starts.size, k, X.shape[1]))
    for c, (a, b) in enumerate(zip(starts, ends)):  # one product per knot cell, not per point
        blocks[c] = W[a:b].T @ W[a:b]
        rhs_blocks[c] = W[a:b].T @ Xs[a:b]
    cc = C[starts]  # (cells, k)
    n = n_poles[0] * n_poles[1]
    rows = np.repeat(cc, k, axis=1).ravel()
    colsg = np.tile(cc, (1, k)).ravel()
    G = sp.coo_matrix((blocks.ravel(), (rows, colsg)), shape=(n, n)).tocsr()
    rhs = np.zeros((n, X.shape[1]))
    np.add.at(rhs, cc.ravel(), rhs_blocks.reshape(-1, X.shape[1]))
    return G, rhs


def plane_parameters(points: Array) -> tuple[Array, Array]:
    """Parameters on the best-fit plane of ``points`` (its two principal axes), scaled to [0, 1]^2."""
    c = points.mean(axis=0)
    _, _, Vt = np.linalg.svd(points - c, full_matrices=False)
    st = (points - c) @ Vt[:2].T
    lo, hi = st.min(axis=0), st.max(axis=0)
    span = np.where(hi > lo, hi - lo, 1.0)
    st = (st - lo) / span
    return st[:, 0], st[:, 1]


def base_parameters(base: BSplineSurface, points: Array, samples: int = 64) -> tuple[Array, Array]:
    """Foot-point parameters of ``points`` on ``base`` (nearest of a ``samples``^2 grid, then
    projection): how a scan over a CAD face is parametrised."""
    from scipy.spatial import cKDTree

    (u0, u1), (v0, v1) = base.domain
    us, vs = np.linspace(u0, u1, samples), np.linspace(v0, v1, samples)
    G = base.evaluate_grid(us, vs).reshape(-1, base.dim)
    _, idx = cKDTree(G).query(points)
    u, v, _ = project_points(base, points, us[idx // samples], vs[idx % samples])
    return u, v


def _solve(AtA: sp.csr_matrix, AtX: Array, n_poles: tuple[int, int], lam: float) -> Array:
    nu, nv = n_poles
    pen = sp.kron(sparse_difference_penalty(nu), sp.identity(nv)) + \
        sp.kron(sp.identity(nu), sparse_difference_penalty(nv))
    c = AtA.diagonal().sum() / max(pen.diagonal().sum(), 1e-300)
    N = (AtA + (lam * c) * pen).tocsc()
    try:
        P = spla.splu(N).solve(AtX)
    except RuntimeError as err:
        raise InvalidGeometryError("points: the poles are not determined by the data (empty knot spans) and no "
                                   f"smoothing keeps them defined; give smoothing > 0 ({err})") from err
    if not np.all(np.isfinite(P)):
        raise InvalidGeometryError("points: the fit is singular (empty knot spans); give smoothing > 0")
    return P.reshape(nu, nv, AtX.shape[1])


def fit_scattered(points: ArrayLike, n_poles: int | tuple[int, int], degree: int | tuple[int, int] = 3, *,
                  params: ArrayLike | None = None, base: BSplineSurface | None = None,
                  knots: tuple[ArrayLike, ArrayLike] | None = None, smoothing: float | None = None,
                  corrections: int = 0, measure: bool = True) -> ScatteredFit:
    """Least-squares surface through a point cloud, with smoothing and parameter correction.

    Parameters
    ----------
    points : array_like, shape (k, 3)
    n_poles : int or (int, int)
    degree : int or (int, int)
    params : array_like, shape (k, 2), optional
        ``(u, v)`` of each point. Default: foot points on ``base`` if given, else coordinates on
        the points' best-fit plane scaled to [0, 1]^2.
    base : BSplineSurface, optional
        A surface the points lie near (a scan over a CAD face).
    knots : (array_like, array_like), optional
        Full knot vectors; default clamped, uniform over the parameters' bounding box.
    smoothing : float, optional
        λ of the difference penalty (see the module notes), ``>= 0``; default
        :data:`~occsurf.algorithms.tolerances.FIT_SCATTERED_SMOOTHING` (tiny: it only keeps poles
        over holes defined). ``0`` is plain least squares (every pole must then see data).
    corrections : int
        Parameter-correction steps (project, refit).
    measure : bool
        Measure the distances by projection (default); ``False`` reports the deviation at the
        parameters instead (an upper bound; skips one projection of every point).

    Returns
    -------
    ScatteredFit
    """
    X = V.as_finite_array(points, "points")
    if X.ndim != 2 or X.shape[1] != 3:
        raise InvalidGeometryError(f"points: expected shape (k, 3), got {X.shape}")
    p, q = (V.as_degree(k) for k in _pair_of(degree, "degree"))
    nu, nv = _pair_of(n_poles, "n_poles")
    if nu < p + 1 or nv < q + 1:
        raise InvalidGeometryError(f"n_poles: expected at least ({p + 1}, {q + 1}) for degree ({p}, {q}), got ({nu}, {nv})")
    check_fit_size((nu, nv), (p, q), "n_poles")
    if X.shape[0] < (p + 1) * (q + 1):
        raise InvalidGeometryError(f"points: a degree ({p}, {q}) fit needs at least {(p + 1) * (q + 1)} points, got {X.shape[0]}")
    lam = float(tolerances.FIT_SCATTERED_SMOOTHING) if smoothing is None else float(smoothing)
    if not (np.isfinite(lam) and lam >= 0):
        raise ParameterError(f"smoothing: expected a number >= 0, got {smoothing!r}")
    steps = int(corrections)
    if steps < 0:
        raise ParameterError(f"corrections: expected an integer >= 0, got {corrections!r}")
    if params is not None:
        uv = V.as_finite_array(params, "params")
        if uv.shape != (X.shape[0], 2):
            raise InvalidGeometryError(f"params: expected shape ({X.shape[0]}, 2), got {uv.shape}")
        u, v = uv[:, 0].copy(), uv[:, 1].copy()
    elif base is not None:
        if not isinstance(base, BSplineSurface) or base.dim != 3:
            raise InvalidGeometryError(f"base: expected a 3-D BSplineSurface, got {type(base).__name__}")
        u, v = base_parameters(base, X)
    else:
        u, v = plane_parameters(X)
    if knots is None:
        if not (u.max() > u.min() and v.max() > v.min()):
            raise InvalidGeometryError("params: the points' parameters span no area (collinear or coincident points)")
        tu = clamped_uniform_knots(float(u.min()), float(u.max()), nu, p)
        tv = clamped_uniform_knots(float(v.min()), float(v.max()), nv, q)
    else:
        tu = V.check_knots(knots[0], p, nu, "knots[0]")
        tv = V.check_knots(knots[1], q, nv, "knots[1]")
    u, v = np.clip(u, tu[p], tu[nu]), np.clip(v, tv[q], tv[nv])
    G, rhs = _normal_equations((tu, tv), (p, q), (nu, nv), u, v, X)
    surf = BSplineSurface((p, q), (tu, tv), _solve(G, rhs, (nu, nv), lam))
    for _step in range(steps):  # parameter correction: project, fit again
        u, v, _ = project_points(surf, X, u, v)
        G, rhs = _normal_equations((tu, tv), (p, q), (nu, nv), u, v, X)
        surf = BSplineSurface((p, q), (tu, tv), _solve(G, rhs, (nu, nv), lam))
    if measure:
        u2, v2, dist = project_points(surf, X, u, v)
    else:
        u2, v2, dist = u, v, np.linalg.norm(surf.evaluate(u, v) - X, axis=-1)
    return ScatteredFit(surf, u2, v2, dist, float(dist.max()), float(np.sqrt(np.mean(dist ** 2))), lam, steps)
