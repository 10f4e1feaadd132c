"""The corpus of an audit: PATH arguments expanded to STEP/IGES files, each with its SHA-256.

A PATH is a file, a folder (searched recursively), a glob pattern (``**`` recursive), or a text
file listing paths (one per line; blank lines and lines starting with ``#`` ignored; relative
paths are taken from the list file's folder). A file is STEP or IGES by its suffix, else by its
first bytes (:func:`occsurf.bridge.exchange.reading.sniff_format`'s rule); any other file given
directly is read as a list. The content hash keys the results: a renamed file is recognised, a
changed one is new. Only the standard library is imported here; sniffing a file imports
:mod:`occsurf.algorithms` (NumPy, SciPy) for its exception classes, as :func:`sniff_format` does.
"""

from __future__ import annotations

import glob
import hashlib
import os
from collections.abc import Iterable, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

from ..exchange.files import input_problem
from ..exchange.reading import SUFFIXES, sniff_format

__all__ = ["CorpusError", "Entry", "expand_paths", "sniff_cad", "sha256_of", "hash_entries"]

_GLOB_CHARS = set("*?[")


class CorpusError(ValueError):
    """A PATH argument that names nothing usable (missing, unreadable, empty corpus)."""


@dataclass
class Entry:
    """One input file: ``path`` (absolute), ``sha256`` (``None`` until hashed or if unreadable),
    ``size`` in bytes, ``error`` (why it cannot be read: it is then recorded as ``error``)."""

    path: str
    sha256: str | None = None
    size: int | None = None
    error: str | None = None


def sniff_cad(path: Path) -> str | None:
    """``'step'``, ``'iges'`` or ``None``: by suffix, else by the file's first 200 bytes
    (:func:`~occsurf.bridge.exchange.reading.sniff_format`, with ``None`` for unreadable or other files)."""
    try:
        return sniff_format(path)
    except OSError:  # ExchangeError: unreadable, or neither STEP nor IGES
        return None


def _walk(folder: Path) -> Iterable[Path]:
    for root, dirs, files in os.walk(folder, followlinks=False):
        dirs.sort()
        for name in sorted(files):
            if os.path.splitext(name)[1].lower() in SUFFIXES:
                yield Path(root) / name


def _list_file(path: Path) -> list[str]:
    try:
        text = path.read_text(encoding="utf-8", errors="replace")
    except OSError as err:
        raise CorpusError(f"{path}: cannot read: {err.strerror or err}") from err
    out = []
    for line in text.splitlines():
        line = line.strip()
        if line and not line.startswith("#"):
            p = Path(line).expanduser()
            out.append(str(p if p.is_absolute() else path.parent / p))
    return out


def _expand_one(arg: str, depth: int, out: list[Entry]) -> None:
    path = Path(arg).expanduser()
    if path.is_dir():
        out.extend(Entry(str(p.absolute())) for p in _walk(path))
    elif path.is_file():
        if sniff_cad(path) is not None:
            out.append(Entry(str(path.absolute())))
        elif depth == 0:  # a list of paths; entries that are missing become error rows, not a refusal
            for line in _list_file(path):
                p = Path(line)
                if p.exists() or any(c in line for c in _GLOB_CHARS):
                    _expand_one(line, depth + 1, out)
                else:
                    out.append(Entry(str(p.absolute()), error="no such file or directory (listed in "
                                     f"{path})"))
        else:
            out.append(Entry(str(path.absolute()), error="not a STEP or IGES file (unrecognised header)"))
    elif os.path.lexists(path) and not (_GLOB_CHARS & set(arg)):  # a device, FIFO, socket, a link to nothing
        out.append(Entry(str(path.absolute()), error=input_problem(path) or "not a regular file; not read"))
    elif _GLOB_CHARS & set(arg):
        for match in sorted(glob.glob(os.path.expanduser(arg), recursive=True)):
            m = Path(match)
            if m.is_dir():
                out.extend(Entry(str(p.absolute())) for p in _walk(m))
            elif m.is_file() and sniff_cad(m) is not None:
                out.append(Entry(str(m.absolute())))
    elif depth == 0:
        raise CorpusError(f"{arg}: no such file or directory")
    else:
        out.append(Entry(str(path.absolute()), error="no such file or directory"))


def expand_paths(args: Sequence[str]) -> list[Entry]:
    """Every STEP/IGES file named by ``args`` (files, folders, globs, list files), each once.

    Raises
    ------
    CorpusError
        An argument names nothing (no such path, no glob match is allowed: it gives no files), a
        list file cannot be read, or the corpus is empty.
    """
    found: list[Entry] = []
    for arg in args:
        _expand_one(arg, 0, found)
    seen: set[str] = set()
    unique = []
    for e in found:
        if e.path not in seen:
            seen.add(e.path)
            unique.append(e)
    if not unique:
        raise CorpusError(f"no STEP/IGES files ({', '.join(SUFFIXES)}) found in {' '.join(args) or 'no PATH'}")
    return unique


def sha256_of(path: str) -> tuple[str, int]:
    """``(hex digest, size)`` of a file, read in 1 MiB blocks."""
    h = hashlib.sha256()
    size = 0
    with open(path, "rb") as fh:
        while block := fh.read(1 << 20):
            h.update(block)
            size += len(block)
    return h.hexdigest(), size


def _hash_one(e: Entry) -> Entry:
    if e.error is None:
        # Before opening: a device (a link to /dev/zero) or a FIFO would read or wait forever, here,
        # before any --timeout applies; a regular file is at most MAX_FILE_BYTES.
        e.error = input_problem(e.path)
    if e.error is None:
        try:
            e.sha256, e.size = sha256_of(e.path)
        except OSError as err:
            e.error = f"cannot read: {err.strerror or err}"
    return e


def hash_entries(entries: list[Entry], threads: int = 8) -> list[Entry]:
    """Fill ``sha256`` and ``size`` in place (threads: hashlib releases the GIL); unreadable files get ``error``."""
    with ThreadPoolExecutor(max_workers=max(1, threads)) as pool:
        list(pool.map(_hash_one, entries, chunksize=64))
    return entries
