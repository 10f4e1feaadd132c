"""Sparse least squares, minimum-norm and equality-constrained solvers for large B-spline systems
(course ch. 3 and §4-4; the dense forms are in :mod:`.linalg`).

* :func:`sparse_lstsq`: LSMR for large sparse ``A`` (minimum-norm from a zero start);
* :func:`sparse_min_norm_solve`: ``min ||x||`` s.t. ``C x = d`` through the sparse augmented system;
* :func:`sparse_constrained_lstsq`: the sparse KKT (augmented) system
  ``[[W^-1, 0, A], [0, 0, C], [A^T, C^T, 0]]``.

A singular augmented system (dependent or conflicting constraints) is diagnosed by the dense
rank-revealing QR of ``C^T`` (:class:`.linalg.ConstraintFactor`), which names the rows.

References
----------
Å. Björck, *Numerical Methods for Least Squares Problems*, SIAM 1996, §2.7 (augmented systems) and
§5.1 (LSE). D. C.-L. Fong, M. Saunders, "LSMR", SIAM J. Sci. Comput. 33 (2011).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from numpy.typing import ArrayLike, NDArray

from .. import tolerances
from ..errors import InvalidGeometryError
from .linalg import ConstraintError, ConstraintFactor, ConvergenceError
from .linalg_args import constrained_system, right_hand_side, row_labels, row_weights, weighted_rows

__all__ = ["sparse_lstsq", "sparse_min_norm_solve", "sparse_constrained_lstsq"]

Array = NDArray[np.float64]


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
    so rank-deficient problems are handled like :func:`.linalg.lstsq`.

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
    rhs = right_hand_side(b, Asp.shape[0], "b")
    Asp, rhs = weighted_rows(Asp, rhs, row_weights(weights, Asp.shape[0], "weights"))
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
    d = right_hand_side(d, m, "d")
    w = row_weights(weights, n, "weights")
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
        names = row_labels(labels, d.shape[0])
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
        :func:`.linalg.constrained_lstsq`, which returns the minimum-norm minimiser.
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
    Asp, b, Csp, d, w = constrained_system(A, b, C, d, weights, _sparse)
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
