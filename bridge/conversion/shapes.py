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

:func:`as_model` goes further for the functions that report per face (``inspect_model``,
``check_model``, ``render_model_lit``...): an :class:`~occsurf.bridge.ImportedModel` passes
through, anything else becomes one whose faces carry the names and colours the objects hold
(build123d ``label``/``color`` along the ``children`` tree, cadquery assembly names/colours), built
by :func:`occsurf.bridge.exchange.objects.model_from_object`.

A null shape, an empty Workplane and anything else are refused with an
:class:`~occsurf.algorithms.errors.InvalidGeometryError` naming the argument.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from OCP.BRep import BRep_Builder
from OCP.TopAbs import TopAbs_FACE
from OCP.TopExp import TopExp
from OCP.TopoDS import TopoDS, TopoDS_Compound, TopoDS_Shape
from OCP.TopTools import TopTools_IndexedMapOfShape

from occsurf.algorithms.errors import InvalidGeometryError

if TYPE_CHECKING:
    from ..exchange.step_iges import ImportedModel

__all__ = ["as_shape", "as_faces", "is_shape_like", "compound"]

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
