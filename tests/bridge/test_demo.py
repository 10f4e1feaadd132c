"""``occsurf demo`` writes its pictures and STEP files, and reports a broken demo in one line."""

from __future__ import annotations

import pytest

from occsurf.bridge import cli
from occsurf.bridge.exchange.step_iges import read_step
from occsurf.examples import gallery as demo


def test_demo_writes_pngs_and_readable_step(tmp_path, capsys):
    assert cli.main(["demo", "--out", str(tmp_path), "--only", "manipulation"]) == 0
    files = sorted((tmp_path / "manipulation").iterdir())
    pngs = [f for f in files if f.suffix == ".png"]
    steps = [f for f in files if f.suffix == ".step"]
    assert len(pngs) == 2 and len(steps) == 1
    for f in pngs:
        assert f.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and f.stat().st_size > 10_000
    model = read_step(steps[0])
    assert len(model.faces) == 1 and model.faces[0].surface is not None
    out = capsys.readouterr().out
    assert "manipulation" in out and str(steps[0]) in out


def test_demo_failure_is_one_line_and_others_still_run(tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(demo.DEMOS, "broken", "occsurf.examples.gallery:no_such_function")
    status = cli.main(["demo", "--out", str(tmp_path), "--only", "broken", "manipulation"])
    assert status == 2
    captured = capsys.readouterr()
    err_lines = [line for line in captured.err.splitlines() if line]
    assert len(err_lines) == 1 and err_lines[0].startswith("occsurf: demo broken:")
    assert "Traceback" not in captured.err
    assert (tmp_path / "manipulation" / "manipulation.step").exists()


def test_unknown_demo_is_rejected(tmp_path, capsys):
    assert cli.main(["demo", "--out", str(tmp_path), "--only", "nope"]) == 2
    assert "unknown demo nope" in capsys.readouterr().err


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(set(demo.DEMOS) - {"manipulation", "figures"}))  # figures: test_figures_vs_occ
def test_every_registered_demo_writes_pictures_and_step(tmp_path, capsys, name):
    """Each gallery entry, run as a user runs it, writes real PNGs and STEP files OCC can read."""
    assert cli.main(["demo", "--out", str(tmp_path), "--only", name]) == 0, capsys.readouterr().err
    files = sorted((tmp_path / name).iterdir())
    pngs = [f for f in files if f.suffix == ".png"]
    steps = [f for f in files if f.suffix == ".step"]
    assert pngs and steps, files
    for f in pngs:
        assert f.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and f.stat().st_size > 10_000
    for f in steps:
        model = read_step(f)
        assert model.faces and all(face.surface is not None for face in model.faces)
    out = capsys.readouterr().out
    assert all(str(f) in out for f in pngs + steps)
