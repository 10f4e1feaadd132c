"""``occsurf fill IN --out OUT.step [--faces I ...] [--all-loops] [--no-occ] [--no-pictures] [--json]
[--timeout SECONDS] [--strict] [--in-process]``.

Reads a STEP or IGES model, fills every hole with :func:`occsurf.bridge.modeling.fill.fill_model`
(n G1 patches per hole, course §8-3), writes the sewn result to ``OUT`` (STEP) and prints per hole
ours against OCC's ``BRepOffsetAPI_MakeFilling``. Exit status 0 when every hole was filled (a model
without holes is written as it is), 2 otherwise or when the input cannot be read.

The untrusted file is read, filled and written in a worker process
(:func:`occsurf.bridge.isolation.run_jobs` with the job :func:`fill_job`): a crash inside OCC is
reported in one line ``occsurf: IN: reason`` with exit status 2, not a dead command; so is a worker
that takes longer than ``--timeout`` seconds. Warnings about the input (damage read around, see
:mod:`occsurf.bridge.exchange.checks`) are printed as ``occsurf: IN: warning: ...`` lines on stderr;
``--strict`` refuses such an input instead (exit status 2, nothing written).
Beside ``OUT`` goes one zebra picture per filled hole, ``OUT_STEM.holeK.png`` (the model around the
hole before and after, :func:`occsurf.bridge.modeling.fill_pictures.zebra_before_after`) where VTK
can render offscreen; ``--no-pictures`` skips them. A fill that turns back over itself (a fold,
:attr:`occsurf.algorithms.topology.nsided.FillQuality.folds`) is written but warned about.
``--in-process`` does the work in the calling process instead (no isolation).
"""

from __future__ import annotations

import argparse
import json
import sys
import warnings
from dataclasses import asdict
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
    output_problem,
    read_model,
    shown_path,
    strip_path,
    timeout_arg,
    worker_failure,
)

__all__ = ["fill_job", "add_parser", "run", "DEFAULT_TIMEOUT"]

#: Seconds the worker may take to read, fill and write before it is stopped (``--timeout``); the same
#: default as ``occsurf inspect``.
DEFAULT_TIMEOUT = 300.0

#: The job the worker runs, and what it loads before starting it.
FILL_JOB = "occsurf.bridge.cli.fill:fill_job"
PRELOAD = ("occsurf.bridge.exchange.step_iges", "occsurf.bridge.modeling.fill")

_HEADER = ("hole", "sides", "status", "G0 gap", "G1 angle", "time", "OCC G0 gap", "OCC G1 angle", "OCC time", "ours by")


def fill_job(item: dict[str, Any]) -> dict[str, Any]:
    """The worker's job: read ``item["input"]``, fill its holes, write ``item["output"]`` (STEP).

    The output is written when some hole was filled, or when there was none to fill (the model
    as it is, sewn).

    Parameters
    ----------
    item : dict
        ``{"input": str, "output": str, "all_loops": bool, "compare_occ": bool}``.

    Returns
    -------
    dict
        ``{"holes": [HoleReport as a dict, ...], "free_loops_after": int, "written": bool}``.

    Raises
    ------
    Exception
        Whatever reading, filling or writing raises (the command prints it on one line).
    """
    from ..isolation import quiet_native_stdout

    src, out = Path(item["input"]), Path(item["output"])
    with warnings.catch_warnings(), quiet_native_stdout():
        warnings.simplefilter("ignore")
        from ..exchange import step_iges as exchange
        from ..modeling.fill import fill_model
        from ..modeling.fill_pictures import hole_pictures

        model = read_model(src, strict=bool(item.get("strict")))
        if item.get("faces"):
            return _refill_job(item, model, exchange)
        result = fill_model(model.shape, all_loops=item["all_loops"], compare_occ=item["compare_occ"])
        filled = any(h.status == "filled" for h in result.holes)
        nothing_to_do = not any(h.status != "outer" for h in result.holes)
        if filled or nothing_to_do:  # a model without holes is written as it is (sewn)
            exchange.write_step(out, result.shape)
        holes = [asdict(h) for h in result.holes]
        if item.get("pictures", True):
            hole_pictures(out, result.holes, holes)
    return {"holes": holes, "free_loops_after": result.free_loops_after,
            "written": filled or nothing_to_do, "warnings": list(model.warnings)}


def _refill_job(item: dict[str, Any], model: Any, exchange: Any) -> dict[str, Any]:
    """``--faces``: remove the faces, fill the hole(s) they leave, write the model if any was filled."""
    from ..modeling.fill_pictures import hole_pictures
    from ..modeling.refill import refill_model

    reports, shape = refill_model(model.shape, item["faces"], compare_occ=item["compare_occ"])
    if shape is not None:
        exchange.write_step(Path(item["output"]), shape)
    holes: list[dict[str, Any]] = []
    for k, r in enumerate(reports):
        d, t = r.occ.get("default", {}), r.occ.get("tuned", {})
        holes.append({"index": k, "faces": r.faces, "sides": r.sides, "g1_edges": r.g1_edges,
                      "status": "filled" if r.status == "filled" else "failed", "reason": r.reason,
                      "seconds": r.seconds, "g0": r.g0, "g1": r.g1, "side_g0": r.side_g0, "side_g1": r.side_g1,
                      "valid": r.valid, "step_round_trip": r.step_round_trip,
                      "occ_status": d.get("status"), "occ_reason": d.get("reason"), "occ_seconds": d.get("seconds"),
                      "occ_g0": d.get("g0"), "occ_g1": d.get("g1"), "occ_tuned": t or None, "folds": r.folds,
                      "method": r.method})
    if shape is not None and item.get("pictures", True):
        hole_pictures(Path(item["output"]), reports, holes, refill=True)
    return {"holes": holes, "free_loops_after": None, "written": shape is not None, "warnings": list(model.warnings)}


def _write_table(src: Path, out: Path, result: dict[str, Any]) -> None:
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
    from ..isolation import ERROR, OK, run_jobs

    src, out = Path(ns.input), Path(ns.out)
    why = output_problem(out)
    if why is not None:
        error(f"{shown_path(out)}: cannot write the filled model there ({why})")
        return EXIT_ERROR
    item = {"input": str(src), "output": str(out), "all_loops": ns.all_loops, "compare_occ": not ns.no_occ,
            "faces": list(ns.faces or []), "strict": ns.strict, "pictures": not ns.no_pictures}
    [outcome] = run_jobs(FILL_JOB, [item], timeout=ns.timeout, isolate=not ns.in_process, preload=PRELOAD)
    if outcome.status != OK:
        why = (strip_path(outcome.error or "unknown error", src) if outcome.status == ERROR else
               worker_failure(outcome, ns.timeout, task="reading and filling this file", process="worker"))
        error(f"{shown_path(src)}: {why}")
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
    f.add_argument("--no-occ", action="store_true", help="do not run OCC's filler for comparison")
    f.add_argument("--no-pictures", action="store_true",
                   help="do not write the zebra before/after picture of each hole (OUT_STEM.holeK.png)")
    f.add_argument("--json", action="store_true", help="print one JSON document instead of the table")
    f.add_argument("--timeout", type=timeout_arg, default=DEFAULT_TIMEOUT, metavar="SECONDS",
                   help=f"stop the worker after this long and report it (default {DEFAULT_TIMEOUT:g})")
    add_strict_option(f, writes=True)
    f.add_argument("--in-process", action="store_true",
                   help="read and fill in this process, not in a worker (a crash inside OCC then ends it)")
    f.set_defaults(func=run)
