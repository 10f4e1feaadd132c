"""Our results measured against OpenCascade's on the same input.

* :mod:`.deviation` — :func:`surface_deviation`, :func:`curve_deviation` (our evaluation, derivatives
  and curvature against OCC's ``D2``/``D3``/``GeomLProp``) and :func:`roundtrip_deviation`;
* :mod:`.inspect` — :func:`inspect_model`: one :class:`FaceReport` per face of an imported model
  (type, degrees, poles, flags, and the deviation of our evaluation from OCC's), what
  ``occsurf inspect`` prints;
* :mod:`.files` — the same per STEP/IGES file: :class:`~.files.FileReport`, :func:`~.files.inspect_files`
  and the worker job of ``occsurf inspect``, :func:`~.files.inspect_job`.
"""
