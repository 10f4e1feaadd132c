"""Coons and Gordon surfaces against OpenCascade, and through STEP (algorithms/construction/).

The distance between two surfaces is measured both ways with ``tests.bridge.generation_occ.max_distance``:
dense samples of one surface (41 uniform values per direction plus values 1e-6, 1e-4, 1e-2 of the
range from each boundary, and the knots) projected onto the other (a seeded local projection, a
global ``GeomAPI_ProjectPointOnSurf`` wherever that does not land on the surface), the maximum
reported. Projection converges to ~1e-15 on these smooth patches, so an exact agreement shows as
<= 1e-12.

Measured (seeded inputs below; printed by ``pytest -s``):
* ``coons(blend="cubic")`` vs ``GeomFill_BSplineCurves`` Coons style, cubic Bézier boundaries:
  identical parametrically (0.0). OCC's Coons style blends the boundary POLES with the cubic
  Hermite functions ``1 - 3t² + 2t³``, ``3t² - 2t³`` (``GeomFill_Coons::Init``), which for
  Bézier boundaries is the bicubically blended Coons patch with zero cross derivatives.
* ``coons()`` (bilinear blending, course §6-20) vs the same OCC surface: 4.4e-2 apart on a
  patch of size 3 — a different surface (different blending functions), not an error. Both
  interpolate the boundaries (checked), and they coincide when the twist of the corner data
  vanishes (parallelogram corners with straight sides: both are then the bilinear plane patch).
* multi-span B-spline boundaries: OCC's pole-index blending is no longer a Coons formula;
  ``coons(blend="cubic")`` and OCC differ inside (measured 0.157) while sharing the boundaries.
* ``gordon`` vs ``ocp_gordon.interpolate_curve_network`` on a 4 x 5 network of iso-curves of a
  bicubic B-spline surface: 4.4e-4 apart, which is exactly ocp_gordon's own distance to the
  network (it reparametrises the curves by approximation); ours is on the network to 1e-12.
  On a network from a bicubic Bézier surface (reproduced by both): 4e-9.
* multi-span Coons value above: 0.157 on a patch of size 3.
"""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose

pytest.importorskip("OCP")

from OCP.GeomFill import GeomFill_BSplineCurves, GeomFill_FillingStyle  # noqa: E402

from occsurf.algorithms.construction import coons, coons_bicubic, gordon  # noqa: E402
from occsurf.algorithms.kernel.curve import BSplineCurve  # noqa: E402
from occsurf.bridge.conversion.splines import from_occ, to_occ  # noqa: E402
from occsurf.bridge.exchange.step_iges import read_step, write_step  # noqa: E402
from tests.algorithms.test_curvenet import boundary_net, network, random_loop, random_surface  # noqa: E402

K = 41
S = np.linspace(0.0, 1.0, K)


def _gen():
    import tests.bridge.generation_occ as mod

    return mod


def _max_projection(points: np.ndarray, occ_surface) -> float:
    """Largest distance of the points to the (bounded) OCC surface."""
    return float(_gen()._project_all(points.reshape(-1, 3), occ_surface, tuple(occ_surface.Bounds())).max())


def surface_distance(ours, occ_surface) -> float:
    """Max of both one-sided projection distances (ours -> OCC, OCC -> ours)."""
    return max(_gen().max_distance(ours, occ_surface, K))


def occ_coons(b, r, t, l):
    # OCC takes a loop: S(u,0)=c1(u), S(1,v)=c2(v), S(u,1)=c3(1-u), S(0,v)=c4(1-v).
    return GeomFill_BSplineCurves(to_occ(b), to_occ(r), to_occ(t.reverse()), to_occ(l.reverse()),
                                  GeomFill_FillingStyle.GeomFill_CoonsStyle).Surface()


def bezier(c: BSplineCurve) -> BSplineCurve:
    return BSplineCurve(c.n_poles - 1, [0] * c.n_poles + [1] * c.n_poles, c.control_points)


def test_cubic_blend_coons_equals_occ_coons_style_on_bezier_boundaries():
    b, r, t, l = map(bezier, random_loop(np.random.default_rng(0), (3, 4, 3, 5), (4, 5, 4, 6)))
    ours = coons(b, r, t, l, blend="cubic")
    occ = occ_coons(b, r, t, l)
    d = surface_distance(ours, occ)
    print(f"\ncoons(blend='cubic') vs GeomFill Coons style (Bezier): {d:.3g}")
    assert d < 1e-12  # the same polynomial patch: projection round-off only
    # parametrically too (same domain [0,1]^2, same degrees)
    assert_allclose(from_occ(occ).evaluate_grid(S, S), ours.evaluate_grid(S, S), rtol=0, atol=1e-13)


def test_bilinear_coons_vs_occ_coons_style_differ_by_the_blending():
    b, r, t, l = map(bezier, random_loop(np.random.default_rng(0), (3, 3, 3, 3), (4, 4, 4, 4)))
    ours, occ = coons(b, r, t, l), occ_coons(b, r, t, l)
    d = surface_distance(ours, occ)
    print(f"\ncoons() (bilinear blend) vs GeomFill Coons style: {d:.3g}")
    assert 1e-3 < d < 0.5  # measured 4.4e-2: different blending functions, same boundaries
    O = from_occ(occ)
    for x in (0.0, 1.0):
        assert_allclose(O.evaluate(S, x), ours.evaluate(S, x), rtol=0, atol=1e-14)
        assert_allclose(O.evaluate(x, S), ours.evaluate(x, S), rtol=0, atol=1e-14)


def test_straight_sides_of_a_parallelogram_all_agree():
    P00, P10, P01 = np.array([0, 0, 0.0]), np.array([3, 0.5, 1.0]), np.array([0.5, 2, -0.5])
    P11 = P10 + P01 - P00
    line = lambda a, c: BSplineCurve(3, [0] * 4 + [1] * 4, a + np.linspace(0, 1, 4)[:, None] * (c - a))  # noqa: E731
    curves = (line(P00, P10), line(P10, P11), line(P01, P11), line(P00, P01))
    occ = occ_coons(*curves)
    for blend in ("linear", "cubic"):
        d = surface_distance(coons(*curves, blend=blend), occ)
        assert d < 1e-12, blend


def test_multispan_boundaries_differ_inside_share_the_boundary():
    b, r, t, l = random_loop(np.random.default_rng(1), (3, 3, 3, 3), (6, 5, 7, 6))
    ours, occ = coons(b, r, t, l, blend="cubic"), occ_coons(b, r, t, l)
    d = surface_distance(ours, occ)
    print(f"\ncoons(blend='cubic') vs GeomFill Coons style (multi-span): {d:.3g}")
    assert d > 1e-4  # OCC blends by pole index: not the Coons formula on non-Bezier boundaries
    O = from_occ(occ)
    for x in (0.0, 1.0):
        assert_allclose(O.evaluate(S, x), ours.evaluate(S, x), rtol=0, atol=1e-14)
        assert_allclose(O.evaluate(x, S), ours.evaluate(x, S), rtol=0, atol=1e-14)


def test_gordon_vs_ocp_gordon():
    ocp_gordon = pytest.importorskip("ocp_gordon")
    F = random_surface(np.random.default_rng(40), nu=6, nv=6)
    us, vs = np.array([0, 0.3, 0.55, 0.8, 1.0]), np.array([0, 0.35, 0.7, 1.0])
    A, B = network(F, us, vs)
    ours = gordon(A, B)
    occ = ocp_gordon.interpolate_curve_network([to_occ(a) for a in A], [to_occ(b) for b in B], tolerance=1e-6)
    d = surface_distance(ours, occ)
    dF = surface_distance(ours, to_occ(F))
    print(f"\ngordon vs ocp_gordon: {d:.3g} (ours vs the source surface: {dF:.3g})")
    # ocp_gordon reparametrises the curves by approximation, so it fits the network only to
    # ~4.4e-4 here (measured); ours interpolates it to round-off. The two surfaces differ by no
    # more than ocp_gordon's own network error: same Boolean-sum construction, and the whole
    # difference is its reparametrisation fit.
    net_pts = np.concatenate([a(S) for a in A] + [b(S) for b in B])
    occ_net = _max_projection(net_pts, occ)
    print(f"ocp_gordon's distance to the network: {occ_net:.3g}")
    assert _max_projection(net_pts, to_occ(ours)) < 1e-12
    assert occ_net < 1e-3
    assert d <= 1.5 * occ_net + 1e-9


def test_gordon_matches_ocp_gordon_when_both_reproduce_the_surface():
    # A bicubic Bezier surface: any network of >= 4 x 4 curves determines it for both methods.
    ocp_gordon = pytest.importorskip("ocp_gordon")
    rng = np.random.default_rng(41)
    x, y = np.meshgrid(np.linspace(0, 3, 4), np.linspace(0, 2, 4), indexing="ij")
    from occsurf.algorithms.kernel.surface import BSplineSurface
    F = BSplineSurface((3, 3), ([0] * 4 + [1] * 4,) * 2, np.stack([x, y, 0.5 * rng.standard_normal((4, 4))], -1))
    A, B = network(F, np.array([0, 0.3, 0.6, 0.8, 1.0]), np.array([0, 0.3, 0.7, 1.0]))
    ours = gordon(A, B)
    occ = ocp_gordon.interpolate_curve_network([to_occ(a) for a in A], [to_occ(b) for b in B], tolerance=1e-6)
    d = surface_distance(ours, occ)
    print(f"\ngordon vs ocp_gordon, Bezier source: {d:.3g}")
    assert surface_distance(ours, to_occ(F)) < 1e-12
    assert d < 1e-5  # ocp_gordon's reparametrisation fits (~1e-6 here)


@pytest.mark.parametrize("kind", ["coons", "coons_cubic", "coons_bicubic", "gordon", "gordon_rational"])
def test_step_round_trip_is_exact(kind, tmp_path):
    rng = np.random.default_rng(50)
    if kind.startswith("coons") and kind != "coons_bicubic":
        s = coons(*random_loop(rng), blend="cubic" if kind == "coons_cubic" else "linear")
    elif kind == "coons_bicubic":
        curves, xd = boundary_net(random_surface(rng))
        s = coons_bicubic(*curves, cross_derivatives=xd)
    else:
        F = random_surface(rng, p=2, q=3, rational=kind == "gordon_rational")
        s = gordon(*network(F, np.array([0, 0.3, 0.6, 1.0]), np.array([0, 0.2, 0.5, 0.75, 1.0])))
        assert s.is_rational == (kind == "gordon_rational")
    path = write_step(tmp_path / f"{kind}.step", s, kind)
    back = read_step(path).faces[0].surface
    # 17 significant digits: every double survives the text round trip exactly
    assert back == s
