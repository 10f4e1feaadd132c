"""IGES names and levels: the names entities carry and the level (layer) names a file gives.

Part of the XCAF side of exchange (:mod:`.xcaf`): OCC's IGES XCAF reader leaves these out, so
they are read from the transferred entities (:func:`iges_face_attributes`) and from the file's
level-function properties (:func:`iges_level_names`, :func:`name_levels`).
"""

from __future__ import annotations

from typing import Any

from .xcaf_tree import XcafData

__all__ = ["iges_face_attributes", "iges_level_names", "name_levels"]

_NO_NAMES = frozenset({"", "NONE"})


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
