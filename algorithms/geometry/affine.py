"""Coordinate-free geometric programming: vectorised affine types (course ch. 1, §1-5..1-30).

DeRose's geometric abstract data type separates the *kinds* of geometric objects so that
coordinate-dependent mistakes become type errors (course §1-5..1-30):

=========================  ===========================================================
operation                  result
=========================  ===========================================================
point - point              :class:`Vector`
point ± vector             :class:`Point`
vector ± vector            :class:`Vector`
scalar · vector            :class:`Vector`
vector · vector            ``dot`` (an array of scalars); ``cross`` (3-D) a vector
normal · vector            ``dot`` (the pairing of a dual vector with a vector)
point + point, s · point   ``TypeError`` (not coordinate-free)
sum w_i P_i, sum w_i = 1   :func:`affine_combination` (a point)
=========================  ===========================================================

Every element type holds *many* elements: ``coords`` has shape ``(..., d)``, the last axis being
coordinates (STYLE "Data"), so one million points cost one NumPy operation. Leading shapes
broadcast as in NumPy; scalars may be arrays of the leading shape.

Maps act on the kinds differently (course §1-20..1-30): an :class:`AffineMap` ``x -> M x + t``
moves points by ``M p + t``, vectors by ``M v``, and normals by the inverse transpose
``M^{-T} n`` (so that ``n · v = 0`` survives non-uniform scaling and shear). A
:class:`ProjectiveMap` acts on points through homogeneous coordinates and maps rational splines
exactly (:meth:`ProjectiveMap.apply_to`).

NumPy arrays are deliberately *not* accepted where a typed element is expected: wrap them in
:class:`Point`, :class:`Vector` or :class:`Normal` to say what they are.
"""

from __future__ import annotations

import numbers
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, ClassVar, TypeVar, Union

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import tolerances
from ..kernel.curve import BSplineCurve
from ..errors import InvalidGeometryError
from ..kernel.surface import BSplineSurface

__all__ = [
    "MAX_CONDITION",
    "Point",
    "Vector",
    "Normal",
    "Frame",
    "AffineMap",
    "ProjectiveMap",
    "affine_combination",
    "vector_combination",
]

Array = NDArray[np.float64]
Spline = Union[BSplineCurve, BSplineSurface]

#: Kept for compatibility; the value used is ``tolerances.MAX_CONDITION`` (overridable).
MAX_CONDITION: float = tolerances.MAX_CONDITION


# ---------------------------------------------------------------------------------------- helpers
def _readonly(a: Array) -> Array:
    a = np.ascontiguousarray(a, dtype=float)
    a.flags.writeable = False
    return a


def _as_coords(value: ArrayLike, name: str) -> Array:
    """Validated ``(..., d)`` coordinates: real, finite, at least 1-D, ``d >= 1``."""
    if isinstance(value, _Element):
        raise TypeError(f"{name}: expected raw coordinates, got a {type(value).__name__}; "
                        f"use its .coords or convert explicitly")
    try:
        a = np.array(value, dtype=float)
    except (TypeError, ValueError) as err:
        raise InvalidGeometryError(f"{name}: expected an array of real numbers, got {type(value).__name__}") from err
    if a.ndim < 1 or a.shape[-1] < 1:
        raise InvalidGeometryError(f"{name}: expected shape (..., d) with d >= 1, got {a.shape}")
    if not np.all(np.isfinite(a)):
        bad = tuple(int(i) for i in np.argwhere(~np.isfinite(a))[0])
        raise InvalidGeometryError(f"{name}: expected finite values, got {a[bad]} at index {bad}")
    return a


def _as_matrix(value: ArrayLike, name: str, dim: int | None = None) -> Array:
    try:
        M = np.array(value, dtype=float)
    except (TypeError, ValueError) as err:
        raise InvalidGeometryError(f"{name}: expected a square matrix of real numbers, got {type(value).__name__}") from err
    if M.ndim != 2 or M.shape[0] != M.shape[1] or M.shape[0] < 1:
        raise InvalidGeometryError(f"{name}: expected a square matrix, got shape {M.shape}")
    if dim is not None and M.shape[0] != dim:
        raise InvalidGeometryError(f"{name}: expected shape {(dim, dim)}, got {M.shape}")
    if not np.all(np.isfinite(M)):
        raise InvalidGeometryError(f"{name}: expected finite values")
    return M


def _check_invertible(M: Array, name: str, max_condition: float) -> None:
    cond = np.linalg.cond(M)
    if not np.isfinite(cond) or cond > max_condition:
        raise InvalidGeometryError(
            f"{name}: expected an invertible matrix (condition number <= {max_condition:g}), got condition {cond:.3g}"
        )


def _scalar(value: object) -> Array | None:
    """``value`` as a float array of scalars, or ``None`` if it is not a scalar (array)."""
    if isinstance(value, (_Element, Frame, AffineMap, ProjectiveMap)) or isinstance(value, (str, bytes)):
        return None
    if isinstance(value, numbers.Real) and not isinstance(value, bool):
        return np.asarray(float(value))
    if isinstance(value, (np.ndarray, np.generic, list, tuple)):
        try:
            a = np.asarray(value, dtype=float)
        except (TypeError, ValueError):
            return None
        return a
    return None


def _broadcast(a: Array, b: Array, name: str) -> None:
    """Check that two ``(..., d)`` coordinate arrays have the same ``d`` and broadcastable leading shapes."""
    if a.shape[-1] != b.shape[-1]:
        raise InvalidGeometryError(f"{name}: expected dimension {a.shape[-1]}, got {b.shape[-1]}")
    try:
        np.broadcast_shapes(a.shape, b.shape)
    except ValueError as err:
        raise InvalidGeometryError(
            f"{name}: leading shape {b.shape[:-1]} does not broadcast against {a.shape[:-1]}"
        ) from err


def _scale(coords: Array, s: Array, name: str) -> Array:
    try:
        np.broadcast_shapes(coords.shape[:-1], s.shape)
    except ValueError as err:
        raise InvalidGeometryError(
            f"{name}: scalar shape {s.shape} does not broadcast against the leading shape {coords.shape[:-1]}"
        ) from err
    if not np.all(np.isfinite(s)):
        raise InvalidGeometryError(f"{name}: expected finite scalars, got {float(s[~np.isfinite(s)].ravel()[0])!r}")
    return coords * s[..., None]


E = TypeVar("E", bound="_Element")


# ---------------------------------------------------------------------------------------- elements
@dataclass(frozen=True, eq=False, repr=False)
class _Element:
    """Common storage of :class:`Point`, :class:`Vector` and :class:`Normal`.

    Parameters
    ----------
    coords : array_like, shape (..., d)
        Coordinates relative to the world (standard) frame; read-only after construction.
    """

    coords: Array

    # numpy must not turn ``ndarray * element`` into an elementwise object loop: defer to us.
    __array_ufunc__: ClassVar[None] = None
    _kind: ClassVar[str] = "element"

    def __post_init__(self) -> None:
        object.__setattr__(self, "coords", _readonly(_as_coords(self.coords, "coords")))

    @classmethod
    def _trusted(cls: type[E], coords: Array) -> E:
        """Fast constructor for internal results (no validation, may hold inf at infinity)."""
        obj = object.__new__(cls)
        object.__setattr__(obj, "coords", _readonly(coords))
        return obj

    @property
    def dim(self) -> int:
        """Number of coordinates ``d``."""
        return self.coords.shape[-1]

    @property
    def shape(self) -> tuple[int, ...]:
        """Leading shape: ``coords.shape[:-1]`` (``()`` for a single element)."""
        return self.coords.shape[:-1]

    def __len__(self) -> int:
        if not self.shape:
            raise TypeError(f"len() of a single {self._kind}")
        return self.shape[0]

    def __getitem__(self: E, key: Any) -> E:
        """Index the leading axes only (the coordinate axis is never indexed)."""
        if not self.shape:
            raise TypeError(f"a single {self._kind} cannot be indexed")
        key = key if isinstance(key, tuple) else (key,)
        c = np.moveaxis(self.coords, -1, 0)[(slice(None),) + key]
        return type(self)._trusted(np.moveaxis(c, 0, -1))

    def reshape(self: E, *shape: int) -> E:
        """Same elements with leading shape ``shape``."""
        if len(shape) == 1 and isinstance(shape[0], tuple):
            shape = shape[0]
        return type(self)._trusted(self.coords.reshape(tuple(shape) + (self.dim,)))

    def __repr__(self) -> str:
        if not self.shape:
            return f"{type(self).__name__}({self.coords.tolist()})"
        return f"{type(self).__name__}(shape={self.shape}, dim={self.dim})"

    def __bool__(self) -> bool:
        raise TypeError(f"the truth value of a {self._kind} is ambiguous")

    # Forbidden operations shared by all kinds; subclasses override what is allowed.
    def _forbid(self, op: str, other: object, reflected: bool = False) -> Any:
        a, b = _kind_of(other), self._kind
        left, right = (a, b) if reflected else (b, a)
        raise TypeError(
            f"{left} {op} {right} is not a coordinate-free operation (course §1-5..1-30); "
            f"allowed: point - point, point ± vector, vector ± vector, scalar * vector, "
            f"affine_combination(points, weights summing to 1)"
        )

    def __add__(self, other: object) -> Any:
        return self._forbid("+", other)

    def __radd__(self, other: object) -> Any:
        return self._forbid("+", other, True)

    def __sub__(self, other: object) -> Any:
        return self._forbid("-", other)

    def __rsub__(self, other: object) -> Any:
        return self._forbid("-", other, True)

    def __mul__(self, other: object) -> Any:
        return self._forbid("*", other)

    def __rmul__(self, other: object) -> Any:
        return self._forbid("*", other, True)

    def __truediv__(self, other: object) -> Any:
        return self._forbid("/", other)

    def __rtruediv__(self, other: object) -> Any:
        return self._forbid("/", other, True)

    def __matmul__(self, other: object) -> Any:
        return self._forbid("@", other)

    def __rmatmul__(self, other: object) -> Any:
        return self._forbid("@", other, True)

    def __neg__(self) -> Any:
        raise TypeError(f"-{self._kind} is not a coordinate-free operation (course §1-5..1-30)")

    def __pos__(self) -> Any:
        raise TypeError(f"+{self._kind} is not a coordinate-free operation (course §1-5..1-30)")

    def allclose(self, other: _Element, rtol: float = 1e-12, atol: float = 0.0) -> bool:
        """``True`` if ``other`` has the same kind and all coordinates agree within tolerances."""
        if type(other) is not type(self):
            return False
        _broadcast(self.coords, other.coords, "other")
        return bool(np.allclose(self.coords, other.coords, rtol=rtol, atol=atol))


def _kind_of(x: object) -> str:
    if isinstance(x, _Element):
        return x._kind
    if _scalar(x) is not None:
        return "scalar"
    return type(x).__name__


@dataclass(frozen=True, eq=False, repr=False)
class _Linear(_Element):
    """Scaling, division by a scalar and negation, shared by the two vector spaces (vectors and
    normals); each result keeps the operand's type."""

    def __mul__(self, other: object) -> Any:
        s = _scalar(other)
        if s is None:
            return self._forbid("*", other)
        return type(self)._trusted(_scale(self.coords, s, "scalar"))

    def __rmul__(self, other: object) -> Any:
        s = _scalar(other)
        if s is None:
            return self._forbid("*", other, True)
        return type(self)._trusted(_scale(self.coords, s, "scalar"))

    def __truediv__(self, other: object) -> Any:
        s = _scalar(other)
        if s is None:
            return self._forbid("/", other)
        if np.any(s == 0):
            raise InvalidGeometryError("scalar: division by zero")
        return type(self)._trusted(_scale(self.coords, 1.0 / s, "scalar"))

    def __neg__(self) -> Any:
        return type(self)._trusted(-self.coords)

    def __pos__(self) -> Any:
        return self


@dataclass(frozen=True, eq=False, repr=False)
class Point(_Element):
    """Points of an affine space, shape ``(..., d)`` (course §1-5..1-30).

    Parameters
    ----------
    coords : array_like, shape (..., d)
        World coordinates of the points.

    Notes
    -----
    ``point - point`` is a :class:`Vector`, ``point ± vector`` a point. ``point + point`` and
    ``scalar * point`` raise ``TypeError``: their result depends on the choice of origin. Use
    :func:`affine_combination` (weights summing to one) instead.

    Examples
    --------
    >>> p, q = Point([0.0, 0.0, 0.0]), Point([1.0, 2.0, 2.0])
    >>> float((q - p).norm())
    3.0
    """

    _kind: ClassVar[str] = "point"

    def __add__(self, other: object) -> Point:
        if isinstance(other, Vector):
            _broadcast(self.coords, other.coords, "other")
            return Point._trusted(self.coords + other.coords)
        return self._forbid("+", other)

    def __radd__(self, other: object) -> Point:
        if isinstance(other, Vector):
            _broadcast(self.coords, other.coords, "other")
            return Point._trusted(self.coords + other.coords)
        return self._forbid("+", other, True)

    def __sub__(self, other: object) -> Any:
        if isinstance(other, Point):
            _broadcast(self.coords, other.coords, "other")
            return Vector._trusted(self.coords - other.coords)
        if isinstance(other, Vector):
            _broadcast(self.coords, other.coords, "other")
            return Point._trusted(self.coords - other.coords)
        return self._forbid("-", other)

    def distance(self, other: Point) -> Array:
        """Euclidean distance ``|self - other|``, shape of the broadcast leading shapes."""
        return (self - other).norm()


@dataclass(frozen=True, eq=False, repr=False)
class Vector(_Linear):
    """Free vectors (displacements), shape ``(..., d)`` (course §1-5..1-30).

    Parameters
    ----------
    coords : array_like, shape (..., d)
        Components in the world frame.

    Notes
    -----
    Vectors form a vector space: ``v ± w``, ``s * v``, ``v / s``, ``-v``; ``s`` may be an array of
    the leading shape. ``v.dot(w)`` and (3-D) ``v.cross(w)`` are the Euclidean products.
    """

    _kind: ClassVar[str] = "vector"

    def __add__(self, other: object) -> Any:
        if isinstance(other, Vector):
            _broadcast(self.coords, other.coords, "other")
            return Vector._trusted(self.coords + other.coords)
        if isinstance(other, Point):
            _broadcast(self.coords, other.coords, "other")
            return Point._trusted(self.coords + other.coords)
        return self._forbid("+", other)

    def __sub__(self, other: object) -> Vector:
        if isinstance(other, Vector):
            _broadcast(self.coords, other.coords, "other")
            return Vector._trusted(self.coords - other.coords)
        return self._forbid("-", other)

    def dot(self, other: Vector | Normal) -> Array:
        """Euclidean inner product (or the pairing with a :class:`Normal`), shape ``(...)``."""
        if not isinstance(other, (Vector, Normal)):
            raise TypeError(f"vector . {_kind_of(other)} is not defined; dot takes a vector or a normal")
        _broadcast(self.coords, other.coords, "other")
        return np.einsum("...i,...i->...", self.coords, other.coords)

    def cross(self, other: Vector) -> Vector:
        """Cross product of 3-D vectors, shape ``(..., 3)``."""
        if not isinstance(other, Vector):
            raise TypeError(f"vector x {_kind_of(other)} is not defined; cross takes a vector")
        if self.dim != 3:
            raise InvalidGeometryError(f"cross: defined for 3-D vectors, got dimension {self.dim}")
        _broadcast(self.coords, other.coords, "other")
        return Vector._trusted(np.cross(self.coords, other.coords))

    def norm(self) -> Array:
        """Euclidean length, shape ``(...)``."""
        return np.linalg.norm(self.coords, axis=-1)

    def normalized(self) -> Vector:
        """Unit vectors; raises :class:`InvalidGeometryError` if any vector is zero."""
        return Vector._trusted(_unit(self.coords, "vector"))


def _unit(c: Array, name: str) -> Array:
    """Unit vectors along the last axis; scaled first by the largest component (no overflow)."""
    m = np.max(np.abs(c), axis=-1, keepdims=True)
    if not np.all(np.isfinite(m)):
        raise InvalidGeometryError(f"{name}: cannot normalise a non-finite {name}")
    if np.any(m == 0):
        raise InvalidGeometryError(f"{name}: cannot normalise a zero {name}")
    c = c / m
    return c / np.linalg.norm(c, axis=-1, keepdims=True)


@dataclass(frozen=True, eq=False, repr=False)
class Normal(_Linear):
    """Normal vectors: dual vectors (covectors), shape ``(..., d)`` (course §1-20..1-30).

    A normal ``n`` is the linear functional ``v -> n · v``; it transforms by the inverse
    transpose of a map's linear part, so that perpendicularity to tangent vectors is preserved:

    .. math::

        n' = M^{-T} n, \\qquad n' \\cdot (M v) = n^T M^{-1} M v = n \\cdot v.

    Parameters
    ----------
    coords : array_like, shape (..., d)
        Components in the world frame.

    Notes
    -----
    Normals form a vector space of their own (``n ± m``, ``s * n``, ``-n``); adding a normal to a
    vector or point raises ``TypeError``.
    """

    _kind: ClassVar[str] = "normal"

    @classmethod
    def from_tangents(cls, a: Vector, b: Vector) -> Normal:
        """The normal ``a x b`` of the plane spanned by two 3-D tangent vectors (not normalised)."""
        if not (isinstance(a, Vector) and isinstance(b, Vector)):
            raise TypeError("from_tangents: expected two Vectors")
        return cls._trusted(a.cross(b).coords)

    def __add__(self, other: object) -> Normal:
        if isinstance(other, Normal):
            _broadcast(self.coords, other.coords, "other")
            return Normal._trusted(self.coords + other.coords)
        return self._forbid("+", other)

    def __sub__(self, other: object) -> Normal:
        if isinstance(other, Normal):
            _broadcast(self.coords, other.coords, "other")
            return Normal._trusted(self.coords - other.coords)
        return self._forbid("-", other)

    def dot(self, other: Vector) -> Array:
        """The pairing ``n · v`` with vectors, shape ``(...)``."""
        if not isinstance(other, Vector):
            raise TypeError(f"normal . {_kind_of(other)} is not defined; a normal pairs with a vector")
        _broadcast(self.coords, other.coords, "other")
        return np.einsum("...i,...i->...", self.coords, other.coords)

    def norm(self) -> Array:
        """Euclidean length, shape ``(...)``."""
        return np.linalg.norm(self.coords, axis=-1)

    def normalized(self) -> Normal:
        """Unit normals; raises :class:`InvalidGeometryError` if any normal is zero."""
        return Normal._trusted(_unit(self.coords, "normal"))


# ---------------------------------------------------------------------------------------- combinations
def _stack(points: Point | Sequence[Point], name: str) -> Array:
    """``(..., k, d)`` coordinates from a Point array or a sequence of ``k`` Points."""
    if isinstance(points, Point):
        if not points.shape:
            raise InvalidGeometryError(f"{name}: expected shape (..., k, d), got a single point")
        return points.coords
    if isinstance(points, (list, tuple)) and points and all(isinstance(p, Point) for p in points):
        dims = {p.dim for p in points}
        if len(dims) != 1:
            raise InvalidGeometryError(f"{name}: all points must have the same dimension, got {sorted(dims)}")
        try:
            shape = np.broadcast_shapes(*(p.coords.shape for p in points))
        except ValueError as err:
            raise InvalidGeometryError(f"{name}: the points' leading shapes do not broadcast") from err
        return np.stack([np.broadcast_to(p.coords, shape) for p in points], axis=-2)
    raise TypeError(f"{name}: expected a Point array of shape (..., k, d) or a non-empty sequence of Points, "
                    f"got {type(points).__name__}")


def _weighted(P: Array, weights: ArrayLike) -> tuple[Array, Array]:
    w = np.array(weights, dtype=float) if not isinstance(weights, _Element) else None
    if w is None:
        raise TypeError("weights: expected an array of scalars")
    if w.ndim < 1 or not np.all(np.isfinite(w)):
        raise InvalidGeometryError(f"weights: expected finite values of shape (..., k), got shape {w.shape}")
    if w.shape[-1] != P.shape[-2]:
        raise InvalidGeometryError(f"weights: expected {P.shape[-2]} weights (one per point), got {w.shape[-1]}")
    try:
        np.broadcast_shapes(w.shape, P.shape[:-1])
    except ValueError as err:
        raise InvalidGeometryError(f"weights: shape {w.shape} does not broadcast against points {P.shape[:-1]}") from err
    return w, np.einsum("...k,...kd->...d", w, P)


def affine_combination(points: Point | Sequence[Point], weights: ArrayLike, *, tol: float | None = None) -> Point:
    """The affine combination ``sum_i w_i P_i`` with ``sum_i w_i = 1`` (course §1-5..1-30).

    Parameters
    ----------
    points : Point, shape (..., k, d), or sequence of k Points of shape (..., d)
        The points combined (axis ``-2`` runs over the ``k`` points).
    weights : array_like, shape (..., k)
        Weights, broadcastable against the points' leading shape; each row must sum to one.
    tol : float, optional
        Allowed ``|sum w - 1|`` relative to ``max(1, sum |w|)``; default
        :data:`occsurf.algorithms.tolerances.WEIGHT_SUM`.

    Returns
    -------
    Point, shape (..., d)

    Raises
    ------
    InvalidGeometryError
        If some row of weights does not sum to one within the tolerance, or shapes mismatch.

    Notes
    -----
    The result does not depend on the origin because the weights sum to one:
    ``sum w_i (P_i - O) + O`` for any ``O``. Barycentric coordinates are the typical weights.
    """
    P = _stack(points, "points")
    w, x = _weighted(P, weights)
    _check_sum(w, 1.0, tol)
    return Point._trusted(x)


def vector_combination(points: Point | Sequence[Point], weights: ArrayLike, *, tol: float | None = None) -> Vector:
    """The combination ``sum_i w_i P_i`` with ``sum_i w_i = 0``, a :class:`Vector` (course §1-5..1-30).

    Parameters and errors as :func:`affine_combination`, with the weights summing to zero
    (e.g. ``P_1 - P_0`` is ``weights = [-1, 1]``; finite differences of control points).
    """
    P = _stack(points, "points")
    w, x = _weighted(P, weights)
    _check_sum(w, 0.0, tol)
    return Vector._trusted(x)


def _check_sum(w: Array, target: float, tol: float | None) -> None:
    tol = tolerances.WEIGHT_SUM if tol is None else float(tol)
    s = w.sum(axis=-1)
    scale = np.maximum(1.0, np.abs(w).sum(axis=-1))
    bad = np.abs(s - target) > tol * scale
    if np.any(bad):
        i = tuple(int(j) for j in np.argwhere(bad)[0]) if np.ndim(bad) else ()
        raise InvalidGeometryError(
            f"weights: expected weights summing to {target:g} (tolerance {tol:g} relative), "
            f"got sum {float(np.asarray(s)[i])!r}" + (f" at index {i}" if i else "")
        )


# Frames and maps live in affine_maps.py (this module would pass 800 lines); re-exported here so
# ``from occsurf.algorithms.geometry.affine import Frame`` keeps working. Imported last: affine_maps uses the types above.
from .affine_maps import AffineMap, Frame, ProjectiveMap  # noqa: E402
