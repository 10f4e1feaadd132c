"""The pieces of a hierarchy's overlay tree (course §5-10..5-24): :class:`Overlay`, the immutable
handle of one overlay (its place in the tree and its refinement), :class:`Node`, the mutable state
and caches of one overlay in a :class:`~.core.Hierarchy`, and :func:`support_mask`, where an
overlay contributes. :mod:`.core` builds and edits the tree.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidGeometryError

__all__ = ["Node", "Overlay", "support_mask"]

Array = NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class Overlay:
    """Handle of one overlay: its place in the tree and its (fixed) refinement.

    Handles are immutable; the overlay's offsets live in the hierarchy that returned the handle
    (and its :meth:`copy`). Pass the handle to that hierarchy's methods.

    Attributes
    ----------
    id : int
        1, 2, ... in creation order (0 is the base).
    parent : int
        Id of the parent (0 = the base).
    level : int
        1 for an overlay of the base, parent's level + 1 otherwise.
    region : tuple of (float, float)
        Per parametric direction, the region it refines, widened to the parent's knots.
    inserted : tuple of ndarray
        The knots inserted into the parent's knot vectors, per direction.
    knots : tuple of ndarray
        The overlay's full (level) knot vectors.
    vertices : tuple of (int, int)
        Inclusive index ranges of the overlay's control vertices in the level net.
    reference_parameters : tuple of ndarray
        Per direction, the Greville abscissae of those vertices (clipped to the domain), where the
        parent's frames are taken.
    """

    id: int
    parent: int
    level: int
    region: tuple[tuple[float, float], ...]
    inserted: tuple[Array, ...]
    knots: tuple[Array, ...]
    vertices: tuple[tuple[int, int], ...]
    reference_parameters: tuple[Array, ...]

    @property
    def shape(self) -> tuple[int, ...]:
        """Number of the overlay's vertices per direction."""
        return tuple(b - a + 1 for a, b in self.vertices)

    @property
    def u_range(self) -> tuple[float, float]:
        return self.region[0]

    @property
    def v_range(self) -> tuple[float, float]:
        if len(self.region) < 2:
            raise AttributeError("a curve overlay has no v_range")
        return self.region[1]

    def __repr__(self) -> str:
        reg = " x ".join(f"[{a:.6g}, {b:.6g}]" for a, b in self.region)
        return f"Overlay(id={self.id}, parent={self.parent}, level={self.level}, region={reg}, vertices={self.shape})"


class Node:
    """Mutable state and caches of one overlay (or of the base: ``handle is None``) of a
    :class:`Hierarchy`.

    Shared by the hierarchical curve and surface modules; not exported by the subpackage.
    """

    __slots__ = ("handle", "parent", "children", "T", "R", "offsets", "frames", "H", "delta", "support",
                 "level_spline", "version", "blk")

    def __init__(self, handle: Overlay | None, parent: Node | None) -> None:
        self.handle = handle
        self.parent = parent
        self.children: list[Node] = []
        self.T: tuple[Array, ...] = ()
        self.R: Array | None = None
        self.offsets: Array | None = None
        self.frames: Array | None = None
        self.H: Array | None = None
        self.delta: Any = None
        self.support: tuple[tuple[float, float], ...] = ()
        self.level_spline: Any = None
        self.version = 0
        self.blk: tuple[slice, ...] = ()

    # Typed views of the fields that only some nodes have, or that are set after construction.
    @property
    def overlay(self) -> Overlay:
        """The handle of an overlay node (the base has none)."""
        if self.handle is None:
            raise InvalidGeometryError("the base is not an overlay")
        return self.handle

    @property
    def up(self) -> Node:
        """The parent node of an overlay (the base has none)."""
        if self.parent is None:
            raise InvalidGeometryError("the base has no parent")
        return self.parent

    @property
    def net(self) -> Array:
        """``H``: the homogeneous level net (set when the node is built)."""
        if self.H is None:
            raise RuntimeError("hierarchy node: the level net is not built yet")
        return self.H

    @property
    def reference(self) -> Array:
        """``R``: the parent's net refined to this overlay's knots (overlays only)."""
        if self.R is None:
            raise RuntimeError("hierarchy node: the reference net is not built yet (or this is the base)")
        return self.R

    @property
    def stored_offsets(self) -> Array:
        """The overlay's stored offsets (overlays only)."""
        if self.offsets is None:
            raise InvalidGeometryError("the base stores control points, not offsets")
        return self.offsets


def support_mask(x: Array, lo: float, hi: float, end: float) -> NDArray[np.bool_]:
    """Parameters ``x`` where an overlay on ``[lo, hi]`` contributes: ``[lo, hi)``, or ``[lo, hi]`` when
    ``hi`` is the domain's ``end``.

    The right-limit convention of B-spline evaluation at interior knots (and of :meth:`flatten`'s
    single spline): at ``hi`` the overlay's own spline would give its *left* limit, whose
    derivatives of order >= degree jump there, on top of the base's right limit.
    """
    return (x >= lo) & ((x < hi) | (hi >= end))
