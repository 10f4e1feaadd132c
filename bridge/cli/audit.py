"""``occsurf audit PATH... --out RESULTS [--scheduler ADDRESS] [--workers N] [--timeout S] [--resume]
[--checks inspect,quality,roundtrip]``.

Audits whole corpora of STEP/IGES files on Dask (:func:`occsurf.bridge.audit.audit`): per file
one task that reads it crash-isolated, inspects every face (our evaluation against OCC's), round
trips it through our STEP writer and reader, and (once available) summarises its quality. Rows go
to Parquet datasets ``RESULTS/files/`` and ``RESULTS/faces/`` as tasks finish; ``summary.json``
and ``summary.html`` at the end. Progress (done/failed/remaining, rate, ETA) and the Dask dashboard
link go to stderr.

Exit status: 0 when every file was audited ``ok``; 1 when the audit completed but some files are
``error``, ``crashed`` or ``timeout`` (their rows say why); 2 on bad input (an empty corpus, a
missing PATH, an unreachable scheduler, an unwritable or already used ``--out``, a missing
dependency), one line on stderr and nothing audited; 130 when interrupted by Ctrl-C (SIGINT), 143 by
SIGTERM: what finished is in RESULTS and ``--resume`` does the rest.

Only the standard library is imported at module level.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib.util
import signal
import sys
import threading
from typing import Any

from ._common import EXIT_ERROR, EXIT_OK, error, timeout_arg

__all__ = ["add_parser", "run", "EXIT_FAILURES", "EXIT_INTERRUPTED"]

EXIT_FAILURES = 1
EXIT_INTERRUPTED = 130
DEFAULT_TIMEOUT = 300.0
_CHECKS = ("inspect", "quality", "roundtrip")


def _checks_arg(text: str) -> tuple[str, ...]:
    names = tuple(x.strip() for x in text.split(",") if x.strip())
    bad = [x for x in names if x not in _CHECKS]
    if bad or not names:
        raise argparse.ArgumentTypeError(f"expected a comma-separated subset of {','.join(_CHECKS)}, got {text!r}")
    return names


def _workers_arg(text: str) -> int:
    try:
        n = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}") from None
    if n < 1:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {n}")
    return n


def _missing_dependencies() -> list[str]:
    return [m for m in ("dask", "distributed", "pyarrow") if importlib.util.find_spec(m) is None]


class _Interrupts:
    """SIGINT (Ctrl-C) and SIGTERM (a killed client) end the run: the first raises
    ``KeyboardInterrupt`` and sets :attr:`stop` (which the audit checks at every finished file, in
    case a library swallowed the exception); later ones are ignored, so the flush of the finished
    rows and the cluster's shutdown run to their end."""

    def __init__(self) -> None:
        self.stop = threading.Event()
        self.signum: int | None = None
        self._hook = sys.unraisablehook

    def handler(self, signum: int, frame: Any) -> None:
        if self.signum is not None:
            return
        self.signum = signum
        self.stop.set()
        raise KeyboardInterrupt

    @property
    def exit_status(self) -> int:
        """128 + the signal's number: 130 for SIGINT, 143 for SIGTERM."""
        return 128 + (self.signum or signal.SIGINT)

    def unraisable(self, info: Any) -> None:
        """The interrupt raised where Python cannot raise (a weakref callback, ``__del__``): it was
        swallowed there, with a traceback printed; :attr:`stop` ends the run instead, quietly."""
        if info.exc_type is KeyboardInterrupt and self.signum is not None:
            return
        self._hook(info)

    @contextlib.contextmanager
    def installed(self) -> Any:
        try:
            old = {s: signal.signal(s, self.handler) for s in (signal.SIGINT, signal.SIGTERM)}
        except ValueError:  # not the main thread
            yield
            return
        self._hook, sys.unraisablehook = sys.unraisablehook, self.unraisable
        try:
            yield
        finally:
            for s, h in old.items():  # after an interrupt the command is ending: a second signal must not
                signal.signal(s, h if self.signum is None else signal.SIG_IGN)  # end it with -2 instead of 130
            sys.unraisablehook = self._hook


def run(ns: argparse.Namespace) -> int:
    """Handler of ``occsurf audit``."""
    missing = _missing_dependencies()
    if missing:
        error(f"audit needs {', '.join(missing)}: pip install 'occsurf[audit]'")
        return EXIT_ERROR
    from ..audit import AuditInputError, ClusterError, CorpusError, StoreError, audit
    from ..messages import error_line

    def dashboard(link: str) -> None:
        print(f"audit: Dask dashboard at {link}", file=sys.stderr, flush=True)

    signals = _Interrupts()

    def interrupted() -> int:
        error(f"interrupted; what finished is in {ns.out} (rerun with --resume to finish the rest)")
        return signals.exit_status

    try:
        with signals.installed():
            result = audit(ns.paths, ns.out, scheduler=ns.scheduler, workers=ns.workers, timeout=ns.timeout,
                           resume=ns.resume, checks=ns.checks, samples=ns.samples, on_dashboard=dashboard,
                           stop=signals.stop)
    except KeyboardInterrupt:  # outside the loop over files (hashing, cluster start-up, the summary), or as our
        return interrupted()  # handler was being installed or restored (a SIGTERM is 143 here too)
    except Exception as err:  # noqa: BLE001 - whatever it is: one line, never a traceback
        if signals.signum is not None:  # the interrupt, made an error of its own by what it went through
            return interrupted()  # (the cluster's start-up, the store, a library)
        if isinstance(err, (CorpusError, StoreError, ClusterError, AuditInputError)):
            error(" ".join(str(err).split()))
        else:  # a defect of ours
            error(f"audit failed: {error_line(err)} (results written so far are in {ns.out}; --resume continues)")
        return EXIT_ERROR
    c = result.counts
    if result.interrupted or signals.signum is not None:
        error(f"interrupted: {sum(c.values())} of {result.n_input} files are in {ns.out}; "
              "rerun with --resume to finish the rest")
        return signals.exit_status
    print(f"{result.n_input} files: {c['ok']} ok, {c['error']} failed, {c['crashed']} crashed, {c['timeout']} timeout "
          f"({result.skipped} already in {ns.out}); {result.seconds:.1f} s; {ns.out}/summary.html", flush=True)
    return EXIT_OK if c["ok"] == result.n_input else EXIT_FAILURES


def add_parser(sub: Any) -> None:
    """Register ``audit`` on the sub-parsers of :func:`occsurf.bridge.cli.build_parser`."""
    p = sub.add_parser(
        "audit",
        help="audit whole corpora of STEP/IGES files on Dask (Parquet results, resumable)",
        description=("Per file: a crash-isolated read, the inspect numbers of every face, a STEP round trip, "
                     "and the quality summary; on a local Dask cluster (one process per core) or an existing "
                     "one (--scheduler). Results: RESULTS/files/ and RESULTS/faces/ (Parquet), summary.json, "
                     "summary.html. Exit 0: all ok; 1: some files failed; 2: bad input; 130: interrupted (Ctrl-C); 143: SIGTERM."),
    )
    p.add_argument("paths", nargs="+", metavar="PATH",
                   help="STEP/IGES files, folders (recursive), glob patterns, or text files listing paths")
    p.add_argument("--out", required=True, metavar="RESULTS", help="results folder (created)")
    p.add_argument("--scheduler", metavar="ADDRESS",
                   help="a running Dask scheduler (tcp://host:8786); default: a local cluster")
    p.add_argument("--workers", type=_workers_arg, metavar="N",
                   help="local worker processes, one thread each (default: one per core)")
    p.add_argument("--timeout", type=timeout_arg, default=DEFAULT_TIMEOUT, metavar="S",
                   help=f"seconds one file may take before it is recorded 'timeout' (default {DEFAULT_TIMEOUT:g})")
    p.add_argument("--resume", action="store_true", help="skip files whose content is already in RESULTS")
    p.add_argument("--checks", type=_checks_arg, default=("inspect", "roundtrip"), metavar="LIST",
                   help="comma-separated: inspect, quality, roundtrip (default inspect,roundtrip)")
    p.add_argument("--samples", type=int, default=11, metavar="N", help="grid size of the deviation checks (default 11)")
    p.set_defaults(func=run)
