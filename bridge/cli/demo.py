"""``occsurf demo [--out DIR] [--only NAME ...]``: the gallery of :mod:`occsurf.examples.gallery`.

Each chapter's showcase is rendered into ``OUT/<name>/`` as PNG pictures plus STEP files; a demo
that fails is reported in one line and the others still run (exit status 2 then).
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

__all__ = ["add_parser", "run"]


def run(ns: argparse.Namespace) -> int:
    """``occsurf demo``: :func:`occsurf.examples.gallery.run_demos` into ``--out``."""
    from occsurf.examples.gallery import run_demos

    return run_demos(Path(ns.out), ns.only)


def add_parser(sub: Any) -> None:
    """Register ``demo`` on the sub-parsers of :func:`occsurf.bridge.cli.build_parser`."""
    d = sub.add_parser(
        "demo",
        help="write a gallery of pictures (PNG) and STEP files of what occsurf does",
        description="Renders each chapter's showcase into OUT/<name>/ as PNG pictures plus STEP files.",
    )
    d.add_argument("--out", default="occsurf-demo", metavar="DIR", help="output folder (default: occsurf-demo)")
    d.add_argument("--only", nargs="+", metavar="NAME", help="run only these demos")
    d.set_defaults(func=run)
