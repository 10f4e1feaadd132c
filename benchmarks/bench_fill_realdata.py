"""Benchmark: remove faces of real models and refill them, occsurf vs OCC's BRepOffsetAPI_MakeFilling.

For every file of ../shared/realdata/ (public STEP/IGES models): each free-form face (B-spline or
Bézier) is removed on its own, and with --pairs each pair of adjacent free-form faces; where that
leaves one closed loop the hole is filled by :func:`occsurf.bridge.modeling.refill.refill_faces`
(trimmed neighbours: fitted cross fields; G1 asked on the edges where the original model was
tangent-continuous, G0 on its sharp edges) and by OCC's MakeFilling with the same constraints
(cadquery's defaults, and tuned: NbPtsOnCur 30, NbIter 4, Tol3d 1e-6, TolAng 1e-3). Both are
measured by OCC's LocalAnalysis_SurfaceContinuity (order G1) along every hole edge
(41 + 32 points per edge): G0 = max C0Value (model units), G1 = max G1Angle (degrees) over the
tangent edges. Our filled model is sewn and checked (BRepCheck_Analyzer, STEP round trip). Each
filled hole says which construction was kept (``method``: 'central', the n-patch central split, or
'plate', the trimmed thin-plate fill tried where the central split refuses, folds or misses a
target); the table has a row per method.

A fill counts as usable when it does not fold (occsurf: FillQuality.folds == 0) and, for either
filler, its G0 is at most 1e-3 of the model size (a gap of a thousandth of the part is no fill, even
where OCC returns a face: MakeFilling's "fills" of the screw's ten-turn thread strips miss their
boundaries by 0.8 mm on a 6 mm screw); both the raw and the usable counts are printed.

Times: the distribution (p50 / p90 / max) of the construction's own seconds (ours: ``seconds``,
OCC: each variant's ``seconds``), and the ratio ours / OCC tuned of the medians.

Quality against a baseline (``--baseline benchmarks/baselines/fill_realdata.json``, rows saved by
``--json`` on an earlier version): per hole in both, our G0 and G1 now against then; a hole filled
then and not now, or worse in G0 or G1 beyond round-off (G0 by more than 1e-9 of the model size or
1 % of the old value, G1 by more than 1e-6 degrees or 1 %), is listed as a regression and the
command exits 1.

Run:  python benchmarks/bench_fill_realdata.py [--pairs | --only-pairs] [--skip N] [--max-holes N] [--files F ...]
      [--json OUT] [--baseline OLD.json]
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
import sys
import time
from collections import Counter
from dataclasses import asdict
from pathlib import Path

import common  # noqa: F401 - pins BLAS threads before NumPy

REALDATA = Path(__file__).resolve().parents[2] / "shared" / "realdata"


def load(path: Path):
    from OCP.IFSelect import IFSelect_ReturnStatus
    from OCP.IGESControl import IGESControl_Reader
    from OCP.STEPControl import STEPControl_Reader

    r = IGESControl_Reader() if path.suffix.lower() in (".igs", ".iges") else STEPControl_Reader()
    if r.ReadFile(str(path)) != IFSelect_ReturnStatus.IFSelect_RetDone:
        raise OSError(f"{path}: cannot be read")
    r.TransferRoots()
    return r.OneShape()


def holes_of(path: Path, pairs: bool, max_holes: int | None, skip: int = 0, only_pairs: bool = False,
             on_row=None) -> list[dict]:
    from OCP.BRep import BRep_Tool
    from OCP.Geom import Geom_BezierSurface, Geom_BSplineSurface

    from occsurf.bridge.modeling.refill import SewnModel, refill_faces

    model = SewnModel(load(path))
    free = [i for i, f in enumerate(model.original)
            if isinstance(BRep_Tool.Surface_s(f), (Geom_BSplineSurface, Geom_BezierSurface))]
    sets = ([] if only_pairs else [[i] for i in free]) + ([list(p) for p in model.adjacent_pairs(free)]
                                                          if pairs or only_pairs else [])
    rows = []
    for faces in sets[skip:][:max_holes]:
        t0 = time.perf_counter()
        rep, _ = refill_faces(model, faces)
        row = asdict(rep)
        row.update(file=path.name, wall=time.perf_counter() - t0, size=model.size)
        rows.append(row)
        if on_row is not None:
            on_row(row)
        o, t = rep.occ.get("default", {}), rep.occ.get("tuned", {})
        print(f"{path.name} {faces}: {rep.status} {rep.method or '-'} n={rep.sides} G0 {rep.g0} G1 {rep.g1} folds {rep.folds} valid {rep.valid} "
              f"step {rep.step_round_trip} | OCC {o.get('status')} {o.get('g0')} {o.get('g1')} | tuned "
              f"{t.get('status')} {t.get('g0')} {t.get('g1')} | {row['wall']:.1f} s | {rep.reason or ''}",
              file=sys.stderr, flush=True)
    return rows


def _quantiles(vals: list[float]) -> str:
    """``p50 / p90 / max`` of ``vals`` (seconds), nearest-rank quantiles."""
    if not vals:
        return "-"
    v = sorted(vals)
    q = [v[min(len(v) - 1, max(0, math.ceil(p * len(v)) - 1))] for p in (0.5, 0.9)]
    return f"{q[0]:.2f} / {q[1]:.2f} / {v[-1]:.2f} s"


def time_table(rows: list[dict]) -> str:
    """The time distribution of each filler over the holes it filled, and ours / OCC tuned."""
    ours = [r["seconds"] for r in rows if r["status"] == "filled" and r.get("seconds") is not None]
    occ = {name: [r["occ"][name]["seconds"] for r in rows if r["occ"].get(name, {}).get("status") == "ok"]
           for name in ("default", "tuned")}
    out = ["| filler | holes | p50 / p90 / max |", "|---|---|---|",
           f"| occsurf | {len(ours)} | {_quantiles(ours)} |"]
    out += [f"| OCC MakeFilling {name} | {len(v)} | {_quantiles(v)} |" for name, v in occ.items()]
    if ours and occ["tuned"]:
        out.append(f"\nmedian ours / OCC tuned: {statistics.median(ours) / statistics.median(occ['tuned']):.1f}; "
                   f"holes over 1 s: {sum(t > 1 for t in ours)}, over 5 s: {sum(t > 5 for t in ours)} "
                   f"(of {len(ours)})")
    return "\n".join(out)


def _key(r: dict) -> tuple[str, tuple[int, ...]]:
    return r["file"], tuple(r["faces"])


def compare_baseline(rows: list[dict], base: list[dict]) -> tuple[str, int]:
    """Per hole in both runs: our G0 / G1 now against the baseline's; the regressions counted."""
    old = {_key(r): r for r in base}
    both = [(r, old[_key(r)]) for r in rows if _key(r) in old]
    lines, bad = [], 0
    better = same = 0
    for r, o in both:
        if o["status"] != "filled":
            continue
        if r["status"] != "filled":
            bad += 1
            lines.append(f"REGRESSION {r['file']} {r['faces']}: filled before, now {r['status']}: {r['reason']}")
            continue
        size = r.get("size") or 1.0
        worse_g0 = r["g0"] > o["g0"] + max(1e-9 * size, 0.01 * o["g0"])
        worse_g1 = r["g1"] > o["g1"] + max(1e-6, 0.01 * o["g1"])
        if worse_g0 or worse_g1:
            bad += 1
            lines.append(f"REGRESSION {r['file']} {r['faces']}: G0 {o['g0']:.2e} -> {r['g0']:.2e}, "
                         f"G1 {o['g1']:.2e} -> {r['g1']:.2e} deg")
        elif r["g0"] < o["g0"] - max(1e-9 * size, 0.01 * o["g0"]) or r["g1"] < o["g1"] - max(1e-6, 0.01 * o["g1"]):
            better += 1
        else:
            same += 1
    new = sum(1 for r, o in both if o["status"] != "filled" and r["status"] == "filled")
    head = (f"against the baseline ({len(both)} holes in both): {same} the same within round-off, {better} better, "
            f"{new} newly filled, {bad} worse")
    return "\n".join([head, *lines]), bad


def _stats(vals: list[float]) -> str:
    return f"{statistics.median(vals):.1e} / {max(vals):.1e}" if vals else "-"


def summary(rows: list[dict]) -> str:
    closed = [r for r in rows if r["occ"] or r["status"] == "filled"]
    out = [f"{len(rows)} face sets removed, {len(closed)} left a closed disk-like hole", "",
           "| filler | holes filled | G0 median / worst | G1 median / worst (deg) | time median | "
           "no worse than OCC default (G0 and G1) |", "|---|---|---|---|---|---|"]
    ours = [r for r in closed if r["status"] == "filled"]
    out.append(f"| occsurf | {len(ours)} / {len(closed)} | {_stats([r['g0'] for r in ours])} | "
               f"{_stats([r['g1'] for r in ours])} | {statistics.median([r['seconds'] for r in ours]) if ours else 0:.2f} s | "
               f"{_no_worse(closed)} |")
    for method in ("central", "plate", "wrap"):  # which construction each filled hole kept (refill.fitted_fill)
        mine = [r for r in ours if r.get("method", "central") == method]
        out.append(f"| occsurf, {method} | {len(mine)} / {len(closed)} | {_stats([r['g0'] for r in mine])} | "
                   f"{_stats([r['g1'] for r in mine])} | {statistics.median([r['seconds'] for r in mine]) if mine else 0:.2f} s | "
                   f"{_no_worse(mine)} |")
    for name in ("default", "tuned"):
        ok = [r["occ"][name] for r in closed if r["occ"].get(name, {}).get("status") == "ok"]
        out.append(f"| OCC MakeFilling {name} | {len(ok)} / {len(closed)} | {_stats([o['g0'] for o in ok])} | "
                   f"{_stats([o['g1'] for o in ok])} | {statistics.median([o['seconds'] for o in ok]) if ok else 0:.2f} s | |")
    valid = sum(bool(r["valid"]) for r in ours)
    step = sum(bool(r["step_round_trip"]) for r in ours)
    out += ["", f"occsurf filled models: {valid} / {len(ours)} valid (BRepCheck_Analyzer), {step} / {len(ours)} "
            "round-trip through STEP"]
    usable = [r for r in ours if not r.get("folds") and r["g0"] <= 1e-3 * r.get("size", float("inf"))]
    per_method = Counter(r.get("method", "central") for r in usable)
    out.append(f"usable fills (no fold, G0 <= 1e-3 of the model size): occsurf {len(usable)} / {len(closed)} "
               f"({', '.join(f'{m} {k}' for m, k in sorted(per_method.items()))}), "
               + ", ".join(f"OCC {name} {sum(1 for r in closed if _occ_usable(r, name))} / {len(closed)}"
                           for name in ("default", "tuned")))
    slow = sorted(ours, key=lambda r: -r["seconds"])[:3]
    if slow:  # where the time goes: the construction's own seconds (OCC's filler and the checks apart)
        out.append("slowest occsurf fills: " + ", ".join(f"{r['file'].split('__')[-1]} {r['faces']} {r['seconds']:.1f} s"
                                                          for r in slow))
    folded = [r for r in ours if r.get("folds")]
    if folded:
        out.append(f"occsurf fills that fold: {len(folded)} ("
                   + ", ".join(f"{r['file'].split('__')[-1]} {r['faces']}" for r in folded[:12]) + ")")
    reasons = Counter(_short(r["reason"]) for r in rows if r["status"] != "filled")
    if reasons:
        out += ["", "not filled by occsurf, per reason:"] + [f"- {n} x {why}" for why, n in reasons.most_common()]
    return "\n".join(out)


def _occ_usable(r: dict, name: str) -> bool:
    o = r["occ"].get(name, {})
    return o.get("status") == "ok" and o["g0"] <= 1e-3 * r.get("size", float("inf"))


#: Round-off floors of the comparison with OCC: G0 below 1e-12 of the model size and G1 below 1e-9
#: degrees are both exact (bearing pair [9, 24], planar: ours 1.4e-17 / 5.4e-13 deg, OCC's 2.2e-17 /
#: 2.2e-13 deg); beneath them "no worse" compares noise.
G0_FLOOR, G1_FLOOR = 1e-12, 1e-9


def _no_worse(closed: list[dict]) -> str:
    both = [r for r in closed if r["status"] == "filled" and r["occ"].get("default", {}).get("status") == "ok"]
    good = [r for r in both if r["g0"] <= max(r["occ"]["default"]["g0"], G0_FLOOR * r.get("size", 0.0))
            and r["g1"] <= max(r["occ"]["default"]["g1"], G1_FLOOR)]
    return f"{len(good)} / {len(both)}"


def _short(reason: str | None) -> str:
    import re

    return re.sub(r"[-+]?\d[\d.e+-]*", "#", reason or "?")[:140]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pairs", action="store_true", help="also remove each pair of adjacent free-form faces")
    ap.add_argument("--only-pairs", action="store_true", help="only the pairs of adjacent free-form faces")
    ap.add_argument("--skip", type=int, default=0, help="skip this many face sets per file first")
    ap.add_argument("--max-holes", type=int, default=None, help="at most this many face sets per file")
    ap.add_argument("--files", nargs="*", default=None, help="file names in realdata (default: all)")
    ap.add_argument("--json", default=None, help="write the per-hole rows here (rewritten after every hole)")
    ap.add_argument("--baseline", default=None, metavar="JSON",
                    help="compare our G0/G1 per hole with rows saved earlier (--json); exit 1 on a regression")
    ap.add_argument("--merge", nargs="+", default=None, metavar="JSON",
                    help="print the table of rows saved by earlier runs (--json) instead of running")
    ns = ap.parse_args()
    if ns.merge:
        rows = [r for f in ns.merge for r in json.loads(Path(f).read_text())]
        sys.exit(report(rows, ns.baseline))
    if not REALDATA.is_dir():
        sys.exit(f"skipped: {REALDATA} is absent")
    files = sorted(p for p in REALDATA.iterdir() if p.suffix.lower() in (".step", ".stp", ".iges", ".igs"))
    if ns.files:
        files = [p for p in files if p.name in ns.files]
    t0 = time.perf_counter()
    rows: list[dict] = []

    def save(row: dict) -> None:  # after every hole: a run stopped half-way keeps what it measured
        rows.append(row)
        if ns.json:
            tmp = Path(ns.json + ".tmp")
            tmp.write_text(json.dumps(rows, indent=1, default=str))
            tmp.replace(ns.json)

    for p in files:
        holes_of(p, ns.pairs, ns.max_holes, ns.skip, ns.only_pairs, on_row=save)
    code = report(rows, ns.baseline)
    print(f"\n(total {time.perf_counter() - t0:.0f} s)")
    sys.exit(code)


def report(rows: list[dict], baseline: str | None) -> int:
    """Print the tables (and the baseline comparison); 1 when a hole got worse."""
    print(summary(rows))
    print()
    print(time_table(rows))
    if baseline is None:
        return 0
    text, bad = compare_baseline(rows, json.loads(Path(baseline).read_text()))
    print()
    print(text)
    return 1 if bad else 0


if __name__ == "__main__":
    main()
