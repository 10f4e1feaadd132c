"""Warn's lighting model, vectorised: :func:`shade` and the per-light factor :func:`light_factor`.

Course ch. 10 (D. R. Warn, "Lighting Controls for Synthetic Images", Computer Graphics 17(3),
SIGGRAPH '83, pp. 13-21), §10-2 .. §10-7. At a surface point ``P`` with unit normal ``N`` seen from
``E``, with ``V = (E - P)/|E - P|``:

.. math::

    C(P) = A \\odot C_d + \\sum_j I_j(P)\\, c_j \\odot
           \\bigl(k_d\\, C_d \\max(N\\cdot L_j, 0) + k_s\\, C_s \\max(R_j\\cdot V, 0)^s\\bigr)

with ``L_j`` the unit vector from ``P`` to light ``j`` (``-direction`` for a directional light),
``R_j = 2 (N.L_j) N - L_j`` (Phong's reflection vector: the specular term is **Phong**, not
Blinn-Phong, as in Warn's paper; it is zero where ``N.L_j <= 0``), ``c_j`` the light's
``intensity * color`` (lights of different colours blend additively per channel, §10-7) and

.. math::

    I_j(P) = \\underbrace{\\max(\\cos\\gamma, 0)^{n}}_{\\text{concentration}}\\;
             \\underbrace{\\bigl(1 - \\mathrm{smoothstep}(\\theta-\\delta, \\theta, \\gamma)\\bigr)}_{\\text{cone}}\\;
             \\underbrace{[\\,lo \\le F(P - O) \\le hi\\,]}_{\\text{flaps}}\\;
             \\underbrace{(d_0/\\max(d, d_0))^k}_{\\text{fall-off}}

where ``gamma`` is the angle between the light's axis and the ray from the light to ``P``, ``n``
the concentration (``n = 0``: the factor is 1 everywhere, a plain point light), ``theta`` and
``delta`` the cone's angle and soft-edge width (a step at ``theta`` when ``delta = 0``), ``F`` the
light's frame (:func:`~.model.light_frame`) and ``O`` its position, ``S_k`` 1 between the flaps
``lo_k .. hi_k`` of axis ``k`` and 0 outside (a step, or a smoothstep rising over ``flap_edge``
inside each flap), ``d = |P - O|`` and ``k`` 0, 1
or 2 (:data:`~.model.FALLOFFS`). The result is linear RGB, not clipped: two lights give exactly
the sum of each alone.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import tolerances
from ..errors import InvalidGeometryError
from . import _kernels
from .model import LightingSetup, Material, WarnLight

__all__ = ["shade", "light_factor"]


def _as_points(value: ArrayLike, name: str) -> NDArray[np.float64]:
    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise InvalidGeometryError(f"{name}: expected an array of shape (..., 3), got {type(value).__name__}") from None
    if a.ndim == 0 or a.shape[-1] != 3:
        raise InvalidGeometryError(f"{name}: expected an array of shape (..., 3), got shape {a.shape}")
    return a


def _setup(lights: LightingSetup | WarnLight | Sequence[WarnLight], material: Material | None,
           ambient: ArrayLike | None, two_sided: bool | None) -> LightingSetup:
    """One validated :class:`LightingSetup` from :func:`shade`'s flexible arguments."""
    if isinstance(lights, LightingSetup):
        setup = lights
    elif isinstance(lights, WarnLight):
        setup = LightingSetup(lights=(lights,))
    else:
        setup = LightingSetup(lights=tuple(lights) if isinstance(lights, (list, tuple)) else lights, ambient=0.0)
    changes: dict[str, Any] = {}
    if material is not None:
        changes["material"] = material
    if ambient is not None:
        changes["ambient"] = ambient if np.ndim(ambient) == 0 else tuple(np.asarray(ambient, float))
    if two_sided is not None:
        changes["two_sided"] = two_sided
    return setup.replace(**changes) if changes else setup


def shade(points: ArrayLike, normals: ArrayLike, view_point: ArrayLike,
          lights: LightingSetup | WarnLight | Sequence[WarnLight], material: Material | None = None, *,
          ambient: ArrayLike | None = None, two_sided: bool | None = None,
          dtype: type[np.floating] = np.float64) -> NDArray[np.floating]:
    """Shade surface points with Warn's lights (course ch. 10): the NumPy reference model.

    Parameters
    ----------
    points : array_like, shape (..., 3)
        Surface points, model units.
    normals : array_like, shape (..., 3)
        Normals at ``points`` (any length > 0; made unit here). A zero or non-finite normal gives
        a NaN row.
    view_point : array_like, shape (3,) or (..., 3)
        The eye (broadcast against ``points``).
    lights : LightingSetup or WarnLight or sequence of WarnLight
        A setup (its ambient, material and ``two_sided`` are used unless given here), one light,
        or a list of lights (ambient 0 unless given).
    material : Material, optional
        Overrides the setup's.
    ambient : float or (3,) floats, optional
        Overrides the setup's ambient light.
    two_sided : bool, optional
        Overrides the setup's: normals facing away from the eye are turned towards it.
    dtype : numpy.float64 or numpy.float32
        Precision of the result. The NumPy path computes in it: float64 (the reference) or float32
        (the renderer's precision, about twice as fast; relative error ~1e-6 of each term,
        invisible in an 8-bit picture). The compiled path computes in float64 either way and
        stores the result as ``dtype``.

    Notes
    -----
    From :data:`~occsurf.algorithms.tolerances.NUMBA_MIN_POINTS` points on, when numba is
    installed (and ``OCCSURF_NO_NUMBA`` is not set), an optional compiled kernel
    (:mod:`._kernels`) shades the points in cache-sized chunks, all lights per chunk, with the
    same operations in the same order: the same numbers (bit for bit with integer exponents),
    to the last ulps of ``pow`` and ``acos`` otherwise; about 3.5x the NumPy path's speed.
    Blocks of :data:`~occsurf.algorithms.tolerances.LIGHT_BLOCK` points run on
    :data:`~occsurf.algorithms.tolerances.LIGHT_THREADS` threads either way.

    Returns
    -------
    ndarray, shape (..., 3), ``dtype``
        Linear RGB, unclipped (the module docstring gives the formula).

    Raises
    ------
    InvalidGeometryError
        Arrays of the wrong shape, non-finite points, or an invalid light/material.
    """
    setup = _setup(lights, material, ambient, two_sided)
    if dtype not in (np.float64, np.float32):
        raise InvalidGeometryError(f"dtype: expected numpy.float64 or numpy.float32, got {dtype!r}")
    P = _as_points(points, "points")
    N = _as_points(normals, "normals")
    E: NDArray[np.floating] = _as_points(view_point, "view_point")
    try:
        shape = np.broadcast_shapes(P.shape, N.shape, E.shape)
    except ValueError:
        raise InvalidGeometryError(f"points {P.shape}, normals {N.shape} and view_point {E.shape}: expected "
                                   "shapes that broadcast") from None
    if not np.all(np.isfinite(P)):
        raise InvalidGeometryError("points: expected finite coordinates")
    single_eye = E.size == 3
    m = math.prod(shape[:-1])
    kern = _kernels.shade_points(m)
    if kern is not None:
        out = _shade_compiled(kern, P, N, E, shape, single_eye, setup, dtype)
        if out is not None:
            return out.reshape(shape)
    # Component-major copies (one pass each): the block kernels then read contiguous rows.
    P, N = (np.ascontiguousarray(np.broadcast_to(a, shape).reshape(-1, 3).T, dtype) for a in (P, N))
    E = (E.reshape(3, 1) if single_eye else np.broadcast_to(E, shape).reshape(-1, 3).T).astype(dtype)
    out = np.empty((3, m), dtype)

    def run(s: int) -> None:
        e = min(s + block, m)
        with np.errstate(all="ignore"):
            out[:, s:e] = _shade_block(P[:, s:e], N[:, s:e], E if single_eye else E[:, s:e], setup)

    block = max(1, int(tolerances.LIGHT_BLOCK))
    _on_threads(run, range(0, m, block))
    return out.T.reshape(shape)


def _on_threads(run: Callable[[int], Any], starts: Sequence[int]) -> list[Any]:
    """``run(s)`` for every block start, on up to ``LIGHT_THREADS`` threads (0: one per CPU).
    NumPy's loops and the compiled kernel release the GIL: blocks run side by side, and each
    point's result does not depend on its block, so the output is the same on any thread count."""
    threads = min(len(starts), max(1, int(tolerances.LIGHT_THREADS) or (os.cpu_count() or 1)))
    if threads > 1:
        from concurrent.futures import ThreadPoolExecutor

        with ThreadPoolExecutor(threads) as pool:
            return list(pool.map(run, starts))
    return [run(s) for s in starts]


def _readonly(a: np.ndarray) -> np.ndarray:
    """A read-only view: the kernel is compiled for one signature whatever the caller's flags."""
    v = a.view()
    v.flags.writeable = False
    return v


def _shade_compiled(kern: Any, P: np.ndarray, N: np.ndarray, E: np.ndarray, shape: tuple[int, ...],
                    single_eye: bool, setup: LightingSetup, dtype: type[np.floating]) -> np.ndarray | None:
    """``(m, 3)`` colours by the numba kernel of :mod:`._kernels` (float64 arithmetic, stored as
    ``dtype``), or None when the kernel fails (the caller then takes the NumPy path)."""
    # Point-major as given (no copy of a contiguous float64 input): the kernel copies each chunk
    # into component-major rows itself, in cache, where its loops vectorise.
    P, N = (_readonly(np.ascontiguousarray(np.broadcast_to(a, shape).reshape(-1, 3), np.float64)) for a in (P, N))
    E = _readonly(np.ascontiguousarray(E.reshape(1, 3) if single_eye else np.broadcast_to(E, shape).reshape(-1, 3),
                                       np.float64))
    m = P.shape[0]
    out = np.empty((m, 3), dtype)
    mat = setup.material
    args = (_kernels.pack_lights(setup), _readonly(np.asarray(setup.ambient) * np.asarray(mat.color)),
            bool(setup.two_sided), bool(mat.specular > 0), float(mat.shininess))
    block = max(1, int(tolerances.LIGHT_BLOCK))

    def run(s: int) -> bool:
        return _kernels.run(kern, P, N, E, single_eye, s, min(s + block, m), *args, out)

    if not run(0):  # the first block on this thread: compiles (once per machine), or fails
        return None
    return out if all(_on_threads(run, range(block, m, block))) else None


def _ipow(x: np.ndarray, s: float) -> np.ndarray:
    """``x ** s`` for ``x >= 0``; integer exponents up to 4096 by repeated squaring (6 products for
    s = 40 instead of a ``pow`` per element)."""
    if s == 1:
        return x
    if float(s).is_integer() and 0 < s <= 4096:
        n = int(s)
        result = None
        base = x
        while True:
            if n & 1:
                result = base if result is None else result * base
            n >>= 1
            if not n:
                return result  # type: ignore[return-value]
            base = base * base
    return np.power(x, s)


def _shade_block(P: np.ndarray, N: np.ndarray, E: np.ndarray, setup: LightingSetup) -> np.ndarray:
    """``(3, m)`` components in (views), ``(3, m)`` RGB out (trusted input, errors ignored by the caller)."""
    mat = setup.material
    n_len = np.sqrt(N[0] * N[0] + N[1] * N[1] + N[2] * N[2])
    bad = ~(n_len > tolerances.LIGHT_DIRECTION_ZERO)
    N = N * (1.0 / n_len)
    V = E - P
    V *= 1.0 / np.sqrt(V[0] * V[0] + V[1] * V[1] + V[2] * V[2])
    NV = N[0] * V[0] + N[1] * V[1] + N[2] * V[2]
    if setup.two_sided:
        back = NV < 0
        if back.any():
            flip = 1.0 - 2.0 * back
            N *= flip
            NV *= flip
    kd = [mat.diffuse * c for c in mat.color]  # Python floats keep the arrays' dtype (NEP 50)
    ks = [mat.specular * c for c in mat.specular_color]
    rgb = np.empty((3, P.shape[1]), P.dtype)
    rgb[:] = (np.asarray(setup.ambient) * np.asarray(mat.color))[:, None]
    for light in setup.lights:
        L, factor = _toward_light(P, light)
        NL = N[0] * L[0] + N[1] * L[1] + N[2] * L[2]
        diff = np.maximum(NL, 0.0)
        spec = None
        if mat.specular > 0:
            RV = 2.0 * NL * NV
            RV -= L[0] * V[0] + L[1] * V[1] + L[2] * V[2]
            np.maximum(RV, 0.0, out=RV)
            RV *= NL > 0  # no highlight from a light behind the surface
            spec = _ipow(RV, mat.shininess) if mat.shininess != 0 else (NL > 0).astype(P.dtype)
        if factor is not None:
            diff *= factor
            if spec is not None:
                spec *= factor
        c = [float(x) for x in light.rgb]
        for ch in range(3):
            if c[ch] == 0:
                continue
            term = diff * (c[ch] * kd[ch])
            if spec is not None:
                term += spec * (c[ch] * ks[ch])
            rgb[ch] += term
    if bad.any():
        rgb[:, bad] = np.nan
    return rgb


def _toward_light(P: np.ndarray, light: WarnLight) -> tuple[np.ndarray, np.ndarray | None]:
    """Unit vectors ``(3, m)`` from the points to the light, and the light's factor ``I(P)`` ``(m,)``
    (``None``: 1 everywhere)."""
    d = [float(x) for x in light.direction]
    m = P.shape[1]
    factor = None
    if light.position is None:
        L = np.broadcast_to(-np.asarray(d, P.dtype)[:, None], (3, m))
        if light.has_flaps:
            factor = _flap_mask(P, light)
        return L, factor
    L = np.asarray(light.position, P.dtype)[:, None] - P
    dist = np.sqrt(L[0] * L[0] + L[1] * L[1] + L[2] * L[2])
    L *= 1.0 / dist
    if not dist.all():  # a point at the light gets no light
        at = dist == 0
        L[:, at] = 0.0
        factor = (~at).astype(P.dtype)

    def times(f: np.ndarray) -> np.ndarray:
        return f if factor is None else factor * f

    if light.concentration > 0 or light.cone_angle_deg is not None:
        cos_g = -(L[0] * d[0] + L[1] * d[1] + L[2] * d[2])
        if light.concentration > 0:
            factor = times(_ipow(np.maximum(cos_g, 0.0), light.concentration))
        if light.cone_angle_deg is not None:
            factor = times(_cone(cos_g, light))
    if light.has_flaps:
        factor = times(_flap_mask(P, light))
    if light.falloff != "none":
        d0 = float(light.falloff_distance)  # type: ignore[arg-type]
        ratio = d0 / np.maximum(dist, d0)
        factor = times(ratio if light.falloff == "inverse" else ratio * ratio)
    return L, factor


def _cone(cos_g: np.ndarray, light: WarnLight) -> np.ndarray:
    """1 inside ``angle - edge``, 0 outside ``angle``, smoothstep in the angle between."""
    theta = math.radians(float(light.cone_angle_deg))  # type: ignore[arg-type]
    delta = math.radians(light.cone_edge_deg)
    if delta == 0:
        return (cos_g >= math.cos(theta)).astype(cos_g.dtype)
    gamma = np.arccos(np.clip(cos_g, -1.0, 1.0))
    t = np.clip((theta - gamma) / delta, 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


def _flap_mask(P: np.ndarray, light: WarnLight) -> np.ndarray:
    """1 inside every flap of the light's frame (``flap_edge`` inside it), 0 outside, smoothstep
    over the soft edge."""
    F = light.frame.tolist()
    rel = P - np.asarray(light.origin, P.dtype)[:, None]
    e = light.flap_edge
    mask = np.ones(P.shape[1], bool) if e == 0 else np.ones(P.shape[1], P.dtype)
    for k, (lo, hi) in enumerate(light.flaps):
        if math.isinf(lo) and math.isinf(hi):
            continue
        q = F[k][0] * rel[0] + F[k][1] * rel[1] + F[k][2] * rel[2]
        if e == 0:
            mask &= (q >= lo) & (q <= hi)
            continue
        for t in ((q - lo) / e if math.isfinite(lo) else None, (hi - q) / e if math.isfinite(hi) else None):
            if t is not None:
                np.clip(t, 0.0, 1.0, out=t)
                mask *= t * t * (3.0 - 2.0 * t)
    return mask.astype(P.dtype) if e == 0 else mask


def light_factor(points: ArrayLike, light: WarnLight) -> NDArray[np.float64]:
    """Warn's factor ``I(P)`` of one light (concentration x cone x flaps x fall-off), in [0, 1].

    Parameters
    ----------
    points : array_like, shape (..., 3)
    light : WarnLight

    Returns
    -------
    ndarray, shape (...)
        What multiplies the light's colour at each point before the diffuse and specular terms.
    """
    if not isinstance(light, WarnLight):
        raise InvalidGeometryError(f"light: expected a WarnLight, got {type(light).__name__}")
    P = _as_points(points, "points")
    if not np.all(np.isfinite(P)):
        raise InvalidGeometryError("points: expected finite coordinates")
    with np.errstate(all="ignore"):
        factor = _toward_light(np.ascontiguousarray(P.reshape(-1, 3).T), light)[1]
    return np.ones(P.shape[:-1]) if factor is None else factor.reshape(P.shape[:-1])
