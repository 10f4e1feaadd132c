"""Optional numba kernels for the hot evaluation loops (scattered points, grid partials).

The NumPy paths in :mod:`.basis`, :mod:`.curve` and :mod:`.surface` are the reference; the kernels
here compute the same quantities point by point (span by table look-up, basis functions by A2.2 and
their derivatives by differentiating lower-degree rows as de Boor's BSPLVD does, tensor contraction,
quotient rule A4.2/A4.4 fused), which avoids the ``(m, p+1, q+1, d)`` gathers and temporaries of
the vectorised form. ``tests/algorithms/test_fast_paths.py`` checks that both agree to 1e-14
(relative to each partial's magnitude). Benchmarks: ``benchmarks/bench_evaluation.py``.

Numba is optional and imported lazily, on the first evaluation of at least
:data:`~occsurf.algorithms.tolerances.NUMBA_MIN_POINTS` points (read at call time, overridable),
so ``import occsurf.algorithms`` never pays for it and small evaluations never compile anything. The
kernels are compiled with ``cache=True`` (once per machine, in ``__pycache__``); where no cache
directory is writable they are compiled once per process instead. Set the environment variable
``OCCSURF_NO_NUMBA=1`` to force the NumPy paths.

Every kernel trusts its input: parameters inside the domain, contiguous float64 arrays, and the
span tables of :func:`span_table`. The kernels are serial (deterministic results; the benchmarks
compare single-threaded peers).

The module is longer than the house's ~600 lines on purpose: numba's on-disk cache is keyed by the
source file of each kernel, and each kernel's cached code holds the helpers it calls (numba links
them into its module), so a kernel in another file would keep its cached copy of a helper after the
helper changed here. One file, one cache. Besides evaluation it holds :func:`surface_project`, the point projection of
:func:`occsurf.algorithms.fitting._common.project_points` per point. The first use of the kernels
on a machine compiles them (all seven: 21-28 s on the 2-core test machine; cached after).

References
----------
L. Piegl, W. Tiller, *The NURBS Book*, 2nd ed., A2.2, A4.2, A4.4. C. de Boor, *A Practical Guide
to Splines*, 1978, BSPLVD (derivatives of all basis functions by differentiating lower degrees).
"""

from __future__ import annotations

import contextlib
import contextvars
import os
import threading
from collections.abc import Iterator
from typing import Any

import numpy as np
from numpy.typing import NDArray

from . import tolerances

__all__ = ["ENV_DISABLE", "span_bounds", "span_table", "surface_args", "enabled", "applies", "batch", "run", "load",
           "loaded", "kernel", "jit", "readonly"]

#: Environment variable that, set to anything but ``""``/``"0"``, forces the NumPy paths.
ENV_DISABLE = "OCCSURF_NO_NUMBA"

_lock = threading.Lock()
_state: dict[str, Any] = {"loaded": False, "kernels": None}
#: True inside :func:`batch` blocks whose work reached NUMBA_MIN_POINTS (per thread and task).
_in_batch: contextvars.ContextVar[bool] = contextvars.ContextVar("occsurf_numba_batch", default=False)


def span_bounds(knots: np.ndarray, degree: int, n_poles: int) -> tuple[int, int]:
    """First and last non-empty knot spans of the domain (as clipped by ``basis.find_span``)."""
    first = int(np.searchsorted(knots, knots[degree], side="right")) - 1
    last = int(np.searchsorted(knots, knots[n_poles], side="left")) - 1
    return first, last


# ---------------------------------------------------------------------------------------------
# Kernel sources. Plain Python functions; :func:`load` compiles them with numba. They call each
# other through module globals, which :func:`load` rebinds to the compiled dispatchers. The
# annotations are for the type checker only (numba infers types from the arguments).

_F = NDArray[np.float64]
_I = NDArray[np.int64]


def span_table(knots: np.ndarray, degree: int, n_poles: int) -> tuple[int, int, np.ndarray, float, float]:
    """Span lookup table for :func:`_span`: ``(first, last, table, x0, scale)``.

    ``table[b]`` is the span (:func:`.basis.find_span`) of ``x0 + b / scale``, for ``nb + 1``
    equally spaced points over the domain, ``nb`` about sixteen per span. A parameter's span
    lies between those of the two table points around it, so the search is one table read and,
    in the few cells that straddle a knot, a short bisection (branch predictors defeat a plain
    bisection on random parameters: 30 ns against 6 ns per search).
    """
    from .kernel.basis import find_span

    first, last = span_bounds(knots, degree, n_poles)
    x0, x1 = float(knots[degree]), float(knots[n_poles])
    nb = int(min(max(64, 16 * (last - first + 1)), 1 << 16))
    scale = nb / (x1 - x0)
    edges = np.clip(x0 + np.arange(nb + 1) / scale, x0, x1)
    table = find_span(knots, degree, n_poles, edges).astype(np.int64)
    return first, last, table, x0, scale


def _span(  # pragma: no cover - compiled
    knots: _F, first: int, last: int, table: _I, x0: float, scale: float, x: float,
) -> int:
    """Largest ``s`` in ``[first, last]`` with ``knots[s] <= x`` (A2.1 via :func:`span_table`)."""
    nb = table.shape[0] - 1
    f = (x - x0) * scale
    b = 0
    if f > 0.0:
        b = min(int(f), nb - 1)
    lo = table[b]
    hi = table[b + 1]
    # Guards against round-off in the cell index; they almost never iterate.
    while lo > first and knots[lo] > x:
        lo -= 1
    while hi < last and knots[hi + 1] <= x:
        hi += 1
    while lo < hi:
        mid = (lo + hi + 1) >> 1
        if knots[mid] <= x:
            lo = mid
        else:
            hi = mid - 1
    return lo


def _basis(knots: _F, p: int, s: int, x: float, N: _F, left: _F, right: _F) -> None:  # pragma: no cover - compiled
    """The ``p + 1`` non-zero basis functions at ``x`` in span ``s`` (A2.2) into ``N``."""
    N[0] = 1.0
    for j in range(1, p + 1):
        left[j] = x - knots[s + 1 - j]
        right[j] = knots[s + j] - x
        saved = 0.0
        for r in range(j):
            temp = N[r] / (right[r + 1] + left[j - r])
            N[r] = saved + right[r + 1] * temp
            saved = left[j - r] * temp
        N[j] = saved


def _basis_ders(  # pragma: no cover - compiled
    knots: _F, p: int, s: int, x: float, order: int, ders: _F, Nt: _F, inv: _F, left: _F, right: _F,
) -> None:
    """Basis functions and derivatives up to ``order`` into ``ders`` (order+1, p+1).

    The triangle of A2.2 keeps every degree (``Nt[j, :j+1]``, degree ``j``); the k-th derivative
    is the degree ``p - k`` row raised k times by differentiation (de Boor's BSPLVD),

    .. math::  N'_{i,d} = d \\Big(\\frac{N_{i,d-1}}{t_{i+d} - t_i} - \\frac{N_{i+1,d-1}}{t_{i+d+1} - t_{i+1}}\\Big),

    which needs ``p`` reciprocals per derivative degree instead of A2.3's divisions per term.
    Row 0 is bit-for-bit :func:`_basis`. ``Nt``, ``inv`` (p+1, p+1) and ``left``, ``right``
    (p+1,) are scratch.
    """
    Nt[0, 0] = 1.0
    for j in range(1, p + 1):
        left[j] = x - knots[s + 1 - j]
        right[j] = knots[s + j] - x
        saved = 0.0
        for r in range(j):
            temp = Nt[j - 1, r] / (right[r + 1] + left[j - r])
            Nt[j, r] = saved + right[r + 1] * temp
            saved = left[j - r] * temp
        Nt[j, j] = saved
    n = min(order, p)
    for d in range(p - n + 1, p + 1):  # inv[d, r] = 1 / (t[s+r+1] - t[s+r+1-d])
        for r in range(d):
            inv[d, r] = 1.0 / (knots[s + r + 1] - knots[s + r + 1 - d])
    for r in range(p + 1):
        ders[0, r] = Nt[p, r]
    for k in range(1, order + 1):
        if k > p:
            for r in range(p + 1):
                ders[k, r] = 0.0
            continue
        # Start from degree p - k (right-aligned in ders[k]) and raise k times.
        d0 = p - k
        for r in range(d0 + 1):
            ders[k, r] = Nt[d0, r]
        for d in range(d0 + 1, p + 1):
            fd = float(d)
            prev = 0.0  # f_{r-1} * inv[d, r-1]
            for r in range(d):
                cur = ders[k, r] * inv[d, r]
                ders[k, r] = fd * (prev - cur)
                prev = cur
            ders[k, d] = fd * prev


def _binomials(n: int) -> _F:  # pragma: no cover - compiled
    """Pascal's triangle ``B[k, i] = C(k, i)`` for ``0 <= i <= k < n`` as floats."""
    B = np.zeros((n, n))
    for k in range(n):
        B[k, 0] = 1.0
        for i in range(1, k + 1):
            B[k, i] = B[k - 1, i - 1] + B[k - 1, i]
    return B


def _curve_quotient(h: _F, binom: _F, out: _F, m: int) -> None:  # pragma: no cover - compiled
    """A4.2 on one point: homogeneous ``h`` (r+1, d+1) to Cartesian ``out[m]`` (r+1, d)."""
    r1 = h.shape[0]
    dw = h.shape[1] - 1
    inv_w = 1.0 / h[0, dw]
    for k in range(r1):
        for c in range(dw):
            out[m, k, c] = h[k, c]
        for i in range(1, k + 1):
            coef = binom[k, i] * h[i, dw]
            for c in range(dw):
                out[m, k, c] -= coef * out[m, k - i, c]
        for c in range(dw):
            out[m, k, c] *= inv_w


def _quotient_plan(r1: int) -> tuple[_I, _I, _I, _F]:  # pragma: no cover - compiled
    """The terms of A4.4 for partials up to ``r1 - 1``, flattened for :func:`_surface_quotient`.

    Partial ``e = k * r1 + l`` takes terms ``start[e] .. start[e+1]``; term ``t`` subtracts
    ``coef[t] * w[wi[t]] * S[src[t]]`` with ``coef = C(k, i) C(l, j)``, ``wi = i * r1 + j`` and
    ``src = (k - i) * r1 + (l - j)``, for ``(i, j) != (0, 0)`` in the order of the NumPy rule.
    """
    binom = _binomials(r1)
    n_terms = (r1 * (r1 + 1) // 2) ** 2 - r1 * r1
    start = np.zeros(r1 * r1 + 1, np.int64)
    src = np.empty(n_terms, np.int64)
    wi = np.empty(n_terms, np.int64)
    coef = np.empty(n_terms)
    t = 0
    for k in range(r1):
        for l in range(r1):
            start[k * r1 + l] = t
            for i in range(k + 1):
                for j in range(l + 1):
                    if i + j == 0:
                        continue
                    src[t] = (k - i) * r1 + (l - j)
                    wi[t] = i * r1 + j
                    coef[t] = binom[k, i] * binom[l, j]
                    t += 1
    start[r1 * r1] = t
    return start, src, wi, coef


def _surface_quotient(  # pragma: no cover - compiled
    h: _F, start: _I, src: _I, wi: _I, coef: _F, o: _F, out: _F, m: int,
) -> None:
    """A4.4 on one point: homogeneous ``h`` (E, d+1) to Cartesian ``out[m]`` (E, d), E = (r+1)^2.

    ``o`` (E, d) is scratch; the terms come from :func:`_quotient_plan`. The same operations in
    the same order as :func:`.rational.surface_quotient_rule`; scalar accumulators for d = 3.
    """
    E = h.shape[0]
    dw = h.shape[1] - 1
    inv_w = 1.0 / h[0, dw]
    for e in range(E):
        if dw == 3:
            v0 = h[e, 0]
            v1 = h[e, 1]
            v2 = h[e, 2]
            for t in range(start[e], start[e + 1]):
                c = coef[t] * h[wi[t], 3]
                sr = src[t]
                v0 -= c * o[sr, 0]
                v1 -= c * o[sr, 1]
                v2 -= c * o[sr, 2]
            o[e, 0] = v0 * inv_w
            o[e, 1] = v1 * inv_w
            o[e, 2] = v2 * inv_w
            out[m, e, 0] = o[e, 0]
            out[m, e, 1] = o[e, 1]
            out[m, e, 2] = o[e, 2]
        else:
            for c in range(dw):
                o[e, c] = h[e, c]
            for t in range(start[e], start[e + 1]):
                cw = coef[t] * h[wi[t], dw]
                sr = src[t]
                for c in range(dw):
                    o[e, c] -= cw * o[sr, c]
            for c in range(dw):
                o[e, c] *= inv_w
                out[m, e, c] = o[e, c]


def curve_points(  # pragma: no cover
    t: _F, p: int, first: int, last: int, table: _I, x0: float, scale: float, H: _F, u: _F, rational: bool, out: _F,
) -> None:
    """Curve points: ``H`` (n, k) homogeneous poles, ``u`` (m,), ``out`` (m, d)."""
    k = H.shape[1]
    N = np.empty(p + 1)
    left = np.empty(p + 1)
    right = np.empty(p + 1)
    acc = np.empty(k)
    for m in range(u.shape[0]):
        x = u[m]
        s = _span(t, first, last, table, x0, scale, x)
        _basis(t, p, s, x, N, left, right)
        for c in range(k):
            acc[c] = 0.0
        for a in range(p + 1):
            w = N[a]
            for c in range(k):
                acc[c] += w * H[s - p + a, c]
        _store_point(acc, rational, out, m)


def curve_derivatives(  # pragma: no cover
    t: _F, p: int, first: int, last: int, table: _I, x0: float, scale: float, H: _F, u: _F, order: int,
    rational: bool, out: _F,
) -> None:
    """Curve derivatives up to ``order``: ``out`` (m, order+1, d)."""
    k = H.shape[1]
    r1 = order + 1
    ders = np.empty((r1, p + 1))
    Nt = np.empty((p + 1, p + 1))
    inv = np.empty((p + 1, p + 1))
    left = np.empty(p + 1)
    right = np.empty(p + 1)
    h = np.empty((r1, k))
    binom = _binomials(r1)
    for m in range(u.shape[0]):
        x = u[m]
        s = _span(t, first, last, table, x0, scale, x)
        _basis_ders(t, p, s, x, order, ders, Nt, inv, left, right)
        for i in range(r1):
            for c in range(k):
                h[i, c] = 0.0
            for a in range(p + 1):
                w = ders[i, a]
                for c in range(k):
                    h[i, c] += w * H[s - p + a, c]
        if rational:
            _curve_quotient(h, binom, out, m)
        else:
            for i in range(r1):
                for c in range(k):
                    out[m, i, c] = h[i, c]


def _store_point(acc: _F, rational: bool, out: _F, m: int) -> None:  # pragma: no cover - compiled
    """Homogeneous point ``acc`` (d+1,) (or Cartesian (d,)) to Cartesian ``out[m]`` (d,)."""
    d = out.shape[1]
    if rational:
        for c in range(d):
            out[m, c] = acc[c] / acc[d]
    else:
        for c in range(d):
            out[m, c] = acc[c]


def _net_point(  # pragma: no cover - compiled
    Hf: _F, base: np.uint64, rowstride: np.uint64, k: int, Nu: _F, Nv: _F, acc: _F,
) -> None:
    """``acc[:k] = sum_a Nu[a] sum_b Nv[b] H[r0 + a, c0 + b, :]`` (scalar accumulators).

    ``Hf`` is the flat net, ``base`` the flat offset of ``H[r0, c0, 0]`` and ``rowstride`` that
    of one u-row (``n_v * k``), both ``uint64``: numba emits no negative-index fix-up for them.
    The coordinates go four at a time in scalar accumulators (a last group of fewer than four
    leaves the fourth lane idle, its spare lanes re-reading the last coordinate, bit for bit):
    independent chains run about twice as fast as a loop over k, which LLVM cannot unroll for a
    run-time k. One body for every k (it replaced separate k = 3, k = 4 and any-k helpers; under
    load, k = 3 measured 0.85-0.9x the time of the k = 3 helper, k = 4 1.0-1.2x, k = 5 0.6x).
    """
    uk = np.uint64(k)
    for cc in range(0, k, 4):
        four = k - cc >= 4
        e0 = np.uint64(cc)
        e1 = np.uint64(min(cc + 1, k - 1))
        e2 = np.uint64(min(cc + 2, k - 1))
        e3 = np.uint64(min(cc + 3, k - 1))
        a0 = 0.0
        a1 = 0.0
        a2 = 0.0
        a3 = 0.0
        row = base
        for a in range(Nu.shape[0]):
            b0 = 0.0
            b1 = 0.0
            b2 = 0.0
            b3 = 0.0
            o = row
            for b in range(Nv.shape[0]):
                w = Nv[b]
                b0 += w * Hf[o + e0]
                b1 += w * Hf[o + e1]
                b2 += w * Hf[o + e2]
                if four:
                    b3 += w * Hf[o + e3]
                o += uk
            w = Nu[a]
            a0 += w * b0
            a1 += w * b1
            a2 += w * b2
            a3 += w * b3
            row += rowstride
        acc[e0] = a0
        acc[e1] = a1
        acc[e2] = a2
        if four:
            acc[e3] = a3


def surface_points(  # pragma: no cover
    U: _F, p: int, fu: int, lu: int, tu: _I, u0: float, cu: float,
    V: _F, q: int, fv: int, lv: int, tv: _I, v0: float, cv: float,
    H: _F, u: _F, v: _F, rational: bool, out: _F,
) -> None:
    """Surface points: ``H`` (n_u, n_v, k) homogeneous net, ``u, v`` (m,), ``out`` (m, d).

    ``fu, lu, tu, u0, cu`` (and the same for v) are :func:`span_table`. Per point: the spans and
    basis functions (:func:`_span`, :func:`_basis`), the contraction with the net in scalar
    accumulators (:func:`_net_point`), the quotient (:func:`_store_point`).
    """
    k = H.shape[2]
    Nu = np.empty(p + 1)
    Nv = np.empty(q + 1)
    left = np.empty(max(p, q) + 1)
    right = np.empty(max(p, q) + 1)
    acc = np.empty(k)
    Hf = H.reshape(H.size)
    rowstride = np.uint64(H.shape[1] * k)
    uk = np.uint64(k)
    for m in range(u.shape[0]):
        x = u[m]
        y = v[m]
        su = _span(U, fu, lu, tu, u0, cu, x)
        sv = _span(V, fv, lv, tv, v0, cv, y)
        _basis(U, p, su, x, Nu, left, right)
        _basis(V, q, sv, y, Nv, left, right)
        r0 = su - p
        c0 = sv - q
        _net_point(Hf, np.uint64(r0) * rowstride + np.uint64(c0) * uk, rowstride, k, Nu, Nv, acc)
        _store_point(acc, rational, out, m)


def _tensor_partials(  # pragma: no cover - compiled
    H: _F, r0: int, c0: int, Du: _F, Dv: _F, T: _F, O: _F, m: int,
) -> None:
    """``O[m, i, j, :] = sum_{a,b} Du[i, a] Dv[j, b] H[r0 + a, c0 + b, :]`` (v first, via ``T``).

    Scalar accumulators over the coordinates (three at a time for k = 3, else four at a time,
    the spare lanes re-reading the last coordinate): independent chains run about twice as
    fast as a loop over k, which LLVM cannot unroll for a run-time k.
    """
    r1 = Du.shape[0]
    p1 = Du.shape[1]
    q1 = Dv.shape[1]
    k = H.shape[2]
    if k == 3:
        for a in range(p1):
            for j in range(r1):
                t0 = 0.0
                t1 = 0.0
                t2 = 0.0
                for b in range(q1):
                    w = Dv[j, b]
                    t0 += w * H[r0 + a, c0 + b, 0]
                    t1 += w * H[r0 + a, c0 + b, 1]
                    t2 += w * H[r0 + a, c0 + b, 2]
                T[a, j, 0] = t0
                T[a, j, 1] = t1
                T[a, j, 2] = t2
        for i in range(r1):
            for j in range(r1):
                t0 = 0.0
                t1 = 0.0
                t2 = 0.0
                for a in range(p1):
                    w = Du[i, a]
                    t0 += w * T[a, j, 0]
                    t1 += w * T[a, j, 1]
                    t2 += w * T[a, j, 2]
                O[m, i, j, 0] = t0
                O[m, i, j, 1] = t1
                O[m, i, j, 2] = t2
        return
    for cc in range(0, k, 4):
        e1 = min(cc + 1, k - 1)
        e2 = min(cc + 2, k - 1)
        e3 = min(cc + 3, k - 1)
        for a in range(p1):
            for j in range(r1):
                t0 = 0.0
                t1 = 0.0
                t2 = 0.0
                t3 = 0.0
                for b in range(q1):
                    w = Dv[j, b]
                    t0 += w * H[r0 + a, c0 + b, cc]
                    t1 += w * H[r0 + a, c0 + b, e1]
                    t2 += w * H[r0 + a, c0 + b, e2]
                    t3 += w * H[r0 + a, c0 + b, e3]
                T[a, j, cc] = t0
                T[a, j, e1] = t1
                T[a, j, e2] = t2
                T[a, j, e3] = t3
        for i in range(r1):
            for j in range(r1):
                t0 = 0.0
                t1 = 0.0
                t2 = 0.0
                t3 = 0.0
                for a in range(p1):
                    w = Du[i, a]
                    t0 += w * T[a, j, cc]
                    t1 += w * T[a, j, e1]
                    t2 += w * T[a, j, e2]
                    t3 += w * T[a, j, e3]
                O[m, i, j, cc] = t0
                O[m, i, j, e1] = t1
                O[m, i, j, e2] = t2
                O[m, i, j, e3] = t3


def _partials_scratch(p: int, q: int, r1: int, k: int) -> tuple:  # pragma: no cover - compiled
    """Work arrays of :func:`_partials_at` for degrees ``(p, q)``, ``r1 = order + 1`` and ``k``
    homogeneous coordinates: ``(Du, Dv, Nt, inv, left, right, T, h4, hf, o, start, src, wi, coef)``
    (``hf`` is ``h4`` as (r1^2, k), made here once rather than per point)."""
    pq = max(p, q) + 1
    start, src, wi, coef = _quotient_plan(r1)
    h4 = np.empty((1, r1, r1, k))
    return (np.empty((r1, p + 1)), np.empty((r1, q + 1)), np.empty((pq, pq)), np.empty((pq, pq)), np.empty(pq),
            np.empty(pq), np.empty((p + 1, r1, k)), h4, h4.reshape(r1 * r1, k), np.empty((r1 * r1, k)),
            start, src, wi, coef)


def _partials_at(  # pragma: no cover - compiled
    U: _F, p: int, fu: int, lu: int, tu: _I, u0: float, cu: float,
    V: _F, q: int, fv: int, lv: int, tv: _I, v0: float, cv: float,
    H: _F, rational: bool, x: float, y: float, order: int, scratch: tuple, out: _F, out3: _F, m: int,
) -> None:
    """The partials up to ``order`` at ``(x, y)`` into ``out[m]`` (``out``: (M, order+1, order+1, d),
    ``out3`` the same array as (M, (order+1)^2, d), which the quotient rule writes); ``scratch`` from
    :func:`_partials_scratch`. Spans and basis derivatives (A2.1 by table, BSPLVD), the tensor
    contraction, the quotient rule (A4.4) for a rational net."""
    Du, Dv, Nt, inv, left, right, T, h4, hf, o, start, src, wi, coef = scratch
    su = _span(U, fu, lu, tu, u0, cu, x)
    sv = _span(V, fv, lv, tv, v0, cv, y)
    _basis_ders(U, p, su, x, order, Du, Nt, inv, left, right)
    _basis_ders(V, q, sv, y, order, Dv, Nt, inv, left, right)
    if rational:
        _tensor_partials(H, su - p, sv - q, Du, Dv, T, h4, 0)
        _surface_quotient(hf, start, src, wi, coef, o, out3, m)
    else:
        _tensor_partials(H, su - p, sv - q, Du, Dv, T, out, m)


def surface_derivatives(  # pragma: no cover
    U: _F, p: int, fu: int, lu: int, tu: _I, u0: float, cu: float,
    V: _F, q: int, fv: int, lv: int, tv: _I, v0: float, cv: float,
    H: _F, u: _F, v: _F, order: int, rational: bool, out: _F,
) -> None:
    """All partials ``d^{i+j}/du^i dv^j`` with ``i, j <= order``: ``out`` (m, order+1, order+1, d)."""
    r1 = order + 1
    Du, Dv, Nt, inv, left, right, T, h4, hf, o, start, src, wi, coef = _partials_scratch(p, q, r1, H.shape[2])
    out3 = out.reshape(out.shape[0], r1 * r1, out.shape[3])
    # the body of _partials_at written out: through the helper the polynomial case ran ~8 % slower
    for m in range(u.shape[0]):
        x = u[m]
        y = v[m]
        su = _span(U, fu, lu, tu, u0, cu, x)
        sv = _span(V, fv, lv, tv, v0, cv, y)
        _basis_ders(U, p, su, x, order, Du, Nt, inv, left, right)
        _basis_ders(V, q, sv, y, order, Dv, Nt, inv, left, right)
        if rational:
            _tensor_partials(H, su - p, sv - q, Du, Dv, T, h4, 0)
            _surface_quotient(hf, start, src, wi, coef, o, out3, m)
        else:
            _tensor_partials(H, su - p, sv - q, Du, Dv, T, out, m)


def _dot3(a: _F, b: _F) -> float:  # pragma: no cover - compiled
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def surface_project(  # pragma: no cover
    U: _F, p: int, fu: int, lu: int, tu: _I, u0: float, cu: float,
    V: _F, q: int, fv: int, lv: int, tv: _I, v0: float, cv: float,
    H: _F, rational: bool, X: _F, a0: _F, b0: _F, D0: _F, box: _F, max_iter: int, stop: float, out: _F,
) -> None:
    """Foot points of ``X`` (m, 3) on a 3-D surface by damped Newton: ``out[i] = (u, v, |S - X|^2)``.

    Per point, the algorithm of :func:`occsurf.algorithms.fitting._common.project_points` (whose
    vectorised form is the reference): from ``(a0, b0)`` with partials ``D0`` (m, 3, 3, 3), the
    Newton step of ``|S - X|^2 / 2`` (exact Hessian where positive definite, else Gauss-Newton;
    ``det`` floored at 1e-300), stop when the step is not above ``stop``; the full step clipped to
    ``box`` = (u_lo, u_hi, v_lo, v_hi) is taken if ``f`` does not increase, else it is halved up to
    seven times; stop when no step was accepted or the move was not above ``stop``; at most
    ``max_iter`` steps.
    """
    k = H.shape[2]
    r1 = 3
    scratch = _partials_scratch(p, q, r1, k)
    left = scratch[4]
    right = scratch[5]
    Dc = np.empty((1, r1, r1, 3))
    Dt = np.empty((1, r1, r1, 3))
    Dc3 = Dc.reshape(1, r1 * r1, 3)
    Dt3 = Dt.reshape(1, r1 * r1, 3)
    Nu = np.empty(p + 1)
    Nv = np.empty(q + 1)
    acc = np.empty(k)
    pt = np.empty((1, 3))
    Hf = H.reshape(H.size)
    rowstride = np.uint64(H.shape[1] * k)
    uk = np.uint64(k)
    r = np.empty(3)
    ulo, uhi, vlo, vhi = box[0], box[1], box[2], box[3]
    for m in range(X.shape[0]):
        x = X[m]
        a = a0[m]
        b = b0[m]
        for i in range(r1):
            for j in range(r1):
                for c in range(3):
                    Dc[0, i, j, c] = D0[m, i, j, c]
        for c in range(3):
            r[c] = Dc[0, 0, 0, c] - x[c]
        f = _dot3(r, r)
        for _it in range(max_iter):
            for c in range(3):
                r[c] = Dc[0, 0, 0, c] - x[c]
            Su = Dc[0, 1, 0]
            Sv = Dc[0, 0, 1]
            g1 = _dot3(r, Su)
            g2 = _dot3(r, Sv)
            h11 = _dot3(Su, Su)
            h12 = _dot3(Su, Sv)
            h22 = _dot3(Sv, Sv)
            e11 = h11 + _dot3(r, Dc[0, 2, 0])
            e12 = h12 + _dot3(r, Dc[0, 1, 1])
            e22 = h22 + _dot3(r, Dc[0, 0, 2])
            if e11 > 0 and e11 * e22 - e12 * e12 > 0:
                h11 = e11
                h12 = e12
                h22 = e22
            det = h11 * h22 - h12 * h12
            if not abs(det) > 1e-300:
                det = 1e-300
            du = -(h22 * g1 - h12 * g2) / det
            dv = -(h11 * g2 - h12 * g1) / det
            adu = abs(du)
            adv = abs(dv)
            if du != du or dv != dv or not (adu > stop or adv > stop):
                break
            ta = min(max(a + du, ulo), uhi)
            tb = min(max(b + dv, vlo), vhi)
            _partials_at(U, p, fu, lu, tu, u0, cu, V, q, fv, lv, tv, v0, cv, H, rational, ta, tb, 2, scratch, Dt, Dt3, 0)
            ft = ((Dt[0, 0, 0, 0] - x[0]) * (Dt[0, 0, 0, 0] - x[0]) + (Dt[0, 0, 0, 1] - x[1]) * (Dt[0, 0, 0, 1] - x[1])
                  + (Dt[0, 0, 0, 2] - x[2]) * (Dt[0, 0, 0, 2] - x[2]))
            full = ft <= f
            accepted = full
            na = a
            nb = b
            if full:
                na = ta
                nb = tb
                f = ft
            else:
                step = 0.5
                for _half in range(7):
                    ta = min(max(a + step * du, ulo), uhi)
                    tb = min(max(b + step * dv, vlo), vhi)
                    su = _span(U, fu, lu, tu, u0, cu, ta)
                    sv = _span(V, fv, lv, tv, v0, cv, tb)
                    _basis(U, p, su, ta, Nu, left, right)
                    _basis(V, q, sv, tb, Nv, left, right)
                    _net_point(Hf, np.uint64(su - p) * rowstride + np.uint64(sv - q) * uk, rowstride, k, Nu, Nv, acc)
                    _store_point(acc, rational, pt, 0)
                    ft = ((pt[0, 0] - x[0]) * (pt[0, 0] - x[0]) + (pt[0, 1] - x[1]) * (pt[0, 1] - x[1])
                          + (pt[0, 2] - x[2]) * (pt[0, 2] - x[2]))
                    if ft <= f:
                        na = ta
                        nb = tb
                        f = ft
                        accepted = True
                        break
                    step *= 0.5
            moved = max(abs(na - a), abs(nb - b))
            a = na
            b = nb
            if not (accepted and moved > stop):
                break
            if full:
                for i in range(r1):
                    for j in range(r1):
                        for c in range(3):
                            Dc[0, i, j, c] = Dt[0, i, j, c]
            else:
                _partials_at(U, p, fu, lu, tu, u0, cu, V, q, fv, lv, tv, v0, cv, H, rational, a, b, 2, scratch, Dc, Dc3, 0)
        out[m, 0] = a
        out[m, 1] = b
        out[m, 2] = f


def _band_point(  # pragma: no cover - compiled
    Du: _F, a: int, s0: int, p: int, G: _F, b: int, O: _F, oa: int, ob: int,
) -> None:
    """``O[oa, ob, i, x] = sum_t Du[a, i, t] G[s0 + t, b, x]`` for all i, x (unrolled by four)."""
    r1 = Du.shape[1]
    X = G.shape[2]
    for t0 in range(0, p + 1, 4):
        if p + 1 - t0 >= 4:
            for i in range(r1):
                d0 = Du[a, i, t0]
                d1 = Du[a, i, t0 + 1]
                d2 = Du[a, i, t0 + 2]
                d3 = Du[a, i, t0 + 3]
                if t0 == 0:
                    for x in range(X):
                        O[oa, ob, i, x] = (d0 * G[s0 + t0, b, x] + d1 * G[s0 + t0 + 1, b, x]
                                           + d2 * G[s0 + t0 + 2, b, x] + d3 * G[s0 + t0 + 3, b, x])
                else:
                    for x in range(X):
                        O[oa, ob, i, x] += (d0 * G[s0 + t0, b, x] + d1 * G[s0 + t0 + 1, b, x]
                                            + d2 * G[s0 + t0 + 2, b, x] + d3 * G[s0 + t0 + 3, b, x])
        else:
            for i in range(r1):
                for t in range(t0, p + 1):
                    d = Du[a, i, t]
                    if t == 0:
                        for x in range(X):
                            O[oa, ob, i, x] = d * G[s0 + t, b, x]
                    else:
                        for x in range(X):
                            O[oa, ob, i, x] += d * G[s0 + t, b, x]


def grid_partials(Du: _F, su: _I, p: int, G: _F, out: _F) -> None:  # pragma: no cover - compiled
    """Second (u) stage of grid partials, polynomial case.

    ``Du`` (m_u, r+1, p+1) basis derivatives, ``su`` their spans, ``G`` (n_u, m_v, X) the net
    already contracted along v (``X = (r+1) k``, index ``[I, b, j*k + c]``); writes
    ``out[a, b, i, x] = sum_t Du[a, i, t] G[su[a]-p+t, b, x]``, shape (m_u, m_v, r+1, X).
    """
    for a in range(Du.shape[0]):
        s0 = su[a] - p
        for b in range(G.shape[1]):
            _band_point(Du, a, s0, p, G, b, out, a, b)


def grid_partials_rational(Du: _F, su: _I, p: int, G: _F, k: int, out: _F) -> None:  # pragma: no cover - compiled
    """:func:`grid_partials` fused with the quotient rule (A4.4).

    ``out`` (m_u * m_v, r+1, r+1, k-1): the grid partials with the two grid axes flattened.
    """
    r1 = Du.shape[1]
    mv = G.shape[1]
    h4 = np.empty((1, 1, r1, r1 * k))
    hf = h4.reshape(r1 * r1, k)
    o = np.empty((r1 * r1, k))
    start, src, wi, coef = _quotient_plan(r1)
    out3 = out.reshape(out.shape[0], r1 * r1, out.shape[3])
    for a in range(Du.shape[0]):
        s0 = su[a] - p
        for b in range(mv):
            _band_point(Du, a, s0, p, G, b, h4, 0, 0)
            _surface_quotient(hf, start, src, wi, coef, o, out3, a * mv + b)


#: Compiled as functions the kernels call; numba links each into the kernel's module and LLVM
#: inlines what it chooses (``surface_points``' machine code: 135 call instructions with numba's
#: ``inline="always"``, 138 without). Numba's inlining, used for all but ``_partials_at`` until
#: 2026-12-07, copies each helper into every kernel's IR before typing: the speeds were the same (old
#: and new alternately in one process: 0.76-1.04x of the time per kernel) and the results the same
#: bit for bit, but the seven kernels' first compile took 34.1-40.8 s against 21.2-28.2 s now.
#: ``_partials_at`` was a call before too: numba-inlined into ``surface_project`` it took that
#: kernel's first compile from 17 s to 29 s for a projection 5-25 % faster.
_HELPERS = (
    "_span", "_basis", "_basis_ders", "_binomials", "_quotient_plan", "_curve_quotient", "_surface_quotient",
    "_tensor_partials", "_band_point", "_store_point", "_net_point", "_dot3", "_partials_scratch", "_partials_at",
)
_KERNELS = (
    "curve_points",
    "curve_derivatives",
    "surface_points",
    "surface_derivatives",
    "grid_partials",
    "grid_partials_rational",
    "surface_project",
)


# ---------------------------------------------------------------------------------------------
# Loading and dispatch.


def jit(numba: Any, fn: Any, **options: Any) -> Any:
    """``fn`` compiled by ``numba.njit`` as every kernel of occsurf is (``nogil``, NumPy's error model,
    ``options`` added), cached on disk where a cache folder is writable, else per process."""
    try:
        return numba.njit(cache=True, nogil=True, error_model="numpy", **options)(fn)
    except RuntimeError:  # no writable cache location: compile per process instead
        return numba.njit(nogil=True, error_model="numpy", **options)(fn)


def load() -> dict[str, Any] | None:
    """The compiled kernels by name, or ``None`` without numba: numba is imported and the kernels
    compiled (or read from the cache) on the first call in a process; later calls return the same."""
    with _lock:
        if _state["loaded"]:
            return _state["kernels"]
        kernels = None
        try:
            import numba
        except Exception:  # noqa: BLE001 - numba missing or broken: NumPy paths
            pass
        else:
            g = globals()
            # Helpers first: kernels resolve them as globals when they compile.
            for name in _HELPERS:
                g[name] = jit(numba, g[name])
            kernels = {name: jit(numba, g[name]) for name in _KERNELS}
        _state["kernels"] = kernels
        _state["loaded"] = True
        return kernels


def readonly(a: Any) -> Any:
    """A C-contiguous read-only view (a copy only if ``a`` is not contiguous)."""
    if isinstance(a, np.ndarray):
        a = np.ascontiguousarray(a).view()
        a.flags.writeable = False
    return a


def loaded() -> bool:
    """Whether :func:`load` has run in this process (numba imported, or found missing)."""
    return bool(_state["loaded"])


def kernel(name: str) -> Any | None:
    """The compiled kernel ``name`` when the kernels are loaded and it has not been dropped (see
    :func:`run`), else ``None``; never loads numba (:func:`applies` or :func:`load` do)."""
    return (_state["kernels"] or {}).get(name)


def surface_args(surface: Any) -> tuple[Any, ...]:
    """A :class:`~occsurf.algorithms.kernel.surface.BSplineSurface`'s knots, degrees, span tables
    (:func:`span_table`) and homogeneous net, as the surface kernels take them before the parameters."""
    (p, q), (U, Vk), (nu, nv) = surface.degree, surface.knots, surface.n_poles
    return (U, p, *span_table(U, p, nu), Vk, q, *span_table(Vk, q, nv), surface.homogeneous_points)


def enabled() -> bool:
    """True unless ``OCCSURF_NO_NUMBA`` is set (numba itself is only imported on first use)."""
    return os.environ.get(ENV_DISABLE, "") in ("", "0")


def applies(n_points: int) -> bool:
    """Whether the numba kernels should evaluate ``n_points`` points.

    True when numba is installed, ``OCCSURF_NO_NUMBA`` is not set and ``n_points`` is at least
    :data:`~occsurf.algorithms.tolerances.NUMBA_MIN_POINTS`. The first True answer in a process
    imports numba.
    """
    if (n_points < tolerances.NUMBA_MIN_POINTS and not _in_batch.get()) or not enabled():
        return False
    kernels = _state["kernels"] if _state["loaded"] else load()
    return kernels is not None


@contextlib.contextmanager
def batch(n_points: int) -> Iterator[None]:
    """Inside the block, :func:`applies` is true at every size when ``n_points`` (the work the
    caller is about to do, e.g. the data of a fit) reaches
    :data:`~occsurf.algorithms.tolerances.NUMBA_MIN_POINTS`.

    An iterative algorithm that starts on many points continues on fewer (the points of a
    projection still moving, the data of one overlay): with the size rule alone those later
    evaluations fall back to the NumPy path, which costs 4-6x more per point from ~100 points on
    (``bench_evaluation.py``). The choice depends on ``n_points`` only, never on what ran before
    in the process, so a call's results do not change with history. Nested blocks keep the
    outer choice when it is on.
    """
    on = n_points >= tolerances.NUMBA_MIN_POINTS and enabled()
    token = _in_batch.set(True) if on else None
    try:
        yield
    finally:
        if token is not None:
            _in_batch.reset(token)


def run(name: str, *args: Any) -> bool:
    """Run kernel ``name`` on ``args``; False means "use the NumPy path" (call :func:`applies` first).

    A kernel that fails (typing or lowering errors under an untested numba version) is dropped
    for the rest of the process with a warning; the caller then computes the result with NumPy.
    """
    kernels = _state["kernels"]
    if kernels is None or name not in kernels:
        return False
    # Inputs as read-only views (the output, last, stays writable): one compiled signature per
    # kernel whatever the flags of the caller's arrays, so nothing is compiled twice.
    args = tuple(readonly(a) for a in args[:-1]) + args[-1:]
    try:
        kernels[name](*args)
    except Exception as err:  # noqa: BLE001
        import warnings

        warnings.warn(f"occsurf: numba kernel {name!r} failed ({err!r}); using NumPy", RuntimeWarning, stacklevel=3)
        kernels.pop(name, None)
        return False
    return True
