"""Crash isolation: run a job on untrusted items in a worker process that may die.

Python can catch exceptions, not a segmentation fault inside OCC (``shared/OCP_NOTES.md`` §7 lists
one; a malformed file can trigger others), nor a reader that never returns. :func:`run_jobs` runs
a *job* (a module-level function, named ``"package.module:function"``) on each of a list of
*items* in a worker subprocess, one item after the other, and reports each item's
:class:`Outcome` as soon as it is known:

===========  =====================================================================================
``ok``       the job returned; ``value`` is what it returned (through JSON)
``error``    the job raised; ``error`` is the exception on one line (``messages.error_line``)
``crashed``  the worker died while running this item (``signal``: ``'SIGSEGV'``, ...; ``exit_code``)
``timeout``  the item took longer than ``timeout`` seconds; the worker was killed
``failed``   the item was not run: the worker could not start, or died outside any item
===========  =====================================================================================

After a crash or a timeout a new worker carries on with the items after the one that failed;
every other item is run exactly once. Used by ``occsurf inspect`` and ``occsurf fill``::

    from occsurf.bridge.isolation import run_jobs

    for outcome in run_jobs("mypkg.jobs:read_one", ["a.step", "b.step"], timeout=60.0):
        print(outcome.index, outcome.status, outcome.value if outcome.ok else outcome.error)

Jobs and items
--------------
A job takes one item and returns a value. Items and values cross the process boundary as JSON,
so they must be JSON-serialisable (dicts, lists, str, numbers, bool, None; floats round-trip
exactly, NaN included); both are passed through JSON in-process too, so the two modes give the
same values. The worker imports the job's module by name, from the same place as this process
(see :func:`worker_env`): a job must be a module-level function of an importable module.

The worker is started by :func:`worker_command`: ``python -P -m occsurf.bridge.isolation``. ``-P``
keeps the current directory off the worker's ``sys.path`` (``-m`` would put it first), so a folder
named ``occsurf`` where the user stands cannot shadow the package; the folder this process imported
``occsurf`` from comes first on the worker's ``PYTHONPATH`` instead. The rest of the environment
(``PYTHONPATH``, site-packages, user site) is kept.

Timing and start-up
-------------------
The worker imports the ``preload`` modules (OCC, say) before it announces its first item, so the
per-item ``timeout`` measures the job alone, not the worker's start-up. An import that fails
there is ignored: the job meets the same failure and reports it as its own ``error``.

Output
------
Native code in the worker (OCC's banners, ``printf``) writes to file descriptor 1, which the
worker points to ``/dev/null``; the protocol travels on a private duplicate of the original
stdout, one line per message, each starting with :data:`MARK` (lines without it are ignored). The
worker's stderr is kept and its last line reported with ``crashed`` and ``failed`` outcomes.

``isolate=False`` runs the jobs in the calling process instead (no protection; handy under a
debugger: the command line's ``--in-process``).

Signals
-------
The worker never outlives its parent: on Linux the kernel kills it when the parent dies, however it
dies (``PR_SET_PDEATHSIG``: SIGTERM, SIGKILL, a crash of the parent), elsewhere a thread of the worker
polls the parent's pid. The worker ignores SIGINT (Ctrl-C at a terminal reaches the whole process
group): the parent's ``KeyboardInterrupt`` kills the worker and propagates; a SIGTERM of the parent
ends it, and with it the worker.

Only the standard library is imported here, so the command-line process stays free of NumPy and OCC.
"""

from __future__ import annotations

import contextlib
import importlib
import json
import math
import os
import signal
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any, TextIO

from .messages import error_line

__all__ = [
    "Outcome",
    "run_jobs",
    "serve",
    "worker_env",
    "worker_command",
    "quiet_native_stdout",
    "describe_exit",
    "OK",
    "ERROR",
    "CRASHED",
    "TIMEOUT",
    "FAILED",
    "MARK",
    "MAX_TIMEOUT",
]

OK = "ok"
ERROR = "error"
CRASHED = "crashed"
TIMEOUT = "timeout"
FAILED = "failed"

#: The longest ``timeout`` accepted (seconds; 1e6 s is 11.6 days). Longer ones overflow the timers and
#: waits they arm (``threading.TIMEOUT_MAX``, ``select``): 1e308 once killed the watchdog thread and
#: the run went on with no timeout at all.
MAX_TIMEOUT = 1e6

#: Prefix of the worker's protocol lines on its stdout (anything else there is ignored).
MARK = "\x1eoccsurf-worker "

#: How the worker is started: ``python -P -m occsurf.bridge.isolation`` (:func:`worker_command`), the job
#: spec on stdin.
WORKER_MODULE = "occsurf.bridge.isolation"


# ---------------------------------------------------------------------------------------- outcome
@dataclass(frozen=True)
class Outcome:
    """What became of one item.

    Attributes
    ----------
    index : int
        Position of the item in the ``items`` given to :func:`run_jobs`.
    status : str
        :data:`OK`, :data:`ERROR`, :data:`CRASHED`, :data:`TIMEOUT` or :data:`FAILED` (see the
        module docstring).
    value : object
        What the job returned, through JSON (``ok`` only, else ``None``).
    error : str or None
        ``error``: the exception on one line. ``crashed`` and ``failed``: the last line the worker
        wrote to stderr (``None`` if nothing), or, when the worker could not be started at all
        (``failed`` with ``exit_code`` ``None``), why. ``None`` for ``ok`` and ``timeout``.
    error_type : str or None
        ``error``: the exception's class name.
    exit_code : int or None
        ``crashed``, ``timeout``, ``failed``: the worker's exit status, negative for a signal
        (``-11``: killed by SIGSEGV); ``None`` if it never started.
    seconds : float
        Wall-clock time from the item's start until its result (or the worker's end) was seen.
    """

    index: int
    status: str
    value: Any = None
    error: str | None = None
    error_type: str | None = None
    exit_code: int | None = None
    seconds: float = 0.0

    @property
    def ok(self) -> bool:
        return self.status == OK

    @property
    def signal(self) -> str | None:
        """The name of the signal that ended the worker (``'SIGSEGV'``), else ``None``."""
        if self.exit_code is None or self.exit_code >= 0:
            return None
        try:
            return signal.Signals(-self.exit_code).name
        except ValueError:
            return f"signal {-self.exit_code}"

    @property
    def exit_reason(self) -> str | None:
        """``'killed by SIGSEGV'`` or ``'exit status 1'`` (:func:`describe_exit`); ``None`` if the
        worker did not end (``ok``, ``error``) or never started."""
        return None if self.exit_code is None else describe_exit(self.exit_code)


def describe_exit(code: int) -> str:
    """A process's exit status in words: ``'killed by SIGSEGV'``, ``'exit status 1'``."""
    if code < 0:
        try:
            name = signal.Signals(-code).name
        except ValueError:
            name = f"signal {-code}"
        return f"killed by {name}"
    return f"exit status {code}"


# ---------------------------------------------------------------------------------------- stdout
@contextlib.contextmanager
def quiet_native_stdout() -> Iterator[None]:
    """Send what C++ code (OCC banners, ``printf``) writes to fd 1 to ``/dev/null`` meanwhile.

    Our own output (a table, a JSON document, the worker protocol) must be all that reaches
    stdout. Python's ``sys.stdout`` is flushed first so nothing is lost or reordered. Nests.
    """
    try:
        sys.stdout.flush()
        fd = sys.__stdout__.fileno() if sys.__stdout__ is not None else 1
        saved = os.dup(fd)
    except (OSError, ValueError, AttributeError):
        yield
        return
    try:
        with open(os.devnull, "wb") as null:
            os.dup2(null.fileno(), fd)
        yield
    finally:
        with contextlib.suppress(OSError, ValueError, AttributeError):
            sys.stdout.flush()
        os.dup2(saved, fd)
        os.close(saved)


@contextlib.contextmanager
def _protocol_channel() -> Iterator[TextIO]:
    """A text stream on a duplicate of stdout, while fd 1 itself goes to ``/dev/null``."""
    try:
        sys.stdout.flush()
        fd = sys.__stdout__.fileno() if sys.__stdout__ is not None else 1
        channel_fd = os.dup(fd)
    except (OSError, ValueError, AttributeError):  # no real stdout (embedded): share sys.stdout
        yield sys.stdout
        return
    channel = os.fdopen(channel_fd, "w", encoding="utf-8", newline="\n")
    try:
        with quiet_native_stdout():
            yield channel
    finally:
        channel.close()


# ---------------------------------------------------------------------------------------- worker
def _resolve(job: str) -> Callable[[Any], Any]:
    module, _, name = job.partition(":")
    func = getattr(importlib.import_module(module), name)
    if not callable(func):
        raise TypeError(f"job: {job!r} is not a function")
    return func


def _preload(modules: Sequence[str]) -> None:
    for name in modules:
        with contextlib.suppress(Exception):  # a failure shows up in the job, per item
            importlib.import_module(name)


def _call(func: Callable[[Any], Any], k: int, item: Any) -> dict[str, Any]:
    """The protocol message for one item: ``report`` with the value, or ``error``."""
    try:
        value = func(item)
        json.dumps(value)  # not serialisable: an error of this item, not of the worker
        return {"report": k, "data": value}
    except Exception as err:  # noqa: BLE001 - reported, the next item still runs
        return {"error": k, "message": error_line(err), "type": type(err).__name__}


def serve(job: str, items: Sequence[Any], preload: Sequence[str] = ()) -> int:
    """The worker loop: run ``job`` on every item, announcing each on stdout.

    Writes ``{"start": k}`` before item ``k`` and ``{"report": k, "data": value}`` (or
    ``{"error": k, "message": ..., "type": ...}``) after it, one JSON document per line prefixed
    by :data:`MARK`, on a private duplicate of stdout; fd 1 points to ``/dev/null`` meanwhile.
    :func:`run_jobs` starts it as ``python -m occsurf.bridge.isolation`` with
    ``{"job": ..., "items": [...], "preload": [...]}`` on stdin; a command of its own may call it
    too (``occsurf _inspect-worker`` does).

    Returns
    -------
    int
        0. A job module that cannot be imported raises (the worker then exits with status 1 and
        every item is reported ``failed`` with the error's last line).
    """
    with _protocol_channel() as channel:

        def send(msg: dict[str, Any]) -> None:
            channel.write(MARK + json.dumps(msg) + "\n")
            channel.flush()

        _preload(preload)  # before the first "start": the timeout excludes start-up
        func = _resolve(job)
        for k, item in enumerate(items):
            send({"start": k})
            send(_call(func, k, item))
    return 0


#: Environment variable through which :func:`run_jobs` tells the worker its parent's pid.
PARENT_PID_ENV = "OCCSURF_WORKER_PARENT"
_PR_SET_PDEATHSIG = 1


def _die_with_parent() -> None:
    """Make sure the worker never outlives the process that started it.

    Linux: ``prctl(PR_SET_PDEATHSIG, SIGKILL)``, so the kernel kills the worker when its parent dies,
    however (SIGKILL included). Elsewhere, or if that fails, a daemon thread polls the parent pid. Either
    way a parent already gone by the time this runs (the start-up window) ends the worker at once.
    """
    parent = int(os.environ.get(PARENT_PID_ENV, "0") or 0)
    armed = False
    if sys.platform.startswith("linux"):
        with contextlib.suppress(Exception):
            import ctypes

            libc = ctypes.CDLL(None, use_errno=True)
            armed = libc.prctl(_PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0) == 0
    if parent and os.getppid() != parent:
        os._exit(1)  # the parent died before the death signal was armed
    if not armed and parent:

        def watch() -> None:
            while os.getppid() == parent:
                time.sleep(0.5)
            os._exit(1)

        threading.Thread(target=watch, name="occsurf-parent-watch", daemon=True).start()


def _worker_main() -> int:
    _die_with_parent()
    # Ctrl-C at a terminal reaches the whole process group: the parent decides (it stops the worker).
    with contextlib.suppress(ValueError, OSError):
        signal.signal(signal.SIGINT, signal.SIG_IGN)
    spec = json.loads(sys.stdin.read())
    return serve(spec["job"], spec["items"], spec.get("preload", ()))


def worker_env() -> dict[str, str]:
    """The worker's environment: this one, with the folder ``occsurf`` was imported from first on
    ``PYTHONPATH``, so the worker runs the same code as this process.

    Empty entries of ``PYTHONPATH`` (``"a::b"``, a trailing ``:``) stand for the current directory;
    they are dropped, as :func:`worker_command` keeps the current directory off ``sys.path``.
    """
    import occsurf

    env = dict(os.environ)
    root = str(Path(occsurf.__file__).resolve().parent.parent)
    rest = [x for x in env.get("PYTHONPATH", "").split(os.pathsep) if x and x != root]
    env["PYTHONPATH"] = os.pathsep.join([root, *rest])
    env[PARENT_PID_ENV] = str(os.getpid())
    return env


def worker_command(module: str = WORKER_MODULE, *args: str) -> list[str]:
    """The command line of a worker process: ``[python, "-P", "-m", module, *args]``.

    ``-P`` (Python 3.11) does not put the current directory first on ``sys.path``, as ``-m`` otherwise
    does: a folder named ``occsurf`` (or ``numpy``...) in the user's current directory cannot shadow
    the package the worker runs. Use it with :func:`worker_env`, which puts this process's ``occsurf``
    first on ``PYTHONPATH``.
    """
    return [sys.executable, "-P", "-m", module, *args]


# ---------------------------------------------------------------------------------------- parent
def _check_args(job: Any, timeout: Any) -> None:
    if not isinstance(job, str) or job.count(":") != 1 or not all(job.partition(":")[::2]):
        raise ValueError(f"job: expected 'package.module:function', got {job!r}")
    if timeout is None:
        return
    number = isinstance(timeout, (int, float)) and not isinstance(timeout, bool)
    if not (number and math.isfinite(timeout) and timeout > 0):
        raise ValueError(f"timeout: expected a positive number of seconds or None, got {timeout!r}")
    if timeout > MAX_TIMEOUT:
        raise ValueError(f"timeout: at most {MAX_TIMEOUT:g} seconds, got {timeout!r}")


def _last_line(fh: IO[bytes]) -> str | None:
    fh.seek(0)
    lines = [ln.strip() for ln in fh.read().decode("utf-8", "replace").splitlines() if ln.strip()]
    return lines[-1] if lines else None


def _run_here(job: str, items: list[Any], preload: Sequence[str], emit: Callable[[Outcome], None]) -> None:
    _preload(preload)
    func = _resolve(job)
    for k, item in enumerate(items):
        t0 = time.perf_counter()
        with quiet_native_stdout():
            msg = _call(func, k, item)
        seconds = time.perf_counter() - t0
        if "report" in msg:
            emit(Outcome(k, OK, value=json.loads(json.dumps(msg["data"])), seconds=seconds))
        else:
            emit(Outcome(k, ERROR, error=msg["message"], error_type=msg["type"], seconds=seconds))


class _Watchdog:
    """Kills the worker when the item it runs takes longer than ``timeout`` seconds."""

    def __init__(self, proc: subprocess.Popen, timeout: float | None) -> None:
        self._proc, self._timeout = proc, timeout
        self._lock = threading.Lock()
        self._timer: threading.Timer | None = None
        self._armed_for: int | None = None
        self.fired = False

    def arm(self, k: int) -> None:
        self.disarm()
        if self._timeout is None:
            return
        with self._lock:
            self._armed_for = k
        self._timer = threading.Timer(self._timeout, self._fire, args=(k,))
        self._timer.daemon = True
        self._timer.start()

    def disarm(self) -> None:
        with self._lock:
            self._armed_for = None
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None

    def _fire(self, k: int) -> None:
        with self._lock:
            if self._armed_for != k:  # the result came in meanwhile
                return
            self.fired = True
        with contextlib.suppress(OSError):
            self._proc.kill()


def _run_one_worker(job: str, items: list[Any], todo: list[int], preload: Sequence[str], timeout: float | None,
                    emit: Callable[[Outcome], None]) -> list[int]:
    """Run the items ``todo`` in one worker; returns the items still to run in a new worker."""
    spec = {"job": job, "items": [items[k] for k in todo], "preload": list(preload)}
    with tempfile.TemporaryFile() as err_log:
        try:
            proc = subprocess.Popen(
                worker_command(WORKER_MODULE),
                stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=err_log, env=worker_env(),
                text=True, encoding="utf-8", errors="replace",
            )
        except OSError as err:
            for k in todo:
                emit(Outcome(k, FAILED, error=str(err)))
            return []
        watchdog = _Watchdog(proc, timeout)
        current: int | None = None
        started = 0.0
        done: set[int] = set()
        try:
            assert proc.stdin is not None and proc.stdout is not None
            with contextlib.suppress(BrokenPipeError):
                proc.stdin.write(json.dumps(spec))
                proc.stdin.close()
            for line in proc.stdout:
                if not line.startswith(MARK):
                    continue  # stray output
                try:
                    msg = json.loads(line[len(MARK):])
                except ValueError:
                    continue  # a line cut short by the worker's death
                if "start" in msg:
                    current, started = todo[msg["start"]], time.perf_counter()
                    watchdog.arm(current)
                    continue
                watchdog.disarm()
                seconds = time.perf_counter() - started
                if "report" in msg:
                    k = todo[msg["report"]]
                    outcome = Outcome(k, OK, value=msg["data"], seconds=seconds)
                else:
                    k = todo[msg["error"]]
                    outcome = Outcome(k, ERROR, error=msg["message"], error_type=msg["type"], seconds=seconds)
                done.add(k)
                current = None
                emit(outcome)
        except BaseException:
            with contextlib.suppress(OSError):
                proc.kill()  # our own failure, a callback's, Ctrl-C: do not leave the worker behind
            raise
        finally:
            watchdog.disarm()
            if proc.stdout is not None:
                proc.stdout.close()
            code = proc.wait()
        detail = _last_line(err_log)
    remaining = [k for k in todo if k not in done]
    if not remaining:
        return []
    if current is None:
        if watchdog.fired:  # killed just as its item's result came in: carry on in a new worker
            return remaining
        # Died outside any item (start-up, or after a result): nothing more would run.
        for k in remaining:
            emit(Outcome(k, FAILED, error=detail, exit_code=code))
        return []
    seconds = time.perf_counter() - started
    if watchdog.fired:
        emit(Outcome(current, TIMEOUT, exit_code=code, seconds=seconds))
    else:
        emit(Outcome(current, CRASHED, error=detail, exit_code=code, seconds=seconds))
    return [k for k in remaining if k != current]


def run_jobs(
    job: str,
    items: Sequence[Any],
    *,
    timeout: float | None = None,
    isolate: bool = True,
    preload: Sequence[str] = (),
    on_outcome: Callable[[Outcome], None] | None = None,
) -> list[Outcome]:
    """Run ``job`` on every item in a worker process; a crash or a hang costs one item only.

    Parameters
    ----------
    job : str
        ``"package.module:function"``: a module-level function taking one item and returning a
        JSON-serialisable value. Whatever it raises becomes that item's ``error`` outcome.
    items : sequence
        JSON-serialisable items, run in order, each at most once.
    timeout : float, optional
        Seconds one item may take before the worker is killed (``timeout`` outcome) and a new one
        continues with the next item; default no limit. Start-up is not counted (see ``preload``).
        Ignored with ``isolate=False``.
    isolate : bool, default True
        ``False`` runs the items in this process: no protection against crashes and hangs, the
        same outcomes otherwise (``ok``/``error``).
    preload : sequence of str
        Modules the worker imports before its first item (failures ignored).
    on_outcome : callable, optional
        Called with each :class:`Outcome` as soon as it is known, in the order of ``items``.

    Returns
    -------
    list of Outcome
        One per item, in the order of ``items``.

    Raises
    ------
    ValueError
        ``job`` not of the form ``"module:function"``, or ``timeout`` not a positive number.
    TypeError
        ``items`` not JSON-serialisable.
    ImportError, AttributeError
        With ``isolate=False`` only: the job cannot be imported (a worker reports that as
        ``failed`` outcomes instead).
    """
    _check_args(job, timeout)
    try:
        wire = json.loads(json.dumps(list(items)))
    except (TypeError, ValueError) as err:
        raise TypeError(f"items: expected JSON-serialisable items, got {err}") from err
    outcomes: list[Outcome] = []

    def emit(outcome: Outcome) -> None:
        outcomes.append(outcome)
        if on_outcome is not None:
            on_outcome(outcome)

    if not isolate:
        _run_here(job, wire, preload, emit)
    else:
        todo = list(range(len(wire)))
        while todo:
            todo = _run_one_worker(job, wire, todo, preload, timeout, emit)
    return sorted(outcomes, key=lambda o: o.index)


if __name__ == "__main__":  # the worker: python -P -m occsurf.bridge.isolation
    from occsurf.bridge.isolation import _worker_main as _main

    sys.exit(_main())
