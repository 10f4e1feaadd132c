"""The refinement machinery shared by the adaptive fits of gridded and scattered data (course §7-10).

:mod:`.adaptive` (data on a grid, ``(m, n)`` arrays) and :mod:`.adaptive_scattered` (a cloud,
``(k,)`` arrays) run the same process and differ only in how data are evaluated, measured, binned
into knot spans and solved for; this module holds the process once, with those differences passed
in as callables:

- :func:`grow_base`: the base's spans multiplied by 1.5 while the places to refine cover more
  than :data:`~occsurf.algorithms.tolerances.FIT_ADAPTIVE_MAX_COVER` of the domain;
- :func:`refine`: the rounds of flag, own, add overlays over the marked spans
  (:func:`rectangles`), fit them, backfit (:class:`OverlayFitter`), measure again;
- :func:`level_reports`: per level, the hierarchy truncated below it, measured.

References
----------
Course notes C25 (SIGGRAPH 1991) §7-10 and ch. 5; D. R. Forsey, R. H. Bartels, "Surface fitting
with hierarchical splines", ACM TOG 14 (1995) 134-161.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, TypeVar

import numpy as np
from numpy.typing import NDArray

from .. import tolerances
from ..errors import ParameterError
from ..hierarchical.overlays import Overlay
from ..hierarchical.surface import HierarchicalSurface
from ..kernel.surface import BSplineSurface

Array = NDArray[np.float64]
Region = tuple[tuple[float, float], tuple[float, float]]
#: Per datum its owner (:func:`owner`): the nodes (None: the base), the owner index per datum, the levels.
Owners = tuple[list[Overlay | None], NDArray[np.int_], NDArray[np.int_]]
_Fit = TypeVar("_Fit")  # an adaptive fit's base fit (grow_base passes it through)


@dataclass(frozen=True)
class LevelReport:
    """Statistics after fitting one level (level 0 is the base).

    Attributes
    ----------
    level : int
    overlays : int
        Overlays added at this level (0 for the base).
    control_points : int
        Degrees of freedom stored at this level: base poles, or the overlays' offsets.
    max_error, rms_error : float
        Distance from the data points to the surface up to this level, measured by projection.
    """

    level: int
    overlays: int
    control_points: int
    max_error: float
    rms_error: float

    def as_dict(self) -> dict:
        return {"level": self.level, "overlays": self.overlays, "control_points": self.control_points,
                "max_error": self.max_error, "rms_error": self.rms_error}


class FitSummary:
    """The error and size properties both adaptive results derive from their ``levels`` and
    ``hierarchy`` fields."""

    levels: tuple[LevelReport, ...]
    hierarchy: HierarchicalSurface

    @property
    def max_error(self) -> float:
        return self.levels[-1].max_error

    @property
    def rms_error(self) -> float:
        return self.levels[-1].rms_error

    @property
    def control_points_total(self) -> int:
        """Base poles plus stored offsets (course §5-17)."""
        return int(self.hierarchy.pole_counts()["stored"])


def check_tol_levels(tol: float, max_levels: int | None) -> tuple[float, int]:
    """``tol`` as a positive float and the deepest overlay level (default
    :data:`~occsurf.algorithms.tolerances.FIT_ADAPTIVE_MAX_LEVELS`); :class:`ParameterError` naming
    the argument otherwise."""
    try:
        tol = float(tol)
    except (TypeError, ValueError) as err:
        raise ParameterError(f"tol: expected a positive number, got {tol!r}") from err
    if not (np.isfinite(tol) and tol > 0):
        raise ParameterError(f"tol: expected a positive number, got {tol!r}")
    depth_max = int(tolerances.FIT_ADAPTIVE_MAX_LEVELS) if max_levels is None else int(max_levels)
    if depth_max < 0:
        raise ParameterError(f"max_levels: expected an integer >= 0, got {max_levels!r}")
    return tol, depth_max


def stats(dist: Array) -> tuple[float, float]:
    """Max and RMS of the finite entries of ``dist``."""
    e = dist[np.isfinite(dist)]
    return float(e.max()), float(np.sqrt(np.mean(e ** 2)))


def boxes(marks: NDArray[np.bool_]) -> list[tuple[int, int, int, int]]:
    """Bounding boxes (i0, i1, j0, j1), end-exclusive, of the connected groups of ``marks``, merged
    until no two overlap."""
    import scipy.ndimage as ndi  # here: ~50 ms at the start of every process importing the fitting

    lab, _ = ndi.label(marks, structure=np.ones((3, 3)))
    out = [(s[0].start, s[0].stop, s[1].start, s[1].stop) for s in ndi.find_objects(lab) if s is not None]
    merged = True
    while merged:
        merged = False
        for a in range(len(out)):
            for b in range(a + 1, len(out)):
                p, q = out[a], out[b]
                if p[0] < q[1] and q[0] < p[1] and p[2] < q[3] and q[2] < p[3]:
                    out[a] = (min(p[0], q[0]), max(p[1], q[1]), min(p[2], q[2]), max(p[3], q[3]))
                    del out[b]
                    merged = True
                    break
            if merged:
                break
    return out


def span_index(knots: Array, lo: float, hi: float, x: Array) -> tuple[Array, NDArray[np.intp]]:
    """Distinct knots ``k`` of ``[lo, hi]`` and the span index of each parameter (-1 outside; the
    last knot belongs to the last span)."""
    k = np.unique(knots[(knots >= lo) & (knots <= hi)])
    idx = np.searchsorted(k, x, side="right") - 1
    idx = np.where(x == k[-1], k.size - 2, idx)
    idx = np.where((x < k[0]) | (x > k[-1]), -1, idx)
    return k, idx


def rectangles(marks: NDArray[np.bool_], ku: Array, kv: Array) -> list[Region]:
    """The marked spans (``marks``, shape (len(ku) - 1, len(kv) - 1)) grown by
    :data:`~occsurf.algorithms.tolerances.FIT_ADAPTIVE_MARGIN` spans, each connected group covered by
    one rectangle (overlapping ones merged), as parameter ranges (u_range, v_range)."""
    if not marks.any():
        return []
    margin = int(tolerances.FIT_ADAPTIVE_MARGIN)
    if margin > 0:
        import scipy.ndimage as ndi

        marks = ndi.binary_dilation(marks, structure=np.ones((3, 3)), iterations=margin)
    return [((float(ku[i0]), float(ku[i1])), (float(kv[j0]), float(kv[j1]))) for i0, i1, j0, j1 in boxes(marks)]


def owner(hs: HierarchicalSurface, shape: tuple[int, ...], where: Callable[[tuple[tuple[float, float], ...]], Any]
          ) -> Owners:
    """Per datum, the deepest node whose region holds it: the nodes (base first, then the overlays
    by level), an index array of ``shape`` into them (0 = the base) and the nodes' levels.
    ``where(region)`` indexes the data inside a region."""
    overlays = sorted(hs.overlays, key=lambda o: o.level)
    nodes: list[Overlay | None] = [None, *overlays]
    own = np.zeros(shape, int)
    for k, ov in enumerate(overlays, 1):
        own[where(ov.region)] = k
    return nodes, own, np.array([0] + [o.level for o in overlays])


def support(ov: Overlay, degree: tuple[int, int]) -> tuple[tuple[float, float], tuple[float, float]]:
    """The parameter box ``(u_range, v_range)`` in which the B-splines of ``ov``'s vertex block are
    not zero."""
    p, q = degree
    (i0, i1), (j0, j1) = ov.vertices
    ku, kv = ov.knots
    su = (ku[i0], ku[min(i1 + p + 1, ku.shape[0] - 1)])
    sv = (kv[j0], kv[min(j1 + q + 1, kv.shape[0] - 1)])
    return su, sv


class OverlayFitter:
    """The hierarchy under construction with every overlay's world displacements ``δ`` kept, so
    that coarser levels can be refitted (backfitting) without losing the finer ones.

    Subclasses give :meth:`evaluate` (a surface at the data parameters) and :meth:`fit_overlay`;
    ``self.data`` holds the data in the shape :meth:`evaluate` returns.
    """

    def __init__(self, hs: HierarchicalSurface, data: Array, u: Array, v: Array,
                 refit_base: Callable[[Array], BSplineSurface] | None) -> None:
        self.hs, self.data, self.u, self.v = hs, data, u, v
        self.refit_base = refit_base
        self.delta: dict[int, Array] = {}
        self.ops: dict[int, tuple] = {}

    def evaluate(self, surface: BSplineSurface) -> Array:
        raise NotImplementedError

    def fit_overlay(self, ov: Overlay, resid: Array) -> None:
        raise NotImplementedError

    def residual(self) -> Array:
        return self.data - self.evaluate(self.hs.flatten())

    def _apply(self, ov: Overlay) -> None:
        frames = self.hs.reference_frames(ov)
        d = self.delta[ov.id]
        off = self.hs.offset_mapping.inverse(d.reshape(-1, 3), None if frames is None else frames.reshape(-1, 3, 3))
        self.hs.set_offsets(ov, np.asarray(off, float).reshape(d.shape))

    def backfit(self) -> None:
        """One block Gauss-Seidel sweep: the base against the data minus every overlay's share,
        the displacements re-applied in the new frames, then each overlay against what is left
        (the base is kept when there is no ``refit_base``)."""
        hs = self.hs
        if self.refit_base is not None:
            share = self.evaluate(hs.flatten()) - self.evaluate(hs.base)
            hs.set_base(self.refit_base(self.data - share))
            for ov in hs.overlays:  # parents first: each sees its parent's new frames
                self._apply(ov)
        resid = self.residual()
        for ov in hs.overlays:
            self.fit_overlay(ov, resid)


def grow_base(poles: tuple[int, int], deg: tuple[int, int], caps: tuple[int, int], tol: float,
              candidate: Callable[[tuple[int, int]], tuple[_Fit, float]],
              measure: Callable[[_Fit], tuple[Array, Array]],
              regions: Callable[[_Fit, NDArray[np.bool_]], tuple[HierarchicalSurface, list[Region]]],
              progress: Callable[[str], None] | None) -> tuple[_Fit, Array]:
    """The base fit, its spans multiplied by 1.5 while the places to refine cover more than
    :data:`~occsurf.algorithms.tolerances.FIT_ADAPTIVE_MAX_COVER` of it (when the error is
    everywhere, uniform refinement is the cheaper hierarchy: no overlay overhead).

    Each step grows u, v or both, whichever lowers the error most per added pole (the largest
    ``-log(e_new / e) / log(n_new / n)``; both when none gains 0.1): data that vary along one
    direction only (a ruled or extruded face) do not pay for poles along the other.

    Parameters
    ----------
    poles, deg, caps : (int, int)
        Starting pole counts, degrees, and the most poles per direction.
    candidate : callable
        ``candidate(poles) -> (fit, estimate)``: a base fit and its cheap (first-order) error, by
        which the candidates are compared.
    measure : callable
        ``measure(fit) -> (dist, err)``: the measured distances, and the error to flag (``dist``
        raised where other criteria count, e.g. the border); the chosen base is measured.
    regions : callable
        ``regions(fit, flagged) -> (hierarchy, rectangles)``: the places the base would refine.

    Returns
    -------
    (fit, dist)
    """
    fit, estimate = candidate(poles)
    while True:
        dist, err = measure(fit)
        worst = float(np.nanmax(err))
        if progress is not None:
            progress(f"base {poles[0]}x{poles[1]}: max error {worst:.3g}")
        if worst <= tol:
            return fit, dist
        flagged = err > max(tol, float(tolerances.FIT_ADAPTIVE_GREED) * worst)
        hs, rects = regions(fit, flagged)
        (u0, u1), (v0, v1) = hs.domain
        cover = sum((b - a) * (d - c) for (a, b), (c, d) in rects) / ((u1 - u0) * (v1 - v0))
        gu, gv = (min(p + int(np.ceil(1.5 * (k - p))), cnt) for k, p, cnt in zip(poles, deg, caps))
        grown = (gu, gv)
        options = {grown, (gu, poles[1]), (poles[0], gv)} - {poles}
        if cover <= float(tolerances.FIT_ADAPTIVE_MAX_COVER) or not options:
            return fit, dist
        best: tuple[tuple[int, int], tuple[_Fit, float]] | None = None
        score = np.inf
        tried: dict[tuple[int, int], tuple[_Fit, float]] = {}
        for cand in sorted(options):
            trial = tried[cand] = candidate(cand)
            gain = np.log(max(trial[1], 1e-300) / max(estimate, 1e-300)) / np.log(np.prod(cand) / np.prod(poles))
            if gain < score:
                best, score = (cand, trial), gain
        if score > -0.1 and grown in tried:  # no direction helps on its own yet: grow both
            best = (grown, tried[grown])
        if best is None:  # grown is a candidate whenever there is one (it differs from poles then)
            raise RuntimeError("grow_base: no candidate base was chosen")
        poles, (fit, estimate) = best


def refine(hs: HierarchicalSurface, fitter: OverlayFitter, dist: Array, tol: float, depth_max: int, *,
           error: Callable[[Array], Array], owners: Callable[[HierarchicalSurface], Owners],
           regions: Callable[[Overlay | None, NDArray[np.bool_]], list[Region]], measure: Callable[[BSplineSurface], Array],
           progress: Callable[[str], None] | None) -> Array:
    """The refinement rounds (course §7-10), in place on ``hs``; returns the last measured distances.

    Rounds of: flag the data farther than ``max(tol, FIT_ADAPTIVE_GREED * max_error)`` (``error(dist)``);
    give each node (base or overlay) whose region is the deepest one holding flagged data, and whose
    level is below ``depth_max``, new child overlays over ``regions(node, flagged_of_node)``; fit
    them to the residual; then :data:`~occsurf.algorithms.tolerances.FIT_ADAPTIVE_SWEEPS` backfitting
    sweeps; measure (``measure(flat surface)``). Stops when the error holds, no overlay was added, or
    after :data:`~occsurf.algorithms.tolerances.FIT_ADAPTIVE_MAX_ROUNDS` rounds.
    """
    for rnd in range(1, int(tolerances.FIT_ADAPTIVE_MAX_ROUNDS) + 1):
        err = error(dist)
        worst = float(np.nanmax(err))
        if worst <= tol:
            break
        flagged = err > max(tol, float(tolerances.FIT_ADAPTIVE_GREED) * worst)
        nodes, own, lv = owners(hs)
        resid = fitter.residual()
        new = []
        for k, node in enumerate(nodes):
            if lv[k] >= depth_max:
                continue
            mine = flagged & (own == k)
            if not mine.any():
                continue
            for ur, vr in regions(node, mine):
                ov = hs.add_overlay(ur, vr, node)
                fitter.fit_overlay(ov, resid)
                new.append(ov)
        if not new:
            break
        for _ in range(int(tolerances.FIT_ADAPTIVE_SWEEPS)):
            fitter.backfit()
        dist = measure(hs.flatten())
        if progress is not None:
            progress(f"round {rnd}: {len(new)} overlays added (depth {hs.depth}), "
                     f"{hs.pole_counts()['stored']} control points, max error {np.nanmax(error(dist)):.3g}")
    return dist


def level_reports(hs: HierarchicalSurface, measure: Callable[[BSplineSurface], Array]
                  ) -> tuple[list[LevelReport], list[BSplineSurface], list[Array]]:
    """Per level L, the surface truncated below L (finer offsets zeroed) measured against the data
    (``measure(flat surface)``): the reports, the truncated flat surfaces and their distance arrays."""
    out, surfs, dists = [], [], []
    for L in range(hs.depth + 1):
        h = hs.copy()
        for ov in sorted(h.overlays, key=lambda o: -o.level):
            if ov.level > L:
                h.set_offsets(ov, np.zeros(ov.shape + (3,)))
        flat = h.flatten()
        dist = measure(flat)
        ovs = [o for o in hs.overlays if o.level == L]
        cps = int(np.prod(hs.base.n_poles)) if L == 0 else sum(int(np.prod(o.shape)) for o in ovs)
        out.append(LevelReport(L, len(ovs), cps, *stats(dist)))
        surfs.append(flat)
        dists.append(dist)
    return out, surfs, dists
