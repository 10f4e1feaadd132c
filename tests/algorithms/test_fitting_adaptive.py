"""Adaptive hierarchical fitting (course §7-10) and the point projection that measures it.

Checks: the tolerance holds at every data point (distance measured by projection, and never more
than the residual at the parameter), the course's claim (on a field with one sharp feature the
hierarchy stores far fewer control points than the uniform least-squares fit meeting the same
tolerance), overlays only where the error was, reproduction of the base space, the result is an
editable hierarchy (ch. 5 edits, dict round trip) whose flat form equals it, height fields stay
graphs, per-level reports add up, tolerances overridable.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from occsurf.algorithms import BSplineSurface, tolerances
from occsurf.algorithms.errors import InvalidGeometryError, ParameterError
from occsurf.algorithms.fitting._common import project_points
from occsurf.algorithms.fitting.adaptive import fit_adaptive, measure_grid
from occsurf.algorithms.fitting.gridded import fit_grid
from occsurf.algorithms.hierarchical import HierarchicalSurface

from .strategies import test_settings

EXACT = 1e-12


def sharp(x, y):
    return 0.2 * np.sin(2 * x) * np.cos(1.5 * y) + 0.3 * np.exp(-((x - 0.62) ** 2 + (y - 0.41) ** 2) / (2 * 0.03 ** 2))


@pytest.fixture(scope="module")
def sharp_fit():
    x = np.linspace(0, 1, 121)
    X, Y = np.meshgrid(x, x, indexing="ij")
    Z = sharp(X, Y)
    return x, Z, fit_adaptive(Z, 1e-3)


def test_tolerance_holds_and_is_measured(sharp_fit):
    x, Z, fit = sharp_fit
    assert fit.converged and fit.max_error <= 1e-3
    flat = fit.hierarchy.flatten()
    P3 = np.stack(np.broadcast_arrays(x[:, None], x[None, :], Z), -1)
    resid = np.linalg.norm(flat.evaluate_grid(x, x) - P3, axis=-1)
    assert np.all(fit.distance <= resid + EXACT)  # projection never worse than the start
    assert float(np.nanmax(fit.distance)) == pytest.approx(fit.max_error)


@pytest.mark.slow
def test_sharp_feature_needs_far_fewer_control_points_than_uniform(sharp_fit):
    x, Z, fit = sharp_fit
    P3 = np.stack(np.broadcast_arrays(x[:, None], x[None, :], Z), -1)
    uniform = None
    for n in range(8, 121, 2):
        g = fit_grid(Z, n, 3)
        if np.nanmax(measure_grid(g.surface, P3, x, x)) <= 1e-3:
            uniform = n * n
            break
    assert uniform is not None
    assert fit.control_points_total * 2 < uniform, (fit.control_points_total, uniform)
    # overlays only where the feature is: the deepest overlays lie around (0.62, 0.41)
    deepest = [o for o in fit.hierarchy.overlays if o.level == fit.hierarchy.depth]
    for o in deepest:
        (a, b), (c, d) = o.region
        assert b - a < 0.5 and d - c < 0.5
        assert a - 0.15 <= 0.62 <= b + 0.15 and c - 0.15 <= 0.41 <= d + 0.15


def test_level_reports_add_up(sharp_fit):
    _, _, fit = sharp_fit
    counts = fit.hierarchy.pole_counts()
    assert sum(L.control_points for L in fit.levels) == counts["stored"] == fit.control_points_total
    assert [L.level for L in fit.levels] == list(range(fit.hierarchy.depth + 1))
    assert sum(L.overlays for L in fit.levels) == len(fit.hierarchy.overlays)
    assert fit.levels[-1].max_error == pytest.approx(fit.max_error)
    assert fit.levels[0].max_error > fit.levels[-1].max_error


def test_result_is_an_editable_hierarchy(sharp_fit):
    x, _, fit = sharp_fit
    hs = fit.hierarchy.copy()
    uu, vv = np.random.default_rng(0).random((2, 300))
    np.testing.assert_allclose(hs.flatten().evaluate(uu, vv), hs.evaluate(uu, vv), atol=EXACT)
    again = HierarchicalSurface.from_dict(hs.to_dict())
    np.testing.assert_allclose(again.evaluate(uu, vv), hs.evaluate(uu, vv), atol=EXACT)
    # a coarse edit: the fitted details ride along (offsets unchanged), the surface moves
    before = hs.evaluate(uu, vv)
    offs = {o.id: hs.offsets(o) for o in hs.overlays}
    hs.move_vertex(None, (3, 3), (0.0, 0.0, 0.2))
    assert np.abs(hs.evaluate(uu, vv) - before).max() > 0.01
    for o in hs.overlays:
        np.testing.assert_array_equal(hs.offsets(o), offs[o.id])
    # a fine edit at the feature: only near it
    target = hs.evaluate(0.62, 0.41) + [0, 0, 0.05]
    far = hs.evaluate(np.array([0.05, 0.95]), np.array([0.95, 0.05]))
    ov = hs.finest_overlay(0.62, 0.41)
    assert ov is not None and ov.level >= 2
    hs.drag_point(0.62, 0.41, target, overlay="finest")
    np.testing.assert_allclose(hs.evaluate(0.62, 0.41), target, atol=1e-10)
    np.testing.assert_allclose(hs.evaluate(np.array([0.05, 0.95]), np.array([0.95, 0.05])), far, atol=EXACT)


def test_height_field_stays_a_graph(sharp_fit):
    _, _, fit = sharp_fit
    uu, vv = np.random.default_rng(1).random((2, 500))
    P = fit.hierarchy.evaluate(uu, vv)
    np.testing.assert_allclose(P[:, 0], uu, atol=EXACT)
    np.testing.assert_allclose(P[:, 1], vv, atol=EXACT)


def test_data_of_the_base_space_need_no_overlay():
    u = np.linspace(0, 1, 30)
    probe = fit_grid(np.zeros((30, 30)), 8, 3)
    s = BSplineSurface((3, 3), probe.surface.knots, np.random.default_rng(4).standard_normal((8, 8, 3)))
    fit = fit_adaptive(s.evaluate_grid(u, u), 1e-9, u_params=u, v_params=u)
    assert len(fit.hierarchy.overlays) == 0 and fit.max_error < 1e-11


def test_point_grids_and_level_limit():
    u = np.linspace(0, 1, 81)
    U, W = np.meshgrid(u, u, indexing="ij")
    Q = np.stack([np.cos(2 * U), np.sin(2 * U), W + 0.2 * np.exp(-((U - 0.5) ** 2 + (W - 0.5) ** 2) / 0.002)], -1)
    fit = fit_adaptive(Q, 2e-3, method="uniform")
    assert fit.converged and fit.max_error <= 2e-3
    with tolerances.override(FIT_ADAPTIVE_MAX_LEVELS=1):
        one = fit_adaptive(Q, 1e-6, method="uniform")
    assert one.hierarchy.depth <= 1 and not one.converged


def test_project_points_closed_form_on_a_cylinder():
    from occsurf.algorithms import circle, extrude

    cyl = extrude(circle([0, 0, 0], 2.0), [0, 0, 3.0])
    rng = np.random.default_rng(7)
    (u0, u1), (v0, v1) = cyl.domain
    uu, vv = u0 + (u1 - u0) * rng.random(400), v0 + (v1 - v0) * rng.random(400)
    on = cyl.evaluate(uu, vv)
    r = 0.3 * rng.random(400) - 0.15
    X = on * np.c_[(2 + r) / 2, (2 + r) / 2, np.ones(400)]  # radius 2 + r, same height
    start_u = np.clip(uu + 0.02, u0, u1)
    _, _, d = project_points(cyl, X, start_u, vv)
    np.testing.assert_allclose(d, np.abs(r), atol=1e-10)


def test_bad_input():
    Z = np.zeros((20, 20))
    with pytest.raises(ParameterError, match="tol"):
        fit_adaptive(Z, 0.0)
    with pytest.raises(ParameterError, match="tol"):
        fit_adaptive(Z, "x")
    with pytest.raises(InvalidGeometryError, match="3-D"):
        fit_adaptive(np.zeros((20, 20, 2)), 1e-3)
    with pytest.raises(ParameterError, match="max_levels"):
        fit_adaptive(Z, 1e-3, max_levels=-1)


def test_adaptive_tolerances_are_read_at_call_time():
    x = np.linspace(0, 1, 41)
    Z = sharp(*np.meshgrid(x, x, indexing="ij"))
    with tolerances.override(FIT_ADAPTIVE_MAX_COVER=1.0, FIT_ADAPTIVE_MAX_LEVELS=0):
        fixed = fit_adaptive(Z, 1e-6)  # the base never grows, no overlay: the default 8 x 8 base
    assert fixed.hierarchy.base.n_poles == (8, 8) and not fixed.hierarchy.overlays
    with tolerances.override(FIT_ADAPTIVE_MAX_COVER=0.0, FIT_ADAPTIVE_MAX_LEVELS=0):
        grown = fit_adaptive(Z, 1e-6)  # any place to refine grows the base
    assert np.prod(grown.hierarchy.base.n_poles) > 64
    s = fixed.hierarchy.flatten()
    P3 = np.stack(np.broadcast_arrays(x[:, None], x[None, :], Z), -1)
    with tolerances.override(FIT_PROJECTION_MAX_ITER=0):  # no Newton step: the residual at the parameters
        d0 = measure_grid(s, P3, x, x)
    np.testing.assert_allclose(d0, np.linalg.norm(s.evaluate_grid(x, x) - P3, axis=-1), atol=EXACT)
    assert np.all(measure_grid(s, P3, x, x) <= d0 + EXACT)


def test_franke_on_a_coarse_grid_reaches_the_tolerance():
    from occsurf.examples.fitting import franke

    x = np.linspace(0, 1, 33)
    fit = fit_adaptive(franke(*np.meshgrid(x, x, indexing="ij")), 1e-3)
    assert fit.converged and fit.max_error <= 1e-3


def test_measure_grid_by_blocks_and_partially_is_exact_where_it_counts():
    from occsurf.algorithms.fitting.adaptive import normal_deviation

    x = np.linspace(0, 1, 90)
    Z = sharp(*np.meshgrid(x, x, indexing="ij"))
    s = fit_grid(Z, 12, 3).surface
    P3 = np.stack(np.broadcast_arrays(x[:, None], x[None, :], Z), -1)
    full = measure_grid(s, P3, x, x)
    with tolerances.override(FIT_MEASURE_BLOCK=100):  # one row per block: the same distances
        np.testing.assert_allclose(measure_grid(s, P3, x, x), full, rtol=0, atol=EXACT)
    U, W = np.meshgrid(x, x, indexing="ij")
    start = project_points(s, P3.reshape(-1, 3), U.ravel(), W.ravel())[2].reshape(full.shape)
    np.testing.assert_allclose(full, start, rtol=0, atol=EXACT)  # grid partials as the start: same result
    tol = 1e-3
    part = measure_grid(s, P3, x, x, above=tol)
    resid = np.linalg.norm(s.evaluate_grid(x, x) - P3, axis=-1)
    skipped = resid <= tol
    assert skipped.any() and (~skipped).any()
    np.testing.assert_array_equal(part[skipped], resid[skipped])
    np.testing.assert_array_equal(part[~skipped], full[~skipped])
    for t in (tol, 3 * tol, 0.1):  # every decision against a threshold >= above is the same
        np.testing.assert_array_equal(part > t, full > t)
    # the first-order (normal) deviation: exact on a plane, close to the distance where it is small
    flat = fit_grid(np.zeros((20, 20)), 4, 3).surface
    h = np.random.default_rng(3).standard_normal((20, 20)) * 1e-2
    g = np.linspace(0, 1, 20)
    Pf = np.stack(np.broadcast_arrays(g[:, None] + 0 * h, g[None, :] + 0 * h, h), -1)
    np.testing.assert_allclose(normal_deviation(flat, Pf, g, g), np.abs(h), atol=EXACT)
    nd = normal_deviation(s, P3, x, x)[1:-1, 1:-1]  # inside (a border point's foot may be clamped)
    small = full[1:-1, 1:-1] < 1e-4
    np.testing.assert_allclose(nd[small], full[1:-1, 1:-1][small], rtol=0.1, atol=1e-7)


# ------------------------------------------- measure_heights: projecting only what decides


def _height_case(seed: int, m: int, poles: int, holes: bool):
    """A coarse least-squares fit of rough heights (steep, wavy, noisy) and its grid points."""
    rng = np.random.default_rng(seed)
    x = np.sort(np.r_[0.0, rng.uniform(0, 1, m - 2), 1.0])
    X, Y = np.meshgrid(x, x, indexing="ij")
    a, b, c = rng.uniform(1, 8, 3)
    Z = 0.3 * np.sin(a * X) * np.cos(b * Y) + 0.5 * np.exp(-((X - 0.6) ** 2 + (Y - 0.4) ** 2) / (0.002 * c))
    Z = Z + 1e-3 * rng.standard_normal(Z.shape)
    if holes:
        Z[rng.integers(1, m - 1, 5), rng.integers(1, m - 1, 5)] = np.nan
    fit = fit_grid(Z, poles, 3, x=x, y=x)
    P3 = np.stack(np.broadcast_arrays(x[:, None], x[None, :], Z), -1)
    return fit.surface, P3, x


@test_settings(25)
@given(seed=st.integers(0, 10**6), poles=st.integers(5, 14), holes=st.booleans())
def test_graph_bounds_bound_the_slope_the_offset_and_the_distance(seed, poles, holes):
    from occsurf.algorithms.fitting.adaptive import graph_bounds

    s, P3, x = _height_case(seed, 41, poles, holes)
    L, eps = graph_bounds(s)
    g = np.linspace(0, 1, 301)
    D = s.derivatives_grid(g, g, 1)
    slope = np.hypot(D[:, :, 1, 0, 2], D[:, :, 0, 1, 2])
    assert slope.max() <= L * (1 + 1e-12)
    # x(u, v) - u is eps at most in exact arithmetic; evaluated, each of the (p + 1)(q + 1) terms of
    # the tensor sum (non-negative basis products summing to 1, times coordinates within [0, 1])
    # carries the round-off of its basis values (a p- and a q-step recurrence) and of the sum: at
    # most (p + 1)(q + 1) + 2 (p + q) ulps of 1. (The former 1e-15, 4.5 ulps, was below that: seed
    # 9835 with 6 poles evaluates y - v to 1.1e-15, 5 ulps, in the code of 2026-12-06 as of today.)
    (p, q) = s.degree
    fp = ((p + 1) * (q + 1) + 2 * (p + q)) * np.finfo(float).eps
    assert np.abs(D[:, :, 0, 0, 0] - g[:, None]).max() <= eps + fp
    assert np.abs(D[:, :, 0, 0, 1] - g[None, :]).max() <= eps + fp
    assert eps <= 1e-14  # a height fit: x = u, y = v up to round-off
    # the lower bound of measure_heights never exceeds the (projected) distance
    ok = np.isfinite(P3[..., 2])
    d = measure_grid(s, P3, x, x)
    rz = np.abs(P3[..., 2] - s.evaluate_grid(x, x)[..., 2])
    lo = np.maximum(rz - L * eps, 0.0) / np.hypot(1.0, L)
    assert np.all(lo[ok] <= d[ok] * (1 + 1e-12))


@test_settings(25)
@given(seed=st.integers(0, 10**6), poles=st.integers(5, 12), holes=st.booleans(),
       tol=st.sampled_from([3e-4, 1e-3, 1e-2]), greed=st.sampled_from([0.0, 0.1, 0.5]), overlays=st.booleans())
def test_measure_heights_decides_as_if_every_point_were_projected(seed, poles, holes, tol, greed, overlays):
    """The maximum of ``boundary_error`` and the knot-span cells holding a flagged point (what the
    refinement uses) are those of every point projected; without cells, every point's flag."""
    from occsurf.algorithms.fitting.adaptive import boundary_error, cell_labels, measure_heights

    s, P3, x = _height_case(seed, 61, poles, holes)
    hs = HierarchicalSurface(s, "frame")
    if overlays:  # owners at two levels: the cells are the owner's level's spans
        (u0, u1), _ = hs.domain
        ov = hs.add_overlay((0.3, 0.8), (0.2, 0.7))
        hs.add_overlay((0.45, 0.65), (0.3, 0.5), ov)
    cells = cell_labels(hs, x, x)
    full = boundary_error(s, P3, x, x, measure_grid(s, P3, x, x, above=tol))
    worst = float(np.nanmax(full))
    thr = max(tol, greed * worst)
    for with_cells in (False, True):
        fast = boundary_error(s, P3, x, x, measure_heights(s, P3, x, x, tol, greed, cells=cells if with_cells else None))
        assert float(np.nanmax(fast)) == worst
        ok = np.isfinite(full)
        assert np.array_equal(np.isfinite(fast), ok)
        if with_cells:
            lab = cells[ok]
            assert set(lab[(full > thr)[ok]]) == set(lab[(fast > thr)[ok]])
        else:
            np.testing.assert_array_equal(fast > thr, full > thr)


@test_settings(10)
@given(seed=st.integers(0, 10**6), poles=st.integers(5, 14))
def test_normal_deviation_is_the_cross_product_formula_bit_for_bit(seed, poles):
    from occsurf.algorithms.fitting.adaptive import normal_deviation

    s, P3, x = _height_case(seed, 41, poles, holes=False)
    D = s.derivatives_grid(x, x, 1)
    N = np.cross(D[:, :, 1, 0], D[:, :, 0, 1])
    N /= np.maximum(np.linalg.norm(N, axis=-1, keepdims=True), 1e-300)
    want = np.abs(np.einsum("ijk,ijk->ij", P3 - D[:, :, 0, 0], N))
    np.testing.assert_array_equal(normal_deviation(s, P3, x, x), want)
