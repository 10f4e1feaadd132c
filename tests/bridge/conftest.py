"""Fixtures shared by the bridge tests."""

from __future__ import annotations

from pathlib import Path

import pytest

REALDATA = Path(__file__).resolve().parents[2].parent / "shared" / "realdata"


@pytest.fixture(scope="session")
def bearing():
    """OCC's bearing (IGES, ../shared/realdata) sewn once (:class:`SewnModel`; refill_faces reads it,
    never changes it); skipped where ../shared is absent."""
    path = REALDATA / "occt__bearing.iges"
    if not path.is_file():
        pytest.skip(f"{path} is absent (public real models)")
    from OCP.IGESControl import IGESControl_Reader

    from occsurf.bridge.modeling.refill import SewnModel

    r = IGESControl_Reader()
    assert int(r.ReadFile(str(path))) == 1
    r.TransferRoots()
    return SewnModel(r.OneShape())
