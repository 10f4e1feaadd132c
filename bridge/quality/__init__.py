"""occsurf.bridge.quality: assessing real models (course ch. 9 "Assessment", 11-2), measured on OCC
models and validated against OCC's own checks.

* :mod:`.continuity` — :func:`edge_continuity`: G0 gap, G1 angle, G2 (absolute and CATIA's
  relative %) and G3 jumps along every edge between two faces (shared edges of a shell, seams, and
  loose faces' edges matched geometrically as Rhino's ``GlobalEdgeContinuity`` does), with each
  edge's worst point and classification (:class:`EdgeReport`); threshold presets
  (:data:`PRESETS`: ``'catia'``, ``'class-a'``, ``'mechanical'``, :class:`Thresholds`) and
  :func:`check_edges` -> :class:`Violation`. Cross-validated against
  ``LocalAnalysis_SurfaceContinuity`` and ``BRepLib::ContinuityOfFaces`` in
  ``tests/bridge/test_continuity*.py``.
* :mod:`._engine` — the measures (G0, G1, cross curvature and its derivative, OCC's curvature gap)
  and the engine that evaluates them for every edge of a model at once.
* :mod:`._batch` — all faces and p-curves of a model evaluated in one vectorised pass.
* :mod:`._pairs` — which faces meet along which edge (topology, seams, geometric matching).
* :mod:`.check_files` — the per-file work of ``occsurf check``: the files its arguments name, the
  worker's job (read, assess, draw), re-runs without the piece that crashed the worker, the pages and JSON.

Names are imported lazily: importing this package does not load OCC.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from occsurf._lazy import lazy_exports

if TYPE_CHECKING:  # the lazily served names, for type checkers and IDEs
    from ._engine import (
        occ_fold,
        occ_gap,
    )
    from .continuity import (
        ContinuityResult,
        EdgeReport,
        Violation,
        check_edges,
        edge_continuity,
    )
    from .report import (
        QualityReport,
        check_model,
        summarize_model,
    )
    from .thresholds import PRESETS, Thresholds

_EXPORTS = {
    name: "continuity"
    for name in ("edge_continuity", "check_edges", "EdgeReport", "Violation", "ContinuityResult")
}
_EXPORTS.update({name: "thresholds" for name in ("Thresholds", "PRESETS")})
# OCC's own measures, written once in the engine (continuity did not define occ_gap: the lazy name
# raised AttributeError until the TYPE_CHECKING imports below made mypy look).
_EXPORTS.update({name: "_engine" for name in ("occ_fold", "occ_gap")})
_EXPORTS.update({name: "report" for name in ("check_model", "summarize_model", "QualityReport")})

__all__ = sorted(_EXPORTS)

__getattr__, __dir__ = lazy_exports(__name__, {k: f".{m}" for k, m in _EXPORTS.items()}, globals())
