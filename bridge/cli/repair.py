"""``occsurf repair IN --preset catia|class-a|mechanical --out OUT.step [--max-change D] [--json]
[--timeout S] [--strict] [--in-process]``.

Checks the model's edges against the preset, matches every edge that is meant to be smooth (not
classified sharp) and breaks it (:func:`occsurf.bridge.audit.repair.repair_model`, in a worker
process), checks again, writes ``OUT`` (STEP) and ``OUT_STEM_report/index.html`` (before and after
side by side, every edge tried with what was done or why not), and prints the counts: edges
repaired (and how many of those the check after still counts as breaking the preset), refused,
faces faired. A sharp edge is never changed, nor is a face moved by more than
``--max-change`` (default 1e-3 of the model's size). Exit status 0 when the model was written, 2
when the input could not be read or repaired (one line on stderr).
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from pathlib import Path
from typing import Any

from ._common import (
    EXIT_ERROR,
    EXIT_OK,
    add_strict_option,
    error,
    outcome_problem,
    paths_problem,
    positive_arg,
    shown_path,
    timeout_arg,
)

__all__ = ["add_parser", "run", "DEFAULT_TIMEOUT"]

#: Seconds the worker may take to read, repair and write.
DEFAULT_TIMEOUT = 1800.0


def run(ns: argparse.Namespace) -> int:
    """``occsurf repair IN --preset P --out OUT``."""
    from ..audit.match_file import REPAIR_JOB, match_file

    src, out = Path(ns.input), Path(ns.out)
    if paths_problem(src, out, "the repaired model"):
        return EXIT_ERROR
    item = {"input": str(src), "output": str(out), "preset": ns.preset, "max_change": ns.max_change,
            "strict": ns.strict}
    outcome = match_file(item, timeout=ns.timeout, isolate=not ns.in_process, job=REPAIR_JOB)
    if outcome_problem(outcome, src, ns.timeout, "reading and repairing this file"):
        return EXIT_ERROR
    res = outcome.value
    for w in res.get("warnings", ()):
        error(f"{shown_path(src)}: warning: {w}")
    rep = res["report"]
    if ns.json:
        sys.stdout.write(json.dumps({**rep, "input": str(src), "output": str(out), "page": res["page"]}, indent=1)
                         + "\n")
    else:
        still = rep["edges_repaired_still_breaking"]
        sys.stdout.write(
            f"{src}: {rep['edges_breaking_before']} smooth edges broke {rep['preset']} before, "
            f"{rep['edges_breaking_after']} after; edges repaired {rep['edges_repaired']}"
            + (f" ({still} of them still break {rep['preset']} in the check after)" if still else "")
            + f", refused {rep['edges_refused']}, faces faired {rep['faces_faired']}\n")
        rt = rep.get("round_trip") or {}
        sys.stdout.write(f"  written and read back: {rt.get('faces_out')} faces of {rt.get('faces_in')}, "
                         f"{'valid' if rt.get('valid') else 'NOT valid'} (BRepCheck_Analyzer)\n")
        reasons: dict[str, int] = {}
        for e in rep["edges"]:
            if e["status"] == "refused":
                key = re.sub(r"[0-9][0-9.e+-]*", "#", (e["reason"] or "?").split("; ")[0].split(": ", 1)[-1])[:70]
                reasons[key] = reasons.get(key, 0) + 1
        for text, n in sorted(reasons.items(), key=lambda kv: -kv[1])[:8]:
            sys.stdout.write(f"  refused x{n}: {text}\n")
        sys.stdout.write(f"wrote {out} and {res['page']}\n")
    sys.stdout.flush()
    return EXIT_OK


def add_parser(sub: Any) -> None:
    """Register ``repair`` on the sub-parsers of :func:`occsurf.bridge.cli.build_parser`."""
    r = sub.add_parser(
        "repair",
        help="match every smooth edge that breaks a preset, check again, write the model and a before/after page",
        description=("Checks the model against the preset, matches every edge meant to be smooth (not sharp) that "
                     "breaks it (the face with fewer constrained edges moves; never by more than --max-change), "
                     "checks again, writes OUT (STEP) and OUT_STEM_report/index.html, prints the counts."),
    )
    r.add_argument("input", metavar="IN", help="STEP or IGES file")
    r.add_argument("--preset", choices=("catia", "class-a", "mechanical"), default="catia",
                   help="the tolerances to repair to (default catia)")
    r.add_argument("--out", required=True, metavar="OUT.step", help="where to write the repaired model (STEP)")
    r.add_argument("--max-change", type=positive_arg, default=None, metavar="D",
                   help="largest change of a face, model units (default 1e-3 of the model's size)")
    r.add_argument("--json", action="store_true", help="print one JSON document instead of the counts")
    r.add_argument("--timeout", type=timeout_arg, default=DEFAULT_TIMEOUT, metavar="SECONDS",
                   help=f"stop the worker after this long and report it (default {DEFAULT_TIMEOUT:g})")
    add_strict_option(r, writes=True)
    r.add_argument("--in-process", action="store_true",
                   help="read and repair in this process, not in a worker (a crash inside OCC then ends it)")
    r.set_defaults(func=run)
