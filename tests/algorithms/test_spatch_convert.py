"""S-patch -> rational tensor-product pieces (algorithms/topology/spatch_convert.py): the exact path against
SPatch.evaluate, the shared piece boundaries, the bidegrees, the approximation path and its
measured deviation."""

from __future__ import annotations

from math import comb

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from numpy.testing import assert_allclose

from occsurf.algorithms import tolerances
from occsurf.algorithms.errors import InvalidGeometryError, ToleranceError
from occsurf.algorithms.topology.spatch import SPatch
from occsurf.algorithms.topology.spatch_convert import (
    convert_spatch,
    exact_bidegree,
    piece_corners,
    piece_domain_points,
    spatch_to_surfaces,
)
from tests.algorithms.strategies import test_settings

# The exact pieces are built from sums of products of positive numbers (no cancellation) and a
# division by binomials <= C(25, 12); a rational Bézier of degree <= 25 is then evaluated stably
# by de Boor. Measured: <= 1.5e-14 relative to the control points' size for bidegree 25, ~3e-15
# for bidegree <= 12. EXACT_REL = 1e-12 leaves two orders of margin while any error in the
# construction (a wrong coefficient, a wrong binomial, a piece mis-mapped) shows as O(1e-2..1).
EXACT_REL = 1e-12


def random_patch(rng, n, d, rational=False, dim=3):
    m = comb(n + d - 1, d)
    w = rng.uniform(0.3, 3.0, m) if rational else None
    return SPatch(n, d, rng.normal(size=(m, dim)), weights=w)


def _max_error_vs_patch(patch, surfaces, rng, count=400):
    s, t = rng.uniform(size=(2, count))
    s[:8], t[:8] = [0, 1, 1, 0, 0.5, 1, 0, 0.3], [0, 0, 1, 1, 0, 0.5, 0.7, 1]  # corners and sides too
    err = 0.0
    for k, surf in enumerate(surfaces):
        ref = patch.evaluate(piece_domain_points(patch.sides, k, s, t))
        err = max(err, float(np.max(np.linalg.norm(surf.evaluate(s, t) - ref, axis=-1))))
    return err


@given(n=st.integers(3, 8), d=st.integers(1, 3), rational=st.booleans(), seed=st.integers(0, 2**32 - 1))
@test_settings(15)
def test_exact_pieces_equal_the_patch(n, d, rational, seed):
    rng = np.random.default_rng(seed)
    patch = random_patch(rng, n, d, rational)
    res = convert_spatch(patch)
    assert res.exact and len(res.surfaces) == n
    D = exact_bidegree(n, d)
    assert res.degree == ((d, d) if n == 4 else (D, D))
    size = np.abs(patch.control_points).max()
    assert _max_error_vs_patch(patch, res.surfaces, rng) <= EXACT_REL * size
    assert res.max_deviation <= EXACT_REL * size
    for surf in res.surfaces:
        assert surf.degree == res.degree
        if surf.weights is not None:
            assert np.all(surf.weights > 0)
    # n = 3, 4: W is constant, so a polynomial patch gives polynomial pieces
    if n in (3, 4) and not rational:
        assert all(s.weights is None for s in res.surfaces)


@pytest.mark.parametrize("n,d", [(5, 5), (6, 4), (7, 5), (9, 3)])
def test_exact_at_high_bidegree(n, d):
    """Bidegrees 15..25: still exact (to round-off) right up to OCC's limit."""
    rng = np.random.default_rng(n * 10 + d)
    patch = random_patch(rng, n, d, rational=(n % 2 == 0))
    res = convert_spatch(patch)
    assert res.exact and res.degree == (d * (n - 2),) * 2 and res.method == "exact"
    assert _max_error_vs_patch(patch, res.surfaces, rng, 200) <= EXACT_REL * np.abs(patch.control_points).max()


def test_piece_layout_and_orientation():
    for n in (3, 5, 8):
        q = piece_corners(n)
        v = np.array([[np.cos(2 * np.pi * k / n), np.sin(2 * np.pi * k / n)] for k in range(n)])
        assert_allclose(q[:, 0, 0], v, atol=1e-15)
        assert_allclose(q[:, 1, 1], 0.0, atol=0)
        assert_allclose(q[:, 1, 0], 0.5 * (v + np.roll(v, -1, 0)), atol=1e-15)
        assert_allclose(q[:, 0, 1], 0.5 * (v + np.roll(v, 1, 0)), atol=1e-15)
        # counter-clockwise corners: x_s × x_t > 0 everywhere on the piece
        rng = np.random.default_rng(n)
        patch = random_patch(rng, n, 2)
        res = convert_spatch(patch)
        s, t = rng.uniform(size=(2, 30))
        for k, surf in enumerate(res.surfaces):
            x = piece_domain_points(n, k, s, t)
            D = surf.derivatives(s, t, 1)
            ns = np.cross(D[:, 1, 0], D[:, 0, 1])
            ns /= np.linalg.norm(ns, axis=1, keepdims=True)
            assert np.all(np.einsum("ij,ij->i", ns, patch.normal(x)) > 1 - 1e-9)


def test_pieces_share_spokes_and_halves_of_boundary_curves():
    rng = np.random.default_rng(11)
    n, d = 6, 3
    patch = random_patch(rng, n, d, rational=True)
    surfaces = spatch_to_surfaces(patch)
    t = np.linspace(0, 1, 21)
    size = np.abs(patch.control_points).max()
    for k in range(n):
        nxt = surfaces[(k + 1) % n]
        # spoke m_k -> centre: s = 1 of piece k, t = 1 of piece k + 1
        assert_allclose(surfaces[k].evaluate(np.ones_like(t), t), nxt.evaluate(t, np.ones_like(t)),
                        rtol=0, atol=EXACT_REL * size)
        # t = 0 of piece k: the first half of boundary curve k; s = 0: the second half of side k - 1, reversed
        assert_allclose(surfaces[k].evaluate(t, np.zeros_like(t)), patch.boundary_curve(k).evaluate(t / 2),
                        rtol=0, atol=EXACT_REL * size)
        assert_allclose(surfaces[k].evaluate(np.zeros_like(t), t),
                        patch.boundary_curve((k - 1) % n).evaluate(1 - t / 2), rtol=0, atol=EXACT_REL * size)


def test_four_sided_reduction_is_exact_and_optional():
    rng = np.random.default_rng(12)
    patch = random_patch(rng, 4, 3)
    full = convert_spatch(patch, reduce=False)
    red = convert_spatch(patch)
    assert full.degree == (6, 6) and red.degree == (3, 3) and red.method == "exact-reduced"
    s, t = rng.uniform(size=(2, 100))
    for a, b in zip(full.surfaces, red.surfaces):
        assert_allclose(a.evaluate(s, t), b.evaluate(s, t), rtol=0, atol=1e-13)


def test_approximation_beyond_degree_25():
    """n = 9, d = 4: bidegree 28 > 25, approximated; the deviation reported is below tol and agrees
    with an independent measurement on random parameters (within the sampling: the reported one is
    a max over a 82 x 82 grid, so a random sample may exceed it slightly — by < 50 %, measured 5 %)."""
    rng = np.random.default_rng(13)
    patch = random_patch(rng, 9, 4)
    tol = 1e-5
    res = convert_spatch(patch, tol=tol)
    assert not res.exact and res.method == "lsq-fit" and res.degree == (tolerances.SPATCH_APPROX_DEGREE,) * 2
    assert res.max_deviation <= tol
    measured = _max_error_vs_patch(patch, res.surfaces, rng, 2000)
    assert measured <= 1.5 * tol
    assert measured <= 1.5 * res.max_deviation
    # neighbouring pieces share their spoke exactly (ends interpolated in the fit)
    t = np.linspace(0, 1, 15)
    for k in range(9):
        a = res.surfaces[k].evaluate(np.ones_like(t), t)
        b = res.surfaces[(k + 1) % 9].evaluate(t, np.ones_like(t))
        assert_allclose(a, b, rtol=0, atol=1e-12)


def test_approximation_that_cannot_reach_tol():
    patch = random_patch(np.random.default_rng(14), 9, 4)
    with tolerances.override(SPATCH_APPROX_MAX_POLES=8), pytest.raises(ToleranceError, match="could not be approximated"):
        convert_spatch(patch, tol=1e-12)


def test_invalid_arguments():
    patch = random_patch(np.random.default_rng(15), 5, 2)
    with pytest.raises(InvalidGeometryError, match="expected an SPatch"):
        convert_spatch("patch")
    for bad in (0.0, -1.0, np.nan, "x"):
        with pytest.raises(InvalidGeometryError, match="tol"):
            convert_spatch(patch, tol=bad)


def test_reduction_tolerance_is_read_at_call_time():
    """SPATCH_REDUCTION_TOL is read when converting: a zero tolerance accepts no reduction (round-off),
    so the 4-sided pieces keep the exact bidegree 2d."""
    patch = random_patch(np.random.default_rng(16), 4, 3)
    assert convert_spatch(patch).method == "exact-reduced" and convert_spatch(patch).degree == (3, 3)
    with tolerances.override(SPATCH_REDUCTION_TOL=0.0):
        res = convert_spatch(patch)
    assert res.method == "exact" and res.degree == (6, 6)
