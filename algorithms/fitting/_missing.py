"""Gridded fits with missing cells (course §7-7): one sparse system, and its GCV (course ch. 7).

NaN cells break the Kronecker structure of :mod:`.gridded`: the problem is solved over the valid
cells as one sparse system (SuperLU), with the constraints as a KKT block. The smoothing term is
the gridded path's own, ``λ (R_u ⊗ G_v + G_u ⊗ R_v)`` with ``G`` the Gram matrices of the complete
grid and ``R = c D^T D`` scaled as there, so λ means the same with and without missing cells and a
grid without a missing cell gives the Kronecker path's solution. The penalty keeps the poles over
a hole defined (their second differences are minimised).

Generalised cross-validation
----------------------------
The fit is an affine smoother of the valid data ``y`` (``nobs`` values): ``f = H y + const`` with
the influence matrix ``H = K M K^T``, ``K`` the collocation rows of the valid cells (per
coordinate) and ``M`` the leading block of the inverse KKT matrix (``N^{-1}`` without
constraints, ``N = K^T K + λ P``). ``GCV(λ) = nobs RSS / (nobs - tr H)^2`` (Craven and Wahba
1979). ``tr H = tr(M K^T K)`` is computed exactly (one multi-right-hand-side solve with the
columns of ``K^T K``) while the unknowns number at most
:data:`~occsurf.algorithms.tolerances.FIT_GCV_EXACT_TRACE`, else estimated by Hutchinson's
method with :data:`~occsurf.algorithms.tolerances.FIT_GCV_PROBES` Rademacher probes in data
space, ``tr H ≈ mean z^T K M K^T z`` (one solve each; ``H`` is symmetric with eigenvalues in
[0, 1], so the estimate's standard deviation is at most ``sqrt(2 tr H / probes)``). The probes
are the same for every λ, so the score is a smooth function of λ.

References
----------
P. Craven, G. Wahba, "Smoothing noisy data with spline functions", Numer. Math. 31 (1979) 377-403;
M. F. Hutchinson, "A stochastic estimator of the trace of the influence matrix for Laplacian
smoothing splines", Comm. Statist. Simul. Comput. 19 (1990) 433-450.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from numpy.typing import NDArray

from .. import tolerances
from ..errors import InvalidGeometryError
from ..manipulation.linalg import ConstraintError
from ._common import difference_penalty

if TYPE_CHECKING:
    from .grid_constraints import Rows

__all__ = ["SparseGrid", "sparse_rows", "kronecker_penalty"]

Array = NDArray[np.float64]


def kronecker_penalty(A: Array, B: Array) -> sp.csr_matrix:
    """``R_u ⊗ G_v + G_u ⊗ R_v`` on ``vec(P)`` (index ``i N_v + j``), ``G = A^T A`` of the complete
    grid, ``R = trace(G) / (2 trace(D^T D)) D^T D`` (second differences): the smoothing term of
    :class:`~.gridded._Direction`, whose λ = 1 weighs data and penalty alike."""
    mats = []
    for M in (A, B):
        G = M.T @ M
        D = difference_penalty(M.shape[1], 2)
        tr = float(np.trace(D))
        R = (np.trace(G) / (2.0 * tr)) * D if tr > 0 else np.zeros_like(D)
        mats.append((sp.csr_matrix(G), sp.csr_matrix(R)))
    (Gu, Ru), (Gv, Rv) = mats
    return (sp.kron(Ru, Gv) + sp.kron(Gu, Rv)).tocsr()


def sparse_rows(rows: Rows, Nu: int, Nv: int, d: int) -> tuple[sp.csr_matrix, Array, list[str]]:
    """Every constraint as sparse rows on the stacked vector ``[vec(P_0), ..., vec(P_{d-1})]``."""
    blocks: list[sp.csr_matrix] = []
    targets: list[Array] = []
    labels: list[str] = []
    size = Nu * Nv
    seen: dict[tuple[int, int, int], float] = {}

    def place(M: sp.spmatrix, c: int) -> sp.csr_matrix:
        return sp.hstack([sp.csr_matrix((M.shape[0], size * c)), M, sp.csr_matrix((M.shape[0], size * (d - c - 1)))],
                         format="csr")

    for c in range(d):
        for ax, items in ((0, rows.cu[c]), (1, rows.cv[c])):
            for e, tgt in items:
                unit = np.count_nonzero(e) == 1
                other = Nv if ax == 0 else Nu
                keep = np.ones(other, bool)
                if unit:  # a fixed pole row/column: drop poles already fixed (corners), checking they agree
                    i = int(np.flatnonzero(e)[0])
                    for j in range(other):
                        key = (c, i, j) if ax == 0 else (c, j, i)
                        if key in seen:
                            keep[j] = False
                            if abs(seen[key] - tgt[j]) > tolerances.CONSISTENCY_RTOL * max(1.0, abs(tgt[j])):
                                raise ConstraintError("constraints: the u-side and v-side constraints disagree at a "
                                                      f"corner by {abs(seen[key] - tgt[j]):.3g}")
                        else:
                            seen[key] = float(tgt[j])
                M = sp.kron(sp.csr_matrix(e[None, :]), sp.identity(Nv)) if ax == 0 else \
                    sp.kron(sp.identity(Nu), sp.csr_matrix(e[None, :]))
                blocks.append(place(sp.csr_matrix(M)[keep], c))
                targets.append(tgt[keep])
                labels += [f"separable row (coordinate {c})"] * int(keep.sum())
    for a, b, w, t, lab in zip(rows.alpha, rows.beta, rows.w, rows.target, rows.labels):
        row = sp.csr_matrix(np.kron(a, b)[None, :])
        blocks.append(sp.hstack([row * w[c] for c in range(d)], format="csr"))
        targets.append(np.array([t]))
        labels.append(lab)
    if not blocks:
        return sp.csr_matrix((0, d * size)), np.zeros(0), []
    return sp.vstack(blocks, format="csr"), np.concatenate(targets), labels


class SparseGrid:
    """The missing-data problem of one grid: solve for a λ, and score λ by GCV (module notes).

    Parameters
    ----------
    A, B : ndarray, shapes (m, N_u), (n, N_v)
        Collocation matrices of the complete grid.
    Q : ndarray, shape (m, n, d)
        Data, NaN on missing cells.
    rows : grid_constraints.Rows
        The constraints.
    """

    def __init__(self, A: Array, B: Array, Q: Array, rows: Rows) -> None:
        m, n, d = Q.shape
        self.valid = ~np.isnan(Q).any(axis=2)
        if not self.valid.any():
            raise InvalidGeometryError("data: every cell is missing (NaN)")
        self.Nu, self.Nv, self.d = A.shape[1], B.shape[1], d
        self.K = sp.kron(sp.csr_matrix(A), sp.csr_matrix(B), format="csr")[self.valid.ravel()]
        self.G = (self.K.T @ self.K).tocsr()
        self.pen = kronecker_penalty(A, B)
        self.y = Q[self.valid]  # (nvalid, d)
        self.rhs = np.concatenate([self.K.T @ self.y[:, c] for c in range(d)])
        self.C, self.t, self.labels = sparse_rows(rows, self.Nu, self.Nv, d)
        self.scale = max(1.0, float(np.abs(self.t).max())) if self.t.size else 1.0

    @property
    def unknowns(self) -> int:
        return self.d * self.Nu * self.Nv

    def _factor(self, lam: float) -> spla.SuperLU:
        N1 = (self.G + lam * self.pen).tocsc()
        if not self.C.shape[0]:
            return spla.splu(N1)
        N = sp.block_diag([N1] * self.d, format="csc")
        return spla.splu(sp.bmat([[N, self.C.T], [self.C, None]], format="csc"))

    def _solve(self, lu: spla.SuperLU, rhs: Array) -> Array:
        """Pole-space part of the solution for stacked right-hand sides ``rhs`` (d N_u N_v, ...)."""
        n1 = self.Nu * self.Nv
        if not self.C.shape[0]:
            parts = rhs.reshape((self.d, n1) + rhs.shape[1:])
            return np.concatenate([lu.solve(np.ascontiguousarray(p)) for p in parts])
        pad = np.zeros((self.C.shape[0],) + rhs.shape[1:])
        full = np.concatenate([rhs, pad + (self.t if rhs.ndim == 1 else 0.0)])
        return lu.solve(full)[: self.unknowns]

    def solve(self, lam: float) -> Array:
        """The poles ``(N_u, N_v, d)`` at smoothing λ (every constraint checked)."""
        try:
            lu = self._factor(lam)
            x = self._solve(lu, self.rhs)
        except RuntimeError as err:
            raise ConstraintError("data: with the missing cells the fit is singular: some poles have no data and the "
                                  f"constraints are dependent or no smoothing is given ({err})") from err
        if not np.all(np.isfinite(x)):
            raise InvalidGeometryError("data: the fit over the valid cells is singular; add smoothing")
        if self.C.shape[0]:
            res = np.abs(self.C @ x - self.t)
            bad = np.flatnonzero(res > tolerances.LINEAR_CHECK_RTOL * self.scale)
            if bad.size:
                raise ConstraintError(f"constraints: {', '.join(self.labels[i] for i in bad[:4])} are not met "
                                      f"(residual {res.max():.3g}); they conflict", bad, [self.labels[i] for i in bad])
        return x.reshape(self.d, self.Nu, self.Nv).transpose(1, 2, 0)

    def _fitted(self, x: Array) -> Array:
        """``K P_c`` per coordinate, (nvalid, d) (x of shape (d N_u N_v,))."""
        n1 = self.Nu * self.Nv
        return np.stack([self.K @ x[c * n1:(c + 1) * n1] for c in range(self.d)], -1)

    def trace(self, lam: float, lu: spla.SuperLU | None = None) -> float:
        """``tr H`` of the influence matrix at λ: exact up to FIT_GCV_EXACT_TRACE unknowns, else
        Hutchinson's estimate (module notes)."""
        lu = self._factor(lam) if lu is None else lu
        n1 = self.Nu * self.Nv
        homog = self.C.shape[0] == 0  # without constraints the coordinates are independent and alike
        size = n1 if homog else self.unknowns
        if size <= int(tolerances.FIT_GCV_EXACT_TRACE):
            if homog:
                return self.d * float(np.trace(lu.solve(self.G.toarray())))
            Gd = sp.block_diag([self.G] * self.d).toarray()
            X = self._solve_homogeneous(lu, Gd)
            return float(np.trace(X))
        probes = int(tolerances.FIT_GCV_PROBES)
        rng = np.random.default_rng(0)
        nval = self.y.shape[0]
        ncoord = 1 if homog else self.d
        Z = rng.choice([-1.0, 1.0], size=(ncoord * nval, probes))
        R = np.concatenate([self.K.T @ Z[c * nval:(c + 1) * nval] for c in range(ncoord)])
        X = lu.solve(R) if homog else self._solve_homogeneous(lu, R)
        KX = np.concatenate([self.K @ X[c * n1:(c + 1) * n1] for c in range(ncoord)])
        est = float(np.mean(np.sum(Z * KX, axis=0)))
        return self.d * est if homog else est

    def _solve_homogeneous(self, lu: spla.SuperLU, rhs: Array) -> Array:
        """The KKT solve with zero constraint targets (the influence of the data alone)."""
        pad = np.zeros((self.C.shape[0], rhs.shape[1]))
        return lu.solve(np.concatenate([rhs, pad]))[: self.unknowns]

    def gcv(self, lam: float) -> float:
        """``nobs RSS / (nobs - tr H)^2`` over the valid cells (inf where the system is singular)."""
        try:
            lu = self._factor(lam)
            x = self._solve(lu, self.rhs)
            tr = self.trace(lam, lu)
        except RuntimeError:
            return float("inf")
        if not np.all(np.isfinite(x)):
            return float("inf")
        rss = float(np.sum((self._fitted(x) - self.y) ** 2))
        nobs = self.y.size
        return nobs * rss / max(nobs - tr, 1e-300) ** 2
