"""What the commands of ``occsurf`` share: exit codes, file arguments, reading a model, tables, messages.

Only the standard library is imported at module level: the command-line process never loads NumPy
or OCC itself (``occsurf --help`` stays instant); the reading helpers import them when called,
normally inside a worker process (:mod:`occsurf.bridge.isolation`).
"""

from __future__ import annotations

import argparse
import contextlib
import math
import os
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from ..exchange.step_iges import ImportedModel
    from ..isolation import Outcome

__all__ = [
    "EXIT_OK",
    "EXIT_ERROR",
    "STEP_SUFFIXES",
    "IGES_SUFFIXES",
    "SUFFIXES",
    "SAMPLES_DIR",
    "error",
    "strip_path",
    "worker_failure",
    "find_samples_dir",
    "files_in",
    "expand",
    "sniff_format",
    "read_model",
    "format_rows",
    "fmt_dev",
    "fmt_pair",
    "fmt_periodic",
    "fmt_rational",
    "fmt_deg",
    "fmt_s",
    "timeout_arg",
]

EXIT_OK = 0
#: Some file could not be read, or a command-line argument is wrong (argparse uses 2 as well).
EXIT_ERROR = 2

STEP_SUFFIXES = (".step", ".stp")
IGES_SUFFIXES = (".iges", ".igs")
SUFFIXES = STEP_SUFFIXES + IGES_SUFFIXES
SAMPLES_DIR = "step_samples"


# ---------------------------------------------------------------------------------------- messages
def error(message: str) -> None:
    """Print ``occsurf: MESSAGE`` on stderr: the one-line form of every error a command reports."""
    print(f"occsurf: {message}", file=sys.stderr, flush=True)


def strip_path(message: str, path: Path) -> str:
    """Drop a leading ``PATH: `` from a message: the CLI prints the path itself."""
    candidates = {str(path), os.fspath(path)}
    with contextlib.suppress(OSError):
        candidates.add(str(path.resolve()))
        candidates.add(str(path.absolute()))
    for c in sorted(candidates, key=len, reverse=True):
        if message.startswith(c + ": "):
            return message[len(c) + 2 :]
    return message


def worker_failure(outcome: Outcome, timeout: float | None, *, task: str, process: str) -> str:
    """Why an item run by :func:`occsurf.bridge.isolation.run_jobs` gave no result, in one line.

    ``task`` says what the job does (``'reading this file'``), ``process`` names the worker
    (``'reader'``). ``outcome`` is neither ``ok`` nor ``error`` (those carry their own result).
    """
    from ..isolation import CRASHED, TIMEOUT

    if outcome.status == TIMEOUT:
        return f"{task} took longer than {timeout:g} s; the {process} process was stopped (--timeout)"
    if outcome.status == CRASHED:
        return f"the {process} process crashed while {task} ({outcome.exit_reason}; a fault inside OpenCascade)"
    if outcome.exit_code is None:
        return f"cannot start the {process} process: {outcome.error}"
    # The worker died outside any item (e.g. cannot import OCC).
    return f"the {process} process failed ({outcome.exit_reason})" + (f": {outcome.error}" if outcome.error else "")


# ---------------------------------------------------------------------------------------- files
def find_samples_dir(cwd: Path | None = None) -> Path | None:
    """The ``step_samples/`` folder: below the current directory first, then the one shipped in the
    package (``occsurf/step_samples`` in a wheel, the repository's folder in a source checkout)."""
    import occsurf

    here = Path.cwd() if cwd is None else Path(cwd)
    shipped = [Path(p) / SAMPLES_DIR for p in occsurf.__path__]
    for candidate in (here / SAMPLES_DIR, *shipped):
        if candidate.is_dir():
            return candidate
    return None


def files_in(folder: Path) -> list[Path]:
    """The STEP and IGES files of a folder (by suffix), sorted."""
    return sorted(p for p in folder.iterdir() if p.is_file() and p.suffix.lower() in SUFFIXES)


def expand(args: Sequence[str]) -> list[tuple[str, Path | None, str | None]]:
    """``(shown path, path or None, error or None)`` for every argument, folders expanded."""
    out: list[tuple[str, Path | None, str | None]] = []
    for arg in args:
        path = Path(arg)
        try:
            if path.is_dir():
                files = files_in(path)
                if not files:
                    out.append((arg, None, f"no STEP/IGES files ({', '.join(SUFFIXES)}) in this folder"))
                out.extend((str(f), f, None) for f in files)
            elif path.exists():
                out.append((arg, path, None))
            else:
                out.append((arg, None, "no such file or directory"))
        except OSError as err:  # unreadable folder, name too long, ...
            out.append((arg, None, f"cannot read: {err.strerror or err}"))
    return out


def sniff_format(path: Path) -> str:
    """``'step'`` or ``'iges'`` from the suffix, else from the start of the file.

    Raises
    ------
    ExchangeError
        The file cannot be read, or is neither.
    """
    from occsurf.algorithms.errors import ExchangeError

    suffix = path.suffix.lower()
    if suffix in STEP_SUFFIXES:
        return "step"
    if suffix in IGES_SUFFIXES:
        return "iges"
    try:
        with open(path, "rb") as fh:
            head = fh.read(200)
    except OSError as err:
        raise ExchangeError(f"cannot read: {err.strerror or err}") from err
    if head.lstrip(b"\xef\xbb\xbf \t\r\n").upper().startswith(b"ISO-10303-21"):
        return "step"
    if head.split(b"\n", 1)[0][72:73] == b"S":  # IGES start section: 80 columns, 'S' in column 73
        return "iges"
    raise ExchangeError(f"not a STEP or IGES file (suffix {suffix or 'none'!r}, unrecognised header)")


def read_model(path: Path, fmt: str | None = None) -> ImportedModel:
    """Read a STEP or IGES file (``fmt`` from :func:`sniff_format` unless given).

    ``read_step``/``read_iges`` are looked up on their module at call time.
    """
    from ..exchange import step_iges as exchange

    fmt = sniff_format(path) if fmt is None else fmt
    return (exchange.read_step if fmt == "step" else exchange.read_iges)(path)


# ---------------------------------------------------------------------------------------- tables
def format_rows(rows: Sequence[Sequence[str]], right: frozenset[int] | set[int] = frozenset()) -> list[str]:
    """Rows of cells as aligned lines: columns as wide as their widest cell, two spaces apart,
    indented by two, left-aligned but for the columns in ``right``; trailing blanks removed."""
    widths = [max(len(r[i]) for r in rows) for i in range(len(rows[0]))]
    lines = []
    for r in rows:
        cells = [c.rjust(w) if i in right else c.ljust(w) for i, (c, w) in enumerate(zip(r, widths))]
        lines.append(("  " + "  ".join(cells)).rstrip())
    return lines


def fmt_dev(x: float | None) -> str:
    return "-" if x is None else f"{x:.1e}"


def fmt_pair(pair: Sequence[Any] | None) -> str:
    return "-" if pair is None else f"{pair[0]}x{pair[1]}"


def fmt_periodic(periodic: Sequence[bool]) -> str:
    return ",".join(d for d, flag in zip("uv", periodic) if flag) or "-"


def fmt_rational(r: bool | None) -> str:
    return "-" if r is None else ("yes" if r else "no")


def fmt_deg(x: float | None) -> str:
    return "-" if x is None else f"{x:.2g} deg"


def fmt_s(x: float | None) -> str:
    return "-" if x is None else f"{x:.2f} s"


# ---------------------------------------------------------------------------------------- arguments
def timeout_arg(text: str) -> float:
    """``--timeout``: a positive, finite number of seconds."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number of seconds, got {text!r}") from None
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"expected a positive number of seconds, got {text!r}")
    return value
