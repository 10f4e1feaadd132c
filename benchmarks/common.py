"""Shared set-up for the benchmark scripts: one BLAS thread, timing, test geometry, peers.

Import this module before NumPy: it pins every BLAS/OpenMP pool to one thread so that our
timings and the peers' (splipy and scipy call BLAS too) are comparable and repeatable on the
2-core benchmark machine.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ[_var] = "1"

import platform  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from collections.abc import Callable  # noqa: E402
from dataclasses import dataclass, field  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from occsurf.algorithms import BSplineSurface, _numba_kernels  # noqa: E402  (the installed occsurf)

SEED = 20240611


def best_of(fn: Callable[[], object], repeat: int = 7, budget: float = 3.0, min_repeat: int = 2) -> float:
    """Best wall-clock time of ``fn()`` in milliseconds (``time.perf_counter``).

    Runs at least ``min_repeat`` and at most ``repeat`` times, stopping early once ``budget``
    seconds have been spent, so slow peers are timed fewer times than fast ones.
    """
    times: list[float] = []
    spent = 0.0
    while len(times) < repeat and (len(times) < min_repeat or spent < budget):
        t0 = time.perf_counter()
        fn()
        dt = time.perf_counter() - t0
        times.append(dt)
        spent += dt
    return 1e3 * min(times)


def machine_note() -> str:
    return (f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, 1 BLAS thread; "
            f"Python {platform.python_version()}, NumPy {np.__version__}")


class numpy_path:
    """Context manager: force the pure-NumPy evaluation path (``OCCSURF_NO_NUMBA=1``)."""

    def __enter__(self) -> None:
        self._old = os.environ.get(_numba_kernels.ENV_DISABLE)
        os.environ[_numba_kernels.ENV_DISABLE] = "1"

    def __exit__(self, *exc: object) -> None:
        if self._old is None:
            del os.environ[_numba_kernels.ENV_DISABLE]
        else:
            os.environ[_numba_kernels.ENV_DISABLE] = self._old


def clamped_knots(n: int, degree: int, rng: np.random.Generator) -> np.ndarray:
    """Clamped knot vector with ``n - degree - 1`` jittered (non-uniform) interior knots."""
    m = n - degree - 1
    interior = (np.arange(1, m + 1) + rng.uniform(-0.3, 0.3, m)) / (m + 1)
    return np.r_[np.zeros(degree + 1), interior, np.ones(degree + 1)]


def test_surface(n: int = 50, degree: int = 3, rational: bool = False) -> BSplineSurface:
    """The benchmark surface: bicubic (by default) ``n x n`` net, non-uniform knots, seeded."""
    rng = np.random.default_rng(SEED)
    U = clamped_knots(n, degree, rng)
    V = clamped_knots(n, degree, rng)
    x, y = np.meshgrid(np.linspace(0, 1, n), np.linspace(0, 1, n), indexing="ij")
    P = np.stack([x, y, 0.2 * rng.standard_normal((n, n))], axis=-1)
    w = rng.uniform(0.5, 2.0, (n, n)) if rational else None
    return BSplineSurface((degree, degree), (U, V), P, w)


# ------------------------------------------------------------------------------------ peers


def splipy_surface(s: BSplineSurface):
    import splipy

    (p, q), (U, V) = s.degree, s.knots
    bu, bv = splipy.BSplineBasis(p + 1, U), splipy.BSplineBasis(q + 1, V)
    H = s.homogeneous_points  # (nu, nv, k), weights premultiplied and last, as splipy wants
    # splipy's flat control-point list runs fastest along u.
    cp = H.transpose(1, 0, 2).reshape(-1, H.shape[2])
    return splipy.Surface(bu, bv, cp.copy(), rational=s.is_rational)


def geomdl_surface(s: BSplineSurface):
    from geomdl import NURBS, BSpline

    (p, q), (U, V) = s.degree, s.knots
    g = NURBS.Surface() if s.is_rational else BSpline.Surface()
    g.degree_u, g.degree_v = p, q
    nu, nv = s.n_poles
    if s.is_rational:
        g.ctrlpts_size_u, g.ctrlpts_size_v = nu, nv
        g.ctrlptsw = s.homogeneous_points.reshape(-1, s.dim + 1).tolist()  # (w x, w), v fastest
    else:
        g.ctrlpts2d = s.control_points.tolist()
    g.knotvector_u, g.knotvector_v = U.tolist(), V.tolist()
    return g


def occ_surface(s: BSplineSurface):
    from occsurf.bridge import to_occ

    return to_occ(s)


def bisplev_tcks(s: BSplineSurface) -> list:
    """FITPACK ``tck`` lists, one per coordinate (``bisplev`` takes scalar coefficients)."""
    (p, q), (U, V) = s.degree, s.knots
    P = s.control_points
    return [[U, V, P[:, :, c].ravel(), p, q] for c in range(P.shape[2])]


@dataclass
class Row:
    """One benchmark case: our time and the peers' (ms); ``None`` = not run."""

    case: str
    ours: float
    ours_numpy: float | None = None
    peers: dict[str, float | None] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)


def _ms(t: float) -> str:
    """Milliseconds with three significant digits, without exponents."""
    if t >= 100:
        return f"{t:.0f}"
    return f"{t:.3g}" if t >= 0.001 else f"{t:.1g}"


def print_table(rows: list[Row], peer_names: list[str]) -> None:
    head = ["case", "ours", "ours (NumPy path)"] + peer_names
    lines = [head]
    for r in rows:
        cells = [r.case, _ms(r.ours), "-" if r.ours_numpy is None else _ms(r.ours_numpy)]
        for name in peer_names:
            t = r.peers.get(name)
            cells.append("-" if t is None else f"{_ms(t)} ({t / r.ours:.{1 if t / r.ours >= 1 else 2}f}x)")
        lines.append(cells)
    widths = [max(len(line[i]) for line in lines) for i in range(len(head))]
    print("times in ms, best of N; (ratio) = peer time / our time")
    print("| " + " | ".join(h.ljust(w) for h, w in zip(head, widths)) + " |")
    print("|" + "|".join("-" * (w + 2) for w in widths) + "|")
    for line in lines[1:]:
        print("| " + " | ".join(c.ljust(w) for c, w in zip(line, widths)) + " |")
    notes = [f"- {r.case}: {n}" for r in rows for n in r.notes]
    if notes:
        print("\n".join(["", "notes:"] + notes))


def check_targets(targets: list[tuple[str, float, float]]) -> bool:
    """Print PASS/FAIL for ``(label, achieved ratio, required ratio)``; True if all pass."""
    ok = True
    print("\ntargets:")
    for label, got, need in targets:
        passed = got >= need
        ok &= passed
        print(f"  {'PASS' if passed else 'FAIL'}  {label}: {got:.2f}x (need >= {need:g}x)")
    return ok


def max_dev(a: np.ndarray, b: np.ndarray) -> float:
    """Largest deviation relative to the magnitude of ``b`` (agreement of a peer with us)."""
    return float(np.max(np.abs(np.asarray(a) - np.asarray(b))) / max(float(np.max(np.abs(b))), 1e-300))


def kernel_load_time() -> float:
    """Seconds of a fresh interpreter's first 1e5-point evaluation: importing numba, loading our
    cached kernel and the evaluation itself (about 7 ms of it)."""
    import subprocess

    code = (
        "import os, time; os.environ['OMP_NUM_THREADS']='1'\n"
        "import numpy as np\n"
        "from algorithms import BSplineSurface\n"
        "s = BSplineSurface((3, 3), ([0]*4 + [1]*4, [0]*4 + [1]*4), np.zeros((4, 4, 3)))\n"
        "u = np.linspace(0, 1, 100000)\n"
        "t = time.perf_counter(); s.evaluate(u, u); print(time.perf_counter() - t)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         cwd=Path(__file__).resolve().parents[1], check=True)
    return float(out.stdout.strip().splitlines()[-1])
