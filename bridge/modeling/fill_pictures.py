"""Before/after zebra pictures of a filled hole (course ch. 9, §9-8 reflection lines; issue 12).

The eye sees a G1 failure as a kink in zebra stripes, a G2 change as a change in their width. One
picture per hole: on the left the model around the hole before (the removed faces and their
neighbours, or the neighbours alone around an open hole), on the right after (the fill's patches and
the same neighbours), both from the same camera (looking onto the hole along its mean normal, tilted
so that the stripes run across it) and with the same per-pixel stripes
(:data:`occsurf.bridge.rendering.vtk_scene.PIXEL_SHADERS` ``'zebra'``: reflection lines of light
tubes at infinity, fixed to the view). Faces are triangulated by ``BRepMesh_IncrementalMesh``; the
per-vertex normals are the surfaces' own (``BRepLib_ToolTriangulatedShape.ComputeNormals``), so
the stripes are those of the exact surfaces, interpolated per pixel.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["zebra_before_after", "hole_pictures", "face_triangles", "ZEBRA_PAIRS", "PICTURE_SIZE"]

#: Light/dark stripe pairs per half turn of the reflected ray.
ZEBRA_PAIRS: int = 10
#: Size in pixels of each half of the picture (before | after).
PICTURE_SIZE: tuple[int, int] = (640, 520)
#: Linear deflection of the mesher relative to the size of the pictured faces, and its angular one.
DEFLECTION: float = 2e-4
ANGULAR: float = 0.05


def face_triangles(face: Any, deflection: float) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """``(points (n, 3), triangles (m, 3), unit normals (n, 3))`` of an OCC face, outward by its
    orientation, or ``None`` when OCC cannot mesh it. One loop over the nodes (OCC hands them out
    one by one)."""
    from OCP.BRep import BRep_Tool
    from OCP.BRepLib import BRepLib_ToolTriangulatedShape
    from OCP.BRepMesh import BRepMesh_IncrementalMesh
    from OCP.TopAbs import TopAbs_REVERSED
    from OCP.TopLoc import TopLoc_Location

    BRepMesh_IncrementalMesh(face, deflection, False, ANGULAR, False).Perform()
    loc = TopLoc_Location()
    tri = BRep_Tool.Triangulation_s(face, loc)
    if tri is None or tri.NbTriangles() == 0:
        return None
    BRepLib_ToolTriangulatedShape.ComputeNormals_s(face, tri)
    trsf = loc.Transformation()
    n, m = tri.NbNodes(), tri.NbTriangles()
    P = np.array([tri.Node(i).Transformed(trsf).Coord() for i in range(1, n + 1)], float)
    N = np.array([tri.Normal(i).Transformed(trsf).Coord() for i in range(1, n + 1)], float)
    T = np.array([tri.Triangle(i).Get() for i in range(1, m + 1)], np.int64) - 1
    if face.Orientation() == TopAbs_REVERSED:
        N, T = -N, T[:, ::-1]
    N /= np.maximum(np.linalg.norm(N, axis=1, keepdims=True), 1e-300)
    return P, T, N


def _view(meshes: list[tuple[np.ndarray, np.ndarray, np.ndarray]]) -> np.ndarray:
    """Camera direction: the area-weighted mean normal, tilted 30 degrees about an in-plane axis."""
    acc = np.zeros(3)
    for P, T, _ in meshes:
        acc += np.cross(P[T[:, 1]] - P[T[:, 0]], P[T[:, 2]] - P[T[:, 0]]).sum(0)
    n = acc / max(float(np.linalg.norm(acc)), 1e-300)
    if not np.all(np.isfinite(n)) or np.linalg.norm(acc) == 0:
        n = np.array([1.0, -1.0, 0.8]) / np.sqrt(2.64)
    e = np.cross(n, np.eye(3)[int(np.argmin(np.abs(n)))])
    e /= np.linalg.norm(e)
    return np.cos(np.radians(30)) * n + np.sin(np.radians(30)) * e


def _scene(meshes: list[tuple[np.ndarray, np.ndarray, np.ndarray]], lines: list[np.ndarray], title: str) -> Any:
    from ..rendering.vtk_scene import Scene

    scene = Scene()
    for P, T, N in meshes:
        scene.add_mesh(P, T, normals=N, shader="zebra", stripes=ZEBRA_PAIRS)
    if lines:
        scene.add_lines(lines, color=(0.85, 0.1, 0.1), width=2.0)
    scene.set_title(title)
    return scene


def _edge_lines(faces: Sequence[Any], samples: int = 64) -> list[np.ndarray]:
    """Polylines of every edge of ``faces`` (the fill's patch boundaries, drawn over the stripes)."""
    from OCP.BRep import BRep_Tool
    from OCP.TopAbs import TopAbs_EDGE
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopoDS import TopoDS

    out = []
    for f in faces:
        ex = TopExp_Explorer(f, TopAbs_EDGE)
        while ex.More():
            e = TopoDS.Edge_s(ex.Current())
            c = BRep_Tool.Curve_s(e, 0.0, 0.0)
            if c is not None and not BRep_Tool.Degenerated_s(e):
                a, b = BRep_Tool.Range_s(e)
                out.append(np.array([c.Value(t).Coord() for t in np.linspace(a, b, samples)]))
            ex.Next()
    return out


def zebra_before_after(path: str | Path, before: Sequence[Any], neighbours: Sequence[Any], after: Sequence[Any], *,
                       label: str = "", after_label: str = "") -> Path:
    """Write one PNG: zebra stripes around a hole before (left) and after (right) the fill.

    Parameters
    ----------
    path : str or Path
        The PNG to write (atomically).
    before : sequence of TopoDS_Face
        The faces the fill replaces (empty for a hole of the model itself).
    neighbours : sequence of TopoDS_Face
        The faces around the hole, drawn in both halves.
    after : sequence of TopoDS_Face
        The fill's faces (their patch boundaries drawn in red).
    label, after_label : str
        Titles of the two halves.

    Returns
    -------
    Path

    Raises
    ------
    RuntimeError
        VTK cannot render offscreen here (:func:`occsurf.bridge.rendering.vtk_scene.render_available`).
    """
    from ..rendering.png import write_png_file
    from ..rendering.vtk_scene import render_available

    if not render_available():
        raise RuntimeError("VTK cannot render offscreen here: no zebra picture")
    all_faces = list(before) + list(neighbours) + list(after)
    size = _size(all_faces)
    mesh = {id(f): face_triangles(f, DEFLECTION * size) for f in all_faces}
    nb = [m for f in neighbours if (m := mesh[id(f)]) is not None]
    old = [m for f in before if (m := mesh[id(f)]) is not None]
    new = [m for f in after if (m := mesh[id(f)]) is not None]
    direction = _view(old + new if (old or new) else nb)
    halves = []
    for meshes, lines, title in ((nb + old, [], label or "before"), (nb + new, _edge_lines(after), after_label or "after")):
        halves.append(_scene(meshes, lines, title).render_array(size=PICTURE_SIZE, camera=tuple(direction)))
    gap = np.full((PICTURE_SIZE[1], 6, 3), 255, np.uint8)
    return write_png_file(path, np.concatenate([halves[0], gap, halves[1]], axis=1), level=1)


def hole_pictures(out: str | Path, reports: Sequence[Any], holes: Sequence[dict[str, Any]], *,
                  refill: bool = False) -> None:
    """One :func:`zebra_before_after` picture per filled hole, ``OUT_STEM.holeK.png`` beside ``out``.

    Parameters
    ----------
    out : str or Path
        The filled model's file (the pictures are named after it).
    reports : sequence
        The holes' reports: :class:`~occsurf.bridge.modeling.fill.HoleReport` of
        :func:`~occsurf.bridge.modeling.fill.fill_model`, or with ``refill`` those of
        :func:`~occsurf.bridge.modeling.refill.refill_model` (the faces it removed are drawn before).
    holes : sequence of dict
        One dict per report (the JSON of ``occsurf fill``): the picture's path goes in as ``picture``, or
        ``None`` and why not (one line) as ``picture_error``; a picture that fails never costs the fill.
    refill : bool, default False
    """
    from ..messages import one_line

    out = Path(out)
    for k, (r, h) in enumerate(zip(reports, holes)):
        if r.status != "filled" or not hasattr(r, "_fill_faces"):
            continue
        try:
            path = zebra_before_after(out.with_name(f"{out.stem}.hole{k}.png"), r._removed if refill else [],
                                      r._neighbours, r._fill_faces, label=f"before (hole {k})",
                                      after_label=_after_label(h, len(r._fill_faces)))
            h["picture"] = str(path)
        except Exception as err:  # noqa: BLE001 - a picture must not cost the fill
            h["picture"], h["picture_error"] = None, one_line(err)


def _size(faces: Sequence[Any]) -> float:
    from OCP.Bnd import Bnd_Box
    from OCP.BRepBndLib import BRepBndLib

    box = Bnd_Box()
    for f in faces:
        BRepBndLib.Add_s(f, box)
    return float(np.sqrt(box.SquareExtent())) if not box.IsVoid() else 1.0


def _after_label(hole: dict[str, Any], n_faces: int) -> str:
    """The caption of a fill's zebra picture: how many faces, and the continuity asked (and got)."""
    faces = "1 face" if n_faces == 1 else f"{n_faces} patches"
    if hole.get("g2") is not None:
        return f"after: occsurf fill, {faces}, G2 (curvature jump {100 * hole['g2']:.2g} %)"
    return f"after: occsurf fill, {faces}"

