"""The surface-quality report of a model: per-face indicators and the edge-continuity table.

:func:`check_model` assembles, for an :class:`~occsurf.bridge.exchange.step_iges.ImportedModel`,
what ``occsurf check`` writes to ``report.json`` and shows in its page (course ch. 9 assessment,
§11-2):

* per face (numbered as ``occsurf inspect`` numbers them): the surface type, the range of the
  principal curvatures over the *trimmed* face (``k_min`` = smallest ``k2``, ``k_max`` = largest
  ``k1``, 1/model units, on the vertices of OCC's triangulation evaluated by our own derivatives),
  Gaussian and mean curvature ranges, degenerate points, and the flags of
  :func:`occsurf.algorithms.quality.face_flags` with their locations and suggested corrections;
* per edge: :func:`occsurf.bridge.quality.continuity.edge_continuity` (G0 gap, G1 angle, G2
  absolute and relative, worst point, how the edge was matched), judged against a threshold preset.

A face that cannot be evaluated keeps its row with ``error`` set; the rest of the model is still
reported. The triangulated faces (:attr:`QualityReport.meshes`, with per-vertex indicators) are
kept for the pictures (:mod:`.pictures`) and the page's 3-D view (:mod:`.html`).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from ..messages import error_line
from .choices import face_scores
from .face_values import FaceValues
from .thresholds import Thresholds, resolve_thresholds
from .uv_masks import MeshMask, uv_mask

if TYPE_CHECKING:
    from occsurf.algorithms import BSplineSurface

    from ..exchange.step_iges import ImportedFace, ImportedModel
    from ..rendering.tessellation import FaceMesh

__all__ = ["FaceQuality", "QualityReport", "FaceField", "check_model", "face_fields", "summarize_model", "DEFAULT_PRESET",
           "face_scores", "worst_faces"]

#: The threshold preset used when none is named (CATIA's Connect Checker defaults).
DEFAULT_PRESET = "catia"
#: Face flags that break each preset under ``--fail-on`` (edges are judged by
#: :func:`.continuity.check_edges`). CATIA-like: wiggles and curvature spikes (visible defects);
#: class A: every flag but a natural pole (near-degenerate normals are poles of revolved faces);
#: mechanical: none (fillets, flats and poles are by design on machined parts).
FACE_FAIL_KINDS: dict[str, frozenset[str]] = {
    "catia": frozenset({"wiggle", "curvature_spike"}),
    "class-a": frozenset({"wiggle", "curvature_spike", "flat_spot", "ill_parametrisation"}),
    "mechanical": frozenset(),
}


def _finite(x: Any) -> float | None:
    try:
        x = float(x)
    except (TypeError, ValueError):
        return None
    return x if math.isfinite(x) else None


@dataclass
class FaceField:
    """A triangulated face with its per-vertex indicators (what the pictures and the 3-D view show).

    Attributes
    ----------
    mesh : FaceMesh
    values : mapping of str -> ndarray, shape (n,)
        ``'mean'``, ``'gaussian'``, ``'max'`` (k1), ``'min'`` (k2), ``'absolute'`` (``|k1|+|k2|``),
        ``'zebra'`` (phase in [0, 1)), ``'isophote'`` (n . l), ``'draft'`` (degrees); NaN where
        undefined (degenerate points). From :func:`face_fields` a :class:`~.face_values.FaceValues`
        (zebra and isophotes computed on access); any mapping when made by hand.
    degenerate : ndarray of bool, shape (n,)
    natural : bool
        The face is its surface's whole parameter box (``ImportedFace.natural``): the sections cut
        it unmasked.
    """

    mesh: FaceMesh
    values: Mapping[str, np.ndarray]
    degenerate: np.ndarray
    surface: Any = None
    trim: Any = None
    _mask: Any = field(default=None, repr=False)
    natural: bool = False

    def mask(self) -> Callable[[np.ndarray, np.ndarray], np.ndarray]:
        """``mask(u, v) -> bool``: inside the trimmed face. The face's exact trim
        (:attr:`trim`, a ``TrimmedSurface``: its loops of p-curves) where the reader gave one, else
        :func:`~.uv_masks.uv_mask` of the mesh (OCC's triangulation: its boundary within the mesh's
        deflection of the trim), a :class:`~.uv_masks.MeshMask`: its triangle finder is built only
        when first called (most faces of a large model are missed by every section plane, ruled
        out by their control net) and held only while it is among the last
        :data:`~.uv_masks.MESH_MASKS_KEPT` used (a finder holds a few megabytes: ~7 MB for a
        fillet torus of 4191 vertices; the 477 a 1089-face plate's sections reach held 1.36 GB)."""
        if self._mask is None:
            self._mask = self.trim.contains if self.trim is not None else MeshMask(self.mesh)
        return self._mask


@dataclass
class FaceQuality:
    """One face of the report (JSON-safe fields only)."""

    index: int
    type: str
    name: str | None = None
    k_min: float | None = None
    k_max: float | None = None
    gaussian: tuple[float | None, float | None] = (None, None)
    mean: tuple[float | None, float | None] = (None, None)
    n_degenerate: int = 0
    n_vertices: int = 0
    flags: list[dict[str, Any]] = field(default_factory=list)
    worst_g1_deg: float | None = None
    notes: list[str] = field(default_factory=list)
    error: str | None = None
    pictures: dict[str, str] = field(default_factory=dict)

    def to_json(self) -> dict[str, Any]:
        return {
            "index": self.index, "type": self.type, "name": self.name, "k_min": self.k_min, "k_max": self.k_max,
            "gaussian_range": list(self.gaussian), "mean_range": list(self.mean),
            "n_degenerate": self.n_degenerate, "n_vertices": self.n_vertices, "flags": list(self.flags),
            "worst_g1_deg": self.worst_g1_deg, "notes": list(self.notes), "error": self.error,
            "pictures": dict(self.pictures),
        }


def worst_faces(report: QualityReport, n: int) -> list[int]:
    """Indices of the ``n`` worst faces by :func:`face_scores` (ties: the lower index first)."""
    scores = face_scores([f.to_json() for f in report.faces], report.violations)
    return sorted(scores, key=lambda i: (-scores[i], i))[:n]


@dataclass
class QualityReport:
    """What :func:`check_model` found; :meth:`to_json` is ``report.json``."""

    path: str
    format: str | None
    size: float
    faces: list[FaceQuality]
    edges: list[dict[str, Any]]
    preset: str
    thresholds: dict[str, Any]
    failures: list[str] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    seconds: dict[str, float] = field(default_factory=dict)
    violations: list[dict[str, Any]] = field(default_factory=list)
    match_tol: float | None = None
    #: ``occsurf check --pictures``: the choice and the faces whose pictures were drawn (``None``: all).
    picture_faces: dict[str, Any] = field(default_factory=dict)
    edge_lines: list[tuple[str, np.ndarray]] = field(default_factory=list, repr=False)
    fields: dict[int, FaceField] = field(default_factory=dict, repr=False)
    #: The model's sections, combs and inflections once computed
    #: (:func:`~occsurf.bridge.quality.pictures.model_sections`: the pictures and the page share them).
    sections: Any = field(default=None, repr=False, compare=False)

    @property
    def passed(self) -> bool:
        """No edge and no face breaks the preset."""
        return not self.failures

    @property
    def worst_g1_deg(self) -> float | None:
        vals = [v for e in self.edges if (v := _finite(e.get("g1_max_deg"))) is not None]
        return max(vals) if vals else None

    def _repr_html_(self) -> str:
        """The report's page (tables and the interactive 3-D view, no PNGs) inline in Jupyter, VS Code
        or any notebook: the whole offline page of ``occsurf check`` in an ``<iframe srcdoc>`` (its
        scripts run inside the frame; nothing is fetched)."""
        import html as _html

        from .html import render_html, viewer_payload

        payload = viewer_payload(self)  # first: a failed section is noted in the warnings
        page = render_html(self.to_json(), payload, {})
        return ('<iframe title="occsurf quality report" style="width:100%;height:720px;border:1px solid #ccd" '
                f'srcdoc="{_html.escape(page, quote=True)}"></iframe>')

    def to_json(self) -> dict[str, Any]:
        return {
            "path": self.path, "format": self.format, "model_size": self.size,
            "n_faces": len(self.faces), "n_edges": len(self.edges),
            "preset": self.preset, "thresholds": self.thresholds, "passed": self.passed,
            "failures": list(self.failures), "violations": list(self.violations),
            "match_tol": self.match_tol, "worst_g1_deg": self.worst_g1_deg,
            "n_flags": sum(len(f.flags) for f in self.faces),
            "warnings": list(self.warnings), "seconds": {k: round(v, 3) for k, v in self.seconds.items()},
            "faces": [f.to_json() for f in self.faces], "edges": list(self.edges),
            "face_pictures": dict(self.picture_faces),
        }


# ---------------------------------------------------------------------------------------- fields
def _surface_of(face: ImportedFace) -> BSplineSurface:
    """The face's converted surface; :class:`InvalidGeometryError` for a face whose surface did not
    convert (``face.surface`` is ``None``, ``face.error`` says why)."""
    if face.surface is None:
        from occsurf.algorithms.errors import InvalidGeometryError

        raise InvalidGeometryError(f"face {face.index}: no surface to evaluate "
                                   f"({face.error or 'the surface did not convert'})")
    return face.surface


def face_fields(face: ImportedFace, mesh: FaceMesh, *, view_dir: Sequence[float] = (-1.0, 1.0, -0.8),
                pull: Sequence[float] = (0.0, 0.0, 1.0), size: float = 1.0) -> FaceField:
    """Per-vertex indicators of one meshed face, by our own exact derivatives (course §9-5..9-13).

    Curvatures come from :func:`occsurf.algorithms.geometry.surface_differential.curvatures_from_derivatives`
    at the mesh's parameters, zebra/isophotes/draft from :mod:`occsurf.algorithms.quality` on the
    mesh's points and normals.
    """
    from occsurf.algorithms.geometry.surface_differential import curvatures_from_derivatives
    from occsurf.algorithms.quality import curvature_values, draft_angle

    surf = _surface_of(face)
    uv = mesh.uv
    c = curvatures_from_derivatives(surf.derivatives(uv[:, 0], uv[:, 1], 2))
    sign = -1.0 if mesh.reversed else 1.0  # curvature sign follows the outward normal of the face
    k1, k2 = np.asarray(c.k1, float), np.asarray(c.k2, float)
    if mesh.reversed:
        k1, k2 = -k2, -k1
    K, H = np.asarray(c.gaussian, float), sign * np.asarray(c.mean, float)
    held = {kind: np.asarray(curvature_values(kind, k1, k2, K, H, size), float)
            for kind in ("mean", "gaussian", "max", "min", "absolute")}
    N = mesh.normals
    degenerate = ~np.all(np.isfinite(N), axis=1) | ~np.isfinite(k1)
    held["draft"] = np.asarray(draft_angle(N, np.asarray(pull, float)), float)
    # zebra and isophotes: computed when asked (the views draw them per pixel), see FaceValues
    values = FaceValues(held, mesh, view_dir, size)
    trim = getattr(face, "trimmed", None)
    if trim is not None and getattr(trim, "surface", None) is not surf:
        trim = None  # loops in another surface's parameters: the mesh's mask instead
    return FaceField(mesh=mesh, values=values, degenerate=degenerate, surface=surf, trim=trim,
                     natural=trim is None and bool(getattr(face, "natural", None)))


def _ranges(field_: FaceField) -> dict[str, Any]:
    def rng(v: np.ndarray) -> tuple[float | None, float | None]:
        v = v[np.isfinite(v)]
        return (float(v.min()), float(v.max())) if v.size else (None, None)

    return {"k_min": rng(field_.values["min"])[0], "k_max": rng(field_.values["max"])[1],
            "gaussian": rng(field_.values["gaussian"]), "mean": rng(field_.values["mean"]),
            "n_degenerate": int(field_.degenerate.sum()), "n_vertices": field_.mesh.n_vertices}


# ---------------------------------------------------------------------------------------- faces
def _flags_of(face: ImportedFace, mesh: FaceMesh, samples: int) -> list[dict[str, Any]]:
    """:func:`occsurf.algorithms.quality.face_flags` of the face's surface on a ``samples`` grid,
    masked to the trimmed face (its loops' classification, ``ImportedFace.trimmed``; the whole grid
    for a face that is its surface's whole box, ``ImportedFace.natural``; else the triangles of
    OCC's mesh), as JSON dicts."""
    from occsurf.algorithms import quality

    surface = _surface_of(face)
    (u0, u1), (v0, v1) = surface.domain
    us, vs = np.linspace(u0, u1, samples), np.linspace(v0, v1, samples)
    grid = np.meshgrid(us, vs, indexing="ij")
    trimmed = getattr(face, "trimmed", None)
    if trimmed is not None:
        inside = trimmed.contains(*grid)
    elif getattr(face, "natural", None):
        inside = None  # the whole parameter box is the face: its sides' samples too (a mesh mask may
        # leave a side's samples out by round-off, as it left a revolved face's pole of mixed.igs)
    else:
        inside = uv_mask(mesh)(*grid) if mesh.source == "brepmesh" else None
    if inside is not None and not inside.any():
        return []
    return [_flag_json(f) for f in quality.face_flags(surface, mask=inside, us=us, vs=vs)]


def _flag_json(flag: Any) -> dict[str, Any]:
    def arr(x: Any) -> Any:
        if x is None:
            return None
        a = np.asarray(x, float).ravel()
        return [_finite(v) for v in a]

    if hasattr(flag, "to_json"):
        return flag.to_json()
    return {"kind": str(flag.kind), "location": arr(flag.location), "uv": arr(flag.uv),
            "value": _finite(flag.value), "suggestion": str(flag.suggestion)}


def _check_face(face: ImportedFace, mesh_of: Callable[[ImportedFace], FaceMesh], samples: int, size: float,
                flags: bool) -> tuple[FaceQuality, FaceField | None]:
    """One face's row and its field; never raises (``error`` set instead)."""
    row = FaceQuality(index=face.index, type=face.surface_type, name=face.name or None)
    if face.surface is None:
        row.error = f"not evaluated: {face.error or 'the surface did not convert'}"
        return row, None
    try:
        with np.errstate(all="ignore"):
            mesh = mesh_of(face)
            fld = face_fields(face, mesh, size=size)
        r = _ranges(fld)
        row.k_min, row.k_max = r["k_min"], r["k_max"]
        row.gaussian, row.mean = r["gaussian"], r["mean"]
        row.n_degenerate, row.n_vertices = r["n_degenerate"], r["n_vertices"]
        row.notes.extend(mesh.notes)
        if mesh.unmapped:
            row.notes.append(f"{mesh.unmapped} mesh vertices not found on the converted surface (OCC's point shown)")
        if row.n_degenerate:
            row.notes.append(f"{row.n_degenerate} degenerate points (undefined normal: pole or collapsed edge), "
                             "drawn magenta")
    except Exception as err:  # noqa: BLE001 - one face must not hide the others
        row.error = f"not evaluated: {error_line(err)}"
        return row, None
    if flags:
        try:
            with np.errstate(all="ignore"):
                row.flags = _flags_of(face, fld.mesh, samples)
        except Exception as err:  # noqa: BLE001
            row.notes.append(f"flags not computed: {error_line(err)}")
    return row, fld


# ---------------------------------------------------------------------------------------- edges
def _thresholds_json(th: Thresholds) -> dict[str, Any]:
    from dataclasses import asdict

    return asdict(th)


# ---------------------------------------------------------------------------------------- entry
def check_model(model: ImportedModel, *, faces: Sequence[int] | None = None, samples: int = 41,
                preset: str = DEFAULT_PRESET, thresholds: Thresholds | None = None, edges: bool | str = True, flags: bool = True,
                progress: Callable[[int, int], None] | None = None, skip: Mapping[int, str] | None = None,
                trace: Callable[[str], None] | None = None, mesh_each: bool = False,
                free_meshes: bool = False) -> QualityReport:
    """Assess a model's surfaces: per-face indicators and flags, the edge-continuity table.

    Parameters
    ----------
    model : ImportedModel, or a build123d / cadquery / OCC shape
        From :func:`~occsurf.bridge.exchange.step_iges.read_step` or ``read_iges``; any other object
        :func:`~occsurf.bridge.exchange.object_import.as_model` accepts (a Solid, Shell, Compound, Workplane...).
    faces : sequence of int, optional
        Face indices to report (as ``occsurf inspect`` numbers them); default all. Edges are
        reported when one of their faces is selected.
    samples : int, default 41
        Grid size per face for :func:`~occsurf.algorithms.quality.face_flags` (masked to the
        trimmed face).
    preset : str
        A key of :data:`occsurf.bridge.quality.thresholds.PRESETS` (``'catia'``: 0.001 mm, 0.01 deg, 2 %).
    thresholds : optional
        Explicit thresholds overriding the preset.
    edges, flags : bool
        Compute the edge table / the face flags (both by default). ``edges`` may be a string
        instead of ``False``: why the table is left out (kept in the report's warnings).
    progress : callable(done, total), optional
        Called after each face.
    skip : mapping of int to str, optional
        Faces not to evaluate, with the reason (their rows keep ``error`` set to it): how
        ``occsurf check`` leaves out a face that crashed the checker process on an earlier attempt.
    trace : callable(str), optional
        Called before each step that runs OCC or heavy code on one piece of the model: ``"mesh"``
        (or ``"mesh face K"`` with ``mesh_each``), ``"face K"``, ``"edges"``; the last one seen
        names the piece at fault when the process dies (:func:`occsurf.bridge.quality.check_files.check_job` writes it
        to a file).
    mesh_each : bool
        Triangulate face by face (each with the model's deflection) instead of the whole shape
        at once, so a face that crashes OCC's mesher can be named and skipped.
    free_meshes : bool
        Free OCC's triangulation of each face once its mesh is copied into the report (the faces'
        fields hold what the rest needs; the placed copies of one part share it: freed after the
        last of them): for a model nothing else will draw, as
        :func:`~occsurf.bridge.quality.check_files.check_file`'s own (on bench_check's 1089-face
        plate OCC's triangulation is ~150 MB). A caller's shape is left meshed by default.

    Returns
    -------
    QualityReport

    Raises
    ------
    InvalidGeometryError
        A face index out of range, or an unknown preset.
    """
    from OCP.BRepTools import BRepTools

    from occsurf.algorithms._validate import check_count
    from occsurf.algorithms.errors import InvalidGeometryError
    from occsurf.algorithms.quality._common import check_grid

    from ..exchange.object_import import as_model
    from ..rendering import tessellation
    from ._setup import shape_size

    check_grid(check_count(samples, "samples", 1, minimum=2), int(samples), "samples")  # each face's flags grid, up front
    model = as_model(model)  # a build123d / cadquery / OCC object: its faces with their labels and colours
    n = len(model.faces)
    chosen = None if faces is None else sorted({int(k) for k in faces})
    if chosen is not None and any(not 0 <= k < n for k in chosen):
        raise InvalidGeometryError(f"faces: expected indices from 0 to {n - 1}, got {chosen}")
    skip = {int(k): str(v) for k, v in (skip or {}).items()}
    note = trace if trace is not None else (lambda stage: None)
    t0 = time.perf_counter()
    todo = [model.faces[k] for k in (chosen if chosen is not None else range(n))]
    size = _mesh(model, [f for f in todo if f.index not in skip], mesh_each, note)
    # the edges' tolerances are relative to OCC's box of the meshed shape: taken before any mesh is freed
    edge_size = shape_size(model.shape) if free_meshes else None
    # a face's triangulation belongs to its TShape, which the placed copies of a part share: freed
    # after the last face that uses it
    uses, shared = (_shared_meshes([f for f in todo if f.index not in skip]) if free_meshes else ({}, {}))
    seconds = {"mesh": time.perf_counter() - t0}
    rows: list[FaceQuality] = []
    fields: dict[int, FaceField] = {}
    t1 = time.perf_counter()
    for k, face in enumerate(todo):
        if face.index in skip:
            row, fld = FaceQuality(index=face.index, type=face.surface_type, name=face.name or None,
                                   error=skip[face.index]), None
        else:
            note(f"face {face.index}")
            row, fld = _check_face(face, lambda f: tessellation.mesh_face(f, size), samples, size, flags)
            if free_meshes:
                uses[shared[face.index]] -= 1
                if uses[shared[face.index]] == 0:
                    BRepTools.Clean_s(face.face)
        rows.append(row)
        if fld is not None:
            fields[face.index] = fld
        if progress is not None:
            progress(k + 1, len(todo))
    seconds["faces"] = time.perf_counter() - t1
    report = QualityReport(path=str(model.path), format=model.format, size=size, faces=rows, edges=[],
                           preset=preset, thresholds={}, fields=fields,
                           warnings=[error_line(w) for w in model.warnings])
    if isinstance(edges, str):
        report.warnings.append(f"edge continuity not computed: {edges}")
        report.thresholds = _thresholds_json(_preset_thresholds(preset, thresholds))
    elif edges:
        t2 = time.perf_counter()
        note("edges")
        _add_edges(report, model, chosen, preset, thresholds, edge_size)
        seconds["edges"] = time.perf_counter() - t2
    fail_kinds = FACE_FAIL_KINDS.get(preset, FACE_FAIL_KINDS[DEFAULT_PRESET])
    for f in rows:
        bad = sorted({g["kind"] for g in f.flags if g.get("kind") in fail_kinds})
        if bad:
            report.failures.append(f"face {f.index}: {', '.join(bad)} ({preset})")
    seconds["total"] = time.perf_counter() - t0
    report.seconds = seconds
    return report


def _shared_meshes(faces: Sequence[ImportedFace]) -> tuple[dict[int, int], dict[int, int]]:
    """``(uses, key)``: per face index the key of its TShape (faces that differ only by their
    location or orientation, the placed copies of one part, share a key and OCC's triangulation),
    and per key how many of ``faces`` use it."""
    from OCP.TopLoc import TopLoc_Location
    from OCP.TopTools import TopTools_IndexedMapOfShape

    seen = TopTools_IndexedMapOfShape()
    key: dict[int, int] = {}
    uses: dict[int, int] = {}
    for f in faces:
        k = int(seen.Add(f.face.Located(TopLoc_Location())))  # the map compares shapes by IsSame
        key[f.index] = k
        uses[k] = uses.get(k, 0) + 1
    return uses, key


def _mesh(model: ImportedModel, faces: Sequence[ImportedFace], each: bool, note: Callable[[str], None]) -> float:
    """Triangulate the model (:func:`~occsurf.bridge.rendering.tessellation.mesh_model`), or with
    ``each`` only ``faces``, one ``BRepMesh_IncrementalMesh`` per face at the model's deflection
    (``note`` names each face first); returns the model size."""
    from ..rendering import tessellation

    if not each:
        note("mesh")
        return tessellation.mesh_model(model)
    size = tessellation.model_size(model)
    for face in faces:
        note(f"mesh face {face.index}")
        tessellation.mesh_one_face(face.face, tessellation.LINEAR_DEFLECTION * size, tessellation.ANGULAR_DEFLECTION)
    return size


def _preset_thresholds(preset: str, thresholds: Thresholds | None) -> Thresholds:
    return resolve_thresholds(preset if thresholds is None else thresholds)


def _add_edges(report: QualityReport, model: ImportedModel, chosen: list[int] | None, preset: str,
               thresholds: Thresholds | None, edge_size: float | None = None) -> None:
    """Fill the edge table (:func:`.continuity.edge_continuity`), each face's worst adjacent G1
    angle, and the edges' violations of the thresholds (:func:`.continuity.check_edges`)."""
    from . import continuity

    th = _preset_thresholds(preset, thresholds)
    result = continuity.edge_continuity(model, preset=th, model_size=edge_size)
    reports = list(result)
    if chosen is not None:
        keep = set(chosen)
        reports = [r for r in reports if set(r.faces) & keep]
    report.edges = [r.to_json() for r in reports]
    report.thresholds = _thresholds_json(th)
    report.match_tol = getattr(result, "match_tol", None)
    report.warnings.extend(str(w) for w in getattr(result, "warnings", ()))
    by_face = {f.index: f for f in report.faces}
    for r in reports:
        g1 = _finite(r.g1_max_deg)
        for k in r.faces:
            f = by_face.get(k)
            if f is not None and g1 is not None and (f.worst_g1_deg is None or g1 > f.worst_g1_deg):
                f.worst_g1_deg = g1
    report.edge_lines = _edge_lines(reports)
    report.violations = [v.to_json() for v in continuity.check_edges(reports, th)]
    report.failures.extend(_failure_text(v) for v in continuity.check_edges(reports, th))


#: Points per edge polyline in the edge picture.
EDGE_POINTS = 24


def _edge_lines(reports: Sequence[Any]) -> list[tuple[str, np.ndarray]]:
    """``(classification, polyline (k, 3))`` of every measured edge, from its first side's 3-D curve
    (OCC's ``BRepAdaptor_Curve``; one call per point, the edge count is small)."""
    from OCP.BRepAdaptor import BRepAdaptor_Curve

    out = []
    for r in reports:
        edge = (getattr(r, "edges", None) or (None,))[0]
        if edge is None:
            continue
        try:
            c = BRepAdaptor_Curve(edge)
            ts = np.linspace(c.FirstParameter(), c.LastParameter(), EDGE_POINTS)
            out.append((str(r.classification), np.array([c.Value(float(t)).Coord() for t in ts])))
        except Exception:  # noqa: BLE001 - a degenerated edge has no curve: nothing to draw
            continue
    return out


def _failure_text(failure: Any) -> str:
    if hasattr(failure, "message"):
        return str(failure.message)
    return str(failure)


#: Edge classes that are meant to be tangent-continuous; designed creases ("sharp"), seams and
#: degenerate edges do not count towards a model's worst G1.
_SMOOTH_CLASSES = frozenset({"gap", "G0", "G1", "G2"})


def summarize_model(model: ImportedModel, *, preset: str = DEFAULT_PRESET, samples: int = 21) -> dict[str, Any]:
    """A few numbers that sum up a model's quality, for corpus audits (``occsurf audit --checks quality``).

    Parameters
    ----------
    model : ImportedModel
        As read by ``read_step``/``read_iges``.
    preset : str, default ``"catia"``
        Threshold preset of :func:`check_model`.
    samples : int, default 21
        Grid samples per face direction (fewer than ``occsurf check``'s 41: an audit reads thousands).

    Returns
    -------
    dict
        ``worst_g1_deg``: the largest G1 angle (degrees) over edges meant to be tangent-continuous
        (classified gap, G0, G1 or G2; designed creases, seams and degenerate edges excluded), None when
        the model has none; ``curvature_spikes``: the number of ``curvature_spike`` flags over all
        faces; ``flags``: every face flag as ``"face N: kind"``; ``failures``: what breaks the preset.
    """
    report = check_model(model, samples=samples, preset=preset)
    smooth = [v for e in report.edges
              if e.get("classification") in _SMOOTH_CLASSES and (v := _finite(e.get("g1_max_deg"))) is not None]
    flags = [f"face {f.index}: {g['kind']}" for f in report.faces for g in f.flags]
    spikes = sum(1 for f in report.faces for g in f.flags if g["kind"] == "curvature_spike")
    return {"worst_g1_deg": max(smooth) if smooth else None, "curvature_spikes": spikes, "flags": flags,
            "failures": list(report.failures)}
