"""The user guide's section "From build123d / cadquery" (issue 16; in the README until the
documentation site) runs as written.

``tests/test_readme.py`` runs every block of README.md and the guide; this test runs the section's ```python blocks
in one namespace in a scratch directory, as that test does, and checks what they print.
"""

from __future__ import annotations

import contextlib
import io
import re
from pathlib import Path

import pytest

pytest.importorskip("build123d")
pytest.importorskip("cadquery")

ROOT = Path(__file__).resolve().parents[2]


def _section() -> str:
    """The guide's page (the section, whole)."""
    text = (ROOT / "docs" / "guide" / "04_from_build123d_cadquery.md").read_text(encoding="utf-8")
    assert text.startswith("# From build123d / cadquery")
    return text


SECTION = _section()

BLOCK = re.compile(r"^```python\n(.*?)^```", re.S | re.M)


def test_section_blocks_run(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    namespace: dict[str, object] = {"__name__": "readme"}
    out = io.StringIO()
    blocks = BLOCK.findall(SECTION)
    assert len(blocks) == 2
    with contextlib.redirect_stdout(out):
        for source in blocks:
            exec(compile(source, "README section", "exec"), namespace)  # noqa: S102 - ours
    lines = out.getvalue().splitlines()
    assert lines[0] == "[('plate_a', (1.0, 0.0, 0.0, 1.0)), ('plate_b', (0.0, 0.0, 1.0, 1.0))]"
    assert lines[1] == "[('plate_a', (0.0, 0.0, 0.0)), ('plate_b', (30.0, 0.0, 0.0))]"
    assert lines[2] == "['plate_a', 'plate_b']"
    assert lines[3] == "['Cylinder', 'Plane']"
    kind, status, valid, g1 = lines[4].split()
    assert (kind, status, valid) == ("Solid", "filled", "True") and float(g1) < 1e-6
    assert (tmp_path / "plates.step").is_file()
