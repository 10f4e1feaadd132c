"""The hole corners of the n-sided fill (step 2 of :func:`.nsided.fill_hole`, course §8-3).

At hole corner ``V_i`` side ``i`` starts and side ``i - 1`` ends; the corner patch ``i`` sees both.
:func:`corner_analysis` fits the two sides' ribbon coefficients to each other there (each ribbon is
the other side's tangent, the twists agree in the least-squares sense) and reports what cannot be
met: the corner residual (neighbours not G1 to each other) and the twist mismatch (neighbours not
G2-compatible: Gregory's twist incompatibility). It refuses degenerate corners (a cusp, a cross
field along its side, neighbours meeting at a sharp edge); :func:`check_inward` refuses a fill that
would leave over a neighbour (a reflex corner).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from .. import tolerances
from ..errors import InvalidGeometryError
from .nsided_poly import angle_deg, cart_tangent
from .nsided_prepare import Side

__all__ = ["CornerFit", "corner_analysis", "check_inward"]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class CornerFit:
    """The ribbon coefficients ``c_f`` at the hole corners (:func:`corner_analysis`).

    Corner ``i`` is the start of side ``i`` and the end of side ``i - 1``, the ``(0, 0)`` corner of
    patch ``i``. ``nf`` is the number of fields: 2 (``X, B'``), 3 for rational data (``X, B', B``).

    Attributes
    ----------
    start, start_d : ndarray, shape (n, nf)
        Value and u-derivative at ``u = 0`` of the coefficients of side ``i``'s ribbon on patch
        ``i`` (``s = sig_i u``): the ribbon there is the tangent of side ``i - 1``.
    end, end_d : ndarray, shape (n, nf)
        The same at ``v = 0`` for side ``i - 1`` on patch ``i`` (``s = 1 - (1 - sig_{i-1}) v``).
    residual : ndarray, shape (n,)
        :attr:`.nsided_types.HoleFill.corner_residual`.
    twist : ndarray, shape (n,)
        :attr:`.nsided_types.HoleFill.twist_mismatch`.
    flat : ndarray of bool, shape (n,)
        :attr:`.nsided_types.HoleFill.flat`.
    """

    start: Array
    start_d: Array
    end: Array
    end_d: Array
    residual: Array
    twist: Array
    flat: Array


def corner_analysis(S: list[Side], sig: Array, rational: bool, c1: Array | None = None) -> CornerFit:
    """Fit the ribbons of the two sides at every hole corner to each other (step 2).

    At corner ``i`` each side's ribbon must be the other side's tangent (so that the patch's
    corner is consistent), and the twists seen from both sides must agree: a least-squares fit in
    the fields' span, whose residuals are the corner diagnostics.

    Parameters
    ----------
    S : list of Side, length n
        The sides in working coordinates.
    sig : ndarray, shape (n,)
        Split parameters.
    rational : bool
    c1 : ndarray, shape (n, nf), optional
        Ribbon coefficients at the midpoints (:func:`.nsided_centre.centre`): at a flat corner the cross-field
        coefficient's derivative is set to its midpoint value (a linear ramp from 0).

    Returns
    -------
    CornerFit

    Raises
    ------
    InvalidGeometryError
        A degenerate cross field at a corner, or neighbours meeting at a sharp edge.
    """
    n, nf = len(S), S[0].nf
    c1 = np.zeros((n, nf)) if c1 is None else c1
    out = [_corner(i, S, sig, rational, c1) for i in range(n)]
    start, end, start_d, end_d = (np.array([c[k] for c in out]).reshape(n, nf) for k in range(4))
    residual, twist = np.array([c[4] for c in out]), np.array([c[5] for c in out])
    return CornerFit(start, start_d, end, end_d, residual, twist, np.array([c[6] for c in out], bool))


def _corner(i: int, S: list[Side], sig: Array, rational: bool,
            c1: Array) -> tuple[Array, Array, Array, Array, float, float, bool]:
    """Hole corner ``i`` for :func:`corner_analysis` (``c1`` (n, nf): the midpoint coefficients).

    Returns
    -------
    start, end, start_d, end_d : ndarray, shape (nf,)
        Row ``i`` of the :class:`CornerFit` arrays of the same names.
    residual, twist : float
        Corner residual and twist mismatch at corner ``i``.
    flat : bool
        The corner is flat.
    """
    nf = S[0].nf
    j = (i - 1) % len(S)
    tau_j = 1.0 - sig[j]
    (Fa,), (dFa,) = S[i].fields(0.0)  # (nf, w) fields of side i at s=0
    (Fb,), (dFb,) = S[j].fields(1.0)  # of side i-1 at s=1
    ta = sig[i] * S[i].tangent(0.0)  # a'(0)
    tb = -tau_j * S[j].tangent(1.0)  # b'(0)
    h0 = S[i].B.evaluate(0.0)  # the corner (homogeneous, weight 1)
    flat = _check_corner_angles(i, j, h0, cart_tangent(h0, ta, rational), cart_tangent(h0, tb, rational), Fa, Fb,
                                rational)
    rcond = tolerances.FILL_RCOND
    xa, *_ = np.linalg.lstsq(Fa.T, tb, rcond=rcond)
    xb, *_ = np.linalg.lstsq(Fb.T, ta, rcond=rcond)
    residual = float(max(np.linalg.norm(Fa.T @ xa - tb) / np.linalg.norm(tb),
                         np.linalg.norm(Fb.T @ xb - ta) / np.linalg.norm(ta)))
    plane_tol = tolerances.FILL_CORNER_PLANE_TOL
    if not residual <= plane_tol:
        raise InvalidGeometryError(
            f"sides: at hole corner {i} the neighbours of sides {j} and {i} meet at a sharp edge (their "
            f"tangent planes differ by {np.degrees(np.arcsin(min(residual, 1.0))):.3g} deg, more than "
            f"{np.degrees(np.arcsin(plane_tol)):.3g}): no surface is G1 to both there")
    rhs = (-tau_j * xb @ dFb) - (sig[i] * xa @ dFa)
    M = np.c_[Fa.T, -Fb.T]
    # At a flat corner the two sides' fields span one plane, so the twist fixes only the difference
    # of their cross-field rates; the solution nearest to both ramping linearly to their midpoint
    # values (y0) keeps both ribbons turning into the hole (a minimum-norm one would send one out).
    # The two fields' planes agree only within the corner's flatness (and a fitted field's error), so
    # directions of M resolved by less than the sine of FILL_MIN_CORNER_ANGLE are left at y0.
    y0 = np.zeros(2 * nf)
    if flat:
        y0[0], y0[nf] = c1[i, 0], c1[j, 0]
        rcond = max(rcond, float(np.sin(np.radians(tolerances.FILL_MIN_CORNER_ANGLE))))
    y = y0 + np.linalg.lstsq(M, rhs - M @ y0, rcond=rcond)[0]
    # A twist far beyond the ribbons' own scale (the derivative of a wiggly fitted cross field at the
    # corner, 1e6 measured on a bearing face) would throw the corner patch out of the hole: the
    # coefficients then ramp linearly to their midpoint values instead, and the unmet twist is
    # reported (and confined to the corner span) like any incompatible one.
    scale = max(float(np.abs(np.r_[xa, xb, c1[i], c1[j]]).max()), 1e-300)
    if np.abs(y).max() > tolerances.FILL_MAX_TWIST_RATIO * scale:
        y = np.r_[c1[i] - xa, c1[j] - xb]
    twist = float(np.linalg.norm(M @ y - rhs) / max(float(np.linalg.norm(ta)), float(np.linalg.norm(tb)),
                                                    1e-300))
    return xa, xb, y[:nf], y[nf:], residual, twist, flat


def _check_corner_angles(i: int, j: int, h0: Array, tca: Array, tcb: Array, Fa: Array, Fb: Array,
                         rational: bool) -> bool:
    """Whether corner ``i`` is flat (its sides tangent, within ``tolerances.FILL_MIN_CORNER_ANGLE``);
    refuse a cross field there that is (nearly) tangent to its side, and a cusp (the two sides
    leaving the corner in the same direction).

    ``h0`` (w,) is the corner, ``tca``, ``tcb`` (3,) the Cartesian tangents of sides ``i`` and
    ``j = i - 1`` into the corner's patch, ``Fa``, ``Fb`` (nf, w) their fields there.
    """
    min_angle = tolerances.FILL_MIN_CORNER_ANGLE
    flat = bool(angle_deg(tca, tcb) < min_angle)
    if flat and float(tca @ tcb) > 0:
        raise InvalidGeometryError(
            f"sides: corner {i} (start of side {i}) is a cusp: sides {j} and {i} leave it in the same direction "
            f"(within {min_angle} deg); the loop turns back on itself there")
    for k, at, F, t_side in ((i, "start", Fa, tca), (j, "end", Fb, tcb)):
        cross = cart_tangent(h0, F[0], rational)
        ang = angle_deg(t_side, cross)
        if not np.linalg.norm(cross) > 0 or not ang >= min_angle:
            raise InvalidGeometryError(
                f"sides[{k}].cross: degenerate at the {at} of the side (its angle to the boundary is "
                f"{ang:.3g} deg): the neighbour has a pole or a collapsed edge at hole corner {i} (a sphere "
                "or a fillet corner), where no tangent plane across the boundary is defined")
    return flat


def check_inward(corners: CornerFit, c1: Array) -> None:
    """Refuse a fill that would leave over a neighbour: the coefficient of the cross field ``X``
    (column 0 of ``corners.start``, ``corners.end`` and ``c1``, each (n, nf)) must be negative; at a
    flat corner, where it is 0, its derivative into the side (``start_d``, ``end_d``)."""
    flat = corners.flat
    start = np.where(flat[:, None], corners.start_d, corners.start)
    end = np.where(flat[:, None], corners.end_d, corners.end)
    for arr, where in ((start, "corner"), (end, "corner"), (c1, "midpoint")):
        if np.any(arr[:, 0] >= 0):
            k = int(np.argmax(arr[:, 0]))
            raise InvalidGeometryError(
                f"sides: at the {where} of side {k} the fill would leave over the neighbour: a reflex corner "
                "(interior angle above 180 deg, not supported by the central split), or a cross field pointing "
                "into the hole (it must point into its neighbour)")
