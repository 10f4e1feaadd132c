"""Surface quality assessment (course ch. 9 "Assessment" and §11-2): the indicators a designer
reads to judge a surface, computed vectorised from exact derivatives.

Public names
------------
Curvature maps (course §9-5 .. §9-13): :func:`curvature_map` -> :class:`CurvatureMap` (Gaussian,
mean, max, min, absolute, radius; degenerate points reported), :func:`curvature_values`,
:func:`color_scale` -> :class:`ColorScale` (symmetric / clipped / linear, NaN-safe, legend ticks).

Shaded-image interrogation from the normal field: :func:`zebra` -> :class:`Stripes` (reflection
lines), :func:`isophotes` -> :class:`Isophotes`, :func:`highlight_lines` (Beier & Chen 1994);
:func:`draft_angle`, :func:`classify_draft`; :func:`normal_hedgehog`, :func:`normal_flips`.

Line curvature plots: :func:`curvature_comb` -> :class:`Comb` (porcupines with inflections),
:func:`iso_curves` (exact iso-parameter curves), :class:`SampledCurve`. Section cuts:
:func:`plane_sections`, :func:`axial_sections` -> :class:`Section` of :class:`SectionCurve`.
Problem areas: :func:`face_flags` -> :class:`Flag` (:data:`FLAG_KINDS`).

Every threshold is a ``QUALITY_...`` entry of :mod:`occsurf.algorithms.tolerances`.
"""

from .combs import Comb, SampledCurve, curvature_comb, iso_curves
from .curvature_maps import KINDS, SCALE_MODES, ColorScale, CurvatureMap, color_scale, curvature_map, curvature_values
from .flags import FLAG_KINDS, Flag, face_flags
from .normals import (
                      DRAFT_INSUFFICIENT,
                      DRAFT_OK,
                      DRAFT_UNDEFINED,
                      DRAFT_UNDERCUT,
                      classify_draft,
                      draft_angle,
                      normal_flips,
                      normal_hedgehog,
)
from .reflection import Isophotes, Stripes, highlight_lines, isophotes, zebra
from .sections import Section, SectionCurve, axial_sections, plane_sections

__all__ = [
    "KINDS",
    "SCALE_MODES",
    "ColorScale",
    "CurvatureMap",
    "color_scale",
    "curvature_map",
    "curvature_values",
    "DRAFT_INSUFFICIENT",
    "DRAFT_OK",
    "DRAFT_UNDEFINED",
    "DRAFT_UNDERCUT",
    "classify_draft",
    "draft_angle",
    "normal_flips",
    "normal_hedgehog",
    "Isophotes",
    "Stripes",
    "highlight_lines",
    "isophotes",
    "zebra",
    "Comb",
    "SampledCurve",
    "curvature_comb",
    "iso_curves",
    "Section",
    "SectionCurve",
    "axial_sections",
    "plane_sections",
    "FLAG_KINDS",
    "Flag",
    "face_flags",
]
