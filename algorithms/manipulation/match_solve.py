"""The conditions of a match and their minimum-norm solution (:func:`.matching.match_surface`;
course ch. 3-4).

At samples ``v`` of the side ``u = u0`` of a surface in the canonical orientation of
:mod:`.matching`, :func:`_cross_rows` gives the cross derivatives' rows over the first pole rows,
:func:`_equations` the G0..G3 conditions' residuals and Jacobian against the target's jets (the
table in :mod:`.matching`), and :func:`min_norm_change` the least change of those pole rows that meets them:
row by row, each by its minimum-norm correction, then for G2 and G3 Gauss-Newton steps on the rows
together, the smaller change kept.
"""

from __future__ import annotations

from math import comb
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from .. import tolerances
from ..kernel.basis import basis_derivatives, find_span
from ..kernel.surface import BSplineSurface
from .match_targets import Jets
from .min_norm import RowSVD, robust_min_norm, row_svd

__all__ = ["JetSource", "min_norm_change"]

Array = NDArray[np.float64]


class JetSource(Protocol):
    """A target side that gives its jets at the points corresponding to a surface's side samples."""

    def corresponding(self, X: BSplineSurface, v: Array) -> Jets: ...


def _cross_rows(S: BSplineSurface, v: Array, r: int) -> Array:
    """Rows of the cross derivatives ``d^j S / du^j (u0, v_k)``, ``j <= r``, over the first ``r + 1``
    pole rows flattened: shape ``(r + 1, m, (r + 1) * n_v)`` (quotient rule at fixed weights)."""
    (p, q), (U, Vk), (nu, nv) = S.degree, S.knots, S.n_poles
    u0 = np.array([U[p]])
    su = find_span(U, p, nu, u0)
    Du = basis_derivatives(U, p, su, u0, r)[0]  # (r+1, p+1): clamped, only the first j+1 are non-zero
    Nu = Du[:, : r + 1]
    m = v.shape[0]
    sv = find_span(Vk, q, nv, v)
    Bv = basis_derivatives(Vk, q, sv, v, 0)[:, 0, :]
    Nv = np.zeros((m, nv))
    Nv[np.arange(m)[:, None], sv[:, None] - q + np.arange(q + 1)] = Bv
    A = Nu[:, None, :, None] * Nv[None, :, None, :]  # (r+1, m, r+1, nv)
    if S.weights is not None:
        Aw = A * S.weights[None, None, : r + 1, :]
        w = Aw.sum(axis=(2, 3))  # (r+1, m)
        R = np.empty_like(A)
        for j in range(r + 1):
            acc = Aw[j].copy()
            for i in range(1, j + 1):
                acc -= comb(j, i) * w[i][:, None, None] * R[j - i]
            R[j] = acc / w[0][:, None, None]
        A = R
    return A.reshape(r + 1, m, (r + 1) * nv)


def _equations(R: Array, Sj: Array, tg: Jets, r: int, lo: int = 0, poles: slice = slice(None)
               ) -> tuple[Array, Array]:
    """Residuals ``F`` and Jacobian ``J`` of the G``lo``..G``r`` conditions, ``J``'s columns those of
    the poles ``poles`` (a slice of ``R``'s last axis, three columns a pole).

    With ``lo = 0`` and every pole these are all the conditions' rows, shape ``(n_eq,)`` and
    ``(n_eq, n_poles * 3)``; a caller that solves for some pole rows under some orders asks for
    just those (:func:`min_norm_change`): each entry is the same product either way, so the block is the
    same as slicing the whole, bit for bit, without building the G0 block (``3 m`` rows, the
    largest) and the columns it then drops."""
    Rp = R[..., poles]
    m, n = Rp.shape[1], Rp.shape[2]
    F: list[Array] = []
    J: list[Array] = []
    N, E = tg.N, tg.E

    def rows(terms: list[tuple[int, Array]]) -> Array:
        return sum(np.einsum("ki,kc->kic", Rp[j], g) for j, g in terms).reshape(m, 3 * n)

    if lo <= 0:
        F.append((Sj[0] - tg.P).ravel())
        J.append(np.einsum("ki,cd->kcid", Rp[0], np.eye(3)).reshape(3 * m, 3 * n))
    if lo <= 1 <= r:
        F.append(np.einsum("kc,kc->k", N, Sj[1]))
        J.append(rows([(1, N)]))
    if r >= 2:
        assert tg.H2 is not None
        xi1 = np.einsum("kac,kc->ka", E, Sj[1])
        Hx1 = np.einsum("kab,kb->ka", tg.H2, xi1)
    if lo <= 2 <= r:
        F.append(np.einsum("kc,kc->k", N, Sj[2]) - np.einsum("ka,ka->k", Hx1, xi1))
        J.append(rows([(2, N), (1, -2.0 * np.einsum("ka,kac->kc", Hx1, E))]))
    if r >= 3:
        assert tg.H2 is not None and tg.H3 is not None
        xi2 = np.einsum("kac,kc->ka", E, Sj[2])
        H3x = np.einsum("kabc,ka,kb->kc", tg.H3, xi1, xi1)
        Hx2 = np.einsum("kab,kb->ka", tg.H2, xi2)
        F.append(np.einsum("kc,kc->k", N, Sj[3]) - np.einsum("kc,kc->k", H3x, xi1)
                 - 3.0 * np.einsum("ka,ka->k", Hx1, xi2))
        J.append(rows([(3, N), (1, -3.0 * np.einsum("ka,kac->kc", H3x + Hx2, E)),
                       (2, -3.0 * np.einsum("ka,kac->kc", Hx1, E))]))
    return np.concatenate(F), np.concatenate(J)


def min_norm_change(S: BSplineSurface, target: JetSource, r: int, v: Array, size: float) -> Array:
    """Minimum-norm change of the first ``r + 1`` pole rows, shape ``(r + 1, n_v, 3)``.

    The target's jets are taken once, at the points that correspond to the side's samples ``v``
    (:meth:`SurfaceSide.corresponding`). Order ``j``'s conditions are linear in row ``j`` once the
    rows below are known, so a first solution takes the rows in turn, each by its minimum-norm
    change (for G0 and G1 it is already the joint minimum-norm change when the rows below are
    determined by their conditions). For G2 and G3, at most ``tolerances.MATCH_MAX_ITERATIONS``
    Gauss-Newton steps ``x <- pinv(J) (J x - F)`` on rows 1..r at once (row 0 is fixed by G0 alone)
    aim at the rows' joint minimum-norm change; the rows are then solved in turn from where the steps
    stopped (the conditions exactly), and that result is kept only if it is smaller than the first.
    On real matches the steps seldom converge (the OCCT bearing's repair: 27 of 231 captured G2
    solves within 10 steps, 39 within 60; the steps keep bouncing at ~1e-2 of the model's size
    rather than shrinking; ``docs/guide/18_speed.md``), so the change returned is the smaller of the
    two row-by-row solutions, not in general the joint minimum-norm change."""
    R = _cross_rows(S, v, r)
    tg = target.corresponding(S, v)
    nv = S.n_poles[1]
    P0 = S.control_points[: r + 1].reshape(-1, 3)

    def residual(x: Array, j: int = r, lo: int = 0, poles: slice = slice(None)) -> tuple[Array, Array]:
        """Order ``lo``..``j``'s residuals and their Jacobian in the columns of ``poles``."""
        Sj = np.einsum("jki,ic->jkc", R[: j + 1], P0 + x.reshape(P0.shape))
        return _equations(R[: j + 1], Sj, tg, j, lo, poles)

    # G0's matrix (row 0's basis values) and G1's for row 1 (the target's normals times row 1's
    # derivative values) do not depend on the poles: their SVDs serve both passes of rowwise
    A0 = R[0][:, :nv]
    svd0 = row_svd(A0)
    svd1: list[RowSVD] = []  # row 1's, from its first pass

    def rowwise(x: Array) -> Array:
        """Row j's minimum-norm correction for order j's conditions, j = 0..r in turn."""
        x = x.copy()
        # G0 alone: the same conditions for each coordinate, one solve with three right-hand sides
        Sj = np.einsum("ki,ic->kc", R[0], P0 + x.reshape(P0.shape))
        x[: 3 * nv] += robust_min_norm(A0, -(Sj - tg.P), svd0).ravel()
        for j in range(1, r + 1):
            F, J = residual(x, j, j, slice(j * nv, (j + 1) * nv))  # order j's rows, row j's columns
            if j == 1 and not svd1:
                svd1.append(row_svd(J))
            x[3 * j * nv: 3 * (j + 1) * nv] += robust_min_norm(J, -F, svd1[0] if j == 1 else None)
        return x

    x = rowwise(np.zeros(P0.size))
    if r >= 2:
        # row 0 is fixed by G0 alone (its change is already the least one): the steps move rows
        # 1..r under the conditions of orders 1..r only, a third smaller system
        y = x.copy()
        cols = slice(3 * nv, None)
        for _ in range(tolerances.MATCH_MAX_ITERATIONS):
            F, Jr = residual(y, r, 1, slice(nv, None))  # orders 1..r, rows 1..r
            z = robust_min_norm(Jr, Jr @ y[cols] - F)
            step = float(np.max(np.abs(z - y[cols])))
            y[cols] = z
            if step <= 1e-12 * size:
                break
        y = rowwise(y)  # the conditions exactly again where the steps stopped short
        if np.linalg.norm(y) < np.linalg.norm(x):
            x = y
    return x.reshape(r + 1, nv, 3)
