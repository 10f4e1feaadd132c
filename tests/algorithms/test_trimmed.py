"""TrimmedSurface (algorithms/kernel/trimmed.py): closed-form areas, classification against exact
geometry, trims respected by evaluation, value semantics, bad input."""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from numpy.testing import assert_allclose

from occsurf.algorithms import BSplineCurve, BSplineSurface, TrimmedSurface, circle, tolerances
from occsurf.algorithms.errors import InvalidGeometryError, ParameterError
from occsurf.algorithms.kernel.trimmed import INSIDE, ON, OUTSIDE, classify_points
from tests.algorithms.strategies import test_settings

R = 0.25


def _line(a, b) -> BSplineCurve:
    return BSplineCurve(1, [0, 0, 1, 1], [a, b])


def _square(ccw: bool = True):
    pts = [(0, 0), (1, 0), (1, 1), (0, 1)]
    loop = tuple(_line(pts[i], pts[(i + 1) % 4]) for i in range(4))
    return loop if ccw else tuple(c.reverse() for c in loop[::-1])


def _hole(center=(0.5, 0.5), r=R) -> BSplineCurve:
    c = circle([center[0], center[1], 0.0], r)
    return BSplineCurve(c.degree, c.knots, c.control_points[:, :2], c.weights)


def _round_holes(rng: np.random.Generator, holes: int, points: int) -> list[np.ndarray]:
    """A 10 x 10 square's closed polyline and ``holes`` closed circles of ``points`` points inside
    it (centres in [1, 9], radii in [0.05, 0.4]: they may overlap), drawn from ``rng``."""
    loops = [np.array([[0, 0], [10, 0], [10, 10], [0, 10], [0, 0]], float)]
    th = np.linspace(0, 2 * np.pi, points)
    for c, r in zip(rng.uniform(1, 9, (holes, 2)), rng.uniform(0.05, 0.4, holes)):
        loops.append(np.c_[c[0] + r * np.cos(th), c[1] + r * np.sin(th)])
    return loops


def _plate(size=4.0, holes=True) -> TrimmedSurface:
    P = np.zeros((2, 2, 3))
    P[1, :, 0] = size
    P[:, 1, 1] = size
    s = BSplineSurface((1, 1), ([0, 0, 1, 1], [0, 0, 1, 1]), P)
    return TrimmedSurface(s, _square(), [(_hole(),)] if holes else [])


def _dome() -> BSplineSurface:
    """A curved bicubic patch (J = |S_u x S_v| not constant)."""
    u = np.linspace(0, 1, 4)
    U, V = np.meshgrid(u, u, indexing="ij")
    P = np.stack([3 * U, 2 * V, 0.8 * np.sin(np.pi * U) * np.cos(np.pi * V)], axis=-1)
    k = [0, 0, 0, 0, 1, 1, 1, 1]
    return BSplineSurface((3, 3), (k, k), P)


def test_area_of_plate_with_hole_is_closed_form():
    t = _plate()
    assert_allclose(t.area(), 16.0 * (1 - np.pi * R ** 2), rtol=1e-13)
    assert_allclose(_plate(holes=False).area(), 16.0, rtol=1e-14)


def test_area_of_curved_patch_agrees_with_dense_quadrature():
    s = _dome()
    t = TrimmedSurface(s, _square(), [(_hole(),)])
    # independent check: tensor Gauss on the whole patch minus polar Gauss on the hole
    x, w = np.polynomial.legendre.leggauss(60)
    a = (x + 1) / 2
    U, Vv = np.meshgrid(a, a, indexing="ij")
    D = s.derivatives(U, Vv, 1)
    whole = np.einsum("i,j,ij->", w / 2, w / 2, np.linalg.norm(np.cross(D[..., 1, 0, :], D[..., 0, 1, :]), axis=-1))
    rr, th = R * (x + 1) / 2, np.pi * (x + 1)
    RR, TT = np.meshgrid(rr, th, indexing="ij")
    D = s.derivatives(0.5 + RR * np.cos(TT), 0.5 + RR * np.sin(TT), 1)
    J = np.linalg.norm(np.cross(D[..., 1, 0, :], D[..., 0, 1, :]), axis=-1) * RR
    hole = np.einsum("i,j,ij->", w * R / 2, w * np.pi, J)
    assert_allclose(t.area(), whole - hole, rtol=1e-10)


def _green_every_piece(surface, c, pieces, anchor):
    """The Green sum of ``trimmed_area.green_area`` with every u piece evaluated at every node (the
    pieces outside ``[min(u, anchor), max(u, anchor)]`` at zero length): its form before the pieces
    were picked per node."""
    from occsurf.algorithms.kernel import trimmed_area

    x, w = trimmed_area.GAUSS
    s, ws = trimmed_area.composite_nodes(trimmed_area.breakpoints(surface, c), pieces, x, w)
    D = c.derivatives(s, 1)
    us, vs, dv = D[:, 0, 0], D[:, 0, 1], D[:, 1, 1]
    kb = np.unique(surface.knots[0][surface.degree[0]:surface.n_poles[0] + 1])
    a = (kb[:-1, None] + np.diff(kb)[:, None] * np.arange(pieces) / pieces).ravel()
    b = np.r_[a[1:], kb[-1]]
    start = np.maximum(a[None, :], np.minimum(us, anchor)[:, None])
    length = np.maximum(np.minimum(b[None, :], np.maximum(us, anchor)[:, None]) - start, 0.0)
    t = start[:, :, None] + length[:, :, None] * (x + 1.0) / 2.0
    Ds = surface.derivatives(t.ravel(), np.broadcast_to(vs[:, None, None], t.shape).ravel(), 1)
    J = np.linalg.norm(np.cross(Ds[:, 1, 0], Ds[:, 0, 1]), axis=-1).reshape(t.shape)
    F = np.sign(us - anchor) * np.einsum("nlg,g,nl->n", J, w, length / 2.0)
    return float(np.sum(ws * F * dv))


@test_settings(max_examples=20)
@given(cx=st.floats(0.3, 0.7), cy=st.floats(0.3, 0.7), r=st.floats(0.05, 0.25), anchor=st.floats(0.0, 1.0),
       level=st.integers(0, 2), rational=st.booleans())
def test_green_sums_over_the_overlapping_pieces_equal_the_sums_over_every_piece(cx, cy, r, anchor, level, rational):
    """The area's inner integrals evaluate, per node, only the u pieces between the node and the
    anchor; the value equals the former sum over every piece (zero-length ones adding 0) to
    round-off: 1e-13 of the integral of |J| over the patch (a few hundred terms of size <= that)."""
    from occsurf.algorithms.kernel import trimmed_area

    s = _dome().insert_knot(0.37, direction="u").insert_knot(0.61, direction="u").insert_knot(0.5, direction="v")
    if rational:
        wts = 1.0 + 0.3 * np.cos(np.arange(s.n_poles[0] * s.n_poles[1])).reshape(s.n_poles)
        s = BSplineSurface(s.degree, s.knots, s.control_points, wts)
    scale = _plate(holes=False).area() * 6.0  # |J| <= ~6 over the unit square of the dome
    for c in (*_square(), _hole((cx, cy), r)):
        got = trimmed_area.green_area(s, c, 1 << level, anchor)
        assert abs(got - _green_every_piece(s, c, 1 << level, anchor)) <= 1e-13 * scale


@test_settings(max_examples=30)
@given(cx=st.floats(0.3, 0.7), cy=st.floats(0.3, 0.7), r=st.floats(0.02, 0.28), knots=st.lists(st.floats(0.05, 0.95),
       min_size=1, max_size=6), rational=st.booleans())
def test_breakpoints_stopped_at_neighbouring_doubles_are_all_sixty_halvings(cx, cy, r, knots, rational):
    """The crossings of the surface's knot lines stop being halved once every bracket is two
    neighbouring doubles: the same crossings, bit for bit, as the 60 halvings of before (circles
    and the trim square over a dome with extra knots in u and v, rational or not)."""
    from occsurf.algorithms.kernel import trimmed_area

    s = _dome()
    for k, x in enumerate(knots):
        s = s.insert_knot(x, direction="u" if k % 2 else "v")
    if rational:
        wts = 1.0 + 0.3 * np.cos(np.arange(s.n_poles[0] * s.n_poles[1])).reshape(s.n_poles)
        s = BSplineSurface(s.degree, s.knots, s.control_points, wts)
    for c in (*_square(), _hole((cx, cy), r)):
        assert np.array_equal(trimmed_area.breakpoints(s, c), trimmed_area.breakpoints(s, c, stop_early=False))


def test_loops_are_oriented_whatever_the_input():
    a = TrimmedSurface(_plate().surface, _square(ccw=False), [(_hole(),)])
    b = TrimmedSurface(_plate().surface, _square(), [(_hole().reverse(),)])
    assert_allclose(a.area(), b.area(), rtol=1e-14)
    assert a.area() > 0


@given(st.lists(st.tuples(st.floats(-0.2, 1.2), st.floats(-0.2, 1.2)), min_size=1, max_size=200))
@test_settings(60)
def test_classification_agrees_with_exact_geometry(pts):
    t = _plate()
    P = np.array(pts)
    state = t.classify(P[:, 0], P[:, 1])
    d_hole = np.hypot(P[:, 0] - 0.5, P[:, 1] - 0.5) - R
    in_square = np.all((P > 0) & (P < 1), axis=1)
    d_square = np.min(np.abs(np.c_[P, 1 - P]), axis=1)
    expected = np.where(in_square & (d_hole > 0), INSIDE, OUTSIDE)
    margin = 1e-6
    clear = (np.abs(d_hole) > margin) & (d_square > margin)
    assert np.array_equal(state[clear], expected[clear])
    assert np.all(state[(np.abs(d_hole) < 1e-12) & in_square] == ON)


def test_classification_is_vectorised_and_handles_many_points():
    t = _plate()
    rng = np.random.default_rng(3)
    u, v = rng.random((2, 300, 400))
    state = t.classify(u, v)
    assert state.shape == (300, 400)
    inside = np.hypot(u - 0.5, v - 0.5) > R
    assert np.array_equal(state >= ON, inside | (state == ON))


def test_classify_points_even_odd_and_on_band():
    sq = np.array([[0, 0], [1, 0], [1, 1], [0, 1], [0, 0]], float)
    st_ = classify_points([[0.5, 0.5], [2, 0.5], [1.0, 0.5], [0.5, 1e-9]], sq[:-1], sq[1:], tol=1e-8)
    assert list(st_) == [INSIDE, OUTSIDE, ON, ON]
    with pytest.raises(InvalidGeometryError, match="seg_a, seg_b: expected the segments"):
        classify_points([[0.5, 0.5]])  # neither segments nor bands: refused, not "outside"


@test_settings(max_examples=10)
@given(seed=st.integers(0, 2**16), tol=st.sampled_from([0.0, 1e-9, 1e-4]))
def test_binned_segments_are_reused_with_the_same_answers(seed, tol):
    """The segments binned once (``segment_bands``, kept per tolerance by ``TrimmedSurface.classify``:
    the sections call it thousands of times on a face with hundreds of holes) give exactly what
    binning them on every call gives; a second tolerance gets its own bins."""
    from occsurf.algorithms.kernel.point_in_loops import segment_bands

    rng = np.random.default_rng(seed)
    t = _plate()
    P = rng.uniform(-0.2, 4.2, (500, 2))
    A, B, keep = t._segments(tolerances.TRIM_POLYLINE * t._diag())
    bands = segment_bands(A, B, tol, keep=keep)
    assert np.array_equal(classify_points(P, bands=bands), classify_points(P, A[keep], B[keep], tol))
    first = t.classify(P[:, 0], P[:, 1], tol=tol if tol > 0 else None)
    other = t.classify(P[:, 0], P[:, 1], tol=1e-3)  # another tolerance, other bins
    fresh = _plate()
    assert np.array_equal(t.classify(P[:, 0], P[:, 1], tol=tol if tol > 0 else None), first)
    assert np.array_equal(fresh.classify(P[:, 0], P[:, 1], tol=tol if tol > 0 else None), first)
    assert np.array_equal(fresh.classify(P[:, 0], P[:, 1], tol=1e-3), other)


@test_settings(max_examples=15)
@given(seed=st.integers(0, 2**16), holes=st.integers(0, 40), tol=st.sampled_from([0.0, 1e-6, 1e-3]))
def test_banded_classification_equals_testing_every_segment(seed, holes, tol):
    """However the segments are binned (fewer, taller bands where they are steep: a plate with many
    small round holes), each point gets exactly the answer of the crossing number over every
    segment, and ON within ``tol`` of any segment."""
    from occsurf.algorithms.kernel.point_in_loops import _point_segment_distance

    rng = np.random.default_rng(seed)
    loops = _round_holes(rng, holes, 97)
    A = np.concatenate([p[:-1] for p in loops])
    B = np.concatenate([p[1:] for p in loops])
    P = np.r_[rng.uniform(-1, 11, (400, 2)), A[rng.integers(0, len(A), 50)]]  # on the loops too
    got = classify_points(P, A, B, tol)
    cross = ((A[None, :, 1] > P[:, None, 1]) != (B[None, :, 1] > P[:, None, 1]))
    with np.errstate(invalid="ignore", divide="ignore"):
        x = A[None, :, 0] + (P[:, None, 1] - A[None, :, 1]) * (B[None, :, 0] - A[None, :, 0]) / (B[None, :, 1] - A[None, :, 1])
    inside = ((cross & (P[:, None, 0] < x)).sum(axis=1) % 2) == 1
    d = np.array([_point_segment_distance(np.repeat(p[None], len(A), 0), A, B).min() for p in P])
    want = np.where((d <= tol) if tol > 0 else np.zeros(len(P), bool), ON, np.where(inside, INSIDE, OUTSIDE))
    assert np.array_equal(got, want)


def test_evaluation_respects_the_trims():
    t = _plate()
    assert_allclose(t.evaluate(0.1, 0.1), [0.4, 0.4, 0.0], atol=1e-15)
    with pytest.raises(ParameterError, match="1 of 2 parameter points lie outside the trimmed face"):
        t.evaluate([0.1, 0.5], [0.1, 0.5])
    out = t.evaluate([0.1, 0.5], [0.1, 0.5], outside="nan")
    assert np.all(np.isnan(out[1])) and np.all(np.isfinite(out[0]))
    D = t.derivatives([0.5, 0.9], [0.5, 0.9], 2, outside="nan")
    assert np.all(np.isnan(D[0])) and np.all(np.isfinite(D[1]))
    k = t.curvatures([0.5, 0.9], [0.5, 0.9], outside="nan")
    assert np.isnan(k.mean[0]) and k.mean[1] == 0.0
    with pytest.raises(ParameterError):
        t.normal(0.5, 0.5)
    with pytest.raises(InvalidGeometryError, match="outside"):
        t.evaluate(0.1, 0.1, outside="clip")


def test_normal_follows_orientation():
    t = _plate()
    flipped = TrimmedSurface(t.surface, t.outer, t.inner, reversed=True)
    assert_allclose(t.normal(0.1, 0.1), [0, 0, 1])
    assert_allclose(flipped.normal(0.1, 0.1), [0, 0, -1])


def test_dict_round_trip_is_exact():
    t = TrimmedSurface(_dome(), _square(), [(_hole(),)], reversed=True)
    back = TrimmedSurface.from_dict(json.loads(json.dumps(t.to_dict())))
    assert back == t and back.reversed
    with pytest.raises(InvalidGeometryError, match="TrimmedSurface"):
        TrimmedSurface.from_dict({"type": "BSplineSurface"})
    d = t.to_dict()
    del d["outer"]
    with pytest.raises(InvalidGeometryError, match="missing key"):
        TrimmedSurface.from_dict(d)


def test_transform_maps_geometry_and_orientation():
    t = _plate()
    big = t.transform(2 * np.eye(3), [1, 2, 3])
    assert_allclose(big.area(), 4 * t.area(), rtol=1e-13)
    assert_allclose(big.evaluate(0.1, 0.1), [1.8, 2.8, 3.0])
    mirrored = t.transform(np.diag([1.0, 1.0, -1.0]))
    assert mirrored.reversed and not t.reversed
    assert_allclose(mirrored.area(), t.area(), rtol=1e-14)


def test_bad_input_is_named():
    s = _plate().surface
    with pytest.raises(InvalidGeometryError, match="surface: expected a BSplineSurface"):
        TrimmedSurface("plane", _square())
    with pytest.raises(InvalidGeometryError, match=r"outer\[0\]: expected a 2-D BSplineCurve"):
        TrimmedSurface(s, (circle([0, 0, 0], 1.0),))
    with pytest.raises(InvalidGeometryError, match="the loop is open"):
        TrimmedSurface(s, _square()[:3])
    with pytest.raises(InvalidGeometryError, match="leaves the surface's domain"):
        TrimmedSurface(s, _square(), [(_hole((0.5, 0.5), 0.7),)])
    with pytest.raises(InvalidGeometryError, match="inner: expected a sequence of loops"):
        TrimmedSurface(s, _square(), _hole())
    with pytest.raises(ParameterError, match="finite"):
        _plate().classify(np.nan, 0.5)


def test_tolerance_override_changes_the_boundary_band():
    t = _plate()
    u, v = 0.5 + R + 1e-5, 0.5
    assert t.classify(u, v) == INSIDE
    with tolerances.override(TRIM_ON=1e-4):
        assert _plate().classify(u, v) == ON
    with tolerances.override(TRIM_POLYLINE=1e-3):
        coarse = _plate().polylines()
    assert len(coarse[1]) < len(t.polylines()[1])


def test_curvature_map_and_flags_respect_the_trims():
    from occsurf.algorithms.quality import curvature_map, face_flags

    t = TrimmedSurface(_dome(), _square(), [(_hole(),)])
    cm = curvature_map(t, 21, 21, "mean")
    g = np.linspace(0, 1, 21)
    on_face = t.contains(*np.meshgrid(g, g, indexing="ij"))
    assert not on_face.all() and on_face.any()
    assert np.array_equal(cm.mask, on_face)
    assert np.all(np.isnan(cm.values[~on_face]))
    plain = curvature_map(t.surface, 21, 21, "mean")
    assert_allclose(cm.values[on_face], plain.values[on_face], rtol=1e-14, atol=0)
    extra = np.zeros((21, 21), bool)
    extra[:10] = True
    assert np.array_equal(curvature_map(t, 21, 21, mask=extra).mask, on_face & extra)
    assert isinstance(face_flags(t, us=g, vs=g), list)


def test_docstring_example_runs():
    import doctest

    from occsurf.algorithms.kernel import trimmed

    assert doctest.testmod(trimmed, verbose=False).failed == 0


def test_trimmed_surface_is_a_lazy_top_level_name():
    """``occsurf.TrimmedSurface`` like the other top-level names: in ``__all__``, the algorithms'
    class, and resolving it loads neither OCC nor the bridge."""
    import json
    import subprocess
    import sys

    import occsurf
    from occsurf.algorithms import TrimmedSurface

    assert "TrimmedSurface" in occsurf.__all__ and occsurf.TrimmedSurface is TrimmedSurface
    code = ("import json, sys, occsurf; before = 'occsurf.algorithms' in sys.modules; occsurf.TrimmedSurface; "
            "print(json.dumps([before] + [m in sys.modules for m in ('occsurf.algorithms', 'OCP', 'occsurf.bridge')]))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=True)
    assert json.loads(out.stdout) == [False, True, False, False]


def test_the_same_trim_on_another_surface_of_the_domain_keeps_its_drawn_loops():
    """``on_surface``: the trim moved to another surface of the same domain (a plate fill's next
    stage) classifies, evaluates and measures as a TrimmedSurface made afresh there, sharing the
    polylines and binned segments already drawn; another domain or a non-surface is refused."""
    face = _plate()
    rng = np.random.default_rng(5)
    u, v = rng.uniform(-0.1, 1.1, 4000), rng.uniform(-0.1, 1.1, 4000)
    first = face.classify(u, v)
    other = _dome()
    moved = face.on_surface(other)
    fresh = TrimmedSurface(other, face.outer, list(face.inner))
    assert moved.surface is other and moved.loops == face.loops and moved._cache is face._cache
    np.testing.assert_array_equal(moved.classify(u, v), fresh.classify(u, v))
    np.testing.assert_array_equal(moved.classify(u, v), first)
    assert moved.area() == fresh.area()
    for p_moved, p_fresh in zip(moved.polylines(), fresh.polylines()):
        np.testing.assert_array_equal(p_moved, p_fresh)
    wider = BSplineSurface((1, 1), ([0, 0, 2, 2], [0, 0, 1, 1]), np.zeros((2, 2, 3)))
    with pytest.raises(InvalidGeometryError, match="expected the domain"):
        face.on_surface(wider)
    with pytest.raises(InvalidGeometryError, match="expected a BSplineSurface"):
        face.on_surface(face)


@test_settings(max_examples=30)
@given(seed=st.integers(0, 2**16), holes=st.integers(0, 60), tol=st.sampled_from([0.0, 1e-6, 1e-3]))
@pytest.mark.parametrize("block", [1 << 20, 97, 1])
def test_segment_bands_in_int32_are_the_int64_bands(seed, holes, tol, block):
    """Issue 28 (memory): ``segment_bands`` keeps its entries' segment ids as int32 and places them
    into their bands a block of entries at a time (a face with 361 holes: ~6e6 entries; +345 MB of
    int64 temporaries, then +224 MB sorting them all at once). The bands are the ones the int64
    construction and one stable sort of all entries give, entry for entry, whatever the block."""
    from unittest import mock

    from occsurf.algorithms.kernel import point_in_loops
    from occsurf.algorithms.kernel.point_in_loops import segment_bands

    rng = np.random.default_rng(seed)
    loops = _round_holes(rng, holes, int(rng.integers(5, 200)))
    A = np.concatenate([p[:-1] for p in loops])
    B = np.concatenate([p[1:] for p in loops])
    with mock.patch.object(point_in_loops, "_BAND_BLOCK", block):
        bands = segment_bands(A, B, tol)
    assert bands.seg_sorted.dtype == np.int32
    ylo, yhi = np.minimum(A[:, 1], B[:, 1]) - tol, np.maximum(A[:, 1], B[:, 1]) + tol
    b0 = np.clip(((ylo - bands.y0) / bands.h).astype(np.int64), 0, bands.nb - 1)
    b1 = np.clip(((yhi - bands.y0) / bands.h).astype(np.int64), 0, bands.nb - 1)
    cnt = b1 - b0 + 1
    seg_of = np.repeat(np.arange(len(A)), cnt)
    band_of = np.repeat(b0, cnt) + (np.arange(cnt.sum()) - np.repeat(np.cumsum(cnt) - cnt, cnt))
    order = np.argsort(band_of, kind="stable")
    assert np.array_equal(bands.seg_sorted, seg_of[order])
    assert np.array_equal(bands.start, np.searchsorted(band_of[order], np.arange(bands.nb + 1)))


@test_settings(max_examples=25)
@given(seed=st.integers(0, 2**16), holes=st.integers(0, 40), tol=st.sampled_from([0.0, 1e-6, 1e-3]))
@pytest.mark.parametrize("block", [1 << 20, 97])
def test_bands_of_polylines_end_to_end_are_the_bands_of_their_segments(seed, holes, tol, block):
    """Issue 28 (memory): a trim's polylines lie end to end in one array, and the classification's
    segments are two views of it (``P[:-1] -> P[1:]``) with the steps from one loop to the next
    left out (``keep``), where each loop's segments were copied twice before. The bands are those of
    the loops' segments alone (the same bands, the same entries in the same order, numbered among
    all), so every point is classified as before, bit for bit."""
    from unittest import mock

    from occsurf.algorithms.kernel import point_in_loops
    from occsurf.algorithms.kernel.point_in_loops import segment_bands

    rng = np.random.default_rng(seed)
    loops = _round_holes(rng, holes, int(rng.integers(5, 120)))
    A = np.concatenate([p[:-1] for p in loops])
    B = np.concatenate([p[1:] for p in loops])
    P = np.concatenate(loops)
    keep = np.ones(len(P) - 1, bool)
    keep[np.cumsum([len(p) for p in loops])[:-1] - 1] = False
    with mock.patch.object(point_in_loops, "_BAND_BLOCK", block):
        apart = segment_bands(A, B, tol)
        joined = segment_bands(P[:-1], P[1:], tol, keep=keep)
    assert (joined.y0, joined.y1, joined.h, joined.nb) == (apart.y0, apart.y1, apart.h, apart.nb)
    assert np.array_equal(joined.start, apart.start)
    assert np.array_equal(np.flatnonzero(keep)[apart.seg_sorted], joined.seg_sorted)
    Q = np.r_[rng.uniform(-1, 11, (600, 2)), A[rng.integers(0, len(A), 80)]]  # on the loops too
    assert np.array_equal(classify_points(Q, bands=joined), classify_points(Q, A, B, tol))


def test_a_trim_holds_its_polylines_once():
    """The polylines a trim hands out and the segments it classifies with are views of one array of
    points (a face with 361 holes held three copies of its 1.5 million points before), and its
    classification is that of the loops' segments taken apart."""
    t = _plate()
    lines = t.polylines()
    pts, _ = t._points(t._tol(None, tolerances.TRIM_POLYLINE, "tol"))
    assert all(np.shares_memory(p, pts) for p in lines)
    with pytest.raises(ValueError, match="read-only"):  # changed in place, it would change the classification
        lines[0][0, 0] += 0.1
    A, B, keep = t._segments(t._tol(None, tolerances.TRIM_POLYLINE, "tol"))
    assert np.shares_memory(A, pts) and np.shares_memory(B, pts) and keep.sum() == sum(len(p) - 1 for p in lines)
    u, v = np.meshgrid(np.linspace(-0.1, 1.1, 61), np.linspace(-0.1, 1.1, 57), indexing="ij")
    on = tolerances.TRIM_ON * t._diag()
    want = classify_points(np.c_[u.ravel(), v.ravel()], np.concatenate([p[:-1] for p in lines]),
                           np.concatenate([p[1:] for p in lines]), on)
    (u0, u1), (v0, v1) = t.domain
    want[(u.ravel() < u0 - on) | (u.ravel() > u1 + on) | (v.ravel() < v0 - on) | (v.ravel() > v1 + on)] = OUTSIDE
    assert np.array_equal(t.classify(u, v).ravel(), want)


def test_segment_bands_take_a_bool_mask_of_the_segments():
    """``keep`` is one bool per segment: an index list (read as a mask it would keep other segments)
    or a mask of another length is refused by name."""
    from occsurf.algorithms.kernel.point_in_loops import segment_bands

    P = np.array([[0, 0], [1, 0], [1, 1], [0, 0], [2, 2], [3, 2], [2, 3], [2, 2]], float)
    for bad in ([0, 2, 3], np.ones(6, bool), np.ones(8, bool)):
        with pytest.raises(InvalidGeometryError, match="keep: expected a bool mask of shape"):
            segment_bands(P[:-1], P[1:], keep=bad)
    keep = np.ones(7, bool)
    keep[3] = False
    assert segment_bands(P[:-1], P[1:], keep=keep).seg_sorted.max() == 6
