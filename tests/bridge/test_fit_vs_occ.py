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
