"""Pictures and STEP files for adaptive hierarchical fitting (course §7-10).

:func:`render_fitting_demo` fits a height field with one sharp local feature (a narrow bump on a
gentle wave, 161 x 161 samples) to a tolerance of 1e-3 by :func:`~occsurf.algorithms.fitting.fit_adaptive`:
a coarse base, then overlays only where the distance to the data still exceeds the tolerance.
It writes the per-level error picture (the hierarchy truncated at each level, coloured by the
measured distance to the data on a log scale, overlay borders drawn), the same for Franke's
function, the same for a noisy scan-like cloud of the sharp feature (scattered points,
:func:`~occsurf.algorithms.fitting.fit_adaptive_scattered`), the flat exact NURBS as STEP with the
editable hierarchy as its JSON sidecar, and a text file comparing the control points stored
against the uniform least-squares fit that meets the same tolerance.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ._common import output_folder

__all__ = ["render_fitting_demo", "sharp_feature", "franke"]

TOL = 1e-3


def franke(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Franke's test function on the unit square (R. Franke, 1979)."""
    return (0.75 * np.exp(-((9 * x - 2) ** 2 + (9 * y - 2) ** 2) / 4) + 0.75 * np.exp(-(9 * x + 1) ** 2 / 49 - (9 * y + 1) / 10)
            + 0.5 * np.exp(-((9 * x - 7) ** 2 + (9 * y - 3) ** 2) / 4) - 0.2 * np.exp(-(9 * x - 4) ** 2 - (9 * y - 7) ** 2))


def sharp_feature(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """A gentle wave with one narrow bump (sigma 0.025) at (0.62, 0.41)."""
    return 0.2 * np.sin(2 * x) * np.cos(1.5 * y) + 0.3 * np.exp(-((x - 0.62) ** 2 + (y - 0.41) ** 2) / (2 * 0.025 ** 2))


def _uniform_count(Z: np.ndarray, x: np.ndarray, tol: float) -> tuple[int, float]:
    """Poles of the smallest square uniform least-squares fit within ``tol`` (measured)."""
    from occsurf.algorithms.fitting import fit_grid
    from occsurf.algorithms.fitting.adaptive import measure_grid

    P3 = np.stack(np.broadcast_arrays(x[:, None], x[None, :], Z), -1)
    for n in range(8, x.size + 1, 2):
        g = fit_grid(Z, n, 3, x=x, y=x)
        err = float(np.nanmax(measure_grid(g.surface, P3, x, x)))
        if err <= tol:
            return n * n, err
    return -1, float("nan")


def render_fitting_demo(out_dir: Path) -> list[Path]:
    """Render the adaptive-fitting demo into ``out_dir`` (created if missing).

    Returns
    -------
    list of Path
        ``fitting_sharp_levels.png``, ``fitting_franke_levels.png`` and
        ``fitting_scattered_levels.png`` (per-level error maps),
        ``fitting_sharp.step`` + ``fitting_sharp.hierarchy.json`` (flat NURBS and editable
        hierarchy), ``fitting_counts.txt`` (control points: adaptive vs uniform).
    """
    from occsurf.algorithms.fitting import fit_adaptive
    from occsurf.bridge.exchange.files import write_text
    from occsurf.bridge.exchange.hierarchical_io import write_hierarchical_step
    from occsurf.bridge.modeling.fit import error_panel
    from occsurf.bridge.rendering.error_maps import render_error_maps

    out = output_folder(out_dir)
    files: list[Path] = []
    lines = [f"Adaptive hierarchical fitting (course 7-10) at tol {TOL:g}, bicubic, distances measured by projection", ""]
    for name, f, m in (("sharp", sharp_feature, 161), ("franke", franke, 101)):
        x = np.linspace(0.0, 1.0, m)
        Z = f(*np.meshgrid(x, x, indexing="ij"))
        fit = fit_adaptive(Z, TOL)
        panels = [error_panel(s, d, fit.u_params, fit.v_params,
                              f"level {L.level}: {L.overlays} overlays, {L.control_points} dof, max {L.max_error:.2g}",
                              [o for o in fit.hierarchy.overlays if o.level == L.level])
                  for L, s, d in zip(fit.levels, fit.level_surfaces, fit.level_distances)]
        stored = fit.control_points_total
        uniform, uerr = _uniform_count(Z, x, TOL)
        title = (f"{'sharp feature' if name == 'sharp' else 'Franke'} ({m} x {m} heights): {stored} control points "
                 f"stored, max distance {fit.max_error:.2g}; uniform least squares needs {uniform}")
        png = render_error_maps(out / f"fitting_{name}_levels.png", panels, tol=TOL, title=title)
        files.append(png)
        lines.append(f"{name}: adaptive {stored} stored ({len(fit.levels) - 1} levels, flat "
                     f"{fit.hierarchy.flatten().n_poles}), max {fit.max_error:.3g}; uniform {uniform} (max {uerr:.3g}); "
                     f"ratio {uniform / stored:.2f}")
        if name == "sharp":
            files.extend(write_hierarchical_step(out / "fitting_sharp.step", fit.hierarchy, "sharp feature fit"))
    png, line = _scattered_demo(out)
    files.append(png)
    lines.append(line)
    files.append(write_text(out / "fitting_counts.txt", "\n".join(lines) + "\n"))
    return files


def _scattered_demo(out: Path, k: int = 30000) -> tuple[Path, str]:
    """A noisy scan-like cloud (k random points over the sharp feature, noise 1e-4) fitted
    adaptively at 2 x TOL; its per-level error picture and one summary line."""
    from occsurf.algorithms.fitting import fit_adaptive_scattered, fit_scattered
    from occsurf.bridge.modeling.fit import scatter_error_panel
    from occsurf.bridge.rendering.error_maps import render_error_maps

    tol = 2 * TOL
    rng = np.random.default_rng(13)
    x, y = rng.random(k), rng.random(k)
    x[:4], y[:4] = [0, 1, 0, 1], [0, 0, 1, 1]
    P = np.c_[x, y, sharp_feature(x, y) + 1e-4 * rng.standard_normal(k)]
    fit = fit_adaptive_scattered(P, tol, params=np.c_[x, y])
    panels = [scatter_error_panel(s, fit.u, fit.v, d, f"level {L.level}: {L.overlays} overlays, {L.control_points} dof, "
                                  f"max {L.max_error:.2g}", [o for o in fit.hierarchy.overlays if o.level == L.level])
              for L, s, d in zip(fit.levels, fit.level_surfaces, fit.level_distances)]
    n = 8
    while n < 120 and fit_scattered(P, n, 3, params=np.c_[x, y]).max_error > tol:
        n += 4
    title = (f"scattered scan ({k} points, noise 1e-4): {fit.control_points_total} control points stored, max "
             f"distance {fit.max_error:.2g}; uniform scattered least squares needs {n * n}")
    png = render_error_maps(out / "fitting_scattered_levels.png", panels, tol=tol, title=title)
    return png, (f"scattered: adaptive {fit.control_points_total} stored ({len(fit.levels) - 1} levels), max "
                 f"{fit.max_error:.3g} at tol {tol:g}; uniform {n * n}; ratio {n * n / fit.control_points_total:.2f}")
