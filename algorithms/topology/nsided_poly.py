"""Vector polynomials and exact spline representations for the n-sided fill (course §8-3).

The ribbons of :func:`~occsurf.algorithms.topology.nsided.fill_hole` are products of cubic
polynomials (:class:`Poly`, monomial form) and the sides' splines; :func:`represent` places such a
function into a spline space that holds it exactly (collocation at the Greville abscissae, checked
against ``tolerances.FILL_REPRESENT_TOL``), :func:`times_linear` multiplies a spline by a linear
factor (the product of a spline and a polynomial is a spline on the same knots, each knot's
multiplicity raised). Also the small vector helpers
shared by the fill's modules: homogeneous to Cartesian points and tangents, unit vectors, angles.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.linalg import lu_factor
from scipy.linalg.lapack import dgetrs

from .. import tolerances
from ..errors import InvalidGeometryError, ToleranceError
from ..kernel.basis import basis_matrix, greville
from ..kernel.curve import BSplineCurve

__all__ = ["Poly", "scalar_poly", "mult_map", "collocation_sites", "represent", "represent_values", "times_linear",
           "cart", "cart_tangent", "unit", "angle_deg"]

Array = NDArray[np.float64]


class Poly:
    """A vector polynomial in monomial form, ``coef`` shape (deg+1, w)."""

    def __init__(self, coef: Array) -> None:
        self.coef = np.asarray(coef, float)

    @classmethod
    def hermite(cls, conds: Sequence[tuple[float, int, Array]]) -> Poly:
        """The polynomial of degree ``len(conds) - 1`` with ``d^k p(t) = value`` for each condition."""
        m = len(conds)
        A = np.zeros((m, m))
        Y = np.array([np.asarray(c[2], float) for c in conds])
        for row, (t, k, _) in enumerate(conds):
            for c in range(k, m):
                A[row, c] = math.prod(range(c - k + 1, c + 1)) * t ** (c - k)
        return cls(np.linalg.solve(A, Y.reshape(m, -1)))

    def __call__(self, t: float | Array, k: int = 0) -> Array:
        """The ``k``-th derivative (the value for ``k = 0``) at ``t``: shape ``t.shape + (w,)``."""
        t = np.asarray(t, float)
        out = np.zeros(t.shape + self.coef.shape[1:])
        for c in range(k, self.coef.shape[0]):
            out += np.multiply.outer(math.prod(range(c - k + 1, c + 1)) * t ** (c - k), self.coef[c])
        return out

    def __mul__(self, other: Poly) -> Poly:
        """Scalar polynomial (w = 1) times vector polynomial."""
        a, b = self.coef, other.coef
        out = np.zeros((a.shape[0] + b.shape[0] - 1, max(a.shape[1], b.shape[1])))
        for i in range(a.shape[0]):
            out[i:i + b.shape[0]] += a[i] * b
        return Poly(out)

    def __add__(self, other: Poly) -> Poly:
        a, b = self.coef, other.coef
        out = np.zeros((max(a.shape[0], b.shape[0]), a.shape[1]))
        out[:a.shape[0]] += a
        out[:b.shape[0]] += b
        return Poly(out)

    def __neg__(self) -> Poly:
        return Poly(-self.coef)

    def deriv(self) -> Poly:
        """The derivative."""
        c = self.coef
        if c.shape[0] == 1:
            return Poly(np.zeros_like(c))
        return Poly(c[1:] * np.arange(1, c.shape[0])[:, None])


def scalar_poly(coefs: Sequence[float]) -> Poly:
    """The scalar polynomial (w = 1) with the monomial coefficients ``coefs``."""
    return Poly(np.asarray(coefs, float)[:, None])


# ============================================================= spline spaces and exact representations
def mult_map(knots: Array, degree: int) -> dict[float, int]:
    """Interior knots (strictly inside the domain) -> multiplicity."""
    lo, hi = knots[degree], knots[-degree - 1]
    eps = tolerances.FILL_KNOT_END_TOL * (hi - lo)  # a knot within round-off of an end is that end (no sliver span)
    vals, counts = np.unique(knots[(knots > lo + eps) & (knots < hi - eps)], return_counts=True)
    return {float(v): int(c) for v, c in zip(vals, counts)}


@functools.lru_cache(maxsize=256)
def _collocation(degree: int, knots_key: bytes) -> tuple[int, Any, Any, Array, Array]:
    """The number of Greville points, the LU factors (and pivots) of the collocation matrix, the
    Greville points followed by the check points between them, and the check points' basis matrix,
    of the spline space ``(degree, knots)``; cached (a fill asks for the same few spaces many times)."""
    knots = np.frombuffer(knots_key)
    n = len(knots) - degree - 1
    x = greville(knots, degree)
    lu, piv = lu_factor(basis_matrix(knots, degree, n, x)[0])
    xm = np.concatenate((0.5 * (x[:-1] + x[1:]), [knots[degree] + 0.37 * (x[1] - x[0])]))
    Nm = basis_matrix(knots, degree, n, xm)[0]
    at = np.concatenate((x, xm))
    at.flags.writeable = False  # shared by the cache's users
    return x.shape[0], lu, piv, at, Nm


def collocation_sites(degree: int, knots: Array) -> Array:
    """The parameters at which :func:`represent` evaluates its function for the space
    ``(degree, knots)``: the Greville abscissae, then the check points between them (read-only)."""
    return _collocation(int(degree), np.ascontiguousarray(knots, float).tobytes())[3]


def represent(fn: Callable[[Array], Array], degree: int, knots: Array) -> Array:
    """Poles of the spline of ``(degree, knots)`` equal to ``fn`` (which must lie in that space).

    Collocation at the Greville abscissae; verified at the points between them
    (:func:`represent_values` of ``fn`` at :func:`collocation_sites`, which ``fn`` receives as a
    read-only array: the cache's own).
    """
    return represent_values(fn(collocation_sites(degree, knots)), degree, knots)


def represent_values(values: Array, degree: int, knots: Array) -> Array:
    """:func:`represent` given the function's values (m, w) at :func:`collocation_sites`: for
    functions evaluated together (a side and the ribbon across it, from one evaluation).

    The factors are applied by LAPACK's ``dgetrs`` as ``scipy.linalg.lu_solve`` does (the same
    call, without its wrappers: 46 -> 8 us for a 17 x 4 system by timeit, 30 calls a fill of three
    sides); values that are not finite are refused, as its ``check_finite`` did (and the check
    points' too).

    Raises
    ------
    InvalidGeometryError
        Values that are not finite, or not one row per site.
    ToleranceError
        The function is not in the space (the check points miss it by more than
        ``tolerances.FILL_REPRESENT_TOL`` of its size).
    """
    n, lu, piv, at, Nm = _collocation(int(degree), np.ascontiguousarray(knots, float).tobytes())
    Y = np.asarray(values, float)
    if Y.ndim != 2 or Y.shape[0] != at.shape[0]:
        raise InvalidGeometryError(f"internal: expected the values at the {at.shape[0]} collocation sites, one row "
                                   f"each, got shape {Y.shape}")
    Y, Ym = Y[:n], Y[n:]
    top, top_m = float(np.abs(Y).max()), float(np.abs(Ym).max())  # nan where a value is nan
    if not (math.isfinite(top) and math.isfinite(top_m)):
        raise InvalidGeometryError("internal: a ribbon has values that are not finite (inf or nan)")
    Q, info = dgetrs(lu, piv, Y)
    if info != 0:  # pragma: no cover - only for an argument LAPACK finds illegal
        raise InvalidGeometryError(f"internal: dgetrs refused its argument {-info}")
    err = float(np.abs(Nm @ Q - Ym).max()) / max(top, top_m, 1e-300)
    if err > tolerances.FILL_REPRESENT_TOL:
        raise ToleranceError(f"internal: a ribbon is not exactly representable (relative error {err:.2e}); "
                             "the side's knots or continuity are inconsistent")
    return Q


def times_linear(c: BSplineCurve, lam: Callable[[Array], Array]) -> BSplineCurve:
    """``lam(s) c(s)`` for a linear ``lam``: degree + 1, every knot one more time."""
    p = c.degree
    inner = [k for k, m in mult_map(c.knots, p).items() for _ in range(m + 1)]
    K = np.r_[np.zeros(p + 2), sorted(inner), np.ones(p + 2)]
    Q = represent(lambda s: lam(s)[:, None] * c.evaluate(s), p + 1, K)
    return BSplineCurve._trusted(p + 1, K, Q)


# ================================================================================== vectors
def cart(h: Array, rational: bool) -> Array:
    """Cartesian points from homogeneous ones ``(w x, w y, w z, w)`` (``h`` itself if not ``rational``)."""
    return h[..., :3] / h[..., 3:4] if rational else h


def cart_tangent(h: Array, dh: Array, rational: bool) -> Array:
    """Cartesian derivative of the projected curve from homogeneous point and derivative."""
    if not rational:
        return dh
    return (dh[..., :3] - dh[..., 3:4] * (h[..., :3] / h[..., 3:4])) / h[..., 3:4]


def unit(v: Array) -> Array:
    """The vectors along the last axis scaled to length 1 (a zero vector stays zero)."""
    return v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-300)


def angle_deg(a: Array, b: Array) -> Array:
    """Angle between lines (or planes, given normals), in degrees, sign-free."""
    a, b = unit(a), unit(b)
    c = np.abs(np.einsum("...i,...i->...", a, b))
    return np.degrees(np.arctan2(np.linalg.norm(np.cross(a, b), axis=-1), c))
