"""Pictures of a quality report, rendered offscreen by VTK (:mod:`occsurf.bridge.rendering.vtk_scene`).

Course ch. 9 (§9-8 graphical display): curvature maps with their legend, zebra stripes, isophotes,
draft angle, normals (hedgehog), section cuts with curvature combs, and flag locations. Every
picture is a PNG of a shaded mesh from OCC's triangulation, coloured per vertex by our own
indicators (:func:`~occsurf.bridge.quality.report.face_fields`); degenerate points are magenta.

:data:`MODEL_PICTURES` are drawn for the whole model, :data:`FACE_PICTURES` for every face;
:func:`render_report_pictures` writes them and records their paths in the report.
"""

from __future__ import annotations

from collections.abc import Callable, Collection, Iterator, Sequence
from concurrent.futures import Future
from pathlib import Path
from typing import TYPE_CHECKING, TypeVar

import numpy as np

from ..messages import error_line
from ..rendering.png import PngWriter
from .choices import PICTURE_CHOICES, WORST_FACES
from .scales import value_range

if TYPE_CHECKING:
    from ..rendering.vtk_scene import Scene
    from .report import FaceField, FaceQuality, QualityReport

__all__ = ["render_report_pictures", "render_picture", "MODEL_PICTURES", "FACE_PICTURES", "PICTURE_KINDS",
           "PICTURE_CHOICES", "WORST_FACES", "section_lines", "face_section_lines", "model_sections"]

#: Every picture kind: (indicator, colour map, legend title).
PICTURE_KINDS: dict[str, tuple[str | None, str, str, str]] = {
    "mean": ("mean", "diverging", "H [1/unit]", "mean curvature H"),
    "gaussian": ("gaussian", "diverging", "K [1/unit^2]", "Gaussian curvature K"),
    "max": ("max", "diverging", "k1 [1/unit]", "max principal curvature k1"),
    "absolute": ("absolute", "rainbow", "|k1|+|k2|", "absolute curvature |k1|+|k2|"),
    "zebra": ("zebra", "stripes", "zebra", "zebra stripes (reflection lines, per pixel)"),
    "isophote": ("isophote", "stripes", "n . v", "isophotes (n . v, light from the viewer, per pixel)"),
    "draft": ("draft", "diverging", "draft [deg]", "draft angle, pull +z"),
    "hedgehog": (None, "grey", "", "normals (hedgehog)"),
    "sections": (None, "grey", "", "sections with curvature combs (green: inflections)"),
    "edges": (None, "grey", "", "edges: G2 green, G1 blue, G0 orange, sharp black, gap magenta; red: violations"),
}
#: Colours of the edge classes of :func:`occsurf.bridge.quality.continuity.edge_continuity`.
EDGE_COLORS: dict[str, tuple[float, float, float]] = {
    "G2": (0.1, 0.65, 0.2), "G1": (0.15, 0.35, 0.9), "G0": (0.95, 0.55, 0.0), "sharp": (0.05, 0.05, 0.05),
    "gap": (0.9, 0.0, 0.9), "seam": (0.55, 0.55, 0.55), "degenerate": (0.5, 0.0, 0.5),
}
MODEL_PICTURES = ("mean", "gaussian", "zebra", "isophote", "draft", "hedgehog", "sections", "edges")
FACE_PICTURES = ("mean", "zebra", "sections")
# ``--pictures`` choices and the worst-face count live in .choices (the command line reads them
# without NumPy); re-exported here.
#: Picture sizes in pixels.
MODEL_SIZE = (900, 640)
FACE_SIZE = (440, 330)
#: Light/dark pairs of the per-pixel zebra (per half turn of the reflected ray) and isophotes
#: (over n . v in [-1, 1]).
ZEBRA_PAIRS = 8
ISOPHOTE_PAIRS = 6
#: Normals drawn: one per cell of a grid of side size / HEDGEHOG_CELLS; length relative to the size.
HEDGEHOG_CELLS = 30
HEDGEHOG_LENGTH = 0.03
#: Section planes per picture (normal to the longest side of the bounding box).
N_SECTIONS = 9
#: Section planes of a face's own picture, through the face's own extent: normal to the model's
#: section direction when the face spans at least FACE_SECTION_MIN_EXTENT of its largest extent
#: along it (sections read the same way on every face), else to the face's own longest side
#: (a face flat across the model's direction would be missed or cut once).
N_FACE_SECTIONS = 7
FACE_SECTION_MIN_EXTENT = 0.2
#: Comb teeth: longest tooth as a fraction of the shown extent (for the curvature at
#: COMB_PERCENTILE of all the picture's cuts: one scale per picture).
COMB_SCALE = 0.12
COMB_PERCENTILE = 99.0


_T = TypeVar("_T")


def _returning(value: _T) -> Callable[[], _T]:
    """A function of no arguments that returns ``value`` (bound now, not when it is called)."""
    return lambda: value


def _hedgehog_points(fields: Sequence[FaceField], size: float) -> tuple[np.ndarray, np.ndarray]:
    """About evenly spread vertices for the normals: one per cell of a grid of side
    ``size / HEDGEHOG_CELLS`` (small faces get few, large faces many): of the vertices (with a
    normal) in a cell, the first in the faces' order, the cells sorted.

    Face by face, then over the faces' picks (the first vertex of a cell is the first of its
    face's, and the earliest face's pick comes first): the same points as over all vertices at
    once without the copies of every vertex (1.8 million for a 1089-face model, ~250 MB)."""
    faces = []  # the faces with a normal somewhere, and which vertices have one (masks only: no copies)
    for f in fields:
        ok = np.all(np.isfinite(f.mesh.normals), axis=1)
        if ok.any():
            faces.append((f, ok))
    if not faces:
        return np.zeros((0, 3)), np.zeros((0, 3))
    low, cell = np.min([f.mesh.points[ok].min(axis=0) for f, ok in faces], axis=0), size / HEDGEHOG_CELLS
    keys, P, N = [], [], []
    for f, ok in faces:  # one face's vertices at a time
        p, n = f.mesh.points[ok], f.mesh.normals[ok]
        k = np.floor((p - low) / cell).astype(np.int64)
        kk, first = np.unique(k, axis=0, return_index=True)
        keys.append(kk)
        P.append(p[first])
        N.append(n[first])
    _, first = np.unique(np.concatenate(keys), axis=0, return_index=True)
    return np.concatenate(P)[first], np.concatenate(N)[first]


Lines = tuple[list[np.ndarray], list[np.ndarray], np.ndarray]


def section_lines(fields: Sequence[FaceField], size: float) -> tuple[Lines, dict[int, Lines]]:
    """Section polylines through the faces, their combs and inflection points, for the whole set
    and per face.

    :data:`N_SECTIONS` planes normal to the longest side of the faces' bounding box, cut by
    :func:`occsurf.algorithms.quality.plane_sections` on the faces' own surfaces (trimmed by
    :func:`~.uv_masks.uv_mask`), chained across face boundaries; every cut carries its curvature comb. The
    per-face lines are the pieces of the same cuts on that face (one family of planes, as a
    surfacer reads sections).

    Returns
    -------
    (lines, per_face)
        ``lines = (polylines, comb_lines, inflections)``: section polylines ``(k, 3)``; comb
        teeth ``(2, 3)`` and comb outlines ``(k, 3)``; inflection points ``(j, 3)``.
        ``per_face``: the same per face index (``FaceMesh.index``).
    """
    pts = np.concatenate([f.mesh.points for f in fields])
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    axis = int(np.argmax(hi - lo))
    return _cut(fields, lo, np.eye(3)[axis], np.linspace(0.04, 0.96, N_SECTIONS) * float(hi[axis] - lo[axis]))


def model_sections(report: QualityReport) -> Lines:
    """The model's sections, combs and inflections (:func:`section_lines` of all its faces), computed
    once per report and kept on it (:attr:`QualityReport.sections`): the sections picture and the
    page's 3-D view share them. Empty lines, and a warning in the report, when cutting fails."""
    if report.sections is None:
        fields = [report.fields[k] for k in sorted(report.fields)]
        empty: Lines = ([], [], np.zeros((0, 3)))
        try:
            report.sections = section_lines(fields, report.size)[0] if fields else empty
        except Exception as err:  # noqa: BLE001 - the rest of the report stands without sections
            report.warnings.append(f"sections not computed: {error_line(err)}")
            report.sections = empty
    lines: Lines = report.sections
    return lines


def face_section_lines(field_: FaceField, axis: int) -> Lines:
    """Sections of one face through its own extent (:data:`N_FACE_SECTIONS` planes), normal to the
    model's section ``axis`` (0, 1, 2) unless the face is thin along it
    (:data:`FACE_SECTION_MIN_EXTENT`), then to the face's own longest side; see :func:`section_lines`."""
    P = field_.mesh.points[np.all(np.isfinite(field_.mesh.points), axis=1)]
    lo, hi = P.min(axis=0), P.max(axis=0)
    ext = hi - lo
    if ext[axis] < FACE_SECTION_MIN_EXTENT * ext.max():
        axis = int(np.argmax(ext))
    whole, _ = _cut([field_], lo, np.eye(3)[axis], np.linspace(0.04, 0.96, N_FACE_SECTIONS) * float(ext[axis]))
    return whole


def model_section_axis(fields: Sequence[FaceField]) -> int:
    """The coordinate axis the model's sections are normal to: its bounding box's longest side."""
    pts = np.concatenate([f.mesh.points for f in fields])
    pts = pts[np.all(np.isfinite(pts), axis=1)]
    return int(np.argmax(pts.max(axis=0) - pts.min(axis=0)))


def _cut(fields: Sequence[FaceField], lo: np.ndarray, normal: np.ndarray,
         offsets: np.ndarray) -> tuple[Lines, dict[int, Lines]]:
    from occsurf.algorithms import quality, tolerances

    faces = [(f.surface, None if f.natural else f.mask()) for f in fields]  # a natural face: its whole box
    index = np.array([f.mesh.index for f in fields])
    acc: dict[int, tuple[list, list, list]] = {}

    def add(key: int, P: np.ndarray, base: np.ndarray, tips: np.ndarray, infl: np.ndarray) -> None:
        lines, combs, inf = acc.setdefault(key, ([], [], []))
        if len(P) < 2:
            return
        lines.append(P)
        if len(tips) >= 2:
            combs.extend(np.stack([base, tips], axis=1)[:: max(1, len(base) // 60)])
            combs.append(tips)
        if len(infl):
            inf.append(infl)

    sections = quality.plane_sections(faces, lo, normal, offsets)
    # one comb scale for the whole picture (as a CAD curvature graph): the curvature of all cuts'
    # COMB_PERCENTILE gets a spine COMB_SCALE of the extent, so a nearly straight cut shows a nearly
    # flat comb beside a curved one (each cut's comb scaled to its own maximum made every cut look
    # alike), and a cut grazing a face (its curvature tends to infinity there) does not flatten the rest
    curves = [c for sec in sections for c in sec.curves]
    ks = np.abs(np.concatenate([np.asarray(c.curvature, float) for c in curves])) if curves else np.zeros(0)
    ks = ks[np.isfinite(ks)]
    kref = float(np.percentile(ks, COMB_PERCENTILE)) if ks.size else 0.0
    pts = np.concatenate([f.mesh.points for f in fields])
    extent = float(np.linalg.norm(np.nanmax(pts, axis=0) - np.nanmin(pts, axis=0)))
    common = COMB_SCALE * extent / kref if kref * extent > tolerances.QUALITY_FLAT_CURVATURE else 0.0
    for cur in curves:
        P = np.asarray(cur.points, float)
        base, tips = np.asarray(cur.comb.points, float), np.asarray(cur.comb.tips, float)
        own = float(cur.comb.scale)
        tips = base + (tips - base) * (common / own) if own > 0 else base.copy()
        infl = np.asarray(cur.inflection_points, float).reshape(-1, 3)
        add(-1, P, base, tips, infl)
        aligned = len(base) == len(P)
        for fi in np.unique(cur.face):
            sel = np.asarray(cur.face) == fi
            add(int(index[fi]), P[sel], base[sel] if aligned else base[:0], tips[sel] if aligned else tips[:0],
                infl[:0])

    def pack(t: tuple[list, list, list]) -> Lines:
        return t[0], t[1], (np.concatenate(t[2]) if t[2] else np.zeros((0, 3)))

    whole = pack(acc.pop(-1, ([], [], [])))
    return whole, {k: pack(v) for k, v in acc.items()}


def render_picture(fields: Sequence[FaceField], kind: str, path: Path, *, size: tuple[int, int] = MODEL_SIZE,
                   title: str = "", model_size: float = 1.0, scale: tuple[float, float] | None = None,
                   flags: np.ndarray | None = None, edges: Sequence[tuple[str, np.ndarray]] = (),
                   sections: Callable[[], tuple[list, list, np.ndarray]] | None = None) -> Path:
    """One picture of ``kind`` (a key of :data:`PICTURE_KINDS`) of some faces, written to ``path``
    (keywords as :func:`picture_scene`)."""
    from ..rendering.png import write_png_file

    scene = picture_scene(fields, kind, title=title, model_size=model_size, scale=scale, flags=flags, edges=edges,
                          sections=sections)
    return write_png_file(path, scene.render_array(size=size, camera="iso"))


def picture_scene(fields: Sequence[FaceField], kind: str, *, title: str = "", model_size: float = 1.0,
                  scale: tuple[float, float] | None = None, flags: np.ndarray | None = None,
                  edges: Sequence[tuple[str, np.ndarray]] = (),
                  sections: Callable[[], tuple[list, list, np.ndarray]] | None = None) -> Scene:
    """The scene of one picture of ``kind`` (a key of :data:`PICTURE_KINDS`) of some faces: their
    meshes coloured by the kind's value (or striped per pixel), the legend, and the kind's lines
    (``sections()``'s lines, comb teeth and inflections; the ``edges`` of each continuity class),
    ``flags`` as red points and ``title``."""
    from ..rendering.vtk_scene import PIXEL_SHADERS, Scene

    if kind not in PICTURE_KINDS:
        raise ValueError(f"kind: expected one of {', '.join(PICTURE_KINDS)}, got {kind!r}")
    value, cmap, legend, _ = PICTURE_KINDS[kind]
    scene = Scene()
    if kind in PIXEL_SHADERS:  # zebra, isophotes: per pixel, from the interpolated normals; no scale to read
        for P, T, N, _ in _merged_meshes(fields, None):
            scene.add_mesh(P, T, normals=N, shader=kind, stripes=ZEBRA_PAIRS if kind == "zebra" else ISOPHOTE_PAIRS)
    elif value is not None:
        lo, hi = scale if scale is not None else value_range([f.values[value] for f in fields], value, model_size)
        for P, T, N, S in _merged_meshes(fields, value):
            scene.add_mesh(P, T, normals=N, scalars=S, cmap=cmap, scale=(lo, hi))
        scene.set_legend(legend, lo, hi, cmap=cmap)
    else:
        for P, T, N, _ in _merged_meshes(fields, None):
            scene.add_mesh(P, T, normals=N, cmap="grey")
    if kind == "hedgehog":
        hp, hn = _hedgehog_points(fields, model_size)
        scene.add_hedgehog(hp, hn, length=HEDGEHOG_LENGTH * model_size, color=(0.1, 0.2, 0.75))
    if kind == "sections" and sections is not None:
        lines, teeth, infl = sections()
        scene.add_lines(lines, color=(0.05, 0.05, 0.05), width=2.0)
        scene.add_lines(teeth, color=(0.85, 0.25, 0.1), width=1.0)
        if len(infl):
            scene.add_points(infl, color=(0.0, 0.6, 0.0), size=10)
    if kind == "edges":
        for cls, colour in EDGE_COLORS.items():
            scene.add_lines([pl for c, pl in edges if c == cls], color=colour, width=3.0)
    if flags is not None and len(flags):
        scene.add_points(flags, color=(0.95, 0.05, 0.05), size=11)
    if title:
        scene.set_title(title)
    return scene


#: Vertices per mesh handed to the scene: the faces' meshes are drawn in groups (one VTK actor per
#: group instead of one per face; the OCCT bearing's 213 faces: its 38 pictures 3.7-4.1 -> 3.1 s,
#: 1734 meshes added -> 38), each group small enough that its concatenated copy stays a few MB.
MERGED_VERTICES = 100_000


def _merged_meshes(fields: Sequence[FaceField], value: str | None,
                   limit: int | None = None) -> Iterator[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray | None]]:
    """The faces' meshes concatenated in their order, in groups of at most ``limit`` vertices (a
    face is never split; default :data:`MERGED_VERTICES`): ``(points, triangles, normals, values of
    `value` or None)`` per group. The same triangles drawn in the same order as one mesh per face
    (faces share no vertices, so a NaN normal's fallback from its own triangles is unchanged):
    the same picture to rasterisation round-off, since VTK shifts and scales each mesh's float32
    vertex buffer about its own bounds (the bearing: at most 0.4 % of a picture's pixels one level
    apart; the linkrods: none; tested)."""
    from ..rendering.vtk_scene import merged_meshes

    def mesh(k: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray | None]:
        m = fields[k].mesh
        return m.points, m.triangles, m.normals, None if value is None else fields[k].values[value]

    cap = MERGED_VERTICES if limit is None else int(limit)
    yield from merged_meshes([f.mesh.n_vertices for f in fields], mesh, cap)


def _violation_points(report: QualityReport) -> np.ndarray:
    pts = [v.get("point") for v in report.violations if v.get("point") is not None and len(v["point"]) == 3]
    return np.asarray(pts, float).reshape(-1, 3)


def _flag_points(report: QualityReport, faces: set[int] | None = None) -> np.ndarray:
    pts = [f2["location"] for f in report.faces if faces is None or f.index in faces for f2 in f.flags
           if f2.get("location") is not None and len(f2["location"]) == 3]
    return np.asarray(pts, float).reshape(-1, 3)


def render_report_pictures(report: QualityReport, out_dir: str | Path, *, model_pictures: Sequence[str] = MODEL_PICTURES,
                           face_pictures: Sequence[str] = FACE_PICTURES, faces: Collection[int] | None = None,
                           progress: Callable[[int, int], None] | None = None,
                           skip: dict[str, str] | None = None, trace: Callable[[str], None] | None = None) -> dict[str, str]:
    """Write the model's and every face's pictures into ``out_dir`` (created); paths relative to it.

    Model pictures are ``model_<kind>.png`` (returned); face pictures ``face_<index>_<kind>.png``
    (recorded in each :attr:`FaceQuality.pictures`), for the faces of index in ``faces`` (default:
    every face; the colour scales stay the whole model's). Every face's sections are cut through its own
    extent (:func:`face_section_lines`). A picture that fails is skipped and noted on its face (or
    in the report's warnings), never fatal; so is every picture named in ``skip`` (file name ->
    reason: one that crashed the process before). ``trace(f"picture {name}")`` is called before each.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    fields = [report.fields[k] for k in sorted(report.fields)]
    shown: dict[str, str] = {}
    if not fields:
        return shown
    scales = {v: value_range([f.values[v] for f in fields], v, report.size) for v in ("mean", "gaussian", "max", "absolute")}
    flags_all = _flag_points(report)
    drawn = [f for f in fields if faces is None or f.mesh.index in faces]
    total = len(model_pictures) + len(drawn) * len(face_pictures)
    skip = dict(skip or {})
    note = trace if trace is not None else (lambda stage: None)
    axis = model_section_axis(fields)
    done = 0
    # each picture is encoded and written on a background thread while the next one renders
    # (rendering.png); a picture that fails there is noted once every file is written, in order:
    # (the file's future, where its name is recorded, the kind, the name, where a failure is noted)
    written: list[tuple[Future[Path], dict[str, str], str, str, list[str]]] = []
    with PngWriter() as writer:

        def draw(name: str, kind: str, size: tuple[int, int], build: Callable[[], Scene], record: dict[str, str],
                 notes: list[str]) -> None:
            """One picture: left out when ``skip`` names it, else built, rendered and handed to the
            writer; a failure is noted in ``notes``, the name recorded in ``record`` once written."""
            nonlocal done
            done += 1
            if name in skip:
                notes.append(f"picture {kind} not drawn: {skip[name]}")
                return
            note(f"picture {name}")
            try:
                rgb = build().render_array(size=size, camera="iso")
                written.append((writer.write(out / name, rgb), record, kind, name, notes))
            except Exception as err:  # noqa: BLE001
                notes.append(f"picture {kind} not drawn: {error_line(err)}")
            if progress is not None:
                progress(done, total)

        for kind in model_pictures:

            def model_scene(kind: str = kind) -> Scene:
                return picture_scene(
                    fields, kind, model_size=report.size, scale=scales.get(PICTURE_KINDS[kind][0] or ""),
                    flags=flags_all if kind == "mean" else (_violation_points(report) if kind == "edges" else None),
                    edges=report.edge_lines, title=f"{Path(report.path).name}: {PICTURE_KINDS[kind][3]}",
                    sections=lambda: model_sections(report))

            draw(f"model_{kind}.png", kind, MODEL_SIZE, model_scene, shown, report.warnings)
        by_index = {f.index: f for f in report.faces}
        for fld in drawn:
            row = by_index[fld.mesh.index]
            for kind in face_pictures:

                def face_scene(fld: FaceField = fld, row: FaceQuality = row, kind: str = kind) -> Scene:
                    own: list[Lines] = []
                    if kind == "sections":
                        own.append(face_section_lines(fld, axis))
                        if not own[0][0]:
                            row.notes.append(f"no section through this face: {N_FACE_SECTIONS} planes through its "
                                             "own extent found no intersection inside its trim")
                    return picture_scene([fld], kind, model_size=report.size,
                                         flags=_flag_points(report, {row.index}) if kind == "mean" else None,
                                         title=f"face {row.index} ({row.type}): {kind}",
                                         sections=_returning(own[0]) if own else None)

                draw(f"face_{row.index}_{kind}.png", kind, FACE_SIZE, face_scene, row.pictures, row.notes)
    for fut, record, kind, name, notes in written:  # all done: the writer's block waited for them
        problem = fut.exception()
        if problem is None:
            record[kind] = name
        else:
            notes.append(f"picture {kind} not drawn: {error_line(problem)}")
    return shown

