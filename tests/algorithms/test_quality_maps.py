"""Curvature maps and colour scales (occsurf.algorithms.quality.curvature_maps).

Oracles: sphere (k1 = k2 = 1/R up to the sign of the normal, poles degenerate), cylinder (1/R, 0),
torus (K = cos(theta) / (r (a + r cos(theta)))), all exact NURBS by revolution; the hierarchical
surface and the S-patch against their own scattered derivatives through surface_curvatures'
formulas. Invariants (hypothesis): rigid motions and knot insertion leave the maps unchanged.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import example, given
from hypothesis import strategies as st
from numpy.testing import assert_allclose

from occsurf.algorithms import BSplineCurve, BSplineSurface, arc, circle, tolerances
from occsurf.algorithms.construction import revolve
from occsurf.algorithms.errors import InvalidGeometryError, ParameterError
from occsurf.algorithms.geometry import curvatures_from_derivatives, surface_curvatures
from occsurf.algorithms.hierarchical import HierarchicalSurface
from occsurf.algorithms.quality import KINDS, color_scale, curvature_map, curvature_values
from occsurf.algorithms.topology import SPatch, generalized_biquadratic

from .strategies import surfaces, test_settings

SETTINGS = test_settings(25)
R = 2.0


def sphere(radius: float = R) -> BSplineSurface:
    prof = arc([0, 0, 0], radius, -np.pi / 2, np.pi / 2, normal=[0, -1, 0], xaxis=[1, 0, 0])
    return revolve(prof, [0, 0, 0], [0, 0, 1])


def cylinder(radius: float = R, height: float = 3.0) -> BSplineSurface:
    return revolve(BSplineCurve(1, [0, 0, 1, 1], [[radius, 0, 0], [radius, 0, height]]), [0, 0, 0], [0, 0, 1])


def torus(a: float = 3.0, r: float = 1.0) -> BSplineSurface:
    return revolve(circle([a, 0, 0], r, normal=[0, 1, 0]), [0, 0, 0], [0, 0, 1])


def wavy(n: int = 7, seed: int = 0) -> BSplineSurface:
    rng = np.random.default_rng(seed)
    g = np.linspace(0, 1, n)
    P = np.stack(np.meshgrid(g * 4, g * 4, indexing="ij"), -1)
    P = np.concatenate((P, rng.normal(scale=0.3, size=(n, n, 1))), -1)
    U = np.r_[0, 0, 0, 0, np.linspace(0, 1, n - 2)[1:-1], 1, 1, 1, 1]
    return BSplineSurface((3, 3), (U, U), P)


# --------------------------------------------------------------------------------- closed forms
def test_sphere_curvature_and_poles_degenerate():
    s = sphere()
    cm = curvature_map(s, 41, 40, "mean")
    # the sign follows the normal S_u x S_v: this revolution has inward normals, so H = +1/R
    sign = np.sign(np.nanmean(cm.mean))
    ok = ~cm.degenerate
    assert_allclose(cm.k1[ok], sign / R, atol=1e-12)
    assert_allclose(cm.k2[ok], sign / R, atol=1e-12)
    assert_allclose(cm.gaussian[ok], 1 / R**2, atol=1e-12)
    assert_allclose(cm.values[ok], sign / R, atol=1e-12)
    # the first and last u rows are the poles: degenerate, NaN-valued, counted, never silent
    assert cm.degenerate[0].all() and cm.degenerate[-1].all()
    assert cm.n_degenerate == 2 * 40
    assert np.isnan(cm.values[cm.degenerate]).all()
    assert_allclose(np.abs(cm.degenerate_points[:, 2]), R, atol=1e-12)
    # a degenerate point still gets a limit normal (for rendering), pointing along -+z
    assert_allclose(np.abs(cm.normals[cm.degenerate][:, 2]), 1.0, atol=1e-6)
    assert np.isfinite(cm.normals).all()
    assert_allclose(cm.values_of("radius")[ok], R, rtol=1e-12)
    assert_allclose(cm.values_of("absolute")[ok], 2 / R, rtol=1e-12)


def test_cylinder_principal_curvatures():
    cm = curvature_map(cylinder(), 17, 9, "max")
    k1, k2 = cm.k1, cm.k2
    # inward normals (|k1| = 1/R is the max) and the rulings are straight
    assert_allclose(np.maximum(np.abs(k1), np.abs(k2)), 1 / R, atol=1e-12)
    assert_allclose(np.minimum(np.abs(k1), np.abs(k2)), 0.0, atol=1e-12)
    assert_allclose(cm.gaussian, 0.0, atol=1e-12)
    assert cm.n_degenerate == 0
    assert_allclose(cm.values_of("radius"), R, rtol=1e-12)


def test_torus_gaussian_formula():
    a, r = 3.0, 1.0
    cm = curvature_map(torus(a, r), 33, 29, "gaussian")
    th = np.arctan2(cm.points[..., 2], np.hypot(cm.points[..., 0], cm.points[..., 1]) - a)
    assert_allclose(cm.values, np.cos(th) / (r * (a + r * np.cos(th))), atol=1e-12)
    # mean curvature magnitude (a + 2 r cos) / (2 r (a + r cos))
    H = (a + 2 * r * np.cos(th)) / (2 * r * (a + r * np.cos(th)))
    assert_allclose(np.abs(cm.mean), H, atol=1e-12)


def test_plane_radius_is_infinite_and_flat_threshold_is_a_tolerance():
    g = np.linspace(0, 1, 3)
    P = np.stack([*np.meshgrid(g, g, indexing="ij"), np.zeros((3, 3))], -1)
    s = BSplineSurface((2, 2), ([0, 0, 0, 1, 1, 1],) * 2, P)
    cm = curvature_map(s, 5, 5, "radius")
    assert np.isinf(cm.values).all()
    # a tiny bend is flat by the default threshold; tightening the tolerance makes it curved
    P2 = P.copy()
    P2[1, 1, 2] = 1e-12
    s2 = BSplineSurface((2, 2), ([0, 0, 0, 1, 1, 1],) * 2, P2)
    assert np.isinf(curvature_map(s2, 5, 5, "radius").values[2, 2])
    with tolerances.override(QUALITY_FLAT_CURVATURE=1e-15):
        assert np.isfinite(curvature_map(s2, 5, 5, "radius").values[2, 2])


def test_all_kinds_consistent():
    s = wavy()
    base = curvature_map(s, 12, 13, "mean")
    for kind in KINDS:
        cm = curvature_map(s, 12, 13, kind)
        assert cm.kind == kind
        assert_allclose(cm.values, base.values_of(kind), rtol=1e-14, atol=1e-14)
        assert_allclose(base.with_kind(kind).values, cm.values)
    assert_allclose(curvature_map(s, 12, 13, "max").values, base.k1)
    assert_allclose(curvature_map(s, 12, 13, "min").values, base.k2)
    assert np.all(base.k1 >= base.k2)


def test_matches_surface_curvatures_on_explicit_params():
    s = wavy(8, 3)
    us, vs = np.linspace(0, 1, 9), np.linspace(0.1, 0.9, 7)
    cm = curvature_map(s, us, vs, "gaussian")
    U, V = np.meshgrid(us, vs, indexing="ij")
    ref = surface_curvatures(s, U, V)
    assert_allclose(cm.k1, ref.k1, rtol=1e-11, atol=1e-12)
    assert_allclose(cm.gaussian, ref.gaussian, rtol=1e-11, atol=1e-12)
    assert_allclose(cm.normals, ref.normal, atol=1e-12)
    assert_allclose(cm.points, s.evaluate(U, V), atol=1e-12)


@pytest.mark.slow
def test_rational_surface_and_large_grid_blocks():
    """A grid larger than one row block goes through the blocked path with the same answer."""
    s = torus()
    us, vs = np.linspace(0, 2 * np.pi, 301), np.linspace(0, 2 * np.pi, 257)
    cm = curvature_map(s, us, vs, "mean")
    U, V = np.meshgrid(us, vs, indexing="ij")
    ref = surface_curvatures(s, U, V)
    assert_allclose(cm.mean, ref.mean, rtol=1e-10, atol=1e-12)


@pytest.mark.parametrize("make", [wavy, torus, sphere])
def test_fused_kernel_matches_numpy_path(make, monkeypatch):
    """The optional numba kernel (quality/_kernels.py) and the NumPy path agree to round-off."""
    pytest.importorskip("numba")
    s = make()
    (u0, u1), (v0, v1) = s.domain
    us, vs = np.linspace(u0, u1, 37), np.linspace(v0, v1, 29)
    m = np.ones((37, 29), bool)
    m[:3] = False
    with tolerances.override(NUMBA_MIN_POINTS=16):
        fused = curvature_map(s, us, vs, "gaussian")
        fused_m = curvature_map(s, us, vs, "gaussian", mask=m)
    monkeypatch.setenv("OCCSURF_NO_NUMBA", "1")
    ref = curvature_map(s, us, vs, "gaussian")
    ref_m = curvature_map(s, us, vs, "gaussian", mask=m)
    # limit normals at poles come from derivatives 1e-7 inside the domain: ~1e-9 round-off there
    assert_allclose(fused.normals[ref.degenerate], ref.normals[ref.degenerate], atol=1e-8)
    for x in (fused, ref, fused_m, ref_m):
        object.__setattr__(x, "normals", np.where(x.degenerate[..., None], 0.0, x.normals))
    for f in ("points", "normals", "k1", "k2", "gaussian", "mean", "values"):
        a, b = getattr(fused, f), getattr(ref, f)
        assert_allclose(a, b, rtol=1e-12, atol=1e-12 * (1 + np.nanmax(np.abs(b))), equal_nan=True, err_msg=f)
        assert_allclose(getattr(fused_m, f), getattr(ref_m, f), rtol=1e-12, atol=1e-12 * (1 + np.nanmax(np.abs(b))),
                        equal_nan=True, err_msg=f)
    assert (fused.degenerate == ref.degenerate).all() and (fused_m.mask == ref_m.mask).all()


def test_trimmed_face_mask():
    s = wavy()
    m = np.zeros((10, 11), bool)
    m[2:7, 3:9] = True
    cm = curvature_map(s, 10, 11, "mean", mask=m)
    assert np.isnan(cm.values[~m]).all() and np.isfinite(cm.values[m]).all()
    assert np.isnan(cm.points[~m]).all()
    assert not cm.degenerate[~m].any()
    assert_allclose(cm.values[m], curvature_map(s, 10, 11, "mean").values[m])


def test_hierarchical_surface_uses_its_own_evaluation():
    hs = HierarchicalSurface(wavy(8, 1))
    o = hs.add_overlay((0.2, 0.8), (0.2, 0.8))
    hs.move_vertex(o, (3, 3), [0.0, 0.0, 0.4])
    cm = curvature_map(hs, 15, 16, "gaussian")
    flat = hs.flatten()
    ref = curvature_map(flat, 15, 16, "gaussian")
    assert_allclose(cm.values, ref.values, rtol=1e-9, atol=1e-10)
    # and the edit changed the curvature (so the overlay was evaluated)
    assert np.nanmax(np.abs(cm.values - curvature_map(wavy(8, 1), 15, 16, "gaussian").values)) > 1e-3


def test_spatch_and_generalized_surface():
    rng = np.random.default_rng(5)
    from occsurf.algorithms.topology import spatch_indices

    n, d = 5, 3
    idx = spatch_indices(n, d)
    P = rng.normal(scale=0.1, size=(idx.shape[0], 3))
    P[:, :2] += idx[:, :2] * 0.3  # a gently curved sheet
    patch = SPatch(n, d, P)
    cm = curvature_map(patch, np.linspace(-1, 1, 21), np.linspace(-1, 1, 21), "gaussian")
    assert 0 < cm.mask.sum() < 21 * 21  # the corners of the box lie outside the pentagon
    X, Y = np.meshgrid(cm.us, cm.vs, indexing="ij")
    pts = np.stack((X[cm.mask], Y[cm.mask]), -1)
    ref = curvatures_from_derivatives(patch.derivatives(pts, 2))
    assert_allclose(cm.values[cm.mask], ref.gaussian, rtol=1e-12, atol=1e-12)
    assert np.isnan(cm.values[~cm.mask]).all()
    with pytest.raises(InvalidGeometryError, match="patch"):
        curvature_map(patch, 5, 5, patch=0)


def test_generalized_surface_needs_patch():
    from .test_generalized import ngon_with_skirt

    gs = generalized_biquadratic(ngon_with_skirt(5, np.random.default_rng(2)))
    with pytest.raises(InvalidGeometryError, match="patch"):
        curvature_map(gs, 5, 5)
    cm = curvature_map(gs, np.linspace(-1, 1, 9), np.linspace(-1, 1, 9), "mean", patch=0)
    assert np.isfinite(cm.values[cm.mask]).all()


# ---------------------------------------------------------------------------------- invariants
def well_conditioned(s: BSplineSurface, us: np.ndarray, vs: np.ndarray) -> np.ndarray:
    """Grid points where the curvature is a well-conditioned function of the net: the partials are
    not tiny and not nearly parallel (random nets can fold; there every method loses digits)."""
    D = s.derivatives_grid(us, vs, 1)
    su, sv = D[..., 1, 0, :], D[..., 0, 1, :]
    lu, lv = np.linalg.norm(su, axis=-1), np.linalg.norm(sv, axis=-1)
    sine = np.linalg.norm(np.cross(su, sv), axis=-1) / np.maximum(lu * lv, 1e-300)
    return (sine > 0.05) & (np.minimum(lu, lv) > 1e-2)


def roundoff_floor(s: BSplineSurface, us: np.ndarray, vs: np.ndarray, size: float) -> np.ndarray:
    """First-order round-off bound of the principal curvatures of ``s`` placed at coordinates of
    magnitude ``size`` (its poles plus a rigid motion's shift).

    Partials computed from coordinates of magnitude ``size`` carry errors of about ``eps * size``
    times their own scale ``m = max(|S_u|, |S_v|, |S_2|)`` even where the exact value is 0 (a flat net
    moved off its plane gets normal-direction partials of round-off size). The second fundamental
    form errs by that much, and the shape operator divides by the first form, whose smallest
    eigenvalue is at least ``|S_u x S_v|^2 / (|S_u|^2 + |S_v|^2)``. The factor 64 covers the
    operations between; rational nets multiply by max w / min w (the quotient rule). Measured on
    the case CI found (:func:`_flat_net_found_by_ci`): 2.8e-8 against a bound of 2.3e-7.
    """
    eps = np.finfo(float).eps
    D = s.derivatives_grid(us, vs, 2)
    su, sv = D[..., 1, 0, :], D[..., 0, 1, :]
    lu, lv = np.linalg.norm(su, axis=-1), np.linalg.norm(sv, axis=-1)
    cross2 = np.linalg.norm(np.cross(su, sv), axis=-1) ** 2
    m2 = np.max(np.linalg.norm(np.stack([D[..., 2, 0, :], D[..., 1, 1, :], D[..., 0, 2, :]]), axis=-1), axis=0)
    w = s.weights
    ratio = 1.0 if w is None else float(np.max(w) / np.min(w))
    # folded points (cross2 0 or subnormal): inf, and outside ``ok`` anyway (sine > 0.05 and |S_u|,
    # |S_v| > 1e-2 there keep cross2 above 2.5e-11); the overflow of a subnormal cross2 warned in CI85
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        return 64.0 * ratio * eps * size * np.maximum.reduce([m2, lu, lv]) * (lu**2 + lv**2) / cross2


def _flat_net_found_by_ci() -> BSplineSurface:
    """A flat net (z = 0) with |S_u| = 0.012 and sin(S_u, S_v) = 0.055 at a grid point: moved to z = 1,
    its k1 there is 2.8e-8 of round-off (CI's hypothesis run found it), inside :func:`roundoff_floor`."""
    P = np.zeros((6, 5, 3))
    P[0, 0, 1], P[0, 1, 0], P[2, 0, 1], P[4, 0, 1] = 1.5, 4.0, 1.4375, 1.203125
    return BSplineSurface((4, 2), (np.array([2, 2, 2.5, 2.5, 2.5, 4, 4, 4, 4, 5, 6.0]),
                                   np.array([1, 1, 1, 1.95, 2.95, 3.95, 4.95, 5.95])), P)


@given(s=surfaces(dims=st.just(3), degrees=st.integers(2, 4)), angles=st.tuples(*[st.floats(-3, 3)] * 3),
       shift=st.tuples(*[st.floats(-5, 5)] * 3))
@example(s=_flat_net_found_by_ci(), angles=(0.0, 0.0, 0.0), shift=(0.0, 0.0, 1.0))
@SETTINGS
def test_rigid_motion_leaves_map_unchanged(s, angles, shift):
    from scipy.spatial.transform import Rotation

    Q = Rotation.from_euler("xyz", angles).as_matrix()
    a = curvature_map(s, 7, 6, "gaussian")
    b = curvature_map(s.transform(Q, shift), 7, 6, "gaussian")
    assert_allclose(b.points, a.points @ Q.T + shift, atol=1e-9)
    ok = well_conditioned(s, a.us, a.vs)
    kmax = 1 + np.nanmax(np.abs(a.k1[ok]), initial=0) + np.nanmax(np.abs(a.k2[ok]), initial=0)
    # the motion's shift raises the coordinates' size and with it the partials' round-off
    floor = roundoff_floor(s, a.us, a.vs, float(np.abs(s.control_points).max()) + float(np.linalg.norm(shift)))[ok]
    for name in ("k1", "k2"):  # assert_allclose's rtol 1e-7 kept; its atol per point
        x, y = getattr(b, name)[ok], getattr(a, name)[ok]
        bad = np.abs(x - y) > 1e-8 * kmax + floor + 1e-7 * np.abs(y)
        assert not bad.any(), (name, x[bad], y[bad], floor[bad])
    assert_allclose(b.values[ok], a.values[ok], atol=1e-8 * kmax**2 + 2 * kmax * floor.max(initial=0))


def _nearly_collapsed_net_found_by_ci() -> BSplineSurface:
    """CI19 (2026-12-07): every pole at (7.3125, 7.3125, 7.3125) but two; at one grid point the
    mean curvature before and after the insertion differed by 1.9e-8 (its round-off bound
    :func:`roundoff_floor` 2.5e-8, against 1.5e-10..3.5e-10 at the others)."""
    P = np.full((7, 5, 3), 7.3125)
    P[1, 4, 0], P[4, 3, 1] = 9.0, 7.25
    return BSplineSurface((3, 2), (np.array([2, 3, 3, 5, 5, 6.75, 6.75, 6.75, 7.75, 8.75, 9.75]),
                                   np.array([2, 3, 4, 6, 9.125, 10.21875, 10.21875, 10.21875])), P)


def _full_knot_at_the_middle_found_by_ci() -> BSplineSurface:
    """CI19: the middle of the u domain [4, 6] is a knot of multiplicity 2 = the degree."""
    return BSplineSurface((2, 2), (np.array([2.0, 3, 4, 5, 5, 6, 6, 7, 8]), np.array([2.0, 3, 4, 5, 6, 7])),
                          np.zeros((6, 3, 3)))


@given(s=surfaces(dims=st.just(3), degrees=st.integers(2, 4), rational=False), t=st.floats(0.05, 0.95))
@example(s=_nearly_collapsed_net_found_by_ci(), t=0.5)
@example(s=_full_knot_at_the_middle_found_by_ci(), t=0.5)
@SETTINGS
def test_knot_insertion_leaves_map_unchanged(s, t):
    (u0, u1), _ = s.domain
    u = u0 + t * (u1 - u0)
    try:
        s2 = s.insert_knot(u, direction="u")
    except InvalidGeometryError as err:  # a knot of full multiplicity there already: refused by name
        assert "exceeds the degree" in str(err)
        assert np.count_nonzero(np.abs(s.knots[0] - u) <= 1e-12 * (u1 - u0)) >= s.degree[0]
        return
    a, b = curvature_map(s, 6, 7, "mean"), curvature_map(s2, 6, 7, "mean")
    ok = well_conditioned(s, a.us, a.vs)
    assert_allclose(b.points, a.points, atol=1e-9)
    kmax = 1 + np.nanmax(np.abs(a.k1[ok]), initial=0) + np.nanmax(np.abs(a.k2[ok]), initial=0)
    # per point, the curvatures' round-off bound as for the rigid motion above (the mean curvature
    # errs by at most the principal curvatures' bound): a nearly collapsed net loses digits there
    floor = roundoff_floor(s, a.us, a.vs, float(np.abs(s.control_points).max()))[ok]
    x, y = b.values[ok], a.values[ok]
    bad = np.abs(x - y) > 1e-8 * kmax + floor + 1e-7 * np.abs(y)
    assert not bad.any(), (x[bad], y[bad], floor[bad])


# -------------------------------------------------------------------------------- colour scales
def test_color_scale_modes():
    v = np.r_[np.linspace(-1, 3, 1000), 500.0, np.nan, np.inf]
    lin = color_scale(v, "linear")
    assert (lin.lo, lin.hi) == (-1.0, 500.0)
    cl = color_scale(v, "clipped")
    assert -1 < cl.lo < -0.8 and 2.8 < cl.hi < 3.0 and cl.n_above > 0
    sy = color_scale(v, "symmetric")
    assert sy.lo == -sy.hi and 2.8 < sy.hi < 3.0
    t = sy.normalize(v)
    assert np.isnan(t[-2]) and t[-1] == 1.0 and t[-3] == 1.0
    assert 0 <= np.nanmin(t) and np.nanmax(t) <= 1
    assert_allclose(sy.normalize(0.0), 0.5)
    assert_allclose(sy.legend_ticks(5), np.linspace(sy.lo, sy.hi, 5))
    assert sy.legend_ticks(5)[2] == 0.0
    fixed = color_scale(v, "linear", lo=0, hi=2)
    assert_allclose(fixed.normalize([1.0, -5, 7]), [0.5, 0, 1])


def test_color_scale_all_nan_and_constant():
    cs = color_scale([np.nan, np.nan])
    assert cs.lo == cs.hi == 0.0
    assert np.isnan(cs.normalize([np.nan]))[0] and cs.normalize([0.0])[0] == 0.5
    c2 = color_scale(np.full(5, 0.3), "linear")
    assert_allclose(c2.normalize([0.3]), 0.5)


def test_curvature_values_direct():
    k1, k2 = np.array([1.0, 0.0, -2.0]), np.array([-1.0, 0.0, -3.0])
    assert_allclose(curvature_values("gaussian", k1, k2), [-1, 0, 6])
    assert_allclose(curvature_values("absolute", k1, k2), [2, 0, 5])
    assert_allclose(curvature_values("radius", k1, k2), [1, np.inf, 1 / 3])


# ----------------------------------------------------------------------------------- bad input
def test_bad_input_messages():
    s = wavy()
    with pytest.raises(InvalidGeometryError, match="kind"):
        curvature_map(s, 5, 5, "bogus")
    with pytest.raises(InvalidGeometryError, match="mask"):
        curvature_map(s, 5, 5, mask=np.ones((4, 5), bool))
    with pytest.raises(InvalidGeometryError, match="surface"):
        curvature_map("not a surface", 5, 5)
    with pytest.raises(ParameterError):
        curvature_map(s, [0.0, 2.0], 5)
    with pytest.raises(InvalidGeometryError, match="us"):
        curvature_map(s, 1, 5)
    flat2d = BSplineSurface((1, 1), ([0, 0, 1, 1],) * 2, np.zeros((2, 2, 2)))
    with pytest.raises(InvalidGeometryError, match="3-D"):
        curvature_map(flat2d, 3, 3)
    with pytest.raises(InvalidGeometryError, match="mode"):
        color_scale([1.0], "log")
    with pytest.raises(InvalidGeometryError, match="percentile"):
        color_scale([1.0], percentile=(90, 10))
    with pytest.raises(InvalidGeometryError, match="lo, hi"):
        color_scale([1.0], lo=2, hi=1)
    with pytest.raises(InvalidGeometryError, match="n:"):
        color_scale([1.0, 2.0]).legend_ticks(1)
