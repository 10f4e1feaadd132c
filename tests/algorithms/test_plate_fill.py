"""Tests of the trimmed plate fill (algorithms/topology/plate_fill.py, course §8-3, issue 12): the
holes the central split refuses (reflex corners) or folds on (long curved holes).

Closed forms. A hole cut from a plane (an L with a reflex corner, a 120 deg annular sector bounded by
exact rational arcs) is refilled by that plane: the height field is h = 0 to round-off (measured
|h| <= 1e-13 of the size, the plane's frame being computed from ~2000 boundary samples; bound
1e-12), and the p-curves are exact (the sides projected, mapped back through the surface: measured
4e-16 of the size, bound 1e-12). A hole with a reflex corner cut from
a sphere (R = 2, an L of width 2h rad, sides great-circle arcs) and from a torus (3/1, an L of
width h rad in (theta, phi), sides fitted to 1e-8) is refilled by a different G1 surface with the
same boundary data; its distance from the original inside the hole shrinks with the hole. Measured
sphere h = 0.4, 0.2, 0.1: 6.2e-4, 1.4e-4, 4.2e-5; torus h = 0.8, 0.4, 0.2: 5.2e-3, 6.9e-4, 1.2e-4
(the fit stops as soon as both targets are met, so these are set by the targets, not round-off).
Bounds 1.5x those and a decrease >= 2.5x per halving (a wrong normal or orientation gives O(1)
deviations and no convergence).

Tolerances. G0 and G1 are the fit's targets (FILL_FIT_G0 of the loop's diameter, FILL_FIT_ANGLE),
checked at the fit's samples and between them by fill_plate itself (``met``) and here, independently,
at 201 points per side against the side curve (G0) and the closed-form normals (G1: the target plus
the side_from_normals fields' own FILL_FIT_ANGLE, since the plate fits those fields, not the exact
normals). Invariance: a rigid motion and scale of the input moves the fill with it (same knots, same
samples, same linear system up to the frame): measured 1e-12 of the size at interior points,
bound 1e-9.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from occsurf.algorithms import tolerances
from occsurf.algorithms.errors import InvalidGeometryError
from occsurf.algorithms.kernel.curve import BSplineCurve
from occsurf.algorithms.topology.nsided import HoleSide, count_folds
from occsurf.algorithms.topology.nsided_sides import fit_boundary, side_from_normals
from occsurf.algorithms.topology.plate_fill import PlateFill, fill_plate
from tests.algorithms.strategies import test_settings

R = 2.0
RT, RR = 3.0, 1.0
L_SHAPE = np.array([[0, 0], [2, 0], [2, 1], [1, 1], [1, 2], [0, 2]], float) - 0.8  # reflex corner at (1, 1)


def _line(a, b) -> BSplineCurve:
    return BSplineCurve(1, [0, 0, 1, 1], np.array([a, b], float))


def _const(x) -> BSplineCurve:
    return BSplineCurve(1, [0, 0, 1, 1], np.array([x, x], float))


def _plane_l(frame: np.ndarray, origin: np.ndarray, scale: float = 1.0) -> list[HoleSide]:
    """The L in the plane spanned by frame[0], frame[1]; cross fields in-plane, pointing out."""
    P = origin + scale * (L_SHAPE[:, :1] * frame[0] + L_SHAPE[:, 1:] * frame[1])
    sides = []
    for i in range(6):
        a, b = P[i], P[(i + 1) % 6]
        out = np.cross(b - a, frame[2])
        sides.append(HoleSide(_line(a, b), _const(out / np.linalg.norm(out))))
    return sides


def _arc(a, b, radius: float = R) -> BSplineCurve:
    a, b = np.asarray(a, float) / np.linalg.norm(a), np.asarray(b, float) / np.linalg.norm(b)
    half = np.arccos(np.clip(a @ b, -1, 1)) / 2
    m = (a + b) / np.linalg.norm(a + b) / np.cos(half)
    return BSplineCurve(2, [0, 0, 0, 1, 1, 1], radius * np.array([a, m, b]), np.array([1.0, np.cos(half), 1.0]))


def _sphere_l(h: float) -> list[HoleSide]:
    corners = [(h * x, h * y, 1.0) for x, y in L_SHAPE]  # counter-clockwise about +z
    sides = []
    for i in range(6):
        c = _arc(corners[i], corners[(i + 1) % 6])
        s = np.linspace(0, 1, 60)
        sides.append(side_from_normals(c, s, c.evaluate(s) / R).side)
    return sides


def _torus(th, ph):
    return np.stack([(RT + RR * np.cos(ph)) * np.cos(th), (RT + RR * np.cos(ph)) * np.sin(th), RR * np.sin(ph)], -1)


def _torus_normal(th, ph):
    return np.stack([np.cos(ph) * np.cos(th), np.cos(ph) * np.sin(th), np.sin(ph)], -1)


def _torus_point_normal(P):
    th = np.arctan2(P[:, 1], P[:, 0])
    return _torus_normal(th, np.arctan2(P[:, 2], np.hypot(P[:, 0], P[:, 1]) - RT))


def _torus_l(h: float) -> list[HoleSide]:
    c = L_SHAPE * h / 2
    t = np.linspace(0, 1, 200)
    sides = []
    for i in range(6):
        pp = c[i] + (c[(i + 1) % 6] - c[i]) * t[:, None]
        curve, gap = fit_boundary(t, _torus(pp[:, 0], pp[:, 1]), 1e-8)
        assert gap <= 1e-8
        sides.append(side_from_normals(curve, t, _torus_normal(pp[:, 0], pp[:, 1])).side)
    return sides


def _inside_points(fill: PlateFill, n: int = 60) -> np.ndarray:
    (u0, u1), (v0, v1) = fill.surface.domain
    U, V = np.meshgrid(np.linspace(u0, u1, n), np.linspace(v0, v1, n), indexing="ij")
    inside = fill.trimmed.contains(U.ravel(), V.ravel())
    assert inside.sum() > n  # the hole covers part of the box
    return fill.surface.evaluate(U.ravel()[inside], V.ravel()[inside])


def _check_boundary(fill: PlateFill, normal_at, field_tol: float) -> None:
    """G0 to each side and G1 to the closed-form normals at 201 points per side, independently of
    fill_plate's own measurement; the located parameters are the p-curve's."""
    for i, side in enumerate(fill.sides):
        t = np.linspace(*side.curve.domain, 201)
        P = side.curve.evaluate(t)
        u, v = fill.locate(i, P)
        D = fill.surface.derivatives(u, v, 1)
        assert np.linalg.norm(D[:, 0, 0] - P, axis=1).max() <= fill.g0_tol
        if normal_at is not None and fill.g1[i]:
            n = np.cross(D[:, 1, 0], D[:, 0, 1])
            ex = normal_at(P)
            c = np.abs(np.einsum("ij,ij->i", n / np.linalg.norm(n, axis=1, keepdims=True), ex))
            assert np.degrees(np.arccos(np.clip(c, 0, 1))).max() <= fill.angle_tol + field_tol


def _graph_check(fill: PlateFill) -> None:
    """A height field: S_u x S_v has a positive component along the plane normal everywhere."""
    assert count_folds(fill.surface) == 0
    (u0, u1), (v0, v1) = fill.surface.domain
    U, V = np.meshgrid(np.linspace(u0, u1, 41), np.linspace(v0, v1, 41), indexing="ij")
    D = fill.surface.derivatives(U.ravel(), V.ravel(), 1)
    assert (np.cross(D[:, 1, 0], D[:, 0, 1]) @ fill.normal).min() > 0


# =========================================================================== closed forms
def test_l_shaped_hole_in_a_plane_is_refilled_by_that_plane() -> None:
    rng = np.random.default_rng(7)
    Q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    frame = Q.T * np.array([1, 1, np.linalg.det(Q)])[:, None]  # a right-handed tilted frame
    origin = np.array([3.0, -1.0, 2.0])
    fill = fill_plate(_plane_l(frame, origin, 5.0))
    assert fill.met and fill.side_g0.max() <= 1e-12 * 10 and np.nanmax(fill.side_g1) <= 1e-9
    size = 10.0
    assert np.abs((fill.surface.control_points - origin) @ frame[2]).max() <= 1e-12 * size
    assert abs(abs(fill.normal @ frame[2]) - 1) <= 1e-12
    # the p-curves are the sides projected: mapped back through the surface they are the sides
    for side, pc in zip(fill.sides, _loop_in_order(fill)):
        t = np.linspace(0, 1, 11)
        uv = pc.evaluate(t)
        assert np.linalg.norm(fill.surface.evaluate(uv[:, 0], uv[:, 1]) - side.curve.evaluate(t), axis=1).max() <= 1e-12 * size
    assert abs(fill.trimmed.area() - 3 * 25) <= 1e-9 * 75  # the L: 3 unit squares, scaled by 5
    _graph_check(fill)


def _loop_in_order(fill: PlateFill) -> list[BSplineCurve]:
    """The trimmed face's p-curves in the sides' order and direction (the constructor may have
    reversed the loop to run counter-clockwise; a plate's loop already does)."""
    pcs = list(fill.trimmed.outer)
    assert len(pcs) == len(fill.sides)
    return pcs


def test_annular_sector_with_rational_sides_in_a_plane() -> None:
    """The long curved hole (120 deg of an annulus, radii 1 and 2) on which the central split
    folds: a plane again, with exact rational arcs as sides (4-D cross fields) and p-curves."""
    a = np.radians([0.0, 60.0, 120.0])
    dirs = np.c_[np.cos(a), np.sin(a), np.zeros(3)]

    def arc3(r, rev):
        c = BSplineCurve(2, [0, 0, 0, 0.5, 0.5, 1, 1, 1], np.r_[_arc(dirs[0], dirs[1], r).control_points,
                                                                 _arc(dirs[1], dirs[2], r).control_points[1:]],
                         np.r_[_arc(dirs[0], dirs[1], r).weights, _arc(dirs[1], dirs[2], r).weights[1:]])
        return c.reverse() if rev else c

    outer, inner = arc3(2.0, False), arc3(1.0, True)
    curves = [outer, _line(outer.evaluate(1.0), inner.evaluate(0.0)), inner, _line(inner.evaluate(1.0), outer.evaluate(0.0))]
    sides = []
    for c in curves:
        s = np.linspace(*c.domain, 60)
        sides.append(side_from_normals(c, s, np.tile([0.0, 0.0, 1.0], (60, 1))).side)
    fill = fill_plate(sides)
    assert fill.met
    assert np.abs(fill.surface.control_points[..., 2]).max() <= 1e-12 * 4
    for side, pc in zip(fill.sides, _loop_in_order(fill)):
        assert pc.is_rational == side.curve.is_rational
        t = np.linspace(*side.curve.domain, 31)
        uv = pc.evaluate(t)
        assert np.linalg.norm(fill.surface.evaluate(uv[:, 0], uv[:, 1]) - side.curve.evaluate(t), axis=1).max() <= 1e-12 * 4
    assert abs(fill.trimmed.area() - np.pi * (4 - 1) / 3) <= 1e-9 * np.pi
    _graph_check(fill)


def test_reflex_hole_in_a_sphere_converges_to_the_sphere() -> None:
    devs = []
    for h in (0.4, 0.2, 0.1):
        fill = fill_plate(_sphere_l(h))
        assert fill.met and fill.side_g0.max() <= fill.g0_tol and np.nanmax(fill.side_g1) <= fill.angle_tol
        _check_boundary(fill, lambda P: P / np.linalg.norm(P, axis=1, keepdims=True), tolerances.FILL_FIT_ANGLE)
        _graph_check(fill)
        devs.append(float(np.abs(np.linalg.norm(_inside_points(fill), axis=1) - R).max()))
    assert devs[0] <= 9.3e-4 and devs[1] <= 2.1e-4 and devs[2] <= 6.4e-5, devs
    assert devs[0] / devs[1] >= 2.5 and devs[1] / devs[2] >= 2.5, devs


def test_reflex_hole_in_a_torus_converges_to_the_torus() -> None:
    devs = []
    for h in (0.8, 0.4, 0.2):
        fill = fill_plate(_torus_l(h))
        assert fill.met
        _check_boundary(fill, _torus_point_normal, tolerances.FILL_FIT_ANGLE)
        _graph_check(fill)
        P = _inside_points(fill)
        devs.append(float(np.abs(np.hypot(np.hypot(P[:, 0], P[:, 1]) - RT, P[:, 2]) - RR).max()))
    assert devs[0] <= 7.9e-3 and devs[1] <= 1.05e-3 and devs[2] <= 1.8e-4, devs
    assert devs[0] / devs[1] >= 2.5 and devs[1] / devs[2] >= 2.5, devs


def test_g0_only_sides_get_positions_only() -> None:
    sides = _sphere_l(0.3)
    fill = fill_plate(sides, g1=[True, False, True, False, True, False])
    assert fill.met and np.isnan(fill.side_g1[1::2]).all() and np.isfinite(fill.side_g1[::2]).all()
    _check_boundary(fill, lambda P: P / np.linalg.norm(P, axis=1, keepdims=True), tolerances.FILL_FIT_ANGLE)


def test_targets_and_span_limit_are_reported_not_hidden() -> None:
    """With one span allowed the targets cannot be met: the fill comes back with ``met`` False and
    the achieved numbers above the targets (what the caller reports)."""
    fill = fill_plate(_torus_l(0.8), max_spans=2)
    assert not fill.met and max(fill.spans) <= 2
    assert fill.side_g0.max() > fill.g0_tol or np.nanmax(fill.side_g1) > fill.angle_tol
    tight = fill_plate(_sphere_l(0.2), g0_tol=1e-3, angle_tol=1.0)
    assert tight.met and tight.g0_tol == 1e-3 and max(tight.spans) <= max(fill_plate(_sphere_l(0.2)).spans)


# =========================================================================== invariance
def _move(side: HoleSide, Rm: np.ndarray, s: float, t: np.ndarray) -> HoleSide:
    c = side.curve
    X = side.cross.control_points
    if X.shape[1] == 4:  # d(w P) moves with the translation times dw
        X = np.c_[s * X[:, :3] @ Rm.T + np.outer(X[:, 3], t), X[:, 3]]
    else:
        X = s * X @ Rm.T
    return HoleSide(BSplineCurve(c.degree, c.knots, s * c.control_points @ Rm.T + t, c.weights),
                    BSplineCurve(side.cross.degree, side.cross.knots, X))


_BASE = _sphere_l(0.3)
_BASE_FILL = fill_plate(_BASE)
_BASE_PTS = _inside_points(_BASE_FILL, 30)


@pytest.mark.slow
@test_settings(6)
@given(q=st.lists(st.floats(-1, 1), min_size=4, max_size=4).filter(lambda q: np.linalg.norm(q) > 0.1),
       log_scale=st.floats(-3, 3), shift=st.lists(st.floats(-100, 100), min_size=3, max_size=3))
def test_rigid_motion_and_scale_move_the_fill_with_the_hole(q, log_scale, shift) -> None:
    w, x, y, z = np.asarray(q) / np.linalg.norm(q)
    Rm = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                   [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                   [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
    s, t = 10.0 ** log_scale, np.asarray(shift)
    fill = fill_plate([_move(side, Rm, s, t) for side in _BASE])
    assert fill.spans == _BASE_FILL.spans or fill.spans == _BASE_FILL.spans[::-1]
    Q = s * _BASE_PTS @ Rm.T + t
    u, v = fill.locate(0, Q)
    size = s * 2 * R
    assert np.linalg.norm(fill.surface.evaluate(u, v) - Q, axis=1).max() <= 1e-9 * size + 1e-13 * np.abs(t).max()
    np.testing.assert_allclose(fill.side_g0 / s, _BASE_FILL.side_g0, rtol=1e-3, atol=1e-6 * fill.g0_tol / s)


# =========================================================================== refusals
def _thread(turns: float = 3.0) -> list[HoleSide]:
    """A strip between two helices (r = 1 and 1.5, pitch 0.3), closed by two radial segments: the
    thread face of a screw, which winds over itself in every projection."""
    t = np.linspace(0, 1, 400)
    a = 2 * np.pi * turns * t

    def helix(r):
        return np.c_[r * np.cos(a), r * np.sin(a), 0.3 * a / (2 * np.pi)]
    c1, _ = fit_boundary(t, helix(1.0), 1e-6)
    c3, _ = fit_boundary(t, helix(1.5)[::-1], 1e-6)
    radial = np.c_[np.cos(a), np.sin(a), 0 * a]
    x1, _ = fit_boundary(t, -radial, 1e-6)
    x3, _ = fit_boundary(t, radial[::-1], 1e-6)

    def tangent(ang):
        return np.array([-np.sin(ang), np.cos(ang), 0.3 / (2 * np.pi)])
    return [HoleSide(c1, x1), HoleSide(_line(c1.evaluate(1.0), c3.evaluate(0.0)), _const(tangent(a[-1]))),
            HoleSide(c3, x3), HoleSide(_line(c3.evaluate(1.0), c1.evaluate(0.0)), _const(-tangent(0.0)))]


def test_a_thread_strip_is_refused_with_the_reason() -> None:
    # every plane tried is named with its reason (the helix crosses itself over each of them)
    with pytest.raises(InvalidGeometryError, match="vector area: the loop crosses itself in projection.*"
                                                   "widest-cap axis: .*vector area: "):
        fill_plate(_thread())


def test_vertical_neighbours_are_refused_with_the_reason() -> None:
    """A square hole in z = 0 whose two opposite neighbours stand vertical (a slot's walls): no
    plane makes both graphs."""
    P = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    outs = [np.array([0, 0, 1.0]), np.array([1.0, 0, 0]), np.array([0, 0, 1.0]), np.array([-1.0, 0, 0])]
    sides = [HoleSide(_line(P[i], P[(i + 1) % 4]), _const(outs[i])) for i in range(4)]
    with pytest.raises(InvalidGeometryError, match="tangent plane stands at 90.0 deg"):
        fill_plate(sides)
    fill_plate(sides, g1=[False, True, False, True])  # asked for G0 only there, the walls do not matter


def test_bad_input_is_refused() -> None:
    sides = _sphere_l(0.3)
    with pytest.raises(InvalidGeometryError, match="the loop is open"):
        fill_plate(sides[:-1])
    with pytest.raises(InvalidGeometryError, match="g1: expected 6 flags"):
        fill_plate(sides, g1=[True] * 5)
    with pytest.raises(InvalidGeometryError, match=r"sides\[0\]: expected a HoleSide"):
        fill_plate([sides[0].curve] + sides[1:])
    with pytest.raises(InvalidGeometryError, match="max_spans"):
        fill_plate(sides, max_spans=0)
    with pytest.raises(InvalidGeometryError, match="positive targets"):
        fill_plate(sides, g0_tol=-1.0)
    with pytest.raises(InvalidGeometryError, match="side: expected 0..5"):
        _BASE_FILL.locate(6, np.zeros((1, 3)))


# =========================================================================== the solver
def test_the_plate_systems_are_solved_to_round_off(monkeypatch: pytest.MonkeyPatch) -> None:
    """Each stage's system ``K`` (symmetric positive definite, its diagonal scaled to 1 before the
    symmetric-mode factorisation) is solved as a dense Cholesky factorisation of the scaled matrix
    solves it: within 1e-8 of the largest coefficient (measured <= 3.9e-10 on the torus L's stages,
    condition numbers up to 3e8); and the fill is the one SuperLU's default factorisation (the G1
    plate's before) gave, to round-off: the same knots, per-side G0 and G1 within 1e-5 relative
    (measured 2.0e-6 and 3.2e-7: the iterated Tikhonov steps amplify the solves' round-off) and
    the poles within 1e-6 of the hole's size (measured 3.7e-8)."""
    import scipy.linalg as sla
    import scipy.sparse.linalg as spla

    from occsurf.algorithms.topology import plate_fill

    factor = plate_fill._SPDFactor
    systems = []

    class Recorded(factor):  # type: ignore[misc, valid-type]
        def __init__(self, stencil, sparse) -> None:
            systems.append((stencil.copy(), sparse()))
            super().__init__(stencil, sparse)

    class Default:  # SuperLU's defaults: column minimum degree, partial pivoting, no scaling
        def __init__(self, stencil, sparse) -> None:
            self.lu = spla.splu(sparse().tocsc())

        def solve(self, b):
            return self.lu.solve(b)

    sides = _torus_l(0.8)
    monkeypatch.setattr(plate_fill, "_SPDFactor", Recorded)
    fill = fill_plate(sides)
    monkeypatch.setattr(plate_fill, "_SPDFactor", Default)
    before = fill_plate(sides)
    assert len(systems) >= 3
    rng = np.random.default_rng(1)
    for stencil, K in systems:
        b = rng.standard_normal(K.shape[0])
        d = 1.0 / np.sqrt(K.diagonal())
        ref = d * sla.cho_solve(sla.cho_factor(K.toarray() * d[:, None] * d[None, :]), d * b)
        assert np.abs(factor(stencil, lambda K=K: K).solve(b) - ref).max() <= 1e-8 * np.abs(ref).max()
    assert fill.spans == before.spans
    np.testing.assert_allclose(fill.side_g0, before.side_g0, rtol=1e-5)
    np.testing.assert_allclose(fill.side_g1, before.side_g1, rtol=1e-5)
    size = np.ptp(np.concatenate([s.curve.control_points for s in sides]), axis=0).max()
    assert np.abs(fill.surface.control_points - before.surface.control_points).max() <= 1e-6 * size


def test_stages_share_their_trim_and_the_fill_is_the_same(monkeypatch: pytest.MonkeyPatch) -> None:
    """Every stage's face reuses the first stage's loops and their polylines (``on_surface``): the
    fill is the one made with a fresh TrimmedSurface per stage, pole for pole, with the same
    measures and fold count."""
    from occsurf.algorithms.kernel.trimmed import TrimmedSurface

    sides = _torus_l(0.8)
    shared = fill_plate(sides)
    monkeypatch.setattr(TrimmedSurface, "on_surface",
                        lambda self, surface: TrimmedSurface(surface, self.outer, list(self.inner)))
    fresh = fill_plate(sides)
    assert shared.spans == fresh.spans and shared.folds == fresh.folds
    np.testing.assert_array_equal(shared.surface.control_points, fresh.surface.control_points)
    np.testing.assert_array_equal(shared.side_g0, fresh.side_g0)
    np.testing.assert_array_equal(shared.side_g1, fresh.side_g1)


def test_the_fit_rows_taken_from_the_evaluation_are_those_evaluated_alone() -> None:
    """``fill_plate`` takes its fit's samples (points, neighbour normals, basis rows) from the stage's
    :class:`Evaluation`, made on the fit's parameters and those between them: the same values, bit
    for bit, as evaluating the fit's parameters alone (every sample is evaluated on its own)."""
    from occsurf.algorithms.topology.plate_fill import _fit_rows, _knots, _params
    from occsurf.algorithms.topology.plate_measure import Evaluation, basis_rows, local_data

    sides = _torus_l(0.8) + _sphere_l(0.4)[:1]  # polynomial (fitted) sides and a rational arc
    rng = np.random.default_rng(3)
    o, R, L = rng.standard_normal(3), np.linalg.qr(rng.standard_normal((3, 3)))[0], 2.5
    ku, kv = _knots(-3.0, 3.0, 11, 3), _knots(-3.0, 3.0, 7, 3)
    fit_t = [_params(s.curve, 24 + 7 * i) for i, s in enumerate(sides)]
    chk_t = [0.5 * (t[1:] + t[:-1]) for t in fit_t]
    ev = Evaluation(sides, np.ones(len(sides), bool), [np.r_[t, c] for t, c in zip(fit_t, chk_t)], ku, kv, 3, o, R, L)
    fit = _fit_rows(fit_t, chk_t)
    alone = [local_data(s, t, o, R, L) for s, t in zip(sides, fit_t)]
    X, M = np.concatenate([d[0] for d in alone]), np.concatenate([d[1] for d in alone])
    assert ev.X[fit].tobytes() == X.tobytes() and ev.M[fit].tobytes() == M.tobytes()
    for got, want in zip((ev.val[fit], ev.du[fit], ev.dv[fit], ev.cols[fit]), basis_rows(ku, kv, 3, X[:, 0], X[:, 1])):
        assert got.tobytes() == want.tobytes()
    assert np.array_equal(ev.sid[fit], np.concatenate([np.full(len(t), i) for i, t in enumerate(fit_t)]))
