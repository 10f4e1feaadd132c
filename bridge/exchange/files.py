"""File-level work of :mod:`occsurf.bridge.exchange.step_iges`, no OCC: loading and framing checks, atomic writes.

OCC must never parse a file that is not complete: ``TransferRoots`` after a failed ``ReadFile``
crashes the process, and a truncated IGES file can read as a valid-looking face with wrong poles.
The checks here run first and raise :class:`ExchangeError` naming the path.

Writes go to a temporary file beside the target, are flushed to disk, then moved over the target
with :func:`os.replace`: a failure at any point leaves no partial file and the old file intact.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from pathlib import Path

from occsurf.algorithms.errors import ExchangeError

__all__ = ["load", "check_step_text", "check_iges_text", "target", "atomic_write"]


def load(path: str | os.PathLike[str], kind: str) -> tuple[Path, bytes]:
    """``(Path, bytes)`` of a readable, non-blank file; ``kind`` ('STEP'/'IGES') for messages."""
    try:
        p = Path(os.fspath(path))
    except TypeError as err:
        raise ExchangeError(f"path: expected a str or path-like, got {type(path).__name__}") from err
    try:
        if p.is_dir():
            raise ExchangeError(f"{p}: is a directory, not a {kind} file")
        data = p.read_bytes()
    except ExchangeError:
        raise
    except FileNotFoundError as err:
        raise ExchangeError(f"{p}: no such file") from err
    except OSError as err:
        raise ExchangeError(f"{p}: cannot read: {err.strerror or err}") from err
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
        sec = line[72:73]
        idx = _IGES_SECTIONS.find(sec) if sec else -1
        # a short line, an unknown section letter, or sections out of order
        if idx < order or len(line.rstrip(b"\x00\x1a")) < 80:
            raise ExchangeError(
                f"{p}: damaged IGES file (line {number} is not an 80-column line of the S, G, D, P sections in order)"
            )
        order = idx
        found[chr(sec[0])] += 1
    if found != declared:
        got = " ".join(f"{k}{v}" for k, v in found.items())
        want = " ".join(f"{k}{v}" for k, v in declared.items())
        raise ExchangeError(
            f"{p}: truncated or damaged IGES file (Terminate section declares {want} lines, file has {got})"
        )
    if found["D"] == 0 or found["D"] % 2:
        raise ExchangeError(f"{p}: damaged IGES file ({found['D']} directory lines; expected a positive even number)")


def target(path: str | os.PathLike[str]) -> Path:
    """The path to write, checked before any work: not a directory, in an existing directory."""
    try:
        p = Path(os.fspath(path))
    except TypeError as err:
        raise ExchangeError(f"path: expected a str or path-like, got {type(path).__name__}") from err
    if p.is_dir():
        raise ExchangeError(f"{p}: is a directory; cannot write a file there")
    parent = p.parent
    if not parent.is_dir():
        why = "is not a directory" if parent.exists() else "does not exist"
        raise ExchangeError(f"{p}: cannot write: {parent} {why}")
    return p


def default_mode() -> int:
    """Permissions of a newly created file under the process umask (mkstemp makes 0o600)."""
    try:
        with open("/proc/self/status", "rb") as fh:
            for line in fh:
                if line.startswith(b"Umask:"):
                    return 0o666 & ~int(line.split()[1], 8)
    except (OSError, ValueError, IndexError):
        pass
    return 0o644


def atomic_write(p: Path, data: bytes) -> None:
    """Write ``data`` to a temporary file beside ``p``, then ``os.replace`` it over ``p``."""
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{p.name[:80]}.", suffix=".tmp", dir=p.parent)
    except OSError as err:
        raise ExchangeError(f"{p}: cannot write: {err.strerror or err}") from err
    try:
        try:
            mode = p.stat().st_mode & 0o7777
        except OSError:
            mode = default_mode()
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
            os.fchmod(fh.fileno(), mode)
        os.replace(tmp, p)
    except BaseException as err:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        if isinstance(err, OSError):
            raise ExchangeError(f"{p}: cannot write: {err.strerror or err}") from err
        raise
