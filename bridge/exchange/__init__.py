"""STEP and IGES exchange through OpenCascade's translators.

* :mod:`.step_iges` — :func:`read_step`, :func:`read_iges` (an :class:`ImportedModel` of converted
  faces and free edges), :func:`write_step`, :func:`write_iges` (17 significant digits, lossless);
* :mod:`.occ_io` — the translator session (messages, static parameters) and the export pipeline;
* :mod:`.files` — file-level checks before OCC parses anything, and atomic writes;
* :mod:`.hierarchical_io` — hierarchical splines (course §5-17) as flat STEP plus an editable sidecar;
* :mod:`.spatch_io` — S-patches (course §8-2) as one sewn shell in STEP, and read back;
* :mod:`.reading` — which files a path names, the format of a file (one rule), reading a model;
* :mod:`.convert` — STEP <-> IGES conversion that reports what it could not carry.
"""
