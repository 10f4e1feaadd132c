"""The Dask cluster an audit runs on: a ``LocalCluster`` sized to the machine, or an existing one.

OCC is not thread-safe and a crash must cost one file: the local cluster has one worker *process*
per core, one thread each. ``--scheduler tcp://host:8786`` connects to a cluster started with
``dask scheduler`` and ``dask worker`` instead; the tasks are the same, so are the results. (The
OCC work itself runs in a reader process below each worker thread, :mod:`.reader`, so even a
worker started with several threads is safe.)
"""

from __future__ import annotations

import contextlib
import importlib.util
import logging
import os
import signal
import threading
from collections.abc import Iterator
from typing import Any

__all__ = ["ClusterError", "open_client", "default_workers", "dashboard_available", "dashboard_link"]

#: Where a local cluster serves its dashboard: this machine only (loopback), on a free port. An
#: existing cluster's scheduler serves its own (``dask scheduler --dashboard-address``).
LOCAL_DASHBOARD = "127.0.0.1:0"


class ClusterError(ConnectionError):
    """The scheduler cannot be reached, or the local cluster cannot start."""


def default_workers() -> int:
    """One worker per usable core (the process's CPU affinity, else ``os.cpu_count()``)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):
        return max(1, os.cpu_count() or 1)


def dashboard_available() -> bool:
    """A local cluster's Dask dashboard needs ``bokeh`` here (declared with ``occsurf[audit]``);
    without it the local cluster runs without one."""
    return importlib.util.find_spec("bokeh") is not None


def dashboard_link(client: Any, probe_timeout: float = 5.0, *, probe: bool = True) -> str | None:
    """The dashboard's address (``http://host:port/status``) when the scheduler serves one, else None.

    Asked of the scheduler, not of this machine: a scheduler started elsewhere may serve a
    dashboard although bokeh is not installed here. Its HTTP service runs even without the
    dashboard (``dask scheduler --no-dashboard`` keeps ``/health`` and ``/metrics``), so the page
    itself is asked for: a 404 means no dashboard. A page that cannot be reached from here (a
    firewall, a tunnel) is still reported: the scheduler says it serves one.

    ``probe=False`` does not ask for the page: for the local cluster of :func:`open_client`, started
    here, whose dashboard is there exactly when bokeh is (:func:`dashboard_available`; without it the
    scheduler still lists its HTTP service as "dashboard", and the page is a 404). Its scheduler runs
    in this process, and drawing the page for the probe held the audit's start ~0.3 s.
    """
    import urllib.error
    import urllib.request

    try:
        if "dashboard" not in client.scheduler_info().get("services", {}):
            return None
        link = str(client.dashboard_link)
    except Exception:  # noqa: BLE001 - no answer: no link (the audit itself reports the scheduler)
        return None
    if not probe:
        return link if dashboard_available() else None
    try:
        with urllib.request.urlopen(link, timeout=probe_timeout):
            return link
    except urllib.error.HTTPError:  # the HTTP service answers, but without a dashboard page
        return None
    except (OSError, ValueError):  # not reachable from here: report what the scheduler says
        return link


def open_client(scheduler: str | None = None, workers: int | None = None,
                connect_timeout: float = 10.0) -> tuple[Any, Any]:
    """``(client, cluster)``: a client of ``scheduler``, or of a new ``LocalCluster`` (``cluster``
    is then returned so the caller closes it; ``None`` for an existing scheduler).

    Raises
    ------
    ClusterError
        The scheduler does not answer within ``connect_timeout`` seconds, or the local cluster
        does not start.
    """
    from distributed import Client, LocalCluster

    if scheduler is not None:
        try:
            return Client(scheduler, timeout=f"{connect_timeout}s", set_as_default=False), None
        except (OSError, TimeoutError, ValueError) as err:
            raise ClusterError(f"--scheduler {scheduler}: cannot connect ({type(err).__name__}: "
                               f"{' '.join(str(err).split()) or 'no answer'})") from err
    n = workers or default_workers()
    # The workers' own logs: CRITICAL only. What goes wrong with a file is its row; at an interrupt, a
    # worker whose heartbeat meets the closing scheduler logged an ERROR with two tracebacks.
    try:
        with _sigint_blocked_for_workers():  # inherited by the worker processes: see there
            cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                                   dashboard_address=LOCAL_DASHBOARD if dashboard_available() else None,
                                   silence_logs=logging.CRITICAL)
    except Exception as err:  # noqa: BLE001 - any start-up failure is one line for the user
        raise ClusterError(f"cannot start a local Dask cluster of {n} workers: {err}") from err
    return Client(cluster, set_as_default=False), cluster


@contextlib.contextmanager
def _sigint_blocked_for_workers() -> Iterator[None]:
    """Block SIGINT in this thread while the local workers are spawned, so that they are born with it
    blocked, and stay so: Ctrl-C in a terminal signals the whole process group, and a worker that
    took it would die mid-task with a traceback. This process still takes it: a Ctrl-C during the
    start-up (about 2 s) waits, blocked, and is handled as the block ends (:func:`held_signals`).

    A thread inherits the mask of the thread that starts it, a spawned process that of the thread
    that forks it; Dask's IO-loop thread is started here, and it starts the threads that spawn the
    workers. Blocking alone did not reach the workers before, because ``multiprocessing``'s resource
    tracker, started on first use from that IO-loop thread, unblocks SIGINT and SIGTERM in its
    caller when it is done (``resource_tracker.ensure_running``: block, spawn, then SIG_UNBLOCK, not
    a restore). It is started here first, while nothing is blocked; the workers use the same one.
    (Ignoring SIGINT instead, which the workers inherit too, lost a Ctrl-C during the start-up.)
    Main thread only, and only where ``pthread_sigmask`` exists: elsewhere this does nothing.
    """
    if not hasattr(signal, "pthread_sigmask") or threading.current_thread() is not threading.main_thread():
        yield
        return
    from multiprocessing import resource_tracker

    resource_tracker.ensure_running()
    old = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)


@contextlib.contextmanager
def held_signals() -> Iterator[None]:
    """Hold SIGINT and SIGTERM back for the block (a cluster's start-up), then deliver them.

    A ``KeyboardInterrupt`` raised inside ``LocalCluster(...)`` leaves a half-started cluster that
    Dask's exit hook then fails to close, with a traceback. Here a signal is recorded while the
    block runs and sent again to the handlers in place before it, once the block is done (the
    caller has its cluster by then and closes it). A SIGINT while the workers spawn waits blocked
    (:func:`_sigint_blocked_for_workers`) and is held here as the mask is restored.
    Main thread only: elsewhere this does nothing.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    got: list[int] = []

    def record(signum: int, frame: Any) -> None:
        got.append(signum)

    old = {s: signal.signal(s, record) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield
    finally:
        for s, h in old.items():
            signal.signal(s, h)
        for signum in dict.fromkeys(got):
            signal.raise_signal(signum)
