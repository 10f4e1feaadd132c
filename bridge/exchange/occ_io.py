"""OCC side of :mod:`occsurf.bridge.exchange.step_iges`: the translator session (messages, ``Interface_Static``
parameters) and the export pipeline (objects to shapes, shapes to STEP or IGES bytes with names).

The bytes are produced in memory; :mod:`occsurf.bridge.exchange.files` puts them on disk atomically.
"""

from __future__ import annotations

import contextlib
import io
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from occsurf.algorithms import BSplineCurve, BSplineSurface, TrimmedSurface
from occsurf.algorithms.errors import ExchangeError, InvalidGeometryError, KernelError

from ..messages import one_line

__all__ = ["FACE_TOLERANCE", "silence_occ", "statics", "normalise", "step_bytes", "print_step", "iges_bytes"]

#: Tolerance (model units) of the faces and edges built from our surfaces and curves for export:
#: OCC's ``Precision::Confusion()``.
FACE_TOLERANCE: float = 1e-7


# ------------------------------------------------------------------------------- OCC session
def silence_occ() -> contextlib.AbstractContextManager[None]:
    """``with silence_occ():`` only failures reach OCC's message printers in the block (no translator
    banners on stdout); the caller's levels come back after it (:func:`occsurf.bridge._occ.quiet_messages`).
    :func:`statics` does the same, so translator code inside a ``statics`` block needs nothing else."""
    from .._occ import quiet_messages

    return quiet_messages()


@contextlib.contextmanager
def statics(values: dict[str, str | int | float]) -> Iterator[None]:
    """Set ``Interface_Static`` parameters for the block, then restore the caller's values.

    The block is also a translator session: OCC's message printers print failures only inside it and
    get the caller's trace levels back after it (:func:`occsurf.bridge._occ.quiet_messages`).
    """
    with silence_occ(), _static_values(values):
        yield


@contextlib.contextmanager
def _static_values(values: dict[str, str | int | float]) -> Iterator[None]:
    from OCP.IGESControl import IGESControl_Controller
    from OCP.Interface import Interface_Static
    from OCP.STEPControl import STEPControl_Controller

    STEPControl_Controller.Init_s()  # the statics exist once the controllers are initialised
    IGESControl_Controller.Init_s()
    get = {int: Interface_Static.IVal_s, float: Interface_Static.RVal_s, str: Interface_Static.CVal_s}
    put = {int: Interface_Static.SetIVal_s, float: Interface_Static.SetRVal_s, str: Interface_Static.SetCVal_s}
    saved: list[tuple[str, str | int | float]] = []
    try:
        for name, value in values.items():
            saved.append((name, get[type(value)](name)))
            put[type(value)](name, value)
        yield
    finally:
        for name, old in reversed(saved):
            put[type(old)](name, old)


# ------------------------------------------------------------------------------------ export
def normalise(objects: Any, names: Any) -> list[tuple[Any, str | None]]:
    """``[(TopoDS_Shape, name or None), ...]`` from the caller's objects and names."""
    seq = list(objects) if isinstance(objects, (list, tuple)) else [objects]
    if not seq:
        raise InvalidGeometryError("objects: expected at least one object to write, got an empty sequence")
    if names is None:
        name_list: list[Any] = [None] * len(seq)
    elif isinstance(names, str):
        if len(seq) != 1:
            raise InvalidGeometryError(f"names: a single str names a single object; got {len(seq)} objects")
        name_list = [names]
    else:
        try:
            name_list = list(names)
        except TypeError:
            raise InvalidGeometryError(
                f"names: expected a str or a sequence of str/None, got {type(names).__name__}"
            ) from None
        if len(name_list) != len(seq):
            raise InvalidGeometryError(f"names: expected {len(seq)} names (one per object), got {len(name_list)}")
    for i, nm in enumerate(name_list):
        if nm is not None and not isinstance(nm, str):
            raise InvalidGeometryError(f"names[{i}]: expected a str or None, got {type(nm).__name__}")
    return [(_as_shape(obj, f"objects[{i}]"), nm or None) for i, (obj, nm) in enumerate(zip(seq, name_list))]


def _as_shape(obj: Any, label: str) -> Any:
    from occsurf.algorithms.hierarchical import HierarchicalCurve, HierarchicalSurface

    if isinstance(obj, (HierarchicalSurface, HierarchicalCurve)):  # e.g. a posed figure: its exact flat form
        obj = obj.flatten()
    if isinstance(obj, TrimmedSurface):  # a trimmed face: its loops rebuilt (conversion.trimming)
        from ..conversion.splines import make_face

        if obj.dim != 3:
            raise InvalidGeometryError(f"{label}: expected a 3-D trimmed surface, got dimension {obj.dim}")
        s = obj.surface
        if not (_is_clamped(s.knots[0], s.degree[0]) and _is_clamped(s.knots[1], s.degree[1])):
            obj = TrimmedSurface(s.clamp(), obj.outer, obj.inner, obj.reversed)  # same parameters
        return make_face(obj)
    if isinstance(obj, (BSplineSurface, BSplineCurve)):
        kind = "surface" if isinstance(obj, BSplineSurface) else "curve"
        if obj.dim != 3:
            raise InvalidGeometryError(f"{label}: expected a 3-D {kind}, got dimension {obj.dim}")
        extent = float(np.ptp(obj.control_points.reshape(-1, 3), axis=0).max())
        if extent <= FACE_TOLERANCE:
            raise InvalidGeometryError(
                f"{label}: the {kind} is degenerate (its control points span {extent:.3g}, not more than "
                f"the tolerance {FACE_TOLERANCE:g}); STEP and IGES readers drop it"
            )
        if isinstance(obj, BSplineSurface):
            if not (_is_clamped(obj.knots[0], obj.degree[0]) and _is_clamped(obj.knots[1], obj.degree[1])):
                obj = obj.clamp()
            return _surface_face(obj, label)
        if not _is_clamped(obj.knots, obj.degree):
            obj = obj.clamp()
        return _curve_edge(obj, label)
    from ..conversion.shapes import as_shape, is_shape_like

    if not is_shape_like(obj):
        raise InvalidGeometryError(
            f"{label}: expected a BSplineSurface, BSplineCurve, TopoDS_Shape, build123d or cadquery shape, "
            f"got {type(obj).__name__}"
        )
    return as_shape(obj, label)  # TopoDS, build123d/cadquery shapes, Workplane, Assembly, builders


def _is_clamped(knots: Any, degree: int) -> bool:
    return bool((knots[: degree + 1] == knots[0]).all() and (knots[-degree - 1 :] == knots[-1]).all())


def _surface_face(surface: BSplineSurface, label: str) -> Any:
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace

    from ..conversion.splines import to_occ

    occ_surface = to_occ(surface)
    try:
        maker = BRepBuilderAPI_MakeFace(occ_surface, FACE_TOLERANCE)
        if maker.IsDone():
            return maker.Face()
        reason = maker.Error().name
    except Exception as err:  # noqa: BLE001
        raise KernelError(f"{label}: OCC could not build a face from the surface: {one_line(err)}") from err
    raise KernelError(f"{label}: OCC could not build a face from the surface ({reason})")


def _curve_edge(curve: BSplineCurve, label: str) -> Any:
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeEdge

    from ..conversion.splines import to_occ

    occ_curve = to_occ(curve)
    try:
        maker = BRepBuilderAPI_MakeEdge(occ_curve)
        if maker.IsDone():
            return maker.Edge()
        reason = maker.Error().name
    except Exception as err:  # noqa: BLE001
        raise KernelError(f"{label}: OCC could not build an edge from the curve: {one_line(err)}") from err
    raise KernelError(f"{label}: OCC could not build an edge from the curve ({reason})")


def step_bytes(p: Path, items: list[tuple[Any, str | None]], digits: int, unit: str = "mm") -> bytes:
    from OCP.IFSelect import IFSelect_ReturnStatus
    from OCP.StepBasic import StepBasic_Product
    from OCP.STEPConstruct import STEPConstruct
    from OCP.STEPControl import STEPControl_StepModelType, STEPControl_Writer
    from OCP.StepShape import StepShape_Face
    from OCP.TCollection import TCollection_HAsciiString
    from OCP.TopLoc import TopLoc_Location

    with statics({"write.step.unit": unit.upper()}):
        writer = STEPControl_Writer()
        for i, (shape, name) in enumerate(items):
            model = writer.WS().Model()
            first = model.NbEntities() + 1
            try:
                # compgraph only once, at the end: recomputing the model's graph after every
                # object made writing n objects O(n^2) (600 surfaces: 30 s instead of 0.4 s).
                last = i == len(items) - 1
                status = writer.Transfer(shape, STEPControl_StepModelType.STEPControl_AsIs, last)
            except Exception as err:  # noqa: BLE001
                raise ExchangeError(f"{p}: STEP translation of objects[{i}] failed: {one_line(err)}") from err
            if status != IFSelect_ReturnStatus.IFSelect_RetDone:
                raise ExchangeError(f"{p}: STEP translation of objects[{i}] failed (status {status.name})")
            model = writer.WS().Model()
            new = [model.Value(k) for k in range(first, model.NbEntities() + 1)]
            # OCC drops a face that is degenerate at its tolerance without a word: check.
            n_written = sum(isinstance(e, StepShape_Face) for e in new)
            n_faces = _count_faces(shape)
            if n_written < n_faces:
                raise ExchangeError(
                    f"{p}: OCC wrote {n_written} of the {n_faces} faces of objects[{i}] "
                    f"(degenerate at the tolerance {FACE_TOLERANCE:g}?)"
                )
            # Without a name the product would be called 'Open CASCADE STEP translator 7.9 1'.
            text = TCollection_HAsciiString(name or "")
            for ent in new:
                if isinstance(ent, StepBasic_Product):
                    ent.SetId(text)
                    ent.SetName(text)
            if name is not None:
                finder = writer.WS().TransferWriter().FinderProcess()
                item = STEPConstruct.FindEntity_s(finder, shape, TopLoc_Location())
                if item is not None:
                    item.SetName(text)
        return print_step(p, writer.WS(), digits)


def print_step(p: Path, ws: Any, digits: int) -> bytes:
    """The STEP text of a translated work session's model, every real printed with ``digits``
    significant digits (``%.{digits-1}E``), the header naming ``p``."""
    from OCP.APIHeaderSection import APIHeaderSection_MakeHeader
    from OCP.StepData import StepData_StepWriter
    from OCP.TCollection import TCollection_HAsciiString

    model = ws.Model()
    try:
        header = APIHeaderSection_MakeHeader(model)
        header.SetName(TCollection_HAsciiString(p.name))
        header.Apply(model)
    except Exception:  # noqa: BLE001 - the header name is cosmetic
        pass
    # OCC's Write() prints through a StepData_StepWriter whose FloatWriter keeps 13 digits;
    # print the same model ourselves with every real in %.{digits-1}E.
    step_writer = StepData_StepWriter(model)
    floats = step_writer.FloatWriter()
    floats.SetFormat(f"%.{digits - 1}E", True)  # True: no special format near 1
    floats.SetZeroSuppress(False)  # OCC's zero suppression mangles %E output (0.5 -> "5.")
    buffer = io.BytesIO()
    try:
        step_writer.SendModel(ws.Protocol())
        ok = step_writer.Print(buffer)
    except Exception as err:  # noqa: BLE001
        raise ExchangeError(f"{p}: printing the STEP model failed: {one_line(err)}") from err
    data = buffer.getvalue()
    if not ok or not data.rstrip().endswith(b"END-ISO-10303-21;"):
        raise ExchangeError(f"{p}: printing the STEP model failed")
    return data


def _count_faces(shape: Any) -> int:
    """Distinct faces of ``shape`` whatever their placement: OCC writes a face that several placed
    instances share once (the instances are references), so that is the count to expect."""
    from OCP.TopAbs import TopAbs_FACE
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopLoc import TopLoc_Location
    from OCP.TopTools import TopTools_IndexedMapOfShape

    identity = TopLoc_Location()
    faces = TopTools_IndexedMapOfShape()
    ex = TopExp_Explorer(shape, TopAbs_FACE)
    while ex.More():
        faces.Add(ex.Current().Located(identity))
        ex.Next()
    return faces.Extent()


def _iges_label(name: str) -> str:
    return "".join(c if 32 < ord(c) < 127 else "_" for c in name)[:8]


def iges_bytes(p: Path, items: list[tuple[Any, str | None]], unit: str = "mm") -> bytes:
    from OCP.IGESBasic import IGESBasic_Name
    from OCP.IGESControl import IGESControl_Writer
    from OCP.TCollection import TCollection_HAsciiString

    with statics({"write.iges.unit": unit.upper()}):
        writer = IGESControl_Writer(unit.upper(), 0)  # 0: faces as trimmed surfaces (144), the usual form
        model = writer.Model()
        ranges: list[tuple[int, int, str]] = []
        for i, (shape, name) in enumerate(items):
            first = model.NbEntities() + 1
            try:
                ok = writer.AddShape(shape)
            except Exception as err:  # noqa: BLE001
                raise ExchangeError(f"{p}: IGES translation of objects[{i}] failed: {one_line(err)}") from err
            if not ok or model.NbEntities() < first:
                raise ExchangeError(f"{p}: IGES translation of objects[{i}] failed")
            if name is not None:
                ranges.append((first, model.NbEntities(), name))
        try:
            header = model.GlobalSection()
            header.SetFileName(TCollection_HAsciiString(p.name))
            model.SetGlobalSection(header)
            writer.ComputeModel()  # sets the subordinate status used below
            for first, last, name in ranges:
                prop = IGESBasic_Name()
                prop.Init(1, TCollection_HAsciiString(name))
                label = TCollection_HAsciiString(_iges_label(name))
                for k in range(first, last + 1):
                    ent = model.Value(k)
                    if ent.SubordinateStatus() == 0:  # independent: a root on reading
                        ent.AddProperty(prop)
                        ent.SetLabel(label)
                model.AddEntity(prop)
            if ranges:
                writer.ComputeModel()
            buffer = io.BytesIO()
            ok = writer.Write(buffer)
        except Exception as err:  # noqa: BLE001
            raise ExchangeError(f"{p}: writing the IGES model failed: {one_line(err)}") from err
    data = buffer.getvalue()
    if not ok or not data:
        raise ExchangeError(f"{p}: writing the IGES model failed")
    return data
