"""``occsurf demo curvenet``: Coons patches and a Gordon surface with their input curves.

Course §6-20 (bilinearly blended Coons), §6-21 (bicubically blended Coons with cross-boundary
derivatives) and §6-22..6-25 (Gordon surfaces). Each surface is written as STEP and drawn,
shaded and coloured by mean curvature, with its input curves in black.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from occsurf.algorithms import BSplineCurve, BSplineSurface
from occsurf.algorithms.construction import coons, coons_bicubic, gordon
from occsurf.bridge.exchange.step_iges import write_step
from occsurf.bridge.rendering.surfaces import render_surfaces

from ._common import output_folder

__all__ = ["render_curvenet_demo", "demo_boundaries", "demo_network"]


def _curve(points: ArrayLike, degree: int = 3) -> BSplineCurve:
    P = np.asarray(points, float)
    n = P.shape[0]
    inner = np.linspace(0, 1, n - degree + 1)[1:-1]
    return BSplineCurve(degree, np.r_[np.zeros(degree + 1), inner, np.ones(degree + 1)], P)


def demo_boundaries() -> tuple[BSplineCurve, BSplineCurve, BSplineCurve, BSplineCurve]:
    """Four wavy boundaries of a 4 x 3 patch: bottom, right, top, left (grid orientation)."""
    x = np.linspace(0, 4, 6)
    bottom = _curve(np.c_[x, 0.3 * np.sin(np.pi * x / 4) * np.array([0, 1, 1, 1, 1, 0]), 0.8 * np.sin(np.pi * x / 4)])
    top = _curve(np.c_[x, 3 + 0.2 * np.sin(np.pi * x / 2) * np.array([0, 1, 1, 1, 1, 0]), 0.4 * np.sin(np.pi * x / 2) * np.array([0, 1, 1, 1, 1, 0])])
    y = np.linspace(0, 3, 5)
    left = _curve(np.c_[-0.3 * np.sin(np.pi * y / 3), y, 0.6 * np.sin(np.pi * y / 3)])
    right = _curve(np.c_[4 + 0.3 * np.sin(np.pi * y / 3), y, -0.5 * np.sin(np.pi * y / 3)])
    return bottom, right, top, left


def demo_network(nu: int = 4, nv: int = 5) -> tuple[list[BSplineCurve], list[BSplineCurve], BSplineSurface]:
    """A 4 x 5 network (4 u-curves, 5 v-curves) of iso-curves of a wavy bicubic surface."""
    n = 8
    x, y = np.meshgrid(np.linspace(0, 4, n), np.linspace(0, 3, n), indexing="ij")
    z = 0.5 * np.sin(1.3 * x) * np.cos(1.7 * y) + 0.15 * x
    kn = np.r_[np.zeros(4), np.linspace(0, 1, n - 2)[1:-1], np.ones(4)]
    F = BSplineSurface((3, 3), (kn, kn), np.stack([x, y, z], axis=-1))
    from occsurf.algorithms.kernel.basis import basis_matrix

    vs, us = np.linspace(0, 1, nu), np.linspace(0, 1, nv)
    Nv = basis_matrix(kn, 3, n, vs)[0]
    Nu = basis_matrix(kn, 3, n, us)[0]
    u_curves = [BSplineCurve(3, kn, np.einsum("j,ijd->id", Nv[k], F.control_points)) for k in range(nu)]
    v_curves = [BSplineCurve(3, kn, np.einsum("i,ijd->jd", Nu[k], F.control_points)) for k in range(nv)]
    return u_curves, v_curves, F


def _cross_derivatives(bottom: BSplineCurve, right: BSplineCurve, top: BSplineCurve, left: BSplineCurve,
                       amount: float = 1.5) -> tuple[BSplineCurve, BSplineCurve, BSplineCurve, BSplineCurve]:
    """Cross-boundary derivative curves (d/dv along bottom and top, d/du along left and right) with a bump, compatible
    at the corners with the boundary tangents (so the bicubic Coons patch is exact)."""
    def blend(tangent_start: np.ndarray, tangent_end: np.ndarray, c: BSplineCurve, lift: float) -> BSplineCurve:
        # linear blend of the corner tangents plus an upward bump vanishing at both ends
        t = np.linspace(0, 1, c.n_poles)[:, None]
        bump = np.sin(np.pi * t) * np.array([0, 0, lift])
        return BSplineCurve(c.degree, c.knots, (1 - t) * tangent_start + t * tangent_end + bump)

    d = lambda c, x: c.derivatives(x, 1)[1]  # noqa: E731
    xb = blend(d(left, 0), d(right, 0), bottom, amount)
    xt = blend(d(left, 1), d(right, 1), top, -amount)
    xl = blend(d(bottom, 0), d(top, 0), left, amount)
    xr = blend(d(bottom, 1), d(top, 1), right, -amount)
    return xb, xr, xt, xl


def render_curvenet_demo(out_dir: Path) -> list[Path]:
    """Bilinear Coons, bicubic Coons and a 4 x 5 Gordon surface: PNGs with the input curves, and STEP."""
    out = output_folder(out_dir)
    files: list[Path] = []
    views = ((30.0, -60.0), (55.0, 30.0))

    b, r, t, l = demo_boundaries()
    C = coons(b, r, t, l)
    files.append(write_step(out / "coons_bilinear.step", [C, b, r, t, l], ["coons", "bottom", "right", "top", "left"]))
    files.append(render_surfaces(out / "coons_bilinear.png", [C], curves=[b, r, t, l], views=views,
                                 title="Bilinearly blended Coons patch (course §6-20)",
                                 subtitle=f"degree {C.degree}, {C.n_poles[0]} x {C.n_poles[1]} poles; boundaries exact"))

    xd = _cross_derivatives(b, r, t, l)
    CB = coons_bicubic(b, r, t, l, cross_derivatives=xd)
    s = np.linspace(0, 1, 9)
    arrows = []
    for c, dc in zip((b, r, t, l), xd):  # short lines showing the prescribed cross derivatives
        P, D = c.evaluate(s), dc.evaluate(s)
        arrows += [np.stack([p, p + 0.08 * q]) for p, q in zip(P, D)]
    files.append(write_step(out / "coons_bicubic.step", [CB], ["coons_bicubic"]))
    files.append(render_surfaces(out / "coons_bicubic.png", [CB], curves=[b, r, t, l, *arrows], views=views,
                                 title="Bicubically blended Coons patch (course §6-21)",
                                 subtitle="same boundaries; short lines: prescribed cross-boundary derivatives (x 0.08)"))

    A, B, _ = demo_network()
    G = gordon(A, B)
    files.append(write_step(out / "gordon.step", [G, *A, *B], ["gordon"] + [f"u{i}" for i in range(len(A))] + [f"v{j}" for j in range(len(B))]))
    files.append(render_surfaces(out / "gordon.png", [G], curves=[*A, *B], views=views,
                                 title="Gordon surface of a 4 x 5 curve network (course §6-22)",
                                 subtitle=f"Boolean sum P1 + P2 - P12 as one B-spline: degree {G.degree}, "
                                          f"{G.n_poles[0]} x {G.n_poles[1]} poles; network exact"))
    return files
