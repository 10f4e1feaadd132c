"""Issue 34, item 8, the bridge: pictures and ``samples`` parameters refused before their arrays.

As ``tests/algorithms/test_size_guards.py``: a 1 MB ``MAX_ARRAY_BYTES`` keeps each refusal fast and
small; the error is check_size's ``InvalidGeometryError`` naming the argument.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator

import numpy as np
import pytest

from occsurf.algorithms import BSplineCurve, BSplineSurface, tolerances
from occsurf.algorithms.errors import InvalidGeometryError


@pytest.fixture(autouse=True)
def _small_limit() -> Iterator[None]:
    with tolerances.override(MAX_ARRAY_BYTES=10**6):
        yield


def refused(call: Callable[[], object], match: str) -> None:
    t0 = time.perf_counter()
    with pytest.raises(InvalidGeometryError, match=match) as info:
        call()
    assert time.perf_counter() - t0 < 1.0
    assert "MAX_ARRAY_BYTES" in str(info.value)


def _surface() -> BSplineSurface:
    t = [0.0] * 4 + [0.5] + [1.0] * 4
    return BSplineSurface((3, 3), (t, t), np.random.default_rng(0).random((5, 5, 3)))


def _curve() -> BSplineCurve:
    return BSplineCurve(3, [0, 0, 0, 0, 0.5, 1, 1, 1, 1], np.c_[np.linspace(0, 4, 5), np.sin(np.arange(5)), np.zeros(5)])


def test_pictures_are_refused_before_the_window_exists() -> None:
    """``render_lit`` allowed 16384 x 16384 with 16 samples (~39 GB of buffers); every window now
    checks its buffers against the limit, as does ``surface_grid``'s resolution."""
    from occsurf.algorithms.lighting import studio_three_point
    from occsurf.bridge.rendering import lighting, vtk_scene
    from occsurf.bridge.rendering.surfaces import surface_grid

    P = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], float)
    T = np.array([[0, 1, 2]])
    refused(lambda: lighting.render_lit(P, T, studio_three_point([0, 0, 0], 2.0), size=(16384, 16384), samples=16),
            r"size: a 16384 x 16384 picture with 16 samples")
    refused(lambda: vtk_scene.Scene().render_array(size=(4000, 3000)), r"size: a 4000 x 3000 picture")
    refused(lambda: surface_grid(_surface(), 400), r"resolution: a 400 x 400 grid")
    assert surface_grid(_surface(), 8)[0].shape == (8, 8, 3)


def test_bridge_samples_are_refused_before_their_arrays() -> None:
    import cadquery as cq

    from occsurf.bridge.modeling.fill import fill_model
    from occsurf.bridge.quality.continuity import edge_continuity
    from occsurf.bridge.quality.report import check_model
    from occsurf.bridge.validation.deviation import curve_deviation, roundtrip_deviation

    s, c = _surface(), _curve()
    refused(lambda: roundtrip_deviation(s, s, samples=2000), r"roundtrip_deviation with samples=2000 \(2000 x 2000 grid\)")
    refused(lambda: roundtrip_deviation(c, c, samples=10**6), r"roundtrip_deviation with samples=1000000")
    refused(lambda: curve_deviation(c, samples=10**6), r"curve_deviation with samples=1000000")
    box = cq.Workplane().box(1, 2, 3).val().wrapped
    refused(lambda: edge_continuity(box, samples=10**6 + 1), r"samples = 1000001")
    refused(lambda: check_model(box, samples=400), r"samples: a 400 x 400 grid")
    refused(lambda: fill_model(box, samples=10**6), r"samples = 1000000")
    with pytest.raises(InvalidGeometryError, match="samples: expected an integer >= 2"):
        fill_model(box, samples=1.5)  # type: ignore[arg-type]
