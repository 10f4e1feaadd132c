"""Sewing a fill into a model whose hole edges carry a tolerance larger than ``SEW_TOLERANCE``
(bridge/modeling/refill_sewing._sew_in, plate.plate_face; issue 12: "the filled model must be a valid,
sewn shell").

Real case: linkrods' faces 17/19 meet their neighbours with edge tolerances up to 8.7e-5 (the
model's own gap; the fill follows the neighbours to within it). Sewn at ``SEW_TOLERANCE`` (1e-5)
the fill was left partly free (one fill edge beside two hole edges) and two neighbours' p-curves
were re-parametrised 5.7e-5 off their 3-D curves with tolerance 1.2e-7
(``BRepCheck_InvalidCurveOnSurface`` + ``InvalidSameParameterFlag`` -> faces unorientable:
``BRepCheck_Analyzer`` invalid); the same with linkrods [18, 19]. Sewn at twice the larger of
the fill's G0 and the hole edges' tolerance, both are valid and closed (measured).

Model here: the 4-sided ring of examples.hole_models (one bicubic dome) and its centre face, the
centre raised by DELTA = 6e-5 along z and sewn to the ring at 2e-4, so the hole edges carry about
DELTA of tolerance; the fill is the centre face lowered by DELTA (its edges lie DELTA from the
ring's and 2 DELTA from the centre's: whichever 3-D curve sewing kept for the hole edges, the
fill is more than SEW_TOLERANCE off it). With the sewing tolerance of before (SEW_GAP_FACTOR set
to 0: SEW_TOLERANCE) the hole stays open; with the gap-aware one it closes and the shell is valid.
End to end (refill_faces: the central split follows the ring's traces, G0 5.1e-7 from the ring,
~DELTA from the hole edges' 3-D curves): before, 13 free edges (the hole open: 4 expected, the
ring's outer loop); now 4.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from OCP.BRepCheck import BRepCheck_Analyzer
from OCP.ShapeAnalysis import ShapeAnalysis_FreeBounds
from OCP.TopAbs import TopAbs_EDGE
from OCP.TopExp import TopExp_Explorer

from occsurf.algorithms.errors import InvalidGeometryError
from occsurf.algorithms.kernel.surface import BSplineSurface
from occsurf.bridge.conversion.splines import make_face
from occsurf.bridge.modeling import refill, refill_sewing
from occsurf.bridge.modeling.fill import sew_faces
from occsurf.bridge.modeling.joints import SEW_TOLERANCE
from occsurf.bridge.modeling.plate import plate_face
from occsurf.examples.hole_models import represent_grid, ring_model

DELTA = 6e-5


def _centre(model, dz: float) -> BSplineSurface:
    """The dome over the hole quad (bilinear map of the domain, composed: exact), moved by dz."""
    G = model.base
    a, b, c, d = model.hole  # counter-clockwise

    def fn(s, t):
        S, T = np.meshgrid(s, t, indexing="ij")
        x = (1 - T) * ((1 - S) * a[0] + S * b[0]) + T * ((1 - S) * d[0] + S * c[0])
        y = (1 - T) * ((1 - S) * a[1] + S * b[1]) + T * ((1 - S) * d[1] + S * c[1])
        return G.evaluate(x, y)

    deg = sum(G.degree)
    k = np.r_[[0.0] * (deg + 1), [1.0] * (deg + 1)]
    net = represent_grid(fn, (deg, deg), (k, k)) + np.array([0.0, 0.0, dz])
    return BSplineSurface((deg, deg), (k, k), net)


def _free_edges(shape) -> int:
    fb = ShapeAnalysis_FreeBounds(shape, SEW_TOLERANCE, False, True)
    n = 0
    for w in (fb.GetClosedWires(), fb.GetOpenWires()):
        ex = TopExp_Explorer(w, TopAbs_EDGE)
        while ex.More():
            n += 1
            ex.Next()
    return n


@pytest.fixture(scope="module")
def gapped():
    ring = ring_model(4, bump=0.0, radius=0.12, width=0.08)
    # the centre first: sewing keeps its 3-D curves for the hole edges (the fill then lies DELTA off them)
    faces = [make_face(_centre(ring, DELTA), 1e-7)] + [make_face(f, 1e-7) for f in ring.faces]
    model = refill.SewnModel(sew_faces(faces, tol=2e-4))
    pairs = model.adjacent_pairs(list(range(len(model.faces))))
    centre = next(k for k in range(len(model.faces)) if sum(k in p for p in pairs) == 4)  # ring faces touch 3
    return ring, model, centre


def test_the_model_declares_a_gap_beyond_the_sewing_tolerance(gapped) -> None:
    _, model, centre = gapped
    assert len(model.faces) == 5 and _free_edges(model.shape) == 4  # the ring's outer loop
    assert SEW_TOLERANCE < refill.hole_gap(model, [centre]) <= 2 * DELTA


def test_fill_off_by_the_model_gap_sews_in_valid_and_closed(gapped, monkeypatch) -> None:
    ring, model, centre = gapped
    fill = make_face(_centre(ring, -DELTA), 1e-7)
    shape = refill_sewing._sew_in(model, [centre], [fill], gap=DELTA)
    assert _free_edges(shape) == 4 and BRepCheck_Analyzer(shape).IsValid()
    monkeypatch.setattr(refill_sewing, "SEW_GAP_FACTOR", 0.0)  # the tolerance of before: SEW_TOLERANCE alone
    before = refill_sewing._sew_in(model, [centre], [fill], gap=DELTA)
    assert _free_edges(before) > 4  # the hole stayed open


def test_refill_of_the_gapped_hole_is_valid_and_closed(gapped, monkeypatch) -> None:
    _, model, centre = gapped
    rep, shape = refill.refill_faces(model, [centre], compare_occ=False)
    assert rep.status == "filled", rep.reason
    assert rep.valid and rep.step_round_trip
    assert _free_edges(shape) == 4
    assert rep.g0 <= 2 * DELTA  # the fill lies within the model's own gap of its neighbours
    monkeypatch.setattr(refill_sewing, "SEW_GAP_FACTOR", 0.0)  # before: sewn at SEW_TOLERANCE, the hole stayed open
    assert _free_edges(refill_sewing._sew_in(model, [centre], rep._fill_faces, rep.g0)) > 4


def test_plate_face_accepts_a_miss_within_the_hole_edges_tolerance() -> None:
    from occsurf.algorithms.kernel.curve import BSplineCurve
    from occsurf.algorithms.topology.nsided import HoleSide
    from occsurf.algorithms.topology.plate_fill import fill_plate

    P = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    line = lambda a, b: BSplineCurve(1, [0, 0, 1, 1], np.array([a, b], float))  # noqa: E731
    sides = [HoleSide(line(P[i], P[(i + 1) % 4]), line(np.cross(P[(i + 1) % 4] - P[i], [0, 0, 1]),
                                                        np.cross(P[(i + 1) % 4] - P[i], [0, 0, 1]))) for i in range(4)]
    fill = dataclasses.replace(fill_plate(sides), side_g0=np.full(4, 3e-5))  # as if 3e-5 off its boundary
    with pytest.raises(InvalidGeometryError, match="misses the hole's boundary by 3e-05"):
        plate_face(fill)
    assert not plate_face(fill, gap=4e-5).IsNull()  # the hole's edges declare 4e-5: it sews in


def test_a_fill_that_sews_in_invalid_is_sewn_again_lower(bearing) -> None:
    """Bearing pair [79, 84]: sewn at twice the hole edges' tolerance (1.4e-5) a corner of the
    kept neighbour 208 collapses into a self-intersecting wire (BRepCheck_SelfIntersectingWire,
    the face unorientable); refill sews again at half the tolerance, and keeps that (valid, the
    model's own free edges only), where before it reported the filled model invalid."""
    rep, shape = refill.refill_faces(bearing, [79, 84], compare_occ=False)
    assert rep.status == "filled" and rep.valid and rep.step_round_trip, rep.reason
    at_first = refill_sewing._sew_in(bearing, rep.faces, rep._fill_faces, rep.g0)
    assert not BRepCheck_Analyzer(at_first).IsValid()  # the cause, as measured
    assert BRepCheck_Analyzer(shape).IsValid()
    assert refill_sewing._free_edge_count(shape) == refill_sewing._free_edge_count(bearing.shape)
