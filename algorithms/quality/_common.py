"""Shared helpers of :mod:`occsurf.algorithms.quality`: argument checks and one evaluator of grid
partials for every surface kind the indicators accept (B-spline / NURBS, hierarchical, S-patch,
generalized B-spline patch)."""

from __future__ import annotations

import numbers
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import _validate as V
from ..errors import InvalidGeometryError
from ..hierarchical.surface import HierarchicalSurface
from ..kernel.surface import BSplineSurface
from ..kernel.trimmed import TrimmedSurface
from ..topology.generalized import GeneralizedSurface
from ..topology.spatch import SPatch, domain_vertices

Array = NDArray[np.float64]

SURFACE_KINDS = "BSplineSurface, TrimmedSurface, HierarchicalSurface, SPatch or GeneralizedSurface (with patch=)"
#: The surfaces the quality functions take (:data:`SURFACE_KINDS`).
QualitySurface = BSplineSurface | TrimmedSurface | HierarchicalSurface | SPatch | GeneralizedSurface
#: What they evaluate (:func:`surface_of`): a trimmed surface's surface, a generalized surface's patch.
Evaluable = BSplineSurface | HierarchicalSurface | SPatch


def dot(a: Array, b: Array) -> Array:
    """Row-wise dot product over the last axis."""
    return np.einsum("...i,...i->...", a, b)


def unit_vectors(value: ArrayLike, name: str) -> Array:
    """``value`` as finite 3-vectors ``(..., 3)`` normalised to unit length; zero vectors rejected."""
    a = V.as_finite_array(value, name)
    if a.ndim == 0 or a.shape[-1] != 3:
        raise InvalidGeometryError(f"{name}: expected 3-vectors, shape (..., 3), got shape {a.shape}")
    n = np.linalg.norm(a, axis=-1, keepdims=True)
    if np.any(n == 0):
        raise InvalidGeometryError(f"{name}: expected non-zero vectors, got a zero vector")
    return a / n


def vectors(value: ArrayLike, name: str, *, allow_nan: bool = False) -> Array:
    """``value`` as an array of 3-vectors ``(..., 3)``; NaN allowed if ``allow_nan`` (degenerate
    normals of a :class:`CurvatureMap`), never infinities."""
    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as err:
        raise InvalidGeometryError(f"{name}: expected an array of 3-vectors, got {type(value).__name__}") from err
    if a.ndim == 0 or a.shape[-1] != 3:
        raise InvalidGeometryError(f"{name}: expected 3-vectors, shape (..., 3), got shape {a.shape}")
    bad = np.isinf(a) if allow_nan else ~np.isfinite(a)
    if np.any(bad):
        raise InvalidGeometryError(f"{name}: expected finite values{' (or NaN)' if allow_nan else ''}, "
                                   f"got {a[bad][0]} at index {tuple(int(i) for i in np.argwhere(bad)[0])}")
    return a


def positive(value: object, name: str) -> float:
    """A positive finite real number."""
    if not (isinstance(value, numbers.Real) and not isinstance(value, bool) and np.isfinite(float(value))
            and float(value) > 0):
        raise InvalidGeometryError(f"{name}: expected a positive finite number, got {value!r}")
    return float(value)


@dataclass(frozen=True)
class GridPartials:
    """Partials up to order 2 of a surface on a parameter grid.

    Attributes
    ----------
    D : ndarray, shape (m, n, 3, 3, 3)
        ``D[i, j, k, l] = d^{k+l} S / du^k dv^l`` at ``(us[i], vs[j])``; NaN outside ``inside``.
    inside : ndarray of bool, shape (m, n)
        Grid points in the surface's domain and the caller's mask.
    us, vs : ndarray, shapes (m,), (n,)
    """

    D: Array
    inside: NDArray[np.bool_]
    us: Array
    vs: Array


def surface_of(surface: QualitySurface, patch: int | None) -> Evaluable:
    """The evaluable surface: a :class:`GeneralizedSurface` needs ``patch``; a
    :class:`TrimmedSurface` gives its surface (its trims go through :func:`trim_mask`)."""
    if isinstance(surface, TrimmedSurface):
        if patch is not None:
            raise InvalidGeometryError("patch: only a GeneralizedSurface takes patch=, got a TrimmedSurface")
        surface = surface.surface
    if isinstance(surface, GeneralizedSurface):
        if patch is None:
            raise InvalidGeometryError("patch: a GeneralizedSurface needs patch=<index of its S-patch>")
        if isinstance(patch, bool) or not isinstance(patch, numbers.Integral) or not 0 <= int(patch) < len(surface):
            raise InvalidGeometryError(f"patch: expected an index from 0 to {len(surface) - 1}, got {patch!r}")
        return surface.patches[int(patch)]
    if not isinstance(surface, (BSplineSurface, HierarchicalSurface, SPatch)):
        raise InvalidGeometryError(f"surface: expected a {SURFACE_KINDS}, got {type(surface).__name__}")
    if patch is not None:
        raise InvalidGeometryError(f"patch: only a GeneralizedSurface takes patch=, got a {type(surface).__name__}")
    if getattr(surface, "dim", 3) != 3:
        raise InvalidGeometryError(f"surface: needs a 3-D surface, this one has dim {surface.dim}")
    return surface


def domain_of(surface: Evaluable) -> tuple[tuple[float, float], tuple[float, float]]:
    """Parameter box: the domain of a tensor-product surface, the bounding box of an S-patch's
    regular n-gon domain."""
    if isinstance(surface, SPatch):
        P = domain_vertices(surface.sides)
        return (float(P[:, 0].min()), float(P[:, 0].max())), (float(P[:, 1].min()), float(P[:, 1].max()))
    (u0, u1), (v0, v1) = surface.domain
    return (float(u0), float(u1)), (float(v0), float(v1))


def grid_axis(x: ArrayLike | int, lo: float, hi: float, name: str) -> Array:
    """``x`` as a 1-D parameter array; an integer ``k >= 2`` means ``k`` equally spaced values."""
    if isinstance(x, numbers.Integral) and not isinstance(x, bool):
        if int(x) < 2:
            raise InvalidGeometryError(f"{name}: expected at least 2 samples, got {x!r}")
        V.check_size((int(x),), f"{name}: {int(x)} samples")
        return np.linspace(lo, hi, int(x))
    a = V.check_parameters(x, lo, hi, name)
    if a.ndim != 1 or a.size == 0:
        raise InvalidGeometryError(f"{name}: expected a non-empty 1-D array of parameters, got shape {a.shape}")
    return a


def grid_axes(surface: Evaluable, us: ArrayLike | int, vs: ArrayLike | int) -> tuple[Array, Array]:
    """Grid parameters of ``surface``: inside the domain of a tensor-product surface; any finite
    domain coordinates for an S-patch (points outside its n-gon are masked, not rejected)."""
    (u0, u1), (v0, v1) = domain_of(surface)
    if isinstance(surface, SPatch):
        out = []
        for x, lo, hi, name in ((us, u0, u1, "us"), (vs, v0, v1, "vs")):
            if isinstance(x, numbers.Integral) and not isinstance(x, bool):
                out.append(grid_axis(x, lo, hi, name))
                continue
            a = V.as_finite_array(x, name, ndim=1)
            if a.size == 0:
                raise InvalidGeometryError(f"{name}: expected a non-empty 1-D array of domain coordinates")
            out.append(a)
        a, b = out
    else:
        a, b = grid_axis(us, u0, u1, "us"), grid_axis(vs, v0, v1, "vs")
    check_grid(a.size, b.size)
    return a, b


#: Floats a map, flag or hedgehog holds per grid point at once: the partials to order 2 (27) and
#: their masked copy, points, normals, the curvature fields, meshgrids and masks.
GRID_FLOATS_PER_POINT = 80


def check_grid(m: int, n: int, name: str = "us, vs") -> None:
    """Refuse an ``m x n`` quality grid above ``tolerances.MAX_ARRAY_BYTES`` before any of its
    per-point arrays exist (every path: NumPy, the numba kernel, S-patches, trimmed faces);
    ``name`` is the argument that set the grid."""
    V.check_size((m, n, GRID_FLOATS_PER_POINT),
                 f"{name}: a {m} x {n} grid ({GRID_FLOATS_PER_POINT} floats per point for the partials and fields)")


def trim_mask(surface: QualitySurface, us: Array, vs: Array, mask: NDArray[np.bool_] | None) -> NDArray[np.bool_] | None:
    """``mask`` and, for a :class:`TrimmedSurface`, its classification of the grid ``us x vs``
    (points on the face, boundary included: :meth:`TrimmedSurface.contains`); ``mask`` itself for
    any other surface."""
    if not isinstance(surface, TrimmedSurface):
        return mask
    inside = surface.contains(*np.meshgrid(us, vs, indexing="ij"))
    return inside if mask is None else inside & mask


def check_mask(mask: ArrayLike | None, shape: tuple[int, int]) -> NDArray[np.bool_] | None:
    if mask is None:
        return None
    m = np.asarray(mask)
    if m.dtype != bool or m.shape != shape:
        raise InvalidGeometryError(f"mask: expected a boolean array of shape {shape}, got {m.dtype} of shape {m.shape}")
    return m


def inside_polygon(x: Array, y: Array, P: Array) -> NDArray[np.bool_]:
    """Points ``(x, y)`` inside or on the convex polygon ``P`` (counter-clockwise vertices)."""
    e = np.roll(P, -1, axis=0) - P
    cross = e[:, 0] * (y[..., None] - P[:, 1]) - e[:, 1] * (x[..., None] - P[:, 0])
    scale = np.abs(P).max()
    return np.all(cross >= -1e-12 * scale * scale, axis=-1)


def grid_partials(surface: Evaluable, us: Array, vs: Array, mask: NDArray[np.bool_] | None) -> GridPartials:
    """Partials up to order 2 on the grid ``us x vs`` by the surface's own evaluator.

    Tensor-product surfaces use ``derivatives_grid`` (two banded products); an S-patch, whose
    domain is a regular n-gon, is evaluated only at the grid points ``(x, y) = (us[i], vs[j])``
    inside the polygon, by its exact Taylor-mode derivatives.
    """
    shape = (us.size, vs.size)
    inside = np.ones(shape, bool) if mask is None else mask.copy()
    if isinstance(surface, SPatch):
        X, Y = np.meshgrid(us, vs, indexing="ij")
        inside &= inside_polygon(X, Y, domain_vertices(surface.sides))
        D = np.full(shape + (3, 3, 3), np.nan)
        pts = np.stack((X[inside], Y[inside]), axis=-1)
        if pts.size:
            D[inside] = surface.derivatives(pts, 2)[..., :3, :3, :]
        return GridPartials(D, inside, us, vs)
    D = np.asarray(surface.derivatives_grid(us, vs, 2))
    if mask is not None:
        D = np.where(inside[..., None, None, None], D, np.nan)
    return GridPartials(D, inside, us, vs)


def nudged_normals(surface: Evaluable, uv: Array) -> Array:
    """Normals at degenerate parameters ``uv`` (k, 2) taken a little way into the domain.

    At a pole or a collapsed edge ``S_u x S_v`` vanishes; the limit normal is the normal at a
    parameter moved by 1e-7 of the domain size towards the domain's centre (a renderer still needs
    a direction there; the point stays reported as degenerate).
    """
    (u0, u1), (v0, v1) = domain_of(surface)
    centre = np.array([(u0 + u1) / 2, (v0 + v1) / 2])
    if isinstance(surface, SPatch):
        centre = np.zeros(2)
    size = np.array([u1 - u0, v1 - v0])
    out = np.full((uv.shape[0], 3), np.nan)
    for h in (1e-7, 1e-5, 1e-3):  # a few fixed step sizes, each vectorised over all points
        todo = ~np.all(np.isfinite(out), axis=1)
        if not np.any(todo):
            break
        q = uv[todo] + h * size * np.sign(centre - uv[todo])
        if isinstance(surface, SPatch):
            q = uv[todo] + h * (centre - uv[todo])
            D = surface.derivatives(q, 1)
        else:
            D = surface.derivatives(q[:, 0], q[:, 1], 1)
        c = np.cross(D[:, 1, 0, :], D[:, 0, 1, :])
        n = np.linalg.norm(c, axis=1, keepdims=True)
        with np.errstate(invalid="ignore", divide="ignore"):
            out[todo] = np.where(n > 0, c / n, np.nan)
    return out
