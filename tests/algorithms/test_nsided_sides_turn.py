"""Tests of :func:`turn_end_tangent` (algorithms/topology/nsided_sides.py, issue 12): a G0-only hole
side's end tangent turned into the G1 neighbour's plane at a corner, the side moving by at most a
budget.

Invariants (hypothesis, polynomial and rational curves of degree 1 to 5, either end, angles 0.01 to
5 deg, budgets 1e-8 to 1e-4 of a unit-sized curve): the end point stays; the new end tangent lies
in the plane and is the old one's projection on it; the second derivative at the end is kept (the
corner twist); the other end keeps point, tangent and second derivative; the curve moves by at
most the budget (sampled densely, clustered towards the end, compared at equal parameters, which
bounds the geometric distance) and not at all beyond the three inserted knots.

Tolerances: points and first derivatives are the refined curve's (Oslo knot insertion: round-off,
1e-12 of the pole scale); the turned tangent is the projection to 100 machine epsilons of the
pole scale over the end leg (~e |C'| / p, e the first inserted span: 2.3e-9 deg seen); the second
derivative at the end is a sum of poles times basis derivatives of size 1/e^2, so it is kept to
1e3 * machine epsilon * pole scale / e^2;
the movement is bounded by max(|D|, |E|) exactly (the rational basis is non-negative and sums to
at most one), checked with a 1e-9 relative margin for the evaluation's round-off.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from occsurf.algorithms.errors import InvalidGeometryError
from occsurf.algorithms.kernel.curve import BSplineCurve
from occsurf.algorithms.topology.nsided_sides import turn_end_tangent
from tests.algorithms.strategies import test_settings

EPS = np.finfo(float).eps


def _curve(seed: int, degree: int, rational: bool) -> BSplineCurve:
    rng = np.random.default_rng(seed)
    n = degree + 1 + int(rng.integers(0, 4))
    P = np.c_[np.linspace(0.0, 1.0, n), np.zeros(n), np.zeros(n)] + 0.3 * rng.uniform(-1, 1, (n, 3))
    inner = np.sort(rng.uniform(0.1, 0.9, n - degree - 1))
    knots = np.r_[np.zeros(degree + 1), inner, np.ones(degree + 1)]
    w = rng.uniform(0.5, 2.0, n) if rational else None
    return BSplineCurve(degree, knots, P, w)


def _d(c: BSplineCurve, u: float, order: int = 2) -> np.ndarray:
    return c.derivatives(np.array([u]), order)[0]


def _deg(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.degrees(np.arctan2(np.linalg.norm(np.cross(a, b)), a @ b)))


@test_settings(60)
@given(seed=st.integers(0, 2**32 - 1), degree=st.integers(1, 5), rational=st.booleans(), end=st.sampled_from([0, 1]),
       beta=st.floats(0.01, 5.0), log_budget=st.floats(-8.0, -4.0))
def test_turned_tangent_in_the_plane_within_the_budget(seed, degree, rational, end, beta, log_budget) -> None:
    c = _curve(seed, degree, rational)
    lo, hi = c.domain
    at, other = (lo, hi) if end == 0 else (hi, lo)
    before = _d(c, at)
    t = before[1] / np.linalg.norm(before[1]) * (1 if end == 0 else -1)  # into the side, from the corner
    rng = np.random.default_rng(seed + 1)
    u = np.cross(t, rng.normal(size=3))
    u /= np.linalg.norm(u)
    normal = np.cos(np.radians(beta)) * u + np.sin(np.radians(beta)) * t  # t leaves the plane by beta
    budget = 10.0 ** log_budget
    out, turned = turn_end_tangent(c, end, normal, budget)
    assert turned == pytest.approx(beta, rel=1e-9)
    scale = float(np.abs(c.control_points).max())
    after = _d(out, at)
    np.testing.assert_allclose(after[0], before[0], rtol=0, atol=1e-12 * scale)
    proj = before[1] - (before[1] @ normal) * normal
    Q = np.asarray(out.control_points)
    leg = float(np.linalg.norm(Q[1] - Q[0] if end == 0 else Q[-2] - Q[-1]))
    assert _deg(after[1], proj) <= np.degrees(1e2 * EPS * scale / leg)  # the pole's round-off over the leg
    e = float(np.sort(np.abs(np.unique(out.knots) - at))[1])  # the first inserted span
    np.testing.assert_allclose(after[2], before[2], rtol=0, atol=1e3 * EPS * scale / e ** 2)
    far_before, far_after = _d(c, other), _d(out, other)
    np.testing.assert_allclose(far_after, far_before, rtol=0, atol=1e-9 * scale * max(1.0, np.abs(far_before).max()))
    g = np.geomspace(1e-12, 1.0, 400) * (hi - lo)
    s = np.unique(np.r_[np.linspace(lo, hi, 2001), lo + g, hi - g])
    s = s[(s >= lo) & (s <= hi)]
    moved = np.linalg.norm(out.evaluate(s) - c.evaluate(s), axis=1)
    assert moved.max() <= budget * (1 + 1e-9) + 1e-12 * scale
    assert moved[np.abs(s - at) > 3 * e * (1 + 1e-9)].max(initial=0.0) <= 1e-12 * scale  # only near the corner


def test_small_angles_are_left_alone() -> None:
    c = _curve(3, 3, False)
    t = _d(c, 0.0)[1]
    n = np.cross(t, [0.0, 0.0, 1.0])
    n /= np.linalg.norm(n)  # t lies in the plane exactly
    out, turned = turn_end_tangent(c, 0, n, 1e-6)
    assert out is c and turned == 0.0
    tilt = np.radians(5e-4)  # below a tenth of FILL_FIT_ANGLE (1e-3 deg)
    out, turned = turn_end_tangent(c, 0, np.cos(tilt) * n + np.sin(tilt) * t / np.linalg.norm(t), 1e-6)
    assert out is c and turned == 0.0
    out, turned = turn_end_tangent(c, 0, np.cos(tilt) * n + np.sin(tilt) * t / np.linalg.norm(t), 1e-6, min_angle=1e-4)
    assert out is not c and turned == pytest.approx(5e-4)


def test_a_line_is_raised_to_a_cubic_and_turned() -> None:
    line = BSplineCurve(1, np.r_[0, 0, 1, 1], np.array([[0.0, 0.0, 0.0], [1.0, 0.0, np.tan(np.radians(0.5))]]))
    out, turned = turn_end_tangent(line, 0, [0.0, 0.0, 1.0], 1e-7)
    assert out.degree == 3 and turned == pytest.approx(0.5)
    t = _d(out, 0.0)[1]
    assert abs(t[2]) <= 1e-12 * np.linalg.norm(t)  # now in the plane z = 0
    assert _d(out, 0.0)[2] == pytest.approx(np.zeros(3), abs=1e-6)  # a line's: zero (1e3 eps / e^2, e ~ 1e-5)
    s = np.linspace(0, 1, 5001)
    assert np.linalg.norm(out.evaluate(s) - line.evaluate(s), axis=1).max() <= 1e-7


@pytest.mark.parametrize("kwargs, word", [(dict(end=2), "end"), (dict(normal=[0, 0, 0]), "normal"),
                                          (dict(normal=[0, np.nan, 1]), "normal"), (dict(budget=0.0), "budget"),
                                          (dict(budget=-1e-6), "budget")])
def test_bad_input_is_named(kwargs, word) -> None:
    args = dict(curve=_curve(5, 3, False), end=0, normal=[0.0, 0.0, 1.0], budget=1e-6) | kwargs
    with pytest.raises(InvalidGeometryError, match=word):
        turn_end_tangent(**args)
