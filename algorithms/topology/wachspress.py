"""Wachspress coordinates of the regular n-gon and their exact derivatives (course §8-1, §8-2).

The S-patch of :mod:`.spatch` is a Bernstein polynomial in the Wachspress coordinates ``λ_k`` of its
domain, the regular n-gon of :func:`.spatch.domain_vertices`: ``λ_k = w_k / Σ w_j`` with ``w_k``
the product of the edge functions of the sides not adjacent to vertex ``k`` (Wachspress 1975;
Floater, Hormann and Kós 2006). Their derivatives are exact: every quantity is propagated as a
truncated bivariate Taylor series ("jet") with exact jet products and quotients (Griewank and
Walther, "Evaluating Derivatives", 2nd ed., ch. 13); :mod:`.spatch` carries the same jets on
through the Bernstein polynomials.
"""

from __future__ import annotations

import functools
from math import factorial

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import _validate as V
from .. import tolerances
from ..errors import InvalidGeometryError, ParameterError
from ._common import check_sides, edge_normals

__all__ = ["wachspress", "wachspress_derivatives", "wachspress_gradient"]

Array = NDArray[np.float64]


# ---------------------------------------------------------------------------- jets
# A jet of order r of a function f at a point is the array of its scaled Taylor coefficients
# f_{ij} = (d^{i+j} f / dx^i dy^j) / (i! j!) for i + j <= r, stored flat along the last axis in the
# order of _jet_layout(r). Products are truncated Cauchy products, exact to round-off.
@functools.lru_cache(maxsize=16)
def _jet_layout(r: int) -> tuple[tuple[tuple[int, int], ...], dict[tuple[int, int], int]]:
    pairs = tuple((i, t - i) for t in range(r + 1) for i in range(t, -1, -1))
    return pairs, {p: k for k, p in enumerate(pairs)}


@functools.lru_cache(maxsize=16)
def _jet_products(r: int) -> tuple[tuple[tuple[int, int], ...], ...]:
    """For each flat output slot c, the (a, b) slot pairs with a + b = c (as bivariate exponents)."""
    pairs, where = _jet_layout(r)
    out = []
    for i, j in pairs:
        out.append(tuple((where[(a, b)], where[(i - a, j - b)]) for a in range(i + 1) for b in range(j + 1)))
    return tuple(out)


def _jet_mul(f: Array, g: Array, r: int) -> Array:
    """Truncated product of two jets (last axis), broadcasting the leading axes."""
    if r == 0:
        return f * g
    prods = _jet_products(r)
    shape = np.broadcast_shapes(f.shape, g.shape)
    out = np.empty(shape)
    for c, terms in enumerate(prods):
        a, b = terms[0]
        acc = f[..., a] * g[..., b]
        for a, b in terms[1:]:
            acc = acc + f[..., a] * g[..., b]
        out[..., c] = acc
    return out


def _jet_div(f: Array, h: Array, r: int) -> Array:
    """Jet of ``f / h`` (``h`` non-zero at the point): solve ``g h = f`` slot by slot."""
    if r == 0:
        return f / h
    shape = np.broadcast_shapes(f.shape, h.shape)
    g = np.empty(shape)
    h0 = h[..., 0]
    for c, terms in enumerate(_jet_products(r)):
        acc = np.broadcast_to(f[..., c], shape[:-1]).copy()
        for a, b in terms:  # a indexes h, b indexes g
            if a != 0:
                acc -= h[..., a] * g[..., b]
        g[..., c] = acc / h0
    return g


def _jet_to_derivatives(jet: Array, r: int) -> Array:
    """Flat jets (..., K, dim) -> derivative table (..., r+1, r+1, dim) with d^{i+j}/dx^i dy^j."""
    pairs, _ = _jet_layout(r)
    out = np.zeros(jet.shape[:-2] + (r + 1, r + 1) + jet.shape[-1:])
    for c, (i, j) in enumerate(pairs):
        out[..., i, j, :] = jet[..., c, :] * (factorial(i) * factorial(j))
    return out


# ---------------------------------------------------------------------------- Wachspress
def _domain_points(points: ArrayLike, n: int, name: str = "points") -> tuple[Array, tuple[int, ...]]:
    try:
        x = np.asarray(points, dtype=float)
    except (TypeError, ValueError) as err:
        raise ParameterError(
            f"{name}: expected real domain points of shape (..., 2), got {type(points).__name__}"
        ) from err
    if x.ndim == 0 or x.shape[-1] != 2:
        raise ParameterError(f"{name}: expected domain points of shape (..., 2), got shape {x.shape}")
    if not np.all(np.isfinite(x)):
        raise ParameterError(f"{name}: domain points must be finite, got {x[~np.isfinite(x)].ravel()[0]!r}")
    flat = x.reshape(-1, 2)
    if flat.shape[0]:
        excess = flat @ edge_normals(n).T - np.cos(np.pi / n)
        worst = np.unravel_index(int(np.argmax(excess)), excess.shape)
        if excess[worst] > tolerances.SPATCH_DOMAIN_SLACK:
            raise ParameterError(
                f"{name}: point {flat[worst[0]].tolist()} lies outside the regular {n}-gon domain "
                f"(beyond side {int(worst[1])} by {float(excess[worst]):.3g})"
            )
    return flat, x.shape[:-1]


def _wachspress_jets(x: Array, n: int, r: int) -> Array:
    """Jets of the Wachspress coordinates at points x (N, 2): shape (N, n, K)."""
    K = (r + 1) * (r + 2) // 2
    N = x.shape[0]
    nrm = edge_normals(n)
    h = np.cos(np.pi / n)
    L = np.zeros((N, n, K))
    L[..., 0] = h - x @ nrm.T
    if r >= 1:
        L[..., 1] = -nrm[:, 0]  # slot (1, 0)
        L[..., 2] = -nrm[:, 1]  # slot (0, 1)
    # w_k = L_{k+1} L_{k+2} ... L_{k+n-2} (indices mod n): all k at once, n - 3 jet products
    w = np.roll(L, -1, axis=1)
    for s in range(2, n - 1):
        w = _jet_mul(w, np.roll(L, -s, axis=1), r)
    W = w.sum(axis=1, keepdims=True)
    return _jet_div(w, W, r)


def wachspress(points: ArrayLike, sides: int) -> Array:
    """Wachspress coordinates on the regular ``n``-gon (course §8-1; Wachspress 1975).

    Parameters
    ----------
    points : array_like, shape (..., 2)
        Points of the domain polygon (:func:`domain_vertices`).
    sides : int

    Returns
    -------
    ndarray, shape (..., sides)
        Non-negative, summing to 1; ``λ_k = 1`` at vertex ``k``; linear along the sides.

    Raises
    ------
    ParameterError
        For non-finite points or points outside the polygon (beyond
        ``tolerances.SPATCH_DOMAIN_SLACK``).
    """
    n = check_sides(sides)
    x, shape = _domain_points(points, n)
    return _wachspress_jets(x, n, 0)[..., 0].reshape(shape + (n,))


def wachspress_derivatives(points: ArrayLike, sides: int, order: int = 2) -> Array:
    """Wachspress coordinates and their partial derivatives up to ``order`` (exact, Taylor mode).

    Returns
    -------
    ndarray, shape (..., sides, order + 1, order + 1)
        ``[..., k, i, j] = d^{i+j} λ_k / dx^i dy^j``; entries with ``i + j > order`` are zero.

    Raises
    ------
    InvalidGeometryError
        ``order`` above ``tolerances.SPATCH_MAX_DERIVATIVE_ORDER``, or work arrays above
        ``tolerances.MAX_ARRAY_BYTES``, before any work.
    """
    n = check_sides(sides)
    r = V.check_order(order)
    if r > tolerances.SPATCH_MAX_DERIVATIVE_ORDER:  # the jet products are ~order**4 / 24 Python-level terms
        raise InvalidGeometryError(
            f"order: {r} exceeds SPATCH_MAX_DERIVATIVE_ORDER = {tolerances.SPATCH_MAX_DERIVATIVE_ORDER} (the jet "
            "products grow like order**4); raise it with tolerances.override")
    x, shape = _domain_points(points, n)
    # the jets L, w, W and the quotient (4 x K per side) and the derivative table ((r+1)^2 per side)
    V.check_size((x.shape[0], n, 4 * (r + 1) * (r + 2) // 2 + (r + 1) ** 2),
                 f"wachspress_derivatives of order {r} at {x.shape[0]} points")
    jets = _wachspress_jets(x, n, r)
    return _jet_to_derivatives(jets[..., None], r)[..., 0].reshape(shape + (n, r + 1, r + 1))


def wachspress_gradient(points: ArrayLike, sides: int) -> Array:
    """Gradients of the Wachspress coordinates (exact).

    Returns
    -------
    ndarray, shape (..., sides, 2)
        ``[..., k, :] = (dλ_k/dx, dλ_k/dy)``; they sum to zero over ``k``.
    """
    n = check_sides(sides)
    x, shape = _domain_points(points, n)
    jets = _wachspress_jets(x, n, 1)
    return jets[..., 1:3].reshape(shape + (n, 2))
