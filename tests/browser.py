"""Headless Chromium for the tests that open pages (the docs site, ``occsurf check``'s report and its
notebook view): Debian's ``chromium`` and ``chromium-driver`` (``.ci/run`` installs them), driven
by selenium, with the network cut off. One place for what four test modules had each written."""

from __future__ import annotations

import shutil
from typing import Any

import pytest

#: Chromium's switches: headless, no sandbox (CI runs as root), every host name unresolvable (the
#: pages must work offline); ``webgl`` adds SwiftShader (WebGL without a GPU, for the 3-D viewer).
BASE_ARGS = ("--headless=new", "--no-sandbox", "--disable-gpu", "--host-resolver-rules=MAP * ~NOTFOUND")
WEBGL_ARGS = ("--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--disable-background-networking")


def chromium() -> tuple[str, str] | None:
    """``(browser, driver)`` paths of Debian's chromium and chromedriver, or ``None`` when absent."""
    browser = shutil.which("chromium") or shutil.which("chromium-browser")
    driver = shutil.which("chromedriver")
    return (browser, driver) if browser and driver else None


needs_chromium = pytest.mark.skipif(chromium() is None, reason="Debian packages chromium and chromium-driver not "
                                                                "installed (.ci/run installs them)")


def chrome(*, webgl: bool = False, size: tuple[int, int] = (1300, 1000), browser_log: bool = False) -> Any:
    """A headless Chrome driver (the caller quits it); skips the test where selenium is missing."""
    webdriver = pytest.importorskip("selenium.webdriver")
    found = chromium()
    if found is None:
        pytest.skip("Debian packages chromium and chromium-driver not installed")
    path, driver_path = found
    opts = webdriver.ChromeOptions()
    opts.binary_location = path
    for arg in BASE_ARGS + (WEBGL_ARGS if webgl else ()) + (f"--window-size={size[0]},{size[1]}",):
        opts.add_argument(arg)
    if browser_log:
        opts.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    return webdriver.Chrome(service=webdriver.ChromeService(executable_path=driver_path), options=opts)
