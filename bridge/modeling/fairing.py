"""Fair faces of a model: wiggles out by the least curvature variation (issue 29, item 3).

:func:`fair_faces` runs :func:`occsurf.algorithms.manipulation.fair_surface` on each face asked for
(a B-spline face; other surfaces have no wiggles to fair and are refused with the reason), over the
face's UV box, holding the outer pole rows where the box reaches the surface's boundary and every
pole whose support leaves the box; the faired surface goes back on the face's own wires as in
:mod:`.matching` (same edges and neighbours, p-curves re-projected, tolerances set by
``SameParameter``), and the model is checked by ``BRepCheck_Analyzer``.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

from OCP.BRep import BRep_Tool
from OCP.BRepCheck import BRepCheck_Analyzer
from OCP.BRepTools import BRepTools, BRepTools_ReShape
from OCP.Geom import Geom_BSplineSurface
from OCP.TopAbs import TopAbs_FACE
from OCP.TopExp import TopExp
from OCP.TopTools import TopTools_IndexedMapOfShape

from occsurf.algorithms.errors import InvalidGeometryError, OccsurfError
from occsurf.algorithms.kernel.surface import BSplineSurface
from occsurf.algorithms.manipulation import fair_surface

from .. import _occ
from ..conversion.splines import from_occ
from .matching import _replace_surface
from .refill_loop import SewnModel

__all__ = ["FaceFairing", "fair_faces"]


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


@_occ.quiet_messages()
def fair_faces(shape: Any, faces: list[int], *, tol: float, hold: str = "G1"
               ) -> tuple[list[FaceFairing], Any, list[int]]:
    """Fair ``faces`` of ``shape`` (numbered as ``occsurf check`` numbers them) within ``tol``.

    Returns
    -------
    (list of FaceFairing, TopoDS_Shape, list of int)
        Per face what was done; the model (sewn; faired faces replaced); for each input face its
        number in the returned model.
    """
    model = SewnModel(shape)
    n = len(model.faces)
    out_reports: list[FaceFairing] = []
    rs = BRepTools_ReShape()
    replaced: dict[int, Any] = {}
    for i in faces:
        if not 0 <= int(i) < n:
            raise InvalidGeometryError(f"faces: face {i} is out of range: the model has {n} faces (0..{n - 1})")
        f = model.faces[int(i)]
        if not isinstance(BRep_Tool.Surface_s(f), Geom_BSplineSurface):
            out_reports.append(FaceFairing(int(i), "refused", reason=f"face {i} is not a B-spline surface "
                                           f"({type(BRep_Tool.Surface_s(f)).__name__}): nothing to fair"))
            continue
        conv = from_occ(f, trims=False)
        assert isinstance(conv, BSplineSurface)
        u0, u1, v0, v1 = BRepTools.UVBounds_s(f)
        (a0, a1), (b0, b1) = conv.domain
        region = ((max(u0, a0), min(u1, a1)), (max(v0, b0), min(v1, b1)))
        try:
            res = fair_surface(conv, region, hold=hold, tol=tol)
        except OccsurfError as err:
            out_reports.append(FaceFairing(int(i), "refused", reason=str(err)))
            continue
        if res.surface is conv or res.wiggles_after >= res.wiggles_before:
            out_reports.append(FaceFairing(int(i), "unchanged" if res.wiggles_before == 0 else "refused",
                                           res.wiggles_before, res.wiggles_before, 0.0,
                                           None if res.wiggles_before == 0 else res.reason or "no fairer within tol"))
            continue
        etol = max(BRep_Tool.Tolerance_s(f), res.max_deviation, 1e-7)
        new = _replace_surface(f, res.surface, etol)
        rs.Replace(f, new)
        replaced[int(i)] = new
        out_reports.append(FaceFairing(int(i), "faired", res.wiggles_before, res.wiggles_after, res.max_deviation,
                                       res.reason))
    with _occ.kernel_errors("replacing the faired faces"):
        out = rs.Apply(model.shape)
    if replaced and not BRepCheck_Analyzer(out).IsValid():
        for r in out_reports:
            if r.status == "faired":
                r.status, r.reason = "refused", "the faired model is not valid (BRepCheck); kept the original"
        out = model.shape
        replaced = {}
    index = TopTools_IndexedMapOfShape()
    TopExp.MapShapes_s(out, TopAbs_FACE, index)
    numbering = [index.FindIndex(replaced.get(k, f)) - 1 for k, f in enumerate(model.faces)]
    return out_reports, out, numbering
