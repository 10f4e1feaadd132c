"""How many threads the BLAS under NumPy and SciPy may use while occsurf factors its systems.

OpenBLAS starts one thread per core and its threads wait for each other by spinning. The systems
occsurf factors are many and small or middling (the fronts of a plate's nested dissection, the
SVDs of a surface match), and there a second thread costs more than it brings; when another
process keeps a core busy, it costs far more: the OCCT bearing's refill of faces 171 and 185 (a
G1 plate, 42 factorisations) took 4.8 s with one BLAS thread and 266-349 s with the default two
beside one busy process on the 2-core machine (2026-12-08). :func:`blas_threads` limits the
thread pools for the duration of a block, whichever BLAS NumPy and SciPy carry (threadpoolctl).
"""

from __future__ import annotations

from contextlib import AbstractContextManager, nullcontext
from typing import Any

__all__ = ["blas_threads", "FACTOR_BLAS_THREADS"]

#: BLAS threads while occsurf factors and solves its systems (:func:`blas_threads`'s default).
FACTOR_BLAS_THREADS: int = 1

_CONTROLLER: list[Any] = []


def blas_threads(limit: int = FACTOR_BLAS_THREADS) -> AbstractContextManager[Any]:
    """A context in which the BLAS libraries NumPy and SciPy loaded use at most ``limit`` threads.

    threadpoolctl's view of the loaded libraries is taken once (scanning them costs ~6.5 ms;
    entering and leaving the limit ~8 us), after SciPy's LAPACK is loaded (SciPy carries an
    OpenBLAS of its own beside NumPy's). threadpoolctl is a dependency of occsurf, but
    ``occsurf.algorithms`` needs NumPy and SciPy alone: without it the context limits nothing.
    """
    if not _CONTROLLER:
        import scipy.linalg  # noqa: F401  (its OpenBLAS loaded before the libraries are listed)

        try:
            from threadpoolctl import ThreadpoolController
        except ImportError:  # the algorithms on NumPy and SciPy alone: the libraries' own thread counts
            _CONTROLLER.append(None)
        else:
            _CONTROLLER.append(ThreadpoolController())
    if _CONTROLLER[0] is None:
        return nullcontext()
    return _CONTROLLER[0].limit(limits=int(limit), user_api="blas")
