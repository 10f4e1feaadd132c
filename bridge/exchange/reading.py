"""STEP and IGES inputs: which files a path names, which format a file is in, and reading it.

The one rule every reader of occsurf follows (the command line's commands, :func:`occsurf.bridge.exchange.
convert.convert`, the audit's corpus, fitting to a face of a CAD file):

* a file is STEP or IGES by its suffix (:data:`STEP_SUFFIXES`, :data:`IGES_SUFFIXES`, any case);
* a file with another suffix by its first bytes: STEP starts with ``ISO-10303-21`` (after a byte-order
  mark or blank space, any case), IGES has ``S`` in column 73 of its first line (the start section of
  the fixed 80-column format); anything else is refused (:func:`sniff_format`), naming the suffix;
* a folder stands for its STEP/IGES files, by suffix, sorted (:func:`folder_entries`, :func:`expand`).

The suffix is trusted: content that contradicts it is refused by the reader's framing checks
(:func:`occsurf.bridge.exchange.files.check_step_text`, ``check_iges_text``: an IGES file named
``.step`` is "not a STEP file"), before OCC parses anything. A file is written as STEP or IGES by its
target's suffix (:func:`target_format`, which also takes ``.p21`` for STEP: a name, not content,
decides a target).

Only the standard library is imported at module level: the command-line process lists files and builds
its parser with these names without loading NumPy or OCC; :func:`read_model` loads them when called.
"""

from __future__ import annotations

import errno
import os
import stat
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from .step_iges import ImportedModel

__all__ = [
    "STEP_SUFFIXES",
    "IGES_SUFFIXES",
    "SUFFIXES",
    "TARGET_SUFFIXES",
    "shown_path",
    "folder_entries",
    "files_in",
    "expand",
    "sniff_format",
    "target_format",
    "read_model",
    "strict_refusal",
]

#: Suffixes read as STEP (ISO 10303-21) without looking at the content (any case).
STEP_SUFFIXES: tuple[str, ...] = (".step", ".stp")
#: Suffixes read as IGES without looking at the content (any case).
IGES_SUFFIXES: tuple[str, ...] = (".iges", ".igs")
#: Every suffix of a STEP or IGES input: what a folder is searched for.
SUFFIXES: tuple[str, ...] = STEP_SUFFIXES + IGES_SUFFIXES
#: Suffixes of a file written as each format (:func:`target_format`): ``.p21`` names a STEP target too.
TARGET_SUFFIXES: dict[str, tuple[str, ...]] = {"step": STEP_SUFFIXES + (".p21",), "iges": IGES_SUFFIXES}

#: How many bytes :func:`sniff_format` reads from a file without a known suffix.
_HEAD_BYTES = 200


def shown_path(path: str | os.PathLike[str]) -> str:
    """A path as it can be printed: bytes that are not UTF-8 shown as ``\\xff`` escapes."""
    return os.fsencode(path).decode("utf-8", "backslashreplace")


def files_in(folder: Path) -> list[Path]:
    """The STEP and IGES files of a folder (by suffix), sorted; links that lead nowhere are left out
    (:func:`folder_entries` reports them)."""
    return [p for p, err in folder_entries(folder) if err is None]


def folder_entries(folder: Path) -> list[tuple[Path, str | None]]:
    """``(path, None)`` for every STEP/IGES file of a folder (by suffix), sorted, and ``(path, reason)``
    for every entry with such a suffix that cannot be read as a file: a dangling symlink, a loop of
    symlinks, a device, FIFO or socket (a symlink to ``/dev/zero`` would read forever)."""
    out: list[tuple[Path, str | None]] = []
    for p in sorted(folder.iterdir()):
        if p.suffix.lower() not in SUFFIXES:
            continue
        try:
            st = os.stat(p)
        except FileNotFoundError:
            target = os.readlink(p) if p.is_symlink() else "?"
            out.append((p, f"dangling symbolic link (to {shown_path(target)})"))
            continue
        except OSError as err:
            why = "a loop of symbolic links" if err.errno == errno.ELOOP else f"cannot read: {err.strerror or err}"
            out.append((p, why))
            continue
        if stat.S_ISDIR(st.st_mode):
            continue  # a folder named like a file is not one
        if not stat.S_ISREG(st.st_mode):
            out.append((p, "not a regular file (a device, FIFO or socket); not read"))
            continue
        out.append((p, None))
    return out


def expand(args: Sequence[str]) -> list[tuple[str, Path | None, str | None]]:
    """``(shown path, path or None, error or None)`` for every argument, folders expanded.

    The shown path is printable (:func:`shown_path`); the path is the real one. Links in a folder
    that lead nowhere are reported as errors, not skipped.
    """
    out: list[tuple[str, Path | None, str | None]] = []
    for arg in args:
        path = Path(arg)
        shown = shown_path(arg)
        try:
            if path.is_dir():
                entries = folder_entries(path)
                if not entries:
                    out.append((shown, None, f"no STEP/IGES files ({', '.join(SUFFIXES)}) in this folder"))
                out.extend((shown_path(f), f if err is None else None, err) for f, err in entries)
                continue
            os.stat(path)
            out.append((shown, path, None))
        except FileNotFoundError:
            why = "dangling symbolic link" if path.is_symlink() else "no such file or directory"
            out.append((shown, None, why))
        except OSError as err:  # unreadable folder, name too long, a loop of links...
            why = "a loop of symbolic links" if err.errno == errno.ELOOP else f"cannot read: {err.strerror or err}"
            out.append((shown, None, why))
    return out


def sniff_format(path: str | os.PathLike[str]) -> str:
    """``'step'`` or ``'iges'`` from the suffix, else from the start of the file (the module's rule).

    Parameters
    ----------
    path : str or path-like

    Returns
    -------
    str
        ``'step'`` or ``'iges'``.

    Raises
    ------
    ExchangeError
        The suffix is neither STEP's nor IGES's and the file cannot be read, or its first bytes are
        neither a STEP header nor an IGES start line. The message does not name the path (callers
        print it beside the message).
    """
    from occsurf.algorithms.errors import ExchangeError

    suffix = Path(os.fsdecode(path)).suffix.lower()
    if suffix in STEP_SUFFIXES:
        return "step"
    if suffix in IGES_SUFFIXES:
        return "iges"
    try:
        with open(path, "rb") as fh:
            head = fh.read(_HEAD_BYTES)
    except OSError as err:
        raise ExchangeError(f"cannot read: {err.strerror or err}") from err
    if head.lstrip(b"\xef\xbb\xbf \t\r\n").upper().startswith(b"ISO-10303-21"):
        return "step"
    if head.split(b"\n", 1)[0][72:73] == b"S":  # IGES start section: 80 columns, 'S' in column 73
        return "iges"
    raise ExchangeError(f"not a STEP or IGES file (suffix {suffix or 'none'!r}, unrecognised header)")


def target_format(path: str | os.PathLike[str]) -> str:
    """``'step'`` or ``'iges'``: the format a file written to ``path`` gets, from its suffix
    (:data:`TARGET_SUFFIXES`).

    Raises
    ------
    InvalidGeometryError
        Another suffix (the message lists the ones accepted).
    """
    from occsurf.algorithms.errors import InvalidGeometryError

    suffix = Path(os.fsdecode(path)).suffix.lower()
    for fmt, suffixes in TARGET_SUFFIXES.items():
        if suffix in suffixes:
            return fmt
    accepted = ", ".join(s for suffixes in TARGET_SUFFIXES.values() for s in suffixes)
    raise InvalidGeometryError(f"target: expected a file name ending in {accepted}, got {os.fspath(path)!r}")


def read_model(path: str | os.PathLike[str], fmt: str | None = None, *, strict: bool = False) -> ImportedModel:
    """Read a STEP or IGES file in this process (``fmt`` from :func:`sniff_format` unless given).

    ``read_step``/``read_iges`` are looked up on :mod:`occsurf.bridge.exchange.step_iges` at call time.
    With ``strict`` (a command's ``--strict``) a file read around damage (``ImportedModel.warnings``,
    see :mod:`occsurf.bridge.exchange.checks`) is refused.

    Parameters
    ----------
    path : str or path-like
    fmt : {'step', 'iges'}, optional
    strict : bool, default False

    Returns
    -------
    ImportedModel

    Raises
    ------
    ExchangeError
        The file cannot be read; with ``strict``, it has warnings (:func:`strict_refusal`, after the path).
    """
    from . import step_iges

    fmt = sniff_format(path) if fmt is None else fmt
    model = (step_iges.read_step if fmt == "step" else step_iges.read_iges)(path)
    if strict and model.warnings:
        from occsurf.algorithms.errors import ExchangeError

        raise ExchangeError(f"{path}: {strict_refusal(model.warnings)}")
    return model


def strict_refusal(warnings: Sequence[str]) -> str:
    """Why ``--strict`` refuses a file: its warning count and the first warning, one line."""
    first = " ".join(str(warnings[0]).split())
    more = f" (and {len(warnings) - 1} more)" if len(warnings) > 1 else ""
    return f"refused by --strict: {len(warnings)} warning{'s' if len(warnings) > 1 else ''}: {first}{more}"
