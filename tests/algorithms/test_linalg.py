"""Computational linear algebra (course ch. 3): oracles from SciPy, ill-conditioned and error paths.

Oracles: ``scipy.linalg.lstsq`` (SVD driver ``gelsd``, independent of our ``gelsy``/``geqp3``
path), ``scipy.linalg.null_space`` and ``numpy.linalg.pinv`` (SVD), and the KKT system solved
densely. Tolerances: ``1e-12`` relative for well-conditioned problems (a few hundred ulps of the
data), ``cond * 1e-15`` for ill-conditioned ones (the forward error a backward-stable method may
make).
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla
import scipy.sparse as sp
from hypothesis import given
from hypothesis import strategies as st
from numpy.testing import assert_allclose

from occsurf.algorithms import InvalidGeometryError
from occsurf.algorithms.kernel.basis import basis_matrix
from occsurf.algorithms.manipulation.linalg import (
    ConstraintError,
    ConstraintFactor,
    ConvergenceError,
    constrained_lstsq,
    lstsq,
    min_norm_solve,
)
from occsurf.algorithms.manipulation.sparse_linalg import sparse_constrained_lstsq, sparse_lstsq, sparse_min_norm_solve

from .strategies import test_settings

WELL = 1e-12
SETTINGS = test_settings(30)


def _random(seed: int, *shape: int) -> np.ndarray:
    return np.random.default_rng(seed).standard_normal(shape)


dims = st.tuples(st.integers(1, 6), st.integers(1, 12), st.integers(1, 3))  # (m constraints, extra unknowns, k rhs)


def _collocation(n_poles: int, m: int, degree: int = 3) -> np.ndarray:
    """A B-spline collocation matrix (banded, well conditioned) at ``m`` sites."""
    t = np.r_[[0.0] * degree, np.linspace(0, 1, n_poles - degree + 1), [1.0] * degree]
    return basis_matrix(t, degree, n_poles, np.linspace(0, 1, m))[0]


# ----------------------------------------------------------------------------- least squares
@SETTINGS
@given(seed=st.integers(0, 2**32 - 1), m=st.integers(1, 15), n=st.integers(1, 10), weighted=st.booleans())
def test_lstsq_matches_scipy(seed, m, n, weighted):
    A, b = _random(seed, m, n), _random(seed + 1, m)
    w = np.random.default_rng(seed).uniform(0.1, 10, m) if weighted else None
    ours = lstsq(A, b, w)
    s = np.ones(m) if w is None else np.sqrt(w)
    ref = sla.lstsq(A * s[:, None], b * s, lapack_driver="gelsd")[0]
    assert_allclose(ours.x, ref, rtol=1e-9, atol=1e-9 * max(1.0, np.abs(ref).max()))
    assert ours.rank == min(m, n)
    # Both residuals are computed in floating point (ours from the factorisation, this one by
    # forming W(Ax - b)); each is exact only to the rounding bound of forming Ax - b,
    # gamma_(n+1) * (|WA||x| + |Wb|) (Higham, Accuracy and Stability, §3.5). For consistent
    # systems (m <= n) the true residual is 0 and both are pure round-off, so compare within it.
    rounding = 2 * (n + 2) * np.finfo(float).eps * np.linalg.norm(np.abs(A * s[:, None]) @ np.abs(ours.x) + np.abs(b * s))
    assert_allclose(ours.residual, np.linalg.norm((A @ ours.x - b) * s), rtol=1e-12, atol=rounding)


def test_lstsq_rank_deficient_is_minimum_norm():
    A = _random(1, 8, 3) @ _random(2, 3, 6)  # rank 3, 6 unknowns
    b = _random(3, 8, 2)
    ours = lstsq(A, b)
    assert ours.rank == 3
    assert_allclose(ours.x, np.linalg.pinv(A) @ b, atol=1e-12)
    # Minimum norm: orthogonal to the null space.
    assert np.abs(sla.null_space(A).T @ ours.x).max() < 1e-12


# ----------------------------------------------------------------------------- minimum norm
@SETTINGS
@given(seed=st.integers(0, 2**32 - 1), shape=dims)
def test_min_norm_matches_pinv_and_null_space(seed, shape):
    m, extra, k = shape
    C, d = _random(seed, m, m + extra), _random(seed + 1, m, k)
    x = min_norm_solve(C, d)
    assert_allclose(C @ x, d, atol=WELL * max(1, np.abs(d).max()) * 10)
    assert_allclose(x, np.linalg.pinv(C) @ d, atol=1e-10 * max(1, np.abs(x).max()))
    N = sla.null_space(C)
    assert np.abs(N.T @ x).max() < 1e-10 * max(1, np.abs(x).max())


@SETTINGS
@given(seed=st.integers(0, 2**32 - 1), shape=dims)
def test_weighted_min_norm_closed_form(seed, shape):
    m, extra, _ = shape
    n = m + extra
    C, d = _random(seed, m, n), _random(seed + 1, m)
    w = np.random.default_rng(seed).uniform(0.1, 10, n)
    x = min_norm_solve(C, d, w)
    Wi = np.diag(1 / w)
    ref = Wi @ C.T @ np.linalg.solve(C @ Wi @ C.T, d)
    assert_allclose(x, ref, rtol=1e-8, atol=1e-10 * max(1, np.abs(ref).max()))


def test_factor_operator_is_pseudo_inverse_and_reusable():
    C = _random(5, 4, 11)
    F = ConstraintFactor(C)
    assert F.rank == 4 and F.redundant.size == 0
    assert_allclose(F.operator, np.linalg.pinv(C), atol=1e-12)
    for seed in range(3):
        d = _random(seed, 4, 3)
        assert_allclose(F.solve(d), F.operator @ d, atol=1e-12)


def test_redundant_consistent_rows_are_dropped():
    C = _random(7, 3, 9)
    d = _random(8, 3)
    C2 = np.vstack([C, 2 * C[0] - C[2], 3 * C[1]])
    d2 = np.r_[d, 2 * d[0] - d[2], 3 * d[1]]
    F = ConstraintFactor(C2)
    assert F.rank == 3 and F.redundant.size == 2
    assert_allclose(min_norm_solve(C2, d2), min_norm_solve(C, d), atol=1e-12)


def test_inconsistent_rows_are_named():
    C = _random(9, 4, 9)
    C2 = np.vstack([C, C[1] + C[3]])  # row 4 depends on rows 1 and 3 only
    d2 = np.r_[_random(10, 4), 0.0]
    d2[4] = d2[1] + d2[3] + 0.5
    labels = ["a", "b", "c", "d", "e"]
    with pytest.raises(ConstraintError, match="conflicting constraints") as info:
        min_norm_solve(C2, d2, labels=labels)
    assert set(info.value.rows) == {1, 3, 4}
    assert set(info.value.labels) == {"b", "d", "e"}
    assert "a" not in info.value.labels and "c" not in info.value.labels


def test_more_constraints_than_unknowns():
    C, d = _random(11, 5, 3), _random(12, 5)
    with pytest.raises(ConstraintError, match="5 conditions on 3 unknowns, of which only 3 are independent"):
        min_norm_solve(C, d)
    # ... but consistent overdetermined systems are fine.
    x = _random(13, 3)
    assert_allclose(min_norm_solve(C, C @ x), x, atol=1e-12)


def test_zero_row_with_nonzero_target():
    C = np.array([[1.0, 2.0, 0.0], [0.0, 0.0, 0.0]])
    with pytest.raises(ConstraintError, match="zero row") as info:
        min_norm_solve(C, [1.0, 1.0], labels=["p", "q"])
    assert info.value.labels == ("q",)
    assert_allclose(min_norm_solve(C, [1.0, 0.0]), [0.2, 0.4, 0.0], atol=1e-15)


def test_row_scaling_does_not_change_the_rank():
    """Rows in wildly different units (positions vs. second derivatives) stay independent."""
    C = _random(14, 3, 8) * np.array([[1e-6], [1.0], [1e6]])
    d = _random(15, 3)
    x = min_norm_solve(C, d)
    # The minimum-norm solution is invariant under row scaling: compare with the scaled-back system.
    s = np.linalg.norm(C, axis=1)
    assert_allclose(x, np.linalg.pinv(C / s[:, None]) @ (d / s), rtol=1e-10)
    # Backward stable row by row: |C_i x - d_i| <= O(eps) |C_i| |x|.
    assert np.all(np.abs(C @ x - d) <= 1e-13 * s * np.linalg.norm(x))


# ----------------------------------------------------------------------------- constrained LS
@SETTINGS
@given(seed=st.integers(0, 2**32 - 1), m=st.integers(0, 4), n=st.integers(5, 10), p_extra=st.integers(0, 8),
       weighted=st.booleans())
def test_constrained_lstsq_matches_kkt(seed, m, n, p_extra, weighted):
    p = n - m + p_extra  # A has full column rank on null(C)
    A, b = _random(seed, p, n), _random(seed + 1, p)
    C, d = _random(seed + 2, m, n), _random(seed + 3, m)
    w = np.random.default_rng(seed).uniform(0.1, 10, p) if weighted else np.ones(p)
    x = constrained_lstsq(A, b, C, d, None if not weighted else w)
    K = np.block([[A.T @ (w[:, None] * A), C.T], [C, np.zeros((m, m))]])
    ref = np.linalg.solve(K, np.r_[A.T @ (w * b), d])[:n]
    assert_allclose(x, ref, rtol=1e-8, atol=1e-9 * max(1, np.abs(ref).max()))
    assert_allclose(C @ x, d, atol=1e-11 * max([1.0, *np.abs(d)]))


def test_constrained_lstsq_null_space_oracle_rank_deficient():
    """A rank deficient on null(C): the minimum-norm minimiser, from scipy's null_space + lstsq."""
    n = 9
    C, d = _random(20, 3, n), _random(21, 3)
    A = _random(22, 10, 2) @ _random(23, 2, n)  # rank 2 < n - 3
    b = _random(24, 10)
    x = constrained_lstsq(A, b, C, d)
    xp = np.linalg.pinv(C) @ d
    N = sla.null_space(C)
    z = sla.lstsq(A @ N, b - A @ xp, lapack_driver="gelsd")[0]
    ref = xp + N @ z
    assert_allclose(x, ref, atol=1e-10)
    assert_allclose(C @ x, d, atol=1e-12)


def test_constrained_lstsq_conflicting_constraints_named():
    C = np.array([[1.0, 0, 0, 0], [0, 1.0, 0, 0], [1.0, 0, 0, 0]])
    with pytest.raises(ConstraintError) as info:
        constrained_lstsq(np.eye(4), np.ones(4), C, [1.0, 2.0, 3.0], labels=["x=1", "y=2", "x=3"])
    assert set(info.value.labels) == {"x=1", "x=3"}


def test_ill_conditioned_constraints_hilbert():
    """Hilbert rows (cond ~ 1e7 for 6x6 blocks): the constraints still hold to round-off."""
    n = 12
    H = sla.hilbert(n)[:6]
    d = H @ np.ones(n)
    x = min_norm_solve(H, d)
    assert np.linalg.norm(H @ x - d) <= 1e-12 * np.linalg.norm(d)
    ref = sla.lstsq(H, d, lapack_driver="gelsd")[0]
    cond = np.linalg.cond(H)
    assert np.linalg.norm(x - ref) <= cond * 1e-15 * np.linalg.norm(ref) * 10
    A = _random(30, 20, n)
    xc = constrained_lstsq(A, A @ np.ones(n), H, d)
    assert_allclose(xc, np.ones(n), atol=cond * 1e-14)


def test_ill_conditioned_nearly_dependent_spline_constraints():
    """Positions at parameters 1e-7 apart: nearly dependent rows, still independent (no false
    conflict), and the solution meets them; at 1e-13 apart they are flagged as conflicting when
    the targets disagree."""
    B = _collocation(12, 12)
    t = np.r_[[0.0] * 3, np.linspace(0, 1, 10), [1.0] * 3]
    rows = basis_matrix(t, 3, 12, np.array([0.4, 0.4 + 1e-7]))[0]
    d = np.array([1.0, 1.0 + 1e-7])
    x = min_norm_solve(rows, d)
    assert_allclose(rows @ x, d, rtol=1e-9)
    close = basis_matrix(t, 3, 12, np.array([0.4, 0.4 + 1e-13]))[0]
    with pytest.raises(ConstraintError):
        min_norm_solve(close, [1.0, 2.0])
    assert np.isfinite(np.linalg.cond(B))


def test_ill_conditioned_least_squares_vandermonde():
    x = np.linspace(0, 1, 30)
    A = np.vander(x, 10, increasing=True)  # cond ~ 1e7
    c = np.arange(1.0, 11.0)
    b = A @ c
    sol = lstsq(A, b).x
    cond = np.linalg.cond(A)
    assert np.linalg.norm(sol - c) <= cond * 1e-15 * np.linalg.norm(c) * 10
    assert_allclose(sol, sla.lstsq(A, b, lapack_driver="gelsd")[0], rtol=cond * 1e-14)


# ----------------------------------------------------------------------------- sparse
def test_sparse_lstsq_matches_dense_on_bspline_fit():
    B = _collocation(300, 900)
    y = np.sin(6 * np.linspace(0, 1, 900))[:, None] * np.array([1.0, 2.0])
    ours = sparse_lstsq(sp.csr_matrix(B), y)
    ref = sla.lstsq(B, y)[0]
    assert_allclose(ours, ref, atol=1e-10)


def test_sparse_min_norm_matches_dense():
    C = sp.random(40, 2000, density=0.01, random_state=3, format="csr") + sp.eye(40, 2000)
    d = _random(31, 40, 3)
    ours = sparse_min_norm_solve(C, d)
    assert_allclose(ours, min_norm_solve(C.toarray(), d), atol=1e-11)
    w = np.random.default_rng(4).uniform(0.5, 2, 2000)
    assert_allclose(sparse_min_norm_solve(C, d, w), min_norm_solve(C.toarray(), d, w), atol=1e-11)


def test_sparse_constrained_lstsq_matches_dense():
    n = 400
    A = sp.csr_matrix(_collocation(n, 1200))
    b = np.cos(5 * np.linspace(0, 1, 1200))
    t = np.r_[[0.0] * 3, np.linspace(0, 1, n - 2), [1.0] * 3]
    C = sp.csr_matrix(basis_matrix(t, 3, n, np.array([0.0, 0.5, 1.0]), 1).reshape(-1, n))  # values + slopes
    d = np.array([1.0, 0.0, 1.0, 0.0, 0.0, 0.0])
    w = np.random.default_rng(5).uniform(0.5, 2, 1200)
    ours = sparse_constrained_lstsq(A, b, C, d, w)
    ref = constrained_lstsq(A.toarray(), b, C.toarray(), d, w)
    assert_allclose(ours, ref, atol=1e-9)
    assert_allclose(C @ ours, d, atol=1e-11)


def test_sparse_redundant_and_conflicting_rows_named():
    C = sp.csr_matrix(np.array([[1.0, 1, 0, 0], [0, 0, 1, 1], [1.0, 1, 0, 0]]))
    with pytest.raises(ConstraintError) as info:
        sparse_min_norm_solve(C, [1.0, 1.0, 2.0], labels=["a", "b", "a again"])
    assert set(info.value.labels) == {"a", "a again"}
    with pytest.raises(ConstraintError, match="redundant"):
        sparse_min_norm_solve(C, [1.0, 1.0, 1.0])


def test_sparse_lstsq_reports_non_convergence():
    B = sp.csr_matrix(_collocation(200, 600))
    with pytest.raises(ConvergenceError, match="LSMR"):
        sparse_lstsq(B, np.ones(600) + np.linspace(0, 1, 600) ** 7, maxiter=2)


# ----------------------------------------------------------------------------- argument errors
@pytest.mark.parametrize(
    "call, match",
    [
        (lambda: lstsq(np.ones(3), np.ones(3)), "A: expected a 2-D array"),
        (lambda: lstsq(np.ones((3, 2)), np.ones(4)), r"b: expected shape \(3,\)"),
        (lambda: lstsq(np.ones((3, 2)), np.ones(3), [1, 0, 1]), "weights: expected finite values > 0"),
        (lambda: min_norm_solve(np.ones((2, 3)), np.ones(2), labels=["a"]), "labels: expected 2 labels"),
        (lambda: min_norm_solve([[np.nan, 1.0]], [1.0]), "C: expected finite values"),
        (lambda: constrained_lstsq(np.ones((3, 2)), np.ones(3), np.ones((1, 3)), np.ones(1)), "same number of columns"),
        (lambda: constrained_lstsq(np.ones((3, 2)), np.ones((3, 2)), np.ones((1, 2)), np.ones(1)), "right-hand sides"),
    ],
)
def test_argument_errors(call, match):
    with pytest.raises(InvalidGeometryError, match=match):
        call()


def test_inputs_are_not_modified():
    C, d = _random(40, 2, 5), _random(41, 2)
    C0, d0 = C.copy(), d.copy()
    min_norm_solve(C, d, np.ones(5))
    constrained_lstsq(np.eye(5), np.ones(5), C, d)
    assert np.array_equal(C, C0) and np.array_equal(d, d0)
