"""Exact surface generation (course §6-26 .. §6-33): extrusion, ruled, revolution, translational and
rotational sweeps.

Tolerances: every construction is an exact tensor product, so results are compared with closed
forms or with the defining formula evaluated independently. The error is round-off of rational
evaluation: a few ulps times the size of the coordinates (|poles| <= 10 from the strategies, up to
~40 after the affine maps), hence ``EXACT = 1e-12`` relative to ``max(1, scale)``; the quadric
closed forms (radius, |P - c| = r) measured 2e-15 relative, asserted at 1e-13.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, given
from hypothesis import strategies as st
from numpy.testing import assert_allclose

from occsurf.algorithms import BSplineCurve, arc, circle, ellipse, tolerances
from occsurf.algorithms.construction.generation import extrude, revolve, rotational_sweep, ruled, translational_sweep
from occsurf.algorithms.errors import InvalidGeometryError
from tests.algorithms.strategies import affine_maps, curves, fractions, test_settings

EXACT = 1e-12     # defining identities (round-off of a few rational evaluations), relative
QUADRIC = 1e-13   # closed-form radius / distance on quadrics, relative to the radius (measured 2e-15)
SETTINGS = test_settings(30)
curves3 = curves(degrees=st.integers(1, 5), dims=st.just(3), max_extra_poles=4)


def rotation(axis: np.ndarray, angle: float) -> np.ndarray:
    """Rodrigues' rotation matrix (independent of the code under test)."""
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * K @ K


def rigid(seed: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    return rotation(rng.normal(size=3), rng.uniform(0, 2 * np.pi)), rng.uniform(-5, 5, 3)


def grid(surface, n: int = 41) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    (a, b), (c, d) = surface.domain
    u, v = np.linspace(a, b, n), np.linspace(c, d, n)
    return u, v, surface.evaluate_grid(u, v)


def line(p, q) -> BSplineCurve:
    return BSplineCurve(1, [0, 0, 1, 1], [p, q])


def scale_of(*cs) -> float:
    return max([1.0] + [float(np.abs(c.control_points).max()) for c in cs])


# ------------------------------------------------------------------------------ revolution: closed forms
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_revolve_segment_gives_cylinder_cone_and_annulus(seed):
    R, t = rigid(seed)
    o, a = t, R @ [0, 0, 1.0]
    to_world = lambda p: R @ np.asarray(p, float) + t  # noqa: E731
    # cylinder radius 2, cone r(h) = 1 + h/2, annulus (plane h = 1) radii 1..3
    cases = {
        "cylinder": (line(to_world([2, 0, 0]), to_world([2, 0, 3])), lambda h: 2 + 0 * h),
        "cone": (line(to_world([1, 0, 0]), to_world([2, 0, 2])), lambda h: 1 + h / 2),
        "annulus": (line(to_world([1, 0, 1]), to_world([3, 0, 1])), None),
    }
    for name, (seg, radius) in cases.items():
        s = revolve(seg, o, a)
        _, _, P = grid(s, 61)
        rel = (P - o) @ R                      # back to the frame of the closed form
        r = np.hypot(rel[..., 0], rel[..., 1])
        if radius is None:
            assert_allclose(rel[..., 2], 1.0, atol=QUADRIC * 10, err_msg=name)
            assert r.min() >= 1 - 1e-13 and r.max() <= 3 + 1e-13
        else:
            assert_allclose(r, radius(rel[..., 2]), rtol=QUADRIC, atol=QUADRIC, err_msg=name)


def test_revolve_circle_gives_torus_and_semicircle_gives_sphere():
    R, t = rigid(7)
    axis = R @ [0, 0, 1.0]
    c = circle(t + R @ [4.0, 0, 0], 1.5, normal=R @ [0, 1.0, 0])
    _, _, P = grid(revolve(c, t, axis), 61)
    rel = (P - t) @ R
    rr = np.hypot(rel[..., 0], rel[..., 1])
    assert_allclose(np.hypot(rr - 4.0, rel[..., 2]), 1.5, rtol=QUADRIC)
    semi = arc(t, 2.5, -np.pi / 2, np.pi / 2, normal=R @ [0, -1.0, 0], xaxis=R @ [1.0, 0, 0])
    s = revolve(semi, t, axis)
    _, _, P = grid(s, 61)
    assert_allclose(np.linalg.norm(P - t, axis=-1), 2.5, rtol=QUADRIC)
    # the two end rows of the profile lie on the axis: collapsed (sphere poles)
    assert np.ptp(s.control_points[0], axis=0).max() < 1e-14 * 10


@pytest.mark.parametrize("angle", [0.3, math.pi / 2, 2.0, math.pi, 4.0, 3 * math.pi / 2 + 0.1, -1.3, -2 * math.pi])
def test_revolve_partial_angle_end_sections_are_rotated_profile(angle):
    prof = BSplineCurve(3, [0, 0, 0, 0, 0.5, 1, 1, 1, 1], [[1, 0, 0], [2, 0.3, 1], [1.5, 0, 2], [2.5, -0.2, 3], [1, 0, 4]],
                        [1, 2, 1, 0.5, 1])
    o, a = np.array([0.2, -0.1, 0.3]), np.array([0.1, 0.2, 1.0])
    s = revolve(prof, o, a, angle)
    k = max(1, math.ceil(abs(angle) / (math.pi / 2) - 1e-12))
    assert s.degree == (3, 2) and s.n_poles == (5, 2 * k + 1)
    assert s.domain[1] == (0.0, abs(angle))
    u = np.linspace(0, 1, 57)
    # v = 0: the profile itself; the first pole column IS the profile (bit-exact poles)
    assert np.array_equal(s.control_points[:, 0], prof.control_points)
    assert_allclose(s.evaluate_grid(u, [0.0])[:, 0], prof(u), atol=EXACT * 4)
    # at the knots v = j delta the rotation angle is exactly sign(angle) * v
    for v in np.linspace(0, abs(angle), 2 * k + 1):
        Rm = rotation(a, math.copysign(v, angle))
        expected = (prof(u) - o) @ Rm.T + o
        assert_allclose(s.evaluate_grid(u, [v])[:, 0], expected, atol=EXACT * 4)


def test_revolve_full_turn_closes_and_profile_may_cross_axis():
    # a profile crossing the axis (allowed): still exact, the radius is |x| of the profile
    prof = BSplineCurve(2, [0, 0, 0, 1, 1, 1], [[-1, 0, 0], [0.5, 0, 1], [2, 0, 2]])
    s = revolve(prof, [0, 0, 0], [0, 0, 1])
    assert np.array_equal(s.control_points[:, 0], s.control_points[:, -1])
    u, v, P = grid(s, 45)
    C = prof(u)
    assert_allclose(np.hypot(P[..., 0], P[..., 1]), np.abs(C[:, :1]) + 0 * v, atol=EXACT * 4)
    assert_allclose(P[..., 2], C[:, 2:3] + 0 * v, atol=EXACT * 4)


@given(curves3, st.integers(0, 2**31 - 1), st.floats(-2 * np.pi, 2 * np.pi).filter(lambda x: abs(x) > 1e-3))
@SETTINGS
def test_revolve_commutes_with_rigid_motions_and_keeps_the_generatrix(c, seed, angle):
    R, t = rigid(seed)
    o, a = np.array([0.5, -1.0, 2.0]), np.array([0.3, -0.2, 1.0])
    s = revolve(c, o, a, angle)
    moved = revolve(c.transform(R, t), R @ o + t, R @ a, angle)
    u, v, P = grid(s, 15)
    tol = EXACT * (scale_of(c) + 10)
    assert_allclose(moved.evaluate_grid(u, v), P @ R.T + t, atol=tol)
    assert_allclose(P[:, 0], c(u), atol=tol)
    # distance to the axis and height along it are constant on each circle (v-isoline)
    ah = a / np.linalg.norm(a)
    rel = P - o
    h = rel @ ah
    rad = np.linalg.norm(rel - h[..., None] * ah, axis=-1)
    assert_allclose(h, h[:, :1] + 0 * h, atol=tol)
    assert_allclose(rad, rad[:, :1] + 0 * rad, atol=tol)


# ------------------------------------------------------------------------------ extrusion, ruled
@given(curves3, st.integers(0, 2**31 - 1))
@SETTINGS
def test_extrude_is_curve_plus_v_d_and_affine_invariant(c, seed):
    d = np.random.default_rng(seed).uniform(-3, 3, 3)
    assume(np.linalg.norm(d) > 0.1)
    s = extrude(c, d)
    u, v, P = grid(s, 13)
    tol = EXACT * scale_of(c)
    assert_allclose(P, c(u)[:, None] + v[None, :, None] * d, atol=tol)
    assert s.degree == (c.degree, 1) and s.domain[1] == (0.0, 1.0)


@given(curves3, st.data())
@SETTINGS
def test_extrude_translational_and_ruled_affine_invariance(c, data):
    M, b = data.draw(affine_maps(3))
    c2 = data.draw(curves3)
    d = np.array([1.0, -2.0, 0.5])
    tol = EXACT * 40 * (scale_of(c, c2) + np.abs(b).max())
    for make, args, moved_args in [
        (extrude, (c, d), (c.transform(M, b), M @ d)),
        (ruled, (c, c2), (c.transform(M, b), c2.transform(M, b))),
        (translational_sweep, (c, c2), (c.transform(M, b), c2.transform(M, b))),
    ]:
        s, m = make(*args), make(*moved_args)
        u, v, P = grid(s, 11)
        assert_allclose(m.evaluate_grid(u, v), P @ M.T + b, atol=tol, err_msg=make.__name__)


@given(curves3, curves3, st.lists(fractions, min_size=1, max_size=6))
@SETTINGS
def test_ruled_boundaries_and_straight_rulings(c1, c2, fr):
    s = ruled(c1, c2)
    assert s.degree == (max(c1.degree, c2.degree), 1)
    same = c1.domain == c2.domain
    (a, b), _ = s.domain
    u = np.linspace(a, b, 17)
    tol = EXACT * 10 * scale_of(c1, c2)   # compatibility (elevation, refinement) adds round-off
    # curve parameters: the same u if the domains agree, else both mapped onto [0, 1]
    to1 = (lambda c, x: x) if same else (lambda c, x: c.domain[0] + x * (c.domain[1] - c.domain[0]))
    P = s.evaluate_grid(u, [0.0, 1.0])
    assert_allclose(P[:, 0], c1(to1(c1, u)), atol=tol)
    assert_allclose(P[:, 1], c2(to1(c2, u)), atol=tol)
    # interior points lie on the segment between the boundary points
    v = np.asarray(fr)
    Q = s.evaluate_grid(u, v)
    A, B = P[:, :1], P[:, 1:]
    cross = np.cross(Q - A, B - A)
    assert np.abs(cross).max() <= tol * (1 + np.abs(B - A).max()) * 10
    along = np.einsum("uvi,uvi->uv", Q - A, B - A)
    L2 = np.einsum("uvi,uvi->uv", B - A, B - A)
    assert np.all(along >= -tol * 10) and np.all(along <= L2 + tol * 10 * (1 + L2))


# ------------------------------------------------------------------------------ sweeps
@given(curves3, curves3)
@SETTINGS
def test_translational_sweep_is_profile_plus_displacement(p, q):
    s = translational_sweep(p, q)
    u, v, P = grid(s, 13)
    expected = p(u)[:, None] + q(v)[None] - q(q.domain[0])
    assert_allclose(P, expected, atol=EXACT * 3 * scale_of(p, q))
    assert s.degree == (p.degree, q.degree) and s.is_rational == (p.is_rational or q.is_rational)


def swung(p_pts: np.ndarray, t_pts: np.ndarray, t0: np.ndarray, o: np.ndarray, a: np.ndarray) -> np.ndarray:
    """The rotational-sweep formula evaluated on points with complex arithmetic (independent)."""
    a = a / np.linalg.norm(a)
    e1 = (t0 - o) - ((t0 - o) @ a) * a
    rho0 = np.linalg.norm(e1)
    e1 /= rho0
    e2 = np.cross(a, e1)
    z = ((t_pts - o) @ e1 + 1j * ((t_pts - o) @ e2)) / rho0          # (m,)
    lift = (t_pts - o) @ a - (t0 - o) @ a
    rel = p_pts - o
    h = rel @ a
    w = rel @ e1 + 1j * (rel @ e2)                                   # in-plane part as complex
    zw = w[:, None] * z[None, :]
    return (o + (h[:, None] + lift[None, :])[..., None] * a
            + zw.real[..., None] * e1 + zw.imag[..., None] * e2)


@given(curves3, curves3, st.integers(0, 2**31 - 1))
@SETTINGS
def test_rotational_sweep_matches_complex_formula(p, t, seed):
    rng = np.random.default_rng(seed)
    o, a = rng.uniform(-2, 2, 3), rng.normal(size=3)
    t0 = t(t.domain[0])
    r0 = (t0 - o) - ((t0 - o) @ a) * a / (a @ a)
    assume(np.linalg.norm(r0) > 0.5)
    s = rotational_sweep(p, t, o, a)
    u, v, P = grid(s, 11)
    expected = swung(p(u), t(v), t0, o, a)
    scale = scale_of(p, t) * (1 + np.abs(t.control_points - o).max() / np.linalg.norm(r0))
    assert_allclose(P, expected, atol=EXACT * 4 * scale)
    assert_allclose(P[:, 0], p(u), atol=EXACT * 4 * scale)     # S(u, v0) = profile


def test_rotational_sweep_with_circle_is_revolve_and_with_ellipse_is_stretched():
    prof = BSplineCurve(3, [0, 0, 0, 0, 0.5, 1, 1, 1, 1], [[1, 0, 0], [2, 0, 1], [1.5, 0, 2], [2.5, 0, 3], [1, 0, 4]],
                        [1, 2, 1, 0.5, 1])
    rs = rotational_sweep(prof, circle([0, 0, 5], 4.0))
    rv = revolve(prof, [0, 0, 0], [0, 0, 1])
    u, v, P = grid(rs, 41)
    assert_allclose(P, rv.evaluate_grid(u, v), atol=EXACT * 4)
    es = rotational_sweep(prof, ellipse([0, 0, -1], 3.0, 1.5))
    u, v, E = grid(es, 41)
    assert_allclose(E, rv.evaluate_grid(u, v) * [1, 0.5, 1], atol=EXACT * 4)


def test_rotational_sweep_lift_along_axis():
    # a helical-ish trajectory (exact circle radius 2, height rising linearly) lifts the sections
    circ = circle([0, 0, 0], 2.0)
    P = circ.control_points.copy()
    knots_g = circ.greville()
    P[:, 2] = 0.5 * knots_g  # poles lifted linearly in the Greville abscissa: height = 0.5 v exactly
    traj = BSplineCurve(2, circ.knots, P, circ.weights)
    prof = line([1, 0, 0], [1.5, 0, 1])
    s = rotational_sweep(prof, traj)
    u, v, S = grid(s, 31)
    T = traj(v)
    assert_allclose(S[..., 2], prof(u)[:, 2:3] + T[None, :, 2], atol=EXACT * 10)
    assert_allclose(np.hypot(S[..., 0], S[..., 1]), prof(u)[:, :1] + 0 * v, atol=EXACT * 10)


# ------------------------------------------------------------------------------ input validation
def test_errors():
    c = line([1, 0, 0], [1, 0, 1])
    c2d = BSplineCurve(1, [0, 0, 1, 1], [[1, 0], [1, 1]])
    with pytest.raises(InvalidGeometryError, match="axis_direction"):
        revolve(c, [0, 0, 0], [0, 0, 0])
    with pytest.raises(InvalidGeometryError, match="angle"):
        revolve(c, [0, 0, 0], [0, 0, 1], 0.0)
    with pytest.raises(InvalidGeometryError, match="angle"):
        revolve(c, [0, 0, 0], [0, 0, 1], 2 * np.pi + 1e-6)
    with pytest.raises(InvalidGeometryError, match="angle"):
        revolve(c, [0, 0, 0], [0, 0, 1], float("nan"))
    with pytest.raises(InvalidGeometryError, match="axis_origin"):
        revolve(c, [0, np.nan, 0], [0, 0, 1])
    with pytest.raises(InvalidGeometryError, match="axis_direction"):
        revolve(c, [0, 0, 0], [0, 1])
    with pytest.raises(InvalidGeometryError, match="profile.*3-D"):
        revolve(c2d, [0, 0, 0], [0, 0, 1])
    with pytest.raises(InvalidGeometryError, match="vector"):
        extrude(c, [0, 0, 0])
    with pytest.raises(InvalidGeometryError, match="vector"):
        extrude(c, [0, np.inf, 0])
    with pytest.raises(InvalidGeometryError, match="curve"):
        extrude("not a curve", [0, 0, 1])
    with pytest.raises(InvalidGeometryError, match="c2.*3-D"):
        ruled(c, c2d)
    with pytest.raises(InvalidGeometryError, match="path"):
        translational_sweep(c, c2d)
    with pytest.raises(InvalidGeometryError, match="trajectory.*axis"):
        rotational_sweep(c, line([0, 0, 1], [1, 0, 1]))
    # 2 pi within ANGLE_SLACK is a full turn
    assert revolve(c, [0, 0, 0], [0, 0, 1], 2 * np.pi + 1e-13).domain[1] == (0.0, 2 * np.pi)


def test_axis_direction_length_is_irrelevant():
    # A direction only has to normalise to a finite unit vector: its length is not compared with
    # the size of the profile (a unit axis used to be refused for a profile of size 1e13, and a
    # direction of length 1e-13 for a profile of size 1), nor may it overflow (a direction of
    # length 1.4e308 used to normalise to the zero vector and give a silently wrong surface).
    prof = BSplineCurve(2, [0, 0, 0, 1, 1, 1], [[1, 0, 0], [2, 0.5, 1], [1, 0, 2]])
    ref = revolve(prof, [0, 0, 0], [1, 1, 0], 2.0)
    for d in ([1e-13, 1e-13, 0], [1e308, 1e308, 0], [3e-320, 3e-320, 0]):
        s = revolve(prof, [0, 0, 0], d, 2.0)
        assert_allclose(s.control_points, ref.control_points, rtol=0, atol=1e-15)
    big = prof.transform(np.eye(3) * 1e13)
    s = revolve(big, [0, 0, 0], [0, 0, 1])
    assert_allclose(s.control_points[:, 0], big.control_points, rtol=1e-15)
    s = rotational_sweep(prof, circle([0, 0, 0], 2.0), axis_direction=[0, 0, 1e-13])
    assert_allclose(s.control_points, rotational_sweep(prof, circle([0, 0, 0], 2.0)).control_points, atol=1e-14)
    with pytest.raises(InvalidGeometryError, match=r"^axis_direction: expected a non-zero vector, got \[0.0, 0.0, 0.0\]"):
        revolve(prof, [0, 0, 0], [0.0, 0.0, 0.0])
    with pytest.raises(InvalidGeometryError, match=r"^angle: expected a real number of radians, got True"):
        revolve(prof, [0, 0, 0], [0, 0, 1], True)


# ------------------------------------------------------------------------------------- tolerances
def test_angle_slack_override_decides_what_counts_as_a_full_turn():
    c = line([1, 0, 0], [1, 0, 1])
    with pytest.raises(InvalidGeometryError, match=r"^angle: expected 0 < \|angle\| <= 2 pi"):
        revolve(c, [0, 0, 0], [0, 0, 1], 2 * np.pi + 1e-9)  # 1e-9 > ANGLE_SLACK = 1e-12
    with tolerances.override(ANGLE_SLACK=1e-6):
        s = revolve(c, [0, 0, 0], [0, 0, 1], 2 * np.pi + 1e-9)
        with pytest.raises(InvalidGeometryError, match=r"^angle"):
            revolve(c, [0, 0, 0], [0, 0, 1], -2 * np.pi - 1e-5)
    assert s.domain[1] == (0.0, 2 * np.pi)
    assert_allclose(s.control_points[:, -1], c.control_points, rtol=0, atol=0)  # closed exactly
    with pytest.raises(InvalidGeometryError, match=r"^angle"):
        revolve(c, [0, 0, 0], [0, 0, 1], 2 * np.pi + 1e-9)  # the default is back


def test_axis_zero_override_decides_what_counts_as_a_zero_vector():
    c = line([1, 0, 0], [2, 0, 1])  # size 2
    d = [0, 0, 1e-9]
    assert_allclose(extrude(c, d).evaluate(0.5, 1.0), c.evaluate(0.5) + d, rtol=0, atol=1e-15)
    traj = line([1e-9, 0, 0], [1e-9, 1, 0])  # starts 1e-9 off the z axis
    rotational_sweep(c, traj)
    with tolerances.override(AXIS_ZERO=1e-6):
        with pytest.raises(InvalidGeometryError, match=r"^vector: expected a non-zero vector"):
            extrude(c, d)  # 1e-9 <= 1e-6 x 2
        with pytest.raises(InvalidGeometryError, match=r"^trajectory: its start point lies on the axis"):
            rotational_sweep(c, traj)
