"""Fairing a region by the least thin-plate energy within a tolerance (issue 29, item 2).

Oracles: the course's closed forms (a plane and a cylinder patch are already fair: nothing moves
beyond round-off), invariants (held pole rows bit-identical, the deviation bound measured on a
grid 4x denser than the one the bound was searched on, the energy never rises, more tolerance never
gives a less fair surface), and the sign changes of the normal curvature along iso-lines counted
here directly from the surface's derivatives.
"""

from __future__ import annotations

import numpy as np
import pytest

from occsurf.algorithms.errors import InvalidGeometryError
from occsurf.algorithms.kernel.surface import BSplineSurface
from occsurf.algorithms.manipulation import ConstraintError
from occsurf.algorithms.manipulation.fairing import fair_surface


def _knots(n: int) -> np.ndarray:
    return np.concatenate([[0.0] * 4, np.linspace(0, 1, n - 2)[1:-1], [1.0] * 4])


def _rippled(n: int = 14, amp: float = 0.004) -> BSplineSurface:
    """A bent sheet ``z = 0.3 x^2`` with a ripple along x that vanishes at the boundary."""
    x = np.linspace(0, 1, n)
    P = np.zeros((n, n, 3))
    P[..., 0], P[..., 1] = x[:, None], x[None, :]
    env = (np.sin(np.pi * P[..., 0]) * np.sin(np.pi * P[..., 1])) ** 2
    P[..., 2] = 0.3 * P[..., 0] ** 2 + amp * np.sin(25 * P[..., 0]) * env
    return BSplineSurface((3, 3), (_knots(n), _knots(n)), P)


def _u_sign_changes(s: BSplineSurface, m: int = 64) -> np.ndarray:
    """Sign changes of the normal curvature along each u-line (|k| above 1e-3)."""
    t = np.linspace(0, 1, m)
    D = s.derivatives_grid(t, t, 2)
    n = np.cross(D[..., 1, 0, :], D[..., 0, 1, :])
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    k = np.einsum("...i,...i", D[..., 2, 0, :], n) / np.einsum("...i,...i", D[..., 1, 0, :], D[..., 1, 0, :])
    sg = np.where(np.abs(k) > 1e-3, np.sign(k), 0.0).T  # rows: u-lines (fixed v)
    out = []
    for row in sg:
        row = row[row != 0]
        out.append(int(np.sum(row[1:] != row[:-1])))
    return np.array(out)


def test_ripple_removed_within_tolerance():
    S = _rippled()
    assert _u_sign_changes(S).max() >= 4
    r = fair_surface(S, tol=0.01)
    assert r.max_deviation <= 0.01
    t = np.linspace(0, 1, 257)
    dev = np.linalg.norm(r.surface.evaluate_grid(t, t) - S.evaluate_grid(t, t), axis=-1).max()
    assert dev <= 0.01 * 1.01  # the bound holds between the search grid's points too (1 % slack)
    assert _u_sign_changes(r.surface).max() == 0
    assert r.energy_after < 0.75 * r.energy_before
    # hold='G1': the two outermost pole rows on every side are untouched
    P, Q = S.control_points, r.surface.control_points
    for sl in (np.s_[:2], np.s_[-2:], np.s_[:, :2], np.s_[:, -2:]):
        assert np.array_equal(P[sl], Q[sl])
    assert r.surface.knots[0].tolist() == S.knots[0].tolist()


def test_more_tolerance_is_never_less_fair():
    S = _rippled()
    e = [fair_surface(S, tol=t).energy_after for t in (0.0005, 0.002, 0.008)]
    assert e[0] >= e[1] >= e[2]


@pytest.mark.parametrize("kind", ["plane", "cylinder"])
def test_fair_surfaces_stay(kind: str):
    n = 8
    x = np.linspace(0, 1, n)
    P = np.zeros((n, n, 3))
    P[..., 0], P[..., 1] = x[:, None], x[None, :]
    if kind == "cylinder":  # z = sqrt(4 - (x-0.5)^2) sampled at the poles: smooth, one-signed curvature
        P[..., 2] = np.sqrt(4 - (P[..., 0] - 0.5) ** 2)
    S = BSplineSurface((3, 3), (_knots(n), _knots(n)), P)
    r = fair_surface(S, tol=1e-3)
    assert r.wiggles_before == 0 and r.wiggles_after == 0 and r.met
    if kind == "plane":
        assert r.max_deviation < 1e-12
    assert r.energy_after <= r.energy_before * (1 + 1e-9)


def test_region_and_errors():
    S = _rippled()
    r = fair_surface(S, ((0.2, 0.8), (0.2, 0.8)), tol=0.01)
    P, Q = S.control_points, r.surface.control_points
    moved = np.argwhere(np.any(P != Q, axis=-1))
    assert moved.size == 0 or (moved.min() >= 3 and moved.max() <= 10)  # only poles whose support is in the box
    assert r.wiggles_after <= r.wiggles_before and r.max_deviation <= 0.01
    with pytest.raises(ConstraintError, match="narrower"):
        fair_surface(S, ((0.45, 0.5), (0.45, 0.5)), tol=0.01)
    with pytest.raises(InvalidGeometryError, match="hold"):
        fair_surface(S, tol=0.01, hold="G5")
    with pytest.raises(InvalidGeometryError, match="region"):
        fair_surface(S, ((0.5, 0.2), (0, 1)), tol=0.01)
    with pytest.raises(InvalidGeometryError, match="tol"):
        fair_surface(S, tol=-1)
