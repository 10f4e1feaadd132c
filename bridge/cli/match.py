"""``occsurf match IN --face I --to J [--continuity G0|G1|G2|G3] [--preserve-opposite none|G0|G1|G2]
[--average] [--tol-g0 D] [--tol-g1 DEG] [--tol-g2 PCT] [--sharp-deg DEG] --out OUT.step [--json]
[--timeout S] [--strict] [--in-process]``.

Changes face ``I`` of a STEP/IGES model so that it meets face ``J`` with the asked continuity along
their shared edge (:func:`occsurf.bridge.modeling.matching.match_faces`, in a worker process:
:func:`occsurf.bridge.audit.match_file.match_file`), writes ``OUT`` (STEP) and prints the edge
before and after as OCC's ``LocalAnalysis`` measures it. Faces are numbered as ``occsurf inspect`` and
``occsurf check`` number them. Exit status 0 when the model was written; 2 (one line on stderr,
nothing written) for faces that share no edge, a face number out of range, a sharp edge, G2 or G3
along an edge inside the face's surface (a face trimmed across its surface is matched G0 or G1
there), a continuity the degree cannot carry, tolerances not met or a result
``BRepCheck_Analyzer`` finds invalid.

``--json`` prints ``{"face", "target", "continuity", "g0_max", "g1_max_deg", "g2_max_rel",
"max_change", "knots_added", "opposite_g1_max_deg", ...}`` (``g2_max_rel`` a fraction: 0.01 is
CATIA's 1 %).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from ._common import (
    EXIT_ERROR,
    EXIT_OK,
    add_strict_option,
    error,
    fmt_deg,
    fmt_dev,
    format_rows,
    outcome_problem,
    paths_problem,
    positive_arg,
    shown_path,
    timeout_arg,
)

__all__ = ["add_parser", "run", "DEFAULT_TIMEOUT"]

#: Seconds the worker may take to read, match and write.
DEFAULT_TIMEOUT = 300.0


def _face(text: str) -> int:
    try:
        i = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a face number, got {text!r}") from None
    if i < 0:
        raise argparse.ArgumentTypeError(f"expected a face number >= 0, got {i}")
    return i


def _table(src: Path, out: Path, rep: dict[str, Any]) -> None:
    sys.stdout.write(f"{src}: face {rep['face']} matched to face {rep['target']} ({rep['continuity']}, side "
                     f"{rep['side']}{', converted from ' + rep['converted'] if rep['converted'] else ''})\n")
    rows = [("", "G0 gap", "G1 angle", "other edges G1"),
            ("before", fmt_dev(rep["g0_before"]), fmt_deg(rep["g1_before_deg"]), fmt_deg(rep["opposite_g1_before_deg"])),
            ("after", fmt_dev(rep["g0_max"]), fmt_deg(rep["g1_max_deg"]), fmt_deg(rep["opposite_g1_max_deg"]))]
    for line in format_rows(rows):
        sys.stdout.write(line + "\n")
    g2 = rep["g2_max_rel"]
    sys.stdout.write(f"  (OCC LocalAnalysis_SurfaceContinuity along the edge; curvature jump across it "
                     f"{'-' if g2 is None else f'{100 * g2:.3g} %'}; largest change {fmt_dev(rep['max_change'])}; "
                     f"{rep['knots_added']} knots added)\n")
    for note in rep.get("notes") or ():
        sys.stdout.write(f"  note: {note}\n")
    sys.stdout.write(f"wrote {out}\n")


def run(ns: argparse.Namespace) -> int:
    """``occsurf match IN --face I --to J --out OUT``."""
    from ..audit.match_file import match_file

    src, out = Path(ns.input), Path(ns.out)
    if paths_problem(src, out, "the matched model"):
        return EXIT_ERROR
    item = {"input": str(src), "output": str(out), "face": ns.face, "target": ns.to, "continuity": ns.continuity,
            "preserve_opposite": ns.preserve_opposite, "average": ns.average, "tol_g0": ns.tol_g0,
            "tol_g1_deg": ns.tol_g1, "tol_g2_rel": ns.tol_g2 / 100.0, "sharp_deg": ns.sharp_deg, "strict": ns.strict}
    outcome = match_file(item, timeout=ns.timeout, isolate=not ns.in_process)
    if outcome_problem(outcome, src, ns.timeout, "reading and matching this file"):
        return EXIT_ERROR
    result = outcome.value
    for w in result.get("warnings", ()):
        error(f"{shown_path(src)}: warning: {w}")
    if result["refused"]:
        error(f"{shown_path(src)}: {result['refused']}")
        return EXIT_ERROR
    if ns.json:
        sys.stdout.write(json.dumps({**result["report"], "input": str(src), "output": str(out)}, indent=1) + "\n")
    else:
        _table(src, out, result["report"])
    sys.stdout.flush()
    return EXIT_OK


def add_parser(sub: Any) -> None:
    """Register ``match`` on the sub-parsers of :func:`occsurf.bridge.cli.build_parser`."""
    m = sub.add_parser(
        "match",
        help="make a face meet its neighbour G0/G1/G2/G3 along their shared edge (least change of its poles)",
        description=("Changes face I of a STEP/IGES model by the least change of its poles (course ch. 3-4) so "
                     "that it meets face J along their shared edge with the asked continuity, writes OUT (STEP) "
                     "and prints the edge before and after (OCC LocalAnalysis). Exit status 0 when written, 2 "
                     "otherwise (one line saying why; nothing written)."),
    )
    m.add_argument("input", metavar="IN", help="STEP or IGES file")
    m.add_argument("--face", type=_face, required=True, metavar="I", help="the face to change (as inspect numbers it)")
    m.add_argument("--to", type=_face, required=True, metavar="J", help="the face to match it to")
    m.add_argument("--continuity", choices=("G0", "G1", "G2", "G3"), default="G1", help="order to reach (default G1)")
    m.add_argument("--preserve-opposite", choices=("none", "G0", "G1", "G2"), default="G1",
                   help="keep the opposite side's position / tangent plane / curvature (default G1)")
    m.add_argument("--average", action="store_true", help="move both faces to their mean along the edge")
    m.add_argument("--tol-g0", type=positive_arg, default=None, metavar="D",
                   help="largest gap, model units (default 1e-7 of the pair's size)")
    m.add_argument("--tol-g1", type=positive_arg, default=0.01, metavar="DEG", help="largest angle (default 0.01)")
    m.add_argument("--tol-g2", type=positive_arg, default=1.0, metavar="PCT",
                   help="largest relative curvature jump, percent (default 1)")
    m.add_argument("--sharp-deg", type=positive_arg, default=None, metavar="DEG",
                   help="refuse edges whose faces meet at this angle or more (default 15): a crease by design")
    m.add_argument("--out", required=True, metavar="OUT.step", help="where to write the changed model (STEP)")
    m.add_argument("--json", action="store_true", help="print one JSON document instead of the table")
    m.add_argument("--timeout", type=timeout_arg, default=DEFAULT_TIMEOUT, metavar="SECONDS",
                   help=f"stop the worker after this long and report it (default {DEFAULT_TIMEOUT:g})")
    add_strict_option(m, writes=True)
    m.add_argument("--in-process", action="store_true",
                   help="read and match in this process, not in a worker (a crash inside OCC then ends it)")
    m.set_defaults(func=run)
