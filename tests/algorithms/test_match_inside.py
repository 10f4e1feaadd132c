"""``match_along`` (:mod:`occsurf.algorithms.manipulation.match_inside`): G0 / G1 along a curve inside a surface (a face trimmed across its surface).

Oracles: the surface's own normals and points evaluated afresh along the curve (dense, not the
match's samples), the pseudo-inverse of the conditions' matrix built column by column from
evaluations (the surface is linear in its poles), the support of the B-spline basis (poles whose
functions miss the curve do not move), and the rational weights.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from occsurf.algorithms.errors import InvalidGeometryError, ParameterError
from occsurf.algorithms.kernel.surface import BSplineSurface
from occsurf.algorithms.manipulation import MatchTarget, match_along


def _knots(n: int, p: int = 3) -> np.ndarray:
    return np.concatenate([np.zeros(p + 1), np.linspace(0, 1, n - p + 1)[1:-1], np.ones(p + 1)])


def _surface(n: int = 8, seed: int = 0, rational: bool = False) -> BSplineSurface:
    g = np.linspace(0, 1, n)
    X, Y = np.meshgrid(g, g, indexing="ij")
    rng = np.random.default_rng(seed)
    P = np.stack([X, Y, 0.2 * np.sin(2 * X + Y) + 0.01 * rng.normal(size=X.shape)], -1)
    w = 1.0 + 0.3 * rng.random((n, n)) if rational else None
    return BSplineSurface((3, 3), (_knots(n), _knots(n)), P, w)


def _curve(m: int, a: float = 0.1, b: float = 0.3, bend: float = 0.4) -> np.ndarray:
    t = np.linspace(0, 1, m)
    return np.stack([a + 0.8 * t, b + bend * t ** 2], 1)


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _tilted_target(S: BSplineSurface, uv: np.ndarray, deg: float, lift: float = 0.0) -> MatchTarget:
    """The surface's own points along the curve (raised by ``lift`` along the normal) and its
    normals turned by ``deg`` about the curve's tangent: a kink of ``deg`` degrees along the curve."""
    D = S.derivatives(uv[:, 0], uv[:, 1], 1)
    n = _unit(np.cross(D[:, 1, 0], D[:, 0, 1]))
    T = _unit(np.gradient(D[:, 0, 0], axis=0))
    th = np.radians(deg)
    N = n * np.cos(th) + np.cross(T, n) * np.sin(th) + T * np.einsum("ij,ij->i", T, n)[:, None] * (1 - np.cos(th))
    return MatchTarget(D[:, 0, 0] + lift * n, N)


def _angles(S: BSplineSurface, uv: np.ndarray, N: np.ndarray) -> np.ndarray:
    D = S.derivatives(uv[:, 0], uv[:, 1], 1)
    n = _unit(np.cross(D[:, 1, 0], D[:, 0, 1]))
    return np.degrees(np.arctan2(np.linalg.norm(np.cross(n, N), axis=1), np.abs(np.einsum("ij,ij->i", n, N))))


def _untouched(S: BSplineSurface, uv: np.ndarray) -> np.ndarray:
    """Mask of the poles whose basis functions vanish at every ``uv`` (refined surface ``S``)."""
    (p, q), (U, V), (nu, nv) = S.degree, S.knots, S.n_poles
    from occsurf.algorithms.kernel.basis import find_span

    su, sv = find_span(U, p, nu, uv[:, 0]), find_span(V, q, nv, uv[:, 1])
    hit = np.zeros((nu, nv), bool)
    for a, b in zip(su, sv):
        hit[a - p: a + 1, b - q: b + 1] = True
    return ~hit


def test_g1_closes_a_3_degree_kink_along_a_curve_across_the_surface():
    S = _surface()
    uv = _curve(161)
    tg = _tilted_target(S, uv, 3.0)
    res = match_along(S, tg, uv, "G1", tol_g0=1e-6, tol_g1_deg=0.01)
    assert res.met and res.g1_max_deg <= 0.01 and res.g0_max <= 1e-6
    # the oracle: the new surface evaluated afresh at the samples
    assert _angles(res.surface, uv, tg.normals).max() <= 0.01
    assert np.linalg.norm(res.surface.evaluate(uv[:, 0], uv[:, 1]) - tg.points, axis=1).max() <= 1e-6
    # before: 3 deg everywhere along the curve
    assert _angles(S, uv, tg.normals).min() > 2.99
    # poles whose functions miss the curve stay where they were, exactly (on the refined net)
    ref = res.surface
    before = S.refine(np.setdiff1d(ref.knots[0], S.knots[0]), direction="u") if res.knots_added else S
    if res.knots_added:
        kv = np.setdiff1d(ref.knots[1], S.knots[1])
        before = before.refine(kv, direction="v") if kv.size else before
    assert before.n_poles == ref.n_poles
    far = _untouched(ref, uv)
    assert far.any() and np.array_equal(ref.control_points[far], before.control_points[far])
    assert np.isnan(res.g2_max_rel) and res.max_change > 0


def test_g0_moves_the_surface_onto_a_lifted_curve_and_the_change_is_the_pseudo_inverse_solution():
    """Few samples, no refinement: the conditions are consistent, and the change is their
    minimum-norm solution, which the pseudo-inverse of the matrix built from evaluations gives."""
    S = _surface(seed=3)
    uv = _curve(6)
    tg = _tilted_target(S, uv, 0.0, lift=1e-3)
    res = match_along(S, tg, uv, "G0", refine=False)
    assert res.met and res.g0_max <= 1e-12 and res.knots_added == 0
    # the conditions' matrix, column by column: the surface is linear in its poles
    nu, nv = S.n_poles
    cols = []
    for k in range(nu * nv):
        P = np.zeros((nu * nv, 3))
        P[k, 0] = 1.0
        E = BSplineSurface((3, 3), S.knots, P.reshape(nu, nv, 3)).evaluate(uv[:, 0], uv[:, 1])[:, 0]
        cols.append(E)
    A = np.array(cols).T  # (m, n_poles): the same for each coordinate
    dP = np.linalg.pinv(A) @ (tg.points - S.evaluate(uv[:, 0], uv[:, 1]))
    got = (res.surface.control_points - S.control_points).reshape(-1, 3)
    assert np.abs(got - dP).max() <= 1e-10 * max(1e-3, np.abs(dP).max())


def test_rational_surface_keeps_its_weights():
    S = _surface(rational=True, seed=5)
    uv = _curve(121, a=0.15, b=0.2)
    tg = _tilted_target(S, uv, 2.0)
    res = match_along(S, tg, uv, "G1", tol_g0=1e-6)
    assert res.met and _angles(res.surface, uv, tg.normals).max() <= 0.01
    # knot insertion keeps the weight function: compare it at points, not the weights themselves
    u = np.linspace(0, 1, 13)
    U, V = np.meshgrid(u, u, indexing="ij")
    one = BSplineSurface(S.degree, S.knots, np.ones(S.control_points.shape), S.weights)
    one2 = BSplineSurface(res.surface.degree, res.surface.knots, np.ones(res.surface.control_points.shape),
                          res.surface.weights)
    assert res.surface.weights is not None
    assert np.allclose(one.evaluate(U.ravel(), V.ravel()), one2.evaluate(U.ravel(), V.ravel()), atol=1e-14)


@settings(max_examples=15, deadline=None)
@given(seed=st.integers(0, 1000), deg=st.floats(0.3, 4.0), a=st.floats(0.05, 0.2), b=st.floats(0.1, 0.5),
       bend=st.floats(-0.08, 0.4))
def test_random_curves_and_kinks_are_matched_and_far_poles_kept(seed, deg, a, b, bend):
    S = _surface(seed=seed)
    uv = _curve(121, a, b, bend)
    tg = _tilted_target(S, uv, deg)
    res = match_along(S, tg, uv, "G1", tol_g0=1e-6, tol_g1_deg=0.01)
    assert res.met
    assert _angles(res.surface, uv, tg.normals).max() <= 0.01
    assert np.linalg.norm(res.surface.evaluate(uv[:, 0], uv[:, 1]) - tg.points, axis=1).max() <= 1e-6


def test_bad_input_is_named():
    S = _surface()
    uv = _curve(11)
    tg = _tilted_target(S, uv, 1.0)
    with pytest.raises(InvalidGeometryError, match="G2 needs it along a side|along a curve inside the surface"):
        match_along(S, tg, uv, "G2")
    with pytest.raises(InvalidGeometryError, match=r"uv: expected shape \(11, 2\)"):
        match_along(S, tg, uv[:5], "G1")
    with pytest.raises(ParameterError, match="outside the domain"):
        match_along(S, tg, uv + 2.0, "G1")
    with pytest.raises(InvalidGeometryError, match="continuity"):
        match_along(S, tg, uv, "C1")
