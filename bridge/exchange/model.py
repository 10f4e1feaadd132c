"""The model a STEP or IGES file reads into: :class:`ImportedModel`, its :class:`ImportedFace` and
:class:`ImportedEdge` records, and how one OCC face or free edge becomes its record.

Below :mod:`.step_iges` (reading and writing files) and :mod:`.objects` (build123d / cadquery
objects), which both build models from these pieces.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from occsurf.algorithms import BSplineCurve, BSplineSurface, TrimmedSurface

from ..messages import one_line

__all__ = ["ImportedFace", "ImportedEdge", "ImportedModel"]


@dataclass(frozen=True)
class ImportedFace:
    """One face of an imported file.

    Attributes
    ----------
    index : int
        0-based position in ``TopExp_Explorer`` order over the model's faces (each face once).
    name : str or None
        The face's own name in the file, else the name of the product (STEP) or root entity
        (IGES) it belongs to; ``None`` if the file carries none.
    surface_type : str
        The original surface: ``'BSplineSurface'``, ``'BezierSurface'``, ``'Plane'``,
        ``'Cylinder'``, ``'Cone'``, ``'Sphere'``, ``'Torus'``, ``'SurfaceOfRevolution'``,
        ``'SurfaceOfExtrusion'``, ``'OffsetSurface'`` or ``'Other'``.
    surface : BSplineSurface or None
        :func:`occsurf.bridge.conversion.splines.from_occ` of the face (bit-exact for B-spline faces); ``None`` if
        the conversion failed.
    error : str or None
        Why the conversion failed, one line.
    face : TopoDS_Face
    occ_surface : Geom_Surface or None
        The face's surface with the face's location applied (``BRep_Tool.Surface_s``); the
        face's orientation is not applied.
    u_periodic, v_periodic : bool
    continuity : str
        OCC's continuity class of ``occ_surface``: ``'C0'``, ``'G1'``, ``'C1'``, ``'G2'``,
        ``'C2'``, ``'C3'`` or ``'CN'``.
    color : (float, float, float, float) or None
        RGBA in [0, 1] the file gives this face: its own colour, else its solid's or shell's, else its
        instance's, else its part's (then up the assembly tree); ``None`` if the file gives none.
        RGB is sRGB, the file's numbers (STEP ``COLOUR_RGB``; IGES 314 percentages / 100), as
        build123d's and cadquery's ``Color(r, g, b)`` take them: ``COLOUR_RGB('',0.2,0.5,0.8)`` reads
        ``(0.2, 0.5, 0.8, 1.0)``. OCC holds colours as linear RGB in float32 (that 0.2 is 0.0331
        there); the conversion moves values by at most 2e-8, undone by rounding to 7 decimals
        (:data:`occsurf.bridge.exchange.xcaf.COLOR_DECIMALS`). Writing gives the file these numbers.
    layer : str or None
        The face's layer, resolved in the same order (the first, when an item is on several layers).
    instance : str or None
        For an assembly, the path of the part instance the face belongs to, from the root, names
        joined by '/' (``'assembly/plate_a'``); ``None`` for a flat file.
    trimmed : TrimmedSurface or None
        The face as an :class:`occsurf.algorithms.TrimmedSurface` (``surface`` plus the face's loops
        of p-curves in its parameters, and its orientation; see
        :mod:`occsurf.bridge.conversion.trimming`) when its boundary is not the natural rectangle of
        ``surface``; ``None`` for an untrimmed face or when the loops could not be converted.
        Built on first access and cached (reading does not pay for faces nobody asks about); a
        face made with ``dataclasses.replace`` shares the cache. To give a value when building an
        ``ImportedFace`` by hand, pass ``_trimmed=`` (a :class:`TrimmedSurface` or ``None``).
    """

    index: int
    name: str | None
    surface_type: str
    surface: BSplineSurface | None
    error: str | None
    face: Any = field(repr=False)
    occ_surface: Any = field(repr=False)
    u_periodic: bool
    v_periodic: bool
    continuity: str
    color: tuple[float, float, float, float] | None = None
    layer: str | None = None
    instance: str | None = None
    _trimmed: Any = field(default=None, repr=False, compare=False)  # the value, or a _LazyTrimmed

    @property
    def trimmed(self) -> TrimmedSurface | None:
        t = self._trimmed
        return t.value() if isinstance(t, _LazyTrimmed) else t

    @property
    def natural(self) -> bool | None:
        """``True`` when the face is the whole parameter box of ``surface`` (its loops run along the
        box's sides: nothing to trim away), ``False`` when it is trimmed (``trimmed`` is set),
        ``None`` when unknown (no surface, loops that did not convert, or an ``ImportedFace`` made
        by hand or unpickled without that knowledge). Builds ``trimmed`` on first access."""
        t = self._trimmed
        if isinstance(t, _LazyTrimmed):
            return t.natural()
        return False if t is not None else None


class _LazyTrimmed:
    """The cached, on-demand :attr:`ImportedFace.trimmed` of one face (its loops converted by
    :func:`_build_trimmed` on the first call of :meth:`value`). Pickles as its value, so an
    ``ImportedFace`` whose OCC objects are dropped or replaced still carries its loops."""

    __slots__ = ("_args", "_value", "_natural")
    _PENDING = object()

    def __init__(self, face: Any, surface: BSplineSurface, occ_surface: Any) -> None:
        self._args: tuple[Any, ...] | None = (face, surface, occ_surface)
        self._value: Any = self._PENDING
        self._natural: bool | None = None

    def value(self) -> TrimmedSurface | None:
        args = self._args
        if args is not None:  # None: built already (the value is set before the arguments are dropped)
            self._value, self._natural = _build_trimmed(*args)
            self._args = None  # the OCC objects are no longer needed here
        return self._value

    def natural(self) -> bool | None:
        """:attr:`ImportedFace.natural` (the loops converted first if they were not)."""
        value = self.value()
        return False if value is not None else self._natural

    def __reduce__(self) -> tuple[Any, tuple[Any]]:
        return _identity, (self.value(),)


def _identity(value: Any) -> Any:
    return value


@dataclass(frozen=True)
class ImportedEdge:
    """One free edge (an edge that bounds no face) of an imported file.

    Attributes
    ----------
    index : int
        0-based position in ``TopExp_Explorer`` order over the model's free edges (each once).
    name : str or None
        As :attr:`ImportedFace.name`.
    curve_type : str
        ``'BSplineCurve'``, ``'BezierCurve'``, ``'Line'``, ``'Circle'``, ``'Ellipse'``,
        ``'Hyperbola'``, ``'Parabola'``, ``'OffsetCurve'`` or ``'Other'``.
    curve : BSplineCurve or None
        :func:`occsurf.bridge.conversion.splines.from_occ` of the edge; ``None`` if the conversion failed.
    error : str or None
        Why the conversion failed, one line.
    edge : TopoDS_Edge
    occ_curve : Geom_Curve or None
        The edge's 3-D curve with the edge's location applied; ``None`` if it has none.
    periodic : bool
    continuity : str
        OCC's continuity class of ``occ_curve`` (``'C0'`` ... ``'CN'``).
    parameter_range : (float, float)
        The edge's range on ``occ_curve``.
    color : (float, float, float, float) or None
        RGBA in [0, 1] the file gives this curve: its own curve colour, else its wire's or curve
        set's, else its instance's or part's (curve or generic colours; a surface colour does not
        colour curves); ``None`` if the file gives none. sRGB, the file's numbers, as :attr:`ImportedFace.color`.
    layer : str or None
        The curve's layer, resolved in the same order.
    instance : str or None
        As :attr:`ImportedFace.instance`: the part instance the curve belongs to (``None`` in a flat file).
    """

    index: int
    name: str | None
    curve_type: str
    curve: BSplineCurve | None
    error: str | None
    edge: Any = field(repr=False)
    occ_curve: Any = field(repr=False)
    periodic: bool
    continuity: str
    parameter_range: tuple[float, float]
    color: tuple[float, float, float, float] | None = None
    layer: str | None = None
    instance: str | None = None


@dataclass(frozen=True)
class ImportedModel:
    """A STEP or IGES file read by :func:`read_step` or :func:`read_iges`.

    Attributes
    ----------
    path : str
    format : str
        ``'step'`` or ``'iges'``.
    shape : TopoDS_Shape
        Everything transferred (a compound when the file has several roots).
    faces : list of ImportedFace
    edges : list of ImportedEdge
        Free edges only: curves, wires; not the edges that bound faces.
    warnings : list of str
        What was wrong with the file but could be read around, one line each: roots OCC could not
        transfer (their geometry is missing from ``shape``), references to undefined instances (the
        partial model is read), OCC's check messages, fewer faces than the file's face instances,
        closed shells that are open (see :mod:`occsurf.bridge.exchange.checks`).
    unit : str
        The length unit the file declares (``'mm'``, ``'cm'``, ``'m'``, ``'inch'``, ``'ft'``, ``'um'``...;
        ``'mm'`` when it says nothing). The geometry is in millimetres whatever the unit.
    unit_scale : float
        Millimetres per file unit (1.0, 10.0, 1000.0, 25.4...).
    assembly : AssemblyNode or None
        The assembly tree (:class:`occsurf.bridge.exchange.xcaf.AssemblyNode`: instances as references
        to shared parts, placements, names, colours, layers); ``None`` for a flat file.
    """

    path: str
    format: str
    shape: Any = field(repr=False)
    faces: list[ImportedFace]
    edges: list[ImportedEdge]
    warnings: list[str] = field(default_factory=list)
    unit: str = "mm"
    unit_scale: float = 1.0
    assembly: Any = field(default=None, repr=False)


def _maps(shape: Any) -> tuple[Any, Any]:
    """The faces and the free edges (outside every face) of ``shape``, in ``TopExp_Explorer`` order."""
    from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopTools import TopTools_IndexedMapOfShape

    faces_map = TopTools_IndexedMapOfShape()
    ex = TopExp_Explorer(shape, TopAbs_FACE)
    while ex.More():
        faces_map.Add(ex.Current())
        ex.Next()
    edges_map = TopTools_IndexedMapOfShape()
    ex = TopExp_Explorer(shape, TopAbs_EDGE, TopAbs_FACE)  # edges outside every face
    while ex.More():
        edges_map.Add(ex.Current())
        ex.Next()
    return faces_map, edges_map


def _geomabs_name(value: Any, prefix: str = "GeomAbs_") -> str:
    name = value.name
    return name[len(prefix):] if name.startswith(prefix) else name


def _kind_name(value: Any, other: str) -> str:
    """The ``GeomAbs`` type name of a surface or curve without its prefix; ``other`` becomes 'Other'."""
    name = _geomabs_name(value)
    return "Other" if name == other else name


def _spline(convert: Any, expected: type) -> tuple[Any, str | None]:
    """``(spline, None)`` from ``convert()``, or ``(None, why)`` when it fails or gives another type
    than ``expected`` (one bad face or curve must not fail the file)."""
    try:
        spline = convert()
    except Exception as err:  # noqa: BLE001
        return None, one_line(err)
    if not isinstance(spline, expected):
        return None, f"from_occ returned {type(spline).__name__}, not a {expected.__name__}"
    return spline, None


def _import_face(index: int, shape: Any, name: str | None) -> ImportedFace:
    from OCP.BRep import BRep_Tool
    from OCP.GeomAdaptor import GeomAdaptor_Surface
    from OCP.TopoDS import TopoDS

    from ..conversion.splines import from_occ

    face = TopoDS.Face_s(shape)
    occ_surface = BRep_Tool.Surface_s(face)
    if occ_surface is None:
        return ImportedFace(index, name, "Other", None, "the face has no surface", face, None, False, False, "C0")
    surface_type = _kind_name(GeomAdaptor_Surface(occ_surface).GetType(), "OtherSurface")
    surface, error = _spline(lambda: from_occ(face, _conversion_bounds(face, occ_surface), trims=False),
                             BSplineSurface)
    return ImportedFace(
        index=index,
        name=name,
        surface_type=surface_type,
        surface=surface,
        error=error,
        face=face,
        occ_surface=occ_surface,
        u_periodic=bool(occ_surface.IsUPeriodic()),
        v_periodic=bool(occ_surface.IsVPeriodic()),
        continuity=_geomabs_name(occ_surface.Continuity()),
        _trimmed=None if surface is None else _LazyTrimmed(face, surface, occ_surface),
    )


def _build_trimmed(face: Any, surface: BSplineSurface, occ_surface: Any) -> tuple[TrimmedSurface | None, bool | None]:
    """:attr:`ImportedFace.trimmed` and :attr:`ImportedFace.natural`: the face's loops on
    ``surface`` and ``False``; ``(None, True)`` when it is untrimmed (its loops are the box's
    sides); ``(None, None)`` when its loops do not convert (the face still has its ``surface``)."""
    from OCP.BRepTools import BRepTools

    from ..conversion.trimming import box_on_domain, face_from_occ

    box = BRepTools.UVBounds_s(face)
    try:
        t = face_from_occ(face, surface, occ_surface, box)
    except Exception:  # noqa: BLE001 - a face whose loops fail keeps its surface
        return None, None
    if not isinstance(t, BSplineSurface):
        return t, False
    # one loop on the sides of the face's UV box: natural only when that box is the surface's whole
    # domain (face_from_occ trims a rectangle inside it; a box reaching past the domain, a periodic
    # face across its seam, is left unknown)
    return None, (True if box_on_domain(surface, box) == "whole" else None)


def _conversion_bounds(face: Any, occ_surface: Any) -> tuple[float, float, float, float] | None:
    """``None`` for B-spline and Bézier faces (converted whole: bit-exact); else the face's UV
    box (``from_occ`` snaps periodic sides, see ``conversion.from_geom.PERIOD_SNAP``)."""
    from OCP.BRepTools import BRepTools
    from OCP.Geom import Geom_BezierSurface, Geom_BSplineSurface

    if isinstance(occ_surface, (Geom_BSplineSurface, Geom_BezierSurface)):
        return None
    return BRepTools.UVBounds_s(face)


def _import_edge(index: int, shape: Any, name: str | None) -> ImportedEdge:
    from OCP.BRep import BRep_Tool
    from OCP.GeomAdaptor import GeomAdaptor_Curve
    from OCP.TopoDS import TopoDS

    from ..conversion.splines import from_occ

    edge = TopoDS.Edge_s(shape)
    first, last = BRep_Tool.Range_s(edge)
    occ_curve = None if BRep_Tool.Degenerated_s(edge) else BRep_Tool.Curve_s(edge, 0.0, 0.0)
    if occ_curve is None:
        return ImportedEdge(index, name, "Other", None, "the edge has no 3-D curve", edge, None, False, "C0",
                            (float(first), float(last)))
    curve_type = _kind_name(GeomAdaptor_Curve(occ_curve).GetType(), "OtherCurve")
    curve, error = _spline(lambda: from_occ(edge), BSplineCurve)
    return ImportedEdge(
        index=index,
        name=name,
        curve_type=curve_type,
        curve=curve,
        error=error,
        edge=edge,
        occ_curve=occ_curve,
        periodic=bool(occ_curve.IsPeriodic()),
        continuity=_geomabs_name(occ_curve.Continuity()),
        parameter_range=(float(first), float(last)),
    )
