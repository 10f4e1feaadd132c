"""Direct manipulation cross-validated with OpenCascade (course ch. 4 vs. ``MovePoint``).

``Geom_BSplineCurve::MovePoint(u, P, i1, i2)`` moves the curve through ``P`` changing poles
``i1..i2`` (1-based) by a heuristic; ``MovePointAndTangent`` does the same for a point and a
tangent with the end poles fixed by start/end conditions; ``Geom_BSplineSurface::MovePoint`` for
surfaces. On the same spline, parameter, target and window:

* both edits meet the request: the point to ``1e-12`` (relative to ``max(1, |pole|)``), the
  tangent to ``1e-12`` relative to ``max(1, |tangent|)``;
* our change of poles is never larger than OCC's in the Frobenius norm: ours is the minimum-norm
  change over the window (Bartels & Beatty 1989), and OCC's is one feasible change in the same
  window (checked: OCC leaves the poles outside the window alone);
* OCC's evaluation of *our* edited curves confirms mixed constraints (curvature via
  ``GeomLProp_CLProps``, tangents via ``D1``) to ``1e-10``.

Each case's norms are collected; the module prints a table (ours vs OCC) when it finishes, and
writes it as Markdown to ``$OCCSURF_REPORT_DIR/manipulation_vs_occ.md`` when that variable is set.
"""

from __future__ import annotations

import contextlib
import os
from pathlib import Path

import numpy as np
import pytest
from hypothesis import assume, given
from hypothesis import strategies as st
from numpy.testing import assert_allclose

pytest.importorskip("OCP")

from OCP.GeomLProp import GeomLProp_CLProps  # noqa: E402
from OCP.gp import gp_Pnt, gp_Vec  # noqa: E402

from occsurf.algorithms import (  # noqa: E402
    BSplineCurve,
    BSplineSurface,
    ConstraintError,
    Curvature,
    Position,
    Tangent,
    constrain,
    drag_point,
    drag_surface_point,
)
from tests.algorithms.strategies import curves, fractions, surfaces, test_settings  # noqa: E402

POINT = 1e-12      # both edits meet the point (relative to max(1, |pole|))
HOLD = 1e-10       # mixed constraints, evaluated by OCC
SETTINGS = test_settings(60)
TABLE: list[dict] = []


# ---------------------------------------------------------------------------------------- helpers
def to_occ(spline):
    """``bridge.to_occ`` (imported lazily, so a broken bridge fails these tests, not collection)."""
    from occsurf.bridge import to_occ as convert

    return convert(spline)


def occ_poles(occ_curve) -> np.ndarray:
    return np.array([occ_curve.Pole(i).Coord() for i in range(1, occ_curve.NbPoles() + 1)])


def occ_net(occ_surface) -> np.ndarray:
    return np.array([[occ_surface.Pole(i, j).Coord() for j in range(1, occ_surface.NbVPoles() + 1)]
                     for i in range(1, occ_surface.NbUPoles() + 1)])


def scale(*arrays) -> float:
    return max([1.0] + [float(np.abs(a).max()) for a in arrays])


def record(kind: str, spline, u, window, ours: float, occ: float, note: str = "") -> None:
    if not note and ours > 0 and occ > 1e3 * ours:
        note = "OCC's change > 1000 x ours (its heuristic on an ill-conditioned window)"
    degree = spline.degree
    TABLE.append(dict(kind=kind, degree=degree, poles=spline.n_poles, rational=spline.weights is not None,
                      u=u, window=window, ours=ours, occ=occ, note=note))


@pytest.fixture(scope="module", autouse=True)
def report_table(request):
    """Print the ours-vs-OCC table at the end of the module (and write it if asked)."""
    yield
    if not TABLE:
        return
    lines = ["| case | degree | poles | rational | u | window (0-based) | |dP| ours | |dP| OCC | OCC/ours | note |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for r in TABLE:
        ratio = r["occ"] / r["ours"] if r["ours"] > 0 else float("nan")
        u = r["u"] if isinstance(r["u"], str) else f"{r['u']:.4g}"
        lines.append(f"| {r['kind']} | {r['degree']} | {r['poles']} | {r['rational']} | {u} | {r['window']} | "
                     f"{r['ours']:.6g} | {r['occ']:.6g} | {ratio:.4g} | {r['note']} |")
    compared = [r for r in TABLE if not r["note"] and r["ours"] > 1e-12 and np.isfinite(r["occ"])]
    ratios = np.array([r["occ"] / r["ours"] for r in compared]) if compared else np.array([np.nan])
    summary = (f"{len(compared)} compared cases: OCC/ours pole-change ratio min {ratios.min():.6g}, median "
               f"{np.median(ratios):.4g}, max {ratios.max():.4g}; {len(TABLE) - len(compared)} more listed "
               "(no or round-off-sized move, OCC defects, no OCC equivalent)")
    text = "\n".join(["# Direct manipulation: our minimum-norm pole change vs OCC", "", summary, ""] + lines) + "\n"
    out = os.environ.get("OCCSURF_REPORT_DIR")
    if out:
        Path(out).mkdir(parents=True, exist_ok=True)
        (Path(out) / "manipulation_vs_occ.md").write_text(text)
    tr = request.config.pluginmanager.get_plugin("terminalreporter")
    cap = request.config.pluginmanager.get_plugin("capturemanager")
    if tr is not None:
        with cap.global_and_fixture_disabled() if cap is not None else contextlib.nullcontext():
            tr.write_line("")
            tr.write_line("manipulation vs OCC: " + summary)
            for line in lines[:2] + lines[2:][:: max(1, len(lines) // 25)]:  # a sample of the cases
                tr.write_line(line)


def _open_end(c: BSplineCurve, u: float) -> bool:
    """``u`` is an end of the domain where the knot vector is not clamped (OCC mishandles it), or
    within 4 ulps of it: OCC's span search puts ``u`` one ulp short of the end on the end (found by
    hypothesis: knots [-3.5, -3.5, 0, 0, 0, 1, 1, 2, 3, 4], u = 1 - 1.1e-16; at 1 - 1e-15 OCC hits)."""
    lo, hi = c.domain
    near_hi, near_lo = abs(u - hi) <= 4 * np.spacing(abs(hi)), abs(u - lo) <= 4 * np.spacing(abs(lo))
    return (near_hi and bool(np.any(c.knots[c.n_poles :] > hi))) or (near_lo and bool(np.any(c.knots[: c.degree + 1] < lo)))


def _window(pair, n: int) -> tuple[int, int]:
    a, b = pair
    return tuple(sorted((int(a * (n - 1) + 0.5), int(b * (n - 1) + 0.5))))  # type: ignore[return-value]


# ---------------------------------------------------------------------------------------- MovePoint
@SETTINGS
@given(c=curves(dims=st.just(3)), fu=fractions, target=st.lists(st.floats(-10, 10), min_size=3, max_size=3),
       win=st.tuples(fractions, fractions), whole=st.booleans())
def test_move_point_ours_is_never_larger_than_occ(c, fu, target, win, whole):
    lo, hi = c.domain
    u = lo + fu * (hi - lo)
    T = np.array(target)
    f, l = (0, c.n_poles - 1) if whole else _window(win, c.n_poles)
    occ = to_occ(c)
    try:
        first, last = occ.MovePoint(u, gp_Pnt(*T), f + 1, l + 1)
    except Exception as err:  # OCC raises Standard_RangeError for some windows that do not act at u
        first, last = 1, 0
        occ_error = type(err).__name__
    else:
        occ_error = ""
    try:
        ours = drag_point(c, u, T, f, l)
    except ConstraintError:
        # We refuse only when no pole of the window acts at u. OCC then reports nothing moved, or
        # "moves" a pole whose basis function vanishes at u and so misses the target.
        if first <= last:
            missed = np.linalg.norm(np.array(occ.Value(u).Coord()) - T)
            # OCC defect seen here: such a "move" can even fill the poles with NaN.
            assert not missed <= 1e-12 or np.array_equal(T, c.evaluate(u)), "OCC reached a target no pole acts on"
            record("MovePoint", c, u, f"{f}..{l}", float("nan"), float("nan"),
                   "no window pole acts at u: we raise; OCC " + ("NaN poles" if np.isnan(missed) else "misses P"))
        return
    R = BSplineCurve(c.degree, c.knots, np.eye(c.n_poles), c.weights).evaluate(u)[f : l + 1]
    assume(np.sum(R**2) > 1e-6)  # a window that barely reaches u asks both for huge moves
    s = scale(c.control_points, T)
    assert_allclose(ours.evaluate(u), T, atol=POINT * scale(ours.control_points, T))
    d_ours = float(np.linalg.norm(ours.control_points - c.control_points))
    P_occ = occ_poles(occ)
    hit = first <= last and np.allclose(np.array(occ.Value(u).Coord()), T, rtol=0, atol=POINT * scale(P_occ, T))
    if not hit and _open_end(c, u):
        # Known OCC defect (see test_occ_move_point_at_the_end_of_an_unclamped_curve): at the end of
        # an unclamped domain MovePoint raises Standard_OutOfRange or misses P. Ours holds anyway.
        record("MovePoint", c, u, f"{f}..{l}", d_ours, float("nan"),
               f"OCC defect at the open domain end: {occ_error or 'misses P'}")
        return
    assert first <= last, f"OCC refused ({occ_error or 'first > last'}) window {f}..{l}, basis mass {np.sum(R**2):.3g}"
    assert_allclose(np.array(occ.Value(u).Coord()), T, atol=POINT * scale(P_occ, T))
    moved = np.nonzero(np.any(P_occ != c.control_points, axis=1))[0]
    assert moved.size == 0 or (moved.min() >= f and moved.max() <= l), "OCC moved poles outside the window"
    d_occ = float(np.linalg.norm(P_occ - c.control_points))
    record("MovePoint", c, u, f"{f}..{l}", d_ours, d_occ)
    assert d_ours <= d_occ * (1 + 1e-12) + 1e-14 * s


@pytest.mark.xfail(strict=True, reason="OCC 7.9.3 defect: Geom_BSplineCurve::MovePoint at the end of an unclamped "
                   "domain leaves the curve where it was (or raises Standard_OutOfRange); drag_point is exact there")
@pytest.mark.parametrize(("degree", "knots", "ulps"), [(2, [2.0, 3.0, 3.0, 4.0, 4.0, 5.0, 6.0], 0),
                                                     (3, [-3.5, -3.5, 0.0, 0.0, 0.0, 1.0, 1.0, 2.0, 3.0, 4.0], 1)])
def test_occ_move_point_at_the_end_of_an_unclamped_curve(degree, knots, ulps):
    c = BSplineCurve(degree, knots, np.zeros((len(knots) - degree - 1, 3)))
    u, T = c.domain[1], np.array([0.0, 0.0, 1.0])
    for _ in range(ulps):  # one ulp short of the end: OCC still takes it for the end (hypothesis found it)
        u = np.nextafter(u, -np.inf)
    n = c.n_poles
    assert_allclose(drag_point(c, u, T, 0, n - 1).evaluate(u), T, atol=1e-15)  # ours
    occ = to_occ(c)
    first, last = occ.MovePoint(u, gp_Pnt(*T), 1, n)
    assert first <= last
    assert_allclose(np.array(occ.Value(u).Coord()), T, atol=1e-12)


# ---------------------------------------------------------------------------------------- MovePointAndTangent
@SETTINGS
@given(c=curves(dims=st.just(3), degrees=st.integers(2, 7), max_extra_poles=8), fu=fractions,
       dp=st.lists(st.floats(-3, 3), min_size=3, max_size=3), dv=st.lists(st.floats(-3, 3), min_size=3, max_size=3),
       start=st.sampled_from([-1, 0, 1]), end=st.sampled_from([-1, 0, 1]))
def test_move_point_and_tangent_ours_is_never_larger_than_occ(c, fu, dp, dv, start, end):
    lo, hi = c.domain
    u = lo + fu * (hi - lo)
    D = c.derivatives(u, 1)
    T = D[0] + np.array(dp)
    V = D[1] * (1 + 0.2 * dv[0]) + np.array(dv) * max(1.0, np.linalg.norm(D[1])) * 0.3
    f, l = start + 1, c.n_poles - 2 - end
    assume(f <= l)
    # The window's rows for C(u) and C'(u) must be well conditioned, else both answers are huge
    # moves that round-off dominates (e.g. u a hair away from the end where the fixed pole acts).
    B = BSplineCurve(c.degree, c.knots, np.eye(c.n_poles), c.weights).derivatives(u, 1)[:, f : l + 1]
    norms = np.linalg.norm(B, axis=1, keepdims=True)
    assume(np.all(norms > 0))
    sv = np.linalg.svd(B / norms, compute_uv=False)
    assume(sv.size == 2 and sv[-1] > 1e-3)
    occ = to_occ(c)
    try:
        (status,) = occ.MovePointAndTangent(u, gp_Pnt(*T), gp_Vec(*V), 1e-9, start, end)
    except Exception:
        status = -1
    assume(status == 0)  # OCC refuses (status != 0) e.g. at the fixed ends; nothing to compare
    P_occ = occ_poles(occ)
    moved = np.nonzero(np.any(P_occ != c.control_points, axis=1))[0]
    ours = constrain(c, [Position(u, T), Tangent(u, V)], movable=slice(f, l + 1))
    if not np.isfinite(P_occ).all() or (moved.size and (moved.min() < f or moved.max() > l)):
        # OCC defect (seen at the end of the domain of unclamped curves): status 0 but NaN poles, or
        # poles moved that the start/end conditions fix. Nothing to compare; ours must still hold.
        record("MovePointAndTangent", c, u, f"{f}..{l} (conds {start},{end})",
               float(np.linalg.norm(ours.control_points - c.control_points)), float("nan"),
               "OCC status 0 but " + ("NaN poles" if not np.isfinite(P_occ).all() else "fixed poles moved"))
        P_occ = None
    # A derivative carries the round-off of the poles it is made of (times degree / span).
    h = float(np.min(np.diff(np.unique(c.knots))))
    tscale = max(1.0, np.linalg.norm(V), scale(c.control_points if P_occ is None else P_occ) * c.degree / h)
    if P_occ is not None:
        assert_allclose(np.array(occ.Value(u).Coord()), T, atol=POINT * scale(P_occ, T))
        assert_allclose(np.array(occ.DN(u, 1).Coord()), V, atol=POINT * tscale)
    assert_allclose(ours.evaluate(u), T, atol=POINT * scale(ours.control_points, T))
    assert_allclose(ours.derivatives(u, 1)[1], V, atol=POINT * max(tscale, scale(ours.control_points) * c.degree / h))
    if P_occ is None:
        return
    d_ours = float(np.linalg.norm(ours.control_points - c.control_points))
    d_occ = float(np.linalg.norm(P_occ - c.control_points))
    record("MovePointAndTangent", c, u, f"{f}..{l} (conds {start},{end})", d_ours, d_occ)
    assert d_ours <= d_occ * (1 + 1e-12) + 1e-14 * scale(c.control_points)


# ---------------------------------------------------------------------------------------- surfaces
@test_settings(30)
@given(s=surfaces(dims=st.just(3), degrees=st.integers(1, 5)), fu=fractions, fv=fractions,
       target=st.lists(st.floats(-10, 10), min_size=3, max_size=3), wu=st.tuples(fractions, fractions),
       wv=st.tuples(fractions, fractions))
def test_surface_move_point_ours_is_never_larger_than_occ(s, fu, fv, target, wu, wv):
    (u0, u1), (v0, v1) = s.domain
    u, v = u0 + fu * (u1 - u0), v0 + fv * (v1 - v0)
    nu, nv = s.n_poles
    (i1, i2), (j1, j2) = _window(wu, nu), _window(wv, nv)
    T = np.array(target)
    try:
        ours = drag_surface_point(s, u, v, T, window=((i1, i2), (j1, j2)))
    except ConstraintError:
        return  # no pole of the window acts at (u, v)
    e = BSplineSurface(s.degree, s.knots, np.eye(nu * nv).reshape(nu, nv, nu * nv), s.weights).evaluate(u, v)
    assume(np.sum(e.reshape(nu, nv)[i1 : i2 + 1, j1 : j2 + 1] ** 2) > 1e-6)  # else both moves are huge
    occ = to_occ(s)
    try:
        res = occ.MovePoint(u, v, gp_Pnt(*T), i1 + 1, i2 + 1, j1 + 1, j2 + 1)
    except Exception:
        return
    uf, ul, vf, vl = res
    assume(uf <= ul and vf <= vl)
    P_occ = occ_net(occ)
    occ_miss = float(np.linalg.norm(np.array(occ.Value(u, v).Coord()) - T))
    assert_allclose(ours.evaluate(u, v), T, atol=POINT * 10 * scale(ours.control_points, T))
    d_ours = float(np.linalg.norm(ours.control_points - s.control_points))
    d_occ = float(np.linalg.norm(P_occ - s.control_points))
    hit = occ_miss <= POINT * scale(P_occ, T)
    TABLE.append(dict(kind="Surface MovePoint", degree=s.degree, poles=s.n_poles, rational=s.weights is not None,
                      u=f"({u:.4g}, {v:.4g})", window=f"({i1}..{i2}, {j1}..{j2})", ours=d_ours, occ=d_occ,
                      note="" if hit else f"OCC misses P by {occ_miss:.3g}"))
    if hit:  # OCC's change is feasible for the same window, so it cannot be smaller than ours
        assert d_ours <= d_occ * (1 + 1e-12) + 1e-14 * scale(s.control_points)


# ---------------------------------------------------------------------------------------- mixed, by OCC's eyes
def _cubic(n=14, seed=0, rational=False) -> BSplineCurve:
    rng = np.random.default_rng(seed)
    t = np.r_[[0.0] * 4, np.linspace(0, 1, n - 2)[1:-1], [1.0] * 4]
    P = np.c_[np.linspace(0, 10, n), rng.uniform(-1, 1, (n, 2))]
    return BSplineCurve(3, t, P, rng.uniform(0.5, 2, n) if rational else None)


@pytest.mark.parametrize("rational", [False, True])
def test_mixed_constraints_checked_by_occ_evaluators(rational):
    c = _cubic(seed=3, rational=rational)
    T1 = np.array([6.0, 1.0, 0.5])
    n1 = np.cross(T1, [0.0, 0.0, 1.0])
    kappa = 0.4 * np.cross(n1, T1) / np.linalg.norm(np.cross(n1, T1))  # perpendicular to T1, radius 2.5
    cons = [Position(0.25, c.evaluate(0.25) + [0, 0.5, 0]), Tangent(0.25, T1), Curvature(0.25, kappa),
            Position(0.6, c.evaluate(0.6) + [0, 0, 0.3]), Curvature(0.8, 1.5)]
    ours = constrain(c, cons)
    occ = to_occ(ours)
    assert_allclose(np.array(occ.Value(0.25).Coord()), cons[0].point, atol=HOLD)
    assert_allclose(np.array(occ.DN(0.25, 1).Coord()), T1, atol=HOLD * 6)
    assert_allclose(np.array(occ.Value(0.6).Coord()), cons[3].point, atol=HOLD)
    props = GeomLProp_CLProps(occ, 0.25, 2, 1e-9)
    centre = gp_Pnt()
    props.CentreOfCurvature(centre)
    k_occ = (np.array(centre.Coord()) - cons[0].point) * props.Curvature() ** 2  # kappa = (centre - P) / r^2
    assert_allclose(k_occ, kappa, atol=HOLD)
    assert abs(GeomLProp_CLProps(occ, 0.8, 2, 1e-9).Curvature() - 1 / 1.5) <= HOLD
    # And the change is the minimum-norm one for the position/tangent part's linear system at the
    # solution (see tests/algorithms/test_manipulation.py for the full KKT check).
    TABLE.append(dict(kind="mixed (OCC evaluates)", degree=3, poles=c.n_poles, rational=rational,
                      u="0.25/0.6/0.8", window="all", ours=float(np.linalg.norm(ours.control_points - c.control_points)),
                      occ=float("nan"), note="no OCC equivalent; constraints hold to 1e-10 in OCC"))


# ---------------------------------------------------------------------------------------- demo
def test_render_manipulation_demo(tmp_path):
    pytest.importorskip("matplotlib")
    from occsurf.bridge import read_step
    from occsurf.examples.manipulation import render_manipulation_demo

    paths = render_manipulation_demo(tmp_path / "demo")
    assert [p.name for p in paths] == ["manipulation_curve.png", "manipulation_surface.png", "manipulation.step"]
    for png in paths[:2]:
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 50_000
    model = read_step(paths[2])
    assert len(model.faces) == 1 and len(model.edges) == 1
    assert model.faces[0].name == "surface with a dragged point"
    curve = model.edges[0].curve
    assert curve.degree == 3 and curve.n_poles == 10
