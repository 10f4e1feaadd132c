"""Remove faces of a model and fill the hole they leave (course §8-3 on real, trimmed models).

The "replace this face" workflow: :func:`refill_faces` removes faces (numbered as in ``inspect``:
``TopExp.MapShapes_s`` order, each face once) from the model sewn into shells, finds the hole's
loop of edges and fills it with :func:`occsurf.algorithms.topology.nsided.fill_hole`, the sides
described by curves and fitted cross fields (:func:`occsurf.algorithms.topology.nsided_sides.side_from_normals`):
the hole edges are trimming curves of their neighbours, not iso-lines. Where the central split
refuses (a reflex corner), folds (a long curved hole) or misses a target, one trimmed thin-plate
surface (:func:`occsurf.algorithms.topology.plate_fill.fill_plate`, OCC face by :mod:`.plate`)
is tried on the same sides and the better kept; :attr:`RefillReport.method` says which.

Per edge the continuity asked for is the original model's: an edge where the removed face met its
neighbour tangent-continuously (within :data:`G1_EDGE_DEG`) gets G1 to the neighbour (its normals
along the p-curve); a sharp edge gets G0 and the removed face's own tangent plane as its cross
field (the fill then keeps the original's shape there; no surface can be G1 to a neighbour the
original met at an angle). OCC's ``BRepOffsetAPI_MakeFilling`` gets the same constraints (G1
with the neighbour as support face on the tangent edges, C0 on the others), with cadquery's
defaults and with tuned parameters, and both are measured the same way, with OCC's
``LocalAnalysis_SurfaceContinuity`` (:func:`occsurf.bridge.modeling.fill.assess_joint`). The
filled model is sewn, checked with ``BRepCheck_Analyzer`` and written to / read back from STEP.

This module holds the entry points (:class:`RefillReport`, :func:`refill_faces`,
:func:`refill_model`); the steps live beside it, in the order they run:

* :mod:`.refill_loop` - the sewn model (:class:`SewnModel`), the hole's loop of edges, how faces
  meet along an edge (:data:`G1_EDGE_DEG`), the gap the model declares along the hole;
* :mod:`.refill_traces` - the neighbours' normals and traces along the hole edges, and side curves
  that follow the traces;
* :mod:`.refill_sides` - the sides handed to the fill: curves and fitted cross fields
  (:func:`refill_sides`);
* :mod:`.refill_candidates` - our candidate fills and OCC's, measured alike, and the choice
  (:func:`fitted_fill`);
* :mod:`.refill_sewing` - the fill sewn in, checked, and round-tripped through STEP.

The public names of those modules that were importable from here stay importable from here. Their
module-level constants are read at call time in their own modules: patch them there.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from occsurf.algorithms._validate import check_tol
from occsurf.algorithms.errors import InvalidGeometryError, OccsurfError
from occsurf.algorithms.topology.nsided import fill_folds

from ..messages import one_line
from .joints import check_continuity, unique_faces
from .refill_candidates import OCC_DEFAULT, OCC_TUNED, PLATE_MARGIN, fill_method, fitted_fill, occ_filling, occ_variant
from .refill_g2 import G2_REL, edge_classes, g2_fill, original_g2
from .refill_loop import (
    G1_EDGE_DEG,
    SewnModel,
    crease_note,
    face_components,
    hole_gap,
    hole_loop,
    joint_angle,
    model_faces,
)
from .refill_sewing import SEW_GAP_FACTOR, round_trip, sew_in_checked
from .refill_sides import EVEN_SPEED_RATIO, refill_sides
from .refill_traces import (
    CORNER_SLOPE,
    FIT_SAMPLES,
    TRACE_MAX_RESAMPLED,
    TRACE_MAX_SAMPLES,
    TRACE_SAMPLES_PER_POLE,
)

__all__ = ["RefillReport", "refill_faces", "refill_model", "refill_components", "sew_refills", "face_components", "model_faces", "fitted_fill", "G1_EDGE_DEG",
           "OCC_TUNED", "OCC_DEFAULT", "fill_method",
           # re-exported from the modules the refill was split into (importable from here before)
           "SewnModel", "hole_gap", "refill_sides", "occ_filling", "FIT_SAMPLES", "CORNER_SLOPE",
           "TRACE_SAMPLES_PER_POLE", "TRACE_MAX_SAMPLES", "TRACE_MAX_RESAMPLED", "PLATE_MARGIN", "SEW_GAP_FACTOR",
           "EVEN_SPEED_RATIO"]


@dataclass
class RefillReport:
    """One removal: the hole, our fill and OCC's, measured alike (JSON-safe; angles in degrees).

    ``g0`` is the largest ``C0Value`` over every hole edge; ``g1`` the largest ``G1Angle`` over the
    edges where G1 is asked (``g1_edges``); ``side_g0``/``side_g1`` per edge (``None`` for G1 where
    only G0 is asked); ``fit_g1`` the fitted cross fields' angle to the neighbours per edge.
    """

    faces: list[int]
    status: str  # 'filled', 'refused', 'failed'
    reason: str | None = None
    sides: int = 0
    g1_edges: int = 0
    seconds: float | None = None
    g0: float | None = None
    g1: float | None = None
    side_g0: list[float] = field(default_factory=list)
    side_g1: list[float | None] = field(default_factory=list)
    fit_g1: list[float] = field(default_factory=list)
    valid: bool | None = None
    step_round_trip: bool | None = None
    folds: int | None = None  # grid pairs where a patch turns back over itself (0: sound; see FillQuality.folds)
    method: str | None = None  # 'central' (fill_hole's n patches), 'plate' (one trimmed plate, fill_plate) or 'wrap' (a plate about an axis, fill_wrapped_plate)
    occ: dict[str, dict[str, Any]] = field(default_factory=dict)  # per OCC variant: refill_candidates.occ_variant's dict ('ok', 'failed' or 'timeout')
    continuity: str = "auto"  # asked: 'auto'/'G2' (G2 where the removed faces were curvature continuous), or 'G1' (issue 31)
    original_g2: list[float | None] = field(default_factory=list)  # G2 asked: the removed faces' jump per edge
    g2_edges: int = 0  # edges filled G2
    g2: float | None = None  # largest relative curvature jump over those edges (OCC's principal curvatures)
    side_g2: list[float | None] = field(default_factory=list)  # ... per edge (None: not asked G2)
    edge_asked: list[str] = field(default_factory=list)  # per edge: 'G2', 'G1' or 'G0' (what the original gave, capped by continuity)
    edge_continuity: list[str] = field(default_factory=list)  # per edge: what the fill reached (refill_g2.edge_classes)
    if TYPE_CHECKING:  # set on a filled report for refill_model and the pictures: plain attributes at run
        # time, not dataclass fields (asdict, the JSON, leaves them out); declared for the type checker
        _fill_faces: list[Any] = field(init=False)  # the fill's OCC faces
        _removed: list[Any] = field(init=False)  # the removed faces
        _neighbours: list[Any] = field(init=False)  # the hole's neighbours, each once


def refill_faces(model: SewnModel | Any, faces: list[int], *, compare_occ: bool = True, check: bool = True,
                 occ_variants: dict[str, dict[str, Any]] | None = None,
                 continuity: str = "auto", occ_time_limit: float | None = None) -> tuple[RefillReport, Any]:
    """Remove ``faces`` (inspect numbering) and fill the hole; returns the report and the new shape.

    Parameters
    ----------
    model : SewnModel or TopoDS_Shape
        The model (sew it once with :class:`SewnModel` when refilling many face sets).
    faces : list of int
        Indices of the faces to remove (they must form a disk: one closed loop).
    compare_occ : bool
        Also run ``BRepOffsetAPI_MakeFilling`` (``occ_variants``: name -> parameters; default
        ``{"default": OCC_DEFAULT, "tuned": OCC_TUNED}``) and measure it alike.
    check : bool
        Sew the fill in, check the result with ``BRepCheck_Analyzer`` and round-trip it through STEP.
    continuity : {'auto', 'G1', 'G2'}
        Per edge, what the removed faces gave (issue 31). ``'auto'`` (default) and ``'G2'``: where
        they met a neighbour curvature continuously (within :data:`.refill_g2.G2_REL`, the ``catia``
        preset's ``g2_rel``) the fill does too, by the G2 plate (:func:`.refill_g2.g2_fill`), G1
        where they were tangent, G0 elsewhere; where that plate cannot be made the fill is G1 and
        ``reason`` says why (``'G2'`` also when no edge was curvature continuous). ``'G1'``: G1
        where the removed faces were tangent, G0 elsewhere (:func:`fitted_fill`).
    occ_time_limit : float, optional
        Seconds each OCC comparison may take, run in a child process and stopped there (its
        entry in ``occ`` then has status ``'timeout'``); default ``None``: in process, unlimited
        (:func:`~.refill_candidates.occ_variant`).

    Returns
    -------
    (RefillReport, TopoDS_Shape or None)
        The shape is ``None`` unless our fill succeeded and ``check`` is set.
    """
    if not isinstance(model, SewnModel):
        from ..conversion.shapes import as_shape

        model = SewnModel(as_shape(model, "model"))
    n = len(model.faces)
    bad = [i for i in faces if not (isinstance(i, (int, np.integer)) and 0 <= i < n)]
    if bad or not faces:
        raise InvalidGeometryError(f"faces: expected indices 0..{n - 1} (as numbered by inspect), got {faces}")
    check_continuity(continuity)  # a bad argument, not a failure of the hole
    if occ_time_limit is not None:
        occ_time_limit = check_tol(occ_time_limit, "occ_time_limit")
        if occ_time_limit <= 0:
            raise InvalidGeometryError(f"occ_time_limit: expected a number of seconds > 0, got {occ_time_limit!r}")
    rep = RefillReport(faces=sorted(int(i) for i in faces), status="refused")
    try:
        edges, nbs, owners = hole_loop(model, rep.faces)
    except OccsurfError as err:
        rep.reason = one_line(err, expected=(OccsurfError,))
        return rep, None
    rep.sides = len(edges)
    shape = None
    g1 = [False] * len(edges)
    try:
        t0 = time.perf_counter()
        g2_try = _g2_attempt(rep, edges, nbs, owners, model.size, continuity)
        if g2_try is not None:
            occ_faces, g1, rep.fit_g1, rep.side_g0, rep.side_g1, rep.side_g2, fill = g2_try
            rep.g2_edges = sum(a is not None for a in rep.side_g2)
            rep.g2 = max([a for a in rep.side_g2 if a is not None], default=None)
        else:
            occ_faces, g1, rep.fit_g1, rep.side_g0, rep.side_g1, fill, _ = fitted_fill(edges, nbs, owners, model.size)
        rep.folds = fill_folds(fill)  # measured for a plate too (inside its trim)
        rep.method = fill_method(fill)
        rep.seconds = time.perf_counter() - t0
        rep.g1_edges = sum(g1)
        rep.g0 = max(rep.side_g0)
        rep.g1 = max([a for a in rep.side_g1 if a is not None], default=0.0)
        # asked: G2 where the removed face met its neighbour within G2_REL (original_g2's rule)
        jumps = rep.original_g2 or [None] * len(edges)  # not measured with continuity='G1'
        rep.edge_asked = ["G2" if j is not None and j <= G2_REL else "G1" if t else "G0" for j, t in zip(jumps, g1)]
        rep.edge_continuity = edge_classes(rep.side_g1, rep.side_g2)
        rep.status = "filled"
        rep._fill_faces = occ_faces  # for refill_model and the pictures (not fields: not serialised)
        rep._removed = [model.faces[i] for i in rep.faces]
        rep._neighbours = unique_faces(nbs)
        if check:
            shape, rep.valid = sew_in_checked(model, rep.faces, occ_faces, rep.g0)
            rep.step_round_trip = round_trip(shape, len(model_faces(shape)))
    except OccsurfError as err:
        rep.status, rep.reason = "refused", one_line(err, expected=(OccsurfError,)) + crease_note(model, rep.faces)
    except Exception as err:  # noqa: BLE001 - an OCC failure on one hole must not stop the others
        rep.status, rep.reason = "failed", one_line(err, expected=(OccsurfError,))
    if compare_occ:
        if rep.g1_edges == 0 and rep.status != "filled":
            g1 = [own is not None and _safe_joint(e, own, nb) for e, nb, own in zip(edges, nbs, owners)]
        for name, params in (occ_variants or {"default": OCC_DEFAULT, "tuned": OCC_TUNED}).items():
            rep.occ[name] = occ_variant(edges, nbs, g1, params, time_limit=occ_time_limit)
    return rep, shape


def _g2_attempt(rep: RefillReport, edges: list[Any], nbs: list[Any], owners: list[Any], size: float,
                continuity: str) -> tuple | None:
    """With ``continuity='G2'`` or ``'auto'``: the G2 plate's result (:func:`.refill_g2.g2_fill`) where
    an edge's removed face was curvature continuous to its neighbour, else ``None`` (the G1 refill
    then), the reason on ``rep`` (with ``'auto'`` only where a G2 edge was not met: G1 everywhere
    is what the original asked when no edge was G2)."""
    rep.continuity = continuity
    if continuity == "G1":
        return None
    from occsurf.algorithms import tolerances

    from .joints import ASSESS_SAMPLES

    floor = tolerances.CONTINUITY_CURVATURE_FLOOR / size
    orig = [original_g2(e, nb, own, floor, ASSESS_SAMPLES) for e, nb, own in zip(edges, nbs, owners)]
    rep.original_g2 = [None if np.isnan(j) else float(j) for _, j in orig]
    if not any(ok for ok, _ in orig):
        if continuity == "G2":
            rep.reason = "G2 asked: no edge of the removed faces was curvature continuous to its neighbour; filled G1"
        return None
    try:
        return g2_fill(edges, nbs, owners, size, [ok for ok, _ in orig], ASSESS_SAMPLES)
    except OccsurfError as err:
        rep.reason = f"G2 plate not made ({one_line(err, expected=(OccsurfError,))}); filled G1"
        return None


def _safe_joint(e: Any, own: Any, nb: Any) -> bool:
    try:
        return joint_angle(e, own, nb) <= G1_EDGE_DEG
    except Exception:  # noqa: BLE001
        return False


def refill_model(shape: Any, faces: list[int], *, compare_occ: bool = True,
                 continuity: str = "auto") -> tuple[list[RefillReport], Any]:
    """Remove ``faces`` (inspect numbering) and fill every hole they leave (one per edge-connected set),
    each with ``continuity`` (:func:`refill_faces`: by default, per edge what the removed faces gave).

    Returns
    -------
    (list of RefillReport, TopoDS_Shape or None)
        One report per hole; the sewn model with every fill that succeeded (``None`` when none did),
        whose ``valid``/``step_round_trip`` are recorded on every filled report.

    Raises
    ------
    InvalidGeometryError
        ``faces`` empty or out of range, or ``shape`` not a non-null shape.
    """
    from ..conversion.shapes import as_shape

    model = SewnModel(as_shape(shape, "shape"))
    reports = [refill_faces(model, comp, compare_occ=compare_occ, check=False, continuity=continuity)[0]
               for comp in refill_components(model, faces)]
    return reports, sew_refills(model, reports)


def refill_components(model: SewnModel, faces: list[int]) -> list[list[int]]:
    """``faces`` checked and grouped into edge-connected sets, one per hole (:func:`refill_model`).

    Raises
    ------
    InvalidGeometryError
        ``faces`` empty or not face indices of ``model``.
    """
    n = len(model.faces)
    bad = [i for i in faces if isinstance(i, bool) or not isinstance(i, (int, np.integer)) or not 0 <= i < n]
    if bad or not faces:
        raise InvalidGeometryError(f"faces: expected face indices 0..{n - 1} (numbered as by inspect), got {list(faces)}")
    return face_components(model, list(faces))


def sew_refills(model: SewnModel, reports: list[RefillReport]) -> Any:
    """The model with every filled report's faces sewn in at once (``None`` when none was filled).

    Checks the result (``BRepCheck_Analyzer``, a STEP round trip) and records both on every filled
    report (``valid``, ``step_round_trip``). The reports need their fill faces (``_fill_faces``), as
    :func:`refill_faces` leaves them.
    """
    filled = [r for r in reports if r.status == "filled"]
    if not filled:
        return None
    removed = sorted({i for r in filled for i in r.faces})
    result, valid = sew_in_checked(model, removed, [f for r in filled for f in r._fill_faces],
                                    max(cast(float, r.g0) for r in filled))
    trip = round_trip(result, len(model_faces(result)))
    for r in filled:
        r.valid, r.step_round_trip = valid, trip
    return result
