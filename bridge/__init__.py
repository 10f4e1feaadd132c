"""occsurf.bridge: the only place OpenCascade (OCP), cadquery and build123d are touched.

Rooms:

==============  ===========================================================================
``conversion``  exact conversion of :mod:`occsurf.algorithms` splines to and from OCC geometry,
                faces and edges (and build123d/cadquery objects); S-patch export
``exchange``    STEP/IGES reading and lossless writing, hierarchical STEP + sidecar
``validation``  our evaluation and curvature against OCC's on the same input
``modeling``    operations on OCC models: hole filling of shells (course §8-3)
``rendering``   PNG pictures of surfaces; per-pixel pictures under Warn's lights (course ch. 10)
``quality``     assessment of real models: continuity across edges (course ch. 9)
``cli``         the ``occsurf`` command line, one module per command
==============  ===========================================================================

:mod:`.isolation` runs a job on untrusted items in a worker process (a crash or a hang inside OCC
costs one item, not the command); :mod:`.messages` formats any error as one line.

:mod:`._occ` holds the few helpers every room shares (OCC arrays, knots + multiplicities, kernel
limits, OCC exceptions as :class:`~occsurf.algorithms.errors.KernelError`).

Names are imported lazily: ``import occsurf.bridge`` does not load OCC until a function is used.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from occsurf._lazy import lazy_exports

if TYPE_CHECKING:  # the lazily served names, for type checkers and IDEs
    from ._occ import (
        quiet_messages,
        silence_messages,
    )
    from .conversion.shapes import (
        as_curve,
        as_edge,
        as_faces,
        as_shape,
    )
    from .conversion.splines import (
        from_occ,
        is_reversed,
        to_cq_edge,
        to_cq_face,
        to_edge,
        to_face,
        to_occ,
    )
    from .exchange.convert import (
        ConversionReport,
        convert,
    )
    from .exchange.object_import import (
        model_from_object,
    )
    from .exchange.objects import (
        to_build123d,
        to_cadquery,
    )
    from .exchange.step_iges import (
        ImportedEdge,
        ImportedFace,
        ImportedModel,
        read_iges,
        read_step,
        write_iges,
        write_step,
    )
    from .exchange.xcaf import (
        AssemblyNode,
    )
    from .modeling.fill import (
        FillResult,
        HoleReport,
        fill_model,
    )
    from .quality.continuity import (
        EdgeReport,
        Violation,
        check_edges,
        edge_continuity,
    )
    from .quality.thresholds import PRESETS, Thresholds
    from .rendering.lighting import (
        render_lit,
        render_model_lit,
        render_surfaces_lit,
    )
    from .validation.deviation import (
        curve_deviation,
        roundtrip_deviation,
        surface_deviation,
    )
    from .validation.inspect import (
        FaceReport,
        inspect_model,
    )

_EXPORTS = {
    "to_occ": "conversion.splines",
    "from_occ": "conversion.splines",
    "to_face": "conversion.splines",
    "to_edge": "conversion.splines",
    "to_cq_face": "conversion.splines",
    "to_cq_edge": "conversion.splines",
    "is_reversed": "conversion.splines",
    "surface_deviation": "validation.deviation",
    "curve_deviation": "validation.deviation",
    "roundtrip_deviation": "validation.deviation",
    "inspect_model": "validation.inspect",
    "FaceReport": "validation.inspect",
    "read_step": "exchange.step_iges",
    "write_step": "exchange.step_iges",
    "read_iges": "exchange.step_iges",
    "write_iges": "exchange.step_iges",
    "ImportedModel": "exchange.step_iges",
    "ImportedFace": "exchange.step_iges",
    "ImportedEdge": "exchange.step_iges",
    "AssemblyNode": "exchange.xcaf",
    "convert": "exchange.convert",
    "ConversionReport": "exchange.convert",
    "to_build123d": "exchange.objects",
    "to_cadquery": "exchange.objects",
    "model_from_object": "exchange.object_import",
    "fill_model": "modeling.fill",
    "FillResult": "modeling.fill",
    "HoleReport": "modeling.fill",
    "as_shape": "conversion.shapes",
    "as_faces": "conversion.shapes",
    "as_edge": "conversion.shapes",
    "as_curve": "conversion.shapes",
    "quiet_messages": "_occ",
    "silence_messages": "_occ",
    "edge_continuity": "quality.continuity",
    "check_edges": "quality.continuity",
    "EdgeReport": "quality.continuity",
    "Thresholds": "quality.thresholds",
    "Violation": "quality.continuity",
    "PRESETS": "quality.thresholds",
    "render_lit": "rendering.lighting",
    "render_model_lit": "rendering.lighting",
    "render_surfaces_lit": "rendering.lighting",
}

__all__ = sorted(_EXPORTS)

__getattr__, __dir__ = lazy_exports(__name__, {k: f".{m}" for k, m in _EXPORTS.items()}, globals())
