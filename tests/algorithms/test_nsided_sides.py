"""Tests of hole sides described by curves and the neighbour's normals (algorithms/topology/nsided_sides.py).

Closed forms: holes cut from a sphere (sides: great-circle arcs, exact rational quadratics, no
iso-line of any sphere parametrisation) and from a torus (sides: diagonal lines of the (theta, phi)
domain, fitted by :func:`fit_boundary`), refilled with the normals of the exact surface.

Tolerances. G0: the side curve is the boundary itself, so the fill's gap is round-off: 1e-11 of the
hole size for the arcs; the fitted torus sides (up to ~40 spans, some short) go through the
collocation of nsided_poly.represent, whose own check is FILL_REPRESENT_TOL = 1e-9 relative: 1.9e-9 of
the size measured at h = 0.4, 1.9e-8 at h = 0.1, bound 5e-8; likewise the angle to the fitted field, 2.4e-5 deg measured, bound
1e-4 (100x below FILL_FIT_ANGLE). G1: the fill is G1 to the fitted field by construction (1e-6 deg
as in test_nsided.py); the field meets the exact normals within FILL_FIT_ANGLE (0.01 deg), checked
against the closed-form normal at 101 points per side, between the fit's samples. Deviation from
the original surface: the fill is a different G1 surface with the same boundary data, so it departs
from the sphere/torus by an amount that shrinks with the hole; measured (R = 2 sphere, hole radius
h R): 8.0e-3, 1.3e-3, 4.2e-4 for h = 0.5, 0.25, 0.125; torus 3/1, hole 0.4 rad: 1.3e-3, 4.3e-4,
1.2e-4. The bounds are 1.5x the measurements and a decrease of >= 2.5x per halving (an error in
the normals or the orientation gives O(1) deviations, and no convergence).
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from occsurf.algorithms import tolerances
from occsurf.algorithms.errors import InvalidGeometryError
from occsurf.algorithms.kernel.curve import BSplineCurve
from occsurf.algorithms.topology.nsided import fill_hole, measure_fill
from occsurf.algorithms.topology.nsided_sides import (
    blend_normals,
    corner_normals,
    fit_boundary,
    plane_angle,
    side_from_normals,
)
from tests.algorithms.strategies import test_settings

R = 2.0
RT, RR = 3.0, 1.0


def _arc(a, b) -> BSplineCurve:
    a, b = np.asarray(a, float) / np.linalg.norm(a), np.asarray(b, float) / np.linalg.norm(b)
    half = np.arccos(np.clip(a @ b, -1, 1)) / 2
    m = (a + b) / np.linalg.norm(a + b) / np.cos(half)
    return BSplineCurve(2, [0, 0, 0, 1, 1, 1], R * np.array([a, m, b]), np.array([1.0, np.cos(half), 1.0]))


def _sphere_hole(h: float):
    corners = [(h, 0, 1), (0, h, 1), (-h, 0, 1), (0, -0.8 * h, 1)]  # counter-clockwise about +z
    fits = []
    for i in range(4):
        c = _arc(corners[i], corners[(i + 1) % 4])
        s = np.linspace(0, 1, 60)
        fits.append(side_from_normals(c, s, c.evaluate(s) / R))
    return fits


def _torus(th, ph):
    return np.stack([(RT + RR * np.cos(ph)) * np.cos(th), (RT + RR * np.cos(ph)) * np.sin(th), RR * np.sin(ph)], -1)


def _torus_normal(th, ph):
    return np.stack([np.cos(ph) * np.cos(th), np.cos(ph) * np.sin(th), np.sin(ph)], -1)


def _torus_hole(h: float):
    corners = np.array([[0, -h], [h / 4, 0.1 * h], [0, h], [-h / 4, 0]])  # a diamond in (theta, phi)
    fits, gaps = [], []
    t = np.linspace(0, 1, 200)
    for i in range(4):
        pp = corners[i] + (corners[(i + 1) % 4] - corners[i]) * t[:, None]
        c, gap = fit_boundary(t, _torus(pp[:, 0], pp[:, 1]), 1e-8)
        fits.append(side_from_normals(c, t, _torus_normal(pp[:, 0], pp[:, 1])))
        gaps.append(gap)
    return fits, max(gaps)


def _check_g1_to(fill, normal_at, gap_rel: float = 1e-11, angle_deg: float = 1e-6) -> None:
    """The fill's boundary G1 to the exact surface: patch normals vs closed-form normals."""
    q = measure_fill(fill, samples=101)
    assert q.boundary_gap.max() <= gap_rel * fill.size
    assert q.boundary_angle.max() <= angle_deg and q.internal_angle.max() <= angle_deg
    u = np.linspace(0, 1, 101)
    for p in fill.patches:
        for pts, d in ((p.derivatives(u, np.zeros_like(u), 1), None), (p.derivatives(np.zeros_like(u), u, 1), None)):
            n = np.cross(pts[:, 1, 0], pts[:, 0, 1])
            ang = plane_angle(normal_at(pts[:, 0, 0]), pts[:, 1, 0], pts[:, 0, 1]) if d else None
            exact = normal_at(pts[:, 0, 0])
            c = np.abs(np.einsum("ij,ij->i", n / np.linalg.norm(n, axis=1, keepdims=True), exact))
            assert np.degrees(np.arccos(np.clip(c, 0, 1))).max() <= tolerances.FILL_FIT_ANGLE + 1e-6, ang


def test_sphere_hole_is_refilled_g1_and_close_to_the_sphere() -> None:
    devs = []
    for h in (0.5, 0.25, 0.125):
        fits = _sphere_hole(h)
        assert all(f.converged and f.angle <= tolerances.FILL_FIT_ANGLE for f in fits)
        fill = fill_hole([f.side for f in fits])
        assert all(p.is_rational for p in fill.patches)  # the arcs are carried exactly
        _check_g1_to(fill, lambda P: P / np.linalg.norm(P, axis=1, keepdims=True))
        uv = np.linspace(0, 1, 31)
        devs.append(max(np.abs(np.linalg.norm(p.evaluate(uv[:, None], uv[None, :]), axis=-1) - R).max()
                        for p in fill.patches))
    assert devs[0] <= 1.2e-2 and devs[1] <= 2e-3 and devs[2] <= 6.3e-4
    assert devs[0] / devs[1] >= 2.5 and devs[1] / devs[2] >= 2.5


def test_torus_hole_is_refilled_g1_and_close_to_the_torus() -> None:
    devs = []
    for h in (0.4, 0.2, 0.1):
        fits, gap = _torus_hole(h)
        assert gap <= 1e-8
        fill = fill_hole([f.side for f in fits])

        def normal(P):
            th = np.arctan2(P[:, 1], P[:, 0])
            rho = np.hypot(P[:, 0], P[:, 1])
            return _torus_normal(th, np.arctan2(P[:, 2], rho - RT))
        _check_g1_to(fill, normal, gap_rel=5e-8, angle_deg=1e-4)
        uv = np.linspace(0, 1, 31)
        P = np.concatenate([p.evaluate(uv[:, None], uv[None, :]).reshape(-1, 3) for p in fill.patches])
        devs.append(float(np.abs(np.hypot(np.hypot(P[:, 0], P[:, 1]) - RT, P[:, 2]) - RR).max()))
    assert devs[0] <= 2e-3 and devs[1] <= 6.5e-4 and devs[2] <= 1.8e-4
    assert devs[0] / devs[1] >= 2.5 and devs[1] / devs[2] >= 2.5


def test_wrong_orientation_of_the_normals_is_refused() -> None:
    corners = [(0.5, 0, 1), (0, 0.5, 1), (-0.5, 0, 1), (0, -0.4, 1)]
    sides = []
    for i in range(4):
        c = _arc(corners[i], corners[(i + 1) % 4])
        s = np.linspace(0, 1, 40)
        sides.append(side_from_normals(c, s, -c.evaluate(s)).side)  # cross fields point into the hole
    with pytest.raises(InvalidGeometryError, match="into its neighbour"):
        fill_hole(sides)


def test_refinement_follows_the_angle_tolerance() -> None:
    """A normal field that turns fast near one end: a tighter tolerance needs more spans."""
    c = BSplineCurve(3, [0, 0, 0, 0, 1, 1, 1, 1], np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0.0]]))
    s = np.linspace(0, 1, 1000)
    tilt = 0.3 * np.tanh((s - 0.8) * 15)
    N = np.c_[np.zeros_like(s), np.sin(tilt), np.cos(tilt)]
    loose = side_from_normals(c, s, N, angle_tol=1.0)
    tight = side_from_normals(c, s, N)  # FILL_FIT_ANGLE
    assert tight.converged and tight.angle <= tolerances.FILL_FIT_ANGLE
    assert tight.spans > loose.spans
    with tolerances.override(FILL_FIT_ANGLE=1e-4):
        tighter = side_from_normals(c, s, N)
    assert tighter.spans > tight.spans and tighter.angle <= 1e-4
    with tolerances.override(FILL_FIT_MAX_SPANS=2):
        capped = side_from_normals(c, s, N)
    assert capped.spans <= 2 and not capped.converged and capped.angle > tolerances.FILL_FIT_ANGLE


@given(st.floats(-np.pi, np.pi), st.floats(-1.0, 1.0), st.floats(0.1, 10.0))
@test_settings(max_examples=15)
def test_achieved_angle_is_invariant_under_rigid_motion_and_scale(angle: float, z: float, scale: float) -> None:
    c = _arc((0.5, 0, 1), (0, 0.5, 1))
    s = np.linspace(0, 1, 50)
    N = c.evaluate(s) / R
    base = side_from_normals(c, s, N, angle_tol=1e-3)
    ca, sa = np.cos(angle), np.sin(angle)
    Q = np.array([[ca, -sa * z, sa * np.sqrt(1 - z * z)], [sa, ca * z, -ca * np.sqrt(1 - z * z)],
                  [0, np.sqrt(1 - z * z), z]])
    Q = np.linalg.qr(Q)[0]
    moved = BSplineCurve(c.degree, c.knots, scale * c.control_points @ Q.T + 5.0, c.weights)
    other = side_from_normals(moved, s, N @ Q.T, angle_tol=1e-3)
    assert other.spans == base.spans
    np.testing.assert_allclose(other.angle, base.angle, rtol=1e-5, atol=1e-9)


def test_corner_normals_and_blend() -> None:
    n = corner_normals([[1, 0, 0], [1, 0, 0]], [[0, 1, 0], [1, 0, 0]], [[0, 0, -2], [0, 1, 0]])
    np.testing.assert_allclose(n, [[0, 0, -1], [0, 1, 0]], atol=1e-15)  # signed like the reference; flat: the reference
    s = np.linspace(0, 1, 11)
    field = np.tile([0.0, 0.0, 1.0], (11, 1))
    out = blend_normals(s, field, [0, 1, 0], [0, 0, 1], 0.2)
    np.testing.assert_allclose(out[0], [0, 1, 0], atol=1e-15)  # the start turned into the corner plane
    np.testing.assert_allclose(out[3:], field[3:], atol=1e-15)  # untouched beyond the span
    with pytest.raises(InvalidGeometryError, match="span"):
        blend_normals(s, field, [0, 1, 0], [0, 0, 1], 0.7)


def test_bad_input_is_reported() -> None:
    c = _arc((0.5, 0, 1), (0, 0.5, 1))
    s = np.linspace(0, 1, 20)
    N = c.evaluate(s)
    with pytest.raises(InvalidGeometryError, match="normals: expected shape"):
        side_from_normals(c, s, N[:5])
    with pytest.raises(InvalidGeometryError, match="at least 8"):
        side_from_normals(c, s[:4], N[:4])
    with pytest.raises(InvalidGeometryError, match="domain"):
        side_from_normals(c, s + 2.0, N)
    N0 = N.copy()
    N0[3] = 0.0
    with pytest.raises(InvalidGeometryError, match="zero"):
        side_from_normals(c, s, N0)
    with pytest.raises(InvalidGeometryError, match="curve"):
        side_from_normals("not a curve", s, N)  # type: ignore[arg-type]
    with pytest.raises(InvalidGeometryError, match="increasing"):
        fit_boundary(s[::-1], N, 1e-6)


@test_settings(40)
@given(rational=st.booleans(), degree=st.integers(1, 7), extra=st.integers(0, 5), split=st.floats(0.05, 0.95),
       seed=st.integers(0, 2 ** 16))
def test_primed_side_answers_as_unprimed_bit_for_bit(rational, degree, extra, split, seed):
    """Side.prime evaluates a side once at its corners and split point (one call for several
    parameters, order 2); fields() and tangent() there must then equal a fresh single-point call to
    the bit, which the fill's choices (corner twists, midpoints) rely on. Fails if prime keeps the
    wrong point's row or tangent() reads the second derivative."""
    from occsurf.algorithms.topology.nsided_prepare import Side

    rng = np.random.default_rng(seed)
    n = degree + 1 + extra
    kn = np.r_[[0.0] * (degree + 1), np.sort(rng.random(extra)), [1.0] * (degree + 1)]
    P = rng.normal(size=(n, 3)) * 10.0 ** rng.uniform(-2, 2)
    if rational:  # working coordinates: the boundary homogeneous (w P, w), a polynomial curve in 4-D
        w = rng.uniform(0.5, 2.0, (n, 1))
        P = np.c_[w * P, w]
    B = BSplineCurve(degree, kn, P)
    X = BSplineCurve(degree, kn, rng.normal(size=(n, 4 if rational else 3)))
    fresh, primed = Side(B, X, rational), Side(B, X, rational)
    primed.prime(np.array([0.0, split, 1.0]))
    for s in (0.0, split, 1.0):
        for a, b in zip(fresh.fields(s), primed.fields(s)):
            assert a.shape == b.shape and np.array_equal(a, b)
        assert np.array_equal(fresh.tangent(s), primed.tangent(s))
        assert np.array_equal(primed.tangent(s), B.derivatives(s, 1)[1])
