"""Generalised cross-validation with missing cells and with point constraints (course §7-7, issue 13).

Oracle: brute-force leave-one-out. A penalised (and constrained) least-squares fit is an affine
smoother ``f = H y + c``; leaving out observation ``i`` gives the residual
``y_i - f^{(-i)}_i = (y_i - f_i) / (1 - H_ii)``, so ``H_ii`` and hence ``tr H`` follow from refits
without each cell (a NaN cell is a left-out observation; the penalty is built on the complete
grid, so every refit has the same smoother). The trace the GCV score uses must equal that sum to
round-off (exact traces) or within Hutchinson's stated standard deviation (estimates).
"""

from __future__ import annotations

import numpy as np
import pytest

from occsurf.algorithms import tolerances
from occsurf.algorithms.fitting._missing import SparseGrid
from occsurf.algorithms.fitting.grid_constraints import FixedPoint, Space, TangentPlane, build_rows
from occsurf.algorithms.fitting.gridded import _Kronecker, fit_grid
from occsurf.algorithms.kernel.basis import basis_matrix


def _field(m=13, n=12, noise=0.05, seed=3):
    rng = np.random.default_rng(seed)
    x, y = np.linspace(0, 1, m), np.linspace(0, 1, n)
    X, Y = np.meshgrid(x, y, indexing="ij")
    truth = np.sin(2.5 * X) * np.cos(2 * Y) + 0.3 * X * Y
    return x, y, truth, truth + noise * rng.standard_normal(truth.shape)


def _system(Z, x, y, poles, constraints):
    """The fit's internal pieces for heights Z (NaN = missing): knots, A, B, rows."""
    probe = fit_grid(np.nan_to_num(Z), poles, 3, x=x, y=y)
    tu, tv = probe.surface.knots
    Q = Z[..., None]
    space = Space(Q, True, x, y, (3, 3), tu, tv)
    A = basis_matrix(tu, 3, poles[0], x)[0]
    B = basis_matrix(tv, 3, poles[1], y)[0]
    return (tu, tv), A, B, Q, build_rows(space, constraints, False)


def _loo_trace(Z, x, y, poles, knots, lam, constraints):
    """``Σ H_ii`` from brute-force leave-one-out refits (every valid cell left out once)."""
    full = fit_grid(Z, poles, 3, x=x, y=y, knots=knots, smoothing=lam, constraints=constraints)
    f = full.surface.evaluate_grid(x, y)[..., 2]
    total = 0.0
    for i, j in np.argwhere(np.isfinite(Z)):
        Zi = Z.copy()
        Zi[i, j] = np.nan
        loo = fit_grid(Zi, poles, 3, x=x, y=y, knots=knots, smoothing=lam, constraints=constraints)
        assert loo.method == "sparse"
        f_loo = loo.surface.evaluate(x[i], y[j])[2]
        total += 1.0 - (Z[i, j] - f[i, j]) / (Z[i, j] - f_loo)
    return total, full


CONSTRAINTS = [FixedPoint(0.3, 0.4, [0.5]), FixedPoint(0.8, 0.7, [-0.2]),
               TangentPlane("u0", [0.25, 0.75], [[0.6, 0.0, 0.8], [0.0, 0.6, 0.8]])]


@pytest.mark.parametrize("lam", [0.01, 1.0])
def test_kronecker_trace_with_point_constraints_equals_leave_one_out(lam):
    x, y, _, Z = _field()
    poles = (7, 6)
    knots, A, B, Q, rows = _system(Z, x, y, poles, CONSTRAINTS)
    kr = _Kronecker(A, B, Q, rows)
    loo, full = _loo_trace(Z, x, y, poles, knots, lam, CONSTRAINTS)
    assert full.method == "kronecker"
    tr = kr.trace(lam)
    np.testing.assert_allclose(tr, loo, rtol=1e-8)
    # the constraints take degrees of freedom away: at most one per row
    free = _Kronecker(A, B, Q, build_rows(Space(Q, True, x, y, (3, 3), *knots), [], False)).trace(lam)
    assert 0.5 < free - tr <= len(rows.alpha) + 1e-9
    # the GCV score uses that trace and the constrained residual
    rss = float(np.sum((full.surface.evaluate_grid(x, y)[..., 2] - Z) ** 2))
    assert kr.gcv(lam) == pytest.approx(Z.size * rss / (Z.size - loo) ** 2, rel=1e-9)


@pytest.mark.parametrize("constraints", [[], CONSTRAINTS[:2]])
def test_sparse_trace_with_missing_cells_equals_leave_one_out(constraints):
    x, y, _, Z = _field(seed=4)
    Z[3:5, 6:9] = np.nan
    Z[10, 1] = np.nan
    poles, lam = (7, 6), 0.05
    knots, A, B, Q, rows = _system(Z, x, y, poles, constraints)
    sg = SparseGrid(A, B, Q, rows)
    loo, full = _loo_trace(Z, x, y, poles, knots, lam, constraints)
    assert full.method == "sparse"
    np.testing.assert_allclose(sg.trace(lam), loo, rtol=1e-8)
    # Hutchinson's estimate: within 4 standard deviations (<= sqrt(2 tr / probes) each)
    probes = 400
    with tolerances.override(FIT_GCV_EXACT_TRACE=0, FIT_GCV_PROBES=probes):
        est = sg.trace(lam)
    assert abs(est - loo) <= 4 * np.sqrt(2 * loo / probes)
    assert est != loo  # really the estimate (the override reached it)


def test_sparse_system_without_missing_cells_is_the_kronecker_fit():
    x, y, _, Z = _field(seed=5)
    poles, lam = (8, 7), 0.2
    knots, A, B, Q, rows = _system(Z, x, y, poles, CONSTRAINTS[:2])
    kr, sg = _Kronecker(A, B, Q, rows), SparseGrid(A, B, Q, rows)
    np.testing.assert_allclose(sg.solve(lam), kr.solve(lam), atol=1e-10)
    np.testing.assert_allclose(sg.trace(lam), kr.trace(lam), rtol=1e-10)
    np.testing.assert_allclose(sg.gcv(lam), kr.gcv(lam), rtol=1e-8)


@pytest.mark.slow
def test_gcv_with_missing_cells_and_constraints_smooths_noise():
    x, y, truth, Z = _field(41, 37, noise=0.05, seed=6)
    Z[10:16, 20:26] = np.nan  # a hole over about one knot span
    cons = [FixedPoint(0.5, 0.5, [float(np.sin(1.25) * np.cos(1.0) + 0.075)])]
    fit = fit_grid(Z, (16, 15), 3, x=x, y=y, smoothing="gcv", constraints=cons)
    assert fit.method == "sparse" and 1e-6 < fit.smoothing < 1e2
    assert fit.surface.evaluate(0.5, 0.5)[2] == pytest.approx(cons[0].point[0], abs=1e-12)
    # the chosen λ minimises the score the fit reports (a scan cannot beat it)
    knots, A, B, Q, rows = _system(Z, x, y, (16, 15), cons)
    sg = SparseGrid(A, B, Q, rows)
    assert fit.gcv <= min(sg.gcv(lam) for lam in 10.0 ** np.linspace(-6, 1, 15)) * (1 + 1e-9)
    assert fit.extras["trace"] == pytest.approx(sg.trace(fit.smoothing), rel=1e-12)
    # and it beats the (almost) unsmoothed fit against the noise-free field
    rough = fit_grid(Z, (16, 15), 3, x=x, y=y, smoothing=1e-8, constraints=cons)
    err = lambda f: np.sqrt(np.mean((f.surface.evaluate_grid(x, y)[..., 2] - truth) ** 2))  # noqa: E731
    assert err(fit) < 0.8 * err(rough)


def test_gcv_with_point_constraints_on_complete_data_counts_them():
    x, y, _, Z = _field(31, 29, noise=0.05, seed=7)
    fit = fit_grid(Z, (12, 11), 3, x=x, y=y, smoothing="gcv", constraints=CONSTRAINTS)
    knots, A, B, Q, rows = _system(Z, x, y, (12, 11), CONSTRAINTS)
    kr = _Kronecker(A, B, Q, rows)
    assert fit.method == "kronecker"
    assert fit.gcv == pytest.approx(kr.gcv(fit.smoothing), rel=1e-9)
    assert fit.extras["trace"] == pytest.approx(kr.trace(fit.smoothing), rel=1e-12)
    np.testing.assert_allclose(fit.surface.evaluate(0.3, 0.4)[2], 0.5, atol=1e-12)
