"""Folds of the central split on long, curved and thin holes (issue 12; algorithms/topology/nsided.py).

A fill that turns back over itself (:func:`count_folds` > 0) is unusable however good its boundary
G0/G1. Closed forms: every hole here lies in the plane z = 0 with in-plane cross fields, so its exact
fill is the plane and any fold is the construction's fault; the fill stays in the plane (|z| <= 1e-13,
as in test_nsided_split.py) and a fold shows as a sign change of the z-component of S_u x S_v.

Tolerances as in test_nsided_split.py: gaps 1e-11 of the hole size (the side curves are the boundary
rows of poles: round-off), angles 1e-6 deg (G1 by construction).

Measured before the harmonic layout (folded grid pairs, 41 x 41 per patch; sectors between r0 and 2):
120 deg r0 = 1.6: 236; 150 deg r0 = 1.5: 156; 100 deg r0 = 1.7: 78; 120 deg r0 = 1.0: 90; 68 deg
r0 = 1.5: 20 (a convex-enough sector whose plain layout folds); 90 deg r0 = 1.25: 50. After: 0. The harmonic centre of a sector lies on its bisector
by symmetry (up to the grid's asymmetry: <= 2 % of the width measured 0.3 %).
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from occsurf.algorithms.kernel.curve import BSplineCurve
from occsurf.algorithms.topology.nsided import HoleSide, count_folds, fill_hole, measure_fill
from occsurf.algorithms.topology.nsided_loops import harmonic_centre
from occsurf.algorithms.topology.nsided_sides import side_from_normals

GAP_REL = 1e-11
ANGLE_DEG = 1e-6
UV = np.linspace(0.0, 1.0, 41)


def _line(a, b) -> BSplineCurve:
    return BSplineCurve(1, [0, 0, 1, 1], np.array([a, b], float))


def _arc(radius: float, a0: float, a1: float) -> BSplineCurve:
    """A planar circular arc from angle a0 to a1: one rational quadratic span (|a1 - a0| < 180 deg;
    several spans would need double knots, a C0 knot that fill_hole refuses)."""
    half, mid = 0.5 * (a1 - a0), 0.5 * (a0 + a1)
    P = radius * np.array([[np.cos(a0), np.sin(a0), 0.0], [np.cos(mid) / np.cos(half), np.sin(mid) / np.cos(half), 0.0],
                           [np.cos(a1), np.sin(a1), 0.0]])
    return BSplineCurve(2, [0, 0, 0, 1, 1, 1], P, np.array([1.0, np.cos(half), 1.0]))


def _planar(curve: BSplineCurve) -> HoleSide:
    """The side with the plane z = 0 (normal +z) as its neighbour (loop counter-clockwise about +z)."""
    s = np.linspace(*curve.domain, 64)
    fit = side_from_normals(curve, s, np.tile([0.0, 0.0, 1.0], (64, 1)))
    assert fit.angle <= 1e-12
    return fit.side


def _sector(span_deg: float, r0: float, r1: float = 2.0) -> list[HoleSide]:
    """An annular sector between radii r0 and r1, counter-clockwise."""
    a = np.radians(span_deg)
    return [_planar(_line([r0, 0, 0], [r1, 0, 0])), _planar(_arc(r1, 0.0, a)),
            _planar(_line([r1 * np.cos(a), r1 * np.sin(a), 0], [r0 * np.cos(a), r0 * np.sin(a), 0])),
            _planar(_arc(r0, a, 0.0))]


def _sliver(length: float, width: float, bend: float) -> list[HoleSide]:
    """A 3-sided sliver: a tip at the origin, a straight short side at x = length, two long sides
    bowed by ``bend`` (quadratic)."""
    A, B, C = np.zeros(3), np.array([length, -0.5 * width, 0.0]), np.array([length, 0.5 * width, 0.0])

    def quad(a, b):
        return BSplineCurve(2, [0, 0, 0, 1, 1, 1], np.array([a, 0.5 * (a + b) + [0.0, bend, 0.0], b]))
    return [_planar(quad(A, B)), _planar(_line(B, C)), _planar(quad(C, A))]


def _check_plane_fill(sides: list[HoleSide]):
    fill = fill_hole(sides)
    q = measure_fill(fill)
    assert q.boundary_gap.max() <= GAP_REL * fill.size and q.boundary_angle.max() <= ANGLE_DEG
    assert q.internal_angle.max() <= ANGLE_DEG and q.center_angle <= ANGLE_DEG
    nz = []
    for p in fill.patches:
        D = p.derivatives(np.repeat(UV, len(UV)), np.tile(UV, len(UV)), 1)
        assert np.abs(D[:, 0, 0, 2]).max() <= 1e-13  # the fill is the plane
        nz.append(np.cross(D[:, 1, 0], D[:, 0, 1])[:, 2])
    return fill, q, np.concatenate(nz)


@pytest.mark.parametrize("span, r0", [(120.0, 1.6), (150.0, 1.5), (100.0, 1.7), (120.0, 1.0)])
def test_annular_sector_does_not_fold(span: float, r0: float) -> None:
    fill, q, nz = _check_plane_fill(_sector(span, r0))
    assert q.folds.sum() == 0
    assert nz.min() > 0  # the Jacobian keeps its sign everywhere, boundary included


def test_sector_centre_is_on_its_bisector_in_the_middle_of_the_width() -> None:
    """By symmetry the harmonic map's centre lies on the bisector; radially it is within the ring."""
    span, r0 = 120.0, 1.6
    fill = fill_hole(_sector(span, r0))
    ang = np.degrees(np.arctan2(fill.center[1], fill.center[0]))
    r = np.hypot(fill.center[0], fill.center[1])
    assert abs(ang - 0.5 * span) <= np.degrees(0.02 * (2.0 - r0) / r)
    assert r0 + 0.25 * (2.0 - r0) < r < 2.0 - 0.25 * (2.0 - r0)


@pytest.mark.parametrize("bend", [0.0, 0.8, -0.8])
def test_long_thin_sliver_does_not_fold(bend: float) -> None:
    """A 3-sided sliver, 8 long and 0.6 wide (tip angle 4.3 deg), straight or bowed."""
    fill, q, nz = _check_plane_fill(_sliver(8.0, 0.6, bend))
    assert q.folds.sum() == 0 and nz.min() > 0


def test_harmonic_centre_of_a_square_is_its_centre_and_moves_rigidly() -> None:
    """A square onto the square domain, side for side: by symmetry the centre is the square's centre
    (to the grid's resolution: its spacing is ~1/63 of the side, bound 1e-2), and the inverse
    Jacobian there maps the domain's axes onto the square's (scale: side / domain side)."""
    t = np.linspace(0.0, 1.0, 65)[:-1, None]
    corners = np.array([[0, 0, 0], [2, 0, 0], [2, 2, 0], [0, 2, 0]], float)
    dom = np.array([[0.5, -0.5], [0.5, 0.5], [-0.5, 0.5], [-0.5, -0.5]])
    loop = np.concatenate([(1 - t) * corners[k] + t * corners[(k + 1) % 4] for k in range(4)])
    tgt = np.concatenate([(1 - t) * dom[k] + t * dom[(k + 1) % 4] for k in range(4)])
    normals = np.tile([0.0, 0.0, 1.0], (4, 1))
    c, nh, inv = harmonic_centre(loop, tgt, normals)
    np.testing.assert_allclose(c, [1, 1, 0], atol=1e-2)
    np.testing.assert_allclose(np.abs(nh), [0, 0, 1], atol=1e-12)
    np.testing.assert_allclose(inv, [[0, 2], [-2, 0], [0, 0]], atol=0.05)  # domain u -> -y, v -> +x
    # a rigid motion of the hole moves the centre with it
    R = np.array([[0.0, -0.6, 0.8], [1.0, 0.0, 0.0], [0.0, 0.8, 0.6]])
    shift = np.array([10.0, -3.0, 7.0])
    c2, nh2, inv2 = harmonic_centre(loop @ R.T + shift, tgt, normals @ R.T)
    np.testing.assert_allclose(c2, R @ c + shift, atol=1e-2)
    np.testing.assert_allclose(inv2, R @ inv, atol=0.05)


def test_harmonic_centre_of_a_degenerate_projection_is_none() -> None:
    loop = np.c_[np.linspace(0, 1, 20), np.zeros(20), np.zeros(20)]
    assert harmonic_centre(loop, np.zeros((20, 2)), np.tile([0.0, 0.0, 1.0], (3, 1))) is None


def _aspect(span: float, r0: float, r1: float = 2.0) -> float:
    """Length of a sector's middle arc over its width."""
    return np.radians(span) * 0.5 * (r0 + r1) / (r1 - r0)


@pytest.mark.slow
@settings(max_examples=12, deadline=None)
@given(span=st.floats(60.0, 160.0), r0=st.floats(1.0, 1.7))
def test_sectors_never_fold(span: float, r0: float) -> None:
    """Annular sectors from fat to thin and from short to 160 deg long, up to a length 10 times the
    width: no fold, the plane exactly.

    The claim was 11 times, from a 10 deg x 0.05 grid of span and r0 (first fold at aspect 11.8,
    150 deg x r0 = 1.6); hypothesis found a 156 deg sector folding at 10.66 (twice, in CI), and a
    0.5 deg x 0.0075 scan of 140..160 deg (aspect 9.8..11, 251 sectors) finds the first folds at
    aspect 10.58 (159.5 deg, r0 1.535), all at 156 deg or more, none below 150 deg. The central split
    folds there (a defect kept as strict xfails below, not fixed); 10 is the bound the scan supports."""
    assume(_aspect(span, r0) <= 10.0)
    fill, q, nz = _check_plane_fill(_sector(span, r0))
    assert q.folds.sum() == 0 and sum(count_folds(p) for p in fill.patches) == 0


@pytest.mark.xfail(strict=True, reason="the central split folds on sectors of 156 deg or more from aspect 10.58 on "
                   "(found by hypothesis: 156 deg, r0 1.546875, aspect 10.66, 4 grid pairs; by a scan: 159.5 deg, "
                   "r0 1.535, aspect 10.58, 24 grid pairs). Not fixed yet; the refill falls back to the plate there.")
@pytest.mark.parametrize(("span", "r0"), [(156.0, 1.546875), (159.5, 1.535)])
def test_long_sectors_below_aspect_11_do_not_fold(span: float, r0: float) -> None:
    assert 10.0 < _aspect(span, r0) < 11.0
    fill, q, nz = _check_plane_fill(_sector(span, r0))
    assert q.folds.sum() == 0 and sum(count_folds(p) for p in fill.patches) == 0


def test_very_long_thin_sector_still_folds_and_says_so() -> None:
    """The known limit: a 150 deg sector 0.25 wide (its middle arc 19 times its width) gets the right
    layout (centre on the bisector, internal edges along the harmonic curves) but the two patches on
    the outer arc fold near their internal edge (58 and 60 grid pairs measured): the cross fields
    along a 75 deg internal edge are cubic in the kite relation and cannot turn with it. Reported,
    never hidden; the bridge then prefers the trimmed plate."""
    assert _aspect(150.0, 1.75) > 17
    fill = fill_hole(_sector(150.0, 1.75))
    q = measure_fill(fill)
    assert abs(np.degrees(np.arctan2(fill.center[1], fill.center[0])) - 75.0) < 0.5
    assert q.boundary_gap.max() <= GAP_REL * fill.size and q.boundary_angle.max() <= ANGLE_DEG
    assert q.folds.sum() > 0


def test_the_fold_count_kept_with_a_fill_is_the_count_made_afresh() -> None:
    """``fill_hole`` and ``fill_plate`` keep the fold count they chose the fill by (``folds``), and
    ``fill_folds`` returns it instead of counting again (the bridge scores every candidate by its
    folds, then reports the winner's: each count was made two or three times). The kept number is
    the fresh count, on a fill that folds (the 150 deg sector) and on ones that do not."""
    from dataclasses import replace

    from occsurf.algorithms.topology.nsided import fill_folds
    from occsurf.algorithms.topology.plate_fill import fill_plate

    folded = fill_hole(_sector(150.0, 1.75))
    plain = fill_hole(_sector(90.0, 1.0))
    plate = fill_plate(_sector(150.0, 1.75))
    assert folded.folds is not None and folded.folds > 0 and plain.folds == 0 and plate.folds is not None
    for fill in (folded, plain, plate):
        assert fill_folds(fill) == fill.folds == fill_folds(replace(fill, folds=None))
    assert fill_folds(replace(folded, folds=None)) == sum(count_folds(p) for p in folded.patches)
    assert fill_folds(replace(plate, folds=None)) == count_folds(plate.trimmed)


@settings(max_examples=60, deadline=None)
@given(n=st.integers(3, 40), seed=st.integers(0, 2 ** 32 - 1), snap=st.booleans())
def test_grid_inside_is_the_crossing_number_of_every_node(n: int, seed: int, snap: bool) -> None:
    """``grid_inside`` (per grid row: the straddled edges' crossings, sorted) against the crossing
    number tested node by node against every edge, as ``harmonic_picture`` did: equal, node for
    node, on random polygons (self-intersecting ones too), with vertices on grid rows and columns
    (``snap``: the half-open rule's ties)."""
    from occsurf.algorithms.kernel.point_in_loops import grid_inside

    rng = np.random.default_rng(seed)
    gx, gy = np.linspace(-1.0, 1.0, 37), np.linspace(-1.2, 0.9, 23)
    poly = rng.uniform(-1.1, 1.1, (n, 2))
    if snap:
        poly[::2, 0] = gx[rng.integers(0, gx.size, poly[::2].shape[0])]
        poly[1::2, 1] = gy[rng.integers(0, gy.size, poly[1::2].shape[0])]
    G = np.stack(np.meshgrid(gx, gy, indexing="ij"), -1).reshape(-1, 2)
    a, b = poly, np.roll(poly, -1, axis=0)
    px, py = G[:, :1], G[:, 1:]
    with np.errstate(divide="ignore", invalid="ignore"):
        cross_x = a[:, 0] + (b[:, 0] - a[:, 0]) * (py - a[:, 1]) / (b[:, 1] - a[:, 1])
    every = ((((a[:, 1] > py) != (b[:, 1] > py)) & (px < cross_x)).sum(1) % 2 == 1).reshape(gx.size, gy.size)
    np.testing.assert_array_equal(grid_inside(poly, gx, gy), every)


def _loop(*corners: tuple[float, float]) -> list[BSplineCurve]:
    """The polygon through ``corners`` (counter-clockwise) as straight p-curves."""
    c = [*corners, corners[0]]
    return [BSplineCurve(1, [0, 0, 1, 1], [c[k], c[k + 1]]) for k in range(len(corners))]


def test_the_trim_is_consulted_only_where_normals_oppose(monkeypatch) -> None:
    """Issue 27: ``count_folds`` of a trimmed surface tests grid points against the trim only when
    some neighbouring normals oppose (a plate's stages were classified in full, 0.4 s of the screw
    run-out's fill, mostly to count 0). A cubic patch whose x doubles back along u near the corner
    (1, 1) folds there (every opposing pair has u + v >= 1.275 on the grid): the trim that holds it
    all counts what the untrimmed patch does, the triangle u + v <= 1 counts none (the trim
    consulted: its box holds the fold), and a patch without a fold leaves the trim alone."""
    from occsurf.algorithms.kernel.surface import BSplineSurface
    from occsurf.algorithms.kernel.trimmed import TrimmedSurface

    U, V = np.meshgrid(np.linspace(0, 1, 4), np.linspace(0, 1, 4), indexing="ij")
    X = U.copy()
    X[:, 2], X[:, 3] = [0, 1 / 3, 1.5, 0.6], [0, 1 / 3, 2.0, 0.2]
    knots = [0, 0, 0, 0, 1, 1, 1, 1]
    surf = BSplineSurface((3, 3), (knots, knots), np.stack([X, V, 0.1 * U * V], axis=-1))
    folded = count_folds(surf)
    assert folded > 0
    calls = []
    real = TrimmedSurface.contains

    def spy(self, *a, **k):
        calls.append(1)
        return real(self, *a, **k)

    monkeypatch.setattr(TrimmedSurface, "contains", spy)
    assert count_folds(TrimmedSurface(surf, _loop((0, 0), (1, 0), (1, 1), (0, 1)))) == folded and calls
    calls.clear()
    assert count_folds(TrimmedSurface(surf, _loop((0, 0), (1, 0), (0, 1)))) == 0 and calls
    calls.clear()
    flat = BSplineSurface((3, 3), (knots, knots), np.stack([U, V, 0.1 * U * V], axis=-1))
    assert count_folds(TrimmedSurface(flat, _loop((0, 0), (1, 0), (0, 1)))) == 0 and not calls
