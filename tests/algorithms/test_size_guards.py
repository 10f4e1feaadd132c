"""Issue 34, item 8: requests whose size the user sets are refused before the large array exists.

Each case runs under a lowered ``MAX_ARRAY_BYTES`` (1 MB), so the refusal is fast and allocates
little; each failed on the code before (a MemoryError, minutes of work, or an array far beyond the
limit). The error is the one :func:`check_size` raises (an ``InvalidGeometryError``), its message
names the argument and the size.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator

import numpy as np
import pytest

from occsurf.algorithms import BSplineCurve, BSplineSurface, tolerances
from occsurf.algorithms.errors import InvalidGeometryError
from occsurf.algorithms.hierarchical.curve import HierarchicalCurve
from occsurf.algorithms.hierarchical.surface import HierarchicalSurface
from occsurf.algorithms.kernel.trimmed import TrimmedSurface

LIMIT = 10**6  # bytes


@pytest.fixture(autouse=True)
def _small_limit() -> Iterator[None]:
    with tolerances.override(MAX_ARRAY_BYTES=LIMIT):
        yield


def refused(call: Callable[[], object], match: str, seconds: float = 1.0) -> str:
    """``call`` raises check_size's error matching ``match``, within ``seconds``; its message."""
    t0 = time.perf_counter()
    with pytest.raises(InvalidGeometryError, match=match) as info:
        call()
    assert time.perf_counter() - t0 < seconds
    assert "MAX_ARRAY_BYTES" in str(info.value)
    return str(info.value)


def _surface() -> BSplineSurface:
    t = [0.0] * 4 + [0.5] + [1.0] * 4
    return BSplineSurface((3, 3), (t, t), np.random.default_rng(0).random((5, 5, 3)))


def _curve() -> BSplineCurve:
    return BSplineCurve(3, [0, 0, 0, 0, 0.5, 1, 1, 1, 1], np.c_[np.linspace(0, 4, 5), np.sin(np.arange(5)), np.zeros(5)])


def _square() -> tuple[BSplineCurve, ...]:
    pts = [(0, 0), (1, 0), (1, 1), (0, 1)]
    return tuple(BSplineCurve(1, [0, 0, 1, 1], [pts[i], pts[(i + 1) % 4]]) for i in range(4))


def _trimmed() -> TrimmedSurface:
    return TrimmedSurface(_surface(), _square())


# ------------------------------------------------------------------ broadcast u, v
def test_broadcast_u_v_is_refused_before_the_points_exist() -> None:
    """``u`` of shape (n, 1) and ``v`` of shape (1, n) ask for n^2 points: evaluate allocated them
    (and derivatives flattened them before its own check)."""
    u = np.linspace(0, 1, 2000)[:, None]
    v = np.linspace(0, 1, 2000)[None, :]
    s, hs, ts = _surface(), HierarchicalSurface(_surface()), _trimmed()
    for call in (lambda: s.evaluate(u, v), lambda: s.derivatives(u, v, 1), lambda: s.normal(u, v),
                 lambda: hs.evaluate(u, v), lambda: hs.derivatives(u, v, 1),
                 lambda: ts.evaluate(u, v), lambda: ts.classify(u, v), lambda: ts.contains(u, v),
                 lambda: ts.normal(u, v)):
        refused(call, r"u, v broadcast to shape \(2000, 2000\)")
    refused(lambda: ts.derivatives(u[:200], v[:, :200], 4), r"u, v broadcast to shape \(200, 200\) for derivatives "
            "of order 4")
    # within the limit: the same values as before
    small_u, small_v = u[:20], v[:, :20]
    assert s.evaluate(small_u, small_v).shape == (20, 20, 3)
    np.testing.assert_allclose(hs.evaluate(small_u, small_v), s.evaluate(small_u, small_v), atol=1e-14)
    np.testing.assert_allclose(ts.evaluate(small_u * 0.5 + 0.25, small_v * 0.5 + 0.25),
                               s.evaluate(small_u * 0.5 + 0.25, small_v * 0.5 + 0.25), atol=1e-14)


# ------------------------------------------------------------------ add_overlay(knots=)
def test_add_overlay_knots_are_refused_before_the_dense_refinement() -> None:
    """``add_overlay(knots=...)`` built the dense (new poles x old poles) Oslo matrix and the refined
    net with no check: 1e5 knots took ~1e10 floats."""
    many = np.linspace(0.01, 0.99, 100_000)
    hs = HierarchicalSurface(_surface())
    refused(lambda: hs.add_overlay((0.0, 1.0), (0.0, 1.0), knots=(many, [0.5 + 1e-3])),
            r"add_overlay with knots= of 100000 inserted u-knots \(the refinement matrix\)")
    hs_big = HierarchicalSurface(BSplineSurface((1, 1), (np.r_[0, np.linspace(0, 1, 201), 1],) * 2,
                                                np.random.default_rng(1).random((201, 201, 3))))
    fine = np.linspace(0.001, 0.999, 400)
    refused(lambda: hs_big.add_overlay((0.0, 1.0), (0.0, 1.0), knots=(fine, fine)),
            r"add_overlay with knots= of 400 x 400 inserted \(the refined net\)")
    hc = HierarchicalCurve(_curve())
    refused(lambda: hc.add_overlay((0.0, 1.0), knots=many), "add_overlay with knots= of 100000 inserted knots")
    assert hs.add_overlay((0.0, 1.0), (0.0, 1.0), knots=(many[:50], [0.25])).shape[0] > 50  # within the limit


# ------------------------------------------------------------------ polylines(tol)
def test_trimmed_polylines_with_a_tiny_tol_are_refused_while_refining() -> None:
    """``polylines(tol=0)``: every segment fails the midpoint test, so 30 halvings asked for
    ~2^30 points per loop."""
    c = BSplineCurve(2, [0, 0, 0, 1, 1, 1], [(0, 0), (1, 1.5), (1, 0)])  # a curved p-curve
    loop = (c, BSplineCurve(1, [0, 0, 1, 1], [(1, 0), (0, 0)]))
    ts = TrimmedSurface(BSplineSurface((1, 1), ([0, 0, 1, 1],) * 2, np.random.default_rng(2).random((2, 2, 3))),
                        loop)
    refused(lambda: ts.polylines(0.0), r"tol = 0: a p-curve's polyline within tol")
    refused(lambda: ts.polylines(1e-300), r"tol = 1e-300")
    assert ts.polylines(1e-6)[0].shape[0] > 10


# ------------------------------------------------------------------ scattered fits
def test_scattered_fit_pole_counts_are_refused_before_the_normal_equations() -> None:
    """``fit_scattered(n_poles=(1e5, 1e5))`` made a dense (n, n) difference matrix (80 GB) and a
    sparse LU whose fill grows as n_u n_v min(n_u, n_v); both fits now refuse up front, naming
    ``n_poles`` / ``base_poles``."""
    from occsurf.algorithms.fitting.adaptive_scattered import fit_adaptive_scattered
    from occsurf.algorithms.fitting.scattered import fit_scattered

    X = np.random.default_rng(3).random((400, 3))
    refused(lambda: fit_scattered(X, (100_000, 100_000)), r"n_poles = \(100000, 100000\): the penalised normal")
    refused(lambda: fit_scattered(X, (60, 60)), r"n_poles = \(60, 60\)")
    refused(lambda: fit_adaptive_scattered(X, 1e-3, base_poles=(60, 60)), r"base_poles = \(60, 60\)")
    assert fit_scattered(X, (8, 8)).surface.n_poles == (8, 8)  # within the limit


def test_sparse_difference_penalty_equals_the_dense_one() -> None:
    from occsurf.algorithms.fitting._common import difference_penalty, sparse_difference_penalty

    for n in (1, 2, 3, 7):
        for order in (1, 2, 3):
            np.testing.assert_array_equal(sparse_difference_penalty(n, order).toarray(), difference_penalty(n, order))


# ------------------------------------------------------------------ S-patches
def test_spatch_depth_elevation_and_wachspress_order_are_refused_up_front() -> None:
    """``elevate_depth(times=200)`` ran 252 s into 965 MB; ``wachspress_derivatives(order=500)``
    built ~order^4 / 24 jet terms."""
    from occsurf.algorithms.topology.spatch import SPatch
    from occsurf.algorithms.topology.wachspress import wachspress_derivatives

    from .test_spatch_convert import random_patch

    patch = random_patch(np.random.default_rng(4), 5, 3)
    refused(lambda: patch.elevate_depth(200), r"elevate_depth\(times=200\) from depth 3 to 203")
    refused(lambda: patch.elevate_depth(12), r"elevate_depth\(times=12\)")
    assert isinstance(patch.elevate_depth(2), SPatch)
    pts = np.zeros((4000, 2))
    refused(lambda: wachspress_derivatives(pts, 5, 6), r"wachspress_derivatives of order 6 at 4000 points")
    with pytest.raises(InvalidGeometryError, match="order: 500 exceeds SPATCH_MAX_DERIVATIVE_ORDER"):
        wachspress_derivatives(pts[:1], 5, 500)
    assert wachspress_derivatives(pts[:10], 5, 2).shape == (10, 5, 3, 3)


# ------------------------------------------------------------------ curves: approximation, interpolation
def test_polynomial_approximation_is_refused_before_a_step_passes_the_limit() -> None:
    """A tolerance never met and ``max_subdivisions=2**40`` doubled the pieces until MemoryError."""
    from occsurf.algorithms.construction.coons_patches import polynomial_approximation
    from occsurf.algorithms.kernel.conics import circle

    c = circle([0.0, 0.0, 0.0], 1.0)
    refused(lambda: polynomial_approximation(c, 0.0, max_subdivisions=2**40),
            r"polynomial_approximation with max_subdivisions=1099511627776: \d+ pieces per span")
    with pytest.raises(InvalidGeometryError, match="max_subdivisions: expected a positive integer"):
        polynomial_approximation(c, 1e-3, max_subdivisions=float("inf"))
    assert polynomial_approximation(c, 1e-4)[1] <= 1e-4


def test_interpolation_is_banded_and_the_dense_fits_are_refused() -> None:
    """``interpolate_curve`` of m points built a dense m x m matrix (20 000 points: 3.2 GB); now the
    band alone, so 20 000 points interpolate within a 1 MB limit. ``fit_curve`` keeps its dense
    least-squares operator and is refused, naming ``points``."""
    from occsurf.algorithms.fitting.interpolation import fit_curve, interpolate_curve, interpolate_surface, parametrize
    from occsurf.algorithms.kernel.basis import basis_matrix

    s = np.linspace(0, 6, 20_000)
    Q = np.c_[np.cos(s), np.sin(s), s / 10]
    c = interpolate_curve(Q)
    u = parametrize(Q)
    np.testing.assert_allclose(c.evaluate(u[::997]), Q[::997], rtol=0, atol=1e-12)
    small = Q[::200]
    c_small = interpolate_curve(small)
    dense = np.linalg.solve(basis_matrix(c_small.knots, 3, small.shape[0], parametrize(small))[0], small)
    np.testing.assert_allclose(c_small.control_points, dense, rtol=0, atol=1e-13)  # the same poles as the dense solve
    refused(lambda: fit_curve(Q[:2000], 500), r"points: 2000 data points need \d+ dense 2000 x 500 matrices")
    refused(lambda: interpolate_surface(np.random.default_rng(5).random((400, 4, 3))),
            r"points: 400 data points need 3 dense 400 x 400 matrices")


# ------------------------------------------------------------------ plates, frames
def test_fill_plate_max_spans_and_frame_dims_are_refused_up_front() -> None:
    from occsurf.algorithms.geometry.affine_maps import AffineMap, Frame
    from occsurf.algorithms.topology.nsided import HoleSide
    from occsurf.algorithms.topology.plate_fill import fill_plate

    sq = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    sides = []
    for i in range(4):
        a, b = sq[i], sq[(i + 1) % 4]
        out = np.cross(b - a, [0, 0, 1.0])
        sides.append(HoleSide(BSplineCurve(1, [0, 0, 1, 1], np.array([a, b])),
                              BSplineCurve(1, [0, 0, 1, 1], np.array([out, out]))))
    refused(lambda: fill_plate(sides, max_spans=10**6), r"max_spans: a plate of up to n_poles = \(1000003, 1000003\)")
    refused(lambda: fill_plate(sides, max_spans=40), r"max_spans")
    refused(lambda: Frame.standard(10**6), r"Frame.standard\(dim=1000000\)")
    refused(lambda: AffineMap.identity(10**5), r"AffineMap.identity\(dim=100000\)")
    with pytest.raises(InvalidGeometryError, match="dim: expected a positive integer"):
        Frame.standard(0)
    assert Frame.standard(4).basis.shape == (4, 4)


# ------------------------------------------------------------------ quality grids, counts, arc length
def test_quality_grids_and_counts_are_refused_before_their_arrays() -> None:
    """Curvature maps, flags and hedgehogs on every path (NumPy, numba, S-patch, trimmed) check the
    grid once; counts (comb samples, fold grids, fill samples, isophote levels, legend ticks,
    patch-continuity samples) and arc-length limit pairs are checked before their arrays."""
    from occsurf.algorithms.geometry.differential import arc_length
    from occsurf.algorithms.quality import curvature_comb, curvature_map, face_flags, isophotes, normal_hedgehog
    from occsurf.algorithms.topology.nsided_measure import count_folds

    from .test_spatch_convert import random_patch

    s, ts, patch = _surface(), _trimmed(), random_patch(np.random.default_rng(6), 5, 3)
    for call in (lambda: curvature_map(s, us=400, vs=400), lambda: curvature_map(ts, us=400, vs=400),
                 lambda: curvature_map(patch, us=400, vs=400), lambda: face_flags(s, us=400, vs=400),
                 lambda: normal_hedgehog(s, us=400, vs=400)):
        refused(call, r"us, vs: a 400 x 400 grid")
    refused(lambda: curvature_map(s, us=10**12, vs=3), r"us: 1000000000000 samples")
    assert curvature_map(s, us=20, vs=20).values.shape == (20, 20)
    refused(lambda: curvature_comb(_curve(), n=10**6), r"n = 1000000")
    refused(lambda: count_folds(s, grid=1000), r"grid = 1000: a 1000 x 1000 grid")
    refused(lambda: isophotes(np.array([[0, 0, 1.0]]), [0, 0, 1.0], levels=10**6), r"levels = 1000000")
    cmap = curvature_map(s, us=5, vs=5)
    from occsurf.algorithms.quality import color_scale
    refused(lambda: color_scale(cmap.values).legend_ticks(10**6), r"n = 1000000")
    c = _curve()
    refused(lambda: arc_length(c, np.zeros((3000, 1)), np.ones((1, 3000)) * 0.5),
            r"u0, u1 broadcast to shape \(3000, 3000\)")
    assert float(arc_length(c, 0.0, 1.0)) > 0


def test_fill_and_generalized_samples_are_refused_before_their_arrays() -> None:
    from occsurf.algorithms.topology.generalized import generalized_biquadratic
    from occsurf.algorithms.topology.nsided import fill_hole
    from occsurf.algorithms.topology.nsided_measure import measure_fill

    from .test_generalized import ngon_with_skirt
    from .test_nsided_split import _circle, _planar

    fill = fill_hole([_planar(_circle())])
    refused(lambda: measure_fill(fill, samples=10**6), r"samples = 1000000")
    g = generalized_biquadratic(ngon_with_skirt(5, np.random.default_rng(7)))
    refused(lambda: g.continuity(samples=10**6), r"samples = 1000000")
    assert g.continuity(samples=9)[0] >= 0.0
