"""Hypothesis profiles of the whole suite, registered here once.

Every property test takes its settings from :func:`tests.algorithms.strategies.test_settings`,
which gives it its own ``max_examples`` (the counts written in the tests) times the *scale* of the
active profile: that profile's ``max_examples`` divided by 100, Hypothesis' own default.

Profiles
--------
``default``
    Hypothesis' built-in profile, unchanged: scale 1, every count as written in the tests.
``ci``
    Hypothesis' built-in ``ci`` profile, unchanged (derandomized, no example database, failing
    examples printed as a blob to replay): scale 1. Hypothesis selects it by itself when the
    ``CI`` environment variable is set (CI services set it; ``.ci/run`` does not, so it runs the
    ``default`` profile: ``CI=1 .ci/run`` gives the derandomized run).
``thorough``
    A deep run: scale 25 (a test written with 40 examples runs 1000), no deadline, failing
    examples printed as a blob.

Selection, first that applies: pytest's ``--hypothesis-profile=NAME`` (Hypothesis' plugin);
``HYPOTHESIS_PROFILE=NAME pytest ...``; ``ci`` under CI and ``default`` elsewhere (Hypothesis' own
choice). ``OCCSURF_HYPOTHESIS_SCALE=K`` (kept from before the profiles) gives the profile chosen by
the environment the scale ``K``, e.g. ``OCCSURF_HYPOTHESIS_SCALE=40 pytest tests/algorithms/test_curve.py``.
"""

from __future__ import annotations

import os

import pytest
from hypothesis import HealthCheck, settings
from hypothesis.errors import InvalidArgument

#: Hypothesis' default ``max_examples``; a profile's ``max_examples`` over this is its scale.
BASE_EXAMPLES = 100
#: Scale of the ``thorough`` profile ("default" and "ci" have scale 1).
THOROUGH_SCALE = 25

# "default" and "ci" are Hypothesis' built-in profiles, kept as they are; only "thorough" is new.
try:
    settings.get_profile("ci")
except InvalidArgument:  # a Hypothesis older than its built-in "ci": the same settings
    settings.register_profile("ci", derandomize=True, deadline=None, database=None, print_blob=True,
                              suppress_health_check=[HealthCheck.too_slow])
settings.register_profile("thorough", settings.get_profile("default"),
                          max_examples=BASE_EXAMPLES * THOROUGH_SCALE, deadline=None,
                          print_blob=True)

_name = os.environ.get("HYPOTHESIS_PROFILE")
if _name:
    settings.load_profile(_name)  # an unknown name fails here, naming it
_scale = os.environ.get("OCCSURF_HYPOTHESIS_SCALE")
if _scale:  # the selected profile (settings() inherits it) with another scale
    settings.register_profile("scaled", settings(), max_examples=max(1, round(BASE_EXAMPLES * float(_scale))))
    settings.load_profile("scaled")


# A suite started in the background by a shell without job control (``nohup ... &``, some CI
# runners) inherits SIGINT *ignored*, and every process it starts inherits that too (an ignored
# signal stays ignored across exec; Python then installs no KeyboardInterrupt handler). The tests
# that press Ctrl-C on an ``occsurf`` process would then see it ignored, which is right for such a
# process but not what they test. The suite's own process takes Python's handler back, so its
# children start with SIGINT at its default, as from a terminal.
def _restore_sigint() -> None:
    import signal

    if signal.getsignal(signal.SIGINT) == signal.SIG_IGN:
        signal.signal(signal.SIGINT, signal.default_int_handler)


_restore_sigint()


# BLAS threads: NumPy's and SciPy's OpenBLAS start one thread per core in every process. Under
# pytest-xdist each worker is a process, so on the 2-core machine two workers ran four BLAS threads
# that busy-wait for each other (OpenBLAS spins between calls): ``tests/algorithms -m "not slow"
# -n auto`` took 66-67 s against 52-54 s with one thread per worker (2026-12-07, two alternating
# runs each). Each worker takes its share of the cores, for itself (threadpoolctl: the libraries
# may be loaded by now) and for the processes it starts (the variables are read when they load
# BLAS). A run without xdist keeps every core; thread counts set in the environment are kept.
_BLAS_VARS = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")
_BLAS_LIMIT: list[object] = []


def _blas_threads_per_worker() -> None:
    workers = os.environ.get("PYTEST_XDIST_WORKER_COUNT")
    if not workers or not os.environ.get("PYTEST_XDIST_WORKER") or any(v in os.environ for v in _BLAS_VARS):
        return
    threads = max(1, (os.cpu_count() or 1) // max(1, int(workers)))
    for var in _BLAS_VARS:
        os.environ[var] = str(threads)
    from threadpoolctl import threadpool_limits

    # kept: the limiter restores the old limits only when asked to
    _BLAS_LIMIT.append(threadpool_limits(limits=threads, user_api="blas"))


_blas_threads_per_worker()


# Worker processes (occsurf.bridge.isolation, the audit reader, the CLI's checker) run test jobs that
# live in this folder (``tests.bridge.isolation_jobs:...``). occsurf itself is the installed package
# (the checkout has no ``occsurf/`` folder at its top to shadow it), so the children need the
# checkout on PYTHONPATH only to import ``tests``; isolation.worker_env keeps what is there.
_REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
if _REPO not in os.environ.get("PYTHONPATH", "").split(os.pathsep):
    os.environ["PYTHONPATH"] = os.pathsep.join(p for p in (_REPO, os.environ.get("PYTHONPATH")) if p)


# numba's kernels are compiled on a machine's first use into their on-disk cache. With that cache
# empty (every CI run: a fresh virtualenv) each xdist worker, and every command-line process a test
# started, compiled the kernels it met for itself: the fast lane took 5 min 48 s against 3 min 15 s
# with the cache full (2026-12-07). The controller of an xdist run compiles them all once (~21 s on
# the 2-core machine; ~1 s to find them cached) before its workers start (tests/numba_warmup.py).
def pytest_configure(config: pytest.Config) -> None:
    if hasattr(config, "workerinput") or not getattr(config.option, "numprocesses", None):
        return  # a worker, or a run without xdist
    from tests.numba_warmup import warm

    try:
        warm()
    except Exception:  # noqa: BLE001 - only a head start: the tests meet (and report) whatever failed here
        pass
