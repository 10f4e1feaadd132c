"""Benchmark: S-patch evaluation and first derivatives (algorithms/topology/spatch.py) vs its peers.

The same 10 000 domain points for everyone: a random piece ``k`` and random ``(s, t)`` in
``[0, 1]²`` per point, mapped to the regular n-gon by :func:`occsurf.algorithms.topology.spatch_convert.piece_domain_points`.

* **ours**: ``SPatch.evaluate(x)`` / ``SPatch.derivatives(x, 1)`` on the n-gon points (Wachspress
  coordinates, Bernstein form, Taylor-mode derivatives; vectorised over the points).
* **OCC D0 / D1 loop**: the exported exact rational pieces (``convert_spatch``, bidegree
  ``d (n-2)``) as ``Geom_BSplineSurface``, one ``D0`` / ``D1`` call per point at its ``(s, t)``,
  coordinates copied out: what a user of the exported STEP faces pays.
* **ours on the pieces**: our own ``BSplineSurface.evaluate`` / ``derivatives`` of the same pieces
  (vectorised per piece), the tensor-product route.

Derivatives are with respect to the domain ``(x, y)`` for the S-patch and ``(s, t)`` for the
pieces: the same amount of work (point and two first partials), not the same numbers. The
printed ratio is peer time / ours (> 1: we are faster). Values are cross-checked (max distance
between our points and OCC's). For ``depth * (sides - 2) > 25`` the pieces are bi-quintic
least-squares fits (no exact OCC form); the peers then evaluate those.

Run:  python benchmarks/bench_spatch.py   (~20 s on the 2-core machine)
"""

from __future__ import annotations

from math import comb

import common  # noqa: F401 - pins BLAS threads before NumPy
import numpy as np
from OCP.gp import gp_Pnt, gp_Vec

from occsurf.algorithms.topology.spatch import SPatch
from occsurf.algorithms.topology.spatch_convert import convert_spatch, piece_domain_points
from occsurf.bridge.conversion.splines import to_occ

CASES = [(5, 3, False), (5, 3, True), (6, 5, False), (9, 3, False), (9, 4, False)]
N_POINTS = 10_000


def case(n: int, d: int, rational: bool) -> dict:
    rng = np.random.default_rng(common.SEED + 100 * n + d)
    m = comb(n + d - 1, d)
    patch = SPatch(n, d, rng.normal(size=(m, 3)), rng.uniform(0.5, 2.0, m) if rational else None)
    k = rng.integers(0, n, N_POINTS)
    s, t = rng.uniform(size=(2, N_POINTS))
    x = np.empty((N_POINTS, 2))
    for j in range(n):
        sel = k == j
        x[sel] = piece_domain_points(n, j, s[sel], t[sel])
    conv = convert_spatch(patch)
    occ = [to_occ(p) for p in conv.surfaces]

    def occ_loop(order: int) -> np.ndarray:
        out = np.empty((N_POINTS, 3))
        P, Du, Dv = gp_Pnt(), gp_Vec(), gp_Vec()
        for i in range(N_POINTS):
            if order == 0:
                occ[k[i]].D0(s[i], t[i], P)
            else:
                occ[k[i]].D1(s[i], t[i], P, Du, Dv)
            out[i] = P.X(), P.Y(), P.Z()
        return out

    def ours_pieces(order: int) -> np.ndarray:
        out = np.empty((N_POINTS, 3))
        for j, surf in enumerate(conv.surfaces):
            sel = k == j
            if order == 0:
                out[sel] = surf.evaluate(s[sel], t[sel])
            else:
                out[sel] = surf.derivatives(s[sel], t[sel], 1)[..., 0, 0, :]
        return out

    row = dict(n=n, d=d, rational=rational, method=conv.method, degree=conv.degree[0])
    row["eval"] = common.best_of(lambda: patch.evaluate(x))
    row["d1"] = common.best_of(lambda: patch.derivatives(x, 1))
    row["occ_d0"] = common.best_of(lambda: occ_loop(0), repeat=3)
    row["occ_d1"] = common.best_of(lambda: occ_loop(1), repeat=3)
    row["pieces_d0"] = common.best_of(lambda: ours_pieces(0), repeat=3)
    row["pieces_d1"] = common.best_of(lambda: ours_pieces(1), repeat=3)
    ours = patch.evaluate(x)
    row["dev_occ"] = float(np.max(np.linalg.norm(occ_loop(0) - ours, axis=1)))
    row["dev_pieces"] = float(np.max(np.linalg.norm(ours_pieces(0) - ours, axis=1)))
    return row


def main() -> None:
    print(f"S-patch evaluation, {N_POINTS} points; {common.machine_note()}")
    print("| n | d | rational | pieces | ours eval | ours D1 | OCC D0 loop (ratio) | OCC D1 loop (ratio) "
          "| our pieces D0 (ratio) | our pieces D1 (ratio) | max |ours - OCC| |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for n, d, rational in CASES:
        r = case(n, d, rational)
        print(f"| {n} | {d} | {'yes' if rational else 'no'} | {r['method']} deg {r['degree']} "
              f"| {r['eval']:.1f} ms | {r['d1']:.1f} ms "
              f"| {r['occ_d0']:.1f} ms ({r['occ_d0'] / r['eval']:.1f}) | {r['occ_d1']:.1f} ms ({r['occ_d1'] / r['d1']:.1f}) "
              f"| {r['pieces_d0']:.1f} ms ({r['pieces_d0'] / r['eval']:.1f}) "
              f"| {r['pieces_d1']:.1f} ms ({r['pieces_d1'] / r['d1']:.1f}) | {r['dev_occ']:.1e} |", flush=True)


if __name__ == "__main__":
    main()
