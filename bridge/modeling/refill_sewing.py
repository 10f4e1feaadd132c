"""Sewing a fill into the model, checking the result and its STEP round trip.

:func:`sew_in_checked` sews the new faces into the hole of the model's kept faces
(:func:`_sew_in`, at a tolerance that covers the fill's G0 and the gap the model declares along the
hole: :func:`_sew_tolerance`), checks the result with ``BRepCheck_Analyzer`` and re-sews at smaller
tolerances where it is not valid; :func:`round_trip` writes the result to STEP and reads it back.
Part of the refill of :mod:`.refill`. :data:`SEW_GAP_FACTOR` is read at call time from this module
(patch it here, not on :mod:`.refill`).
"""

from __future__ import annotations

import io
from typing import Any

from OCP.BRep import BRep_Builder, BRep_Tool
from OCP.BRepBuilderAPI import BRepBuilderAPI_Sewing
from OCP.BRepCheck import BRepCheck_Analyzer
from OCP.IFSelect import IFSelect_ReturnStatus
from OCP.STEPControl import STEPControl_Reader, STEPControl_StepModelType, STEPControl_Writer
from OCP.TopoDS import TopoDS, TopoDS_Shell

from occsurf.algorithms import tolerances

from .. import _occ
from .joints import SEW_TOLERANCE, edge_face_map
from .refill_loop import SewnModel, hole_gap, model_faces

__all__ = ["sew_in_checked", "round_trip", "SEW_GAP_FACTOR"]

#: A fill is sewn in at this multiple of the larger of its achieved G0 and the hole edges' own
#: tolerance (and at least ``SEW_TOLERANCE``): the gap between a fill edge and a hole edge is at
#: most about their sum (:func:`_sew_in`).
SEW_GAP_FACTOR: float = 2.0

def round_trip(shape: Any, n_faces: int) -> bool:
    w = STEPControl_Writer()
    w.Transfer(shape, STEPControl_StepModelType.STEPControl_AsIs)
    bio = io.BytesIO()
    w.WriteStream(bio)
    bio.seek(0)
    r = STEPControl_Reader()
    if r.ReadStream("refill", bio) != IFSelect_ReturnStatus.IFSelect_RetDone:
        return False
    r.TransferRoots()
    return len(model_faces(r.OneShape())) == n_faces


def _free_edge_count(shape: Any) -> int:
    """Edges of ``shape`` that bound one face (degenerate edges apart)."""
    m = edge_face_map(shape)
    return sum(1 for i in range(1, m.Extent() + 1)
               if m.FindFromIndex(i).Size() == 1 and not BRep_Tool.Degenerated_s(TopoDS.Edge_s(m.FindKey(i))))


def sew_in_checked(model: SewnModel, removed: list[int], new_faces: list[Any], gap: float = 0.0) -> tuple[Any, bool]:
    """:func:`_sew_in` at its tolerance, and whether ``BRepCheck_Analyzer`` finds the result valid.

    Where it does not, the sewing is redone at half that tolerance, a quarter, ...
    (``FILL_RESEW_HALVINGS``, 6, times, never below the fill's own G0), and the first valid result that leaves no more free edges is kept:
    sewing at 1.4e-5 merged a corner of bearing face 208 (a neighbour of pairs [79, 84], [79, 197],
    [79, 199]) into a self-intersecting wire; at 7.1e-6 the same fills sew in valid, with the
    model's own 25 free edges (at 1e-6 three fill edges stay free). The hole's edges declare up to
    9.9e-6 there, but lie closer than that."""
    tol = _sew_tolerance(model, removed, gap)
    shape = _sew_in(model, removed, new_faces, gap, tol=tol)
    if BRepCheck_Analyzer(shape).IsValid():
        return shape, True
    free = _free_edge_count(shape)
    for _ in range(int(tolerances.FILL_RESEW_HALVINGS)):
        tol *= 0.5
        if tol <= float(gap):
            break
        cand = _sew_in(model, removed, new_faces, gap, tol=tol)
        if _free_edge_count(cand) <= free and BRepCheck_Analyzer(cand).IsValid():
            return cand, True
    return shape, False


def _sew_tolerance(model: SewnModel, removed: list[int], gap: float) -> float:
    """The tolerance :func:`_sew_in` sews at by default: ``max(SEW_TOLERANCE, SEW_GAP_FACTOR *
    max(gap, hole_gap))``."""
    return max(SEW_TOLERANCE, SEW_GAP_FACTOR * max(float(gap), hole_gap(model, removed)))


def _sew_in(model: SewnModel, removed: list[int], new_faces: list[Any], gap: float = 0.0,
            tol: float | None = None) -> Any:
    """The model without ``removed`` with ``new_faces`` sewn into the hole(s).

    The kept faces go in as one shell (their shared edges stay as they are: sewing works on the
    free edges), the new faces one by one, at the tolerance ``max(SEW_TOLERANCE, SEW_GAP_FACTOR *
    max(gap, hole_gap))``: ``gap`` is the fill's achieved G0, :func:`hole_gap` the model's own
    tolerance along the hole. At ``SEW_TOLERANCE`` alone a hole whose edges carry a larger
    tolerance (linkrods [17, 19]: 8.7e-5) sewed only in part: a fill edge was left free beside two
    hole edges and the neighbours' p-curves re-parametrised beyond their tolerance
    (``BRepCheck_InvalidCurveOnSurface`` / ``InvalidSameParameterFlag`` -> faces unorientable).
    ``tol`` overrides that tolerance (:func:`sew_in_checked`)."""
    sew = BRepBuilderAPI_Sewing(_sew_tolerance(model, removed, gap) if tol is None else tol)
    shell, b = TopoDS_Shell(), BRep_Builder()
    b.MakeShell(shell)
    for k, f in enumerate(model.faces):
        if k not in removed:
            b.Add(shell, f)
    sew.Add(shell)
    for f in new_faces:
        sew.Add(f)
    with _occ.kernel_errors("sewing the fill in"):
        sew.Perform()
    return sew.SewedShape()


