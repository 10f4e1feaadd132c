"""What the gallery's render functions share: their output folder, 3-D axes labelling, and the
``python -m occsurf.examples.<name> [OUT_DIR]`` entry point."""

from __future__ import annotations

import sys
from collections.abc import Callable
from pathlib import Path


def output_folder(out_dir: Path | str) -> Path:
    """``out_dir`` as a Path, created (with its parents) if missing."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    return out


def script(render: Callable[[Path], list[Path]]) -> None:  # pragma: no cover - manual use
    """Run ``render`` into ``sys.argv[1]`` (default ``demo_out``) and print the files it wrote."""
    for p in render(Path(sys.argv[1] if len(sys.argv) > 1 else "demo_out")):
        print(p)
