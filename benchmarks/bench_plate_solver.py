"""The plate fill's sparse factorisation: ours (``kernel.grid_cholesky``) against SciPy's SuperLU.

    python benchmarks/bench_plate_solver.py [--realdata]

Every stage of a G1 plate fill solves ``K c = b`` with ``K = A^T A + eps E`` (course §8-3), one
factorisation per knot vector. The systems are recorded as the fills of this script's holes make
them, then each is factored again by both solvers in the same run:

* ours: :class:`~occsurf.algorithms.kernel.grid_cholesky.GridCholesky` (multifrontal Cholesky in the
  nested-dissection order of the coefficient grid, Jacobi-scaled), what the G1 plate uses since
  2026-12-06;
* SuperLU: ``scipy.sparse.linalg.splu`` of the Jacobi-scaled ``K`` in its symmetric mode (minimum
  degree on ``K + K^T``, diagonal pivots), what the G1 plate used before and the G2 plate still
  uses (its refinement follows the round-off of its ill-conditioned systems: see ``_SPDFactor``).

Times are the best of three factorisations (ms) and of five solves; "agree" is the largest
difference of the two solutions relative to the largest coefficient (the systems' round-off: their
condition numbers after scaling reach ~1e8). Systems that SuperLU factors with negative pivots
(indefinite to working precision) are counted, not timed.

Holes: the G1 plate of the 4- and 6-sided bump rings of ``examples/hole_models.py``
(``fill_plate`` on their sides); with ``--realdata``, linkrods face 35 refilled (bicubic G1 plates,
up to 131 x 131 coefficients; ``../shared/realdata``).
"""

from __future__ import annotations

import argparse
import datetime
import os
import time
from pathlib import Path
from typing import Any

import common  # noqa: F401 - pins BLAS threads before NumPy
import numpy as np
import scipy.sparse as sp

from occsurf.algorithms.kernel.grid_cholesky import GridCholesky, NotPositiveDefinite
from occsurf.algorithms.topology import plate_fill
from occsurf.algorithms.topology.plate_fill import fill_plate
from occsurf.bridge.exchange.step_iges import read_step
from occsurf.examples.hole_models import ring_model

ROOT = Path(__file__).resolve().parents[1]
REALDATA = ROOT.parent / "shared" / "realdata"


def record(make: Any) -> list[tuple[sp.csc_matrix, tuple[int, int], int]]:
    """The plate systems ``make()`` factors, as ``(K, (nu, nv), p)``."""
    systems = []
    factor = plate_fill._SPDFactor

    class Recorded(factor):  # type: ignore[misc, valid-type]
        def __init__(self, stencil: Any, sparse: Any) -> None:
            if stencil is not None:  # a G1 plate's (a G2 plate's system goes to SuperLU: no stencil)
                systems.append((sp.csc_matrix(sparse(), copy=True), stencil.shape[:2], stencil.shape[2] // 2))
            super().__init__(stencil, sparse)

    plate_fill._SPDFactor = Recorded
    try:
        make()
    finally:
        plate_fill._SPDFactor = factor
    return systems


def _best(fn: Any, repeat: int) -> tuple[float, Any]:
    best, out = np.inf, None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return 1e3 * best, out


def superlu(K: sp.spmatrix) -> Any:
    """The plate's LU (the G1 plate's before, the G2 plate's still): ``_SPDFactor`` without a stencil."""
    return plate_fill._SPDFactor(None, lambda: K)


def one(K: sp.csc_matrix, shape: tuple[int, int], p: int, b: np.ndarray) -> tuple | None:
    """Both factorisations of one system: ``(SuperLU ms, ours ms, SuperLU solve ms, ours solve ms,
    agreement)``; ``None`` where SuperLU meets a pivot <= 0 (indefinite to working precision)."""
    t_lu, lu = _best(lambda: superlu(K), 3)
    if (lu.lu.U.diagonal() <= 0).any():
        return None
    t_ours, g = _best(lambda: GridCholesky(K, shape, p), 3)
    ts_lu, x_lu = _best(lambda: lu.solve(b), 5)
    ts_ours, x = _best(lambda: g.solve(b), 5)
    return t_lu, t_ours, ts_lu, ts_ours, float(np.abs(x - x_lu).max() / np.abs(x_lu).max())


def compare(label: str, systems: list) -> dict:
    """Both factorisations of each system; a table row per system of at least 2000 unknowns."""
    rng = np.random.default_rng(common.SEED)
    tot_ours = tot_lu = 0.0
    worst = 0.0
    indefinite = 0
    print(f"\n{label}: {len(systems)} systems")
    print("| grid | degree | unknowns | SuperLU factor (ms) | ours (ms) | ratio | SuperLU solve (ms) | ours | agree |")
    print("|---|---|---|---|---|---|---|---|---|")
    for K, shape, p in systems:
        try:
            got = one(K, shape, p, rng.standard_normal(K.shape[0]))
        except NotPositiveDefinite:  # SuperLU's pivots were all positive: not expected
            print(f"| {shape[0]} x {shape[1]} | {p} | {K.shape[0]} | Cholesky refused a system SuperLU factored |")
            continue
        if got is None:
            indefinite += 1
            continue
        t_lu, t_ours, ts_lu, ts_ours, agree = got
        worst = max(worst, agree)
        tot_ours += t_ours
        tot_lu += t_lu
        if K.shape[0] >= 2000:
            print(f"| {shape[0]} x {shape[1]} | {p} | {K.shape[0]} | {t_lu:.1f} | {t_ours:.1f} | {t_lu / t_ours:.2f}x "
                  f"| {ts_lu:.2f} | {ts_ours:.2f} | {agree:.1e} |")
    ratio = tot_lu / tot_ours if tot_ours else float("nan")
    print(f"all {len(systems) - indefinite} positive definite systems: SuperLU {tot_lu:.0f} ms, ours {tot_ours:.0f} ms "
          f"({ratio:.2f}x); solutions agree within {worst:.1e}; indefinite to working precision (SuperLU kept): "
          f"{indefinite}")
    return {"case": label, "superlu_ms": tot_lu, "ours_ms": tot_ours, "ratio": ratio, "indefinite": indefinite}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--realdata", action="store_true", help="also linkrods face 35's G1 plates (../shared/realdata)")
    args = ap.parse_args()
    print(f"{datetime.datetime.now().isoformat(timespec='seconds')}; {common.machine_note()}; "
          f"load {os.getloadavg()[0]:.2f}")
    rows = []
    for n in (4, 6):
        sides = ring_model(n).sides
        rows.append(compare(f"G1 plate, bump ring n = {n}", record(lambda sides=sides: fill_plate(sides))))
    if args.realdata:
        path = REALDATA / "occt__linkrods.step"
        if not path.exists():
            print(f"\n--realdata: {path} is absent; skipped")
        else:
            from occsurf.bridge.modeling.refill import SewnModel, refill_faces
            model = SewnModel(read_step(path))
            rows.append(compare("G1 plates, linkrods face 35 refilled",
                                record(lambda: refill_faces(model, [35], compare_occ=False, check=False))))
    print("\n| case | SuperLU (ms) | ours (ms) | ratio |")
    print("|---|---|---|---|")
    for r in rows:
        print(f"| {r['case']} | {r['superlu_ms']:.0f} | {r['ours_ms']:.0f} | {r['ratio']:.2f}x |")
    print(f"load average after: {os.getloadavg()}")


if __name__ == "__main__":
    main()
