"""Fair faces of a model: wiggles out by the least curvature variation (issue 29, item 3).

:func:`fair_faces` runs :func:`occsurf.algorithms.manipulation.fair_surface` on each face asked for
(a B-spline face; other surfaces have no wiggles to fair and are refused with the reason), over the
face's UV box, holding the outer pole rows where the box reaches the surface's boundary and every
pole whose support leaves the box; the faired surface goes back on the face's own wires as in
:func:`.model_edits.replace_surface` (same edges and neighbours, p-curves re-projected, tolerances set by
``SameParameter``), and the model is checked by ``BRepCheck_Analyzer``.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

from OCP.BRep import BRep_Tool
from OCP.BRepCheck import BRepCheck_Analyzer
from OCP.BRepTools import BRepTools
from OCP.Geom import Geom_BSplineSurface

from occsurf.algorithms.errors import OccsurfError
from occsurf.algorithms.manipulation import fair_surface

from .. import _occ
from .model_edits import ModelEdits

__all__ = ["FaceFairing", "fair_faces", "fair_edited"]


@dataclass
class FaceFairing:
    """One face: ``status`` ``'faired'``, ``'unchanged'`` (no wiggle to take out) or ``'refused'``."""

    face: int
    status: str
    wiggles_before: int = 0
    wiggles_after: int = 0
    max_deviation: float = 0.0
    reason: str | None = None

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


def fair_edited(edits: ModelEdits, faces: list[int], *, tol: float, hold: str = "G1") -> list[FaceFairing]:
    """Fair ``faces`` of ``edits`` within ``tol``, each face replaced when it is faired and valid
    (``BRepCheck_Analyzer`` on the face); one :class:`FaceFairing` per face."""
    out_reports: list[FaceFairing] = []
    for i in faces:
        i = edits.index(i, "faces")
        f = edits.faces[i]
        if not isinstance(BRep_Tool.Surface_s(f), Geom_BSplineSurface):
            out_reports.append(FaceFairing(i, "refused", reason=f"face {i} is not a B-spline surface "
                                           f"({type(BRep_Tool.Surface_s(f)).__name__}): nothing to fair"))
            continue
        conv, _ = edits.surface(i)
        u0, u1, v0, v1 = BRepTools.UVBounds_s(f)
        (a0, a1), (b0, b1) = conv.domain
        region = ((max(u0, a0), min(u1, a1)), (max(v0, b0), min(v1, b1)))
        try:
            res = fair_surface(conv, region, hold=hold, tol=tol)
        except OccsurfError as err:
            out_reports.append(FaceFairing(i, "refused", reason=str(err)))
            continue
        if res.surface is conv or res.wiggles_after >= res.wiggles_before:
            out_reports.append(FaceFairing(i, "unchanged" if res.wiggles_before == 0 else "refused",
                                           res.wiggles_before, res.wiggles_before, 0.0,
                                           None if res.wiggles_before == 0 else res.reason or "no fairer within tol"))
            continue
        etol = max(BRep_Tool.Tolerance_s(f), res.max_deviation, 1e-7)
        if not edits.replace({i: res.surface}, etol):
            out_reports.append(FaceFairing(i, "refused", res.wiggles_before, res.wiggles_before, 0.0,
                                           "the faired face is not valid (BRepCheck); kept the original"))
            continue
        out_reports.append(FaceFairing(i, "faired", res.wiggles_before, res.wiggles_after, res.max_deviation,
                                       res.reason))
    return out_reports


@_occ.quiet_messages()
def fair_faces(shape: Any, faces: list[int], *, tol: float, hold: str = "G1"
               ) -> tuple[list[FaceFairing], Any, list[int]]:
    """Fair ``faces`` of ``shape`` (numbered as ``occsurf check`` numbers them) within ``tol``.

    Returns
    -------
    (list of FaceFairing, TopoDS_Shape, list of int)
        Per face what was done; the model (sewn; faired faces replaced; the sewn input with every
        fairing refused when ``BRepCheck_Analyzer`` finds the whole model invalid); for each input
        face its number in the returned model.
    """
    edits = ModelEdits(shape)
    reports = fair_edited(edits, faces, tol=tol, hold=hold)
    out, numbering = edits.shape()
    if any(r.status == "faired" for r in reports) and not BRepCheck_Analyzer(out).IsValid():
        for r in reports:
            if r.status == "faired":
                r.status, r.reason = "refused", "the faired model is not valid (BRepCheck); kept the original"
        out, numbering = edits.model.shape, list(range(len(edits)))
    return reports, out, numbering
