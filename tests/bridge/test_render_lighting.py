"""The per-pixel Warn renderer (bridge/rendering/lighting.py) against the NumPy reference, and
``occsurf render``. Offscreen (EGL), no display needed.

Tolerance: the picture is 8-bit, so a pixel can differ from ``round(clip(shade) * 255)`` by one
level of rounding plus the float32 arithmetic of the shader and the interpolation of the mesh's
vertex positions and normals across its triangles: on the exact plane (positions and normals
interpolate exactly) we demand <= 2 levels everywhere but within 2 pixels of the silhouette or of a
discontinuity of the light (a flap, a hard cone), where a pixel's centre may fall on either side. On
a tessellated sphere the interpolated normal differs from the exact one by up to ~1e-4 rad; we
demand <= 3 levels.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from occsurf.algorithms.lighting import LightingSetup, Material, WarnLight, shade, studio_three_point

lighting = pytest.importorskip("occsurf.bridge.rendering.lighting")
from scipy.ndimage import binary_dilation, binary_erosion  # noqa: E402

pytestmark = pytest.mark.skipif(not lighting.render_available(), reason="VTK cannot open an offscreen window here")

REPO = Path(__file__).resolve().parents[2]
SIZE = (320, 240)


def _plane(n: int = 60, half: float = 5.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    x, y = np.meshgrid(np.linspace(-half, half, n), np.linspace(-half, half, n), indexing="ij")
    P = np.stack([x.ravel(), y.ravel(), np.zeros(x.size)], axis=-1)
    k = np.arange(n * n).reshape(n, n)
    a, b, c, d = k[:-1, :-1].ravel(), k[1:, :-1].ravel(), k[1:, 1:].ravel(), k[:-1, 1:].ravel()
    T = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    return P, T, np.tile([0.0, 0.0, 1.0], (len(P), 1))


def _sphere(n: int = 160) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    th, ph = np.meshgrid(np.linspace(0, 2 * np.pi, 2 * n), np.linspace(1e-3, np.pi - 1e-3, n), indexing="ij")
    P = np.stack([np.cos(th) * np.sin(ph), np.sin(th) * np.sin(ph), np.cos(ph)], -1).reshape(-1, 3)
    k = np.arange(2 * n * n).reshape(2 * n, n)
    a, b, c, d = k[:-1, :-1].ravel(), k[1:, :-1].ravel(), k[1:, 1:].ravel(), k[:-1, 1:].ravel()
    return P, np.concatenate([np.stack([a, c, b], 1), np.stack([a, d, c], 1)]), P.copy()


def _compare(img, setup, normal_of, *, levels: float, margin: int = 2) -> tuple[np.ndarray, np.ndarray]:
    """The NumPy model at the renderer's pixel positions (from its depth buffer) against the picture."""
    W = lighting.pixel_world_points(img)
    cov = img.covered
    ref = np.zeros(img.rgb.shape)
    ref[cov] = shade(W[cov], normal_of(W[cov]), img.camera.position, setup)
    ref8 = np.round(np.clip(ref, 0, 1) * 255)
    # discontinuities of the light: neighbours whose reference differs by a lot
    jump = np.zeros(cov.shape, bool)
    for ax in (0, 1):
        dj = np.abs(np.diff(ref8, axis=ax)).max(axis=-1) > 24
        sl = [slice(None)] * 2
        sl[ax] = slice(0, -1)
        jump[tuple(sl)] |= dj
    keep = binary_erosion(cov, iterations=margin) & ~binary_dilation(jump, iterations=margin)
    diff = np.abs(ref8[keep] - img.rgb[keep].astype(float)).max(axis=-1)
    assert keep.sum() > 0.3 * cov.sum()
    assert diff.max() <= levels, f"max {diff.max()} levels, {np.mean(diff > levels):.2%} of pixels over {levels}"
    return ref8, keep


def test_plane_with_flaps_cone_and_concentration_matches_the_reference() -> None:
    """A known scene: the plane z = 0 seen from the top under a concentrated light with flaps and a
    soft cone, a coloured directional light with flaps and a light with soft flap edges; every
    kept pixel within 2 levels."""
    P, T, N = _plane()
    key = WarnLight(position=(0.5, -1.0, 6.0), direction=(0.0, 0.2, -1.0), concentration=3.0,
                    cone_angle_deg=32, cone_edge_deg=8, flaps={"x": [-2.5, 3.0], "y": [-4.0, None]})
    soft = WarnLight(position=(-3.0, 2.0, 5.0), direction=(0.5, -0.2, -1.0), color=(0.5, 0.4, 0.1),
                     flaps={"x": [-1.0, 1.0]}, flap_edge=0.6)
    blue = WarnLight(position=None, direction=(0.3, 0.2, -1.0), color=(0.1, 0.2, 0.6), flaps={"y": [-1.0, 2.0]})
    setup = LightingSetup(lights=(key, blue, soft), ambient=0.06,
                          material=Material(color=(0.8, 0.7, 0.6), diffuse=0.8, specular=0.3, shininess=20))
    img = lighting.render_lit(P, T, setup, normals=N, size=SIZE, view="top")
    ref8, keep = _compare(img, setup, lambda W: np.broadcast_to([0.0, 0.0, 1.0], W.shape), levels=2)
    # flaps: outside the key's flap the reference (and the picture) is ambient + the blue light only
    assert (ref8[keep].max(axis=-1) - ref8[keep].min(axis=-1)).max() > 50


def test_pixels_outside_a_flap_are_ambient_only_in_the_picture() -> None:
    P, T, N = _plane()
    light = WarnLight(position=(0.0, 0.0, 8.0), direction=(0, 0, -1), flaps={"x": [-1.0, 1.5]})
    setup = LightingSetup(lights=(light,), ambient=0.1, material=Material(color=(1, 1, 1), specular=0.0))
    img = lighting.render_lit(P, T, setup, normals=N, size=SIZE, view="top")
    W = lighting.pixel_world_points(img)
    inner = binary_erosion(img.covered, iterations=2)
    outside = inner & ((W[..., 0] < -1.1) | (W[..., 0] > 1.6))
    inside = inner & (W[..., 0] > -0.9) & (W[..., 0] < 1.4)
    assert outside.sum() > 1000 and inside.sum() > 1000
    assert np.all(np.abs(img.rgb[outside].astype(int) - 26) <= 1)  # 0.1 * 255 = 25.5
    assert img.rgb[inside].min() > 100


def test_sphere_matches_the_reference() -> None:
    """Curved: the studio preset on a tessellated unit sphere, within 3 levels off the silhouette."""
    P, T, N = _sphere()
    setup = studio_three_point([0, 0, 0], 2.0)
    img = lighting.render_lit(P, T, setup, normals=N, size=SIZE, view="iso")
    _compare(img, setup, lambda W: W / np.linalg.norm(W, axis=-1, keepdims=True), levels=3)


def test_views_and_cameras() -> None:
    P, T, N = _plane()
    setup = LightingSetup(lights=(WarnLight(position=(0.0, 0.0, 8.0), direction=(0, 0, -1)),))
    top = lighting.render_lit(P, T, setup, normals=N, size=SIZE, view="top")
    assert top.covered.mean() > 0.25  # the whole plane, seen from above
    np.testing.assert_allclose(top.camera.position[:2], [0, 0], atol=1e-9)
    assert top.camera.position[2] > 0
    edge = lighting.render_lit(P, T, setup, normals=N, size=SIZE, view="front")
    assert edge.covered.mean() < 0.05  # the plane seen edge-on
    cam = lighting.Camera(position=(0.0, -12.0, 12.0), target=(0.0, 0.0, 0.0), up=(0.0, 0.0, 1.0))
    img = lighting.render_lit(P, T, setup, normals=N, size=SIZE, camera=cam)
    assert img.covered.any() and img.camera == cam
    with pytest.raises(ValueError, match="view"):
        lighting.render_lit(P, T, setup, normals=N, size=SIZE, view="diagonal")
    with pytest.raises(ValueError, match="camera.up"):
        lighting.Camera(position=(0, 0, 5), target=(0, 0, 0), up=(0, 0, 1))
    with pytest.raises(ValueError, match="size"):
        lighting.render_lit(P, T, setup, size=(8, 8))
    with pytest.raises(ValueError, match="triangles"):
        lighting.render_lit(P, T + len(P), setup)


def test_write_png_is_atomic_and_checked(tmp_path) -> None:
    from PIL import Image

    P, T, N = _plane(10)
    img = lighting.render_lit(P, T, LightingSetup(ambient=0.5), normals=N, size=SIZE, view="top")
    out = lighting.write_png(tmp_path / "a.png", img)
    assert Image.open(out).size == SIZE
    with pytest.raises(OSError):
        lighting.write_png(tmp_path / "missing" / "a.png", img)
    assert not list(tmp_path.glob("*.tmp*"))


# ---------------------------------------------------------------------------------------- CLI
def _occsurf(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    env = dict(os.environ)
    return subprocess.run([sys.executable, "-m", "occsurf.bridge.cli", *args], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=600)


@pytest.fixture(scope="module")
def sample() -> Path:
    path = REPO / "step_samples" / "nurbs_torus.step"
    if not path.exists():
        pytest.skip(f"{path} missing")
    return path


@pytest.mark.slow
def test_cli_renders_a_model(tmp_path, sample) -> None:
    from PIL import Image

    lights = tmp_path / "lights.json"
    lights.write_text(json.dumps({"ambient": 0.05, "lights": [
        {"position": [0, -300, 300], "direction": [0, 1, -1], "color": [1, 0.9, 0.8], "intensity": 1.0,
         "concentration": 2, "cone": {"angle_deg": 30, "edge_deg": 4}, "flaps": {"x": [-50, 50]}}]}))
    out = tmp_path / "torus.png"
    r = _occsurf("render", str(sample), "--lights", str(lights), "--out", str(out), "--size", "200", "150",
                 "--view", "top", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert "wrote" in r.stdout
    arr = np.asarray(Image.open(out))
    assert arr.shape == (150, 200, 3) and arr.max() > 60


@pytest.mark.parametrize("case", ["bad-json", "bad-field", "unknown-view", "unwritable", "missing-input",
                                  "unknown-preset"])
def test_cli_errors_are_one_line_exit_2(tmp_path, sample, case) -> None:
    good = tmp_path / "good.json"
    good.write_text('{"lights": [{"position": [0, 0, 100], "direction": [0, 0, -1]}]}')
    args = ["render", str(sample), "--lights", str(good), "--out", str(tmp_path / "o.png"), "--size", "64", "48"]
    if case == "bad-json":
        (tmp_path / "bad.json").write_text('{"lights": [}')
        args[3] = str(tmp_path / "bad.json")
        expect = "not valid JSON"
    elif case == "bad-field":
        (tmp_path / "bad.json").write_text('{"lights": [{"position": [0,0,1], "direction": [0,0,-1], '
                                           '"cone": {"angle_deg": 120}}]}')
        args[3] = str(tmp_path / "bad.json")
        expect = "lights[0].cone.angle_deg"
    elif case == "unknown-view":
        args += ["--view", "sideways"]
        expect = "unknown view 'sideways'"
    elif case == "unwritable":
        args[5] = str(tmp_path / "no" / "such" / "o.png")
        expect = "cannot write the picture there"
    elif case == "missing-input":
        args[1] = str(tmp_path / "nothing.step")
        expect = "no such file"
    else:
        args[2:4] = ["--preset", "noir"]
        expect = "unknown preset"
    r = _occsurf(*args, cwd=tmp_path)
    assert r.returncode == 2
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and expect in lines[0], r.stderr
    assert "Traceback" not in r.stderr
    assert not (tmp_path / "o.png").exists()


def test_back_faces_follow_two_sided() -> None:
    """Seen from below, the plane lit from above: two-sided lights its back like its front (as the
    reference does), one-sided shows ambient only."""
    P, T, N = _plane()
    light = WarnLight(position=(0.0, 0.0, -6.0), direction=(0, 0, 1))  # below the plane, facing its back
    cam = lighting.Camera(position=(0.0, -3.0, -15.0), target=(0.0, 0.0, 0.0), up=(0.0, 1.0, 0.0))
    mat = Material(color=(1, 1, 1), specular=0.0)
    two = lighting.render_lit(P, T, LightingSetup(lights=(light,), ambient=0.1, material=mat), normals=N,
                              size=SIZE, camera=cam)
    one_setup = LightingSetup(lights=(light,), ambient=0.1, material=mat, two_sided=False)
    one = lighting.render_lit(P, T, one_setup, normals=N, size=SIZE, camera=cam)
    inner = binary_erosion(two.covered, iterations=2)
    assert two.rgb[inner].mean() > 100
    assert np.all(np.abs(one.rgb[inner].astype(int) - 26) <= 1)
    _compare(two, LightingSetup(lights=(light,), ambient=0.1, material=mat),
             lambda W: np.broadcast_to([0.0, 0.0, 1.0], W.shape), levels=2)


def test_bspline_surface_matches_the_reference() -> None:
    """A curved B-spline surface (exact grid points and normals) against shade() at the pixels'
    positions, with the normal of the exact surface found by projecting each pixel's point."""
    from occsurf.algorithms import BSplineSurface

    k = np.array([0.0] * 4 + [1.0] * 4)
    x, y = np.meshgrid(np.linspace(-2, 2, 4), np.linspace(-2, 2, 4), indexing="ij")
    z = 0.6 - 0.15 * (x ** 2 + y ** 2)  # a cap: the bicubic interpolant of a paraboloid's net
    surf = BSplineSurface(degree=(3, 3), knots=(k, k), control_points=np.stack([x, y, z], -1))
    setup = studio_three_point([0, 0, 0], 5.0)
    img = lighting.render_surfaces_lit(surf, setup, resolution=201, size=SIZE, view="iso")
    assert img.covered.mean() > 0.2
    u = np.linspace(0, 1, 401)
    D = surf.derivatives(*np.meshgrid(u, u, indexing="ij"), 1).reshape(-1, 2, 2, 3)
    pts, nrm = D[:, 0, 0], np.cross(D[:, 1, 0], D[:, 0, 1])
    from scipy.spatial import cKDTree

    tree = cKDTree(pts)
    _compare(img, setup, lambda W: nrm[tree.query(W)[1]], levels=4)
    with pytest.raises(ValueError, match="surfaces"):
        lighting.render_surfaces_lit([], setup)


def test_concentration_ratio_renders_as_warns_exponent() -> None:
    """A lights file counting concentration from 1 (concentration_ratio C = n + 1) gives the same
    picture as Warn's exponent n; C = 1 the same as the plain light."""
    from occsurf.algorithms.lighting import setup_from_dict

    P, T, N = _plane()

    def picture(**control):
        light = {"position": [0.5, -1.0, 6.0], "direction": [0.0, 0.2, -1.0], **control}
        return lighting.render_lit(P, T, setup_from_dict({"lights": [light]}), normals=N, size=SIZE, view="top").rgb

    np.testing.assert_array_equal(picture(concentration_ratio=13), picture(concentration=12))
    np.testing.assert_array_equal(picture(concentration_ratio=1), picture())
    assert np.abs(picture(concentration_ratio=13).astype(int) - picture().astype(int)).max() > 50
