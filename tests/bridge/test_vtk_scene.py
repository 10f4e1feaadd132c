"""The VTK offscreen renderer (occsurf.bridge.rendering.vtk_scene) and the triangulated faces it draws.

Every picture is rendered with no display (EGL offscreen) and judged by its pixels: not blank
(many pixels differ from the background, several colours), the legend present (the colour map's
two end colours in the scalar bar's strip on the right), stripes per pixel (many black/white
alternations along a row), cameras that differ.
"""

from __future__ import annotations

import numpy as np
import pytest

from occsurf.bridge.rendering import vtk_scene
from occsurf.bridge.rendering.vtk_scene import COLORMAPS, Scene, colormap_rgb

pytestmark = pytest.mark.skipif(not vtk_scene.render_available(), reason="VTK cannot open an offscreen window here")

SIZE = (400, 300)


def _sphere(n: int = 40, r: float = 1.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A UV sphere: points, triangles, outward normals (closed form)."""
    th, ph = np.meshgrid(np.linspace(0.05, np.pi - 0.05, n), np.linspace(0, 2 * np.pi, 2 * n), indexing="ij")
    N = np.stack([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)], -1).reshape(-1, 3)
    k = np.arange(n * 2 * n).reshape(n, 2 * n)
    a, b, c, d = k[:-1, :-1].ravel(), k[1:, :-1].ravel(), k[1:, 1:].ravel(), k[:-1, 1:].ravel()
    T = np.concatenate([np.column_stack([a, b, c]), np.column_stack([a, c, d])])
    return r * N, T, N


def _background_share(img: np.ndarray) -> float:
    """Share of pixels that are the gradient background (light blue-grey to white, r <= g <= b)."""
    r, g, b = (img[..., k].astype(int) for k in range(3))
    return float(np.mean((r >= 200) & (b >= r) & (b - r <= 25) & (abs(g - (r + b) / 2) <= 8)))


def _is_picture(img: np.ndarray, min_object: float = 0.05) -> None:
    assert img.dtype == np.uint8 and img.shape == (SIZE[1], SIZE[0], 3)
    assert 1 - _background_share(img) > min_object, "almost only background"
    assert len(np.unique(img.reshape(-1, 3) // 8, axis=0)) > 20, "too few colours: flat or blank"


def _legend_present(img: np.ndarray, cmap: str) -> None:
    """Both end colours of the map appear in the right-hand strip where the scalar bar sits."""
    strip = img[:, int(0.84 * img.shape[1]):, :].reshape(-1, 3).astype(int)
    ends = np.array(COLORMAPS[cmap])[[0, -1]] * 255
    for end in ends:
        assert np.min(np.abs(strip - end).sum(axis=1)) < 30, f"legend end colour {end} missing"


def test_scalar_map_with_legend() -> None:
    P, T, N = _sphere()
    s = Scene()
    s.add_mesh(P, T, normals=N, scalars=P[:, 2], cmap="diverging", scale=(-1, 1))
    s.set_legend("z", -1, 1, cmap="diverging")
    img = s.render_array(size=SIZE)
    _is_picture(img)
    _legend_present(img, "diverging")
    # without the legend the strip holds background only
    s2 = Scene()
    s2.add_mesh(P, T, normals=N, scalars=P[:, 2], cmap="diverging", scale=(-1, 1))
    img2 = s2.render_array(size=SIZE)
    assert _background_share(img2[:, int(0.9 * SIZE[0]):]) > 0.97


@pytest.mark.parametrize("cmap", ["rainbow", "sequential"])
def test_other_maps_and_legend(cmap: str) -> None:
    P, T, N = _sphere()
    s = Scene()
    s.add_mesh(P, T, normals=N, scalars=P[:, 0], cmap=cmap, scale=(-1, 1))
    s.set_legend("x", -1, 1, cmap=cmap)
    img = s.render_array(size=SIZE)
    _is_picture(img)
    _legend_present(img, cmap)


@pytest.mark.parametrize("shader", ["zebra", "isophote"])
def test_per_pixel_stripes(shader: str) -> None:
    P, T, N = _sphere(16)  # coarse mesh: the stripes must still be sharp, per pixel
    s = Scene()
    s.add_mesh(P, T, normals=N, shader=shader, stripes=8)
    img = s.render_array(size=SIZE, camera="front")
    _is_picture(img)
    grey = img.mean(axis=2)
    obj = grey[SIZE[1] // 2]
    dark, light = obj < 60, obj > 200
    assert dark.sum() > 20 and light.sum() > 20, "no black and white stripes"
    flips = np.count_nonzero(np.diff(dark[dark | light].astype(int)))
    assert flips >= 4, f"only {flips} stripe edges along the middle row"


def test_nan_scalars_are_magenta_not_a_scale_colour() -> None:
    P, T, N = _sphere()
    vals = P[:, 2].copy()
    vals[P[:, 2] > 0.6] = np.nan  # a degenerate cap
    s = Scene()
    s.add_mesh(P, T, normals=N, scalars=vals, cmap="diverging", scale=(-1, 1))
    img = s.render_array(size=SIZE, camera="front").astype(int)
    magenta = (img[..., 0] > 120) & (img[..., 2] > 120) & (img[..., 1] < 60)
    assert magenta.mean() > 0.005


def test_lines_points_hedgehog_and_rgb() -> None:
    P, T, N = _sphere()
    s = Scene()
    s.add_mesh(P, T, normals=N, colors=(np.abs(N) * 255).astype(np.uint8))
    t = np.linspace(0, 2 * np.pi, 100)
    s.add_lines([np.column_stack([1.3 * np.cos(t), 1.3 * np.sin(t), 0 * t])], color=(0, 0, 0), width=3)
    s.add_points(np.array([[0, 0, 1.2]]), color=(1, 0, 0), size=14)
    s.add_hedgehog(P[::50], N[::50], length=0.4, color=(0, 0, 1))
    s.set_title("lines, points, hedgehog")
    img = s.render_array(size=SIZE, camera="top")
    _is_picture(img)
    black = (img.max(axis=2) < 40).mean()
    assert black > 0.002  # the circle and the title
    blue = (img[..., 2] > 150) & (img[..., 0] < 60) & (img[..., 1] < 60)
    assert blue.sum() > 30  # hedgehog


def test_cameras_differ_and_png_written(tmp_path) -> None:
    P, T, N = _sphere()
    P = P * np.array([3.0, 1.0, 0.5])  # an ellipsoid: every view differs
    s = Scene()
    s.add_mesh(P, T, normals=N, scalars=P[:, 0], cmap="rainbow")
    imgs = {c: s.render_array(size=SIZE, camera=c) for c in vtk_scene.CAMERAS}
    for a in imgs:
        for b in imgs:
            if a < b:
                assert np.abs(imgs[a].astype(int) - imgs[b].astype(int)).mean() > 2, (a, b)
    path = s.render(tmp_path / "e.png", size=SIZE, camera=(1.0, 2.0, 3.0))
    from PIL import Image

    with Image.open(path) as im:
        assert im.size == SIZE


def test_colormap_rgb_matches_table_and_nan() -> None:
    rgb = colormap_rgb(np.array([-1.0, 0.0, 1.0, np.nan, 5.0]), -1.0, 1.0, "diverging")
    ends = np.round(np.array(COLORMAPS["diverging"])[[0, -1]] * 255)
    assert np.abs(rgb[0] - ends[0]).max() <= 1 and np.abs(rgb[2] - ends[1]).max() <= 1
    assert tuple(rgb[3]) == (255, 0, 255)
    assert np.array_equal(rgb[4], rgb[2])  # clipped


def test_bad_input() -> None:
    P, T, N = _sphere(8)
    s = Scene()
    with pytest.raises(ValueError, match="points"):
        s.add_mesh(P[:, :2], T)
    with pytest.raises(ValueError, match="scalars"):
        s.add_mesh(P, T, scalars=np.zeros(3))
    with pytest.raises(ValueError, match="cmap"):
        s.add_mesh(P, T, scalars=P[:, 0], cmap="nope")
    with pytest.raises(ValueError, match="shader"):
        s.add_mesh(P, T, normals=N, shader="nope")
    with pytest.raises(ValueError, match="normals"):
        s.add_mesh(P, T, shader="zebra")
    s.add_mesh(P, T)
    with pytest.raises(ValueError, match="camera"):
        s.render_array(size=SIZE, camera="nope")
    with pytest.raises(ValueError, match="size"):
        s.render_array(size=(4, 4))


# ---------------------------------------------------------------------------------------- one window and camera path
def _vtk_reset_and_zoom(direction, up, lo, hi, aspect, legend, zoom):
    """The oracle: VTK's own ResetCamera + vtkCamera.Zoom + the legend's shift, as the Scene framed
    its pictures before fit_camera computed it (a renderer in a window of that aspect)."""
    from vtkmodules.vtkRenderingCore import vtkActor, vtkPolyDataMapper, vtkRenderer

    w, h = (300, int(round(300 / aspect))) if aspect >= 1 else (int(round(300 * aspect)), 300)
    win = vtk_scene.window(w, h)
    ren = vtkRenderer()
    corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
    mapper = vtkPolyDataMapper()
    mapper.SetInputData(vtk_scene.polydata(corners, [np.arange(8)], "lines"))
    actor = vtkActor()
    actor.SetMapper(mapper)
    ren.AddActor(actor)
    win.AddRenderer(ren)
    try:
        centre = (np.asarray(lo) + np.asarray(hi)) / 2
        radius = max(float(np.linalg.norm(np.subtract(hi, lo))) / 2, 1e-9)
        d = np.asarray(direction, float) / np.linalg.norm(direction)
        cam = ren.GetActiveCamera()
        cam.SetFocalPoint(*centre)
        cam.SetPosition(*(centre + d * radius * 4.0))
        cam.SetViewUp(*up)
        cam.SetViewAngle(30.0)
        ren.ResetCamera()
        V = vtk_scene.vtk_matrix(cam.GetViewTransformMatrix())
        c = np.c_[corners, np.ones(8)] @ V.T
        depth = np.maximum(-c[:, 2], 1e-12)
        half = np.tan(np.radians(cam.GetViewAngle()) / 2)
        share = 0.80 if legend else 0.94
        need = max(float(np.max(np.abs(c[:, 1]) / depth)) / (0.94 * half),
                   float(np.max(np.abs(c[:, 0]) / depth)) / (share * half * aspect), 1e-9)
        cam.Zoom(zoom / need)
        if legend:
            right = np.cross(np.array(cam.GetDirectionOfProjection()), np.array(cam.GetViewUp()))
            shift = right * (-(1 - share) * half * aspect * cam.GetDistance() / (zoom / need))
            cam.SetFocalPoint(*(np.array(cam.GetFocalPoint()) - shift))
            cam.SetPosition(*(np.array(cam.GetPosition()) - shift))
        return np.array(cam.GetPosition()), np.array(cam.GetFocalPoint()), cam.GetViewAngle()
    finally:
        win.RemoveRenderer(ren)


@pytest.mark.parametrize("view", ["iso", "top", "front", "right", (1.0, 2.0, 3.0), (0.0, 0.1, 1.0)])
@pytest.mark.parametrize("aspect, legend, zoom", [(4 / 3, False, 1.0), (4 / 3, True, 1.3), (0.75, True, 1.0)])
def test_scene_framing_is_vtks_reset_camera_and_zoom(view, aspect, legend, zoom) -> None:
    """fit_camera(keep_distance=True) computes what VTK's ResetCamera + Zoom did for the Scene (the
    pictures of occsurf check and fit stay as they were), to round-off."""
    lo, hi = np.array([-3.0, -1.0, -0.5]), np.array([3.0, 1.2, 0.5])
    direction, up = vtk_scene.VIEWS[view] if isinstance(view, str) else (view, None)
    cam = vtk_scene.fit_camera(view, lo, hi, aspect, keep_distance=True, width_share=0.80 if legend else 0.94,
                               shift_left=legend, zoom=zoom)
    if up is None:
        up = cam.up
    pos, focal, angle = _vtk_reset_and_zoom(direction, up, lo, hi, aspect, legend, zoom)
    scale = float(np.linalg.norm(hi - lo))
    np.testing.assert_allclose(cam.position, pos, atol=1e-12 * scale * 10)
    np.testing.assert_allclose(cam.target, focal, atol=1e-12 * scale * 10)
    assert abs(cam.view_angle - angle) <= 1e-12 * angle


def test_one_window_cache_for_scenes_and_warn_pictures() -> None:
    """The Warn renderer draws in the Scene's cached windows (one per size and multisampling) with
    the same cameras: no second window or camera code path."""
    from occsurf.algorithms.lighting import studio_three_point
    from occsurf.bridge.rendering import lighting

    assert lighting._window is vtk_scene.window and lighting.Camera is vtk_scene.Camera
    assert lighting.VIEWS is vtk_scene.VIEWS and lighting.render_available is vtk_scene.render_available
    P, T, N = _sphere()
    s = Scene()
    s.add_mesh(P, T, normals=N)
    s.render_array(size=(208, 160))
    win = vtk_scene.window(208, 160)
    lighting.render_lit(P, T, studio_three_point([0, 0, 0], 2.0), normals=N, size=(208, 160), samples=0)
    assert vtk_scene.window(208, 160) is win and win.GetRenderers().GetNumberOfItems() == 0
    lighting.render_lit(P, T, studio_three_point([0, 0, 0], 2.0), normals=N, size=(208, 160), samples=4)
    assert vtk_scene.window(208, 160, 4) is not win and vtk_scene.window(208, 160, 4).GetMultiSamples() == 4
    cam = lighting.camera_for_view("top", P.min(axis=0), P.max(axis=0), 1.3)
    assert cam == vtk_scene.fit_camera("top", P.min(axis=0), P.max(axis=0), 1.3)
    with pytest.raises(ValueError, match="camera: expected one of iso, top, bottom"):
        s.render_array(size=(208, 160), camera="diagonal")


@pytest.mark.parametrize("cmap", [*COLORMAPS, "stripes"])
def test_lookup_tables_map_as_entry_by_entry_tables(cmap: str) -> None:
    """``_lut`` sets its RGBA bytes at once (``SetTable``); a table filled entry by entry with
    ``SetTableValue``, as it was, gives every value the same colour and opacity: across the range,
    outside it, NaN and infinities, for a range and for a single value."""
    from vtkmodules.vtkCommonCore import vtkLookupTable

    for stripes in (1, 5):
        for lo, hi in ((-1.0, 2.0), (0.3, 0.3)):
            table = vtk_scene._table(cmap, stripes)
            ref = vtkLookupTable()
            ref.SetNumberOfTableValues(len(table))
            for k, (r, g, b) in enumerate(table):
                ref.SetTableValue(k, float(r), float(g), float(b), 1.0)
            ref.SetRange(lo, hi if hi > lo else lo + 1.0)
            ref.SetNanColor(*vtk_scene.NAN_COLOR, 1.0)
            ref.Build()
            lut = vtk_scene._lut(cmap, lo, hi, stripes)
            for v in np.r_[np.linspace(-2.0, 3.0, 501), np.nan, -np.inf, np.inf]:
                got, want = [0.0] * 3, [0.0] * 3
                lut.GetColor(float(v), got)
                ref.GetColor(float(v), want)
                assert got == want and lut.GetOpacity(float(v)) == ref.GetOpacity(float(v)), (cmap, stripes, v)


def test_compact_cells_and_float32_normals_draw_the_same_picture(tmp_path, monkeypatch) -> None:
    """Issue 28 (memory): a mesh's triangles are stored with 32-bit ids, its normals as float32 and
    of every prop only its extent is kept for framing (the 1089-face plate's model pictures held its
    1.8 million points twice, and 64-bit cells). The cells are the same, and so are the pictures,
    byte for byte, against 64-bit cells and float64 normals (as ``polydata`` makes them by default)."""
    import vtkmodules.util.numpy_support as ns
    from vtkmodules.util.numpy_support import vtk_to_numpy

    P, T, N = _sphere()
    compact, wide = vtk_scene.polydata(P, T, "triangles", ids32=True), vtk_scene.polydata(P, T, "triangles")
    assert not compact.GetPolys().IsStorage64Bit() and wide.GetPolys().IsStorage64Bit()
    for get in ("GetConnectivityArray", "GetOffsetsArray"):
        a, b = (vtk_to_numpy(getattr(pd.GetPolys(), get)()) for pd in (compact, wide))
        assert a.dtype == np.int32 and np.array_equal(a, b)

    def draw(path):
        s = Scene()
        s.add_mesh(P, T, normals=N, scalars=P[:, 2], cmap="diverging")
        s.add_lines([P[:50]], color=(0.1, 0.1, 0.1))
        s.add_points(P[::97])
        s.render(path, size=SIZE)
        return path.read_bytes()

    new = draw(tmp_path / "new.png")
    real_polydata, real_to_vtk = vtk_scene.polydata, ns.numpy_to_vtk
    monkeypatch.setattr(vtk_scene, "polydata", lambda p, c, k, ids32=False: real_polydata(p, c, k))  # 64-bit cells
    monkeypatch.setattr(ns, "numpy_to_vtk", lambda a, deep=False, array_type=None: real_to_vtk(  # float64 normals
        np.ascontiguousarray(a, np.float64) if np.asarray(a).dtype == np.float32 else a, deep=deep, array_type=array_type))
    old = draw(tmp_path / "old.png")
    probe = Scene()
    probe.add_mesh(P, T, normals=N)
    actors = probe._renderer.GetActors()
    actors.InitTraversal()
    pd = actors.GetNextActor().GetMapper().GetInput()
    assert pd.GetPointData().GetNormals().GetDataTypeAsString() == "double" and pd.GetPolys().IsStorage64Bit()
    assert new == old and len(new) > 1000


def _add_at_normals(P: np.ndarray, T: np.ndarray) -> np.ndarray:
    """The fallback normals as they were summed before 2026-12-06 (np.add.at, corner by corner)."""
    fn = np.cross(P[T[:, 1]] - P[T[:, 0]], P[T[:, 2]] - P[T[:, 0]])
    N = np.zeros_like(P)
    for k in range(3):
        np.add.at(N, T[:, k], fn)
    length = np.linalg.norm(N, axis=1, keepdims=True)
    with np.errstate(all="ignore"):
        return np.where(length > 0, N / length, np.array([0.0, 0.0, 1.0]))


@pytest.mark.parametrize("seed", range(12))
def test_fallback_normals_of_the_degenerate_vertices_alone_are_the_whole_meshs(seed: int) -> None:
    """``_vertex_normals`` sums by ``np.bincount`` in np.add.at's order, and with ``at`` only over the
    triangles touching the wanted vertices: those rows are bit for bit the whole mesh's (random
    meshes, repeated and degenerate triangles, isolated vertices)."""
    rng = np.random.default_rng(seed)
    n, m = int(rng.integers(3, 400)), int(rng.integers(1, 900))
    P = rng.normal(size=(n, 3)) * 10.0 ** rng.integers(-3, 4)
    T = rng.integers(0, n, (m, 3))
    T[: m // 10] = T[0]  # repeated triangles
    P[T[-1]] = P[T[-1, 0]]  # a collapsed one
    ref = _add_at_normals(P, T)
    assert np.array_equal(vtk_scene._vertex_normals(P, T), ref)
    at = rng.random(n) < 0.1
    at[T[-1]] = True
    assert np.array_equal(vtk_scene._vertex_normals(P, T, at)[at], ref[at])
