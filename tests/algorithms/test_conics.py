"""Conics as rational quadratics (course §2, §12): closed-form truth and error paths."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from numpy.testing import assert_allclose

from occsurf.algorithms import (
    InvalidGeometryError,
    arc,
    circle,
    conic_arc,
    conic_from_shoulder,
    conic_through_point,
    conic_type,
    ellipse,
)

from .strategies import test_settings

# Exact identities evaluated in double precision: a few ulps of the coordinates' size.
EXACT = 1e-14

finite = st.floats(-100, 100, allow_nan=False)


@test_settings(60, suppress=None)
@given(
    center=st.tuples(finite, finite, finite),
    radius=st.floats(0.01, 100),
    normal=st.tuples(st.floats(-1, 1), st.floats(-1, 1), st.floats(-1, 1)).filter(
        lambda n: np.linalg.norm(n) > 0.1
    ),
)
def test_circle_is_exact_and_planar(center, radius, normal):
    c = circle(center, radius, normal=normal)
    u = np.linspace(*c.domain, 2001)
    p = c.evaluate(u) - np.asarray(center)
    scale = max(1.0, np.abs(center).max(), radius)
    # Radius and plane hold to round-off of the coordinates' magnitude.
    assert np.abs(np.linalg.norm(p, axis=1) - radius).max() <= 8 * EXACT * scale
    n = np.asarray(normal) / np.linalg.norm(normal)
    assert np.abs(p @ n).max() <= 8 * EXACT * scale
    # Counter-clockwise about the normal: (p(u) x p'(u)) . n > 0.
    d = c.derivatives(u[1:-1], 1)
    assert np.all(np.cross(d[:, 0] - center, d[:, 1]) @ n > 0)
    assert c.degree == 2 and c.n_poles == 9 and c.is_rational
    assert_allclose(c.evaluate(c.domain[0]), c.evaluate(c.domain[1]), atol=8 * EXACT * scale)


@test_settings(60, suppress=None)
@given(a0=st.floats(-7, 7), sweep=st.floats(1e-3, 2 * math.pi), r=st.floats(0.1, 10))
def test_arc_end_points_and_radius(a0, sweep, r):
    c = arc([0.0, 0.0], r, a0, a0 + sweep)
    assert_allclose(c.evaluate(a0), [r * math.cos(a0), r * math.sin(a0)], atol=EXACT * 10 * r)
    assert_allclose(c.evaluate(a0 + sweep), [r * math.cos(a0 + sweep), r * math.sin(a0 + sweep)], atol=EXACT * 10 * r)
    p = c.evaluate(np.linspace(a0, a0 + sweep, 501))
    assert np.abs(np.linalg.norm(p, axis=1) - r).max() <= EXACT * 10 * r
    # Pieces of at most 90 degrees: 2k+1 poles with k = ceil(sweep / 90deg).
    assert c.n_poles == 2 * max(1, math.ceil(sweep / (math.pi / 2) - 1e-12)) + 1
    # The arc stays on the swept side: angles increase monotonically.
    ang = np.unwrap(np.arctan2(p[:, 1], p[:, 0]))
    assert np.all(np.diff(ang) > 0)


def test_ellipse_implicit_equation_and_axes():
    e = ellipse([1.0, -2.0, 0.5], 3.0, 1.25, normal=[0, 0, 1], xaxis=[1, 1, 0])
    p = e.evaluate(np.linspace(*e.domain, 1001)) - [1.0, -2.0, 0.5]
    x = p @ (np.array([1, 1, 0]) / math.sqrt(2))
    y = p @ (np.array([-1, 1, 0]) / math.sqrt(2))
    assert np.abs(x**2 / 9 + y**2 / 1.5625 - 1).max() <= 1e-14
    assert np.abs(p[:, 2]).max() <= 1e-15


@pytest.mark.parametrize("w, kind", [(0.5, "ellipse"), (1.0, "parabola"), (2.0, "hyperbola")])
def test_conic_type_matches_implicit_discriminant(w, kind):
    c = conic_arc([0, 0], [1, 1], [2, 0], w)
    assert conic_type(w) == kind
    # Fit the implicit conic a x^2 + b xy + c y^2 + d x + e y + f = 0 through many points and read
    # the type off b^2 - 4ac: the rational quadratic must be that conic, whatever w is.
    p = c.evaluate(np.linspace(0, 1, 50))
    M = np.c_[p[:, 0] ** 2, p[:, 0] * p[:, 1], p[:, 1] ** 2, p[:, 0], p[:, 1], np.ones(len(p))]
    coef = np.linalg.svd(M)[2][-1]
    assert np.abs(M @ coef).max() <= 1e-12
    disc = coef[1] ** 2 - 4 * coef[0] * coef[2]
    expected = {"ellipse": -1, "parabola": 0, "hyperbola": 1}[kind]
    assert (abs(disc) <= 1e-10) if expected == 0 else (np.sign(disc) == expected)


def test_shoulder_point_is_the_midpoint_of_the_curve():
    P0, P1, P2 = np.array([0.0, 0.0]), np.array([1.0, 2.0]), np.array([3.0, 0.0])
    M = (P0 + P2) / 2
    S = M + 0.3 * (P1 - M)
    by_point = conic_from_shoulder(P0, P1, P2, S)
    by_ratio = conic_from_shoulder(P0, P1, P2, 0.3)
    assert_allclose(by_point.evaluate(0.5), S, atol=EXACT)
    assert_allclose(by_point.weights, by_ratio.weights, rtol=1e-15)
    assert_allclose(by_ratio.weights[1], 0.3 / 0.7, rtol=1e-15)


def _cross2(a, b):
    return a[0] * b[1] - a[1] * b[0]


def test_conic_through_point_hits_point_and_tangents():
    P0, T0, P2, T2, Q = [0.0, 0.0], [1.0, 0.2], [3.0, 2.0], [0.1, 1.0], [2.3, 0.6]
    c = conic_through_point(P0, T0, P2, T2, Q)
    # Independent closed form: barycentrics (a, b, c) of Q in the tangent triangle give the
    # parameter of Q through t / (1 - t) = sqrt(c / a).
    P1 = c.control_points[1]
    A = np.c_[np.r_[P0, 1.0], np.r_[P1, 1.0], np.r_[P2, 1.0]]
    a, _, cc = np.linalg.solve(A, np.r_[Q, 1.0])
    r = math.sqrt(cc / a)
    assert_allclose(c.evaluate(r / (1 + r)), Q, atol=1e-14 * 4)
    d = c.derivatives(np.array([0.0, 1.0]), 1)
    assert abs(_cross2(d[0, 1], T0)) <= 1e-14 * np.linalg.norm(d[0, 1]) * np.linalg.norm(T0)
    assert abs(_cross2(d[1, 1], T2)) <= 1e-14 * np.linalg.norm(d[1, 1]) * np.linalg.norm(T2)


def test_conic_errors_name_the_argument():
    with pytest.raises(InvalidGeometryError, match="radius"):
        circle([0, 0, 0], -1.0)
    with pytest.raises(InvalidGeometryError, match="end_angle"):
        arc([0, 0], 1.0, 1.0, 1.0)
    with pytest.raises(InvalidGeometryError, match="normal"):
        circle([0, 0, 0], 1.0, normal=[0, 0, 0])
    with pytest.raises(InvalidGeometryError, match="weight"):
        conic_arc([0, 0], [1, 1], [2, 0], 0.0)
    with pytest.raises(InvalidGeometryError, match="parallel"):
        conic_through_point([0, 0], [1, 0], [0, 1], [1, 0], [0.5, 0.5])
    with pytest.raises(InvalidGeometryError, match="triangle"):
        conic_through_point([0, 0], [1, 0], [2, 2], [0, 1], [5.0, 5.0])
    with pytest.raises(InvalidGeometryError, match="shoulder"):
        conic_from_shoulder([0, 0], [1, 1], [2, 0], 1.5)
