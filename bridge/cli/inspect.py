"""``occsurf inspect [FILE|DIR ...] [--json | --jsonl] [--samples N] [--timeout SECONDS] [--strict] [--in-process]``.

Reads STEP and IGES files and prints, per face, what
:func:`occsurf.bridge.validation.inspect.inspect_model` reports: the surface type, degrees,
poles, rational and periodic flags, OCC's continuity class and the largest distance between our
evaluation of the converted surface and OCC's evaluation of the original one on an ``N x N``
grid, relative to the diagonal of the sampled points' bounding box (``-`` for analytic faces).
Without arguments it reads every STEP/IGES file in the ``step_samples/`` folder (below the current
directory, else the one shipped with occsurf).

Exit status: 0 when every file was read; 2 when at least one could not be (each such file gets one
line ``occsurf: PATH: reason`` on stderr and an ``error`` in the JSON, and the other files are still
reported), or when an argument is wrong. A file read around damage (references to undefined instances,
OCC's check messages, fewer faces than the file's face instances, an open closed shell; see
:mod:`occsurf.bridge.exchange.checks`) has ``warnings``: in the JSON, in the table, and one line
``occsurf: PATH: warning: ...`` each on stderr; ``--strict`` makes them exit status 2 too. Links in a
folder that lead nowhere (dangling, loops, devices) are reported as errors, not skipped.

Output: a table per file as soon as it is read (in the order of the arguments), then a summary line;
``--json``: one JSON document at the end (``{"samples", "seconds", "interrupted", "files": [...]}``);
``--jsonl``: one JSON line per file as soon as it is read (the objects of ``--json``'s ``files``),
for streaming into ``jq`` or a log. Ctrl-C stops the reading and keeps what was done: the tables and
JSON lines already printed stay whole (no line is cut), ``--json`` prints the document of the files
read so far with ``"interrupted": true``; then ``occsurf: interrupted`` on stderr, exit status 130.
A closed pipe (``occsurf inspect DIR | head -1``) ends the command quietly (exit status 2).

Each file is read in a worker process (:func:`occsurf.bridge.isolation.run_jobs` with the job
:func:`occsurf.bridge.validation.files.inspect_job`): a file that crashes OCC, or takes longer than
``--timeout``, is reported as an error and the other files are still read. ``--in-process`` reads in the
calling process instead (no isolation; handy under a debugger). The per-file work is library code,
:mod:`occsurf.bridge.validation.files` (:func:`~occsurf.bridge.validation.files.inspect_files` is the
in-process entry); this module parses the arguments and prints.
"""

from __future__ import annotations

import argparse
import io
import json
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, TextIO

from ..validation.files import INSPECT_JOB, PRELOAD, FileReport
from ..validation.inspect import DEFAULT_SAMPLES
from . import _common
from ._common import (
    EXIT_ERROR,
    EXIT_OK,
    IGES_SUFFIXES,
    SAMPLES_DIR,
    STEP_SUFFIXES,
    InOrder,
    error,
    expand,
    fmt_dev,
    fmt_pair,
    fmt_periodic,
    fmt_rational,
    format_rows,
    interrupts_held,
    timeout_arg,
    worker_failure,
    write_json_line,
    write_out,
)

if TYPE_CHECKING:
    from ..isolation import Outcome

__all__ = ["add_parser", "add_worker_parser", "run", "DEFAULT_TIMEOUT", "WORKER_COMMAND"]

#: Seconds one file may take in the reader process before it is killed and reported as timed out
#: (a hang inside OCC must not hang the command); ``--timeout`` overrides it.
DEFAULT_TIMEOUT = 300.0
#: The hidden command that runs the reader loop on ``{"files": [[shown, path], ...], "samples": N}``.
WORKER_COMMAND = "_inspect-worker"


# ---------------------------------------------------------------------------------------- reading
def _report_of(shown: str, outcome: Outcome, timeout: float) -> FileReport:
    """A file's report from the reader process's outcome."""
    from ..isolation import ERROR, OK

    if outcome.status == OK:
        return FileReport.from_json(outcome.value)
    if outcome.status == ERROR:
        return FileReport(path=shown, error=outcome.error)
    return FileReport(path=shown, error=worker_failure(outcome, timeout, task="reading this file", process="reader"))


# ---------------------------------------------------------------------------------------- output
_HEADER = ("face", "type", "degree", "poles", "rational", "periodic", "continuity", "max dev", "")
_RIGHT = frozenset({0, 7})


def _write_file_table(rep: FileReport, out: TextIO) -> None:
    fmt = f" ({rep.format.upper()})" if rep.format else ""
    out.write(f"{rep.path}{fmt}\n")
    if rep.error is not None:
        out.write(f"  error: {rep.error}\n")
        return
    names = {f.name for f in rep.faces}
    shared_name = names.pop() if len(names) == 1 else None  # one product name on every face: say it once
    if shared_name:
        out.write(f"  name: {shared_name!r}\n")
    rows = [_HEADER]
    for f in rep.faces:
        own = f.name if (f.name and not shared_name) else None
        note = " ".join(x for x in (own and repr(own), f.error and f"[{f.error}]") if x)
        rows.append((str(f.index), f.surface_type, fmt_pair(f.degree), fmt_pair(f.poles),
                     fmt_rational(f.rational), fmt_periodic(f.periodic), f.continuity or "-",
                     fmt_dev(f.max_deviation), note))
    for line in format_rows(rows, _RIGHT):
        out.write(line + "\n")
    for w in rep.warnings:
        out.write(f"  warning: {w}\n")
    out.write(f"  {len(rep.faces)} faces, {rep.n_free_form} free-form, worst deviation "
              f"{fmt_dev(rep.worst_deviation)} (relative to bbox diagonal), {rep.seconds:.2f} s\n")


# ---------------------------------------------------------------------------------------- command
def run(ns: argparse.Namespace) -> int:
    """``occsurf inspect``: read the files (in a worker), print each file's table in order."""
    from ..isolation import run_jobs

    paths = list(ns.paths)
    if not paths:
        folder = _common.find_samples_dir()
        if folder is None:
            error(f"no {SAMPLES_DIR}/ folder found (looked in {Path.cwd() / SAMPLES_DIR} and "
                  "in the installed package); name FILE or DIR arguments")
            return EXIT_ERROR
        paths = [str(folder)]
    t0 = time.perf_counter()
    entries = expand(paths)

    def show(k: int, r: FileReport) -> None:
        """A report's stderr lines and its table or JSON line (called in the order of the arguments)."""
        if r.error is not None:
            error(f"{r.path}: {r.error}")
        for w in r.warnings:
            error(f"{r.path}: warning: {w}")
        if ns.jsonl:
            write_json_line(r.to_json())
        elif not ns.json:
            table = io.StringIO()
            if k:
                table.write("\n")
            _write_file_table(r, table)
            write_out(table.getvalue())

    stream = InOrder(len(entries), show)
    emit = stream.put

    todo: list[tuple[int, str]] = []
    items: list[dict[str, Any]] = []
    try:
        for k, (shown, path, err) in enumerate(entries):
            if path is None:
                emit(k, FileReport(path=shown, error=err))
            else:
                todo.append((k, shown))
                items.append({"shown": shown, "path": str(path), "samples": ns.samples})
        if items:
            run_jobs(INSPECT_JOB, items, timeout=ns.timeout, isolate=not ns.in_process, preload=PRELOAD,
                     on_outcome=lambda o: emit(todo[o.index][0], _report_of(todo[o.index][1], o, ns.timeout)))
    except KeyboardInterrupt:  # Ctrl-C: print what was done (the worker is stopped), then exit 130
        with interrupts_held():
            _finish(ns, stream.emitted, len(entries), time.perf_counter() - t0, interrupted=True)
        raise
    done = [r for r in stream.emitted if r is not None]  # every report, in order
    _finish(ns, done, len(entries), time.perf_counter() - t0, interrupted=False)
    failed = any(r.error is not None for r in done) or (ns.strict and any(r.warnings for r in done))
    return EXIT_ERROR if failed else EXIT_OK


def _finish(ns: argparse.Namespace, done: Sequence[FileReport | None], n_files: int, total: float,
            interrupted: bool) -> None:
    """The end of the output: ``--json``'s document, or the tables' summary line (``--jsonl``: nothing)."""
    reports = [r for r in done if r is not None]
    if ns.jsonl:
        return
    if ns.json:
        doc = {"samples": ns.samples, "seconds": round(total, 4), "interrupted": interrupted,
               "files": [r.to_json() for r in reports]}
        write_out(json.dumps(doc, indent=1, allow_nan=False) + "\n")
    elif len(reports) > 1 or interrupted:
        n_bad = sum(r.error is not None for r in reports)
        what = f"{len(reports)} of {n_files} files read before the interruption" if interrupted else f"{len(reports)} files"
        write_out(f"\n{what} ({n_bad} unreadable), {sum(len(r.faces) for r in reports)} faces, "
                  f"{sum(r.n_free_form for r in reports)} free-form, {total:.2f} s\n")


def _worker(ns: argparse.Namespace) -> int:
    """The hidden reader command: ``{"files": [[shown, path], ...], "samples": N}`` on stdin, a
    ``start`` line before each file and a ``report`` line after it on stdout."""
    from ..isolation import serve

    job = json.loads(sys.stdin.read())
    items = [{"shown": shown, "path": path, "samples": int(job["samples"])} for shown, path in job["files"]]
    serve(INSPECT_JOB, items, preload=PRELOAD)
    return EXIT_OK


# ---------------------------------------------------------------------------------------- parser
def _samples_arg(text: str) -> int:
    try:
        n = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer from 2 to 1000, got {text!r}") from None
    if not 2 <= n <= 1000:
        raise argparse.ArgumentTypeError(f"expected an integer from 2 to 1000, got {n}")
    return n


def add_parser(sub: Any) -> None:
    """Register ``inspect`` on the sub-parsers of :func:`occsurf.bridge.cli.build_parser`."""
    p = sub.add_parser(
        "inspect",
        help="list the faces of STEP/IGES files and check our evaluation against OCC's",
        description=("For every face: surface type, degree, poles, rational, periodic, OCC continuity, "
                     "and the largest distance between our evaluation and OCC's on an N x N grid, "
                     "relative to the bounding-box diagonal ('-' for faces that are not B-spline or "
                     "Bezier). Exit status 0 when every file was read, 2 otherwise."),
    )
    p.add_argument("paths", nargs="*", metavar="FILE|DIR",
                   help=f"STEP ({', '.join(STEP_SUFFIXES)}) or IGES ({', '.join(IGES_SUFFIXES)}) files, "
                        f"or folders holding them (default: {SAMPLES_DIR}/)")
    fmt = p.add_mutually_exclusive_group()
    fmt.add_argument("--json", action="store_true", help="print one JSON document instead of tables")
    fmt.add_argument("--jsonl", action="store_true",
                     help="print one JSON line per file as soon as it is read (the objects of --json's 'files')")
    p.add_argument("--samples", type=_samples_arg, default=DEFAULT_SAMPLES, metavar="N",
                   help=f"grid size N of the deviation check (default {DEFAULT_SAMPLES})")
    p.add_argument("--timeout", type=timeout_arg, default=DEFAULT_TIMEOUT, metavar="SECONDS",
                   help=f"stop reading a file after this long and report it (default {DEFAULT_TIMEOUT:g})")
    p.add_argument("--strict", action="store_true",
                   help="exit with status 2 when a file has warnings (damaged data read around)")
    p.add_argument("--in-process", action="store_true",
                   help="read the files in this process, not in a worker (a crash inside OCC then ends it)")
    p.set_defaults(func=run)


def add_worker_parser(sub: Any) -> None:
    """Register the hidden reader command (no ``help=``, so it stays out of the listing)."""
    w = sub.add_parser(WORKER_COMMAND)
    w.set_defaults(func=_worker)
