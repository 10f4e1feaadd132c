"""The plate's Gram matrices (:func:`plate_fill._gram`) summed into their band are the sparse
product ``B^T diag(w) B`` of the basis functions' k-th derivatives at the Gauss points, bit for bit
(the same products, added in the same order), over uniform, bisected and random knot vectors of
degrees 3 to 5; and exact on polynomials (a closed form)."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from hypothesis import given, settings
from hypothesis import strategies as st

from occsurf.algorithms.kernel.basis import basis_derivatives, find_span
from occsurf.algorithms.topology import plate_fill as pf


def _product_form(knots: np.ndarray, p: int, top: int) -> list[sp.csr_matrix]:
    n = knots.size - p - 1
    brk = np.unique(knots)
    x, w = np.polynomial.legendre.leggauss(p + 1)
    a, b = brk[:-1, None], brk[1:, None]
    t = (0.5 * (a + b) + 0.5 * (b - a) * x).ravel()
    wt = (0.5 * (b - a) * w).ravel()
    span = find_span(knots, p, n, t)
    D = basis_derivatives(knots, p, span, t, top)
    cols = span[:, None] - p + np.arange(p + 1)
    out = []
    for k in range(top + 1):
        B = sp.csr_matrix((D[:, k].ravel(), cols.ravel(), np.arange(0, t.size * (p + 1) + 1, p + 1)), shape=(t.size, n))
        M = (B.T @ sp.diags(wt) @ B).tocsr()
        M.sort_indices()
        out.append(M)
    return out


@st.composite
def _knot_vectors(draw):
    p = draw(st.integers(3, 5))
    spans = draw(st.integers(1, 130))
    lo = draw(st.floats(-3.0, 0.0))
    hi = lo + draw(st.floats(0.1, 5.0))
    kind = draw(st.sampled_from(["uniform", "bisected", "random"]))
    if kind == "random":
        inner = np.sort(np.asarray(draw(st.lists(st.floats(0.01, 0.99), min_size=spans - 1, max_size=spans - 1))))
        knots = np.r_[[lo] * (p + 1), lo + (hi - lo) * inner, [hi] * (p + 1)]
    else:
        knots = pf._knots(lo, hi, spans, p)
        if kind == "bisected":
            rng = np.random.default_rng(spans)
            for _ in range(3):
                knots = pf._bisect(knots, p, rng.uniform(lo, hi, 6), 128)
    return knots, p, draw(st.integers(2, 3))


@settings(max_examples=150, deadline=None)
@given(_knot_vectors())
def test_gram_is_the_sparse_product_bit_for_bit(case) -> None:
    knots, p, top = case
    pf._gram_cached.cache_clear()
    got = pf._gram(knots, p, top)
    for G, M in zip(got, _product_form(knots, p, top)):
        assert G.shape == M.shape
        assert np.array_equal(G.indptr, M.indptr) and np.array_equal(G.indices, M.indices)
        assert np.array_equal(G.data, M.data)


def test_gram_integrates_polynomials_exactly() -> None:
    """Sum_ij G_k[i, j] c_i c_j = int (f^(k))^2 for f = sum c_i N_i: with all c_i = x-Greville
    abscissae, f(x) = x on [0, 2], so int f^2 = 8/3, int f'^2 = 2, int f''^2 = 0."""
    p = 3
    knots = pf._knots(0.0, 2.0, 7, p)
    g = pf._greville(knots, p)
    G0, G1, G2 = pf._gram(knots, p, 2)
    assert np.isclose(g @ (G0 @ g), 8.0 / 3.0, rtol=1e-14)
    assert np.isclose(g @ (G1 @ g), 2.0, rtol=1e-14)
    assert abs(g @ (G2 @ g)) <= 1e-13
