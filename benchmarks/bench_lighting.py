"""Warn lighting (course ch. 10): per-pixel pictures and the NumPy reference, timed side by side.

Measured in one run, on a ~100k-triangle mesh (the demo's bicubic hood, ``grid_mesh`` 224 x 224:
98 898 triangles) and, when ``../shared/realdata/occt__linkrods.step`` is present, that model
meshed finely, each at 1600 x 1200 under three Warn lights (the studio preset with a cone and
flaps added to the key light):

* ``ours``: :func:`occsurf.bridge.rendering.lighting.render_lit` without and with 4x multisampling
  (``samples``; the numpy per-pixel column is without) - building the VTK mesh, the GLSL
  of this setup and camera, one render, reading back RGB and depth. ``cold`` is the first call in
  the process (OpenGL context and shader compilation included); ``warm`` the median of ``--repeat``
  further calls (each still builds its actor and shader). ``+png`` adds the atomic PNG write.
* ``vtk phong``: VTK's own Phong shading of the same mesh with three VTK spot lights (exponent and
  cone only: no flaps, no soft edge): the price of a plain render on this machine.
* ``numpy per-pixel``: the alternative design - world normals rendered into float buffers with
  ``vtkValuePass`` (one pass per component), positions from the depth buffer, then
  :func:`occsurf.algorithms.lighting.shade` on the covered pixels.

Then the reference alone: :func:`shade` on 2M random points with 1 and with 3 lights (M shaded
points/s; best of ``--repeat``), by its compiled kernel (numba) and by its NumPy path.

Run: ``python benchmarks/bench_lighting.py [--repeat 5] [--size 1600 1200]``. The machine has 2
cores and no GPU (Mesa llvmpipe renders on the CPU).
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))
REALDATA = REPO.parent / "shared" / "realdata"


def three_lights(center: np.ndarray, size: float):
    from occsurf.algorithms.lighting import LightingSetup, WarnLight, studio_three_point

    s = studio_three_point(center, size)
    key = s.lights[0]
    key = WarnLight(position=key.position, direction=key.direction, color=key.color, intensity=key.intensity,
                    concentration=key.concentration, cone_angle_deg=25.0, cone_edge_deg=5.0,
                    flaps={"y": [-0.3 * size, 0.3 * size]}, name="key")
    return LightingSetup(lights=(key, *s.lights[1:]), ambient=s.ambient, material=s.material)


def hood_mesh():
    from occsurf.bridge.rendering.tessellation import grid_mesh
    from occsurf.examples.lighting import demo_hood

    m = grid_mesh(demo_hood(), 224)
    return "hood (grid 224 x 224)", m.points, m.triangles, m.normals


def linkrods_mesh():
    path = REALDATA / "occt__linkrods.step"
    if not path.exists():
        return None
    from occsurf.bridge.exchange.step_iges import read_step
    from occsurf.bridge.rendering import tessellation
    from occsurf.bridge.rendering.lighting import mesh_of_model

    model = read_step(path)
    old = tessellation.LINEAR_DEFLECTION
    tessellation.LINEAR_DEFLECTION = 5e-5  # finer than the default, towards 100k triangles
    try:
        P, T, N = mesh_of_model(model)
    finally:
        tessellation.LINEAR_DEFLECTION = old
    return "occt__linkrods.step", P, T, N


def time_ours(P, T, N, setup, size, repeat, out: Path, samples: int):
    from occsurf.bridge.rendering.lighting import render_lit, write_png

    t0 = time.perf_counter()
    render_lit(P, T, setup, normals=N, size=size, view="iso", samples=samples)
    cold = time.perf_counter() - t0
    warm, with_png = [], []
    for _ in range(repeat):
        t0 = time.perf_counter()
        img = render_lit(P, T, setup, normals=N, size=size, view="iso", samples=samples)
        warm.append(time.perf_counter() - t0)
        write_png(out, img)
        with_png.append(time.perf_counter() - t0)
    return cold, statistics.median(warm), min(warm), statistics.median(with_png), img


def _vtk_scene(P, T, N, size, samples=0):
    from vtkmodules.vtkRenderingCore import vtkRenderer

    from occsurf.bridge.rendering import lighting as L
    from occsurf.bridge.rendering.cameras import apply_camera

    win = L._window(*size, samples)
    ren = vtkRenderer()
    actor = L._actor(P, T, N)
    ren.AddActor(actor)
    apply_camera(ren, L.camera_for_view("iso", P.min(axis=0), P.max(axis=0), size[0] / size[1]))
    return win, ren, actor


def time_vtk_phong(P, T, N, setup, size, repeat, samples):
    from vtkmodules.vtkCommonCore import vtkUnsignedCharArray
    from vtkmodules.vtkRenderingCore import vtkLight

    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        win, ren, _ = _vtk_scene(P, T, N, size, samples)
        for wl in setup.lights:
            light = vtkLight()
            light.SetPositional(True)
            light.SetPosition(*wl.position)
            light.SetFocalPoint(*(np.asarray(wl.position) + np.asarray(wl.direction)))
            light.SetExponent(max(wl.concentration, 1.0))
            light.SetConeAngle(wl.cone_angle_deg or 90.0)
            ren.AddLight(light)
        win.AddRenderer(ren)
        win.Render()
        px = vtkUnsignedCharArray()
        win.GetPixelData(0, 0, size[0] - 1, size[1] - 1, 0, px, 0)
        win.RemoveRenderer(ren)
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def time_numpy_per_pixel(P, T, N, setup, size, repeat):
    """Normals by vtkValuePass (3 passes), positions from depth, shade() in NumPy."""
    from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy
    from vtkmodules.vtkCommonCore import vtkFloatArray
    from vtkmodules.vtkRenderingOpenGL2 import vtkCameraPass, vtkRenderPassCollection, vtkSequencePass, vtkValuePass

    from occsurf.algorithms.lighting import shade
    from occsurf.bridge.rendering.lighting import LitImage, _matrix, pixel_world_points

    times, split = [], None
    w, h = size
    for _ in range(repeat):
        t0 = time.perf_counter()
        win, ren, actor = _vtk_scene(P, T, N, size)
        arr = numpy_to_vtk(np.ascontiguousarray(N, np.float32), deep=True)
        arr.SetName("nrm")
        actor.GetMapper().GetInput().GetPointData().AddArray(arr)
        vp = vtkValuePass()
        vp.SetInputArrayToProcess(3, "nrm")  # VTK_SCALAR_MODE_USE_POINT_FIELD_DATA
        seq, coll = vtkSequencePass(), vtkRenderPassCollection()
        coll.AddItem(vp)
        seq.SetPasses(coll)
        cp = vtkCameraPass()
        cp.SetDelegatePass(seq)
        ren.SetPass(cp)
        win.AddRenderer(ren)
        comps = []
        for c in range(3):
            vp.SetInputComponentToProcess(c)
            win.Render()
            comps.append(vtk_to_numpy(vp.GetFloatImageDataArray(ren)).reshape(h, w)[::-1].copy())
        ren.SetPass(None)  # the value pass draws into its own buffers: one plain pass for the depth
        win.Render()
        zf = vtkFloatArray()
        win.GetZbufferData(0, 0, w - 1, h - 1, zf)
        depth = vtk_to_numpy(zf).reshape(h, w)[::-1].copy()
        cam = ren.GetActiveCamera()
        matrix = _matrix(cam.GetCompositeProjectionTransformMatrix(w / h, -1, 1))
        win.RemoveRenderer(ren)
        t1 = time.perf_counter()
        img = LitImage(rgb=np.zeros((h, w, 3), np.uint8), depth=depth, camera=None, matrix=matrix)  # type: ignore[arg-type]
        W = pixel_world_points(img)
        cov = img.covered
        normals = np.stack(comps, axis=-1)[cov]
        rgb = shade(W[cov], normals, cam.GetPosition(), setup)
        out = np.zeros((h, w, 3), np.uint8)
        out[cov] = np.round(np.clip(rgb, 0, 1) * 255)
        times.append(time.perf_counter() - t0)
        split = (t1 - t0, time.perf_counter() - t1, int(cov.sum()))
    return statistics.median(times), split


def time_reference(repeat):
    """M shaded points/s of shade(): wall clock (threads as configured) and per CPU-second on one
    thread (``time.process_time``: what a quiet core would do; the machine is shared), float64 and
    float32, with 1 and 3 lights, by the compiled kernel (numba, when installed) and by the NumPy
    path (``OCCSURF_NO_NUMBA=1``) in the same run."""
    import os

    from occsurf.algorithms import tolerances
    from occsurf.algorithms.lighting import LightingSetup, shade

    rng = np.random.default_rng(0)
    P = rng.random((2_000_000, 3)) * 10
    N = rng.normal(size=(2_000_000, 3))
    setup = three_lights(np.array([5.0, 5.0, 5.0]), 17.0)
    rows = []
    for path in ("compiled", "numpy"):
        if path == "numpy":
            os.environ["OCCSURF_NO_NUMBA"] = "1"
        try:
            for dtype in (np.float64, np.float32):
                for k in (1, 3):
                    s = LightingSetup(lights=setup.lights[:k], ambient=0.05, material=setup.material)
                    shade(P[:100_000], N[:100_000], [5, -30, 20], s, dtype=dtype)  # compiles once per machine
                    wall = min(_timed(lambda s=s, dtype=dtype: shade(P, N, [5, -30, 20], s, dtype=dtype))
                               for _ in range(repeat))
                    with tolerances.override(LIGHT_THREADS=1):
                        cpu = min(_timed(lambda s=s, dtype=dtype: shade(P, N, [5, -30, 20], s, dtype=dtype), time.process_time)
                                  for _ in range(repeat))
                    rows.append((path, np.dtype(dtype).name, k, len(P) / wall / 1e6, len(P) / cpu / 1e6))
        finally:
            os.environ.pop("OCCSURF_NO_NUMBA", None)
    return rows


def _timed(f, clock=time.perf_counter) -> float:
    t0 = clock()
    f()
    return clock() - t0


def render_table(size, repeat, out: Path) -> None:
    meshes = [hood_mesh()]
    extra = linkrods_mesh()
    if extra is not None:
        meshes.append(extra)
    print(f"Warn lighting, {size[0]} x {size[1]}, 3 lights (concentration, cone with soft edge, flaps); "
          f"median of {repeat} (seconds)")
    print(f"{'model':28s} {'triangles':>9s} {'samples':>7s} {'ours cold':>9s} {'ours warm':>9s} {'(min)':>6s} "
          f"{'+png':>6s} {'vtk phong':>9s} {'numpy/pixel':>11s} {'ratio':>6s}")
    for name, P, T, N in meshes:
        setup = three_lights((P.min(axis=0) + P.max(axis=0)) / 2, float(np.linalg.norm(P.max(axis=0) - P.min(axis=0))))
        npx, split = time_numpy_per_pixel(P, T, N, setup, size, max(1, repeat // 2))
        for samples in (0, 4):
            cold, warm, best, png, _ = time_ours(P, T, N, setup, size, repeat, out, samples)
            phong = time_vtk_phong(P, T, N, setup, size, repeat, samples)
            print(f"{name:28s} {len(T):9d} {samples:7d} {cold:9.3f} {warm:9.3f} {best:6.3f} {png:6.3f} {phong:9.3f} "
                  f"{npx:11.3f} {npx / warm:5.1f}x")
        print(f"{'':28s} numpy per-pixel: {split[0]:.3f} s for 3 value passes + depth, {split[1]:.3f} s shading "
              f"{split[2]} pixels ({split[2] / split[1] / 1e6:.1f} M/s)")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--size", type=int, nargs=2, default=[1600, 1200])
    ap.add_argument("--only", choices=["render", "reference"], help="time one part only")
    ns = ap.parse_args()
    size = tuple(ns.size)
    import tempfile

    out = Path(tempfile.mkdtemp()) / "bench.png"
    if ns.only != "reference":
        render_table(size, ns.repeat, out)
    if ns.only == "render":
        return
    print(f"Reference shade(), 2M points, best of {ns.repeat} (M shaded points/s; compiled = the numba kernel, "
          f"numpy = OCCSURF_NO_NUMBA=1):")
    print(f"  {'path':9s} {'dtype':8s} {'lights':>6s} {'wall':>7s} {'1 thread, per CPU-s':>20s} {'vs numpy':>9s}")
    rows = time_reference(ns.repeat)
    numpy_wall = {(d, k): w for p, d, k, w, _ in rows if p == "numpy"}
    for path, dtype, k, wall, cpu in rows:
        print(f"  {path:9s} {dtype:8s} {k:6d} {wall:7.1f} {cpu:20.1f} {wall / numpy_wall[dtype, k]:8.1f}x")


if __name__ == "__main__":
    main()
