"""Tests of the thin-plate fairing of a fill patch's interior poles (``_fair_interior``,
algorithms/topology/nsided_patches.py).

``_fair_interior`` minimises ``int |S_uu|^2 + 2 |S_uv|^2 + |S_vv|^2`` over the free poles with the
others fixed. Its matrix ``K = Gu2 (x) Gv0 + 2 Gu1 (x) Gv1 + Gu0 (x) Gv2`` is banded-Kronecker and is
built sparse and factored by SuperLU (a dense (nu nv)^2 array was 1.1 GB and ~90 s on the lens's
face 2, a 213 x 56 patch).

Oracles and tolerances:
- the dense normal equations (``np.kron`` of the same Gram matrices, ``np.linalg.solve``) on small
  patches: both are LU solves of one system whose condition is at most ~1e6 at these sizes, so
  they agree within 1e-8 of the pole scale (measured <= 1e-11);
- an affine map of the Greville abscissae has zero thin-plate energy and is the unique minimiser
  with its own boundary rows fixed: its interior poles come back to 1e-9 (same conditioning);
- fixed poles are copied, not solved: bit-identical;
- memory: a 150 x 56 patch (8176 free poles; dense K would be 8400^2 floats = 564 MB) is faired
  with a NumPy allocation peak below 250 MB (measured 106 MB: the three Kronecker products are
  built in COO form, ~1.4e6 entries of 24 bytes each, before they are summed to CSR).
"""

from __future__ import annotations

import tracemalloc

import numpy as np
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from occsurf.algorithms.kernel.basis import greville
from occsurf.algorithms.topology.nsided_patches import _fair_interior, _gram
from tests.algorithms.strategies import test_settings


def _knots(degree: int, inner: np.ndarray, corner: bool) -> np.ndarray:
    """Clamped knots on [0, 1] with the given inner knots (and a corner knot of multiplicity
    ``degree - 1`` near 0 as the fill's ``_corner_knot`` inserts)."""
    inner = np.sort(np.asarray(inner, float))
    if corner:
        inner = np.r_[[0.5 * inner[0]] * (degree - 1), inner] if len(inner) else np.r_[[0.1] * (degree - 1)]
    return np.r_[[0.0] * (degree + 1), inner, [1.0] * (degree + 1)]


def _free_interior(nu: int, nv: int) -> np.ndarray:
    """Free poles: all but the two outer rows on every edge (as ``_assemble_poles`` fixes them)."""
    free = np.zeros((nu, nv), bool)
    free[2:-2, 2:-2] = True
    return free


def _dense_fair(H: np.ndarray, free: np.ndarray, degree, knots) -> np.ndarray:
    """The dense normal equations: the former implementation, kept here as the oracle."""
    G = [[_gram(knots[d], degree[d], k) for k in range(3)] for d in range(2)]
    K = np.kron(G[0][2], G[1][0]) + 2 * np.kron(G[0][1], G[1][1]) + np.kron(G[0][0], G[1][2])
    f = free.ravel()
    flat = H.reshape(-1, H.shape[2]).copy()
    flat[f] = np.linalg.solve(K[np.ix_(f, f)], -K[np.ix_(f, ~f)] @ flat[~f])
    return flat.reshape(H.shape)


patch = st.tuples(
    st.integers(3, 6), st.integers(3, 6),                       # degrees
    st.integers(1, 6), st.integers(1, 6),                       # inner knot counts
    st.booleans(), st.integers(0, 2**32 - 1),                   # corner knot, seed
)


def _patch(pu: int, pv: int, ku: int, kv: int, corner: bool, seed: int):
    rng = np.random.default_rng(seed)
    Ku = _knots(pu, rng.uniform(0.05, 0.95, ku), corner)
    Kv = _knots(pv, rng.uniform(0.05, 0.95, kv), corner)
    nu, nv = len(Ku) - pu - 1, len(Kv) - pv - 1
    return (pu, pv), (Ku, Kv), nu, nv, rng


@test_settings(30)
@given(patch)
def test_fair_interior_matches_dense_solve(args):
    degree, knots, nu, nv, rng = _patch(*args)
    H = rng.uniform(-10, 10, (nu, nv, 4))
    free = _free_interior(nu, nv)
    got = _fair_interior(H, free, degree, knots)
    want = _dense_fair(H, free, degree, knots)
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-8 * np.abs(H).max())
    assert np.array_equal(got[~free], H[~free])


@test_settings(30)
@given(patch)
def test_fair_interior_reproduces_affine_patches(args):
    degree, knots, nu, nv, rng = _patch(*args)
    gu, gv = greville(knots[0], degree[0]), greville(knots[1], degree[1])
    A, b = rng.normal(size=(2, 3)), rng.normal(size=3)
    exact = np.stack(np.meshgrid(gu, gv, indexing="ij"), axis=-1) @ A + b
    free = _free_interior(nu, nv)
    H = exact.copy()
    H[free] = rng.normal(size=(int(free.sum()), 3)) * 100.0  # garbage where the solve must write
    np.testing.assert_allclose(_fair_interior(H, free, degree, knots), exact, rtol=0, atol=1e-9)


def test_fair_interior_without_free_poles_is_identity():
    degree, knots, nu, nv, rng = _patch(3, 3, 2, 2, False, 1)
    H = rng.normal(size=(nu, nv, 3))
    assert _fair_interior(H, np.zeros((nu, nv), bool), degree, knots) is H


def test_fair_interior_large_patch_stays_sparse():
    pu = pv = 6
    Ku = _knots(pu, np.linspace(0, 1, 145)[1:-1], False)   # 150 poles along u
    Kv = _knots(pv, np.linspace(0, 1, 51)[1:-1], False)    # 56 along v
    nu, nv = len(Ku) - pu - 1, len(Kv) - pv - 1
    assert (nu, nv) == (150, 56)
    gu, gv = greville(Ku, pu), greville(Kv, pv)
    exact = np.stack(np.meshgrid(gu, gv, indexing="ij"), axis=-1) @ np.array([[1.0, 0.5, -2.0], [0.3, 1.0, 4.0]])
    free = _free_interior(nu, nv)
    H = exact.copy()
    H[free] = 0.0
    tracemalloc.start()
    try:
        got = _fair_interior(H, free, (pu, pv), (Ku, Kv))
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 250e6, f"NumPy allocation peak {peak / 1e6:.0f} MB (dense K would be 564 MB)"
    np.testing.assert_allclose(got, exact, rtol=0, atol=1e-9)


def test_symmetric_mode_agrees_with_the_default_factorisation_and_leaves_no_larger_residual():
    """The free block is factored in SuperLU's symmetric mode (minimum degree on K + K^T, diagonal
    pivots; 3 to 6 times faster on linkrods face 20's patches). Against SuperLU's default (COLAMD,
    partial pivoting) on a 150 x 56 patch of degree 6 with random boundary poles: the poles agree
    within 1e-8 of the pole scale (round-off through the system's condition: measured 1e-9 relative
    on the real patches), and the residual of K_ff x = -K_fb h_b is no larger (measured 3-4 times
    smaller there)."""
    from scipy import sparse
    from scipy.sparse.linalg import splu

    pu = pv = 6
    Ku = _knots(pu, np.linspace(0, 1, 145)[1:-1], True)
    Kv = _knots(pv, np.linspace(0, 1, 51)[1:-1], True)
    nu, nv = len(Ku) - pu - 1, len(Kv) - pv - 1
    H = np.random.default_rng(7).uniform(-10, 10, (nu, nv, 3))
    free = _free_interior(nu, nv)
    got = _fair_interior(H, free, (pu, pv), (Ku, Kv))
    G = [[sparse.csr_matrix(_gram(k, p, d)) for d in range(3)] for k, p in ((Ku, pu), (Kv, pv))]
    K = (sparse.kron(G[0][2], G[1][0]) + 2 * sparse.kron(G[0][1], G[1][1]) + sparse.kron(G[0][0], G[1][2])).tocsr()
    f = free.ravel()
    Kff, rhs = K[f][:, f].tocsc(), -(K[f][:, ~f] @ H.reshape(-1, 3)[~f])
    default = splu(Kff).solve(rhs)
    ours = got.reshape(-1, 3)[f]
    np.testing.assert_allclose(ours, default, rtol=0, atol=1e-8 * np.abs(H).max())

    def residual(x: np.ndarray) -> float:
        return float(np.linalg.norm(Kff @ x - rhs) / np.linalg.norm(rhs))
    assert residual(ours) <= residual(default), (residual(ours), residual(default))


@test_settings(20)
@given(patch, st.integers(0, 2**32 - 1))
def test_kept_factors_give_the_poles_of_a_fresh_factorisation_bit_for_bit(args, seed2):
    """Small fairing systems keep their factors (tolerances.FILL_FAIR_CACHE_FREE): a second patch
    of the same layout, solved with them, gets exactly the poles a fresh factorisation gives; a
    different free mask is a different system."""
    from occsurf.algorithms import tolerances
    from occsurf.algorithms.topology.nsided_patches import _fair_system_cached

    degree, knots, nu, nv, rng = _patch(*args)
    free = _free_interior(nu, nv)
    H1, H2 = rng.uniform(-10, 10, (2, nu, nv, 4))
    _fair_system_cached.cache_clear()
    with tolerances.override(FILL_FAIR_CACHE_FREE=0):  # no cache: factored on every call
        fresh = [_fair_interior(H, free, degree, knots) for H in (H1, H2)]
    assert _fair_system_cached.cache_info().currsize == 0
    kept = [_fair_interior(H, free, degree, knots) for H in (H1, H2)]
    info = _fair_system_cached.cache_info()
    assert (info.misses, info.hits) == (1, 1)
    for a, b in zip(fresh, kept):
        assert np.array_equal(a, b)
    other = free.copy()
    other[tuple(np.argwhere(free)[np.random.default_rng(seed2).integers(free.sum())])] = False  # one pole fixed
    if other.any():
        with tolerances.override(FILL_FAIR_CACHE_FREE=0):
            want = _fair_interior(H1, other, degree, knots)
        np.testing.assert_array_equal(_fair_interior(H1, other, degree, knots), want)
        assert _fair_system_cached.cache_info().misses == 2


@given(p=st.integers(1, 10), inner=st.lists(st.floats(0.01, 0.99), max_size=10), snap=st.booleans())
@settings(max_examples=60, deadline=None)
def test_grams_of_one_basis_evaluation_equal_each_order_alone(p, inner, snap):
    """The fairing's Gram matrices of orders 0-2 come from one evaluation of the basis to order 2 at
    the Gauss points, summed over each point's non-zero basis functions (the bands of
    ``basis.gram_bands``, shared with the plate): each equals, bit for bit, the same sums from an
    evaluation to its own order only, summed into the full matrix; and, to round-off (1e-13 of the largest
    entry), the dense product ``B^T (w B)`` of the whole collocation matrix, which is how they were
    made before 2026-12-06 (BLAS sums the terms in an order of its own)."""
    from occsurf.algorithms.kernel.basis import basis_derivatives, basis_matrix, find_span, gauss_legendre
    from occsurf.algorithms.topology.nsided_patches import _gram_cached

    t = np.sort(np.round(np.array(inner) * 4) / 4 if snap else np.array(inner))
    knots = np.r_[[0.0] * (p + 1), t, [1.0] * (p + 1)]
    assume(np.all(np.unique(knots, return_counts=True)[1][1:-1] <= p))
    n = len(knots) - p - 1
    xg, wg = gauss_legendre(p + 1)
    br = np.unique(knots)
    a, b = br[:-1], br[1:]
    x = (0.5 * (a + b)[:, None] + 0.5 * (b - a)[:, None] * xg).ravel()
    wt = (0.5 * (b - a)[:, None] * wg).ravel()
    span = find_span(knots, p, n, x)
    cols = span[:, None] - p + np.arange(p + 1)
    at = (cols[:, :, None] * n + cols[:, None, :]).ravel()
    _gram_cached.cache_clear()
    for order in range(3):
        Dk = basis_derivatives(knots, p, span, x, order)[:, order]  # evaluated to this order only
        alone = np.bincount(at, weights=((wt[:, None] * Dk)[:, :, None] * Dk[:, None, :]).ravel(),
                            minlength=n * n).reshape(n, n)
        G = _gram(knots, p, order)
        assert np.array_equal(G, alone)
        D = basis_matrix(knots, p, n, x, order)[order]
        dense = D.T @ (wt[:, None] * D)
        assert np.abs(G - dense).max() <= 1e-13 * np.abs(dense).max()
