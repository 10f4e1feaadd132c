"""Second-order data of a hole's neighbours along its sides: what a curvature-continuous (G2) fill
matches (course §8-3 and ch. 9, continuity; issue 31).

A side (:class:`.nsided_types.HoleSide`) with ``cross2`` carries the neighbour surface ``G(s, t)``
to second order along the boundary ``t = 0``: ``G``, ``G_s``, ``G_ss`` from the boundary curve,
``G_t``, ``G_st`` from ``cross`` and ``G_tt`` from ``cross2`` (homogeneous for a rational side).
:func:`side_jet` turns these into Cartesian partials (the quotient rule, The NURBS Book eq. (4.8)
and its second-order form), :func:`cross_curvature` takes the normal curvature of a surface across
a curve from its partials (the measure CATIA's G2 percentage and ``occsurf check``'s ``g2_rel``
compare: with G0 and G1 holding, the curvature across the edge is the only one that can jump), and
:func:`graph_jet` writes a surface near a point as a height over a plane (gradient and Hessian by
implicit differentiation), which is what the plate fill (:func:`.plate_fill.fill_plate`) fits.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidGeometryError
from ..kernel.curve import BSplineCurve
from .nsided_types import HoleSide

__all__ = ["side_jet", "cross_curvature", "graph_jet", "relative_jump"]

Array = NDArray[np.float64]


def side_jet(side: HoleSide, t: Array) -> tuple[Array, Array, Array, Array, Array, Array]:
    """Cartesian partials of the neighbour along a side: ``(G, G_s, G_t, G_ss, G_st, G_tt)``, each (m, 3).

    ``s`` is the side's parameter, ``t`` the parameter across it (``G_t`` is ``side.cross``,
    pointing into the neighbour). For a rational side the homogeneous partials ``A = w G`` are
    converted by ``G_a = (A_a - w_a G) / w`` and
    ``G_ab = (A_ab - w_ab G - w_a G_b - w_b G_a) / w``.

    Raises
    ------
    InvalidGeometryError
        The side carries no second-order data (``cross2`` is ``None``).
    """
    if side.cross2 is None:
        raise InvalidGeometryError("side: no second cross derivative (cross2): the neighbour's curvature across "
                                   "the side is unknown, so a G2 fill cannot be asked on it")
    t = np.asarray(t, float)
    c = side.curve
    Xd = side.cross.derivatives(t, 1)
    X2 = side.cross2.evaluate(t)
    if not c.is_rational:
        D = c.derivatives(t, 2)
        return D[:, 0], D[:, 1], Xd[:, 0], D[:, 2], Xd[:, 1], X2
    hc = BSplineCurve._trusted(c.degree, c.knots, c.homogeneous_points)
    D = hc.derivatives(t, 2)
    A, As, Ass = D[:, 0, :3], D[:, 1, :3], D[:, 2, :3]
    w, ws, wss = D[:, 0, 3:], D[:, 1, 3:], D[:, 2, 3:]
    At, wt = Xd[:, 0, :3], Xd[:, 0, 3:]
    Ast, wst = Xd[:, 1, :3], Xd[:, 1, 3:]
    Att, wtt = X2[:, :3], X2[:, 3:]
    G = A / w
    Gs, Gt = (As - ws * G) / w, (At - wt * G) / w
    Gss = (Ass - wss * G - 2 * ws * Gs) / w
    Gst = (Ast - wst * G - ws * Gt - wt * Gs) / w
    Gtt = (Att - wtt * G - 2 * wt * Gt) / w
    return G, Gs, Gt, Gss, Gst, Gtt


def cross_curvature(Su: Array, Sv: Array, Suu: Array, Suv: Array, Svv: Array, T: Array, n: Array) -> Array:
    """Normal curvature of a surface across a curve on it: in the direction ``b = n x T`` (unit).

    Parameters
    ----------
    Su, Sv, Suu, Suv, Svv : ndarray, shape (m, 3)
        The surface's partials at the curve's points.
    T : ndarray, shape (m, 3)
        The curve's tangents (any length).
    n : ndarray, shape (m, 3)
        Unit normals giving the sign (the curvature is ``n . S_bb``: positive where the surface
        bends towards ``n``); the surface's own normal is turned to agree with them.

    Returns
    -------
    ndarray, shape (m,)
        ``k = n . (a^2 S_uu + 2 a b S_uv + b^2 S_vv)`` where ``a S_u + b S_v = b`` (least squares:
        ``b`` lies in the tangent plane when ``n`` is the surface's normal).
    """
    N = np.cross(Su, Sv)
    N /= np.maximum(np.linalg.norm(N, axis=1, keepdims=True), 1e-300)
    N *= np.where(np.einsum("ij,ij->i", N, n) < 0, -1.0, 1.0)[:, None]
    b = np.cross(N, T)
    b /= np.maximum(np.linalg.norm(b, axis=1, keepdims=True), 1e-300)
    # (a, c) from the 2 x 2 normal equations of [Su Sv] (a, c) = b
    g11, g12, g22 = (np.einsum("ij,ij->i", x, y) for x, y in ((Su, Su), (Su, Sv), (Sv, Sv)))
    r1, r2 = np.einsum("ij,ij->i", Su, b), np.einsum("ij,ij->i", Sv, b)
    det = g11 * g22 - g12 ** 2
    det = np.where(np.abs(det) > 0, det, 1e-300)
    a, c = (g22 * r1 - g12 * r2) / det, (g11 * r2 - g12 * r1) / det
    second = a[:, None] ** 2 * Suu + 2 * (a * c)[:, None] * Suv + c[:, None] ** 2 * Svv
    return np.einsum("ij,ij->i", N, second)


def relative_jump(k1: Array, k2: Array, floor: float) -> Array:
    """CATIA's G2 ratio ``|k1 - k2| / max(|k1|, |k2|)`` (a fraction, not percent); 0 where both
    curvatures are below ``floor`` (between two almost flat surfaces the ratio is noise), and the
    jump over ``floor`` where only one is."""
    k1, k2 = np.asarray(k1, float), np.asarray(k2, float)
    den = np.maximum(np.maximum(np.abs(k1), np.abs(k2)), floor)
    out = np.abs(k1 - k2) / den
    return np.where((np.abs(k1) < floor) & (np.abs(k2) < floor), 0.0, out)


def graph_jet(Gs: Array, Gt: Array, Gss: Array, Gst: Array, Gtt: Array) -> tuple[Array, Array]:
    """A surface as a height ``z = f(x, y)`` near each point, from its partials in a frame whose third
    axis is the height: the gradient ``(f_x, f_y)`` (m, 2) and the Hessian ``(f_xx, f_xy, f_yy)`` (m, 3).

    With ``J = [[x_s, x_t], [y_s, y_t]]``: ``grad f = J^{-T} (z_s, z_t)`` and
    ``J^T H J = [z_ab - grad f . (x_ab, y_ab)]`` (implicit differentiation of ``z(s, t) =
    f(x(s, t), y(s, t))``). The partials must already be in the frame (rotate them first).

    Raises
    ------
    InvalidGeometryError
        The surface stands vertical over the plane somewhere (``J`` singular): no height there.
    """
    J = np.stack([np.c_[Gs[:, 0], Gt[:, 0]], np.c_[Gs[:, 1], Gt[:, 1]]], axis=1)  # (m, 2, 2)
    det = np.linalg.det(J)
    scale = np.linalg.norm(Gs[:, :2], axis=1) * np.linalg.norm(Gt[:, :2], axis=1)
    if np.any(~(np.abs(det) > 1e-12 * np.maximum(scale, 1e-300))):
        raise InvalidGeometryError("side: the neighbour stands vertical over the fill's plane (its curvature "
                                   "cannot be written as a height there)")
    Ji = np.linalg.inv(J)
    g = np.einsum("mji,mj->mi", Ji, np.c_[Gs[:, 2], Gt[:, 2]])  # J^{-T} (z_s, z_t)
    A = np.empty((len(Gs), 2, 2))
    for (i, j), D in (((0, 0), Gss), ((0, 1), Gst), ((1, 1), Gtt)):
        A[:, i, j] = D[:, 2] - np.einsum("mi,mi->m", g, D[:, :2])
    A[:, 1, 0] = A[:, 0, 1]
    H = np.einsum("mki,mkl,mlj->mij", Ji, A, Ji)  # J^{-T} A J^{-1}
    return g, np.c_[H[:, 0, 0], 0.5 * (H[:, 0, 1] + H[:, 1, 0]), H[:, 1, 1]]
