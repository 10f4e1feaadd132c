"""Scattered-data least squares (course ch. 7): sparse normal equations, smoothing over holes,
parameter correction.

Oracles: scipy's ``LSQBivariateSpline`` (FITPACK, Givens rotations) on the same knots must give
the same surface (evaluations to 1e-10); points sampled from a spline of the fitted space are
reproduced; the normal equations assembled cell by cell equal ``A^T A`` of the explicit sparse
collocation matrix.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.interpolate import LSQBivariateSpline

from occsurf.algorithms import BSplineSurface, tolerances
from occsurf.algorithms.errors import InvalidGeometryError, ParameterError
from occsurf.algorithms.fitting._common import clamped_uniform_knots
from occsurf.algorithms.fitting.scattered import _normal_equations, fit_scattered, scattered_collocation


def _cloud(k=6000, seed=0, noise=0.0):
    rng = np.random.default_rng(seed)
    x, y = rng.random(k), rng.random(k)
    z = np.sin(3 * x) * np.cos(2 * y) + noise * rng.standard_normal(k)
    return x, y, np.stack([x, y, z], -1)


def test_equals_fitpack_lsq_bivariate_spline():
    x, y, P = _cloud(noise=0.01)
    fit = fit_scattered(P, (12, 9), 3, params=np.c_[x, y], smoothing=0.0)
    tu, tv = fit.surface.knots
    ref = LSQBivariateSpline(x, y, P[:, 2], tu[4:-4], tv[4:-4], kx=3, ky=3)
    uu, vv = np.random.default_rng(1).random((2, 500))
    np.testing.assert_allclose(fit.surface.evaluate(uu, vv)[:, 2], ref.ev(uu, vv), atol=1e-10)


def test_normal_equations_by_cells_equal_the_explicit_product():
    x, y, P = _cloud(3000, seed=3)
    kn = (clamped_uniform_knots(0, 1, 9, 2), clamped_uniform_knots(0, 1, 7, 3))
    A = scattered_collocation(kn, (2, 3), (9, 7), x, y)
    G, rhs = _normal_equations(kn, (2, 3), (9, 7), x, y, P)
    np.testing.assert_allclose(G.toarray(), (A.T @ A).toarray(), atol=1e-12)
    np.testing.assert_allclose(rhs, A.T @ P, atol=1e-12)


def test_reproduces_a_spline_of_the_same_space():
    rng = np.random.default_rng(5)
    kn = (clamped_uniform_knots(0, 1, 7, 3), clamped_uniform_knots(0, 1, 6, 2))
    s = BSplineSurface((3, 2), kn, rng.standard_normal((7, 6, 3)))
    uv = rng.random((4000, 2))
    fit = fit_scattered(s.evaluate(uv[:, 0], uv[:, 1]), (7, 6), (3, 2), params=uv, knots=kn, smoothing=0.0,
                        measure=False)
    np.testing.assert_allclose(fit.surface.control_points, s.control_points, atol=1e-10)


def test_holes_are_kept_defined_by_the_smoothing_term():
    x, y, P = _cloud(8000, seed=2)
    keep = (x - 0.5) ** 2 + (y - 0.5) ** 2 > 0.05  # a hole wider than several knot spans
    uv = np.c_[x[keep], y[keep]]
    fit = fit_scattered(P[keep], 30, 3, params=uv)
    assert np.all(np.isfinite(fit.surface.control_points)) and fit.max_error < 1e-3
    inside = fit.surface.evaluate(np.array([0.5]), np.array([0.5]))[0, 2]
    assert abs(inside - np.sin(1.5) * np.cos(1.0)) < 0.05  # the smooth continuation over the hole
    with pytest.raises(InvalidGeometryError, match="smoothing"):
        fit_scattered(P[keep], 30, 3, params=uv, smoothing=0.0)
    with tolerances.override(FIT_SCATTERED_SMOOTHING=0.0), pytest.raises(InvalidGeometryError):
        fit_scattered(P[keep], 30, 3, params=uv)


def test_parameter_correction_reduces_the_error_of_a_curved_sheet():
    rng = np.random.default_rng(8)
    a, h = rng.random(5000) * 3.0, rng.random(5000)
    P = np.stack([np.cos(a), np.sin(a), h], -1)  # a half cylinder: plane parameters crowd its flanks
    plain = fit_scattered(P, 6, 3)
    better = fit_scattered(P, 6, 3, corrections=3)
    # measured: rms 0.0157 -> 0.0111, max 0.094 -> 0.072
    assert better.rms_error < 0.8 * plain.rms_error and better.max_error < 0.85 * plain.max_error
    assert better.corrections == 3


def test_parameters_from_a_base_surface():
    from occsurf.algorithms import circle, extrude

    cyl = extrude(circle([0, 0, 0], 1.0), [0, 0, 1.0])
    (u0, u1), (v0, v1) = cyl.domain
    rng = np.random.default_rng(9)
    uu, vv = u0 + (0.1 + 0.4 * rng.random(3000)) * (u1 - u0), v0 + (v1 - v0) * rng.random(3000)
    P = cyl.evaluate(uu, vv) * [1.001, 1.001, 1.0]  # a scan 0.001 off the face, away from its seam
    from occsurf.algorithms.fitting.scattered import base_parameters

    u, v = base_parameters(cyl, P)
    np.testing.assert_allclose(np.c_[u, v], np.c_[uu, vv], atol=1e-9)  # radial offset: the same foot points
    fit = fit_scattered(P, 12, 3, base=cyl)
    exact = fit_scattered(P, 12, 3, params=np.c_[uu, vv])
    assert fit.max_error == pytest.approx(exact.max_error, rel=1e-6)


def test_bad_input():
    x, y, P = _cloud(100)
    with pytest.raises(InvalidGeometryError, match="points"):
        fit_scattered(P[:, :2], 5)
    with pytest.raises(InvalidGeometryError, match="at least"):
        fit_scattered(P[:10], 5)
    with pytest.raises(InvalidGeometryError, match="n_poles"):
        fit_scattered(P, 2, 3)
    with pytest.raises(ParameterError, match="smoothing"):
        fit_scattered(P, 5, smoothing=-1)
    with pytest.raises(InvalidGeometryError, match="params"):
        fit_scattered(P, 5, params=np.zeros((100, 3)))
    with pytest.raises(InvalidGeometryError, match="area"):
        fit_scattered(P, 5, params=np.zeros((100, 2)))
