"""Adaptive hierarchical fitting of scattered data (course §7-10 on point clouds, issue 13).

Checks: the tolerance holds at every point (distance measured by projection, never more than the
deviation at the point's parameters); cross-checks against the gridded path on gridded input (the
same base, the same level-1 regions, an overlay solve that agrees with the gridded pseudo-inverse,
and final surfaces within the tolerance of each other with comparable control-point counts);
reproduction of the base space; the course's claim on a sharp feature (far fewer control points
than the uniform scattered least squares meeting the same tolerance); holes; an editable
hierarchy whose flat form equals it; tolerances read at call time; bad input named.
"""

from __future__ import annotations

import numpy as np
import pytest

from occsurf.algorithms import BSplineSurface, tolerances
from occsurf.algorithms.errors import InvalidGeometryError, ParameterError
from occsurf.algorithms.fitting import fit_adaptive, fit_adaptive_scattered, fit_grid, fit_scattered
from occsurf.algorithms.fitting._common import clamped_uniform_knots
from occsurf.algorithms.fitting.adaptive import _Fitter
from occsurf.algorithms.fitting.adaptive_scattered import _ScatteredFitter, block_collocation
from occsurf.algorithms.hierarchical import HierarchicalSurface
from occsurf.examples.fitting import sharp_feature

EXACT = 1e-12


def _cloud(k, seed=0, f=sharp_feature):
    rng = np.random.default_rng(seed)
    x, y = rng.random(k), rng.random(k)
    x[:4], y[:4] = [0, 1, 0, 1], [0, 0, 1, 1]  # the corners: the parameter box is the unit square
    return x, y, np.c_[x, y, f(x, y)]


@pytest.fixture(scope="module")
def sharp_cloud():
    x, y, P = _cloud(12000)
    return x, y, P, fit_adaptive_scattered(P, 2e-3, params=np.c_[x, y])


def test_tolerance_holds_and_is_measured(sharp_cloud):
    x, y, P, fit = sharp_cloud
    assert fit.converged and fit.max_error <= 2e-3
    flat = fit.hierarchy.flatten()
    resid = np.linalg.norm(flat.evaluate(x, y) - P, axis=-1)
    assert np.all(fit.distance <= resid + EXACT)
    assert float(fit.distance.max()) == pytest.approx(fit.max_error)
    assert fit.levels[0].max_error > 0.1 and fit.hierarchy.depth >= 2
    assert sum(L.control_points for L in fit.levels) == fit.control_points_total


def test_fewer_control_points_than_uniform_scattered_least_squares(sharp_cloud):
    x, y, P, fit = sharp_cloud
    uniform = None
    for n in range(8, 80, 4):
        f = fit_scattered(P, n, 3, params=np.c_[x, y])
        if f.max_error <= 2e-3:
            uniform = n * n
            break
    assert uniform is None or fit.control_points_total * 2 < uniform, (fit.control_points_total, uniform)
    deepest = [o for o in fit.hierarchy.overlays if o.level == fit.hierarchy.depth]
    for o in deepest:  # the finest overlays sit on the feature at (0.62, 0.41)
        (a, b), (c, d) = o.region
        assert a - 0.15 <= 0.62 <= b + 0.15 and c - 0.15 <= 0.41 <= d + 0.15


def test_result_is_an_editable_hierarchy(sharp_cloud):
    *_, fit = sharp_cloud
    hs = fit.hierarchy.copy()
    uu, vv = np.random.default_rng(1).random((2, 300))
    np.testing.assert_allclose(hs.flatten().evaluate(uu, vv), hs.evaluate(uu, vv), atol=EXACT)
    again = HierarchicalSurface.from_dict(hs.to_dict())
    np.testing.assert_allclose(again.evaluate(uu, vv), hs.evaluate(uu, vv), atol=EXACT)
    offs = {o.id: hs.offsets(o) for o in hs.overlays}
    before = hs.evaluate(uu, vv)
    hs.move_vertex(None, (2, 2), (0.0, 0.0, 0.1))  # a coarse edit: the fitted details ride along
    assert np.abs(hs.evaluate(uu, vv) - before).max() > 0.01
    for o in hs.overlays:
        np.testing.assert_array_equal(hs.offsets(o), offs[o.id])


@pytest.mark.slow
def test_on_gridded_input_it_follows_the_gridded_path():
    x = np.linspace(0, 1, 101)
    X, Y = np.meshgrid(x, x, indexing="ij")
    Z = sharp_feature(X, Y)
    P = np.stack([X, Y, Z], -1).reshape(-1, 3)
    tol = 2e-3
    with tolerances.override(FIT_ADAPTIVE_MAX_COVER=1.0):  # an ungrown 8 x 8 base
        grid = fit_adaptive(Z, tol)
    cloud = fit_adaptive_scattered(P, tol, params=P[:, :2], smoothing=0.0, knots=grid.hierarchy.base.knots)
    # the same least-squares base to start from (then both are refitted by backfitting)
    kn = grid.hierarchy.base.knots
    b_grid = fit_grid(Z, 8, 3, knots=kn).surface
    b_cloud = fit_scattered(P, 8, 3, params=P[:, :2], knots=kn, smoothing=0.0).surface
    np.testing.assert_allclose(b_cloud.control_points, b_grid.control_points, atol=1e-10)
    np.testing.assert_allclose(cloud.hierarchy.base.control_points, grid.hierarchy.base.control_points, atol=1e-4)
    assert cloud.levels[0].max_error == pytest.approx(grid.levels[0].max_error, rel=1e-3)
    # the same overlays (regions and parents), the same storage, both within the tolerance
    assert [(o.region, o.parent) for o in grid.hierarchy.overlays] == \
        [(o.region, o.parent) for o in cloud.hierarchy.overlays]
    assert grid.converged and cloud.converged
    assert grid.control_points_total == cloud.control_points_total
    # and the same surface: the overlay solves differ only in how weakly determined vertices are
    # damped (truncated pseudo-inverse vs ridge, both at FIT_OVERLAY_RCOND); measured 4e-7
    d = np.abs(grid.hierarchy.evaluate_grid(x, x) - cloud.hierarchy.evaluate_grid(x, x)).max()
    assert d <= 1e-5
    assert cloud.max_error == pytest.approx(grid.max_error, abs=1e-5)


def test_overlay_solve_agrees_with_the_gridded_pseudo_inverse():
    x = np.linspace(0, 1, 41)
    X, Y = np.meshgrid(x, x, indexing="ij")
    Z = sharp_feature(X, Y)
    base = fit_grid(Z, 8, 3).surface
    P3 = np.stack([X, Y, Z], -1)
    hs_g, hs_s = HierarchicalSurface(base, "frame"), HierarchicalSurface(base, "frame")
    og = hs_g.add_overlay((0.3, 0.9), (0.1, 0.7))
    os_ = hs_s.add_overlay((0.3, 0.9), (0.1, 0.7))
    fg = _Fitter(hs_g, P3, x, x, False, None)
    fs = _ScatteredFitter(hs_s, P3.reshape(-1, 3), X.ravel(), Y.ravel(), None)
    rg, rs = fg.residual(), fs.residual()
    fg.fit_overlay(og, rg)
    fs.fit_overlay(os_, rs)
    scale = np.abs(P3 - base.evaluate_grid(x, x)).max()
    # the surfaces after the overlay fit agree to the damping's order (rcond 1e-3 of the residual)
    np.testing.assert_allclose(hs_s.evaluate_grid(x, x), hs_g.evaluate_grid(x, x), atol=2e-3 * scale)
    np.testing.assert_allclose(rs.reshape(rg.shape), rg, atol=2e-3 * scale)
    assert np.abs(rg).max() < 0.75 * scale  # the overlay took a share of the feature (measured 0.69)


def test_block_collocation_is_the_columns_of_the_full_one():
    from occsurf.algorithms.fitting.scattered import scattered_collocation

    kn = (clamped_uniform_knots(0, 1, 11, 3), clamped_uniform_knots(0, 1, 9, 2))
    u, v = np.random.default_rng(3).random((2, 500))
    full = scattered_collocation(kn, (3, 2), (11, 9), u, v).toarray().reshape(500, 11, 9)
    blk = block_collocation(kn, (3, 2), ((2, 6), (3, 8)), u, v).toarray().reshape(500, 5, 6)
    np.testing.assert_allclose(blk, full[:, 2:7, 3:9], atol=EXACT)


def test_data_of_the_base_space_need_no_overlay():
    rng = np.random.default_rng(4)
    kn = (clamped_uniform_knots(0, 1, 8, 3), clamped_uniform_knots(0, 1, 8, 3))
    s = BSplineSurface((3, 3), kn, rng.standard_normal((8, 8, 3)))
    uv = rng.random((3000, 2))
    uv[:4] = [[0, 0], [1, 0], [0, 1], [1, 1]]
    fit = fit_adaptive_scattered(s.evaluate(uv[:, 0], uv[:, 1]), 1e-9, params=uv, smoothing=0.0)
    assert not fit.hierarchy.overlays and fit.max_error < 1e-10
    np.testing.assert_allclose(fit.hierarchy.base.control_points, s.control_points, atol=1e-9)


def test_a_hole_stays_defined():
    x, y, P = _cloud(10000, seed=5)
    keep = (x - 0.3) ** 2 + (y - 0.7) ** 2 > 0.02  # a hole away from the feature, wider than base spans
    fit = fit_adaptive_scattered(P[keep], 2e-3, params=np.c_[x[keep], y[keep]])
    assert fit.converged
    inside = fit.hierarchy.evaluate(0.3, 0.7)[2]
    assert np.isfinite(inside) and abs(inside - sharp_feature(0.3, 0.7)) < 0.02


def test_noisy_scan_over_a_curved_sheet_with_parameter_correction():
    rng = np.random.default_rng(6)
    a, h = rng.random(8000) * 2.5, rng.random(8000)
    P = np.stack([np.cos(a), np.sin(a), h + 0.05 * np.exp(-((a - 1.2) ** 2 + (h - 0.5) ** 2) / 0.005)], -1)
    P += 2e-4 * rng.standard_normal(P.shape)
    fit = fit_adaptive_scattered(P, 2e-3, corrections=2)
    assert fit.converged and fit.max_error <= 2e-3
    assert fit.hierarchy.overlays  # the bump needed refinement


def test_tolerances_are_read_at_call_time():
    x, y, P = _cloud(3000, seed=7)
    with tolerances.override(FIT_ADAPTIVE_SPAN_POINTS=10 ** 6, FIT_ADAPTIVE_MAX_COVER=1.0):
        none = fit_adaptive_scattered(P, 1e-4, params=np.c_[x, y])
    assert not none.hierarchy.overlays and not none.converged
    some = fit_adaptive_scattered(P, 1e-4, params=np.c_[x, y], max_levels=1)
    assert some.hierarchy.overlays and some.hierarchy.depth == 1


def test_bad_input():
    x, y, P = _cloud(200)
    with pytest.raises(ParameterError, match="tol"):
        fit_adaptive_scattered(P, 0.0)
    with pytest.raises(ParameterError, match="tol"):
        fit_adaptive_scattered(P, "x")
    with pytest.raises(ParameterError, match="max_levels"):
        fit_adaptive_scattered(P, 1e-3, max_levels=-1)
    with pytest.raises(InvalidGeometryError, match="points"):
        fit_adaptive_scattered(P[:, :2], 1e-3)
    with pytest.raises(InvalidGeometryError, match="at least"):
        fit_adaptive_scattered(P[:10], 1e-3)
    with pytest.raises(InvalidGeometryError, match="params"):
        fit_adaptive_scattered(P, 1e-3, params=np.zeros((200, 3)))
    with pytest.raises(InvalidGeometryError, match="area"):
        fit_adaptive_scattered(P, 1e-3, params=np.zeros((200, 2)))
    with pytest.raises(ParameterError, match="smoothing"):
        fit_adaptive_scattered(P, 1e-3, smoothing=-1.0)


def test_partial_measure_is_exact_against_every_threshold_above_it():
    from occsurf.algorithms.fitting.adaptive_scattered import measure_points

    x, y, P = _cloud(4000, seed=9)
    s = fit_scattered(P, 10, 3, params=np.c_[x, y]).surface
    full = measure_points(s, P, x, y)
    part = measure_points(s, P, x, y, above=1e-3)
    resid = np.linalg.norm(s.evaluate(x, y) - P, axis=-1)
    skipped = resid <= 1e-3
    assert skipped.any() and (~skipped).any()
    np.testing.assert_array_equal(part[skipped], resid[skipped])
    np.testing.assert_array_equal(part[~skipped], full[~skipped])
    for t in (1e-3, 1e-2, 0.1):
        np.testing.assert_array_equal(part > t, full > t)
