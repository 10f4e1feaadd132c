"""build123d and cadquery objects as imported models: :func:`model_from_object`, :func:`as_model`.

The way back of :mod:`.objects`: any build123d / cadquery object (a shape, a ``Compound`` with
``children``, an ``Assembly``; labels, colours and layers included) becomes an
:class:`~occsurf.bridge.exchange.step_iges.ImportedModel`, which is how every bridge function that
reports per face accepts those objects (:func:`as_model`).
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING, Any

import numpy as np

from occsurf.algorithms.errors import InvalidGeometryError

from .objects import AS_CHOICES, RGBA, _faces_of, _location

if TYPE_CHECKING:
    from .model import ImportedModel

__all__ = ["model_from_object", "as_model", "is_assembly_object"]


@dataclasses.dataclass
class _Leaf:
    """A part instance of a user's object placed where it is in the whole, with what it carries."""

    shape: Any  # TopoDS_Shape, global placement
    name: str | None
    color: RGBA | None
    instance: str | None
    subshapes: Any = None  # callable(face) -> (name, color, layer) of a subshape, or None


def model_from_object(obj: Any, name: str = "model") -> ImportedModel:
    """An :class:`ImportedModel` of any object :func:`~occsurf.bridge.conversion.shapes.as_shape`
    accepts, its faces and free edges converted as ``read_step`` converts them.

    A build123d ``Compound`` with ``children`` or a cadquery ``Assembly`` also gives the model's
    ``assembly`` tree (:class:`~occsurf.bridge.exchange.xcaf.AssemblyNode`: names, colours,
    placements relative to the parent, one part per shared shape), so
    ``write_step(path, model_from_object(obj))`` writes the structure as ``read_step`` reads it.
    Per face: ``name`` the nearest label (build123d) / node name (cadquery) or the face's own
    subshape name, ``color`` the nearest colour (as build123d and cadquery inherit colours) or the
    face's subshape colour, ``layer`` a cadquery subshape layer, ``instance`` the path of names from
    the root. ``path`` names the type (``'<build123d Compound>'``); ``format`` is ``'build123d'``,
    ``'cadquery'`` or ``'occ'``. Faces are numbered in ``TopExp_Explorer`` order over the placed parts.

    Raises
    ------
    InvalidGeometryError
        ``obj`` is not accepted (see ``as_shape``), or holds no face and no edge.
    """
    from ..conversion.shapes import as_shape, compound
    from . import model as si

    leaves: list[_Leaf] = []
    tree = _object_tree(obj, leaves)
    if not leaves:
        own = getattr(obj, "_color", None) if _package(obj) == "build123d" else None
        leaves = [_Leaf(as_shape(obj, name), _label_of(obj), _rgba(own), None)]
    shape = leaves[0].shape if len(leaves) == 1 else compound([leaf.shape for leaf in leaves])
    faces_map, edges_map = si._maps(shape)
    if faces_map.Extent() == 0 and edges_map.Extent() == 0:
        raise InvalidGeometryError(f"{name}: the {type(obj).__name__} holds no faces and no edges")
    meta: dict[int, tuple[Any, ...]] = {}
    for leaf in leaves:
        for f in _faces_of(leaf.shape):
            k = faces_map.FindIndex(f)
            if k > 0 and k not in meta:
                sub = leaf.subshapes(f) if leaf.subshapes is not None else (None, None, None)
                meta[k] = (sub[0] or leaf.name, sub[1] or leaf.color, sub[2], leaf.instance)
    faces = []
    for i in range(1, faces_map.Extent() + 1):
        fname, color, layer, instance = meta.get(i, (None, None, None, None))
        face = si._import_face(i - 1, faces_map.FindKey(i), fname)
        faces.append(_with(face, color=color, layer=layer, instance=instance))
    edges = [si._import_edge(i - 1, edges_map.FindKey(i), None) for i in range(1, edges_map.Extent() + 1)]
    package = _package(obj)
    fmt = package if package in AS_CHOICES else "occ"
    model = si.ImportedModel(path=f"<{package} {type(obj).__name__}>", format=fmt, shape=shape, faces=faces,
                             edges=edges)
    return _with(model, assembly=tree)


def _with(record: Any, **values: Any) -> Any:
    """``record`` (a dataclass) with the contract's optional fields set, where it has them."""
    names = {f.name for f in dataclasses.fields(record)}
    values = {k: v for k, v in values.items() if k in names and v is not None}
    return dataclasses.replace(record, **values) if values else record


def _package(obj: Any) -> str:
    return type(obj).__module__.split(".", 1)[0]


def _label_of(obj: Any) -> str | None:
    label = getattr(obj, "label", None) if _package(obj) == "build123d" else None
    return label or None


def _rgba(color: Any) -> RGBA | None:
    """RGBA of a build123d / cadquery colour: sRGB, the numbers ``bd.Color(r, g, b)`` / ``cq.Color(r, g, b)``
    were given and the file will state, rounded as the readers round them
    (:func:`~occsurf.bridge.exchange.xcaf.rgba_from_occ`: cadquery's ``toTuple`` gives 0.9999999999999999 for 1)."""
    if color is None:
        return None
    from OCP.Quantity import Quantity_ColorRGBA

    from .xcaf import rgba_from_occ

    occ = getattr(color, "wrapped", None)
    if isinstance(occ, Quantity_ColorRGBA):
        return rgba_from_occ(occ)
    values = tuple(float(x) for x in (color.toTuple() if hasattr(color, "toTuple") else tuple(color)))
    return values if len(values) == 4 else None


def _matrix(location: Any) -> np.ndarray:
    """``(4, 4)`` matrix of a ``TopLoc_Location``."""
    t = location.Transformation()
    m = np.eye(4)
    m[:3] = [[t.Value(i, j) for j in range(1, 5)] for i in range(1, 4)]
    return m


class _Parts:
    """Part keys: one per distinct shape (by ``TShape``, whatever the placement), named after the
    first instance, made unique with ``#2``, ``#3``... as the reader does."""

    def __init__(self) -> None:
        from OCP.TopTools import TopTools_IndexedMapOfShape

        self.bare = TopTools_IndexedMapOfShape()
        self.keys: list[str] = []
        self.used: set[str] = set()

    def key(self, name: str | None, shape: Any = None) -> str:
        from OCP.TopLoc import TopLoc_Location

        if shape is not None:
            k = self.bare.Add(shape.Located(TopLoc_Location()))
            if k <= len(self.keys):
                return self.keys[k - 1]
        base, n = name or "part", 1
        key = base
        while key in self.used:
            n += 1
            key = f"{base}#{n}"
        self.used.add(key)
        if shape is not None:
            self.keys.append(key)
        return key


def is_assembly_object(obj: Any) -> bool:
    """True for a build123d shape with ``children`` or a cadquery ``Assembly``: objects with a
    structure (names, colours, placements) that ``write_step`` / ``write_iges`` write as such."""
    if _package(obj) == "build123d":
        return bool(getattr(obj, "children", None))
    return _package(obj) == "cadquery" and callable(getattr(obj, "toCompound", None)) and hasattr(obj, "children")


def _object_tree(obj: Any, leaves: list[_Leaf]) -> Any:
    """The AssemblyNode tree of a build123d tree or a cadquery assembly (filling ``leaves``), else
    ``None`` (``leaves`` then holds the object itself for a labelled build123d shape)."""
    from .xcaf import AssemblyNode

    parts = _Parts()
    if _package(obj) == "build123d" and getattr(obj, "children", None):
        return _b3d_tree(AssemblyNode, obj, np.eye(4), "", None, None, parts, leaves, root=True)
    if _package(obj) == "cadquery" and callable(getattr(obj, "toCompound", None)) and hasattr(obj, "children"):
        return _cq_tree(AssemblyNode, obj, np.eye(4), "", None, parts, leaves, root=True)
    return None


def _placed(shape: Any, matrix: np.ndarray) -> Any:
    from OCP.TopLoc import TopLoc_Location

    return shape.Located(TopLoc_Location()) if np.array_equal(matrix, np.eye(4)) else shape.Located(_location(matrix))


def _b3d_tree(Node: Any, node: Any, parent: np.ndarray, path: str, label: str | None, color: RGBA | None,
              parts: _Parts, leaves: list[_Leaf], root: bool = False) -> Any:
    """build123d: ``location`` of a child is relative to its parent; labels and colours inherited."""
    from OCP.TopLoc import TopLoc_Location

    try:
        wrapped = node.wrapped
    except AssertionError:  # an empty build123d shape
        return None
    if wrapped is None or wrapped.IsNull():
        return None
    name = node.label or ""
    here = f"{path}/{name}" if path else name
    own = _rgba(node._color) if getattr(node, "_color", None) is not None else None
    label, color = node.label or label, own or color
    local = _matrix(wrapped.Location())
    placed = parent @ local
    if root:  # the root's own placement goes to its children: a root is written unplaced
        local = np.eye(4)
    if node.children:
        kids = [_b3d_tree(Node, c, placed, here, label, color, parts, leaves) for c in node.children]
        kids = [k for k in kids if k is not None]
        shape = wrapped.Located(TopLoc_Location())
        return Node(name, own, None, local if not root else np.eye(4), parts.key(name or "assembly"), shape,
                    tuple(kids))
    proto = wrapped.Located(TopLoc_Location())
    leaves.append(_Leaf(_placed(proto, placed), label, color, here or None))
    if root:
        return Node(name, own, None, np.eye(4), parts.key(name, proto), wrapped, ())
    return Node(name, own, None, local, parts.key(name, proto), proto, ())


def _cq_tree(Node: Any, assy: Any, parent: np.ndarray, path: str, color: RGBA | None, parts: _Parts,
             leaves: list[_Leaf], root: bool = False) -> Any:
    """cadquery: ``loc`` relative to the parent, colours inherited (as ``Assembly.__iter__``); a node
    with an object and children gets its object as a first child named ``<name>_part`` (as
    cadquery's own STEP export does)."""
    from OCP.TopLoc import TopLoc_Location

    name = assy.name
    here = f"{path}/{name}" if path else name
    own = _rgba(assy.color) if assy.color is not None else None
    color = own or color
    local = np.eye(4) if root else _matrix(assy.loc.wrapped)
    placed = parent @ (_matrix(assy.loc.wrapped) if root else local)
    kids = []
    shapes = [s.wrapped for s in assy.shapes]
    if shapes:
        from ..conversion.shapes import compound

        obj = shapes[0] if len(shapes) == 1 else compound(shapes)
        obj_local = _matrix(obj.Location())
        proto = obj.Located(TopLoc_Location())
        subshapes = _cq_subshape_lookup(assy)
        if assy.children:  # the object as a part of its own below this node
            part_name = f"{name}_part"
            leaves.append(_Leaf(_placed(proto, placed @ obj_local), name, color, f"{here}/{part_name}", subshapes))
            kids.append(Node(part_name, None, None, obj_local, parts.key(part_name, proto), proto, ()))
        else:
            leaves.append(_Leaf(_placed(proto, placed @ obj_local), name, color, here, subshapes))
            if root:  # a root is written unplaced: its placement stays on its shape
                return Node(name, own, None, np.eye(4), parts.key(name, proto), _placed(proto, placed @ obj_local), ())
            return Node(name, own, None, local @ obj_local, parts.key(name, proto), proto, ())
    kids += [k for k in (_cq_tree(Node, c, placed, here, color, parts, leaves) for c in assy.children)
             if k is not None]
    from ..conversion.shapes import compound

    shape = compound([k.shape.Located(_location(k.location)) for k in kids]) if kids else None
    if shape is None:
        return None
    return Node(name, own, None, local, parts.key(name), shape, tuple(kids))


def _cq_subshape_lookup(assy: Any) -> Any:
    names, colors, layers = assy._subshape_names, assy._subshape_colors, assy._subshape_layers
    if not (names or colors or layers):
        return None

    def lookup(face: Any) -> tuple[str | None, RGBA | None, str | None]:
        return _bidict_get(names, face), _rgba(_bidict_get(colors, face)), _bidict_get(layers, face)

    return lookup


def _bidict_get(mapping: Any, face: Any) -> Any:
    """The value cadquery keeps for a subshape that is ``face`` (same TShape, any placement)."""
    for shape, value in mapping.items():
        if shape.wrapped.IsPartner(face):
            return value
    return None


def as_model(obj: Any, name: str = "model") -> ImportedModel:
    """``obj`` as an :class:`~occsurf.bridge.ImportedModel`: itself if it is one, else the model of
    its faces and free edges (converted as ``read_step`` converts them) with the names and colours
    the objects carry; see :func:`occsurf.bridge.exchange.object_import.model_from_object`.

    Raises
    ------
    InvalidGeometryError
        As :func:`as_shape`; or the object holds no face and no edge.
    """
    from .model import ImportedModel

    if isinstance(obj, ImportedModel):
        return obj
    return model_from_object(obj, name)
