"""The central split on a fillet strip that wraps half-way around an axis (issue 12; bearing faces [4, 166]).

Closed form: the hole is cut from the torus ``(RC + RT cos th) (cos ph, sin ph), RT sin th`` (RC = 1,
RT = 0.16: the bearing's fillet, tube radius 0.0026-0.0028 about a circle of radius 0.017, scaled),
``ph`` over 180 deg, ``th`` over 0..90 deg (a quarter round between a wall and a top face), its outer
arc cut into three sides at 32 and 46 deg from one end as the bearing's is (6 sides; four corners
within 46 deg of one end). Sides: :func:`fit_boundary` to 1e-9, fields :func:`side_from_normals` of
the torus normals. The distance of a point to the torus is ``| |(rho - RC, z)| - RT |``.

Measured: folds 75 (41 x 41 per patch), deviation from the torus 0.32 (the strip is 0.25 across).
Why: the harmonic layout (``nsided_centre.harmonic_layout``) is refused because three midpoint ribbons,
projected from its mean-plane picture into the wall's steep tangent plane, point along or out of
their side; the plain layout's centre (the harmonic centre) lies near the end with four corners,
and internal edge 0 runs from the other end straight across the half annulus. Turning those
ribbons into the hole (as ``_centre`` does for slivers) reduces the folds (75 -> 16 here, deviation
0.32 -> 0.21; with th over -10..80: 41 -> 0 folds, deviation 0.35 -> 0.33; the bearing pair: 73 -> 0
folds) but the fill still departs from the surface (the bearing: 6.0e-3 from the removed faces,
against 3.6e-4 for the wrapped plate that refill keeps today), so it was not committed. The strict
expected failure below fails the suite once the central split fills such a strip fold-free and near
the surface; refill should then keep it only if it is also as close as the wrapped plate.
"""

from __future__ import annotations

import numpy as np
import pytest

from occsurf.algorithms.topology.nsided import count_folds, fill_hole, measure_fill
from occsurf.algorithms.topology.nsided_sides import fit_boundary, side_from_normals

RC, RT = 1.0, 0.16


def _torus(ph, th):
    return np.stack([(RC + RT * np.cos(th)) * np.cos(ph), (RC + RT * np.cos(th)) * np.sin(ph), RT * np.sin(th)], -1)


def _normal(ph, th):
    return np.stack([np.cos(th) * np.cos(ph), np.cos(th) * np.sin(ph), np.sin(th)], -1)


def _torus_distance(P):
    return np.abs(np.hypot(np.hypot(P[:, 0], P[:, 1]) - RC, P[:, 2]) - RT)


def _strip(span: float = 180.0, th0: float = 0.0, th1: float = 90.0, cuts=(32.0, 46.0)):
    """The strip's sides in loop order (counter-clockwise in (ph, th): fields point out of the hole)."""
    p0, p1, a0, a1 = np.radians([90.0, 90.0 + span, th0, th1])
    corners = [(p0, a0)] + [(np.radians(90.0 + c), a0) for c in cuts] + [(p1, a0), (p1, a1), (p0, a1)]
    t = np.linspace(0.0, 1.0, 200)
    sides = []
    for i, a in enumerate(corners):
        b = corners[(i + 1) % len(corners)]
        pp = np.asarray(a) + (np.asarray(b) - np.asarray(a)) * t[:, None]
        curve, _ = fit_boundary(t, _torus(pp[:, 0], pp[:, 1]), 1e-9)
        sides.append(side_from_normals(curve, t, _normal(pp[:, 0], pp[:, 1])).side)
    return sides


def test_strip_sides_lie_on_the_torus():
    """The fixture itself: every side on the torus within 1e-7 (fit_boundary meets 1e-9 at its 200
    samples; between them the cubic is 4.9e-8 off, measured at 301 points), 1e5 below the shape bound."""
    for sd in _strip():
        P = sd.curve.evaluate(np.linspace(*sd.curve.domain, 301))
        assert _torus_distance(P).max() <= 1e-7


@pytest.mark.slow
@pytest.mark.xfail(strict=True, reason="central split on a strip wrapping 180 deg about an axis: folds (75) and "
                                       "departs 0.32 from the torus; refill fills such holes with the wrapped plate")
def test_half_turn_fillet_strip_is_filled_fold_free_near_the_torus():
    fill = fill_hole(_strip())
    q = measure_fill(fill, samples=51)
    # G1 and G0 by construction (round-off; as test_nsided_folds.py), so only the shape can fail
    assert q.internal_angle.max() <= 1e-6 and q.boundary_gap.max() <= 1e-7 * fill.size
    assert sum(count_folds(p) for p in fill.patches) == 0
    g = np.linspace(0.0, 1.0, 41)
    U, V = np.meshgrid(g, g, indexing="ij")
    P = np.concatenate([p.evaluate(U.ravel(), V.ravel()) for p in fill.patches])
    # 0.1 RT: the wrapped plate's own fill of the 120-deg strip is 0.016 = 0.1 RT off the torus
    assert _torus_distance(P).max() <= 0.1 * RT
