"""Check several STEP/IGES files at once, in worker processes (``occsurf check --jobs N``).

:func:`check_files` runs :func:`occsurf.bridge.quality.check_files.check_job` on every item, as
:func:`~occsurf.bridge.quality.check_files.run_checks` does one file after the other, but in ``jobs``
persistent reader processes (:class:`occsurf.bridge.audit.reader.Reader`: OCC imported once per
reader) fed from a thread pool (:class:`concurrent.futures.ThreadPoolExecutor`), a file at a time:
a reader takes the next file as soon as it is free, so a long file does not hold up the others (OCC
is not thread-safe, so the checking is in the processes, the threads only wait for them:
:func:`~occsurf.bridge.audit.reader.on_free_readers`, shared with ``fill --jobs``). A file
whose reader crashes is checked again without the piece at fault
(:func:`~occsurf.bridge.quality.check_files.rerun_without_fault`, from the item's ``trace`` file), up to
:data:`~occsurf.bridge.quality.check_files.MAX_RETRIES` times, as by ``run_checks``; its outcome is
worded as ``run_jobs`` words it (:meth:`Reader.outcome`), so a failure reads the same with any
number of jobs. Ctrl-C stops every reader at once.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any

from ..isolation import Outcome
from ..quality.check_files import CHECK_JOB, MAX_RETRIES, PRELOAD, rerun_without_fault
from .reader import Reader, on_free_readers

__all__ = ["check_files"]


def check_files(items: list[dict[str, Any]], *, jobs: int, timeout: float | None,
                on_outcome: Callable[[int, Outcome], None] | None = None, job: str | None = None) -> list[Outcome]:
    """Run :func:`~occsurf.bridge.quality.check_files.check_job` on every item in ``jobs`` reader
    processes at once (see the module).

    Parameters
    ----------
    items : list of dict
        ``check_job``'s items. An item run again is replaced in this list by a copy whose ``skip``
        names what was left out (so the caller can report it), before its outcome is reported.
    jobs : int
        Reader processes (at most one per item).
    timeout : float or None
        Seconds a reader may take per item (its start-up not counted).
    on_outcome : callable, optional
        ``on_outcome(k, outcome)`` with each item's final outcome as soon as it is known: one call
        at a time, in the order the items finish.
    job : str, optional
        The job's ``"module:function"`` (default :data:`~occsurf.bridge.quality.check_files.CHECK_JOB`).

    Returns
    -------
    list of Outcome
        The final outcomes, in the order of ``items`` (``index``: the item's position).

    Raises
    ------
    ValueError
        ``jobs`` not a positive whole number.
    """
    if isinstance(jobs, bool) or not isinstance(jobs, int) or jobs < 1:
        raise ValueError(f"jobs: expected a positive number of worker processes, got {jobs!r}")
    spec = CHECK_JOB if job is None else job
    readers = [Reader(tuple(PRELOAD)) for _ in range(max(1, min(jobs, len(items))))]
    lock = threading.Lock()

    def check(reader: Reader, k: int) -> Outcome | None:
        for attempt in range(MAX_RETRIES + 1):
            o = reader.outcome(spec, items[k], timeout, index=k)  # a crashed reader starts again here
            rerun = rerun_without_fault(items[k], o) if attempt < MAX_RETRIES else None
            if rerun is not None:
                items[k] = rerun
                continue
            if on_outcome is not None:
                with lock:
                    on_outcome(k, o)
            return o
        return None  # not reached: the last attempt always reports

    try:
        outcomes = on_free_readers(readers, len(items), check, lambda k: None, name="check")
    finally:
        for r in readers:
            r.stop()
    return [o for o in outcomes if o is not None]
