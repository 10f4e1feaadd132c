"""Hierarchical curves (course §5-33) and the offset frames and mappings (§5-15, §5-37)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from numpy.testing import assert_allclose

from occsurf.algorithms import BSplineCurve, BSplineSurface, tolerances
from occsurf.algorithms.errors import InvalidGeometryError, ParameterError
from occsurf.algorithms.hierarchical.curve import HierarchicalCurve
from occsurf.algorithms.hierarchical.offsets import (
    ADDITIVE_OFFSETS,
    FRAME_OFFSETS,
    curve_frames,
    frames_from_partials,
    get_offset_mapping,
    surface_frames,
)
from occsurf.algorithms.hierarchical.surface import HierarchicalSurface
from tests.algorithms.strategies import curves, test_settings


# ------------------------------------------------------------------------ curves
@given(curves(degrees=st.integers(1, 5), dims=st.integers(2, 3)), st.data())
@test_settings(30)
def test_curve_overlays_leave_the_curve_unchanged_and_flatten_exactly(c, data):
    hc = HierarchicalCurve(c)
    lo, hi = c.domain
    a = data.draw(st.floats(0, 0.6))
    o1 = hc.add_overlay((lo + a * (hi - lo), hi))
    o2 = hc.add_overlay(o1.region[0], o1)
    x = np.linspace(lo, hi, 101)
    scale = max(1.0, float(np.abs(c.control_points).max()))
    # Zero delta splines are added; a rational curve is then evaluated as homogeneous point plus
    # quotient rule, another rounding path than BSplineCurve.evaluate: a few ulps (1e-14).
    assert_allclose(hc.evaluate(x), c.evaluate(x), rtol=0, atol=1e-14 * scale)
    # Oslo refinement: exact up to round-off (measured ~1e-15 relative); 1e-12 as for surfaces.
    assert_allclose(hc.flatten().evaluate(x), c.evaluate(x), rtol=0, atol=1e-12 * scale)
    rng = np.random.default_rng(0)
    hc.set_offsets(o2, rng.uniform(-1, 1, o2.shape + (c.dim,)))
    hc.move_vertex(None, 0, np.ones(c.dim))
    hc.move_vertex(o1, o1.shape[0] - 1, -np.ones(c.dim))  # the last vertex (negative indices are refused)
    f = hc.flatten()
    big = max(scale, float(np.abs(f.control_points).max()))
    assert_allclose(hc.evaluate(x), f.evaluate(x), rtol=0, atol=1e-10 * big)
    D, Df = hc.derivatives(x, 2), f.derivatives(x, 2)
    assert_allclose(D, Df, rtol=0, atol=1e-10 * max(1.0, np.abs(Df).max()))
    h2 = HierarchicalCurve.from_dict(json.loads(json.dumps(hc.to_dict())))
    assert np.array_equal(h2.evaluate(x), hc.evaluate(x))


def test_curve_details_follow_a_rotated_base():
    t = np.r_[[0.0] * 4, 0.25, 0.5, 0.75, [1.0] * 4]
    c = BSplineCurve(3, t, np.c_[np.linspace(0, 6, 7), np.sin(np.linspace(0, 3, 7))])
    hc = HierarchicalCurve(c)
    o = hc.add_overlay((0.25, 0.75))
    hc.set_offset(o, 2, (0.0, 0.3))  # along the normal J t
    x = np.linspace(0, 1, 50)
    before = hc.evaluate(x)
    a = 1.1
    R = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
    hc2 = HierarchicalCurve(c.transform(R), "frame")
    o2 = hc2.add_overlay((0.25, 0.75))
    hc2.set_offset(o2, 2, (0.0, 0.3))
    assert_allclose(hc2.evaluate(x), before @ R.T, atol=1e-13)
    F = hc.reference_frames(o)[2]
    assert_allclose(F.T @ F, np.eye(2), atol=1e-15)
    assert_allclose(np.linalg.det(F), 1.0, atol=1e-15)


def test_curve_drag_point_and_errors():
    t = np.r_[[0.0] * 4, 0.25, 0.5, 0.75, [1.0] * 4]
    c = BSplineCurve(3, t, np.c_[np.linspace(0, 6, 7), np.zeros(7), np.zeros(7)])
    hc = HierarchicalCurve(c)
    o1 = hc.add_overlay((0.25, 0.75))
    o2 = hc.add_overlay((0.375, 0.625), o1)
    hc.set_offset(o2, 1, (0, 0, 0.2))
    keep = hc.offsets(o2)
    hc.drag_point(0.45, [2.7, 0.5, 0.3], overlay=o1)
    assert_allclose(hc.evaluate(0.45), [2.7, 0.5, 0.3], atol=1e-10)
    assert np.array_equal(hc.offsets(o2), keep)
    hc.drag_point(0.1, [0.6, 0.1, 0.0])
    assert_allclose(hc.evaluate(0.1), [0.6, 0.1, 0.0], atol=1e-10)
    assert hc.pole_counts()["offsets"] == o1.shape[0] + o2.shape[0]
    with pytest.raises(ParameterError, match="parent"):
        hc.add_overlay((0.0, 0.3), o2)
    with pytest.raises(InvalidGeometryError, match="offsets"):
        HierarchicalCurve(BSplineCurve(1, [0, 0, 1, 1], np.zeros((2, 4))))
    with pytest.raises(InvalidGeometryError, match="base"):
        HierarchicalCurve(BSplineSurface((1, 1), ([0, 0, 1, 1], [0, 0, 1, 1]), np.zeros((2, 2, 3))))
    with pytest.raises(InvalidGeometryError, match="index"):
        hc.move_vertex(o1, (1, 2), [0, 0, 1])


# ------------------------------------------------------------------------ frames
def test_frames_from_partials_gram_schmidt_and_degenerate_flags():
    su = np.array([[2.0, 0, 0], [0, 0, 0], [1, 1, 0], [1e-3, 0, 0]])
    sv = np.array([[0.5, 3.0, 0], [0, 1, 0], [2, 2, 0], [0, 1e3, 0]])
    F, bad = frames_from_partials(su, sv)
    assert bad.tolist() == [False, True, True, False]
    assert_allclose(F[0], np.eye(3), atol=1e-15)  # t = x, n = z, b = n x t = y
    assert_allclose(F[1], np.eye(3))  # world axes where degenerate
    assert_allclose(F[3], np.eye(3), atol=1e-15)  # scale-invariant test: a short S_u is fine


def test_degenerate_normal_on_a_collapsed_edge_uses_the_nudged_frame():
    # A "cone": the u = 0 row of poles collapses to the apex, so S_v = 0 all along u = 0.
    g = np.linspace(0, 2 * np.pi, 6)
    r = np.array([0.0, 1.0, 2.0, 3.0])
    P = np.stack([np.outer(r, np.cos(g)), np.outer(r, np.sin(g)), np.outer(3 - r, np.ones(6))], -1)
    t = [0, 0, 0, 0, 1, 1, 1, 1]
    tv = np.r_[[0.0] * 4, 1 / 3, 2 / 3, [1.0] * 4]
    s = BSplineSurface((3, 3), (t, tv), P)
    vs = np.array([0.1, 0.5, 0.8])
    F = surface_frames(s, np.array([0.0]), vs)[0]
    assert_allclose(np.einsum("kij,kil->kjl", F, F), np.broadcast_to(np.eye(3), F.shape), atol=1e-12)
    # Limit normal: the normal a little further in. The nudged frame sits FRAME_NUDGE inside, so
    # it matches the normal at u = 1e-3 to O(1e-3) (the normal turns linearly away from the edge).
    n_in = s.normal(np.full(3, 1e-3), vs)
    assert np.all(np.einsum("ki,ki->k", F[:, :, 2], n_in) > 1 - 1e-4)
    assert tolerances.FRAME_NUDGE < 1e-3
    # Used as an offset frame, storing and applying an offset there is consistent.
    hs = HierarchicalSurface(s)
    o = hs.add_overlay((0.0, 0.5), (0.0, 1.0))
    hs.move_vertex(o, (0, 2), (0.0, 0.0, 0.4))
    assert_allclose(hs.flatten().evaluate_grid(vs, vs), hs.evaluate_grid(vs, vs), atol=1e-12)


def test_fully_collapsed_patch_falls_back_to_world_axes():
    s = BSplineSurface((2, 2), ([0, 0, 0, 1, 1, 1], [0, 0, 0, 1, 1, 1]), np.ones((3, 3, 3)))
    F = surface_frames(s, np.array([0.2, 0.7]), np.array([0.5]))
    assert_allclose(F, np.broadcast_to(np.eye(3), F.shape))
    hs = HierarchicalSurface(s)
    o = hs.add_overlay((0.0, 1.0), (0.0, 1.0))
    hs.set_offset(o, (1, 1), (0.1, 0.2, 0.3))  # acts additively there
    assert_allclose(hs.control_points(o)[1, 1], [1.1, 1.2, 1.3], atol=1e-15)


def test_curve_frames():
    c2 = BSplineCurve(1, [0, 0, 1, 1], [[0, 0], [2, 0]])
    assert_allclose(curve_frames(c2, np.array([0.5])), [[[1, 0], [0, 1]]])
    c3 = BSplineCurve(1, [0, 0, 1, 1], [[0, 0, 0], [0, 2, 0]])
    F = curve_frames(c3, np.array([0.5]))[0]
    assert_allclose(F, np.column_stack([[0, 1, 0], [0, 0, 1], [1, 0, 0]]), atol=1e-15)
    up = BSplineCurve(1, [0, 0, 1, 1], [[0, 0, 0], [0, 0, 2]])  # tangent along the up axis
    F = curve_frames(up, np.array([0.5]))[0]
    assert_allclose(F[:, 0], [0, 0, 1]) and assert_allclose(F.T @ F, np.eye(3), atol=1e-15)
    still = BSplineCurve(1, [0, 0, 1, 1], [[1, 1], [1, 1]])
    assert_allclose(curve_frames(still, np.array([0.5]))[0], np.eye(2))
    with pytest.raises(InvalidGeometryError):
        curve_frames(BSplineCurve(1, [0, 0, 1, 1], np.zeros((2, 4))), np.array([0.5]))


def test_provided_mappings():
    rng = np.random.default_rng(2)
    F = np.linalg.qr(rng.normal(size=(5, 3, 3)))[0]
    o = rng.normal(size=(5, 3))
    d = FRAME_OFFSETS(o, F)
    assert_allclose(d, np.einsum("mij,mj->mi", F, o))
    assert_allclose(FRAME_OFFSETS.inverse(d, F), o, atol=1e-15)
    assert_allclose(ADDITIVE_OFFSETS(o, None), o) and not ADDITIVE_OFFSETS.uses_frames
    assert get_offset_mapping("frame") is FRAME_OFFSETS
    with pytest.raises(InvalidGeometryError):
        get_offset_mapping("nope")


@pytest.mark.parametrize("degree", [1, 2, 3])
def test_curve_derivatives_at_the_ends_of_an_overlay_follow_the_flat_convention(degree):
    """Review: the same right-limit convention as flatten() at the ends of an overlay's support."""
    rng = np.random.default_rng(degree)
    U = np.r_[[0.0] * degree, np.linspace(0, 1, 6), [1.0] * degree]
    c = BSplineCurve(degree, U, rng.normal(size=(U.size - degree - 1, 3)))
    hc = HierarchicalCurve(c)
    o = hc.add_overlay((0.2, 0.6))
    hc.set_offsets(o, 0.1 * rng.normal(size=o.shape + (3,)))
    (ua, ub), = hc._node(o).support
    x = np.array([0.0, ua, ub, 1.0])
    ref = hc.flatten().derivatives(x, degree)
    assert_allclose(hc.derivatives(x, degree), ref, rtol=0, atol=1e-12 * np.abs(ref).max())


def test_hierarchical_modules_import_no_private_names():
    """curve.py and surface.py build on core.py's public Hierarchy and overlays.py's Node, not on private names."""
    import ast
    from pathlib import Path

    import occsurf.algorithms.hierarchical as Hpkg

    for path in Path(Hpkg.__file__).parent.glob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.level and node.module:  # not `from .. import _validate`
                private = [a.name for a in node.names if a.name.startswith("_")]
                assert not private, f"{path.name} imports private names {private} from {node.module}"
