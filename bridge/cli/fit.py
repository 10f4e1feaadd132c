"""``occsurf fit DATA --tol T --out OUT.step [--json] [--ctrl NU NV] [--degree D] [--smooth S]
[--fix-boundary] [--x X0 X1] [--y Y0 Y1] [--face N] [--levels L] [--timeout SECONDS] [--strict] [--in-process]``.

Fits data to a surface (course ch. 7) with :mod:`occsurf.bridge.modeling.fit`: adaptive
hierarchical by default (§7-10: overlays only where the distance to the data exceeds ``T``),
plain least squares with ``--ctrl``. Writes ``OUT.step`` (the flat exact NURBS), ``OUT.json``
(the editable hierarchy, in the sidecar format read by
:func:`occsurf.bridge.exchange.hierarchical_io.read_hierarchical_step` with ``sidecar=``) and
``OUT.png`` (the error map per level), prints the per-level statistics (or one JSON document with
``--json``); progress goes to stderr.

The data file is read, fitted and written in a worker process
(:func:`occsurf.bridge.isolation.run_jobs` with the job :func:`occsurf.bridge.audit.fit_file.fit_job`), so a STEP/IGES file that
crashes OCC costs a one-line error, not the command; the worker's progress lines reach stderr
through a small file this process follows; a worker that takes longer than ``--timeout`` seconds (reading,
fitting and writing together) is stopped and reported. Bad data (NaN-only rows, too few points for the
degree, ragged or non-numeric rows named by their line) give one line ``occsurf: DATA: reason``
and exit status 2. A STEP/IGES file read around damage (see :mod:`occsurf.bridge.exchange.checks`) is
fitted as read, with one line ``occsurf: DATA: warning: ...`` per warning on stderr (and ``warnings`` in
the JSON); ``--strict`` refuses it instead (exit status 2, nothing written), as every reading command does.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from ..audit.fit_file import FIT_JOB, PRELOAD
from ._common import EXIT_ERROR, EXIT_OK, add_strict_option, error, format_rows, strip_path, timeout_arg, worker_failure

__all__ = ["add_parser", "run"]

#: Seconds the worker may take to read, fit and write before it is stopped (``--timeout``): a file that
#: hangs OCC's reader must not hang the command; real fits take seconds (see the README's fitting section).
DEFAULT_TIMEOUT = 1800.0


class _Follow(threading.Thread):
    """Copies the lines the worker appends to a progress file onto stderr, as they come."""

    def __init__(self, path: str) -> None:
        super().__init__(daemon=True)
        self.path, self.done = path, threading.Event()

    def run(self) -> None:
        pos = 0
        while True:
            stop = self.done.is_set()
            try:
                with open(self.path, encoding="utf-8") as fh:
                    fh.seek(pos)
                    chunk = fh.read()
                    pos = fh.tell()
            except OSError:
                chunk = ""
            for line in chunk.splitlines():
                print(f"occsurf fit: {line}", file=sys.stderr, flush=True)
            if stop:
                return
            self.done.wait(0.2)


def _table(doc: dict[str, Any]) -> None:
    rows = [("level", "overlays", "control points", "max error", "rms error")]
    for L in doc["levels"]:
        rows.append((str(L["level"]), str(L["overlays"]), str(L["control_points"]), f"{L['max_error']:.3e}",
                     f"{L['rms_error']:.3e}"))
    out = sys.stdout
    out.write(f"{doc['detected']}\n{doc['method']}, degree {doc['degree'][0]}:\n")
    for line in format_rows(rows, right={0, 1, 2}):
        out.write(line + "\n")
    ok = "<=" if doc["converged"] else ">"
    out.write(f"  total: {doc['control_points_total']} control points stored (flat {doc['flat_poles'][0]} x "
              f"{doc['flat_poles'][1]} poles); max distance to the data {doc['max_error']:.3e} {ok} tol {doc['tol']:g}\n")
    if "face_deviation" in doc:
        out.write(f"  deviation from the original face (OCC projection): {doc['face_deviation']:.3e}\n")
    out.write("wrote " + ", ".join(doc["outputs"].values()) + "\n")


def _positive(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive number, got {text!r}") from None
    if not (math.isfinite(v) and v > 0):
        raise argparse.ArgumentTypeError(f"expected a positive number, got {text!r}")
    return v


def _smooth(text: str) -> float | str:
    if text == "gcv":
        return text
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number >= 0 or 'gcv', got {text!r}") from None
    if not (math.isfinite(v) and v >= 0):
        raise argparse.ArgumentTypeError(f"expected a number >= 0 or 'gcv', got {text!r}")
    return v


def _count(lo: int) -> Callable[[str], int]:
    def parse(text: str) -> int:
        try:
            v = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected an integer >= {lo}, got {text!r}") from None
        if v < lo:
            raise argparse.ArgumentTypeError(f"expected an integer >= {lo}, got {text!r}")
        return v
    return parse


def _number(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not math.isfinite(v):
        raise argparse.ArgumentTypeError(f"expected a finite number, got {text!r}")
    return v


def _check_out(out: Path) -> str | None:
    if out.suffix.lower() not in (".step", ".stp"):
        return f"{out}: the output must be a .step or .stp file (OUT.json and OUT.png are written beside it)"
    folder = out.parent if str(out.parent) else Path(".")
    if out.is_dir() or not folder.is_dir() or not os.access(folder, os.W_OK):
        why = "is a directory" if out.is_dir() else f"the folder {folder} does not exist or is not writable"
        return f"{out}: cannot write the fit there ({why})"
    return None


def run(ns: argparse.Namespace) -> int:
    """``occsurf fit DATA --tol T --out OUT.step``: fit in a worker, print the per-level table or JSON."""
    from ..exchange.files import input_problem
    from ..exchange.reading import shown_path
    from ..isolation import ERROR, OK, run_jobs

    src, out = Path(ns.data), Path(ns.out)
    why = input_problem(src, "data")
    bad = _check_out(out) if why is None else f"{shown_path(src)}: {why}"
    if bad is None and ns.x is not None and not ns.x[0] < ns.x[1]:
        bad = f"--x: expected X0 < X1, got {ns.x[0]:g} {ns.x[1]:g}"
    if bad is None and ns.y is not None and not ns.y[0] < ns.y[1]:
        bad = f"--y: expected Y0 < Y1, got {ns.y[0]:g} {ns.y[1]:g}"
    if bad is None and ns.ctrl is not None and min(ns.ctrl) < ns.degree + 1:
        bad = f"--ctrl: degree {ns.degree} needs at least {ns.degree + 1} poles per direction, got {ns.ctrl[0]} {ns.ctrl[1]}"
    if bad is not None:
        error(bad)
        return EXIT_ERROR
    fd, progress = tempfile.mkstemp(prefix="occsurf-fit-", suffix=".log")
    os.close(fd)
    item = {"input": str(src), "output": str(out), "tol": ns.tol, "ctrl": ns.ctrl, "degree": ns.degree,
            "smooth": ns.smooth, "fix_boundary": ns.fix_boundary, "x": ns.x, "y": ns.y, "face": ns.face,
            "levels": ns.levels, "progress": progress, "strict": ns.strict}
    follow = _Follow(progress)
    follow.start()
    t0 = time.perf_counter()
    try:
        [outcome] = run_jobs(FIT_JOB, [item], timeout=ns.timeout, isolate=not ns.in_process, preload=PRELOAD)
    finally:
        follow.done.set()
        follow.join()
        os.unlink(progress)
    if outcome.status != OK:
        why = (strip_path(outcome.error or "unknown error", src) if outcome.status == ERROR else
               worker_failure(outcome, ns.timeout, task="fitting this file", process="worker"))
        error(f"{src}: {why}")
        return EXIT_ERROR
    doc = outcome.value
    doc["seconds"] = round(time.perf_counter() - t0, 3)
    for w in doc.get("warnings", ()):
        error(f"{src}: warning: {w}")
    if not doc["converged"]:
        error(f"{src}: the tolerance {ns.tol:g} is not reached (max distance {doc['max_error']:.3g}); the data "
              "need more levels (--levels) or poles (--ctrl)")
    if ns.json:
        sys.stdout.write(json.dumps(doc, indent=1) + "\n")
    else:
        _table(doc)
    sys.stdout.flush()
    return EXIT_OK


def add_parser(sub: Any) -> None:
    """Register ``fit`` on the sub-parsers of :func:`occsurf.bridge.cli.build_parser`."""
    f = sub.add_parser(
        "fit",
        help="fit gridded or scattered data (or refit a STEP/IGES face) to a surface within a tolerance",
        description=("Fits DATA (.npy: an (m, n, 3) point grid or (m, n) heights over the unit square or --x/--y; "
                     ".csv/.xyz rows x y z, gridded or scattered, detected; a STEP/IGES face with --face N) by "
                     "adaptive hierarchical least squares (course 7-10): overlays only where the distance to the "
                     "data exceeds --tol. --ctrl NU NV fits plain least squares instead. Writes OUT.step (flat "
                     "exact NURBS), OUT.json (editable hierarchy) and OUT.png (error map per level)."),
    )
    f.add_argument("data", metavar="DATA", help=".npy, .csv, .xyz, or a STEP/IGES file")
    f.add_argument("--tol", required=True, type=_positive, metavar="T",
                   help="largest allowed distance from a data point to the surface")
    f.add_argument("--out", required=True, metavar="OUT.step", help="the STEP file to write (OUT.json, OUT.png beside)")
    f.add_argument("--json", action="store_true", help="print one JSON document instead of the table")
    f.add_argument("--ctrl", nargs=2, type=_count(2), metavar=("NU", "NV"),
                   help="plain least squares with NU x NV poles instead of the adaptive fit")
    f.add_argument("--degree", type=_count(1), default=3, help="degree in both directions (default 3)")
    f.add_argument("--smooth", type=_smooth, default=0.0, metavar="S",
                   help="smoothing weight (difference penalty, >= 0), or 'gcv' to choose it (with --ctrl)")
    f.add_argument("--fix-boundary", action="store_true",
                   help="the four boundary curves are fitted to the boundary rows first and held exactly")
    f.add_argument("--x", nargs=2, type=_number, metavar=("X0", "X1"), help="x range of an (m, n) height grid")
    f.add_argument("--y", nargs=2, type=_number, metavar=("Y0", "Y1"), help="y range of an (m, n) height grid")
    f.add_argument("--face", type=_count(0), metavar="N", help="the face of a STEP/IGES file to refit (default 0)")
    f.add_argument("--levels", type=_count(0), metavar="L", help="deepest overlay level (default 6)")
    f.add_argument("--timeout", type=timeout_arg, default=DEFAULT_TIMEOUT, metavar="SECONDS",
                   help=f"stop the worker after this long and report it (default {DEFAULT_TIMEOUT:g})")
    add_strict_option(f, writes=True)
    f.add_argument("--in-process", action="store_true", help="fit in this process, not in a worker")
    f.set_defaults(func=run)
