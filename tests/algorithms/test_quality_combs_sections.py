"""Curvature combs, iso-curves and section cuts (occsurf.algorithms.quality.combs / sections).

Closed forms: a circle's comb has constant spines (1/R); the cubic (t, (t - a)^3) has its one
inflection at t = a; iso-curves of a torus are its exact circles; a plane section of a sphere is a
circle of radius sqrt(R^2 - z^2) with constant curvature and comb length; the section of an
extruded cubic has its inflection at the cubic's; axial sections of a torus are its tube circles.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from numpy.testing import assert_allclose

from occsurf.algorithms import BSplineCurve, circle, tolerances
from occsurf.algorithms.construction import extrude
from occsurf.algorithms.errors import InvalidGeometryError
from occsurf.algorithms.quality import SampledCurve, axial_sections, curvature_comb, iso_curves, plane_sections
from occsurf.algorithms.quality.section_cuts import order_chains, rank

from .strategies import test_settings
from .test_quality_maps import sphere, torus, wavy

R = 2.0


def cubic_with_inflection(a: float) -> BSplineCurve:
    """(t, (t - a)^3) on [0, 1], as a Bézier (power basis -> Bernstein)."""
    c0, c1, c2 = -a**3, 3 * a**2, -3 * a
    b = [c0, c0 + c1 / 3, c0 + 2 * c1 / 3 + c2 / 3, c0 + c1 + c2 + 1]
    return BSplineCurve(3, [0, 0, 0, 0, 1, 1, 1, 1], [[0, b[0]], [1 / 3, b[1]], [2 / 3, b[2]], [1, b[3]]])


# ------------------------------------------------------------------------------------ combs
def test_circle_comb_is_constant():
    cb = curvature_comb(circle([0, 0, 0], R), 64, plane_normal=[0, 0, 1])
    assert_allclose(cb.curvature, 1 / R, rtol=1e-12)
    assert_allclose(cb.signed, 1 / R, rtol=1e-12)  # counter-clockwise about +z: turning left
    spines = np.linalg.norm(cb.tips - cb.points, axis=1)
    assert_allclose(spines, spines[0], rtol=1e-12)
    # spines point away from the centre (convex side)
    assert np.all(np.linalg.norm(cb.tips, axis=1) > R)
    assert cb.n_inflections == 0
    # default scale: the longest spine is 20 % of the diagonal of the sampled points
    assert_allclose(spines.max(), 0.2 * np.linalg.norm(np.ptp(cb.points, axis=0)), rtol=1e-12)
    # without a plane the comb is unsigned
    assert curvature_comb(circle([0, 0, 0], R), 16).signed is None


@pytest.mark.parametrize("a", [0.37, 0.5, 0.8123])
def test_cubic_inflection_at_known_parameter(a):
    cb = curvature_comb(cubic_with_inflection(a), 31)
    assert cb.n_inflections == 1
    assert abs(cb.inflection_params[0] - a) <= 1e-12
    assert_allclose(cb.inflection_points[0], [a, 0, 0], atol=1e-12)
    # the spines change side at the inflection
    side = np.sign((cb.tips - cb.points)[:, 1])  # the curve runs along +x: spines above or below
    assert side[0] != side[-1]


def test_inflection_tolerance_is_a_tolerance():
    with tolerances.override(QUALITY_INFLECTION_TOL=1e-3):
        cb = curvature_comb(cubic_with_inflection(0.37), 31)
    assert 1e-9 < abs(cb.inflection_params[0] - 0.37) <= 1e-3


def test_straight_piece_has_no_spurious_inflection():
    line = BSplineCurve(3, [0, 0, 0, 0, 1, 1, 1, 1], [[0, 0], [1, 0], [2, 0], [3, 0]])
    cb = curvature_comb(line, 20)
    assert cb.n_inflections == 0 and np.all(cb.curvature == 0)
    assert_allclose(cb.tips, cb.points)


def test_sampled_curve_comb():
    t = np.linspace(0, 1, 201)
    a = 0.4
    P = np.c_[t, (t - a) ** 3, np.zeros_like(t)]
    d1 = np.c_[np.ones_like(t), 3 * (t - a) ** 2, np.zeros_like(t)]
    d2 = np.c_[np.zeros_like(t), 6 * (t - a), np.zeros_like(t)]
    cb = curvature_comb(SampledCurve(t, P, d1, d2), plane_normal=[0, 0, 1])
    assert cb.n_inflections == 1 and abs(cb.inflection_params[0] - a) < 1e-3
    ref = curvature_comb(cubic_with_inflection(a), 201)
    assert_allclose(cb.curvature, ref.curvature, rtol=1e-12, atol=1e-14)
    with pytest.raises(InvalidGeometryError, match="params"):
        curvature_comb(SampledCurve(t[::-1], P, d1, d2))


def test_comb_bad_input():
    with pytest.raises(InvalidGeometryError, match="curve"):
        curvature_comb([1, 2, 3])
    with pytest.raises(InvalidGeometryError, match="n:"):
        curvature_comb(circle([0, 0, 0], 1.0), 1)
    with pytest.raises(InvalidGeometryError, match="plane_normal"):
        curvature_comb(circle([0, 0, 0], 1.0), 5, plane_normal=[0, 0, 0])


# ----------------------------------------------------------------------------------- iso-curves
def test_iso_curves_are_exact():
    s = torus()
    t = np.linspace(0, 2 * np.pi, 13)
    for u0, c in zip([0.3, 2.0], iso_curves(s, "u", [0.3, 2.0])):
        assert c.is_rational
        assert_allclose(c.evaluate(t), s.evaluate(np.full_like(t, u0), t), atol=1e-14)
    for v0, c in zip([0.0, 5.0], iso_curves(s, "v", [0.0, 5.0])):
        assert_allclose(c.evaluate(t), s.evaluate(t, np.full_like(t, v0)), atol=1e-14)
        cb = curvature_comb(c, 40)
        assert np.all(np.isfinite(cb.curvature))
    with pytest.raises(InvalidGeometryError, match="direction"):
        iso_curves(s, "w", [0.1])


@given(u=st.floats(0, 1), seed=st.integers(0, 50))
@test_settings(20)
def test_iso_curve_matches_surface_and_knot_insertion(u, seed):
    s = wavy(7, seed)
    c = iso_curves(s, "u", [u])[0]
    v = np.linspace(0, 1, 9)
    assert_allclose(c.evaluate(v), s.evaluate(np.full_like(v, u), v), atol=1e-12)
    s2 = s.insert_knot(0.5, direction="v")
    c2 = iso_curves(s2, "u", [u])[0]
    assert_allclose(c2.evaluate(v), c.evaluate(v), atol=1e-12)


# ------------------------------------------------------------------------------------- sections
@pytest.mark.parametrize("z", [0.5, -1.0, 1.9, 0.0])
def test_plane_section_of_sphere_is_a_circle(z):
    (sec,) = plane_sections([sphere()], [0, 0, 0], [0, 0, 1], [z])
    assert len(sec.curves) == 1 and sec.n_unconverged == 0
    c = sec.curves[0]
    assert c.closed
    r = np.sqrt(R**2 - z**2)
    assert_allclose(np.hypot(c.points[:, 0], c.points[:, 1]), r, atol=1e-10 * 4 * R)
    assert_allclose(c.points[:, 2], z, atol=1e-10 * 4 * R)
    assert_allclose(np.abs(c.curvature), 1 / r, rtol=1e-9)
    spines = np.linalg.norm(c.comb.tips - c.comb.points, axis=1)
    assert_allclose(spines, spines[0], rtol=1e-9)
    assert c.inflection_points.shape == (0, 3)


def test_parallel_family_and_tolerance():
    secs = plane_sections([sphere()], [0, 0, -1], [0, 0, 2.0], [0.0, 0.5, 1.0, 1.5, 5.0])
    assert [s.offset for s in secs] == [0.0, 0.5, 1.0, 1.5, 5.0]
    assert [len(s.curves) for s in secs] == [1, 1, 1, 1, 0]
    assert_allclose(secs[2].curves[0].points[:, 2], 0.0, atol=1e-12)
    loose = plane_sections([sphere()], [0, 0, 0.3], [0, 0, 1], [0.0], tol=1e-3)[0].curves[0]
    assert np.max(np.abs(loose.points[:, 2] - 0.3)) <= 1e-3


def test_section_of_extruded_cubic_finds_its_inflection():
    a = 0.37
    s = extrude(cubic_with_inflection(a).__class__(3, [0, 0, 0, 0, 1, 1, 1, 1],
                np.c_[cubic_with_inflection(a).control_points, np.zeros(4)]), [0, 0, 1.0])
    (sec,) = plane_sections([s], [0, 0, 0], [0, 0, 1], [0.5])
    assert len(sec.curves) == 1 and not sec.curves[0].closed
    assert sec.n_inflections == 1
    assert_allclose(sec.inflection_points[0], [a, 0, 0.5], atol=1e-10)
    # the exact curvature of the cut equals the cubic's
    c = sec.curves[0]
    x = c.points[:, 0]
    k = 6 * (x - a) / (1 + 9 * (x - a) ** 4) ** 1.5
    assert_allclose(np.abs(c.curvature), np.abs(k), atol=1e-9)


def test_sections_chain_across_faces_and_fit():
    s = sphere()
    left, right = s.split(np.pi, direction="v")
    (sec,) = plane_sections([left, right], [0, 0, 0], [0, 0, 1], [0.7], fit=True)
    assert len(sec.curves) == 1
    c = sec.curves[0]
    assert c.closed and set(np.unique(c.face)) == {0, 1}
    r = np.sqrt(R**2 - 0.49)
    assert_allclose(np.hypot(c.points[:, 0], c.points[:, 1]), r, atol=1e-10)
    t = np.linspace(0, 1, 50)
    assert_allclose(np.hypot(*c.spline.evaluate(t)[:, :2].T), r, atol=1e-3)
    # trimmed faces: keep x > 0 only
    (half,) = plane_sections([(s, lambda u, v: s.evaluate(u, v)[..., 0] > 0)], [0, 0, 0], [0, 0, 1], [0.7])
    pts = np.concatenate([c.points for c in half.curves])
    assert np.all(pts[:, 0] > -1e-9) and len(half.curves) == 1 and not half.curves[0].closed


def test_axial_sections_of_torus():
    secs = axial_sections([torus()], [0, 0, 0], [0, 0, 1], [0.0, 1.0, 2.5])
    for sec in secs:
        assert len(sec.curves) == 1
        c = sec.curves[0]
        assert c.closed
        rho = np.hypot(c.points[:, 0], c.points[:, 1])
        assert_allclose(np.hypot(rho - 3, c.points[:, 2]), 1.0, atol=1e-10)
        assert_allclose(np.abs(c.curvature), 1.0, rtol=1e-9)
        ang = np.arctan2(c.points[:, 1], c.points[:, 0])
        d = np.angle(np.exp(1j * (ang - ang[0])))
        assert np.max(np.abs(d)) < 1e-9  # one meridian half-plane, not both


def test_chain_ordering_pointer_doubling():
    # two paths and a cycle, shuffled
    src = np.array([5, 0, 1, 7, 8, 9, 3, 2])
    dst = np.array([6, 1, 2, 8, 9, 7, 4, 3])
    chains = {tuple(n): c for n, c in order_chains(src, dst)}
    assert chains[(0, 1, 2, 3, 4)] is False and chains[(5, 6)] is False
    assert any(c and sorted(n) == [7, 8, 9] for n, c in chains.items())
    nxt = np.array([1, 2, 3, -1])
    assert list(rank(nxt)) == [3, 2, 1, 0]


def test_section_bad_input():
    with pytest.raises(InvalidGeometryError, match="faces"):
        plane_sections(sphere(), [0, 0, 0], [0, 0, 1], [0])
    with pytest.raises(InvalidGeometryError, match="faces\\[0\\]"):
        plane_sections(["x"], [0, 0, 0], [0, 0, 1], [0])
    with pytest.raises(InvalidGeometryError, match="normal"):
        plane_sections([sphere()], [0, 0, 0], [0, 0, 0], [0])
    with pytest.raises(InvalidGeometryError, match="offsets"):
        plane_sections([sphere()], [0, 0, 0], [0, 0, 1], [np.nan])
    with pytest.raises(InvalidGeometryError, match="angles"):
        axial_sections([sphere()], [0, 0, 0], [0, 0, 1], [])


def test_sections_and_iso_curves_of_a_hierarchical_surface():
    from occsurf.algorithms.hierarchical import HierarchicalSurface

    hs = HierarchicalSurface(wavy(8, 4))
    o = hs.add_overlay((0.2, 0.8), (0.2, 0.8))
    hs.move_vertex(o, (3, 3), [0.0, 0.0, 0.3])
    flat = hs.flatten()
    (a,) = plane_sections([hs], [2.0, 0, 0], [1, 0, 0], [0.0])
    (b,) = plane_sections([flat], [2.0, 0, 0], [1, 0, 0], [0.0])
    assert len(a.curves) == len(b.curves) == 1
    assert_allclose(a.curves[0].points, b.curves[0].points, atol=1e-9)
    assert_allclose(a.curves[0].curvature, b.curves[0].curvature, rtol=1e-7, atol=1e-9)
    c = iso_curves(hs, "v", [0.5])[0]
    t = np.linspace(0, 1, 11)
    assert_allclose(c.evaluate(t), hs.evaluate(t, np.full_like(t, 0.5)), atol=1e-12)


# ------------------------------------------------------------------------------ trims and samples
def test_sections_reach_the_trim_boundary():
    """A dome trimmed to a disk in parameter space: every cut is marched on to the trim (its ends on
    the disk's circle to the section tolerance), not stopped at the last seed-grid crossing inside."""
    from .test_quality_flags import dome

    s = dome()
    R = 0.3

    def mask(u, v):
        return (np.asarray(u) - 0.5) ** 2 + (np.asarray(v) - 0.5) ** 2 < R**2

    secs = plane_sections([(s, mask)], [0, 0, 0], [1, 0, 0], np.linspace(0.35, 0.65, 7))
    ends = []
    for sec in secs:
        assert len(sec.curves) == 1
        c = sec.curves[0]
        assert np.all(mask(c.uv[:, 0], c.uv[:, 1]))
        ends.append(c.uv[[0, -1]])
    r = np.linalg.norm(np.concatenate(ends) - 0.5, axis=1)
    # the ends of each cut are on the trim circle |uv - centre| = R
    # (the seed grid's last crossings inside lie up to one cell, 1/48 of the domain, short of it)
    assert_allclose(r, R, atol=1e-8)


def test_sampled_curve_inflections_are_root_found():
    """y = sin x sampled at 13 points: the inflection at pi is root-found on the quintic Hermite
    interpolant of the samples (points, first and second derivatives), far closer than linear
    interpolation of the curvature between samples, and to 1e-12 on the exact derivatives."""
    t = np.linspace(0.3, 5.9, 13)
    P = np.c_[t, np.sin(t), 0 * t]
    d1 = np.c_[1 + 0 * t, np.cos(t), 0 * t]
    d2 = np.c_[0 * t, -np.sin(t), 0 * t]
    cb = curvature_comb(SampledCurve(t, P, d1, d2), plane_normal=[0, 0, 1])
    assert cb.n_inflections == 1
    err = abs(cb.inflection_params[0] - np.pi)
    i = np.searchsorted(t, np.pi) - 1
    ks = -np.sin(t) / (1 + np.cos(t) ** 2) ** 1.5
    linear = t[i] + ks[i] / (ks[i] - ks[i + 1]) * (t[i + 1] - t[i])
    assert err < 1e-5 and err < 1e-2 * abs(linear - np.pi)
    assert_allclose(cb.inflection_points[0], [cb.inflection_params[0], np.sin(cb.inflection_params[0]), 0], atol=1e-5)

    def exact(x):
        x = np.asarray(x, float)
        return np.stack((np.c_[x, np.sin(x), 0 * x], np.c_[1 + 0 * x, np.cos(x), 0 * x],
                         np.c_[0 * x, -np.sin(x), 0 * x]), axis=1)

    cb = curvature_comb(SampledCurve(t, P, d1, d2, derivatives=exact), plane_normal=[0, 0, 1])
    assert_allclose(cb.inflection_params, [np.pi], atol=1e-11)
    assert_allclose(cb.inflection_points, [[np.pi, 0, 0]], atol=1e-11)
    with pytest.raises(InvalidGeometryError, match="derivatives"):
        curvature_comb(SampledCurve(t, P, d1, d2, derivatives=lambda x: np.zeros((len(x), 3))), plane_normal=[0, 0, 1])


def test_cut_of_a_plane_has_no_comb_noise():
    """A tilted plane's cuts are straight: round-off curvature (1e-13) must not be blown up into a
    full-size comb (the default scale makes the largest spine 20 % of the extent)."""
    from occsurf.algorithms import BSplineSurface

    g = np.linspace(0, 1, 5)
    X, Y = np.meshgrid(g, g, indexing="ij")
    net = np.stack([X * np.cos(0.3) + 0.1 * Y, Y, 0.37 * X + 0.21 * Y], -1)
    s = BSplineSurface((3, 3), (np.r_[0, 0, 0, 0, 0.5, 1, 1, 1, 1],) * 2, net)
    for sec in plane_sections([s], [0, 0, 0], [0.3, 0.8, 0.1], [0.2, 0.4, 0.6]):
        for c in sec.curves:
            assert np.max(np.abs(c.curvature)) < 1e-9
            assert_allclose(c.comb.tips, c.comb.points, atol=0)
