"""Reflection lines (zebra stripes), isophotes and highlight lines from a normal field
(course ch. 9, "shaded images" as surface interrogation).

All three are functions of points and unit normals only, so they work per vertex of a mesh as well
as per pixel of a rendered normal buffer: every argument broadcasts over any leading shape.

References
----------
R. Klass, "Correction of local surface irregularities using reflection lines", CAD 12(2), 1980.
J. Poeschl, "Detecting surface irregularities using isophotes", CAGD 1(2), 1984.
K.-P. Beier, Y. Chen, "Highlight-line algorithm for realtime surface-quality assessment",
CAD 26(4), 1994.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import _validate as V
from ..errors import InvalidGeometryError
from ._common import Array, dot, positive, unit_vectors, vectors

__all__ = ["Stripes", "Isophotes", "zebra", "isophotes", "highlight_lines"]


@dataclass(frozen=True)
class Stripes:
    """Zebra stripes per vertex or pixel.

    Attributes
    ----------
    phase : ndarray, shape S
        Position across the light lines in units of one light/dark pair, in ``[0, 1)``; NaN where
        the reflected ray misses the light plane or the normal is undefined.
    stripe : ndarray of bool, shape S
        ``phase < 0.5``: on a light stripe (False where ``phase`` is NaN).
    hit : ndarray of bool, shape S
        Whether the reflected ray meets the light plane.
    coordinate : ndarray, shape S
        The unwrapped coordinate across the light lines (model units); its level sets are the
        reflection lines, for contouring.
    width : float
        Width of one light/dark pair on the light plane (model units).
    """

    phase: Array
    stripe: NDArray[np.bool_]
    hit: NDArray[np.bool_]
    coordinate: Array
    width: float


def _extent(P: Array) -> tuple[Array, float]:
    flat = P.reshape(-1, 3)
    flat = flat[np.all(np.isfinite(flat), axis=1)]
    if flat.size == 0:
        return np.zeros(3), 1.0
    lo, hi = flat.min(axis=0), flat.max(axis=0)
    return 0.5 * (lo + hi), max(float(np.linalg.norm(hi - lo)), np.finfo(float).tiny)


def zebra(points: ArrayLike, normals: ArrayLike, view_dir: ArrayLike, *, stripe_dir: ArrayLike = (0.0, 0.0, 1.0),
          width: float | None = None, distance: float | None = None) -> Stripes:
    """Reflection lines of a family of parallel light lines (zebra stripes; Klass 1980).

    The light source is a plane of parallel straight light tubes, all parallel to ``stripe_dir``,
    one light/dark pair every ``width``; the plane faces the model from behind the viewer. A
    surface point ``x`` with unit normal ``n`` seen along ``d`` (``view_dir``, from the eye towards
    the model) reflects the ray

    .. math:: r = d - 2 (d \\cdot n)\\, n ,

    which meets the light plane ``{y : (y - c) \\cdot w = 0}`` at ``y = x + t r`` with
    ``t = (c - x) \\cdot w / (r \\cdot w)``. The stripe coordinate is ``s = y \\cdot b`` with
    ``b = w \\times a`` (``a`` = ``stripe_dir``), and ``phase = frac(s / width)``. Here
    ``w = -d_\\perp/|d_\\perp|`` (``d_\\perp``: the part of the mean ``d`` perpendicular to ``a``)
    and ``c`` lies ``distance`` behind the centre of the points.

    A plane reflects every ray to a plane: its stripes are straight and parallel (evenly spaced in
    an orthographic view). A tangent (G1) break kinks the stripes, a curvature (G2) break bends them
    abruptly; on a G2 joint they stay smooth (Klass 1980).

    Parameters
    ----------
    points : array_like, shape S + (3,)
    normals : array_like, shape S + (3,)
        Unit or not; normalised here. NaN normals give NaN phases. The sign does not matter.
    view_dir : array_like, shape (3,) or S + (3,)
        Viewing direction (orthographic) or per-vertex directions ``x - eye`` (perspective).
    stripe_dir : array_like, shape (3,)
        Direction of the light lines; not parallel to the view direction.
    width : float, optional
        Width of one light/dark pair on the light plane; default 1/8 of the points' extent.
    distance : float, optional
        Distance of the light plane behind the centre of the points; default 2x their extent. Pass
        both ``width`` and ``distance`` explicitly when computing in chunks (per-pixel tiles), so
        every chunk uses the same lights.

    Returns
    -------
    Stripes
    """
    P = vectors(points, "points")
    N = vectors(normals, "normals", allow_nan=True)
    d = unit_vectors(view_dir, "view_dir")
    a = unit_vectors(stripe_dir, "stripe_dir")
    if a.ndim != 1:
        raise InvalidGeometryError(f"stripe_dir: expected one 3-vector, got shape {a.shape}")
    centre, ext = _extent(P)
    width = ext / 8.0 if width is None else positive(width, "width")
    distance = 2.0 * ext if distance is None else positive(distance, "distance")
    dm = d.reshape(-1, 3).mean(axis=0)
    dperp = dm - np.dot(dm, a) * a
    if np.linalg.norm(dperp) <= 1e-9 * np.linalg.norm(dm):
        raise InvalidGeometryError("stripe_dir: must not be parallel to view_dir (the light plane would be edge-on)")
    w = -dperp / np.linalg.norm(dperp)
    b = np.cross(w, a)
    c = centre + distance * w
    with np.errstate(invalid="ignore", divide="ignore"):
        n = N / np.linalg.norm(N, axis=-1, keepdims=True)
        r = d - 2.0 * dot(d, n)[..., None] * n
        rw = r @ w
        hit = rw > 1e-12
        t = np.where(hit, ((c - P) @ w) / np.where(hit, rw, 1.0), np.nan)
        s = (P @ b) + t * (r @ b)
    s = np.where(hit, s, np.nan)
    phase = np.mod(s / width, 1.0)
    with np.errstate(invalid="ignore"):
        stripe = phase < 0.5
    return Stripes(phase=phase, stripe=stripe, hit=np.asarray(hit), coordinate=s, width=width)


@dataclass(frozen=True)
class Isophotes:
    """Isophotes (lines of equal light intensity; Poeschl 1984).

    Attributes
    ----------
    intensity : ndarray, shape S
        ``n . l`` (cosine of the angle between normal and light direction), in ``[-1, 1]``; NaN
        where the normal is undefined. Its level sets at ``levels`` are the isophotes.
    band : ndarray of int, shape S
        Index of the interval of ``levels`` holding the intensity (``0 .. len(levels)``; -1 where
        NaN): an isophote runs where neighbouring bands differ.
    levels : ndarray, shape (k,)
        Sorted intensity levels.
    """

    intensity: Array
    band: NDArray[np.intp]
    levels: Array


def isophotes(normals: ArrayLike, light_dir: ArrayLike, levels: ArrayLike | int = 10) -> Isophotes:
    """Isophotes of a normal field for a directional light (Poeschl 1984).

    An isophote is a curve of constant ``n . l``; it is one order less smooth than the surface
    (G1 breaks tear isophotes apart, G2 breaks kink them).

    Parameters
    ----------
    normals : array_like, shape S + (3,)
        Normalised here; NaN allowed (degenerate points).
    light_dir : array_like, shape (3,)
        Direction towards the light.
    levels : array_like, shape (k,), or int
        Intensity levels in ``[-1, 1]``; an integer ``k`` means ``k`` levels at equally spaced
        angles ``arccos`` from 0 to 180 degrees (exclusive).

    Returns
    -------
    Isophotes
    """
    N = vectors(normals, "normals", allow_nan=True)
    ell = unit_vectors(light_dir, "light_dir")
    if isinstance(levels, (int, np.integer)) and not isinstance(levels, bool):
        k = V.check_count(levels, "levels", 4)
        lv = np.cos(np.linspace(0.0, np.pi, k + 2)[1:-1])[::-1]
    else:
        lv = np.sort(np.asarray(levels, dtype=float).ravel())
        if lv.size == 0 or not np.all(np.isfinite(lv)) or lv[0] < -1 or lv[-1] > 1:
            raise InvalidGeometryError(f"levels: expected finite values in [-1, 1], got {levels!r}")
    with np.errstate(invalid="ignore"):
        cos = dot(N, ell) / np.linalg.norm(N, axis=-1)
    band = np.where(np.isnan(cos), -1, np.searchsorted(lv, np.nan_to_num(cos), side="right"))
    return Isophotes(intensity=np.clip(cos, -1.0, 1.0), band=band.astype(np.intp), levels=lv)


def highlight_lines(points: ArrayLike, normals: ArrayLike, line_origin: ArrayLike, line_direction: ArrayLike) -> Array:
    """Signed distance between each normal line and a linear light source (Beier & Chen 1994).

    The highlight line of a linear light source ``L(t) = o + t e`` is the set of surface points
    whose normal line ``x + s n`` meets ``L``; the distance between the two lines is

    .. math:: d = \\frac{(x - o) \\cdot (e \\times n)}{|e \\times n|},

    signed, so its zero level set is the highlight line and ``|d| <= w`` a highlight band of
    width ``2 w``. Unlike reflection lines it does not depend on the eye point.

    Parameters
    ----------
    points, normals : array_like, shape S + (3,)
    line_origin, line_direction : array_like, shape (3,) or broadcastable to S + (3,)

    Returns
    -------
    ndarray, shape S
        NaN where the normal is undefined or parallel to the light line.
    """
    P = vectors(points, "points")
    N = vectors(normals, "normals", allow_nan=True)
    o = vectors(line_origin, "line_origin")
    e = unit_vectors(line_direction, "line_direction")
    with np.errstate(invalid="ignore", divide="ignore"):
        n = N / np.linalg.norm(N, axis=-1, keepdims=True)
        c = np.cross(e, n)
        lc = np.linalg.norm(c, axis=-1)
        ok = lc > 1e-12
        return np.where(ok, dot(P - o, c) / np.where(ok, lc, 1.0), np.nan)
