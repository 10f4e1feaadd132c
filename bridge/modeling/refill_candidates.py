"""Candidate fills of a hole, measured alike, and the choice between them (course §8-3).

:func:`fitted_fill` builds our candidates on the sides of :func:`.refill_sides.refill_sides` (both
variants: following the neighbours' traces, and on the model's edge curves): the central split
(:func:`occsurf.algorithms.topology.nsided.fill_hole`, n patches), and where that refuses, folds or
misses a target the plate (:func:`occsurf.algorithms.topology.plate_fill.fill_plate`, one trimmed
surface), and where neither is fold-free the wrapped plate (a plate about an axis); each is
measured with OCC (:func:`_measure`, ``LocalAnalysis_SurfaceContinuity``), scored against the
issue's targets (:func:`_score`) and the best kept (:func:`_plate_wins`); :func:`fill_method` names
the construction that won. OCC's own filler, ``BRepOffsetAPI_MakeFilling``
(:func:`occ_filling`, with cadquery's defaults :data:`OCC_DEFAULT` and tuned :data:`OCC_TUNED`),
is measured the same way for comparison (:func:`occ_variant`). Part of the refill of :mod:`.refill`.
"""

from __future__ import annotations

import operator
import time
from collections.abc import Callable
from typing import Any

from OCP.BRep import BRep_Tool
from OCP.BRepOffsetAPI import BRepOffsetAPI_MakeFilling
from OCP.GeomAbs import GeomAbs_Shape
from OCP.TopoDS import TopoDS

from occsurf.algorithms import tolerances
from occsurf.algorithms.errors import InvalidGeometryError, OccsurfError
from occsurf.algorithms.topology.nsided import HoleFill, fill_folds, fill_hole, fold_free_fill
from occsurf.algorithms.topology.plate_fill import PlateFill

from .. import _occ
from ..conversion.splines import make_face
from ..messages import one_line
from .joints import ASSESS_SAMPLES, SEW_TOLERANCE, assess_joint, filling_order
from .plate import plate_fill_faces, revolution_axes, wrapped_fill_faces
from .refill_sides import refill_side_variants, refill_sides

__all__ = ["fitted_fill", "fill_method", "occ_filling", "occ_variant", "OCC_DEFAULT", "OCC_TUNED", "PLATE_MARGIN"]

#: The plate (tried where the central split refuses, folds or misses a target) replaces a central
#: fill that does not fold only when its misses of the targets (:func:`_score`) are below this
#: fraction of the central fill's (:func:`_plate_wins`).
PLATE_MARGIN: float = 0.9
#: ``BRepOffsetAPI_MakeFilling`` parameters: cadquery's ``makeNSidedSurface`` defaults, and the
#: tuned ones of OCP_NOTES §6 (more points on each constraint, more iterations).
OCC_DEFAULT = dict(degree=3, nb_pts_on_cur=15, nb_iter=2, anisotropy=False, tol2d=1e-5, tol3d=1e-4,
                   tol_ang=1e-2, tol_curv=0.1, max_deg=8, max_segments=9)
OCC_TUNED = dict(OCC_DEFAULT, nb_pts_on_cur=30, nb_iter=4, tol3d=1e-6, tol_ang=1e-3)


def occ_filling(edges: list[Any], nbs: list[Any], g1: list[bool] | list[str], params: dict[str, Any]) -> Any:
    """OCC's ``BRepOffsetAPI_MakeFilling`` with ``params`` (:data:`OCC_DEFAULT`'s keys); per edge ``g1[k]``:
    ``True`` or ``'G1'`` (tangent to its neighbour), ``'G2'`` (curvature, :func:`.joints.filling_order`),
    ``False`` or ``'G0'`` (through the edge only)."""
    o = params
    mk = BRepOffsetAPI_MakeFilling(o["degree"], o["nb_pts_on_cur"], o["nb_iter"], o["anisotropy"], o["tol2d"],
                                   o["tol3d"], o["tol_ang"], o["tol_curv"], o["max_deg"], o["max_segments"])
    with _occ.kernel_errors("BRepOffsetAPI_MakeFilling"):
        for e, f, t in zip(edges, nbs, g1):
            if t is True or t in ("G1", "G2"):
                mk.Add(e, f, filling_order("G1" if t is True else str(t)), True)
            else:
                mk.Add(e, GeomAbs_Shape.GeomAbs_C0, True)
        mk.Build()
        if not mk.IsDone():
            raise InvalidGeometryError("BRepOffsetAPI_MakeFilling: not done")
        return TopoDS.Face_s(mk.Shape())


def _measure(edges: list[Any], nbs: list[Any], g1: list[bool], surfs: list[Any], locate: Any = None,
             samples: int = ASSESS_SAMPLES) -> tuple[list[float], list[float | None]]:
    s0: list[float] = []
    s1: list[float | None] = []
    for i, (e, f, t) in enumerate(zip(edges, nbs, g1)):
        loc = None if locate is None else locate(i)
        a, b = assess_joint(e, f, surfs, samples, locate=loc)
        s0.append(a)
        s1.append(b if t else None)
    return s0, s1


def occ_variant(edges: list[Any], nbs: list[Any], g1: list[bool], params: dict[str, Any],
                time_limit: float | None = None) -> dict[str, Any]:
    """OCC's filler (:func:`occ_filling` with ``params``) on the hole, measured as our fills are:
    ``{"status": "ok", "seconds", "g0", "g1", "side_g0", "side_g1"}`` or ``{"status": "failed",
    "reason", "seconds"}``.

    ``time_limit`` (seconds): the filler and its measurement run in a child process (forked: it
    shares the edges and faces as they are), stopped at the limit; then ``{"status": "timeout",
    "reason", "seconds"}``. ``BRepOffsetAPI_MakeFilling`` cannot be interrupted in process, and on
    some holes of real models it runs for tens of minutes (a pair of the bearing's faces: over 30
    min tuned); a benchmark comparing every hole needs to go on. ``None`` (default): in process.
    """
    if time_limit is None:
        return _occ_variant(edges, nbs, g1, params)
    return _occ_variant_limited(edges, nbs, g1, params, float(time_limit))


def _occ_variant_limited(edges: list[Any], nbs: list[Any], g1: list[bool], params: dict[str, Any],
                         time_limit: float) -> dict[str, Any]:
    """:func:`occ_variant` in a forked child, waited for ``time_limit`` seconds, killed after."""
    import multiprocessing

    ctx = multiprocessing.get_context("fork")  # the child takes the OCC shapes as they are, unpickled
    receive, send = ctx.Pipe(duplex=False)

    def child() -> None:
        receive.close()
        send.send(_occ_variant(edges, nbs, g1, params))
        send.close()

    t0 = time.perf_counter()
    proc = ctx.Process(target=child, daemon=True)
    proc.start()
    send.close()
    try:
        if receive.poll(time_limit):
            try:
                return dict(receive.recv())
            except EOFError:  # the child died without a result (a crash in OCC)
                proc.join()
                return {"status": "failed", "seconds": time.perf_counter() - t0,
                        "reason": f"BRepOffsetAPI_MakeFilling: its process ended without a result (exit {proc.exitcode})"}
        return {"status": "timeout", "seconds": time.perf_counter() - t0,
                "reason": f"BRepOffsetAPI_MakeFilling: no result within the time limit of {time_limit:g} s (stopped)"}
    finally:
        receive.close()
        if proc.is_alive():
            proc.kill()
        proc.join()


def _occ_variant(edges: list[Any], nbs: list[Any], g1: list[bool], params: dict[str, Any]) -> dict[str, Any]:
    """:func:`occ_variant` in process."""
    t0 = time.perf_counter()
    try:
        face = occ_filling(edges, nbs, g1, params)
        secs = time.perf_counter() - t0
        s0, s1 = _measure(edges, nbs, g1, [BRep_Tool.Surface_s(face)])
        return {"status": "ok", "seconds": secs, "g0": max(s0), "g1": max([a for a in s1 if a is not None], default=0.0),
                "side_g0": s0, "side_g1": s1}
    except Exception as err:  # noqa: BLE001
        return {"status": "failed", "reason": one_line(err, expected=(OccsurfError,)),
                "seconds": time.perf_counter() - t0}


def fill_method(fill: Any) -> str:
    """``'plate'`` for a :class:`PlateFill`, ``'wrap'`` for a plate made about an axis
    (:class:`~occsurf.algorithms.topology.plate_wrap.WrappedPlateFill`), ``'central'`` for the
    central split's :class:`HoleFill`."""
    if isinstance(fill, PlateFill):
        return "wrap" if fill.method == "wrapped plate" else "plate"
    return "central"


def _our_fill(edges: list[Any], nbs: list[Any], owners: list[Any], size: float, follow: bool,
              samples: int = ASSESS_SAMPLES, method: str = "central", prepared: tuple | None = None,
              fill: HoleFill | None = None) -> tuple:
    """Our fill of the hole, as OCC faces, measured: (faces, g1 flags, fit angles, side G0, side G1,
    the HoleFill or PlateFill, the side of each edge). ``method``: ``'central'`` (:func:`fill_hole`)
    or ``'plate'`` (:func:`fill_plate`: G1 asked on a side when any of its edges asks it, G0 to
    ``FILL_FIT_G0 * size``, at most ``FILL_PLATE_SEW_SHARE`` (half) of ``SEW_TOLERANCE``); ``prepared``: :func:`refill_sides`' result for these arguments;
    ``fill``: the central split already made on them (:func:`fold_free_fill`)."""
    sides, side_of_edge, g1, fit = prepared or refill_sides(edges, nbs, owners, size, follow)
    made: PlateFill | HoleFill
    if method == "plate":
        flags = [any(g1[k] for k in range(len(edges)) if side_of_edge[k] == j) for j in range(len(sides))]
        # G0 target: the 1e-7 of the model size, but at most half the sewing tolerance (the
        # face must sew in; plate_face refuses beyond SEW_TOLERANCE)
        g0_tol = min(tolerances.FILL_FIT_G0 * size, tolerances.FILL_PLATE_SEW_SHARE * SEW_TOLERANCE)
        made, occ_faces = plate_fill_faces(sides, flags, g0_tol,
                                           gap=max(BRep_Tool.Tolerance_s(e) for e in edges))
    elif method == "wrap":  # a plate in cylindrical coordinates about the neighbours' (or a fitted) axis
        flags = [any(g1[k] for k in range(len(edges)) if side_of_edge[k] == j) for j in range(len(sides))]
        g0_tol = min(tolerances.FILL_FIT_G0 * size, tolerances.FILL_PLATE_SEW_SHARE * SEW_TOLERANCE)
        made, occ_faces = wrapped_fill_faces(sides, flags, g0_tol,
                                             gap=max(BRep_Tool.Tolerance_s(e) for e in edges),
                                             axes=revolution_axes(nbs))
    else:
        made = fill_hole(sides) if fill is None else fill
        occ_faces = [make_face(p, tolerances.FILL_PATCH_FACE_TOL) for p in made.patches]
    surfs = [BRep_Tool.Surface_s(f) for f in occ_faces]

    def locate(i: int) -> Any:
        return lambda pts: made.locate_input(side_of_edge[i], pts)[:3]
    s0, s1 = _measure(edges, nbs, g1, surfs, locate, samples)
    return occ_faces, g1, fit, s0, s1, made, side_of_edge


def fitted_fill(edges: list[Any], nbs: list[Any], owners: list[Any], size: float,
                samples: int = ASSESS_SAMPLES) -> tuple:
    """The hole filled with fitted sides (trimming-curve edges), both boundary variants tried (the
    neighbours' traces, the model's edge curves) and the better kept (:func:`_score`); where
    following the traces keeps every edge curve the two are the same sides, filled once
    (:func:`.refill_sides.refill_side_variants`).

    The central split (:func:`fill_hole`) first; when it refuses both variants, or its best fill
    folds or misses one of the issue's targets (G0 1e-7 of the size, G1 0.01 deg: ``_score(...)[1]``
    above 1), the plate (:func:`fill_plate`, one trimmed surface: reflex corners, long curved holes)
    is tried on both and the best of all kept; where none of those is fold-free, the wrapped plate
    (:func:`~occsurf.algorithms.topology.plate_wrap.fill_wrapped_plate`, a plate in cylindrical
    coordinates about the neighbours' or a fitted axis: thread strips, fillet strips wrapping around
    an axis) is tried on both as well. The trigger was the looser edge-tolerance number
    (``[2]``) before: bearing faces 175, 185 and 198 kept central fills 1.8e-7, 1.7e-6 and 4.0e-8
    off a neighbour (OCC 1.7e-7, 6.8e-8, 2.8e-8) without trying the plate, which reads 2.5e-9 to
    7.4e-9 there with G1 no worse. The side curves (so the face's edge) are the same for both: at
    face 185's corner where one neighbour's trace runs 3.4e-6 past the other's, both edges stop
    there; the central split is measured at the closest point of its side curve, the plate (like
    OCC's fill) at the neighbour point's projection on its surface, which continues past the edge.

    A central split that folds loses to any fold-free candidate, so it is given up at its first
    folding patch (:func:`fold_free_fill`) and built in full only if every candidate folds
    (:class:`_Choice`): the same fill is chosen, bit for bit; linkrods' four largest holes took
    10.7-15.9 s before and 6.6-8.9 s after, the screw's face 8 12.8 -> 2.6 s.

    Returns the tuple of :func:`_our_fill` (its fill's type says which construction won:
    :func:`fill_method`).

    Raises
    ------
    InvalidGeometryError
        No variant can be filled by any construction (the last reason of each).
    """
    last_err: InvalidGeometryError | None = None
    etol = max(BRep_Tool.Tolerance_s(e) for e in edges)
    prepared = {}
    try:  # the neighbours' traces (G0 to them), and the model's edge curves: one variant where they agree
        variants = refill_side_variants(edges, nbs, owners, size)
    except InvalidGeometryError as err:
        variants = [(True, err)]
    choice = _Choice()  # a central split that folds is built in full only if every candidate folds
    for follow, prep in variants:
        if isinstance(prep, InvalidGeometryError):
            last_err = prep
            continue
        prepared[follow] = prep  # the plates below are tried on it even where the central split refuses
        try:
            cand = _Candidate.central(edges, nbs, owners, size, follow, samples, prep, etol)
        except InvalidGeometryError as err:
            last_err = err
            continue
        choice.offer(operator.lt, cand)
    # the plate where the central split refuses, folds or misses an issue target; the wrapped plate
    # (a hole winding around an axis) where neither gives a fold-free fill
    errors = {}
    for method in ("plate", "wrap"):  # judged on the best fill so far (a plate that won counts for the wrap)
        free = choice.fold_free
        if free is not None and not (method == "plate" and free.score[1] > 1.0):
            continue
        for follow, prep in prepared.items():
            try:
                cand = _Candidate(_our_fill(edges, nbs, owners, size, follow, samples, method=method, prepared=prep),
                                  size, etol)
            except OccsurfError as err:
                errors[method] = err
                continue
            choice.offer(_plate_wins, cand)
    best = choice.best
    plate_err, wrap_err = errors.get("plate"), errors.get("wrap")
    if best is None:
        if plate_err is None or last_err is None:
            first = last_err or plate_err
            assert first is not None  # no fill: the central split failed on each variant (last_err)
            raise first
        assert wrap_err is not None  # no fill: the wrapped plate was tried wherever the plate was
        raise InvalidGeometryError(f"central split: {one_line(last_err, expected=(OccsurfError,))}; "
                                   f"plate: {one_line(plate_err, expected=(OccsurfError,))}; "
                                   f"wrapped plate: {one_line(wrap_err, expected=(OccsurfError,))}") from plate_err
    return best.result


class _Choice:
    """The best of the candidates offered in turn, each with the rule that decides whether it replaces
    the best before it (``operator.lt`` on :func:`_score` between central splits, :func:`_plate_wins`
    for a plate): the best the sequence of comparisons leaves.

    A fold-free candidate beats every folding one under both rules and none that folds replaces
    it, so as soon as one is fold-free the best is the best of the fold-free ones alone
    (:attr:`fold_free`), found without the folding candidates' scores: a central split that folds
    (:meth:`_Candidate.central`) is then never built in full. Only where every candidate folds does
    :attr:`best` compare them all, in the order offered.
    """

    def __init__(self) -> None:
        self.offered: list[tuple[Callable[[Any, Any], bool], Any]] = []
        self.fold_free: Any = None

    def offer(self, rule: Callable[[Any, Any], bool], cand: Any) -> None:
        """Offer ``cand`` (with ``folds`` and ``score``); ``rule(new score, best score)`` says whether it
        replaces the best."""
        self.offered.append((rule, cand))
        if not cand.folds and (self.fold_free is None or rule(cand.score, self.fold_free.score)):
            self.fold_free = cand

    @property
    def best(self) -> Any:
        """The best candidate, ``None`` if none was offered."""
        if self.fold_free is not None:
            return self.fold_free
        best = None
        for rule, cand in self.offered:
            if best is None or rule(cand.score, best.score):
                best = cand
        return best


class _Candidate:
    """A candidate fill: :func:`_our_fill`'s tuple and its :func:`_score`, or (:meth:`central`) a
    central split known to fold, built and measured only when its score is asked for."""

    def __init__(self, result: tuple | None, size: float, etol: float,
                 build: Callable[[], tuple] | None = None) -> None:
        self._result, self._build, self._size, self._etol = result, build, size, etol
        self._score = None if result is None else _score(result, size, etol)  # once: it counts folds
        self.folds = True if self._score is None else self._score[0]

    @classmethod
    def central(cls, edges: list[Any], nbs: list[Any], owners: list[Any], size: float, follow: bool,
                samples: int, prepared: tuple, etol: float) -> _Candidate:
        """The central split on ``prepared`` sides: built and measured where it has no fold
        (:func:`fold_free_fill`), else left for later (``folds`` set)."""
        fill = fold_free_fill(prepared[0])
        built = _our_fill(edges, nbs, owners, size, follow, samples, prepared=prepared, fill=fill) if fill else None
        return cls(built, size, etol, build=lambda: _our_fill(edges, nbs, owners, size, follow, samples,
                                                              prepared=prepared))

    @property
    def result(self) -> tuple:
        """:func:`_our_fill`'s tuple (built now if it was left)."""
        if self._result is None:
            assert self._build is not None
            self._result = self._build()
            self._score = _score(self._result, self._size, self._etol)
        return self._result

    @property
    def score(self) -> tuple[bool, float, float]:
        """:func:`_score` of the fill (built now if it was left)."""
        self.result  # noqa: B018 - builds a left candidate
        assert self._score is not None
        return self._score


def _plate_wins(plate: tuple[bool, float, float], central: tuple[bool, float, float]) -> bool:
    """The plate replaces the central split's fill when that folds and the plate does not, or when
    both fold alike and the plate's misses (G0 and G1 in target units, :func:`_score`) are below
    ``PLATE_MARGIN`` of the central split's: a tie (the lens' face 1: both 0.0193 deg, set by the
    fitted fields at a corner) keeps the central split, whose G0 there is round-off (the plate's is its
    1e-7-of-the-size target). The numbers compared are the misses in the issue's units
    (``_score(...)[1]``): in the edges' tolerance (``[2]``) a central fill 1.3e-6 off a neighbour
    (0.16 of 8.1e-6) beat a plate 2.4e-7 off it (bearing face 181, G1 0.012 and 0.011 deg; OCC
    1.2e-6, 0.22 deg)."""
    if plate[0] != central[0]:
        return not plate[0]
    return plate[1] < PLATE_MARGIN * central[1]


def _score(cand: tuple, size: float, edge_tol: float = 0.0) -> tuple[bool, float, float]:
    """``(folds, misses, worse of G0 and G1 in looser G0 units)``, smaller is better.

    A fill that folds (:func:`fill_folds`) comes after every one that does not. Then ``misses``:
    G0 and G1 in units of the issue's targets (1e-7 of the model size, 0.01 deg), each at least 1,
    multiplied: a fill twice as far off in G0 is as bad as one twice as far off in G1, and a number
    within its target does not count (bearing face 0: a fill 7.9e-7 off, G1 0.070 deg, against one
    8.6e-7 off, 0.040 deg; the larger of the two numbers alone took the first). The third number
    is the worse of G1 and of G0 in units of the hole edges' own tolerance where that is larger:
    below 1 the fill meets its targets as far as the model itself declares its gaps, but it
    neither triggers the plate nor decides between two fills whose misses differ (it only breaks
    an exact tie of misses, e.g. two fills both within the targets): there a
    fill 4.4e-6 off the neighbour of an edge of tolerance 5.1e-6 (bearing face 170, on the model's
    edge curves) would count 0.86, as good as one 1.2e-8 off it (on the neighbour's trace)."""
    g0 = max(cand[3])
    g1 = max([a for a in cand[4] if a is not None], default=0.0) / tolerances.FILL_FIT_ANGLE
    target = tolerances.FILL_FIT_G0 * size
    misses = max(g0 / target, 1.0) * max(g1, 1.0)
    return fill_folds(cand[5]) > 0, misses, max(g0 / max(target, edge_tol), g1)


