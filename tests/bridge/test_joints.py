"""The joint measurement of :mod:`occsurf.bridge.modeling.joints` (issue 12): OCC's own per-point
projection is the oracle for the projector :func:`assess_joint` sets up once per fill surface.

``assess_joint`` without ``locate`` (how OCC's MakeFilling fills are measured) used to call
``GeomAPI_ProjectPointOnSurf.Init(point, surface)`` at every sample, which rebuilds the projection's
sampling grid of the surface each time; it now builds one projector per surface and ``Perform``s each
point. The numbers must be the *same* (equal floats), not merely close: the overload
``Init(surface, bounds)`` without the tolerance argument projects differently (up to 3e-9 in
distance on the surface below), so these tests fail if the tolerance is dropped.
"""

from __future__ import annotations

import math

import numpy as np
from OCP.GeomAPI import GeomAPI_ProjectPointOnSurf
from OCP.gp import gp_Pnt
from OCP.TopAbs import TopAbs_EDGE
from OCP.TopExp import TopExp_Explorer
from OCP.TopoDS import TopoDS

from occsurf.algorithms import BSplineSurface
from occsurf.bridge.conversion.splines import make_face, to_occ
from occsurf.bridge.modeling.joints import _local_analysis, _projector, assess_joint, edge_samples

KNOTS = [0, 0, 0, 0, 0.3, 0.6, 1, 1, 1, 1]


def _bumpy(seed: int, lift: float = 0.0) -> BSplineSurface:
    """A bicubic over the unit square with random heights (uneven knots), raised by ``lift``."""
    rng = np.random.default_rng(seed)
    g = np.linspace(0.0, 1.0, 6)
    net = np.stack(np.meshgrid(g, g, indexing="ij"), -1)
    net = np.concatenate([net, lift + 0.3 * rng.standard_normal((6, 6, 1))], -1)
    return BSplineSurface((3, 3), (KNOTS, KNOTS), net)


def _lowest(pr: GeomAPI_ProjectPointOnSurf) -> tuple[float, float, float]:
    return (pr.LowerDistance(), *pr.LowerDistanceParameters())


def test_projector_gives_the_numbers_of_a_projection_per_point():
    s = to_occ(_bumpy(3))
    rng = np.random.default_rng(7)
    pts = np.concatenate([rng.random((200, 2)), 0.3 * rng.standard_normal((200, 1))], axis=1)
    pr = _projector(s)
    for p in pts:
        ref = GeomAPI_ProjectPointOnSurf()
        ref.Init(gp_Pnt(*p), s)
        pr.Perform(gp_Pnt(*p))
        assert _lowest(pr) == _lowest(ref)


def _reference(edge, face, surfaces, samples):
    """assess_joint's measurement with a fresh ``Init(point, surface)`` per sample and surface."""
    s_n, uvs, pts = edge_samples(edge, face, samples)
    g0 = g1 = 0.0
    for uv, p in zip(uvs, pts):
        best = None
        for s_f in surfaces:
            pr = GeomAPI_ProjectPointOnSurf()
            pr.Init(gp_Pnt(*p), s_f)
            if pr.NbPoints() and (best is None or pr.LowerDistance() < best[0]):
                best = (pr.LowerDistance(), s_f, *pr.LowerDistanceParameters())
        gap, ang = _local_analysis(s_n, uv, best[1], best[2], best[3])
        g0, g1 = max(g0, gap), max(g1, ang)
    return g0, g1


def test_assess_joint_without_locate_equals_a_projection_per_point():
    """Two fill surfaces (the nearest is kept per point) against every edge of a neighbour face:
    equal numbers, and numbers that measure something (a gap and an angle that are not zero)."""
    face = make_face(_bumpy(3))
    fills = [to_occ(_bumpy(11, lift=0.01)), to_occ(_bumpy(12, lift=-0.02))]
    ex = TopExp_Explorer(face, TopAbs_EDGE)
    edges = []
    while ex.More():
        edges.append(TopoDS.Edge_s(ex.Current()))
        ex.Next()
    assert len(edges) == 4
    for e in edges:
        got = assess_joint(e, face, fills, samples=9)
        assert got == _reference(e, face, fills, samples=9)
        assert got[0] > 1e-3 and 0.1 < got[1] < 90 and all(math.isfinite(v) for v in got)
