"""``occsurf check FILE_OR_DIR ... [--out DIR] [--json | --jsonl] [--faces ...] [--fail-on PRESET]
[--pictures worst|all|none] [--jobs N] [--timeout S] [--strict] [--in-process]``: the surface-quality report.

Reads each STEP or IGES model in a worker process (:func:`occsurf.bridge.isolation.run_jobs`, as
``occsurf inspect`` does: a crash or a hang inside OCC costs that file, not the terminal, and the
other files are still checked) and runs :func:`occsurf.bridge.quality.report.check_model` there:
per face (numbered as ``occsurf inspect`` numbers them) the curvature range and flags, per edge
between two faces the G0/G1/G2 continuity against a threshold preset. Folders are searched
recursively for STEP/IGES files. For one file, ``DIR`` gets

* ``DIR/report.json``: every number (``faces``: index, type, k_min, k_max, flags, ...; ``edges``:
  faces, midpoint, matched, g0_max, g1_max_deg, g2_max, g2_max_rel, worst_point, ...);
* ``DIR/index.html``: one offline page (overview, sortable face table, edge table, per-face
  pictures and flags, an interactive 3-D view) with its PNG pictures beside it: the model's and,
  by default, the 10 worst faces' (``--pictures all``: every face's; ``none``: no PNG);

for several files (or a folder) each file gets those in a folder of its own below ``DIR`` (its path
relative to the folder given, ``.`` of the suffix made ``_``: ``DIR/sub/part_step/``), and ``DIR``
gets an ``index.html`` and a ``report.json`` over all files (per file: status, faces, edges, the
worst G1 edge, flags by kind, violations, seconds, crashed faces). Everything is written atomically.
Several files are checked by ``--jobs`` workers at once (default one per core; each worker takes the
next file as soon as it is free, OCC loaded once: :mod:`occsurf.bridge.audit.check_pool`), their
lines still printed in the order of the arguments. A progress bar runs on stderr when it is a
terminal (with one worker at a time).

Crash isolation per face: the worker notes on a file which piece it is working on (the mesh, a
face, the edges, a picture) before each step. When the worker dies (a segmentation fault inside
OCC), the file is checked again without the piece at fault (a face is reported with ``error``
naming the crash, the edges or a picture are left out with a warning), up to
:data:`~occsurf.bridge.quality.check_files.MAX_RETRIES` times; the report keeps every other face.

The per-file work (finding the files, the worker's job, the retries, the pages and JSON) is library code,
:mod:`occsurf.bridge.quality.check_files`; this module parses the arguments, prints and shows progress.

A model read around damage (see :mod:`occsurf.bridge.exchange.checks`) is checked as read, its warnings in
the report; ``--strict`` refuses it instead (that file is unreadable: exit status 2, no report for it).

Output: a few lines per file as soon as it is checked (in the order of the arguments), then for several files
a summary; ``--json``: ``report.json`` (one file) or the summary ``report.json`` (several) at the end;
``--jsonl``: one JSON line per file as soon as it is checked, the file's object of the summary
``report.json``'s ``files`` (status, faces, edges, worst G1 edge, flags, violations, seconds; ``report`` and
``data`` relative to ``DIR``, ``./index.html`` for one file), for streaming into ``jq`` or a log. Ctrl-C
stops the checking: the lines printed stay whole, ``occsurf: interrupted`` on stderr, exit status 130; a
closed pipe (``occsurf check DIR --jsonl | head -1``) ends the command quietly (exit status 2). The
streaming is :class:`~occsurf.bridge.cli._common.InOrder`'s, shared with ``occsurf inspect``.

Exit status: 0 when every model was read and reported; 2 when one could not be read, an argument is
wrong or ``--out`` cannot be written (one line on stderr per problem); else, with ``--fail-on
PRESET``, 1 when an edge or a face of any file breaks that preset's thresholds (a CI gate).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import sys
import tempfile
import threading
from pathlib import Path
from typing import Any

from ..messages import error_line, strip_path
from ..quality.check_files import collect_files, file_summary, run_checks, write_outputs, write_summary
from ..quality.choices import PICTURE_CHOICES, WORST_FACES
from ._common import (
    EXIT_ERROR,
    EXIT_OK,
    InOrder,
    add_strict_option,
    error,
    jobs_arg,
    timeout_arg,
    worker_failure,
    write_json_line,
    write_out,
)

__all__ = ["add_parser", "run", "PRESET_NAMES", "EXIT_FAILED", "DEFAULT_TIMEOUT"]

#: Exit status when ``--fail-on`` finds an edge or a face that breaks the preset.
EXIT_FAILED = 1
#: The threshold presets of :data:`occsurf.bridge.quality.thresholds.PRESETS` (named here so the
#: command line does not import NumPy to list them; a test keeps the two equal).
PRESET_NAMES = ("catia", "class-a", "mechanical")
#: Seconds the worker may take for the whole model before it is stopped.
DEFAULT_TIMEOUT = 1800.0


# ---------------------------------------------------------------------------------------- parent
def _check_out(out: Path) -> str | None:
    """Why ``out`` cannot hold the report (``None`` when it can): created if missing, then a probe."""
    try:
        out.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile(dir=out, prefix=".occsurf-probe-"):
            pass
    except OSError as err:
        return f"--out {out}: cannot write there: {err.strerror or err}"
    return None


class _Progress:
    """Polls the worker's progress file and shows a bar on stderr (when stderr is a terminal)."""

    def __init__(self, path: Path, enabled: bool) -> None:
        self.path, self.enabled = path, enabled
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def __enter__(self) -> _Progress:
        if self.enabled:
            self._thread.start()
        return self

    def __exit__(self, *exc: Any) -> None:
        self._stop.set()
        if self.enabled:
            self._thread.join(timeout=2.0)

    def _run(self) -> None:
        from tqdm import tqdm

        bar: Any = None
        stage = None
        while not self._stop.wait(0.2):
            try:
                lines = self.path.read_text("utf-8").splitlines()
            except OSError:
                continue
            if not lines:
                continue
            parts = lines[-1].split()
            if len(parts) != 3:
                continue
            name, k, n = parts[0], int(parts[1]), int(parts[2])
            if name != stage:
                if bar is not None:
                    bar.close()
                bar = tqdm(total=n, desc=name, unit=name[:-1] if name.endswith("s") else name, file=sys.stderr,
                           leave=False)
                stage = name
            bar.n = k
            bar.refresh()
        if bar is not None:
            bar.close()


def _parse_faces(values: list[str] | None) -> list[int] | None:
    """``--faces 0 3 5-8`` or ``0,3,5-8`` -> sorted indices."""
    if not values:
        return None
    out: set[int] = set()
    for v in values:
        for part in v.split(","):
            part = part.strip()
            if not part:
                continue
            a, sep, b = part.partition("-")
            try:
                lo, hi = int(a), int(b) if sep else int(a)
            except ValueError:
                raise argparse.ArgumentTypeError(f"--faces: expected face indices like 0 3 5-8, got {part!r}") from None
            if lo < 0 or hi < lo:
                raise argparse.ArgumentTypeError(f"--faces: expected indices >= 0 and ranges low-high, got {part!r}")
            out.update(range(lo, hi + 1))
    return sorted(out)


# ---------------------------------------------------------------------------------------- output
def _summary(doc: dict[str, Any], out: Path, fail_on: str | None) -> str:
    g1 = doc.get("worst_g1_deg")
    lines = [
        f"{doc.get('path')}: {doc.get('n_faces')} faces, {doc.get('n_edges')} edges, worst G1 "
        f"{'-' if g1 is None else f'{g1:.3g} deg'}, {doc.get('n_flags')} flags, "
        f"{len(doc.get('failures') or [])} violations of {doc.get('preset')}, {doc['seconds'].get('total', 0):.2f} s",
        f"  report: {out / 'index.html'}",
        f"  data:   {out / 'report.json'}",
    ]
    crashed = [f["index"] for f in doc.get("faces") or [] if "crashed the checker" in str(f.get("error") or "")
               or "mesher crashed" in str(f.get("error") or "")]
    if crashed:
        lines.insert(1, f"  faces {', '.join(map(str, crashed))} crashed the checker and are left out")
    if fail_on:
        lines.append(f"  --fail-on {fail_on}: {'passed' if doc.get('passed') else 'FAILED'}")
    return "\n".join(lines) + "\n"


def _failure_reason(outcome: Any, ns: argparse.Namespace, path: Path) -> str:
    from ..isolation import ERROR

    reason = outcome.error if outcome.status == ERROR else worker_failure(outcome, ns.timeout, task="checking this file",
                                                                        process="checker")
    return strip_path(reason or "failed", path.resolve())


def run(ns: argparse.Namespace) -> int:
    """``occsurf check``: validate the arguments, run the worker per file, write the pages and the JSON."""
    from ..isolation import OK

    try:
        faces = _parse_faces(ns.faces)
    except argparse.ArgumentTypeError as err:
        error(str(err))
        return EXIT_ERROR
    single = len(ns.file) == 1 and not Path(ns.file[0]).is_dir()
    if faces is not None and not single:
        error("--faces: face numbers belong to one model; give a single FILE with --faces")
        return EXIT_ERROR
    entries = collect_files(ns.file)
    if single:
        shown, path, why, _ = entries[0]
        if path is None or not path.is_file():
            error(f"{shown}: {why or 'is not a regular file'}")
            return EXIT_ERROR
        default = Path(f"{path.stem}_check")
    else:
        first = Path(ns.file[0])
        default = Path(f"{first.resolve().name or 'model'}_check" if len(ns.file) == 1 else "occsurf_check")
    out = Path(ns.out) if ns.out else default
    why = _check_out(out)
    if why is not None:
        error(why)
        return EXIT_ERROR
    preset = ns.fail_on or "catia"
    work = [(k, (shown, path, why, name)) for k, (shown, path, why, name) in enumerate(entries) if path is not None]
    folders = {k: out if single else out / e[3] for k, e in work}
    for k in folders:
        why = _check_out(folders[k])
        if why is not None:
            error(why)
            return EXIT_ERROR
    fd, progress_name = tempfile.mkstemp(prefix=".progress-", dir=out)
    os.close(fd)
    scratch = [Path(progress_name)]
    items = []
    for k, e in work:
        fd, trace_name = tempfile.mkstemp(prefix=".trace-", dir=out)
        os.close(fd)
        scratch.append(Path(trace_name))
        items.append({"path": str(e[1].resolve()), "out": str(folders[k].resolve()), "faces": faces, "preset": preset,
                      "progress": progress_name, "trace": trace_name, "pictures": "none" if ns.no_pictures else ns.pictures,
                      "skip": {},
                      "strict": ns.strict})
    rows: dict[int, dict[str, Any]] = {}
    code = EXIT_OK
    failed = False
    # each file's lines (or its --jsonl row) as soon as it and the files before it are done: a crashed
    # file is re-run later, and with several workers files finish in any order
    def emit(k: int, done: tuple[dict[str, Any], str | None]) -> None:
        row, text = done
        if ns.jsonl:
            write_json_line(row)
        elif text:
            write_out(text)

    stream = InOrder(len(entries), emit)

    def finish(j: int, outcome: Any) -> None:
        nonlocal code, failed
        k, (shown, path, _, name) = work[j]
        folder = folders[k]
        if outcome.status != OK:
            error(f"{shown}: {_failure_reason(outcome, ns, path)}")
            rows[k] = file_summary(shown, None, error_text=_failure_reason(outcome, ns, path))
            code = EXIT_ERROR
            stream.put(k, (rows[k], None))
            return
        result = outcome.value
        result["report"]["path"] = shown
        try:
            write_outputs(folder, result)
        except Exception as err:  # noqa: BLE001 - one line, never a traceback
            error(f"--out {folder}: {error_line(err)}")
            rows[k] = file_summary(shown, None, error_text=f"report not written: {error_line(err)}")
            code = EXIT_ERROR
            stream.put(k, (rows[k], None))
            return
        doc = result["report"]
        for w in doc.get("warnings") or []:  # what the reading read around, as inspect, convert and fill say it
            error(f"{shown}: warning: {w}")
        failed |= not doc.get("passed", True)
        rows[k] = file_summary(shown, "." if single else name, doc, crashed=items[j].get("skip"),
                               thumbnail=(result.get("pictures") or {}).get("mean"))
        if single and ns.json:
            write_out(json.dumps(doc, indent=1, allow_nan=False) + "\n")
        stream.put(k, (rows[k], None if ns.json or ns.jsonl else _summary(doc, folder, ns.fail_on)))

    for k, (shown, path, why, _) in enumerate(entries):
        if path is None:
            error(f"{shown}: {why}")
            rows[k] = file_summary(shown, None, error_text=why)
            code = EXIT_ERROR
            stream.put(k, (rows[k], None))
    try:
        from ..audit.fill_file import default_jobs

        jobs = 1 if ns.in_process else min(default_jobs() if ns.jobs is None else ns.jobs, max(1, len(items)))
        # the progress file holds the stage of the worker that wrote last: a bar with one worker only
        with _Progress(scratch[0], enabled=sys.stderr.isatty() and not (ns.json or ns.jsonl) and jobs == 1):
            if jobs > 1:
                from ..audit.check_pool import check_files

                check_files(items, jobs=jobs, timeout=ns.timeout, on_outcome=finish)
            else:
                run_checks(items, timeout=ns.timeout, isolate=not ns.in_process, on_outcome=finish)
    finally:
        for f in scratch:
            with contextlib.suppress(OSError):
                f.unlink()
    if not single:
        summary = write_summary(out, [rows[k] for k in sorted(rows)], preset, ns.fail_on)
        if ns.json:
            sys.stdout.write(json.dumps(summary, indent=1, allow_nan=False) + "\n")
        elif not ns.jsonl:
            n = summary["n_files"]
            # the status words of report.json ("failed": breaks the preset) said as what they mean
            words = {"failed": f"break{'s' if summary['counts'].get('failed') == 1 else ''} {summary['preset']}"}
            counts = ", ".join(f"{c} {words.get(k, k)}" for k, c in summary["counts"].items())
            gate = f"  --fail-on {ns.fail_on}: {'passed' if summary['passed'] else 'FAILED'}\n" if ns.fail_on else ""
            sys.stdout.write(f"{n} file{'' if n == 1 else 's'}: {counts}\n  index:  {out / 'index.html'}\n"
                             f"  data:   {out / 'report.json'}\n{gate}")
    sys.stdout.flush()
    if code != EXIT_OK:
        return code
    if ns.fail_on and failed:
        return EXIT_FAILED
    return EXIT_OK


def add_parser(sub: Any) -> None:
    """Register ``check`` on the sub-parsers of :func:`occsurf.bridge.cli.build_parser`."""
    p = sub.add_parser(
        "check",
        help="surface-quality report of a STEP/IGES model: curvature, zebra, sections, edge continuity",
        description=("Assess every face (curvature range, flags with suggested corrections) and every edge "
                     "between two faces (G0 gap, G1 angle, G2 jump) of STEP/IGES models (files, or folders searched "
                     "recursively); write DIR/index.html (an offline page with pictures and a 3-D view) and "
                     "DIR/report.json per file, and for several files an index.html and report.json over all. "
                     "Each file is read in a worker process; a face that crashes it is left out and named. Exit 0 "
                     "when all were read, 2 when one was unreadable or on bad arguments, 1 with --fail-on when an "
                     "edge or face of any file breaks the preset."),
    )
    p.add_argument("file", nargs="+", metavar="FILE_OR_DIR",
                   help="STEP (.step, .stp) or IGES (.iges, .igs) files, or folders searched recursively for them")
    p.add_argument("--out", metavar="DIR", help="folder for index.html, report.json and the pictures (default: FILE's "
                                                "stem + '_check', a folder's name + '_check', or occsurf_check for "
                                                "several arguments, in the current folder); several files: one folder "
                                                "per file below DIR plus DIR/index.html and DIR/report.json over all")
    fmt = p.add_mutually_exclusive_group()
    fmt.add_argument("--json", action="store_true", help="print report.json on stdout instead of the summary (several "
                                                         "files: the summary report.json)")
    fmt.add_argument("--jsonl", action="store_true",
                     help="print one JSON line per file as soon as it is checked (the objects of the summary "
                          "report.json's 'files')")
    p.add_argument("--faces", nargs="+", metavar="N", help="only these faces (numbered as in 'occsurf inspect'; "
                                                          "ranges like 5-8 and commas allowed)")
    p.add_argument("--fail-on", choices=PRESET_NAMES, metavar="PRESET",
                   help=f"exit 1 when an edge or face breaks this preset ({', '.join(PRESET_NAMES)}); it is also the "
                        "preset the report is judged against (default catia)")
    pics = p.add_mutually_exclusive_group()
    pics.add_argument("--pictures", choices=PICTURE_CHOICES, default="worst",
                      help="PNG pictures: 'worst' (default) the model's and the "
                           f"{WORST_FACES} worst faces' (by flags and violations), 'all' every face's too, 'none' "
                           "(the page keeps its tables and 3-D view)")
    pics.add_argument("--no-pictures", action="store_true", help="the same as --pictures none: a faster CI gate")
    p.add_argument("--jobs", type=jobs_arg, default=None, metavar="N",
                   help="check this many files at once, in as many worker processes, each taking the next file "
                        "when it is free (default: one per core; the lines keep the order of the arguments)")
    p.add_argument("--timeout", type=timeout_arg, default=DEFAULT_TIMEOUT, metavar="SECONDS",
                   help=f"stop the checker after this long (default {DEFAULT_TIMEOUT:g})")
    add_strict_option(p, writes=True)
    p.add_argument("--in-process", action="store_true",
                   help="check in this process, not in a worker (a crash inside OCC then ends it)")
    p.set_defaults(func=run)
