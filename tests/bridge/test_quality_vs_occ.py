"""Curvature maps (occsurf.algorithms.quality.curvature_map) against OpenCascade's
``GeomLProp_SLProps`` on the same points of the bit-identical ``to_occ`` copies, and of faces of
the public models in ../shared/realdata read through occsurf.bridge.

Tolerance: 1e-8 relative to ``max(|k1|, |k2|, 1/size)`` at each point (``RTOL``)
-------------------------------------------------------------------------------
Both sides evaluate the same closed formulas from derivatives that agree to ~1e-13 relative
(tests/bridge/test_kernel_vs_occ.py); curvatures are quotients, amplified by ``1/sin`` of the angle
between ``S_u`` and ``S_v``. Points with ``sin < 1e-2`` (where both sides lose digits) are left out
of the value comparison but checked for consistency of the degenerate flag. OCC's ``MaxCurvature``
and ``MinCurvature`` are ``H +- sqrt(H^2 - K)``: near an umbilic (sphere) that loses half the digits
(``sqrt(eps) ~ 1.5e-8`` relative), so k1, k2 are compared at ``RTOL_UMBILIC = 1e-7`` where
``k1 - k2 < 1e-4 max|k|``, elsewhere at ``RTOL * (1 + 3 max|k| / (k1 - k2))`` (the amplification of
that square root of errors ``RTOL`` in H and K). Measured here: <= 1e-12 on the random bicubic
faces and the torus; <= 1e-13 on the lens faces.

Real faces with clustered knots: ``occt__linkrods.step`` has degree (6, 8) rational faces whose first
v span is 1/10 of the domain, so ``|S_vv| ~ 3600`` against ``|S_v| ~ 0.8``; there OCC's and our
second derivatives differ by 1.6e-10 relative (round-off of two correct de Boor evaluations, not a
defect on either side), and the curvatures by up to 5.6e-8 relative (faces 17, 18; 16 of its 18
B-spline faces agree within 1e-8). That file is compared at ``RTOL_CLUSTERED = 1e-7``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from OCP.GeomLProp import GeomLProp_SLProps

from occsurf.algorithms import BSplineSurface
from occsurf.algorithms.quality import curvature_map
from occsurf.bridge.conversion.splines import to_occ
from tests.algorithms.test_quality_maps import sphere, torus, wavy

REALDATA = Path(__file__).resolve().parents[3] / "shared" / "realdata"
RTOL = 1e-8
RTOL_UMBILIC = 1e-7
RTOL_CLUSTERED = 1e-7
LPROP_TOL = 1e-9


def occ_grid_curvatures(occ, us, vs):
    """The user's loop: one ``GeomLProp_SLProps`` per grid point; NaN where OCC says undefined."""
    shape = (len(us), len(vs))
    out = {k: np.full(shape, np.nan) for k in ("K", "H", "k1", "k2")}
    out["n"] = np.full(shape + (3,), np.nan)
    pr = GeomLProp_SLProps(occ, 2, LPROP_TOL)
    for i, u in enumerate(us):
        for j, v in enumerate(vs):
            pr.SetParameters(float(u), float(v))
            try:
                if pr.IsNormalDefined():
                    out["n"][i, j] = pr.Normal().Coord()
                if not pr.IsCurvatureDefined():
                    continue
            except Exception:  # noqa: BLE001 - OCP exposes no common base class
                continue
            out["K"][i, j], out["H"][i, j] = pr.GaussianCurvature(), pr.MeanCurvature()
            out["k1"][i, j], out["k2"][i, j] = pr.MaxCurvature(), pr.MinCurvature()
    return out


def compare(s: BSplineSurface, us, vs, occ=None, rtol: float = RTOL) -> dict[str, float]:
    """Largest relative deviations; asserts the tolerances. Returns them for the messages."""
    cm = curvature_map(s, us, vs, "gaussian")
    ref = occ_grid_curvatures(to_occ(s) if occ is None else occ, cm.us, cm.vs)
    D = s.derivatives_grid(cm.us, cm.vs, 1)
    su, sv = D[..., 1, 0, :], D[..., 0, 1, :]
    sine = np.linalg.norm(np.cross(su, sv), axis=-1) / np.maximum(
        np.linalg.norm(su, axis=-1) * np.linalg.norm(sv, axis=-1), 1e-300)
    ok = (sine >= 1e-2) & np.isfinite(ref["K"])
    assert ok.mean() > 0.5, "too few comparable points"
    scale = np.maximum(np.maximum(np.abs(cm.k1), np.abs(cm.k2)), 1.0 / cm.size)[ok]
    dev = {}
    gap = (cm.k1 - cm.k2)[ok]
    for ours, key in ((cm.gaussian, "K"), (cm.mean, "H"), (cm.k1, "k1"), (cm.k2, "k2")):
        power = 2 if key == "K" else 1
        d = np.abs(ours[ok] - ref[key][ok]) / scale**power
        if key in ("k1", "k2"):
            # OCC's H +- sqrt(H^2 - K): errors e*s of H and e*s^2 of K (s = max|k|) give
            # d sqrt <= (2|H| dH + dK) / (k1 - k2) <= 3 e s^2 / gap; near umbilics half the digits go
            with np.errstate(divide="ignore"):
                amp = 1.0 + 3.0 * scale / gap
            allowed = np.where(gap < 1e-4 * scale, RTOL_UMBILIC, rtol * amp)
            assert np.all(d <= allowed), f"{key}: {np.max(d / allowed):.3g} x the allowed deviation"
            d = d / amp
        dev[key] = float(d.max()) if d.size else 0.0
        assert dev[key] <= rtol, f"{key}: {dev[key]:.3g} > {rtol}"
    n_dev = np.abs(np.einsum("...i,...i", cm.normals[ok], ref["n"][ok]) - 1).max()
    assert n_dev <= 1e-12, f"normals: {n_dev:.3g}"
    # points we call degenerate are points where OCC has no curvature either
    assert not np.any(np.isfinite(ref["K"][cm.degenerate]))
    return dev


def test_random_bicubic_faces():
    for seed in range(3):
        compare(wavy(9, seed), np.linspace(0, 1, 100), np.linspace(0, 1, 100))


def test_rational_torus_1e4_points():
    compare(torus(), np.linspace(0, 2 * np.pi, 100), np.linspace(0, 2 * np.pi, 100))


def test_sphere_poles_are_undefined_on_both_sides():
    s = sphere()
    cm = curvature_map(s, 50, 20)
    ref = occ_grid_curvatures(to_occ(s), cm.us, cm.vs)
    assert cm.n_degenerate == 40
    assert np.all(np.isnan(ref["K"][cm.degenerate]))
    compare(s, np.linspace(-1.5, 1.5, 60), np.linspace(0, 2 * np.pi, 60))


def _real_faces(name: str, limit: int):
    path = REALDATA / name
    if not path.exists():
        pytest.skip(f"{path} is absent (public models of ../shared/realdata)")
    from occsurf.bridge import read_iges, read_step

    model = read_iges(path) if path.suffix in (".igs", ".iges") else read_step(path)
    faces = [f for f in model.faces if f.surface_type == "BSplineSurface" and f.surface is not None]
    return faces[:limit]


@pytest.mark.parametrize(("name", "limit", "rtol"), [("pythonocc-core__sunglasses_lens.igs", 9, RTOL),
                                                     ("occt__linkrods.step", 18, RTOL_CLUSTERED)])
def test_real_bspline_faces(name, limit, rtol):
    """Free-form faces of public models, on the face's own OCC surface (location applied)."""
    faces = _real_faces(name, limit)
    assert faces
    for f in faces:
        s = f.surface
        (u0, u1), (v0, v1) = s.domain
        compare(s, np.linspace(u0, u1, 50), np.linspace(v0, v1, 50), occ=f.occ_surface, rtol=rtol)
