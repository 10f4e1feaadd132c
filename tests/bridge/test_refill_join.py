"""Sides merged at flat corners are joined exactly (:func:`occsurf.bridge.modeling.refill_sides._joined`).

A hole side made of several tangent-continuous edges (a flat corner, merged into one side) used to be
one cubic fitted through them: bearing pair [9, 24] kept two such sides 4.1e-9 off the exact arcs
that OCC's filler reproduced to 2e-17. Joined, the side *is* its edges.
"""

from __future__ import annotations

import numpy as np
import pytest

from occsurf.algorithms.kernel.curve import BSplineCurve
from occsurf.bridge.modeling.refill_sides import _joined

W = np.sqrt(0.5)


def _quarter(k: int, radius: float = 2.0) -> BSplineCurve:
    """The exact rational quadratic quarter circle from angle k*90 to (k+1)*90 degrees."""
    a0, a1 = k * np.pi / 2, (k + 1) * np.pi / 2
    P = radius * np.array([[np.cos(a0), np.sin(a0), 0], [np.cos(a0) + np.cos(a1), np.sin(a0) + np.sin(a1), 0],
                           [np.cos(a1), np.sin(a1), 0]])
    return BSplineCurve(2, [0, 0, 0, 1, 1, 1], P, [1.0, W, 1.0])


def test_two_quarter_circles_join_into_an_exact_half_circle() -> None:
    c = _joined([_quarter(0), _quarter(1)], 1e-8)
    assert c.is_rational and c.domain == (0.0, 1.0)
    P = c.evaluate(np.linspace(0, 1, 1001))
    assert np.abs(np.linalg.norm(P[:, :2], axis=1) - 2.0).max() < 1e-14
    assert np.allclose(c.evaluate(0.5), [0, 2, 0], atol=1e-15)  # the joint at half the length


def test_a_line_and_a_tangent_arc_join_with_their_weights_scaled() -> None:
    """A polynomial line (raised to degree 2) and an arc whose weights are all scaled by 3 (the same
    curve): the joint pole gets one weight and both pieces stay exactly what they were."""
    line = BSplineCurve(1, [0, 0, 1, 1], [[2.0, -3, 0], [2.0, 0, 0]])
    arc = _quarter(0)
    arc = BSplineCurve(2, arc.knots, arc.control_points, 3 * arc.weights)
    c = _joined([line, arc], 1e-8)
    knots, counts = np.unique(c.knots, return_counts=True)
    joint = float(knots[counts == 2][0])  # the joint: a knot of multiplicity p = 2
    assert joint == pytest.approx(3.0 / (3.0 + np.pi), rel=1e-4)  # at its share of the arc length
    assert np.allclose(c.evaluate(joint), [2, 0, 0], atol=1e-15)
    L = c.evaluate(np.linspace(0, joint, 50))
    assert np.abs(L[:, 0] - 2).max() < 1e-15 and np.all(np.diff(L[:, 1]) > 0) and L[0, 1] == -3
    Q = c.evaluate(np.linspace(joint, 1, 200))
    assert np.abs(np.linalg.norm(Q[:, :2], axis=1) - 2.0).max() < 1e-14


def test_pieces_that_do_not_meet_are_not_joined() -> None:
    far = BSplineCurve(1, [0, 0, 1, 1], [[5.0, 5, 0], [6.0, 5, 0]])
    assert _joined([_quarter(0), far], 1e-8) is None


@pytest.mark.parametrize("n", [1, 3])
def test_one_or_several_pieces(n: int) -> None:
    c = _joined([_quarter(k) for k in range(n)], 1e-8)
    P = c.evaluate(np.linspace(0, 1, 301))
    assert np.abs(np.linalg.norm(P[:, :2], axis=1) - 2.0).max() < 1e-14
    assert np.allclose(c.evaluate(1.0), _quarter(n - 1).evaluate(1.0), atol=1e-15)
