"""occsurf.bridge: the only place OpenCascade (OCP), cadquery and build123d are touched.

Exact conversion between :mod:`algorithms` splines and ``Geom_BSplineCurve``/``Geom_BSplineSurface``
(and any OCC curve, surface, face, edge, build123d or cadquery object), STEP/IGES exchange, validation
of our evaluation against OCC's, and the ``occsurf`` command line.

Names are imported lazily: ``import bridge`` does not load OCC until a function is used.
"""

from __future__ import annotations

import importlib
from typing import Any

_EXPORTS = {
    "to_occ": "convert",
    "from_occ": "convert",
    "to_face": "convert",
    "to_edge": "convert",
    "to_cq_face": "convert",
    "to_cq_edge": "convert",
    "is_reversed": "convert",
    "surface_deviation": "validate",
    "curve_deviation": "validate",
    "roundtrip_deviation": "validate",
    "read_step": "exchange",
    "write_step": "exchange",
    "read_iges": "exchange",
    "write_iges": "exchange",
    "ImportedModel": "exchange",
    "ImportedFace": "exchange",
    "ImportedEdge": "exchange",
}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str) -> Any:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'bridge' has no attribute {name!r}")
    value = getattr(importlib.import_module(f".{module}", __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(list(globals()) + __all__)
