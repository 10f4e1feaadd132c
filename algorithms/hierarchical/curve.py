"""Hierarchical B-spline curves with offset referencing (course §5-33, curves and volumes).

The one-parameter case of :class:`.hierarchical.HierarchicalSurface`: a base
:class:`BSplineCurve` (any degree, knots, weights) and a tree of overlays refining parameter
intervals; overlay vertices are offsets in the parent curve's local frame (2-D: tangent and
normal; 3-D: tangent, an "up"-aligned normal and their cross product, see
:mod:`.offsets`) or plain world differences (``offsets="additive"``).

Mutability: as for surfaces, **every edit changes this object in place** and returns ``None``
(``add_overlay`` returns the handle); :meth:`HierarchicalCurve.copy` keeps a state and
:meth:`HierarchicalCurve.flatten` returns a frozen :class:`BSplineCurve`.

References
----------
D. R. Forsey, R. H. Bartels, "Hierarchical B-spline refinement", SIGGRAPH '88; course notes C25,
SIGGRAPH 1991, §5-33..5-37.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import _validate as V
from .. import tolerances
from ..errors import InvalidGeometryError
from ..kernel.curve import BSplineCurve
from ..kernel.rational import curve_quotient_rule
from ..manipulation.curves import drag_point as _drag_curve_point
from ..manipulation.linalg import ConvergenceError
from .core import Hierarchy, check_format
from .offsets import OffsetMapping, curve_frames
from .overlays import Overlay, support_mask

__all__ = ["HierarchicalCurve"]

Array = NDArray[np.float64]


class HierarchicalCurve(Hierarchy):
    """A hierarchical B-spline curve (course §5-33).

    Parameters
    ----------
    base : BSplineCurve
    offsets : {"frame", "additive"} or OffsetMapping, default "frame"
        Frame offsets need a 2-D or 3-D curve.

    Notes
    -----
    **Edits change this object in place** (see the module notes).
    """

    _npar = 1
    _kind = "HierarchicalCurve"

    def __init__(self, base: BSplineCurve, offsets: str | OffsetMapping = "frame") -> None:
        if not isinstance(base, BSplineCurve):
            raise InvalidGeometryError(f"base: expected a BSplineCurve, got {type(base).__name__}")
        self._init(base, offsets)

    def _check_mapping_dim(self) -> None:
        if self._mapping.uses_frames and self._dim not in (2, 3):
            raise InvalidGeometryError(f"offsets: frame offsets need a 2-D or 3-D curve, the base has dim "
                                       f"{self._dim}; use offsets='additive'")

    def _base_knots(self, spline: BSplineCurve) -> tuple[Array]:
        return (spline.knots,)

    def _make(self, knots: tuple[Array, ...], P: Array, w: Array | None) -> BSplineCurve:
        return BSplineCurve._trusted(self._deg[0], knots[0], P, w)

    def _frames_of(self, spline: BSplineCurve, params: tuple[Array, ...]) -> Array:
        return curve_frames(spline, params[0])

    # ------------------------------------------------------------------ properties
    @property
    def base(self) -> BSplineCurve:
        """The current base curve (a frozen value)."""
        return self._root.level_spline

    @property
    def degree(self) -> int:
        return self._deg[0]

    @property
    def domain(self) -> tuple[float, float]:
        return self._domain[0]

    def __repr__(self) -> str:
        return (f"HierarchicalCurve(degree={self._deg[0]}, base poles={self.base.n_poles}, "
                f"overlays={len(self._nodes)}, depth={self.depth}, offsets={self._mapping.name!r})")

    def level_curve(self, overlay: Overlay | int | None = None) -> BSplineCurve:
        """The curve up to ``overlay`` (base plus the details of the overlay and its ancestors)."""
        return self._level(self._node(overlay))

    # ------------------------------------------------------------------ edits (in place)
    def add_overlay(self, u_range: tuple[float, float], parent: Overlay | int | None = None, *,
                    knots: ArrayLike | None = None) -> Overlay:
        """Add an overlay refining ``u_range`` of ``parent`` (in place); see
        :meth:`HierarchicalSurface.add_overlay`."""
        return self._add((u_range,), parent, knots)

    def move_vertex(self, overlay: Overlay | int | None, index: int, displacement: ArrayLike) -> None:
        """Move a control vertex by a world ``displacement`` (in place); ``overlay=None``: the base."""
        node = self._node(overlay)
        idx = self._index(node, index)
        self._move_world(node, idx, self._vector(displacement, "displacement"))

    def drag_point(self, u: float, target: ArrayLike, *, overlay: Overlay | int | None = None,
                   tol: float | None = None) -> None:
        """Move ``C(u)`` to ``target`` changing only ``overlay``'s vertices (in place; course §5-27).

        The minimum-norm solve :func:`.manipulation.drag_point` on the overlay's level curve
        (window = its vertices), repeated on the residual while finer frame-referenced details
        turn (see :meth:`HierarchicalSurface.drag_point`).
        """
        lo, hi = self.domain
        uu = V.check_parameter(u, lo, hi, "u")
        tgt = self._vector(target, "target")
        node = self._node(overlay)
        tol = tolerances.EDIT_POINT_RTOL * max(1.0, float(np.abs(tgt).max())) if tol is None else float(tol)
        max_iter = int(tolerances.EDIT_POINT_MAX_ITER)
        first, last = (None, None) if node.handle is None else node.handle.vertices[0]
        saved = self._snapshot(node)
        for _ in range(max_iter):
            r = tgt - self.evaluate(uu)
            if float(np.linalg.norm(r)) <= tol:
                return
            lvl = self._level(node)
            moved = _drag_curve_point(lvl, uu, lvl.evaluate(uu) + r, first, last)
            if node.handle is None:
                self._set_base(moved)
            else:  # every vertex of the overlay, as world displacements
                self._move_world(node, (...,), (moved.control_points - lvl.control_points)[node.blk])
        res = float(np.linalg.norm(tgt - self.evaluate(uu)))
        if res > tol:
            self._restore(node, saved)
            raise ConvergenceError(f"drag_point: |C(u) - target| = {res:.3g} > tol = {tol:.3g} after "
                                   f"{max_iter} solves; the curve is left as it was")

    # ------------------------------------------------------------------ evaluation
    def _h(self, a: Array, order: int) -> Array:
        d = self._dim
        base = self.base
        hb = base if not self._rational else BSplineCurve._trusted(self._deg[0], base.knots, base.homogeneous_points)
        H = np.array(hb.derivatives(a, order))
        for n in self._nodes.values():
            (ua, ub), = n.support
            m = support_mask(a, ua, ub, self.domain[1])
            if np.any(m):
                H[m, :, :d] += n.delta.derivatives(a[m], order)
        return H

    def derivatives(self, u: ArrayLike, order: int = 1) -> Array:
        """Point and derivatives up to ``order``, shape ``u.shape + (order + 1, d)``."""
        order = V.check_order(order)
        lo, hi = self.domain
        a = V.check_parameters(u, lo, hi, "u")
        shape = a.shape
        H = self._h(a.reshape(-1), order)
        if self._rational:
            H = curve_quotient_rule(H)
        return H.reshape(shape + (order + 1, self._dim))

    def evaluate(self, u: ArrayLike) -> Array:
        """Points, shape ``u.shape + (d,)``."""
        return self.derivatives(u, 0)[..., 0, :]

    __call__ = evaluate

    # ------------------------------------------------------------------ flat form, storage
    def flatten(self) -> BSplineCurve:
        """The hierarchy as one exact :class:`BSplineCurve` on the union of all overlay knots."""
        (knots,), H = self._flat_h()
        if self._rational:
            return BSplineCurve._trusted(self._deg[0], knots, H[:, :-1] / H[:, -1:], H[:, -1])
        return BSplineCurve._trusted(self._deg[0], knots, H)

    def to_dict(self) -> dict[str, Any]:
        """JSON-safe, lossless, versioned dict (as :meth:`HierarchicalSurface.to_dict`)."""
        return self._to_dict()

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> HierarchicalCurve:
        """Inverse of :meth:`to_dict`."""
        check_format(data, cls._kind)
        try:
            base = BSplineCurve.from_dict(data["base"])
        except KeyError as err:
            raise InvalidGeometryError(f"from_dict: missing key {err}") from err
        hc = cls(base, data.get("offset_mapping", "frame"))
        hc._load_overlays(data)
        return hc
