"""Hierarchical B-spline surfaces with offset referencing (course ch. 5, Forsey–Bartels).

Invariants (hypothesis): creating overlays never changes the surface; flatten() is the same
surface; coarse edits carry details along. Oracles: refinement by BSplineSurface.refine, frames
by explicit cross products, rigid motions. Round trips: to_dict -> JSON -> from_dict.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from numpy.testing import assert_allclose

from occsurf.algorithms import BSplineSurface, tolerances
from occsurf.algorithms.errors import InvalidGeometryError, ParameterError
from occsurf.algorithms.hierarchical.offsets import (
    ADDITIVE_OFFSETS,
    FRAME_OFFSETS,
    OffsetMapping,
    register_offset_mapping,
)
from occsurf.algorithms.hierarchical.surface import HierarchicalSurface, Overlay
from occsurf.algorithms.manipulation.linalg import ConstraintError
from occsurf.algorithms.manipulation.surfaces import drag_surface_point
from tests.algorithms.strategies import surfaces, test_settings

_float = dict(allow_nan=False, allow_infinity=False, allow_subnormal=False)


def smooth_base(n: int = 7, size: float = 6.0, z: np.ndarray | None = None, knots=None) -> BSplineSurface:
    g = np.linspace(0.0, size, n)
    X, Y = np.meshgrid(g, g, indexing="ij")
    Z = 0.4 * np.sin(X / 2.0) * np.cos(Y / 2.5) if z is None else z
    t = np.r_[[0.0] * 4, np.linspace(0, 1, n - 2)[1:-1], [1.0] * 4] if knots is None else knots
    return BSplineSurface((3, 3), (t, t), np.stack([X, Y, Z], -1))


def three_levels(offsets="frame") -> tuple[HierarchicalSurface, list[Overlay]]:
    hs = HierarchicalSurface(smooth_base(11), offsets)  # interior knots k/8
    o1 = hs.add_overlay((0.2, 0.8), (0.2, 0.8))
    o2 = hs.add_overlay((0.35, 0.65), (0.35, 0.65), o1)
    o3 = hs.add_overlay((0.45, 0.55), (0.4, 0.6), o2)
    return hs, [o1, o2, o3]


@st.composite
def nested_ranges(draw, domain):
    """A random sub-interval of ``domain`` (as fractions drawn by hypothesis)."""
    lo, hi = domain
    a, b = sorted(draw(st.lists(st.floats(0, 1, **_float), min_size=2, max_size=2)))
    b = max(b, a + 0.05)
    return lo + a * (hi - lo), lo + min(b, 1.0) * (hi - lo)


# ------------------------------------------------------------------------ creating overlays
@given(surfaces(degrees=st.integers(1, 4), dims=st.just(3)), st.data())
@test_settings(25)
def test_random_overlay_creation_leaves_surface_unchanged(s, data):
    hs = HierarchicalSurface(s)
    parent = None
    made = []
    for _ in range(data.draw(st.integers(1, 3))):
        dom = s.domain if parent is None else parent.region
        ru = data.draw(nested_ranges(dom[0]))
        rv = data.draw(nested_ranges(dom[1]))
        try:
            o = hs.add_overlay(ru, rv, parent)
        except ParameterError:  # a region too thin to hold a refined vertex: allowed, skip it
            continue
        made.append(o)
        parent = o if data.draw(st.booleans()) else parent
    (u0, u1), (v0, v1) = s.domain
    us, vs = np.linspace(u0, u1, 23), np.linspace(v0, v1, 19)
    scale = max(1.0, float(np.abs(s.control_points).max()))
    # Evaluation adds all-zero delta splines: bit-identical.
    assert np.array_equal(hs.evaluate_grid(us, vs), s.evaluate_grid(us, vs))
    # The refined level nets and the flat form: Oslo refinement, exact up to round-off. Measured
    # ~1e-15 relative to the pole size; 1e-12 leaves room for degree-4 rational refinement chains.
    f = hs.flatten()
    assert_allclose(f.evaluate_grid(us, vs), s.evaluate_grid(us, vs), rtol=0, atol=1e-12 * scale)
    for o in made:
        assert_allclose(hs.level_surface(o).evaluate_grid(us, vs), s.evaluate_grid(us, vs), rtol=0, atol=1e-12 * scale)
        # The overlay's vertices are the refined base poles (oracle: BSplineSurface.refine).
        r = s
        for anc in _ancestors(hs, o):
            r = r.refine(anc.inserted[0], direction="u").refine(anc.inserted[1], direction="v")
        (i0, i1), (j0, j1) = o.vertices
        assert_allclose(hs.control_points(o), r.control_points[i0:i1 + 1, j0:j1 + 1], rtol=0, atol=1e-12 * scale)
        assert np.all(hs.offsets(o) == 0.0)


def _ancestors(hs, o):
    chain = []
    by_id = {h.id: h for h in hs.overlays}
    while o is not None:
        chain.append(o)
        o = by_id.get(o.parent)
    return chain[::-1]


def test_overlay_refines_midpoints_and_owns_the_region_vertices():
    hs = HierarchicalSurface(smooth_base())  # interior knots 0.25, 0.5, 0.75
    o = hs.add_overlay((0.3, 0.55), (0.25, 0.5))
    assert o.region == ((0.25, 0.75), (0.25, 0.5))  # widened to the parent's knots
    assert_allclose(o.inserted[0], [0.375, 0.625])
    assert_allclose(o.inserted[1], [0.375])
    for ax in range(2):
        g = o.reference_parameters[ax]
        assert g.min() >= o.region[ax][0] and g.max() <= o.region[ax][1]
    o2 = hs.add_overlay((0.3, 0.5), (0.25, 0.5), o, knots=([0.35, 0.4, 0.45], [0.3]))
    assert_allclose(o2.inserted[0], [0.35, 0.4, 0.45])
    assert o2.level == 2 and hs.children(o) == [o2] and hs.depth == 2


# ------------------------------------------------------------------------ flatten
def _edited(offsets="frame", seed=0):
    hs, (o1, o2, o3) = three_levels(offsets)
    rng = np.random.default_rng(seed)
    for o in (o1, o2, o3):
        hs.set_offsets(o, 0.05 * rng.standard_normal(o.shape + (3,)))
    hs.move_vertex(None, (3, 3), (0.0, 0.3, 1.0))
    return hs


@pytest.mark.parametrize("offsets", ["frame", "additive"])
def test_flatten_equals_hierarchy_densely(offsets):
    hs = _edited(offsets)
    f = hs.flatten()
    us = np.linspace(0, 1, 201)
    # Issue requirement 1e-10; measured ~1e-15 (refinement is exact, only round-off differs).
    assert_allclose(hs.evaluate_grid(us, us), f.evaluate_grid(us, us), rtol=0, atol=1e-10)
    rng = np.random.default_rng(1)
    u, v = rng.uniform(0, 1, 2000), rng.uniform(0, 1, 2000)
    assert_allclose(hs.evaluate(u, v), f.evaluate(u, v), rtol=0, atol=1e-10)
    # Partials up to order 2 scale with the finest span (1/40) squared: 1e-10 relative to their size.
    D, Df = hs.derivatives(u, v, 2), f.derivatives(u, v, 2)
    assert_allclose(D, Df, rtol=0, atol=1e-10 * np.abs(Df).max())
    G = hs.derivatives_grid(us[::10], us[::10], 2)
    assert_allclose(G, f.derivatives_grid(us[::10], us[::10], 2), rtol=0, atol=1e-10 * np.abs(G).max())
    assert_allclose(hs.normal_grid(us[::10], us[::10]), f.normal(*np.meshgrid(us[::10], us[::10], indexing="ij")),
                    atol=1e-10)
    assert_allclose(hs.normal(u, v), f.normal(u, v), atol=1e-10)


def test_flatten_rational_non_uniform_unclamped():
    rng = np.random.default_rng(3)
    U = np.array([-1, -0.5, 0, 0.3, 0.5, 0.9, 1.4, 2, 2.2, 3.0])
    Vk = np.r_[[0] * 4, 0.4, 0.45, [1] * 4]
    P = rng.normal(size=(6, 6, 3))
    w = rng.uniform(0.5, 2, (6, 6))
    s = BSplineSurface((3, 3), (U, Vk), P, w)
    hs = HierarchicalSurface(s)
    o1 = hs.add_overlay(s.domain[0], s.domain[1])
    o2 = hs.add_overlay((0.3, 0.9), (0.2, 0.6), o1)
    hs.set_offsets(o2, rng.normal(size=o2.shape + (3,)) * 0.1)
    hs.move_vertex(o1, (2, 2), (0.1, 0.0, -0.2))
    f = hs.flatten()
    assert f.is_rational
    u, v = rng.uniform(0.3, 1.4, 3000), rng.uniform(0, 1, 3000)
    assert_allclose(hs.evaluate(u, v), f.evaluate(u, v), rtol=0, atol=1e-10)
    counts = hs.pole_counts()
    assert counts["flat"] == f.n_poles[0] * f.n_poles[1]
    assert counts["stored"] == 36 + o1.shape[0] * o1.shape[1] + o2.shape[0] * o2.shape[1]


# ------------------------------------------------------------------------ offset referencing
def test_move_vertex_moves_the_world_vertex_and_stores_frame_offset():
    hs, (o1, o2, o3) = three_levels()
    before = hs.control_points(o2)
    d = np.array([0.02, -0.01, 0.05])
    hs.move_vertex(o2, (2, 3), d)
    after = hs.control_points(o2)
    assert_allclose(after[2, 3] - before[2, 3], d, atol=1e-15)
    mask = np.ones(o2.shape, bool)
    mask[2, 3] = False
    assert_allclose(after[mask], before[mask], atol=0)
    F = hs.reference_frames(o2)[2, 3]
    assert_allclose(hs.offsets(o2)[2, 3], F.T @ d, atol=1e-15)  # offsets are (t, b, n) coordinates


def test_reference_frames_are_gram_schmidt_of_the_parent_partials():
    hs, (o1, o2, _) = three_levels()
    hs.move_vertex(None, (2, 4), (0.5, 0.2, 1.5))
    # Level 1 carries a wave, so its surface (the parent of o2) turns away from the base: the
    # frames must be those of the parent level (base + level 1), not of the base.
    wave = np.zeros(o1.shape + (3,))
    wave[..., 2] = 0.3 * np.sin(1.3 * np.arange(o1.shape[0]))[:, None]
    hs.set_offsets(o1, wave)
    F = hs.reference_frames(o2)
    gu, gv = o2.reference_parameters
    n_base = hs.base.normal(*np.meshgrid(gu, gv, indexing="ij"))
    assert np.degrees(np.arccos(np.einsum("...i,...i->...", n_base, F[..., 2]).min())) > 5
    D = hs.level_surface(o1).derivatives_grid(gu, gv, 1)
    su, sv = D[:, :, 1, 0], D[:, :, 0, 1]
    t = su / np.linalg.norm(su, axis=-1, keepdims=True)
    n = np.cross(su, sv)
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    assert_allclose(F[..., 0], t, atol=1e-14)
    assert_allclose(F[..., 2], n, atol=1e-14)
    assert_allclose(F[..., 1], np.cross(n, t), atol=1e-14)
    assert_allclose(np.einsum("...ki,...kj->...ij", F, F), np.broadcast_to(np.eye(3), F.shape), atol=1e-14)
    assert_allclose(np.linalg.det(F), 1.0, atol=1e-14)


def test_rigid_motion_of_the_base_moves_every_detail_rigidly():
    hs = _edited("frame")
    us = np.linspace(0, 1, 41)
    before = hs.evaluate_grid(us, us)
    c, s = np.cos(0.7), np.sin(0.7)
    R = np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]]) @ np.array([[1, 0, 0], [0, c, -s], [0, s, c]])
    b = np.array([1.0, -2.0, 0.5])
    hs.set_base(hs.base.transform(R, b))
    # Frames turn with the base, refinement is affine-invariant: round-off only (measured 4e-15).
    assert_allclose(hs.evaluate_grid(us, us), before @ R.T + b, atol=1e-12)
    add = _edited("additive")
    add.set_base(add.base.transform(R, b))
    assert np.abs(add.evaluate_grid(us, us) - (before @ R.T + b)).max() > 1e-3  # additive details do not turn


def _bump(hs, parent, child, h):
    """Normal offsets h on a 3 x 3 block of ``child``'s vertices around its middle; returns the
    centre index."""
    ci, cj = child.shape[0] // 2, child.shape[1] // 2
    offs = np.zeros(child.shape + (3,))
    offs[ci - 1:ci + 2, cj - 1:cj + 2, 2] = h
    hs.set_offsets(child, offs)
    return ci, cj


def _greville(knots, p):
    """Greville abscissae computed here (not by the code under test)."""
    t = np.asarray(knots, float)
    return np.array([t[i + 1:i + p + 1].mean() for i in range(t.size - p - 1)])


def _bump_oracle(base, child, heights, c):
    """What frame offsets mean, built without the hierarchical code: the bump's vertices
    ``c +- 1`` of ``child`` displaced by ``h_k n_k`` (``n_k`` the base's own normal at the
    vertex's Greville point, from ``BSplineSurface.normal``) on ``child``'s knots, as one
    B-spline. Valid while the levels between the base and ``child`` carry zero offsets.

    Returns the detail spline, the normals ``n_k`` (3, 3, 3) and the centre's parameter."""
    (i0, _), (j0, _) = child.vertices
    gu, gv = (_greville(k, 3) for k in child.knots)
    iu, iv = np.arange(3) + i0 + c[0] - 1, np.arange(3) + j0 + c[1] - 1
    normals = base.normal(*np.meshgrid(gu[iu], gv[iv], indexing="ij"))  # (3, 3, 3)
    net = np.zeros((gu.size, gv.size, 3))
    net[np.ix_(iu, iv)] = heights[..., None] * normals
    g = (gu[iu[1]], gv[iv[1]])
    return BSplineSurface((3, 3), child.knots, net), normals, g


@given(z=st.lists(st.floats(-1, 1, **_float), min_size=49, max_size=49),
       moves=st.lists(st.tuples(st.integers(0, 6), st.integers(0, 6),
                                st.lists(st.floats(-1.5, 1.5, **_float), min_size=3, max_size=3)),
                      min_size=1, max_size=4),
       h=st.lists(st.floats(0.01, 0.3, **_float), min_size=9, max_size=9))
@test_settings(30)
def test_coarse_edits_carry_details_along(z, moves, h):
    hs = HierarchicalSurface(smooth_base(z=np.reshape(z, (7, 7))))
    o1 = hs.add_overlay((0.2, 0.8), (0.2, 0.8))
    o2 = hs.add_overlay((0.4, 0.6), (0.4, 0.6), o1)
    H = np.reshape(h, (3, 3))
    c = _bump(hs, o1, o2, H)
    us = np.linspace(0.0, 1.0, 33)

    def state():
        """Detail height at the centre along the base's own normal there; the bump's normals."""
        delta, normals, g = _bump_oracle(hs.base, o2, H, c)
        n_c = normals[1, 1]
        # The whole detail is the oracle's (n_k from BSplineSurface.normal, no frames of the code
        # under test): round-off of two evaluations, measured ~1e-15 (details <= 0.3, poles <= 6).
        assert_allclose(hs.evaluate_grid(us, us) - hs.base.evaluate_grid(us, us), delta.evaluate_grid(us, us),
                        rtol=0, atol=1e-12)
        return float((hs.evaluate(*g) - hs.base.evaluate(*g)) @ n_c), float((normals @ n_c).min())

    h0, cos0 = state()
    for i, j, d in moves:
        hs.move_vertex(None, (i, j), d)
    h1, cos1 = state()
    # Height model: sum_k B_k(g) h_k (n_k . n_g) over the bump's vertices k, B_k <= 1, so a coarse
    # edit changes the height along the (new) normal by at most sum_k h_k (1 - min cos(n_k, n_g))
    # over both states: details keep their height up to the turn of the normal across the bump.
    # Plus round-off (1e-12).
    bound = float(np.sum(h)) * (1.0 - min(cos0, cos1)) + 1e-12
    assert abs(h1 - h0) <= bound
    # The stored offsets never change: the base edit moves the detail with the parent surface.
    assert_allclose(hs.offsets(o2)[c], [0, 0, h[4]], atol=0)


def test_single_vertex_detail_keeps_its_height_exactly_under_bending():
    hs, (o1, o2, _) = three_levels()
    c = (o2.shape[0] // 2, o2.shape[1] // 2)
    hs.set_offset(o2, c, (0.0, 0.0, 0.2))
    g = [o2.reference_parameters[k][c[k]] for k in range(2)]

    def detail(h):
        """Detail vector at the vertex's reference point; the base's own unit normal there."""
        return h.evaluate(*g) - h.base.evaluate(*g), h.base.normal(*g)

    d0, n0 = detail(hs)
    hs.move_vertex(None, (4, 5), (0.0, 0.0, 2.0))  # tilts the surface under the detail
    hs.move_vertex(None, (5, 6), (1.0, 0.0, -1.0))
    d1, n1 = detail(hs)
    assert np.degrees(np.arccos(n0 @ n1)) > 20  # a real bend
    # One vertex: detail = B_c(g) * 0.2 * n_c with n_c the normal at g itself (levels 0 and 1 are
    # the same surface here): it stays along the new normal with the same length, to round-off
    # (measured 1e-16).
    assert_allclose(d1, (d0 @ n0) * n1, rtol=0, atol=1e-13)
    assert d0 @ n0 > 0.05
    add, (a1, a2, _) = three_levels("additive")
    add.set_offset(a2, c, (0.0, 0.0, 0.2))
    add.move_vertex(None, (4, 5), (0.0, 0.0, 2.0))
    add.move_vertex(None, (5, 6), (1.0, 0.0, -1.0))
    da, na = detail(add)
    assert abs(da @ na - d0 @ n0) > 1e-3


def test_edits_are_local_and_leave_other_levels_alone():
    hs, (o1, o2, o3) = three_levels()
    us = np.linspace(0, 1, 81)
    before = hs.evaluate_grid(us, us)
    offs = {o: hs.offsets(o) for o in (o1, o3)}
    hs.move_vertex(o2, (1, 1), (0.0, 0.0, 0.1))
    after = hs.evaluate_grid(us, us)
    # Outside the moved vertex's support nothing changes (bit-identical).
    p = 3
    (i0, _), (j0, _) = o2.vertices
    U, Vk = o2.knots
    su = (U[i0 + 1], U[i0 + 1 + p + 1])
    sv = (Vk[j0 + 1], Vk[j0 + 1 + p + 1])
    outside = ~(((us >= su[0]) & (us <= su[1]))[:, None] & ((us >= sv[0]) & (us <= sv[1]))[None, :])
    assert np.array_equal(after[outside], before[outside])
    assert np.abs(after - before).max() > 1e-3
    for o, v in offs.items():
        assert np.array_equal(hs.offsets(o), v)


def test_grid_cache_is_invalidated_by_edits():
    hs, (o1, o2, o3) = three_levels()
    us = np.linspace(0, 1, 50)
    hs.evaluate_grid(us, us)
    for target, idx in ((o3, (2, 2)), (o1, (1, 2)), (None, (3, 3))):
        hs.move_vertex(target, idx, (0.0, 0.0, 0.05))
        assert_allclose(hs.evaluate_grid(us, us), hs.flatten().evaluate_grid(us, us), atol=1e-12)


# ------------------------------------------------------------------------ edit points
@pytest.mark.parametrize("offsets", ["frame", "additive"])
def test_drag_point_changes_only_the_chosen_level(offsets):
    hs = _edited(offsets)
    o1, o2, o3 = hs.overlays
    u, v = 0.47, 0.52
    keep = {o: hs.offsets(o) for o in (o1, o3)}
    base = hs.base
    target = hs.evaluate(u, v) + np.array([0.0, 0.05, 0.2])
    hs.drag_point(u, v, target, overlay=o2)
    assert_allclose(hs.evaluate(u, v), target, atol=1e-10)
    for o, val in keep.items():
        assert np.array_equal(hs.offsets(o), val)
    assert hs.base == base


def test_drag_point_is_the_minimum_norm_change_of_the_level_vertices():
    hs = _edited("additive")
    o2 = hs.overlays[1]
    lvl = hs.level_surface(o2)
    u, v = 0.47, 0.52
    target = hs.evaluate(u, v) + np.array([0.1, 0.0, 0.2])
    # Oracle: drag_surface_point on the level surface with the overlay's vertices as window.
    ref = drag_surface_point(lvl, u, v, lvl.evaluate(u, v) + (target - hs.evaluate(u, v)), window=o2.vertices)
    before = hs.control_points(o2)
    hs.drag_point(u, v, target, overlay=o2)
    (i0, i1), (j0, j1) = o2.vertices
    assert_allclose(hs.control_points(o2) - before,
                    (ref.control_points - lvl.control_points)[i0:i1 + 1, j0:j1 + 1], atol=1e-13)


def test_edit_points_and_finest_level():
    hs, (o1, o2, o3) = three_levels()
    params, pts = hs.edit_points(o2)
    assert params.shape == o2.shape + (2,) and pts.shape == o2.shape + (3,)
    assert_allclose(pts[1, 2], hs.evaluate(*params[1, 2]), atol=1e-15)
    target = pts[1, 2] + np.array([0.0, 0.0, 0.1])
    hs.move_edit_point(o2, (1, 2), target)
    assert_allclose(hs.evaluate(*params[1, 2]), target, atol=1e-10)
    assert hs.finest_overlay(0.5, 0.5) is o3
    assert hs.finest_overlay(0.3, 0.3) is o1
    assert hs.finest_overlay(0.05, 0.05) is None
    t = hs.evaluate(0.5, 0.45) + np.array([0.0, 0.0, 0.03])
    before = hs.offsets(o2)
    hs.drag_point(0.5, 0.45, t, overlay="finest")  # §5-30: the finest level there (o3)
    assert_allclose(hs.evaluate(0.5, 0.45), t, atol=1e-10)
    assert np.array_equal(hs.offsets(o2), before) and np.abs(hs.offsets(o3)).max() > 0
    hs.drag_point(0.05, 0.05, hs.evaluate(0.05, 0.05) + 0.1, overlay="finest")  # the base
    with pytest.raises(ConstraintError):
        hs.drag_point(0.02, 0.02, np.zeros(3), overlay=o3)  # no o3 vertex acts there


# ------------------------------------------------------------------------ storage
def test_to_dict_round_trip_is_lossless_through_json():
    hs = _edited("frame")
    d = json.loads(json.dumps(hs.to_dict()))
    h2 = HierarchicalSurface.from_dict(d)
    assert h2.to_dict() == hs.to_dict()
    us = np.linspace(0, 1, 57)
    assert np.array_equal(h2.evaluate_grid(us, us), hs.evaluate_grid(us, us))
    assert [o.vertices for o in h2.overlays] == [o.vertices for o in hs.overlays]
    # Still editable, with the same handles semantics.
    h2.move_vertex(h2.overlays[2], (0, 0), (0, 0, 0.1))


def test_from_dict_rejects_bad_input():
    d = _edited().to_dict()
    with pytest.raises(InvalidGeometryError, match="version"):
        HierarchicalSurface.from_dict({**d, "version": 99})
    with pytest.raises(InvalidGeometryError, match="type"):
        HierarchicalSurface.from_dict({**d, "type": "BSplineSurface"})
    bad = json.loads(json.dumps(d))
    bad["overlays"][1]["parent"] = 3
    with pytest.raises(InvalidGeometryError, match="parent"):
        HierarchicalSurface.from_dict(bad)
    bad = json.loads(json.dumps(d))
    bad["overlays"][0]["offsets"] = [[0.0]]
    with pytest.raises(InvalidGeometryError, match="offsets"):
        HierarchicalSurface.from_dict(bad)
    with pytest.raises(InvalidGeometryError, match="offsets"):
        HierarchicalSurface.from_dict({**d, "offset_mapping": "no-such-mapping"})


@pytest.mark.parametrize("key, value, match", [
    ("region", 3, "region"), ("inserted_knots", 0.5, "inserted_knots"), ("region", [[0.2, 0.8]], "region"),
    ("id", 1.0, "integers"), ("id", True, "integers"), ("parent", "0", "integers"),
    ("region", [[0.8, 0.2], [0.2, 0.8]], "overlay 1: u_range"), ("inserted_knots", [["x"], []], "overlay 1: knots"),
])
def test_from_dict_malformed_overlay_entries_raise_named_errors(key, value, match):
    # A corrupt file must give an InvalidGeometryError naming the overlay and entry, never a
    # TypeError from deep inside (found in review: a scalar 'region' raised TypeError).
    bad = json.loads(json.dumps(_edited().to_dict()))
    bad["overlays"][0][key] = value
    with pytest.raises(InvalidGeometryError, match=match):
        HierarchicalSurface.from_dict(bad)


def test_custom_offset_mapping_is_pluggable_and_stored_by_name():
    # Offsets in the frame, but the normal component scaled by 2 (a "softness" field).
    S = np.diag([1.0, 1.0, 2.0])
    m = OffsetMapping("test-double-normal",
                      lambda o, F: FRAME_OFFSETS(o @ S.T, F),
                      lambda d, F: FRAME_OFFSETS.inverse(d, F) @ np.linalg.inv(S).T)
    register_offset_mapping(m)
    hs = HierarchicalSurface(smooth_base(), m)
    o = hs.add_overlay((0.2, 0.8), (0.2, 0.8))
    hs.set_offset(o, (2, 2), (0, 0, 0.1))
    F = hs.reference_frames(o)[2, 2]
    r = hs.level_surface(None).refine(o.inserted[0], direction="u").refine(o.inserted[1], direction="v")
    (i0, _), (j0, _) = o.vertices
    assert_allclose(hs.control_points(o)[2, 2] - r.control_points[i0 + 2, j0 + 2], 0.2 * F[:, 2], atol=1e-14)
    hs.move_vertex(o, (1, 1), (0.1, 0.2, 0.3))
    assert_allclose(hs.control_points(o)[1, 1] - r.control_points[i0 + 1, j0 + 1], [0.1, 0.2, 0.3], atol=1e-14)
    h2 = HierarchicalSurface.from_dict(json.loads(json.dumps(hs.to_dict())))
    assert h2.offset_mapping is m
    with pytest.raises(InvalidGeometryError):
        register_offset_mapping(OffsetMapping("frame", ADDITIVE_OFFSETS.forward, ADDITIVE_OFFSETS.inverse))


def test_copy_is_independent():
    hs, (o1, o2, o3) = three_levels()
    c = hs.copy()
    c.move_vertex(o2, (1, 1), (0, 0, 1.0))
    c.move_vertex(None, (0, 0), (0, 0, 1.0))
    assert np.abs(hs.offsets(o2)).max() == 0.0
    assert hs.base == smooth_base(11)
    assert np.abs(c.offsets(o2)).max() > 0


# ------------------------------------------------------------------------ errors
def test_errors_name_the_argument():
    hs, (o1, o2, o3) = three_levels()
    with pytest.raises(ParameterError, match="u_range"):
        hs.add_overlay((0.5, 1.5), (0.2, 0.3))
    with pytest.raises(ParameterError, match="parent overlay's region"):
        hs.add_overlay((0.1, 0.3), (0.4, 0.5), o2)
    with pytest.raises(ParameterError, match="v_range"):
        hs.add_overlay((0.2, 0.3), (0.3, 0.3))
    other, (x1, _, _) = three_levels()
    with pytest.raises(InvalidGeometryError, match="overlay"):
        hs.move_vertex(x1, (0, 0), (0, 0, 1))
    with pytest.raises(InvalidGeometryError, match="index"):
        hs.move_vertex(o1, (99, 0), (0, 0, 1))
    with pytest.raises(InvalidGeometryError, match="displacement"):
        hs.move_vertex(o1, (0, 0), (0, 1))
    with pytest.raises(InvalidGeometryError, match="offsets"):
        HierarchicalSurface(BSplineSurface((1, 1), ([0, 0, 1, 1], [0, 0, 1, 1]), np.zeros((2, 2, 2))))
    HierarchicalSurface(BSplineSurface((1, 1), ([0, 0, 1, 1], [0, 0, 1, 1]), np.zeros((2, 2, 2))), "additive")
    with pytest.raises(InvalidGeometryError, match="knots"):
        hs.add_overlay((0.2, 0.4), (0.2, 0.4), knots=([0.3] * 5, []))
    with pytest.raises(ParameterError, match="u"):
        hs.evaluate(1.5, 0.5)
    with pytest.raises(InvalidGeometryError, match="base"):
        hs.set_base(hs.base.refine([0.5], direction="u"))


@pytest.mark.parametrize("degree", [1, 2, 3])
def test_derivatives_at_the_ends_of_an_overlay_follow_the_flat_convention(degree):
    """Review: at the right end of an overlay's support the overlay's own spline gives its left
    limit, whose derivatives of order >= degree jump there; added to the base's right limit that
    gave a derivative (and normal) matching neither side. The hierarchy must agree with flatten()
    (one spline: right limits at interior knots) at every support end, in u and in v."""
    rng = np.random.default_rng(degree)
    U = np.r_[[0.0] * degree, np.linspace(0, 1, 6), [1.0] * degree]
    n = U.size - degree - 1
    P = np.stack(np.meshgrid(np.linspace(0, 1, n), np.linspace(0, 1, n), indexing="ij"), -1)
    P = np.concatenate([P, 0.2 * rng.standard_normal((n, n, 1))], -1)
    hs = HierarchicalSurface(BSplineSurface((degree, degree), (U, U), P))
    o = hs.add_overlay((0.2, 0.6), (0.2, 0.6))
    hs.set_offsets(o, 0.1 * rng.normal(size=o.shape + (3,)))
    f = hs.flatten()
    (ua, ub), (va, vb) = hs._node(o).support
    ends = np.array([ua, ub, va, vb, 0.0, 1.0])
    uu, vv = (x.ravel() for x in np.meshgrid(ends, np.r_[ends, 0.5], indexing="ij"))
    # round-off relative to the largest partial (third derivatives of a 6-span cubic reach ~1e3)
    for a, b in ((uu, vv), (vv, uu)):
        ref = f.derivatives(a, b, degree)
        assert_allclose(hs.derivatives(a, b, degree), ref, rtol=0, atol=1e-12 * np.abs(ref).max())
        assert_allclose(hs.normal(a, b), f.normal(a, b), atol=1e-11)
    ref = f.derivatives_grid(ends, ends, degree)
    assert_allclose(hs.derivatives_grid(ends, ends, degree), ref, rtol=0, atol=1e-12 * np.abs(ref).max())


def test_tiny_knot_spans_and_knot_sized_regions():
    """Review: a base knot gap of 1e-13 gave a midpoint knot that from_dict snapped away (the saved
    hierarchy could not be loaded); a range within the tolerance of one knot gave a zero-width
    overlay that could not be loaded either. Both round-trip or are refused now."""
    rng = np.random.default_rng(0)
    U = [0, 0, 0, 0, .3, .5, .5 + 1e-13, .7, 1, 1, 1, 1]
    V = [0, 0, 0, 0, 1 / 3, 2 / 3, 1, 1, 1, 1]
    hs = HierarchicalSurface(BSplineSurface((3, 3), (U, V), rng.normal(size=(8, 6, 3))))
    o = hs.add_overlay((0.3, 0.7), (0.2, 0.8))
    hs.set_offsets(o, 0.1 * rng.normal(size=o.shape + (3,)))
    back = HierarchicalSurface.from_dict(json.loads(json.dumps(hs.to_dict())))
    g = np.linspace(0, 1, 23)
    assert np.array_equal(back.evaluate_grid(g, g), hs.evaluate_grid(g, g))
    k = [0, 0, 0, 0, 1 / 3, 2 / 3, 1, 1, 1, 1]
    hs2 = HierarchicalSurface(BSplineSurface((3, 3), (k, k), rng.normal(size=(6, 6, 3))))
    with pytest.raises(ParameterError, match=r"^u_range: .* shrinks to the single knot 0\.333"):
        hs2.add_overlay((1 / 3, 1 / 3 + 1e-13), (0.2, 0.8))


def _review_drag_case() -> HierarchicalSurface:
    k = [0, 0, 0, 0, .25, .5, .75, 1, 1, 1, 1]
    rng = np.random.default_rng(4)
    P = np.stack(np.meshgrid(np.linspace(0, 1, 7), np.linspace(0, 1, 7), indexing="ij"), -1)
    P = np.concatenate([P, 0.2 * rng.standard_normal((7, 7, 1))], -1)
    hs = HierarchicalSurface(BSplineSurface((3, 3), (k, k), P))
    o1 = hs.add_overlay((0.2, 0.8), (0.2, 0.8))
    o2 = hs.add_overlay((0.4, 0.6), (0.4, 0.6), parent=o1)
    o3 = hs.add_overlay((0.45, 0.9), (0.1, 0.55))
    rng = np.random.default_rng(5)
    for o in (o1, o2, o3):
        hs.set_offsets(o, 0.1 * rng.normal(size=o.shape + (3,)))
    return hs


def test_drag_point_converges_with_large_details_and_restores_on_failure():
    """Review: with details of 0.1 on a unit patch the residual falls only by ~0.16 per solve;
    12 solves were not enough (ConvergenceError) and the failed drag left the surface moved."""
    import occsurf.algorithms.hierarchical.surface as H

    hs = _review_drag_case()
    p0 = hs.evaluate(0.52, 0.47)
    target = p0 + [0.05, -0.03, 0.2]
    hs.drag_point(0.52, 0.47, target)
    assert np.linalg.norm(hs.evaluate(0.52, 0.47) - target) <= tolerances.EDIT_POINT_RTOL
    hs = _review_drag_case()
    g = np.linspace(0, 1, 15)
    before = hs.evaluate_grid(g, g)
    with tolerances.override(EDIT_POINT_MAX_ITER=3):
        with pytest.raises(H.ConvergenceError, match="after 3 solves.*left as it was"):
            hs.drag_point(0.52, 0.47, target)
    assert np.array_equal(hs.evaluate_grid(g, g), before)


def test_drag_point_takes_one_parameter_pair():
    hs, (o1, _, _) = three_levels()
    with pytest.raises(ParameterError, match=r"^u: expected one parameter, got an array of shape \(2,\)"):
        hs.drag_point([0.5, 0.6], 0.5, np.zeros(3))
