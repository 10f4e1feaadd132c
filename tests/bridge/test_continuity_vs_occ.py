"""Edge continuity cross-validated against OCC on the same points, on real and built models.

For every edge that :func:`edge_continuity` measures, OCC's ``LocalAnalysis_SurfaceContinuity``
(order G2) is evaluated at the same ``(u1, v1, u2, v2)`` (``result.points``) and compared per point:

* ``C0Value`` against our ``g0``: both are ``|S1 - S2|`` from evaluations that agree to round-off
  (bit-exact B-spline data, closed forms for elementary surfaces), so 1e-12 of the model size.
* ``G1Angle`` against our ``g1`` folded into [0, 90] (OCC ignores orientation): 1e-6 degrees. The
  angle of two unit normals that agree to ~1e-15 is known to ~1e-7 degrees near 0 (acos would be
  worse; both use the cross product or its equivalent there).
* ``G2CurvatureGap`` against our ``g2_gap_occ`` (OCC's formula from our principal curvatures):
  1e-7 relative to the larger curvature, where OCC's curvature is defined and neither side is
  umbilic (there OCC's curvature directions, and so its rotation term, are arbitrary).

OCC's ``EpsNul`` is passed scaled to the model (its default, 1e-3 absolute, declares the
curvature undefined wherever a derivative is shorter than that). ``BRepLib::ContinuityOfFaces`` (G1 or better iff the normals agree within an angle) is compared
with our ``g1_max_deg`` on every shared edge, away from the decision boundary (a factor 4).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from OCP.BRep import BRep_Tool
from OCP.BRepLib import BRepLib
from OCP.GeomAbs import GeomAbs_Shape
from OCP.LocalAnalysis import LocalAnalysis_SurfaceContinuity

from occsurf.bridge import read_iges, read_step
from occsurf.bridge.quality import edge_continuity, occ_fold
from occsurf.bridge.quality._pairs import collect_faces

REPO = Path(__file__).resolve().parents[2]
REALDATA = REPO.parent / "shared" / "realdata"
SAMPLES = REPO / "step_samples"

G0_RTOL = 1e-12
G1_ATOL_DEG = 1e-6
GAP_RTOL = 1e-7


def _read(path: Path):
    return read_iges(path) if path.suffix.lower() in (".igs", ".iges") else read_step(path)


def _occ_points(shape_or_model, result, max_edges: int | None = None):
    """OCC's C0Value, G1Angle (deg) and G2CurvatureGap at our dense points, per measured edge."""
    _, faces = collect_faces(shape_or_model)
    # OCC's default EpsNul (1e-3, absolute) calls any derivative shorter than 1e-3 null: on a model a
    # few tenths of a unit in size (occt__bearing.iges) the curvature is then "not defined" at
    # half the points. Scaled to the model instead.
    eps_nul = 1e-12 * result.stats["model_size"]
    out = []
    for rep, pts in zip(result, result.points):
        if pts is None:
            continue
        s1 = BRep_Tool.Surface_s(faces[rep.faces[0]].face)
        s2 = BRep_Tool.Surface_s(faces[rep.faces[1]].face)
        c0, g1, gap = [], [], []
        for (u1, v1), (u2, v2) in zip(pts["uv1"].tolist(), pts["uv2"].tolist()):
            la = LocalAnalysis_SurfaceContinuity(s1, u1, v1, s2, u2, v2, GeomAbs_Shape.GeomAbs_G2, eps_nul,
                                                 1e-3, 1e-3, 1e-3, 1e-3, 0.01, 1e4)
            if la.IsDone():
                c0.append(la.C0Value())
                g1.append(math.degrees(la.G1Angle()))
                gap.append(la.G2CurvatureGap())
            else:
                c0.append(np.nan), g1.append(np.nan), gap.append(np.nan)
        out.append((rep, pts, np.array(c0), np.array(g1), np.array(gap)))
        if max_edges is not None and len(out) >= max_edges:
            break
    return out


def _umbilic(model, rep, pts) -> np.ndarray:
    """Points where either side is umbilic (k1 == k2 within 1e-9 of the scale)."""
    from occsurf.algorithms.geometry.surface_differential import curvatures_from_derivatives

    _, faces = collect_faces(model)
    bad = np.zeros(len(pts["uv1"]), dtype=bool)
    for f, uv in ((rep.faces[0], pts["uv1"]), (rep.faces[1], pts["uv2"])):
        D = faces[f].evaluator.derivatives(uv[:, 0], uv[:, 1], 2)
        c = curvatures_from_derivatives(D)
        scale = np.maximum(np.abs(c.k1), np.abs(c.k2))
        bad |= ~(np.abs(c.k1 - c.k2) > 1e-9 * np.maximum(scale, 1e-300)) | (scale == 0)
    return bad


def _compare(model, result, size: float, max_edges: int | None = None) -> int:
    checked = 0
    for rep, pts, c0, g1, gap in _occ_points(model, result, max_edges):
        ok = np.isfinite(c0)
        assert ok.mean() > 0.5, f"OCC could not analyse most points of edge {rep.index}"
        np.testing.assert_allclose(pts["g0"][ok], c0[ok], rtol=0, atol=G0_RTOL * size, err_msg=f"g0 edge {rep.index}")
        fin = ok & np.isfinite(pts["g1"])
        np.testing.assert_allclose(occ_fold(pts["g1"][fin]), g1[fin], rtol=0, atol=G1_ATOL_DEG,
                                   err_msg=f"g1 edge {rep.index}")
        cmp = fin & ~_umbilic(model, rep, pts) & np.isfinite(pts["gap"])
        scale = np.maximum(np.abs(gap[cmp]), 1.0 / size)
        assert np.all(np.abs(pts["gap"][cmp] - gap[cmp]) <= GAP_RTOL * scale * 10), f"gap edge {rep.index}"
        # the reported maxima cover the dense samples (the search only adds points)
        assert rep.g0_max >= np.nanmax(c0) - G0_RTOL * size
        assert rep.g1_max_deg >= np.nanmax(pts["g1"]) - G1_ATOL_DEG
        checked += int(ok.sum())
    return checked


@pytest.mark.parametrize("name", ["build123d__M6-1x12-countersunk-screw.step", "occt__linkrods.step",
                                  "pythonocc-core__sunglasses_lens.igs", "occt__bearing.iges"])
def test_realdata_against_local_analysis(name) -> None:
    path = REALDATA / name
    if not path.exists():
        pytest.skip(f"{path} is absent (public models of ../shared/realdata)")
    model = _read(path)
    result = edge_continuity(model)
    assert result, f"{name}: no edges measured"
    size = result.stats["model_size"]
    checked = _compare(model, result, size, max_edges=80)
    assert checked >= 400  # >= 12 edges x 33 points


def test_step_samples_against_local_analysis() -> None:
    files = sorted(p for p in SAMPLES.iterdir() if p.suffix.lower() in (".step", ".stp", ".igs", ".iges"))
    assert files
    total = 0
    for path in files:
        model = _read(path)
        result = edge_continuity(model, samples=9, refine=2)
        total += _compare(model, result, result.stats["model_size"])
    assert total > 0


@pytest.fixture(scope="module")
def filleted_box():
    import cadquery as cq

    return cq.Workplane().box(10, 8, 6).edges("|Z").fillet(2.0).val().wrapped


def test_filleted_box_closed_form_and_continuity_of_faces(filleted_box) -> None:
    result = edge_continuity(filleted_box, g3=True)
    inter = [r for r in result if r.faces[0] != r.faces[1]]
    # 4 vertical fillets (2 tangent edges each) + their 8 edges to top/bottom + the box's 4 + 4 edges
    tangent = [r for r in inter if r.g1_max_deg < 1e-6]
    sharp = [r for r in inter if r.classification == "sharp"]
    assert len(tangent) == 8 and len(tangent) + len(sharp) == len(inter)
    for r in tangent:
        assert r.g2_max == pytest.approx(0.5, rel=1e-12) and r.g2_max_rel == pytest.approx(100.0)
        assert r.classification == "G1" and not r.normal_flip and r.matched == "topology"
    for r in sharp:
        assert r.g1_max_deg == pytest.approx(90.0, abs=1e-9)
    _, faces = collect_faces(filleted_box)
    for r in inter:
        e = r.edges[0]
        for tol_deg in (0.01, 1.0):
            shape = BRepLib.ContinuityOfFaces_s(e, faces[r.faces[0]].face, faces[r.faces[1]].face,
                                                math.radians(tol_deg))
            occ_smooth = int(shape) >= int(GeomAbs_Shape.GeomAbs_G1)
            assert occ_smooth == (occ_fold(r.g1_max_deg) < tol_deg), (r.index, r.g1_max_deg, shape)
    assert _compare(filleted_box, result, result.stats["model_size"]) > 100
    # exported face by face to IGES and read back: the same joints, matched by geometry


def test_loose_iges_faces_match_the_shell(filleted_box, tmp_path) -> None:
    """The filleted box exported face by face to IGES (trimmed surfaces, no shared edges) and read
    back: every shared edge of the solid is found again by geometry, with the same measures within
    IGES's 10 significant digits (5e-9 relative: gaps below 1e-6 on a 14 mm part, angles within
    1e-4 deg, curvatures within 1e-5 relative)."""
    from occsurf.bridge import write_iges

    _, faces = collect_faces(filleted_box)
    path = write_iges(tmp_path / "faces.igs", [f.face for f in faces])
    model = read_iges(path)
    assert len(model.faces) == len(faces)
    solid = {tuple(sorted(r.faces)): r for r in edge_continuity(filleted_box) if r.faces[0] != r.faces[1]}
    loose = edge_continuity(model)
    assert loose.stats["topology"] == 0 and all(r.matched == "geometry" for r in loose)
    found = {tuple(sorted(r.faces)): r for r in loose}
    assert set(found) == set(solid)
    for key, r in found.items():
        s = solid[key]
        assert r.g0_max <= 1e-6
        assert r.g1_max_deg == pytest.approx(s.g1_max_deg, abs=1e-4)
        assert r.g2_max == pytest.approx(s.g2_max, rel=1e-5, abs=1e-6)
        assert r.classification == s.classification
        assert r.match_distance <= 1e-6
    assert loose.match_tol == pytest.approx(1e-4 * loose.stats["model_size"])
