"""Fixtures shared by the bridge tests."""

from __future__ import annotations

from pathlib import Path

import pytest

REALDATA = Path(__file__).resolve().parents[2].parent / "shared" / "realdata"


def _sewn(name: str, reader: str):
    """The realdata file ``name`` read by OCP's ``reader`` (``IGESControl_Reader`` or
    ``STEPControl_Reader``) and sewn once; skipped where ../shared is absent."""
    path = REALDATA / name
    if not path.is_file():
        pytest.skip(f"{path} is absent (public real models)")
    import importlib

    from occsurf.bridge.modeling.refill import SewnModel

    module = "OCP.IGESControl" if reader.startswith("IGES") else "OCP.STEPControl"
    r = getattr(importlib.import_module(module), reader)()
    assert int(r.ReadFile(str(path))) == 1
    r.TransferRoots()
    return SewnModel(r.OneShape())


@pytest.fixture(scope="session")
def bearing():
    """OCC's bearing (IGES, ../shared/realdata) sewn once (:class:`SewnModel`; refill_faces reads it,
    never changes it); skipped where ../shared is absent."""
    return _sewn("occt__bearing.iges", "IGESControl_Reader")


@pytest.fixture(scope="session")
def screw():
    """build123d's M6 x 12 countersunk screw (STEP, ../shared/realdata) sewn once; skipped where
    ../shared is absent."""
    return _sewn("build123d__M6-1x12-countersunk-screw.step", "STEPControl_Reader")


@pytest.fixture(scope="session")
def linkrods():
    """OCC's linkrods (STEP, ../shared/realdata) sewn once; skipped where ../shared is absent."""
    return _sewn("occt__linkrods.step", "STEPControl_Reader")
