"""Axes of revolution and of helical motions fitted to a hole's loop (course §8-3), for the plate
filled in cylindrical coordinates (:mod:`.plate_wrap`): the line-geometric helical axis of
Pottmann and Randrup ("Rotational and helical surface approximation for reverse engineering",
Computing 60, 1998), a robust (median) residual of a given axis, and least-squares cylinders
through the loop's points.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike
from scipy.optimize import least_squares

Array = np.ndarray

__all__ = ["axis_frame", "axis_residual", "fitted_axes", "helical_axis"]


def axis_frame(axis: Array) -> tuple[Array, Array]:
    """Unit vectors ``e1, e2`` square to ``axis`` and to each other, ``(e1, e2, axis)`` right-handed;
    ``e1`` from the coordinate axis least aligned with ``axis``."""
    a = axis / np.linalg.norm(axis)
    e1 = np.eye(3)[int(np.argmin(np.abs(a)))]
    e1 = e1 - (e1 @ a) * a
    e1 /= np.linalg.norm(e1)
    return e1, np.cross(a, e1)


def helical_axis(points: ArrayLike, normals: ArrayLike) -> tuple[Array, Array, float] | None:
    """The axis of the helical motion (rotation, or screw) most nearly tangent to a surface at
    ``points`` with ``normals``: Pottmann and Randrup's line-geometric fit ("Rotational and helical
    surface approximation for reverse engineering", Computing 60, 1998).

    A helical motion has the velocity field ``v(P) = c + a x P``; a surface of revolution (``a . c =
    0``) or a helical surface (a thread flank) is tangent to it: ``v . n = c . n + a . (P x n) = 0``
    at every point, linear in ``(c, a)``. ``c`` is eliminated by least squares (the Schur complement)
    and ``a`` is the eigenvector of the smallest eigenvalue, ``|a| = 1``; the axis passes through
    ``a x c`` with pitch ``a . c``.

    Parameters
    ----------
    points : array_like, shape (m, 3)
        Points of the surface (the loop's samples).
    normals : array_like, shape (m, 3)
        The surface's normals there (any length).

    Returns
    -------
    (point, direction, residual) or None
        ``residual``: root mean square of ``v . n`` per unit normal and unit of the points' spread
        (0 for an exact surface of revolution or helical surface); None when the normals do not
        determine one axis: a second motion fits as well (a sphere: every line through its centre),
        or the axis's point is free (all normals parallel: a plane, about any of its normal lines).
    """
    P = np.asarray(points, float).reshape(-1, 3)
    N = np.asarray(normals, float).reshape(-1, 3)
    N = N / np.maximum(np.linalg.norm(N, axis=1, keepdims=True), 1e-300)
    o = P.mean(axis=0)
    scale = float(np.linalg.norm(P - o, axis=1).max()) or 1.0
    Q = (P - o) / scale
    A = np.c_[N, np.cross(Q, N)]
    M = A.T @ A
    Mcc, Mca, Maa = M[:3, :3], M[:3, 3:], M[3:, 3:]
    K = np.linalg.pinv(Mcc, rcond=1e-10) @ Mca
    w, V = np.linalg.eigh(Maa - Mca.T @ K)
    a = V[:, 0]
    c = -K @ a
    if w[1] <= 1e-9 * max(float(np.trace(M)), 1e-300):  # a second motion as tangent: a sphere
        return None
    wc, Vc = np.linalg.eigh(Mcc)
    free = Vc[:, wc <= 1e-9 * max(float(wc.max()), 1e-300)]  # translations c the normals do not see
    if free.size and np.any(np.linalg.norm(np.cross(free.T, a), axis=1) > 1e-6):  # other than along a: a plane
        return None
    residual = float(np.sqrt(max(w[0], 0.0) / len(P)))
    return o + scale * np.cross(a, c), a, residual


def axis_residual(points: ArrayLike, normals: ArrayLike, point: ArrayLike, direction: ArrayLike,
                  weights: ArrayLike | None = None) -> float:
    """How far a surface is from being tangent to the best helical motion about a given axis: the
    median of ``|v . n|`` (unit normals, points in units of their spread) at the pitch that makes it
    least (0 where most of the samples lie on surfaces of revolution or helical surfaces about that
    axis, whatever the rest do).

    A median, not the root mean square :func:`helical_axis` minimises: a hole's neighbours are
    rarely all turned about one axis (screw pair [8, 22]: the thread's flanks and crest are helical
    about the screw's axis, its run-out's neighbours are not), and the mean square then prefers an
    axis tilted to split the difference (2.1 deg there: RMS 0.0091 against the screw axis's 0.017),
    about which the boundary is met and the inside is 0.47 mm off the thread. The pitch: the least
    median of the candidates ``-rot_i / an_i`` (201 quantiles) and the least-squares one.
    ``weights`` (default equal): each sample's share of the loop, e.g. its arc length (a loop sampled
    alike per side would let two short ends outvote two long sides: the ends of a cylinder strip
    lie in planes through any axis crossing them, where ``v . n`` is 0 for the pitch 0)."""
    P = np.asarray(points, float).reshape(-1, 3)
    N = np.asarray(normals, float).reshape(-1, 3)
    N = N / np.maximum(np.linalg.norm(N, axis=1, keepdims=True), 1e-300)
    a = np.asarray(direction, float) / np.linalg.norm(direction)
    scale = float(np.linalg.norm(P - P.mean(axis=0), axis=1).max()) or 1.0
    rot = np.einsum("ij,ij->i", np.cross(a, (P - np.asarray(point, float)) / scale), N)
    an = N @ a
    pitches = [-float(rot @ an) / max(float(an @ an), 1e-300)]
    steep = np.abs(an) > 1e-3  # samples whose normal has a component along the axis fix a pitch
    if steep.any():
        pitches += list(np.quantile(-rot[steep] / an[steep], np.linspace(0.0, 1.0, 201)))
    res = np.abs(rot[None, :] + np.asarray(pitches)[:, None] * an[None, :])
    w = np.ones(len(P)) if weights is None else np.asarray(weights, float).ravel()
    order = np.argsort(res, axis=1)
    cum = np.cumsum(w[order], axis=1)
    k = np.argmax(cum >= 0.5 * cum[:, -1:], axis=1)  # the weighted median of each row
    return float(np.take_along_axis(res, order, axis=1)[np.arange(len(res)), k].min())


def fitted_axes(points: ArrayLike, normals: ArrayLike | None = None) -> list[tuple[Array, Array]]:
    """Candidate axes of a loop that winds around one.

    First, with ``normals`` (the neighbours' at the loop), the helical axis (:func:`helical_axis`:
    exact for neighbours that are surfaces of revolution or helical surfaces); then least-squares
    cylinders through ``points``: each principal axis of the points starts a Levenberg-Marquardt
    fit (``scipy.optimize.least_squares``) of ``dist(P_i, axis) - R`` over the axis (two angles,
    two offsets) and ``R`` (two coaxial helices of different radii tilt it: a thread flank's
    fitted cylinder is 5e-3 rad off its axis, which the first candidate is not). Distinct ones only.

    Parameters
    ----------
    points : array_like, shape (m, 3)
    normals : array_like, shape (m, 3), optional

    Returns
    -------
    list of (point, direction)
    """
    P = np.asarray(points, float).reshape(-1, 3)
    o = P.mean(axis=0)
    Q = P - o
    _, _, Vt = np.linalg.svd(Q, full_matrices=False)
    first = []
    if normals is not None:
        hel = helical_axis(P, normals)
        if hel is not None:
            first.append((-1.0, hel[0], hel[1]))
    found = []
    for k in range(3):
        a0 = Vt[k]
        e1, e2 = axis_frame(a0)

        def residual(x: Array, a0: Array = a0, e1: Array = e1, e2: Array = e2) -> Array:
            a = a0 + x[0] * e1 + x[1] * e2
            a = a / np.linalg.norm(a)
            c = x[2] * e1 + x[3] * e2
            R = Q - c
            R = R - np.outer(R @ a, a)
            return np.linalg.norm(R, axis=1) - x[4]

        r_start = float(np.mean(np.linalg.norm(Q - np.outer(Q @ a0, a0), axis=1)))
        sol = least_squares(residual, np.r_[0.0, 0.0, 0.0, 0.0, r_start], method="lm")
        a = a0 + sol.x[0] * e1 + sol.x[1] * e2
        a /= np.linalg.norm(a)
        found.append((float(sol.cost), o + sol.x[2] * e1 + sol.x[3] * e2, a))
    found.sort(key=lambda f: f[0])
    out: list[tuple[Array, Array]] = []
    for _, c, a in first + found:
        if all(abs(abs(float(a @ b)) - 1) > 1e-6 or np.linalg.norm(np.cross(c - d, b)) > 1e-6 * (1 + np.linalg.norm(Q, axis=1).max())
               for d, b in out):
            out.append((c, a))
    return out
