"""Exact conversion between occsurf's splines and OpenCascade geometry and topology.

* :mod:`.splines` — :func:`to_occ`, :func:`from_occ` (bit-exact for B-splines; also any Geom
  curve/surface, ``TopoDS`` face/edge, build123d and cadquery objects), :func:`to_face`,
  :func:`to_edge`, :func:`to_cq_face`, :func:`to_cq_edge`, :func:`make_face`,
  :func:`make_edge`;
* :mod:`.trimming` — trimmed faces both ways: ``from_occ(face)`` gives an
  :class:`occsurf.algorithms.TrimmedSurface` (surface + loops of p-curves) for a face that is not
  the natural rectangle of its surface, ``make_face`` / ``to_face`` rebuild the face from it;
* :mod:`.spatch_export` — S-patches and generalized B-spline surfaces (course ch. 8) as sewn OCC
  shells (their STEP files: :mod:`occsurf.bridge.exchange.spatch_io`);
* :mod:`.occ_evaluators` — OCC faces and p-curves evaluated many points at once in OCC's own
  parametrisation (our B-splines, closed forms for elementary surfaces, OCC point by point for the
  rest): the continuity check's and the refill's.
"""
