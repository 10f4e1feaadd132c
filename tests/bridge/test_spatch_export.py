"""S-patches exported to OCC faces, sewn shells (bridge/conversion/spatch_export.py) and STEP
(bridge/exchange/spatch_io.py): OCC's own evaluation of the faces against SPatch.evaluate, shell validity
and free boundaries, two patches sewn along a common side, the approximated path, STEP round trip."""

from __future__ import annotations

from math import comb

import numpy as np
import pytest
from OCP.BRep import BRep_Tool
from OCP.BRepCheck import BRepCheck_Analyzer
from OCP.ShapeAnalysis import ShapeAnalysis_FreeBounds
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_ShapeEnum
from OCP.TopExp import TopExp_Explorer
from OCP.TopoDS import TopoDS

import occsurf.bridge.conversion.spatch_export as export_mod
from occsurf.algorithms.errors import InvalidGeometryError, KernelError
from occsurf.algorithms.topology.spatch import SPatch, spatch_indices
from occsurf.algorithms.topology.spatch_convert import piece_domain_points
from occsurf.bridge.conversion.spatch_export import export_spatches, spatch_faces
from occsurf.bridge.exchange.spatch_io import read_spatches_step, write_spatches_step

# OCC evaluates the exact rational Bézier pieces (bidegree <= 18 here) by its own de Boor in
# homogeneous coordinates; measured agreement with SPatch.evaluate: <= 4e-15 relative to the
# control points' size. OCC_REL = 1e-12 bounds round-off of both evaluations with margin; a wrong
# pole, weight or parametrisation shows as >= 1e-3.
OCC_REL = 1e-12


def random_patch(rng, n, d, rational=False):
    m = comb(n + d - 1, d)
    # a bumpy surface over the xy-plane, so faces and the shell are geometrically sane
    idx = spatch_indices(n, d)
    ang = 2 * np.pi * np.arange(n) / n
    xy = (idx @ np.column_stack((np.cos(ang), np.sin(ang)))) / d * 10.0
    P = np.c_[xy, rng.normal(size=m)] + 0.3 * rng.normal(size=(m, 3))
    return SPatch(n, d, P, weights=rng.uniform(0.5, 2.0, m) if rational else None)


def _faces(shape):
    out, exp = [], TopExp_Explorer(shape, TopAbs_FACE)
    while exp.More():
        out.append(TopoDS.Face_s(exp.Current()))
        exp.Next()
    return out


def _occ_vs_patch(patch, faces, s, t):
    """Max distance between OCC's evaluation of each piece's face and SPatch.evaluate."""
    err = 0.0
    for k, face in enumerate(faces):
        surf = BRep_Tool.Surface_s(face)
        occ = np.array([surf.Value(float(a), float(b)).Coord() for a, b in zip(s, t)])
        ref = patch.evaluate(piece_domain_points(patch.sides, k, s, t))
        err = max(err, float(np.max(np.linalg.norm(occ - ref, axis=1))))
    return err


def _free_edges(shape) -> int:
    fb = ShapeAnalysis_FreeBounds(shape, 1e-7)
    wires = fb.GetClosedWires()
    n, exp = 0, TopExp_Explorer(wires, TopAbs_EDGE)
    while exp.More():
        n += 1
        exp.Next()
    open_exp = TopExp_Explorer(fb.GetOpenWires(), TopAbs_EDGE)
    assert not open_exp.More(), "free boundary should be closed loops only"
    return n


@pytest.mark.parametrize("n,d,rational", [(3, 3, False), (4, 2, True), (5, 3, False), (6, 3, True), (8, 2, False)])
def test_faces_evaluated_by_occ_equal_the_patch(n, d, rational):
    rng = np.random.default_rng(100 + n + d)
    patch = random_patch(rng, n, d, rational)
    res = export_spatches(patch)
    assert res.exact and len(res.faces[0]) == n
    s, t = rng.uniform(size=(2, 60))
    s[:4], t[:4] = [0, 1, 1, 0], [0, 0, 1, 1]
    size = np.abs(patch.control_points).max()
    assert _occ_vs_patch(patch, res.faces[0], s, t) <= OCC_REL * size


@pytest.mark.parametrize("n", [3, 5, 7])
def test_one_patch_is_one_valid_shell_with_one_boundary_loop(n):
    patch = random_patch(np.random.default_rng(200 + n), n, 3)
    shape = spatch_faces(patch)
    assert shape.ShapeType() == TopAbs_ShapeEnum.TopAbs_SHELL
    assert BRepCheck_Analyzer(shape).IsValid()
    assert len(_faces(shape)) == n
    # every piece has two half-sides on the patch boundary; the spokes are all sewn
    assert _free_edges(shape) == 2 * n


def test_two_patches_sharing_a_side_sew_into_one_shell():
    """A 4-sided and a 5-sided patch whose side 0 is the same curve, run in opposite directions."""
    rng = np.random.default_rng(300)
    a = random_patch(rng, 4, 3)
    b = random_patch(rng, 5, 3)
    side_a = a.control_points[a.boundary_indices(0)]
    P = b.control_points.copy()
    rows_b = b.boundary_indices(0)
    P[rows_b] = side_a[::-1]
    b = SPatch(5, 3, P)
    shape = spatch_faces([a, b])
    assert shape.ShapeType() == TopAbs_ShapeEnum.TopAbs_SHELL
    assert BRepCheck_Analyzer(shape).IsValid()
    assert len(_faces(shape)) == 9
    assert _free_edges(shape) == 2 * 4 + 2 * 5 - 4  # the 2 + 2 half-sides of the shared side are sewn


def test_approximated_patch_exports_within_tol():
    """9 sides, depth 4: bidegree 28 > 25, fitted; OCC's evaluation is within tol of the patch
    (the fit's own max deviation, measured on an 82 x 82 grid, plus sampling: 1.5 x tol)."""
    rng = np.random.default_rng(400)
    patch = random_patch(rng, 9, 4)
    tol = 1e-4
    res = export_spatches(patch, tol=tol)
    assert not res.exact and res.max_deviation <= tol
    assert BRepCheck_Analyzer(res.shape).IsValid() and res.shape.ShapeType() == TopAbs_ShapeEnum.TopAbs_SHELL
    s, t = rng.uniform(size=(2, 40))
    assert _occ_vs_patch(patch, res.faces[0], s, t) <= 1.5 * tol
    assert _free_edges(res.shape) == 18


def test_step_round_trip(tmp_path):
    rng = np.random.default_rng(500)
    patches = [random_patch(rng, 5, 3, rational=True), random_patch(rng, 3, 2)]
    res = export_spatches(patches)
    path = write_spatches_step(tmp_path / "spatches.step", patches, name="spatches")
    model = read_spatches_step(path)
    assert len(model.faces) == 8
    ours = [s for c in res.conversions for s in c.surfaces]
    back = [f.surface for f in model.faces]
    # write_step prints 17 significant digits: poles, weights and knots come back bit-identical
    # (as sets: compare each of ours with the read face it equals)
    for s in ours:
        assert any(s == b for b in back)
    # and the read faces, evaluated by OCC, are the patches
    s_, t_ = rng.uniform(size=(2, 30))
    by_surface = {id(b): f for f, b in zip(model.faces, back)}
    for patch, conv in zip(patches, res.conversions):
        faces = [by_surface[id(next(b for b in back if b == surf))].face for surf in conv.surfaces]
        assert _occ_vs_patch(patch, faces, s_, t_) <= OCC_REL * np.abs(patch.control_points).max()
    assert not list(tmp_path.glob("*.tmp*"))  # atomic write leaves no temporary file


def test_invalid_input_and_invalid_shape(monkeypatch):
    with pytest.raises(InvalidGeometryError, match="at least one"):
        spatch_faces([])
    with pytest.raises(InvalidGeometryError, match="expected an SPatch"):
        spatch_faces([object()])
    flat = SPatch(3, 1, np.eye(3)[:, :2])
    with pytest.raises(InvalidGeometryError, match="3-D"):
        spatch_faces(flat)

    class Invalid:
        def __init__(self, shape):
            pass

        def IsValid(self):
            return False

    monkeypatch.setattr(export_mod, "BRepCheck_Analyzer", Invalid)
    with pytest.raises(KernelError, match="not valid"):
        spatch_faces(random_patch(np.random.default_rng(0), 3, 1))
