"""Trimmed faces both ways: an OCC ``TopoDS_Face`` <-> :class:`occsurf.algorithms.TrimmedSurface`.

OCC -> ours (:func:`face_from_occ`, what ``from_occ(face)`` calls)
------------------------------------------------------------------
The surface is converted as ``from_occ`` always did (B-spline and Bézier surfaces whole and
bit-exact; other surfaces on the face's UV box through ``GeomConvert``). Every wire of the face
(explored on its FORWARD copy, edges in connection order by ``BRepTools_WireExplorer``) gives a
loop; every edge its p-curve on the face (``BRep_Tool.CurveOnSurface``, the one of its orientation
for a seam), trimmed to the edge's range and converted by ``Geom2dConvert`` (exact image; B-spline
p-curves segmented, not approximated), reversed when the edge is. ``BRepTools.OuterWire`` names the
outer loop.

P-curves live in OCC's parametrisation of the surface; the conversion keeps it for B-splines,
Bézier surfaces, planes and linear directions, but ``GeomConvert`` writes a circular direction
(cylinders, cones, spheres, tori, revolutions) as rational quadratic arcs whose parameter ``t`` is
the half-angle substitution of OCC's angle ``a`` on each span ``[k_i, k_i+1]`` of the converted
knots: ``t = m + h tan((a - m) / 2) / tan(h / 2)`` with ``m`` the span's middle and ``h`` its
half-width (:func:`angle_to_parameter`; checked per face against OCC at 25 points). A p-curve
that is constant in a converted coordinate (circles and seams of cylinders, meridians and poles of
spheres: nearly every edge of a machined part) maps exactly: it stays a straight iso-line. Any
other p-curve on such a surface is resampled and interpolated (quintic, span by span of the p-curve,
the points doubled until the interpolant is within :data:`TRIM_FIT_TOL` of the parameter box's
diagonal of the exact map at the midpoints).

A face is *untrimmed* when it has one wire whose p-curves all lie on the sides of its UV box (the
box faces of a solid, a full cylinder with its seam, a sphere with its poles): ``from_occ``
returns the plain :class:`~occsurf.algorithms.BSplineSurface`, exactly as before.

Ours -> OCC (:func:`trimmed_to_occ_face`, what ``make_face`` / ``to_face`` call)
--------------------------------------------------------------------------------
The surface by ``to_occ`` (bit-exact); each p-curve as a ``Geom2d_BSplineCurve`` (bit-exact); one
vertex per junction of a loop (the surface's point at the junction); edges by
``BRepBuilderAPI_MakeEdge(pcurve, surface, V1, V2, t0, t1)``. A p-curve whose 3-D image is a point
becomes a degenerated edge (sphere and cone poles); two p-curves with the same 3-D image traversed
in opposite directions on a closed surface become one seam edge with two p-curves
(``BRep_Builder.UpdateEdge(E, C1, C2, ...)``), used FORWARD then REVERSED. The 3-D curves are
built by ``BRepLib.BuildCurve3d_s`` on every edge but the degenerated ones; the face is reversed when :attr:`TrimmedSurface.reversed`.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from OCP.BRep import BRep_Builder, BRep_Tool
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeEdge, BRepBuilderAPI_MakeFace, BRepBuilderAPI_MakeVertex
from OCP.BRepLib import BRepLib
from OCP.BRepTools import BRepTools, BRepTools_WireExplorer
from OCP.Geom import Geom_BezierSurface, Geom_BSplineSurface, Geom_Surface
from OCP.Geom2d import Geom2d_BSplineCurve, Geom2d_TrimmedCurve
from OCP.Geom2dConvert import Geom2dConvert
from OCP.GeomAbs import GeomAbs_Shape
from OCP.gp import gp_Pnt, gp_Pnt2d
from OCP.TColgp import TColgp_Array1OfPnt2d
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FORWARD, TopAbs_REVERSED, TopAbs_WIRE
from OCP.TopExp import TopExp_Explorer
from OCP.TopLoc import TopLoc_Location
from OCP.TopoDS import TopoDS, TopoDS_Face, TopoDS_Wire

from occsurf.algorithms import BSplineCurve, BSplineSurface, TrimmedSurface
from occsurf.algorithms.errors import InvalidGeometryError, KernelError
from occsurf.algorithms.fitting import interpolate_curve

from .. import _occ

__all__ = ["face_from_occ", "box_on_domain", "trimmed_to_occ_face", "angle_to_parameter", "parameter_maps", "TRIM_FIT_TOL",
           "EDGE_TOLERANCE"]

#: P-curves that must be resampled (not iso-lines on a surface whose circular directions
#: GeomConvert re-parametrised) are interpolated until within this of the exact map, relative to
#: the diagonal of the UV box.
TRIM_FIT_TOL: float = 1e-11

#: Tolerance of the edges and vertices of rebuilt faces, and of ``BuildCurves3d``: relative to the
#: size of the surface's control net (at least ``1e-7``, OCC's ``Precision::Confusion()``).
EDGE_TOLERANCE: float = 1e-9

_FIT_MAX_POINTS = 1 << 12
_FIT_DEGREE = 5


# ============================================================================ OCC -> ours
def face_from_occ(face: TopoDS_Face, surface: BSplineSurface, occ_surface: Geom_Surface, uv_box: tuple[float, ...]
                  ) -> TrimmedSurface | BSplineSurface:
    """The face as a :class:`TrimmedSurface` on ``surface``, or ``surface`` when it is untrimmed
    (one loop along the sides of ``surface``'s whole domain; a face on a rectangle inside the domain
    is trimmed by that rectangle).

    Parameters
    ----------
    face : TopoDS_Face
    surface : BSplineSurface
        ``from_occ`` of the face's surface (whole for B-splines, on ``uv_box`` otherwise).
    occ_surface : Geom_Surface
        ``BRep_Tool.Surface_s(face)``.
    uv_box : (u0, u1, v0, v1)
        ``BRepTools.UVBounds_s(face)``.
    """
    fwd = TopoDS.Face_s(face.Oriented(TopAbs_FORWARD))
    outer = BRepTools.OuterWire_s(fwd)
    wires: list[list[BSplineCurve]] = []
    outer_index = 0
    exp = TopExp_Explorer(fwd, TopAbs_WIRE)
    while exp.More():
        w = TopoDS.Wire_s(exp.Current())
        if not outer.IsNull() and w.IsSame(outer):
            outer_index = len(wires)
        wires.append(_wire_pcurves(w, fwd))
        exp.Next()
    if not wires or not all(wires):
        raise InvalidGeometryError("from_occ: the face has a wire without edges (or no wire)")
    if len(wires) == 1 and _on_box(wires[0], uv_box) and box_on_domain(surface, uv_box) != "inside":
        return surface
    # (one loop on the sides of a box inside the surface's domain -- a B-spline face using a
    # rectangle of its surface, as linkrods' face 19 does -- is a trim too: until 2026-12-06 it was
    # returned as the whole surface)
    maps = parameter_maps(surface, occ_surface, uv_box)
    loops = [tuple(_map_pcurve(c, maps, surface, uv_box) for c in loop) for loop in wires]
    outer_loop = loops.pop(outer_index)
    return TrimmedSurface(surface, outer_loop, tuple(loops), face.Orientation() == TopAbs_REVERSED)


def _wire_pcurves(wire: TopoDS_Wire, face: TopoDS_Face) -> list[BSplineCurve]:
    out = []
    wexp = BRepTools_WireExplorer(wire, face)
    while wexp.More():
        edge = wexp.Current()
        with _occ.kernel_errors("from_occ: reading a p-curve"):
            pc = BRep_Tool.CurveOnSurface_s(edge, face, 0.0, 0.0)
            if pc is None:
                raise InvalidGeometryError("from_occ: an edge of the face has no p-curve on it")
            t0, t1 = BRep_Tool.Range_s(edge, face)
            c = _pcurve_to_ours(pc, t0, t1)
        out.append(c.reverse() if edge.Orientation() == TopAbs_REVERSED else c)
        wexp.Next()
    return out


def _pcurve_to_ours(pc: Any, t0: float, t1: float) -> BSplineCurve:
    """A Geom2d curve on ``[t0, t1]`` as our 2-D B-spline (bit-exact for B-spline p-curves on their
    whole range; ``Geom2dConvert`` otherwise: exact image)."""
    if isinstance(pc, Geom2d_BSplineCurve) and not pc.IsPeriodic() and \
            pc.FirstParameter() == t0 and pc.LastParameter() == t1:
        b = pc
    else:
        if pc.IsPeriodic():
            period = pc.Period()
            if t1 - t0 > period:
                t1 = t0 + period
        b = Geom2dConvert.CurveToBSplineCurve_s(Geom2d_TrimmedCurve(pc, t0, t1))
    n = b.NbPoles()
    P = np.array([b.Pole(i).Coord() for i in range(1, n + 1)], float)
    w = None if not b.IsRational() else np.array([b.Weight(i) for i in range(1, n + 1)], float)
    knots = _occ.knots_from_occ(b.Knots(), b.Multiplicities())
    if b.IsPeriodic():
        knots = _occ.from_real_array(b.KnotSequence())
        p = b.Degree()
        idx = np.arange(knots.shape[0] - p - 1) % n
        P, w = P[idx], None if w is None else w[idx]
    return BSplineCurve(b.Degree(), knots, P, w)


def box_on_domain(surface: BSplineSurface, box: tuple[float, ...]) -> str:
    """Where a face's UV ``box`` ``(u0, u1, v0, v1)`` lies against ``surface``'s domain, to 1e-9 of
    the domain's diagonal: ``"whole"`` (the same box), ``"inside"`` (within it and smaller: a
    rectangle cut out of the surface) or ``"past"`` (reaching beyond it: a periodic face across its
    seam)."""
    u0, u1, v0, v1 = box
    (a0, a1), (b0, b1) = surface.domain
    tol = 1e-9 * max(1.0, float(np.hypot(a1 - a0, b1 - b0)))
    if not (u0 >= a0 - tol and u1 <= a1 + tol and v0 >= b0 - tol and v1 <= b1 + tol):
        return "past"
    return "inside" if max(u0 - a0, a1 - u1, v0 - b0, b1 - v1) > tol else "whole"


def _on_box(loop: list[BSplineCurve], box: tuple[float, ...]) -> bool:
    """Every p-curve of ``loop`` lies on one side of the UV box (its poles do: convex hull)."""
    u0, u1, v0, v1 = box
    tol = 1e-9 * max(1.0, float(np.hypot(u1 - u0, v1 - v0)))
    for c in loop:
        P = c.control_points
        if not any(np.all(np.abs(P[:, k] - x) <= tol) for k, x in ((0, u0), (0, u1), (1, v0), (1, v1))):
            return False
    return True


def angle_to_parameter(a: np.ndarray, knots: np.ndarray, degree: int, n_poles: int) -> np.ndarray:
    """OCC's angle ``a`` -> the parameter of ``GeomConvert``'s rational quadratic arcs.

    On each span ``[k_i, k_i+1]`` of the distinct knots of the domain the arc is the half-angle
    substitution: ``t = m + h tan((a - m) / 2) / tan(h / 2)`` with ``m = (k_i + k_i+1) / 2`` and
    ``h = (k_i+1 - k_i) / 2`` (The NURBS Book, 2nd ed., §7.5: the circular arc with middle weight
    ``cos(h)``, whose parameter is ``tan`` of half the angle from the middle).
    """
    k = np.unique(knots[degree:n_poles + 1])
    a = np.asarray(a, float)
    i = np.clip(np.searchsorted(k, a, side="right") - 1, 0, k.size - 2)
    m, h = 0.5 * (k[i] + k[i + 1]), 0.5 * (k[i + 1] - k[i])
    return m + h * np.tan(0.5 * (a - m)) / np.tan(0.5 * h)


def parameter_maps(surface: BSplineSurface, occ_surface: Geom_Surface, uv_box: tuple[float, ...]) -> tuple[bool, bool]:
    """Which directions of ``surface`` GeomConvert re-parametrised by :func:`angle_to_parameter`.

    Returns ``(map_u, map_v)``. B-spline and Bézier surfaces keep OCC's parameters. For any other
    surface the four candidates are checked against OCC's own points at 25 scattered parameters of
    the UV box; :class:`InvalidGeometryError` if none reproduces them.
    """
    basis = occ_surface
    if isinstance(basis, (Geom_BSplineSurface, Geom_BezierSurface)):
        return False, False
    u0, u1, v0, v1 = uv_box
    g = np.array([0.0, 0.13, 0.41, 0.77, 1.0])
    uu2, vv2 = np.meshgrid(u0 + g * (u1 - u0), v0 + g[::-1].copy() * (v1 - v0), indexing="ij")
    uu, vv = uu2.ravel(), vv2.ravel()
    ref = np.array([occ_surface.Value(float(a), float(b)).Coord() for a, b in zip(uu, vv)])
    scale = max(1.0, float(np.ptp(ref, axis=0).max()))
    (su0, su1), (sv0, sv1) = surface.domain
    best = None
    for mu, mv in ((False, False), (True, False), (False, True), (True, True)):
        a = _map(uu, surface, 0) if mu else uu
        b = _map(vv, surface, 1) if mv else vv
        dev = float(np.abs(surface.evaluate(np.clip(a, su0, su1), np.clip(b, sv0, sv1)) - ref).max())
        if dev <= 1e-9 * scale:
            return mu, mv
        best = dev if best is None else min(best, dev)
    raise InvalidGeometryError(
        f"from_occ: the converted surface's parametrisation could not be related to OCC's "
        f"({type(occ_surface).__name__}; best deviation {best:.3g}); its p-curves cannot be carried over")


def _map(x: np.ndarray, surface: BSplineSurface, ax: int) -> np.ndarray:
    return angle_to_parameter(x, surface.knots[ax], surface.degree[ax], surface.n_poles[ax])


def _map_pcurve(c: BSplineCurve, maps: tuple[bool, bool], surface: BSplineSurface, box: tuple[float, ...]) -> BSplineCurve:
    if not any(maps):
        return c
    P = c.control_points
    tol = 1e-12 * max(1.0, float(np.hypot(box[1] - box[0], box[3] - box[2])))
    const = [bool(np.all(np.abs(P[:, k] - P[0, k]) <= tol)) for k in (0, 1)]
    monotone = [bool(np.all(np.diff(P[:, k]) >= 0) or np.all(np.diff(P[:, k]) <= 0)) for k in (0, 1)]
    for k in (0, 1):
        if const[k] and monotone[1 - k]:  # an iso-line: stays one, ends mapped exactly
            ends = c.evaluate(np.array(c.domain))
            a = _map_xy(ends, maps, surface)
            a[:, k] = a[0, k]
            return BSplineCurve(1, np.array([c.domain[0]] * 2 + [c.domain[1]] * 2), a)
    diag = max(1.0, float(np.hypot(box[1] - box[0], box[3] - box[2])))
    return _refit(c, maps, surface, TRIM_FIT_TOL * diag)


def _map_xy(P: np.ndarray, maps: tuple[bool, bool], surface: BSplineSurface) -> np.ndarray:
    out = np.array(P, float)
    for k in (0, 1):
        if maps[k]:
            out[:, k] = _map(out[:, k], surface, k)
    return out


def _refit(c: BSplineCurve, maps: tuple[bool, bool], surface: BSplineSurface, tol: float) -> BSplineCurve:
    """The mapped p-curve, interpolated span by span of ``c`` and between the points where it
    crosses a knot of a re-parametrised direction (quintic, C0 at those breaks so a kink stays a
    kink), the points of a span doubled until its midpoints are within ``tol`` of the exact map.

    With ``n`` equally spaced points per span, the interpolation matrix is the same for every span
    (averaged knots on the normalised span): it is inverted once per ``n`` and applied to all the
    spans at once."""
    p = _FIT_DEGREE
    breaks = np.union1d(np.unique(c.knots[c.degree:c.n_poles + 1]), _knot_crossings(c, maps, surface))
    keep = np.r_[True, np.diff(breaks) > 1e-9 * (breaks[-1] - breaks[0])]
    keep[-1] = True
    breaks = breaks[keep] if keep.sum() >= 2 else breaks[[0, -1]]
    if breaks.size > 2 and breaks[-1] - breaks[-2] <= 1e-9 * (breaks[-1] - breaks[0]):
        breaks = np.delete(breaks, -2)
    a, b = breaks[:-1], breaks[1:]
    pieces: list[tuple[np.ndarray, np.ndarray] | None] = [None] * a.size
    todo = np.arange(a.size)
    n = 2 * p
    while todo.size:
        unit, mid_basis = _unit_interpolant(n, p)
        t = a[todo, None] + (b - a)[todo, None] * np.linspace(0.0, 1.0, n)[None, :]
        Q = _map_xy(c.evaluate(t.ravel()), maps, surface).reshape(todo.size, n, 2)
        poles = np.einsum("ij,sjd->sid", unit.control_points, Q)  # (spans, n, 2)
        tm = 0.5 * (t[:, :-1] + t[:, 1:])
        exact = _map_xy(c.evaluate(tm.ravel()), maps, surface).reshape(todo.size, n - 1, 2)
        err = np.abs(np.einsum("ij,sjd->sid", mid_basis, Q) - exact).max(axis=(1, 2))
        for k, ok in zip(todo, err <= tol):
            if ok:
                pieces[k] = (a[k] + (b[k] - a[k]) * unit.knots, poles[np.searchsorted(todo, k)])
        todo = todo[err > tol]
        if todo.size and n >= _FIT_MAX_POINTS:
            raise KernelError(f"from_occ: a p-curve could not be mapped onto the converted surface within {tol:.3g} "
                              f"(reached {float(err.max()):.3g} with {n} points on one span)")
        n *= 2
    knots = [np.full(p + 1, breaks[0])]
    P: list[np.ndarray] = []
    for i, piece in enumerate(pieces):
        if piece is None:  # cannot happen: the loop above ends once every span is fitted, or raises
            raise AssertionError("_refit: a span was left without its fit")
        kn, span_poles = piece
        knots += [kn[p + 1:kn.size - p - 1], np.full(p, b[i])]
        P.append(span_poles if i == 0 else span_poles[1:])
    knots[-1] = np.full(p + 1, breaks[-1])
    return BSplineCurve(p, np.concatenate(knots), np.concatenate(P))


def _unit_interpolant(n: int, p: int) -> tuple[BSplineCurve, np.ndarray]:
    """Interpolation of ``n`` equally spaced points on [0, 1] (degree ``p``, averaged knots): the
    curve whose poles are the inverse collocation matrix (interpolating the identity), and the
    matrix taking data to the interpolant's values at the midpoints."""
    unit = interpolate_curve(np.eye(n), p, params=np.linspace(0.0, 1.0, n))
    mids = 0.5 * (np.linspace(0.0, 1.0, n)[:-1] + np.linspace(0.0, 1.0, n)[1:])
    return unit, unit.evaluate(mids)


def _knot_crossings(c: BSplineCurve, maps: tuple[bool, bool], surface: BSplineSurface) -> np.ndarray:
    """Parameters where ``c`` crosses an interior knot of a re-parametrised direction of the
    surface: the map is only C1 there, so the interpolation breaks there too (bisection on 64
    samples per span, 60 halvings: to round-off)."""
    t0, t1 = c.domain
    s = np.linspace(t0, t1, 64 * max(1, np.unique(c.knots).size) + 1)
    out = []
    for k in (0, 1):
        if not maps[k]:
            continue
        p, K, n = surface.degree[k], surface.knots[k], surface.n_poles[k]
        inner = np.unique(K[p + 1:n])
        inner = inner[(inner > K[p]) & (inner < K[n])]
        if inner.size == 0:
            continue
        x = c.evaluate(s)[:, k]
        f = x[:, None] - inner[None, :]
        i, j = np.nonzero(np.sign(f[:-1]) * np.sign(f[1:]) < 0)
        lo, hi = s[i], s[i + 1]
        flo = np.sign(f[i, j])
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            fm = np.sign(c.evaluate(mid)[:, k] - inner[j])
            same = fm == flo
            lo, hi = np.where(same, mid, lo), np.where(same, hi, mid)
        out.append(0.5 * (lo + hi))
    r = np.concatenate(out) if out else np.zeros(0)
    return r[(r > t0) & (r < t1)]


# ============================================================================ ours -> OCC
def trimmed_to_occ_face(t: TrimmedSurface, occ_surface: Geom_Surface, tol: float | None = None) -> TopoDS_Face:
    """Rebuild an OCC face from a :class:`TrimmedSurface` (see the module docstring).

    Parameters
    ----------
    t : TrimmedSurface
        3-D.
    occ_surface : Geom_Surface
        ``to_occ(t.surface)``.
    tol : float, optional
        Edge and vertex tolerance; default :data:`EDGE_TOLERANCE` x the net's size, at least 1e-7.

    Raises
    ------
    KernelError
        An OCC builder failed, or the rebuilt face's 3-D curves could not be built.
    """
    if t.dim != 3:
        raise InvalidGeometryError(f"to_face: OpenCascade faces are 3-D, got a TrimmedSurface of dim {t.dim}")
    size = float(np.ptp(t.surface.control_points.reshape(-1, 3), axis=0).max())
    tol = max(1e-7, EDGE_TOLERANCE * size) if tol is None else float(tol)
    loops = t.loops
    flat = [(i, j, c) for i, loop in enumerate(loops) for j, c in enumerate(loop)]
    images = {(i, j): _image(t.surface, c) for i, j, c in flat}
    # imported loops do not close exactly: what is "the same point" grows with their largest gap
    near = max(tol, 2.0 * _largest_gap(images, loops))
    degenerate = {key for key, pts in images.items() if float(np.ptp(pts, axis=0).max()) <= near}
    seams = _seam_pairs(flat, images, degenerate, near)
    builder = BRep_Builder()
    edges: dict[tuple[int, int], Any] = {}
    with _occ.kernel_errors("to_face: building the edges of a trimmed face"):
        verts = _junction_vertices(t.surface, loops, seams, tol, near)
        for i, loop in enumerate(loops):
            for j, c in enumerate(loop):
                key = (i, j)
                if key in edges:
                    continue
                v1, v2 = verts[(i, j)], verts[(i, (j + 1) % len(loop))]
                occ_c = _pcurve_to_occ(c)
                me = BRepBuilderAPI_MakeEdge(occ_c, occ_surface, v1, v2, *c.domain)
                if not me.IsDone():
                    raise KernelError(f"to_face: BRepBuilderAPI_MakeEdge failed for p-curve {j} of loop {i} "
                                      f"(status {me.Error()})")
                edge = me.Edge()
                if key in degenerate:
                    builder.Degenerated(edge, True)
                if key in seams:
                    other = seams[key]
                    twin = _pcurve_to_occ(loops[other[0]][other[1]].reverse())
                    builder.UpdateEdge(edge, occ_c, twin, occ_surface, TopLoc_Location(), tol)
                    edges[other] = edge.Reversed()
                edges[key] = edge
        wires = []
        for i, loop in enumerate(loops):
            w = TopoDS_Wire()
            builder.MakeWire(w)
            for j in range(len(loop)):
                builder.Add(w, edges[(i, j)])
            w.Closed(True)
            wires.append(w)
        mf = BRepBuilderAPI_MakeFace(occ_surface, wires[0], True)
        for w in wires[1:]:
            mf.Add(w)
        if not mf.IsDone():
            raise KernelError(f"to_face: BRepBuilderAPI_MakeFace failed (status {mf.Error()})")
        face = mf.Face()
        _build_curves_3d(face, tol)
        BRepLib.SameParameter_s(face, tol, False)
    return TopoDS.Face_s(face.Reversed()) if t.reversed else face


def _build_curves_3d(face: TopoDS_Face, tol: float) -> None:
    """``BRepLib.BuildCurve3d`` on every edge but the degenerated ones (which have no 3-D curve;
    ``BRepLib.BuildCurves3d`` reports failure for them, so it is not used on a face with poles)."""
    exp = TopExp_Explorer(face, TopAbs_EDGE)
    k = 0
    while exp.More():
        edge = TopoDS.Edge_s(exp.Current())
        if not BRep_Tool.Degenerated_s(edge) and \
                not BRepLib.BuildCurve3d_s(edge, tol, GeomAbs_Shape.GeomAbs_C1, 14, 0):
            raise KernelError(f"to_face: BRepLib.BuildCurve3d could not build the 3-D curve of edge {k}")
        k += 1
        exp.Next()


def _largest_gap(images: dict[tuple[int, int], np.ndarray], loops: tuple[tuple[BSplineCurve, ...], ...]) -> float:
    """Largest 3-D distance between the end of a p-curve's image and the start of the next one's."""
    gaps = [np.linalg.norm(images[(i, j - 1 if j else len(loop) - 1)][-1] - images[(i, j)][0])
            for i, loop in enumerate(loops) for j in range(len(loop))]
    return float(max(gaps, default=0.0))


def _image(surface: BSplineSurface, c: BSplineCurve) -> np.ndarray:
    s = np.linspace(*c.domain, 9)
    uv = c.evaluate(s)
    (u0, u1), (v0, v1) = surface.domain
    return surface.evaluate(np.clip(uv[:, 0], u0, u1), np.clip(uv[:, 1], v0, v1))


def _seam_pairs(flat: list[tuple[int, int, BSplineCurve]], images: dict[tuple[int, int], np.ndarray],
                degenerate: set[tuple[int, int]], tol: float) -> dict[tuple[int, int], tuple[int, int]]:
    """First -> second use of p-curve pairs with one 3-D image traversed both ways (seams).

    Candidates are the pairs whose 3-D ends match crosswise (one distance matrix); each is then
    checked on 9 points and must be two different curves in ``(u, v)``."""
    keys = [(i, j) for i, j, _ in flat if (i, j) not in degenerate]
    if len(keys) < 2:
        return {}
    curves = {(i, j): c for i, j, c in flat}
    start = np.array([images[k][0] for k in keys])
    end = np.array([images[k][-1] for k in keys])
    cross = (np.linalg.norm(start[:, None] - end[None, :], axis=-1) <= tol) & \
            (np.linalg.norm(end[:, None] - start[None, :], axis=-1) <= tol)
    out: dict[tuple[int, int], tuple[int, int]] = {}
    used: set[tuple[int, int]] = set()
    for ia, ib in zip(*np.nonzero(np.triu(cross, 1))):
        a, b = keys[ia], keys[ib]
        if a in used or b in used:
            continue
        ca, cb = curves[a], curves[b]
        if not np.allclose(ca.domain, cb.domain, atol=0, rtol=1e-12):
            continue
        if np.abs(images[a] - images[b][::-1]).max() > tol:
            continue
        uv_a, uv_b = ca.evaluate(np.array(ca.domain)), cb.evaluate(np.array(cb.domain))[::-1]
        if np.abs(uv_a - uv_b).max() <= 1e-9 * max(1.0, float(np.abs(uv_a).max())):
            continue  # the same p-curve twice: not a seam
        out[a] = b
        used.update((a, b))
    return out


def _junction_vertices(surface: BSplineSurface, loops: tuple[tuple[BSplineCurve, ...], ...],
                       seams: dict[tuple[int, int], tuple[int, int]], tol: float, near: float
                       ) -> dict[tuple[int, int], Any]:
    """One vertex per junction ``(loop, index of the p-curve that starts there)``: the surface's
    point there. Junctions share a vertex when a p-curve between them has a closed 3-D image (a
    full circle, a degenerated edge) and where the two uses of a seam meet the same corners."""
    root: dict[tuple[int, int], tuple[int, int]] = {}
    pts: dict[tuple[int, int], list[np.ndarray]] = {}
    (u0, u1), (v0, v1) = surface.domain
    for i, loop in enumerate(loops):
        ends = np.array([c.evaluate(np.array(c.domain)) for c in loop]).reshape(-1, 2)
        xyz = surface.evaluate(np.clip(ends[:, 0], u0, u1), np.clip(ends[:, 1], v0, v1)).reshape(-1, 2, 3)
        for j in range(len(loop)):
            root[(i, j)] = (i, j)
            pts[(i, j)] = [xyz[j, 0], xyz[j - 1, 1]]  # this p-curve's start, the previous one's end
        closed = np.linalg.norm(xyz[:, 0] - xyz[:, 1], axis=1) <= near
        for jc in np.flatnonzero(closed):
            _union(root, (i, int(jc)), (i, (int(jc) + 1) % len(loop)))
    for (i, j), (i2, j2) in seams.items():
        _union(root, (i2, j2), (i, (j + 1) % len(loops[i])))
        _union(root, (i2, (j2 + 1) % len(loops[i2])), (i, j))
    groups: dict[tuple[int, int], list[np.ndarray]] = {}
    for key in root:
        groups.setdefault(_find(root, key), []).extend(pts[key])
    builder = BRep_Builder()
    made: dict[tuple[int, int], Any] = {}
    for r, members in groups.items():
        P = np.array(members)
        centre = P.mean(axis=0)
        vertex = BRepBuilderAPI_MakeVertex(gp_Pnt(*map(float, centre))).Vertex()
        gap = float(np.linalg.norm(P - centre, axis=1).max())
        builder.UpdateVertex(vertex, max(tol, 1.5 * gap))  # the ends of imported p-curves do not meet exactly
        made[r] = vertex
    return {key: made[_find(root, key)] for key in root}


def _find(root: dict, a: Any) -> Any:
    while root[a] != a:
        a = root[a]
    return a


def _union(root: dict, a: Any, b: Any) -> None:
    ra, rb = _find(root, a), _find(root, b)
    if ra != rb:
        root[max(ra, rb)] = min(ra, rb)


def _pcurve_to_occ(c: BSplineCurve) -> Geom2d_BSplineCurve:
    p = _occ.check_degree(c.degree, "p-curve degree")
    occ_k, occ_m = _occ.knots_to_occ(c.knots, p, "p-curve knots")
    poles = TColgp_Array1OfPnt2d(1, c.n_poles)
    for i, (x, y) in enumerate(c.control_points.tolist(), start=1):
        poles.SetValue(i, gp_Pnt2d(x, y))
    if c.weights is None:
        return Geom2d_BSplineCurve(poles, occ_k, occ_m, p, False)
    return Geom2d_BSplineCurve(poles, _occ.real_array(c.weights), occ_k, occ_m, p, False)
