"""Pictures and STEP files for generalized B-spline surfaces of arbitrary topology (course §8-6, 8-7).

:func:`render_generalized_demo` builds the generalized biquadratic surface (Loop & DeRose 1990) of a
small irregular control mesh (a wavy pentagonal dome: one Catmull–Clark step turns it into quads
with vertices of valence 3, 4 and 5) and of a genus-1 picture frame, and the generalized bicubic
surface of both (one Doo–Sabin step: every vertex of valence 4, faces of 3 to 5 sides), pictures them coloured by mean
and Gaussian curvature (computed from the S-patches' exact second derivatives) with the control
mesh overlaid, and writes each surface to STEP as a sewn shell through
:func:`occsurf.bridge.exchange.spatch_io.write_spatches_step`.

Rendering: every piece of every S-patch is a grid of points with its exact normals, drawn by VTK
(:func:`occsurf.bridge.rendering.surfaces.render_surfaces`: one depth buffer for all of them).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from occsurf.algorithms.topology.generalized import GeneralizedSurface, generalized_biquadratic, spatch_curvatures
from occsurf.algorithms.topology.generalized_bicubic import generalized_bicubic
from occsurf.algorithms.topology.mesh import Mesh
from occsurf.algorithms.topology.spatch_convert import piece_domain_points

from ._common import output_folder

__all__ = ["render_generalized_demo", "demo_dome", "demo_frame", "render_generalized"]



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
def _sample(surface: GeneralizedSurface, resolution: int, which: str) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """Every patch piece as a ``resolution x resolution`` grid: points, unit normals and the
    ``which`` ("mean" or "gaussian") curvature."""
    s = np.linspace(0.0, 1.0, resolution)
    S, T = np.meshgrid(s, s, indexing="ij")
    grids = []
    for p in surface.patches:
        for k in range(p.sides):
            x = piece_domain_points(p.sides, k, S, T)
            K, H, N = spatch_curvatures(p, x)
            grids.append((p.evaluate(x), N, K if which == "gaussian" else H))
    return grids


def render_generalized(path: Path, surface: GeneralizedSurface, *, title: str, control: Mesh | None = None,
                       color: str = "mean", views: tuple[tuple[float, float], ...] = ((30.0, -60.0), (65.0, 25.0)),
                       resolution: int = 9, subtitle: str | None = None) -> Path:
    """One PNG: the surface's patches coloured by ``color`` ("mean" or "gaussian") curvature and
    shaded by VTK (:func:`~occsurf.bridge.rendering.surfaces.render_panels`), the control mesh
    drawn as thin green lines with its vertices as dots, patch boundaries as thin dark lines."""
    from matplotlib import cm
    from matplotlib.colors import TwoSlopeNorm

    from occsurf.bridge.rendering.surfaces import Panel, render_panels

    grids = _sample(surface, resolution, color)
    lim = float(np.percentile(np.abs(np.concatenate([g[2].ravel() for g in grids])), 97)) or 1.0
    grids = [(P, N, np.clip(c, -lim, lim)) for P, N, c in grids]
    t = np.linspace(0.0, 1.0, 24)
    boundaries = [(p.evaluate(p.edge_points(k, t)), (0.15, 0.15, 0.15), 1.0) for p in surface.patches
                  for k in range(p.sides)]
    mesh = control if control is not None else surface.mesh
    panels = [Panel(grids, mesh_lines=[mesh.vertices[list(e)] for e in mesh.edges], lines=boundaries,
                    points=[(mesh.vertices, (0.16, 0.48, 0.16), 6.0)], view=view) for view in views]
    return render_panels(path, panels, norm=TwoSlopeNorm(vcenter=0.0, vmin=-lim, vmax=lim), cmap=cm.coolwarm,
                         colorbar_label="mean curvature H" if color == "mean" else "Gaussian curvature K",
                         title=title, subtitle=subtitle, figsize=(5.6 * len(views) + 1.2, 5.6))


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
