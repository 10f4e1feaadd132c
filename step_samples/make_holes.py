"""Rebuild the STEP files with holes in ``step_samples/holes/`` (read by ``occsurf fill``).

Run from anywhere::

    python step_samples/make_holes.py            # writes into step_samples/holes/
    python step_samples/make_holes.py OUTDIR

Each hole is a ring model of ``examples/hole_models.py``: faces that are a smooth base
surface composed with bilinear maps (exact Bézier/B-spline faces), with a multi-span C2 bump so
that the hole sides are genuine multi-span B-splines; the hole's neighbours are G2 to each other.
Every ring is a shell whose outer loop is its boundary (``occsurf fill`` leaves that loop alone).

| file | holds |
|---|---|
| ``holes/dome_holes.step`` | bicubic dome, four rings around a 3-, 4-, 5- and 6-sided hole (degree 6, 4 spans) |
| ``holes/rational_holes.step`` | rational biquadratic dome, rings around a 5- and an 8-sided hole (rational degree 4) |

The files are written with :func:`occsurf.bridge.exchange.step_iges.write_step` (17 digits); the STEP time stamp is
fixed so rebuilding gives the same bytes.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path
from typing import TYPE_CHECKING

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

from occsurf.bridge.conversion.splines import make_face  # noqa: E402
from occsurf.bridge.exchange.step_iges import write_step  # noqa: E402
from occsurf.bridge.modeling.fill import sew_faces  # noqa: E402
from occsurf.examples.hole_models import ring_model  # noqa: E402

if TYPE_CHECKING:
    from OCP.TopoDS import TopoDS_Shape

FIXED_STEP_TIME = "2000-01-01T00:00:00"
LAYOUT = {
    "dome_holes.step": (False, [(3, (0.27, 0.27)), (4, (0.73, 0.27)), (5, (0.27, 0.73)), (6, (0.73, 0.73))]),
    "rational_holes.step": (True, [(5, (0.3, 0.5)), (8, (0.72, 0.5))]),
}


def build(rational: bool, holes: list[tuple[int, tuple[float, float]]]) -> TopoDS_Shape:
    faces = []
    for n, c in holes:
        m = ring_model(n, rational=rational, center=c, radius=0.1, width=0.08, bump=0.3)
        faces += [make_face(f, 1e-7) for f in m.faces]
    return sew_faces(faces)


def main(out: Path) -> list[Path]:
    out.mkdir(parents=True, exist_ok=True)
    written = []
    for name, (rational, holes) in LAYOUT.items():
        p = write_step(out / name, build(rational, holes), names=name.split(".")[0])
        text = re.sub(r"FILE_NAME\('([^']*)','[^']*'", lambda m: f"FILE_NAME('{m.group(1)}','{FIXED_STEP_TIME}'",
                      p.read_text())
        p.write_text(text)
        written.append(p)
    return written


if __name__ == "__main__":
    target = Path(sys.argv[1]) if len(sys.argv) > 1 else HERE / "holes"
    for f in main(target):
        print(f)
