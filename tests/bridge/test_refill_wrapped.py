"""Thread strips of a real screw refilled by the wrapped plate (issue 12; :mod:`occsurf.algorithms.topology.plate_wrap`).

build123d's M6 x 12 countersunk screw (``../shared/realdata``): face 9 is the thread's crest, a strip
0.12 mm wide winding nine times around the screw's axis (z through the origin). No plane sees it as
a height field, the central split refuses it, and OCC's ``BRepOffsetAPI_MakeFilling`` fails on it
(default and tuned); the wrapped plate, about the axis of the neighbouring cylinders, fills it within
the issue's G0 target (1e-7 of the model size: 1.9e-6), as a valid face that sews in and round-trips
through STEP. All sides are G0-only (the crest meets the flanks at a crease).
"""

from __future__ import annotations

import numpy as np
import pytest

from occsurf.algorithms import tolerances


@pytest.fixture(scope="module")
def crest(screw):
    from occsurf.bridge.modeling.refill import refill_faces

    return refill_faces(screw, [9])


def test_neighbour_axes_hold_the_screw_axis(screw) -> None:
    from occsurf.bridge.modeling.plate import revolution_axes
    from occsurf.bridge.modeling.refill_loop import hole_loop

    _, nbs, _ = hole_loop(screw, [9])
    axes = revolution_axes(nbs)
    assert any(abs(abs(a[2]) - 1) < 1e-12 and np.hypot(*c[:2]) < 1e-9 for c, a in axes)


@pytest.mark.slow
def test_thread_crest_is_filled_by_the_wrapped_plate(screw, crest) -> None:
    rep, shape = crest
    assert rep.status == "filled" and rep.method == "wrap", rep.reason
    assert rep.valid and rep.step_round_trip and rep.folds == 0
    assert max(rep.side_g0) <= tolerances.FILL_FIT_G0 * screw.size  # 1.9e-6, measured by LocalAnalysis


@pytest.mark.xfail(strict=True, reason="OCC defect: BRepOffsetAPI_MakeFilling fails on the nine-turn thread "
                   "crest strip (default: not done; tuned: Standard_ConstructionError)")
def test_occ_filling_fills_the_thread_crest(crest) -> None:
    rep, _ = crest
    assert any(o.get("status") == "ok" for o in rep.occ.values())


@pytest.fixture(scope="module")
def run_out(screw):
    from occsurf.bridge.modeling.refill import refill_faces

    return refill_faces(screw, [8, 22])


def _distances_to(faces, shape_faces, zmin: float, count: int = 150) -> np.ndarray:
    """Distances from ``count`` mesh nodes (z above ``zmin``) of ``shape_faces`` to the compound of ``faces``."""
    from OCP.BRep import BRep_Builder, BRep_Tool
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeVertex
    from OCP.BRepExtrema import BRepExtrema_DistShapeShape
    from OCP.BRepMesh import BRepMesh_IncrementalMesh
    from OCP.gp import gp_Pnt
    from OCP.TopLoc import TopLoc_Location
    from OCP.TopoDS import TopoDS_Compound

    comp, b = TopoDS_Compound(), BRep_Builder()
    b.MakeCompound(comp)
    for f in faces:
        b.Add(comp, f)
    pts = []
    for f in shape_faces:
        BRepMesh_IncrementalMesh(f, 0.01, False, 0.2)
        tri = BRep_Tool.Triangulation_s(f, TopLoc_Location())
        pts += [(p.X(), p.Y(), p.Z()) for p in (tri.Node(i) for i in range(1, tri.NbNodes() + 1))]
    P = np.array(pts)
    P = P[P[:, 2] > zmin]
    P = P[np.random.default_rng(0).choice(len(P), min(count, len(P)), replace=False)]
    return np.array([BRepExtrema_DistShapeShape(BRepBuilderAPI_MakeVertex(gp_Pnt(*p)).Vertex(), comp).Value()
                     for p in P])


@pytest.mark.slow
def test_a_flank_with_its_run_out_is_filled_about_the_screw_axis(screw, run_out) -> None:
    """Faces 8 and 22 removed together: a flank strip with its run-out at the thread's start (14
    edges). Unrolled about the axis, neither r nor z is a height over the whole loop (see
    test_plate_wrap's run-out in closed form); the plate over the unrolled loop's own plane is.
    About a fitted axis 2.1 deg off the screw's the boundary was met (1.6e-6) with the inside 0.47 mm
    off the thread's flank; about the screw's own axis (the neighbours' median residual 6e-8 against
    2.4e-3: the tilted axis is not tried) the fill stays within 5e-3 of the flank away from the
    run-out (z above -10.5; measured 2.5e-3 worst, median 4e-4), and its boundary is 6.2e-6 off
    (target 1.9e-6, missed at the run-out's corner; within the sewing tolerance 1e-5). OCC's fills
    miss the boundary by 1.14 mm (default) and 1.17 mm (tuned) on this 19 mm screw."""
    rep, _ = run_out
    assert rep.status == "filled" and rep.method == "wrap", rep.reason
    assert rep.valid and rep.step_round_trip and rep.folds == 0
    assert max(rep.side_g0) <= 1e-5
    d = _distances_to([screw.faces[8], screw.faces[22]], rep._fill_faces, zmin=-10.5)
    assert d.max() <= 5e-3, d.max()
    occ = [max(o["side_g0"]) for o in rep.occ.values() if o.get("status") == "ok"]
    assert all(g > 1e3 * max(rep.side_g0) for g in occ)  # where OCC fills it, a thousand times further off


def test_a_refusal_names_the_crease_between_removed_faces(screw, bearing) -> None:
    """Flank and crest (screw faces 8 and 9) meet at a 60 deg crease that runs the strip's length;
    removed together, no fill comes within 6e-4 of the boundary where the crease ends on it (OCC's
    filler fails too), and the refusal says so. The bearing's fillet pair [4, 166] meets
    tangentially: no crease."""
    from occsurf.bridge.modeling.refill_loop import _inner_creases, crease_note

    creases = _inner_creases(screw, [8, 9])
    assert len(creases) == 1 and abs(creases[0][0] - 60.0) < 0.5
    assert abs(np.hypot(*creases[0][1][:2]) - 3.0) < 0.1  # on the crest's radius
    assert "sharpest at 60.1 deg" in crease_note(screw, [8, 9])
    assert _inner_creases(bearing, [4, 166]) == [] and crease_note(bearing, [4, 166]) == ""
    assert crease_note(screw, [9]) == ""  # a single face has no inner edge
