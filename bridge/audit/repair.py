"""Repair what the report finds: match every smooth edge that breaks a preset (issue 29, item 4).

:func:`repair_model` is the loop assess -> repair -> assess again:

1. :func:`occsurf.bridge.quality.continuity.edge_continuity` and
   :func:`~occsurf.bridge.quality.continuity.check_edges` find the edges that break the preset;
   the ones meant to be smooth (not classified ``sharp``, ``gap``, ``seam`` or ``degenerate``)
   with a G1 or curvature violation are repaired, worst first;
2. for each, the face that moves is the one with fewer other smooth edges (the fewer constraints
   it carries), ties to the smaller area; the continuity asked is G2 where the preset checks
   curvature jumps, else G1, at half the preset's tolerances (so that the check after passes with
   room); G1 is also tried where G2 is refused, on edges that break G1 (an edge that breaks only
   the curvature measures is G1 already). :class:`.matching.FaceMatcher` does it on one
   :class:`.model_edits.ModelEdits` (sewn once). A match is refused (and the other face tried)
   when it fails, would move the face more than ``max_change``, misses the tolerances, would
   leave any other edge of the face worse than it was (and than the preset allows) by OCC's
   measure, or gives an invalid face;
3. the B-spline faces ``face_flags`` flags for wiggles are faired
   (:func:`.fairing.fair_edited`, within ``max_change``, the outer pole rows held);
4. the model is made once, checked by ``BRepCheck_Analyzer`` and again with the same preset.

A sharp edge is never changed (it is not a candidate), nor is any face moved by more than
``max_change`` (default 1e-3 of the model's size).
"""

from __future__ import annotations

import html
import math
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from OCP.BRep import BRep_Tool
from OCP.BRepCheck import BRepCheck_Analyzer
from OCP.BRepGProp import BRepGProp
from OCP.Geom import Geom_BSplineSurface
from OCP.GProp import GProp_GProps

from occsurf.algorithms.errors import OccsurfError

from .. import _occ
from ..modeling.fairing import FaceFairing, fair_edited
from ..modeling.matching import FaceMatcher
from ..modeling.model_edits import ModelEdits

__all__ = ["RepairReport", "EdgeRepair", "repair_model", "write_repair_page", "MAX_CHANGE_RTOL", "REPAIR_MAX_POLES"]

#: Default largest change of a face, relative to the model's size (bounding-box diagonal).
MAX_CHANGE_RTOL: float = 1e-3
#: The most poles along the matched side a repair's match may refine to (``match_surface``'s
#: ``max_poles``; its own default is ``tolerances.MATCH_MAX_POLES``, 400). On the OCCT bearing every
#: match that met its tolerances needed at most 47 (503 matches; the largest, 86, did not meet
#: them). On linkrods, G2 matches against sampled targets that miss by 11 to 75 deg refined 18 ->
#: 208 poles in 52 s before folding back over the target: each round's solve costs the cube of
#: the poles, and such a match is not one a repair would keep.
REPAIR_MAX_POLES: int = 64


@dataclass
class EdgeRepair:
    """One edge: its faces (input numbering), what broke, what was done."""

    edge: int
    faces: tuple[int, int]
    classification: str
    measures: list[str]
    g1_before_deg: float
    g2_rel_before: float
    status: str = "refused"  # "repaired" or "refused"
    moved: int | None = None
    continuity: str | None = None
    reason: str | None = None
    g1_after_deg: float | None = None
    max_change: float | None = None
    #: The check after the repair, on the same pair of faces (the largest over their edges), by the
    #: same measure as ``g1_before_deg`` / ``g2_rel_before``; ``breaks_after``: it still breaks the preset.
    g1_check_after_deg: float | None = None
    g2_rel_check_after: float | None = None
    breaks_after: bool | None = None


@dataclass
class RepairReport:
    """What :func:`repair_model` did; ``violations_*``: the preset's violations on smooth edges."""

    preset: str
    max_change: float
    edges: list[EdgeRepair] = field(default_factory=list)
    violations_before: int = 0
    violations_after: int = 0
    edges_breaking_before: int = 0
    edges_breaking_after: int = 0
    worst_smooth_g1_before: float = 0.0
    worst_smooth_g1_after: float = 0.0
    #: The smooth edges' violations per measure (``'g1'``, ``'g2_rel'``, ``'g2'``).
    by_measure_before: dict[str, int] = field(default_factory=dict)
    by_measure_after: dict[str, int] = field(default_factory=dict)
    faces_faired: int = 0
    #: ``BRepCheck_Analyzer`` on the whole repaired model.
    valid_after: bool = True
    fairings: list[dict[str, Any]] = field(default_factory=list)
    seconds: dict[str, float] = field(default_factory=dict)

    @property
    def repaired(self) -> int:
        return sum(e.status == "repaired" for e in self.edges)

    @property
    def refused(self) -> int:
        return sum(e.status == "refused" for e in self.edges)

    @property
    def repaired_still_breaking(self) -> int:
        """Repaired edges whose pair of faces the check after still counts as breaking the preset
        (``breaks_after``: any edge between the two faces). The causes include a measure left (G1
        matched where G2 could not be), a later match or fairing of either face, and the check's own
        measure, which compares the faces at equal edge parameters and so sees the edge's tolerance
        times the surfaces' curvature across it (the OCCT bearing's edge between faces 16 and 163:
        0.043 deg there, 0.002 deg by OCC's ``LocalAnalysis`` at the moved face's nearest points,
        the sewn edge's tolerance 1.6e-6)."""
        return sum(e.status == "repaired" and bool(e.breaks_after) for e in self.edges)

    def to_dict(self) -> dict[str, Any]:
        out = asdict(self)
        out.update(edges_repaired=self.repaired, edges_refused=self.refused,
                   edges_repaired_still_breaking=self.repaired_still_breaking)
        return _finite(out)


def _finite(x: Any) -> Any:
    if isinstance(x, float):
        return x if math.isfinite(x) else None
    if isinstance(x, dict):
        return {k: _finite(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_finite(v) for v in x]
    return x


_SMOOTH_MEASURES = ("g1", "g2_rel", "g2")
_NOT_SMOOTH = ("sharp", "gap", "seam", "degenerate")


def _breaking(shape: Any, preset: str) -> tuple[Any, dict[int, list[Any]], float]:
    """The continuity result, the smooth edges' violations by edge, and the worst smooth G1."""
    from ..quality.continuity import check_edges, edge_continuity

    res = edge_continuity(shape, preset=preset)
    by_edge: dict[int, list[Any]] = {}
    for v in check_edges(res, preset):
        r = res[v.edge]
        if v.measure in _SMOOTH_MEASURES and r.classification not in _NOT_SMOOTH and r.faces[0] != r.faces[1]:
            by_edge.setdefault(v.edge, []).append(v)
    worst = max((r.g1_max_deg for r in res if r.classification not in _NOT_SMOOTH
                 and math.isfinite(r.g1_max_deg)), default=0.0)
    return res, by_edge, float(worst)


def _edges_after(edges: list[EdgeRepair], res: Any, breaking: dict[int, list[Any]], numbering: list[int]) -> None:
    """Each edge's numbers in the check after the repair: the edges of the same two faces (the
    model after is numbered anew: ``numbering`` maps the input's faces to it)."""
    by_pair: dict[frozenset[int], list[int]] = {}
    for k, r in enumerate(res):
        by_pair.setdefault(frozenset(r.faces), []).append(k)
    for e in edges:
        ks = by_pair.get(frozenset(numbering[f] for f in e.faces), [])
        g1 = [res[k].g1_max_deg for k in ks if math.isfinite(res[k].g1_max_deg)]
        g2 = [res[k].g2_max_rel for k in ks if res[k].g2_max_rel is not None and math.isfinite(res[k].g2_max_rel)]
        e.g1_check_after_deg = max(g1) if g1 else None
        e.g2_rel_check_after = max(g2) if g2 else None
        e.breaks_after = any(k in breaking for k in ks) if ks else None


def _by_measure(by_edge: dict[int, list[Any]]) -> dict[str, int]:
    out: dict[str, int] = {}
    for vs in by_edge.values():
        for v in vs:
            out[v.measure] = out.get(v.measure, 0) + 1
    return dict(sorted(out.items()))


def _wiggly_faces(edits: ModelEdits) -> list[int]:
    """B-spline faces of the model that ``face_flags`` flags for wiggles."""
    from occsurf.algorithms.quality.flags import face_flags

    out = []
    for k in range(len(edits)):
        if not isinstance(BRep_Tool.Surface_s(edits.faces[k]), Geom_BSplineSurface):
            continue
        if any(fl.kind == "wiggle" for fl in face_flags(edits.surface(k)[0])):
            out.append(k)
    return out


def _area(face: Any) -> float:
    props = GProp_GProps()
    BRepGProp.SurfaceProperties_s(face, props)
    return float(props.Mass())


@_occ.quiet_messages()
def repair_model(shape: Any, preset: str = "catia", *, max_change: float | None = None
                 ) -> tuple[RepairReport, Any]:
    """Match every smooth edge of ``shape`` that breaks ``preset``; check again.

    Parameters
    ----------
    shape : TopoDS_Shape (or a build123d / cadquery shape)
        Faces numbered as ``occsurf check`` numbers them.
    preset : {'catia', 'class-a', 'mechanical'}
    max_change : float, optional
        Largest change of any face (model units); default ``MAX_CHANGE_RTOL`` x the model's size.

    Returns
    -------
    (RepairReport, TopoDS_Shape)
        The report (face numbers of the input) and the repaired model (sewn: numbered anew).
    """
    from ..quality.thresholds import PRESETS

    if preset not in PRESETS:
        raise OccsurfError(f"preset: expected one of {', '.join(sorted(PRESETS))}, got {preset!r}")
    th = PRESETS[preset]
    t0 = time.perf_counter()
    before, by_edge, worst0 = _breaking(shape, preset)
    size = float(before.stats.get("model_size") or 1.0)
    limit = MAX_CHANGE_RTOL * size if max_change is None else float(max_change)
    report = RepairReport(preset, limit, violations_before=sum(map(len, by_edge.values())),
                          edges_breaking_before=len(by_edge), worst_smooth_g1_before=worst0,
                          by_measure_before=_by_measure(by_edge))
    report.seconds["check_before"] = time.perf_counter() - t0
    edits = ModelEdits(shape)
    matcher = FaceMatcher(edits)
    smooth_count: dict[int, int] = {}
    for r in before:
        if r.classification not in _NOT_SMOOTH:
            for f in set(r.faces):
                smooth_count[f] = smooth_count.get(f, 0) + 1
    order = sorted(by_edge, key=lambda e: -max(v.value / v.limit for v in by_edge[e]))
    t1 = time.perf_counter()
    for e in order:
        r = before[e]
        a, b = r.faces
        item = EdgeRepair(e, (a, b), r.classification, sorted({v.measure for v in by_edge[e]}), r.g1_max_deg,
                          r.g2_max_rel)
        report.edges.append(item)
        # G2 where the preset checks curvature; where that would move a face too far, G1 still
        # mends the tangent planes -- where they break: an edge that breaks only the curvature
        # measures is G1 already, and a G1 match would change it for nothing (on the OCCT bearing
        # 111 of 116 "repairs" were such, before)
        conts = ["G1"] if th.g2_rel is None else ["G2", "G1"] if "g1" in item.measures else ["G2"]
        first = sorted((a, b), key=lambda f: (smooth_count.get(f, 0), _area(edits.model.faces[f])))
        reasons = []
        for cont, (move, other) in ((c, m) for c in conts for m in (first, first[::-1])):
            try:
                rep = matcher.match(move, other, cont, tol_g1_deg=0.5 * th.g1_deg,
                                    tol_g2_rel=0.5 * (th.g2_rel if th.g2_rel is not None else 2.0) / 100.0,
                                    strict=True, max_change=limit, others_deg=th.g1_deg, max_poles=REPAIR_MAX_POLES)
            except (OccsurfError, ValueError) as err:
                reasons.append(f"{cont} face {move}: {err}")
                continue
            if rep.refused is not None:
                reasons.append(f"{cont} face {move}: {rep.refused}")
                continue
            item.status, item.moved, item.continuity = "repaired", move, cont
            item.g1_after_deg, item.max_change = rep.g1_max_deg, rep.max_change
            break
        if item.status != "repaired":
            item.reason = "; ".join(reasons)
    report.seconds["match"] = time.perf_counter() - t1
    tf = time.perf_counter()
    wiggly = _wiggly_faces(edits)
    # a face next to an edge made G2 is faired holding its curvature there too (holding G1 only,
    # the lens's face 3 lost the G2 match of its edge to face 4: 19 % after); each face within what
    # its matches left of the change allowed
    g2_faces = {f for e in report.edges if e.status == "repaired" and e.continuity in ("G2", "G3") for f in e.faces}
    fairs: list[FaceFairing] = []
    for k in wiggly:
        budget = limit - edits.change(k)
        if budget <= 0.0:
            fairs.append(FaceFairing(k, "refused", reason=f"its matches have used the change allowed ({limit:.3g})"))
            continue
        fairs += fair_edited(edits, [k], tol=budget, hold="G2" if k in g2_faces else "G1")
    if fairs:
        report.fairings = [r.to_dict() for r in fairs]
        report.faces_faired = sum(r.status == "faired" for r in fairs)
    current, numbering = edits.shape()
    report.valid_after = bool(BRepCheck_Analyzer(current).IsValid())
    report.seconds["fair"] = time.perf_counter() - tf
    t2 = time.perf_counter()
    res_after, after, worst1 = _breaking(current, preset)
    _edges_after(report.edges, res_after, after, numbering)
    report.violations_after = sum(map(len, after.values()))
    report.edges_breaking_after = len(after)
    report.worst_smooth_g1_after = worst1
    report.by_measure_after = _by_measure(after)
    report.seconds["check_after"] = time.perf_counter() - t2
    report.seconds["total"] = time.perf_counter() - t0
    return report, current


def write_repair_page(report: RepairReport, folder: str | Path, source: str = "") -> Path:
    """``folder/index.html``: the counts before and after side by side, and every edge tried."""
    from ..exchange.files import atomic_write

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)

    def num(x: float | None, unit: str = "") -> str:
        return "-" if x is None or not math.isfinite(x) else f"{x:.3g}{unit}"

    def measures(counts: dict[str, int]) -> str:
        names = {"g1": "G1 angle", "g2_rel": "relative curvature jump", "g2": "curvature jump"}
        keys = sorted(set(report.by_measure_before) | set(report.by_measure_after))
        return "".join(f"<tr><th style='text-align:right'>{names.get(k, k)}</th><td>{counts.get(k, 0)}</td></tr>"
                       for k in keys)

    rows = "\n".join(
        f"<tr class='{e.status}'><td>{e.edge}</td><td>{e.faces[0]}-{e.faces[1]}</td><td>{html.escape(e.classification)}"
        f"</td><td>{', '.join(e.measures)}</td><td>{num(e.g1_before_deg, ' deg')}</td><td>{num(e.g2_rel_before, ' %')}"
        f"</td><td>{e.status}</td><td>{'' if e.moved is None else e.moved}</td><td>{e.continuity or ''}</td>"
        f"<td>{num(e.g1_after_deg, ' deg')}</td><td>{num(e.max_change)}</td><td>{num(e.g1_check_after_deg, ' deg')}</td>"
        f"<td>{num(e.g2_rel_check_after, ' %')}</td><td>{'' if e.breaks_after is None else 'yes' if e.breaks_after else 'no'}"
        f"</td><td>{html.escape(e.reason or '')}</td></tr>"
        for e in report.edges)
    fair_rows = "" if not report.fairings else (
        "<h2>Faces flagged for wiggles</h2><table><tr><th>face</th><th>status</th><th>wiggly iso-lines before</th>"
        "<th>after</th><th>change</th><th>reason</th></tr>" + "".join(
            f"<tr class='{'repaired' if f['status'] == 'faired' else 'refused'}'><td>{f['face']}</td><td>{f['status']}"
            f"</td><td>{f['wiggles_before']}</td><td>{f['wiggles_after']}</td><td>{num(f['max_deviation'])}</td>"
            f"<td>{html.escape(f['reason'] or '')}</td></tr>" for f in report.fairings) + "</table>")
    page = f"""<!doctype html><html><head><meta charset="utf-8"><title>occsurf repair {html.escape(source)}</title>
<style>body{{font-family:sans-serif;margin:1.5em}} table{{border-collapse:collapse}} td,th{{border:1px solid #ccc;
padding:2px 6px;font-size:13px}} tr.repaired{{background:#e8f6e8}} tr.refused{{background:#fbeaea}}
.side{{display:inline-block;vertical-align:top;margin-right:3em}}</style></head><body>
<h1>Repair of {html.escape(source)} ({html.escape(report.preset)})</h1>
<div class="side"><h2>Before</h2><table>
<tr><th>smooth edges breaking the preset</th><td>{report.edges_breaking_before}</td></tr>
<tr><th>violations on them</th><td>{report.violations_before}</td></tr>
<tr><th>worst smooth G1 angle</th><td>{num(report.worst_smooth_g1_before, ' deg')}</td></tr>
{measures(report.by_measure_before)}</table></div>
<div class="side"><h2>After</h2><table>
<tr><th>smooth edges breaking the preset</th><td>{report.edges_breaking_after}</td></tr>
<tr><th>violations on them</th><td>{report.violations_after}</td></tr>
<tr><th>worst smooth G1 angle</th><td>{num(report.worst_smooth_g1_after, ' deg')}</td></tr>
{measures(report.by_measure_after)}
<tr><th>valid (BRepCheck)</th><td>{'yes' if report.valid_after else 'NO'}</td></tr></table></div>
<p>Edges repaired: {report.repaired}; refused: {report.refused}; faces faired: {report.faces_faired};
largest change allowed {num(report.max_change)} (model units). Face numbers are the input's. In the
edge table "G1/G2 before" and "G1/G2 after" are the check's own measure on the model before and after
(the same as <code>occsurf check</code>); "G1 after (OCC)" is OCC's LocalAnalysis of the match that was made.</p>
{fair_rows}
<h2>Smooth edges that broke the preset</h2>
<table><tr><th>edge</th><th>faces</th><th>class</th><th>broke</th><th>G1 before</th><th>G2 before</th><th>status</th>
<th>moved</th><th>asked</th><th>G1 after (OCC)</th><th>change</th><th>G1 after</th><th>G2 after</th>
<th>still breaks</th><th>reason</th></tr>
{rows}</table></body></html>
"""
    path = folder / "index.html"
    atomic_write(path, page.encode("utf-8"))
    return path
