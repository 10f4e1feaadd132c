"""occsurf.algorithms: spline-surface algorithms of the SIGGRAPH '91 course C25, in NumPy/SciPy.

Pure NumPy/SciPy: this package never imports OCP, cadquery or build123d.
"""

from .affine import AffineMap, Frame, Normal, Point, ProjectiveMap, Vector, affine_combination
from .conics import arc, circle, conic_arc, conic_from_shoulder, conic_through_point, conic_type, ellipse
from .compat import make_compatible
from .curve import BSplineCurve
from .curvenet import coons, coons_bicubic, gordon, network_parameters, polynomial_approximation
from .generation import extrude, revolve, rotational_sweep, ruled, translational_sweep
from .sweeping import SweepResult, exact_sweep, sweep
from .fitting import (
    approximation_knots,
    averaged_knots,
    fit_curve,
    fit_surface,
    interpolate_curve,
    interpolate_surface,
    loft,
    parametrize,
)
from .generalized import GeneralizedSurface, biquadratic_patch, generalized_biquadratic, ribbon_patch, spatch_curvatures
from .generalized_bicubic import generalized_bicubic
from .hierarchical import HierarchicalSurface
from .hierarchical_core import Overlay
from .hierarchical_curve import HierarchicalCurve
from .hierarchical_offsets import ADDITIVE_OFFSETS, FRAME_OFFSETS, OffsetMapping, register_offset_mapping
from .differential import (
    arc_length,
    curvature,
    curve_frenet,
    rotation_minimizing_frames,
    surface_curvatures,
    torsion,
)
from .nsided import FillQuality, HoleFill, HoleSide, fill_hole, measure_fill, side_from_surface
from .mesh import Mesh, catmull_clark, doo_sabin, read_obj, write_obj
from .spatch import SPatch, domain_vertices, spatch_indices, wachspress, wachspress_derivatives, wachspress_gradient
from .spatch_convert import SPatchConversion, convert_spatch, spatch_to_surfaces
from .surface import BSplineSurface
from .manipulation import (
    Curvature,
    Derivative,
    Dragger,
    Position,
    PreparedConstraints,
    Tangent,
    constrain,
    drag_point,
    drag_surface_point,
)
from .linalg import ConstraintError, ConvergenceError
from .errors import (
    ExchangeError,
    InvalidGeometryError,
    KernelError,
    OccsurfError,
    ParameterError,
    ToleranceError,
)

__all__ = [
    "HoleSide",
    "HoleFill",
    "FillQuality",
    "side_from_surface",
    "fill_hole",
    "measure_fill",
    "extrude",
    "ruled",
    "revolve",
    "translational_sweep",
    "rotational_sweep",
    "sweep",
    "SweepResult",
    "exact_sweep",
    "coons",
    "coons_bicubic",
    "gordon",
    "network_parameters",
    "polynomial_approximation",
    "SPatch",
    "spatch_indices",
    "domain_vertices",
    "wachspress",
    "wachspress_gradient",
    "wachspress_derivatives",
    "spatch_to_surfaces",
    "convert_spatch",
    "SPatchConversion",
    "Mesh",
    "read_obj",
    "write_obj",
    "catmull_clark",
    "doo_sabin",
    "GeneralizedSurface",
    "generalized_biquadratic",
    "generalized_bicubic",
    "ribbon_patch",
    "biquadratic_patch",
    "spatch_curvatures",
    "make_compatible",
    "parametrize",
    "averaged_knots",
    "approximation_knots",
    "interpolate_curve",
    "fit_curve",
    "interpolate_surface",
    "fit_surface",
    "loft",
    "HierarchicalSurface",
    "HierarchicalCurve",
    "Overlay",
    "OffsetMapping",
    "FRAME_OFFSETS",
    "ADDITIVE_OFFSETS",
    "register_offset_mapping",
    "curve_frenet",
    "curvature",
    "torsion",
    "arc_length",
    "rotation_minimizing_frames",
    "surface_curvatures",
    "Point",
    "Vector",
    "Normal",
    "Frame",
    "AffineMap",
    "ProjectiveMap",
    "affine_combination",
    "arc",
    "circle",
    "ellipse",
    "conic_arc",
    "conic_from_shoulder",
    "conic_through_point",
    "conic_type",
    "BSplineCurve",
    "BSplineSurface",
    "OccsurfError",
    "InvalidGeometryError",
    "ParameterError",
    "ToleranceError",
    "KernelError",
    "ExchangeError",
    "constrain",
    "drag_point",
    "drag_surface_point",
    "Dragger",
    "PreparedConstraints",
    "Position",
    "Tangent",
    "Derivative",
    "Curvature",
    "ConstraintError",
    "ConvergenceError",
]
