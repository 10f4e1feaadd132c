"""Exact conversion between our splines and OpenCascade geometry and topology.

``to_occ`` and ``from_occ`` are inverse and **bit-exact** for B-splines: poles, weights and knots
are copied as IEEE doubles, never recomputed. The knot vector is split into OCC's distinct knots +
multiplicities in one place (:func:`occsurf.bridge._occ.knots_to_occ`).

What ``from_occ`` accepts, and how exact the result is
------------------------------------------------------
* ``Geom_BSplineCurve`` / ``Geom_BSplineSurface``: bit-exact (periodic ones: see below).
* ``Geom_BezierCurve`` / ``Geom_BezierSurface``: exact, the same poles on knots ``[0]*(p+1) + [1]*(p+1)``.
* Lines, conics, planes, cylinders, cones, spheres, tori, surfaces of revolution and extrusion,
  trimmed curves and surfaces, offsets with an analytic equivalent (``Geom_OffsetSurface.Surface()``):
  through ``GeomConvert``. The *image* is exact (rational degree 2 in the circular directions, up
  to round-off), the *parametrisation* in circular directions is not OCC's (they differ by up to
  ~1e-2 in parameter; see OCP_NOTES §2).
* Other offset curves and surfaces: approximated by ``GeomConvert_ApproxCurve`` /
  ``GeomConvert_ApproxSurface`` within ``tol`` (:class:`ToleranceError` if that is not reached).
* ``TopoDS_Face`` / ``TopoDS_Edge`` and build123d / cadquery ``Face`` / ``Edge`` (their
  ``.wrapped``): the underlying surface / curve, see "Faces and edges".

Infinite geometry (lines, planes, cylinders, cones, extrusions) has no B-spline form: pass
``bounds`` (``(t0, t1)`` for curves, ``(u0, u1, v0, v1)`` for surfaces). ``bounds`` on a finite
surface or curve trims it too (``Geom_RectangularTrimmedSurface`` / ``Geom_TrimmedCurve``, then
``GeomConvert``, which segments a B-spline without changing its parametrisation).

Periodic B-splines
------------------
We have no periodic flag: a periodic OCC spline with ``n`` poles, degree ``p`` and flat knots
``KnotSequence()`` (length ``m``) is returned as the *equivalent unclamped non-periodic spline* with
the same flat knots and the ``m - p - 1`` poles ``P[j mod n]`` (poles wrapped around, copied
bit-exactly; weights likewise). Its domain ``[flat[p], flat[m - p - 1]]`` is the period
``[FirstParameter, LastParameter]``, and it evaluates to the same points as the periodic curve (the
B-spline basis on the period is the same; verified against OCC in ``tests/bridge``). One
difference at the seam: at ``LastParameter`` OCC wraps round and takes derivatives from the right
of the seam (those at ``FirstParameter``); the unclamped form takes them from the left, as at the
end of any domain. They differ where the seam is not smooth enough (e.g. degree 1). OCC's own
``SetNotPeriodic`` gives the same structure, but it goes through homogeneous coordinates and rounds
the poles of rational splines, so it is not used. ``to_occ`` of the result is a non-periodic OCC
spline with the same geometry. A periodic spline with fewer than ``degree + 1`` poles (OCC's
periodic circle in build123d sweeps) has an invalid ``KnotSequence``; its flat knots are then built
from the distinct knots with OCC's convention (see ``_periodic_flat``).

Faces and edges
---------------
A face whose boundary is not the natural rectangle of its surface (a hole, a cut, a fillet's end)
comes back as an :class:`~occsurf.algorithms.TrimmedSurface`: the surface below plus the face's
loops of p-curves in its parameters and its orientation (:mod:`.trimming`); ``trims=False`` or
``bounds`` give the surface alone, as every face did before. ``make_face`` / ``to_face`` of a
TrimmedSurface rebuild the trimmed face.

``BRep_Tool.Surface_s(face)`` / ``BRep_Tool.Curve_s(edge)`` give the geometry with the shape's
``Location`` applied. A B-spline or Bézier surface (curve) is returned whole and exact; any other
surface is trimmed to the face's UV bounds (``BRepTools.UVBounds_s``) — an edge's curve to the edge's
parameter range — before conversion. **Orientation is not applied**: a ``REVERSED`` face keeps the
normal of its surface (``S_u x S_v``), which then points *into* the solid; a ``REVERSED`` edge runs
against its curve. Ask :func:`is_reversed` and apply it yourself (``surface.reverse(direction="u")`` flips
the normal, ``curve.reverse()`` the direction) when you need the topological sense.

Dimension
---------
Geom2d is out of scope: ``to_occ`` raises :class:`InvalidGeometryError` for a spline whose points
are not 3-D (pad planar curves with a zero z column yourself: ``np.c_[P, np.zeros(len(P))]``), and
``from_occ`` refuses ``Geom2d_*`` objects. Silently padding would break the round trip
``from_occ(to_occ(c)) == c``.

Weights
-------
OCC stores a spline whose weights are all equal as polynomial (``Weights()`` is ``None``), so
``from_occ(to_occ(c))`` of such a rational ``c`` has ``weights=None``: the same geometry, but not
the same arrays. Any other rational spline round-trips bit-exactly.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
from OCP.BRep import BRep_Tool
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeEdge, BRepBuilderAPI_MakeFace
from OCP.BRepTools import BRepTools
from OCP.Geom import (
    Geom_BezierCurve,
    Geom_BezierSurface,
    Geom_BSplineCurve,
    Geom_BSplineSurface,
    Geom_Curve,
    Geom_Geometry,
    Geom_Surface,
)
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_REVERSED
from OCP.TopExp import TopExp, TopExp_Explorer
from OCP.TopoDS import TopoDS, TopoDS_Edge, TopoDS_Face, TopoDS_Shape
from OCP.TopTools import TopTools_IndexedMapOfShape

from occsurf.algorithms import BSplineCurve, BSplineSurface, TrimmedSurface
from occsurf.algorithms.errors import InvalidGeometryError, KernelError

from .. import _occ
from .from_geom import from_geom_curve, from_geom_surface
from .shapes import as_edge, as_shape, is_shape_like

if TYPE_CHECKING:
    import build123d as bd
    import cadquery as cq

__all__ = [
    "FACE_TOLERANCE",
    "APPROX_TOLERANCE",
    "to_occ",
    "from_occ",
    "is_reversed",
    "to_face",
    "to_edge",
    "to_cq_face",
    "to_cq_edge",
    "make_face",
    "make_edge",
]

#: Tolerance given to ``BRepBuilderAPI_MakeFace`` / stored on the edges of faces we build: OCC's
#: ``Precision::Confusion()``. Absolute, model units.
FACE_TOLERANCE: float = 1e-7

#: Default 3-D tolerance for offset curves and surfaces that have no exact B-spline form and are
#: approximated by ``GeomConvert_ApproxCurve`` / ``GeomConvert_ApproxSurface`` (``GeomConvert``
#: itself would use 1e-4). Absolute, model units; ``from_occ(..., tol=)`` overrides it.
APPROX_TOLERANCE: float = 1e-7



# ================================================================================= ours -> OCC
def to_occ(obj: BSplineCurve | BSplineSurface) -> Geom_BSplineCurve | Geom_BSplineSurface:
    """Our spline as a non-periodic ``Geom_BSplineCurve`` / ``Geom_BSplineSurface``, bit-exact.

    Parameters
    ----------
    obj : BSplineCurve or BSplineSurface
        3-D (``dim == 3``). Clamped or unclamped knots; rational or not.

    Returns
    -------
    Geom_BSplineCurve or Geom_BSplineSurface
        Same degree(s), poles, weights and flat knot vector(s) (``KnotSequence()``) as ``obj``.

    Raises
    ------
    InvalidGeometryError
        ``obj`` is not one of our splines (the message names its type); not 3-D; a degree above
        OCC's 25 (possible through ``_trusted``); an interior knot of multiplicity ``degree + 1``
        (OCC allows it at the ends only); two knots closer than one ulp.
    KernelError
        OCC refused the data anyway (e.g. weights <= 0 smuggled in through ``_trusted``).
    """
    if isinstance(obj, BSplineCurve):
        return _curve_to_occ(obj)
    if isinstance(obj, BSplineSurface):
        return _surface_to_occ(obj)
    raise InvalidGeometryError(f"to_occ: expected a BSplineCurve or BSplineSurface, got {type(obj).__name__}")


def _check_dim(dim: int, what: str) -> None:
    if dim != 3:
        raise InvalidGeometryError(
            f"{what}: OpenCascade geometry is 3-D, got dim {dim} (Geom2d is out of scope; "
            "pad 2-D control points with a zero z column to place the spline in the plane z = 0)"
        )


def _curve_to_occ(c: BSplineCurve) -> Geom_BSplineCurve:
    _check_dim(c.dim, "to_occ(curve)")
    p = _occ.check_degree(c.degree, "degree")
    occ_knots, occ_mults = _occ.knots_to_occ(c.knots, p, "knots")
    occ_poles = _occ.pnt_array(c.control_points)
    with _occ.kernel_errors("to_occ: building Geom_BSplineCurve"):
        if c.weights is None:
            return Geom_BSplineCurve(occ_poles, occ_knots, occ_mults, p, False)
        return Geom_BSplineCurve(occ_poles, _occ.real_array(c.weights), occ_knots, occ_mults, p, False)


def _surface_to_occ(s: BSplineSurface) -> Geom_BSplineSurface:
    _check_dim(s.dim, "to_occ(surface)")
    p = _occ.check_degree(s.degree[0], "degree[0] (u)")
    q = _occ.check_degree(s.degree[1], "degree[1] (v)")
    occ_uk, occ_um = _occ.knots_to_occ(s.knots[0], p, "knots[0] (U)")
    occ_vk, occ_vm = _occ.knots_to_occ(s.knots[1], q, "knots[1] (V)")
    occ_poles = _occ.pnt_array2(s.control_points)
    with _occ.kernel_errors("to_occ: building Geom_BSplineSurface"):
        if s.weights is None:
            return Geom_BSplineSurface(occ_poles, occ_uk, occ_vk, occ_um, occ_vm, p, q, False, False)
        return Geom_BSplineSurface(occ_poles, _occ.real_array2(s.weights), occ_uk, occ_vk, occ_um, occ_vm,
                                   p, q, False, False)


# ================================================================================= OCC -> ours
def from_occ(obj: Any, bounds: tuple[float, ...] | None = None, *, tol: float | None = None,
             trims: bool = True
             ) -> BSplineCurve | BSplineSurface | TrimmedSurface | list[BSplineCurve | BSplineSurface | TrimmedSurface]:
    """Our B-spline equivalent of an OCC curve, surface, edge or face.

    Parameters
    ----------
    obj : Geom_Curve, Geom_Surface, TopoDS_Edge, TopoDS_Face, or a build123d / cadquery Edge / Face
        See the module docstring for what is exact. A shape holding faces (``TopoDS_Shell``,
        ``TopoDS_Solid``, ``TopoDS_Compound``, build123d / cadquery ``Shell``, ``Solid``,
        ``Compound``, ``Part``, a cadquery ``Workplane`` or ``Assembly``...; see
        :func:`occsurf.bridge.conversion.shapes.as_shape`) gives a list: each face converted, in
        ``TopExp_Explorer`` order, each once; a shape without faces, its edges likewise.
    bounds : tuple of float, optional
        ``(t0, t1)`` for a curve or edge, ``(u0, u1, v0, v1)`` for a surface or face: trim to this
        parameter box first. Required for unbounded geometry (plane, cylinder, line, ...).
    tol : float, optional
        3-D tolerance for offsets that must be approximated; default :data:`APPROX_TOLERANCE`.
    trims : bool, optional
        For a face without ``bounds``: return a trimmed face as a :class:`TrimmedSurface` (the
        surface plus its loops of p-curves, see :mod:`.trimming`) when its boundary is not the
        natural rectangle of its surface (default). ``False`` gives the surface alone (on the
        face's UV box for non-B-spline surfaces), as before trimmed faces existed. An untrimmed
        face, or any face with ``bounds``, gives a BSplineSurface either way.

    Returns
    -------
    BSplineCurve or BSplineSurface, or a list of them
        3-D. Bit-exact for OCC B-splines (periodic ones as their unclamped equivalent). A list for a
        shape that holds faces or edges (see ``obj``), even of one.

    Raises
    ------
    InvalidGeometryError
        Unsupported type (named), a null shape (``TopoDS_Face()``), 2-D geometry, missing or malformed
        ``bounds`` (or ``bounds`` with a shape of several faces), degenerated edge, ``tol`` not a
        positive finite number.
    ToleranceError
        An offset could not be approximated within ``tol``.
    KernelError
        OCC failed (e.g. ``bounds`` outside a non-periodic spline's range).
    """
    tol = APPROX_TOLERANCE if tol is None else _positive(tol, "tol")
    if not isinstance(obj, (TopoDS_Shape, Geom_Geometry)) and is_shape_like(obj):
        obj = as_shape(obj, "from_occ: obj")  # build123d / cadquery objects, Workplane, Assembly...
    if isinstance(obj, TopoDS_Shape):
        if obj.IsNull():  # every query of a null shape dereferences nothing: a segfault
            raise InvalidGeometryError(f"from_occ: the {type(obj).__name__} is null (an empty shape)")
        if obj.ShapeType() not in (TopAbs_FACE, TopAbs_EDGE):
            return _from_container(obj, bounds, tol, trims)
        return _from_shape(obj, bounds, tol, trims)
    if isinstance(obj, (Geom_Curve, Geom_Surface)):
        b = _check_bounds(bounds, 2, "curve") if isinstance(obj, Geom_Curve) else _check_bounds(bounds, 4, "surface")
        try:
            if isinstance(obj, Geom_Curve):
                return from_geom_curve(obj, b, tol)
            return from_geom_surface(obj, b, tol)
        except AttributeError as err:
            if "'NoneType'" not in str(err):
                raise
            # OCC's arrays came back as None: the wrapper holds no object (made by __new__, say)
            raise InvalidGeometryError(f"from_occ: the {type(obj).__name__} holds no geometry (a null or "
                                       "uninitialised handle: its poles read as None)") from err
    name = type(obj).__name__
    if name.startswith("Geom2d"):
        raise InvalidGeometryError(f"from_occ: 2-D geometry ({name}) is out of scope; expected 3-D Geom_* objects")
    raise InvalidGeometryError(
        f"from_occ: expected a Geom_Curve, Geom_Surface, TopoDS_Edge, TopoDS_Face or a build123d/cadquery "
        f"Edge/Face, got {name}"
    )


def _from_container(shape: TopoDS_Shape, bounds: Any, tol: float, trims: bool
                    ) -> list[BSplineCurve | BSplineSurface | TrimmedSurface]:
    """Every face of a shell, solid or compound converted (its edges if it has no face)."""
    if bounds is not None:
        raise InvalidGeometryError("bounds: applies to one face or edge; got a shape holding several "
                                   "(convert its faces one by one to trim each)")
    kind = TopAbs_FACE if TopExp_Explorer(shape, TopAbs_FACE).More() else TopAbs_EDGE
    items = TopTools_IndexedMapOfShape()
    TopExp.MapShapes_s(shape, kind, items)
    if items.Extent() == 0:
        raise InvalidGeometryError("from_occ: the shape holds no faces and no edges")
    return [_from_shape(items.FindKey(i), None, tol, trims) for i in range(1, items.Extent() + 1)]


def is_reversed(shape: Any) -> bool:
    """True if a face or edge (OCC, build123d or cadquery) has ``TopAbs_REVERSED`` orientation.

    ``from_occ`` ignores orientation; for a reversed face the outward normal is ``-S_u x S_v``.
    """
    if not isinstance(shape, TopoDS_Shape):
        if not is_shape_like(shape):
            raise InvalidGeometryError(f"is_reversed: expected a TopoDS_Shape or a build123d/cadquery shape, got {type(shape).__name__}")
        shape = as_shape(shape, "is_reversed: shape")
    if shape.IsNull():
        raise InvalidGeometryError(f"is_reversed: the {type(shape).__name__} is null (an empty shape)")
    return shape.Orientation() == TopAbs_REVERSED


def _positive(value: Any, name: str) -> float:
    """A positive, finite real (a NaN tolerance would disable every check that uses it)."""
    try:
        x = float(value)
    except (TypeError, ValueError) as err:
        raise InvalidGeometryError(f"{name}: expected a positive number, got {value!r}") from err
    if isinstance(value, bool) or not (np.isfinite(x) and x > 0):
        raise InvalidGeometryError(f"{name}: expected a positive, finite number, got {value!r}")
    return x


def _check_bounds(bounds: tuple[float, ...] | None, n: int, what: str) -> tuple[float, ...] | None:
    if bounds is None:
        return None
    try:
        b = tuple(float(x) for x in bounds)
    except (TypeError, ValueError) as err:
        raise InvalidGeometryError(f"bounds: expected {n} real numbers for a {what}, got {bounds!r}") from err
    if len(b) != n or not all(np.isfinite(b)) or any(b[i] >= b[i + 1] for i in range(0, n, 2)):
        form = "(t0, t1)" if n == 2 else "(u0, u1, v0, v1)"
        raise InvalidGeometryError(f"bounds: expected finite {form} with t0 < t1 for a {what}, got {bounds!r}")
    return b


def _from_shape(shape: TopoDS_Shape, bounds: tuple[float, ...] | None, tol: float, trims: bool = True
                ) -> BSplineCurve | BSplineSurface | TrimmedSurface:
    kind = shape.ShapeType()
    if kind == TopAbs_FACE:
        face = shape if isinstance(shape, TopoDS_Face) else TopoDS.Face_s(shape)
        b = _check_bounds(bounds, 4, "face")
        with _occ.kernel_errors("from_occ: reading the surface of a face"):
            occ_surface = BRep_Tool.Surface_s(face)  # Location applied (OCP_NOTES §2)
            if b is None and not isinstance(occ_surface, (Geom_BSplineSurface, Geom_BezierSurface)):
                b = BRepTools.UVBounds_s(face)
        if occ_surface is None:
            raise InvalidGeometryError("from_occ: the face has no surface")
        surface = from_geom_surface(occ_surface, b, tol)
        if bounds is not None or not trims:
            return surface
        from .trimming import face_from_occ

        with _occ.kernel_errors("from_occ: reading the trimming loops of a face"):
            box = BRepTools.UVBounds_s(face)
        return face_from_occ(face, surface, occ_surface, box)
    if kind == TopAbs_EDGE:
        edge = shape if isinstance(shape, TopoDS_Edge) else TopoDS.Edge_s(shape)
        b = _check_bounds(bounds, 2, "edge")
        with _occ.kernel_errors("from_occ: reading the curve of an edge"):
            occ_curve = BRep_Tool.Curve_s(edge, 0.0, 0.0)  # Location applied; range from Range_s
            first, last = BRep_Tool.Range_s(edge)
        if occ_curve is None:
            raise InvalidGeometryError("from_occ: the edge has no 3-D curve (degenerated edge, e.g. at a sphere's pole)")
        if b is None and not (
            isinstance(occ_curve, (Geom_BSplineCurve, Geom_BezierCurve))
            and (first, last) == (occ_curve.FirstParameter(), occ_curve.LastParameter())
        ):
            b = _check_bounds((first, last), 2, "edge")
        return from_geom_curve(occ_curve, b, tol)
    raise InvalidGeometryError(
        f"from_occ: expected a face or an edge, got a {str(kind).rsplit('_', 1)[-1].lower()} "
        "(iterate over its faces or edges)"
    )


def make_face(surface: BSplineSurface | TrimmedSurface | Geom_Surface, tol: float | None = None) -> TopoDS_Face:
    """An OCC ``TopoDS_Face`` bounded by the whole parameter domain of ``surface``, or by the loops
    of a :class:`TrimmedSurface` (rebuilt as :func:`.trimming.trimmed_to_occ_face` says: same
    wires, same edges per wire, seams and degenerated edges restored, 3-D curves built).

    The face :func:`to_face` and :func:`to_cq_face` wrap; use it directly to hand faces to OCC
    algorithms (sewing, filling, STEP export).

    Parameters
    ----------
    surface : BSplineSurface or Geom_Surface
        Ours is converted with :func:`to_occ` (bit-exact); an OCC surface is used as it is.
    tol : float, optional
        Edge tolerance for ``BRepBuilderAPI_MakeFace``, model units; default
        :data:`FACE_TOLERANCE` (read at call time).

    Returns
    -------
    TopoDS_Face

    Raises
    ------
    InvalidGeometryError
        ``surface`` is neither, or see :func:`to_occ`.
    KernelError
        ``BRepBuilderAPI_MakeFace`` failed.
    """
    if isinstance(surface, TrimmedSurface):
        from .trimming import trimmed_to_occ_face

        edge_tol = None if tol is None else _positive(tol, "tol")
        return trimmed_to_occ_face(surface, to_occ(surface.surface), edge_tol)
    occ_surface = surface if isinstance(surface, Geom_Surface) else _as_occ(surface, BSplineSurface, "surface")
    tol = FACE_TOLERANCE if tol is None else _positive(tol, "tol")
    with _occ.kernel_errors("building a face (BRepBuilderAPI_MakeFace)"):
        mf = BRepBuilderAPI_MakeFace(occ_surface, tol)
        if not mf.IsDone():
            raise KernelError(f"BRepBuilderAPI_MakeFace failed with status {mf.Error()}")
        return mf.Face()


def make_edge(curve: BSplineCurve | Geom_Curve) -> TopoDS_Edge:
    """An OCC ``TopoDS_Edge`` over the whole domain of ``curve`` (what :func:`to_edge` and
    :func:`to_cq_edge` wrap).

    Parameters
    ----------
    curve : BSplineCurve, Geom_Curve, or an edge
        Ours is converted with :func:`to_occ` (bit-exact); an OCC curve is used as it is; an edge
        (``TopoDS_Edge``, build123d / cadquery ``Edge``, a ``Wire`` of one edge) is returned as it is
        (:func:`occsurf.bridge.conversion.shapes.as_edge`), so ``to_edge(cq_edge)`` is the same edge.

    Returns
    -------
    TopoDS_Edge

    Raises
    ------
    InvalidGeometryError
        ``curve`` is neither, or see :func:`to_occ`.
    KernelError
        ``BRepBuilderAPI_MakeEdge`` failed.
    """
    if not isinstance(curve, (Geom_Curve, BSplineCurve)) and is_shape_like(curve):
        return as_edge(curve, "curve")
    occ_curve = curve if isinstance(curve, Geom_Curve) else _as_occ(curve, BSplineCurve, "curve")
    with _occ.kernel_errors("building an edge (BRepBuilderAPI_MakeEdge)"):
        me = BRepBuilderAPI_MakeEdge(occ_curve)
        if not me.IsDone():
            raise KernelError(f"BRepBuilderAPI_MakeEdge failed with status {me.Error()}")
        return me.Edge()


def _as_occ(obj: Any, cls: type[BSplineCurve] | type[BSplineSurface], name: str) -> Geom_Geometry:
    if not isinstance(obj, cls):
        raise InvalidGeometryError(f"{name}: expected a {cls.__name__} (or an OCC Geom object), got {type(obj).__name__}")
    return to_occ(obj)


def to_face(surface: BSplineSurface | TrimmedSurface | Geom_Surface, *, tol: float = FACE_TOLERANCE) -> bd.Face:
    """A build123d ``Face`` bounded by the whole parameter domain of ``surface``, or the trimmed
    face of a :class:`TrimmedSurface` (see :func:`make_face`).

    Parameters
    ----------
    surface : BSplineSurface or Geom_Surface
    tol : float
        Edge tolerance for ``BRepBuilderAPI_MakeFace``; default :data:`FACE_TOLERANCE`.

    Raises
    ------
    InvalidGeometryError
        Wrong type, or see :func:`to_occ`.
    KernelError
        ``BRepBuilderAPI_MakeFace`` failed.
    """
    import build123d as bd

    return bd.Face(make_face(surface, tol))


def to_edge(curve: BSplineCurve | Geom_Curve) -> bd.Edge:
    """A build123d ``Edge`` over the whole domain of ``curve`` (see :func:`to_face` for errors)."""
    import build123d as bd

    return bd.Edge(make_edge(curve))


def to_cq_face(surface: BSplineSurface | Geom_Surface, *, tol: float = FACE_TOLERANCE) -> cq.Face:
    """A cadquery ``Face`` bounded by the whole parameter domain of ``surface`` (as :func:`to_face`)."""
    import cadquery as cq

    return cq.Face(make_face(surface, tol))


def to_cq_edge(curve: BSplineCurve | Geom_Curve) -> cq.Edge:
    """A cadquery ``Edge`` over the whole domain of ``curve`` (as :func:`to_edge`)."""
    import cadquery as cq

    return cq.Edge(make_edge(curve))
