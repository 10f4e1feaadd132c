"""The one place where the objects users already hold become OCC shapes (and models).

Every bridge function that takes faces or a model accepts, through :func:`as_shape` /
:func:`as_model`:

==========================================  ==========================================================
``TopoDS_Shape`` (any type)                 itself
build123d / cadquery ``Shape``              its ``.wrapped`` (``Face``, ``Shell``, ``Solid``,
                                            ``Compound``, ``Edge``, ``Wire``, ``Part``, ``Sketch``...)
build123d ``BuildPart`` / ``BuildSketch``   the builder's object (``.part``, ``.sketch``, ``.line``)
/ ``BuildLine``
cadquery ``Workplane``                      a compound of the shapes on its stack (``.vals()``)
cadquery ``Assembly``                       ``toCompound()`` (every part placed)
:class:`~occsurf.bridge.ImportedModel`      its ``.shape``
a list or tuple of the above                a compound of them
==========================================  ==========================================================

Edges and curves alike (:func:`as_edges`, :func:`as_edge`, :func:`as_curve`), for the functions that
take an edge or a curve (``curve_deviation``, ``make_edge``/``to_edge``/``to_cq_edge``, the fill's
``assess_joint``, ``hole_sides``, ``occ_fill``, ``neighbour_face``): a ``TopoDS_Edge``, a build123d or
cadquery ``Edge`` or ``Wire`` (any object of the table above: its edges), or a bounded ``Geom_Curve``
(an edge over its whole parameter range).

:func:`as_model` goes further for the functions that report per face (``inspect_model``,
``check_model``, ``render_model_lit``...): an :class:`~occsurf.bridge.ImportedModel` passes
through, anything else becomes one whose faces carry the names and colours the objects hold
(build123d ``label``/``color`` along the ``children`` tree, cadquery assembly names/colours), built
by :func:`occsurf.bridge.exchange.object_import.model_from_object`.

A null shape, an empty Workplane and anything else are refused with an
:class:`~occsurf.algorithms.errors.InvalidGeometryError` naming the argument.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from OCP.BRep import BRep_Builder, BRep_Tool
from OCP.Geom import Geom_Curve
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE
from OCP.TopExp import TopExp
from OCP.TopoDS import TopoDS, TopoDS_Compound, TopoDS_Edge, TopoDS_Face, TopoDS_Shape
from OCP.TopTools import TopTools_IndexedMapOfShape

from occsurf.algorithms.errors import InvalidGeometryError

if TYPE_CHECKING:
    pass

__all__ = ["as_shape", "as_faces", "as_face", "as_edges", "as_edge", "as_curve", "is_shape_like", "is_edge_like",
           "compound"]

#: Attributes of build123d builders that hold the object built (BuildPart, BuildSketch, BuildLine).
_BUILDER_RESULTS = ("part", "sketch", "line")


def is_shape_like(obj: Any) -> bool:
    """True if :func:`as_shape` would accept ``obj``'s type (its content is not checked)."""
    return _unwrap(obj) is not None


def as_shape(obj: Any, name: str = "shape") -> TopoDS_Shape:
    """The OCC shape of ``obj`` (see the module table), never null.

    Parameters
    ----------
    obj : TopoDS_Shape, build123d/cadquery object, ImportedModel, or a list/tuple of them
    name : str
        The argument's name, for messages.

    Returns
    -------
    TopoDS_Shape
        ``obj`` itself for a ``TopoDS_Shape``; the shape it wraps; or a ``TopoDS_Compound`` of the
        shapes of a Workplane, an assembly or a sequence (locations kept, nothing copied).

    Raises
    ------
    InvalidGeometryError
        Not one of the accepted objects, an empty sequence or Workplane, or a null shape.
    """
    shape = _unwrap(obj, name)
    if shape is None:
        raise InvalidGeometryError(
            f"{name}: expected a TopoDS_Shape, a build123d or cadquery shape (Face, Shell, Solid, Compound...), "
            f"a cadquery Workplane or Assembly, a build123d builder or an ImportedModel; got {type(obj).__name__}"
        )
    if shape.IsNull():  # every query of a null shape dereferences nothing: a segfault
        raise InvalidGeometryError(f"{name}: the {type(obj).__name__} holds a null (empty) shape")
    return shape


def as_faces(obj: Any, name: str = "shape") -> list[Any]:
    """The faces of ``obj`` (any object :func:`as_shape` accepts) as ``TopoDS_Face``.

    ``TopExp_Explorer`` order, each face once (the numbering of ``occsurf inspect``), with the
    locations of the shapes that hold them.
    """
    faces = TopTools_IndexedMapOfShape()
    TopExp.MapShapes_s(as_shape(obj, name), TopAbs_FACE, faces)
    return [TopoDS.Face_s(faces.FindKey(i)) for i in range(1, faces.Extent() + 1)]


def as_face(obj: Any, name: str = "face") -> TopoDS_Face:
    """The one face of ``obj`` (any object :func:`as_shape` accepts) as a ``TopoDS_Face``.

    Raises
    ------
    InvalidGeometryError
        As :func:`as_shape`, or ``obj`` holds no face or more than one.
    """
    shape = as_shape(obj, name)
    if shape.ShapeType() == TopAbs_FACE:
        return TopoDS.Face_s(shape)  # itself, orientation and location kept
    faces = as_faces(shape, name)
    if len(faces) != 1:
        raise InvalidGeometryError(f"{name}: expected one face, got a {type(obj).__name__} with {len(faces)} faces")
    return faces[0]


def is_edge_like(obj: Any) -> bool:
    """True if :func:`as_edges` would accept ``obj``'s type: a ``Geom_Curve`` or a shape-like object."""
    return isinstance(obj, Geom_Curve) or is_shape_like(obj)


def as_edges(obj: Any, name: str = "edges") -> list[TopoDS_Edge]:
    """The edges of ``obj`` as ``TopoDS_Edge``: the edge equivalent of :func:`as_faces`.

    Parameters
    ----------
    obj : TopoDS_Edge, build123d/cadquery Edge or Wire, Geom_Curve, or anything :func:`as_shape` takes
        A ``Geom_Curve`` becomes one edge over its whole parameter range (``BRepBuilderAPI_MakeEdge``;
        the curve is shared, not copied); a shape gives its edges.
    name : str
        The argument's name, for messages.

    Returns
    -------
    list of TopoDS_Edge
        ``TopExp.MapShapes`` order, each edge once, with the locations of the shapes that hold them
        (a ``TopoDS_Edge`` or a build123d/cadquery ``Edge`` gives itself, orientation kept).

    Raises
    ------
    InvalidGeometryError
        Not an accepted object, a null shape, a shape without edges, or an unbounded curve.
    """
    if isinstance(obj, Geom_Curve):
        return [_edge_of_curve(obj, name)]
    shape = as_shape(obj, name)
    if isinstance(shape, TopoDS_Edge) or shape.ShapeType() == TopAbs_EDGE:
        return [TopoDS.Edge_s(shape)]
    edges = TopTools_IndexedMapOfShape()
    TopExp.MapShapes_s(shape, TopAbs_EDGE, edges)
    if edges.Extent() == 0:
        raise InvalidGeometryError(f"{name}: the {type(obj).__name__} holds no edges")
    return [TopoDS.Edge_s(edges.FindKey(i)) for i in range(1, edges.Extent() + 1)]


def as_edge(obj: Any, name: str = "edge") -> TopoDS_Edge:
    """The one edge of ``obj`` (see :func:`as_edges`): an edge, a curve, or a wire or shape of one edge.

    Raises
    ------
    InvalidGeometryError
        As :func:`as_edges`, or ``obj`` holds more than one edge.
    """
    edges = as_edges(obj, name)
    if len(edges) != 1:
        raise InvalidGeometryError(f"{name}: expected one edge (an Edge, a curve, or a Wire of one edge), got a "
                                   f"{type(obj).__name__} with {len(edges)} edges")
    return edges[0]


def as_curve(obj: Any, name: str = "curve") -> Geom_Curve:
    """The OCC curve of ``obj``: a ``Geom_Curve`` as it is, else the 3-D curve of :func:`as_edge`'s edge.

    The edge's location is applied (``BRep_Tool.Curve_s``: a transformed copy when the edge is
    placed); its orientation and range are not (as ``BRep_Tool.Surface_s`` for faces): the
    curve keeps its own parametrisation.

    Raises
    ------
    InvalidGeometryError
        As :func:`as_edge`, or the edge has no 3-D curve (a degenerated edge, e.g. at a sphere's pole).
    """
    if isinstance(obj, Geom_Curve):
        return obj
    edge = as_edge(obj, name)
    curve = BRep_Tool.Curve_s(edge, 0.0, 0.0)
    if curve is None:
        raise InvalidGeometryError(f"{name}: the edge has no 3-D curve (a degenerated edge, e.g. at a sphere's pole)")
    return curve


def _edge_of_curve(curve: Geom_Curve, name: str) -> TopoDS_Edge:
    """An edge over the whole range of a bounded curve."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeEdge
    from OCP.Precision import Precision

    t0, t1 = curve.FirstParameter(), curve.LastParameter()
    if Precision.IsInfinite_s(t0) or Precision.IsInfinite_s(t1):
        raise InvalidGeometryError(f"{name}: the {type(curve).__name__} is unbounded (trim it first, e.g. "
                                   "Geom_TrimmedCurve)")
    maker = BRepBuilderAPI_MakeEdge(curve)
    if not maker.IsDone():
        raise InvalidGeometryError(f"{name}: no edge can be made of this {type(curve).__name__} "
                                   f"(BRepBuilderAPI_MakeEdge status {maker.Error()})")
    return maker.Edge()


def compound(shapes: list[TopoDS_Shape]) -> TopoDS_Compound:
    """A ``TopoDS_Compound`` holding ``shapes`` (shared, not copied)."""
    comp = TopoDS_Compound()
    builder = BRep_Builder()
    builder.MakeCompound(comp)
    for s in shapes:
        builder.Add(comp, s)
    return comp


def _unwrap(obj: Any, name: str = "shape") -> TopoDS_Shape | None:
    """The shape of ``obj``, or ``None`` if its type is not accepted (nullness not checked)."""
    if isinstance(obj, TopoDS_Shape):
        return obj
    try:
        wrapped = getattr(obj, "wrapped", None)
    except AssertionError:  # an empty build123d shape (Compound()) asserts on .wrapped
        raise InvalidGeometryError(f"{name}: the {type(obj).__name__} is empty (no shape)") from None
    if isinstance(wrapped, TopoDS_Shape):  # build123d / cadquery Shape
        return wrapped
    shape = getattr(obj, "shape", None)  # ImportedModel
    if isinstance(shape, TopoDS_Shape) and isinstance(getattr(obj, "faces", None), list):
        return shape
    if isinstance(obj, (list, tuple)):
        if not obj:
            raise InvalidGeometryError(f"{name}: expected at least one shape, got an empty {type(obj).__name__}")
        return compound([as_shape(o, f"{name}[{i}]") for i, o in enumerate(obj)])
    if _is_class(obj, "cadquery"):
        if callable(getattr(obj, "toCompound", None)) and hasattr(obj, "children"):  # Assembly
            return obj.toCompound().wrapped
        if callable(getattr(obj, "vals", None)):  # Workplane
            parts = [v.wrapped for v in obj.vals() if isinstance(getattr(v, "wrapped", None), TopoDS_Shape)]
            if not parts:
                raise InvalidGeometryError(f"{name}: the cadquery Workplane holds no shapes")
            return parts[0] if len(parts) == 1 else compound(parts)
    if _is_class(obj, "build123d"):
        for attr in _BUILDER_RESULTS:
            if hasattr(type(obj), attr):
                result = getattr(obj, attr)
                if result is None:
                    raise InvalidGeometryError(f"{name}: the build123d {type(obj).__name__} has built nothing yet")
                return _unwrap(result, name)
    return None


def _is_class(obj: Any, package: str) -> bool:
    return type(obj).__module__.split(".", 1)[0] == package
