"""G1 at a hole corner between a G1 side and a G0-only side (a crease), issue 12.

At a corner a fill regular there has its tangent plane spanned by the two side tangents. When the
G0 side's tangent leaves the G1 neighbour's plane by ``alpha``, no fill through the curves is
closer than ``alpha`` to that neighbour at the corner point (the lower bound); the M6 screw's faces
[22, 23] and [23, 26] lost 0.767 deg there (the G0 side's tangent 0.765 deg out of the cylinder's
plane: the original model's own crease), OCC's MakeFilling 0.70 / 0.67 by missing the boundary by
2e-3. G0 asks position only: ``refill_sides._corner_treatment`` now turns the G0 side's end tangent into
the neighbour's plane within a stretch where the side moves by at most
``FILL_CORNER_TURN_G0 * FILL_FIT_G0 * size`` (:func:`turn_end_tangent`), and the G1 side keeps
its neighbour's normals up to the corner.

Closed form: the hole of the twisted face ``z = h x y`` over the unit square (``h = tan(alpha)``),
side 0 (``y = 0``) asked G1 to the plane ``z = 0``, the other three G0 with the face's own normals;
side 1 (``x = 1``: ``(1, t, h t)``) leaves the plane by exactly ``alpha`` at corner ``(1, 0, 0)``.
The fill's normal is measured along side 0 (2001 points plus 400 clustered at both ends).

Tolerances. Left untreated, the fill's angle at the corner is the lower bound ``alpha`` (a
regular patch: the normal is ``S_u x S_v`` of the two side tangents), to 1e-6 deg (measured
3e-8, 1.4e-7 at alpha 0.5, 2 deg). Turned: the corner itself within 1e-6 deg (measured 4e-11,
3.5e-9), the whole side within FILL_FIT_ANGLE (the issue's 0.01 deg; measured 1.7e-4 and 6.7e-4 deg,
near the other corner, where the twisted face's twist h meets the plane's 0: Gregory's
incompatibility, confined by the fill); side 1 moved by at most its budget (measured 4.7e-8 of
7.1e-8), the other sides not at all. On the screw (skipped where ../shared/realdata is absent) our
fill is judged against OCC's with cadquery's defaults, measured alike: no worse in G0 and G1, no
fold; measured G1 0.0017 deg / OCC 0.70, G0 3.9e-7 / 2.0e-3.
"""

from __future__ import annotations

import numpy as np
import pytest

from occsurf.algorithms import tolerances
from occsurf.algorithms.kernel.curve import BSplineCurve
from occsurf.algorithms.topology.nsided import count_folds, fill_hole
from occsurf.algorithms.topology.nsided_sides import side_from_normals


def _crease_hole(alpha_deg: float) -> tuple[list[BSplineCurve], list[tuple[np.ndarray, np.ndarray]], float]:
    h = np.tan(np.radians(alpha_deg))
    V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, h], [0, 1, 0]], float)
    curves = [BSplineCurve(1, np.r_[0, 0, 1, 1], np.array([V[k], V[(k + 1) % 4]])) for k in range(4)]
    ends = np.geomspace(1e-4, 5e-2, 8)  # as refill samples a hole edge (edge_params)
    s = np.unique(np.r_[np.linspace(0, 1, 81), ends, 1 - ends])
    fields = []
    for k, c in enumerate(curves):
        P = c.evaluate(s)
        if k == 0:  # the plane z = 0 (B' x N = -y: into the neighbour, away from the hole)
            N = np.tile([0.0, 0.0, 1.0], (len(s), 1))
        else:  # the removed face z = h x y itself (G0 sides keep its tangent planes)
            N = np.c_[-h * P[:, 1], -h * P[:, 0], np.ones(len(s))]
        fields.append((s, N / np.linalg.norm(N, axis=1, keepdims=True)))
    return curves, fields, float(np.linalg.norm(V.max(0) - V.min(0)))


def _fill_angles_on_side0(curves, fields, g1, tol):
    from occsurf.bridge.modeling.refill_sides import _corner_treatment

    turned, treated = _corner_treatment(curves, fields, g1, tol)
    fill = fill_hole([side_from_normals(c, s, N).side for c, (s, N) in zip(turned, treated)])
    t = np.unique(np.r_[np.linspace(0, 1, 2001), np.geomspace(1e-7, 0.2, 200), 1 - np.geomspace(1e-7, 0.2, 200)])
    idx, u, v, _ = fill.locate_input(0, curves[0].evaluate(t))
    ang = np.full(len(t), np.nan)
    for k, patch in enumerate(fill.patches):
        m = idx == k
        if m.any():
            D = patch.derivatives(u[m], v[m], 1)
            nrm = np.cross(D[:, 1, 0], D[:, 0, 1])
            ang[m] = np.degrees(np.arctan2(np.linalg.norm(nrm[:, :2], axis=1), np.abs(nrm[:, 2])))
    assert sum(count_folds(p) for p in fill.patches) == 0
    return t, ang, turned


@pytest.mark.parametrize("alpha", [0.5, 2.0])
def test_the_untreated_crease_corner_costs_its_angle(alpha) -> None:
    curves, fields, _ = _crease_hole(alpha)
    t, ang, _ = _fill_angles_on_side0(curves, fields, None, 0.0)
    assert abs(ang[-1] - alpha) <= 1e-6  # the lower bound, attained at the corner
    assert ang.max() <= alpha + 1e-6


@pytest.mark.parametrize("alpha", [0.5, 2.0])
def test_turning_the_crease_side_gives_g1_up_to_the_corner(alpha) -> None:
    curves, fields, size = _crease_hole(alpha)
    g1 = [(True, True), (False, False), (False, False), (False, False)]
    tol = tolerances.FILL_FIT_G0 * size
    t, ang, turned = _fill_angles_on_side0(curves, fields, g1, tol)
    assert ang[-1] <= 1e-6  # the corner (1, 0, 0): was alpha
    assert np.nanmax(ang) <= tolerances.FILL_FIT_ANGLE and not np.isnan(ang).any()
    s = np.unique(np.r_[np.linspace(0, 1, 20001), np.geomspace(1e-12, 1e-2, 500)])
    moved = [np.linalg.norm(a.evaluate(s) - b.evaluate(s), axis=1).max() for a, b in zip(turned, curves)]
    assert moved[1] <= tolerances.FILL_CORNER_TURN_G0 * tol
    assert moved[0] == moved[2] == moved[3] == 0.0  # only the G0 side at the crease corner moves
    T = turned[1].derivatives(np.array([0.0]), 1)[0, 1]
    assert abs(T[2]) <= 1e-12 * np.linalg.norm(T)  # its tangent now in the plane z = 0


def test_screw_crease_corner_no_worse_than_occ(screw) -> None:
    from occsurf.bridge.modeling.refill import OCC_DEFAULT, refill_faces

    rep, _ = refill_faces(screw, [22, 23], check=False, occ_variants={"default": OCC_DEFAULT})
    occ = rep.occ["default"]
    assert rep.status == "filled" and occ["status"] == "ok" and rep.folds == 0
    assert rep.g1_edges == 1  # the one G1 edge, between two creases
    assert rep.g1 <= occ["g1"], (rep.side_g1, occ["side_g1"])  # was 0.767 against 0.696
    assert rep.g0 <= occ["g0"], (rep.side_g0, occ["side_g0"])
    assert rep.g0 <= tolerances.FILL_FIT_G0 * screw.size  # the G0 target (1.9e-6)
