"""Differential geometry of surfaces (course §6-7 .. §6-16), vectorised, rational included.

First and second fundamental forms, Gaussian / mean / principal curvatures with principal
directions in 3-D, umbilics, and the normal curvature of a tangent direction, from
``surface.derivatives`` (the quotient rule for rational surfaces: The NURBS Book, 2nd ed., A4.4) or
from partials the caller already has (:func:`curvatures_from_derivatives`). Curves are in
:mod:`~occsurf.algorithms.geometry.differential`, whose docstring gives the sign conventions (those
of OpenCascade's ``GeomLProp``) and the rule for degenerate points: where
``|S_u x S_v| <= tolerances.NORMAL_ZERO max(|S_u|, |S_v|)^2`` (a sphere's pole, a collapsed edge)
the normal and every curvature are NaN, never a silent wrong number and never an exception.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import _validate as V
from .. import tolerances
from ..errors import InvalidGeometryError
from ..kernel.surface import BSplineSurface
from ._common import divide_where, lengths

Array = NDArray[np.float64]

__all__ = [
    "SurfaceCurvatures",
    "surface_curvatures",
    "curvatures_from_derivatives",
    "principal_curvatures",
    "is_umbilic",
    "normal_curvature",
]

# Tolerances (read at call time from :mod:`occsurf.algorithms.tolerances`): NORMAL_ZERO, UMBILIC.


@dataclass(frozen=True)
class SurfaceCurvatures:
    """Curvatures of a 3-D surface at parameters of shape ``S`` (OCC's ``GeomLProp`` signs).

    Attributes
    ----------
    gaussian, mean, k1, k2 : ndarray, shape S
        ``K = k1 k2``, ``H = (k1 + k2) / 2``, ``k1 >= k2`` (OCC's Max/MinCurvature).
    dir1, dir2 : ndarray, shape S + (3,)
        Unit principal directions of ``k1``, ``k2``; ``(dir1, dir2, normal)`` is right-handed.
        At an umbilic every direction is principal: ``dir1`` is then ``S_u / |S_u|``.
    normal : ndarray, shape S + (3,)
        ``S_u x S_v / |S_u x S_v|``.
    first_form : tuple of 3 ndarrays, shape S
        ``(E, F, G)``.
    second_form : tuple of 3 ndarrays, shape S
        ``(L, M, N)`` against ``normal``.

    All fields are NaN where the normal is undefined (:data:`~occsurf.algorithms.tolerances.NORMAL_ZERO`).
    """

    gaussian: Array
    mean: Array
    k1: Array
    k2: Array
    dir1: Array
    dir2: Array
    normal: Array
    first_form: tuple[Array, Array, Array]
    second_form: tuple[Array, Array, Array]


def _check_surface(surface: object) -> BSplineSurface:
    if not isinstance(surface, BSplineSurface):
        raise InvalidGeometryError(f"surface: expected a BSplineSurface, got {type(surface).__name__}")
    if surface.dim != 3:
        raise InvalidGeometryError(f"surface: needs a 3-D surface, this one has dim {surface.dim}")
    return surface


def _forms(surface: BSplineSurface, u: ArrayLike, v: ArrayLike) -> dict[str, Array]:
    return _forms_of(surface.derivatives(u, v, 2))


def _forms_of(D: Array) -> dict[str, NDArray[Any]]:  # float and bool arrays
    """First and second fundamental forms from partials ``D`` of shape S + (>=3, >=3, 3)."""
    su, sv = D[..., 1, 0, :], D[..., 0, 1, :]
    cr = np.cross(su, sv)
    ncr = lengths(cr)
    lu, lv = lengths(su), lengths(sv)
    ok = ncr > tolerances.NORMAL_ZERO * np.maximum(lu, lv) ** 2
    n = divide_where(cr, ncr[..., None], ok[..., None])
    dot = lambda x, y: np.einsum("...i,...i->...", x, y)  # noqa: E731
    return dict(su=su, sv=sv, n=n, ok=ok, lu=lu,
                E=np.where(ok, dot(su, su), np.nan), F=np.where(ok, dot(su, sv), np.nan),
                G=np.where(ok, dot(sv, sv), np.nan),
                L=dot(D[..., 2, 0, :], n), M=dot(D[..., 1, 1, :], n), N=dot(D[..., 0, 2, :], n))


def surface_curvatures(surface: BSplineSurface, u: ArrayLike, v: ArrayLike) -> SurfaceCurvatures:
    """Fundamental forms, Gaussian / mean / principal curvatures and directions (course §6-8 .. §6-12).

    Parameters
    ----------
    surface : BSplineSurface
        3-D, rational or not.
    u, v : array_like, broadcastable to shape S

    Returns
    -------
    SurfaceCurvatures

    Notes
    -----
    With ``e1 = S_u/|S_u|``, ``e2 = n x e1`` and ``[S_u S_v] = [e1 e2] A``,
    ``A = [[|S_u|, S_v.e1], [0, S_v.e2]]``, the shape operator in the orthonormal frame is the
    symmetric matrix ``W = A^{-T} [[L, M], [M, N]] A^{-1} = [[a, b], [b, c]]``, so

    .. math:: k_{1,2} = \\frac{a + c}{2} \\pm \\operatorname{hypot}\\Big(\\frac{a - c}{2}, b\\Big),
              \\qquad \\theta_1 = \\tfrac12 \\operatorname{atan2}(2b, a - c),

    ``dir1 = cos(theta1) e1 + sin(theta1) e2``. Unlike ``H +- sqrt(H^2 - K)`` this loses no accuracy
    near umbilics, and the directions come from an angle, never from a null vector of a nearly
    zero matrix. ``K = (LN - M^2)/(EG - F^2)`` and ``H = (EN - 2FM + GL) / (2(EG - F^2))``.
    """
    s = _check_surface(surface)
    return curvatures_from_derivatives(s.derivatives(u, v, 2))


def curvatures_from_derivatives(D: ArrayLike) -> SurfaceCurvatures:
    """:func:`surface_curvatures` from partial derivatives computed by any evaluator.

    For surfaces that are not a :class:`BSplineSurface` (hierarchical surfaces, S-patches, grids of
    partials from ``derivatives_grid``) the same formulas and the same degenerate-point rule apply.

    Parameters
    ----------
    D : array_like, shape S + (r + 1, r + 1, 3), r >= 2
        ``D[..., k, l, :] = d^{k+l} S / du^k dv^l`` (the layout of ``BSplineSurface.derivatives``).

    Returns
    -------
    SurfaceCurvatures
        Of shape S; NaN where the normal is undefined.
    """
    D = np.asarray(D, dtype=float)
    if D.ndim < 3 or D.shape[-3] < 3 or D.shape[-2] < 3 or D.shape[-1] != 3:
        raise InvalidGeometryError(f"D: expected partials of shape (..., r+1, r+1, 3) with r >= 2, got {D.shape}")
    f = _forms_of(D)
    su, sv, n, ok = f["su"], f["sv"], f["n"], f["ok"]
    e1 = divide_where(su, f["lu"][..., None], ok[..., None])
    e2 = np.cross(n, e1)
    dot = lambda x, y: np.einsum("...i,...i->...", x, y)  # noqa: E731
    a11, a12, a22 = f["lu"], dot(sv, e1), dot(sv, e2)
    L, M, N = f["L"], f["M"], f["N"]
    with np.errstate(divide="ignore", invalid="ignore"):
        # A^{-1} = [[1/a11, -a12/(a11 a22)], [0, 1/a22]]
        i11, i12, i22 = 1.0 / a11, -a12 / (a11 * a22), 1.0 / a22
        a = L * i11 * i11
        b = i11 * (L * i12 + M * i22)
        c = i12 * (L * i12 + 2.0 * M * i22) + N * i22 * i22
    half = 0.5 * (a + c)
    rad = np.hypot(0.5 * (a - c), b)
    k1, k2 = half + rad, half - rad
    theta = 0.5 * np.arctan2(2.0 * b, a - c)
    d1 = np.cos(theta)[..., None] * e1 + np.sin(theta)[..., None] * e2
    d2 = np.cross(n, d1)
    E, F, G = f["E"], f["F"], f["G"]
    with np.errstate(divide="ignore", invalid="ignore"):
        det = E * G - F * F
        K = np.where(ok, (L * N - M * M) / det, np.nan)
        H = np.where(ok, (E * N - 2.0 * F * M + G * L) / (2.0 * det), np.nan)
    nan = lambda x: np.where(ok if x.ndim == ok.ndim else ok[..., None], x, np.nan)  # noqa: E731
    return SurfaceCurvatures(gaussian=K, mean=H, k1=nan(k1), k2=nan(k2), dir1=nan(d1), dir2=nan(d2),
                             normal=n, first_form=(E, F, G), second_form=(nan(L), nan(M), nan(N)))


def principal_curvatures(surface: BSplineSurface, u: ArrayLike, v: ArrayLike) -> tuple[Array, Array]:
    """``(k1, k2)`` with ``k1 >= k2``, as :func:`surface_curvatures`."""
    r = surface_curvatures(surface, u, v)
    return r.k1, r.k2


def is_umbilic(surface: BSplineSurface, u: ArrayLike, v: ArrayLike, tol: float | None = None) -> NDArray[np.bool_]:
    """Whether ``k1 - k2 <= tol * max(|k1|, |k2|, 1/R)`` (R: largest control-point distance from
    the net's centroid, so that round-off on a plane counts as flat). Default tol
    :data:`~occsurf.algorithms.tolerances.UMBILIC`. False where the curvature is undefined (NaN)."""
    s = _check_surface(surface)
    tol = tolerances.UMBILIC if tol is None else float(tol)
    P = s.control_points.reshape(-1, 3)
    R = max(float(np.max(lengths(P - P.mean(axis=0)))), np.finfo(float).tiny)
    r = surface_curvatures(s, u, v)
    scale = np.maximum(np.maximum(np.abs(r.k1), np.abs(r.k2)), 1.0 / R)
    with np.errstate(invalid="ignore"):
        return np.asarray((r.k1 - r.k2) <= tol * scale)


def normal_curvature(surface: BSplineSurface, u: ArrayLike, v: ArrayLike, direction: ArrayLike) -> Array:
    """Normal curvature ``II(d) / I(d)`` of the tangent direction ``d = (du, dv)`` (course §6-9).

    Parameters
    ----------
    direction : array_like, shape (..., 2)
        Parameter-space direction, broadcast against ``u, v``; its length does not matter.

    Returns
    -------
    ndarray
        ``(L du^2 + 2 M du dv + N dv^2) / (E du^2 + 2 F du dv + G dv^2)``; NaN for a zero direction
        or an undefined normal.
    """
    s = _check_surface(surface)
    d = V.as_finite_array(direction, "direction")
    if d.ndim == 0 or d.shape[-1] != 2:
        raise InvalidGeometryError(f"direction: expected shape (..., 2), got {d.shape}")
    f = _forms(s, u, v)
    du, dv = d[..., 0], d[..., 1]
    num = f["L"] * du * du + 2.0 * f["M"] * du * dv + f["N"] * dv * dv
    den = f["E"] * du * du + 2.0 * f["F"] * du * dv + f["G"] * dv * dv
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(den > 0, num / den, np.nan)
