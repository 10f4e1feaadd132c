"""Generalized biquadratic surfaces to OCC and STEP: sewn, valid shells whose faces are the S-patches.

Each S-patch goes to OCC as its ``sides`` rational tensor-product pieces
(:func:`occsurf.algorithms.topology.spatch_convert.spatch_to_surfaces`; exact here: bidegree ``d (n - 2) <= 25``),
the pieces are sewn into one shell (:func:`occsurf.bridge.conversion.spatch_export.spatch_faces`), checked by
``BRepCheck_Analyzer``, written to STEP and read back.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from occsurf.algorithms.topology.generalized import generalized_biquadratic
from occsurf.algorithms.topology.generalized_bicubic import generalized_bicubic
from occsurf.algorithms.topology.mesh import read_obj
from occsurf.algorithms.topology.spatch_convert import piece_domain_points
from occsurf.bridge.conversion.spatch_export import spatch_faces
from occsurf.bridge.exchange.spatch_io import write_spatches_step
from occsurf.bridge.exchange.step_iges import read_step

FIXTURES = Path(__file__).resolve().parents[1] / "fixtures" / "meshes"
# expected face count (None: computed); "bicubic:" = the generalized bicubic scheme (Doo-Sabin cube:
# 8 triangles of depth 6 and 18 quads of depth 3, so 8 * 3 + 18 * 4 pieces, all exact: degree 6)
CASES = {"cube": 8 * 3, "pentagonal_prism": None, "bicubic:cube": 8 * 3 + 18 * 4, "bicubic:pentagonal_prism": None}

# OCC evaluates the exact rational pieces; measured agreement with SPatch.evaluate ~1e-15 before
# STEP, and STEP keeps ~13 significant digits (OCP_NOTES §7): bounds 1e-12 and 1e-10 on unit-size
# models.
OCC_TOL = 1e-12
STEP_TOL = 1e-10
GRID = np.linspace(0.0, 1.0, 7)


def _surface(name: str):
    if name.startswith("bicubic:"):
        return generalized_bicubic(read_obj(FIXTURES / f"{name.split(':')[1]}.obj"))
    return generalized_biquadratic(read_obj(FIXTURES / f"{name}.obj"))


def _pieces(surf):
    """(patch, piece k, centre point) for every piece, to match OCC faces to S-patch pieces."""
    out = []
    for p in surf.patches:
        for k in range(p.sides):
            out.append((p, k, p.evaluate(piece_domain_points(p.sides, k, np.array(0.5), np.array(0.5)))))
    return out


def _faces(shape):
    from OCP.TopAbs import TopAbs_FACE
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopoDS import TopoDS

    exp, out = TopExp_Explorer(shape, TopAbs_FACE), []
    while exp.More():
        out.append(TopoDS.Face_s(exp.Current()))
        exp.Next()
    return out


def _compare(evaluate_face, pieces, n_faces) -> float:
    """Max distance between a face and the S-patch piece whose centre it passes through."""
    S, T = np.meshgrid(GRID, GRID, indexing="ij")
    centres = np.array([c for _, _, c in pieces])
    worst, used = 0.0, set()
    for i in range(n_faces):
        vals = evaluate_face(i, S, T)  # (7, 7, 3)
        j = int(np.argmin(np.linalg.norm(centres - vals[3, 3], axis=1)))
        used.add(j)
        p, k, _ = pieces[j]
        ref = p.evaluate(piece_domain_points(p.sides, k, S, T))
        worst = max(worst, float(np.max(np.linalg.norm(vals - ref, axis=-1))))
    assert len(used) == n_faces  # every face matched a different piece
    return worst


@pytest.mark.parametrize("name", list(CASES))
def test_sewn_shell_is_valid_and_closed(name):
    from OCP.BRepCheck import BRepCheck_Analyzer
    from OCP.ShapeAnalysis import ShapeAnalysis_FreeBounds
    from OCP.TopAbs import TopAbs_EDGE, TopAbs_SHELL
    from OCP.TopExp import TopExp_Explorer

    surf = _surface(name)
    shape = spatch_faces(list(surf.patches))
    assert BRepCheck_Analyzer(shape).IsValid()
    faces = _faces(shape)
    assert len(faces) == (CASES[name] or sum(p.sides for p in surf.patches))
    exp, shells = TopExp_Explorer(shape, TopAbs_SHELL), 0
    while exp.More():
        shells += 1
        exp.Next()
    assert shells == 1
    fb = ShapeAnalysis_FreeBounds(shape, 1e-7)  # a closed mesh gives a closed shell: no free edges
    for wires in (fb.GetClosedWires(), fb.GetOpenWires()):
        assert not TopExp_Explorer(wires, TopAbs_EDGE).More()


@pytest.mark.slow
@pytest.mark.parametrize("name", list(CASES))
def test_occ_faces_agree_with_spatch_evaluation(name):
    from OCP.BRep import BRep_Tool
    from OCP.gp import gp_Pnt

    surf = _surface(name)
    faces = _faces(spatch_faces(list(surf.patches)))
    geoms = [BRep_Tool.Surface_s(f) for f in faces]

    def ev(i, S, T):
        g = geoms[i]
        u0, u1, v0, v1 = g.Bounds()
        out = np.empty(S.shape + (3,))
        for a in range(S.shape[0]):
            for b in range(S.shape[1]):
                p = gp_Pnt()
                g.D0(u0 + S[a, b] * (u1 - u0), v0 + T[a, b] * (v1 - v0), p)
                out[a, b] = p.Coord()
        return out

    assert _compare(ev, _pieces(surf), len(faces)) < OCC_TOL


@pytest.mark.slow
@pytest.mark.parametrize("name", list(CASES))
def test_step_round_trip(tmp_path, name):
    surf = _surface(name)
    path = write_spatches_step(tmp_path / f"{name.replace(':', '_')}.step", list(surf.patches))
    model = read_step(path)
    faces = [f for f in model.faces if f.surface is not None]
    assert len(faces) == len(model.faces) == sum(p.sides for p in surf.patches)

    def ev(i, S, T):
        s = faces[i].surface
        (u0, u1), (v0, v1) = s.domain
        return s.evaluate(u0 + S * (u1 - u0), v0 + T * (v1 - v0))

    assert _compare(ev, _pieces(surf), len(faces)) < STEP_TOL
