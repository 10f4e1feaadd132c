"""An arm for the animated-figure surfaces (course §5-42..5-47): pictures, STEP files and a GIF.

:func:`demo_arm` builds the course's motivating case: one bicubic tube (30 x 30 poles) around a
two-segment skeleton (shoulder → elbow), with four overlays in frame offsets — a biceps on the
inner side of the upper arm that flexes with the elbow (a :class:`JointBulge`, §5-46), the
forearm's flesh with a vein on it (level 2), and the point of the elbow on the outer side — its base bound to the bones with
a multi-segment joint at the elbow (§5-45).

:func:`render_figures_demo` poses it at five elbow angles and writes, per pose, a VTK picture
(Warn lighting, :func:`occsurf.bridge.rendering.lighting.render_lit`) and the exact posed NURBS as
STEP; a contact sheet of the five (and the linear baseline at 120 degrees); ``bend.gif``, the elbow
bending and stopping while the forearm's flesh (a dynamic level, the vein riding on it) jiggles and
settles (§5-47); ``cross_section.png``, the joint's
cross-section area against the angle for dual-quaternion and linear blending; and the figure as
JSON (skeleton, bindings, procedure).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from occsurf.algorithms import BSplineSurface
from occsurf.algorithms.hierarchical.figures import (
    AttachedSurface,
    JointBulge,
    attach,
    bind_to_bones,
    section_area,
)
from occsurf.algorithms.hierarchical.skeleton import Joint, Skeleton
from occsurf.algorithms.hierarchical.surface import HierarchicalSurface

from ._common import output_folder, script

__all__ = ["arm_tube", "arm_skeleton", "demo_arm", "render_figures_demo", "POSES_DEG", "ARM"]

#: Upper arm and forearm lengths, blend half-width at the elbow (model units). The half-width is 2.4
#: times the elbow's radius: 1.6 times lets the inner sides cross at 120 degrees (measured: the
#: inner generator crosses itself), 2.0 times clears them by 0.08.
ARM: dict[str, float] = {"upper": 3.0, "fore": 2.6, "blend": 1.2}
#: The elbow angles (degrees) of the five pictures.
POSES_DEG: tuple[float, ...] = (0.0, 30.0, 60.0, 90.0, 120.0)


def _radius(x: np.ndarray) -> np.ndarray:
    """Tube radius along the arm: 0.5 at the elbow, thicker towards the shoulder, thinner to the wrist."""
    return 0.5 - 0.03 * x - 0.012 * x ** 2 * (x > 0)


def arm_tube(n_u: int = 30, n_v: int = 30) -> BSplineSurface:
    """A closed bicubic tube along x from ``-upper`` to ``fore`` (elbow at the origin), ``n_u x n_v``
    poles; v runs around (bottom seam, v = 1/4 the outer side -y, 1/2 the top, 3/4 the inner +y),
    curvature continuous around (a uniform periodic net, clamped exactly)."""
    x = np.linspace(-ARM["upper"], ARM["fore"], n_u)
    m = n_v - 3
    phi = 2.0 * np.pi * (np.arange(m) + 0.5) / m
    shrink = (4.0 + 2.0 * np.cos(2.0 * np.pi / m)) / 6.0  # a periodic cubic lies inside its poles' circle
    R = _radius(x)[:, None] / shrink
    P = np.stack([np.broadcast_to(x[:, None], (n_u, m)), -R * np.sin(phi), -R * np.cos(phi)], -1)
    P = np.concatenate([P, P[:, :3]], 1)
    tu = np.r_[[0.0] * 4, np.linspace(0.0, 1.0, n_u - 2)[1:-1], [1.0] * 4]
    tv = (np.arange(n_v + 4) - 3.0) / m
    return BSplineSurface((3, 3), (tu, tv), P).clamp()


def arm_skeleton() -> Skeleton:
    """Shoulder (root, at x = -upper) and elbow (at the origin, hinge about z: positive angles turn
    the forearm towards +y, the inner side)."""
    return Skeleton([
        Joint("shoulder", None, (-ARM["upper"], 0.0, 0.0), length=ARM["upper"]),
        Joint("elbow", "shoulder", (ARM["upper"], 0.0, 0.0), axis=(0.0, 0.0, 1.0), length=ARM["fore"]),
    ])


def _u_of_x(surface: BSplineSurface, x: float) -> float:
    us = np.linspace(0.0, 1.0, 2001)
    xs = surface.evaluate(us, np.full_like(us, 0.5))[:, 0]
    return float(np.interp(x, xs, us))


def _bump(shape: tuple[int, ...], margin: int = 3) -> np.ndarray:
    """1 in the middle of a net, falling smoothly to 0 over ``margin`` vertices of its border."""
    def one(n: int) -> np.ndarray:
        i = np.arange(n)
        d = np.minimum(i, n - 1 - i) / max(margin, 1)
        t = np.clip(d, 0.0, 1.0)
        return t * t * (3 - 2 * t)
    return np.outer(one(shape[0]), one(shape[1]))


def demo_hierarchy(n_u: int = 30, n_v: int = 30, vein: bool = True) -> tuple[HierarchicalSurface, dict[str, int]]:
    """The arm at rest: the tube with four overlays in frame offsets — the biceps (level 1), the
    forearm's flesh (level 1, the dynamic level of the GIF), a vein on it (level 2) and the point
    of the elbow (level 1); returns it and the overlay ids by name. ``vein=False`` leaves the vein
    out (three overlays, the benchmark's surface)."""
    base = arm_tube(n_u, n_v)
    hs = HierarchicalSurface(base)
    u = lambda x: _u_of_x(base, x)  # noqa: E731 - a local shorthand
    biceps = hs.add_overlay((u(-2.3), u(-0.7)), (0.62, 0.88))
    flesh = hs.add_overlay((u(0.3), u(2.45)), (0.08, 0.92))
    ids = {"biceps": biceps.id, "flesh": flesh.id}
    if vein:
        v = hs.add_overlay((u(0.6), u(2.3)), (0.44, 0.56), flesh)
        o = np.zeros(v.shape + (3,))
        mid = v.shape[1] // 2
        o[1:-1, mid, 2] = 0.06 * _bump((v.shape[0], 1), 3)[1:-1, 0]
        o[1:-1, mid, 1] = 0.02 * np.sin(np.linspace(0, 3 * np.pi, v.shape[0] - 2))  # it meanders
        hs.set_offsets(v, o)
        ids["vein"] = v.id
    point = hs.add_overlay((u(-0.45), u(0.45)), (0.17, 0.33))
    ids["point"] = point.id
    hs.set_offsets(flesh, 0.03 * _bump(flesh.shape, 4)[..., None] * np.array([0.0, 0.0, 1.0]))
    hs.set_offsets(point, 0.09 * _bump(point.shape, 2)[..., None] * np.array([0.0, 0.0, 1.0]))
    hs.set_offsets(biceps, 0.04 * _bump(biceps.shape, 3)[..., None] * np.array([0.0, 0.0, 1.0]))
    return hs, ids


def demo_arm(blend: str = "dual_quaternion", n_u: int = 30, n_v: int = 30, vein: bool = True) -> AttachedSurface:
    """The arm attached to its skeleton: base bound to the bones (a multi-segment joint at the
    elbow, half-width ``ARM['blend']``), the biceps flexing by 0.06 per radian of elbow angle."""
    hs, ids = demo_hierarchy(n_u, n_v, vein)
    sk = arm_skeleton()
    binding = bind_to_bones(hs.base.control_points, sk, ARM["blend"])
    shape = next(o for o in hs.overlays if o.id == ids["biceps"]).shape
    bulge = JointBulge(ids["biceps"], "elbow", _bump(shape, 3), gain=0.06)
    return attach(hs, sk, binding, blend=blend, procedures=[bulge])


def bisector(theta: float) -> tuple[np.ndarray, np.ndarray]:
    """The plane through the elbow that halves a bend by ``theta``: (origin, normal)."""
    return np.zeros(3), np.array([np.cos(theta / 2), np.sin(theta / 2), 0.0])


def linear_baseline(figure: AttachedSurface) -> AttachedSurface:
    """The baseline the tests measure against: the rest surface flattened to one B-spline whose poles
    are bound to the bones the same way and blended linearly (no hierarchy, no dual quaternions)."""
    flat = figure.rest.flatten()
    sk = figure.skeleton
    return attach(flat, sk, bind_to_bones(flat.control_points, sk, ARM["blend"]), blend="linear")


def render_figures_demo(out_dir: Path) -> list[Path]:
    """Write the pose pictures, STEP files, contact sheet, GIF, chart and JSON into ``out_dir``."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from PIL import Image, ImageDraw, ImageFont

    from occsurf.algorithms.hierarchical.dynamics import SoftTissue
    from occsurf.algorithms.lighting import LightingSetup, Material, WarnLight
    from occsurf.bridge.exchange.files import write_figure
    from occsurf.bridge.exchange.step_iges import write_step
    from occsurf.bridge.rendering.lighting import Camera, render_lit, write_png
    from occsurf.bridge.rendering.tessellation import grid_mesh

    out = output_folder(out_dir)
    arm = demo_arm()
    sk = arm.skeleton
    skin = Material(color=(0.86, 0.68, 0.58), diffuse=0.85, specular=0.25, shininess=30)
    key = WarnLight(position=(-2.0, -4.0, 7.0), direction=(0.3, 0.6, -1.0), name="key")
    fill = WarnLight(position=(5.0, 6.0, 3.0), direction=(-0.6, -0.6, -0.3), name="fill", color=(0.35, 0.38, 0.45))
    setup = LightingSetup(lights=(key, fill), ambient=0.12, material=skin)
    camera = Camera(position=(-0.5, -3.2, 7.4), target=(-0.3, 0.8, 0.0), up=(0.0, 0.9, 0.4), view_angle=37.0)
    size = (900, 700)
    font = ImageFont.load_default(size=30)

    def picture(hs: HierarchicalSurface, caption: str) -> Image.Image:
        mesh = grid_mesh(hs.flatten(), 181)
        img = render_lit(mesh.points, mesh.triangles, setup, normals=mesh.normals, size=size, camera=camera)
        tile = Image.fromarray(img.rgb)
        ImageDraw.Draw(tile).text((16, 12), caption, fill=(240, 240, 240), font=font)
        return tile

    files: list[Path] = []
    tiles = []
    for deg in POSES_DEG:
        posed = arm.at(sk.pose({"elbow": np.radians(deg)}))
        tile = picture(posed, f"elbow {deg:.0f} deg")
        tiles.append(tile)
        files.append(write_png(out / f"pose_{deg:03.0f}.png", np.asarray(tile)))
        files.append(write_step(out / f"arm_{deg:03.0f}.step", [posed.flatten()], names=[f"arm at {deg:.0f} deg"]))
    lin = linear_baseline(arm).at(sk.pose({"elbow": np.radians(POSES_DEG[-1])}))
    tiles.append(picture(lin, f"baseline: linear blend of the flat poles, {POSES_DEG[-1]:.0f} deg"))
    w, h = tiles[0].size
    sheet = Image.new("RGB", (3 * w // 2, 2 * h // 2))
    for k, tile in enumerate(tiles):
        sheet.paste(tile.resize((w // 2, h // 2), Image.Resampling.LANCZOS), ((k % 3) * w // 2, (k // 3) * h // 2))
    files.append(write_png(out / "contact_sheet.png", np.asarray(sheet)))

    # the bend, then a sudden stop: the soft base lags, jiggles and settles (§5-47)
    flesh = arm.rest.overlays[1].id
    tissue = SoftTissue(arm, flesh, mass=1.0, stiffness=2000.0, coupling=400.0, damping=8.0)
    dt, frames = 1.0 / 60.0, []
    s = np.linspace(0.0, 1.0, 40)  # 0.65 s of accelerating bend, stopped while still moving
    ramp = (1.0 - np.cos(0.8 * np.pi * s)) / (1.0 - np.cos(0.8 * np.pi))
    angles = list(np.radians(110.0 * ramp)) + [float(np.radians(110.0))] * 60
    for k, a in enumerate(angles):
        hs = tissue.step(sk.pose({"elbow": float(a)}), dt)
        if k % 2 == 0:  # 30 frames a second
            frames.append(picture(hs, f"t = {tissue.time:.2f} s   flesh energy {tissue.energy():.3g}").resize(
                (w // 2, h // 2), Image.Resampling.LANCZOS))
    gif = out / "bend.gif"
    frames[0].save(gif, save_all=True, append_images=frames[1:], duration=int(2000 * dt), loop=0)
    files.append(gif)

    # the joint's cross-section against the angle: dual quaternions against the linear baseline
    base_lin = linear_baseline(arm)
    degs = np.linspace(0.0, 120.0, 13)
    area: dict[str, list[float]] = {"dual quaternion (ours)": [], "linear blend of flat poles": []}
    for deg in degs:
        th = float(np.radians(deg))
        pose = sk.pose({"elbow": th})
        o, n = bisector(th)
        area["dual quaternion (ours)"].append(section_area(arm.at(pose), o, n))
        area["linear blend of flat poles"].append(section_area(base_lin.at(pose), o, n))
    fig = Figure(figsize=(6.4, 4.2), dpi=110)
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(1, 1, 1)
    for label, vals in area.items():
        ax.plot(degs, np.asarray(vals) / vals[0], marker="o", label=label)
    ax.axhline(0.8, color="grey", lw=0.8, ls="--")
    ax.set_xlabel("elbow angle (degrees)")
    ax.set_ylabel("cross-section area at the elbow / rest")
    ax.set_title("Multi-segment joint (course §5-45): the elbow keeps its section")
    ax.legend()
    files.append(write_figure(fig, out / "cross_section.png"))

    js = out / "arm.json"
    js.write_text(json.dumps(arm.to_dict()))
    files.append(js)
    return files


def measures(figure: AttachedSurface, degrees: Any = POSES_DEG) -> list[dict[str, float]]:
    """Per elbow angle, the joint's cross-section area relative to rest (for the README table)."""
    sk = figure.skeleton
    a0 = section_area(figure.at(sk.pose()), *bisector(0.0))
    rows = []
    for deg in degrees:
        th = float(np.radians(deg))
        rows.append({"deg": float(deg), "area": section_area(figure.at(sk.pose({"elbow": th})), *bisector(th)) / a0})
    return rows


if __name__ == "__main__":  # pragma: no cover - manual use
    script(render_figures_demo)
