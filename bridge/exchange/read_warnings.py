"""Warnings after OCC has read a STEP/IGES file (the second half of :mod:`.checks`; OCC imported lazily).

:func:`occ_check_warnings` turns OCC's own check messages (``Interface_CheckTool``) into warnings:
wrong arity, a text where a real is expected (read as 0), more than 3 coordinates (cut to 3), a
reference of the wrong type; :func:`occ_broken_ids` names the instances OCC could not read, for
:mod:`.checks` to prune. :func:`model_warnings` compares the model with the file: fewer faces than
face instances (:func:`faces_lost` reads that warning back), and shells the file calls closed (STEP
``CLOSED_SHELL``, IGES shell 514 of form 1) that have free edges.
"""

from __future__ import annotations

import re
from typing import Any

from .checks import STEP_FACE_TYPES, StepScan, limited_lines
from .iges_checks import IgesScan

__all__ = ["occ_check_warnings", "occ_broken_ids", "model_warnings", "faces_lost", "FACE_COUNT_WARNING"]


def _step_id(model: Any, num: int, scan: StepScan | None) -> int | None:
    """The ``#id`` of OCC's ``num``-th instance: OCC numbers them in file order."""
    if scan is not None and len(scan.ids) == model.NbEntities() and 1 <= num <= len(scan.ids):
        return scan.ids[num - 1]
    return None


#: OCC check failures that leave a null field in the instance read (its transfer would dereference it).
_NULL_FIELD_FAILS = ("illegal type", "Count of Parameters", "not an Entity", "Unresolved Reference",
                     "reference to another entity is unresolved")


def occ_broken_ids(reader: Any, scan: StepScan) -> dict[int, str]:
    """Instances OCC's STEP parser read with a null field (a reference of the wrong type, a wrong number
    of parameters): ``{id: why}``, to be removed (:func:`.checks.scan_step`) before OCC transfers anything."""
    from OCP.Interface import Interface_CheckTool

    model = reader.WS().Model()
    out: dict[int, str] = {}
    try:
        it = Interface_CheckTool(model).CompleteCheckList()
        it.Start()
    except Exception:  # noqa: BLE001
        return out
    while it.More():
        check, num = it.Value(), it.Number()
        ident = _step_id(model, num, scan) if num > 0 else None
        if ident is not None:
            fails = [" ".join(str(check.CFail(i)).split()) for i in range(1, check.NbFails() + 1)]
            bad = [f for f in fails if any(k in f for k in _NULL_FIELD_FAILS)]
            if bad:
                out[ident] = f"OCC cannot read it ({bad[0]})"
        it.Next()
    return out


def occ_check_warnings(reader: Any, fmt: str, scan: StepScan | None = None) -> list[str]:
    """OCC's check messages on the model it read, one warning each (unresolved references excluded:
    :func:`.checks.scan_step` reports those)."""
    from OCP.Interface import Interface_CheckTool

    model = reader.WS().Model()
    lines: list[str] = []
    try:
        it = Interface_CheckTool(model).CompleteCheckList()
        it.Start()
    except Exception:  # noqa: BLE001 - the checks are advisory
        return lines
    while it.More():
        check, num = it.Value(), it.Number()
        label = "file"
        if num > 0:
            try:
                ent = model.Value(num)
                name = ent.DynamicType().Name()
                name = name.split("_", 1)[1] if "_" in name else name
                if fmt == "step":
                    ident = _step_id(model, num, scan)
                    label = f"#{ident} {name}" if ident is not None else f"instance {num} ({name})"
                else:
                    label = f"D{2 * num - 1} {name}"  # the entity's first directory line
            except Exception:  # noqa: BLE001
                label = f"entity {num}"
        msgs = [check.CFail(i) for i in range(1, check.NbFails() + 1)]
        if num > 0:  # warnings on the file's header (a missing date) say nothing about the model
            msgs += [check.CWarning(i) for i in range(1, check.NbWarnings() + 1)]
        for msg in msgs:
            text = " ".join(str(msg).split())
            if fmt == "step" and ("Unresolved Reference" in text or "reference to another entity is unresolved" in text):
                continue  # scan_step reported (and pruned) them
            lines.append(f"{label}: {text} (OCC)")
        it.Next()
    return limited_lines(lines, "OCC check messages")


#: The warning of :func:`model_warnings` when the model has another number of faces than the file
#: describes (:func:`faces_lost` reads it back).
FACE_COUNT_WARNING = "the file has {listed} face instances ({what}); the model read has {read} faces"
_FACE_COUNT = re.compile(r"^the file has (\d+) face instances \(.*\); the model read has (\d+) faces$")


def faces_lost(warnings: list[str]) -> tuple[int, int] | None:
    """``(listed, read)`` when the warnings say the model has fewer faces than the file describes."""
    for w in warnings:
        m = _FACE_COUNT.match(w)
        if m and int(m.group(2)) < int(m.group(1)):
            return int(m.group(1)), int(m.group(2))
    return None


def model_warnings(shape: Any, reader: Any, scan: StepScan | IgesScan | None, n_faces: int) -> list[str]:
    """The model against the file: face count, and shells the file calls closed that have free edges
    (STEP ``CLOSED_SHELL``, IGES shell entity 514 of form 1)."""
    lines: list[str] = []
    if scan is None:
        return lines
    step = isinstance(scan, StepScan)
    what = ", ".join(STEP_FACE_TYPES) if step else "entities 510, or 143/144 and surfaces"
    if scan.face_instances and n_faces != scan.face_instances:
        lines.append(FACE_COUNT_WARNING.format(listed=scan.face_instances, what=what, read=n_faces))
    if scan.closed_shells:
        labels = [f"#{i}" for i in scan.closed_shells] if step else [f"D{i}" for i in scan.closed_shells]
        lines += _open_closed_shells(shape, labels, "CLOSED_SHELL" if step else "closed shells (entity 514, form 1)")
    return lines


def _open_closed_shells(shape: Any, labels: list[str], what: str) -> list[str]:
    """The file's closed shells (``labels``: ``#16`` or ``D41``) against the shells of the model without
    free edges: a warning when fewer of the model's shells are closed than the file says."""
    from OCP.BRep import BRep_Tool
    from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_SHELL
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopLoc import TopLoc_Location
    from OCP.TopoDS import TopoDS
    from OCP.TopTools import TopTools_IndexedMapOfShape

    shells = TopTools_IndexedMapOfShape()
    sx = TopExp_Explorer(shape, TopAbs_SHELL)
    while sx.More():
        shells.Add(sx.Current().Located(TopLoc_Location()))  # an instanced part counts once
        sx.Next()
    n_closed, free_counts = 0, []
    for k in range(1, shells.Extent() + 1):
        edges = TopTools_IndexedMapOfShape()
        uses: list[int] = []
        fx = TopExp_Explorer(shells.FindKey(k), TopAbs_FACE)
        while fx.More():
            ex = TopExp_Explorer(fx.Current(), TopAbs_EDGE)
            while ex.More():
                e = ex.Current()
                if not BRep_Tool.Degenerated_s(TopoDS.Edge_s(e)):
                    i = edges.Add(e)  # IsSame: one key per edge, whatever its orientation in a face
                    if i > len(uses):
                        uses.append(0)
                    uses[i - 1] += 1
                ex.Next()
            fx.Next()
        free = sum(u == 1 for u in uses)
        if free:
            free_counts.append(free)
        elif uses:
            n_closed += 1
    n_file = len(labels)
    if n_closed >= n_file:
        return []
    shown = ", ".join(labels[:6]) + (" ..." if n_file > 6 else "")
    opened = f"; {len(free_counts)} open, with {', '.join(map(str, free_counts[:6]))} free edges" if free_counts else ""
    return [f"the file has {n_file} {what} ({shown}); {n_closed} shells of the model are closed{opened}"]
