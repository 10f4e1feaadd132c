"""Imported models as the Python objects users already hold: build123d and cadquery shapes, and back.

:func:`to_build123d` and :func:`to_cadquery` are built from an
:class:`~occsurf.bridge.exchange.step_iges.ImportedModel`'s fields only (the shape, the faces'
names and colours, the assembly tree); ``read_step(path, as_="build123d")`` / ``as_="cadquery"``
(and ``read_iges``) call them. :func:`.object_import.model_from_object` goes the other way: any build123d /
cadquery object (labels and colours included) becomes an ``ImportedModel``, which is how every
bridge function that reports per face accepts those objects
(:func:`.object_import.as_model`).

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

__all__ = ["to_build123d", "to_cadquery", "convert_model", "shape_object", "AS_CHOICES", "RGBA"]

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
