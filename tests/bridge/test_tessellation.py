"""How the report meshes a model (``tessellation.mesh_shape``): the curved faces with OCC's default
(Watson) triangulation, then the planes with Delabella's. What that must leave as it was: every
node of every face, and every triangle of every curved face, exactly as one
``BRepMesh_IncrementalMesh(shape, linear, False, angular, False)`` on the whole shape makes them
(the report's per-vertex numbers are taken at those nodes); a plane's triangles may join its nodes
differently but cover the same face (the same area to 1e-9 of it)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from .conftest import REALDATA

SAMPLES = Path(__file__).resolve().parents[2] / "step_samples"


def _plate_with_holes(tmp_path: Path, n: int = 3) -> Path:
    """A plate with ``n x n`` filleted, chamfered through holes (the kind of model where Watson's
    Delaunay on the two planes with many holes is slow), as a STEP file."""
    from build123d import Box, Cylinder, Locations, chamfer, export_step, fillet

    plate = Box(60, 60, 6)
    holes = [Cylinder(3, 6) for _ in range(n * n)]
    spots = Locations(*[(-20 + 20 * i, -20 + 20 * j, 0) for i in range(n) for j in range(n)])
    part = plate - spots * holes[0]
    top = [e for e in part.edges() if e.center().Z > 2.9 and e.geom_type.name == "CIRCLE"]
    part = fillet(top, 1.0)
    bottom = [e for e in part.edges() if e.center().Z < -2.9 and e.geom_type.name == "CIRCLE"]
    part = chamfer(bottom, 0.8)
    path = tmp_path / "plate.step"
    export_step(part, str(path))
    return path


def _meshes(path: Path, split: bool) -> tuple[list[tuple[np.ndarray, np.ndarray, float]], list[bool]]:
    from OCP.BRep import BRep_Tool
    from OCP.BRepMesh import BRepMesh_IncrementalMesh
    from OCP.TopLoc import TopLoc_Location

    from occsurf.bridge.exchange.reading import read_model
    from occsurf.bridge.rendering import tessellation

    model = read_model(path)
    size = tessellation.model_size(model)
    lin, ang = tessellation.LINEAR_DEFLECTION * size, tessellation.ANGULAR_DEFLECTION
    if split:
        tessellation.mesh_shape(model.shape, lin, ang)
    else:
        BRepMesh_IncrementalMesh(model.shape, lin, False, ang, False)
    out, planes = [], []
    for f in model.faces:
        tri = BRep_Tool.Triangulation_s(f.face, TopLoc_Location())
        assert tri is not None, (path.name, f.index)
        P = np.array([tri.Node(i).Coord() for i in range(1, tri.NbNodes() + 1)])
        T = np.array([tri.Triangle(i).Get() for i in range(1, tri.NbTriangles() + 1)]) - 1
        area = float(np.linalg.norm(np.cross(P[T[:, 1]] - P[T[:, 0]], P[T[:, 2]] - P[T[:, 0]]), axis=1).sum() / 2)
        out.append((P, T, area))
        planes.append(tessellation.is_plane(f.face))
    return out, planes


#: The models with planes among their faces (on the others ``mesh_shape`` is one default call on
#: the whole shape, as before: the bearing and the lens are B-splines only, the torus and the vase
#: one face each).
WITH_PLANES = ("loft.step", "swept_tube.step", "mixed.igs", "build123d__M6-1x12-countersunk-screw.step",
               "occt__linkrods.step")


def _files(tmp_path_factory) -> list[Path]:
    files = [d / name for name in WITH_PLANES for d in (SAMPLES, REALDATA) if (d / name).is_file()]
    return files + [_plate_with_holes(tmp_path_factory.mktemp("plate"))]


@pytest.mark.slow
def test_planes_by_delabella_leave_every_node_and_curved_triangle_as_watson_makes_them(tmp_path_factory) -> None:
    """The samples and realdata models with planes (where ../shared is present) and a plate with 9
    filleted, chamfered holes: the same nodes on every face, the same triangles on every curved face;
    a plane's triangles cover the same area; planes were there to be meshed differently."""
    n_planes = n_curved = 0
    for path in _files(tmp_path_factory):
        before, planes = _meshes(path, split=False)
        after, _ = _meshes(path, split=True)
        for k, ((P, T, a), (Q, U, b), plane) in enumerate(zip(before, after, planes, strict=True)):
            assert np.array_equal(P, Q), (path.name, k, len(P), len(Q))
            if plane:
                n_planes += 1
                assert len(U) == len(T) and b == pytest.approx(a, rel=1e-9), (path.name, k)
            else:
                n_curved += 1
                assert np.array_equal(T, U), (path.name, k)
    assert n_planes >= 16 and n_curved >= 50  # the samples and the plate alone: 16 and 58


def test_a_plane_with_many_holes_is_meshed_by_delabella(tmp_path, monkeypatch) -> None:
    """``mesh_shape`` asks for Delabella on the planes only (the parameters it hands OCC), and a
    plane Delabella leaves without a triangulation is meshed again by Watson."""
    from OCP.IMeshTools import IMeshTools_MeshAlgoType_Delabella

    from occsurf.bridge.rendering import tessellation

    calls: list[tuple[bool, bool]] = []
    real = tessellation._mesh_parameters

    def spy(linear: float, angular: float, delabella: bool):
        p = real(linear, angular, delabella)
        calls.append((delabella, p.MeshAlgo == IMeshTools_MeshAlgoType_Delabella))
        return p

    monkeypatch.setattr(tessellation, "_mesh_parameters", spy)
    after, planes = _meshes(_plate_with_holes(tmp_path), split=True)
    assert calls == [(False, False), (True, True)] and sum(planes) == 6

    # Delabella failing on a plane (simulated: its pass leaves the planes unmeshed): Watson meshes them
    from OCP import BRepMesh

    real_mesh = BRepMesh.BRepMesh_IncrementalMesh

    def failing(shape, params, *rest):
        if params.MeshAlgo == IMeshTools_MeshAlgoType_Delabella:
            return None
        return real_mesh(shape, params, *rest)

    monkeypatch.setattr(BRepMesh, "BRepMesh_IncrementalMesh", failing)
    (tmp_path / "again").mkdir()
    again, _ = _meshes(_plate_with_holes(tmp_path / "again"), split=True)
    for (P, _, a), (Q, _, b) in zip(after, again, strict=True):
        assert np.array_equal(P, Q) and b == pytest.approx(a, rel=1e-9)


def test_free_meshes_frees_occ_triangulation_and_changes_nothing_reported() -> None:
    """``check_model(..., free_meshes=True)`` (``occsurf check``'s own model) leaves no face with
    OCC's triangulation and reports what the default reports (the faces' numbers, every field's
    mesh and values, the edges); by default a caller's shape stays meshed."""
    from OCP.BRep import BRep_Tool
    from OCP.TopLoc import TopLoc_Location

    from occsurf.bridge.exchange.reading import read_model
    from occsurf.bridge.quality.report import check_model

    kept, freed = read_model(SAMPLES / "mixed.igs"), read_model(SAMPLES / "mixed.igs")
    a, b = check_model(kept), check_model(freed, free_meshes=True)
    assert all(BRep_Tool.Triangulation_s(f.face, TopLoc_Location()) is not None for f in kept.faces)
    assert all(BRep_Tool.Triangulation_s(f.face, TopLoc_Location()) is None for f in freed.faces)
    ja, jb = a.to_json(), b.to_json()
    ja.pop("seconds"), jb.pop("seconds")
    assert ja == jb
    for k, fa in a.fields.items():
        fb = b.fields[k]
        assert np.array_equal(fa.mesh.points, fb.mesh.points) and np.array_equal(fa.mesh.triangles, fb.mesh.triangles)
        for name, v in fa.values.items():
            assert np.array_equal(v, fb.values[name], equal_nan=True), (k, name)


def test_free_meshes_keeps_the_mesh_that_placed_copies_of_a_part_share() -> None:
    """Two placed copies of one box (a compound sharing the box's faces, moved): their faces share
    OCC's triangulation, so freeing it after the first copy's faces would leave the second copy's
    without one (drawn as the untrimmed parameter box, with a note). ``free_meshes`` frees it after
    the last face that uses it: the report is the default's."""
    import build123d as bd

    from occsurf.bridge.quality.report import check_model

    box = bd.Box(10, 6, 4)
    two = bd.Compound([box, box.moved(bd.Location((20, 0, 0)))])
    a, b = check_model(two), check_model(two, free_meshes=True)
    assert len(a.fields) == 12
    ja, jb = a.to_json(), b.to_json()
    ja.pop("seconds"), jb.pop("seconds")
    assert ja == jb
    for k, fa in a.fields.items():
        fb = b.fields[k]
        assert fb.mesh.source == "brepmesh" and not fb.mesh.notes, (k, fb.mesh.notes)
        assert np.array_equal(fa.mesh.points, fb.mesh.points) and np.array_equal(fa.mesh.triangles, fb.mesh.triangles)


@pytest.mark.parametrize("rational", [False, True])
def test_grid_mesh_is_the_point_by_point_evaluation_to_round_off(rational: bool) -> None:
    """``grid_mesh`` takes its points and normals from the grid evaluation (the basis once per row
    and per column) instead of point by point: the same values to round-off -- points within 1e-14
    and normals within 1e-12 of the scattered evaluation at the mesh's (u, v) (unit vectors from
    partials that agree to ~1e-14 of their size), NaN at the same vertices where the surface is
    degenerate (a pole: a collapsed row of poles; on this net -- where |S_u x S_v| falls within
    round-off of the 1e-14 cut-off either evaluation may call a vertex degenerate), the triangles
    and the flip as before."""
    from occsurf.algorithms import BSplineSurface
    from occsurf.bridge.rendering.tessellation import _normals, grid_mesh

    rng = np.random.default_rng(7)
    ku = np.r_[[0.0] * 4, 0.3, 0.55, [1.0] * 4]
    kv = np.r_[[0.0] * 3, 0.8, [2.0] * 3]
    P = rng.random((6, 4, 3))
    P[0] = P[0, 0]  # u = 0 is a pole: the normal there is NaN
    w = 0.5 + rng.random((6, 4)) if rational else None
    s = BSplineSurface((3, 2), (ku, kv), P, w)
    meshes = []
    for flip in (False, True):
        mask = np.ones((33, 33), bool)
        mask[10:14, 5:9] = False
        m = grid_mesh(s, 33, flip=flip, mask=mask)
        np.testing.assert_allclose(m.points, s.evaluate(m.uv[:, 0], m.uv[:, 1]), rtol=0, atol=1e-14)
        scattered = _normals(s, m.uv, flip)
        nan = np.isnan(m.normals).any(axis=1)
        assert nan[:33].all() and not nan[33:].any()  # the pole's row of vertices, and only it
        np.testing.assert_array_equal(nan, np.isnan(scattered).any(axis=1))
        np.testing.assert_allclose(m.normals[~nan], scattered[~nan], rtol=0, atol=1e-12)
        assert m.triangles.shape == (2 * (32 * 32 - 5 * 5), 3)  # cells with a corner in the hole dropped
        meshes.append(m)
    np.testing.assert_array_equal(meshes[1].triangles, meshes[0].triangles[:, ::-1])  # flipped: the winding
    np.testing.assert_array_equal(meshes[1].normals, -meshes[0].normals)
