"""Conic sections as rational quadratic B-splines (course §2 "rational splines", §12).

A conic arc is a rational quadratic Bézier segment ``[P0, P1, P2]`` with weights ``[1, w, 1]``:
``P0``, ``P2`` are the end points, ``P1`` the intersection of the end tangents, and the middle
weight decides the type — ellipse for ``w < 1``, parabola for ``w = 1``, hyperbola for ``w > 1``.
The curve point at ``t = 1/2`` (the *shoulder point*) is ``S = (M + w P1) / (1 + w)`` with ``M`` the
midpoint of ``P0 P2``, so ``w = s / (1 - s)`` where ``s = |S - M| / |P1 - M|``.

Circles and ellipses are exact: arcs of at most 90 degrees each with ``w = cos(half-angle)``,
joined with double knots (The NURBS Book, 2nd ed., A7.1). Every result is a
:class:`~occsurf.algorithms.kernel.curve.BSplineCurve`, so OCC receives it exactly through ``bridge.to_occ``.

References
----------
E. T. Y. Lee, "The rational Bézier representation for conics", in *Geometric Modeling*, SIAM 1987.
Piegl & Tiller, *The NURBS Book*, 2nd ed., §7.2–7.5, A7.1.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import _validate as V
from ..errors import InvalidGeometryError
from .curve import BSplineCurve

__all__ = ["circle", "arc", "ellipse", "conic_arc", "conic_from_shoulder", "conic_through_point", "conic_type"]

Array = NDArray[np.float64]


def _frame(center: ArrayLike, normal: ArrayLike | None, xaxis: ArrayLike | None) -> tuple[Array, Array, Array]:
    """Centre and orthonormal in-plane axes (x, y); 2-D when ``center`` has 2 coordinates."""
    c = V.as_finite_array(center, "center", ndim=1)
    if c.shape[0] == 2:
        if normal is not None:
            raise InvalidGeometryError("normal: a 2-D conic takes no normal")
        x = np.array([1.0, 0.0]) if xaxis is None else V.as_finite_array(xaxis, "xaxis", ndim=1)
        if x.shape != (2,) or np.linalg.norm(x) == 0:
            raise InvalidGeometryError(f"xaxis: expected a non-zero 2-D vector, got {x!r}")
        x = x / np.linalg.norm(x)
        return c, x, np.array([-x[1], x[0]])
    if c.shape[0] != 3:
        raise InvalidGeometryError(f"center: expected 2 or 3 coordinates, got {c.shape[0]}")
    n = np.array([0.0, 0.0, 1.0]) if normal is None else V.as_finite_array(normal, "normal", ndim=1)
    if n.shape != (3,) or np.linalg.norm(n) == 0:
        raise InvalidGeometryError(f"normal: expected a non-zero 3-D vector, got {n!r}")
    n = n / np.linalg.norm(n)
    if xaxis is None:
        # Same default as OCC's gp_Ax2(P, N): X is perpendicular to N, chosen from the smallest axis.
        helper = np.eye(3)[int(np.argmin(np.abs(n)))]
        x = helper - n * (helper @ n)
    else:
        x = V.as_finite_array(xaxis, "xaxis", ndim=1)
        if x.shape != (3,):
            raise InvalidGeometryError(f"xaxis: expected a 3-D vector, got shape {x.shape}")
        x = x - n * (x @ n)
        if np.linalg.norm(x) < 1e-12:
            raise InvalidGeometryError("xaxis: must not be parallel to normal")
    x = x / np.linalg.norm(x)
    return c, x, np.cross(n, x)


def _positive(value: float, name: str) -> float:
    v = float(value)
    if not (math.isfinite(v) and v > 0):
        raise InvalidGeometryError(f"{name}: expected a positive finite number, got {value!r}")
    return v


def arc(
    center: ArrayLike,
    radius: float,
    start_angle: float,
    end_angle: float,
    normal: ArrayLike | None = None,
    xaxis: ArrayLike | None = None,
) -> BSplineCurve:
    """Exact circular arc from ``start_angle`` to ``end_angle`` (radians, counter-clockwise about
    ``normal``), as a rational quadratic B-spline (NURBS Book A7.1).

    The arc is cut into ``ceil(sweep / 90°)`` equal pieces, each a rational quadratic Bézier with
    middle weight ``cos(delta / 2)``; the parameter runs over ``[start_angle, end_angle]`` (the knots
    are the piece angles; the parametrisation is not arc-length, as for every rational conic).

    Parameters
    ----------
    center : array_like, shape (2,) or (3,)
    radius : float
    start_angle, end_angle : float
        ``0 < end_angle - start_angle <= 2 pi``.
    normal, xaxis : array_like, shape (3,), optional
        Plane of a 3-D arc; angles are measured from ``xaxis`` (default as OCC's ``gp_Ax2``).

    Returns
    -------
    BSplineCurve
        Degree 2, rational, ``2 k + 1`` poles for ``k`` pieces.
    """
    r = _positive(radius, "radius")
    a0, a1 = float(start_angle), float(end_angle)
    sweep = a1 - a0
    if not (math.isfinite(sweep) and 0 < sweep <= 2 * math.pi + 1e-12):
        raise InvalidGeometryError(f"end_angle: expected 0 < end_angle - start_angle <= 2 pi, got {sweep!r}")
    c, x, y = _frame(center, normal, xaxis)
    k = max(1, math.ceil(sweep / (math.pi / 2) - 1e-12))
    delta = sweep / k
    w_mid = math.cos(delta / 2)
    angles = a0 + delta * np.arange(k + 1)
    ends = c + r * (np.cos(angles)[:, None] * x + np.sin(angles)[:, None] * y)
    mids_a = angles[:-1] + delta / 2
    mids = c + (r / w_mid) * (np.cos(mids_a)[:, None] * x + np.sin(mids_a)[:, None] * y)
    P = np.empty((2 * k + 1, c.shape[0]))
    P[0::2] = ends
    P[1::2] = mids
    w = np.ones(2 * k + 1)
    w[1::2] = w_mid
    knots = np.concatenate(([a0] * 3, np.repeat(angles[1:-1], 2), [a1] * 3))
    if sweep >= 2 * math.pi - 1e-12:
        P[-1] = P[0]  # close exactly
    return BSplineCurve(2, knots, P, w)


def circle(center: ArrayLike, radius: float, normal: ArrayLike | None = None, xaxis: ArrayLike | None = None) -> BSplineCurve:
    """Exact full circle: four 90-degree rational quadratic pieces on ``[0, 2 pi]`` (9 poles)."""
    return arc(center, radius, 0.0, 2 * math.pi, normal, xaxis)


def ellipse(
    center: ArrayLike,
    major_radius: float,
    minor_radius: float,
    normal: ArrayLike | None = None,
    xaxis: ArrayLike | None = None,
    start_angle: float = 0.0,
    end_angle: float = 2 * math.pi,
) -> BSplineCurve:
    """Exact ellipse (or elliptic arc): the affine image of the unit circle's NURBS.

    ``xaxis`` carries the major radius. Rational B-splines are invariant under affine maps, so
    scaling the circle's control points (weights unchanged) is exact.
    """
    a = _positive(major_radius, "major_radius")
    b = _positive(minor_radius, "minor_radius")
    c, x, y = _frame(center, normal, xaxis)
    unit = arc(np.zeros(2), 1.0, start_angle, end_angle)
    Q = unit.control_points
    P = c + a * Q[:, :1] * x + b * Q[:, 1:] * y
    return BSplineCurve._trusted(2, unit.knots, P, unit.weights)


def conic_arc(p0: ArrayLike, p1: ArrayLike, p2: ArrayLike, weight: float) -> BSplineCurve:
    """Rational quadratic Bézier ``[p0, p1, p2]`` with weights ``[1, weight, 1]`` on ``[0, 1]``.

    ``weight < 1``: ellipse arc; ``= 1``: parabola; ``> 1``: hyperbola (see :func:`conic_type`).
    """
    w = _positive(weight, "weight")
    P = np.array([V.as_finite_array(p, name, ndim=1) for p, name in ((p0, "p0"), (p1, "p1"), (p2, "p2"))])
    return BSplineCurve(2, [0, 0, 0, 1, 1, 1], P, [1.0, w, 1.0])


def conic_from_shoulder(p0: ArrayLike, p1: ArrayLike, p2: ArrayLike, shoulder: float | ArrayLike) -> BSplineCurve:
    """Conic arc from end points, tangent intersection and a shoulder (course §2, rational splines).

    Parameters
    ----------
    shoulder : float or array_like
        Either the ratio ``s = |S - M| / |P1 - M|`` in ``(0, 1)`` or the shoulder point ``S`` itself
        (it must lie on the segment from the chord midpoint ``M`` to ``p1``). ``w = s / (1 - s)``.
    """
    P0, P1, P2 = (V.as_finite_array(p, n, ndim=1) for p, n in ((p0, "p0"), (p1, "p1"), (p2, "p2")))
    M = 0.5 * (P0 + P2)
    if np.ndim(shoulder) == 0:
        s = float(np.asarray(shoulder))
    else:
        S = V.as_finite_array(shoulder, "shoulder", ndim=1)
        d = P1 - M
        dd = float(d @ d)
        if dd == 0:
            raise InvalidGeometryError("p1: coincides with the chord midpoint; the conic is degenerate")
        s = float((S - M) @ d) / dd
        off = float(np.linalg.norm(S - M - s * d))
        if off > 1e-9 * max(1.0, math.sqrt(dd)):
            raise InvalidGeometryError(
                f"shoulder: must lie on the segment from the chord midpoint to p1 (off by {off:.3g})"
            )
    if not 0 < s < 1:
        raise InvalidGeometryError(f"shoulder: ratio must be in (0, 1), got {s!r}")
    return conic_arc(P0, P1, P2, s / (1 - s))


def conic_through_point(
    p0: ArrayLike, t0: ArrayLike, p2: ArrayLike, t2: ArrayLike, point: ArrayLike
) -> BSplineCurve:
    """The conic arc from ``p0`` (tangent ``t0``) to ``p2`` (tangent ``t2``) through ``point``.

    The tangent lines meet at ``P1``; with barycentric coordinates ``(a, b, c)`` of ``point`` in the
    triangle ``P0 P1 P2``, the rational quadratic passes through it at ``t / (1 - t) = sqrt(c / a)``
    exactly when ``w = b / (2 sqrt(a c))`` (Lee 1987).

    Raises
    ------
    InvalidGeometryError
        Parallel tangents, non-coplanar data, or a point outside the tangent triangle (no conic arc
        of this kind passes through it).
    """
    P0, T0, P2, T2, Q = (
        V.as_finite_array(a, n, ndim=1) for a, n in ((p0, "p0"), (t0, "t0"), (p2, "p2"), (t2, "t2"), (point, "point"))
    )
    # Intersect P0 + a T0 with P2 + b T2 (least squares; checked below).
    A = np.stack([T0, -T2], axis=1)
    sol, *_ = np.linalg.lstsq(A, P2 - P0, rcond=None)
    if abs(np.linalg.det(A.T @ A)) < 1e-24 * max(1.0, float(T0 @ T0 * (T2 @ T2))):
        raise InvalidGeometryError("t0, t2: the end tangents are parallel; no single conic arc")
    P1 = P0 + sol[0] * T0
    scale = max(1.0, float(np.linalg.norm(P2 - P0)))
    if np.linalg.norm(P0 + sol[0] * T0 - (P2 + sol[1] * T2)) > 1e-9 * scale:
        raise InvalidGeometryError("t0, t2: the tangent lines do not meet (data not coplanar)")
    B = np.stack([P0 - P1, P2 - P1], axis=1)
    bc, *_ = np.linalg.lstsq(B, Q - P1, rcond=None)
    if np.linalg.norm(P1 + B @ bc - Q) > 1e-9 * scale:
        raise InvalidGeometryError("point: not in the plane of the end points and tangents")
    a, c = float(bc[0]), float(bc[1])
    b = 1.0 - a - c
    if not (a > 0 and b > 0 and c > 0):
        raise InvalidGeometryError("point: must lie strictly inside the triangle p0, tangent intersection, p2")
    return conic_arc(P0, P1, P2, b / (2 * math.sqrt(a * c)))


def conic_type(weight: float, tol: float = 1e-12) -> str:
    """``'ellipse'``, ``'parabola'`` or ``'hyperbola'`` for the middle weight of a conic arc."""
    w = _positive(weight, "weight")
    if abs(w - 1.0) <= tol:
        return "parabola"
    return "ellipse" if w < 1 else "hyperbola"
