"""Compile occsurf's numba kernels into their on-disk cache before a test session's workers start.

On a machine where the cache is empty (every CI run: a fresh virtualenv, the package installed with
its ``__pycache__`` empty), each pytest-xdist worker and every command-line process a test starts
compiled the kernels it met first for itself: the fast lane took 5 min 48 s with the cache empty
against 3 min 15 s with it full (2026-12-07, the 2-core machine). :func:`warm` runs every kernel
once through the library's own calls, on small inputs (``NUMBA_MIN_POINTS`` overridden), so the
argument types are the ones the library passes (a check of the OCCT bearing and of
``step_samples/`` compiles nothing after it). ``tests/conftest.py`` calls it in an xdist run's
controller, in one process (two processes sharing the calls lost a signature to a race on numba's
index file); ``python -m tests.numba_warmup`` runs it alone. Results of the kernels are not looked
at here: ``test_fast_paths.py`` compares them with the NumPy paths."""

from __future__ import annotations

import numpy as np


def _curve(rational: bool):
    from occsurf.algorithms import BSplineCurve

    t = np.r_[[0.0] * 4, 0.3, 0.6, [1.0] * 4]
    P = np.random.default_rng(1).random((6, 3))
    return BSplineCurve(3, t, P, np.linspace(0.7, 1.3, 6) if rational else None)


def _surface(rational: bool):
    from occsurf.algorithms import BSplineSurface

    ku = np.r_[[0.0] * 4, 0.3, 0.6, [1.0] * 4]
    kv = np.r_[[0.0] * 3, 0.5, [1.0] * 3]
    P = np.random.default_rng(2).random((6, 4, 3))
    return BSplineSurface((3, 2), (ku, kv), P, np.full((6, 4), 1.1) if rational else None)


def _jobs():
    """(name, call) for every kernel signature the library uses."""
    from occsurf.algorithms.fitting._common import project_points

    x = np.linspace(0.0, 1.0, 50)
    jobs = []
    for rational in (False, True):
        c, s = _curve(rational), _surface(rational)
        jobs += [
            (f"curve points {rational}", lambda c=c: c.evaluate(x)),
            (f"curve derivatives {rational}", lambda c=c: c.derivatives(x, 2)),
            (f"surface points {rational}", lambda s=s: s.evaluate(x, x[::-1])),
            (f"surface derivatives {rational}", lambda s=s: s.derivatives(x, x[::-1], 2)),
            (f"grid partials {rational}", lambda s=s: s.derivatives_grid(x, x, 2)),
        ]
    s = _surface(False)
    X = s.evaluate(x, x) + 1e-3
    jobs.append(("surface project", lambda: project_points(s, X, x, x)))
    return jobs


def warm() -> list[str]:
    """Run every kernel signature once; returns their names."""
    from occsurf.algorithms import _numba_kernels as nk
    from occsurf.algorithms import tolerances

    if not nk.enabled() or nk.load() is None:
        return []
    done = []
    with tolerances.override(NUMBA_MIN_POINTS=0):
        for name, call in _jobs():
            call()
            done.append(name)
    return done


if __name__ == "__main__":
    print(", ".join(warm()))
