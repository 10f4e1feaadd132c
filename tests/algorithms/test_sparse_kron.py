"""Tests of :func:`occsurf.algorithms.kernel.sparse_kron.kron_sum` (the tensor-product energies of the
plate fill and of the central split's fairing, course §8-3).

The contract is bit-identity of the values: the matrix is the one ``scipy.sparse`` builds for
``c_0 kron(A_0, B_0) + c_1 kron(A_1, B_1) + ...`` (compared with ``==``, no tolerance), with the
same sorted pattern but for explicit zeros, which it never stores. Checked on the Gram matrices of
B-spline spaces (the uses), on random banded matrices with negative values, holes in their band and
cancelling terms (Hypothesis; given dense, so read in place: the central split passes its dense
Gram matrices), and through the fallback for wide bands. What that does to the fills:
the plate's system drops the zeros anyway (``A^T A + eps E``), so the plate is bit-identical; the
central split's fairing factored explicit zeros where scipy had built a product in blocks (a Gram
matrix of at most ~12 poles), so its poles move by round-off there (bound 1e-9 of the hole's size,
measured 5.4e-11 on the bump rings and 0 on the flat ones).
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from hypothesis import given
from hypothesis import strategies as st

from occsurf.algorithms.errors import InvalidGeometryError
from occsurf.algorithms.kernel.sparse_kron import MAX_HALF_BAND, kron_rows, kron_sum
from occsurf.algorithms.topology.plate_fill import _gram
from tests.algorithms.strategies import test_settings


def _scipy_sum(terms, keep_zeros: bool = False):
    """The sparse sum as scipy makes it; ``keep_zeros``: with the zeros it stores in the blocks of a
    product of a narrow ``B_k`` (BSR), as the fairing factored them before ``kron_sum``."""
    total = None
    for c, a, b in terms:
        k = sp.kron(sp.csr_matrix(a), sp.csr_matrix(b))
        k = k if c == 1 else c * k
        total = k if total is None else total + k
    out = sp.csr_matrix(total)
    if keep_zeros:
        return out
    out.eliminate_zeros()
    out.sort_indices()
    return out


def _same(got: sp.csr_matrix, want: sp.csr_matrix) -> None:
    assert got.shape == want.shape
    assert np.array_equal(got.indptr, want.indptr)
    assert np.array_equal(got.indices, want.indices)
    assert np.array_equal(got.data, want.data)  # bit for bit: no tolerance
    assert not (got.data == 0).any()


@pytest.mark.parametrize("p, coefs", [(3, (1, 2.0, 1)), (4, (1, 3.0, 3.0, 1))])
def test_the_thin_plate_and_curvature_variation_energies_bit_for_bit(p: int, coefs) -> None:
    """The plate's G1 (thin plate) and G2 (curvature variation) energies on uneven knots."""
    ku = np.r_[[0.0] * (p + 1), np.linspace(0, 1, 41)[1:-1], [1.0] * (p + 1)]
    kv = np.r_[[0.0] * (p + 1), np.linspace(0, 1, 29)[1:-1] ** 1.7, [1.0] * (p + 1)]
    top = len(coefs) - 1
    Gu, Gv = _gram(ku, p, top), _gram(kv, p, top)
    terms = [(c, Gu[top - k], Gv[k]) for k, c in enumerate(coefs)]
    _same(kron_sum(terms), _scipy_sum(terms))


@st.composite
def _banded(draw, size: int, half: int) -> np.ndarray:
    M = np.array(draw(st.lists(st.floats(-1e3, 1e3, allow_nan=False), min_size=size * size, max_size=size * size)))
    M = M.reshape(size, size)
    i, j = np.indices(M.shape)
    M[np.abs(i - j) > half] = 0.0
    holes = np.array(draw(st.lists(st.booleans(), min_size=size * size, max_size=size * size))).reshape(size, size)
    M[holes] = 0.0  # holes in the band (and, with the cancelling sums below, zero results)
    return M


@test_settings(40)
@given(data=st.data(), m=st.integers(1, 7), n=st.integers(1, 7), ha=st.integers(0, 3), hb=st.integers(0, 3),
       coefs=st.lists(st.sampled_from([1, 2, 3.0, -1.0, 0.5]), min_size=1, max_size=4))
def test_random_banded_matrices_bit_for_bit(data, m, n, ha, hb, coefs) -> None:
    terms = [(c, data.draw(_banded(m, ha)), data.draw(_banded(n, hb))) for c in coefs]
    if len(terms) > 1:  # a term that cancels another: its entries sum to exact zeros, which are dropped
        terms.append((-1.0, terms[0][1], terms[0][2]) if terms[0][0] == 1 else terms[-1])
    _same(kron_sum(terms), _scipy_sum(terms))


@test_settings(40)
@given(data=st.data(), m=st.integers(1, 7), n=st.integers(1, 7), ha=st.integers(0, 3), hb=st.integers(0, 3),
       coefs=st.lists(st.sampled_from([1, 2, 3.0, -1.0, 0.5]), min_size=1, max_size=3))
def test_kron_rows_are_the_rows_of_the_sum_bit_for_bit(data, m, n, ha, hb, coefs) -> None:
    """Any block of rows ``I x J`` (the fairing's interior of the grid): ``kron_sum(terms)`` at those
    rows, values, columns and pattern, with the sum's zeros left out alike."""
    terms = [(c, data.draw(_banded(m, ha)), data.draw(_banded(n, hb))) for c in coefs]
    i0 = data.draw(st.integers(0, m - 1))
    i1 = data.draw(st.integers(i0 + 1, m))
    j0 = data.draw(st.integers(0, n - 1))
    j1 = data.draw(st.integers(j0 + 1, n))
    rows = (np.arange(i0, i1)[:, None] * n + np.arange(j0, j1)).ravel()
    _same(kron_rows(terms, range(i0, i1), range(j0, j1)), kron_sum(terms)[rows])


def test_kron_rows_of_wide_bands_and_bad_ranges() -> None:
    rng = np.random.default_rng(5)
    A = rng.standard_normal((MAX_HALF_BAND + 4, MAX_HALF_BAND + 4))  # dense: left to scipy
    B = np.diag(rng.standard_normal(5))
    terms = [(1, A, B), (2.0, A.T, B)]
    rows = (np.arange(2, 9)[:, None] * 5 + np.arange(1, 4)).ravel()
    _same(kron_rows(terms, range(2, 9), range(1, 4)), _scipy_sum(terms)[rows])
    for ra, rb in ((range(0), range(2)), (range(0, 30), range(2)), (range(0, 4, 2), range(2)), ([0, 1], range(2))):
        with pytest.raises(InvalidGeometryError, match="expected a non-empty range with step 1"):
            kron_rows(terms, ra, rb)


def test_the_fairing_takes_the_free_rows_alone_where_they_are_a_block(monkeypatch: pytest.MonkeyPatch) -> None:
    """``_fair_system``'s free rows by ``kron_rows`` where the free poles are a block of the grid
    (else ``kron_sum``'s rows): the same coupling and factors, so the same solve, bit for bit."""
    from occsurf.algorithms.topology import nsided_patches
    from occsurf.algorithms.topology.nsided_patches import _fair_system, _free_block

    free = np.zeros((9, 8), dtype=bool)
    free[2:7, 2:6] = True
    assert _free_block(free) == (range(2, 7), range(2, 6))
    corner = free.copy()
    corner[2, 2] = False
    gaps = free.copy()
    gaps[4] = False  # two blocks of rows
    assert _free_block(corner) is None and _free_block(gaps) is None and _free_block(free & False) is None
    p = 4
    ku = np.r_[[0.0] * (p + 1), np.linspace(0, 1, 6)[1:-1] ** 1.3, [1.0] * (p + 1)]
    kv = np.r_[[0.0] * (p + 1), np.linspace(0, 1, 5)[1:-1], [1.0] * (p + 1)]
    key = (ku.tobytes(), kv.tobytes(), (p, p))
    rhs = np.random.default_rng(1).standard_normal((72 - 20, 3))
    coupling, lu = _fair_system(*key, free)
    monkeypatch.setattr(nsided_patches, "_free_block", lambda f: None)  # every row of K, then the free ones
    coupling_all, lu_all = _fair_system(*key, free)
    _same(coupling, coupling_all)
    assert np.array_equal(lu.solve(-(coupling @ rhs)), lu_all.solve(-(coupling_all @ rhs)))


def test_wide_bands_are_summed_by_scipy() -> None:
    rng = np.random.default_rng(3)
    A = rng.standard_normal((MAX_HALF_BAND + 4, MAX_HALF_BAND + 4))  # dense: half-band above the limit
    B = np.diag(rng.standard_normal(5))
    terms = [(1, A, B), (2.0, A.T, B)]
    _same(kron_sum(terms), _scipy_sum(terms))


def test_bad_input_is_refused() -> None:
    with pytest.raises(InvalidGeometryError, match="at least one term"):
        kron_sum([])
    with pytest.raises(InvalidGeometryError, match="square A_k of one size"):
        kron_sum([(1, np.eye(3), np.eye(2)), (1, np.eye(4), np.eye(2))])
    with pytest.raises(InvalidGeometryError, match="square A_k of one size"):
        kron_sum([(1, np.ones((2, 3)), np.eye(2))])


@pytest.mark.parametrize("n", [3, 5, 7])
def test_central_split_poles_move_by_round_off_only(n: int, monkeypatch: pytest.MonkeyPatch) -> None:
    from occsurf.algorithms.topology import nsided_patches
    from occsurf.algorithms.topology.nsided import fill_hole
    from occsurf.examples.hole_models import ring_model

    ring = ring_model(n, bump=0.3)
    now = fill_hole(ring.sides)
    monkeypatch.setattr(nsided_patches, "kron_sum", lambda terms: _scipy_sum(terms, keep_zeros=True))
    before = fill_hole(ring.sides)
    size = np.ptp(np.concatenate([p.control_points.reshape(-1, 3) for p in now.patches]), axis=0).max()
    for a, b in zip(now.patches, before.patches):
        assert np.abs(a.control_points - b.control_points).max() <= 1e-9 * size


@test_settings(40)
@given(data=st.data(), m=st.integers(1, 7), n=st.integers(1, 7), ha=st.integers(0, 3), hb=st.integers(0, 3),
       extra=st.integers(0, 2), coefs=st.lists(st.sampled_from([1, 2, 3.0, -1.0, 0.5]), min_size=1, max_size=4))
def test_the_stencil_form_holds_the_same_values(data, m, n, ha, hb, extra, coefs) -> None:
    """``kron_stencil`` (the rows on the grid, for the plate's grid Cholesky) holds the values of
    ``kron_sum`` bit for bit (``==``: a product that is -0.0 counts as the zero ``kron_sum`` drops), on
    a stencil as wide as the bands or wider, zero off the grid; a reach below a band is refused."""
    from occsurf.algorithms.kernel.grid_cholesky import grid_stencil
    from occsurf.algorithms.kernel.sparse_kron import kron_stencil

    terms = [(c, data.draw(_banded(m, ha)), data.draw(_banded(n, hb))) for c in coefs]
    reach = max(ha, hb, 1) + extra
    got = kron_stencil(terms, reach)
    want = grid_stencil(kron_sum(terms), (m, n), reach)
    assert got.shape == (m, n, 2 * reach + 1, 2 * reach + 1)
    assert np.array_equal(got, want)
    if max(ha, hb) > 0 and any(np.abs(np.subtract(*np.nonzero(t[1]))).max(initial=0) == ha > 0 for t in terms):
        with pytest.raises(InvalidGeometryError, match="exceed the stencil's reach"):
            kron_stencil(terms, ha - 1)
