"""Direct manipulation: one drag update after preprocessing, against OCC's MovePoint, in one run.

Run from the repository root::

    python benchmarks/bench_manipulation.py            # print the tables
    python benchmarks/bench_manipulation.py --write    # also rewrite MANIPULATION.md

The curve is a clamped uniform cubic with 200 poles in 3-D. Timed (best of 7 repeats of many calls,
per call, wall clock):

* ``Dragger.apply`` after preprocessing (course §4-6) with 3 constraints: the triple constraint
  system (position, tangent, second derivative at one parameter, course §4-11); three positions at
  three parameters; the triple system restricted to a window of 41 poles. Target: <= 50 us.
* the same with 1 constraint (position: what ``MovePoint`` does) and 2 (position + tangent: what
  ``MovePointAndTangent`` does);
* ``drag_point`` and ``constrain`` without preprocessing (validation, basis rows, factorisation);
* OCC's ``Geom_BSplineCurve::MovePoint`` and ``MovePointAndTangent`` on the same curve, parameter
  and targets. OCC edits its curve in place; ours returns a new immutable curve (the copy of the
  200 poles and the construction of the result are included in our times).

A second table compares the size of the pole change (Frobenius norm) on 200 random drags of the
same curve (random parameter, target and window): ours is the minimum-norm change.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import timeit
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:  # run as a script from anywhere
    sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402
from OCP.gp import gp_Pnt, gp_Vec  # noqa: E402

from occsurf.algorithms import BSplineCurve, Derivative, Dragger, Position, Tangent, constrain, drag_point  # noqa: E402
from occsurf.bridge import to_occ  # noqa: E402

N_POLES = 200
TARGET_US = 50.0


def make_curve(n: int = N_POLES, seed: int = 0) -> BSplineCurve:
    t = np.r_[[0.0] * 4, np.linspace(0, 1, n - 2)[1:-1], [1.0] * 4]
    rng = np.random.default_rng(seed)
    P = np.c_[np.linspace(0, 100, n), rng.uniform(-1, 1, (n, 2))]
    return BSplineCurve(3, t, P)


def per_call_us(fn, number: int) -> float:
    """Best of 7 repeats, microseconds per call."""
    return min(timeit.repeat(fn, number=number, repeat=7)) / number * 1e6


def timings() -> list[tuple[str, int, float]]:
    c = make_curve()
    u, u2, u3 = 0.5, 0.25, 0.75
    D = c.derivatives(u, 2)
    rows: list[tuple[str, int, float]] = []

    def bench(label: str, k: int, fn, number: int = 20000) -> None:
        rows.append((label, k, per_call_us(fn, number)))

    # Ours, prepared (course §4-6).
    triple = Dragger(c, [Position(u, D[0]), Tangent(u, D[1]), Derivative(u, 2, D[2])])
    T3 = triple.current + np.array([[0.5, 0.3, 0.1], [2.0, 1.0, 0.0], [10.0, -5.0, 3.0]])
    bench("Dragger.apply, triple system at one u (pos + tangent + 2nd derivative)", 3, lambda: triple.apply(T3))
    three = Dragger(c, [Position(x, c.evaluate(x)) for x in (u2, u, u3)])
    P3 = three.current + 0.3
    bench("Dragger.apply, three positions at three parameters", 3, lambda: three.apply(P3))
    local = Dragger(c, [Position(u, D[0]), Tangent(u, D[1]), Derivative(u, 2, D[2])], movable=slice(80, 121))
    bench("Dragger.apply, triple system, window of 41 poles", 3, lambda: local.apply(T3))
    one = Dragger(c, [Position(u, D[0])])
    bench("Dragger.apply, position", 1, lambda: one.apply(T3[:1]))
    two = Dragger(c, [Position(u, D[0]), Tangent(u, D[1])])
    bench("Dragger.apply, position + tangent", 2, lambda: two.apply(T3[:2]))
    # Ours, unprepared.
    bench("drag_point (no preprocessing)", 1, lambda: drag_point(c, u, T3[0], 0, N_POLES - 1), 2000)
    cons3 = [Position(u, T3[0]), Tangent(u, T3[1]), Derivative(u, 2, T3[2])]
    bench("constrain, triple system (no preprocessing)", 3, lambda: constrain(c, cons3), 2000)
    # OCC, same curve, parameter and targets (edits in place).
    occ = to_occ(c)
    occ_p = gp_Pnt(*T3[0])
    occ_v = gp_Vec(*T3[1])
    bench("OCC Geom_BSplineCurve::MovePoint (poles 1..200)", 1, lambda: occ.MovePoint(u, occ_p, 1, N_POLES))
    occ2 = to_occ(c)
    bench("OCC Geom_BSplineCurve::MovePointAndTangent (conds -1, -1)", 2,
          lambda: occ2.MovePointAndTangent(u, occ_p, occ_v, 1e-9, -1, -1), 5000)
    return rows


def norm_comparison(cases: int = 200, seed: int = 1) -> dict[str, float]:
    """Ours vs OCC pole-change norms on random drags of the benchmark curve."""
    c = make_curve()
    rng = np.random.default_rng(seed)
    ratios, point_err = [], []
    tangent_ratios = []
    for _ in range(cases):
        u = float(rng.uniform(0.01, 0.99))
        T = c.evaluate(u) + rng.uniform(-2, 2, 3)
        centre = int(u * (N_POLES - 3))
        f, l = max(0, centre - int(rng.integers(0, 20))), min(N_POLES - 1, centre + 3 + int(rng.integers(0, 20)))
        ours = drag_point(c, u, T, f, l)
        occ = to_occ(c)
        occ.MovePoint(u, gp_Pnt(*T), f + 1, l + 1)
        P_occ = np.array([occ.Pole(i).Coord() for i in range(1, N_POLES + 1)])
        ratios.append(np.linalg.norm(P_occ - c.control_points) / np.linalg.norm(ours.control_points - c.control_points))
        point_err.append(max(np.abs(ours.evaluate(u) - T).max(), np.abs(np.array(occ.Value(u).Coord()) - T).max()))
        V = c.derivatives(u, 1)[1] * rng.uniform(0.5, 1.5) + rng.uniform(-20, 20, 3)
        occ2 = to_occ(c)
        (status,) = occ2.MovePointAndTangent(u, gp_Pnt(*T), gp_Vec(*V), 1e-9, -1, -1)
        if status == 0:
            P2 = np.array([occ2.Pole(i).Coord() for i in range(1, N_POLES + 1)])
            ours2 = constrain(c, [Position(u, T), Tangent(u, V)])
            tangent_ratios.append(np.linalg.norm(P2 - c.control_points)
                                  / np.linalg.norm(ours2.control_points - c.control_points))
    r, r2 = np.array(ratios), np.array(tangent_ratios)
    return dict(cases=cases, min=r.min(), median=float(np.median(r)), max=r.max(), point=max(point_err),
                t_cases=r2.size, t_min=r2.min(), t_median=float(np.median(r2)), t_max=r2.max())


def report() -> str:
    rows = timings()
    occ1 = next(t for label, k, t in rows if label.startswith("OCC") and k == 1)
    occ2 = next(t for label, k, t in rows if label.startswith("OCC") and k == 2)
    lines = [f"| operation | constraints | us per call | OCC MovePoint / this | within {TARGET_US:.0f} us |",
             "|---|---|---|---|---|"]
    for label, k, t in rows:
        ok = "" if label.startswith("OCC") or "no preprocessing" in label else ("yes" if t <= TARGET_US else "NO")
        lines.append(f"| {label} | {k} | {t:.1f} | {occ1 / t:.2f} | {ok} |")
    nc = norm_comparison()
    lines += [
        "",
        f"OCC MovePointAndTangent / our prepared position + tangent: "
        f"{occ2 / next(t for label, k, t in rows if label == 'Dragger.apply, position + tangent'):.2f}",
        "",
        "| pole-change norm, OCC / ours | cases | min | median | max |",
        "|---|---|---|---|---|",
        f"| MovePoint (random u, target, window) | {nc['cases']} | {nc['min']:.6g} | {nc['median']:.4g} | {nc['max']:.4g} |",
        f"| MovePointAndTangent (conds -1, -1) | {nc['t_cases']} | {nc['t_min']:.6g} | {nc['t_median']:.4g} | "
        f"{nc['t_max']:.4g} |",
        "",
        f"Largest distance of either edited curve from its target point: {nc['point']:.2g}.",
    ]
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    env = (f"Python {platform.python_version()}, NumPy {np.__version__}, {platform.machine()}, "
           f"{os.cpu_count()} CPUs, load average {load:.1f} during the run")
    return "\n".join(lines) + f"\n\n({env}; best of 7 repeats.)\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--write", action="store_true", help="rewrite benchmarks/MANIPULATION.md with the results")
    args = ap.parse_args(argv)
    text = report()
    print(text)
    if args.write:
        path = Path(__file__).with_name("MANIPULATION.md")
        path.write_text(HEADER + text + FOOTER)
        print(f"wrote {path}")
    return 0


HEADER = """# Direct manipulation benchmark (course §4-6: preprocessing, then one product per drag)

Generated by `benchmarks/bench_manipulation.py --write` on a 200-pole clamped uniform cubic in 3-D.
A drag update after preprocessing must take at most 50 us with 3 constraints.

"""

FOOTER = """
## How to read it

* `Dragger.apply` is the interactive step of course §4-6: the minimum-norm operator
  `W^-1/2 (G W^-1/2)^+` (a few active poles x m constraints) was computed once by pivoted QR;
  each drag is `targets - current`, one `(n_active x m) @ (m x 3)` product, a copy of the 200 poles
  and the construction of the new (frozen) curve. Its cost hardly depends on the number of poles.
* OCC's `MovePoint` recomputes its basis functions and moves the poles of its curve in place at
  every call; `MovePointAndTangent` solves its system at every call. In C++ `MovePoint` is some
  5x faster than our Python update; both are far below what a 60 Hz drag needs.
* The timings were taken on a shared machine (see the load average): between runs they vary by up
  to 2x (our prepared update 8-23 us, OCC's `MovePoint` 1.3-5.6 us over four runs); compare the
  ratios of one run.
* Norms: ours is the minimum-norm change of the movable poles, so OCC / ours >= 1 always. OCC's
  `MovePoint` heuristic moves the poles some 5-20 % more; `MovePointAndTangent` spreads its change
  over the whole window (all 200 poles with conditions -1, -1) where the minimum-norm change stays
  on the few poles acting at `u`, hence 4-7 times more. The hypothesis tests in
  `tests/bridge/test_manipulation_vs_occ.py` compare random curves (degrees 1-9, rational or not,
  clamped or not) and print the same table per case.
"""


if __name__ == "__main__":
    raise SystemExit(main())
