"""Surfaces of arbitrary topology (course ch. 8): S-patches (§8-2), n-sided hole filling (§8-3),
control meshes and subdivision, generalized biquadratic and bicubic B-splines (§8-6, 8-7).

Public names: :class:`SPatch` and its helpers (:func:`spatch_indices`, :func:`domain_vertices`,
:func:`wachspress` and derivatives), :func:`spatch_to_surfaces`, :func:`convert_spatch`,
:class:`SPatchConversion`; :class:`HoleSide`, :func:`side_from_surface`, :func:`fill_hole`,
:class:`HoleFill`, :func:`measure_fill`, :class:`FillQuality`, :func:`count_folds`; sides described by a curve and the
neighbour's normals (trimmed neighbours): :func:`side_from_normals`, :class:`SideFit`, :func:`fit_boundary`; one trimmed thin-plate fill (reflex corners, long curved holes):
:func:`fill_plate`, :class:`PlateFill`; :class:`Mesh`, :func:`read_obj`,
:func:`write_obj`, :func:`catmull_clark`, :func:`doo_sabin`; :class:`GeneralizedSurface`,
:func:`generalized_biquadratic`, :func:`generalized_bicubic`, :func:`ribbon_patch`,
:func:`biquadratic_patch`, :func:`spatch_curvatures`.
"""

from .generalized import GeneralizedSurface, biquadratic_patch, generalized_biquadratic, ribbon_patch, spatch_curvatures
from .generalized_bicubic import generalized_bicubic
from .mesh import Mesh, catmull_clark, doo_sabin, read_obj, write_obj
from .nsided import FillQuality, HoleFill, HoleSide, count_folds, fill_hole, measure_fill, side_from_surface
from .nsided_sides import SideFit, fit_boundary, side_from_normals
from .plate_fill import PlateFill, fill_plate
from .spatch import SPatch, domain_vertices, spatch_indices
from .spatch_convert import SPatchConversion, convert_spatch, spatch_to_surfaces
from .wachspress import wachspress, wachspress_derivatives, wachspress_gradient

__all__ = [
    "SPatch",
    "domain_vertices",
    "spatch_indices",
    "wachspress",
    "wachspress_derivatives",
    "wachspress_gradient",
    "SPatchConversion",
    "convert_spatch",
    "spatch_to_surfaces",
    "FillQuality",
    "HoleFill",
    "HoleSide",
    "fill_hole",
    "measure_fill",
    "count_folds",
    "side_from_surface",
    "SideFit",
    "fit_boundary",
    "side_from_normals",
    "PlateFill",
    "fill_plate",
    "Mesh",
    "catmull_clark",
    "doo_sabin",
    "read_obj",
    "write_obj",
    "GeneralizedSurface",
    "biquadratic_patch",
    "generalized_biquadratic",
    "ribbon_patch",
    "spatch_curvatures",
    "generalized_bicubic",
]
