"""The argument checks and row weighting of the least-squares solvers (course ch. 3): the dense
ones of :mod:`.linalg` and the sparse ones of :mod:`.sparse_linalg` (LSMR, SuperLU) check their
right-hand sides, weights, constrained systems and constraint labels here, and :mod:`.linalg` its
dense matrices, so that a bad argument is refused with its name before any factorisation sees it.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any, TypeVar, overload

import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidGeometryError

__all__ = ["dense_matrix", "right_hand_side", "row_weights", "per_row", "weighted_rows", "constrained_system",
           "row_labels"]

Array = NDArray[np.float64]
_M = TypeVar("_M")  # a dense Array or a SciPy sparse matrix (SciPy ships no type stubs: Any)


def dense_matrix(a: ArrayLike, name: str) -> Array:
    """``a`` as a finite 2-D float array (a copy); else :class:`InvalidGeometryError` naming ``name``."""
    try:
        m = np.array(a, dtype=float)
    except (TypeError, ValueError) as err:
        raise InvalidGeometryError(f"{name}: expected a 2-D array of real numbers, got {type(a).__name__}") from err
    if m.ndim != 2:
        raise InvalidGeometryError(f"{name}: expected a 2-D array, got shape {m.shape}")
    if not np.all(np.isfinite(m)):
        raise InvalidGeometryError(f"{name}: expected finite values")
    return m


def right_hand_side(b: ArrayLike, rows: int, name: str) -> Array:
    """``b`` as finite floats of shape ``(rows,)`` or ``(rows, k)`` (a copy); else
    :class:`InvalidGeometryError` naming ``name``."""
    try:
        v = np.array(b, dtype=float)
    except (TypeError, ValueError) as err:
        raise InvalidGeometryError(f"{name}: expected an array of real numbers, got {type(b).__name__}") from err
    if v.ndim not in (1, 2) or v.shape[0] != rows:
        raise InvalidGeometryError(f"{name}: expected shape ({rows},) or ({rows}, k), got {v.shape}")
    if not np.all(np.isfinite(v)):
        raise InvalidGeometryError(f"{name}: expected finite values")
    return v


def row_weights(w: ArrayLike | None, size: int, name: str) -> Array | None:
    """``w`` as ``size`` finite positive floats (``None`` stays ``None``); else
    :class:`InvalidGeometryError` naming ``name``."""
    if w is None:
        return None
    v = np.array(w, dtype=float)
    if v.shape != (size,):
        raise InvalidGeometryError(f"{name}: expected shape ({size},), got {v.shape}")
    if not np.all(np.isfinite(v)) or np.any(v <= 0):
        raise InvalidGeometryError(f"{name}: expected finite values > 0, got min {v.min()!r}")
    return v


def per_row(x: Array, s: Array) -> Array:
    """``s`` (m,) shaped to scale the rows of ``x`` (shape (m,) or (m, k)): ``x * per_row(x, s)``."""
    return s if x.ndim == 1 else s[:, None]


@overload
def weighted_rows(A: Array, b: Array, w: Array | None) -> tuple[Array, Array]: ...
@overload
def weighted_rows(A: Any, b: Array, w: Array | None) -> tuple[Any, Array]: ...
def weighted_rows(A: Any, b: Array, w: Array | None) -> tuple[Any, Array]:
    """``W^(1/2) A`` and ``W^(1/2) b`` for row weights ``w`` (``A`` dense or sparse; unchanged if
    ``w`` is None)."""
    if w is None:
        return A, b
    s = np.sqrt(w)
    A = sp.diags(s) @ A if sp.issparse(A) else A * s[:, None]
    return A, b * per_row(b, s)


def constrained_system(A: Any, b: ArrayLike, C: Any, d: ArrayLike, weights: ArrayLike | None,
                        as_matrix: Callable[[Any, str], _M]) -> tuple[_M, Array, _M, Array, Array | None]:
    """Validated inputs of a constrained least-squares problem (dense or sparse by ``as_matrix``):
    ``A`` and ``C`` with as many columns, ``b`` and ``d`` with as many right-hand sides, row weights."""
    A = as_matrix(A, "A")
    C = as_matrix(C, "C")
    if A.shape[1] != C.shape[1]:
        raise InvalidGeometryError(f"A, C: expected the same number of columns, got {A.shape[1]} and {C.shape[1]}")
    b = right_hand_side(b, A.shape[0], "b")
    d = right_hand_side(d, C.shape[0], "d")
    w = row_weights(weights, A.shape[0], "weights")
    if b.ndim != d.ndim or (b.ndim == 2 and b.shape[1] != d.shape[1]):
        raise InvalidGeometryError(f"b, d: expected the same number of right-hand sides, got shapes {b.shape} and {d.shape}")
    return A, b, C, d, w


def row_labels(labels: Sequence[str] | None, m: int) -> list[str]:
    """One label per constraint row: ``labels`` as strings, or ``"row i"`` where none were given."""
    if labels is None:
        return [f"row {i}" for i in range(m)]
    labels = [str(s) for s in labels]
    if len(labels) != m:
        raise InvalidGeometryError(f"labels: expected {m} labels (one per constraint row), got {len(labels)}")
    return labels
