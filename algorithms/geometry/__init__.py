"""Affine and differential geometry (course ch. 1 and §6-0..6-14).

Public names: the typed affine objects :class:`Point`, :class:`Vector`, :class:`Normal`,
:class:`Frame`, :class:`AffineMap`, :class:`ProjectiveMap`, :func:`affine_combination`, and the
differential geometry of curves and surfaces: :func:`curve_frenet`, :func:`curvature`,
:func:`torsion`, :func:`arc_length`, :func:`rotation_minimizing_frames`, :func:`surface_curvatures`,
:func:`curvatures_from_derivatives`.
"""

from .affine import Normal, Point, Vector, affine_combination
from .affine_maps import AffineMap, Frame, ProjectiveMap
from .differential import arc_length, curvature, curve_frenet, rotation_minimizing_frames, torsion
from .surface_differential import curvatures_from_derivatives, surface_curvatures

__all__ = [
    "AffineMap",
    "Frame",
    "Normal",
    "Point",
    "ProjectiveMap",
    "Vector",
    "affine_combination",
    "arc_length",
    "curvature",
    "curvatures_from_derivatives",
    "curve_frenet",
    "rotation_minimizing_frames",
    "surface_curvatures",
    "torsion",
]
