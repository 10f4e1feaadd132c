"""Optional numba kernel of :func:`~occsurf.algorithms.quality.curvature_map` on B-spline grids.

The NumPy path (``derivatives_grid`` then
:func:`~occsurf.algorithms.geometry.curvatures_from_derivatives`) is the reference. This kernel
fuses the same steps per grid point — the u-contraction of the v-contracted net (the banded product
of ``BSplineSurface.derivatives_grid``), the quotient rule (The NURBS Book A4.4) and the curvature
formulas of ``curvatures_from_derivatives`` — so the ``(m, n, 3, 3, 3)`` partials (216 MB per
million points) are never stored. ``tests/algorithms/test_quality_maps.py`` checks that both paths
agree to round-off.

Loaded lazily with the switches of :mod:`occsurf.algorithms._numba_kernels`: used from
:data:`~occsurf.algorithms.tolerances.NUMBA_MIN_POINTS` points on when numba is installed and
``OCCSURF_NO_NUMBA`` is not set; compiled once per machine (``cache=True``), serial.
"""

from __future__ import annotations

import math
import threading
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from .. import _numba_kernels as _nk
from .. import tolerances

if TYPE_CHECKING:
    from ..kernel.surface import BSplineSurface

__all__ = ["grid_curvatures"]

_lock = threading.Lock()
_state: dict[str, Any] = {"loaded": False, "kernel": None}
_F = NDArray[np.float64]  # the kernel's annotations are for the type checker only (numba infers from the arguments)
#: ``(points, normals, k1, k2, K, H, ok)`` on a grid: float arrays and the boolean ``ok``.
GridCurvatures = tuple[_F, _F, _F, _F, _F, _F, NDArray[np.bool_]]


def _curvature_grid(  # pragma: no cover
    Du: _F, su: NDArray[np.int64], p: int, G3: _F, k: int, rational: bool, normal_zero: float,
    P: _F, Nrm: _F, K1: _F, K2: _F, GK: _F, MH: _F, OK: NDArray[np.bool_],
) -> None:
    mu = Du.shape[0]
    mv = G3.shape[1]
    T = np.empty((3, 12))  # [k, l * kk + c]: homogeneous partials of one point
    S = np.empty((3, 3, 3))
    kk3 = 3 * k
    for a in range(mu):
        s0 = su[a] - p
        for b in range(mv):
            for d in range(3):
                for j in range(kk3):
                    T[d, j] = 0.0
            for i in range(p + 1):  # rows of G3 are contiguous: one pass over 3k values per row
                row = G3[s0 + i, b]
                d0, d1, d2 = Du[a, 0, i], Du[a, 1, i], Du[a, 2, i]
                for j in range(kk3):
                    g = row[j]
                    T[0, j] += d0 * g
                    T[1, j] += d1 * g
                    T[2, j] += d2 * g
            if rational:
                w = T[0, 0 * k + 3]
                w10, w01, w20, w11, w02 = T[1, 0 * k + 3], T[0, 1 * k + 3], T[2, 0 * k + 3], T[1, 1 * k + 3], T[0, 2 * k + 3]
                for c in range(3):
                    s00 = T[0, 0 * k + c] / w
                    s10 = (T[1, 0 * k + c] - w10 * s00) / w
                    s01 = (T[0, 1 * k + c] - w01 * s00) / w
                    S[0, 0, c] = s00
                    S[1, 0, c] = s10
                    S[0, 1, c] = s01
                    S[2, 0, c] = (T[2, 0 * k + c] - 2.0 * w10 * s10 - w20 * s00) / w
                    S[1, 1, c] = (T[1, 1 * k + c] - w10 * s01 - w01 * s10 - w11 * s00) / w
                    S[0, 2, c] = (T[0, 2 * k + c] - 2.0 * w01 * s01 - w02 * s00) / w
            else:
                for kk in range(3):
                    for ll in range(3):
                        for c in range(3):
                            S[kk, ll, c] = T[kk, ll * k + c]
            ux, uy, uz = S[1, 0, 0], S[1, 0, 1], S[1, 0, 2]
            vx, vy, vz = S[0, 1, 0], S[0, 1, 1], S[0, 1, 2]
            P[a, b, 0], P[a, b, 1], P[a, b, 2] = S[0, 0, 0], S[0, 0, 1], S[0, 0, 2]
            cx, cy, cz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx
            ncr = math.sqrt(cx * cx + cy * cy + cz * cz)
            lu = math.sqrt(ux * ux + uy * uy + uz * uz)
            lv = math.sqrt(vx * vx + vy * vy + vz * vz)
            big = max(lu, lv)
            if not ncr > normal_zero * big * big:
                OK[a, b] = False
                Nrm[a, b, 0] = Nrm[a, b, 1] = Nrm[a, b, 2] = np.nan
                K1[a, b] = K2[a, b] = GK[a, b] = MH[a, b] = np.nan
                continue
            OK[a, b] = True
            nx, ny, nz = cx / ncr, cy / ncr, cz / ncr
            Nrm[a, b, 0], Nrm[a, b, 1], Nrm[a, b, 2] = nx, ny, nz
            L = S[2, 0, 0] * nx + S[2, 0, 1] * ny + S[2, 0, 2] * nz
            M = S[1, 1, 0] * nx + S[1, 1, 1] * ny + S[1, 1, 2] * nz
            N = S[0, 2, 0] * nx + S[0, 2, 1] * ny + S[0, 2, 2] * nz
            E = ux * ux + uy * uy + uz * uz
            F = ux * vx + uy * vy + uz * vz
            G = vx * vx + vy * vy + vz * vz
            # shape operator in the frame e1 = S_u/|S_u|, e2 = n x e1 (as curvatures_from_derivatives)
            e1x, e1y, e1z = ux / lu, uy / lu, uz / lu
            e2x, e2y, e2z = ny * e1z - nz * e1y, nz * e1x - nx * e1z, nx * e1y - ny * e1x
            a11 = lu
            a12 = vx * e1x + vy * e1y + vz * e1z
            a22 = vx * e2x + vy * e2y + vz * e2z
            i11 = 1.0 / a11
            i12 = -a12 / (a11 * a22)
            i22 = 1.0 / a22
            wa = L * i11 * i11
            wb = i11 * (L * i12 + M * i22)
            wc = i12 * (L * i12 + 2.0 * M * i22) + N * i22 * i22
            half = 0.5 * (wa + wc)
            rad = math.hypot(0.5 * (wa - wc), wb)
            K1[a, b] = half + rad
            K2[a, b] = half - rad
            det = E * G - F * F
            GK[a, b] = (L * N - M * M) / det
            MH[a, b] = (E * N - 2.0 * F * M + G * L) / (2.0 * det)


def _load() -> Any:
    with _lock:
        if not _state["loaded"]:
            try:
                import numba

                try:
                    kern = numba.njit(cache=True, nogil=True, error_model="numpy")(_curvature_grid)
                except Exception:  # noqa: BLE001 - no writable cache directory
                    kern = numba.njit(nogil=True, error_model="numpy")(_curvature_grid)
            except Exception:  # noqa: BLE001 - numba missing or broken: NumPy path
                kern = None
            _state["kernel"] = kern
            _state["loaded"] = True
        return _state["kernel"]


def grid_curvatures(surface: BSplineSurface, us: np.ndarray, vs: np.ndarray) -> GridCurvatures | None:
    """``(points, normals, k1, k2, K, H, ok)`` on the grid by the fused kernel, or None (use NumPy).

    ``surface`` must be a 3-D :class:`~occsurf.algorithms.kernel.surface.BSplineSurface`; ``us``,
    ``vs`` validated grid parameters.
    """
    m, n = us.size, vs.size
    if not _nk.applies(m * n):
        return None
    kern = _load()
    if kern is None:
        return None
    G = surface._grid_v(vs, 2)  # (n_u, n, 3, k)
    k = G.shape[3]
    su, Du = surface._grid_basis(0, us, 2)
    G3 = np.ascontiguousarray(G.reshape(G.shape[0], n, 3 * k))
    P, Nrm = np.empty((m, n, 3)), np.empty((m, n, 3))
    K1, K2, GK, MH = (np.empty((m, n)) for _ in range(4))
    OK = np.empty((m, n), dtype=np.bool_)
    try:
        kern(np.ascontiguousarray(Du), np.ascontiguousarray(su, dtype=np.int64), int(surface.degree[0]), G3, int(k),
             bool(surface.is_rational), float(tolerances.NORMAL_ZERO), P, Nrm, K1, K2, GK, MH, OK)
    except Exception as err:  # noqa: BLE001 - an untested numba version: fall back, once
        import warnings

        warnings.warn(f"occsurf: numba curvature kernel failed ({err!r}); using NumPy", RuntimeWarning, stacklevel=3)
        _state["kernel"] = None
        return None
    return P, Nrm, K1, K2, GK, MH, OK
