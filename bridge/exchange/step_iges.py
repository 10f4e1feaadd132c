"""STEP and IGES exchange: read every face and free edge as our splines, write ours losslessly.

Reading (:func:`read_step`, :func:`read_iges`) returns an :class:`ImportedModel`: the OCC shape,
then per face (``TopExp_Explorer`` order, each face once) its original surface type, OCC's
continuity class and periodicity, the surface converted by :func:`occsurf.bridge.conversion.splines.from_occ`
(exact for B-spline faces) and the name the file carries for it; per free edge (an edge that
bounds no face) the same for its curve. A face or edge that does not convert gets ``error`` set;
it never fails the whole file.

Writing (:func:`write_step`, :func:`write_iges`) takes our surfaces and curves (or any OCC,
build123d or cadquery shape), in millimetres, with optional names (unclamped splines are written as
their ``clamp()``, the same geometry; see :func:`write_step`), and replaces the target file
atomically: the file is produced in memory, written to a temporary file in the same directory and
moved over the target with :func:`os.replace`, so a failure never leaves a partial file behind and
never clobbers an existing one.

Precision
---------
STEP
    OCC's default STEP writer formats reals with ``%14.12E``, and ``%14.12f`` for
    ``0.1 <= |x| < 1000``: 13 significant digits, but only 12 decimals in that range, so a value
    moves by up to ``5e-13 |x|``, ``5e-12 |x|`` just above 0.1 (measured on random rational
    surfaces: 4.9e-12 per value, 2.6e-13 median relative to the largest coordinate), knots too.
    :func:`write_step` prints the same model through ``StepData_StepWriter`` with its
    ``FloatWriter`` set to ``%.16E`` (``precision_digits`` = 17 significant digits, no zero
    suppression). 17 significant digits identify an IEEE double and OCC parses reals with correct
    rounding, so write then read returns **bit-identical** poles, knots and weights. Two OCC
    behaviours remain: weights that are all equal (to an ulp) come back as ``None``, since
    ``Geom_BSpline*`` drops them; a closed spline (end poles, or end rows of poles, coinciding)
    comes back periodic, the same geometry in OCC's periodic representation, because OCC's reader
    makes it so.
IGES
    OCC's IGES writer formats reals with ``%11.9E`` (10 significant digits), ``%11.9f`` for
    ``0.1 <= |x| < 1000``. A value therefore comes back within :data:`IGES_RELATIVE_ERROR`
    (``5e-9 |x|``, the worst case being ``|x|`` just above 0.1 where 9 decimals are 9 significant
    digits). :func:`write_iges` keeps OCC's format: the global section declares 15 significant
    digits, and no more is claimed here.

Units
-----
Files are written in millimetres (``write.step.unit``/IGES global unit ``MM``), whatever a caller
set in ``Interface_Static``, and read in millimetres: values are unchanged by a round trip. A file
in another unit is converted to millimetres by OCC on reading.

Names
-----
STEP
    ``names[i]`` becomes the ``PRODUCT`` id and name of the i-th object and the name of the item
    OCC maps it to (the ``ADVANCED_FACE`` of a surface, the ``GEOMETRIC_CURVE_SET`` of a curve);
    an object without a name gets an empty product name. On reading, a face or edge takes the
    name of its own entity if it has one (neither empty nor ``'NONE'``), else the name of the
    product it belongs to. Any Unicode name survives a round trip (written as UTF-8).
IGES
    ``names[i]`` becomes a Name property (entity 406, form 15, full length, attached to every
    independent entity of the object) and, as ASCII with non-ASCII characters replaced by ``_``,
    the first 8 characters of their entity label. On reading, a face or edge takes the name value
    (the 406 name, else the 8-character label) of its own entity, else that of the root entity it
    came from. Full names, Unicode included, survive OCC's round trip; another reader may only see
    the 8-character label.

Corrupt files
-------------
OCC must never see a file that failed to parse: ``TransferRoots`` after a failed ``ReadFile``
crashes the process. Before OCC parses anything, a STEP file must start with ``ISO-10303-21;`` and
end with ``END-ISO-10303-21;``; an IGES file must end with a Terminate section whose line counts
match the Start, Global, Directory and Parameter sections (a truncated IGES file otherwise reads as
a valid-looking face with wrong poles). :mod:`occsurf.bridge.exchange.checks` (and :mod:`~occsurf.bridge.exchange.iges_checks`) then refuses what
crashes OCC's parsers (deep nesting, reference cycles, impossible B-spline counts) and prunes
references to undefined instances; what OCC reads but should not accept silently becomes
``ImportedModel.warnings``. Every refusal raises :class:`ExchangeError` naming the path. A file from
an untrusted source is best read with ``isolated=True``: a crash inside OCC that no check foresaw
then costs a worker process, not the caller.
"""

from __future__ import annotations

import io
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from occsurf.algorithms.errors import ExchangeError, InvalidGeometryError

from ..messages import one_line
from . import files as _files
from . import occ_io as _xocc
from . import write_checks, xcaf, xcaf_write
from .entity_names import BareIndex, entity_names, root_name
from .model import (  # noqa: F401 - the model types are part of this module's names
    ImportedEdge,
    ImportedFace,
    ImportedModel,
    _build_trimmed,
    _conversion_bounds,
    _geomabs_name,
    _import_edge,
    _import_face,
    _LazyTrimmed,
    _maps,
)
from .occ_io import FACE_TOLERANCE  # re-exported: part of the public constants

__all__ = [
    "ImportedFace",
    "ImportedEdge",
    "ImportedModel",
    "read_step",
    "read_iges",
    "write_step",
    "write_iges",
    "STEP_DIGITS",
    "STEP_DEFAULT_RELATIVE_ERROR",
    "IGES_RELATIVE_ERROR",
    "FACE_TOLERANCE",
]

#: Significant digits :func:`write_step` prints by default: 17 identify every IEEE double, so a
#: STEP round trip is bit-exact.
STEP_DIGITS: int = 17

#: Per-value relative error bound of OCC's default STEP writer (``%14.12f`` for ``0.1 <= |x| < 1000``:
#: 12 decimals, half a unit of 1e-12 on a value of 0.1; ``%14.12E`` elsewhere, 5e-13). Not used by
#: this module: documentation, and the bound the test of OCC's own writer checks.
STEP_DEFAULT_RELATIVE_ERROR: float = 5e-12

#: Per-value relative error bound of an IGES round trip: OCC writes ``%11.9f`` for
#: ``0.1 <= |x| < 1000`` (absolute error <= 5e-10, relative <= 5e-9 at ``|x| = 0.1``) and ``%11.9E``
#: elsewhere (10 significant digits, relative <= 5e-10); parsing adds at most half an ulp.
IGES_RELATIVE_ERROR: float = 5e-9



# ------------------------------------------------------------------------------------ reading
#: The job the reader process of ``read_step(..., isolated=True)`` runs, and what it loads first.
READ_JOB = "occsurf.bridge.exchange.step_iges:transfer_job"
READ_PRELOAD = ("occsurf.bridge.exchange.step_iges",)


def read_step(path: str | os.PathLike[str], *, isolated: bool = False, timeout: float | None = None,
              as_: str | None = None) -> ImportedModel | Any:
    """Read a STEP file: every face and free edge, converted to our splines.

    Parameters
    ----------
    path : str or path-like
    isolated : bool, default False
        Parse the file in a worker process (:func:`occsurf.bridge.isolation.run_jobs`): a crash or a
        hang inside OCC becomes an :class:`ExchangeError` naming the file instead of the end of this
        process. The shape comes back exactly (OCC's binary BRep); only the conversion to our splines
        runs here. Use it for files from untrusted sources.
    timeout : float, optional
        With ``isolated``: seconds the worker may take before it is stopped (default no limit).
    as_ : {None, 'build123d', 'cadquery'}
        Return the model as the objects build123d or cadquery users hold instead
        (:func:`occsurf.bridge.exchange.objects.to_build123d` / ``to_cadquery``): a build123d
        ``Compound`` tree (``label`` and ``color`` on every node, instances sharing their part's
        shape, each moved to its placement) or a cadquery ``Assembly`` (names, colours, locations,
        per-face colours and names as subshapes); a flat file as a ``Compound`` / ``Assembly``
        labelled with the file's stem, one child per top-level shape.

    Returns
    -------
    ImportedModel, or a build123d Compound / cadquery Assembly with ``as_``
        ``format == 'step'``. Values in millimetres. ``warnings`` lists what was wrong with the file
        but could be read around (see :mod:`occsurf.bridge.exchange.checks`): references to undefined
        instances (the partial model is read), OCC's check messages (wrong arity, a text for a number,
        more than 3 coordinates), fewer faces than face instances, closed shells that are open.

    Raises
    ------
    ExchangeError
        Missing file, a directory, a device, FIFO or dangling/looping symlink; an empty, truncated (no
        ``END-ISO-10303-21;``), unparsable or garbage file; nesting or cycles that crash OCC's parser;
        a valid file without any face or edge; with ``isolated``, a crash or a time-out of the reader
        process. The message names the path.
    """
    from .objects import check_as, convert_model

    check_as(as_)
    if isolated:
        return convert_model(_read_isolated(path, "step", timeout), as_)
    p, shape, names, warnings, xdata = _transfer(path, "step")
    return convert_model(_convert(p, "step", shape, names, warnings, xdata), as_)


def read_iges(path: str | os.PathLike[str], *, isolated: bool = False, timeout: float | None = None,
              as_: str | None = None) -> ImportedModel | Any:
    """Read an IGES file: every face and free edge, converted to our splines.

    B-spline curves are taken as the file gives them (``read.iges.bspline.continuity = 0``:
    OCC neither removes knots nor splits C0 curves).

    Parameters
    ----------
    path : str or path-like
    isolated, timeout, as_
        As :func:`read_step`.

    Returns
    -------
    ImportedModel
        ``format == 'iges'``. Values in millimetres; ``warnings`` as :func:`read_step` (OCC's check
        messages).

    Raises
    ------
    ExchangeError
        Missing file, a directory, a device or broken symlink; an empty, truncated (Terminate section
        missing or not matching the section lengths), binary/compressed, unparsable or garbage file; a
        directory entry without its parameters, a B-spline entity (126/128) with impossible counts; a
        valid file without any face or edge; with ``isolated``, a crash or time-out of the reader
        process. The message names the path.
    """
    from .objects import check_as, convert_model

    check_as(as_)
    if isolated:
        return convert_model(_read_isolated(path, "iges", timeout), as_)
    p, shape, names, warnings, xdata = _transfer(path, "iges")
    return convert_model(_convert(p, "iges", shape, names, warnings, xdata), as_)


def _occ_name(p: Path) -> str:
    """The file name as OCC can take it (a name that is not UTF-8 would fail pybind's conversion)."""
    return os.fsencode(p).decode("utf-8", "replace")


def _transfer(path: str | os.PathLike[str], fmt: str) -> tuple[Path, Any, tuple[dict[int, str], dict[int, str]],
                                                               list[str], Any]:
    """Check, parse and transfer a file: ``(path, shape, (face names, edge names), warnings, xcaf data)``.

    The file is parsed by OCC's XCAF reader; the roots are transferred one by one (a root that fails
    is a warning), then the same transfer fills an XCAF document (:func:`.xcaf.read_xcaf`): unit,
    assembly tree, colours, layers, instances. In an assembly a face without a name of its own is
    named after its instance."""
    from . import checks, iges_checks, read_warnings

    kind = fmt.upper()
    p, data = _files.load(path, kind)
    if fmt == "step":
        _files.check_step_text(p, data)
        scan = checks.scan_step(p, data)
        warnings = list(scan.warnings)
    else:
        _files.check_iges_text(p, data)
        iges_scan = iges_checks.scan_iges(p, data)
        warnings = list(iges_scan.warnings)
        scan = None
    from OCP.IFSelect import IFSelect_ReturnStatus

    settings: dict[str, str | int | float] = {"xstep.cascade.unit": "MM", "read.stepcaf.subshapes.name": 1}
    if fmt == "iges":
        settings["read.iges.bspline.continuity"] = 0
    with _xocc.statics(settings):
        try:
            reader, status, caf = _parse(p, fmt, scan.data if scan is not None else data)
        except Exception as err:  # noqa: BLE001 - any OCC failure is a bad file
            raise ExchangeError(f"{p}: {kind} parser failed: {one_line(err)}") from err
        # Checked BEFORE any transfer: TransferRoots after a failed read crashes the process.
        if status != IFSelect_ReturnStatus.IFSelect_RetDone:
            raise ExchangeError(f"{p}: not a readable {kind} file (OCC read status {status.name})")
        if scan is not None:
            reader, scan, warnings, caf = _without_broken(p, data, reader, scan, warnings, caf)
        warnings += read_warnings.occ_check_warnings(reader, fmt, scan)
        if fmt == "step":
            reader.SetSystemLengthUnit(1.0)  # millimetres
        unit, scale, unit_warnings = xcaf.step_unit(reader) if fmt == "step" else xcaf.iges_unit(reader)
        try:
            shape, names, root_warnings, own_face_names = _transfer_roots(p, reader)
        except ExchangeError as err:
            if not warnings:
                raise
            raise ExchangeError(f"{err} ({warnings[0]})") from err
        warnings += root_warnings + unit_warnings
        warnings += read_warnings.model_warnings(shape, reader, scan if fmt == "step" else iges_scan, _count_bare_faces(shape))
        faces_map, edges_map = _maps(shape)
        xdata = xcaf.read_xcaf(caf, faces_map, BareIndex(faces_map), p.stem, (edges_map, BareIndex(edges_map)))
        xdata.unit, xdata.unit_scale = unit, scale
        if fmt == "iges":  # names and levels of uncoloured faces in groups; level names (406 form 3)
            own_names, levels = xcaf.iges_face_attributes(reader.WS().TransferReader(), faces_map,
                                                          {**xdata.face_names, **own_face_names}, xdata.layers)
            own_face_names.update(own_names)
            names[0].update(own_names)
            for i, level in levels.items():
                xdata.layers.setdefault(i, level)
            xcaf.name_levels(xdata, xcaf.iges_level_names(data))
        warnings += xdata.warnings
        for i, instance_name in xdata.instance_names.items():  # own name, else the instance's
            names[0][i] = own_face_names.get(i) or xdata.face_names.get(i) or instance_name
        for i, face_name in xdata.face_names.items():  # flat models too: a face's own name wins
            names[0][i] = own_face_names.get(i) or face_name
    del caf
    return p, shape, names, warnings, xdata


def _without_broken(p: Path, data: bytes, reader: Any, scan: Any, warnings: list[str],
                    caf: Any) -> tuple[Any, Any, list[str], Any]:
    """Parse again without the instances OCC read with a null field (a reference of the wrong type:
    transferring them crashes the process), as long as it finds such instances (at most 3 rounds)."""
    from OCP.IFSelect import IFSelect_ReturnStatus

    from . import checks, read_warnings

    broken: dict[int, str] = {}
    for _ in range(3):
        new = read_warnings.occ_broken_ids(reader, scan)
        if not new or new.keys() <= broken.keys():
            break
        broken.update(new)
        scan = checks.scan_step(p, data, broken)
        warnings = list(scan.warnings)
        try:
            reader, status, caf = _parse(p, "step", scan.data)
        except Exception as err:  # noqa: BLE001
            raise ExchangeError(f"{p}: STEP parser failed: {one_line(err)}") from err
        if status != IFSelect_ReturnStatus.IFSelect_RetDone:
            raise ExchangeError(f"{p}: not a readable STEP file (OCC read status {status.name})")
    return reader, scan, warnings, caf


def _parse(p: Path, fmt: str, data: bytes) -> tuple[Any, Any, Any]:
    """OCC's XCAF reader on ``data`` (the checked bytes, not the file again): ``(reader, status, caf)``:
    ``reader`` the ``STEPControl_Reader``/``IGESControl_Reader`` inside ``caf`` (keep ``caf`` alive
    while ``reader`` is used)."""
    if fmt == "step":
        from OCP.STEPCAFControl import STEPCAFControl_Reader

        caf = STEPCAFControl_Reader()
        reader = caf.ChangeReader()
        return reader, reader.ReadStream(_occ_name(p), io.BytesIO(data)), caf
    import tempfile

    from OCP.IGESCAFControl import IGESCAFControl_Reader

    reader = IGESCAFControl_Reader()  # reads files only: a private copy of the checked bytes
    with tempfile.TemporaryDirectory(prefix="occsurf-iges-") as tmp:
        copy = Path(tmp) / "model.igs"
        copy.write_bytes(data)
        return reader, reader.ReadFile(str(copy)), reader


def _count_bare_faces(shape: Any) -> int:
    """Distinct faces of ``shape`` whatever their location (an instanced part counts once)."""
    from OCP.TopAbs import TopAbs_FACE
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopLoc import TopLoc_Location
    from OCP.TopTools import TopTools_IndexedMapOfShape

    identity = TopLoc_Location()
    bare = TopTools_IndexedMapOfShape()
    ex = TopExp_Explorer(shape, TopAbs_FACE)
    while ex.More():
        bare.Add(ex.Current().Located(identity))
        ex.Next()
    return bare.Extent()


def transfer_job(item: dict[str, Any]) -> dict[str, Any]:
    """The reader process's job of ``read_step/read_iges(..., isolated=True)``.

    Parses ``item["path"]`` (``item["format"]``: ``'step'``/``'iges'``), writes the shape to
    ``item["out"]`` as OCC binary BRep and returns the names (by face and free-edge index, in the
    order :func:`_convert` explores them), the warnings and the counts.
    """
    from OCP.BinTools import BinTools

    p, shape, (face_names, edge_names), warnings, xdata = _transfer(item["path"], item["format"])
    xdoc, prototypes = xdata.to_json()
    # one BRep holding the model and the assembly's prototypes: shared sub-shapes stay shared
    if not BinTools.Write_s(xcaf.compound([shape, *prototypes]) if prototypes else shape, item["out"]):
        raise ExchangeError(f"{p}: cannot pass the model on ({item['out']} not written)")
    faces_map, edges_map = _maps(shape)
    return {"faces": faces_map.Extent(), "edges": edges_map.Extent(), "warnings": warnings,
            "face_names": {str(k): v for k, v in face_names.items()},
            "edge_names": {str(k): v for k, v in edge_names.items()},
            "xcaf": xdoc, "n_prototypes": len(prototypes)}


def _read_isolated(path: str | os.PathLike[str], fmt: str, timeout: float | None) -> ImportedModel:
    import tempfile

    from OCP.BinTools import BinTools
    from OCP.TopoDS import TopoDS_Shape

    from ..isolation import CRASHED, ERROR, OK, TIMEOUT, run_jobs

    p = Path(os.fsdecode(path))
    with tempfile.TemporaryDirectory(prefix="occsurf-read-") as tmp:
        out = str(Path(tmp) / "shape.brep")
        item = {"path": os.fspath(p), "format": fmt, "out": out}
        try:
            [outcome] = run_jobs(READ_JOB, [item], timeout=timeout, preload=READ_PRELOAD)
        except ValueError as err:  # a bad timeout
            raise InvalidGeometryError(str(err)) from err
        if outcome.status == ERROR:
            raise ExchangeError(outcome.error if str(p) in (outcome.error or "") else f"{p}: {outcome.error}")
        if outcome.status == TIMEOUT:
            raise ExchangeError(f"{p}: reading took longer than {timeout:g} s; the reader process was stopped")
        if outcome.status == CRASHED:
            raise ExchangeError(f"{p}: the reader process crashed while reading the file ({outcome.exit_reason}; "
                                "a fault inside OpenCascade)")
        if outcome.status != OK:
            raise ExchangeError(f"{p}: the reader process failed ({outcome.exit_reason or outcome.error})")
        shape = TopoDS_Shape()
        if not BinTools.Read_s(shape, out) or shape.IsNull():
            raise ExchangeError(f"{p}: the reader process's model could not be loaded")
    info = outcome.value
    names = ({int(k): v for k, v in info["face_names"].items()}, {int(k): v for k, v in info["edge_names"].items()})
    prototypes: list[Any] = []
    if info["n_prototypes"]:
        from OCP.TopoDS import TopoDS_Iterator

        it = TopoDS_Iterator(shape)
        parts = []
        while it.More():
            parts.append(it.Value())
            it.Next()
        if len(parts) != 1 + info["n_prototypes"]:
            raise ExchangeError(f"{p}: the reader process's model could not be loaded (assembly parts missing)")
        shape, prototypes = parts[0], parts[1:]
    xdata = xcaf.XcafData.from_json(info["xcaf"], prototypes)
    model = _convert(p, fmt, shape, names, list(info["warnings"]), xdata)
    if (len(model.faces), len(model.edges)) != (info["faces"], info["edges"]):
        raise ExchangeError(f"{p}: the model changed on its way from the reader process "
                            f"({info['faces']} faces, {info['edges']} edges; got {len(model.faces)}, {len(model.edges)})")
    return model


def _transfer_roots(p: Path, reader: Any) -> tuple[Any, tuple[dict[int, str], dict[int, str]], list[str],
                                                  dict[int, str]]:
    """Transfer every root: ``(shape, (face names, edge names) by 1-based map index, warnings, own face names)``."""
    n_roots = reader.NbRootsForTransfer()
    if n_roots == 0:
        raise ExchangeError(f"{p}: no transferable entities in the file")
    warnings: list[str] = []
    root_shapes: list[tuple[Any, str | None]] = []
    for i in range(1, n_roots + 1):
        root = reader.RootForTransfer(i)
        before = reader.NbShapes()
        try:
            reader.TransferOneRoot(i)
        except Exception as err:  # noqa: BLE001 - keep the other roots
            warnings.append(f"root {i} not transferred: {one_line(err)}")
            continue
        if reader.NbShapes() == before:
            warnings.append(f"root {i} ({root.DynamicType().Name()}) gave no shape")
        name = root_name(root)
        new = [reader.Shape(k) for k in range(before + 1, reader.NbShapes() + 1)]
        root_shapes.extend((s, name) for s in new if not s.IsNull())  # a null shape crashes OCP
    shape = reader.OneShape()
    if not root_shapes or shape.IsNull():
        raise ExchangeError(f"{p}: none of the {n_roots} roots of the file could be transferred")
    faces_map, edges_map = _maps(shape)
    if faces_map.Extent() == 0 and edges_map.Extent() == 0:
        raise ExchangeError(f"{p}: the file holds no faces and no curves")
    names, own_face_names = entity_names(reader, root_shapes, faces_map, edges_map)
    return shape, names, warnings, own_face_names


def _convert(p: Path, fmt: str, shape: Any, names: tuple[dict[int, str], dict[int, str]],
             warnings: list[str], xdata: xcaf.XcafData | None = None) -> ImportedModel:
    """The :class:`ImportedModel` of a transferred shape: every face and free edge converted."""
    from dataclasses import replace

    faces_map, edges_map = _maps(shape)
    face_names, edge_names = names
    x = xdata if xdata is not None else xcaf.XcafData()
    faces = []
    for i in range(1, faces_map.Extent() + 1):
        face = _import_face(i - 1, faces_map.FindKey(i), face_names.get(i))
        color, layer, instance = x.colors.get(i), x.layers.get(i), x.instances.get(i)
        if color is not None or layer is not None or instance is not None:
            face = replace(face, color=color, layer=layer, instance=instance)
        faces.append(face)
    edges = [_import_edge(i - 1, edges_map.FindKey(i), edge_names.get(i)) for i in range(1, edges_map.Extent() + 1)]
    edges = [replace(e, color=x.edge_colors.get(i), layer=x.edge_layers.get(i), instance=x.edge_instances.get(i))
             if i in x.edge_colors or i in x.edge_layers or i in x.edge_instances else e
             for i, e in enumerate(edges, start=1)]
    for what, entries in (("face", faces), ("curve", edges)):
        for e in entries:
            if e.error is not None and "expected finite values" in e.error:
                how = (f"after scaling from {x.unit} to mm (x{x.unit_scale:g})" if x.unit_scale != 1.0 else "in the file")
                warnings.append(f"{what} {e.index}: coordinates not finite {how}: {e.error}")
    return ImportedModel(path=str(p), format=fmt, shape=shape, faces=faces, edges=edges, warnings=warnings,
                         unit=x.unit, unit_scale=x.unit_scale, assembly=x.assembly)


def write_step(
    path: str | os.PathLike[str],
    objects: Any,
    names: str | Sequence[str | None] | None = None,
    *,
    precision_digits: int = STEP_DIGITS,
    replace_readonly: bool = False,
    unit: str | None = None,
) -> Path:
    """Write surfaces, curves and shapes, or a read model with its structure, to a STEP file (AP214), atomically.

    Parameters
    ----------
    path : str or path-like
        The target; an existing file is replaced only once the new one is complete.
    objects : object or sequence of objects
        :class:`BSplineSurface` (written as one face over its whole domain; a hierarchical surface or
        curve, such as a posed figure's ``AttachedSurface.at(pose)``, as its exact ``flatten()``), :class:`BSplineCurve`
        (one edge), ``TopoDS_Shape``, build123d or cadquery shapes (or a cadquery ``Workplane``).
        Surfaces and curves must be 3-D. Each object is one STEP product. A spline with an
        unclamped knot vector is written as its ``clamp()`` (the same geometry): OCC's STEP writer
        silently drops some unclamped rational faces and its reader trims others.
        Or an :class:`ImportedModel` (from :func:`read_step`/:func:`read_iges`) or an
        :class:`~occsurf.bridge.exchange.xcaf.AssemblyNode` tree: written through OCC's XCAF writer
        with its assembly structure (each part once, instances as references with their placements),
        the names of parts, instances and faces, the colours and layers of instances and faces.
        A build123d ``Compound`` with ``children`` or a cadquery ``Assembly`` (without ``names``) is
        written the same way, as :func:`occsurf.bridge.exchange.object_import.model_from_object` reads it
        (labels / names, colours, placements, shared parts, cadquery subshape colours and names).
    names : str or sequence of (str or None), optional
        One name per object (a str for a single object); see the module notes for where they go.
        Not with a model or a tree (they carry their names).
    precision_digits : int, default 17
        Significant digits of every real, 2 to 17. 17 makes the round trip bit-exact; OCC's own
        writer uses 13.
    replace_readonly : bool, default False
        Replace an existing read-only file (refused otherwise). A target that exists and is not a
        regular file (a device such as ``/dev/null``, a FIFO, a socket) is always refused; a symlink
        to a regular file is followed (the link stays, its target is replaced).
    unit : str, optional
        Length unit the file declares, a key of :data:`occsurf.bridge.exchange.xcaf.UNITS` (``'mm'``,
        ``'m'``, ``'inch'``...): values are written divided by its size in millimetres and read back
        unchanged. Default: the model's ``unit``, else ``'mm'``.

    Returns
    -------
    pathlib.Path

    Raises
    ------
    InvalidGeometryError
        An unsupported, null or non-3-D object; ``names``, ``precision_digits`` or ``unit`` invalid.
    KernelError
        OCC could not build a face or edge from a surface or curve.
    ExchangeError
        The path is a directory or not writable; OCC failed to translate or print the model, or
        silently left out a face (one degenerate at :data:`FACE_TOLERANCE`, e.g. all of whose
        boundary collapses). No file is created or modified in any failure.
    """
    p = _files.target(path, replace_readonly=replace_readonly)
    if isinstance(precision_digits, bool) or not isinstance(precision_digits, int) or not 2 <= precision_digits <= 17:
        raise InvalidGeometryError(f"precision_digits: expected an integer from 2 to 17, got {precision_digits!r}")
    objects = _assembly_as_model(objects, names)
    file_unit = _write_unit(objects, names, unit)
    if isinstance(objects, (ImportedModel, xcaf.AssemblyNode)):
        write_checks.refuse(p, "step", objects, None)
        data = xcaf_write.step_document_bytes(p, objects, precision_digits, file_unit)
    else:
        items = _xocc.normalise(objects, names)
        write_checks.refuse(p, "step", objects, items)
        data = _xocc.step_bytes(p, items, precision_digits, file_unit)
    _files.atomic_write(p, data, replace_readonly=replace_readonly)
    return p


def _assembly_as_model(objects: Any, names: Any) -> Any:
    """A build123d Compound tree or a cadquery Assembly (without ``names``) as the model of its
    structure, names and colours (:func:`occsurf.bridge.exchange.object_import.model_from_object`)."""
    from .object_import import is_assembly_object, model_from_object

    return model_from_object(objects, "objects") if names is None and is_assembly_object(objects) else objects


def _write_unit(objects: Any, names: Any, unit: str | None) -> str:
    """The unit to write (checked); a model or a tree takes no ``names``."""
    if isinstance(objects, (ImportedModel, xcaf.AssemblyNode)) and names is not None:
        raise InvalidGeometryError("names: a model or an assembly tree carries its own names; got names as well")
    if unit is None:
        unit = objects.unit if isinstance(objects, ImportedModel) else "mm"
    if unit not in xcaf.WRITE_UNITS:
        raise InvalidGeometryError(f"unit: expected one of {', '.join(xcaf.WRITE_UNITS)}, got {unit!r}")
    return unit


def write_iges(
    path: str | os.PathLike[str],
    objects: Any,
    names: str | Sequence[str | None] | None = None,
    *,
    replace_readonly: bool = False,
    unit: str | None = None,
) -> Path:
    """Write surfaces, curves and shapes to an IGES file (millimetres, faces as 144/128), atomically.

    IGES keeps 10 significant digits (9 decimals for ``0.1 <= |x| < 1000``): values come back within
    :data:`IGES_RELATIVE_ERROR` (``5e-9 |x|``). Use :func:`write_step` for lossless exchange.

    Parameters
    ----------
    path, objects, names, replace_readonly, unit
        As :func:`write_step`. A model or tree keeps names, colours (without transparency: IGES has
        none) and layers (IGES levels by name); IGES has no instances, so each part instance is
        written as a placed copy of its part, named after the instance.

    Returns
    -------
    pathlib.Path

    Raises
    ------
    InvalidGeometryError, KernelError, ExchangeError
        As :func:`write_step`.
    """
    p = _files.target(path, replace_readonly=replace_readonly)
    objects = _assembly_as_model(objects, names)
    file_unit = _write_unit(objects, names, unit)
    if isinstance(objects, (ImportedModel, xcaf.AssemblyNode)):
        write_checks.refuse(p, "iges", objects, None)
        data = xcaf_write.iges_document_bytes(p, objects, file_unit)
        items = None
    else:
        items = _xocc.normalise(objects, names)
        write_checks.refuse(p, "iges", objects, items)
        data = _xocc.iges_bytes(p, items, file_unit)
    write_checks.check_iges_bytes(p, data, objects, items)
    _files.atomic_write(p, data, replace_readonly=replace_readonly)
    return p
