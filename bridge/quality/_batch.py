"""Many faces (and p-curves) evaluated in one vectorised pass: where the speed of the continuity
check comes from.

A model has hundreds of small B-spline faces and a thousand p-curves, each evaluated at a few dozen
points; calling a per-spline evaluator for each costs far more in Python overhead than in
arithmetic. Here the splines of one degree are stacked: their knot vectors are concatenated (the
Cox-de Boor recurrence, The NURBS Book A2.3, only reads the knots of a point's own span, so a span
index into the concatenation is all it needs), their homogeneous poles too, and every point of every
spline goes through one :func:`~occsurf.algorithms.kernel.basis.basis_derivatives` call per direction
and one gather + ``einsum``. Only the span search (``searchsorted``) runs per spline.

Rational and polynomial splines are evaluated alike in homogeneous form (weight 1 for polynomial
ones; the quotient rule (A4.4) then divides by exactly 1, so their values are unchanged).
Faces and p-curves with no spline form here (analytic, OCC-evaluated) are evaluated one by one
through their own evaluators. When numba is installed (and ``OCCSURF_NO_NUMBA`` unset), calls of at
least :data:`NUMBA_MIN_POINTS` points evaluate the B-spline faces with the compiled per-surface
kernel of :mod:`occsurf.algorithms._numba_kernels` instead (same values to ~1e-14, no gathers).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from occsurf.algorithms.kernel.basis import basis_derivatives
from occsurf.algorithms.kernel.rational import curve_quotient_rule, surface_quotient_rule

from ..conversion.occ_evaluators import PCurveEvaluator, SurfaceEvaluator

Array = NDArray[np.float64]
Index = NDArray[np.intp]

__all__ = ["SurfaceBatch", "CurveBatch"]


def _span_bounds(knots: Array, degree: int, n: int) -> tuple[int, int]:
    """First and last non-empty span of the domain (as ``find_span`` clips)."""
    last = int(np.searchsorted(knots, knots[n], side="left")) - 1
    first = int(np.searchsorted(knots, knots[degree], side="right")) - 1
    return first, last


class _Stack:
    """Knot vectors of one direction of several splines, concatenated, with per-spline offsets.

    Spans are found for all splines with one ``searchsorted``: each spline's knots are mapped
    affinely (domain onto ``[0, 1]``) and shifted into disjoint intervals of one sorted key array;
    the rounding of that map can misplace a parameter within ~1e-13 of a knot by a span (several
    across a repeated knot), so the span is then checked against the original knots and moved.
    """

    def __init__(self, knot_vectors: list[Array], degree: int, counts: list[int]) -> None:
        self.knots = np.concatenate(knot_vectors)
        self.degree = degree
        lengths = np.array([len(k) for k in knot_vectors], dtype=np.intp)
        self.offset = np.r_[0, np.cumsum(lengths)[:-1]].astype(np.intp)
        bounds = np.array([_span_bounds(k, degree, n) for k, n in zip(knot_vectors, counts)], dtype=np.intp)
        self.first, self.last = bounds[:, 0], bounds[:, 1]
        self.lo = np.array([k[degree] for k in knot_vectors])
        self.hi = np.array([k[n] for k, n in zip(knot_vectors, counts)])
        width = np.where(self.hi > self.lo, self.hi - self.lo, 1.0)
        norm = [(k - a) / w for k, a, w in zip(knot_vectors, self.lo, width)]
        lo_n = np.array([x[0] for x in norm])
        hi_n = np.array([x[-1] for x in norm])
        shift = np.r_[0.0, np.cumsum((hi_n - lo_n + 1.0)[:-1])] - lo_n
        self.width, self.shift = width, shift
        self.keys = np.concatenate([x + c for x, c in zip(norm, shift)])

    def spans(self, member: Index, x: Array) -> Index:
        """Local span index (``degree <= s <= n - 1``, as ``find_span``) of each parameter in its spline."""
        key = (x - self.lo[member]) / self.width[member] + self.shift[member]
        s = np.searchsorted(self.keys, key, side="right") - 1 - self.offset[member]
        first, last = self.first[member], self.last[member]
        s = np.clip(s, first, last)
        base = self.offset[member]
        for _ in range(self.degree + 2):  # across a repeated knot: at most its multiplicity steps
            down = (x < self.knots[base + s]) & (s > first)
            up = (x >= self.knots[base + s + 1]) & (s < last)
            if not (down.any() or up.any()):
                break
            s = s - down + up
        return s


class SurfaceBatch:
    """Partials of many faces at once: ``derivatives(fid, u, v, order)``.

    Parameters
    ----------
    evaluators : list of SurfaceEvaluator or None
        One per face (``None``: the face cannot be evaluated; its points come back NaN).
    """

    def __init__(self, evaluators: list[SurfaceEvaluator | None]) -> None:
        self.evaluators = evaluators
        n = len(evaluators)
        self.group = np.full(n, -1, dtype=np.intp)
        self.local = np.full(n, -1, dtype=np.intp)
        # the faces evaluated from their B-spline, and their splines
        self._splines = {f: ev.spline for f, ev in enumerate(evaluators) if ev is not None and ev.spline is not None}
        members: dict[tuple[int, int], list[int]] = {}
        for f, spline in self._splines.items():
            members.setdefault(spline.degree, []).append(f)
        self.groups: list[dict[str, Any]] = []
        self._kargs: dict[int, tuple] = {}
        self.dom = np.zeros((n, 4))
        self.per = np.zeros((n, 2), dtype=bool)
        for f, ev in enumerate(evaluators):
            if ev is not None and ev.spline is not None:
                (u0, u1), (v0, v1) = ev.spline.domain
                self.dom[f] = (u0, u1, v0, v1)
                self.per[f] = ev.periodic
        for g, ((p, q), faces) in enumerate(members.items()):
            splines = [self._splines[f] for f in faces]
            nu = [s.n_poles[0] for s in splines]
            nv = [s.n_poles[1] for s in splines]
            H = [self._homogeneous(s) for s in splines]
            self.groups.append({
                "p": p, "q": q,
                "U": _Stack([s.knots[0] for s in splines], p, nu),
                "V": _Stack([s.knots[1] for s in splines], q, nv),
                "nv": np.array(nv, dtype=np.intp),
                "H": np.concatenate(H),
                "H_off": np.cumsum([0] + [len(h) for h in H[:-1]]).astype(np.intp),
                "uper": self.per[faces, 0],
                "vper": self.per[faces, 1],
                "rational": any(s.weights is not None for s in splines),
            })
            self.group[faces] = g
            self.local[faces] = np.arange(len(faces))

    @staticmethod
    def _homogeneous(s: Any) -> Array:
        P = s.control_points.reshape(-1, s.control_points.shape[-1])
        if s.weights is None:
            return np.c_[P, np.ones(P.shape[0])]
        w = np.asarray(s.weights, dtype=float).reshape(-1)
        return np.c_[P * w[:, None], w]

    def derivatives(self, fid: Index, u: Array, v: Array, order: int) -> tuple[Array, dict[int, BaseException]]:
        """``D (m, order+1, order+1, 3)`` and the faces whose evaluation raised (their points NaN)."""
        grp = self.group[fid]
        # every row of a B-spline face is written below; only the others start as NaN
        D = np.empty((u.shape[0], order + 1, order + 1, 3))
        D[grp < 0] = np.nan
        errors: dict[int, BaseException] = {}
        if self.groups and _use_numba(u.shape[0]):
            self._numba(fid, u, v, order, grp, D)
        else:
            for g, G in enumerate(self.groups):
                sel = np.flatnonzero(grp == g)
                if sel.size:
                    D[sel] = self._group(G, self.local[fid[sel]], u[sel], v[sel], order)
        for f in np.unique(fid[grp < 0]):
            ev = self.evaluators[f]
            if ev is None:
                continue
            sel = np.flatnonzero(fid == f)
            try:
                D[sel] = ev.derivatives(u[sel], v[sel], order)
            except Exception as err:  # noqa: BLE001 - keep the other faces
                errors[int(f)] = err
        return D, errors

    def _numba(self, fid: Index, u: Array, v: Array, order: int, grp: Index, D: Array) -> None:
        """The B-spline faces through the compiled per-surface kernel of
        :mod:`occsurf.algorithms._numba_kernels` (one call per face; the NumPy stack is the fallback)."""
        from occsurf.algorithms import _numba_kernels as nk

        kernel = nk.kernel("surface_derivatives")
        sel = np.flatnonzero(grp >= 0)
        # the points sorted by face, so each face's parameters and results are contiguous slices
        # of one buffer (one gather and one scatter in all, not one per face)
        order_idx = sel[np.argsort(fid[sel], kind="stable")]
        fs = fid[order_idx]
        U = np.ascontiguousarray(_into(u[order_idx], self.dom[fs, 0], self.dom[fs, 1], self.per[fs, 0]))
        V = np.ascontiguousarray(_into(v[order_idx], self.dom[fs, 2], self.dom[fs, 3], self.per[fs, 1]))
        out = np.empty((order_idx.size, order + 1, order + 1, 3))
        bounds = np.r_[0, np.flatnonzero(np.diff(fs)) + 1, fs.size]
        for a, b in zip(bounds[:-1].tolist(), bounds[1:].tolist()):
            if a == b:
                continue
            f = int(fs[a])
            spline = self._splines[f]
            args = self._kargs.get(f)
            if args is None:  # span tables and read-only views built once per face
                args = self._kargs[f] = tuple(nk.readonly(x) for x in nk.surface_args(spline))
            if kernel is not None:
                try:
                    # u, v read-only as nk.run passes them: the signature the library compiles
                    # anyway (writable, they were a second compile of the kernel, ~4 s once)
                    kernel(*args, nk.readonly(U[a:b]), nk.readonly(V[a:b]), order, spline.is_rational, out[a:b])
                    continue
                except Exception:  # noqa: BLE001 - as nk.run: fall back to NumPy
                    kernel = None
            chunk = order_idx[a:b]
            G = self.groups[self.group[f]]
            out[a:b] = self._group(G, self.local[fid[chunk]], u[chunk], v[chunk], order)
        D[order_idx] = out

    @staticmethod
    def _group(G: dict[str, Any], k: Index, u: Array, v: Array, order: int) -> Array:
        p, q, U, V = G["p"], G["q"], G["U"], G["V"]
        u = _into(u, U.lo[k], U.hi[k], G["uper"][k])
        v = _into(v, V.lo[k], V.hi[k], G["vper"][k])
        su, sv = U.spans(k, u), V.spans(k, v)
        Du = basis_derivatives(U.knots, p, su + U.offset[k], u, order)
        Dv = basis_derivatives(V.knots, q, sv + V.offset[k], v, order)
        nv = G["nv"][k]
        rows = (su - p)[:, None] + np.arange(p + 1)
        cols = (sv - q)[:, None] + np.arange(q + 1)
        idx = G["H_off"][k][:, None, None] + rows[:, :, None] * nv[:, None, None] + cols[:, None, :]
        m, r = u.shape[0], order + 1
        tmp = np.matmul(Dv[:, None], G["H"][idx])  # (m, p+1, r, 4): contracted over v
        Hd = np.matmul(Du, tmp.reshape(m, p + 1, -1)).reshape(m, r, r, -1)  # then over u
        return surface_quotient_rule(Hd) if G["rational"] else Hd[..., :3]


#: Evaluations of at least this many points load numba (about 0.5 s the first time in a process,
#: from its cache) and use its compiled per-surface kernel; once loaded it is used for any size.
NUMBA_MIN_POINTS: int = 4096


def _use_numba(n: int) -> bool:
    from occsurf.algorithms import _numba_kernels as nk

    if not nk.enabled():
        return False
    if nk.loaded():
        return nk.load() is not None  # the kernels loaded before (no compiling): whatever n
    return n >= NUMBA_MIN_POINTS and nk.load() is not None


def _into(x: Array, lo: Array, hi: Array, periodic: NDArray[np.bool_]) -> Array:
    """Parameters into each spline's domain: by whole periods where periodic, else clipped."""
    inside = (x >= lo) & (x <= hi)
    wrapped = lo + np.mod(x - lo, hi - lo)
    return np.where(inside, x, np.where(periodic, wrapped, np.clip(x, lo, hi)))


class CurveBatch:
    """Many p-curves at once: ``evaluate(cid, t) -> (uv, duv)``; lines in closed form, B-splines stacked."""

    def __init__(self, curves: list[PCurveEvaluator | None]) -> None:
        self.curves = curves
        n = len(curves)
        self.is_line = np.array([c is not None and c.line is not None for c in curves], dtype=bool)
        self.origin = np.zeros((n, 2))
        self.direction = np.zeros((n, 2))
        for i, c in enumerate(curves):
            if c is not None and c.line is not None:
                self.origin[i], self.direction[i] = c.line
        self.group = np.full(n, -1, dtype=np.intp)
        self.local = np.full(n, -1, dtype=np.intp)
        # the p-curves evaluated from their B-spline, and their splines
        spline_of = {i: c.spline for i, c in enumerate(curves) if c is not None and c.spline is not None}
        members: dict[int, list[int]] = {}
        for i, spline in spline_of.items():
            members.setdefault(spline.degree, []).append(i)
        self.groups: list[dict[str, Any]] = []
        for g, (p, ids) in enumerate(members.items()):
            splines = [spline_of[i] for i in ids]
            H = [np.c_[s.control_points * (1.0 if s.weights is None else s.weights[:, None]),
                       np.ones(s.n_poles) if s.weights is None else s.weights] for s in splines]
            self.groups.append({"p": p, "T": _Stack([s.knots for s in splines], p, [s.n_poles for s in splines]),
                                "H": np.concatenate(H), "rational": any(s.weights is not None for s in splines),
                                "H_off": np.cumsum([0] + [len(h) for h in H[:-1]]).astype(np.intp)})
            self.group[ids] = g
            self.local[ids] = np.arange(len(ids))

    def evaluate(self, cid: Index, t: Array) -> tuple[Array, Array]:
        uv = np.full((t.shape[0], 2), np.nan)
        duv = np.full((t.shape[0], 2), np.nan)
        line = self.is_line[cid]
        if line.any():
            c = cid[line]
            uv[line] = self.origin[c] + t[line, None] * self.direction[c]
            duv[line] = self.direction[c]
        grp = self.group[cid]
        for g, G in enumerate(self.groups):
            sel = np.flatnonzero(grp == g)
            if sel.size == 0:
                continue
            k, T, p = self.local[cid[sel]], G["T"], G["p"]
            x = np.clip(t[sel], T.lo[k], T.hi[k])
            s = T.spans(k, x)
            Dn = basis_derivatives(T.knots, p, s + T.offset[k], x, 1)
            idx = G["H_off"][k][:, None] + (s - p)[:, None] + np.arange(p + 1)
            Hd = np.matmul(Dn, G["H"][idx])
            Hd = curve_quotient_rule(Hd) if G["rational"] else Hd[..., :2]
            uv[sel], duv[sel] = Hd[:, 0], Hd[:, 1]
        other = ~line & (grp < 0)
        for i in np.unique(cid[other]):
            c = self.curves[i]
            if c is None:
                continue
            sel = np.flatnonzero(cid == i)
            uv[sel], duv[sel] = c(t[sel])
        return uv, duv
