"""Knot refinement: occsurf against OCC, splipy and geomdl in one run.

    python benchmarks/bench_knots.py [--quick]

Inserts 100 distinct random knots into a bicubic 50 x 50 surface along u (and along v), as one
refinement. OCC is timed on its one-call ``InsertUKnots`` (knot arrays built beforehand, a fresh
copy of the surface per call, made just before it and not timed); ours on ``s.refine(knots, direction="u")``, the public,
validated call that returns a new surface. geomdl inserts one knot per call, so it is timed on
10 knots and scaled. The refined nets are compared with OCC's. Exit status 1 if a target fails.
"""

from __future__ import annotations

import argparse
import time

import common  # first: pins BLAS to one thread  # noqa: I001
import numpy as np
from common import Row, best_of, check_targets, max_dev, print_table

from occsurf.algorithms.kernel.knots import merge_knots, refine_poles


def occ_insert_time(occ, knots: np.ndarray, direction: str, repeat: int) -> tuple[float, object]:
    """Best time (ms) of one ``InsertUKnots``/``InsertVKnots`` call on fresh copies.

    Each copy is made right before its call: copies made long before are out of cache and
    make OCC look ~1.6x slower than it is (0.22 ms against 0.14 ms here).
    """
    from OCP.TColStd import TColStd_Array1OfInteger, TColStd_Array1OfReal

    K = TColStd_Array1OfReal(1, len(knots))
    M = TColStd_Array1OfInteger(1, len(knots))
    for i, x in enumerate(knots, start=1):
        K.SetValue(i, float(x))
        M.SetValue(i, 1)
    best = float("inf")
    for _ in range(repeat):
        c = occ.Copy()  # made just before the call, so its poles are in cache, as ours are
        insert = c.InsertUKnots if direction == "u" else c.InsertVKnots
        t0 = time.perf_counter()
        insert(K, M, 0.0, True)
        best = min(best, time.perf_counter() - t0)
    return 1e3 * best, c


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="fewer repetitions")
    args = ap.parse_args()
    from geomdl import operations

    from occsurf.bridge import from_occ

    rep = 20 if args.quick else 200
    s = common.test_surface()
    rng = np.random.default_rng(common.SEED + 2)
    knots = np.sort(rng.uniform(0.005, 0.995, 100))
    print("# Knot refinement: 100 knots into a bicubic 50 x 50 surface")
    print(f"# {common.machine_note()}")
    occ = common.occ_surface(s)
    rows: list[Row] = []
    deviations: list[str] = []
    results = {}
    for direction in ("u", "v"):
        ax = 0 if direction == "u" else 1
        ours = s.refine(knots, direction=direction)
        # The kernel alone: the Oslo matrix times the net, no validation or new object.
        H = s.homogeneous_points if ax == 0 else np.ascontiguousarray(s.homogeneous_points.transpose(1, 0, 2))
        tau = merge_knots(s.knots[ax], knots)
        # Sub-millisecond calls: time ours and OCC in alternating rounds, so that a burst of load
        # from other processes cannot fall on one of them only.
        t_ours = t_kernel = t_occ = float("inf")
        for _ in range(5):
            t_ours = min(t_ours, best_of(lambda direction=direction: s.refine(knots, direction=direction), rep // 5, budget=1.0))
            t_kernel = min(t_kernel, best_of(lambda ax=ax, H=H, tau=tau: refine_poles(s.knots[ax], s.degree[ax], H, tau), rep // 5, budget=1.0))
            t, occ_done = occ_insert_time(occ, knots, direction, rep // 5)
            t_occ = min(t_occ, t)
        r = Row(f"refine 100 knots along {direction}", t_ours)
        r.peers["our Oslo kernel alone"] = t_kernel
        r.peers["OCC Insert*Knots"] = t_occ
        deviations.append(f"{direction}: OCC poles {max_dev(from_occ(occ_done).control_points, ours.control_points):.1e}")

        def splipy_refine(ax=ax):
            spl = common.splipy_surface(s)  # splipy refines in place: a fresh object per call
            return spl.insert_knot(list(knots), direction=ax)

        t_make = best_of(lambda: common.splipy_surface(s), 20, budget=1.0)
        r.peers["splipy"] = max(best_of(splipy_refine, 20 if not args.quick else 5, budget=2.0) - t_make, 0.0)
        r.notes.append(f"splipy: insert_knot on a fresh copy, the copy's {t_make:.2f} ms subtracted")
        n_geo = 10

        def geomdl_insert(ax=ax, n_geo=n_geo):
            g = common.geomdl_surface(s)
            for x in knots[:n_geo]:
                operations.insert_knot(g, [float(x), None] if ax == 0 else [None, float(x)], [1, 0] if ax == 0 else [0, 1])

        t_geo_make = best_of(lambda: common.geomdl_surface(s), 3, budget=1.0)
        r.peers["geomdl"] = max(best_of(geomdl_insert, 2, budget=5.0, min_repeat=1) - t_geo_make, 0.0) * len(knots) / n_geo
        r.notes.append(f"geomdl: one insert_knot call per knot, {n_geo} knots timed, scaled x{len(knots) / n_geo:g}")
        rows.append(r)
        results[direction] = r

    # Single knot (Boehm) for reference.
    r = Row("insert one knot (u = 0.5)", best_of(lambda: s.insert_knot(0.5, direction="u"), rep, budget=2.0))
    r.peers["OCC Insert*Knots"] = occ_insert_time(occ, np.array([0.5]), "u", rep)[0]
    rows.append(r)

    print()
    print_table(rows, ["our Oslo kernel alone", "OCC Insert*Knots", "splipy", "geomdl"])
    print("\nagreement of the refined net with OCC's (max |OCC - ours| / max |ours|):")
    for d in deviations:
        print("  " + d)
    print("\n(the target is the issue's s.refine(knots, direction='u'); the v row is for information: our v-refinement")
    print(" transposes the net before and after the u kernel)")
    ok = check_targets([
        ("refine 100 knots along u within 1.2x of OCC's one call (OCC time / ours; issue 30)",
         results["u"].peers["OCC Insert*Knots"] / results["u"].ours, 1 / 1.2),
    ])
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
