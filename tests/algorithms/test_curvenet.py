"""Coons patches and Gordon surfaces (algorithms/construction/, course §6-17..6-25).

Oracles: the defining formulas evaluated directly (bilinear Coons), closed forms (four lines give
the bilinear patch; networks of iso-curves of a known surface reproduce it under the stated
condition), exactness on the input curves; invariants under hypothesis (affine invariance, random
networks interpolated); every error path.

Tolerances. Exact identities are checked relative to the size of the data (``scale`` = largest
coordinate). Boundaries of a Coons net ARE the compatible boundary poles (written, not computed),
so a boundary evaluates like the input curve after degree elevation / knot refinement: the only
error is the round-off of those exact operations and of evaluation, measured below ~4e-16 x scale;
asserted at 1e-14 x scale. The bilinear-Coons formula is a sum of 7 terms evaluated separately:
measured ~3e-15 x scale, asserted 1e-13 x scale. Gordon surfaces add banded interpolation solves
whose round-off grows with the conditioning of the collocation matrices: measured <= 2e-15 x scale
on the networks here, asserted 1e-12 x scale.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from numpy.testing import assert_allclose, assert_array_equal

from occsurf.algorithms import tolerances
from occsurf.algorithms.construction import (
    _common,
    coons,
    coons_bicubic,
    gordon,
    network_parameters,
    polynomial_approximation,
)
from occsurf.algorithms.construction import coons_patches as cp
from occsurf.algorithms.construction import gordon_surfaces as gs
from occsurf.algorithms.errors import InvalidGeometryError, ToleranceError
from occsurf.algorithms.kernel.basis import basis_matrix
from occsurf.algorithms.kernel.compat import make_compatible
from occsurf.algorithms.kernel.curve import BSplineCurve
from occsurf.algorithms.kernel.surface import BSplineSurface
from tests.algorithms.strategies import affine_maps, test_settings

S = np.linspace(0.0, 1.0, 57)
UU, VV = np.meshgrid(S, S, indexing="ij")


# ------------------------------------------------------------------------------------ helpers
def iso_u(F: BSplineSurface, v: float) -> BSplineCurve:
    """The iso-curve ``F(., v)`` as an exact B-spline (rows of the net contracted with N_j(v))."""
    (p, q), (U, V) = F.degree, F.knots
    N = basis_matrix(V, q, F.n_poles[1], np.atleast_1d(float(v)))[0][0]
    H = np.einsum("j,ijk->ik", N, F.homogeneous_points)
    if F.is_rational:
        return BSplineCurve(p, U, H[:, :-1] / H[:, -1:], H[:, -1])
    return BSplineCurve(p, U, H)


def iso_v(F: BSplineSurface, u: float) -> BSplineCurve:
    return iso_u(F.swap_uv(), u)


def d_iso_u(F: BSplineSurface, v: float) -> BSplineCurve:
    """``dF/dv (., v)`` as a B-spline curve (polynomial F)."""
    (p, q), (U, V) = F.degree, F.knots
    N = basis_matrix(V, q, F.n_poles[1], np.atleast_1d(float(v)), 1)[1][0]
    return BSplineCurve(p, U, np.einsum("j,ijk->ik", N, F.control_points))


def boundary_net(F: BSplineSurface):
    b, t, l, r = iso_u(F, 0), iso_u(F, 1), iso_v(F, 0), iso_v(F, 1)
    G = F.swap_uv()
    return (b, r, t, l), (d_iso_u(F, 0), d_iso_u(G, 1), d_iso_u(F, 1), d_iso_u(G, 0))


def clamped(n: int, p: int, rng: np.random.Generator) -> np.ndarray:
    inner = np.sort(rng.uniform(0.1, 0.9, n - p - 1))
    return np.r_[np.zeros(p + 1), inner, np.ones(p + 1)]


def random_surface(rng, p=3, q=3, nu=7, nv=6, rational=False) -> BSplineSurface:
    x, y = np.meshgrid(np.linspace(0, 3, nu), np.linspace(0, 2, nv), indexing="ij")
    P = np.stack([x, y, 0.5 * rng.standard_normal((nu, nv))], axis=-1)
    w = rng.uniform(0.5, 2.0, (nu, nv)) if rational else None
    return BSplineSurface((p, q), (clamped(nu, p, rng), clamped(nv, q, rng)), P, w)


def wiggly(a, b, n, p, rng, amp=0.3) -> BSplineCurve:
    t = np.linspace(0, 1, n)[:, None]
    P = a + t * (b - a)
    P[1:-1] += amp * rng.standard_normal((n - 2, a.shape[0]))
    return BSplineCurve(p, clamped(n, p, rng), P)


CORNERS = np.array([[0, 0, 0.0], [3, 0, 0.5], [3, 2, 0.0], [0, 2, 1.0]])  # 00, 10, 11, 01


def random_loop(rng, degrees=(3, 2, 3, 1), counts=(6, 5, 7, 2)):
    P00, P10, P11, P01 = CORNERS
    b = wiggly(P00, P10, counts[0], degrees[0], rng)
    r = wiggly(P10, P11, counts[1], degrees[1], rng)
    t = wiggly(P01, P11, counts[2], degrees[2], rng)
    l = wiggly(P00, P01, counts[3], degrees[3], rng)
    return b, r, t, l


def scale_of(*objs) -> float:
    return max(float(np.abs(o.control_points).max()) for o in objs)


def check_boundaries(Sf: BSplineSurface, b, r, t, l, rtol=1e-14):
    (u0, u1), (v0, v1) = Sf.domain
    us, vs = u0 + S * (u1 - u0), v0 + S * (v1 - v0)
    sc = scale_of(b, r, t, l)
    for got, c, x in ((Sf.evaluate(us, v0), b, b.domain), (Sf.evaluate(us, v1), t, t.domain),
                      (Sf.evaluate(u0, vs), l, l.domain), (Sf.evaluate(u1, vs), r, r.domain)):
        assert_allclose(got, c.evaluate(x[0] + S * (x[1] - x[0])), rtol=0, atol=rtol * sc)


# ------------------------------------------------------------------------------------ Coons
def test_coons_boundaries_are_the_input_curves():
    b, r, t, l = random_loop(np.random.default_rng(0))
    C = coons(b, r, t, l)
    assert C.degree == (3, 2) and not C.is_rational
    check_boundaries(C, b, r, t, l)


def test_coons_equals_the_bilinear_coons_formula():
    b, r, t, l = random_loop(np.random.default_rng(1))
    C = coons(b, r, t, l)
    u, v = UU[..., None], VV[..., None]
    P00, P10, P11, P01 = CORNERS
    ref = ((1 - v) * b(UU) + v * t(UU) + (1 - u) * l(VV) + u * r(VV)
           - (1 - u) * (1 - v) * P00 - u * (1 - v) * P10 - u * v * P11 - (1 - u) * v * P01)
    assert_allclose(C.evaluate(UU, VV), ref, rtol=0, atol=1e-13 * scale_of(b, r, t, l))


def test_coons_of_four_lines_is_the_bilinear_patch():
    P00, P10, P11, P01 = CORNERS
    line = lambda a, c: BSplineCurve(1, [0, 0, 1, 1], [a, c])  # noqa: E731
    C = coons(line(P00, P10), line(P10, P11), line(P01, P11), line(P00, P01))
    assert C.degree == (1, 1) and C.n_poles == (2, 2)
    assert_allclose(C.control_points, [[P00, P01], [P10, P11]], rtol=0, atol=1e-15)
    u, v = UU[..., None], VV[..., None]
    bil = (1 - u) * (1 - v) * P00 + u * (1 - v) * P10 + u * v * P11 + (1 - u) * v * P01
    assert_allclose(C.evaluate(UU, VV), bil, rtol=0, atol=1e-14)


def test_coons_reproduces_a_surface_linear_in_one_direction():
    # P1 (ruled in v) reproduces F when F is linear in v, so (I - P1)(I - P2) F = 0.
    rng = np.random.default_rng(2)
    F = random_surface(rng, p=3, q=1, nu=6, nv=2)
    (b, r, t, l), _ = boundary_net(F)
    assert_allclose(coons(b, r, t, l).evaluate(UU, VV), F.evaluate(UU, VV), rtol=0, atol=1e-14 * scale_of(F))


def test_coons_domains_kept_or_normalised():
    b, r, t, l = random_loop(np.random.default_rng(3))
    C = coons(b.reparametrize(2, 5), r.reparametrize(-1, 1), t.reparametrize(2, 5), l.reparametrize(-1, 1))
    assert C.domain == ((2.0, 5.0), (-1.0, 1.0))
    check_boundaries(C, b.reparametrize(2, 5), r.reparametrize(-1, 1), t.reparametrize(2, 5), l.reparametrize(-1, 1))
    C2 = coons(b.reparametrize(2, 5), r, t, l)  # bottom and top disagree: both mapped to [0, 1]
    assert C2.domain == ((0.0, 1.0), (0.0, 1.0))
    check_boundaries(C2, b, r, t, l)


def test_coons_closes_small_gaps_and_moves_curves_by_at_most_the_gap():
    b, r, t, l = random_loop(np.random.default_rng(4))
    gap = 4e-8  # below NETWORK_TOLERANCE = 1e-7
    t2 = t.transform(np.eye(3), [0, 0, gap])
    C = coons(b, r, t2, l)
    assert_allclose(C.evaluate(S, 1.0), t2(S), rtol=0, atol=gap / 2 + 1e-14 * scale_of(t))
    assert_allclose(C.evaluate(0.0, S), l(S), rtol=0, atol=gap / 2 + 1e-14 * scale_of(l))
    assert np.abs(C.evaluate(S, 1.0) - t2(S)).max() > gap / 4  # the ends really moved


@pytest.mark.parametrize("which", ["bottom", "right", "top", "left"])
def test_coons_names_a_reversed_curve(which):
    curves = dict(zip(("bottom", "right", "top", "left"), random_loop(np.random.default_rng(5))))
    curves[which] = curves[which].reverse()
    with pytest.raises(InvalidGeometryError, match=rf"^{which}: the curve runs the wrong way.*{which}\.reverse\(\)"):
        coons(**curves)


def test_coons_recognises_a_head_to_tail_loop_and_names_the_fix():
    # OCC and most CAD systems take the four boundaries as a loop: top and left then run backwards.
    b, r, t, l = random_loop(np.random.default_rng(5))
    with pytest.raises(InvalidGeometryError, match=r"^top, left: the curves form a head-to-tail loop .*"
                                                   r"pass top\.reverse\(\), pass left\.reverse\(\)$"):
        coons(b, r, t.reverse(), l.reverse())
    with pytest.raises(InvalidGeometryError, match=r"^bottom, right, top, left: the curves run the wrong way"):
        coons(b.reverse(), r.reverse(), t.reverse(), l.reverse())


def test_coons_names_the_open_corner_and_the_gap():
    b, r, t, l = random_loop(np.random.default_rng(6))
    P = np.array(r.control_points)
    P[-1] += [0, 0, 0.25]  # the end of right misses the end of top
    r2 = BSplineCurve(r.degree, r.knots, P)
    with pytest.raises(InvalidGeometryError, match=r"open at corner \(u1, v1\).*top and the end of right are 0\.25 apart"):
        coons(b, r2, t, l)
    with pytest.raises(InvalidGeometryError, match="open at corner"):
        coons(b, r, t.transform(np.eye(3), [0, 0, 1e-6]), l)  # 1e-6 > tol = 1e-7
    coons(b, r, t.transform(np.eye(3), [0, 0, 1e-6]), l, tol=1e-5)  # accepted with a larger tol


def test_coons_rejects_bad_input():
    b, r, t, l = random_loop(np.random.default_rng(7))
    with pytest.raises(InvalidGeometryError, match="^left: expected a BSplineCurve, got list"):
        coons(b, r, t, [[0, 0, 0]])
    flat = BSplineCurve(1, [0, 0, 1, 1], [[0, 0], [0, 2]])
    with pytest.raises(InvalidGeometryError, match="same dimension"):
        coons(b, r, t, flat)
    with pytest.raises(InvalidGeometryError, match="tol: expected a finite value >= 0"):
        coons(b, r, t, l, tol=-1)


def test_coons_rational_boundaries_of_a_nurbs_surface_are_exact():
    F = random_surface(np.random.default_rng(8), p=2, q=2, nu=4, nv=5, rational=True)
    (b, r, t, l), _ = boundary_net(F)
    C = coons(b, r, t, l)
    assert C.is_rational
    check_boundaries(C, b, r, t, l, rtol=1e-14)
    # Scaling one boundary's weights changes nothing geometrically: still exact.
    r3 = BSplineCurve(r.degree, r.knots, r.control_points, r.weights * 3.0)
    check_boundaries(coons(b, r3, t, l), b, r3, t, l, rtol=1e-14)


def test_coons_rational_with_unmatchable_corner_weights_is_approximated():
    F = random_surface(np.random.default_rng(9), p=2, q=2, nu=4, nv=4, rational=True)
    (b, r, t, l), _ = boundary_net(F)
    w = np.array(t.weights)
    w[-1] *= 2.0  # changes the curve and the loop's weight-ratio product; corners still meet
    t2 = BSplineCurve(t.degree, t.knots, t.control_points, w)
    C = coons(b, r, t2, l, approx_tol=1e-8)
    assert not C.is_rational
    # each boundary within its approximation's measured error (<= approx_tol)
    check_boundaries(C, b, r, t2, l, rtol=1e-8 / scale_of(b, r, t2, l))
    assert np.abs(C.evaluate(S, 1.0) - t2(S)).max() > 1e-14  # really an approximation
    with pytest.raises(ToleranceError, match="could not approximate"):
        coons(b, r, t2, l, approx_tol=1e-30)


@given(data=st.data())
@test_settings(15)
def test_coons_affine_invariance(data):
    seed = data.draw(st.integers(0, 2**31 - 1))
    M, v = data.draw(affine_maps(3))
    rng = np.random.default_rng(seed)
    degrees = tuple(data.draw(st.integers(1, 4)) for _ in range(4))
    counts = tuple(d + 1 + data.draw(st.integers(0, 3)) for d in degrees)
    b, r, t, l = random_loop(rng, degrees, counts)
    C = coons(b, r, t, l)
    CT = coons(*(c.transform(M, v) for c in (b, r, t, l)))
    sc = np.abs(CT.control_points).max() + np.abs(M).max() * scale_of(b, r, t, l)
    # both are the same linear combinations of (transformed) poles; M and v add round-off only
    assert_allclose(CT.control_points, C.control_points @ M.T + v, rtol=0, atol=1e-13 * sc)
    check_boundaries(C, b, r, t, l)


# ------------------------------------------------------------------------------------ bicubic Coons
def test_bicubic_coons_interpolates_boundaries_and_cross_derivatives():
    F = random_surface(np.random.default_rng(10), nu=7, nv=6)
    curves, xd = boundary_net(F)
    C = coons_bicubic(*curves, cross_derivatives=xd)
    assert C.degree == (3, 3)
    sc = scale_of(F)
    D, DF = C.derivatives_grid(S, [0, 1], 1), F.derivatives_grid(S, [0, 1], 1)
    assert_allclose(D[:, :, 0, 0], DF[:, :, 0, 0], rtol=0, atol=1e-14 * sc)
    # derivatives scale with the degree over the shortest span (~3 / 0.1): 1e-12 x scale
    assert_allclose(D[:, :, 0, 1], DF[:, :, 0, 1], rtol=0, atol=1e-12 * sc)
    D, DF = C.derivatives_grid([0, 1], S, 1), F.derivatives_grid([0, 1], S, 1)
    assert_allclose(D[:, :, 0, 0], DF[:, :, 0, 0], rtol=0, atol=1e-14 * sc)
    assert_allclose(D[:, :, 1, 0], DF[:, :, 1, 0], rtol=0, atol=1e-12 * sc)


def test_bicubic_coons_reproduces_a_bicubic_bezier_patch():
    rng = np.random.default_rng(11)
    F = BSplineSurface((3, 3), ([0] * 4 + [1] * 4,) * 2, rng.standard_normal((4, 4, 3)))
    curves, xd = boundary_net(F)
    assert_allclose(coons_bicubic(*curves, cross_derivatives=xd).evaluate(UU, VV), F.evaluate(UU, VV),
                    rtol=0, atol=1e-13 * scale_of(F))
    # zero twists: no longer the patch (F has non-zero twists), cross derivatives off
    Z = coons_bicubic(*curves, cross_derivatives=xd, twists="zero")
    assert np.abs(Z.evaluate(UU, VV) - F.evaluate(UU, VV)).max() > 1e-3
    # explicit twists equal to F's reproduce it again
    W = F.derivatives(np.array([0, 1, 1, 0.0]), np.array([0, 0, 1, 1.0]), 1)[:, 1, 1]
    assert_allclose(coons_bicubic(*curves, cross_derivatives=xd, twists=W).evaluate(UU, VV), F.evaluate(UU, VV),
                    rtol=0, atol=1e-13 * scale_of(F))


def test_bicubic_coons_error_paths():
    F = random_surface(np.random.default_rng(12))
    (b, r, t, l), (xb, xr, xt, xl) = boundary_net(F)
    with pytest.raises(InvalidGeometryError, match=r"cross_derivatives\[0\]: at corner \(u0, v0\).*tangent of left"):
        coons_bicubic(b, r, t, l, cross_derivatives=(xb.transform(np.eye(3), [0, 0, 1]), xr, xt, xl))
    with pytest.raises(InvalidGeometryError, match=r"cross_derivatives: expected at least 4 curves, got 3"):
        coons_bicubic(b, r, t, l, cross_derivatives=(xb, xr, xt))
    with pytest.raises(InvalidGeometryError, match=r"cross_derivatives\[1\]: expected the domain"):
        coons_bicubic(b, r, t, l, cross_derivatives=(xb, xr.reparametrize(0, 2), xt, xl))
    with pytest.raises(InvalidGeometryError, match="twists: expected 'average', 'zero'"):
        coons_bicubic(b, r, t, l, cross_derivatives=(xb, xr, xt, xl), twists="adini")
    with pytest.raises(InvalidGeometryError, match=r"twists: expected shape \(4, 3\)"):
        coons_bicubic(b, r, t, l, cross_derivatives=(xb, xr, xt, xl), twists=np.zeros((3, 3)))
    with pytest.raises(InvalidGeometryError, match="wrong way"):
        coons_bicubic(b.reverse(), r, t, l, cross_derivatives=(xb, xr, xt, xl))


# ------------------------------------------------------------------------------------ Gordon
def network(F, us, vs):
    return [iso_u(F, v) for v in vs], [iso_v(F, u) for u in us]


def check_network(G, A, B, us, vs, rtol=1e-12):
    sc = scale_of(*A, *B)
    for a, v in zip(A, vs):
        assert_allclose(G.evaluate(S, v), a(S), rtol=0, atol=rtol * sc)
    for b, u in zip(B, us):
        assert_allclose(G.evaluate(u, S), b(S), rtol=0, atol=rtol * sc)


def test_gordon_interpolates_every_network_curve():
    F = random_surface(np.random.default_rng(20))
    us, vs = np.array([0, 0.15, 0.4, 0.6, 0.85, 1.0]), np.array([0, 0.2, 0.45, 0.7, 1.0])
    A, B = network(F, us, vs)
    G = gordon(A, B)
    check_network(G, A, B, us, vs)
    assert G.degree == (3, 3)
    # a 5 x 6 network of a surface with interior knots in both directions does not determine it
    assert np.abs(G.evaluate(UU, VV) - F.evaluate(UU, VV)).max() > 1e-3


def test_gordon_parameters_found_by_closest_points():
    F = random_surface(np.random.default_rng(21))
    us, vs = np.array([0, 0.3, 0.7, 1.0]), np.array([0, 0.25, 0.5, 0.9, 1.0])
    A, B = network(F, us, vs)
    s, t, d = network_parameters(A, B)
    assert_allclose(s, np.broadcast_to(us, s.shape), rtol=0, atol=1e-12)
    assert_allclose(t, np.broadcast_to(vs[:, None], t.shape), rtol=0, atol=1e-12)
    assert d.max() < 1e-13 * scale_of(F)
    G1, G2 = gordon(A, B), gordon(A, B, u_params=us, v_params=vs)
    assert_allclose(G1.control_points, G2.control_points, rtol=0, atol=1e-12 * scale_of(F))


def test_gordon_reproduces_the_surface_when_the_cross_space_contains_it():
    F = random_surface(np.random.default_rng(22))
    # v: the u-curves at F's v Greville abscissae with F's v knots across v => P1 F = F.
    vs = F.greville()[1]
    us = np.array([0, 0.5, 1.0])
    A, B = network(F, us, vs)
    G = gordon(A, B, cross_knots=(None, F.knots[1]))
    assert_allclose(G.evaluate(UU, VV), F.evaluate(UU, VV), rtol=0, atol=1e-13 * scale_of(F))
    # u likewise (swap the roles)
    us2 = F.greville()[0]
    A2, B2 = network(F, us2, np.array([0, 0.4, 1.0]))
    G2 = gordon(A2, B2, cross_knots=(F.knots[0], None))
    assert_allclose(G2.evaluate(UU, VV), F.evaluate(UU, VV), rtol=0, atol=1e-13 * scale_of(F))
    # a polynomial-in-v surface of degree 3 is reproduced by any >= 4 u-curves (default knots)
    Fb = random_surface(np.random.default_rng(23), q=3, nv=4)
    A3, B3 = network(Fb, np.array([0, 0.5, 1.0]), np.array([0, 0.2, 0.7, 1.0]))
    assert_allclose(gordon(A3, B3).evaluate(UU, VV), Fb.evaluate(UU, VV), rtol=0, atol=1e-13 * scale_of(Fb))


def test_gordon_network_inside_the_domain_extrapolates_consistently():
    F = random_surface(np.random.default_rng(24))
    us, vs = np.array([0.1, 0.4, 0.6, 0.9]), np.array([0.05, 0.5, 0.8, 0.95])
    A, B = network(F, us, vs)
    G = gordon(A, B)
    assert G.domain == ((0.0, 1.0), (0.0, 1.0))
    check_network(G, A, B, us, vs)


@given(data=st.data())
@test_settings(15)
def test_gordon_random_networks_are_interpolated(data):
    rng = np.random.default_rng(data.draw(st.integers(0, 2**31 - 1)))
    p, q = data.draw(st.integers(1, 4)), data.draw(st.integers(1, 4))
    F = random_surface(rng, p=p, q=q, nu=p + 1 + data.draw(st.integers(0, 3)), nv=q + 1 + data.draw(st.integers(0, 3)),
                       rational=data.draw(st.booleans()))
    m, n = data.draw(st.integers(2, 6)), data.draw(st.integers(2, 6))
    gaps = lambda k: np.cumsum(rng.uniform(0.3, 1.0, k))  # noqa: E731  well-separated parameters
    us, vs = gaps(n), gaps(m)
    us, vs = (us - us[0]) / (us[-1] - us[0]), (vs - vs[0]) / (vs[-1] - vs[0])
    A, B = network(F, us, vs)
    deg = (data.draw(st.integers(1, 4)), data.draw(st.integers(1, 4)))
    G = gordon(A, B, u_params=us, v_params=vs, degree=deg)
    # Rational networks of iso-curves meet in homogeneous space too: built exactly, unless the
    # homogeneous Boolean sum has a non-positive weight (then approximated within 1e-6).
    exact = G.is_rational == F.is_rational
    check_network(G, A, B, us, vs, rtol=1e-12 if exact else 1e-5 / scale_of(F))
    if not exact:
        return  # the approximation's refinement depends on distances, which an affine map scales
    M, v = data.draw(affine_maps(3))
    GT = gordon([a.transform(M, v) for a in A], [b.transform(M, v) for b in B], u_params=us, v_params=vs, degree=deg)
    sc = np.abs(GT.control_points).max() + np.abs(M).max() * scale_of(F)
    assert_allclose(GT.evaluate(UU, VV), G.evaluate(UU, VV) @ M.T + v, rtol=0, atol=1e-11 * sc)


def test_gordon_rational_network_not_meeting_homogeneously_is_approximated():
    F = random_surface(np.random.default_rng(25), p=2, q=2, nu=4, nv=4, rational=True)
    us, vs = np.array([0, 0.25, 0.5, 0.8, 1]), np.array([0, 0.3, 0.6, 1])
    A, B = network(F, us, vs)
    A[1] = BSplineCurve(A[1].degree, A[1].knots, A[1].control_points, A[1].weights * 3)  # same curve
    G = gordon(A, B, approx_tol=1e-7)
    assert not G.is_rational
    # within the approximation error of each curve (<= 1e-7), plus the interpolants of the
    # differences of the approximations at the crossings (same order)
    check_network(G, A, B, us, vs, rtol=1e-6 / scale_of(*A, *B))


def test_gordon_error_paths():
    F = random_surface(np.random.default_rng(26))
    us, vs = np.array([0, 0.3, 0.7, 1.0]), np.array([0, 0.5, 1.0])
    A, B = network(F, us, vs)
    with pytest.raises(InvalidGeometryError, match="u_curves: expected at least 2 curves, got 1"):
        gordon(A[:1], B)
    with pytest.raises(InvalidGeometryError, match=r"u_params: expected 4 values \(one per v-curve"):
        gordon(A, B, u_params=[0, 1], v_params=vs)
    with pytest.raises(InvalidGeometryError, match="u_params: expected strictly increasing"):
        gordon(A, B, u_params=[0, 0.7, 0.3, 1.0], v_params=vs)
    with pytest.raises(InvalidGeometryError, match="v_curves: expected strictly increasing.*order the v-curves by increasing u"):
        gordon(A, B[::-1])
    far = B[1].transform(np.eye(3), [0, 0, 0.5])
    with pytest.raises(InvalidGeometryError, match=r"u_curves\[\d\], v_curves\[1\]: the curves do not meet: closest distance 0\.\d+ at u="):
        gordon(A, [B[0], far, B[2], B[3]])
    with pytest.raises(InvalidGeometryError, match=r"the network is not consistent"):
        gordon(A, B, u_params=[0, 0.35, 0.7, 1.0], v_params=vs)
    with pytest.raises(InvalidGeometryError, match=r"degree: expected a pair"):
        gordon(A, B, degree=3)
    with pytest.raises(InvalidGeometryError, match=r"cross_knots\[1\]: expected 6 values"):
        gordon(A, B, cross_knots=(None, [0, 0, 0, 1, 1]))


def test_gordon_inconsistent_parametrisation_is_explained():
    # Lines y = v_i (u = x) and x = u_j (v = y); the middle u-line is parametrised by x = u^2,
    # so it crosses x = u_j at u = sqrt(u_j): the curves meet, the parameters do not agree.
    us, vs = np.array([0, 0.25, 0.5, 1.0]), np.array([0, 0.5, 1.0])
    A = [BSplineCurve(1, [0, 0, 1, 1], [[0, y, 0], [1, y, 0]]) for y in vs]
    A[1] = BSplineCurve(2, [0, 0, 0, 1, 1, 1], [[0, 0.5, 0], [0, 0.5, 0], [1, 0.5, 0]])
    B = [BSplineCurve(1, [0, 0, 1, 1], [[x, 0, 0], [x, 1, 0]]) for x in us]
    with pytest.raises(InvalidGeometryError, match=r"u_curves\[1\], v_curves\[\d\]: the network is not consistent"):
        gordon(A, B)


# ------------------------------------------------------------------------------------ approximation
def test_polynomial_approximation_measured_error_holds_on_dense_samples():
    F = random_surface(np.random.default_rng(30), p=2, q=2, nu=5, nv=4, rational=True)
    c = iso_u(F, 0.37)
    for tol in (1e-4, 1e-8):
        a, err = polynomial_approximation(c, tol)
        assert not a.is_rational and err <= tol
        x = np.linspace(0, 1, 4001)
        dense = float(np.max(np.linalg.norm(a(x) - c(x), axis=-1)))
        # the measured error is a sampled maximum: a denser sampling may exceed it only slightly
        assert dense <= 1.1 * err + 1e-15
        assert_allclose(a(np.array([0.0, 1.0])), c(np.array([0.0, 1.0])), rtol=0, atol=1e-14 * scale_of(c))
    poly = iso_u(random_surface(np.random.default_rng(31)), 0.5)
    assert polynomial_approximation(poly) == (poly, 0.0)
    assert tolerances.APPROXIMATION_TOLERANCE == 1e-6
    with pytest.raises(ToleranceError, match="could not approximate"):
        polynomial_approximation(c, 1e-30, max_subdivisions=4)


def test_coons_of_arcs_whose_homogeneous_net_has_non_positive_weights_is_approximated():
    """Review: four single-segment 120-degree arcs (middle weight 0.5) match at their corners, but
    their homogeneous Coons net gets weight 0 inside; coons used to raise with advice that could
    not help. It falls back to polynomial boundaries within approx_tol, as gordon does."""
    def arc(a, m, b, w):
        return BSplineCurve(2, [0, 0, 0, 1, 1, 1], np.array([a, m, b], float), np.array([1.0, w, 1.0]))

    A, B, C, D = [0.0, 0, 0], [1.0, 0, 0], [1.0, 1, 0], [0.0, 1, 0]
    b, r = arc(A, [.5, -.5, 0], B, 0.5), arc(B, [1.5, .5, 0], C, 0.5)
    t, l = arc(D, [.5, 1.5, 0], C, 0.5), arc(A, [-.5, .5, 0], D, 0.5)
    s = coons(b, r, t, l, approx_tol=1e-7)
    assert s.weights is None
    x = np.linspace(0, 1, 201)
    (u0, u1), (v0, v1) = s.domain
    for curve, pts in ((b, s.evaluate(u0 + x * (u1 - u0), v0)), (t, s.evaluate(u0 + x * (u1 - u0), v1)),
                       (l, s.evaluate(u0, v0 + x * (v1 - v0))), (r, s.evaluate(u1, v0 + x * (v1 - v0)))):
        # at equal parameters: an upper bound of the distance between the curves
        assert np.linalg.norm(pts - curve.evaluate(x), axis=1).max() <= 1e-7


def test_gordon_of_a_network_closed_around_a_cylinder():
    """Review: the last v-line sits on the circles' seam; its crossing was found at u = 0 instead of
    u = 2 pi and the network was refused as unordered. The parameters are unwrapped on closed
    curves, and the surface is the exact cylinder."""
    from occsurf.algorithms import circle

    circ = [circle([0, 0, z], 1.0, normal=[0, 0, 1]) for z in (0.0, 1.0, 2.0)]
    pts = [circ[0].evaluate(a) for a in np.linspace(0, 2 * np.pi, 5)]
    lines = [BSplineCurve(1, [0, 0, 1, 1], np.array([p, p + [0, 0, 2]])) for p in pts]
    g = gordon(circ, lines)
    ref = gordon(circ, lines, u_params=np.linspace(0, 2 * np.pi, 5))
    assert_allclose(g.control_points, ref.control_points, atol=1e-14)
    X = g.evaluate_grid(np.linspace(0, 2 * np.pi, 61), np.linspace(0, 1, 7))
    assert_allclose(np.linalg.norm(X[..., :2], axis=-1), 1.0, atol=1e-14)


def test_gordon_finds_the_parameters_of_a_large_network():
    """A 12 x 12 network of 40-span iso-curves (the parameter search used a dense all-pairs distance
    matrix and a full sort per curve pair; now a k-d tree): the found parameters give the surface
    built from the true ones."""
    n = 43
    U = np.r_[[0.0] * 4, np.linspace(0, 1, 41)[1:-1], [1.0] * 4]
    X, Y = np.meshgrid(np.linspace(0, 10, n), np.linspace(0, 10, n), indexing="ij")
    S = BSplineSurface((3, 3), (U, U), np.stack([X, Y, np.sin(X) * np.cos(Y)], -1))
    us = np.linspace(0, 1, 12)
    A, B = [iso_u(S, v) for v in us], [iso_v(S, u) for u in us]
    found = gordon(A, B)
    given = gordon(A, B, u_params=us, v_params=us)
    assert_allclose(found.control_points, given.control_points, atol=1e-11)


# ------------------------------------------------------------------------------------ tolerances
def test_network_tolerance_override_turns_an_accepted_gap_into_a_refusal_and_back():
    b, r, t, l = random_loop(np.random.default_rng(4))
    t2 = t.transform(np.eye(3), [0, 0, 4e-8])  # corner gaps of 4e-8 < NETWORK_TOLERANCE = 1e-7
    coons(b, r, t2, l)
    with tolerances.override(NETWORK_TOLERANCE=1e-8):
        with pytest.raises(InvalidGeometryError, match=r"open at corner .*\(tol=1e-08\)"):
            coons(b, r, t2, l)
        coons(b, r, t2, l, tol=1e-7)  # an explicit tol= wins over the override
    coons(b, r, t2, l)  # the default is back


def test_network_tolerance_override_applies_to_gordon_crossings():
    F = random_surface(np.random.default_rng(20))
    us, vs = np.array([0, 0.4, 1.0]), np.array([0, 0.5, 1.0])
    A, B = network(F, us, vs)
    A[1] = A[1].transform(np.eye(3), [0, 0, 4e-8])
    gordon(A, B, u_params=us, v_params=vs)
    with tolerances.override(NETWORK_TOLERANCE=1e-8):
        with pytest.raises(InvalidGeometryError, match=r"not consistent.*\(tol=1e-08\)"):
            gordon(A, B, u_params=us, v_params=vs)
    gordon(A, B, u_params=us, v_params=vs)


def test_derivative_tolerance_override_decides_the_corner_compatibility_check():
    F = random_surface(np.random.default_rng(12))
    (b, r, t, l), (xb, xr, xt, xl) = boundary_net(F)
    xb2 = xb.transform(np.eye(3), [0, 0, 1e-5])  # S_v along bottom 1e-5 off the tangents of left / right
    with pytest.raises(InvalidGeometryError, match=r"^cross_derivatives\[0\]: at corner \(u0, v0\)"):
        coons_bicubic(b, r, t, l, cross_derivatives=(xb2, xr, xt, xl))
    with tolerances.override(DERIVATIVE_TOLERANCE=1e-3):
        coons_bicubic(b, r, t, l, cross_derivatives=(xb2, xr, xt, xl))


def test_approximation_tolerance_override_is_the_default_of_polynomial_approximation():
    F = random_surface(np.random.default_rng(30), p=2, q=2, nu=5, nv=4, rational=True)
    c = iso_u(F, 0.37)
    _, err = polynomial_approximation(c)
    assert 1e-10 < err <= 1e-6  # measured 6.4e-7
    with tolerances.override(APPROXIMATION_TOLERANCE=1e-10):
        _, err2 = polynomial_approximation(c)
    assert err2 <= 1e-10


def line_w(p, q, w) -> BSplineCurve:
    return BSplineCurve(1, [0, 0, 1, 1], np.array([p, q], float), np.array(w, float))


def test_scale_loop_weights_matches_homogeneous_corners_within_the_weight_rtol():
    P00, P10, P11, P01 = CORNERS
    # bottom, right, top, left: the corner-weight ratios around the loop multiply to 1 + 1e-10
    loop = [line_w(P00, P10, [1, 2]), line_w(P10, P11, [1, 1]), line_w(P01, P11, [1, 2 * (1 + 1e-10)]),
            line_w(P00, P01, [1, 1])]
    assert cp._scale_loop_weights(loop) is None  # 1e-10 > HOMOGENEOUS_WEIGHT_RTOL = 1e-12
    with tolerances.override(HOMOGENEOUS_WEIGHT_RTOL=1e-8):
        b, r, t, l = cp._scale_loop_weights(loop)
    assert_allclose([b.weights[0], b.weights[-1], t.weights[0], t.weights[-1]],
                    [l.weights[0], r.weights[0], l.weights[-1], r.weights[-1]], rtol=1e-8)
    for c, c0 in zip((b, r, t, l), loop):  # each scaled by a constant: the curves do not change
        assert_allclose(c.weights / c0.weights, c.weights[0] / c0.weights[0], rtol=1e-15)
        assert_allclose(c(S), c0(S), rtol=0, atol=1e-14 * scale_of(c0))


def test_homogeneous_weight_rtol_override_decides_whether_gordon_curves_meet_homogeneously():
    F = random_surface(np.random.default_rng(25), p=2, q=2, nu=4, nv=4, rational=True)
    us, vs = np.array([0, 0.25, 0.5, 0.8, 1]), np.array([0, 0.3, 0.6, 1])
    A, B = network(F, us, vs)
    A, B = make_compatible(A), make_compatible(B)
    assert gs._homogeneous_crossing_points(A, B, us, vs) is not None
    # the same curve, weights scaled by 1 + 1e-8 > 1e3 HOMOGENEOUS_WEIGHT_RTOL
    A[1] = BSplineCurve(A[1].degree, A[1].knots, A[1].control_points, A[1].weights * (1 + 1e-8))
    assert gs._homogeneous_crossing_points(A, B, us, vs) is None
    with tolerances.override(HOMOGENEOUS_WEIGHT_RTOL=1e-9):
        assert gs._homogeneous_crossing_points(A, B, us, vs) is not None


def test_gordon_search_limits_are_read_from_tolerances():
    F = random_surface(np.random.default_rng(21))
    us, vs = np.array([0, 0.3, 0.7, 1.0]), np.array([0, 0.25, 0.5, 0.9, 1.0])
    A, B = network(F, us, vs)
    spans = np.unique(A[0].knots).shape[0] - 1  # 4: GORDON_SAMPLES_PER_SPAN = 8 > 16 / 4
    assert gs._samples(A[0]).shape == (8 * spans + 1,)
    with tolerances.override(GORDON_SAMPLES_PER_SPAN=20):
        assert gs._samples(A[0]).shape == (20 * spans + 1,)
    with tolerances.override(GORDON_NEWTON_STEPS=0):
        _, _, d0 = network_parameters(A, B)  # the closest sample pairs, not refined
    assert d0.max() > 1e-3  # measured 0.055
    with tolerances.override(GORDON_STARTS=1):
        s, t, d = network_parameters(A, B)  # one start per pair suffices on this network
    assert_allclose(s, np.broadcast_to(us, s.shape), rtol=0, atol=1e-12)
    assert d.max() < 1e-13 * scale_of(F)


# ------------------------------------------------------------------------------------ shared helpers
def test_resolve_tolerance_and_curve_checks_name_the_argument():
    c = BSplineCurve(1, [0, 0, 1, 1], [[0, 0, 0], [1, 0, 0]])
    assert _common.resolve_tolerance(None, 0.5) == 0.5
    assert _common.resolve_tolerance(2, 0.5) == 2.0
    for bad in (-1.0, np.nan, np.inf):
        with pytest.raises(InvalidGeometryError, match=r"^approx_tol: expected a finite value >= 0"):
            _common.resolve_tolerance(bad, 0.5, "approx_tol")
    assert _common.check_curves((c, c), "u_curves") == [c, c]
    with pytest.raises(InvalidGeometryError, match=r"^u_curves: expected a sequence of BSplineCurve, got int"):
        _common.check_curves(3, "u_curves")
    with pytest.raises(InvalidGeometryError, match=r"^u_curves: expected at least 2 curves, got 1"):
        _common.check_curves([c], "u_curves")
    with pytest.raises(InvalidGeometryError, match=r"^u_curves\[1\]: expected a BSplineCurve, got str"):
        _common.check_curves([c, "c"], "u_curves")


def test_homogeneous_poles():
    P = np.array([[0, 0, 0], [1, 2, 0], [3, 1, 1.0]])
    w = np.array([1.0, 0.5, 2.0])
    c = BSplineCurve(2, [0, 0, 0, 1, 1, 1], P, w)
    assert_array_equal(_common.homogeneous_poles(c, False), P)
    assert_allclose(_common.homogeneous_poles(c, True), np.c_[P * w[:, None], w], rtol=1e-15)
    poly = BSplineCurve(2, [0, 0, 0, 1, 1, 1], P)
    assert_array_equal(_common.homogeneous_poles(poly, True), np.c_[P, np.ones(3)])


def test_unify_nets_gives_one_degree_and_knot_pair_and_keeps_every_surface():
    rng = np.random.default_rng(40)
    F1 = random_surface(rng, p=2, q=3, nu=5, nv=6, rational=True)
    F2 = random_surface(rng, p=3, q=1, nu=6, nv=3, rational=True)
    deg, kn, nets = _common.unify_nets([(F.degree, F.knots, F.homogeneous_points) for F in (F1, F2)])
    assert deg == (3, 3)
    assert nets[0].shape == nets[1].shape == (kn[0].shape[0] - 4, kn[1].shape[0] - 4, 4)
    for F, H in zip((F1, F2), nets):
        assert H.flags.c_contiguous
        G = _common.surface_from_net(deg, kn, H, True, "test")
        assert_allclose(G.evaluate(UU, VV), F.evaluate(UU, VV), rtol=0, atol=1e-14 * scale_of(F))


def test_surface_from_net_divides_out_the_weights_and_refuses_non_positive_ones():
    F = random_surface(np.random.default_rng(41), rational=True)
    G = _common.surface_from_net(F.degree, F.knots, F.homogeneous_points, True, "gordon")
    assert_allclose(G.control_points, F.control_points, rtol=1e-14)
    assert_allclose(G.weights, F.weights, rtol=1e-15)
    P = _common.surface_from_net(F.degree, F.knots, F.control_points, False, "gordon")
    assert not P.is_rational and np.array_equal(P.control_points, F.control_points)
    H = np.array(F.homogeneous_points)
    H[2, 3] *= -1.0
    with pytest.raises(InvalidGeometryError, match=r"^gordon: the homogeneous construction gives non-positive weights"):
        _common.surface_from_net(F.degree, F.knots, H, True, "gordon")


# ------------------------------------------------------------------------------------ Coons steps
def test_compatible_loop_gives_each_pair_one_degree_and_one_knot_vector():
    loop = random_loop(np.random.default_rng(3))  # degrees 3, 2, 3, 1
    b, r, t, l = cp._compatible_loop(*loop, 1e-7, True, 1e-6)
    assert b.degree == t.degree == 3 and l.degree == r.degree == 2
    assert_array_equal(b.knots, t.knots)
    assert_array_equal(l.knots, r.knots)
    for c, c0 in zip((b, r, t, l), loop):
        assert_allclose(c(S), c0(S), rtol=0, atol=1e-14 * scale_of(c0))
    P = lambda c, k: c.control_points[k]  # noqa: E731
    for (c1, k1), (c2, k2) in (((b, 0), (l, 0)), ((b, -1), (r, 0)), ((t, -1), (r, -1)), ((t, 0), (l, -1))):
        assert_array_equal(P(c1, k1), P(c2, k2))  # one corner point, bit for bit


def test_boolean_sum_writes_the_boundary_rows_of_its_terms():
    A, B, C = np.random.default_rng(42).standard_normal((3, 5, 4, 3))
    H = cp._boolean_sum(A, B, C)
    assert_array_equal(H[1:-1, 1:-1], (A + B - C)[1:-1, 1:-1])
    assert_array_equal(H[1:-1, [0, -1]], A[1:-1, [0, -1]])  # the v = v0, v1 boundaries come from A
    assert_array_equal(H[[0, -1]], B[[0, -1]])  # the u = u0, u1 boundaries from B


def test_homogeneous_coons_net_is_none_without_an_exact_nurbs_form():
    F = random_surface(np.random.default_rng(9), p=2, q=2, nu=4, nv=4, rational=True)
    (b, r, t, l), _ = boundary_net(F)
    deg, kn, H = cp._homogeneous_coons_net(*cp._compatible_loop(b, r, t, l, 1e-7, True, 1e-6), "linear")
    assert deg == (2, 2) and H.shape[-1] == 4 and np.all(H[..., -1] > 0)
    w = np.array(t.weights)
    w[-1] *= 2.0  # the corner-weight ratios no longer multiply to 1
    t2 = BSplineCurve(t.degree, t.knots, t.control_points, w)
    assert cp._homogeneous_coons_net(*cp._compatible_loop(b, r, t2, l, 1e-7, True, 1e-6), "linear") is None

    def arc(a, m, e):  # a 120-degree arc: its homogeneous Coons net has weight 0 inside
        return BSplineCurve(2, [0, 0, 0, 1, 1, 1], np.array([a, m, e], float), np.array([1.0, 0.5, 1.0]))

    A_, B_, C_, D_ = [0.0, 0, 0], [1.0, 0, 0], [1.0, 1, 0], [0.0, 1, 0]
    arcs = (arc(A_, [.5, -.5, 0], B_), arc(B_, [1.5, .5, 0], C_), arc(D_, [.5, 1.5, 0], C_), arc(A_, [-.5, .5, 0], D_))
    assert cp._homogeneous_coons_net(*cp._compatible_loop(*arcs, 1e-7, True, 1e-6), "linear") is None


def test_corner_data_of_a_surface_are_its_corner_derivatives():
    F = random_surface(np.random.default_rng(10))
    (b, r, t, l), (xb, xr, xt, xl) = boundary_net(F)
    corners = cp._corner_data(b, t, xb, xt, l, r, xl, xr)
    D = F.derivatives(np.array([0, 1, 1, 0.0]), np.array([0, 0, 1, 1.0]), 1)  # corners 00, 10, 11, 01
    sc = scale_of(F)
    assert_allclose(corners.points, D[:, 0, 0], rtol=0, atol=1e-14 * sc)
    for field, (i, j) in (("su", (1, 0)), ("tangent_u", (1, 0)), ("sv", (0, 1)), ("tangent_v", (0, 1)),
                          ("twist_u", (1, 1)), ("twist_v", (1, 1))):
        # derivatives scale with the degree over the shortest span: 1e-11 x scale
        assert_allclose(getattr(corners, field), D[:, i, j], rtol=0, atol=1e-11 * sc, err_msg=field)
    cp._check_corner_derivatives(corners)  # compatible data: no error
    with pytest.raises(InvalidGeometryError, match=r"^cross_derivatives\[3\]: at corner \(u0, v0\) .*along left .*"
                                                   r"tangent of bottom"):
        cp._check_corner_derivatives(corners._replace(su=corners.su + [0, 0, 1e-3]))


def test_corner_twists_average_zero_or_given():
    rng = np.random.default_rng(43)
    corners = cp._CornerData(*rng.standard_normal((7, 4, 3)))
    assert_array_equal(cp._corner_twists("average", corners), (corners.twist_u + corners.twist_v) / 2)
    assert_array_equal(cp._corner_twists("zero", corners), np.zeros((4, 3)))
    W = rng.standard_normal((4, 3))
    assert_array_equal(cp._corner_twists(W, corners), W)
    with pytest.raises(InvalidGeometryError, match=r"^twists: expected 'average', 'zero' or an array of shape "):
        cp._corner_twists("adini", corners)
    with pytest.raises(InvalidGeometryError, match=r"^twists: expected shape \(4, 3\), got \(4, 2\)"):
        cp._corner_twists(W[:, :2], corners)


def test_hermite_corner_patch_interpolates_the_corner_data():
    rng = np.random.default_rng(44)
    corners = cp._CornerData(*rng.standard_normal((7, 4, 3)))
    W = rng.standard_normal((4, 3))
    T = cp._hermite_corner_patch(corners, W, 2.0, 0.5)
    patch = BSplineSurface((3, 3), ([0] * 4 + [2] * 4, [0] * 4 + [0.5] * 4), T)
    D = patch.derivatives(np.array([0, 2, 2, 0.0]), np.array([0, 0, 0.5, 0.5]), 1)
    assert_allclose(D[:, 0, 0], corners.points, rtol=0, atol=1e-14)
    assert_allclose(D[:, 1, 0], corners.su, rtol=0, atol=1e-13)
    assert_allclose(D[:, 0, 1], corners.sv, rtol=0, atol=1e-13)
    assert_allclose(D[:, 1, 1], W, rtol=0, atol=1e-13)


def test_bicubic_terms_each_interpolate_their_data():
    F = random_surface(np.random.default_rng(10))
    (b, r, t, l), (xb, xr, xt, xl) = boundary_net(F)
    u_side, v_side = make_compatible([b, t, xb, xt]), make_compatible([l, r, xl, xr])
    corners = cp._corner_data(*u_side, *v_side)
    L1, L2, T = (BSplineSurface(*net) for net in
                 cp._bicubic_terms(u_side, v_side, corners, cp._corner_twists("average", corners)))
    sc = scale_of(F)
    D = L1.derivatives_grid(S, [0, 1], 1)  # Hermite in v: bottom, top and their S_v at v0, v1
    for got, c in ((D[:, 0, 0, 0], b), (D[:, 1, 0, 0], t), (D[:, 0, 0, 1], xb), (D[:, 1, 0, 1], xt)):
        assert_allclose(got, c(S), rtol=0, atol=1e-12 * sc)
    D = L2.derivatives_grid([0, 1], S, 1)  # Hermite in u: left, right and their S_u at u0, u1
    for got, c in ((D[0, :, 0, 0], l), (D[1, :, 0, 0], r), (D[0, :, 1, 0], xl), (D[1, :, 1, 0], xr)):
        assert_allclose(got, c(S), rtol=0, atol=1e-12 * sc)
    DT = T.derivatives(np.array([0, 1, 1, 0.0]), np.array([0, 0, 1, 1.0]), 1)
    assert_allclose(DT[:, 0, 0], corners.points, rtol=0, atol=1e-13 * sc)


# ------------------------------------------------------------------------------------ Gordon steps
def test_check_network_lowers_the_cross_degrees_to_the_curve_counts():
    F = random_surface(np.random.default_rng(26))
    A, B = network(F, np.array([0, 1.0]), np.array([0, 0.5, 1.0]))
    assert gs._check_network(A, B, (3, 3))[2:] == (1, 2)
    assert gs._check_network(A, B, [1, 1])[2:] == (1, 1)
    with pytest.raises(InvalidGeometryError, match=r"^u_curves, v_curves: all curves must have one dimension"):
        gs._check_network(A, [BSplineCurve(1, [0, 0, 1, 1], [[0, 0], [1, 1]])] * 2, (3, 3))


def test_crossing_points_are_the_means_and_refuse_a_gap_above_tol():
    F = random_surface(np.random.default_rng(20))
    us, vs = np.array([0, 0.4, 1.0]), np.array([0, 0.5, 1.0])
    A, B = network(F, us, vs)
    A[1] = A[1].transform(np.eye(3), [0, 0, 4e-8])
    Q = gs._crossing_points(A, B, us, vs, 1e-7)
    exact = F.evaluate_grid(us, vs).transpose(1, 0, 2)  # (m, n, 3): Q[i, j] at (us[j], vs[i])
    exact[1, :, 2] += 2e-8  # half the gap
    assert_allclose(Q, exact, rtol=0, atol=1e-14 * scale_of(F))
    with pytest.raises(InvalidGeometryError, match=r"^u_curves\[1\], v_curves\[\d\]: the network is not consistent"):
        gs._crossing_points(A, B, us, vs, 1e-8)


def test_gordon_terms_each_interpolate_their_curves():
    F = random_surface(np.random.default_rng(20))
    us, vs = np.array([0, 0.15, 0.4, 0.6, 0.85, 1.0]), np.array([0, 0.2, 0.45, 0.7, 1.0])
    A, B = network(F, us, vs)
    A, B = make_compatible(A), make_compatible(B)
    Q = gs._crossing_points(A, B, us, vs, 1e-7)
    Ku, Kv = gs._cross_knots(us, 3, (0.0, 1.0)), gs._cross_knots(vs, 3, (0.0, 1.0))
    P1, P2, P12 = (BSplineSurface(*net) for net in gs._gordon_terms(A, B, (us, vs), Q, (3, 3), (Ku, Kv), False))
    sc = scale_of(F)
    for a, v in zip(A, vs):
        assert_allclose(P1.evaluate(S, v), a(S), rtol=0, atol=1e-12 * sc)
    for b, u in zip(B, us):
        assert_allclose(P2.evaluate(u, S), b(S), rtol=0, atol=1e-12 * sc)
    assert_allclose(P12.evaluate_grid(us, vs), Q.transpose(1, 0, 2), rtol=0, atol=1e-12 * sc)


def test_polynomial_network_widens_the_tolerance_by_the_approximation_errors():
    F = random_surface(np.random.default_rng(25), p=2, q=2, nu=4, nv=4, rational=True)
    A, B = network(F, np.array([0, 0.25, 0.5, 0.8, 1]), np.array([0, 0.3, 0.6, 1]))
    A2, B2, tol = gs._polynomial_network(make_compatible(A), make_compatible(B), 1e-7, 1e-8)
    assert not any(c.is_rational for c in A2 + B2)
    for fam, fam0 in ((A2, A), (B2, B)):
        assert all(np.array_equal(c.knots, fam[0].knots) for c in fam)  # compatible again
        for c, c0 in zip(fam, fam0):
            assert np.linalg.norm(c(S) - c0(S), axis=-1).max() <= 1.1e-8
    assert 1e-7 < tol <= 1e-7 + 2e-8


def test_gordon_net_is_none_for_a_rational_network_not_meeting_in_homogeneous_space():
    F = random_surface(np.random.default_rng(25), p=2, q=2, nu=4, nv=4, rational=True)
    us, vs = np.array([0, 0.25, 0.5, 0.8, 1]), np.array([0, 0.3, 0.6, 1])
    A, B = network(F, us, vs)
    A, B = make_compatible(A), make_compatible(B)
    deg, kn, H = gs._gordon_net(A, B, (us, vs), (3, 3), (None, None), 1e-7, True)
    assert H.shape[-1] == 4 and np.all(H[..., -1] > 0)
    A[1] = BSplineCurve(A[1].degree, A[1].knots, A[1].control_points, A[1].weights * 3)  # the same curve
    assert gs._gordon_net(A, B, (us, vs), (3, 3), (None, None), 1e-7, True) is None
