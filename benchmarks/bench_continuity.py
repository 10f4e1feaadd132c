"""Benchmark: edge continuity (bridge/quality/continuity.py) vs OCC's LocalAnalysis_SurfaceContinuity.

1. ``occt__bearing.iges`` (213 loose B-spline faces): every edge between two faces (shared ones and
   the ones matched by geometry), at the same dense points for both. Ours: one batched
   ``measure`` call (p-curves of both sides, the projection onto the matched edge, both faces'
   partials to order 2, the G0/G1/G2 measures and OCC's curvature-gap formula). OCC: per point the
   two p-curves' ``Value`` (at our parameters, so OCC is spared the projection) and
   ``LocalAnalysis_SurfaceContinuity(..., GeomAbs_G2)`` with ``C0Value``, ``G1Angle``,
   ``G2CurvatureGap`` read out. Both are given the matched edge's parameters; ours is also timed
   finding them (Gauss-Newton onto the other edge). Agreement: largest differences over all points where OCC's
   analysis is done (EpsNul scaled to the model; see tests/bridge/test_continuity_vs_occ.py).
2. Every file of ../shared/realdata: ``edge_continuity`` end to end (matching, dense samples, the
   worst-point search): edges by topology / geometry, worst G0 / G1 / G2, seconds.

Run:  python benchmarks/bench_continuity.py
"""

from __future__ import annotations

import math
import sys
import time
from collections import Counter
from pathlib import Path

import common  # noqa: F401 - pins BLAS threads before NumPy
import numpy as np
from OCP.BRep import BRep_Tool
from OCP.GeomAbs import GeomAbs_Shape
from OCP.LocalAnalysis import LocalAnalysis_SurfaceContinuity

from occsurf.bridge import read_iges, read_step
from occsurf.bridge.quality import continuity as C
from occsurf.bridge.quality import edge_continuity, occ_fold

REALDATA = Path(__file__).resolve().parents[2] / "shared" / "realdata"


def _read(path: Path):
    return read_iges(path) if path.suffix.lower() in (".igs", ".iges") else read_step(path)


def _engine(model, samples: int):
    """The measured pairs and the dense requests ``(pid, t)`` of ``edge_continuity``."""
    from occsurf.bridge.quality._setup import build_engine

    setup = build_engine(model)
    engine, pairs = setup.engine, setup.pairs
    good = np.array([i for i, p in enumerate(pairs) if C._why_not(engine, p) is None], dtype=np.intp)
    s01 = C._chebyshev(samples)
    first = np.array([pairs[i].first for i in good])
    last = np.array([pairs[i].last for i in good])
    t = (first[:, None] + (last - first)[:, None] * s01).reshape(-1)
    return engine, setup.faces, np.repeat(good, samples), t, setup.size


def _occ(engine, faces, pid, t, s, size):
    """OCC at the same points: p-curve values and LocalAnalysis (G2)."""
    from OCP.BRep import BRep_Tool as BT

    eps = 1e-12 * size
    c2d, surf = {}, {}
    out = np.full((pid.size, 3), np.nan)
    for m, (p, a, b) in enumerate(zip(pid.tolist(), t.tolist(), s.tolist())):
        pr = engine.pairs[p]
        if p not in c2d:
            c2d[p] = tuple(BT.CurveOnSurface_s(side.edge, faces[side.face].face, 0.0, 0.0)
                           for side in (pr.side1, pr.side2))
            surf[p] = tuple(BRep_Tool.Surface_s(faces[side.face].face) for side in (pr.side1, pr.side2))
        u1, v1 = c2d[p][0].Value(a).Coord()
        u2, v2 = c2d[p][1].Value(b).Coord()
        la = LocalAnalysis_SurfaceContinuity(surf[p][0], u1, v1, surf[p][1], u2, v2, GeomAbs_Shape.GeomAbs_G2,
                                             eps, 1e-3, 1e-3, 1e-3, 1e-3, 0.01, 1e4)
        if la.IsDone():
            out[m] = (la.C0Value(), math.degrees(la.G1Angle()), la.G2CurvatureGap())
    return out


def bearing(samples: int = 33) -> None:
    path = REALDATA / "occt__bearing.iges"
    if not path.exists():
        print(f"{path} absent: skipped")
        return
    model = _read(path)
    engine, faces, pid, t, size = _engine(model, samples)
    M = engine.measure(pid, t, set_flip=True, gap=True)  # warm-up (and the side-2 parameters for OCC)
    ours_ms = common.best_of(lambda: engine.measure(pid, t, s=M["s"]), repeat=5)
    gap_ms = common.best_of(lambda: engine.measure(pid, t, s=M["s"], gap=True), repeat=5)
    proj_ms = common.best_of(lambda: engine.measure(pid, t), repeat=3)
    occ_ms = common.best_of(lambda: _occ(engine, faces, pid, t, M["s"], size), repeat=3, min_repeat=1)
    ref = _occ(engine, faces, pid, t, M["s"], size)
    done = np.isfinite(ref[:, 0])
    d0 = np.nanmax(np.abs(M["g0"][done] - ref[done, 0]))
    d1 = np.nanmax(np.abs(occ_fold(M["g1"][done]) - ref[done, 1]))
    scale = np.maximum(np.abs(ref[done, 2]), 1.0 / size)
    d2 = np.nanmax(np.abs(M["gap"][done] - ref[done, 2]) / scale)
    n_geo = int(engine.geo.sum())
    print(f"occt__bearing.iges: {len(engine.pairs)} edges ({len(engine.pairs) - n_geo} topology, {n_geo} geometry), "
          f"{pid.size} points, OCC done at {done.sum()}")
    print(f"  ours (batched measure)   {ours_ms:9.1f} ms   {1e3 * ours_ms / pid.size:6.2f} us/point")
    print(f"  OCC LocalAnalysis loop   {occ_ms:9.1f} ms   {1e3 * occ_ms / pid.size:6.2f} us/point")
    print(f"  ratio OCC / ours         {occ_ms / ours_ms:9.1f} x")
    print(f"  ours with OCC's G2CurvatureGap formula too: {gap_ms:.1f} ms ({occ_ms / gap_ms:.1f} x)")
    print(f"  ours, projecting onto the matched edges too (OCC is given those points): {proj_ms:.1f} ms")
    print(f"  agreement: |g0 - C0Value| <= {d0:.2e} (model size {size:.3g}), |g1 - G1Angle| <= {d1:.2e} deg, "
          f"gap rel. diff <= {d2:.2e}")
    t0 = time.perf_counter()
    edge_continuity(model)
    print(f"  edge_continuity end to end (matching + {samples} samples + worst-point search): "
          f"{time.perf_counter() - t0:.2f} s")


def realdata_table() -> None:
    print("\nfile | faces | edges (topology / geometry) | unmatched free | classes | worst G0 | worst G1 deg | "
          "worst G2 1/unit | worst G2 % | s")
    for path in sorted(REALDATA.glob("*")):
        if path.suffix.lower() not in (".step", ".stp", ".igs", ".iges"):
            continue
        model = _read(path)
        t0 = time.perf_counter()
        r = edge_continuity(model)
        dt = time.perf_counter() - t0
        meas = [x for x in r if x.classification not in ("degenerate",)]
        smooth = [x for x in meas if x.classification not in ("sharp", "gap")]

        def worst(items, key):
            vals = [getattr(x, key) for x in items if getattr(x, key) is not None and math.isfinite(getattr(x, key))]
            return max(vals) if vals else float("nan")

        classes = dict(sorted(Counter(x.classification for x in r).items()))
        print(f"{path.name} | {r.stats['faces']} | {len(r)} ({r.stats['topology']} / {r.stats['geometry']}) | "
              f"{r.stats['unmatched_free_edges']} | {classes} | {worst(meas, 'g0_max'):.2e} | "
              f"{worst(smooth, 'g1_max_deg'):.3g} (all: {worst(meas, 'g1_max_deg'):.3g}) | "
              f"{worst(smooth, 'g2_max'):.3g} | {worst(smooth, 'g2_max_rel'):.3g} | {dt:.2f}")
    print("(worst G1/G2 over the edges that are not creases or gaps; 'all' includes creases)")


if __name__ == "__main__":
    print(common.machine_note())
    bearing(int(sys.argv[1]) if len(sys.argv) > 1 else 33)
    realdata_table()
