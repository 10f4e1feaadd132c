"""Computational linear algebra for spline manipulation and fitting (course ch. 3).

Everything here is orthogonal-transformation based and runs on LAPACK through SciPy: the
"fundamental transformations" of course §3-5 are Householder reflections, and the "reduction to
triangular form" of §3-9 is a QR factorisation with column pivoting (``?geqp3``), which also
reveals the rank. No Gaussian elimination is written by hand.

* :func:`lstsq`: ``min ||W^(1/2) (A x - b)||``, minimum-norm when ``A`` is rank deficient;
* :func:`min_norm_solve`: the shortest ``x`` with ``C x = d`` (course §4-4), conflicts reported;
* :class:`ConstraintFactor`: the pivoted QR of ``C^T`` behind it, factored once and reused (§4-6);
* :func:`constrained_lstsq`: ``min ||W^(1/2) (A x - b)||`` subject to ``C x = d`` by the
  null-space method (§3-12).

The sparse forms (LSMR, the augmented and KKT systems by SuperLU) are in :mod:`.sparse_linalg`, the
argument checks both share in :mod:`.linalg_args`.

Rank and consistency
--------------------
The constraint rows are first *equilibrated* (each row of ``C`` and its entry of ``d`` divided by
the row's Euclidean norm: the solution set is unchanged, and rows measured in different units, such
as positions and second derivatives of a spline, become comparable). Then ``C^T P = Q R`` with
column pivoting; the rank is the number of diagonal entries of ``R`` above
``tolerances.RANK_RTOL * |R[0, 0]|``. A row that is not among the first ``rank`` pivots is a
combination of those that are; if its target disagrees with the same combination of their targets
by more than ``tolerances.CONSISTENCY_RTOL`` (relative), the system is inconsistent and
:class:`ConstraintError` names the row and the rows it depends on. Consistent redundant rows are simply dropped.

References
----------
R. Bartels, course notes C25 (SIGGRAPH 1991), ch. 3 "Computational linear algebra" (§3-9
reduction to triangular form, §3-12 constrained equation systems) and §4-4 "Solving underdetermined
systems of equations". G. H. Golub, C. F. Van Loan, *Matrix Computations*, 4th ed., §5.4-5.6 and
§6.2 (the null-space method for LSE). Å. Björck, *Numerical Methods for Least Squares Problems*,
SIAM 1996, §5.1 (LSE).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import NamedTuple

import numpy as np
import scipy.linalg as sla
from numpy.typing import ArrayLike, NDArray

from .. import tolerances
from ..errors import InvalidGeometryError, ToleranceError
from .linalg_args import (
    constrained_system,
    dense_matrix,
    per_row,
    right_hand_side,
    row_labels,
    row_weights,
    weighted_rows,
)

__all__ = [
    "ConstraintError",
    "ConvergenceError",
    "LstsqResult",
    "lstsq",
    "ConstraintFactor",
    "min_norm_solve",
    "constrained_lstsq",
]

Array = NDArray[np.float64]


class ConstraintError(InvalidGeometryError):
    """Constraints that cannot all hold: inconsistent (conflicting) or too many for the unknowns.

    Attributes
    ----------
    rows : tuple of int
        Indices of the rows (constraints) involved in the conflict.
    labels : tuple of str
        Their labels (``"row 3"`` when the caller gave none).
    """

    def __init__(self, message: str, rows: Iterable[int] = (), labels: Sequence[str] = ()) -> None:
        super().__init__(message)
        self.rows = tuple(int(r) for r in rows)
        self.labels = tuple(labels)


class ConvergenceError(ToleranceError):
    """An iterative method stopped before meeting its tolerance; nothing is returned."""


class LstsqResult(NamedTuple):
    """Result of :func:`lstsq`.

    Attributes
    ----------
    x : ndarray, shape (n,) or (n, k)
    residual : ndarray, shape () or (k,)
        ``||W^(1/2) (A x - b)||`` per right-hand side.
    rank : int
        Numerical rank of ``W^(1/2) A``.
    """

    x: Array
    residual: Array
    rank: int


# ------------------------------------------------------------------------------ least squares
def lstsq(A: ArrayLike, b: ArrayLike, weights: ArrayLike | None = None, *, rcond: float | None = None) -> LstsqResult:
    """Weighted linear least squares, minimum-norm when ``A`` is rank deficient (course §3-9).

    .. math:: \\min_x \\; \\sum_i w_i \\,(a_i^T x - b_i)^2

    solved by LAPACK ``?gelsy``: QR with column pivoting of ``W^(1/2) A`` followed by a complete
    orthogonal factorisation, so that among all minimisers the shortest ``x`` is returned.

    Parameters
    ----------
    A : array_like, shape (m, n)
    b : array_like, shape (m,) or (m, k)
    weights : array_like, shape (m,), optional
        Positive row weights ``w_i`` (default 1).
    rcond : float, optional
        Relative cut-off for the rank (default: machine precision, as ``scipy.linalg.lstsq``).

    Returns
    -------
    LstsqResult
        ``x`` of shape ``(n,)`` or ``(n, k)``, the weighted residual norm, the numerical rank.

    Raises
    ------
    InvalidGeometryError
        Shapes that do not match, non-finite values, weights ``<= 0``.
    """
    A = dense_matrix(A, "A")
    b = right_hand_side(b, A.shape[0], "b")
    A, b = weighted_rows(A, b, row_weights(weights, A.shape[0], "weights"))
    if A.shape[1] == 0:
        x = np.zeros((0,) + b.shape[1:])
        return LstsqResult(x, np.linalg.norm(b, axis=0), 0)
    x, _, rank, _ = sla.lstsq(A, b, cond=rcond, lapack_driver="gelsy", check_finite=False)
    return LstsqResult(x, np.linalg.norm(A @ x - b, axis=0), int(rank))


# ------------------------------------------------------------------------------ constraints
class ConstraintFactor:
    """Rank-revealing factorisation of a constraint matrix ``C``, for minimum-norm solves.

    ``C`` is row-equilibrated and ``C^T P = Q R`` is computed once (LAPACK ``?geqp3``); each
    :meth:`solve` then costs two triangular solves and a product (course §4-6, "preprocessing"):

    .. math::

        x = Q_1 R_{11}^{-T} (P^T d)_{1:r}, \\qquad C x = d, \\quad \\|x\\| \\text{ minimal},

    where ``r`` is the numerical rank. :attr:`operator` is that map as one ``(n, m)`` matrix
    (the pseudo-inverse of ``C`` when ``C`` has full row rank).

    Parameters
    ----------
    C : array_like, shape (m, n)
        Constraint rows. Any ``m``: dependent rows are detected.
    labels : sequence of str, optional
        One name per row, used in error messages (default ``"row i"``).
    rank_rtol : float, optional
        Default :data:`~occsurf.algorithms.tolerances.RANK_RTOL`.
    full : bool
        Also compute an orthonormal basis of the null space of ``C`` (:attr:`null_basis`), as the
        null-space method of :func:`constrained_lstsq` needs.

    Attributes
    ----------
    rank : int
    independent : ndarray of int
        Rows kept (the first ``rank`` pivots), in pivot order.
    redundant : ndarray of int
        Rows found to be combinations of the independent ones.
    coefficients : ndarray, shape (m - rank, rank)
        ``C_eq[redundant[j]] = coefficients[j] @ C_eq[independent]`` (equilibrated rows).
    null_basis : ndarray, shape (n, n - rank) or None
    """

    def __init__(self, C: ArrayLike, labels: Sequence[str] | None = None, *, rank_rtol: float | None = None,
                 full: bool = False) -> None:
        C = dense_matrix(C, "C")
        m, n = C.shape
        self.shape = (m, n)
        self.labels = row_labels(labels, m)
        rtol = tolerances.RANK_RTOL if rank_rtol is None else float(rank_rtol)
        norms = np.linalg.norm(C, axis=1)
        self.row_scale = np.where(norms > 0, norms, 1.0)
        Ce = C / self.row_scale[:, None]
        self._Ce = Ce
        if m == 0 or n == 0 or not np.any(norms > 0):
            r = 0
            Q = np.eye(n)
            R = np.zeros((n, m))
            piv = np.arange(m)
        else:
            Q, R, piv = sla.qr(Ce.T, mode="full" if full else "economic", pivoting=True, check_finite=False)
            diag = np.abs(np.diag(R))
            r = int(np.count_nonzero(diag > rtol * diag[0]))
        self.rank = r
        self.independent = piv[:r]
        self.redundant = piv[r:]
        self._Q1 = np.ascontiguousarray(Q[:, :r])
        self._R11 = np.triu(R[:r, :r])
        if m - r:
            self.coefficients = sla.solve_triangular(self._R11, R[:r, r:], check_finite=False).T if r else np.zeros((m - r, 0))
        else:
            self.coefficients = np.zeros((0, r))
        self.null_basis = np.ascontiguousarray(Q[:, r:]) if full else None
        self._operator: Array | None = None

    @property
    def operator(self) -> Array:
        """``(n, m)`` matrix ``K`` with ``x = K d`` the minimum-norm solution for consistent ``d``.

        Columns of redundant rows are zero (their targets are implied by the others).
        """
        if self._operator is None:
            m, n = self.shape
            K = np.zeros((n, m))
            if self.rank:
                Rinv_T = sla.solve_triangular(self._R11.T, np.eye(self.rank), lower=True, check_finite=False)
                K[:, self.independent] = (self._Q1 @ Rinv_T) / self.row_scale[self.independent]
            self._operator = K
        return self._operator

    def inconsistency(self, d: ArrayLike) -> Array:
        """Per redundant row, how far its (equilibrated) target is from the combination of the
        independent rows' targets, shape ``(m - rank,)`` (max over right-hand sides)."""
        de = np.asarray(d, float)
        de = de / per_row(de, self.row_scale)
        if not self.redundant.size:
            return np.zeros(0)
        r = de[self.redundant] - self.coefficients @ de[self.independent]
        return np.abs(r).reshape(r.shape[0], -1).max(axis=1)

    def check(self, d: ArrayLike, tol: float | None = None) -> None:
        """Raise :class:`ConstraintError` if the redundant rows' targets disagree with the others.

        Parameters
        ----------
        d : array_like, shape (m,) or (m, k)
        tol : float, optional
            Absolute tolerance on the equilibrated residual; default
            :data:`~occsurf.algorithms.tolerances.CONSISTENCY_RTOL` times the largest equilibrated
            target times ``1 + max |coefficient row sum|``.
        """
        if not self.redundant.size:
            return
        de = np.asarray(d, float)
        de = de / per_row(de, self.row_scale)
        res = self.inconsistency(d)
        if tol is None:
            scale = float(np.abs(de).max()) if de.size else 0.0
            amp = 1.0 + np.abs(self.coefficients).sum(axis=1) if self.coefficients.size else np.ones(res.shape)
            tol_j = tolerances.CONSISTENCY_RTOL * max(scale, np.finfo(float).tiny) * amp
        else:
            tol_j = np.full(res.shape, float(tol))
        bad = np.nonzero(res > tol_j)[0]
        if not bad.size:
            return
        rows: list[int] = []
        parts: list[str] = []
        for j in bad:
            row = int(self.redundant[j])
            c = self.coefficients[j]
            big = np.abs(c) > 1e-8 * max(np.abs(c).max(), 1e-300) if c.size else np.zeros(0, bool)
            deps = [int(i) for i in self.independent[big]]
            rows.extend([row] + [i for i in deps if i not in rows])
            if deps:
                parts.append(f"{self.labels[row]} is a combination of {', '.join(self.labels[i] for i in deps)} "
                             f"but its target differs from theirs by {res[j]:.3g}")
            else:
                parts.append(f"{self.labels[row]} has no free unknown acting on it (zero row) but asks for a "
                             f"change of {res[j]:.3g}")
        rows = list(dict.fromkeys(rows))
        m, n = self.shape
        hint = f"; {m} conditions on {n} unknowns, of which only {self.rank} are independent"
        raise ConstraintError("conflicting constraints: " + "; ".join(parts) + hint,
                              rows, [self.labels[i] for i in rows])

    def solve(self, d: ArrayLike, *, check: bool = True, tol: float | None = None) -> Array:
        """Minimum-norm ``x`` with ``C x = d``.

        Parameters
        ----------
        d : array_like, shape (m,) or (m, k)
        check : bool
            Verify that redundant rows are consistent (else they are ignored).
        tol : float, optional
            See :meth:`check`.

        Returns
        -------
        ndarray, shape (n,) or (n, k)

        Raises
        ------
        ConstraintError
            Inconsistent constraints, naming the rows involved.
        """
        d = right_hand_side(d, self.shape[0], "d")
        if check:
            self.check(d, tol)
        n = self.shape[1]
        if self.rank == 0:
            return np.zeros((n,) + d.shape[1:])
        de = d / per_row(d, self.row_scale)
        y = sla.solve_triangular(self._R11.T, de[self.independent], lower=True, check_finite=False)
        return self._Q1 @ y


def min_norm_solve(C: ArrayLike, d: ArrayLike, weights: ArrayLike | None = None, *,
                   labels: Sequence[str] | None = None, tol: float | None = None) -> Array:
    """The minimum-norm solution of an underdetermined system ``C x = d`` (course §4-4).

    .. math:: \\min_x \\sum_j w_j x_j^2 \\quad \\text{subject to} \\quad C x = d

    Parameters
    ----------
    C : array_like, shape (m, n)
        Usually ``m < n``. Redundant consistent rows are allowed.
    d : array_like, shape (m,) or (m, k)
    weights : array_like, shape (n,), optional
        Positive weights of the unknowns; a heavy unknown moves little.
    labels : sequence of str, optional
        Row names for error messages.
    tol : float, optional
        Consistency tolerance, see :meth:`ConstraintFactor.check`.

    Returns
    -------
    ndarray, shape (n,) or (n, k)

    Raises
    ------
    ConstraintError
        Conflicting rows (named), or more independent conditions than unknowns.
    """
    C = dense_matrix(C, "C")
    d = right_hand_side(d, C.shape[0], "d")
    w = row_weights(weights, C.shape[1], "weights")
    if w is None:
        return ConstraintFactor(C, labels).solve(d, tol=tol)
    s = 1.0 / np.sqrt(w)
    y = ConstraintFactor(C * s, labels).solve(d, tol=tol)
    return y * per_row(y, s)


def constrained_lstsq(A: ArrayLike, b: ArrayLike, C: ArrayLike, d: ArrayLike, weights: ArrayLike | None = None, *,
                      labels: Sequence[str] | None = None, tol: float | None = None,
                      rcond: float | None = None) -> Array:
    """Equality-constrained least squares by the null-space method (course §3-12).

    .. math::

        \\min_x \\|W^{1/2}(A x - b)\\| \\quad \\text{subject to} \\quad C x = d

    With ``C^T P = [Q_1\\ Q_2] R`` (pivoted QR), every solution of the constraints is
    ``x = x_c + Q_2 z`` where ``x_c = Q_1 R_{11}^{-T} (P^T d)_{1:r}`` is the minimum-norm one; ``z``
    solves the unconstrained problem ``min ||W^(1/2)(A Q_2 z - (b - A x_c))||`` (minimum-norm via
    ``?gelsy`` when ``A Q_2`` is rank deficient). Because ``x_c ⟂ range(Q_2)``, the result is also
    the shortest ``x`` among all constrained minimisers.

    Parameters
    ----------
    A : array_like, shape (p, n)
    b : array_like, shape (p,) or (p, k)
    C : array_like, shape (m, n)
    d : array_like, shape (m,) or (m, k)
        Same number of columns as ``b`` if both are 2-D.
    weights : array_like, shape (p,), optional
        Positive weights of the rows of ``A``.
    labels : sequence of str, optional
        Names of the rows of ``C`` for error messages.
    tol : float, optional
        Consistency tolerance of the constraints, see :meth:`ConstraintFactor.check`.
    rcond : float, optional
        Rank cut-off of the reduced least-squares problem (default machine precision).

    Returns
    -------
    ndarray, shape (n,) or (n, k)

    Raises
    ------
    ConstraintError
        The constraints conflict (rows named) or are more than the unknowns allow.
    InvalidGeometryError
        Shapes or values that do not fit.
    """
    Am, bv, Cm, dv, w = constrained_system(A, b, C, d, weights, dense_matrix)
    F = ConstraintFactor(Cm, labels, full=True)
    xc = F.solve(dv, tol=tol)
    Z = F.null_basis
    if Z is None or Z.shape[1] == 0 or Am.shape[0] == 0:
        return xc
    r = bv - Am @ xc
    z = lstsq(Am @ Z, r, w, rcond=rcond).x
    return xc + Z @ z
