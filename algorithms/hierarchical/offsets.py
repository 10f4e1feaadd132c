"""Offset referencing for hierarchical splines: local frames and offset mapping functions.

Course §5-15 (offset referencing) and §5-37..5-41 (offset fields and offset mapping functions):
every control vertex of an overlay is stored as an *offset* from its reference vertex (the parent's
refined control vertex), expressed in a local frame of the parent surface at the vertex's
reference parameter. An :class:`OffsetMapping` turns stored offsets into world displacements (and
back); two are provided and others can be registered:

``FRAME_OFFSETS`` ("frame")
    ``d = F o``: the offset's coordinates along the orthonormal frame ``F = [t, b, n]`` of the
    parent surface (tangent-u, the second tangent, the normal). Details ride along when a coarser
    level bends or turns (Forsey & Bartels 1988).
``ADDITIVE_OFFSETS`` ("additive")
    ``d = o``: plain world-space differences, for comparison (details translate, never turn).

Frame construction (surfaces, :func:`surface_frames`)
-----------------------------------------------------
At a reference parameter ``(u, v)`` with partials ``S_u``, ``S_v`` of the parent surface:

.. math::

    t = S_u / \\|S_u\\|, \\qquad n = \\frac{S_u \\times S_v}{\\|S_u \\times S_v\\|}, \\qquad b = n \\times t,

i.e. Gram–Schmidt of ``(S_u, S_v)`` completed by the normal; ``F = [t | b | n]`` (columns) is
right-handed and orthonormal, so its inverse is ``F^T``. ``b`` is the part of ``S_v`` orthogonal to
``S_u``, normalised.

Degenerate normals. The normal is *degenerate* where
``|S_u x S_v| <= FRAME_DEGENERACY (|S_u|^2 + |S_v|^2)`` (a collapsed edge or corner, a fold, a
vanishing partial; the test is scale-invariant). There the frame is taken at the parameter moved
towards the domain centre by ``FRAME_NUDGE`` times the domain size in each direction — at a
collapsed edge this is the limit normal up to ``O(FRAME_NUDGE)``, and it is deterministic, so
storing an offset and applying it again give the same displacement. If the normal is still
degenerate there (e.g. a patch collapsed to a point), the world axes are used: the offset then
acts additively at that vertex.

Curves (:func:`curve_frames`): 2-D ``[t | J t]`` with ``J`` the quarter turn; 3-D
``[t | e | t x e]`` with ``e`` the unit part of :data:`CURVE_UP` orthogonal to ``t`` (the x axis
where ``t`` is parallel to it). A vanishing tangent is treated as above (nudge, then world axes).

References
----------
D. R. Forsey, R. H. Bartels, "Hierarchical B-spline refinement", SIGGRAPH '88, 205-212;
course notes C25, SIGGRAPH 1991, §5-15, §5-37..5-41.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from .. import tolerances
from ..errors import InvalidGeometryError
from ..kernel.curve import BSplineCurve
from ..kernel.surface import BSplineSurface

__all__ = [
    "CURVE_UP",
    "OffsetMapping",
    "FRAME_OFFSETS",
    "ADDITIVE_OFFSETS",
    "register_offset_mapping",
    "get_offset_mapping",
    "surface_frames",
    "curve_frames",
    "frames_from_partials",
]

Array = NDArray[np.float64]

# FRAME_DEGENERACY and FRAME_NUDGE (see the module notes) are tolerances of
# :mod:`occsurf.algorithms.tolerances`, read at call time (``tolerances.FRAME_NUDGE``).

#: Reference "up" direction of 3-D curve frames (see the module notes).
CURVE_UP: tuple[float, float, float] = (0.0, 0.0, 1.0)


# ------------------------------------------------------------------------------------ mappings
@dataclass(frozen=True)
class OffsetMapping:
    """An offset mapping function (course §5-37): stored offsets -> world displacements.

    Parameters
    ----------
    name : str
        Key under which :meth:`HierarchicalSurface.to_dict` stores it (register custom mappings
        with :func:`register_offset_mapping` so that saved hierarchies load again).
    forward : callable ``(offsets (m, d), frames (m, d, d)) -> displacements (m, d)``
        ``frames[k]`` has the frame axes as columns (world coordinates).
    inverse : callable ``(displacements (m, d), frames (m, d, d)) -> offsets (m, d)``
        The inverse of ``forward`` for fixed frames (used to store world-space edits).
    uses_frames : bool
        If False the frames are never computed (``frames`` is passed as ``None``), which saves
        the parent evaluations.

    Notes
    -----
    The edit-point solve (:meth:`HierarchicalSurface.drag_point`) assumes ``forward`` is linear in
    the offsets for fixed frames; both provided mappings are.
    """

    name: str
    forward: Callable[[Array, Array | None], Array]
    inverse: Callable[[Array, Array | None], Array]
    uses_frames: bool = True

    def __call__(self, offsets: Array, frames: Array | None) -> Array:
        return self.forward(offsets, frames)


def _frame_forward(offsets: Array, frames: Array | None) -> Array:
    if frames is None:  # the hierarchy computes them for a mapping that uses_frames
        raise InvalidGeometryError("the frame offset mapping needs the parent's frames")
    return np.einsum("mij,mj->mi", frames, offsets)


def _frame_inverse(displacements: Array, frames: Array | None) -> Array:
    if frames is None:  # the hierarchy computes them for a mapping that uses_frames
        raise InvalidGeometryError("the frame offset mapping needs the parent's frames")
    return np.einsum("mji,mj->mi", frames, displacements)  # orthonormal: F^-1 = F^T


def _identity(values: Array, frames: Array | None) -> Array:
    return np.array(values, dtype=float, copy=True)


#: Offsets are coordinates in the parent's orthonormal local frame (course §5-15).
FRAME_OFFSETS = OffsetMapping("frame", _frame_forward, _frame_inverse, True)
#: Offsets are world-space differences (plain hierarchical refinement, for comparison).
ADDITIVE_OFFSETS = OffsetMapping("additive", _identity, _identity, False)

_REGISTRY: dict[str, OffsetMapping] = {"frame": FRAME_OFFSETS, "additive": ADDITIVE_OFFSETS}


def register_offset_mapping(mapping: OffsetMapping) -> None:
    """Make a custom :class:`OffsetMapping` known by name (to :func:`get_offset_mapping` and
    ``from_dict``). Re-registering a built-in name raises."""
    if not isinstance(mapping, OffsetMapping):
        raise InvalidGeometryError(f"mapping: expected an OffsetMapping, got {type(mapping).__name__}")
    if mapping.name in ("frame", "additive") and _REGISTRY[mapping.name] is not mapping:
        raise InvalidGeometryError(f"mapping: the name {mapping.name!r} is built in and cannot be replaced")
    _REGISTRY[mapping.name] = mapping


def get_offset_mapping(mapping: str | OffsetMapping) -> OffsetMapping:
    """The mapping itself, or the registered one of that name."""
    if isinstance(mapping, OffsetMapping):
        return mapping
    if isinstance(mapping, str) and mapping in _REGISTRY:
        return _REGISTRY[mapping]
    raise InvalidGeometryError(
        f"offsets: expected an OffsetMapping or one of {sorted(_REGISTRY)}, got {mapping!r}")


# ------------------------------------------------------------------------------------ frames
def frames_from_partials(su: Array, sv: Array) -> tuple[Array, NDArray[np.bool_]]:
    """Orthonormal frames ``[t | b | n]`` from partials, and where the normal is degenerate.

    Parameters
    ----------
    su, sv : ndarray, shape (m, 3)

    Returns
    -------
    frames : ndarray, shape (m, 3, 3)
        Columns ``t, b, n`` (see the module notes); identity rows where degenerate.
    degenerate : ndarray of bool, shape (m,)
    """
    n = np.cross(su, sv)
    ln = np.linalg.norm(n, axis=-1)
    lu = np.linalg.norm(su, axis=-1)
    scale = np.einsum("mi,mi->m", su, su) + np.einsum("mi,mi->m", sv, sv)
    bad = ~(ln > tolerances.FRAME_DEGENERACY * scale) | ~(lu > 0)
    F = np.empty(su.shape[:1] + (3, 3))
    F[:] = np.eye(3)
    ok = ~bad
    if np.any(ok):
        t = su[ok] / lu[ok, None]
        nn = n[ok] / ln[ok, None]
        F[ok] = np.stack([t, np.cross(nn, t), nn], axis=-1)
    return F, bad


def _towards_centre(x: Array, lo: float, hi: float) -> Array:
    step = tolerances.FRAME_NUDGE * (hi - lo)
    return np.where(x < 0.5 * (lo + hi), x + step, x - step)


def surface_frames(surface: BSplineSurface, us: Array, vs: Array) -> Array:
    """Offset-referencing frames of a 3-D surface on the grid ``us x vs``.

    Parameters
    ----------
    surface : BSplineSurface
        3-D (the parent level's surface).
    us, vs : ndarray, shape (m_u,), (m_v,)
        Reference parameters inside the domain.

    Returns
    -------
    ndarray, shape (m_u, m_v, 3, 3)
        Columns ``t, b, n``; degenerate normals handled as in the module notes.
    """
    D = surface.derivatives_grid(us, vs, 1)
    shape = D.shape[:2]
    F, bad = frames_from_partials(D[:, :, 1, 0].reshape(-1, 3), D[:, :, 0, 1].reshape(-1, 3))
    if np.any(bad):
        uu, vv = np.meshgrid(us, vs, indexing="ij")
        (u0, u1), (v0, v1) = surface.domain
        a = _towards_centre(uu.reshape(-1)[bad], u0, u1)
        b = _towards_centre(vv.reshape(-1)[bad], v0, v1)
        Db = surface.derivatives(a, b, 1)
        F[bad], _ = frames_from_partials(Db[:, 1, 0], Db[:, 0, 1])  # still degenerate: world axes
    return F.reshape(shape + (3, 3))


def curve_frames(curve: BSplineCurve, us: Array) -> Array:
    """Offset-referencing frames of a 2-D or 3-D curve at the parameters ``us``.

    Returns
    -------
    ndarray, shape (m, d, d)
        Columns: the unit tangent first (see the module notes); world axes where the tangent
        vanishes even after the nudge.
    """
    d = curve.dim
    if d not in (2, 3):
        raise InvalidGeometryError(f"curve: frame offsets need a 2-D or 3-D curve, this one has dim {d}; "
                                   "use offsets='additive'")

    def frames(t: Array) -> tuple[Array, NDArray[np.bool_]]:
        lt = np.linalg.norm(t, axis=-1)
        bad = ~(lt > 0)
        F = np.empty(t.shape[:1] + (d, d))
        F[:] = np.eye(d)
        ok = ~bad
        tt = t[ok] / lt[ok, None]
        if d == 2:
            F[ok] = np.stack([tt, np.stack([-tt[:, 1], tt[:, 0]], -1)], -1)
        else:
            up = np.broadcast_to(np.asarray(CURVE_UP, float), tt.shape).copy()
            e = up - np.einsum("mi,mi->m", up, tt)[:, None] * tt
            le = np.linalg.norm(e, axis=-1)
            par = le <= 1e-8
            if np.any(par):
                x = np.array([1.0, 0.0, 0.0])
                e[par] = x - (tt[par] @ x)[:, None] * tt[par]
                le[par] = np.linalg.norm(e[par], axis=-1)
            e = e / le[:, None]
            F[ok] = np.stack([tt, e, np.cross(tt, e)], -1)
        return F, bad

    F, bad = frames(curve.derivatives(us, 1)[:, 1])
    if np.any(bad):
        lo, hi = curve.domain
        F[bad], _ = frames(curve.derivatives(_towards_centre(us[bad], lo, hi), 1)[:, 1])
    return F
