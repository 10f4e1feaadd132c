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

Maps act on the kinds differently (course §1-20..1-30): an
:class:`~occsurf.algorithms.geometry.affine_maps.AffineMap` ``x -> M x + t`` moves points by
``M p + t``, vectors by ``M v``, and normals by the inverse transpose ``M^{-T} n`` (so that
``n · v = 0`` survives non-uniform scaling and shear). A
:class:`~occsurf.algorithms.geometry.affine_maps.ProjectiveMap` acts on points through homogeneous
coordinates and maps rational splines exactly. Frames and maps live in
:mod:`~occsurf.algorithms.geometry.affine_maps`; both modules are re-exported by
:mod:`occsurf.algorithms.geometry`. The helpers they share are in ``geometry/_common.py``.

NumPy arrays are deliberately *not* accepted where a typed element is expected: wrap them in
:class:`Point`, :class:`Vector` or :class:`Normal` to say what they are.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar, Self

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import tolerances
from ..errors import InvalidGeometryError
from ._common import Element, as_scalar, check_broadcast, kind_of, unit

__all__ = [
    "Point",
    "Vector",
    "Normal",
    "affine_combination",
    "vector_combination",
]

Array = NDArray[np.float64]


# ---------------------------------------------------------------------------------------- helpers
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


@dataclass(frozen=True, eq=False, repr=False)
class _Kind(Element):
    """Addition and subtraction by a table of what each kind allows (course §1-5..1-30).

    ``_ADD`` and ``_SUB`` hold ``(other kind, result kind)`` pairs (filled in below the classes);
    any other operand is refused with :meth:`Element._forbid`.
    """

    _ADD: ClassVar[tuple] = ()
    _SUB: ClassVar[tuple] = ()

    def _combine(self, other: object, op: str, rules: tuple, fn: Any, reflected: bool = False) -> Any:
        for kind, result in rules:
            if isinstance(other, kind):
                check_broadcast(self.coords, other.coords, "other")
                return result._trusted(fn(self.coords, other.coords))
        return self._forbid(op, other, reflected)

    def __add__(self, other: object) -> Any:
        return self._combine(other, "+", self._ADD, np.add)

    def __sub__(self, other: object) -> Any:
        return self._combine(other, "-", self._SUB, np.subtract)


@dataclass(frozen=True, eq=False, repr=False)
class _Linear(_Kind):
    """Scaling, division by a scalar, negation, length, normalisation and the pairing ``dot``,
    shared by the two vector spaces (vectors and normals); each result keeps the operand's type."""

    def _times(self, other: object, reflected: bool) -> Self:
        s = as_scalar(other)
        if s is None:
            return self._forbid("*", other, reflected)
        return type(self)._trusted(_scale(self.coords, s, "scalar"))

    def __mul__(self, other: object) -> Self:
        return self._times(other, False)

    def __rmul__(self, other: object) -> Self:
        return self._times(other, True)

    def __truediv__(self, other: object) -> Self:
        s = as_scalar(other)
        if s is None:
            return self._forbid("/", other)
        if np.any(s == 0):
            raise InvalidGeometryError("scalar: division by zero")
        return type(self)._trusted(_scale(self.coords, 1.0 / s, "scalar"))

    def __neg__(self) -> Self:
        return type(self)._trusted(-self.coords)

    def __pos__(self) -> Self:
        return self

    def _pairing(self, other: object, kinds: tuple, hint: str) -> Array:
        if not isinstance(other, kinds):
            raise TypeError(f"{self._kind} . {kind_of(other)} is not defined; {hint}")
        check_broadcast(self.coords, other.coords, "other")
        return np.einsum("...i,...i->...", self.coords, other.coords)

    def norm(self) -> Array:
        """Euclidean length, shape ``(...)``."""
        return np.linalg.norm(self.coords, axis=-1)

    def normalized(self) -> Self:
        """Unit elements of the same kind; raises :class:`InvalidGeometryError` if any is zero."""
        return type(self)._trusted(unit(self.coords, self._kind))


@dataclass(frozen=True, eq=False, repr=False)
class Point(_Kind):
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

    if TYPE_CHECKING:  # the generated __init__ takes array_like; __post_init__ stores a float array

        def __init__(self, coords: ArrayLike) -> None: ...

    def __radd__(self, other: object) -> Point:
        return self._combine(other, "+", self._ADD, np.add, True)

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

    if TYPE_CHECKING:  # the generated __init__ takes array_like; __post_init__ stores a float array

        def __init__(self, coords: ArrayLike) -> None: ...

    def dot(self, other: Vector | Normal) -> Array:
        """Euclidean inner product (or the pairing with a :class:`Normal`), shape ``(...)``."""
        return self._pairing(other, (Vector, Normal), "dot takes a vector or a normal")

    def cross(self, other: Vector) -> Vector:
        """Cross product of 3-D vectors, shape ``(..., 3)``."""
        if not isinstance(other, Vector):
            raise TypeError(f"vector x {kind_of(other)} is not defined; cross takes a vector")
        if self.dim != 3:
            raise InvalidGeometryError(f"cross: defined for 3-D vectors, got dimension {self.dim}")
        check_broadcast(self.coords, other.coords, "other")
        return Vector._trusted(np.cross(self.coords, other.coords))


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

    if TYPE_CHECKING:  # the generated __init__ takes array_like; __post_init__ stores a float array

        def __init__(self, coords: ArrayLike) -> None: ...

    @classmethod
    def from_tangents(cls, a: Vector, b: Vector) -> Normal:
        """The normal ``a x b`` of the plane spanned by two 3-D tangent vectors (not normalised)."""
        if not (isinstance(a, Vector) and isinstance(b, Vector)):
            raise TypeError("from_tangents: expected two Vectors")
        return cls._trusted(a.cross(b).coords)

    def dot(self, other: Vector) -> Array:
        """The pairing ``n · v`` with vectors, shape ``(...)``."""
        return self._pairing(other, (Vector,), "a normal pairs with a vector")


# What each kind adds and subtracts: (other kind, result kind); anything else is refused.
Point._ADD = ((Vector, Point),)
Point._SUB = ((Point, Vector), (Vector, Point))
Vector._ADD = ((Vector, Vector), (Point, Point))
Vector._SUB = ((Vector, Vector),)
Normal._ADD = Normal._SUB = ((Normal, Normal),)


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
    w = np.array(weights, dtype=float) if not isinstance(weights, Element) else None
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

