"""BSplineSurface: NdBSpline oracles, the sphere as a closed form, and invariants (u/v, swap_uv).

Tolerances are relative to a scale of the compared quantity (see test_curve's module docstring):
``pole_scale(s) = max |P|`` for points, ``deriv_scale(s, k, l)`` for the partial ``d^{k+l}/du^k dv^l``.
"""

from __future__ import annotations

import inspect
import json
import math

import numpy as np
import pytest
from hypothesis import assume, given
from hypothesis import strategies as st
from numpy.testing import assert_allclose, assert_array_equal
from scipy.interpolate import NdBSpline
from scipy.special import comb

from occsurf.algorithms import BSplineCurve, BSplineSurface

from .strategies import affine_maps, fractions, surfaces, test_settings

# Exact identities in double precision: the same budget as test_curve (deep runs see a few
# 1e-15 of the scale; tensor products of two recurrences), any real error is O(1).
EXACT = 1e-12
ORACLE = 1e-12

SETTINGS = test_settings(25)
SMALL = dict(degrees=st.integers(1, 5))  # for the heavier operations (keeps the suite quick)


# ---------------------------------------------------------------------------------------- helpers
def pole_scale(s: BSplineSurface) -> float:
    return max(float(np.max(np.abs(s.control_points))), np.finfo(float).tiny)


def deriv_scale(s: BSplineSurface, k: int, l: int) -> float:
    """A-priori size of ``d^{k+l} S / du^k dv^l``: ``max|P| k! l! (p rho / h_u)^k (q rho / h_v)^l``
    (``h`` the shortest non-empty span in each direction, ``rho`` the weight ratio or 1)."""
    (p, q), (U, V) = s.degree, s.knots
    hu, hv = (float(np.min(np.diff(np.unique(t)))) for t in (U, V))
    rho = 1.0 if s.weights is None else float(s.weights.max() / s.weights.min())
    return pole_scale(s) * math.factorial(k) * math.factorial(l) * (p * rho / hu) ** k * (q * rho / hv) ** l


def _last_span(t: np.ndarray, n: int) -> int:
    return int(np.searchsorted(t, t[n], side="left")) - 1


def scipy_surface(U, V, coef, p, q, u, v, nu=(0, 0)) -> np.ndarray:
    """NdBSpline partial ``nu`` at points ``(u, v)``, with the domain ends taken as left limits.

    As for curves (test_curve.scipy_bspline), scipy's interval search picks the empty last span
    when the end knot is repeated inside the vector; at ``u == U[n_u]`` (resp. v) a one-span
    NdBSpline on the last non-empty span is used instead, still scipy's own arithmetic.
    """
    if nu[0] > p or nu[1] > q:
        return np.zeros(u.shape + coef.shape[2:])
    nu_, nv_ = coef.shape[:2]
    out = np.empty(u.shape + coef.shape[2:])
    ue, ve = u == U[nu_], v == V[nv_]
    su, sv = _last_span(U, nu_), _last_span(V, nv_)
    for a in (False, True):
        for b in (False, True):
            m = (ue == a) & (ve == b)
            if not np.any(m):
                continue
            tu, cu = (U[su - p : su + p + 2], slice(su - p, su + 1)) if a else (U, slice(None))
            tv, cv = (V[sv - q : sv + q + 2], slice(sv - q, sv + 1)) if b else (V, slice(None))
            spl = NdBSpline((tu, tv), coef[cu, cv], (p, q))
            out[m] = spl(np.column_stack((u[m], v[m])), nu=nu)
    return out


def oracle_partials(s: BSplineSurface, u: np.ndarray, v: np.ndarray, r: int) -> np.ndarray:
    """All partials ``(m, r+1, r+1, d)``; rational ones from the homogeneous NdBSpline by the
    two-variable Leibniz rule on ``A = w S``, written out here again:
    ``S^(k,l) = (A^(k,l) - sum_{(i,j) != (0,0)} C(k,i) C(l,j) w^(i,j) S^(k-i,l-j)) / w``."""
    (p, q), (U, V) = s.degree, s.knots
    if s.weights is None:
        return np.stack([np.stack([scipy_surface(U, V, s.control_points, p, q, u, v, (k, l))
                                   for l in range(r + 1)], axis=1) for k in range(r + 1)], axis=1)
    H = np.concatenate((s.control_points * s.weights[..., None], s.weights[..., None]), axis=-1)
    A = {(k, l): scipy_surface(U, V, H, p, q, u, v, (k, l)) for k in range(r + 1) for l in range(r + 1)}
    S: dict[tuple[int, int], np.ndarray] = {}
    for k in range(r + 1):
        for l in range(r + 1):
            acc = A[k, l][:, :-1].copy()
            for i in range(k + 1):
                for j in range(l + 1):
                    if i or j:
                        acc -= comb(k, i, exact=True) * comb(l, j, exact=True) * A[i, j][:, -1:] * S[k - i, l - j]
            S[k, l] = acc / A[0, 0][:, -1:]
    return np.stack([np.stack([S[k, l] for l in range(r + 1)], axis=1) for k in range(r + 1)], axis=1)


@st.composite
def surface_points(draw, s: BSplineSurface, max_size: int = 8):
    """Parameter pairs in the domain; some u, v exactly on knots."""
    (u0, u1), (v0, v1) = s.domain
    m = draw(st.integers(1, max_size))
    fu = np.array(draw(st.lists(fractions, min_size=m, max_size=m)))
    fv = np.array(draw(st.lists(fractions, min_size=m, max_size=m)))
    u = np.clip(u0 + fu * (u1 - u0), u0, u1)
    v = np.clip(v0 + fv * (v1 - v0), v0, v1)
    U, V = s.knots
    ku = np.unique(U[(U >= u0) & (U <= u1)])
    kv = np.unique(V[(V >= v0) & (V <= v1)])
    extra = draw(st.lists(st.tuples(st.sampled_from(list(ku)), st.sampled_from(list(kv))), max_size=2))
    if extra:
        u = np.concatenate((u, [e[0] for e in extra]))
        v = np.concatenate((v, [e[1] for e in extra]))
    return u, v


def grid(s: BSplineSurface, m: int = 9) -> tuple[np.ndarray, np.ndarray]:
    """A grid over the domain plus every knot in it, as flattened (u, v) arrays."""
    (u0, u1), (v0, v1) = s.domain
    U, V = s.knots
    us = np.unique(np.concatenate((np.linspace(u0, u1, m), U[(U >= u0) & (U <= u1)])))
    vs = np.unique(np.concatenate((np.linspace(v0, v1, m), V[(V >= v0) & (V <= v1)])))
    uu, vv = np.meshgrid(us, vs, indexing="ij")
    return uu.ravel(), vv.ravel()


def interior(lo: float, hi: float, f: float) -> float:
    return lo + (0.02 + 0.96 * f) * (hi - lo)


def assert_same_geometry(s1, s2, scale, points=None):
    u, v = grid(s1) if points is None else points
    assert_allclose(s2.evaluate(u, v), s1.evaluate(u, v), rtol=0, atol=EXACT * scale)


def assert_same_surface_data(a: BSplineSurface, b: BSplineSurface, scale: float) -> None:
    assert a.degree == b.degree
    for ka, kb in zip(a.knots, b.knots):
        assert_array_equal(ka, kb)
    assert_allclose(a.control_points, b.control_points, rtol=0, atol=EXACT * scale)
    assert (a.weights is None) == (b.weights is None)
    if a.weights is not None:
        assert_allclose(a.weights, b.weights, rtol=EXACT, atol=0)


# ------------------------------------------------------------------------------------- oracles
@pytest.mark.parametrize("rational", [False, True], ids=["polynomial", "rational"])
@SETTINGS
@given(data=st.data())
def test_values_and_partials_match_ndbspline(rational, data):
    """Against scipy's NdBSpline (rational: on the homogeneous net, then the quotient rule), all
    partials up to the largest degree (rational: one more, they do not vanish above it)."""
    s = data.draw(surfaces(rational=rational, degrees=st.integers(1, 4 if rational else 6)))
    u, v = data.draw(surface_points(s))
    r = max(s.degree) + (1 if rational else 0)
    D = s.derivatives(u, v, r)
    assert D.shape == (u.size, r + 1, r + 1, s.dim)
    ref = oracle_partials(s, u, v, r)
    assert_allclose(s.evaluate(u, v), ref[:, 0, 0], rtol=0, atol=ORACLE * pole_scale(s))
    for k in range(r + 1):
        for l in range(r + 1):
            assert_allclose(D[:, k, l], ref[:, k, l], rtol=0, atol=ORACLE * deriv_scale(s, k, l),
                            err_msg=f"partial ({k}, {l})")


@SETTINGS
@given(data=st.data())
def test_grid_evaluation_matches_scattered(data):
    s = data.draw(surfaces(degrees=st.integers(1, 6)))
    (u0, u1), (v0, v1) = s.domain
    us = np.clip(u0 + np.array(data.draw(st.lists(fractions, min_size=1, max_size=6))) * (u1 - u0), u0, u1)
    vs = np.clip(v0 + np.array(data.draw(st.lists(fractions, min_size=1, max_size=6))) * (v1 - v0), v0, v1)
    uu, vv = np.meshgrid(us, vs, indexing="ij")
    G = s.evaluate_grid(us, vs)
    assert G.shape == (us.size, vs.size, s.dim)
    assert_allclose(G, s.evaluate(uu, vv), rtol=0, atol=EXACT * pole_scale(s))
    DG, D = s.derivatives_grid(us, vs, 2), s.derivatives(uu, vv, 2)
    assert DG.shape == D.shape == (us.size, vs.size, 3, 3, s.dim)
    for k in range(3):
        for l in range(3):
            assert_allclose(DG[:, :, k, l], D[:, :, k, l], rtol=0, atol=EXACT * deriv_scale(s, k, l))


# ---------------------------------------------------------------------------------- closed forms
SQRT1_2 = math.sqrt(0.5)


def sphere_octant(radius: float = 1.0) -> BSplineSurface:
    """Biquadratic rational octant: meridian quarter circle (r, z) times parallel quarter circle.

    ``S(u, v) = (r(u) x(v), r(u) y(v), z(u))`` exactly, because the rational tensor product of
    two rational curves factors (weights ``w_i w_j``), so ``|S| = radius`` identically.
    """
    meridian = np.array([[1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])  # (r, z)
    parallel = np.array([[1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])  # (x, y)
    w = np.array([1.0, SQRT1_2, 1.0])
    P = np.empty((3, 3, 3))
    P[..., 0] = meridian[:, None, 0] * parallel[None, :, 0]
    P[..., 1] = meridian[:, None, 0] * parallel[None, :, 1]
    P[..., 2] = meridian[:, None, 1]
    t = [0, 0, 0, 1, 1, 1]
    return BSplineSurface((2, 2), (t, t), radius * P, np.outer(w, w))


def test_sphere_octant_is_exact():
    s = sphere_octant()
    us = np.linspace(0, 1, 101)
    X = s.evaluate_grid(us, us)
    assert np.max(np.abs(np.linalg.norm(X, axis=-1) - 1.0)) <= 1e-14
    uu, vv = np.meshgrid(us, us, indexing="ij")
    assert np.max(np.abs(np.linalg.norm(s.evaluate(uu, vv), axis=-1) - 1.0)) <= 1e-14
    # Corners: equator at (1,0,0) and (0,1,0), pole at (0,0,1) for every v.
    assert_allclose(s.evaluate([0, 0, 1, 1], [0, 1, 0, 1]), [[1, 0, 0], [0, 1, 0], [0, 0, 1], [0, 0, 1]],
                    rtol=0, atol=1e-15)
    # Every point is in the first octant and the octant is covered: the midpoint of the patch.
    assert np.all(X >= -1e-15)
    assert_allclose(s.evaluate(0.5, 0.5), [0.5, 0.5, SQRT1_2], rtol=0, atol=1e-15)


def test_sphere_octant_normals_are_radial_and_tangents_orthogonal():
    s = sphere_octant(3.0)
    us = np.linspace(0, 0.9, 31)  # away from the pole u = 1, where S_v vanishes
    uu, vv = np.meshgrid(us, np.linspace(0, 1, 31), indexing="ij")
    X = s.evaluate(uu, vv)
    n = s.normal(uu, vv)
    assert_allclose(np.abs(np.einsum("...d,...d->...", n, X / 3.0)), 1.0, rtol=0, atol=1e-14)
    D = s.derivatives(uu, vv, 1)
    # |S|^2 = R^2: both first partials are orthogonal to the position.
    assert_allclose(np.einsum("...d,...d->...", D[..., 0, 0, :], D[..., 1, 0, :]), 0.0, rtol=0, atol=1e-13 * 9)
    assert_allclose(np.einsum("...d,...d->...", D[..., 0, 0, :], D[..., 0, 1, :]), 0.0, rtol=0, atol=1e-13 * 9)


def test_sphere_normal_at_the_pole_is_nan():
    # At u = 1 every pole of the row coincides: S_v = 0, the normal is undefined (documented NaN).
    n = sphere_octant().normal(1.0, 0.5)
    assert np.all(np.isnan(n))


# ---------------------------------------------------------------------- geometry-preserving ops
def _insertion_site(s, f: float, times: int, direction: str) -> tuple[int, float]:
    """Axis and interior knot (fraction ``f`` of the domain) of an insertion ``times`` times that keeps
    the multiplicity <= the degree; other draws are rejected (``assume``)."""
    ax = "uv".index(direction)
    x = interior(*s.domain[ax], f)
    assume(int(np.count_nonzero(s.knots[ax] == x)) + times <= s.degree[ax])
    return ax, x


@SETTINGS
@given(s=surfaces(**SMALL), f=fractions, times=st.integers(1, 2), direction=st.sampled_from("uv"))
def test_insert_knot_keeps_geometry(s, f, times, direction):
    ax, x = _insertion_site(s, f, times, direction)
    s2 = s.insert_knot(x, times, direction=direction)
    assert s2.n_poles[ax] == s.n_poles[ax] + times and s2.n_poles[1 - ax] == s.n_poles[1 - ax]
    assert_array_equal(s2.knots[1 - ax], s.knots[1 - ax])
    assert_same_geometry(s, s2, pole_scale(s))


@SETTINGS
@given(s=surfaces(**SMALL), fs=st.lists(fractions, min_size=1, max_size=5), direction=st.sampled_from("uv"))
def test_refine_keeps_geometry(s, fs, direction):
    ax = "uv".index(direction)
    x = np.array([interior(*s.domain[ax], f) for f in fs])
    t = np.sort(np.concatenate((s.knots[ax], x)))
    assume(np.max(np.unique(t, return_counts=True)[1]) <= s.degree[ax] + 1)
    s2 = s.refine(x, direction=direction)
    assert_array_equal(s2.knots[ax], t)
    assert_same_geometry(s, s2, pole_scale(s))


@SETTINGS
@given(s=surfaces(**SMALL), times=st.integers(1, 2), direction=st.sampled_from("uv"))
def test_elevate_degree_keeps_geometry(s, times, direction):
    ax = "uv".index(direction)
    s2 = s.elevate_degree(times, direction=direction)
    assert s2.degree[ax] == s.degree[ax] + times and s2.degree[1 - ax] == s.degree[1 - ax]
    assert s2.domain == s.domain
    assert_same_geometry(s, s2, pole_scale(s))


@SETTINGS
@given(s=surfaces(**SMALL))
def test_clamp_keeps_geometry(s):
    s2 = s.clamp()
    assert s2.domain == s.domain
    for t, (lo, hi), p in zip(s2.knots, s2.domain, s2.degree):
        assert np.all(t[: p + 1] == lo) and np.all(t[-p - 1 :] == hi)
    assert_same_geometry(s, s2, pole_scale(s))
    # clamped already: the surface itself (no rebuild through P = H / w and back), and clamping
    # one direction leaves the other's knots and the homogeneous poles of a clamped one alone
    assert s2.clamp() is s2
    if all(t[0] == t[p] and t[-1] == t[-p - 1] for t, p in zip(s.knots, s.degree)):
        assert s2 is s


def test_clamp_of_a_clamped_rational_surface_is_the_surface_and_one_direction_is_left_alone():
    """``clamp`` of a clamped surface returns it (it rebuilt it twice before 2026-12-07, through
    ``P = H / w`` and back, for the same surface); a surface clamped in v but not u is clamped in
    u only, its v knots the same array values."""
    rng = np.random.default_rng(7)
    P, w = rng.standard_normal((4, 5, 3)), rng.uniform(0.3, 3.0, (4, 5))
    s = BSplineSurface((3, 2), ([0.0] * 4 + [1.0] * 4, [0.0] * 3 + [0.5, 0.5] + [1.0] * 3), P, w)
    assert s.clamp() is s
    un = BSplineSurface((3, 2), (np.linspace(0.0, 1.0, 8), [0.0] * 3 + [0.5, 0.5] + [1.0] * 3), P, w)  # u unclamped
    c = un.clamp()
    assert np.array_equal(c.knots[1], un.knots[1]) and c.knots[0][0] == c.knots[0][3]


@SETTINGS
@given(s=surfaces(**SMALL), f=fractions, direction=st.sampled_from("uv"))
def test_split_pieces_reproduce_the_surface(s, f, direction):
    ax = "uv".index(direction)
    lo, hi = s.domain[ax]
    a, b = s.split(interior(lo, hi, f), direction=direction)
    x = a.domain[ax][1]
    assert b.domain[ax] == (x, hi) and a.domain[ax][0] == lo
    assert x == pytest.approx(interior(lo, hi, f), rel=0, abs=1e-12 * max(hi - lo, 1.0))
    for piece in (a, b):
        u, v = grid(piece)
        assert_allclose(piece.evaluate(u, v), s.evaluate(u, v), rtol=0, atol=EXACT * pole_scale(s))


@SETTINGS
@given(s=surfaces(**SMALL))
def test_to_bezier_patches_reproduce_the_surface(s):
    patches = s.to_bezier()
    (u0, u1), (v0, v1) = s.domain
    U, V = s.knots
    bu = np.unique(U[(U >= u0) & (U <= u1)])
    bv = np.unique(V[(V >= v0) & (V <= v1)])
    assert len(patches) == bu.size - 1 and all(len(row) == bv.size - 1 for row in patches)
    for i, row in enumerate(patches):
        for j, patch in enumerate(row):
            assert patch.n_poles == (s.degree[0] + 1, s.degree[1] + 1)
            assert patch.domain == ((bu[i], bu[i + 1]), (bv[j], bv[j + 1]))
            # Half-open cells [a, b) x [c, d): each knot line belongs to the next patch.
            uu, vv = np.meshgrid(np.linspace(bu[i], bu[i + 1], 5)[:-1], np.linspace(bv[j], bv[j + 1], 5)[:-1],
                                 indexing="ij")
            assert_allclose(patch.evaluate(uu, vv), s.evaluate(uu, vv), rtol=0, atol=EXACT * pole_scale(s))


@SETTINGS
@given(s=surfaces(**SMALL), f=fractions, times=st.integers(1, 2), direction=st.sampled_from("uv"))
def test_insert_then_remove_returns_the_original(s, f, times, direction):
    ax, x = _insertion_site(s, f, times, direction)
    back = s.insert_knot(x, times, direction=direction).remove_knot(x, times, direction=direction)
    assert_same_surface_data(back, s, pole_scale(s))


# --------------------------------------------------------------------------------------- blossom
@SETTINGS
@given(data=st.data())
def test_blossom_symmetric_diagonal_and_poles(data):
    s = data.draw(surfaces(**SMALL))
    (p, q), (U, V), (nu, nv) = s.degree, s.knots, s.n_poles
    su = data.draw(st.sampled_from([m for m in range(p, nu) if U[m] < U[m + 1]]))
    sv = data.draw(st.sampled_from([m for m in range(q, nv) if V[m] < V[m + 1]]))
    # Arguments inside the chosen patch: every blossom weight is in [0, 1].
    au = U[su] + np.array(data.draw(st.lists(fractions, min_size=p, max_size=p))) * (U[su + 1] - U[su])
    av = V[sv] + np.array(data.draw(st.lists(fractions, min_size=q, max_size=q))) * (V[sv + 1] - V[sv])
    span = (0.5 * (U[su] + U[su + 1]), 0.5 * (V[sv] + V[sv + 1]))
    f = s.blossom(au, av, span=span)
    pu, pv = data.draw(st.permutations(range(p))), data.draw(st.permutations(range(q)))
    scale = pole_scale(s)
    assert_allclose(s.blossom(au[list(pu)], av[list(pv)], span=span), f, rtol=0, atol=EXACT * scale)
    # Diagonal: the surface itself.
    uv = data.draw(surface_points(s))
    d = s.blossom(np.repeat(uv[0][:, None], p, 1), np.repeat(uv[1][:, None], q, 1))
    assert_allclose(d, s.evaluate(*uv), rtol=0, atol=EXACT * scale)
    # P_ij = f(U_{i+1..i+p}; V_{j+1..j+q}) on the chosen patch, for the poles it holds. Knots far
    # from the patch extrapolate; the weights then grow like (distance / span)^degree.
    hu, hv = U[su + 1] - U[su], V[sv + 1] - V[sv]
    for i in range(su - p, su + 1):
        for j in range(sv - q, sv + 1):
            ku, kv = U[i + 1 : i + p + 1], V[j + 1 : j + q + 1]
            growth = np.prod(1 + 2 * np.abs(ku - span[0]) / hu) * np.prod(1 + 2 * np.abs(kv - span[1]) / hv)
            rho = 1.0 if s.weights is None else float(s.weights.max() / s.weights.min())
            assert_allclose(s.blossom(ku, kv, span=span), s.control_points[i, j], rtol=0,
                            atol=EXACT * scale * growth * rho, err_msg=f"pole ({i}, {j})")


# ---------------------------------------------------------------- affine invariance, convex hull
@SETTINGS
@given(data=st.data())
def test_affine_invariance(data):
    s = data.draw(surfaces(**SMALL))
    M, b = data.draw(affine_maps(s.dim))
    u, v = data.draw(surface_points(s))
    s2 = s.transform(M, b)
    norm_m = np.abs(M).sum(axis=1).max()
    assert_allclose(s2.evaluate(u, v), s.evaluate(u, v) @ M.T + b, rtol=0,
                    atol=EXACT * (pole_scale(s) * norm_m + np.abs(b).max()))
    D2, D = s2.derivatives(u, v, 1), s.derivatives(u, v, 1)
    for k, l in ((1, 0), (0, 1), (1, 1)):
        assert_allclose(D2[:, k, l], D[:, k, l] @ M.T, rtol=0,
                        atol=EXACT * (deriv_scale(s2, k, l) + norm_m * deriv_scale(s, k, l)))


@SETTINGS
@given(data=st.data())
def test_points_lie_in_the_bounding_box_of_the_active_poles(data):
    s = data.draw(surfaces())
    u, v = data.draw(surface_points(s, max_size=12))
    X = s.evaluate(u, v)
    (p, q), (U, V), (nu, nv) = s.degree, s.knots, s.n_poles
    (_, u1), (_, v1) = s.domain
    slack = EXACT * pole_scale(s)
    for ui, vi, x in zip(u, v, X):
        su = _last_span(U, nu) if ui >= u1 else int(np.searchsorted(U, ui, side="right")) - 1
        sv = _last_span(V, nv) if vi >= v1 else int(np.searchsorted(V, vi, side="right")) - 1
        active = s.control_points[su - p : su + 1, sv - q : sv + 1].reshape(-1, s.dim)
        assert np.all(x >= active.min(axis=0) - slack) and np.all(x <= active.max(axis=0) + slack)


# ----------------------------------------------------------- reverse, reparametrize, swap_uv
@SETTINGS
@given(data=st.data(), direction=st.sampled_from("uv"))
def test_reverse(data, direction):
    s = data.draw(surfaces(**SMALL))
    ax = "uv".index(direction)
    r = s.reverse(direction=direction)
    u, v = data.draw(surface_points(s))
    (u0, u1), (v0, v1) = s.domain
    ur, vr = (np.clip(u0 + u1 - u, *r.domain[0]), v) if ax == 0 else (u, np.clip(v0 + v1 - v, *r.domain[1]))
    assert_allclose(r.evaluate(ur, vr), s.evaluate(u, v), rtol=0, atol=EXACT * pole_scale(s))
    rr = r.reverse(direction=direction)
    assert rr.degree == s.degree
    assert_array_equal(rr.knots[1 - ax], s.knots[1 - ax])
    # (a+b) - ((a+b) - t) is t up to one rounding of the sum; poles and weights are copied.
    lo, hi = s.domain[ax]
    assert_allclose(rr.knots[ax], s.knots[ax], rtol=0, atol=4 * np.spacing(np.abs(s.knots[ax]).max() + abs(lo + hi)))
    assert_array_equal(rr.control_points, s.control_points)
    assert (rr.weights is None) == (s.weights is None)
    if s.weights is not None:
        assert_array_equal(rr.weights, s.weights)


@SETTINGS
@given(data=st.data(), a=st.floats(-50, 50), la=st.floats(0.1, 100), b=st.floats(-50, 50), lb=st.floats(0.1, 100))
def test_reparametrize_maps_partials_by_the_chain_rule(data, a, la, b, lb):
    s = data.draw(surfaces(**SMALL))
    r = s.reparametrize((a, a + la), (b, b + lb))
    assert r.domain == ((a, a + la), (b, b + lb))
    assert all(np.all(np.diff(t) >= 0) for t in r.knots)
    (u0, u1), (v0, v1) = s.domain
    fu = np.array(data.draw(st.lists(fractions, min_size=1, max_size=6)))
    fv = np.array(data.draw(st.lists(fractions, min_size=fu.size, max_size=fu.size)))
    u, v = np.clip(u0 + fu * (u1 - u0), u0, u1), np.clip(v0 + fv * (v1 - v0), v0, v1)
    x, y = np.clip(a + fu * la, a, a + la), np.clip(b + fv * lb, b, b + lb)
    cu, cv = (u1 - u0) / la, (v1 - v0) / lb
    D, Dr = s.derivatives(u, v, 2), r.derivatives(x, y, 2)
    # Mapping the parameters rounds them by ~eps * du: budget one more derivative order of that.
    du = abs(u0) + abs(u1) + (abs(a) + abs(a + la)) * cu
    dv = abs(v0) + abs(v1) + (abs(b) + abs(b + lb)) * cv
    for k in range(3):
        for l in range(3):
            atol = EXACT * cu**k * cv**l * (deriv_scale(s, k, l) + deriv_scale(s, k + 1, l) * du
                                             + deriv_scale(s, k, l + 1) * dv)
            assert_allclose(Dr[:, k, l], cu**k * cv**l * D[:, k, l], rtol=0, atol=atol, err_msg=f"({k}, {l})")


def test_reparametrize_keeps_the_knot_vectors_non_decreasing():
    t = [2, 3, 4, 4, 5, 6, 7, 8, 15, 15, 15, 15]
    s = BSplineSurface((3, 1), (t, [0, 0, 1, 1]), np.arange(48.0).reshape(8, 2, 3))
    r = s.reparametrize((0.0, 54.5), (0.0, 1.0))
    assert np.all(np.diff(r.knots[0]) >= 0), r.knots[0].tolist()
    assert_allclose(r.evaluate(54.5, 0.5), s.evaluate(15.0, 0.5), rtol=0, atol=EXACT * 48)


OPERATIONS = {
    "insert_knot": lambda s, d, x: s.insert_knot(x, direction=d),
    "refine": lambda s, d, x: s.refine([x, x], direction=d),
    "elevate_degree": lambda s, d, x: s.elevate_degree(direction=d),
    "split_left": lambda s, d, x: s.split(x, direction=d)[0],
    "split_right": lambda s, d, x: s.split(x, direction=d)[1],
    "reverse": lambda s, d, x: s.reverse(direction=d),
    "insert_remove": lambda s, d, x: s.insert_knot(x, direction=d).remove_knot(x, direction=d),
}


@SETTINGS
@given(data=st.data(), name=st.sampled_from(sorted(OPERATIONS)))
def test_operations_along_v_equal_swap_uv_then_along_u(data, name):
    s = data.draw(surfaces(**SMALL, max_multiplicity=1))
    op = OPERATIONS[name]
    x = interior(*s.domain[1], data.draw(fractions))
    along_v = op(s, "v", x)
    via_u = op(s.swap_uv(), "u", x).swap_uv()
    assert_same_surface_data(along_v, via_u, pole_scale(s))
    # And the swap itself: S'(v, u) = S(u, v).
    u, v = data.draw(surface_points(s))
    assert_allclose(s.swap_uv().evaluate(v, u), s.evaluate(u, v), rtol=0, atol=EXACT * pole_scale(s))


# ----------------------------------------------------------------- one directional convention
#: The methods that work along one direction (the rule is in the BSplineSurface docstring).
DIRECTIONAL = ("elevate_degree", "insert_knot", "refine", "remove_knot", "reverse", "split")


def test_directional_methods_follow_the_curve_signatures():
    """Each directional method takes the curve method's parameters (names, kinds, defaults,
    annotations, in order), then ``direction``: keyword-only, no default. No other public
    method takes a direction."""
    public = [n for n, _ in inspect.getmembers(BSplineSurface, inspect.isfunction) if not n.startswith("_")]
    takes_direction = [n for n in public if "direction" in inspect.signature(getattr(BSplineSurface, n)).parameters]
    assert sorted(takes_direction) == list(DIRECTIONAL)
    for name in DIRECTIONAL:
        curve = list(inspect.signature(getattr(BSplineCurve, name)).parameters.values())
        *leading, direction = inspect.signature(getattr(BSplineSurface, name)).parameters.values()
        assert [(p.name, p.kind, p.default, p.annotation) for p in leading] == \
            [(p.name, p.kind, p.default, p.annotation) for p in curve], name
        assert direction.name == "direction", name
        assert direction.kind is inspect.Parameter.KEYWORD_ONLY, name
        assert direction.default is inspect.Parameter.empty, name


def test_direction_must_be_given_by_keyword():
    s = BSplineSurface((2, 2), ([0, 0, 0, 1, 1, 1], [0, 0, 0, 1, 1, 1]), np.zeros((3, 3, 3)))
    with pytest.raises(TypeError, match="direction"):
        s.insert_knot(0.5)
    with pytest.raises(TypeError):
        s.insert_knot(0.5, 1, "v")
    with pytest.raises(TypeError):
        s.elevate_degree("u")
    assert s.insert_knot(0.5, direction="v").n_poles == (3, 4)
    assert s.elevate_degree(direction="u").degree == (3, 2)


# ------------------------------------------------------------------------------- serialisation
@SETTINGS
@given(s=surfaces())
def test_to_dict_json_round_trip_is_exact(s):
    text = json.dumps(s.to_dict())
    back = BSplineSurface.from_dict(json.loads(text))
    assert back == s
    assert back.degree == s.degree and all(type(d) is int for d in back.degree)
    for a, b in zip(back.knots, s.knots):
        assert_array_equal(a, b)
    assert_array_equal(back.control_points, s.control_points)
    assert json.loads(json.dumps(back.to_dict())) == json.loads(text)


@SETTINGS
@given(data=st.data(), m=st.integers(1, 12), order=st.integers(0, 3), d=st.integers(2, 3), k=st.integers(0, 11))
def test_the_quotient_rule_of_a_point_does_not_depend_on_the_other_points(data, m, order, d, k):
    """A rational surface's grid partials apply the quotient rule (A4.4) once over the whole grid,
    where they applied it per group of rows sharing a u-span: the rule works point by point, so a
    point's partials are the same bits whichever points share the call. (The grid's homogeneous
    partials themselves come from a matrix product per span group, whose summation order BLAS may
    choose by the group's size: that part is unchanged.)"""
    from occsurf.algorithms.kernel.rational import surface_quotient_rule

    r1 = order + 1
    vals = st.floats(-1e3, 1e3, allow_nan=False, allow_subnormal=False)
    H = np.array(data.draw(st.lists(vals, min_size=m * r1 * r1 * (d + 1), max_size=m * r1 * r1 * (d + 1))))
    H = H.reshape(m, r1, r1, d + 1)
    H[:, 0, 0, -1] = np.abs(H[:, 0, 0, -1]) + 0.1  # a positive weight at each point
    k %= m
    assert_array_equal(surface_quotient_rule(H)[k], surface_quotient_rule(H[k:k + 1])[0])
