"""Atomic file writes: the one helper every writer of occsurf uses (STEP, IGES, OBJ, sidecars, PNG, Markdown).

Standard library only (the algorithms layer writes OBJ files through it; ``occsurf.bridge.exchange.files``
re-exports it for the bridge, the demos and the command line).

A write goes to a temporary file beside the target (``.NAME.PID.XXXXXXXX.occsurf-tmp``), held under an
exclusive ``flock`` while it is written, flushed and ``fsync``-ed, given the permissions of the file it
replaces (else those of a new file under the umask), then moved over the target with :func:`os.replace`
and the folder synced. A failure at any point (a full disk, an exception, Ctrl-C) removes the temporary
file and leaves the old target intact; ``kill -9`` leaves only the temporary file, which the next write
to that folder removes (its writer's lock is gone: the lock, not the age, says it is dead).

Targets are checked first:

* an existing target must be a regular file (a symlink is followed and its target replaced, so the
  link survives). A device, FIFO or socket is refused: ``os.replace`` would turn ``/dev/null`` into a
  regular file;
* a read-only target is refused unless ``replace_readonly=True``;
* the folder must exist.

:func:`atomic_write_many` commits several files together; callers writing a pair (a STEP file and its
sidecar) hold :func:`file_lock` on their folder meanwhile, so two processes writing the same pair cannot
interleave (the last writer's pair wins whole), and readers take the same lock shared.
"""

from __future__ import annotations

import contextlib
import errno
import os
import re
import stat
import tempfile
import time
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import Any, BinaryIO

from .errors import ExchangeError

__all__ = ["atomic_write", "atomic_write_many", "check_target", "clean_stale_temps", "file_lock", "default_mode",
           "as_path", "file_kind", "TEMP_SUFFIX", "STALE_GRACE_SECONDS"]

#: Suffix of the temporary files of :func:`atomic_write` (``.NAME.PID.XXXXXXXX.occsurf-tmp``).
TEMP_SUFFIX = ".occsurf-tmp"
#: A temporary file whose lock is free is removed when its writer's pid is gone, or when it is older than
#: this (a pid reused by an unrelated process, a writer on another host).
STALE_GRACE_SECONDS = 60.0

_TEMP_NAME = re.compile(r"^\..*\.(\d+)\.[A-Za-z0-9_]+" + re.escape(TEMP_SUFFIX) + r"$")

Payload = bytes | bytearray | memoryview | Callable[[BinaryIO], None]


def default_mode() -> int:
    """Permissions of a newly created file under the process umask (mkstemp makes 0o600)."""
    mask = os.umask(0o022)
    os.umask(mask)
    return 0o666 & ~mask


def as_path(path: str | bytes | os.PathLike[Any], label: str = "path") -> Path:
    """``path`` as a :class:`~pathlib.Path`; :class:`ExchangeError` naming ``label`` when it is not a
    str, bytes or path-like (bytes, an OS path as the system gives it, are decoded as
    :func:`os.fsdecode` does: undecodable bytes survive as surrogates and name the same file)."""
    try:
        return Path(os.fsdecode(path))
    except TypeError as err:
        raise ExchangeError(f"{label}: expected a str, bytes or path-like, got {type(path).__name__}") from err


def file_kind(mode: int) -> str:
    """What a file that is not a regular file is, from its ``st_mode``: ``'a character device'``,
    ``'a block device'``, ``'a FIFO'``, ``'a socket'``, ``'a directory'``, else ``'not a regular file'``."""
    for test, name in ((stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
                       (stat.S_ISFIFO, "a FIFO"), (stat.S_ISSOCK, "a socket"), (stat.S_ISDIR, "a directory")):
        if test(mode):
            return name
    return "not a regular file"


def check_target(path: str | os.PathLike[str], *, replace_readonly: bool = False) -> Path:
    """The file a write of ``path`` replaces, checked before any work is done.

    Returns the path to replace: ``path`` itself, or the file a symlink ``path`` points to (so the link
    is kept). Nothing is created.

    Raises
    ------
    ExchangeError
        ``path`` exists and is not a regular file (a directory, device, FIFO, socket; a symlink loop);
        it is read-only and ``replace_readonly`` is false; its folder does not exist. The message names
        the path.
    """
    p = as_path(path)
    target = p
    try:
        if p.is_symlink():
            target = Path(os.path.realpath(p))
        st = os.stat(target)
    except (FileNotFoundError, NotADirectoryError):
        st = None  # a new file (or a dangling symlink: its target is created); the folder is checked below
    except OSError as err:
        if err.errno == errno.ELOOP:
            raise ExchangeError(f"{p}: cannot write: a loop of symbolic links") from err
        raise ExchangeError(f"{p}: cannot write: {err.strerror or err}") from err
    if st is not None:
        if not stat.S_ISREG(st.st_mode):
            what = "is a directory" if stat.S_ISDIR(st.st_mode) else f"is {file_kind(st.st_mode)}"
            raise ExchangeError(f"{p}: {what}; refusing to replace it with a regular file")
        writable = bool(st.st_mode & 0o222) and os.access(target, os.W_OK)
        if not writable and not replace_readonly:
            raise ExchangeError(f"{p}: is read-only; not replaced (pass replace_readonly=True to replace it)")
    parent = target.parent
    if not parent.is_dir():
        why = "is not a directory" if parent.exists() else "does not exist"
        raise ExchangeError(f"{p}: cannot write: {parent} {why}")
    return target


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OverflowError):
        return True
    return True


def clean_stale_temps(folder: str | os.PathLike[str]) -> list[Path]:
    """Remove the temporary files that killed writes left in ``folder``; returns those removed.

    A temporary file is stale when nobody holds its lock and its writer's pid is gone (or it is older
    than :data:`STALE_GRACE_SECONDS`). Live writes, of this process or another, are never touched.
    """
    import fcntl

    removed: list[Path] = []
    try:
        names = [n for n in os.listdir(folder) if n.endswith(TEMP_SUFFIX)]
    except OSError:
        return removed
    now = time.time()
    for name in names:
        m = _TEMP_NAME.match(name)
        if m is None:
            continue
        path = Path(folder) / name
        try:
            fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK)
        except OSError:
            continue
        try:
            st = os.fstat(fd)
            if not stat.S_ISREG(st.st_mode):
                continue
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError:
                continue  # a live writer holds it
            if _pid_alive(int(m.group(1))) and now - st.st_mtime < STALE_GRACE_SECONDS:
                continue  # created a moment ago, its lock not yet taken
            with contextlib.suppress(OSError):
                os.unlink(path)
                removed.append(path)
        finally:
            os.close(fd)
    return removed


@contextlib.contextmanager
def file_lock(path: str | os.PathLike[str], *, shared: bool = False) -> Iterator[None]:
    """Hold an advisory ``flock`` on ``path`` for the block: exclusive for writers, shared for readers.

    ``path`` may be a folder (nothing is created then: the pair of a STEP file and its sidecar locks
    their folder) or a file, created by a writer if missing. A reader finding nothing to lock reads
    without the lock.
    """
    import fcntl

    try:
        fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW)
    except FileNotFoundError as err:
        if shared:
            yield
            return
        try:
            fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW, default_mode())
        except OSError as err2:
            raise ExchangeError(f"{path}: cannot create the lock file: {err2.strerror or err2}") from err
    except OSError as err:
        if shared:
            yield
            return
        raise ExchangeError(f"{path}: cannot lock: {err.strerror or err}") from err
    try:
        fcntl.flock(fd, fcntl.LOCK_SH if shared else fcntl.LOCK_EX)
        yield
    finally:
        os.close(fd)  # releases the lock


def _write_temp(target: Path, payload: Payload, shown: Path) -> str:
    """The payload in a synced, locked temporary file beside ``target``; returns its name."""
    import fcntl

    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{target.name[:80]}.{os.getpid()}.", suffix=TEMP_SUFFIX,
                                   dir=target.parent)
    except OSError as err:
        raise ExchangeError(f"{shown}: cannot write: {err.strerror or err}") from err
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)  # held until the file is closed: marks the write as live
        try:
            mode = os.stat(target).st_mode & 0o7777
        except OSError:
            mode = default_mode()
        with os.fdopen(fd, "wb") as fh:
            if callable(payload):
                payload(fh)
            else:
                fh.write(payload)
            fh.flush()
            os.fsync(fh.fileno())
            os.fchmod(fh.fileno(), mode)
    except BaseException as err:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        if isinstance(err, OSError) and not isinstance(err, ExchangeError):
            raise ExchangeError(f"{shown}: cannot write: {err.strerror or err}") from err
        raise
    return tmp


def _sync_folder(folder: Path) -> None:
    with contextlib.suppress(OSError):
        fd = os.open(folder, os.O_RDONLY | os.O_DIRECTORY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)


def atomic_write_many(items: Sequence[tuple[str | os.PathLike[str], Payload]], *,
                      lock: str | os.PathLike[str] | None = None, replace_readonly: bool = False) -> list[Path]:
    """Write every ``(path, payload)`` atomically; all temporary files are complete before any rename.

    Parameters
    ----------
    items : sequence of (path, bytes or callable)
        A payload is the bytes to write, or a function writing them to a binary file object.
    lock : path, optional
        A lock file held exclusively from the first write to the last rename: concurrent writers of the
        same files (with the same lock) are serialised, so their files never mix.
    replace_readonly : bool
        Replace read-only targets too (see :func:`check_target`).

    Returns
    -------
    list of Path
        The paths written (symlinks followed).

    Raises
    ------
    ExchangeError
        A target that :func:`check_target` refuses, or any OS error while writing (named with the path);
        no target is modified then (only the renames themselves, one system call each, are not one
        transaction: the lock keeps other occsurf writers out of that window).
    """
    targets = [(check_target(p, replace_readonly=replace_readonly), as_path(p), data) for p, data in items]
    for folder in {t.parent for t, _, _ in targets}:
        clean_stale_temps(folder)
    with file_lock(lock) if lock is not None else contextlib.nullcontext():
        tmps: list[str] = []
        try:
            for target, shown, data in targets:
                tmps.append(_write_temp(target, data, shown))
            for (target, shown, _), tmp in zip(targets, tmps):
                try:
                    os.replace(tmp, target)
                except OSError as err:
                    raise ExchangeError(f"{shown}: cannot write: {err.strerror or err}") from err
        finally:
            for tmp in tmps:
                with contextlib.suppress(OSError):
                    os.unlink(tmp)
    for folder in {t.parent for t, _, _ in targets}:
        _sync_folder(folder)
    return [t for t, _, _ in targets]


def atomic_write(path: str | os.PathLike[str], data: Payload, *, replace_readonly: bool = False) -> Path:
    """Write ``data`` (bytes, or a function writing to a binary file) to ``path`` atomically.

    See :func:`atomic_write_many`; returns the path written.
    """
    return atomic_write_many([(path, data)], replace_readonly=replace_readonly)[0]
