r"""Exact surface generation: extrusion, ruled surfaces, revolution, translational and rotational
sweeps (course §6-26 .. §6-33, "Sweeping"; The NURBS Book, 2nd ed., §8.3 - §8.5 and §10.2).

Every construction here is a tensor product of the input curve(s) with a simple curve in the other
direction, so the result is *exact* (up to round-off), rational inputs included:

=====================  ==========================================================================
:func:`extrude`        ``S(u, v) = C(u) + v d``, ``v`` in ``[0, 1]`` (general cylinder, NURBS §8.3)
:func:`ruled`          ``S(u, v) = (1 - v) C1(u) + v C2(u)`` after making the curves compatible
                       (NURBS §8.4); the v-isolines are straight (for rational curves they are
                       straight lines with a rational parametrisation).
:func:`revolve`        profile rotated about an axis, rational quadratic arcs in v (NURBS A8.1)
:func:`translational_sweep`  ``S(u, v) = P(u) + Q(v) - Q(v0)``
:func:`rotational_sweep`     the swung surface (Woodward 1987; NURBS §10.2), see its docstring
=====================  ==========================================================================

Parameter convention: ``u`` always runs along the profile / generatrix (its own knots and
degree), ``v`` along the motion. ``S(u, v0)`` is the profile itself for every construction
except :func:`ruled` (whose ``v = 0`` row is ``c1`` and ``v = 1`` row ``c2``). Note that OCC's
``Geom_SurfaceOfRevolution`` has the roles swapped (U = angle, V = profile); ``swap_uv()`` gives
that convention.

Rational tensor products
------------------------
If ``f(P, T)`` is affine in each argument separately (bi-affine) and ``R_i(u)``, ``R_j(v)`` are
rational basis functions with weights ``w_i`` and ``ω_j`` (each a partition of unity), then

.. math:: f\Big(\sum_i R_i(u) P_i,\ \sum_j R_j(v) T_j\Big) = \sum_{i,j} R_i(u) R_j(v)\, f(P_i, T_j),

and ``R_i(u) R_j(v)`` are exactly the rational basis functions of the tensor-product net with weights
``w_i ω_j``. Extrusion, translational sweep, revolution (``f`` = rotation of ``P`` by the arc point
``T``) and the swung surface are all of this form, which is why each is exact for rational inputs.

Tolerances: ``ANGLE_SLACK`` (a revolution angle may exceed ``2 pi`` by this much) and
``AXIS_ZERO`` (an extrusion vector or a trajectory's distance to the axis is zero at most this
times the size of the geometry) of :mod:`occsurf.algorithms.tolerances`, read at call time.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import _validate as V
from .. import tolerances
from ..errors import InvalidGeometryError
from ..kernel.compat import compatible_poles
from ..kernel.curve import BSplineCurve
from ..kernel.surface import BSplineSurface
from ._common import check_curve

__all__ = [
    "extrude",
    "ruled",
    "revolve",
    "translational_sweep",
    "rotational_sweep",
]

Array = NDArray[np.float64]


# ------------------------------------------------------------------------------------- validation
def _check_curve(curve: object, name: str) -> BSplineCurve:
    return check_curve(curve, name, dim=3)


def _size(*curves: BSplineCurve) -> float:
    return max([1.0] + [float(np.abs(c.control_points).max()) for c in curves])


def _vector3(value: ArrayLike, name: str) -> Array:
    a = V.as_finite_array(value, name)
    if a.shape != (3,):
        raise InvalidGeometryError(f"{name}: expected 3 coordinates, got shape {a.shape}")
    return a


def _nonzero3(value: ArrayLike, name: str, size: float) -> Array:
    a = _vector3(value, name)
    n = float(np.linalg.norm(a))
    # scale-free; an axis *direction* (see _axis) only needs to normalise to a finite unit vector
    if not n > tolerances.AXIS_ZERO * size:
        raise InvalidGeometryError(f"{name}: expected a non-zero vector, got {a.tolist()} (length {n:.3g})")
    return a


def _axis(origin: ArrayLike, direction: ArrayLike) -> tuple[Array, Array]:
    o = _vector3(origin, "axis_origin")
    a = _vector3(direction, "axis_direction")
    big = float(np.abs(a).max())
    unit = a / big if big > 0 else a            # scaled first: no overflow or underflow in the norm
    n = float(np.linalg.norm(unit))
    if not (big > 0 and np.isfinite(unit / n).all()):
        raise InvalidGeometryError(f"axis_direction: expected a non-zero vector, got {a.tolist()}")
    return o, unit / n


def _tensor(profile: BSplineCurve, degree_v: int, knots_v: Array, poles: Array, w_v: Array | None) -> BSplineSurface:
    """Surface with the profile's u-structure; ``poles (n_u, n_v, 3)``; weights ``w_i * w_v[j]``."""
    w_u = profile.weights
    if w_u is None and w_v is None:
        W = None
    else:
        wu = np.ones(profile.n_poles) if w_u is None else w_u
        wv = np.ones(poles.shape[1]) if w_v is None else w_v
        W = np.outer(wu, wv)
    return BSplineSurface._trusted((profile.degree, degree_v), (profile.knots.copy(), knots_v), poles, W)


# ------------------------------------------------------------------------------------- extrusion
def extrude(curve: BSplineCurve, vector: ArrayLike) -> BSplineSurface:
    """Extrude a curve along a vector: the general cylinder ``S(u, v) = C(u) + v d`` (course §6-26;
    The NURBS Book, 2nd ed., §8.3).

    Parameters
    ----------
    curve : BSplineCurve
        3-D, rational or not, clamped or not.
    vector : array_like, shape (3,)
        The extrusion vector ``d``, non-zero and finite.

    Returns
    -------
    BSplineSurface
        Degree ``(p, 1)``, u = the curve's knots, v in ``[0, 1]``; poles ``(n, 2, 3)`` =
        ``[P_i, P_i + d]``, weights ``w_i`` in both columns. Exact: ``S(u, 0) = C(u)``,
        ``S(u, 1) = C(u) + d``. Same geometry as OCC's ``Geom_SurfaceOfLinearExtrusion(C, d)``
        restricted to ``V in [0, |d|]`` (OCC's v is a length along the unit direction).

    Raises
    ------
    InvalidGeometryError
        ``curve`` not a 3-D BSplineCurve; ``vector`` not 3 finite numbers or zero.
    """
    c = _check_curve(curve, "curve")
    d = _nonzero3(vector, "vector", _size(c))
    P = np.stack([c.control_points, c.control_points + d], axis=1)
    return _tensor(c, 1, np.array([0.0, 0.0, 1.0, 1.0]), P, None if c.weights is None else np.ones(2))


# ------------------------------------------------------------------------------------- ruled
def ruled(c1: BSplineCurve, c2: BSplineCurve) -> BSplineSurface:
    """Ruled surface between two curves (course §6-26; The NURBS Book, 2nd ed., §8.4).

    The curves are first made compatible (:func:`occsurf.algorithms.kernel.compat.make_compatible`: common degree
    by degree elevation, common domain, merged knot vector by refinement, both rational if either
    is); then the net is ``[c1 poles, c2 poles]`` with degree 1 in v.

    Parameters
    ----------
    c1, c2 : BSplineCurve
        3-D curves, rational or not. Their domains may differ: then both are reparametrised onto
        ``[0, 1]`` (so corresponding parameters are joined by the rulings).

    Returns
    -------
    BSplineSurface
        Degree ``(max p, 1)``, v in ``[0, 1]``; ``S(u, 0) = c1(u)``, ``S(u, 1) = c2(u)`` (exact up to
        round-off of the compatibility operations). Each v-isoline is the straight segment from
        ``c1(u)`` to ``c2(u)``; with different weights in the two rows it is traversed with a
        rational (non-uniform) speed, as in OCC's ``GeomFill::Surface``.

    Raises
    ------
    InvalidGeometryError
        Not 3-D BSplineCurves.
    """
    a = _check_curve(c1, "c1")
    b = _check_curve(c2, "c2")
    p, T, ((Pa, wa), (Pb, wb)) = compatible_poles([a, b])
    P = np.stack([Pa, Pb], axis=1)
    W = None if wa is None or wb is None else np.stack([wa, wb], axis=1)  # both or neither
    return BSplineSurface._trusted((p, 1), (T, np.array([0.0, 0.0, 1.0, 1.0])), P, W)


# ------------------------------------------------------------------------------------- revolution
def _arc_structure(angle: float) -> tuple[Array, Array, Array, float]:
    """Angles of the ``2 k + 1`` arc poles, their weights, the knot vector on ``[0, |angle|]`` and
    the factor ``1 / cos(delta / 2)`` of the middle poles (NURBS Book A8.1 segmentation)."""
    sweep = abs(angle)
    k = max(1, math.ceil(sweep / (math.pi / 2) - 1e-12))
    delta = sweep / k
    w_mid = math.cos(delta / 2)
    theta = np.copysign(delta / 2, angle) * np.arange(2 * k + 1)  # end and mid angles, signed
    w = np.ones(2 * k + 1)
    w[1::2] = w_mid
    breaks = delta * np.arange(1, k)
    knots = np.concatenate(([0.0] * 3, np.repeat(breaks, 2), [sweep] * 3))
    return theta, w, knots, 1.0 / w_mid


def _check_angle(angle: float) -> float:
    if isinstance(angle, (bool, np.bool_)):
        raise InvalidGeometryError(f"angle: expected a real number of radians, got {angle!r}")
    try:
        a = float(angle)
    except (TypeError, ValueError) as err:
        raise InvalidGeometryError(f"angle: expected a real number of radians, got {angle!r}") from err
    if not math.isfinite(a) or a == 0.0 or abs(a) > 2 * math.pi + tolerances.ANGLE_SLACK:
        raise InvalidGeometryError(f"angle: expected 0 < |angle| <= 2 pi (radians), got {angle!r}")
    return max(-2 * math.pi, min(2 * math.pi, a))


def revolve(
    profile: BSplineCurve,
    axis_origin: ArrayLike,
    axis_direction: ArrayLike,
    angle: float = 2 * math.pi,
) -> BSplineSurface:
    r"""Exact surface of revolution of any profile curve about any axis (course §6-26; The NURBS
    Book, 2nd ed., A8.1).

    Each profile pole ``P_i`` is rotated along a circular arc about the axis, the arc written as
    ``k = ceil(|angle| / 90°)`` rational quadratic pieces with middle weight ``cos(delta / 2)``,
    ``delta = |angle| / k``. With ``X_i = P_i - O_i`` (``O_i`` the foot of ``P_i`` on the axis)
    the poles of row ``i`` are

    .. math:: O_i + \cos\theta_j\,X_i + \sin\theta_j\,(a \times X_i) \quad (\text{ends}),\qquad
              \big(O_i + \cos\theta_j\,X_i + \sin\theta_j\,(a \times X_i)\big) / \cos(\delta / 2)
              \ \text{(middles, relative to } O_i)

    and the weights ``w_i ω_j`` (the profile's weights times the arc's).

    Parameters
    ----------
    profile : BSplineCurve
        3-D, rational or not. It may touch or cross the axis (poles on the axis give collapsed
        rows, e.g. a sphere's poles; a profile crossing the axis gives a self-intersecting but
        still exact surface). It need not be planar.
    axis_origin : array_like, shape (3,)
    axis_direction : array_like, shape (3,)
        Non-zero; the rotation is right-handed about it.
    angle : float, default 2 pi
        ``0 < |angle| <= 2 pi`` radians; negative turns the other way.

    Returns
    -------
    BSplineSurface
        Degree ``(p, 2)``, rational, ``n x (2 k + 1)`` poles. u: the profile's parameter; v in
        ``[0, |angle|]``, knots at the piece ends (double interior knots). The first pole column is
        the profile's poles bit for bit, so ``S(u, 0) = C(u)``; for a full turn the last column is
        too; ``S(u, |angle|)`` is the profile rotated by ``angle``. At the knots ``v = j delta``
        (and at piece midpoints) the rotation angle is exactly ``± v``; in between it is not
        (rational quadratic arcs are not arc-length parametrised).

    Raises
    ------
    InvalidGeometryError
        ``profile`` not a 3-D BSplineCurve; ``axis_direction`` zero; non-finite input;
        ``angle`` zero, non-finite or ``|angle| > 2 pi``.
    """
    c = _check_curve(profile, "profile")
    o, a = _axis(axis_origin, axis_direction)
    ang = _check_angle(angle)
    theta, w_arc, knots_v, mid_scale = _arc_structure(ang)
    P = c.control_points
    rel = P - o
    h = rel @ a
    foot = o + h[:, None] * a                         # (n, 3)
    X = rel - h[:, None] * a                          # radial part
    Y = np.cross(a, X)
    cos, sin = np.cos(theta), np.sin(theta)
    R = cos[None, :, None] * X[:, None, :] + sin[None, :, None] * Y[:, None, :]   # (n, 2k+1, 3)
    R[:, 1::2] *= mid_scale
    net = foot[:, None, :] + R
    net[:, 0] = P  # the generatrix bit-exact (foot + X rounds)
    if abs(ang) == 2 * math.pi:
        net[:, -1] = P  # close exactly
    return _tensor(c, 2, knots_v, net, w_arc)


# ------------------------------------------------------------------------------------- sweeps
def translational_sweep(profile: BSplineCurve, path: BSplineCurve) -> BSplineSurface:
    r"""Translational sweep ``S(u, v) = P(u) + Q(v) - Q(v_0)`` (course §6-26, "sweeping": the
    profile moved without rotation along the path; The NURBS Book, 2nd ed., §10.4, eq. 10.26).

    The net is ``S_ij = P_i + Q_j - Q(v_0)`` with weights ``w_i ω_j``: exact for rational profiles
    and paths too (the map is bi-affine; see the module notes).

    Parameters
    ----------
    profile : BSplineCurve
        3-D; it sits at the path's start point ``Q(v_0)``, i.e. ``S(u, v_0) = P(u)``.
    path : BSplineCurve
        3-D trajectory; only its displacement ``Q(v) - Q(v_0)`` matters.

    Returns
    -------
    BSplineSurface
        Degree ``(p_profile, p_path)``, knots of the profile and the path.

    Raises
    ------
    InvalidGeometryError
        Not 3-D BSplineCurves.
    """
    c = _check_curve(profile, "profile")
    q = _check_curve(path, "path")
    q0 = q.evaluate(q.domain[0])
    net = c.control_points[:, None, :] + (q.control_points - q0)[None, :, :]
    return _tensor(c, q.degree, q.knots.copy(), net, q.weights)


def rotational_sweep(
    profile: BSplineCurve,
    trajectory: BSplineCurve,
    axis_origin: ArrayLike = (0.0, 0.0, 0.0),
    axis_direction: ArrayLike = (0.0, 0.0, 1.0),
) -> BSplineSurface:
    r"""Rotational sweep: the profile turned about an axis while following a trajectory curve — the
    *swung surface* of Woodward (1987), The NURBS Book, 2nd ed., §10.2 (course §6-26 .. §6-33,
    "Sweeping": a rotational sweep generalises the surface of revolution).

    In the axis frame (origin ``O``, unit axis ``a``) write the trajectory ``T(v)`` as an axial
    height ``h(v) = a·(T - O)`` and an in-plane part, read as the complex number
    ``z(v) = ρ(v) e^{iφ(v)}`` relative to its start, ``z(v_0) = 1``. Then every profile point is
    rotated about the axis by ``φ(v)``, its distance to the axis scaled by ``ρ(v)``, and lifted by
    ``h(v) - h(v_0)``:

    .. math:: S(u, v) = O + \Re z(v)\,X(u) + \Im z(v)\,\big(a \times X(u)\big)
                      + \big(a\cdot(P(u) - O) + h(v) - h(v_0)\big)\,a,

    ``X(u)`` the radial part of ``P(u) - O``. This is bi-affine in ``(P, T)``, so the result is the
    exact tensor product of the two curves (weights ``w_i ω_j``). Special cases: a circle
    trajectory centred on the axis gives the surface of revolution (:func:`revolve`); an ellipse
    centred on the axis gives a revolution surface stretched by ``b / a`` in one direction (Woodward's
    swung surfaces); a trajectory with varying height adds a translation along the axis.

    Parameters
    ----------
    profile : BSplineCurve
        3-D; ``S(u, v_0) = P(u)`` exactly. It may touch or cross the axis, and need not be planar.
    trajectory : BSplineCurve
        3-D; its start point must not lie on the axis (``z`` is normalised by it). Elsewhere it may
        pass through the axis (the sections collapse there).
    axis_origin, axis_direction : array_like, shape (3,)
        Default: the z axis through the origin.

    Returns
    -------
    BSplineSurface
        Degree ``(p_profile, p_trajectory)``, the two knot vectors.

    Raises
    ------
    InvalidGeometryError
        Not 3-D BSplineCurves, zero axis direction, non-finite input, or the trajectory starting on
        the axis.
    """
    c = _check_curve(profile, "profile")
    t = _check_curve(trajectory, "trajectory")
    o, a = _axis(axis_origin, axis_direction)
    t0 = t.evaluate(t.domain[0]) - o
    r0 = t0 - (t0 @ a) * a
    rho0 = float(np.linalg.norm(r0))
    if not rho0 > tolerances.AXIS_ZERO * _size(c, t):
        raise InvalidGeometryError("trajectory: its start point lies on the axis; the rotation angle is undefined there")
    e1 = r0 / rho0
    e2 = np.cross(a, e1)
    T = t.control_points - o
    re, im = (T @ e1) / rho0, (T @ e2) / rho0           # z of each trajectory pole (n_v,)
    lift = T @ a - t0 @ a                                # h_j - h(v0)
    rel = c.control_points - o
    h = rel @ a
    X = rel - h[:, None] * a
    Y = np.cross(a, X)
    net = (o + (h[:, None, None] + lift[None, :, None]) * a
           + re[None, :, None] * X[:, None, :] + im[None, :, None] * Y[:, None, :])
    return _tensor(c, t.degree, t.knots.copy(), net, t.weights)
