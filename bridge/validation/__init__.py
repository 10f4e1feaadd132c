"""Our results measured against OpenCascade's on the same input.

* :mod:`.deviation` — :func:`surface_deviation`, :func:`curve_deviation` (our evaluation, derivatives
  and curvature against OCC's ``D2``/``D3``/``GeomLProp``) and :func:`roundtrip_deviation`.
"""
