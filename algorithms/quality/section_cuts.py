"""One face cut by planes (:mod:`.sections`' steps 1, 2 and 4, and step 3's ordering of the
chains): marching squares on the signed distance over a parameter grid, every crossing refined
onto the exact surface, the pieces that leave the face's trim cut at its boundary, the chains of
segments ordered by pointer doubling, and the exact curvature of the cut with its inflections
located.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from .. import tolerances
from ..hierarchical.surface import HierarchicalSurface
from ..kernel.surface import BSplineSurface
from ._common import Array, dot

__all__ = ["Face", "Ints", "march", "edge_ends", "on_edge", "newton", "to_trim", "order_chains", "rank", "cut_curvature",
           "tangent_hints", "refine_inflections"]

Ints = NDArray[np.intp]
#: A surface the sections cut.
Face = BSplineSurface | HierarchicalSurface


# ------------------------------------------------------------------------------ marching squares
def march(h: Array) -> tuple[Ints, Ints, Ints, int, Ints]:
    """Oriented zero-crossing segments of ``h`` (k, mu, mv), all planes at once.

    Returns ``(plane, src_edge, dst_edge, n_u_edges, cell)`` (``cell = i * (mv - 1) + j``): edge ids ``< n_u_edges`` lie along u
    (``(i, j)-(i+1, j)`` -> ``i * mv + j``), the others along v (``(i, j)-(i, j+1)``).
    """
    k, mu, mv = h.shape
    pos = h >= 0
    c = np.stack((pos[:, :-1, :-1], pos[:, 1:, :-1], pos[:, 1:, 1:], pos[:, :-1, 1:]), -1)  # (k, cu, cv, 4) CCW
    cu, cv = mu - 1, mv - 1
    ii, jj = np.meshgrid(np.arange(cu), np.arange(cv), indexing="ij")
    nu_e = (mu - 1) * mv
    eid = np.stack((ii * mv + jj, nu_e + (ii + 1) * (mv - 1) + jj, ii * mv + jj + 1, nu_e + ii * (mv - 1) + jj), -1)
    nxt = np.roll(c, -1, axis=-1)
    exit_ = c & ~nxt  # + -> - walking CCW along edge e (from corner e to corner e + 1)
    entry = ~c & nxt
    n_exit = exit_.sum(-1)
    planes, srcs, dsts, cells = [], [], [], []
    one = n_exit == 1  # one segment: from the exit edge to the entry edge
    pk, pi, pj = np.nonzero(one)
    planes.append(pk)
    cells.append(pi * cv + pj)
    srcs.append(eid[pi, pj, np.argmax(exit_[one], -1)])
    dsts.append(eid[pi, pj, np.argmax(entry[one], -1)])
    two = n_exit == 2  # saddle: the bilinear centre value decides which corners are joined
    pk, pi, pj = np.nonzero(two)
    if pk.size:
        centre = 0.25 * (h[:, :-1, :-1] + h[:, 1:, :-1] + h[:, 1:, 1:] + h[:, :-1, 1:])[two] >= 0
        step = np.where(centre, 1, -1)  # positive centre: cut off the negative corners
        ex = np.argsort(~exit_[two], axis=-1, kind="stable")[:, :2]
        for which in (0, 1):
            e = ex[:, which]
            planes.append(pk)
            cells.append(pi * cv + pj)
            srcs.append(eid[pi, pj, e])
            dsts.append(eid[pi, pj, (e + step) % 4])
    return np.concatenate(planes), np.concatenate(srcs), np.concatenate(dsts), nu_e, np.concatenate(cells)


def edge_ends(edges: Ints, plane: Ints, h: Array, us: Array, vs: Array, nu_e: int) -> tuple[Array, Array, Array]:
    """End parameters ``(n, 2)`` of each grid edge and the linear-interpolation zero ``t`` on it."""
    mv = vs.size
    along_u = edges < nu_e
    i = np.where(along_u, edges // mv, (edges - nu_e) // (mv - 1))
    j = np.where(along_u, edges % mv, (edges - nu_e) % (mv - 1))
    i2, j2 = np.where(along_u, i + 1, i), np.where(along_u, j, j + 1)
    h0, h1 = h[plane, i, j], h[plane, i2, j2]
    with np.errstate(invalid="ignore", divide="ignore"):
        t = np.clip(np.where(h0 != h1, h0 / (h0 - h1), 0.5), 0.0, 1.0)
    return np.stack((us[i], vs[j]), -1), np.stack((us[i2], vs[j2]), -1), t


def on_edge(s: Face, uv0: Array, uv1: Array, t: Array, o: Array, n: Array, tol: float) -> tuple[Array, NDArray[np.bool_]]:
    """The zero of ``h = (S - o) . n`` on each grid edge ``uv0 -> uv1`` (bracketed: ``h`` changes
    sign along it), by Newton's method safeguarded with bisection, all edges at once; converges
    whenever the seed is real. Returns ``(uv, converged)``."""
    lo, hi = np.zeros(t.size), np.ones(t.size)
    d = uv1 - uv0
    D0 = s.derivatives(uv0[:, 0], uv0[:, 1], 0)
    sign0 = np.sign(dot(D0[:, 0, 0] - o, n))
    done = np.zeros(t.size, bool)
    for _ in range(4 * int(tolerances.QUALITY_SECTION_NEWTON_STEPS)):
        todo = np.flatnonzero(~done)
        if todo.size == 0:
            break
        uv = uv0[todo] + t[todo, None] * d[todo]
        D = s.derivatives(uv[:, 0], uv[:, 1], 1)
        f = dot(D[:, 0, 0] - o[todo], n[todo])
        ok = np.abs(f) <= tol
        done[todo[ok]] = True
        same = np.sign(f) == sign0[todo]
        lo[todo] = np.where(same, t[todo], lo[todo])
        hi[todo] = np.where(same, hi[todo], t[todo])
        fp = dot(D[:, 1, 0], n[todo]) * d[todo, 0] + dot(D[:, 0, 1], n[todo]) * d[todo, 1]
        with np.errstate(invalid="ignore", divide="ignore"):
            tn = t[todo] - f / fp
        inside = np.isfinite(tn) & (tn > lo[todo]) & (tn < hi[todo])
        t[todo] = np.where(ok, t[todo], np.where(inside, tn, 0.5 * (lo[todo] + hi[todo])))
        # a bracket shrunk to round-off with |f| still above tol: the tolerance is below what the
        # surface's evaluation resolves there; stop (the final check reports it unconverged)
        done[todo[(hi[todo] - lo[todo]) <= 4 * np.finfo(float).eps]] = True
    uv = uv0 + t[:, None] * d
    D = s.derivatives(uv[:, 0], uv[:, 1], 0)
    conv = np.abs(dot(D[:, 0, 0] - o, n)) <= tol
    return uv, conv


def newton(s: Face, uv: Array, o: Array, n: Array, tol: float) -> tuple[Array, NDArray[np.bool_]]:
    """Refine ``uv`` (p, 2) onto ``(S - o) . n = 0`` (o, n per point); returns (uv, converged)."""
    (u0, u1), (v0, v1) = s.domain
    uv = uv.copy()
    done = np.zeros(uv.shape[0], bool)
    for _ in range(int(tolerances.QUALITY_SECTION_NEWTON_STEPS)):
        todo = np.flatnonzero(~done)
        if todo.size == 0:
            break
        D = s.derivatives(uv[todo, 0], uv[todo, 1], 1)
        h = dot(D[:, 0, 0] - o[todo], n[todo])
        ok = np.abs(h) <= tol
        done[todo[ok]] = True
        g = np.stack((dot(D[:, 1, 0], n[todo]), dot(D[:, 0, 1], n[todo])), -1)
        g2 = dot(g, g)
        with np.errstate(invalid="ignore", divide="ignore"):
            step = np.where((g2 > 0)[:, None], -h[:, None] * g / g2[:, None], 0.0)
        w = todo[~ok]
        uv[w] = uv[w] + step[~ok]
        uv[w, 0] = np.clip(uv[w, 0], u0, u1)
        uv[w, 1] = np.clip(uv[w, 1], v0, v1)
    return uv, done


def to_trim(s: Face, keep: Callable[[Array, Array, Ints], NDArray[np.bool_]], uv_in: Array, uv_out: Array, o: Array,
             n: Array, tol_h: float) -> Array:
    """March each cut from its last point inside the trim (``uv_in``) to the trim boundary, towards
    its next point outside (``uv_out``; both on the intersection): bisection along the cut, every
    trial point projected onto the intersection by :func:`newton` and tested by ``keep(uv, X, i)``,
    all segments at once, until the inside and outside points are within ``tol_h`` of each other
    in model space (so the returned inside point is within ``tol_h`` of the boundary that
    ``keep`` draws). Returns the inside ends ``(p, 2)``."""
    lo, hi = uv_in.copy(), uv_out.copy()
    X_lo, X_hi = s.evaluate(lo[:, 0], lo[:, 1]), s.evaluate(hi[:, 0], hi[:, 1])
    live = np.linalg.norm(X_hi - X_lo, axis=1) > tol_h
    for _ in range(4 * int(tolerances.QUALITY_SECTION_NEWTON_STEPS)):
        i = np.flatnonzero(live)
        if i.size == 0:
            break
        mid, conv = newton(s, 0.5 * (lo[i] + hi[i]), o[i], n[i], tol_h)
        Xm = s.evaluate(mid[:, 0], mid[:, 1])
        inside = conv & keep(mid, Xm, i)
        j, k = i[inside], i[~inside]
        lo[j], X_lo[j] = mid[inside], Xm[inside]
        hi[k], X_hi[k] = mid[~inside], Xm[~inside]
        live[i] = np.linalg.norm(X_hi[i] - X_lo[i], axis=1) > tol_h
        live[i[~conv]] = False  # the cut turned tangent to the plane: keep the last inside point
    return lo


# -------------------------------------------------------------------------------------- chaining
def order_chains(src: Ints, dst: Ints) -> list[tuple[Ints, bool]]:
    """Oriented segments ``src -> dst`` (node ids 0..N-1, each node at most one in and one out)
    ordered into chains by pointer doubling. Returns ``[(nodes, closed), ...]``."""
    N = int(max(src.max(), dst.max())) + 1
    nxt = np.full(N, -1)
    nxt[src] = dst
    has_pred = np.zeros(N, bool)
    has_pred[dst] = True
    used = np.zeros(N, bool)
    used[src] = used[dst] = True
    ncomp, lab = connected_components(coo_matrix((np.ones(src.size), (src, dst)), shape=(N, N)), directed=False)
    # components without a start node are cycles: cut each before its smallest node
    starts = used & ~has_pred
    has_start = np.zeros(ncomp, bool)
    has_start[lab[starts]] = True
    cyc_nodes = np.flatnonzero(used & ~has_start[lab])
    closed = np.zeros(ncomp, bool)
    if cyc_nodes.size:
        first = np.full(ncomp, N)
        np.minimum.at(first, lab[cyc_nodes], cyc_nodes)
        cut_to = first[lab[cyc_nodes]]
        pred_of_first = cyc_nodes[nxt[cyc_nodes] == cut_to]
        nxt[pred_of_first] = -1
        closed[lab[cyc_nodes]] = True
    dist = rank(nxt)
    nodes = np.flatnonzero(used)
    order = np.lexsort((-dist[nodes], lab[nodes]))
    nodes = nodes[order]
    labs = lab[nodes]
    cuts = np.flatnonzero(np.diff(labs)) + 1
    return [(part, bool(closed[lab[part[0]]])) for part in np.split(nodes, cuts)]


def rank(nxt: Ints) -> NDArray[np.int64]:
    """Number of steps from each node to the end of its (acyclic) chain: list ranking by pointer
    doubling (Wyllie), ``log2`` of the longest chain synchronous NumPy steps."""
    dist = (nxt >= 0).astype(np.int64)
    ptr = nxt.copy()
    while True:
        live = np.flatnonzero(ptr >= 0)
        if live.size == 0:
            return dist
        p = ptr[live]
        new_dist = dist[live] + dist[p]
        new_ptr = ptr[p]
        dist[live] = new_dist
        ptr[live] = new_ptr


# ------------------------------------------------------------------------- curvature on the cut
def cut_curvature(s: Face, uv: Array, m: Array, tangent_hint: Array) -> tuple[Array, Array, Array]:
    """Signed curvature of the intersection with the plane of normal ``m`` (per point), the unit
    tangent oriented along ``tangent_hint`` and the points. Meusnier: ``kappa_s = k_n(t) / (N_c . n_s)``."""
    D = s.derivatives(uv[:, 0], uv[:, 1], 2)
    su, sv = D[:, 1, 0], D[:, 0, 1]
    with np.errstate(invalid="ignore", divide="ignore"):
        ns = np.cross(su, sv)
        ns /= np.linalg.norm(ns, axis=-1, keepdims=True)
        t = np.cross(m, ns)
        t /= np.linalg.norm(t, axis=-1, keepdims=True)
        t *= np.where(dot(t, tangent_hint) < 0, -1.0, 1.0)[:, None]
        E, F, G = dot(su, su), dot(su, sv), dot(sv, sv)
        b1, b2 = dot(t, su), dot(t, sv)
        det = E * G - F * F
        a = (G * b1 - F * b2) / det  # t = a S_u + b S_v (t is tangent to the surface)
        b = (E * b2 - F * b1) / det
        L, M, N = dot(D[:, 2, 0], ns), dot(D[:, 1, 1], ns), dot(D[:, 0, 2], ns)
        kn = (L * a * a + 2 * M * a * b + N * b * b) / (E * a * a + 2 * F * a * b + G * b * b)
        Nc = np.cross(m, t)
        ks = kn / dot(Nc, ns)
    return ks, t, D[:, 0, 0]


def tangent_hints(P: Array, closed: bool) -> Array:
    """Chord directions along a polyline (central differences), used to orient tangents."""
    if P.shape[0] < 2:
        return np.zeros_like(P)
    if closed:
        return np.roll(P, -1, axis=0) - np.roll(P, 1, axis=0)
    g = np.empty_like(P)
    g[1:-1] = P[2:] - P[:-2]
    g[0], g[-1] = P[1] - P[0], P[-1] - P[-2]
    return g


def refine_inflections(s: Face, uv_a: Array, uv_b: Array, ka: Array, kb: Array, o: Array, m: Array, hint: Array,
                        tol_uv: float, tol_h: float) -> Array:
    """Zeros of the signed curvature on the exact cut between samples of opposite sign: the
    Illinois variant of regula falsi on the fraction ``c`` of the bracket (each trial point projected
    onto the intersection by Newton), all brackets at once; stops when the bracket is below
    ``tol_uv`` in parameter space or the curvature is zero to round-off."""
    n = uv_a.shape[0]
    a, b = np.zeros(n), np.ones(n)
    fa, fb = ka.astype(float).copy(), kb.astype(float).copy()
    span = np.linalg.norm(uv_b - uv_a, axis=1)
    on = np.broadcast_to(o, (n, 3))
    mm = np.broadcast_to(m, (n, 3))
    best = 0.5 * np.ones(n)
    live = np.ones(n, bool)
    for _ in range(100):
        live &= np.abs(b - a) * span > tol_uv
        if not np.any(live):
            break
        i = np.flatnonzero(live)
        c = (a[i] * fb[i] - b[i] * fa[i]) / (fb[i] - fa[i])
        c = np.where(np.isfinite(c) & (c > np.minimum(a[i], b[i])) & (c < np.maximum(a[i], b[i])), c, 0.5 * (a[i] + b[i]))
        uv, _ok = newton(s, uv_a[i] + c[:, None] * (uv_b[i] - uv_a[i]), on[i], mm[i], tol_h)
        fc, _, _ = cut_curvature(s, uv, mm[i], hint[i])
        best[i] = c
        exact = ~np.isfinite(fc) | (fc == 0)
        swap = fc * fb[i] < 0  # the root lies between b and c: b becomes the other end
        a[i] = np.where(swap, b[i], a[i])
        fa[i] = np.where(swap, fb[i], 0.5 * fa[i])  # Illinois: halve the stale end's value
        b[i], fb[i] = c, fc
        live[i[exact]] = False
    uv, _ok = newton(s, uv_a + best[:, None] * (uv_b - uv_a), on, mm, tol_h)
    return s.evaluate(uv[:, 0], uv[:, 1])
