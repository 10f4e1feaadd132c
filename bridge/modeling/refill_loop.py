"""The hole in a sewn model: its loop of edges, their neighbours, how faces meet along them.

:class:`SewnModel` sews a model's faces once (faces numbered as ``inspect`` numbers them:
:func:`model_faces`); :func:`hole_loop` finds the loop of edges the removed faces leave, each edge's
neighbour (the kept face on its other side) and the removed face it bounded; :func:`face_components`
groups removed faces into edge-connected sets, one hole each; :func:`hole_gap` is the gap the model
itself declares along a hole (its edges' tolerance). Along an edge, :func:`normals_on` samples a
face's normals on the edge's p-curve (at :func:`edge_params`) and :func:`joint_angle` says at which
angle two faces meet: within :data:`G1_EDGE_DEG` the joint counts as tangent-continuous, and a
sharp edge between two removed faces (:func:`crease_note`) explains why a hole is refused.
Part of the refill of :mod:`.refill` (course §8-3 on real, trimmed models).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from OCP.Bnd import Bnd_Box
from OCP.BRep import BRep_Builder, BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Curve
from OCP.BRepBndLib import BRepBndLib
from OCP.BRepBuilderAPI import BRepBuilderAPI_Sewing
from OCP.BRepTools import BRepTools_WireExplorer
from OCP.GeomLProp import GeomLProp_SLProps
from OCP.gp import gp_Pnt, gp_Vec
from OCP.ShapeAnalysis import ShapeAnalysis_FreeBounds
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_REVERSED, TopAbs_WIRE
from OCP.TopExp import TopExp, TopExp_Explorer
from OCP.TopoDS import TopoDS, TopoDS_Shell
from OCP.TopTools import TopTools_IndexedMapOfShape

from occsurf.algorithms import tolerances
from occsurf.algorithms.errors import InvalidGeometryError

from .. import _occ
from .joints import SEW_TOLERANCE, edge_face_map

__all__ = ["SewnModel", "model_faces", "hole_loop", "hole_gap", "face_components", "edge_params", "normals_on",
           "joint_angle", "crease_note", "G1_EDGE_DEG"]

#: An edge counts as tangent-continuous in the original model (and the fill is asked to be G1 to
#: the neighbour there) when the removed face and the neighbour meet within this angle (degrees).
G1_EDGE_DEG: float = 1.0


def model_faces(shape: Any) -> list[Any]:
    """The faces of ``shape`` numbered as ``inspect`` numbers them (each face once)."""
    m = TopTools_IndexedMapOfShape()
    TopExp.MapShapes_s(shape, TopAbs_FACE, m)
    return [TopoDS.Face_s(m.FindKey(i)) for i in range(1, m.Extent() + 1)]


class SewnModel:
    """The model's faces sewn once; original face ``i`` -> sewn face; the edge -> faces map.

    ``shape``: a ``TopoDS_Shape``, a model read by :mod:`occsurf.bridge.exchange` or a build123d /
    cadquery object (:func:`occsurf.bridge.conversion.shapes.as_shape`; anything else is an
    ``InvalidGeometryError`` naming it)."""

    @_occ.quiet_messages()
    def __init__(self, shape: Any) -> None:
        from ..conversion.shapes import as_shape

        self.original = model_faces(as_shape(shape, "shape"))
        sew = BRepBuilderAPI_Sewing(SEW_TOLERANCE)
        for f in self.original:
            sew.Add(f)
        with _occ.kernel_errors("sewing"):
            sew.Perform()
        self.shape = sew.SewedShape()
        self.faces = [TopoDS.Face_s(sew.Modified(f)) if sew.IsModified(f) else f for f in self.original]
        self.e2f = edge_face_map(self.shape)
        box = Bnd_Box()
        BRepBndLib.Add_s(self.shape, box)
        self.size = math.sqrt(box.SquareExtent()) if not box.IsVoid() else 1.0

    def edge_faces(self, edge: Any) -> list[Any]:
        idx = self.e2f.FindIndex(edge)
        if idx == 0:
            return []
        return [TopoDS.Face_s(f) for f in self.e2f.FindFromIndex(idx)]

    def adjacent_pairs(self, indices: list[int]) -> list[tuple[int, int]]:
        """Pairs ``(i, j)``, ``i < j``, both in ``indices``, of faces sharing an edge."""
        index = set(indices)
        pairs = set()
        for i in index:
            ex = TopExp_Explorer(self.faces[i], TopAbs_EDGE)
            while ex.More():
                for g in self.edge_faces(ex.Current()):
                    j = self.index_of(g)
                    if j is not None and j != i and j in index:
                        pairs.add((min(i, j), max(i, j)))
                ex.Next()
        return sorted(pairs)

    def index_of(self, face: Any) -> int | None:
        if not hasattr(self, "_lookup"):
            self._lookup: dict[Any, list[int]] = {}  # TShape -> indices of the faces on it
            for k, f in enumerate(self.faces):
                self._lookup.setdefault(f.TShape(), []).append(k)
        for k in self._lookup.get(face.TShape(), []):
            if self.faces[k].IsSame(face):
                return k
        return None


def hole_loop(model: SewnModel, removed: list[int]) -> tuple[list[Any], list[Any], list[Any]]:
    """The hole's edges in loop order, each edge's neighbour and the removed face it bounded.

    Raises
    ------
    InvalidGeometryError
        The removed faces leave no closed loop, several loops (not a disk), or reach a free
        boundary of the model (the hole is not closed).
    """
    shell, b = TopoDS_Shell(), BRep_Builder()
    b.MakeShell(shell)
    for i in removed:
        b.Add(shell, model.faces[i])
    fb = ShapeAnalysis_FreeBounds(shell, SEW_TOLERANCE, False, True)
    wires, open_ = [], TopExp_Explorer(fb.GetOpenWires(), TopAbs_WIRE)
    if open_.More():
        raise InvalidGeometryError("the removed faces' boundary is not a closed loop")
    wex = TopExp_Explorer(fb.GetClosedWires(), TopAbs_WIRE)
    while wex.More():
        wires.append(TopoDS.Wire_s(wex.Current()))
        wex.Next()
    if len(wires) != 1:
        raise InvalidGeometryError(f"removing the faces leaves {len(wires)} loops (not a disk-like hole)")
    removed_faces = [model.faces[i] for i in removed]
    edges: list[Any] = []
    nbs: list[Any] = []
    owners: list[Any] = []
    we = BRepTools_WireExplorer(wires[0])
    while we.More():
        e = we.Current()
        fs = model.edge_faces(e)
        nb = [f for f in fs if not any(f.IsSame(r) for r in removed_faces)]
        own = [f for f in fs if any(f.IsSame(r) for r in removed_faces)]
        if not nb:
            raise InvalidGeometryError("a hole edge bounds no other face: the removed faces reach a free boundary "
                                       "of the model (the hole is not closed)")
        edges.append(e)
        nbs.append(nb[0])
        owners.append(own[0] if own else None)
        we.Next()
    return edges, nbs, owners


def edge_params(edge: Any, face: Any, k: int) -> np.ndarray:
    """Parameters of ``edge`` on ``face``'s p-curve: ``k`` uniform ones and, at each end,
    ``FILL_EDGE_END_SAMPLES`` more at geometric fractions of the range from ``FILL_EDGE_END_NEAREST``
    to ``FILL_EDGE_END_FARTHEST`` (sorted, each once)."""
    a, b = BRep_Tool.Range_s(edge, face)
    ends = np.geomspace(tolerances.FILL_EDGE_END_NEAREST, tolerances.FILL_EDGE_END_FARTHEST,
                        int(tolerances.FILL_EDGE_END_SAMPLES))
    f = np.unique(np.r_[np.linspace(0, 1, k), ends, 1 - ends])
    return a + f * (b - a)


#: Samples from which :func:`normals_on` (asked for no uv points) evaluates the face and its p-curve
#: many at a time (:mod:`~occsurf.bridge.conversion.occ_evaluators`: our B-splines, closed forms for
#: elementary surfaces) instead of by OCC's ``D1`` point by point: below it, making the evaluator (a
#: conversion of the surface) costs about what the loop does (the traces ask for up to 16 001).
VECTOR_SAMPLES = 256
#: How far (relative to the domain) a p-curve's parameters, or the uv it gives, may lie beyond the
#: p-curve's or the surface's domain for the many-at-once evaluation, which clips there where OCC's
#: extrapolates: round-off overshoots (1e-18 to 4e-12 on linkrods' edges) move a point by at most
#: about this fraction of the surface's extent. Farther (1.5e-10 and 1e-9 on two linkrods p-curves),
#: OCC's loop.
VECTOR_OVERSHOOT = 1e-11


def _d1_vectorised(s: Any, pc: Any, edge: Any, face: Any, ts: np.ndarray) -> tuple[np.ndarray, ...] | None:
    """``(uv, P, DU, DV)`` at ``ts`` by :mod:`~occsurf.bridge.conversion.occ_evaluators`, or ``None``
    where the surface or the p-curve has no vectorised form there (OCC's loop then)."""
    from ..conversion.occ_evaluators import pcurve_evaluator, surface_evaluator

    def beyond(x: np.ndarray, lo: float, hi: float) -> bool:
        slack = VECTOR_OVERSHOOT * (hi - lo)
        return bool(x.min() < lo - slack or x.max() > hi + slack)

    first, last = BRep_Tool.Range_s(edge, face)
    try:  # a p-curve or surface our conversion refuses (as the continuity check allows): OCC's loop
        curve = pcurve_evaluator(pc, first, last)
        # our splines clip to their domain where OCC's extrapolate: beyond it by more than round-off, OCC's loop
        if curve.kind == "occ" or (curve.spline is not None and beyond(ts, *curve.spline.domain)):
            return None
        surface = surface_evaluator(s)
        if surface.kind == "occ":
            return None
        uv, _ = curve(ts)
        if surface.spline is not None:
            for k, ((lo, hi), periodic) in enumerate(zip(surface.spline.domain, surface.periodic, strict=True)):
                if not periodic and beyond(uv[:, k], lo, hi):
                    return None
        D = surface.derivatives(uv[:, 0], uv[:, 1], 1)
    except Exception:  # noqa: BLE001 - any failure of the fast path leaves the exact one
        return None
    if not (np.all(np.isfinite(uv)) and np.all(np.isfinite(D[:, :2, :2]))):
        return None
    return uv, D[:, 0, 0], D[:, 1, 0], D[:, 0, 1]


def normals_on(edge: Any, face: Any, ts: np.ndarray, *, uv_points: bool = True
               ) -> tuple[np.ndarray, np.ndarray, list[Any]]:
    """Points, unit normals (face orientation applied) and uv (``gp_Pnt2d``; an empty list with
    ``uv_points=False``) of ``face`` along ``edge``'s p-curve, where the normal is defined.

    Without uv points and from :data:`VECTOR_SAMPLES` samples on, the face and the p-curve are
    evaluated many points at a time (the same points as OCC's loop to round-off: 8.3e-14 of the model
    size at worst on every shared edge of the screw, linkrods and the swept tube, 1e-12 tested in
    tests/bridge/test_refill_traces.py); else by OCC's ``D1`` per point."""
    s = BRep_Tool.Surface_s(face)
    pc = BRep_Tool.CurveOnSurface_s(edge, face, 0.0, 0.0)
    sign = -1.0 if face.Orientation() == TopAbs_REVERSED else 1.0
    m = len(ts)
    uvs: list[Any] = []
    fast = None if uv_points or m < VECTOR_SAMPLES else _d1_vectorised(s, pc, edge, face, np.asarray(ts, float))
    if fast is not None:
        uv, P, DU, DV = fast
    else:
        uv = np.empty((m, 2))
        P, DU, DV = np.empty((m, 3)), np.empty((m, 3)), np.empty((m, 3))
        p, du, dv = gp_Pnt(), gp_Vec(), gp_Vec()
        for k, t in enumerate(ts):  # OCC's D1 per point; the arithmetic below is vectorised
            q = pc.Value(float(t))
            s.D1(q.X(), q.Y(), p, du, dv)
            P[k], DU[k], DV[k] = p.Coord(), du.Coord(), dv.Coord()
            uv[k] = q.X(), q.Y()
            if uv_points:
                uvs.append(q)
    nrm = np.cross(DU, DV)
    floor = tolerances.FILL_EDGE_NORMAL_DEGENERATE * np.maximum(
        np.linalg.norm(DU, axis=1) * np.linalg.norm(DV, axis=1), 1e-300)
    for j in np.flatnonzero((np.linalg.norm(nrm, axis=1) <= floor) | ~np.all(np.isfinite(nrm), axis=1)):
        # a degenerate point (a pole of the surface): the normal by its limit, where OCC defines one
        pr = GeomLProp_SLProps(s, float(uv[j, 0]), float(uv[j, 1]), 1, tolerances.FILL_EDGE_NORMAL_RESOLUTION)
        nrm[j] = np.array(pr.Normal().Coord()) if pr.IsNormalDefined() else np.full(3, np.nan)
    N = nrm * sign
    good = np.all(np.isfinite(N), axis=1) & (np.linalg.norm(N, axis=1) > 0)
    if good.sum() < int(tolerances.FILL_EDGE_MIN_NORMALS):
        raise InvalidGeometryError("the neighbour's normal is undefined along a hole edge")
    return P[good], N[good] / np.linalg.norm(N[good], axis=1, keepdims=True), \
        [u for u, g in zip(uvs, good, strict=True) if g] if uv_points else []


def joint_angle(edge: Any, f1: Any, f2: Any) -> float:
    """Largest angle (degrees) between the two faces' normals along the edge (``FILL_JOINT_SAMPLES``
    samples); 90 where a normal is undefined (a sharp edge as far as the fill is concerned)."""
    a1, b1 = BRep_Tool.Range_s(edge, f1)
    a2, b2 = BRep_Tool.Range_s(edge, f2)
    k = int(tolerances.FILL_JOINT_SAMPLES)
    try:
        _, n1, _ = normals_on(edge, f1, np.linspace(a1, b1, k))
        _, n2, _ = normals_on(edge, f2, np.linspace(a2, b2, k))
    except InvalidGeometryError:
        return 90.0
    if len(n1) != len(n2):  # a normal undefined on one side only (a pole): judge it sharp
        return 90.0
    c = np.abs(np.einsum("ij,ij->i", n1, n2))  # sign-free: face orientations need not agree here
    return float(np.degrees(np.arccos(np.clip(c, 0, 1))).max())


def hole_gap(model: SewnModel, removed: list[int]) -> float:
    """The largest tolerance of an edge between a removed face and a kept one: the gap the model
    itself declares along the hole (linkrods' faces 17/19 meet their neighbours with 8.7e-5)."""
    gone = [model.faces[i] for i in removed]
    gap = 0.0
    for f in gone:
        ex = TopExp_Explorer(f, TopAbs_EDGE)
        while ex.More():
            e = TopoDS.Edge_s(ex.Current())
            if any(not any(g.IsSame(r) for r in gone) for g in model.edge_faces(e)):
                gap = max(gap, BRep_Tool.Tolerance_s(e))
            ex.Next()
    return gap


def face_components(model: SewnModel, faces: list[int]) -> list[list[int]]:
    """The faces grouped into edge-connected sets: each set leaves one hole."""
    left, out = set(int(i) for i in faces), []
    pairs = model.adjacent_pairs(sorted(left))
    while left:
        comp, todo = set(), [min(left)]
        while todo:
            i = todo.pop()
            if i in comp:
                continue
            comp.add(i)
            todo += [b if a == i else a for a, b in pairs if i in (a, b)]
        out.append(sorted(comp))
        left -= comp
    return out


def _inner_creases(model: SewnModel, removed: list[int]) -> list[tuple[float, np.ndarray]]:
    """The sharp edges between two removed faces: ``(largest angle in degrees between the faces'
    normals along it, its mid point)`` for each edge where it exceeds :data:`G1_EDGE_DEG`, sharpest
    first. Such an edge runs across the hole from boundary to boundary: a fill smooth across it
    must turn its tangent plane by that angle at the corners where the edge ends (screw pairs
    [8, 9] and [9, 12]: flank and crest meet at 60 deg, and no fill comes within 6e-4 of the
    boundary there; OCC's filler fails on both)."""
    gone = [model.faces[i] for i in removed]
    edges = TopTools_IndexedMapOfShape()  # each edge once
    for f in gone:
        TopExp.MapShapes_s(f, TopAbs_EDGE, edges)
    out = []
    for i in range(1, edges.Extent() + 1):
        e = TopoDS.Edge_s(edges.FindKey(i))
        pair = [g for g in model.edge_faces(e) if any(g.IsSame(r) for r in gone)]
        if len(pair) != 2 or BRep_Tool.Degenerated_s(e):
            continue
        angle = joint_angle(e, pair[0], pair[1])
        if angle > G1_EDGE_DEG:
            a, b = BRep_Tool.Range_s(e)
            mid = BRepAdaptor_Curve(e).Value(0.5 * (a + b))
            out.append((angle, np.array([mid.X(), mid.Y(), mid.Z()])))
    return sorted(out, key=lambda c: -c[0])


def crease_note(model: SewnModel, removed: list[int]) -> str:
    """A refusal's postscript naming the sharpest crease between removed faces, if any."""
    try:
        creases = _inner_creases(model, removed) if len(removed) > 1 else []
    except Exception:  # noqa: BLE001 - a note, never a second failure
        return ""
    if not creases:
        return ""
    angle, mid = creases[0]
    return (f" (the removed faces meet at {len(creases)} sharp edge(s), the sharpest at {angle:.1f} deg near "
            f"{np.array2string(mid, precision=4)}: a fill smooth across it turns its tangent plane by that "
            "much where the edge meets the hole's boundary)")


