"""Adaptive hierarchical fitting of scattered data (course §7-10, carried over from grids to clouds).

The gridded process of :mod:`.adaptive` on a point cloud ``X_k`` with parameters ``(u_k, v_k)``:

1. Base: sparse least squares (:func:`~.scattered.fit_scattered`, a tiny difference penalty keeps
   poles over holes defined), its spans multiplied by 1.5 while the places to refine cover more
   than :data:`~occsurf.algorithms.tolerances.FIT_ADAPTIVE_MAX_COVER` of the domain.
2. Each round, the points farther than ``max(tol, FIT_ADAPTIVE_GREED * max_error)`` from the
   surface (distance by point projection, :func:`~._common.project_points`) are binned into the
   knot spans of the deepest node (base or overlay) whose region holds them (``np.bincount`` over
   span ids); spans holding fewer than :data:`~occsurf.algorithms.tolerances.FIT_ADAPTIVE_SPAN_POINTS`
   points are not refined (the data could not determine finer poles); each connected group of
   marked spans becomes one overlay (midpoint knot insertion, course ch. 5).
3. An overlay's world displacements ``δ`` are the least-squares fit of the residual
   ``X_k - S(u_k, v_k)`` over the points in the overlay's support, with the overlay's own
   B-splines: the sparse collocation matrix ``A`` (``(p+1)(q+1)`` entries per row, restricted to
   the overlay's vertex block) gives ``(A^T A + ρ I) δ = A^T R`` with the ridge
   ``ρ = FIT_OVERLAY_RCOND^2 max diag(A^T A)``: the counterpart of the gridded path's truncated
   pseudo-inverse (a vertex that sees the data only with the tail of its B-spline stays at zero
   instead of swinging between the points; singular values of ``A`` below ``FIT_OVERLAY_RCOND``
   times the largest are damped). The normal matrix is factorised once (SuperLU) per overlay: the
   parameters do not change, so the backfitting sweeps reuse it, as they reuse the base's.
4. :data:`~occsurf.algorithms.tolerances.FIT_ADAPTIVE_SWEEPS` block Gauss-Seidel sweeps (base,
   then every overlay, against what the others leave), then the error is measured again.

The result is an editable :class:`~occsurf.algorithms.hierarchical.HierarchicalSurface` (frame
offsets, course §5-15) whose :meth:`flatten` is one exact B-spline surface (for STEP).

References
----------
Course notes C25 (SIGGRAPH 1991) §7-10; D. R. Forsey, R. H. Bartels, "Surface fitting with
hierarchical splines", ACM TOG 14 (1995) 134-161; Hoschek, "Intrinsic parametrization for
approximation", CAGD 5 (1988) 27-31 (parameter correction of the base).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from numpy.typing import ArrayLike, NDArray

from .. import _numba_kernels as _nk
from .. import _validate as V
from .. import tolerances
from ..errors import InvalidGeometryError, ParameterError
from ..hierarchical.overlays import Overlay
from ..hierarchical.surface import HierarchicalSurface
from ..kernel.surface import BSplineSurface
from ._common import check_fit_size, project_points, sparse_difference_penalty
from ._refine import (
    FitSummary,
    LevelReport,
    OverlayFitter,
    Owners,
    Region,
    check_tol_levels,
    grow_base,
    level_reports,
    owner,
    rectangles,
    refine,
    span_index,
    support,
)
from .gridded import _pair_of
from .scattered import _local, base_parameters, fit_scattered, plane_parameters, scattered_collocation

__all__ = ["ScatteredAdaptiveFit", "fit_adaptive_scattered", "measure_points", "normal_deviation", "block_collocation"]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class ScatteredAdaptiveFit(FitSummary):
    """Result of :func:`fit_adaptive_scattered`.

    Attributes
    ----------
    hierarchy : HierarchicalSurface
        Editable; ``hierarchy.flatten()`` is the exact single B-spline surface.
    levels : tuple of LevelReport
        Per level L, the hierarchy truncated below L measured against the points.
    distance : ndarray, shape (k,)
        Measured distance of each point to the final surface (point projection).
    u, v : ndarray, shape (k,)
        The points' parameters used by the fit (given, from ``base``, or from the best-fit plane,
        then corrected on the base fit when asked).
    tol : float
    converged : bool
        ``max_error <= tol``.
    level_surfaces : tuple of BSplineSurface
        Per level, the flat surface of the truncated hierarchy.
    level_distances : tuple of ndarray, each (k,)
        Their measured distances (the per-level error picture).
    """

    hierarchy: HierarchicalSurface
    levels: tuple[LevelReport, ...]
    distance: Array
    u: Array
    v: Array
    tol: float
    converged: bool
    level_surfaces: tuple[BSplineSurface, ...] = ()
    level_distances: tuple[Array, ...] = ()


def measure_points(surface: BSplineSurface, X: Array, u: Array, v: Array, *, above: float | None = None) -> Array:
    """Distance of every point ``X[k]`` to ``surface`` by projection from ``(u_k, v_k)``
    (:func:`~._common.project_points`), shape (k,). With ``above`` only the points whose deviation
    at their parameters exceeds it are projected; the others keep that deviation, an upper bound
    of their distance (at most ``above``), so every comparison against a threshold ``>= above``
    is the same as with all points projected."""
    if above is None:
        return project_points(surface, X, u, v)[2]
    out = np.linalg.norm(surface.evaluate(u, v) - X, axis=-1)
    far = np.flatnonzero(out > above)
    if far.size:
        out[far] = project_points(surface, X[far], u[far], v[far])[2]
    return out


def normal_deviation(surface: BSplineSurface, X: Array, u: Array, v: Array) -> Array:
    """``|(X_k - S(u_k, v_k)) . N(u_k, v_k)|``, shape (k,): the first-order distance (exact for a
    plane), cheap; used to compare candidate base fits, never reported."""
    D = surface.derivatives(u, v, 1)
    N = np.cross(D[:, 1, 0], D[:, 0, 1])
    N /= np.maximum(np.linalg.norm(N, axis=-1, keepdims=True), 1e-300)
    return np.abs(np.einsum("ij,ij->i", X - D[:, 0, 0], N))


def block_collocation(knots: tuple[Array, Array], degree: tuple[int, int], vertices: tuple[tuple[int, int], ...],
                      u: Array, v: Array) -> sp.csr_matrix:
    """The collocation matrix of the B-splines of one vertex block of a level net at scattered
    parameters: ``A[k, (i - i0) n_b + (j - j0)] = N_i(u_k) M_j(v_k)`` for ``i0 <= i <= i1``,
    ``j0 <= j <= j1``; shape ``(k, (i1 - i0 + 1) (j1 - j0 + 1))``, at most ``(p+1)(q+1)`` entries per row."""
    (tu, tv), (p, q) = knots, degree
    nu, nv = tu.shape[0] - p - 1, tv.shape[0] - q - 1
    (i0, i1), (j0, j1) = vertices
    vals, cols, _ = _local((tu, tv), (p, q), (nu, nv), u, v)
    i, j = cols // nv, cols % nv
    keep = (i >= i0) & (i <= i1) & (j >= j0) & (j <= j1)
    nb = j1 - j0 + 1
    rows = np.broadcast_to(np.arange(u.size)[:, None], cols.shape)[keep]
    return sp.csr_matrix((vals[keep], (rows, (i[keep] - i0) * nb + (j[keep] - j0))),
                         shape=(u.size, (i1 - i0 + 1) * nb))


class _BaseSolver:
    """The base's penalised normal equations on fixed parameters, factorised once (SuperLU)."""

    def __init__(self, surface: BSplineSurface, u: Array, v: Array, lam: float) -> None:
        self.knots, self.deg, self.n = surface.knots, surface.degree, surface.n_poles
        self.A = scattered_collocation(self.knots, self.deg, self.n, u, v)
        G = (self.A.T @ self.A).tocsr()
        nu, nv = self.n
        pen = sp.kron(sparse_difference_penalty(nu), sp.identity(nv)) + \
            sp.kron(sp.identity(nu), sparse_difference_penalty(nv))
        c = G.diagonal().sum() / max(pen.diagonal().sum(), 1e-300)
        self.lu = spla.splu((G + (lam * c) * pen).tocsc())

    def __call__(self, target: Array) -> BSplineSurface:
        P = self.lu.solve(np.asarray(self.A.T @ target))
        return BSplineSurface(self.deg, self.knots, P.reshape(self.n + (target.shape[1],)))


class _ScatteredFitter(OverlayFitter):
    """The hierarchy under construction (:class:`~._refine.OverlayFitter`) on a cloud ``X`` (k, 3):
    per overlay its points, collocation block and factorised normal matrix."""

    def evaluate(self, surface: BSplineSurface) -> Array:
        return surface.evaluate(self.u, self.v)  # one spline: the compiled kernel

    def operators(self, ov: Overlay) -> tuple[NDArray[np.intp], sp.csr_matrix, spla.SuperLU]:
        if ov.id not in self.ops:
            su, sv = support(ov, self.hs.degree)
            idx = np.flatnonzero((self.u >= su[0]) & (self.u <= su[1]) & (self.v >= sv[0]) & (self.v <= sv[1]))
            A = block_collocation((ov.knots[0], ov.knots[1]), self.hs.degree, ov.vertices, self.u[idx], self.v[idx])
            G = (A.T @ A).tocsc()
            ridge = float(tolerances.FIT_OVERLAY_RCOND) ** 2 * max(float(G.diagonal().max(initial=0.0)), 1e-300)
            lu = spla.splu((G + ridge * sp.identity(G.shape[0], format="csc")).tocsc())
            self.ops[ov.id] = (idx, A, lu)
        return self.ops[ov.id]

    def fit_overlay(self, ov: Overlay, resid: Array) -> None:
        """Least-squares ``δ`` of ``ov`` against ``resid`` plus its own current share; updates ``resid``."""
        idx, A, lu = self.operators(ov)
        old = self.delta.get(ov.id)
        R = resid[idx]
        if old is not None:
            R = R + A @ old.reshape(-1, 3)
        delta = lu.solve(np.asarray(A.T @ R)) if idx.size else np.zeros((A.shape[1], 3))
        self.delta[ov.id] = delta.reshape(ov.shape + (3,))
        self._apply(ov)
        resid[idx] = R - A @ delta


def _owner(hs: HierarchicalSurface, u: Array, v: Array) -> Owners:
    """Per point, the deepest node whose region holds it: the nodes, a (k,) index into them
    (0 = the base) and the nodes' levels."""
    return owner(hs, u.shape, lambda r: (u >= r[0][0]) & (u <= r[0][1]) & (v >= r[1][0]) & (v <= r[1][1]))



def _regions(hs: HierarchicalSurface, parent: Overlay | None, flagged: NDArray[np.bool_], u: Array, v: Array
             ) -> list[tuple[tuple[float, float], tuple[float, float]]]:
    """Rectangles (u_range, v_range) to refine inside ``parent``: its knot spans holding a flagged
    point and at least FIT_ADAPTIVE_SPAN_POINTS points, grown by the margin, grouped and merged."""
    lvl = hs.level_surface(parent)
    (ua, ub), (va, vb) = hs.domain if parent is None else parent.region
    ku, iu = span_index(lvl.knots[0], ua, ub, u)
    kv, iv = span_index(lvl.knots[1], va, vb, v)
    inside = (iu >= 0) & (iv >= 0)
    nu, nv = ku.size - 1, kv.size - 1
    cell = iu * nv + iv
    counts = np.bincount(cell[inside], minlength=nu * nv).reshape(nu, nv)
    marks = np.zeros(nu * nv, bool)
    marks[cell[inside & flagged]] = True
    marks = marks.reshape(nu, nv) & (counts >= int(tolerances.FIT_ADAPTIVE_SPAN_POINTS))
    return rectangles(marks, ku, kv)


def _grow_base(X: Array, u: Array, v: Array, poles: tuple[int, int], deg: tuple[int, int], tol: float, lam: float,
               progress: Callable[[str], None] | None) -> tuple[BSplineSurface, Array]:
    """The base fit, its spans multiplied by 1.5 while the regions to refine cover more than
    FIT_ADAPTIVE_MAX_COVER of the domain; each step grows u, v or both, whichever lowers the
    error most per added pole (:func:`~._refine.grow_base`: candidates compared by the
    first-order :func:`normal_deviation`, the chosen base measured)."""
    cap = max(deg[0] + 1, deg[1] + 1, int(np.sqrt(X.shape[0] / 2)))

    def candidate(poles_: tuple[int, int]) -> tuple[BSplineSurface, float]:
        f = fit_scattered(X, poles_, deg, params=np.c_[u, v], smoothing=lam, measure=False)
        return f.surface, float(normal_deviation(f.surface, X, u, v).max())

    def measured(surf: BSplineSurface) -> tuple[Array, Array]:
        dist = measure_points(surf, X, u, v, above=tol)
        return dist, dist

    def regions(surf: BSplineSurface, flagged: NDArray[np.bool_]) -> tuple[HierarchicalSurface, list[Region]]:
        hs = HierarchicalSurface(surf, "frame")
        return hs, _regions(hs, None, flagged, u, v)

    return grow_base(poles, deg, (cap, cap), tol, candidate, measured, regions, progress)


def _level_reports(hs: HierarchicalSurface, X: Array, u: Array, v: Array
                   ) -> tuple[list[LevelReport], list[BSplineSurface], list[Array]]:
    """Per level L, the hierarchy truncated below L (finer offsets zeroed), measured."""
    return level_reports(hs, lambda flat: measure_points(flat, X, u, v))


def _corrected(X: Array, u: Array, v: Array, poles: tuple[int, int], deg: tuple[int, int], lam: float
               ) -> tuple[Array, Array]:
    """One parameter correction (Hoschek): fit, then each point's foot point on the fit. A foot
    point that lands on the domain's border (the point lies beyond the surface's edge) takes one
    unclamped Gauss-Newton step from there instead, so the parameters, and with them the next fit's
    knot box, grow to cover the data rather than pinning such points to the border curve."""
    surf = fit_scattered(X, poles, deg, params=np.c_[u, v], smoothing=lam, measure=False).surface
    a, b, _ = project_points(surf, X, u, v)
    (u0, u1), (v0, v1) = surf.domain
    edge = (a <= u0) | (a >= u1) | (b <= v0) | (b >= v1)
    if edge.any():
        D = surf.derivatives(a[edge], b[edge], 1)
        r = X[edge] - D[:, 0, 0]
        Su, Sv = D[:, 1, 0], D[:, 0, 1]
        g11, g12, g22 = (np.einsum("ij,ij->i", p, q) for p, q in ((Su, Su), (Su, Sv), (Sv, Sv)))
        r1, r2 = np.einsum("ij,ij->i", r, Su), np.einsum("ij,ij->i", r, Sv)
        det = g11 * g22 - g12 * g12
        ok = det > 1e-300
        du = np.where(ok, (g22 * r1 - g12 * r2) / np.where(ok, det, 1.0), 0.0)
        dv = np.where(ok, (g11 * r2 - g12 * r1) / np.where(ok, det, 1.0), 0.0)
        a, b = a.copy(), b.copy()
        a[edge] += du
        b[edge] += dv
    return a, b


def _parameters(X: Array, params: ArrayLike | None, base: BSplineSurface | None, corrections: int
                ) -> tuple[Array, Array]:
    if params is not None:
        uv = V.as_finite_array(params, "params")
        if uv.shape != (X.shape[0], 2):
            raise InvalidGeometryError(f"params: expected shape ({X.shape[0]}, 2), got {uv.shape}")
        return uv[:, 0].copy(), uv[:, 1].copy()
    if base is not None:
        if not isinstance(base, BSplineSurface) or base.dim != 3:
            raise InvalidGeometryError(f"base: expected a 3-D BSplineSurface, got {type(base).__name__}")
        return base_parameters(base, X)
    return plane_parameters(X)


def fit_adaptive_scattered(points: ArrayLike, tol: float, degree: int | tuple[int, int] = 3, *,
                           params: ArrayLike | None = None, base: BSplineSurface | None = None,
                           base_poles: int | tuple[int, int] | None = None,
                           knots: tuple[ArrayLike, ArrayLike] | None = None, smoothing: float | None = None,
                           corrections: int = 0, max_levels: int | None = None,
                           progress: Callable[[str], None] | None = None) -> ScatteredAdaptiveFit:
    """Adaptive hierarchical least-squares fit of a point cloud to a tolerance (course §7-10).

    See the module notes for the process. On gridded data given as points with the grid's
    parameters it follows :func:`~.adaptive.fit_adaptive` (same base, same refinement rule, the
    overlay solves differing only in how vertices without data are damped).

    Parameters
    ----------
    points : array_like, shape (k, 3)
    tol : float
        Largest allowed distance from a point to the surface (model units, > 0).
    degree : int or (int, int)
    params : array_like, shape (k, 2), optional
        ``(u, v)`` of each point; default the foot points on ``base``, else coordinates on the
        points' best-fit plane scaled to [0, 1]^2.
    base : BSplineSurface, optional
        A surface the points lie near (a scan over a CAD face).
    base_poles : int or (int, int), optional
        Poles of the first base fit; default ``degree + 5``.
    knots : (array_like, array_like), optional
        Full knot vectors of the base (e.g. a gridded fit's, to compare the paths); the base is
        then not grown. Default clamped, uniform over the parameters' bounding box.
    smoothing : float, optional
        λ of the base's difference penalty; default
        :data:`~occsurf.algorithms.tolerances.FIT_SCATTERED_SMOOTHING` (keeps holes defined).
    corrections : int
        Parameter-correction steps on the base (the points' parameters then become their foot
        points on it, fixed for the overlays).
    max_levels : int, optional
        Deepest overlay level; default :data:`~occsurf.algorithms.tolerances.FIT_ADAPTIVE_MAX_LEVELS`.
    progress : callable, optional
        Called with a one-line message after each round.

    Returns
    -------
    ScatteredAdaptiveFit

    Raises
    ------
    ParameterError
        A non-positive ``tol``, a negative ``max_levels``/``corrections``/``smoothing``.
    InvalidGeometryError
        Bad shapes, too few points for the degree, parameters spanning no area.
    """
    tol, depth_max = check_tol_levels(tol, max_levels)
    if int(corrections) < 0:
        raise ParameterError(f"corrections: expected an integer >= 0, got {corrections!r}")
    X = V.as_finite_array(points, "points")
    if X.ndim != 2 or X.shape[1] != 3:
        raise InvalidGeometryError(f"points: expected shape (k, 3), got {X.shape}")
    pu, pv = (V.as_degree(k) for k in _pair_of(degree, "degree"))
    if X.shape[0] < (pu + 1) * (pv + 1):
        raise InvalidGeometryError(f"points: a degree ({pu}, {pv}) fit needs at least {(pu + 1) * (pv + 1)} points, "
                                   f"got {X.shape[0]}")
    lam = float(tolerances.FIT_SCATTERED_SMOOTHING) if smoothing is None else float(smoothing)
    if not (np.isfinite(lam) and lam >= 0):
        raise ParameterError(f"smoothing: expected a number >= 0, got {smoothing!r}")
    with _nk.batch(int(tolerances.FIT_EVALUATIONS_PER_DATUM) * X.shape[0]):  # as fit_adaptive
        return _fit(X, params, base, (pu, pv), tol, depth_max, lam, base_poles, knots, int(corrections), progress)


def _fit(X: Array, params: ArrayLike | None, base: BSplineSurface | None, deg: tuple[int, int], tol: float,
         depth_max: int, lam: float, base_poles: int | tuple[int, int] | None,
         knots: tuple[ArrayLike, ArrayLike] | None, corrections: int,
         progress: Callable[[str], None] | None) -> ScatteredAdaptiveFit:
    """:func:`fit_adaptive_scattered` on checked arguments."""
    pu, pv = deg
    u, v = _parameters(X, params, base, corrections)
    if not (u.max() > u.min() and v.max() > v.min()):
        raise InvalidGeometryError("params: the points' parameters span no area (collinear or coincident points)")
    poles = _pair_of(base_poles, "base_poles") if base_poles is not None else (pu + 5, pv + 5)
    check_fit_size(poles, (pu, pv), "base_poles")
    for _ in range(corrections):
        u, v = _corrected(X, u, v, poles, (pu, pv), lam)
    if knots is None:
        surf, dist = _grow_base(X, u, v, poles, (pu, pv), tol, lam, progress)
    else:
        tu = V.check_knots(knots[0], pu, np.size(knots[0]) - pu - 1, "knots[0]")
        tv = V.check_knots(knots[1], pv, np.size(knots[1]) - pv - 1, "knots[1]")
        u, v = np.clip(u, tu[pu], tu[-pu - 1]), np.clip(v, tv[pv], tv[-pv - 1])
        surf = fit_scattered(X, (tu.size - pu - 1, tv.size - pv - 1), (pu, pv), params=np.c_[u, v], knots=(tu, tv),
                             smoothing=lam, measure=False).surface
        dist = measure_points(surf, X, u, v, above=tol)
    hs = HierarchicalSurface(surf, "frame")
    fitter = _ScatteredFitter(hs, X, u, v, _BaseSolver(surf, u, v, lam))
    dist = refine(hs, fitter, dist, tol, depth_max, error=lambda d: d, owners=lambda h: _owner(h, u, v),
                  regions=lambda node, mine: _regions(hs, node, mine, u, v),
                  measure=lambda flat: measure_points(flat, X, u, v, above=tol), progress=progress)
    reports, surfs, dists = _level_reports(hs, X, u, v)
    return ScatteredAdaptiveFit(hs, tuple(reports), dists[-1], u, v, tol, reports[-1].max_error <= tol,
                                tuple(surfs), tuple(dists))
