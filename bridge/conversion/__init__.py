"""Exact conversion between occsurf's splines and OpenCascade geometry and topology.

* :mod:`.splines` — :func:`to_occ`, :func:`from_occ` (bit-exact for B-splines; also any Geom
  curve/surface, ``TopoDS`` face/edge, build123d and cadquery objects), :func:`to_face`,
  :func:`to_edge`, :func:`to_cq_face`, :func:`to_cq_edge`, :func:`make_face`,
  :func:`make_edge`;
* :mod:`.spatch_export` — S-patches and generalized B-spline surfaces (course ch. 8) as sewn OCC
  shells and STEP files.
"""
