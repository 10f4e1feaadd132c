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
