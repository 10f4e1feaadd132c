"""Filling an n-sided hole with G1 continuity (course §8-3, the n-sided hole problem).

Given ``n >= 3`` boundary curves forming a closed loop (the free edges of the faces around a hole)
and, along each, the neighbour face's cross-boundary derivative, :func:`fill_hole` builds ``n``
tensor-product (rational) B-spline patches that

* interpolate every boundary curve exactly (the boundary row of poles *is* the curve, refined and
  degree-raised: round-off only), multi-span and rational curves included;
* are G1 to the neighbour along the whole boundary, by a polynomial identity (below), not at samples;
* are G1 to each other along the internal edges, again by a polynomial identity, and share one
  tangent plane at the centre.

The choice: a central split into four-sided patches
---------------------------------------------------
A single S-patch (Loop & DeRose 1989) has Bézier sides of one degree, while CAD boundaries are
multi-span, often rational B-splines. Splitting the sides at their knots into extra (straight)
sides makes the S-patch singular at every straight corner (its tangent plane there is spanned by
two collinear edge tangents) and the number of control points explodes (``C(d+N-1, N-1)`` for ``N``
spans). We therefore decompose the hole, as the course suggests for n-sided regions (§8-3, the
Sabin/Gregory "central split" into n quadrilaterals; also the NURBS Book §10 on G1 joins): the
centre ``C`` is joined to a point ``m_i`` on every side, giving ``n`` four-sided patches; patch
``i`` covers hole corner ``V_i`` and is bounded by the first part of side ``i``, the last part of
side ``i-1`` and the internal edges ``E_i`` (``m_i -> C``) and ``E_{i-1}``. A four-sided patch is
a four-sided S-patch (a tensor product; for one span a Bézier patch of bidegree ``(d, d)``), and a
tensor product carries a multi-span rational boundary exactly: its u-knots are the side's knots.

Boundary G1 by construction. Work in homogeneous coordinates (``R^4`` for rational data, ``R^3``
otherwise). Along side ``i`` with boundary ``B(s)`` and neighbour cross-derivative ``X(s)`` the
patch's cross-boundary derivative is set to::

    F_v(u, 0) = sum_f c_f(u) f(s(u)),   f in {X, B', B (rational only)}

with cubic polynomials ``c_f``. Its poles are computed exactly in the patch's knot space (the
product of a spline and a polynomial is a spline on the same knots, multiplicity raised). Then
``span(F, F_u, F_v) = span(B, B', X)`` identically in ``u``: the projected tangent planes coincide
at every point of the boundary (provided ``c_X != 0``; it is checked to stay negative, pointing into
the hole). This is the classical ribbon (G1 "transversal vector field") construction.

Internal G1 by construction. Along ``E_i`` the two cross derivatives ``L`` (patch ``i``) and
``R`` (patch ``i+1``) satisfy ``a(t) L + b(t) R = r(t) E'(t)`` with ``a, b`` linear, ``r``
quadratic, taken from a *domain picture*: a regular n-gon split into kites, whose bilinear
parametrisations satisfy the same relation exactly. ``L = b Z + l E'``, ``R = -a Z + m E'`` with
``a l + b m = r`` make it a polynomial identity. Corner compatibility (the twists at ``V_i``,
``m_i`` and ``C``) fixes the end derivatives of the ``c_f``; the centre data come from one affine
map of the domain, so the ``n`` twists there agree. The remaining interior poles minimise the
thin-plate energy ``int |F_uu|^2 + 2|F_uv|^2 + |F_vv|^2``.

Flat corners, round holes, slivers. A corner where the two sides are tangent (180 degrees, within
``tolerances.FILL_MIN_CORNER_ANGLE``) gets a corner patch with a degenerate corner: the ribbon's
cross-field coefficient is 0 there and grows linearly (the twist is solved for the rest), so the
normal tends to the neighbour's and G1 holds up to that one point. This lets a loop of one side (a
round hole) or two (a slot end) be cut at arc-length points into four sides (S-patch-style central
split of a smooth loop). Where the midpoints' mean lies outside the hole (a crescent, a tapering
sliver), the centre is moved to the preimage of the domain's centre under a harmonic map of the hole
onto the domain (the point farthest from the boundary if that map cannot be built) and internal
edges that would leave the hole leave their side at 30 degrees instead. A fill that folds
(:func:`count_folds`, :attr:`FillQuality.folds`: a long curved hole, a sliver) is rebuilt on the
harmonic layout (:func:`_harmonic_layout`): centre, internal-edge directions and lengths at the
midpoints, and the centre's tangent map all from that one-to-one map, so the internal edges follow
the hole instead of cutting across it; the fill with fewer folds is kept. Very long thin curved holes
(a sector whose middle arc is more than ~12 times its width) still fold near their internal edges,
and :func:`measure_fill` says so.

Known limits (reported, never hidden): at a hole corner the twist is over-determined when the two
neighbours are only G1 (not G2) to each other there (Gregory's twist incompatibility): its normal
component is then averaged and G1 holds up to :attr:`HoleFill.twist_mismatch` near that corner.
A side with a C0 knot (a kink, no tangent) is refused; split the side there. A reflex corner
(interior angle above 180 degrees) would fold the corner patch and is refused, as is a cusp and a
loop that crosses or touches itself.

References
----------
Course C25 §8-3 (n-sided holes), §8-5 (Sabin nets). C. Loop, T. DeRose, "A multisided
generalization of Bézier surfaces", ACM ToG 8 (1989). J. Gregory, "N-sided surface patches" (1986).
L. Piegl, W. Tiller, The NURBS Book, 2nd ed., 1997, A2.3 (derivatives), §10 (G1 joins).
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy import sparse
from scipy.linalg import lu_factor, lu_solve
from scipy.sparse.linalg import splu

from .. import tolerances
from ..errors import InvalidGeometryError, ToleranceError
from ..kernel.basis import basis_matrix, greville
from ..kernel.curve import BSplineCurve
from ..kernel.surface import BSplineSurface
from ..kernel.trimmed import TrimmedSurface
from .nsided_loops import (
    arc_length_parameters,
    check_simple_loop,
    closest_parameters,
    harmonic_centre,
    harmonic_picture,
    inner_point,
    turns_inward,
)

__all__ = [
    "HoleSide",
    "HoleFill",
    "FillQuality",
    "side_from_surface",
    "closest_parameters",
    "fill_hole",
    "measure_fill",
    "count_folds",
    "fill_folds",
]

Array = NDArray[np.float64]
# Tolerances and limits (read at call time from :mod:`occsurf.algorithms.tolerances`): FILL_RCOND,
# FILL_NULL_RTOL (the small least-squares solves), FILL_CLOSURE_TOL, FILL_MIN_CORNER_ANGLE,
# FILL_CORNER_PLANE_TOL (the checks of the hole), FILL_REPRESENT_TOL (the exact representations),
# FILL_TWIST_TOL, FILL_CORNER_SPAN (incompatible twists) and FILL_MAX_SIDES.


# ============================================================================================ data
@dataclass(frozen=True)
class HoleSide:
    """One side of a hole: the boundary curve and the neighbour's cross-boundary derivative.

    Parameters
    ----------
    curve : BSplineCurve
        The boundary, 3-D, oriented along the loop (side ``i`` ends where side ``i+1`` starts).
    cross : BSplineCurve
        Non-rational, on the same domain as ``curve``: the derivative of the neighbour surface
        across the boundary, pointing *into the neighbour* (away from the hole). For a polynomial
        ``curve`` it is 3-D; for a rational one it is the 4-D derivative of the neighbour's
        homogeneous surface ``(w x, w y, w z, w)`` (what :func:`side_from_surface` returns).
    """

    curve: BSplineCurve
    cross: BSplineCurve


@dataclass(frozen=True)
class HoleFill:
    """The result of :func:`fill_hole`.

    Attributes
    ----------
    patches : list of BSplineSurface
        ``n`` four-sided patches; patch ``i`` has corner ``(0, 0)`` at the start of side ``i``, its
        ``v = 0`` edge on side ``i`` (parameters ``[0, split[i]]``), its ``u = 0`` edge on side
        ``i-1`` (``[split[i-1], 1]`` reversed), its ``u = 1`` edge on internal edge ``i`` and its
        ``(1, 1)`` corner at the centre.
    sides : list of HoleSide
        The input sides reparametrised to ``[0, 1]``.
    split : ndarray, shape (n,)
        Parameter on each side where the internal edge starts (1/2 unless a knot of low continuity
        sits there).
    center : ndarray, shape (3,)
    corner_residual : ndarray, shape (n,)
        At each hole corner: how far (relative) the adjacent side's tangent lies out of the
        neighbour's tangent plane. Zero when the neighbours are G1 to each other at the corner.
    twist_mismatch : ndarray, shape (n,)
        At each hole corner: relative size of the twist incompatibility (0 when the neighbours are
        G2-compatible there; see the module notes).
    flat : ndarray of bool, shape (n,)
        Hole corners where the two sides meet tangentially (within
        ``tolerances.FILL_MIN_CORNER_ANGLE`` of 180 degrees): the corner patch has a degenerate
        (180 degree) corner there, its normal defined by continuity (see :func:`fill_hole`).
    source : ndarray, shape (n, 3)
        Per side of the fill: ``(input side, t0, t1)``, the part ``[t0, t1]`` (on ``[0, 1]``) of the
        input side it is. The identity unless the input had fewer than 3 sides and was split
        (:func:`fill_hole`).
    """

    patches: list[BSplineSurface]
    sides: list[HoleSide]
    split: Array
    center: Array
    corner_residual: Array
    twist_mismatch: Array
    size: float = field(default=1.0)

    method: str = field(default="quads")
    flat: Array = field(default_factory=lambda: np.zeros(0, bool))
    source: Array = field(default_factory=lambda: np.zeros((0, 3)))

    def locate_input(self, side: int, points: Array) -> tuple[NDArray[np.intp], Array, Array, Array]:
        """:meth:`locate` for points of *input* side ``side`` (the same unless the loop was split):
        each point goes to the nearest of the fill sides that side was split into."""
        rows = np.flatnonzero(self.source[:, 0] == side) if len(self.source) else np.array([side])
        best = self.locate(int(rows[0]), points)
        for r in rows[1:]:
            cand = self.locate(int(r), points)
            take = cand[3] < best[3]
            best = tuple(np.where(take, c, b) for c, b in zip(cand, best))  # type: ignore[assignment]
        return best[0].astype(np.intp), best[1], best[2], best[3]

    def locate(self, side: int, points: Array) -> tuple[NDArray[np.intp], Array, Array, Array]:
        """Which patch, at which ``(u, v)``, carries the points ``(m, 3)`` of side ``side``.

        The side parameter of each point comes from :func:`closest_parameters` (vectorised); patch
        ``side`` covers ``[0, split]`` of the side on its ``v = 0`` edge, patch ``side + 1`` the rest
        on its ``u = 0`` edge (reversed).

        Returns
        -------
        patch : ndarray of intp, shape (m,)
        u, v : ndarray, shape (m,)
        distance : ndarray, shape (m,)
            Distance of each point from the side curve (the caller judges it).
        """
        n = len(self.patches)
        s, dist = closest_parameters(self.sides[side].curve, points)
        sp = float(self.split[side])
        first = s <= sp
        patch = np.where(first, side, (side + 1) % n)
        u = np.where(first, s / sp, 0.0)
        v = np.where(first, 0.0, (1.0 - s) / (1.0 - sp))
        return patch.astype(np.intp), u, v, dist


@dataclass(frozen=True)
class FillQuality:
    """Dense measurements of a fill (:func:`measure_fill`).

    Attributes
    ----------
    boundary_gap : ndarray, shape (n,)
        Largest distance between the fill and side ``i`` (model units).
    boundary_angle : ndarray, shape (n,)
        Largest angle (degrees) between the fill's and the neighbour's tangent planes along side ``i``.
    internal_gap, internal_angle : ndarray, shape (n,)
        The same between patches ``i`` and ``i+1`` along internal edge ``i``.
    center_angle : float
        Largest angle (degrees) between the patches' normals at the centre.
    folds : ndarray of intp, shape (n,)
        Per patch, the neighbouring pairs of a 41 x 41 parameter grid whose normals ``S_u x S_v``
        point in opposite directions: a fold (the patch turning back over itself, as the central
        split does on long curved holes such as a crescent or a helical strip). 0 for a sound fill.
    """

    boundary_gap: Array
    boundary_angle: Array
    internal_gap: Array
    internal_angle: Array
    center_angle: float
    folds: NDArray[np.intp] = field(default_factory=lambda: np.zeros(0, np.intp))


# ====================================================================================== helpers
def _mult_map(knots: Array, degree: int) -> dict[float, int]:
    """Interior knots (strictly inside the domain) -> multiplicity."""
    lo, hi = knots[degree], knots[-degree - 1]
    eps = tolerances.FILL_KNOT_END_TOL * (hi - lo)  # a knot within round-off of an end is that end (no sliver span)
    vals, counts = np.unique(knots[(knots > lo + eps) & (knots < hi - eps)], return_counts=True)
    return {float(v): int(c) for v, c in zip(vals, counts)}


@functools.lru_cache(maxsize=256)
def _collocation(degree: int, knots_key: bytes) -> tuple[Array, Any, Array, Array]:
    """Greville points, LU factors of the collocation matrix, check points and their basis matrix
    of the spline space ``(degree, knots)``; cached (a fill asks for the same few spaces many times)."""
    knots = np.frombuffer(knots_key)
    n = len(knots) - degree - 1
    x = greville(knots, degree)
    lu = lu_factor(basis_matrix(knots, degree, n, x)[0])
    xm = np.r_[0.5 * (x[:-1] + x[1:]), knots[degree] + 0.37 * (x[1] - x[0])]
    Nm = basis_matrix(knots, degree, n, xm)[0]
    return x, lu, xm, Nm


def _represent(fn: Callable[[Array], Array], degree: int, knots: Array) -> Array:
    """Poles of the spline of ``(degree, knots)`` equal to ``fn`` (which must lie in that space).

    Collocation at the Greville abscissae; verified at the points between them.
    """
    x, lu, xm, Nm = _collocation(int(degree), np.ascontiguousarray(knots, float).tobytes())
    Y = fn(np.r_[x, xm])
    Y, Ym = Y[:len(x)], Y[len(x):]
    Q = lu_solve(lu, Y)
    scale = max(float(np.abs(Y).max()), float(np.abs(Ym).max()), 1e-300)
    err = float(np.abs(Nm @ Q - Ym).max()) / scale
    if err > tolerances.FILL_REPRESENT_TOL:
        raise ToleranceError(f"internal: a ribbon is not exactly representable (relative error {err:.2e}); "
                             "the side's knots or continuity are inconsistent")
    return Q


class _Poly:
    """A vector polynomial in monomial form, ``coef`` shape (deg+1, w)."""

    def __init__(self, coef: Array) -> None:
        self.coef = np.asarray(coef, float)

    @classmethod
    def hermite(cls, conds: Sequence[tuple[float, int, Array]]) -> _Poly:
        """The polynomial of degree ``len(conds) - 1`` with ``d^k p(t) = value`` for each condition."""
        m = len(conds)
        A = np.zeros((m, m))
        Y = np.array([np.asarray(c[2], float) for c in conds])
        for row, (t, k, _) in enumerate(conds):
            for c in range(k, m):
                A[row, c] = np.prod(np.arange(c - k + 1, c + 1)) * t ** (c - k)
        return cls(np.linalg.solve(A, Y.reshape(m, -1)))

    def __call__(self, t: Array, k: int = 0) -> Array:
        t = np.asarray(t, float)
        out = np.zeros(t.shape + self.coef.shape[1:])
        for c in range(k, self.coef.shape[0]):
            out += np.multiply.outer(np.prod(np.arange(c - k + 1, c + 1)) * t ** (c - k), self.coef[c])
        return out

    def __mul__(self, other: _Poly) -> _Poly:
        """Scalar polynomial (w = 1) times vector polynomial."""
        a, b = self.coef, other.coef
        out = np.zeros((a.shape[0] + b.shape[0] - 1, max(a.shape[1], b.shape[1])))
        for i in range(a.shape[0]):
            out[i:i + b.shape[0]] += a[i] * b
        return _Poly(out)

    def __add__(self, other: _Poly) -> _Poly:
        a, b = self.coef, other.coef
        out = np.zeros((max(a.shape[0], b.shape[0]), a.shape[1]))
        out[:a.shape[0]] += a
        out[:b.shape[0]] += b
        return _Poly(out)

    def __neg__(self) -> _Poly:
        return _Poly(-self.coef)

    def deriv(self) -> _Poly:
        c = self.coef
        if c.shape[0] == 1:
            return _Poly(np.zeros_like(c))
        return _Poly(c[1:] * np.arange(1, c.shape[0])[:, None])


def _scalar_poly(coefs: Sequence[float]) -> _Poly:
    return _Poly(np.asarray(coefs, float)[:, None])


class _Side:
    """A side in working coordinates: boundary ``B`` and cross field ``X`` on ``[0, 1]``."""

    def __init__(self, B: BSplineCurve, X: BSplineCurve, rational: bool) -> None:
        self.B, self.X, self.rational = B, X, rational
        self.nf = 3 if rational else 2

    def fields(self, s: Array) -> tuple[Array, Array]:
        """Fields ``[X, B', (B)]`` and their s-derivatives at ``s``: each (m, nf, w)."""
        s = np.atleast_1d(np.asarray(s, float))
        DB = self.B.derivatives(s, 2)
        DX = self.X.derivatives(s, 1)
        if self.rational:
            F = np.stack([DX[:, 0], DB[:, 1], DB[:, 0]], 1)
            dF = np.stack([DX[:, 1], DB[:, 2], DB[:, 1]], 1)
        else:
            F = np.stack([DX[:, 0], DB[:, 1]], 1)
            dF = np.stack([DX[:, 1], DB[:, 2]], 1)
        return F, dF

    def continuity(self) -> dict[float, int]:
        """Interior knot -> continuity order of the fields (B' and X) there."""
        out: dict[float, int] = {}
        for k, m in _mult_map(self.B.knots, self.B.degree).items():
            out[k] = min(out.get(k, 99), self.B.degree - 1 - m)
        for k, m in _mult_map(self.X.knots, self.X.degree).items():
            out[k] = min(out.get(k, 99), self.X.degree - m)
        return out

    @property
    def degree(self) -> int:
        return max(self.B.degree, self.X.degree)


def _cart(h: Array, rational: bool) -> Array:
    return h[..., :3] / h[..., 3:4] if rational else h


def _cart_tangent(h: Array, dh: Array, rational: bool) -> Array:
    """Cartesian derivative of the projected curve from homogeneous point and derivative."""
    if not rational:
        return dh
    return (dh[..., :3] - dh[..., 3:4] * (h[..., :3] / h[..., 3:4])) / h[..., 3:4]


def _unit(v: Array) -> Array:
    return v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-300)


def _angle_deg(a: Array, b: Array) -> Array:
    """Angle between lines (or planes, given normals), in degrees, sign-free."""
    a, b = _unit(a), _unit(b)
    c = np.abs(np.einsum("...i,...i->...", a, b))
    return np.degrees(np.arctan2(np.linalg.norm(np.cross(a, b), axis=-1), c))


# ======================================================================================= inputs
def side_from_surface(surface: BSplineSurface, edge: str, reverse: bool = False) -> HoleSide:
    """The hole side along one iso-boundary of a neighbour surface, with its exact cross derivative.

    Parameters
    ----------
    surface : BSplineSurface
        The neighbour (3-D, polynomial or rational; unclamped knots are clamped first).
    edge : {'u0', 'u1', 'v0', 'v1'}
        Which boundary lies on the hole: ``'v0'`` is the curve ``S(u, v_min)``, etc.
    reverse : bool
        Reverse the curve (and field) so that the side runs the right way around the loop.

    Returns
    -------
    HoleSide
        The boundary curve (the row of poles, bit-exact) and the derivative across it pointing into
        the surface (homogeneous for a rational surface), The NURBS Book eq. (3.17) applied to the
        first two rows of homogeneous poles.
    """
    if not isinstance(surface, BSplineSurface):
        raise InvalidGeometryError(f"surface: expected a BSplineSurface, got {type(surface).__name__}")
    if edge not in ("u0", "u1", "v0", "v1"):
        raise InvalidGeometryError(f"edge: expected one of 'u0', 'u1', 'v0', 'v1', got {edge!r}")
    if surface.dim != 3:
        raise InvalidGeometryError(f"surface: expected 3-D control points, got dimension {surface.dim}")
    s = surface.clamp()
    H = s.homogeneous_points
    if edge[0] == "u":  # make the boundary direction the first index
        H = np.swapaxes(H, 0, 1)
        (q, p), (Kc, Kb) = s.degree, s.knots
    else:
        (p, q), (Kb, Kc) = s.degree, s.knots
    nc = H.shape[1]
    if edge[1] == "0":
        row, cross = H[:, 0], q / (Kc[q + 1] - Kc[1]) * (H[:, 1] - H[:, 0])
    else:
        row, cross = H[:, -1], q / (Kc[nc + q - 1] - Kc[nc - 1]) * (H[:, -2] - H[:, -1])
    if s.is_rational:
        curve = BSplineCurve(p, Kb, row[:, :3] / row[:, 3:], row[:, 3])
    else:
        curve = BSplineCurve(p, Kb, row)
    X = BSplineCurve(p, Kb, cross)
    if reverse:
        curve, X = curve.reverse(), X.reverse()
    return HoleSide(curve, X)


def _working_sides(sides: Sequence[HoleSide]) -> tuple[list[HoleSide], list[_Side], bool, float, Array]:
    """Check the sides of a hole and bring them into working coordinates (step 0 of :func:`fill_hole`).

    Returns
    -------
    unit : list of HoleSide, length n
        The sides clamped and reparametrised to ``[0, 1]``.
    work : list of _Side, length n
        The same about ``origin``, homogeneous (end weights 1) if any side is rational.
    rational : bool
    size : float
        Diagonal of the loop's bounding box.
    origin : ndarray, shape (3,)
        The mean of the hole corners.

    Raises
    ------
    InvalidGeometryError
        Wrong types, dimensions or domains, no side or more than ``tolerances.FILL_MAX_SIDES``
        sides, or a loop that is not closed (``tolerances.FILL_CLOSURE_TOL``).
    """
    if isinstance(sides, (str, bytes)) or not isinstance(sides, Sequence):
        raise InvalidGeometryError(f"sides: expected a sequence of HoleSide, got {type(sides).__name__}")
    n = len(sides)
    max_sides = tolerances.FILL_MAX_SIDES
    if not 1 <= n <= max_sides:
        raise InvalidGeometryError(f"sides: expected 1 to {max_sides} sides, got {n}")
    rational = False
    for k, sd in enumerate(sides):
        if not isinstance(sd, HoleSide):
            raise InvalidGeometryError(f"sides[{k}]: expected a HoleSide, got {type(sd).__name__}")
        if not isinstance(sd.curve, BSplineCurve) or not isinstance(sd.cross, BSplineCurve):
            raise InvalidGeometryError(f"sides[{k}]: curve and cross must be BSplineCurve")
        if sd.curve.dim != 3:
            raise InvalidGeometryError(f"sides[{k}].curve: expected a 3-D curve, got dimension {sd.curve.dim}")
        want = 4 if sd.curve.is_rational else 3
        if sd.cross.is_rational or sd.cross.dim != want:
            raise InvalidGeometryError(
                f"sides[{k}].cross: expected a non-rational {want}-D field "
                f"({'homogeneous, for a rational curve' if want == 4 else 'Cartesian'}), got "
                f"{'rational ' if sd.cross.is_rational else ''}{sd.cross.dim}-D")
        domain_tol = tolerances.FILL_DOMAIN_TOL
        if not np.allclose(sd.curve.domain, sd.cross.domain, rtol=domain_tol, atol=domain_tol):
            raise InvalidGeometryError(f"sides[{k}].cross: domain {sd.cross.domain} differs from the curve's "
                                       f"{sd.curve.domain}")
        rational |= sd.curve.is_rational
    unit = [HoleSide(sd.curve.clamp().reparametrize(0.0, 1.0), sd.cross.clamp().reparametrize(0.0, 1.0))
            for sd in sides]
    ends = np.array([[sd.curve.evaluate(0.0), sd.curve.evaluate(1.0)] for sd in unit])
    size = float(np.linalg.norm(np.ptp(np.concatenate([sd.curve.evaluate(np.linspace(0, 1, 33)) for sd in unit]),
                                       axis=0)))
    size = max(size, 1e-300)
    closure_tol = tolerances.FILL_CLOSURE_TOL
    for k in range(n):
        gap = float(np.linalg.norm(ends[k, 1] - ends[(k + 1) % n, 0]))
        if gap > closure_tol * size:
            raise InvalidGeometryError(
                f"sides: the boundary is not closed: side {k} ends {gap:.3g} away from the start of side "
                f"{(k + 1) % n} (tolerance {closure_tol * size:.3g}); order and orient the sides along the loop")
    check_simple_loop(unit, closure_tol * size)
    # The construction works about the hole's own centre: boundary derivatives and the exactness
    # checks of _represent then lose no digits to the model's distance from the origin (a hole
    # 1e6 away failed the representation check; at 1e4 the G1 angle grew from 4e-11 to 1e-7 deg).
    origin = ends[:, 0].mean(axis=0)
    work: list[_Side] = []
    for sd in unit:
        c = BSplineCurve._trusted(sd.curve.degree, sd.curve.knots, np.asarray(sd.curve.control_points, float) - origin,
                                 sd.curve.weights)
        X = sd.cross
        if c.is_rational:  # the homogeneous cross field (w x, w y, w z, w)' moves by -w' origin
            Xp = np.asarray(X.control_points, float)
            X = BSplineCurve._trusted(X.degree, X.knots, np.c_[Xp[:, :3] - Xp[:, 3:] * origin, Xp[:, 3:]])
        if rational:
            Hc = c.homogeneous_points if c.is_rational else np.c_[c.control_points, np.ones(c.n_poles)]
            Xh = X.control_points if c.is_rational else np.c_[X.control_points, np.zeros(X.n_poles)]
            B = BSplineCurve._trusted(c.degree, c.knots, Hc)
            Xc = BSplineCurve._trusted(X.degree, X.knots, Xh)
            w0, w1 = float(Hc[0, 3]), float(Hc[-1, 3])
            weight_tol = tolerances.FILL_END_WEIGHT_TOL
            if abs(w0 - 1.0) > weight_tol or abs(w1 - 1.0) > weight_tol:
                # lambda(s) B(s) with lambda linear: end weights 1, same projected curve and same span.
                lam = lambda s, w0=w0, w1=w1: (1 - s) / w0 + s / w1  # noqa: E731
                B, Xc = _times_linear(B, lam), _times_linear(Xc, lam)
        else:
            B, Xc = c, X
        work.append(_Side(B, Xc, rational))
    return unit, work, rational, size, origin


def _split_short_loop(unit: list[HoleSide]) -> tuple[list[HoleSide], Array]:
    """A loop of one or two sides (a round hole, a slot end) as four sides (course §8-3: the
    central split needs ``n >= 3``): one side is cut at the quarters of its arc length, each of two
    sides at its half. The cuts are flat corners (180 degrees) of the new loop, which
    :func:`fill_hole` fills with a degenerate corner patch; the neighbour data are only cut, not
    changed. ``unit``: sides on ``[0, 1]``.

    Returns
    -------
    sides : list of HoleSide, length 4
        On ``[0, 1]``.
    source : ndarray, shape (4, 3)
        :attr:`HoleFill.source`.
    """
    cuts = [0.25, 0.5, 0.75] if len(unit) == 1 else [0.5]
    out, src = [], []
    for k, sd in enumerate(unit):
        t = arc_length_parameters(sd.curve, np.array(cuts))
        # a cut that (nearly) meets a knot is moved onto it: a sliver span of 1e-16 left by the cut
        # would make the fill's knot spaces singular
        knots = np.unique(np.r_[sd.curve.knots, sd.cross.knots])
        near = np.abs(knots[None, :] - t[:, None])
        t = np.where(near.min(1) <= tolerances.FILL_CUT_SNAP, knots[near.argmin(1)], t)
        b = np.r_[0.0, t, 1.0]
        for t0, t1 in zip(b[:-1], b[1:]):
            out.append(HoleSide(sd.curve.segment(t0, t1).reparametrize(0.0, 1.0),
                                sd.cross.segment(t0, t1).reparametrize(0.0, 1.0)))
            src.append((k, t0, t1))
    return out, np.array(src, float)


def _times_linear(c: BSplineCurve, lam: Callable[[Array], Array]) -> BSplineCurve:
    """``lam(s) c(s)`` for a linear ``lam``: degree + 1, every knot one more time."""
    p = c.degree
    inner = [k for k, m in _mult_map(c.knots, p).items() for _ in range(m + 1)]
    K = np.r_[np.zeros(p + 2), sorted(inner), np.ones(p + 2)]
    Q = _represent(lambda s: lam(s)[:, None] * c.evaluate(s), p + 1, K)
    return BSplineCurve._trusted(p + 1, K, Q)


# ================================================================================= construction
def _choose_split(side: _Side) -> float:
    """1/2, unless a knot there breaks the continuity of the fields' first derivative."""
    cont = side.continuity()
    bad = sorted(k for k, c in cont.items() if c < 1)
    tol = tolerances.FILL_SPLIT_KNOT_TOL
    if not any(abs(k - 0.5) < tol for k in bad):
        return 0.5
    knots = np.unique(np.r_[0.0, list(cont), 1.0])
    j = int(np.searchsorted(knots, 0.5 - tol))  # knots[j] ~ 0.5
    left, right = 0.5 * (knots[j - 1] + knots[j]), 0.5 * (knots[j] + knots[j + 1])
    return float(left if 0.5 - left <= right - 0.5 else right)


def _half_space(side: _Side, lo: float, hi: float, reverse: bool, degree: int) -> Array:
    """Knot vector (degree ``degree``, on [0, 1]) of the part ``[lo, hi]`` of a side."""
    inner: list[float] = []
    tol = tolerances.FILL_KNOT_END_TOL  # the side is on [0, 1]: absolute is relative
    for k, c in side.continuity().items():
        if lo + tol < k < hi - tol:
            if c < 0:
                raise InvalidGeometryError(
                    f"sides: a side has a C0 knot (no tangent) at parameter {k:.6g}; split the side there")
            x = (hi - k) / (hi - lo) if reverse else (k - lo) / (hi - lo)
            inner += [x] * min(degree, degree - c)
    return np.r_[np.zeros(degree + 1), sorted(inner), np.ones(degree + 1)]


def _kite_relation(v: Array, p: Array, i: int, n: int) -> tuple[_Poly, _Poly, _Poly, dict[str, Array]]:
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
    a, b = _scalar_poly([x[0], x[1] - x[0]]), _scalar_poly([x[2], x[3] - x[2]])
    # r(t) = (a A + b B) . T / |T|^2, quadratic
    A = _Poly(np.array([A0, A1 - A0]))
    Bp = _Poly(np.array([B0, B1 - B0]))
    V = a * A + b * Bp
    r = _Poly((V.coef @ T / (T @ T))[:, None])
    return a, b, r, {"A0": A0, "A1": A1, "B0": B0, "B1": B1, "T": T}


def fill_hole(sides: Sequence[HoleSide]) -> HoleFill:
    """Fill an n-sided hole with n four-sided patches, G1 to the neighbours and to each other.

    Parameters
    ----------
    sides : sequence of HoleSide, length n (1 to ``tolerances.FILL_MAX_SIDES``)
        The hole's boundary in loop order, each with the neighbour's cross derivative
        (:func:`side_from_surface` builds them from neighbour surfaces). One closed side (a round
        hole) is cut at the quarters of its arc length, two sides (a slot end) at their halves
        (:attr:`HoleFill.source` maps the fill's sides back).

    Returns
    -------
    HoleFill
        The patches (rational if any side is) and the corner diagnostics.

    Raises
    ------
    InvalidGeometryError
        No side, a loop that is not closed (``tolerances.FILL_CLOSURE_TOL``), a degenerate cross
        field (``tolerances.FILL_MIN_CORNER_ANGLE``; a neighbour's pole at a corner), neighbours
        meeting at a sharp edge at a corner
        (``tolerances.FILL_CORNER_PLANE_TOL``), a kink inside a side, or a fill that would turn back
        over the neighbour (cross field pointing into the hole).

    Notes
    -----
    Flat corners (the sides tangent there, within ``tolerances.FILL_MIN_CORNER_ANGLE``: the cuts of
    a round hole, or sides a caller did not merge) get a corner patch whose corner is degenerate
    (its two boundary tangents opposite): the ribbon's cross-field coefficient is 0 there and grows
    linearly into the side (its derivative is set to the midpoint's value, the twist solved for the
    rest), so the patch's normal tends to the neighbour's as the corner is approached and G1 holds
    along the whole side; OCC's LocalAnalysis reports no normal at that one point.

    Construction in the module docstring (course §8-3; central split with G1 ribbons). The steps:
    the sides in working coordinates (:func:`_working_sides`), where each is split
    (:func:`_choose_split`), the kite domain picture (:func:`_domain_picture`), the ribbon
    coefficients at the hole corners (:func:`_corner_analysis`), the side midpoints and the centre
    (:func:`_midpoints`, :func:`_centre`), the centre's tangent map (:func:`_centre_map`), the
    internal edges with their cross fields (:func:`_internal_edge`) and, last, one patch per hole
    corner (:func:`_corner_patch`).
    """
    unit, S, rational, size, origin = _working_sides(sides)
    source = np.array([(k, 0.0, 1.0) for k in range(len(unit))])
    if len(unit) < 3:  # a round hole or a slot end: four sides meeting at flat corners
        split, source = _split_short_loop(unit)
        unit, S, rational, size, origin = _working_sides(split)
    n = len(S)
    sig = np.array([_choose_split(sd) for sd in S])
    vdom, pdom = _domain_picture(sig)
    mid = _midpoints(S, sig, rational)
    loop = np.concatenate([_cart(sd.B.evaluate(np.linspace(0.0, 1.0, 49)[:-1]), rational) for sd in S])
    hb = _harmonic_boundary(S, sig, vdom, pdom, rational)

    def build(C: Array, c1: Array, DPhi: Array) -> tuple[list[BSplineSurface], _CornerFit, int]:
        corners = _corner_analysis(S, sig, rational, c1)
        _check_inward(corners, c1)
        Ch = np.r_[C, 1.0] if rational else C
        edges = [_internal_edge(i, vdom, pdom, sig[i], mid, c1[i], Ch, DPhi) for i in range(n)]
        patches = [_corner_patch(i, S, sig, corners, c1, edges, rational, origin) for i in range(n)]
        return patches, corners, sum(count_folds(p) for p in patches)

    # The plain layout first (midpoints' mean; a convex hole keeps its fill), then, if it folds or is
    # refused, the harmonic layout (a long curved hole, a sliver); the fill with fewer folds is kept.
    C, c1 = _centre(mid, rational, loop, hb)
    err: InvalidGeometryError | None = None
    try:
        best = (*build(C, c1, _centre_map(C, mid.cart, pdom, rational)), C)
    except InvalidGeometryError as e:
        best, err = None, e
    if best is None or best[2] > 0:
        layout = _harmonic_layout(mid, rational, hb, pdom)
        if layout is not None:
            try:
                cand = (*build(*layout), layout[0])
                if best is None or cand[2] < best[2]:
                    best = cand
            except InvalidGeometryError:
                pass
    if best is None:
        raise err if err is not None else InvalidGeometryError("sides: no layout of the central split could be built")
    patches, corners, _, C = best
    return HoleFill(patches, unit, sig, C + origin, corners.residual, corners.twist, size, flat=corners.flat,
                    source=source)


# ---- step 1: the domain picture
def _harmonic_boundary(S: list[_Side], sig: Array, vdom: Array, pdom: Array, rational: bool,
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
            P = _cart(sd.B.evaluate(np.r_[t, hi]), rational)
            cum = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(P, axis=0), axis=1))]
            f = (cum / max(cum[-1], 1e-300))[:-1, None]
            pts.append(P[:-1]), tgt.append((1 - f) * a + f * b)
    return np.concatenate(pts), np.concatenate(tgt)


def _domain_picture(sig: Array) -> tuple[Array, Array]:
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


# ---- step 2: geometry at the corners V_i: coefficient values and derivatives at the patch corner
@dataclass(frozen=True)
class _CornerFit:
    """The ribbon coefficients ``c_f`` at the hole corners (:func:`_corner_analysis`).

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
        :attr:`HoleFill.corner_residual`.
    twist : ndarray, shape (n,)
        :attr:`HoleFill.twist_mismatch`.
    flat : ndarray of bool, shape (n,)
        :attr:`HoleFill.flat`.
    """

    start: Array
    start_d: Array
    end: Array
    end_d: Array
    residual: Array
    twist: Array
    flat: Array


def _corner_analysis(S: list[_Side], sig: Array, rational: bool, c1: Array | None = None) -> _CornerFit:
    """Fit the ribbons of the two sides at every hole corner to each other (step 2).

    At corner ``i`` each side's ribbon must be the other side's tangent (so that the patch's
    corner is consistent), and the twists seen from both sides must agree: a least-squares fit in
    the fields' span, whose residuals are the corner diagnostics.

    Parameters
    ----------
    S : list of _Side, length n
        The sides in working coordinates.
    sig : ndarray, shape (n,)
        Split parameters.
    rational : bool
    c1 : ndarray, shape (n, nf), optional
        Ribbon coefficients at the midpoints (:func:`_centre`): at a flat corner the cross-field
        coefficient's derivative is set to its midpoint value (a linear ramp from 0).

    Returns
    -------
    _CornerFit

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
    return _CornerFit(start, start_d, end, end_d, residual, twist, np.array([c[6] for c in out], bool))


def _corner(i: int, S: list[_Side], sig: Array, rational: bool,
            c1: Array) -> tuple[Array, Array, Array, Array, float, float, bool]:
    """Hole corner ``i`` for :func:`_corner_analysis` (``c1`` (n, nf): the midpoint coefficients).

    Returns
    -------
    start, end, start_d, end_d : ndarray, shape (nf,)
        Row ``i`` of the :class:`_CornerFit` arrays of the same names.
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
    ta = sig[i] * S[i].B.derivatives(0.0, 1)[1]  # a'(0)
    tb = -tau_j * S[j].B.derivatives(1.0, 1)[1]  # b'(0)
    h0 = S[i].B.evaluate(0.0)  # the corner (homogeneous, weight 1)
    flat = _check_corner_angles(i, j, h0, _cart_tangent(h0, ta, rational), _cart_tangent(h0, tb, rational), Fa, Fb,
                                rational)
    rcond = tolerances.FILL_RCOND
    xa, *_ = np.linalg.lstsq(Fa.T, tb, rcond=rcond)
    xb, *_ = np.linalg.lstsq(Fb.T, ta, rcond=rcond)
    residual = max(np.linalg.norm(Fa.T @ xa - tb) / np.linalg.norm(tb),
                   np.linalg.norm(Fb.T @ xb - ta) / np.linalg.norm(ta))
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
    twist = np.linalg.norm(M @ y - rhs) / max(np.linalg.norm(ta), np.linalg.norm(tb), 1e-300)
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
    flat = bool(_angle_deg(tca, tcb) < min_angle)
    if flat and float(tca @ tcb) > 0:
        raise InvalidGeometryError(
            f"sides: corner {i} (start of side {i}) is a cusp: sides {j} and {i} leave it in the same direction "
            f"(within {min_angle} deg); the loop turns back on itself there")
    for k, at, F, t_side in ((i, "start", Fa, tca), (j, "end", Fb, tcb)):
        cross = _cart_tangent(h0, F[0], rational)
        ang = _angle_deg(t_side, cross)
        if not np.linalg.norm(cross) > 0 or not ang >= min_angle:
            raise InvalidGeometryError(
                f"sides[{k}].cross: degenerate at the {at} of the side (its angle to the boundary is "
                f"{ang:.3g} deg): the neighbour has a pole or a collapsed edge at hole corner {i} (a sphere "
                "or a fillet corner), where no tangent plane across the boundary is defined")
    return flat


# ---- step 3: centre, midpoints and the coefficients there
@dataclass(frozen=True)
class _Midpoints:
    """The sides at their split points ``m_i``, where the internal edges start (:func:`_midpoints`).

    Attributes
    ----------
    fields : list of (ndarray, ndarray), length n
        Side ``i``'s fields and their s-derivatives at ``sig_i`` (:meth:`_Side.fields`), each
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


def _midpoints(S: list[_Side], sig: Array, rational: bool) -> _Midpoints:
    """Evaluate every side at its split point, with the neighbour's tangent plane there.

    Raises
    ------
    InvalidGeometryError
        A cross field (nearly) tangent to its side at the split point.
    """
    n = len(S)
    Fm = [sd.fields(sig[i]) for i, sd in enumerate(S)]
    mh = np.array([S[i].B.evaluate(sig[i]) for i in range(n)])
    mder = np.array([S[i].B.derivatives(sig[i], 1)[1] for i in range(n)])
    mc = _cart(mh, rational)
    normals = np.zeros((n, 3))
    for i in range(n):
        tc = _cart_tangent(mh[i], mder[i], rational)
        dc = _cart_tangent(mh[i], Fm[i][0][0, 0], rational)
        if _angle_deg(tc, dc) < tolerances.FILL_MIN_CORNER_ANGLE:
            raise InvalidGeometryError(f"sides[{i}].cross: nearly tangent to the boundary "
                                       f"({_angle_deg(tc, dc):.3g} deg); the neighbour is degenerate there")
        normals[i] = _unit(np.cross(tc, dc))
    return _Midpoints(Fm, mh, mder, mc, normals)


def _centre(mid: _Midpoints, rational: bool, loop: Array | None = None,
            harmonic: tuple[Array, Array] | None = None) -> tuple[Array, Array]:
    """The centre ``C`` and the ribbon coefficients at the midpoints.

    ``C`` is the mean of the midpoints, each moved half-way towards that mean within its
    neighbour's tangent plane; the ribbon at ``m_i`` points along the projection of ``C - m_i``.
    When that leaves the hole at some midpoint (a long curved hole, a crescent: the midpoints' mean
    lies outside it), and ``loop`` (m, 3), points of the boundary, is given, ``C`` is instead the
    preimage of the domain's centre under the harmonic map of ``harmonic`` (loop samples (k, 3) and
    their domain places (k, 2), :func:`_harmonic_boundary`;
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
    if loop is None or not np.any(c1[:, 0] >= 0) or not turns_inward(loop, normals):
        return C, c1  # convex enough, or cross fields that point into the hole: _check_inward says so
    inner = None if harmonic is None else harmonic_centre(harmonic[0], harmonic[1], normals)
    inner = inner[:2] if inner is not None else inner_point(loop, normals)
    if inner is not None:
        C0, nh = inner
        C = C0 + nh * np.mean([nh @ (mc[i] + proj(i, C0 - mc[i]) - C0) for i in range(n)])
        c1 = _midpoint_coefficients(mid, C, rational)
    if np.any(c1[:, 0] >= 0):  # a sliver: the centre is along the side, not across it
        c1 = _midpoint_coefficients(mid, C, rational, turn=True)
    return C, c1


def _harmonic_layout(mid: _Midpoints, rational: bool, boundary: tuple[Array, Array], pdom: Array
                     ) -> tuple[Array, Array, Array] | None:
    """Centre, midpoint ribbons and centre map from the harmonic picture of the hole (course §8-3).

    A harmonic map of the hole onto the domain polygon
    (:func:`~occsurf.algorithms.topology.nsided_loops.harmonic_picture`, ``boundary`` from
    :func:`_harmonic_boundary`) is one-to-one; the central split takes its layout
    from it: ``C`` is the preimage of the domain's centre (lifted, as in :func:`_centre`, to the mean
    of the midpoints' tangent planes), internal edge ``i`` leaves ``m_i`` along the preimage of the
    domain segment ``p_i -> 0`` (its ribbon there: that direction in the neighbour's tangent plane,
    as long as the preimage curve), and the centre map ``DPhi`` is the inverse map's Jacobian at the
    centre (plus the slope of the chords ``C - m_i`` out of the mean plane). On a long curved hole
    the chords ``C - m_i`` cut across the hole and the corner patches fold; the harmonic curves
    follow it.

    Returns
    -------
    (C, c1, DPhi) or None
        As :func:`_centre` and :func:`_centre_map`; ``None`` when the picture cannot be built or
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
        t = length * _unit(t)
        target = np.r_[mid.point[i, 3] * t, 0.0] if rational else t
        c1[i], *_ = np.linalg.lstsq(mid.fields[i][0][0].T, target, rcond=tolerances.FILL_RCOND)
    if np.any(c1[:, 0] >= 0):
        return None
    rise = np.array([nh @ (C - mc[i]) for i in range(n)])
    slope = np.linalg.lstsq(-pdom, rise, rcond=tolerances.FILL_RCOND)[0]
    D = Jc + np.outer(nh, slope)
    DPhi = np.r_[D, np.zeros((1, 2))] if rational else D
    return C, c1, DPhi


def _midpoint_coefficients(mid: _Midpoints, C: Array, rational: bool, turn: bool = False) -> Array:
    """Coefficients (n, nf) of the fields at the midpoints for ribbons along the projections of
    ``C - m_i`` into the neighbours' tangent planes; with ``turn``, a projection that leaves the
    side at less than ``tolerances.FILL_MIN_EDGE_ANGLE`` into the hole is turned to that angle (same length)."""
    n, mc, normals = len(mid.cart), mid.cart, mid.normals
    c1 = np.zeros((n, mid.fields[0][0].shape[1]))
    for i in range(n):
        d = C - mc[i]
        t = d - normals[i] * (normals[i] @ d)
        if turn:
            tau = _unit(_cart_tangent(mid.point[i], mid.tangent[i], rational))
            x = _cart_tangent(mid.point[i], mid.fields[i][0][0, 0], rational)
            w = -_unit(x - tau * (x @ tau))  # in the tangent plane, across the side, into the hole
            a, b, length = float(t @ tau), float(t @ w), float(np.linalg.norm(t))
            lo = np.radians(tolerances.FILL_MIN_EDGE_ANGLE)
            if b < np.sin(lo) * length:
                t = length * (np.cos(lo) * (1.0 if a >= 0 else -1.0) * tau + np.sin(lo) * w)
        target = np.r_[mid.point[i, 3] * t, 0.0] if rational else t
        c1[i], *_ = np.linalg.lstsq(mid.fields[i][0][0].T, target, rcond=tolerances.FILL_RCOND)
    return c1


def _check_inward(corners: _CornerFit, c1: Array) -> None:
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


def _centre_map(C: Array, mc: Array, pdom: Array, rational: bool) -> Array:
    """The derivative ``DPhi`` (w, 2) of the affine map of the domain that gives the centre's
    tangent plane: ``C - m_i = DPhi (-p_i)`` in the least-squares sense (``mc``, ``pdom``: (n, 3),
    (n, 2)); one map for all patches, so that their tangent planes at the centre agree."""
    n = len(mc)
    tg = np.array([np.r_[C - mc[i], 0.0] if rational else C - mc[i] for i in range(n)])
    return np.linalg.lstsq(-pdom, tg, rcond=tolerances.FILL_RCOND)[0].T  # g_i = DPhi (-p_i)


# ---- step 4: internal edges: E_i, L_i (patch i), R_i (patch i+1); coefficient end derivatives
@dataclass(frozen=True)
class _InternalEdge:
    """Internal edge ``i``, from ``m_i`` (``t = 0``) to the centre (``t = 1``) (:func:`_internal_edge`).

    Attributes
    ----------
    curve : _Poly
        ``E_i(t)``, quartic, coefficients (5, w).
    left, right : _Poly
        The cross derivatives ``L_i`` of patch ``i`` and ``R_i`` of patch ``i + 1`` along it.
    coef_d_before, coef_d_after : ndarray, shape (nf,)
        Derivatives of the ribbon coefficients at ``m_i``: along ``u`` on patch ``i`` (the half
        side before ``m_i``) and along ``v`` on patch ``i + 1`` (the half after it).
    """

    curve: _Poly
    left: _Poly
    right: _Poly
    coef_d_before: Array
    coef_d_after: Array


def _internal_edge(i: int, vdom: Array, pdom: Array, sig_i: float, mid: _Midpoints, c1_i: Array, Ch: Array,
                   DPhi: Array) -> _InternalEdge:
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
    Ei = _Poly.hermite([(0.0, 0, mh), (0.0, 1, T0), (1.0, 0, Ch), (1.0, 1, DPhi @ dom["T"]),
                        (1.0, 2, np.zeros(mh.shape[0]))])
    left = (sig_i * mder, ca1d @ F + sig_i * c1_i @ dF, DPhi @ dom["A1"], DPhi @ (dom["A1"] - dom["A0"]))
    right = (-tau_i * mder, cb1d @ F - tau_i * c1_i @ dF, DPhi @ dom["B1"], DPhi @ (dom["B1"] - dom["B0"]))
    Li, Ri = _edge_cross_fields(i, a, b, r, Ei.deriv(), left, right)
    return _InternalEdge(Ei, Li, Ri, ca1d, cb1d)


def _edge_cross_fields(i: int, a: _Poly, b: _Poly, r: _Poly, T: _Poly, left: tuple[Array, Array, Array, Array],
                       right: tuple[Array, Array, Array, Array]) -> tuple[_Poly, _Poly]:
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
    ell, emm = _scalar_poly(lm[:2]), _scalar_poly(lm[2:])
    b0, b0d = b(0.0)[0], b(0.0, 1)[0]
    b1, b1d, ell0, ell1, ell0d = b(1.0)[0], b(1.0, 1)[0], ell(0.0)[0], ell(1.0)[0], ell(0.0, 1)[0]
    Z0 = (L0 - ell0 * T(0.0)) / b0
    Z1 = (L1 - ell1 * T(1.0)) / b1
    Z0d = (L0d - b0d * Z0 - ell0d * T(0.0) - ell0 * T(0.0, 1)) / b0
    Z1d = (L1d - b1d * Z1 - ell(1.0, 1)[0] * T(1.0) - ell1 * T(1.0, 1)) / b1
    Z = _Poly.hermite([(0.0, 0, Z0), (0.0, 1, Z0d), (1.0, 0, Z1), (1.0, 1, Z1d)])
    Li, Ri = b * Z + ell * T, -(a * Z) + emm * T
    # self-check: R must meet its end data too (it does when the corner conditions hold)
    scale = max(np.abs(L0).max(), np.abs(L1).max(), 1e-300)
    err = max(np.abs(Ri(0.0) - R0).max(), np.abs(Ri(1.0) - R1).max(), np.abs(Ri(0.0, 1) - R0d).max(),
              np.abs(Ri(1.0, 1) - R1d).max()) / scale
    if err > tolerances.FILL_EDGE_CONSISTENCY_TOL:
        raise ToleranceError(f"internal: the G1 data of internal edge {i} are inconsistent ({err:.2e})")
    return Li, Ri


# ---- step 5: one patch per hole corner
def _corner_patch(i: int, S: list[_Side], sig: Array, corners: _CornerFit, c1: Array, edges: list[_InternalEdge],
                  rational: bool, origin: Array) -> BSplineSurface:
    """Patch ``i`` (hole corner ``V_i``): its boundary rows and ribbons fixed, the rest faired.

    Its ``v = 0`` edge is ``[0, sig_i]`` of side ``i``, its ``u = 0`` edge ``[sig_{i-1}, 1]`` of
    side ``i - 1`` (reversed), its ``u = 1`` edge internal edge ``i`` and its ``v = 1`` edge
    internal edge ``i - 1``; ``c1`` (n, nf) are the ribbon coefficients at the midpoints, ``origin``
    (3,) the working origin added back.
    """
    j = (i - 1) % len(S)
    sa, sb = S[i], S[j]
    pa = _coefficient_poly(corners.start[i], corners.start_d[i], c1[i], edges[i].coef_d_before)  # u: s = sig_i u
    pb = _coefficient_poly(corners.end[i], corners.end_d[i], c1[j], edges[j].coef_d_after)  # v: s = 1 - tau_j v
    degree, knots = _patch_space(sa, sb, sig[i], sig[j], bool(corners.twist[i] > tolerances.FILL_TWIST_TOL))
    boundary = _boundary_ribbons(sa, sb, pa, pb, sig[i], 1.0 - sig[j], degree, knots)
    internal = _internal_ribbons(edges[i], edges[j], degree, knots)
    H = _assemble_poles(boundary, internal, degree, knots)
    if rational:
        if np.any(H[..., 3] <= 0):
            raise InvalidGeometryError(f"sides: the rational fill of corner {i} got a non-positive weight "
                                       f"({H[..., 3].min():.3g}); the neighbours' weights vary too much")
        return BSplineSurface(degree, knots, H[..., :3] / H[..., 3:] + origin, H[..., 3])
    return BSplineSurface(degree, knots, H + origin)


def _coefficient_poly(v0: Array, d0: Array, v1: Array, d1: Array) -> _Poly:
    """The cubic ribbon coefficients on a half side, ``t`` in [0, 1]: values and derivatives
    (each (nf,)) at the corner (``t = 0``) and at the midpoint (``t = 1``)."""
    return _Poly.hermite([(0.0, 0, v0), (0.0, 1, d0), (1.0, 0, v1), (1.0, 1, d1)])


def _patch_space(sa: _Side, sb: _Side, sig_i: float, sig_j: float,
                 twisted: bool) -> tuple[tuple[int, int], tuple[Array, Array]]:
    """Bidegree and knots of the patch between half sides ``sa[0, sig_i]`` (u) and ``sb[sig_j, 1]``
    (v, reversed): the sides' knots, the degree raised by 3 (cubic coefficients times the fields);
    with ``twisted`` (an incompatible corner twist) a corner span :func:`_corner_knot` in both."""
    Pu, Pv = max(sa.degree + 3, 4), max(sb.degree + 3, 4)
    Ku = _half_space(sa, 0.0, sig_i, False, Pu)
    Kv = _half_space(sb, sig_j, 1.0, True, Pv)
    if twisted:  # confine the incompatible twist to a small corner span
        Ku, Kv = _corner_knot(Ku, Pu), _corner_knot(Kv, Pv)
    return (Pu, Pv), (Ku, Kv)


def _boundary_ribbons(sa: _Side, sb: _Side, pa: _Poly, pb: _Poly, sig_i: float, tau_j: float,
                      degree: tuple[int, int], knots: tuple[Array, Array]) -> tuple[Array, Array, Array, Array]:
    """Poles of the two hole sides of a patch and of the ribbons (cross derivatives) along them.

    Exact: each is the side (or the side's fields times the cubic coefficients ``pa``, ``pb``)
    placed into the patch's knot space (:func:`_represent`, checked).

    Returns
    -------
    row0, da : ndarray, shape (nu, w)
        ``B_a(sig_i u)`` and ``F_v(u, 0) = sum_f pa_f(u) f_a(sig_i u)``, on ``(degree[0], knots[0])``.
    col0, db : ndarray, shape (nv, w)
        ``B_b(1 - tau_j v)`` and ``F_u(0, v) = sum_f pb_f(v) f_b(1 - tau_j v)``, on
        ``(degree[1], knots[1])``.
    """
    (Pu, Pv), (Ku, Kv) = degree, knots
    s_a = lambda u: sig_i * u  # noqa: E731
    s_b = lambda v: 1.0 - tau_j * v  # noqa: E731
    row0 = _represent(lambda u: sa.B.evaluate(s_a(u)), Pu, Ku)
    da = _represent(lambda u: np.einsum("mf,mfw->mw", pa(u), sa.fields(s_a(u))[0]), Pu, Ku)
    col0 = _represent(lambda v: sb.B.evaluate(s_b(v)), Pv, Kv)
    db = _represent(lambda v: np.einsum("mf,mfw->mw", pb(v), sb.fields(s_b(v))[0]), Pv, Kv)
    return row0, da, col0, db


def _internal_ribbons(edge_u: _InternalEdge, edge_v: _InternalEdge, degree: tuple[int, int],
                      knots: tuple[Array, Array]) -> tuple[Array, Array, Array, Array]:
    """Poles of the two internal edges of a patch and of its cross derivatives along them.

    Returns
    -------
    colE, colL : ndarray, shape (nv, w)
        ``edge_u``'s curve and left field (the patch's ``u = 1`` edge), on ``(degree[1], knots[1])``.
    rowE, rowR : ndarray, shape (nu, w)
        ``edge_v``'s curve and right field (the ``v = 1`` edge), on ``(degree[0], knots[0])``.
    """
    (Pu, Pv), (Ku, Kv) = degree, knots
    Ei, Li, Ej, Rj = edge_u.curve, edge_u.left, edge_v.curve, edge_v.right
    colE = _represent(lambda v: Ei(v), Pv, Kv)
    colL = _represent(lambda v: Li(v), Pv, Kv)
    rowE = _represent(lambda u: Ej(u), Pu, Ku)
    rowR = _represent(lambda u: Rj(u), Pu, Ku)
    return colE, colL, rowE, rowR


def _assemble_poles(boundary: tuple[Array, Array, Array, Array], internal: tuple[Array, Array, Array, Array],
                    degree: tuple[int, int], knots: tuple[Array, Array]) -> Array:
    """The patch's poles (nu, nv, w): the two outer rows on every edge from the boundary and internal
    ribbons (:func:`_boundary_ribbons`, :func:`_internal_ribbons`), the interior faired
    (:func:`_fair_interior`). Poles set twice (the corner blocks) are averaged: they agree but for
    the twist."""
    row0, da, col0, db = boundary
    colE, colL, rowE, rowR = internal
    (Pu, Pv), (Ku, Kv) = degree, knots
    nu, nv = len(Ku) - Pu - 1, len(Kv) - Pv - 1
    w = row0.shape[1]
    hu0, hv0 = Ku[Pu + 1] / Pu, Kv[Pv + 1] / Pv
    hu1, hv1 = (1.0 - Ku[nu - 1]) / Pu, (1.0 - Kv[nv - 1]) / Pv
    cnt = np.zeros((nu, nv))
    acc = np.zeros((nu, nv, w))
    for idx, vals in (((slice(None), 0), row0), ((slice(None), 1), row0 + hv0 * da),
                      ((0, slice(None)), col0), ((1, slice(None)), col0 + hu0 * db),
                      ((nu - 1, slice(None)), colE), ((nu - 2, slice(None)), colE - hu1 * colL),
                      ((slice(None), nv - 1), rowE), ((slice(None), nv - 2), rowE - hv1 * rowR)):
        acc[idx] += vals
        cnt[idx] += 1
    H = np.full((nu, nv, w), np.nan)
    fixed = cnt > 0
    H[fixed] = acc[fixed] / cnt[fixed][:, None]
    return _fair_interior(H, ~fixed, degree, knots)


def _corner_knot(K: Array, degree: int) -> Array:
    """Insert a knot of multiplicity ``degree - 1`` at ``tolerances.FILL_CORNER_SPAN`` (or half the
    first span)."""
    first = float(K[degree + 1])
    kappa = min(tolerances.FILL_CORNER_SPAN, 0.5 * first)
    return np.r_[K[:degree + 1], [kappa] * (degree - 1), K[degree + 1:]]


@functools.lru_cache(maxsize=16)
def _leggauss(m: int) -> tuple[Array, Array]:
    return np.polynomial.legendre.leggauss(m)


@functools.lru_cache(maxsize=64)
def _gram_cached(knots_key: bytes, degree: int, order: int) -> Array:
    knots = np.frombuffer(knots_key)
    n = len(knots) - degree - 1
    xg, wg = _leggauss(degree + 1)
    br = np.unique(knots)
    a, b = br[:-1], br[1:]
    x = (0.5 * (b - a)[:, None] * (xg + 1) + a[:, None]).ravel()
    wt = (0.5 * (b - a)[:, None] * wg).ravel()
    D = basis_matrix(knots, degree, n, x, order)[order]
    G = D.T @ (wt[:, None] * D)
    G.flags.writeable = False
    return G


def _gram(knots: Array, degree: int, order: int) -> Array:
    """``G[i, j] = int N_i^(order) N_j^(order)`` by Gauss-Legendre per span (cached per space)."""
    return _gram_cached(np.ascontiguousarray(knots, float).tobytes(), int(degree), int(order))


def _fair_interior(H: Array, free: NDArray[np.bool_], degree: tuple[int, int], knots: tuple[Array, Array]) -> Array:
    """Fill the free poles by minimising the thin-plate energy with the others fixed.

    The energy's matrix ``K = Gu2 (x) Gv0 + 2 Gu1 (x) Gv1 + Gu0 (x) Gv2`` is banded-Kronecker (at most
    ``(2p+1)^2`` non-zeros a row), so it is built sparse and the free block is factored by SuperLU:
    a dense (nu nv)^2 array was 1.1 GB and ~90 s for a 213 x 56 patch (lens face 2)."""
    if not free.any():
        return H
    G = [[sparse.csr_matrix(_gram(knots[d], degree[d], k)) for k in range(3)] for d in range(2)]
    K = (sparse.kron(G[0][2], G[1][0]) + 2 * sparse.kron(G[0][1], G[1][1])
         + sparse.kron(G[0][0], G[1][2])).tocsr()
    f = free.ravel()
    flat = H.reshape(-1, H.shape[2]).copy()
    Kf = K[f]
    flat[f] = splu(Kf[:, f].tocsc()).solve(-(Kf[:, ~f] @ flat[~f]))
    return flat.reshape(H.shape)


# ================================================================================== measurement
def _point_normal(surface: BSplineSurface, u: Array, v: Array) -> tuple[Array, Array]:
    """Points and (unnormalised) normals ``S_u x S_v`` from one derivative evaluation.

    Where ``S_u`` and ``S_v`` are parallel (the degenerate corner of a flat hole corner) the normal
    is the limit, taken ``tolerances.FILL_NORMAL_STEP`` (1e-7) of the domain into the patch (angle
    error ~1e-5 deg); a normal still degenerate there is NaN (as :meth:`BSplineSurface.normal`), so
    that it fails every angle check. Degenerate: ``|S_u x S_v|`` at most
    ``tolerances.FILL_DEGENERATE_NORMAL`` times ``|S_u| |S_v|``."""
    degenerate, step = tolerances.FILL_DEGENERATE_NORMAL, tolerances.FILL_NORMAL_STEP
    D = surface.derivatives(u, v, 1)
    nrm = np.cross(D[:, 1, 0], D[:, 0, 1])
    scale = np.linalg.norm(D[:, 1, 0], axis=1) * np.linalg.norm(D[:, 0, 1], axis=1)
    bad = np.linalg.norm(nrm, axis=1) <= degenerate * scale
    if bad.any():
        (u0, u1), (v0, v1) = surface.domain
        ub, vb = np.broadcast_to(u, bad.shape)[bad], np.broadcast_to(v, bad.shape)[bad]
        ub = ub + np.where(ub < 0.5 * (u0 + u1), step, -step) * (u1 - u0)
        vb = vb + np.where(vb < 0.5 * (v0 + v1), step, -step) * (v1 - v0)
        Db = surface.derivatives(ub, vb, 1)
        nb = np.cross(Db[:, 1, 0], Db[:, 0, 1])
        sb = np.linalg.norm(Db[:, 1, 0], axis=1) * np.linalg.norm(Db[:, 0, 1], axis=1)
        nb[~(np.linalg.norm(nb, axis=1) > degenerate * sb)] = np.nan
        nrm[bad] = nb
    return D[:, 0, 0], nrm


def _neighbour_normal(side: HoleSide, s: Array) -> Array:
    c = side.curve
    D = c.derivatives(s, 1)
    X = side.cross.evaluate(s)
    if c.is_rational:
        Hs = BSplineCurve._trusted(c.degree, c.knots, c.homogeneous_points).evaluate(s)
        X = (X[:, :3] - X[:, 3:] * (Hs[:, :3] / Hs[:, 3:])) / Hs[:, 3:]
    return np.cross(D[:, 1], X)


def measure_fill(fill: HoleFill, samples: int = 201) -> FillQuality:
    """Measure a fill densely: positional gap and tangent-plane angle along every joint.

    Parameters
    ----------
    fill : HoleFill
    samples : int
        Points per half side / internal edge (plus every knot of the patches' edges).

    Returns
    -------
    FillQuality
    """
    if not isinstance(fill, HoleFill):
        raise InvalidGeometryError(f"fill: expected a HoleFill, got {type(fill).__name__}")
    P, sd, n = fill.patches, fill.sides, len(fill.patches)
    t = np.linspace(0.0, 1.0, max(int(samples), 3))
    bg, ba, ig, ia = (np.zeros(n) for _ in range(4))
    for i in range(n):
        k = (i + 1) % n
        tu = np.unique(np.r_[t, P[i].knots[0]])
        tv = np.unique(np.r_[t, P[k].knots[1]])
        s1, s2 = fill.split[i] * tu, 1.0 - (1.0 - fill.split[i]) * tv
        c1, c2 = sd[i].curve.evaluate(s1), sd[i].curve.evaluate(s2)
        (f1, n1), (f2, n2) = _point_normal(P[i], tu, 0.0 * tu), _point_normal(P[k], 0.0 * tv, tv)
        bg[i] = max(np.linalg.norm(f1 - c1, axis=1).max(), np.linalg.norm(f2 - c2, axis=1).max())
        ba[i] = max(_angle_deg(n1, _neighbour_normal(sd[i], s1)).max(), _angle_deg(n2, _neighbour_normal(sd[i], s2)).max())
        te = np.unique(np.r_[t, P[i].knots[1], P[k].knots[0]])
        (e1, m1), (e2, m2) = _point_normal(P[i], 1.0 + 0 * te, te), _point_normal(P[k], te, 1.0 + 0 * te)
        ig[i] = np.linalg.norm(e1 - e2, axis=1).max()
        ia[i] = _angle_deg(m1, m2).max()
    nc = np.array([p.normal(1.0, 1.0) for p in P])
    ca = float(max(_angle_deg(nc[0], nc[i]) for i in range(n)))
    return FillQuality(bg, ba, ig, ia, ca, np.array([count_folds(p) for p in P], np.intp))


def count_folds(surface: BSplineSurface | TrimmedSurface, grid: int = 41) -> int:
    """Neighbouring pairs of a ``grid`` x ``grid`` parameter grid of ``surface`` whose normals
    ``S_u x S_v`` point in opposite directions (:attr:`FillQuality.folds`); a degenerate normal (a
    flat hole corner) counts as neither.

    Parameters
    ----------
    surface : BSplineSurface or TrimmedSurface
        For a trimmed surface (a plate fill's :attr:`~.plate_fill.PlateFill.trimmed`) the grid
        spans the trimming loops' parameter box and only pairs with both points on the face
        (:meth:`~occsurf.algorithms.kernel.trimmed.TrimmedSurface.contains`, boundary included)
        count: outside its trim the surface is not part of the face (a plate's height field can
        be steep there, beyond the hole, and those slopes are no fold of the fill). Its grid has
        at least two points per knot span of the box in each direction: one surface spans the
        whole hole there (a plate of 127 x 51 spans), where the central split has ``n`` patches
        of ``grid`` x ``grid`` each, and a ripple a span wide turned its normal by more than 90
        degrees between samples 2e-3 apart on linkrods' faces [22, 26] (10 to 13 pairs on grids of
        121 to 201, none on 41 x 41).
    grid : int
        Grid points per direction (the least, for a trimmed surface).

    Returns
    -------
    int
    """
    trimmed = surface if isinstance(surface, TrimmedSurface) else None
    if trimmed is not None:
        surface = trimmed.surface
        uv = np.concatenate([np.asarray(c.evaluate(np.linspace(*c.domain, 65)), float)[:, :2] for c in trimmed.outer])
        (u0, v0), (u1, v1) = uv.min(axis=0), uv.max(axis=0)
        (a0, a1), (b0, b1) = surface.domain
        u0, u1, v0, v1 = max(u0, a0), min(u1, a1), max(v0, b0), min(v1, b1)
        ku, kv = (np.unique(k) for k in surface.knots)  # at least two grid points per span
        gu = max(grid, 2 * int(np.count_nonzero((ku > u0) & (ku < u1))) + 3)
        gv = max(grid, 2 * int(np.count_nonzero((kv > v0) & (kv < v1))) + 3)
    else:
        (u0, u1), (v0, v1) = surface.domain
        gu = gv = grid
    U, V = np.meshgrid(np.linspace(u0, u1, gu), np.linspace(v0, v1, gv), indexing="ij")
    D = surface.derivatives(U.ravel(), V.ravel(), 1)
    N = np.cross(D[:, 1, 0], D[:, 0, 1]).reshape(gu, gv, 3)
    length = np.linalg.norm(N, axis=2)
    N[length <= tolerances.FILL_FOLD_DEGENERATE * np.median(length)] = 0.0  # a degenerate point (flat hole corner) has no side
    du = np.einsum("ijk,ijk->ij", N[1:], N[:-1]) < 0
    dv = np.einsum("ijk,ijk->ij", N[:, 1:], N[:, :-1]) < 0
    if trimmed is not None:  # only pairs on the face
        inside = trimmed.contains(U, V)
        du &= inside[1:] & inside[:-1]
        dv &= inside[:, 1:] & inside[:, :-1]
    return int(du.sum() + dv.sum())


def fill_folds(fill: Any) -> int:
    """Folds of a fill (:func:`count_folds`): summed over a :class:`HoleFill`'s patches; for a fill
    that is one trimmed surface (a :class:`~.plate_fill.PlateFill`: its ``trimmed`` attribute),
    counted on the face only, inside its trim."""
    trimmed = getattr(fill, "trimmed", None)
    if isinstance(trimmed, TrimmedSurface):
        return count_folds(trimmed)
    return sum(count_folds(p) for p in fill.patches)
