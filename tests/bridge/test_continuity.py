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
