"""occsurf.algorithms: spline-surface algorithms of the SIGGRAPH '91 course C25, in NumPy/SciPy.

Pure NumPy/SciPy: this package never imports OCP, cadquery or build123d, nor :mod:`occsurf.bridge`.
One subpackage per family of course chapters:

=================  ==========================================================================
``kernel``         basis, knots, curves, surfaces, Bézier, blossoms, degree, rational, conics (ch. 2, 12)
``geometry``       affine and differential geometry (ch. 1, §6-0..6-14)
``construction``   extrusion, revolution, sweeps, Coons, Gordon (ch. 6)
``fitting``        parameters, knots, interpolation, least squares, lofting (ch. 7)
``manipulation``   linear algebra, constraints, dragging (ch. 3, 4)
``hierarchical``   hierarchical B-splines (ch. 5)
``topology``       S-patches, n-sided holes, meshes, generalized B-splines (ch. 8)
``quality``        curvature maps, combs, sections, zebra, draft, problem flags (ch. 9, 11-2)
=================  ==========================================================================

Cross-cutting modules stay at this level: :mod:`.errors` (the exception hierarchy),
:mod:`.tolerances` (every numeric tolerance, overridable), :mod:`._validate` (argument checks) and
:mod:`._numba_kernels` (optional compiled kernels).
"""

from typing import TYPE_CHECKING

from occsurf._lazy import lazy_exports

from .errors import (
    ExchangeError,
    InvalidGeometryError,
    KernelError,
    OccsurfError,
    ParameterError,
    ToleranceError,
)

if TYPE_CHECKING:  # the lazily served names, for type checkers and IDEs
    from .construction import (
        SweepResult,
        coons,
        coons_bicubic,
        exact_sweep,
        extrude,
        gordon,
        network_parameters,
        polynomial_approximation,
        revolve,
        rotational_sweep,
        ruled,
        sweep,
        translational_sweep,
    )
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
    from .geometry import (
        AffineMap,
        Frame,
        Normal,
        Point,
        ProjectiveMap,
        Vector,
        affine_combination,
        arc_length,
        curvature,
        curve_frenet,
        rotation_minimizing_frames,
        surface_curvatures,
        torsion,
    )
    from .hierarchical import (
        ADDITIVE_OFFSETS,
        FRAME_OFFSETS,
        HierarchicalCurve,
        HierarchicalSurface,
        OffsetMapping,
        Overlay,
        register_offset_mapping,
    )
    from .kernel import (
        BSplineCurve,
        BSplineSurface,
        TrimmedSurface,
        arc,
        circle,
        conic_arc,
        conic_from_shoulder,
        conic_through_point,
        conic_type,
        ellipse,
        make_compatible,
    )
    from .manipulation import (
        ConstraintError,
        ConvergenceError,
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
    from .topology import (
        FillQuality,
        GeneralizedSurface,
        HoleFill,
        HoleSide,
        Mesh,
        SPatch,
        SPatchConversion,
        biquadratic_patch,
        catmull_clark,
        convert_spatch,
        domain_vertices,
        doo_sabin,
        fill_hole,
        generalized_biquadratic,
        measure_fill,
        read_obj,
        ribbon_patch,
        side_from_surface,
        spatch_curvatures,
        spatch_indices,
        spatch_to_surfaces,
        wachspress_derivatives,
        wachspress_gradient,
        write_obj,
    )
    from .topology.generalized_bicubic import generalized_bicubic  # a function named as its module
    from .topology.wachspress import wachspress  # (from the package, mypy sees the module's name twice)

#: Name -> the subpackage that defines it: imported on first use (PEP 562), so `import
#: occsurf.algorithms` (or one chapter) does not load every chapter and its SciPy modules.
_EXPORTS: dict[str, str] = {
    "SweepResult": ".construction",
    "coons": ".construction",
    "coons_bicubic": ".construction",
    "exact_sweep": ".construction",
    "extrude": ".construction",
    "gordon": ".construction",
    "network_parameters": ".construction",
    "polynomial_approximation": ".construction",
    "revolve": ".construction",
    "rotational_sweep": ".construction",
    "ruled": ".construction",
    "sweep": ".construction",
    "translational_sweep": ".construction",
    "approximation_knots": ".fitting",
    "averaged_knots": ".fitting",
    "fit_curve": ".fitting",
    "fit_surface": ".fitting",
    "interpolate_curve": ".fitting",
    "interpolate_surface": ".fitting",
    "loft": ".fitting",
    "parametrize": ".fitting",
    "AffineMap": ".geometry",
    "Frame": ".geometry",
    "Normal": ".geometry",
    "Point": ".geometry",
    "ProjectiveMap": ".geometry",
    "Vector": ".geometry",
    "affine_combination": ".geometry",
    "arc_length": ".geometry",
    "curvature": ".geometry",
    "curve_frenet": ".geometry",
    "rotation_minimizing_frames": ".geometry",
    "surface_curvatures": ".geometry",
    "torsion": ".geometry",
    "ADDITIVE_OFFSETS": ".hierarchical",
    "FRAME_OFFSETS": ".hierarchical",
    "HierarchicalCurve": ".hierarchical",
    "HierarchicalSurface": ".hierarchical",
    "OffsetMapping": ".hierarchical",
    "Overlay": ".hierarchical",
    "register_offset_mapping": ".hierarchical",
    "BSplineCurve": ".kernel",
    "BSplineSurface": ".kernel",
    "TrimmedSurface": ".kernel",
    "arc": ".kernel",
    "circle": ".kernel",
    "conic_arc": ".kernel",
    "conic_from_shoulder": ".kernel",
    "conic_through_point": ".kernel",
    "conic_type": ".kernel",
    "ellipse": ".kernel",
    "make_compatible": ".kernel",
    "ConstraintError": ".manipulation",
    "ConvergenceError": ".manipulation",
    "Curvature": ".manipulation",
    "Derivative": ".manipulation",
    "Dragger": ".manipulation",
    "Position": ".manipulation",
    "PreparedConstraints": ".manipulation",
    "Tangent": ".manipulation",
    "constrain": ".manipulation",
    "drag_point": ".manipulation",
    "drag_surface_point": ".manipulation",
    "FillQuality": ".topology",
    "GeneralizedSurface": ".topology",
    "HoleFill": ".topology",
    "HoleSide": ".topology",
    "Mesh": ".topology",
    "SPatch": ".topology",
    "SPatchConversion": ".topology",
    "biquadratic_patch": ".topology",
    "catmull_clark": ".topology",
    "convert_spatch": ".topology",
    "domain_vertices": ".topology",
    "doo_sabin": ".topology",
    "fill_hole": ".topology",
    "generalized_bicubic": ".topology",
    "generalized_biquadratic": ".topology",
    "measure_fill": ".topology",
    "read_obj": ".topology",
    "ribbon_patch": ".topology",
    "side_from_surface": ".topology",
    "spatch_curvatures": ".topology",
    "spatch_indices": ".topology",
    "spatch_to_surfaces": ".topology",
    "wachspress": ".topology",
    "wachspress_derivatives": ".topology",
    "wachspress_gradient": ".topology",
    "write_obj": ".topology",
}

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
    "TrimmedSurface",
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

_names, _dir = lazy_exports(__name__, _EXPORTS, globals())
#: The chapters and cross-cutting modules, served as attributes once imported on first use
#: (``occsurf.algorithms.quality.curvature_map`` works without importing ``quality`` first).
_SUBMODULES = ("kernel", "geometry", "construction", "fitting", "manipulation", "hierarchical", "topology",
               "quality", "lighting", "errors", "tolerances")


def __getattr__(name: str) -> object:
    if name in _SUBMODULES:
        import importlib

        return importlib.import_module(f"{__name__}.{name}")
    return _names(name)


def __dir__() -> list[str]:
    return sorted(set(_dir()) | set(_SUBMODULES))
