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
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from occsurf.algorithms.errors import InvalidGeometryError

from ..messages import one_line

__all__ = ["AssemblyNode", "UNITS", "WRITE_UNITS", "unit_scale", "XcafData", "read_xcaf", "step_unit", "iges_unit", "compound",
           "iter_nodes", "instance_overrides", "instance_layer_losses", "COLOR_DECIMALS", "rgba_from_occ", "occ_color"]

#: Millimetres per unit of each length unit occsurf reports or writes (``ImportedModel.unit``,
#: ``write_step(..., unit=)``, ``occsurf convert --unit``).
UNITS: dict[str, float] = {
    "mm": 1.0, "cm": 10.0, "m": 1000.0, "km": 1e6, "um": 1e-3, "nm": 1e-6, "dm": 100.0,
    "inch": 25.4, "ft": 304.8, "mi": 1609344.0, "mil": 0.0254, "uin": 2.54e-5,
}

#: OCC's unit keyword (``write.step.unit`` / ``write.iges.unit``) of each unit occsurf writes.
_OCC_UNIT = {"mm": "MM", "cm": "CM", "m": "M", "km": "KM", "um": "UM", "inch": "INCH", "ft": "FT",
             "mi": "MI", "mil": "MIL", "uin": "UIN"}

#: Decimals to which the RGB of a colour read is rounded (:func:`rgba_from_occ`). OCC holds colours as
#: linear RGB in float32 and converts from and to the file's sRGB: the file's 0.2 comes back from
#: ``Values(Quantity_TOC_sRGB)`` as 0.19999999868, 1 as 0.9999999999999999 (measured: at most 1.93e-8
#: off over 20 000 random values in [0, 1], 1.8e-8 over every 8-bit value, 1.6e-8 over every
#: percentage). Rounding to 7 decimals therefore gives back exactly every value the file states with
#: up to 7 decimals (0.2, 0.5, 1, 128/255 to 7 decimals) and any other within 5e-8 + 2e-8; build123d's
#: ``tuple(Color)`` rounds to 7 decimals too.
COLOR_DECIMALS: int = 7

#: The units ``write_step``/``write_iges(..., unit=)`` and ``occsurf convert --unit`` accept.
WRITE_UNITS: tuple[str, ...] = tuple(_OCC_UNIT)

#: STEP unit names (``FileUnits``: SI prefix + 'metre', or a conversion-based unit's name).
_STEP_NAMES = {
    "millimetre": "mm", "millimeter": "mm", "centimetre": "cm", "centimeter": "cm", "metre": "m", "meter": "m",
    "kilometre": "km", "kilometer": "km", "micrometre": "um", "micrometer": "um", "micron": "um",
    "nanometre": "nm", "nanometer": "nm", "decimetre": "dm", "decimeter": "dm",
    "inch": "inch", "in": "inch", "foot": "ft", "feet": "ft", "ft": "ft", "mile": "mi", "mil": "mil",
    "thou": "mil", "microinch": "uin", "mm": "mm", "cm": "cm", "m": "m",
}

#: IGES global-section unit flags (IGES 5.3, §2.2.4.3, parameter 14).
_IGES_FLAGS = {1: "inch", 2: "mm", 4: "ft", 5: "mi", 6: "m", 7: "km", 8: "mil", 9: "um", 10: "cm", 11: "uin"}
_IGES_NAMES = {"IN": "inch", "INCH": "inch", "MM": "mm", "FT": "ft", "MI": "mi", "M": "m", "KM": "km",
               "MIL": "mil", "UM": "um", "MICRON": "um", "CM": "cm", "UIN": "uin"}

_NO_NAMES = frozenset({"", "NONE"})
_IDENTITY = np.eye(4)
_IDENTITY.setflags(write=False)


# ---------------------------------------------------------------------------------------- the tree
@dataclass(frozen=True, eq=False)
class AssemblyNode:
    """One node of an assembly: the root, a sub-assembly instance or a part instance.

    Attributes
    ----------
    name : str
        The instance's name (STEP: the ``NEXT_ASSEMBLY_USAGE_OCCURRENCE``'s name, else the product's);
        the root's product name.
    color : tuple of 4 floats or None
        RGBA in [0, 1] the file gives this occurrence: an override for this very occurrence (STEP
        SHUO: one of two instances of a sub-assembly's part recoloured; then the two nodes' colours
        differ although they are the same component of the same sub-assembly), else the instance's
        (component's) colour, else its part's. sRGB, the file's numbers (see
        :attr:`occsurf.bridge.exchange.model.ImportedFace.color`).
    layer : str or None
        The instance's (else its part's) layer.
    location : ndarray, shape (4, 4)
        Placement relative to the parent (the identity for the root), millimetres.
    part : str or None
        Key of the shared prototype: the part's (product's) name, made unique with ``'#2'``, ``'#3'``...
        when two different parts share a name. Two instances of one part have equal ``part`` and the
        same ``shape``.
    shape : TopoDS_Shape
        The prototype, unlocated (for an assembly, the compound of its placed children).
    children : tuple of AssemblyNode
        Empty for a part instance.
    """

    name: str
    color: tuple[float, float, float, float] | None
    layer: str | None
    location: np.ndarray = field(repr=False)
    part: str | None
    shape: Any = field(repr=False)
    children: tuple[AssemblyNode, ...] = ()

    def __post_init__(self) -> None:
        loc = np.array(self.location, dtype=float)
        if loc.shape != (4, 4) or not np.isfinite(loc).all():
            raise InvalidGeometryError(f"location: expected a finite (4, 4) matrix, got shape {loc.shape}")
        loc.setflags(write=False)
        object.__setattr__(self, "location", loc)
        object.__setattr__(self, "children", tuple(self.children))


def iter_nodes(node: AssemblyNode, path: str = "") -> Iterable[tuple[str, AssemblyNode]]:
    """``(path, node)`` of ``node`` and every node below it, depth first, path names joined by '/'."""
    here = f"{path}/{node.name}" if path else node.name
    yield here, node
    for child in node.children:
        yield from iter_nodes(child, here)


def node_key(node: AssemblyNode) -> str:
    """The prototype key of a node: its part, else (a node built without one) its identity."""
    return node.part if node.part is not None else f"\0{id(node)}"


def instance_overrides(root: AssemblyNode) -> list[tuple[str, tuple[int, ...], tuple[float, float, float, float]]]:
    """The occurrences whose colour differs from the one their component has in the first
    occurrence of its assembly: ``(path, child indices from the root, colour)``.

    A part or sub-assembly is written once, from its first occurrence; such an occurrence needs a
    per-occurrence override (STEP: a ``SPECIFIED_HIGHER_USAGE_OCCURRENCE`` styled by an
    ``OVER_RIDING_STYLED_ITEM``; OCC: an SHUO), or, in IGES, a placed copy of its own colour.
    Occurrences directly below the root are their own components: never listed."""
    first: dict[str, tuple[AssemblyNode, ...]] = {}
    out: list[tuple[str, tuple[int, ...], tuple[float, float, float, float]]] = []

    def walk(node: AssemblyNode, path: str, indices: tuple[int, ...]) -> None:
        given = first.setdefault(node_key(node), node.children)
        for i, (child, written) in enumerate(zip(node.children, given)):
            here, below = f"{path}/{child.name}", (*indices, i)
            if indices and child.color is not None and child.color != written.color:
                out.append((here, below, child.color))
            walk(child, here, below)

    walk(root, root.name, ())
    return out


def instance_layer_losses(root: AssemblyNode) -> list[tuple[str, str | None, str | None]]:
    """``(path, layer, written layer)`` of each occurrence whose layer differs from its part's
    first occurrence's: OCC's ``STEPCAFControl_Writer`` writes no layer on an instance
    (``WriteLayers`` skips component and assembly labels: "there is no way to assign layer to
    instance in STEP", OCC 7.9), so a part is written on its first occurrence's layer and every
    occurrence reads back on it."""
    first: dict[str, AssemblyNode] = {}
    out = []
    for path, node in iter_nodes(root):
        written = first.setdefault(node_key(node), node)
        if written is not node and node.layer != written.layer:
            out.append((path, node.layer, written.layer))
    return out


@dataclass
class XcafData:
    """What the XCAF document adds to the transferred shape (face keys: 1-based map indices)."""

    unit: str = "mm"
    unit_scale: float = 1.0
    colors: dict[int, tuple[float, float, float, float]] = field(default_factory=dict)
    layers: dict[int, str] = field(default_factory=dict)
    edge_colors: dict[int, tuple[float, float, float, float]] = field(default_factory=dict)
    edge_layers: dict[int, str] = field(default_factory=dict)
    edge_instances: dict[int, str] = field(default_factory=dict)
    instances: dict[int, str] = field(default_factory=dict)
    instance_names: dict[int, str] = field(default_factory=dict)
    face_names: dict[int, str] = field(default_factory=dict)
    assembly: AssemblyNode | None = None
    warnings: list[str] = field(default_factory=list)

    # -- crossing the process boundary of read_step(..., isolated=True) --------------------------
    def to_json(self) -> tuple[dict[str, Any], list[Any]]:
        """A JSON-safe dict plus the prototype shapes it refers to by index (to write as one BRep)."""
        shapes: list[Any] = []
        ids: dict[Any, int] = {}

        def node_json(n: AssemblyNode) -> dict[str, Any]:
            key = n.part if n.part is not None else id(n)  # one prototype per part: shared once
            if key not in ids:
                ids[key] = len(shapes)
                shapes.append(n.shape)
            return {"name": n.name, "color": n.color, "layer": n.layer, "location": n.location.tolist(),
                    "part": n.part, "shape": ids[key], "children": [node_json(c) for c in n.children]}

        doc = {"unit": self.unit, "unit_scale": self.unit_scale,
               "colors": {str(k): list(v) for k, v in self.colors.items()},
               "layers": {str(k): v for k, v in self.layers.items()},
               "edge_colors": {str(k): list(v) for k, v in self.edge_colors.items()},
               "edge_layers": {str(k): v for k, v in self.edge_layers.items()},
               "edge_instances": {str(k): v for k, v in self.edge_instances.items()},
               "instances": {str(k): v for k, v in self.instances.items()},
               "instance_names": {str(k): v for k, v in self.instance_names.items()},
               "face_names": {str(k): v for k, v in self.face_names.items()},
               "warnings": list(self.warnings),
               "assembly": node_json(self.assembly) if self.assembly is not None else None}
        return doc, shapes

    @classmethod
    def from_json(cls, doc: dict[str, Any], shapes: Sequence[Any]) -> XcafData:
        def node(d: dict[str, Any]) -> AssemblyNode:
            color = tuple(d["color"]) if d["color"] is not None else None
            return AssemblyNode(d["name"], color, d["layer"], np.array(d["location"]), d["part"],
                                shapes[d["shape"]], tuple(node(c) for c in d["children"]))

        return cls(unit=doc["unit"], unit_scale=float(doc["unit_scale"]),
                   colors={int(k): tuple(v) for k, v in doc["colors"].items()},
                   layers={int(k): v for k, v in doc["layers"].items()},
                   edge_colors={int(k): tuple(v) for k, v in doc["edge_colors"].items()},
                   edge_layers={int(k): v for k, v in doc["edge_layers"].items()},
                   edge_instances={int(k): v for k, v in doc["edge_instances"].items()},
                   instances={int(k): v for k, v in doc["instances"].items()},
                   instance_names={int(k): v for k, v in doc["instance_names"].items()},
                   face_names={int(k): v for k, v in doc["face_names"].items()},
                   warnings=list(doc["warnings"]),
                   assembly=node(doc["assembly"]) if doc["assembly"] is not None else None)


def unit_scale(unit: str) -> float:
    """Millimetres per ``unit`` (a key of :data:`UNITS`); raises :class:`InvalidGeometryError` otherwise."""
    if unit not in UNITS:
        raise InvalidGeometryError(f"unit: expected one of {', '.join(UNITS)}, got {unit!r}")
    return UNITS[unit]


# ---------------------------------------------------------------------------------------- units
def step_unit(reader: Any) -> tuple[str, float, list[str]]:
    """``(unit, millimetres per unit, warnings)`` the STEP file declares (read before any transfer).

    Several representation contexts with different length units: the most frequent is reported, with
    a warning (OCC converts each context's values with its own unit, so the geometry is right).
    """
    from OCP.TColStd import TColStd_SequenceOfAsciiString

    lengths, angles, solid_angles = (TColStd_SequenceOfAsciiString() for _ in range(3))
    try:
        reader.FileUnits(lengths, angles, solid_angles)
    except Exception as err:  # noqa: BLE001 - no unit is not fatal
        return "mm", 1.0, [f"the file's length unit could not be read ({one_line(err)}); millimetres assumed"]
    names = [lengths.Value(i).ToCString() for i in range(1, lengths.Length() + 1)]
    if not names:
        return "mm", 1.0, []
    counts: dict[str, int] = {}
    for n in names:
        counts[n] = counts.get(n, 0) + 1
    name = max(counts, key=lambda n: counts[n])
    warnings = []
    if len(counts) > 1:
        warnings.append(f"the file declares several length units ({', '.join(sorted(counts))}); "
                        f"'{name}' is reported, each part's values are converted with its own")
    unit = _STEP_NAMES.get(name.strip().lower())
    if unit is None:
        factor = _conversion_factor(reader, name)
        if factor is None:
            return name.strip().lower(), 1.0, [*warnings, f"unknown length unit '{name}' (unit_scale 1.0 reported)"]
        return name.strip().lower(), factor, warnings
    return unit, UNITS[unit], warnings


def _conversion_factor(reader: Any, name: str) -> float | None:
    """Millimetres per unit of a STEP ``CONVERSION_BASED_UNIT`` called ``name`` (from the file)."""
    try:
        from OCP.StepBasic import StepBasic_ConversionBasedUnit, StepBasic_SiUnit

        model = reader.WS().Model()
        prefix = {"MILLI": 1.0, "CENTI": 10.0, "DECI": 100.0, "KILO": 1e6, "MICRO": 1e-3, "NANO": 1e-6}
        for k in range(1, model.NbEntities() + 1):
            ent = model.Value(k)
            if isinstance(ent, StepBasic_ConversionBasedUnit) and ent.Name().ToCString() == name:
                factor = ent.ConversionFactor()
                value = float(factor.ValueComponent())
                base = factor.UnitComponent().NamedUnit()
                if isinstance(base, StepBasic_SiUnit):
                    scale = prefix.get(base.Prefix().name.split("_")[-1].upper(), 1000.0) if base.HasPrefix() else 1000.0
                    return value * scale
                return None
    except Exception:  # noqa: BLE001
        return None
    return None


def iges_unit(reader: Any) -> tuple[str, float, list[str]]:
    """``(unit, millimetres per unit, warnings)`` of the IGES global section (flag, else the name)."""
    try:
        header = reader.IGESModel().GlobalSection()
        flag = int(header.UnitFlag())
        name = header.UnitName().ToCString().strip() if header.UnitName() is not None else ""
    except Exception as err:  # noqa: BLE001
        return "mm", 1.0, [f"the file's length unit could not be read ({one_line(err)}); millimetres assumed"]
    unit = _IGES_FLAGS.get(flag) or _IGES_NAMES.get(name.upper())
    if unit is None:
        return "mm", 1.0, [f"unknown IGES unit (flag {flag}, name '{name}'); millimetres assumed"]
    return unit, UNITS[unit], []


#: IGES entity types a face is transferred from (IGES 5.3 §4: analytic and spline surfaces 108-140,
#: bounded/trimmed surfaces 143/144, CSG-free B-rep surfaces 190-198, the B-rep face 510).
_IGES_FACE_TYPES = frozenset({108, 114, 118, 120, 122, 128, 140, 143, 144, 190, 192, 194, 196, 198, 510})


def _iges_own_name(entity: Any) -> str | None:
    """The name an IGES entity carries (406 form 15 name property, else its entity label)."""
    try:
        value = entity.NameValue() if entity.HasName() else None
    except Exception:  # noqa: BLE001 - a name is optional
        return None
    text = value.ToCString().strip() if value is not None else ""
    return None if text in _NO_NAMES else text


def _iges_level(entity: Any) -> int | None:
    """The one level an IGES entity is on (None: none, or a list of levels)."""
    from OCP.IGESData import IGESData_DefList

    try:
        if entity.DefLevel() == IGESData_DefList.IGESData_DefOne and entity.Level() > 0:
            return int(entity.Level())
    except Exception:  # noqa: BLE001
        return None
    return None


def iges_face_attributes(transfer: Any, faces_map: Any, named: Any, layered: Any) -> tuple[dict[int, str],
                                                                                            dict[int, str]]:
    """Own names and levels of faces whose IGES surface entity neither OCC nor its XCAF reader reports.

    OCC binds a surface entity inside a 402 group to its face in the transient process, but
    ``ShapeResult`` only knows the recorded (root) results, and the XCAF reader finds the face's
    label only when the entity has a colour: the name property (406-15 or label) and the level of
    an uncoloured face are lost. Here the face side is searched (``EntityFromShapeResult(face, -1)``:
    one scan of the process per face), only when named or levelled face entities are left
    unresolved, only for faces still without a name or a layer, until every such entity is found.

    Parameters
    ----------
    transfer : XSControl_TransferReader
        The IGES reader's, after the roots were transferred.
    faces_map : TopTools_IndexedMapOfShape
        The model's faces.
    named, layered : container of int
        Faces (1-based map index) that already have their own name, a layer.

    Returns
    -------
    (dict of int to str, dict of int to str)
        Further own face names, and layers (the level number as text), by 1-based map index.
    """
    process = transfer.TransientProcess()
    # keyed by the Python object: OCP's MapIndex/Number of these entities answer 0 (measured), while
    # the same C++ entity always comes back as the same (kept alive) Python object
    unresolved: dict[int, tuple[Any, str | None, int | None]] = {}
    for k in range(1, process.NbMapped() + 1):
        entity = process.Mapped(k)
        if not hasattr(entity, "TypeNumber") or entity.TypeNumber() not in _IGES_FACE_TYPES:
            continue
        name, level = _iges_own_name(entity), _iges_level(entity)
        if name is None and level is None:
            continue
        try:
            shape = transfer.ShapeResult(entity)
        except Exception:  # noqa: BLE001
            shape = None
        if shape is None or shape.IsNull():
            unresolved[id(entity)] = (entity, name, level)
    names: dict[int, str] = {}
    levels: dict[int, str] = {}
    candidates = dict(unresolved)
    for i in range(1, faces_map.Extent() + 1):
        if not unresolved:  # (a further face split from the last entity keeps what OCC gave it)
            break
        if i in named and i in layered:
            continue
        try:
            entity = transfer.EntityFromShapeResult(faces_map.FindKey(i), -1)
        except Exception:  # noqa: BLE001 - not found
            continue
        hit = candidates.get(id(entity)) if entity is not None else None
        if hit is None:
            continue
        unresolved.pop(id(entity), None)
        if hit[1] is not None and i not in named:
            names[i] = hit[1]
        if hit[2] is not None and i not in layered:
            levels[i] = str(hit[2])
    return names, levels


def iges_level_names(data: bytes) -> dict[int, str]:
    """Level names of an IGES file: ``{level: name}`` from its Level Function properties (entity 406
    form 3, IGES 5.3 §4.98: the function description of the level the entity is on), which OCC's
    reader ignores (its layers are the bare level numbers). Read from the file's text: the Directory
    entry's type, form and level, then the property's third parameter (a Hollerith string)."""
    text = data.decode("latin-1")
    by_sec: dict[str, list[str]] = {"G": [], "D": [], "P": []}
    for line in text.splitlines():
        if line[72:73] in by_sec:
            by_sec[line[72:73]].append(line)
    glob = "".join(x[:72] for x in by_sec["G"])
    delim = glob[2] if glob[:2] == "1H" and len(glob) > 2 else ","
    names: dict[int, str] = {}
    d, par = by_sec["D"], by_sec["P"]
    for k in range(0, len(d) - 1, 2):
        a, b = d[k], d[k + 1]
        if a[0:8].strip() != "406" or b[32:40].strip() != "3":
            continue
        try:
            ptr, level, count = int(a[8:16]), int(a[32:40]), int(b[24:32])
        except ValueError:
            continue
        if level <= 0 or ptr < 1:  # 0: no level; negative: a list of levels (406 form 1)
            continue
        name = _level_function_text("".join(x[:64] for x in par[ptr - 1:ptr - 1 + count]), delim)
        if name:
            names.setdefault(level, name)
    return names


def _level_function_text(params: str, delim: str) -> str | None:
    """The function description of a 406-3 parameter record ``406,NP,FC,nH...;`` (None if absent)."""
    fields = params.split(delim, 3)
    if len(fields) < 4 or fields[0].strip() != "406":
        return None
    rest = fields[3].lstrip()
    count, _, body = rest.partition("H")
    if not (count.isascii() and count.isdigit()) or len(body) < int(count):
        return None
    if body[int(count):].lstrip()[:1] not in (delim, ";"):  # the string must end the parameter
        return None
    value = body[:int(count)].strip()
    return None if value in _NO_NAMES else value


def name_levels(data: XcafData, names: dict[int, str]) -> None:
    """Layers of faces and free edges read as level numbers ('1') take the name the file gives the
    level (in place)."""
    if names:
        data.layers, data.edge_layers = ({i: names.get(int(v), v) if v.isascii() and v.isdigit() else v
                                          for i, v in layers.items()} for layers in (data.layers, data.edge_layers))


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
