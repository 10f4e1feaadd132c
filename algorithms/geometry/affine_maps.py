"""Affine frames, affine maps and projective maps acting on the typed elements (course §1-20..1-30).

A :class:`Frame` converts coordinates between frames; an :class:`AffineMap` moves points by
``M p + t``, vectors by ``M v`` and normals by the inverse transpose; a :class:`ProjectiveMap`
acts on homogeneous points and maps rational splines exactly. The element types (Point, Vector,
Normal) are in :mod:`occsurf.algorithms.geometry.affine`; :mod:`occsurf.algorithms.geometry`
exports both modules' public names.
"""

from __future__ import annotations

import numbers
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import _validate as V
from .. import tolerances
from ..errors import InvalidGeometryError
from ..kernel.curve import BSplineCurve
from ..kernel.surface import BSplineSurface
from ._common import Element, as_coords, as_matrix, check_broadcast, check_invertible, kind_of, readonly, unit
from .affine import Normal, Point, Vector

__all__ = ["Frame", "AffineMap", "ProjectiveMap"]

Array = NDArray[np.float64]
Spline = BSplineCurve | BSplineSurface

# ---------------------------------------------------------------------------------------- frames
_Kind = type[Point] | type[Vector] | type[Normal] | Literal["point", "vector", "normal"]
_KINDS: dict[str, type[Element]] = {"point": Point, "vector": Vector, "normal": Normal}


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
        exceeds :data:`occsurf.algorithms.tolerances.MAX_CONDITION`.
    """

    origin: Point
    basis: Array
    _inverse: Array = field(init=False, repr=False)

    if TYPE_CHECKING:  # the generated __init__ takes array_like; __post_init__ stores a Point and an array

        def __init__(self, origin: Point | ArrayLike, basis: ArrayLike) -> None: ...

    def __post_init__(self) -> None:
        o = self.origin
        o_c = o.coords if isinstance(o, Point) else as_coords(o, "origin")
        if isinstance(o, (Vector, Normal)):
            raise TypeError(f"origin: expected a Point, got a {o._kind}")
        if o_c.ndim != 1:
            raise InvalidGeometryError(f"origin: expected a single point of shape (d,), got {o_c.shape}")
        B = as_matrix(self.basis, "basis", o_c.shape[0])
        check_invertible(B, "basis", tolerances.MAX_CONDITION)
        object.__setattr__(self, "origin", Point._trusted(o_c))
        object.__setattr__(self, "basis", readonly(B))
        object.__setattr__(self, "_inverse", readonly(np.linalg.inv(B)))

    @classmethod
    def standard(cls, dim: int = 3) -> Frame:
        """The world frame: origin 0, basis the identity.

        Raises
        ------
        InvalidGeometryError
            ``dim`` not a positive integer, or its basis, inverse and their work arrays (about four
            ``dim x dim`` matrices) above ``tolerances.MAX_ARRAY_BYTES``.
        """
        d = _dim(dim, 4, "Frame.standard")
        return cls(Point(np.zeros(d)), np.eye(d))

    @classmethod
    def orthonormal(cls, origin: Point | ArrayLike, x_dir: Vector | ArrayLike, z_dir: Vector | ArrayLike) -> Frame:
        """A right-handed orthonormal 3-D frame with ``z`` along ``z_dir`` and ``x`` in the
        ``(x_dir, z_dir)`` plane (Gram–Schmidt; ``y = z x x``).

        Raises
        ------
        InvalidGeometryError
            If the directions are not 3-D, zero, or parallel.
        """
        z = as_coords(z_dir.coords if isinstance(z_dir, Vector) else z_dir, "z_dir")
        x = as_coords(x_dir.coords if isinstance(x_dir, Vector) else x_dir, "x_dir")
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
            check_broadcast(self.origin.coords, x.coords, "point_or_vector")
            return (x.coords - self.origin.coords) @ self._inverse.T
        if isinstance(x, Vector):
            check_broadcast(self.origin.coords, x.coords, "point_or_vector")
            return x.coords @ self._inverse.T
        if isinstance(x, Normal):
            check_broadcast(self.origin.coords, x.coords, "point_or_vector")
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
        c = as_coords(coords, "coords")
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
    if TYPE_CHECKING:  # the generated __init__ takes array_like; __post_init__ stores arrays (t = 0 for None)
        translation: Array

        def __init__(self, matrix: ArrayLike, translation: ArrayLike | None = None) -> None: ...
    else:
        translation: Array | None = None

    def __post_init__(self) -> None:
        M = as_matrix(self.matrix, "matrix")
        d = M.shape[0]
        if self.translation is None:
            t = np.zeros(d)
        else:
            t = as_coords(self.translation, "translation")
            if t.shape != (d,):
                raise InvalidGeometryError(f"translation: expected shape {(d,)}, got {t.shape}")
        object.__setattr__(self, "matrix", readonly(M))
        object.__setattr__(self, "translation", readonly(t))

    @classmethod
    def _trusted(cls, matrix: ArrayLike, translation: ArrayLike) -> AffineMap:
        obj = object.__new__(cls)
        object.__setattr__(obj, "matrix", readonly(matrix))
        object.__setattr__(obj, "translation", readonly(translation))
        return obj

    @classmethod
    def identity(cls, dim: int = 3) -> AffineMap:
        """The identity map of ``dim``-D space (``dim`` a positive integer; its ``dim x dim`` matrix
        is refused above ``tolerances.MAX_ARRAY_BYTES``)."""
        d = _dim(dim, 1, "AffineMap.identity")
        return cls._trusted(np.eye(d), np.zeros(d))

    @classmethod
    def translate(cls, v: Vector | ArrayLike) -> AffineMap:
        """Translation by ``v``."""
        t = v.coords if isinstance(v, Vector) else as_coords(v, "v")
        if t.ndim != 1:
            raise InvalidGeometryError(f"v: expected a single vector of shape (d,), got {t.shape}")
        return cls._trusted(np.eye(t.shape[0]), t)

    @classmethod
    def from_homogeneous(cls, matrix: ArrayLike) -> AffineMap:
        """From a ``(d+1, d+1)`` homogeneous matrix whose last row is ``[0, ..., 0, 1]``."""
        H = as_matrix(matrix, "matrix")
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

    def _normal_matrix(self) -> NDArray[np.floating]:
        check_invertible(self.matrix, "matrix", tolerances.MAX_CONDITION)
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
        if isinstance(x, Element):
            if x.dim != self.dim:
                raise InvalidGeometryError(f"x: expected dimension {self.dim}, got {x.dim}")
            if isinstance(x, Point):
                return Point._trusted(x.coords @ self.matrix.T + self.translation)
            if isinstance(x, Vector):
                return Vector._trusted(x.coords @ self.matrix.T)
            n = x.coords @ self._normal_matrix().T
            return Normal._trusted(unit(n, "normal") if normalize else n)
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
        if isinstance(other, Element):
            raise TypeError("AffineMap @ element: apply a map by calling it, f(x)")
        return NotImplemented

    def inverse(self) -> AffineMap:
        """The inverse map ``x -> M^{-1} (x - t)``; raises if ``M`` is (numerically) singular."""
        check_invertible(self.matrix, "matrix", tolerances.MAX_CONDITION)
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

    if TYPE_CHECKING:  # the generated __init__ takes array_like; __post_init__ stores a float array

        def __init__(self, matrix: ArrayLike) -> None: ...

    def __post_init__(self) -> None:
        H = as_matrix(self.matrix, "matrix")
        if H.shape[0] < 2:
            raise InvalidGeometryError(f"matrix: expected shape (d+1, d+1) with d >= 1, got {H.shape}")
        # Judged in units of the translation's size: a change of length unit x -> c x turns
        # [[A, t], [p, s]] into [[A, c t], [p / c, s]], the same map, and the condition number of
        # the raw matrix grows like |t|^2 (a plain shift by 1e6 looked singular).
        c = max(1.0, float(np.abs(H[:-1, -1]).max()))
        B = H.copy()
        B[:-1, -1] /= c
        B[-1, :-1] *= c
        check_invertible(B, "matrix", tolerances.MAX_CONDITION)
        object.__setattr__(self, "matrix", readonly(H))

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
            raise TypeError(f"ProjectiveMap: acts on Points and splines, not on {kind_of(x)}; "
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
            If the new weights are not all of one sign (or one is 0): the spline's control
            polygon crosses (or touches) the plane sent to infinity, so the image is not a valid
            NURBS. (All negative is the same map as ``-H``: the weights are negated.)
        """
        if not isinstance(spline, (BSplineCurve, BSplineSurface)):
            raise TypeError(f"spline: expected a BSplineCurve or BSplineSurface, got {type(spline).__name__}")
        if spline.dim != self.dim:
            raise InvalidGeometryError(f"spline: expected dimension {self.dim}, got {spline.dim}")
        P = spline.control_points
        w = np.ones(P.shape[:-1]) if spline.weights is None else spline.weights
        h = self._homogeneous(P)
        new_w = w * h[..., -1]
        if np.all(new_w < 0):
            new_w = -new_w  # H and -H are one projective map: every weight negative is a sign, not a crossing
        if np.any(new_w <= 0):
            i = tuple(int(j) for j in np.argwhere(new_w <= 0)[0])
            raise InvalidGeometryError(
                f"spline: control point {i} maps to weight {float(new_w[i])!r} <= 0 "
                f"(on or beyond the plane sent to infinity)"
            )
        new_P = h[..., :-1] / h[..., -1:]
        new_weights = None if spline.weights is None and np.all(new_w == 1.0) else new_w
        if isinstance(spline, BSplineCurve):
            return type(spline)._trusted(spline.degree, spline.knots, new_P, new_weights)
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
        if isinstance(other, Element):
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


def _dim(dim: object, copies: int, what: str) -> int:
    """A dimension: a positive integer whose ``copies`` ``dim x dim`` matrices fit ``MAX_ARRAY_BYTES``."""
    if isinstance(dim, bool) or not isinstance(dim, numbers.Integral) or int(dim) < 1:
        raise InvalidGeometryError(f"dim: expected a positive integer, got {dim!r}")
    d = int(dim)
    V.check_size((copies, d, d), f"{what}(dim={d})")
    return d
