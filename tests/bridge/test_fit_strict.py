"""``occsurf fit --strict`` (issue 16): every reading command refuses a file read around damage with
``--strict``; fit did not have the option. Without it fit reads such a file as read and says so, one
``warning:`` line per warning on stderr (and ``warnings`` in its JSON), as render and fill do.

The damaged file is made here from a clean one (tests/bridge/corrupt_files.py): a STEP box whose one
ADVANCED_FACE record is deleted, which OCC reads with the face missing and occsurf warns about.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from occsurf.algorithms.errors import ExchangeError
from occsurf.bridge.exchange.step_iges import write_step

from . import corrupt_files as C

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def files(tmp_path_factory) -> dict[str, Path]:
    cq = pytest.importorskip("cadquery")
    folder = tmp_path_factory.mktemp("fit_strict")
    box = cq.Workplane().box(1, 2, 3).edges("|Z").fillet(0.2).val().wrapped
    clean = write_step(folder / "box.step", [box])
    st = C.StepText.parse(clean.read_bytes())
    face = next(i for i, r in enumerate(st.records) if b"ADVANCED_FACE" in r)
    return {"clean": clean, "bad": C.write(folder, "noface.step", C.step_delete(st, face))}


def _fit(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "occsurf.bridge.cli", "fit", *args, "--tol", "1e-3", "--ctrl", "6",
                           "6", "--timeout", "300"], capture_output=True, text=True, cwd=REPO, timeout=600)


@pytest.mark.slow
def test_fit_strict_refuses_a_damaged_file_and_writes_nothing(files, tmp_path):
    out = tmp_path / "fit.step"
    proc = _fit(str(files["bad"]), "--out", str(out), "--strict")
    lines = proc.stderr.strip().splitlines()
    assert proc.returncode == 2 and "Traceback" not in proc.stderr, proc.stderr
    # the message of inspect/fill/render/convert/check: 'occsurf: PATH: refused by --strict: N warnings: ...'
    assert len(lines) == 1 and lines[0].startswith(f"occsurf: {files['bad']}: refused by --strict: "), lines
    assert not out.exists() and not out.with_suffix(".json").exists() and not out.with_suffix(".png").exists()


@pytest.mark.slow
def test_fit_without_strict_fits_and_names_the_warnings(files, tmp_path):
    out = tmp_path / "fit.step"
    proc = _fit(str(files["bad"]), "--out", str(out), "--json")
    assert proc.returncode == 0, proc.stderr
    doc = json.loads(proc.stdout)
    warned = [ln for ln in proc.stderr.splitlines() if ln.startswith(f"occsurf: {files['bad']}: warning: ")]
    assert doc["warnings"] and len(warned) == len(doc["warnings"]), (doc["warnings"], proc.stderr)
    assert out.is_file()


@pytest.mark.slow
def test_fit_strict_passes_a_clean_file(files, tmp_path):
    out = tmp_path / "fit.step"
    proc = _fit(str(files["clean"]), "--out", str(out), "--strict", "--json")
    assert proc.returncode == 0 and "warning" not in proc.stderr, proc.stderr
    assert json.loads(proc.stdout)["warnings"] == [] and out.is_file()


def test_read_fit_input_strict_in_the_library(files):
    from occsurf.bridge.modeling.fit import read_fit_input

    assert read_fit_input(files["bad"]).warnings  # read around the damage, warned
    with pytest.raises(ExchangeError, match=r"noface\.step: refused by --strict: \d+ warnings?: "):
        read_fit_input(files["bad"], strict=True)
    assert read_fit_input(files["clean"], strict=True).warnings == []
