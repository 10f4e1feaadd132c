"""The domain picture and the internal edges of the n-sided fill (steps 1 and 4 of
:func:`.nsided.fill_hole`, course §8-3).

The domain is a regular n-gon split into kites (:func:`domain_picture`); along each kite edge the
bilinear parametrisations of the two kites satisfy ``a A + b B = r T`` with ``a, b`` linear and
``r`` quadratic (:func:`_kite_relation`). :func:`internal_edge` builds internal edge ``E_i`` (a
quartic from the side's split point ``m_i`` to the centre) and the two patches' cross derivatives
``L``, ``R`` along it so that ``a L + b R = r E'`` holds identically: G1 between patches ``i`` and
``i + 1`` by a polynomial identity (course §8-3; the NURBS Book, 2nd ed., §10 on G1 joins).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from .. import tolerances
from ..errors import InvalidGeometryError, ToleranceError
from .nsided_centre import Midpoints
from .nsided_poly import Poly, scalar_poly

__all__ = ["domain_picture", "InternalEdge", "internal_edge"]

Array = NDArray[np.float64]


def domain_picture(sig: Array) -> tuple[Array, Array]:
    """The regular n-gon of the kite split: its vertices and the images of the split points.

    Parameters
    ----------
    sig : ndarray, shape (n,)
        Split parameter of each side.

    Returns
    -------
    vdom : ndarray, shape (n, 2)
        Vertex ``i`` (hole corner ``V_i``) at angle ``2 pi i / n`` on the unit circle.
    pdom : ndarray, shape (n, 2)
        The point of domain side ``i`` at ``sig[i]`` (the midpoint ``m_i``).
    """
    n = len(sig)
    th = 2 * np.pi * np.arange(n) / n
    vdom = np.c_[np.cos(th), np.sin(th)]
    pdom = np.array([(1 - sig[i]) * vdom[i] + sig[i] * vdom[(i + 1) % n] for i in range(n)])
    return vdom, pdom


def _kite_relation(v: Array, p: Array, i: int, n: int) -> tuple[Poly, Poly, Poly, dict[str, Array]]:
    """Domain relation ``a A + b B = r T`` along internal edge ``i`` of the kite split (see module)."""
    A0, A1 = p[i] - v[i], -p[i - 1]
    B0, B1 = p[i] - v[(i + 1) % n], -p[(i + 1) % n]
    T = -p[i]
    perp = np.array([-T[1], T[0]])
    M = np.array([[perp @ A0, 0.0, perp @ B0, 0.0],
                  [perp @ A1, perp @ A0, perp @ B1, perp @ B0],
                  [0.0, perp @ A1, 0.0, perp @ B1]])
    # The null space of M is 1-D in general but 2-D when the split is symmetric (every side split
    # at its middle: then A and B mirror each other about T and every a = b solves it), where a
    # bare "last singular vector" is an arbitrary member, LAPACK-dependent, that can have a0 = 0.
    # Take the member nearest to a = b = 1 (constant coefficients, the lowest degree): unique,
    # continuous in the data, and the same on every machine.
    null_rtol = tolerances.FILL_NULL_RTOL
    _, sv, Vt = np.linalg.svd(M)
    null = Vt[np.r_[sv, np.zeros(4 - sv.shape[0])] <= null_rtol * sv[0]]
    if null.shape[0] == 0:
        null = Vt[-1:]
    x = null.T @ (null @ np.ones(4))  # (a0, a1, b0, b1)
    if not np.any(x):
        x = Vt[-1]
    if x[0] < 0:
        x = -x
    if not np.all(x > null_rtol * np.abs(x).max()):
        raise InvalidGeometryError(
            f"sides: the domain relation of internal edge {i} has a coefficient that vanishes on the edge "
            f"({np.array2string(x, precision=3)}): the side split parameters are too uneven")
    a, b = scalar_poly([x[0], x[1] - x[0]]), scalar_poly([x[2], x[3] - x[2]])
    # r(t) = (a A + b B) . T / |T|^2, quadratic
    A = Poly(np.array([A0, A1 - A0]))
    Bp = Poly(np.array([B0, B1 - B0]))
    V = a * A + b * Bp
    r = Poly((V.coef @ T / (T @ T))[:, None])
    return a, b, r, {"A0": A0, "A1": A1, "B0": B0, "B1": B1, "T": T}


# ================================================================================ internal edges
@dataclass(frozen=True)
class InternalEdge:
    """Internal edge ``i``, from ``m_i`` (``t = 0``) to the centre (``t = 1``) (:func:`internal_edge`).

    Attributes
    ----------
    curve : Poly
        ``E_i(t)``, quartic, coefficients (5, w).
    left, right : Poly
        The cross derivatives ``L_i`` of patch ``i`` and ``R_i`` of patch ``i + 1`` along it.
    coef_d_before, coef_d_after : ndarray, shape (nf,)
        Derivatives of the ribbon coefficients at ``m_i``: along ``u`` on patch ``i`` (the half
        side before ``m_i``) and along ``v`` on patch ``i + 1`` (the half after it).
    """

    curve: Poly
    left: Poly
    right: Poly
    coef_d_before: Array
    coef_d_after: Array


def internal_edge(i: int, vdom: Array, pdom: Array, sig_i: float, mid: Midpoints, c1_i: Array, Ch: Array,
                  DPhi: Array) -> InternalEdge:
    """Build internal edge ``i`` and the two cross fields along it, G1 by a polynomial identity.

    ``E_i`` is the Hermite quartic from ``m_i`` (tangent = the ribbon there) to the centre ``Ch``
    (w,) (tangent from ``DPhi`` (w, 2)); its end derivatives and those of the cross fields come
    from the corner conditions at ``m_i`` (``c1_i`` (nf,), the ribbon coefficients there) and from
    the centre's affine map. ``vdom``, ``pdom`` (n, 2): the domain picture.
    """
    tau_i = 1.0 - sig_i
    a, b, r, dom = _kite_relation(vdom, pdom, i, len(vdom))
    a0, b0 = a(0.0)[0], b(0.0)[0]
    a0d, b0d = a(0.0, 1)[0], b(0.0, 1)[0]
    r0d = r(0.0, 1)[0]
    (F,), (dF,) = mid.fields[i]
    rhs = r0d * c1_i.copy()
    rhs[1] -= a0d * sig_i - b0d * tau_i
    ca1d, cb1d = 0.5 * rhs / a0, 0.5 * rhs / b0
    T0 = c1_i @ F
    mh, mder = mid.point[i], mid.tangent[i]
    Ei = Poly.hermite([(0.0, 0, mh), (0.0, 1, T0), (1.0, 0, Ch), (1.0, 1, DPhi @ dom["T"]),
                        (1.0, 2, np.zeros(mh.shape[0]))])
    left = (sig_i * mder, ca1d @ F + sig_i * c1_i @ dF, DPhi @ dom["A1"], DPhi @ (dom["A1"] - dom["A0"]))
    right = (-tau_i * mder, cb1d @ F - tau_i * c1_i @ dF, DPhi @ dom["B1"], DPhi @ (dom["B1"] - dom["B0"]))
    Li, Ri = _edge_cross_fields(i, a, b, r, Ei.deriv(), left, right)
    return InternalEdge(Ei, Li, Ri, ca1d, cb1d)


def _edge_cross_fields(i: int, a: Poly, b: Poly, r: Poly, T: Poly, left: tuple[Array, Array, Array, Array],
                       right: tuple[Array, Array, Array, Array]) -> tuple[Poly, Poly]:
    """Cross fields ``L = b Z + l T``, ``R = -a Z + m T`` with ``a l + b m = r``, so that
    ``a L + b R = r T`` holds identically (the kite relation of :func:`_kite_relation`).

    ``l``, ``m`` are linear; ``Z`` is the cubic Hermite polynomial that makes ``L`` meet its end
    data ``left = (L(0), L'(0), L(1), L'(1))``, each (w,). ``R`` then meets ``right`` (the same for
    ``R``) when the corner conditions hold: checked, since a failure would break G1 silently.
    ``T`` is ``E_i'``.

    Raises
    ------
    ToleranceError
        The end data of ``R`` are not met (an internal inconsistency).
    """
    L0, L0d, L1, L1d = left
    R0, R0d, R1, R1d = right
    # l, m linear with a l + b m = r (coefficients of the quadratic identity)
    Amat = np.array([[a.coef[0, 0], 0, b.coef[0, 0], 0],
                     [a.coef[1, 0], a.coef[0, 0], b.coef[1, 0], b.coef[0, 0]],
                     [0, a.coef[1, 0], 0, b.coef[1, 0]]])
    rc = np.zeros(3)
    rc[:r.coef.shape[0]] = r.coef[:3, 0]
    lm = np.linalg.lstsq(Amat, rc, rcond=tolerances.FILL_RCOND)[0]
    ell, emm = scalar_poly(lm[:2]), scalar_poly(lm[2:])
    b0, b0d = b(0.0)[0], b(0.0, 1)[0]
    b1, b1d, ell0, ell1, ell0d = b(1.0)[0], b(1.0, 1)[0], ell(0.0)[0], ell(1.0)[0], ell(0.0, 1)[0]
    Z0 = (L0 - ell0 * T(0.0)) / b0
    Z1 = (L1 - ell1 * T(1.0)) / b1
    Z0d = (L0d - b0d * Z0 - ell0d * T(0.0) - ell0 * T(0.0, 1)) / b0
    Z1d = (L1d - b1d * Z1 - ell(1.0, 1)[0] * T(1.0) - ell1 * T(1.0, 1)) / b1
    Z = Poly.hermite([(0.0, 0, Z0), (0.0, 1, Z0d), (1.0, 0, Z1), (1.0, 1, Z1d)])
    Li, Ri = b * Z + ell * T, -(a * Z) + emm * T
    # self-check: R must meet its end data too (it does when the corner conditions hold)
    scale = max(np.abs(L0).max(), np.abs(L1).max(), 1e-300)
    err = max(np.abs(Ri(0.0) - R0).max(), np.abs(Ri(1.0) - R1).max(), np.abs(Ri(0.0, 1) - R0d).max(),
              np.abs(Ri(1.0, 1) - R1d).max()) / scale
    if err > tolerances.FILL_EDGE_CONSISTENCY_TOL:
        raise ToleranceError(f"internal: the G1 data of internal edge {i} are inconsistent ({err:.2e})")
    return Li, Ri
