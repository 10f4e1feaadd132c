"""Matching and repair speed (issue 29), measured in one run.

Run from the repository root::

    python benchmarks/bench_match.py            # match times on a 20 x 20-pole face
    python benchmarks/bench_match.py --repair   # also: occsurf repair of the bearing against
                                                # occsurf check --no-pictures of it (../shared)

* ``match_surface`` G0 / G1 / G2 / G3 of a bicubic 20 x 20-pole face to a 20 x 20-pole neighbour
  sharing its side, kinked by 2 deg, best of several runs. Target: G1 < 50 ms. OCC has no edge matching to compare with.
* ``match_along`` G0 / G1 of the same face along a curve across its interior (161 samples, a 2 deg
  kink): a trimmed face's edge.
* ``match_faces`` on the same pair as an OCC model (conversion, the new face on the old wires,
  BRepCheck, OCC LocalAnalysis before and after).
* With ``--repair``: ``repair_model`` of ``occt__bearing.iges`` (catia) against the library call
  behind ``occsurf check --no-pictures`` (``check_file(..., pictures=False)``) on the same file,
  same process. Target: repair < 3x check.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

from benchmarks.common import best_of, machine_note  # noqa: E402
from occsurf.algorithms.kernel.surface import BSplineSurface  # noqa: E402
from occsurf.algorithms.manipulation import match_surface  # noqa: E402

REALDATA = ROOT.parent / "shared" / "realdata"


def _knots(n: int) -> np.ndarray:
    return np.concatenate([[0.0] * 4, np.linspace(0, 1, n - 2)[1:-1], [1.0] * 4])


def pair(n: int = 20, kink_deg: float = 2.0) -> tuple[BSplineSurface, BSplineSurface]:
    """A target on x <= 0 and a face on x >= 0 sharing the edge x = 0 (the face's side u0, the same
    boundary curve), both n x n poles; the face continues the target's cross tangent with its
    second row turned by ``kink_deg`` about the edge."""
    ys = np.linspace(0, 1, n)
    h = 1.0 / (n - 1)
    T = np.zeros((n, n, 3))
    S = np.zeros((n, n, 3))
    for i in range(n):
        T[i, :, 0], T[i, :, 1] = -i * h, ys
        T[i, :, 2] = 0.2 * np.sin(2.0 * T[i, :, 0] + 3.0 * ys)
        S[i, :, 0], S[i, :, 1] = i * h, ys
        S[i, :, 2] = 0.2 * np.sin(2.0 * S[i, :, 0] + 3.0 * ys)
    S[0] = T[0]
    S[1] = T[0] + (T[0] - T[1])  # C1 across the edge (equal first spans) ...
    S[1, :, 2] += h * np.tan(np.radians(kink_deg))  # ... then kinked
    kn = _knots(n)
    return BSplineSurface((3, 3), (kn, kn), T), BSplineSurface((3, 3), (kn, kn), S)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repair", action="store_true", help="also time repair of the bearing against check")
    args = ap.parse_args()
    print(machine_note())
    T, S = pair()
    print("match_surface, 20 x 20 poles, a 2 deg kink along the shared side:")
    for c in ("G0", "G1", "G2", "G3"):
        res = match_surface(S, T, "u0", c)
        t = best_of(lambda c=c: match_surface(S, T, "u0", c), repeat=5, budget=5.0)
        print(f"  {c}: {t:7.1f} ms  (knots added {res.knots_added}, G0 {res.g0_max:.1e}, "
              f"G1 {res.g1_max_deg:.1e} deg, G2 {res.g2_max_rel:.1e}, met {res.met})")
    # inside: the same face matched along a curve across its interior (a trimmed face's edge)
    from occsurf.algorithms.manipulation import MatchTarget, match_along

    t = np.linspace(0.0, 1.0, 161)
    uv = np.stack([0.1 + 0.8 * t, 0.3 + 0.4 * t * t], 1)
    D = S.derivatives(uv[:, 0], uv[:, 1], 1)
    n = np.cross(D[:, 1, 0], D[:, 0, 1])
    n /= np.linalg.norm(n, axis=1)[:, None]
    tan = np.gradient(D[:, 0, 0], axis=0)
    tan /= np.linalg.norm(tan, axis=1)[:, None]
    th = np.radians(2.0)  # the normals turned 2 deg about the curve (Rodrigues)
    N = n * np.cos(th) + np.cross(tan, n) * np.sin(th) + tan * np.einsum("ij,ij->i", tan, n)[:, None] * (1 - np.cos(th))
    inside = MatchTarget(D[:, 0, 0], N)
    print("match_along, the same face, a 2 deg kink along a curve across it (161 samples):")
    for c in ("G0", "G1"):
        res = match_along(S, inside, uv, c, tol_g0=1e-6)
        t_in = best_of(lambda c=c: match_along(S, inside, uv, c, tol_g0=1e-6), repeat=5, budget=5.0)
        print(f"  {c}: {t_in:7.1f} ms  (knots added {res.knots_added}, G0 {res.g0_max:.1e}, G1 {res.g1_max_deg:.1e} deg, "
              f"change {res.max_change:.2e}, met {res.met})")
    from OCP.BRepBuilderAPI import BRepBuilderAPI_Sewing

    from occsurf.bridge.conversion.splines import make_face
    from occsurf.bridge.modeling.matching import match_faces

    sew = BRepBuilderAPI_Sewing(1e-6)
    sew.Add(make_face(T))
    sew.Add(make_face(S))
    sew.Perform()
    shape = sew.SewedShape()
    t = best_of(lambda: match_faces(shape, 1, 0, "G1"), repeat=3, budget=10.0)
    rep, _ = match_faces(shape, 1, 0, "G1")
    print(f"match_faces G1 on the pair as an OCC model: {t:.0f} ms (OCC G1 {rep.g1_before_deg:.2f} -> "
          f"{rep.g1_max_deg:.1e} deg, valid {rep.valid})")
    if args.repair:
        path = REALDATA / "occt__bearing.iges"
        if not path.is_file():
            print(f"--repair: {path} is absent")
            return
        from occsurf.bridge import read_iges
        from occsurf.bridge.audit.repair import repair_model
        from occsurf.bridge.quality.check_files import check_file

        out = Path(os.environ.get("TMPDIR", "/tmp")) / "bench_match_check"
        out.mkdir(parents=True, exist_ok=True)  # (the command makes it; the library call writes into it)
        t0 = time.perf_counter()
        check_file(path, out, pictures=False)
        t_check = time.perf_counter() - t0
        t0 = time.perf_counter()
        rep2, _ = repair_model(read_iges(path).shape, "catia")
        t_rep = time.perf_counter() - t0
        print(f"bearing: check --no-pictures {t_check:.1f} s; repair {t_rep:.1f} s = {t_rep / t_check:.1f}x check "
              f"(target < 3x); edges breaking catia {rep2.edges_breaking_before} -> {rep2.edges_breaking_after}, "
              f"repaired {rep2.repaired}, refused {rep2.refused}, faired {rep2.faces_faired}; violations by measure "
              f"{rep2.by_measure_before} -> {rep2.by_measure_after}; worst smooth G1 "
              f"{rep2.worst_smooth_g1_before:.4f} -> {rep2.worst_smooth_g1_after:.4f} deg; valid {rep2.valid_after}")


if __name__ == "__main__":
    main()
