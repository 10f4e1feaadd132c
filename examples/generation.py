"""Pictures and STEP files for surface generation (course §6-26 .. §6-33, "Sweeping").

:func:`render_generation_demo` builds one surface per construction of
:mod:`occsurf.algorithms.construction.generation` and :mod:`occsurf.algorithms.construction.sweeping` — extrusion, ruled surface, full and
partial revolution, translational sweep, rotational (swung) sweep and a generalised sweep with
twist and scaling laws — and writes, for each, a STEP file (through
:func:`occsurf.bridge.exchange.step_iges.write_step`) and a PNG (shaded, coloured by mean curvature, with the input
curves in black) through :func:`occsurf.bridge.rendering.surfaces.render_surfaces`.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from occsurf.algorithms import BSplineCurve, BSplineSurface, circle, ellipse
from occsurf.algorithms.construction.generation import extrude, revolve, rotational_sweep, ruled, translational_sweep
from occsurf.algorithms.construction.sweeping import sweep
from occsurf.algorithms.fitting.interpolation import interpolate_curve

from ._common import output_folder, script

__all__ = ["render_generation_demo", "demo_surfaces"]


def _vase_profile() -> BSplineCurve:
    """A rational cubic profile in the xz half-plane (a vase outline)."""
    P = np.array([[1.0, 0, 0], [2.2, 0, 0.8], [0.8, 0, 2.0], [0.7, 0, 3.0], [1.6, 0, 4.0], [1.2, 0, 4.6]])
    t = np.r_[[0.0] * 4, [1 / 3, 2 / 3], [1.0] * 4]
    return BSplineCurve(3, t, P, np.array([1, 1.5, 1, 1, 2, 1]))


def _wave(y: float, z: float, amp: float) -> BSplineCurve:
    x = np.linspace(0, 6, 7)
    return interpolate_curve(np.c_[x, y + amp * np.sin(x), z + 0.4 * np.cos(1.3 * x)])


def demo_surfaces() -> dict[str, tuple[BSplineSurface, list[BSplineCurve], str]]:
    """name -> (surface, input curves, caption)."""
    out: dict[str, tuple[BSplineSurface, list[BSplineCurve], str]] = {}
    c = _wave(0, 0, 0.6)
    out["extrude"] = (extrude(c, [0.5, 1.0, 3.0]), [c],
                      "extrude(curve, d): S(u, v) = C(u) + v d")
    c1, c2 = _wave(0, 0, 0.8), BSplineCurve(2, np.array([0, 0, 0, 1, 1, 1.0]),
                                               np.array([[0, 3, 2], [3, 5, 4], [6, 3, 1.5]]))
    out["ruled"] = (ruled(c1, c2), [c1, c2], "ruled(c1, c2): straight rulings between compatible curves")
    prof = _vase_profile()
    out["revolve_full"] = (revolve(prof, [0, 0, 0], [0, 0, 1]), [prof],
                           "revolve(profile, axis): exact rational quadratic arcs (NURBS A8.1)")
    out["revolve_partial"] = (revolve(prof, [0, 0, 0], [0, 0, 1], 4.0), [prof],
                              "revolve(..., angle=4.0 rad): partial, 3 arcs")
    path = interpolate_curve(np.array([[0, 0, 0], [2, 1.5, 1], [4, 1, 3], [6, 3, 4], [8, 3, 6.0]]))
    sec = circle([0, 0, 0], 0.8, normal=[0, 0, 1])
    out["translational_sweep"] = (translational_sweep(sec, path), [sec, path],
                                  "translational_sweep: P(u) + Q(v) - Q(v0), exact")
    prof2 = BSplineCurve(2, np.array([0, 0, 0, 1, 1, 1.0]), np.array([[1.0, 0, 0], [1.8, 0, 1.2], [1.0, 0, 2.0]]))
    traj = ellipse([0, 0, -0.3], 1.4, 0.75)  # only its shape relative to the start point matters
    out["rotational_sweep"] = (rotational_sweep(prof2, traj), [prof2, traj],
                               "rotational_sweep: profile swung along an ellipse (Woodward)")
    th = np.linspace(0, 2 * np.pi, 10)
    helix = interpolate_curve(np.c_[3 * np.cos(th), 3 * np.sin(th), 0.9 * th])
    d = helix.derivatives(helix.domain[0], 1)
    p0, t0 = d[0], d[1] / np.linalg.norm(d[1])
    n0 = np.cross(t0, [0, 0, 1.0])
    n0 /= np.linalg.norm(n0)
    square = BSplineCurve(1, np.r_[0, 0, np.linspace(0, 1, 5)[1:-1], 1, 1],
                          np.array([p0 + (0.7 * a * n0 + 0.15 * b * np.cross(t0, n0)) for a, b in
                                    [(1, 1), (-1, 1), (-1, -1), (1, -1), (1, 1)]]))
    rep = sweep(square, helix, frame="rmf", twist=lambda t: np.pi * t, scale=lambda t: 1 + 0.8 * t,
                tol=1e-5, return_report=True)
    out["sweep_twist_scale"] = (rep.surface, [square, helix],
                                f"sweep of a flat rectangle (RMF, twist pi, scale 1->1.8): max error {rep.max_error:.1e} "
                                f"({rep.n_sections} sections)")
    return out


def render_generation_demo(out_dir: Path) -> list[Path]:
    """Render the generation gallery: one PNG and one STEP file per construction.

    Parameters
    ----------
    out_dir : Path
        Created if missing.

    Returns
    -------
    list of Path
        ``generation_<name>.png`` and ``generation_<name>.step`` for extrude, ruled, revolve_full,
        revolve_partial, translational_sweep, rotational_sweep and sweep_twist_scale.
    """
    from occsurf.bridge.exchange.step_iges import write_step
    from occsurf.bridge.rendering.surfaces import render_surfaces

    out = output_folder(out_dir)
    files: list[Path] = []
    # Second panels look down steeply enough to show the plan shape, but not from straight above:
    # near elevation 90 matplotlib piles the z tick labels on top of each other.
    views = {"revolve_full": ((25.0, -60.0), (58.0, 30.0)), "revolve_partial": ((30.0, -40.0), (58.0, 60.0)),
             "rotational_sweep": ((30.0, -60.0), (58.0, 30.0)), "sweep_twist_scale": ((20.0, -60.0), (58.0, 30.0))}
    for name, (surface, curves, caption) in demo_surfaces().items():
        png = out / f"generation_{name}.png"
        render_surfaces(png, [surface], color="mean", title=f"{name.replace('_', ' ')}", subtitle=caption,
                        curves=curves, views=views.get(name, ((28.0, -60.0), (60.0, 20.0))), resolution=70)
        step = out / f"generation_{name}.step"
        write_step(step, [surface], names=[name])
        files += [png, step]
    return files


if __name__ == "__main__":  # pragma: no cover - manual use
    script(render_generation_demo)
