"""Adaptive hierarchical fitting of gridded data (course §7-10).

"Fitting of gridded data by tensor-product surfaces and the adaptive refinement of this fitting
process to produce a hierarchical surface": fit a coarse base surface by least squares
(:func:`~.gridded.fit_grid`), measure the distance of every data point to the surface, and where
it exceeds the tolerance add overlays (course ch. 5) that refine only those knot spans; fit the
residual at the finer level as the overlays' displacements and store them as offsets in the
parent's frames (§5-15); repeat level by level until the tolerance holds everywhere or the level
limit is reached.

Per level
---------
1. For each overlay made at the previous level (the base at level 1), mark its knot spans that
   hold a data point farther than ``tol`` from the surface, grow the marks by
   :data:`~occsurf.algorithms.tolerances.FIT_ADAPTIVE_MARGIN` spans and cover each connected group
   of marked spans by one rectangle; overlapping rectangles merge. Spans holding fewer than two
   data rows in a direction are not refined further (the data could not determine finer poles).
2. Each rectangle becomes an overlay (midpoint knot insertion). Its world displacements ``δ``
   are the least-squares fit of the current residual ``Q - S`` over the data in the overlay's
   support, with the overlay's own B-splines: ``δ = A^+ R B^{+T}`` (course §7-4 on the sub-grid;
   singular values below :data:`~occsurf.algorithms.tolerances.FIT_OVERLAY_RCOND` times the
   largest are dropped, so a vertex that touches the data only with the tail of its B-spline
   stays put instead of swinging between the samples), then stored as frame offsets. Overlays of one level are
   fitted one after the other, each against the residual its predecessors left.
3. The error is measured again: the distance from each data point to the (flattened) surface by
   point projection (:func:`~._common.project_points`), which never exceeds the residual at the
   data parameter; on the four boundary rows the residual at the parameters counts too
   (:func:`boundary_error`), so the surface's border stays within ``tol`` of the data's border
   (a corner of a least-squares fit can flare out along the surface, near every data point).

Height grids keep ``x = u``, ``y = v`` exactly (displacements along z only), so the result stays a
height field. The result is an editable :class:`~occsurf.algorithms.hierarchical.HierarchicalSurface`
whose :meth:`flatten` is one exact B-spline surface (for STEP).

References
----------
Course notes C25 (SIGGRAPH 1991) §7-10 and ch. 5; D. R. Forsey, R. H. Bartels, "Surface fitting
with hierarchical splines", ACM TOG 14 (1995) 134-161.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.linalg as sla
from numpy.typing import ArrayLike, NDArray

from .. import _numba_kernels as _nk
from .. import tolerances
from ..errors import InvalidGeometryError
from ..hierarchical.overlays import Overlay
from ..hierarchical.surface import HierarchicalSurface
from ..kernel.basis import basis_matrix
from ..kernel.surface import BSplineSurface
from ._common import project_points
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
from .gridded import GridFit, _grid_data, _pair_of, fit_grid

__all__ = ["LevelReport", "AdaptiveFit", "fit_adaptive", "measure_grid", "measure_heights", "graph_bounds",
           "normal_deviation", "boundary_error"]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class AdaptiveFit(FitSummary):
    """Result of :func:`fit_adaptive`.

    Attributes
    ----------
    hierarchy : HierarchicalSurface
        Editable; ``hierarchy.flatten()`` is the exact single B-spline surface.
    levels : tuple of LevelReport
    distance : ndarray, shape (m, n)
        Measured distance of each data point to the final surface (NaN on missing cells).
    u_params, v_params : ndarray
    converged : bool
        ``max_error <= tol``, and the boundary rows are within ``tol`` of the surface's border at
        their parameters (:func:`boundary_error`).
    level_surfaces : tuple of BSplineSurface
        Per level L, the flat surface of the hierarchy truncated below L (finer offsets zeroed).
    level_distances : tuple of ndarray, each (m, n)
        Their measured distances to the data (the per-level error picture).
    """

    hierarchy: HierarchicalSurface
    levels: tuple[LevelReport, ...]
    distance: Array
    u_params: Array
    v_params: Array
    tol: float
    converged: bool
    level_surfaces: tuple[BSplineSurface, ...] = ()
    level_distances: tuple[Array, ...] = ()


def measure_grid(surface: BSplineSurface, points: Array, u: Array, v: Array, *, above: float | None = None) -> Array:
    """Distance of every grid point ``points[i, j]`` (shape (m, n, 3), NaN = missing) to ``surface``,
    by projection from ``(u_i, v_j)`` (:func:`~._common.project_points`). Shape (m, n).

    The grid is processed in blocks of rows (memory O(block), not O(data) x 27 partials), the
    starting partials coming from ``derivatives_grid`` (tensor-product evaluation). With ``above``
    only the points whose deviation at their parameters exceeds it are projected; the others
    keep that deviation, an upper bound of their distance (at most ``above``): every comparison
    against a threshold ``>= above`` is then the same as with all points projected.
    """
    m, n = points.shape[:2]
    out = np.full((m, n), np.nan)
    rows = max(1, int(tolerances.FIT_MEASURE_BLOCK) // max(n, 1))
    for i0 in range(0, m, rows):
        sl = slice(i0, min(i0 + rows, m))
        D = surface.derivatives_grid(u[sl], v, 2)  # (r, n, 3, 3, 3)
        Q = points[sl]
        r = np.linalg.norm(D[:, :, 0, 0] - Q, axis=-1)
        ok = ~np.isnan(Q).any(axis=-1)
        blk = np.where(ok, r, np.nan)
        todo = ok if above is None else ok & (r > above)
        if todo.any():
            I, J = np.nonzero(todo)
            _, _, d = project_points(surface, Q[I, J], u[sl][I], v[J], initial=D[I, J])
            blk[I, J] = d
        out[sl] = blk
    return out


def graph_bounds(surface: BSplineSurface) -> tuple[float, float]:
    """``(L, eps)`` for a polynomial 3-D surface meant as a height field ``x = u, y = v`` (a fit of
    heights): ``|grad z(u, v)| <= L`` and ``|(x(u, v) - u, y(u, v) - v)| <= eps`` on the domain.

    Both by the convex hull property: the partials of ``z`` are B-splines whose coefficients are
    the scaled differences ``p (z_{i+1,j} - z_ij) / (t_{i+p+1} - t_{i+1})`` of the net (The NURBS
    Book, eq. 3.17), and ``x(u, v) - u = sum (x_ij - xi_i) N_i(u) N_j(v)`` with ``xi_i`` the
    Greville abscissae (linear precision), so ``eps`` is the largest deviation of the net's x and
    y from them (round-off for a height fit).
    """
    if surface.is_rational or surface.dim != 3:
        raise InvalidGeometryError("graph_bounds: expected a polynomial 3-D surface")
    (p, q), (U, Vk) = surface.degree, surface.knots
    P = surface.control_points
    grads = []
    for ax, (deg, t) in enumerate(((p, U), (q, Vk))):
        n = P.shape[ax]
        if deg == 0 or n < 2:
            grads.append(0.0)
            continue
        dz = np.diff(P[..., 2], axis=ax)
        h = t[deg + 1:n + deg] - t[1:n]  # t_{i+p+1} - t_{i+1}, i = 0 .. n-2
        h = h[:, None] if ax == 0 else h[None, :]
        c = np.where(h > 0, deg * dz / np.where(h > 0, h, 1.0), 0.0)
        grads.append(float(np.abs(c).max()))
    gu, gv = surface.greville()
    eps = float(np.hypot(np.abs(P[..., 0] - gu[:, None]).max(), np.abs(P[..., 1] - gv[None, :]).max()))
    return math.hypot(*grads), eps


def _project_grid(surface: BSplineSurface, points: Array, u: Array, v: Array, mask: NDArray[np.bool_]) -> Array:
    """The projected distances (:func:`measure_grid`'s values, bit for bit: the same starting
    partials, by rows) of the grid points in ``mask``, in ``mask``'s row-major order."""
    rows = np.flatnonzero(mask.any(axis=1))
    n = points.shape[1]
    step = max(1, int(tolerances.FIT_MEASURE_BLOCK) // max(n, 1))
    out = []
    for k in range(0, rows.size, step):
        blk = rows[k:k + step]
        I, J = np.nonzero(mask[blk])
        D = surface.derivatives_grid(u[blk], v, 2)
        out.append(project_points(surface, points[blk][I, J], u[blk][I], v[J], initial=D[I, J])[2])
    return np.concatenate(out) if out else np.empty(0)


def cell_labels(hs: HierarchicalSurface, u: Array, v: Array) -> NDArray[np.intp]:
    """Per grid point, a label of the knot span cell that a flag on it would mark: the cell of
    its owner's level (the deepest node whose region holds it, :func:`_owner`; the spans as
    :func:`_regions` bins them), distinct across nodes; shape (m, n), -1 where none."""
    nodes, own, _ = _owner(hs, u, v)
    labels = np.full(own.shape, -1, dtype=np.intp)
    offset = 0
    for k, node in enumerate(nodes):
        knots = hs.level_surface(node).knots
        (ua, ub), (va, vb) = hs.domain if node is None else node.region
        ku, iu, _ = _cells(knots[0], ua, ub, u)
        kv, iv, _ = _cells(knots[1], va, vb, v)
        mine = (own == k) & (iu >= 0)[:, None] & (iv >= 0)[None, :]
        labels[mine] = (offset + iu[:, None] * (kv.size - 1) + iv[None, :])[mine]
        offset += (ku.size - 1) * (kv.size - 1)
    return labels


def measure_heights(surface: BSplineSurface, points: Array, u: Array, v: Array, tol: float, greed: float,
                    cells: NDArray[np.intp] | None = None) -> Array:
    """The distances of a height fit's grid points that decide its refinement (exact, as
    :func:`measure_grid` with ``above=tol``), and bounds for the others.

    The adaptive fit uses a distance array ``dist`` only through ``err = boundary_error(dist)``:
    its maximum ``W`` and the flags ``err > max(tol, greed W)``. Those come out the same as
    with every point projected while most points are not:

    - each point gets ``r = |Q - S(u, v)|`` at its parameters (one grid evaluation), an upper
      bound of its distance ``d`` (the projection never increases the distance from its start);
    - a lower bound: with ``(L, eps)`` of :func:`graph_bounds`, a data point ``Q = (u_i, v_j, z)``
      and any surface point ``S(a, b)``, ``rho = |(a, b) - (u_i, v_j)|``: the horizontal gap is at
      least ``rho - eps`` and the vertical one at least ``r_z - L rho`` (``r_z = |z - S_z(u_i, v_j)|``,
      the domain being convex), so ``|Q - S(a, b)|^2 >= sigma^2 + (r_z - L eps - L sigma)^2`` with
      ``sigma = max(0, rho - eps)``, whose minimum over ``sigma >= 0`` is
      ``max(0, r_z - L eps)^2 / (1 + L^2)``: ``d >= lo = max(0, r_z - L eps) / sqrt(1 + L^2)``.
      ``1e-12`` of the data's size is taken off ``r_z`` for the round-off of the evaluation;
    - the points within ``tol`` at their parameters keep ``r`` (as :func:`measure_grid`); the
      border rows are projected (``boundary_error`` raises them to ``r``, but ``max(dist)`` is
      reported);
    - ``W``: the interior points are projected in decreasing ``r``, first the largest 1/64,
      then every one whose ``r`` exceeds the largest error found (no other can exceed it);
    - with ``thr = max(tol, greed W)``: a point with ``r <= thr`` is not flagged (``d <= r``) and
      keeps ``r``; one with ``lo > thr`` is flagged (``d >= lo``) and gets ``lo`` (``<= d <= W``:
      the maximum stays ``W``); only the others are projected;
    - with ``cells`` (:func:`cell_labels`): the flags are used only as "some point of this knot
      span cell is flagged" (:func:`_regions`), so the undecided points of a cell that holds a
      flagged point already are not projected either; they keep ``r`` (``<= W``).

    So every point above the threshold is flagged or lies in a cell flagged anyway, and no point
    below it is flagged but in such a cell: the maximum and the marked cells, hence the fit, are
    those of the distances of every point. The values of the points not projected are bounds,
    never reported (:func:`fit_adaptive` reports distances from :func:`measure_grid`).
    """
    m, n = points.shape[:2]
    R = points - surface.evaluate_grid(u, v)
    r = np.linalg.norm(R, axis=-1)  # NaN on missing cells
    ok = np.isfinite(r)
    L, eps = graph_bounds(surface)
    size = max(1.0, float(np.nanmax(np.abs(points))))
    lower = np.maximum(np.abs(R[..., 2]) - L * eps - 1e-12 * size, 0.0) / np.hypot(1.0, L)
    out = np.where(ok, r, np.nan)
    done = ~ok | (r <= tol)

    def project(mask: NDArray[np.bool_]) -> None:
        if mask.any():
            out[mask] = _project_grid(surface, points, u, v, mask)
            done[mask] = True

    border = np.zeros((m, n), bool)
    border[[0, -1], :] = True
    border[:, [0, -1]] = True
    project(border & ~done)
    worst_border = float(np.max(r[border & ok], initial=0.0))  # boundary_error raises the border to r
    todo = np.flatnonzero(~done)
    if todo.size:
        first = np.zeros((m, n), bool)
        first.flat[todo[np.argsort(-r.flat[todo], kind="stable")[:max(1024, todo.size // 1024)]]] = True
        project(first)
    interior = ~border & ok
    worst = max(worst_border, float(np.max(out[interior & done], initial=0.0)))
    project(~done & (r > worst))  # only these could exceed the largest error found
    worst = max(worst_border, float(np.max(out[interior & done], initial=0.0)))
    thr = max(tol, greed * worst)
    sure = ~done & (lower > thr)
    out[sure] = lower[sure]
    undecided = ~done & (r > thr) & ~sure
    if cells is not None and undecided.any():
        marked = np.zeros(int(cells.max()) + 2, bool)  # index -1 (no cell) lands on the spare last entry

        def unmarked() -> NDArray[np.bool_]:
            marked[cells[sure | (done & (out > thr))]] = True
            marked[-1] = False
            return undecided & ~done & ~marked[cells]

        # first the most likely flags: the points of largest r of each cell not marked yet
        idx = np.flatnonzero(unmarked())
        c = cells.flat[idx]
        order = np.lexsort((-r.flat[idx], c))
        c, idx = c[order], idx[order]
        rank = np.arange(c.size) - np.searchsorted(c, c)  # position within its cell
        first = np.zeros((m, n), bool)
        first.flat[idx[rank < 16]] = True
        project(first)
        undecided = unmarked()
    project(undecided)
    return out


def normal_deviation(surface: BSplineSurface, points: Array, u: Array, v: Array) -> Array:
    """``|(Q - S(u, v)) . N(u, v)|`` on the grid, shape (m, n) (NaN on missing cells): the
    first-order distance of each point to the surface (the deviation along the normal; exact for
    a plane). Cheap (tensor-product partials), used to compare candidate fits, never reported."""
    D = surface.derivatives_grid(u, v, 1)
    # np.cross and np.linalg.norm written out (the same operations in the same order, bit for bit,
    # without their strided temporaries)
    a, b = D[:, :, 1, 0], D[:, :, 0, 1]
    N = np.empty(a.shape)
    N[..., 0] = a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1]
    N[..., 1] = a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2]
    N[..., 2] = a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]
    length = np.sqrt(N[..., 0] * N[..., 0] + N[..., 1] * N[..., 1] + N[..., 2] * N[..., 2])
    N /= np.maximum(length, 1e-300)[..., None]
    return np.abs(np.einsum("ijk,ijk->ij", points - D[:, :, 0, 0], N))


def boundary_error(surface: BSplineSurface, points: Array, u: Array, v: Array, dist: Array) -> Array:
    """``dist`` with the four boundary rows raised to the deviation at the data parameters,
    ``|Q - S(u, v)|``: a fit whose border slides along the surface (a flared corner) is near every
    data point, so the distance misses it, but its border is that far from the data's border."""
    e = dist.copy()
    for idx in ((0, slice(None)), (-1, slice(None)), (slice(None), 0), (slice(None), -1)):
        uu, vv = u[idx[0]], v[idx[1]]
        S = surface.evaluate_grid(np.atleast_1d(uu), np.atleast_1d(vv)).reshape(points[idx].shape)
        r = np.linalg.norm(points[idx] - S, axis=-1)
        e[idx] = np.fmax(e[idx], r)
    return e


def _cells(knots: Array, lo: float, hi: float, x: Array) -> tuple[Array, NDArray[np.intp], NDArray[np.intp]]:
    """Distinct knots ``k`` of ``[lo, hi]``, the span index of each parameter (-1 outside) and
    the number of data parameters per span."""
    k, idx = span_index(knots, lo, hi, x)
    counts = np.bincount(idx[idx >= 0], minlength=k.size - 1)
    return k, idx, counts


def _owner(hs: HierarchicalSurface, u: Array, v: Array) -> Owners:
    """Per data row/column pair, the deepest node whose region holds it: returns the nodes and
    an (m, n) index into them (0 = the base)."""
    return owner(hs, (u.size, v.size), lambda r: np.ix_((u >= r[0][0]) & (u <= r[0][1]),
                                                         (v >= r[1][0]) & (v <= r[1][1])))


def _regions(hs: HierarchicalSurface, parent: Overlay | None, flagged: NDArray[np.bool_], u: Array, v: Array
             ) -> list[tuple[tuple[float, float], tuple[float, float]]]:
    """The rectangles (u_range, v_range) to refine inside ``parent`` (its knot spans holding a
    flagged point, grown by the margin, grouped and merged)."""
    lvl = hs.level_surface(parent)
    (ua, ub), (va, vb) = hs.domain if parent is None else parent.region
    ku, iu, cu = _cells(lvl.knots[0], ua, ub, u)
    kv, iv, cv = _cells(lvl.knots[1], va, vb, v)
    su, sv = iu >= 0, iv >= 0
    if not su.any() or not sv.any():
        return []
    marks = np.zeros((ku.size - 1, kv.size - 1), bool)
    I, J = np.nonzero(flagged[np.ix_(su, sv)])
    marks[iu[su][I], iv[sv][J]] = True
    marks &= (cu >= 2)[:, None] & (cv >= 2)[None, :]  # the halves of a span must still hold data rows
    return rectangles(marks, ku, kv)


def _block(A: Array, D: Array, B: Array) -> Array:
    """``A D_k B^T`` per coordinate k: an overlay's share on its sub-grid, (rows, cols, 3)."""
    return np.stack([A @ D[..., k] @ B.T for k in range(D.shape[-1])], -1)


class _Fitter(OverlayFitter):
    """The hierarchy under construction (:class:`~._refine.OverlayFitter`) on a grid of data
    ``P3`` (m, n, 3): per overlay, the data rows/columns in its support and its B-spline blocks."""

    def __init__(self, hs: HierarchicalSurface, P3: Array, u: Array, v: Array, heights: bool,
                 refit_base: Callable[[Array], BSplineSurface] | None) -> None:
        super().__init__(hs, P3, u, v, refit_base)
        self.heights = heights

    def evaluate(self, surface: BSplineSurface) -> Array:
        return surface.evaluate_grid(self.u, self.v)

    def _operators(self, ov: Overlay) -> tuple[NDArray[np.intp], NDArray[np.intp], Array, Array]:
        if ov.id not in self.ops:
            p, q = self.hs.degree
            ku, kv = ov.knots
            (i0, i1), (j0, j1) = ov.vertices
            su, sv = support(ov, (p, q))
            ru = np.flatnonzero((self.u >= su[0]) & (self.u <= su[1]))
            rv = np.flatnonzero((self.v >= sv[0]) & (self.v <= sv[1]))
            A = basis_matrix(ku, p, ku.shape[0] - p - 1, self.u[ru])[0][:, i0:i1 + 1]
            B = basis_matrix(kv, q, kv.shape[0] - q - 1, self.v[rv])[0][:, j0:j1 + 1]
            self.ops[ov.id] = (ru, rv, A, B)
        return self.ops[ov.id]

    def fit_overlay(self, ov: Overlay, resid: Array) -> None:
        """Least-squares ``δ`` of ``ov`` against ``resid`` plus its own current share; updates ``resid``."""
        ru, rv, A, B = self._operators(ov)
        old = self.delta.get(ov.id)
        if ru.size == 0 or rv.size == 0:
            self.delta[ov.id] = np.zeros(ov.shape + (3,)) if old is None else old
            self._apply(ov)
            return
        R = resid[np.ix_(ru, rv)]
        if old is not None:
            R = R + _block(A, old, B)
        comps = [2] if self.heights else [0, 1, 2]
        delta = np.zeros((A.shape[1], B.shape[1], 3))
        missing = np.isnan(R).any(axis=-1)
        if not missing.any():
            rc = float(tolerances.FIT_OVERLAY_RCOND)
            Ap, Bp = sla.pinv(A, rtol=rc, check_finite=False), sla.pinv(B, rtol=rc, check_finite=False)
            for c in comps:
                delta[..., c] = Ap @ R[..., c] @ Bp.T
        else:  # missing cells: Kronecker rows of the valid ones, minimum-norm least squares
            K = np.einsum("ia,jb->ijab", A, B)[~missing].reshape(-1, A.shape[1] * B.shape[1])
            sol = sla.lstsq(K, R[~missing][:, comps], cond=float(tolerances.FIT_OVERLAY_RCOND), lapack_driver="gelsd",
                            check_finite=False)[0]
            delta[..., comps] = sol.reshape(A.shape[1], B.shape[1], len(comps))
        self.delta[ov.id] = delta
        self._apply(ov)
        resid[np.ix_(ru, rv)] = R - _block(A, delta, B)


def _level_reports(hs: HierarchicalSurface, P3: Array, u: Array, v: Array
                   ) -> tuple[list[LevelReport], list[BSplineSurface], list[Array]]:
    """Per level L, the surface truncated below L (finer offsets zeroed) measured against the data:
    the reports, the truncated flat surfaces and their distance arrays."""
    return level_reports(hs, lambda flat: measure_grid(flat, P3, u, v))


def _measure(flat: BSplineSurface, hs: HierarchicalSurface, P3: Array, u: Array, v: Array, tol: float,
             heights: bool) -> Array:
    """The distances of ``flat`` (``hs.flatten()``) that decide a round (:func:`~._refine.refine`):
    :func:`measure_heights` for a height fit, else :func:`measure_grid` with the points within
    ``tol`` at their parameters skipped."""
    if heights:
        return measure_heights(flat, P3, u, v, tol, float(tolerances.FIT_ADAPTIVE_GREED), cells=cell_labels(hs, u, v))
    return measure_grid(flat, P3, u, v, above=tol)


def _grow_base(Q: Array, heights: bool, poles: tuple[int, int], deg: tuple[int, int], tol: float,
               opts: dict[str, Any], progress: Callable[[str], None] | None) -> tuple[GridFit, Array, Array]:
    """The base fit, its spans multiplied by 1.5 while the places to refine cover more than
    :data:`~occsurf.algorithms.tolerances.FIT_ADAPTIVE_MAX_COVER` of it (when the error is
    everywhere, uniform refinement is the cheaper hierarchy: no overlay overhead).

    Each step grows u, v or both, whichever lowers the error most per added pole (the largest
    ``-log(e_new / e) / log(n_new / n)``; both when none gains 0.1): data that vary along one
    direction only (a ruled or extruded face) do not pay for poles along the other. The candidates
    are compared by the first-order distance :func:`normal_deviation` (cheap); the base chosen is
    measured by projection (:func:`_measure`), which decides whether to grow further.
    """
    m, n = Q.shape[:2]
    data = Q[..., 0] if heights else Q

    def candidate(poles_: tuple[int, int]) -> tuple[tuple[GridFit, Array], float]:
        base_ = fit_grid(data, poles_, deg, **opts)
        u_, v_ = base_.u_params, base_.v_params
        P3_ = np.stack(np.broadcast_arrays(u_[:, None], v_[None, :], Q[..., 0]), -1) if heights else Q
        est = normal_deviation(base_.surface, P3_, u_, v_)
        return (base_, P3_), float(np.nanmax(boundary_error(base_.surface, P3_, u_, v_, est)))

    def measured(fit: tuple[GridFit, Array]) -> tuple[Array, Array]:
        (base_, P3_), u_, v_ = fit, fit[0].u_params, fit[0].v_params
        dist_ = _measure(base_.surface, HierarchicalSurface(base_.surface, "frame"), P3_, u_, v_, tol, heights)
        return dist_, boundary_error(base_.surface, P3_, u_, v_, dist_)

    def regions(fit: tuple[GridFit, Array], flagged: NDArray[np.bool_]) -> tuple[HierarchicalSurface, list[Region]]:
        hs = HierarchicalSurface(fit[0].surface, "frame")
        return hs, _regions(hs, None, flagged, fit[0].u_params, fit[0].v_params)

    (base, P3), dist = grow_base(poles, deg, (m, n), tol, candidate, measured, regions, progress)
    return base, P3, dist


def fit_adaptive(data: ArrayLike, tol: float, degree: int | tuple[int, int] = 3, *,
                 base_poles: int | tuple[int, int] | None = None, x: ArrayLike | None = None,
                 y: ArrayLike | None = None, u_params: ArrayLike | None = None, v_params: ArrayLike | None = None,
                 method: str = "centripetal", smoothing: float = 0.0, fix_boundary: bool = False,
                 max_levels: int | None = None, progress: Callable[[str], None] | None = None) -> AdaptiveFit:
    """Adaptive hierarchical least-squares fit of gridded data to a tolerance (course §7-10).

    Rounds of: mark the data points farther than ``max(tol, FIT_ADAPTIVE_GREED * max_error)``
    from the surface; give each node (base or overlay) whose region is the deepest one holding
    marked points new child overlays over the marked spans (module notes); fit them to the
    residual; then :data:`~occsurf.algorithms.tolerances.FIT_ADAPTIVE_SWEEPS` backfitting sweeps
    (the base and every overlay refitted in turn, finer displacements kept), which removes the
    ringing a coarse fit of a sharp feature leaves far from it. Refining the worst places first
    keeps overlays where the data need them.

    Parameters
    ----------
    data : array_like, shape (m, n, 3) or (m, n)
        Points, or heights over ``x, y`` (NaN = missing cell).
    tol : float
        Largest allowed distance from a data point to the surface (model units, > 0).
    degree : int or (int, int)
    base_poles : int or (int, int), optional
        Poles of the base fit; default ``degree + 5`` (five spans), at most the data count.
    x, y, u_params, v_params, method
        As :func:`~.gridded.fit_grid`.
    smoothing : float
        Smoothing λ of the base fit.
    fix_boundary : bool
        The base holds the four boundary curves fitted to the boundary rows.
    max_levels : int, optional
        Deepest overlay level; default :data:`~occsurf.algorithms.tolerances.FIT_ADAPTIVE_MAX_LEVELS`.
    progress : callable, optional
        Called with a one-line message after each round.

    Returns
    -------
    AdaptiveFit
        Per-level reports measure the hierarchy truncated below each level.
    """
    tol, depth_max = check_tol_levels(tol, max_levels)
    Q, heights, xs, ys = _grid_data(data, x, y)
    m, n = Q.shape[:2]
    if not heights and Q.shape[2] != 3:
        raise InvalidGeometryError(f"data: adaptive fitting needs 3-D points or heights, got {Q.shape[2]}-D points")
    pu, pv = _pair_of(degree, "degree")
    if base_poles is None:
        base_poles = (min(pu + 5, m), min(pv + 5, n))
    opts: dict[str, Any] = dict(x=xs if heights else None, y=ys if heights else None, u_params=u_params, v_params=v_params,
                method=method, smoothing=smoothing, fix_boundary=fix_boundary)
    # every datum is evaluated ~20 times (candidate bases, Newton steps of each measurement, sweeps,
    # level reports; 849 190 scattered evaluations for Franke 200 x 200): a fit of a few thousand
    # points repays numba's loading, and its smaller evaluations (overlays, the points of a
    # projection still moving) keep the kernels
    with _nk.batch(int(tolerances.FIT_EVALUATIONS_PER_DATUM) * m * n):
        return _fit(Q, heights, _pair_of(base_poles, "base_poles"), (pu, pv), tol, depth_max, opts, progress)


def _fit(Q: Array, heights: bool, base_poles: tuple[int, int], deg: tuple[int, int], tol: float, depth_max: int,
         opts: dict[str, Any], progress: Callable[[str], None] | None) -> AdaptiveFit:
    """:func:`fit_adaptive` on checked arguments."""
    pu, pv = deg
    base, P3, dist = _grow_base(Q, heights, base_poles, deg, tol, opts, progress)
    u, v = base.u_params, base.v_params
    knots = base.surface.knots

    def refit_base(target: Array) -> BSplineSurface:
        data_ = target[..., 2] if heights else target
        o = dict(opts, u_params=u, v_params=v, x=None, y=None)
        return fit_grid(data_, base.surface.n_poles, (pu, pv), knots=knots, **o).surface

    hs = HierarchicalSurface(base.surface, "frame")
    fitter = _Fitter(hs, P3, u, v, heights, refit_base)
    dist = refine(hs, fitter, dist, tol, depth_max, error=lambda d: boundary_error(hs.flatten(), P3, u, v, d),
                  owners=lambda h: _owner(h, u, v), regions=lambda node, mine: _regions(hs, node, mine, u, v),
                  measure=lambda flat: _measure(flat, hs, P3, u, v, tol, heights), progress=progress)
    reports, surfs, dists = _level_reports(hs, P3, u, v)
    border = float(np.nanmax(boundary_error(surfs[-1], P3, u, v, dists[-1])))
    return AdaptiveFit(hs, tuple(reports), dists[-1], u, v, tol, border <= tol, tuple(surfs), tuple(dists))
