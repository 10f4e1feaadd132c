"""Benchmark: our curvature-continuous (G2) hole fill vs our G1 fill and OCC's filler asked for G2.

Per hole, three fills of the same loop, each measured by OCC at the same points along every
boundary edge (41 evenly spaced plus 16 clustered at each end):

* ours G1: ``fill_model(continuity='G1')`` (the n-patch central split, method 'central');
* ours G2: ``fill_model(continuity='G2')`` (one plate with the neighbours' curvature across each
  side, method 'plate');
* OCC G2: ``BRepOffsetAPI_MakeFilling`` with cadquery's defaults and the curvature constraint on
  every edge (the OCC result of the ``continuity='G2'`` run).

Measures: G0 gap (``LocalAnalysis_SurfaceContinuity.C0Value``, model units, model size ~14) and G1
angle (``G1Angle``, degrees), max over the boundary; the curvature jump, the largest relative jump
``|k1 - k2| / max(|k1|, |k2|)`` of the normal curvature across the edge from OCC's principal
curvatures (``joints.assess_curvature``, as a percentage). For ours G2 and OCC G2 the jump is the
one ``fill_model`` reports (``g2``, ``occ_g2``); our G1 fill's is measured here with
``assess_curvature`` on its faces, the boundary points projected onto them (``locate=None``).
Times are wall-clock for the fill alone (ours: ``HoleReport.seconds``, the fill and its OCC
measurement, the latter under 0.03 s; OCC: ``Add`` + ``Build``), one run per case in a single process (no best-of: the G2
fills take seconds), so the machine's load (printed) matters.

Holes: ring models of examples/hole_models.py (smooth: bump=0, n = 3, 4, 5, 6, 8 polynomial and 5,
8 rational; bump: multi-span sides, n = 3, 4, 6 polynomial and 5 rational) and every hole of
step_samples/holes/dome_holes.step.

Run:  python benchmarks/bench_fill_g2.py [--quick]
      (about 70 s on the 2-core machine; --quick: the smooth and the bump 4-sided rings only, ~12 s)
"""

from __future__ import annotations

import argparse
import datetime
import os
import statistics
import time
from pathlib import Path
from typing import Any

import common  # noqa: F401 - pins BLAS threads before NumPy
from OCP.BRep import BRep_Tool

from occsurf.algorithms import tolerances
from occsurf.bridge.conversion.splines import make_face
from occsurf.bridge.exchange.step_iges import read_step
from occsurf.bridge.modeling.fill import ASSESS_SAMPLES, fill_model, model_holes, neighbour_face, sew_faces
from occsurf.bridge.modeling.joints import assess_curvature
from occsurf.examples.hole_models import ring_model

DOME = Path(__file__).resolve().parents[1] / "step_samples" / "holes" / "dome_holes.step"

# (label, n, rational, bump): bump 0 = smooth ring, None = ring_model's default bump
RINGS = ([(f"smooth n={n}", n, False, 0.0) for n in (3, 4, 5, 6, 8)]
         + [(f"smooth n={n} rational", n, True, 0.0) for n in (5, 8)]
         + [(f"bump n={n}", n, False, None) for n in (3, 4, 6)]
         + [("bump n=5 rational", 5, True, None)])
QUICK = {"smooth n=4", "bump n=4"}


def _ring_shell(n: int, rational: bool, bump: float | None) -> Any:
    kw = {} if bump is None else {"bump": bump}
    return sew_faces([make_face(f, 1e-7) for f in ring_model(n, rational=rational, **kw).faces])


def cases(quick: bool) -> list[tuple[str, Any]]:
    out = [(label, _ring_shell(n, rational, bump)) for label, n, rational, bump in RINGS
           if not quick or label in QUICK]
    if not quick:
        model = read_step(DOME)
        out.append((DOME.name, getattr(model, "shape", model)))
    return out


def _g1_jump(holes: Any, k: int, rep: Any) -> float:
    """Largest relative curvature jump (fraction) of our G1 fill of hole ``k`` to its neighbours."""
    edges = holes.loops[k][0]
    if len(edges) != rep.sides:
        raise RuntimeError(f"hole {k}: {len(edges)} edges here, {rep.sides} in the fill")
    surfs = [BRep_Tool.Surface_s(f) for f in rep._fill_faces]
    floor = tolerances.CONTINUITY_CURVATURE_FLOOR / holes.size
    return max(assess_curvature(e, neighbour_face(holes.e2f, e), surfs, floor, samples=ASSESS_SAMPLES,
                                locate=None)[0] for e in edges)


def run_case(label: str, shape: Any) -> list[dict]:
    g1 = fill_model(shape, continuity="G1", compare_occ=False)
    g2 = fill_model(shape, continuity="G2", compare_occ=True)
    holes = model_holes(shape)  # the same loops in the same order, for the G1 curvature measure
    rows = []
    for a, b in zip(g1.holes, g2.holes):
        if a.status == "outer":
            continue
        name = label if len(holes.loops) <= 2 else f"{label} #{a.index} ({a.sides}-sided)"
        r = dict(case=name, g1=a, g2=b, g1_jump=None, notes=[])
        if a.status == "filled":
            r["g1_jump"] = _g1_jump(holes, a.index, a)
        else:
            r["notes"].append(f"ours G1 failed: {a.reason}")
        if a.method != "central":
            r["notes"].append(f"ours G1 method {a.method!r}")
        if b.status != "filled":
            r["notes"].append(f"ours G2 failed: {b.reason}")
        elif b.method != "plate" or b.reason:
            r["notes"].append(f"ours G2 method {b.method!r}" + (f": {b.reason}" if b.reason else ""))
        if b.occ_status != "ok":
            r["notes"].append(f"OCC G2 failed: {b.occ_reason}")
        rows.append(r)
    return rows


def _pct(x: float | None) -> str:
    return "-" if x is None else f"{100 * x:.3g} %"


def _fill(seconds: float | None, g0: float | None, g1: float | None, jump: float | None) -> str:
    if g0 is None:
        return f"{seconds:.3f} s | - | - | -" if seconds is not None else "- | - | - | -"
    return f"{seconds:.3f} s | {g0:.1e} | {g1:.1e} deg | {_pct(jump)}"


def _ratios(r: dict) -> tuple[float | None, float | None]:
    a, b = r["g1"], r["g2"]
    ok = a.status == "filled" and b.status == "filled"
    over_g1 = b.seconds / a.seconds if ok else None
    over_occ = b.seconds / b.occ_seconds if b.status == "filled" and b.occ_status == "ok" else None
    return over_g1, over_occ


def _ratio(x: float | None) -> str:
    return "-" if x is None else f"{x:.1f}"


def line(r: dict) -> str:
    a, b = r["g1"], r["g2"]
    ours1 = _fill(a.seconds, a.g0, a.g1, r["g1_jump"]) if a.status == "filled" else f"failed: {a.reason} | - | - | -"
    ours2 = _fill(b.seconds, b.g0, b.g1, b.g2) if b.status == "filled" else f"failed: {b.reason} | - | - | -"
    if b.occ_status == "ok":
        occ = _fill(b.occ_seconds, b.occ_g0, b.occ_g1, b.occ_g2)
    else:
        occ = f"{b.occ_seconds:.3f} s | failed: {b.occ_reason} | - | -" if b.occ_seconds else f"failed: {b.occ_reason} | - | - | -"
    over_g1, over_occ = _ratios(r)
    return f"| {r['case']} | {ours1} | {ours2} | {occ} | {_ratio(over_g1)} | {_ratio(over_occ)} |"


HEAD = ("| case | ours G1 time | G0 | G1 | curv. jump | ours G2 time | G0 | G1 | curv. jump "
        "| OCC G2 time | G0 | G1 | curv. jump | time G2/G1 | time ours G2/OCC G2 |")


def markdown(rows: list[dict]) -> str:
    return "\n".join([HEAD, "|" + "---|" * HEAD.count(" | ") + "---|"] + [line(r) for r in rows])


def medians(rows: list[dict]) -> str:
    def med(xs: list[float | None]) -> str:
        xs = [x for x in xs if x is not None]
        return f"{statistics.median(xs):.3g}" if xs else "-"

    ok1 = [r for r in rows if r["g1"].status == "filled"]
    ok2 = [r for r in rows if r["g2"].status == "filled"]
    okocc = [r for r in rows if r["g2"].occ_status == "ok"]
    return "\n".join([
        f"medians over {len(rows)} holes:",
        f"  time: ours G1 {med([r['g1'].seconds for r in ok1])} s, ours G2 {med([r['g2'].seconds for r in ok2])} s, "
        f"OCC G2 {med([r['g2'].occ_seconds for r in okocc])} s",
        f"  time ratio ours G2 / ours G1 {med([_ratios(r)[0] for r in rows])}, "
        f"ours G2 / OCC G2 {med([_ratios(r)[1] for r in rows])}",
        f"  curvature jump %: ours G1 {med([100 * r['g1_jump'] for r in ok1 if r['g1_jump'] is not None])}, "
        f"ours G2 {med([100 * r['g2'].g2 for r in ok2 if r['g2'].g2 is not None])}, "
        f"OCC G2 {med([100 * r['g2'].occ_g2 for r in okocc if r['g2'].occ_g2 is not None])}",
        f"  G1 angle deg: ours G1 {med([r['g1'].g1 for r in ok1])}, ours G2 {med([r['g2'].g1 for r in ok2])}, "
        f"OCC G2 {med([r['g2'].occ_g1 for r in okocc])}",
    ])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="only the smooth and the bump 4-sided rings")
    args = ap.parse_args()
    t0 = time.perf_counter()
    load0 = os.getloadavg()
    rows: list[dict] = []
    for label, shape in cases(args.quick):
        t = time.perf_counter()
        new = run_case(label, shape)
        for r in new:
            print(line(r), flush=True)
        print(f"  ({label}: {time.perf_counter() - t:.1f} s)", flush=True)
        rows += new
    print()
    print(f"{datetime.datetime.now().isoformat(timespec='seconds')}; {common.machine_note()}")
    print("times: one run each, wall clock; G0 gap in model units (model size ~14), G1 angle in degrees; "
          "curv. jump: largest relative normal-curvature jump across the boundary")
    print(markdown(rows))
    notes = [f"- {r['case']}: {n}" for r in rows for n in r["notes"]]
    if notes:
        print("\n".join(["", "notes:"] + notes))
    print()
    print(medians(rows))
    print(f"\nload average (1, 5, 15 min): before {tuple(round(x, 2) for x in load0)}, "
          f"after {tuple(round(x, 2) for x in os.getloadavg())}")
    print(f"(total {time.perf_counter() - t0:.1f} s)")


if __name__ == "__main__":
    main()
