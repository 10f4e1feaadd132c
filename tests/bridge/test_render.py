"""occsurf.bridge.rendering.surfaces writes curvature-coloured PNGs of any sampled surface."""

from __future__ import annotations

import numpy as np
import pytest

from occsurf.algorithms import BSplineSurface, circle
from occsurf.algorithms.fitting.interpolation import loft
from occsurf.bridge.rendering.surfaces import render_surfaces, surface_grid


def _vase() -> BSplineSurface:
    return loft([circle([0, 0, z], 1 + 0.3 * np.sin(2 * z), [0, 0, 1]) for z in np.linspace(0, 3, 5)])


def test_surface_grid_curvature_of_a_sphere_like_section():
    # a loft of equal circles is a cylinder: mean curvature -1/(2r) or +1/(2r) by orientation, K = 0
    s = loft([circle([0, 0, z], 2.0, [0, 0, 1]) for z in (0.0, 1.0, 2.0)], degree=1)
    P, n, H = surface_grid(s, 20, "mean")
    assert P.shape == n.shape == (20, 20, 3) and H.shape == (20, 20)
    np.testing.assert_allclose(np.abs(H), 0.25, rtol=1e-9)  # closed form, round-off only
    _, _, K = surface_grid(s, 20, "gaussian")
    np.testing.assert_allclose(K, 0.0, atol=1e-12)


@pytest.mark.parametrize("color", ["mean", "gaussian", "height", "none"])
def test_render_writes_png(tmp_path, color):
    s = _vase()
    grid = surface_grid(s, 15, "height")
    out = render_surfaces(tmp_path / f"{color}.png", [s, grid], color=color, title="t",
                          curves=[circle([0, 0, 0], 1.0, [0, 0, 1])], nets=[s.control_points],
                          views=((30, -60), (60, 20)), panel_titles=["a", "b"], resolution=20)
    data = out.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 20_000


def test_render_rejects_unknown_colouring(tmp_path):
    with pytest.raises(ValueError, match="color"):
        render_surfaces(tmp_path / "x.png", [_vase()], color="rainbow")


def _wave() -> BSplineSurface:
    """z = 0.3 sin(2 pi x) over the unit square, near enough: mean curvature < 0 on the crest
    (x ~ 1/4) and > 0 in the trough (x ~ 3/4) for the upward normal."""
    from occsurf.algorithms.fitting.gridded import fit_grid

    x = np.linspace(0, 1, 41)
    X, Y = np.meshgrid(x, x, indexing="ij")
    return fit_grid(np.stack([X, Y, 0.3 * np.sin(2 * np.pi * X)], -1), (12, 4), (3, 3)).surface


def _pixels(path) -> np.ndarray:
    import matplotlib.pyplot as plt

    img = plt.imread(path)
    return np.round(img[..., :3] * 255).astype(int)


def test_the_surface_is_drawn_in_its_curvature_colours(tmp_path):
    """Seen from above, the wave's crest and trough show the diverging map's two ends (blue where
    H < 0, red where H > 0: saturated colours no background, bar or grey surface has); without
    colouring neither appears."""
    s = _wave()
    H = surface_grid(s, 30, "mean")[2]
    assert H.min() < -0.5 and H.max() > 0.5
    counts = {}
    for color in ("mean", "none"):
        img = _pixels(render_surfaces(tmp_path / f"{color}.png", [s], color=color, views=((89.0, -90.0),)))
        r, g, b = img[..., 0], img[..., 1], img[..., 2]
        counts[color] = (int(np.sum((r > b + 80) & (r > g + 60))), int(np.sum((b > r + 80) & (b > g + 40))))
    total = img.shape[0] * img.shape[1]
    assert min(counts["mean"]) > 0.01 * total, counts  # the bar alone is < 0.3 % of the picture
    assert max(counts["none"]) == 0, counts


def test_panels_framed_on_one_box_compare_at_one_scale():
    """``Panel.frame``: a panel framed on a box three times the surface's shows it smaller, by about
    the square of the ratio in area (perspective: not exactly)."""
    from matplotlib.colors import Normalize

    from occsurf.bridge.rendering import surfaces as R
    from occsurf.bridge.rendering.vtk_scene import render_available

    if not render_available():
        pytest.skip("VTK cannot open an offscreen window here")
    grid = surface_grid(_wave(), 20, "height")
    box = np.array([[-1.0, -1.0, -1.0], [2.0, 2.0, 2.0]])
    red = lambda v: np.tile([0.9, 0.05, 0.05, 1.0], (len(v), 1))  # noqa: E731
    areas = []
    for frame in (None, box):
        img = R._render_view(R.Panel([grid], view=(89.0, -90.0), frame=frame), Normalize(0, 1), red, (300, 300))
        r, g, b = (img[..., k].astype(int) for k in range(3))
        areas.append(int(np.sum((r > g + 60) & (r > b + 60))))
    assert areas[0] > 0.3 * 300 * 300 and 0.03 < areas[1] / areas[0] < 0.3, areas


def test_no_model_is_shaded_by_matplotlib():
    """House rule: shaded pictures come from VTK; matplotlib draws charts and lays pictures out.
    No module of the package (or the docs' gallery) builds a 3-D matplotlib axes."""
    from pathlib import Path

    root = Path(__file__).resolve().parents[2]
    files = [p for d in ("algorithms", "bridge", "examples", "docs/gallery") for p in (root / d).rglob("*.py")]
    assert len(files) > 100
    bad = [str(p.relative_to(root)) for p in files
           if any(s in p.read_text(encoding="utf-8") for s in ("mplot3d", 'projection="3d"', "projection='3d'"))]
    assert bad == []
