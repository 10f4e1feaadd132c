"""occsurf.bridge.rendering.surfaces writes curvature-coloured PNGs of any sampled surface."""

from __future__ import annotations

import numpy as np
import pytest

from occsurf.algorithms import BSplineSurface, circle
from occsurf.algorithms.fitting.interpolation import loft
from occsurf.bridge.rendering.surfaces import render_surfaces, surface_grid
from occsurf.bridge.rendering.vtk_scene import render_available

needs_vtk = pytest.mark.skipif(not render_available(), reason="VTK cannot open an offscreen window here")


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



@pytest.mark.parametrize("color", ["mean", "gaussian"])
def test_surface_grid_is_the_point_by_point_curvature_to_round_off(color):
    """``surface_grid`` takes the partials on the grid (``derivatives_grid``) rather than point by
    point: its normals and curvatures are ``surface_curvatures``' at the same (u, v) to round-off
    (1e-12 of the largest principal curvature, its square for the Gaussian; normals 1e-12), on a rational vase and a wave."""
    from occsurf.algorithms.geometry.surface_differential import surface_curvatures

    for s in (_vase(), _wave()):
        P, n, val = surface_grid(s, 31, color)
        (u0, u1), (v0, v1) = s.domain
        eu, ev = 1e-6 * (u1 - u0), 1e-6 * (v1 - v0)
        U, W = np.meshgrid(np.linspace(u0 + eu, u1 - eu, 31), np.linspace(v0 + ev, v1 - ev, 31), indexing="ij")
        sc = surface_curvatures(s, U, W)
        ref = np.asarray(sc.mean if color == "mean" else sc.gaussian, float)
        assert np.isfinite(ref).all()
        k = np.abs(np.asarray([sc.k1, sc.k2])).max()  # the curvature's scale (K's is its square)
        np.testing.assert_allclose(val, ref, rtol=0, atol=1e-12 * (k if color == "mean" else k * k))
        np.testing.assert_allclose(n, np.asarray(sc.normal), rtol=0, atol=1e-12)
        np.testing.assert_allclose(P, s.evaluate(U, W), rtol=0, atol=1e-13)

@needs_vtk
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


@needs_vtk
def test_the_surface_is_drawn_in_its_curvature_colours(tmp_path):
    """Seen from above (+x to the right), the wave's crest (x ~ 1/4, H < 0) is blue and its trough
    (x ~ 3/4, H > 0) red, the diverging map's two ends (saturated colours no background, bar or
    grey surface has); without colouring neither appears."""
    s = _wave()
    H = surface_grid(s, 30, "mean")[2]
    assert H.min() < -0.5 and H.max() > 0.5
    counts = {}
    for color in ("mean", "none"):
        img = _pixels(render_surfaces(tmp_path / f"{color}.png", [s], color=color, views=((89.0, -90.0),)))
        r, g, b = img[..., 0], img[..., 1], img[..., 2]
        red, blue = (r > b + 80) & (r > g + 60), (b > r + 80) & (b > g + 40)
        counts[color] = (int(red.sum()), int(blue.sum()))
        if color == "mean":
            cols = np.broadcast_to(np.arange(img.shape[1])[None, :], red.shape)
            panel = cols < 0.8 * img.shape[1]  # the colour bar stands right of it
            x_red, x_blue = (float(cols[panel & m].mean()) for m in (red, blue))
            assert x_red > x_blue + 0.1 * img.shape[1], (x_red, x_blue)
    total = img.shape[0] * img.shape[1]
    assert min(counts["mean"]) > 0.01 * total, counts  # the bar alone is < 0.3 % of the picture
    assert max(counts["none"]) == 0, counts


@pytest.mark.parametrize("elev", [30.0, 60.0, 75.0, 80.0, 89.0, 90.0, -80.0])
@pytest.mark.parametrize("azim", [-60.0, 0.0, 25.0])
def test_views_are_matplotlibs(elev, azim):
    """``(elev, azim)`` as matplotlib's ``view_init``: the eye's direction, and +z shown upwards,
    square to the view; straight down (or up) the limit of that, with no jump near the pole (VTK's
    own choice, +y above 72 degrees, turned steep pictures by up to 90 degrees)."""
    from occsurf.bridge.rendering.surfaces import _view_axes

    d, up = (np.array(x) for x in _view_axes(elev, azim))
    e, a = np.radians(elev), np.radians(azim)
    np.testing.assert_allclose(d, [np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)], atol=1e-15)
    assert abs(np.linalg.norm(up) - 1) < 1e-12 and abs(up @ d) < 1e-12
    if abs(elev) < 90:
        assert up[2] > 0
    near = np.array(_view_axes(elev - 1e-6 * np.sign(elev), azim)[1])
    assert np.linalg.norm(up - near) < 1e-5  # continuous up to the pole


@needs_vtk
def test_a_steep_view_keeps_matplotlibs_up():
    """At (80, 0) the eye stands high on the +x side: a marker at -x shows above one at +x (VTK's
    default up, +y at that elevation, put them side by side)."""
    from matplotlib.colors import Normalize

    from occsurf.bridge.rendering import surfaces as R

    grid = surface_grid(_wave(), 10, "height")
    panel = R.Panel([grid], points=[(np.array([[-0.5, 0.5, 0.5]]), (0.9, 0.0, 0.0), 30.0),
                                    (np.array([[1.5, 0.5, 0.5]]), (0.0, 0.0, 0.9), 30.0)], view=(80.0, 0.0))
    img = R._render_view(panel, Normalize(0, 1), None, (300, 300)).astype(int)
    r, g, b = img[..., 0], img[..., 1], img[..., 2]
    rows_red, cols_red = np.nonzero((r > 150) & (g < 80) & (b < 80))
    rows_blue, cols_blue = np.nonzero((b > 150) & (r < 80) & (g < 80))
    assert rows_red.size and rows_blue.size
    assert rows_red.mean() < rows_blue.mean() - 40 and abs(cols_red.mean() - cols_blue.mean()) < 20


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
           if any(s in p.read_text(encoding="utf-8") for s in ("mplot3d", 'projection="3d"', "projection='3d'",
                                                               ".view_init(", "Axes3D", ".plot_surface(", ".plot_trisurf("))]
    assert bad == []


def test_bad_grids_views_and_panels_are_refused(tmp_path):
    """Sampled items must be grids (points (r, s, 3), normals alike, values (r, s)): points as a
    list, or values of another shape, are named, not drawn as slivers or half a surface; no view,
    no panel and a legend for a panel that is not there are refused before anything is drawn."""
    from matplotlib.lines import Line2D

    from occsurf.algorithms.errors import InvalidGeometryError
    from occsurf.bridge.rendering.surfaces import Panel, render_panels

    P, n, val = surface_grid(_wave(), 12, "height")
    flat = BSplineSurface((1, 1), ([0, 0, 1, 1], [0, 0, 1, 1]), np.zeros((2, 2, 2)))  # a 2-D surface
    with pytest.raises(InvalidGeometryError, match="surface: needs a 3-D BSplineSurface"):
        surface_grid(flat, 5)
    with pytest.raises(InvalidGeometryError, match=r"items\[0\]: expected points \(r, s, 3\)"):
        render_surfaces(tmp_path / "a.png", [(P.reshape(-1, 3), n.reshape(-1, 3), val.ravel())], color="height")
    with pytest.raises(InvalidGeometryError, match=r"items\[1\].*\(6, 12\)"):
        render_surfaces(tmp_path / "b.png", [(P, n, val), (P, n, val[:6])], color="height")
    with pytest.raises(ValueError, match="views: expected at least one"):
        render_surfaces(tmp_path / "c.png", [(P, n, val)], views=())
    with pytest.raises(ValueError, match="panels: expected at least one"):
        render_panels(tmp_path / "d.png", [])
    with pytest.raises(ValueError, match="legend_panel: expected a panel's index from -2 to 1, got 2"):
        render_panels(tmp_path / "e.png", [Panel([(P, n, val)]), Panel([(P, n, val)])],
                      legend=[("a", Line2D([], []))], legend_panel=2)
    assert not any((tmp_path / f"{c}.png").exists() for c in "abcde")


@needs_vtk
def test_nan_values_are_magenta_and_the_rest_keeps_its_colours(tmp_path):
    """A NaN value (a degenerate point's curvature) is drawn in ``vtk_scene.NAN_COLOR`` where it
    is; it neither blackens the surface (a NaN in the range made every vertex the map's 'bad'
    colour) nor stops the range of the others being found (``norm`` left to the values)."""
    from matplotlib import cm

    from occsurf.bridge.rendering import surfaces as R

    P, n, val = surface_grid(_wave(), 20, "height")
    val = val.copy()
    val[8:12, 8:12] = np.nan
    path = R.render_panels(tmp_path / "nan.png", [R.Panel([(P, n, val)], view=(89.0, -90.0))],
                           cmap=cm.viridis, colorbar_label="z")
    rgb = _pixels(path)
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    magenta = (r > 140) & (g < 90) & (b > 140) & (np.abs(r - b) < 40)  # shaded: ~(170, 0, 170)
    black = (r < 30) & (g < 30) & (b < 30)
    assert magenta.sum() > 50 and black.sum() < 0.01 * r.size, (int(magenta.sum()), int(black.sum()))


def test_an_up_along_the_view_is_refused_and_another_is_made_square():
    from occsurf.algorithms.errors import InvalidGeometryError
    from occsurf.bridge.rendering.cameras import fit_camera

    lo, hi = (0.0, 0.0, 0.0), (1.0, 1.0, 1.0)
    with pytest.raises(InvalidGeometryError, match="up: expected a direction across the view"):
        fit_camera((0.0, 0.0, 1.0), lo, hi, up=(0.0, 0.0, -2.0))
    cam = fit_camera((1.0, 0.0, 1.0), lo, hi, up=(0.0, 0.0, 1.0))
    np.testing.assert_allclose(cam.up, np.array([-1.0, 0.0, 1.0]) / np.sqrt(2), atol=1e-15)


@needs_vtk
def test_a_panel_s_grids_drawn_as_merged_meshes_give_the_picture_of_one_mesh_each(monkeypatch):
    """``_render_view`` hands its grids to VTK in groups of at most ``MERGED_VERTICES`` vertices
    (one actor per group; the generalized demo's S-patch panels had hundreds of actors). Drawn
    that way, with a group boundary falling between grids and a grid with a NaN normal (its
    fallback comes from its own triangles), the picture is the one drawn with one mesh per grid.
    Each tile has values of its own, so colours or points taken from the wrong grid show."""
    from matplotlib import cm
    from matplotlib.colors import Normalize

    from occsurf.bridge.rendering import surfaces as R

    grids = []
    for k in range(12):  # tiles of one wave, side by side, each its own grid and colours
        P, n, val = surface_grid(_wave(), 9, "height")
        P = P.copy()
        P[..., 0] += 1.05 * (k % 4)
        P[..., 1] += 1.05 * (k // 4)
        n = n.copy()
        if k == 5:
            n[4, 4] = np.nan
        grids.append((P, n, val + 0.15 * k))
    meshes = [(P.reshape(-1, 3), R._triangles(9, 9), n.reshape(-1, 3), np.zeros((81, 3))) for P, n, _ in grids]
    merged = R._merged(meshes)
    assert len(merged) == 1 and merged[0][1].max() == 12 * 81 - 1  # the default: one group, indices offset
    box = np.array([[0.0, 0.0, -1.0], [4.2, 3.2, 1.0]])
    panel = R.Panel(grids, view=(35.0, -60.0), frame=box)
    norm = Normalize(-0.3, 2.0)
    monkeypatch.setattr(R, "MERGED_VERTICES", 5 * 81 + 7)  # groups of 5, 5 and 2 grids
    assert [g[0].shape[0] for g in R._merged(meshes)] == [405, 405, 162]
    img = R._render_view(panel, norm, cm.viridis, (320, 240))
    monkeypatch.setattr(R, "MERGED_VERTICES", 1)  # one mesh per grid, as before
    one_each = R._render_view(panel, norm, cm.viridis, (320, 240))
    empty = R._render_view(R.Panel([], view=(35.0, -60.0), frame=box), norm, cm.viridis, (320, 240))
    assert (img != empty).any(axis=2).mean() > 0.2  # the tiles are drawn
    np.testing.assert_array_equal(img, one_each)
