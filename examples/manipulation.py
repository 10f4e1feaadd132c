"""Pictures and a STEP file for constraint-based manipulation (course ch. 4).

:func:`render_manipulation_demo` edits a planar cubic by a point drag, a tangent and a curvature
constraint (Bartels & Beatty 1989; Fowler & Bartels 1993), drags a point of a bicubic surface
with its tangent plane, draws before/after PNGs (curvature combs on the curves, shaded and
wireframe surfaces), and writes the edited curve and surface to STEP through
:func:`occsurf.bridge.exchange.step_iges.write_step`.

matplotlib is imported here, in the examples, never in ``occsurf.algorithms``; the figures use the
object-oriented API with the Agg canvas (no pyplot state, no display needed).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from occsurf.algorithms import (
    BSplineCurve,
    BSplineSurface,
    Curvature,
    Position,
    Tangent,
    constrain,
    drag_point,
    drag_surface_point,
)
from occsurf.bridge.exchange.files import write_figure

from ._common import output_folder, script

if TYPE_CHECKING:
    from matplotlib.axes import Axes

__all__ = ["render_manipulation_demo", "demo_curve", "demo_surface"]

BEFORE = "#9a9a9a"
AFTER = "#1f5fbf"
TARGET = "#d62728"
COMB = "#2ca02c"
#: Radius of curvature asked for in the third curve edit.
RADIUS = 0.8


# ------------------------------------------------------------------------------------- geometry
def demo_curve() -> BSplineCurve:
    """A planar clamped cubic with 10 poles (in the plane z = 0 so that it can go to STEP)."""
    x = np.linspace(0.0, 9.0, 10)
    y = np.array([0.0, 1.2, 2.0, 1.1, 0.2, 0.4, 1.5, 1.9, 1.0, 0.0])
    t = np.r_[[0.0] * 4, np.linspace(0, 1, 8)[1:-1], [1.0] * 4]
    return BSplineCurve(3, t, np.c_[x, y, np.zeros(10)])


def demo_surface() -> BSplineSurface:
    """A gently waved bicubic patch on 7 x 7 poles over [0, 6]^2."""
    g = np.linspace(0.0, 6.0, 7)
    X, Y = np.meshgrid(g, g, indexing="ij")
    Z = 0.4 * np.sin(X / 2.0) * np.cos(Y / 2.5)
    t = np.r_[[0.0] * 4, [1 / 4, 2 / 4, 3 / 4], [1.0] * 4]
    return BSplineSurface((3, 3), (t, t), np.stack([X, Y, Z], -1))


def _curvature_vectors(c: BSplineCurve, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    D = c.derivatives(u, 2)
    a, b = D[:, 1], D[:, 2]
    s = np.einsum("ij,ij->i", a, a)
    kappa = b / s[:, None] - (np.einsum("ij,ij->i", a, b) / s**2)[:, None] * a
    return D[:, 0], kappa


def _comb(ax: Axes, c: BSplineCurve, color: str, scale: float, alpha: float = 1.0, label: str | None = None) -> None:
    """Curvature comb: hairs along ``-kappa`` (outside the bend), length ``scale * |kappa|``."""
    u = np.linspace(*c.domain, 161)
    P, k = _curvature_vectors(c, u)
    tips = P - scale * k
    segs = np.stack([P[:, :2], tips[:, :2]], 1)
    from matplotlib.collections import LineCollection

    ax.add_collection(LineCollection(list(segs), colors=color, linewidths=0.6, alpha=0.6 * alpha))
    ax.plot(tips[:, 0], tips[:, 1], color=color, lw=0.9, alpha=alpha, label=label)


def _curve_panel(ax: Axes, before: BSplineCurve, after: BSplineCurve, title: str, comb_scale: float) -> None:
    u = np.linspace(*before.domain, 400)
    pb, pa = before.evaluate(u), after.evaluate(u)
    _comb(ax, before, BEFORE, comb_scale, alpha=0.5)
    _comb(ax, after, COMB, comb_scale, label="curvature comb (after)")
    ax.plot(*before.control_points[:, :2].T, "o--", color=BEFORE, lw=0.8, ms=3, label="control polygon (before)")
    ax.plot(*after.control_points[:, :2].T, "o--", color=AFTER, lw=0.8, ms=3, alpha=0.7,
            label="control polygon (after)")
    ax.plot(pb[:, 0], pb[:, 1], color=BEFORE, lw=2.0, label="curve before")
    ax.plot(pa[:, 0], pa[:, 1], color=AFTER, lw=2.2, label="curve after")
    ax.set_title(title, fontsize=11)
    ax.set_aspect("equal")
    ax.grid(alpha=0.25)


def _render_curves(path: Path) -> tuple[BSplineCurve, dict[str, float]]:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    c0 = demo_curve()
    # 1. Single constraint system (course §4-8): drag the point at u = 0.3 up, poles 1..6 movable.
    u1 = 0.3
    p1 = c0.evaluate(u1) + np.array([0.3, 1.6, 0.0])
    c1 = drag_point(c0, u1, p1, 1, 6)
    # 2. Double constraint system (§4-9): keep the point at u = 0.62, turn its tangent upwards.
    u2 = 0.62
    q2 = c1.evaluate(u2)
    t2 = np.array([6.0, 9.0, 0.0])
    c2 = constrain(c1, [Position(u2, q2), Tangent(u2, t2)])
    # 3. Triple system with curvature (§4-11, §4-12): at u = 0.86 keep the point and the tangent
    #    and bend to radius R (it was 2.5 there).
    u3, radius = 0.86, RADIUS
    d3 = c2.derivatives(u3, 1)
    c3 = constrain(c2, [Position(u3, d3[0]), Tangent(u3, d3[1]), Curvature(u3, radius)])
    fig = Figure(figsize=(16, 5.6), dpi=110)
    FigureCanvasAgg(fig)
    axes = fig.subplots(1, 3)
    scale = 0.8
    _curve_panel(axes[0], c0, c1, f"1. Position: drag C({u1}) (poles 1..6 movable)", scale)
    axes[0].plot(*c0.evaluate(u1)[:2], "s", color=BEFORE, ms=8, label=f"C({u1}) before")
    axes[0].plot(*p1[:2], "*", color=TARGET, ms=15, label="target")
    axes[0].annotate("", p1[:2], c0.evaluate(u1)[:2], arrowprops=dict(arrowstyle="->", color=TARGET, lw=1.5))
    _curve_panel(axes[1], c1, c2, f"2. Tangent at u={u2} (point kept)", scale)
    axes[1].plot(*q2[:2], "*", color=TARGET, ms=15, label="point kept")
    e = t2 / np.linalg.norm(t2) * 1.5
    axes[1].annotate("", (q2 + e)[:2], q2[:2], arrowprops=dict(arrowstyle="-|>", color=TARGET, lw=2),
                     annotation_clip=False)
    axes[1].plot([], [], color=TARGET, lw=2, label="tangent wanted")
    _curve_panel(axes[2], c2, c3, f"3. Curvature: radius {radius} at u={u3} (point, tangent kept)", scale)
    P, k = _curvature_vectors(c3, np.array([u3]))
    centre = P[0] + k[0] / np.dot(k[0], k[0])
    th = np.linspace(0, 2 * np.pi, 200)
    axes[2].plot(centre[0] + radius * np.cos(th), centre[1] + radius * np.sin(th), ":", color=TARGET, lw=1.5,
                 label=f"osculating circle, r = {radius}")
    axes[2].plot(*P[0, :2], "*", color=TARGET, ms=15, label="point and tangent kept")
    for ax in axes:
        ax.legend(loc="lower center", fontsize=7.5, ncol=2, framealpha=0.9)
        ax.set_ylim(-3.4, 5.2)
        ax.set_xlabel("x")
    axes[0].set_ylabel("y")
    fig.suptitle("Constraint-based curve manipulation: minimum-norm change of the control points "
                 "(course ch. 4; Bartels & Beatty 1989, Fowler & Bartels 1993)", fontsize=12)
    fig.tight_layout(rect=(0, 0, 1, 0.95))
    write_figure(fig, path)
    dk = _curvature_vectors(c3, np.array([u3]))[1][0]
    info = {"point error": float(np.abs(c1.evaluate(u1) - p1).max()),
            "radius": float(1 / np.linalg.norm(dk))}
    return c3, info


def _render_surface(path: Path) -> BSplineSurface:
    """The surface before and after :func:`drag_surface_point`, coloured by height and shaded by
    VTK (:func:`~occsurf.bridge.rendering.surfaces.render_panels`), with the control nets, the
    point before, the target and the normal asked for; returns the dragged surface."""
    from matplotlib import cm
    from matplotlib.colors import Normalize, to_rgb
    from matplotlib.lines import Line2D

    from occsurf.bridge.rendering.surfaces import Panel, render_panels

    s0 = demo_surface()
    u, v = 0.5, 0.45
    p0 = s0.evaluate(u, v)
    target = p0 + np.array([0.0, 0.0, 1.8])
    normal = np.array([-0.5, 0.3, 1.0])
    s1 = drag_surface_point(s0, u, v, target, normal=normal, window=((1, 5), (1, 5)))
    us = np.linspace(0, 1, 41)
    U, V = np.meshgrid(us, us, indexing="ij")
    G0, G1 = s0.evaluate_grid(us, us), s1.evaluate_grid(us, us)
    zlim = (min(G0[..., 2].min(), G1[..., 2].min()) - 0.2, max(G0[..., 2].max(), G1[..., 2].max()) + 0.3)
    tip = target + 1.2 * s1.normal(u, v)
    target_rgb, before_rgb = to_rgb(TARGET), to_rgb(BEFORE)
    wire = [G0[i] for i in range(0, 41, 4)] + [G0[:, j] for j in range(0, 41, 4)]
    box = np.concatenate([G0.reshape(-1, 3), G1.reshape(-1, 3), tip[None]])
    panels = []
    for s, G, title in ((s0, G0, "before"), (s1, G1, "after: point dragged up 1.8, normal tilted")):
        grid = (G, s.normal(U, V), G[..., 2])
        marks = [(s.control_points.reshape(-1, 3), (0.1, 0.1, 0.1), 5.0), (p0[None], (1.0, 1.0, 1.0), 12.0),
                 (target[None], target_rgb, 16.0)]
        lines: list[tuple[np.ndarray, tuple[float, float, float], float]] = []
        if s is s1:
            lines = [(w, before_rgb, 1.0) for w in wire] + [(np.stack([target, tip]), target_rgb, 4.0)]
            marks.append((tip[None], target_rgb, 10.0))
        panels.append(Panel([grid], nets=[s.control_points], lines=lines, points=marks, view=(28.0, -60.0),
                            title=f"Surface {title}", frame=box))
    legend = [("control net", Line2D([], [], color="0.25", marker="o", markersize=3, lw=0.8)),
              ("surface before (wireframe)", Line2D([], [], color=BEFORE, lw=1)),
              ("normal wanted (reached)", Line2D([], [], color=TARGET, lw=2.5)),
              (f"S({u}, {v}) before (seen on the left)", Line2D([], [], color="w", marker="o", markeredgecolor="k", lw=0)),
              ("target", Line2D([], [], color=TARGET, marker="o", markersize=8, lw=0))]
    render_panels(path, panels, norm=Normalize(*zlim), cmap=cm.viridis, colorbar_label="z", legend=legend,
                  legend_panel=1, title="drag_surface_point: minimum-norm change of the poles in the window (1..5) x "
                  "(1..5) (course ch. 4 applied to a tensor-product surface)", figsize=(15.0, 6.4))
    return s1


def render_manipulation_demo(out_dir: Path) -> list[Path]:
    """Render the manipulation demo: two PNGs and one STEP file in ``out_dir``.

    Parameters
    ----------
    out_dir : Path
        Created if missing.

    Returns
    -------
    list of Path
        ``manipulation_curve.png`` (position, tangent and curvature edits with curvature combs),
        ``manipulation_surface.png`` (shaded before/after of a surface point drag with its tangent
        plane) and ``manipulation.step`` (the edited curve and surface, named).
    """
    out = output_folder(out_dir)
    curve_png = out / "manipulation_curve.png"
    surface_png = out / "manipulation_surface.png"
    step = out / "manipulation.step"
    curve, _ = _render_curves(curve_png)
    surface = _render_surface(surface_png)
    from occsurf.bridge.exchange.step_iges import write_step

    write_step(step, [curve, surface], names=["edited curve (position, tangent, curvature)",
                                              "surface with a dragged point"])
    return [curve_png, surface_png, step]


if __name__ == "__main__":  # pragma: no cover - manual use
    script(render_manipulation_demo)
