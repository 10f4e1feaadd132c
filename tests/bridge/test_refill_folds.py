"""Folds of refilled holes (issue 12): side curves of uneven speed, and the fold count of a trimmed fill.

* ``refill_sides._even_speed``: a side whose parameter speed varies by more than ``EVEN_SPEED_RATIO`` is
  re-fitted as a cubic of its arc length. Closed-form holes: planar slivers 6 x 1 (z = 0, in-plane
  cross fields: the exact fill is the plane) with one long side crawling at one end (speed ratio
  e^3 = 20; the M6 screw's thread edges have 13.5 and 13.9), a cubic of 131 poles, re-fitted to a
  cubic of 4 and 11 poles. These slivers folded (424 and 212 folded grid pairs) while the cross field
  kept every knot of its side, spans without a normal sample included: the minimum-norm field sagged
  between samples. With only the sampled knots (``nsided_sides._sampled_knots``) neither the crawling
  side nor its re-fit folds; the re-fit is kept for its few poles (the patches take the side's knots,
  ``nsided_patches._patch_space``). The re-fit stays within its tolerance
  (1e-7 of the hole's length here, as refill_sides asks 1e-7 of the model size) of the original curve,
  both ways (closest points by Newton's iteration, converged to round-off), and keeps both ends
  bit-exact (the sides meet).
* ``count_folds`` of a :class:`TrimmedSurface` counts only grid pairs on the face: a surface steep
  (or folded) outside its trim is not folded as a face; a fold inside the trim still counts.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from occsurf.algorithms.kernel.curve import BSplineCurve
from occsurf.algorithms.kernel.surface import BSplineSurface
from occsurf.algorithms.kernel.trimmed import TrimmedSurface
from occsurf.algorithms.topology.nsided import HoleSide, closest_parameters, count_folds, fill_folds, fill_hole
from occsurf.algorithms.topology.nsided_sides import fit_boundary, side_from_normals
from occsurf.bridge.modeling.refill_sides import EVEN_SPEED_RATIO, _even_speed


def _line(a, b) -> BSplineCurve:
    return BSplineCurve(1, [0, 0, 1, 1], np.array([a, b], float))


def _quad(a, b, bend: float) -> BSplineCurve:
    a, b = np.asarray(a, float), np.asarray(b, float)
    return BSplineCurve(2, [0, 0, 0, 1, 1, 1], np.array([a, 0.5 * (a + b) + [0.0, bend, 0.0], b]))


def _crawl(curve: BSplineCurve, k: float) -> BSplineCurve:
    """The same curve (within 1e-9) run at speed ~ e^(k t): a cubic fitted at t to curve(g(t)),
    g(t) = (e^(k t) - 1) / (e^k - 1)."""
    t = np.linspace(0.0, 1.0, 801)
    return fit_boundary(t, curve.evaluate(np.expm1(k * t) / np.expm1(k)), 1e-9)[0]


def _speed_ratio(curve: BSplineCurve) -> float:
    s = np.linalg.norm(curve.derivatives(np.linspace(*curve.domain, 2001), 1)[:, 1], axis=1)
    return float(s.max() / s.min())


def _planar(curve: BSplineCurve) -> HoleSide:
    s = np.linspace(*curve.domain, 64)
    return side_from_normals(curve, s, np.tile([0.0, 0.0, 1.0], (64, 1))).side


def _distance_to(curve: BSplineCurve, points: np.ndarray) -> np.ndarray:
    """Distance of each point to ``curve`` (closest points by Newton's iteration, vectorised)."""
    return closest_parameters(curve, points)[1]


def _sliver(long_side: BSplineCurve, length: float = 6.0, width: float = 1.0, bend: float = 0.3) -> list[HoleSide]:
    B, C = [length, -0.5 * width, 0.0], [length, 0.5 * width, 0.0]
    return [_planar(long_side), _planar(_line(B, C)), _planar(_quad(C, [0, 0, 0], bend))]


@pytest.mark.parametrize("bend, k", [(0.0, 3.0), (-0.3, -3.0)])
def test_uneven_side_is_refitted_by_arc_length_to_few_poles_and_neither_fill_folds(bend, k):
    length = 6.0
    side = _crawl(_quad([0, 0, 0], [length, -0.5, 0], bend), k)
    assert _speed_ratio(side) > 15  # e^3
    before = fill_hole(_sliver(side, length))
    # 424 and 212 (module docstring) while the cross field kept all the side's knots; with only the
    # sampled ones (nsided_sides._sampled_knots) the sag that folded it is gone (lens helper, issue 12)
    assert fill_folds(before) == 0
    tol = 1e-7 * length
    even = _even_speed(side, tol)
    assert even is not side and _speed_ratio(even) < 1.2
    assert len(even.control_points) <= 16 < len(side.control_points)  # 4 and 11 poles against 131
    after = fill_hole(_sliver(even, length))
    assert fill_folds(after) == 0
    assert _distance_to(side, even.evaluate(np.linspace(0, 1, 1001))).max() <= tol
    assert _distance_to(even, side.evaluate(np.linspace(*side.domain, 1001))).max() <= tol
    np.testing.assert_array_equal(even.evaluate(0.0), side.evaluate(side.domain[0]))
    np.testing.assert_array_equal(even.evaluate(1.0), side.evaluate(side.domain[1]))


@settings(max_examples=10, deadline=None)
@given(k=st.floats(1.5, 4.0), bend=st.floats(-1.0, 1.0), lift=st.floats(-1.0, 1.0))
def test_even_speed_within_tolerance_ends_exact(k, bend, lift):
    c = _quad([0, 0, 0], [5.0, 1.0, lift], bend)
    side = _crawl(c, k)
    tol = 5e-7
    even = _even_speed(side, tol)
    assert even is not side and _speed_ratio(even) < 1.5
    assert _distance_to(side, even.evaluate(np.linspace(0, 1, 801))).max() <= tol
    assert _distance_to(even, side.evaluate(np.linspace(*side.domain, 801))).max() <= tol
    np.testing.assert_array_equal(even.evaluate(np.array([0.0, 1.0])), side.evaluate(np.array(side.domain)))


def test_even_speed_leaves_even_and_unfittable_curves_alone():
    c = _quad([0, 0, 0], [5.0, 1.0, 0.0], 0.5)  # speed ratio 1.08
    assert _speed_ratio(c) < EVEN_SPEED_RATIO and _even_speed(c, 1e-9) is c
    side = _crawl(c, 3.0)
    assert _even_speed(side, 1e-30) is side  # no cubic within 1e-30: the exact curve is kept


# ------------------------------------------------------------------ count_folds inside a trim
def _square_loop(u0: float, u1: float, v0: float, v1: float) -> list[BSplineCurve]:
    P = [(u0, v0), (u1, v0), (u1, v1), (u0, v1)]
    return [BSplineCurve(1, [0, 0, 1, 1], np.array([P[i], P[(i + 1) % 4]], float)) for i in range(4)]


def _folded_sheet() -> BSplineSurface:
    """(x, y, z) = ((u - 0.51)^2, v, 0) folds over itself at u = 0.51 (its normal (0, 0, 2u - 1.02) flips;
    off the grid's u = 1/2, where the normal would vanish and count as neither side)."""
    P = np.zeros((3, 2, 3))
    P[:, :, 0] = np.array([0.2601, -0.2499, 0.2401])[:, None]  # Bernstein coefficients of (u - 0.51)^2
    P[:, :, 1] = np.array([0.0, 1.0])[None, :]
    return BSplineSurface((2, 1), ([0, 0, 0, 1, 1, 1], [0, 0, 1, 1]), P)


def _steep_valley(depth: float = 200.0) -> BSplineSurface:
    """A height field z = depth (u - 0.81)^2 over the unit square: not a fold anywhere, but the grid
    neighbours u = 0.8, 0.825 have slopes -4 and 6 (on the trimmed grid of [0.5, 1]: 0.8, 0.8125, -4
    and 1), normals more than 90 degrees apart (count_folds
    counts them)."""
    P = np.zeros((3, 2, 3))
    P[:, :, 0] = np.array([0.0, 0.5, 1.0])[:, None]
    P[:, :, 1] = np.array([0.0, 1.0])[None, :]
    z = depth * np.array([0.6561, -0.1539, 0.0361])  # Bernstein coefficients of (u - 0.81)^2
    P[:, :, 2] = z[:, None]
    return BSplineSurface((2, 1), ([0, 0, 0, 1, 1, 1], [0, 0, 1, 1]), P)


def test_count_folds_counts_only_inside_the_trim():
    sheet = _folded_sheet()
    assert count_folds(sheet) > 0
    assert count_folds(TrimmedSurface(sheet, _square_loop(0.2, 0.8, 0.1, 0.9))) > 0  # the fold is on the face
    assert count_folds(TrimmedSurface(sheet, _square_loop(0.0, 0.45, 0.0, 1.0))) == 0
    assert count_folds(TrimmedSurface(sheet, _square_loop(0.55, 1.0, 0.0, 1.0))) == 0
    valley = _steep_valley()
    assert count_folds(valley) > 0
    assert count_folds(TrimmedSurface(valley, _square_loop(0.0, 0.7, 0.0, 1.0))) == 0
    assert count_folds(TrimmedSurface(valley, _square_loop(0.5, 1.0, 0.0, 1.0))) > 0


def test_a_ripple_one_span_wide_on_a_trimmed_face_is_seen():
    """A height field of 128 cubic spans in u with one ripple (three poles +-0.02, three spans wide,
    normals more than 90 degrees apart a span apart): the 41 x 41 grid steps over it (0 pairs, measured),
    the trimmed face's grid (two points per span) counts it."""
    m, p = 128, 3
    K = np.r_[np.zeros(p + 1), np.arange(1, m) / m, np.ones(p + 1)]
    n = len(K) - p - 1
    P = np.zeros((n, 2, 3))
    P[:, :, 0] = np.convolve(K[1:-1], np.ones(p) / p, mode="valid")[:, None]  # Greville abscissae: x = u
    P[:, :, 1] = np.array([0.0, 1.0])[None, :]
    P[41:44, :, 2] = 0.02 * np.array([1.0, -1.0, 1.0])[:, None]
    ripple = BSplineSurface((p, 1), (K, [0, 0, 1, 1]), P)
    assert count_folds(ripple) == 0
    assert count_folds(TrimmedSurface(ripple, _square_loop(0.0, 1.0, 0.0, 1.0))) > 0
