"""Tests of :func:`occsurf.bridge.validation.inspect.inspect_model` called directly (not through the CLI)
on models read from ``step_samples/``.

Our evaluation of a B-spline face against OCC's on the same (bit-exact) data differs by round-off
only: relative to the bbox diagonal the sample faces stay below 1e-14; 1e-12 (the CLI tests'
``SAMPLE_TOL``) leaves a margin of 100.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from occsurf.algorithms.errors import InvalidGeometryError
from occsurf.bridge import FaceReport, inspect_model, read_iges, read_step
from occsurf.bridge.validation import deviation as validate

SAMPLES = Path(__file__).resolve().parents[2] / "step_samples"
SAMPLE_TOL = 1e-12


@pytest.fixture(scope="module")
def tube():
    return read_step(SAMPLES / "swept_tube.step")


def test_reports_are_typed_and_filled(tube) -> None:
    reports = inspect_model(tube, samples=9)
    assert len(reports) == len(tube.faces) == 3
    assert all(isinstance(r, FaceReport) for r in reports)
    assert [r.index for r in reports] == [f.index for f in tube.faces] == [0, 1, 2]
    swept = reports[0]
    assert swept.surface_type == "BSplineSurface" and swept.free_form
    assert swept.degree == (3, 9) and swept.poles == (12, 24)
    assert all(type(x) is int for x in swept.degree + swept.poles)
    assert swept.rational is False and swept.periodic == (True, False) and swept.continuity == "C2"
    for value in (swept.max_deviation, swept.max_d1_deviation, swept.max_d2_deviation, swept.max_normal_angle):
        assert type(value) is float and 0.0 <= value
    assert swept.max_deviation <= SAMPLE_TOL and swept.error is None
    plane = reports[1]
    assert plane.surface_type == "Plane" and not plane.free_form and plane.error is None
    assert (plane.degree, plane.poles, plane.rational, plane.max_deviation) == (None, None, None, None)
    assert plane.continuity == "CN" and type(plane.periodic) is tuple


@pytest.mark.parametrize("name", ["loft.step", "nurbs_torus.step", "periodic_vase.step", "mixed.igs"])
def test_free_form_faces_match_occ(name: str) -> None:
    model = (read_iges if name.endswith(".igs") else read_step)(SAMPLES / name)
    reports = inspect_model(model, samples=11)
    free = [r for r in reports if r.free_form]
    assert free and all(r.error is None for r in reports)
    assert max(r.max_deviation for r in free) <= SAMPLE_TOL
    for r, face in zip(reports, model.faces):  # the face's own fields, read as they are
        assert (r.index, r.name, r.surface_type, r.continuity) == (face.index, face.name, face.surface_type,
                                                                   face.continuity)
        assert r.periodic == (face.u_periodic, face.v_periodic)
    if name == "nurbs_torus.step":
        assert [(r.degree, r.poles, r.rational, r.periodic) for r in reports] == [((2, 2), (9, 9), True, (True, True))]


def test_json_round_trip(tube) -> None:
    for r in inspect_model(tube, samples=5):
        data = r.to_json()
        assert list(data) == [f.name for f in dataclasses.fields(FaceReport)]
        assert data["periodic"] == list(r.periodic) and FaceReport.from_json(data) == r


def test_unconverted_face_keeps_its_error_on_one_line(tube) -> None:
    broken = dataclasses.replace(tube.faces[0], surface=None, error="from_occ failed:\n  no luck")
    model = dataclasses.replace(tube, faces=[broken, *tube.faces[1:]])
    r = inspect_model(model, samples=5)[0]
    assert r.error == "from_occ failed: no luck"
    assert r.degree is None and r.max_deviation is None and r.surface_type == "BSplineSurface"


def test_failed_measurement_stays_with_the_face(tube, monkeypatch: pytest.MonkeyPatch) -> None:
    def broken(*args, **kwargs):
        raise ValueError("no grid today")

    monkeypatch.setattr(validate, "surface_deviation", broken)
    reports = inspect_model(tube, samples=5)
    assert reports[0].error == "deviation not measured: ValueError: no grid today"
    assert reports[0].degree == (3, 9) and reports[0].max_deviation is None
    assert reports[1].error is None


@pytest.mark.parametrize("samples", [1, 2.5, True, "25"])
def test_bad_samples_is_refused(tube, samples) -> None:
    with pytest.raises(InvalidGeometryError, match="samples"):
        inspect_model(tube, samples=samples)
