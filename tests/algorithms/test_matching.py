"""Surface matching along an edge, G0-G3 (course ch. 3-4): closed forms, oracles, invariants, errors.

Oracles, independent of the code under test:
* tangent planes: ``BSplineSurface.normal`` on both sides of the edge, angle by ``atan2`` (the G1
  angle of a 3 deg kink must drop to 1e-10 deg: arccos would lose 1e-6 deg to round-off);
* curvature across the edge: the classical ``(L a^2 + 2 M a b + N b^2) / (E a^2 + 2 F a b + G b^2)``
  with ``(a, b)`` solving ``S_u a + S_v b = d`` for the direction ``d`` across the edge, not the
  height-function jets the matcher uses;
* the least change: ``scipy.linalg.pinv`` of the G1 conditions built here, at 60 points of the
  test's own choosing (the conditions are polynomial of degree 8 along a bicubic edge, so any 9 or
  more points give the same solution set, and the minimum-norm change is unique).

Tolerances: G0 1e-9 of the size and G1 0.01 deg are the issue's targets; the measured values are
1e-15 and 1e-13 deg, and the tests ask 1e-12 / 1e-10 where the target side lies in the surface's
spline space (exact matches). The pseudo-inverse comparison is to 1e-10 (two factorisations of
the same system).
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla
from hypothesis import given, settings
from hypothesis import strategies as st

from occsurf.algorithms.errors import InvalidGeometryError
from occsurf.algorithms.kernel.surface import BSplineSurface
from occsurf.algorithms.manipulation import ConstraintError, MatchTarget, match_surface
from occsurf.algorithms.manipulation.matching import _canonical, _restore

CUBIC = np.array([0, 0, 0, 0, 1, 1, 1, 1], float)


def _knots(n: int, p: int = 3) -> np.ndarray:
    return np.concatenate([np.zeros(p + 1), np.linspace(0, 1, n - p + 1)[1:-1], np.ones(p + 1)])


def _pair(kink_deg: float = 3.0, nu_s: int = 4, seed: int = 1, nv: int = 4):
    """Target T on x <= 0 and surface S on x >= 0 sharing the edge x = 0 (S's side u0 is T's side
    u0); S's second pole row turned by ``kink_deg`` about the edge."""
    rng = np.random.default_rng(seed)
    ys = np.linspace(0, 1, nv)
    h = 1.0 / 3
    T = np.zeros((4, nv, 3))
    S = np.zeros((nu_s, nv, 3))
    for i in range(4):
        T[i, :, 0], T[i, :, 1] = -i * h, ys
        T[i, :, 2] = 0.3 * np.sin(1.3 * T[i, :, 0] + 2.0 * ys) + 0.02 * rng.normal(size=nv)
    for i in range(nu_s):
        S[i, :, 0], S[i, :, 1] = i * h, ys
        S[i, :, 2] = 0.3 * np.sin(1.3 * S[i, :, 0] + 2.0 * ys) + 0.02 * rng.normal(size=nv)
    S[0] = T[0]
    S[1, :, 2] = T[0, :, 2] + (T[0, :, 2] - T[1, :, 2]) + h * np.tan(np.radians(kink_deg))
    return (BSplineSurface((3, 3), (CUBIC, _knots(nv)), T),
            BSplineSurface((3, 3), (_knots(nu_s), _knots(nv)), S))


def _angles(a: BSplineSurface, ua: float, b: BSplineSurface, ub: float, vs: np.ndarray) -> np.ndarray:
    na, nb = a.normal(np.full_like(vs, ua), vs), b.normal(np.full_like(vs, ub), vs)
    ang = np.degrees(np.arctan2(np.linalg.norm(np.cross(na, nb), axis=1), np.einsum("ij,ij->i", na, nb)))
    return np.minimum(ang, 180 - ang)


def _cross_curvature(s: BSplineSurface, u: np.ndarray, v: np.ndarray, d: np.ndarray, n: np.ndarray) -> np.ndarray:
    """Normal curvature of ``s`` in the tangent direction ``d`` with respect to the normal ``n``."""
    D = s.derivatives(u, v, 2)
    Su, Sv = D[:, 1, 0], D[:, 0, 1]
    E, F, G = (np.einsum("ij,ij->i", x, y) for x, y in ((Su, Su), (Su, Sv), (Sv, Sv)))
    L, M, N = (np.einsum("ij,ij->i", x, n) for x in (D[:, 2, 0], D[:, 1, 1], D[:, 0, 2]))
    A = np.stack([Su, Sv], axis=2)  # (m, 3, 2)
    ab = np.array([np.linalg.lstsq(A[k], d[k], rcond=None)[0] for k in range(len(u))])
    a, b = ab[:, 0], ab[:, 1]
    return (L * a * a + 2 * M * a * b + N * b * b) / (E * a * a + 2 * F * a * b + G * b * b)


def _g2_rel(T: BSplineSurface, S: BSplineSurface, vs: np.ndarray) -> np.ndarray:
    """Relative jump of the curvature across the edge x = 0 between T (side u0) and S (side u0)."""
    z = np.zeros_like(vs)
    nT = T.normal(z, vs)
    tau = T.derivatives(z, vs, 1)[:, 0, 1]
    d = np.cross(nT, tau)
    d /= np.linalg.norm(d, axis=1)[:, None]
    nS = S.normal(z, vs)
    nS *= np.sign(np.einsum("ij,ij->i", nS, nT))[:, None]
    kT, kS = _cross_curvature(T, z, vs, d, nT), _cross_curvature(S, z, vs, d, nS)
    return np.abs(kT - kS) / np.maximum(np.abs(kT), np.abs(kS))


VS = np.linspace(0, 1, 201)


def test_g1_closes_a_3_degree_kink_exactly():
    T, S = _pair(3.0)
    assert _angles(T, 0, S, 0, VS).max() > 2.9
    res = match_surface(S, T, "u0", "G1")
    assert res.met and res.knots_added == 0
    assert _angles(T, 0, res.surface, 0, VS).max() < 1e-10
    gap = np.linalg.norm(T.evaluate(0 * VS, VS) - res.surface.evaluate(0 * VS, VS), axis=1).max()
    assert gap <= 1e-12 * 2 and res.g0_max <= 1e-12
    assert res.g1_max_deg < 1e-10
    # only the second row moved (the first is already on the target; preserve_opposite='G1' holds rows 3, 4)
    dP = res.surface.control_points - S.control_points
    assert np.abs(dP[0]).max() < 1e-14 and np.abs(dP[2:]).max() == 0.0
    assert res.max_change > 0 and res.max_change <= res.max_pole_change + 1e-15


def test_g1_change_is_the_pseudo_inverse_solution():
    T, S = _pair(3.0, seed=4)
    res = match_surface(S, T, "u0", "G1")
    # the G1 conditions n_T(v) . S_u(0, v) = 0 at 60 points, on the change of row 1 (row 0 fixed by G0)
    vs = np.linspace(0, 1, 60)
    n = T.normal(np.zeros(60), vs)
    Nv = np.array([BSplineSurface((3, 3), (CUBIC, CUBIC), np.eye(16).reshape(4, 4, 16))
                   .derivatives(0.0, v, 1)[1, 0] for v in vs])  # (60, 16): dS_u/dP over the net
    cols = [4 + j for j in range(4)]  # row 1 of the flattened 4 x 4 net
    C = np.einsum("kc,ki->kic", n, Nv[:, cols]).reshape(60, 12)
    Su = S.derivatives(np.zeros(60), vs, 1)[:, 1, 0]
    d = -np.einsum("kc,kc->k", n, Su)
    dx = sla.pinv(C, rtol=1e-12) @ d
    got = (res.surface.control_points[1] - S.control_points[1]).ravel()
    np.testing.assert_allclose(got, dx, atol=1e-10 * np.abs(dx).max())


def test_g2_curvature_jump_below_one_percent_and_far_edge_kept():
    T, S = _pair(3.0, nu_s=7)
    # a third patch Q continuing S across its side u1 with C1 continuity
    P = S.control_points
    Q = np.zeros((4, 4, 3))
    Q[0] = P[-1]
    for i in range(1, 4):
        Q[i] = P[-1] + i * (P[-1] - P[-2])
    Q = BSplineSurface((3, 3), (CUBIC, CUBIC), Q)
    before = _angles(S, 1, Q, 0, VS)
    res = match_surface(S, T, "u0", "G2", preserve_opposite="G1")
    assert res.met and res.g2_max_rel <= 0.01
    assert _g2_rel(T, res.surface, VS).max() <= 0.01
    assert _angles(T, 0, res.surface, 0, VS).max() < 1e-10
    after = _angles(res.surface, 1, Q, 0, VS)
    np.testing.assert_allclose(after, before, atol=1e-6)


def test_g2_on_a_cubic_with_preserve_inserts_rows():
    T, S = _pair(3.0)  # 4 rows: G2 moves 3, preserve G1 holds 2 -> one knot across
    res = match_surface(S, T, "u0", "G2", preserve_opposite="G1")
    assert res.met and res.knots_added >= 1 and res.surface.n_poles[0] >= 5
    assert _g2_rel(T, res.surface, VS).max() <= 0.01
    with pytest.raises(ConstraintError, match="rows across the side"):
        match_surface(S, T, "u0", "G2", preserve_opposite="G1", refine=False)


def test_g3_on_cubic():
    T, S = _pair(2.0, nu_s=8)
    res = match_surface(S, T, "u0", "G3")
    assert res.met and res.g3_max_rel < 1e-6 and res.g2_max_rel < 1e-9


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 10_000), side_s=st.sampled_from(["u0", "u1", "v0", "v1"]),
       side_t=st.sampled_from(["u0", "u1", "v0", "v1"]), order=st.sampled_from(["G0", "G1", "G2"]),
       kink=st.floats(-8.0, 8.0), flip=st.booleans())
def test_match_any_sides(seed, side_s, side_t, order, kink, flip):
    """Random pairs presented with the matched sides anywhere (and the target's edge reversed):
    the tolerances hold by the oracles, and the opposite side's rows do not move."""
    T, S = _pair(kink, nu_s=7, seed=seed)
    Tr, Sr = _restore(T.reverse(direction="v") if flip else T, side_t), _restore(S, side_s)
    res = match_surface(Sr, Tr, side_s, order)
    assert res.met
    new = _canonical(res.surface, side_s)  # in S's own parametrisation again, as T is
    gap = np.linalg.norm(T.evaluate(0 * VS, VS) - new.evaluate(0 * VS, VS), axis=1).max()
    assert gap <= 1e-9 * 3
    if order != "G0":
        assert _angles(T, 0, new, 0, VS).max() <= 0.01
    if order == "G2":
        assert _g2_rel(T, new, VS).max() <= 0.01
    old = _canonical(Sr, side_s)
    assert np.array_equal(new.control_points[-2:], old.control_points[-2:])


def _cylinder(R: float, a0: float, a1: float, c=(0.0, 0.0)) -> BSplineSurface:
    am, h = 0.5 * (a0 + a1), 0.5 * (a1 - a0)
    P2 = np.array([[np.cos(a0), np.sin(a0)], [np.cos(am) / np.cos(h), np.sin(am) / np.cos(h)],
                   [np.cos(a1), np.sin(a1)]]) * R + np.asarray(c)
    P = np.zeros((3, 4, 3))
    P[..., 0], P[..., 2], P[..., 1] = P2[:, 0, None], P2[:, 1, None], np.linspace(0, 1, 4)[None]
    w = np.repeat(np.array([1.0, np.cos(h), 1.0])[:, None], 4, 1)
    return BSplineSurface((2, 3), ([0, 0, 0, 1, 1, 1], CUBIC), P, w)


def test_rational_g2_to_a_cylinder_keeps_the_weight_function():
    T = _cylinder(1.0, 0.0, np.pi / 2)
    a = np.radians(5)
    c = np.array([0.0, 1.0]) - 1.5 * np.array([np.cos(np.pi / 2 - a), np.sin(np.pi / 2 - a)])
    S = _cylinder(1.5, np.pi / 2 - a, np.pi / 2 - a + 0.8, c)
    res = match_surface(S, T, "u0", "G2")
    assert res.met
    new = res.surface
    # the weight function is S's (refined exactly), the curvature across the edge is the cylinder's 1/R
    extra = np.setdiff1d(new.knots[0], S.knots[0])
    np.testing.assert_allclose(new.weights, S.refine(extra, direction="u").weights, rtol=0, atol=1e-15)
    z = np.zeros_like(VS)
    nS = new.normal(z, VS)
    d = -new.derivatives(z, VS, 1)[:, 1, 0]
    d -= np.einsum("ij,ij->i", d, nS)[:, None] * nS
    k = _cross_curvature(new, z, VS, d, nS)
    assert np.allclose(np.abs(k), 1.0, rtol=0.01)


def test_match_target_samples_give_the_surface_result():
    T, S = _pair(3.0, nu_s=7, seed=7)
    vs = np.linspace(0, 1, 41)
    z = np.zeros_like(vs)
    pts, nrm = T.evaluate(z, vs), T.normal(z, vs)
    tau = T.derivatives(z, vs, 1)[:, 0, 1]
    b = np.cross(nrm, tau)
    b /= np.linalg.norm(b, axis=1)[:, None]
    k = _cross_curvature(T, z, vs, b, nrm)
    res = match_surface(S, MatchTarget(pts, nrm, k), "u0", "G2")
    assert res.met
    assert _angles(T, 0, res.surface, 0, VS).max() <= 0.01
    assert _g2_rel(T, res.surface, VS).max() <= 0.01
    # G1 is linear: the same least change as with the surface itself, to the samples' interpolation
    # error (1e-8 in the points, 1e-6 in the change measured). G2 is not: both meet it, by different
    # changes of the second row, so only the tolerances are compared there.
    one = match_surface(S, MatchTarget(pts, nrm, k), "u0", "G1").surface
    ref = match_surface(S, T, "u0", "G1").surface
    assert np.abs(one.control_points - ref.control_points).max() < 1e-3 * np.abs(ref.control_points - S.control_points).max()


def test_average_moves_both_and_meets():
    T, S = _pair(4.0, nu_s=7, seed=3)
    T7 = T.insert_knot(0.3, direction="u").insert_knot(0.6, direction="u").insert_knot(0.8, direction="u")
    one = match_surface(S, T7, "u0", "G1")
    res = match_surface(S, T7, "u0", "G1", average=True)
    assert res.met and isinstance(res.target, BSplineSurface)
    assert _angles(res.target, 0, res.surface, 0, VS).max() <= 0.01
    moved_t = np.abs(res.target.control_points - T7.control_points).max()
    moved_s = np.abs(res.surface.control_points - S.control_points).max()
    assert 0 < moved_s < np.abs(one.surface.control_points - S.control_points).max()
    assert moved_t > 0
    # max_change bounds both surfaces' changes, also where the target moves the more (T7 matched to
    # S: S, the stiffer, moves 3x as far), measured on a grid of our own
    g = np.linspace(0, 1, 41)
    back = match_surface(T7, S, "u0", "G1", average=True)
    for r, pairs in ((res, ((S, res.surface), (T7, res.target))), (back, ((T7, back.surface), (S, back.target)))):
        moves = [np.linalg.norm(b.evaluate_grid(g, g) - a.evaluate_grid(g, g), axis=-1).max() for a, b in pairs]
        assert max(moves) <= r.max_change * (1 + 1e-9) + 1e-15 and max(moves) >= 0.9 * r.max_change
        assert r.max_pole_change >= max(np.abs(b.control_points - a.control_points).max() for a, b in pairs
                                        if a.n_poles == b.n_poles) - 1e-15
    assert moves[1] > 2 * moves[0]  # the target moved the more


def test_bad_input_is_named():
    T, S = _pair()
    with pytest.raises(InvalidGeometryError, match="side"):
        match_surface(S, T, "w0")
    with pytest.raises(InvalidGeometryError, match="continuity"):
        match_surface(S, T, "u0", "C2")
    with pytest.raises(InvalidGeometryError, match="preserve_opposite"):
        match_surface(S, T, "u0", preserve_opposite="G4")
    with pytest.raises(InvalidGeometryError, match="tol_g1_deg"):
        match_surface(S, T, "u0", tol_g1_deg=-1)
    with pytest.raises(InvalidGeometryError, match="target"):
        match_surface(S, "T", "u0")  # type: ignore[arg-type]
    lin = BSplineSurface((1, 3), ([0, 0, 1, 1], CUBIC), S.control_points[:2])
    with pytest.raises(ConstraintError, match="degree >= 2"):
        match_surface(lin, T, "u0", "G2")
    pts = T.evaluate(np.zeros(5), np.linspace(0, 1, 5))
    nrm = T.normal(np.zeros(5), np.linspace(0, 1, 5))
    with pytest.raises(InvalidGeometryError, match="cross_curvatures"):
        match_surface(S, MatchTarget(pts, nrm), "u0", "G2")
    with pytest.raises(InvalidGeometryError, match="G3"):
        match_surface(S, MatchTarget(pts, nrm, np.zeros(5)), "u0", "G3")
    with pytest.raises(InvalidGeometryError, match="coincide"):
        MatchTarget(np.zeros((3, 3)), nrm[:3])


def test_max_poles_caps_the_refinement():
    """S has 4 poles along the side, the target 12: the match needs the target's 8 knots. With
    max_poles=12 it is the default's match to the bit; with 11 the refinement stops at 4 poles,
    where the coarse match folds back over the target (refused)."""
    T, S = _pair(3.0, nu_s=7, nv=12)
    S4 = BSplineSurface((3, 3), (S.knots[0], _knots(4)), S.evaluate_grid(np.linspace(0, 1, 7), np.linspace(0, 1, 4)))
    full = match_surface(S4, T, "u0", "G1")
    assert full.met and full.knots_added == 8 and full.surface.n_poles == (7, 12)
    capped = match_surface(S4, T, "u0", "G1", max_poles=12)
    assert np.array_equal(capped.surface.control_points, full.surface.control_points)
    with pytest.raises(ConstraintError, match="folds back"):
        match_surface(S4, T, "u0", "G1", max_poles=11)
    for bad in (0, -3, 2.5, True):
        with pytest.raises(InvalidGeometryError, match="max_poles"):
            match_surface(S4, T, "u0", "G1", max_poles=bad)


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 10_000), r=st.integers(0, 3), nv=st.integers(4, 9), kink=st.floats(-8.0, 8.0))
def test_equation_blocks_are_the_slices_of_the_whole_system_bit_for_bit(seed, r, nv, kink):
    """``_solve`` asks ``_equations`` for one order's rows and one pole row's columns (the rows in
    turn) or for orders 1..r and rows 1..r (the Gauss-Newton steps) instead of building the whole
    system and slicing it: the blocks must be those slices exactly, F and J alike."""
    from occsurf.algorithms.manipulation.match_solve import _cross_rows, _equations
    from occsurf.algorithms.manipulation.match_targets import SurfaceSide
    from occsurf.algorithms.manipulation.matching import _solve_params

    T, S = _pair(kink, nu_s=7, seed=seed, nv=nv)
    v = _solve_params(S)
    R = _cross_rows(S, v, r)
    tg = SurfaceSide(T).corresponding(S, v)
    x = np.random.default_rng(seed).normal(scale=1e-3, size=(r + 1) * nv * 3)
    Sj = np.einsum("jki,ic->jkc", R, S.control_points[: r + 1].reshape(-1, 3) + x.reshape(-1, 3))
    F, J = _equations(R, Sj, tg, r)
    m = v.shape[0]
    start = [0, 3 * m] + [3 * m + j * m for j in range(1, r + 1)]
    for lo in range(r + 1):
        for a, b in ((0, None), (lo * nv, (lo + 1) * nv), (lo * nv, None)):
            Fb, Jb = _equations(R, Sj, tg, r, lo, slice(a, b))
            cols = slice(3 * a, None if b is None else 3 * b)
            assert np.array_equal(Fb, F[start[lo]:]) and np.array_equal(Jb, J[start[lo]:, cols])
            assert Fb.tobytes() == F[start[lo]:].tobytes()  # signed zeros too
            assert Jb.tobytes() == np.ascontiguousarray(J[start[lo]:, cols]).tobytes()


@settings(max_examples=12, deadline=None)
@given(seed=st.integers(0, 10_000), order=st.sampled_from(["G2", "G3"]), kink=st.floats(-8.0, 8.0))
def test_kept_svds_give_the_same_match_bit_for_bit(seed, order, kink):
    """``_solve`` keeps the SVDs of G0's and of row 1's G1 matrices (independent of the poles) for
    its second pass of row-by-row solves: the matched surface is the one made with every SVD taken
    afresh, pole for pole (signed zeros too), with two SVDs fewer per solve of G2 or G3."""
    import occsurf.algorithms.manipulation.match_solve as M  # where _solve lives
    import occsurf.algorithms.manipulation.min_norm as MN

    T, S = _pair(kink, nu_s=8, seed=seed, nv=5)
    calls = []
    row_svd, plain = MN.row_svd, MN.robust_min_norm
    with pytest.MonkeyPatch.context() as mp:
        for module in (M, MN):  # _solve's own SVDs and those robust_min_norm takes afresh
            mp.setattr(module, "row_svd", lambda J: calls.append(J.shape) or row_svd(J))
        kept = match_surface(S, T, "u0", order)
        n_kept = len(calls)
        mp.setattr(M, "robust_min_norm", lambda J, rhs, svd=None: plain(J, rhs))  # every SVD afresh
        calls.clear()
        fresh = match_surface(S, T, "u0", order)
    assert kept.surface.control_points.tobytes() == fresh.surface.control_points.tobytes()
    assert n_kept <= len(calls) - 2


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 10_000), n=st.integers(32, 90), ratio=st.floats(2.0, 8.0), decades=st.floats(0.0, 16.0),
       k=st.sampled_from([1, 3]))
def test_row_svd_of_tall_matrices_through_qr_gives_the_plain_solution(seed, n, ratio, decades, k):
    """A tall ``J`` (at least twice as many rows as columns) is factored by QR first and ``U^T b``
    applied through the Householder reflectors (``RowSVD.project``): the singular values are those
    of the SVD of ``J`` itself, and the robust minimum-norm solution agrees with the one through the
    explicit ``U`` within 1e-10 of its norm, for conditioning from 1 to 1e-16 (round-off: both are
    backward stable; the rank cut-offs then decide alike). Rows of very different norms and a zero
    row are part of the draw, as the G1 and G2 conditions give them."""
    import occsurf.algorithms.manipulation.min_norm as M

    rng = np.random.default_rng(seed)
    m = int(ratio * n)
    J = rng.standard_normal((m, n)) @ np.diag(np.logspace(0.0, -decades, n)) @ rng.standard_normal((n, n))
    J *= np.logspace(-3, 3, m)[rng.permutation(m)][:, None]
    J[rng.integers(m)] = 0.0
    b = rng.standard_normal((m, k)) if k > 1 else rng.standard_normal(m)
    f = M.row_svd(J)
    assert f.U is None and f.qr is not None  # the QR path
    s = np.where(np.linalg.norm(J, axis=1) > 0, np.linalg.norm(J, axis=1), 1.0)
    U, sv, Vt = sla.svd(J / s[:, None], full_matrices=False, lapack_driver="gesdd")
    assert np.allclose(f.sv, sv, rtol=0, atol=1e-13 * sv[0])
    plain = M.RowSVD(s, sv, Vt, U=U)
    x_qr, x_plain = M.robust_min_norm(J, b, f), M.robust_min_norm(J, b, plain)
    assert np.linalg.norm(x_qr - x_plain) <= 1e-10 * max(np.linalg.norm(x_plain), 1e-300)
    assert np.array_equal(M.robust_min_norm(J, b), x_qr)  # the same factorisation when taken afresh


def test_row_svd_keeps_the_plain_svd_below_the_qr_shapes():
    """Near-square or narrow matrices (fewer than 32 columns) keep the plain SVD: faster there."""
    import occsurf.algorithms.manipulation.min_norm as M

    rng = np.random.default_rng(5)
    for shape in [(28, 24), (400, 31), (60, 45), (100, 60)]:
        f = M.row_svd(rng.standard_normal(shape))
        assert f.U is not None and f.qr is None, shape
    assert M.row_svd(rng.standard_normal((64, 32))).qr is not None


def test_row_svd_holds_one_form_of_u():
    """A ``RowSVD`` holds ``U`` or the QR path's ``qr``, ``tau`` and ``U_R``: neither, both, or a part
    of the QR path is refused by name (``project`` would otherwise answer from the wrong one)."""
    import occsurf.algorithms.manipulation.min_norm as M

    z = np.zeros(3)
    with pytest.raises(InvalidGeometryError, match="either U, or qr, tau and U_R"):
        M.RowSVD(z, z, np.eye(3))
    with pytest.raises(InvalidGeometryError, match="either U, or qr, tau and U_R"):
        M.RowSVD(z, z, np.eye(3), U=np.eye(3), qr=np.eye(3), tau=z, U_R=np.eye(3))
    with pytest.raises(InvalidGeometryError, match="either U, or qr, tau and U_R"):
        M.RowSVD(z, z, np.eye(3), qr=np.eye(3), tau=z)
    f = M.row_svd(np.random.default_rng(1).standard_normal((80, 33)))
    assert f != M.row_svd(np.random.default_rng(1).standard_normal((80, 33)))  # identity, not arrays compared
