"""The fast evaluation paths agree with the pure-NumPy reference paths.

Two kinds of fast path are checked:

- the banded grid products (:func:`occsurf.algorithms.kernel.basis.band_product`, NumPy) against the dense
  collocation matrices of :func:`occsurf.algorithms.kernel.basis.basis_matrix` and against scattered evaluation;
- the optional numba kernels (:mod:`occsurf.algorithms._numba_kernels`) against the NumPy paths, to 1e-14
  relative to each partial's magnitude, on clamped, unclamped and rational curves and surfaces of
  degrees 1 to 7, at random parameters, at every knot, at the domain ends, up to order 3.

Paths are forced with the documented switches: ``OCCSURF_NO_NUMBA=1`` for NumPy, and
``tolerances.override(NUMBA_MIN_POINTS=0)`` so that the kernels run on small inputs. Without numba
the kernel comparisons skip and the rest still runs.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from numpy.testing import assert_allclose

from occsurf.algorithms import BSplineCurve, BSplineSurface, tolerances
from occsurf.algorithms import _numba_kernels as nk
from occsurf.algorithms.kernel.basis import band_product, basis_derivatives, basis_matrix, find_span, span_groups

from .strategies import surfaces, test_settings

RTOL = 1e-14  # both paths: a few ulps of each partial's magnitude
DEGREES = range(1, 8)
KINDS = ("clamped", "unclamped", "rational")

try:
    import numba  # noqa: F401

    HAVE_NUMBA = True
except ImportError:
    HAVE_NUMBA = False

needs_numba = pytest.mark.skipif(not HAVE_NUMBA, reason="numba is not installed (optional)")


# ----------------------------------------------------------------------------------- helpers


def knot_vector(rng: np.random.Generator, degree: int, n: int, clamped: bool) -> np.ndarray:
    """Full knot vector with a double interior knot (a triple one for degree >= 3)."""
    m = n - degree - 1  # interior knots of a clamped vector
    interior = np.sort(rng.uniform(0.05, 0.95, m))
    if m >= 3:
        interior[1] = interior[0]  # repeated knot
        if degree >= 3 and m >= 4:
            interior[2] = interior[0]
    if clamped:
        return np.r_[np.zeros(degree + 1), interior, np.ones(degree + 1)]
    lo = -np.sort(rng.uniform(0.05, 0.5, degree))[::-1] * 0.5
    hi = 1 + np.sort(rng.uniform(0.05, 0.5, degree)) * 0.5
    return np.r_[lo, 0.0, interior, 1.0, hi]


def make_curve(degree: int, kind: str, seed: int) -> BSplineCurve:
    rng = np.random.default_rng(seed)
    n = degree + 6
    t = knot_vector(rng, degree, n, clamped=kind != "unclamped")
    w = rng.uniform(0.3, 3.0, n) if kind == "rational" else None
    return BSplineCurve(degree, t, rng.uniform(-5, 5, (n, 3)), w)


def make_surface(degree: int, kind: str, seed: int) -> BSplineSurface:
    rng = np.random.default_rng(seed)
    p, q = degree, 8 - degree  # (1, 7), (2, 6), ..., (7, 1)
    nu, nv = p + 5, q + 4
    U = knot_vector(rng, p, nu, clamped=kind != "unclamped")
    V = knot_vector(rng, q, nv, clamped=kind != "unclamped")
    w = rng.uniform(0.3, 3.0, (nu, nv)) if kind == "rational" else None
    return BSplineSurface((p, q), (U, V), rng.uniform(-5, 5, (nu, nv, 3)), w)


def params_with_knots(t: np.ndarray, lo: float, hi: float, rng: np.random.Generator, n: int = 40) -> np.ndarray:
    """Random parameters, every knot of the domain, and both domain ends, exactly."""
    inside = t[(t >= lo) & (t <= hi)]
    return np.r_[rng.uniform(lo, hi, n), inside, lo, hi]


def assert_partials_close(actual: np.ndarray, desired: np.ndarray, partial_axes: int, floor=0.0) -> None:
    """Each partial (the last ``partial_axes`` axes before the coordinates) to ``RTOL`` of its
    largest magnitude: derivatives of different orders differ by orders of magnitude.

    ``floor`` (broadcastable to one point's partials, without the coordinate axis) bounds the
    scale from below, for partials that vanish up to round-off (a constant surface, say).
    """
    assert actual.shape == desired.shape
    lead = desired.ndim - 1 - partial_axes
    flat_a = actual.reshape((-1,) + desired.shape[lead:])
    flat_d = desired.reshape((-1,) + desired.shape[lead:])
    scale = np.maximum(np.max(np.abs(flat_d), axis=(0, -1), keepdims=True), np.asarray(floor)[..., None])
    err = np.abs(flat_a - flat_d) / np.where(scale > 0, scale, 1.0)
    assert np.all(np.isfinite(actual))
    assert err.max() <= RTOL, f"max relative deviation {err.max():.2e}"


@pytest.fixture
def numpy_only(monkeypatch):
    monkeypatch.setenv(nk.ENV_DISABLE, "1")


@pytest.fixture
def with_numba(monkeypatch):
    monkeypatch.delenv(nk.ENV_DISABLE, raising=False)
    with tolerances.override(NUMBA_MIN_POINTS=0):
        assert nk.applies(1)
        yield


def both_paths(monkeypatch, fn):
    """``fn()`` on the NumPy path, then on the numba kernels."""
    monkeypatch.setenv(nk.ENV_DISABLE, "1")
    ref = fn()
    monkeypatch.delenv(nk.ENV_DISABLE)
    with tolerances.override(NUMBA_MIN_POINTS=0):
        assert nk.applies(1)
        return ref, fn()


# ------------------------------------------------------------- numba kernels vs NumPy paths


@pytest.mark.slow
@needs_numba
@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("degree", DEGREES)
def test_curve_kernels_match_numpy(monkeypatch, degree, kind):
    c = make_curve(degree, kind, seed=100 * degree + len(kind))
    u = params_with_knots(c.knots, *c.domain, np.random.default_rng(degree))
    ref, fast = both_paths(monkeypatch, lambda: (c.evaluate(u), c.derivatives(u, 3)))
    assert_partials_close(fast[0], ref[0], 0)
    assert_partials_close(fast[1], ref[1], 1)


@pytest.mark.slow
@needs_numba
@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("degree", DEGREES)
def test_surface_kernels_match_numpy(monkeypatch, degree, kind):
    s = make_surface(degree, kind, seed=100 * degree + len(kind))
    rng = np.random.default_rng(degree)
    (u0, u1), (v0, v1) = s.domain
    us = params_with_knots(s.knots[0], u0, u1, rng, 12)
    vs = params_with_knots(s.knots[1], v0, v1, rng, 10)
    uu, vv = (a.ravel() for a in np.meshgrid(us, vs, indexing="ij"))  # every knot pair, ends too

    def run():
        return s.evaluate(uu, vv), s.derivatives(uu, vv, 3), s.evaluate_grid(us, vs), s.derivatives_grid(us, vs, 3)

    ref, fast = both_paths(monkeypatch, run)
    assert_partials_close(fast[0], ref[0], 0)
    assert_partials_close(fast[1], ref[1], 2)
    assert_partials_close(fast[2], ref[2], 0)
    assert_partials_close(fast[3], ref[3], 2)
    # The grid (banded products) and the scattered kernel agree too.
    assert_partials_close(fast[3].reshape(fast[1].shape), fast[1], 2)


@needs_numba
@pytest.mark.parametrize("order", [0, 1, 2])
def test_surface_kernels_orders_and_shapes(monkeypatch, order):
    s = make_surface(3, "rational", seed=7)
    rng = np.random.default_rng(1)
    u = rng.uniform(0, 1, (4, 5))
    v = rng.uniform(0, 1, (1, 5))  # broadcasts
    ref, fast = both_paths(monkeypatch, lambda: s.derivatives(u, v, order))
    assert fast.shape == (4, 5, order + 1, order + 1, 3)
    assert_partials_close(fast, ref, 2)


@pytest.mark.slow
@needs_numba
def test_two_dimensional_and_high_dimensional_poles(monkeypatch):
    # Dimensions 2 and 5 (k = 2, 3, 5, 6) take the generic, not the 3/4-coordinate, contraction.
    rng = np.random.default_rng(5)
    U = np.r_[0, 0, 0, 0.3, 0.6, 0.8, 1, 1, 1]
    V = np.r_[0, 0, 0, 0, 0.4, 0.5, 1, 1, 1, 1]
    for dim in (2, 5):
        for w in (None, rng.uniform(0.5, 2, (6, 6))):
            s = BSplineSurface((2, 3), (U, V), rng.uniform(-1, 1, (6, 6, dim)), w)
            u, v = rng.uniform(0, 1, 50), rng.uniform(0, 1, 50)
            g = np.r_[0.0, 0.3, 0.35, 1.0]
            ref, fast = both_paths(monkeypatch, lambda s=s, u=u, v=v, g=g: (s.evaluate(u, v), s.derivatives(u, v, 2),
                                                                        s.derivatives_grid(g, g, 2)))
            for a, b, axes in zip(fast, ref, (0, 2, 2)):
                assert_partials_close(a, b, axes)


@needs_numba
def test_environment_variable_forces_numpy(monkeypatch):
    with tolerances.override(NUMBA_MIN_POINTS=0):
        monkeypatch.setenv(nk.ENV_DISABLE, "1")
        assert not nk.applies(10**6)
        monkeypatch.setenv(nk.ENV_DISABLE, "0")
        assert nk.applies(10**6)
    with tolerances.override(NUMBA_MIN_POINTS=100):
        assert not nk.applies(99)
        assert nk.applies(100)


@needs_numba
def test_numba_min_points_override_routes_small_inputs_through_the_kernels(monkeypatch):
    """tolerances.NUMBA_MIN_POINTS is read at call time: an override sends a 7-point evaluation
    through the kernels (and leaves the default, 2**15, untouched outside the block)."""
    monkeypatch.delenv(nk.ENV_DISABLE, raising=False)
    c = make_curve(3, "rational", seed=11)
    s = make_surface(2, "clamped", seed=12)
    u = np.linspace(*c.domain, 7)
    calls: list[str] = []
    real_run = nk.run

    def spy(name, *args):
        calls.append(name)
        return real_run(name, *args)

    monkeypatch.setattr(nk, "run", spy)
    ref = c.evaluate(u), s.evaluate(u, u)
    assert calls == [] and tolerances.NUMBA_MIN_POINTS == tolerances.defaults()["NUMBA_MIN_POINTS"]
    with tolerances.override(NUMBA_MIN_POINTS=7):
        fast = c.evaluate(u), s.evaluate(u, u)
        assert tolerances.NUMBA_MIN_POINTS == 7
    assert calls == ["curve_points", "surface_points"]
    assert_partials_close(fast[0], ref[0], 0)
    assert_partials_close(fast[1], ref[1], 0)
    with tolerances.override(NUMBA_MIN_POINTS=8):
        c.evaluate(u)
    assert calls == ["curve_points", "surface_points"]  # 7 < 8: NumPy path


@needs_numba
def test_failing_kernel_falls_back_to_numpy_with_a_warning(monkeypatch, with_numba):
    s = make_surface(3, "clamped", seed=3)
    u = np.linspace(0, 1, 30)
    monkeypatch.setenv(nk.ENV_DISABLE, "1")
    ref = s.evaluate(u, u)
    monkeypatch.delenv(nk.ENV_DISABLE)

    def broken(*args):
        raise TypeError("simulated typing error")

    kernels = dict(nk._state["kernels"])
    kernels["surface_points"] = broken
    monkeypatch.setitem(nk._state, "kernels", kernels)
    with pytest.warns(RuntimeWarning, match="surface_points"):
        out = s.evaluate(u, u)
    assert_allclose(out, ref, rtol=0, atol=0)
    assert "surface_points" not in kernels  # dropped for the rest of the process


@needs_numba
def test_uncachable_kernel_source_still_compiles():
    # numba raises RuntimeError at decoration when no cache directory is usable (here: a
    # function without a source file); jit must then compile without the cache.
    import numba

    ns: dict = {}
    exec("def twice(x):\n    return 2 * x\n", ns)  # noqa: S102 - no file, so no cache locator
    f = nk.jit(numba, ns["twice"])
    assert f(21) == 42


@needs_numba
def test_span_tables_are_made_once_per_spline_and_not_pickled(monkeypatch):
    """A curve's and a surface's span tables (the kernels' arguments) are made on the first kernel
    call and kept: later calls give the same values bit for bit without making them again; a pickle
    leaves them out and its copy makes its own."""
    import pickle

    monkeypatch.delenv(nk.ENV_DISABLE, raising=False)
    c = make_curve(3, "rational", seed=21)
    s = make_surface(3, "clamped", seed=22)
    u = np.linspace(*c.domain, 9)
    made: list[int] = []
    real = nk.span_table
    monkeypatch.setattr(nk, "span_table", lambda *a: made.append(1) or real(*a))
    with tolerances.override(NUMBA_MIN_POINTS=1):
        first = c.derivatives(u, 2), s.derivatives(u, u, 2)
        assert len(made) == 1 + 2  # the curve's, the surface's two
        again = c.derivatives(u, 2), c.evaluate(u), s.derivatives(u, u, 2), s.evaluate(u, u)
        assert len(made) == 3
        assert np.array_equal(again[0], first[0]) and np.array_equal(again[2], first[1])
        c2, s2 = pickle.loads(pickle.dumps(c)), pickle.loads(pickle.dumps(s))
        assert "_derived" in c.__dict__ and "_derived" in s.__dict__
        assert "_derived" not in c2.__dict__ and "_derived" not in s2.__dict__
        assert np.array_equal(c2.derivatives(u, 2), first[0]) and np.array_equal(s2.derivatives(u, u, 2), first[1])
        assert len(made) == 6


def test_span_table_matches_find_span():
    rng = np.random.default_rng(11)
    for degree in DEGREES:
        for clamped in (True, False):
            t = knot_vector(rng, degree, degree + 8, clamped)
            n = t.shape[0] - degree - 1
            first, last, table, x0, scale = nk.span_table(t, degree, n)
            edges = np.clip(x0 + np.arange(table.shape[0]) / scale, t[degree], t[n])
            assert np.array_equal(table, find_span(t, degree, n, edges))
            assert (first, last) == (int(find_span(t, degree, n, t[degree : degree + 1])[0]),
                                     int(find_span(t, degree, n, t[n : n + 1])[0]))


# ------------------------------------------------------------- banded grid products (NumPy)


@pytest.mark.parametrize("order", [0, 1, 3])
def test_band_product_equals_dense_collocation_product(order):
    rng = np.random.default_rng(order)
    p, n = 4, 13
    t = knot_vector(rng, p, n, clamped=False)
    x = np.r_[rng.uniform(t[p], t[n], 60), t[p : n + 1]]
    for u in (np.sort(x), x):  # runs of equal spans, and grouping of unsorted parameters
        span = find_span(t, p, n, u)
        D = basis_derivatives(t, p, span, u, order)
        M = rng.standard_normal((n, 7))
        R = band_product(D, span, p, M)
        B = basis_matrix(t, p, n, u, order)
        for i in range(order + 1):
            assert_allclose(R[:, i], B[i] @ M, rtol=0, atol=1e-12 * np.abs(B[i]).sum(1).max() * np.abs(M).max())


def test_span_groups_cover_every_parameter_once():
    rng = np.random.default_rng(2)
    for span in (np.repeat([3, 4, 4, 7], 5), rng.integers(3, 9, 200), np.array([5]), np.array([], np.intp)):
        groups = span_groups(span)
        seen = np.concatenate([np.arange(span.shape[0])[sel] for sel, _ in groups]) if groups else np.array([], int)
        assert np.array_equal(np.sort(seen), np.arange(span.shape[0]))
        for sel, s in groups:
            assert np.all(span[sel] == s)


@pytest.mark.parametrize("kind", KINDS)
def test_grid_numpy_path_matches_scattered_for_unsorted_parameters(numpy_only, kind):
    s = make_surface(3, kind, seed=21)
    rng = np.random.default_rng(4)
    (u0, u1), (v0, v1) = s.domain
    us = rng.permutation(params_with_knots(s.knots[0], u0, u1, rng, 30))
    vs = rng.permutation(params_with_knots(s.knots[1], v0, v1, rng, 20))
    grid = s.derivatives_grid(us, vs, 2)
    scattered = s.derivatives(us[:, None], vs[None, :], 2)
    assert_partials_close(grid, scattered, 2)
    assert_partials_close(s.evaluate_grid(us, vs), s.evaluate(us[:, None], vs[None, :]), 0)
    assert grid.flags.c_contiguous and s.evaluate_grid(us, vs).flags.c_contiguous


def test_grid_order_zero_and_empty_grids(numpy_only):
    s = make_surface(2, "rational", seed=8)
    g = np.linspace(0, 1, 9)
    assert_allclose(s.derivatives_grid(g, g, 0)[:, :, 0, 0], s.evaluate_grid(g, g), rtol=0, atol=0)
    assert s.evaluate_grid([], g).shape == (0, 9, 3)
    assert s.derivatives_grid(g, [], 2).shape == (9, 0, 3, 3, 3)


@given(surfaces(degrees=st.integers(1, 7), max_extra_poles=3))
@test_settings(25)
def test_grid_equals_scattered_on_random_surfaces(s):
    (u0, u1), (v0, v1) = s.domain
    us = np.r_[np.linspace(u0, u1, 7), s.knots[0][(s.knots[0] >= u0) & (s.knots[0] <= u1)]]
    vs = np.r_[np.linspace(v0, v1, 5), s.knots[1][(s.knots[1] >= v0) & (s.knots[1] <= v1)]]
    # Round-off scale of partial (i, j): |P| (2p / h_u)^i (2q / h_v)^j, times the weight ratio
    # to the power i + j + 1 and (i + j)! for the quotient rule; h = the shortest non-empty span.
    scale = np.max(np.abs(s.control_points))
    fac = []
    for ax in (0, 1):
        t, p = s.knots[ax], s.degree[ax]
        h = np.diff(np.unique(t[p : s.n_poles[ax] + 1])).min()
        fac.append((2 * p / h) ** np.arange(3))
    ij = np.add.outer(np.arange(3), np.arange(3))
    rho = 1.0 if s.weights is None else s.weights.max() / s.weights.min()
    floor = scale * np.outer(*fac) * rho ** (ij + 1) * np.array([1, 1, 2, 6, 24])[ij]
    assert_partials_close(s.derivatives_grid(us, vs, 2), s.derivatives(us[:, None], vs[None, :], 2), 2, floor)


# ----------------------------------------------------------- the fused projection kernel


@needs_numba
@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("degree", [1, 2, 3, 5])
def test_projection_kernel_matches_the_vectorised_newton(monkeypatch, degree, kind):
    """``surface_project`` runs project_points' damped Newton per point: the same foot points.

    Points near the surface (a fit's case) and far from it (steps halved, feet on the boundary),
    starts off the foot by up to a tenth of the domain. The two paths differ by round-off in each
    step, so one may take one more step below the stopping threshold (1e-12 of the domain): near
    points' distances agree to 1e-12 of the surface's size, their parameters to 1e-7 of the domain
    (a foot point is flat to first order along the surface, so its parameters are far less
    settled). A far point whose foot slides along a boundary converges linearly there and stops
    when a step no longer lowers ``f`` in the last bits: the two paths stop at different places of
    that slide, measured up to 4e-10 of the distance (2.2) for one point of the 1200; 1e-8 of
    the distance is allowed.
    """
    from occsurf.algorithms.fitting._common import project_points

    s = make_surface(degree, kind, seed=31 * degree + len(kind))
    rng = np.random.default_rng(degree)
    (u0, u1), (v0, v1) = s.domain
    k = 600
    u, v = rng.uniform(u0, u1, k), rng.uniform(v0, v1, k)
    D = s.derivatives(u, v, 1)
    n = np.cross(D[:, 1, 0], D[:, 0, 1])
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    off = np.r_[rng.normal(0, 1e-3, k // 2), rng.normal(0, 2.0, k - k // 2)]
    X = D[:, 0, 0] + off[:, None] * n
    su = np.clip(u + rng.normal(0, 0.1 * (u1 - u0), k), u0, u1)
    sv = np.clip(v + rng.normal(0, 0.1 * (v1 - v0), k), v0, v1)
    calls: list[str] = []
    real_run = nk.run
    monkeypatch.setattr(nk, "run", lambda name, *a: calls.append(name) or real_run(name, *a))
    ref, fast = both_paths(monkeypatch, lambda: project_points(s, X, su, sv))
    assert "surface_project" in calls
    size = float(np.ptp(s.control_points.reshape(-1, 3), axis=0).max())
    near = slice(0, k // 2)
    assert np.abs(fast[2] - ref[2])[near].max() <= 1e-12 * size
    assert np.abs(fast[0] - ref[0])[near].max() <= 1e-7 * (u1 - u0)
    assert np.abs(fast[1] - ref[1])[near].max() <= 1e-7 * (v1 - v0)
    assert np.all(np.abs(fast[2] - ref[2]) <= 1e-8 * ref[2] + 1e-12 * size)
    assert np.all(fast[2] <= np.linalg.norm(s.evaluate(su, sv) - X, axis=-1) + 1e-15 * size)  # never worse than the start


@needs_numba
def test_batch_keeps_the_kernels_for_small_evaluations_and_depends_on_the_work_only(monkeypatch):
    """Inside ``batch(n)`` with n >= NUMBA_MIN_POINTS every size takes the kernels; below, the
    size rule applies whatever ran before (a call's results never depend on history)."""
    monkeypatch.delenv(nk.ENV_DISABLE, raising=False)
    nk.load()
    assert not nk.applies(100)
    with nk.batch(tolerances.NUMBA_MIN_POINTS):
        assert nk.applies(1) and nk.applies(100)
        with nk.batch(10):  # an inner, small block keeps the outer choice
            assert nk.applies(100)
    assert not nk.applies(100)
    with nk.batch(tolerances.NUMBA_MIN_POINTS - 1):
        assert not nk.applies(100)
    monkeypatch.setenv(nk.ENV_DISABLE, "1")
    with nk.batch(10**9):
        assert not nk.applies(10**9)
