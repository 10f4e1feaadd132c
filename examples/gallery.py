"""``occsurf demo``: a gallery of what occsurf does, written as PNG pictures plus STEP files.

Each chapter that has something to show registers one entry in :data:`DEMOS`: a name and the
dotted path of a function ``render(out_dir: Path) -> list[Path]``. Modules are imported only when
their demo runs, so a broken demo is reported (one line) and the others still run.
"""

from __future__ import annotations

import importlib
import sys
import time
from pathlib import Path

__all__ = ["DEMOS", "run_demos"]

#: name -> "module:function"; every function takes the output folder and returns the files it wrote.
DEMOS: dict[str, str] = {
    "manipulation": "occsurf.examples.manipulation:render_manipulation_demo",  # course ch. 3-4
    "generation": "occsurf.examples.generation:render_generation_demo",  # course §6-26..6-33
    "curvenet": "occsurf.examples.curvenet:render_curvenet_demo",  # course §6-20..6-25
    "hierarchical": "occsurf.examples.hierarchical:render_hierarchical_demo",  # course ch. 5
    "fitting": "occsurf.examples.fitting:render_fitting_demo",  # course §7-10
    "fill": "occsurf.examples.fill:render_fill_demo",  # course §8-3
    "generalized": "occsurf.examples.generalized:render_generalized_demo",  # course §8-6, 8-7
    "lighting": "occsurf.examples.lighting:render_lighting_demo",  # course ch. 10
    "repair": "occsurf.examples.repair:render_repair_demo",  # course ch. 3-4, 9 (issue 29)
    "figures": "occsurf.examples.figures:render_figures_demo",  # course §5-42..5-47
}


def run_demos(out_dir: Path, only: list[str] | None = None) -> int:
    """Run the demos into ``out_dir``; print each file written. Returns 0, or 2 if any demo failed."""
    names = list(DEMOS) if not only else only
    unknown = [n for n in names if n not in DEMOS]
    if unknown:
        print(f"occsurf: demo: unknown demo {', '.join(unknown)}; known: {', '.join(DEMOS)}", file=sys.stderr)
        return 2
    status = 0
    for name in names:
        module, func = DEMOS[name].split(":")
        t0 = time.perf_counter()
        try:
            files = getattr(importlib.import_module(module), func)(Path(out_dir) / name)
        except Exception as err:  # one line per failed demo, the others still run
            print(f"occsurf: demo {name}: {type(err).__name__}: {str(err).splitlines()[0] if str(err) else ''}",
                  file=sys.stderr)
            status = 2
            continue
        print(f"{name} ({time.perf_counter() - t0:.1f} s):")
        for f in files:
            print(f"  {f}")
    return status
