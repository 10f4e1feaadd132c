"""Shaded pictures of surfaces for ``occsurf demo``: curvature colouring with Lambert shading.

Course ch. 9 (quality assessment: colour-coded curvature, §9-8 graphical representation) and
ch. 10 (a directional light). Pure matplotlib on the Agg canvas (no display needed); lives in
``occsurf.bridge`` (the gallery in ``occsurf.examples`` uses it), not in ``occsurf.algorithms``.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from occsurf.algorithms import BSplineCurve, BSplineSurface
from occsurf.algorithms.geometry.differential import surface_curvatures

from ..exchange.files import write_figure

__all__ = ["render_surfaces", "surface_grid"]

COLORINGS = ("mean", "gaussian", "height", "none")
_LIGHT = np.array([-0.45, -0.35, 0.82]) / np.linalg.norm([-0.45, -0.35, 0.82])


def surface_grid(surface: BSplineSurface, resolution: int = 60, color: str = "mean") -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Points ``(r, r, 3)``, unit normals ``(r, r, 3)`` and the colour scalar ``(r, r)`` of a surface.

    The scalar is the mean or Gaussian curvature (course §6-12), the height z, or zeros.
    Degenerate points (NaN curvature, e.g. a sphere's pole) take the value of their neighbours'
    median so they do not blot the picture.
    """
    from occsurf.algorithms._validate import check_count
    from occsurf.algorithms.quality._common import check_grid

    r = check_count(resolution, "resolution", 1, minimum=2)
    check_grid(r, r, "resolution")  # the grid, its curvatures and the mesh, refused before any of them exists
    (u0, u1), (v0, v1) = surface.domain
    # pull the samples a hair inside so poles of revolved surfaces do not give NaN normals
    eu, ev = 1e-6 * (u1 - u0), 1e-6 * (v1 - v0)
    us = np.linspace(u0 + eu, u1 - eu, resolution)
    vs = np.linspace(v0 + ev, v1 - ev, resolution)
    U, W = np.meshgrid(us, vs, indexing="ij")
    P = surface.evaluate_grid(us, vs)
    sc = surface_curvatures(surface, U, W)
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


def render_surfaces(
    path: str | Path,
    items: Sequence[BSplineSurface | tuple[np.ndarray, np.ndarray, np.ndarray]],
    *,
    color: str = "mean",
    title: str | None = None,
    subtitle: str | None = None,
    curves: Sequence[BSplineCurve | np.ndarray] = (),
    nets: Sequence[np.ndarray] = (),
    views: Sequence[tuple[float, float]] = ((28.0, -60.0),),
    resolution: int = 60,
    limits: tuple[float, float] | None = None,
    panel_titles: Sequence[str] | None = None,
    figsize: tuple[float, float] | None = None,
    dpi: int = 110,
) -> Path:
    """Write a PNG of surfaces, shaded by a light and coloured by curvature.

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
    curves : sequence of BSplineCurve or (m, 3) arrays
        Drawn as black lines on top (input curves of a curve net, boundaries).
    nets : sequence of (nu, nv, 3) arrays
        Control nets drawn as thin grey lines.
    views : sequence of (elevation, azimuth)
        One panel per view, side by side.
    panel_titles : sequence of str, optional
        One title per view.

    Returns
    -------
    Path
        ``path``.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    if color not in COLORINGS:
        raise ValueError(f"color: expected one of {', '.join(COLORINGS)}, got {color!r}")
    grids = _grids(items, resolution, color)
    lo, hi, norm, cmap = _colour_scale(grids, color, limits)
    centre, half = _bounding_cube(grids)
    nv = len(views)
    fig = Figure(figsize=figsize or (6.4 * nv + (1.2 if color != "none" else 0), 6.0), dpi=dpi)
    FigureCanvasAgg(fig)
    for k, (elev, azim) in enumerate(views):
        ax = fig.add_subplot(1, nv, k + 1, projection="3d")
        ax.computed_zorder = False
        for P, n, val in grids:
            rgb = _shaded_colours(P, n, val, color, lo, hi, norm, cmap)
            ax.plot_surface(P[..., 0], P[..., 1], P[..., 2], facecolors=rgb, rstride=1, cstride=1,
                            linewidth=0, antialiased=False, shade=False)
        _draw_lines(ax, nets, curves)
        _frame_view(ax, centre, half, elev, azim, None if panel_titles is None or k >= len(panel_titles)
                    else panel_titles[k])
    _annotate(fig, color, norm, cmap, title, subtitle)
    path = Path(path)
    write_figure(fig, path)
    return path


# ---------------------------------------------------------------------------------------- steps
Grid = tuple[np.ndarray, np.ndarray, np.ndarray]


def _grids(items: Sequence[BSplineSurface | Grid], resolution: int, color: str) -> list[Grid]:
    """Points ``(r, s, 3)``, normals ``(r, s, 3)`` and colour scalar ``(r, s)`` of every item:
    surfaces sampled by :func:`surface_grid`, sampled tuples taken as float arrays."""
    grids = []
    for it in items:
        if isinstance(it, BSplineSurface):
            grids.append(surface_grid(it, resolution, color))
        else:
            P, n, val = (np.asarray(a, float) for a in it)
            grids.append((P, n, val))
    return grids


def _colour_scale(grids: list[Grid], color: str, limits: tuple[float, float] | None) -> tuple[float, float, Any, Any]:
    """``(lo, hi, norm, cmap)``: the colour range over all items and its mapping.

    Curvatures: symmetric about 0 at the 98th percentile of ``|value|`` on a diverging map
    (``coolwarm``, centred on 0 when the range straddles it); height and none: min to max on
    ``viridis``. ``limits`` overrides the range.
    """
    from matplotlib import cm
    from matplotlib.colors import Normalize, TwoSlopeNorm

    allv = np.concatenate([g[2].ravel() for g in grids])
    if limits is not None:
        lo, hi = limits
    elif color in ("mean", "gaussian"):
        m = float(np.percentile(np.abs(allv), 98)) or 1.0
        lo, hi = -m, m
    else:
        lo, hi = float(allv.min()), float(allv.max())
        if hi <= lo:
            hi = lo + 1.0
    if color in ("mean", "gaussian"):
        norm: Any = TwoSlopeNorm(vcenter=0.0, vmin=lo, vmax=hi) if lo < 0 < hi else Normalize(lo, hi)
        cmap = cm.coolwarm
    else:
        norm, cmap = Normalize(lo, hi), cm.viridis
    return lo, hi, norm, cmap


def _bounding_cube(grids: list[Grid]) -> tuple[np.ndarray, float]:
    """Centre ``(3,)`` and half side of the cube around every sampled point (equal axes)."""
    pts = np.concatenate([g[0].reshape(-1, 3) for g in grids])
    lo3, hi3 = pts.min(axis=0), pts.max(axis=0)
    return (lo3 + hi3) / 2, max(float((hi3 - lo3).max()) / 2, 1e-12)


def _shaded_colours(P: np.ndarray, n: np.ndarray, val: np.ndarray, color: str, lo: float, hi: float,
                    norm: Any, cmap: Any) -> np.ndarray:
    """RGBA face colours ``(r, s, 4)``: the scalar's colour (grey for ``'none'``) darkened by a
    two-sided Lambert term ``0.35 + 0.65 |n . light|`` (course ch. 10, a directional light)."""
    base = np.full(P.shape[:2] + (4,), (0.72, 0.74, 0.78, 1.0)) if color == "none" else cmap(norm(np.clip(val, lo, hi)))
    lam = np.abs(np.einsum("...i,i->...", n, _LIGHT))  # two-sided Lambert
    shade = 0.35 + 0.65 * lam
    rgb = base.copy()
    rgb[..., :3] *= shade[..., None]
    return rgb


def _draw_lines(ax: Any, nets: Sequence[np.ndarray], curves: Sequence[BSplineCurve | np.ndarray]) -> None:
    """Control nets as thin grey polylines (rows, then columns), then curves in black on top."""
    for net in nets:
        net = np.asarray(net, float)
        for row in net:
            ax.plot(*row.T, color="0.25", lw=0.5, alpha=0.6)
        for col in net.transpose(1, 0, 2):
            ax.plot(*col.T, color="0.25", lw=0.5, alpha=0.6)
    for c in curves:
        if isinstance(c, BSplineCurve):
            c = c.evaluate(np.linspace(*c.domain, 200))
        ax.plot(*np.asarray(c, float).T, color="k", lw=1.6)


def _frame_view(ax: Any, centre: np.ndarray, half: float, elev: float, azim: float, title: str | None) -> None:
    """Equal axes on the bounding cube, the camera, axis labels and the panel's title."""
    ax.set_xlim(centre[0] - half, centre[0] + half)
    ax.set_ylim(centre[1] - half, centre[1] + half)
    ax.set_zlim(centre[2] - half, centre[2] + half)
    ax.set_box_aspect((1, 1, 1))
    ax.view_init(elev=elev, azim=azim)
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    ax.set_zlabel("z")
    if title is not None:
        ax.set_title(title, fontsize=10)


def _annotate(fig: Any, color: str, norm: Any, cmap: Any, title: str | None, subtitle: str | None) -> None:
    """The colour bar (unless ``color == 'none'``) and the figure's title with its subtitle."""
    from matplotlib import cm

    if color != "none":
        sm = cm.ScalarMappable(norm=norm, cmap=cmap)
        label = {"mean": "mean curvature H", "gaussian": "Gaussian curvature K", "height": "z"}[color]
        fig.colorbar(sm, ax=fig.axes, shrink=0.6, pad=0.02, label=label)
    if title:
        fig.suptitle(title if not subtitle else f"{title}\n{subtitle}", fontsize=12)
