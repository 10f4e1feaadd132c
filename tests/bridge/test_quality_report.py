"""check_model (occsurf.bridge.quality.report), its pictures and its page, called from Python.

Closed forms: on a sphere of radius R every principal curvature is 1/R in magnitude and both have
the same sign; on a cylinder one is 0 and the other 1/R; on a plane both are 0. The values are our
exact derivatives at OCC's mesh vertices mapped onto our converted surface (Newton inversion for
analytic faces), so they match to round-off (1e-9 relative leaves the inversion's 2x-deflection
acceptance far behind: a vertex off the surface would give a wrong radius by its offset).
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

from occsurf.bridge import read_step
from occsurf.bridge.quality import pictures as P
from occsurf.bridge.quality.html import render_html, viewer_payload
from occsurf.bridge.quality.report import FACE_FAIL_KINDS, check_model
from occsurf.bridge.rendering import tessellation, vtk_scene

SAMPLES = Path(__file__).resolve().parents[2] / "step_samples"


def _write(shape, tmp_path: Path, name: str) -> Path:
    from build123d import export_step

    path = tmp_path / name
    export_step(shape, str(path))
    return path


@pytest.fixture(scope="module")
def loft():
    return read_step(SAMPLES / "loft.step")


@pytest.fixture(scope="module")
def loft_report(loft):
    return check_model(loft)


def test_sphere_and_cylinder_closed_forms(tmp_path) -> None:
    from build123d import Cylinder, Pos, Sphere

    R, r = 2.0, 0.75
    model = read_step(_write(Sphere(R) + Pos(6, 0, 0) * Cylinder(r, 3.0), tmp_path, "sc.step"))
    rep = check_model(model, edges=False, flags=False)
    assert len(rep.faces) == len(model.faces)
    seen = set()
    for row in rep.faces:
        assert row.error is None, row.error
        if row.type == "Sphere":
            fld = rep.fields[row.index]
            k1, k2 = fld.values["max"], fld.values["min"]
            ok = np.isfinite(k1)
            assert ok.mean() > 0.95
            np.testing.assert_allclose(np.abs(k1[ok]), 1 / R, rtol=1e-9)
            np.testing.assert_allclose(k1[ok], k2[ok], rtol=1e-9)
            assert abs(row.k_min) == pytest.approx(1 / R, rel=1e-9) and abs(row.k_max) == pytest.approx(1 / R, rel=1e-9)
            seen.add("sphere")
        elif row.type == "Cylinder":
            got = sorted([abs(row.k_min), abs(row.k_max)])
            assert got[0] == pytest.approx(0.0, abs=1e-9) and got[1] == pytest.approx(1 / r, rel=1e-9)
            seen.add("cylinder")
        elif row.type == "Plane":
            assert abs(row.k_min) < 1e-9 and abs(row.k_max) < 1e-9
    assert seen == {"sphere", "cylinder"}


def test_outward_orientation_sign(tmp_path) -> None:
    """Convex solids: with outward normals the mean curvature has one sign on every curved face
    (a reversed face must not flip it)."""
    from build123d import Cylinder, Sphere

    for shape in (Sphere(1.5), Cylinder(1.0, 2.0)):
        model = read_step(_write(shape, tmp_path, "c.step"))
        rep = check_model(model, edges=False, flags=False)
        signs = {np.sign(np.nanmedian(rep.fields[f.index].values["mean"])) for f in rep.faces if f.type != "Plane"}
        assert len(signs) == 1 and 0 not in signs


def test_report_json_keys_and_edges(loft_report) -> None:
    doc = json.loads(json.dumps(loft_report.to_json(), allow_nan=False))
    assert doc["n_faces"] == len(doc["faces"]) == 11
    for f in doc["faces"]:
        assert {"index", "type", "k_min", "k_max", "flags"} <= set(f)
        for g in f["flags"]:
            assert {"kind", "location", "uv", "value", "suggestion"} <= set(g)
    assert doc["edges"], "the loft's faces share edges"
    for e in doc["edges"]:
        assert {"faces", "midpoint", "matched", "g0_max", "g1_max_deg", "g2_max", "g2_max_rel", "worst_point"} <= set(e)
        assert len(e["faces"]) == 2 and len(e["midpoint"]) == 3 and e["matched"] in ("topology", "geometry")
    worst = max(e["g1_max_deg"] for e in doc["edges"])
    assert doc["worst_g1_deg"] == pytest.approx(worst)
    by_index = {f["index"]: f for f in doc["faces"]}
    for e in doc["edges"]:
        for k in e["faces"]:
            assert by_index[k]["worst_g1_deg"] >= e["g1_max_deg"] - 1e-12


def test_face_failures_follow_the_preset(loft) -> None:
    catia = check_model(loft, preset="catia")
    mech = check_model(loft, preset="mechanical")
    flagged = {f.index for f in catia.faces if any(g["kind"] in FACE_FAIL_KINDS["catia"] for g in f.flags)}
    assert flagged, "the loft's sides wiggle (sections show several inflections)"
    assert {int(x.split()[1].rstrip(":")) for x in catia.failures if x.startswith("face ")} == flagged
    assert not [x for x in mech.failures if x.startswith("face ")]


def test_selected_faces_and_bad_index(loft) -> None:
    rep = check_model(loft, faces=[0, 9], flags=False)
    assert [f.index for f in rep.faces] == [0, 9]
    assert all(set(e["faces"]) & {0, 9} for e in rep.edges)
    from occsurf.algorithms.errors import InvalidGeometryError

    with pytest.raises(InvalidGeometryError, match="faces"):
        check_model(loft, faces=[99])
    with pytest.raises(InvalidGeometryError, match="preset"):
        check_model(loft, preset="nope")


def test_a_face_that_cannot_be_evaluated_is_still_reported(loft, monkeypatch) -> None:
    faces = list(loft.faces)
    faces[3] = dataclasses.replace(faces[3], surface=None, error="conversion failed (test)")
    model = dataclasses.replace(loft, faces=faces)
    real = tessellation.mesh_face

    def broken(face, size):
        if face.index == 5:
            raise RuntimeError("Standard_Failure: BRep_Tool: no surface")
        return real(face, size)

    monkeypatch.setattr(tessellation, "mesh_face", broken)
    rep = check_model(model, flags=False)
    rows = {f.index: f for f in rep.faces}
    assert len(rows) == 11
    assert "conversion failed (test)" in rows[3].error and 3 not in rep.fields
    assert "no surface" in rows[5].error and 5 not in rep.fields
    assert all(rows[k].error is None and rows[k].k_max is not None for k in rows if k not in (3, 5))
    assert rep.edges  # the edge table is still measured


def test_degenerate_points_reported(tmp_path) -> None:
    from build123d import Cone

    model = read_step(_write(Cone(1.0, 0.0, 2.0), tmp_path, "cone.step"))  # apex: collapsed edge
    rep = check_model(model, edges=False, flags=False)
    cone = [f for f in rep.faces if f.type == "Cone"][0]
    fld = rep.fields[cone.index]
    assert cone.n_degenerate == int(fld.degenerate.sum()) > 0  # the apex vertices
    assert any("degenerate" in n for n in cone.notes)
    assert np.isnan(fld.values["mean"][fld.degenerate]).all()  # never coloured as a value
    apex = fld.mesh.points[fld.degenerate]
    np.testing.assert_allclose(apex[:, :2], 0.0, atol=1e-9)


@pytest.mark.slow
@pytest.mark.skipif(not vtk_scene.render_available(), reason="VTK cannot open an offscreen window here")
def test_every_picture_kind(loft_report, tmp_path) -> None:
    """Every picture kind of the model and of each face is drawn: not blank; curvature and draft
    maps carry their legend."""
    from PIL import Image

    shown = P.render_report_pictures(loft_report, tmp_path)
    assert set(shown) == set(P.MODEL_PICTURES)
    for kind, name in shown.items():
        img = np.asarray(Image.open(tmp_path / name).convert("RGB"))
        assert img.shape[:2] == (P.MODEL_SIZE[1], P.MODEL_SIZE[0])
        body = img[:, : int(0.8 * img.shape[1])].reshape(-1, 3).astype(int)
        r, g, b = body.T
        background = (r >= 200) & (b >= r) & (b - r <= 25)
        assert 1 - background.mean() > 0.1, f"{kind}: almost blank"
        assert len(np.unique(body // 16, axis=0)) > 10, f"{kind}: flat"
        strip = img[:, int(0.84 * img.shape[1]):].reshape(-1, 3).astype(int)
        cmap = P.PICTURE_KINDS[kind][1]
        if cmap in ("diverging", "rainbow"):
            for end in np.array(vtk_scene.COLORMAPS[cmap])[[0, -1]] * 255:
                assert np.min(np.abs(strip - end).sum(axis=1)) < 30, f"{kind}: legend missing"
    sections = np.asarray(Image.open(tmp_path / shown["sections"]).convert("RGB")).astype(int)
    comb = (sections[..., 0] > 170) & (sections[..., 1] < 110) & (sections[..., 2] < 80)
    assert comb.sum() > 200, "no curvature comb drawn"
    edges = np.asarray(Image.open(tmp_path / shown["edges"]).convert("RGB")).astype(int)
    coloured = (edges.max(axis=2) - edges.min(axis=2)) > 80  # class colours on a grey model
    assert coloured.sum() > 100, "no classified edge drawn"
    for row in loft_report.faces:
        assert set(row.pictures) == set(P.FACE_PICTURES), (row.index, row.notes)
        for name in row.pictures.values():
            assert (tmp_path / name).stat().st_size > 2000


def test_page_is_offline_and_complete(loft_report) -> None:
    doc = loft_report.to_json()
    page = render_html(doc, viewer_payload(loft_report), {"mean": "model_mean.png"})
    assert "http://" not in page.replace("http://www.w3.org", "") and "https://" not in page.split("<script>")[0]
    assert "<script src=" not in page and "<link" not in page
    assert 'id="face-table"' in page and 'id="edge-table"' in page and 'id="viewer"' in page
    for f in doc["faces"]:
        assert f'id="face-{f["index"]}"' in page
    assert "three.js r187" in page and "MIT" in page
    payload = viewer_payload(loft_report)
    assert len(payload["faces"]) == 11 and set(payload["ranges"]) >= {"mean", "gaussian", "draft"}


def test_vendored_viewer_and_licence() -> None:
    from importlib import resources

    static = resources.files("occsurf.bridge.quality").joinpath("static")
    head = static.joinpath("three-viewer.min.js").read_text("utf-8")[:400]
    assert "three.js r187" in head and "MIT License" in head
    assert "MIT License" in static.joinpath("THREE_LICENSE").read_text("utf-8")
    import tomllib

    data = tomllib.loads((Path(__file__).resolve().parents[2] / "pyproject.toml").read_text("utf-8"))
    assert "static/three-viewer.min.js" in data["tool"]["setuptools"]["package-data"]["occsurf.bridge.quality"]


def test_cli_preset_names_match_the_library() -> None:
    from occsurf.bridge.cli.check import PRESET_NAMES
    from occsurf.bridge.quality import thresholds

    assert sorted(PRESET_NAMES) == sorted(thresholds.PRESETS) == sorted(FACE_FAIL_KINDS)


def test_python_access_edges_and_coloured_meshes(loft_report, tmp_path) -> None:
    from build123d import Edge

    from occsurf.bridge.quality import export

    lines = export.section_curves(loft_report)
    assert lines["sections"] and lines["combs"]
    edges = export.as_edges(lines["sections"])
    assert edges and all(isinstance(e, Edge) for e in edges)
    for e, pl in zip(edges, lines["sections"]):
        chord = float(np.linalg.norm(np.diff(pl, axis=0), axis=1).sum())
        assert e.length == pytest.approx(chord, rel=1e-2)  # a spline through the cut points
    teeth = export.as_edges([c for c in lines["combs"] if len(c) == 2], smooth=False)
    assert teeth and all(e.geom_type.name == "LINE" for e in teeth[:5])

    mesh = export.colored_mesh(loft_report, "mean")
    n = sum(f.mesh.n_vertices for f in loft_report.fields.values())
    assert mesh.points.shape == (n, 3) and mesh.colors.shape == (n, 3) and mesh.colors.dtype == np.uint8
    assert mesh.lo == -mesh.hi  # symmetric, as the pictures
    np.testing.assert_array_equal(mesh.colors, vtk_scene.colormap_rgb(mesh.values, mesh.lo, mesh.hi, "diverging"))
    assert len(np.unique(mesh.colors, axis=0)) > 50
    from vtkmodules.vtkIOPLY import vtkPLYReader

    reader = vtkPLYReader()
    reader.SetFileName(str(mesh.write_ply(tmp_path / "m.ply")))
    reader.Update()
    assert reader.GetOutput().GetNumberOfPoints() == n and reader.GetOutput().GetNumberOfCells() == len(mesh.triangles)
    with pytest.raises(ValueError, match="indicator"):
        export.colored_mesh(loft_report, "nope")

    fld = loft_report.fields[3]
    segs = export.reflection_lines(fld)
    assert segs.shape[1:] == (2, 3) and len(segs) > 20
    lo, hi = fld.mesh.points.min(axis=0), fld.mesh.points.max(axis=0)
    assert np.all(segs >= lo - 1e-9) and np.all(segs <= hi + 1e-9)
    # every segment crosses a stripe boundary: its ends sit on edges of one triangle
    assert np.all(np.linalg.norm(segs[:, 0] - segs[:, 1], axis=1) < np.ptp(fld.mesh.points, axis=0).max() / 5)


def test_summarize_model_is_the_audit_quality_hook() -> None:
    """``occsurf audit --checks quality`` calls summarize_model through its hook: the numbers it
    stores come from check_model, with designed creases excluded from the worst G1."""
    from occsurf.bridge.audit.tasks import audit_job, make_item
    from occsurf.bridge.quality import summarize_model

    model = read_step(SAMPLES / "loft.step")
    summary = summarize_model(model)
    report = check_model(model, samples=21)
    smooth = [e["g1_max_deg"] for e in report.edges if e["classification"] in {"gap", "G0", "G1", "G2"}]
    sharp = [e["g1_max_deg"] for e in report.edges if e["classification"] == "sharp"]
    assert sharp and max(sharp) > 45          # the loft's caps meet its skin at designed creases ...
    assert summary["worst_g1_deg"] == pytest.approx(max(smooth))   # ... which do not count here
    assert summary["worst_g1_deg"] < 1e-6     # the lofted skin is G1 (C2 B-spline) across its seams
    assert summary["flags"] == [f"face {f.index}: {g['kind']}" for f in report.faces for g in f.flags]
    assert summary["curvature_spikes"] == sum(g["kind"] == "curvature_spike" for f in report.faces for g in f.flags)

    out = audit_job(make_item(str(SAMPLES / "loft.step"), "0" * 64, ("inspect", "quality"), 5, None))
    assert out["quality_status"] == "ok"
    assert out["quality"]["worst_g1_deg"] == pytest.approx(summary["worst_g1_deg"])
    assert out["quality"]["flags"] == summary["flags"]


# ---------------------------------------------------------------------------------------- issue 11 follow-ups
def test_plain_cone_passes_catia_and_a_real_spike_fails(tmp_path) -> None:
    """A cone's apex (curvature growing as 1 / distance) is not a curvature spike: a plain cone
    passes ``--fail-on catia``; the same cone with a pole pushed off it near the apex fails."""
    from build123d import Cone

    from occsurf.bridge import write_step

    from ..algorithms.test_quality_flags import cone

    model = read_step(_write(Cone(1.0, 0.0, 2.0), tmp_path, "cone.step"))
    rep = check_model(model, preset="catia")
    assert not [g for f in rep.faces for g in f.flags if g["kind"] == "curvature_spike"]
    assert not [x for x in rep.failures if x.startswith("face")], rep.failures
    write_step(tmp_path / "bumped.step", [cone(bump=0.2, pole=(1, 2))])
    rep = check_model(read_step(tmp_path / "bumped.step"), preset="catia", edges=False)
    assert any("curvature_spike" in x for x in rep.failures), rep.failures


def test_every_face_gets_sections_through_its_own_extent(tmp_path) -> None:
    """A long box: the model's section planes (normal to x) miss its two end faces; each face is cut
    by planes through its own extent instead, so every face has section polylines."""
    from build123d import Box

    model = read_step(_write(Box(10.0, 1.0, 1.0), tmp_path, "box.step"))
    rep = check_model(model, edges=False, flags=False)
    fields = [rep.fields[k] for k in sorted(rep.fields)]
    axis = P.model_section_axis(fields)
    assert axis == 0
    _, per_face = P.section_lines(fields, rep.size)
    assert len(per_face) < len(fields)  # the model's family misses the end faces
    for f in fields:
        lines, _teeth, _infl = P.face_section_lines(f, axis)
        assert len(lines) == P.N_FACE_SECTIONS, f.mesh.index
        ext = np.ptp(f.mesh.points, axis=0)
        for pl in lines:  # each a straight cut across the whole face (flat faces: no comb)
            assert np.linalg.norm(pl[-1] - pl[0]) >= 0.999 * min(e for e in ext if e > 1e-9) - 1e-9


@pytest.mark.skipif(not vtk_scene.render_available(), reason="VTK cannot open an offscreen window here")
def test_lines_are_as_wide_as_asked_and_the_first_scene_draws() -> None:
    """Edge and section lines keep their width offscreen (EGL), and the first scene of a process is
    drawn (it used to come out black: its renderer was made before VTK's OpenGL factories loaded)."""
    import subprocess
    import sys

    first = subprocess.run([sys.executable, "-c", (
        "import numpy as np\nfrom occsurf.bridge.rendering.vtk_scene import Scene\ns = Scene()\n"
        "s.add_mesh(np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0.0]]), np.array([[0, 1, 2]]), cmap='grey')\n"
        "print(s.render_array(size=(64, 48), camera='top').mean())")], capture_output=True, text=True, timeout=120)
    assert first.returncode == 0 and float(first.stdout.split()[-1]) > 100, first.stdout + first.stderr
    pts = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0.0]])
    tri = np.array([[0, 1, 2], [0, 2, 3]])
    for width in (3.0, 5.0):
        s = vtk_scene.Scene()
        s.add_mesh(pts, tri, cmap="grey")
        s.add_lines([np.array([[0.5, 0.1, 0], [0.5, 0.9, 0]])], color=(0.9, 0.0, 0.0), width=width)
        img = s.render_array(size=(400, 300), camera="iso").astype(int)
        red = np.argwhere((img[..., 0] > 150) & (img[..., 1] < 80) & (img[..., 2] < 80)).astype(float)
        # thickness across the line = red area / its length along the principal axis (the line runs
        # diagonally in the iso view, where untubed wide lines came out 1 px thick in one direction)
        axis = np.linalg.svd(red - red.mean(axis=0), full_matrices=False)[2][0]
        length = np.ptp(red @ axis)
        assert len(red) / length >= 0.8 * width, (width, len(red) / length)


def test_sections_end_on_the_trim(tmp_path) -> None:
    """A plate with a round hole: every cut of its top face ends on the hole's circle or on the
    plate's outline. With the reader's exact trim (the face's loops of p-curves) within the trim's
    boundary band (TRIM_ON); with OCC's triangulation as the mask, within the mesh's deflection
    (it was up to one seed cell short: 1/48 of the face)."""
    from build123d import Box, Cylinder

    from occsurf.bridge.rendering.tessellation import LINEAR_DEFLECTION

    model = read_step(_write(Box(4.0, 4.0, 1.0) - Cylinder(1.0, 2.0), tmp_path, "plate.step"))
    rep = check_model(model, edges=False, flags=False)
    top = [f for f in rep.fields.values() if np.allclose(f.mesh.points[:, 2], 0.5)]
    assert len(top) == 1
    fld = top[0]
    lines, _, _ = P.face_section_lines(fld, P.model_section_axis(list(rep.fields.values())))
    assert len(lines) > P.N_FACE_SECTIONS  # the planes through the hole give two pieces each
    ends = np.concatenate([pl[[0, -1], :2] for pl in lines])
    on_hole = np.abs(np.linalg.norm(ends, axis=1) - 1.0)
    on_outline = np.abs(np.max(np.abs(ends), axis=1) - 2.0)
    off = np.minimum(on_hole, on_outline)
    if fld.trim is not None:  # the trim's own boundary band (TRIM_ON of its parameter box; a plane's
        from occsurf.algorithms import tolerances  # parameters are lengths), then the section tolerance

        (u0, u1), (v0, v1) = fld.trim.domain
        band = (tolerances.TRIM_ON + tolerances.TRIM_POLYLINE) * np.hypot(u1 - u0, v1 - v0)  # + its polyline
        tol = 1.01 * band + tolerances.QUALITY_SECTION_TOL * rep.size
    else:
        tol = 2 * LINEAR_DEFLECTION * rep.size
    assert off.max() <= tol, (fld.trim is not None, off.max())
    assert (on_hole < tol).sum() >= 2  # cuts through the hole end on its circle
    if fld.trim is None:
        pytest.skip("the reader gave no exact trim for this face: checked against the mesh's mask only")


def test_a_face_s_mesh_mask_is_built_only_when_a_section_needs_it(monkeypatch, tmp_path) -> None:
    """Faces without the reader's exact trim are masked by their mesh's triangle finder (a few MB
    each: 3.5 MB for a 4191-vertex fillet torus, 2.5 GB over the 361 fillets of a 1089-face plate
    when every face's was built up front). It is built on the mask's first call, once, and gives
    what ``uv_mask`` gives; faces no section plane reaches never build one, and the sections are
    the same as with every mask built first."""
    from build123d import Box, Cylinder, GeomType, Pos, fillet

    import occsurf.bridge.quality.uv_masks as R

    part = Box(40.0, 10.0, 4.0) - Pos(-15, 0, 0) * Cylinder(1.5, 4.0) - Pos(15, 0, 0) * Cylinder(1.5, 4.0)
    part = fillet([e for e in part.edges() if e.geom_type == GeomType.CIRCLE and abs(e.center().Z - 2) < 1e-6], 0.5)
    rep = check_model(read_step(_write(part, tmp_path, "holes.step")), edges=False, flags=False)
    fields = [rep.fields[k] for k in sorted(rep.fields)]
    for f in fields:  # the mesh masks' path (faces whose loops do not convert): these untrimmed
        f.natural = False  # faces are natural, which the sections cut unmasked
    built: list[int] = []
    real = R.uv_mask

    def counting(mesh):
        built.append(mesh.index)
        return real(mesh)

    monkeypatch.setattr(R, "uv_mask", counting)
    meshed = [f for f in fields if f.trim is None]
    assert meshed, "every face had an exact trim: nothing to test"
    masks = {f.mesh.index: f.mask() for f in meshed}
    assert built == []  # nothing built yet
    f0 = meshed[0]
    u, v = f0.mesh.uv[:5, 0], f0.mesh.uv[:5, 1]
    assert np.array_equal(masks[f0.mesh.index](u, v), real(f0.mesh)(u, v))
    masks[f0.mesh.index](u, v)
    assert built == [f0.mesh.index] and f0.mask() is masks[f0.mesh.index]  # built once, kept
    built.clear()
    lines = P.section_lines(fields, rep.size)[0][0]
    assert len(built) < len(meshed)  # some faces were never reached by a plane
    monkeypatch.setattr(R, "uv_mask", real)
    fresh = check_model(read_step(tmp_path / "holes.step"), edges=False, flags=False)
    for f in fresh.fields.values():
        f.natural = False
        f.mask()(np.zeros(1), np.zeros(1))  # every mask built up front, as before
    again = P.section_lines([fresh.fields[k] for k in sorted(fresh.fields)], fresh.size)[0][0]
    assert len(again) == len(lines) and all(np.array_equal(a, b) for a, b in zip(lines, again))


def test_mesh_inversion_stops_converged_nodes_without_changing_them(tmp_path) -> None:
    """OCC's mesh nodes of analytic faces (sphere, cylinder, torus, cone, plane) are mapped onto our
    converted surfaces by Newton's method; a node stops once a step moved it by at most
    NEWTON_STILL (1e-13) of the parameter box. Against all NEWTON_STEPS steps for every node (the
    former loop, written out here): the same parameters to 1e-12 of the box (measured 1.6e-14 on
    the real models' 265 faces), the same accepted nodes."""
    from build123d import Box, Cone, Cylinder, Pos, Sphere, Torus

    part = (Box(30, 30, 4) + Pos(0, 0, 8) * Sphere(5) + Pos(10, 10, 4) * Cylinder(2, 6) + Pos(-9, 8, 3) * Cone(3, 1, 4)
            + Pos(-8, -8, 2) * Torus(4, 1))
    model = read_step(_write(part, tmp_path, "analytic.step"))
    size = tessellation.mesh_model(model)

    def reference(surface, target, uv0, tol):
        (u0, u1), (v0, v1) = surface.domain
        lo, hi = np.array([u0, v0]), np.array([u1, v1])
        uv = np.clip(uv0, lo, hi)
        for _ in range(tessellation.NEWTON_STEPS):
            D = surface.derivatives(uv[:, 0], uv[:, 1], 1)
            J = np.stack([D[:, 1, 0], D[:, 0, 1]], axis=-1)
            JtJ = np.einsum("nki,nkj->nij", J, J)
            Jtr = np.einsum("nki,nk->ni", J, D[:, 0, 0] - target)
            det = JtJ[:, 0, 0] * JtJ[:, 1, 1] - JtJ[:, 0, 1] ** 2
            good = np.abs(det) > 1e-300
            inv = np.zeros_like(JtJ)
            inv[good, 0, 0], inv[good, 1, 1] = JtJ[good, 1, 1] / det[good], JtJ[good, 0, 0] / det[good]
            inv[good, 0, 1] = inv[good, 1, 0] = -JtJ[good, 0, 1] / det[good]
            uv = np.clip(uv - np.einsum("nij,nj->ni", inv, Jtr), lo, hi)
        err = np.linalg.norm(surface.evaluate(uv[:, 0], uv[:, 1]) - target, axis=-1)
        return uv, err <= tol

    calls: list[tuple] = []
    real = tessellation._invert

    def both(surface, target, uv0, tol):
        calls.append((real(surface, target, uv0, tol), reference(surface, target, uv0, tol), surface.domain))
        return calls[-1][0]

    import unittest.mock as mock

    with mock.patch.object(tessellation, "_invert", both):
        for face in model.faces:
            tessellation.mesh_face(face, size)
    assert len(calls) >= 5  # the analytic faces went through the inversion
    for (uv, ok), (uv_ref, ok_ref), ((u0, u1), (v0, v1)) in calls:
        assert np.array_equal(ok, ok_ref)
        assert np.abs(uv - uv_ref).max() <= 1e-12 * max(u1 - u0, v1 - v0)


def test_mesh_masks_held_at_once_are_bounded_and_rebuilt_alike(monkeypatch, tmp_path) -> None:
    """Issue 28: a 1089-face plate's sections build 477 triangle finders (faces without an exact
    trim; up to ~7 MB each, in C++), all held to the end: 1.36 GB of the check's 2.6 GB peak. A
    mesh mask now gives its finder up once ``MESH_MASKS_KEPT`` others were used after it, and builds
    it again when called again, with the same answers; the sections of a model are the same whether
    one finder or every finder is held."""
    from build123d import Box, Cylinder, GeomType, Pos, fillet

    import occsurf.bridge.quality.uv_masks as M

    part = Box(40.0, 10.0, 4.0)
    for x in (-15, -5, 5, 15):
        part = part - Pos(x, 0, 0) * Cylinder(1.5, 4.0)
    part = fillet([e for e in part.edges() if e.geom_type == GeomType.CIRCLE and abs(e.center().Z - 2) < 1e-6], 0.5)
    rep = check_model(read_step(_write(part, tmp_path, "four.step")), edges=False, flags=False)
    fields = [rep.fields[k] for k in sorted(rep.fields)]
    for f in fields:  # cut through their mesh masks, as faces whose loops do not convert are (these
        f.natural = False  # untrimmed faces are natural: the sections would cut them unmasked)
    meshed = [f.mask() for f in fields if f.trim is None]
    assert len(meshed) >= 4 and all(isinstance(m, M.MeshMask) for m in meshed), "too few faces without a trim"
    probe = [(f.mesh.uv[::7, 0], f.mesh.uv[::7, 1]) for f in fields if f.trim is None]
    first = [m(*q) for m, q in zip(meshed, probe)]
    monkeypatch.setattr(M, "MESH_MASKS_KEPT", 2)
    for m, q in zip(meshed, probe):
        m(*q)
    assert [m.built for m in meshed].count(True) == 2 and meshed[-1].built and not meshed[0].built
    again = [m(*q) for m, q in zip(meshed, probe)]  # each built again: the same answers
    assert all(np.array_equal(a, b) for a, b in zip(first, again)) and any(a.any() for a in first)
    monkeypatch.setattr(M, "MESH_MASKS_KEPT", 1)
    few = P.section_lines(fields, rep.size)[0][0]
    assert sum(m.built for m in meshed) <= 1
    monkeypatch.setattr(M, "MESH_MASKS_KEPT", 10**6)
    fresh = check_model(read_step(tmp_path / "four.step"), edges=False, flags=False)
    for f in fresh.fields.values():
        f.natural = False
    many = P.section_lines([fresh.fields[k] for k in sorted(fresh.fields)], fresh.size)[0][0]
    assert len(few) == len(many) > 0 and all(np.array_equal(a, b) for a, b in zip(few, many))


def test_a_released_mesh_mask_frees_its_finder_at_once(tmp_path) -> None:
    """The triangle finder is made directly, not by ``Triangulation.get_trifinder()``, which keeps it
    on the triangulation: a reference cycle that only a full garbage collection frees (the plate's
    released finders stayed in memory that way). Released, nothing refers to the finder any more."""
    import gc
    import weakref

    from build123d import Box, Cylinder, Pos

    part = Box(20.0, 10.0, 4.0) - Pos(0, 0, 0) * Cylinder(2.0, 4.0)
    rep = check_model(read_step(_write(part, tmp_path, "one.step")), edges=False, flags=False)
    masks = [f.mask() for f in rep.fields.values() if f.trim is None]
    if not masks:
        pytest.skip("every face had an exact trim: no mesh mask to test")
    m = masks[0]
    m(m.mesh.uv[:3, 0], m.mesh.uv[:3, 1])
    held = [c.cell_contents for c in m._finder.__closure__ or ()]
    trap = [c for c in held if type(c).__name__ == "TrapezoidMapTriFinder"]
    assert len(trap) == 1, held
    finder = weakref.ref(trap[0])
    del held, trap
    gc.disable()
    try:
        m.release()
        assert finder() is None  # freed by reference counting, no cycle left for the collector
    finally:
        gc.enable()


def test_flags_of_a_natural_face_sample_its_whole_box(monkeypatch) -> None:
    """A face that is its surface's whole parameter box (``ImportedFace.natural``) has its flags
    on the whole grid, sides included, with no mesh mask built: mixed.igs' revolved face 12 has its
    pole on the side u = 0, which OCC's mesh left out of the mask by round-off (the flag was
    reported at u = pi/2, the same point), and the other faces keep their flags."""
    from occsurf.algorithms import quality
    from occsurf.bridge.exchange.step_iges import read_iges
    from occsurf.bridge.quality import report as R

    model = read_iges(SAMPLES / "mixed.igs")
    assert all(f.natural for f in model.faces) and all(f.trimmed is None for f in model.faces)
    built = []
    original = R.uv_mask
    monkeypatch.setattr(R, "uv_mask", lambda mesh: built.append(mesh.index) or original(mesh))
    rep = check_model(model, edges=False)
    assert built == []
    for row in rep.faces:
        s = model.faces[row.index].surface
        (u0, u1), (v0, v1) = s.domain
        want = quality.face_flags(s, mask=None, us=np.linspace(u0, u1, 41), vs=np.linspace(v0, v1, 41))
        assert row.flags == [R._flag_json(f) for f in want], row.index
    pole = [f for f in rep.faces[12].flags if f["kind"] == "near_degenerate_normal"]
    assert len(pole) == 1 and pole[0]["uv"][0] == 0.0 and pole[0]["location"] == [12.0, 7.0, -8.0]
    # a trimmed face still classifies its grid against its loops
    loft = read_step(SAMPLES / "loft.step")
    assert any(f.natural is False and f.trimmed is not None for f in loft.faces)


def test_sections_cut_natural_faces_unmasked(monkeypatch) -> None:
    """A natural face (its surface's whole box) is cut by the sections without a mesh mask: no
    triangle finder is built for mixed.igs (every face natural), and the section lines equal those
    cut through the mesh masks to 1e-9 of the model's size (a cut's end on a face's side found by
    the march instead of the bisection to the mesh's boundary: 4e-10 measured; identical on the
    bearing, the screw and four samples; 5e-10 on linkrods, 6e-11 on the lens)."""
    import occsurf.bridge.quality.uv_masks as M
    from occsurf.bridge.exchange.step_iges import read_iges

    rep = check_model(read_iges(SAMPLES / "mixed.igs"), edges=False, flags=False)
    fields = [rep.fields[k] for k in sorted(rep.fields)]
    assert all(f.natural for f in fields)
    built = []
    real = M.uv_mask
    monkeypatch.setattr(M, "uv_mask", lambda mesh: built.append(mesh.index) or real(mesh))
    unmasked = P.section_lines(fields, rep.size)
    assert built == []
    for f in fields:
        f.natural = False
    masked = P.section_lines(fields, rep.size)
    assert built  # the masks were used this time

    def arrays(x):
        if isinstance(x, np.ndarray):
            return [x]
        if isinstance(x, dict):
            return [a for k in sorted(x) for a in arrays(x[k])]
        return [a for y in x for a in arrays(y)] if isinstance(x, (list, tuple)) else []

    a, b = arrays(unmasked), arrays(masked)
    assert len(a) == len(b) > 100 and [x.shape for x in a] == [y.shape for y in b]
    assert max(float(np.abs(x - y).max(initial=0.0)) for x, y in zip(a, b)) <= 1e-9 * rep.size


def test_face_values_compute_zebra_and_isophotes_when_asked(loft_report, monkeypatch) -> None:
    """``FaceField.values`` holds the curvatures and the draft and computes the zebra phase and the
    isophote intensity on each access (memory on large models): the values the zebra and isophote
    functions give on the same mesh with the report's set-up (the literals it had when the values
    were held), bit for bit; every name listed, in order, and ``in`` computes nothing; the mapping
    survives pickling (as a report's fields would)."""
    import pickle

    from occsurf.algorithms.quality import isophotes, zebra
    from occsurf.bridge.quality import face_values
    from occsurf.bridge.quality.face_values import VALUE_NAMES

    fld = loft_report.fields[3]
    vals = fld.values
    assert list(vals) == list(VALUE_NAMES) and len(vals) == len(VALUE_NAMES)
    assert "zebra" not in vals._held and "isophote" not in vals._held  # not held: computed
    vd = np.array([-1.0, 1.0, -0.8])  # face_fields' default view, as check_model calls it
    d = 10.0 * loft_report.size  # ZEBRA_DISTANCE, ZEBRA_WIDTH 0.45, ISOPHOTE_LEVELS 12
    phase = zebra(fld.mesh.points, fld.mesh.normals, vd, width=0.45 * d, distance=d).phase
    assert np.array_equal(vals["zebra"], phase, equal_nan=True) and np.nanmax(vals["zebra"]) > 0.5
    assert np.array_equal(vals["isophote"], isophotes(fld.mesh.normals, -vd, 12).intensity, equal_nan=True)
    with monkeypatch.context() as mp:
        mp.setattr(face_values.FaceValues, "__getitem__", lambda self, key: pytest.fail("computed for `in`"))
        assert "zebra" in vals and "isophote" in vals and "mean" in vals and "nope" not in vals
    assert vals["zebra"] is not vals["zebra"]  # a new array on each access: nothing kept
    with pytest.raises(KeyError):
        vals["nope"]
    again = pickle.loads(pickle.dumps(vals))
    assert list(again) == list(vals)
    assert all(np.array_equal(again[k], vals[k], equal_nan=True) for k in vals)
