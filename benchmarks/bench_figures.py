"""Animated-figure surfaces (course §5-42..5-47): posing a skinned hierarchical arm, in one run.

Run from the repository root::

    python benchmarks/bench_figures.py

The surface: the demo arm of :mod:`occsurf.examples.figures` — a bicubic 30 x 30-pole tube, three
overlays in frame offsets (biceps with a pose procedure, forearm flesh, the elbow's point), the base
bound to a two-segment skeleton with a dual-quaternion multi-segment joint at the elbow. Timed
(best of N, wall clock, one BLAS thread):

* **pose + flatten** (target <= 5 ms): ``AttachedSurface.at(skeleton.pose({"elbow": a}))`` then
  ``flatten()``, the exact NURBS of the pose (what a STEP export or a CAD viewer needs);
* pose only (the hierarchy rebuilt on the posed base; the overlays' frames re-evaluated);
* pose + ``evaluate_grid`` 100 x 100 (what a viewer draws each frame);
* one step of the dynamic level (``SoftTissue.step``: pose, modal transform, exact propagator);
* baseline 1: linear blending of the flat rest surface's poles (every one of its poles skinned,
  no hierarchy) and the surface built, what a plain skinning of the NURBS would cost;
* baseline 2, OCC: ``bridge.to_occ`` of the posed flat surface (handing the pose to cadquery or
  build123d), and OCC's ``D0`` on the 100 x 100 grid from Python.

The printed ratio is baseline time / our pose + flatten. Exit status 1 if the target fails.
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import common  # noqa: E402  (pins BLAS threads before NumPy)
import numpy as np  # noqa: E402

from occsurf.algorithms.hierarchical import SoftTissue  # noqa: E402
from occsurf.examples.figures import demo_arm, linear_baseline  # noqa: E402

TARGET_MS = 5.0
GRID = 100


def main() -> int:
    arm = demo_arm(vein=False)
    sk = arm.skeleton
    lin = linear_baseline(arm)
    us = np.linspace(0.0, 1.0, GRID)
    angle = [0.0]

    def next_pose():
        angle[0] = (angle[0] + 0.37) % 2.0
        return sk.pose({"elbow": angle[0]})

    def pose_flatten():
        return arm.at(next_pose()).flatten()

    def pose_only():
        return arm.at(next_pose())

    def pose_grid():
        return arm.at(next_pose()).evaluate_grid(us, us)

    tissue = SoftTissue(arm, arm.rest.overlays[1].id, stiffness=2000.0, coupling=400.0, damping=8.0)
    tissue.step(next_pose(), 1 / 60)

    def dyn_step():
        return tissue.step(next_pose(), 1 / 60)

    def linear_flat():
        return lin.at(next_pose()).flatten()

    pose_flatten()
    t_pf = common.best_of(pose_flatten, repeat=60, budget=2.0, min_repeat=20)
    import time

    runs = []
    for _ in range(100):
        t0 = time.perf_counter()
        pose_flatten()
        runs.append(1e3 * (time.perf_counter() - t0))
    t_med = float(np.median(runs))
    t_p = common.best_of(pose_only, repeat=60, budget=2.0, min_repeat=20)
    t_pg = common.best_of(pose_grid, repeat=30, budget=2.0, min_repeat=10)
    t_dyn = common.best_of(dyn_step, repeat=30, budget=2.0, min_repeat=10)
    t_lin = common.best_of(linear_flat, repeat=60, budget=2.0, min_repeat=20)

    from OCP.gp import gp_Pnt

    flat = pose_flatten()
    t_to_occ = common.best_of(lambda: common.occ_surface(flat), repeat=30, budget=2.0, min_repeat=10)
    occ = common.occ_surface(flat)
    p = gp_Pnt()

    def occ_grid() -> np.ndarray:
        out = np.empty((GRID, GRID, 3))
        for i, u in enumerate(us.tolist()):
            for j, v in enumerate(us.tolist()):
                occ.D0(u, v, p)
                out[i, j] = p.Coord()
        return out

    t_occ = common.best_of(occ_grid, repeat=5, budget=3.0)
    posed = arm.at(sk.pose({"elbow": angle[0]}))
    dev = float(np.abs(posed.evaluate_grid(us, us) - occ_grid()).max())
    counts = arm.rest.pole_counts()

    print(f"machine: {common.machine_note()}")
    print(f"surface: 30 x 30-pole bicubic arm, {len(arm.rest.overlays)} overlays "
          f"{', '.join(str(o.shape) for o in arm.rest.overlays)}; stored {counts['stored']}, flat poles {counts['flat']}")
    print("times in ms, best of N; ratio = baseline / our pose + flatten")
    rows = [
        ("pose + flatten (exact NURBS of the pose)", t_pf, None),
        ("pose + flatten, median of 100 runs", t_med, None),
        ("pose only (posed hierarchy)", t_p, None),
        (f"pose + evaluate_grid {GRID} x {GRID}", t_pg, None),
        ("one SoftTissue.step of the flesh level (pose, modes, exact step)", t_dyn, None),
        ("baseline: linear blend of the flat poles + surface", t_lin, t_lin / t_pf),
        ("baseline: OCC to_occ of the posed flat surface", t_to_occ, t_to_occ / t_pf),
        (f"baseline: OCC D0 on the {GRID} x {GRID} grid, from Python", t_occ, t_occ / t_pf),
    ]
    w = max(len(r[0]) for r in rows)
    for label, t, ratio in rows:
        print(f"  {label.ljust(w)}  {t:8.3f} ms" + ("" if ratio is None else f"   ({ratio:.2f}x)"))
    print(f"agreement: |hierarchical - OCC of the flat form| on the grid = {dev:.2g}")
    ok = t_pf <= TARGET_MS
    print(f"\ntarget: {'PASS' if ok else 'FAIL'}  pose + flatten {t_pf:.2f} ms (need <= {TARGET_MS:g} ms)")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
