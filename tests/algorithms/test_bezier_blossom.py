"""occsurf.algorithms.kernel.bezier: Bernstein basis, de Casteljau, blossom, subdivision, degree raising (course §2-1..2-6).

Oracles: scipy's ``BPoly`` (its own Bernstein-form evaluation), the explicit Bernstein sum, and
the B-spline classes (a Bézier segment is a clamped B-spline with a single span).
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from numpy.testing import assert_allclose, assert_array_equal
from scipy.interpolate import BPoly

from occsurf.algorithms import BSplineCurve
from occsurf.algorithms.kernel.bezier import bernstein, bezier_blossom, de_casteljau, elevate_bezier, subdivide

from .strategies import COORD, fractions, poles, test_settings

# All inputs are convex combinations on [0, 1] (or affine ones with coefficients up to ~3 for
# arguments in [-1, 2]): round-off is a few ulps of COORD per level, degree <= 9 levels.
EXACT = 1e-12
SETTINGS = test_settings(40)

degrees = st.integers(1, 9)


@st.composite
def segments(draw, degree=degrees):
    n = draw(degree)
    d = draw(st.integers(1, 3))
    return draw(poles((n + 1, d)))


params = st.lists(fractions, min_size=1, max_size=10).map(np.array)


@SETTINGS
@given(n=degrees, t=params)
def test_bernstein_partition_of_unity_and_nonnegative(n, t):
    B = bernstein(n, t)
    assert B.shape == (t.size, n + 1)
    assert_allclose(B.sum(axis=1), 1.0, rtol=0, atol=1e-14)
    assert np.all(B >= 0)
    # Symmetry B_{i,n}(t) = B_{n-i,n}(1 - t).
    assert_allclose(bernstein(n, 1 - t)[:, ::-1], B, rtol=0, atol=1e-14)


@SETTINGS
@given(P=segments(), t=params)
def test_de_casteljau_matches_bernstein_sum_and_scipy_bpoly(P, t):
    n = P.shape[0] - 1
    x = de_casteljau(P, t)
    assert x.shape == (t.size, P.shape[1])
    assert_allclose(x, bernstein(n, t) @ P, rtol=0, atol=EXACT * COORD)
    assert_allclose(x, BPoly(P[:, None, :], [0.0, 1.0])(t), rtol=0, atol=EXACT * COORD)
    # Scalar parameter: one point; the ends interpolate the end control points exactly.
    assert de_casteljau(P, 0.25).shape == (P.shape[1],)
    assert_array_equal(de_casteljau(P, 0.0), P[0])
    assert_allclose(de_casteljau(P, 1.0), P[-1], rtol=0, atol=0)


@SETTINGS
@given(P=segments(), t=params)
def test_bezier_segment_is_a_single_span_bspline(P, t):
    n = P.shape[0] - 1
    c = BSplineCurve(n, [0.0] * (n + 1) + [1.0] * (n + 1), P)
    assert_allclose(c.evaluate(t), de_casteljau(P, t), rtol=0, atol=EXACT * COORD)


def test_degree_zero_segment_is_constant():
    P = np.array([[1.5, -2.0]])
    assert_array_equal(de_casteljau(P, [0.0, 0.3, 1.0]), np.repeat(P, 3, axis=0))


@SETTINGS
@given(data=st.data())
def test_subdivision_halves_reproduce_the_segment(data):
    P = data.draw(segments())
    t = data.draw(st.floats(0.01, 0.99))
    left, right = subdivide(P, t)
    assert left.shape == right.shape == P.shape
    s = data.draw(params)
    assert_allclose(de_casteljau(left, s), de_casteljau(P, t * s), rtol=0, atol=EXACT * COORD)
    assert_allclose(de_casteljau(right, s), de_casteljau(P, t + (1 - t) * s), rtol=0, atol=EXACT * COORD)
    assert_array_equal(left[0], P[0])
    assert_array_equal(right[-1], P[-1])
    assert_array_equal(left[-1], right[0])
    # The halves' control points are blossom values (course §2-4): f(0^(n-i), t^i), f(t^(n-i), 1^i).
    n = P.shape[0] - 1
    i = np.arange(n + 1)[:, None]
    j = np.arange(n)[None, :]
    args_left = np.where(j < n - i, 0.0, t)
    args_right = np.where(j < n - i, t, 1.0)
    assert_allclose(left, bezier_blossom(P, args_left), rtol=0, atol=EXACT * COORD)
    assert_allclose(right, bezier_blossom(P, args_right), rtol=0, atol=EXACT * COORD)


def test_subdivide_default_is_the_midpoint():
    P = np.array([[0.0, 0.0], [1.0, 2.0], [3.0, 2.0], [4.0, 0.0]])
    left, right = subdivide(P)
    assert_allclose(left[-1], de_casteljau(P, 0.5), rtol=0, atol=1e-15)
    assert_allclose(left, [[0, 0], [0.5, 1], [1.25, 1.5], [2, 1.5]], rtol=0, atol=1e-15)
    assert_allclose(right, [[2, 1.5], [2.75, 1.5], [3.5, 1], [4, 0]], rtol=0, atol=1e-15)


@SETTINGS
@given(P=segments(degree=st.integers(1, 8)), times=st.integers(1, 3), t=params)
def test_elevate_bezier_keeps_the_curve(P, times, t):
    Q = elevate_bezier(P, times)
    assert Q.shape == (P.shape[0] + times, P.shape[1])
    assert_array_equal(Q[0], P[0])
    assert_allclose(Q[-1], P[-1], rtol=0, atol=1e-15 * COORD)
    assert_allclose(de_casteljau(Q, t), de_casteljau(P, t), rtol=0, atol=EXACT * COORD)


def test_elevate_bezier_closed_form_line_to_quadratic():
    # Course §2-6: a line raised to degree 2 gets its midpoint as the middle control point.
    assert_allclose(elevate_bezier([[0.0, 0.0], [2.0, 4.0]]), [[0, 0], [1, 2], [2, 4]], rtol=0, atol=0)


@SETTINGS
@given(data=st.data())
def test_bezier_blossom_symmetric_diagonal_and_multi_affine(data):
    P = data.draw(segments())
    n = P.shape[0] - 1
    x = np.array(data.draw(st.lists(st.floats(-1, 2), min_size=n, max_size=n)))
    perm = list(data.draw(st.permutations(range(n))))
    f = bezier_blossom(P, x[None])
    # Arguments in [-1, 2]: each level is an affine combination with coefficients <= 3 in size.
    scale = COORD * 3.0**n
    assert_allclose(bezier_blossom(P, x[perm][None]), f, rtol=0, atol=EXACT * scale)
    t = data.draw(params)
    assert_allclose(bezier_blossom(P, np.repeat(t[:, None], n, axis=1)), de_casteljau(P, t), rtol=0,
                    atol=EXACT * COORD)
    i = data.draw(st.integers(0, n - 1))
    y, z = data.draw(st.floats(-1, 2)), data.draw(st.floats(-1, 2))
    a = data.draw(st.floats(-1, 2))
    args = np.repeat(x[None], 3, axis=0)
    args[:, i] = [a * y + (1 - a) * z, y, z]
    fz, fy, fz2 = bezier_blossom(P, args)
    assert_allclose(fz, a * fy + (1 - a) * fz2, rtol=0, atol=EXACT * scale * 4)


@SETTINGS
@given(P=segments())
def test_control_points_are_blossom_values_at_the_ends(P):
    # P_i = f(0^(n-i), 1^i) (course §2-3).
    n = P.shape[0] - 1
    i = np.arange(n + 1)[:, None]
    args = np.where(np.arange(n)[None, :] < n - i, 0.0, 1.0)
    assert_allclose(bezier_blossom(P, args), P, rtol=0, atol=0)


def test_bezier_blossom_rejects_wrong_number_of_arguments():
    with pytest.raises(ValueError, match="args"):
        bezier_blossom(np.zeros((4, 2)), np.zeros((1, 2)))


@SETTINGS
@given(P=segments(degree=st.integers(1, 6)))
def test_bspline_to_bezier_poles_agree_with_de_casteljau(P):
    # A clamped two-span B-spline: its Bézier pieces, re-parametrised to [0, 1], are Bézier segments.
    n = P.shape[0] - 1
    extra = np.vstack((P, P[-1:] + 1.0))  # one more pole -> a knot at 0.4
    c = BSplineCurve(n, [0.0] * (n + 1) + [0.4] + [1.0] * (n + 1), extra)
    for seg in c.to_bezier():
        a, b = seg.domain
        s = np.linspace(0, 1, 7)
        u = np.minimum(a + s * (b - a), b)
        assert_allclose(de_casteljau(seg.control_points, s), c.evaluate(u), rtol=0, atol=EXACT * (COORD + 1))
