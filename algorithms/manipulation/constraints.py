"""Constraint objects for direct manipulation (course §4-2, §4-7) and their residuals.

:class:`Position`, :class:`Tangent`, :class:`Derivative` and :class:`Curvature` are small frozen
values naming a property of a curve at a parameter and the value wanted. :func:`bind` checks one
against a curve and turns it into rows: a residual ``F(D)`` of the derivatives
``D = (C(u), C'(u), ..., C^(K)(u))``, its Jacobian ``dF/dD`` and, for the nonlinear ones, the
Hessian of ``lambda . F`` that the Newton-KKT refinement needs. The solver lives in
:mod:`occsurf.algorithms.manipulation.curves`; the surface variant in :mod:`occsurf.algorithms.manipulation.surfaces`.

References
----------
R. H. Bartels, J. C. Beatty, "A technique for the direct manipulation of spline curves",
Graphics Interface '89 (1989). B. Fowler, R. Bartels, "Constraint-based curve manipulation",
IEEE CG&A 13(5) (1993). Course notes C25, SIGGRAPH 1991, §4-2, §4-7 .. §4-12.
"""

from __future__ import annotations

import numbers
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import scipy.linalg as sla
from numpy.typing import ArrayLike, NDArray

from .. import _validate as V
from ..errors import InvalidGeometryError, ParameterError
from .linalg import ConstraintError

__all__ = ["Position", "Tangent", "Derivative", "Curvature", "Constraint", "Rows", "bind"]

Array = NDArray[np.float64]

_AXES = "xyzw"


def as_parameter(u: object, cls: str) -> float:
    """``u`` as a float, checked to be a finite real number (not a bool).

    Raises
    ------
    ParameterError
        Naming ``{cls}.u`` (``cls`` is the constraint class or function that received ``u``).
    """
    if isinstance(u, bool) or not isinstance(u, numbers.Real) or not np.isfinite(float(u)):
        raise ParameterError(f"{cls}.u: expected a finite real parameter, got {u!r}")
    return float(u)


def _vector(v: ArrayLike, name: str) -> Array:
    a = V.as_finite_array(v, name)
    if a.ndim != 1 or a.size < 1:
        raise InvalidGeometryError(f"{name}: expected a vector of shape (d,), got shape {a.shape}")
    return V.readonly(a)


@dataclass(frozen=True, eq=False)
class Position:
    """The curve passes through ``point`` at ``u``: ``C(u) = point`` (course §4-8).

    Parameters
    ----------
    u : float
    point : array_like, shape (d,)
    """

    u: float
    point: Array

    if TYPE_CHECKING:  # the generated __init__ takes array_like; __post_init__ stores a float array

        def __init__(self, u: float, point: ArrayLike) -> None: ...

    def __post_init__(self) -> None:
        object.__setattr__(self, "u", as_parameter(self.u, "Position"))
        object.__setattr__(self, "point", _vector(self.point, "Position.point"))

    @property
    def order(self) -> int:
        return 0

    def __repr__(self) -> str:
        return f"Position(u={self.u:.6g}, point={np.array2string(self.point, precision=4)})"


@dataclass(frozen=True, eq=False)
class Tangent:
    """The first derivative at ``u`` (course §4-9, double constraint systems).

    Parameters
    ----------
    u : float
    vector : array_like, shape (d,), or float
        The derivative ``C'(u)`` wanted. With ``magnitude_only`` a speed ``|C'(u)|`` (a float, or
        a vector whose length is used).
    direction_only : bool
        Only the direction counts: ``C'(u)`` parallel to ``vector`` with the same sense, any
        length. Imposed linearly as ``Q^T C'(u) = 0`` (``Q`` spans the complement of ``vector``);
        if the minimum-norm change would cancel or reverse the tangent, the current speed is kept
        (``C'(u) = |C'_old(u)| vector/|vector|``).
    magnitude_only : bool
        Only the speed ``|C'(u)|`` counts (nonlinear in the poles).
    """

    u: float
    vector: Array
    direction_only: bool = False
    magnitude_only: bool = False

    if TYPE_CHECKING:  # the generated __init__ takes array_like; __post_init__ stores a float array

        def __init__(
            self, u: float, vector: ArrayLike, direction_only: bool = False, magnitude_only: bool = False
        ) -> None: ...

    def __post_init__(self) -> None:
        object.__setattr__(self, "u", as_parameter(self.u, "Tangent"))
        if self.direction_only and self.magnitude_only:
            raise InvalidGeometryError("Tangent: direction_only and magnitude_only exclude each other")
        if self.magnitude_only and np.ndim(self.vector) == 0:
            s = V.as_finite_array(self.vector, "Tangent.vector")
            if s < 0:
                raise InvalidGeometryError(f"Tangent.vector: a speed must be >= 0, got {float(s)!r}")
            object.__setattr__(self, "vector", V.readonly(np.atleast_1d(s)))
            return
        v = _vector(self.vector, "Tangent.vector")
        if self.direction_only and not np.linalg.norm(v) > 0:
            raise InvalidGeometryError("Tangent.vector: a direction must be a non-zero vector")
        object.__setattr__(self, "vector", v)

    @property
    def order(self) -> int:
        return 1

    def __repr__(self) -> str:
        kind = ", direction_only=True" if self.direction_only else ", magnitude_only=True" if self.magnitude_only else ""
        return f"Tangent(u={self.u:.6g}, vector={np.array2string(self.vector, precision=4)}{kind})"


@dataclass(frozen=True, eq=False)
class Derivative:
    """The ``order``-th derivative at ``u`` equals ``vector`` (linear; ``order`` 0..degree).

    ``Derivative(u, 0, p)`` is ``Position(u, p)``, ``Derivative(u, 1, v)`` is ``Tangent(u, v)``;
    ``Derivative(u, 2, a)`` fixes the second derivative (course §4-11, triple constraint systems).
    """

    u: float
    order: int
    vector: Array

    if TYPE_CHECKING:  # the generated __init__ takes array_like; __post_init__ stores a float array

        def __init__(self, u: float, order: int, vector: ArrayLike) -> None: ...

    def __post_init__(self) -> None:
        object.__setattr__(self, "u", as_parameter(self.u, "Derivative"))
        if isinstance(self.order, bool) or not isinstance(self.order, numbers.Integral) or self.order < 0:
            raise InvalidGeometryError(f"Derivative.order: expected an integer >= 0, got {self.order!r}")
        object.__setattr__(self, "order", int(self.order))
        object.__setattr__(self, "vector", _vector(self.vector, "Derivative.vector"))

    def __repr__(self) -> str:
        return f"Derivative(u={self.u:.6g}, order={self.order}, vector={np.array2string(self.vector, precision=4)})"


@dataclass(frozen=True, eq=False)
class Curvature:
    """The curvature at ``u`` (course §4-12, manipulating curvature; nonlinear).

    Parameters
    ----------
    u : float
    value : array_like, shape (d,), or float
        * a vector: the curvature vector ``kappa = (C'' - (C''.T) T) / |C'|^2`` (``T = C'/|C'|``),
          which points to the centre of curvature and has length ``1/radius``; it must be
          perpendicular to the tangent the curve ends up with (else the request conflicts);
          the zero vector asks for an inflection / flat point;
        * a float: the radius of curvature. For planar (2-D) curves it is signed, positive when
          the curve turns left (counter-clockwise); for space curves it is the radius ``> 0``,
          the plane of curvature being free. ``inf`` asks for zero curvature.

    Requires a non-vanishing tangent at ``u`` (the curvature is undefined otherwise).
    """

    u: float
    value: float | Array

    if TYPE_CHECKING:  # the generated __init__ takes array_like; __post_init__ stores a float or a float array

        def __init__(self, u: float, value: ArrayLike) -> None: ...

    def __post_init__(self) -> None:
        object.__setattr__(self, "u", as_parameter(self.u, "Curvature"))
        if np.ndim(self.value) == 0:
            try:
                r = float(self.value)
            except (TypeError, ValueError) as err:
                raise InvalidGeometryError(f"Curvature.value: expected a radius or a vector, got {self.value!r}") from err
            if np.isnan(r) or r == 0:
                raise InvalidGeometryError(f"Curvature.value: a radius must be non-zero (inf for straight), got {r!r}")
            object.__setattr__(self, "value", r)
        else:
            object.__setattr__(self, "value", _vector(self.value, "Curvature.value"))

    @property
    def order(self) -> int:
        return 2

    @property
    def is_radius(self) -> bool:
        return np.ndim(self.value) == 0

    def __repr__(self) -> str:
        v = f"{self.value:.6g}" if self.is_radius else np.array2string(np.asarray(self.value), precision=4)
        return f"Curvature(u={self.u:.6g}, value={v})"


Constraint = Position | Tangent | Derivative | Curvature


# ============================================================================ internal rows
@dataclass
class Rows:
    """One constraint bound to a curve (internal): its residual ``F(D)`` and ``dF/dD``.

    ``D`` holds ``C, C', ..., C^(K)`` at the constraint's parameter, shape ``(K + 1, d)``.
    """

    index: int
    source: Constraint
    u: float
    linear: bool
    names: list[str]
    scale: float
    kind: str
    order: int
    M: Array | None  # linear: F = M @ D[order] - target
    target: Array

    @property
    def size(self) -> int:
        return len(self.names)

    @property
    def label(self) -> str:
        """``"constraints[i] Kind(u=...)"``, for error messages."""
        return self.names[0].split(" [")[0]

    @property
    def orders(self) -> tuple[int, ...]:
        """Derivative orders the residual depends on."""
        if self.linear:
            return (self.order,)
        return (1,) if self.kind == "speed" else (1, 2)

    def hessian(self, D: Array, lam: Array, K: int) -> Array:
        """Hessian of ``lam . F`` with respect to ``D``, shape ``((K+1) d, (K+1) d)``.

        Zero for linear rows; for nonlinear ones by central differences of the analytic gradient
        ``lam . dF/dD`` (step ``1e-5`` relative): accurate to ~1e-10, which is all the Newton-KKT
        refinement needs (the KKT residual it drives to zero is evaluated exactly).
        """
        n = D.size
        if self.linear:
            return np.zeros((n, n))
        flat = D.ravel()
        H = np.empty((n, n))
        for j in range(n):  # (K + 1) * d <= 12 columns: a loop over coordinates, not points
            h = 1e-5 * max(1.0, abs(flat[j]))
            e = np.zeros(n)
            e[j] = h
            gp = lam @ self.residual((flat + e).reshape(D.shape), K)[1].reshape(self.size, n)
            gm = lam @ self.residual((flat - e).reshape(D.shape), K)[1].reshape(self.size, n)
            H[:, j] = (gp - gm) / (2 * h)
        return 0.5 * (H + H.T)

    def residual(self, D: Array, K: int) -> tuple[Array, Array]:
        d = D.shape[-1]
        if self.linear:
            if self.M is None:  # bind gives every linear row its matrix
                raise ValueError(f"{self.label}: a linear row needs its matrix M")
            F = self.M @ D[self.order] - self.target
            dF = np.zeros((self.size, K + 1, d))
            dF[:, self.order, :] = self.M
            return F, dF
        return _NONLINEAR[self.kind](self, D, K)


def _tangent_of(D: Array, row: Rows) -> tuple[Array, np.float64]:
    a = D[1]
    s = np.float64(a @ a)  # a NumPy scalar: overflow at wild trial points gives inf, not an exception
    if not s > 0:
        raise ConstraintError(f"{row.label}: the tangent vanishes at u={row.u:.6g}, so the curvature / speed is "
                              "undefined there", [row.index], [row.label])
    return a, s


def _curvature_jacobian(a: Array, b: Array, s: np.float64) -> tuple[Array, Array, Array]:
    """``kappa`` and its partials with respect to ``a = C'`` and ``b = C''``."""
    ab = np.float64(a @ b)
    I = np.eye(a.shape[0])
    kappa = b / s - ab * a / s**2
    dk_db = (I - np.outer(a, a) / s) / s
    dk_da = (-2.0 * np.outer(b, a) - np.outer(a, b) - ab * I) / s**2 + 4.0 * ab * np.outer(a, a) / s**3
    return kappa, dk_da, dk_db


def _res_curvature_vector(row: Rows, D: Array, K: int) -> tuple[Array, Array]:
    a, s = _tangent_of(D, row)
    kappa, dk_da, dk_db = _curvature_jacobian(a, D[2], s)
    dF = np.zeros((a.shape[0], K + 1, a.shape[0]))
    dF[:, 1, :] = dk_da
    dF[:, 2, :] = dk_db
    return kappa - row.target, dF


def _res_curvature_signed(row: Rows, D: Array, K: int) -> tuple[Array, Array]:
    a, s = _tangent_of(D, row)
    b = D[2]
    cr = a[0] * b[1] - a[1] * b[0]
    k = cr / s**1.5
    dF = np.zeros((1, K + 1, 2))
    dF[0, 1] = np.array([b[1], -b[0]]) / s**1.5 - 3.0 * cr * a / s**2.5
    dF[0, 2] = np.array([-a[1], a[0]]) / s**1.5
    return np.array([k - row.target[0]]), dF


def _res_curvature_magnitude(row: Rows, D: Array, K: int) -> tuple[Array, Array]:
    a, s = _tangent_of(D, row)
    kappa, dk_da, dk_db = _curvature_jacobian(a, D[2], s)
    nk = float(np.linalg.norm(kappa))
    if not nk > 0:
        raise ConstraintError(f"{row.label}: the curve is straight at u={row.u:.6g}, so a radius alone does not "
                              "say which way to bend it; give a curvature vector instead", [row.index], [row.label])
    e = kappa / nk
    dF = np.zeros((1, K + 1, a.shape[0]))
    dF[0, 1] = e @ dk_da
    dF[0, 2] = e @ dk_db
    return np.array([nk - row.target[0]]), dF


def _res_speed(row: Rows, D: Array, K: int) -> tuple[Array, Array]:
    a, s = _tangent_of(D, row)
    r = np.sqrt(s)
    dF = np.zeros((1, K + 1, a.shape[0]))
    dF[0, 1] = a / r
    return np.array([r - row.target[0]]), dF


_NONLINEAR = {
    "curvature": _res_curvature_vector,
    "curvature_signed": _res_curvature_signed,
    "curvature_radius": _res_curvature_magnitude,
    "speed": _res_speed,
}


def bind(c: object, i: int, dim: int, degree: int, domain: tuple[float, float]) -> Rows:
    """Validate constraint ``i`` against a curve (dimension, degree, domain) and turn it into rows.

    Raises
    ------
    InvalidGeometryError
        Not a constraint object, wrong vector size, derivative order above the degree.
    ParameterError
        ``u`` outside the domain (message names ``constraints[i].u``).
    ConstraintError
        Curvature on a degree-1 curve.
    """
    if not isinstance(c, (Position, Tangent, Derivative, Curvature)):
        raise InvalidGeometryError(
            f"constraints[{i}]: expected Position, Tangent, Derivative or Curvature, got {type(c).__name__}")
    u = float(V.check_parameters(c.u, *domain, name=f"constraints[{i}].u"))
    label = f"constraints[{i}] {type(c).__name__}(u={u:.6g})"
    axes = [f"{label} [{_AXES[j] if dim <= 4 else j}]" for j in range(dim)]
    I = np.eye(dim)

    def vec(v: Array, what: str) -> Array:
        if v.shape != (dim,):
            raise InvalidGeometryError(f"constraints[{i}].{what}: expected shape ({dim},) for a {dim}-D curve, got {v.shape}")
        return v

    def scale(v: ArrayLike) -> float:
        return max(1.0, float(np.max(np.abs(v))) if np.size(v) else 0.0)

    if isinstance(c, Position):
        t = vec(c.point, "point")
        return Rows(i, c, u, True, axes, scale(t), "position", 0, I, t)
    if isinstance(c, Derivative):
        if c.order > degree:
            raise InvalidGeometryError(f"constraints[{i}].order: a degree-{degree} curve has no non-zero derivative "
                                       f"of order {c.order}")
        t = vec(c.vector, "vector")
        return Rows(i, c, u, True, axes, scale(t), "derivative", c.order, I, t)
    if isinstance(c, Tangent):
        if c.magnitude_only:
            if c.vector.size > 1:
                vec(c.vector, "vector")
            sp = float(np.linalg.norm(c.vector))  # the speed, or the length of the vector given
            return Rows(i, c, u, False, [f"{label} [speed]"], scale(sp), "speed", 1, None, np.array([sp]))
        t = vec(c.vector, "vector")
        if c.direction_only and dim < 2:
            raise InvalidGeometryError(f"constraints[{i}]: a direction-only tangent needs a curve of dimension >= 2")
        if c.direction_only:
            e = t / np.linalg.norm(t)
            Q = sla.null_space(e[None, :])  # (d, d-1), orthonormal complement of the direction
            names = [f"{label} [perp {j}]" for j in range(dim - 1)]
            return Rows(i, c, u, True, names, 1.0, "direction", 1, Q.T, np.zeros(dim - 1))
        return Rows(i, c, u, True, axes, scale(t), "derivative", 1, I, t)
    # Curvature
    if dim < 2:
        raise InvalidGeometryError(f"constraints[{i}]: curvature needs a curve of dimension >= 2, got {dim}")
    if degree < 2:
        raise ConstraintError(f"{label}: a degree-1 curve has no curvature to edit", [i], [label])
    if c.is_radius:
        r = float(c.value)
        if dim == 2:
            k = 0.0 if np.isinf(r) else 1.0 / r
            return Rows(i, c, u, False, [f"{label} [signed curvature]"], scale(k), "curvature_signed", 2, None,
                         np.array([k]))
        if r < 0:
            raise InvalidGeometryError(f"constraints[{i}].value: a radius of a {dim}-D curve must be > 0, got {r!r}")
        if np.isinf(r):
            return Rows(i, c, u, False, [f"{label} [kappa {a}]" for a in "xyzw"[:dim]], 1.0, "curvature", 2, None,
                         np.zeros(dim))
        return Rows(i, c, u, False, [f"{label} [|kappa|]"], scale(1.0 / r), "curvature_radius", 2, None,
                     np.array([1.0 / r]))
    kv = vec(np.asarray(c.value), "value")
    return Rows(i, c, u, False, [f"{label} [kappa {_AXES[j] if dim <= 4 else j}]" for j in range(dim)], scale(kv),
                 "curvature", 2, None, kv)


# ============================================================================ shared validation
def movable_indices(movable: object, n: int, name: str = "movable") -> NDArray[np.intp]:
    """Indices (sorted, unique) of the movable poles from None / slice / range / ints / mask."""
    if movable is None:
        return np.arange(n)
    if isinstance(movable, slice):
        idx = np.arange(n)[movable]
    else:
        a = np.asarray(movable)
        if a.dtype == bool:
            if a.shape != (n,):
                raise InvalidGeometryError(f"{name}: a boolean mask needs shape ({n},), got {a.shape}")
            idx = np.nonzero(a)[0]
        else:
            if a.ndim != 1 or (a.size and not np.issubdtype(a.dtype, np.integer)):
                raise InvalidGeometryError(f"{name}: expected pole indices (1-D integers), a slice or a mask, got {movable!r}")
            idx = a.astype(np.intp)
            if idx.size and (idx.min() < 0 or idx.max() >= n):
                bad = idx.min() if idx.min() < 0 else idx.max()
                raise InvalidGeometryError(f"{name}: pole index {int(bad)} is out of range 0..{n - 1}")
    idx = np.unique(idx)
    if idx.size == 0:
        raise InvalidGeometryError(f"{name}: the window of movable poles is empty")
    return idx


def pole_weights(weights: ArrayLike | None, shape: tuple[int, ...]) -> Array | None:
    if weights is None:
        return None
    w = V.as_finite_array(weights, "weights")
    if w.shape != shape:
        raise InvalidGeometryError(f"weights: expected one positive weight per pole, shape {shape}, got {w.shape}")
    if np.any(w <= 0):
        raise InvalidGeometryError(f"weights: the norm weights must be > 0, got {float(w.min())!r}")
    return w


def pole_index(i: object, name: str, n: int) -> int:
    if isinstance(i, bool) or not isinstance(i, numbers.Integral):
        raise InvalidGeometryError(f"{name}: expected a pole index (int), got {i!r}")
    if not 0 <= int(i) < n:
        raise InvalidGeometryError(f"{name}: pole index {int(i)} is out of range 0..{n - 1}")
    return int(i)
