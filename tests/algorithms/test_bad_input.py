"""Issue 17, API bad input: specific errors instead of silent nonsense or minutes of work."""

from __future__ import annotations

import time
import warnings

import numpy as np
import pytest

from occsurf.algorithms import BSplineCurve, BSplineSurface, tolerances
from occsurf.algorithms.errors import InvalidGeometryError, ParameterError
from occsurf.algorithms.hierarchical.curve import HierarchicalCurve
from occsurf.algorithms.hierarchical.surface import HierarchicalSurface
from occsurf.algorithms.topology.spatch import spatch_indices

from .test_spatch_convert import random_patch


def _curve() -> BSplineCurve:
    return BSplineCurve(3, [0, 0, 0, 0, 0.5, 1, 1, 1, 1], np.c_[np.linspace(0, 4, 5), np.sin(np.arange(5)), np.zeros(5)])


def _surface() -> BSplineSurface:
    return BSplineSurface((3, 3), ([0.0] * 4 + [0.5] + [1.0] * 4,) * 2, np.random.default_rng(0).random((5, 5, 3)))


@pytest.mark.parametrize("tol", [float("nan"), -1.0, float("inf"), "1e-3", True])
def test_remove_knot_refuses_a_tolerance_that_is_not_a_non_negative_number(tol):
    with pytest.raises(InvalidGeometryError, match="tol"):
        _curve().remove_knot(0.5, tol=tol)
    with pytest.raises(InvalidGeometryError, match="tol"):
        _surface().remove_knot(0.5, tol=tol, direction="u")
    assert _curve().remove_knot(0.5, tol=1.0).n_poles == 4  # a real tolerance still works


def test_override_refuses_nan_inf_negative_and_names_unknown_entries():
    for bad in (float("nan"), float("inf"), -1.0, -1):
        with pytest.raises(ValueError, match="KNOT_REMOVAL"), tolerances.override(KNOT_REMOVAL=bad):
            pass
    with pytest.raises(KeyError, match="known: .*KNOT_REMOVAL"), tolerances.override(KNOT_REMOVL=1e-3):
        pass
    with tolerances.override(KNOT_REMOVAL=0.0):  # exact removal only: a meaningful value
        assert tolerances.KNOT_REMOVAL == 0.0


def test_move_vertex_refuses_negative_indices():
    hs = HierarchicalSurface(_surface())
    with pytest.raises(InvalidGeometryError, match="negative"):
        hs.move_vertex(None, (-1, 0), (0.0, 0.0, 1.0))
    hc = HierarchicalCurve(_curve())
    with pytest.raises(InvalidGeometryError, match="negative"):
        hc.move_vertex(None, -1, (0.0, 0.0, 1.0))
    before = hs.base.control_points.copy()
    hs.move_vertex(None, (4, 0), (0.0, 0.0, 1.0))  # the last vertex, named as such
    assert np.array_equal(hs.base.control_points[4, 0], before[4, 0] + [0, 0, 1])


def test_split_within_the_knot_tolerance_of_an_end_is_refused():
    # A domain of twice the knot tolerance (1e-12): one of 1e-12 or less is itself refused (its ends are one knot).
    tiny = BSplineCurve(3, [0, 0, 0, 0, 2e-12, 2e-12, 2e-12, 2e-12], np.random.default_rng(1).random((4, 3)))
    with pytest.raises(ParameterError, match="param: 4e-13 is within the knot tolerance"):
        tiny.split(4e-13)
    s = BSplineSurface((1, 1), ([0, 0, 2e-12, 2e-12], [0, 0, 1, 1]), np.random.default_rng(2).random((2, 2, 3)))
    with pytest.raises(ParameterError, match="within the knot tolerance"):
        s.split(4e-13, direction="u")
    left, right = _curve().split(0.25)  # an ordinary split is unchanged
    assert left.n_poles >= 4 and right.n_poles >= 4


def test_reparametrize_refuses_overflowing_domains():
    with pytest.raises(ParameterError, match="overflows"):
        _curve().reparametrize(-1e308, 1e308)
    with pytest.raises(ParameterError, match="overflows"):
        _surface().reparametrize((-1e308, 1e308), (0, 1))
    with pytest.raises(ParameterError, match="too short"):
        _curve().reparametrize(1.0, 1.0 + 1e-16 * 2)  # the knot at the middle would merge with an end
    c = _curve().reparametrize(-1e300, 1e300)  # large but representable: fine
    assert np.all(np.isfinite(c.evaluate(np.linspace(-1e300, 1e300, 5))))
    # an unclamped curve: the domain's length is a double, the knots outside it scaled with it are
    # not; said as such, without a RuntimeWarning first (warnings are errors in this block)
    unclamped = BSplineCurve(2, [-2, -1, 0, 1, 2, 3], np.random.default_rng(0).random((3, 3)))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(ParameterError, match=r"\(0.0, 1e\+308\) is too long for doubles \(the knots outside it"):
            unclamped.reparametrize(0, 1e308)


def test_rational_overflow_is_refused():
    P = np.random.default_rng(3).random((4, 3)) * 1e150
    with pytest.raises(InvalidGeometryError, match="overflows"):
        BSplineCurve(3, [0, 0, 0, 0, 1, 1, 1, 1], P, weights=[1e200, 1, 1e200, 1])
    S = np.random.default_rng(3).random((2, 2, 3)) * 1e150
    with pytest.raises(InvalidGeometryError, match="overflows"):
        BSplineSurface((1, 1), ([0, 0, 1, 1],) * 2, S, weights=np.full((2, 2), 1e200))
    ok = BSplineCurve(3, [0, 0, 0, 0, 1, 1, 1, 1], P, weights=[1e100, 1, 1e100, 1])
    assert np.all(np.isfinite(ok.evaluate(np.linspace(0, 1, 7))))


def test_complex_control_points_are_refused():
    with pytest.raises(InvalidGeometryError, match="complex"):
        BSplineCurve(1, [0, 0, 1, 1], np.array([[1 + 1j, 0, 0], [2, 0, 0]]))
    with pytest.raises(InvalidGeometryError, match="complex"):
        BSplineCurve(1, [0, 0, 1, 1], [[1 + 0j, 0, 0], [2, 0, 0]])
    with pytest.raises(InvalidGeometryError, match="complex"):
        BSplineSurface((1, 1), ([0, 0, 1, 1],) * 2, np.zeros((2, 2, 3)) + 0j)


def test_huge_requests_are_refused_before_allocating():
    s, c = _surface(), _curve()
    big = np.linspace(0, 1, 100_000)
    for call, word in [(lambda: s.evaluate_grid(big, big), "evaluate_grid of 100000 x 100000"),
                       (lambda: s.derivatives_grid(big, big, 2), "derivatives_grid"),
                       (lambda: s.derivatives(0.5, 0.5, 100_000), "derivatives of order 100000"),
                       (lambda: c.derivatives(big, 10**9), "derivatives of order 1000000000"),
                       (lambda: spatch_indices(5, 200), r"spatch_indices\(5, 200\)"),
                       (lambda: random_patch(np.random.default_rng(1), 5, 3).derivatives([[0.1, 0.2]], 99),
                        "SPATCH_MAX_DERIVATIVE_ORDER")]:
        t0 = time.perf_counter()
        with pytest.raises(InvalidGeometryError, match=word):
            call()
        assert time.perf_counter() - t0 < 2.0
    assert spatch_indices(5, 3).shape == (35, 5)
    with tolerances.override(MAX_ARRAY_BYTES=1000):  # read at call time
        with pytest.raises(InvalidGeometryError, match="MAX_ARRAY_BYTES"):
            s.evaluate_grid(np.linspace(0, 1, 10), np.linspace(0, 1, 10))
    with tolerances.override(SPATCH_MAX_DERIVATIVE_ORDER=2):
        with pytest.raises(InvalidGeometryError, match="SPATCH_MAX_DERIVATIVE_ORDER = 2"):
            random_patch(np.random.default_rng(1), 5, 3).derivatives([[0.1, 0.2]], 3)
