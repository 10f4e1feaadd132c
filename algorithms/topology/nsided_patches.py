"""The corner patches of the n-sided fill (step 5 of :func:`.nsided.fill_hole`, course §8-3).

Patch ``i`` covers hole corner ``V_i``: its two hole sides and the ribbons along them are placed
exactly into the patch's knot space (:func:`_boundary_ribbons`: the side's knots, the degree raised
by the cubic coefficients), so are its two internal edges and their cross fields
(:func:`_internal_ribbons`); these fix the two outer rows of poles on every edge
(:func:`_assemble_poles`), and the interior poles minimise the thin-plate energy
``int |F_uu|^2 + 2|F_uv|^2 + |F_vv|^2`` (:func:`_fair_interior`, Gauss-Legendre Gram matrices,
sparse). :func:`corner_patch` does all of it for one corner; :func:`patch_poles` says how many poles
it will have before any of that work, and :class:`FairSystems` keeps one hole's fairing factors for
its second layout.
"""

from __future__ import annotations

import functools

import numpy as np
from numpy.typing import NDArray
from scipy import sparse
from scipy.sparse.linalg import SuperLU, splu

from .. import tolerances
from ..errors import InvalidGeometryError
from ..kernel.basis import gram_band_index, gram_bands
from ..kernel.sparse_kron import kron_rows, kron_sum
from ..kernel.surface import BSplineSurface
from .nsided_corners import CornerFit
from .nsided_edges import InternalEdge
from .nsided_poly import Poly, collocation_sites, represent, represent_values
from .nsided_prepare import Side, half_space

__all__ = ["corner_patch", "patch_poles", "FairSystems"]

Array = NDArray[np.float64]


class FairSystems:
    """The fairing systems (:func:`_fair_system`) of one hole's large patches, kept while its layouts
    are built: the central split's plain and harmonic layouts (:func:`.nsided.fill_hole`) give a
    corner the same patch space and free poles, so the same system, where only the fixed poles
    differ. Linkrods face 22 factored its 13 756- to 100 344-unknown systems twice, 2.7 s of 13.8.

    Systems are kept while their factors' entries (SuperLU's ``nnz`` and the coupling block's) stay
    within ``budget`` in all (default ``tolerances.FILL_FAIR_KEEP_NNZ``); past it a system is
    factored for its patch alone, as without the store. The same factors give the same poles bit
    for bit. Systems of at most ``tolerances.FILL_FAIR_CACHE_FREE`` unknowns are not kept here but in
    the process-wide cache (:func:`_fair_system_cached`).
    """

    def __init__(self, budget: int | None = None) -> None:
        self.budget = int(tolerances.FILL_FAIR_KEEP_NNZ if budget is None else budget)
        self.entries = 0
        self._kept: dict[tuple, tuple[sparse.csr_matrix, SuperLU]] = {}

    def get(self, ku: bytes, kv: bytes, degree: tuple[int, int], free: NDArray[np.bool_]
            ) -> tuple[sparse.csr_matrix, SuperLU]:
        """:func:`_fair_system` for these arguments, factored once while the budget allows."""
        key = (ku, kv, degree, free.shape, np.packbits(free).tobytes())
        kept = self._kept.get(key)
        if kept is not None:
            return kept
        system = _fair_system(ku, kv, degree, free)
        size = int(system[1].nnz) + int(system[0].nnz)
        if self.entries + size <= self.budget:
            self._kept[key] = system
            self.entries += size
        return system

    def __len__(self) -> int:
        return len(self._kept)


def patch_poles(i: int, S: list[Side], sig: Array, corners: CornerFit) -> int:
    """The number of poles of :func:`corner_patch` ``i`` (the size of its fairing system), from its
    patch space alone."""
    j = (i - 1) % len(S)
    (Pu, Pv), (Ku, Kv) = _patch_space(S[i], S[j], sig[i], sig[j], bool(corners.twist[i] > tolerances.FILL_TWIST_TOL))
    return (len(Ku) - Pu - 1) * (len(Kv) - Pv - 1)


def corner_patch(i: int, S: list[Side], sig: Array, corners: CornerFit, c1: Array, edges: list[InternalEdge],
                 rational: bool, origin: Array, systems: FairSystems | None = None) -> BSplineSurface:
    """Patch ``i`` (hole corner ``V_i``): its boundary rows and ribbons fixed, the rest faired.

    Its ``v = 0`` edge is ``[0, sig_i]`` of side ``i``, its ``u = 0`` edge ``[sig_{i-1}, 1]`` of
    side ``i - 1`` (reversed), its ``u = 1`` edge internal edge ``i`` and its ``v = 1`` edge
    internal edge ``i - 1``; ``c1`` (n, nf) are the ribbon coefficients at the midpoints, ``origin``
    (3,) the working origin added back; ``systems``: the hole's kept fairing systems (shared by
    its layouts), if any.
    """
    j = (i - 1) % len(S)
    sa, sb = S[i], S[j]
    pa = _coefficient_poly(corners.start[i], corners.start_d[i], c1[i], edges[i].coef_d_before)  # u: s = sig_i u
    pb = _coefficient_poly(corners.end[i], corners.end_d[i], c1[j], edges[j].coef_d_after)  # v: s = 1 - tau_j v
    degree, knots = _patch_space(sa, sb, sig[i], sig[j], bool(corners.twist[i] > tolerances.FILL_TWIST_TOL))
    boundary = _boundary_ribbons(sa, sb, pa, pb, sig[i], 1.0 - sig[j], degree, knots)
    internal = _internal_ribbons(edges[i], edges[j], degree, knots)
    H = _assemble_poles(boundary, internal, degree, knots, systems)
    if rational:
        if np.any(H[..., 3] <= 0):
            raise InvalidGeometryError(f"sides: the rational fill of corner {i} got a non-positive weight "
                                       f"({H[..., 3].min():.3g}); the neighbours' weights vary too much")
        return BSplineSurface(degree, knots, H[..., :3] / H[..., 3:] + origin, H[..., 3])
    return BSplineSurface(degree, knots, H + origin)


def _coefficient_poly(v0: Array, d0: Array, v1: Array, d1: Array) -> Poly:
    """The cubic ribbon coefficients on a half side, ``t`` in [0, 1]: values and derivatives
    (each (nf,)) at the corner (``t = 0``) and at the midpoint (``t = 1``)."""
    return Poly.hermite([(0.0, 0, v0), (0.0, 1, d0), (1.0, 0, v1), (1.0, 1, d1)])


def _patch_space(sa: Side, sb: Side, sig_i: float, sig_j: float,
                 twisted: bool) -> tuple[tuple[int, int], tuple[Array, Array]]:
    """Bidegree and knots of the patch between half sides ``sa[0, sig_i]`` (u) and ``sb[sig_j, 1]``
    (v, reversed): the sides' knots, the degree raised by 3 (cubic coefficients times the fields);
    with ``twisted`` (an incompatible corner twist) a corner span :func:`_corner_knot` in both."""
    Pu, Pv = max(sa.degree + 3, 4), max(sb.degree + 3, 4)
    Ku = half_space(sa, 0.0, sig_i, False, Pu)
    Kv = half_space(sb, sig_j, 1.0, True, Pv)
    if twisted:  # confine the incompatible twist to a small corner span
        Ku, Kv = _corner_knot(Ku, Pu), _corner_knot(Kv, Pv)
    return (Pu, Pv), (Ku, Kv)


def _boundary_ribbons(sa: Side, sb: Side, pa: Poly, pb: Poly, sig_i: float, tau_j: float,
                      degree: tuple[int, int], knots: tuple[Array, Array]) -> tuple[Array, Array, Array, Array]:
    """Poles of the two hole sides of a patch and of the ribbons (cross derivatives) along them.

    Exact: each is the side (or the side's fields times the cubic coefficients ``pa``, ``pb``)
    placed into the patch's knot space (:func:`represent`, checked).

    Returns
    -------
    row0, da : ndarray, shape (nu, w)
        ``B_a(sig_i u)`` and ``F_v(u, 0) = sum_f pa_f(u) f_a(sig_i u)``, on ``(degree[0], knots[0])``.
    col0, db : ndarray, shape (nv, w)
        ``B_b(1 - tau_j v)`` and ``F_u(0, v) = sum_f pb_f(v) f_b(1 - tau_j v)``, on
        ``(degree[1], knots[1])``.
    """
    (Pu, Pv), (Ku, Kv) = degree, knots
    u, v = collocation_sites(Pu, Ku), collocation_sites(Pv, Kv)
    Ba, Fa = sa.values(sig_i * u)  # the side and its fields at the same parameters: B once
    Bb, Fb = sb.values(1.0 - tau_j * v)
    row0 = represent_values(Ba, Pu, Ku)
    da = represent_values(np.einsum("mf,mfw->mw", pa(u), Fa), Pu, Ku)
    col0 = represent_values(Bb, Pv, Kv)
    db = represent_values(np.einsum("mf,mfw->mw", pb(v), Fb), Pv, Kv)
    return row0, da, col0, db


def _internal_ribbons(edge_u: InternalEdge, edge_v: InternalEdge, degree: tuple[int, int],
                      knots: tuple[Array, Array]) -> tuple[Array, Array, Array, Array]:
    """Poles of the two internal edges of a patch and of its cross derivatives along them.

    Returns
    -------
    colE, colL : ndarray, shape (nv, w)
        ``edge_u``'s curve and left field (the patch's ``u = 1`` edge), on ``(degree[1], knots[1])``.
    rowE, rowR : ndarray, shape (nu, w)
        ``edge_v``'s curve and right field (the ``v = 1`` edge), on ``(degree[0], knots[0])``.
    """
    (Pu, Pv), (Ku, Kv) = degree, knots
    Ei, Li, Ej, Rj = edge_u.curve, edge_u.left, edge_v.curve, edge_v.right
    colE = represent(lambda v: Ei(v), Pv, Kv)
    colL = represent(lambda v: Li(v), Pv, Kv)
    rowE = represent(lambda u: Ej(u), Pu, Ku)
    rowR = represent(lambda u: Rj(u), Pu, Ku)
    return colE, colL, rowE, rowR


def _assemble_poles(boundary: tuple[Array, Array, Array, Array], internal: tuple[Array, Array, Array, Array],
                    degree: tuple[int, int], knots: tuple[Array, Array], systems: FairSystems | None = None) -> Array:
    """The patch's poles (nu, nv, w): the two outer rows on every edge from the boundary and internal
    ribbons (:func:`_boundary_ribbons`, :func:`_internal_ribbons`), the interior faired
    (:func:`_fair_interior`). Poles set twice (the corner blocks) are averaged: they agree but for
    the twist."""
    row0, da, col0, db = boundary
    colE, colL, rowE, rowR = internal
    (Pu, Pv), (Ku, Kv) = degree, knots
    nu, nv = len(Ku) - Pu - 1, len(Kv) - Pv - 1
    w = row0.shape[1]
    hu0, hv0 = Ku[Pu + 1] / Pu, Kv[Pv + 1] / Pv
    hu1, hv1 = (1.0 - Ku[nu - 1]) / Pu, (1.0 - Kv[nv - 1]) / Pv
    cnt = np.zeros((nu, nv))
    acc = np.zeros((nu, nv, w))
    for idx, vals in (((slice(None), 0), row0), ((slice(None), 1), row0 + hv0 * da),
                      ((0, slice(None)), col0), ((1, slice(None)), col0 + hu0 * db),
                      ((nu - 1, slice(None)), colE), ((nu - 2, slice(None)), colE - hu1 * colL),
                      ((slice(None), nv - 1), rowE), ((slice(None), nv - 2), rowE - hv1 * rowR)):
        acc[idx] += vals
        cnt[idx] += 1
    H = np.full((nu, nv, w), np.nan)
    fixed = cnt > 0
    H[fixed] = acc[fixed] / cnt[fixed][:, None]
    return _fair_interior(H, ~fixed, degree, knots, systems)


def _corner_knot(K: Array, degree: int) -> Array:
    """Insert a knot of multiplicity ``degree - 1`` at ``tolerances.FILL_CORNER_SPAN`` (or half the
    first span)."""
    first = float(K[degree + 1])
    kappa = min(tolerances.FILL_CORNER_SPAN, 0.5 * first)
    return np.r_[K[:degree + 1], [kappa] * (degree - 1), K[degree + 1:]]


# ==================================================================================== fairing
@functools.lru_cache(maxsize=64)
def _gram_cached(knots_key: bytes, degree: int) -> tuple[Array, Array, Array]:
    """The Gram matrices of orders 0, 1 and 2 (:func:`_gram`) for the knots as bytes (hashable), dense,
    from their bands (:func:`~..kernel.basis.gram_bands`: one evaluation of the basis and its
    derivatives at the Gauss points, each entry summed straight into its place); read-only, shared
    by the cache.

    The dense product ``B^T (w B)`` (before 2026-12-06) multiplied the whole collocation matrices,
    zeros and all: 0.14 s for a degree-6 space of a few hundred poles, eight of them 1.2 s of
    linkrods pair [22, 23]'s central split; BLAS sums its terms in an order of its own, so the two
    agree to round-off (within 1e-13 of the largest entry, tested), not bit for bit. The bands are
    the plate's (:func:`.plate_fill._gram`) since 2026-12-06, where this module had a copy of its
    own that formed the Gauss points and the products in another order (the same to round-off)."""
    bands = gram_bands(np.frombuffer(knots_key), degree, 2)
    n, h = bands.shape[1], bands.shape[2]
    row, col, inside = gram_band_index(n, degree)
    out: list[Array] = []
    for band in bands.reshape(3, n * h):
        G = np.zeros((n, n))
        G[row[inside], col[inside]] = band[inside]
        G.flags.writeable = False
        out.append(G)
    return out[0], out[1], out[2]


def _gram(knots: Array, degree: int, order: int) -> Array:
    """``G[i, j] = int N_i^(order) N_j^(order)`` by Gauss-Legendre per span (cached per space), for
    ``order`` 0, 1 or 2."""
    return _gram_cached(np.ascontiguousarray(knots, float).tobytes(), int(degree))[order]


def _fair_interior(H: Array, free: NDArray[np.bool_], degree: tuple[int, int], knots: tuple[Array, Array],
                   systems: FairSystems | None = None) -> Array:
    """Fill the free poles by minimising the thin-plate energy with the others fixed.

    The energy's matrix ``K = Gu2 (x) Gv0 + 2 Gu1 (x) Gv1 + Gu0 (x) Gv2`` is banded-Kronecker (at most
    ``(2p+1)^2`` non-zeros a row), so it is built sparse and the free block is factored by SuperLU:
    a dense (nu nv)^2 array was 1.1 GB and ~90 s for a 213 x 56 patch (lens face 2).

    The free block is symmetric positive definite, so SuperLU runs in its symmetric mode (minimum
    degree on ``K + K^T``, diagonal pivots): on linkrods face 20's patches (13794 to 62111 free
    poles) 3 to 6 times faster than the default column ordering with partial pivoting, and with a
    3 to 4 times smaller residual (7e-10 against 3e-9 relative; the poles move by 1e-9 relative).
    ``systems``: where a large system is kept for the hole's other layout (:class:`FairSystems`)."""
    if not free.any():
        return H
    f = free.ravel()
    key = (np.ascontiguousarray(knots[0], float).tobytes(), np.ascontiguousarray(knots[1], float).tobytes(),
           (int(degree[0]), int(degree[1])))
    if int(f.sum()) <= int(tolerances.FILL_FAIR_CACHE_FREE):
        coupling, lu = _fair_system_cached(*key, free.shape, np.packbits(f).tobytes())
    elif systems is not None:
        coupling, lu = systems.get(*key, free)
    else:
        coupling, lu = _fair_system(*key, free)
    flat = H.reshape(-1, H.shape[2]).copy()
    flat[f] = lu.solve(-(coupling @ flat[~f]))
    return flat.reshape(H.shape)


def _fair_system(ku: bytes, kv: bytes, degree: tuple[int, int], free: NDArray[np.bool_]
                 ) -> tuple[sparse.csr_matrix, SuperLU]:
    """The thin-plate energy's free-by-fixed block and the free block's factors
    (:func:`_fair_interior`), for knots given as bytes."""
    G = [[_gram(np.frombuffer(k), degree[d], o) for o in range(3)] for d, k in enumerate((ku, kv))]  # dense, read by kron_sum
    terms = [(1, G[0][2], G[1][0]), (2, G[0][1], G[1][1]), (1, G[0][0], G[1][2])]
    f = free.ravel()
    block = _free_block(free)
    # the free rows of K, bit for bit K[f]: made alone where the free poles are a block of the grid
    Kf = kron_sum(terms)[f] if block is None else kron_rows(terms, *block)
    lu = splu(Kf[:, f].tocsc(), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, options={"SymmetricMode": True})
    return Kf[:, ~f], lu


def _free_block(free: NDArray[np.bool_]) -> tuple[range, range] | None:
    """The rows and columns of the grid whose product is exactly the ``free`` poles (the interior
    that :func:`_assemble_poles` leaves free), or ``None`` for another pattern."""
    rows, cols = np.flatnonzero(free.any(axis=1)), np.flatnonzero(free.any(axis=0))
    if rows.size == 0 or rows[-1] - rows[0] + 1 != rows.size or cols[-1] - cols[0] + 1 != cols.size:
        return None
    block = range(int(rows[0]), int(rows[-1]) + 1), range(int(cols[0]), int(cols[-1]) + 1)
    return block if int(np.count_nonzero(free)) == rows.size * cols.size else None


@functools.lru_cache(maxsize=16)
def _fair_system_cached(ku: bytes, kv: bytes, degree: tuple[int, int], shape: tuple[int, int], free: bytes
                        ) -> tuple[sparse.csr_matrix, SuperLU]:
    """:func:`_fair_system` kept for small systems: a hole's patches share one layout (the same
    knots and free poles; a ring of n sides refactored the same 196-unknown system n times, 7 ms
    each), and the same factors give the same poles bit for bit."""
    mask = np.unpackbits(np.frombuffer(free, np.uint8), count=shape[0] * shape[1]).astype(bool).reshape(shape)
    return _fair_system(ku, kv, degree, mask)
