"""The quality report in notebooks and build123d viewers (issue 28, item 3): ``_repr_html_`` opened
in headless Chromium, and ``quality_overlays`` as coloured build123d Compounds."""

from __future__ import annotations

import io
import time
from pathlib import Path

import numpy as np
import pytest

from occsurf.bridge.quality.export import OVERLAY_COLORS, quality_overlays
from occsurf.bridge.quality.pictures import EDGE_COLORS

from ..browser import chrome, needs_chromium

SAMPLES = Path(__file__).resolve().parents[2] / "step_samples"


@pytest.fixture(scope="module")
def loft_report():
    from occsurf.bridge import read_step
    from occsurf.bridge.quality.report import check_model

    return check_model(read_step(str(SAMPLES / "loft.step")))


def test_overlays_are_labelled_coloured_compounds_of_the_reports_lines(loft_report):
    overlays = quality_overlays(loft_report)
    by_label = {c.label: c for c in overlays}
    assert {"sections", "combs"} <= set(by_label)
    classes = {cls for cls, _ in loft_report.edge_lines}
    assert {f"edges {c}" for c in classes} <= set(by_label)
    for c in overlays:
        rgb = EDGE_COLORS[c.label.split()[1]] if c.label.startswith("edges ") else OVERLAY_COLORS[c.label]
        assert np.allclose(tuple(c.color)[:3], rgb)
        assert c.edges()
    # one edge per drawn edge polyline, each on its polyline's ends
    for cls in classes:
        pls = [pl for k, pl in loft_report.edge_lines if k == cls]
        comp = by_label[f"edges {cls}"]
        assert len(comp.edges()) == len(pls)


def test_overlays_of_a_build123d_part_show_its_tangent_and_sharp_edges():
    import build123d as bd

    box = bd.Box(10, 20, 5)
    part = bd.fillet(box.edges().group_by(bd.Axis.Z)[-1], 1.5)  # the top edges rounded
    labels = {c.label for c in quality_overlays(part)}
    assert {"edges sharp", "edges G1"} <= labels  # the bottom's corners, the fillets' tangent joints




@pytest.mark.slow
@needs_chromium
def test_repr_html_shows_the_viewer_inline_in_chromium(loft_report, tmp_path):
    """A notebook cell's output (the report's ``_repr_html_`` in a page) opened in headless Chromium:
    the framed page's viewer script finishes, its 3-D canvas is not blank, the tables are there."""
    from PIL import Image
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support.ui import WebDriverWait

    cell = tmp_path / "cell.html"
    cell.write_text("<!doctype html><html><body><p>In [1]: check_model(part)</p>" + loft_report._repr_html_()
                    + "</body></html>", encoding="utf-8")
    drv = chrome(webgl=True)
    try:
        drv.get(cell.resolve().as_uri())
        drv.switch_to.frame(drv.find_element(By.TAG_NAME, "iframe"))
        WebDriverWait(drv, 60).until(lambda d: d.find_element(By.TAG_NAME, "body").get_attribute("data-viewer") == "ready")
        status = drv.find_element(By.ID, "viewer-status").text
        assert status.startswith("11 faces,"), status
        canvas = drv.find_element(By.ID, "viewer")
        drv.execute_script("arguments[0].scrollIntoView()", canvas)
        time.sleep(0.5)
        img = np.asarray(Image.open(io.BytesIO(canvas.screenshot_as_png)).convert("RGB")).astype(int)
        model = np.abs(img - np.array([0xF4, 0xF6, 0xFA])).sum(axis=2) > 40
        assert model.mean() > 0.03, "the 3-D canvas is blank"
        assert len(drv.find_elements(By.CSS_SELECTOR, "#face-table tbody tr")) == 11
        drv.switch_to.default_content()
        drv.save_screenshot(str(tmp_path / "cell.png"))
        shot = np.asarray(Image.open(tmp_path / "cell.png").convert("L"))
        assert shot.std() > 5  # the cell with its framed report, not a blank page
    finally:
        drv.quit()
