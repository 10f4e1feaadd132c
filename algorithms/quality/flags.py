"""Problem areas of a face, found automatically, each with a suggested correction (course ch. 9
assessment; corrections from ch. 3-5 and 7). Suggestions are text: nothing is applied.

Every threshold is a tolerance of :mod:`occsurf.algorithms.tolerances` (``QUALITY_...``), so a
caller tightens or loosens them with ``tolerances.override`` or the ``thresholds=`` mapping.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import ndimage

from .. import tolerances
from ..errors import InvalidGeometryError
from ._common import Array, QualitySurface, check_mask, grid_axes, grid_partials, surface_of, trim_mask
from .curvature_maps import CurvatureMap, map_from_partials

__all__ = ["FLAG_KINDS", "Flag", "face_flags", "sign_changes"]

#: Kinds of :class:`Flag`, with the correction each suggests.
SUGGESTIONS = {
    "wiggle": ("knot removal (BSplineSurface.remove_knot) of superfluous knots near uv, or fairing by "
               "constrained least squares holding the boundary (occsurf.algorithms.manipulation, course "
               "ch. 3-4); refit (occsurf.algorithms.fitting.fit_surface) if the net is noisy"),
    "flat_spot": ("a local hierarchical edit (HierarchicalSurface.add_overlay + move_vertex, course ch. 5) "
                  "to restore curvature there, or a refit (fitting.fit_surface) with fewer knots"),
    "curvature_spike": ("knot removal (BSplineSurface.remove_knot) near uv or fairing by constrained least "
                        "squares (course ch. 3-4); a local hierarchical edit (course ch. 5) for a dent"),
    "near_degenerate_normal": ("refit the face (fitting.interpolate_surface / fit_surface) or split it so the "
                               "partials stay independent; a pole of a revolved surface is a natural "
                               "singularity and acceptable if intended"),
    "ill_parametrisation": ("reparametrise: refit on chord-length parameters (fitting.fit_surface, course ch. 7) "
                            "or insert / remove knots (refine, remove_knot) to even the pole spacing"),
}
FLAG_KINDS = tuple(SUGGESTIONS)


@dataclass(frozen=True)
class Flag:
    """A problem area of a face.

    Attributes
    ----------
    kind : str
        One of :data:`FLAG_KINDS`.
    location : ndarray, shape (3,)
        Model-space point of the worst sample.
    uv : ndarray, shape (2,)
        Its parameters.
    value : float
        The measured quantity: wiggle: sign changes of the normal curvature along the worst
        iso-line; flat spot: ``max|k|`` over the face's median; spike: ``(|k1| + |k2|)`` over its
        neighbourhood median; near-degenerate normal: sine of the angle between ``S_u``, ``S_v``;
        ill-parametrisation: Jacobian ratio max/min.
    suggestion : str
        The occsurf operation that could correct it (suggested, not applied).
    count : int
        Samples (or iso-lines, for wiggles) in the area.
    """

    kind: str
    location: Array
    uv: Array
    value: float
    suggestion: str
    count: int = 1

    def to_dict(self) -> dict[str, Any]:
        return {"kind": self.kind, "location": [float(x) for x in self.location],
                "uv": [float(x) for x in self.uv], "value": float(self.value), "count": int(self.count),
                "suggestion": self.suggestion}


def _flag(kind: str, cm: CurvatureMap, i: int | np.integer, j: int | np.integer, value: float, count: int) -> Flag:
    return Flag(kind=kind, location=cm.points[i, j].copy(), uv=np.array([cm.us[i], cm.vs[j]]), value=float(value),
                suggestion=SUGGESTIONS[kind], count=int(count))


def sign_changes(k: Array, zero: float) -> NDArray[np.intp]:
    """Significant sign changes along the last axis (values with |k| <= zero and NaN skipped)."""
    s = np.where(np.abs(np.nan_to_num(k)) > zero, np.sign(np.nan_to_num(k)), 0.0)
    # carry the last non-zero sign forward, vectorised: index of the last non-zero so far
    idx = np.where(s != 0, np.arange(s.shape[-1]), 0)
    np.maximum.accumulate(idx, axis=-1, out=idx)
    carried = np.take_along_axis(s, idx, axis=-1)
    changes = (carried[..., 1:] * carried[..., :-1] < 0)
    return changes


def _wiggles(cm: CurvatureMap, D: Array, size: float) -> list[Flag]:
    """Iso-lines whose normal curvature changes sign more than once (course ch. 9: a fair surface's
    sections and iso-lines have at most the inflections the design asks for)."""
    su, sv = D[..., 1, 0, :], D[..., 0, 1, :]
    n = cm.normals
    zero = tolerances.QUALITY_WIGGLE_CURVATURE / size
    with np.errstate(invalid="ignore", divide="ignore"):
        ku = np.einsum("...i,...i", D[..., 2, 0, :], n) / np.einsum("...i,...i", su, su)  # along u-lines
        kv = np.einsum("...i,...i", D[..., 0, 2, :], n) / np.einsum("...i,...i", sv, sv)
    ku = np.where(cm.mask & ~cm.degenerate, ku, np.nan)
    kv = np.where(cm.mask & ~cm.degenerate, kv, np.nan)
    out = []
    for k, axis in ((ku, 0), (kv, 1)):  # two directions
        lines = np.moveaxis(k, axis, -1)  # iso-lines along the varying parameter
        ch = sign_changes(lines, zero)
        count = ch.sum(-1)
        bad = np.flatnonzero(count >= 2)
        if bad.size == 0:
            continue
        labels, nlab = ndimage.label(count >= 2)
        for lab in range(1, nlab + 1):
            rows = np.flatnonzero(labels == lab)
            r = rows[np.argmax(count[rows])]
            pos = np.flatnonzero(ch[r])
            c = int(pos[len(pos) // 2]) + 1
            i, j = (c, r) if axis == 0 else (r, c)
            out.append(_flag("wiggle", cm, i, j, count[r], rows.size))
    return out


def _flat_spots(cm: CurvatureMap, size: float) -> list[Flag]:
    kmax = np.maximum(np.abs(cm.k1), np.abs(cm.k2))
    valid = cm.mask & ~cm.degenerate & np.isfinite(kmax)
    if not np.any(valid):
        return []
    med = float(np.median(kmax[valid]))
    if med * size <= tolerances.QUALITY_WIGGLE_CURVATURE:
        return []  # a flat or nearly flat face: flat spots are the design
    low = valid & (kmax < tolerances.QUALITY_FLAT_SPOT_RATIO * med)
    labels, nlab = ndimage.label(low)
    out = []
    need = max(2, int(np.ceil(tolerances.QUALITY_FLAT_SPOT_AREA * valid.sum())))
    for lab in range(1, nlab + 1):
        region = labels == lab
        if region.sum() < need:
            continue
        vals = np.where(region, kmax, np.inf)
        i, j = np.unravel_index(np.argmin(vals), vals.shape)
        out.append(_flag("flat_spot", cm, i, j, kmax[i, j] / med, region.sum()))
    return out


def _spikes(cm: CurvatureMap, size: float) -> list[Flag]:
    A = np.abs(cm.k1) + np.abs(cm.k2)
    valid = cm.mask & ~cm.degenerate & np.isfinite(A)
    if valid.sum() < 9:
        return []
    r = max(1, int(round(0.5 * tolerances.QUALITY_SPIKE_WINDOW * min(A.shape))))
    Af = np.where(valid, A, np.nan)
    fill = np.where(valid, A, np.nanmedian(Af))
    local_max = fill >= ndimage.maximum_filter(fill, size=2 * r + 1, mode="nearest")
    cand = valid & local_max & (A * size > 1.0)
    ci, cj = np.nonzero(cand)
    if ci.size == 0:
        return []
    # neighbourhood medians at the candidates only: their windows gathered in one array
    pad = np.pad(fill, r, mode="edge")
    win = np.lib.stride_tricks.sliding_window_view(pad, (2 * r + 1, 2 * r + 1))[ci, cj]
    med = np.median(win.reshape(ci.size, -1), axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        ratio = np.where(med > 0, A[ci, cj] / med, np.inf)
    keep = ratio > tolerances.QUALITY_SPIKE_RATIO
    if np.any(keep) and np.any(cm.degenerate & cm.mask):
        k = np.flatnonzero(keep)
        keep[k] = _apex_ratio(cm, A, valid, ci[k], cj[k], r) > tolerances.QUALITY_SPIKE_RATIO
    return [_flag("curvature_spike", cm, i, j, q, 1) for i, j, q in zip(ci[keep], cj[keep], ratio[keep])]


def _apex_ratio(cm: CurvatureMap, A: Array, valid: NDArray[np.bool_], ci: NDArray[np.intp], cj: NDArray[np.intp],
                r: int) -> Array:
    """The spike ratio of candidates next to a cone apex, with the apex's own growth taken out.

    Near the apex ``X0`` of a true cone (every tangent plane passes through the apex:
    ``|n . (X - X0)| <= QUALITY_CONE_APEX_TOL |X - X0|`` at every valid sample of the candidate's
    window) the curvature grows as ``1 / |X - X0|`` (a right circular cone of half-angle ``a``:
    ``|k1| + |k2| = 1 / (|X - X0| tan a)``), which is the geometry, not a defect: the ratio is then
    measured on ``(|k1| + |k2|) |X - X0|``. Candidates whose window is not conical (a dent next to
    a sphere's pole, a spike on a cone away from its generators' law) keep ``inf`` here, i.e. their
    plain ratio. ``X0`` is the degenerate sample nearest to the candidate. Returns ``(c,)``.
    """
    deg = np.argwhere(cm.degenerate & cm.mask)
    apex_pts = cm.points[deg[:, 0], deg[:, 1]]
    X = cm.points[ci, cj]
    X0 = apex_pts[np.argmin(np.linalg.norm(X[:, None] - apex_pts[None], axis=-1), axis=1)]  # (c, 3)
    w = 2 * r + 1
    P = np.lib.stride_tricks.sliding_window_view(np.pad(cm.points, ((r, r), (r, r), (0, 0)), mode="edge"),
                                                 (w, w), axis=(0, 1))[ci, cj]  # (c, 3, w, w)
    Nw = np.lib.stride_tricks.sliding_window_view(np.pad(cm.normals, ((r, r), (r, r), (0, 0)), mode="edge"),
                                                  (w, w), axis=(0, 1))[ci, cj]
    Aw = np.lib.stride_tricks.sliding_window_view(np.pad(A, r, mode="edge"), (w, w))[ci, cj]
    Vw = np.lib.stride_tricks.sliding_window_view(np.pad(valid, r, mode="edge"), (w, w))[ci, cj]
    rel = P - X0[:, :, None, None]
    dist = np.linalg.norm(rel, axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        off = np.abs(np.einsum("cxij,cxij->cij", Nw, rel)) / dist
        conical = np.all(np.where(Vw & (dist > 0), off <= tolerances.QUALITY_CONE_APEX_TOL, True), axis=(1, 2))
        scaled = np.where(Vw & (dist > 0), Aw * dist, np.nan).reshape(ci.size, -1)
        med = np.nanmedian(scaled, axis=1)
        own = A[ci, cj] * np.linalg.norm(X - X0, axis=1)
        ratio = np.where(med > 0, own / med, np.inf)
    return np.where(conical, ratio, np.inf)


def _degenerate(cm: CurvatureMap, D: Array) -> tuple[list[Flag], NDArray[np.bool_]]:
    su, sv = D[..., 1, 0, :], D[..., 0, 1, :]
    with np.errstate(invalid="ignore", divide="ignore"):
        J = np.linalg.norm(np.cross(su, sv), axis=-1)
        sine = J / np.maximum(np.linalg.norm(su, axis=-1), np.linalg.norm(sv, axis=-1)) ** 2
    sine = np.where(cm.degenerate, 0.0, np.nan_to_num(sine, nan=0.0))
    near = cm.mask & (sine < tolerances.QUALITY_NEAR_DEGENERATE)
    labels, nlab = ndimage.label(near)
    out = []
    for lab in range(1, nlab + 1):
        region = labels == lab
        vals = np.where(region, sine, np.inf)
        i, j = np.unravel_index(np.argmin(vals), vals.shape)
        out.append(_flag("near_degenerate_normal", cm, i, j, sine[i, j], region.sum()))
    ok = cm.mask & ~near
    flags = []
    if ok.sum() >= 2:
        Jv = np.where(ok, J, np.nan)
        lo, hi = np.nanmin(Jv), np.nanmax(Jv)
        ratio = hi / lo if lo > 0 else np.inf
        if ratio > tolerances.QUALITY_JACOBIAN_RATIO:
            i, j = np.unravel_index(np.nanargmin(Jv), Jv.shape)
            flags.append(_flag("ill_parametrisation", cm, i, j, ratio, 1))
    return out + flags, near


def face_flags(surface: QualitySurface, *, mask: ArrayLike | None = None, thresholds: Mapping[str, float] | None = None,
               us: ArrayLike | int = 64, vs: ArrayLike | int = 64, patch: int | None = None) -> list[Flag]:
    """Problem areas of one face: wiggles, flat spots, curvature spikes, near-degenerate normals,
    ill-parametrisation; each with a suggested occsurf correction.

    Parameters
    ----------
    surface, mask, patch
        As :func:`~occsurf.algorithms.quality.curvature_map` (``mask`` of shape ``(len(us), len(vs))``).
    thresholds : mapping, optional
        Overrides of ``QUALITY_...`` tolerances for this call, e.g. ``{"QUALITY_SPIKE_RATIO": 5}``.
    us, vs : array_like or int
        Sample grid (default 64 x 64 equally spaced).

    Returns
    -------
    list of Flag
        In the order: near-degenerate normals, ill-parametrisation, wiggles, flat spots, spikes.

    Notes
    -----
    * wiggle: the normal curvature along an iso-line (``L/E`` along u, ``N/G`` along v) changes sign
      at least twice with ``|k| * size > QUALITY_WIGGLE_CURVATURE`` on both sides; one flag per
      band of neighbouring iso-lines.
    * flat spot: ``max(|k1|, |k2|) < QUALITY_FLAT_SPOT_RATIO`` x the face median on a curved face,
      over at least ``QUALITY_FLAT_SPOT_AREA`` of the samples.
    * curvature spike: a local maximum of ``|k1| + |k2|`` above ``QUALITY_SPIKE_RATIO`` x the median
      of its neighbourhood (a window ``QUALITY_SPIKE_WINDOW`` of the grid's side) and above ``1 / size``.
      Next to the apex of a true cone (all tangent planes of the window through the apex, within
      ``QUALITY_CONE_APEX_TOL``) the ratio is taken on ``(|k1| + |k2|) |X - apex|``: the cone's
      ``1 / distance`` growth is its geometry, not a spike.
    * near-degenerate normal: ``|S_u x S_v| / max(|S_u|, |S_v|)^2 < QUALITY_NEAR_DEGENERATE``
      (degenerate points included); ill-parametrisation: ``max |S_u x S_v| / min > QUALITY_JACOBIAN_RATIO``
      over the other samples.
    """
    if thresholds is not None:
        if not isinstance(thresholds, Mapping):
            raise InvalidGeometryError(f"thresholds: expected a mapping of QUALITY_ tolerance names, got {thresholds!r}")
        bad = [k for k in thresholds if not str(k).startswith("QUALITY_")]
        if bad:
            raise InvalidGeometryError(f"thresholds: only QUALITY_ tolerances apply here, got {bad}")
        with tolerances.override(**dict(thresholds)):
            return face_flags(surface, mask=mask, us=us, vs=vs, patch=patch)
    s = surface_of(surface, patch)
    a, b = grid_axes(s, us, vs)
    m = trim_mask(surface, a, b, check_mask(mask, (a.size, b.size)))
    g = grid_partials(s, a, b, m)
    cm = map_from_partials(s, g, "absolute", m)
    D = g.D
    size = max(cm.size, np.finfo(float).tiny)
    degenerate, _near = _degenerate(cm, D)
    return degenerate + _wiggles(cm, D, size) + _flat_spots(cm, size) + _spikes(cm, size)
