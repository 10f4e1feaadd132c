"""The per-file task of ``occsurf audit``: read, inspect every face, round trip, quality hook.

Two halves, two processes:

* :func:`audit_task` runs in a Dask worker (no OCC there). It hands the file to the worker
  thread's persistent reader process (:mod:`.reader`), so a segmentation fault or a hang inside
  OCC costs that file only, with the signal known, and returns one JSON-safe result dict with
  ``status`` ``ok`` | ``error`` | ``crashed`` | ``timeout``. It never raises for a file.
* :func:`audit_job` runs in the reader process (OCC loaded once): the crash-prone work.

Checks (``--checks``, any of :data:`CHECKS`)
--------------------------------------------
``inspect``
    :func:`occsurf.bridge.validation.inspect.inspect_model` per face: type, degrees, poles,
    rational/periodic flags, continuity, our evaluation against OCC's (``max_dev``, relative to the
    face's sampled bounding-box diagonal).
``roundtrip``
    Every converted face surface written with our lossless STEP writer (17 digits), read back with
    our reader and compared with :func:`occsurf.bridge.validation.deviation.roundtrip_deviation`:
    per face ``roundtrip_dev`` (largest point distance, relative to the diagonal of the face's
    poles) and ``roundtrip_exact`` (same structure, poles, knots and weights identical).
``quality``
    The hook for the surface-quality issue: :data:`QUALITY_HOOK` names a function
    ``summarize(model) -> {"worst_g1_deg": float, "curvature_spikes": int, "flags": [str]}``.
    Until that module exists the columns stay empty and the file row says why
    (``quality_status``).
"""

from __future__ import annotations

import contextlib
import importlib
import os
import socket
import tempfile
import time
from pathlib import Path
from typing import Any

from ..messages import error_line, strip_path

__all__ = ["CHECKS", "DEFAULT_CHECKS", "QUALITY_HOOK", "PRELOAD", "JOB", "audit_task", "audit_job", "make_item"]

CHECKS = ("inspect", "quality", "roundtrip")
DEFAULT_CHECKS = ("inspect", "roundtrip")
#: ``module:function`` of the quality summary (issue 11, surface quality); optional.
QUALITY_HOOK = "occsurf.bridge.quality:summarize_model"
#: Modules the reader loads before its first file (its start-up is not part of any timeout).
PRELOAD = ("occsurf.bridge.exchange.step_iges", "occsurf.bridge.validation.deviation",
           "occsurf.bridge.validation.inspect")
JOB = "occsurf.bridge.audit.tasks:audit_job"


def make_item(path: str, sha256: str, checks: tuple[str, ...], samples: int, timeout: float | None) -> dict[str, Any]:
    """The task's input (JSON-safe): what the Dask worker needs to audit one file."""
    return {"path": path, "sha256": sha256, "checks": list(checks), "samples": samples, "timeout": timeout}


# ------------------------------------------------------------------------------------ Dask side
def audit_task(item: dict[str, Any]) -> dict[str, Any]:
    """Audit one file in this worker thread's reader process; runs in a Dask worker.

    Parameters
    ----------
    item : dict
        From :func:`make_item`.

    Returns
    -------
    dict
        ``status`` (``ok``/``error``/``crashed``/``timeout``), ``error``, ``signal``, ``exit_code``,
        ``seconds`` (wall clock in the reader), ``worker`` (``host:pid`` of the Dask worker),
        ``reader_pid``, and for ``ok`` the job's value (``format``, ``n_faces``, ``faces``, ...).
    """
    from .reader import reader_for_thread

    t0 = time.perf_counter()
    base = {"path": item["path"], "sha256": item["sha256"], "worker": f"{socket.gethostname()}:{os.getpid()}"}
    try:
        reader = reader_for_thread(PRELOAD)
        reply = reader.run(JOB, item, item.get("timeout"))
    except Exception as err:  # noqa: BLE001 - the reader could not start: this file's error, not the run's
        return {**base, "status": "error", "error": error_line(err), "seconds": time.perf_counter() - t0}
    out = {**base, "status": reply.status, "error": reply.error, "signal": reply.signal,
           "exit_code": reply.exit_code, "seconds": reply.seconds, "reader_pid": reader.pid}
    if reply.status == "ok":
        value = dict(reply.value)
        if value.get("error"):  # read failed cleanly (a bad file): the file's error
            out["status"], out["error"] = "error", value["error"]
        out.update({k: v for k, v in value.items() if k != "error"})
    return out


# ------------------------------------------------------------------------------------ reader side
def audit_job(item: dict[str, Any]) -> dict[str, Any]:
    """Read one file and run the checks; runs in the reader process (OCC loaded).

    Returns ``{"format", "n_faces", "faces": [face rows], "roundtrip_status", "quality_status",
    "quality": {...} or None, "error": None or str}``; an unreadable file gives ``error`` set and no
    faces (it is not an exception: the reader stays up).
    """
    from ..exchange.reading import read_model, sniff_format

    path, checks, samples = Path(item["path"]), set(item["checks"]), int(item["samples"])
    try:
        fmt = sniff_format(path)
        model = read_model(path, fmt)
    except Exception as err:  # noqa: BLE001 - the file's error
        return {"error": strip_path(error_line(err), path), "n_faces": 0, "faces": []}
    faces = _inspect_rows(model, samples) if "inspect" in checks else _bare_rows(model)
    out: dict[str, Any] = {"format": fmt, "n_faces": len(model.faces), "faces": faces, "error": None,
                           "warnings": [str(w) for w in model.warnings][:20]}
    out["roundtrip_status"] = _roundtrip(model, faces, samples) if "roundtrip" in checks else None
    out["quality_status"], out["quality"] = _quality(model) if "quality" in checks else (None, None)
    return out


def _bare_rows(model: Any) -> list[dict[str, Any]]:
    return [{"face": f.index, "name": f.name, "type": f.surface_type, "continuity": f.continuity,
             "periodic_u": bool(f.u_periodic), "periodic_v": bool(f.v_periodic), "error": f.error} for f in model.faces]


def _inspect_rows(model: Any, samples: int) -> list[dict[str, Any]]:
    from ..validation.inspect import inspect_model

    rows = []
    for r in inspect_model(model, samples=samples):
        rows.append({
            "face": r.index, "name": r.name, "type": r.surface_type,
            "degree_u": None if r.degree is None else r.degree[0], "degree_v": None if r.degree is None else r.degree[1],
            "poles_u": None if r.poles is None else r.poles[0], "poles_v": None if r.poles is None else r.poles[1],
            "rational": r.rational, "periodic_u": bool(r.periodic[0]), "periodic_v": bool(r.periodic[1]),
            "continuity": r.continuity, "max_dev": r.max_deviation, "max_d1_dev": r.max_d1_deviation,
            "max_d2_dev": r.max_d2_deviation, "max_normal_angle": r.max_normal_angle, "error": r.error,
        })
    return rows


def _roundtrip(model: Any, rows: list[dict[str, Any]], samples: int) -> str:
    """Write the converted faces with our STEP writer, read them back, compare face by face.

    Fills ``roundtrip_dev`` and ``roundtrip_exact`` into ``rows`` (matched by face index); returns
    ``'ok'``, ``'empty'`` or ``'error: ...'`` for the file.
    """
    import numpy as np

    from ..exchange.step_iges import read_step, write_step
    from ..validation.deviation import roundtrip_deviation

    faces = [f for f in model.faces if f.surface is not None]
    if not faces:
        return "empty"
    by_index = {r["face"]: r for r in rows}
    with tempfile.TemporaryDirectory(prefix="occsurf-audit-") as tmp:
        target = Path(tmp) / "roundtrip.step"
        try:
            write_step(target, [f.surface for f in faces])
            back = read_step(target)
        except Exception as err:  # noqa: BLE001 - the file's round trip failed; its faces stay
            return f"error: {error_line(err)}"
    if len(back.faces) != len(faces):
        return f"error: wrote {len(faces)} faces, read back {len(back.faces)}"
    for f, b in zip(faces, back.faces):
        row = by_index[f.index]
        if b.surface is None:
            row["roundtrip_dev"], row["roundtrip_exact"] = None, False
            continue
        d = roundtrip_deviation(f.surface, b.surface, samples=min(samples, 11))
        poles = np.asarray(f.surface.control_points).reshape(-1, f.surface.control_points.shape[-1])
        diag = float(np.linalg.norm(poles.max(axis=0) - poles.min(axis=0))) or 1.0
        row["roundtrip_dev"] = d.max_point / diag
        row["roundtrip_exact"] = bool(d.same_structure and d.max_pole == 0.0 and d.max_knot == 0.0 and d.max_weight == 0.0)
    return "ok"


def _quality(model: Any) -> tuple[str, dict[str, Any] | None]:
    module, _, name = QUALITY_HOOK.partition(":")
    try:
        summarize = getattr(importlib.import_module(module), name)
    except (ImportError, AttributeError):
        return "not available (surface quality module not installed)", None
    try:
        q = dict(summarize(model))
    except Exception as err:  # noqa: BLE001 - the file's quality failed, its other results stay
        return f"error: {error_line(err)}", None
    with contextlib.suppress(TypeError, ValueError):
        q = {"worst_g1_deg": None if q.get("worst_g1_deg") is None else float(q["worst_g1_deg"]),
             "curvature_spikes": None if q.get("curvature_spikes") is None else int(q["curvature_spikes"]),
             "flags": [str(x) for x in q.get("flags", ())]}
    return "ok", q
