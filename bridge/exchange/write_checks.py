"""What a STEP or IGES writer must refuse before it prints anything (:func:`refuse`).

OCC's writers print whatever they are given and call it done: a coordinate that overflowed to
infinity as ``INF``, a name with a line break that splits an IGES line, a NUL that cuts the name,
a STEP name so long that OCC's own reader fails on the file. Each such write is refused here,
naming the object and the limit, before a byte is written (nothing is cut silently).

Names: a name must come back from the file exactly as given, or be refused:

* control characters (U+0000..U+001F but TAB, DEL) and line boundaries (NEL U+0085, U+2028,
  U+2029) are refused in both formats: OCC's STEP reader drops a CR and stops at a NUL; an IGES line
  break makes the file unreadable, and a SUB (U+001A) in an IGES name crashes OCC's IGES XCAF reader
  (a segmentation fault; found by hypothesis; measured with OCC 7.9.3);
* leading or trailing blanks, an empty name and ``NONE`` are refused: readers strip blanks and read
  ``''``/``NONE`` as no name;
* IGES: OCC writes a character beyond ASCII as its UTF-8 bytes where the fixed 80-column layout
  counts characters; where that breaks the layout (``'ą'`` did, ``'∑'`` need not) the written bytes fail
  the framing check and the write is refused (:func:`check_iges_bytes`);
* STEP: a name holding one of STEP's own control directives (``\\X\\``, ``\\X2\\``, ``\\X4\\``, ``\\X0\\``,
  ``\\S\\``, ``\\P?\\``, ``\\N\\``) is refused: OCC writes it as it is and its reader decodes it
  (``\\X2\\00E9\\X0\\`` came back as ``é``); and the name's encoded length (ASCII 1, an apostrophe 2, any
  other character at most 12: ``\\X2\\hhhh\\X0\\``) may not exceed :data:`STEP_NAME_MAX` (OCC's reader
  failed on names of 16,161 characters and read 16,132).
"""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Any

from occsurf.algorithms.errors import ExchangeError

__all__ = ["refuse", "check_name", "check_iges_bytes", "STEP_NAME_MAX"]

#: The longest STEP name accepted, in encoded characters (OCC 7.9.3's reader read 16,132 and failed at 16,161).
STEP_NAME_MAX = 16000

_RESERVED = frozenset({"", "NONE"})
_BREAKS = re.compile("[\x00-\x08\x0a-\x1f\x7f\x85\u2028\u2029]")
_STEP_DIRECTIVE = re.compile(r"\\(?:X[024]?|S|P[A-I]?|N)\\")


def check_name(name: str, fmt: str, label: str) -> None:
    """Refuse ``name`` if ``fmt`` ('step' or 'iges') cannot carry it exactly (see the module).

    Raises
    ------
    ExchangeError
        Naming ``label`` (where the name comes from) and the limit.
    """
    bad = _BREAKS.search(name)
    if bad is not None:
        raise ExchangeError(f"{label}: {name[:40]!r} holds U+{ord(bad.group()):04X} (a control character or line break), which "
                            f"{fmt.upper()} cannot carry; rename it")
    if name != name.strip() or name.strip() in _RESERVED:
        raise ExchangeError(f"{label}: {name[:40]!r}: readers drop a name's leading and trailing blanks, and read "
                            f"{', '.join(repr(r) for r in sorted(_RESERVED))} as no name; rename it")
    if fmt != "step":
        return
    directive = _STEP_DIRECTIVE.search(name)
    if directive is not None:
        raise ExchangeError(f"{label}: {name[:40]!r} holds {directive.group()!r}, a STEP string directive that "
                            "readers would decode; rename it")
    size = sum(1 if ord(c) < 128 and c != "'" else 2 if c == "'" else 12 for c in name)
    if size > STEP_NAME_MAX:
        raise ExchangeError(f"{label}: a name of {len(name)} characters ({size} encoded) is longer than STEP readers "
                            f"take (STEP_NAME_MAX = {STEP_NAME_MAX} encoded characters); shorten it")


def _names_of(objects: Any, items: Any) -> list[tuple[str, str]]:
    """``(label, name)`` of every name the write will print."""
    from .model import ImportedModel
    from .xcaf import AssemblyNode, iter_nodes

    out: list[tuple[str, str]] = []
    if isinstance(objects, ImportedModel):
        out += [(f"face {f.index}'s name", f.name) for f in objects.faces if f.name]
        out += [(f"curve {e.index}'s name", e.name) for e in objects.edges if e.name]
        root = objects.assembly
    elif isinstance(objects, AssemblyNode):
        root = objects
    else:
        out += [(f"names[{k}]", name) for k, (_, name) in enumerate(items) if name]
        root = None
    if root is not None:
        out += [(f"assembly node {path!r}", node.name) for path, node in iter_nodes(root) if node.name]
    return out


def _shapes_of(objects: Any, items: Any) -> list[Any]:
    """The OCC shapes a write will translate (a model's, an assembly's prototypes, or the items')."""
    from .model import ImportedModel
    from .xcaf import AssemblyNode, iter_nodes

    if isinstance(objects, ImportedModel):
        return [objects.shape]
    if isinstance(objects, AssemblyNode):
        return [n.shape for _, n in iter_nodes(objects)]
    return [shape for shape, _ in items]


def refuse(p: Path, fmt: str, objects: Any, items: Any) -> None:
    """Refuse the write of ``objects`` (a model, an assembly, or ``items``: ``(shape, name)`` pairs) to
    ``p`` in ``fmt`` if a name cannot be carried or a coordinate is not finite.

    Raises
    ------
    ExchangeError
        Naming the path, the object and the problem; nothing is written.
    """
    for label, name in _names_of(objects, items):
        try:
            check_name(name, fmt, label)
        except ExchangeError as err:
            raise ExchangeError(f"{p}: {err}; nothing written") from None
    _refuse_nonfinite(p, _shapes_of(objects, items))


def _refuse_nonfinite(p: Path, shapes: Any) -> None:
    """Refuse a face or curve whose coordinates are infinite or NaN (a pole of 1e308 in a file in feet
    overflows when read into millimetres): OCC would print ``INF``."""
    from OCP.Bnd import Bnd_Box
    from OCP.BRep import BRep_Tool
    from OCP.BRepBndLib import BRepBndLib
    from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE
    from OCP.TopExp import TopExp
    from OCP.TopoDS import TopoDS
    from OCP.TopTools import TopTools_IndexedMapOfShape

    def finite(shape: Any) -> bool:
        box = Bnd_Box()
        BRepBndLib.Add_s(shape, box, False)
        if not (box.IsVoid() or all(math.isfinite(v) for v in box.Get())):
            return False
        # The box covers the part of a surface its face uses: a pole of a B-spline or Bezier surface
        # outside that part (a mutated torus pole at 1e308 km, inf in mm) is written all the same.
        m = TopTools_IndexedMapOfShape()
        TopExp.MapShapes_s(shape, TopAbs_FACE, m)
        for i in range(1, m.Extent() + 1):
            if not _poles_finite(BRep_Tool.Surface_s(TopoDS.Face_s(m.FindKey(i)))):
                return False
        return True

    for k, shape in enumerate(shapes):
        if shape is None or shape.IsNull() or finite(shape):
            continue
        for kind, what in ((TopAbs_FACE, "face"), (TopAbs_EDGE, "curve")):
            m = TopTools_IndexedMapOfShape()
            TopExp.MapShapes_s(shape, kind, m)
            for i in range(1, m.Extent() + 1):
                if not finite(m.FindKey(i)):
                    raise ExchangeError(f"{p}: object {k}, {what} {i - 1}: coordinates not finite (infinite or NaN); "
                                        "nothing written")
        raise ExchangeError(f"{p}: object {k}: coordinates not finite (infinite or NaN); nothing written")


def _poles_finite(surface: Any) -> bool:
    """Whether every pole (and weight) of a B-spline or Bezier surface is finite; other surfaces:
    ``True`` (their box says it)."""
    if surface is None or not hasattr(surface, "NbUPoles"):
        return True
    for i in range(1, surface.NbUPoles() + 1):
        for j in range(1, surface.NbVPoles() + 1):
            if not (all(map(math.isfinite, surface.Pole(i, j).Coord())) and math.isfinite(surface.Weight(i, j))):
                return False
    return True


def check_iges_bytes(p: Path, data: bytes, objects: Any, items: Any) -> None:
    """Refuse IGES bytes that our own reader's framing check would call damaged (a name beyond ASCII
    whose UTF-8 bytes shifted OCC's fixed columns), naming the names beyond ASCII."""
    from .files import check_iges_text
    from .iges_checks import scan_iges

    try:
        check_iges_text(p, data)
        scan_iges(p, data)  # the directory entries against the parameter lines, as reading checks them
    except ExchangeError as err:
        wide = [name for _, name in _names_of(objects, items) if any(ord(c) > 127 for c in name)]
        cause = (f"names beyond ASCII shift IGES's fixed columns in OCC's writer: {', '.join(repr(n[:40]) for n in wide)}"
                 if wide else "OCC's IGES writer")
        raise ExchangeError(f"{err} (written by {cause}); nothing written") from None
