"""Warn's lighting controls on one surface (course ch. 10, the figures of §10-5 and §10-7).

:func:`render_lighting_demo` lights the same bicubic "hood" (a crowned panel with a character
line, the kind of car-body surface Warn lit at GM) six ways and writes one PNG per light plus a
contact sheet:

1. ``1_plain.png`` - an unrestricted point light (concentration 0): the whole panel is lit;
2. ``2_concentration.png`` - the same light with concentration n = 40: a pool of light where its
   axis meets the panel;
3. ``3_flaps.png`` - the light with flaps: a band of light across the panel, with sharp edges
   where the barn doors cut it off;
4. ``4_cone.png`` - the light with a 14 degree cone and a 5 degree soft edge: a round spot;
5. ``5_colour_blend.png`` - two coloured lights, red from the left and blue from the right,
   blending additively (§10-7): the hue shows which way the surface faces;
6. ``6_key_flaps_preset.png`` - the "key light with flaps" preset over a glossy red paint.

Every picture is rendered per pixel by :func:`occsurf.bridge.rendering.lighting.render_lit` (the
GLSL form of :func:`occsurf.algorithms.lighting.shade`), with the same camera, 1200 x 900.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from occsurf.algorithms import BSplineSurface
from occsurf.algorithms.lighting import LightingSetup, Material, WarnLight, key_light_with_flaps

__all__ = ["render_lighting_demo", "demo_hood", "demo_setups"]

SIZE = (1200, 900)


def demo_hood() -> BSplineSurface:
    """A bicubic 7 x 13 panel over [-2, 2] x [-1.3, 1.3]: crowned across, falling to the front, with a
    raised character line along x at y = 0.45."""
    xs = np.linspace(-2.0, 2.0, 7)
    ys = np.linspace(-1.3, 1.3, 13)
    X, Y = np.meshgrid(xs, ys, indexing="ij")
    Z = 0.55 * (1 - (Y / 1.5) ** 2) - 0.12 * X - 0.05 * X ** 2
    Z += 0.16 * np.exp(-((Y - 0.45) / 0.22) ** 2)  # the character line
    poles = np.stack([X, Y, Z], axis=-1)
    u = np.concatenate([[0.0] * 4, [1 / 4, 2 / 4, 3 / 4], [1.0] * 4])
    v = np.concatenate([[0.0] * 4, np.arange(1, 10) / 10, [1.0] * 4])
    return BSplineSurface(degree=(3, 3), knots=(u, v), control_points=poles)


def demo_setups() -> dict[str, tuple[str, LightingSetup]]:
    """File stem -> (caption, setup) of the six pictures."""
    paint = Material(color=(0.78, 0.78, 0.80), diffuse=0.8, specular=0.45, shininess=60)
    pos, aim = (-0.6, -2.2, 3.2), (0.35, 0.25, 0.3)
    d = tuple(np.subtract(aim, pos))
    plain = WarnLight(position=pos, direction=d, name="plain")

    def one(light: WarnLight) -> LightingSetup:
        return LightingSetup(lights=(light,), ambient=0.06, material=paint)

    conc = WarnLight(position=pos, direction=d, concentration=40.0)
    flaps = WarnLight(position=pos, direction=d, concentration=2.0, flaps={"x": [-3.0, 3.0], "y": [-0.35, 0.25]})
    cone = WarnLight(position=pos, direction=d, cone_angle_deg=14.0, cone_edge_deg=5.0)
    red = WarnLight(position=(-4.0, -1.0, 2.0), direction=(4.0, 1.0, -2.0), color=(1.0, 0.15, 0.1), intensity=0.9)
    blue = WarnLight(position=(4.0, -1.0, 2.0), direction=(-4.0, 1.0, -2.0), color=(0.1, 0.3, 1.0), intensity=0.9)
    key = key_light_with_flaps([0.0, 0.0, 0.3], 5.0, concentration=6.0, width=0.9, height=0.09)
    return {
        "1_plain": ("unrestricted light (n = 0)", one(plain)),
        "2_concentration": ("concentration n = 40", one(conc)),
        "3_flaps": ("flaps: y in [-0.35, 0.25]", one(flaps)),
        "4_cone": ("cone 14 deg, soft edge 5 deg", one(cone)),
        "5_colour_blend": ("red + blue lights blended", LightingSetup(lights=(red, blue), ambient=0.04, material=paint)),
        "6_key_flaps_preset": ("preset: key light with flaps", key),
    }


def render_lighting_demo(out_dir: Path) -> list[Path]:
    """Write the six pictures, ``contact_sheet.png`` and the lit surface as ``hood.step`` into
    ``out_dir``; returns the paths."""
    from PIL import Image, ImageDraw

    from occsurf.bridge.exchange.step_iges import write_step
    from occsurf.bridge.rendering.lighting import Camera, render_lit, write_png
    from occsurf.bridge.rendering.tessellation import grid_mesh

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    hood = demo_hood()
    mesh = grid_mesh(hood, 161)
    camera = Camera(position=(2.6, -5.6, 4.2), target=(0.0, 0.0, 0.15), up=(0.0, 0.0, 1.0), view_angle=30.0)
    files, tiles = [], []
    for stem, (caption, setup) in demo_setups().items():
        img = render_lit(mesh.points, mesh.triangles, setup, normals=mesh.normals, size=SIZE, camera=camera)
        files.append(write_png(out_dir / f"{stem}.png", img))
        tile = Image.fromarray(img.rgb).resize((SIZE[0] // 2, SIZE[1] // 2), Image.Resampling.LANCZOS)
        ImageDraw.Draw(tile).text((12, 10), caption, fill=(235, 235, 235))
        tiles.append(tile)
    w, h = tiles[0].size
    sheet = Image.new("RGB", (3 * w, 2 * h))
    for k, tile in enumerate(tiles):
        sheet.paste(tile, ((k % 3) * w, (k // 3) * h))
    files.append(write_png(out_dir / "contact_sheet.png", np.asarray(sheet)))
    step = out_dir / "hood.step"
    write_step(step, [hood], names=["hood"])
    files.append(step)
    return files
