"""Tests of :func:`occsurf.algorithms.kernel.banded_lstsq.spline_lstsq` (band accumulation of the QR
factorisation, Lawson and Hanson's BNDACC, for the hole sides' fits).

Against the dense ``numpy.linalg.lstsq`` it replaced, on the same weighted problems: the
coefficients within 1e-9 of the largest (both are backward stable and these matrices have condition
numbers below ~1e4 even with the end weights of 1e4 that ``fit_boundary`` uses; measured 5.4e-13 on
the 115 fits of linkrods face 22's sides); closed form: a spline reproduces itself from its own
samples (to 1e-12); rank deficiency (a knot span without samples) falls back to ``lstsq``'s
minimum-norm answer, equal to it exactly.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from occsurf.algorithms.errors import InvalidGeometryError
from occsurf.algorithms.kernel.banded_lstsq import spline_lstsq
from occsurf.algorithms.kernel.basis import basis_matrix
from occsurf.algorithms.kernel.curve import BSplineCurve
from tests.algorithms.strategies import test_settings


def _dense(knots, p, s, Y, w):
    n = len(knots) - p - 1
    A = basis_matrix(np.asarray(knots, float), p, n, s)[0] * np.sqrt(w)[:, None]
    coef, *_ = np.linalg.lstsq(A, Y * np.sqrt(w)[:, None], rcond=None)
    return coef


@test_settings(60)
@given(p=st.integers(1, 5), spans=st.integers(1, 30), per_span=st.integers(2, 12), d=st.integers(1, 3),
       seed=st.integers(0, 2 ** 32 - 1), end_weight=st.sampled_from([1.0, 1e4]))
def test_agrees_with_the_dense_least_squares(p, spans, per_span, d, seed, end_weight) -> None:
    rng = np.random.default_rng(seed)
    inner = np.sort(rng.uniform(0.02, 0.98, spans - 1))
    inner = inner[np.r_[True, np.diff(inner) > 1e-3]] if inner.size else inner
    knots = np.r_[[0.0] * (p + 1), inner, [1.0] * (p + 1)]
    brk = np.r_[0.0, inner, 1.0]
    # at least p + 1 samples a span (Schoenberg-Whitney holds), in shuffled order
    s = np.concatenate([rng.uniform(a, b, per_span + p) for a, b in zip(brk[:-1], brk[1:])] + [[0.0, 1.0]])
    rng.shuffle(s)
    Y = rng.normal(size=(s.size, d)) * 10.0
    w = rng.uniform(0.5, 2.0, s.size)
    w[s == 0.0] = w[s == 1.0] = end_weight
    got, want = spline_lstsq(knots, p, s, Y, w), _dense(knots, p, s, Y, w)
    assert np.abs(got - want).max() <= 1e-9 * np.abs(want).max()


def test_a_spline_is_reproduced_from_its_samples() -> None:
    rng = np.random.default_rng(7)
    knots = np.r_[[0.0] * 4, np.linspace(0, 1, 60)[1:-1], [1.0] * 4]
    c = BSplineCurve(3, knots, rng.normal(size=(knots.size - 4, 3)))
    s = np.linspace(0, 1, 4000)
    coef = spline_lstsq(knots, 3, s, c.evaluate(s), np.ones_like(s))
    assert np.abs(coef - c.control_points).max() <= 1e-12 * np.abs(c.control_points).max()


def test_a_span_without_samples_falls_back_to_the_minimum_norm_solution() -> None:
    knots = np.r_[[0.0] * 4, np.linspace(0, 1, 11)[1:-1], [1.0] * 4]
    s = np.r_[np.linspace(0, 0.28, 30), np.linspace(0.72, 1, 30)]  # nothing in [0.3, 0.7]: a basis function unseen
    Y = np.sin(6 * s)[:, None]
    w = np.ones_like(s)
    np.testing.assert_array_equal(spline_lstsq(knots, 3, s, Y, w), _dense(knots, 3, s, Y, w))


def test_bad_input_is_refused() -> None:
    knots = np.r_[[0.0] * 4, [1.0] * 4]
    s = np.linspace(0, 1, 10)
    with pytest.raises(InvalidGeometryError, match="expected s"):
        spline_lstsq(knots, 3, s, np.zeros(10), np.ones(10))
    with pytest.raises(InvalidGeometryError, match="positive weights"):
        spline_lstsq(knots, 3, s, np.zeros((10, 1)), np.zeros(10))
