"""``occsurf fill IN --out OUT.step [--faces I ...] [--all-loops] [--no-occ] [--no-pictures] [--json]
[--jobs N] [--timeout SECONDS] [--strict] [--in-process]``.

Reads a STEP or IGES model, fills every hole with :func:`occsurf.bridge.modeling.fill.fill_model`
(n G1 patches per hole, course §8-3), writes the sewn result to ``OUT`` (STEP) and prints per hole
ours against OCC's ``BRepOffsetAPI_MakeFilling``. Exit status 0 when every hole was filled (a model
without holes is written as it is), 2 otherwise or when the input cannot be read.

The untrusted file is read, filled and written in worker processes
(:func:`occsurf.bridge.audit.fill_file.fill_file`): ``--jobs N`` (default: one per core) fill
independent holes at once and the fills are sewn in once; a crash inside OCC is reported in one
line ``occsurf: IN: reason`` with exit status 2, not a dead command; so is a worker that takes longer
than ``--timeout`` seconds (with several jobs, a hole whose worker crashes or overruns fails with
that reason and the others are still filled). Warnings about the input (damage read around, see
:mod:`occsurf.bridge.exchange.checks`) are printed as ``occsurf: IN: warning: ...`` lines on stderr;
``--strict`` refuses such an input instead (exit status 2, nothing written).
Beside ``OUT`` goes one zebra picture per filled hole, ``OUT_STEM.holeK.png`` (the model around the
hole before and after, :func:`occsurf.bridge.modeling.fill_pictures.zebra_before_after`) where VTK
can render offscreen; ``--no-pictures`` skips them. A fill that turns back over itself (a fold,
:attr:`occsurf.algorithms.topology.nsided.FillQuality.folds`) is written but warned about.
``--in-process`` does the work in the calling process instead (no isolation, one hole after the other).
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
    fmt_s,
    format_rows,
    jobs_arg,
    outcome_problem,
    paths_problem,
    shown_path,
    timeout_arg,
)

__all__ = ["add_parser", "run", "DEFAULT_TIMEOUT"]

#: Seconds a worker may take before it is stopped (``--timeout``): to read, fill and write with one
#: job; with several, per step (the plan, each hole, the sewing). The same default as ``occsurf inspect``.
DEFAULT_TIMEOUT = 300.0

_HEADER = ("hole", "sides", "status", "G0 gap", "G1 angle", "time", "OCC G0 gap", "OCC G1 angle", "OCC time", "ours by")


def _write_table(src: Path, out: Path, result: dict[str, Any]) -> None:
    from ..modeling.refill_g2 import shortfall

    all_holes = result["holes"]
    holes = [h for h in all_holes if h["status"] != "outer"]
    n_outer = len(all_holes) - len(holes)
    sys.stdout.write(f"{src}: {len(holes)} holes" + (f" ({n_outer} outer boundaries left open)" if n_outer else "")
                     + "\n")
    rows = [_HEADER]
    for h in holes:
        occ = ((fmt_dev(h["occ_g0"]), fmt_deg(h["occ_g1"]), fmt_s(h["occ_seconds"])) if h["occ_status"] == "ok" else
               ("failed: " + (h["occ_reason"] or "?"), "-", fmt_s(h["occ_seconds"])) if h["occ_status"] else
               ("-", "-", "-"))
        rows.append((str(h["index"]), str(h["sides"]), h["status"], fmt_dev(h["g0"]), fmt_deg(h["g1"]),
                     fmt_s(h["seconds"]), *occ, h.get("method") or "-"))
    for line in format_rows(rows):
        sys.stdout.write(line + "\n")
    sys.stdout.write("  (G0 gap in model units, G1 angle between tangent planes: max along the hole's boundary, "
                     "OCC LocalAnalysis_SurfaceContinuity)\n")
    for k, h in enumerate(holes):
        name = f"hole {h.get('index', k)}" if "faces" not in h else f"faces {' '.join(map(str, h['faces']))}"
        if h.get("g2") is not None:
            on = f" on {h['g2_edges']} of {h['sides']} edges" if "g2_edges" in h else ""
            sys.stdout.write(f"  {name}: G2{on}, curvature jump across the boundary {100 * h['g2']:.2f} % "
                             f"(|k1 - k2| / max |k|, OCC's principal curvatures)\n")
        elif h["status"] == "filled" and (h.get("continuity") == "G2" or h.get("reason")):
            sys.stdout.write(f"  {name}: {h.get('reason') or 'filled G1'}\n")
        short = shortfall(h.get("edge_asked") or [], h.get("edge_continuity") or [], h.get("side_g2") or [])
        if h["status"] == "filled" and short:
            sys.stdout.write(f"  {name}: {short}\n")
    n_filled = sum(h["status"] == "filled" for h in all_holes)
    if n_filled and result["free_loops_after"] is None:  # --faces
        faces = ", ".join(" ".join(map(str, h["faces"])) for h in all_holes if h["status"] == "filled")
        sys.stdout.write(f"wrote {out} (faces {faces} replaced by {n_filled} fills)\n")
    elif n_filled:
        sys.stdout.write(f"wrote {out} ({n_filled} fills sewn in; {result['free_loops_after']} free loops left)\n")
    elif result["written"]:
        sys.stdout.write(f"no holes to fill; wrote {out} unchanged\n")
    pictures = [h["picture"] for h in all_holes if h.get("picture")]
    if pictures:
        sys.stdout.write(f"zebra before/after: {', '.join(pictures)}\n")


def run(ns: argparse.Namespace) -> int:
    """``occsurf fill IN --out OUT``: fill every hole (in a worker), print per hole ours vs OCC's filler."""
    from ..audit.fill_file import default_jobs, fill_file

    src, out = Path(ns.input), Path(ns.out)
    if paths_problem(src, out, "the filled model"):
        return EXIT_ERROR
    item = {"input": str(src), "output": str(out), "all_loops": ns.all_loops, "compare_occ": not ns.no_occ,
            "faces": list(ns.faces or []), "strict": ns.strict, "pictures": not ns.no_pictures,
            "continuity": ns.continuity}
    jobs = default_jobs() if ns.jobs is None else ns.jobs
    outcome = fill_file(item, jobs=jobs, timeout=ns.timeout, isolate=not ns.in_process)
    if outcome_problem(outcome, src, ns.timeout, "reading and filling this file"):
        return EXIT_ERROR
    result = outcome.value
    for w in result.get("warnings", ()):
        error(f"{shown_path(src)}: warning: {w}")
    failed = [h for h in result["holes"] if h["status"] == "failed"]
    for h in failed:
        error(f"{src}: hole {h['index']} ({h['sides']} sides) not filled: {h['reason']}")
    for h in result["holes"]:
        if h.get("folds"):
            error(f"{src}: hole {h['index']}: warning: the fill turns back over itself ({h['folds']} folded grid "
                  "pairs): the hole is too long and curved for one central split")
        if h.get("picture_error"):
            error(f"{src}: hole {h['index']}: warning: no picture ({h['picture_error']})")
    if ns.json:
        doc = {"input": str(src), "output": str(out) if result["written"] else None, "holes": result["holes"],
               "free_loops_after": result["free_loops_after"]}
        sys.stdout.write(json.dumps(doc, indent=1) + "\n")
    else:
        _write_table(src, out, result)
    sys.stdout.flush()
    return EXIT_ERROR if failed or not result["written"] else EXIT_OK


def add_parser(sub: Any) -> None:
    """Register ``fill`` on the sub-parsers of :func:`occsurf.bridge.cli.build_parser`."""
    f = sub.add_parser(
        "fill",
        help="fill every hole of a STEP/IGES model with G1 patches and compare with OCC's filler",
        description=("Finds the closed loops of free edges of the model's shells (the largest loop of a shell with "
                     "several is its outer boundary and stays open unless --all-loops), fills each hole with n "
                     "G1 patches (course 8-3), sews them in, writes OUT (STEP) and prints per hole: sides, G0 gap "
                     "and G1 angle (OCC LocalAnalysis, max along the boundary) for our fill and for OCC's "
                     "BRepOffsetAPI_MakeFilling. Exit status 0 when every hole was filled, 2 otherwise."),
    )
    f.add_argument("input", metavar="IN", help="STEP or IGES file")
    f.add_argument("--out", required=True, metavar="OUT.step", help="where to write the filled model (STEP)")
    f.add_argument("--all-loops", action="store_true", help="fill outer boundaries too")
    f.add_argument("--faces", type=int, nargs="+", metavar="I", default=None,
                   help="remove these faces (numbered as in inspect's table) and refill the hole(s) they leave: "
                        "adjacent faces make one hole; G1 is asked where the original was tangent-continuous")
    f.add_argument("--continuity", choices=("auto", "G1", "G2"), default="auto",  # modeling.fill.CONTINUITIES (tested)
                   help="G1: tangent continuous (n patches, exact boundary); G2: curvature continuous too, "
                        "by one plate matching the neighbours' curvature across the edges (holes: every edge "
                        "of iso-boundary neighbours; --faces: the edges where the removed faces were G2 "
                        "within 2 %%, G1 where tangent, G0 elsewhere); where it cannot be made, G1 with the "
                        "reason. auto (default): what the original gave, i.e. as G2 with --faces and as G1 "
                        "for holes (no face was there)")
    f.add_argument("--no-occ", action="store_true", help="do not run OCC's filler for comparison")
    f.add_argument("--no-pictures", action="store_true",
                   help="do not write the zebra before/after picture of each hole (OUT_STEM.holeK.png)")
    f.add_argument("--json", action="store_true", help="print one JSON document instead of the table")
    f.add_argument("--jobs", type=jobs_arg, default=None, metavar="N",
                   help="fill up to N holes at once, each in its own worker process, and sew once "
                        "(default: one per core)")
    f.add_argument("--timeout", type=timeout_arg, default=DEFAULT_TIMEOUT, metavar="SECONDS",
                   help=f"stop a worker after this long and report it: the whole fill with one job, each hole "
                        f"with several (default {DEFAULT_TIMEOUT:g})")
    add_strict_option(f, writes=True)
    f.add_argument("--in-process", action="store_true",
                   help="read and fill in this process, not in a worker (a crash inside OCC then ends it)")
    f.set_defaults(func=run)
