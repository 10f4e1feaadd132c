"""The report's pictures encoded and written on a background thread (``bridge.rendering.png``):
the same files as written at once, failures reported per picture, a bounded queue."""

from __future__ import annotations

import threading
import time
from pathlib import Path

import numpy as np
import pytest

from occsurf.bridge.rendering import png, vtk_scene


def _image(seed: int, shape: tuple[int, int] = (60, 80)) -> np.ndarray:
    rng = np.random.default_rng(seed)
    base = np.linspace(0, 255, shape[1])[None, :, None] * np.ones((shape[0], 1, 3))
    return np.clip(base + rng.integers(0, 40, (*shape, 3)), 0, 255).astype(np.uint8)


@pytest.mark.parametrize("threads", [0, 1, 2])
def test_background_files_equal_the_ones_written_at_once(tmp_path: Path, threads: int) -> None:
    from PIL import Image

    images = [_image(k) for k in range(6)]
    with png.PngWriter(threads=threads, pending=2) as writer:
        futures = [writer.write(tmp_path / f"bg_{k}.png", img) for k, img in enumerate(images)]
    for k, (fut, img) in enumerate(zip(futures, images)):
        assert fut.result() == tmp_path / f"bg_{k}.png"
        now = png.write_png_file(tmp_path / f"now_{k}.png", img)
        assert (tmp_path / f"bg_{k}.png").read_bytes() == now.read_bytes()
        assert np.array_equal(np.asarray(Image.open(now)), img)  # lossless


def test_a_failed_write_is_the_future_exception_and_leaves_nothing(tmp_path: Path) -> None:
    target = tmp_path / "kept.png"
    target.write_bytes(b"old")
    with png.PngWriter(threads=1) as writer:
        missing = writer.write(tmp_path / "no such folder" / "a.png", _image(0))
        bad = writer.write(target, np.zeros((4, 4, 7), np.uint8))  # not an image Pillow can encode
        good = writer.write(tmp_path / "b.png", _image(1))
    assert isinstance(missing.exception(), OSError)
    assert bad.exception() is not None and target.read_bytes() == b"old"  # the old file kept whole
    assert good.result().stat().st_size > 100
    assert sorted(p.name for p in tmp_path.iterdir()) == ["b.png", "kept.png"]  # no temporary left


def test_at_most_pending_images_wait(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """``write`` blocks once ``pending`` images wait: a slow disk does not queue a model's thousands."""
    active, most = [0], [0]
    lock = threading.Lock()
    original = png.write_png_file

    def slow(path, rgb, level=png.REPORT_PNG_LEVEL):
        with lock:
            active[0] += 1
            most[0] = max(most[0], active[0])
        time.sleep(0.02)
        try:
            return original(path, rgb, level)
        finally:
            with lock:
                active[0] -= 1

    monkeypatch.setattr(png, "write_png_file", slow)
    queued = []
    with png.PngWriter(threads=2, pending=3) as writer:
        for k in range(12):
            queued.append(writer.write(tmp_path / f"{k}.png", _image(k, (8, 8))))
            assert sum(not f.done() for f in queued) <= 3
    assert all(f.result().exists() for f in queued) and most[0] <= 2


@pytest.mark.skipif(not vtk_scene.render_available(), reason="VTK cannot open an offscreen window here")
def test_report_picture_that_fails_to_write_is_noted_on_its_face(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A picture whose file cannot be written is left out and noted (the face's row, or the
    report's warnings for a model picture); the others are written and recorded as before."""
    from occsurf.bridge.exchange.step_iges import read_step
    from occsurf.bridge.quality import pictures as P
    from occsurf.bridge.quality.report import check_model

    report = check_model(read_step(Path(__file__).resolve().parents[2] / "step_samples" / "loft.step"))
    original = png.write_png_file

    def failing(path, rgb, level=png.REPORT_PNG_LEVEL):
        if Path(path).name in ("face_0_zebra.png", "model_mean.png"):
            raise OSError(28, "No space left on device")
        return original(path, rgb, level)

    monkeypatch.setattr(png, "write_png_file", failing)
    faces = {report.faces[0].index}
    shown = P.render_report_pictures(report, tmp_path, faces=faces)
    assert "mean" not in shown and set(shown) == set(P.MODEL_PICTURES) - {"mean"}
    assert any(w.startswith("picture mean not drawn:") and "No space left" in w for w in report.warnings)
    row = report.faces[0]
    assert row.index == 0 and set(row.pictures) == set(P.FACE_PICTURES) - {"zebra"}
    failed = [n for n in row.notes if "not drawn" in n]
    assert len(failed) == 1 and failed[0].startswith("picture zebra not drawn:") and "No space left" in failed[0]
    assert not (tmp_path / "face_0_zebra.png").exists() and not (tmp_path / "model_mean.png").exists()
    assert {p.name for p in tmp_path.glob("*.png")} == set(shown.values()) | set(row.pictures.values())


@pytest.mark.skipif(not vtk_scene.render_available(), reason="VTK cannot open an offscreen window here")
@pytest.mark.parametrize("kind", ["mean", "zebra", "edges"])
def test_model_picture_of_merged_meshes_equals_one_mesh_per_face(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                                  kind: str) -> None:
    """The faces drawn as a few merged meshes (``pictures.MERGED_VERTICES``) give the picture of
    one mesh per face to rasterisation round-off: VTK shifts and scales each mesh's float32
    vertex buffer about its own bounds, so a few pixels on faces' borders and stripe edges, and
    colours one level apart, may differ. Measured on the OCCT bearing's eight model pictures:
    at most 0.4 % of the pixels differ, 12 of them by more than 2 levels (of 576 000)."""
    from PIL import Image

    from occsurf.bridge.exchange.step_iges import read_iges
    from occsurf.bridge.quality import pictures as P
    from occsurf.bridge.quality.report import check_model

    report = check_model(read_iges(Path(__file__).resolve().parents[2] / "step_samples" / "mixed.igs"))
    fields = [report.fields[k] for k in sorted(report.fields)]
    assert len(fields) > 3
    groups = list(P._merged_meshes(fields, "mean", limit=10**9))
    assert len(groups) == 1 and len(groups[0][0]) == sum(f.mesh.n_vertices for f in fields)
    pics = {}
    for label, limit in (("merged", 10**9), ("each", 1)):
        monkeypatch.setattr(P, "MERGED_VERTICES", limit)
        P.render_picture(fields, kind, tmp_path / f"{label}.png", model_size=report.size, edges=report.edge_lines)
        pics[label] = np.asarray(Image.open(tmp_path / f"{label}.png").convert("RGB")).astype(int)
    d = np.abs(pics["merged"] - pics["each"]).max(axis=2)
    assert (d > 0).mean() <= 0.02 and (d > 2).sum() <= 60, ((d > 0).mean(), int((d > 2).sum()))
    assert np.abs(pics["merged"] - 255).sum(axis=2).astype(bool).mean() > 0.1  # not blank


@pytest.mark.parametrize("shape", [(1, 1, 3), (5, 7, 3), (5, 7, 4), (5, 7), (64, 90, 3)])
def test_encoded_pixels_decode_the_same_in_pillow_and_vtk(tmp_path: Path, shape: tuple[int, ...]) -> None:
    """The encoder (unfiltered rows, one IDAT) writes standard PNGs: Pillow and VTK's libpng reader
    give back every pixel, grey, RGB and RGBA."""
    import io

    from PIL import Image
    from vtkmodules.util.numpy_support import vtk_to_numpy
    from vtkmodules.vtkIOImage import vtkPNGReader

    img = np.random.default_rng(len(shape) * 100 + shape[0]).integers(0, 256, shape).astype(np.uint8)
    data = png.png_bytes(img)
    assert data.startswith(b"\x89PNG\r\n\x1a\n") and data.endswith(b"IEND\xaeB`\x82")
    assert np.array_equal(np.asarray(Image.open(io.BytesIO(data))), img)
    path = png.write_png_file(tmp_path / "a.png", img)
    reader = vtkPNGReader()
    reader.SetFileName(str(path))
    reader.Update()
    channels = 1 if img.ndim == 2 else img.shape[2]
    got = vtk_to_numpy(reader.GetOutput().GetPointData().GetScalars()).reshape(shape[0], shape[1], channels)[::-1]
    assert np.array_equal(got.reshape(img.shape), img)  # VTK's rows run bottom up


@pytest.mark.skipif(not vtk_scene.render_available(), reason="VTK cannot open an offscreen window here")
@pytest.mark.parametrize("kind", ["mean", "zebra", "edges"])
def test_a_report_picture_encodes_smaller_than_pillows_adaptive_filter(tmp_path: Path, kind: str) -> None:
    """The reason for the encoder (see the module): a report's rendered picture (flat background,
    shading, stripes, lines) compresses smaller with unfiltered rows at level 4 than with Pillow's
    adaptive row filters at level 6 (the former encoder), and decodes to the same pixels."""
    import io

    from PIL import Image

    from occsurf.bridge.exchange.step_iges import read_iges
    from occsurf.bridge.quality import pictures as P
    from occsurf.bridge.quality.report import check_model

    report = check_model(read_iges(Path(__file__).resolve().parents[2] / "step_samples" / "mixed.igs"))
    fields = [report.fields[k] for k in sorted(report.fields)]
    path = P.render_picture(fields, kind, tmp_path / "p.png", model_size=report.size, edges=report.edge_lines)
    img = np.asarray(Image.open(path).convert("RGB"))
    buf = io.BytesIO()
    Image.fromarray(img).save(buf, format="PNG", compress_level=6)
    assert path.stat().st_size < len(buf.getvalue()), (path.stat().st_size, len(buf.getvalue()))


def test_not_an_image_is_refused_by_name() -> None:
    for bad in (np.zeros((4, 4, 7), np.uint8), np.zeros((0, 4, 3), np.uint8), np.zeros((2, 2, 2, 3), np.uint8)):
        with pytest.raises(ValueError, match="expected an image of shape"):
            png.png_bytes(bad)
