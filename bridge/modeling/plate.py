"""The plate fill as an OCC face (course §8-3; :func:`occsurf.algorithms.topology.plate_fill.fill_plate`).

The plate is one trimmed surface: its face is the B-spline height field bounded by the hole sides'
p-curves (exact: the sides' poles projected onto the plate's plane), built by
:func:`occsurf.bridge.conversion.trimming.trimmed_to_occ_face` through
:func:`occsurf.bridge.conversion.splines.make_face`. The face's edges are the p-curves' images on
the plate, which lie within the fill's achieved G0 of the hole's edges, so the face sews to the
neighbours with the model's ``SEW_TOLERANCE`` (:mod:`.joints`), or the hole edges' own larger
tolerance, whenever that G0 is below it (:func:`plate_face` checks it and says so otherwise).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from occsurf.algorithms.errors import InvalidGeometryError
from occsurf.algorithms.topology.nsided import HoleSide, count_folds
from occsurf.algorithms.topology.plate_fill import PlateFill, fill_plate
from occsurf.algorithms.topology.plate_wrap import WrappedPlateFill, fill_wrapped_plate

from ..conversion.splines import make_face
from .joints import SEW_TOLERANCE

__all__ = ["plate_face", "plate_fill_faces", "plate_quality", "revolution_axes", "wrapped_fill_faces"]


def plate_face(fill: PlateFill, tol: float | None = None, gap: float = 0.0) -> Any:
    """The OCC ``TopoDS_Face`` of a plate fill (its trimmed surface).

    Parameters
    ----------
    fill : PlateFill
    tol : float, optional
        Edge/vertex tolerance of the face; default the larger of 1e-7 and the fill's achieved G0
        (the p-curve images lie that close to the hole's edges).
    gap : float
        The hole edges' own tolerance (model units; the model declares its faces meet within it):
        the fill may miss the boundary by that much (it is sewn in at a tolerance covering it,
        :func:`occsurf.bridge.modeling.refill_sewing._sew_in`).

    Raises
    ------
    InvalidGeometryError
        The fill misses its boundary by more than ``max(SEW_TOLERANCE, gap)`` (it would not sew in).
    """
    k = int(np.argmax(fill.side_g0))
    g0 = float(fill.side_g0[k])
    limit = max(SEW_TOLERANCE, float(gap))
    if g0 > limit:
        raise InvalidGeometryError(f"plate fill: it misses the hole's boundary by {g0:.3g} (side {k} of "
                                   f"{len(fill.side_g0)}), more than the sewing tolerance {SEW_TOLERANCE:g} and "
                                   f"the hole edges' own tolerance {gap:.3g} (its best with {fill.spans[0]} x "
                                   f"{fill.spans[1]} spans)")
    return make_face(fill.trimmed, max(1e-7, g0) if tol is None else tol)


def plate_fill_faces(sides: Sequence[HoleSide], g1: Sequence[bool], g0_tol: float, gap: float = 0.0,
                     **kw: Any) -> tuple[PlateFill, list[Any]]:
    """:func:`fill_plate` and its face (``gap``: :func:`plate_face`): ``(fill, [face])``."""
    fill = fill_plate(sides, g1=g1, g0_tol=g0_tol, **kw)
    return fill, [plate_face(fill, gap=gap)]


def revolution_axes(faces: Sequence[Any]) -> list[tuple[np.ndarray, np.ndarray]]:
    """The axes ``(point, direction)`` of the cylinders, cones, tori and surfaces of revolution among
    ``faces`` (each once): where a hole that winds around an axis (a thread strip) is unrolled
    (:func:`wrapped_fill_faces`)."""
    from OCP.BRepAdaptor import BRepAdaptor_Surface
    from OCP.GeomAbs import GeomAbs_SurfaceType as T

    getters = {T.GeomAbs_Cylinder: lambda s: s.Cylinder().Axis(), T.GeomAbs_Cone: lambda s: s.Cone().Axis(),
               T.GeomAbs_Torus: lambda s: s.Torus().Axis(), T.GeomAbs_SurfaceOfRevolution: lambda s: s.AxeOfRevolution()}
    out: list[tuple[np.ndarray, np.ndarray]] = []
    for f in faces:
        s = BRepAdaptor_Surface(f)
        get = getters.get(s.GetType())
        if get is None:
            continue
        ax = get(s)
        c = np.array(ax.Location().Coord())
        a = np.array(ax.Direction().Coord())
        if not any(abs(abs(float(a @ b)) - 1) < 1e-9 and np.linalg.norm(np.cross(c - d, b)) < 1e-9 * (1 + np.linalg.norm(c))
                   for d, b in out):
            out.append((c, a))
    return out


def wrapped_fill_faces(sides: Sequence[HoleSide], g1: Sequence[bool], g0_tol: float, gap: float = 0.0,
                       axes: Sequence[tuple[np.ndarray, np.ndarray]] = (), **kw: Any) -> tuple[WrappedPlateFill, list[Any]]:
    """:func:`occsurf.algorithms.topology.plate_wrap.fill_wrapped_plate` (a hole winding around an axis:
    ``axes`` first, e.g. :func:`revolution_axes` of its neighbours) and its face: ``(fill, [face])``."""
    fill = fill_wrapped_plate(sides, axes=axes, g1=g1, g0_tol=g0_tol, **kw)
    return fill, [plate_face(fill, gap=gap)]


def plate_quality(fill: PlateFill) -> tuple[float, float, float, int]:
    """Our own numbers for a plate, as :class:`.fill.HoleReport` records them for the central split:
    ``(own_g0, own_g1, internal_g1, folds)``: the fit's largest distance and angle over the sides
    (angle 0 where only G0 was asked), no internal edges (0.0), and the folds *measured* on the
    face (:func:`count_folds` inside its trim: a height field does not fold over itself, but a steep
    ripple turns its normals by more than 90 degrees between neighbouring samples, and counts)."""
    g1 = fill.side_g1[np.isfinite(fill.side_g1)]
    return float(np.max(fill.side_g0)), float(g1.max()) if g1.size else 0.0, 0.0, int(count_folds(fill.trimmed))
