"""Operations on OpenCascade models built from the algorithms.

* :mod:`.fill` — :func:`fill_model`: find the holes of a model (free edge loops), fill each with the
  G1 n-sided fill of course §8-3 and compare with OCC's ``BRepOffsetAPI_MakeFilling``; the
  topology helpers it uses, :func:`sew_faces`, :func:`edge_face_map` and :func:`neighbour_face`.
"""
