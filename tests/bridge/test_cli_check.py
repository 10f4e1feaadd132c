"""``occsurf check`` end to end: exit codes, the JSON keys, the files written, one-line errors,
and the page opened in a real headless Chromium (Debian's ``chromium``; skipped with the reason
when it is not installed)."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from occsurf.bridge.cli import main

from ..browser import chrome, needs_chromium

SAMPLES = Path(__file__).resolve().parents[2] / "step_samples"
REALDATA = Path(__file__).resolve().parents[3] / "shared" / "realdata"
FACE_KEYS = {"index", "type", "k_min", "k_max", "flags"}
EDGE_KEYS = {"faces", "midpoint", "matched", "g0_max", "g1_max_deg", "g2_max", "g2_max_rel", "worst_point"}


def _one_error_line(err: str) -> str:
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1, err
    assert lines[0].startswith("occsurf: ") and "Traceback" not in err
    return lines[0]


@pytest.fixture(scope="module")
def loft_out(tmp_path_factory):
    """One run through the worker process (the default), shared by the tests that read its output."""
    out = tmp_path_factory.mktemp("loft_check")
    proc = subprocess.run([sys.executable, "-m", "occsurf.bridge.cli", "check", str(SAMPLES / "loft.step"),
                           "--out", str(out), "--json"], capture_output=True, text=True, timeout=600)
    return out, proc


@pytest.mark.slow
def test_json_and_files(loft_out) -> None:
    out, proc = loft_out
    assert proc.returncode == 0, proc.stderr
    doc = json.loads(proc.stdout)
    assert json.loads((out / "report.json").read_text()) == doc
    assert (out / "index.html").is_file() and not list(out.glob(".viewer*")) and not list(out.glob(".progress*"))
    assert [f["index"] for f in doc["faces"]] == list(range(11))
    assert all(FACE_KEYS <= set(f) for f in doc["faces"])
    assert doc["edges"] and all(EDGE_KEYS <= set(e) for e in doc["edges"])
    for f in doc["faces"]:
        for name in f["pictures"].values():
            assert (out / name).stat().st_size > 2000
    # faces numbered as `occsurf inspect` numbers them
    from occsurf.bridge.validation.files import inspect_files

    (rep,) = inspect_files([str(SAMPLES / "loft.step")], samples=3)
    assert [(f.index, f.surface_type) for f in rep.faces] == [(f["index"], f["type"]) for f in doc["faces"]]


@pytest.mark.slow
def test_fail_on_gates(tmp_path, capsys) -> None:
    path = str(SAMPLES / "loft.step")
    assert main(["check", path, "--out", str(tmp_path / "a"), "--fail-on", "catia", "--in-process"]) == 1
    out = capsys.readouterr().out
    assert "--fail-on catia: FAILED" in out
    doc = json.loads((tmp_path / "a" / "report.json").read_text())
    assert doc["passed"] is False and doc["failures"]
    # the same model passes the mechanical preset (no curvature checks; its creases are by design)
    rc = main(["check", path, "--out", str(tmp_path / "b"), "--fail-on", "mechanical", "--in-process", "--faces", "9",
               "--no-pictures"])
    assert not list((tmp_path / "b").glob("*.png")) and (tmp_path / "b" / "index.html").is_file()
    doc = json.loads((tmp_path / "b" / "report.json").read_text())
    assert rc == (0 if doc["passed"] else 1)
    assert rc == 0, doc["failures"]


@pytest.mark.slow
def test_faces_option(tmp_path, capsys) -> None:
    assert main(["check", str(SAMPLES / "loft.step"), "--out", str(tmp_path), "--faces", "0,2-3", "--json",
                 "--in-process"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert [f["index"] for f in doc["faces"]] == [0, 2, 3]
    assert main(["check", str(SAMPLES / "loft.step"), "--out", str(tmp_path), "--faces", "99", "--in-process"]) == 2
    assert "faces" in _one_error_line(capsys.readouterr().err)
    assert main(["check", str(SAMPLES / "loft.step"), "--out", str(tmp_path), "--faces", "x"]) == 2
    _one_error_line(capsys.readouterr().err)


@pytest.mark.slow
def test_unreadable_and_missing(tmp_path, capsys) -> None:
    bad = tmp_path / "bad.step"
    bad.write_text("ISO-10303-21;\nHEADER;\nthis is not a model\n")
    assert main(["check", str(bad), "--out", str(tmp_path / "o")]) == 2
    line = _one_error_line(capsys.readouterr().err)
    assert str(bad) in line and "truncated" in line
    assert not (tmp_path / "o" / "index.html").exists()
    assert main(["check", str(tmp_path / "nope.step"), "--out", str(tmp_path / "o")]) == 2
    assert "no such file" in _one_error_line(capsys.readouterr().err)


def test_unwritable_out(tmp_path, capsys) -> None:
    blocker = tmp_path / "file"
    blocker.write_text("x")
    assert main(["check", str(SAMPLES / "loft.step"), "--out", str(blocker / "sub")]) == 2
    line = _one_error_line(capsys.readouterr().err)
    assert "--out" in line and "cannot write" in line


def test_model_without_shared_edges(tmp_path, capsys) -> None:
    """Loose faces far apart: nothing to match; the faces are still reported, the page says so."""
    from build123d import Box, Compound, Pos, export_step

    faces = list(Box(1, 1, 1).faces())[:1] + list((Pos(10, 0, 0) * Box(1, 1, 1)).faces())[:1]
    path = tmp_path / "loose.step"
    export_step(Compound(faces), str(path))
    assert main(["check", str(path), "--out", str(tmp_path / "o"), "--json", "--in-process"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert len(doc["faces"]) == 2 and doc["edges"] == []
    assert "nothing to measure" in (tmp_path / "o" / "index.html").read_text()


# ---------------------------------------------------------------------------------------- browser


@pytest.mark.slow
@needs_chromium
def test_page_in_headless_chromium(loft_out) -> None:
    """Open index.html from the file system in headless Chromium (WebGL through SwiftShader, the
    network cut off): the viewer script finishes, the 3-D canvas shows the model (a screenshot of
    the canvas element, not blank, many colours), switching the indicator to zebra changes the
    picture, and the face and edge tables are there, sortable."""
    import io
    import time

    from PIL import Image
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support.ui import Select, WebDriverWait

    out, proc = loft_out
    assert proc.returncode == 0
    drv = chrome(webgl=True)
    try:
        drv.get((out / "index.html").resolve().as_uri())
        WebDriverWait(drv, 60).until(lambda d: d.find_element(By.TAG_NAME, "body").get_attribute("data-viewer") == "ready")
        status = drv.find_element(By.ID, "viewer-status").text
        assert status.startswith("11 faces,"), status  # not "WebGL is not available ..."
        canvas = drv.find_element(By.ID, "viewer")
        drv.execute_script("arguments[0].scrollIntoView()", canvas)

        def shot() -> np.ndarray:
            time.sleep(0.5)  # a few animation frames
            return np.asarray(Image.open(io.BytesIO(canvas.screenshot_as_png)).convert("RGB")).astype(int)

        img = shot()
        model = np.abs(img - np.array([0xF4, 0xF6, 0xFA])).sum(axis=2) > 40
        assert model.mean() > 0.03, "the 3-D canvas is blank"
        assert len(np.unique(img[model] // 16, axis=0)) > 10, "the model is drawn in one flat colour"
        Select(drv.find_element(By.ID, "indicator")).select_by_value("zebra")
        for _ in range(10):  # SwiftShader compiles the stripe shader on first use
            zebra = shot()
            zmodel = np.abs(zebra - np.array([0xF4, 0xF6, 0xFA])).sum(axis=2) > 40
            g = zebra.mean(axis=2)
            grey = g[zmodel]
            rows = [r[(r < 50) | (r > 220)] < 50 for r in g[:: max(1, g.shape[0] // 20)]]
            edges = sum(int(np.count_nonzero(np.diff(r.astype(int)))) for r in rows if r.size)
            if (grey < 50).mean() > 0.02 and (grey > 220).mean() > 0.01 and edges >= 10:
                break
        else:
            raise AssertionError(f"no zebra stripes: {(grey < 50).mean():.3f} dark, {(grey > 220).mean():.3f} light, "
                                 f"{edges} stripe edges")
        rows = drv.find_elements(By.CSS_SELECTOR, "#face-table tbody tr")
        assert len(rows) == 11
        assert drv.find_elements(By.CSS_SELECTOR, "#edge-table tbody tr")
        header = drv.find_elements(By.CSS_SELECTOR, "#face-table th")[0]
        # the first column's shown text in one round trip (a WebDriver call per cell was 7 s of
        # the test: every call waits for the busy SwiftShader renderer)
        column = ("return Array.from(document.querySelectorAll('#face-table tbody tr'), "
                  "r => r.querySelector('td').innerText.trim())")
        header.click()
        first = drv.execute_script(column)
        header.click()
        second = drv.execute_script(column)
        assert len(first) == len(second) == 11
        assert sorted(first, key=int) in (first, second) and second == first[::-1]
    finally:
        drv.quit()


# ---------------------------------------------------------------------------------------- several files
@pytest.mark.slow
def test_folders_recursively_with_an_index(tmp_path, capsys) -> None:
    """A folder (searched recursively, STEP and IGES) and a file: one report folder per file, a
    top-level index.html and report.json over all (status, worst G1 edge, flags); an unreadable
    file costs its row only (exit 2), the other files are still checked."""
    src = tmp_path / "models"
    (src / "sub").mkdir(parents=True)
    shutil.copy(SAMPLES / "loft.step", src / "loft.step")
    shutil.copy(SAMPLES / "nurbs_torus.step", src / "sub" / "nurbs_torus.step")
    (src / "bad.step").write_text("ISO-10303-21;\nHEADER;\nthis is not a model\n")
    (src / "notes.txt").write_text("not a model")
    out = tmp_path / "o"
    rc = main(["check", str(src), "--out", str(out), "--no-pictures", "--fail-on", "mechanical"])
    captured = capsys.readouterr()
    assert rc == 2
    assert [ln for ln in captured.err.splitlines() if ln.strip()] == [
        ln for ln in captured.err.splitlines() if ln.startswith("occsurf: ") and "bad.step" in ln]
    doc = json.loads((out / "report.json").read_text())
    # loft breaks even the mechanical preset (a G0 edge at 3.1 deg); the torus passes it
    assert doc["n_files"] == 3 and doc["counts"] == {"failed": 1, "ok": 1, "unreadable": 1}
    rows = {Path(r["path"]).name: r for r in doc["files"]}
    assert rows["bad.step"]["status"] == "unreadable" and "truncated" in rows["bad.step"]["error"]
    loft = rows["loft.step"]
    assert loft["report"] == "loft_step/index.html" and (out / "loft_step" / "index.html").is_file()
    per_file = json.loads((out / "loft_step" / "report.json").read_text())
    assert loft["n_faces"] == per_file["n_faces"] == 11 and loft["n_edges"] == per_file["n_edges"]
    assert sum(loft["flags"].values()) == per_file["n_flags"] and loft["status"] == "failed"
    assert loft["n_violations"] == len(per_file["failures"]) > 0 and per_file["passed"] is False
    w = loft["worst_g1_edge"]
    smooth = [e for e in per_file["edges"] if e["classification"] in ("gap", "G0", "G1", "G2")]
    assert (w is None) == (not smooth)
    if w is not None:
        assert w["g1_max_deg"] == max(e["g1_max_deg"] for e in smooth)
    torus = rows["nurbs_torus.step"]
    assert torus["status"] == "ok" and torus["passed"] is True
    assert torus["report"] == "sub/nurbs_torus_step/index.html" and (out / "sub" / "nurbs_torus_step" / "report.json").is_file()
    page = (out / "index.html").read_text()
    assert 'href="loft_step/index.html"' in page and "unreadable" in page
    assert "http://" not in page and "https://" not in page and "<script src" not in page  # offline
    # the gate counts every file: loft breaks catia (wiggles, creases), so exit 1 when all are readable
    (src / "bad.step").unlink()
    rc = main(["check", str(src / "loft.step"), str(src / "sub"), "--out", str(tmp_path / "p"), "--no-pictures",
               "--fail-on", "catia", "--json"])
    summary = json.loads(capsys.readouterr().out)
    assert rc == 1 and summary["passed"] is False and summary["n_files"] == 2
    assert {r["status"] for r in summary["files"]} <= {"ok", "failed"} and summary["files"][0]["status"] == "failed"
    # every file passes: exit 0
    assert main(["check", str(src / "sub"), "--out", str(tmp_path / "q"), "--no-pictures", "--fail-on",
                 "mechanical"]) == 0
    assert "1 file: 1 ok" in capsys.readouterr().out
    # the summary line says what report.json's "failed" means: the file breaks the preset (it was read)
    assert main(["check", str(src / "loft.step"), str(src / "sub"), "--out", str(tmp_path / "r"), "--no-pictures"]) == 0
    assert "2 files: 1 breaks catia, 1 ok" in capsys.readouterr().out
    # --faces names faces of one model
    assert main(["check", str(src), "--faces", "1"]) == 2
    assert "--faces" in _one_error_line(capsys.readouterr().err)


@pytest.mark.slow
def test_a_crashing_face_is_left_out_and_named(tmp_path, capsys, monkeypatch) -> None:
    """A face that kills the worker (SIGSEGV inside OCC) costs that face only: the file is checked
    again without it, the report keeps every other face and names the crashed one."""
    import occsurf.bridge.quality.check_files as check_files

    monkeypatch.setattr(check_files, "CHECK_JOB", "tests.bridge.check_crash_jobs:crash_on_face")
    monkeypatch.setenv("OCCSURF_TEST_CRASH_FACES", "3,7")
    out = tmp_path / "o"
    assert main(["check", str(SAMPLES / "loft.step"), "--out", str(out), "--no-pictures"]) == 0
    text = capsys.readouterr().out
    assert "faces 3, 7 crashed the checker" in text
    doc = json.loads((out / "report.json").read_text())
    by = {f["index"]: f for f in doc["faces"]}
    assert sorted(by) == list(range(11))
    for k in (3, 7):
        assert "crashed the checker" in by[k]["error"] and "SIGSEGV" in by[k]["error"]
    assert all(by[k]["error"] is None and by[k]["k_max"] is not None for k in by if k not in (3, 7))
    assert doc["edges"]


@pytest.mark.slow
def test_a_crashing_picture_is_left_out(tmp_path, capsys, monkeypatch) -> None:
    import occsurf.bridge.quality.check_files as check_files

    monkeypatch.setattr(check_files, "CHECK_JOB", "tests.bridge.check_crash_jobs:crash_on_picture")
    monkeypatch.setenv("OCCSURF_TEST_CRASH_PICTURE", "face_1_zebra.png")
    out = tmp_path / "o"
    assert main(["check", str(SAMPLES / "loft.step"), "--out", str(out), "--faces", "0-2", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    by = {f["index"]: f for f in doc["faces"]}
    assert "zebra" not in by[1]["pictures"] and {"mean", "sections"} <= set(by[1]["pictures"])
    assert any("zebra not drawn" in n and "crashed" in n for n in by[1]["notes"])
    assert all({"mean", "zebra", "sections"} <= set(by[k]["pictures"]) for k in (0, 2))


def test_triangulation_freed_after_the_faces_changes_nothing(tmp_path, monkeypatch) -> None:
    """``check_file`` frees OCC's triangulation once the faces' meshes are copied: the pictures and
    the page's data are byte for byte those of a check that keeps it (nothing after the faces reads
    OCC's mesh; if something did, it would mesh a grid instead), and the shape is left unmeshed."""
    from OCP.BRep import BRep_Tool
    from OCP.TopAbs import TopAbs_FACE
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopLoc import TopLoc_Location
    from OCP.TopoDS import TopoDS

    from occsurf.bridge.quality import check_files

    seen = []
    original = check_files._drop_triangulation

    def dropping(model):
        original(model)
        seen.append(model.shape)

    outs = {}
    for label, drop in (("kept", lambda model: None), ("dropped", dropping)):
        monkeypatch.setattr(check_files, "_drop_triangulation", drop)
        check_files.check_file(SAMPLES / "mixed.igs", tmp_path / label, pictures="worst")
        outs[label] = {p.name: p.read_bytes() for p in (tmp_path / label).iterdir()}
    assert outs["kept"].keys() == outs["dropped"].keys() and any(n.endswith(".png") for n in outs["kept"])
    assert outs["kept"] == outs["dropped"]
    exp = TopExp_Explorer(seen[0], TopAbs_FACE)
    while exp.More():
        assert BRep_Tool.Triangulation_s(TopoDS.Face_s(exp.Current()), TopLoc_Location()) is None
        exp.Next()
