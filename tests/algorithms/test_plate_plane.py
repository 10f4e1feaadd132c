"""The plate's reference plane (algorithms/topology/plate_fill.plate_plane, course §8-3, issue 12):
a hole that is a height field over *some* plane, but not over the loop's vector-area plane, its
neighbours' mean normal or its principal axes, is filled over the axis of the smallest cap holding
the neighbours' normals (the least lean any plane can have).

The hole: a strip on the unit cylinder x = sin(theta), z = cos(theta) (axis y) over theta in
[-70, 80] deg, 0.1 wide at theta = -70 and 0.005 wide at 80 (its area, and so its vector-area
normal, lies at the wide end), with three sides on the theta = -70 edge (so the mean of the
neighbour normals, sampled per side, leans the same way), and thin along y (the principal axes'
normal is y). Measured leans of the steepest neighbour from each candidate: vector area 117.4 deg,
mean normal 116.0, principal axes 91.8 (all beyond FILL_PLATE_MAX_TILT = 80: refused before the cap
axis was tried), cap axis 75.2 (theta = 5 deg, half the 150 deg spread). Over the cap plane the strip
projects one-to-one (x = sin(theta) rises monotonically), and the plate meets its targets:
G0 2.2e-7 (target FILL_FIT_G0 of the loop's diameter), G1 0.006 deg (target 0.01), and stays within
1.2e-3 of the cylinder inside the 0.1-wide strip (a different G1 surface with the same boundary
data; bound 3e-3, an O(1) departure for a wrong plane or orientation). Closed-form check: the cap
axis of normals spread symmetrically about a known axis is that axis (to 1e-3 rad: the
core-set iteration converges as 1/iterations).
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from occsurf.algorithms import tolerances
from occsurf.algorithms.errors import InvalidGeometryError
from occsurf.algorithms.kernel.curve import BSplineCurve
from occsurf.algorithms.topology.nsided import HoleSide, count_folds
from occsurf.algorithms.topology.nsided_sides import fit_boundary, side_from_normals
from occsurf.algorithms.topology.plate_fill import fill_plate
from occsurf.algorithms.topology.plate_plane import _widest_cap_axis, plate_plane

DEG = np.radians
STRIP = [(-70, 0.0), (80, 0.0), (80, 0.005), (-40, 0.02), (-40, 0.1), (-70, 0.1), (-70, 0.066), (-70, 0.033)]


def _line(a: np.ndarray, b: np.ndarray) -> BSplineCurve:
    return BSplineCurve(1, [0, 0, 1, 1], np.array([a, b], float))


def _cylinder(th: np.ndarray, y: np.ndarray) -> np.ndarray:
    return np.stack([np.sin(th), y, np.cos(th)], -1)


def _normal(th: np.ndarray) -> np.ndarray:
    return np.stack([np.sin(th), 0 * th, np.cos(th)], -1)


def _strip_samples(n: int = 200) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """Per side (straight in (theta, y)): parameters, points, outward normals."""
    t = np.linspace(0, 1, n)
    out = []
    for i in range(len(STRIP)):
        a, b = np.array(STRIP[i], float), np.array(STRIP[(i + 1) % len(STRIP)], float)
        d = a + (b - a) * t[:, None]
        out.append((t, _cylinder(DEG(d[:, 0]), d[:, 1]), _normal(DEG(d[:, 0]))))
    return out


def _candidate_leans(P: np.ndarray, M: np.ndarray) -> list[float]:
    Q = P - P.mean(axis=0)
    newell = 0.5 * np.cross(Q, np.roll(Q, -1, axis=0)).sum(axis=0)
    pca = np.linalg.svd(Q, full_matrices=False)[2][2]
    leans = []
    for N in (newell, M.sum(axis=0), pca):
        N = N / np.linalg.norm(N) * np.sign(N @ newell)
        leans.append(float(np.degrees(np.arccos((M @ N).min()))))
    return leans


def test_strip_is_refused_by_the_first_three_planes_and_taken_over_the_cap_axis() -> None:
    samples = _strip_samples()
    P = np.concatenate([s[1][:-1] for s in samples])
    M = np.concatenate([s[2][:-1] for s in samples])
    leans = _candidate_leans(P, M)
    assert min(leans) > tolerances.FILL_PLATE_MAX_TILT, leans  # the case: none of the three passes
    o, e1, e2, N, lean = plate_plane(P, M)  # raised InvalidGeometryError before the cap axis
    assert abs(lean - 75.0) < 0.5  # half the 150 deg spread of the normals
    assert np.degrees(np.arccos(N @ _normal(DEG(np.array([5.0])))[0])) < 0.5
    assert abs(np.linalg.det(np.c_[e1, e2, N]) - 1) < 1e-12


@pytest.mark.slow
def test_strip_plate_fill_meets_its_targets_and_stays_near_the_cylinder() -> None:
    sides = []
    for t, P, M in _strip_samples():
        curve, gap = fit_boundary(t, P, 1e-9)
        assert gap <= 1e-7  # the cubic fit of the side (measured 6.3e-8), below the plate's G0 target 2e-7
        sides.append(side_from_normals(curve, t, M).side)
    fill = fill_plate(sides)
    assert fill.met and fill.side_g0.max() <= fill.g0_tol and np.nanmax(fill.side_g1) <= fill.angle_tol
    assert fill.lean < tolerances.FILL_PLATE_MAX_TILT
    (u0, u1), (v0, v1) = fill.surface.domain
    U, V = np.meshgrid(np.linspace(u0, u1, 60), np.linspace(v0, v1, 60), indexing="ij")
    inside = fill.trimmed.contains(U.ravel(), V.ravel())
    assert inside.sum() > 100
    X = fill.surface.evaluate(U.ravel()[inside], V.ravel()[inside])
    assert np.abs(np.hypot(X[:, 0], X[:, 2]) - 1).max() <= 3e-3
    assert count_folds(fill.surface) == 0


def test_cap_axis_of_a_symmetric_spread_is_its_axis() -> None:
    rng = np.random.default_rng(3)
    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    e = np.cross(axis, [1.0, 0, 0])
    e /= np.linalg.norm(e)
    f = np.cross(axis, e)
    phi = np.linspace(0, 2 * np.pi, 50, endpoint=False)
    ring = np.cos(DEG(60)) * axis + np.sin(DEG(60)) * (np.cos(phi)[:, None] * e + np.sin(phi)[:, None] * f)
    inner = np.cos(DEG(20)) * axis + np.sin(DEG(20)) * (np.cos(3 * phi)[:, None] * e + np.sin(3 * phi)[:, None] * f)
    c = _widest_cap_axis(np.r_[ring, inner[:7]])
    assert np.arccos(np.clip(c @ axis / np.linalg.norm(c), -1, 1)) <= 1e-3


def test_no_plane_reason_names_every_candidate() -> None:
    """A square hole whose opposite neighbours stand vertical (a slot's walls): every candidate,
    the cap axis included, leans 90 deg from one wall; the message names each."""
    P = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    outs = [np.array([0, 0, 1.0]), np.array([1.0, 0, 0]), np.array([0, 0, 1.0]), np.array([-1.0, 0, 0])]
    sides = [HoleSide(_line(P[i], P[(i + 1) % 4]), _line(outs[i], outs[i])) for i in range(4)]
    with pytest.raises(InvalidGeometryError) as err:
        fill_plate(sides)
    msg = str(err.value)
    for name in ("vector area", "mean neighbour normal", "principal axes", "widest-cap axis",
                 "cap axis 1/3 towards the vector area", "cap axis 2/3 towards the vector area"):
        assert f"{name}: " in msg, msg
    assert "FILL_PLATE_MAX_TILT" in msg


@settings(max_examples=60, deadline=None)
@given(st.integers(4, 160), st.integers(0, 3), st.integers(0, 2**31 - 1))
def test_crossings_finds_the_first_crossing_pair_as_all_pairs_do(m: int, kind: int, seed: int) -> None:
    """The loop's self-crossing test (the plane's one-to-one check) compares only segments that share
    a grid cell: the answer is the lexicographically first crossing pair, the same as comparing all
    pairs (brute force here), on smooth, self-crossing, random-walk and noisy sliver loops with
    repeated points. It made the check 80-90 times faster (2048-point loops: 180-200 ms -> 2-3 ms)."""
    from occsurf.algorithms.topology.plate_plane import _crossings

    rng = np.random.default_rng(seed)
    t = np.linspace(0, 2 * np.pi, m, endpoint=False)
    Q = [np.c_[(1 + 0.3 * np.sin(5 * t)) * np.cos(t), (1 + 0.3 * np.sin(5 * t)) * np.sin(t)],
         np.c_[np.sin(t), 0.5 * np.sin(2 * t)],
         np.cumsum(rng.normal(size=(m, 2)), axis=0),
         np.c_[np.cos(t), 0.01 * np.sin(t)] + 1e-3 * rng.normal(size=(m, 2))][kind]
    if seed % 5 == 0:
        Q = np.repeat(Q, 2, axis=0)
    n = len(Q)
    A, B = Q, np.roll(Q, -1, axis=0)

    def orient(p, q, r):
        return (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0])

    want = None
    for i in range(n):
        for j in range(i + 2, n):
            if j - i >= n - 1:
                continue
            if (orient(A[i], B[i], A[j]) * orient(A[i], B[i], B[j]) < 0
                    and orient(A[j], B[j], A[i]) * orient(A[j], B[j], B[i]) < 0):
                want = (i, j)
                break
        if want is not None:
            break
    assert _crossings(Q) == want
