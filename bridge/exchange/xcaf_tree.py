"""The assembly tree read from (and written to) an XCAF document, and what the document adds to a shape.

Part of the XCAF side of exchange (:mod:`.xcaf`): :class:`AssemblyNode` (products and their
instances, each a reference to a shared prototype, with its placement, colour and layer),
the walks over it, and :class:`XcafData` (units, per-face and per-edge colours, layers, instance
paths and names; JSON for the process boundary of ``read_step(..., isolated=True)``).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from occsurf.algorithms.errors import InvalidGeometryError

__all__ = ["AssemblyNode", "iter_nodes", "node_key", "instance_overrides", "instance_layer_losses", "XcafData"]

_IDENTITY = np.eye(4)
_IDENTITY.setflags(write=False)

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
