"""Shared pieces of the coordinate-free types (course ch. 1, §1-5..1-30).

Holds what both :mod:`~occsurf.algorithms.geometry.affine` (the element types) and
:mod:`~occsurf.algorithms.geometry.affine_maps` (frames and maps) need, so that neither module
imports the other's internals:

* argument checks that name the argument: :func:`as_coords`, :func:`as_matrix`,
  :func:`check_invertible`, :func:`check_broadcast`, :func:`as_scalar`;
* array helpers: :func:`readonly`, :func:`unit`, and :func:`lengths`, :func:`divide_where` (shared
  by :mod:`~occsurf.algorithms.geometry.differential` and
  :mod:`~occsurf.algorithms.geometry.surface_differential`);
* :class:`Element`, the common storage (and the forbidden operations) of ``Point``, ``Vector`` and
  ``Normal``, with :func:`kind_of` naming an operand in error messages.

These are internal building blocks of the subpackage, not part of the public API of
:mod:`occsurf.algorithms.geometry`.
"""

from __future__ import annotations

import numbers
from dataclasses import dataclass
from typing import Any, ClassVar, NoReturn, TypeVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidGeometryError

__all__ = [
    "Element",
    "as_coords",
    "as_matrix",
    "as_scalar",
    "check_broadcast",
    "check_invertible",
    "divide_where",
    "kind_of",
    "lengths",
    "readonly",
    "unit",
]

Array = NDArray[np.float64]


# ---------------------------------------------------------------------------------------- helpers
def readonly(a: ArrayLike) -> Array:
    """``a`` as a C-contiguous float array whose ``writeable`` flag is cleared (a copy if needed)."""
    a = np.ascontiguousarray(a, dtype=float)
    a.flags.writeable = False
    return a


def lengths(a: Array) -> Array:
    """Euclidean lengths of the vectors on the last axis of ``a``."""
    return np.linalg.norm(a, axis=-1)


def divide_where(num: Array, den: Array, ok: NDArray[np.bool_]) -> Array:
    """``num / den`` where ``ok``, NaN elsewhere (no warning for the zeros left out)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(ok, num / np.where(ok, den, 1.0), np.nan)


def as_coords(value: ArrayLike, name: str) -> Array:
    """Validated ``(..., d)`` coordinates: real, finite, at least 1-D, ``d >= 1``.

    Raises
    ------
    TypeError
        If ``value`` is an :class:`Element` (its kind must not be dropped silently).
    InvalidGeometryError
        Naming ``name``: not real numbers, wrong shape, or non-finite values.
    """
    if isinstance(value, Element):
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


def as_matrix(value: ArrayLike, name: str, dim: int | None = None) -> Array:
    """A validated finite square matrix, shape ``(dim, dim)`` if ``dim`` is given.

    Raises
    ------
    InvalidGeometryError
        Naming ``name``: not real numbers, not square (or not ``dim`` x ``dim``), or non-finite.
    """
    try:
        M = np.array(value, dtype=float)
    except (TypeError, ValueError) as err:
        raise InvalidGeometryError(
            f"{name}: expected a square matrix of real numbers, got {type(value).__name__}") from err
    if M.ndim != 2 or M.shape[0] != M.shape[1] or M.shape[0] < 1:
        raise InvalidGeometryError(f"{name}: expected a square matrix, got shape {M.shape}")
    if dim is not None and M.shape[0] != dim:
        raise InvalidGeometryError(f"{name}: expected shape {(dim, dim)}, got {M.shape}")
    if not np.all(np.isfinite(M)):
        raise InvalidGeometryError(f"{name}: expected finite values")
    return M


def check_invertible(M: Array, name: str, max_condition: float) -> None:
    """Raise :class:`InvalidGeometryError` naming ``name`` if ``cond_2(M) > max_condition``.

    Callers pass ``tolerances.MAX_CONDITION`` read at call time.
    """
    cond = np.linalg.cond(M)
    if not np.isfinite(cond) or cond > max_condition:
        raise InvalidGeometryError(
            f"{name}: expected an invertible matrix (condition number <= {max_condition:g}), got condition {cond:.3g}"
        )


def as_scalar(value: object) -> Array | None:
    """``value`` as a float array of scalars, or ``None`` if it is not a scalar (array).

    Elements, strings and any object that is neither a real number nor an array, list or tuple
    (frames and maps among them) give ``None``.
    """
    if isinstance(value, (Element, str, bytes)):
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


def check_broadcast(a: Array, b: Array, name: str) -> None:
    """Check that two ``(..., d)`` coordinate arrays have the same ``d`` and broadcastable leading shapes.

    Raises
    ------
    InvalidGeometryError
        Naming ``name`` (the argument that holds ``b``).
    """
    if a.shape[-1] != b.shape[-1]:
        raise InvalidGeometryError(f"{name}: expected dimension {a.shape[-1]}, got {b.shape[-1]}")
    try:
        np.broadcast_shapes(a.shape, b.shape)
    except ValueError as err:
        raise InvalidGeometryError(
            f"{name}: leading shape {b.shape[:-1]} does not broadcast against {a.shape[:-1]}"
        ) from err


def unit(c: Array, name: str) -> Array:
    """Unit vectors along the last axis; scaled first by the largest component (no overflow).

    Raises
    ------
    InvalidGeometryError
        Naming ``name`` if some vector is zero or non-finite.
    """
    m = np.max(np.abs(c), axis=-1, keepdims=True)
    if not np.all(np.isfinite(m)):
        raise InvalidGeometryError(f"{name}: cannot normalise a non-finite {name}")
    if np.any(m == 0):
        raise InvalidGeometryError(f"{name}: cannot normalise a zero {name}")
    c = c / m
    return c / np.linalg.norm(c, axis=-1, keepdims=True)


E = TypeVar("E", bound="Element")


# ---------------------------------------------------------------------------------------- elements
@dataclass(frozen=True, eq=False, repr=False)
class Element:
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
        object.__setattr__(self, "coords", readonly(as_coords(self.coords, "coords")))

    @classmethod
    def _trusted(cls: type[E], coords: Array) -> E:
        """Fast constructor for internal results (no validation, may hold inf at infinity)."""
        obj = object.__new__(cls)
        object.__setattr__(obj, "coords", readonly(coords))
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
    def _forbid(self, op: str, other: object, reflected: bool = False) -> NoReturn:
        a, b = kind_of(other), self._kind
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

    def allclose(self, other: Element, rtol: float = 1e-12, atol: float = 0.0) -> bool:
        """``True`` if ``other`` has the same kind and all coordinates agree within tolerances."""
        if type(other) is not type(self):
            return False
        check_broadcast(self.coords, other.coords, "other")
        return bool(np.allclose(self.coords, other.coords, rtol=rtol, atol=atol))


def kind_of(x: object) -> str:
    """The name of ``x``'s kind for error messages: ``"point"``, ``"scalar"``, or its type name."""
    if isinstance(x, Element):
        return x._kind
    if as_scalar(x) is not None:
        return "scalar"
    return type(x).__name__
