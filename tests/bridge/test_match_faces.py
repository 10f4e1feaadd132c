"""Matching two faces of a model along their shared edge (issue 29, items 3-4), measured by OCC.

Every "after" value is OCC's: ``LocalAnalysis_SurfaceContinuity`` (``G1Angle``, ``C0Value``) at the
points of the edge on the unchanged face, the changed face's surface found by
``GeomAPI_ProjectPointOnSurf`` (:func:`occsurf.bridge.modeling.joints.assess_joint`), on the model
written to STEP and read back; validity by ``BRepCheck_Analyzer``. Tolerances: the issue's G1
0.01 deg; on the closed-form pair (whose target side lies in the face's spline space) OCC measures
1e-13 deg, so 1e-9 deg is asked there.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from OCP.BRepBuilderAPI import BRepBuilderAPI_Sewing
from OCP.BRepCheck import BRepCheck_Analyzer

from occsurf.algorithms.errors import InvalidGeometryError
from occsurf.algorithms.kernel.surface import BSplineSurface
from occsurf.algorithms.manipulation import ConstraintError
from occsurf.bridge.conversion.splines import make_face
from occsurf.bridge.exchange.step_iges import read_step, write_step
from occsurf.bridge.modeling.joints import assess_joint
from occsurf.bridge.modeling.matching import match_faces
from occsurf.bridge.modeling.model_edits import ModelEdits
from occsurf.bridge.modeling.refill_loop import SewnModel, model_faces
from tests.algorithms.test_matching import CUBIC, _knots, _pair

from .test_cli import REALDATA, run_cli


def _model(*surfaces: BSplineSurface):
    sew = BRepBuilderAPI_Sewing(1e-6)
    for s in surfaces:
        sew.Add(make_face(s))
    sew.Perform()
    return sew.SewedShape()


def _occ_edge(shape, i: int, j: int) -> tuple[float, float]:
    """OCC's largest C0 gap and G1 angle along the edge(s) of faces i and j of ``shape``."""
    from OCP.BRep import BRep_Tool

    m = ModelEdits(shape)
    g0 = g1 = 0.0
    for e in m.shared_edges(i, j):
        a, b = assess_joint(e, m.faces[j], [BRep_Tool.Surface_s(m.faces[i])])
        g0, g1 = max(g0, a), max(g1, b)
    return g0, g1


@pytest.mark.parametrize("continuity", ["G1", "G2"])
def test_pair_matched_and_round_tripped(tmp_path: Path, continuity: str):
    T, S = _pair(3.0, nu_s=7)
    shape = _model(T, S)
    assert _occ_edge(shape, 1, 0)[1] > 2.9
    rep, out = match_faces(shape, 1, 0, continuity)
    assert rep.met and rep.valid and rep.side == "u0" and rep.target_side == "u0"
    assert rep.g1_before_deg > 2.9 and rep.g1_max_deg < 1e-9 and rep.g0_max < 1e-9
    if continuity == "G2":
        assert rep.g2_max_rel <= 0.01
    path = tmp_path / "m.step"
    write_step(path, out)
    back = read_step(path).shape
    assert len(model_faces(back)) == 2 and BRepCheck_Analyzer(back).IsValid()
    g0, g1 = _occ_edge(back, 1, 0)
    assert g1 < 1e-9 and g0 < 1e-7  # STEP's 10 digits on a unit-sized pair


def test_bad_requests_are_named():
    T, S = _pair(3.0, nu_s=7)
    # a third face beside S's far side, sharing no edge with T
    P = S.control_points
    Q = np.zeros((4, 4, 3))
    for i in range(4):
        Q[i] = P[-1] + i * (P[-1] - P[-2])
    shape = _model(T, S, BSplineSurface((3, 3), (CUBIC, CUBIC), Q))
    with pytest.raises(InvalidGeometryError, match="share no edge"):
        match_faces(shape, 2, 0)
    with pytest.raises(InvalidGeometryError, match="out of range"):
        match_faces(shape, 1, 7)
    with pytest.raises(InvalidGeometryError, match="same face"):
        match_faces(shape, 1, 1)
    with pytest.raises(InvalidGeometryError, match="continuity"):
        match_faces(shape, 1, 0, "C1")
    T30, S30 = _pair(30.0, nu_s=7)
    with pytest.raises(InvalidGeometryError, match="sharp"):
        match_faces(_model(T30, S30), 1, 0)
    lin = BSplineSurface((1, 3), ([0, 0, 0.5, 1, 1], _knots(4)), S.control_points[[0, 1, 2]])
    with pytest.raises(ConstraintError, match="degree >= 2"):
        match_faces(_model(T, lin), 1, 0, "G2")


@pytest.mark.skipif(not REALDATA.is_dir(), reason=f"public CAD files not present at {REALDATA}")
def test_bearing_faces_matched_by_occs_measure(tmp_path: Path):
    """Bearing faces 0 and 2 meet at 0.048 deg (breaking CATIA's 0.01): G1 to 1e-9 deg after."""
    from occsurf.bridge import read_iges

    shape = read_iges(REALDATA / "occt__bearing.iges").shape
    rep, out = match_faces(shape, 0, 2, "G1")
    assert rep.g1_before_deg > 0.04
    assert rep.met and rep.valid and rep.g1_max_deg < 1e-6 and rep.g0_max < 1e-9
    a, b = rep.faces_out  # the changed model (sewn: its faces renumbered)
    assert _occ_edge(out, a, b)[1] < 1e-6
    write_step(tmp_path / "b.step", out)  # (STEP renumbers the faces: only counted and checked there)
    back = read_step(tmp_path / "b.step").shape
    assert len(model_faces(back)) == len(model_faces(shape)) and BRepCheck_Analyzer(back).IsValid()


def test_cli_match(tmp_path: Path):
    T, S = _pair(3.0, nu_s=7)
    src = tmp_path / "pair.step"
    write_step(src, _model(T, S))
    out = tmp_path / "out.step"
    proc = run_cli("match", str(src), "--face", "1", "--to", "0", "--continuity", "G2", "--out", str(out), "--json")
    assert proc.returncode == 0, proc.stderr
    doc = json.loads(proc.stdout)
    for key in ("face", "target", "continuity", "g0_max", "g1_max_deg", "g2_max_rel", "max_change", "knots_added",
                "opposite_g1_max_deg"):
        assert key in doc
    assert doc["face"] == 1 and doc["target"] == 0 and doc["g1_max_deg"] < 1e-9 and doc["g2_max_rel"] <= 0.01
    assert out.is_file() and _occ_edge(read_step(out).shape, 1, 0)[1] < 1e-9
    bad = tmp_path / "bad.step"
    for args, words in ((("--face", "1", "--to", "5"), "out of range"), (("--face", "1", "--to", "1"), "same face"),
                        (("--face", "1", "--to", "0", "--continuity", "G9"), "invalid choice")):
        proc = run_cli("match", str(src), *args, "--out", str(bad))
        assert proc.returncode == 2 and words in proc.stderr
        assert len(proc.stderr.strip().splitlines()) == 1 and "Traceback" not in proc.stderr
        assert not bad.exists()


def _three_faces(kink_ts: float, kink_sq: float):
    """T | S | Q: the T-S edge kinked by ``kink_ts`` degrees, S-Q by ``kink_sq`` (about the edge)."""
    T, S = _pair(kink_ts, nu_s=7)
    P = S.control_points
    d = P[-1] - P[-2]
    a = np.radians(kink_sq)
    d = np.stack([d[:, 0] * np.cos(a) - d[:, 2] * np.sin(a), d[:, 1], d[:, 0] * np.sin(a) + d[:, 2] * np.cos(a)], 1)
    Q = np.stack([P[-1] + i * d for i in range(4)])
    return _model(T, S, BSplineSurface((3, 3), (CUBIC, S.knots[1]), Q))


@pytest.mark.parametrize("preset, kinks", [("catia", (0.2, 2.0)), ("mechanical", (2.0, 10.0))])
def test_repair_fixes_the_smooth_edge_and_leaves_the_crease(tmp_path: Path, preset: str, kinks):
    """catia: 0.2 deg breaks G1 (0.01) and 2 deg is a crease (>= 0.5); mechanical: 2 deg breaks G1
    (0.5), 10 deg is a crease (>= 5). Under catia the pair's curvature jump (~100 %) cannot be
    closed within the 1e-3 change limit: G2 is refused, G1 done, the edge still breaks G2."""
    from occsurf.bridge.audit.repair import repair_model, write_repair_page

    shape = _three_faces(*kinks)
    before_sq = _occ_edge(shape, 1, 2)[1]
    assert abs(_occ_edge(shape, 1, 0)[1] - kinks[0]) < 0.05 * kinks[0] and before_sq > 0.9 * kinks[1]
    # 2 deg over a row spacing of 1/3 asks ~0.012 of change: above the default 1e-3 of the size
    # (0.0042), refused there, done with a larger limit
    if preset == "mechanical":
        refused, _ = repair_model(shape, preset)
        assert refused.repaired == 0 and "would move by" in (refused.edges[0].reason or "")
    rep, out = repair_model(shape, preset, max_change=0.05 if preset == "mechanical" else None)
    assert rep.edges_breaking_before == 1 and rep.repaired == 1
    [e] = rep.edges
    assert e.faces == (0, 1) and e.g1_after_deg is not None and e.g1_after_deg < 1e-9
    assert e.max_change is not None and e.max_change <= rep.max_change
    assert rep.worst_smooth_g1_after < 1e-6
    if preset == "mechanical":
        assert rep.edges_breaking_after == 0 and e.continuity == "G1"
    else:
        assert e.continuity == "G1" and "G2" in (e.reason or "G2 refused")
    # the check after, by its own measure, on the same two faces (the model after is numbered anew)
    assert e.g1_check_after_deg is not None and e.g1_check_after_deg < 1e-6 < e.g1_before_deg
    assert e.g2_rel_check_after is not None
    if preset == "mechanical":
        assert e.breaks_after is False
    else:  # the curvature jump stays (G2 refused): the edge still breaks CATIA's G2 %
        assert e.breaks_after is True and e.g2_rel_check_after > 1.0
    m = SewnModel(out)
    assert len(m.faces) == 3 and BRepCheck_Analyzer(out).IsValid()
    # the crease keeps its angle (S's rows next to it are held by preserve_opposite)
    sq = [_occ_edge(out, a, b)[1] for a in range(3) for b in range(a + 1, 3)]
    assert abs(max(sq) - before_sq) < 1e-6
    page = write_repair_page(rep, tmp_path / "rep", "three.step")
    text = page.read_text()
    assert "Before" in text and "After" in text and "repaired" in text


def test_cli_repair(tmp_path: Path):
    src = tmp_path / "three.step"
    write_step(src, _three_faces(0.2, 2.0))
    out = tmp_path / "fixed.step"
    proc = run_cli("repair", str(src), "--preset", "catia", "--out", str(out), "--json")
    assert proc.returncode == 0, proc.stderr
    doc = json.loads(proc.stdout)
    assert doc["edges_repaired"] == 1 and doc["worst_smooth_g1_after"] < 1e-6 and doc["faces_faired"] == 0
    assert doc["round_trip"] == {"faces_in": 3, "faces_out": 3, "valid": True}
    assert out.is_file() and (tmp_path / "fixed_report" / "index.html").is_file()
    # its G1 is repaired, its curvature jump is not (G2 refused): still breaking CATIA in the check after
    assert doc["edges_repaired_still_breaking"] == 1 and doc["edges"][0]["breaks_after"] is True
    proc = run_cli("repair", str(src), "--preset", "catia", "--out", str(out), "--in-process")
    assert proc.returncode == 0, proc.stderr
    assert "edges repaired 1 (1 of them still break catia in the check after), refused 0" in proc.stdout
    # mechanical, with room to move: repaired and no longer breaking, nothing said about it
    proc = run_cli("repair", str(src), "--preset", "mechanical", "--max-change", "0.05", "--out", str(out),
                   "--in-process")
    assert proc.returncode == 0, proc.stderr
    assert "edges repaired 1, refused 0" in proc.stdout and "still break" not in proc.stdout
    proc = run_cli("repair", str(src), "--preset", "nx", "--out", str(tmp_path / "x.step"))
    assert proc.returncode == 2 and "invalid choice" in proc.stderr and len(proc.stderr.strip().splitlines()) == 1


def test_fair_faces_and_repair_fairs_wiggles(tmp_path: Path):
    from occsurf.bridge.audit.repair import repair_model
    from occsurf.bridge.modeling.fairing import fair_faces
    from tests.algorithms.test_fairing import _rippled, _u_sign_changes

    S = _rippled()
    reps, out, numbering = fair_faces(make_face(S), [0], tol=0.01)
    [r] = reps
    assert r.status == "faired" and r.wiggles_after < r.wiggles_before and r.max_deviation <= 0.01
    assert BRepCheck_Analyzer(out).IsValid() and numbering == [0]
    from occsurf.bridge.conversion.splines import from_occ

    faired = from_occ(model_faces(out)[0], trims=False)
    assert _u_sign_changes(S).max() >= 4 and _u_sign_changes(faired).max() == 0
    rep, _ = repair_model(make_face(S), "catia", max_change=0.01)
    assert rep.faces_faired == 1 and rep.fairings[0]["face"] == 0
    with pytest.raises(InvalidGeometryError, match="out of range"):
        fair_faces(make_face(S), [3], tol=0.01)


def _with_smooth_neighbour():
    """T | S | Q as :func:`_three_faces` (T-S kinked 0.2 deg, S-Q a 2 deg crease), and W below S
    across S's side v0, a C1 continuation of it (W's poles S's reflected through its side)."""
    T, S = _pair(0.2, nu_s=7)
    P = S.control_points
    d = P[-1] - P[-2]
    a = np.radians(2.0)
    d = np.stack([d[:, 0] * np.cos(a) - d[:, 2] * np.sin(a), d[:, 1], d[:, 0] * np.sin(a) + d[:, 2] * np.cos(a)], 1)
    Q = BSplineSurface((3, 3), (CUBIC, S.knots[1]), np.stack([P[-1] + i * d for i in range(4)]))
    W = BSplineSurface((3, 3), S.knots, (2.0 * P[:, :1] - P)[:, ::-1])
    return _model(T, S, Q, W)


def test_strict_match_judges_each_other_edge_on_its_own():
    """Matching S to T moves S's side v0 off W: its edge to W breaks G1 while the worst of S's
    other edges (the crease to Q, held by preserve_opposite) stays what it was. A strict match
    is refused for the one edge, and nothing is changed."""
    from OCP.BRep import BRep_Tool

    from occsurf.bridge.modeling.matching import FaceMatcher

    shape = _with_smooth_neighbour()
    m = ModelEdits(shape)
    assert len(m) == 4 and m.shared_edges(1, 3) and m.shared_edges(1, 2) and not m.shared_edges(0, 3)
    assert _occ_edge(shape, 1, 3)[1] < 1e-6 and _occ_edge(shape, 1, 2)[1] > 1.9
    tolerances = [BRep_Tool.Tolerance_s(e) for f in model_faces(shape) for e in ModelEdits(f).edges(0)]
    matcher = FaceMatcher(m)
    rep = matcher.match(1, 0, "G1", strict=True, max_change=1.0, others_deg=0.01)
    assert rep.refused is not None and "edge to face 3" in rep.refused, rep.refused
    # judged by the worst of the other edges, the change would have passed
    assert rep.opposite_g1_before_deg > 1.9 and rep.opposite_g1_max_deg <= rep.opposite_g1_before_deg + 1e-6
    assert m.version == [0, 0, 0, 0] and m.faces[1] is m.model.faces[1]
    # not strict: made, and OCC's own measure on the result finds the S-W edge broken
    rep = matcher.match(1, 0, "G1")
    assert rep.refused is None and rep.valid and m.version[1] == 1
    out, numbering = m.shape()
    assert _occ_edge(out, numbering[1], numbering[3])[1] > 0.01 and _occ_edge(out, numbering[1], numbering[0])[1] < 0.01
    # the caller's model is not touched (ModelEdits works on a copy)
    assert [BRep_Tool.Tolerance_s(e) for f in model_faces(shape) for e in ModelEdits(f).edges(0)] == tolerances


def test_repair_leaves_a_g1_edge_that_breaks_only_curvature_to_g2():
    """T-S without a kink is G1 (OCC: < 1e-6 deg) but jumps in curvature (~100 %): CATIA's preset
    flags only its G2. G2 would move S more than 1e-3 of the size, and a G1 match would change
    nothing the preset asks: the edge is refused, G1 never tried, the model unchanged."""
    from occsurf.bridge.audit.repair import repair_model

    shape = _three_faces(0.0, 2.0)
    assert _occ_edge(shape, 1, 0)[1] < 1e-6
    rep, out = repair_model(shape, "catia")
    [e] = rep.edges
    assert e.measures == ["g2_rel"] and e.status == "refused"
    assert e.reason is not None and "G2 face" in e.reason and "G1 face" not in e.reason
    assert rep.by_measure_before == {"g2_rel": 1} and rep.by_measure_after == {"g2_rel": 1} and rep.valid_after


def test_the_change_limit_is_on_a_faces_changes_together():
    """A face matched once (by c) and asked again with a limit below c is refused "in all": the
    second match alone moves it by ~0, but the face now lies c from its first surface."""
    from occsurf.bridge.modeling.matching import FaceMatcher

    m = ModelEdits(_three_faces(0.2, 2.0))
    matcher = FaceMatcher(m)
    assert m.change(1) == 0.0
    first = matcher.match(1, 0, "G1")
    c = m.change(1)
    assert first.refused is None and 0.5 * first.max_change < c < 2.0 * first.max_change
    again = matcher.match(1, 0, "G1", strict=True, max_change=0.5 * c)
    assert again.max_change < 1e-3 * c and again.total_change >= c * (1 - 1e-9)
    assert again.refused is not None and "in all" in again.refused and m.version[1] == 1
    ok = matcher.match(1, 0, "G1", strict=True, max_change=2.0 * c)
    assert ok.refused is None and m.version[1] == 2


def _trimmed_across_pair(kink_deg: float = 3.0):
    """Face 0: the plane z = 0 as a bicubic B-spline over [0, 1]^2 trimmed to the triangle x >= y
    (its diagonal edge crosses the surface's interior); face 1: a bicubic plane through the
    diagonal on the other side, tilted by ``kink_deg`` about it. Sewn: they share the diagonal."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeEdge, BRepBuilderAPI_MakeFace, BRepBuilderAPI_MakeWire
    from OCP.BRepLib import BRepLib
    from OCP.Geom2d import Geom2d_Line
    from OCP.gp import gp_Dir2d, gp_Pnt2d

    from occsurf.bridge.conversion.splines import to_occ

    g = np.linspace(0, 1, 4)
    X, Y = np.meshgrid(g, g, indexing="ij")
    A = BSplineSurface((3, 3), (CUBIC, CUBIC), np.stack([X, Y, 0 * X], -1))
    geom = to_occ(A)

    def edge(p, q):
        L = float(np.hypot(q[0] - p[0], q[1] - p[1]))
        e = BRepBuilderAPI_MakeEdge(Geom2d_Line(gp_Pnt2d(*p), gp_Dir2d(q[0] - p[0], q[1] - p[1])), geom, 0.0, L).Edge()
        BRepLib.BuildCurves3d_s(e)
        return e

    wire = BRepBuilderAPI_MakeWire(edge((0, 0), (1, 0)), edge((1, 0), (1, 1)), edge((1, 1), (0, 0))).Wire()
    face_a = BRepBuilderAPI_MakeFace(geom, wire, True).Face()
    th = np.radians(kink_deg)
    d = np.array([-np.cos(th) / np.sqrt(2), np.cos(th) / np.sqrt(2), np.sin(th)])
    S, W = np.meshgrid(g, g, indexing="ij")
    B = BSplineSurface((3, 3), (CUBIC, CUBIC), np.stack([S, S, 0 * S], -1) + 0.5 * W[..., None] * d)
    sew = BRepBuilderAPI_Sewing(1e-6)
    sew.Add(face_a)
    sew.Add(make_face(B))
    sew.Perform()
    return sew.SewedShape()


@pytest.mark.parametrize("continuity", ["G0", "G1"])
def test_face_trimmed_across_its_surface_is_matched_along_the_edge_inside_it(tmp_path: Path, continuity: str):
    """The edge runs inside face 0's surface (no side carries it): the match is made along the
    edge's p-curve (``match_along``), measured by OCC along the edge and round-tripped through STEP."""
    shape = _trimmed_across_pair(3.0)
    assert _occ_edge(shape, 0, 1)[1] > 2.9
    rep, out = match_faces(shape, 0, 1, continuity)
    assert rep.side == "inside" and rep.valid and rep.met
    assert any("inside face 0's surface" in n for n in rep.notes)
    if continuity == "G1":
        assert rep.g1_before_deg > 2.9 and rep.g1_max_deg <= 0.01
    assert rep.g0_max <= 1e-6
    write_step(tmp_path / "m.step", out)
    back = read_step(tmp_path / "m.step").shape
    assert len(model_faces(back)) == 2 and BRepCheck_Analyzer(back).IsValid()
    if continuity == "G1":
        assert _occ_edge(back, 0, 1)[1] <= 0.01
    with pytest.raises(InvalidGeometryError, match="runs inside face 0's surface.*G2 needs it along a side"):
        match_faces(shape, 0, 1, "G2")


@pytest.mark.skipif(not REALDATA.is_dir(), reason=f"public CAD files not present at {REALDATA}")
def test_linkrods_face_trimmed_inside_its_surface_matched_by_occs_measure(tmp_path: Path):
    """OCCT linkrods faces 35 and 34 meet at 0.052 deg along an edge 1.2e-4 inside face 35's
    B-spline surface (no side carries it): matched G1 inside, OCC measures 1e-8 deg after."""
    shape = read_step(REALDATA / "occt__linkrods.step").shape
    rep, out = match_faces(shape, 35, 34, "G1")
    assert rep.side == "inside" and rep.converted is None
    assert rep.g1_before_deg > 0.05 and rep.met and rep.valid and rep.g1_max_deg < 1e-6 and rep.g0_max < 1e-9
    assert rep.opposite_g1_max_deg <= rep.opposite_g1_before_deg + 1e-6  # its other edges no worse
    a, b = rep.faces_out
    assert _occ_edge(out, a, b)[1] < 1e-6
    write_step(tmp_path / "l.step", out)
    back = read_step(tmp_path / "l.step").shape
    assert len(model_faces(back)) == len(model_faces(shape)) and BRepCheck_Analyzer(back).IsValid()
