"""Normal-field indicators (course ch. 9): normal hedgehogs, normal flips between neighbouring
faces, and the draft-angle map of mould making."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import tolerances
from ..errors import InvalidGeometryError
from ._common import (
    Array,
    QualitySurface,
    check_mask,
    dot,
    grid_axes,
    grid_partials,
    nudged_normals,
    surface_of,
    trim_mask,
    unit_vectors,
    vectors,
)

__all__ = ["DRAFT_OK", "DRAFT_INSUFFICIENT", "DRAFT_UNDERCUT", "DRAFT_UNDEFINED", "draft_angle", "classify_draft",
           "normal_hedgehog", "normal_flips"]

#: Codes of :func:`classify_draft`.
DRAFT_OK, DRAFT_INSUFFICIENT, DRAFT_UNDERCUT, DRAFT_UNDEFINED = 1, 0, -1, -2


def draft_angle(normals: ArrayLike, pull_direction: ArrayLike) -> Array:
    """Draft angle in degrees for a pull (mould opening) direction.

    .. math:: \\alpha = \\arcsin(n \\cdot p) \\cdot 180 / \\pi

    with ``n`` the unit outward normal and ``p`` the unit pull direction: 0 on a wall parallel to
    the pull, +90 on a face looking along the pull, -90 against it. Positive angles release with
    the pull (the wall opens towards it); negative ones are undercuts for this half of the mould.

    Parameters
    ----------
    normals : array_like, shape S + (3,)
        Outward normals (normalised here; NaN allowed).
    pull_direction : array_like, shape (3,)

    Returns
    -------
    ndarray, shape S
        Degrees in ``[-90, 90]``; NaN where the normal is undefined.
    """
    N = vectors(normals, "normals", allow_nan=True)
    p = unit_vectors(pull_direction, "pull_direction")
    with np.errstate(invalid="ignore", divide="ignore"):
        s = dot(N, p) / np.linalg.norm(N, axis=-1)
    return np.degrees(np.arcsin(np.clip(s, -1.0, 1.0)))


def classify_draft(angles: ArrayLike, min_draft: float | None = None) -> NDArray[np.int8]:
    """Classify draft angles against a minimum draft.

    Parameters
    ----------
    angles : array_like
        Degrees, from :func:`draft_angle`.
    min_draft : float, optional
        Minimum draft in degrees; default :data:`~occsurf.algorithms.tolerances.QUALITY_MIN_DRAFT_DEG`.

    Returns
    -------
    ndarray of int8, shape of ``angles``
        :data:`DRAFT_OK` (1) for ``angle >= min_draft``, :data:`DRAFT_UNDERCUT` (-1) for
        ``angle <= -min_draft`` (releases only with the opposite half), :data:`DRAFT_INSUFFICIENT`
        (0) in between, ``DRAFT_UNDEFINED`` (-2) for NaN.
    """
    a = np.asarray(angles, dtype=float)
    m = tolerances.QUALITY_MIN_DRAFT_DEG if min_draft is None else float(min_draft)
    if not np.isfinite(m) or m < 0:
        raise InvalidGeometryError(f"min_draft: expected a finite angle >= 0 in degrees, got {min_draft!r}")
    out = np.full(a.shape, DRAFT_INSUFFICIENT, dtype=np.int8)
    with np.errstate(invalid="ignore"):
        out[a >= m] = DRAFT_OK
        out[a <= -m] = DRAFT_UNDERCUT
    out[np.isnan(a)] = DRAFT_UNDEFINED
    return out


def normal_hedgehog(surface: QualitySurface, us: ArrayLike | int, vs: ArrayLike | int, length: float | None = None, *,
                    mask: ArrayLike | None = None, patch: int | None = None) -> tuple[Array, Array]:
    """Normal vectors drawn as spines (a "hedgehog") on the grid ``us x vs``.

    Parameters
    ----------
    surface, us, vs, mask, patch
        As :func:`~occsurf.algorithms.quality.curvature_map`.
    length : float, optional
        Spine length in model units; default 5 % of the diagonal of the sampled points.

    Returns
    -------
    points, tips : ndarray, shape (m, n, 3)
        ``tips = points + length * normal``; at degenerate points the limit normal taken just inside
        the domain is used; NaN outside the mask.
    """
    s = surface_of(surface, patch)
    a, b = grid_axes(s, us, vs)
    m = trim_mask(surface, a, b, check_mask(mask, (a.size, b.size)))
    g = grid_partials(s, a, b, m)
    P = g.D[..., 0, 0, :]
    with np.errstate(invalid="ignore", divide="ignore"):
        c = np.cross(g.D[..., 1, 0, :], g.D[..., 0, 1, :])
        nc = np.linalg.norm(c, axis=-1)
        lim = tolerances.NORMAL_ZERO * np.maximum(np.linalg.norm(g.D[..., 1, 0, :], axis=-1),
                                                  np.linalg.norm(g.D[..., 0, 1, :], axis=-1)) ** 2
        ok = nc > lim
        N = np.where(ok[..., None], c / nc[..., None], np.nan)
    bad = g.inside & ~ok
    if np.any(bad):
        iu, iv = np.nonzero(bad)
        N[bad] = nudged_normals(s, np.stack((a[iu], b[iv]), axis=1))
    if length is None:
        f = P[g.inside]
        length = 0.05 * float(np.linalg.norm(f.max(axis=0) - f.min(axis=0))) if f.size else 0.0
    elif not np.isfinite(float(length)):
        raise InvalidGeometryError(f"length: expected a finite number, got {length!r}")
    return P, P + float(length) * N


def normal_flips(normals_a: ArrayLike, normals_b: ArrayLike) -> tuple[NDArray[np.bool_], Array]:
    """Normal flips between two faces sampled at the same points of a shared edge.

    Parameters
    ----------
    normals_a, normals_b : array_like, shape S + (3,)
        Normals of the two faces at matching edge samples (as oriented in the shell).

    Returns
    -------
    flipped : ndarray of bool, shape S
        Angle > 90 degrees: one face's normal points to the other side (an inconsistently
        oriented shell, or a cusp).
    angle : ndarray, shape S
        Angle between the normals in degrees, ``[0, 180]``; NaN where either is undefined. Its
        value where not flipped is the G1 break angle.
    """
    A = vectors(normals_a, "normals_a", allow_nan=True)
    B = vectors(normals_b, "normals_b", allow_nan=True)
    try:
        A, B = np.broadcast_arrays(A, B)
    except ValueError:
        raise InvalidGeometryError(f"normals_b: shape {B.shape} does not match normals_a {A.shape}") from None
    with np.errstate(invalid="ignore", divide="ignore"):
        # atan2(|a x b|, a . b) is accurate at small and near-180-degree angles, unlike arccos.
        ang = np.degrees(np.arctan2(np.linalg.norm(np.cross(A, B), axis=-1), dot(A, B)))
        return np.asarray(ang > 90.0), ang
