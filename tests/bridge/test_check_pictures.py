"""``occsurf check --pictures worst|all|none`` (issue 28): PNGs only where they serve."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from occsurf.bridge.cli import main
from occsurf.bridge.quality.report import face_scores

SAMPLES = Path(__file__).resolve().parents[2] / "step_samples"


def test_face_scores_rank_errors_then_flags_and_violations_then_g1():
    faces = [
        {"index": 0, "flags": [], "worst_g1_deg": 5.0},
        {"index": 1, "flags": [{"kind": "wiggle"}], "worst_g1_deg": 0.0},
        {"index": 2, "flags": [], "worst_g1_deg": 0.1, "error": "did not convert"},
        {"index": 3, "flags": [], "worst_g1_deg": 0.2},
        {"index": 4, "flags": [], "worst_g1_deg": 0.3},
    ]
    violations = [{"faces": [3, 4], "measure": "g1"}, {"faces": [3, 0], "measure": "g2_rel"}]
    s = face_scores(faces, violations)
    order = sorted(s, key=lambda i: -s[i])
    # the error first; then 3 (two violations), then 0 and 1 and 4 (one flag or violation each, by G1)
    assert order == [2, 3, 0, 4, 1]


@pytest.mark.slow
def test_worst_all_and_none(tmp_path, capsys):
    path = str(SAMPLES / "loft.step")  # 11 faces: one more than the worst 10
    assert main(["check", path, "--out", str(tmp_path / "w"), "--in-process"]) in (0, 1)
    doc = json.loads((tmp_path / "w" / "report.json").read_text())
    drawn = sorted(f["index"] for f in doc["faces"] if f["pictures"])
    assert doc["face_pictures"] == {"choice": "worst", "faces": drawn} and len(drawn) == 10
    s = face_scores(doc["faces"], doc["violations"])
    left_out = (set(range(11)) - set(drawn)).pop()
    assert all(s[left_out] <= s[i] for i in drawn)  # the one left out is the least bad
    assert {p.name for p in (tmp_path / "w").glob("model_*.png")} >= {"model_mean.png", "model_zebra.png"}
    assert len(list((tmp_path / "w").glob("face_*.png"))) == 30
    page = (tmp_path / "w" / "index.html").read_text()
    assert f'id="face-{left_out}"' in page  # its row and details stay, without pictures

    assert main(["check", path, "--out", str(tmp_path / "a"), "--in-process", "--pictures", "all"]) in (0, 1)
    doc = json.loads((tmp_path / "a" / "report.json").read_text())
    assert doc["face_pictures"] == {"choice": "all", "faces": None}
    assert all(f["pictures"] for f in doc["faces"]) and len(list((tmp_path / "a").glob("face_*.png"))) == 33

    for flag in (["--pictures", "none"], ["--no-pictures"]):
        out = tmp_path / flag[-1].strip("-")
        assert main(["check", path, "--out", str(out), "--in-process", *flag]) in (0, 1)
        doc = json.loads((out / "report.json").read_text())
        assert doc["face_pictures"] == {"choice": "none", "faces": []}
        assert not list(out.glob("*.png")) and (out / "index.html").is_file()
    capsys.readouterr()


@pytest.mark.parametrize("args", [["--pictures", "bogus"], ["--pictures", "all", "--no-pictures"]])
def test_bad_pictures_option_is_one_line_exit_2(tmp_path, capsys, args):
    assert main(["check", str(SAMPLES / "loft.step"), "--out", str(tmp_path / "x"), *args]) == 2
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]
    assert len(err) == 1 and err[0].startswith("occsurf: check: argument") and "--pictures" in err[0]


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2**31 - 1), st.integers(1, 6))
def test_hedgehog_points_face_by_face_are_those_of_all_vertices_at_once(seed: int, n_faces: int) -> None:
    """Issue 28 (memory): the normals picture's points are picked face by face, then over the picks,
    instead of over every vertex of the model at once (~250 MB of copies for 1.8 million vertices);
    the points and normals are the same, in the same order: per cell of the grid, the first vertex
    with a normal in the faces' order, the cells sorted (faces sharing cells, normals undefined at
    some vertices, a face with none)."""
    from types import SimpleNamespace

    from occsurf.bridge.quality.pictures import HEDGEHOG_CELLS, _hedgehog_points

    rng = np.random.default_rng(seed)
    fields = []
    for _ in range(n_faces):
        P = rng.uniform(-1, 1, (int(rng.integers(0, 400)), 3)) * rng.uniform(0.1, 3.0)
        N = rng.normal(size=P.shape)
        N[rng.random(len(P)) < 0.2] = np.nan
        fields.append(SimpleNamespace(mesh=SimpleNamespace(points=P, normals=N)))
    size = float(rng.uniform(0.5, 10.0))
    P = np.concatenate([f.mesh.points for f in fields])
    N = np.concatenate([f.mesh.normals for f in fields])
    ok = np.all(np.isfinite(N), axis=1)
    P, N = P[ok], N[ok]
    got = _hedgehog_points(fields, size)
    if not len(P):
        assert got[0].shape == (0, 3) and got[1].shape == (0, 3)
        return
    keys = np.floor((P - P.min(axis=0)) / (size / HEDGEHOG_CELLS)).astype(np.int64)
    _, first = np.unique(keys, axis=0, return_index=True)
    np.testing.assert_array_equal(got[0], P[first])
    np.testing.assert_array_equal(got[1], N[first])
