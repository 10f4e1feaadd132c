"""Gridded least squares with smoothing and constraints (course §7-4, 7-5, 7-7).

Oracles: scipy's ``make_lsq_spline`` applied separably (same knots, same data: the unconstrained
coefficients must agree to 1e-10), a dense KKT solve of the full ``(mn x NuNv)`` problem on small
grids (the Kronecker + null-space + Schur implementation must give the same poles), splines of
the fitted space (reproduced to 1e-12), GCV evaluated by brute force. Constraints must hold to
1e-12 (relative to the data's size 1).
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla
from hypothesis import given
from hypothesis import strategies as st
from scipy.interpolate import make_lsq_spline

from occsurf.algorithms import BSplineSurface, tolerances
from occsurf.algorithms.errors import InvalidGeometryError, ParameterError
from occsurf.algorithms.fitting._common import difference_penalty
from occsurf.algorithms.fitting.gridded import (
    BoundaryCurve,
    CrossDerivative,
    FixedPoint,
    Symmetry,
    TangentPlane,
    fit_grid,
)
from occsurf.algorithms.kernel.basis import basis_matrix
from occsurf.algorithms.manipulation.linalg import ConstraintError
from tests.algorithms.strategies import test_settings

EXACT = 1e-12  # identities: round-off of O(1) data through well-conditioned (cond < 1e3) systems


def franke(x, y):
    return (0.75 * np.exp(-((9 * x - 2) ** 2 + (9 * y - 2) ** 2) / 4) + 0.75 * np.exp(-(9 * x + 1) ** 2 / 49 - (9 * y + 1) / 10)
            + 0.5 * np.exp(-((9 * x - 7) ** 2 + (9 * y - 3) ** 2) / 4) - 0.2 * np.exp(-(9 * x - 4) ** 2 - (9 * y - 7) ** 2))


def _grid(m=41, n=37, noise=0.0, seed=0):
    x, y = np.linspace(0, 1, m), np.linspace(0, 1, n)
    X, Y = np.meshgrid(x, y, indexing="ij")
    Z = franke(X, Y) + noise * np.random.default_rng(seed).standard_normal(X.shape)
    return x, y, X, Y, Z


def _separable_scipy(u, v, Q, tu, tv, p, q):
    m, n, d = Q.shape
    c1 = make_lsq_spline(u, Q.reshape(m, -1), tu, p).c.reshape(-1, n, d)  # (Nu, n, d)
    c2 = make_lsq_spline(v, c1.transpose(1, 0, 2).reshape(n, -1), tv, q).c
    return c2.reshape(-1, c1.shape[0], d).transpose(1, 0, 2)


# ----------------------------------------------------------------------------- oracles
@pytest.mark.parametrize("degree", [(1, 1), (2, 3), (3, 3), (5, 2)])
def test_unconstrained_equals_scipy_make_lsq_spline(degree):
    rng = np.random.default_rng(3)
    m, n = 53, 47
    Q = rng.standard_normal((m, n, 3))
    u = np.sort(np.r_[0.0, rng.random(m - 2), 1.0])
    v = np.sort(np.r_[0.0, rng.random(n - 2), 1.0])
    fit = fit_grid(Q, (14, 11), degree, u_params=u, v_params=v)
    tu, tv = fit.surface.knots
    ref = _separable_scipy(u, v, Q, tu, tv, *degree)
    np.testing.assert_allclose(fit.surface.control_points, ref, atol=1e-10, rtol=0)


def test_heights_equal_scipy_and_stay_a_graph():
    x, y, X, Y, Z = _grid(noise=1e-3)
    fit = fit_grid(Z, (12, 10), 3, x=2 * x, y=3 * y)
    tu, tv = fit.surface.knots
    ref = _separable_scipy(2 * x, 3 * y, Z[..., None], tu, tv, 3, 3)[..., 0]
    np.testing.assert_allclose(fit.surface.control_points[..., 2], ref, atol=1e-10, rtol=0)
    uu, vv = np.random.default_rng(1).random((2, 200))
    P = fit.surface.evaluate(2 * uu, 3 * vv)
    np.testing.assert_allclose(P[:, 0], 2 * uu, atol=EXACT)
    np.testing.assert_allclose(P[:, 1], 3 * vv, atol=EXACT)


@pytest.mark.slow
@given(st.integers(1, 4), st.integers(1, 4), st.integers(0, 10_000))
@test_settings(25)
def test_reproduces_a_spline_of_the_same_space(p, q, seed):
    rng = np.random.default_rng(seed)
    Nu, Nv = p + 1 + int(rng.integers(0, 6)), q + 1 + int(rng.integers(0, 6))
    u, v = np.linspace(0, 1, 3 * Nu), np.linspace(0, 1, 3 * Nv)
    probe = fit_grid(np.zeros((u.size, v.size, 3)), (Nu, Nv), (p, q), u_params=u, v_params=v)
    s = BSplineSurface((p, q), probe.surface.knots, rng.standard_normal((Nu, Nv, 3)))
    Q = s.evaluate_grid(u, v)
    for kw in ({}, {"fix_boundary": True}, {"constraints": [FixedPoint(0.3, 0.6, s.evaluate(0.3, 0.6))]}):
        fit = fit_grid(Q, (Nu, Nv), (p, q), u_params=u, v_params=v, knots=s.knots, **kw)
        scale = max(1.0, float(np.abs(Q).max()))
        np.testing.assert_allclose(fit.surface.control_points, s.control_points, atol=EXACT * scale)
        assert fit.max_error < EXACT * scale


def _dense_oracle(A, B, Q, lam, C, dvec, Ru=None, Rv=None):
    """min ||(A⊗B) x - q||^2 + λ x^T (Ru⊗Gv + Gu⊗Rv) x  s.t.  C x = d, stacked over coordinates."""
    d = Q.shape[2]
    K = np.kron(A, B)
    Gu, Gv = A.T @ A, B.T @ B
    Pen = np.kron(Ru, Gv) + np.kron(Gu, Rv)
    N1 = K.T @ K + lam * Pen
    N = sla.block_diag(*[N1] * d)
    rhs = np.concatenate([K.T @ Q[..., c].ravel() for c in range(d)])
    M = np.block([[N, C.T], [C, np.zeros((C.shape[0], C.shape[0]))]])
    x = np.linalg.lstsq(M, np.r_[rhs, dvec], rcond=None)[0][: N.shape[0]]
    return x.reshape(d, A.shape[1], B.shape[1]).transpose(1, 2, 0)


@pytest.mark.parametrize("lam", [0.0, 0.05])
def test_constrained_equals_dense_kkt(lam):
    """Boundary curves + fixed points + tangent planes via Kronecker/null space/Schur = dense KKT."""
    x, y, X, Y, Z = _grid(17, 15, noise=1e-2)
    Q = np.stack([X, Y, Z], -1)
    cons = [FixedPoint(0.4, 0.55, [0.4, 0.55, 0.7]), TangentPlane("v1", [0.2, 0.5, 0.8], [[0, 0.2, 1.0]] * 3)]
    fit = fit_grid(Q, (8, 7), 3, method="uniform", smoothing=lam, fix_boundary=True, constraints=cons)
    tu, tv = fit.surface.knots
    u, v = fit.u_params, fit.v_params
    A, B = basis_matrix(tu, 3, 8, u)[0], basis_matrix(tv, 3, 7, v)[0]
    Nu, Nv, size = 8, 7, 56
    rows, d = [], []
    P = fit.surface.control_points
    for c in range(3):  # boundary rows and columns as the fit holds them (their values are tested below)
        for i in range(Nu):
            for j in range(Nv):
                if i in (0, Nu - 1) or j in (0, Nv - 1):
                    r = np.zeros(3 * size)
                    r[c * size + i * Nv + j] = 1
                    rows.append(r), d.append(P[i, j, c])
    a, b = basis_matrix(tu, 3, 8, np.array([0.4]))[0, 0], basis_matrix(tv, 3, 7, np.array([0.55]))[0, 0]
    for c, t in enumerate([0.4, 0.55, 0.7]):
        r = np.zeros(3 * size)
        r[c * size:(c + 1) * size] = np.kron(a, b)
        rows.append(r), d.append(t)
    cross = basis_matrix(tv, 3, 7, np.array([1.0]), 1)[1, 0]  # d/dv at the side v = 1
    for s in (0.2, 0.5, 0.8):
        along = basis_matrix(tu, 3, 8, np.array([s]))[0, 0]
        rows.append(np.concatenate([w * np.kron(along, cross) for w in (0.0, 0.2, 1.0)])), d.append(0.0)
    C = np.array(rows)
    cu = np.trace(A.T @ A) / (2 * np.trace(difference_penalty(Nu)))
    cv = np.trace(B.T @ B) / (2 * np.trace(difference_penalty(Nv)))
    ref = _dense_oracle(A, B, Q, lam, C, np.array(d), cu * difference_penalty(Nu), cv * difference_penalty(Nv))
    np.testing.assert_allclose(P, ref, atol=1e-10)


# ----------------------------------------------------------------------------- constraints hold
def test_boundary_curves_hold_exactly_and_meet_the_corners():
    x, y, X, Y, Z = _grid(noise=1e-3)
    fit = fit_grid(np.stack([X, Y, Z], -1), (11, 9), 3, fix_boundary=True)
    s = fit.surface
    for side, row in (("u0", s.control_points[0]), ("u1", s.control_points[-1]),
                      ("v0", s.control_points[:, 0]), ("v1", s.control_points[:, -1])):
        free = fit_grid(np.stack([X, Y, Z], -1), (11, 9), 3, constraints=[BoundaryCurve(side)])
        P = free.surface.control_points
        got = {"u0": P[0], "u1": P[-1], "v0": P[:, 0], "v1": P[:, -1]}[side]
        np.testing.assert_allclose(got, row, atol=EXACT)
    # corners interpolate the data corners
    for (i, j) in ((0, 0), (0, -1), (-1, 0), (-1, -1)):
        np.testing.assert_allclose(s.control_points[i, j], [X[i, j], Y[i, j], Z[i, j]], atol=EXACT)


def test_given_boundary_curve_is_held():
    x, y, X, Y, Z = _grid()
    base = fit_grid(Z, (10, 9), 3)
    tv = base.surface.knots[1]
    from occsurf.algorithms import BSplineCurve

    cur = BSplineCurve(3, tv, np.c_[np.zeros(9), np.linspace(0, 1, 9), 0.3 + 0.1 * np.sin(np.arange(9))])
    fit = fit_grid(Z, (10, 9), 3, constraints=[BoundaryCurve("u0", cur)])
    vv = np.linspace(0, 1, 50)
    np.testing.assert_allclose(fit.surface.evaluate(np.zeros(50), vv)[:, 2], cur.evaluate(vv)[:, 2], atol=EXACT)


def test_points_tangent_planes_and_cross_rows_hold():
    x, y, X, Y, Z = _grid(noise=1e-2)
    sites = np.array([0.25, 0.5, 0.75])
    held = fit_grid(Z, (12, 12), 3, fix_boundary=True).surface  # the same boundary curves as below
    tangent = held.derivatives(np.zeros(3), sites, 1)[:, 0, 1]
    n = np.cross(tangent, [[1.0, 0.0, 0.3], [1.0, 0.2, -0.2], [1.0, -0.1, 0.1]])  # neighbour normals: G1 along it
    cons = [FixedPoint(0.5, 0.5, [0.3]), FixedPoint(0.21, 0.83, [0.0, 0.0, -0.1]),
            TangentPlane("u0", sites, n)]
    fit = fit_grid(Z, (12, 12), 3, smoothing=0.01, fix_boundary=True, constraints=cons)
    s = fit.surface
    assert abs(s.evaluate(0.5, 0.5)[2] - 0.3) < EXACT
    assert abs(s.evaluate(0.21, 0.83)[2] + 0.1) < EXACT
    D = s.derivatives(np.zeros(3), np.array([0.25, 0.5, 0.75]), 1)
    np.testing.assert_allclose(np.einsum("kc,kc->k", n, D[:, 1, 0]), 0.0, atol=EXACT)
    nrm = np.cross(D[:, 1, 0], D[:, 0, 1])
    nrm /= np.linalg.norm(nrm, axis=1)[:, None]
    np.testing.assert_allclose(np.abs(np.einsum("kc,kc->k", nrm, n / np.linalg.norm(n, axis=1)[:, None])), 1.0,
                               atol=EXACT)
    # a C1 join: the first two pole rows prescribed
    rows = np.stack([s.control_points[0], s.control_points[1] + [0, 0, 0.01]])
    c1 = fit_grid(Z, (12, 12), 3, constraints=[CrossDerivative("u0", rows)])
    np.testing.assert_allclose(c1.surface.control_points[:2], rows, atol=EXACT)


def test_symmetry_holds():
    x, y, X, Y, Z = _grid(41, 31, noise=1e-2)
    Q = np.stack([X, Y, Z], -1)
    fit = fit_grid(Q, (12, 9), 3, method="uniform", constraints=[Symmetry("u", axis=0, offset=0.5)])
    P = fit.surface.control_points
    np.testing.assert_allclose(P[::-1, :, 0], 1.0 - P[:, :, 0], atol=EXACT)
    np.testing.assert_allclose(P[::-1, :, 1:], P[:, :, 1:], atol=EXACT)
    h = fit_grid(Z, (12, 9), 3, constraints=[Symmetry("v")])
    Pz = h.surface.control_points[..., 2]
    np.testing.assert_allclose(Pz[:, ::-1], Pz, atol=EXACT)


# ----------------------------------------------------------------------------- smoothing
def test_gcv_minimises_the_score_and_beats_no_smoothing_on_noise():
    x, y, X, Y, Z = _grid(61, 61, noise=0.02, seed=5)
    fit = fit_grid(Z, (30, 30), 3, smoothing="gcv")
    lams = 10.0 ** np.linspace(-6, 1, 15)
    from occsurf.algorithms.fitting.grid_constraints import Rows
    from occsurf.algorithms.fitting.gridded import _Kronecker

    A = basis_matrix(fit.surface.knots[0], 3, 30, x)[0]
    B = basis_matrix(fit.surface.knots[1], 3, 30, y)[0]
    kr = _Kronecker(A, B, Z[..., None], Rows([[]], [[]]))
    assert fit.gcv <= min(kr.gcv(lam) for lam in lams) * (1 + 1e-9)
    truth = franke(X, Y)
    plain = fit_grid(Z, (30, 30), 3)
    err = lambda f: np.sqrt(np.mean((f.surface.evaluate_grid(x, y)[..., 2] - truth) ** 2))  # noqa: E731
    assert err(fit) < 0.7 * err(plain)


def test_gcv_range_is_an_overridable_tolerance():
    x, y, X, Y, Z = _grid(41, 41, noise=0.02)
    with tolerances.override(FIT_GCV_MIN_LOG10=1.0, FIT_GCV_MAX_LOG10=2.0):
        fit = fit_grid(Z, (20, 20), 3, smoothing="gcv")
    assert 10.0 <= fit.smoothing <= 100.0


# ----------------------------------------------------------------------------- missing data
def test_missing_cells_fall_back_to_a_sparse_solve():
    u, v = np.linspace(0, 1, 40), np.linspace(0, 1, 36)
    probe = fit_grid(np.zeros((40, 36)), (9, 8), 3)
    s = BSplineSurface((3, 3), probe.surface.knots, np.random.default_rng(2).standard_normal((9, 8, 3)))
    Q = s.evaluate_grid(u, v)
    Qn = Q.copy()
    Qn[10:14, 20:23] = np.nan  # every span still holds data
    with tolerances.override(FIT_MISSING_SMOOTHING=0.0):  # plain least squares: reproduces the spline
        fit = fit_grid(Qn, (9, 8), 3, u_params=u, v_params=v, knots=s.knots)
    assert fit.method == "sparse"
    np.testing.assert_allclose(fit.surface.control_points, s.control_points, atol=1e-9)
    assert np.isnan(fit.residual[11, 21]) and np.isfinite(fit.max_error)
    # a hole bigger than a knot span: singular without smoothing, defined with the default
    Qh = Q.copy()
    Qh[8:30, 8:30] = np.nan
    with tolerances.override(FIT_MISSING_SMOOTHING=0.0), pytest.raises(InvalidGeometryError):
        fit_grid(Qh, (20, 20), 3, u_params=u, v_params=v)
    fit = fit_grid(Qh, (20, 20), 3, u_params=u, v_params=v, fix_boundary=True,
                   constraints=[FixedPoint(0.5, 0.5, s.evaluate(0.5, 0.5))])
    assert np.all(np.isfinite(fit.surface.control_points))
    np.testing.assert_allclose(fit.surface.evaluate(0.5, 0.5), s.evaluate(0.5, 0.5), atol=EXACT)


# ----------------------------------------------------------------------------- errors
def test_bad_input_is_named():
    Z = np.zeros((10, 10))
    with pytest.raises(InvalidGeometryError, match="data"):
        fit_grid(np.zeros(5), 4)
    with pytest.raises(InvalidGeometryError, match="at least"):
        fit_grid(np.zeros((3, 10)), 4, 3)
    with pytest.raises(InvalidGeometryError, match="n_poles"):
        fit_grid(Z, 11, 3)
    with pytest.raises(InvalidGeometryError, match="infinity"):
        fit_grid(np.full((10, 10), np.inf), 4)
    with pytest.raises(ParameterError, match="smoothing"):
        fit_grid(Z, 5, smoothing=-1.0)
    with pytest.raises(ParameterError, match="gcv"):
        fit_grid(Z, 5, smoothing="gvc")
    with pytest.raises(ConstraintError):
        fit_grid(Z, 5, constraints=[FixedPoint(0.5, 0.5, [1.0]), FixedPoint(0.5, 0.5, [2.0])])
    with pytest.raises(ParameterError, match="side"):
        fit_grid(Z, 5, constraints=[BoundaryCurve("w0")])
    with pytest.raises(InvalidGeometryError, match="symmetric"):
        fit_grid(Z, 5, x=np.linspace(0, 1, 10) ** 2, constraints=[Symmetry("u")])
    with pytest.raises(InvalidGeometryError, match="expected BoundaryCurve"):
        fit_grid(Z, 5, constraints=["boundary"])
