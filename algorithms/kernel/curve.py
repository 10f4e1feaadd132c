"""B-spline and NURBS curves (course §2, §12).

:class:`BSplineCurve` is a frozen value: every operation returns a new curve. Its arrays are
read-only. Rational curves take Cartesian control points plus a separate ``weights`` array, as
OCC does; kernels work in homogeneous coordinates.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import partial
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import _numba_kernels as _nk
from .. import _validate as V
from .. import tolerances
from ..errors import InvalidGeometryError, ParameterError, ToleranceError
from ._common import ARRAY, SCALAR, ControlPointValue
from ._poles import HomogeneousPoles
from .basis import basis_derivatives, basis_functions, find_span, greville
from .blossom import blossom_poles
from .degree import elevate_poles
from .knots import (
    bezier_poles,
    check_rescaled,
    clamp_poles,
    insert_knot_boehm,
    multiplicity,
    refine_poles,
    refinement_knots,
    remove_knot_lsq,
    rescale_knots,
    snap_knot,
    split_poles,
)
from .rational import curve_quotient_rule, pole_deviation

__all__ = ["BSplineCurve"]

Array = NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class BSplineCurve(HomogeneousPoles, ControlPointValue):
    """A B-spline (or NURBS) curve of any dimension.

    Parameters
    ----------
    degree : int
        1 to 25 (OpenCascade's limit).
    knots : array_like, shape (n + degree + 1,)
        Full, non-decreasing knot vector with repeats; multiplicities at most ``degree + 1``.
        Need not be clamped: the domain is ``[knots[degree], knots[n]]``, as in OCC.
    control_points : array_like, shape (n, d)
        Poles (Cartesian even for rational curves), ``n >= degree + 1``.
    weights : array_like, shape (n,), optional
        Positive weights; ``None`` for a polynomial spline.

    Raises
    ------
    InvalidGeometryError
        Naming the argument at fault: wrong shapes or lengths, decreasing knots, a multiplicity
        above ``degree + 1``, an empty domain, non-finite values, weights <= 0, degree outside 1..25.

    Examples
    --------
    >>> c = BSplineCurve(2, [0, 0, 0, 1, 1, 1], [[0, 0], [1, 1], [2, 0]])
    >>> c.evaluate(0.5)
    array([1. , 0.5])

    Notes
    -----
    ``to_dict``, ``from_dict``, ``transform`` and ``==`` come from
    :class:`._common.ControlPointValue` (dict type ``"BSplineCurve"``, header ``degree``, ``knots``).
    """

    _DICT_TYPE = "BSplineCurve"
    _HEADER = (("degree", SCALAR), ("knots", ARRAY))

    degree: int
    knots: Array
    control_points: Array
    weights: Array | None = None
    _hpoles: Array = field(init=False, repr=False, compare=False)

    if TYPE_CHECKING:  # the generated __init__ takes array_like; __post_init__ stores float arrays

        def __init__(
            self, degree: int, knots: ArrayLike, control_points: ArrayLike, weights: ArrayLike | None = None
        ) -> None: ...

    def __post_init__(self) -> None:
        p = V.as_degree(self.degree)
        P = V.as_finite_array(self.control_points, "control_points")
        if P.ndim != 2 or P.shape[1] < 1:
            raise InvalidGeometryError(f"control_points: expected shape (n, d), got {P.shape}")
        n = P.shape[0]
        if n < p + 1:
            raise InvalidGeometryError(f"control_points: a degree-{p} curve needs at least {p + 1} poles, got {n}")
        t = V.check_knots(self.knots, p, n)
        w = None if self.weights is None else V.check_weights(self.weights, (n,))
        V.check_homogeneous(P, w)
        self._set(p, t, P, w)

    def _set(self, p: int, t: Array, P: Array, w: Array | None) -> None:
        object.__setattr__(self, "degree", p)
        object.__setattr__(self, "knots", V.readonly(t))
        self._set_poles(P, w)

    @classmethod
    def _trusted(cls, degree: int, knots: Array, control_points: Array, weights: Array | None = None) -> BSplineCurve:
        """Fast constructor for internal results that are valid by construction (no checks)."""
        obj = object.__new__(cls)
        obj._set(int(degree), np.asarray(knots, float), np.asarray(control_points, float),
                 None if weights is None else np.asarray(weights, float))
        return obj

    # ------------------------------------------------------------------ properties
    @property
    def n_poles(self) -> int:
        return self.control_points.shape[0]

    @property
    def dim(self) -> int:
        return self.control_points.shape[1]

    @property
    def domain(self) -> tuple[float, float]:
        """``(knots[degree], knots[n])``."""
        return float(self.knots[self.degree]), float(self.knots[self.n_poles])

    @property
    def is_clamped(self) -> bool:
        p, t = self.degree, self.knots
        return bool(np.all(t[: p + 1] == t[0]) and np.all(t[-p - 1 :] == t[-1]))

    @property
    def homogeneous_points(self) -> Array:
        """``(n, d + 1)`` homogeneous poles ``(w P, w)`` (``(n, d)`` poles if not rational)."""
        return self._hpoles

    def greville(self) -> Array:
        """Greville abscissae, shape ``(n,)``."""
        return greville(self.knots, self.degree)

    def __repr__(self) -> str:
        kind = "rational " if self.is_rational else ""
        return f"BSplineCurve({kind}degree={self.degree}, poles={self.n_poles}, dim={self.dim}, domain={self.domain})"

    # ------------------------------------------------------------------ evaluation
    def _span_table(self) -> tuple[Any, ...]:
        """The numba kernels' span table (:func:`.._numba_kernels.span_table`), made once per curve
        (:meth:`_kept`)."""
        table: tuple[Any, ...] = self._kept("span_table", lambda: _nk.span_table(self.knots, self.degree, self.n_poles))
        return table

    def _params(self, u: ArrayLike, name: str = "u") -> tuple[Array, tuple[int, ...]]:
        a = V.check_parameters(u, *self.domain, name=name)
        return a.reshape(-1), a.shape

    def evaluate(self, u: ArrayLike) -> Array:
        """Points of the curve (course §2-9).

        Parameters
        ----------
        u : float or array_like, shape (...)

        Returns
        -------
        ndarray, shape (..., d)

        Raises
        ------
        ParameterError
            If a parameter is not finite or lies outside the domain.

        Notes
        -----
        From ``tolerances.NUMBA_MIN_POINTS`` points on, an optional numba kernel computes the same
        values (to round-off) when numba is installed; ``OCCSURF_NO_NUMBA=1`` turns it off.
        """
        flat, shape = self._params(u)
        p, n = self.degree, self.n_poles
        if _nk.applies(flat.shape[0]):
            out = np.empty((flat.shape[0], self.dim))
            args = (self.knots, p, *self._span_table(), self._hpoles, flat, self.is_rational, out)
            if _nk.run("curve_points", *args):
                return out.reshape(shape + (self.dim,))
        span = find_span(self.knots, p, n, flat)
        N = basis_functions(self.knots, p, span, flat)
        idx = span[:, None] - p + np.arange(p + 1)
        H = np.einsum("mk,mkd->md", N, np.take(self._hpoles, idx, axis=0))  # einsum: see derivatives
        if self.is_rational:
            H = H[:, :-1] / H[:, -1:]
        return H.reshape(shape + (self.dim,))

    __call__ = evaluate

    def derivatives(self, u: ArrayLike, order: int = 1) -> Array:
        """The point and all derivatives up to ``order`` (A2.3; rational by A4.2).

        Returns
        -------
        ndarray, shape (..., order + 1, d)
            ``[..., k, :]`` is ``d^k C / du^k``. At knots the derivative is the one from the
            right (left at the domain end), as in OCC.

        Notes
        -----
        From ``tolerances.NUMBA_MIN_POINTS`` points on, an optional numba kernel computes the same
        values (to round-off) when numba is installed; ``OCCSURF_NO_NUMBA=1`` turns it off.
        """
        order = V.check_order(order)
        flat, shape = self._params(u)
        p, n = self.degree, self.n_poles
        V.check_size((flat.shape[0], order + 1, max(p + 1, self.dim + 1)), f"derivatives of order {order} at "
                     f"{flat.shape[0]} points")
        if _nk.applies(flat.shape[0]):
            out = np.empty((flat.shape[0], order + 1, self.dim))
            args = (self.knots, p, *self._span_table(), self._hpoles, flat, order, self.is_rational, out)
            if _nk.run("curve_derivatives", *args):
                return out.reshape(shape + (order + 1, self.dim))
        span = find_span(self.knots, p, n, flat)
        D = basis_derivatives(self.knots, p, span, flat, order)
        idx = span[:, None] - p + np.arange(p + 1)
        # einsum's plain sums, not a matrix product: BLAS sums in another order and rounds
        # differently, and a straight line's C'' (exactly 0 here) becomes 1e-15 in a random direction:
        # a Frenet normal where OCC raises LProp_NotDefined. np.take gathers faster than a fancy index.
        H = np.einsum("mjk,mkd->mjd", D, np.take(self._hpoles, idx, axis=0))
        if self.is_rational:
            H = curve_quotient_rule(H)
        return H.reshape(shape + (order + 1, self.dim))

    def blossom(self, args: ArrayLike, span: float | None = None) -> Array:
        """Polar form (blossom) of one polynomial piece (course §2-3, §2-7).

        Parameters
        ----------
        args : array_like, shape (..., degree)
            Blossom arguments; any real values (the blossom is multi-affine).
        span : float, optional
            A parameter selecting the polynomial piece (the knot span holding it). Default: the
            piece holding the mean of each argument set. ``blossom([u] * p) == evaluate(u)``.

        Returns
        -------
        ndarray, shape (..., d)
        """
        a = V.as_finite_array(args, "args")
        p = self.degree
        if a.shape[-1:] != (p,):
            raise InvalidGeometryError(f"args: expected last axis of length degree = {p}, got shape {a.shape}")
        shape = a.shape[:-1]
        a2 = a.reshape(-1, p)
        lo, hi = self.domain
        if span is None:
            at = np.clip(a2.mean(axis=1), lo, hi)
        else:
            at = np.full(a2.shape[0], float(V.check_parameters(span, lo, hi, "span")))
        mu = find_span(self.knots, p, self.n_poles, at)
        H = blossom_poles(self.knots, p, self._hpoles, mu, a2)
        if self.is_rational:
            H = H[:, :-1] / H[:, -1:]
        return H.reshape(shape + (self.dim,))

    # ------------------------------------------------------------------ knot operations
    def _rebuild(self, degree: int, knots: Array, hpoles: Array) -> BSplineCurve:
        return BSplineCurve._from_homogeneous(degree, knots, hpoles, self.is_rational)

    def _interior_knot(self, u: float, name: str) -> float:
        lo, hi = self.domain
        x = float(V.check_parameters(u, lo, hi, name))
        if x <= lo or x >= hi:
            raise ParameterError(f"{name}: {x!r} must lie strictly inside the domain ({lo!r}, {hi!r})")
        snapped = snap_knot(self.knots, x)
        if snapped <= lo or snapped >= hi:  # within the knot tolerance of an end: a piece would be empty
            raise ParameterError(f"{name}: {x!r} is within the knot tolerance of the domain end {snapped!r} "
                                 f"(domain ({lo!r}, {hi!r})); no interior knot can be placed there")
        return snapped

    def insert_knot(self, knot: float, times: int = 1) -> BSplineCurve:
        """Insert ``knot`` ``times`` times by Boehm's algorithm (course §2-10; A5.1).

        The curve is unchanged; ``times`` extra poles appear.

        Parameters
        ----------
        knot : float
            The parameter value to insert, strictly inside the domain (snapped to an existing knot
            within round-off).
        times : int, optional
            How many copies to insert; the multiplicity may not exceed the degree.

        Raises
        ------
        ParameterError
            ``knot`` not strictly inside the domain.
        InvalidGeometryError
            The multiplicity would exceed the degree.
        """
        times = V.check_times(times)
        x = self._interior_knot(knot, "knot")
        s = multiplicity(self.knots, x)
        if s + times > self.degree:
            raise InvalidGeometryError(
                f"times: knot {x!r} has multiplicity {s}; inserting {times} more exceeds the degree {self.degree}"
            )
        t, H = insert_knot_boehm(self.knots, self.degree, self._hpoles, x, times)
        return self._rebuild(self.degree, t, H)

    def refine(self, knots: ArrayLike) -> BSplineCurve:
        """Insert many knots at once by the Oslo algorithm (course §2-10, knot refinement).

        Parameters
        ----------
        knots : array_like, shape (k,)
            Values strictly inside the domain, repeats allowed, any order.
        """
        x = V.as_finite_array(knots, "knots", ndim=1)
        if x.size == 0:
            return self
        tau = refinement_knots(self.knots, self.degree, self.n_poles, self._hpoles.shape[-1], x)
        H = refine_poles(self.knots, self.degree, self._hpoles, tau)
        return self._rebuild(self.degree, tau, H)

    def remove_knot(self, knot: float, times: int = 1, tol: float | None = None) -> BSplineCurve:
        """Remove ``knot`` ``times`` times if the curve moves by at most ``tol``.

        The new poles are the least-squares solution over the poles that removal changes; the
        deviation checked is the largest movement of any pole of the original representation,
        an upper bound of the curve's movement (convex-hull property) for polynomial curves.
        For rational curves it is measured on the Cartesian poles of the refined form (and the
        weights must agree to the same relative tolerance).

        Parameters
        ----------
        knot : float
            An interior knot of the curve.
        times : int, optional
            How many of its copies to remove.
        tol : float, optional
            Absolute tolerance in model units; default ``tolerances.KNOT_REMOVAL``.

        Raises
        ------
        ToleranceError
            The knot cannot be removed within ``tol``; the message gives the deviation needed.
            Nothing is changed (there is nothing to change: curves are immutable).
        InvalidGeometryError
            ``knot`` is not a knot, or has fewer than ``times`` copies.
        """
        times = V.check_times(times)
        tol = V.check_tol(tolerances.KNOT_REMOVAL if tol is None else tol)
        x = self._interior_knot(knot, "knot")
        s = multiplicity(self.knots, x)
        if s < times:
            raise InvalidGeometryError(f"knot: {x!r} is a knot of multiplicity {s}, cannot remove it {times} times")
        t, H, dev = remove_knot_lsq(self.knots, self.degree, self._hpoles, x, times, partial(pole_deviation, rational=self.is_rational))
        if dev > tol:
            raise ToleranceError(
                f"remove_knot: knot {x!r} (x{times}) cannot be removed within tol={tol:g}; "
                f"the curve would move by up to {dev:.3g}"
            )
        return self._rebuild(self.degree, t, H)

    def elevate_degree(self, times: int = 1) -> BSplineCurve:
        """Raise the degree by ``times`` keeping the curve (course §2-6; blossom form).

        Every distinct knot's multiplicity grows by ``times`` so the continuity is kept. An
        unclamped curve is clamped first (its unused outer poles carry no geometry).
        """
        times = V.check_times(times)
        if self.degree + times > tolerances.MAX_DEGREE:
            raise InvalidGeometryError(
                f"times: degree {self.degree} + {times} exceeds the maximum {tolerances.MAX_DEGREE}"
            )
        t, H = elevate_poles(self.knots, self.degree, self._hpoles, times)
        return self._rebuild(self.degree + times, t, H)

    def clamp(self) -> BSplineCurve:
        """The same curve with clamped (multiplicity ``degree + 1``) end knots."""
        t, H = clamp_poles(self.knots, self.degree, self._hpoles)
        if t is self.knots:
            return self
        return self._rebuild(self.degree, t, H)

    def to_bezier(self) -> list[BSplineCurve]:
        """Bézier segments, one per non-empty knot span (course §2-11; A5.6).

        Returns
        -------
        list of BSplineCurve
            Each of ``degree + 1`` poles with knots ``[a]*(p+1) + [b]*(p+1)`` on its span.
        """
        p = self.degree
        breaks, segs = bezier_poles(self.knots, p, self._hpoles)
        return [
            self._rebuild(p, np.r_[np.full(p + 1, breaks[j]), np.full(p + 1, breaks[j + 1])], segs[j])
            for j in range(segs.shape[0])
        ]

    def split(self, param: float) -> tuple[BSplineCurve, BSplineCurve]:
        """Split at an interior parameter into two clamped curves on ``[a, param]`` and ``[param, b]``.

        Raises
        ------
        ParameterError
            ``param`` not strictly inside the domain ``(a, b)``.
        """
        x = self._interior_knot(param, "param")
        (tl, Hl), (tr, Hr) = split_poles(self.knots, self.degree, self._hpoles, x)
        left = self._rebuild(self.degree, tl, Hl)
        right = self._rebuild(self.degree, tr, Hr)
        return left, right

    def segment(self, u0: float, u1: float) -> BSplineCurve:
        """The piece of the curve on ``[u0, u1]`` (clamped), like OCC's ``Segment``."""
        lo, hi = self.domain
        a = float(V.check_parameters(u0, lo, hi, "u0"))
        b = float(V.check_parameters(u1, lo, hi, "u1"))
        if not a < b:
            raise ParameterError(f"segment: expected u0 < u1, got {a!r} >= {b!r}")
        c = self.clamp()
        # an end within the knot tolerance of the domain's is that end (split refuses to cut there)
        a, b = snap_knot(c.knots, a), snap_knot(c.knots, b)
        if not a < b:
            raise ParameterError(f"segment: u0 = {u0!r} and u1 = {u1!r} are the same knot within its tolerance")
        if b < hi:
            c = c.split(b)[0]
        if a > lo:
            c = c.split(a)[1]
        return c

    def reverse(self) -> BSplineCurve:
        """The same point set traversed backwards: ``r(u) = c(a + b - u)`` on the same domain."""
        t = self.knots
        lo, hi = self.domain
        w = None if self.weights is None else self.weights[::-1]
        # Cartesian poles and weights are copied, not rebuilt from homogeneous form: bit-exact.
        return BSplineCurve._trusted(self.degree, (lo + hi) - t[::-1], self.control_points[::-1], w)

    def reparametrize(self, start: float, end: float) -> BSplineCurve:
        """The same curve on the domain ``[start, end]`` (affine change of parameter)."""
        a, b = float(start), float(end)
        if not (np.isfinite(a) and np.isfinite(b) and a < b):
            raise ParameterError(f"reparametrize: expected finite start < end, got {start!r}, {end!r}")
        t = check_rescaled(rescale_knots(self.knots, self.domain, (a, b)), self.knots, (a, b), "reparametrize")
        return BSplineCurve._trusted(self.degree, t, self.control_points, self.weights)
