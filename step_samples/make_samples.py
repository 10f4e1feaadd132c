"""Rebuild the sample STEP/IGES files of ``step_samples/`` (the files ``occsurf inspect`` reads by default).

Run from anywhere::

    python step_samples/make_samples.py            # writes beside this script
    python step_samples/make_samples.py OUTDIR     # writes into OUTDIR

Every model is built from fixed numbers with build123d, cadquery, OCC's own constructors or our
:mod:`occsurf.algorithms` kernel, and written with :func:`occsurf.bridge.exchange.step_iges.write_step` (17 significant
digits: our surfaces come back bit-exact) or :func:`occsurf.bridge.exchange.step_iges.write_iges`. The output is
byte-for-byte reproducible with the pinned OCC (7.9.3): the only varying bytes OCC writes, the time
stamps of the STEP ``FILE_NAME`` and of the IGES global section, are set to 2000-01-01 00:00:00.

| file | holds |
|---|---|
| ``loft.step`` | build123d loft through circle -> rounded rectangle -> ellipse (B-spline sides, 2 planes) |
| ``swept_tube.step`` | build123d sweep of a closed lobed spline along a 3-D spline (u-periodic B-spline) |
| ``nurbs_torus.step`` | our exact NURBS torus (rational biquadratic, 9x9 poles), written from the kernel |
| ``periodic_vase.step`` | OCC periodic bicubic interpolation (non-rational, u-periodic) |
| ``mixed.igs`` | IGES: our bicubic patch on uneven knots + a cadquery filleted block (planes, cylinders, spheres) |
"""

from __future__ import annotations

import math
import re
import sys
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))  # run from a source checkout without installing

import numpy as np  # noqa: E402

from occsurf.algorithms import BSplineSurface, circle  # noqa: E402

if TYPE_CHECKING:
    import build123d as bd
    import cadquery as cq

#: Written into every file instead of the wall-clock time, so rebuilding changes nothing.
FIXED_STEP_TIME = "2000-01-01T00:00:00"
FIXED_IGES_DATE = {15: "20000101.000000", 13: "000101.000000"}
MAX_BYTES = 300_000


# ------------------------------------------------------------------------------------- models
def loft_body() -> bd.Solid:
    """A solid lofted through three different closed sections (free-form sides)."""
    import build123d as bd

    bottom = bd.Wire.make_circle(10.0)
    middle = bd.Pos(0, 0, 15) * bd.RectangleRounded(16.0, 12.0, 3.0).wire()
    top = bd.Pos(0, 0, 30) * bd.Wire.make_ellipse(9.0, 5.0)
    return bd.Solid.make_loft([bottom, middle, top])


def swept_tube() -> bd.Solid:
    """A closed, lobed section swept along a 3-D spline: OCC gives a B-spline periodic around the tube.

    The section is a periodic cubic spline through 9 points of a three-lobed curve. (A circular
    section would give OCC's rational periodic circle, 6 poles of degree 6, which
    ``occsurf.bridge.conversion.splines.from_occ`` refuses: fewer than degree + 1 poles.)
    """
    import build123d as bd

    path = bd.Wire([bd.Edge.make_spline([(0, 0, 0), (10, 5, 0), (20, 0, 5), (30, -5, 10)])])
    plane = bd.Plane(origin=(0, 0, 0), z_dir=path.tangent_at(0))
    angles = [2.0 * math.pi * i / 9 for i in range(9)]
    radius = [2.0 * (1.0 + 0.25 * math.cos(3.0 * t)) for t in angles]
    points = [plane.from_local_coords((r * math.cos(t), r * math.sin(t))) for r, t in zip(radius, angles)]
    section = bd.Wire([bd.Edge.make_spline(points, periodic=True)])
    return bd.Solid.sweep(section, path)


def nurbs_torus(major: float = 10.0, minor: float = 3.0) -> BSplineSurface:
    """The exact torus as a rational biquadratic surface: the minor circle revolved by the major one.

    Tensor product of two 9-pole rational circles (The NURBS Book, 2nd ed., A8.1, surface of
    revolution): ``P_ij = (x_j c_i, z_j)`` and ``w_ij = W_i w_j`` with ``c_i``, ``W_i`` the poles
    and weights of the unit circle about z and ``(x_j, z_j)``, ``w_j`` those of the minor circle in
    the xz-plane.
    """
    unit = circle([0.0, 0.0, 0.0], 1.0, normal=[0.0, 0.0, 1.0])
    section = circle([major, 0.0, 0.0], minor, normal=[0.0, -1.0, 0.0], xaxis=[1.0, 0.0, 0.0])
    c, x, z = unit.control_points, section.control_points[:, 0], section.control_points[:, 2]
    P = np.empty((c.shape[0], x.shape[0], 3))
    P[..., 0] = c[:, None, 0] * x[None, :]
    P[..., 1] = c[:, None, 1] * x[None, :]
    P[..., 2] = z[None, :]
    if unit.weights is None or section.weights is None:
        raise RuntimeError("nurbs_torus: circle() gave a non-rational circle")
    W = np.outer(unit.weights, section.weights)
    return BSplineSurface((2, 2), (unit.knots, section.knots), P, W)


def periodic_vase() -> bd.Face:
    """A bicubic surface interpolating a closed grid of points, periodic in u (OCC's interpolator)."""
    import build123d as bd
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace
    from OCP.GeomAPI import GeomAPI_PointsToBSplineSurface
    from OCP.gp import gp_Pnt
    from OCP.TColgp import TColgp_Array2OfPnt

    nu, nv = 8, 5
    grid = TColgp_Array2OfPnt(1, nu, 1, nv)
    for i in range(nu):
        t = 2.0 * math.pi * i / nu
        for j in range(nv):
            r = 10.0 + 3.0 * math.sin(0.8 * j) + 1.5 * math.cos(3.0 * t)
            grid.SetValue(i + 1, j + 1, gp_Pnt(r * math.cos(t), r * math.sin(t), 10.0 * j))
    fit = GeomAPI_PointsToBSplineSurface()
    fit.Interpolate(grid, True)  # periodic: rows are not repeated, u closes on its own
    occ_surface = fit.Surface()
    if not occ_surface.IsUPeriodic():
        raise RuntimeError("periodic_vase: OCC's interpolation did not come back u-periodic")
    maker = BRepBuilderAPI_MakeFace(occ_surface, 1e-7)
    if not maker.IsDone():
        raise RuntimeError(f"periodic_vase: BRepBuilderAPI_MakeFace failed ({maker.Error().name})")
    return bd.Face(maker.Face())


def bicubic_patch() -> BSplineSurface:
    """A non-rational bicubic patch on uneven interior knots, with bumps."""
    U = [0, 0, 0, 0, 0.3, 0.5, 1, 1, 1, 1]
    V = [0, 0, 0, 0, 0.4, 1, 1, 1, 1]
    nu, nv = len(U) - 4, len(V) - 4
    i, j = np.meshgrid(np.arange(nu), np.arange(nv), indexing="ij")
    P = np.stack([8.0 * i, 6.0 * j, 3.0 * np.sin(1.3 * i) * np.cos(0.9 * j)], axis=-1)
    return BSplineSurface((3, 3), (np.array(U, float), np.array(V, float)), P.astype(float))


def filleted_block() -> cq.Workplane:
    """A cadquery block with rounded edges: planes, cylinders and spheres (analytic faces)."""
    import cadquery as cq

    return cq.Workplane("XY").box(20.0, 14.0, 8.0).edges().fillet(2.0).translate((20.0, 0.0, -10.0))


# ------------------------------------------------------------------------------------- writing
def _fix_step_time(path: Path) -> None:
    text = path.read_text(encoding="utf-8")
    head, sep, rest = text.partition("DATA;")
    head = re.sub(r"(FILE_NAME\('(?:[^']|'')*',)'[^']*'", rf"\1'{FIXED_STEP_TIME}'", head, count=1)
    path.write_text(head + sep + rest, encoding="utf-8")


def _fix_iges_dates(path: Path) -> None:
    """Replace the Hollerith date strings of the global section (they may wrap across lines)."""
    lines = path.read_text(encoding="ascii").split("\n")
    g = [k for k, ln in enumerate(lines) if ln[72:73] == "G"]
    if not g:
        return
    body = "".join(lines[k][:72] for k in g)

    def fixed(m: re.Match[str]) -> str:
        n = int(m.group(1))
        return f"{n}H{FIXED_IGES_DATE[n]}"

    new = re.sub(r"(15|13)H(?:\d{8}|\d{6})\.\d{6}", fixed, body)
    if len(new) != len(body):
        raise RuntimeError(f"{path}: IGES date replacement changed the global section's length")
    for n, k in enumerate(g):
        lines[k] = new[72 * n : 72 * n + 72] + lines[k][72:]
    path.write_text("\n".join(lines), encoding="ascii")


def write_samples(outdir: Path) -> list[Path]:
    """Build every model and write the sample files into ``outdir``; returns the paths."""
    from occsurf.bridge.exchange.step_iges import write_iges, write_step

    jobs: list[tuple[str, Callable[[], tuple[list, list[str]]]]] = [
        ("loft.step", lambda: ([loft_body()], ["loft circle-rounded rect-ellipse"])),
        ("swept_tube.step", lambda: ([swept_tube()], ["swept tube"])),
        ("nurbs_torus.step", lambda: ([nurbs_torus()], ["NURBS torus R10 r3"])),
        ("periodic_vase.step", lambda: ([periodic_vase()], ["periodic vase"])),
        ("mixed.igs", lambda: ([bicubic_patch(), filleted_block()], ["bicubic patch", "filleted block"])),
    ]
    written = []
    for name, build in jobs:
        objects, names = build()
        path = outdir / name
        if path.suffix == ".step":
            write_step(path, objects, names=names)
            _fix_step_time(path)
        else:
            write_iges(path, objects, names=names)
            _fix_iges_dates(path)
        size = path.stat().st_size
        if size > MAX_BYTES:
            raise RuntimeError(f"{path}: {size} bytes, more than the {MAX_BYTES} allowed for a sample")
        written.append(path)
    return written


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    if args and args[0] in ("-h", "--help"):
        print(__doc__)
        return 0
    if len(args) > 1:
        print("usage: make_samples.py [OUTDIR]", file=sys.stderr)
        return 2
    outdir = Path(args[0]) if args else HERE
    outdir.mkdir(parents=True, exist_ok=True)
    for path in write_samples(outdir):
        print(f"{path}  {path.stat().st_size:>7} bytes")
    return 0


if __name__ == "__main__":
    sys.exit(main())
