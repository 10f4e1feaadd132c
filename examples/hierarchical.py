"""Pictures and STEP files for hierarchical B-splines (course ch. 5, Forsey–Bartels).

:func:`render_hierarchical_demo` builds the course's showcase: a gently waved base with details at
three levels (a ridge at level 1, two bumps at level 2, small knobs at level 3), then bends the
*base* (a coarse edit of four base vertices). With offset referencing (§5-15) the details ride
along, keeping their height along the new normal; with plain additive offsets (for comparison)
the same details stay vertical and shear. It writes shaded PNGs (colour = detail height above the
base surface, along its normal) and the edited surface as STEP with its editable hierarchy in a
JSON sidecar (:mod:`occsurf.bridge.exchange.hierarchical_io`).

The surfaces are shaded by VTK offscreen (:func:`occsurf.bridge.rendering.surfaces.render_panels`);
matplotlib lays the panels out and draws the section profiles (2-D) on the Agg canvas.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from occsurf.algorithms import BSplineSurface
from occsurf.algorithms.hierarchical.surface import HierarchicalSurface
from occsurf.bridge.exchange.files import write_figure

from ._common import output_folder, script

#: A panel's data: the points (m, m, 3), their unit normals and the detail height above the base.
PanelData = tuple[np.ndarray, np.ndarray, np.ndarray]

__all__ = ["render_hierarchical_demo", "demo_hierarchy"]

RESOLUTION = 101
#: Parameter window ``[lo, hi]^2`` of the level-by-level pictures: the overlays' region, so the
#: level-3 knobs are large enough to see.
LEVELS_WINDOW = (0.22, 0.78)


def demo_base() -> BSplineSurface:
    """A bicubic 8 x 8 patch over [0, 7]^2, slightly waved."""
    g = np.linspace(0.0, 7.0, 8)
    X, Y = np.meshgrid(g, g, indexing="ij")
    Z = 0.25 * np.sin(X / 2.0) * np.cos(Y / 3.0)
    t = np.r_[[0.0] * 4, np.linspace(0, 1, 6)[1:-1], [1.0] * 4]
    return BSplineSurface((3, 3), (t, t), np.stack([X, Y, Z], -1))


def demo_hierarchy(offsets: str = "frame") -> HierarchicalSurface:
    """The showcase hierarchy: features at levels 1, 2 and 3 (offsets along the normal)."""
    hs = HierarchicalSurface(demo_base(), offsets)
    o1 = hs.add_overlay((0.2, 0.8), (0.2, 0.8))
    o2 = hs.add_overlay((0.3, 0.7), (0.3, 0.7), o1)
    o3 = hs.add_overlay((0.4, 0.6), (0.3, 0.45), o2)
    # Level 1: a ridge along u (normal offsets on two rows of vertices, lower at the ends).
    off1 = np.zeros(o1.shape + (3,))
    c = o1.shape[1] // 2
    ends = np.r_[0.3, np.ones(o1.shape[0] - 2), 0.3]
    off1[:, c, 2] = 0.8 * ends
    off1[:, c - 1, 2] = 0.3 * ends
    off1[:, c + 1, 2] = 0.3 * ends
    hs.set_offsets(o1, off1)
    # Level 2: a bump on one side of the ridge, a dimple on the other.
    off2 = np.zeros(o2.shape + (3,))
    for (i, j), h in (((o2.shape[0] // 2 - 3, 2), 0.8), ((o2.shape[0] // 2 + 3, o2.shape[1] - 3), -0.6)):
        off2[i - 1:i + 2, j - 1:j + 2, 2] = 0.5 * h
        off2[i, j, 2] = h
    hs.set_offsets(o2, off2)
    # Level 3: a row of small knobs and dimples in front of the bump.
    off3 = np.zeros(o3.shape + (3,))
    j = o3.shape[1] // 2
    for k, i in enumerate(range(2, o3.shape[0] - 2, 2)):
        off3[i, j, 2] = 0.3 if k % 2 == 0 else -0.25
    hs.set_offsets(o3, off3)
    return hs


#: Radius of the cylinder the base is rolled onto by the coarse edit.
BEND_RADIUS = 3.2


def bent_base(base: BSplineSurface) -> BSplineSurface:
    """The coarse edit: every base pole rolled onto a cylinder of radius :data:`BEND_RADIUS`
    about an axis parallel to x (the sheet curls up towards y = 7; the detail region ends up on
    a flank tilted by about 50 degrees)."""
    P = np.array(base.control_points)
    th = (P[..., 1] - 0.8) / BEND_RADIUS
    th = np.where(th > 0, th, 0.0)
    y = np.where(P[..., 1] > 0.8, 0.8 + BEND_RADIUS * np.sin(th), P[..., 1])
    z = P[..., 2] + BEND_RADIUS * (1.0 - np.cos(th))
    # the small waves of the base ride along the roll (their z offset taken along the cylinder normal)
    y = y - P[..., 2] * np.sin(th)
    z = z - P[..., 2] + P[..., 2] * np.cos(th)
    return BSplineSurface(base.degree, base.knots, np.stack([P[..., 0], y, z], -1), base.weights)


def coarse_edit(hs: HierarchicalSurface) -> None:
    """Bend the base (all 64 base poles, :func:`bent_base`), in place: overlays keep their offsets."""
    hs.set_base(bent_base(hs.base))


def _sample(hs: HierarchicalSurface, lo: float = 0.0, hi: float = 1.0, res: int = RESOLUTION
            ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Points, normals and detail height (above the base, along its normal) on a grid of
    ``[lo, hi]^2``."""
    us = np.linspace(lo, hi, res)
    P = hs.evaluate_grid(us, us)
    n = hs.normal_grid(us, us)
    base = hs.base
    nb = base.normal(*np.meshgrid(us, us, indexing="ij"))
    h = np.einsum("...i,...i->...", P - base.evaluate_grid(us, us), nb)
    return P, n, h  # NaN normals (a degenerate point) are mended by the scene, from the mesh


def _render(path: Path, panels: list[tuple[PanelData, str]], suptitle: str, view: tuple[float, float] = (30, -62),
            ncols: int = 3) -> None:
    """Panels coloured by the detail height (one diverging scale) and shaded by VTK, all framed
    on the box of every panel's points (:func:`~occsurf.bridge.rendering.surfaces.render_panels`)."""
    from matplotlib import cm
    from matplotlib.colors import TwoSlopeNorm

    from occsurf.bridge.rendering.surfaces import Panel, render_panels

    m = max(float(np.abs(d[2]).max()) for d, _ in panels) or 1.0
    norm = TwoSlopeNorm(vcenter=0.0, vmin=-m, vmax=m)
    pts = np.concatenate([d[0].reshape(-1, 3) for d, _ in panels])
    box = np.array([pts.min(0), pts.max(0)])
    nrows = (len(panels) + ncols - 1) // ncols
    render_panels(path, [Panel([data], view=view, title=title, frame=box) for data, title in panels], norm=norm,
                  cmap=cm.RdYlBu_r, colorbar_label="detail height above the base (along its normal)", title=suptitle,
                  ncols=ncols, figsize=(6.2 * ncols + 1.0, 5.6 * nrows), dpi=100)


def render_hierarchical_demo(out_dir: Path) -> list[Path]:
    """Render the hierarchical-surface demo into ``out_dir`` (created if missing).

    Returns
    -------
    list of Path
        ``hierarchical_levels.png`` (the surface level by level: base, + level 1, + level 2, all
        three), ``hierarchical_coarse_edit.png`` (before the coarse edit; after it with offset
        referencing; after it with additive offsets), ``hierarchical_profiles.png`` (sections
        across the details before and after the edit, equal axes), ``hierarchical.step`` (the edited surface, flattened) and
        ``hierarchical.hierarchy.json`` (its editable hierarchy).
    """
    from occsurf.bridge.exchange.hierarchical_io import write_hierarchical_step

    out = output_folder(out_dir)
    hs = demo_hierarchy("frame")
    o1, o2, o3 = hs.overlays
    # 1. The levels: each picture adds one level of detail.
    stages = []
    for keep, title in ((0, "base (level 0)"), (1, "+ level 1: a ridge"), (2, "+ level 2: two bumps"),
                        (3, "+ level 3: knobs and dimples")):
        h = hs.copy()
        for o in hs.overlays[keep:]:
            h.set_offsets(o, np.zeros(o.shape + (3,)))
        stages.append((_sample(h, *LEVELS_WINDOW), title))
    levels_png = out / "hierarchical_levels.png"
    _render(levels_png, stages, "Hierarchical B-spline surface: details at three levels of overlays "
            "(course §5-10, Forsey & Bartels 1988)\nclose-up of the detail region, "
            f"u, v in [{LEVELS_WINDOW[0]:g}, {LEVELS_WINDOW[1]:g}]", view=(38, -62), ncols=2)
    # 2. A coarse edit: the base is bent; offset referencing vs additive offsets.
    before = _sample(hs)
    add = demo_hierarchy("additive")
    coarse_edit(hs)
    coarse_edit(add)
    after, after_add = _sample(hs), _sample(add)
    edit_png = out / "hierarchical_coarse_edit.png"
    counts = hs.pole_counts()
    _render(edit_png, [(before, "before: details at levels 1-3"),
                       (after, "base bent — offset referencing (§5-15):\ndetails follow, normal to the new surface"),
                       (after_add, "base bent — additive offsets:\ndetails stay vertical and shear")],
            f"A coarse edit (base rolled onto a cylinder) carries the details along  "
            f"(stored: {counts['base']} base poles + {counts['offsets']} offsets; flat form: {counts['flat']} poles)",
            view=(24, -28))
    close_png = out / "hierarchical_profiles.png"
    u_bump = float(o2.reference_parameters[0][o2.shape[0] // 2 - 3])
    _render_profiles(close_png, demo_hierarchy("frame"), hs, add, [0.5, u_bump])
    step, side = write_hierarchical_step(out / "hierarchical.step", hs, name="hierarchical surface, base bent")
    return [levels_png, edit_png, close_png, step, side]


def _render_profiles(path: Path, before: HierarchicalSurface, after: HierarchicalSurface,
                     after_add: HierarchicalSurface, u_values: list[float]) -> None:
    """Cross-sections ``S(u, v)``, v in [0, 1], drawn in the (y, z) plane with equal axes."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    vs = np.linspace(0.0, 1.0, 600)
    fig = Figure(figsize=(7.0 * len(u_values), 6.6), dpi=100)
    FigureCanvasAgg(fig)
    for k, u in enumerate(u_values):
        ax = fig.add_subplot(1, len(u_values), k + 1)
        uu = np.full_like(vs, u)
        curves: list[tuple[HierarchicalSurface, dict[str, Any], str]] = [
            (before, dict(color="0.45", lw=1.6), "before the edit"),
            (after, dict(color="#1f5fbf", lw=2.2), "after, offset referencing"),
            (after_add, dict(color="#e07b00", lw=1.8, ls="--"), "after, additive offsets")]
        for hs, style, label in curves:
            P = hs.evaluate(uu, vs)
            ax.plot(P[:, 1], P[:, 2], label=label, **style)
        Bb, Ba = before.base.evaluate(uu, vs), after.base.evaluate(uu, vs)
        ax.plot(Bb[:, 1], Bb[:, 2], color="0.45", lw=0.8, ls=":", label="base surfaces (level 0)")
        ax.plot(Ba[:, 1], Ba[:, 2], color="0.45", lw=0.8, ls=":")
        ax.set_aspect("equal")
        ax.set_xlabel("y")
        ax.set_ylabel("z")
        ax.grid(alpha=0.3)
        ax.set_title(f"section u = {u:.3g} (x = {7 * u:.2f})", fontsize=11)
        ax.legend(loc="upper left", fontsize=9)
    fig.suptitle("Sections across the ridge (level 1), bump and dimple (level 2), knobs (level 3): with offset "
                 "referencing\nthe details stand on the bent surface as they stood on the flat one; additive "
                 "offsets keep them vertical", fontsize=12)
    fig.tight_layout(rect=(0, 0, 1, 0.92))
    write_figure(fig, path)


if __name__ == "__main__":  # pragma: no cover - manual use
    script(render_hierarchical_demo)
