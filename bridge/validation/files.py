"""Inspect STEP/IGES files: per file, what :func:`occsurf.bridge.validation.inspect.inspect_model` reports.

The per-file work of ``occsurf inspect`` (the command line parses its arguments, runs :func:`inspect_job`
through :func:`occsurf.bridge.isolation.run_jobs` and prints the reports):

* :class:`FileReport` — one file: its format, unit, warnings, one
  :class:`~occsurf.bridge.validation.inspect.FaceReport` per face, or the ``error`` that kept it unread;
  to and from JSON (the worker process hands it over as JSON);
* :func:`inspect_job` — the job a reader process runs per file (:data:`INSPECT_JOB`, with the modules
  :data:`PRELOAD` loaded before the first file); never raises;
* :func:`inspect_files` — the same for files and folders, in this process.

A file is found and read by :mod:`occsurf.bridge.exchange.reading`'s rule. Only the standard library is
imported at module level (the command line reads :class:`FileReport` back from its worker without loading
NumPy or OCC).
"""

from __future__ import annotations

import contextlib
import json
import time
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..exchange.reading import expand, read_model, sniff_format
from ..messages import error_line, strip_path
from .inspect import DEFAULT_SAMPLES, FaceReport

__all__ = ["FileReport", "inspect_files", "inspect_job", "inspect_path", "INSPECT_JOB", "PRELOAD"]

#: The job a reader process runs per file (``"module:function"`` for :func:`~occsurf.bridge.isolation.run_jobs`).
INSPECT_JOB = "occsurf.bridge.validation.files:inspect_job"
#: What the reader process loads before its first file (so a file's time excludes loading OCC).
PRELOAD = ("occsurf.bridge.exchange.step_iges", "occsurf.bridge.validation.deviation")


@dataclass
class FileReport:
    """One file (or one argument that is not a readable file)."""

    path: str
    format: str | None = None
    error: str | None = None
    faces: list[FaceReport] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    seconds: float = 0.0
    #: The length unit the file declares (``ImportedModel.unit``: 'mm', 'm', 'inch'...); None if unread.
    unit: str | None = None

    @property
    def n_free_form(self) -> int:
        return sum(f.free_form for f in self.faces)

    @property
    def worst_deviation(self) -> float | None:
        devs = [f.max_deviation for f in self.faces if f.max_deviation is not None]
        return max(devs) if devs else None

    def to_json(self) -> dict[str, Any]:
        return {
            "path": self.path,
            "format": self.format,
            "unit": self.unit,
            "error": self.error,
            "n_faces": len(self.faces),
            "n_free_form": self.n_free_form,
            "worst_deviation": self.worst_deviation,
            "seconds": round(self.seconds, 4),
            "warnings": list(self.warnings),
            "faces": [f.to_json() for f in self.faces],
        }

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> FileReport:
        faces = [FaceReport.from_json(face) for face in data.get("faces", ())]
        return cls(path=data["path"], format=data.get("format"), error=data.get("error"), faces=faces,
                   warnings=list(data.get("warnings", ())), seconds=float(data.get("seconds", 0.0)),
                   unit=data.get("unit"))


def inspect_path(shown: str, path: Path, samples: int) -> FileReport:
    """Read one file and inspect its faces (``shown``: the path as reported); never raises for a bad
    file (``error`` is set, without the path)."""
    import numpy as np

    from ..isolation import quiet_native_stdout

    report = FileReport(path=shown)
    with contextlib.suppress(Exception):  # load OCC outside the timing (a failure shows up below)
        from ..exchange import step_iges  # noqa: F401
        from . import deviation  # noqa: F401
    t0 = time.perf_counter()
    try:
        with warnings.catch_warnings(), np.errstate(all="ignore"), quiet_native_stdout():
            warnings.simplefilter("ignore")
            from .inspect import inspect_model

            report.format = sniff_format(path)
            model = read_model(path, report.format)
            report.warnings = [error_line(w) for w in model.warnings]
            report.unit = model.unit
            report.faces = inspect_model(model, samples)
    except Exception as err:  # noqa: BLE001 - report, never crash, never a traceback
        report.error = strip_path(error_line(err), path)
    report.seconds = time.perf_counter() - t0
    return report


def inspect_job(item: dict[str, Any]) -> dict[str, Any]:
    """The reader process's job: ``{"shown", "path", "samples"}`` -> the file's report as JSON.

    Never raises: a failure, even of the report's serialisation, is the file's ``error``.
    """
    shown = item["shown"]
    try:
        payload = inspect_path(shown, Path(item["path"]), int(item["samples"])).to_json()
        json.dumps(payload, allow_nan=False)  # fail here, per file, rather than in the parent
    except Exception as err:  # noqa: BLE001
        payload = FileReport(path=shown, error=error_line(err)).to_json()
    return payload


def inspect_files(args: Sequence[str], samples: int = DEFAULT_SAMPLES) -> list[FileReport]:
    """Inspect every file named in ``args`` (folders expanded), in this process.

    Never raises for a bad file: its report has ``error`` set. (A segmentation fault inside OCC
    still ends the process; the command line reads files in a worker process instead.)

    Parameters
    ----------
    args : sequence of str
        Files and folders (a folder stands for its STEP/IGES files, sorted).
    samples : int
        Grid size of the deviation check.

    Returns
    -------
    list of FileReport
    """
    return [inspect_path(shown, path, samples) if path is not None else FileReport(path=shown, error=err)
            for shown, path, err in expand(args)]
