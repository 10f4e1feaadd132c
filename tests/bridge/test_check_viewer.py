"""The report page's interactive 3-D view (issue 28, item 1): the data it is given equals the
analysis' own, and in headless Chromium (WebGL through SwiftShader) every indicator, the stripe
and pull controls, the line sets, picking and the edge rows change what is drawn; with
``#no-webgl`` the page shows the PNG pictures instead. Skipped with the reason when Chromium or
chromedriver is not installed.

The browser tests share one page load (a module-scoped driver): SwiftShader is slow to start and
to compile shaders, and each picture is read from the canvas itself (``toDataURL``; the renderer
keeps its drawing buffer) after two animation frames, not after a fixed sleep.
"""

from __future__ import annotations

import base64
import io
import time
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.testing import assert_allclose

from occsurf.bridge.quality.html import PULL_CHOICES, VIEWER_INDICATORS, viewer_array, viewer_payload, write_html

from ..browser import chrome, needs_chromium

SAMPLES = Path(__file__).resolve().parents[2] / "step_samples"
BACKGROUND = np.array([0xF4, 0xF6, 0xFA])


def _report(name: str):
    from occsurf.bridge import read_step
    from occsurf.bridge.quality.report import check_model

    return check_model(read_step(str(SAMPLES / name)))


def _f4(payload: dict, ref: dict) -> np.ndarray:
    assert ref["dtype"] == "<f4"
    return viewer_array(payload, ref).astype(float)


def _u4(payload: dict, ref: dict) -> np.ndarray:
    assert ref["dtype"] == "<u4"
    return viewer_array(payload, ref)


# ---------------------------------------------------------------------------------------- payload
def _hole_report():
    """A box with a cylindrical hole: the hole is a reversed face (its outward normal points into
    the hole, against the surface's own), so the mean curvature's sign is flipped."""
    import build123d as bd

    from occsurf.bridge.quality.report import check_model

    return check_model(bd.Box(10, 10, 10) - bd.Cylinder(3, 10))


@pytest.mark.parametrize("name", ["loft.step", "hole"])
def test_payload_curvatures_are_the_analysis_own_at_the_vertices(name: str) -> None:
    """Mean and Gaussian curvature decoded from the page's data equal ``curvature_map`` at the
    mesh vertices' (u, v) within 1e-6 relative (float32 storage is 6e-8); the mean curvature's
    sign follows the face's outward normal (reversed faces flip it), as the report's. Values that
    are round-off zeros (planes, the ruled direction) are compared to 1e-9 of the face's largest."""
    from occsurf.algorithms.quality import curvature_map

    report = _hole_report() if name == "hole" else _report(name)
    payload = viewer_payload(report)
    assert len(payload["faces"]) == len(report.fields)
    rng = np.random.default_rng(0)
    compared = {"mean": 0, "gaussian": 0, "reversed": 0}
    for face in payload["faces"]:
        fld = report.fields[face["index"]]
        uv = fld.mesh.uv
        pts = _f4(payload, face["points"]).reshape(-1, 3)
        assert_allclose(pts, fld.mesh.points, rtol=1e-6, atol=1e-6 * report.size)
        pick = rng.choice(len(uv), size=min(40, len(uv)), replace=False)
        cmap = curvature_map(fld.surface, uv[pick, 0], uv[pick, 1], "mean")  # the grid's diagonal: the vertices
        sign = -1.0 if fld.mesh.reversed else 1.0
        for kind, want in (("mean", sign * np.diagonal(cmap.mean)), ("gaussian", np.diagonal(cmap.gaussian))):
            stored = _f4(payload, face["values"][kind])
            assert stored.shape == (face["n"],)
            got = stored[pick]
            ok = np.isfinite(want)
            assert np.array_equal(ok, np.isfinite(got)), (name, face["index"], kind)
            scale = max(float(np.abs(want[ok]).max(initial=0.0)), 1.0 / report.size ** (2 if kind == "gaussian" else 1))
            assert_allclose(got[ok], want[ok], rtol=1e-6, atol=1e-9 * scale, err_msg=f"{name} face {face['index']} {kind}")
            big = np.abs(want) > 1e-3 * scale
            compared[kind] += int(big.sum())
            if kind == "mean" and fld.mesh.reversed:
                compared["reversed"] += int(big.sum())
    assert compared["mean"] >= 40 and (compared["gaussian"] >= 40 or name == "hole")  # a cylinder: K = 0
    assert compared["reversed"] > 0 or name != "hole"


def test_payload_draft_is_asin_of_the_normal_along_the_pull_and_lines_are_packed() -> None:
    """What the page recomputes for another pull direction, done here for the stored +z: the
    draft the report stored is ``asin(n . z)`` of the normals it sends (to float32 accuracy);
    the section, comb and edge polylines decode to the report's own."""
    from occsurf.bridge.quality.pictures import EDGE_COLORS, model_sections

    report = _report("loft.step")
    payload = viewer_payload(report)
    assert payload["pull"] == [0.0, 0.0, 1.0] and ("+z", (0, 0, 1)) in PULL_CHOICES
    for face in payload["faces"]:
        N = _f4(payload, face["normals"]).reshape(-1, 3)
        own = np.degrees(np.arcsin(np.clip(N[:, 2] / np.linalg.norm(N, axis=1), -1, 1)))
        assert_allclose(own, _f4(payload, face["values"]["draft"]), atol=0.05)

    def decode(pack: dict[str, str]) -> list[np.ndarray]:
        P, counts = _f4(payload, pack["points"]).reshape(-1, 3), _u4(payload, pack["counts"])
        return np.split(P, np.cumsum(counts)[:-1]) if len(counts) else []

    sections, combs, infl = model_sections(report)
    lines = payload["lines"]
    for got, want in ((decode(lines["sections"]), sections), (decode(lines["combs"]), combs)):
        assert len(got) == len(want) > 0
        for g, w in zip(got, want, strict=True):
            assert_allclose(g, w, rtol=1e-6, atol=1e-6 * report.size)
    assert_allclose(_f4(payload, lines["inflections"]).reshape(-1, 3), infl, atol=1e-6 * report.size)
    classes = {c for c, _ in report.edge_lines}
    assert {e["class"] for e in lines["edges"]} == classes
    for e in lines["edges"]:
        assert tuple(e["color"]) == EDGE_COLORS[e["class"]]
        assert len(decode(e)) == sum(1 for c, _ in report.edge_lines if c == e["class"])


def test_payload_triangles_are_the_mesh_and_per_pixel_indicators_are_not_sent(monkeypatch) -> None:
    """Each face's triangles decode (uint16 up to 65536 vertices, uint32 beyond) to its mesh's own;
    the values sent are the coloured indicators only (zebra and isophotes are drawn per pixel from
    the normals), each the report's own in float32."""
    from occsurf.bridge.quality import html as H

    report = _report("loft.step")
    payload = viewer_payload(report)
    coloured = {k for k, *_ in VIEWER_INDICATORS} - set(H.PER_PIXEL) - {"shaded"}
    for face in payload["faces"]:
        fld = report.fields[face["index"]]
        assert face["triangles_dtype"] == "uint16"
        assert face["triangles"]["dtype"] == "<u2"
        tris = viewer_array(payload, face["triangles"]).reshape(-1, 3)
        assert np.array_equal(tris, fld.mesh.triangles)
        assert set(face["values"]) == coloured
        for k in coloured:
            assert np.array_equal(_f4(payload, face["values"][k]), fld.values[k].astype("<f4").astype(float), equal_nan=True)
    # a face of more than 65536 vertices: 32-bit indices, the same triangles
    big = report.fields[payload["faces"][0]["index"]]
    monkeypatch.setattr(type(big.mesh), "n_vertices", property(lambda self: 70_000))
    monkeypatch.setattr(H, "MAX_VIEWER_VERTICES", 10**9)  # every face counts 70 000 now
    payload = viewer_payload(report)
    face = payload["faces"][0]
    assert face["triangles_dtype"] == "uint32"
    assert np.array_equal(_u4(payload, face["triangles"]).reshape(-1, 3), big.mesh.triangles)


@settings(max_examples=80, deadline=None)
@given(st.lists(st.tuples(st.sampled_from(["<f4", "<u2", "<u4"]), st.integers(0, 14), st.sampled_from([1, 3]),
                          st.booleans()), max_size=6), st.integers(0, 2**31))
def test_packed_arrays_read_back_and_follow_the_documented_layout(arrays, seed) -> None:
    """Arrays of any length (empty too; NaN, infinities and signed zeros among the floats; integers
    up to their largest, whose differences wrap) packed into one block, by rows of 1 or 3 columns,
    as differences or not, read back bit for bit, in order; each starts at a multiple of 4 bytes
    and stores byte k of element i at ``at + k * n + i``, the elements column by column, each the
    difference from the one before it in its column where ``delta`` (:data:`~occsurf.bridge.quality.
    html.VIEWER_DATA_LAYOUT`, which the page's decoder follows)."""
    from occsurf.bridge.quality.html import _UNSIGNED, _Packer, viewer_data

    rng = np.random.default_rng(seed)
    pack, refs, want = _Packer(), [], []
    for dtype, rows, columns, delta in arrays:
        n = rows * columns
        if dtype == "<f4":
            a = rng.normal(size=n).astype("<f4")
            a[rng.random(n) < 0.2] = rng.choice(np.array([np.nan, np.inf, -np.inf, -0.0], "<f4"))
        else:
            a = rng.integers(0, np.iinfo(dtype).max, size=n, endpoint=True).astype(dtype)
        refs.append(pack.add(a.reshape(rows, columns), dtype, columns=columns, delta=delta))
        want.append((a, columns, delta))
    raw = viewer_data({"data": pack.data()})
    for ref, (a, columns, delta) in zip(refs, want, strict=True):
        assert ref["at"] % 4 == 0 and ref["n"] == a.size and ref["dtype"] == a.dtype.str
        assert ref["columns"] == columns and ref["delta"] == delta
        got = viewer_array(raw, ref)
        assert got.dtype == a.dtype and got.view(np.uint8).tobytes() == a.view(np.uint8).tobytes()
        # the layout spelled out: column-major, differences of the bits, byte planes
        u = a.view(_UNSIGNED[a.dtype.str]).reshape(-1, columns).T.astype(np.int64)
        if delta:
            u[:, 1:] = (u[:, 1:] - u[:, :-1]) % (1 << (8 * a.dtype.itemsize))
        stored = u.reshape(-1).astype(_UNSIGNED[a.dtype.str])
        w = a.dtype.itemsize
        for i in range(min(a.size, 4)):
            assert bytes(raw[ref["at"] + k * a.size + i] for k in range(w)) == stored[i:i + 1].tobytes()


# ---------------------------------------------------------------------------------------- browser


@pytest.fixture(scope="module")
def page(tmp_path_factory):
    """The loft's report page with two overview pictures, as ``occsurf check`` writes it."""
    from occsurf.bridge.quality.pictures import render_report_pictures

    out = tmp_path_factory.mktemp("viewer")
    report = _report("loft.step")
    shown = render_report_pictures(report, out, model_pictures=("mean", "edges"), face_pictures=())
    payload = viewer_payload(report)
    doc = report.to_json()
    write_html(out / "index.html", doc, payload, shown)
    return out / "index.html", doc, payload


@pytest.fixture(scope="module")
def browser():
    drv = chrome(webgl=True, browser_log=True)
    yield drv
    drv.quit()


def _open(drv, url: str, state: str) -> None:
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support.ui import WebDriverWait

    drv.get("about:blank")  # a new document even when only the #hash differs
    drv.get(url)
    WebDriverWait(drv, 60).until(lambda d: d.find_element(By.TAG_NAME, "body").get_attribute("data-viewer") == state)
    drv.get_log("browser")  # start the log afresh


def _errors(drv) -> list[str]:
    return [e["message"] for e in drv.get_log("browser") if e["level"] == "SEVERE"]


def _shot(drv) -> np.ndarray:
    """The canvas' own pixels after two more animation frames."""
    from PIL import Image

    drv.execute_async_script("const done = arguments[0]; requestAnimationFrame(() => requestAnimationFrame(() => done()));")
    url = drv.execute_script("return document.getElementById('viewer').toDataURL('image/png')")
    return np.asarray(Image.open(io.BytesIO(base64.b64decode(url.split(",", 1)[1]))).convert("RGB")).astype(int)


def _model(img: np.ndarray) -> np.ndarray:
    return np.abs(img - BACKGROUND).sum(axis=2) > 40


def _changed(a: np.ndarray, b: np.ndarray) -> float:
    """Fraction of the canvas whose colour changed visibly."""
    return float((np.abs(a - b).sum(axis=2) > 30).mean())


def _set(drv, element_id: str, value: str, event: str) -> None:
    drv.execute_script("const e = document.getElementById(arguments[0]); e.value = arguments[1];"
                       "e.dispatchEvent(new Event(arguments[2], {bubbles: true}));", element_id, value, event)


@pytest.mark.slow
@needs_chromium
def test_viewer_indicators_controls_lines_and_picking(page, browser) -> None:
    """One page load: every indicator draws a non-blank canvas unlike the others; the zebra stripe
    count and direction, the isophote count and the pull direction change the pixels (+z again
    gives back the stored draft picture); each line set's checkbox changes them; a click on the
    model tints the face under the cursor and marks its row, a click beside it clears both, a click
    on that row tints it again; an edge row moves the view's target to its worst point."""
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.by import By

    path, doc, _ = page
    drv = browser
    _open(drv, path.resolve().as_uri(), "ready")
    assert drv.find_element(By.ID, "viewer-status").text.startswith("11 faces,")
    drv.execute_script("document.getElementById('view3d').scrollIntoView()")

    shots = {}
    for key, *_ in VIEWER_INDICATORS:
        _set(drv, "indicator", key, "change")
        shots[key] = img = _shot(drv)
        assert _model(img).mean() > 0.05, f"{key}: the canvas is blank"
    for a in shots:
        for b in shots:
            if a < b:
                assert _changed(shots[a], shots[b]) > 0.01, f"{a} and {b} draw the same picture"

    _set(drv, "indicator", "zebra", "change")
    for element_id, value, event in (("zebra-count", "17", "input"), ("zebra-dir", "0.0,1.0,0.0", "change")):
        before = _shot(drv)
        _set(drv, element_id, value, event)
        assert _changed(before, _shot(drv)) > 0.02, f"{element_id} = {value} changed nothing"
    _set(drv, "indicator", "isophote", "change")
    before = _shot(drv)
    _set(drv, "iso-count", "13", "input")
    assert _changed(before, _shot(drv)) > 0.02, "the isophote count changed nothing"

    _set(drv, "indicator", "draft", "change")
    stored = _shot(drv)
    for pull in ("1,0,0", "0,-1,0", "0,0,-1"):
        _set(drv, "pull", pull, "change")
        assert _changed(stored, _shot(drv)) > 0.02, f"pull {pull}: the draft picture did not change"
    _set(drv, "pull", "0,0,1", "change")
    assert _changed(stored, _shot(drv)) < 0.001, "pull +z again does not show the stored draft"

    _set(drv, "indicator", "shaded", "change")
    plain = _shot(drv)
    for box in ("show-sections", "show-combs", "show-edges"):
        drv.find_element(By.ID, box).click()
        assert _changed(plain, _shot(drv)) > 0.002, f"{box} drew nothing"
        drv.find_element(By.ID, box).click()
    assert _changed(plain, _shot(drv)) < 0.001

    canvas = drv.find_element(By.ID, "viewer")
    h, w = plain.shape[:2]
    marked = ("return Array.from(document.querySelectorAll('#face-table tr.picked'), r => r.dataset.face)")
    ActionChains(drv).move_to_element_with_offset(canvas, 0, 0).click().perform()  # the model's middle
    picked = _shot(drv)
    rows = drv.execute_script(marked)
    assert len(rows) == 1, rows
    assert f"face {rows[0]} selected" in drv.find_element(By.ID, "viewer-pick").text
    patch = (slice(h // 2 - 4, h // 2 + 5), slice(w // 2 - 4, w // 2 + 5))
    redder = (picked[patch][..., 0] - picked[patch][..., 2]).mean() - (plain[patch][..., 0] - plain[patch][..., 2]).mean()
    assert redder > 25, "the face under the click is not tinted"
    ActionChains(drv).move_to_element_with_offset(canvas, -w // 2 + 8, -h // 2 + 8).click().perform()  # background
    assert drv.execute_script(marked) == [] and _changed(plain, _shot(drv)) < 0.001
    drv.execute_script("document.querySelector(`#face-table tr[data-face='${arguments[0]}']`).click()", rows[0])
    assert drv.execute_script(marked) == rows and _changed(picked, _shot(drv)) < 0.001

    edge = next(e for e in doc["edges"] if e.get("worst_point"))
    drv.execute_script("document.querySelector(`#edge-table tr[data-edge='${arguments[0]}']`).click()", edge["index"])
    want = np.asarray(edge["worst_point"], float)
    for _ in range(50):  # the 0.5 s flight
        target = np.asarray(drv.execute_script("return occsurfViewer.target()"), float)
        if np.abs(target - want).max() <= 1e-9 * doc["model_size"]:
            break
        time.sleep(0.1)
    assert_allclose(target, want, atol=1e-9 * doc["model_size"])
    assert _changed(picked, _shot(drv)) > 0.05, "the view did not move"
    assert drv.find_elements(By.CSS_SELECTOR, "#edge-table tr.picked")
    assert _errors(drv) == []


@pytest.mark.slow
@needs_chromium
def test_without_webgl_the_page_shows_the_pictures(page, browser) -> None:
    """``#no-webgl`` takes the path of a browser without WebGL: no canvas, the overview PNGs
    (loaded) in its place with a note, the tables still there, nothing logged as an error."""
    from selenium.webdriver.common.by import By

    path, doc, _ = page
    drv = browser
    _open(drv, path.resolve().as_uri() + "#no-webgl", "fallback")
    assert not drv.find_element(By.ID, "viewer").is_displayed()
    fallback = drv.find_element(By.ID, "viewer-fallback")
    assert fallback.is_displayed() and "needs WebGL" in fallback.text
    from selenium.webdriver.support.ui import WebDriverWait

    drv.execute_script("arguments[0].scrollIntoView()", fallback)
    script = ("return Array.from(document.querySelectorAll('#viewer-fallback img'),"
              " i => [i.getAttribute('src'), i.complete && i.naturalWidth > 0])")
    WebDriverWait(drv, 10).until(lambda d: all(ok for _, ok in d.execute_script(script)))
    loaded = drv.execute_script(script)
    assert sorted(src for src, _ in loaded) == ["model_edges.png", "model_mean.png"]
    assert all(ok for _, ok in loaded), loaded
    assert len(drv.find_elements(By.CSS_SELECTOR, "#face-table tbody tr")) == len(doc["faces"])
    assert _errors(drv) == []


@pytest.mark.slow
@needs_chromium
def test_the_page_decodes_the_arrays_the_payload_holds(page, browser) -> None:
    """The page's inflating and byte-plane decoding (``viewer_js``) gives every face's positions,
    normals, triangles and indicator values bit for bit as :func:`viewer_array` reads them, which
    the payload tests hold to the report's own."""
    path, _, payload = page
    drv = browser
    _open(drv, path.resolve().as_uri(), "ready")
    for face in payload["faces"]:
        for name in ("points", "normals", "triangles", "mean", "draft"):
            ref = face[name] if name in face else face["values"][name]
            got = drv.execute_script("return occsurfViewer.arrays(arguments[0], arguments[1])", face["index"], name)
            want = viewer_array(payload, ref)
            assert np.array_equal(np.asarray(got, dtype=want.dtype), want, equal_nan=True), (face["index"], name)
    assert _errors(drv) == []


@pytest.mark.slow
@needs_chromium
def test_a_browser_that_cannot_inflate_shows_the_pictures(page, browser) -> None:
    """Without ``DecompressionStream`` (browsers before Chromium 80, Firefox 113, Safari 16.4) the
    page says why and shows the overview pictures, as without WebGL."""
    from selenium.webdriver.common.by import By

    path, _, _ = page
    drv = browser
    added = drv.execute_cdp_cmd("Page.addScriptToEvaluateOnNewDocument", {"source": "delete window.DecompressionStream;"})
    try:
        _open(drv, path.resolve().as_uri(), "fallback")
        fallback = drv.find_element(By.ID, "viewer-fallback")
        assert fallback.is_displayed() and "could not unpack its data" in fallback.text
        assert len(drv.find_elements(By.CSS_SELECTOR, "#viewer-fallback img")) == 2
    finally:
        drv.execute_cdp_cmd("Page.removeScriptToEvaluateOnNewDocument", {"identifier": added["identifier"]})
