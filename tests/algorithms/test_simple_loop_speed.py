"""Tests of :func:`occsurf.algorithms.topology.nsided_loops.check_simple_loop` on long loops (issue 12).

The thread faces of the M6 screw (build123d's countersunk screw in tests' realdata) have 9-turn helical
sides, 170 mm long on a 13 mm loop: sampled at 65 parameters per side, every turn was a candidate of
every other and the one-by-one confirmation took 20-45 s per call. The loop check now samples each
side by its length and flatness and confirms all candidates at once; these tests pin what it decides.

Closed forms. A helical strip: side 0 the helix H(th) = (3 cos th, 3 sin th, th / 2 pi) (pitch 1, 9
turns), side 2 the same helix raised by delta(th) and run backwards, sides 1 and 3 straight lines
joining their ends. Both helices interpolate the same 32-per-turn data (SciPy's cubic not-a-knot
interpolant), the raised one the data plus delta(th_i) e_z: interpolation is linear, so side 2 is
side 0 plus the interpolant of delta exactly, and one turn of side 0 is the previous turn plus
(0, 0, 1) to round-off away from the ends (measured 1e-16 at mid-length; 1.3e-4 within a turn of an
end, where the end conditions act, which is why the near-touch is placed mid-length). Where delta
peaks at a data point at 1 - g, the raised turn passes at distance g below the next turn of side 0
at the peak: g = tol / 4 is a touch (refused, distance reported 0.25 tol to 3 digits), g = 2 tol
or 10 tol is not (accepted; the candidates there are confirmed on the curves and let through).

Tolerance: the one fill_hole uses, FILL_CLOSURE_TOL (1e-6) of the loop's size.
"""

from __future__ import annotations

import re

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from scipy.interpolate import make_interp_spline

from occsurf.algorithms import tolerances
from occsurf.algorithms.errors import InvalidGeometryError
from occsurf.algorithms.kernel.curve import BSplineCurve
from occsurf.algorithms.topology import nsided_loops
from occsurf.algorithms.topology.nsided import HoleSide
from occsurf.algorithms.topology.nsided_loops import check_simple_loop

from .strategies import test_settings

RADIUS, PITCH, TURNS, PER_TURN = 3.0, 1.0, 9, 32
TH = np.linspace(0.0, 2 * np.pi * TURNS, TURNS * PER_TURN + 1)
HELIX = np.c_[RADIUS * np.cos(TH), RADIUS * np.sin(TH), PITCH * TH / (2 * np.pi)]
PEAK = 9 * np.pi  # mid-length, a data point (144 of 288)
#: a cross field: check_simple_loop reads only the curves
_CROSS = BSplineCurve(1, [0, 0, 1, 1], np.array([[0.0, 0.0, 1.0], [0.0, 0.0, 1.0]]))


def _line(a, b) -> BSplineCurve:
    return BSplineCurve(1, [0, 0, 1, 1], np.array([a, b], float))


def _interpolant(data: np.ndarray) -> BSplineCurve:
    s = make_interp_spline(TH, data, k=3)
    return BSplineCurve(3, s.t, s.c).reparametrize(0.0, 1.0)


def _loop(curves: list[BSplineCurve]) -> list[HoleSide]:
    return [HoleSide(c, _CROSS) for c in curves]


def _strip(delta: np.ndarray) -> list[HoleSide]:
    """The helical strip of the module docstring, side 2 raised by ``delta`` (at the data points)."""
    low = _interpolant(HELIX)
    high = _interpolant(HELIX + np.c_[0 * TH, 0 * TH, delta]).reverse()
    return _loop([low, _line(low.evaluate(1.0), high.evaluate(0.0)), high,
                  _line(high.evaluate(1.0), low.evaluate(0.0))])


def _size(sides: list[HoleSide]) -> float:
    pts = np.concatenate([sd.curve.evaluate(np.linspace(0.0, 1.0, 65)) for sd in sides])
    return float(np.linalg.norm(np.ptp(pts, axis=0)))


def _bump(gap: float) -> np.ndarray:
    """delta: 0.5 (half the pitch) away from PEAK, rising to PITCH - gap at it."""
    return 0.5 + (0.5 - gap) * np.exp(-((TH - PEAK) / 1.0) ** 2)


@pytest.fixture
def confirmed(monkeypatch) -> list[int]:
    """Counts the candidate pairs that reach the confirmation on the curves."""
    counts: list[int] = []
    inner = nsided_loops._closest_pairs

    def counting(curves, sa, *args):
        counts.append(len(sa))
        return inner(curves, sa, *args)

    monkeypatch.setattr(nsided_loops, "_closest_pairs", counting)
    return counts


def test_long_helical_strip_is_accepted_without_candidates(confirmed) -> None:
    """Turns half a pitch apart (0.5 on a 12.7 loop): no segment pair is even a candidate (at 65
    samples per side the segments were 2.7 long and every turn was a candidate of every other)."""
    sides = _strip(np.full_like(TH, 0.5))
    check_simple_loop(sides, tolerances.FILL_CLOSURE_TOL * _size(sides))
    assert sum(confirmed) == 0


@pytest.mark.parametrize("gap_in_tol", [2.0, 10.0])
def test_helix_turns_close_but_apart_are_accepted(confirmed, gap_in_tol: float) -> None:
    """One turn comes within 2 (10) tolerances of the next: candidates, confirmed on the curves, let through."""
    tol = tolerances.FILL_CLOSURE_TOL * _size(_strip(_bump(0.0)))
    check_simple_loop(_strip(_bump(gap_in_tol * tol)), tol)
    assert sum(confirmed) > 0


def test_helix_turns_touching_within_tol_are_refused_with_where() -> None:
    """One turn comes within a quarter tolerance of the next at mid-length: refused, naming the two
    helices, the parameters of the peak (side 0 one turn later: 11/18; side 2 run backwards: 1/2) and
    the distance."""
    tol = tolerances.FILL_CLOSURE_TOL * _size(_strip(_bump(0.0)))
    with pytest.raises(InvalidGeometryError) as err:
        check_simple_loop(_strip(_bump(0.25 * tol)), tol)
    m = re.fullmatch(r"sides: the loop crosses itself: side 0 at parameter (\S+) comes within (\S+) of side 2 at "
                     r"(\S+) \(tolerance (\S+)\); a hole's boundary must be a simple loop", str(err.value))
    assert m is not None, str(err.value)
    t0, dist, t2 = float(m[1]), float(m[2]), float(m[3])
    # the curves' nearest points are at the peak to the printed 4 digits (the bump is symmetric about it)
    assert abs(t0 - (PEAK + 2 * np.pi) / TH[-1]) <= 1e-4 and abs(t2 - (1 - PEAK / TH[-1])) <= 1e-4
    assert abs(dist - 0.25 * tol) <= 0.005 * tol  # printed to 3 digits


def test_helix_lying_on_the_next_turn_is_refused() -> None:
    """Side 2 raised by a whole pitch minus tol / 4 runs along side 0's next turns for 8 turns: refused."""
    sides = _strip(np.full_like(TH, PITCH))
    tol = tolerances.FILL_CLOSURE_TOL * _size(sides)
    with pytest.raises(InvalidGeometryError, match=r"crosses itself: side 0 at .* of side 2 at"):
        check_simple_loop(_strip(np.full_like(TH, PITCH - 0.25 * tol)), tol)


def test_crossing_at_a_small_angle_is_found() -> None:
    """Two parabolas crossing at ~1e-3 rad at s = t = 0.5: alternating closest points would shrink the
    distance by cos^2(1e-3) per round; the joint Newton step finds the crossing (distance ~ round-off)."""
    a = BSplineCurve(2, [0, 0, 0, 1, 1, 1], np.array([[0, 0, 0], [0.5, 0.05, 0], [1, 0, 0]], float))
    b = BSplineCurve(2, [0, 0, 0, 1, 1, 1], np.array([[0, -5e-4, 0], [0.5, 0.05, 0], [1, 5e-4, 0]], float))
    one = np.zeros(1, np.intp)
    ta, tb, dist = nsided_loops._closest_pairs([a, b], one, one + 1, np.array([0.3]), np.array([0.7]),
                                               (np.zeros(1), np.ones(1)), (np.zeros(1), np.ones(1)))
    assert dist[0] <= 1e-14
    np.testing.assert_allclose([ta[0], tb[0]], [0.5, 0.5], atol=1e-12)


@pytest.mark.parametrize("eps", [1.0, 0.1])
def test_zero_angle_corner_is_left_to_the_cusp_check(eps: float) -> None:
    """Two parabolas y = x^2 and y = (1 + eps) x^2 leave the origin in the same direction (a zero-angle
    corner) and part as eps x^2: within tol only within sqrt(tol / eps) of the corner (1e-3 of the
    loop for eps = 1, 4e-3 for 0.1, inside the first segments). The loop check lets the corner through,
    as it did before, so that fill_hole names it: a cusp."""
    from occsurf.algorithms.topology.nsided import fill_hole
    from occsurf.algorithms.topology.nsided_sides import side_from_normals

    b = 1.0 + eps
    quad = lambda *p: BSplineCurve(2, [0, 0, 0, 1, 1, 1], np.array(p, float))  # noqa: E731
    curves = [_line([-1, 1, 0], [-1, b, 0]), quad([-1, b, 0], [-0.5, 0, 0], [0, 0, 0]),
              quad([0, 0, 0], [-0.5, 0, 0], [-1, 1, 0])]  # counter-clockwise about +z
    sides = _loop(curves)
    check_simple_loop(sides, tolerances.FILL_CLOSURE_TOL * _size(sides))
    s = np.linspace(0.0, 1.0, 64)
    planar = [side_from_normals(c, s, np.tile([0.0, 0.0, 1.0], (64, 1))).side for c in curves]
    with pytest.raises(InvalidGeometryError, match=r"corner 2 \(start of side 2\) is a cusp"):
        fill_hole(planar)


# --- a property: random star-shaped loops are simple; pushing one side through another is not


@st.composite
def star_loops(draw) -> tuple[list[BSplineCurve], np.ndarray]:
    """A loop of n (4-8) quadratic sides, each inside the triangle (centre, v_k, v_k+1) of a star-shaped
    polygon (vertices at increasing angles, gaps below pi, radii 0.5-1.5): the triangles meet only
    along the rays, so the loop is simple. Some sides degree-elevated or refined (other parametrisations),
    the whole placed by a random rotation, scale and translation. Returns the sides and the placement."""
    n = draw(st.integers(4, 8))
    weights = np.array(draw(st.lists(st.floats(1.0, 2.5), min_size=n, max_size=n)))
    gaps = 2 * np.pi * weights / weights.sum()  # 0.34 (n = 8) to 2.86 (n = 4) rad: every gap below pi
    ang = np.cumsum(gaps) - gaps[0]
    rad = np.array(draw(st.lists(st.floats(0.5, 1.5), min_size=n, max_size=n)))
    v = np.c_[rad * np.cos(ang), rad * np.sin(ang), np.zeros(n)]
    bary = np.array(draw(st.lists(st.tuples(st.floats(0.05, 0.9), st.floats(0.05, 0.9)), min_size=n, max_size=n)))
    bary = bary / np.maximum(bary.sum(1, keepdims=True), 1.0) * 0.95  # weights of v_k, v_k+1; the rest the centre
    Q = np.linalg.qr(np.array(draw(st.lists(st.floats(-1, 1), min_size=9, max_size=9))).reshape(3, 3)
                     + 3 * np.eye(3))[0]
    scale = draw(st.floats(0.01, 100.0))
    shift = np.array(draw(st.lists(st.floats(-100, 100), min_size=3, max_size=3)))
    place = np.r_[Q.ravel(), scale, shift]
    sides = []
    for k in range(n):
        a, b = v[k], v[(k + 1) % n]
        mid = bary[k, 0] * a + bary[k, 1] * b
        c = BSplineCurve(2, [0, 0, 0, 1, 1, 1], np.array([a, mid, b]))
        how = draw(st.sampled_from(["as is", "elevated", "refined"]))
        if how == "elevated":
            c = c.elevate_degree(1)
        elif how == "refined":
            c = c.refine(np.sort(np.array(draw(st.lists(st.floats(0.05, 0.95), min_size=1, max_size=3)))))
        sides.append(c)
    return sides, place


def _placed(curves: list[BSplineCurve], place: np.ndarray) -> list[HoleSide]:
    Q, scale, shift = place[:9].reshape(3, 3), place[9], place[10:]
    return _loop([BSplineCurve(c.degree, c.knots, scale * np.asarray(c.control_points) @ Q.T + shift)
                  for c in curves])


@test_settings(30)
@given(star_loops(), st.data())
def test_star_loop_is_simple_and_pushing_a_side_through_another_is_not(loop, data) -> None:
    curves, place = loop
    n = len(curves)
    sides = _placed(curves, place)
    tol = tolerances.FILL_CLOSURE_TOL * _size(sides)
    check_simple_loop(sides, tol)
    # side k redrawn through the middle of a side j not next to it: a crossing (or touch) there
    k = data.draw(st.integers(0, n - 1))
    j = (k + data.draw(st.integers(2, n - 2))) % n
    q = curves[j].evaluate(0.5)
    a, b = curves[k].evaluate(0.0), curves[k].evaluate(1.0)
    curves = list(curves)
    curves[k] = BSplineCurve(2, [0, 0, 0, 1, 1, 1], np.array([a, 2 * q - 0.5 * (a + b), b]))
    with pytest.raises(InvalidGeometryError, match=rf"crosses itself: side (?:{k} .* side \d+|\d+ .* side {k}) at"):
        check_simple_loop(_placed(curves, place), tol)
