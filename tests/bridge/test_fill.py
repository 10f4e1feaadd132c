"""Tests of bridge/modeling/fill.py: holes found in OCC shells, filled, assessed by OCC, compared with
BRepOffsetAPI_MakeFilling.

Tolerances: OCC's LocalAnalysis G0 gap between our fill and the neighbour is round-off (measured
<= 4e-14 on models of size ~14), asserted <= 1e-9 of the model size (the issue's target); its G1
angle is round-off too (<= 1.2e-10 deg measured), asserted <= 1e-6 deg. OCC's filler on the same
holes measured 0.8-5.5 deg and 2e-4-4e-3 gaps: the comparison asserts ours is at least 1000x better
in angle, not a fixed OCC value (OCC may improve).
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from occsurf.algorithms.errors import InvalidGeometryError
from occsurf.bridge.conversion.splines import make_face
from occsurf.bridge.exchange.step_iges import read_step, write_step
from occsurf.bridge.modeling.fill import edge_face_map, fill_model, find_loops, hole_sides, neighbour_face, sew_faces
from occsurf.examples.hole_models import ring_model

SIZE = 14.0  # bounding-box diagonal of the base dome ([0, 10]^2, height ~5)


def _shell(*models):
    return sew_faces([make_face(f, 1e-7) for m in models for f in m.faces])


@pytest.fixture(scope="module")
def two_holes():
    a = ring_model(5, rational=True, center=(0.3, 0.5), radius=0.12, width=0.08)
    b = ring_model(7, center=(0.72, 0.5), radius=0.12, width=0.08)
    return fill_model(_shell(a, b))


def test_every_hole_filled_g1_by_occ_measure(two_holes) -> None:
    holes = [h for h in two_holes.holes if h.status != "outer"]
    assert sorted(h.sides for h in holes) == [5, 7]
    assert all(h.status == "filled" for h in holes)
    for h in holes:
        assert len(h.side_g0) == h.sides
        assert h.g0 <= 1e-9 * SIZE and h.own_g0 <= 1e-9 * SIZE
        assert h.g1 <= 1e-6 and h.own_g1 <= 1e-6 and h.internal_g1 <= 1e-6


def test_outer_boundaries_are_left_open_and_holes_closed(two_holes) -> None:
    outer = [h for h in two_holes.holes if h.status == "outer"]
    assert len(outer) == 2 and all(h.reason for h in outer)
    assert two_holes.free_loops_after == 2  # only the two rings' outer loops remain free


def test_occ_filler_compared_on_the_same_holes(two_holes) -> None:
    for h in two_holes.holes:
        if h.status == "outer":
            continue
        assert h.occ_status in ("ok", "failed")
        assert h.occ_seconds is not None and h.occ_seconds >= 0
        if h.occ_status == "ok":
            assert h.g1 * 1000 < h.occ_g1
        else:
            assert h.occ_reason


def test_filled_model_round_trips_through_step(two_holes, tmp_path) -> None:
    p = write_step(tmp_path / "filled.step", two_holes.shape)
    model = read_step(p)
    assert len(model.faces) == 5 + 7 + 5 + 7  # the rings plus one patch per corner
    sewn = sew_faces([f.face for f in model.faces])
    assert len(find_loops(sewn, all_loops=True)) == 2  # the two rings' outer loops, nothing else


def test_missing_neighbour_face_is_a_clear_error() -> None:
    m = ring_model(4)
    shell = _shell(m)
    loops = [edges for edges, outer in find_loops(shell) if not outer]
    e2f = edge_face_map(shell)
    faces = [neighbour_face(e2f, e) for e in loops[0]]
    faces[2] = None
    with pytest.raises(InvalidGeometryError, match="no neighbour face"):
        hole_sides(loops[0], faces)


def test_unfillable_hole_is_reported_and_others_still_filled() -> None:
    """A reflex corner (interior angle above 180 deg) is refused by the central split with both
    side constructions (the exact iso-line sides and the fitted ones); the plate then fills it
    (tests/bridge/test_plate_refill.py measures it); the other hole is filled as before."""
    good = ring_model(3, center=(0.3, 0.5), radius=0.1, width=0.08)
    reflex = np.array([[0.6, 0.4], [0.8, 0.4], [0.73, 0.5], [0.8, 0.6], [0.6, 0.6]])
    bad = ring_model(5, polygon=reflex, bump=0.0, radius=0.1, width=0.08)
    res = fill_model(_shell(good, bad), compare_occ=False)
    holes = {h.sides: h for h in res.holes if h.status != "outer"}
    assert holes[3].status == "filled" and holes[3].construction == "iso"
    assert holes[5].status == "filled" and holes[5].method == "plate" and holes[5].folds == 0, holes[5].reason


def test_flat_corner_hole_is_filled_g1_by_occ_measure() -> None:
    """Two sides of a hole meeting tangentially (a flat corner, once refused): filled from the exact
    iso-line sides; OCC's LocalAnalysis finds no normal at the degenerate patch corner itself (it
    is skipped there, as at a pole) and G1 to round-off elsewhere (1e-6 deg as above)."""
    sq = np.array([[0.6, 0.4], [0.8, 0.4], [0.8, 0.5], [0.8, 0.6], [0.6, 0.6]])
    flat = ring_model(5, polygon=sq, bump=0.0, radius=0.1, width=0.08)
    res = fill_model(_shell(flat), compare_occ=False)
    [hole] = [h for h in res.holes if h.status != "outer"]
    assert hole.status == "filled" and hole.construction == "iso", hole.reason
    assert hole.g0 <= 1e-9 * SIZE and hole.g1 <= 1e-6
    assert res.fills[hole.index].flat.tolist() == [False, False, True, False, False]


def _trimmed_ring(ext: float):
    """A 5-sided hole whose neighbour faces use only part of their B-spline surfaces (UV bounds
    u in [s0, s1]; the hole edges lie on the surfaces' v = 0 boundary for that range only)."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace

    from occsurf.algorithms.kernel.surface import BSplineSurface
    from occsurf.bridge.conversion.splines import to_occ
    from occsurf.examples.hole_models import base_surface, represent_grid

    G = base_surface(False)
    m = ring_model(5, bump=0.0)
    s0, s1 = ext / (1 + 2 * ext), (1 + ext) / (1 + 2 * ext)
    K = np.r_[[0.0] * 7, [1.0] * 7]
    faces = []
    for i in range(5):
        a, b = m.hole[i], m.hole[(i + 1) % 5]
        A, B = m.outer[i], m.outer[(i + 1) % 5]
        a2, b2, A2, B2 = a - ext * (b - a), b + ext * (b - a), A - ext * (B - A), B + ext * (B - A)

        def fn(s, t, a2=a2, b2=b2, A2=A2, B2=B2):
            S, T = np.meshgrid(s, t, indexing="ij")
            xy = [(1 - T) * ((1 - S) * a2[c] + S * b2[c]) + T * ((1 - S) * A2[c] + S * B2[c]) for c in (0, 1)]
            return G.evaluate(*xy)

        srf = BSplineSurface((6, 6), (K, K), represent_grid(fn, (6, 6), (K, K)))
        faces.append(BRepBuilderAPI_MakeFace(to_occ(srf), s0, s1, 0.0, 1.0, 1e-7).Face())
    return sew_faces(faces)


def test_neighbours_trimmed_by_uv_bounds_are_filled() -> None:
    """Review: the whole B-spline surface of each neighbour was used, so its iso-boundary ran past
    the hole's corners and the loop was refused as 'not closed'."""
    res = fill_model(_trimmed_ring(0.25), compare_occ=False)
    holes = [h for h in res.holes if h.status != "outer"]
    assert [h.status for h in holes] == ["filled"], holes[0].reason
    assert holes[0].g0 <= 1e-9 * SIZE and holes[0].g1 <= 1e-6


def test_a_face_outside_any_shell_has_its_loops_found() -> None:
    """Review: only shells were searched, so a lone face beside a shell (or alone) had no loops."""
    from OCP.BRep import BRep_Builder
    from OCP.TopoDS import TopoDS_Compound

    shell = _shell(ring_model(5))
    lone = make_face(ring_model(3, center=(0.2, 0.2), radius=0.05, width=0.04).faces[0], 1e-7)
    comp = TopoDS_Compound()
    b = BRep_Builder()
    b.MakeCompound(comp)
    b.Add(comp, shell)
    b.Add(comp, lone)
    assert len(find_loops(comp)) == len(find_loops(shell)) + 1
    assert len(find_loops(lone)) == 1


def _face_with_round_hole(radius: float, bump: float):
    """A bicubic B-spline face over [-2, 2]^2 (z = bump (x^2 + y^2) / 8, exact in the cubic space:
    a polynomial of degree 2 in x and y) with a circular hole of ``radius`` about the origin, cut by
    a wire whose edge is the circle's projection onto the surface (a trimming curve: no iso-line)."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeEdge, BRepBuilderAPI_MakeFace, BRepBuilderAPI_MakeWire
    from OCP.Geom2d import Geom2d_Circle
    from OCP.gp import gp_Ax2d, gp_Dir2d, gp_Pnt2d
    from OCP.ShapeFix import ShapeFix_Face

    from occsurf.algorithms.kernel.surface import BSplineSurface
    from occsurf.bridge.conversion.splines import to_occ

    K = np.r_[[0.0] * 4, [1.0] * 4]
    t = np.linspace(-2, 2, 4)  # the Bézier poles of x, y (linear) and of x^2 (1/3 rule)
    q = np.array([4.0, -4.0 / 3.0 * 1, -4.0 / 3.0 * 1, 4.0])  # poles of x^2 on [-2, 2]: 4, -4/3, -4/3, 4
    X, Y = np.meshgrid(t, t, indexing="ij")
    Z = bump * (q[:, None] + q[None, :]) / 8.0
    srf = BSplineSurface((3, 3), (K, K), np.stack([X, Y, Z], -1))
    occ = to_occ(srf)
    circle = Geom2d_Circle(gp_Ax2d(gp_Pnt2d(0.5, 0.5), gp_Dir2d(1.0, 0.0)), radius / 4.0)
    edge = BRepBuilderAPI_MakeEdge(circle, occ).Edge()
    hole = BRepBuilderAPI_MakeWire(edge).Wire()
    mk = BRepBuilderAPI_MakeFace(occ, 1e-9)
    mk.Add(TopoDS_reversed(hole))
    fix = ShapeFix_Face(mk.Face())
    fix.Perform()
    from OCP.BRepLib import BRepLib
    from OCP.GeomAbs import GeomAbs_Shape

    face = fix.Face()
    BRepLib.BuildCurves3d_s(face, 1e-10, GeomAbs_Shape.GeomAbs_C2, 14, 64)
    return face


def TopoDS_reversed(shape):
    from OCP.TopoDS import TopoDS

    return TopoDS.Wire_s(shape.Reversed())


@pytest.mark.slow
@pytest.mark.parametrize("bump", [0.0, 1.0])
def test_round_hole_with_a_trimming_edge_is_capped(bump: float) -> None:
    """A plain ``fill`` of a one-sided hole whose edge is a trimming curve (course §8-3): the exact
    iso-line construction refuses, the fitted sides fill it (the circle cut into four at its
    quarters, four flat corners). G0: the edge's 3-D curve (OCC's approximation of the p-curve on
    the surface) is off the surface by 4.4e-6 measured, and the fill follows the edge; bound 1e-5.
    G1 (OCC LocalAnalysis): 0 on the plane, 2.7e-4 deg measured on the paraboloid, bound
    FILL_FIT_ANGLE. The cap lies on the surface it replaces: on the plane to round-off (bound 1e-12),
    within 1.6e-3 of the paraboloid z = (x^2 + y^2) / 8 measured at radius 0.5 (another G1 surface
    with the same boundary data), bound 2.4e-3; inside the circle; no fold.

    Which construction: the central split's cap (four patches, the cut points flat corners) is
    4.4e-6 off, above the issue's 1e-7 of the size, so ``fitted_fill`` tries the plate, which
    reads 5e-16 (plane) and 5.5e-7 (paraboloid; G1 4.5e-4 deg) and is kept: the same bounds
    apply to either, checked on the surface inside its trim."""
    from occsurf.algorithms import tolerances

    face = _face_with_round_hole(0.5, bump)
    res = fill_model(face, compare_occ=True)
    holes = [h for h in res.holes if h.status != "outer"]
    assert len(holes) == 1
    [h] = holes
    assert h.sides == 1 and h.status == "filled" and h.construction == "fitted", h.reason
    assert h.g0 <= 1e-5 and h.g1 <= tolerances.FILL_FIT_ANGLE and h.folds == 0
    fill = res.fills[h.index]
    if h.method == "central":
        assert len(fill.patches) == 4 and fill.flat.all()
        uv = np.linspace(0, 1, 21)
        P = np.concatenate([p.evaluate(uv[:, None], uv[None, :]).reshape(-1, 3) for p in fill.patches])
    else:
        assert h.method == "plate" and len(fill.patches) == 1
        (u0, u1), (v0, v1) = fill.surface.domain
        U, V = np.meshgrid(np.linspace(u0, u1, 61), np.linspace(v0, v1, 61), indexing="ij")
        inside = fill.trimmed.contains(U.ravel(), V.ravel())
        assert inside.sum() > 1000  # the disc covers ~pi/4 of its box
        P = fill.surface.evaluate(U.ravel()[inside], V.ravel()[inside])
    dev = np.abs(P[:, 2] - bump * (P[:, 0] ** 2 + P[:, 1] ** 2) / 8.0).max()
    assert dev <= (1e-12 if bump == 0 else 2.4e-3)
    assert np.hypot(P[:, 0], P[:, 1]).max() <= 0.5 + 1e-5


def _nearest_boundary_by_sampling_all(surf, pts):
    """The first choice of ``_iso_side`` as first written: every boundary sampled at 201 points."""
    from occsurf.algorithms.topology.nsided import side_from_surface

    cands = []
    for e in ("u0", "u1", "v0", "v1"):
        c = side_from_surface(surf, e).curve
        dense = c.evaluate(np.linspace(*c.domain, 201))
        cands.append((float(np.sqrt(((pts[:, None] - dense[None]) ** 2).sum(-1).min(axis=1)).max()), e))
    return min(cands, key=lambda c: c[0])[1]


@given(seed=st.integers(0, 2 ** 16), rational=st.booleans(), edge=st.sampled_from(["u0", "u1", "v0", "v1"]),
       part=st.tuples(st.floats(0.0, 0.4), st.floats(0.6, 1.0)), collapse=st.booleans(), bend=st.floats(0.0, 3.0),
       scatter=st.sampled_from([0.0, 0.0, 0.1, 0.5, 1.5]))
@settings(max_examples=80, deadline=None)
def test_nearest_boundary_samples_only_boundaries_that_could_win(seed, rational, edge, part, collapse, bend, scatter):
    """_nearest_boundary samples a boundary only when its poles' box is no farther from the edge points than
    the best boundary sampled so far: on surfaces bent onto themselves (boundaries close together),
    with a boundary collapsed to a point, the edge covering part of a boundary and points scattered
    off it (where several boundaries come close), it picks the boundary that sampling all four picks
    (the first of equals)."""
    from occsurf.algorithms import BSplineSurface
    from occsurf.algorithms.topology.nsided import boundary_curve
    from occsurf.bridge.modeling.fill import _nearest_boundary

    rng = np.random.default_rng(seed)
    nu, nv = 4 + int(rng.integers(0, 3)), 4 + int(rng.integers(0, 3))
    U, V = np.meshgrid(np.linspace(0, 1, nu), np.linspace(0, 1, nv), indexing="ij")
    P = np.stack([np.cos(bend * U) * (1 + V), np.sin(bend * U) * (1 + V), 0.3 * V], -1)
    P += 0.05 * rng.normal(size=P.shape)
    if collapse:
        P[:, 0] = P[:, 0].mean(axis=0)  # boundary v0 a pole
    w = rng.uniform(0.5, 2.0, (nu, nv)) if rational else None
    kn = lambda n: np.r_[[0.0] * 4, np.linspace(0, 1, n - 2)[1:-1], [1.0] * 4]  # noqa: E731
    surf = BSplineSurface((3, 3), (kn(nu), kn(nv)), P, w)
    c = boundary_curve(surf, edge)
    pts = c.evaluate(np.linspace(*part, 41)) + scatter * rng.normal(size=(41, 3))  # off it too: close calls
    assume(float(np.ptp(pts, axis=0).max()) > 1e-6)  # not the collapsed boundary itself
    assert _nearest_boundary(surf, pts) == _nearest_boundary_by_sampling_all(surf, pts)
