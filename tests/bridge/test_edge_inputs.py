"""Every bridge function that takes an OCC edge or curve takes the edges build123d and cadquery users
hold (issue 16): build123d ``Edge`` / ``Wire``, cadquery ``Edge`` / ``Wire``, a ``TopoDS_Edge`` and a
``Geom_Curve``, through the coercions of :mod:`occsurf.bridge.conversion.shapes` (``as_edges``,
``as_edge``, ``as_curve``; ``as_face`` for the fill helpers' neighbour faces).

Each wrapper is checked against the call on the plain OCC object: the results must be *equal*
(the same curve is evaluated at the same parameters), not merely close.
"""

from __future__ import annotations

import numpy as np
import pytest

bd = pytest.importorskip("build123d")
cq = pytest.importorskip("cadquery")

from OCP.BRep import BRep_Tool  # noqa: E402
from OCP.TopoDS import TopoDS_Edge  # noqa: E402

from occsurf import bridge  # noqa: E402
from occsurf.algorithms import BSplineCurve  # noqa: E402
from occsurf.algorithms.errors import InvalidGeometryError  # noqa: E402
from occsurf.bridge.conversion.shapes import as_curve, as_edge, as_edges, as_face  # noqa: E402
from occsurf.bridge.conversion.splines import make_edge  # noqa: E402


def _curve() -> BSplineCurve:
    """A rational cubic with uneven knots (a double interior knot): every derivative compared matters."""
    P = np.array([[0, 0, 0], [1, 2, 0.5], [2, 2.5, 1], [3.5, 1, 0.2], [4, -1, 1.5], [5, 0, 0]], float)
    w = np.array([1, 0.8, 1.3, 1, 0.7, 1])
    return BSplineCurve(3, [0, 0, 0, 0, 0.3, 0.3, 1.2, 1.2, 1.2, 1.2], P, weights=w)


CURVE = _curve()


def _edge_objects() -> dict:
    occ = bridge.to_occ(CURVE)
    b3d, cqe = bridge.to_edge(CURVE), bridge.to_cq_edge(CURVE)
    return {
        "Geom_Curve": occ,
        "TopoDS_Edge": make_edge(CURVE),
        "b3d Edge": b3d,
        "b3d Wire": bd.Wire([b3d]),
        "b3d Compound": bd.Compound([b3d]),
        "cq Edge": cqe,
        "cq Wire": cq.Wire.assembleEdges([cqe]),
    }


OBJECTS = _edge_objects()


@pytest.mark.parametrize("kind", sorted(OBJECTS))
def test_curve_deviation_takes_every_edge_kind(kind):
    """curve_deviation(ours, X) equals curve_deviation(ours, the Geom_Curve) for every wrapper, field by
    field, and both are round-off (our evaluator and OCC's on identical data: 1e-14 of the size)."""
    plain = bridge.curve_deviation(CURVE, bridge.to_occ(CURVE), samples=41)
    got = bridge.curve_deviation(CURVE, OBJECTS[kind], samples=41)
    assert got == plain
    assert got.max_point_rel < 1e-14 and got.max_d3_rel < 1e-12


@pytest.mark.parametrize("kind", sorted(OBJECTS))
def test_edge_coercions(kind):
    obj = OBJECTS[kind]
    [edge] = as_edges(obj)
    assert isinstance(edge, TopoDS_Edge) and (kind == "Geom_Curve" or as_edge(obj).IsSame(edge))  # a curve: a new edge
    assert BRep_Tool.Curve_s(edge, 0.0, 0.0) is not None
    curve = as_curve(obj)
    assert bridge.from_occ(curve) == CURVE  # the same curve, bit for bit
    single = kind in ("Geom_Curve", "TopoDS_Edge", "b3d Edge", "cq Edge")
    assert bridge.from_occ(obj) == (CURVE if single else [CURVE])  # a container gives a list (from_occ's rule)


def test_native_build123d_and_cadquery_splines():
    """Edges the libraries make themselves: from_occ(edge), then curve_deviation against the edge, the
    same as against its Geom_Curve."""
    pts = [(0, 0, 0), (1, 2, 0.5), (3, 1, 1), (4, 3, -1), (6, 2, 0)]
    for edge in (bd.Edge.make_spline(pts), cq.Edge.makeSpline([cq.Vector(*p) for p in pts])):
        ours = bridge.from_occ(edge)
        dev = bridge.curve_deviation(ours, edge, samples=33)
        assert dev == bridge.curve_deviation(ours, BRep_Tool.Curve_s(edge.wrapped, 0.0, 0.0), samples=33)
        assert dev.max_point_rel < 1e-14


def test_the_edges_location_is_applied():
    """A moved edge stands for its moved curve (BRep_Tool.Curve_s applies the location): it matches our
    curve translated likewise, and not the unmoved one."""
    shift = np.array([1.0, -2.0, 3.0])
    moved = bridge.to_edge(CURVE).moved(bd.Location(tuple(shift)))
    translated = BSplineCurve(CURVE.degree, CURVE.knots, CURVE.control_points + shift, weights=CURVE.weights)
    assert bridge.curve_deviation(translated, moved).max_point < 1e-13
    assert bridge.curve_deviation(CURVE, moved).max_point == pytest.approx(np.linalg.norm(shift), rel=1e-12)
    cq_moved = bridge.to_cq_edge(CURVE).moved(cq.Location(cq.Vector(*shift)))
    assert bridge.curve_deviation(translated, cq_moved) == bridge.curve_deviation(translated, moved)


def test_what_is_not_one_edge_is_refused_naming_the_argument():
    two = bd.Wire([bridge.to_edge(CURVE), bd.Edge.make_line((5, 0, 0), (6, 0, 0))])
    with pytest.raises(InvalidGeometryError, match=r"occ_curve: expected one edge .* Wire with 2 edges"):
        bridge.curve_deviation(CURVE, two)
    with pytest.raises(InvalidGeometryError, match=r"occ_curve: expected one edge .* with 4 edges"):
        bridge.curve_deviation(CURVE, bd.Face.make_rect(1, 2))
    with pytest.raises(InvalidGeometryError, match="occ_curve: expected a Geom_Curve or an edge .* got str"):
        bridge.curve_deviation(CURVE, "edge")
    from OCP.TopAbs import TopAbs_EDGE
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopoDS import TopoDS

    ex = TopExp_Explorer(bd.Sphere(1).wrapped, TopAbs_EDGE)
    while not BRep_Tool.Degenerated_s(TopoDS.Edge_s(ex.Current())):
        ex.Next()
    pole = bd.Edge(TopoDS.Edge_s(ex.Current()))  # a sphere's pole: an edge without a 3-D curve
    with pytest.raises(InvalidGeometryError, match="no 3-D curve"):
        bridge.curve_deviation(CURVE, pole)
    from OCP.Geom import Geom_Line
    from OCP.gp import gp_Dir, gp_Pnt

    with pytest.raises(InvalidGeometryError, match="unbounded"):
        as_edges(Geom_Line(gp_Pnt(0, 0, 0), gp_Dir(1, 0, 0)))
    with pytest.raises(InvalidGeometryError, match="holds no edges"):
        as_edges(bd.Vertex(0, 0, 0))
    with pytest.raises(InvalidGeometryError, match="expected one face"):
        as_face(bd.Box(1, 1, 1))


def test_make_edge_to_edge_to_cq_edge_take_edges():
    """An edge given to make_edge / to_edge / to_cq_edge is that edge: build123d <-> cadquery for free."""
    b3d, cqe = bridge.to_edge(CURVE), bridge.to_cq_edge(CURVE)
    assert bridge.to_edge(cqe).wrapped.IsSame(cqe.wrapped)
    assert bridge.to_cq_edge(b3d).wrapped.IsSame(b3d.wrapped)
    assert make_edge(bd.Wire([b3d])).IsSame(b3d.wrapped)
    assert make_edge(b3d.wrapped).IsSame(b3d.wrapped)
    with pytest.raises(InvalidGeometryError, match="expected one edge"):
        bridge.to_edge(bd.Box(1, 1, 1))


def test_is_reversed_and_writers_take_build123d_and_cadquery_edges(tmp_path):
    """is_reversed and write_step already took edges through as_shape: the wrappers give what the
    TopoDS_Edge gives (the curve written and read back: the same B-spline to STEP's digits)."""
    edge = make_edge(CURVE)
    flipped = edge.Reversed()
    for wrap in (bd.Edge, cq.Edge):
        assert bridge.is_reversed(wrap(flipped)) and not bridge.is_reversed(wrap(edge))
    path = tmp_path / "edge.step"
    bridge.write_step(path, [bd.Edge(edge), cq.Wire.assembleEdges([cq.Edge(edge)])])
    back = bridge.read_step(path)
    curves = [bridge.from_occ(e.edge) for e in back.edges]
    assert len(curves) == 2
    for c in curves:
        assert np.allclose(c.control_points, CURVE.control_points, rtol=0, atol=1e-12)


# ------------------------------------------------------------------------------------ the fill's helpers
@pytest.fixture(scope="module")
def open_ball():
    """A sphere of radius 5 cut into 8 faces without the 4 above z = 3: one 4-sided hole whose
    neighbours are smooth (as in test_shape_inputs)."""
    from occsurf.bridge.modeling.fill import edge_face_map, find_loops, neighbour_face

    faces = [bd.Sphere(5).faces()[0]]
    for plane in (bd.Plane.XZ, bd.Plane.YZ, bd.Plane.XY.offset(3)):
        faces = [g for f in faces for half in f.split(plane, keep=bd.Keep.BOTH) for g in half.faces()]
    shell = bd.Shell([f for f in faces if f.center().Z < 3])
    [(edges, _)] = find_loops(shell.wrapped)
    m = edge_face_map(shell.wrapped)
    return shell, edges, [neighbour_face(m, e) for e in edges]


def test_fill_helpers_take_build123d_and_cadquery_edges_and_faces(open_ball):
    from occsurf.bridge.modeling.fill import (
        assess_joint,
        edge_face_map,
        find_loops,
        hole_sides,
        neighbour_face,
        occ_fill,
    )

    shell, edges, faces = open_ball
    b3d_edges, b3d_faces = [bd.Edge(e) for e in edges], [bd.Face(f) for f in faces]
    cq_edges, cq_faces = [cq.Edge(e) for e in edges], [cq.Face(f) for f in faces]
    assert [len(loop) for loop, _ in find_loops(shell)] == [len(loop) for loop, _ in find_loops(cq.Shell(shell.wrapped))] == [4]
    m_b3d = edge_face_map(shell)
    for _e, b, c, f in zip(edges, b3d_edges, cq_edges, faces):
        assert neighbour_face(m_b3d, b).IsSame(f) and neighbour_face(m_b3d, c).IsSame(f)
    plain = hole_sides(edges, faces)
    for es, fs in ((b3d_edges, b3d_faces), (cq_edges, cq_faces), ([bd.Wire([e]) for e in b3d_edges], b3d_faces)):
        got = hole_sides(es, fs)
        assert all(a.curve == b.curve and a.cross == b.cross for a, b in zip(got, plain))
    fill = occ_fill(edges, faces)
    area = bd.Face(fill).area
    assert bd.Face(occ_fill(b3d_edges, b3d_faces)).area == area == bd.Face(occ_fill(cq_edges, cq_faces)).area
    assert 0 < area < 4 * np.pi * 25
    surfaces = [BRep_Tool.Surface_s(fill)]
    ref = assess_joint(edges[0], faces[0], surfaces, samples=9)
    assert assess_joint(b3d_edges[0], b3d_faces[0], surfaces, samples=9) == ref
    assert assess_joint(cq_edges[0], cq_faces[0], surfaces, samples=9) == ref
    with pytest.raises(InvalidGeometryError, match=r"faces\[0\]: expected one face"):
        hole_sides(b3d_edges, [shell] + b3d_faces[1:])
