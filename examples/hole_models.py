"""Models with n-sided holes, built exactly in code (pure NumPy; shared by the fill tests, the
benchmark, the demo and ``step_samples/make_holes.py``).

A *ring model*: one smooth base surface ``G`` (a polynomial bicubic or a rational biquadratic Bézier
patch over ``[0, 1]^2``), an n-gon hole in its parameter domain, and a ring of ``n`` four-sided
faces around the hole. Face ``k`` is ``G`` composed with the bilinear map of the domain quad between
hole side ``k`` and the outer polygon's side ``k``; the composition of a (rational) Bézier patch
with a bilinear map is a (rational) Bézier patch of bidegree ``(p+q, p+q)``, so the faces are exact.
Optionally each face gets a multi-span B-spline *bump* ``phi(s) psi(t)`` (``phi`` a cubic C2 spline
with interior knots, vanishing with its first two derivatives at both ends): the hole sides are then
genuinely multi-span, while the faces stay G2 to each other across the lateral edges (the bump and
its derivatives vanish there), so the hole corners are twist-compatible. ``bump_order=1`` makes the
bump vanish only to first order at the lateral edges: the faces are then only G1 to each other there.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from occsurf.algorithms.kernel.basis import basis_matrix, greville
from occsurf.algorithms.kernel.curve import BSplineCurve
from occsurf.algorithms.kernel.surface import BSplineSurface
from occsurf.algorithms.topology.nsided import HoleSide, side_from_surface

__all__ = ["RingModel", "base_surface", "ring_model", "represent_grid"]


@dataclass(frozen=True)
class RingModel:
    faces: list[BSplineSurface]
    sides: list[HoleSide]
    base: BSplineSurface
    hole: np.ndarray  # (n, 2) hole polygon in the base's domain
    outer: np.ndarray  # (n, 2)


def base_surface(rational: bool) -> BSplineSurface:
    """A gently curved dome over ``[0, 10]^2`` (bicubic), or a rational biquadratic one."""
    if rational:
        g = np.linspace(0.0, 10.0, 3)
        X, Y = np.meshgrid(g, g, indexing="ij")
        Z = np.array([[0.0, 2.0, 0.5], [1.5, 5.0, 2.5], [0.3, 2.2, 1.0]])
        W = np.array([[1.0, 0.8, 1.1], [0.7, 1.4, 0.9], [1.2, 0.85, 1.0]])
        k = np.r_[[0.0] * 3, [1.0] * 3]
        return BSplineSurface((2, 2), (k, k), np.stack([X, Y, Z], -1), W)
    g = np.linspace(0.0, 10.0, 4)
    X, Y = np.meshgrid(g, g, indexing="ij")
    Z = np.array([[0.0, 1.0, 1.5, 0.2], [1.2, 4.0, 3.5, 1.0], [0.8, 3.0, 4.5, 1.4], [0.1, 1.3, 0.9, 0.0]])
    k = np.r_[[0.0] * 4, [1.0] * 4]
    return BSplineSurface((3, 3), (k, k), np.stack([X, Y, Z], -1))


def represent_grid(fn: Callable[[np.ndarray, np.ndarray], np.ndarray], degree: tuple[int, int], knots: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
    """Poles of the tensor spline equal to ``fn(s, t) -> (m, k, d)`` on a grid (exact collocation)."""
    xs = [greville(knots[d], degree[d]) for d in range(2)]
    N = [basis_matrix(knots[d], degree[d], len(xs[d]), xs[d])[0] for d in range(2)]
    Y = fn(xs[0], xs[1])
    Q = np.linalg.solve(N[0], Y.reshape(len(xs[0]), -1)).reshape(Y.shape)
    Q = np.linalg.solve(N[1], np.swapaxes(Q, 0, 1).reshape(len(xs[1]), -1)).reshape(
        (Y.shape[1], Y.shape[0], Y.shape[2]))
    return np.swapaxes(Q, 0, 1)


def _bump(order: int) -> BSplineCurve:
    """phi(s): cubic with interior knots 0.3, 0.5, 0.7; zero to ``order`` derivatives at s=0, 1."""
    t = np.r_[[0.0] * 4, 0.3, 0.5, 0.7, [1.0] * 4]
    P = np.zeros(7)
    if order >= 2:
        P[3] = 1.0
    else:
        P[2], P[3], P[4] = 0.6, 1.0, -0.5
    return BSplineCurve(3, t, P[:, None])


def ring_model(n: int, *, rational: bool = False, bump: float = 0.6, bump_order: int = 2,
               radius: float = 0.22, width: float = 0.16, center: tuple[float, float] = (0.5, 0.5),
               jitter: float = 0.12,
               base: BSplineSurface | None = None, polygon: np.ndarray | None = None) -> RingModel:
    """An n-sided hole with its ring of n neighbour faces (see the module docstring)."""
    G = base_surface(rational) if base is None else base
    GH = BSplineSurface(G.degree, G.knots, G.homogeneous_points)
    k = np.arange(n)
    th = 2 * np.pi * k / n + 0.3
    rr = radius * (1.0 + jitter * np.sin(2.7 * k + 1.0))
    hole = np.c_[center[0] + rr * np.cos(th), center[1] + rr * np.sin(th)]
    outer = np.c_[center[0] + (rr + width) * np.cos(th), center[1] + (rr + width) * np.sin(th)]
    if polygon is not None:  # an explicit hole polygon (n, 2); the ring is it scaled about its centroid
        hole = np.asarray(polygon, float)
        n = len(hole)
        c = hole.mean(0)
        outer = c + (hole - c) * (1.0 + width / radius)
    p, q = G.degree
    dg = p + q
    phi = _bump(bump_order) if bump else None
    faces: list[BSplineSurface] = []
    sides: list[HoleSide] = []
    for i in range(n):
        a, b = hole[i], hole[(i + 1) % n]
        A, B = outer[i], outer[(i + 1) % n]
        amp = bump * (0.6 + 0.4 * math.cos(1.3 * i)) if bump else 0.0

        def fn(s: np.ndarray, t: np.ndarray, a: np.ndarray = a, b: np.ndarray = b, A: np.ndarray = A,
               B: np.ndarray = B, amp: float = amp) -> np.ndarray:
            S, T = np.meshgrid(s, t, indexing="ij")
            x = ((1 - T) * ((1 - S) * a[0] + S * b[0]) + T * ((1 - S) * A[0] + S * B[0]))
            y = ((1 - T) * ((1 - S) * a[1] + S * b[1]) + T * ((1 - S) * A[1] + S * B[1]))
            H = GH.evaluate(x, y)
            if amp and phi is not None:  # homogeneous coordinates for a rational base: z moves by amp phi psi / w
                H[..., 2] += amp * phi.evaluate(S)[..., 0] * (1.0 - T)
            return H

        if phi is not None:
            Ps = max(dg, 3)
            inner = [0.3, 0.5, 0.7]
            Ks = np.r_[[0.0] * (Ps + 1), np.repeat(inner, Ps - 2), [1.0] * (Ps + 1)]
        else:
            Ps = dg
            Ks = np.r_[[0.0] * (Ps + 1), [1.0] * (Ps + 1)]
        Pt = dg
        Kt = np.r_[[0.0] * (Pt + 1), [1.0] * (Pt + 1)]
        Hnet = represent_grid(fn, (Ps, Pt), (Ks, Kt))
        if G.is_rational:
            face = BSplineSurface((Ps, Pt), (Ks, Kt), Hnet[..., :3] / Hnet[..., 3:], Hnet[..., 3])
        else:
            face = BSplineSurface((Ps, Pt), (Ks, Kt), Hnet)
        faces.append(face)
        sides.append(side_from_surface(face, "v0"))
    return RingModel(faces, sides, G, hole, outer)
