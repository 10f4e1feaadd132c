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

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.ndimage as ndi
from numpy.typing import ArrayLike, NDArray

from .. import tolerances
from ..errors import InvalidGeometryError, ParameterError
from ..hierarchical.core import Overlay
from ..hierarchical.surface import HierarchicalSurface
from ..kernel.basis import basis_matrix
from ..kernel.surface import BSplineSurface
from ._common import project_points
from .gridded import GridFit, _grid_data, _pair_of, _params, fit_grid

__all__ = ["LevelReport", "AdaptiveFit", "fit_adaptive", "measure_grid", "normal_deviation", "boundary_error"]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class LevelReport:
    """Statistics after fitting one level (level 0 is the base).

    Attributes
    ----------
    level : int
    overlays : int
        Overlays added at this level (0 for the base).
    control_points : int
        Degrees of freedom stored at this level: base poles, or the overlays' offsets.
    max_error, rms_error : float
        Distance from the data points to the surface up to this level, measured by projection.
    """

    level: int
    overlays: int
    control_points: int
    max_error: float
    rms_error: float

    def as_dict(self) -> dict:
        return {"level": self.level, "overlays": self.overlays, "control_points": self.control_points,
                "max_error": self.max_error, "rms_error": self.rms_error}


@dataclass(frozen=True)
class AdaptiveFit:
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
    level_surfaces: tuple = ()
    level_distances: tuple = ()

    @property
    def max_error(self) -> float:
        return self.levels[-1].max_error

    @property
    def rms_error(self) -> float:
        return self.levels[-1].rms_error

    @property
    def control_points_total(self) -> int:
        """Base poles plus stored offsets (course §5-17)."""
        return int(self.hierarchy.pole_counts()["stored"])


def measure_grid(surface, points: Array, u: Array, v: Array, *, above: float | None = None) -> Array:
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


def normal_deviation(surface, points: Array, u: Array, v: Array) -> Array:
    """``|(Q - S(u, v)) . N(u, v)|`` on the grid, shape (m, n) (NaN on missing cells): the
    first-order distance of each point to the surface (the deviation along the normal; exact for
    a plane). Cheap (tensor-product partials), used to compare candidate fits, never reported."""
    D = surface.derivatives_grid(u, v, 1)
    N = np.cross(D[:, :, 1, 0], D[:, :, 0, 1])
    N /= np.maximum(np.linalg.norm(N, axis=-1, keepdims=True), 1e-300)
    return np.abs(np.einsum("ijk,ijk->ij", points - D[:, :, 0, 0], N))


def boundary_error(surface, points: Array, u: Array, v: Array, dist: Array) -> Array:
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


def _stats(dist: Array) -> tuple[float, float]:
    e = dist[np.isfinite(dist)]
    return float(e.max()), float(np.sqrt(np.mean(e ** 2)))


def _boxes(marks: Array) -> list[tuple[int, int, int, int]]:
    """Bounding boxes (i0, i1, j0, j1), end-exclusive, of the connected groups of ``marks``, merged
    until no two overlap."""
    lab, _ = ndi.label(marks, structure=np.ones((3, 3)))
    boxes = [(s[0].start, s[0].stop, s[1].start, s[1].stop) for s in ndi.find_objects(lab) if s is not None]
    merged = True
    while merged:
        merged = False
        for a in range(len(boxes)):
            for b in range(a + 1, len(boxes)):
                p, q = boxes[a], boxes[b]
                if p[0] < q[1] and q[0] < p[1] and p[2] < q[3] and q[2] < p[3]:
                    boxes[a] = (min(p[0], q[0]), max(p[1], q[1]), min(p[2], q[2]), max(p[3], q[3]))
                    del boxes[b]
                    merged = True
                    break
            if merged:
                break
    return boxes


def _cells(knots: Array, lo: float, hi: float, x: Array) -> tuple[Array, Array, Array]:
    """Distinct knots ``k`` of ``[lo, hi]``, the span index of each parameter (-1 outside) and
    the number of data parameters per span."""
    k = np.unique(knots[(knots >= lo) & (knots <= hi)])
    idx = np.searchsorted(k, x, side="right") - 1
    idx = np.where(x == k[-1], k.size - 2, idx)
    idx = np.where((x < k[0]) | (x > k[-1]), -1, idx)
    counts = np.bincount(idx[idx >= 0], minlength=k.size - 1)
    return k, idx, counts


def _owner(hs: HierarchicalSurface, u: Array, v: Array) -> tuple[list[Overlay | None], Array, Array]:
    """Per data row/column pair, the deepest node whose region holds it: returns the nodes and
    an (m, n) index into them (0 = the base)."""
    nodes: list[Overlay | None] = [None] + sorted(hs.overlays, key=lambda o: o.level)
    own = np.zeros((u.size, v.size), int)
    for k, ov in enumerate(nodes[1:], 1):
        (a, b), (c, d) = ov.region
        own[np.ix_((u >= a) & (u <= b), (v >= c) & (v <= d))] = k
    return nodes, own, np.array([0] + [o.level for o in nodes[1:]])


def _regions(hs: HierarchicalSurface, parent: Overlay | None, flagged: Array, u: Array, v: Array
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
    if not marks.any():
        return []
    margin = int(tolerances.FIT_ADAPTIVE_MARGIN)
    if margin > 0:
        marks = ndi.binary_dilation(marks, structure=np.ones((3, 3)), iterations=margin)
    return [((float(ku[i0]), float(ku[i1])), (float(kv[j0]), float(kv[j1]))) for i0, i1, j0, j1 in _boxes(marks)]


def _block(A: Array, D: Array, B: Array) -> Array:
    """``A D_k B^T`` per coordinate k: an overlay's share on its sub-grid, (rows, cols, 3)."""
    return np.stack([A @ D[..., k] @ B.T for k in range(D.shape[-1])], -1)


class _Fitter:
    """The hierarchy under construction with every overlay's world displacements ``δ`` kept, so
    that coarser levels can be refitted (backfitting) without losing the finer ones."""

    def __init__(self, hs: HierarchicalSurface, P3: Array, u: Array, v: Array, heights: bool, refit_base) -> None:
        self.hs, self.P3, self.u, self.v, self.heights = hs, P3, u, v, heights
        self.refit_base = refit_base
        self.delta: dict[int, Array] = {}
        self.ops: dict[int, tuple[Array, Array, Array, Array]] = {}

    def residual(self) -> Array:
        return self.P3 - self.hs.flatten().evaluate_grid(self.u, self.v)

    def _operators(self, ov: Overlay) -> tuple[Array, Array, Array, Array]:
        if ov.id not in self.ops:
            p, q = self.hs.degree
            (i0, i1), (j0, j1) = ov.vertices
            ku, kv = ov.knots
            su = (ku[i0], ku[min(i1 + p + 1, ku.shape[0] - 1)])
            sv = (kv[j0], kv[min(j1 + q + 1, kv.shape[0] - 1)])
            ru = np.flatnonzero((self.u >= su[0]) & (self.u <= su[1]))
            rv = np.flatnonzero((self.v >= sv[0]) & (self.v <= sv[1]))
            A = basis_matrix(ku, p, ku.shape[0] - p - 1, self.u[ru])[0][:, i0:i1 + 1]
            B = basis_matrix(kv, q, kv.shape[0] - q - 1, self.v[rv])[0][:, j0:j1 + 1]
            self.ops[ov.id] = (ru, rv, A, B)
        return self.ops[ov.id]

    def _apply(self, ov: Overlay) -> None:
        frames = self.hs.reference_frames(ov)
        d = self.delta[ov.id]
        off = self.hs.offset_mapping.inverse(d.reshape(-1, 3), None if frames is None else frames.reshape(-1, 3, 3))
        self.hs.set_offsets(ov, np.asarray(off, float).reshape(d.shape))

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

    def backfit(self) -> Array:
        """One block Gauss-Seidel sweep: the base against the data minus every overlay's share,
        the displacements re-applied in the new frames, then each overlay against what is left."""
        hs = self.hs
        share = hs.flatten().evaluate_grid(self.u, self.v) - hs.base.evaluate_grid(self.u, self.v)
        hs.set_base(self.refit_base(self.P3 - share))
        for ov in hs.overlays:  # parents first: each sees its parent's new frames
            self._apply(ov)
        resid = self.residual()
        for ov in hs.overlays:
            self.fit_overlay(ov, resid)
        return self.residual()


def _level_reports(hs: HierarchicalSurface, P3: Array, u: Array, v: Array
                   ) -> tuple[list[LevelReport], list[BSplineSurface], list[Array]]:
    """Per level L, the surface truncated below L (finer offsets zeroed) measured against the data:
    the reports, the truncated flat surfaces and their distance arrays."""
    out, surfs, dists = [], [], []
    depth = hs.depth
    for L in range(depth + 1):
        h = hs.copy()
        for ov in sorted(h.overlays, key=lambda o: -o.level):
            if ov.level > L:
                h.set_offsets(ov, np.zeros(ov.shape + (3,)))
        flat = h.flatten()
        dist = measure_grid(flat, P3, u, v)
        ovs = [o for o in hs.overlays if o.level == L]
        cps = int(np.prod(hs.base.n_poles)) if L == 0 else sum(int(np.prod(o.shape)) for o in ovs)
        out.append(LevelReport(L, len(ovs), cps, *_stats(dist)))
        surfs.append(flat)
        dists.append(dist)
    return out, surfs, dists


def _grow_base(Q: Array, heights: bool, poles: tuple[int, int], deg: tuple[int, int], tol: float, opts: dict,
               progress) -> tuple[GridFit, Array, Array]:
    """The base fit, its spans multiplied by 1.5 while the places to refine cover more than
    :data:`~occsurf.algorithms.tolerances.FIT_ADAPTIVE_MAX_COVER` of it (when the error is
    everywhere, uniform refinement is the cheaper hierarchy: no overlay overhead).

    Each step grows u, v or both, whichever lowers the error most per added pole (the largest
    ``-log(e_new / e) / log(n_new / n)``; both when none gains 0.1): data that vary along one
    direction only (a ruled or extruded face) do not pay for poles along the other. The candidates
    are compared by the first-order distance :func:`normal_deviation` (cheap); the base chosen is
    measured by projection (:func:`measure_grid`, points within ``tol`` at their parameters
    skipped), which decides whether to grow further.
    """
    m, n = Q.shape[:2]
    data = Q[..., 0] if heights else Q

    def candidate(poles_):
        base_ = fit_grid(data, poles_, deg, **opts)
        u_, v_ = base_.u_params, base_.v_params
        P3_ = np.stack(np.broadcast_arrays(u_[:, None], v_[None, :], Q[..., 0]), -1) if heights else Q
        est = normal_deviation(base_.surface, P3_, u_, v_)
        return base_, P3_, float(np.nanmax(boundary_error(base_.surface, P3_, u_, v_, est)))

    def measured(base_, P3_):
        u_, v_ = base_.u_params, base_.v_params
        dist_ = measure_grid(base_.surface, P3_, u_, v_, above=tol)
        return dist_, float(np.nanmax(boundary_error(base_.surface, P3_, u_, v_, dist_)))

    base, P3, estimate = candidate(poles)
    while True:
        dist, worst = measured(base, P3)
        if progress is not None:
            progress(f"base {poles[0]}x{poles[1]}: max error {worst:.3g}")
        if worst <= tol:
            return base, P3, dist
        flagged = boundary_error(base.surface, P3, base.u_params, base.v_params, dist) > \
            max(tol, float(tolerances.FIT_ADAPTIVE_GREED) * worst)
        hs = HierarchicalSurface(base.surface, "frame")
        boxes = _regions(hs, None, flagged, base.u_params, base.v_params)
        (u0, u1), (v0, v1) = hs.domain
        cover = sum((b - a) * (d - c) for (a, b), (c, d) in boxes) / ((u1 - u0) * (v1 - v0))
        grown = [min(p + int(np.ceil(1.5 * (k - p))), cnt) for k, p, cnt in zip(poles, deg, (m, n))]
        options = {tuple(grown), (grown[0], poles[1]), (poles[0], grown[1])} - {tuple(poles)}
        if cover <= float(tolerances.FIT_ADAPTIVE_MAX_COVER) or not options:
            return base, P3, dist
        best, score, tried = None, np.inf, {}
        for cand in sorted(options):
            trial = tried[cand] = candidate(cand)
            gain = np.log(max(trial[2], 1e-300) / max(estimate, 1e-300)) / np.log(np.prod(cand) / np.prod(poles))
            if gain < score:
                best, score = (cand, trial), gain
        if score > -0.1 and tuple(grown) in tried:  # no direction helps on its own yet: grow both
            best = (tuple(grown), tried[tuple(grown)])
        poles, (base, P3, estimate) = best


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
    try:
        tol = float(tol)
    except (TypeError, ValueError) as err:
        raise ParameterError(f"tol: expected a positive number, got {tol!r}") from err
    if not (np.isfinite(tol) and tol > 0):
        raise ParameterError(f"tol: expected a positive number, got {tol!r}")
    depth_max = int(tolerances.FIT_ADAPTIVE_MAX_LEVELS) if max_levels is None else int(max_levels)
    if depth_max < 0:
        raise ParameterError(f"max_levels: expected an integer >= 0, got {max_levels!r}")
    Q, heights, xs, ys = _grid_data(data, x, y)
    m, n = Q.shape[:2]
    if not heights and Q.shape[2] != 3:
        raise InvalidGeometryError(f"data: adaptive fitting needs 3-D points or heights, got {Q.shape[2]}-D points")
    pu, pv = _pair_of(degree, "degree")
    if base_poles is None:
        base_poles = (min(pu + 5, m), min(pv + 5, n))
    opts = dict(x=xs if heights else None, y=ys if heights else None, u_params=u_params, v_params=v_params,
                method=method, smoothing=smoothing, fix_boundary=fix_boundary)
    base, P3, dist = _grow_base(Q, heights, _pair_of(base_poles, "base_poles"), (pu, pv), tol, opts, progress)
    u, v = base.u_params, base.v_params
    knots = base.surface.knots

    def refit_base(target: Array):
        data_ = target[..., 2] if heights else target
        o = dict(opts, u_params=u, v_params=v, x=None, y=None)
        return fit_grid(data_, base.surface.n_poles, (pu, pv), knots=knots, **o).surface

    hs = HierarchicalSurface(base.surface, "frame")
    fitter = _Fitter(hs, P3, u, v, heights, refit_base)
    for rnd in range(1, int(tolerances.FIT_ADAPTIVE_MAX_ROUNDS) + 1):
        err = boundary_error(hs.flatten(), P3, u, v, dist)
        worst = float(np.nanmax(err))
        if worst <= tol:
            break
        flagged = err > max(tol, float(tolerances.FIT_ADAPTIVE_GREED) * worst)
        nodes, own, lv = _owner(hs, u, v)
        resid = fitter.residual()
        new = []
        for k, node in enumerate(nodes):
            if lv[k] >= depth_max:
                continue
            mine = flagged & (own == k)
            if not mine.any():
                continue
            for ur, vr in _regions(hs, node, mine, u, v):
                ov = hs.add_overlay(ur, vr, node)
                fitter.fit_overlay(ov, resid)
                new.append(ov)
        if not new:
            break
        for _ in range(int(tolerances.FIT_ADAPTIVE_SWEEPS)):
            fitter.backfit()
        dist = measure_grid(hs.flatten(), P3, u, v, above=tol)
        if progress is not None:
            progress(f"round {rnd}: {len(new)} overlays added (depth {hs.depth}), "
                     f"{hs.pole_counts()['stored']} control points, max error {np.nanmax(dist):.3g}")
    reports, surfs, dists = _level_reports(hs, P3, u, v)
    border = float(np.nanmax(boundary_error(surfs[-1], P3, u, v, dists[-1])))
    return AdaptiveFit(hs, tuple(reports), dists[-1], u, v, tol, border <= tol, tuple(surfs), tuple(dists))
