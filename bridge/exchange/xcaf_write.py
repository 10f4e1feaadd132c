"""Writing side of :mod:`occsurf.bridge.exchange.xcaf`: an XCAF document from a model or a tree, then STEP or IGES.

:func:`build_document` rebuilds the document of an :class:`~occsurf.bridge.exchange.step_iges.ImportedModel`
(its assembly tree, or its roots when it is flat) or of an :class:`~occsurf.bridge.exchange.xcaf.AssemblyNode`:
each part once (``XCAFDoc_ShapeTool.AddShape``), instances as components referring to it with their
placements, names on parts, instances and faces, colours and layers on instances, parts and faces (only
where a face differs from its instance). :func:`step_document_bytes` writes it with
``STEPCAFControl_Writer`` and prints the model with 17 significant digits;
:func:`iges_document_bytes` flattens it first (IGES has no instances: each part instance becomes a
placed copy named after the instance, every face with its own colour and layer) and writes it with
``IGESCAFControl_Writer``.

Per-occurrence colours: a part or sub-assembly is written once, from its first occurrence; an
occurrence of a nested component whose colour differs gets an SHUO (:meth:`_Writer.overrides`),
which OCC's STEP writer makes a ``SPECIFIED_HIGHER_USAGE_OCCURRENCE`` styled in its context, and
IGES (no instances) a placed copy of its own colour. Free curves carry their curve colour and layer
on their part's sub-shape labels (IGES: on the placed copies).

A part is written without locations inside it (:func:`_unlocated_items`: a located member of a
compound becomes a moved copy): OCC's STEP writer drops the colour of a moved instance of a part
whose members are located (every build123d primitive is a compound holding a located solid).

What OCC cannot carry, measured: a layer on an instance (component or SHUO label) is not written
(``STEPCAFControl_Writer::WriteLayers`` skips reference labels; a layer set on a placed shape lands
on the part), so a part carries the layer of its first instance
(:func:`.xcaf.instance_layer_losses`); a face coloured in one instance only has no XCAF form (no
sub-shape labels under a component; OCC's reader turns a face style in the context of an instance
into the whole instance's colour), so a part's face colours are those of its first instance and
the rest is reported by ``occsurf convert``; a part without a name would be named 'Open CASCADE
STEP translator 7.9 n', so it gets an empty product name; IGES has no transparency and its layers
are level numbers (occsurf names each level with a 406 form 3 property, :func:`_add_level_names`).
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from occsurf.algorithms.errors import ExchangeError

from ..messages import one_line
from .xcaf import (
    _IDENTITY,
    _OCC_UNIT,
    AssemblyNode,
    _distinct,
    _location,
    instance_overrides,
    iter_nodes,
    label_entry,
    main_shuos,
    node_key,
    occ_color,
    shuo_chain,
)

__all__ = ["build_document", "step_document_bytes", "iges_document_bytes"]


def _set_name(label: Any, name: str | None, names: set[str] | None = None) -> None:
    from OCP.TCollection import TCollection_ExtendedString
    from OCP.TDataStd import TDataStd_Name

    # always a name, if empty: else OCC's writer names the product 'Open CASCADE STEP translator 7.9 n'
    TDataStd_Name.Set_s(label, TCollection_ExtendedString(name or "", True))
    if names is not None and name:
        names.add(name)


def _set_color(color_tool: Any, label: Any, rgba: Sequence[float] | None, *, curve: bool = False,
               generic: bool = False) -> None:
    from OCP.XCAFDoc import XCAFDoc_ColorType

    if rgba is None:
        return
    color = occ_color(rgba)  # sRGB, the numbers the file will state
    kind = XCAFDoc_ColorType.XCAFDoc_ColorCurv if curve else XCAFDoc_ColorType.XCAFDoc_ColorSurf
    if generic:  # an instance's colour: its faces' and its free curves'
        kind = XCAFDoc_ColorType.XCAFDoc_ColorGen
    color_tool.SetColor(label, color, kind)


def _set_layer(layer_tool: Any, label: Any, layer: str | None) -> None:
    from OCP.TCollection import TCollection_ExtendedString

    if layer:
        layer_tool.SetLayer(label, TCollection_ExtendedString(layer, True))


class _Writer:
    """An XCAF document built from a model (or a tree): prototypes once, instances as references."""

    def __init__(self, explicit: bool = False) -> None:
        from OCP.TCollection import TCollection_ExtendedString
        from OCP.TDocStd import TDocStd_Document
        from OCP.XCAFDoc import XCAFDoc_DocumentTool

        self.doc = TDocStd_Document(TCollection_ExtendedString("XCAF"))
        self.shape_tool = XCAFDoc_DocumentTool.ShapeTool_s(self.doc.Main())
        self.color_tool = XCAFDoc_DocumentTool.ColorTool_s(self.doc.Main())
        self.layer_tool = XCAFDoc_DocumentTool.LayerTool_s(self.doc.Main())
        self.shape_tool.SetAutoNaming_s(False)
        #: every face gets its resolved colour and layer on its own label (IGES: the writer does not
        #: pass a part's colour on to all its faces)
        self.explicit = explicit
        self.protos: dict[str, Any] = {}
        self.proto_shapes: dict[str, Any] = {}
        #: the shape each part is written as (:func:`_unlocated_items` of its shape)
        self.written: dict[str, Any] = {}
        #: an assembly prototype's component labels
        self.components: dict[str, list[Any]] = {}
        #: face names to set on the written face entities: (prototype face, name)
        self.face_names: list[tuple[Any, str]] = []
        #: every name given to a label (the products OCC names itself are the others)
        self.names: set[str] = set()

    def proto(self, node: AssemblyNode) -> Any:
        key = node_key(node)
        if key in self.protos:
            return self.protos[key]
        if node.children:
            label = self.shape_tool.NewShape()
            comps = self.components[key] = []
            for child in node.children:
                comp = self.shape_tool.AddComponent(label, self.proto(child), _location(child.location))
                _set_name(comp, child.name, self.names)
                _set_color(self.color_tool, comp, child.color, generic=True)
                comps.append(comp)
        else:
            self.written[key] = _unlocated_items(node.shape)
            label = self.shape_tool.AddShape(self.written[key], False, False)
        _set_name(label, node.part or node.name, self.names)
        # OCC's STEP writer drops layers of instances (components): the part carries the layer of its
        # first instance; an instance on another layer than its part's first instance loses it
        _set_layer(self.layer_tool, label, node.layer)
        self.protos[key] = label
        self.proto_shapes[key] = node.shape
        return label

    def overrides(self, root: AssemblyNode) -> int:
        """Per-occurrence colours (SHUO) of the tree written from ``root``
        (:func:`.xcaf.instance_overrides`: a sub-assembly is written once, from its first
        occurrence): ``XCAFDoc_ShapeTool::SetSHUO`` on the occurrence's component path, coloured;
        OCC's STEP writer makes it a ``SPECIFIED_HIGHER_USAGE_OCCURRENCE`` whose representation is the
        context of a ``STYLED_ITEM``'s ``PRESENTATION_STYLE_BY_CONTEXT`` (an ``OVER_RIDING_STYLED_ITEM``
        when the part has a style of its own). Returns how many were set."""
        n = 0
        for _, indices, rgba in instance_overrides(root):
            labels, node = [], root
            for i in indices:
                labels.append(self.components[node_key(node)][i])
                node = node.children[i]
            n += self.set_shuo(tuple(labels), rgba)
        return n

    def set_shuo(self, path: tuple[Any, ...], rgba: Sequence[float]) -> int:
        """Colour the occurrence reached through the component labels ``path`` (upper first)."""
        from OCP.TDF import TDF_LabelSequence
        from OCP.XCAFDoc import XCAFDoc_GraphNode

        seq = TDF_LabelSequence()
        for comp in path:
            seq.Append(comp)
        want = tuple(label_entry(comp) for comp in path)
        if not any(shuo_chain(s) == want for s in main_shuos(path[0])):
            # (OCP does not hand the new attribute back through the out-argument: found below)
            self.shape_tool.SetSHUO(seq, XCAFDoc_GraphNode())
        for shuo in main_shuos(path[0]):
            if shuo_chain(shuo) == want:
                _set_color(self.color_tool, shuo, rgba, generic=True)
                return 1
        return 0

    def edges(self, label: Any, proto_shape: Any, target_shape: Any, edges: Sequence[Any]) -> None:
        """Curve colours and layers of the free edges of a part (``label``, written as ``target_shape``:
        the part itself, or a placed copy with its sub-shapes in the same explorer order), from the
        model's ``edges`` that are edges of ``proto_shape`` (the first one of a part edge wins)."""
        from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE
        from OCP.TopLoc import TopLoc_Location
        from OCP.TopTools import TopTools_IndexedMapOfShape

        attributed = [e for e in edges if e.color is not None or e.layer is not None]
        if not attributed:
            return
        identity = TopLoc_Location()
        bare = TopTools_IndexedMapOfShape()
        for e in _distinct(proto_shape, TopAbs_EDGE, TopAbs_FACE):
            bare.Add(e.Located(identity))
        targets = _distinct(target_shape, TopAbs_EDGE, TopAbs_FACE)
        if len(targets) != bare.Extent():
            return
        done: set[int] = set()
        for e in attributed:
            j = bare.FindIndex(e.edge.Located(identity))
            if not j or j in done:
                continue
            done.add(j)
            # a part that is one free edge (an IGES root curve) carries its colour itself
            same = targets[j - 1].IsSame(target_shape)
            sub = label if same else self.shape_tool.AddSubShape(label, targets[j - 1])
            if sub is not None and not sub.IsNull():
                _set_color(self.color_tool, sub, e.color, curve=True)
                _set_layer(self.layer_tool, sub, e.layer)

    def faces(self, key: str, node: AssemblyNode, faces: list[Any]) -> None:
        """Face-level colours, layers and names of one part (``faces``: ImportedFace of one of its instances)."""
        from OCP.TopAbs import TopAbs_FACE
        from OCP.TopExp import TopExp_Explorer
        from OCP.TopLoc import TopLoc_Location
        from OCP.TopTools import TopTools_IndexedMapOfShape

        label = self.protos[key]
        bare = TopTools_IndexedMapOfShape()
        ex = TopExp_Explorer(node.shape, TopAbs_FACE)
        identity = TopLoc_Location()
        first: dict[int, int] = {}  # index in bare -> explorer position of the face's first occurrence
        position = 0
        while ex.More():
            first.setdefault(bare.Add(ex.Current().Located(identity)), position)
            position += 1
            ex.Next()
        # the faces of the shape written for the part (the same explorer order as node.shape's)
        proto_faces = _explore_faces(self.written.get(key, node.shape))
        if len(proto_faces) != position:
            return
        for f in faces:
            j = bare.FindIndex(f.face.Located(identity))
            if not j:
                continue
            pf = proto_faces[first[j]]
            own_name = f.name if f.name and f.name != node.name else None
            if f.color is None and f.layer is None and own_name is None:
                continue
            if f.color != node.color or f.layer != node.layer or self.explicit:
                sub = self.shape_tool.AddSubShape(label, pf)
                if sub is not None and not sub.IsNull():
                    if f.color != node.color or self.explicit:
                        _set_color(self.color_tool, sub, f.color)
                    if f.layer != node.layer or self.explicit:
                        _set_layer(self.layer_tool, sub, f.layer)
                    if own_name is not None and self.explicit:  # IGES: the face entity's name
                        _set_name(sub, own_name, self.names)
            if own_name is not None:
                self.face_names.append((pf, own_name))

    def copy_faces(self, label: Any, leaf: AssemblyNode, proto_faces: list[Any], copy_faces: list[Any],
                   faces: list[Any]) -> None:
        """Face colours and layers on a placed copy (faces in the same explorer order as the part's)."""
        from OCP.TopLoc import TopLoc_Location
        from OCP.TopTools import TopTools_IndexedMapOfShape

        identity = TopLoc_Location()
        bare = TopTools_IndexedMapOfShape()
        for pf in proto_faces:
            bare.Add(pf.Located(identity))
        for f in faces:
            j = bare.FindIndex(f.face.Located(identity))
            own_name = f.name if f.name and f.name != leaf.name else None
            if not j or (f.color is None and f.layer is None and own_name is None):
                continue
            sub = self.shape_tool.AddSubShape(label, copy_faces[j - 1])
            if sub is not None and not sub.IsNull():
                _set_color(self.color_tool, sub, f.color)
                _set_layer(self.layer_tool, sub, f.layer)
                if own_name is not None:
                    _set_name(sub, own_name, self.names)


def _unlocated_items(shape: Any) -> Any:
    """``shape`` with every shape inside its compounds unplaced: a compound's located member is
    replaced by a copy whose geometry is moved (``BRepBuilderAPI_Transform(..., copy=True)``), so a
    part holds no ``TopLoc_Location`` below its own. ``shape`` itself when nothing inside is located.

    Why (issue 16): ``STEPCAFControl_Writer`` looks up the STEP item of each member of a coloured
    instance at the member's location composed with the instance's; it finds the item when that is
    the member's own location or the identity, so the colour of a moved instance of a part with a
    located member (every build123d primitive: a compound holding a located solid) was not written.
    The STEP writer bakes such locations into the written geometry anyway; the copy keeps the
    ``TopExp_Explorer`` order of the faces and edges.
    """
    from OCP.BRep import BRep_Builder
    from OCP.BRepBuilderAPI import BRepBuilderAPI_Transform
    from OCP.TopAbs import TopAbs_COMPOUND
    from OCP.TopLoc import TopLoc_Location
    from OCP.TopoDS import TopoDS_Compound, TopoDS_Iterator

    identity = TopLoc_Location()

    def located_inside(s: Any) -> bool:
        it = TopoDS_Iterator(s, False, False)
        while it.More():
            member = it.Value()
            if not member.Location().IsIdentity():
                return True
            if member.ShapeType() == TopAbs_COMPOUND and located_inside(member):
                return True
            it.Next()
        return False

    def rebuilt(s: Any) -> Any:  # s: a compound, placed relative to the part
        builder, out = BRep_Builder(), TopoDS_Compound()
        builder.MakeCompound(out)
        it = TopoDS_Iterator(s, False, True)  # members placed relative to the part, own orientation
        while it.More():
            member = it.Value()
            if member.ShapeType() == TopAbs_COMPOUND:
                member = rebuilt(member).Oriented(member.Orientation())
            elif not member.Location().IsIdentity():
                trsf = member.Location().Transformation()
                member = BRepBuilderAPI_Transform(member.Located(identity), trsf, True).Shape()
            builder.Add(out, member)
            it.Next()
        return out

    if shape.ShapeType() != TopAbs_COMPOUND or not located_inside(shape):
        return shape
    out = rebuilt(shape.Located(identity))
    out.Orientation(shape.Orientation())
    return out.Located(shape.Location())


def _explore_faces(shape: Any) -> list[Any]:
    from OCP.TopAbs import TopAbs_FACE
    from OCP.TopExp import TopExp_Explorer

    out = []
    ex = TopExp_Explorer(shape, TopAbs_FACE)
    while ex.More():
        out.append(ex.Current())
        ex.Next()
    return out


def _by_instance(items: Sequence[Any]) -> dict[str, list[Any]]:
    """ImportedFace or ImportedEdge of each leaf instance path."""
    out: dict[str, list[Any]] = {}
    for item in items:
        if item.instance is not None:
            out.setdefault(item.instance, []).append(item)
    return out


def _flat_tree(model: Any, name: str) -> AssemblyNode:
    """A flat model as a one-level tree: one part per top-level shape (the file's roots)."""
    from OCP.TopAbs import TopAbs_COMPOUND
    from OCP.TopoDS import TopoDS_Iterator

    shape = model.shape
    parts = []
    if shape.ShapeType() == TopAbs_COMPOUND:
        it = TopoDS_Iterator(shape)
        while it.More():
            parts.append(it.Value())
            it.Next()
    # a located root would become an assembly instance in XCAF: keep such a model as one shape
    if len(parts) < 2 or any(not part.Location().IsIdentity() for part in parts):
        parts = [shape]
    return AssemblyNode(name, None, None, _IDENTITY, None, shape, tuple(
        AssemblyNode("", None, None, _IDENTITY, None, part) for part in parts))


def _flattened(root: AssemblyNode) -> list[tuple[str, AssemblyNode, AssemblyNode]]:
    """The tree with every part instance as a placed copy of its part, directly below the root
    (IGES has no instances: what its writer would do anyway, but with each copy keeping its name):
    ``(path, original part instance, copy)`` per part instance."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_Transform

    leaves: list[tuple[str, AssemblyNode, AssemblyNode]] = []

    def walk(node: AssemblyNode, placed: np.ndarray, path: str, color: Any, layer: Any) -> None:
        here = f"{path}/{node.name}" if path else node.name
        placed = placed @ node.location
        color, layer = node.color or color, node.layer or layer
        if node.children:
            for child in node.children:
                walk(child, placed, here, color, layer)
            return
        shape = node.shape
        if not np.array_equal(placed, _IDENTITY):
            shape = BRepBuilderAPI_Transform(node.shape, _location(placed).Transformation(), True).Shape()
        leaves.append((here, node, AssemblyNode(node.name, color, layer, _IDENTITY, f"\0{here}", shape)))

    walk(root, _IDENTITY, "", None, None)
    return leaves


def build_document(source: Any, name: str, *, flatten: bool = False) -> _Writer:
    """The XCAF document of an ImportedModel (its tree, or its roots when flat) or an AssemblyNode;
    ``flatten``: instances as placed copies, every face with its own colour and layer (for IGES)."""
    from OCP.TopAbs import TopAbs_FACE
    from OCP.TopExp import TopExp_Explorer

    writer = _Writer(explicit=flatten)
    if isinstance(source, AssemblyNode):
        root, model = source, None
    else:
        model = source
        root = model.assembly
    if root is not None and flatten:
        faces = _by_instance(model.faces) if model is not None else {}
        edges = _by_instance(model.edges) if model is not None else {}
        for here, original, leaf in _flattened(root):
            label = writer.shape_tool.AddShape(leaf.shape, False, False)
            _set_name(label, leaf.name, writer.names)
            _set_color(writer.color_tool, label, leaf.color)
            _set_layer(writer.layer_tool, label, leaf.layer)
            writer.protos[leaf.part] = label  # type: ignore[index]
            writer.edges(label, original.shape, leaf.shape, edges.get(here, []))
            copy_faces = _explore_faces(leaf.shape)
            proto_faces = _explore_faces(original.shape)
            if len(copy_faces) != len(proto_faces) or here not in faces:
                continue
            writer.copy_faces(label, leaf, proto_faces, copy_faces, faces[here])
        return writer
    if root is not None:
        writer.proto(root)
        writer.overrides(root)
        if model is not None:
            faces, edges = _by_instance(model.faces), _by_instance(model.edges)
            done: set[str] = set()
            for path, node in iter_nodes(root):
                key = node_key(node)
                if not node.children and key not in done and (path in faces or path in edges):
                    # a part's faces and curves once, as its first instance has them: OCC's XCAF has no
                    # sub-shape colours per instance, and another instance's must not recolour the first's
                    done.add(key)
                    writer.faces(key, node, faces.get(path, []))
                    writer.edges(writer.protos[key], node.shape, writer.written.get(key, node.shape),
                                 edges.get(path, []))
        writer.shape_tool.UpdateAssemblies()
        return writer
    # flat: one free shape per root, with the faces' common name/colour/layer on it
    tree = _flat_tree(model, name)
    from OCP.TopTools import TopTools_IndexedMapOfShape

    index = TopTools_IndexedMapOfShape()
    for f in model.faces:
        index.Add(f.face)
    for k, part in enumerate(tree.children):
        members = []
        ex = TopExp_Explorer(part.shape, TopAbs_FACE)
        while ex.More():
            j = index.FindIndex(ex.Current())
            if j:
                members.append(model.faces[j - 1])
            ex.Next()
        colors = {f.color for f in members}
        layers = {f.layer for f in members}
        # the part is named after most of its faces (an IGES group read back: its faces carry the
        # group's name but for those with their own, which stay face names); a face without a name
        # would inherit it, so then the part has none
        counted = Counter(f.name for f in members)
        common_name = counted.most_common(1)[0][0] if counted and None not in counted else None
        common_color = next(iter(colors)) if len(colors) == 1 else None
        common_layer = next(iter(layers)) if len(layers) == 1 else None
        node = replace(part, name=common_name or part.name, part=f"\0flat{k}", color=common_color,
                       layer=common_layer)
        label = writer.shape_tool.AddShape(node.shape, False, False)
        _set_name(label, node.name, writer.names)
        _set_color(writer.color_tool, label, node.color)
        _set_layer(writer.layer_tool, label, node.layer)
        writer.protos[node.part] = label
        writer.faces(node.part, node, members)
        writer.edges(label, node.shape, node.shape, model.edges)
    return writer


def _unname_products(model: Any, names: set[str]) -> None:
    """Products OCC named itself ('Open CASCADE STEP translator 7.9 n': the part had no name) get ''."""
    from OCP.StepBasic import StepBasic_Product
    from OCP.TCollection import TCollection_HAsciiString

    empty = TCollection_HAsciiString("")
    for k in range(1, model.NbEntities() + 1):
        ent = model.Value(k)
        if isinstance(ent, StepBasic_Product) and ent.Name() is not None:
            if ent.Name().ToCString() not in names:
                ent.SetName(empty)
                ent.SetId(empty)


def step_document_bytes(p: Path, source: Any, digits: int, unit: str) -> bytes:
    """STEP (AP214) of an ImportedModel or AssemblyNode through ``STEPCAFControl_Writer``, reals
    printed with ``digits`` significant digits, lengths in ``unit`` (values divided by its size in mm)."""
    from OCP.STEPCAFControl import STEPCAFControl_Writer
    from OCP.STEPConstruct import STEPConstruct
    from OCP.STEPControl import STEPControl_StepModelType
    from OCP.TCollection import TCollection_HAsciiString
    from OCP.TopLoc import TopLoc_Location
    from OCP.XSControl import XSControl_WorkSession

    from . import occ_io

    with occ_io.statics({"write.step.unit": _OCC_UNIT[unit], "write.stepcaf.subshapes.name": 1}):
        built = build_document(source, p.stem)
        session = XSControl_WorkSession()
        caf = STEPCAFControl_Writer(session, False)
        for mode in ("SetNameMode", "SetColorMode", "SetLayerMode"):
            getattr(caf, mode)(True)
        try:
            ok = caf.Transfer(built.doc, STEPControl_StepModelType.STEPControl_AsIs)
        except Exception as err:  # noqa: BLE001
            raise ExchangeError(f"{p}: STEP translation failed: {one_line(err)}") from err
        if not ok:
            raise ExchangeError(f"{p}: STEP translation failed")
        ws = caf.ChangeWriter().WS()
        _unname_products(ws.Model(), built.names)
        finder = ws.TransferWriter().FinderProcess()
        for face, name in built.face_names:
            item = STEPConstruct.FindEntity_s(finder, face, TopLoc_Location())
            if item is not None:
                item.SetName(TCollection_HAsciiString(name))
        return occ_io.print_step(p, ws, digits)


def _level_numbers(layer_tool: Any) -> dict[str, int]:
    """The level number OCC's ``IGESCAFControl_Writer`` gives each layer that holds shapes (its
    ``WriteLayers``, OCC 7.9): a layer named by an integer is that level; the others get the next
    numbers above the largest such integer, in the document's layer order."""
    from OCP.TCollection import TCollection_AsciiString, TCollection_ExtendedString
    from OCP.TDF import TDF_LabelSequence

    labels = TDF_LabelSequence()
    layer_tool.GetLayerLabels(labels)
    named: list[str] = []
    numbers: dict[str, int] = {}
    for i in range(1, labels.Length() + 1):
        text = TCollection_ExtendedString()
        shapes = TDF_LabelSequence()
        layer_tool.GetShapesOfLayer_s(labels.Value(i), shapes)
        if not layer_tool.GetLayer(labels.Value(i), text) or shapes.Length() == 0:
            continue
        ascii_name = TCollection_AsciiString(text, "?")
        if ascii_name.IsIntegerValue():
            numbers[TCollection_AsciiString(text).ToCString()] = ascii_name.IntegerValue()
        else:
            named.append(TCollection_AsciiString(text).ToCString())
    top = max(numbers.values(), default=0)
    for k, name in enumerate(named, start=1):
        numbers.setdefault(name, top + k)
    return numbers


def _add_level_names(model: Any, layer_tool: Any) -> None:
    """A Level Function property (IGES 5.3 §4.98, entity 406 form 3: "the meaning or intended use of a
    level") on each level OCC numbered for a named layer, with the layer's name as its description:
    IGES levels are numbers, so without it the layer 'cap' reads back as '1'. OCC's reader ignores
    these entities (:func:`.xcaf.iges_level_names` reads them); characters outside ASCII become '_'
    (as in OCC's own IGES names)."""
    from OCP.IGESData import IGESData_FreeFormatEntity
    from OCP.Interface import Interface_ParamType

    for name, level in _level_numbers(layer_tool).items():
        if name == str(level):
            continue
        text = "".join(c if 32 <= ord(c) < 127 else "_" for c in name)
        entity = IGESData_FreeFormatEntity()
        entity.SetTypeNumber(406)
        entity.SetFormNumber(3)
        entity.AddLiteral(Interface_ParamType.Interface_ParamInteger, "2")  # number of property values
        entity.AddLiteral(Interface_ParamType.Interface_ParamInteger, "0")  # function code: none
        entity.AddLiteral(Interface_ParamType.Interface_ParamText, f"{len(text)}H{text}")
        entity.InitLevel(None, level)  # the property describes the level it is on
        model.AddEntity(entity)


def iges_document_bytes(p: Path, source: Any, unit: str) -> bytes:
    """IGES of an ImportedModel or AssemblyNode through ``IGESCAFControl_Writer`` (instances become
    placed copies), lengths in ``unit``."""
    import io

    from OCP.IGESCAFControl import IGESCAFControl_Writer
    from OCP.TCollection import TCollection_HAsciiString

    from . import occ_io

    with occ_io.statics({"write.iges.unit": _OCC_UNIT[unit], "write.iges.brep.mode": 0}):
        built = build_document(source, p.stem, flatten=True)
        caf = IGESCAFControl_Writer()
        for mode in ("SetNameMode", "SetColorMode", "SetLayerMode"):
            getattr(caf, mode)(True)
        try:
            ok = caf.Transfer(built.doc)
            _add_level_names(caf.Model(), built.layer_tool)
            header = caf.Model().GlobalSection()
            header.SetFileName(TCollection_HAsciiString(p.name))
            caf.Model().SetGlobalSection(header)
            buffer = io.BytesIO()
            ok = ok and caf.Write(buffer)
        except Exception as err:  # noqa: BLE001
            raise ExchangeError(f"{p}: IGES translation failed: {one_line(err)}") from err
    data = buffer.getvalue()
    if not ok or not data:
        raise ExchangeError(f"{p}: writing the IGES model failed")
    return data


