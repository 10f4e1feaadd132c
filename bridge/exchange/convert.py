"""STEP ⇄ IGES ⇄ STEP conversion that says what it could not carry (``occsurf convert``).

:func:`convert` reads the input (in a worker process by default: the input is untrusted), writes it
with :func:`occsurf.bridge.exchange.step_iges.write_step` / ``write_iges`` (through XCAF: assembly
structure, names, colours, layers, the input's unit unless another is asked for; STEP with 17
significant digits, atomic), then reads the written file back and compares, face by face, what a
user cares about: the face count, names, colours, layers, instance paths and the unit, and the
free curves' colours and layers. What the target format cannot hold (IGES: instances, per-instance
colour overrides, transparency, 17 digits; STEP through OCC's writer: layers of instances) and
whatever the comparison finds changed (also each face's wire count, its area beyond
:data:`AREA_RTOL` and its position beyond :data:`POSITION_RTOL`) is returned as one line per
property in :attr:`ConversionReport.not_carried`.
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass, field
from typing import Any

from occsurf.algorithms.errors import ExchangeError, InvalidGeometryError

from .read_warnings import faces_lost
from .reading import IGES_SUFFIXES, STEP_SUFFIXES, sniff_format, strict_refusal, target_format

__all__ = ["ConversionReport", "convert", "target_format", "source_format", "STEP_SUFFIXES", "IGES_SUFFIXES",
           "COLOR_TOLERANCE", "AREA_RTOL", "POSITION_RTOL", "format_losses", "compare", "face_area", "wire_count", "trim_band"]


#: Largest difference of a colour component (RGBA in [0, 1]) read back that still counts as the same
#: colour: IGES stores colours as percentages printed with 10 significant digits.
COLOR_TOLERANCE: float = 1e-6

#: Largest move of a face's centroid (``BRepGProp``), as a fraction of the model's bounding-box
#: diagonal, that counts as the face staying in place: an instance or a face placed elsewhere keeps
#: its area, wires, name and colour, so only its position shows it. Measured on the round trips of
#: ../shared/realdata and build123d assemblies: up to 1.2e-5 (the bearing's sliver faces re-trimmed by
#: OCC's IGES -> STEP reading; 17-digit STEP -> STEP 4.5e-9, IGES 1e-7); a lost placement moves faces
#: by a part's size.
POSITION_RTOL: float = 1e-4

#: Largest relative change of a face's area (``BRepGProp``, 1e-9) that counts as unchanged, by target
#: format. STEP: 17 digits, so round-off of the area computation only (measured 0 to 1e-15; the
#: screw's faces move 4.5e-8 through OCC's STEP reader with or without occsurf, so they are reported).
#: IGES: 10 digits, a value moves by up to 5e-10 of itself (measured up to 6e-8 on the real files).
AREA_RTOL: dict[str, float] = {"step": 1e-12, "iges": 1e-7}


@dataclass
class ConversionReport:
    """What :func:`convert` did.

    Attributes
    ----------
    source, target : str
    source_format, target_format : str
        ``'step'`` or ``'iges'``.
    unit : str
        The unit the target file declares.
    n_faces, n_edges : int
        Faces and free edges read from the source.
    not_carried : list of str
        One line per property that did not survive (empty when everything did).
    warnings : list of str
        What the reader found wrong with the source but read around.
    seconds : float
    """

    source: str
    target: str
    source_format: str
    target_format: str
    unit: str
    n_faces: int
    n_edges: int
    not_carried: list[str] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    seconds: float = 0.0


def source_format(path: str | os.PathLike[str]) -> str:
    """``'step'`` or ``'iges'``: :func:`occsurf.bridge.exchange.reading.sniff_format` (by suffix, else by
    the file's first bytes), its refusal naming the path.

    Raises
    ------
    ExchangeError
        Neither suffix, and the file cannot be read or starts like neither format.
    """
    try:
        return sniff_format(path)
    except ExchangeError as err:
        raise ExchangeError(f"{os.fspath(path)}: {err}") from err


def convert(
    source: str | os.PathLike[str],
    target: str | os.PathLike[str],
    *,
    unit: str | None = None,
    digits: int | None = None,
    isolated: bool = True,
    timeout: float | None = None,
    replace_readonly: bool = False,
    strict: bool = False,
    allow_loss: bool = False,
) -> ConversionReport:
    """Convert a STEP or IGES file to STEP or IGES (by the target's suffix), keeping its structure.

    Parameters
    ----------
    source : str or path-like
        STEP or IGES file (format by suffix, else by content: :mod:`occsurf.bridge.exchange.reading`).
    target : str or path-like
        ``.step``/``.stp``/``.p21`` or ``.iges``/``.igs`` (:func:`~occsurf.bridge.exchange.reading.target_format`);
        replaced atomically.
    unit : str, optional
        Length unit of the target (a key of :data:`occsurf.bridge.exchange.xcaf.WRITE_UNITS`); default
        the unit the source declares.
    digits : int, optional
        Significant digits of STEP reals, 2 to 17 (default 17: lossless). IGES keeps 10 whatever is
        asked (reported in ``not_carried`` when more is asked).
    isolated : bool, default True
        Read the source in a worker process (:func:`occsurf.bridge.isolation.run_jobs`).
    timeout : float, optional
        Seconds the worker may read before it is stopped.
    replace_readonly : bool, default False
        As :func:`occsurf.bridge.exchange.step_iges.write_step`.
    strict : bool, default False
        Refuse a source read around damage (``ImportedModel.warnings``, see
        :mod:`occsurf.bridge.exchange.checks`): nothing is written then (the command line's ``--strict``).
    allow_loss : bool, default False
        Write a model that has fewer faces than the source describes (OCC refused some: a B-spline
        of degree 1e9, decreasing knots...). By default that is refused, nothing written (the
        command line's ``--allow-loss`` allows it).

    Returns
    -------
    ConversionReport

    Raises
    ------
    InvalidGeometryError
        A bad target suffix, ``unit`` or ``digits``.
    ExchangeError
        The source cannot be read (missing, damaged, neither STEP nor IGES, a crash or time-out of the reader),
        lost faces (without ``allow_loss``), or the target cannot be written; no target file is created or
        modified then.
    """
    from . import xcaf
    from .step_iges import STEP_DIGITS, read_iges, read_step, write_iges, write_step

    t0 = time.perf_counter()
    out_fmt = target_format(target)
    if unit is not None and unit not in xcaf.WRITE_UNITS:
        raise InvalidGeometryError(f"unit: expected one of {', '.join(xcaf.WRITE_UNITS)}, got {unit!r}")
    if digits is not None and (isinstance(digits, bool) or not isinstance(digits, int) or not 2 <= digits <= 17):
        raise InvalidGeometryError(f"digits: expected an integer from 2 to 17, got {digits!r}")
    in_fmt = source_format(source)
    reader = read_step if in_fmt == "step" else read_iges
    model = reader(source, isolated=isolated, timeout=timeout)
    if strict and model.warnings:
        raise ExchangeError(f"{os.fspath(source)}: {strict_refusal(model.warnings)}")
    lost = faces_lost(model.warnings)
    if lost is not None and not allow_loss:
        named = [w for w in model.warnings if "OCC cannot build it" in w]
        why = f": {named[0]}" + (f" and {len(named) - 1} more" if len(named) > 1 else "") if named else ""
        raise ExchangeError(f"{os.fspath(source)}: the file describes {lost[0]} faces and {lost[1]} were read "
                            f"({lost[0] - lost[1]} lost{why}); nothing written (allow_loss / --allow-loss writes "
                            "what was read)")
    out_unit = unit if unit is not None else (model.unit if model.unit in xcaf.WRITE_UNITS else "mm")
    if out_fmt == "step":
        written = write_step(target, model, precision_digits=digits or STEP_DIGITS, unit=out_unit,
                             replace_readonly=replace_readonly)
        again = read_step(written)
    else:
        written = write_iges(target, model, unit=out_unit, replace_readonly=replace_readonly)
        again = read_iges(written)
    report = ConversionReport(source=os.fspath(source), target=os.fspath(target), source_format=in_fmt,
                              target_format=out_fmt, unit=out_unit, n_faces=len(model.faces),
                              n_edges=len(model.edges), warnings=list(model.warnings))
    report.not_carried = format_losses(model, out_fmt, digits) + compare(model, again, out_fmt, out_unit)
    report.seconds = time.perf_counter() - t0
    return report


def format_losses(model: Any, out_fmt: str, digits: int | None) -> list[str]:
    """What the target format (or OCC's writer of it) cannot hold, by construction (before any comparison)."""
    from .xcaf import WRITE_UNITS, instance_layer_losses, instance_overrides, iter_nodes

    lines: list[str] = []
    if model.unit not in WRITE_UNITS:
        lines.append(f"unit '{model.unit}' cannot be written: the values are written in millimetres")
    if out_fmt != "iges":
        if digits is not None and digits < 17:
            lines.append(f"STEP written with {digits} significant digits (--digits): values move by up to "
                         f"5e-{digits} of their size")
        layers = instance_layer_losses(model.assembly) if model.assembly is not None else []
        if layers:
            path, layer, written = layers[0]
            lines.append(f"layers of {len(layers)} instances not carried: OCC's STEP writer writes no layer on an "
                         f"instance, each part is written on its first instance's layer (instance '{path}' on "
                         f"{layer!r} written on {written!r})")
        return lines
    lines.append("IGES keeps 10 significant digits: values move by up to 5e-10 of their size"
                 + (f" (--digits {digits} not possible)" if digits is not None and digits > 10 else ""))
    if model.assembly is not None:
        counts: dict[str, int] = {}
        n_leaves = 0
        for _, node in iter_nodes(model.assembly):
            if not node.children:
                n_leaves += 1
                counts[node.part or node.name] = counts.get(node.part or node.name, 0) + 1
        for part, n in counts.items():
            if n > 1:
                lines.append(f"IGES has no assembly instances: {n} instances of '{part}' written as copies")
        lines.append(f"IGES has no assembly structure: {n_leaves} part instances written as placed copies "
                     "at the top level, named after the instance")
        overrides = instance_overrides(model.assembly)
        if overrides:
            lines.append(f"IGES has no per-instance colour overrides: {len(overrides)} written as the colour of "
                         f"the instance's placed copy (e.g. '{overrides[0][0]}')")
    transparent = sum(1 for f in model.faces if f.color is not None and f.color[3] < 1.0)
    if transparent:
        lines.append(f"IGES has no transparency: the alpha of {transparent} faces is dropped (their colour is kept)")
    return lines


def compare(before: Any, after: Any, out_fmt: str, unit: str) -> list[str]:
    """One line per property that differs between the model written and the file read back."""
    lines: list[str] = []
    if after.unit != unit:
        lines.append(f"unit: written as '{unit}', read back as '{after.unit}'")
    if len(after.faces) != len(before.faces):
        lines.append(f"faces: {len(before.faces)} written, {len(after.faces)} read back")
        return lines
    def color(item: Any) -> Any:
        return item.color if out_fmt == "step" or item.color is None else item.color[:3]

    checks: dict[str, Any] = {"names": lambda f: f.name, "colours": color, "layers": lambda f: f.layer}
    if out_fmt == "step":
        checks["instance paths"] = lambda f: f.instance
    lines += _changed(before.faces, after.faces, "faces", "face", checks)
    if out_fmt == "step" and before.assembly is not None:
        lines += _structure_changes(before.assembly, after.assembly)
    if len(after.edges) != len(before.edges):
        lines.append(f"free curves: {len(before.edges)} written, {len(after.edges)} read back")
    else:
        edge_checks: dict[str, Any] = {"colours": color, "layers": lambda e: e.layer}
        if out_fmt == "step":
            edge_checks["instance paths"] = lambda e: e.instance
        lines += _changed(before.edges, after.edges, "free curves", "curve", edge_checks)
    return lines + _geometry_changes(before, after, AREA_RTOL[out_fmt])


def _structure_changes(before: Any, after: Any) -> list[str]:
    """STEP keeps an assembly: the same tree (instance paths) and part names read back, else one line.
    Faces' own instance paths are compared elsewhere; this covers what a face does not name: the parts
    (an instance written as a copy of its part comes back as another part, ``'plate#2'``) and
    sub-assemblies without faces."""
    from .xcaf import iter_nodes

    if after is None:
        return ["assembly structure not carried: the file read back has none (flat)"]
    a = [(path, node.part, len(node.children)) for path, node in iter_nodes(before)]
    b = [(path, node.part, len(node.children)) for path, node in iter_nodes(after)]
    if [(x[0], x[2]) for x in a] != [(y[0], y[2]) for y in b]:
        first = next(((x, y) for x, y in zip(a, b) if (x[0], x[2]) != (y[0], y[2])), None)
        where = ("" if first is None else f" ({first[0][0]!r} read back as {first[1][0]!r})" if first[0][0] != first[1][0]
                 else f" ({first[0][0]!r}: {first[0][2]} children read back as {first[1][2]})")
        return [f"assembly structure not carried: {len(a)} nodes written, {len(b)} read back{where}"]
    lines = []
    renamed = [(x[0], x[1], y[1]) for x, y in zip(a, b) if x[1] != y[1]]
    if renamed:
        path, was, now = renamed[0]
        lines.append(f"part names of {len(renamed)} of {len(a)} assembly nodes not carried ({path}: {was!r} read back "
                     f"as {now!r})")
    return lines


def _changed(before: Any, after: Any, items: str, item: str, checks: dict[str, Any]) -> list[str]:
    """One line per property (``checks``: name -> value of an item) that differs between paired items."""
    lines = []
    for what, key in checks.items():
        changed = [(a, b) for a, b in zip(before, after) if not _same(key(a), key(b))]
        if changed:
            a, b = changed[0]
            lines.append(f"{what} of {len(changed)} of {len(before)} {items} not carried "
                         f"({item} {a.index}: {key(a)!r} read back as {key(b)!r})")
    return lines


def _geometry_changes(before: Any, after: Any, rtol: float) -> list[str]:
    """Faces whose wire count changed, or whose area moved by more than ``rtol`` of itself (with the
    largest change, and whether it stays within the band the face's edge tolerances leave open)."""
    wires = [(a.index, wire_count(a.face), wire_count(b.face)) for a, b in zip(before.faces, after.faces)]
    lines = [f"boundaries: the wire count of {len(bad)} faces changed (face {bad[0][0]}: {bad[0][1]} -> {bad[0][2]})"
             for bad in [[w for w in wires if w[1] != w[2]]] if bad]
    import numpy as np

    moved, shifted = [], []
    centres = []
    for a, b in zip(before.faces, after.faces):
        (area_a, centre_a), (area_b, centre_b) = _area_centre(a.face), _area_centre(b.face)
        centres.append(centre_a)
        shifted.append((float(np.linalg.norm(centre_b - centre_a)), a.index))
        change = abs(area_b - area_a)
        if change > rtol * abs(area_a):
            moved.append((change / abs(area_a) if area_a else float("inf"), a.index, change <= trim_band(a.face)))
    if moved:
        worst = max(moved)
        inside = sum(m[2] for m in moved)
        lines.append(f"areas of {len(moved)} of {len(before.faces)} faces moved by more than {rtol:g} of themselves "
                     f"(face {worst[1]}: {worst[0]:.2g}; {inside} of them within their edges' tolerance band, "
                     "where OCC's reader recomputes the trimming)")
    if shifted:
        diagonal = _diagonal(before.faces)
        far = [s for s in shifted if s[0] > POSITION_RTOL * diagonal]
        if far:
            worst_shift = max(far)
            lines.append(f"positions of {len(far)} of {len(before.faces)} faces not carried: their centroids moved by "
                         f"more than {POSITION_RTOL:g} of the model's size (face {worst_shift[1]}: "
                         f"{worst_shift[0]:.3g}, model diagonal {diagonal:.3g})")
    return lines


def _area_centre(face: Any) -> tuple[float, Any]:
    """OCC's area and centroid of a face (``BRepGProp.SurfaceProperties_s`` to 1e-9), as in :func:`face_area`."""
    import numpy as np
    from OCP.BRepGProp import BRepGProp
    from OCP.GProp import GProp_GProps

    props = GProp_GProps()
    BRepGProp.SurfaceProperties_s(face, props, 1e-9)
    c = props.CentreOfMass()
    return float(props.Mass()), np.array([c.X(), c.Y(), c.Z()])


def _diagonal(faces: Any) -> float:
    """The diagonal of the faces' bounding box (OCC's ``BRepBndLib``)."""
    from OCP.Bnd import Bnd_Box
    from OCP.BRepBndLib import BRepBndLib

    box = Bnd_Box()
    for f in faces:
        BRepBndLib.Add_s(f.face, box)
    if box.IsVoid():
        return 0.0
    x0, y0, z0, x1, y1, z1 = box.Get()
    return float(((x1 - x0) ** 2 + (y1 - y0) ** 2 + (z1 - z0) ** 2) ** 0.5)


def face_area(face: Any) -> float:
    """OCC's area of a face (``BRepGProp.SurfaceProperties_s`` to 1e-9)."""
    from OCP.BRepGProp import BRepGProp
    from OCP.GProp import GProp_GProps

    props = GProp_GProps()
    BRepGProp.SurfaceProperties_s(face, props, 1e-9)
    return float(props.Mass())


def wire_count(face: Any) -> int:
    """How many wires (outer boundary and holes) a face has."""
    from OCP.TopAbs import TopAbs_WIRE
    from OCP.TopExp import TopExp_Explorer

    ex, n = TopExp_Explorer(face, TopAbs_WIRE), 0
    while ex.More():
        n += 1
        ex.Next()
    return n


def trim_band(face: Any) -> float:
    """Sum over the face's edges of length x tolerance: the area its trimming is uncertain by.

    A face's boundary is only defined to within its edges' tolerances; a reader that recomputes the
    p-curves from the 3-D edges may trim anywhere in that band (measured: the bearing's 8e-6 mm2
    face 0, edge tolerance 1.9e-6, comes back 1.6e-4 larger through OCC's own STEPControl_Writer too).
    """
    from OCP.BRep import BRep_Tool
    from OCP.BRepGProp import BRepGProp
    from OCP.GProp import GProp_GProps
    from OCP.TopAbs import TopAbs_EDGE
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopoDS import TopoDS

    band, ex = 0.0, TopExp_Explorer(face, TopAbs_EDGE)
    while ex.More():
        edge = TopoDS.Edge_s(ex.Current())
        props = GProp_GProps()
        BRepGProp.LinearProperties_s(edge, props)
        band += props.Mass() * BRep_Tool.Tolerance_s(edge)
        ex.Next()
    return band


def _same(a: Any, b: Any) -> bool:
    if isinstance(a, tuple) and isinstance(b, tuple) and len(a) == len(b):
        return all(abs(x - y) <= COLOR_TOLERANCE for x, y in zip(a, b))
    return bool(a == b)
