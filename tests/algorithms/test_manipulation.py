"""Constraint-based curve and surface manipulation (course ch. 4): oracles, invariants, errors.

Oracles
-------
* The (rational) basis row at ``u`` is read off a spline whose control points are the identity
  matrix: ``BSplineCurve(p, t, eye(n), w).derivatives(u, k)[j] = d^j R_i / du^j``, independent of
  the code under test.
* Linear constraint systems: the minimum-norm change from ``scipy.linalg.lstsq`` (SVD ``gelsd``)
  on the Kronecker system built from those rows, and the closed form ``dP_i = R_i r / sum R_j^2``
  of the single constraint system (course §4-8).
* Curvature (nonlinear): the constraints hold to 1e-10, the change satisfies the first-order
  optimality condition of ``min ||dP||`` (it lies in the row space of the constraint Jacobian
  at the solution, checked with ``lstsq``), and no smaller change is found by SciPy's SLSQP.

Tolerances: constraint residuals ``1e-10`` relative to ``max(1, |target|)`` (brief), pole
changes against the oracles ``1e-9`` relative (two different factorisations of the same system).
"""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
import scipy.linalg as sla
from hypothesis import assume, given
from hypothesis import strategies as st
from numpy.testing import assert_allclose
from scipy.optimize import NonlinearConstraint, minimize

from occsurf.algorithms import (
    BSplineCurve,
    BSplineSurface,
    ConstraintError,
    ConvergenceError,
    Curvature,
    Derivative,
    Dragger,
    InvalidGeometryError,
    ParameterError,
    Position,
    PreparedConstraints,
    Tangent,
    constrain,
    drag_point,
    drag_surface_point,
)

from .strategies import curves, fractions, surfaces, test_settings

HOLD = 1e-10     # constraints hold (relative to max(1, |target|))
ORACLE = 1e-9    # pole changes vs. an independent factorisation
SETTINGS = test_settings(40)


# ---------------------------------------------------------------------------------------- helpers
def basis_rows(c: BSplineCurve, u: float, order: int) -> np.ndarray:
    """``(order+1, n)``: the rational basis and its derivatives at ``u`` (identity-pole oracle)."""
    e = BSplineCurve(c.degree, c.knots, np.eye(c.n_poles), c.weights)
    return e.derivatives(u, order)


def surface_rows(s: BSplineSurface, u: float, v: float) -> np.ndarray:
    """``(3, nu*nv)``: rows of ``S, S_u, S_v`` (identity-net oracle)."""
    nu, nv = s.n_poles
    e = BSplineSurface(s.degree, s.knots, np.eye(nu * nv).reshape(nu, nv, nu * nv), s.weights)
    D = e.derivatives(u, v, 1)
    return np.stack([D[0, 0], D[1, 0], D[0, 1]])


def curvature(c: BSplineCurve, u: float) -> np.ndarray:
    _, a, b = c.derivatives(u, 2)
    s = a @ a
    return b / s - (a @ b) * a / s**2


def scale(c: BSplineCurve) -> float:
    return max(1.0, float(np.abs(c.control_points).max()))


def cubic(n: int = 12, dim: int = 3, seed: int = 0, rational: bool = False) -> BSplineCurve:
    rng = np.random.default_rng(seed)
    t = np.r_[[0.0] * 4, np.linspace(0, 1, n - 2)[1:-1], [1.0] * 4]
    P = np.c_[np.linspace(0, 10, n), rng.uniform(-1, 1, (n, dim - 1))]
    return BSplineCurve(3, t, P, rng.uniform(0.5, 2, n) if rational else None)


def _window(draw_pair, n: int) -> tuple[int, int]:
    a, b = draw_pair
    f, l = sorted((int(a * (n - 1) + 0.5), int(b * (n - 1) + 0.5)))
    return f, l


# ---------------------------------------------------------------------------------------- drag_point
@SETTINGS
@given(c=curves(), fu=fractions, target=st.lists(st.floats(-10, 10), min_size=3, max_size=3),
       win=st.tuples(fractions, fractions), use_window=st.booleans())
def test_drag_point_is_the_single_constraint_closed_form(c, fu, target, win, use_window):
    lo, hi = c.domain
    u = lo + fu * (hi - lo)
    T = np.array(target[: c.dim])
    f, l = _window(win, c.n_poles) if use_window else (0, c.n_poles - 1)
    R = basis_rows(c, u, 0)[0]
    Rw = np.zeros_like(R)
    Rw[f : l + 1] = R[f : l + 1]
    if not np.any(Rw != 0):
        with pytest.raises(ConstraintError, match="no movable pole acts"):
            drag_point(c, u, T, f, l)
        return
    assume(np.sum(Rw**2) > 1e-6)  # a window that barely reaches u asks for huge moves
    c2 = drag_point(c, u, T, f, l)
    s = max(scale(c), scale(c2), np.abs(T).max())
    assert_allclose(c2.evaluate(u), T, atol=1e-12 * s * 10)
    dP = c2.control_points - c.control_points
    # Closed form (course §4-8): dP_i = R_i r / sum_window R_j^2; zero outside the window.
    r = T - c.evaluate(u)
    assert_allclose(dP, np.outer(Rw, r) / np.sum(Rw**2), atol=ORACLE * s)
    assert np.all(dP[:f] == 0) and np.all(dP[l + 1 :] == 0)
    # Minimal against scipy's SVD least squares on the same linear system.
    J = np.kron(Rw[f : l + 1], np.eye(c.dim))
    y = sla.lstsq(J, r, lapack_driver="gelsd")[0].reshape(-1, c.dim)
    assert_allclose(dP[f : l + 1], y, atol=ORACLE * s)
    assert c2.knots is c.knots or np.array_equal(c2.knots, c.knots)
    assert (c2.weights is None) == (c.weights is None)
    if c.weights is not None:
        assert np.array_equal(c2.weights, c.weights)


def test_drag_point_weighted_norm_closed_form():
    c = cubic(10, 2)
    u, T = 0.43, np.array([5.0, 3.0])
    w = np.linspace(1, 5, 10)
    c2 = constrain(c, [Position(u, T)], weights=w)
    R = basis_rows(c, u, 0)[0]
    r = T - c.evaluate(u)
    expect = np.outer(R / w, r) / np.sum(R**2 / w)
    assert_allclose(c2.control_points - c.control_points, expect, atol=1e-12)
    assert_allclose(c2.evaluate(u), T, atol=1e-12)


def test_drag_point_no_change_when_target_is_on_the_curve():
    c = cubic()
    c2 = drag_point(c, 0.3, c.evaluate(0.3), 0, c.n_poles - 1)
    assert_allclose(c2.control_points, c.control_points, atol=1e-15)


# ---------------------------------------------------------------------------------------- linear systems
@st.composite
def linear_cases(draw):
    rational = draw(st.booleans())
    dim = draw(st.integers(2, 3))
    c = cubic(14, dim, seed=draw(st.integers(0, 1000)), rational=rational)
    # Up to three parameters in separate thirds of the domain; at each a single, double or
    # triple constraint system (course §4-8, §4-9, §4-11).
    cons = []
    for j in range(draw(st.integers(1, 3))):
        u = (j + draw(st.floats(0.3, 0.7))) / 3  # at least 2 knot spans apart
        kind = draw(st.integers(1, 3))

        def vec() -> np.ndarray:
            return np.array(draw(st.lists(st.floats(-5, 5), min_size=dim, max_size=dim)))

        cons.append(Position(u, c.evaluate(u) + vec()))
        if kind >= 2:
            cons.append(Tangent(u, c.derivatives(u, 1)[1] + vec()))
        if kind >= 3:
            cons.append(Derivative(u, 2, c.derivatives(u, 2)[2] + 10 * vec()))
    return c, cons


def _linear_oracle(c: BSplineCurve, cons, movable=None) -> np.ndarray:
    n, d = c.n_poles, c.dim
    rows, rhs = [], []
    for k in cons:
        order = 0 if isinstance(k, Position) else 1 if isinstance(k, Tangent) else k.order
        g = basis_rows(c, k.u, order)[order]
        target = k.point if isinstance(k, Position) else k.vector
        rows.append(np.kron(g, np.eye(d)))
        rhs.append(target - c.derivatives(k.u, order)[order])
    J, r = np.vstack(rows), np.concatenate(rhs)
    if movable is not None:
        mask = np.zeros(n, bool)
        mask[movable] = True
        J = J * np.repeat(mask, d)
    return sla.lstsq(J, r, lapack_driver="gelsd")[0].reshape(n, d)


@SETTINGS
@given(case=linear_cases())
def test_mixed_linear_constraints_hold_and_are_minimal(case):
    c, cons = case
    c2 = constrain(c, cons)
    for k in cons:
        if isinstance(k, Position):
            got, want = c2.evaluate(k.u), k.point
        else:
            order = 1 if isinstance(k, Tangent) else k.order
            got, want = c2.derivatives(k.u, order)[order], k.vector
        assert_allclose(got, want, atol=HOLD * max(1.0, np.abs(want).max()))
    dP = c2.control_points - c.control_points
    ref = _linear_oracle(c, cons)
    assert_allclose(dP, ref, atol=ORACLE * max(1.0, np.abs(ref).max()))


def test_window_keeps_the_edit_local_and_is_minimal_within_it():
    c = cubic(20)
    cons = [Position(0.5, c.evaluate(0.5) + [0, 1, 0]), Tangent(0.5, [5.0, 0, 0])]
    movable = np.arange(7, 14)
    c2 = constrain(c, cons, movable=movable)
    dP = c2.control_points - c.control_points
    assert np.all(dP[:7] == 0) and np.all(dP[14:] == 0)
    assert_allclose(dP, _linear_oracle(c, cons, movable), atol=1e-10)
    # A mask and a slice mean the same window.
    mask = np.zeros(20, bool)
    mask[7:14] = True
    assert_allclose(constrain(c, cons, movable=mask).control_points, c2.control_points, atol=1e-14)
    assert_allclose(constrain(c, cons, movable=slice(7, 14)).control_points, c2.control_points, atol=1e-14)


def test_direction_only_tangent():
    c = cubic(10, 3, seed=3)
    u = 0.4
    t = np.array([1.0, 1.0, 0.5])
    c2 = constrain(c, [Tangent(u, t, direction_only=True)])
    a = c2.derivatives(u, 1)[1]
    e = t / np.linalg.norm(t)
    assert np.linalg.norm(np.cross(a, e)) <= HOLD * np.linalg.norm(a) and a @ e > 0
    # Oracle: the linear system Q^T C'(u) = 0, Q the complement of the direction.
    Q = sla.null_space(e[None])
    J = np.kron(basis_rows(c, u, 1)[1], Q.T)
    y = sla.lstsq(J, -Q.T @ c.derivatives(u, 1)[1], lapack_driver="gelsd")[0]
    assert_allclose((c2.control_points - c.control_points).ravel(), y, atol=1e-10)


def test_direction_only_tangent_reversed_keeps_the_speed():
    c = cubic(10, 2, seed=4)
    u = 0.5
    a0 = c.derivatives(u, 1)[1]
    c2 = constrain(c, [Tangent(u, -a0, direction_only=True)])
    a = c2.derivatives(u, 1)[1]
    assert_allclose(a, -a0, atol=HOLD * np.linalg.norm(a0))


def test_tangent_magnitude_only():
    c = cubic(10, 3, seed=5)
    c2 = constrain(c, [Tangent(0.6, 3.5, magnitude_only=True), Position(0.2, c.evaluate(0.2))])
    assert abs(np.linalg.norm(c2.derivatives(0.6, 1)[1]) - 3.5) <= HOLD * 3.5
    assert_allclose(c2.evaluate(0.2), c.evaluate(0.2), atol=1e-12 * scale(c))


# ---------------------------------------------------------------------------------------- curvature
def _check_first_order_optimal(c, c2, cons, tol=1e-6):
    """dP is in the row space of the Jacobian of all constraints at the solution (KKT)."""
    n, d = c.n_poles, c.dim
    P2 = c2.control_points

    def F(x):
        cc = BSplineCurve(c.degree, c.knots, x.reshape(n, d), c.weights)
        out = []
        for k in cons:
            if isinstance(k, Position):
                out.append(cc.evaluate(k.u) - k.point)
            elif isinstance(k, Tangent):
                out.append(cc.derivatives(k.u, 1)[1] - k.vector)
            else:
                out.append(curvature(cc, k.u) - k.value)
        return np.concatenate(out)

    x = P2.ravel()
    h = 1e-7
    J = np.stack([(F(x + h * e) - F(x - h * e)) / (2 * h) for e in np.eye(x.size)], axis=1)
    dP = (P2 - c.control_points).ravel()
    proj = J.T @ sla.lstsq(J.T, dP, lapack_driver="gelsd")[0]
    assert np.linalg.norm(dP - proj) <= tol * np.linalg.norm(dP)
    return F


@pytest.mark.parametrize("rational", [False, True])
def test_triple_constraint_with_curvature_vector(rational):
    """Position, tangent and curvature at one parameter (course §4-11, §4-12)."""
    c = cubic(12, 3, seed=6, rational=rational)
    u = 0.45
    T = np.array([1.0, 0.2, 0.0]) * 8
    n1 = np.array([-0.2, 1.0, 0.0]) / np.hypot(0.2, 1.0)
    kappa = 0.3 * n1 + 0.4 * np.array([0.0, 0.0, 1.0])  # perpendicular to T: |kappa| = 0.5, radius 2
    cons = [Position(u, c.evaluate(u) + [0, 0.3, 0.1]), Tangent(u, T), Curvature(u, kappa)]
    c2 = constrain(c, cons)
    assert_allclose(c2.evaluate(u), cons[0].point, atol=HOLD * scale(c2))
    assert_allclose(c2.derivatives(u, 1)[1], T, atol=HOLD * 8)
    assert_allclose(curvature(c2, u), kappa, atol=HOLD)
    if not rational:
        assert c2.weights is None
    else:
        assert np.array_equal(c2.weights, c.weights)
    _check_first_order_optimal(c, c2, cons)


@pytest.mark.filterwarnings("ignore:delta_grad == 0.0")
def test_curvature_mixed_over_several_parameters_and_minimal_against_trust_constr():
    """Curvature at two parameters and a position between: a hard request (the tangents must turn
    by ~25 degrees) that exercises the SLSQP fallback. No smaller feasible change is found by an
    independent optimiser (SciPy's trust-region SQP on the unreduced problem, numeric Jacobians)."""
    c = cubic(9, 2, seed=7)
    cons = [Curvature(0.3, [0.0, 0.8]), Position(0.6, c.evaluate(0.6) + [0.0, 0.4]), Curvature(0.85, [0.0, -0.5])]
    c2 = constrain(c, cons)
    F = _check_first_order_optimal(c, c2, cons)
    assert np.abs(F(c2.control_points.ravel())).max() <= HOLD
    x0 = c.control_points.ravel()
    ours = np.linalg.norm(c2.control_points.ravel() - x0)
    res = minimize(lambda x: 0.5 * np.sum((x - x0) ** 2), x0, jac=lambda x: x - x0, hess=lambda x: np.eye(x.size),
                   method="trust-constr", constraints=[NonlinearConstraint(F, 0.0, 0.0)],
                   options={"gtol": 1e-10, "xtol": 1e-12, "maxiter": 3000})
    assert np.abs(F(res.x)).max() < 1e-8
    assert ours <= np.linalg.norm(res.x - x0) * (1 + 1e-6)


@test_settings(20)
@given(seed=st.integers(0, 10_000), dim=st.integers(2, 3), rational=st.booleans(), fu=st.floats(0.15, 0.85),
       amount=st.floats(0.05, 1.0), with_position=st.booleans())
def test_curvature_random_edits_hold_and_are_first_order_optimal(seed, dim, rational, fu, amount, with_position):
    c = cubic(10, dim, seed=seed, rational=rational)
    rng = np.random.default_rng(seed)
    a = c.derivatives(fu, 1)[1]
    e = a / np.linalg.norm(a)
    delta = rng.standard_normal(dim)
    delta -= (delta @ e) * e  # perpendicular to the current tangent (the tangent may still turn)
    kappa = curvature(c, fu) + amount * delta / max(np.linalg.norm(delta), 1e-12)
    cons = [Curvature(fu, kappa)]
    if with_position:
        v = 0.05 if fu > 0.5 else 0.95
        cons.append(Position(v, c.evaluate(v)))
    c2 = constrain(c, cons)
    assert_allclose(curvature(c2, fu), kappa, atol=HOLD * max(1.0, np.abs(kappa).max()))
    if with_position:
        assert_allclose(c2.evaluate(cons[1].u), cons[1].point, atol=1e-12 * scale(c2))
    _check_first_order_optimal(c, c2, cons, tol=1e-5)


def test_curvature_radius_space_and_signed_planar():
    c3 = cubic(10, 3, seed=8)
    c3b = constrain(c3, [Curvature(0.5, 2.5)])
    assert abs(np.linalg.norm(curvature(c3b, 0.5)) - 1 / 2.5) <= HOLD
    c2 = cubic(10, 2, seed=9)
    for r in (1.5, -4.0):
        cc = constrain(c2, [Curvature(0.5, r), Position(0.5, c2.evaluate(0.5))])
        _, a, b = cc.derivatives(0.5, 2)
        k = (a[0] * b[1] - a[1] * b[0]) / np.linalg.norm(a) ** 3
        assert abs(k - 1 / r) <= HOLD
        assert_allclose(cc.evaluate(0.5), c2.evaluate(0.5), atol=1e-12 * scale(c2))


@pytest.mark.parametrize("dim", [2, 3])
def test_infinite_radius_flattens(dim):
    c = cubic(10, dim, seed=10)
    c2 = constrain(c, [Curvature(0.5, np.inf)])
    assert np.abs(curvature(c2, 0.5)).max() <= HOLD


def test_curvature_with_window_and_weights():
    c = cubic(16, 3, seed=11)
    w = np.ones(16)
    w[8] = 100.0
    a = c.derivatives(0.5, 1)[1]
    e = np.cross(a, [0.0, 0.0, 1.0])
    kappa = 0.6 * np.cross(a, e) / np.linalg.norm(np.cross(a, e))  # perpendicular to the kept tangent
    cons = [Curvature(0.5, kappa), Tangent(0.5, a)]
    c2 = constrain(c, cons, movable=range(5, 12), weights=w)
    dP = c2.control_points - c.control_points
    assert np.all(dP[:5] == 0) and np.all(dP[12:] == 0)
    assert np.linalg.norm(dP[8]) < 0.1 * np.linalg.norm(dP, axis=1).max()  # the heavy pole hardly moves
    assert_allclose(curvature(c2, 0.5), kappa, atol=HOLD)
    assert_allclose(c2.derivatives(0.5, 1)[1], a, atol=HOLD * np.abs(a).max())


# ---------------------------------------------------------------------------------------- invariance
@SETTINGS
@given(seed=st.integers(0, 2**31), case=linear_cases())
def test_rigid_motion_invariance(seed, case):
    """min-norm edits commute with rotations + translations of the whole problem."""
    c, cons = case
    d = c.dim
    rng = np.random.default_rng(seed)
    Q, _ = np.linalg.qr(rng.standard_normal((d, d)))
    b = rng.uniform(-5, 5, d)

    def move(k):
        if isinstance(k, Position):
            return Position(k.u, Q @ k.point + b)
        if isinstance(k, Tangent):
            return Tangent(k.u, Q @ k.vector)
        return Derivative(k.u, k.order, Q @ k.vector)

    left = constrain(c.transform(Q, b), [move(k) for k in cons])
    right = constrain(c, cons).transform(Q, b)
    assert_allclose(left.control_points, right.control_points, atol=1e-9 * max(scale(left), 10))


# ---------------------------------------------------------------------------------------- Dragger
def test_dragger_matches_constrain_for_new_targets():
    c = cubic(200, 3, seed=12)
    u = [0.3, 0.3, 0.7]
    kinds = [Position(0.3, c.evaluate(0.3)), Tangent(0.3, c.derivatives(0.3, 1)[1]), Position(0.7, c.evaluate(0.7))]
    drag = Dragger(c, kinds, movable=slice(40, 160))
    assert PreparedConstraints is Dragger
    assert drag.operator.shape == (drag.active.size, 3)
    assert_allclose(drag.apply().control_points, c.control_points, atol=1e-12)
    rng = np.random.default_rng(0)
    for _ in range(5):
        T = drag.current + rng.uniform(-1, 1, (3, 3))
        got = drag.apply(T)
        want = constrain(c, [Position(u[0], T[0]), Tangent(u[1], T[1]), Position(u[2], T[2])], movable=slice(40, 160))
        assert_allclose(got.control_points, want.control_points, atol=1e-11)
        assert_allclose(got.evaluate(0.7), T[2], atol=1e-12 * 10)
    assert c.control_points.flags.writeable is False


def test_dragger_rejects_nonlinear_and_bad_targets():
    c = cubic()
    with pytest.raises(InvalidGeometryError, match="use constrain"):
        Dragger(c, [Curvature(0.5, 2.0)])
    with pytest.raises(InvalidGeometryError, match="use constrain"):
        Dragger(c, [Tangent(0.5, [1, 0, 0], direction_only=True)])
    drag = Dragger(c, [Position(0.5, c.evaluate(0.5))])
    with pytest.raises(InvalidGeometryError, match=r"targets: expected shape \(1, 3\)"):
        drag.apply(np.zeros((2, 3)))
    with pytest.raises(InvalidGeometryError, match="finite"):
        drag.apply([[np.nan, 0, 0]])


def test_dragger_with_redundant_constraints_checks_targets():
    c = cubic()
    p = c.evaluate(0.5)
    drag = Dragger(c, [Position(0.5, p), Position(0.5, p)])
    assert_allclose(drag.apply([p + 1, p + 1]).evaluate(0.5), p + 1, atol=1e-12 * 10)
    with pytest.raises(ConstraintError, match="conflicting"):
        drag.apply([p + 1, p + 2])


# ---------------------------------------------------------------------------------------- errors
def test_bad_requests_raise_clear_errors_and_leave_the_curve_alone():
    c = cubic(8, 3)
    P0 = c.control_points.copy()
    lo, hi = c.domain
    cases = [
        (lambda: drag_point(c, hi + 1, [0, 0, 0]), ParameterError, r"constraints\[0\].u: parameter .* outside the domain"),
        (lambda: drag_point(c, 0.5, [0, 0, 0], 5, 3), InvalidGeometryError, "empty"),
        (lambda: drag_point(c, 0.5, [0, 0, 0], 0, 8), InvalidGeometryError, r"last: pole index 8 is out of range 0..7"),
        (lambda: drag_point(c, 0.5, [0, 0, 0], -1, 3), InvalidGeometryError, "first: pole index -1"),
        (lambda: drag_point(c, 0.05, [0, 0, 0], 6, 7), ConstraintError, "no movable pole acts"),
        (lambda: drag_point(c, 0.5, [0, 0]), InvalidGeometryError, r"expected shape \(3,\)"),
        (lambda: constrain(c, []), InvalidGeometryError, "at least one constraint"),
        (lambda: constrain(c, [Position(0.5, [0, 0, 0])], movable=[]), InvalidGeometryError, "empty"),
        (lambda: constrain(c, [Position(0.5, [0, 0, 0])], movable=[2, 9]), InvalidGeometryError, "out of range"),
        (lambda: constrain(c, ["point"]), InvalidGeometryError, "expected Position, Tangent"),
        (lambda: constrain(c, [Derivative(0.5, 4, [0, 0, 0])]), InvalidGeometryError, "no non-zero derivative of order 4"),
        (lambda: constrain(c, [Position(0.5, [0, 0, 0])], weights=np.zeros(8)), InvalidGeometryError, "weights"),
        (lambda: Tangent(0.5, [0, 0, 0], direction_only=True), InvalidGeometryError, "non-zero"),
        (lambda: Curvature(0.5, 0.0), InvalidGeometryError, "non-zero"),
        (lambda: Position(np.nan, [0, 0, 0]), ParameterError, "finite"),
    ]
    for call, exc, match in cases:
        with pytest.raises(exc, match=match):
            call()
    assert np.array_equal(c.control_points, P0)


def test_conflicting_positions_are_named():
    c = cubic()
    with pytest.raises(ConstraintError, match="conflicting") as info:
        constrain(c, [Position(0.2, [0, 0, 0]), Position(0.5, [1, 1, 1]), Position(0.5, [1, 1, 2])])
    assert set(info.value.rows) == {1, 2}
    assert all("Position(u=0.5)" in s for s in info.value.labels)


def test_more_constraints_than_free_poles():
    c = cubic()
    with pytest.raises(ConstraintError, match=r"scalar conditions, 3 free coordinates = 1 active poles"):
        constrain(c, [Position(0.5, c.evaluate(0.5) + 1), Tangent(0.5, [1, 2, 3])], movable=[5])


def test_curvature_not_perpendicular_to_prescribed_tangent_conflicts():
    c = cubic()
    with pytest.raises(ConstraintError) as info:
        constrain(c, [Tangent(0.5, [1.0, 0, 0]), Curvature(0.5, [0.5, 0.5, 0])])
    assert set(info.value.rows) == {0, 1}


def test_curvature_errors():
    line = BSplineCurve(3, [0, 0, 0, 0, 1, 1, 1, 1], np.linspace([0, 0, 0], [3, 0, 0], 4))
    with pytest.raises(ConstraintError, match="straight"):
        constrain(line, [Curvature(0.5, 2.0)])
    poly = BSplineCurve(1, [0, 0, 0.5, 1, 1], [[0, 0], [1, 1], [2, 0]])
    with pytest.raises(ConstraintError, match="degree-1"):
        constrain(poly, [Curvature(0.25, 1.0)])
    # A radius smaller than the poles of the window can make: the iteration cannot converge.
    c = cubic(10, 3, seed=2)
    with pytest.raises((ConvergenceError, ConstraintError)):
        constrain(c, [Curvature(0.5, [0, 0, 50.0]), Tangent(0.5, c.derivatives(0.5, 1)[1])], max_iter=1)


def test_tangent_vanishing_for_speed_and_curvature():
    c = BSplineCurve(2, [0, 0, 0, 1, 1, 1], [[0, 0], [0, 0], [1, 0]])  # C'(0) = 0
    with pytest.raises(ConstraintError, match="tangent vanishes"):
        constrain(c, [Curvature(0.0, [0.0, 1.0])])


# ---------------------------------------------------------------------------------------- surfaces
@SETTINGS
@given(s=surfaces(dims=st.just(3), max_extra_poles=3), fu=fractions, fv=fractions,
       target=st.lists(st.floats(-10, 10), min_size=3, max_size=3), wu=st.tuples(fractions, fractions),
       wv=st.tuples(fractions, fractions))
def test_drag_surface_point_closed_form(s, fu, fv, target, wu, wv):
    (u0, u1), (v0, v1) = s.domain
    u, v = u0 + fu * (u1 - u0), v0 + fv * (v1 - v0)
    nu, nv = s.n_poles
    (i1, i2), (j1, j2) = _window(wu, nu), _window(wv, nv)
    R = surface_rows(s, u, v)[0].reshape(nu, nv)
    mask = np.zeros((nu, nv), bool)
    mask[i1 : i2 + 1, j1 : j2 + 1] = True
    Rw = np.where(mask, R, 0.0)
    T = np.array(target)
    if not np.any(Rw != 0):
        with pytest.raises(ConstraintError, match=r"no pole of the window .* acts"):
            drag_surface_point(s, u, v, T, window=((i1, i2), (j1, j2)))
        return
    assume(np.sum(Rw**2) > 1e-6)
    s2 = drag_surface_point(s, u, v, T, window=((i1, i2), (j1, j2)))
    sc = max(1.0, np.abs(s2.control_points).max(), np.abs(s.control_points).max())
    assert_allclose(s2.evaluate(u, v), T, atol=1e-11 * sc)
    r = T - s.evaluate(u, v)
    expect = Rw[..., None] * r / np.sum(Rw**2)
    assert_allclose(s2.control_points - s.control_points, expect, atol=ORACLE * sc)
    assert np.all((s2.control_points - s.control_points)[~mask] == 0)


@pytest.mark.parametrize("rational", [False, True])
def test_drag_surface_point_with_tangent_plane_and_partials(rational):
    rng = np.random.default_rng(13)
    U = np.r_[[0.0] * 4, 0.3, 0.6, [1.0] * 4]
    g = np.linspace(0, 5, 6)
    net = np.stack(np.meshgrid(g, g, indexing="ij"), -1)
    net = np.concatenate([net, rng.uniform(-0.3, 0.3, (6, 6, 1))], -1)
    s = BSplineSurface((3, 3), (U, U), net, rng.uniform(0.5, 2, (6, 6)) if rational else None)
    u, v = 0.45, 0.55
    n = np.array([0.3, -0.2, 1.0])
    T = s.evaluate(u, v) + [0, 0, 0.7]
    s2 = drag_surface_point(s, u, v, T, normal=n)
    assert_allclose(s2.evaluate(u, v), T, atol=1e-12 * 10)
    nn = s2.normal(u, v)
    assert np.linalg.norm(np.cross(nn, n / np.linalg.norm(n))) <= 1e-10 and nn @ n > 0
    # Oracle: min-norm via scipy on rows from the identity net.
    G = surface_rows(s, u, v)
    e = n / np.linalg.norm(n)
    J = np.vstack([np.kron(G[0], np.eye(3)), np.kron(G[1], e[None]), np.kron(G[2], e[None])])
    D0 = G @ s.control_points.reshape(36, 3)
    r = np.r_[T - D0[0], -e @ D0[1], -e @ D0[2]]
    y = sla.lstsq(J, r, lapack_driver="gelsd")[0]
    assert_allclose((s2.control_points - s.control_points).ravel(), y, atol=1e-10)
    # Partials
    du, dv = np.array([6.0, 0.0, 0.5]), np.array([0.0, 4.0, -0.5])
    s3 = drag_surface_point(s, u, v, None, du=du, dv=dv)
    D = s3.derivatives(u, v, 1)
    assert_allclose(D[1, 0], du, atol=1e-10)
    assert_allclose(D[0, 1], dv, atol=1e-10)
    assert_allclose(D[0, 0], s.evaluate(u, v), atol=1e-12 * 10)
    if rational:
        assert np.array_equal(s3.weights, s.weights)


def test_drag_surface_point_errors():
    U = np.r_[[0.0] * 4, [1.0] * 4]
    g = np.linspace(0, 3, 4)
    net = np.concatenate([np.stack(np.meshgrid(g, g, indexing="ij"), -1), np.zeros((4, 4, 1))], -1)
    s = BSplineSurface((3, 3), (U, U), net)
    with pytest.raises(ConstraintError, match="reversed or degenerate"):
        drag_surface_point(s, 0.5, 0.5, None, normal=[0, 0, -1])
    with pytest.raises(ConstraintError, match="conflicting"):
        drag_surface_point(s, 0.5, 0.5, None, du=[1.0, 0, 1.0], normal=[0, 0, 1])
    with pytest.raises(ConstraintError, match=r"no pole of the window .* acts"):
        drag_surface_point(s, 0.0, 0.0, [0, 0, 1], window=((2, 3), (2, 3)))
    with pytest.raises(InvalidGeometryError, match="window"):
        drag_surface_point(s, 0.5, 0.5, [0, 0, 1], window=((2, 1), (0, 3)))
    with pytest.raises(InvalidGeometryError, match="out of range"):
        drag_surface_point(s, 0.5, 0.5, [0, 0, 1], window=((0, 4), (0, 3)))
    with pytest.raises(ParameterError):
        drag_surface_point(s, 1.5, 0.5, [0, 0, 1])
    s2d = BSplineSurface((3, 3), (U, U), net[..., :2])
    with pytest.raises(InvalidGeometryError, match="3-D surface"):
        drag_surface_point(s2d, 0.5, 0.5, None, normal=[0, 0, 1])


# ------------------------------------------------------------------ drag_surface_point, step by step
def _plate(n: int = 4) -> BSplineSurface:
    U = np.r_[[0.0] * 4, np.linspace(0, 1, n - 2)[1:-1], [1.0] * 4]
    g = np.linspace(0, 3, n)
    net = np.concatenate([np.stack(np.meshgrid(g, g, indexing="ij"), -1), np.zeros((n, n, 1))], -1)
    return BSplineSurface((3, 3), (U, U), net)


def test_surface_edit_window_ranges():
    from occsurf.algorithms.manipulation.surfaces import _window_ranges

    assert _window_ranges(None, (5, 4)) == ((0, 4), (0, 3))
    assert _window_ranges(((1, 3), (np.int64(0), 2)), (5, 4)) == ((1, 3), (0, 2))
    assert all(type(i) is int for pair in _window_ranges(((1, 3), (np.int64(0), 2)), (5, 4)) for i in pair)
    with pytest.raises(InvalidGeometryError, match=r"^window: expected \(\(i1, i2\), \(j1, j2\)\)"):
        _window_ranges((1, 2, 3), (5, 4))
    with pytest.raises(InvalidGeometryError, match=r"^window\[1\]\[1\]: pole index 4 is out of range 0..3"):
        _window_ranges(((0, 1), (0, 4)), (5, 4))
    with pytest.raises(InvalidGeometryError, match=r"^window\[0\]\[0\]: expected a pole index"):
        _window_ranges(((0.5, 1), (0, 1)), (5, 4))
    with pytest.raises(InvalidGeometryError, match=r"^window: empty window \(\(3, 1\), \(0, 1\)\)"):
        _window_ranges(((3, 1), (0, 1)), (5, 4))


def test_surface_edit_active_poles_are_the_window_poles_acting_on_the_requested_rows():
    from occsurf.algorithms.manipulation.surfaces import _active_poles, _surface_basis_rows

    s = _plate(5)
    G = _surface_basis_rows(s, 0.0, 0.0)  # at a corner only pole (0, 0) carries S; S_u, S_v add (1, 0), (0, 1)
    whole = ((0, 4), (0, 4))
    assert _active_poles(G, (5, 5), whole, [0], "corner").tolist() == [0]
    assert _active_poles(G, (5, 5), whole, [0, 1, 2], "corner").tolist() == [0, 1, 5]
    assert _active_poles(G, (5, 5), ((1, 4), (0, 4)), [0, 1], "corner").tolist() == [5]
    with pytest.raises(ConstraintError, match=r"no pole of the window \(\(1, 4\), \(1, 4\)\) acts at corner"):
        _active_poles(G, (5, 5), ((1, 4), (1, 4)), [0, 1, 2], "corner")
    # Inside, the (p + 1) x (q + 1) poles of the span act, in u-major flat order.
    G = _surface_basis_rows(s, 0.4, 0.7)
    act = _active_poles(G, (5, 5), whole, [0], "inside")
    assert act.size == 16 and np.all(np.diff(act) > 0) and np.all(G[0, act] > 0)
    assert np.count_nonzero(G[0]) == 16


def test_surface_edit_conditions_are_the_kronecker_rows_of_the_requests():
    from occsurf.algorithms.manipulation.surfaces import _edit_conditions, _surface_basis_rows

    s = _plate(5)
    G = _surface_basis_rows(s, 0.4, 0.7)
    act = np.flatnonzero(np.any(G != 0, axis=0))
    Ga = G[:, act]
    inv_sw = np.linspace(0.5, 2.0, act.size)
    D0 = G @ s.control_points.reshape(-1, 3)
    T, du = np.array([1.0, 2.0, 3.0]), np.array([3.0, 0.0, 0.5])
    n = np.array([0.0, 0.6, 0.8])
    J, r, names, nrm = _edit_conditions(Ga, inv_sw, D0, T, du, None, 2 * n, "(u=0.4, v=0.7)")
    assert J.shape == (3 + 3 + 2, 3 * act.size) and r.shape == (8,) and len(names) == 8
    assert_allclose(J[:3], np.kron(Ga[0] * inv_sw, np.eye(3)), rtol=0, atol=0)
    assert_allclose(J[3:6], np.kron(Ga[1] * inv_sw, np.eye(3)), rtol=0, atol=0)
    assert_allclose(J[6], np.kron(Ga[1] * inv_sw, n), atol=1e-15)
    assert_allclose(J[7], np.kron(Ga[2] * inv_sw, n), atol=1e-15)
    assert_allclose(r, np.r_[T - D0[0], du - D0[1], -n @ D0[1], -n @ D0[2]], atol=1e-15)
    assert_allclose(nrm, n, atol=1e-15)
    assert names[0] == "position (u=0.4, v=0.7) [0]" and names[6] == "normal.S_u (u=0.4, v=0.7) [0]"
    # target=None keeps the point: zero right-hand side for the position rows.
    J, r, _, nrm = _edit_conditions(Ga, inv_sw, D0, None, None, None, None, "here")
    assert J.shape == (3, 3 * act.size) and np.all(r == 0) and nrm is None
    with pytest.raises(InvalidGeometryError, match=r"^du: expected shape \(3,\), got \(2,\)"):
        _edit_conditions(Ga, inv_sw, D0, T, [1.0, 2.0], None, None, "here")
    with pytest.raises(InvalidGeometryError, match="^normal: expected a non-zero vector"):
        _edit_conditions(Ga, inv_sw, D0, T, None, None, [0.0, 0.0, 0.0], "here")
    with pytest.raises(InvalidGeometryError, match="^normal: needs a 3-D surface, this one has dim 2"):
        _edit_conditions(Ga, inv_sw, D0[:, :2], None, None, None, [0.0, 0.0, 1.0], "here")


def test_surface_edit_min_norm_change_and_its_checks():
    from occsurf.algorithms.manipulation.surfaces import _min_norm_change

    rng = np.random.default_rng(8)
    J = rng.normal(size=(4, 9))
    r = rng.normal(size=4)
    D0 = rng.normal(size=(3, 3))
    y = _min_norm_change(J, r, [f"c{i}" for i in range(4)], D0)
    assert_allclose(y, sla.lstsq(J, r, lapack_driver="gelsd")[0], atol=1e-13)
    J2 = np.vstack([J, J[0]])  # a repeated condition with another target: a conflict, named
    with pytest.raises(ConstraintError, match=r"conflicting.*\(5 conditions, 3 active poles x 3\)") as info:
        _min_norm_change(J2, np.r_[r, r[0] + 1.0], [f"c{i}" for i in range(5)], D0)
    assert "c4" in info.value.labels
    assert_allclose(_min_norm_change(J2, np.r_[r, r[0]], [f"c{i}" for i in range(5)], D0), y, atol=1e-13)


def test_surface_edit_orientation_check():
    from occsurf.algorithms.manipulation.surfaces import _check_orientation

    D1 = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 2.0, 0.0]])  # S_u x S_v along +z
    _check_orientation(D1, np.array([0.0, 0.6, 0.8]), "p")
    with pytest.raises(ConstraintError, match=r"would then be \[ 0\.  0\. -1\.\] \(reversed or degenerate\)"):
        _check_orientation(D1[[0, 2, 1]], np.array([0.0, 0.0, 1.0]), "p")
    with pytest.raises(ConstraintError, match="would then be degenerate"):
        _check_orientation(np.array([[0.0] * 3, [1.0, 0, 0], [2.0, 0, 0]]), np.array([0.0, 0.0, 1.0]), "p")


def test_manipulation_modules_import_no_private_names():
    """surfaces.py takes the parameter check from constraints.py's public as_parameter."""
    import ast
    from pathlib import Path

    import occsurf.algorithms.manipulation as M

    for path in Path(M.__file__).parent.glob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.level and node.module:  # not `from .. import _validate`
                private = [a.name for a in node.names if a.name.startswith("_")]
                assert not private, f"{path.name} imports private names {private} from {node.module}"


# ---------------------------------------------------------------------------------------- boundary
def test_algorithms_modules_do_not_import_occ_or_matplotlib():
    code = (
        "import sys\n"
        "for m in ('OCP', 'cadquery', 'build123d', 'matplotlib'): sys.modules[m] = None\n"
        "import occsurf.algorithms.manipulation.linalg, occsurf.algorithms.manipulation.curves\n"
        "assert not any(k.startswith('matplotlib.') for k in sys.modules)\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True, cwd=str(__import__("pathlib").Path(__file__).parents[2]))
