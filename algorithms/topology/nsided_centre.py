"""Where the internal edges of the n-sided fill go (step 3 of :func:`.nsided.fill_hole`, course §8-3).

The central split joins a point ``m_i`` on every side (:func:`midpoints`) to a centre ``C``
(:func:`centre`); the ribbon coefficients at ``m_i`` say which way the internal edge leaves the
side, and :func:`centre_map` is the one affine map of the domain that gives the patches a common
tangent plane at ``C``. Where the midpoints' mean lies outside the hole (a crescent, a tapering
sliver) or the plain layout folds, the layout is taken from a harmonic map of the hole onto the
domain polygon (:func:`harmonic_boundary`, :func:`harmonic_layout`;
:mod:`~occsurf.algorithms.topology.nsided_loops` builds the map).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from .. import tolerances
from ..errors import InvalidGeometryError
from .nsided_loops import harmonic_centre, harmonic_picture, inner_point, turns_inward
from .nsided_poly import angle_deg, cart, cart_tangent, unit
from .nsided_prepare import Side

__all__ = ["Midpoints", "midpoints", "outward_ribbons", "centre", "centre_map", "harmonic_boundary",
           "harmonic_layout"]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class Midpoints:
    """The sides at their split points ``m_i``, where the internal edges start (:func:`midpoints`).

    Attributes
    ----------
    fields : list of (ndarray, ndarray), length n
        Side ``i``'s fields and their s-derivatives at ``sig_i`` (:meth:`Side.fields`), each
        shape (1, nf, w).
    point, tangent : ndarray, shape (n, w)
        ``B_i(sig_i)`` and ``B_i'(sig_i)`` (homogeneous for rational data).
    cart : ndarray, shape (n, 3)
        The Cartesian points ``m_i``.
    normals : ndarray, shape (n, 3)
        Unit normals of the neighbours' tangent planes at ``m_i``.
    """

    fields: list[tuple[Array, Array]]
    point: Array
    tangent: Array
    cart: Array
    normals: Array


def midpoints(S: list[Side], sig: Array, rational: bool) -> Midpoints:
    """Evaluate every side at its split point, with the neighbour's tangent plane there.

    Raises
    ------
    InvalidGeometryError
        A cross field (nearly) tangent to its side at the split point.
    """
    n = len(S)
    Fm = [sd.fields(sig[i]) for i, sd in enumerate(S)]
    mh = np.array([S[i].B.evaluate(sig[i]) for i in range(n)])
    mder = np.array([S[i].tangent(sig[i]) for i in range(n)])
    mc = cart(mh, rational)
    normals = np.zeros((n, 3))
    for i in range(n):
        tc = cart_tangent(mh[i], mder[i], rational)
        dc = cart_tangent(mh[i], Fm[i][0][0, 0], rational)
        if angle_deg(tc, dc) < tolerances.FILL_MIN_CORNER_ANGLE:
            raise InvalidGeometryError(f"sides[{i}].cross: nearly tangent to the boundary "
                                       f"({angle_deg(tc, dc):.3g} deg); the neighbour is degenerate there")
        normals[i] = unit(np.cross(tc, dc))
    return Midpoints(Fm, mh, mder, mc, normals)


def outward_ribbons(c1: Array) -> bool:
    """Whether a ribbon at a midpoint does not point into the hole (a coefficient of its cross
    field ``>= 0``, :func:`centre`'s ``c1``): the hole may not be convex, and only then does
    :func:`centre` look at the loop (so its caller need not make the loop otherwise)."""
    return bool(np.any(c1[:, 0] >= 0))


def centre(mid: Midpoints, rational: bool, loop: Array | None = None,
           harmonic: tuple[Array, Array] | None = None) -> tuple[Array, Array]:
    """The centre ``C`` and the ribbon coefficients at the midpoints.

    ``C`` is the mean of the midpoints, each moved half-way towards that mean within its
    neighbour's tangent plane; the ribbon at ``m_i`` points along the projection of ``C - m_i``.
    When that leaves the hole at some midpoint (a long curved hole, a crescent: the midpoints' mean
    lies outside it), and ``loop`` (m, 3), points of the boundary, is given, ``C`` is instead the
    preimage of the domain's centre under the harmonic map of ``harmonic`` (loop samples (k, 3) and
    their domain places (k, 2), :func:`harmonic_boundary`;
    :func:`~occsurf.algorithms.topology.nsided_loops.harmonic_centre`), or without it the point of
    the hole farthest from its boundary in the hole's mean plane
    (:func:`~occsurf.algorithms.topology.nsided_loops.inner_point`: on a sector any point of the
    medial arc, which folded the fill), lifted to the mean of the midpoints' tangent planes above it.

    Returns
    -------
    C : ndarray, shape (3,)
        Cartesian, in working coordinates.
    c1 : ndarray, shape (n, nf)
        Coefficients of the fields at ``m_i``.
    """
    n, mc, normals = len(mid.cart), mid.cart, mid.normals

    def proj(i: int, d: Array) -> Array:
        return d - normals[i] * (normals[i] @ d)

    C0 = mc.mean(0)
    C = np.mean([mc[i] + 0.5 * proj(i, C0 - mc[i]) for i in range(n)], axis=0)
    c1 = _midpoint_coefficients(mid, C, rational)
    if loop is None or not outward_ribbons(c1) or not turns_inward(loop, normals):
        return C, c1  # convex enough, or cross fields that point into the hole: check_inward says so
    hc = None if harmonic is None else harmonic_centre(harmonic[0], harmonic[1], normals)
    inner = hc[:2] if hc is not None else inner_point(loop, normals)
    if inner is not None:
        C0, nh = inner
        C = C0 + nh * np.mean([nh @ (mc[i] + proj(i, C0 - mc[i]) - C0) for i in range(n)])
        c1 = _midpoint_coefficients(mid, C, rational)
    if np.any(c1[:, 0] >= 0):  # a sliver: the centre is along the side, not across it
        c1 = _midpoint_coefficients(mid, C, rational, turn=True)
    return C, c1


def _midpoint_coefficients(mid: Midpoints, C: Array, rational: bool, turn: bool = False) -> Array:
    """Coefficients (n, nf) of the fields at the midpoints for ribbons along the projections of
    ``C - m_i`` into the neighbours' tangent planes; with ``turn``, a projection that leaves the
    side at less than ``tolerances.FILL_MIN_EDGE_ANGLE`` into the hole is turned to that angle (same length)."""
    n, mc, normals = len(mid.cart), mid.cart, mid.normals
    c1 = np.zeros((n, mid.fields[0][0].shape[1]))
    for i in range(n):
        d = C - mc[i]
        t = d - normals[i] * (normals[i] @ d)
        if turn:
            tau = unit(cart_tangent(mid.point[i], mid.tangent[i], rational))
            x = cart_tangent(mid.point[i], mid.fields[i][0][0, 0], rational)
            w = -unit(x - tau * (x @ tau))  # in the tangent plane, across the side, into the hole
            a, b, length = float(t @ tau), float(t @ w), float(np.linalg.norm(t))
            lo = np.radians(tolerances.FILL_MIN_EDGE_ANGLE)
            if b < np.sin(lo) * length:
                t = length * (np.cos(lo) * (1.0 if a >= 0 else -1.0) * tau + np.sin(lo) * w)
        target = np.r_[mid.point[i, 3] * t, 0.0] if rational else t
        c1[i], *_ = np.linalg.lstsq(mid.fields[i][0][0].T, target, rcond=tolerances.FILL_RCOND)
    return c1


def centre_map(C: Array, mc: Array, pdom: Array, rational: bool) -> Array:
    """The derivative ``DPhi`` (w, 2) of the affine map of the domain that gives the centre's
    tangent plane: ``C - m_i = DPhi (-p_i)`` in the least-squares sense (``mc``, ``pdom``: (n, 3),
    (n, 2)); one map for all patches, so that their tangent planes at the centre agree."""
    n = len(mc)
    tg = np.array([np.r_[C - mc[i], 0.0] if rational else C - mc[i] for i in range(n)])
    return np.linalg.lstsq(-pdom, tg, rcond=tolerances.FILL_RCOND)[0].T  # g_i = DPhi (-p_i)


def harmonic_boundary(S: list[Side], sig: Array, vdom: Array, pdom: Array, rational: bool,
                      samples: int = 128) -> tuple[Array, Array]:
    """Dense loop points (n * samples, 3) and their places (n * samples, 2) on the boundary of the
    domain polygon, for :func:`~occsurf.algorithms.topology.nsided_loops.harmonic_centre`: the
    half side ``[0, sig_i]`` of side ``i`` goes onto ``[v_i, p_i]`` and ``[sig_i, 1]`` onto
    ``[p_i, v_{i+1}]``, each in proportion to arc length (a side's parametrisation, often far from
    uniform on a fitted trace, does not skew the picture)."""
    n = len(S)
    pts, tgt = [], []
    for i, sd in enumerate(S):
        for lo, hi, a, b in ((0.0, sig[i], vdom[i], pdom[i]), (sig[i], 1.0, pdom[i], vdom[(i + 1) % n])):
            t = np.linspace(lo, hi, samples // 2 + 1)[:-1]
            P = cart(sd.B.evaluate(np.r_[t, hi]), rational)
            cum = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(P, axis=0), axis=1))]
            f = (cum / max(cum[-1], 1e-300))[:-1, None]
            pts.append(P[:-1])
            tgt.append((1 - f) * a + f * b)
    return np.concatenate(pts), np.concatenate(tgt)


def harmonic_layout(mid: Midpoints, rational: bool, boundary: tuple[Array, Array], pdom: Array
                     ) -> tuple[Array, Array, Array] | None:
    """Centre, midpoint ribbons and centre map from the harmonic picture of the hole (course §8-3).

    A harmonic map of the hole onto the domain polygon
    (:func:`~occsurf.algorithms.topology.nsided_loops.harmonic_picture`, ``boundary`` from
    :func:`harmonic_boundary`) is one-to-one; the central split takes its layout
    from it: ``C`` is the preimage of the domain's centre (lifted, as in :func:`centre`, to the mean
    of the midpoints' tangent planes), internal edge ``i`` leaves ``m_i`` along the preimage of the
    domain segment ``p_i -> 0`` (its ribbon there: that direction in the neighbour's tangent plane,
    as long as the preimage curve), and the centre map ``DPhi`` is the inverse map's Jacobian at the
    centre (plus the slope of the chords ``C - m_i`` out of the mean plane). On a long curved hole
    the chords ``C - m_i`` cut across the hole and the corner patches fold; the harmonic curves
    follow it.

    Returns
    -------
    (C, c1, DPhi) or None
        As :func:`centre` and :func:`centre_map`; ``None`` when the picture cannot be built or
        inverted (a degenerate projection), or a ribbon would not point into the hole.
    """
    n, mc, normals = len(mid.cart), mid.cart, mid.normals
    if not turns_inward(boundary[0], normals):
        return None
    hp = harmonic_picture(boundary[0], boundary[1], normals)
    if hp is None:
        return None
    fr = np.linspace(0.0, 1.0, 9)[1:]
    uv = (pdom[:, None, :] * (1.0 - fr)[None, :, None]).reshape(-1, 2)
    P, Jinv, ok = hp.preimage(np.r_[np.zeros((1, 2)), uv])
    if not ok.all():
        return None
    nh = hp.normal
    C0, Jc, curves = P[0], Jinv[0], P[1:].reshape(n, len(fr), 3)
    proj = lambda i, d: d - normals[i] * (normals[i] @ d)  # noqa: E731
    C = C0 + nh * np.mean([nh @ (mc[i] + proj(i, C0 - mc[i]) - C0) for i in range(n)])
    c1 = np.zeros((n, mid.fields[0][0].shape[1]))
    for i in range(n):
        start = mc[i] - nh * (nh @ (mc[i] - hp.origin))  # m_i in the mean plane
        poly = np.r_[start[None], curves[i]]
        length = float(np.linalg.norm(np.diff(poly, axis=0), axis=1).sum())
        t = proj(i, curves[i][1] - start)
        t = length * unit(t)
        target = np.r_[mid.point[i, 3] * t, 0.0] if rational else t
        c1[i], *_ = np.linalg.lstsq(mid.fields[i][0][0].T, target, rcond=tolerances.FILL_RCOND)
    if np.any(c1[:, 0] >= 0):
        return None
    rise = np.array([nh @ (C - mc[i]) for i in range(n)])
    slope = np.linalg.lstsq(-pdom, rise, rcond=tolerances.FILL_RCOND)[0]
    D = Jc + np.outer(nh, slope)
    DPhi = np.r_[D, np.zeros((1, 2))] if rational else D
    return C, c1, DPhi
