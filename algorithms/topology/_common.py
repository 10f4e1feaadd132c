"""Helpers shared by the S-patch modules of :mod:`occsurf.algorithms.topology` (course §8-1, 8-2).

The index sets of an S-patch and the side normals of its regular n-gon domain, needed by
:mod:`.spatch` (evaluation, degree elevation) and :mod:`.spatch_convert` (the exact pieces). They are
trusted kernels: nothing is validated here but by :func:`check_sides` and :func:`check_depth`, which the public entry points (:class:`.spatch.SPatch`,
:func:`.spatch.spatch_indices`, :func:`.spatch.domain_vertices`) call to check their arguments once.
"""

from __future__ import annotations

import functools
import numbers

import numpy as np
from numpy.typing import NDArray

from .. import tolerances
from ..errors import InvalidGeometryError

__all__ = ["index_tuples", "edge_normals", "check_sides", "check_depth"]


@functools.lru_cache(maxsize=256)
def index_tuples(sides: int, depth: int) -> tuple[tuple[int, ...], ...]:
    """The multi-indices of an S-patch as a cached tuple of tuples (hashable, for dict keys).

    The same indices, in the same order, as :func:`.spatch.spatch_indices`, which returns them as
    a fresh array after checking its arguments. The result is cached and shared: never mutate it.

    Parameters
    ----------
    sides : int
        ``n >= 1`` (not validated; the recursion goes down to one coordinate).
    depth : int
        ``d >= 0`` (not validated); depth 0 gives the single index ``(0, ..., 0)``.

    Returns
    -------
    tuple of tuple of int, length C(sides + depth - 1, depth)
        Each a ``sides``-tuple of non-negative integers summing to ``depth``, in descending
        lexicographic order: the first is ``(depth, 0, ..., 0)``, the last ``(0, ..., 0, depth)``.
    """
    if sides == 1:
        return ((depth,),)
    out: list[tuple[int, ...]] = []
    for first in range(depth, -1, -1):
        out.extend((first,) + rest for rest in index_tuples(sides - 1, depth - first))
    return tuple(out)


def edge_normals(sides: int) -> NDArray[np.float64]:
    """Outward unit normals of the sides of the regular ``n``-gon domain (not validated).

    The domain is that of :func:`.spatch.domain_vertices` (circumradius 1, vertex ``k`` at angle
    ``2πk/n``). Side ``k`` joins vertex ``k`` and vertex ``k + 1 (mod n)``; its normal ``n_k`` is at
    angle ``2π(k + 1/2)/n`` and the side lies on the line ``x · n_k = cos(π/n)`` (the apothem).

    Parameters
    ----------
    sides : int
        ``n >= 3``.

    Returns
    -------
    ndarray, shape (sides, 2)
    """
    a = 2.0 * np.pi * (np.arange(sides) + 0.5) / sides
    return np.column_stack((np.cos(a), np.sin(a)))


def check_sides(sides: object, name: str = "sides") -> int:
    limit = tolerances.SPATCH_MAX_SIDES
    if isinstance(sides, bool) or not isinstance(sides, numbers.Integral) or not 3 <= int(sides) <= limit:
        raise InvalidGeometryError(f"{name}: expected an integer from 3 to {limit}, got {sides!r}")
    return int(sides)


def check_depth(depth: object, name: str = "depth") -> int:
    if isinstance(depth, bool) or not isinstance(depth, numbers.Integral) or int(depth) < 1:
        raise InvalidGeometryError(f"{name}: expected an integer >= 1, got {depth!r}")
    return int(depth)
