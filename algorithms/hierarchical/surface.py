"""Hierarchical B-spline surfaces with offset referencing (course ch. 5, Forsey–Bartels).

A :class:`HierarchicalSurface` is a base :class:`BSplineSurface` (any degree, non-uniform or
unclamped knots, rational allowed: course §5-32..5-33) plus a tree of overlays (§5-10). An
overlay refines a rectangle of its parent's knot vectors (midpoint insertion by default) and owns
the refined control vertices whose Greville points lie in it; creating one leaves the surface
unchanged. Each overlay vertex is stored as an offset from its reference vertex (the parent's
refined vertex) in the parent's local frame at its reference parameter (§5-15, see
:mod:`.offsets`), so editing a coarse level carries the details along (§5-23..5-24).

Mutability (one rule for every edit)
------------------------------------
A hierarchical surface is an *editing model*: every edit — :meth:`~HierarchicalSurface.add_overlay`,
:meth:`~HierarchicalSurface.move_vertex`, :meth:`~HierarchicalSurface.set_offset`,
:meth:`~HierarchicalSurface.set_offsets`, :meth:`~HierarchicalSurface.move_edit_point`,
:meth:`~HierarchicalSurface.drag_point`, :meth:`~HierarchicalSurface.set_base` — **changes this
object in place** and returns ``None`` (``add_overlay`` returns the new overlay's handle). This
keeps interactive edits cheap: only the caches of the edited overlay and its descendants are
rebuilt. Use :meth:`~HierarchicalSurface.copy` to keep a state; :meth:`~HierarchicalSurface.flatten`
returns a frozen :class:`BSplineSurface` snapshot, and evaluations return new arrays.

References
----------
D. R. Forsey, R. H. Bartels, "Hierarchical B-spline refinement", SIGGRAPH '88, 205-212;
course notes C25, SIGGRAPH 1991, ch. 5 (§5-10 overlays, §5-15 offset referencing, §5-17 storage,
§5-24 multi-level editing, §5-27 edit points, §5-30 arbitrary positions, §5-32..5-41 generalised
forms).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import _validate as V
from .. import tolerances
from ..errors import InvalidGeometryError
from ..kernel.rational import surface_quotient_rule
from ..kernel.surface import BSplineSurface
from ..manipulation.linalg import ConvergenceError
from ..manipulation.surfaces import drag_surface_point
from .core import FORMAT_VERSION, Hierarchy, check_format
from .offsets import OffsetMapping, surface_frames
from .overlays import Node, Overlay, support_mask

__all__ = ["HierarchicalSurface", "Overlay", "FORMAT_VERSION"]

Array = NDArray[np.float64]

# drag_point reads EDIT_POINT_RTOL and EDIT_POINT_MAX_ITER from :mod:`occsurf.algorithms.tolerances`
# at call time. Frame offsets make the point a mildly non-linear function of the vertices; the
# residual falls by the factor (detail size x frame rotation) per linearised solve: 2-4 solves for
# small details, 14 measured for details of 0.1 on a unit patch (factor 0.16).


def _select(x: Array, lo: float, hi: float, end: float) -> slice | NDArray[np.intp] | None:
    """Indices of ``x`` in the support ``[lo, hi)`` (``[lo, hi]`` at the domain ``end``; see
    :func:`support_mask`): a slice if contiguous, None if empty."""
    idx = np.flatnonzero(support_mask(x, lo, hi, end))
    if idx.size == 0:
        return None
    if idx[-1] - idx[0] + 1 == idx.size:
        return slice(int(idx[0]), int(idx[-1]) + 1)
    return idx


def _ix(a: slice | NDArray[np.intp], b: slice | NDArray[np.intp]) -> Any:
    if isinstance(a, slice) and isinstance(b, slice):
        return a, b
    ar = np.arange(a.start, a.stop) if isinstance(a, slice) else a
    br = np.arange(b.start, b.stop) if isinstance(b, slice) else b
    return np.ix_(ar, br)


class HierarchicalSurface(Hierarchy):
    """A Forsey–Bartels hierarchical B-spline surface (course ch. 5).

    Parameters
    ----------
    base : BSplineSurface
        The level-0 surface: any degrees, knots (non-uniform, unclamped) and weights.
    offsets : {"frame", "additive"} or OffsetMapping, default "frame"
        The offset mapping function (course §5-37): ``"frame"`` stores overlay vertices in the
        parent's local orthonormal frame (offset referencing, §5-15; needs a 3-D surface),
        ``"additive"`` as plain world-space differences (for comparison).

    Notes
    -----
    **Edits change this object in place** (see the module notes); evaluation never does.
    Evaluation is vectorised; each overlay contributes only where its delta spline's support
    covers the parameter. See :mod:`.core` for the representation and the caches.

    Examples
    --------
    >>> hs = HierarchicalSurface(base)                      # doctest: +SKIP
    >>> o1 = hs.add_overlay((0.25, 0.75), (0.25, 0.75))    # doctest: +SKIP
    >>> hs.set_offset(o1, (3, 3), (0, 0, 0.2))             # a bump along the normal
    >>> hs.move_vertex(None, (2, 2), (0, 0, 1.0))          # bend the base: the bump follows
    """

    _npar = 2
    _kind = "HierarchicalSurface"

    def __init__(self, base: BSplineSurface, offsets: str | OffsetMapping = "frame") -> None:
        if not isinstance(base, BSplineSurface):
            raise InvalidGeometryError(f"base: expected a BSplineSurface, got {type(base).__name__}")
        self._init(base, offsets)
        self._grid_cache: dict[str, Any] | None = None
        self._base_h_cache: BSplineSurface | None = None
        self._base_h_version = -1

    # ------------------------------------------------------------------ hooks
    def _check_mapping_dim(self) -> None:
        if self._mapping.uses_frames and self._dim != 3:
            raise InvalidGeometryError(f"offsets: frame offsets need a 3-D surface, the base has dim {self._dim}; "
                                       "use offsets='additive'")

    def _base_knots(self, spline: BSplineSurface) -> tuple[Array, Array]:
        return spline.knots

    def _make(self, knots: tuple[Array, ...], P: Array, w: Array | None) -> BSplineSurface:
        return BSplineSurface._trusted(self._deg, knots, P, w)

    def _frames_of(self, spline: BSplineSurface, params: tuple[Array, ...]) -> Array:
        return surface_frames(spline, params[0], params[1])

    # ------------------------------------------------------------------ properties
    @property
    def base(self) -> BSplineSurface:
        """The current base surface (a frozen value)."""
        return self._root.level_spline

    @property
    def degree(self) -> tuple[int, int]:
        return self._deg  # type: ignore[return-value]

    @property
    def domain(self) -> tuple[tuple[float, float], tuple[float, float]]:
        return self._domain  # type: ignore[return-value]

    def __repr__(self) -> str:
        kind = "rational " if self._rational else ""
        return (f"HierarchicalSurface({kind}degree={self._deg}, base poles={self.base.n_poles}, "
                f"overlays={len(self._nodes)}, depth={self.depth}, offsets={self._mapping.name!r})")

    def level_surface(self, overlay: Overlay | int | None = None) -> BSplineSurface:
        """The surface up to ``overlay``: the base refined with the overlay's ancestors' details and
        its own (``None``: the base). Its poles on the overlay's vertices are
        :meth:`control_points`; other overlays (siblings, descendants) are not included."""
        return self._level(self._node(overlay))

    # ------------------------------------------------------------------ edits (in place)
    def add_overlay(self, u_range: tuple[float, float], v_range: tuple[float, float],
                    parent: Overlay | int | None = None, *, knots: tuple[ArrayLike, ArrayLike] | None = None) -> Overlay:
        """Add an overlay refining ``u_range x v_range`` of ``parent`` (in place; course §5-10).

        Parameters
        ----------
        u_range, v_range : (float, float)
            The region, inside the parent overlay's region; widened to the parent's knots.
        parent : Overlay, int or None
            ``None`` (or 0): the base.
        knots : (array_like, array_like), optional
            The u- and v-knots to insert (within the widened region); default the midpoints of
            every parent knot span in the region.

        Returns
        -------
        Overlay
            The new overlay's handle; its vertices are those of the refined parent whose Greville
            points lie in the region, all with zero offsets (the surface does not change).

        Raises
        ------
        ParameterError
            A range outside the domain or the parent's region, or holding no refined vertex.
        InvalidGeometryError
            A bad parent handle, or knots that would exceed multiplicity ``degree + 1``.
        """
        h = self._add((u_range, v_range), parent, knots)
        return h

    def move_vertex(self, overlay: Overlay | int | None, index: tuple[int, int], displacement: ArrayLike) -> None:
        """Move a control vertex by a world-space ``displacement`` (in place; course §5-24).

        Parameters
        ----------
        overlay : Overlay, int or None
            ``None`` moves a vertex of the base net (all overlays follow it, offsets unchanged);
            an overlay's vertex is stored back as an offset in its parent's frame.
        index : (int, int)
            Into the overlay's vertex array (``overlay.shape``) or the base net.
        displacement : array_like, shape (d,)
        """
        node = self._node(overlay)
        idx = self._index(node, index)
        self._move_world(node, idx, self._vector(displacement, "displacement"))

    def set_base(self, base: BSplineSurface) -> None:
        """Replace the base by a surface with the same degrees, knots and weights (in place); the
        overlays keep their offsets and follow."""
        cur = self.base
        if (not isinstance(base, BSplineSurface) or base.degree != cur.degree or base.n_poles != cur.n_poles
                or not all(np.array_equal(a, b) for a, b in zip(base.knots, cur.knots))
                or (base.weights is None) != (cur.weights is None)
                or (base.weights is not None and cur.weights is not None and not np.array_equal(base.weights, cur.weights))
                or base.dim != cur.dim):
            raise InvalidGeometryError("base: expected a BSplineSurface with the current base's degrees, knots, "
                                       "weights and dimension (only the poles may change)")
        self._set_base(base)

    # ------------------------------------------------------------------ edit points (§5-27, §5-30)
    def edit_points(self, overlay: Overlay | int | None = None) -> tuple[Array, Array]:
        """The edit points of ``overlay`` (course §5-27): per control vertex its reference
        parameter and the hierarchical surface's point there.

        Returns
        -------
        params : ndarray, shape overlay.shape + (2,)
        points : ndarray, shape overlay.shape + (d,)
        """
        node = self._node(overlay)
        if node.handle is None:
            gu, gv = (np.clip(g, lo, hi) for g, (lo, hi) in zip(self.base.greville(), self._domain))
        else:
            gu, gv = node.handle.reference_parameters
        uu, vv = np.meshgrid(gu, gv, indexing="ij")
        return np.stack([uu, vv], -1), self.evaluate_grid(gu, gv)

    def move_edit_point(self, overlay: Overlay | int | None, index: tuple[int, int], target: ArrayLike, *,
                        tol: float | None = None) -> None:
        """Drag the edit point of vertex ``index`` to ``target`` (in place; course §5-27), changing
        only ``overlay``'s vertices (minimum-norm change, :meth:`drag_point`)."""
        node = self._node(overlay)
        i, j = self._index(node, index)
        params, _ = self.edit_points(overlay)
        u, v = params[i, j]
        self.drag_point(float(u), float(v), target, overlay=overlay, tol=tol)

    def finest_overlay(self, u: float, v: float) -> Overlay | None:
        """The deepest overlay whose region holds ``(u, v)`` (the latest one on ties); ``None``
        if no overlay does (course §5-30: the level an arbitrary surface position is edited at)."""
        best: Node | None = None
        for n in self._nodes.values():
            (a, b), (c, d) = n.overlay.region
            if a <= u <= b and c <= v <= d and (best is None or n.overlay.level >= best.overlay.level):
                best = n
        return None if best is None else best.overlay

    def drag_point(self, u: float, v: float, target: ArrayLike, *, overlay: Overlay | int | str | None = None,
                   tol: float | None = None) -> None:
        """Move the surface point ``S(u, v)`` to ``target`` changing one level only (in place).

        Course §5-27 (edit points) and §5-30 (editing arbitrary surface positions): the vertices
        of ``overlay`` change by the minimum-norm amount (the direct-manipulation solve
        :func:`.surface_manipulation.drag_surface_point` on the overlay's level surface, window =
        the overlay's vertices); every other stored value stays. With frame offsets the finer
        details turn with the edit, which moves the point a little more: the solve is repeated
        on the remaining residual (a few times at most) until ``|S(u, v) - target| <= tol``.

        Parameters
        ----------
        u, v : float
        target : array_like, shape (d,)
        overlay : Overlay, int, None or "finest"
            The level edited: ``None`` the base, ``"finest"`` :meth:`finest_overlay` at ``(u, v)``
            (the base if none covers it).
        tol : float, optional
            Absolute; default :data:`~occsurf.algorithms.tolerances.EDIT_POINT_RTOL`
            ``* max(1, |target|)``.

        Raises
        ------
        ConstraintError
            No vertex of the overlay acts at ``(u, v)``.
        ConvergenceError
            Not within ``tol`` after :data:`~occsurf.algorithms.tolerances.EDIT_POINT_MAX_ITER`
            solves (the surface is restored).
        """
        (u0, u1), (v0, v1) = self._domain
        uu = V.check_parameter(u, u0, u1, "u")
        vv = V.check_parameter(v, v0, v1, "v")
        tgt = self._vector(target, "target")
        if isinstance(overlay, str):
            if overlay != "finest":
                raise InvalidGeometryError(f"overlay: expected an Overlay, id, None or 'finest', got {overlay!r}")
            overlay = self.finest_overlay(uu, vv)
        node = self._node(overlay)
        tol = tolerances.EDIT_POINT_RTOL * max(1.0, float(np.abs(tgt).max())) if tol is None else float(tol)
        max_iter = int(tolerances.EDIT_POINT_MAX_ITER)
        window = None if node.handle is None else (node.handle.vertices[0], node.handle.vertices[1])
        saved = self._snapshot(node)
        res = np.inf
        for _ in range(max_iter):
            r = tgt - self.evaluate(uu, vv)
            res = float(np.linalg.norm(r))
            if res <= tol:
                return
            lvl = self._level(node)
            moved = drag_surface_point(lvl, uu, vv, lvl.evaluate(uu, vv) + r, window=window)
            dP = moved.control_points - lvl.control_points
            if node.handle is None:
                self._set_base(moved)
            else:  # every vertex of the overlay, as world displacements
                self._move_world(node, (...,), dP[node.blk])
            r = tgt - self.evaluate(uu, vv)
        res = float(np.linalg.norm(r))
        if res > tol:
            self._restore(node, saved)
            raise ConvergenceError(f"drag_point: |S(u, v) - target| = {res:.3g} > tol = {tol:.3g} after "
                                   f"{max_iter} solves; the surface is left as it was")

    # ------------------------------------------------------------------ evaluation
    def _base_h(self) -> BSplineSurface:
        """The base's homogeneous net as a polynomial surface (the base itself if polynomial)."""
        if self._base_h_cache is None or self._base_h_version != self._root.version:
            base = self._root.level_spline
            self._base_h_cache = base if not self._rational else BSplineSurface._trusted(
                self._deg, base.knots, base.homogeneous_points)
            self._base_h_version = self._root.version
        return self._base_h_cache

    def _uv(self, u: ArrayLike, v: ArrayLike) -> tuple[Array, Array, tuple[int, ...]]:
        du, dv = self._domain
        # per point: the flattened u, v, the base's homogeneous values, their copy and the quotient
        return V.check_uv(u, v, (du, dv), per_point=2 + 3 * (self._dim + 1))

    def _scattered_h(self, a: Array, b: Array, order: int) -> Array:
        """Homogeneous partials ``(m, r+1, r+1, k)`` at scattered parameters."""
        d = self._dim
        H = np.array(self._base_h().derivatives(a, b, order))
        for n in self._nodes.values():
            (ua, ub), (va, vb) = n.support
            m = support_mask(a, ua, ub, self._domain[0][1]) & support_mask(b, va, vb, self._domain[1][1])
            if np.any(m):
                H[m, ..., :d] += n.delta.derivatives(a[m], b[m], order)
        return H

    def evaluate(self, u: ArrayLike, v: ArrayLike) -> Array:
        """Points at broadcastable parameters.

        Returns
        -------
        ndarray, shape broadcast(u, v).shape + (d,)
        """
        a, b, shape = self._uv(u, v)
        d = self._dim
        H = np.array(self._base_h().evaluate(a, b)).reshape(-1, self._base_h().dim)
        for n in self._nodes.values():
            (ua, ub), (va, vb) = n.support
            m = support_mask(a, ua, ub, self._domain[0][1]) & support_mask(b, va, vb, self._domain[1][1])
            if np.any(m):
                H[m, :d] += n.delta.evaluate(a[m], b[m])
        P = H[:, :d] / H[:, d:] if self._rational else H
        return P.reshape(shape + (d,))

    __call__ = evaluate

    def derivatives(self, u: ArrayLike, v: ArrayLike, order: int = 1) -> Array:
        """Point and partials ``d^{k+l} S / du^k dv^l``, ``k, l <= order``.

        Returns
        -------
        ndarray, shape broadcast(u, v).shape + (order + 1, order + 1, d)
        """
        order = V.check_order(order)
        a, b, shape = self._uv(u, v)
        H = self._scattered_h(a, b, order)
        if self._rational:
            H = surface_quotient_rule(H)
        return H.reshape(shape + (order + 1, order + 1, self._dim))

    def normal(self, u: ArrayLike, v: ArrayLike) -> Array:
        """Unit normals ``S_u x S_v / |S_u x S_v|`` (NaN where degenerate), shape ``(..., 3)``."""
        if self._dim != 3:
            raise InvalidGeometryError(f"normal: needs a 3-D surface, this one has dim {self._dim}")
        D = self.derivatives(u, v, 1)
        return _unit(np.cross(D[..., 1, 0, :], D[..., 0, 1, :]))

    def _grid_params(self, us: ArrayLike, vs: ArrayLike) -> tuple[Array, Array]:
        (u0, u1), (v0, v1) = self._domain
        return (V.check_parameters(us, u0, u1, "us").reshape(-1), V.check_parameters(vs, v0, v1, "vs").reshape(-1))

    def evaluate_grid(self, us: ArrayLike, vs: ArrayLike) -> Array:
        """Points on the grid ``us x vs``.

        The base and every overlay contribute through banded basis products on the sub-grid their
        support covers; each contribution is cached for the last grid asked for and recomputed
        only when its overlay (or an ancestor) changed.

        Returns
        -------
        ndarray, shape (len(us), len(vs), d)
        """
        a, b = self._grid_params(us, vs)
        d = self._dim
        key = (a.tobytes(), b.tobytes())
        cache = self._grid_cache
        if cache is None or cache["key"] != key:
            cache = self._grid_cache = {"key": key, "parts": {}}
        parts = cache["parts"]
        base = parts.get(0)
        if base is None or base[0] != self._root.version:
            base = parts[0] = (self._root.version, self._base_h().evaluate_grid(a, b))
        H = base[1].copy()
        for ident, n in self._nodes.items():
            part = parts.get(ident)
            if part is None or part[0] != n.version:
                (ua, ub), (va, vb) = n.support
                iu, iv = _select(a, ua, ub, self._domain[0][1]), _select(b, va, vb, self._domain[1][1])
                vals = None if iu is None or iv is None else n.delta.evaluate_grid(a[iu], b[iv])
                part = parts[ident] = (n.version, iu, iv, vals)
            if part[3] is not None:
                H[_ix(part[1], part[2]) + (slice(0, d),)] += part[3]
        return H[..., :d] / H[..., d:] if self._rational else H

    def derivatives_grid(self, us: ArrayLike, vs: ArrayLike, order: int = 1) -> Array:
        """All partials up to ``order`` on the grid ``us x vs``.

        Returns
        -------
        ndarray, shape (len(us), len(vs), order + 1, order + 1, d)
        """
        order = V.check_order(order)
        a, b = self._grid_params(us, vs)
        d = self._dim
        H = np.array(self._base_h().derivatives_grid(a, b, order))
        for n in self._nodes.values():
            (ua, ub), (va, vb) = n.support
            iu, iv = _select(a, ua, ub, self._domain[0][1]), _select(b, va, vb, self._domain[1][1])
            if iu is not None and iv is not None:
                H[_ix(iu, iv) + (Ellipsis, slice(0, d))] += n.delta.derivatives_grid(a[iu], b[iv], order)
        return surface_quotient_rule(H) if self._rational else H

    def normal_grid(self, us: ArrayLike, vs: ArrayLike) -> Array:
        """Unit normals on the grid, shape ``(len(us), len(vs), 3)`` (NaN where degenerate)."""
        if self._dim != 3:
            raise InvalidGeometryError(f"normal: needs a 3-D surface, this one has dim {self._dim}")
        D = self.derivatives_grid(us, vs, 1)
        return _unit(np.cross(D[..., 1, 0, :], D[..., 0, 1, :]))

    # ------------------------------------------------------------------ flat form, storage
    def flatten(self) -> BSplineSurface:
        """The hierarchy as one exact :class:`BSplineSurface` (a snapshot).

        The base is refined to the union of all overlay knots (the coarsest common refinement,
        Oslo), and every overlay's weighted displacements are refined to the same knots and
        added (course §5-17). Equal to the hierarchical surface to round-off.
        """
        knots, H = self._flat_h()
        if self._rational:
            return BSplineSurface._trusted(self._deg, knots, H[..., :-1] / H[..., -1:], H[..., -1])
        return BSplineSurface._trusted(self._deg, knots, H)

    def to_dict(self) -> dict[str, Any]:
        """JSON-safe, lossless, versioned dict of the whole hierarchy (course §5-17).

        Holds the base (:meth:`BSplineSurface.to_dict`), the offset mapping's name and per overlay
        its id, parent id, region, inserted knots and offsets; floats survive ``json`` exactly.
        """
        return self._to_dict()

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> HierarchicalSurface:
        """Inverse of :meth:`to_dict`; loads every format version up to :data:`FORMAT_VERSION`.

        A custom offset mapping must be registered first
        (:func:`.offsets.register_offset_mapping`).
        """
        check_format(data, cls._kind)
        try:
            base = BSplineSurface.from_dict(data["base"])
            mapping = data.get("offset_mapping", "frame")
        except KeyError as err:
            raise InvalidGeometryError(f"from_dict: missing key {err}") from err
        hs = cls(base, mapping)
        hs._load_overlays(data)
        return hs


def _unit(n: Array) -> Array:
    ln = np.linalg.norm(n, axis=-1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(ln > 0, n / ln, np.nan)
