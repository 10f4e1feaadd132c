"""What the commands of ``occsurf`` share: exit codes, file arguments, tables, messages, streamed output.

Finding and reading STEP/IGES inputs (the suffixes, folders expanded, the format of a file, reading a
model, ``--strict``'s refusal) is library code, :mod:`occsurf.bridge.exchange.reading`, re-exported
here for the commands; :func:`strip_path` is :mod:`occsurf.bridge.messages`'.

Only the standard library is imported at module level: the command-line process never loads NumPy
or OCC itself (``occsurf --help`` stays instant); the reading helpers import them when called,
normally inside a worker process (:mod:`occsurf.bridge.isolation`).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..exchange.reading import (
    IGES_SUFFIXES,
    STEP_SUFFIXES,
    SUFFIXES,
    expand,
    files_in,
    folder_entries,
    read_model,
    shown_path,
    sniff_format,
    strict_refusal,
)
from ..messages import strip_path

if TYPE_CHECKING:
    from ..isolation import Outcome

__all__ = [
    "OneLineParser",
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
    "folder_entries",
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
    "shown_path",
    "output_problem",
    "guarded",
    "EXIT_INTERRUPTED",
    "write_out",
    "write_json_line",
    "InOrder",
    "interrupts_held",
    "add_strict_option",
    "strict_refusal",
]

EXIT_OK = 0
#: Some file could not be read, or a command-line argument is wrong (argparse uses 2 as well).
EXIT_ERROR = 2
#: Stopped by Ctrl-C (128 + SIGINT, as shells report it).
EXIT_INTERRUPTED = 130

SAMPLES_DIR = "step_samples"


# ---------------------------------------------------------------------------------------- messages
def error(message: str) -> None:
    """Print ``occsurf: MESSAGE`` on stderr: the one-line form of every error a command reports."""
    print(f"occsurf: {message}", file=sys.stderr, flush=True)


class OneLineParser(argparse.ArgumentParser):
    """The ``occsurf`` parser (and, through ``add_subparsers``, every command's): a usage error is one
    line on stderr, ``occsurf: convert: argument --unit: invalid choice: 'furlong' (choose from ...)``,
    exit :data:`EXIT_ERROR`, like every other error of the command line (argparse's own prints the
    usage block first)."""

    def error(self, message: str) -> Any:
        command = self.prog.split(" ", 1)[1] if " " in self.prog else ""
        error(f"{command}: {message}" if command else message)
        self.exit(EXIT_ERROR)


def paths_problem(src: Path, out: Path, what: str) -> bool:
    """Report (one line) an input that cannot be read or an output ``what`` cannot be written to;
    ``True`` when there is such a problem (the command then exits :data:`EXIT_ERROR`)."""
    from ..exchange.files import input_problem

    why = input_problem(src)
    if why is not None:
        error(f"{shown_path(src)}: {why}")
        return True
    why = output_problem(out)
    if why is not None:
        error(f"{shown_path(out)}: cannot write {what} there ({why})")
        return True
    return False


def outcome_problem(outcome: Outcome, src: Path, timeout: float | None, task: str) -> bool:
    """Report (one line) why a worker run on ``src`` gave no result; ``True`` when it gave none."""
    from ..isolation import ERROR, OK

    if outcome.status == OK:
        return False
    why = (strip_path(outcome.error or "unknown error", src) if outcome.status == ERROR else
           worker_failure(outcome, timeout, task=task, process="worker"))
    error(f"{shown_path(src)}: {why}")
    return True


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


def _quiet_stdout() -> None:
    """Point fd 1 to /dev/null: nothing more can fail there, not even the flush at exit."""
    with contextlib.suppress(OSError, ValueError, AttributeError):
        null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(null, sys.stdout.fileno())
        os.close(null)


@contextlib.contextmanager
def interrupts_held() -> Any:
    """Hold SIGINT (Ctrl-C) back for the block: it is delivered, as ``KeyboardInterrupt``, right after.

    What a command writes inside the block (one JSON line, a final document) is written whole: Ctrl-C
    never cuts a line of output in two. Only in the main thread on POSIX; elsewhere a no-op.
    """
    import signal
    import threading

    held = (hasattr(signal, "pthread_sigmask") and threading.current_thread() is threading.main_thread())
    if held:
        old = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        if held:
            signal.pthread_sigmask(signal.SIG_SETMASK, old)


def write_out(text: str) -> None:
    """Write ``text`` to stdout and flush it, whole (:func:`interrupts_held`): the unit of streamed output."""
    with interrupts_held():
        sys.stdout.write(text)
        sys.stdout.flush()


def write_json_line(obj: Any) -> None:
    """One JSON line (``--jsonl``), written whole (:func:`write_out`); NaN refused (not JSON)."""
    write_out(json.dumps(obj, allow_nan=False) + "\n")


class InOrder:
    """Results that arrive in any order, handed on in the order of their indices: each as soon as it and
    every earlier one have arrived. How ``inspect`` and ``check`` print a file's table or ``--jsonl`` line
    the moment it is done while keeping the order of the arguments (``check`` re-runs a crashed file
    later; a worker pool would finish files out of order).

    ``emit(k, item)`` is called once per index, in order; when it raises (a closed pipe, Ctrl-C), that
    item counts as not emitted. :attr:`emitted` is what was handed on, in order (what Ctrl-C keeps).
    """

    def __init__(self, n: int, emit: Callable[[int, Any], None]) -> None:
        self._items: list[Any] = [None] * n
        self._arrived = [False] * n
        self._emit = emit
        #: How many items have been handed on (indices ``0 .. count - 1``).
        self.count = 0

    def put(self, k: int, item: Any) -> None:
        """Store item ``k``; hand on every item that is next in order."""
        self._items[k], self._arrived[k] = item, True
        while self.count < len(self._items) and self._arrived[self.count]:
            self._emit(self.count, self._items[self.count])
            self.count += 1

    @property
    def emitted(self) -> list[Any]:
        """The items handed on so far, in order."""
        return self._items[: self.count]


def guarded(func: Any, ns: argparse.Namespace) -> int:
    """Run a command's handler with the command line's promises: one line on stderr, never a traceback.

    * Ctrl-C (``KeyboardInterrupt``): what was written so far is flushed (a command prints what it had
      done first: ``inspect`` its files so far), then ``occsurf: interrupted``, exit
      :data:`EXIT_INTERRUPTED` (a worker process is stopped by :func:`occsurf.bridge.isolation.run_jobs`
      on the way out);
    * stdout closed by its reader (``occsurf inspect DIR | head -1``): no message, exit 2;
    * stdout that cannot be written (a full disk, ``> /dev/full``, closed): ``occsurf: cannot write the
      output: REASON``, exit 2, so a truncated JSON document never passes for a complete one.
    """
    import errno

    if sys.stdout is None:  # started with fd 1 closed (``occsurf inspect >&-``)
        error("cannot write the output: standard output is closed")
        return EXIT_ERROR
    with contextlib.suppress(AttributeError, ValueError):  # a non-UTF-8 file name must not stop a table
        sys.stdout.reconfigure(errors="backslashreplace")  # type: ignore[union-attr]
    interrupted = _note_interrupts()
    try:
        try:
            code = int(func(ns))
            sys.stdout.flush()
            return code
        except Exception:
            # Ctrl-C inside a compiled module's import (OCP's initialisation turns the KeyboardInterrupt
            # into ``ImportError: initialization failed``) is still Ctrl-C, not a traceback.
            if interrupted():
                raise KeyboardInterrupt from None
            raise
    except KeyboardInterrupt:
        with contextlib.suppress(OSError, ValueError, KeyboardInterrupt):
            with interrupts_held():
                sys.stdout.flush()  # what was done so far stays printed
        _quiet_stdout()
        error("interrupted")
        return EXIT_INTERRUPTED
    except BrokenPipeError:
        _quiet_stdout()
        return EXIT_ERROR
    except OSError as err:
        if err.errno not in (errno.ENOSPC, errno.EIO, errno.EDQUOT, errno.EFBIG, errno.EBADF, errno.EPIPE):
            raise
        _quiet_stdout()
        error(f"cannot write the output: {err.strerror or err}")
        return EXIT_ERROR
    finally:
        interrupted.restore()


class _SigintSeen:
    """Whether SIGINT arrived since :func:`_note_interrupts` (callable), and ``restore()`` of the handler."""

    def __init__(self) -> None:
        import signal
        import threading

        self.seen = False
        self._old: Any = None
        if threading.current_thread() is threading.main_thread() \
                and signal.getsignal(signal.SIGINT) is signal.default_int_handler:
            self._old = signal.signal(signal.SIGINT, self._handle)

    def _handle(self, signum: int, frame: Any) -> None:
        import signal

        self.seen = True
        signal.default_int_handler(signum, frame)

    def __call__(self) -> bool:
        return self.seen

    def restore(self) -> None:
        import signal

        if self._old is not None:
            signal.signal(signal.SIGINT, self._old)
            self._old = None


def _note_interrupts() -> _SigintSeen:
    """Note Ctrl-C while a command runs (Python's own handler still raises ``KeyboardInterrupt``); an
    ignored SIGINT (a job started in the background) stays ignored."""
    return _SigintSeen()


def output_problem(path: Path) -> str | None:
    """Why ``path`` cannot be written, checked in the command-line process before any work (standard
    library only; :func:`occsurf.bridge.exchange.files.check_target` applies the same rules again when the
    worker writes): ``None`` if it can be."""
    import stat

    try:
        st = os.stat(path)
    except (FileNotFoundError, NotADirectoryError):
        st = None
    except OSError as err:
        return f"cannot write there: {err.strerror or err}"
    if st is not None:
        if stat.S_ISDIR(st.st_mode):
            return "is a directory"
        if not stat.S_ISREG(st.st_mode):
            return "exists and is not a regular file (a device, FIFO or socket); refusing to replace it"
        if not (st.st_mode & 0o222 and os.access(path, os.W_OK)):
            return "is read-only; not replaced"
    folder = path.parent if str(path.parent) else Path(".")
    if not folder.is_dir() or not os.access(folder, os.W_OK):
        return f"the folder {shown_path(folder)} does not exist or is not writable"
    return None


# ---------------------------------------------------------------------------------------- files
def find_samples_dir(cwd: Path | None = None) -> Path | None:
    """The ``step_samples/`` folder: below the current directory first, then the one shipped in the
    package, :mod:`occsurf.step_samples` (``occsurf/step_samples`` in a wheel, the repository's folder
    under an editable install)."""
    import occsurf.step_samples

    here = Path.cwd() if cwd is None else Path(cwd)
    shipped = [Path(p) for p in occsurf.step_samples.__path__]
    for candidate in (here / SAMPLES_DIR, *shipped):
        if candidate.is_dir():
            return candidate
    return None


def add_strict_option(parser: argparse.ArgumentParser, *, writes: bool = False) -> None:
    """``--strict`` on a command that reads an untrusted model: warnings (damage read around, see
    :mod:`occsurf.bridge.exchange.checks`) become exit status 2; ``writes``: and nothing is written."""
    parser.add_argument("--strict", action="store_true",
                        help="exit with status 2 when the input has warnings (damaged data read around)"
                             + ("; nothing is written then" if writes else ""))


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
def jobs_arg(text: str) -> int:
    """``--jobs``: a positive whole number of worker processes."""
    try:
        value = int(text, 10)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number of worker processes, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected at least 1 worker process, got {text!r}")
    return value


def positive_arg(text: str) -> float:
    """A positive, finite number (a tolerance, a distance)."""
    try:
        x = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not (x > 0 and x < float("inf")):
        raise argparse.ArgumentTypeError(f"expected a finite number > 0, got {text!r}")
    return x


def timeout_arg(text: str) -> float:
    """``--timeout``: a positive, finite number of seconds."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number of seconds, got {text!r}") from None
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"expected a positive number of seconds, got {text!r}")
    from ..isolation import MAX_TIMEOUT

    if value > MAX_TIMEOUT:
        raise argparse.ArgumentTypeError(f"at most {MAX_TIMEOUT:g} seconds, got {text!r}")
    return value
