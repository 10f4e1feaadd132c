"""Check STEP/IGES files for surface quality: the per-file work of ``occsurf check``.

The command line parses its arguments, prints and shows progress; the work is here:

* :func:`collect_files` — the files its arguments name (folders searched recursively), each with the
  folder its report goes to;
* :func:`check_file` — read one model (:func:`occsurf.bridge.exchange.reading.read_model`), assess it
  (:func:`occsurf.bridge.quality.report.check_model`), draw its pictures and the 3-D view's data;
  :func:`check_job` is the same as the worker process's job (:data:`CHECK_JOB`);
* :func:`run_checks` — :func:`check_job` on every file in a worker process; when the worker dies (a
  segmentation fault inside OCC) the file is checked again without the piece at fault
  (:func:`crash_skip`: a face, the edges, a picture), up to :data:`MAX_RETRIES` times;
* :func:`write_outputs` — a file's ``report.json`` and ``index.html``; :func:`file_summary` its row of the
  summary over several files, which :func:`write_summary` writes (``report.json``, ``index.html``).

Everything is written atomically. Only the standard library is imported at module level (the command
line imports this module to build its parser); the checks load NumPy and OCC when they run.
"""

from __future__ import annotations

import contextlib
import json
import os
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..exchange.reading import SUFFIXES, expand, folder_entries, read_model, shown_path, sniff_format

if TYPE_CHECKING:
    from ..isolation import Outcome

__all__ = ["check_file", "check_job", "run_checks", "rerun_without_fault", "crash_skip", "write_outputs", "collect_files", "file_summary",
           "write_summary", "CHECK_JOB", "PRELOAD", "MAX_RETRIES"]

#: The job the worker process runs per file (``"module:function"`` for :func:`~occsurf.bridge.isolation.run_jobs`).
CHECK_JOB = "occsurf.bridge.quality.check_files:check_job"
#: What the worker loads before its first file.
PRELOAD = ("occsurf.bridge.exchange.step_iges", "occsurf.bridge.quality.report", "occsurf.bridge.quality.continuity",
           "occsurf.bridge.rendering.vtk_scene")
#: Times a file is checked again after its worker crashed, each time without the piece at fault.
MAX_RETRIES = 8


# ---------------------------------------------------------------------------------------- files
def collect_files(args: list[str]) -> list[tuple[str, Path | None, str | None, str]]:
    """``(shown path, path or None, error or None, output folder name)`` for every argument, folders
    searched recursively (sorted) for STEP/IGES files by suffix.

    The output folder name is the file's path relative to the folder argument (just its name for a
    file argument), suffix dot made ``_`` (``sub/part.step`` -> ``sub/part_step``), made unique.
    Links that lead nowhere, devices and unreadable folders are reported as errors, not skipped.
    """
    out: list[tuple[str, Path | None, str | None, str]] = []
    for arg in args:
        root = Path(arg)
        if not root.is_dir():
            (shown, path, err), = expand([arg])
            out.append((shown, path, err, root.name.replace(".", "_") or "model"))
            continue
        found: list[tuple[Path, str | None]] = []
        walk_errors: list[OSError] = []
        for folder, dirs, _files in os.walk(root, onerror=walk_errors.append):
            dirs.sort()
            found.extend(folder_entries(Path(folder)))
        for walk_error in walk_errors:
            out.append((shown_path(walk_error.filename or arg), None,
                        f"cannot read this folder: {walk_error.strerror or walk_error}", ""))
        found.sort(key=lambda t: (len(t[0].relative_to(root).parts) > 1, str(t[0])))
        if not found and not walk_errors:
            out.append((shown_path(arg), None, f"no STEP/IGES files ({', '.join(SUFFIXES)}) in this folder or below", ""))
        for f, err in found:
            rel = f.relative_to(root)
            out.append((shown_path(f), f if err is None else None, err, str(rel.with_name(rel.name.replace(".", "_")))))
    seen: dict[str, int] = {}
    unique = []
    for shown, path, err, name in out:
        base = name.replace(os.sep, "/") or "model"
        seen[base] = seen.get(base, 0) + 1
        unique.append((shown, path, err, base if seen[base] == 1 else f"{base}-{seen[base]}"))
    return unique


# ---------------------------------------------------------------------------------------- worker
def check_file(path: str | os.PathLike[str], out: str | os.PathLike[str], *, faces: list[int] | None = None,
               preset: str = "catia", pictures: bool | str = "worst", progress: Callable[[str, int, int], None] | None = None,
               skip: dict[str, Any] | None = None, trace: Callable[[str], None] | None = None,
               strict: bool = False) -> dict[str, Any]:
    """Read, assess and draw one model; the library side of ``occsurf check`` (in this process).

    ``pictures``: ``"worst"`` (the model pictures and the :data:`~.pictures.WORST_FACES` worst faces'),
    ``"all"`` (every face's too), ``"none"``; ``True``/``False`` mean ``"all"``/``"none"``.

    Writes the pictures and ``.viewer.json`` (the 3-D view's data) into ``out``; returns
    ``{"report": report JSON, "pictures": {kind: file}, "viewer": path of the viewer data}``.
    ``index.html`` and ``report.json`` are written by :func:`write_outputs`.

    ``skip`` leaves out what crashed an earlier attempt: ``{"faces": {index: reason}, "edges":
    reason, "pictures": {file name: reason}, "mesh_each": bool}``; ``trace(stage)`` is called
    before each piece of work (see :func:`~occsurf.bridge.quality.report.check_model`).
    """
    from .pictures import PICTURE_CHOICES

    choice = {True: "all", False: "none"}.get(pictures, pictures) if isinstance(pictures, bool) else pictures
    if choice not in PICTURE_CHOICES:
        raise ValueError(f"pictures: expected one of {', '.join(PICTURE_CHOICES)}, got {pictures!r}")
    p = Path(path)
    skip = skip or {}
    note: Callable[[str], None] = trace if trace is not None else (lambda stage: None)
    t0 = time.perf_counter()
    note("read")
    model = read_model(p, sniff_format(p), strict=strict)  # strict: warnings refuse the file
    t_read = time.perf_counter() - t0
    # every face is sampled on a 41 x 41 grid and more: a model of 20 faces or more repays numba's
    # loading, and then its many small evaluations (sections, trims, flags) keep the kernels too
    from occsurf.algorithms import _numba_kernels as _nk  # not at module level: the CLI imports this module

    with _nk.batch(len(model.faces) * 41 * 41):
        return _check_read(model, path, out, t0, t_read, faces, preset, choice, progress, skip, note)


def _check_read(model: Any, path: str | os.PathLike[str], out: str | os.PathLike[str], t0: float, t_read: float,
                faces: list[int] | None, preset: str, choice: str, progress: Callable[[str, int, int], None] | None,
                skip: dict[str, Any], note: Callable[[str], None]) -> dict[str, Any]:
    """:func:`check_file` after reading the model."""
    from ..exchange.files import atomic_write
    from .html import viewer_payload
    from .pictures import WORST_FACES, render_report_pictures
    from .report import check_model, worst_faces

    report = check_model(model, faces=faces, preset=preset,
                         progress=None if progress is None else (lambda k, n: progress("faces", k, n)),
                         skip={int(k): v for k, v in (skip.get("faces") or {}).items()},
                         edges=skip.get("edges") or True, trace=note, mesh_each=bool(skip.get("mesh_each")),
                         free_meshes=True)
    report.path = str(path)
    _drop_triangulation(model)
    shown: dict[str, str] = {}
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)  # also without pictures: the viewer data goes there
    chosen: set[int] | None = set() if choice == "none" else (
        None if choice == "all" else set(worst_faces(report, WORST_FACES)))
    if choice != "none":
        t1 = time.perf_counter()
        shown = render_report_pictures(report, out, faces=chosen, progress=None if progress is None else
                                       (lambda k, n: progress("pictures", k, n)),
                                       skip=skip.get("pictures"), trace=note)
        report.seconds["pictures"] = time.perf_counter() - t1
    report.picture_faces = {"choice": choice, "faces": None if chosen is None else sorted(chosen)}
    note("viewer")
    report.seconds["read"] = t_read
    report.seconds["total"] = time.perf_counter() - t0
    viewer = out / ".viewer.json"
    atomic_write(viewer, json.dumps(viewer_payload(report), allow_nan=False).encode("utf-8"))
    return {"report": report.to_json(), "pictures": shown, "viewer": str(viewer)}


def _drop_triangulation(model: Any) -> None:
    """Free OCC's triangulation of the model this check read (the faces' meshes were copied into
    the report's fields; nothing after the faces reads OCC's: the 1089-face plate's held ~150 MB
    through the pictures). Only here, on a model of our own: :func:`~.report.check_model` leaves a
    caller's shape as meshed."""
    from OCP.BRepTools import BRepTools

    BRepTools.Clean_s(model.shape)


def check_job(item: dict[str, Any]) -> dict[str, Any]:
    """The worker's job (:data:`CHECK_JOB`): ``{"path", "out", "faces", "preset", "pictures", "skip", "strict",
    "progress", "trace"}`` -> :func:`check_file`'s result.

    ``progress`` names a file that gets a line ``STAGE K N`` as work advances; ``trace`` a file that holds
    the piece being worked on, written through before each piece (it survives a crash of the process:
    :func:`run_checks` reads it to know what to leave out).
    """
    import numpy as np

    from ..isolation import quiet_native_stdout

    progress_file = item.get("progress")
    trace_file = item.get("trace")

    def progress(stage: str, k: int, n: int) -> None:
        if progress_file:
            with contextlib.suppress(OSError), open(progress_file, "a", encoding="utf-8") as fh:
                fh.write(f"{stage} {k} {n}\n")

    def trace(stage: str) -> None:
        if trace_file:  # written through to the kernel before the step: it survives a crash of this process
            with contextlib.suppress(OSError), open(trace_file, "w", encoding="utf-8") as fh:
                fh.write(stage)

    with np.errstate(all="ignore"), quiet_native_stdout():
        return check_file(item["path"], item["out"], faces=item.get("faces"), preset=item.get("preset", "catia"),
                          pictures=item.get("pictures", "worst"), progress=progress, skip=item.get("skip"),
                          trace=trace, strict=bool(item.get("strict")))


# ---------------------------------------------------------------------------------------- retries
def crash_skip(stage: str, reason: str, skip: dict[str, Any]) -> dict[str, Any] | None:
    """``skip`` grown by the piece named ``stage`` (what the crashed worker was doing), or ``None``
    when nothing can be left out (reading the file, or the same piece again)."""
    new = json.loads(json.dumps(skip))
    words = stage.split()
    if stage == "mesh" and not new.get("mesh_each"):
        new["mesh_each"] = True
    elif len(words) == 3 and words[:2] == ["mesh", "face"] and words[2].isdigit():
        new.setdefault("faces", {})[words[2]] = f"not evaluated: OCC's mesher crashed on this face ({reason})"
    elif len(words) == 2 and words[0] == "face" and words[1].isdigit():
        new.setdefault("faces", {})[words[1]] = f"not evaluated: checking this face crashed the checker ({reason})"
    elif stage == "edges" and not new.get("edges"):
        new["edges"] = f"measuring them crashed the checker ({reason})"
    elif len(words) == 2 and words[0] == "picture":
        new.setdefault("pictures", {})[words[1]] = f"drawing it crashed the checker ({reason})"
    else:
        return None
    return None if new == skip else new


def rerun_without_fault(item: dict[str, Any], outcome: Outcome) -> dict[str, Any] | None:
    """The item to check again after ``outcome``: ``item`` with the piece its ``trace`` file names
    (the stage the worker was in when it died) added to ``skip`` (:func:`crash_skip`); ``None`` when
    the worker did not crash, or the trace names nothing left to skip. What :func:`run_checks` and
    ``check --jobs`` (:func:`occsurf.bridge.audit.check_pool.check_files`) do after a crash."""
    from ..isolation import CRASHED

    if outcome.status != CRASHED:
        return None
    try:
        stage = Path(item["trace"]).read_text("utf-8").strip()
    except OSError:
        stage = ""
    grown = crash_skip(stage, outcome.exit_reason or "crashed", item.get("skip") or {})
    return None if grown is None else dict(item, skip=grown)


def run_checks(items: list[dict[str, Any]], *, timeout: float | None, isolate: bool = True,
               on_outcome: Callable[[int, Outcome], None] | None = None, job: str | None = None) -> list[Outcome]:
    """Run :func:`check_job` on every item in a worker process (:func:`~occsurf.bridge.isolation.run_jobs`);
    an item whose worker crashed is run again without the piece at fault (:func:`crash_skip`, from the
    item's ``trace`` file), up to :data:`MAX_RETRIES` times.

    Parameters
    ----------
    items : list of dict
        :func:`check_job`'s items. An item run again is replaced in this list by a copy whose ``skip``
        names what was left out (so the caller can report it).
    timeout : float or None
        Seconds a worker may take per item.
    isolate : bool, default True
        False: run in this process (no protection against a crash).
    on_outcome : callable, optional
        ``on_outcome(k, outcome)`` with each item's final outcome, as soon as it is known.
    job : str, optional
        The job's ``"module:function"`` (default :data:`CHECK_JOB`, read at call time).

    Returns
    -------
    list of Outcome
        The final outcomes, in the order of ``items``.
    """
    from ..isolation import run_jobs

    spec = CHECK_JOB if job is None else job
    final: dict[int, Outcome] = {}
    todo = list(range(len(items)))
    for attempt in range(MAX_RETRIES + 1):
        if not todo:
            break
        batch = [items[k] for k in todo]
        again: list[int] = []

        def settle(o: Outcome, todo: list[int] = todo, again: list[int] = again, attempt: int = attempt) -> None:
            k = todo[o.index]
            rerun = rerun_without_fault(items[k], o) if attempt < MAX_RETRIES else None
            if rerun is not None:
                items[k] = rerun
                again.append(k)
                return
            final[k] = o
            if on_outcome is not None:
                on_outcome(k, o)

        run_jobs(spec, batch, timeout=timeout, isolate=isolate, preload=PRELOAD, on_outcome=settle)
        todo = sorted(again)
    return [final[k] for k in range(len(items))]


# ---------------------------------------------------------------------------------------- outputs
def write_outputs(out: Path, result: dict[str, Any]) -> None:
    """``report.json`` and ``index.html`` from the worker's result, atomically; drops the viewer data."""
    from ..exchange.files import atomic_write
    from .html import write_html

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


def _smooth_worst(edges: list[dict[str, Any]]) -> dict[str, Any] | None:
    """The edge with the largest G1 angle among those meant to be tangent-continuous."""
    from math import isfinite

    smooth = ("gap", "G0", "G1", "G2")
    cand = [e for e in edges if e.get("classification") in smooth and isinstance(e.get("g1_max_deg"), (int, float))
            and isfinite(e["g1_max_deg"])]
    if not cand:
        return None
    e = max(cand, key=lambda e: e["g1_max_deg"])
    return {k: e.get(k) for k in ("faces", "g1_max_deg", "classification", "matched", "midpoint", "worst_point")}


def file_summary(shown: str, folder: str | None, doc: dict[str, Any] | None = None, *, error_text: str | None = None,
                 crashed: dict[str, Any] | None = None, thumbnail: str | None = None) -> dict[str, Any]:
    """One file's row of the summary ``report.json`` (and of its ``index.html``): ``status`` is
    ``ok``, ``failed`` (breaks the preset) or ``unreadable`` (``error`` says why); ``crashed_faces``
    and ``skipped`` name what was left out after a crash of the checker; ``thumbnail`` is a picture
    of the model relative to the summary's folder."""
    row: dict[str, Any] = {"path": shown, "report": None if folder is None else f"{folder}/index.html",
                           "data": None if folder is None else f"{folder}/report.json"}
    if doc is None:
        row.update(status="unreadable", error=error_text, n_faces=None, n_edges=None, worst_g1_deg=None,
                   worst_g1_edge=None, flags={}, n_violations=None, passed=None, crashed_faces=[], skipped=[],
                   seconds=None, report=None, data=None, thumbnail=None)
        return row
    flags: dict[str, int] = {}
    for f in doc.get("faces") or []:
        for g in f.get("flags") or []:
            flags[g["kind"]] = flags.get(g["kind"], 0) + 1
    crashed = crashed or {}
    crashed_faces = sorted(int(k) for k in (crashed.get("faces") or {}))
    skipped = ([f"edges not measured: {crashed['edges']}"] if crashed.get("edges") else []) + [
        f"picture {k} not drawn: {v}" for k, v in (crashed.get("pictures") or {}).items()]
    row.update(status="ok" if doc.get("passed", True) else "failed", error=None, n_faces=doc.get("n_faces"),
               n_edges=doc.get("n_edges"), worst_g1_deg=doc.get("worst_g1_deg"),
               worst_g1_edge=_smooth_worst(doc.get("edges") or []), flags=dict(sorted(flags.items())),
               n_violations=len(doc.get("failures") or []), passed=bool(doc.get("passed", True)),
               crashed_faces=crashed_faces, skipped=skipped, seconds=(doc.get("seconds") or {}).get("total"),
               thumbnail=None if thumbnail is None or folder is None else f"{folder}/{thumbnail}")
    return row


def write_summary(out: Path, rows: list[dict[str, Any]], preset: str, fail_on: str | None) -> dict[str, Any]:
    """The top-level ``report.json`` and ``index.html`` over all files (atomically); returns the JSON."""
    from ..exchange.files import atomic_write
    from .html import write_index_html

    counts: dict[str, int] = {}
    for r in rows:
        counts[r["status"]] = counts.get(r["status"], 0) + 1
    summary = {"n_files": len(rows), "counts": counts, "preset": preset, "fail_on": fail_on,
               "passed": all(r["status"] == "ok" for r in rows), "files": rows}
    atomic_write(out / "report.json", (json.dumps(summary, indent=1, allow_nan=False) + "\n").encode("utf-8"))
    write_index_html(out / "index.html", summary)
    return summary
