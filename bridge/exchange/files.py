"""File-level work of :mod:`occsurf.bridge.exchange.step_iges`, no OCC: loading and framing checks, atomic writes.

OCC must never parse a file that is not complete: ``TransferRoots`` after a failed ``ReadFile``
crashes the process, and a truncated IGES file can read as a valid-looking face with wrong poles.
The checks here run first and raise :class:`ExchangeError` naming the path.

Writes go through the one atomic-write helper, :func:`occsurf.algorithms._files.atomic_write` (re-exported
here with :func:`write_figure` and :func:`write_text` for pictures and reports): a temporary file beside
the target, synced, then moved over it with :func:`os.replace`. A failure at any point leaves no partial
file and the old file intact; devices, FIFOs and read-only files are refused.
"""

from __future__ import annotations

import errno
import io
import os
import stat
from pathlib import Path
from typing import Any

from occsurf.algorithms._files import (
    TEMP_SUFFIX,
    as_path,
    atomic_write,
    atomic_write_many,
    check_target,
    clean_stale_temps,
    default_mode,
    file_kind,
    file_lock,
)
from occsurf.algorithms.errors import ExchangeError

__all__ = ["load", "input_problem", "check_step_text", "check_iges_text", "target", "atomic_write", "atomic_write_many",
           "check_target", "clean_stale_temps", "file_lock", "default_mode", "write_figure", "write_text",
           "MAX_FILE_BYTES", "TEMP_SUFFIX"]

#: Largest file :func:`load` reads (bytes): a bigger one is refused before it is read into memory.
MAX_FILE_BYTES: int = 4 << 30


def input_problem(path: str | bytes | os.PathLike[Any], kind: str = "STEP or IGES") -> str | None:
    """Why ``path`` cannot be read as a ``kind`` file, in a few words, or ``None`` when it can be tried.

    The one check every command runs on a file it is given before anything opens it: a missing
    file, a dangling symlink or a loop of symlinks, a folder, a device (a symlink to ``/dev/zero``
    reads forever), FIFO or socket (opening a FIFO waits for a writer), a file larger than
    :data:`MAX_FILE_BYTES`. Nothing is opened; ``os.stat`` only.
    """
    p = as_path(path)
    try:
        st = os.stat(p)
    except FileNotFoundError:
        if os.path.islink(p):
            return f"dangling symbolic link (to {os.readlink(p)})"
        return "no such file"
    except OSError as err:
        if err.errno == errno.ELOOP:
            return "a loop of symbolic links"
        return f"cannot read: {err.strerror or err}"
    if stat.S_ISDIR(st.st_mode):
        return f"is a directory, not a {kind} file"
    if not stat.S_ISREG(st.st_mode):
        return f"is {file_kind(st.st_mode)}, not a {kind} file; not read"
    if st.st_size > MAX_FILE_BYTES:
        return f"{st.st_size} bytes, more than the {MAX_FILE_BYTES} a {kind} file may have here"
    return None


def load(path: str | os.PathLike[str], kind: str) -> tuple[Path, bytes]:
    """``(Path, bytes)`` of a readable, non-blank regular file; ``kind`` ('STEP'/'IGES') for messages.

    The file is checked before it is read: a device (a symlink to ``/dev/zero``), FIFO or socket, a
    dangling symlink or a loop of symlinks, and a file larger than :data:`MAX_FILE_BYTES` are refused.
    """
    p = as_path(path)
    why = input_problem(p, kind)
    if why is not None:
        raise ExchangeError(f"{p}: {why}")
    try:
        with open(p, "rb") as fh:
            data = fh.read(MAX_FILE_BYTES + 1)  # a file that grows while read cannot exceed the limit
    except OSError as err:
        raise ExchangeError(f"{p}: cannot read: {err.strerror or err}") from err
    if len(data) > MAX_FILE_BYTES:
        raise ExchangeError(f"{p}: more than {MAX_FILE_BYTES} bytes (it grew while read); not read")
    if not data.strip(b" \t\r\n\x00\x1a"):
        raise ExchangeError(f"{p}: empty file" if not data else f"{p}: file holds only blank space")
    return p, data


def check_step_text(p: Path, data: bytes) -> None:
    """ISO 10303-21 framing: header at the start, terminator at the end (no truncation)."""
    head = data.lstrip(b"\xef\xbb\xbf \t\r\n")
    if not head.startswith(b"ISO-10303-21"):
        raise ExchangeError(f"{p}: not a STEP file (does not start with 'ISO-10303-21;')")
    if not data.rstrip(b" \t\r\n\x00\x1a").endswith(b"END-ISO-10303-21;"):
        raise ExchangeError(f"{p}: truncated STEP file (no 'END-ISO-10303-21;' at the end)")
    if b"DATA;" not in data or b"ENDSEC;" not in data:
        raise ExchangeError(f"{p}: damaged STEP file (no DATA section)")


_IGES_SECTIONS = b"SGDP"


def check_iges_text(p: Path, data: bytes) -> None:
    """Fixed-format IGES (80 columns, section letter in column 73) ending in a Terminate line
    whose counts match the sections: a truncated file fails here, before OCC sees it."""
    lines = data.splitlines()
    while lines and not lines[-1].strip(b" \t\x00\x1a"):
        lines.pop()
    first = lines[0]
    letter = first[72:73]
    if letter in (b"B", b"C"):
        raise ExchangeError(f"{p}: binary or compressed IGES is not supported (flag {letter.decode()!r} in column 73)")
    if letter != b"S":
        raise ExchangeError(f"{p}: not an IGES file (column 73 of the first line is not 'S')")
    last = lines[-1]
    if last[72:73] != b"T":
        raise ExchangeError(f"{p}: truncated IGES file (no Terminate section at the end)")
    if not last[73:80].strip().isdigit() or len(last.rstrip()) < 80:
        raise ExchangeError(f"{p}: truncated IGES file (the Terminate line is cut short)")
    declared: dict[str, int] = {}
    try:
        for k, sec in enumerate(_IGES_SECTIONS):
            fld = last[8 * k : 8 * k + 8]
            if fld[:1] != bytes([sec]):
                raise ValueError
            declared[chr(sec)] = int(fld[1:])
    except ValueError:
        raise ExchangeError(f"{p}: damaged IGES file (unreadable Terminate section)") from None
    found = dict.fromkeys("SGDP", 0)
    order = 0
    for number, line in enumerate(lines[:-1], start=1):
        tag = line[72:73]
        idx = _IGES_SECTIONS.find(tag) if tag else -1
        # a short line, an unknown section letter, or sections out of order
        if idx < order or len(line.rstrip(b"\x00\x1a")) < 80:
            raise ExchangeError(
                f"{p}: damaged IGES file (line {number} is not an 80-column line of the S, G, D, P sections in order)"
            )
        order = idx
        found[chr(tag[0])] += 1
    if found != declared:
        got = " ".join(f"{k}{v}" for k, v in found.items())
        want = " ".join(f"{k}{v}" for k, v in declared.items())
        raise ExchangeError(
            f"{p}: truncated or damaged IGES file (Terminate section declares {want} lines, file has {got})"
        )
    if found["D"] == 0 or found["D"] % 2:
        raise ExchangeError(f"{p}: damaged IGES file ({found['D']} directory lines; expected a positive even number)")


def target(path: str | os.PathLike[str], *, replace_readonly: bool = False) -> Path:
    """The path to write, checked before any work (:func:`occsurf.algorithms._files.check_target`): not a
    directory, device, FIFO or socket, not read-only unless ``replace_readonly``, in an existing folder."""
    p = as_path(path)
    check_target(p, replace_readonly=replace_readonly)
    return p


def write_figure(fig: Any, path: str | os.PathLike[str], **savefig_kwargs: Any) -> Path:
    """Save a matplotlib figure atomically (format from the suffix, PNG by default); returns ``path``.

    The picture is rendered in memory first: a full disk or a killed process never leaves a truncated
    or empty picture in place of the old one.
    """
    p = target(path)
    buffer = io.BytesIO()
    fmt = savefig_kwargs.pop("format", None) or (p.suffix[1:].lower() or "png")
    fig.savefig(buffer, format=fmt, **savefig_kwargs)
    atomic_write(p, buffer.getvalue())
    return p


def write_text(path: str | os.PathLike[str], text: str, *, encoding: str = "utf-8") -> Path:
    """Write a text file atomically (UTF-8 by default); returns ``path``."""
    p = target(path)
    atomic_write(p, text.encode(encoding))
    return p
