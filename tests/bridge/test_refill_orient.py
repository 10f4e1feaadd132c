"""The hole's edge curves are oriented head to tail, also on a loop of two edges
(:func:`occsurf.bridge.modeling.refill_sides._oriented_curves`).

A half disk's boundary is a segment and an arc, both running from (-1, 0, 0) to (1, 0, 0): each end of
one touches an end of the other, so a curve cannot be oriented by its next neighbour alone (both
kept their direction, and the screw's face 24 was refilled mm off). Walking the chain reverses the arc.
"""

from __future__ import annotations

import numpy as np
import pytest
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeEdge
from OCP.GC import GC_MakeArcOfCircle
from OCP.gp import gp_Pnt

from occsurf.bridge.modeling.refill_sides import _oriented_curves


def _edges(points: list[tuple[float, float, float]], arc_via: tuple[float, float, float] | None):
    seg = BRepBuilderAPI_MakeEdge(gp_Pnt(*points[0]), gp_Pnt(*points[1])).Edge()
    arc = GC_MakeArcOfCircle(gp_Pnt(*points[0]), gp_Pnt(*arc_via), gp_Pnt(*points[1])).Value()
    return [seg, BRepBuilderAPI_MakeEdge(arc).Edge()]


@pytest.mark.parametrize("swap", [False, True])
def test_two_edge_loop_runs_head_to_tail(swap: bool) -> None:
    edges = _edges([(-1, 0, 0), (1, 0, 0)], (0, 1, 0))
    if swap:
        edges = edges[::-1]
    curves = _oriented_curves(edges)
    for a, b in zip(curves, curves[1:] + curves[:1]):
        assert np.linalg.norm(a.evaluate(a.domain[1]) - b.evaluate(b.domain[0])) < 1e-12
    arc = curves[0 if swap else 1]
    assert np.abs(np.linalg.norm(arc.evaluate(np.linspace(*arc.domain, 50)), axis=1) - 1).max() < 1e-12
