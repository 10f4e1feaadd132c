"""Curvature maps and their colour scales (course §9-5 .. §9-13).

A curvature map samples a surface on a parameter grid and colours it by one of the curvature
functions of differential geometry (course §6-8 .. §6-12): Gaussian ``K = k1 k2``, mean
``H = (k1 + k2) / 2``, the principal curvatures ``k1 >= k2``, the absolute curvature
``|k1| + |k2|`` and the radius of curvature ``1 / max(|k1|, |k2|)``.

The curvatures come from :func:`occsurf.algorithms.geometry.curvatures_from_derivatives`, the same
formulas as :func:`~occsurf.algorithms.geometry.surface_curvatures` and the same signs as OCC's
``GeomLProp_SLProps`` (an outward sphere of radius r has ``k1 = k2 = H = -1/r``).

Degenerate points (sphere poles, collapsed edges: ``|S_u x S_v|`` below
:data:`~occsurf.algorithms.tolerances.NORMAL_ZERO`) are reported in :attr:`CurvatureMap.degenerate`
with NaN values; they are never coloured silently.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import _validate as V
from .. import tolerances
from ..errors import InvalidGeometryError
from ..geometry.surface_differential import curvatures_from_derivatives
from ..kernel.surface import BSplineSurface
from ..topology.spatch import SPatch
from . import _kernels
from ._common import (
    Array,
    Evaluable,
    GridPartials,
    QualitySurface,
    check_mask,
    grid_axes,
    grid_partials,
    nudged_normals,
    surface_of,
    trim_mask,
)

__all__ = ["KINDS", "SCALE_MODES", "CurvatureMap", "ColorScale", "curvature_map", "curvature_values", "color_scale"]

#: Curvature functions of :func:`curvature_map`.
KINDS = ("gaussian", "mean", "max", "min", "absolute", "radius")
#: Modes of :func:`color_scale`.
SCALE_MODES = ("symmetric", "clipped", "linear")

# Grid rows evaluated per block: keeps the (rows, n, 3, 3, 3) partials of a block in cache.
_BLOCK_POINTS = 1 << 16


def _check_kind(kind: object) -> str:
    if kind not in KINDS:
        raise InvalidGeometryError(f"kind: expected one of {', '.join(map(repr, KINDS))}, got {kind!r}")
    return str(kind)


def curvature_values(kind: str, k1: ArrayLike, k2: ArrayLike, gaussian: ArrayLike | None = None,
                     mean: ArrayLike | None = None, size: float = 1.0) -> Array:
    """One curvature function from the principal curvatures.

    Parameters
    ----------
    kind : {"gaussian", "mean", "max", "min", "absolute", "radius"}
    k1, k2 : array_like, same shape
        Principal curvatures, ``k1 >= k2`` (NaN where undefined).
    gaussian, mean : array_like, optional
        ``K`` and ``H`` from the fundamental forms (more accurate than ``k1 k2`` near ``K = 0``);
        computed from ``k1, k2`` when not given.
    size : float
        Model size: ``radius`` is ``inf`` where ``max(|k1|, |k2|) * size`` is at most
        :data:`~occsurf.algorithms.tolerances.QUALITY_FLAT_CURVATURE` (flat).

    Returns
    -------
    ndarray, shape of ``k1``
    """
    kind = _check_kind(kind)
    k1, k2 = np.asarray(k1, float), np.asarray(k2, float)
    if kind == "gaussian":
        return np.asarray(k1 * k2 if gaussian is None else gaussian, float)
    if kind == "mean":
        return np.asarray(0.5 * (k1 + k2) if mean is None else mean, float)
    if kind == "max":
        return k1
    if kind == "min":
        return k2
    if kind == "absolute":
        return np.abs(k1) + np.abs(k2)
    kmax = np.maximum(np.abs(k1), np.abs(k2))
    flat = kmax * size <= tolerances.QUALITY_FLAT_CURVATURE
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(flat, np.inf, 1.0 / kmax)


@dataclass(frozen=True)
class CurvatureMap:
    """Curvature of a surface sampled on a parameter grid ``us x vs``.

    Attributes
    ----------
    points, normals : ndarray, shape (m, n, 3)
        Surface points and unit normals ``S_u x S_v / |S_u x S_v|``. At degenerate points the
        normal is the limit normal taken just inside the domain (a renderer needs one); outside
        ``mask`` both are NaN.
    values : ndarray, shape (m, n)
        The curvature function ``kind`` (1/model units; ``radius`` in model units); NaN at
        degenerate points and outside ``mask``.
    k1, k2, gaussian, mean : ndarray, shape (m, n)
        Principal (``k1 >= k2``), Gaussian and mean curvature, NaN where undefined.
    degenerate : ndarray of bool, shape (m, n)
        Points of the mask where the normal, hence the curvature, is undefined.
    kind : str
    mask : ndarray of bool, shape (m, n)
        The evaluated points: the caller's mask (trimmed faces) and, for an S-patch, the points of
        the grid inside its n-gon domain.
    us, vs : ndarray, shapes (m,), (n,)
        The grid parameters (for an S-patch: domain coordinates ``x``, ``y``).
    size : float
        Diagonal of the bounding box of the evaluated points (the model size used for "flat").
    """

    points: Array
    normals: Array
    values: Array
    k1: Array
    k2: Array
    gaussian: Array
    mean: Array
    degenerate: NDArray[np.bool_]
    kind: str
    mask: NDArray[np.bool_]
    us: Array
    vs: Array
    size: float

    @property
    def n_degenerate(self) -> int:
        """Number of degenerate grid points."""
        return int(np.count_nonzero(self.degenerate))

    @property
    def degenerate_points(self) -> Array:
        """Model-space points of the degenerate samples, shape (k, 3)."""
        return self.points[self.degenerate]

    def values_of(self, kind: str) -> Array:
        """Another curvature function on the same samples, without evaluating again."""
        return curvature_values(kind, self.k1, self.k2, self.gaussian, self.mean, self.size)

    def with_kind(self, kind: str) -> CurvatureMap:
        """The same map coloured by ``kind``."""
        from dataclasses import replace

        return replace(self, kind=_check_kind(kind), values=self.values_of(kind))

    def range(self) -> tuple[float, float]:
        """``(min, max)`` of the finite values (NaN, NaN when there is none)."""
        v = self.values[np.isfinite(self.values)]
        return (float(v.min()), float(v.max())) if v.size else (float("nan"), float("nan"))


def _block_curvatures(D: Array) -> _kernels.GridCurvatures:
    """Points, normals, k1, k2, K, H and ok of a block of partials, in row blocks kept in cache."""
    m, n = D.shape[:2]
    P, Nrm = np.empty((m, n, 3)), np.empty((m, n, 3))
    k1, k2, K, H = (np.empty((m, n)) for _ in range(4))
    ok = np.empty((m, n), bool)
    rows = max(1, _BLOCK_POINTS // max(n, 1))
    for i in range(0, m, rows):
        sl = slice(i, i + rows)
        c = curvatures_from_derivatives(D[sl])
        P[sl] = D[sl, :, 0, 0, :]
        Nrm[sl] = c.normal
        k1[sl], k2[sl], K[sl], H[sl] = c.k1, c.k2, c.gaussian, c.mean
        ok[sl] = np.isfinite(c.normal[..., 0])
    return P, Nrm, k1, k2, K, H, ok


def curvature_map(surface: QualitySurface, us: ArrayLike | int, vs: ArrayLike | int, kind: str = "mean", *,
                  mask: ArrayLike | None = None, patch: int | None = None) -> CurvatureMap:
    """Curvature map of a surface on the grid ``us x vs`` (course §9-5 .. §9-13).

    Parameters
    ----------
    surface : BSplineSurface, TrimmedSurface, HierarchicalSurface, SPatch or GeneralizedSurface
        3-D; rational or not. Each kind is evaluated by its own exact derivatives. A
        :class:`~occsurf.algorithms.TrimmedSurface` is mapped on its surface's grid, the grid points
        off the face (:meth:`~occsurf.algorithms.TrimmedSurface.contains`) masked as by ``mask``.
    us, vs : array_like, shapes (m,), (n,), or int
        Grid parameters inside the domain (an integer: that many equally spaced values). For an
        S-patch they are domain coordinates ``x``, ``y`` and grid points outside its regular n-gon
        are left out of :attr:`CurvatureMap.mask`.
    kind : {"gaussian", "mean", "max", "min", "absolute", "radius"}
        ``radius`` is ``1 / max(|k1|, |k2|)``, ``inf`` where the surface is flat.
    mask : array_like of bool, shape (m, n), optional
        Grid points inside a trimmed face's boundary; the others are NaN.
    patch : int, optional
        For a :class:`GeneralizedSurface`: the index of the S-patch to map.

    Returns
    -------
    CurvatureMap

    Raises
    ------
    InvalidGeometryError
        Unsupported surface, bad ``kind`` or ``mask``; :class:`ParameterError` for parameters
        outside the domain.

    Notes
    -----
    Tensor-product surfaces are evaluated by ``derivatives_grid`` (two banded basis products);
    the curvature formulas run in row blocks of about 65 000 points so the partials stay in cache.
    From :data:`~occsurf.algorithms.tolerances.NUMBA_MIN_POINTS` grid points on, a B-spline surface
    goes through an optional numba kernel that fuses the same steps per point
    (:mod:`occsurf.algorithms.quality._kernels`; ``OCCSURF_NO_NUMBA=1`` turns it off).
    """
    kind = _check_kind(kind)
    s = surface_of(surface, patch)
    a, b = grid_axes(s, us, vs)
    m = trim_mask(surface, a, b, check_mask(mask, (a.size, b.size)))
    fused = _kernels.grid_curvatures(s, a, b) if isinstance(s, BSplineSurface) else None
    if fused is None:
        return map_from_partials(s, grid_partials(s, a, b, m), kind, m)
    P, Nrm, k1, k2, K, H, ok = fused
    inside = np.ones(ok.shape, bool) if m is None else m.copy()
    if m is not None:
        for x in (P, Nrm):
            x[~inside] = np.nan
        for x in (k1, k2, K, H):
            x[~inside] = np.nan
    return _assemble(s, a, b, m, kind, inside, (P, Nrm, k1, k2, K, H, ok))


def map_from_partials(s: Evaluable, g: GridPartials, kind: str, mask: NDArray[np.bool_] | None) -> CurvatureMap:
    """A :class:`CurvatureMap` from grid partials already computed (trusted arguments; shared with
    :func:`~occsurf.algorithms.quality.face_flags`, which needs the partials too)."""
    return _assemble(s, g.us, g.vs, mask, kind, g.inside, _block_curvatures(g.D))


def _assemble(s: Evaluable, a: Array, b: Array, m: NDArray[np.bool_] | None, kind: str, inside: NDArray[np.bool_],
              parts: _kernels.GridCurvatures) -> CurvatureMap:
    P, Nrm, k1, k2, K, H, ok = parts
    degenerate = inside & ~ok
    if np.any(degenerate):
        iu, iv = np.nonzero(degenerate)
        Nrm[degenerate] = nudged_normals(s, np.stack((a[iu], b[iv]), axis=1))
    finite = P.reshape(-1, 3) if m is None and not isinstance(s, SPatch) else P[inside]
    size = float(np.linalg.norm(finite.max(axis=0) - finite.min(axis=0))) if finite.size else 0.0
    values = curvature_values(kind, k1, k2, K, H, size)
    if m is not None or isinstance(s, SPatch) or np.any(degenerate):
        values = np.where(inside & ~degenerate, values, np.nan)
    return CurvatureMap(points=P, normals=Nrm, values=values, k1=k1, k2=k2, gaussian=K, mean=H,
                        degenerate=degenerate, kind=kind, mask=inside, us=a, vs=b, size=size)


# ------------------------------------------------------------------------------------ colour scale


@dataclass(frozen=True)
class ColorScale:
    """A map from values to ``[0, 1]`` for a colour bar.

    Attributes
    ----------
    lo, hi : float
        Values mapped to 0 and 1; ``lo < hi`` unless every value is equal (then ``lo == hi`` and
        everything maps to 0.5).
    mode : {"symmetric", "clipped", "linear"}
    n_below, n_above : int
        Finite samples of the input below ``lo`` / above ``hi`` (clipped to the ends of the bar).
    """

    lo: float
    hi: float
    mode: str
    n_below: int = 0
    n_above: int = 0

    def normalize(self, values: ArrayLike) -> Array:
        """``(v - lo) / (hi - lo)`` clipped to ``[0, 1]``; NaN stays NaN, ``+-inf`` go to 1 / 0."""
        v = np.asarray(values, dtype=float)
        if self.hi == self.lo:
            return np.where(np.isnan(v), np.nan, np.where(v > self.hi, 1.0, np.where(v < self.lo, 0.0, 0.5)))
        with np.errstate(invalid="ignore", over="ignore"):
            t = (v - self.lo) / (self.hi - self.lo)
        return np.clip(t, 0.0, 1.0)

    def legend_ticks(self, n: int = 5) -> Array:
        """``n >= 2`` equally spaced values from ``lo`` to ``hi`` (symmetric scales include 0 when
        ``n`` is odd), for the labels of a colour bar."""
        return np.linspace(self.lo, self.hi, V.check_count(n, "n", 1, minimum=2))


def _percentile(p: Iterable[float]) -> tuple[float, float]:
    try:
        a, b = (float(x) for x in p)
    except (TypeError, ValueError):
        raise InvalidGeometryError(f"percentile: expected a pair (low, high), got {p!r}") from None
    if not 0.0 <= a < b <= 100.0:
        raise InvalidGeometryError(f"percentile: expected 0 <= low < high <= 100, got {p!r}")
    return a, b


def color_scale(values: ArrayLike, mode: str = "symmetric", *, percentile: tuple[float, float] = (2, 98),
                lo: float | None = None, hi: float | None = None) -> ColorScale:
    """Colour scale of a curvature map's values, robust to spikes and NaN-safe.

    Parameters
    ----------
    values : array_like
        Any shape; NaN (degenerate or masked points) and infinities (flat radius) are ignored.
    mode : {"symmetric", "clipped", "linear"}
        ``"linear"``: the full finite range. ``"clipped"``: the ``percentile`` range (a few spikes do
        not wash the map out). ``"symmetric"``: ``[-a, a]`` with ``a`` the larger magnitude of the
        two percentiles, so that zero (flat, inflection) is the middle colour; this is the usual
        scale of Gaussian and mean curvature maps.
    percentile : (float, float)
        Percentiles for ``"clipped"`` and ``"symmetric"``.
    lo, hi : float, optional
        Override either end (for a common scale over several faces).

    Returns
    -------
    ColorScale

    Raises
    ------
    InvalidGeometryError
        Unknown mode, bad percentile, ``lo >= hi``.
    """
    if mode not in SCALE_MODES:
        raise InvalidGeometryError(f"mode: expected one of {', '.join(map(repr, SCALE_MODES))}, got {mode!r}")
    pa, pb = _percentile(percentile)
    v = np.asarray(values, dtype=float).ravel()
    v = v[np.isfinite(v)]
    if v.size == 0:
        a, b = 0.0, 0.0
    elif mode == "linear":
        a, b = float(v.min()), float(v.max())
    else:
        a, b = (float(x) for x in np.percentile(v, [pa, pb]))
        if mode == "symmetric":
            b = max(abs(a), abs(b))
            a = -b
    for name, x in (("lo", lo), ("hi", hi)):
        if x is not None and not np.isfinite(float(x)):
            raise InvalidGeometryError(f"{name}: expected a finite number, got {x!r}")
    a = a if lo is None else float(lo)
    b = b if hi is None else float(hi)
    if a > b or (a == b and (lo is not None and hi is not None)):
        raise InvalidGeometryError(f"lo, hi: expected lo < hi, got lo = {a!r}, hi = {b!r}")
    return ColorScale(lo=a, hi=b, mode=mode, n_below=int(np.count_nonzero(v < a)), n_above=int(np.count_nonzero(v > b)))
