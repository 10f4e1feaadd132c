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
import threading
import time
from collections.abc import Iterable, Sequence
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
    ``size`` in bytes, ``error`` (why it cannot be read: it is then recorded as ``error``, or as
    ``timeout`` when ``timed_out``: hashing it took longer than the audit's ``--timeout``)."""

    path: str
    sha256: str | None = None
    size: int | None = None
    error: str | None = None
    timed_out: bool = False


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


def sha256_of(path: str, deadline: float | None = None) -> tuple[str, int]:
    """``(hex digest, size)`` of a file, read in 1 MiB blocks.

    Raises
    ------
    TimeoutError
        ``time.monotonic()`` passed ``deadline`` between two blocks (a slow disk or network share).
    """
    h = hashlib.sha256()
    size = 0
    with open(path, "rb") as fh:
        while block := fh.read(1 << 20):
            h.update(block)
            size += len(block)
            if deadline is not None and time.monotonic() > deadline:
                raise TimeoutError
    return h.hexdigest(), size


def _hash_one(e: Entry, timeout: float | None = None) -> Entry:
    if e.error is None:
        # Before opening: a device (a link to /dev/zero) or a FIFO would read or wait forever, here;
        # a regular file is at most MAX_FILE_BYTES.
        e.error = input_problem(e.path)
    if e.error is None:
        try:
            e.sha256, e.size = sha256_of(e.path, None if timeout is None else time.monotonic() + timeout)
        except TimeoutError:
            _timed_out(e, timeout)
        except OSError as err:
            e.error = f"cannot read: {err.strerror or err}"
    return e


def _timed_out(e: Entry, timeout: float | None) -> None:
    e.sha256 = e.size = None
    e.timed_out = True
    e.error = f"reading it to hash its contents took more than {timeout:g} s (--timeout); not audited"


def hash_entries(entries: list[Entry], threads: int = 8, timeout: float | None = None) -> list[Entry]:
    """Fill ``sha256`` and ``size`` in place (threads: hashlib releases the GIL); unreadable files get ``error``.

    Each file is hashed under ``timeout`` seconds (``None``: no limit), as the audit's ``--timeout``
    bounds its reading. A read that keeps returning blocks is stopped between two of them; one that
    blocks inside the system call (a hung network share, a FUSE file system) cannot be: its file is
    recorded ``timeout`` at its deadline all the same, a fresh thread takes its place, and the stuck
    thread (a daemon) is left behind without holding up the rest or the process's exit. The waiting
    is in the calling thread, so SIGINT and SIGTERM end it at once.
    """
    todo = list(entries)
    if not todo:
        return entries
    lock = threading.Condition()
    queue = list(reversed(todo))
    started: dict[int, tuple[Entry, float]] = {}  # id(thread's current entry) -> (entry, start)
    settled: set[int] = set()

    def work() -> None:
        while True:
            with lock:
                if not queue:
                    return
                e = queue.pop()
                started[id(e)] = (e, time.monotonic())
            copy = Entry(e.path, error=e.error)
            _hash_one(copy, timeout)
            with lock:
                if id(e) not in settled:  # not already recorded as timed out by the watchdog
                    e.sha256, e.size, e.error, e.timed_out = copy.sha256, copy.size, copy.error, copy.timed_out
                    settled.add(id(e))
                started.pop(id(e), None)
                lock.notify_all()

    def spawn() -> None:
        threading.Thread(target=work, name="occsurf-audit-hash", daemon=True).start()

    for _ in range(max(1, min(threads, len(todo)))):
        spawn()
    with lock:
        while len(settled) < len(todo):
            wait = None
            if timeout is not None and started:
                now = time.monotonic()
                for key, (e, t0) in list(started.items()):
                    if now - t0 > timeout:  # stuck in a read: recorded now, its thread replaced
                        _timed_out(e, timeout)
                        settled.add(key)
                        del started[key]
                        spawn()
                wait = max(0.0, min((t0 + timeout for _, t0 in started.values()), default=now + timeout) - now) + 0.01
            lock.wait(wait)
    return entries
