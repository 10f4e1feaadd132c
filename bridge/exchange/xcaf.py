"""XCAF (OCC's Extended Data Exchange) side of STEP/IGES: names, colours, layers, units, assemblies.

:func:`occsurf.bridge.exchange.step_iges.read_step` and ``read_iges`` parse a file with
``STEPCAFControl_Reader`` / ``IGESCAFControl_Reader``: the geometry is transferred root by root exactly
as before (faces keep their order), then the same transfer is put into an XCAF document
(``TDocStd_Document``) from which this module takes

* the **length unit the file declares** (before OCC converts the values to millimetres): STEP's
  ``LENGTH_UNIT`` of the representation contexts (``STEPControl_Reader.FileUnits``: SI prefixes and
  conversion-based units such as ``INCH``), IGES's global-section unit flag;
* the **assembly tree**: products and their instances (STEP ``NEXT_ASSEMBLY_USAGE_OCCURRENCE``), each
  instance a *reference* to a shared prototype (two instances of one part have the same
  :attr:`AssemblyNode.part` and the same :attr:`AssemblyNode.shape`), with its placement;
* **per-instance colour overrides** of nested instances (STEP's ``SPECIFIED_HIGHER_USAGE_OCCURRENCE``
  styled through an ``OVER_RIDING_STYLED_ITEM``, what CATIA, NX or SolidWorks write when one
  occurrence of a part inside a sub-assembly is coloured differently; OCC's SHUO,
  ``XCAFDoc_ColorTool::SetInstanceColor``): the :attr:`AssemblyNode.color` of that occurrence, and so
  the colour of the faces of its placed copy;
* per face: the **colour** (face colour > solid/shell colour > instance colour (an override of the
  occurrence first) > part colour, walking up the tree), the **layer** (the same order; the first of
  several), and the **instance path** from the root ('assembly/plate_a');
* per free edge (a curve bounding no face): its **curve colour** (edge > wire/compound > instance >
  part, curve or generic colours only) and **layer**.

Writing (:func:`.xcaf_write.step_document_bytes`, :func:`.xcaf_write.iges_document_bytes`) rebuilds an XCAF document from an
:class:`~occsurf.bridge.exchange.step_iges.ImportedModel` or an :class:`AssemblyNode` tree
(prototypes once, instances as references, colours, layers, names) and writes it with
``STEPCAFControl_Writer`` (printed with 17 significant digits, as ``write_step``) or
``IGESCAFControl_Writer`` (IGES has no instances: each instance becomes a placed copy); the
writing side is :mod:`occsurf.bridge.exchange.xcaf_write`.

This module reads the document (:func:`read_xcaf`, colours, the tree's walk); beside it live the
assembly tree and :class:`XcafData` (:mod:`.xcaf_tree`), the length units (:mod:`.xcaf_units`) and
IGES names and levels (:mod:`.xcaf_iges`). Their public names stay importable from here.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from occsurf.algorithms.errors import InvalidGeometryError

from ..messages import one_line
from .xcaf_iges import _NO_NAMES, iges_face_attributes, iges_level_names, name_levels
from .xcaf_tree import (
    _IDENTITY,
    AssemblyNode,
    XcafData,
    instance_layer_losses,
    instance_overrides,
    iter_nodes,
    node_key,
)
from .xcaf_units import _OCC_UNIT, UNITS, WRITE_UNITS, iges_unit, step_unit, unit_scale

__all__ = ["AssemblyNode", "UNITS", "WRITE_UNITS", "unit_scale", "XcafData", "read_xcaf", "step_unit", "iges_unit", "compound",
           "iter_nodes", "instance_overrides", "instance_layer_losses", "COLOR_DECIMALS", "rgba_from_occ", "occ_color",
           # from the modules the XCAF side was split into (importable from here before)
           "node_key", "iges_face_attributes", "iges_level_names", "name_levels", "_OCC_UNIT", "_IDENTITY", "_NO_NAMES"]

#: Decimals to which the RGB of a colour read is rounded (:func:`rgba_from_occ`). OCC holds colours as
#: linear RGB in float32 and converts from and to the file's sRGB: the file's 0.2 comes back from
#: ``Values(Quantity_TOC_sRGB)`` as 0.19999999868, 1 as 0.9999999999999999 (measured: at most 1.93e-8
#: off over 20 000 random values in [0, 1], 1.8e-8 over every 8-bit value, 1.6e-8 over every
#: percentage). Rounding to 7 decimals therefore gives back exactly every value the file states with
#: up to 7 decimals (0.2, 0.5, 1, 128/255 to 7 decimals) and any other within 5e-8 + 2e-8; build123d's
#: ``tuple(Color)`` rounds to 7 decimals too.
COLOR_DECIMALS: int = 7


# ---------------------------------------------------------------------------------------- reading
def _label_name(label: Any) -> str | None:
    from OCP.TCollection import TCollection_AsciiString
    from OCP.TDataStd import TDataStd_Name

    # IsAttribute first: FindAttribute of an absent name crashed OCP on labels read from IGES
    if label.IsNull() or not label.IsAttribute(TDataStd_Name.GetID_s()):
        return None
    attr = TDataStd_Name()
    if not label.FindAttribute(TDataStd_Name.GetID_s(), attr):
        return None
    # AsciiString of an ExtendedString is its UTF-8 (ToExtString() crashed on names read from IGES)
    text = TCollection_AsciiString(attr.Get()).ToCString().strip()
    return None if text in _NO_NAMES or text.startswith("=>[") else text


def rgba_from_occ(color: Any) -> tuple[float, float, float, float]:
    """The RGBA a file states for an OCC colour: sRGB, as STEP ``COLOUR_RGB``, IGES 314 and build123d's
    and cadquery's ``Color`` give it.

    Parameters
    ----------
    color : Quantity_ColorRGBA
        OCC's colour (linear RGB in float32, OCC >= 7.5).

    Returns
    -------
    (float, float, float, float)
        ``(r, g, b, alpha)`` in [0, 1]: ``Values(Quantity_TOC_sRGB)`` rounded to :data:`COLOR_DECIMALS`
        decimals, alpha as OCC holds it (float32).
    """
    from OCP.Quantity import Quantity_TypeOfColor

    r, g, b = color.GetRGB().Values(Quantity_TypeOfColor.Quantity_TOC_sRGB)
    return (round(float(r), COLOR_DECIMALS), round(float(g), COLOR_DECIMALS), round(float(b), COLOR_DECIMALS),
            float(color.Alpha()))


def occ_color(rgba: Sequence[float]) -> Any:
    """The OCC colour (``Quantity_ColorRGBA``) of sRGB values ``(r, g, b, alpha)`` in [0, 1], the
    file's numbers: ``Quantity_Color(r, g, b, Quantity_TOC_sRGB)`` (OCC converts to linear RGB and its
    writers back to sRGB; see :data:`COLOR_DECIMALS` for what that keeps)."""
    from OCP.Quantity import Quantity_Color, Quantity_ColorRGBA, Quantity_TypeOfColor

    r, g, b, a = (float(x) for x in rgba)
    return Quantity_ColorRGBA(Quantity_Color(r, g, b, Quantity_TypeOfColor.Quantity_TOC_sRGB), a)



def _label_color(label: Any, surface: bool = True) -> tuple[float, float, float, float] | None:
    from OCP.Quantity import Quantity_ColorRGBA
    from OCP.XCAFDoc import XCAFDoc_ColorTool, XCAFDoc_ColorType

    kinds = (XCAFDoc_ColorType.XCAFDoc_ColorSurf, XCAFDoc_ColorType.XCAFDoc_ColorGen)
    if not surface:
        kinds = (XCAFDoc_ColorType.XCAFDoc_ColorCurv, XCAFDoc_ColorType.XCAFDoc_ColorGen)
    color = Quantity_ColorRGBA()
    for kind in kinds:
        if XCAFDoc_ColorTool.GetColor_s(label, kind, color):
            return rgba_from_occ(color)
    return None


def _label_layer(layer_tool: Any, label: Any) -> str | None:
    from OCP.TCollection import TCollection_AsciiString

    seq = layer_tool.GetLayers(label)
    if seq is None or seq.Length() == 0:
        return None
    return TCollection_AsciiString(seq.Value(1)).ToCString()


def _matrix(location: Any) -> np.ndarray:
    """4x4 matrix of a ``TopLoc_Location``."""
    trsf = location.Transformation()
    m = np.eye(4)
    for i in range(3):
        for j in range(4):
            m[i, j] = trsf.Value(i + 1, j + 1)
    return m


def label_entry(label: Any) -> str:
    """The label's entry ('0:1:1:2:1'): its identity within the document."""
    from OCP.TCollection import TCollection_AsciiString
    from OCP.TDF import TDF_Tool

    entry = TCollection_AsciiString()
    TDF_Tool.Entry_s(label, entry)
    return entry.ToCString()


def shuo_chain(shuo: Any) -> tuple[str, ...]:
    """The component path a main SHUO label (``XCAFDoc_GraphNode``) styles: the entries of the
    components it and its next usages are attached to, upper first (OCC keeps each SHUO node as a
    child label of its component)."""
    from OCP.TDF import TDF_LabelSequence
    from OCP.XCAFDoc import XCAFDoc_ShapeTool

    chain = [label_entry(shuo.Father())]
    current = shuo
    while len(chain) < 64:  # an assembly deeper than that, or a cycle, is not a chain OCC writes
        nxt = TDF_LabelSequence()
        if not XCAFDoc_ShapeTool.GetSHUONextUsage_s(current, nxt) or nxt.Length() == 0:
            break
        current = nxt.Value(1)
        chain.append(label_entry(current.Father()))
    return tuple(chain)


def main_shuos(component: Any) -> list[Any]:
    """The SHUO labels whose chain starts at ``component`` (the ones the writer styles)."""
    from OCP.TDF import TDF_AttributeSequence, TDF_LabelSequence
    from OCP.XCAFDoc import XCAFDoc_ShapeTool

    attrs = TDF_AttributeSequence()
    if not XCAFDoc_ShapeTool.GetAllComponentSHUO_s(component, attrs):
        return []
    out = []
    for i in range(1, attrs.Length() + 1):
        label = attrs.Value(i).Label()
        upper = TDF_LabelSequence()
        XCAFDoc_ShapeTool.GetSHUOUpperUsage_s(label, upper)
        if upper.Length() == 0 and label.Father().IsEqual(component):
            out.append(label)
    return out


class _Index:
    """Faces or free edges of the model: the map, the sub-shapes by bare shape, which are taken."""

    def __init__(self, index_map: Any, bare: Any) -> None:
        self.map = index_map
        self.bare = bare
        self.mats: dict[int, np.ndarray] = {}
        self.assigned: set[int] = set()


class _Reader:
    """One pass over an XCAF document: the tree, then every leaf's faces and free edges matched to
    the model's."""

    def __init__(self, doc: Any, faces_map: Any, bare: Any, edges: tuple[Any, Any] | None = None) -> None:
        from OCP.XCAFDoc import XCAFDoc_DocumentTool

        self.shape_tool = XCAFDoc_DocumentTool.ShapeTool_s(doc.Main())
        self.layer_tool = XCAFDoc_DocumentTool.LayerTool_s(doc.Main())
        self.faces = _Index(faces_map, bare)
        self.edges = _Index(*edges) if edges is not None else None
        self.data = XcafData()
        self.parts: dict[str, str] = {}  # label entry -> part key
        self._part_names: set[str] = set()
        self._sub_attributes: dict[str, tuple[_SubAttributes, _SubAttributes]] = {}
        #: colour of each SHUO met so far, by the component path it styles (label entries, upper first)
        self._shuos: dict[tuple[str, ...], tuple[float, float, float, float]] = {}
        self._n_unmatched = 0
        #: whether the document holds an assembly (else faces get no instance path)
        self.in_assembly = False

    def part_key(self, label: Any) -> str:
        key = label_entry(label)
        if key not in self.parts:
            base = _label_name(label) or f"part {key}"
            name, k = base, 1
            while name in self._part_names:
                k += 1
                name = f"{base}#{k}"
            self._part_names.add(name)
            self.parts[key] = name
        return self.parts[key]

    def override(self, components: tuple[str, ...]) -> tuple[float, float, float, float] | None:
        """The SHUO colour of the occurrence at the end of ``components`` (the upper-most wins)."""
        for start in range(len(components) - 1):
            color = self._shuos.get(components[start:])
            if color is not None:
                return color
        return None

    def node(self, label: Any, parent: np.ndarray, path: str, inherited: list[tuple[Any, Any, Any]],
             top: bool, components: tuple[str, ...] = ()) -> AssemblyNode:
        """The node of a free or component label; walks its components, matches its faces and edges.

        ``inherited``: ``(surface colour, curve colour, layer)`` of the ancestors, nearest first;
        ``components``: the entries of the component labels from the root down to the parent."""
        from OCP.TDF import TDF_Label, TDF_LabelSequence
        from OCP.XCAFDoc import XCAFDoc_ShapeTool

        proto = label
        local = _IDENTITY
        if XCAFDoc_ShapeTool.IsReference_s(label):
            proto = TDF_Label()
            XCAFDoc_ShapeTool.GetReferredShape_s(label, proto)
            local = _matrix(XCAFDoc_ShapeTool.GetLocation_s(label))
            components = (*components, label_entry(label))
            for shuo in main_shuos(label):  # registered before the occurrences below it are met
                color = _label_color(shuo)
                if color is not None:
                    self._shuos.setdefault(shuo_chain(shuo), color)
        name = _label_name(label) or _label_name(proto) or self.part_key(proto)
        here = f"{path}/{name}" if path else name
        color = self.override(components) or _label_color(label) or _label_color(proto)
        curve = self.override(components) or _label_color(label, False) or _label_color(proto, False)
        layer = _label_layer(self.layer_tool, label) or _label_layer(self.layer_tool, proto)
        chain = [(color, curve, layer), *inherited]  # the occurrence first, then its ancestors
        placed = parent @ local
        children: list[AssemblyNode] = []
        if XCAFDoc_ShapeTool.IsAssembly_s(proto):
            comps = TDF_LabelSequence()
            XCAFDoc_ShapeTool.GetComponents_s(proto, comps)
            children = [self.node(comps.Value(i), placed, here, chain, False, components)
                        for i in range(1, comps.Length() + 1)]
        else:
            self.leaf(proto, placed, here if not top or self.in_assembly else None, name, chain)
        return AssemblyNode(name=name, color=color, layer=layer, location=local, part=self.part_key(proto),
                            shape=XCAFDoc_ShapeTool.GetShape_s(proto), children=tuple(children))

    def leaf(self, proto: Any, placed: np.ndarray, path: str | None, name: str,
             chain: list[tuple[Any, Any, Any]]) -> None:
        """Colour, layer and instance of each face, colour and layer of each free edge, of a part
        instance placed at ``placed``."""
        from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE
        from OCP.XCAFDoc import XCAFDoc_ShapeTool

        key = self.part_key(proto)
        if key not in self._sub_attributes:  # once per part, however many instances
            self._sub_attributes[key] = (self.sub_shape_attributes(proto, TopAbs_FACE),
                                         self.sub_shape_attributes(proto, TopAbs_EDGE))
        face_attributes, edge_attributes = self._sub_attributes[key]
        inherited_color = next((c for c, _, _ in chain if c), None)
        inherited_curve = next((c for _, c, _ in chain if c), None)
        inherited_layer = next((x for _, _, x in chain if x), None)
        shape = XCAFDoc_ShapeTool.GetShape_s(proto)
        # k: the position sub_shape_attributes keys by
        kinds = [(self.faces, _distinct(shape, TopAbs_FACE), face_attributes, inherited_color,
                  self.data.colors, self.data.layers, self.data.instances)]
        if self.edges is not None:
            kinds.append((self.edges, _distinct(shape, TopAbs_EDGE, TopAbs_FACE), edge_attributes, inherited_curve,
                          self.data.edge_colors, self.data.edge_layers, self.data.edge_instances))
        for index, members, (own_color, own_layer, own_name), inherited, colors, layers, instances in kinds:
            for k, member in enumerate(members, start=1):
                i = self.match(index, member, placed)
                if i is None:
                    continue
                color = own_color.get(k) or inherited
                layer = own_layer.get(k) or inherited_layer
                if color is not None:
                    colors.setdefault(i, color)
                if layer is not None:
                    layers.setdefault(i, layer)
                if k in own_name:
                    self.data.face_names.setdefault(i, own_name[k])
                if path is not None:
                    instances.setdefault(i, path)
                    if index is self.faces:
                        self.data.instance_names.setdefault(i, name)

    def sub_shape_attributes(self, proto: Any, kind: Any) -> _SubAttributes:
        """Colours and layers of a prototype's sub-shape labels for its faces (``kind`` TopAbs_FACE) or
        free edges (TopAbs_EDGE: curve colours), the sub-shape's own level winning over a containing
        sub-shape's (solid, shell, wire, compound), and face names; keyed by the sub-shape's 1-based
        position in ``TopExp_Explorer`` order over the prototype (each once)."""
        from OCP.TDF import TDF_LabelSequence
        from OCP.TopAbs import TopAbs_FACE
        from OCP.TopTools import TopTools_IndexedMapOfShape
        from OCP.XCAFDoc import XCAFDoc_ShapeTool

        subs = TDF_LabelSequence()
        XCAFDoc_ShapeTool.GetSubShapes_s(proto, subs)
        colors: dict[int, Any] = {}
        layers: dict[int, str] = {}
        names: dict[int, str] = {}
        if subs.Length() == 0:
            return colors, layers, names
        avoid = TopAbs_FACE if kind != TopAbs_FACE else None
        members_map = TopTools_IndexedMapOfShape()  # position k of each member = its map index
        for member in _distinct(XCAFDoc_ShapeTool.GetShape_s(proto), kind, avoid):
            members_map.Add(member)
        surface = kind == TopAbs_FACE
        own_level: tuple[dict[int, Any], dict[int, str]] = ({}, {})
        other_level: tuple[dict[int, Any], dict[int, str]] = ({}, {})
        for i in range(1, subs.Length() + 1):
            sub = subs.Value(i)
            color, layer = _label_color(sub, surface), _label_layer(self.layer_tool, sub)
            sub_shape = XCAFDoc_ShapeTool.GetShape_s(sub)
            own = sub_shape.ShapeType() == kind
            name = _label_name(sub) if own and surface else None
            if name is not None and members_map.FindIndex(sub_shape):
                names.setdefault(members_map.FindIndex(sub_shape), name)
            if color is None and layer is None:
                continue
            if own:
                targets, members = own_level, [members_map.FindIndex(sub_shape)]
            else:
                targets = other_level
                members = [members_map.FindIndex(s) for s in _distinct(sub_shape, kind, avoid)]
            for j in members:
                if j and color is not None:
                    targets[0].setdefault(j, color)
                if j and layer is not None:
                    targets[1].setdefault(j, layer)
        return {**other_level[0], **own_level[0]}, {**other_level[1], **own_level[1]}, names

    def match(self, index: _Index, shape: Any, placed: np.ndarray) -> int | None:
        """The model's face or edge (1-based map index) that is ``shape`` of a prototype placed at ``placed``."""
        candidates = index.bare.find(shape)
        if not candidates:
            self._n_unmatched += 1
            return None
        if len(candidates) == 1:
            index.assigned.add(candidates[0])
            return candidates[0]
        want = placed @ _matrix(shape.Location())
        scale = 1.0 + float(np.abs(want).max())
        best, best_err = None, math.inf
        for i in candidates:
            m = index.mats.get(i)
            if m is None:
                m = index.mats[i] = _matrix(index.map.FindKey(i).Location())
            err = float(np.abs(m - want).max())
            if err < best_err and i not in index.assigned:
                best, best_err = i, err
        if best is None or best_err > 1e-9 * scale:
            self._n_unmatched += 1
            return None
        index.assigned.add(best)
        return best


#: What :meth:`_Reader.sub_shape_attributes` gives: colours, layers and names by sub-shape position.
_SubAttributes = tuple[dict[int, Any], dict[int, str], dict[int, str]]


def _distinct(shape: Any, kind: Any, avoid: Any = None) -> list[Any]:
    """The sub-shapes of ``kind`` of ``shape`` (outside sub-shapes of ``avoid``), each once, in
    ``TopExp_Explorer`` order."""
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopTools import TopTools_IndexedMapOfShape

    seen = TopTools_IndexedMapOfShape()
    out = []
    ex = TopExp_Explorer(shape, kind, avoid) if avoid is not None else TopExp_Explorer(shape, kind)
    while ex.More():
        n_before = seen.Extent()
        if seen.Add(ex.Current()) > n_before:
            out.append(ex.Current())
        ex.Next()
    return out


def read_xcaf(caf: Any, faces_map: Any, bare: Any, name: str, edges: tuple[Any, Any] | None = None) -> XcafData:
    """Transfer the parsed (and already root-by-root transferred) file into an XCAF document and read it.

    Parameters
    ----------
    caf : STEPCAFControl_Reader or IGESCAFControl_Reader
        After ``ReadFile``/``ReadStream`` and the transfer of the roots (the document reuses it).
    faces_map : TopTools_IndexedMapOfShape
        The model's faces (``ImportedModel.faces`` order).
    bare : object with ``find(shape) -> list[int]``
        The faces of ``faces_map`` by shape without location.
    name : str
        Name of a synthetic root when the file holds several free shapes, one at least an assembly.
    edges : (TopTools_IndexedMapOfShape, object with find), optional
        The model's free edges (``ImportedModel.edges`` order) and their index by bare shape: their
        colours and layers are read too.

    Returns
    -------
    XcafData
        Without ``unit`` (see :func:`step_unit`, :func:`iges_unit`). A failure of the XCAF transfer
        is a warning: the model is then flat, without colours and layers.
    """
    from OCP.TCollection import TCollection_ExtendedString
    from OCP.TDF import TDF_LabelSequence
    from OCP.TDocStd import TDocStd_Document
    from OCP.XCAFDoc import XCAFDoc_ShapeTool

    doc = TDocStd_Document(TCollection_ExtendedString("XCAF"))
    # SHUOs (per-occurrence styles) are off by default in OCC's STEP reader
    for mode in ("SetNameMode", "SetColorMode", "SetLayerMode", "SetSHUOMode"):
        if hasattr(caf, mode):
            getattr(caf, mode)(True)
    data = XcafData()
    try:
        ok = caf.Transfer(doc)
    except Exception as err:  # noqa: BLE001
        data.warnings.append(f"names, colours, layers and assembly structure not read: {one_line(err)}")
        return data
    if not ok:
        data.warnings.append("names, colours, layers and assembly structure not read (XCAF transfer failed)")
        return data
    reader = _Reader(doc, faces_map, bare, edges)
    free = TDF_LabelSequence()
    reader.shape_tool.GetFreeShapes(free)
    labels = [free.Value(i) for i in range(1, free.Length() + 1)]

    def is_assembly(label: Any) -> bool:
        return bool(XCAFDoc_ShapeTool.IsAssembly_s(label) or XCAFDoc_ShapeTool.IsReference_s(label))

    reader.in_assembly = any(is_assembly(lab) for lab in labels)
    nodes = [reader.node(lab, _IDENTITY, "", [], True) for lab in labels]
    reader.data.warnings = data.warnings
    if reader.in_assembly:
        if len(nodes) == 1:
            reader.data.assembly = nodes[0]
        else:
            comp = compound([n.shape.Moved(_location(n.location)) for n in nodes])
            reader.data.assembly = AssemblyNode(name, None, None, _IDENTITY, None, comp, tuple(nodes))
    if reader._n_unmatched:
        reader.data.warnings.append(f"{reader._n_unmatched} faces or curves of the assembly structure were not "
                                    "found in the transferred shape: they have no instance, colour or layer")
    return reader.data


def _location(matrix: np.ndarray) -> Any:
    """``TopLoc_Location`` of a rigid 4x4 placement (a uniform scale is kept as such)."""
    from OCP.gp import gp_Trsf
    from OCP.TopLoc import TopLoc_Location

    m = np.asarray(matrix, dtype=float)
    if np.array_equal(m, _IDENTITY):
        return TopLoc_Location()
    trsf = gp_Trsf()
    try:
        trsf.SetValues(*(float(x) for x in m[:3, :4].ravel()))
    except Exception as err:  # noqa: BLE001 - a matrix that is not a similarity
        raise InvalidGeometryError(f"location: expected a rigid placement (rotation, translation), "
                                   f"OCC refused it: {one_line(err)}") from err
    return TopLoc_Location(trsf)


def compound(shapes: Sequence[Any]) -> Any:
    """A ``TopoDS_Compound`` of ``shapes`` (in order): :func:`occsurf.bridge.conversion.shapes.compound`
    (imported on call: this module loads OCP only when it reads or writes)."""
    from ..conversion.shapes import compound as make_compound

    return make_compound(list(shapes))


# ---------------------------------------------------------------------------------------- writing
