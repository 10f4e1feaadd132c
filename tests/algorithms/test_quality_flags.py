"""Problem areas of faces (occsurf.algorithms.quality.flags): every kind is produced on a surface
built to have it, and is absent from the closed-form surfaces that do not; thresholds are
tolerances (an override changes the answer)."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose

from occsurf.algorithms import BSplineSurface, tolerances
from occsurf.algorithms.errors import InvalidGeometryError
from occsurf.algorithms.quality import FLAG_KINDS, face_flags

from .test_quality_maps import cylinder, sphere, torus

U12 = np.r_[0, 0, 0, 0, np.linspace(0, 1, 10)[1:-1], 1, 1, 1, 1]


def dome(bump: float = 0.0, plateau: bool = False) -> BSplineSurface:
    g = np.linspace(0, 1, 12)
    X, Y = np.meshgrid(g, g, indexing="ij")
    Z = 0.5 * (X - 0.5) ** 2 + 0.5 * (Y - 0.5) ** 2
    if plateau:
        Z = np.where((np.abs(X - 0.5) < 0.3) & (np.abs(Y - 0.5) < 0.3), 0.5 * 0.3**2 + 0.0 * X, Z)
        Z = np.maximum(Z, 0.5 * 0.3**2)
    Z[6, 6] += bump
    return BSplineSurface((3, 3), (U12, U12), np.stack([X, Y, Z], -1))


def kinds(flags):
    return sorted({f.kind for f in flags})


def test_clean_closed_forms_have_no_curvature_flags():
    assert face_flags(torus()) == []
    assert face_flags(cylinder()) == []
    assert face_flags(dome()) == []


def test_sphere_poles_are_near_degenerate():
    f = face_flags(sphere())
    assert kinds(f) == ["near_degenerate_normal"] and len(f) == 2
    assert_allclose(sorted(abs(x.location[2]) for x in f), [2.0, 2.0], atol=1e-12)
    assert all(x.value == 0.0 and "pole" in x.suggestion for x in f)


def test_bump_is_a_wiggle_located_at_the_bump():
    f = face_flags(dome(bump=0.05))
    w = [x for x in f if x.kind == "wiggle"]
    assert len(w) >= 1
    for x in w:
        assert np.linalg.norm(x.uv - 0.5) < 0.2
        assert x.value >= 2 and "knot removal" in x.suggestion and "least squares" in x.suggestion
    # a loose wiggle threshold hides a bump this small
    with tolerances.override(QUALITY_WIGGLE_CURVATURE=100.0):
        assert not [x for x in face_flags(dome(bump=0.05)) if x.kind == "wiggle"]
    assert not [x for x in face_flags(dome(bump=0.05), thresholds={"QUALITY_WIGGLE_CURVATURE": 100.0})
                if x.kind == "wiggle"]


def test_flat_spot_on_a_curved_face():
    f = face_flags(dome(plateau=True))
    flat = [x for x in f if x.kind == "flat_spot"]
    assert len(flat) == 1 and flat[0].value < tolerances.QUALITY_FLAT_SPOT_RATIO
    assert np.linalg.norm(flat[0].uv - 0.5) < 0.25 and "hierarchical" in flat[0].suggestion


def spiky(height: float) -> BSplineSurface:
    """A gentle bowl (|k| ~ 0.2) on a fine 40 x 40 net with one pole lifted: a narrow spike."""
    n = 40
    g = np.linspace(0, 1, n)
    X, Y = np.meshgrid(g, g, indexing="ij")
    Z = 0.05 * ((X - 0.5) ** 2 + (Y - 0.5) ** 2)
    Z[20, 20] += height
    U = np.r_[0, 0, 0, 0, np.linspace(0, 1, n - 2)[1:-1], 1, 1, 1, 1]
    return BSplineSurface((3, 3), (U, U), np.stack([X, Y, Z], -1))


def test_curvature_spike():
    f = face_flags(spiky(0.002))
    spikes = [x for x in f if x.kind == "curvature_spike"]
    assert len(spikes) == 1 and spikes[0].value > 10
    assert np.linalg.norm(spikes[0].uv - 20 / 39) < 0.05
    assert "knot removal" in spikes[0].suggestion
    assert not [x for x in face_flags(spiky(0.0)) if x.kind == "curvature_spike"]
    # the ratio is a tolerance
    assert not [x for x in face_flags(spiky(0.002), thresholds={"QUALITY_SPIKE_RATIO": 1e3})
                if x.kind == "curvature_spike"]


def test_ill_parametrisation():
    # poles bunched towards u = 0: the Jacobian varies by far more than 100x
    g = np.linspace(0, 1, 8)
    X, Y = np.meshgrid(g**4, g, indexing="ij")
    U = np.r_[0, 0, 0, 0, np.linspace(0, 1, 6)[1:-1], 1, 1, 1, 1]
    s = BSplineSurface((3, 3), (U, U), np.stack([X, Y, 0.1 * X * Y], -1))
    f = [x for x in face_flags(s) if x.kind == "ill_parametrisation"]
    assert len(f) == 1 and f[0].value > 100 and f[0].uv[0] < 0.1
    assert "reparametrise" in f[0].suggestion
    # a uniform net is fine
    X, Y = np.meshgrid(g, g, indexing="ij")
    assert not face_flags(BSplineSurface((3, 3), (U, U), np.stack([X, Y, 0.1 * X * Y], -1)))


def test_flag_dict_and_bad_input():
    f = face_flags(sphere())[0]
    d = f.to_dict()
    assert d["kind"] in FLAG_KINDS and len(d["location"]) == 3 and len(d["uv"]) == 2
    with pytest.raises(InvalidGeometryError, match="thresholds"):
        face_flags(sphere(), thresholds={"NORMAL_ZERO": 1.0})
    with pytest.raises(InvalidGeometryError, match="thresholds"):
        face_flags(sphere(), thresholds=[1, 2])
    with pytest.raises(InvalidGeometryError, match="surface"):
        face_flags(None)


def test_masked_face_reports_only_inside():
    m = np.zeros((64, 64), bool)
    m[10:50, 10:50] = True
    f = face_flags(sphere(), mask=m)
    assert f == []  # the poles are trimmed away


# ---------------------------------------------------------------------------------------- cone apex
def cone(bump: float = 0.0, pole: tuple[int, int] = (2, 3)) -> BSplineSurface:
    """A right circular cone (apex at the origin, half-angle atan(1/2)) revolved exactly from its
    straight generator (u along it, arc length; v the angle), degree raised to 3 and refined to 8
    poles along u (both exact); ``bump`` moves one pole off the cone along its normal."""
    from occsurf.algorithms import BSplineCurve
    from occsurf.algorithms.construction import revolve

    gen = BSplineCurve(1, [0, 0, 1, 1], [[0, 0, 0], [1, 0, 2.0]])
    surf = revolve(gen, [0, 0, 0], [0, 0, 1]).elevate_degree(2, direction="u").refine([0.2, 0.4, 0.6, 0.8],
                                                                                      direction="u")
    if bump:
        P = surf.control_points.copy()
        i, j = pole
        radial = P[i, j, :2] / max(np.linalg.norm(P[i, j, :2]), 1e-300)
        P[i, j] += bump * np.r_[2 * radial, -1.0] / np.sqrt(5)  # along the cone's normal there
        surf = BSplineSurface(surf.degree, surf.knots, P, weights=surf.weights)
    return surf


#: The cone's samples with its seam (angle 0) left out, as the mask of a trimmed face from OCC's
#: triangulation leaves it: the apex samples next to it then have a window mostly outside, which
#: is where the plain ratio saw a spike (20x) on every cone.
SEAM_OUT = np.ones((41, 41), bool)
SEAM_OUT[:, 0] = False


def test_cone_apex_is_not_a_curvature_spike():
    """A true cone's curvature grows as 1 / distance to the apex: geometry, not a spike. Without the
    cone test (QUALITY_CONE_APEX_TOL = 0: round-off makes no window conical) the samples next to
    the apex are flagged, so the test can fail."""
    c = cone()
    for mask in (None, SEAM_OUT):
        assert "curvature_spike" not in kinds(face_flags(c, us=41, vs=41, mask=mask))
    with tolerances.override(QUALITY_CONE_APEX_TOL=0.0):
        assert "curvature_spike" in kinds(face_flags(c, us=41, vs=41, mask=SEAM_OUT))


@pytest.mark.parametrize(("bump", "pole"), [(0.2, (1, 2)), (0.4, (2, 3))])
def test_real_spike_on_a_cone_is_still_flagged(bump, pole):
    """A pole pushed off the cone next to the apex: the window is no longer conical (tangent planes
    miss the apex), and the spike is flagged (a bump half-way up is a broad one: a wiggle there)."""
    flags = [f for f in face_flags(cone(bump=bump, pole=pole), us=41, vs=41, mask=SEAM_OUT)
             if f.kind == "curvature_spike"]
    assert flags
    assert all(f.value > tolerances.QUALITY_SPIKE_RATIO for f in flags)
