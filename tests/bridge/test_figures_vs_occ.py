"""Posed figure surfaces (course §5-42..5-47) against OCC: the exact NURBS of a pose evaluated by OCC,
written to STEP and read back, and the elbow's cross-section area against OCC's plane section."""

from __future__ import annotations

import json

import numpy as np
import pytest
from OCP.BRepAlgoAPI import BRepAlgoAPI_Section
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace
from OCP.BRepCheck import BRepCheck_Analyzer
from OCP.BRepGProp import BRepGProp
from OCP.gp import gp_Dir, gp_Pln, gp_Pnt
from OCP.GProp import GProp_GProps
from OCP.ShapeAnalysis import ShapeAnalysis_FreeBounds
from OCP.TopAbs import TopAbs_EDGE
from OCP.TopExp import TopExp_Explorer
from OCP.TopoDS import TopoDS
from OCP.TopTools import TopTools_HSequenceOfShape

from occsurf.algorithms.hierarchical import AttachedSurface, section_area
from occsurf.bridge import to_occ
from occsurf.bridge.exchange.step_iges import read_step, write_step
from occsurf.examples.figures import bisector, demo_arm


@pytest.fixture(scope="module")
def arm() -> AttachedSurface:
    return demo_arm()


def test_a_posed_arm_is_exact_nurbs_that_occ_evaluates_alike(arm):
    posed = arm.at(arm.skeleton.pose({"elbow": np.radians(90)}))
    flat = posed.flatten()
    occ = to_occ(flat)
    rng = np.random.default_rng(2)
    u, v = rng.uniform(0, 1, 600), rng.uniform(0, 1, 600)
    theirs = np.array([occ.Value(float(a), float(b)).Coord() for a, b in zip(u, v)])
    # the hierarchy's own evaluation (base + delta splines) against OCC's of the single flat spline:
    # both are round-off on coordinates of size ~6 (measured 5e-15)
    assert np.abs(posed.evaluate(u, v) - theirs).max() < 1e-12


def test_a_pose_written_as_step_reads_back_to_round_off_and_valid(arm, tmp_path):
    hierarchy = arm.at(arm.skeleton.pose({"elbow": np.radians(60)}))
    posed = hierarchy.flatten()
    path = write_step(tmp_path / "arm_060.step", [hierarchy], names=["arm at 60 deg"])  # written as its flatten()
    model = read_step(path)
    assert len(model.faces) == 1
    back = model.faces[0].surface
    # The tube is closed around v: OCC's reader makes that direction periodic, so the knot vector
    # comes back in another (equivalent) form; the geometry is the same to round-off (17 digits
    # written; OCC's number parser is not correctly rounded, a few ulps)
    assert back.domain == posed.domain
    rng = np.random.default_rng(4)
    u, v = rng.uniform(0, 1, 2000), rng.uniform(0, 1, 2000)
    assert np.abs(back.evaluate(u, v) - posed.evaluate(u, v)).max() < 1e-14
    assert BRepCheck_Analyzer(model.faces[0].face).IsValid()


def _occ_section_area(surface, origin, normal) -> float:
    face = BRepBuilderAPI_MakeFace(to_occ(surface), 1e-7).Face()
    # a square of the plane around the joint: the whole plane also cuts the flexed biceps further out
    plane = BRepBuilderAPI_MakeFace(gp_Pln(gp_Pnt(*map(float, origin)), gp_Dir(*map(float, normal))),
                                    -0.9, 0.9, -0.9, 0.9).Face()
    sec = BRepAlgoAPI_Section(face, plane)
    sec.Build()
    edges = TopTools_HSequenceOfShape()
    ex = TopExp_Explorer(sec.Shape(), TopAbs_EDGE)
    while ex.More():
        edges.Append(ex.Current())
        ex.Next()
    wires = TopTools_HSequenceOfShape()
    ShapeAnalysis_FreeBounds.ConnectEdgesToWires_s(edges, 1e-6, False, wires)
    assert wires.Length() == 1
    disk = BRepBuilderAPI_MakeFace(TopoDS.Wire_s(wires.Value(1)), True).Face()
    props = GProp_GProps()
    BRepGProp.SurfaceProperties_s(disk, props, 1e-9)
    return props.Mass()


@pytest.mark.parametrize("deg", [0.0, 60.0, 120.0])
def test_section_area_agrees_with_occs_plane_section(arm, deg):
    """``section_area`` (sampled lines, secant refinement, shoelace) against OCC's exact plane section
    of the same posed NURBS, closed into a planar face and measured by BRepGProp: the sampled
    polygon of 256 points misses O(1/256^2) = 1e-4 of the area, and its Richardson extrapolation with
    the 128-point polygon (measured 6.9e-6 off) is within 1e-5."""
    th = np.radians(deg)
    flat = arm.at(arm.skeleton.pose({"elbow": th})).flatten()
    ours = section_area(flat, *bisector(th))
    theirs = _occ_section_area(flat, *bisector(th))
    assert ours == pytest.approx(theirs, rel=1e-5)


@pytest.mark.slow
def test_the_figures_demo_writes_poses_a_gif_of_the_bend_and_a_figure_that_loads(tmp_path, capsys):
    """``occsurf demo --only figures`` as a user runs it (the gallery's generic test leaves this demo
    to this one): five pose pictures and STEP files OCC reads, the GIF of the bend, the JSON."""
    from PIL import Image

    from occsurf.bridge import cli

    assert cli.main(["demo", "--out", str(tmp_path), "--only", "figures"]) == 0, capsys.readouterr().err
    files = sorted((tmp_path / "figures").iterdir())
    pngs = [f for f in files if f.suffix == ".png"]
    assert len(pngs) == 7  # five poses, the contact sheet, the cross-section chart
    for f in pngs:
        assert f.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and f.stat().st_size > 10_000
    steps = [f for f in files if f.suffix == ".step"]
    assert len(steps) == 5
    for f in steps:
        model = read_step(f)
        assert len(model.faces) == 1 and BRepCheck_Analyzer(model.faces[0].face).IsValid()
    with Image.open(tmp_path / "figures" / "bend.gif") as im:
        assert im.n_frames == 50
        im.seek(0)
        first = np.asarray(im.convert("RGB"), float)
        im.seek(20)
        bent = np.asarray(im.convert("RGB"), float)
    assert np.abs(first - bent).mean() > 1.0  # the arm moved
    fig = AttachedSurface.from_dict(json.loads((tmp_path / "figures" / "arm.json").read_text()))
    assert len(fig.rest.overlays) == 4 and len(fig.procedures) == 1
