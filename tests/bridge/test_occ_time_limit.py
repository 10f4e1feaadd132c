"""OCC's filler under a time limit (issue 27): ``occ_variant(..., time_limit=S)`` runs
``BRepOffsetAPI_MakeFilling`` and its measurement in a forked child and stops it at the limit, so
that a benchmark over every hole of a real model goes on past a hole where OCC's filler runs for
tens of minutes (a pair of the bearing's faces: over 30 min, tuned)."""

from __future__ import annotations

import time

import pytest

from occsurf.algorithms.errors import InvalidGeometryError
from occsurf.bridge.conversion.splines import make_face
from occsurf.bridge.modeling import refill_candidates as rc
from occsurf.bridge.modeling.fill import model_holes, neighbour_face, sew_faces
from occsurf.examples.hole_models import ring_model


def _hole():
    """The edges, neighbour faces and G1 flags of the 4-sided ring's hole."""
    shell = sew_faces([make_face(f, 1e-7) for f in ring_model(4).faces])
    holes = model_holes(shell)
    edges, _ = next(loop for loop in holes.loops if not loop[1])
    return edges, [neighbour_face(holes.e2f, e) for e in edges], [True] * len(edges)


def test_in_a_child_the_same_measures_as_in_process() -> None:
    """With a time limit the fill runs in a forked child: the same OCC face, so the same G0 and G1
    per edge, bit for bit."""
    edges, nbs, g1 = _hole()
    here = rc.occ_variant(edges, nbs, g1, rc.OCC_DEFAULT)
    child = rc.occ_variant(edges, nbs, g1, rc.OCC_DEFAULT, time_limit=120.0)
    assert here["status"] == child["status"] == "ok"
    for key in ("g0", "g1", "side_g0", "side_g1"):
        assert child[key] == here[key], key


def test_a_filler_past_the_limit_is_stopped_and_said(monkeypatch: pytest.MonkeyPatch) -> None:
    """A filler that does not finish (here one that sleeps 60 s) is stopped at the limit: status
    'timeout' with the limit in the reason, within a few seconds of it; the caller's process goes
    on. A filler that fails in the child is 'failed' with OCC's reason, as in process."""
    edges, nbs, g1 = _hole()

    def slow(*args: object) -> None:
        time.sleep(60)

    monkeypatch.setattr(rc, "occ_filling", slow)  # the forked child runs the patched module
    t0 = time.perf_counter()
    out = rc.occ_variant(edges, nbs, g1, rc.OCC_DEFAULT, time_limit=0.5)
    assert out["status"] == "timeout" and "time limit of 0.5 s" in out["reason"], out
    assert 0.5 <= out["seconds"] and time.perf_counter() - t0 < 10

    def fails(*args: object) -> None:
        raise InvalidGeometryError("BRepOffsetAPI_MakeFilling: not done")

    monkeypatch.setattr(rc, "occ_filling", fails)
    out = rc.occ_variant(edges, nbs, g1, rc.OCC_DEFAULT, time_limit=30.0)
    assert out["status"] == "failed" and "not done" in out["reason"], out


@pytest.mark.parametrize("bad", [0, -1.0, float("nan"), "10"])
def test_refill_refuses_a_time_limit_that_is_not_positive_seconds(bad: object) -> None:
    from occsurf.bridge.modeling.refill import refill_faces

    shell = sew_faces([make_face(f, 1e-7) for f in ring_model(4).faces])
    with pytest.raises(InvalidGeometryError, match="occ_time_limit"):
        refill_faces(shell, [0], occ_time_limit=bad)
