"""``fill_model(continuity='G2')`` and ``occsurf fill --continuity G2`` (issue 31), measured by OCC:
the relative jump of the normal curvature across every hole edge from OCC's principal curvatures
(``GeomLProp_SLProps``, :func:`occsurf.bridge.modeling.joints.assess_curvature`), G0 and G1 by
``LocalAnalysis_SurfaceContinuity``; OCC's own filler asked for curvature beside it.

The model is a 4-sided hole in a smooth ring (:func:`occsurf.examples.hole_models.ring_model`, no
bump): its neighbours are curvature continuous, so a G2 fill exists (the base surface).
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from occsurf.algorithms import tolerances
from occsurf.algorithms.errors import InvalidGeometryError


@pytest.fixture(scope="module")
def ring():
    from occsurf.bridge.conversion.splines import make_face
    from occsurf.bridge.modeling.fill import sew_faces
    from occsurf.examples.hole_models import ring_model

    return sew_faces([make_face(f, 1e-7) for f in ring_model(4, bump=0).faces])


@pytest.fixture(scope="module")
def filled(ring):
    from occsurf.bridge.modeling.fill import fill_model

    return fill_model(ring, continuity="G2"), fill_model(ring, continuity="G1")


def test_g2_fill_is_curvature_continuous_by_occ_s_measures(ring, filled) -> None:
    """Ours G2: curvature jump 0.21 % (target 1 %), G1 0.0013 deg, G0 2.4e-7 (the plate's target is
    1e-7 of the ring's size, met at its own samples). OCC's filler asked for curvature
    (GeomAbs_C1, see the xfail below) misses it: jump 177 %, G1 3.7 deg. The G1 fill of the same
    hole (the central split, exact boundary) leaves a jump of more than ten times ours."""
    from OCP.BRep import BRep_Tool

    from occsurf.bridge.modeling.fill import model_holes, neighbour_face
    from occsurf.bridge.modeling.joints import assess_curvature

    g2, g1 = filled
    (h,) = [h for h in g2.holes if h.status != "outer"]
    assert h.status == "filled" and h.continuity == "G2" and h.method == "plate", h.reason
    assert h.g2 is not None and h.g2 <= tolerances.FILL_FIT_G2_REL and len(h.side_g2) == 4
    assert h.g1 <= tolerances.FILL_FIT_ANGLE and h.g0 <= 1e-6
    assert h.occ_status == "ok" and h.occ_g2 is not None and h.occ_g2 > 10 * h.g2
    assert h.edge_asked == h.edge_continuity == ["G2"] * 4
    (k,) = [k for k in g1.holes if k.status != "outer"]
    assert k.continuity == "G1" and k.g2 is None and k.method == "central"
    assert k.edge_asked == k.edge_continuity == ["G1"] * 4
    holes = model_holes(ring)
    edges = holes.loops[k.index][0]
    surfs = [BRep_Tool.Surface_s(f) for f in k._fill_faces]
    floor = tolerances.CONTINUITY_CURVATURE_FLOOR / holes.size
    jumps = [assess_curvature(e, neighbour_face(holes.e2f, e), surfs, floor)[0] for e in edges]
    assert max(jumps) > 10 * h.g2, jumps


@pytest.mark.xfail(strict=True, reason="OCC defect: BRepFill_Filling passes GeomAbs_Shape's enum value on as the "
                   "constraint order (0..2), so GeomAbs_G2 (3) throws 'The continuity is not G0 G1 or G2'; "
                   "GeomAbs_C1 (2) is its curvature constraint")
def test_occ_filling_takes_geomabs_g2(ring) -> None:
    from OCP.BRepOffsetAPI import BRepOffsetAPI_MakeFilling
    from OCP.GeomAbs import GeomAbs_Shape

    from occsurf.bridge.modeling.fill import model_holes, neighbour_face

    holes = model_holes(ring)
    edges = holes.loops[[k for k, (_, outer) in enumerate(holes.loops) if not outer][0]][0]
    mk = BRepOffsetAPI_MakeFilling()
    for e in edges:
        mk.Add(e, neighbour_face(holes.e2f, e), GeomAbs_Shape.GeomAbs_G2, True)
    mk.Build()
    assert mk.IsDone()


def test_continuity_names_are_checked_and_the_cli_offers_the_same(ring) -> None:
    from occsurf.bridge.cli import build_parser
    from occsurf.bridge.modeling.fill import CONTINUITIES, fill_model

    with pytest.raises(InvalidGeometryError, match="continuity: expected one of auto, G1, G2, got 'G3'"):
        fill_model(ring, continuity="G3")
    sub = next(a for a in build_parser()._actions if getattr(a, "choices", None) and "fill" in a.choices)
    cont = next(a for a in sub.choices["fill"]._actions if a.dest == "continuity")
    assert tuple(cont.choices) == CONTINUITIES and cont.default == "auto"


def test_a_hole_is_filled_g1_by_default(ring) -> None:
    """``continuity='auto'`` (the default) follows the original per edge; a hole of the model had no
    face there, so it is the G1 central split, with no G2 numbers and no reason."""
    from occsurf.bridge.modeling.fill import fill_model

    (h,) = [h for h in fill_model(ring, compare_occ=False).holes if h.status != "outer"]
    assert h.status == "filled" and h.continuity == "auto" and h.method == "central" and h.reason is None
    assert h.g2 is None and h.side_g2 == [] and h.g1 <= tolerances.FILL_FIT_ANGLE
    assert h.edge_asked == h.edge_continuity == ["G1"] * 4


def test_cli_fills_g2_and_says_the_jump(tmp_path: Path, ring) -> None:
    """``occsurf fill --continuity G2``: the JSON carries ``continuity``, ``g2``, ``side_g2``,
    ``occ_g2``; the table says the jump in percent. An unknown continuity is one line, exit 2."""
    from occsurf.bridge.exchange.step_iges import write_step

    src = write_step(tmp_path / "ring.step", ring)
    cmd = [sys.executable, "-m", "occsurf.bridge.cli", "fill", str(src), "--out", str(tmp_path / "out.step"),
           "--continuity", "G2", "--no-pictures"]
    proc = subprocess.run(cmd + ["--json", "--jobs", "1"], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    (h,) = [h for h in json.loads(proc.stdout)["holes"] if h["status"] != "outer"]
    assert h["continuity"] == "G2" and h["g2"] <= 0.01 and len(h["side_g2"]) == 4 and h["occ_g2"] > 0.1
    table = subprocess.run(cmd + ["--jobs", "1", "--no-occ"], capture_output=True, text=True, timeout=300)
    assert table.returncode == 0 and "G2, curvature jump across the boundary" in table.stdout, table.stdout
    for extra in (["--continuity", "G3"],):
        bad = subprocess.run(cmd + extra, capture_output=True, text=True, timeout=120)
        assert bad.returncode == 2 and len(bad.stderr.strip().splitlines()) == 1, bad.stderr
        assert "Traceback" not in bad.stderr
    assert np.isfinite(h["g1"])


def test_refill_keeps_the_curvature_continuity_the_removed_face_had(bearing) -> None:
    """A real model (OCC's bearing, IGES): fillet face 4 meets faces 8 and 166 curvature continuously
    (the check's G2 edges; jump 0.0) and its other two neighbours only tangentially (100 %: a fillet
    of radius r against a plane). Refilled with ``continuity='G2'`` the plate is asked G2 on those
    two edges only, and its jump there is 5.3 % and 8.3 % (the issue's 1 % is not met on this 90 deg
    fillet strip); the G1 refill (the central split) leaves 199 % there, its curvature turned the
    other way. The default (``'auto'``: what the original gave, per edge) is the G2 refill."""
    from OCP.BRep import BRep_Tool

    from occsurf.bridge.modeling.joints import assess_curvature
    from occsurf.bridge.modeling.refill import refill_faces
    from occsurf.bridge.modeling.refill_g2 import shortfall
    from occsurf.bridge.modeling.refill_loop import hole_loop

    rep, _ = refill_faces(bearing, [4], compare_occ=False, check=False, continuity="G2")
    assert rep.status == "filled" and rep.method == "plate" and rep.continuity == "G2", rep.reason
    orig = np.array(rep.original_g2, float)
    assert np.array_equal(orig <= 0.02, [True, False, True, False]), orig
    assert rep.g2_edges == 2 and [a is None for a in rep.side_g2] == [False, True, False, True]
    assert rep.g2 is not None and rep.g2 <= 0.15, rep.side_g2
    auto, _ = refill_faces(bearing, [4], compare_occ=False, check=False)
    assert auto.continuity == "auto" and auto.method == "plate" and auto.reason is None
    assert auto.side_g2 == rep.side_g2 and auto.original_g2 == rep.original_g2
    # per edge what was asked and what the fill reached (G1 within 1 deg, G2 also within 2 %): the two
    # G2 edges reach G1 only, and the report says so
    assert rep.edge_asked == ["G2", "G1", "G2", "G1"] and rep.edge_continuity == ["G1"] * 4
    assert shortfall(rep.edge_asked, rep.edge_continuity, rep.side_g2).startswith("edges 0, 2 asked G2 got G1 (jump ")
    g1, _ = refill_faces(bearing, [4], compare_occ=False, check=False, continuity="G1")
    assert g1.continuity == "G1" and g1.g2 is None and g1.method == "central"
    assert g1.edge_asked == g1.edge_continuity == ["G1"] * 4
    edges, nbs, _ = hole_loop(bearing, [4])
    surfs = [BRep_Tool.Surface_s(f) for f in g1._fill_faces]
    floor = tolerances.CONTINUITY_CURVATURE_FLOOR / bearing.size
    jumps = [assess_curvature(edges[k], nbs[k], surfs, floor)[0] for k in (0, 2)]
    assert min(jumps) > 1.0, jumps


def test_a_hole_no_plate_can_fill_g2_is_filled_g1_with_the_reason(ring, monkeypatch) -> None:
    """Where the G2 plate cannot be made (here its refusal is forced: a hole that is a height over no
    plane, as a thread strip), the hole is still filled, G1 by the central split, and the report says
    why; no G2 numbers are left behind."""
    import occsurf.bridge.modeling.plate as plate
    from occsurf.bridge.modeling.fill import fill_model

    def refuse(*args, **kwargs):
        raise InvalidGeometryError("plate fill: not a height field over any plane tried (forced)")

    monkeypatch.setattr(plate, "fill_plate", refuse)
    res = fill_model(ring, continuity="G2", compare_occ=False)
    (h,) = [h for h in res.holes if h.status != "outer"]
    assert h.status == "filled" and h.method == "central" and h.continuity == "G2"
    assert h.reason == "G2 not available, filled G1: plate fill: not a height field over any plane tried (forced)"
    assert h.g2 is None and h.side_g2 == [] and h.corner_g2 == [] and h.g1 <= 1e-6
    assert h.edge_asked == ["G2"] * 4 and h.edge_continuity == ["G1"] * 4  # said per edge, not silently


def test_the_exact_sides_are_made_once_for_the_g2_attempt_and_the_g1_fallback(ring, monkeypatch) -> None:
    """A G2 attempt that falls back to G1 fills from the same exact sides (``hole_sides`` once, where it
    was made again for the fallback); where no exact sides exist the G2 attempt says so and the
    fill goes on to the fitted sides, as before."""
    import occsurf.bridge.modeling.fill as fill_mod
    import occsurf.bridge.modeling.plate as plate
    from occsurf.bridge.modeling.fill import fill_model

    calls = []
    real = fill_mod.hole_sides

    def counted(*args, **kwargs):
        calls.append(1)
        return real(*args, **kwargs)

    def refuse(*args, **kwargs):
        raise InvalidGeometryError("plate fill: not a height field over any plane tried (forced)")

    monkeypatch.setattr(fill_mod, "hole_sides", counted)
    monkeypatch.setattr(plate, "fill_plate", refuse)
    (h,) = [h for h in fill_model(ring, continuity="G2", compare_occ=False).holes if h.status != "outer"]
    assert h.status == "filled" and h.method == "central" and len(calls) == 1

    def no_sides(*args, **kwargs):
        calls.append(1)
        raise InvalidGeometryError("edge 0: the neighbour is trimmed across it (forced)")

    calls.clear()
    monkeypatch.setattr(fill_mod, "hole_sides", no_sides)
    (h,) = [h for h in fill_model(ring, continuity="G2", compare_occ=False).holes if h.status != "outer"]
    assert h.status == "filled" and h.construction == "fitted" and len(calls) == 1
    assert h.reason == "G2 not available, filled G1: edge 0: the neighbour is trimmed across it (forced)"


def test_edge_classes_and_the_shortfall_line() -> None:
    """What a fill reached per edge, by the rules that classify the original joints (G1 within 1 deg,
    G2 also within 2 %; an edge not measured in G2 claims G1 at most, one not measured in G1 G0),
    and the one line that names the edges short of what was asked."""
    from occsurf.bridge.modeling.refill_g2 import edge_classes, shortfall

    got = edge_classes([0.001, 0.5, 1.5, None, 0.002], [0.019, 0.021, 0.0, None, None])
    assert got == ["G2", "G1", "G0", "G0", "G1"]
    assert shortfall(["G2", "G2", "G1", "G0", "G1"], got, [0.019, 0.021, 0.0, None, None]) == \
        "edge 1 asked G2 got G1 (jump 2.1 %); edge 2 asked G1 got G0"
    assert shortfall(["G1", "G1"], ["G2", "G1"], []) is None  # more than asked is no shortfall


def _curvature_one_by_one(edge, face, fill_surfaces, floor, locate):
    """assess_curvature as it was written before its arithmetic ran on all samples at once: Euler's
    formula and the ratio sample by sample (the reference the vectorised form is held to)."""
    from OCP.BRep import BRep_Tool
    from OCP.GeomAbs import GeomAbs_Shape
    from OCP.GeomLProp import GeomLProp_SLProps
    from OCP.gp import gp_Dir, gp_Pnt2d, gp_Vec2d
    from OCP.LocalAnalysis import LocalAnalysis_SurfaceContinuity

    from occsurf.bridge.modeling.joints import ASSESS_SAMPLES, _fractions, edge_samples

    def normal_curvature(props, direction):
        if props.IsUmbilic():
            return float(props.MeanCurvature())
        dmax, dmin = gp_Dir(), gp_Dir()
        props.CurvatureDirections(dmax, dmin)
        c, s = float(np.dot(direction, dmax.Coord())), float(np.dot(direction, dmin.Coord()))
        return props.MaxCurvature() * c * c + props.MinCurvature() * s * s

    s_n, uvs, pts = edge_samples(edge, face, ASSESS_SAMPLES)
    pc = BRep_Tool.CurveOnSurface_s(edge, face, 0.0, 0.0)
    a, b = BRep_Tool.Range_s(edge, face)
    idx, us, vs = locate(pts)
    worst_rel = worst_gap = 0.0
    p2, d2 = gp_Pnt2d(), gp_Vec2d()
    for t, uv, k, u, v in zip(_fractions(ASSESS_SAMPLES), uvs, idx, us, vs):
        s_f = fill_surfaces[int(k)]
        pn = GeomLProp_SLProps(s_n, uv.X(), uv.Y(), 2, 1e-9)
        pf = GeomLProp_SLProps(s_f, float(u), float(v), 2, 1e-9)
        if not (pn.IsNormalDefined() and pf.IsNormalDefined() and pn.IsCurvatureDefined() and pf.IsCurvatureDefined()):
            continue
        pc.D1(a + t * (b - a), p2, d2)
        T = np.array(pn.D1U().Coord()) * d2.X() + np.array(pn.D1V().Coord()) * d2.Y()
        nn, nf = np.array(pn.Normal().Coord()), np.array(pf.Normal().Coord())
        cross = np.cross(nn, T)
        cross /= max(float(np.linalg.norm(cross)), 1e-300)
        kn, kf = normal_curvature(pn, cross), normal_curvature(pf, cross) * (1.0 if nn @ nf >= 0 else -1.0)
        if max(abs(kn), abs(kf)) >= floor:
            worst_rel = max(worst_rel, abs(kn - kf) / max(abs(kn), abs(kf), floor))
        la = LocalAnalysis_SurfaceContinuity(s_n, uv.X(), uv.Y(), s_f, float(u), float(v), GeomAbs_Shape.GeomAbs_G2)
        if la.IsDone():
            worst_gap = max(worst_gap, la.G2CurvatureGap())
    return worst_rel, worst_gap


def test_curvature_jumps_on_all_samples_at_once_are_the_per_sample_ones(bearing) -> None:
    """assess_curvature asks OCC per sample and does the arithmetic (tangent, the direction across,
    Euler's formula, the ratio) on all samples at once: the same jumps as sample by sample to 1e-13
    (the direction's norm and Euler's dot products are summed in another order: a few ulps on each
    curvature, so ~1e-16 on the ratio; where the jump is small, 2.4e-7 on bearing face 80, that is
    a relative 1.7e-9 of it), the same OCC gaps, and
    without ``gap`` no LocalAnalysis at all (0). On the bearing's fillet face 4 (two G2 edges, two
    G1): the original face (and it with its normal turned) and the G1 refill against the neighbours."""
    from OCP.BRep import BRep_Tool

    from occsurf.bridge.modeling.joints import ASSESS_SAMPLES, _nearest_feet, assess_curvature, edge_samples
    from occsurf.bridge.modeling.refill import refill_faces
    from occsurf.bridge.modeling.refill_loop import hole_loop

    edges, nbs, owners = hole_loop(bearing, [4])
    floor = tolerances.CONTINUITY_CURVATURE_FLOOR / bearing.size
    g1, _ = refill_faces(bearing, [4], compare_occ=False, check=False, continuity="G1")
    fill_surfs = [BRep_Tool.Surface_s(f) for f in g1._fill_faces]
    checked = 0
    for e, nb, own in zip(edges, nbs, owners):
        _, uvs, _ = edge_samples(e, own, ASSESS_SAMPLES)
        u, v = np.array([p.X() for p in uvs]), np.array([p.Y() for p in uvs])
        s_own = BRep_Tool.Surface_s(own)
        flipped = s_own.UReversed()  # the same surface, its normal turned: the fill's sign is then -1
        ur = np.array([s_own.UReversedParameter(x) for x in u])
        for surfs, locate in (([s_own], lambda pts, u=u, v=v: (np.zeros(len(pts), int), u, v)),
                              ([flipped], lambda pts, ur=ur, v=v: (np.zeros(len(pts), int), ur, v)),
                              (fill_surfs, lambda pts: _nearest_feet(fill_surfs, pts))):
            ref = _curvature_one_by_one(e, nb, surfs, floor, locate)
            got = assess_curvature(e, nb, surfs, floor, ASSESS_SAMPLES, locate=locate)
            assert abs(got[0] - ref[0]) <= 1e-13, (got, ref)  # a fraction: each k is off by ulps, so the ratio by ~1e-16
            assert got[1] == ref[1]
            assert assess_curvature(e, nb, surfs, floor, ASSESS_SAMPLES, locate=locate, gap=False) == (got[0], 0.0)
            checked += 1
    assert checked == 12
