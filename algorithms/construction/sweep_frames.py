"""The frames a generalised sweep moves its profile by (course §6-6, for the sweeps of §6-26 ..
§6-32): rotation-minimizing (the double reflection method), Frenet or fixed, at any parameters of
the path (:class:`PathFrames`). The sweep itself is :mod:`.sweeping`.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from .. import tolerances
from ..errors import InvalidGeometryError
from ..geometry.differential import Frames, cross3, frenet_axes, rotation_minimizing_frames
from ..kernel.curve import BSplineCurve
from ..kernel.knots import distinct_knots

__all__ = ["PathFrames", "path_frames", "reflect_in_planes"]

Array = NDArray[np.float64]


def reflect_in_planes(v: Array, *xs: Array) -> tuple[Array, list[Array]]:
    """Reflect each of ``xs`` (m, 3 each) in the planes normal to ``v`` (m, 3); identity where
    ``v = 0``. Returns also where ``v = 0``."""
    c2 = np.einsum("mi,mi->m", v, v)
    ok = c2 > 0
    g = np.where(ok, 2.0 / np.where(ok, c2, 1.0), 0.0)
    return ~ok, [x - (g * np.einsum("mi,mi->m", v, x))[:, None] * v for x in xs]


class PathFrames:
    """Orthonormal frames ``F(v)`` (columns T, N, B) of a sweep's path at any parameters.

    ``kind``: ``'rmf'`` (rotation-minimizing: a reference chain of ``SWEEP_RMF_STEPS``
    double-reflection steps per span, computed once, then one step from the nearest reference
    sample; Wang et al. 2008), ``'frenet'`` or ``'fixed'`` (the start frame everywhere).
    ``holonomy``: on a closed, tangent-continuous path, the angle the RMF comes back turned by
    about the tangent (0 otherwise)."""

    def __init__(self, path: BSplineCurve, kind: str) -> None:
        # rmf: reference chain of SWEEP_RMF_STEPS double-reflection steps per span, computed once
        self.path, self.kind = path, kind
        #: The path derivatives the frames need (``path.derivatives(v, order)`` in __call__).
        self.order = {"rmf": 1, "frenet": 2, "fixed": 0}[kind]
        v0, v1 = path.domain
        if kind == "rmf":
            brk = distinct_knots(path.knots)[0]
            brk = brk[(brk >= v0) & (brk <= v1)]
            steps = np.linspace(0.0, 1.0, int(tolerances.SWEEP_RMF_STEPS) + 1)[:-1]
            grid = np.concatenate([a + (b - a) * steps for a, b in zip(brk[:-1], brk[1:]) if b > a] + [[v1]])
            fr = path_frames(path, grid)
            self.grid, self.x, self.t, self.r = grid, fr.point, fr.tangent, fr.normal
            self.start = np.stack([fr.tangent[0], fr.normal[0], fr.binormal[0]], axis=-1)
            # On a closed, tangent-continuous path the RMF comes back turned about the tangent by
            # its holonomy angle: the sweep spreads that angle linearly (module notes) to close.
            size = max(1.0, float(np.abs(fr.point).max()))
            closed = np.linalg.norm(fr.point[-1] - fr.point[0]) <= tolerances.SWEEP_CLOSE_TOL * size
            t0, t1 = fr.tangent[0], fr.tangent[-1]
            tangent_ok = math.atan2(float(np.linalg.norm(np.cross(t0, t1))), float(t0 @ t1)) <= tolerances.SWEEP_CLOSE_ANGLE
            self.holonomy = (math.atan2(float(fr.normal[-1] @ fr.binormal[0]), float(fr.normal[-1] @ fr.normal[0]))
                             if closed and tangent_ok else 0.0)
        elif kind == "frenet":
            at = np.array([v0])
            self.start = self(at, path.derivatives(at, 2))[0]
            self.holonomy = 0.0
        else:  # the start normal does not matter (module notes): Frenet's, or any perpendicular
            f0 = path_frames(path, np.array([v0]))
            self.start = np.stack([f0.tangent[0], f0.normal[0], f0.binormal[0]], axis=-1)
            self.holonomy = 0.0

    def __call__(self, v: Array, D: Array | None = None) -> Array:
        """Frames at ``v`` (m,): shape (m, 3, 3), from ``D = path.derivatives(v, self.order)`` (computed
        if not given)."""
        if self.kind == "fixed":
            return np.broadcast_to(self.start, (v.shape[0], 3, 3))
        if D is None:
            D = self.path.derivatives(v, self.order)
        if self.kind == "frenet":
            F = frenet_axes(D)
            bad = ~np.all(np.isfinite(F[:, :, 1]), axis=-1)
            if np.any(bad):
                raise InvalidGeometryError(
                    f"path: the Frenet frame is undefined at v = {float(v[np.argmax(bad)])!r} (zero curvature); "
                    "use frame='rmf'"
                )
            return F
        x, d1 = D[:, 0], D[:, 1]
        speed = np.sqrt(np.einsum("mi,mi->m", d1, d1))
        if np.any(speed == 0):
            raise InvalidGeometryError(f"path: C'(v) = 0 at v = {float(v[np.argmax(speed == 0)])!r}; the frame is undefined")
        F = np.empty((v.shape[0], 3, 3))
        t = F[:, :, 0]
        np.divide(d1, speed[:, None], out=t)
        k = np.minimum(np.maximum(np.searchsorted(self.grid, v, side="right") - 1, 0), self.grid.shape[0] - 1)
        # One double-reflection step (Wang et al. 2008) from reference sample k to v. At the sample
        # itself (x = x_k) the step is the identity: the first reflection is then skipped, so the
        # second one's axis t - t_k would be round-off in a random direction; keep r_k there.
        at_sample, (rL, tL) = reflect_in_planes(x - self.x[k], self.r[k], self.t[k])
        r = reflect_in_planes(t - tL, rL)[1][0]
        if np.any(at_sample):
            r[at_sample] = self.r[k[at_sample]]
        r -= np.einsum("mi,mi->m", r, t)[:, None] * t
        F[:, :, 1] = r / np.sqrt(np.einsum("mi,mi->m", r, r))[:, None]
        F[:, :, 2] = cross3(t, F[:, :, 1])
        return F


def path_frames(path: BSplineCurve, v: Array) -> Frames:
    """:func:`rotation_minimizing_frames` with its errors naming the ``path`` argument."""
    try:
        return rotation_minimizing_frames(path, v)
    except InvalidGeometryError as err:
        msg = str(err)
        raise InvalidGeometryError("path" + msg[msg.index(":"):] if msg.startswith("curve:") else msg) from err
