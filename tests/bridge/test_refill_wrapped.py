"""Thread strips of a real screw refilled by the wrapped plate (issue 12; :mod:`occsurf.algorithms.topology.plate_wrap`).

build123d's M6 x 12 countersunk screw (``../shared/realdata``): face 9 is the thread's crest, a strip
0.12 mm wide winding nine times around the screw's axis (z through the origin). No plane sees it as
a height field, the central split refuses it, and OCC's ``BRepOffsetAPI_MakeFilling`` fails on it
(default and tuned); the wrapped plate, about the axis of the neighbouring cylinders, fills it within
the issue's G0 target (1e-7 of the model size: 1.9e-6), as a valid face that sews in and round-trips
through STEP. All sides are G0-only (the crest meets the flanks at a crease).
"""

from __future__ import annotations

import numpy as np
import pytest

from occsurf.algorithms import tolerances

@pytest.fixture(scope="module")
def crest(screw):
    from occsurf.bridge.modeling.refill import refill_faces

    return refill_faces(screw, [9])


def test_neighbour_axes_hold_the_screw_axis(screw) -> None:
    from occsurf.bridge.modeling.plate import revolution_axes
    from occsurf.bridge.modeling.refill import _hole_loop

    _, nbs, _ = _hole_loop(screw, [9])
    axes = revolution_axes(nbs)
    assert any(abs(abs(a[2]) - 1) < 1e-12 and np.hypot(*c[:2]) < 1e-9 for c, a in axes)


def test_thread_crest_is_filled_by_the_wrapped_plate(screw, crest) -> None:
    rep, shape = crest
    assert rep.status == "filled" and rep.method == "wrap", rep.reason
    assert rep.valid and rep.step_round_trip and rep.folds == 0
    assert max(rep.side_g0) <= tolerances.FILL_FIT_G0 * screw.size  # 1.9e-6, measured by LocalAnalysis


@pytest.mark.xfail(strict=True, reason="OCC defect: BRepOffsetAPI_MakeFilling fails on the nine-turn thread "
                   "crest strip (default: not done; tuned: Standard_ConstructionError)")
def test_occ_filling_fills_the_thread_crest(crest) -> None:
    rep, _ = crest
    assert any(o.get("status") == "ok" for o in rep.occ.values())


@pytest.fixture(scope="module")
def run_out(screw):
    from occsurf.bridge.modeling.refill import refill_faces

    return refill_faces(screw, [8, 22])


def test_a_flank_with_its_run_out_is_filled_over_the_unrolled_loops_plane(screw, run_out) -> None:
    """Faces 8 and 22 removed together: a flank strip with its run-out at the thread's start (14
    edges). Unrolled about the axis, neither r nor z is a height over the whole loop (see
    test_plate_wrap's run-out in closed form); the plate over the unrolled loop's own plane is.
    Measured: every edge within 1.33e-6 (target 1.9e-6); OCC's fills miss by 1.14 mm (default) and
    1.17 mm (tuned) on this 19 mm screw."""
    rep, _ = run_out
    assert rep.status == "filled" and rep.method == "wrap", rep.reason
    assert rep.valid and rep.step_round_trip and rep.folds == 0
    assert max(rep.side_g0) <= tolerances.FILL_FIT_G0 * screw.size
    occ = [max(o["side_g0"]) for o in rep.occ.values() if o.get("status") == "ok"]
    assert all(g > 1e3 * max(rep.side_g0) for g in occ)  # where OCC fills it, a thousand times further off


def test_a_refusal_names_the_crease_between_removed_faces(screw, bearing) -> None:
    """Flank and crest (screw faces 8 and 9) meet at a 60 deg crease that runs the strip's length;
    removed together, no fill comes within 6e-4 of the boundary where the crease ends on it (OCC's
    filler fails too), and the refusal says so. The bearing's fillet pair [4, 166] meets
    tangentially: no crease."""
    from occsurf.bridge.modeling.refill import _crease_note, _inner_creases

    creases = _inner_creases(screw, [8, 9])
    assert len(creases) == 1 and abs(creases[0][0] - 60.0) < 0.5
    assert abs(np.hypot(*creases[0][1][:2]) - 3.0) < 0.1  # on the crest's radius
    assert "sharpest at 60.1 deg" in _crease_note(screw, [8, 9])
    assert _inner_creases(bearing, [4, 166]) == [] and _crease_note(bearing, [4, 166]) == ""
    assert _crease_note(screw, [9]) == ""  # a single face has no inner edge
