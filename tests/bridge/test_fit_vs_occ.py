"""Fitting against OCC (issue 13): ``GeomAPI_PointsToBSplineSurface`` on the same grid, and
free-form faces of ../shared/realdata refitted with the deviation measured by OCC projection.

OCC's fitter takes a 3-D tolerance but no pole count; on the same data its pole count and its
error (measured by projection, like ours) are recorded against the adaptive hierarchy at the same
tolerance: the course's claim is fewer control points, which the sharp-feature field shows.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from occsurf.algorithms.fitting import fit_adaptive
from occsurf.algorithms.fitting._common import project_points
from occsurf.algorithms.fitting.scattered import base_parameters
from occsurf.examples.fitting import sharp_feature

REALDATA = Path(__file__).resolve().parents[3] / "shared" / "realdata"


def _occ_fit(P: np.ndarray, tol: float):
    from OCP.GeomAbs import GeomAbs_C2
    from OCP.GeomAPI import GeomAPI_PointsToBSplineSurface
    from OCP.gp import gp_Pnt
    from OCP.TColgp import TColgp_Array2OfPnt

    from occsurf.bridge.conversion.splines import from_occ

    m, n = P.shape[:2]
    arr = TColgp_Array2OfPnt(1, m, 1, n)
    for i in range(m):
        for j in range(n):
            arr.SetValue(i + 1, j + 1, gp_Pnt(*map(float, P[i, j])))
    api = GeomAPI_PointsToBSplineSurface()
    api.Init(arr, 3, 3, GeomAbs_C2, tol)
    assert api.IsDone()
    s = from_occ(api.Surface())
    pts = P.reshape(-1, 3)
    u, v = base_parameters(s, pts)
    return s, float(project_points(s, pts, u, v)[2].max())


def test_fewer_control_points_than_occ_fitter_on_a_sharp_feature():
    tol = 1e-3
    x = np.linspace(0, 1, 101)
    X, Y = np.meshgrid(x, x, indexing="ij")
    Z = sharp_feature(X, Y)
    ours = fit_adaptive(Z, tol)
    occ, occ_err = _occ_fit(np.stack([X, Y, Z], -1), tol)
    assert ours.converged and ours.max_error <= tol
    # OCC's Tol3D is its target, not a bound it guarantees; record both measured errors
    assert occ_err < 5 * tol
    assert ours.control_points_total < np.prod(occ.n_poles), (ours.control_points_total, occ.n_poles, occ_err)


@pytest.mark.slow
@pytest.mark.skipif(not REALDATA.is_dir(), reason="../shared/realdata (public CAD files) is absent")
@pytest.mark.parametrize("name, faces", [("pythonocc-core__sunglasses_lens.igs", [0, 1, 2]),
                                         ("occt__linkrods.step", [12])])
def test_realdata_faces_refit_within_tolerance(name, faces):
    from occsurf.bridge.modeling.fit import fit_input, read_fit_input

    for k in faces:
        inp = read_fit_input(REALDATA / name, face=k)
        size = float(np.ptp(inp.data.reshape(-1, 3), axis=0).max())
        res = fit_input(inp, 1e-3 * size)
        assert res.converged, (name, k, res.max_error)
        # between the samples the fit stays near the original face (OCC point projection)
        assert res.face_deviation <= 3e-3 * size, (name, k, res.face_deviation / size)


def _occ_distances(surface, pts: np.ndarray) -> np.ndarray:
    """Distance of each point to ``surface`` (ours, converted) by OCC's GeomAPI_ProjectPointOnSurf."""
    from OCP.GeomAPI import GeomAPI_ProjectPointOnSurf
    from OCP.gp import gp_Pnt

    from occsurf.bridge.conversion.splines import to_occ

    occ = to_occ(surface)
    proj = GeomAPI_ProjectPointOnSurf()
    out = np.empty(len(pts))
    for k, (x, y, z) in enumerate(pts):  # OCC projects one point per call
        proj.Init(gp_Pnt(float(x), float(y), float(z)), occ)
        out[k] = proj.LowerDistance() if proj.NbPoints() else np.inf
    return out


@pytest.mark.slow
def test_scattered_adaptive_fit_distances_agree_with_occ_projection():
    """A noisy scan-like cloud with one sharp feature: our measured distances (Newton from the data
    parameters) equal OCC's projections onto the same flat NURBS, and the tolerance holds by OCC's
    measure too; OCC's own fitter (which needs a grid: the same field sampled 101 x 101) needs
    more poles at the same tolerance."""
    from occsurf.algorithms.fitting import fit_adaptive_scattered

    tol = 2e-3
    rng = np.random.default_rng(11)
    k = 15000
    x, y = rng.random(k), rng.random(k)
    x[:4], y[:4] = [0, 1, 0, 1], [0, 0, 1, 1]
    P = np.c_[x, y, sharp_feature(x, y) + 2e-4 * rng.standard_normal(k)]
    fit = fit_adaptive_scattered(P, tol, params=np.c_[x, y])
    assert fit.converged and fit.hierarchy.overlays
    flat = fit.hierarchy.flatten()
    pick = np.r_[np.argsort(fit.distance)[-300:], rng.choice(k, 700, replace=False)]  # the worst and a sample
    occ_d = _occ_distances(flat, P[pick])
    # OCC searches globally, we go down from the data parameters: equal where both find the foot point
    np.testing.assert_allclose(fit.distance[pick], occ_d, atol=1e-9)
    assert occ_d.max() <= tol
    g = np.linspace(0, 1, 101)
    X, Y = np.meshgrid(g, g, indexing="ij")
    occ, occ_err = _occ_fit(np.stack([X, Y, sharp_feature(X, Y)], -1), tol)
    assert fit.control_points_total < np.prod(occ.n_poles), (fit.control_points_total, occ.n_poles, occ_err)


def _one_face_per_type(name: str) -> list[int]:
    from occsurf.bridge.exchange.reading import read_model

    seen: dict[str, int] = {}
    for k, f in enumerate(read_model(REALDATA / name).faces):
        seen.setdefault(f.surface_type, k)
    return sorted(seen.values())


@pytest.mark.slow
@pytest.mark.skipif(not REALDATA.is_dir(), reason="../shared/realdata (public CAD files) is absent")
@pytest.mark.parametrize("name", ["build123d__M6-1x12-countersunk-screw.step", "occt__linkrods.step",
                                  "occt__bearing.iges"])
def test_realdata_faces_of_every_type_refit_at_1e_4_of_their_size(name):
    """One face of each surface type per file (plane, cylinder, cone, torus, revolution, B-spline)
    sampled and refitted at 1e-4 x its size: the tolerance holds at the samples, and the fit stays
    near the original face between them by OCC's projection (the benchmark runs every face)."""
    from occsurf.bridge.modeling.fit import face_inputs, fit_input

    faces = _one_face_per_type(name)[:5]
    for k, inp in face_inputs(REALDATA / name, faces):
        assert not isinstance(inp, Exception), (name, k, inp)
        size = float(np.ptp(inp.data.reshape(-1, 3), axis=0).max())
        res = fit_input(inp, 1e-4 * size)
        assert res.converged, (name, k, res.max_error / size)
        # within tol at the samples; between them the benchmark measured at most 8.3e-5 x size over
        # every face of these files, so 3 x tol is a bound with room, not a guess
        assert res.face_deviation <= 3e-4 * size, (name, k, res.face_deviation / size)


@pytest.mark.skipif(not REALDATA.is_dir(), reason="../shared/realdata (public CAD files) is absent")
@pytest.mark.parametrize("name, face", [("occt__bearing.iges", 2), ("occt__bearing.iges", 5),
                                        ("pythonocc-core__sunglasses_lens.igs", 1)])
def test_face_deviation_equals_both_projections_on_every_point(name, face):
    """face_deviation runs OCC's extrema search only where it can raise the maximum; the value is
    exactly the largest over all points of the smaller of the two OCC projections (bearing face 2:
    the collapsed corner row where GeomAPI reports 1.7e-3 for a point on the surface)."""
    from OCP.GeomAPI import GeomAPI_ProjectPointOnSurf
    from OCP.gp import gp_Pnt
    from OCP.ShapeAnalysis import ShapeAnalysis_Surface

    from occsurf.algorithms.fitting import fit_grid
    from occsurf.bridge.modeling.fit import face_deviation, read_fit_input

    inp = read_fit_input(REALDATA / name, face=face)
    fitted = fit_grid(inp.data, 8, 3).surface  # a coarse fit: deviations of every size
    (u0, u1), (v0, v1) = fitted.domain
    P = fitted.evaluate_grid(np.linspace(u0, u1, 41), np.linspace(v0, v1, 41)).reshape(-1, 3)
    proj, sas = GeomAPI_ProjectPointOnSurf(), ShapeAnalysis_Surface(inp.face)
    both = []
    for x, y, z in P:
        p = gp_Pnt(float(x), float(y), float(z))
        proj.Init(p, inp.face)
        a = float(proj.LowerDistance()) if proj.NbPoints() else np.inf
        sas.ValueOfUV(p, 1e-12)
        both.append(min(a, float(sas.Gap())))
    assert face_deviation(fitted, inp.face) == max(both)


def test_face_deviation_pruning_keeps_the_maximum_of_the_minimum(monkeypatch):
    """The pruning alone, with OCC's two projections replaced by given distances per point: the
    result is max_i min(a_i, b_i) however the two disagree, and the extrema search is called only on
    points whose ValueOfUV gap exceeds the largest minimum found before them."""
    import OCP.GeomAPI
    import OCP.ShapeAnalysis

    from occsurf.algorithms import BSplineSurface
    from occsurf.bridge.modeling.fit import face_deviation

    rng = np.random.default_rng(5)
    s = BSplineSurface((1, 1), ([0, 0, 1, 1], [0, 0, 1, 1]), [[[0, 0, 0], [0, 1, 0]], [[1, 0, 0], [1, 1, 0]]])
    g = np.linspace(0, 1, 41)
    P = s.evaluate_grid(g, g).reshape(-1, 3)
    index = {tuple(p): i for i, p in enumerate(P)}
    gap, ext = rng.uniform(0, 1, len(P)), rng.uniform(0, 1, len(P))
    ext[rng.integers(len(P), size=50)] = np.inf  # no extremum found: the gap counts
    calls: list[int] = []

    class Surface:
        def __init__(self, surface):
            self.last = 0

        def ValueOfUV(self, p, tol):  # noqa: N802 (OCC's names)
            self.last = index[p.Coord()]

        def Gap(self):  # noqa: N802
            return float(gap[self.last])

    class Project:
        def Init(self, p, surface):  # noqa: N802
            self.i = index[p.Coord()]
            calls.append(self.i)

        def NbPoints(self):  # noqa: N802
            return 0 if np.isinf(ext[self.i]) else 1

        def LowerDistance(self):  # noqa: N802
            return float(ext[self.i])

    monkeypatch.setattr(OCP.ShapeAnalysis, "ShapeAnalysis_Surface", Surface)
    monkeypatch.setattr(OCP.GeomAPI, "GeomAPI_ProjectPointOnSurf", Project)
    want = float(np.max(np.minimum(gap, ext)))
    assert face_deviation(s, None) == want
    assert 0 < len(calls) < len(P) and all(gap[i] > 0 for i in calls)
