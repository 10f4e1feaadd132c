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
from collections.abc import Iterator
from typing import Any

__all__ = ["ClusterError", "open_client", "default_workers", "dashboard_available"]


class ClusterError(ConnectionError):
    """The scheduler cannot be reached, or the local cluster cannot start."""


def default_workers() -> int:
    """One worker per usable core (the process's CPU affinity, else ``os.cpu_count()``)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):
        return max(1, os.cpu_count() or 1)


def dashboard_available() -> bool:
    """The Dask dashboard needs ``bokeh``; without it there is no dashboard link."""
    return importlib.util.find_spec("bokeh") is not None


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
    try:
        with _sigint_ignored():  # inherited by the worker processes: see _sigint_ignored
            cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                                   dashboard_address=":0" if dashboard_available() else None,
                                   silence_logs=logging.ERROR)
    except Exception as err:  # noqa: BLE001 - any start-up failure is one line for the user
        raise ClusterError(f"cannot start a local Dask cluster of {n} workers: {err}") from err
    return Client(cluster, set_as_default=False), cluster


@contextlib.contextmanager
def _sigint_ignored() -> Iterator[None]:
    """Ignore SIGINT while the local workers are spawned, so that they inherit "ignored".

    Ctrl-C in a terminal signals the whole process group. The client handles it (flushes the
    finished rows, closes the cluster); workers that also took it would die mid-task with a
    traceback each. A signal ignored at exec stays ignored, and Python then installs no
    KeyboardInterrupt handler of its own. Only the main thread may change handlers: elsewhere
    this does nothing.
    """
    try:
        old = signal.signal(signal.SIGINT, signal.SIG_IGN)
    except ValueError:
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, old)
