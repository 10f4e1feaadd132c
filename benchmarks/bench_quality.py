"""Curvature maps: occsurf.algorithms.quality.curvature_map against OCC's GeomLProp_SLProps loop.

    python benchmarks/bench_quality.py [--quick]

Cases (the bicubic 50 x 50 net with non-uniform knots of common.test_surface, and its rational
version with random weights 0.5..2):

1. curvature map (points, normals, k1, k2, K, H, degenerate flags) on a 1000 x 1000 grid (1e6 points);
   "ours" uses the fused numba kernel (quality/_kernels.py), the NumPy path is shown beside it
2. the same on the rational surface
3. plane sections: 20 parallel cuts of the bicubic surface, refined to 1e-10 of its size

The OCC peer is what a user writes from Python: one ``GeomLProp_SLProps.SetParameters`` per
point, reading Gaussian, mean, max and min curvature and the normal. It takes seconds per million
points, so it is timed on every 10th grid row (1e5 points) and scaled by 10 (noted). Agreement is
checked on those rows: largest deviation relative to ``max(|k1|, |k2|)`` at each point.
Exit status 1 if a target fails (>= 10x faster than OCC, agreement within 1e-8).
"""

from __future__ import annotations

import argparse

import numpy as np
from common import Row, best_of, check_targets, machine_note, numpy_path, print_table, test_surface

from occsurf.algorithms.quality import curvature_map, plane_sections


def occ_loop(occ, us, vs):
    """The user's loop over ``GeomLProp_SLProps``; (len(us), len(vs), 4) K, H, k1, k2."""
    from OCP.GeomLProp import GeomLProp_SLProps

    pr = GeomLProp_SLProps(occ, 2, 1e-9)
    out = np.full((len(us), len(vs), 4), np.nan)
    N = np.empty((len(us), len(vs), 3))
    for i, u in enumerate(us):
        row, nrow = out[i], N[i]
        for j, v in enumerate(vs):
            pr.SetParameters(u, v)
            if pr.IsCurvatureDefined():
                row[j] = pr.GaussianCurvature(), pr.MeanCurvature(), pr.MaxCurvature(), pr.MinCurvature()
                nrow[j] = pr.Normal().Coord()
    return out, N


def case(name: str, s, n: int, stride: int) -> tuple[Row, float]:
    from occsurf.bridge.conversion.splines import to_occ

    us = np.linspace(*s.domain[0], n)
    vs = np.linspace(*s.domain[1], n)
    curvature_map(s, us[:64], vs[:64])  # warm-up: numba kernels loaded
    ours = best_of(lambda: curvature_map(s, us, vs, "mean"), repeat=5)
    cm = curvature_map(s, us, vs, "mean")
    with numpy_path():
        ours_np = best_of(lambda: curvature_map(s, us, vs, "mean"), repeat=3)
    occ = to_occ(s)
    sub = us[::stride]
    t_occ = best_of(lambda: occ_loop(occ, sub, vs), repeat=2, budget=10.0) * stride
    ref, _ = occ_loop(occ, sub, vs)
    scale = np.maximum(np.maximum(np.abs(cm.k1[::stride]), np.abs(cm.k2[::stride])), 1e-300)
    dev = 0.0
    for k, ours_v in enumerate((cm.gaussian[::stride] / scale, cm.mean[::stride], cm.k1[::stride], cm.k2[::stride])):
        r = ref[..., k] / (scale if k == 0 else 1.0)
        dev = max(dev, float(np.nanmax(np.abs(ours_v - r) / scale)))
    row = Row(name, ours, ours_numpy=ours_np, peers={"OCC GeomLProp loop": t_occ},
              notes=[f"OCC timed on every {stride}th row ({n // stride} x {n} points) x {stride}",
                     f"agreement with OCC: {dev:.2g} (relative to max|k| per point)",
                     f"{cm.n_degenerate} degenerate points"])
    return row, dev


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="300 x 300 grid instead of 1000 x 1000")
    args = ap.parse_args()
    n, stride = (300, 3) if args.quick else (1000, 10)
    print(machine_note())
    rows, targets = [], []
    for name, s in ((f"curvature map {n}x{n}, bicubic", test_surface()),
                    (f"curvature map {n}x{n}, rational", test_surface(rational=True))):
        row, dev = case(name, s, n, stride)
        rows.append(row)
        ratio = row.peers["OCC GeomLProp loop"] / row.ours
        targets.append((f"{name} vs OCC", ratio, 10.0))
        targets.append((f"{name}: agreement 1e-8 / deviation {dev:.2g}", 1e-8 / max(dev, 1e-300), 1.0))
    s = test_surface()
    t = best_of(lambda: plane_sections([s], [0, 0, 0], [1, 0, 0], np.linspace(0.02, 0.98, 20)), repeat=3)
    secs = plane_sections([s], [0, 0, 0], [1, 0, 0], np.linspace(0.02, 0.98, 20))
    npts = sum(c.points.shape[0] for sec in secs for c in sec.curves)
    rows.append(Row("plane_sections, 20 cuts", t, notes=[f"{npts} points refined to 1e-10 of the size, "
                                                          f"{sum(sec.n_inflections for sec in secs)} inflections"]))
    print_table(rows, ["OCC GeomLProp loop"])
    return 0 if check_targets(targets) else 1


if __name__ == "__main__":
    raise SystemExit(main())
