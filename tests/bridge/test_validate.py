"""``occsurf.bridge.validation.deviation``: deviation reports against OCC and between two of our splines."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from numpy.testing import assert_allclose
from OCP.Geom import Geom_SphericalSurface
from OCP.gp import gp_Ax3

from occsurf.algorithms import BSplineCurve, BSplineSurface
from occsurf.algorithms.errors import InvalidGeometryError
from occsurf.bridge.conversion.splines import from_occ, to_occ
from occsurf.bridge.validation.deviation import (
    CurveDeviation,
    RoundTripDeviation,
    SurfaceDeviation,
    curve_deviation,
    roundtrip_deviation,
    surface_deviation,
)

from .test_kernel_vs_occ import SETTINGS, curves, occ_rtol, surfaces


def _rot_x(theta: float) -> np.ndarray:
    c, s = np.cos(theta), np.sin(theta)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


# ============================================================================ against OCC
@SETTINGS
@given(s=surfaces(degrees=st.integers(1, 9)))
def test_surface_deviation_of_identical_data_is_round_off(s):
    dev = surface_deviation(s, samples=7)
    assert isinstance(dev, SurfaceDeviation) and dev.n_samples == 49
    tol = occ_rtol(max(s.degree))  # OCC's own accuracy bounds the agreement (test_kernel_vs_occ)
    assert dev.max_d1_rel <= tol and dev.max_d2_rel <= tol
    # points relative to the bbox: coordinates are <= 1 here, so bbox-relative = coordinate-relative
    # as long as the patch is not tiny; OCC's round-off is ~1e-12 of the coordinates at degree 9.
    assert dev.max_point <= tol
    # angles between nearly equal unit vectors: sqrt-sensitive; near a singular point the derivatives'
    # round-off alone turns the normal by up to normal_angle_bound (first order; twice it for the rest)
    assert dev.max_normal_angle <= max(1e-6, 2.0 * dev.normal_angle_bound)


@SETTINGS
@given(c=curves())
def test_curve_deviation_of_identical_data_is_round_off(c):
    dev = curve_deviation(c, samples=21)
    assert isinstance(dev, CurveDeviation) and dev.n_samples == 21
    tol = occ_rtol(c.degree)
    assert dev.max_point <= tol
    assert max(dev.max_d1_rel, dev.max_d2_rel, dev.max_d3_rel) <= tol


@pytest.mark.parametrize("seed", range(6))
def test_normal_angle_bound_bounds_the_normals_of_a_perturbed_surface(seed):
    """Poles moved by 1e-6 (far above round-off): the normals turn by at most the first-order bound
    from the first derivatives' differences (twice it, for the second-order rest), and by more
    than a thousandth of it (the bound is not vacuous)."""
    rng = np.random.default_rng(seed)
    s = BSplineSurface((3, 2), ([0, 0, 0, 0, 0.4, 1, 1, 1, 1], [0, 0, 0, 1, 1, 1]), rng.uniform(-1, 1, (5, 3, 3)))
    moved = BSplineSurface(s.degree, s.knots, s.control_points + 1e-6 * rng.standard_normal((5, 3, 3)))
    dev = surface_deviation(s, to_occ(moved), samples=9)
    assert 1e-3 * dev.normal_angle_bound <= dev.max_normal_angle <= 2.0 * dev.normal_angle_bound


def test_surface_deviation_measures_a_translation_exactly():
    rng = np.random.default_rng(0)
    s = BSplineSurface((3, 2), ([0, 0, 0, 0, 0.4, 1, 1, 1, 1], [0, 0, 0, 1, 1, 1]),
                       rng.uniform(-1, 1, (5, 3, 3)), rng.uniform(0.5, 2, (5, 3)))
    delta = np.array([3e-4, -4e-4, 0.0])  # |delta| = 5e-4
    dev = surface_deviation(s, to_occ(s.transform(np.eye(3), delta)), samples=9)
    assert_allclose(dev.max_point, 5e-4, rtol=1e-9)  # every point moves by |delta| (round-off only)
    assert_allclose(dev.max_point_rel, 5e-4 / dev.bbox_diagonal, rtol=1e-6)
    assert dev.max_d1_rel <= 1e-12 and dev.max_d2_rel <= 1e-12  # derivatives are unchanged
    assert dev.max_normal_angle <= 1e-7


def test_surface_deviation_measures_a_rotation_of_the_normals():
    # A planar bilinear patch rotated by theta about the x-axis: every normal turns by theta.
    P = np.array([[[0, 0, 0], [0, 1, 0]], [[1, 0, 0], [1, 1, 0]]], float)
    s = BSplineSurface((1, 1), ([0, 0, 1, 1], [0, 0, 1, 1]), P)
    theta = 0.05
    dev = surface_deviation(s, to_occ(s.transform(_rot_x(theta))), samples=5)
    assert_allclose(dev.max_normal_angle, theta, rtol=1e-9)
    # the far corner (0, 1) or (1, 1) moves by 2 sin(theta/2)
    assert_allclose(dev.max_point, 2 * np.sin(theta / 2), rtol=1e-9)
    assert dev.max_d2 == 0.0  # a bilinear patch has S_uu = S_vv = 0 and S_uv = 0 exactly here
    assert dev.max_d2_rel == 0.0


def test_curve_deviation_measures_a_scaled_curve():
    rng = np.random.default_rng(1)
    c = BSplineCurve(3, [0, 0, 0, 0, 0.3, 0.6, 1, 1, 1, 1], rng.uniform(-1, 1, (6, 3)))
    dev = curve_deviation(c, to_occ(c.transform(1.001 * np.eye(3))), samples=31)
    D = c.derivatives(np.linspace(0, 1, 31), 3)
    # scaling by 1.001 changes every derivative by 0.001 of itself
    assert_allclose(dev.max_point, 1e-3 * np.max(np.linalg.norm(D[:, 0], axis=-1)), rtol=1e-9)
    assert_allclose(dev.max_d1, 1e-3 * np.max(np.linalg.norm(D[:, 1], axis=-1)), rtol=1e-9)
    assert_allclose(dev.max_d3, 1e-3 * np.max(np.linalg.norm(D[:, 3], axis=-1)), rtol=1e-9)
    # relative to max(sup, control-polygon size) >= 1.001 sup
    assert 0 < dev.max_d3_rel <= 1e-3 / 1.001 * (1 + 1e-9)


def test_samples_an_ulp_off_a_knot_are_snapped_onto_it():
    # Found by hypothesis: a C0 (degree 1) patch whose uniform v-samples land 1 ulp below a knot.
    # OCC treats such a parameter as the knot (derivative from the right), we would not: without
    # the snapping the report showed a "deviation" of O(1) in S_v.
    v0, v1 = 3.14991296, 9.59962184
    lin = np.linspace(v0, v1, 7)
    k = np.nextafter(lin[2], np.inf)  # the sample lin[2] is one ulp below this knot
    U = np.array([1.0, 1.0, 2.0, 3.0, 4.0, 4.0])
    V = np.array([v0, v0, k, 6.44971888, v1, v1])
    P = np.ones((4, 4, 3))
    P[:, 1] = [0.0, 1.0, 1.0]  # the v-derivative jumps at every knot
    s = BSplineSurface((1, 1), (U, V), P)
    occ = to_occ(s)
    assert occ.DN(1.5, lin[2], 0, 1).Coord() == occ.DN(1.5, k, 0, 1).Coord()  # OCC: as at the knot
    assert not np.allclose(s.derivatives(1.5, lin[2], 1)[0, 1], s.derivatives(1.5, k, 1)[0, 1])  # ours: not
    dev = surface_deviation(s, samples=7)
    assert dev.max_d1_rel <= 1e-15 and dev.max_point <= 1e-15  # identical data: round-off at most


def test_sphere_poles_do_not_spoil_the_normal_angle():
    # From OCC's sphere: the grid includes both poles, where S_u = 0 and our cross product is noise.
    s = from_occ(Geom_SphericalSurface(gp_Ax3(), 3.0))
    dev = surface_deviation(s, samples=11)
    assert dev.max_normal_angle <= 1e-12
    assert dev.max_point_rel <= 1e-14  # degree 2: OCC is accurate too


def test_surface_deviation_against_the_analytic_original():
    # OCC's sphere and its B-spline have the same image, not the same parametrisation: the report
    # makes the difference visible (it is large), which is what it is for.
    occ_sphere = Geom_SphericalSurface(gp_Ax3(), 3.0)
    dev = surface_deviation(from_occ(occ_sphere), occ_sphere, samples=9)
    assert dev.max_point > 1e-2


def test_deviation_reports_are_frozen():
    c = BSplineCurve(1, [0, 0, 1, 1], [[0, 0, 0], [1, 0, 0]])
    dev = curve_deviation(c, samples=3)
    with pytest.raises(dataclasses.FrozenInstanceError):
        dev.max_point = 1.0


@pytest.mark.parametrize("samples", [1, 0, 2.5, True, "9"])
def test_bad_sample_counts(samples):
    c = BSplineCurve(1, [0, 0, 1, 1], [[0, 0, 0], [1, 0, 0]])
    with pytest.raises(InvalidGeometryError, match="samples"):
        curve_deviation(c, samples=samples)


def test_wrong_types():
    c = BSplineCurve(1, [0, 0, 1, 1], [[0, 0, 0], [1, 0, 0]])
    with pytest.raises(InvalidGeometryError, match="BSplineCurve"):
        surface_deviation(c)
    with pytest.raises(InvalidGeometryError, match="ndarray"):
        curve_deviation(np.zeros(3))


# ============================================================================ round trips
@SETTINGS
@given(s=surfaces(degrees=st.integers(1, 5)))
def test_roundtrip_deviation_of_an_exact_copy_is_zero(s):
    r = roundtrip_deviation(s, from_occ(to_occ(s)))
    assert r == RoundTripDeviation(0.0, 0.0, 0.0, 0.0, True)


def test_roundtrip_deviation_reports_each_kind_of_change():
    rng = np.random.default_rng(2)
    c = BSplineCurve(3, [0, 0, 0, 0, 0.5, 1, 1, 1, 1], rng.uniform(-1, 1, (5, 3)), rng.uniform(0.5, 2, 5))
    # moved pole
    P = c.control_points.copy()
    P[2] += [0.0, 3e-6, 4e-6]
    r = roundtrip_deviation(c, BSplineCurve(3, c.knots, P, c.weights))
    assert r.same_structure and r.max_knot == 0.0 and r.max_weight == 0.0
    assert_allclose(r.max_pole, 5e-6, rtol=1e-9)
    assert 0 < r.max_point <= 5e-6  # convex hull: a point moves at most as far as a pole
    # changed weight
    w = c.weights.copy()
    w[1] *= 1.5
    r = roundtrip_deviation(c, BSplineCurve(3, c.knots, c.control_points, w))
    assert_allclose(r.max_weight, 0.5 * c.weights[1], rtol=1e-15)
    # shifted parametrisation: knots differ, points (mapped affinely) do not
    r = roundtrip_deviation(c, c.reparametrize(10.0, 11.0))
    # (the kernel rebuilds rational poles from homogeneous ones: an ulp of change)
    assert r.same_structure and r.max_knot == 10.0 and r.max_pole <= 1e-15
    # parameters near 10 are rounded to ulp(10) = 1.8e-15; times |C'| (<= ~10 here)
    assert r.max_point <= 1e-13
    # different structure, same curve
    r = roundtrip_deviation(c, c.insert_knot(0.25))
    assert not r.same_structure and r.max_pole == np.inf and r.max_knot == np.inf
    assert r.max_point <= 1e-15
    # a missing weight array counts as ones
    poly = BSplineCurve(3, c.knots, c.control_points)
    r = roundtrip_deviation(poly, BSplineCurve(3, c.knots, c.control_points, np.ones(5)))
    assert (r.max_pole, r.max_knot, r.max_weight, r.same_structure) == (0.0, 0.0, 0.0, True)
    assert r.max_point <= 1e-15  # the rational form divides by sum(N_i) = 1 +- an ulp


def test_roundtrip_deviation_refuses_mixed_kinds():
    c = BSplineCurve(1, [0, 0, 1, 1], [[0, 0, 0], [1, 0, 0]])
    s = BSplineSurface((1, 1), ([0, 0, 1, 1], [0, 0, 1, 1]), np.zeros((2, 2, 3)))
    with pytest.raises(InvalidGeometryError, match="BSplineCurve and BSplineSurface"):
        roundtrip_deviation(c, s)
    with pytest.raises(InvalidGeometryError, match="dimensions differ"):
        roundtrip_deviation(c, BSplineCurve(1, [0, 0, 1, 1], [[0, 0], [1, 0]]))
