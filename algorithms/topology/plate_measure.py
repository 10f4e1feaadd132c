"""What a plate's coefficients achieve along the hole's sides (:func:`.plate_fill.fill_plate`, course §8-3).

The plate is a height field over a plane; its fit and its stopping rule look at the sides at
samples. This module holds those samples in the plate's local frame (points, the neighbours'
normals, for G2 sides the neighbours' curvature as a height's Hessian), the tensor basis rows
there (values, first and second derivatives), the G2 sides' least-squares curvature rows, and
:class:`Evaluation`: the distance, angle and curvature jump a coefficient vector leaves at every
sample, per side, and where it misses a target (the spans :func:`.plate_fill.fill_plate` refines).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..kernel.basis import basis_derivatives, find_span
from ..kernel.curve import BSplineCurve
from .nsided_types import HoleSide
from .side_jets import cross_curvature, graph_jet, relative_jump, side_jet

__all__ = ["side_samples", "local_data", "local_jet", "basis_rows", "basis_rows2", "normal_angle", "Evaluation",
           "Curvature", "curvature_rows", "corner_g2"]

Array = NDArray[np.float64]


def side_samples(side: HoleSide, t: Array) -> tuple[Array, Array, Array]:
    """Points, Cartesian tangents and Cartesian cross derivatives of a side at parameters ``t``."""
    c = side.curve
    D = c.derivatives(t, 1)
    P, T = D[:, 0], D[:, 1]
    X = side.cross.evaluate(t)
    if c.is_rational:
        hc = BSplineCurve._trusted(c.degree, c.knots, c.homogeneous_points)
        h = hc.evaluate(t)
        X = (X[:, :3] - X[:, 3:4] * (h[:, :3] / h[:, 3:4])) / h[:, 3:4]
    return P, T, X


def basis_rows(ku: Array, kv: Array, p: int, u: Array, v: Array) -> tuple[Array, Array, Array, Array]:
    """Per point: values, d/du and d/dv of the (p+1)^2 non-zero tensor basis functions, and their columns."""
    nu, nv = ku.size - p - 1, kv.size - p - 1
    su, sv = find_span(ku, p, nu, u), find_span(kv, p, nv, v)
    Du, Dv = basis_derivatives(ku, p, su, u, 1), basis_derivatives(kv, p, sv, v, 1)  # (m, 2, p+1)
    val = (Du[:, 0, :, None] * Dv[:, 0, None, :]).reshape(u.size, -1)
    du = (Du[:, 1, :, None] * Dv[:, 0, None, :]).reshape(u.size, -1)
    dv = (Du[:, 0, :, None] * Dv[:, 1, None, :]).reshape(u.size, -1)
    cols = ((su[:, None] - p + np.arange(p + 1))[:, :, None] * nv
            + (sv[:, None] - p + np.arange(p + 1))[:, None, :]).reshape(u.size, -1)
    return val, du, dv, cols


def basis_rows2(ku: Array, kv: Array, p: int, u: Array,
           v: Array) -> tuple[Array, Array, Array, Array, Array, Array, Array]:
    """:func:`basis_rows` and the rows of d2/du2, d2/dudv and d2/dv2: ``(val, du, dv, duu, duv, dvv, cols)``."""
    nu, nv = ku.size - p - 1, kv.size - p - 1
    su, sv = find_span(ku, p, nu, u), find_span(kv, p, nv, v)
    Du, Dv = basis_derivatives(ku, p, su, u, 2), basis_derivatives(kv, p, sv, v, 2)  # (m, 3, p+1)

    def tensor(i: int, j: int) -> Array:
        return (Du[:, i, :, None] * Dv[:, j, None, :]).reshape(u.size, -1)

    cols = ((su[:, None] - p + np.arange(p + 1))[:, :, None] * nv
            + (sv[:, None] - p + np.arange(p + 1))[:, None, :]).reshape(u.size, -1)
    return tensor(0, 0), tensor(1, 0), tensor(0, 1), tensor(2, 0), tensor(1, 1), tensor(0, 2), cols


def normal_angle(gu: Array, gv: Array, m: Array) -> Array:
    """Angle (degrees, sign-free) between the normal ``(-gu, -gv, 1)`` and ``m`` (local frame)."""
    n = np.c_[-gu, -gv, np.ones_like(gu)]
    c = np.abs(np.einsum("ij,ij->i", n, m))
    s = np.linalg.norm(np.cross(n, m), axis=1)
    return np.degrees(np.arctan2(s, c))


class Evaluation:
    """Boundary samples (the fit's and those between them) with their basis rows: what a coefficient
    vector achieves there (vectorised over all samples)."""

    def __init__(self, sides: list[HoleSide], flags: NDArray[np.bool_], ts: list[Array], ku: Array, kv: Array,
                 p: int, o: Array, R: Array, L: float, g2: NDArray[np.bool_] | None = None, kfloor: float = 0.0,
                 g2_tol: float = 1.0) -> None:
        data = [local_data(s, t, o, R, L) for s, t in zip(sides, ts)]
        self.sid = np.concatenate([np.full(len(t), i) for i, t in enumerate(ts)])
        self.X = np.concatenate([d[0] for d in data])
        self.M = np.concatenate([d[1] for d in data])
        self.g1 = flags[self.sid]
        self.val, self.du, self.dv, self.cols = basis_rows(ku, kv, p, self.X[:, 0], self.X[:, 1])
        self.L, self.n = L, len(sides)
        self.curv: Curvature | None = None
        if g2 is not None and g2.any():
            self.curv = Curvature(sides, g2, ts, ku, kv, p, o, R, L, kfloor)
        self.g2_tol = g2_tol

    def side_g2(self, c: Array) -> Array:
        """Per side: the largest relative curvature jump across it (``nan`` where G2 is not asked)."""
        out = np.full(self.n, np.nan)
        if self.curv is not None:
            rel = self.curv.jumps(c)
            top = np.full(self.n, -np.inf)
            np.maximum.at(top, self.curv.sid, rel)
            out[np.isfinite(top)] = top[np.isfinite(top)]
        return out

    def errors(self, c: Array) -> tuple[Array, Array]:
        """Per sample: distance (model units) and angle (degrees; nan on G0-only sides)."""
        cc = c[self.cols]
        e0 = np.abs(np.einsum("ij,ij->i", self.val, cc) - self.X[:, 2]) * self.L
        ang = np.full(e0.shape, np.nan)
        g = self.g1
        ang[g] = normal_angle(np.einsum("ij,ij->i", self.du[g], cc[g]), np.einsum("ij,ij->i", self.dv[g], cc[g]), self.M[g])
        return e0, ang

    def score(self, c: Array, g0_tol: float, angle_tol: float) -> float:
        """The worst sample in units of the targets (<= 1: both met everywhere)."""
        e0, ang = self.errors(c)
        worst = float(e0.max()) / g0_tol
        if self.g1.any():
            worst = max(worst, float(np.nanmax(ang)) / angle_tol)
        if self.curv is not None:
            worst = max(worst, float(self.curv.jumps(c).max()) / self.g2_tol)
        return worst if np.isfinite(worst) else np.inf

    def measure(self, c: Array, g0_tol: float, angle_tol: float) -> tuple[Array, Array, Array, Array]:
        """Per side the largest distance and angle; the (u, v) of the samples that miss a target."""
        e0, ang = self.errors(c)
        g0 = np.zeros(self.n)
        np.maximum.at(g0, self.sid, e0)
        g1 = np.full(self.n, -np.inf)
        np.maximum.at(g1, self.sid[self.g1], ang[self.g1])
        g1[~np.isfinite(g1)] = np.nan
        miss = (e0 > g0_tol) | (self.g1 & (np.nan_to_num(ang, nan=0.0) > angle_tol))
        bu, bv = self.X[miss, 0], self.X[miss, 1]
        if self.curv is not None:
            far = self.curv.jumps(c) > self.g2_tol
            bu, bv = np.r_[bu, self.curv.X[far, 0]], np.r_[bv, self.curv.X[far, 1]]
        return g0, g1, bu, bv


class Curvature:
    """The neighbours' curvature across the G2 sides at samples (local frame, units of ``L``) and the
    plate's second-derivative rows there: the relative jump a coefficient vector leaves."""

    def __init__(self, sides: list[HoleSide], g2: NDArray[np.bool_], ts: list[Array], ku: Array, kv: Array,
                 p: int, o: Array, R: Array, L: float, kfloor: float) -> None:
        idx = [i for i in range(len(sides)) if g2[i]]
        jets = [local_jet(sides[i], ts[i], o, R, L) for i in idx]
        self.sid = np.concatenate([np.full(len(ts[i]), i) for i in idx])
        self.X = np.concatenate([j[0] for j in jets])
        self.T = np.concatenate([j[1] for j in jets])
        self.m = np.concatenate([j[2] for j in jets])
        self.k = np.concatenate([j[5] for j in jets])
        self.val, self.du, self.dv, self.duu, self.duv, self.dvv, self.cols = basis_rows2(
            ku, kv, p, self.X[:, 0], self.X[:, 1])
        self.kfloor = kfloor

    def jumps(self, c: Array) -> Array:
        """Per sample, CATIA's G2 ratio between the plate and the neighbour across the side."""
        cc = c[self.cols]
        h = [np.einsum("ij,ij->i", rows, cc) for rows in (self.du, self.dv, self.duu, self.duv, self.dvv)]
        z, one = np.zeros_like(h[0]), np.ones_like(h[0])
        Su, Sv = np.c_[one, z, h[0]], np.c_[z, one, h[1]]
        k = cross_curvature(Su, Sv, np.c_[z, z, h[2]], np.c_[z, z, h[3]], np.c_[z, z, h[4]], self.T, self.m)
        return relative_jump(k, self.k, self.kfloor)


def local_jet(side: HoleSide, t: Array, o: Array, R: Array, L: float) -> tuple[Array, Array, Array, Array, Array, Array]:
    """At ``t`` on a G2 side, in the local frame (units of ``L``): points, tangents, unit neighbour
    normals, the neighbour's gradient (m, 2) and Hessian (m, 3) as a height over the plane
    (:func:`.side_jets.graph_jet`) and its normal curvature across the side (signed by the normal)."""
    G, Gs, Gt, Gss, Gst, Gtt = side_jet(side, t)
    Gl = [(G - o) @ R / L] + [D @ R / L for D in (Gs, Gt, Gss, Gst, Gtt)]
    m = np.cross(Gl[2], Gl[1])  # as local_data: cross x tangent
    m /= np.maximum(np.linalg.norm(m, axis=1, keepdims=True), 1e-300)
    g, H = graph_jet(*Gl[1:])
    k = cross_curvature(Gl[1], Gl[2], Gl[3], Gl[4], Gl[5], Gl[1], m)
    return Gl[0], Gl[1], m, g, H, k


def curvature_rows(sides: list[HoleSide], g2: NDArray[np.bool_], ts: list[Array], ku: Array, kv: Array, p: int,
                    o: Array, R: Array, L: float, g2_tol: float, kfloor: float) -> tuple[Array, Array, Array]:
    """Least-squares rows ``(rows, columns, right-hand side)`` asking the plate's Hessian at the G2
    sides' samples to be the neighbour's (as heights over the plane): ``h_xx``, ``sqrt 2 h_xy``,
    ``h_yy``, each weighted so that a residual of 1 is about the target jump of the curvature
    (``g2_tol`` of the neighbour's curvature across the side, at least ``kfloor``; in a graph the
    normal curvature in any direction changes by at most the Hessian's change)."""
    rows, cols, rhs = [], [], []
    for i in np.flatnonzero(g2):
        X, _, _, _, H, k = local_jet(sides[i], ts[i], o, R, L)
        _, _, _, duu, duv, dvv, cl = basis_rows2(ku, kv, p, X[:, 0], X[:, 1])
        w = 1.0 / (g2_tol * np.maximum(np.abs(k), kfloor))
        r2 = np.sqrt(2.0)
        rows += [duu * w[:, None], duv * (r2 * w)[:, None], dvv * w[:, None]]
        cols += [cl, cl, cl]
        rhs += [H[:, 0] * w, r2 * H[:, 1] * w, H[:, 2] * w]
    return np.vstack(rows), np.vstack(cols), np.concatenate(rhs)


def corner_g2(sides: list[HoleSide], g2: NDArray[np.bool_], o: Array, R: Array, L: float, kfloor: float) -> Array:
    """:attr:`PlateFill.corner_g2`: the two G2 neighbours' Hessians (heights over the plane) at each
    corner, their relative difference (Frobenius; ``kfloor`` the least scale)."""
    out = np.full(len(sides), np.nan)
    for i in np.flatnonzero(g2 & np.roll(g2, -1)):
        a, b = sides[i], sides[(i + 1) % len(sides)]
        Ha = local_jet(a, np.array([a.curve.domain[1]]), o, R, L)[4][0]
        Hb = local_jet(b, np.array([b.curve.domain[0]]), o, R, L)[4][0]
        norm = lambda H: float(np.sqrt(H[0] ** 2 + 2 * H[1] ** 2 + H[2] ** 2))  # noqa: E731
        out[i] = norm(Ha - Hb) / max(norm(Ha), norm(Hb), kfloor)
    return out


def local_data(side: HoleSide, t: Array, o: Array, R: Array, L: float) -> tuple[Array, Array]:
    """Boundary points (local frame, units of ``L``) and neighbour normals (local frame) at ``t``."""
    P, T, X = side_samples(side, t)
    m = np.cross(X, T)
    m /= np.maximum(np.linalg.norm(m, axis=1, keepdims=True), 1e-300)
    return (P - o) @ R / L, m @ R
