"""What a surface is matched to along an edge: the target's jets at the points of the edge.

A match to order ``r`` (G0 to G3, course ch. 4 and 11-2) asks the changed surface to share, at each
point ``P`` of its side, the target's *height function* ``h`` over the target's tangent plane at
``P`` up to order ``r``: with an orthonormal tangent frame ``(e1, e2)`` and the unit normal ``N``,
the target near ``P`` is ``P + x e1 + y e2 + h(x, y) N`` with ``h(0) = 0``, ``grad h(0) = 0``, and
its second and third derivatives ``H2 = D^2 h(0)`` (the second fundamental form) and
``H3 = D^3 h(0)`` are what G2 and G3 need. This module gives them, vectorised over the points:

* :func:`height_jets`: ``H2`` and ``H3`` of any parametric surface from its partials up to order 3,
  by implicit differentiation of ``z(s, t) = h(x(s, t), y(s, t))`` (no Python loop per point);
* :class:`MatchTarget`: a target given by samples along a curve (a trimmed face's edge, measured
  data): points, unit normals and, for G2, the normal curvatures across the curve;
* the private targets :class:`SurfaceSide` (a side of a B-spline surface) and :class:`SampledCurve`
  (a :class:`MatchTarget`, or the average of two surfaces' jets), both answering :meth:`at`: the
  target's jets at the feet of given points on its edge.

References
----------
R. Bartels, course notes C25 (SIGGRAPH 1991), ch. 4 (direct manipulation of position, tangent and
curvature); D. Warn, ibid. ch. 9-11 (continuity across a boundary); M. do Carmo, *Differential
Geometry of Curves and Surfaces* (1976), §3-3 (the second fundamental form as the Hessian of the
height function).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from .. import _validate as V
from ..errors import InvalidGeometryError
from ..kernel.curve import BSplineCurve
from ..kernel.surface import BSplineSurface
from ..topology.nsided_loops import closest_parameters

__all__ = ["MatchTarget", "height_jets"]

Array = NDArray[np.float64]


def _unit(v: Array) -> Array:
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    return v / np.where(n > 0, n, 1.0)


def height_jets(D: Array, N: Array, E: Array) -> tuple[Array, Array | None]:
    """Second and third derivatives of a surface's height function over a tangent frame.

    Parameters
    ----------
    D : ndarray, shape (m, k, k, 3)
        Partials ``D[:, a, b] = d^{a+b} S / ds^a dt^b`` at m points, ``k >= 3`` (``k >= 4`` for
        the third derivatives).
    N : ndarray, shape (m, 3)
        Unit normals (either orientation: ``h`` is measured along ``N``).
    E : ndarray, shape (m, 2, 3)
        Orthonormal tangent frames ``(e1, e2)`` perpendicular to ``N``.

    Returns
    -------
    H2 : ndarray, shape (m, 2, 2)
        ``h_ij``: the second fundamental form in the frame (``H2[:, i, i]`` is the normal
        curvature along ``e_i``, positive where the surface bends towards ``N``).
    H3 : ndarray, shape (m, 2, 2, 2) or None
        ``h_ijk`` (``None`` when ``k < 4``).

    Notes
    -----
    With ``x^i = e_i . (S - P)``, ``z = N . (S - P)`` and ``J[i, a] = e_i . S_a`` the chain rule
    gives ``z_ab = h_ij x^i_a x^j_b`` and ``z_abc = h_ijk x^i_a x^j_b x^k_c + h_ij (x^i_ab x^j_c
    + x^i_ac x^j_b + x^i_bc x^j_a)`` (the terms in ``h_i`` vanish at ``P``), solved for ``h`` with
    ``J^-1``.
    """
    k = D.shape[1]
    S1 = np.stack([D[:, 1, 0], D[:, 0, 1]], axis=1)  # (m, 2, 3): S_s, S_t
    J = np.einsum("mic,mac->mia", E, S1)
    Ji = np.linalg.inv(J)  # Ji[m, a, i]
    S2 = np.empty(D.shape[:1] + (2, 2, 3))
    S2[:, 0, 0], S2[:, 0, 1], S2[:, 1, 0], S2[:, 1, 1] = D[:, 2, 0], D[:, 1, 1], D[:, 1, 1], D[:, 0, 2]
    Z2 = np.einsum("mc,mabc->mab", N, S2)
    H2 = np.einsum("mai,mab,mbj->mij", Ji, Z2, Ji)
    if k < 4:
        return H2, None
    S3 = np.empty(D.shape[:1] + (2, 2, 2, 3))
    for a in range(2):
        for b in range(2):
            for c in range(2):
                S3[:, a, b, c] = D[:, 3 - (a + b + c), a + b + c]
    Z3 = np.einsum("md,mabcd->mabc", N, S3)
    X2 = np.einsum("mid,mabd->miab", E, S2)  # x^i_ab
    T = np.einsum("mij,miab,mjc->mabc", H2, X2, J)  # h_ij x^i_ab x^j_c
    W = Z3 - (T + T.transpose(0, 1, 3, 2) + T.transpose(0, 2, 3, 1))
    H3 = np.einsum("mabc,mai,mbj,mck->mijk", W, Ji, Ji, Ji)
    return H2, H3


@dataclass
class Jets:
    """The target at m points of its edge (the feet of the points asked about).

    ``P`` (m, 3) points; ``N`` (m, 3) unit normals; ``E`` (m, 2, 3) the frame ``(e1, e2)`` with
    ``e1`` along the edge and ``e2 = N x e1``; ``H2`` (m, 2, 2) and ``H3`` (m, 2, 2, 2) the height
    function's derivatives in that frame (``None`` where the target does not carry them);
    ``inward`` (m, 3) the unit direction into the target across its edge (``None`` for targets given
    by samples, which have no inside).
    """

    P: Array
    N: Array
    E: Array
    H2: Array | None
    H3: Array | None
    inward: Array | None = None


class SurfaceSide:
    """Side ``s = s_min`` of a clamped B-spline surface (the canonical side ``'u0'``) as a target."""

    def __init__(self, surface: BSplineSurface) -> None:
        self.surface = surface
        p, q = surface.degree
        U, Vk = surface.knots
        self.s0 = float(U[p])
        w = None if surface.weights is None else surface.weights[0]
        self.curve = BSplineCurve(q, Vk, surface.control_points[0], w)

    def feet(self, points: Array, t0: Array | None = None, samples: int = 401) -> tuple[Array, Array]:
        """Parameters on the side of the points nearest to ``points`` (m, 3) and the distances:
        Newton's iteration from ``t0``, or from the nearest of ``samples`` uniform parameters."""
        return closest_parameters(self.curve, points, samples=samples, t0=t0)

    def params(self, S: BSplineSurface, v: Array) -> Array:
        """The side's parameters paired with side u0 of ``S`` at ``v``: mapped linearly end to end,
        in the direction that pairs the nearer ends."""
        (a, b), (lo, hi) = S.domain[1], self.curve.domain
        ends = S.evaluate(np.full(2, S.knots[0][S.degree[0]]), np.array([a, b]))
        mine = self.curve.evaluate(np.array([lo, hi]))
        same = np.linalg.norm(ends - mine, axis=1).sum() <= np.linalg.norm(ends - mine[::-1], axis=1).sum()
        x = (v - a) / (b - a)
        return lo + (hi - lo) * (x if same else 1.0 - x)

    def corresponding(self, S: BSplineSurface, v: Array) -> Jets:
        """The target's jets at the points that correspond to side u0 of ``S`` at ``v``
        (:meth:`params`)."""
        return self._jets(self.params(S, v))

    def at_near(self, points: Array, S: BSplineSurface, v: Array) -> Jets:
        """:meth:`at`, the feet found by Newton's iteration from the parameters paired with ``v``."""
        return self._jets(self.feet(points, self.params(S, v))[0])

    def to_side(self, S: BSplineSurface, t: Array) -> Array:
        """The parameters of side u0 of ``S`` that :meth:`corresponding` pairs with ``t``."""
        (a, b), (lo, hi) = S.domain[1], self.curve.domain
        ends = S.evaluate(np.full(2, S.knots[0][S.degree[0]]), np.array([a, b]))
        mine = self.curve.evaluate(np.array([lo, hi]))
        same = np.linalg.norm(ends - mine, axis=1).sum() <= np.linalg.norm(ends - mine[::-1], axis=1).sum()
        x = (t - lo) / (hi - lo)
        return a + (b - a) * (x if same else 1.0 - x)

    def at(self, points: Array) -> Jets:
        """The target's jets at the feet of ``points`` on its edge."""
        return self._jets(self.feet(points)[0])

    def _jets(self, t: Array) -> Jets:
        D = self.surface.derivatives(np.full_like(t, self.s0), t, 3)
        Ss, St = D[:, 1, 0], D[:, 0, 1]
        N = _unit(np.cross(Ss, St))
        e1 = _unit(St)
        e2 = np.cross(N, e1)
        E = np.stack([e1, e2], axis=1)
        H2, H3 = height_jets(D, N, E)
        inward = e2 * np.sign(np.einsum("mc,mc->m", e2, Ss))[:, None]
        return Jets(D[:, 0, 0], N, E, H2, H3, inward)


@dataclass(frozen=True)
class MatchTarget:
    """A match target given by samples along a curve (a trimmed face's edge, or measured data).

    Parameters
    ----------
    points : array_like, shape (m, 3)
        Points along the curve in order, ``m >= 2``; consecutive points distinct. The curve between
        them is the cubic interpolant over chord length (linear for two points, quadratic for three).
    normals : array_like, shape (m, 3)
        The target's normals there (normalised here; their orientation sets the sign of
        ``cross_curvatures``).
    cross_curvatures : array_like, shape (m,), optional
        The target's normal curvature across the curve, in the direction ``b = n x t`` (``t`` the
        curve's tangent in the order of the points), positive where the target bends towards
        ``n``. Needed for G2; G3 needs a surface target.
    """

    points: Array
    normals: Array
    cross_curvatures: Array | None = None
    _curve: object = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        P = V.as_finite_array(self.points, "MatchTarget.points")
        if P.ndim != 2 or P.shape[1] != 3 or P.shape[0] < 2:
            raise InvalidGeometryError(f"MatchTarget.points: expected shape (m >= 2, 3), got {P.shape}")
        N = V.as_finite_array(self.normals, "MatchTarget.normals")
        if N.shape != P.shape:
            raise InvalidGeometryError(f"MatchTarget.normals: expected shape {P.shape}, got {N.shape}")
        nn = np.linalg.norm(N, axis=1)
        if np.any(nn <= 1e-12):
            raise InvalidGeometryError(f"MatchTarget.normals: normal {int(np.argmin(nn))} is zero")
        chords = np.linalg.norm(np.diff(P, axis=0), axis=1)
        if np.any(chords <= 1e-12 * max(float(np.ptp(P, axis=0).max()), 1e-300)):
            raise InvalidGeometryError(f"MatchTarget.points: points {int(np.argmin(chords))} and "
                                       f"{int(np.argmin(chords)) + 1} coincide")
        K = None
        if self.cross_curvatures is not None:
            K = V.as_finite_array(self.cross_curvatures, "MatchTarget.cross_curvatures")
            if K.shape != (P.shape[0],):
                raise InvalidGeometryError(f"MatchTarget.cross_curvatures: expected shape ({P.shape[0]},), got {K.shape}")
        object.__setattr__(self, "points", V.readonly(P))
        object.__setattr__(self, "normals", V.readonly(N / nn[:, None]))
        object.__setattr__(self, "cross_curvatures", None if K is None else V.readonly(K))
        c = np.concatenate([[0.0], np.cumsum(chords)])
        object.__setattr__(self, "_curve", SampledCurve(c / c[-1], P, self.normals, K))


class SampledCurve:
    """A target known at samples ``c`` (increasing in [0, 1]) along a curve: interpolated points,
    normals and either cross curvatures (a :class:`MatchTarget`) or full ``H2`` / ``H3`` in the frame
    ``(t, n x t)`` of the interpolated curve (the average of two surfaces)."""

    def __init__(self, c: Array, P: Array, N: Array, cross: Array | None = None, H2: Array | None = None,
                 H3: Array | None = None) -> None:
        # imported here: scipy.interpolate and scipy.spatial cost ~0.3 s at the start of every
        # process that imports the package (every command's worker), matching or not
        from scipy.interpolate import make_interp_spline
        from scipy.spatial import cKDTree

        k = min(3, len(c) - 1)
        self.k = k
        self.curve = make_interp_spline(c, P, k=k)
        self.normal = make_interp_spline(c, N, k=k)
        self.cross = None if cross is None else make_interp_spline(c, cross, k=k)
        self.h2 = None if H2 is None else make_interp_spline(c, H2.reshape(len(c), -1), k=k)
        self.h3 = None if H3 is None else make_interp_spline(c, H3.reshape(len(c), -1), k=k)
        self.dense_c = np.linspace(0.0, 1.0, 16 * len(c) + 1)
        self.dense = self.curve(self.dense_c)
        self._tree = cKDTree(self.dense)
        self._d1 = self.curve.derivative(1)
        self._d2 = self.curve.derivative(2) if k > 1 else None

    def feet(self, points: Array) -> tuple[Array, Array]:
        """The curve's parameters nearest to ``points`` (m, 3), and the distances: Newton's
        iteration from the nearest of the dense samples (found by a k-d tree)."""
        c = self.dense_c[self._tree.query(points)[1]]
        d1, d2c = self._d1, self._d2
        for _ in range(12):
            r = self.curve(c) - points
            g1 = d1(c)
            h = np.einsum("md,md->m", g1, g1) + (np.einsum("md,md->m", r, d2c(c)) if d2c is not None else 0.0)
            step = np.where(h > 0, np.einsum("md,md->m", r, g1) / np.where(h > 0, h, 1.0), 0.0)
            c_new = np.clip(c - step, 0.0, 1.0)
            if np.max(np.abs(c_new - c)) <= 1e-15:
                c = c_new
                break
            c = c_new
        return c, np.linalg.norm(self.curve(c) - points, axis=1)

    def at(self, points: Array) -> Jets:
        c, _ = self.feet(points)
        P = self.curve(c)
        g1 = self._d1(c)
        n_raw = self.normal(c)
        N = _unit(n_raw)
        t = _unit(g1 - np.einsum("md,md->m", g1, N)[:, None] * N)
        b = np.cross(N, t)
        E = np.stack([t, b], axis=1)
        H2 = H3 = None
        if self.h2 is not None:
            H2 = self.h2(c).reshape(-1, 2, 2)
            H3 = None if self.h3 is None else self.h3(c).reshape(-1, 2, 2, 2)
        elif self.cross is not None:
            speed2 = np.einsum("md,md->m", g1, g1)
            g2 = self._d2(c) if self._d2 is not None else np.zeros_like(g1)
            k_t = np.einsum("md,md->m", N, g2) / speed2
            dn = self.normal.derivative(1)(c)
            dN = (dn - np.einsum("md,md->m", dn, N)[:, None] * N) / np.linalg.norm(n_raw, axis=1)[:, None]
            tau = -np.einsum("md,md->m", dN, b) / np.sqrt(speed2)
            H2 = np.empty((len(c), 2, 2))
            H2[:, 0, 0], H2[:, 0, 1], H2[:, 1, 0], H2[:, 1, 1] = k_t, tau, tau, self.cross(c)
        return Jets(P, N, E, H2, H3, None)

    def corresponding(self, S: BSplineSurface, v: Array) -> Jets:
        """The target's jets at the feet of the points of side u0 of ``S`` at ``v``."""
        return self.at(S.evaluate(np.full_like(v, S.knots[0][S.degree[0]]), v))
