"""S-patches (course §8-1, 8-2; Loop & DeRose 1989): Wachspress coordinates, evaluation, derivatives,
boundary curves, cross-boundary derivatives, the 3- and 4-sided identities, rational patches.

Oracles written here, independent of algorithms/topology/spatch.py: barycentric coordinates of a triangle by
a linear solve and a triangular de Casteljau; bilinear coordinates of the square; tensor-product
Bézier surfaces (BSplineSurface); a dict-polynomial multinomial expansion; sympy's exact
derivatives of the Wachspress coordinates; Richardson-extrapolated central differences.
"""

from __future__ import annotations

import json
from math import comb, factorial

import numpy as np
import pytest
from hypothesis import assume, given
from hypothesis import strategies as st
from numpy.testing import assert_allclose

from occsurf.algorithms.errors import InvalidGeometryError, ParameterError
from occsurf.algorithms.kernel.bezier import de_casteljau
from occsurf.algorithms.kernel.surface import BSplineSurface
from occsurf.algorithms.topology.spatch import (
    SPatch,
    domain_vertices,
    spatch_indices,
    wachspress,
    wachspress_derivatives,
    wachspress_gradient,
)
from tests.algorithms.strategies import test_settings

# Tolerances. The identities below are exact in real arithmetic; the computations are short sums
# of positive terms (Bernstein values, Wachspress products) of size O(1) with control points of
# size O(1..10), so round-off is a few ulps of the result: measured <= 3e-15 absolute. EXACT leaves
# a margin of ~30 for the depths and side counts drawn.
EXACT = 1e-13


# ------------------------------------------------------------------------- strategies / helpers
def random_patch(rng: np.random.Generator, n: int, d: int, dim: int = 3, rational: bool = False) -> SPatch:
    m = comb(n + d - 1, d)
    w = rng.uniform(0.3, 3.0, m) if rational else None
    return SPatch(n, d, rng.normal(size=(m, dim)), weights=w)


def interior_points(rng: np.random.Generator, n: int, count: int, shrink: float = 0.98) -> np.ndarray:
    """Random points of the regular n-gon: random convex combinations of a random triangle fan."""
    v = domain_vertices(n) * shrink
    k = rng.integers(0, n, count)
    a, b = rng.uniform(size=(2, count))
    flip = a + b > 1
    a[flip], b[flip] = 1 - a[flip], 1 - b[flip]
    return a[:, None] * v[k] + b[:, None] * v[(k + 1) % n]


@st.composite
def patches(draw, sides=st.integers(3, 8), depth=st.integers(1, 4), rational=st.booleans()):
    n, d = draw(sides), draw(depth)
    seed = draw(st.integers(0, 2**32 - 1))
    return random_patch(np.random.default_rng(seed), n, d, rational=draw(rational)), seed


def richardson(f, x: np.ndarray, e: np.ndarray, h: float = 1e-2, levels: int = 4) -> np.ndarray:
    """Directional derivative of f at x along e by Richardson-extrapolated central differences.

    Error O(h^(2 levels)) plus round-off ~ eps |f| / h; with h = 1e-2 and 4 levels the measured
    error on these smooth rational functions is ~1e-10."""
    T = []
    for i in range(levels):
        hi = h / 2**i
        T.append((f(x + hi * e) - f(x - hi * e)) / (2 * hi))
    for j in range(1, levels):
        T = [(4**j * T[i + 1] - T[i]) / (4**j - 1) for i in range(len(T) - 1)]
    return T[0]


# ------------------------------------------------------------------------- index set and domain
@pytest.mark.parametrize("n,d", [(3, 1), (3, 4), (5, 3), (8, 2), (6, 5)])
def test_indices_count_order_and_sums(n, d):
    idx = spatch_indices(n, d)
    assert idx.shape == (comb(n + d - 1, d), n)
    assert np.all(idx >= 0) and np.all(idx.sum(axis=1) == d)
    assert tuple(idx[0]) == (d,) + (0,) * (n - 1)
    assert tuple(idx[-1]) == (0,) * (n - 1) + (d,)
    rows = [tuple(r) for r in idx]
    assert rows == sorted(rows, reverse=True) and len(set(rows)) == len(rows)


def test_domain_vertices_regular():
    for n in range(3, 10):
        v = domain_vertices(n)
        assert_allclose(np.linalg.norm(v, axis=1), 1.0, rtol=0, atol=1e-15)
        assert_allclose(v[1], [np.cos(2 * np.pi / n), np.sin(2 * np.pi / n)], atol=1e-15)


# ------------------------------------------------------------------------- Wachspress
@given(n=st.integers(3, 10), seed=st.integers(0, 2**32 - 1))
@test_settings(30)
def test_wachspress_partition_positivity_linear_precision(n, seed):
    rng = np.random.default_rng(seed)
    x = interior_points(rng, n, 50)
    lam = wachspress(x, n)
    assert lam.shape == (50, n)
    assert np.all(lam >= 0)
    assert_allclose(lam.sum(axis=1), 1.0, rtol=0, atol=EXACT)
    # linear precision: sum_k lambda_k v_k = x (a defining property of Wachspress coordinates)
    assert_allclose(lam @ domain_vertices(n), x, rtol=0, atol=EXACT)


@pytest.mark.parametrize("n", [3, 4, 5, 7, 10])
def test_wachspress_vertices_and_edges(n):
    v = domain_vertices(n)
    assert_allclose(wachspress(v, n), np.eye(n), rtol=0, atol=EXACT)
    t = np.linspace(0, 1, 11)
    for k in range(n):
        x = (1 - t)[:, None] * v[k] + t[:, None] * v[(k + 1) % n]
        lam = wachspress(x, n)
        expected = np.zeros((11, n))
        expected[:, k] += 1 - t  # linear along side k, and zero for the other vertices
        expected[:, (k + 1) % n] += t
        assert_allclose(lam, expected, rtol=0, atol=EXACT)


def test_wachspress_triangle_is_barycentric():
    rng = np.random.default_rng(1)
    v = domain_vertices(3)
    x = interior_points(rng, 3, 40)
    A = np.vstack([v.T, np.ones(3)])  # independent: solve [v; 1] lambda = [x; 1]
    bary = np.linalg.solve(A, np.vstack([x.T, np.ones(40)])).T
    assert_allclose(wachspress(x, 3), bary, rtol=0, atol=EXACT)


def _square_uv(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(u, v) of x on the 4-gon (1,0),(0,1),(-1,0),(0,-1): x = v0 + u (v1 - v0) + v (v3 - v0)."""
    M = np.array([[-1.0, -1.0], [1.0, -1.0]])  # columns v1 - v0 and v3 - v0
    uv = np.linalg.solve(M, (x - [1.0, 0.0]).T).T
    return uv[:, 0], uv[:, 1]


def test_wachspress_square_is_bilinear():
    rng = np.random.default_rng(2)
    x = interior_points(rng, 4, 40)
    u, v = _square_uv(x)
    expected = np.column_stack([(1 - u) * (1 - v), u * (1 - v), u * v, (1 - u) * v])
    assert_allclose(wachspress(x, 4), expected, rtol=0, atol=EXACT)


@pytest.mark.slow
@pytest.mark.parametrize("n", [5, 6])
def test_wachspress_derivatives_vs_sympy(n):
    """Exact symbolic gradients and Hessians of the Wachspress coordinates (sympy) as the oracle."""
    sp = pytest.importorskip("sympy")
    X, Y = sp.symbols("x y")
    # Float coefficients (cos, sin of the side normals) instead of symbolic trigonometric constants:
    # the differentiation stays exact and symbolic, but sympy no longer carries nested radicals
    # through the quotient rule (14 s -> < 1 s); the coefficients are the doubles the code uses.
    h = sp.Float(float(np.cos(np.pi / n)), 17)
    L = [h - X * sp.Float(float(np.cos(2 * np.pi * (j + 0.5) / n)), 17)
         - Y * sp.Float(float(np.sin(2 * np.pi * (j + 0.5) / n)), 17) for j in range(n)]
    w = [sp.expand(sp.Mul(*[L[j] for j in range(n) if j not in ((k - 1) % n, k)])) for k in range(n)]
    W = sp.expand(sp.Add(*w))
    lam = [wk / W for wk in w]  # expanded polynomials over one expanded denominator: small trees
    pts = interior_points(np.random.default_rng(3), n, 4)
    ours = wachspress_derivatives(pts, n, order=2)
    for k in (0, 2):
        exprs = {(1, 0): sp.diff(lam[k], X), (0, 1): sp.diff(lam[k], Y), (2, 0): sp.diff(lam[k], X, 2),
                 (1, 1): sp.diff(lam[k], X, Y), (0, 2): sp.diff(lam[k], Y, 2)}
        for (i, j), e in exprs.items():
            f = sp.lambdify((X, Y), e, "numpy")
            assert_allclose(ours[:, k, i, j], f(pts[:, 0], pts[:, 1]), rtol=0, atol=1e-12)
    grad = wachspress_gradient(pts, n)
    assert_allclose(grad, ours[..., [1, 0], [0, 1]], rtol=0, atol=0)


@given(n=st.integers(3, 9), seed=st.integers(0, 2**32 - 1))
@test_settings(25)
def test_wachspress_derivative_identities(n, seed):
    """Differentiating sum(lambda) = 1 and sum(lambda v) = x: gradients sum to 0, sum grad v^T = I;
    all second derivatives of both sums vanish."""
    x = interior_points(np.random.default_rng(seed), n, 20)
    D = wachspress_derivatives(x, n, order=2)  # (20, n, 3, 3)
    v = domain_vertices(n)
    for i, j in [(1, 0), (0, 1), (2, 0), (1, 1), (0, 2)]:
        assert_allclose(D[:, :, i, j].sum(axis=1), 0.0, atol=1e-12)
    assert_allclose(np.einsum("pk,kc->pc", D[:, :, 1, 0], v), [[1.0, 0.0]] * 20, atol=1e-12)
    assert_allclose(np.einsum("pk,kc->pc", D[:, :, 0, 1], v), [[0.0, 1.0]] * 20, atol=1e-12)
    for i, j in [(2, 0), (1, 1), (0, 2)]:
        assert_allclose(np.einsum("pk,kc->pc", D[:, :, i, j], v), 0.0, atol=1e-11)


# ------------------------------------------------------------------------- n = 3: Bézier triangle
def triangle_de_casteljau(net: dict[tuple[int, int, int], np.ndarray], d: int, bary: np.ndarray) -> np.ndarray:
    """Bézier triangle of degree d by the triangular de Casteljau algorithm (Farin, CAGD ch. 17)."""
    level = {k: np.broadcast_to(p, (bary.shape[0],) + p.shape) for k, p in net.items()}
    for r in range(d, 0, -1):
        level = {(i, j, r - 1 - i - j): bary[:, 0:1] * level[(i + 1, j, r - 1 - i - j)]
                 + bary[:, 1:2] * level[(i, j + 1, r - 1 - i - j)] + bary[:, 2:3] * level[(i, j, r - i - j)]
                 for i in range(r) for j in range(r - i)}
    return level[(0, 0, 0)]


@pytest.mark.parametrize("d", [1, 2, 3, 5])
def test_three_sided_is_bezier_triangle(d):
    rng = np.random.default_rng(10 + d)
    net = {(i, j, d - i - j): rng.normal(size=3) for i in range(d + 1) for j in range(d + 1 - i)}
    patch = SPatch(3, d, net)
    x = interior_points(rng, 3, 60, shrink=1.0)
    v = domain_vertices(3)
    bary = np.linalg.solve(np.vstack([v.T, np.ones(3)]), np.vstack([x.T, np.ones(60)])).T
    assert_allclose(patch.evaluate(x), triangle_de_casteljau(net, d, bary), rtol=0, atol=EXACT)


# ------------------------------------------------------------------------- n = 4: tensor products
@pytest.mark.parametrize("d", [1, 2, 3, 4])
def test_four_sided_depth_d_is_tensor_product_bidegree_d(d):
    """λ = bilinear products, so B_I(λ) = (d!/I!) u^{i1+i2} (1-u)^{i0+i3} v^{i2+i3} (1-v)^{i0+i1}."""
    rng = np.random.default_rng(20 + d)
    patch = random_patch(rng, 4, d)
    Q = np.zeros((d + 1, d + 1, 3))
    for I, P in zip(patch.indices, patch.control_points):
        a, b = I[1] + I[2], I[2] + I[3]
        multinomial = factorial(d) / np.prod([factorial(int(i)) for i in I])
        Q[a, b] += multinomial / (comb(d, a) * comb(d, b)) * P
    kn = [0.0] * (d + 1) + [1.0] * (d + 1)
    tp = BSplineSurface((d, d), (kn, kn), Q)
    x = interior_points(rng, 4, 60, shrink=1.0)
    u, v = _square_uv(x)
    assert_allclose(patch.evaluate(x), tp.evaluate(np.clip(u, 0, 1), np.clip(v, 0, 1)), rtol=0, atol=EXACT)


def _poly_mul(a: dict, b: dict) -> dict:
    out: dict = {}
    for ka, ca in a.items():
        for kb, cb in b.items():
            k = tuple(x + y for x, y in zip(ka, kb))
            out[k] = out.get(k, 0.0) + ca * cb
    return out


def _poly_pow(a: dict, e: int) -> dict:
    out = {(0, 0, 0, 0): 1.0}
    for _ in range(e):
        out = _poly_mul(out, a)
    return out


@pytest.mark.parametrize("d", [1, 2, 3])
def test_tensor_product_bidegree_d_is_four_sided_depth_2d(d):
    """u = λ1 + λ2, 1 - u = λ0 + λ3, v = λ2 + λ3, 1 - v = λ0 + λ1 on the square: expand each
    tensor-product Bernstein product as a homogeneous polynomial of degree 2d in λ (multinomially,
    with dicts) and read off the S-patch control points."""
    rng = np.random.default_rng(30 + d)
    Q = rng.normal(size=(d + 1, d + 1, 3))
    e = np.eye(4, dtype=int)
    lin = {name: {tuple(e[i]): 1.0 for i in ids} for name, ids in
           {"u": (1, 2), "1-u": (0, 3), "v": (2, 3), "1-v": (0, 1)}.items()}
    ctrl = {tuple(int(i) for i in I): np.zeros(3) for I in spatch_indices(4, 2 * d)}
    for a in range(d + 1):
        for b in range(d + 1):
            poly = _poly_mul(_poly_mul(_poly_pow(lin["u"], a), _poly_pow(lin["1-u"], d - a)),
                             _poly_mul(_poly_pow(lin["v"], b), _poly_pow(lin["1-v"], d - b)))
            for I, c in poly.items():
                multinomial = factorial(2 * d) / np.prod([factorial(i) for i in I])
                ctrl[I] += comb(d, a) * comb(d, b) * c / multinomial * Q[a, b]
    patch = SPatch(4, 2 * d, ctrl)
    kn = [0.0] * (d + 1) + [1.0] * (d + 1)
    tp = BSplineSurface((d, d), (kn, kn), Q)
    x = interior_points(rng, 4, 60, shrink=1.0)
    u, v = _square_uv(x)
    assert_allclose(patch.evaluate(x), tp.evaluate(np.clip(u, 0, 1), np.clip(v, 0, 1)), rtol=0, atol=EXACT)


# ------------------------------------------------------------------------- invariants
@given(data=patches())
@test_settings(30)
def test_partition_of_unity_and_vertex_interpolation(data):
    patch, seed = data
    n, d = patch.sides, patch.depth
    c = np.array([1.5, -2.0, 0.25])
    const = SPatch._trusted(n, d, np.tile(c, (patch.n_control_points, 1)), patch.weights)
    x = interior_points(np.random.default_rng(seed), n, 20)
    assert_allclose(const.evaluate(x), np.tile(c, (20, 1)), rtol=0, atol=EXACT)
    D = const.derivatives(x, 2)
    assert_allclose(D[:, 1:, :, :].reshape(20, -1), 0.0, atol=1e-11)
    corners = [patch.index_of(tuple(d * np.eye(n, dtype=int)[k])) for k in range(n)]
    assert_allclose(patch.evaluate(domain_vertices(n)), patch.control_points[corners], rtol=0, atol=EXACT * 10)


@given(n=st.integers(3, 8), d=st.integers(1, 4), seed=st.integers(0, 2**32 - 1))
@test_settings(25)
def test_linear_precision(n, d, seed):
    """P_I = sum_k (i_k / d) v_k gives S(x) = x, S_x = (1, 0), S_y = (0, 1), second derivatives 0."""
    idx = spatch_indices(n, d)
    patch = SPatch(n, d, idx @ domain_vertices(n) / d)
    x = interior_points(np.random.default_rng(seed), n, 20)
    D = patch.derivatives(x, 2)
    assert_allclose(D[:, 0, 0], x, rtol=0, atol=EXACT)
    assert_allclose(D[:, 1, 0], [[1.0, 0.0]] * 20, rtol=0, atol=1e-12)
    assert_allclose(D[:, 0, 1], [[0.0, 1.0]] * 20, rtol=0, atol=1e-12)
    for i, j in [(2, 0), (1, 1), (0, 2)]:
        assert_allclose(D[:, i, j], 0.0, atol=1e-11)


@given(data=patches(), a=st.integers(0, 2**32 - 1))
@test_settings(25)
def test_affine_invariance(data, a):
    patch, seed = data
    rng = np.random.default_rng(a)
    M, b = rng.normal(size=(3, 3)), rng.normal(size=3)
    x = interior_points(np.random.default_rng(seed), patch.sides, 15)
    moved = patch.transform(M, b)
    scale = 1 + np.abs(M).sum() * (1 + np.abs(patch.control_points).max())
    assert_allclose(moved.evaluate(x), patch.evaluate(x) @ M.T + b, rtol=0, atol=EXACT * scale)
    D0, D1 = patch.derivatives(x, 1), moved.derivatives(x, 1)
    assert_allclose(D1[:, 1, 0], D0[:, 1, 0] @ M.T, rtol=1e-12, atol=1e-12 * scale)


@given(data=patches(rational=st.just(True)))
@test_settings(25)
def test_rational_projective_invariance(data):
    """A rational S-patch is the projection of the polynomial S-patch of its homogeneous points:
    a projective map of the homogeneous control points maps every point of the patch the same way."""
    patch, seed = data
    rng = np.random.default_rng(seed + 1)
    T = np.eye(4) + 0.05 * rng.normal(size=(4, 4))  # near identity, keeps the new weights positive
    H = patch.homogeneous_points @ T.T
    assume(np.all(H[:, -1] > 0.05))
    moved = SPatch(patch.sides, patch.depth, H[:, :3] / H[:, 3:], weights=H[:, 3])
    x = interior_points(rng, patch.sides, 15)
    # 1e-12 relative: two rational evaluations (quotients of O(1) sums), measured <= 2e-14
    y = np.c_[patch.evaluate(x), np.ones(15)] @ T.T
    expected = y[:, :3] / y[:, 3:]
    assert_allclose(moved.evaluate(x), expected, rtol=0, atol=1e-12 * (1 + np.abs(expected).max()))
    # the polynomial patch of the homogeneous points, projected, is the rational patch
    poly = SPatch(patch.sides, patch.depth, patch.homogeneous_points)
    hp = poly.evaluate(x)
    size = 1 + np.abs(patch.control_points).max()
    assert_allclose(patch.evaluate(x), hp[:, :3] / hp[:, 3:], rtol=0, atol=1e-12 * size)


def test_equal_weights_give_the_polynomial_patch():
    rng = np.random.default_rng(5)
    p = random_patch(rng, 6, 3)
    r = SPatch(6, 3, p.control_points, weights=np.full(p.n_control_points, 2.5))
    x = interior_points(rng, 6, 30)
    assert_allclose(r.derivatives(x, 2), p.derivatives(x, 2), rtol=0, atol=1e-12)


@given(data=patches(depth=st.integers(1, 3)), times=st.integers(1, 2))
@test_settings(20)
def test_depth_elevation_keeps_the_surface(data, times):
    patch, seed = data
    up = patch.elevate_depth(times)
    # second derivatives of a depth-(d+2) patch: sums of O(d^2 |P|) terms, measured <= 5e-13 |P|
    assert up.depth == patch.depth + times
    x = interior_points(np.random.default_rng(seed), patch.sides, 15)
    size = 1 + np.abs(patch.control_points).max()
    assert_allclose(up.derivatives(x, 2), patch.derivatives(x, 2), rtol=0, atol=1e-11 * size)


# ------------------------------------------------------------------------- derivatives vs oracle
@pytest.mark.parametrize("n,d,rational", [(3, 3, False), (5, 3, False), (5, 2, True), (7, 2, True), (4, 4, True)])
def test_derivatives_vs_richardson(n, d, rational):
    rng = np.random.default_rng(40 + n + d)
    patch = random_patch(rng, n, d, rational=rational)
    x = interior_points(rng, n, 6, shrink=0.8)  # keep x ± h inside the domain
    D = patch.derivatives(x, 3)
    ex, ey = np.array([1.0, 0.0]), np.array([0.0, 1.0])
    # 1e-8: Richardson's error (~1e-10 measured) and the size of the derivatives (up to ~1e2)
    tol = dict(rtol=1e-8, atol=1e-8)
    assert_allclose(richardson(patch.evaluate, x, ex), D[:, 1, 0], **tol)
    assert_allclose(richardson(patch.evaluate, x, ey), D[:, 0, 1], **tol)
    assert_allclose(richardson(lambda p: patch.derivatives(p, 1)[:, 1, 0], x, ex), D[:, 2, 0], **tol)
    assert_allclose(richardson(lambda p: patch.derivatives(p, 1)[:, 1, 0], x, ey), D[:, 1, 1], **tol)
    assert_allclose(richardson(lambda p: patch.derivatives(p, 1)[:, 0, 1], x, ey), D[:, 0, 2], **tol)
    assert_allclose(richardson(lambda p: patch.derivatives(p, 2)[:, 1, 1], x, ey), D[:, 1, 2], **tol)
    assert np.all(D[:, 2, 2] == 0) and np.all(D[:, 3, 1] == 0)  # i + j > order: zero


def test_normal_is_unit_cross_product():
    rng = np.random.default_rng(6)
    patch = random_patch(rng, 5, 3)
    x = interior_points(rng, 5, 10)
    D = patch.derivatives(x, 1)
    c = np.cross(D[:, 1, 0], D[:, 0, 1])
    assert_allclose(patch.normal(x), c / np.linalg.norm(c, axis=1, keepdims=True), rtol=0, atol=1e-14)


# ------------------------------------------------------------------------- boundary
@given(data=patches(), k=st.integers(0, 7))
@test_settings(30)
def test_boundary_curve_is_bezier_of_boundary_control_points(data, k):
    patch, seed = data
    k %= patch.sides
    n, d = patch.sides, patch.depth
    t = np.linspace(0, 1, 13)
    v = domain_vertices(n)
    x = (1 - t)[:, None] * v[k] + t[:, None] * v[(k + 1) % n]
    # independent control points: P_I with i_k = d - j, i_{k+1} = j, others 0
    rows = []
    for j in range(d + 1):
        I = [0] * n
        I[k], I[(k + 1) % n] = d - j, j
        rows.append(patch.index_of(tuple(I)))
    H = patch.homogeneous_points[rows]
    expected = de_casteljau(H, t)
    if patch.is_rational:
        expected = expected[:, :-1] / expected[:, -1:]
    curve = patch.boundary_curve(k)
    assert curve.degree == d
    assert_allclose(curve.evaluate(t), expected, rtol=0, atol=EXACT * 10)
    assert_allclose(patch.evaluate(x), expected, rtol=0, atol=EXACT * 10)
    # derivative along the side = curve derivative / side length (exact derivatives on the boundary)
    edge = v[(k + 1) % n] - v[k]
    D = patch.derivatives(x, 1)
    along = (D[:, 1, 0] * edge[0] + D[:, 0, 1] * edge[1])
    assert_allclose(along, curve.derivatives(t, 1)[:, 1], rtol=1e-11, atol=1e-11 * (1 + np.abs(along).max()))


@given(data=patches(depth=st.integers(2, 4)), k=st.integers(0, 7))
@test_settings(30)
def test_cross_boundary_derivative_depends_on_two_rows_only(data, k):
    patch, seed = data
    k %= patch.sides
    n, d = patch.sides, patch.depth
    rng = np.random.default_rng(seed)
    s = patch.indices[:, k] + patch.indices[:, (k + 1) % n]
    far = s < d - 1
    if not far.any():
        return
    P = patch.control_points.copy()
    P[far] += rng.normal(size=(int(far.sum()), 3)) * 5
    other = SPatch._trusted(n, d, P, patch.weights)
    t = np.linspace(0, 1, 9)
    a, b = patch.cross_boundary_derivative(k, t), other.cross_boundary_derivative(k, t)
    assert_allclose(a, b, rtol=1e-12, atol=1e-12 * (1 + np.abs(a).max()))
    # ... and it is the derivative along the inward normal: oracle by one-sided Richardson
    nu = patch.inward_normal(k)
    x = patch.edge_points(k, t[3:6])
    f = lambda h: patch.evaluate(x + h * nu)  # noqa: E731
    T = [(f(h) - f(0.0)) / h for h in (4e-3, 2e-3, 1e-3, 5e-4)]
    for j in range(1, 4):  # one-sided differences: error O(h), O(h^2), ... eliminated in turn
        T = [(2**j * T[i + 1] - T[i]) / (2**j - 1) for i in range(len(T) - 1)]
    assert_allclose(a[3:6], T[0], rtol=1e-6, atol=1e-6 * (1 + np.abs(a).max()))
    # while the interior does move
    xin = np.zeros((1, 2))
    assert not np.allclose(other.evaluate(xin), patch.evaluate(xin))


# ------------------------------------------------------------------------- API, shapes, errors
def test_mapping_and_array_inputs_agree_and_shapes():
    rng = np.random.default_rng(7)
    p = random_patch(rng, 5, 2, rational=True)
    keyed = {tuple(int(i) for i in I): P for I, P in zip(p.indices, p.control_points)}
    wkeyed = {tuple(int(i) for i in I): w for I, w in zip(p.indices, p.weights)}
    q = SPatch(5, 2, dict(reversed(list(keyed.items()))), weights=wkeyed)
    assert q == p
    x = interior_points(rng, 5, 12).reshape(3, 4, 2)
    assert p.evaluate(x).shape == (3, 4, 3)
    assert p.evaluate(x[0, 0]).shape == (3,)
    assert p.derivatives(x, 2).shape == (3, 4, 3, 3, 3)
    assert p.cross_boundary_derivative(1, 0.5).shape == (3,)
    assert p.boundary_curve(4).n_poles == 3
    assert p.indices.flags.writeable is False and p.control_points.flags.writeable is False


def test_to_dict_round_trip_through_json():
    p = random_patch(np.random.default_rng(8), 6, 3, rational=True)
    q = SPatch.from_dict(json.loads(json.dumps(p.to_dict())))
    assert q == p
    with pytest.raises(InvalidGeometryError, match="type 'SPatch'"):
        SPatch.from_dict({"type": "BSplineSurface"})


@pytest.mark.parametrize("args,match", [
    ((2, 1, np.zeros((2, 3))), "sides"),
    ((True, 1, np.zeros((3, 3))), "sides"),
    ((3, 0, np.zeros((1, 3))), "depth"),
    ((3, 1.5, np.zeros((3, 3))), "depth"),
    ((3, 2, np.zeros((5, 3))), "6 control points"),
    ((3, 2, np.zeros((6,))), "control_points"),
    ((3, 1, [[0, 0, 0], [1, 0, 0], [0, np.nan, 0]]), "finite"),
    ((3, 1, {(1, 0, 0): [0, 0], (0, 1, 0): [1, 0]}), r"missing \[\(0, 0, 1\)\]"),
    ((3, 1, {(1, 0, 0): [0, 0], (0, 1, 0): [1, 0], (0, 0, 1): [0, 1], (1, 1, 0): [0, 0]}), "unexpected"),
    ((3, 1, {("a", 0, 0): [0, 0]}), "tuples of integers"),
])
def test_invalid_patches(args, match):
    with pytest.raises(InvalidGeometryError, match=match):
        SPatch(*args)


def test_invalid_weights():
    P = np.zeros((3, 3))
    with pytest.raises(InvalidGeometryError, match="weights must be > 0"):
        SPatch(3, 1, P, weights=[1.0, 0.0, 1.0])
    with pytest.raises(InvalidGeometryError, match="weights"):
        SPatch(3, 1, P, weights=[1.0, 1.0])
    with pytest.raises(InvalidGeometryError, match="weights"):
        SPatch(3, 1, P, weights=[1.0, np.inf, 1.0])


def test_invalid_points_and_sides():
    p = random_patch(np.random.default_rng(9), 5, 2)
    with pytest.raises(ParameterError, match="outside the regular 5-gon"):
        p.evaluate([[0.95, 0.3]])
    with pytest.raises(ParameterError, match="finite"):
        p.evaluate([[np.nan, 0.0]])
    with pytest.raises(ParameterError, match=r"shape \(\.\.\., 2\)"):
        p.evaluate([0.1, 0.2, 0.3])
    with pytest.raises(InvalidGeometryError, match="side number"):
        p.boundary_curve(5)
    with pytest.raises(ParameterError):
        p.cross_boundary_derivative(0, 1.5)
    with pytest.raises(InvalidGeometryError, match="order"):
        p.derivatives([0.0, 0.0], -1)
    with pytest.raises(InvalidGeometryError, match="3-D"):
        random_patch(np.random.default_rng(0), 4, 1, dim=2).normal([0.0, 0.0])
    with pytest.raises(InvalidGeometryError, match="sides"):
        wachspress([0.0, 0.0], 2)
    # points on the sides, a round-off hair outside, are accepted
    v = domain_vertices(5)
    edge = 0.5 * (v[0] + v[1]) * (1 + 1e-12)
    assert np.all(np.isfinite(p.evaluate(edge)))


def test_too_many_sides_and_bad_index_tuples():
    """Review (issue 4 error paths): sides beyond MAX_SIDES, and index tuples that are not n
    non-negative integers summing to d, are refused with a message naming them."""
    from occsurf.algorithms import tolerances

    MAX_SIDES = tolerances.SPATCH_MAX_SIDES
    with pytest.raises(InvalidGeometryError, match=f"sides: expected an integer from 3 to {MAX_SIDES}, got {MAX_SIDES + 1}"):
        SPatch(MAX_SIDES + 1, 1, np.zeros((MAX_SIDES + 1, 3)))
    with pytest.raises(InvalidGeometryError, match="sides"):
        domain_vertices(MAX_SIDES + 1)
    p = random_patch(np.random.default_rng(11), 3, 2)
    for bad in [(1.5, 1, 0), (2, 0), (3, -1, 0), (1, 1, 1), (True, 1, 0)]:
        with pytest.raises(InvalidGeometryError, match="index: expected 3 non-negative integers summing to 2"):
            p.index_of(bad)
    with pytest.raises(InvalidGeometryError, match="row: expected an integer from 0 to 2"):
        p.boundary_indices(0, 3)
    with pytest.raises(InvalidGeometryError, match="row"):
        p.boundary_indices(0, -1)
    with pytest.raises(InvalidGeometryError, match="unexpected"):
        SPatch(3, 1, {(2, -1, 0): [0, 0], (0, 1, 0): [1, 0], (0, 0, 1): [0, 1]})


def test_spatch_tolerances_are_read_at_call_time():
    """SPATCH_MAX_SIDES and SPATCH_DOMAIN_SLACK come from occsurf.algorithms.tolerances when a
    patch is built or evaluated, so an override applies to the block and nothing else."""
    from occsurf.algorithms import tolerances

    with tolerances.override(SPATCH_MAX_SIDES=5):
        with pytest.raises(InvalidGeometryError, match=r"^sides: expected an integer from 3 to 5, got 6$"):
            SPatch(6, 1, np.zeros((6, 3)))
        with pytest.raises(InvalidGeometryError, match="from 3 to 5"):
            domain_vertices(6)
        assert SPatch(5, 1, np.zeros((5, 3))).sides == 5
    assert SPatch(6, 1, np.zeros((6, 3))).sides == 6
    p = random_patch(np.random.default_rng(12), 5, 2)
    v = domain_vertices(5)
    outside = 0.5 * (v[0] + v[1]) * (1 + 1e-6)  # beyond side 0 by 8e-7
    with pytest.raises(ParameterError, match="outside the regular 5-gon"):
        p.evaluate(outside)
    with tolerances.override(SPATCH_DOMAIN_SLACK=1e-5):
        assert np.all(np.isfinite(p.evaluate(outside)))


@pytest.mark.parametrize("n", [3, 5, 8])
def test_shared_index_and_normal_helpers(n):
    """The trusted helpers shared by spatch and spatch_convert (topology._common) agree with the
    public functions: the same index order, and side k's outward normal through the midpoint of
    vertices k and k+1 at the apothem cos(pi/n)."""
    from occsurf.algorithms.topology._common import edge_normals, index_tuples

    for d in (1, 2, 4):
        assert np.array_equal(np.array(index_tuples(n, d)), spatch_indices(n, d))
    assert index_tuples(n, 0) == ((0,) * n,)
    v, nrm = domain_vertices(n), edge_normals(n)
    mids = 0.5 * (v + np.roll(v, -1, axis=0))
    assert_allclose(nrm * np.cos(np.pi / n), mids, rtol=0, atol=1e-15)
    assert_allclose(np.linalg.norm(nrm, axis=1), 1.0, rtol=0, atol=1e-15)
