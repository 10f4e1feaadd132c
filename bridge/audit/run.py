"""The audit driver: corpus in, tasks on Dask, rows into RESULTS as they finish.

The client keeps a bounded window of tasks in flight (:data:`WINDOW_PER_WORKER` per worker
thread), so a million-file corpus costs the scheduler a few hundred tasks at a time, not a million.
Results are written by this process alone (:class:`.store.ResultStore`): a task that Dask runs
again after its worker died (``allowed-failures``) still gives one row. A task whose workers kept
dying (:class:`distributed.KilledWorker`) is recorded as ``crashed`` with that reason.
"""

from __future__ import annotations

import math
import sys
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, TextIO

from ..isolation import MAX_TIMEOUT
from .corpus import Entry, expand_paths, hash_entries
from .store import ResultStore
from .tasks import CHECKS, DEFAULT_CHECKS, audit_task, make_item

__all__ = ["AuditResult", "AuditInputError", "audit", "Progress", "STATUSES", "WINDOW_PER_WORKER"]

STATUSES = ("ok", "error", "crashed", "timeout")
#: Tasks kept in flight per worker thread (enough to hide the scheduler's round trip).
WINDOW_PER_WORKER = 4
DEFAULT_SAMPLES = 11


class AuditInputError(ValueError):
    """An argument of :func:`audit` out of range (checks, timeout, workers)."""


@dataclass
class AuditResult:
    """What one run did: ``counts`` per status over the whole input (earlier runs included with
    ``resume``), ``skipped`` (already in RESULTS), ``interrupted``, ``dashboard`` link if any."""

    n_input: int
    counts: dict[str, int]
    skipped: int
    seconds: float
    interrupted: bool = False
    dashboard: str | None = None
    hashes: list[str | None] = field(default_factory=list)


class Progress:
    """Progress lines on a stream: done/failed/remaining, rate and ETA, at most every ``every`` s."""

    def __init__(self, total: int, stream: TextIO | None = sys.stderr, every: float = 2.0) -> None:
        self.total, self.stream, self.every = total, stream, every
        self.counts = dict.fromkeys(STATUSES, 0)
        self.t0 = self._last = time.monotonic()
        self.new = 0

    def add(self, status: str, new: bool = True) -> None:
        self.counts[status] += 1
        self.new += new
        if time.monotonic() - self._last >= self.every:
            self.show()

    def line(self) -> str:
        done = sum(self.counts.values())
        elapsed = max(time.monotonic() - self.t0, 1e-9)
        rate = self.new / elapsed
        left = self.total - done
        eta = f"{left / rate:.0f} s" if rate > 0 else "?"
        c = self.counts
        return (f"audit: {done}/{self.total} files: {c['ok']} ok, {c['error']} failed, {c['crashed']} crashed, "
                f"{c['timeout']} timeout; {left} remaining; {rate:.2f} files/s; ETA {eta}")

    def show(self) -> None:
        self._last = time.monotonic()
        if self.stream is not None:
            print(self.line(), file=self.stream, flush=True)


def _rows(entry: Entry, res: dict[str, Any], run_id: str) -> tuple[dict[str, Any], list[dict[str, Any]]]:
    """The files row and face rows of one task result."""
    faces = [dict(f, sha256=entry.sha256) for f in res.get("faces", ())]
    devs = [f["max_dev"] for f in faces if f.get("max_dev") is not None]
    rts = [f["roundtrip_dev"] for f in faces if f.get("roundtrip_dev") is not None]
    q = res.get("quality") or {}
    row = {
        "path": entry.path, "sha256": entry.sha256, "size": entry.size, "format": res.get("format"),
        "status": res["status"], "error": res.get("error"), "signal": res.get("signal"),
        "exit_code": res.get("exit_code"), "n_faces": res.get("n_faces", len(faces)) if res["status"] == "ok" else None,
        "n_free_form": sum(f.get("type") in ("BSplineSurface", "BezierSurface") for f in faces) if faces else None,
        "max_dev": max(devs) if devs else None, "roundtrip_status": res.get("roundtrip_status"),
        "roundtrip_max_dev": max(rts) if rts else None,
        "roundtrip_inexact": sum(f.get("roundtrip_exact") is False for f in faces) if rts else None,
        "quality_status": res.get("quality_status"), "quality_worst_g1_deg": q.get("worst_g1_deg"),
        "quality_curvature_spikes": q.get("curvature_spikes"),
        "quality_flags": ",".join(q.get("flags", ())) or None if q else None,
        "seconds": res.get("seconds"), "worker": res.get("worker"), "run_id": run_id,
        "finished": time.time() * 1000.0,
    }
    row["finished"] = int(row["finished"])
    return row, faces


def _failure(entry: Entry, err: BaseException) -> dict[str, Any]:
    """A task that Dask itself gave up on (its workers died: KilledWorker)."""
    from distributed import KilledWorker

    from ..messages import error_line

    if isinstance(err, KilledWorker):
        why = f"the Dask worker running it died each time it was tried (KilledWorker: {' '.join(str(err).split())[:300]})"
        return {"status": "crashed", "error": why, "signal": None}
    return {"status": "error", "error": f"task failed: {error_line(err)}"}


def _check_args(checks: Sequence[str], timeout: float | None, workers: int | None) -> tuple[str, ...]:
    bad = [c for c in checks if c not in CHECKS]
    if bad or not checks:
        raise AuditInputError(f"checks: expected a comma-separated subset of {','.join(CHECKS)}, got {','.join(checks)!r}")
    if timeout is not None and not (math.isfinite(timeout) and timeout > 0):
        raise AuditInputError(f"timeout: expected a positive number of seconds, got {timeout!r}")
    if timeout is not None and timeout > MAX_TIMEOUT:
        raise AuditInputError(f"timeout: at most {MAX_TIMEOUT:g} seconds, got {timeout!r}")
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int) or workers < 1):
        raise AuditInputError(f"workers: expected a positive integer, got {workers!r}")
    return tuple(c for c in CHECKS if c in checks)


def audit(paths: Sequence[str], out: str, *, scheduler: str | None = None, workers: int | None = None,
          timeout: float | None = 300.0, resume: bool = False, checks: Sequence[str] = DEFAULT_CHECKS,
          samples: int = DEFAULT_SAMPLES, progress: TextIO | None = sys.stderr,
          on_dashboard: Callable[[str], None] | None = None, flush_seconds: float = 2.0,
          stop: threading.Event | None = None) -> AuditResult:
    """Audit every STEP/IGES file of ``paths`` on Dask and write RESULTS ``out``.

    Parameters
    ----------
    paths : sequence of str
        Files, folders (recursive), glob patterns, list files (:func:`.corpus.expand_paths`).
    out : str
        RESULTS folder: ``files/``, ``faces/`` (Parquet), ``summary.json``, ``summary.html``.
    scheduler : str, optional
        Address of a running Dask scheduler; default a ``LocalCluster`` of ``workers`` processes.
    workers : int, optional
        Local worker processes (one thread each); default one per core. Ignored with ``scheduler``.
    timeout : float or None
        Seconds one file may take in its reader before it is recorded ``timeout``.
    resume : bool
        Skip files whose content hash is already in RESULTS.
    checks : sequence of str
        Any of ``inspect``, ``quality``, ``roundtrip``.
    samples : int
        Grid size of the per-face deviation checks.
    stop : threading.Event, optional
        Set (by a signal handler, say) to end the run as an interrupt does, at the next file that
        finishes, even where the ``KeyboardInterrupt`` itself was swallowed (inside Dask's callbacks).

    Returns
    -------
    AuditResult

    Raises
    ------
    CorpusError, StoreError, ClusterError, AuditInputError
        Bad input (nothing audited).
    KeyboardInterrupt
        Not raised: an interrupted run flushes what finished and returns ``interrupted=True``.
    """
    checks = _check_args(tuple(checks), timeout, workers)
    entries = expand_paths(paths)  # every refusal (corpus, --out, scheduler) before the long work
    store = ResultStore(out, resume=resume, flush_seconds=flush_seconds)
    from .cluster import dashboard_link, held_signals, open_client

    t0 = time.monotonic()
    dashboard = None
    client = cluster = None
    try:
        with held_signals():  # a signal during start-up: delivered once the cluster is ours to close
            client, cluster = open_client(scheduler, workers)
        # first: the dashboard shows the cluster from the start; a local cluster's page is ours (not probed)
        dashboard = dashboard_link(client, probe=cluster is None)
        if dashboard is not None and on_dashboard is not None:
            on_dashboard(dashboard)
        if progress is not None:
            print(f"audit: {len(entries)} files; hashing their contents", file=progress, flush=True)
        hash_entries(entries, timeout=timeout)  # under --timeout too: a hung read is a timeout row
        bar = Progress(len(entries), progress)
        skipped, interrupted = _drive(client, entries, store, bar, checks, samples, timeout, stop)
    finally:
        store.flush()
        if client is not None:
            client.close()
        if cluster is not None:
            cluster.close()
    counts = dict.fromkeys(STATUSES, 0)
    for e in entries:
        status = store.done.get(e.sha256) if e.sha256 else (_unread_status(e) if e.error else None)
        if status is not None:  # None: not reached before an interruption
            counts[status] += 1
    if not interrupted:
        from .summary import write_summary

        write_summary(store.out, [e.sha256 for e in entries if e.sha256], n_input=len(entries),
                      unreadable=[e for e in entries if e.sha256 is None])
    bar.show()
    return AuditResult(len(entries), counts, skipped, time.monotonic() - t0, interrupted, dashboard,
                       [e.sha256 for e in entries])


def _unread_status(e: Entry) -> str:
    """The status of a file that was not read: ``timeout`` if hashing it passed ``--timeout``."""
    return "timeout" if e.timed_out else "error"


def _drive(client: Any, entries: list[Entry], store: ResultStore, bar: Progress, checks: tuple[str, ...],
           samples: int, timeout: float | None, stop: threading.Event | None = None) -> tuple[int, bool]:
    """Submit a bounded window of tasks, record results as they come; returns (skipped, interrupted)."""
    from distributed import as_completed

    by_hash: dict[str, list[Entry]] = {}
    skipped = 0
    for e in entries:
        if e.sha256 is None:  # unreadable: recorded at once, redone by a later --resume
            store.add({"path": e.path, "sha256": None, "status": _unread_status(e), "error": e.error, "run_id": store.run_id,
                       "finished": int(time.time() * 1000)})
            bar.add(_unread_status(e))
        elif e.sha256 in store.done:
            skipped += 1
            bar.add(store.done[e.sha256], new=False)
        else:
            by_hash.setdefault(e.sha256, []).append(e)
    todo = list(by_hash)
    threads = max(1, sum(client.nthreads().values())) if todo else 1
    window = max(8, WINDOW_PER_WORKER * threads)
    pending = iter(todo)
    futures: dict[Any, str] = {}

    def submit(n: int) -> list[Any]:
        new = []
        for _ in range(n):
            h = next(pending, None)
            if h is None:
                break
            item = make_item(by_hash[h][0].path, h, checks, samples, timeout)
            fut = client.submit(audit_task, item, key=f"occsurf-audit-{h[:20]}-{store.run_id}", pure=False)
            futures[fut] = h
            new.append(fut)
        return new

    if not todo:
        return skipped, False
    try:
        if stop is not None and stop.is_set():
            raise KeyboardInterrupt
        ac = as_completed(submit(window), with_results=False, loop=client.loop)
        for fut in ac:
            if stop is not None and stop.is_set():  # the interrupt was swallowed somewhere: stop here
                raise KeyboardInterrupt
            h = futures.pop(fut)
            try:
                res = fut.result()
            except Exception as err:  # noqa: BLE001 - KilledWorker and the like: recorded, never dropped
                res = _failure(by_hash[h][0], err)
            fut.release()
            for i, e in enumerate(by_hash[h]):
                row, faces = _rows(e, res, store.run_id)
                store.add(row, faces if i == 0 else [])
                bar.add(row["status"])
            store.maybe_flush()
            for new in submit(1):
                ac.add(new)
    except KeyboardInterrupt:
        return skipped, True
    return skipped, False
