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
command exits 1. A ``--continuity G2`` run takes a baseline of G2 rows (and a G1 run one of G1
rows) and also compares the largest curvature jump of each hole filled G2 then: more than 1 % (or
1e-6) above it, or no G2 fill now, is a regression too.

Curvature continuity (``--continuity G2``; issue 31): every face set is refilled by
``refill_faces(..., continuity='G2')``, which asks G2 (the G2 plate) on the edges where the removed
faces met their neighbour within 2 % of relative curvature jump (``RefillReport.original_g2``) and G1
as before elsewhere; the tables above are then of those fills. For each hole with such an edge three
fills are set side by side on the edges filled G2 (where the G2 plate was not made: the originally
curvature-continuous edges): ours G2 (its ``g2``: the largest relative jump of the normal curvature
across those edges, OCC's principal curvatures at the plate's own parameters), ours G1 (the same
face set refilled with ``continuity='G1'``, neither checked nor compared with OCC) and OCC's
MakeFilling (cadquery's defaults, ``OCC_DEFAULT``) asked for curvature on those edges
(``GeomAbs_C1``, its curvature order: an OCC defect makes its ``GeomAbs_G2`` throw), G1 with the
neighbour on the other tangent edges and C0 on the sharp ones; the jumps of these two by
``joints.assess_curvature`` with the boundary points projected onto the fill. Then how many holes
had a G2 edge and were filled G2, the median and worst jump of each, and the median over those
holes of our time G2 / G1. ``--only-g2`` refills only the face sets with such an edge (``original_g2``
per hole edge, measured before any fill).

Run:  python benchmarks/bench_fill_realdata.py [--pairs | --only-pairs] [--skip N] [--max-holes N] [--files F ...]
      [--json OUT] [--baseline OLD.json] [--continuity G1|G2] [--only-g2]
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
             on_row=None, continuity: str = "G1", only_g2: bool = False, occ_time_limit: float | None = None) -> list[dict]:
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
        if only_g2 and not had_g2_edge(model, faces):
            continue
        t0 = time.perf_counter()
        rep, _ = refill_faces(model, faces, continuity=continuity, occ_time_limit=occ_time_limit)
        row = asdict(rep)
        row.update(file=path.name, wall=time.perf_counter() - t0, size=model.size)
        if continuity == "G2" and _g2_edges_of(row):
            try:
                row["g2_compare"] = g2_compare(model, rep)
            except Exception as err:  # noqa: BLE001 - listed under the G2 table; the other holes go on
                row["g2_compare_error"] = f"{type(err).__name__}: {err}"
            row["wall"] = time.perf_counter() - t0
        rows.append(row)
        if on_row is not None:
            on_row(row)
        o, t = rep.occ.get("default", {}), rep.occ.get("tuned", {})
        print(f"{path.name} {faces}: {rep.status} {rep.method or '-'} n={rep.sides} G0 {rep.g0} G1 {rep.g1} folds {rep.folds} valid {rep.valid} "
              f"step {rep.step_round_trip} | OCC {o.get('status')} {o.get('g0')} {o.get('g1')} | tuned "
              f"{t.get('status')} {t.get('g0')} {t.get('g1')} | {row['wall']:.1f} s | {rep.reason or ''}",
              file=sys.stderr, flush=True)
        if "g2_compare" in row:
            print("    " + " | ".join(_g2_cells(row)[2:]), file=sys.stderr, flush=True)
    return rows


def had_g2_edge(model, faces: list[int]) -> bool:
    """Whether the removed ``faces`` met a neighbour curvature continuously along an edge of their hole
    (:func:`occsurf.bridge.modeling.refill_g2.original_g2`, as ``refill_faces(continuity='G2')``
    measures it); ``False`` where they leave no closed loop."""
    from occsurf.algorithms import tolerances
    from occsurf.algorithms.errors import OccsurfError
    from occsurf.bridge.modeling.joints import ASSESS_SAMPLES
    from occsurf.bridge.modeling.refill_g2 import original_g2
    from occsurf.bridge.modeling.refill_loop import hole_loop

    try:
        edges, nbs, owners = hole_loop(model, sorted(faces))
    except OccsurfError:
        return False
    floor = tolerances.CONTINUITY_CURVATURE_FLOOR / model.size
    return any(original_g2(e, nb, own, floor, ASSESS_SAMPLES)[0] for e, nb, own in zip(edges, nbs, owners))


def _g2_edges_of(row: dict) -> list[int]:
    """The hole edges the G2 comparison is made on: those filled G2, else (no G2 plate) those where the
    removed faces were curvature continuous (``original_g2`` within ``G2_REL``)."""
    from occsurf.bridge.modeling.refill_g2 import G2_REL

    filled = [k for k, a in enumerate(row.get("side_g2") or []) if a is not None]
    return filled or [k for k, j in enumerate(row.get("original_g2") or []) if j is not None and j <= G2_REL]


def _jump(edges: list, nbs: list, on: list[int], surfs: list, floor: float) -> float:
    """Largest relative curvature jump (fraction) across the edges ``on`` between their neighbours and
    the fill (Geom ``surfs``), the boundary points projected onto it (``assess_curvature``, ``locate=None``)."""
    from occsurf.bridge.modeling.joints import ASSESS_SAMPLES, assess_curvature

    return max(assess_curvature(edges[k], nbs[k], surfs, floor, ASSESS_SAMPLES, locate=None, gap=False)[0] for k in on)


def g2_compare(model, rep) -> dict:
    """Beside the G2 refill ``rep`` (a hole with an originally curvature-continuous edge): our G1 refill
    of the same faces and OCC's filler asked for curvature, with their jumps on the same edges."""
    from OCP.BRep import BRep_Tool

    from occsurf.algorithms import tolerances
    from occsurf.algorithms.errors import OccsurfError
    from occsurf.bridge.messages import one_line
    from occsurf.bridge.modeling.joints import ASSESS_SAMPLES, assess_joint
    from occsurf.bridge.modeling.refill import refill_faces
    from occsurf.bridge.modeling.refill_candidates import OCC_DEFAULT, occ_filling
    from occsurf.bridge.modeling.refill_loop import G1_EDGE_DEG, hole_loop, joint_angle

    edges, nbs, owners = hole_loop(model, rep.faces)
    on = _g2_edges_of(asdict(rep))
    floor = tolerances.CONTINUITY_CURVATURE_FLOOR / model.size
    out: dict = {"edges": on}
    if rep.status == "filled":  # where the G2 plate was not made, our (G1) fill's jump there, projected
        try:  # projected for the plate too: the same measure as the other two (g2 is at its own parameters)
            out["ours_g2_jump_projected"] = _jump(edges, nbs, on, [BRep_Tool.Surface_s(f) for f in rep._fill_faces],
                                                  floor)
        except Exception as err:  # noqa: BLE001 - a measure failing on one hole must not stop the others
            out["ours_g2_jump_error"] = one_line(err, expected=(OccsurfError,))
        out["ours_g2_jump"] = rep.g2 if rep.g2_edges else out.get("ours_g2_jump_projected")
    g1rep, _ = refill_faces(model, rep.faces, compare_occ=False, check=False, continuity="G1")
    ours = {"status": g1rep.status, "reason": g1rep.reason, "method": g1rep.method, "seconds": g1rep.seconds,
            "g0": g1rep.g0, "g1": g1rep.g1}
    if g1rep.status == "filled":
        try:
            ours["jump"] = _jump(edges, nbs, on, [BRep_Tool.Surface_s(f) for f in g1rep._fill_faces], floor)
        except Exception as err:  # noqa: BLE001 - a measure failing on one hole must not stop the others
            ours["jump_error"] = one_line(err, expected=(OccsurfError,))
    out["ours_g1"] = ours
    # OCC: curvature on those edges, G1 (with the neighbour) where the fill was asked tangency, C0 elsewhere
    asked = next((r.side_g1 for r in (rep, g1rep) if r.status == "filled"), None)
    if asked is not None:
        tangent = [a is not None for a in asked]
    else:
        tangent = [own is not None and _tangent(joint_angle, e, own, nb, G1_EDGE_DEG)
                   for e, nb, own in zip(edges, nbs, owners)]
    orders = ["G2" if k in on else "G1" if tangent[k] else "G0" for k in range(len(edges))]
    t0 = time.perf_counter()
    try:
        face = occ_filling(edges, nbs, orders, OCC_DEFAULT)
        secs = time.perf_counter() - t0
        surfs = [BRep_Tool.Surface_s(face)]
        joints = [assess_joint(e, nb, surfs, ASSESS_SAMPLES) for e, nb in zip(edges, nbs)]
        out["occ"] = {"status": "ok", "seconds": secs, "g0": max(a for a, _ in joints),
                      "g1": max([b for (_, b), o in zip(joints, orders) if o != "G0"], default=0.0),
                      "jump": _jump(edges, nbs, on, surfs, floor)}
    except Exception as err:  # noqa: BLE001 - an OCC failure on one hole must not stop the others
        out["occ"] = {"status": "failed", "reason": one_line(err, expected=(OccsurfError,)),
                      "seconds": time.perf_counter() - t0}
    return out


def _tangent(joint_angle, e, own, nb, limit: float) -> bool:
    try:
        return joint_angle(e, own, nb) <= limit
    except Exception:  # noqa: BLE001
        return False


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
        j_then, j_now = o.get("g2"), r.get("g2")  # G2 rows: the largest relative curvature jump (a fraction)
        worse_g2 = j_then is not None and (j_now is None or j_now > j_then + max(1e-6, 0.01 * j_then))
        better_g2 = j_then is not None and j_now is not None and j_now < j_then - max(1e-6, 0.01 * j_then)
        if worse_g0 or worse_g1 or worse_g2:
            bad += 1
            jump = "" if j_then is None else f", jump {100 * j_then:.3g} % -> " + (
                "none (not filled G2)" if j_now is None else f"{100 * j_now:.3g} %")
            lines.append(f"REGRESSION {r['file']} {r['faces']}: G0 {o['g0']:.2e} -> {r['g0']:.2e}, "
                         f"G1 {o['g1']:.2e} -> {r['g1']:.2e} deg{jump}")
        elif (r["g0"] < o["g0"] - max(1e-9 * size, 0.01 * o["g0"]) or r["g1"] < o["g1"] - max(1e-6, 0.01 * o["g1"])
              or better_g2):
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


def _pct(j: float | None) -> str:
    return "-" if j is None else f"{100 * j:.3g} %"


def _num(x: float | None, fmt: str = ".1e") -> str:
    return "-" if x is None else format(x, fmt)


def _g2_cells(r: dict) -> list[str]:
    """One hole's cells of :func:`g2_table`."""
    c = r["g2_compare"]
    g1, o = c["ours_g1"], c["occ"]
    ours = (f"{r['status']} {r.get('method') or '-'}{'' if r.get('g2_edges') else ' (G1)'}, "
            f"{_num(r.get('seconds'), '.2f')} s, G0 {_num(r.get('g0'))}, G1 {_num(r.get('g1'), '.2g')} deg, "
            f"jump {_pct(c.get('ours_g2_jump'))}")
    mine = (f"{g1['status']} {g1.get('method') or '-'}, {_num(g1.get('seconds'), '.2f')} s, "
            f"G0 {_num(g1.get('g0'))}, G1 {_num(g1.get('g1'), '.2g')} deg, jump {_pct(g1.get('jump'))}")
    occ = (f"{o['status']}, {o['seconds']:.2f} s, G0 {_num(o.get('g0'))}, G1 {_num(o.get('g1'), '.2g')} deg, "
           f"jump {_pct(o.get('jump'))}")
    return [r["file"].split("__")[-1], str(r["faces"]),
            f"{sum(j is not None and j <= 0.02 for j in r['original_g2'])} ({len(c['edges'])})", ours, mine, occ,
            "; ".join(_g2_notes(r))]


def _g2_notes(r: dict) -> list[str]:
    """What looks wrong in one hole of :func:`g2_table`: a slow G2 fill, G0/G1 worse than the G1 refill's
    beyond round-off (as :func:`compare_baseline` judges), a fall-back's reason, a failure."""
    c = r["g2_compare"]
    g1 = c["ours_g1"]
    notes = []
    if (r.get("seconds") or 0.0) > 60:
        notes.append(f"G2 fill {r['seconds']:.0f} s")
    if r["status"] == "filled" and g1["status"] == "filled":
        size = r.get("size") or 1.0
        if r["g0"] > g1["g0"] + max(1e-9 * size, 0.01 * g1["g0"]):
            notes.append(f"G0 worse than G1 refill ({r['g0']:.2e} vs {g1['g0']:.2e})")
        if r["g1"] > g1["g1"] + max(1e-6, 0.01 * g1["g1"]):
            notes.append(f"G1 worse than G1 refill ({r['g1']:.3g} vs {g1['g1']:.3g} deg)")
    if r.get("folds"):
        notes.append(f"folds {r['folds']}")
    if r["status"] != "filled" or not r.get("g2_edges"):
        notes.append((r.get("reason") or "?")[:110])
    if g1["status"] != "filled":
        notes.append("G1 refill: " + (g1.get("reason") or "?")[:80])
    proj, own = c.get("ours_g2_jump_projected"), c.get("ours_g2_jump")
    if r.get("g2_edges") and proj is not None and own is not None and abs(proj - own) > max(0.01, 0.5 * own):
        notes.append(f"G2 jump projected {_pct(proj)}")
    if "ours_g2_jump_error" in c:
        notes.append("G2 jump: " + c["ours_g2_jump_error"][:80])
    if "jump_error" in g1:
        notes.append("G1 jump: " + g1["jump_error"][:80])
    if c["occ"]["status"] != "ok":
        notes.append("OCC: " + (c["occ"].get("reason") or "?")[:80])
    return notes


def g2_table(rows: list[dict]) -> str:
    """Per hole with an originally curvature-continuous edge: ours G2, ours G1 and OCC asked for
    curvature, their jumps on the same edges; then the counts, the jumps' median / worst and the times."""
    g2 = [r for r in rows if "g2_compare" in r]
    out = [f"curvature continuity (G2): {len(rows)} face sets refilled G2, {len(g2)} with an edge the removed "
           "faces met curvature continuously (within 2 %)", "",
           "| file | faces | G2 edges (compared) | ours G2: status method, s, G0, G1, jump | "
           "ours G1: status method, s, G0, G1, jump | OCC curvature-asked: status, s, G0, G1, jump | notes |",
           "|---|---|---|---|---|---|---|"]
    out += ["| " + " | ".join(_g2_cells(r)) + " |" for r in g2]
    made = [r for r in g2 if r["status"] == "filled" and r.get("g2_edges") and r.get("method") == "plate"]
    out += ["", f"face sets with a G2 edge: {len(g2)}; filled G2 (the G2 plate): {len(made)}"]
    jumps = {"ours G2": [r["g2_compare"].get("ours_g2_jump") for r in made],
             "ours G1": [r["g2_compare"]["ours_g1"].get("jump") for r in made],
             "OCC curvature-asked": [r["g2_compare"]["occ"].get("jump") for r in made]}
    out.append(f"jump median / worst on the holes filled G2 ({len(made)}): " + "; ".join(
        f"{name} {_jumps(v)}" for name, v in jumps.items()))
    within = [j for j in jumps["ours G2"] if j is not None and j <= 0.02]
    out.append(f"holes filled G2 whose jump is within 2 %: {len(within)} / {len(made)}; ours G1 "
               f"{sum(j is not None and j <= 0.02 for j in jumps['ours G1'])}, OCC "
               f"{sum(j is not None and j <= 0.02 for j in jumps['OCC curvature-asked'])}")
    every = {"ours G2": [r["g2_compare"].get("ours_g2_jump") for r in g2],
             "ours G1": [r["g2_compare"]["ours_g1"].get("jump") for r in g2],
             "OCC curvature-asked": [r["g2_compare"]["occ"].get("jump") for r in g2]}
    out.append(f"jump median / worst on every hole with a G2 edge ({len(g2)}; ours G2 fell back to G1 on "
               f"{len(g2) - len(made)}): " + "; ".join(f"{name} {_jumps(v)}" for name, v in every.items()))
    ratio = [r["seconds"] / r["g2_compare"]["ours_g1"]["seconds"] for r in made
             if r["g2_compare"]["ours_g1"].get("seconds")]
    if ratio:
        out.append(f"time ours G2 / ours G1, median over the holes filled G2: {statistics.median(ratio):.2g} "
                   f"(min {min(ratio):.2g}, max {max(ratio):.2g}); ours G2 median "
                   f"{statistics.median([r['seconds'] for r in made]):.2f} s, ours G1 median "
                   f"{statistics.median([r['g2_compare']['ours_g1']['seconds'] for r in made]):.2f} s")
    both = [(r, r["g2_compare"]["ours_g1"]) for r in made if r["g2_compare"]["ours_g1"]["status"] == "filled"]
    if both:
        out.append(f"G0 / G1 on the holes filled G2 ({len(both)}), each median / worst: ours G2 G0 "
                   f"{_stats([r['g0'] for r, _ in both])}, G1 {_stats([r['g1'] for r, _ in both])} deg; ours G1 G0 "
                   f"{_stats([g['g0'] for _, g in both])}, G1 {_stats([g['g1'] for _, g in both])} deg; ours G2 worse "
                   f"than ours G1 (beyond round-off) in G0 on {sum(any(n.startswith('G0 worse') for n in _g2_notes(r)) for r, _ in both)}, "
                   f"in G1 on {sum(any(n.startswith('G1 worse') for n in _g2_notes(r)) for r, _ in both)}")
    slow = [r for r in g2 if (r.get("seconds") or 0.0) > 60]
    out.append(f"G2 refills over 60 s: {len(slow)}" + (" (" + ", ".join(
        f"{r['file'].split('__')[-1]} {r['faces']} {r['seconds']:.0f} s" for r in slow) + ")" if slow else ""))
    broken = [r for r in rows if "g2_compare_error" in r]
    if broken:
        out.append("comparison failed on: " + ", ".join(f"{r['file'].split('__')[-1]} {r['faces']}: "
                                                        f"{r['g2_compare_error'][:100]}" for r in broken))
    occ_ok = [r["g2_compare"]["occ"]["seconds"] for r in g2 if r["g2_compare"]["occ"]["status"] == "ok"]
    out.append(f"OCC curvature-asked: {len(occ_ok)} / {len(g2)} made, time median "
               f"{statistics.median(occ_ok) if occ_ok else 0:.2f} s")
    return "\n".join(out)


def _jumps(vals: list[float | None]) -> str:
    v = [x for x in vals if x is not None]
    return f"{_pct(statistics.median(v))} / {_pct(max(v))} (of {len(v)})" if v else "-"


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
    ap.add_argument("--continuity", choices=("G1", "G2"), default="G1",
                    help="G2: refill curvature continuously where the removed faces were, beside our G1 "
                         "refill and OCC's filler asked for curvature")
    ap.add_argument("--only-g2", action="store_true",
                    help="only the face sets with an edge the removed faces met curvature continuously")
    ap.add_argument("--occ-time-limit", type=float, default=None, metavar="S",
                    help="stop each OCC MakeFilling comparison after S seconds (run in a child process; "
                         "recorded with status 'timeout'); default: unlimited, in process")
    ap.add_argument("--merge", nargs="+", default=None, metavar="JSON",
                    help="print the table of rows saved by earlier runs (--json) instead of running")
    ns = ap.parse_args()
    if ns.baseline and not ns.merge:  # G1 refills against G1 rows, G2 against G2 (jumps compared too)
        kinds = {r.get("continuity") == "G2" for r in json.loads(Path(ns.baseline).read_text())}
        if kinds != {ns.continuity == "G2"}:
            ap.error(f"--baseline {ns.baseline} holds {'G2' if True in kinds else 'G1'} refills"
                     f"{' and G1 ones' if len(kinds) > 1 else ''}; this run makes {ns.continuity} refills")
    if ns.only_g2 and ns.continuity != "G2":
        ap.error("--only-g2 goes with --continuity G2")
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
        holes_of(p, ns.pairs, ns.max_holes, ns.skip, ns.only_pairs, on_row=save, continuity=ns.continuity,
                 only_g2=ns.only_g2, occ_time_limit=ns.occ_time_limit)
    code = report(rows, ns.baseline)
    print(f"\n(total {time.perf_counter() - t0:.0f} s)")
    sys.exit(code)


def report(rows: list[dict], baseline: str | None) -> int:
    """Print the tables (and the baseline comparison); 1 when a hole got worse."""
    print(summary(rows))
    print()
    print(time_table(rows))
    if any(r.get("continuity") == "G2" for r in rows):
        print()
        print(g2_table(rows))
    if baseline is None:
        return 0
    text, bad = compare_baseline(rows, json.loads(Path(baseline).read_text()))
    print()
    print(text)
    return 1 if bad else 0


if __name__ == "__main__":
    main()
