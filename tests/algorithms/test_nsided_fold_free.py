"""The central split given up at its first fold (:func:`fold_free_fill`) and the fairing factors one
hole's layouts share (:class:`FairSystems`), both against the full construction (:func:`fill_hole`).

Holes: planar crescents (an arc of radius 2 over ``angle`` degrees, an inner arc of radius ``r0``
back, two radial lines; in-plane cross fields, so the exact fill is the plane). Thin and long
ones fold in both layouts of the central split (58 to 300 folded grid pairs at r0 = 1.8), wide
ones do not (120 and 180 degrees at r0 = 1.5): both answers are exercised.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import occsurf.algorithms.topology.nsided_patches as patches_mod
from occsurf.algorithms.kernel.curve import BSplineCurve
from occsurf.algorithms.topology.nsided import HoleSide, fill_hole, fold_free_fill
from occsurf.algorithms.topology.nsided_patches import FairSystems, _fair_interior
from occsurf.algorithms.topology.nsided_sides import fit_boundary, side_from_normals


def _line(a, b) -> BSplineCurve:
    return BSplineCurve(1, [0, 0, 1, 1], np.array([a, b], float))


def _arc(r: float, a0: float, a1: float) -> BSplineCurve:
    t = np.linspace(0.0, 1.0, 200)
    a = a0 + (a1 - a0) * t
    return fit_boundary(t, np.c_[r * np.cos(a), r * np.sin(a), 0.0 * a], 1e-9)[0]


def _planar(curve: BSplineCurve) -> HoleSide:
    s = np.linspace(*curve.domain, 64)
    return side_from_normals(curve, s, np.tile([0.0, 0.0, 1.0], (64, 1))).side


def _crescent(angle: float, r0: float) -> list[HoleSide]:
    a = np.radians(angle)

    def p(r: float, t: float) -> tuple[float, float, float]:
        return (r * np.cos(t), r * np.sin(t), 0.0)
    return [_planar(c) for c in (_arc(2.0, 0.0, a), _line(p(2.0, a), p(r0, a)), _arc(r0, a, 0.0),
                                 _line(p(r0, 0.0), p(2.0, 0.0)))]


def _same(a, b) -> bool:
    return len(a.patches) == len(b.patches) and all(
        np.array_equal(p.control_points, q.control_points) and all(np.array_equal(u, v) for u, v in zip(p.knots, q.knots))
        for p, q in zip(a.patches, b.patches))


@pytest.mark.parametrize("angle, r0, folds", [(120, 1.5, False), (180, 1.5, False), (120, 1.8, True), (300, 1.8, True)])
def test_fold_free_fill_is_fill_hole_or_none_where_that_folds(angle, r0, folds) -> None:
    sides = _crescent(angle, r0)
    full = fill_hole(sides)
    got = fold_free_fill(sides)
    assert (full.folds > 0) == folds
    if folds:
        assert got is None
    else:
        assert got is not None and got.folds == 0 and _same(got, full)
        assert np.array_equal(got.center, full.center) and np.array_equal(got.split, full.split)


@settings(max_examples=5, deadline=None)
@given(angle=st.floats(100.0, 320.0), r0=st.floats(1.3, 1.85))
def test_fold_free_fill_agrees_with_fill_hole_on_crescents(angle, r0) -> None:
    sides = _crescent(angle, r0)
    full = fill_hole(sides)
    got = fold_free_fill(sides)
    if full.folds:
        assert got is None
    else:
        assert got is not None and _same(got, full)


def test_the_loop_picture_is_made_only_for_a_hole_that_may_not_be_convex(monkeypatch: pytest.MonkeyPatch) -> None:
    """The loop's harmonic picture (``harmonic_boundary``) is made once for a crescent (the centre
    and, where the plain layout folds, the harmonic layout share it) and never for the convex ring
    holes, whose centre is the midpoints' mean either way."""
    from occsurf.algorithms.topology import nsided
    from occsurf.examples.hole_models import ring_model

    made = []
    real = nsided.harmonic_boundary
    monkeypatch.setattr(nsided, "harmonic_boundary", lambda *a, **k: made.append(1) or real(*a, **k))
    for n in (3, 5):
        fill_hole(ring_model(n).sides)
    assert made == []
    fill_hole(_crescent(300, 1.8))  # folds in the plain layout: the harmonic one is tried too
    assert made == [1]


def test_fold_free_fill_raises_what_fill_hole_raises() -> None:
    pts = [(0, 0, 0), (4, 0, 0), (4, 1, 0), (1, 1, 0), (1, 4, 0), (0, 4, 0)]  # a reflex corner
    sides = [_planar(_line(pts[i], pts[(i + 1) % 6])) for i in range(6)]
    with pytest.raises(Exception) as full:
        fill_hole(sides)
    with pytest.raises(type(full.value), match="reflex corner"):
        fold_free_fill(sides)


def _system(nu: int = 40, nv: int = 36):
    rng = np.random.default_rng(3)
    degree = (4, 5)
    knots = tuple(np.r_[[0.0] * (p + 1), np.sort(rng.uniform(0.05, 0.95, n - p - 1)), [1.0] * (p + 1)]
                  for n, p in zip((nu, nv), degree))
    free = np.zeros((nu, nv), bool)
    free[2:-2, 2:-2] = True  # as the corner patches fix two rows on every edge
    H = rng.standard_normal((nu, nv, 3))
    H[free] = np.nan
    return H, free, degree, knots


def test_fair_systems_give_the_same_poles_and_factor_once(monkeypatch) -> None:
    H, free, degree, knots = _system()
    assert free.sum() > 1024  # past the process-wide cache of small systems
    alone = _fair_interior(H, free, degree, knots)
    calls = []
    real = patches_mod._fair_system
    monkeypatch.setattr(patches_mod, "_fair_system", lambda *a: calls.append(1) or real(*a))
    systems = FairSystems()
    H2 = H.copy()
    H2[~free] += 1.0  # the other layout: other fixed poles, the same system
    first = _fair_interior(H, free, degree, knots, systems)
    second = _fair_interior(H2, free, degree, knots, systems)
    assert np.array_equal(first, alone)
    assert np.array_equal(second, _fair_interior(H2, free, degree, knots))
    assert len(calls) == 1 + 1 and len(systems) == 1 and systems.entries > 0
    # past the budget nothing is kept, and every patch is factored alone
    none = FairSystems(budget=0)
    calls.clear()
    assert np.array_equal(_fair_interior(H, free, degree, knots, none), alone)
    assert np.array_equal(_fair_interior(H, free, degree, knots, none), alone)
    assert len(calls) == 2 and len(none) == 0 and none.entries == 0
