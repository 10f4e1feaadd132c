"""Edge continuity (:mod:`occsurf.bridge.quality.continuity`) on closed-form models, presets,
violations, the JSON contract and bad input.

Closed forms (see ``continuity_models``): the measures are exact up to round-off of the surface
evaluation (a few ulps of the coordinates, ~1e-15 on unit-sized models), so 1e-12 is asserted for
distances and curvatures, 1e-9 degrees for angles (the arctan2 of a ~1e-16 cross product).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from occsurf.algorithms.errors import InvalidGeometryError
from occsurf.bridge.quality import PRESETS, EdgeReport, Thresholds, check_edges, edge_continuity

from . import continuity_models as cm

TOL = 1e-12
ANGLE_TOL = 1e-9
ISSUE_KEYS = {"faces", "midpoint", "matched", "g0_max", "g1_max_deg", "g2_max", "g2_max_rel", "worst_point"}


def _one(shape, **kw) -> EdgeReport:
    """The one edge between the two faces (faces 0 and 1)."""
    reports = [r for r in edge_continuity(shape, **kw) if r.faces[0] != r.faces[1]]
    assert len(reports) == 1, reports
    assert sorted(reports[0].faces) == [0, 1]
    return reports[0]


@pytest.mark.parametrize("build, matched", [(cm.sewn, "topology"), (cm.loose, "geometry")])
def test_coplanar_joint_is_all_zero(build, matched) -> None:
    r = _one(build("coplanar"), g3=True)
    assert r.matched == matched
    assert r.g0_max <= TOL and r.g1_max_deg <= ANGLE_TOL and r.g2_max <= TOL and r.g3_max <= TOL
    assert r.g2_max_rel == 0.0 and r.classification == "G2" and not r.normal_flip
    np.testing.assert_allclose(r.midpoint, [0.0, 0.5, 0.0], atol=TOL)
    assert r.length == pytest.approx(1.0, abs=1e-12)


@pytest.mark.parametrize("gap", [0.01, 0.003])
def test_offset_joint_has_the_gap(gap) -> None:
    sewn = _one(cm.sewn("offset", gap, tol=2 * gap))
    loose = _one(cm.loose("offset", gap), match_tol=2 * gap)
    for r in (sewn, loose):
        assert r.g0_max == pytest.approx(gap, abs=TOL)
        assert r.g1_max_deg <= ANGLE_TOL
        assert r.classification == "gap"
    assert (sewn.matched, loose.matched) == ("topology", "geometry")
    # below the matching tolerance the loose faces are not matched, and the result says so
    none = edge_continuity(cm.loose("offset", gap), match_tol=gap / 2)
    assert len(none) == 0 and any("nothing to check" in w for w in none.warnings)


@pytest.mark.parametrize("angle", [30.0, 5.0, 0.2])
def test_crease_angle(angle) -> None:
    for build in (cm.sewn, cm.loose):
        r = _one(build("crease", angle))
        assert r.g1_max_deg == pytest.approx(angle, abs=ANGLE_TOL)
        assert r.g0_max <= TOL
        assert r.classification == ("sharp" if angle >= PRESETS["catia"].sharp_deg else "G0")


@pytest.mark.parametrize("radius", [2.0, 0.25, 40.0])
def test_plane_tangent_to_cylinder(radius) -> None:
    r = _one(cm.sewn("cylinder", radius), g3=True)
    assert r.g0_max <= TOL * radius and r.g1_max_deg <= ANGLE_TOL
    assert r.g2_max == pytest.approx(1.0 / radius, rel=1e-12)
    assert r.g2_max_rel == pytest.approx(100.0, rel=1e-12)
    assert r.g3_max <= TOL / radius**2  # both sections have constant curvature
    assert r.g2_gap_occ_max == pytest.approx(0.5 / radius, rel=1e-12)  # OCC's measure: half the jump
    assert r.classification == "G1"
    assert r.evaluators == ("analytic", "analytic")


def test_cylinder_loose_faces_have_opposite_normals() -> None:
    """Built separately, the plane's normal is +z and the cylinder's -z at the joint: a flip. The
    shell made by sewing reverses one face, so there is none."""
    loose = _one(cm.loose("cylinder", 2.0))
    sewn = _one(cm.sewn("cylinder", 2.0))
    assert loose.normal_flip and not sewn.normal_flip
    assert loose.g1_max_deg <= ANGLE_TOL  # measured with the flip corrected
    assert loose.g2_max == pytest.approx(0.5, rel=1e-12)
    kinds = [v.measure for v in check_edges([loose], "mechanical")]
    assert kinds == ["normal_flip"]


@pytest.mark.parametrize("c", [0.5, 2.0])
def test_cubic_blend_is_g2_with_known_g3(c) -> None:
    """``z = c x^3`` meets ``z = 0`` with equal curvature (0); the curvature derivative jumps by 6 c."""
    for build in (cm.sewn, cm.loose):
        r = _one(build("cubic", c), g3=True)
        assert r.g0_max <= TOL and r.g1_max_deg <= ANGLE_TOL and r.g2_max <= TOL
        assert r.g3_max == pytest.approx(6 * c, rel=1e-12)
        assert r.classification == "G2"
        assert r.evaluators[1] == "bspline" or r.evaluators[0] == "bspline"
    assert _one(cm.sewn("cubic", c)).g3_max is None  # not requested


def test_presets_and_thresholds() -> None:
    assert (PRESETS["catia"].g0, PRESETS["catia"].g1_deg, PRESETS["catia"].g2_rel) == (0.001, 0.01, 2.0)
    assert PRESETS["class-a"].g1_deg < PRESETS["catia"].g1_deg < PRESETS["mechanical"].g1_deg
    assert PRESETS["mechanical"].g2_rel is None
    r = _one(cm.sewn("cylinder", 2.0))
    assert [v.measure for v in check_edges([r], "catia")] == ["g2_rel"]
    assert check_edges([r], "mechanical") == []
    mine = PRESETS["catia"].replace(g2_rel=150.0)
    assert mine.name == "catia+custom" and check_edges([r], mine) == []
    crease = _one(cm.sewn("crease", 0.2))
    assert [v.measure for v in check_edges([crease], "catia")] == ["g1"]  # 0.2 deg: below sharp
    assert check_edges([_one(cm.sewn("crease", 30.0))], "catia") == []  # a crease by design
    gap = _one(cm.sewn("offset", 0.01, tol=0.02))
    v = check_edges([gap], Thresholds(g0=0.005))
    assert [x.measure for x in v] == ["g0"] and v[0].value == pytest.approx(0.01) and v[0].limit == 0.005
    assert "faces 0-1" in v[0].message or "faces 1-0" in v[0].message


def test_worst_point_lies_on_the_edge_where_the_defect_is() -> None:
    # a twisted second face: the gap grows linearly along y, worst at y = 1
    r = _one(cm.sewn("crease", 0.2))
    assert r.worst_point[0] == pytest.approx(0.0, abs=1e-12) and 0.0 <= r.worst_point[1] <= 1.0
    gap = _one(cm.loose("offset", 0.01), match_tol=0.02)
    assert set(gap.worst_points) == {"g0", "g1", "g2", "g2_rel"}


def test_json_contract() -> None:
    result = edge_continuity(cm.sewn("cylinder", 2.0), g3=True)
    data = json.loads(json.dumps(result.to_json()))
    assert ISSUE_KEYS <= set(data[0])
    edge = [d for d in data if d["faces"][0] != d["faces"][1]][0]
    assert edge["matched"] == "topology" and len(edge["midpoint"]) == 3 and len(edge["worst_point"]) == 3
    assert edge["g2_max"] == pytest.approx(0.5) and edge["classification"] == "G1"
    assert result.match_tol is not None and result.thresholds.name == "catia"
    assert result.stats["topology"] == 1


def test_geometry_matching_is_reported_with_its_tolerance() -> None:
    result = edge_continuity(cm.loose("coplanar"))
    assert result.match_tol == pytest.approx(1e-4 * math.sqrt(2**2 + 1), rel=1e-6)
    assert result.stats["geometry"] == 1 and result.stats["topology"] == 0
    assert edge_continuity(cm.loose("coplanar"), loose=False) == []


@pytest.mark.parametrize("kw, name", [({"samples": 2}, "samples"), ({"samples": 3.5}, "samples"),
                                      ({"match_tol": -1.0}, "match_tol"), ({"match_tol": float("nan")}, "match_tol"),
                                      ({"preset": "rhino"}, "preset")])
def test_bad_arguments(kw, name) -> None:
    with pytest.raises(InvalidGeometryError, match=name):
        edge_continuity(cm.sewn("coplanar"), **kw)


def test_bad_thresholds() -> None:
    with pytest.raises(InvalidGeometryError, match="g1_deg"):
        Thresholds(g1_deg=-1.0)
    with pytest.raises(InvalidGeometryError, match="model"):
        edge_continuity("not a shape")


# ---------------------------------------------------------------------------------------- search
def _bump_face(d: float):
    """``z = d b(y)`` over ``0 <= x <= 1``, ``b(y) = 3 y (1 - y)^2`` (cubic Bezier 0, 1, 0, 0): largest,
    4/9, at ``y = 1/3``, between the samples of a coarse grid."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace
    from OCP.Geom import Geom_BSplineSurface

    from occsurf.bridge._occ import int_array, pnt_array2, real_array

    P = np.zeros((2, 4, 3))
    for i in range(2):
        for j, z in enumerate((0.0, d, 0.0, 0.0)):
            P[i, j] = (i, j / 3, z)
    s = Geom_BSplineSurface(pnt_array2(P), real_array([0.0, 1.0]), real_array([0.0, 1.0]),
                            int_array([2, 2]), int_array([4, 4]), 1, 3)
    return BRepBuilderAPI_MakeFace(s, 1e-7).Face()


def test_worst_point_search_finds_the_maximum_between_samples() -> None:
    from OCP.BRepBuilderAPI import BRepBuilderAPI_Sewing

    d = 0.01
    sew = BRepBuilderAPI_Sewing(d)
    sew.Add(cm.face_a())
    sew.Add(_bump_face(d))
    sew.Perform()
    shell = sew.SewedShape()
    coarse = _one(shell, samples=5, refine=0)
    fine = _one(shell, samples=5, refine=30)
    brute = _one(shell, samples=20001, refine=0)
    assert coarse.matched == fine.matched == "topology"
    assert coarse.g0_max < 4 * d / 9 - 1e-3 * d  # the samples miss the top
    # the sewn edge's p-curves agree within the sewing tolerance only (same-parameter), so the gap
    # is the vertical 4/9 d up to ~1e-4 relative; the search must find the brute-force maximum
    assert fine.g0_max == pytest.approx(4 * d / 9, rel=1e-3)
    assert fine.g0_max == pytest.approx(brute.g0_max, rel=1e-8)
    np.testing.assert_allclose(fine.worst_points["g0"][:2], [0.0, 1 / 3], atol=1e-2)
    assert fine.samples > coarse.samples == 5
    assert fine.classification == "gap"


# ---------------------------------------------------------------------------------------- bad input
def test_degenerate_edges_and_seams_of_a_sphere() -> None:
    import cadquery as cq

    sphere = cq.Solid.makeSphere(2.0, angleDegrees1=-90, angleDegrees2=90).wrapped
    result = edge_continuity(sphere)
    kinds = sorted(r.classification for r in result)
    assert kinds == ["degenerate", "degenerate", "seam"]  # two poles, one seam
    for r in result:
        if r.classification == "degenerate":
            assert r.error and "degenerated" in r.error and math.isnan(r.g0_max)
            assert json.loads(json.dumps(r.to_json()))["g0_max"] is None
        else:  # the seam closes smoothly
            assert r.g0_max <= 1e-12 and r.g1_max_deg <= 1e-6 and r.g2_max_rel <= 1e-6
    assert check_edges(result, "class-a") == []


def test_a_face_that_cannot_be_evaluated_spares_the_others(monkeypatch) -> None:
    import cadquery as cq

    from occsurf.bridge.conversion import occ_evaluators as _evaluators

    box = cq.Workplane().box(10, 8, 6).edges("|Z").fillet(2.0).val().wrapped
    real = _evaluators._analytic_fn

    def broken(s):
        fn = real(s)
        if type(s).__name__ == "Geom_CylindricalSurface":
            def fail(u, v, order):
                raise RuntimeError("cannot evaluate this cylinder")
            return fail
        return fn

    monkeypatch.setattr(_evaluators, "_analytic_fn", broken)
    result = edge_continuity(box)
    bad = [r for r in result if r.error]
    good = [r for r in result if not r.error]
    assert len(bad) == 16 and len(good) == 8  # every edge of the 4 fillets; the box's own 8 edges
    for r in bad:
        assert r.classification == "degenerate" and "could not be evaluated" in r.error
        assert "cannot evaluate this cylinder" in r.error
    assert all(r.classification == "sharp" and r.g1_max_deg == pytest.approx(90.0) for r in good)
    assert any("could not be evaluated" in w for w in result.warnings)


def test_surface_with_no_vectorised_form_goes_through_occ() -> None:
    """A face on an offset surface (no closed form here) is evaluated by OCC point by point."""
    from OCP.BRep import BRep_Builder
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace
    from OCP.Geom import Geom_OffsetSurface, Geom_Plane
    from OCP.gp import gp_Ax3, gp_Dir, gp_Pnt
    from OCP.TopoDS import TopoDS_Compound

    plane = Geom_Plane(gp_Ax3(gp_Pnt(0, 0, -0.25), gp_Dir(0, 0, 1), gp_Dir(1, 0, 0)))
    face_b = BRepBuilderAPI_MakeFace(Geom_OffsetSurface(plane, 0.25), 0.0, 1.0, 0.0, 1.0, 1e-7).Face()
    comp = TopoDS_Compound()
    bld = BRep_Builder()
    bld.MakeCompound(comp)
    bld.Add(comp, cm.face_a())
    bld.Add(comp, face_b)
    result = edge_continuity(comp)
    r = _one(comp)
    assert sorted(r.evaluators) == ["analytic", "occ"] and result.stats["occ_evaluated_faces"] == 1
    assert r.g0_max <= TOL and r.g1_max_deg <= ANGLE_TOL and r.classification == "G2"


def test_model_without_shared_edges() -> None:
    result = edge_continuity(cm.face_a())
    assert result == [] and result.stats["free_edges"] == 4
    assert any("no shared edges" in w and "nothing to check" in w for w in result.warnings)
    far = edge_continuity(cm.loose("offset", 0.5))  # 0.5 apart: beyond the default match_tol
    assert far == [] and far.stats["unmatched_free_edges"] == 8


# ---------------------------------------------------------------------------------------- options
def test_tolerances_are_read_at_call_time() -> None:
    from occsurf.algorithms import tolerances

    shape = cm.loose("offset", 0.01)
    assert edge_continuity(shape) == []  # 0.01 apart > 1e-4 of the diagonal (~0.02)
    with tolerances.override(CONTINUITY_MATCH_RTOL=0.01):  # 0.022: matches the one joint
        wide = edge_continuity(shape)
    assert len(wide) == 1 and wide.match_tol == pytest.approx(0.01 * wide.stats["model_size"])
    with tolerances.override(CONTINUITY_SAMPLES=7, CONTINUITY_REFINE_ITERATIONS=0):
        r = _one(cm.sewn("cylinder", 2.0))
    assert r.samples == 7
    with tolerances.override(CONTINUITY_CURVATURE_FLOOR=1e3):  # 1/R = 0.5 now counts as flat
        assert _one(cm.sewn("cylinder", 2.0)).g2_max_rel == 0.0


def test_chosen_face_pairs() -> None:
    import cadquery as cq

    box = cq.Workplane().box(10, 8, 6).edges("|Z").fillet(2.0).val().wrapped
    every = edge_continuity(box)
    pair = every[0].faces
    only = edge_continuity(box, face_pairs=[pair[::-1]])
    assert [r.faces for r in only] == [pair]
    assert edge_continuity(box, face_pairs=[]) == []
    with pytest.raises(InvalidGeometryError, match="face_pairs"):
        edge_continuity(box, face_pairs=[(0, 99)])
    with pytest.raises(InvalidGeometryError, match="refine"):
        edge_continuity(box, refine=-1)


# ---------------------------------------------------------------------------------------- batches
def test_batched_evaluation_matches_each_surface(monkeypatch) -> None:
    """The stacked evaluation (NumPy and numba paths) gives each face's own partials, at random
    parameters, at knots (where the stacked span search must not slip) and beyond a periodic end."""
    from pathlib import Path

    from occsurf.algorithms import _numba_kernels as nk
    from occsurf.bridge import read_step
    from occsurf.bridge.quality import _batch
    from occsurf.bridge.quality._pairs import collect_faces

    root = Path(__file__).resolve().parents[2] / "step_samples"
    models = [read_step(p) for p in sorted(root.glob("*.step"))[:4]]
    rng = np.random.default_rng(7)
    for model in models:
        _, faces = collect_faces(model)
        evs = [f.evaluator for f in faces]
        fid, u, v = [], [], []
        for f, ev in enumerate(evs):
            if ev is None or ev.spline is None:
                continue
            (u0, u1), (v0, v1) = ev.spline.domain
            ku = np.unique(ev.spline.knots[0][(ev.spline.knots[0] >= u0) & (ev.spline.knots[0] <= u1)])
            uu = np.r_[rng.uniform(u0, u1, 20), ku, np.full(ku.size, 0.5 * (u0 + u1))]
            vv = np.r_[rng.uniform(v0, v1, 20), np.full(ku.size, 0.5 * (v0 + v1)), rng.uniform(v0, v1, ku.size)]
            fid += [f] * uu.size
            u.append(uu)
            v.append(vv)
        if not fid:
            continue
        fid, u, v = np.array(fid), np.concatenate(u), np.concatenate(v)
        ref = np.concatenate([evs[f].spline.derivatives(u[fid == f], v[fid == f], 2) for f in np.unique(fid)])
        order = np.argsort(fid, kind="stable")
        batch = _batch.SurfaceBatch(evs)
        for use_numba in (False, True):
            monkeypatch.setattr(_batch, "_use_numba", lambda n, flag=use_numba: flag and nk.load() is not None)
            D, errors = batch.derivatives(fid, u, v, 2)
            assert not errors
            # the partials the measures use (i + j <= 2); same arithmetic in other summation orders
            # (numba fuses the quotient rule of rational faces): round-off of each partial's scale
            for i, j in ((0, 0), (1, 0), (0, 1), (2, 0), (1, 1), (0, 2)):
                scale = np.abs(ref[:, i, j]).max()
                np.testing.assert_allclose(D[order][:, i, j], ref[:, i, j], rtol=0, atol=1e-12 * scale)


def test_a_missing_pcurve_is_replaced_by_projection(monkeypatch) -> None:
    """Without a p-curve on one face, that face's (u, v) come from projecting the other face's
    points: the same measures as with both p-curves (the exact feet on these surfaces)."""
    from occsurf.bridge.quality import _pairs

    ref = {tuple(sorted(r.faces)): r for r in edge_continuity(cm.sewn("cylinder", 2.0))}
    real = _pairs._pcurve

    def no_pcurve_on_the_cylinder(edge, face):
        from OCP.BRep import BRep_Tool

        if type(BRep_Tool.Surface_s(face)).__name__ == "Geom_CylindricalSurface":
            return None
        return real(edge, face)

    monkeypatch.setattr(_pairs, "_pcurve", no_pcurve_on_the_cylinder)
    got = {tuple(sorted(r.faces)): r for r in edge_continuity(cm.sewn("cylinder", 2.0))}
    r, s = got[(0, 1)], ref[(0, 1)]
    assert r.error is None and r.matched == "topology"
    assert r.g0_max <= 1e-12 and r.g1_max_deg <= 1e-6
    assert r.g2_max == pytest.approx(s.g2_max, rel=1e-9) and r.classification == s.classification


def _same_to_roundoff(a, b, rel: float = 1e-12) -> bool:
    """Equal structures whose floats agree to ``rel`` (NaN equal to NaN); everything else exactly."""
    if isinstance(a, float) and isinstance(b, float):
        return (math.isnan(a) and math.isnan(b)) or math.isclose(a, b, rel_tol=rel, abs_tol=0.0)
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(_same_to_roundoff(a[k], b[k], rel) for k in a)
    if isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)):
        return len(a) == len(b) and all(_same_to_roundoff(x, y, rel) for x, y in zip(a, b))
    return bool(a == b)


def _blocks_model(model: str):
    """``loose``: three faces along one line, matched by geometry (the cylinder's pair (0, 2), not
    the first, with opposite normals); ``sample``: a sewn model of ``step_samples``."""
    from pathlib import Path

    from occsurf.bridge import read_step

    if model == "loose":
        from OCP.BRep import BRep_Builder
        from OCP.TopoDS import TopoDS_Compound

        shape, builder = TopoDS_Compound(), BRep_Builder()
        builder.MakeCompound(shape)
        for face in (cm.face_a(), cm.face_b("crease", 10.0), cm.face_b("cylinder", 2.0)):
            builder.Add(shape, face)
        return shape
    return read_step(str(Path(__file__).resolve().parents[2] / "step_samples" / "swept_tube.step"))


@pytest.mark.parametrize("model", ["loose", "sample"])
def test_measures_in_blocks_equal_one_batch(monkeypatch, model) -> None:
    """The engine measures many requests in blocks of whole edges (``MEASURE_BLOCK``, for the
    check's memory on large models): the reports and sample values of one batch, to round-off.

    Every measure is pointwise; what a block can change is the last digit where NumPy's vectorised
    loops take an array's tail element by element (one g3 value of the tube at blocks of 7
    requests: 1 ulp). 1e-12 relative is asserted (values here are 1e-15..1e2, a few ulps of round-off
    is 1e-15 relative); the classifications and the structure exactly. The blocks are seen to be
    many, and each pair's dense samples (its orientation taken from all of them) in one block."""
    from occsurf.bridge.quality import _engine

    shape = _blocks_model(model)
    calls: list[tuple[frozenset[int], bool]] = []
    real = _engine.Engine._measure

    def spy(self, pid, t, set_flip, s, gap):
        calls.append((frozenset(int(p) for p in pid), set_flip))
        return real(self, pid, t, set_flip, s, gap)

    monkeypatch.setattr(_engine.Engine, "_measure", spy)

    def run(block: int):
        monkeypatch.setattr(_engine, "MEASURE_BLOCK", block)
        monkeypatch.setattr(_engine, "NUMBA_MIN_POINTS", 1)  # small blocks allowed (none here reaches numba's 4096)
        calls.clear()
        res = edge_continuity(shape, g3=True)
        points = [None if p is None else {k: np.asarray(v).tolist() for k, v in p.items()} for p in res.points]
        return [r.to_json() for r in res], points, list(calls)

    one, one_points, one_calls = run(10**9)
    blocks, block_points, block_calls = run(7)
    assert len(one) >= (3 if model == "loose" else 2)
    flip_blocks = [pids for pids, flip in block_calls if flip]
    assert len([c for c in one_calls if c[1]]) == 1 and len(flip_blocks) >= len(one)  # many blocks, a pair in each
    assert sorted(p for pids in flip_blocks for p in pids) == sorted(set().union(*flip_blocks))  # each pair once
    if model == "loose":
        assert {r["matched"] for r in one} == {"geometry"}
        assert [r["normal_flip"] for r in one] == [sorted(r["faces"]) == [0, 2] for r in one]
    assert [r["classification"] for r in blocks] == [r["classification"] for r in one]
    assert _same_to_roundoff(blocks, one)
    assert _same_to_roundoff(block_points, one_points)


def test_engine_blocks_with_given_side_2_parameters(monkeypatch) -> None:
    """``Engine.measure`` with the side-2 parameters given (``s``: a benchmark giving OCC and us the
    same points) and with a pair's requests in several runs under ``set_flip`` (then one block):
    the values of one batch, to round-off (as above); ``s`` of another length is refused."""
    from occsurf.bridge.quality import _engine
    from occsurf.bridge.quality import continuity as C
    from occsurf.bridge.quality._setup import build_engine

    monkeypatch.setattr(_engine, "NUMBA_MIN_POINTS", 1)
    for model in ("loose", "sample"):
        shape = _blocks_model(model)
        engine = build_engine(shape, g3=True).engine  # edge_continuity's set-up, with G3
        good = np.array([i for i, p in enumerate(engine.pairs) if C._why_not(engine, p) is None], dtype=np.intp)
        s01 = np.linspace(0.0, 1.0, 21)
        first = np.array([engine.pairs[i].first for i in good])
        last = np.array([engine.pairs[i].last for i in good])
        t = (first[:, None] + (last - first)[:, None] * s01).reshape(-1)
        pid = np.repeat(good, s01.size)
        monkeypatch.setattr(_engine, "MEASURE_BLOCK", 10**9)
        ref = engine.measure(pid, t, set_flip=True)
        backwards = engine.measure(pid[::-1], t[::-1], set_flip=True)  # each pair one run still, last first
        given_one = engine.measure(pid, t, s=ref["s"])
        monkeypatch.setattr(_engine, "MEASURE_BLOCK", 5)
        given = engine.measure(pid, t, s=ref["s"])
        mixed = np.r_[pid[::2], pid[1::2]]  # every pair in two runs: one block under set_flip
        assert _engine.Engine._blocks(mixed, True) == [0, mixed.size]
        lone = np.full(11, good[0])  # one pair's requests only (no place to cut): one block
        assert _engine.Engine._blocks(lone, True) == _engine.Engine._blocks(lone, False) == [0, 11]
        assert len(_engine.Engine._blocks(pid, True)) > 2
        for k in given_one:
            assert _same_to_roundoff(np.asarray(given[k]).tolist(), np.asarray(given_one[k]).tolist()), k
            assert _same_to_roundoff(np.asarray(backwards[k])[::-1].tolist(), np.asarray(ref[k]).tolist()), k
        with pytest.raises(ValueError, match="side-2 parameter"):
            engine.measure(pid, t, s=ref["s"][:-1])
