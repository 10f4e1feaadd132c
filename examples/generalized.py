"""Pictures and STEP files for generalized B-spline surfaces of arbitrary topology (course §8-6, 8-7).

:func:`render_generalized_demo` builds the generalized biquadratic surface (Loop & DeRose 1990) of a
small irregular control mesh (a wavy pentagonal dome: one Catmull–Clark step turns it into quads
with vertices of valence 3, 4 and 5) and of a genus-1 picture frame, and the generalized bicubic
surface of both (one Doo–Sabin step: every vertex of valence 4, faces of 3 to 5 sides), pictures them coloured by mean
and Gaussian curvature (computed from the S-patches' exact second derivatives) with the control
mesh overlaid, and writes each surface to STEP as a sewn shell through
:func:`occsurf.bridge.exchange.spatch_io.write_spatches_step`.

Rendering: all quads of all patches go into one ``Poly3DCollection`` so matplotlib depth-sorts them
together (separate ``plot_surface`` calls are painted in call order and show through each other).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from occsurf.algorithms.topology.generalized import GeneralizedSurface, generalized_biquadratic, spatch_curvatures
from occsurf.algorithms.topology.generalized_bicubic import generalized_bicubic
from occsurf.algorithms.topology.mesh import Mesh
from occsurf.algorithms.topology.spatch_convert import piece_domain_points
from occsurf.bridge.exchange.files import write_figure

from ._common import output_folder

__all__ = ["render_generalized_demo", "demo_dome", "demo_frame", "render_generalized"]

_LIGHT = np.array([-0.45, -0.35, 0.82]) / np.linalg.norm([-0.45, -0.35, 0.82])


# ------------------------------------------------------------------------------------- meshes
def demo_dome() -> Mesh:
    """An open wavy pentagonal dome: a pentagon on top, a ring of 5 quads below it and a wavy skirt
    of 10 quads. Its pentagon and the valence-3 corners of the top stay interior, so the
    Catmull–Clark step leaves interior vertices of valence 3 and 5."""
    rings = ((5, 1.0, 1.9, 0.0), (5, 1.6, 0.9, 0.0), (10, 2.6, 0.0, 0.45))  # count, radius, height, wave
    verts: list[tuple[float, float, float]] = []
    start: list[int] = []
    for r, (n, rad, h, wave) in enumerate(rings):
        start.append(len(verts))
        for i in range(n):
            a = 2 * np.pi * i / n + (np.pi / 5 if r == 2 else 0.0)
            verts.append((rad * np.cos(a) * (1 + 0.08 * np.cos(2 * a)), rad * np.sin(a), h + wave * np.sin(2.5 * a)))
    s0, s1, s2 = start
    faces: list[tuple[int, ...]] = [tuple(range(s0, s0 + 5))]
    for i in range(5):
        j = (i + 1) % 5
        faces.append((s0 + j, s0 + i, s1 + i, s1 + j))
        faces.append((s1 + j, s1 + i, s2 + 2 * i, s2 + 2 * i + 1))
        faces.append((s1 + j, s2 + 2 * i + 1, s2 + (2 * i + 2) % 10))
    return Mesh(np.array(verts), tuple(faces))


def demo_frame() -> Mesh:
    """A square picture frame (genus 1) of 32 quads: outer corners of valence 3, hole corners of
    valence 5; slightly twisted so that it is not symmetric."""
    vid: dict[tuple[int, int, int], int] = {}
    pts: list[tuple[float, float, float]] = []
    for z in (0, 1):
        for i in range(4):
            for j in range(4):
                vid[(i, j, z)] = len(pts)
                pts.append((i + 0.15 * z * (j - 1.5), j, 0.8 * z + 0.1 * np.sin(i + j)))
    F: list[tuple[int, ...]] = []
    for i in range(3):
        for j in range(3):
            if (i, j) != (1, 1):
                F.append((vid[(i, j, 1)], vid[(i + 1, j, 1)], vid[(i + 1, j + 1, 1)], vid[(i, j + 1, 1)]))
                F.append((vid[(i, j, 0)], vid[(i, j + 1, 0)], vid[(i + 1, j + 1, 0)], vid[(i + 1, j, 0)]))
    outer = [(i, 0) for i in range(3)] + [(3, j) for j in range(3)] + [(i, 3) for i in range(3, 0, -1)] + [(0, j) for j in range(3, 0, -1)]
    hole = [(1, 1), (1, 2), (2, 2), (2, 1)]
    for loop in (outer, hole):
        for a, b in zip(loop, loop[1:] + loop[:1]):
            F.append((vid[a + (0,)], vid[b + (0,)], vid[b + (1,)], vid[a + (1,)]))
    return Mesh(np.array(pts, float), tuple(F))


# ------------------------------------------------------------------------------------- drawing
def _sample(surface: GeneralizedSurface, resolution: int, which: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Quads (Q, 4, 3), their unit normals (Q, 3) and curvature values (Q,) of every patch piece."""
    s = np.linspace(0.0, 1.0, resolution)
    S, T = np.meshgrid(s, s, indexing="ij")
    quads, normals, vals = [], [], []
    for p in surface.patches:
        for k in range(p.sides):
            x = piece_domain_points(p.sides, k, S, T)
            K, H, N = spatch_curvatures(p, x)
            P = p.evaluate(x)
            c = K if which == "gaussian" else H
            q = np.stack((P[:-1, :-1], P[1:, :-1], P[1:, 1:], P[:-1, 1:]), axis=2).reshape(-1, 4, 3)
            quads.append(q)
            nq = (N[:-1, :-1] + N[1:, :-1] + N[1:, 1:] + N[:-1, 1:]).reshape(-1, 3)
            normals.append(nq / np.linalg.norm(nq, axis=-1, keepdims=True))
            vals.append(((c[:-1, :-1] + c[1:, :-1] + c[1:, 1:] + c[:-1, 1:]) / 4).ravel())
    return np.concatenate(quads), np.concatenate(normals), np.concatenate(vals)


def render_generalized(path: Path, surface: GeneralizedSurface, *, title: str, control: Mesh | None = None,
                       color: str = "mean", views: tuple[tuple[float, float], ...] = ((30.0, -60.0), (65.0, 25.0)),
                       resolution: int = 9, subtitle: str | None = None) -> Path:
    """One PNG: the surface's patches shaded and coloured by ``color`` ("mean" or "gaussian")
    curvature, the control mesh drawn as thin lines, patch boundaries as dark lines."""
    from matplotlib import cm
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.colors import TwoSlopeNorm
    from matplotlib.figure import Figure
    from mpl_toolkits.mplot3d.art3d import Line3DCollection, Poly3DCollection

    quads, normals, vals = _sample(surface, resolution, color)
    lim = float(np.percentile(np.abs(vals), 97)) or 1.0
    norm = TwoSlopeNorm(vcenter=0.0, vmin=-lim, vmax=lim)
    rgb = cm.coolwarm(norm(np.clip(vals, -lim, lim)))
    rgb[:, :3] *= (0.35 + 0.65 * np.abs(normals @ _LIGHT))[:, None]
    t = np.linspace(0.0, 1.0, 24)
    edges = [p.evaluate(p.edge_points(k, t)) for p in surface.patches for k in range(p.sides)]
    mesh = control if control is not None else surface.mesh
    mesh_lines = [mesh.vertices[list(e)] for e in mesh.edges]
    pts = np.concatenate((quads.reshape(-1, 3), mesh.vertices))
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    centre, half = (lo + hi) / 2, float((hi - lo).max()) / 2 * 0.8
    fig = Figure(figsize=(5.6 * len(views) + 1.2, 5.6), dpi=110)
    FigureCanvasAgg(fig)
    fig.subplots_adjust(left=0.0, right=0.9, bottom=0.0, top=0.88, wspace=0.0)
    for i, (elev, azim) in enumerate(views):
        ax = fig.add_subplot(1, len(views), i + 1, projection="3d")
        ax.add_collection3d(Poly3DCollection(quads, facecolors=rgb, edgecolors="none", linewidths=0))
        ax.add_collection3d(Line3DCollection(edges, colors="0.15", linewidths=0.5, alpha=0.5))
        ax.add_collection3d(Line3DCollection(mesh_lines, colors="#2a7a2a", linewidths=0.9, alpha=0.85))
        ax.scatter(*mesh.vertices.T, s=4, c="#2a7a2a", depthshade=False)
        ax.set_xlim(centre[0] - half, centre[0] + half)
        ax.set_ylim(centre[1] - half, centre[1] + half)
        ax.set_zlim(centre[2] - half, centre[2] + half)
        ax.set_box_aspect((1, 1, 1))
        ax.view_init(elev=elev, azim=azim)
        ax.set_axis_off()
    sm = cm.ScalarMappable(norm=norm, cmap=cm.coolwarm)
    fig.colorbar(sm, ax=fig.axes, shrink=0.6, pad=0.02,
                 label="mean curvature H" if color == "mean" else "Gaussian curvature K")
    fig.suptitle(title if not subtitle else f"{title}\n{subtitle}", fontsize=11)
    write_figure(fig, path)
    return Path(path)


# ------------------------------------------------------------------------------------- demo
def render_generalized_demo(out_dir: Path) -> list[Path]:
    """Write the generalized-B-spline pictures and STEP files into ``out_dir``; return their paths."""
    from occsurf.bridge.exchange.spatch_io import write_spatches_step

    out = output_folder(out_dir)
    files: list[Path] = []
    schemes = (("biquadratic", "", generalized_biquadratic), ("bicubic", "bicubic_", generalized_bicubic))
    for scheme, prefix, build in schemes:
        for name, mesh in (("dome", demo_dome()), ("frame", demo_frame())):
            surf = build(mesh)
            gap, ang = surf.continuity(33)
            val = sorted({p.sides for p in surf.patches})
            sub = (f"{len(surf)} S-patches (sides {', '.join(map(str, val))}); green: control mesh; "
                   f"measured G0 gap {gap:.1e}, normal angle {np.degrees(ang):.1e} deg")
            for color in ("mean", "gaussian"):
                files.append(render_generalized(out / f"generalized_{prefix}{name}_{color}.png", surf, control=mesh,
                                                title=f"Generalized {scheme} B-spline surface ({name}), "
                                                      f"{'mean' if color == 'mean' else 'Gaussian'} curvature",
                                                subtitle=sub, color=color))
            files.append(write_spatches_step(out / f"generalized_{prefix}{name}.step", list(surf.patches)))
    return files
