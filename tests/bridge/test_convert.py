"""``occsurf.bridge.conversion.splines``: bit-exact round trips, periodic and Bézier inputs, topology, error paths."""

from __future__ import annotations

import build123d as bd
import cadquery as cq
import numpy as np
import pytest
from hypothesis import assume, example, given
from hypothesis import strategies as st
from numpy.testing import assert_allclose, assert_array_equal
from OCP.BRep import BRep_Tool
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeEdge
from OCP.Geom import (
    Geom_BezierCurve,
    Geom_BezierSurface,
    Geom_BSplineCurve,
    Geom_BSplineSurface,
    Geom_Circle,
    Geom_Line,
    Geom_OffsetCurve,
    Geom_OffsetSurface,
    Geom_Plane,
    Geom_TrimmedCurve,
)
from OCP.Geom2d import Geom2d_Circle
from OCP.GeomAPI import GeomAPI_ProjectPointOnCurve, GeomAPI_ProjectPointOnSurf
from OCP.gp import gp_Ax1, gp_Ax2, gp_Ax2d, gp_Ax3, gp_Dir, gp_Pnt
from OCP.TopAbs import TopAbs_EDGE
from OCP.TopExp import TopExp_Explorer
from OCP.TopoDS import TopoDS

from occsurf.algorithms import BSplineCurve, BSplineSurface
from occsurf.algorithms.errors import InvalidGeometryError, KernelError, ToleranceError
from occsurf.bridge import _occ
from occsurf.bridge.conversion.splines import from_occ, is_reversed, to_cq_edge, to_cq_face, to_edge, to_face, to_occ

from .test_kernel_vs_occ import (
    D2_ORDER,
    SETTINGS,
    curves,
    fractions01,
    occ_curve_d3,
    occ_rtol,
    occ_surface_d2,
    pole_radius,
    rel_error,
    snap_to_knots,
    surfaces,
)

_float = dict(allow_nan=False, allow_infinity=False, allow_subnormal=False, width=64)


def occ_curve_arrays(occ: Geom_BSplineCurve):
    w = occ.Weights()
    return (_occ.from_pnt_array(occ.Poles()), None if w is None else _occ.from_real_array(w),
            _occ.from_real_array(occ.KnotSequence()))


def _as_occ_stores(x):
    """``x`` as OCC stores it: a spline whose weights are all equal comes back polynomial with the
    same poles (``test_equal_weights_are_stored_as_polynomial_by_occ``; hypothesis drew such
    weights in CI10: a 2 x 2 surface with every weight 2.0); anything else bit for bit itself."""
    if x.weights is None or np.ptp(x.weights) > 0:
        return x
    if isinstance(x, BSplineCurve):
        return BSplineCurve(x.degree, x.knots, x.control_points)
    return BSplineSurface(x.degree, x.knots, x.control_points)


# ============================================================================ bit-exact round trips
@SETTINGS
@given(c=curves())
def test_curve_round_trip_is_bit_exact(c):
    occ = to_occ(c)
    assert isinstance(occ, Geom_BSplineCurve)
    assert occ.Degree() == c.degree and not occ.IsPeriodic()
    P, w, flat = occ_curve_arrays(occ)
    assert_array_equal(P, c.control_points)  # exact: no tolerance
    assert_array_equal(flat, c.knots)
    assert (w is None) == (_as_occ_stores(c).weights is None)
    if w is not None:
        assert_array_equal(w, c.weights)
    assert (occ.FirstParameter(), occ.LastParameter()) == c.domain
    assert from_occ(occ) == _as_occ_stores(c)  # BSplineCurve.__eq__ compares arrays exactly


@SETTINGS
@given(s=surfaces())
def test_surface_round_trip_is_bit_exact(s):
    occ = to_occ(s)
    assert isinstance(occ, Geom_BSplineSurface)
    assert (occ.UDegree(), occ.VDegree()) == s.degree
    assert_array_equal(_occ.from_pnt_array2(occ.Poles()), s.control_points)
    assert_array_equal(_occ.from_real_array(occ.UKnotSequence()), s.knots[0])
    assert_array_equal(_occ.from_real_array(occ.VKnotSequence()), s.knots[1])
    assert occ.Bounds() == (*s.domain[0], *s.domain[1])
    assert from_occ(occ) == _as_occ_stores(s)


def test_weights_varying_only_along_u_are_kept():
    # OCP_NOTES §1: IsURational() is False when the weights vary only with the u index; from_occ
    # must read Weights() instead.
    P = np.array([[[i, j, 0.0] for j in range(2)] for i in range(3)], float)
    W = np.array([[1.0, 1.0], [0.7, 0.7], [1.0, 1.0]])
    s = BSplineSurface((2, 1), ([0, 0, 0, 1, 1, 1], [0, 0, 1, 1]), P, W)
    occ = to_occ(s)
    assert occ.IsURational() is False  # the pitfall is real ...
    assert from_occ(occ) == s  # ... and avoided


def test_equal_weights_are_stored_as_polynomial_by_occ():
    # Documented exception to bit-exactness: OCC drops weights that are all equal.
    c = BSplineCurve(3, [0, 0, 0, 0, 1, 1, 1, 1], np.random.default_rng(0).uniform(-1, 1, (4, 3)), [2.0] * 4)
    back = from_occ(to_occ(c))
    assert back.weights is None
    assert_array_equal(back.control_points, c.control_points)
    ts = np.linspace(0, 1, 11)
    assert_allclose(back.evaluate(ts), c.evaluate(ts), rtol=0, atol=1e-15)  # w/w = 1: round-off only


# ============================================================================ periodic OCC splines
@st.composite
def periodic_knots(draw, degree: int):
    """Distinct knots and multiplicities of a periodic spline (end multiplicities equal)."""
    k = draw(st.integers(2, 7))
    gaps = draw(st.lists(st.floats(0.25, 4.0, **_float), min_size=k - 1, max_size=k - 1))
    K = draw(st.floats(-10, 10, **_float)) + np.r_[0.0, np.cumsum(gaps)]
    m_end = draw(st.integers(1, degree))
    M = [m_end] + draw(st.lists(st.integers(1, degree), min_size=k - 2, max_size=k - 2)) + [m_end]
    assume(sum(M[:-1]) >= degree + 1)
    return K, M


@st.composite
def periodic_curves(draw):
    p = draw(st.integers(1, 6))
    K, M = draw(periodic_knots(p))
    n = sum(M[:-1])
    P = np.array(draw(st.lists(st.tuples(*[st.floats(-1, 1, **_float)] * 3), min_size=n, max_size=n)))
    rational = draw(st.booleans())
    args = [_occ.pnt_array(P)]
    if rational:
        w = np.array(draw(st.lists(st.floats(0.5, 2, **_float), min_size=n, max_size=n)))
        assume(np.ptp(w) > 0)
        args.append(_occ.real_array(w))
    return Geom_BSplineCurve(*args, _occ.real_array(K), _occ.int_array(M), p, True)


@SETTINGS
@given(occ=periodic_curves(), fracs=st.lists(fractions01, min_size=2, max_size=8))
def test_periodic_curve_becomes_the_equivalent_unclamped_curve(occ, fracs):
    assert occ.IsPeriodic()
    c = from_occ(occ)
    p, n = occ.Degree(), occ.NbPoles()
    P, w, flat = occ_curve_arrays(occ)
    # structure: OCC's flat knots, poles wrapped around (bit-exact copies), domain = the period
    assert_array_equal(c.knots, flat)
    idx = np.arange(flat.size - p - 1) % n
    assert_array_equal(c.control_points, P[idx])
    if w is not None:
        assert_array_equal(c.weights, w[idx])
    assert c.domain == (occ.FirstParameter(), occ.LastParameter())
    # geometry: the same curve as OCC's periodic one (orders 0..3, knots and the start included;
    # at the end of the period OCC wraps round to the start and takes derivatives from the right
    # of the seam, the unclamped form from the left: they differ where the seam is not C^3)
    lo, hi = c.domain
    ts = np.r_[lo + np.asarray(fracs) * (hi - lo), lo, flat[(flat >= lo) & (flat < hi)]]
    ts = np.unique(snap_to_knots(ts, flat))
    ts = ts[ts < hi]  # fracs may be 1.0
    ours, ref = c.derivatives(ts, 3), occ_curve_d3(occ, ts)
    g = p / np.min(np.diff(np.unique(flat)))
    for k in range(4):
        assert rel_error(ours[:, k], ref[:, k], pole_radius(c) * g**k) <= occ_rtol(p)
    assert rel_error(c.evaluate(hi), occ_curve_d3(occ, [hi])[0, 0], pole_radius(c)) <= occ_rtol(p)
    # and back to OCC as a non-periodic spline with the same points
    again = to_occ(c)
    assert not again.IsPeriodic()
    assert rel_error(occ_curve_d3(again, ts)[:, 0], ref[:, 0], pole_radius(c)) <= occ_rtol(p)


@SETTINGS
@given(data=st.data(), uper=st.booleans(), vper=st.booleans())
def test_periodic_surface_becomes_the_equivalent_unclamped_surface(data, uper, vper):
    assume(uper or vper)
    p, q = data.draw(st.integers(1, 4)), data.draw(st.integers(1, 4))
    dirs = []
    for deg, per in ((p, uper), (q, vper)):
        if per:
            K, M = data.draw(periodic_knots(deg))
        else:
            K, M = np.array([0.0, 1.0]), [deg + 1, deg + 1]
        dirs.append((K, M, sum(M[:-1]) if per else deg + 1))
    (UK, UM, nu), (VK, VM, nv) = dirs
    rng = np.random.default_rng(data.draw(st.integers(0, 2**32 - 1)))
    P = rng.uniform(-1, 1, (nu, nv, 3))
    W = rng.uniform(0.5, 2.0, (nu, nv))
    occ = Geom_BSplineSurface(_occ.pnt_array2(P), _occ.real_array2(W), _occ.real_array(UK), _occ.real_array(VK),
                              _occ.int_array(UM), _occ.int_array(VM), p, q, uper, vper)
    s = from_occ(occ)
    assert s.domain == (occ.Bounds()[:2], occ.Bounds()[2:])
    iu = np.arange(s.n_poles[0]) % nu
    iv = np.arange(s.n_poles[1]) % nv
    assert_array_equal(s.control_points, P[iu][:, iv])
    assert_array_equal(s.weights, W[iu][:, iv])
    (u0, u1), (v0, v1) = s.domain
    # points on the closed grid; derivatives off the far seam (see the curve test above)
    uu, vv = [x.ravel() for x in np.meshgrid(np.linspace(u0, u1, 7), np.linspace(v0, v1, 7), indexing="ij")]
    assert rel_error(s.evaluate(uu, vv), occ_surface_d2(occ, uu, vv)[:, 0], pole_radius(s)) <= occ_rtol(max(p, q))
    uu, vv = [x.ravel() for x in np.meshgrid(snap_to_knots(np.linspace(u0, u1, 7)[:-1], s.knots[0]),
                                             snap_to_knots(np.linspace(v0, v1, 7)[:-1], s.knots[1]), indexing="ij")]
    ours, ref = s.derivatives(uu, vv, 1), occ_surface_d2(occ, uu, vv)
    gu = p / np.min(np.diff(np.unique(s.knots[0])))
    gv = q / np.min(np.diff(np.unique(s.knots[1])))
    for (a, b), k in D2_ORDER.items():
        if a + b <= 1:
            assert rel_error(ours[:, a, b], ref[:, k], pole_radius(s) * gu**a * gv**b) <= occ_rtol(max(p, q))


def test_periodic_spline_with_too_few_poles_is_refused():
    # 3 poles, degree 5: OCC accepts it but its KnotSequence is not sorted and its evaluation
    # disagrees with the periodic extension (by ~2e-2), so there is no faithful conversion.
    P = np.random.default_rng(0).uniform(-1, 1, (3, 3))
    occ = Geom_BSplineCurve(_occ.pnt_array(P), _occ.real_array([0, 1, 2, 3]), _occ.int_array([1, 1, 1, 1]), 5, True)
    with pytest.raises(InvalidGeometryError, match="fewer than degree \\+ 1 poles"):
        from_occ(occ)


@pytest.mark.parametrize("radius", [0.7, 3.0])
def test_build123d_circle_sweep_with_degree_many_poles_converts(radius):
    # build123d sweeps a circle into a u-periodic surface with 6 poles of degree 6 (n == p), for
    # which OCC's KnotSequence is invalid; we rebuild the flat knots with OCC's convention.
    path = bd.Spline((0, 0, 0), (0, 2, 5), (3, 1, 10))
    profile = bd.Plane(origin=(0, 0, 0), z_dir=path.tangent_at(0)) * bd.Circle(radius)
    swept = bd.sweep(profile, path=path)
    faces = [f for f in swept.faces() if type(BRep_Tool.Surface_s(f.wrapped)).__name__ == "Geom_BSplineSurface"]
    assert faces
    for f in faces:
        occ = BRep_Tool.Surface_s(f.wrapped)
        s = from_occ(f)
        (u0, u1), (v0, v1) = s.domain
        uu, vv = (x.ravel() for x in np.meshgrid(np.linspace(u0, u1, 13), np.linspace(v0, v1, 13), indexing="ij"))
        ref = np.array([occ.Value(float(a), float(b)).Coord() for a, b in zip(uu, vv)])
        # Exact representation: round-off of the evaluation only, relative to the poles' size.
        assert np.abs(s.evaluate(uu, vv) - ref).max() <= 1e-13 * np.abs(s.control_points).max()


def test_circle_converts_through_its_periodic_bspline():
    c = from_occ(Geom_Circle(gp_Ax2(), 2.0))
    assert c.is_rational and not c.is_clamped and c.domain == (0.0, 2 * np.pi)
    X = c.evaluate(np.linspace(*c.domain, 101))
    assert_allclose(np.linalg.norm(X, axis=1), 2.0, rtol=1e-15, atol=0)  # exact image, round-off only


# ============================================================================ Bézier, trimming, bounds
def test_bezier_curve_and_surface_are_copied_exactly():
    rng = np.random.default_rng(1)
    P = rng.uniform(-1, 1, (5, 3))
    w = rng.uniform(0.5, 2, 5)
    c = from_occ(Geom_BezierCurve(_occ.pnt_array(P), _occ.real_array(w)))
    assert c.degree == 4
    assert_array_equal(c.knots, [0, 0, 0, 0, 0, 1, 1, 1, 1, 1])
    assert_array_equal(c.control_points, P)
    assert_array_equal(c.weights, w)
    S = rng.uniform(-1, 1, (3, 4, 3))
    s = from_occ(Geom_BezierSurface(_occ.pnt_array2(S)))
    assert s.degree == (2, 3) and s.weights is None
    assert_array_equal(s.control_points, S)


def _clear_of_knots(knots, values, length) -> bool:
    """Each value is a knot or at least 1e-6 * length from every knot: OCC snaps a bound within
    its parametric confusion (1e-9) onto a knot, our kernel within 1e-12 relative; avoid the gap."""
    d = np.abs(np.subtract.outer(np.asarray(values), knots))
    return bool(np.all((d.min(axis=1) == 0) | (d.min(axis=1) > 1e-6 * length)))


@SETTINGS
@given(c=curves(degrees=st.integers(1, 7)), f=st.tuples(fractions01, fractions01))
def test_curve_bounds_segment_like_our_kernel(c, f):
    lo, hi = c.domain
    a, b = sorted(lo + np.asarray(f) * (hi - lo))
    assume(b - a > 1e-3 * (hi - lo))
    assume(_clear_of_knots(c.knots, (a, b), hi - lo))
    ours = c.segment(a, b)
    back = from_occ(to_occ(c), (a, b))
    assert back.domain == (a, b)
    assert_array_equal(back.knots, ours.knots)
    # Segmenting = knot insertion (convex combinations): 1e-12 relative to the pole magnitude.
    assert_allclose(back.control_points, ours.control_points, rtol=0, atol=1e-12 * max(1, pole_radius(c)))


@SETTINGS
@given(s=surfaces(degrees=st.integers(1, 5), clamped=True), f=st.tuples(*[st.floats(0.1, 0.9, **_float)] * 4))
def test_surface_bounds_segment_like_our_kernel(s, f):
    (u0, u1), (v0, v1) = s.domain
    a, b = sorted((u0 + f[0] * (u1 - u0), u0 + f[1] * (u1 - u0)))
    c, d = sorted((v0 + f[2] * (v1 - v0), v0 + f[3] * (v1 - v0)))
    assume(b - a > 1e-3 * (u1 - u0) and d - c > 1e-3 * (v1 - v0))
    assume(_clear_of_knots(s.knots[0], (a, b), u1 - u0) and _clear_of_knots(s.knots[1], (c, d), v1 - v0))
    ours = s.split(b, direction="u")[0].split(a, direction="u")[1].split(d, direction="v")[0].split(c, direction="v")[1]
    back = from_occ(to_occ(s), (a, b, c, d))
    assert back.domain == ((a, b), (c, d))
    for x, y in zip(back.knots, ours.knots):
        assert_array_equal(x, y)
    assert_allclose(back.control_points, ours.control_points, rtol=0, atol=1e-12 * max(1, pole_radius(s)))


def test_unbounded_geometry_needs_bounds():
    with pytest.raises(InvalidGeometryError, match="Geom_Plane is unbounded"):
        from_occ(Geom_Plane(gp_Ax3()))
    with pytest.raises(InvalidGeometryError, match="Geom_Line is unbounded"):
        from_occ(Geom_Line(gp_Ax1()))
    line = from_occ(Geom_Line(gp_Ax1(gp_Pnt(1, 2, 3), gp_Dir(0, 0, 1))), (-1.0, 2.0))
    assert line.degree == 1
    assert_array_equal(line.evaluate([-1.0, 2.0]), [[1, 2, 2], [1, 2, 5]])  # exact: poles are the ends
    plane = from_occ(Geom_Plane(gp_Ax3()), (0.0, 1.0, -2.0, 2.0))
    assert plane.domain == ((0.0, 1.0), (-2.0, 2.0))


@pytest.mark.parametrize("bounds", [(0.0,), (1.0, 0.0), (0.0, np.nan), ("a", "b"), (0.0, 1.0, 2.0)])
def test_malformed_curve_bounds(bounds):
    with pytest.raises(InvalidGeometryError, match="bounds"):
        from_occ(Geom_Circle(gp_Ax2(), 1.0), bounds)


def test_malformed_surface_bounds():
    with pytest.raises(InvalidGeometryError, match="bounds"):
        from_occ(Geom_Plane(gp_Ax3()), (0.0, 1.0, 1.0, 1.0))


def test_bounds_outside_a_nonperiodic_spline_are_a_kernel_error():
    c = BSplineCurve(2, [0, 0, 0, 1, 1, 1], [[0, 0, 0], [1, 1, 0], [2, 0, 0]])
    with pytest.raises(KernelError) as info:
        from_occ(to_occ(c), (-1.0, 0.5))
    assert _occ.is_occ_exception(info.value.__cause__)


def test_offset_surface_without_analytic_equivalent_is_approximated_within_tol():
    P = np.array([[[i, j, 0.3 * np.sin(i + 2 * j)] for j in range(4)] for i in range(3)], float)
    off = Geom_OffsetSurface(Geom_BezierSurface(_occ.pnt_array2(P)), 0.2)
    s = from_occ(off)  # default tol 1e-7
    (u0, u1), (v0, v1) = s.domain
    X = s.evaluate_grid(np.linspace(u0, u1, 7), np.linspace(v0, v1, 7)).reshape(-1, 3)
    dist = max(GeomAPI_ProjectPointOnSurf(gp_Pnt(*x), off).LowerDistance() for x in X.tolist())
    assert dist <= 1e-7  # the approximation tolerance (measured 4e-9)
    with pytest.raises(ToleranceError, match="tol=1e-15"):
        from_occ(off, tol=1e-15)


def test_offset_curve_is_approximated_within_tol():
    bc = Geom_BezierCurve(_occ.pnt_array(np.array([[0, 0, 0], [1, 2, 0], [2, -1, 0.5], [3, 1, 0]], float)))
    off = Geom_OffsetCurve(bc, 0.3, gp_Dir(0, 0, 1))
    c = from_occ(off)
    X = c.evaluate(np.linspace(*c.domain, 41))
    assert max(GeomAPI_ProjectPointOnCurve(gp_Pnt(*x), off).LowerDistance() for x in X.tolist()) <= 1e-7
    with pytest.raises(ToleranceError):
        from_occ(off, tol=1e-15)


def test_trimmed_circle():
    c = from_occ(Geom_TrimmedCurve(Geom_Circle(gp_Ax2(gp_Pnt(1, 0, 0), gp_Dir(0, 0, 1)), 3.0), 0.5, 2.0))
    X = c.evaluate(np.linspace(*c.domain, 21))
    assert_allclose(np.linalg.norm(X - [1, 0, 0], axis=1), 3.0, rtol=2e-15, atol=0)


# ============================================================================ 2-D is out of scope
def test_two_dimensional_splines_are_refused():
    c2 = BSplineCurve(2, [0, 0, 0, 1, 1, 1], [[0, 0], [1, 1], [2, 0]])
    with pytest.raises(InvalidGeometryError, match="dim 2"):
        to_occ(c2)
    s2 = BSplineSurface((1, 1), ([0, 0, 1, 1], [0, 0, 1, 1]), np.zeros((2, 2, 2)))
    with pytest.raises(InvalidGeometryError, match="dim 2"):
        to_occ(s2)
    with pytest.raises(InvalidGeometryError, match="Geom2d_Circle"):
        from_occ(Geom2d_Circle(gp_Ax2d(), 1.0))


# ============================================================================ topology
@SETTINGS
@given(s=surfaces(degrees=st.integers(1, 5)))
@example(s=BSplineSurface((1, 1), ([1.0, 1, 2, 2], [1.0, 1, 2, 2]), np.zeros((2, 2, 3)), np.full((2, 2), 2.0)))  # CI10
def test_face_round_trip_build123d_and_cadquery(s):
    face = to_face(s)
    assert isinstance(face, bd.Face)
    want = _as_occ_stores(s)
    assert from_occ(face) == want  # B-spline surfaces come back whole and bit-exact
    assert from_occ(face.wrapped) == want
    cq_face = to_cq_face(s)
    assert isinstance(cq_face, cq.Face)
    assert from_occ(cq_face) == want


@SETTINGS
@given(c=curves(degrees=st.integers(1, 7)))
def test_edge_round_trip_build123d_and_cadquery(c):
    edge = to_edge(c)
    assert isinstance(edge, bd.Edge)
    assert from_occ(edge) == _as_occ_stores(c)
    cq_edge = to_cq_edge(c)
    assert isinstance(cq_edge, cq.Edge)
    assert from_occ(cq_edge.wrapped) == _as_occ_stores(c)


def test_located_face_gets_its_location_applied():
    rng = np.random.default_rng(4)
    s = BSplineSurface((2, 2), ([0, 0, 0, 1, 1, 1],) * 2, rng.uniform(-1, 1, (3, 3, 3)), rng.uniform(0.5, 2, (3, 3)))
    moved = bd.Pos(10, 20, 30) * to_face(s)
    back = from_occ(moved)
    assert_array_equal(back.weights, s.weights)
    # a translation applied by OCC to the poles: one rounding of the addition per coordinate
    assert_allclose(back.control_points, s.control_points + [10, 20, 30], rtol=0, atol=1e-13)


def test_box_faces_keep_their_surface_normal_and_expose_orientation():
    n_reversed = 0
    for face in bd.Box(2, 2, 2).faces():
        s = from_occ(face)
        (u0, u1), (v0, v1) = s.domain
        n = s.normal(0.5 * (u0 + u1), 0.5 * (v0 + v1))
        outward = np.array(tuple(face.center()))  # the box is centred on the origin
        assert (n @ outward < 0) == is_reversed(face)  # REVERSED faces: geometry normal points in
        n_reversed += is_reversed(face)
    assert n_reversed == 3  # so the test really sees both orientations


def test_sphere_and_cylinder_faces_are_trimmed_to_their_uv_bounds():
    sphere = from_occ(bd.Solid.make_sphere(2).faces()[0])
    (u0, u1), (v0, v1) = sphere.domain
    X = sphere.evaluate_grid(np.linspace(u0, u1, 13), np.linspace(v0, v1, 13))
    assert_allclose(np.linalg.norm(X, axis=-1), 2.0, rtol=0, atol=1e-14)  # exact image, round-off
    side = [f for f in bd.Solid.make_cylinder(1, 2).faces() if f.geom_type == bd.GeomType.CYLINDER][0]
    cyl = from_occ(side)  # an infinite surface: the face's UV box bounds it
    (u0, u1), (v0, v1) = cyl.domain
    X = cyl.evaluate_grid(np.linspace(u0, u1, 13), np.linspace(v0, v1, 13))
    assert_allclose(np.hypot(X[..., 0], X[..., 1]), 1.0, rtol=0, atol=1e-14)
    assert_allclose([X[..., 2].min(), X[..., 2].max()], [0.0, 2.0], rtol=0, atol=1e-14)


def test_edge_on_part_of_a_bspline_is_its_segment():
    c = BSplineCurve(3, [0, 0, 0, 0, 0.5, 1, 1, 1, 1], np.random.default_rng(5).uniform(-1, 1, (5, 3)))
    edge = BRepBuilderAPI_MakeEdge(to_occ(c), 0.2, 0.7).Edge()
    back = from_occ(edge)
    ours = c.segment(0.2, 0.7)
    assert_array_equal(back.knots, ours.knots)
    assert_allclose(back.control_points, ours.control_points, rtol=0, atol=1e-12)  # knot insertion round-off


def test_circle_edge():
    c = from_occ(bd.Edge.make_circle(2.0, start_angle=10, end_angle=100))
    X = c.evaluate(np.linspace(*c.domain, 11))
    assert_allclose(np.linalg.norm(X, axis=1), 2.0, rtol=0, atol=1e-14)


def test_degenerated_edge_and_non_face_shapes_are_refused():
    solid = bd.Solid.make_sphere(1).wrapped
    ex = TopExp_Explorer(solid, TopAbs_EDGE)
    degenerated = []
    while ex.More():
        e = TopoDS.Edge_s(ex.Current())
        if BRep_Tool.Degenerated_s(e):
            degenerated.append(e)
        ex.Next()
    assert degenerated
    with pytest.raises(InvalidGeometryError, match="degenerated"):
        from_occ(degenerated[0])
    # A solid is converted face by face (issue 16: every bridge function takes Solids, Shells,
    # Compounds), bit-exactly as each face alone; trimming bounds apply to one face only.
    box = bd.Solid.make_box(1, 2, 3)
    surfaces = from_occ(box)
    assert isinstance(surfaces, list) and len(surfaces) == 6
    for s, f in zip(surfaces, box.faces()):
        np.testing.assert_array_equal(s.control_points, from_occ(f).control_points)
    assert len(from_occ(solid)) == 1
    with pytest.raises(InvalidGeometryError, match="bounds"):
        from_occ(box, (0.0, 1.0, 0.0, 1.0))
    with pytest.raises(InvalidGeometryError, match="no faces and no edges"):
        from_occ(bd.Vertex(0, 0, 0))


# ============================================================================ error paths
@pytest.mark.parametrize("bad", [42, "surface", None, np.zeros((3, 3)), gp_Pnt()])
def test_wrong_types_name_the_type(bad):
    with pytest.raises(InvalidGeometryError, match=type(bad).__name__):
        to_occ(bad)
    with pytest.raises(InvalidGeometryError, match=type(bad).__name__):
        from_occ(bad)


def test_wrong_kinds_for_faces_and_edges():
    c = BSplineCurve(1, [0, 0, 1, 1], [[0, 0, 0], [1, 0, 0]])
    s = BSplineSurface((1, 1), ([0, 0, 1, 1], [0, 0, 1, 1]), np.zeros((2, 2, 3)) + [[[0, 0, 0]]])
    with pytest.raises(InvalidGeometryError, match="BSplineCurve"):
        to_face(c)
    with pytest.raises(InvalidGeometryError, match="BSplineSurface"):
        to_cq_edge(s)
    with pytest.raises(InvalidGeometryError, match="BSplineCurve"):
        from_occ(c)  # ours is not an OCC object
    with pytest.raises(InvalidGeometryError, match="int"):
        is_reversed(3)


def test_degree_above_occ_limit_is_refused_before_occ():
    p = 26
    knots = np.r_[np.zeros(p + 1), np.ones(p + 1)]
    c = BSplineCurve._trusted(p, knots, np.zeros((p + 1, 3)))
    with pytest.raises(InvalidGeometryError, match="degrees 1 to 25, got 26"):
        to_occ(c)
    s = BSplineSurface._trusted((2, p), ([0, 0, 0, 1, 1, 1], knots), np.zeros((3, p + 1, 3)))
    with pytest.raises(InvalidGeometryError, match=r"degree\[1\] \(v\)"):
        to_occ(s)


def test_interior_knot_of_multiplicity_degree_plus_one_is_refused():
    # Valid for our kernel (a discontinuous curve), not for OCC.
    c = BSplineCurve(2, [0, 0, 0, 0.5, 0.5, 0.5, 1, 1, 1], np.random.default_rng(6).uniform(-1, 1, (6, 3)))
    with pytest.raises(InvalidGeometryError, match="interior knot 0.5 has multiplicity 3"):
        to_occ(c)


def test_adjacent_float_knots_are_refused():
    k = 0.5
    c = BSplineCurve(2, [0, 0, 0, k, np.nextafter(k, 1), 1, 1, 1], np.random.default_rng(7).uniform(-1, 1, (5, 3)))
    with pytest.raises(InvalidGeometryError, match="adjacent floats"):
        to_occ(c)


def test_decreasing_knots_from_trusted_are_refused():
    c = BSplineCurve._trusted(1, np.array([0.0, 0.0, 2.0, 1.0, 1.0]), np.zeros((3, 3)))
    with pytest.raises(InvalidGeometryError, match="non-decreasing"):
        to_occ(c)


def test_occ_failure_is_wrapped_as_kernel_error():
    # Weights <= 0 slip past _trusted; OCC raises Standard_ConstructionError, we raise KernelError.
    c = BSplineCurve._trusted(1, np.array([0.0, 0.0, 1.0, 1.0]), np.eye(3)[:2], np.array([1.0, -1.0]))
    with pytest.raises(KernelError, match="Standard_ConstructionError") as info:
        to_occ(c)
    assert _occ.is_occ_exception(info.value.__cause__)


def test_kernel_errors_lets_other_exceptions_through():
    with pytest.raises(ZeroDivisionError):
        with _occ.kernel_errors("testing"):
            _ = 1 / 0


def test_knot_vector_helpers_round_trip():
    t = np.array([-1.0, -1.0, 0.25, 0.25, 0.5, 2.0, 2.0, 2.0])
    K, M = _occ.knots_to_occ(t, 2)
    assert_array_equal(_occ.from_real_array(K), [-1.0, 0.25, 0.5, 2.0])
    assert_array_equal(_occ.from_int_array(M), [2, 2, 1, 3])
    assert_array_equal(_occ.knots_from_occ(K, M), t)


@pytest.mark.parametrize(
    "bounds",
    [(-8.9e-16, 6.28318530718, 0.0, 1.0), (-1e-12, 2 * np.pi - 1e-12, 0.0, 1.0), (0.0, 2 * np.pi, -1.0, 2.0)],
)
def test_periodic_bounds_overshooting_by_round_off_are_snapped(bounds):
    # GeomConvert segfaults on the first range (a face of linkrods.step) and returns a surface
    # with no poles on the second; from_occ snaps such bounds onto the period first.
    from OCP.Geom import Geom_CylindricalSurface

    s = from_occ(Geom_CylindricalSurface(gp_Ax3(), 2.0), bounds)
    (u0, u1), (v0, v1) = s.domain
    u, v = np.linspace(u0, u1, 41), np.linspace(v0, v1, 5)
    X = s.evaluate_grid(u, v)
    # exact image of the cylinder (rational quadratic): radius error is round-off only
    assert_allclose(np.hypot(X[..., 0], X[..., 1]), 2.0, rtol=1e-14, atol=0)


def test_bounds_longer_than_a_period_are_refused():
    from OCP.Geom import Geom_CylindricalSurface

    with pytest.raises(InvalidGeometryError, match="more than one period"):
        from_occ(Geom_CylindricalSurface(gp_Ax3(), 2.0), (0.0, 7.0, 0.0, 1.0))
    with pytest.raises(InvalidGeometryError, match="more than one period"):
        from_occ(Geom_Circle(gp_Ax2(), 1.0), (0.0, 7.0))
