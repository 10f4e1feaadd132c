"""Shaded pictures of surfaces for ``occsurf demo``: curvature colouring, lit by a 3-D engine.

Course ch. 9 (quality assessment: colour-coded curvature, §9-8 graphical representation) and
ch. 10 (lighting). Each view is rendered offscreen by VTK (:class:`~.vtk_scene.Scene`: depth
buffer, smooth shading from the surfaces' own normals, lines drawn over the surface); the views,
their titles and the colour bar are laid out side by side by matplotlib, which draws nothing 3-D.
Lives in ``occsurf.bridge`` (the gallery in ``occsurf.examples`` uses it), not in
``occsurf.algorithms``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from occsurf.algorithms import BSplineCurve, BSplineSurface
from occsurf.algorithms.geometry.surface_differential import curvatures_from_derivatives

from ..exchange.files import write_figure

__all__ = ["render_surfaces", "render_panels", "Panel", "surface_grid"]

COLORINGS = ("mean", "gaussian", "height", "none")


def surface_grid(surface: BSplineSurface, resolution: int = 60, color: str = "mean") -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Points ``(r, r, 3)``, unit normals ``(r, r, 3)`` and the colour scalar ``(r, r)`` of a surface.

    The scalar is the mean or Gaussian curvature (course §6-12), the height z, or zeros.
    Degenerate points (NaN curvature, e.g. a sphere's pole) take the value of their neighbours'
    median so they do not blot the picture.
    """
    from occsurf.algorithms._validate import check_count
    from occsurf.algorithms.errors import InvalidGeometryError
    from occsurf.algorithms.quality._common import check_grid

    if not isinstance(surface, BSplineSurface) or surface.dim != 3:  # as surface_curvatures refuses it
        raise InvalidGeometryError(f"surface: needs a 3-D BSplineSurface, got {surface!r}")
    r = check_count(resolution, "resolution", 1, minimum=2)
    check_grid(r, r, "resolution")  # the grid, its curvatures and the mesh, refused before any of them exists
    (u0, u1), (v0, v1) = surface.domain
    # pull the samples a hair inside so poles of revolved surfaces do not give NaN normals
    eu, ev = 1e-6 * (u1 - u0), 1e-6 * (v1 - v0)
    us = np.linspace(u0 + eu, u1 - eu, resolution)
    vs = np.linspace(v0 + ev, v1 - ev, resolution)
    P = surface.evaluate_grid(us, vs)
    # the partials on the grid (the basis once per row and per column), not point by point: the
    # curvatures of surface_curvatures at the same points to round-off
    sc = curvatures_from_derivatives(surface.derivatives_grid(us, vs, 2))
    n = np.asarray(sc.normal)
    if color == "mean":
        val = np.asarray(sc.mean, float)
    elif color == "gaussian":
        val = np.asarray(sc.gaussian, float)
    elif color == "height":
        val = P[..., 2].copy()
    else:
        val = np.zeros(P.shape[:2])
    bad = ~np.isfinite(val)
    if bad.any():
        val[bad] = np.nanmedian(val) if np.isfinite(val).any() else 0.0
    nbad = ~np.all(np.isfinite(n), axis=-1)
    if nbad.any():
        n[nbad] = (0.0, 0.0, 1.0)
    return P, n, val


Grid = tuple[np.ndarray, np.ndarray, np.ndarray]
RGB = tuple[float, float, float]


@dataclass
class Panel:
    """What one view of :func:`render_panels` shows.

    Attributes
    ----------
    grids : sequence of (points (r, s, 3), normals (r, s, 3), scalar (r, s))
        Sampled surfaces, drawn as triangles with their normals at the vertices (smooth shading),
        coloured by the scalar through the picture's colour map (grey without one).
    curves : sequence of BSplineCurve or (m, 3) arrays
        Black lines over the surfaces (input curves, boundaries).
    nets : sequence of (nu, nv, 3) arrays
        Control nets: thin grey lines (rows and columns).
    mesh_lines : sequence of (m, 3) arrays
        Thin green polylines: control meshes of arbitrary topology (course ch. 8).
    lines : sequence of (polyline (m, 3), colour, width)
        Any other polylines, width in pixels.
    points : sequence of (points (k, 3), colour, size)
        Markers (round sprites of ``size`` pixels).
    view : (elevation, azimuth)
        Degrees, as matplotlib's ``view_init``: the camera looks at the panel's bounding box from
        ``(cos e cos a, cos e sin a, sin e)``.
    title : str, optional
    frame : ndarray, shape (k, 3), optional
        Points the camera frames besides the content (panels given the same box compare at one
        scale).
    """

    grids: Sequence[Grid] = ()
    curves: Sequence[BSplineCurve | np.ndarray] = ()
    nets: Sequence[np.ndarray] = ()
    mesh_lines: Sequence[np.ndarray] = ()
    lines: Sequence[tuple[np.ndarray, RGB, float]] = ()
    points: Sequence[tuple[np.ndarray, RGB, float]] = ()
    view: tuple[float, float] = (28.0, -60.0)
    title: str | None = None
    frame: np.ndarray | None = None


def render_surfaces(
    path: str | Path,
    items: Sequence[BSplineSurface | tuple[np.ndarray, np.ndarray, np.ndarray]],
    *,
    color: str = "mean",
    title: str | None = None,
    subtitle: str | None = None,
    curves: Sequence[BSplineCurve | np.ndarray] = (),
    nets: Sequence[np.ndarray] = (),
    mesh_lines: Sequence[np.ndarray] = (),
    views: Sequence[tuple[float, float]] = ((28.0, -60.0),),
    resolution: int = 60,
    limits: tuple[float, float] | None = None,
    panel_titles: Sequence[str] | None = None,
    figsize: tuple[float, float] | None = None,
    dpi: int = 110,
) -> Path:
    """Write a PNG of surfaces, coloured by curvature and shaded by VTK, one panel per view.

    Parameters
    ----------
    path : path-like
        The PNG to write (parent folders must exist).
    items : sequence of BSplineSurface or (points (r, s, 3), normals (r, s, 3), scalar (r, s))
        Surfaces drawn together in every view; the tuple form accepts any sampled surface (e.g. the
        quad pieces of an S-patch, or data computed elsewhere).
    color : {"mean", "gaussian", "height", "none"}
        The scalar mapped to colour (diverging map, symmetric about 0 for curvatures; the limits
        are the 98th percentile of ``|value|`` over all items unless ``limits`` is given).
    curves, nets, mesh_lines
        As :class:`Panel`'s, in every view.
    views : sequence of (elevation, azimuth)
        One panel per view, side by side (see :class:`Panel`).
    panel_titles : sequence of str, optional
        One title per view.

    Returns
    -------
    Path
        ``path``.

    Raises
    ------
    ValueError
        An unknown ``color``; no view.
    InvalidGeometryError
        An item that is neither a surface nor points ``(r, s, 3)``, normals of their shape and
        values ``(r, s)``.
    RuntimeError
        VTK cannot render offscreen here (:func:`~.vtk_scene.render_available`).
    """
    if color not in COLORINGS:
        raise ValueError(f"color: expected one of {', '.join(COLORINGS)}, got {color!r}")
    if not views:
        raise ValueError("views: expected at least one (elevation, azimuth)")
    grids = _grids(items, resolution, color)
    lo, hi, norm, cmap = _colour_scale(grids, color, limits)
    grids = [(P, n, np.clip(val, lo, hi)) for P, n, val in grids]
    panels = [Panel(grids, curves, nets, mesh_lines, view=view,
                    title=None if panel_titles is None or k >= len(panel_titles) else panel_titles[k])
              for k, view in enumerate(views)]
    label = {"mean": "mean curvature H", "gaussian": "Gaussian curvature K", "height": "z", "none": None}[color]
    nv = len(views)
    return render_panels(path, panels, norm=norm, cmap=None if color == "none" else cmap, colorbar_label=label,
                         title=title, subtitle=subtitle, figsize=figsize or (6.4 * nv + (1.2 if label else 0), 6.0),
                         dpi=dpi)


def render_panels(path: str | Path, panels: Sequence[Panel], *, norm: Any = None, cmap: Any = None,
                  colorbar_label: str | None = None, title: str | None = None, subtitle: str | None = None,
                  ncols: int | None = None, figsize: tuple[float, float] | None = None, dpi: int = 110,
                  legend: Sequence[tuple[str, Any]] = (), legend_panel: int = 0) -> Path:
    """Write a PNG of panels, each rendered offscreen by VTK (:class:`~.vtk_scene.Scene`), laid
    out in a grid of ``ncols`` columns (default: one row) with their titles, one colour bar and
    the picture's title by matplotlib (2-D only).

    Parameters
    ----------
    path : path-like
        The PNG to write (parent folders must exist).
    panels : sequence of Panel
    norm, cmap : matplotlib ``Normalize`` and colour map, optional
        The grids' scalars to colour (every panel alike; NaN values in ``vtk_scene.NAN_COLOR``);
        without ``cmap`` the surfaces are grey, without ``norm`` the values' range is mapped.
    colorbar_label : str, optional
        Draw the colour bar of ``norm`` and ``cmap`` with this label.
    title, subtitle : str, optional
    figsize : (width, height), optional
        Inches; default 6.4 x 6.0 a panel (and the colour bar's strip).
    legend : sequence of (label, matplotlib artist), optional
        A legend in panel ``legend_panel`` (proxy artists: ``Line2D`` for a line or a marker).

    Returns
    -------
    Path
        ``path``.

    Raises
    ------
    ValueError
        No panel; ``legend_panel`` not a panel's index (negative counts from the end).
    InvalidGeometryError
        A grid is not points ``(r, s, 3)``, normals of their shape and values ``(r, s)``.
    RuntimeError
        VTK cannot render offscreen here (:func:`~.vtk_scene.render_available`).
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from .vtk_scene import render_available

    n = len(panels)
    if n == 0:
        raise ValueError("panels: expected at least one panel")
    if legend and not -n <= legend_panel < n:
        raise ValueError(f"legend_panel: expected a panel's index from {-n} to {n - 1}, got {legend_panel}")
    panels = [replace(p, grids=[_check_grid(g, f"panels[{k}].grids[{i}]") for i, g in enumerate(p.grids)])
              for k, p in enumerate(panels)]
    if cmap is not None and norm is None:  # the grids' finite values, min to max
        from matplotlib.colors import Normalize

        vals = np.concatenate([np.ravel(g[2]) for p in panels for g in p.grids] or [np.zeros(1)])
        vals = vals[np.isfinite(vals)]
        norm = Normalize(float(vals.min()), float(vals.max())) if vals.size else Normalize(0.0, 1.0)
    if not render_available():
        raise RuntimeError("VTK cannot render offscreen here: no surface picture")
    ncols = n if ncols is None else max(1, min(int(ncols), n))
    nrows = (n + ncols - 1) // ncols
    bar = colorbar_label is not None and cmap is not None
    width_in, height_in = figsize or (6.4 * ncols + (1.2 if bar else 0), 6.0 * nrows)
    top = 0.86 if nrows == 1 else max(0.5, 1.0 - 0.8 / height_in)
    size = (max(16, int(width_in * dpi * (0.9 if bar else 0.98) / ncols)),
            max(16, int(height_in * dpi * (top - 0.02) / nrows * 0.92)))
    fig = Figure(figsize=(width_in, height_in), dpi=dpi)
    FigureCanvasAgg(fig)
    for k, panel in enumerate(panels):
        ax = fig.add_subplot(nrows, ncols, k + 1)
        ax.imshow(_render_view(panel, norm, cmap, size), interpolation="antialiased")
        ax.set_axis_off()
        if panel.title:
            ax.set_title(panel.title, fontsize=10)
        if legend and k == legend_panel % n:
            ax.legend([h for _, h in legend], [s for s, _ in legend], loc="upper left", fontsize=8, framealpha=0.8)
    fig.subplots_adjust(left=0.01, right=0.9 if bar else 0.99, bottom=0.02, top=top, wspace=0.02, hspace=0.08)
    if bar:
        from matplotlib import cm

        fig.colorbar(cm.ScalarMappable(norm=norm, cmap=cmap), ax=fig.axes, shrink=0.6, pad=0.02, label=colorbar_label)
    if title:
        fig.suptitle(title if not subtitle else f"{title}\n{subtitle}", fontsize=12)
    path = Path(path)
    write_figure(fig, path)
    return path


# ---------------------------------------------------------------------------------------- steps
def _grids(items: Sequence[BSplineSurface | Grid], resolution: int, color: str) -> list[Grid]:
    """Points ``(r, s, 3)``, normals ``(r, s, 3)`` and colour scalar ``(r, s)`` of every item:
    surfaces sampled by :func:`surface_grid`, sampled tuples taken as float arrays."""
    grids = []
    for k, it in enumerate(items):
        if isinstance(it, BSplineSurface):
            grids.append(surface_grid(it, resolution, color))
        else:
            grids.append(_check_grid(it, f"items[{k}]"))
    return grids


def _check_grid(grid: Any, name: str) -> Grid:
    """A sampled surface as float arrays: points ``(r, s, 3)`` with ``r, s >= 2``, normals of the
    same shape, values ``(r, s)``."""
    from occsurf.algorithms.errors import InvalidGeometryError

    try:
        P, n, val = (np.asarray(a, float) for a in grid)
    except (TypeError, ValueError) as err:
        raise InvalidGeometryError(f"{name}: expected (points, normals, values) arrays ({err})") from err
    if P.ndim != 3 or P.shape[-1] != 3 or min(P.shape[:2]) < 2 or n.shape != P.shape or val.shape != P.shape[:2]:
        raise InvalidGeometryError(f"{name}: expected points (r, s, 3) with r, s >= 2, normals of their shape and "
                                   f"values (r, s); got {P.shape}, {n.shape} and {val.shape}")
    return P, n, val


def _colour_scale(grids: list[Grid], color: str, limits: tuple[float, float] | None) -> tuple[float, float, Any, Any]:
    """``(lo, hi, norm, cmap)``: the colour range over all items and its mapping.

    Curvatures: symmetric about 0 at the 98th percentile of ``|value|`` on a diverging map
    (``coolwarm``, centred on 0 when the range straddles it); height and none: min to max on
    ``viridis``. ``limits`` overrides the range.
    """
    from matplotlib import cm
    from matplotlib.colors import Normalize, TwoSlopeNorm

    allv = np.concatenate([g[2].ravel() for g in grids])
    allv = allv[np.isfinite(allv)]  # NaN values are drawn in vtk_scene.NAN_COLOR, not counted here
    if limits is not None:
        lo, hi = limits
    elif color in ("mean", "gaussian"):
        m = (float(np.percentile(np.abs(allv), 98)) if allv.size else 0.0) or 1.0
        lo, hi = -m, m
    else:
        lo, hi = (float(allv.min()), float(allv.max())) if allv.size else (0.0, 1.0)
        if hi <= lo:
            hi = lo + 1.0
    if color in ("mean", "gaussian"):
        norm: Any = TwoSlopeNorm(vcenter=0.0, vmin=lo, vmax=hi) if lo < 0 < hi else Normalize(lo, hi)
        cmap = cm.coolwarm
    else:
        norm, cmap = Normalize(lo, hi), cm.viridis
    return lo, hi, norm, cmap


def _triangles(r: int, s: int) -> np.ndarray:
    """Two triangles per cell of an ``r x s`` grid of points numbered row by row."""
    idx = np.arange(r * s).reshape(r, s)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    return np.concatenate([np.stack([a, b, c], axis=1), np.stack([a, c, d], axis=1)])


#: Vertices per mesh handed to the scene: a panel's grids are drawn in groups, one VTK actor per
#: group instead of one per grid (an S-patch panel has hundreds of patches: the generalized demo's
#: 16 views added 3860 meshes), each group small enough that its concatenated copy stays a few MB.
#: As for the report's pictures (``quality.pictures.MERGED_VERTICES``).
MERGED_VERTICES = 100_000


def _merged(meshes: Sequence[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]]
            ) -> list[tuple[Any, ...]]:
    """The meshes ``(points, triangles, normals, colours)`` in groups of at most
    :data:`MERGED_VERTICES` vertices (:func:`.vtk_scene.merged_meshes`)."""
    from .vtk_scene import merged_meshes

    return list(merged_meshes([m[0].shape[0] for m in meshes], meshes.__getitem__, MERGED_VERTICES))

def _render_view(panel: Panel, norm: Any, cmap: Any, size: tuple[int, int]) -> np.ndarray:
    """One panel as an image ``(height, width, 3)``: its grids coloured (grey without ``cmap``;
    VTK's lights shade them), control nets thin grey, control meshes thin green, its own lines,
    curves black on top, markers."""
    from .vtk_scene import NAN_COLOR, Scene

    scene = Scene()
    meshes = []
    for P, n, val in panel.grids:
        r, s = P.shape[:2]
        if cmap is None:
            rgb = np.broadcast_to(np.array([0.72, 0.74, 0.78]), (r * s, 3))
        else:
            v = np.asarray(val, float).reshape(-1)
            rgb = cmap(norm(np.where(np.isfinite(v), v, 0.0)))[:, :3]
            rgb[~np.isfinite(v)] = NAN_COLOR
        meshes.append((P.reshape(-1, 3), _triangles(r, s), n.reshape(-1, 3), rgb))
    for P, T, N, C in _merged(meshes):
        scene.add_mesh(P, T, normals=N, colors=C, specular=0.2)
    net_lines: list[np.ndarray] = []
    for net in panel.nets:
        net = np.asarray(net, float)
        net_lines += list(net) + list(net.transpose(1, 0, 2))
    scene.add_lines(net_lines, color=(0.25, 0.25, 0.25), width=1.0, opacity=0.6)
    scene.add_lines([np.asarray(m, float) for m in panel.mesh_lines], color=(0.16, 0.48, 0.16), width=1.5, opacity=0.85)
    styles: dict[tuple[RGB, float], list[np.ndarray]] = {}  # one VTK actor per colour and width
    for line, rgb_line, width in panel.lines:
        styles.setdefault((rgb_line, float(width)), []).append(np.asarray(line, float))
    for (rgb_line, width), polylines in styles.items():
        scene.add_lines(polylines, color=rgb_line, width=width)
    curves = [c.evaluate(np.linspace(*c.domain, 200)) if isinstance(c, BSplineCurve) else np.asarray(c, float)
              for c in panel.curves]
    scene.add_lines(curves, color=(0.0, 0.0, 0.0), width=2.5)
    for pts, rgb_pts, px in panel.points:
        scene.add_points(np.asarray(pts, float), color=rgb_pts, size=px)
    if panel.frame is not None:
        scene.frame(panel.frame)
    direction, up = _view_axes(*panel.view)
    return scene.render_array(size=size, camera=direction, up=up)


def _view_axes(elev: float, azim: float) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """matplotlib's ``view_init(elev, azim)`` as a camera: the direction from the target to the eye
    and the direction shown upwards, +z made square to the view (looking straight down or up,
    where that vanishes, the limit of it: ``-/+ (cos a, sin a, 0)``)."""
    e, a = np.radians(elev), np.radians(azim)
    d = np.array([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])
    up = np.array([0.0, 0.0, 1.0]) - d[2] * d
    if np.linalg.norm(up) < 1e-9:
        up = -np.sign(d[2]) * np.array([np.cos(a), np.sin(a), 0.0])
    up /= np.linalg.norm(up)
    return (float(d[0]), float(d[1]), float(d[2])), (float(up[0]), float(up[1]), float(up[2]))
