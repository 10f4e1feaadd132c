"""Hierarchical surfaces (course ch. 5): one interactive edit, against flat baselines, in one run.

Run from the repository root::

    python benchmarks/bench_hierarchical.py

The surface: a bicubic 20 x 20 base (non-uniform knots, seeded) with three nested overlays
(midpoint refinement of [0.2, 0.8]^2, then [0.35, 0.65]^2, then [0.45, 0.55]^2), frame offsets,
random details on every level. Timed (best of N, wall clock, one BLAS thread):

* **the interactive edit** (target <= 5 ms): ``move_vertex`` of one level-2 vertex, then
  ``evaluate_grid`` on a 100 x 100 grid. The level-3 overlay follows the edit (its reference
  vertices and frames are rebuilt); the base and level-1 contributions come from the cache.
* the same edit without the evaluation cache (every level re-evaluated on the grid);
* baseline 1, what an editor holding only flat splines would do after the edit: ``flatten()``
  then ``BSplineSurface.evaluate_grid`` of the flat surface on the same grid;
* baseline 2, OCC: ``Geom_BSplineSurface.D0`` of the flattened surface (``bridge.to_occ``) at the
  same 10^4 grid points, called from Python as users do (the conversion not included).

The printed ratio is baseline time / our edit time. Agreement of the three evaluations is
printed too. Exit status 1 if the target fails.
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import common  # noqa: E402  (pins BLAS threads before NumPy)
import numpy as np  # noqa: E402

from occsurf.algorithms.hierarchical.surface import HierarchicalSurface  # noqa: E402

TARGET_MS = 5.0
GRID = 100


def build() -> tuple[HierarchicalSurface, list]:
    base = common.test_surface(n=20)
    hs = HierarchicalSurface(base)
    o1 = hs.add_overlay((0.2, 0.8), (0.2, 0.8))
    o2 = hs.add_overlay((0.35, 0.65), (0.35, 0.65), o1)
    o3 = hs.add_overlay((0.45, 0.55), (0.45, 0.55), o2)
    rng = np.random.default_rng(common.SEED)
    for o, s in ((o1, 0.02), (o2, 0.01), (o3, 0.005)):
        hs.set_offsets(o, s * rng.standard_normal(o.shape + (3,)))
    return hs, [o1, o2, o3]


def main() -> int:
    hs, (o1, o2, o3) = build()
    us = np.linspace(0.0, 1.0, GRID)
    centre = (o2.shape[0] // 2, o2.shape[1] // 2)
    sign = [1.0]

    def edit() -> np.ndarray:
        sign[0] = -sign[0]
        hs.move_vertex(o2, centre, (0.0, 0.0, 1e-3 * sign[0]))
        return hs.evaluate_grid(us, us)

    def edit_uncached() -> np.ndarray:
        sign[0] = -sign[0]
        hs.move_vertex(o2, centre, (0.0, 0.0, 1e-3 * sign[0]))
        hs._grid_cache = None  # noqa: SLF001 - measure the cold evaluation
        return hs.evaluate_grid(us, us)

    def flat_eval() -> np.ndarray:
        return hs.flatten().evaluate_grid(us, us)

    edit()
    t_edit = common.best_of(edit, repeat=50, budget=2.0, min_repeat=20)
    t_cold = common.best_of(edit_uncached, repeat=30, budget=2.0, min_repeat=10)
    t_flat = common.best_of(flat_eval, repeat=20, budget=2.0, min_repeat=5)

    from OCP.gp import gp_Pnt

    occ = common.occ_surface(hs.flatten())
    p = gp_Pnt()

    def occ_eval() -> np.ndarray:
        out = np.empty((GRID, GRID, 3))
        for i, u in enumerate(us.tolist()):
            for j, v in enumerate(us.tolist()):
                occ.D0(u, v, p)
                out[i, j] = p.Coord()
        return out

    t_occ = common.best_of(occ_eval, repeat=5, budget=3.0)
    ours = hs.evaluate_grid(us, us)
    dev_flat = float(np.abs(ours - flat_eval()).max())
    dev_occ = float(np.abs(ours - occ_eval()).max())
    counts = hs.pole_counts()

    print(f"machine: {common.machine_note()}")
    print(f"surface: 20 x 20 bicubic base, overlays {o1.shape}, {o2.shape}, {o3.shape} (levels 1-3); "
          f"stored poles+offsets {counts['stored']}, flat poles {counts['flat']}")
    print(f"grid {GRID} x {GRID}; times in ms, best of N; ratio = baseline / our edit")
    rows = [
        ("edit: move_vertex at level 2 + evaluate_grid (cached levels)", t_edit, None),
        ("same, evaluation cache cleared (all levels evaluated)", t_cold, t_cold / t_edit),
        ("baseline: flatten() + flat evaluate_grid (ours)", t_flat, t_flat / t_edit),
        ("baseline: OCC Geom_BSplineSurface.D0 of the flat form, 10^4 calls", t_occ, t_occ / t_edit),
    ]
    w = max(len(r[0]) for r in rows)
    for label, t, ratio in rows:
        print(f"  {label.ljust(w)}  {t:8.3f} ms" + ("" if ratio is None else f"   ({ratio:.1f}x)"))
    print(f"agreement: |hierarchical - flat| = {dev_flat:.2g}, |hierarchical - OCC| = {dev_occ:.2g}")
    ok = t_edit <= TARGET_MS
    print(f"\ntarget: {'PASS' if ok else 'FAIL'}  interactive edit {t_edit:.2f} ms (need <= {TARGET_MS:g} ms)")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
