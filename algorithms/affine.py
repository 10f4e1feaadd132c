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
from dataclasses import dataclass, field
from typing import Any, ClassVar, Literal, TypeVar, Union

import numpy as np
from numpy.typing import ArrayLike, NDArray

from . import tolerances
from .curve import BSplineCurve
from .errors import InvalidGeometryError
from .surface import BSplineSurface

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

#: A frame basis (or a matrix that must be inverted) whose 2-norm condition number exceeds this
#: is treated as singular: its inverse would lose more than ~12 of 16 significant digits.
MAX_CONDITION: float = 1e12


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
        :data:`algorithms.tolerances.WEIGHT_SUM`.

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


# ---------------------------------------------------------------------------------------- frames
_Kind = Union[type[Point], type[Vector], type[Normal], Literal["point", "vector", "normal"]]
_KINDS: dict[str, type[_Element]] = {"point": Point, "vector": Vector, "normal": Normal}


@dataclass(frozen=True, eq=False)
class Frame:
    """An affine frame: an origin and a basis of vectors (course §1-5..1-30).

    A point with frame coordinates ``c`` is ``origin + B c``; a vector is ``B c``. The basis need
    not be orthonormal, only invertible.

    Parameters
    ----------
    origin : Point or array_like, shape (d,)
        The frame's origin (a single point).
    basis : array_like, shape (d, d)
        Columns are the axes ``e_1 .. e_d`` in world coordinates.

    Raises
    ------
    InvalidGeometryError
        Naming the argument: wrong shapes, non-finite values, or a basis whose condition number
        exceeds :data:`MAX_CONDITION`.
    """

    origin: Point
    basis: Array
    _inverse: Array = field(init=False, repr=False)

    def __post_init__(self) -> None:
        o = self.origin
        o_c = o.coords if isinstance(o, Point) else _as_coords(o, "origin")
        if isinstance(o, (Vector, Normal)):
            raise TypeError(f"origin: expected a Point, got a {o._kind}")
        if o_c.ndim != 1:
            raise InvalidGeometryError(f"origin: expected a single point of shape (d,), got {o_c.shape}")
        B = _as_matrix(self.basis, "basis", o_c.shape[0])
        _check_invertible(B, "basis", MAX_CONDITION)
        object.__setattr__(self, "origin", Point._trusted(o_c))
        object.__setattr__(self, "basis", _readonly(B))
        object.__setattr__(self, "_inverse", _readonly(np.linalg.inv(B)))

    @classmethod
    def standard(cls, dim: int = 3) -> Frame:
        """The world frame: origin 0, basis the identity."""
        return cls(Point(np.zeros(dim)), np.eye(dim))

    @classmethod
    def orthonormal(cls, origin: Point | ArrayLike, x_dir: Vector | ArrayLike, z_dir: Vector | ArrayLike) -> Frame:
        """A right-handed orthonormal 3-D frame with ``z`` along ``z_dir`` and ``x`` in the
        ``(x_dir, z_dir)`` plane (Gram–Schmidt; ``y = z x x``).

        Raises
        ------
        InvalidGeometryError
            If the directions are not 3-D, zero, or parallel.
        """
        z = _as_coords(z_dir.coords if isinstance(z_dir, Vector) else z_dir, "z_dir")
        x = _as_coords(x_dir.coords if isinstance(x_dir, Vector) else x_dir, "x_dir")
        for name, a in (("z_dir", z), ("x_dir", x)):
            if a.shape != (3,):
                raise InvalidGeometryError(f"{name}: expected a 3-D direction of shape (3,), got {a.shape}")
            if not np.linalg.norm(a) > 0:
                raise InvalidGeometryError(f"{name}: expected a non-zero direction")
        z = z / np.linalg.norm(z)
        x = x - (x @ z) * z
        nx = np.linalg.norm(x)
        if nx <= 1e-12 * np.linalg.norm(x_dir.coords if isinstance(x_dir, Vector) else x_dir):
            raise InvalidGeometryError("x_dir: must not be parallel to z_dir")
        x = x / nx
        y = np.cross(z, x)
        return cls(origin if isinstance(origin, Point) else Point(origin), np.column_stack((x, y, z)))

    @property
    def dim(self) -> int:
        return self.basis.shape[0]

    @property
    def axes(self) -> Vector:
        """The basis vectors as a Vector array of shape ``(d, d)`` (row ``i`` is axis ``i``)."""
        return Vector._trusted(self.basis.T)

    def coordinates_of(self, x: Point | Vector | Normal) -> Array:
        """Frame coordinates of world elements, shape ``(..., d)``.

        Points: ``B^{-1} (p - o)``; vectors: ``B^{-1} v``; normals (covariant): ``B^T n``, so
        that ``n · v`` equals the dot product of the coordinate arrays.
        """
        if isinstance(x, Point):
            _broadcast(self.origin.coords, x.coords, "point_or_vector")
            return (x.coords - self.origin.coords) @ self._inverse.T
        if isinstance(x, Vector):
            _broadcast(self.origin.coords, x.coords, "point_or_vector")
            return x.coords @ self._inverse.T
        if isinstance(x, Normal):
            _broadcast(self.origin.coords, x.coords, "point_or_vector")
            return x.coords @ self.basis
        raise TypeError(f"coordinates_of: expected a Point, Vector or Normal, got {type(x).__name__}")

    def from_coordinates(self, coords: ArrayLike, kind: _Kind = Point) -> Point | Vector | Normal:
        """World elements from frame coordinates ``(..., d)``; inverse of :meth:`coordinates_of`.

        Parameters
        ----------
        coords : array_like, shape (..., d)
        kind : Point, Vector or Normal (class or name), default Point
        """
        k = _KINDS.get(kind, None) if isinstance(kind, str) else kind
        if k not in (Point, Vector, Normal):
            raise TypeError(f"kind: expected Point, Vector or Normal, got {kind!r}")
        c = _as_coords(coords, "coords")
        if c.shape[-1] != self.dim:
            raise InvalidGeometryError(f"coords: expected dimension {self.dim}, got {c.shape[-1]}")
        if k is Point:
            return Point._trusted(c @ self.basis.T + self.origin.coords)
        if k is Vector:
            return Vector._trusted(c @ self.basis.T)
        return Normal._trusted(c @ self._inverse)

    def to_world(self) -> AffineMap:
        """The affine map from frame coordinates to world coordinates, ``c -> B c + o``."""
        return AffineMap(self.basis, self.origin.coords)

    def from_world(self) -> AffineMap:
        """The affine map from world coordinates to frame coordinates (inverse of :meth:`to_world`)."""
        return AffineMap._trusted(self._inverse, -self._inverse @ self.origin.coords)


# ---------------------------------------------------------------------------------------- maps
@dataclass(frozen=True, eq=False)
class AffineMap:
    """The affine map ``x -> M x + t`` (course §1-20..1-30).

    Parameters
    ----------
    matrix : array_like, shape (d, d)
        Linear part ``M`` (may be singular, e.g. a projection; then :meth:`inverse` and the action
        on normals raise).
    translation : array_like, shape (d,), optional
        Translation ``t``; default zero.

    Notes
    -----
    Calling the map dispatches on the kind (course §1-20..1-30):

    .. math::

        p \\mapsto M p + t, \\qquad v \\mapsto M v, \\qquad n \\mapsto M^{-T} n.

    Composition ``(A @ B)(x) = A(B(x))``.
    """

    matrix: Array
    translation: Array | None = None

    def __post_init__(self) -> None:
        M = _as_matrix(self.matrix, "matrix")
        d = M.shape[0]
        if self.translation is None:
            t = np.zeros(d)
        else:
            t = _as_coords(self.translation, "translation")
            if t.shape != (d,):
                raise InvalidGeometryError(f"translation: expected shape {(d,)}, got {t.shape}")
        object.__setattr__(self, "matrix", _readonly(M))
        object.__setattr__(self, "translation", _readonly(t))

    @classmethod
    def _trusted(cls, matrix: Array, translation: Array) -> AffineMap:
        obj = object.__new__(cls)
        object.__setattr__(obj, "matrix", _readonly(matrix))
        object.__setattr__(obj, "translation", _readonly(translation))
        return obj

    @classmethod
    def identity(cls, dim: int = 3) -> AffineMap:
        return cls._trusted(np.eye(dim), np.zeros(dim))

    @classmethod
    def translate(cls, v: Vector | ArrayLike) -> AffineMap:
        """Translation by ``v``."""
        t = v.coords if isinstance(v, Vector) else _as_coords(v, "v")
        if t.ndim != 1:
            raise InvalidGeometryError(f"v: expected a single vector of shape (d,), got {t.shape}")
        return cls._trusted(np.eye(t.shape[0]), t)

    @classmethod
    def from_homogeneous(cls, matrix: ArrayLike) -> AffineMap:
        """From a ``(d+1, d+1)`` homogeneous matrix whose last row is ``[0, ..., 0, 1]``."""
        H = _as_matrix(matrix, "matrix")
        d = H.shape[0] - 1
        if d < 1 or not np.array_equal(H[-1], np.r_[np.zeros(d), 1.0]):
            raise InvalidGeometryError(f"matrix: expected last row [0, ..., 0, 1] of an affine map, got {H[-1].tolist()}")
        return cls._trusted(H[:d, :d], H[:d, d])

    @property
    def dim(self) -> int:
        return self.matrix.shape[0]

    @property
    def homogeneous(self) -> Array:
        """The ``(d+1, d+1)`` homogeneous matrix ``[[M, t], [0, 1]]``."""
        d = self.dim
        H = np.eye(d + 1)
        H[:d, :d], H[:d, d] = self.matrix, self.translation
        return H

    def _normal_matrix(self) -> Array:
        _check_invertible(self.matrix, "matrix", MAX_CONDITION)
        return np.linalg.inv(self.matrix).T

    def __call__(self, x: Any, *, normalize: bool = False) -> Any:
        """Apply the map to a Point, Vector, Normal (``(..., d)``), Frame or B-spline.

        Parameters
        ----------
        x : Point, Vector, Normal, Frame, BSplineCurve or BSplineSurface
        normalize : bool
            For normals only: rescale the mapped normals to unit length.

        Raises
        ------
        TypeError
            For raw arrays (say what they are: Point, Vector or Normal) and other types.
        InvalidGeometryError
            On dimension mismatch; for normals when ``M`` is (numerically) singular.
        """
        if isinstance(x, _Element):
            if x.dim != self.dim:
                raise InvalidGeometryError(f"x: expected dimension {self.dim}, got {x.dim}")
            if isinstance(x, Point):
                return Point._trusted(x.coords @ self.matrix.T + self.translation)
            if isinstance(x, Vector):
                return Vector._trusted(x.coords @ self.matrix.T)
            n = x.coords @ self._normal_matrix().T
            return Normal._trusted(_unit(n, "normal") if normalize else n)
        if isinstance(x, Frame):
            if x.dim != self.dim:
                raise InvalidGeometryError(f"x: expected dimension {self.dim}, got {x.dim}")
            return Frame(self(x.origin), self.matrix @ x.basis)
        if isinstance(x, (BSplineCurve, BSplineSurface)):
            return self.apply_to(x)
        raise TypeError(f"AffineMap: cannot apply to {type(x).__name__}; wrap arrays in Point, Vector or Normal")

    def apply_to(self, spline: Spline) -> Spline:
        """The image of a B-spline curve or surface (rational or not), exactly.

        By affine invariance (course §1-5..1-30) mapping the control points maps the spline; the
        weights are unchanged. Uses the spline's own ``transform(matrix, translation)``.
        """
        if not isinstance(spline, (BSplineCurve, BSplineSurface)):
            raise TypeError(f"spline: expected a BSplineCurve or BSplineSurface, got {type(spline).__name__}")
        if spline.dim != self.dim:
            raise InvalidGeometryError(f"spline: expected dimension {self.dim}, got {spline.dim}")
        return spline.transform(self.matrix, self.translation)

    def __matmul__(self, other: object) -> Any:
        if isinstance(other, AffineMap):
            if other.dim != self.dim:
                raise InvalidGeometryError(f"other: expected dimension {self.dim}, got {other.dim}")
            return AffineMap._trusted(self.matrix @ other.matrix, self.matrix @ other.translation + self.translation)
        if isinstance(other, ProjectiveMap):
            return ProjectiveMap(self.homogeneous) @ other
        if isinstance(other, _Element):
            raise TypeError("AffineMap @ element: apply a map by calling it, f(x)")
        return NotImplemented

    def inverse(self) -> AffineMap:
        """The inverse map ``x -> M^{-1} (x - t)``; raises if ``M`` is (numerically) singular."""
        _check_invertible(self.matrix, "matrix", MAX_CONDITION)
        Mi = np.linalg.inv(self.matrix)
        return AffineMap._trusted(Mi, -Mi @ self.translation)

    def __repr__(self) -> str:
        return f"AffineMap(matrix={self.matrix.tolist()}, translation={self.translation.tolist()})"


@dataclass(frozen=True, eq=False)
class ProjectiveMap:
    """A projective map given by a homogeneous ``(d+1, d+1)`` matrix (course §1-20..1-30).

    A point ``p`` maps to ``(H [p; 1])[:d] / (H [p; 1])[d]``.

    Parameters
    ----------
    matrix : array_like, shape (4, 4) or (3, 3)
        Homogeneous matrix for 3-D (resp. 2-D) points; must be invertible.

    Notes
    -----
    A projective map does not act on free vectors or normals independently of a base point, so
    calling it on a :class:`Vector` or :class:`Normal` raises ``TypeError``. Points sent to the
    plane at infinity (``w = 0``) raise :class:`InvalidGeometryError` unless
    ``at_infinity="inf"`` is passed, which returns ``±inf`` / ``nan`` coordinates (IEEE division)
    for those points.
    """

    matrix: Array

    def __post_init__(self) -> None:
        H = _as_matrix(self.matrix, "matrix")
        if H.shape[0] < 2:
            raise InvalidGeometryError(f"matrix: expected shape (d+1, d+1) with d >= 1, got {H.shape}")
        _check_invertible(H, "matrix", MAX_CONDITION)
        object.__setattr__(self, "matrix", _readonly(H))

    @property
    def dim(self) -> int:
        return self.matrix.shape[0] - 1

    @property
    def is_affine(self) -> bool:
        """``True`` if the last row is ``[0, ..., 0, c]`` with ``c != 0``."""
        return bool(np.all(self.matrix[-1, :-1] == 0) and self.matrix[-1, -1] != 0)

    def _homogeneous(self, P: Array) -> Array:
        return P @ self.matrix[:, :-1].T + self.matrix[:, -1]

    def __call__(self, x: Any, *, at_infinity: Literal["raise", "inf"] = "raise") -> Any:
        """Map Points ``(..., d)`` or B-splines (see :meth:`apply_to`).

        Raises
        ------
        InvalidGeometryError
            If a point maps to ``w = 0`` (and ``at_infinity="raise"``), or on dimension mismatch.
        TypeError
            For vectors, normals, raw arrays and other types.
        """
        if isinstance(x, (BSplineCurve, BSplineSurface)):
            return self.apply_to(x)
        if not isinstance(x, Point):
            raise TypeError(f"ProjectiveMap: acts on Points and splines, not on {_kind_of(x)}; "
                            f"map the end points of a vector instead")
        if x.dim != self.dim:
            raise InvalidGeometryError(f"x: expected dimension {self.dim}, got {x.dim}")
        h = self._homogeneous(x.coords)
        w = h[..., -1]
        if at_infinity == "raise":
            if np.any(w == 0):
                i = tuple(int(j) for j in np.argwhere(w == 0)[0])
                raise InvalidGeometryError(f"x: point at index {i} maps to the plane at infinity (w = 0)")
        elif at_infinity != "inf":
            raise ValueError(f"at_infinity: expected 'raise' or 'inf', got {at_infinity!r}")
        with np.errstate(divide="ignore", invalid="ignore"):
            return Point._trusted(h[..., :-1] / w[..., None])

    def apply_to(self, spline: Spline) -> Spline:
        """The exact image of a (rational or polynomial) B-spline curve or surface.

        With homogeneous poles ``(w_i P_i, w_i)`` the image has poles ``H (w_i P_i, w_i)``:

        .. math::

            w_i' = w_i \\, (h_{d+1} \\cdot [P_i; 1]), \\qquad
            P_i' = \\frac{(H [P_i; 1])_{1..d}}{h_{d+1} \\cdot [P_i; 1]},

        because the rational spline is the projection of a polynomial spline in homogeneous space,
        on which ``H`` acts linearly (course §1-20..1-30; The NURBS Book, 2nd ed., §4.2).

        Returns
        -------
        BSplineCurve or BSplineSurface
            Rational unless the spline is polynomial and every new weight is exactly 1 (e.g. an
            affine ``H`` with last row ``[0, ..., 0, 1]``).

        Raises
        ------
        InvalidGeometryError
            If any new weight is ``<= 0``: the spline's control polygon crosses (or touches) the
            plane sent to infinity, so the image is not a valid NURBS.
        """
        if not isinstance(spline, (BSplineCurve, BSplineSurface)):
            raise TypeError(f"spline: expected a BSplineCurve or BSplineSurface, got {type(spline).__name__}")
        if spline.dim != self.dim:
            raise InvalidGeometryError(f"spline: expected dimension {self.dim}, got {spline.dim}")
        P = spline.control_points
        w = np.ones(P.shape[:-1]) if spline.weights is None else spline.weights
        h = self._homogeneous(P)
        new_w = w * h[..., -1]
        if np.any(new_w <= 0):
            i = tuple(int(j) for j in np.argwhere(new_w <= 0)[0])
            raise InvalidGeometryError(
                f"spline: control point {i} maps to weight {float(new_w[i])!r} <= 0 "
                f"(on or beyond the plane sent to infinity)"
            )
        new_P = h[..., :-1] / h[..., -1:]
        new_weights = None if spline.weights is None and np.all(new_w == 1.0) else new_w
        return type(spline)._trusted(spline.degree, spline.knots, new_P, new_weights)

    def __matmul__(self, other: object) -> ProjectiveMap:
        if isinstance(other, ProjectiveMap):
            if other.dim != self.dim:
                raise InvalidGeometryError(f"other: expected dimension {self.dim}, got {other.dim}")
            return ProjectiveMap(self.matrix @ other.matrix)
        if isinstance(other, AffineMap):
            if other.dim != self.dim:
                raise InvalidGeometryError(f"other: expected dimension {self.dim}, got {other.dim}")
            return ProjectiveMap(self.matrix @ other.homogeneous)
        if isinstance(other, _Element):
            raise TypeError("ProjectiveMap @ element: apply a map by calling it, f(x)")
        return NotImplemented

    def __rmatmul__(self, other: object) -> ProjectiveMap:
        if isinstance(other, AffineMap):
            return ProjectiveMap(other.homogeneous) @ self
        return NotImplemented

    def inverse(self) -> ProjectiveMap:
        """The inverse projective map (``H^{-1}``)."""
        return ProjectiveMap(np.linalg.inv(self.matrix))

    def __repr__(self) -> str:
        return f"ProjectiveMap(matrix={self.matrix.tolist()})"
