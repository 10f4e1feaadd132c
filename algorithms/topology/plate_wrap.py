"""A hole that winds around an axis, filled by a plate in cylindrical coordinates (course §8-3).

The plate (:mod:`.plate_fill`) needs a plane over which the hole is a height field. A thread strip
is over none: the flank of an M6 screw's thread, removed, leaves a strip 0.3 mm wide that winds nine
times around the screw's axis, and every plane sees the loop cross itself. Around the axis, though,
the strip is a height field: in cylindrical coordinates ``(theta, z, r)`` about the axis the loop is
simple, and the flank is ``r(theta, z)``. So the hole is *unrolled* by

.. math::

    U(P) = (r_0\\, \\theta, z, r), \\qquad \\Phi(x, z, r) = c + z\\, a + r\\,(\\cos(x / r_0)\\, e_1
    + \\sin(x / r_0)\\, e_2) = U^{-1}

(``theta`` unwrapped continuously along the loop, ``r_0`` the loop's mean radius, so ``x`` is arc
length on the mean cylinder), the plate is fitted there, and mapped back:

1. every side's curve ``U(C(t))`` and cross derivative ``J_U X(t)`` (the Jacobian maps tangent
   vectors, so the neighbour's tangent plane maps to the unrolled neighbour's: G1 is a statement
   about tangency, which a diffeomorphism keeps) are fitted by cubic B-splines on the side's own
   parameter (least squares, ``scipy.interpolate.make_lsq_spline``; the side's own C0 and C1 knots
   kept as C0 knots), densely enough that the unrolled side is within a twentieth of the target of
   ``U(C(t))``;
2. :func:`.plate_fill.fill_plate` fits a height field over the plane normal to the unrolled ``r``
   axis (a flank, a crest), else to the ``z`` axis (a flank square to the axis), else over the
   unrolled loop's own plane (:func:`.plate_fill.plate_plane`: a run-out where the surface stands
   upright over one of the first two at one corner and over the other at the next), the first
   that meets the targets or else the closest, with the targets shrunk by the map's distortion
   (distances along ``x`` scale by ``r / r_0``, angles at most by ``max(r / r_0, r_0 / r)``);
3. the surface ``Phi(plate(u, v))`` is fitted on the plate's parameter box by a cubic
   tensor-product spline whose knots are the plate's, cut to at least ``_NODES_PER_RADIAN`` spans per
   radian of turn (least squares along each direction, :func:`_lsq_columns`),
   spans bisected until it is within a quarter of the G0 target of ``Phi(plate)`` on the face
   (:func:`_map_back`);
4. the face is that surface trimmed by the plate's p-curves (the same parameter plane).

What is achieved is measured in model space against the input sides (:attr:`PlateFill.side_g0`,
``side_g1``), not in the unrolled one. The axis: each one given (the bridge passes the axes of
neighbouring cylinders, cones and surfaces of revolution), then the least-squares cylinder through
the loop (:func:`~occsurf.algorithms.topology.axis_fit.fitted_axes`, started from each
principal axis). An axis is refused when the loop
winds around it (then it bounds no strip of the cylinder: a cap is a plate over a plane), comes
close to it (``theta`` is singular there) or the unrolled plate is no height field; the reasons are
named per axis.

References: course §8-3; Duchon 1977 (the thin-plate energy); for the unrolling, the cylindrical
development of ruled and helical surfaces in any text on differential geometry of surfaces (do
Carmo, "Differential Geometry of Curves and Surfaces", 1976, §1-3 and §4-2: local isometries of
the cylinder and the plane); for the axis, Pottmann and Randrup, "Rotational and helical surface
approximation for reverse engineering", Computing 60 (1998).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike, NDArray
from scipy.interpolate import make_lsq_spline
from scipy.linalg import solveh_banded

from .. import tolerances
from ..errors import InvalidGeometryError, OccsurfError
from ..kernel.basis import basis_derivatives, find_span
from ..kernel.curve import BSplineCurve
from ..kernel.surface import BSplineSurface
from ..kernel.trimmed import TrimmedSurface
from .axis_fit import axis_frame, axis_residual, fitted_axes
from .nsided import HoleSide
from .nsided_loops import closest_parameters
from .plate_fill import PlateFill, _validate, fill_plate
from .plate_measure import side_samples

Array = np.ndarray

__all__ = ["WrappedPlateFill", "fill_wrapped_plate"]

_NODES_PER_RADIAN = 12.0  # knot spans of the map-back spline per radian of turn (refined until met)
_MAX_SPANS_PRODUCT = 250_000  # spans of the map-back spline, u x v (its check grid is 16 times that)
_SIDE_SAMPLES = 64  # first knot spans of an unrolled side's fit (doubled until the side is met)
_MAX_SIDE_SAMPLES = 1 << 15  # most spans
_MIN_RADIUS = 0.05  # of the mean radius: closer to the axis, theta is too steep to unroll
_AXIS_RESIDUAL_RATIO = 10.0  # axes whose residual is more than this times the best's (plus the floor) are not tried
_AXIS_RESIDUAL_FLOOR = 1e-4  # residual (|v . n| per unit spread) below which axes count as equally good


@dataclass(frozen=True, eq=False)
class WrappedPlateFill(PlateFill):
    """A :class:`.plate_fill.PlateFill` made in cylindrical coordinates about an axis.

    Those of :class:`.plate_fill.PlateFill`, with ``surface``, ``trimmed``, ``side_g0``, ``side_g1``
    and ``met`` in model space; ``origin``, ``e1``, ``e2``, ``normal`` and ``lean`` are the plate's
    frame in the unrolled space (nothing in the bridge reads them); and:

    Attributes
    ----------
    unrolled : PlateFill
        The plate in the unrolled space ``(r_0 theta, z, r)``.
    axis_point, axis, ref : ndarray, shape (3,)
        The axis (``ref``: the direction of ``theta = 0``).
    radius : float
        ``r_0``.
    """

    unrolled: PlateFill | None = None
    axis_point: Array = field(default_factory=lambda: np.zeros(3))
    axis: Array = field(default_factory=lambda: np.zeros(3))
    ref: Array = field(default_factory=lambda: np.zeros(3))
    radius: float = 1.0

    def _uv(self, side: int, t: Array, points: Array) -> tuple[Array, Array]:
        """Plate parameters of ``points`` lying near side ``side`` at its parameters ``t`` (the turn
        of ``theta`` is the one of the unrolled side there)."""
        X = _unroll(points, self.axis_point, self.axis, self.ref, self.radius)
        if self.unrolled is None:  # fill_wrapped_plate always sets it (None is only the dataclass default)
            raise ValueError("WrappedPlateFill: no unrolled plate to map points through")
        xref = self.unrolled.sides[side].curve.evaluate(t)[:, 0]
        turn = 2 * np.pi * self.radius
        X[:, 0] += np.round((xref - X[:, 0]) / turn) * turn
        Q = X - self.origin
        return Q @ self.e1, Q @ self.e2

    def locate(self, side: int, points: ArrayLike) -> tuple[Array, Array]:
        """Parameters ``(u, v)`` on :attr:`surface` of points on (or near) side ``side``: unrolled
        about the axis (on the turn of the side's closest point) and projected onto the plate's plane."""
        if not 0 <= int(side) < len(self.sides):
            raise InvalidGeometryError(f"side: expected 0..{len(self.sides) - 1}, got {side}")
        P = np.asarray(points, float).reshape(-1, 3)
        t, _ = closest_parameters(self.sides[side].curve, P)
        return self._uv(int(side), t, P)


# ===================================================================================== the map
def _unroll(P: Array, c: Array, a: Array, e1: Array, r0: float) -> Array:
    """``(r0 theta, z, r)`` of points ``P`` (``theta`` in (-pi, pi])."""
    Q = np.asarray(P, float) - c
    z = Q @ a
    e2 = np.cross(a, e1)
    x, y = Q @ e1, Q @ e2
    return np.c_[r0 * np.arctan2(y, x), z, np.hypot(x, y)]


def _radial(P: Array, c: Array, a: Array) -> tuple[Array, Array]:
    """The points' offsets from the axis, square to it, and their lengths ``r``."""
    Q = np.asarray(P, float) - c
    R = Q - np.outer(Q @ a, a)
    return R, np.linalg.norm(R, axis=1)


def _jacobian_apply(P: Array, V: Array, c: Array, a: Array, e1: Array, r0: float) -> Array:
    """The unrolling's Jacobian applied to vectors ``V`` at points ``P``: ``(r0/r e_theta . V, a . V,
    e_r . V)``."""
    R, r = _radial(P, c, a)
    r = np.maximum(r, 1e-300)
    er = R / r[:, None]
    et = np.cross(a, er)
    return np.c_[r0 / r * np.einsum("ij,ij->i", et, V), V @ a, np.einsum("ij,ij->i", er, V)]


def _roll_back(X: Array, c: Array, a: Array, e1: Array, r0: float, block: int = 32768) -> Array:
    """``Phi``: points of the unrolled space back in the model.

    ``c + y a + z (cos(x / r0) e1 + sin(x / r0) e2)`` coordinate by coordinate, ``block`` points at
    a time: the same operations in the same order as broadcasting over the last axis (the same
    values), on whole rows instead of rows of three and on blocks that stay in the cache (the
    map-back's grids reach 1.7 million points: 0.2-0.3 s a call broadcast, 0.05 s so)."""
    e2 = np.cross(a, e1)
    flat = np.asarray(X, float).reshape(-1, 3)
    out = np.empty(flat.shape)
    for s in range(0, len(flat), block):
        x, o = flat[s:s + block], out[s:s + block]
        th = x[:, 0] / r0
        cs, sn = np.cos(th), np.sin(th)
        y, z = x[:, 1], x[:, 2]
        for k in range(3):
            o[:, k] = c[k] + y * a[k] + z * (cs * e1[k] + sn * e2[k])
    return out.reshape(np.shape(X))


# ===================================================================================== the sides
def _layout(curve: BSplineCurve, spans: int) -> tuple[Array, Array]:
    """Knots (cubic, clamped) and samples for fitting a function of ``curve``'s parameter: about
    ``spans`` uniform spans spread over the pieces between the curve's knots of continuity C1 or
    lower (a side joined from several edges has C0 knots: :func:`occsurf.bridge.modeling.refill_sides._joined`),
    which become triple knots (C0) of the fit, three samples per span."""
    p = curve.degree
    k, mult = np.unique(curve.knots, return_counts=True)
    lo, hi = curve.domain
    b = np.r_[lo, k[(k > lo) & (k < hi) & (mult >= max(p - 1, 1))], hi]
    L = np.diff(b)
    per = np.maximum(1, np.round(spans * L / (hi - lo))).astype(int)
    knots, x = [np.full(4, lo)], []
    for i in range(len(L)):  # per piece (a handful), vectorised inside
        knots += [np.linspace(b[i], b[i + 1], per[i] + 1)[1:-1], np.full(3 if i < len(L) - 1 else 4, b[i + 1])]
        xs = np.linspace(b[i], b[i + 1], 3 * per[i] + 1)
        x.append(xs if i == len(L) - 1 else xs[:-1])
    return np.concatenate(knots), np.concatenate(x)


def _unrolled_side(side: HoleSide, c: Array, a: Array, e1: Array, r0: float, x_start: float | None,
                   tol: float) -> HoleSide:
    """The side in the unrolled space, on the turn that starts nearest ``x_start`` (the previous
    side's end), fitted (least squares, :func:`_layout`) within ``tol`` of the exact unrolled curve
    half-way between the samples."""
    count = _SIDE_SAMPLES
    turn = 2 * np.pi * r0
    while True:
        knots, t = _layout(side.curve, count)
        P, T, X = side_samples(side, t)
        U = _unroll(P, c, a, e1, r0)
        U[:, 0] = r0 * np.unwrap(U[:, 0] / r0)
        if x_start is not None:
            U[:, 0] += np.round((x_start - U[0, 0]) / turn) * turn
        # theta unwrapped safely: its speed |e_theta . T| / r (from the tangent, so a step near a whole
        # turn cannot alias as np.unwrap's differences would) times the step below a quarter radian
        speed = np.abs(_jacobian_apply(P, T, c, a, e1, r0)[:, 0]) / r0
        if float(np.max(np.maximum(speed[1:], speed[:-1]) * np.diff(t))) < 0.25 or count >= _MAX_SIDE_SAMPLES:
            curve = make_lsq_spline(t, U, knots, k=3)
            tm = 0.5 * (t[1:] + t[:-1])
            Um = _unroll(side_samples(side, tm)[0], c, a, e1, r0)
            Ui = curve(tm)
            Um[:, 0] += np.round((Ui[:, 0] - Um[:, 0]) / turn) * turn
            err = float(np.linalg.norm(Ui - Um, axis=1).max())
            if err <= tol or count >= _MAX_SIDE_SAMPLES:
                break
        count *= 2
    if err > tol:
        raise InvalidGeometryError(f"wrapped plate: a side unrolled about the axis is {err:.3g} off its "
                                   f"fit with {count} spans (target {tol:.3g})")
    cross = make_lsq_spline(t, _jacobian_apply(P, X, c, a, e1, r0), knots, k=3)
    return HoleSide(BSplineCurve(3, curve.t, curve.c), BSplineCurve(3, cross.t, cross.c))


# ===================================================================================== the fill
def _one_axis(sides: list[HoleSide], flags: Array, c: Array, a: Array, g0_tol: float, angle_tol: float,
              max_spans: int | None) -> WrappedPlateFill:
    a = a / np.linalg.norm(a)
    e1, _ = axis_frame(a)
    dense = np.concatenate([side_samples(s, np.linspace(*s.curve.domain, 257))[0] for s in sides])
    _, r = _radial(dense, c, a)
    r0 = float(r.mean())
    if r.min() < _MIN_RADIUS * r0:
        k = int(np.argmin(r))
        raise InvalidGeometryError(f"the loop comes within {r[k]:.3g} of the axis (at "
                                   f"{np.array2string(dense[k], precision=4)}; mean radius {r0:.3g})")
    stretch = max(1.0, float(r.max()) / r0)
    kappa = max(stretch, r0 / float(r.min()))
    usides, x_end = [], None
    for s in sides:
        us = _unrolled_side(s, c, a, e1, r0, x_end, 0.05 * g0_tol / stretch)
        usides.append(us)
        x_end = float(us.curve.evaluate(us.curve.domain[1])[0])
    if x_end is None:  # _validate takes at least one side
        raise InvalidGeometryError("sides: expected at least one HoleSide, got none")
    x_first = float(usides[0].curve.evaluate(usides[0].curve.domain[0])[0])
    winding = (x_end - x_first) / (2 * np.pi * r0)
    if abs(winding) > 0.25:
        raise InvalidGeometryError(f"the loop winds {winding:+.2f} times around the axis (a strip of the "
                                   "cylinder about it must wind 0 times)")
    gap = abs(x_end - x_first)
    if gap > tolerances.FILL_CLOSURE_TOL * 2 * float(r.max()) * r0 / float(r.min()):
        raise InvalidGeometryError(f"the loop does not close when unrolled about the axis: it ends {gap:.3g} "
                                   "along the turn from its start")
    if gap > 0:  # close the loop exactly in the unrolled space (it closes in the model)
        us = usides[-1]
        cp = us.curve.control_points.copy()
        cp[-1, 0] = x_first
        usides[-1] = HoleSide(BSplineCurve(3, us.curve.knots, cp), us.cross)
    plate, best, why = None, np.inf, []
    # the height: r over (r0 theta, z) (a flank, a crest); else z over (r0 theta, r) (a flank
    # square to the axis: r spans it at constant z, which r over (theta, z) cannot); else over the
    # unrolled loop's own plane (a run-out: where the loop goes on straight over (theta, z) but
    # kinks in r the surface stands upright over (theta, z), where it goes on straight over
    # (theta, r) but kinks in z it stands upright over (theta, r); screw pair [8, 22]: 2.9e-3 off
    # with r, 1.6e-3 with z, met over its own plane: test_a_run_out_corner_takes_the_plane_...)
    tol0, tol1 = 0.5 * g0_tol / stretch, 0.5 * angle_tol / kappa
    for height, normal in (("r", (0.0, 0.0, 1.0)), ("z", (0.0, 1.0, 0.0)), ("the plate's own plane", None)):
        try:
            cand = fill_plate(usides, g1=flags, g0_tol=tol0, angle_tol=tol1, max_spans=max_spans,
                              normal=None if normal is None else np.array(normal))
        except OccsurfError as err:
            why.append(f"{height} as the height: {err}")
            continue
        score = _miss(cand, tol0, tol1)
        if score < best:
            plate, best = cand, score
        if cand.met:
            break
    if plate is None:
        raise InvalidGeometryError("in the unrolled space (r0 theta, z, r) about the axis through "
                                   f"{np.array2string(c, precision=4)} along {np.array2string(a, precision=4)}: "
                                   + "; ".join(why))
    surf = _map_back(plate, c, a, e1, r0, g0_tol, sides)
    trimmed = TrimmedSurface(surf, list(plate.trimmed.outer))
    fill = WrappedPlateFill(surface=surf, trimmed=trimmed, sides=sides, g1=flags, side_g0=np.zeros(len(sides)),
                            side_g1=np.full(len(sides), np.nan), origin=plate.origin, e1=plate.e1, e2=plate.e2,
                            normal=plate.normal, spans=surf.n_poles, met=False, g0_tol=g0_tol, angle_tol=angle_tol,
                            lean=plate.lean, method="wrapped plate", unrolled=plate, axis_point=c, axis=a, ref=e1,
                            radius=r0)
    g0, g1 = _measure(fill)
    met = bool(np.all(g0 <= g0_tol) and np.all(np.nan_to_num(g1, nan=0.0) <= angle_tol))
    return replace(fill, side_g0=g0, side_g1=g1, met=met)


def _miss(fill: PlateFill, g0_tol: float, angle_tol: float) -> float:
    """The fill's worst side in units of the targets (<= 1: both met; G0-only sides have no angle)."""
    return max(float(np.max(fill.side_g0)) / g0_tol, float(np.nanmax(np.r_[fill.side_g1, 0.0])) / angle_tol)


def _map_back(plate: PlateFill, c: Array, a: Array, e1: Array, r0: float, g0_tol: float,
              sides: list[HoleSide]) -> BSplineSurface:
    """``Phi(plate(u, v))`` as a cubic B-spline surface on the plate's parameter box, within a
    quarter of ``g0_tol`` of it on the face (inside the plate's trim).

    The knots are the plate's, each span cut into pieces of at most ``1 / _NODES_PER_RADIAN`` radian
    of turn (``Phi`` is analytic, the plate a C2 cubic: with the plate's knots among its own, the
    surface has no kink to chase), fitted by tensor-product least squares (one
    :func:`_lsq_columns` along ``u`` for all rows, then one along ``v``: exact for gridded data) at four samples per span; spans where a sample between them, on the face, misses
    are bisected and the fit repeated; the sides' own points (where the face's edges lie, which a
    grid point inside the trim may never land near) are checked as well. Off the face the plate may
    be steep (nothing holds it there) and is not chased. At ``_MAX_SPANS_PRODUCT`` spans the
    spline is returned as it is; the fill's boundary is measured afterwards."""
    p = 3
    ku, kv = (np.unique(k) for k in plate.surface.knots)
    rate = np.abs(np.array([plate.e1[0], plate.e2[0]])) / r0  # radians of turn per unit of u and of v
    breaks = []
    for k, rt in zip((ku, kv), rate):
        per = np.maximum(1, np.ceil(np.diff(k) * rt * _NODES_PER_RADIAN)).astype(int)
        breaks.append(np.concatenate([np.linspace(k[i], k[i + 1], per[i] + 1)[:-1] for i in range(len(per))] + [k[-1:]]))
    f = np.array([0.1, 0.35, 0.65, 0.9])  # samples per span (Schoenberg-Whitney holds: 4 per span)
    g = np.array([0.0, 0.225, 0.5, 0.775])  # checks: between the samples and at the breaks

    def model(U: Array, V: Array) -> Array:
        return _roll_back(plate.surface.evaluate_grid(U, V), c, a, e1, r0)

    edge_uv = np.concatenate([np.c_[plate.locate(i, s.curve.evaluate(np.linspace(*s.curve.domain, 2049)))]
                              for i, s in enumerate(plate.sides)])
    (u0, u1), (v0, v1) = plate.surface.domain
    edge_uv = np.clip(edge_uv, [u0, v0], [u1, v1])
    edge_model = _roll_back(plate.surface.evaluate(edge_uv[:, 0], edge_uv[:, 1]), c, a, e1, r0)

    while True:
        bu, bv = breaks
        tu, tv = (np.r_[np.full(p, b[0]), b, np.full(p, b[-1])] for b in breaks)
        xu = (bu[:-1, None] + f[None] * np.diff(bu)[:, None]).ravel()
        xv = (bv[:-1, None] + f[None] * np.diff(bv)[:, None]).ravel()
        F = model(xu, xv)
        Cu = _lsq_columns(xu, F.reshape(len(xu), -1), tu, p).reshape(-1, len(xv), 3)
        cv = _lsq_columns(xv, Cu.transpose(1, 0, 2).reshape(len(xv), -1), tv, p)
        poles = cv.reshape(-1, Cu.shape[0], 3).transpose(1, 0, 2)
        surf = BSplineSurface((p, p), (tu, tv), poles)
        cu = np.r_[(bu[:-1, None] + g[None] * np.diff(bu)[:, None]).ravel(), bu[-1]]
        cv = np.r_[(bv[:-1, None] + g[None] * np.diff(bv)[:, None]).ravel(), bv[-1]]
        err = np.linalg.norm(surf.evaluate_grid(cu, cv) - model(cu, cv), axis=-1)
        over = np.flatnonzero(err > 0.25 * g0_tol)  # only a miss off the face is let go: classify those
        if over.size:
            iu, iv = np.unravel_index(over, err.shape)
            err.flat[over[~plate.trimmed.contains(cu[iu], cv[iv])]] = 0.0
        e_edge = np.linalg.norm(surf.evaluate(edge_uv[:, 0], edge_uv[:, 1]) - edge_model, axis=1)
        worst = max(float(err.max()), float(e_edge.max()))
        if worst <= 0.25 * g0_tol:
            return surf
        miss = e_edge > 0.25 * g0_tol
        bad_u = np.unique(np.clip(np.searchsorted(bu, np.r_[cu[np.any(err > 0.25 * g0_tol, axis=1)], edge_uv[miss, 0]],
                                                  "right") - 1, 0, len(bu) - 2))
        bad_v = np.unique(np.clip(np.searchsorted(bv, np.r_[cv[np.any(err > 0.25 * g0_tol, axis=0)], edge_uv[miss, 1]],
                                                  "right") - 1, 0, len(bv) - 2))
        if (len(bu) + bad_u.size) * (len(bv) + bad_v.size) > _MAX_SPANS_PRODUCT:
            # as fine as it may get: what the face achieves on its boundary is measured in model space
            # (:func:`_measure`, ``met``), which is what counts (screw pair [9, 12]: 1.5e-6 left here
            # at the edges' points, the fill's boundary within 1.3e-6 of the hole's, target 1.9e-6)
            return surf
        breaks = [np.sort(np.r_[b, 0.5 * (b[bad] + b[bad + 1])]) for b, bad in ((bu, bad_u), (bv, bad_v))]


def _lsq_columns(x: Array, F: Array, knots: Array, p: int) -> Array:
    """Least-squares spline coefficients ``(n, k)`` of every column of ``F`` ``(m, k)`` sampled at
    ``x``, on ``knots`` of degree ``p``: what ``make_lsq_spline(x, F, knots, p).c`` returns, by the
    banded normal equations (one banded Cholesky factorisation for all columns).

    ``make_lsq_spline`` reduces the whole right-hand side by Givens rotations, column for column:
    4.8 s of the screw run-out's 7.0 s map-back, whose right-hand sides have ~900 columns. The
    samples here (four per span, inside it) keep the collocation matrix well conditioned, so the
    normal equations agree with the QR solution to ~1e-14 relative (tested against it)."""
    n = knots.size - p - 1
    span = find_span(knots, p, n, x)
    N = basis_derivatives(knots, p, span, x, 0)[:, 0]  # (m, p+1)
    cols = span[:, None] - p + np.arange(p + 1)
    ab = np.zeros((p + 1, n))  # upper band: ab[p + i - j, j] = (B^T B)[i, j], i <= j
    for a in range(p + 1):
        for b in range(a, p + 1):
            np.add.at(ab[p - (b - a)], cols[:, b], N[:, a] * N[:, b])
    B = sp.csr_matrix((N.ravel(), cols.ravel(), np.arange(0, N.size + 1, p + 1)), shape=(len(x), n))
    return solveh_banded(ab, np.asarray(B.T @ F), check_finite=False)


def _measure(fill: WrappedPlateFill, per_span: int = 16) -> tuple[Array, Array]:
    """Per side: the largest distance to the surface and angle (degrees) to the neighbour's tangent
    plane (nan on G0-only sides), in model space, at ``per_span`` samples in every knot span of the
    surface that the side crosses (a side of nine turns crosses hundreds; one that runs into a
    corner crosses the spans refined there)."""
    g0 = np.zeros(len(fill.sides))
    g1 = np.full(len(fill.sides), np.nan)
    brk = [np.unique(k) for k in fill.surface.knots]
    for i, s in enumerate(fill.sides):
        t0 = np.linspace(*s.curve.domain, 1025)
        u0, v0 = fill._uv(i, t0, side_samples(s, t0)[0])
        # spans crossed between neighbouring samples: each such step gets per_span samples per span
        cross = (np.abs(np.diff(np.searchsorted(brk[0], u0))) + np.abs(np.diff(np.searchsorted(brk[1], v0))))
        reps = per_span * (cross + 1)
        start = np.repeat(t0[:-1], reps)
        step = np.repeat(np.diff(t0) / reps, reps)
        k = np.arange(reps.sum()) - np.repeat(np.cumsum(reps) - reps, reps)
        t = np.r_[start + k * step, t0[-1]]
        P, T, X = side_samples(s, t)
        u, v = fill._uv(i, t, P)
        D = fill.surface.derivatives(u, v, 1)
        g0[i] = float(np.linalg.norm(D[:, 0, 0] - P, axis=1).max())
        if fill.g1[i]:
            n = np.cross(D[:, 1, 0], D[:, 0, 1])
            m = np.cross(X, T)
            cs = np.abs(np.einsum("ij,ij->i", n, m))
            sn = np.linalg.norm(np.cross(n, m), axis=1)
            g1[i] = float(np.degrees(np.arctan2(sn, cs)).max())
    return g0, g1


def fill_wrapped_plate(sides: Sequence[HoleSide], *, axes: Sequence[tuple[ArrayLike, ArrayLike]] = (),
                       g1: Sequence[bool] | NDArray[np.bool_] | None = None, g0_tol: float | None = None,
                       angle_tol: float | None = None, max_spans: int | None = None,
                       size: float | None = None) -> WrappedPlateFill:
    """Fill a hole that winds around an axis (a thread strip) with a plate in cylindrical
    coordinates (see the module; course §8-3).

    Parameters
    ----------
    sides : sequence of HoleSide
        As for :func:`.plate_fill.fill_plate`.
    axes : sequence of (point, direction)
        Axes to try first (e.g. of neighbouring surfaces of revolution); then :func:`fitted_axes`.
    g1, g0_tol, angle_tol, max_spans, size
        As for :func:`.plate_fill.fill_plate` (the targets are met in model space).

    Returns
    -------
    WrappedPlateFill
        The first axis whose fill meets both targets, else the one that comes closest.

    Raises
    ------
    InvalidGeometryError
        No axis gives a fill; the reason per axis.
    """
    sides, flags = _validate(sides, g1)
    angle_tol = float(tolerances.FILL_FIT_ANGLE if angle_tol is None else angle_tol)
    samples = [side_samples(s, np.linspace(*s.curve.domain, 129)) for s in sides]
    dense = np.concatenate([d[0] for d in samples])
    normals = np.concatenate([np.cross(d[2], d[1]) for d in samples])
    diag = 2.0 * float(np.linalg.norm(dense - dense.mean(axis=0), axis=1).max()) or 1.0
    g0_tol = float(tolerances.FILL_FIT_G0 * (diag if size is None else float(size)) if g0_tol is None else g0_tol)
    if not (g0_tol > 0 and angle_tol > 0):
        raise InvalidGeometryError(f"g0_tol, angle_tol: expected positive targets, got {g0_tol}, {angle_tol}")
    given = []
    for k, (c, a) in enumerate(axes):
        c, a = np.asarray(c, float).ravel(), np.asarray(a, float).ravel()
        if c.shape != (3,) or a.shape != (3,) or not (np.all(np.isfinite(np.r_[c, a])) and np.linalg.norm(a) > 0):
            raise InvalidGeometryError(f"axes[{k}]: expected a finite point and a non-zero direction in 3-D, "
                                       f"got {np.array2string(c)}, {np.array2string(a)}")
        given.append((c, a))
    # the axes the neighbours turn about best first (a neighbour's axis may have nothing to do with
    # this hole: the first axis whose fill meets the targets is kept, and the boundary targets can be
    # met about a wrong axis with the inside off the surface it was cut from)
    lengths = np.concatenate([np.linalg.norm(d[1], axis=1) * (s.curve.domain[1] - s.curve.domain[0]) / (len(d[1]) - 1)
                              for d, s in zip(samples, sides)])  # each sample's arc length
    cands = [(axis_residual(dense, normals, c, a, lengths), k < len(given), c, a)
             for k, (c, a) in enumerate(given + fitted_axes(dense, normals))]
    cands.sort(key=lambda x: (x[0], not x[1]))
    best, why, anchor = None, [], None
    for k, (res, is_given, c, a) in enumerate(cands):
        name = f"axis {k}" + (" (given" if is_given else " (fitted") + f", residual {res:.2g})"
        if anchor is not None and res > _AXIS_RESIDUAL_RATIO * anchor + _AXIS_RESIDUAL_FLOOR:
            # the neighbours turn about an axis that gave a fill far better: a fill about this one
            # may meet the boundary and miss the inside (screw pair [8, 22] about a fitted axis 2.1
            # deg off the screw's: boundary 1.6e-6, inside 0.47 mm off the thread; residuals 2.4e-3
            # and 6e-8). Axes refused (wound around, come too close) set no such bar.
            why.append(f"{name}: not tried, the neighbours turn more than {_AXIS_RESIDUAL_RATIO:g} times as "
                       "nearly about an axis already filled")
            continue
        try:
            fill = _one_axis(sides, flags, c, a, g0_tol, angle_tol, max_spans)
        except OccsurfError as err:
            why.append(f"{name}: {err}")
            continue
        anchor = res if anchor is None else anchor
        score = _miss(fill, g0_tol, angle_tol)
        if best is None or score < best[0]:
            best = (score, fill)
        if fill.met:
            break
    if best is None:
        raise InvalidGeometryError("wrapped plate: no axis the hole winds around gives a fill (" + "; ".join(why) + ")")
    return best[1]
