"""``occsurf check --pictures worst|all|none`` (issue 28): PNGs only where they serve."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

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
