"""The machinery shared by hierarchical curves and surfaces (course §5-10..5-24, §5-32..5-34).

A hierarchy is a base spline plus a tree of *overlays*. An overlay refines a region of its
parent's knot vectors (knot insertion, Oslo: :func:`.knots.refinement_matrix`) and owns the refined
control vertices whose reference parameters (Greville abscissae) lie in that region. Each node
``N`` has a *level net* ``H_N`` on its knots (homogeneous for rational bases):

.. math::

    H_N = T_N H_{parent(N)} + \\begin{cases} (w\\,\\delta, 0) & \\text{on N's vertices} \\\\
    0 & \\text{elsewhere} \\end{cases}, \\qquad \\delta = \\mathrm{map}(o_N, F_N),

with ``T_N`` the refinement matrices (one per parametric direction), ``o_N`` the stored offsets,
``F_N`` the parent's frames at the reference parameters and ``map`` the offset mapping function
(:mod:`.offsets`). The level spline ``(knots_N, H_N)`` is the surface "up to N"
(base and N's ancestors). Because refinement does not change a spline, the whole hierarchical
spline is the base plus one small *delta spline* per overlay:

.. math::

    S(u) = \\frac{h_0(u) + \\sum_N \\sum_{i \\in N} w_{N,i}\\, \\delta_{N,i} B_{N,i}(u)}{w(u)},

``w`` being the base's weight function (``1`` if polynomial). Each delta spline is non-zero only
on its support, so evaluation visits only the overlays that cover a parameter.

Caches (invalidated only for what an edit touches): per overlay the refinement matrices, the
refined parent net ``T_N H_parent``, the frames at the reference parameters, the level spline and
the delta spline; an edit of an overlay's offsets rebuilds that overlay and its descendants, an
edit of the base rebuilds everything below it.
"""

from __future__ import annotations

import copy as _copy
import reprlib
from collections.abc import Sequence
from typing import Any, Self

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import _validate as V
from ..errors import InvalidGeometryError, ParameterError
from ..kernel.basis import greville
from ..kernel.knots import knot_tol, merge_knots, refinement_matrix, snap_knots
from .offsets import OffsetMapping, get_offset_mapping
from .overlays import Node, Overlay

__all__ = ["FORMAT_VERSION", "Hierarchy", "check_format"]

Array = NDArray[np.float64]

#: Version of the ``to_dict`` format written by this module; every older version loads.
FORMAT_VERSION: int = 1


def _refine_net(H: Array, Ts: tuple[Array, ...]) -> Array:
    """Apply one refinement matrix per parametric axis of the net ``H`` (last axis: coordinates)."""
    for ax, T in enumerate(Ts):
        H = np.moveaxis(np.tensordot(T, H, axes=(1, ax)), 0, ax)
    return np.ascontiguousarray(H)


def _union_knots(vectors: list[Array]) -> Array:
    """The coarsest common refinement: every value with its largest multiplicity."""
    mult: dict[float, int] = {}
    for t in vectors:
        vals, counts = np.unique(t, return_counts=True)
        for x, c in zip(vals.tolist(), counts.tolist()):
            if c > mult.get(x, 0):
                mult[x] = c
    xs = sorted(mult)
    return np.repeat(np.array(xs, float), [mult[x] for x in xs])


class Hierarchy:
    """Base class of :class:`HierarchicalSurface` and :class:`HierarchicalCurve` (shared by their
    modules, not exported by the subpackage).

    Subclasses set ``_npar`` (parametric directions) and implement ``_base_knots``, ``_make``
    (a spline from knots, poles, weights) and ``_frames_of`` (frames of a level spline at the
    reference parameters).
    """

    _npar: int = 0
    _kind: str = ""
    _grid_cache: dict[str, Any] | None  # the surface's grid-evaluation cache (copy() resets it)

    # ------------------------------------------------------------------ construction
    def _init(self, base: Any, offsets: str | OffsetMapping) -> None:
        self._mapping = get_offset_mapping(offsets)
        self._rational = base.is_rational
        self._dim = base.dim
        self._deg: tuple[int, ...] = tuple(base.degree) if self._npar == 2 else (int(base.degree),)
        self._root = Node(None, None)
        self._root.H = np.array(base.homogeneous_points, dtype=float)
        self._root.level_spline = base
        self._nodes: dict[int, Node] = {}
        self._next_id = 1
        self._domain: tuple[tuple[float, float], ...] = (
            tuple(base.domain) if self._npar == 2 else (base.domain,))
        self._check_mapping_dim()

    def _check_mapping_dim(self) -> None:
        """Subclasses: refuse a frame mapping in a dimension without frames."""

    def _base_knots(self, spline: Any) -> tuple[Array, ...]:
        raise NotImplementedError

    def _make(self, knots: tuple[Array, ...], P: Array, w: Array | None) -> Any:
        raise NotImplementedError

    def _frames_of(self, spline: Any, params: tuple[Array, ...]) -> Array:
        raise NotImplementedError

    # ------------------------------------------------------------------ node access
    def _node(self, overlay: Overlay | int | None, name: str = "overlay") -> Node:
        if overlay is None or (isinstance(overlay, int) and not isinstance(overlay, bool) and overlay == 0):
            return self._root
        if isinstance(overlay, Overlay):
            node = self._nodes.get(overlay.id)
            if node is None or node.handle is not overlay:
                raise InvalidGeometryError(f"{name}: {overlay!r} is not an overlay of this hierarchy")
            return node
        if isinstance(overlay, int) and not isinstance(overlay, bool) and overlay in self._nodes:
            return self._nodes[overlay]
        raise InvalidGeometryError(f"{name}: expected an Overlay handle of this hierarchy, an overlay id or None "
                                   f"(the base), got {overlay!r}")

    def _knots_of(self, node: Node) -> tuple[Array, ...]:
        return self._base_knots(self._root.level_spline) if node.handle is None else node.handle.knots

    @property
    def overlays(self) -> list[Overlay]:
        """The overlay handles in creation order (parents before children)."""
        return [n.overlay for n in self._nodes.values()]

    @property
    def offset_mapping(self) -> OffsetMapping:
        return self._mapping

    @property
    def dim(self) -> int:
        return self._dim

    @property
    def is_rational(self) -> bool:
        return self._rational

    @property
    def depth(self) -> int:
        """The deepest overlay level (0 without overlays)."""
        return max((n.overlay.level for n in self._nodes.values()), default=0)

    def children(self, overlay: Overlay | int | None = None) -> list[Overlay]:
        """The overlays directly below ``overlay`` (``None``: the base)."""
        return [c.overlay for c in self._node(overlay).children]

    # ------------------------------------------------------------------ level splines
    def _spline_from_h(self, knots: tuple[Array, ...], H: Array) -> Any:
        if self._rational:
            return self._make(knots, H[..., :-1] / H[..., -1:], H[..., -1])
        return self._make(knots, H, None)

    def _level(self, node: Node) -> Any:
        if node.level_spline is None:
            node.level_spline = self._spline_from_h(self._knots_of(node), node.net)
        return node.level_spline

    # ------------------------------------------------------------------ adding overlays
    def _region_axis(self, ax: int, rng: Any, parent: Node, knots: Any, name: str) -> tuple[tuple[float, float], Array]:
        """Validate one direction's range; return the region widened to parent knots and the
        knots to insert (midpoints of the parent's spans in the region, or ``knots``)."""
        try:
            a, b = (float(x) for x in rng)
        except (TypeError, ValueError) as err:
            raise ParameterError(f"{name}: expected a pair (start, end), got {rng!r}") from err
        lo, hi = self._domain[ax]
        if not (np.isfinite(a) and np.isfinite(b) and a < b):
            raise ParameterError(f"{name}: expected finite start < end, got ({a!r}, {b!r})")
        t = self._knots_of(parent)[ax]
        tol = knot_tol(t)
        if a < lo - tol or b > hi + tol:
            raise ParameterError(f"{name}: ({a!r}, {b!r}) is not inside the domain [{lo!r}, {hi!r}]")
        if parent.handle is not None:
            pa, pb = parent.handle.region[ax]
            if a < pa - tol or b > pb + tol:
                raise ParameterError(f"{name}: ({a!r}, {b!r}) is not inside the parent overlay's region "
                                     f"[{pa!r}, {pb!r}] (an overlay refines part of its parent)")
        vals = np.unique(t[(t >= lo) & (t <= hi)])
        a2 = float(vals[max(int(np.searchsorted(vals, a + tol, side="right")) - 1, 0)])
        b2 = float(vals[min(int(np.searchsorted(vals, b - tol, side="left")), vals.size - 1)])
        if not a2 < b2:
            raise ParameterError(f"{name}: ({a!r}, {b!r}) shrinks to the single knot {a2!r} of the parent "
                                 f"(within its knot tolerance {tol:.3g}); a region must cover a knot span")
        if knots is None:
            inner = vals[(vals >= a2) & (vals <= b2)]
            mid = 0.5 * (inner[:-1] + inner[1:])
            # spans narrower than the knot tolerance get no midpoint: it would snap onto their ends
            # (as explicit knots are snapped, also when from_dict reads these back)
            ins = mid[np.diff(inner) > 2.0 * tol]
        else:
            ins = V.as_finite_array(knots, f"knots[{ax}]" if self._npar > 1 else "knots", ndim=1)
            if ins.size and (ins.min() < a2 - tol or ins.max() > b2 + tol or ins.min() <= lo or ins.max() >= hi):
                raise ParameterError(f"knots: the inserted {'uv'[ax]}-knots must lie strictly inside the domain and "
                                     f"within the region [{a2!r}, {b2!r}], got {ins.min()!r}..{ins.max()!r}")
            ins = np.sort(snap_knots(t, ins))
        return (a2, b2), ins

    def _add(self, ranges: tuple[Any, ...], parent: Overlay | int | None, knots: Any, ident: int | None = None) -> Overlay:
        pnode = self._node(parent, "parent")
        if knots is not None and self._npar == 2:
            if not isinstance(knots, (tuple, list)) or len(knots) != 2:
                raise InvalidGeometryError(f"knots: expected a pair (u_knots, v_knots), got {knots!r}")
            knots_ax = tuple(knots)
        else:
            knots_ax = (knots,) if self._npar == 1 else (None, None)
        names = ("u_range", "v_range") if self._npar == 2 else ("u_range",)
        regions, inserted, new_knots, Ts, vertices, refs = [], [], [], [], [], []
        for ax in range(self._npar):
            reg, ins = self._region_axis(ax, ranges[ax], pnode, knots_ax[ax], names[ax])
            p = self._deg[ax]
            t = self._knots_of(pnode)[ax]
            tau = merge_knots(t, ins)
            vals, counts = np.unique(tau, return_counts=True)
            if np.any(counts > p + 1):
                i = int(np.argmax(counts))
                raise InvalidGeometryError(f"knots: {'uv'[ax]}-knot {float(vals[i])!r} would get multiplicity "
                                           f"{counts[i]} > degree + 1")
            g = greville(tau, p)
            tol = knot_tol(tau)
            idx = np.flatnonzero((g >= reg[0] - tol) & (g <= reg[1] + tol))
            if idx.size == 0:
                raise ParameterError(f"{names[ax]}: the region [{reg[0]!r}, {reg[1]!r}] holds no refined control vertex")
            lo, hi = self._domain[ax]
            regions.append(reg)
            inserted.append(V.readonly(ins))
            new_knots.append(V.readonly(tau))
            vertices.append((int(idx[0]), int(idx[-1])))
            refs.append(V.readonly(np.clip(g[idx[0]: idx[-1] + 1], lo, hi)))
        # Refused before the dense refinement matrices (new poles x old poles per direction) and the
        # refined nets (reference, net, offsets, frames: ~4 (d + 1) + d^2 floats a pole) exist.
        olds = [self._knots_of(pnode)[ax] for ax in range(self._npar)]
        news = tuple(tau.size - self._deg[ax] - 1 for ax, tau in enumerate(new_knots))
        for ax in range(self._npar):
            kind = f"{'uv'[ax]}-knots" if self._npar == 2 else "knots"
            V.check_size((news[ax], olds[ax].size - self._deg[ax] - 1),
                         f"add_overlay with knots= of {inserted[ax].size} inserted {kind} (the refinement matrix)")
        V.check_size(news + (4 * (self._dim + 1) + self._dim ** 2,),
                     "add_overlay with knots= of " + " x ".join(str(k.size) for k in inserted) + " inserted (the refined net)")
        for ax in range(self._npar):
            Ts.append(refinement_matrix(olds[ax], self._deg[ax], new_knots[ax]))
        ident = self._next_id if ident is None else ident
        level = 1 if pnode.handle is None else pnode.handle.level + 1
        h = Overlay(ident, 0 if pnode.handle is None else pnode.handle.id, level, tuple(regions), tuple(inserted),
                    tuple(new_knots), tuple(vertices), tuple(refs))
        node = Node(h, pnode)
        node.T = tuple(Ts)
        node.blk = tuple(slice(a, b + 1) for a, b in vertices)
        node.offsets = np.zeros(h.shape + (self._dim,))
        pnode.children.append(node)
        self._nodes[ident] = node
        self._next_id = max(self._next_id, ident + 1)
        self._update(node, recurse=False)
        return h

    # ------------------------------------------------------------------ updates
    def _displacements(self, node: Node, offsets: Array, frames: Array | None) -> Array:
        d = self._dim
        shape = offsets.shape
        F = None if frames is None else frames.reshape(-1, d, d)
        return np.asarray(self._mapping(offsets.reshape(-1, d), F), float).reshape(shape)

    def _update(self, node: Node, recurse: bool = True, *, reference: bool = True) -> None:
        """Rebuild ``node`` (reference net and frames too if ``reference``), then its subtree."""
        if reference:
            node.R = _refine_net(node.up.net, node.T)
            node.frames = (self._frames_of(self._level(node.up), node.overlay.reference_parameters)
                           if self._mapping.uses_frames else None)
        D = self._displacements(node, node.stored_offsets, node.frames)
        H = node.reference.copy()
        if self._rational:
            W = H[node.blk + (slice(-1, None),)]
            WD = W * D
            H[node.blk + (slice(None, -1),)] += WD
        else:
            WD = D
            H[node.blk] += WD
        node.H = H
        node.level_spline = None
        self._build_delta(node, WD)
        node.version += 1
        if recurse:
            for c in node.children:
                self._update(c)

    def _build_delta(self, node: Node, WD: Array) -> None:
        """The delta spline of ``node``: its weighted displacements padded by ``degree`` zero
        vertices on each side, on the matching stretch of its knots (domain = support)."""
        h = node.overlay
        knots, sl, shape = [], [], []
        for ax, (i0, i1) in enumerate(h.vertices):
            p = self._deg[ax]
            n = h.knots[ax].shape[0] - p - 1
            a, b = max(i0 - p, 0), min(i1 + p, n - 1)
            knots.append(h.knots[ax][a: b + p + 2])
            sl.append(slice(i0 - a, i1 - a + 1))
            shape.append(b - a + 1)
        net = np.zeros(tuple(shape) + (self._dim,))
        net[tuple(sl)] = WD
        node.delta = self._make(tuple(knots), net, None)
        node.support = tuple((float(k[p]), float(k[-p - 1])) for k, p in zip(knots, self._deg))

    def _refresh_subtree_of_root(self) -> None:
        self._root.version += 1
        for c in self._root.children:
            self._update(c)

    # ------------------------------------------------------------------ edits
    def _index(self, node: Node, index: Any) -> tuple[int, ...]:
        shape = node.stored_offsets.shape[:-1] if node.handle is not None else node.net.shape[:-1]
        idx = (index,) if self._npar == 1 and not isinstance(index, (tuple, list)) else tuple(index) if isinstance(index, (tuple, list)) else None
        if idx is None or len(idx) != self._npar or any(isinstance(i, bool) or not isinstance(i, (int, np.integer)) for i in idx):
            raise InvalidGeometryError(f"index: expected {'(i, j)' if self._npar == 2 else 'an integer i'}, got {index!r}")
        out = []
        for i, n in zip(idx, shape):
            i = int(i)
            if i < 0:  # no Python wrap-around: -1 silently moved the last vertex
                raise InvalidGeometryError(f"index: {index!r} has a negative entry; expected 0 <= index < {shape}")
            if i >= n:
                raise InvalidGeometryError(f"index: {index!r} is outside the vertex array of shape {shape}")
            out.append(i)
        return tuple(out)

    def _vector(self, value: ArrayLike, name: str) -> Array:
        a = V.as_finite_array(value, name)
        if a.shape != (self._dim,):
            raise InvalidGeometryError(f"{name}: expected shape ({self._dim},), got {a.shape}")
        return a

    def _move_world(self, node: Node, idx: tuple[Any, ...], disp: Array) -> None:
        """Add world displacements ``disp`` to vertices ``idx`` of ``node`` (stored as offsets)."""
        if node.handle is None:
            base = self._root.level_spline
            P = np.array(base.control_points)
            P[idx] += disp
            w = None if base.weights is None else base.weights
            self._set_base(self._make(self._base_knots(base), P, w))
            return
        F = None if node.frames is None else node.frames[idx]
        d = self._dim
        cur = self._displacements(node, node.stored_offsets[idx], F)
        Fm = None if F is None else F.reshape(-1, d, d)
        new = np.asarray(self._mapping.inverse((cur + disp).reshape(-1, d), Fm), float)
        node.stored_offsets[idx] = new.reshape(cur.shape)
        self._update(node, reference=False)

    def _set_base(self, base: Any) -> None:
        self._root.level_spline = base
        self._root.H = np.array(base.homogeneous_points, dtype=float)
        self._refresh_subtree_of_root()

    def _snapshot(self, node: Node) -> Any:
        """What an edit of ``node``'s own vertices changes, for :meth:`_restore`."""
        return self._level(node) if node.handle is None else node.stored_offsets.copy()

    def _restore(self, node: Node, saved: Any) -> None:
        """Undo edits of ``node``'s vertices made since :meth:`_snapshot` (a failed drag leaves nothing)."""
        if node.handle is None:
            self._set_base(saved)
        else:
            node.offsets = saved
            self._update(node, reference=False)

    def set_offsets(self, overlay: Overlay | int, offsets: ArrayLike) -> None:
        """Replace all stored offsets of ``overlay`` (in place; see the class notes).

        Parameters
        ----------
        offsets : array_like, shape overlay.shape + (d,)
            In the offset mapping's coordinates (frame: ``(t, b, n)`` components).
        """
        node = self._node(overlay)
        if node.handle is None:
            raise InvalidGeometryError("overlay: the base stores control points, not offsets; use move_vertex")
        o = V.as_finite_array(offsets, "offsets")
        if o.shape != node.stored_offsets.shape:
            raise InvalidGeometryError(f"offsets: expected shape {node.stored_offsets.shape}, got {o.shape}")
        node.offsets = o.copy()
        self._update(node, reference=False)

    def set_offset(self, overlay: Overlay | int, index: int | Sequence[int], offset: ArrayLike) -> None:
        """Set one stored offset of ``overlay`` (in place), e.g. ``(0, 0, h)``: height ``h`` along
        the parent's normal with the frame mapping."""
        node = self._node(overlay)
        if node.handle is None:
            raise InvalidGeometryError("overlay: the base stores control points, not offsets; use move_vertex")
        idx = self._index(node, index)
        node.stored_offsets[idx] = self._vector(offset, "offset")
        self._update(node, reference=False)

    def offsets(self, overlay: Overlay | int) -> Array:
        """A copy of the stored offsets of ``overlay``, shape ``overlay.shape + (d,)``."""
        node = self._node(overlay)
        if node.handle is None:
            raise InvalidGeometryError("overlay: the base has no offsets")
        return node.stored_offsets.copy()

    def reference_frames(self, overlay: Overlay | int) -> Array | None:
        """The parent's frames at the overlay's reference parameters, ``shape + (d, d)`` (columns are
        the axes); ``None`` for a mapping that uses no frames."""
        node = self._node(overlay)
        if node.handle is None:
            raise InvalidGeometryError("overlay: the base has no reference frames")
        return None if node.frames is None else node.frames.copy()

    def control_points(self, overlay: Overlay | int | None = None) -> Array:
        """World positions of the overlay's control vertices (reference + displacement), shape
        ``overlay.shape + (d,)``; of the base net for ``None``."""
        node = self._node(overlay)
        H = node.net if node.handle is None else node.net[node.blk]
        return H[..., :-1] / H[..., -1:] if self._rational else H.copy()

    # ------------------------------------------------------------------ flatten
    def _flat_h(self) -> tuple[tuple[Array, ...], Array]:
        """Knots of the common refinement and the exact homogeneous net there."""
        nodes = list(self._nodes.values())
        knots = tuple(_union_knots([self._knots_of(self._root)[ax]] + [n.overlay.knots[ax] for n in nodes])
                      for ax in range(self._npar))
        base_kn = self._knots_of(self._root)
        H = _refine_net(self._root.net, tuple(refinement_matrix(base_kn[ax], self._deg[ax], knots[ax])
                                            for ax in range(self._npar)))
        d = self._dim
        for n in nodes:
            WD = (n.net - n.reference)[n.blk][..., :d]
            Ts = tuple(refinement_matrix(n.overlay.knots[ax], self._deg[ax], knots[ax])[:, n.blk[ax]]
                       for ax in range(self._npar))
            H[..., :d] += _refine_net(WD, Ts)
        return knots, H

    def pole_counts(self) -> dict[str, int]:
        """Storage of the hierarchy against its flat form (course §5-17).

        Returns
        -------
        dict
            ``base`` (base poles), ``offsets`` (stored overlay offsets), ``stored`` (their sum),
            ``flat`` (poles of :meth:`flatten`'s single spline).
        """
        base = int(np.prod(self._root.net.shape[:-1]))
        offs = sum(int(np.prod(n.stored_offsets.shape[:-1])) for n in self._nodes.values())
        knots = [
            _union_knots([self._knots_of(self._root)[ax]] + [n.overlay.knots[ax] for n in self._nodes.values()])
            for ax in range(self._npar)]
        flat = int(np.prod([k.shape[0] - p - 1 for k, p in zip(knots, self._deg)]))
        return {"base": base, "offsets": offs, "stored": base + offs, "flat": flat}

    # ------------------------------------------------------------------ copy, storage
    def copy(self) -> Self:
        """An independent copy (handles stay valid for the copy: they are shared, immutable)."""
        new = _copy.copy(self)
        memo: dict[int, Node] = {}

        def clone(n: Node, parent: Node | None) -> Node:
            c = Node(n.handle, parent)
            for s in Node.__slots__:
                if s not in ("parent", "children"):
                    v = getattr(n, s)
                    setattr(c, s, v.copy() if isinstance(v, np.ndarray) and s in ("offsets",) else v)
            c.children = [clone(k, c) for k in n.children]
            memo[id(n)] = c
            return c

        new._root = clone(self._root, None)
        new._nodes = {i: memo[id(n)] for i, n in self._nodes.items()}
        new._grid_cache = None
        return new

    def _to_dict(self) -> dict[str, Any]:
        return {
            "type": self._kind,
            "version": FORMAT_VERSION,
            "offset_mapping": self._mapping.name,
            "base": self._root.level_spline.to_dict(),
            "overlays": [
                {
                    "id": n.overlay.id,
                    "parent": n.overlay.parent,
                    "region": [list(r) for r in n.overlay.region],
                    "inserted_knots": [k.tolist() for k in n.overlay.inserted],
                    "offsets": n.stored_offsets.tolist(),
                }
                for n in self._nodes.values()
            ],
        }

    def _load_overlays(self, data: dict[str, Any]) -> None:
        items = data.get("overlays", [])
        if not isinstance(items, list):
            raise InvalidGeometryError("from_dict: 'overlays' must be a list")
        def whole(x: Any) -> bool:
            return isinstance(x, int) and not isinstance(x, bool)

        for k, item in enumerate(items):
            try:
                ident, parent = item["id"], item["parent"]
                region, ins, offs = item["region"], item["inserted_knots"], item["offsets"]
            except (KeyError, TypeError, IndexError) as err:
                raise InvalidGeometryError(f"from_dict: overlay {k}: missing or bad entry ({err!r})") from err
            if not whole(ident) or not whole(parent):
                raise InvalidGeometryError(f"from_dict: overlay {k}: 'id' and 'parent' must be integers, got "
                                           f"{ident!r} and {parent!r}")
            if ident in self._nodes or ident < 1:
                raise InvalidGeometryError(f"from_dict: overlay {k}: duplicate or invalid id {ident}")
            if parent != 0 and parent not in self._nodes:
                raise InvalidGeometryError(f"from_dict: overlay {ident}: parent {parent} must come before it")
            if not all(isinstance(x, (list, tuple)) and len(x) == self._npar for x in (region, ins)):
                raise InvalidGeometryError(f"from_dict: overlay {ident}: 'region' and 'inserted_knots' must be lists "
                                           f"of {self._npar} entries (one per parametric direction), got "
                                           f"{reprlib.repr(region)} and {reprlib.repr(ins)}")
            kn = ins[0] if self._npar == 1 else tuple(ins)
            try:
                h = self._add(tuple(region), parent, kn, ident=ident)
            except InvalidGeometryError as err:  # same class, with the overlay named
                raise type(err)(f"from_dict: overlay {ident}: {err}") from err
            node = self._nodes[ident]
            o = V.as_finite_array(offs, f"overlays[{k}].offsets")
            if o.shape != node.stored_offsets.shape:
                raise InvalidGeometryError(f"from_dict: overlay {ident}: offsets of shape {o.shape}, expected "
                                           f"{node.stored_offsets.shape}")
            node.offsets = o
            self._update(node, recurse=False, reference=False)
            if not all(np.array_equal(a, b) for a, b in zip(h.inserted, [np.asarray(x, float) for x in ins])):
                raise InvalidGeometryError(f"from_dict: overlay {ident}: its knots do not reproduce")


def check_format(data: object, kind: str) -> None:
    """Reject dicts of another type or a newer format version."""
    if not isinstance(data, dict) or data.get("type") != kind:
        raise InvalidGeometryError(f"from_dict: expected a dict with type {kind!r}, got "
                                   f"{data.get('type') if isinstance(data, dict) else type(data).__name__!r}")
    version = data.get("version")
    if not isinstance(version, int) or isinstance(version, bool) or not 1 <= version <= FORMAT_VERSION:
        raise InvalidGeometryError(f"from_dict: format version {version!r} is not supported (this is version "
                                   f"{FORMAT_VERSION}; older versions load)")
