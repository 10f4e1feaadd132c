"""Preparing a hole's sides for the n-sided fill (step 0 of :func:`.nsided.fill_hole`, course §8-3).

:func:`working_sides` checks the sides (types, domains, a closed and simple loop) and brings them
into working coordinates about the hole's own centre, homogeneous if any side is rational, as
:class:`Side` objects (boundary ``B`` and cross field ``X`` on ``[0, 1]``); :func:`split_short_loop`
cuts a loop of one or two sides into four (course §8-3: the central split needs ``n >= 3``);
:func:`choose_split` picks the parameter where each side's internal edge starts and
:func:`half_space` the knot vector of the part of a side a corner patch covers.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from .. import tolerances
from ..errors import InvalidGeometryError
from ..kernel.curve import BSplineCurve
from .nsided_loops import arc_length_parameters, check_simple_loop
from .nsided_poly import mult_map, times_linear
from .nsided_types import HoleSide

__all__ = ["Side", "working_sides", "split_short_loop", "choose_split", "half_space"]

Array = NDArray[np.float64]


class Side:
    """A side in working coordinates: boundary ``B`` and cross field ``X`` on ``[0, 1]``."""

    def __init__(self, B: BSplineCurve, X: BSplineCurve, rational: bool) -> None:
        self.B, self.X, self.rational = B, X, rational
        self.nf = 3 if rational else 2
        #: What :meth:`prime` evaluated, per parameter: (fields, their derivatives, B's derivatives to order 1).
        self._primed: dict[float, tuple[Array, Array, Array]] = {}
        self._continuity: dict[float, int] | None = None

    def prime(self, s: Array) -> None:
        """Evaluate the side once at the parameters ``s`` (the corners and the split point) for the
        fill's many questions there: :meth:`fields` and :meth:`tangent` at each ``s[k]`` then return
        what one call at ``s[k]`` would, bit for bit: a curve's points and derivatives are computed
        point by point (the basis per parameter, ``einsum``'s sums per point; the numba kernels, from
        ``tolerances.NUMBA_MIN_POINTS`` points or inside a ``batch``, likewise), and the first
        derivative does not depend on the highest order asked (tests/algorithms/test_curve.py)."""
        s = np.asarray(s, float)
        DB = self.B.derivatives(s, 2)
        F, dF = self._fields(DB, self.X.derivatives(s, 1))
        for k, sk in enumerate(s):
            self._primed[float(sk)] = (F[k:k + 1], dF[k:k + 1], DB[k, :2])

    def tangent(self, s: float) -> Array:
        """``B'(s)``: ``B.derivatives(s, 1)[1]`` (from :meth:`prime` where it evaluated ``s``)."""
        kept = self._primed.get(float(s))
        return kept[2][1] if kept is not None else self.B.derivatives(s, 1)[1]

    def fields(self, s: float | Array) -> tuple[Array, Array]:
        """Fields ``[X, B', (B)]`` and their s-derivatives at ``s``: each (m, nf, w)."""
        if np.ndim(s) == 0 and float(s) in self._primed:
            F, dF, _ = self._primed[float(s)]
            return F, dF
        s = np.atleast_1d(np.asarray(s, float))
        return self._fields(self.B.derivatives(s, 2), self.X.derivatives(s, 1))

    def values(self, s: Array) -> tuple[Array, Array]:
        """``B(s)`` (m, w) and the fields ``[X, B', (B)]`` at the parameters ``s`` (m,) without their
        derivatives (m, nf, w), from one evaluation of ``B`` to order 1 and ``X`` to order 0.

        Bit for bit ``B.evaluate(s)`` and :meth:`fields` ``(s)[0]``: ``B`` is polynomial (homogeneous
        for a rational hole) and a polynomial curve's derivatives up to an order are its points
        and derivatives however high the order asked (tests/algorithms/test_curve.py). A patch's
        side and the ribbon across it are placed at the same parameters, so ``B`` is evaluated
        there once."""
        DB = self.B.derivatives(s, 1)
        return DB[:, 0], self._stack(self.X.derivatives(s, 0)[:, 0], DB[:, 1], DB[:, 0])

    def _fields(self, DB: Array, DX: Array) -> tuple[Array, Array]:
        return self._stack(DX[:, 0], DB[:, 1], DB[:, 0]), self._stack(DX[:, 1], DB[:, 2], DB[:, 1])

    def _stack(self, X: Array, B1: Array, B0: Array) -> Array:
        """``[X, B', (B)]`` (B only for a rational side: the homogeneous fields), shape (m, nf, w)."""
        return np.stack([X, B1, B0] if self.rational else [X, B1], 1)

    def continuity(self) -> dict[float, int]:
        """Interior knot -> continuity order of the fields (B' and X) there (made once: the split
        point and every patch's knot space ask)."""
        if self._continuity is None:
            out: dict[float, int] = {}
            for k, m in mult_map(self.B.knots, self.B.degree).items():
                out[k] = min(out.get(k, 99), self.B.degree - 1 - m)
            for k, m in mult_map(self.X.knots, self.X.degree).items():
                out[k] = min(out.get(k, 99), self.X.degree - m)
            self._continuity = out
        return dict(self._continuity)

    @property
    def degree(self) -> int:
        """The larger of the boundary's and the cross field's degrees."""
        return max(self.B.degree, self.X.degree)


def working_sides(sides: Sequence[HoleSide]) -> tuple[list[HoleSide], list[Side], bool, float, Array]:
    """Check the sides of a hole and bring them into working coordinates (step 0 of
    :func:`.nsided.fill_hole`).

    Returns
    -------
    unit : list of HoleSide, length n
        The sides clamped and reparametrised to ``[0, 1]``.
    work : list of Side, length n
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
    dense = [sd.curve.evaluate(np.linspace(0, 1, 33)) for sd in unit]  # point by point: ends as evaluate(0), (1)
    ends = np.array([[d[0], d[-1]] for d in dense])
    size = float(np.linalg.norm(np.ptp(np.concatenate(dense), axis=0)))
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
    # checks of represent then lose no digits to the model's distance from the origin (a hole
    # 1e6 away failed the representation check; at 1e4 the G1 angle grew from 4e-11 to 1e-7 deg).
    origin = ends[:, 0].mean(axis=0)
    work: list[Side] = []
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
                B, Xc = times_linear(B, lam), times_linear(Xc, lam)
        else:
            B, Xc = c, X
        work.append(Side(B, Xc, rational))
    return unit, work, rational, size, origin


def split_short_loop(unit: list[HoleSide]) -> tuple[list[HoleSide], Array]:
    """A loop of one or two sides (a round hole, a slot end) as four sides (course §8-3: the
    central split needs ``n >= 3``): one side is cut at the quarters of its arc length, each of two
    sides at its half. The cuts are flat corners (180 degrees) of the new loop, which
    :func:`.nsided.fill_hole` fills with a degenerate corner patch; the neighbour data are only cut, not
    changed. ``unit``: sides on ``[0, 1]``.

    Returns
    -------
    sides : list of HoleSide, length 4
        On ``[0, 1]``.
    source : ndarray, shape (4, 3)
        :attr:`.nsided_types.HoleFill.source`.
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


def choose_split(side: Side) -> float:
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


def half_space(side: Side, lo: float, hi: float, reverse: bool, degree: int) -> Array:
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
