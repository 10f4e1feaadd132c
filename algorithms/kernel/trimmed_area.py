"""The area of a trimmed surface by Green's theorem (course §2, §6-0; :meth:`.trimmed.TrimmedSurface.area`):
per boundary p-curve ``integral F(c(s)) v'(s) ds`` with ``F(u, v) = integral_{anchor}^{u}
|S_u x S_v|(t, v) dt``, both integrals by composite Gauss-Legendre on the pieces between the
p-curve's knots, its crossings of the surface's knot lines (:func:`breakpoints`) and the surface's
u breakpoints, where the integrands are smooth.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from .. import _validate as V
from .curve import BSplineCurve
from .surface import BSplineSurface

__all__ = ["GAUSS", "breakpoints", "composite_nodes", "green_area"]

Array = NDArray[np.float64]

#: The 8-point Gauss-Legendre rule on [-1, 1]: (nodes, weights), read-only.
GAUSS = tuple(V.readonly(a) for a in np.polynomial.legendre.leggauss(8))


def green_area(surface: BSplineSurface, c: BSplineCurve, pieces: int, anchor: float) -> float:
    """``integral F(c(s)) v'(s) ds`` over one p-curve, ``F(u, v) = integral_{anchor}^{u}
    |S_u x S_v|(t, v) dt`` (see :meth:`~.trimmed.TrimmedSurface.area`)."""
    x, w = GAUSS
    ks = breakpoints(surface, c)
    s, ws = composite_nodes(ks, pieces, x, w)
    D = c.derivatives(s, 1)  # (n, 2, 2)
    (u0, u1), (v0, v1) = surface.domain
    us = np.clip(D[:, 0, 0], u0, u1)
    vs = np.clip(D[:, 0, 1], v0, v1)
    dv = D[:, 1, 1]
    keep = dv != 0
    if not keep.any():
        return 0.0
    us, vs, dv, ws = us[keep], vs[keep], dv[keep], ws[keep]
    p, U, nu = surface.degree[0], surface.knots[0], surface.n_poles[0]
    kb = np.unique(U[p:nu + 1])  # the surface's u breakpoints
    a = np.repeat(kb[:-1], pieces) + np.tile(np.arange(pieces), kb.size - 1) * np.repeat(np.diff(kb), pieces) / pieces
    b = np.r_[a[1:], kb[-1]]
    # Each node's inner integral runs over [lo, hi] = [min(u, anchor), max(u, anchor)]: only the
    # pieces that overlap it (a contiguous run, b_l > lo and a_l < hi) are evaluated; the others
    # added exact zeros before (the same points and weights, so the same value to round-off).
    lo, hi = np.minimum(us, anchor), np.maximum(us, anchor)
    first = np.searchsorted(b, lo, side="right")
    count = np.maximum(np.searchsorted(a, hi, side="left") - first, 0)
    node = np.repeat(np.arange(us.size), count)
    piece = np.arange(node.size) - np.repeat(np.cumsum(count) - count, count) + np.repeat(first, count)
    start = np.maximum(a[piece], lo[node])
    length = np.maximum(np.minimum(b[piece], hi[node]) - start, 0.0)
    G = np.empty(node.size)
    block = max(1, (1 << 20) // x.size)
    for k in range(0, node.size, block):
        sl = slice(k, k + block)
        t = start[sl, None] + length[sl, None] * (x + 1.0) / 2.0  # (pairs, g)
        vv = np.broadcast_to(vs[node[sl], None], t.shape)
        Ds = surface.derivatives(t.ravel(), vv.ravel(), 1)
        J = np.linalg.norm(np.cross(Ds[:, 1, 0], Ds[:, 0, 1]), axis=-1).reshape(t.shape)
        G[sl] = (J @ w) * (length[sl] / 2.0)
    F = np.sign(us - anchor) * np.bincount(node, weights=G, minlength=us.size)
    return float(np.sum(ws * F * dv))


def breakpoints(surface: BSplineSurface, c: BSplineCurve, stop_early: bool = True) -> Array:
    """The p-curve's distinct knots and the parameters where it crosses an interior knot line of
    the surface: between them ``F(c(s))`` is smooth and Gauss-Legendre converges exponentially
    (across a knot line the surface is only C^(p-1)). Crossings by bisection from 32 samples per
    span (60 halvings: to round-off).

    With ``stop_early`` the bisection stops once every bracket is two neighbouring doubles (or
    one): then each midpoint is one of its ends, an end keeps its side of the knot line when
    evaluated again (a point evaluates to the same bits in any call), so the halvings left would
    change nothing; the same crossings as all 60, bit for bit (tested)."""
    ks = np.unique(c.knots[c.degree:c.n_poles + 1])
    s = (ks[:-1, None] + np.diff(ks)[:, None] * (np.arange(32) / 32.0)).ravel()
    s = np.r_[s, ks[-1]]
    X = c.evaluate(s)
    found = [ks]
    for ax in (0, 1):
        p, K, n = surface.degree[ax], surface.knots[ax], surface.n_poles[ax]
        inner = np.unique(K[p + 1:n])
        inner = inner[(inner > K[p]) & (inner < K[n])]
        if inner.size == 0:
            continue
        f = np.sign(X[:, ax, None] - inner[None, :])
        i, j = np.nonzero(f[:-1] * f[1:] < 0)
        lo, hi, flo = s[i], s[i + 1], f[i, j]
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            if stop_early and np.all((mid == lo) | (mid == hi)):
                break
            same = np.sign(c.evaluate(mid)[:, ax] - inner[j]) == flo
            lo, hi = np.where(same, mid, lo), np.where(same, hi, mid)
        found.append(0.5 * (lo + hi))
    b = np.unique(np.concatenate(found))
    keep = np.r_[True, np.diff(b) > 1e-12 * max(b[-1] - b[0], np.finfo(float).tiny)]
    b = b[keep]
    b[-1] = ks[-1]
    return b


def composite_nodes(breaks: Array, pieces: int, x: Array, w: Array) -> tuple[Array, Array]:
    """Gauss-Legendre nodes and weights on every interval of ``breaks`` cut in ``pieces``."""
    a, b = breaks[:-1], breaks[1:]
    t = (np.arange(pieces + 1) / pieces)
    edges = a[:, None] + (b - a)[:, None] * t[None, :]  # (K, pieces + 1)
    lo, hi = edges[:, :-1].ravel(), edges[:, 1:].ravel()
    half = (hi - lo) / 2.0
    nodes = (lo + hi)[:, None] / 2.0 + half[:, None] * x[None, :]
    weights = half[:, None] * w[None, :]
    return nodes.ravel(), weights.ravel()
