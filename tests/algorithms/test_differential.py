"""Differential geometry (occsurf.algorithms.geometry.differential, .surface_differential): closed forms, invariants, degenerate points.

Oracles: circle (kappa = 1/r, tau = 0, length r theta), the twisted cubic (t, t^2, t^3) written as a
cubic Bézier (closed-form kappa, tau), sphere / cylinder / torus as exact rational B-splines built
here from their NURBS nets (tensor products of exact circles), Euler's theorem for the normal
curvature, and finite differences for dkappa/ds and the rotation-minimizing property.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import assume, example, given
from hypothesis import strategies as st
from numpy.testing import assert_allclose

from occsurf.algorithms import BSplineCurve, BSplineSurface, arc, circle, tolerances
from occsurf.algorithms.errors import InvalidGeometryError, ParameterError
from occsurf.algorithms.geometry import differential
from occsurf.algorithms.geometry.differential import (
    FrenetFrame,
    arc_length,
    curvature,
    curvature_derivative,
    curve_frenet,
    frenet_axes,
    rotation_minimizing_frames,
    torsion,
)
from occsurf.algorithms.geometry.surface_differential import (
    SurfaceCurvatures,
    is_umbilic,
    normal_curvature,
    principal_curvatures,
    surface_curvatures,
)

from .strategies import curves, surfaces, test_settings

SETTINGS = test_settings(30)


# ------------------------------------------------------------------------------------ fixtures
def twisted_cubic() -> BSplineCurve:
    """(t, t^2, t^3) on [0, 1] as a cubic Bézier (power basis -> Bernstein)."""
    P = [[0, 0, 0], [1 / 3, 0, 0], [2 / 3, 1 / 3, 0], [1, 1, 1]]
    return BSplineCurve(3, [0, 0, 0, 0, 1, 1, 1, 1], P)


def twisted_cubic_kappa_tau(t):
    q = 9 * t**4 + 9 * t**2 + 1
    kappa = 2 * np.sqrt(q) / (1 + 4 * t**2 + 9 * t**4) ** 1.5
    return kappa, 3 / q


def revolve(profile: BSplineCurve) -> BSplineSurface:
    """Surface of revolution about z of a profile curve in the xz-plane (NURBS Book A8.1 style):
    the u direction is the full circle of ``circle``, v the profile; exact."""
    c = circle([0, 0, 0], 1.0)
    cw = c.weights
    prof_P, prof_w = profile.control_points, (np.ones(profile.n_poles) if profile.weights is None else profile.weights)
    X = c.control_points  # (nu, 3) on the unit circle net, z = 0
    P = np.empty((c.n_poles, profile.n_poles, 3))
    P[..., 0] = X[:, None, 0] * prof_P[None, :, 0]
    P[..., 1] = X[:, None, 1] * prof_P[None, :, 0]
    P[..., 2] = np.broadcast_to(prof_P[None, :, 2], P.shape[:2])
    W = cw[:, None] * prof_w[None, :]
    return BSplineSurface((c.degree, profile.degree), (c.knots, profile.knots), P, W)


def sphere(r: float) -> BSplineSurface:
    # Half circle from the south to the north pole in the xz-plane: x = r cos, z = r sin.
    prof = arc([0, 0, 0], r, -np.pi / 2, np.pi / 2, normal=[0, -1, 0], xaxis=[1, 0, 0])
    return revolve(prof)


def torus(R: float, r: float) -> BSplineSurface:
    prof = circle([R, 0, 0], r, normal=[0, -1, 0], xaxis=[1, 0, 0])
    return revolve(prof)


def cylinder(r: float, h: float) -> BSplineSurface:
    prof = BSplineCurve(1, [0, 0, 1, 1], [[r, 0, 0], [r, 0, h]])
    return revolve(prof)


def grid(s: BSplineSurface, n: int = 9, margin: float = 0.0):
    (u0, u1), (v0, v1) = s.domain
    du, dv = margin * (u1 - u0), margin * (v1 - v0)
    return np.meshgrid(np.linspace(u0 + du, u1 - du, n), np.linspace(v0 + dv, v1 - dv, n), indexing="ij")


def outward(s: BSplineSurface, u, v, centre=(0.0, 0.0, 0.0)) -> np.ndarray:
    """+1 where our normal points away from ``centre``."""
    r = surface_curvatures(s, u, v)
    return np.sign(np.einsum("...i,...i->...", r.normal, s.evaluate(u, v) - np.asarray(centre)))


# ------------------------------------------------------------------------------------ curves
def test_circle_frenet_closed_form():
    r = 2.5
    c = circle([1, 2, 3], r, normal=[0, 0, 1])
    u = np.linspace(*c.domain, 41)
    f = curve_frenet(c, u)
    assert isinstance(f, FrenetFrame)
    assert_allclose(f.curvature, 1 / r, rtol=1e-13)
    assert_allclose(f.torsion, 0, atol=1e-13)
    # The normal points to the centre, the binormal is the circle's axis (counter-clockwise).
    assert_allclose(f.point + r * f.normal, np.broadcast_to([1, 2, 3], f.point.shape), atol=1e-12)
    assert_allclose(f.binormal, np.broadcast_to([0, 0, 1], f.binormal.shape), atol=1e-13)
    assert_allclose(curvature_derivative(c, u), 0, atol=1e-12)
    # Orthonormal, right-handed.
    assert_allclose(np.cross(f.tangent, f.normal), f.binormal, atol=1e-13)
    assert_allclose(np.linalg.norm(f.tangent, axis=-1), 1, rtol=1e-14)


def test_planar_curve_2d():
    c = circle([0, 0], 3.0)
    f = curve_frenet(c, np.linspace(*c.domain, 9))
    assert f.point.shape == (9, 2) and f.normal.shape == (9, 2) and f.binormal.shape == (9, 3)
    assert_allclose(f.curvature, 1 / 3, rtol=1e-13)
    assert_allclose(f.torsion, 0, atol=1e-14)
    assert_allclose(f.binormal, np.broadcast_to([0, 0, 1], (9, 3)), atol=1e-14)


def test_twisted_cubic_closed_form():
    c = twisted_cubic()
    t = np.linspace(0, 1, 33)
    k, tau = twisted_cubic_kappa_tau(t)
    assert_allclose(curvature(c, t), k, rtol=1e-13)
    assert_allclose(torsion(c, t), tau, rtol=1e-13)
    # dkappa/ds from the closed form: dkappa/dt / |C'|.
    h = 1e-5
    tt = np.linspace(0.1, 0.9, 9)
    dk = (twisted_cubic_kappa_tau(tt + h)[0] - twisted_cubic_kappa_tau(tt - h)[0]) / (2 * h)
    speed = np.sqrt(1 + 4 * tt**2 + 9 * tt**4)
    assert_allclose(curvature_derivative(c, tt), dk / speed, rtol=1e-8)


def test_vectorised_shapes():
    c = twisted_cubic()
    u = np.linspace(0, 1, 6).reshape(2, 3)
    f = curve_frenet(c, u)
    assert f.point.shape == (2, 3, 3) and f.curvature.shape == (2, 3) and f.torsion.shape == (2, 3)
    assert curvature(c, 0.5).shape == ()
    assert_allclose(f.curvature, curvature(c, u.ravel()).reshape(2, 3), rtol=0, atol=0)


def test_straight_line_gives_nan_normal_not_error():
    c = BSplineCurve(2, [0, 0, 0, 1, 1, 1], [[0, 0, 0], [1, 1, 1], [2, 2, 2]])
    with np.errstate(all="raise"):
        f = curve_frenet(c, np.linspace(0, 1, 5))
        dk = curvature_derivative(c, np.linspace(0, 1, 5))
    assert_allclose(f.curvature, 0)
    assert_allclose(f.tangent, np.full((5, 3), 1 / np.sqrt(3)), rtol=1e-14)
    assert np.all(np.isnan(f.normal)) and np.all(np.isnan(f.binormal)) and np.all(np.isnan(f.torsion))
    assert np.all(np.isnan(dk))


def test_inflection_gives_nan_normal():
    # y = x^3 style cubic with an inflection at t = 1/2 (the control polygon is point-symmetric).
    c = BSplineCurve(3, [0, 0, 0, 0, 1, 1, 1, 1], [[0, 0, 0], [1, 1, 0], [2, -1, 0], [3, 0, 0]])
    f = curve_frenet(c, [0.25, 0.5, 0.75])
    assert f.curvature[1] == 0 and np.all(np.isnan(f.normal[1]))
    assert np.all(np.isfinite(f.normal[[0, 2]]))


def test_zero_first_derivative_gives_nan():
    # Repeated first pole: C'(0) = 0.
    c = BSplineCurve(2, [0, 0, 0, 1, 1, 1], [[0, 0, 0], [0, 0, 0], [1, 1, 0]])
    f = curve_frenet(c, [0.0, 0.5])
    assert np.all(np.isnan(f.tangent[0])) and np.isnan(f.curvature[0])
    assert np.all(np.isfinite(f.tangent[1]))


def _curvature_roundoff(c: BSplineCurve, u: np.ndarray, shift: float) -> np.ndarray:
    """First-order bound on how far round-off moves the curvature of ``c`` moved rigidly by ``shift``.

    Moving the poles rounds each one by a few ulps of ``|P_i| + shift``; evaluating either curve
    rounds by about ``degree + 2`` ulps of ``sum_i |R_i^(k)(u)| |P_i|``. So the k-th derivative moves by
    at most ``e * a_k`` with ``a_k = sum_i |R_i^(k)(u)| (|P_i| + shift)`` (the rational basis functions'
    derivatives ``R_i^(k)``: the same curve with the unit vectors as poles) and
    ``e = 2 (degree + 4) eps``. Curvature ``|C' x C''| / |C'|^3`` then moves by at most
    ``e (a_1 |C''| + |C'| a_2) / |C'|^3 + 3 kappa e a_1 / |C'|``. This is not small where the poles
    differ in the last bits of a coordinate the shift makes large (hypothesis found a cubic whose
    curvature 6e-5 comes from pole differences of 6e-8 beside a shift of 3: 1.1e-8 relative).
    """
    n = len(c.control_points)
    R = BSplineCurve(c.degree, c.knots, np.eye(n), c.weights).derivatives(u, 2)  # (m, 3, n)
    size = np.linalg.norm(c.control_points, axis=-1) + shift
    a1, a2 = np.abs(R[:, 1]) @ size, np.abs(R[:, 2]) @ size
    d = c.derivatives(u, 2)
    d1, d2 = np.linalg.norm(d[:, 1], axis=-1), np.linalg.norm(d[:, 2], axis=-1)
    kappa = np.linalg.norm(np.cross(d[:, 1], d[:, 2]), axis=-1) / np.maximum(d1, 1e-300) ** 3
    e = 2 * (c.degree + 4) * np.finfo(float).eps
    return e * ((a1 * d2 + d1 * a2) / np.maximum(d1, 1e-300) ** 3 + 3 * kappa * a1 / np.maximum(d1, 1e-300))


@SETTINGS
@given(c=curves(degrees=st.integers(2, 5), dims=st.just(3)), f=st.lists(st.floats(0, 1), min_size=1, max_size=6),
       angle=st.floats(0, 6.28), shift=st.floats(-5, 5))
@example(  # |C' x C''| lands on the CURVATURE_ZERO threshold: one representation snaps to 0, the other not
    c=BSplineCurve(4, [2, 2, 2, 3, 3, 3, 4, 5, 6, 7, 8, 9, 10],
                   [[1, 1, 1], [1, 1, 1], [0, 1, 1], [1, 1, 1], [1, 0, 1], [1, 1, 1], [1, 1, 1], [1, 1, 1]]),
    f=[1e-12], angle=0.0, shift=0.0)
@example(  # the curvature (6e-5) comes from pole differences of 6e-8 beside a shift of 3: 1.1e-8 relative
    c=BSplineCurve(3, [2, 3, 6.75, 9.75, 12.75, 14.75, 15.75, 16.75, 16.75, 16.75, 16.75],
                   [[0, 2**-24, 2**-24], [2**-24, 1, 2**-24], [2**-24, 2**-24, 2**-24], [3, 2**-24, 2**-24],
                    [2**-24, 2**-24, 2**-24], [2**-24, 2**-24, 2**-24], [2**-24, 2**-24, 2**-24]]),
    f=[0.0], angle=0.0, shift=1.0)
@example(  # C' and C'' 1.5e-9 off parallel near a C1 knot: curvature 7.4e-6 moves 2.5e-13 on elevation
    c=BSplineCurve(5, [1] * 6 + [5] * 4 + [6.90625] * 2 + [7.90625, 8.90625, 9.90625, 10.90625, 11.90625],
                   [[1, 0, 0], [0, 0, 0], [0, 0, 0], [2, 1, 0]] + [[0, 0, 0]] * 7),
    f=[0.67578125], angle=0.0, shift=0.0)
def test_curvature_invariant_under_rigid_motion_and_refinement(c, f, angle, shift):
    lo, hi = c.domain
    u = lo + np.asarray(f) * (hi - lo)
    k0 = curve_frenet(c, u)
    assume(np.all(np.isfinite(k0.torsion)))
    ca, sa = np.cos(angle), np.sin(angle)
    Q = np.array([[ca, -sa, 0], [sa, ca, 0], [0, 0, 1]]) @ np.array([[1, 0, 0], [0, 0, -1], [0, 1, 0]])
    R = float(np.max(np.linalg.norm(c.control_points, axis=-1)))
    moved = c.transform(Q, [shift * R, 0, 0])  # a shift on the curve's own scale
    k1 = curve_frenet(moved, u)
    scale = max(np.max(k0.curvature), 1e-3 / max(R, 1e-300))  # below 1e-3/R: round-off of a line
    # Curvature is a ratio of derivatives: compare where the point is well away from a cusp.
    s = np.linalg.norm(c.derivatives(u, 1)[:, 1], axis=-1)
    good = s > 1e-3 * np.max(np.linalg.norm(np.diff(c.control_points, axis=0), axis=-1)) * c.degree
    bound = _curvature_roundoff(c, u, abs(shift) * R)
    assert np.all(np.abs(k1.curvature - k0.curvature)[good]
                  <= (1e-8 * k0.curvature + 1e-10 * scale + bound)[good])
    assert_allclose(k1.tangent[good], k0.tangent[good] @ Q.T, atol=1e-8)
    # Where the sine of the angle between C' and C'' is near tolerances.CURVATURE_ZERO, curvature snaps
    # to 0 on one side of the threshold: round-off of the two representations may fall on either
    # side. There both must be at most a few thresholds of |C''| / |C'|^2 (no Frenet normal in the
    # documented sense); everywhere else they must agree.
    d = c.derivatives(u, 2)
    d1, d2 = np.linalg.norm(d[:, 1], axis=-1), np.linalg.norm(d[:, 2], axis=-1)
    sine = np.linalg.norm(np.cross(d[:, 1], d[:, 2]), axis=-1) / np.maximum(d1 * d2, 1e-300)
    near = sine <= 10 * tolerances.CURVATURE_ZERO
    raised = c.elevate_degree()
    elevated = curvature(raised, u)
    clear = good & ~near
    # Degree elevation rounds each new pole (a convex combination of the old ones) by a few ulps, as
    # the rigid motion does without its shift: the same first-order bound, for both representations.
    lifted = _curvature_roundoff(c, u, 0.0) + _curvature_roundoff(raised, u, 0.0)
    assert np.all(np.abs(elevated - k0.curvature)[clear]
                  <= (1e-8 * k0.curvature + 1e-10 * scale + lifted)[clear])
    bound = 10 * tolerances.CURVATURE_ZERO * d2 / np.maximum(d1, 1e-300) ** 2 * (1 + 1e-8)
    assert np.all(elevated[good & near] <= bound[good & near])
    assert np.all(k0.curvature[good & near] <= bound[good & near])


def test_arc_length_circle():
    r = 1.7
    c = circle([0, 0, 0], r)
    lo, hi = c.domain
    assert abs(arc_length(c, lo, hi) - 2 * np.pi * r) <= 1e-12
    # The circle's parameter is the angle only at the knots; compare against the knot angles.
    a = arc([0, 0, 0], r, 0.3, 2.9)
    assert abs(arc_length(a, *a.domain) - r * 2.6) <= 1e-12
    # Vectorised, additive, signed.
    u = np.linspace(lo, hi, 7)
    parts = arc_length(c, u[:-1], u[1:])
    assert parts.shape == (6,)
    assert abs(parts.sum() - 2 * np.pi * r) <= 1e-12
    assert_allclose(arc_length(c, u[1:], u[:-1]), -parts, rtol=0, atol=0)
    assert arc_length(c, 1.0, 1.0) == 0.0


def test_arc_length_twisted_cubic_against_gauss():
    # Reference: a 200-point Gauss–Legendre rule on the analytic speed (entire on [0, 1]: exact to
    # round-off), independent of our spans and adaptivity.
    c = twisted_cubic()
    x, w = np.polynomial.legendre.leggauss(200)
    t = 0.5 * (x + 1)
    ref = 0.5 * np.sum(w * np.sqrt(1 + 4 * t**2 + 9 * t**4))
    assert abs(arc_length(c, 0.0, 1.0) - ref) <= 1e-13
    assert abs(arc_length(c, 0.0, 1.0, tol=1e-6) - ref) <= 1e-6


def test_arc_length_errors():
    c = twisted_cubic()
    with pytest.raises(ParameterError):
        arc_length(c, 0.0, 2.0)
    with pytest.raises(InvalidGeometryError, match="tol"):  # a bad tol is bad input, as everywhere
        arc_length(c, 0.0, 1.0, tol=-1.0)
    with pytest.raises(InvalidGeometryError):
        curvature("not a curve", 0.5)


# ------------------------------------------------------------------------------------ RMF
def _check_rmf(c: BSplineCurve, m: int, **kw):
    u = np.linspace(*c.domain, m)
    fr = rotation_minimizing_frames(c, u, **kw)
    T, r, s = fr.tangent, fr.normal, fr.binormal
    frame = np.stack([T, r, s], axis=-1)
    assert_allclose(np.einsum("mji,mjk->mik", frame, frame), np.broadcast_to(np.eye(3), (m, 3, 3)), atol=1e-13)
    assert_allclose(np.linalg.det(frame), 1, atol=1e-13)
    return u, fr


@SETTINGS
@given(c=curves(dims=st.just(3)), fs=st.lists(st.floats(0, 1), min_size=1, max_size=9))
def test_frenet_axes_are_curve_frenets_frames(c, fs):
    """frenet_axes (the sweep's frames from derivatives it already has) gives curve_frenet's
    tangent, normal and binormal bit for bit, NaN where they are undefined."""
    lo, hi = c.domain
    u = lo + np.array(fs) * (hi - lo)
    f = curve_frenet(c, u)
    F = frenet_axes(c.derivatives(u, 2))
    assert F.shape == (u.shape[0], 3, 3)
    assert np.array_equal(F, np.stack([f.tangent, f.normal, f.binormal], axis=-1), equal_nan=True)


def test_frenet_axes_flags_lines_and_rejects_bad_shapes():
    line = BSplineCurve(1, [0, 0, 1, 1], [[0, 0, 0], [1, 2, 3]])
    F = frenet_axes(line.derivatives(np.array([0.2, 0.7]), 2))
    assert_allclose(F[:, :, 0], np.broadcast_to(np.array([1, 2, 3]) / np.sqrt(14), (2, 3)), atol=1e-15)
    assert np.isnan(F[:, :, 1:]).all()
    with pytest.raises(InvalidGeometryError, match=r"expected shape S \+ \(k >= 3, 3\)"):
        frenet_axes(line.derivatives(np.array([0.2]), 1))
    with pytest.raises(InvalidGeometryError, match="D: expected an array of derivatives, got str"):
        frenet_axes("abc")


@pytest.mark.parametrize("n", [0, 1, 2, 7, 100, 1153])
def test_chain_of_steps_equals_the_sequential_product(n):
    """The two-level scan of rotation_minimizing_frames against the plain loop r_{i+1} = M_i r_i."""
    rng = np.random.default_rng(n)
    Q, _ = np.linalg.qr(rng.normal(size=(n, 3, 3)))
    r0 = np.array([0.6, 0.0, 0.8])
    expect = [r0]
    for M in Q:
        expect.append(M @ expect[-1])
    got = differential._chain(Q, r0)
    assert got.shape == (n + 1, 3)
    assert_allclose(got, np.array(expect), rtol=0, atol=1e-14 * max(1.0, np.sqrt(n)))


def test_rmf_has_no_twist_on_space_curve():
    c = twisted_cubic()
    u, fr = _check_rmf(c, 2001)
    # Angular velocity omega of the frame: r' = omega x r, so omega . T = s . r'. For an RMF this
    # tangential component vanishes; compare against the normal component |T'| (curvature * speed).
    h = u[1] - u[0]
    dr = (fr.normal[2:] - fr.normal[:-2]) / (2 * h)
    twist = np.einsum("mi,mi->m", fr.binormal[1:-1], dr)
    dT = (fr.tangent[2:] - fr.tangent[:-2]) / (2 * h)
    assert np.max(np.abs(twist)) <= 1e-6 * np.max(np.linalg.norm(dT, axis=-1))
    # The Frenet frame of the same curve does twist (torsion != 0): the check has teeth.
    f = curve_frenet(c, u)
    dn = (f.normal[2:] - f.normal[:-2]) / (2 * h)
    assert np.max(np.abs(np.einsum("mi,mi->m", f.binormal[1:-1], dn))) > 0.1
    # Convergence: fourth order (Wang et al. 2008), so 250 steps agree with 2000 to ~1e-7.
    _, coarse = _check_rmf(c, 251)
    assert_allclose(coarse.normal, fr.normal[::8], atol=1e-7)


def test_rmf_equals_frenet_on_planar_curve():
    c = arc([0, 0, 0], 2.0, 0.0, 3.0)
    u, fr = _check_rmf(c, 50)
    f = curve_frenet(c, u)
    assert_allclose(fr.normal, f.normal, atol=1e-12)
    # With another initial normal the RMF is the Frenet frame rotated by a constant angle.
    u, fr2 = _check_rmf(c, 50, initial_normal=[0, 0, 1])
    assert_allclose(fr2.normal, np.broadcast_to([0, 0, 1], (50, 3)), atol=1e-12)
    assert_allclose(fr2.binormal, -f.normal, atol=1e-12)


def test_rmf_on_2d_curve_and_errors():
    c = circle([0, 0], 1.0)
    u, fr = _check_rmf(c, 20, initial_normal=[0.3, 0.0, 1.0])
    assert_allclose(fr.normal[:, 2], fr.normal[0, 2], atol=1e-12)
    with pytest.raises(InvalidGeometryError):
        rotation_minimizing_frames(c, u, initial_normal=fr.tangent[0])
    with pytest.raises(InvalidGeometryError):
        rotation_minimizing_frames(c, u.reshape(4, 5))


# ------------------------------------------------------------------------------------ surfaces
def test_sphere_closed_form():
    r = 3.0
    s = sphere(r)
    uu, vv = grid(s, 11, margin=0.02)
    res = surface_curvatures(s, uu, vv)
    assert isinstance(res, SurfaceCurvatures)
    sign = outward(s, uu, vv)
    assert np.all(sign == sign.flat[0])
    assert_allclose(res.gaussian, 1 / r**2, rtol=1e-12)
    assert_allclose(res.mean, -sign / r, rtol=1e-12)  # OCC convention: outward normal -> H = -1/r
    assert_allclose(res.k1, -sign / r, rtol=1e-11)
    assert_allclose(res.k2, -sign / r, rtol=1e-11)
    assert np.all(is_umbilic(s, uu, vv))
    # Principal frame is orthonormal and right-handed even at umbilics.
    assert_allclose(np.cross(res.dir1, res.dir2), res.normal, atol=1e-12)


def test_sphere_pole_is_nan():
    s = sphere(2.0)
    (u0, u1), (v0, v1) = s.domain
    with np.errstate(all="raise"):
        res = surface_curvatures(s, [0.4, 0.4, 0.4], [v0, v1, 0.5 * (v0 + v1)])
    for name in ("gaussian", "mean", "k1", "k2"):
        val = getattr(res, name)
        assert np.all(np.isnan(val[:2])) and np.isfinite(val[2]), name
    assert np.all(np.isnan(res.normal[:2])) and np.all(np.isnan(res.dir1[:2]))
    assert not np.any(is_umbilic(s, [0.4, 0.4], [v0, v1]))
    assert np.all(np.isnan(normal_curvature(s, [0.4, 0.4], [v0, v1], [1.0, 0.0])))


def test_cylinder_closed_form():
    r = 2.0
    s = cylinder(r, 5.0)
    uu, vv = grid(s, 7)
    res = surface_curvatures(s, uu, vv)
    sign = outward(s, uu, vv, centre=(0, 0, 0))  # x, y part is all that matters; z = 0 plane centre
    centre = np.zeros(uu.shape + (3,))
    centre[..., 2] = s.evaluate(uu, vv)[..., 2]
    sign = np.sign(np.einsum("...i,...i->...", res.normal, s.evaluate(uu, vv) - centre))
    assert np.all(sign == sign.flat[0])
    k = sorted([0.0, -sign.flat[0] / r])
    assert_allclose(res.k1, k[1], atol=1e-13)
    assert_allclose(res.k2, k[0], rtol=1e-12)
    assert_allclose(res.gaussian, 0, atol=1e-13)
    assert_allclose(res.mean, k[0] / 2, rtol=1e-12)
    # The zero-curvature direction is the axis.
    flat = res.dir1 if k[1] == 0 else res.dir2
    assert_allclose(np.abs(flat[..., 2]), 1, atol=1e-12)
    assert not np.any(is_umbilic(s, uu, vv))


def test_torus_closed_form():
    R, r = 5.0, 1.0
    s = torus(R, r)
    uu, vv = grid(s, 13)
    res = surface_curvatures(s, uu, vv)
    P = s.evaluate(uu, vv)
    rho = np.hypot(P[..., 0], P[..., 1])
    cos_phi = (rho - R) / r  # cos of the tube angle (1 outer equator, -1 inner)
    sign = np.sign(np.einsum("...i,...i->...", res.normal, P - np.stack([R * P[..., 0] / rho, R * P[..., 1] / rho, 0 * rho], -1)))
    assert np.all(sign == sign.flat[0])
    sg = sign.flat[0]
    assert_allclose(res.gaussian, cos_phi / (r * (R + r * cos_phi)), atol=1e-13)
    assert_allclose(res.mean, -sg * (R + 2 * r * cos_phi) / (2 * r * (R + r * cos_phi)), rtol=1e-12)
    # Outer equator K = 1/(r(R+r)) > 0, inner equator K = -1/(r(R-r)) < 0.
    out = np.isclose(cos_phi, 1, atol=1e-14)
    inn = np.isclose(cos_phi, -1, atol=1e-14)
    assert out.any() and inn.any()
    assert_allclose(res.gaussian[out], 1 / (r * (R + r)), rtol=1e-12)
    assert_allclose(res.gaussian[inn], -1 / (r * (R - r)), rtol=1e-12)
    kt, kr = -sg / r, -sg * cos_phi / (R + r * cos_phi)  # tube and rotational normal curvatures
    assert_allclose(res.k1, np.maximum(kt, kr), atol=1e-12)
    assert_allclose(res.k2, np.minimum(kt, kr), atol=1e-12)


def test_plane_is_flat_umbilic():
    s = BSplineSurface((2, 2), ([0, 0, 0, 1, 1, 1],) * 2,
                       np.stack(list(np.meshgrid([0, 0.7, 2], [0, 1.1, 2], indexing="ij")) + [np.zeros((3, 3))], -1))
    uu, vv = grid(s, 5)
    res = surface_curvatures(s, uu, vv)
    assert_allclose(np.stack([res.gaussian, res.mean, res.k1, res.k2]), 0, atol=1e-15)
    assert np.all(is_umbilic(s, uu, vv))


def test_forms_and_shapes():
    s = torus(4.0, 1.5)
    u = np.full((2, 3), 1.0)
    v = np.linspace(0.1, 5.0, 3)
    res = surface_curvatures(s, u, v)
    assert res.k1.shape == (2, 3) and res.dir1.shape == (2, 3, 3) and res.first_form[0].shape == (2, 3)
    E, F, G = res.first_form
    L, M, N = res.second_form
    assert_allclose(res.gaussian, (L * N - M * M) / (E * G - F * F), rtol=1e-12)
    assert_allclose(res.k1 * res.k2, res.gaussian, rtol=1e-12)
    assert_allclose((res.k1 + res.k2) / 2, res.mean, rtol=1e-12)
    k1, k2 = principal_curvatures(s, u, v)
    assert_allclose(k1, res.k1, rtol=0, atol=0)


def _to_uv(s: BSplineSurface, u, v, d3):
    D = s.derivatives(u, v, 1)
    J = np.stack([D[..., 1, 0, :], D[..., 0, 1, :]], -1)  # (..., 3, 2)
    return np.linalg.lstsq(J, d3, rcond=None)[0]


@SETTINGS
@given(s=surfaces(degrees=st.integers(2, 5), dims=st.just(3)), fu=st.floats(0, 1), fv=st.floats(0, 1))
def test_euler_theorem_random_surfaces(s, fu, fv):
    (u0, u1), (v0, v1) = s.domain
    u, v = u0 + fu * (u1 - u0), v0 + fv * (v1 - v0)
    res = surface_curvatures(s, u, v)
    D = s.derivatives(u, v, 1)
    su, sv = D[1, 0], D[0, 1]
    sin = np.linalg.norm(np.cross(su, sv)) / (np.linalg.norm(su) * np.linalg.norm(sv) + 1e-300)
    lu, lv = np.linalg.norm(su), np.linalg.norm(sv)
    assume(sin > 1e-2 and min(lu, lv) >= 1e-2 * max(lu, lv))
    assert np.isfinite(res.k1) and np.isfinite(res.k2)
    k1, k2 = float(res.k1), float(res.k2)
    R = float(np.max(np.linalg.norm(s.control_points, axis=-1)))
    scale = max(abs(k1), abs(k2), 1e-3 / max(R, 1e-300))  # below 1e-3/R: round-off of a plane
    # Principal directions are tangent and orthonormal; their normal curvatures are k1, k2.
    assert_allclose(np.array([res.dir1 @ res.normal, res.dir2 @ res.normal, res.dir1 @ res.dir2]), 0, atol=1e-12)
    assert_allclose(normal_curvature(s, u, v, _to_uv(s, u, v, res.dir1)), k1, atol=1e-9 * scale)
    assert_allclose(normal_curvature(s, u, v, _to_uv(s, u, v, res.dir2)), k2, atol=1e-9 * scale)
    # Euler: k(theta) = k1 cos^2 + k2 sin^2 for the direction at angle theta from dir1.
    th = np.linspace(0, np.pi, 37)
    d3 = np.cos(th)[:, None] * res.dir1 + np.sin(th)[:, None] * res.dir2
    duv = np.stack([_to_uv(s, u, v, d) for d in d3])
    kn = normal_curvature(s, np.full(37, u), np.full(37, v), duv)
    assert_allclose(kn, k1 * np.cos(th) ** 2 + k2 * np.sin(th) ** 2, atol=1e-9 * scale)
    assert np.all(kn <= k1 + 1e-9 * scale) and np.all(kn >= k2 - 1e-9 * scale)


def test_normal_curvature_errors_and_zero_direction():
    s = torus(4.0, 1.0)
    assert np.isnan(normal_curvature(s, 1.0, 1.0, [0.0, 0.0]))
    with pytest.raises(InvalidGeometryError):
        normal_curvature(s, 1.0, 1.0, [1.0, 0.0, 0.0])
    flat = BSplineSurface((1, 1), ([0, 0, 1, 1],) * 2, np.zeros((2, 2, 2)) + [[[0, 0], [0, 1]], [[1, 0], [1, 1]]])
    with pytest.raises(InvalidGeometryError):
        surface_curvatures(flat, 0.5, 0.5)


@pytest.mark.parametrize("tol", ["1e-3", -1.0, 0.0, float("nan"), True])
def test_arc_length_tol_must_be_a_positive_number(tol):
    """Review: a string tol raised a bare TypeError from np.isfinite, a negative one ToleranceError."""
    from occsurf.algorithms import circle

    with pytest.raises(InvalidGeometryError, match="tol: expected a positive finite number"):
        arc_length(circle([0, 0, 0], 1.0), 0.0, 1.0, tol=tol)
