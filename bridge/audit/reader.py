"""A persistent, crash-isolated reader process per Dask worker thread.

Why not read in the Dask worker itself
--------------------------------------
A segmentation fault inside OCC would kill the Dask worker. Its nanny restarts it, but the
scheduler then blames *every* task that was assigned to the worker (with queueing that is the
running task and the next one), learns no signal, and after ``allowed-failures`` reports a
:class:`distributed.KilledWorker` that may name an innocent file. Why not
:func:`occsurf.bridge.isolation.run_jobs` per task: it starts a fresh interpreter per call, and
importing OCC costs ~2 s, longer than reading most files.

So every Dask worker thread keeps one *reader* subprocess here (OCC loaded once) and sends it one
file at a time. When the reader dies the task knows exactly which file did it and by which signal
(``crashed``, ``SIGSEGV``); when a file takes longer than the timeout the task kills the reader
(``timeout``); either way the next file gets a fresh reader ("the worker is recycled") and the
Dask worker never notices. A Dask worker killed from outside is Dask's business: its tasks are
rescheduled on other workers, and the reader it leaves behind exits when it sees its parent gone.

Protocol: one JSON request per line on the reader's stdin (``{"job": "mod:func", "item": ...}``),
one reply per line on a private duplicate of its stdout, each prefixed by
:data:`occsurf.bridge.isolation.MARK` (fd 1 itself goes to ``/dev/null``: OCC's banners). The
first reply is ``{"ready": pid}`` once the preload modules are imported, so the timeout never
counts the reader's start-up. The reader is started as the isolation worker is
(:func:`occsurf.bridge.isolation.worker_command`: ``python -P -m ...``), so a folder named ``occsurf``
in the current directory cannot shadow the package. Only the standard library is imported here.
"""

from __future__ import annotations

import contextlib
import importlib
import json
import os
import select
import signal
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, TypeVar

from ..isolation import (
    CRASHED,
    ERROR,
    FAILED,
    MARK,
    OK,
    TIMEOUT,
    Outcome,
    describe_exit,
    quiet_native_stdout,
    worker_command,
    worker_env,
)
from ..messages import error_line

__all__ = ["Reader", "Reply", "reader_for_thread", "on_free_readers", "STARTUP_TIMEOUT"]

#: Seconds a reader may take to start and import its preload modules (OCC: ~2 s unloaded).
STARTUP_TIMEOUT = 180.0
_MODULE = "occsurf.bridge.audit.reader"
T = TypeVar("T")


@dataclass(frozen=True)
class Reply:
    """What became of one request: ``status`` is ``ok``, ``error``, ``crashed`` or ``timeout``."""

    status: str
    value: Any = None
    error: str | None = None
    signal: str | None = None
    exit_code: int | None = None
    seconds: float = 0.0


def _signal_name(code: int | None) -> str | None:
    if code is None or code >= 0:
        return None
    try:
        return signal.Signals(-code).name
    except ValueError:
        return f"signal {-code}"


class Reader:
    """One reader subprocess, started on first use and after every crash or timeout.

    Parameters
    ----------
    preload : sequence of str
        Modules the reader imports before it says it is ready (OCC, our deviation code).
    """

    def __init__(self, preload: tuple[str, ...] = ()) -> None:
        self.preload = tuple(preload)
        self.proc: subprocess.Popen | None = None
        self.starts = 0
        self._buf = b""
        self._eof = False
        self._err: Any = None

    # ------------------------------------------------------------------------------ lifecycle
    def _start(self) -> None:
        self._err = tempfile.TemporaryFile()
        self.proc = subprocess.Popen(worker_command(_MODULE, json.dumps(list(self.preload))),
                                     stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=self._err,
                                     env=worker_env(), bufsize=0)
        self._buf = b""
        self._eof = False
        self.starts += 1
        msg = self._read_message(time.monotonic() + STARTUP_TIMEOUT)
        if msg is None or "ready" not in msg:
            code = self.stop()
            err = self._last_err()
            raise RuntimeError(f"the reader process did not start ({describe_exit(code) if code is not None else 'no reply'}"
                               f"{': ' + err if err else ''})")

    def stop(self) -> int | None:
        """Kill the reader (if any); returns its exit status."""
        proc, self.proc = self.proc, None
        if proc is None:
            return None
        with contextlib.suppress(OSError):
            proc.kill()
        code = proc.wait()
        for fh in (proc.stdin, proc.stdout):
            if fh is not None:  # both are pipes (Popen(stdin=PIPE, stdout=PIPE))
                with contextlib.suppress(OSError):
                    fh.close()
        return code

    @property
    def pid(self) -> int | None:
        return None if self.proc is None else self.proc.pid

    def _last_err(self) -> str | None:
        if self._err is None:
            return None
        with contextlib.suppress(OSError):
            self._err.seek(0, os.SEEK_END)
            size = self._err.tell()
            self._err.seek(max(0, size - 4096))
            lines = [ln.strip() for ln in self._err.read().decode("utf-8", "replace").splitlines() if ln.strip()]
            return lines[-1] if lines else None
        return None

    # ------------------------------------------------------------------------------ messages
    def _read_message(self, deadline: float | None) -> dict[str, Any] | None:
        """The next protocol message; ``None`` at EOF (the reader died: :attr:`_eof` set) or at
        the deadline."""
        assert self.proc is not None and self.proc.stdout is not None
        fd = self.proc.stdout.fileno()
        while True:
            while b"\n" in self._buf:
                line, self._buf = self._buf.split(b"\n", 1)
                text = line.decode("utf-8", "replace")
                if text.startswith(MARK):
                    with contextlib.suppress(ValueError):
                        return json.loads(text[len(MARK):])
            wait = None if deadline is None else deadline - time.monotonic()
            if wait is not None and wait <= 0:
                return None
            ready, _, _ = select.select([fd], [], [], wait)
            if not ready:
                return None
            chunk = os.read(fd, 1 << 16)
            if not chunk:
                self._eof = True
                return None
            self._buf += chunk

    def run(self, job: str, item: Any, timeout: float | None) -> Reply:
        """Run ``job`` (``"module:function"``) on ``item`` in the reader; never raises for the item."""
        if self.proc is None or self.proc.poll() is not None:
            self.stop()
            self._start()
        assert self.proc is not None and self.proc.stdin is not None
        t0 = time.monotonic()
        try:
            self.proc.stdin.write((json.dumps({"job": job, "item": item}) + "\n").encode())
        except OSError:
            pass  # it died: seen as EOF below
        msg = self._read_message(None if timeout is None else t0 + timeout)
        seconds = time.monotonic() - t0
        if msg is not None and "report" in msg:
            return Reply("ok", value=msg["report"], seconds=seconds)
        if msg is not None and "error" in msg:
            return Reply("error", error=msg["error"], seconds=seconds)
        # EOF: the reader died by itself (its pipe closes before its exit status is available,
        # so poll() alone would race); else no reply within the timeout and we kill it.
        died = self._eof
        if died:
            with contextlib.suppress(subprocess.TimeoutExpired):
                self.proc.wait(timeout=30)
        detail = self._last_err()
        code = self.stop()
        if not died:
            return Reply("timeout", error=f"no result after {timeout:g} s; the reader process was recycled",
                         exit_code=code, seconds=seconds)
        why = describe_exit(code) if code is not None else "no exit status"
        return Reply("crashed", error=f"the reader process died ({why})" + (f": {detail}" if detail and code and code > 0 else ""),
                     signal=_signal_name(code), exit_code=code, seconds=seconds)

    def outcome(self, job: str, item: Any, timeout: float | None, index: int = 0) -> Outcome:
        """:meth:`run` reported as :func:`occsurf.bridge.isolation.run_jobs` reports an item (``index``:
        the item's position), so that callers of either word a failure alike; a reader that cannot
        start is a ``failed`` outcome."""
        try:
            reply = self.run(job, item, timeout)
        except RuntimeError as err:  # the worker could not start
            return Outcome(index, FAILED, error=str(err))
        if reply.status == OK:
            return Outcome(index, OK, value=reply.value, seconds=reply.seconds)
        if reply.status == ERROR:
            return Outcome(index, ERROR, error=reply.error, seconds=reply.seconds)
        return Outcome(index, CRASHED if reply.status == CRASHED else TIMEOUT, error=reply.error,
                       exit_code=reply.exit_code, seconds=reply.seconds)


def on_free_readers(readers: list[Reader], n: int, work: Callable[[Reader, int], T], stopped: Callable[[int], T], *,
                    name: str) -> list[T]:
    """Run ``work(reader, k)`` for every ``k < n``, each on whichever of ``readers`` is free first
    (one thread per reader: the work is in the reader processes, the threads wait for them); the
    results in the order of ``k``. On Ctrl-C (or any exception here) the items not started get
    ``stopped(k)`` and every reader is stopped at once rather than waited for; the exception is raised
    again. How ``fill --jobs`` fills holes and ``check --jobs`` checks files."""
    from concurrent.futures import ThreadPoolExecutor
    from queue import SimpleQueue

    idle: SimpleQueue[Reader] = SimpleQueue()
    for r in readers:
        idle.put(r)
    stopping = threading.Event()

    def one(k: int) -> T:
        if stopping.is_set():
            return stopped(k)
        reader = idle.get()
        try:
            return work(reader, k)
        finally:
            idle.put(reader)

    pool = ThreadPoolExecutor(max_workers=max(1, len(readers)), thread_name_prefix=f"occsurf-{name}")
    try:
        return list(pool.map(one, range(n)))
    except BaseException:  # Ctrl-C, ...: stop the readers now rather than wait for their items
        stopping.set()
        pool.shutdown(wait=False, cancel_futures=True)
        for r in readers:
            r.stop()
        raise
    finally:
        pool.shutdown(wait=True)


_local = threading.local()


def reader_for_thread(preload: tuple[str, ...]) -> Reader:
    """The calling thread's :class:`Reader` (one per Dask worker thread, kept between tasks)."""
    reader = getattr(_local, "reader", None)
    if reader is None:
        reader = _local.reader = Reader(preload)
    return reader


# ------------------------------------------------------------------------------------ child side
def _watch_parent(parent: int) -> None:
    """Exit when the parent (the Dask worker) is gone, even while OCC is busy or hung."""
    while True:
        time.sleep(1.0)
        if os.getppid() != parent:
            os._exit(0)


def _serve(preload: list[str]) -> int:
    # Ctrl-C in a terminal reaches the whole process group: the reader is stopped by its parent
    # only, so that an interrupted audit records nothing false (a reader dying of SIGINT would
    # look like a crash of the file it was reading).
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    threading.Thread(target=_watch_parent, args=(os.getppid(),), daemon=True).start()
    sys.stdout.flush()
    channel = os.fdopen(os.dup(1), "w", encoding="utf-8", newline="\n")

    def send(msg: dict[str, Any]) -> None:
        channel.write(MARK + json.dumps(msg) + "\n")
        channel.flush()

    with quiet_native_stdout():
        for name in preload:
            with contextlib.suppress(Exception):  # a failure shows up per item, in the job
                importlib.import_module(name)
        send({"ready": os.getpid()})
        for line in sys.stdin:
            if not line.strip():
                continue
            try:
                req = json.loads(line)
                module, _, name = req["job"].partition(":")
                value = getattr(importlib.import_module(module), name)(req["item"])
                json.dumps(value, allow_nan=True)
                send({"report": value})
            except Exception as err:  # noqa: BLE001 - reported; the next item still runs
                send({"error": error_line(err)})
    return 0


if __name__ == "__main__":
    from occsurf.bridge.audit.reader import _serve as _main

    sys.exit(_main(json.loads(sys.argv[1]) if len(sys.argv) > 1 else []))
