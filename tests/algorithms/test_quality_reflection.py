"""Reflection lines, isophotes, highlight lines, draft angles, hedgehogs and normal flips
(occsurf.algorithms.quality.reflection / normals).

Closed forms: the zebra of a plane is straight, evenly spaced stripes; a cylinder's stripes are
straight along the rulings; isophotes of a sphere are circles about the light direction; the
highlight line of a cylinder under a light parallel to its axis is the ruling facing it; the draft
of a vertical wall is 0 and of a 5-degree cone wall is 5.
"""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose

from occsurf.algorithms import tolerances
from occsurf.algorithms.errors import InvalidGeometryError
from occsurf.algorithms.quality import (
    DRAFT_INSUFFICIENT,
    DRAFT_OK,
    DRAFT_UNDEFINED,
    DRAFT_UNDERCUT,
    classify_draft,
    curvature_map,
    draft_angle,
    highlight_lines,
    isophotes,
    normal_flips,
    normal_hedgehog,
    zebra,
)

from .test_quality_maps import cylinder, sphere


def plane_grid(n: int = 21):
    g = np.linspace(-1, 1, n)
    X, Y = np.meshgrid(g, g, indexing="ij")
    P = np.stack((X, Y, np.zeros_like(X)), -1)
    return P, np.broadcast_to([0.0, 0.0, 1.0], P.shape)


def test_zebra_of_a_plane_is_straight_even_stripes():
    P, N = plane_grid()
    z = zebra(P, N, [0.3, 0.2, -1.0], stripe_dir=[0, 1, 0], width=0.25)
    # the stripe coordinate is affine in x (orthographic view): constant along y, even steps in x
    s = z.coordinate
    assert_allclose(s, s[:, :1] * np.ones_like(s), atol=1e-12)
    d = np.diff(s[:, 0])
    assert_allclose(d, d[0], rtol=1e-12) and abs(d[0]) > 0
    assert z.hit.all() and ((0 <= z.phase) & (z.phase < 1)).all()
    assert_allclose(z.phase, np.mod(s / 0.25, 1.0))
    assert (z.stripe == (z.phase < 0.5)).all()


def test_zebra_plane_perspective_stripes_are_straight_lines():
    P, N = plane_grid(9)
    eye = np.array([0.4, -0.3, 3.0])
    z = zebra(P, N, P - eye, stripe_dir=[0, 1, 0], width=0.3, distance=5.0)
    # level sets of the coordinate on a plane are lines: the coordinate is a ratio of affine functions
    # of (x, y), i.e. s (c0 + c1 x + c2 y) = a0 + a1 x + a2 y; fit and check the residual
    x, y, s = P[..., 0].ravel(), P[..., 1].ravel(), z.coordinate.ravel()
    A = np.c_[np.ones_like(x), x, y, -s * x, -s * y]
    coef, *_ = np.linalg.lstsq(A, s, rcond=None)
    assert np.max(np.abs(A @ coef - s)) < 1e-9


def test_zebra_cylinder_stripes_follow_rulings_and_width_setting():
    cm = curvature_map(cylinder(), 24, 12, "mean")
    z1 = zebra(cm.points, cm.normals, [1.0, 0.0, 0.0], stripe_dir=[0, 0, 1], width=0.5, distance=10.0)
    # along a ruling (u here: the revolved line; the axis z) the normal is constant: same coordinate
    ok = z1.hit
    assert ok.sum() > 20
    cols = ok.all(axis=0)  # rulings whose reflected rays all reach the light plane
    assert cols.sum() >= 3
    c = z1.coordinate[:, cols]
    assert np.max(c.max(axis=0) - c.min(axis=0)) < 1e-9
    z2 = zebra(cm.points, cm.normals, [1.0, 0.0, 0.0], stripe_dir=[0, 0, 1], width=0.25, distance=10.0)
    assert_allclose(z2.coordinate[ok], z1.coordinate[ok])
    assert_allclose(z2.phase[ok], np.mod(z1.coordinate[ok] / 0.25, 1.0))


def test_zebra_nan_normals_and_bad_input():
    P, N = plane_grid(3)
    N = np.array(N)
    N[0, 0] = np.nan
    z = zebra(P, N, [0, 0, -1.0], stripe_dir=[0, 1, 0])
    assert np.isnan(z.phase[0, 0]) and not z.stripe[0, 0] and not z.hit[0, 0]
    with pytest.raises(InvalidGeometryError, match="parallel"):
        zebra(P, N, [0, 0, -1.0], stripe_dir=[0, 0, 1])
    with pytest.raises(InvalidGeometryError, match="view_dir"):
        zebra(P, N, [0, 0, 0])
    with pytest.raises(InvalidGeometryError, match="width"):
        zebra(P, N, [0, 0, -1.0], stripe_dir=[0, 1, 0], width=-1)
    with pytest.raises(InvalidGeometryError, match="points"):
        zebra(P[..., :2], N, [0, 0, -1.0])


def test_isophotes_of_a_sphere_are_circles_about_the_light():
    cm = curvature_map(sphere(), 30, 30, "mean")
    light = np.array([0.0, 0.0, 1.0])
    iso = isophotes(cm.normals, light, [-0.5, 0.0, 0.5])
    # n = -+x/R: the intensity is the height on the sphere (up to the normal's sign)
    assert_allclose(np.abs(iso.intensity), np.abs(cm.points[..., 2]) / 2.0, atol=1e-6)
    assert set(np.unique(iso.band)) <= {0, 1, 2, 3}
    iso2 = isophotes(cm.normals, [0, 0, 5.0], 5)
    assert iso2.levels.size == 5 and np.all(np.diff(iso2.levels) > 0)
    with pytest.raises(InvalidGeometryError, match="levels"):
        isophotes(cm.normals, light, [2.0])


def test_highlight_line_on_a_cylinder():
    cm = curvature_map(cylinder(), 73, 5, "mean")
    # light line parallel to the axis through (5, 0, *): the normal line of the ruling at +x meets it
    d = highlight_lines(cm.points, cm.normals, [5.0, 0.0, 0.0], [0, 0, 1])
    ang = np.arctan2(cm.points[..., 1], cm.points[..., 0])
    # normal lines of the cylinder all pass through the axis; distance to a parallel line at
    # distance 5 from the axis is 5 |sin(phi)|
    assert_allclose(np.abs(d), 5 * np.abs(np.sin(ang)), atol=1e-9)
    i0 = np.argmin(np.abs(ang[:, 0]))
    assert abs(d[i0, 0]) < 1e-9
    # a light parallel to the normals gives NaN, not a number
    assert np.isnan(highlight_lines([[0, 0, 0.0]], [[0, 0, 1.0]], [1, 0, 0], [0, 0, 1])).all()


def test_draft_angles():
    assert_allclose(draft_angle([[1, 0, 0], [0, 1, 0]], [0, 0, 1]), 0.0, atol=1e-12)
    assert_allclose(draft_angle([[0, 0, 2.0], [0, 0, -1.0]], [0, 0, 1]), [90, -90])
    # a cone wall opening 5 degrees towards +z: outward normal (cos 5, 0, sin 5)
    a = np.radians(5)
    assert_allclose(draft_angle([np.cos(a), 0, np.sin(a)], [0, 0, 1]), 5.0, atol=1e-12)
    # vertical wall of a real surface: the cylinder
    cm = curvature_map(cylinder(), 9, 4, "mean")
    assert_allclose(draft_angle(cm.normals, [0, 0, 1]), 0.0, atol=1e-12)
    ang = np.array([5.0, 0.5, -0.5, -3.0, np.nan])
    assert list(classify_draft(ang, 1.0)) == [DRAFT_OK, DRAFT_INSUFFICIENT, DRAFT_INSUFFICIENT, DRAFT_UNDERCUT,
                                              DRAFT_UNDEFINED]
    with tolerances.override(QUALITY_MIN_DRAFT_DEG=0.25):
        assert list(classify_draft(ang)) == [DRAFT_OK, DRAFT_OK, DRAFT_UNDERCUT, DRAFT_UNDERCUT, DRAFT_UNDEFINED]
    with pytest.raises(InvalidGeometryError, match="min_draft"):
        classify_draft(ang, -1)
    with pytest.raises(InvalidGeometryError, match="pull_direction"):
        draft_angle([[1, 0, 0]], [0, 0, 0])


def test_hedgehog_and_flips():
    s = sphere()
    P, T = normal_hedgehog(s, 9, 8, 0.5)
    assert_allclose(np.linalg.norm(T - P, axis=-1), 0.5, rtol=1e-9)
    # spines are radial on a sphere (inward for this parametrisation), also at the poles
    radial = (T - P) / 0.5
    assert_allclose(np.abs(np.einsum("...i,...i", radial, P / 2.0)), 1.0, atol=1e-6)
    P2, T2 = normal_hedgehog(cylinder(), 5, 5)
    assert np.isfinite(T2).all()
    n = np.array([[0, 0, 1.0], [0, 0, 1.0], [0, 0, 1.0]])
    m = np.array([[0, 0, 1.0], [0, np.sin(0.1), np.cos(0.1)], [0, 0.1, -1.0]])
    flipped, ang = normal_flips(n, m)
    assert list(flipped) == [False, False, True]
    assert_allclose(ang[:2], [0, np.degrees(0.1)], atol=1e-12)
    with pytest.raises(InvalidGeometryError, match="normals_b"):
        normal_flips(n, m[:2])


def test_per_pixel_shapes_broadcast():
    """Indicators take any leading shape (a (H, W) normal buffer of a renderer)."""
    rng = np.random.default_rng(1)
    N = rng.normal(size=(4, 5, 6, 3))
    P = rng.normal(size=(4, 5, 6, 3))
    assert zebra(P, N, [0, 0, -1.0], stripe_dir=[0, 1, 0], width=0.3, distance=4.0).phase.shape == (4, 5, 6)
    assert isophotes(N, [0, 0, 1.0], 4).band.shape == (4, 5, 6)
    assert highlight_lines(P, N, [0, 0, 0], [1, 0, 0]).shape == (4, 5, 6)
    assert draft_angle(N, [0, 0, 1]).shape == (4, 5, 6)
    # per-pixel results equal per-vertex ones
    z1 = zebra(P, N, [0, 0, -1.0], stripe_dir=[0, 1, 0], width=0.3, distance=4.0)
    z2 = zebra(P.reshape(-1, 3), N.reshape(-1, 3), [0, 0, -1.0], stripe_dir=[0, 1, 0], width=0.3, distance=4.0)
    assert_allclose(z1.phase.ravel(), z2.phase, equal_nan=True)


def test_hedgehog_on_hierarchical_and_spatch():
    from occsurf.algorithms.hierarchical import HierarchicalSurface
    from occsurf.algorithms.topology import SPatch, spatch_indices

    from .test_quality_maps import wavy

    hs = HierarchicalSurface(wavy(8, 2))
    P, T = normal_hedgehog(hs, 6, 7, 0.1)
    ref = curvature_map(hs.flatten(), 6, 7)
    assert_allclose((T - P) / 0.1, ref.normals, atol=1e-9)
    idx = spatch_indices(4, 2)
    net = np.c_[idx[:, :2] * 0.5, np.zeros(idx.shape[0])]
    patch = SPatch(4, 2, net)
    P2, T2 = normal_hedgehog(patch, np.linspace(-1, 1, 9), np.linspace(-1, 1, 9), 1.0)
    inside = np.isfinite(P2[..., 0])
    assert inside.sum() > 20
    assert_allclose(np.abs((T2 - P2)[inside][:, 2]), 1.0, atol=1e-12)  # a flat patch: normals along z
