"""``occsurf check FILE [--out DIR] [--json] [--faces ...] [--fail-on PRESET] [--no-pictures]``: the surface-quality report.

Reads a STEP or IGES model in a worker process (:func:`occsurf.bridge.isolation.run_jobs`, as
``occsurf inspect`` does: a crash or a hang inside OCC costs the command, not the terminal) and
runs :func:`occsurf.bridge.quality.report.check_model` there: per face (numbered as ``occsurf
inspect`` numbers them) the curvature range and flags, per edge between two faces the G0/G1/G2
continuity against a threshold preset. Writes

* ``DIR/report.json``: every number (``faces``: index, type, k_min, k_max, flags, ...; ``edges``:
  faces, midpoint, matched, g0_max, g1_max_deg, g2_max, g2_max_rel, worst_point, ...);
* ``DIR/index.html``: one offline page (overview, sortable face table, edge table, per-face
  pictures and flags, an interactive 3-D view) with its PNG pictures beside it;

both atomically. A progress bar runs on stderr when it is a terminal.

Exit status: 0 when the model was read and reported; 2 when it could not be read, an argument is
wrong or ``--out`` cannot be written (one line on stderr); with ``--fail-on PRESET``, 1 when an
edge or a face breaks that preset's thresholds (a CI gate).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

from ..messages import error_line
from ._common import EXIT_ERROR, EXIT_OK, error, strip_path, timeout_arg, worker_failure

__all__ = ["add_parser", "run", "check_job", "check_file", "PRESET_NAMES", "EXIT_FAILED", "DEFAULT_TIMEOUT"]

#: Exit status when ``--fail-on`` finds an edge or a face that breaks the preset.
EXIT_FAILED = 1
#: The threshold presets of :data:`occsurf.bridge.quality.continuity.PRESETS` (named here so the
#: command line does not import NumPy to list them; a test keeps the two equal).
PRESET_NAMES = ("catia", "class-a", "mechanical")
#: Seconds the worker may take for the whole model before it is stopped.
DEFAULT_TIMEOUT = 1800.0
CHECK_JOB = "occsurf.bridge.cli.check:check_job"
PRELOAD = ("occsurf.bridge.exchange.step_iges", "occsurf.bridge.quality.report", "occsurf.bridge.quality.continuity",
           "occsurf.bridge.rendering.vtk_scene")


# ---------------------------------------------------------------------------------------- worker
def check_file(path: str | os.PathLike[str], out: str | os.PathLike[str], *, faces: list[int] | None = None,
               preset: str = "catia", pictures: bool = True, progress: Any = None) -> dict[str, Any]:
    """Read, assess and draw one model; the library side of ``occsurf check`` (in this process).

    Writes the pictures and ``.viewer.json`` (the 3-D view's data) into ``out``; returns
    ``{"report": report JSON, "pictures": {kind: file}, "viewer": path of the viewer data}``.
    ``index.html`` and ``report.json`` are written by :func:`write_outputs`.
    """
    from ..exchange.files import atomic_write
    from ..quality.html import viewer_payload
    from ..quality.pictures import render_report_pictures
    from ..quality.report import check_model
    from ._common import read_model, sniff_format

    p = Path(path)
    t0 = time.perf_counter()
    model = read_model(p, sniff_format(p))
    t_read = time.perf_counter() - t0
    report = check_model(model, faces=faces, preset=preset,
                         progress=None if progress is None else (lambda k, n: progress("faces", k, n)))
    report.path = str(path)
    shown: dict[str, str] = {}
    out = Path(out)
    if pictures:
        t1 = time.perf_counter()
        shown = render_report_pictures(report, out, progress=None if progress is None else
                                       (lambda k, n: progress("pictures", k, n)))
        report.seconds["pictures"] = time.perf_counter() - t1
    report.seconds["read"] = t_read
    report.seconds["total"] = time.perf_counter() - t0
    viewer = out / ".viewer.json"
    atomic_write(viewer, json.dumps(viewer_payload(report), allow_nan=False).encode("utf-8"))
    return {"report": report.to_json(), "pictures": shown, "viewer": str(viewer)}


def check_job(item: dict[str, Any]) -> dict[str, Any]:
    """The worker's job: ``{"path", "out", "faces", "preset", "progress"}`` -> :func:`check_file`'s result."""
    import numpy as np

    from ..isolation import quiet_native_stdout

    progress_file = item.get("progress")

    def progress(stage: str, k: int, n: int) -> None:
        if progress_file:
            with contextlib.suppress(OSError), open(progress_file, "a", encoding="utf-8") as fh:
                fh.write(f"{stage} {k} {n}\n")

    with np.errstate(all="ignore"), quiet_native_stdout():
        return check_file(item["path"], item["out"], faces=item.get("faces"), preset=item.get("preset", "catia"),
                          pictures=bool(item.get("pictures", True)), progress=progress)


def write_outputs(out: Path, result: dict[str, Any]) -> None:
    """``report.json`` and ``index.html`` from the worker's result, atomically; drops the viewer data."""
    from ..exchange.files import atomic_write
    from ..quality.html import write_html

    doc = result["report"]
    atomic_write(out / "report.json", (json.dumps(doc, indent=1, allow_nan=False) + "\n").encode("utf-8"))
    viewer = Path(result["viewer"])
    try:
        payload = json.loads(viewer.read_text("utf-8"))
    except (OSError, ValueError):
        payload = {"faces": [], "ranges": {}, "skipped": True, "n_vertices": 0, "size": 1.0}
    write_html(out / "index.html", doc, payload, result.get("pictures") or {})
    with contextlib.suppress(OSError):
        viewer.unlink()


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

        bar = None
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


def _summary(doc: dict[str, Any], out: Path, fail_on: str | None) -> str:
    g1 = doc.get("worst_g1_deg")
    lines = [
        f"{doc.get('path')}: {doc.get('n_faces')} faces, {doc.get('n_edges')} edges, worst G1 "
        f"{'-' if g1 is None else f'{g1:.3g} deg'}, {doc.get('n_flags')} flags, "
        f"{len(doc.get('failures') or [])} violations of {doc.get('preset')}, {doc['seconds'].get('total', 0):.2f} s",
        f"  report: {out / 'index.html'}",
        f"  data:   {out / 'report.json'}",
    ]
    if fail_on:
        lines.append(f"  --fail-on {fail_on}: {'passed' if doc.get('passed') else 'FAILED'}")
    return "\n".join(lines) + "\n"


def run(ns: argparse.Namespace) -> int:
    """``occsurf check``: validate the arguments, run the worker, write the page and the JSON."""
    from ..isolation import ERROR, OK, run_jobs

    try:
        faces = _parse_faces(ns.faces)
    except argparse.ArgumentTypeError as err:
        error(str(err))
        return EXIT_ERROR
    path = Path(ns.file)
    if not path.is_file():
        error(f"{ns.file}: {'is a directory' if path.is_dir() else 'no such file'}")
        return EXIT_ERROR
    out = Path(ns.out) if ns.out else Path(f"{path.stem}_check")
    why = _check_out(out)
    if why is not None:
        error(why)
        return EXIT_ERROR
    preset = ns.fail_on or "catia"
    fd, progress_name = tempfile.mkstemp(prefix=".progress-", dir=out)
    os.close(fd)
    progress_path = Path(progress_name)
    item = {"path": str(path.resolve()), "out": str(out.resolve()), "faces": faces, "preset": preset,
            "progress": progress_name, "pictures": not ns.no_pictures}
    try:
        with _Progress(progress_path, enabled=sys.stderr.isatty() and not ns.json):
            (outcome,) = run_jobs(CHECK_JOB, [item], timeout=ns.timeout, isolate=not ns.in_process, preload=PRELOAD)
    finally:
        with contextlib.suppress(OSError):
            progress_path.unlink()
    if outcome.status != OK:
        reason = outcome.error if outcome.status == ERROR else worker_failure(outcome, ns.timeout, task="checking this file",
                                                                            process="checker")
        error(f"{ns.file}: {strip_path(reason or 'failed', path.resolve())}")
        return EXIT_ERROR
    result = outcome.value
    result["report"]["path"] = ns.file
    try:
        write_outputs(out, result)
    except Exception as err:  # noqa: BLE001 - one line, never a traceback
        error(f"--out {out}: {error_line(err)}")
        return EXIT_ERROR
    doc = result["report"]
    if ns.json:
        sys.stdout.write(json.dumps(doc, indent=1, allow_nan=False) + "\n")
    else:
        sys.stdout.write(_summary(doc, out, ns.fail_on))
    sys.stdout.flush()
    if ns.fail_on and not doc.get("passed", True):
        return EXIT_FAILED
    return EXIT_OK


def add_parser(sub: Any) -> None:
    """Register ``check`` on the sub-parsers of :func:`occsurf.bridge.cli.build_parser`."""
    p = sub.add_parser(
        "check",
        help="surface-quality report of a STEP/IGES model: curvature, zebra, sections, edge continuity",
        description=("Assess every face (curvature range, flags with suggested corrections) and every edge "
                     "between two faces (G0 gap, G1 angle, G2 jump) of a STEP/IGES model; write DIR/index.html "
                     "(an offline page with pictures and a 3-D view) and DIR/report.json. Exit 0 when read, 2 when "
                     "unreadable or on bad arguments, 1 with --fail-on when an edge or face breaks the preset."),
    )
    p.add_argument("file", metavar="FILE", help="a STEP (.step, .stp) or IGES (.iges, .igs) file")
    p.add_argument("--out", metavar="DIR", help="folder for index.html, report.json and the pictures "
                                                "(default: FILE's stem + '_check' in the current folder)")
    p.add_argument("--json", action="store_true", help="print report.json on stdout instead of the summary")
    p.add_argument("--faces", nargs="+", metavar="N", help="only these faces (numbered as in 'occsurf inspect'; "
                                                          "ranges like 5-8 and commas allowed)")
    p.add_argument("--fail-on", choices=PRESET_NAMES, metavar="PRESET",
                   help=f"exit 1 when an edge or face breaks this preset ({', '.join(PRESET_NAMES)}); it is also the "
                        "preset the report is judged against (default catia)")
    p.add_argument("--no-pictures", action="store_true",
                   help="skip the PNG pictures (the page keeps its tables and 3-D view): a faster CI gate")
    p.add_argument("--timeout", type=timeout_arg, default=DEFAULT_TIMEOUT, metavar="SECONDS",
                   help=f"stop the checker after this long (default {DEFAULT_TIMEOUT:g})")
    p.add_argument("--in-process", action="store_true",
                   help="check in this process, not in a worker (a crash inside OCC then ends it)")
    p.set_defaults(func=run)
