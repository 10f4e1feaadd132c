"""Optional numba kernel of :func:`~occsurf.algorithms.lighting.shade`: Warn's model fused in chunks.

The NumPy path of :mod:`.shading` is the reference. This kernel evaluates the same formulas
(course ch. 10, module docstring of :mod:`.shading`) on chunks of 256 points that stay in the
first-level cache, all lights per chunk, instead of the NumPy path's ``(3, block)`` temporaries
per operation. It writes the same operations in the same order (unit normal by the reciprocal
of its length, ``V``, ``N.V``, the two-sided flip, per light ``L``, the factor ``concentration x
cone x flaps x fall-off``, Lambert and Phong terms, integer exponents by the same repeated
squaring), so with integer exponents the two paths agree bit for bit, and to the last ulps of
``pow``/``acos`` otherwise. The cone's ``acos`` is taken only on its soft edge: inside ``angle -
edge`` the smoothstep is 1, outside ``angle`` 0 (what the reference computes there, to the
rounding of a smoothstep whose slope is zero at both ends).

``tests/algorithms/test_lighting.py`` checks both paths against each other. Loaded lazily with
the switches of :mod:`occsurf.algorithms._numba_kernels`: used from
:data:`~occsurf.algorithms.tolerances.NUMBA_MIN_POINTS` points on when numba is installed and
``OCCSURF_NO_NUMBA`` is not set; compiled once per machine (``cache=True``), serial per call
(:func:`~.shading.shade` runs blocks on threads: the kernel releases the GIL).
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
    from .model import LightingSetup

__all__ = ["pack_lights", "shade_points"]

_lock = threading.Lock()
_state: dict[str, Any] = {"loaded": False, "kernel": None}

# Columns of the packed light table (one row per light, float64).
_DIRECTIONAL, _POS, _DIR, _FRAME, _LO, _HI, _EDGE, _HAS_FLAPS = 0, 1, 4, 7, 16, 19, 22, 23
_CONC, _HAS_CONE, _THETA, _DELTA, _COS_OUT, _COS_IN, _FALL_K, _D0 = 24, 25, 26, 27, 28, 29, 30, 31
_WIDTH = 32


def pack_lights(setup: LightingSetup) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
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
# loop without branches on the data (selects only) over rows of one scratch buffer at fixed
# offsets, the chunk's points and normals first copied there component-major: LLVM turns those
# loops into SIMD code, and no branch on a random normal stalls the pipeline. Measured: a scalar
# loop with per-point early exits ran at NumPy's speed; loops over point-major (m, 3) arrays or
# over one scratch array per quantity were not vectorised; a transposed copy of the whole input
# (as the NumPy path makes) cost a third of the time.
_CHUNK = 256
_F = NDArray[np.float64]  # the annotations are for the type checker only (numba infers from the arguments)
(_S_NX, _S_NY, _S_NZ, _S_VX, _S_VY, _S_VZ, _S_NV, _S_R, _S_G, _S_B, _S_LX, _S_LY, _S_LZ, _S_D, _S_NL, _S_CG, _S_F,
 _S_RV, _S_W, _S_W2, _S_BAD, _S_PX, _S_PY, _S_PZ) = (k * _CHUNK for k in range(24))
_S_ROWS = 24


def _ipow_into(S: _F, x: int, s: float, o: int, b: int, n: int) -> None:  # pragma: no cover - compiled
    """``S[o:o+n] = S[x:x+n] ** s`` for values >= 0: integer ``s`` up to 4096 by repeated squaring
    as :func:`.shading._ipow` (the same products in the same order; ``1.0 * x`` is ``x``), else
    ``pow``. ``b`` is a scratch row."""
    if s == 1.0:
        for i in range(n):
            S[o + i] = S[x + i]
        return
    if s == math.floor(s) and 0.0 < s <= 4096.0:
        k = int(s)
        for i in range(n):
            S[o + i] = 1.0
            S[b + i] = S[x + i]
        while True:
            if k & 1:
                for i in range(n):
                    S[o + i] = S[o + i] * S[b + i]
            k >>= 1
            if k == 0:
                return
            for i in range(n):
                S[b + i] = S[b + i] * S[b + i]
    for i in range(n):
        S[o + i] = S[x + i] ** s


def _smooth(t: float) -> float:  # pragma: no cover - compiled
    t = min(max(t, 0.0), 1.0)
    return t * t * (3.0 - 2.0 * t)


def _light_into(T: _F, j: int, n: int, S: _F, specular: bool, shininess: float) -> None:  # pragma: no cover - compiled
    """Light ``j`` on points ``s .. s+n``: rows NL (N.L), F (Warn's factor), RV (the Phong term
    before the factor), as ``shading._toward_light`` and ``shading._shade_block``."""
    directional = T[j, _DIRECTIONAL] != 0.0
    dx, dy, dz = T[j, _DIR], T[j, _DIR + 1], T[j, _DIR + 2]
    ox, oy, oz = T[j, _POS], T[j, _POS + 1], T[j, _POS + 2]
    if directional:
        for i in range(n):
            S[_S_LX + i], S[_S_LY + i], S[_S_LZ + i], S[_S_D + i] = -dx, -dy, -dz, 1.0
    else:
        for i in range(n):
            lx, ly, lz = ox - S[_S_PX + i], oy - S[_S_PY + i], oz - S[_S_PZ + i]
            d = math.sqrt(lx * lx + ly * ly + lz * lz)
            inv = 1.0 / d
            at = d == 0.0  # a point at the light gets no light
            S[_S_LX + i] = 0.0 if at else lx * inv
            S[_S_LY + i] = 0.0 if at else ly * inv
            S[_S_LZ + i] = 0.0 if at else lz * inv
            S[_S_D + i] = d
    for i in range(n):
        lx, ly, lz = S[_S_LX + i], S[_S_LY + i], S[_S_LZ + i]
        S[_S_NL + i] = S[_S_NX + i] * lx + S[_S_NY + i] * ly + S[_S_NZ + i] * lz
        S[_S_F + i] = 0.0 if S[_S_D + i] == 0.0 else 1.0
        S[_S_CG + i] = -(lx * dx + ly * dy + lz * dz)
    conc = T[j, _CONC]
    if not directional and conc > 0.0:
        for i in range(n):
            c = S[_S_CG + i]
            S[_S_W + i] = c if c > 0.0 else 0.0
        _ipow_into(S, _S_W, conc, _S_W2, _S_RV, n)
        for i in range(n):
            S[_S_F + i] = S[_S_F + i] * S[_S_W2 + i]
    if not directional and T[j, _HAS_CONE] != 0.0:
        _cone_into(T, j, S, n)
    if T[j, _HAS_FLAPS] != 0.0:
        _flaps_into(T, j, n, ox, oy, oz, S)
    k = T[j, _FALL_K]
    if not directional and k != 0.0:
        d0 = T[j, _D0]
        for i in range(n):
            ratio = d0 / max(S[_S_D + i], d0)
            S[_S_F + i] = S[_S_F + i] * (ratio if k == 1.0 else ratio * ratio)
    if specular:
        for i in range(n):
            rv = 2.0 * S[_S_NL + i] * S[_S_NV + i]
            rv -= S[_S_LX + i] * S[_S_VX + i] + S[_S_LY + i] * S[_S_VY + i] + S[_S_LZ + i] * S[_S_VZ + i]
            rv = rv if rv > 0.0 else 0.0
            S[_S_W + i] = rv if S[_S_NL + i] > 0.0 else 0.0
        if shininess != 0.0:
            _ipow_into(S, _S_W, shininess, _S_RV, _S_W2, n)
        else:
            for i in range(n):
                S[_S_RV + i] = 1.0 if S[_S_NL + i] > 0.0 else 0.0


def _cone_into(T: _F, j: int, S: _F, n: int) -> None:  # pragma: no cover - compiled
    """Row F times the cone of light ``j`` (as ``shading._cone``): a step at the angle, or the
    smoothstep over the soft edge, whose ``acos`` is taken on the edge only (1 inside, 0 outside)."""
    delta = T[j, _DELTA]
    cos_out, cos_in, theta = T[j, _COS_OUT], T[j, _COS_IN], T[j, _THETA]
    if delta == 0.0:
        for i in range(n):
            S[_S_F + i] = S[_S_F + i] * (1.0 if S[_S_CG + i] >= cos_out else 0.0)
        return
    for i in range(n):
        c = S[_S_CG + i]
        S[_S_W + i] = 1.0 if c >= cos_in else (0.0 if c <= cos_out else -1.0)
    for i in range(n):
        if S[_S_W + i] < 0.0:
            S[_S_W + i] = _smooth((theta - math.acos(min(max(S[_S_CG + i], -1.0), 1.0))) / delta)
    for i in range(n):
        S[_S_F + i] = S[_S_F + i] * S[_S_W + i]


def _flaps_into(T: _F, j: int, n: int, ox: float, oy: float, oz: float, S: _F) -> None:  # pragma: no cover - compiled
    """Row F times the flaps of light ``j`` (as ``shading._flap_mask``, in its order: the mask of
    all axes first, 1 inside, 0 outside, the smoothstep over a soft edge; a directional light's
    origin is the model's)."""
    e = T[j, _EDGE]
    for i in range(n):
        S[_S_W + i] = 1.0
    for k in range(3):
        lo, hi = T[j, _LO + k], T[j, _HI + k]
        lo_open, hi_open = math.isinf(lo), math.isinf(hi)
        if lo_open and hi_open:
            continue
        f0, f1, f2 = T[j, _FRAME + 3 * k], T[j, _FRAME + 3 * k + 1], T[j, _FRAME + 3 * k + 2]
        for i in range(n):
            q = f0 * (S[_S_PX + i] - ox) + f1 * (S[_S_PY + i] - oy) + f2 * (S[_S_PZ + i] - oz)
            if e == 0.0:
                S[_S_W + i] = S[_S_W + i] if (q >= lo and q <= hi) else 0.0
            else:
                w = S[_S_W + i]
                if not lo_open:
                    w = w * _smooth((q - lo) / e)
                if not hi_open:
                    w = w * _smooth((hi - q) / e)
                S[_S_W + i] = w
    for i in range(n):
        S[_S_F + i] = S[_S_F + i] * S[_S_W + i]


def _eye_into(  # pragma: no cover - compiled
    P: _F, N: _F, E: _F, one_eye: bool, two_sided: bool, normal_zero: float, amb: _F, s: int, n: int, S: _F,
) -> None:
    """Rows P (the chunk's points, component-major), N (unit, turned to the eye when two-sided),
    V, N.V, the ambient colour and BAD (a normal too short to be made unit), as the start of
    ``shading._shade_block``. ``P``, ``N`` and ``E`` are point-major ``(m, 3)`` (``E`` ``(1, 3)``
    for one eye): this copy into the chunk's rows replaces a transposed copy of the whole input."""
    for i in range(n):
        S[_S_PX + i], S[_S_PY + i], S[_S_PZ + i] = P[s + i, 0], P[s + i, 1], P[s + i, 2]
        S[_S_NX + i], S[_S_NY + i], S[_S_NZ + i] = N[s + i, 0], N[s + i, 1], N[s + i, 2]
    if one_eye:
        e0, e1, e2 = E[0, 0], E[0, 1], E[0, 2]
        for i in range(n):
            S[_S_VX + i], S[_S_VY + i], S[_S_VZ + i] = e0 - S[_S_PX + i], e1 - S[_S_PY + i], e2 - S[_S_PZ + i]
    else:
        for i in range(n):
            S[_S_VX + i] = E[s + i, 0] - S[_S_PX + i]
            S[_S_VY + i] = E[s + i, 1] - S[_S_PY + i]
            S[_S_VZ + i] = E[s + i, 2] - S[_S_PZ + i]
    a0, a1, a2 = amb[0], amb[1], amb[2]
    for i in range(n):
        nx, ny, nz = S[_S_NX + i], S[_S_NY + i], S[_S_NZ + i]
        n_len = math.sqrt(nx * nx + ny * ny + nz * nz)
        S[_S_BAD + i] = 0.0 if n_len > normal_zero else 1.0
        inv = 1.0 / n_len
        nx, ny, nz = nx * inv, ny * inv, nz * inv
        vx, vy, vz = S[_S_VX + i], S[_S_VY + i], S[_S_VZ + i]
        inv = 1.0 / math.sqrt(vx * vx + vy * vy + vz * vz)
        vx, vy, vz = vx * inv, vy * inv, vz * inv
        nv = nx * vx + ny * vy + nz * vz
        flip = -1.0 if (two_sided and nv < 0.0) else 1.0
        S[_S_NX + i], S[_S_NY + i], S[_S_NZ + i], S[_S_NV + i] = nx * flip, ny * flip, nz * flip, nv * flip
        S[_S_VX + i], S[_S_VY + i], S[_S_VZ + i] = vx, vy, vz
        S[_S_R + i], S[_S_G + i], S[_S_B + i] = a0, a1, a2


def _shade(  # pragma: no cover - compiled
    P: _F, N: _F, E: _F, one_eye: bool, start: int, stop: int, lights: _F, ckd: _F, cks: _F, amb: _F,
    two_sided: bool, specular: bool, shininess: float, normal_zero: float, out: _F,
) -> None:
    """``out[i] = `` Warn's colour of point ``i`` for ``start <= i < stop``; ``P``, ``N``, ``out``
    point-major ``(m, 3)``, ``E`` ``(1, 3)`` (``one_eye``) or ``(m, 3)``."""
    S = np.empty(_S_ROWS * _CHUNK)
    for s in range(start, stop, _CHUNK):
        n = min(_CHUNK, stop - s)
        _eye_into(P, N, E, one_eye, two_sided, normal_zero, amb, s, n, S)
        for j in range(lights.shape[0]):
            _light_into(lights, j, n, S, specular, shininess)
            k0, k1, k2, c0, c1, c2 = ckd[j, 0], ckd[j, 1], ckd[j, 2], cks[j, 0], cks[j, 1], cks[j, 2]
            for i in range(n):
                nl = S[_S_NL + i]
                f = S[_S_F + i]
                diff = (nl if nl > 0.0 else 0.0) * f
                spec = S[_S_RV + i] * f if specular else 0.0
                S[_S_R + i] += diff * k0 + spec * c0
                S[_S_G + i] += diff * k1 + spec * c1
                S[_S_B + i] += diff * k2 + spec * c2
        for i in range(n):
            bad = S[_S_BAD + i] != 0.0
            out[s + i, 0] = np.nan if bad else S[_S_R + i]
            out[s + i, 1] = np.nan if bad else S[_S_G + i]
            out[s + i, 2] = np.nan if bad else S[_S_B + i]


_HELPERS = ("_ipow_into", "_smooth", "_cone_into", "_flaps_into", "_light_into", "_eye_into")


def _load() -> Any:
    with _lock:
        if not _state["loaded"]:
            kern = None
            try:
                import numba

                g = globals()
                for name in _HELPERS:  # called, LLVM inlines them (as the evaluation kernels' helpers)
                    g[name] = _nk.jit(numba, g[name])
                kern = _nk.jit(numba, _shade)
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


def run(kern: Any, P: np.ndarray, N: np.ndarray, E: np.ndarray, one_eye: bool, start: int, stop: int,
        packed: tuple[np.ndarray, np.ndarray, np.ndarray], amb: np.ndarray, two_sided: bool, specular: bool,
        shininess: float, out: np.ndarray) -> bool:
    """Shade points ``start .. stop`` into ``out``; False if the kernel failed (it is then dropped,
    with a warning)."""
    table, ckd, cks = packed
    try:
        kern(P, N, E, one_eye, start, stop, table, ckd, cks, amb, two_sided, specular, shininess,
             float(tolerances.LIGHT_DIRECTION_ZERO), out)
    except Exception as err:  # noqa: BLE001 - an untested numba version: fall back, once
        import warnings

        warnings.warn(f"occsurf: numba lighting kernel failed ({err!r}); using NumPy", RuntimeWarning, stacklevel=3)
        _state["kernel"] = None
        return False
    return True
