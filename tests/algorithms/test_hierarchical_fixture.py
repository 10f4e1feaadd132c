"""A hierarchy saved by format version 1 must load in every later version (course §5-17).

``tests/fixtures/hierarchical_v1.json`` was written once by running this file as a script
(``python -m tests.algorithms.test_hierarchical_fixture --write``) and is kept as data. The tests
load it and compare with (a) the same hierarchy built again through the public API and (b) an
oracle that does not use the hierarchical code: ``BSplineSurface.refine`` plus frames from explicit
cross products for the level-1 overlay.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
from numpy.testing import assert_allclose

from occsurf.algorithms import BSplineSurface
from occsurf.algorithms.hierarchical.surface import HierarchicalSurface

FIXTURE = Path(__file__).resolve().parents[1] / "fixtures" / "hierarchical_v1.json"


def build_reference() -> HierarchicalSurface:
    """Rational, non-uniform bicubic base; three levels; two side-by-side overlays; a base edit."""
    U = np.r_[[0.0] * 4, 0.15, 0.4, 0.55, 0.8, [1.0] * 4]
    Vk = np.r_[[0.0] * 4, 0.3, 0.5, 0.7, [1.0] * 4]
    g_u, g_v = np.linspace(0, 4, 8), np.linspace(0, 3, 7)
    X, Y = np.meshgrid(g_u, g_v, indexing="ij")
    Z = 0.5 * np.sin(X) * np.cos(Y)
    w = 1.0 + 0.25 * np.cos(X + Y)
    hs = HierarchicalSurface(BSplineSurface((3, 3), (U, Vk), np.stack([X, Y, Z], -1), w))
    a = hs.add_overlay((0.15, 0.55), (0.3, 0.7))
    b = hs.add_overlay((0.55, 1.0), (0.0, 0.5))  # beside a
    c = hs.add_overlay((0.275, 0.475), (0.4, 0.6), a)
    d = hs.add_overlay((0.3375, 0.4), (0.45, 0.55), c, knots=([0.36, 0.37], [0.5]))
    rng = np.random.default_rng(61)
    for o, s in ((a, 0.1), (b, 0.05), (c, 0.03), (d, 0.01)):
        hs.set_offsets(o, s * rng.standard_normal(o.shape + (3,)))
    hs.move_vertex(None, (4, 3), (0.2, -0.1, 0.8))
    return hs


def load() -> HierarchicalSurface:
    return HierarchicalSurface.from_dict(json.loads(FIXTURE.read_text()))


def test_fixture_loads_and_matches_the_same_hierarchy_built_again():
    hs, ref = load(), build_reference()
    assert [o.vertices for o in hs.overlays] == [o.vertices for o in ref.overlays]
    us, vs = np.linspace(0, 1, 61), np.linspace(0, 1, 47)
    # Same operations, same arithmetic: measured bit-identical; 1e-12 lets later versions round
    # differently without changing the geometry.
    assert_allclose(hs.evaluate_grid(us, vs), ref.evaluate_grid(us, vs), rtol=0, atol=1e-12)
    assert_allclose(hs.flatten().evaluate_grid(us, vs), ref.flatten().evaluate_grid(us, vs), rtol=0, atol=1e-12)


def test_fixture_level_one_against_an_independent_oracle():
    hs = load()
    data = json.loads(FIXTURE.read_text())
    base = BSplineSurface.from_dict(data["base"])
    item = data["overlays"][0]
    assert item["parent"] == 0
    ku, kv = (np.array(k) for k in item["inserted_knots"])
    offsets = np.array(item["offsets"])
    # Reference vertices: the base refined (Oslo, BSplineSurface.refine); frames: the base's
    # Gram-Schmidt frames at the Greville points of the refined knots, from explicit partials.
    r = base.refine(ku, direction="u").refine(kv, direction="v")
    gu, gv = r.greville()
    iu = np.flatnonzero((gu >= item["region"][0][0]) & (gu <= item["region"][0][1]))
    iv = np.flatnonzero((gv >= item["region"][1][0]) & (gv <= item["region"][1][1]))
    D = base.derivatives_grid(gu[iu], gv[iv], 1)
    su, sv = D[:, :, 1, 0], D[:, :, 0, 1]
    t = su / np.linalg.norm(su, axis=-1, keepdims=True)
    n = np.cross(su, sv)
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    disp = offsets[..., :1] * t + offsets[..., 1:2] * np.cross(n, t) + offsets[..., 2:] * n
    P = np.array(r.control_points)
    P[np.ix_(iu, iv)] += disp
    oracle = BSplineSurface(r.degree, r.knots, P, r.weights)
    a = hs.overlays[0]
    assert_allclose(hs.level_surface(a).control_points, oracle.control_points, rtol=0, atol=1e-13)
    us, vs = np.linspace(0, 1, 31), np.linspace(0, 1, 29)
    assert_allclose(hs.level_surface(a).evaluate_grid(us, vs), oracle.evaluate_grid(us, vs), rtol=0, atol=1e-12)
    # Away from the supports of the other overlays (b, c, d) only a acts: the surface is the oracle.
    g = np.linspace(0, 1, 81)
    keep = np.ones((81, 81), bool)
    for o in hs.overlays[1:]:
        (i0, i1), (j0, j1) = o.vertices
        su = (o.knots[0][i0], o.knots[0][i1 + 4])
        sv = (o.knots[1][j0], o.knots[1][j1 + 4])
        keep &= ~(((g >= su[0]) & (g <= su[1]))[:, None] & ((g >= sv[0]) & (g <= sv[1]))[None, :])
    uu, vv = np.meshgrid(g, g, indexing="ij")
    u, v = uu[keep], vv[keep]
    assert np.abs(oracle.evaluate(u, v) - base.evaluate(u, v)).max() > 1e-3  # a's details are there
    assert_allclose(hs.evaluate(u, v), oracle.evaluate(u, v), rtol=0, atol=1e-12)

if __name__ == "__main__" and "--write" in sys.argv:  # pragma: no cover - run once to create the fixture
    FIXTURE.parent.mkdir(exist_ok=True)
    FIXTURE.write_text(json.dumps(build_reference().to_dict(), indent=1) + "\n")
    print(f"wrote {FIXTURE}")
