"""Generalised sweep (course §6-26 .. §6-33): closed forms, the error report, frames, errors.

Tolerances: the sweep is an approximation refined until the pole-row error bound is <= ``tol`` at
the check points, so closed-form comparisons use ``tol`` itself (the report's dense verification
is off the fitting and check sites) plus round-off. At points not used by the algorithm at all
(random ones), the error may exceed ``tol`` only between check points; measured <= 0.76 tol on
the cases below, asserted at ``1.5 tol`` (a cubic interpolant's error curve between 5 check points
per span cannot rise much above its sampled maximum when the span error is O(h^4)-smooth).
The rotation-minimising frame field is compared with an independent ODE solution (scipy
``solve_ivp``, rtol 1e-12): measured 8e-12 with SWEEP_RMF_STEPS = 128, asserted at 1e-9.
"""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal
from scipy.integrate import solve_ivp

import occsurf.algorithms.construction.sweeping as sw
from occsurf.algorithms import BSplineCurve, arc, circle, tolerances
from occsurf.algorithms.construction.generation import translational_sweep
from occsurf.algorithms.construction.sweep_frames import PathFrames
from occsurf.algorithms.construction.sweeping import SweepResult, exact_sweep, sweep
from occsurf.algorithms.errors import InvalidGeometryError, ToleranceError
from occsurf.algorithms.fitting.interpolation import interpolate_curve
from occsurf.algorithms.kernel.basis import greville

ROUND = 1e-12


def line(p, q) -> BSplineCurve:
    return BSplineCurve(1, [0, 0, 1, 1], [p, q])


def helix_path(turns: float = 1.5) -> BSplineCurve:
    th = np.linspace(0, 2 * np.pi * turns, 12)
    return interpolate_curve(np.c_[3 * np.cos(th), 3 * np.sin(th), 0.8 * th])


def start_frame(path: BSplineCurve) -> tuple[np.ndarray, np.ndarray]:
    d = path.derivatives(path.domain[0], 1)
    return d[0], d[1] / np.linalg.norm(d[1])


def dense(surface, n=37, m=53):
    (a, b), (c, d) = surface.domain
    rng = np.random.default_rng(3)
    u = np.sort(rng.uniform(a, b, n))
    v = np.sort(rng.uniform(c, d, m))
    return u, v, surface.evaluate_grid(u, v)


# ------------------------------------------------------------------------------ closed forms
def test_twisted_line_along_straight_path_is_helicoid():
    path = line([0, 0, 0], [0, 0, 5])
    prof = line([-1, 0, 0], [1, 0, 0])
    tol = 1e-9
    r = sweep(prof, path, twist=lambda t: 3 * t, tol=tol, return_report=True)
    assert isinstance(r, SweepResult) and r.max_error <= tol
    u, v, S = dense(r.surface)
    # helicoid: (x cos 3v, x sin 3v, 5 v), x = 2u - 1 (right-handed twist about +z)
    x, ang = (2 * u - 1)[:, None], 3 * v[None, :]
    expected = np.stack([x * np.cos(ang), x * np.sin(ang), 5 * v[None, :] + 0 * x], -1)
    assert np.abs(S - expected).max() <= 1.5 * tol


def test_scaled_circle_along_straight_path_is_cone():
    path = line([1, 2, 3], [1, 2, 7])
    prof = circle([1, 2, 3], 0.5, normal=[0, 0, 1])
    tol = 1e-10
    r = sweep(prof, path, scale=lambda t: 1 + 2 * t, tol=tol, return_report=True)
    u, v, S = dense(r.surface)
    radius = np.hypot(S[..., 0] - 1, S[..., 1] - 2)
    # a linear law on a straight path: the rows are linear in v, reproduced exactly by the cubic
    assert_allclose(radius, 0.5 * (1 + 2 * (S[..., 2] - 3) / 4), atol=ROUND * 10)
    assert r.max_error <= 1e-13 and r.iterations == 1


@pytest.mark.parametrize("frame", ["rmf", "frenet"])
def test_circle_along_circle_is_torus(frame):
    path = arc([0, 0, 0], 4.0, 0.0, 1.5 * np.pi)
    p0, t0 = start_frame(path)
    prof = circle(p0, 1.0, normal=t0)
    tol = 1e-8
    r = sweep(prof, path, frame=frame, tol=tol, return_report=True)
    assert r.max_error <= tol <= r.tol
    _, _, S = dense(r.surface)
    rr = np.hypot(S[..., 0], S[..., 1])
    assert np.abs(np.hypot(rr - 4.0, S[..., 2]) - 1.0).max() <= 1.5 * tol


def test_fixed_frame_equals_translational_sweep():
    path = BSplineCurve(3, [0, 0, 0, 0, 0.4, 1, 1, 1, 1], [[0, 0, 0], [2, 1, 0], [3, 3, 1], [5, 4, 0], [6, 7, 2]])
    prof = circle([0, 0, 0], 0.7, normal=[1, 0.2, 0])
    r = sweep(prof, path, frame="fixed", return_report=True)
    exact = translational_sweep(prof, path)
    u, v, S = dense(r.surface)
    # the path is a cubic and the frame constant: the cubic interpolant in v is exact
    assert_allclose(S, exact.evaluate_grid(u, v), atol=ROUND * 10)
    assert r.max_error <= ROUND * 10


# ------------------------------------------------------------------------------ the report
@pytest.mark.parametrize("frame", ["rmf", "frenet"])
def test_report_bounds_and_independent_check(frame):
    path = helix_path()
    p0, t0 = start_frame(path)
    n0 = np.cross(t0, [0, 0, 1.0])
    prof = BSplineCurve(3, [0, 0, 0, 0, 0.5, 1, 1, 1, 1],
                        [p0 + 0.4 * n0, p0 + [0, 0, 0.6], p0 - 0.5 * n0, p0 + [0, 0, -0.4], p0 + 0.4 * n0],
                        [1, 0.5, 2, 1, 1])
    scale, twist = (lambda t: 1 + 0.5 * np.sin(3 * t)), (lambda t: 2 * t**2)
    for tol in (1e-4, 1e-7):
        r = sweep(prof, path, frame=frame, scale=scale, twist=twist, tol=tol, return_report=True)
        assert r.max_error <= tol
        assert r.max_error <= r.pole_bound * (1 + 1e-9)  # convex-combination bound
        # The true error, on a grid 7x denser in v than the report's and off all its points:
        # the pole bound (sampled at the report's points) bounds it, and so does tol. Measured
        # true / pole_bound = 0.62 .. 0.81 and true / tol = 0.39 .. 0.80 on these cases;
        # max_error, a sampled maximum, is within 2 % of the true supremum (ratio 1.005 .. 1.017).
        u, v, S = dense(r.surface, 41, 7 * r.n_sections)
        E = exact_sweep(prof, path, u, v, frame=frame, scale=scale, twist=twist)
        true = np.linalg.norm(S - E, axis=-1).max()
        assert true <= r.pole_bound and true <= tol
        assert true <= 1.05 * r.max_error
        # exact on the profile at the path start (scale(0) = 1, twist(0) = 0)
        assert_allclose(r.surface.evaluate_grid(u, [path.domain[0]])[:, 0], prof(u), atol=ROUND * 10)
    coarse = sweep(prof, path, frame=frame, scale=scale, twist=twist, tol=1e-4, return_report=True)
    assert coarse.n_sections < r.n_sections


def test_rmf_frame_field_matches_ode():
    path = helix_path()
    v = np.linspace(*path.domain, 301)
    F = PathFrames(path, "rmf")(v)

    def rhs(s, r):  # r' = -(r . T') T : the rotation-minimising (Bishop) transport
        d = path.derivatives(s, 2)
        speed = np.linalg.norm(d[1])
        t = d[1] / speed
        dt = (d[2] - (d[2] @ t) * t) / speed
        return -(r @ dt) * t

    sol = solve_ivp(rhs, path.domain, F[0][:, 1], t_eval=v, rtol=1e-12, atol=1e-13, method="DOP853")
    assert np.abs(sol.y.T - F[:, :, 1]).max() <= 1e-9
    assert_allclose(np.einsum("mij,mik->mjk", F, F), np.broadcast_to(np.eye(3), F.shape), atol=1e-13)


def test_rmf_frame_field_at_its_reference_samples_is_the_reference_frame():
    """At a reference sample the double-reflection step has no first reflection (``x = x_k``), so its
    second axis ``t - t_k`` is round-off in a random direction: the field keeps ``r_k`` there.
    Tangents off by 1e-13 (another way to compute them) once turned those normals by up to 140 degrees."""
    path = helix_path()
    field = PathFrames(path, "rmf")
    v = field.grid[::7]
    D = path.derivatives(v, 1)
    ref = field.r[::7]
    assert_allclose(field(v, D)[:, :, 1], ref, rtol=0, atol=1e-14)
    rng = np.random.default_rng(3)
    noisy = D.copy()
    noisy[:, 1] += 1e-13 * np.linalg.norm(D[:, 1], axis=-1)[:, None] * rng.normal(size=(v.shape[0], 3))
    F = field(v, noisy)
    assert_allclose(F[:, :, 1], ref, rtol=0, atol=1e-12)
    assert_allclose(np.einsum("mij,mik->mjk", F, F), np.broadcast_to(np.eye(3), F.shape), atol=1e-13)


def test_rmf_sweep_along_a_planar_circle_is_the_frenet_sweep():
    """On a planar path the RMF is the Frenet frame turned by a constant angle, and the sweep does not
    depend on that angle (module notes): both frames give the same surface. Before 2026-12-07 the RMF
    field's frames at its own reference samples (here the Greville sites at the closed circle's ends)
    were turned by round-off, and this sweep took 176 sections in 3 passes against Frenet's 73 in 2."""
    path = circle([1, 2, 3], 5.0, normal=[0.2, 0.3, 1.0])
    d0 = path.derivatives(path.domain[0], 1)
    prof = circle(d0[0], 0.3, normal=d0[1])
    rmf = sweep(prof, path, frame="rmf", return_report=True)
    frenet = sweep(prof, path, frame="frenet", return_report=True)
    assert (rmf.n_sections, rmf.iterations) == (frenet.n_sections, frenet.iterations)
    assert_allclose(rmf.surface.control_points, frenet.surface.control_points, rtol=0, atol=1e-12 * 5.0)
    assert rmf.max_error <= rmf.tol


def test_rmf_sweep_independent_of_start_normal_and_rigid_motion():
    path = helix_path(1.0)
    p0, t0 = start_frame(path)
    prof = circle(p0 + [0, 0, 0.2], 0.5, normal=t0)
    R = np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1.0]]) @ np.array([[1, 0, 0], [0, 0.6, -0.8], [0, 0.8, 0.6]])
    b = np.array([1.0, -2.0, 0.5])
    tol = 1e-8
    s1 = sweep(prof, path, tol=tol, twist=lambda t: t)
    s2 = sweep(prof.transform(R, b), path.transform(R, b), tol=tol, twist=lambda t: t)
    u, v, S1 = dense(s1)
    assert np.abs(s2.evaluate_grid(u, v) - (S1 @ R.T + b)).max() <= 3 * tol


# ------------------------------------------------------------------------------ errors
def test_errors():
    path = line([0, 0, 0], [0, 0, 1])
    prof = line([1, 0, 0], [2, 0, 0])
    with pytest.raises(InvalidGeometryError, match="frame"):
        sweep(prof, path, frame="bishop")
    with pytest.raises(InvalidGeometryError, match="Frenet"):
        sweep(prof, path, frame="frenet")          # a straight path has no Frenet normal
    with pytest.raises(InvalidGeometryError, match="scale"):
        sweep(prof, path, scale=-1.0)
    with pytest.raises(InvalidGeometryError, match="scale"):
        sweep(prof, path, scale=lambda t: 1 - 2 * t)
    with pytest.raises(InvalidGeometryError, match="twist"):
        sweep(prof, path, twist=lambda t: np.where(t > 0.5, np.nan, 0.0))
    with pytest.raises(InvalidGeometryError, match="twist"):
        sweep(prof, path, twist=lambda t: np.zeros(3))
    with pytest.raises(InvalidGeometryError, match="tol"):
        sweep(prof, path, tol=0.0)
    with pytest.raises(InvalidGeometryError, match="path.*3-D"):
        sweep(prof, BSplineCurve(1, [0, 0, 1, 1], [[0, 0], [1, 1]]))
    with pytest.raises(InvalidGeometryError, match="profile"):
        sweep(None, path)
    with tolerances.override(SWEEP_MAX_SECTIONS=60), pytest.raises(ToleranceError, match="not reached"):
        sweep(prof, path, twist=lambda t: np.where(t > 0.3, 1.0, 0.0), tol=1e-6)   # a jump in the twist never converges


def test_tol_that_is_not_a_number_is_named():
    path, prof = line([0, 0, 0], [0, 0, 1]), line([1, 0, 0], [2, 0, 0])
    with pytest.raises(InvalidGeometryError, match="tol: expected a positive finite number, got 'a'"):
        sweep(prof, path, tol="a")


def test_path_with_zero_derivative_is_named_path():
    prof = line([1, 0, 0], [2, 0, 0])
    cusp = BSplineCurve(2, [0, 0, 0, 1, 1, 1], [[0, 0, 0], [0, 0, 0], [0, 0, 1]])
    with pytest.raises(InvalidGeometryError, match=r"^path: C'\(u\) = 0 at u = 0.0"):
        sweep(prof, cusp)


def test_path_must_be_continuous_and_tangent_continuous_for_moving_frames():
    prof = line([1, 0, 0], [2, 0, 0])
    # a kinked path: the moving frame would jump (the sweep tears); named, with the way out
    kink = BSplineCurve(1, [0, 0, 0.5, 1, 1], [[0, 0, 0], [0, 0, 1], [1, 0, 1]])
    for frame in ("rmf", "frenet"):
        with pytest.raises(InvalidGeometryError, match=r"^path: not tangent-continuous at v = 0.5 .*turns by 90 degrees"):
            sweep(prof, kink, frame=frame)
    fixed = sweep(prof, kink, frame="fixed", return_report=True)   # a translation: fine across the kink
    assert fixed.max_error <= ROUND * 10
    jump = BSplineCurve(1, [0, 0, 0.5, 0.5, 1, 1], [[0, 0, 0], [0, 0, 1], [0, 0, 2], [1, 0, 2]])
    with pytest.raises(InvalidGeometryError, match=r"^path: not continuous at v = 0.5 \(the two sides are 1 apart\)"):
        sweep(prof, jump, frame="fixed")


def _review_path() -> tuple[BSplineCurve, BSplineCurve]:
    H = np.array([[0.0, 0, 0], [1, 0, 0.5], [1, 1, 1], [0, 1, 1.5], [0, 0, 2]])
    path = BSplineCurve(3, [0, 0, 0, 0, 0.5, 1, 1, 1, 1], H)
    return path, circle(path.evaluate(0.0), 0.1, normal=path.derivatives(0.0, 1)[1])


def test_pole_bound_never_exceeds_tol():
    """Review: only 5 check points per span were compared with tol, and the report's 9 verification
    points found pole_bound 2.54e-6 for tol 2e-6 (on 40 random paths up to 3 % over). The
    verification points now take part in the refinement."""
    path, prof = _review_path()
    r = sweep(prof, path, scale=lambda t: 1 + np.abs(t - 0.5), return_report=True)
    assert r.pole_bound <= r.tol and r.max_error <= r.tol
    rng = np.random.default_rng(11)
    for _ in range(10):
        P = np.cumsum(rng.normal(size=(6, 3)), axis=0)
        p = interpolate_curve(P)
        pr = circle(p.evaluate(p.domain[0]), 0.2, normal=p.derivatives(p.domain[0], 1)[1])
        r = sweep(pr, p, frame="rmf", twist=1.0, return_report=True)
        assert r.pole_bound <= r.tol and r.max_error <= r.tol


def test_error_that_does_not_fall_is_named_with_its_place():
    """Review: a jump in a law or a cusp of the path cut spans to round-off width and then failed
    with a ParameterError about an internal 'params' argument."""
    path, prof = _review_path()
    with pytest.raises(ToleranceError, match=r"^sweep: tolerance .* does not fall .* near v = 0\.32"):
        sweep(prof, path, scale=lambda t: np.where(t < 0.3217, 1.0, 1.5))
    back = BSplineCurve(2, [0, 0, 0, 1, 1, 1], np.array([[0.0, 0, 0], [3, 0, 0], [1, 0, 0]]))  # C'(0.6) = 0
    with pytest.raises(ToleranceError, match=r"near v = 0\.6.*cusp"):
        sweep(circle([0, 0, 0], 0.2, normal=[1, 0, 0]), back)


def test_rmf_sweep_along_a_closed_non_planar_path_closes():
    """Review: the RMF's holonomy left a 3.3e-4 gap at the seam of a tube swept along a closed
    non-planar path. The angle (here -1.77 rad) is spread as a uniform twist: the tube closes."""
    th = np.linspace(0, 2 * np.pi, 13)[:-1]
    pts = np.c_[2 * np.cos(th), np.sin(th), 0.6 * np.sin(2 * th)]  # a saddle-shaped closed loop
    P = np.vstack((pts, pts[:3]))  # wrapped poles: a closed, C2 uniform cubic, then clamped
    closed = BSplineCurve(3, np.arange(P.shape[0] + 4, dtype=float), P).clamp()
    d0, d1 = closed.derivatives(closed.domain[0], 1), closed.derivatives(closed.domain[1], 1)
    assert np.linalg.norm(d0[0] - d1[0]) < 1e-12 and np.linalg.norm(d0[1] - d1[1]) < 1e-9
    assert abs(PathFrames(closed, "rmf").holonomy) > 1.0  # there is something to correct
    prof = circle(d0[0], 0.2, normal=d0[1])
    r = sweep(prof, closed, frame="rmf", tol=1e-7, return_report=True)
    (u0, u1), (v0, v1) = r.surface.domain
    uu = np.linspace(u0, u1, 41)
    gap = np.linalg.norm(r.surface.evaluate(uu, v0 + 0 * uu) - r.surface.evaluate(uu, v1 + 0 * uu), axis=-1).max()
    assert gap <= 2e-7  # both ends within the sweep's tolerance of one closed section
    assert r.max_error <= 1e-7
    # an open path keeps the pure RMF (no correction)
    assert PathFrames(closed.segment(*closed.domain[:1], closed.domain[1] - 0.5), "rmf").holonomy == 0.0


# ------------------------------------------------------------------------------ tolerances
def test_sweep_tolerance_override_is_met_by_the_report():
    path, prof = _review_path()
    size = max(1.0, float(np.abs(prof.control_points).max()), float(np.abs(path.control_points).max()))
    default = sweep(prof, path, return_report=True)
    assert default.tol == 1e-6 * size
    with tolerances.override(SWEEP_TOLERANCE=1e-9):
        r = sweep(prof, path, return_report=True)
    assert r.tol == 1e-9 * size
    assert r.pole_bound <= r.tol and r.max_error <= r.tol
    assert r.n_sections > default.n_sections
    assert sweep(prof, path, tol=1e-9 * size, return_report=True) == r  # the same as an explicit tol=


def test_check_and_verify_points_follow_an_override_of_their_counts():
    assert_allclose(sw._check_fractions(), (np.arange(5) + 0.5) / 5 * 0.96 + 0.013, rtol=0, atol=0)
    assert sw._verify_fractions().shape == (9,)
    with tolerances.override(SWEEP_CHECKS_PER_SPAN=3, SWEEP_VERIFY_PER_SPAN=4):
        assert sw._check_fractions().shape == (3,) and sw._verify_fractions().shape == (4,)
        path, prof = _review_path()
        r = sweep(prof, path, return_report=True)
    assert r.pole_bound <= r.tol
    # n_checked = (8 per profile span + 2 ends) x (4 per v span)
    n_u = 8 * (np.unique(prof.knots).shape[0] - 1) + 2
    assert r.n_checked == n_u * 4 * (np.unique(r.surface.knots[1]).shape[0] - 1)


def test_frame_and_knot_limits_are_read_from_tolerances():
    path = helix_path()
    spans = np.unique(path.knots).shape[0] - 1
    assert PathFrames(path, "rmf").grid.shape == (128 * spans + 1,)
    with tolerances.override(SWEEP_RMF_STEPS=16):
        assert PathFrames(path, "rmf").grid.shape == (16 * spans + 1,)
    K = sw._initial_knots(path, "rmf", 3)
    with tolerances.override(SWEEP_INITIAL_PIECES=4):
        K4 = sw._initial_knots(path, "rmf", 3)
    assert K4.shape[0] - K.shape[0] == 2 * spans  # two more cuts per span


def test_kink_angle_override_decides_whether_a_joint_is_a_kink():
    kink = BSplineCurve(1, [0, 0, 0.5, 1, 1], [[0, 0, 0], [0, 0, 1], [1e-6, 0, 2]])  # turns by 1e-6 rad
    with pytest.raises(InvalidGeometryError, match=r"^path: not tangent-continuous at v = 0.5"):
        sw._check_joints(kink, "rmf", 2.0)
    with tolerances.override(SWEEP_KINK_ANGLE=1e-5):
        sw._check_joints(kink, "rmf", 2.0)


def test_close_tol_override_decides_whether_a_path_is_closed():
    th = np.linspace(0, 2 * np.pi, 13)[:-1]
    pts = np.c_[2 * np.cos(th), np.sin(th), 0.6 * np.sin(2 * th)]
    P = np.vstack((pts, pts[:3]))
    P[-1] += [0, 0, 1e-6]  # the end moves 1e-6 off the start (the tangents still agree within 1e-6)
    almost = BSplineCurve(3, np.arange(P.shape[0] + 4, dtype=float), P).clamp()
    assert PathFrames(almost, "rmf").holonomy == 0.0  # 1e-6 > SWEEP_CLOSE_TOL * size
    with tolerances.override(SWEEP_CLOSE_TOL=1e-5, SWEEP_CLOSE_ANGLE=1e-3):
        assert abs(PathFrames(almost, "rmf").holonomy) > 1.0


# ------------------------------------------------------------------------------ the steps
def test_absolute_tolerance():
    assert sw._absolute_tolerance(None, 3.0) == 1e-6 * 3.0
    with tolerances.override(SWEEP_TOLERANCE=1e-8):
        assert sw._absolute_tolerance(None, 3.0) == 1e-8 * 3.0
    assert sw._absolute_tolerance("1e-5", 3.0) == 1e-5
    for bad in (0.0, -1.0, np.inf, np.nan, "a", []):
        with pytest.raises(InvalidGeometryError, match=r"^tol: expected a positive finite number"):
            sw._absolute_tolerance(bad, 3.0)


def _rows(K, q=3):
    n = K.shape[0] - q - 1
    return BSplineCurve._trusted(q, K, np.zeros((n, 3)))


def test_split_spans_cuts_each_bad_span_as_the_error_model_asks():
    K = np.r_[[0.0] * 4, 0.25, 0.5, 0.75, [1.0] * 4]  # 4 spans
    tol = 1e-6
    err = np.array([0.0, 1e4 * tol, 2 * tol, 0.5 * tol])
    new = np.setdiff1d(sw._split_spans(_rows(K), err, tol, (0.0, 1.0)), K)
    # span 1: ceil(1.2 * 10) = 12 pieces; span 2: ceil(1.2 * 2^(1/4)) = 2 pieces
    assert_allclose(new, np.r_[0.25 + 0.25 * np.arange(1, 12) / 12, 0.625], rtol=0, atol=1e-15)
    with tolerances.override(SWEEP_MAX_SPLIT=4, SWEEP_SPLIT_SAFETY=1.0):
        new = np.setdiff1d(sw._split_spans(_rows(K), err, tol, (0.0, 1.0)), K)
    assert_allclose(new, np.r_[0.25 + 0.25 * np.arange(1, 4) / 4, 0.625], rtol=0, atol=1e-15)
    with tolerances.override(SWEEP_MAX_SECTIONS=15), pytest.raises(ToleranceError, match="not reached with 15 "):
        sw._split_spans(_rows(K), err, tol, (0.0, 1.0))  # 7 rows + 12 new ones
    with tolerances.override(SWEEP_MIN_SPAN=0.05), pytest.raises(ToleranceError, match=r"does not fall .* v = 0\.25"):
        sw._split_spans(_rows(K), err, tol, (0.0, 1.0))  # 0.25 / 12 < 0.05


def test_fitted_maps_give_pole_rows_interpolating_the_exact_ones_at_the_greville_abscissae():
    path, prof = _review_path()
    ex = sw._Sweep(prof, path, "rmf", None, None)
    K = sw._initial_knots(path, "rmf", 3)
    maps, err = sw._fit_maps(ex, K, 3)
    rows = sw._rows(ex, maps)
    assert_array_equal(rows.knots, K)
    sites = greville(K, 3)
    exact = ex.place(sites, prof.control_points).reshape(sites.shape[0], -1)
    assert_allclose(rows(sites), exact, rtol=0, atol=1e-13)
    assert err.shape == (np.unique(K).shape[0] - 1,) and np.all(err > 0)


def test_refine_meets_the_tolerance_at_the_verification_points():
    path, prof = _review_path()
    ex = sw._Sweep(prof, path, "rmf", None, None)
    fit = sw._refine(ex, sw._initial_knots(path, "rmf", 3), 3, 1e-7)
    assert fit.iterations >= 2 and fit.span_errors.max() <= 1e-7
    a, b = sw._spans(fit.rows.knots, 3)
    assert fit.verify_v.shape == (9 * a.shape[0],) and np.all(np.diff(fit.verify_v) > 0)
    surface = sw._surface_from_rows(prof, fit.rows)
    assert surface.degree == (prof.degree, 3) and surface.weights is not None  # the circle is rational
    uu = np.linspace(*prof.domain, 17)
    E = sw.exact_sweep(prof, path, uu, fit.verify_v)
    assert np.linalg.norm(surface.evaluate_grid(uu, fit.verify_v) - E, axis=-1).max() <= fit.span_errors.max()
