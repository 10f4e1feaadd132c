"""Quality results for your own viewer: sections, combs and reflection lines as build123d edges,
indicator maps as coloured meshes (course ch. 9; OCP CAD Viewer's zebra works on meshes only).

::

    from occsurf.bridge import read_step
    from occsurf.bridge.quality.report import check_model
    from occsurf.bridge.quality import export

    report = check_model(read_step("part.step"))
    lines = export.section_curves(report)                 # {"sections": [...], "combs": [...], "inflections": (k, 3)}
    edges = export.as_edges(lines["sections"])            # build123d Edges (splines through the cut points)
    mesh = export.colored_mesh(report, "mean")            # ColoredMesh: points, triangles, RGB per vertex
    mesh.write_ply("mean.ply")                            # any mesh viewer; or mesh.to_vtk() / to_build123d()
    zebra = export.reflection_lines(report.fields[3])     # (k, 2, 3) segments of the zebra boundaries
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    import build123d as bd
    from vtkmodules.vtkCommonDataModel import vtkPolyData

    from .report import FaceField, QualityReport

__all__ = ["ColoredMesh", "colored_mesh", "as_edges", "section_curves", "reflection_lines", "quality_overlays",
           "OVERLAY_COLORS"]

#: Colours (RGB 0..1) of the overlays of :func:`quality_overlays` that have no edge class.
OVERLAY_COLORS: dict[str, tuple[float, float, float]] = {
    "sections": (0.15, 0.15, 0.2), "combs": (0.85, 0.1, 0.55), "inflections": (0.1, 0.7, 0.2)}


@dataclass(frozen=True)
class ColoredMesh:
    """A triangle mesh with one RGB colour per vertex.

    Attributes
    ----------
    points : ndarray, shape (n, 3)
    triangles : ndarray, shape (m, 3), int
    colors : ndarray, shape (n, 3), uint8
    values : ndarray, shape (n,)
        The indicator (NaN at degenerate points, coloured magenta).
    normals : ndarray, shape (n, 3)
    indicator : str
    lo, hi : float
        The colour scale.
    """

    points: np.ndarray
    triangles: np.ndarray
    colors: np.ndarray
    values: np.ndarray
    normals: np.ndarray
    indicator: str
    lo: float
    hi: float

    def write_ply(self, path: str | Path) -> Path:
        """Binary little-endian PLY with per-vertex colours, written atomically."""
        from ..exchange.files import atomic_write

        n, m = len(self.points), len(self.triangles)
        head = ("ply\nformat binary_little_endian 1.0\n"
                f"comment occsurf check: {self.indicator} on [{self.lo:.6g}, {self.hi:.6g}]\n"
                f"element vertex {n}\nproperty float x\nproperty float y\nproperty float z\n"
                "property uchar red\nproperty uchar green\nproperty uchar blue\n"
                f"element face {m}\nproperty list uchar int vertex_indices\nend_header\n").encode("ascii")
        vert = np.zeros(n, dtype=[("p", "<f4", 3), ("c", "u1", 3)])
        vert["p"], vert["c"] = self.points, self.colors
        face = np.zeros(m, dtype=[("k", "u1"), ("i", "<i4", 3)])
        face["k"], face["i"] = 3, self.triangles
        path = Path(path)
        atomic_write(path, head + vert.tobytes() + face.tobytes())
        return path

    def to_vtk(self) -> vtkPolyData:
        """vtkPolyData with the colours as its point scalars (name ``'rgb'``) and the values as ``indicator``."""
        from vtkmodules.util.numpy_support import numpy_to_vtk

        from ..rendering.vtk_scene import polydata

        pd = polydata(self.points, self.triangles, "triangles")
        rgb = numpy_to_vtk(np.ascontiguousarray(self.colors), deep=True)
        rgb.SetName("rgb")
        pd.GetPointData().SetScalars(rgb)
        val = numpy_to_vtk(np.ascontiguousarray(self.values, float), deep=True)
        val.SetName(self.indicator)
        pd.GetPointData().AddArray(val)
        return pd


def _fields(source: QualityReport | FaceField | Sequence[FaceField]) -> list[FaceField]:
    from .report import FaceField

    if isinstance(source, FaceField):
        return [source]
    if hasattr(source, "fields"):
        return [source.fields[k] for k in sorted(source.fields)]
    return list(source)


def colored_mesh(source: QualityReport | FaceField | Sequence[FaceField], indicator: str = "mean", *,
                 scale: tuple[float, float] | None = None, cmap: str | None = None) -> ColoredMesh:
    """One mesh of the faces coloured by an indicator, with the same scale and map as the pictures.

    Parameters
    ----------
    source : QualityReport, FaceField or sequence of FaceField
    indicator : str
        ``'mean'``, ``'gaussian'``, ``'max'``, ``'min'``, ``'absolute'``, ``'draft'``, ``'isophote'``
        or ``'zebra'`` (per-vertex phase; black/white).
    scale : (lo, hi), optional
        Default: as the report's pictures (symmetric about 0 for signed curvatures).
    cmap : str, optional
        A key of :data:`occsurf.bridge.rendering.vtk_scene.COLORMAPS`; default as the pictures.
    """
    from ..rendering.vtk_scene import colormap_rgb
    from .pictures import PICTURE_KINDS
    from .scales import value_range

    fields = _fields(source)
    if not fields:
        raise ValueError("source: no evaluated face to colour")
    if indicator not in fields[0].values:
        raise ValueError(f"indicator: expected one of {', '.join(sorted(fields[0].values))}, got {indicator!r}")
    offsets = np.cumsum([0] + [f.mesh.n_vertices for f in fields])
    P = np.concatenate([f.mesh.points for f in fields])
    N = np.concatenate([f.mesh.normals for f in fields])
    T = np.concatenate([f.mesh.triangles + o for f, o in zip(fields, offsets)])
    V = np.concatenate([f.values[indicator] for f in fields])
    if indicator == "zebra":
        lo, hi = 0.0, 1.0
        colors = np.where(np.isfinite(V), np.where(V < 0.5, 245, 15), 128).astype(np.uint8)[:, None].repeat(3, 1)
    else:
        size = getattr(source, "size", None) or 1.0
        lo, hi = scale if scale is not None else value_range([f.values[indicator] for f in fields], indicator, size)
        kind = PICTURE_KINDS.get(indicator)
        name = cmap or (kind[1] if kind is not None and kind[1] not in ("stripes", "grey") else "diverging")
        colors = colormap_rgb(V, lo, hi, name)
    return ColoredMesh(points=P, triangles=T, colors=colors, values=V, normals=N, indicator=indicator, lo=lo, hi=hi)


def as_edges(polylines: Sequence[np.ndarray], *, smooth: bool = True) -> list[bd.Edge]:
    """build123d edges through polylines ``(k, 3)``: a spline through the points (``smooth``, for
    section cuts and comb outlines) or straight segments (combs' teeth ``(2, 3)``, reflection-line
    segments). Polylines with fewer than 2 distinct points are skipped."""
    from build123d import Edge, Vector

    out: list[bd.Edge] = []
    for pl in polylines:
        P = np.asarray(pl, float)
        P = P[np.all(np.isfinite(P), axis=1)]
        if len(P) >= 2:
            keep = np.concatenate([[True], np.linalg.norm(np.diff(P, axis=0), axis=1) > 1e-12])
            P = P[keep]
        if len(P) < 2:
            continue
        pts: list[bd.VectorLike] = [Vector(*map(float, p)) for p in P]
        if smooth and len(P) >= 3:
            out.append(Edge.make_spline(pts))
        else:
            out.extend(Edge.make_line(a, b) for a, b in zip(pts[:-1], pts[1:]))
    return out


def section_curves(source: QualityReport | FaceField | Sequence[FaceField]) -> dict[str, Any]:
    """The section cuts with their curvature combs and inflection points, as the report's pictures
    draw them (:func:`occsurf.bridge.quality.pictures.section_lines`).

    Returns
    -------
    dict
        ``{"sections": [(k, 3) ...], "combs": [(2, 3) teeth and (k, 3) outlines ...], "inflections": (j, 3)}``.
    """
    from .pictures import section_lines

    fields = _fields(source)
    size = getattr(source, "size", None) or 1.0
    (lines, combs, infl), _ = section_lines(fields, size)
    return {"sections": lines, "combs": combs, "inflections": infl}


def reflection_lines(field: FaceField, *, levels: Sequence[float] = (0.0, 0.5)) -> np.ndarray:
    """Zebra boundaries on a face: segments ``(k, 2, 3)`` where the stripe phase crosses ``levels``.

    Marching triangles on the per-vertex phase of :func:`occsurf.algorithms.quality.zebra` (the
    report's set-up), unwrapped per triangle so a wrap from 1 to 0 is a crossing, not a jump.
    Triangles with an undefined phase (the reflected ray misses the lights) give no segment.
    """
    T = field.mesh.triangles
    P = field.mesh.points
    v = np.asarray(field.values["zebra"], float)[T]
    ok = np.all(np.isfinite(v), axis=1)
    T, v = T[ok], v[ok]
    d = v[:, 1:] - v[:, :1]
    v[:, 1:] = v[:, :1] + d - np.round(d)
    segs = []
    lo = np.floor(v.min(axis=1))
    for shift in (-1.0, 0.0, 1.0):
        for level in levels:
            L = (lo + shift + level)[:, None]
            s = v - L
            cross = []
            for a, b in ((0, 1), (1, 2), (2, 0)):
                hit = s[:, a] * s[:, b] < 0
                t = np.where(hit, s[:, a] / np.where(hit, s[:, a] - s[:, b], 1.0), 0.0)
                cross.append((hit, P[T[:, a]] + t[:, None] * (P[T[:, b]] - P[T[:, a]])))
            hits = np.stack([c[0] for c in cross], axis=1)
            two = hits.sum(axis=1) == 2
            pts = np.stack([c[1] for c in cross], axis=1)[two]
            first = np.argmax(hits[two], axis=1)
            second = 2 - np.argmax(hits[two][:, ::-1], axis=1)
            rows = np.arange(len(pts))
            segs.append(np.stack([pts[rows, first], pts[rows, second]], axis=1))
    return np.concatenate(segs) if segs else np.zeros((0, 2, 3))


def quality_overlays(source: Any, *, preset: str = "catia") -> list[bd.Compound]:
    """The report's line sets as coloured, labelled build123d Compounds, to show beside the part in
    a build123d viewer (``ocp_vscode.show(part, *quality_overlays(part))``) (issue 28).

    Parameters
    ----------
    source : QualityReport, ImportedModel or a build123d / cadquery / OCP shape
        A report of :func:`~occsurf.bridge.quality.report.check_model`, or a model to check (with
        ``preset``).

    Returns
    -------
    list of build123d.Compound
        ``sections`` (the cuts), ``combs`` (teeth and outlines), ``inflections`` (small crosses at
        the combs' sign changes) and one ``edges <class>`` per edge-continuity class present (G2,
        G1, G0, sharp, gap, seam, degenerate; the colours of the report's edge picture). Each has
        ``label`` and ``color`` set; empty sets are left out.
    """
    from build123d import Color, Compound, Edge, Vector

    from .pictures import EDGE_COLORS
    from .report import QualityReport, check_model

    report = source if isinstance(source, QualityReport) else check_model(source, preset=preset)
    lines: dict[str, Any] = (section_curves(report) if report.fields
                             else {"sections": [], "combs": [], "inflections": np.zeros((0, 3))})
    groups: list[tuple[str, tuple[float, float, float], list[bd.Edge]]] = [
        ("sections", OVERLAY_COLORS["sections"], as_edges(lines["sections"])),
        ("combs", OVERLAY_COLORS["combs"], as_edges([c for c in lines["combs"] if len(c) == 2], smooth=False)
         + as_edges([c for c in lines["combs"] if len(c) > 2])),
    ]
    infl = np.asarray(lines["inflections"], float).reshape(-1, 3)
    if len(infl):
        r = 0.004 * (report.size or 1.0)
        crosses = [Edge.make_line(Vector(*(p - r * e)), Vector(*(p + r * e))) for p in infl for e in np.eye(3)]
        groups.append(("inflections", OVERLAY_COLORS["inflections"], crosses))
    by_class: dict[str, list[np.ndarray]] = {}
    for cls, pl in report.edge_lines:
        by_class.setdefault(cls, []).append(pl)
    for cls, pls in by_class.items():
        groups.append((f"edges {cls}", EDGE_COLORS.get(cls, (0.5, 0.5, 0.5)), as_edges(pls)))
    out: list[bd.Compound] = []
    for label, rgb, edges in groups:
        if not edges:
            continue
        comp = Compound(children=edges)
        comp.label = label
        comp.color = Color(*rgb)
        out.append(comp)
    return out
