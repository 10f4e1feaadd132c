"""Imported models as the Python objects users already hold: build123d and cadquery shapes, and back.

:func:`to_build123d` and :func:`to_cadquery` are built from an
:class:`~occsurf.bridge.exchange.step_iges.ImportedModel`'s fields only (the shape, the faces'
names and colours, the assembly tree); ``read_step(path, as_="build123d")`` / ``as_="cadquery"``
(and ``read_iges``) call them. :func:`model_from_object` goes the other way: any build123d /
cadquery object (labels and colours included) becomes an ``ImportedModel``, which is how every
bridge function that reports per face accepts those objects
(:func:`as_model`).

What is carried
---------------
* **Assembly structure**: build123d gets a ``Compound`` per assembly node whose ``children`` are the
  instances, each moved to its placement; cadquery a sub-``Assembly`` per node, ``loc`` relative to
  its parent.
* **Instances**: one prototype shape per part, shared by its instances (the same ``TShape``, placed
  by the instance's location), so nothing is copied and cadquery writes the part once.
* **Names**: the ``label`` (build123d) / ``name`` (cadquery) of every node is the instance's name
  (build123d 0.12's own ``import_step`` gives every instance its part's name instead). cadquery
  needs names unique among siblings: repeats get ``_2``, ``_3``... Faces with their own names become
  cadquery subshape names.
* **Colours**: the ``color`` of every node is the instance's, else its part's, else the colour of
  its largest coloured face (a build123d shape has one colour; build123d's importer uses the same
  rule). cadquery also keeps every face whose colour differs from its node's as a subshape colour,
  so per-face colours survive there.
* **Layers**: cadquery subshape layers, per face (cadquery has no layer per node); build123d has no
  layers.

A flat file (no assembly) gives a root ``Compound`` / ``Assembly`` labelled with the file's stem,
one child per top-level shape of the file (a solid, a shell, a face, a wire), labelled with its
product's name. build123d's own ``import_step`` returns the child itself when there is only one;
here the type is always the same.
"""

from __future__ import annotations

import dataclasses
from collections import Counter
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from occsurf.algorithms.errors import InvalidGeometryError

if TYPE_CHECKING:
    from .model import ImportedFace, ImportedModel

__all__ = ["to_build123d", "to_cadquery", "model_from_object", "as_model", "convert_model", "shape_object", "AS_CHOICES"]

#: The values of ``read_step(..., as_=...)`` / ``fill_model(..., as_=...)`` besides ``None``.
AS_CHOICES: tuple[str, ...] = ("build123d", "cadquery")

RGBA = tuple[float, float, float, float]


def convert_model(model: ImportedModel, as_: str | None) -> Any:
    """``model`` itself for ``as_=None``, else :func:`to_build123d` / :func:`to_cadquery` of it.

    Raises
    ------
    InvalidGeometryError
        ``as_`` is not ``None``, ``'build123d'`` or ``'cadquery'``.
    """
    if as_ is None:
        return model
    check_as(as_)
    return to_build123d(model) if as_ == "build123d" else to_cadquery(model)


def check_as(as_: Any) -> None:
    """Refuse an ``as_`` value other than ``None`` or one of :data:`AS_CHOICES`, naming it."""
    if as_ is not None and (not isinstance(as_, str) or as_ not in AS_CHOICES):
        raise InvalidGeometryError(f"as_: expected None, 'build123d' or 'cadquery', got {as_!r}")


def shape_object(shape: Any, as_: str, *, solid: bool = True) -> Any:
    """An OCC shape as a build123d / cadquery object of its own kind, a closed shell as a Solid.

    Parameters
    ----------
    shape : TopoDS_Shape
    as_ : {'build123d', 'cadquery'}
    solid : bool, default True
        A single shell without free edges becomes a ``Solid`` (``BRepBuilderAPI_MakeSolid``, oriented
        outward with ``BRepLib::OrientClosedSolid``); an open shell stays a ``Shell``.

    Returns
    -------
    build123d or cadquery ``Solid``, ``Shell``, ``Face`` or ``Compound``
        Sharing the faces of ``shape`` (nothing is copied).
    """
    check_as(as_)
    from OCP.TopAbs import TopAbs_SHELL

    occ = shape
    if solid and occ.ShapeType() == TopAbs_SHELL and _is_closed(occ):
        occ = _solid(occ)
    if as_ == "build123d":
        import build123d as bd
        from build123d.importers import topods_lut
        from build123d.topology.shape_core import downcast

        occ = downcast(occ)
        return topods_lut.get(type(occ), bd.Compound)(occ)
    import cadquery as cq

    return cq.Shape.cast(occ)


def _is_closed(shell: Any) -> bool:
    """No free edges (``BRep_Tool.IsClosed`` on the shell checks exactly that)."""
    from OCP.BRep import BRep_Tool

    return bool(BRep_Tool.IsClosed_s(shell))


def _solid(shell: Any) -> Any:
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeSolid
    from OCP.BRepLib import BRepLib
    from OCP.TopoDS import TopoDS

    from .._occ import kernel_errors

    with kernel_errors("making a solid of the closed shell (BRepBuilderAPI_MakeSolid)"):
        maker = BRepBuilderAPI_MakeSolid(TopoDS.Shell_s(shell))
        if not maker.IsDone():
            return shell
        solid = maker.Solid()
        BRepLib.OrientClosedSolid_s(solid)
    return solid


# ------------------------------------------------------------------------------- OCC helpers
def _trsf(matrix: Any) -> Any:
    """``gp_Trsf`` of a ``(4, 4)`` placement matrix (rotation + translation, last row 0 0 0 1)."""
    from OCP.gp import gp_Trsf

    m = np.asarray(matrix, dtype=float)
    if m.shape != (4, 4) or not np.all(np.isfinite(m)):
        raise InvalidGeometryError(f"location: expected a finite (4, 4) matrix, got shape {m.shape}")
    t = gp_Trsf()
    t.SetValues(*m[:3].reshape(-1).tolist())
    return t


def _location(matrix: Any) -> Any:
    from OCP.TopLoc import TopLoc_Location

    return TopLoc_Location(_trsf(matrix))


def _face_index(model: ImportedModel) -> Any:
    """``TopTools_IndexedMapOfShape`` of the model's faces: ``FindIndex(face) - 1`` is the face's index."""
    from OCP.TopTools import TopTools_IndexedMapOfShape

    index = TopTools_IndexedMapOfShape()
    for f in model.faces:
        index.Add(f.face)
    return index


def _faces_of(shape: Any) -> Iterator[Any]:
    from OCP.TopAbs import TopAbs_FACE
    from OCP.TopExp import TopExp_Explorer

    ex = TopExp_Explorer(shape, TopAbs_FACE)
    while ex.More():
        yield ex.Current()
        ex.Next()


def _pieces(shape: Any) -> list[Any]:
    """The top-level shapes of a flat model: the members of its compound, else the shape itself.

    Fresh handles (same ``TShape``, same location): ``move`` on a build123d / cadquery object
    changes its handle in place, which must not move the model's own shape."""
    from OCP.TopAbs import TopAbs_COMPOUND
    from OCP.TopLoc import TopLoc_Location
    from OCP.TopoDS import TopoDS_Iterator

    identity = TopLoc_Location()
    if shape.ShapeType() != TopAbs_COMPOUND:
        return [shape.Moved(identity)]
    out, it = [], TopoDS_Iterator(shape)
    while it.More():
        out.append(it.Value().Moved(identity))
        it.Next()
    return out


def _extent(face: Any) -> float:
    from OCP.Bnd import Bnd_Box
    from OCP.BRepBndLib import BRepBndLib

    box = Bnd_Box()
    BRepBndLib.Add_s(face, box)
    return 0.0 if box.IsVoid() else box.SquareExtent()


def _largest_colour(faces: list[ImportedFace]) -> RGBA | None:
    """The colour of the largest coloured face (build123d's rule for one colour per shape)."""
    coloured = [f for f in faces if getattr(f, "color", None) is not None]
    if not coloured:
        return None
    return max(coloured, key=lambda f: _extent(f.face)).color


def _common(values: list[str | None]) -> str | None:
    """The most frequent non-empty value (the first of equals), ``None`` if there is none."""
    counts = Counter(v for v in values if v)
    return max(counts, key=counts.__getitem__) if counts else None


# ------------------------------------------------------------------------------- flat models
@dataclasses.dataclass
class _Piece:
    """A top-level shape of a flat model with what its faces carry."""

    shape: Any
    label: str | None
    color: RGBA | None
    faces: list[ImportedFace]


def _flat_pieces(model: ImportedModel) -> list[_Piece]:
    """One piece per top-level shape: label = its faces' (else its free edges') most common
    instance / name, colour = its largest coloured face's."""
    index = _face_index(model)
    edge_index = None
    if model.edges:
        from OCP.TopTools import TopTools_IndexedMapOfShape

        edge_index = TopTools_IndexedMapOfShape()
        for e in model.edges:
            edge_index.Add(e.edge)
    pieces = []
    for shape in _pieces(model.shape):
        faces = [model.faces[i - 1] for i in (index.FindIndex(f) for f in _faces_of(shape)) if i > 0]
        names = [_instance_leaf(f) or f.name for f in faces]
        if not faces and edge_index is not None:
            names = _edge_names(model, edge_index, shape)
        pieces.append(_Piece(shape, _common(names), _largest_colour(faces), faces))
    return pieces


def _edge_names(model: ImportedModel, edge_index: Any, shape: Any) -> list[str | None]:
    from OCP.TopAbs import TopAbs_EDGE
    from OCP.TopExp import TopExp_Explorer

    out, ex = [], TopExp_Explorer(shape, TopAbs_EDGE)
    while ex.More():
        i = edge_index.FindIndex(ex.Current())
        if i > 0:
            out.append(model.edges[i - 1].name)
        ex.Next()
    return out


def _instance_leaf(face: ImportedFace) -> str | None:
    inst = getattr(face, "instance", None)
    return inst.rsplit("/", 1)[-1] if inst else None


def _stem(model: ImportedModel) -> str:
    return Path(model.path).stem or "model"


# ------------------------------------------------------------------------------- assemblies
def _faces_by_instance(model: ImportedModel) -> dict[str, list[ImportedFace]]:
    out: dict[str, list[ImportedFace]] = {}
    for f in model.faces:
        inst = getattr(f, "instance", None)
        if inst:
            out.setdefault(inst, []).append(f)
    return out


def _child_path(path: str, child: Any) -> str:
    """The instance path of ``child`` (as :attr:`ImportedFace.instance` spells it)."""
    return f"{path}/{child.name}" if path else child.name


def _root_path(root: Any) -> str:
    """``''`` for the synthetic root of several free shapes (it has no part: the paths of the faces
    start at its children), else the root's name."""
    return root.name if root.part is not None else ""


# ------------------------------------------------------------------------------- build123d
def to_build123d(model: ImportedModel) -> Any:
    """The model as a build123d ``Compound`` tree with labels and colours.

    Parameters
    ----------
    model : ImportedModel
        From :func:`~occsurf.bridge.read_step` / :func:`~occsurf.bridge.read_iges`.

    Returns
    -------
    build123d.Compound
        An assembly: a ``Compound`` per assembly node (``label`` its name, ``color`` its colour),
        its ``children`` the instances, each moved to its placement; instances of one part share one
        prototype shape. A flat file: a ``Compound`` labelled with the file's stem whose children are
        the file's top-level shapes (``Solid``, ``Shell``, ``Face``, ``Wire``...) labelled with their
        product's name. A node without a colour of its own gets the colour of its largest coloured face.
        The faces are OCC's (the same ``TShape`` objects as ``model.faces[i].face``), so the geometry
        is the file's, bit for bit.

    Examples
    --------
    >>> part = occsurf.bridge.read_step("plates.step", as_="build123d")   # doctest: +SKIP
    >>> [(c.label, c.color) for c in part.children]                        # doctest: +SKIP
    [('plate_a', Color(1, 0, 0, 1)), ('plate_b', Color(1, 0, 0, 1))]
    """
    import build123d as bd

    root = getattr(model, "assembly", None)
    if root is None:
        out = bd.Compound(label=_stem(model))
        out.children = [_b3d_shape(p.shape, p.label, p.color) for p in _flat_pieces(model)]
        return out
    return _b3d_node(root, _root_path(root), _faces_by_instance(model))


def _b3d_shape(shape: Any, label: str | None, color: RGBA | None) -> Any:
    import build123d as bd
    from build123d.importers import topods_lut
    from build123d.topology.shape_core import downcast

    occ = downcast(shape)
    obj = topods_lut.get(type(occ), bd.Compound)(occ)
    obj.label = label or ""
    if color is not None:
        obj.color = _b3d_color(color)
    return obj


def _b3d_color(color: RGBA) -> Any:
    """A build123d ``Color`` holding ``color``, sRGB as the readers report it: ``bd.Color(r, g, b, a)``
    takes sRGB too (``Quantity_TOC_sRGB``), so the file's 0.2 is ``tuple(Color)``'s 0.2."""
    import build123d as bd

    from .xcaf import occ_color

    return bd.Color(occ_color(color))


def _b3d_node(node: Any, path: str, faces: dict[str, list[ImportedFace]]) -> Any:
    import build123d as bd

    color = node.color if node.color is not None else _largest_colour(faces.get(path, []))
    if node.children:
        obj = bd.Compound(label=node.name)
        obj.children = [_b3d_node(c, _child_path(path, c), faces) for c in node.children]
        if color is not None:
            obj.color = _b3d_color(color)
        obj.move(bd.Location(_location(node.location)))
        return obj
    if node.shape is None or node.shape.IsNull():
        return bd.Compound(label=node.name)  # an empty part: kept, so the tree has every node
    # A fresh handle per instance: the prototype's TShape is shared, its placement is not.
    return _b3d_shape(node.shape.Moved(_location(node.location)), node.name, color)


# ------------------------------------------------------------------------------- cadquery
def to_cadquery(model: ImportedModel) -> Any:
    """The model as a cadquery ``Assembly`` with names and colours.

    Parameters
    ----------
    model : ImportedModel

    Returns
    -------
    cadquery.Assembly
        An assembly: a sub-assembly per node (``name``, ``color``, ``loc`` relative to its parent),
        the parts' prototype shapes shared by their instances; faces whose own name or colour differs
        from their part's carried as subshape names / colours (``addSubshape``). A flat file: an
        assembly named after the file's stem with one child per top-level shape. Names are made unique
        among siblings (``_2``, ``_3``...), which cadquery requires.

    Examples
    --------
    >>> assy = occsurf.bridge.read_step("plates.step", as_="cadquery")     # doctest: +SKIP
    >>> [(c.name, c.color.toTuple()) for c in assy.children]               # doctest: +SKIP
    [('plate_a', (1.0, 0.0, 0.0, 1.0)), ('plate_b', (1.0, 0.0, 0.0, 1.0))]
    """
    import cadquery as cq

    root = getattr(model, "assembly", None)
    if root is None:
        assy = cq.Assembly(name=_stem(model))
        used: set[str] = set()
        for p in _flat_pieces(model):
            child = cq.Assembly(cq.Shape.cast(p.shape), name=_unique(p.label or "shape", used), color=_cq_color(p.color))
            _cq_subshapes(child, p.faces, p.label, p.color, None)
            assy.add(child)
        return assy
    return _cq_node(root, _root_path(root), _faces_by_instance(model), set(), {})


def _cq_color(color: RGBA | None) -> Any:
    import cadquery as cq

    return None if color is None else cq.Color(*color, True)  # sRGB, as the file states it and cadquery takes it


def _unique(name: str, used: set[str]) -> str:
    out, k = name, 1
    while out in used:
        k += 1
        out = f"{name}_{k}"
    used.add(out)
    return out


def _cq_node(node: Any, path: str, faces: dict[str, list[ImportedFace]], used: set[str],
             parts: dict[Any, Any]) -> Any:
    """The sub-assembly of ``node``; ``parts``: one cadquery shape per part key, shared by its
    instances (cadquery writes a part once per object and colour)."""
    import cadquery as cq
    from OCP.TopLoc import TopLoc_Location

    loc = cq.Location(_location(node.location))
    name = _unique(node.name or "node", used)
    if node.children or node.shape is None or node.shape.IsNull():
        assy = cq.Assembly(name=name, loc=loc, color=_cq_color(node.color))
        siblings: set[str] = set()
        for c in node.children:
            assy.add(_cq_node(c, _child_path(path, c), faces, siblings, parts))
        return assy
    own = faces.get(path, [])
    color = node.color if node.color is not None else _largest_colour(own)
    key = node.part if node.part is not None else id(node)
    if key not in parts:  # a fresh handle: moving the cadquery shape must not move the model's prototype
        parts[key] = cq.Shape.cast(node.shape.Moved(TopLoc_Location()))
    assy = cq.Assembly(parts[key], name=name, loc=loc, color=_cq_color(color))
    _cq_subshapes(assy, own, node.name, color, node.shape)  # cadquery has no node layer: every face's
    return assy


def _cq_subshapes(assy: Any, faces: list[ImportedFace], label: str | None, color: RGBA | None,
                  prototype: Any, layer: str | None = None) -> None:
    """Faces whose own name, colour or layer differs from their node's become subshape names /
    colours / layers.

    ``prototype``: the unlocated part shape whose faces the node's object holds (``None`` when the
    object is the located piece itself); an imported face is matched to it by its ``TShape``.
    """
    import cadquery as cq
    from OCP.TopLoc import TopLoc_Location
    from OCP.TopTools import TopTools_IndexedMapOfShape

    identity = TopLoc_Location()
    proto = None
    if prototype is not None:  # the prototype's faces by TShape (a map of the faces moved to the identity)
        proto = TopTools_IndexedMapOfShape()
        proto_faces: list[Any] = []  # TopoDS_Face
        for f in _faces_of(prototype):
            if proto.Add(f.Located(identity)) > len(proto_faces):
                proto_faces.append(f.Moved(identity))  # a fresh handle, placed as in the prototype
    for f in faces:
        name = f.name if f.name and f.name != label else None
        fcolor = getattr(f, "color", None)
        fcolor = fcolor if fcolor is not None and fcolor != color else None
        flayer = getattr(f, "layer", None)
        flayer = flayer if flayer and flayer != layer else None
        if name is None and fcolor is None and flayer is None:
            continue
        if proto is None:
            occ_face = f.face
        else:
            k = proto.FindIndex(f.face.Located(identity))
            if k == 0:
                continue
            occ_face = proto_faces[k - 1]
        assy.addSubshape(cq.Face(occ_face), name=name, color=_cq_color(fcolor), layer=flayer)


# ------------------------------------------------------------------------------- objects -> model
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
    the objects carry; see :func:`occsurf.bridge.exchange.objects.model_from_object`.

    Raises
    ------
    InvalidGeometryError
        As :func:`as_shape`; or the object holds no face and no edge.
    """
    from .model import ImportedModel

    if isinstance(obj, ImportedModel):
        return obj
    return model_from_object(obj, name)
