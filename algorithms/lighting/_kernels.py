"""Optional numba kernel of :func:`~occsurf.algorithms.lighting.shade`: Warn's model fused per point.

The NumPy path of :mod:`.shading` is the reference. This kernel evaluates the same formulas
(course ch. 10, module docstring of :mod:`.shading`) point by point, all lights in one pass, so
none of the NumPy path's ``(3, m)`` temporaries is stored; it writes the same operations in the
same order (unit normal by the reciprocal of its length, ``V``, ``N.V``, the two-sided flip, per
light ``L``, the factor ``concentration x cone x flaps x fall-off``, Lambert and Phong terms,
integer exponents by the same repeated squaring), so with integer exponents the two paths agree
bit for bit, and to the last ulps of ``pow``/``acos`` otherwise. Three shortcuts skip work whose
result is exactly zero in the reference: a light behind the surface (``N.L <= 0``), a point
outside a hard flap or cone, and behind a concentrated light (factor 0). The cone's ``acos`` is
taken only on its soft edge: inside ``angle - edge`` the smoothstep is 1, outside ``angle`` 0.

``tests/algorithms/test_lighting.py`` checks both paths against each other. Loaded lazily with
the switches of :mod:`occsurf.algorithms._numba_kernels`: used from
:data:`~occsurf.algorithms.tolerances.NUMBA_MIN_POINTS` points on when numba is installed and
``OCCSURF_NO_NUMBA`` is not set; compiled once per machine (``cache=True``), serial per call
(:func:`~.shading.shade` runs blocks on threads: the kernel releases the GIL).
"""

from __future__ import annotations

import math
import threading
from typing import Any

import numpy as np

from .. import _numba_kernels as _nk
from .. import tolerances

__all__ = ["pack_lights", "shade_points"]

_lock = threading.Lock()
_state: dict[str, Any] = {"loaded": False, "kernel": None}

# Columns of the packed light table (one row per light, float64).
_DIRECTIONAL, _POS, _DIR, _FRAME, _LO, _HI, _EDGE, _HAS_FLAPS = 0, 1, 4, 7, 16, 19, 22, 23
_CONC, _HAS_CONE, _THETA, _DELTA, _COS_OUT, _COS_IN, _FALL_K, _D0 = 24, 25, 26, 27, 28, 29, 30, 31
_WIDTH = 32


def pack_lights(setup: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(table (k, 32), ckd (k, 3), cks (k, 3))``: the lights of a validated setup as numbers,
    with ``c_j * k_d * C_d`` and ``c_j * k_s * C_s`` per channel (Python floats, as the reference)."""
    mat = setup.material
    kd = [mat.diffuse * c for c in mat.color]
    ks = [mat.specular * c for c in mat.specular_color]
    k = len(setup.lights)
    table = np.zeros((k, _WIDTH))
    ckd, cks = np.zeros((k, 3)), np.zeros((k, 3))
    for j, light in enumerate(setup.lights):
        row = table[j]
        row[_DIRECTIONAL] = light.position is None
        row[_POS:_POS + 3] = light.origin
        row[_DIR:_DIR + 3] = light.direction
        row[_FRAME:_FRAME + 9] = light.frame.ravel()
        row[_LO:_LO + 3] = [lo for lo, _ in light.flaps]
        row[_HI:_HI + 3] = [hi for _, hi in light.flaps]
        row[_EDGE] = light.flap_edge
        row[_HAS_FLAPS] = light.has_flaps
        row[_CONC] = light.concentration
        if light.cone_angle_deg is not None:
            theta, delta = math.radians(float(light.cone_angle_deg)), math.radians(light.cone_edge_deg)
            row[_HAS_CONE], row[_THETA], row[_DELTA] = 1.0, theta, delta
            row[_COS_OUT], row[_COS_IN] = math.cos(theta), math.cos(theta - delta)
        row[_FALL_K] = {"none": 0.0, "inverse": 1.0, "inverse_square": 2.0}[light.falloff]
        row[_D0] = light.falloff_distance or 1.0
        c = [float(x) for x in light.rgb]
        ckd[j] = [c[ch] * kd[ch] for ch in range(3)]
        cks[j] = [c[ch] * ks[ch] for ch in range(3)]
    return table, ckd, cks


# ---------------------------------------------------------------------------------------- kernel
# The points are shaded in chunks of _CHUNK, stage by stage as the NumPy path does, each stage one
# loop without branches on the data (selects only): LLVM turns those loops into SIMD code, and no
# branch on a random normal stalls the pipeline (a scalar loop with per-point early exits ran no
# faster than NumPy, measured: 21 M points/s with one light).
_CHUNK = 256


def _ipow_into(x, s, out, base, n):  # pragma: no cover - compiled
    """``out[:n] = x[:n] ** s`` for ``x >= 0``: integer ``s`` up to 4096 by repeated squaring as
    :func:`.shading._ipow` (the same products in the same order; ``1.0 * x`` is ``x``), else ``pow``."""
    if s == 1.0:
        for i in range(n):
            out[i] = x[i]
        return
    if s == math.floor(s) and 0.0 < s <= 4096.0:
        k = int(s)
        for i in range(n):
            out[i] = 1.0
            base[i] = x[i]
        while True:
            if k & 1:
                for i in range(n):
                    out[i] = out[i] * base[i]
            k >>= 1
            if k == 0:
                return
            for i in range(n):
                base[i] = base[i] * base[i]
    for i in range(n):
        out[i] = x[i] ** s


def _smooth(t):  # pragma: no cover - compiled
    t = min(max(t, 0.0), 1.0)
    return t * t * (3.0 - 2.0 * t)


def _light_into(T, j, P, s, n, Nx, Ny, Nz, Vx, Vy, Vz, NV, specular, shininess, Lx, Ly, Lz, D, NL, CG, F, RV, W,
                W2):  # pragma: no cover - compiled
    """Light ``j`` on points ``s .. s+n``: ``NL`` (N.L), ``F`` (Warn's factor), ``RV`` (the Phong
    term before the factor), as ``shading._toward_light`` and ``shading._shade_block``."""
    directional = T[j, _DIRECTIONAL] != 0.0
    dx, dy, dz = T[j, _DIR], T[j, _DIR + 1], T[j, _DIR + 2]
    ox, oy, oz = T[j, _POS], T[j, _POS + 1], T[j, _POS + 2]
    for i in range(n):
        if directional:
            lx, ly, lz, d = -dx, -dy, -dz, 1.0
        else:
            lx, ly, lz = ox - P[s + i, 0], oy - P[s + i, 1], oz - P[s + i, 2]
            d = math.sqrt(lx * lx + ly * ly + lz * lz)
            inv = 1.0 / d
            at = d == 0.0  # a point at the light gets no light
            lx, ly, lz = (0.0 if at else lx * inv), (0.0 if at else ly * inv), (0.0 if at else lz * inv)
        Lx[i], Ly[i], Lz[i], D[i] = lx, ly, lz, d
        NL[i] = Nx[i] * lx + Ny[i] * ly + Nz[i] * lz
        F[i] = 0.0 if d == 0.0 else 1.0
        CG[i] = -(lx * dx + ly * dy + lz * dz)
    conc = T[j, _CONC]
    if not directional and conc > 0.0:
        for i in range(n):
            W[i] = max(CG[i], 0.0)
        _ipow_into(W, conc, W2, RV, n)
        for i in range(n):
            F[i] = F[i] * W2[i]
    if not directional and T[j, _HAS_CONE] != 0.0:
        delta = T[j, _DELTA]
        cos_out, cos_in, theta = T[j, _COS_OUT], T[j, _COS_IN], T[j, _THETA]
        if delta == 0.0:
            for i in range(n):
                F[i] = F[i] * (1.0 if CG[i] >= cos_out else 0.0)
        else:
            for i in range(n):  # the smoothstep is 1 inside angle - edge, 0 outside angle: acos on the edge only
                c = CG[i]
                W[i] = 1.0 if c >= cos_in else (0.0 if c <= cos_out else -1.0)
            for i in range(n):
                if W[i] < 0.0:
                    W[i] = _smooth((theta - math.acos(min(max(CG[i], -1.0), 1.0))) / delta)
            for i in range(n):
                F[i] = F[i] * W[i]
    if T[j, _HAS_FLAPS] != 0.0:
        _flaps_into(T, j, P, s, n, ox, oy, oz, F, W)
    k = T[j, _FALL_K]
    if not directional and k != 0.0:
        d0 = T[j, _D0]
        for i in range(n):
            ratio = d0 / max(D[i], d0)
            F[i] = F[i] * (ratio if k == 1.0 else ratio * ratio)
    if specular:
        for i in range(n):
            rv = 2.0 * NL[i] * NV[i]
            rv -= Lx[i] * Vx[i] + Ly[i] * Vy[i] + Lz[i] * Vz[i]
            rv = rv if rv > 0.0 else 0.0
            W[i] = rv if NL[i] > 0.0 else 0.0
        if shininess != 0.0:
            _ipow_into(W, shininess, RV, W2, n)
        else:
            for i in range(n):
                RV[i] = 1.0 if NL[i] > 0.0 else 0.0


def _flaps_into(T, j, P, s, n, ox, oy, oz, F, W):  # pragma: no cover - compiled
    """``F *=`` the flaps of light ``j`` (as ``shading._flap_mask``, in its order: the mask of all
    axes first, 1 inside, 0 outside, the smoothstep over a soft edge; a directional light's origin
    is the model's). ``W`` is scratch."""
    e = T[j, _EDGE]
    for i in range(n):
        W[i] = 1.0
    for k in range(3):
        lo, hi = T[j, _LO + k], T[j, _HI + k]
        lo_open, hi_open = math.isinf(lo), math.isinf(hi)
        if lo_open and hi_open:
            continue
        f0, f1, f2 = T[j, _FRAME + 3 * k], T[j, _FRAME + 3 * k + 1], T[j, _FRAME + 3 * k + 2]
        for i in range(n):
            q = f0 * (P[s + i, 0] - ox) + f1 * (P[s + i, 1] - oy) + f2 * (P[s + i, 2] - oz)
            if e == 0.0:
                W[i] = W[i] if (q >= lo and q <= hi) else 0.0
            else:
                if not lo_open:
                    W[i] = W[i] * _smooth((q - lo) / e)
                if not hi_open:
                    W[i] = W[i] * _smooth((hi - q) / e)
    for i in range(n):
        F[i] = F[i] * W[i]


def _shade(P, N, E, lights, ckd, cks, amb, two_sided, specular, shininess, normal_zero, out):  # pragma: no cover
    """``out[i] = `` Warn's colour of point ``i`` (``E`` of shape ``(1, 3)``: one eye for all)."""
    m = P.shape[0]
    one_eye = E.shape[0] == 1
    C = _CHUNK
    Nx, Ny, Nz, Vx, Vy, Vz, NV = np.empty(C), np.empty(C), np.empty(C), np.empty(C), np.empty(C), np.empty(C), np.empty(C)
    R, G, B, Lx, Ly, Lz, D = np.empty(C), np.empty(C), np.empty(C), np.empty(C), np.empty(C), np.empty(C), np.empty(C)
    NL, CG, F, RV, W, W2 = np.empty(C), np.empty(C), np.empty(C), np.empty(C), np.empty(C), np.empty(C)
    for s in range(0, m, C):
        n = min(C, m - s)
        for i in range(n):
            nx, ny, nz = N[s + i, 0], N[s + i, 1], N[s + i, 2]
            inv = 1.0 / math.sqrt(nx * nx + ny * ny + nz * nz)
            nx, ny, nz = nx * inv, ny * inv, nz * inv
            e = 0 if one_eye else s + i
            vx, vy, vz = E[e, 0] - P[s + i, 0], E[e, 1] - P[s + i, 1], E[e, 2] - P[s + i, 2]
            inv = 1.0 / math.sqrt(vx * vx + vy * vy + vz * vz)
            vx, vy, vz = vx * inv, vy * inv, vz * inv
            nv = nx * vx + ny * vy + nz * vz
            flip = -1.0 if (two_sided and nv < 0.0) else 1.0
            Nx[i], Ny[i], Nz[i], NV[i] = nx * flip, ny * flip, nz * flip, nv * flip
            Vx[i], Vy[i], Vz[i] = vx, vy, vz
            R[i], G[i], B[i] = amb[0], amb[1], amb[2]
        for j in range(lights.shape[0]):
            _light_into(lights, j, P, s, n, Nx, Ny, Nz, Vx, Vy, Vz, NV, specular, shininess, Lx, Ly, Lz, D, NL, CG, F,
                        RV, W, W2)
            k0, k1, k2, c0, c1, c2 = ckd[j, 0], ckd[j, 1], ckd[j, 2], cks[j, 0], cks[j, 1], cks[j, 2]
            for i in range(n):
                diff = (NL[i] if NL[i] > 0.0 else 0.0) * F[i]
                spec = RV[i] * F[i] if specular else 0.0
                R[i] += diff * k0 + spec * c0
                G[i] += diff * k1 + spec * c1
                B[i] += diff * k2 + spec * c2
        for i in range(n):
            nx, ny, nz = N[s + i, 0], N[s + i, 1], N[s + i, 2]
            bad = not (math.sqrt(nx * nx + ny * ny + nz * nz) > normal_zero)
            out[s + i, 0] = np.nan if bad else R[i]
            out[s + i, 1] = np.nan if bad else G[i]
            out[s + i, 2] = np.nan if bad else B[i]


_HELPERS = ("_ipow_into", "_smooth", "_light_into", "_flaps_into")


def _load() -> Any:
    with _lock:
        if not _state["loaded"]:
            kern = None
            try:
                import numba

                g = globals()
                for name in _HELPERS:
                    g[name] = _nk._jit(numba, g[name], inline="always")
                kern = _nk._jit(numba, _shade)
            except Exception:  # noqa: BLE001 - numba missing or broken: NumPy path
                kern = None
            _state["kernel"] = kern
            _state["loaded"] = True
        return _state["kernel"]


def shade_points(n_points: int) -> Any:
    """The compiled kernel when it applies to ``n_points`` points (numba installed, not switched
    off, at least ``NUMBA_MIN_POINTS``), else None (use the NumPy path)."""
    if not _nk.applies(n_points):
        return None
    return _load()


def run(kern: Any, P: np.ndarray, N: np.ndarray, E: np.ndarray, packed: tuple[np.ndarray, np.ndarray, np.ndarray],
        amb: np.ndarray, two_sided: bool, specular: bool, shininess: float, out: np.ndarray) -> bool:
    """Shade one block into ``out``; False if the kernel failed (it is then dropped, with a warning)."""
    table, ckd, cks = packed
    try:
        kern(P, N, E, table, ckd, cks, amb, two_sided, specular, shininess, float(tolerances.LIGHT_DIRECTION_ZERO),
             out)
    except Exception as err:  # noqa: BLE001 - an untested numba version: fall back, once
        import warnings

        warnings.warn(f"occsurf: numba lighting kernel failed ({err!r}); using NumPy", RuntimeWarning, stacklevel=3)
        _state["kernel"] = None
        return False
    return True
