"""S-patches: multisided Bézier surfaces over a regular n-gon (course §8-1, 8-2).

An ``n``-sided S-patch of depth ``d`` (Loop & DeRose 1989, "A multisided generalization of Bézier
surfaces", ACM TOG 8(3)) is the composition of two maps:

1. the domain map ``L``: a point ``x`` of the regular ``n``-gon goes to the ``(n-1)``-simplex through
   the generalised barycentric (Wachspress) coordinates ``λ(x) = (λ_0, ..., λ_{n-1})``;
2. a Bézier simplex of degree ``d`` over the ``(n-1)``-simplex, with control points ``P_I`` indexed
   by the multi-indices ``I = (i_0, ..., i_{n-1})``, ``i_k >= 0``, ``|I| = d``:

.. math::

    S(x) = \\sum_{|I| = d} P_I\\, B^d_I(λ(x)), \\qquad
    B^d_I(λ) = \\frac{d!}{i_0! \\cdots i_{n-1}!}\\, λ_0^{i_0} \\cdots λ_{n-1}^{i_{n-1}}.

A rational S-patch carries a weight ``ω_I`` per control point:
``S = Σ ω_I P_I B_I / Σ ω_I B_I``.

Domain and conventions
----------------------
The domain is the regular ``n``-gon of circumradius 1 with vertex ``k`` at angle ``2πk/n``
(:func:`domain_vertices`). Side ``k`` runs from vertex ``k`` to vertex ``k + 1 (mod n)``; its
outward unit normal is at angle ``2π(k + 1/2)/n`` and the apothem is ``h = cos(π/n)``. The edge
function ``L_k(x) = h - x·n_k`` is the distance from the line of side ``k`` (positive inside).
Wachspress coordinates of a regular polygon (the constant corner areas cancel) are

.. math::

    λ_k = \\frac{w_k}{\\sum_j w_j}, \\qquad w_k = \\prod_{j \\notin \\{k-1, k\\}} L_j ,

rational of degree ``n - 2`` over ``n - 3`` in ``(x, y)``, equal to 1 at vertex ``k``, linear along
the two sides at vertex ``k`` and zero on all other sides (Wachspress 1975; Floater 2015, "Generalized
barycentric coordinates and applications", §3). On side ``k`` only ``λ_k = 1 - t`` and
``λ_{k+1} = t`` are non-zero, so the boundary curve of side ``k`` is the Bézier curve of degree ``d``
whose control points are the ``P_I`` with ``i_k + i_{k+1} = d``; and since ``λ_j`` vanishes to first
order on the side for every other ``j``, the cross-boundary derivative there depends only on the
``P_I`` with ``i_k + i_{k+1} >= d - 1`` (the first two rows next to the side).

Control points are stored as an ``(m, dim)`` array in the order of :func:`spatch_indices`
(multi-indices in descending lexicographic order, ``m = C(n + d - 1, d)``), or given as a mapping
from index tuples to points.

Derivatives are exact: every quantity (the edge functions, ``w_k``, ``λ_k``, the Bernstein
polynomials and the rational quotient) is propagated as a truncated bivariate Taylor series ("jet")
of the requested order, with exact jet products and quotients (automatic differentiation in Taylor
mode; Griewank & Walther, "Evaluating Derivatives", 2nd ed., ch. 13). Nothing is differenced.
"""

from __future__ import annotations

import functools
import numbers
from collections.abc import Mapping
from dataclasses import dataclass, field
from math import comb, factorial
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import _validate as V
from .. import tolerances
from ..errors import InvalidGeometryError
from ..kernel._common import SCALAR, ControlPointValue
from ..kernel.curve import BSplineCurve
from ._common import check_depth, check_sides, edge_normals, index_tuples
from .wachspress import (
    _domain_points,
    _jet_div,
    _jet_mul,
    _jet_to_derivatives,
    _wachspress_jets,
    wachspress,
    wachspress_derivatives,
    wachspress_gradient,
)

__all__ = [
    "SPatch",
    "spatch_indices",
    "domain_vertices",
    "wachspress",
    "wachspress_gradient",
    "wachspress_derivatives",
]

Array = NDArray[np.float64]

# The domain slack and the largest number of sides are tolerances.SPATCH_DOMAIN_SLACK and
# tolerances.SPATCH_MAX_SIDES, read at call time.

#: Points processed per block in the vectorised kernels (bounds the ``points x indices x jet``
#: work arrays to a few tens of MB).
_BLOCK_ELEMENTS = 4_000_000

#: At most this many points per block: the Bernstein tables of a block then stay in the CPU cache
#: (measured: 2048-point blocks are up to 2x faster than 10k-point ones on the 2-core machine).
_BLOCK_POINTS = 2048


# ---------------------------------------------------------------------------- index sets
def spatch_indices(sides: int, depth: int) -> NDArray[np.intp]:
    """All multi-indices of an S-patch: ``n``-tuples of non-negative integers summing to ``depth``.

    Parameters
    ----------
    sides : int
        ``n >= 3``.
    depth : int
        ``d >= 1``.

    Returns
    -------
    ndarray of intp, shape (m, sides)
        ``m = C(sides + depth - 1, depth)`` rows in descending lexicographic order: the first row is
        ``(depth, 0, ..., 0)``, the last ``(0, ..., 0, depth)``. A fresh (writable) array.
    """
    n = check_sides(sides)
    d = check_depth(depth)
    # m rows, built as Python tuples first (about 24 bytes per entry with the array): refuse before
    # spending minutes and gigabytes on them (spatch_indices(5, 200) has 6.9e7 rows)
    V.check_size((comb(n + d - 1, n - 1), n), f"spatch_indices({n}, {d})", itemsize=24)
    return np.array(index_tuples(n, d), dtype=np.intp).reshape(-1, n)


def domain_vertices(sides: int) -> Array:
    """Vertices of the regular ``n``-gon domain: circumradius 1, vertex ``k`` at angle ``2πk/n``.

    Returns
    -------
    ndarray, shape (sides, 2)
    """
    n = check_sides(sides)
    a = 2.0 * np.pi * np.arange(n) / n
    return np.column_stack((np.cos(a), np.sin(a)))


# ---------------------------------------------------------------------------- the patch
def _multinomials(idx: NDArray[np.intp], depth: int) -> Array:
    f = np.array([factorial(i) for i in range(depth + 1)], dtype=float)
    return factorial(depth) / np.prod(f[idx], axis=1)


def _unit_jet(r: int) -> Array:
    e = np.zeros((r + 1) * (r + 2) // 2)
    e[0] = 1.0
    return e


@functools.lru_cache(maxsize=128)
def _multinomial_column(n: int, depth: int) -> Array:
    """``d! / I!`` for the indices of :func:`spatch_indices` order, shape (m, 1)."""
    idx = np.array(index_tuples(n, depth), dtype=np.intp).reshape(-1, n)
    return _multinomials(idx, depth)[:, None]


def _bernstein_levels(lam: Array, n: int, depth: int, lowest: int = 0, monomials: bool = False) -> dict[int, Array]:
    """Bernstein polynomials ``B^l_I(λ) = (l!/I!) λ^I`` of the depths ``lowest .. depth``, point axis last.

    Entry ``l`` has shape (C(n + l - 1, l), N) in :func:`spatch_indices` order. The monomials are
    built from the last coordinate forwards, using the recursive structure of the order: the
    indices of sum ``e`` over coordinates ``s .. n-1`` are ``(i, J)`` for ``i = e .. 0`` and ``J``
    those of sum ``e - i`` over ``s + 1 .. n-1``, so each block is one power of ``λ_s`` times a
    contiguous block built before (no gathers; ``~m`` products per depth and point). Products of
    non-negative factors: the relative error of a value is at most ``~(l + 1) ε`` for ``λ >= 0``,
    and a coordinate that is exactly zero on a side gives exactly zero to every polynomial with a
    positive power of it. (``exp(J · log λ)``, used before, is as accurate but costs one ``exp`` per
    value.)

    Parameters
    ----------
    lam : ndarray, shape (n, N)
        Barycentric (Wachspress) coordinates, one column per point.
    monomials : bool
        Return the monomials ``λ^I`` without the factors ``l!/I!`` (callers that fold them into
        the control points save a pass over the values).
    """
    N = lam.shape[1]
    powers = np.empty((n, depth + 1, N))
    powers[:, 0] = 1.0
    for e in range(1, depth + 1):
        powers[:, e] = powers[:, e - 1] * lam
    M = [powers[n - 1, e][None] for e in range(depth + 1)]  # coordinate n-1 alone
    for s in range(n - 2, -1, -1):
        M_new: list[Array] = []
        for e in range(depth + 1):
            if s == 0 and e < lowest:
                M_new.append(np.empty((0, N)))  # a placeholder: levels below lowest are not returned
                continue
            blocks = [M[e - i] for i in range(e, -1, -1)]
            out = np.empty((sum(b.shape[0] for b in blocks), N))
            r = 0
            for i, b in zip(range(e, -1, -1), blocks):
                np.multiply(b, powers[s, i], out=out[r : r + b.shape[0]])
                r += b.shape[0]
            M_new.append(out)
        M = M_new
    if monomials:
        return {e: M[e] for e in range(lowest, depth + 1)}
    return {e: M[e] * _multinomial_column(n, e) for e in range(lowest, depth + 1)}


def _bernstein_values(lam: Array, n: int, depth: int) -> Array:
    """All ``B^depth_J(λ)`` at points ``lam`` (N, n): shape (N, m), :func:`spatch_indices` order."""
    return _bernstein_levels(np.ascontiguousarray(lam.T), n, depth, depth)[depth].T


@functools.lru_cache(maxsize=128)
def _taylor_table(n: int, d: int, j: int) -> tuple[NDArray[np.intp], NDArray[np.intp], Array]:
    """For |K| = j: rows[J, K] of J + K among depth d; each K as the list of its j sides with
    repetition (``(2, 0, 1) -> [0, 0, 2]``), shape (m_j, j); and ``d!/((d-j)! K!)``."""
    upper = {ix: i for i, ix in enumerate(index_tuples(n, d))}
    Js = index_tuples(n, d - j)
    Ks = np.array(index_tuples(n, j), dtype=np.intp).reshape(-1, n) if j else np.zeros((1, n), dtype=np.intp)
    rows = np.array([[upper[tuple(a + b for a, b in zip(J, K))] for K in Ks] for J in Js], dtype=np.intp)
    factors = np.array([np.repeat(np.arange(n), K) for K in Ks], dtype=np.intp).reshape(len(Ks), j)
    fac = np.array([factorial(v) for v in range(j + 1)], dtype=float)
    coef = factorial(d) / factorial(d - j) / np.prod(fac[Ks], axis=1)
    return rows, factors, coef


@dataclass(frozen=True, eq=False)
class SPatch(ControlPointValue):
    """An ``n``-sided S-patch of depth ``d`` (Loop & DeRose 1989; course §8-2).

    Parameters
    ----------
    sides : int
        Number of sides ``n >= 3``.
    depth : int
        Depth (degree of the Bézier simplex) ``d >= 1``.
    control_points : mapping or array_like, shape (m, dim)
        Either a mapping from every index tuple ``I`` (``n`` non-negative ints summing to ``d``) to
        a point of shape ``(dim,)``, with exactly that key set, or an ``(m, dim)`` array in the order
        of ``spatch_indices(sides, depth)``.
    weights : array_like, shape (m,), or mapping, optional
        Positive weights of a rational S-patch (same order / keys), or ``None``.

    Attributes
    ----------
    indices : ndarray of intp, shape (m, sides)
        ``spatch_indices(sides, depth)`` (read-only).

    Raises
    ------
    InvalidGeometryError
        Naming the argument at fault: sides < 3, depth < 1, a key set that is not the index set,
        wrong shapes, non-finite values, weights <= 0.

    Examples
    --------
    A triangle of depth 1 is the flat triangle of its three corner points:

    >>> s = SPatch(3, 1, {(1, 0, 0): [0, 0, 0], (0, 1, 0): [1, 0, 0], (0, 0, 1): [0, 1, 0]})
    >>> s.evaluate(domain_vertices(3)[1])
    array([1., 0., 0.])
    """

    _DICT_TYPE = "SPatch"
    _HEADER = (("sides", SCALAR), ("depth", SCALAR))

    sides: int
    depth: int
    control_points: Array
    weights: Array | None = None
    indices: NDArray[np.intp] = field(init=False, repr=False)
    _hpoles: Array = field(init=False, repr=False)

    if TYPE_CHECKING:  # the generated __init__ takes mappings or array_like; __post_init__ stores arrays

        def __init__(
            self,
            sides: int,
            depth: int,
            control_points: Mapping[tuple[int, ...], ArrayLike] | ArrayLike,
            weights: Mapping[tuple[int, ...], float] | ArrayLike | None = None,
        ) -> None: ...

    def __post_init__(self) -> None:
        n = check_sides(self.sides)
        d = check_depth(self.depth)
        idx = spatch_indices(n, d)
        P = self._points_array(self.control_points, idx, "control_points")
        if P.ndim != 2 or P.shape[1] < 1:
            raise InvalidGeometryError(f"control_points: expected shape ({idx.shape[0]}, dim), got {P.shape}")
        if P.shape[0] != idx.shape[0]:
            raise InvalidGeometryError(
                f"control_points: a {n}-sided S-patch of depth {d} has C({n + d - 1}, {d}) = {idx.shape[0]} "
                f"control points, got {P.shape[0]}"
            )
        w = None
        if self.weights is not None:
            w = self._points_array(self.weights, idx, "weights", scalar=True)
            w = V.check_weights(w, (idx.shape[0],))
        self._set(n, d, idx, P, w)

    @staticmethod
    def _points_array(data: Any, idx: NDArray[np.intp], name: str, scalar: bool = False) -> Array:
        if not isinstance(data, Mapping):
            return V.as_finite_array(data, name)
        wanted = {tuple(int(v) for v in row) for row in idx}
        keys: dict[tuple[int, ...], Any] = {}
        for key, value in data.items():
            try:
                k = tuple(int(v) for v in key)
            except (TypeError, ValueError) as err:
                raise InvalidGeometryError(f"{name}: keys must be tuples of integers, got {key!r}") from err
            if any(int(v) != v for v in key):
                raise InvalidGeometryError(f"{name}: keys must be tuples of integers, got {key!r}")
            keys[k] = value
        missing = wanted - keys.keys()
        extra = keys.keys() - wanted
        if missing or extra:
            what = []
            if missing:
                what.append(f"missing {sorted(missing, reverse=True)[:3]}{' ...' if len(missing) > 3 else ''}")
            if extra:
                what.append(f"unexpected {sorted(extra, reverse=True)[:3]}{' ...' if len(extra) > 3 else ''}")
            n, d = idx.shape[1], int(idx[0].sum())
            raise InvalidGeometryError(
                f"{name}: keys must be exactly the {len(wanted)} {n}-tuples of non-negative integers summing "
                f"to {d}; {', '.join(what)}"
            )
        values = [keys[tuple(int(v) for v in row)] for row in idx]
        a = V.as_finite_array(values, name)
        if scalar and a.ndim != 1:
            raise InvalidGeometryError(f"{name}: expected one number per index, got values of shape {a.shape[1:]}")
        return a

    def _set(self, n: int, d: int, idx: NDArray[np.intp], P: Array, w: Array | None) -> None:
        object.__setattr__(self, "sides", n)
        object.__setattr__(self, "depth", d)
        object.__setattr__(self, "indices", V.readonly(idx))
        object.__setattr__(self, "control_points", V.readonly(P))
        object.__setattr__(self, "weights", None if w is None else V.readonly(w))
        H = P if w is None else np.concatenate((P * w[:, None], w[:, None]), axis=1)
        object.__setattr__(self, "_hpoles", V.readonly(H))

    @classmethod
    def _trusted(cls, sides: int, depth: int, control_points: Array, weights: Array | None = None) -> SPatch:
        """Fast constructor for internal results valid by construction (array order, no checks)."""
        obj = object.__new__(cls)
        obj._set(int(sides), int(depth), np.array(index_tuples(sides, depth), dtype=np.intp),
                 np.asarray(control_points, float), None if weights is None else np.asarray(weights, float))
        return obj

    # ------------------------------------------------------------------ properties
    @property
    def dim(self) -> int:
        return self.control_points.shape[1]

    @property
    def is_rational(self) -> bool:
        return self.weights is not None

    @property
    def n_control_points(self) -> int:
        return self.control_points.shape[0]

    @property
    def homogeneous_points(self) -> Array:
        """``(m, dim + 1)`` homogeneous control points ``(ω P, ω)`` (``(m, dim)`` if not rational)."""
        return self._hpoles

    def index_of(self, index: tuple[int, ...]) -> int:
        """Row of ``control_points`` holding the control point with multi-index ``index``."""
        msg = f"index: expected {self.sides} non-negative integers summing to {self.depth}, got {index!r}"
        try:
            values = list(index)
        except TypeError as err:
            raise InvalidGeometryError(msg) from err
        if not all(isinstance(v, numbers.Integral) and not isinstance(v, bool) for v in values):
            raise InvalidGeometryError(msg)  # 1.5 or True must not be truncated to an index
        key = tuple(int(v) for v in values)
        if len(key) != self.sides or sum(key) != self.depth or min(key) < 0:
            raise InvalidGeometryError(msg)
        return int(np.flatnonzero(np.all(self.indices == np.array(key), axis=1))[0])

    def control_point(self, index: tuple[int, ...]) -> Array:
        """The control point ``P_I`` (read-only view), shape ``(dim,)``."""
        return self.control_points[self.index_of(index)]

    def vertices(self) -> Array:
        """Domain vertices (:func:`domain_vertices`), shape ``(sides, 2)``."""
        return domain_vertices(self.sides)

    def __repr__(self) -> str:
        kind = "rational " if self.is_rational else ""
        return (f"SPatch({kind}sides={self.sides}, depth={self.depth}, "
                f"control_points={self.n_control_points}, dim={self.dim})")

    # ------------------------------------------------------------------ evaluation
    def _jets(self, x: Array, r: int) -> Array:
        """Jets of order ``r`` of the (homogeneous, then projected) patch at points x (N, 2): (N, K, dim).

        Taylor expansion of the Bernstein polynomial about ``λ0 = λ(x)`` with ``δ = λ(x + h) - λ0``
        (a jet without constant term, so only ``|K| <= r`` matters):

        .. math::

            S(λ_0 + δ) = \\sum_{|K| \\le \\min(r, d)} \\frac{d!}{(d - |K|)!\\, K!}\\, δ^K
                \\sum_{|J| = d - |K|} B^{d-|K|}_J(λ_0)\\, P_{J + K}.
        """
        n, d = self.sides, self.depth
        H = self._hpoles
        c = H.shape[1]
        K_len = (r + 1) * (r + 2) // 2
        out = np.empty((x.shape[0], K_len, self.dim))
        top = min(r, d)
        tables = [_taylor_table(n, d, j) for j in range(1, top + 1)]
        # P_{J+K} scaled by the multinomial of J, so that the monomials λ^J stand for B^{d-j}_J
        HK = [H[rows] * _multinomial_column(n, d - j)[:, :, None] for j, (rows, _, _) in enumerate(tables, 1)]
        H0 = H * _multinomial_column(n, d)
        # work per point: every Bernstein level, the Q_j and the δ^K jets
        per_point = 2 * sum(len(index_tuples(n, l)) for l in range(d + 1)) + sum(
            h.shape[1] * (c + 2 * K_len) for h in HK) + n * K_len * (n + 2)
        block = max(256, min(_BLOCK_POINTS, _BLOCK_ELEMENTS // per_point))
        for s in range(0, x.shape[0], block):
            xb = x[s : s + block]
            lam = _wachspress_jets(xb, n, r)  # (B, n, K)
            Bs = _bernstein_levels(np.ascontiguousarray(lam[..., 0].T), n, d, d - top, monomials=True)
            acc = np.zeros((xb.shape[0], K_len, c))
            acc[:, 0, :] = Bs[d].T @ H0
            if top:
                delta = lam.copy()
                delta[..., 0] = 0.0
            for j, ((_, factors, coef), Hj) in enumerate(zip(tables, HK), start=1):
                Q = np.tensordot(Bs[d - j], Hj, axes=(0, 0))  # (B, m_j, c)
                dK = delta[:, factors[:, 0], :]  # (B, m_j, K): jets of δ^K, all K at once
                for f in range(1, j):
                    dK = _jet_mul(dK, delta[:, factors[:, f], :], r)
                acc += np.einsum("bqs,bqc->bsc", dK * coef[:, None], Q, optimize=True)
            if self.is_rational:
                A = _jet_div(np.moveaxis(acc[..., :-1], 1, -1), acc[:, None, :, -1], r)  # (B, dim, K)
                acc = np.moveaxis(A, -1, 1)
            out[s : s + block] = acc
        return out

    def evaluate(self, points: ArrayLike) -> Array:
        """Points of the patch (simplex Bernstein form composed with Wachspress coordinates).

        Parameters
        ----------
        points : array_like, shape (..., 2)
            Points of the regular ``n``-gon domain.

        Returns
        -------
        ndarray, shape (..., dim)

        Raises
        ------
        ParameterError
            For non-finite points or points outside the domain polygon.
        """
        x, shape = _domain_points(points, self.sides)
        return self._jets(x, 0)[:, 0, :].reshape(shape + (self.dim,))

    __call__ = evaluate

    def derivatives(self, points: ArrayLike, order: int = 1) -> Array:
        """The point and all partial derivatives up to ``order`` with respect to domain ``x, y``.

        Parameters
        ----------
        points : array_like, shape (..., 2)
        order : int
            Highest total order ``r >= 0``.

        Returns
        -------
        ndarray, shape (..., order + 1, order + 1, dim)
            ``[..., i, j, :] = d^{i+j} S / dx^i dy^j``; entries with ``i + j > order`` are zero.

        Notes
        -----
        Exact (Taylor-mode differentiation of the Wachspress quotient, the Bernstein products and,
        for rational patches, the weight quotient); the cost grows steeply with ``order`` (about
        ``order**6``), so ``order`` above ``tolerances.SPATCH_MAX_DERIVATIVE_ORDER`` and work arrays
        above ``tolerances.MAX_ARRAY_BYTES`` are refused before any work (InvalidGeometryError).
        """
        r = V.check_order(order)
        if r > tolerances.SPATCH_MAX_DERIVATIVE_ORDER:
            raise InvalidGeometryError(
                f"order: {r} exceeds SPATCH_MAX_DERIVATIVE_ORDER = {tolerances.SPATCH_MAX_DERIVATIVE_ORDER} (the "
                "cost grows like order**6: 2.3 s per point at order 25); raise it with tolerances.override")
        x, shape = _domain_points(points, self.sides)
        V.check_size((x.shape[0], (r + 1) * (r + 2) // 2, max(self._hpoles.shape[1], 1) * 4),
                     f"SPatch.derivatives of order {r} at {x.shape[0]} points")
        D = _jet_to_derivatives(self._jets(x, r), r)
        return D.reshape(shape + (r + 1, r + 1, self.dim))

    def normal(self, points: ArrayLike) -> Array:
        """Unit normal ``(S_x × S_y) / |S_x × S_y|`` (3-D patches only).

        Returns
        -------
        ndarray, shape (..., 3)

        Raises
        ------
        InvalidGeometryError
            If the patch is not 3-D, or the normal is undefined (``S_x × S_y = 0``) at some point.
        """
        if self.dim != 3:
            raise InvalidGeometryError(f"normal: needs a 3-D patch, this one has dim {self.dim}")
        D = self.derivatives(points, 1)
        nrm = np.cross(D[..., 1, 0, :], D[..., 0, 1, :])
        length = np.linalg.norm(nrm, axis=-1, keepdims=True)
        if np.any(length == 0):
            raise InvalidGeometryError("normal: the patch is degenerate (S_x × S_y = 0) at some point")
        return nrm / length

    # ------------------------------------------------------------------ boundary
    def _side(self, k: object) -> int:
        if isinstance(k, bool) or not isinstance(k, numbers.Integral) or not 0 <= int(k) < self.sides:
            raise InvalidGeometryError(f"k: expected a side number from 0 to {self.sides - 1}, got {k!r}")
        return int(k)

    def boundary_indices(self, k: int, row: int = 0) -> NDArray[np.intp]:
        """Rows of ``control_points`` of row ``row`` next to side ``k``, ordered from vertex k to k+1.

        Row ``r`` holds the indices with ``i_k + i_{k+1} = d - r``; for ``r = 0`` these are the
        Bézier control points of :meth:`boundary_curve`. For ``r >= 1`` several indices share the same
        ``i_{k+1}``; they are ordered by ``i_{k+1}`` ascending, then by the index order.
        """
        k = self._side(k)
        if isinstance(row, bool) or not isinstance(row, numbers.Integral) or not 0 <= int(row) <= self.depth:
            raise InvalidGeometryError(f"row: expected an integer from 0 to {self.depth}, got {row!r}")
        k1 = (k + 1) % self.sides
        s = self.indices[:, k] + self.indices[:, k1]
        rows = np.flatnonzero(s == self.depth - int(row))
        return rows[np.argsort(self.indices[rows, k1], kind="stable")]

    def boundary_curve(self, k: int) -> BSplineCurve:
        """Side ``k`` of the patch: a Bézier curve of degree ``d`` on ``[0, 1]``.

        It runs from the image of domain vertex ``k`` (``t = 0``) to that of vertex ``k + 1 (mod n)``
        (``t = 1``); the domain point of parameter ``t`` is ``(1 - t) v_k + t v_{k+1}``. Control
        points: the ``P_I`` with ``i_k + i_{k+1} = d``, in order of ``i_{k+1}`` (rational patch:
        their weights).
        """
        rows = self.boundary_indices(k)
        d = self.depth
        knots = np.r_[np.zeros(d + 1), np.ones(d + 1)]
        w = None if self.weights is None else self.weights[rows].copy()
        return BSplineCurve._trusted(d, knots, self.control_points[rows].copy(), w)

    def edge_points(self, k: int, t: ArrayLike) -> Array:
        """Domain points ``(1 - t) v_k + t v_{k+1}`` of side ``k``, shape ``(..., 2)``."""
        k = self._side(k)
        t = V.check_parameters(t, 0.0, 1.0, name="t")
        v = domain_vertices(self.sides)
        a, b = v[k], v[(k + 1) % self.sides]
        return (1.0 - t)[..., None] * a + t[..., None] * b

    def inward_normal(self, k: int) -> Array:
        """Inward unit normal of side ``k`` of the domain polygon, shape ``(2,)``."""
        k = self._side(k)
        return -edge_normals(self.sides)[k]

    def cross_boundary_derivative(self, k: int, t: ArrayLike) -> Array:
        """Derivative of the patch along the inward unit normal of domain side ``k``.

        Parameters
        ----------
        k : int
            Side number.
        t : float or array_like, shape (...)
            Edge parameters in ``[0, 1]`` (as in :meth:`boundary_curve`).

        Returns
        -------
        ndarray, shape (..., dim)
            ``∇S · ν_k`` at ``(1 - t) v_k + t v_{k+1}``, ``ν_k`` the inward unit normal. It depends
            only on the control points with ``i_k + i_{k+1} >= d - 1``.
        """
        x = self.edge_points(k, t)
        D = self.derivatives(x, 1)
        nu = self.inward_normal(k)
        return nu[0] * D[..., 1, 0, :] + nu[1] * D[..., 0, 1, :]

    # ------------------------------------------------------------------ operations
    def elevate_depth(self, times: int = 1) -> SPatch:
        """The same surface as an S-patch of depth ``d + times`` (Loop & DeRose 1989, §4).

        ``P'_J = Σ_k (j_k / (d + 1)) P_{J - e_k}`` per step, in homogeneous coordinates.

        Raises
        ------
        InvalidGeometryError
            ``times`` whose control net (``C(n + d + times - 1, n - 1)`` points, each with its index
            tuple in the lookup of the step) would exceed ``tolerances.MAX_ARRAY_BYTES``, before any work.
        """
        t = V.check_times(times)
        n, d, H = self.sides, self.depth, self._hpoles
        # per point of the last step: its index tuple as Python objects (~24 bytes an entry, as in
        # spatch_indices) in the new and old index sets, and the old and new homogeneous nets
        V.check_size((comb(n + d + t - 1, n - 1), 2 * 3 * n + 2 * H.shape[1]),
                     f"elevate_depth(times={t}) from depth {d} to {d + t}")
        for _ in range(t):
            old = {tuple(row): i for i, row in enumerate(np.array(index_tuples(n, d)))}
            new_idx = np.array(index_tuples(n, d + 1), dtype=np.intp)
            Hn = np.zeros((new_idx.shape[0], H.shape[1]))
            for k in range(n):
                sel = new_idx[:, k] > 0
                src = new_idx[sel].copy()
                src[:, k] -= 1
                rows = np.array([old[tuple(s)] for s in src], dtype=np.intp)
                Hn[sel] += (new_idx[sel, k] / (d + 1))[:, None] * H[rows]
            H, d = Hn, d + 1
        if self.is_rational:
            return SPatch._trusted(n, d, H[:, :-1] / H[:, -1:], H[:, -1].copy())
        return SPatch._trusted(n, d, H)

    # transform, to_dict, from_dict and == : ControlPointValue (kernel/_common.py), from the
    # header ``sides``, ``depth``; control points in :func:`spatch_indices` order.
