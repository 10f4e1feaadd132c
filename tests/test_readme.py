"""The README's Python snippets run as written, in order, in one namespace (a later block may use the
names an earlier one made), in a scratch directory where the repository's ``tests/fixtures`` and
``step_samples`` are reachable by the relative paths the README uses."""

from __future__ import annotations

import os
import re
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
BLOCK = re.compile(r"^```python\n(.*?)^```", re.S | re.M)


def python_blocks(text: str) -> list[tuple[int, str]]:
    """``(line number, source)`` of every fenced ```python block of ``text``."""
    return [(text.count("\n", 0, m.start()) + 2, m.group(1)) for m in BLOCK.finditer(text)]


def test_readme_has_python_blocks() -> None:
    assert len(python_blocks(README.read_text(encoding="utf-8"))) >= 6


def test_block_finder_sees_fences_only_at_line_starts() -> None:
    text = "intro\n```python\nx = 1\n```\n\n  ```python\nnot a block\n```\n```bash\nls\n```\n"
    assert python_blocks(text) == [(3, "x = 1\n")]


@pytest.mark.slow
def test_readme_python_blocks_run(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    (tmp_path / "tests").mkdir()
    (tmp_path / "tests" / "fixtures").symlink_to(ROOT / "tests" / "fixtures")
    (tmp_path / "step_samples").symlink_to(ROOT / "step_samples")
    monkeypatch.chdir(tmp_path)
    namespace: dict[str, object] = {"__name__": "readme"}
    np.random.seed(0)  # the README uses np.random.rand for sample data
    for line, source in python_blocks(README.read_text(encoding="utf-8")):
        code = compile(source, f"README.md, block at line {line}", "exec")
        try:
            exec(code, namespace)  # noqa: S102 - the README is ours
        except Exception as err:
            pytest.fail(f"README.md block at line {line} failed: {type(err).__name__}: {err}")
    written = sorted(p.name for p in tmp_path.iterdir() if p.is_file())
    assert written, "the README's snippets write at least one file (a STEP export)"
    assert os.getcwd() == str(tmp_path)
