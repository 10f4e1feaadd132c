"""The Python snippets of the README and of the user guide it links to (``docs/guide/*.md``, the
sections the README held before the documentation site) run as written, in order, in one
namespace (a later block may use the names an earlier one made), in a scratch directory where the
repository's ``tests/fixtures`` and ``step_samples`` are reachable by the relative paths they use."""

from __future__ import annotations

import os
import re
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
GUIDE = sorted((ROOT / "docs" / "guide").glob("[0-9]*.md"))
BLOCK = re.compile(r"^```python\n(.*?)^```", re.S | re.M)


def python_blocks(text: str) -> list[tuple[int, str]]:
    """``(line number, source)`` of every fenced ```python block of ``text``."""
    return [(text.count("\n", 0, m.start()) + 2, m.group(1)) for m in BLOCK.finditer(text)]


def _documents() -> list[Path]:
    return [README, *GUIDE]


def test_readme_has_python_blocks() -> None:
    assert len(GUIDE) >= 10
    assert sum(len(python_blocks(p.read_text(encoding="utf-8"))) for p in _documents()) >= 6


def test_the_readme_links_every_guide_page() -> None:
    text = README.read_text(encoding="utf-8")
    assert all(f"(docs/guide/{p.name})" in text for p in GUIDE)


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
    for doc in _documents():
        name = doc.relative_to(ROOT)
        for line, source in python_blocks(doc.read_text(encoding="utf-8")):
            code = compile(source, f"{name}, block at line {line}", "exec")
            try:
                exec(code, namespace)  # noqa: S102 - the README and the guide are ours
            except Exception as err:
                pytest.fail(f"{name} block at line {line} failed: {type(err).__name__}: {err}")
    written = sorted(p.name for p in tmp_path.iterdir() if p.is_file())
    assert written, "the README's snippets write at least one file (a STEP export)"
    assert os.getcwd() == str(tmp_path)
