"""The measures of :mod:`.continuity` at points of edges: G0, G1, cross curvature (G2) and its
derivative (G3), OCC's curvature-gap formula, and the engine that evaluates them for all edges of a
model at once (both faces through :mod:`._batch`, the projections onto matched edges or faces).

See :mod:`.continuity` for the definitions; this module holds the arithmetic.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..messages import one_line
from ._batch import NUMBA_MIN_POINTS, CurveBatch, SurfaceBatch
from ._pairs import FaceData, Pair

Array = NDArray[np.float64]

__all__ = ["Engine", "occ_gap", "occ_fold", "PROJECTION_ITERATIONS", "MEASURE_BLOCK"]

#: Gauss-Newton steps when projecting onto the other edge of a geometrically matched pair: from
#: the matching table (9 points per edge) for the dense samples, then from the dense samples'
#: table for the worst-point search (Gauss-Newton converges quadratically for the zero or tiny
#: residuals of matched edges).
PROJECTION_ITERATIONS: tuple[int, int] = (4, 2)

#: Requests per block of :meth:`Engine.measure` (at most). A model's dense samples (every edge's at
#: once) are measured in about equal blocks of whole edges, so that both faces' partials (27 or 48
#: floats a point and side) and the arithmetic on them take tens of MB, not hundreds: on the
#: 1089-face plate of ``benchmarks/bench_check.py`` (2026-12-07) the one batch raised the check's
#: peak memory by about 125 MB. Every measure is pointwise, so a block changes at most a last digit
#: (where NumPy's vectorised loops take an array's tail element by element): at this block the reports
#: and samples of the four realdata models and the plate were bit for bit those of one batch; the test
#: takes blocks of 7 requests and asserts 1e-12 relative. At least 2 x ``_batch.NUMBA_MIN_POINTS``,
#: so that the blocks (over half of this) take the compiled evaluation as one batch does.
MEASURE_BLOCK = 16384


# ======================================================================================= measures
def _normalize(a: Array) -> tuple[Array, Array]:
    n = np.linalg.norm(a, axis=-1)
    with np.errstate(invalid="ignore", divide="ignore"):
        return a / n[..., None], n


def _dot(a: Array, b: Array) -> Array:
    return np.einsum("...i,...i->...", a, b)


def _section(D: Array, n: Array, T: Array, third: bool) -> tuple[Array, Array]:
    """Cross curvature ``h''(0)`` and its derivative ``h'''(0)`` of the normal section across ``T``.

    ``D (m, r+1, r+1, 3)`` partials, ``n`` oriented unit normals, ``T`` unit edge tangents.
    """
    b = _unit(_cross(n, T))
    Tk = _cross(b, n)
    Su, Sv = D[:, 1, 0], D[:, 0, 1]
    j11, j12, j21, j22 = _dot(Tk, Su), _dot(Tk, Sv), _dot(b, Su), _dot(b, Sv)
    with np.errstate(invalid="ignore", divide="ignore"):
        inv_det = 1.0 / (j11 * j22 - j12 * j21)
    x1, y1 = (-j12 * inv_det)[:, None], (j11 * inv_det)[:, None]  # w1 = J^{-1} (0, 1)
    Suu, Suv, Svv = D[:, 2, 0], D[:, 1, 1], D[:, 0, 2]
    Q2 = Suu * (x1 * x1) + Suv * (2.0 * x1 * y1) + Svv * (y1 * y1)
    k = _dot(n, Q2)
    if not third:
        return k, np.full_like(k, np.nan)
    r1, r2 = _dot(Tk, Q2), _dot(b, Q2)  # w2 = -J^{-1} (r1, r2)
    x2 = (-(j22 * r1 - j12 * r2) * inv_det)[:, None]
    y2 = (-(-j21 * r1 + j11 * r2) * inv_det)[:, None]
    B = Suu * (x1 * x2) + Suv * (x1 * y2 + y1 * x2) + Svv * (y1 * y2)
    D3 = D[:, 3, 0] * x1**3 + 3 * D[:, 2, 1] * x1**2 * y1 + 3 * D[:, 1, 2] * x1 * y1**2 + D[:, 0, 3] * y1**3
    return k, _dot(n, 3.0 * B + D3)


def _principal(D: Array) -> tuple[Array, Array, Array]:
    """Principal curvatures ``kmax >= kmin`` (against ``S_u x S_v``, as ``GeomLProp``) and the
    component-wise mean of their directions' absolute values, ``(|dmin| + |dmax|) / 2``, normalised.

    The shape operator in the orthonormal tangent frame ``e1 = S_u / |S_u|``, ``e2 = n x e1`` is
    ``[[a, b], [b, c]]``; its eigenvectors are at the angle ``theta = atan2(2 b, a - c) / 2``.
    """
    Su, Sv = D[:, 1, 0], D[:, 0, 1]
    n = _unit(_cross(Su, Sv))
    e1 = _unit(Su)
    e2 = _cross(n, e1)
    L, M, N = _dot(D[:, 2, 0], n), _dot(D[:, 1, 1], n), _dot(D[:, 0, 2], n)
    a11 = np.sqrt(_dot(Su, Su))
    a12, a22 = _dot(Sv, e1), _dot(Sv, e2)
    with np.errstate(invalid="ignore", divide="ignore"):
        i11, i12, i22 = 1.0 / a11, -a12 / (a11 * a22), 1.0 / a22
        a = L * i11 * i11
        b = i11 * (L * i12 + M * i22)
        c = i12 * (L * i12 + 2.0 * M * i22) + N * i22 * i22
    half, rad = 0.5 * (a + c), np.hypot(0.5 * (a - c), b)
    theta = 0.5 * np.arctan2(2.0 * b, a - c)
    ct, st = np.abs(np.cos(theta))[:, None], np.abs(np.sin(theta))[:, None]
    # |d1| + |d2| component-wise, d1 = cos e1 + sin e2, d2 = n x d1 = -sin e1 + cos e2
    d1 = ct * e1 * np.sign(np.cos(theta))[:, None] + st * e2 * np.sign(np.sin(theta))[:, None]
    d2 = _cross(n, d1)
    return half + rad, half - rad, _unit(np.abs(d1) + np.abs(d2))


#: The partials the measures read, in the order of :func:`_components`: S, S_u, S_v, S_uu, S_uv, S_vv.
_PARTIALS = ((0, 0), (1, 0), (0, 1), (2, 0), (1, 1), (0, 2))


def _components(D: Array) -> Array:
    """The partials of :data:`_PARTIALS` of ``D (m, r, r, 3)`` as ``(6, 3, m)``: each coordinate of
    each partial one contiguous row (a column gather, then a 2-D transpose: NumPy copies a 4-D
    transpose of the same data some 30 times slower)."""
    m, r = D.shape[0], D.shape[1]
    cols = [(i * r + j) * 3 + c for i, j in _PARTIALS for c in range(3)]
    return np.ascontiguousarray(D.reshape(m, -1)[:, cols].T).reshape(len(_PARTIALS), 3, m)


def _dot3(a: Array, b: Array) -> Array:
    """Dot products of component-major vectors ``(3, m)``."""
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _cross3(a: Array, b: Array) -> Array:
    """Cross products of component-major vectors ``(3, m)``."""
    return np.stack((a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]))


def _unit3(a: Array) -> Array:
    with np.errstate(invalid="ignore", divide="ignore"):
        a /= np.sqrt(_dot3(a, a))
    return a


def _cross_curvature(X: Array, n: Array, T: Array) -> Array:
    """:func:`_section`'s ``h''(0)`` on component-major partials ``X (6, 3, m)`` (:func:`_components`),
    normals and tangents ``(3, m)``: ``n . (S_uu x1^2 + 2 S_uv x1 y1 + S_vv y1^2)`` with
    ``(x1, y1) = J^{-1} (0, 1)``."""
    b = _unit3(_cross3(n, T))
    Tk = _cross3(b, n)
    Su, Sv = X[1], X[2]
    j11, j12, j21, j22 = _dot3(Tk, Su), _dot3(Tk, Sv), _dot3(b, Su), _dot3(b, Sv)
    with np.errstate(invalid="ignore", divide="ignore"):
        inv_det = 1.0 / (j11 * j22 - j12 * j21)
    x1, y1 = -j12 * inv_det, j11 * inv_det
    return _dot3(n, X[3]) * (x1 * x1) + _dot3(n, X[4]) * (2.0 * x1 * y1) + _dot3(n, X[5]) * (y1 * y1)


def _cross(a: Array, b: Array) -> Array:
    out = np.empty_like(a)
    out[:, 0] = a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1]
    out[:, 1] = a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2]
    out[:, 2] = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
    return out


def _unit(a: Array) -> Array:
    with np.errstate(invalid="ignore", divide="ignore"):
        return a / np.sqrt(_dot(a, a))[:, None]


def occ_gap(D1: Array, D2: Array) -> Array:
    """OCC's ``LocalAnalysis_SurfaceContinuity::G2CurvatureGap`` from our partials (OCCT 7.9 formula).

    With principal curvatures ``kmax, kmin`` (signs against ``S_u x S_v``, as ``GeomLProp``),
    ``eta = (kmin + kmax) / 2``, ``zeta = (kmax - kmin) / 2`` and ``alpha`` the angle between the
    directions ``(|dmin| + |dmax|) / 2`` (component-wise) of the two sides::

        gap = |eta_1 - eta_2| / 2 + sqrt(((zeta_1 - zeta_2) / 2)^2 cos^2 alpha + zeta^2 sin^2 alpha)

    with ``zeta = (zeta_1 + zeta_2) / 2``. At an umbilic the directions, and so ``alpha``, are
    arbitrary (OCC's and ours may differ there).
    """
    a1, b1, mcd1 = _principal(D1)
    a2, b2, mcd2 = _principal(D2)
    c = _cross(mcd1, mcd2)
    alpha = np.arctan2(np.sqrt(_dot(c, c)), _dot(mcd1, mcd2))
    eta1, eta2 = (a1 + b1) / 2, (a2 + b2) / 2
    zeta1, zeta2 = (a1 - b1) / 2, (a2 - b2) / 2
    zeta = (zeta1 + zeta2) / 2
    return np.abs(eta1 - eta2) / 2 + np.sqrt(((zeta1 - zeta2) / 2) ** 2 * np.cos(alpha) ** 2
                                             + zeta**2 * np.sin(alpha) ** 2)


def occ_fold(angle_deg: Array | float) -> Array:
    """Our G1 angle as OCC's ``G1Angle`` reports it: folded into [0, 90] degrees."""
    a = np.asarray(angle_deg, dtype=float)
    return np.where(a > 90.0, 180.0 - a, a)


# ======================================================================================= engine
class Engine:
    """Evaluates the measures at ``(pair, t)`` requests, all pairs and faces at once (:mod:`._batch`)."""

    def __init__(self, faces: list[FaceData], pairs: list[Pair], third: bool, floor: float, surfaces: SurfaceBatch) -> None:

        self.faces, self.pairs, self.third, self.floor = faces, pairs, third, floor
        self.order = 3 if third else 2
        self.flip = np.ones(len(pairs))
        self.face_errors: dict[int, str] = {}
        self.evaluated = np.zeros(len(pairs), dtype=int)
        self.surfaces = surfaces
        # p-curve 2 k is side 1 of pair k, 2 k + 1 its side 2
        self.curves = CurveBatch([c for p in pairs for c in (p.side1.pcurve, p.side2.pcurve)])
        self.f1 = np.array([p.side1.face for p in pairs], dtype=np.intp)
        self.f2 = np.array([p.side2.face for p in pairs], dtype=np.intp)
        self.sense1 = np.array([p.side1.sense for p in pairs], dtype=float)
        self.sense2 = np.array([p.side2.sense for p in pairs], dtype=float)
        self.geo = np.array([p.matched == "geometry" for p in pairs], dtype=bool)
        self.seam = np.array([p.seam for p in pairs], dtype=bool)
        orient = np.array([-1.0 if f.reversed else 1.0 for f in faces])
        self.o1 = orient[self.f1] if pairs else np.zeros(0)
        self.o2 = orient[self.f2] if pairs else np.zeros(0)
        big = [(p.side2.pcurve.first, p.side2.pcurve.last) if p.side2.pcurve is not None else (0.0, 1.0) for p in pairs]
        self.lo2 = np.array([b[0] for b in big])
        self.hi2 = np.array([b[1] for b in big])
        # side 2 without a p-curve: its (u, v) by projecting side 1's points onto its surface
        self.on_surface = np.array([p.side2.pcurve is None and p.matched == "topology" for p in pairs], dtype=bool)
        self._grids: dict[int, tuple[Array, Array]] = {}

    # -------------------------------------------------------------------------- batches
    def _surfaces(self, fid: NDArray[np.intp], uv: Array, order: int) -> Array:
        D, errors = self.surfaces.derivatives(fid, uv[:, 0], uv[:, 1], order)
        for f, err in errors.items():
            self.face_errors.setdefault(f, f"face {f} could not be evaluated: {one_line(err)}")
        return D

    def _project(self, pid: NDArray[np.intp], t: Array, X: Array, iterations: int) -> Array:
        """Side-2 parameters of geometry pairs: Gauss-Newton onto the other edge, all pairs at once."""
        s = np.empty_like(t)
        for p in np.unique(pid):
            sel = pid == p
            pr = self.pairs[p]
            s[sel] = np.interp(t[sel], pr.t_table, pr.s_table)
        fid, lo, hi, cid = self.f2[pid], self.lo2[pid], self.hi2[pid], 2 * pid + 1
        for _ in range(iterations):
            uv, duv = self.curves.evaluate(cid, s)
            D = self._surfaces(fid, uv, 1)
            dC = D[:, 1, 0] * duv[:, :1] + D[:, 0, 1] * duv[:, 1:]
            den = _dot(dC, dC)
            ok = np.isfinite(den) & (den > 0)
            step = np.where(ok, -_dot(dC, D[:, 0, 0] - X) / np.where(ok, den, 1.0), 0.0)
            s = np.clip(s + step, lo, hi)
        return s

    def _grid(self, f: int) -> tuple[Array, Array]:
        """A 17 x 17 grid of the face's UV box and its points: starting points of projections."""
        if f not in self._grids:
            from OCP.BRepTools import BRepTools

            u0, u1, v0, v1 = BRepTools.UVBounds_s(self.faces[f].face)
            uu, vv = np.meshgrid(np.linspace(u0, u1, 17), np.linspace(v0, v1, 17), indexing="ij")
            uv = np.c_[uu.ravel(), vv.ravel()]
            D = self._surfaces(np.full(uv.shape[0], f, dtype=np.intp), uv, 0)
            self._grids[f] = (uv, D[:, 0, 0])
        return self._grids[f]

    def _project_surface(self, fid: NDArray[np.intp], X: Array) -> Array:
        """``(u, v)`` of the feet of points ``X`` on faces ``fid``: nearest grid point, then
        Gauss-Newton steps ``(J^T J) d = -J^T (S - X)`` within the face's UV box."""
        uv = np.empty((X.shape[0], 2))
        lo, hi = np.empty((X.shape[0], 2)), np.empty((X.shape[0], 2))
        for f in np.unique(fid):
            sel = fid == f
            g_uv, g_P = self._grid(int(f))
            d2 = ((X[sel][:, None, :] - g_P[None]) ** 2).sum(axis=2)
            uv[sel] = g_uv[np.nanargmin(np.nan_to_num(d2, nan=np.inf), axis=1)]
            lo[sel], hi[sel] = g_uv.min(axis=0), g_uv.max(axis=0)
        for _ in range(PROJECTION_ITERATIONS[0] * 2):
            D = self._surfaces(fid, uv, 1)
            Su, Sv, f = D[:, 1, 0], D[:, 0, 1], D[:, 0, 0] - X
            a, b, c = _dot(Su, Su), _dot(Su, Sv), _dot(Sv, Sv)
            r1, r2 = _dot(Su, f), _dot(Sv, f)
            det = a * c - b * b
            ok = np.isfinite(det) & (det > 0)
            det = np.where(ok, det, 1.0)
            step = np.stack([np.where(ok, -(c * r1 - b * r2) / det, 0.0), np.where(ok, -(a * r2 - b * r1) / det, 0.0)], -1)
            uv = np.clip(uv + step, lo, hi)
        return uv

    # -------------------------------------------------------------------------- measures
    def measure(self, pid: NDArray[np.intp], t: Array, set_flip: bool = False, s: Array | None = None,
                gap: bool = False) -> dict[str, Array]:
        """All measures at the requests ``(pid[m], t[m])``: arrays of shape ``(m,)`` (points ``(m, 3)``),
        and the parameters used: ``'uv1'``, ``'uv2'`` ``(m, 2)``, ``'s'`` (side 2's edge parameter).

        More than :data:`MEASURE_BLOCK` requests are measured in blocks of whole runs of one pair
        (every measure is pointwise: the same values to round-off, see there), each written into
        the outputs as it is done (a block's arrays, views of its partials among them, are freed
        before the next). ``set_flip`` takes each geometry pair's orientation from all its
        requests: they must then be one run per pair, as the dense samples are (else one block).
        Where a face fails to evaluate in one block only, its message is that block's (the edge's
        report is degenerate either way)."""
        if set_flip:
            self._reset_flip()
        m = pid.shape[0]
        if s is not None:
            s = np.asarray(s, dtype=float)
            if s.shape != t.shape:
                raise ValueError(f"s: expected one side-2 parameter per request, shape {t.shape}, got {s.shape}")
        bounds = self._blocks(pid, set_flip)
        if len(bounds) <= 2:
            return self._measure(pid, t, set_flip, s, gap)
        out: dict[str, Array] = {}
        for a, b in zip(bounds[:-1], bounds[1:]):
            part = self._measure(pid[a:b], t[a:b], set_flip, None if s is None else s[a:b], gap)
            for k, v in part.items():
                if k not in out:
                    out[k] = np.empty((m,) + v.shape[1:], v.dtype)
                out[k][a:b] = v
            del part
        return out

    @staticmethod
    def _blocks(pid: NDArray[np.intp], set_flip: bool) -> list[int]:
        """Where :meth:`measure` splits its requests: about equal blocks of at most
        :data:`MEASURE_BLOCK`, cut where the pair changes; ``[0, m]`` (one block) for fewer, for a
        pair in several runs under ``set_flip``, or where a block would evaluate fewer than
        :data:`~._batch.NUMBA_MIN_POINTS` points (one batch takes the compiled evaluation there)."""
        m = pid.shape[0]
        runs = np.flatnonzero(pid[1:] != pid[:-1]) + 1
        if m <= MEASURE_BLOCK or runs.size == 0 or (set_flip and runs.size + 1 != np.unique(pid).size):
            return [0, m]  # few requests, one pair's only, or a pair in several runs
        n_blocks = -(-m // MEASURE_BLOCK)
        cuts = runs[np.minimum(np.searchsorted(runs, np.arange(1, n_blocks) * m // n_blocks), runs.size - 1)]
        bounds = [0] + sorted(set(int(c) for c in cuts) - {0, m}) + [m]
        if min(np.diff(bounds)) < NUMBA_MIN_POINTS:
            return [0, m]
        return bounds

    def _measure(self, pid: NDArray[np.intp], t: Array, set_flip: bool, s: Array | None, gap: bool) -> dict[str, Array]:
        """:meth:`measure` on one block."""
        self.evaluated += np.bincount(pid, minlength=len(self.pairs))
        m = pid.shape[0]
        geo, proj = self.geo[pid], self.on_surface[pid]
        given = s is not None  # side 2's parameters given (a benchmark giving OCC and us the same points)
        s = np.asarray(s, dtype=float) if given else t.copy()
        if (given or not geo.any()) and not proj.any():
            # side 2's (u, v) do not depend on side 1's points: both sides in one batch
            uv, duv = self.curves.evaluate(np.r_[2 * pid, 2 * pid + 1], np.r_[t, s])
            D = self._surfaces(np.r_[self.f1[pid], self.f2[pid]], uv, self.order)
            uv1, uv2, duv1, duv2, D1, D2 = uv[:m], uv[m:], duv[:m], duv[m:], D[:m], D[m:]
        else:
            uv1, duv1 = self.curves.evaluate(2 * pid, t)
            D1 = self._surfaces(self.f1[pid], uv1, self.order)
            if not given and geo.any():
                s[geo] = self._project(pid[geo], t[geo], D1[geo, 0, 0], PROJECTION_ITERATIONS[0 if set_flip else 1])
            uv2, duv2 = self.curves.evaluate(2 * pid + 1, s)
            if proj.any():
                uv2[proj] = self._project_surface(self.f2[pid[proj]], D1[proj, 0, 0])
            D2 = self._surfaces(self.f2[pid], uv2, self.order)
        # the arithmetic on components (structure of arrays): every product below runs on contiguous
        # (m,) rows instead of strided (m, 3) columns
        X1, X2 = _components(D1), _components(D2)
        T = _unit3(X1[1] * duv1[:, 0] + X1[2] * duv1[:, 1])
        n1 = _unit3(_cross3(X1[1], X1[2]))
        n2 = _unit3(_cross3(X2[1], X2[2]))
        if set_flip:
            T2 = X2[1] * duv2[:, 0] + X2[2] * duv2[:, 1]
            self._set_flip(pid, self.sense1[pid] * _dot3(T, T2) * self.sense2[pid])
        n1 *= self.o1[pid]
        n2 *= self.o2[pid] * self.flip[pid]
        c12 = _cross3(n1, n2)
        g1 = np.degrees(np.arctan2(np.sqrt(_dot3(c12, c12)), _dot3(n1, n2)))
        k1, k2 = _cross_curvature(X1, n1, T), _cross_curvature(X2, n2, T)
        if self.third:
            dk1 = _section(D1, n1.T, T.T, True)[1]
            dk2 = _section(D2, n2.T, T.T, True)[1]
        else:
            dk1 = dk2 = np.full_like(k1, np.nan)
        g2 = np.abs(k1 - k2)
        big = np.maximum(np.abs(k1), np.abs(k2))
        with np.errstate(invalid="ignore", divide="ignore"):
            rel = np.where(big > self.floor, 100.0 * g2 / np.where(big > 0, big, 1.0), np.where(np.isnan(big), np.nan, 0.0))
        d12 = X1[0] - X2[0]
        return {"g0": np.sqrt(_dot3(d12, d12)), "g1": g1, "g2": g2, "g2_rel": rel,
                "g3": np.abs(dk1 - dk2), "gap": occ_gap(D1, D2) if gap else np.full_like(g2, np.nan),
                "P": D1[:, 0, 0], "uv1": uv1, "uv2": uv2, "s": s}

    def _reset_flip(self) -> None:
        """Orientation agreement per pair: a shell's faces run along a shared edge in opposite senses.
        Topology pairs: the senses of the edge in the two faces; geometry pairs: 1 until
        :meth:`_set_flip` compares their tangents."""
        topo = ~self.geo
        self.flip = np.where(topo & ~self.seam & (self.sense1 == self.sense2), -1.0, 1.0)

    def _set_flip(self, pid: NDArray[np.intp], along: Array) -> None:
        """The orientation agreement of the geometry pairs among ``pid``, by the median sign of the
        dot products ``along`` of their tangents at these requests."""
        for p in np.unique(pid[self.geo[pid]]):
            d = along[pid == p]
            d = d[np.isfinite(d)]
            self.flip[p] = -1.0 if d.size and np.median(d) > 0 else 1.0


