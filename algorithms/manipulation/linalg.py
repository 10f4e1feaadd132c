"""Computational linear algebra for spline manipulation and fitting (course ch. 3).

Everything here is orthogonal-transformation based and runs on LAPACK through SciPy: the
"fundamental transformations" of course §3-5 are Householder reflections, and the "reduction to
triangular form" of §3-9 is a QR factorisation with column pivoting (``?geqp3``), which also
reveals the rank. No Gaussian elimination is written by hand.

* :func:`lstsq`: ``min ||W^(1/2) (A x - b)||``, minimum-norm when ``A`` is rank deficient;
* :func:`min_norm_solve`: the shortest ``x`` with ``C x = d`` (course §4-4), conflicts reported;
* :class:`ConstraintFactor`: the pivoted QR of ``C^T`` behind it, factored once and reused (§4-6);
* :func:`constrained_lstsq`: ``min ||W^(1/2) (A x - b)||`` subject to ``C x = d`` by the
  null-space method (§3-12);
* :func:`sparse_lstsq`: LSMR for large sparse ``A`` (minimum-norm from a zero start);
* :func:`sparse_min_norm_solve`: ``min ||x||`` s.t. ``C x = d`` through the sparse augmented system;
* :func:`sparse_constrained_lstsq`: the sparse KKT (augmented) system
  ``[[W^-1, 0, A], [0, 0, C], [A^T, C^T, 0]]``.

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
SIAM 1996, §2.7 (augmented systems) and §5.1 (LSE). D. C.-L. Fong, M. Saunders, "LSMR", SIAM J. Sci.
Comput. 33 (2011).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from typing import Any, NamedTuple, TypeVar, overload

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from numpy.typing import ArrayLike, NDArray

from .. import tolerances
from ..errors import InvalidGeometryError, ToleranceError

__all__ = [
    "ConstraintError",
    "ConvergenceError",
    "LstsqResult",
    "lstsq",
    "ConstraintFactor",
    "min_norm_solve",
    "constrained_lstsq",
    "sparse_lstsq",
    "sparse_min_norm_solve",
    "sparse_constrained_lstsq",
]

Array = NDArray[np.float64]
_M = TypeVar("_M")  # a dense Array or a SciPy sparse matrix (SciPy ships no type stubs: Any)


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


# ------------------------------------------------------------------------------ validation
def _matrix(a: ArrayLike, name: str) -> Array:
    try:
        m = np.array(a, dtype=float)
    except (TypeError, ValueError) as err:
        raise InvalidGeometryError(f"{name}: expected a 2-D array of real numbers, got {type(a).__name__}") from err
    if m.ndim != 2:
        raise InvalidGeometryError(f"{name}: expected a 2-D array, got shape {m.shape}")
    if not np.all(np.isfinite(m)):
        raise InvalidGeometryError(f"{name}: expected finite values")
    return m


def _rhs(b: ArrayLike, rows: int, name: str) -> Array:
    try:
        v = np.array(b, dtype=float)
    except (TypeError, ValueError) as err:
        raise InvalidGeometryError(f"{name}: expected an array of real numbers, got {type(b).__name__}") from err
    if v.ndim not in (1, 2) or v.shape[0] != rows:
        raise InvalidGeometryError(f"{name}: expected shape ({rows},) or ({rows}, k), got {v.shape}")
    if not np.all(np.isfinite(v)):
        raise InvalidGeometryError(f"{name}: expected finite values")
    return v


def _positive(w: ArrayLike | None, size: int, name: str) -> Array | None:
    if w is None:
        return None
    v = np.array(w, dtype=float)
    if v.shape != (size,):
        raise InvalidGeometryError(f"{name}: expected shape ({size},), got {v.shape}")
    if not np.all(np.isfinite(v)) or np.any(v <= 0):
        raise InvalidGeometryError(f"{name}: expected finite values > 0, got min {v.min()!r}")
    return v


def _per_row(x: Array, s: Array) -> Array:
    """``s`` (m,) shaped to scale the rows of ``x`` (shape (m,) or (m, k)): ``x * _per_row(x, s)``."""
    return s if x.ndim == 1 else s[:, None]


@overload
def _weighted_rows(A: Array, b: Array, w: Array | None) -> tuple[Array, Array]: ...
@overload
def _weighted_rows(A: Any, b: Array, w: Array | None) -> tuple[Any, Array]: ...
def _weighted_rows(A: Any, b: Array, w: Array | None) -> tuple[Any, Array]:
    """``W^(1/2) A`` and ``W^(1/2) b`` for row weights ``w`` (``A`` dense or sparse; unchanged if
    ``w`` is None)."""
    if w is None:
        return A, b
    s = np.sqrt(w)
    A = sp.diags(s) @ A if sp.issparse(A) else A * s[:, None]
    return A, b * _per_row(b, s)


def _constrained_system(A: Any, b: ArrayLike, C: Any, d: ArrayLike, weights: ArrayLike | None,
                        as_matrix: Callable[[Any, str], _M]) -> tuple[_M, Array, _M, Array, Array | None]:
    """Validated inputs of a constrained least-squares problem (dense or sparse by ``as_matrix``):
    ``A`` and ``C`` with as many columns, ``b`` and ``d`` with as many right-hand sides, row weights."""
    A = as_matrix(A, "A")
    C = as_matrix(C, "C")
    if A.shape[1] != C.shape[1]:
        raise InvalidGeometryError(f"A, C: expected the same number of columns, got {A.shape[1]} and {C.shape[1]}")
    b = _rhs(b, A.shape[0], "b")
    d = _rhs(d, C.shape[0], "d")
    w = _positive(weights, A.shape[0], "weights")
    if b.ndim != d.ndim or (b.ndim == 2 and b.shape[1] != d.shape[1]):
        raise InvalidGeometryError(f"b, d: expected the same number of right-hand sides, got shapes {b.shape} and {d.shape}")
    return A, b, C, d, w


def _labels(labels: Sequence[str] | None, m: int) -> list[str]:
    if labels is None:
        return [f"row {i}" for i in range(m)]
    labels = [str(s) for s in labels]
    if len(labels) != m:
        raise InvalidGeometryError(f"labels: expected {m} labels (one per constraint row), got {len(labels)}")
    return labels


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
    A = _matrix(A, "A")
    b = _rhs(b, A.shape[0], "b")
    A, b = _weighted_rows(A, b, _positive(weights, A.shape[0], "weights"))
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
        C = _matrix(C, "C")
        m, n = C.shape
        self.shape = (m, n)
        self.labels = _labels(labels, m)
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
        de = de / _per_row(de, self.row_scale)
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
        de = de / _per_row(de, self.row_scale)
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
        d = _rhs(d, self.shape[0], "d")
        if check:
            self.check(d, tol)
        n = self.shape[1]
        if self.rank == 0:
            return np.zeros((n,) + d.shape[1:])
        de = d / _per_row(d, self.row_scale)
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
    C = _matrix(C, "C")
    d = _rhs(d, C.shape[0], "d")
    w = _positive(weights, C.shape[1], "weights")
    if w is None:
        return ConstraintFactor(C, labels).solve(d, tol=tol)
    s = 1.0 / np.sqrt(w)
    y = ConstraintFactor(C * s, labels).solve(d, tol=tol)
    return y * _per_row(y, s)


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
    Am, bv, Cm, dv, w = _constrained_system(A, b, C, d, weights, _matrix)
    F = ConstraintFactor(Cm, labels, full=True)
    xc = F.solve(dv, tol=tol)
    Z = F.null_basis
    if Z is None or Z.shape[1] == 0 or Am.shape[0] == 0:
        return xc
    r = bv - Am @ xc
    z = lstsq(Am @ Z, r, w, rcond=rcond).x
    return xc + Z @ z


# ------------------------------------------------------------------------------ sparse
def _sparse(a: object, name: str) -> sp.csr_matrix:
    try:
        m = sp.csr_matrix(a, dtype=float)
    except (TypeError, ValueError) as err:
        raise InvalidGeometryError(f"{name}: expected a sparse or dense 2-D matrix, got {type(a).__name__}") from err
    if not np.all(np.isfinite(m.data)):
        raise InvalidGeometryError(f"{name}: expected finite values")
    return m


def sparse_lstsq(A: object, b: ArrayLike, weights: ArrayLike | None = None, *, tol: float | None = None,
                 maxiter: int | None = None) -> Array:
    """Least squares for large sparse ``A`` by LSMR (minimum-norm from the zero start).

    Suited to the banded collocation matrices of B-spline fitting: each iteration costs two
    sparse products. From ``x0 = 0`` LSMR converges to the minimum-norm least-squares solution,
    so rank-deficient problems are handled like :func:`lstsq`.

    Parameters
    ----------
    A : sparse matrix or array_like, shape (m, n)
    b : array_like, shape (m,) or (m, k)
        Each column is solved separately.
    weights : array_like, shape (m,), optional
    tol : float, optional
        ``atol = btol`` of LSMR; default :data:`~occsurf.algorithms.tolerances.SPARSE_TOL`.
    maxiter : int, optional
        Default ``10 * n``.

    Returns
    -------
    ndarray, shape (n,) or (n, k)

    Raises
    ------
    ConvergenceError
        LSMR hit ``maxiter`` or the condition-number limit before converging.
    """
    Asp = _sparse(A, "A")
    rhs = _rhs(b, Asp.shape[0], "b")
    Asp, rhs = _weighted_rows(Asp, rhs, _positive(weights, Asp.shape[0], "weights"))
    t = tolerances.SPARSE_TOL if tol is None else float(tol)
    it = 10 * Asp.shape[1] if maxiter is None else int(maxiter)
    B = rhs.reshape(rhs.shape[0], -1)
    X = np.empty((Asp.shape[1], B.shape[1]))
    for k in range(B.shape[1]):  # one Krylov run per right-hand side
        out = spla.lsmr(Asp, B[:, k], atol=t, btol=t, conlim=1e12, maxiter=it)
        if out[1] in (3, 6, 7):
            raise ConvergenceError(
                f"sparse_lstsq: LSMR stopped without converging (istop={out[1]}, {out[2]} iterations, "
                f"residual {out[3]:.3g}); raise maxiter or loosen tol"
            )
        X[:, k] = out[0]
    return X[:, 0] if rhs.ndim == 1 else X


def _splu_solve(K: sp.spmatrix, rhs: Array, what: str) -> Array:
    try:
        lu = spla.splu(sp.csc_matrix(K))
    except RuntimeError as err:  # SuperLU: "Factor is exactly singular"
        raise ConstraintError(f"{what}: the augmented system is singular ({err})") from err
    x = lu.solve(rhs)
    if not np.all(np.isfinite(x)):
        raise ConstraintError(f"{what}: the augmented system is numerically singular")
    return x


def _diagnose_sparse(C: sp.csr_matrix, d: Array, labels: Sequence[str] | None, what: str) -> None:
    """Name the conflicting rows of a sparse constraint matrix (dense QR of ``C^T``, ``m`` small)."""
    m, n = C.shape
    if m * n > 50_000_000:
        return
    F = ConstraintFactor(C.toarray(), labels)
    F.check(d)
    if F.rank < m:
        raise ConstraintError(
            f"{what}: rows {', '.join(F.labels[i] for i in F.redundant)} are redundant (consistent); the sparse "
            "solver needs independent constraints: drop them or use the dense solver",
            F.redundant, [F.labels[i] for i in F.redundant],
        )


def sparse_min_norm_solve(C: object, d: ArrayLike, weights: ArrayLike | None = None, *,
                          labels: Sequence[str] | None = None, tol: float | None = None) -> Array:
    """Minimum-norm solution of ``C x = d`` for large sparse ``C`` (course §4-4, sparse form).

    Solves the augmented (saddle-point) system by sparse LU (SuperLU):

    .. math::

        \\begin{bmatrix} W & C^T \\\\ C & 0 \\end{bmatrix}
        \\begin{bmatrix} x \\\\ -\\lambda \\end{bmatrix} =
        \\begin{bmatrix} 0 \\\\ d \\end{bmatrix},

    the optimality conditions of ``min x^T W x / 2`` subject to ``C x = d`` (Björck 1996, §2.7).
    Its matrix is never formed densely, so B-spline systems with many thousands of poles are cheap.

    Parameters
    ----------
    C : sparse matrix or array_like, shape (m, n)
        Independent rows (a redundant or conflicting row makes the system singular; the error then
        names the rows, found by a dense rank-revealing QR of ``C^T``).
    d : array_like, shape (m,) or (m, k)
    weights : array_like, shape (n,), optional
    labels : sequence of str, optional
    tol : float, optional
        Relative tolerance of the final check ``||C x - d|| <= tol * max(1, ||d||)``; default
        :data:`~occsurf.algorithms.tolerances.CONSISTENCY_RTOL`.

    Returns
    -------
    ndarray, shape (n,) or (n, k)

    Raises
    ------
    ConstraintError
        Dependent (consistent or not) rows; conflicting rows are named.
    """
    Csp = _sparse(C, "C")
    m, n = Csp.shape
    d = _rhs(d, m, "d")
    w = _positive(weights, n, "weights")
    W = sp.identity(n, format="csr") if w is None else sp.diags(w, format="csr")
    K = sp.bmat([[W, Csp.T], [Csp, sp.csr_matrix((m, m))]], format="csc")
    rhs = np.concatenate([np.zeros((n,) + d.shape[1:]), d])
    try:
        sol = _splu_solve(K, rhs, "sparse_min_norm_solve")
    except ConstraintError:
        _diagnose_sparse(Csp, d, labels, "sparse_min_norm_solve")
        raise
    x = sol[:n]
    _check_residual(Csp, x, d, tol, labels, "sparse_min_norm_solve")
    return x


def _check_residual(C: sp.csr_matrix, x: Array, d: Array, tol: float | None, labels: Sequence[str] | None,
                    what: str) -> None:
    res = np.abs(C @ x - d).reshape(d.shape[0], -1).max(axis=1)
    rtol = tolerances.CONSISTENCY_RTOL if tol is None else float(tol)
    t = rtol * max(1.0, float(np.abs(d).max()) if d.size else 0.0)
    if np.any(res > t):
        _diagnose_sparse(C, d, labels, what)
        bad = np.nonzero(res > t)[0]
        names = _labels(labels, d.shape[0])
        raise ConstraintError(f"{what}: constraints {', '.join(names[i] for i in bad)} are not met "
                              f"(residual up to {res.max():.3g}); the system is too ill-conditioned",
                              bad, [names[i] for i in bad])


def sparse_constrained_lstsq(A: object, b: ArrayLike, C: object, d: ArrayLike, weights: ArrayLike | None = None, *,
                             labels: Sequence[str] | None = None, tol: float | None = None) -> Array:
    """Equality-constrained least squares for large sparse systems (augmented KKT system).

    With the weighted residual ``s = W (b - A x)`` and multipliers ``mu``, the optimality conditions
    of ``min ||W^(1/2)(A x - b)||`` subject to ``C x = d`` are the sparse symmetric system

    .. math::

        \\begin{bmatrix} W^{-1} & 0 & A \\\\ 0 & 0 & C \\\\ A^T & C^T & 0 \\end{bmatrix}
        \\begin{bmatrix} s \\\\ \\mu \\\\ x \\end{bmatrix} =
        \\begin{bmatrix} b \\\\ d \\\\ 0 \\end{bmatrix}

    (Björck 1996, §5.1), factored by SuperLU. The residual block avoids forming ``A^T A``, so the
    conditioning is that of the problem, not its square.

    Parameters
    ----------
    A : sparse matrix or array_like, shape (p, n)
        ``[A; C]`` must have full column rank (the solution unique); otherwise use the dense
        :func:`constrained_lstsq`, which returns the minimum-norm minimiser.
    b : array_like, shape (p,) or (p, k)
    C : sparse matrix or array_like, shape (m, n)
        Independent rows.
    d : array_like, shape (m,) or (m, k)
    weights : array_like, shape (p,), optional
    labels : sequence of str, optional
        Names of the rows of ``C``.
    tol : float, optional
        As in :func:`sparse_min_norm_solve`.

    Returns
    -------
    ndarray, shape (n,) or (n, k)

    Raises
    ------
    ConstraintError
        Dependent or conflicting constraints (named), or a solution that is not unique.
    """
    Asp, b, Csp, d, w = _constrained_system(A, b, C, d, weights, _sparse)
    (p, n), m = Asp.shape, Csp.shape[0]
    Winv = sp.identity(p, format="csr") if w is None else sp.diags(1.0 / w, format="csr")
    K = sp.bmat([
        [Winv, None, Asp],
        [None, sp.csr_matrix((m, m)), Csp],
        [Asp.T, Csp.T, sp.csr_matrix((n, n))],
    ], format="csc")
    rhs = np.concatenate([b, d, np.zeros((n,) + b.shape[1:])])
    try:
        sol = _splu_solve(K, rhs, "sparse_constrained_lstsq")
    except ConstraintError as err:
        _diagnose_sparse(Csp, d, labels, "sparse_constrained_lstsq")
        raise ConstraintError(f"{err}; the constraints are independent, so [A; C] is rank deficient and the "
                              "minimiser is not unique: use constrained_lstsq for the minimum-norm one") from err
    x = sol[p + m:]
    _check_residual(Csp, x, d, tol, labels, "sparse_constrained_lstsq")
    return x
