"""A model sewn once whose faces are given new surfaces one after another, on their own wires.

:class:`ModelEdits` is what a sequence of matches and fairings works on (``occsurf repair``: one
per edge that breaks the preset, hundreds on a real model). Sewing the model, converting its faces
and checking the whole shape after every change cost more than the changes themselves (the OCCT
bearing: 0.04 s to sew, for each of ~1000 attempts); here the model is sewn once, each face's
surface converted once (and a replaced face's surface is the one given, exact, not read back from
OCC), and a replacement is checked by ``BRepCheck_Analyzer`` on the new face alone: its wires are
the old ones, so the shell's topology does not change. :meth:`ModelEdits.shape` makes the model
once at the end (``BRepTools_ReShape``).

A new face is the new surface bounded by the *old wires* (``BRep_Builder``; ``ShapeFix_Edge`` adds
the p-curves on the new surface, ``BRepLib::SameParameter`` sets the edges' tolerances), so the
topology and the neighbours are untouched. The edges are shared with the neighbours: a replacement
found invalid is undone on them too (the p-curves on the new surface removed, the edge and vertex
tolerances set back).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from OCP.BRep import BRep_Builder, BRep_Tool
from OCP.BRepBuilderAPI import BRepBuilderAPI_Copy
from OCP.BRepCheck import BRepCheck_Analyzer
from OCP.BRepLib import BRepLib
from OCP.BRepTools import BRepTools_ReShape
from OCP.Geom import Geom_BSplineSurface
from OCP.ShapeFix import ShapeFix_Edge, ShapeFix_ShapeTolerance
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_FORWARD, TopAbs_REVERSED, TopAbs_VERTEX, TopAbs_WIRE
from OCP.TopExp import TopExp, TopExp_Explorer
from OCP.TopLoc import TopLoc_Location
from OCP.TopoDS import TopoDS, TopoDS_Face
from OCP.TopTools import TopTools_IndexedMapOfShape

from occsurf.algorithms.errors import ArgumentTypeError, InvalidGeometryError
from occsurf.algorithms.kernel.surface import BSplineSurface
from occsurf.algorithms.kernel.trimmed import TrimmedSurface
from occsurf.algorithms.manipulation.matching import surface_change

from .. import _occ
from ..conversion.splines import from_occ, to_occ
from .refill_loop import SewnModel

__all__ = ["ModelEdits", "replace_surface", "SAME_PARAMETER_TOLERANCE"]


#: Tolerance of ``BRepLib::SameParameter`` on the sewn model (``Precision::Confusion``). Sewing
#: keeps each face's p-curve as it was for the face's own edge, parameterised for that edge's
#: curve, not for the sewn edge's: the report's topological measure, which compares the two faces
#: at equal edge parameters, then sees the edge tolerance as an offset along the edge. On the OCCT
#: bearing sewing alone raised the worst smooth G1 angle it measures from 0.247 to 0.328 deg;
#: re-parameterised, 0.249 deg (0.06 s; the model stays valid).
SAME_PARAMETER_TOLERANCE: float = 1e-7


def replace_surface(face: Any, surface: BSplineSurface | Any, tol: float) -> Any:
    """A face on ``surface`` (ours, or an OCC ``Geom_Surface``) bounded by ``face``'s own wires
    (same edges), oriented as ``face``.

    The face is made by ``BRep_Builder`` with the wires as the old face holds them (their stored
    orientations): ``BRepBuilderAPI_MakeFace(surface, wire, inside)`` re-orients the wire and the
    face then fails ``BRepCheck`` with ``BadOrientationOfSubshape``. Each edge gets its p-curve on
    the new surface by projection (``ShapeFix_Edge::FixAddPCurve``); ``BRepLib::SameParameter``
    then sets the edge tolerances to what the new surface needs. The edges are changed in place
    (they are the neighbours' edges too)."""
    geom = to_occ(surface) if isinstance(surface, BSplineSurface) else surface
    fwd = TopoDS.Face_s(face.Oriented(TopAbs_FORWARD))
    b = BRep_Builder()
    new = TopoDS_Face()
    with _occ.kernel_errors("rebuilding the face on its new surface"):
        b.MakeFace(new, geom, TopLoc_Location(), BRep_Tool.Tolerance_s(fwd))
        ex = TopExp_Explorer(fwd, TopAbs_WIRE)
        while ex.More():
            b.Add(new, ex.Current())
            ex.Next()
        fix = ShapeFix_Edge()
        ex = TopExp_Explorer(new, TopAbs_EDGE)
        while ex.More():
            e = TopoDS.Edge_s(ex.Current())
            ex.Next()
            if not BRep_Tool.Degenerated_s(e):
                fix.FixAddPCurve(e, new, False, tol)
        BRepLib.SameParameter_s(new, tol, True)
    return TopoDS.Face_s(new.Reversed()) if face.Orientation() == TopAbs_REVERSED else new


def _sub_shapes(shape: Any, kind: Any) -> list[Any]:
    m = TopTools_IndexedMapOfShape()
    TopExp.MapShapes_s(shape, kind, m)
    return [m.FindKey(k) for k in range(1, m.Extent() + 1)]


class ModelEdits:
    """A model's faces, sewn once, given new surfaces one after another (course ch. 3-4 on models).

    Faces are numbered as ``occsurf check`` / ``inspect`` number them (:func:`.refill_loop.
    model_faces`) throughout, whatever was replaced. ``version[i]`` counts the replacements of face
    ``i`` (for callers that cache what they measured on it).
    """

    @_occ.quiet_messages()
    def __init__(self, shape: Any) -> None:
        from ..conversion.shapes import as_shape

        # a copy: sewing keeps the faces it does not change, and a replacement changes their
        # edges in place (the caller's model must not change)
        with _occ.kernel_errors("copying the model"):
            copy = BRepBuilderAPI_Copy(as_shape(shape, "shape"), True, False).Shape()
        self.model = SewnModel(copy)
        with _occ.kernel_errors("making the sewn edges same-parameter"):
            BRepLib.SameParameter_s(self.model.shape, SAME_PARAMETER_TOLERANCE, True)
        self.faces: list[Any] = list(self.model.faces)
        self.size: float = self.model.size
        self.version: list[int] = [0] * len(self.faces)
        self._surfaces: dict[int, tuple[BSplineSurface, str | None]] = {}
        self._originals: dict[int, BSplineSurface] = {}
        self._edges: dict[int, list[Any]] = {}
        self._edge_faces: dict[int, list[int]] = {}

    def __len__(self) -> int:
        return len(self.faces)

    def index(self, value: object, name: str) -> int:
        """``value`` as a face number of this model, or a one-line error naming ``name``."""
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
            raise ArgumentTypeError(f"{name}: expected a face number, got {type(value).__name__}")
        i, n = int(value), len(self.faces)
        if not 0 <= i < n:
            raise InvalidGeometryError(f"{name}: face {i} is out of range: the model has {n} faces (0..{n - 1})")
        return i

    def surface(self, i: int) -> tuple[BSplineSurface, str | None]:
        """Face ``i``'s surface as ours (untrimmed; a non-B-spline surface converted exactly on the
        face's UV box) and what it was converted from (``None``: it is a B-spline). A replaced
        face's surface is the one it was given."""
        if i not in self._surfaces:
            f = self.faces[i]
            geom = BRep_Tool.Surface_s(f)
            conv = from_occ(f, trims=False)
            surface = conv.surface if isinstance(conv, TrimmedSurface) else conv
            assert isinstance(surface, BSplineSurface)
            converted = None if isinstance(geom, Geom_BSplineSurface) else type(geom).__name__.replace("Geom_", "")
            self._surfaces[i] = (surface, converted)
            self._originals.setdefault(i, surface)
        return self._surfaces[i]

    def change(self, i: int, surface: BSplineSurface | None = None) -> float:
        """How far ``surface`` (default: face ``i``'s surface now) lies from face ``i``'s surface
        before any replacement, as ``match_surface`` measures ``max_change``
        (:func:`~occsurf.algorithms.manipulation.matching.surface_change`). A surface that went
        through several changes is measured against the first, so that their sum stays within a
        limit."""
        now = self.surface(i)[0]  # (also keeps the face's first surface)
        original = self._originals[i]
        s = now if surface is None else surface
        return 0.0 if s is original else surface_change(original, s)

    def edges(self, i: int) -> list[Any]:
        """The edges of face ``i``, each once, degenerated ones left out (a replaced face keeps them)."""
        if i not in self._edges:
            out: list[Any] = []
            for e in _sub_shapes(self.model.faces[i], TopAbs_EDGE):
                e = TopoDS.Edge_s(e)
                if not BRep_Tool.Degenerated_s(e):
                    out.append(e)
            self._edges[i] = out
        return self._edges[i]

    def neighbours(self, edge: Any, i: int) -> list[int]:
        """The faces other than ``i`` that ``edge`` bounds.

        The faces of each edge are looked up once (by the edge's index in the model's edge-face map):
        a replacement keeps the edges and their faces' numbers, and a repair of the OCCT bearing
        asked 4091 times (2.5 s of its matching, listing the faces anew each time)."""
        idx = self.model.e2f.FindIndex(edge)
        if idx not in self._edge_faces:
            self._edge_faces[idx] = [k for f in self.model.edge_faces(edge)
                                     if (k := self.model.index_of(f)) is not None]
        return [k for k in self._edge_faces[idx] if k != i]

    def shared_edges(self, i: int, j: int) -> list[Any]:
        """The edges faces ``i`` and ``j`` share."""
        return [e for e in self.edges(i) if j in self.neighbours(e, i)]

    def replace(self, surfaces: dict[int, BSplineSurface], tol: float, *, geoms: dict[int, Any] | None = None,
                keep_invalid: bool = False) -> bool:
        """Give faces ``surfaces`` (face -> new surface) on their own wires, all or none.

        Each new face is checked by ``BRepCheck_Analyzer``; when one is invalid and not
        ``keep_invalid``, every change is undone (faces, the shared edges' p-curves on the new
        surfaces and their tolerances) and ``False`` returned. ``geoms``: the OCC surfaces of
        ``surfaces`` where the caller has made them already.
        """
        geoms = dict(geoms or {})
        saved_edges: dict[Any, tuple[Any, float]] = {}
        saved_vertices: dict[Any, tuple[Any, float]] = {}
        for i in surfaces:
            for e in _sub_shapes(self.faces[i], TopAbs_EDGE):
                saved_edges.setdefault(e.TShape(), (e, BRep_Tool.Tolerance_s(TopoDS.Edge_s(e))))
            for v in _sub_shapes(self.faces[i], TopAbs_VERTEX):
                saved_vertices.setdefault(v.TShape(), (v, BRep_Tool.Tolerance_s(TopoDS.Vertex_s(v))))
        new: dict[int, Any] = {}
        valid = True
        for i in surfaces:
            self.surface(i)  # the face's first surface kept (self.change measures from it)
        for i, s in surfaces.items():
            geoms.setdefault(i, to_occ(s))
            new[i] = replace_surface(self.faces[i], geoms[i], tol)
            valid = valid and bool(BRepCheck_Analyzer(new[i]).IsValid())
        if not valid and not keep_invalid:
            b, fix = BRep_Builder(), ShapeFix_ShapeTolerance()
            for i, f in new.items():
                for e in _sub_shapes(f, TopAbs_EDGE):
                    e = TopoDS.Edge_s(e)
                    if not BRep_Tool.Degenerated_s(e):
                        b.UpdateEdge(e, None, geoms[i], TopLoc_Location(), 0.0)  # the p-curve(s) removed
            for e, t in saved_edges.values():
                fix.SetTolerance(e, t, TopAbs_EDGE)
            for v, t in saved_vertices.values():
                fix.SetTolerance(v, t, TopAbs_VERTEX)
            return False
        for i, f in new.items():
            self.faces[i] = f
            self._surfaces[i] = (surfaces[i], None)
            self.version[i] += 1
        return valid

    def shape(self) -> tuple[Any, list[int]]:
        """The model with the replaced faces, and for each face its number in it (``-1``: lost)."""
        rs = BRepTools_ReShape()
        for f0, f in zip(self.model.faces, self.faces):
            if f is not f0:
                rs.Replace(f0, f)
        with _occ.kernel_errors("replacing the changed faces"):
            out = rs.Apply(self.model.shape)
        index = TopTools_IndexedMapOfShape()
        TopExp.MapShapes_s(out, TopAbs_FACE, index)
        return out, [index.FindIndex(f) - 1 for f in self.faces]
