"""Which faces a report puts first and pictures, and the ``--pictures`` choices (issue 28).

Standard library only: the command line imports these names to build its parser without loading
NumPy or OpenCascade, and both the report (:mod:`.report`) and its page (:mod:`.html`) rank faces
with :func:`face_scores`.
"""

from __future__ import annotations

from typing import Any

__all__ = ["PICTURE_CHOICES", "WORST_FACES", "face_scores"]

#: ``occsurf check --pictures``: ``worst`` (the default) draws the model pictures and the
#: :data:`WORST_FACES` worst faces' (:func:`~occsurf.bridge.quality.report.worst_faces`), ``all``
#: every face's, ``none`` no PNG (the page keeps its tables and 3-D view).
PICTURE_CHOICES: tuple[str, ...] = ("worst", "all", "none")
#: Faces whose pictures ``--pictures worst`` draws.
WORST_FACES: int = 10


def face_scores(faces: list[dict[str, Any]], violations: list[dict[str, Any]]) -> dict[int, float]:
    """How bad each face is, for the face table's order and the ``--pictures worst`` choice (report
    JSON rows): unevaluated faces first, then by their flags plus the threshold violations of their
    edges, then by the largest G1 angle at an adjacent edge."""
    touching: dict[int, int] = {}
    for v in violations:
        for i in v.get("faces") or ():
            touching[int(i)] = touching.get(int(i), 0) + 1
    return {int(f["index"]): (1e9 if f.get("error") else 0.0)
            + 1e6 * (len(f.get("flags") or ()) + touching.get(int(f["index"]), 0)) + float(f.get("worst_g1_deg") or 0.0)
            for f in faces}
