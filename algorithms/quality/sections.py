"""Section cuts (course ch. 9): families of parallel planes and of planes through an axis cut
through a set of faces, with the exact curvature comb of every cut.

Algorithm
---------
1. **Seed** (per face, all planes at once): the signed distance ``h_k(u, v) = (S(u, v) - o_k) . n_k``
   on a parameter grid; vectorised marching squares gives oriented segments between grid-edge
   crossings (saddle cells resolved by the bilinear centre value; positive side on the left).
2. **Refine** every crossing on its grid edge (an iso-parameter segment along which ``h`` changes
   sign, so the root is bracketed) by Newton's method safeguarded with bisection, on the exact
   surface, until ``|h| <= QUALITY_SECTION_TOL * size``. Inflection brackets are refined with the
   minimal-norm Newton step ``-h grad h / |grad h|^2`` (``grad h = (S_u . n, S_v . n)``).
3. **Chain** the oriented segments into polylines by pointer doubling (``log2`` NumPy steps, no
   per-point loop), then join polylines of neighbouring faces whose ends are within
   ``QUALITY_CHAIN_TOL * size``.
4. **Curvature** of the exact intersection curve at every point (Meusnier): with the surface normal
   ``n_s``, the curve tangent ``t = m x n_s / |m x n_s|`` and the in-plane normal ``N_c = m x t``,

   .. math:: \\kappa_s = \\frac{II(t)}{I(t)} \\Big/ (N_c \\cdot n_s),

   signed in the plane; inflections (sign changes of ``kappa_s``) are located by Illinois regula
   falsi on the exact surface to ``QUALITY_INFLECTION_TOL`` of the parameter range.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import tolerances
from ..errors import InvalidGeometryError
from ..hierarchical.surface import HierarchicalSurface
from ..kernel.curve import BSplineCurve
from ..kernel.surface import BSplineSurface
from ._common import Array, dot, positive, unit_vectors, vectors
from .combs import Comb, _finish
from .section_cuts import (
    Face,
    Ints,
    cut_curvature,
    edge_ends,
    march,
    on_edge,
    order_chains,
    refine_inflections,
    tangent_hints,
    to_trim,
)

__all__ = ["Section", "SectionCurve", "plane_sections", "axial_sections"]

MaskFn = Callable[[Array, Array], NDArray[np.bool_]]
#: A face as given: the surface or ``(surface, mask)``.
SectionFace = Face | tuple[Face, MaskFn | None]


@dataclass(frozen=True)
class SectionCurve:
    """One connected piece of a section: a polyline on the exact intersection.

    Attributes
    ----------
    points : ndarray, shape (k, 3)
        On the surfaces and within the section tolerance of the plane.
    uv : ndarray, shape (k, 2)
        Parameters on ``faces[face[i]]``.
    face : ndarray of int, shape (k,)
        Face index of each point (a chain crosses face boundaries).
    closed : bool
    curvature : ndarray, shape (k,)
        Signed curvature of the intersection curve in the plane (exact, from the surface's second
        derivatives); NaN where the surface is tangent to the plane.
    comb : Comb
        The curvature comb (``params`` is the chord length along the polyline).
    inflection_points : ndarray, shape (j, 3)
        Sign changes of ``curvature``, refined on the exact surface.
    spline : BSplineCurve or None
        A cubic fit through the points (``fit=True``).
    """

    points: Array
    uv: Array
    face: NDArray[np.intp]
    closed: bool
    curvature: Array
    comb: Comb
    inflection_points: Array
    spline: BSplineCurve | None = None


@dataclass(frozen=True)
class Section:
    """All curves of one cutting plane ``{x : (x - origin)·normal = 0}``.

    Attributes
    ----------
    origin, normal : ndarray, shape (3,)
    offset : float
        Offset along ``normal`` from the family's origin (parallel sections) or the angle in
        radians (axial sections).
    curves : list of SectionCurve
    n_unconverged : int
        Seed points dropped because Newton did not reach the tolerance (reported, never hidden).
    """

    origin: Array
    normal: Array
    offset: float
    curves: list[SectionCurve] = field(default_factory=list)
    n_unconverged: int = 0

    @property
    def combs(self) -> list[Comb]:
        return [c.comb for c in self.curves]

    @property
    def inflection_points(self) -> Array:
        pts = [c.inflection_points for c in self.curves]
        return np.concatenate(pts) if pts else np.empty((0, 3))

    @property
    def n_inflections(self) -> int:
        return int(self.inflection_points.shape[0])


# ----------------------------------------------------------------------------------- input checks
def _faces(faces: object) -> list[tuple[Face, MaskFn | None]]:
    if isinstance(faces, (BSplineSurface, HierarchicalSurface)) or not isinstance(faces, Sequence):
        raise InvalidGeometryError("faces: expected a list of surfaces or (surface, mask) pairs")
    out = []
    for i, f in enumerate(faces):
        s, m = (f if isinstance(f, tuple) else (f, None))
        if not isinstance(s, (BSplineSurface, HierarchicalSurface)) or s.dim != 3:
            raise InvalidGeometryError(f"faces[{i}]: expected a 3-D BSplineSurface or HierarchicalSurface, got {type(s).__name__}")
        if m is not None and not callable(m):
            raise InvalidGeometryError(f"faces[{i}]: the mask must be a callable mask(u, v) -> bool array")
        out.append((s, m))
    if not out:
        raise InvalidGeometryError("faces: expected at least one face")
    return out


def _grid(s: Face) -> tuple[Array, Array]:
    (u0, u1), (v0, v1) = s.domain
    base = s.base if isinstance(s, HierarchicalSurface) else s
    out = []
    for ax, (lo, hi) in enumerate(((u0, u1), (v0, v1))):
        p, t, n = base.degree[ax], base.knots[ax], base.n_poles[ax]
        spans = max(1, np.unique(t[p:n + 1]).size - 1)
        cells = max(int(tolerances.QUALITY_SECTION_GRID), int(tolerances.QUALITY_SECTION_CELLS_PER_SPAN) * spans)
        cells = min(cells, int(tolerances.QUALITY_SECTION_MAX_CELLS))
        out.append(np.linspace(lo, hi, cells + 1))
    return out[0], out[1]


# ------------------------------------------------------------------------------------ the driver
@dataclass
class _Piece:
    points: Array
    uv: Array
    face: Ints
    closed: bool


def _face_pieces(fi: int, s: Face, mask: MaskFn | None, O: Array, Nm: Array, half: Array | None,
                 tol_h: float) -> tuple[list[list[_Piece]], NDArray[np.int64]]:
    """Polylines of face ``fi`` for every plane, and the count of unconverged seeds per plane.

    Planes that miss the convex hull of the face's control net (the surface lies inside it for
    positive weights) are skipped without evaluating anything."""
    k = O.shape[0]
    pieces_all: list[list[_Piece]] = [[] for _ in range(k)]
    bad_all = np.zeros(k, np.int64)
    if isinstance(s, BSplineSurface):
        hp = s.control_points.reshape(-1, 3) @ Nm.T - np.einsum("kc,kc->k", O, Nm)
        active = np.flatnonzero((hp.min(axis=0) <= tol_h) & (hp.max(axis=0) >= -tol_h))
    else:
        active = np.arange(k)
    if active.size == 0:
        return pieces_all, bad_all
    pieces, bad = _face_pieces_of(fi, s, mask, O[active], Nm[active], None if half is None else half[active], tol_h)
    for j, i in enumerate(active):
        pieces_all[i] = pieces[j]
        bad_all[i] = bad[j]
    return pieces_all, bad_all


def _face_pieces_of(fi: int, s: Face, mask: MaskFn | None, O: Array, Nm: Array, half: Array | None,
                    tol_h: float) -> tuple[list[list[_Piece]], NDArray[np.int64]]:
    k = O.shape[0]
    us, vs = _grid(s)
    P = s.evaluate_grid(us, vs)
    h = np.einsum("abc,kc->kab", P, Nm) - np.einsum("kc,kc->k", O, Nm)[:, None, None]
    if mask is not None:
        inside = np.asarray(mask(*np.meshgrid(us, vs, indexing="ij")), bool)
        # cells with a corner inside the trim: their refined points are tested against the mask again
        cell_in = (inside[:-1, :-1] | inside[1:, :-1] | inside[1:, 1:] | inside[:-1, 1:]).ravel()
    pieces: list[list[_Piece]] = [[] for _ in range(k)]
    bad = np.zeros(k, np.int64)
    plane, src, dst, nu_e, cell = march(h)
    if mask is not None and plane.size:
        keep = cell_in[cell]
        plane, src, dst = plane[keep], src[keep], dst[keep]
    if plane.size == 0:
        return pieces, bad
    n_edges = nu_e + us.size * (vs.size - 1)
    ids, inv = np.unique(np.concatenate((plane * n_edges + src, plane * n_edges + dst)), return_inverse=True)
    node_plane, node_edge = ids // n_edges, ids % n_edges
    e0, e1, t0 = edge_ends(node_edge, node_plane, h, us, vs, nu_e)
    uv, conv = on_edge(s, e0, e1, t0, O[node_plane], Nm[node_plane], tol_h)
    keep_node = conv.copy()
    if mask is not None:
        keep_node &= np.asarray(mask(uv[:, 0], uv[:, 1]), bool)
    X = s.evaluate(uv[:, 0], uv[:, 1])
    if half is not None:
        keep_node &= dot(X - O[node_plane], half[node_plane]) >= -tol_h
    np.add.at(bad, node_plane[~conv], 1)
    a, b = inv[: src.size], inv[src.size:]
    ok = keep_node[a] & keep_node[b]
    cross = conv[a] & conv[b] & (keep_node[a] != keep_node[b])
    if np.any(cross):  # a segment leaving the trim: its outside end is moved onto the trim boundary
        ci = np.flatnonzero(cross)
        a_in = keep_node[a[ci]]
        inner, outer = np.where(a_in, a[ci], b[ci]), np.where(a_in, b[ci], a[ci])
        pl = node_plane[inner]

        def keep(uv_: Array, X_: Array, i: Ints) -> NDArray[np.bool_]:
            k = np.ones(uv_.shape[0], bool) if mask is None else np.asarray(mask(uv_[:, 0], uv_[:, 1]), bool)
            return k if half is None else k & (dot(X_ - O[pl[i]], half[pl[i]]) >= -tol_h)

        uv_end = to_trim(s, keep, uv[inner], uv[outer], O[pl], Nm[pl], tol_h)
        new = uv.shape[0] + np.arange(ci.size)
        uv = np.concatenate((uv, uv_end))
        X = np.concatenate((X, s.evaluate(uv_end[:, 0], uv_end[:, 1])))
        node_plane = np.concatenate((node_plane, pl))
        a, b = a.copy(), b.copy()
        a[ci], b[ci] = np.where(a_in, a[ci], new), np.where(a_in, new, b[ci])
        ok[ci] = True
    if not np.any(ok):
        return pieces, bad
    for nodes, closed in order_chains(a[ok], b[ok]):
        if nodes.size < 2:
            continue
        pieces[int(node_plane[nodes[0]])].append(_Piece(X[nodes], uv[nodes], np.full(nodes.size, fi), closed))
    return pieces, bad


def _join(pieces: list[_Piece], tol: float) -> list[_Piece]:
    """Join open polylines (of different faces) whose ends coincide within ``tol``; a loop over
    polylines (a handful per plane), never over points."""
    open_ = [p for p in pieces if not p.closed]
    done = [p for p in pieces if p.closed]
    while open_:
        cur = open_.pop()
        grown = True
        while grown:
            grown = False
            for i, q in enumerate(open_):
                ends = [(cur.points[-1], q.points[0], False, False), (cur.points[-1], q.points[-1], False, True),
                        (cur.points[0], q.points[-1], True, False), (cur.points[0], q.points[0], True, True)]
                for e1, e2, prepend, rev in ends:
                    if np.linalg.norm(e1 - e2) <= tol:
                        qq = _Piece(q.points[::-1], q.uv[::-1], q.face[::-1], False) if rev else q
                        parts = (qq, cur) if prepend else (cur, qq)
                        cur = _Piece(np.concatenate((parts[0].points, parts[1].points[1:])),
                                     np.concatenate((parts[0].uv, parts[1].uv[1:])),
                                     np.concatenate((parts[0].face, parts[1].face[1:])), False)
                        open_.pop(i)
                        grown = True
                        break
                if grown:
                    break
        if cur.points.shape[0] > 2 and np.linalg.norm(cur.points[0] - cur.points[-1]) <= tol:
            cur = _Piece(cur.points[:-1], cur.uv[:-1], cur.face[:-1], True)
        done.append(cur)
    return done


@dataclass
class _Curve:
    """A joined polyline of one plane with its exact curvature, before its inflections are refined."""

    plane: int
    points: Array
    uv: Array
    face: Ints
    closed: bool
    ks: Array
    tangent: Array
    hint: Array
    brackets: tuple[Ints, Ints]  # sample pairs (cur, nxt) on one face with opposite curvature signs
    inflections: list[Array] = field(default_factory=list)


def _curve(plane: int, piece: _Piece, faces: list[tuple[Face, MaskFn | None]], m: Array, size: float,
           tol_h: float) -> _Curve:
    P, uv, face = piece.points, piece.uv, piece.face
    # a crossing through a grid vertex is found on two grid edges: keep one of coincident points
    keep = np.r_[True, np.linalg.norm(np.diff(P, axis=0), axis=1) > 100 * tol_h]
    P, uv, face = P[keep], uv[keep], face[keep]
    hint = tangent_hints(P, piece.closed)
    ks = np.empty(P.shape[0])
    T = np.empty_like(P)
    for fi in np.unique(face):  # one vectorised evaluation per face
        sel = face == fi
        ks[sel], T[sel], _ = cut_curvature(faces[fi][0], uv[sel], m, hint[sel])
    nxt = np.roll(np.arange(P.shape[0]), -1) if piece.closed else np.arange(1, P.shape[0])
    cur = np.arange(nxt.size)
    zero = tolerances.QUALITY_WIGGLE_CURVATURE / max(size, np.finfo(float).tiny) * 1e-3
    sc = np.sign(np.where(np.abs(ks) > zero, ks, 0.0))
    br = np.flatnonzero(sc[cur] * sc[nxt] < 0)
    same = face[cur[br]] == face[nxt[br]]
    c = _Curve(plane, P, uv, face, piece.closed, ks, T, hint, (cur[br[same]], nxt[br[same]]))
    cross = br[~same]
    if cross.size:  # a sign change across a face boundary (a G2 break): linear interpolation
        w = ks[cur[cross]] / (ks[cur[cross]] - ks[nxt[cross]])
        c.inflections.append(P[cur[cross]] + w[:, None] * (P[nxt[cross]] - P[cur[cross]]))
    return c


def _refine_all(curves: list[_Curve], faces: list[tuple[Face, MaskFn | None]], O: Array, Nm: Array, tol_h: float) -> None:
    """Refine the inflection brackets of every curve of every plane, one batch per face."""
    rows = [(ci, fi, a, b) for ci, c in enumerate(curves) for fi in np.unique(c.face[c.brackets[0]])
            for a, b in [(c.brackets[0][c.face[c.brackets[0]] == fi], c.brackets[1][c.face[c.brackets[0]] == fi])]]
    for fi in {r[1] for r in rows}:
        mine = [r for r in rows if r[1] == fi]
        s = faces[fi][0]
        (u0, u1), (v0, v1) = s.domain
        cat = lambda f: np.concatenate([f(curves[ci], a, b) for ci, _, a, b in mine])  # noqa: E731, B023 - used in this iteration only
        owner = np.concatenate([np.full(a.size, ci) for ci, _, a, _b in mine])
        X = refine_inflections(
            s, cat(lambda c, a, b: c.uv[a]), cat(lambda c, a, b: c.uv[b]), cat(lambda c, a, b: c.ks[a]),
            cat(lambda c, a, b: c.ks[b]), cat(lambda c, a, b: np.broadcast_to(O[c.plane], (a.size, 3))),
            cat(lambda c, a, b: np.broadcast_to(Nm[c.plane], (a.size, 3))), cat(lambda c, a, b: c.hint[a]),
            tolerances.QUALITY_INFLECTION_TOL * max(u1 - u0, v1 - v0), tol_h)
        for ci in np.unique(owner):
            curves[ci].inflections.append(X[owner == ci])


def _section_curve(c: _Curve, m: Array, fit: bool, scale: float | None) -> SectionCurve:
    P = c.points
    infl_p = np.concatenate(c.inflections) if c.inflections else np.empty((0, 3))
    arc = np.concatenate(([0.0], np.cumsum(np.linalg.norm(np.diff(P, axis=0), axis=1))))
    comb = _finish(arc, P, np.abs(c.ks), c.ks, -np.cross(m, c.tangent), scale, m, np.empty(0), infl_p)
    spline = None
    if fit and P.shape[0] >= 4:
        from ..fitting.interpolation import interpolate_curve

        spline = interpolate_curve(np.vstack((P, P[:1])) if c.closed else P, 3)
    return SectionCurve(points=P, uv=c.uv, face=c.face, closed=c.closed, curvature=c.ks, comb=comb,
                        inflection_points=infl_p, spline=spline)


def _sections(faces: object, O: Array, Nm: Array, offsets: Array, half: Array | None, tol: float | None,
              fit: bool, scale: float | None) -> list[Section]:
    fl = _faces(faces)
    grids = [f[0].evaluate_grid(*[np.linspace(d0, d1, 9) for d0, d1 in f[0].domain]) for f in fl]
    allp = np.concatenate([g.reshape(-1, 3) for g in grids])
    size = max(float(np.linalg.norm(np.ptp(allp, axis=0))), np.finfo(float).tiny)
    tol_h = tolerances.QUALITY_SECTION_TOL * size if tol is None else positive(tol, "tol")
    k = O.shape[0]
    per_plane: list[list[_Piece]] = [[] for _ in range(k)]
    bad = np.zeros(k, np.int64)
    for fi, (s, mask) in enumerate(fl):  # a loop over faces; each face handles all planes at once
        pieces, b = _face_pieces(fi, s, mask, O, Nm, half, tol_h)
        bad += b
        for i in range(k):
            per_plane[i].extend(pieces[i])
    curves = [_curve(i, p, fl, Nm[i], size, tol_h) for i in range(k)
              for p in _join(per_plane[i], tolerances.QUALITY_CHAIN_TOL * size)]
    _refine_all(curves, fl, O, Nm, tol_h)
    out = [Section(origin=O[i], normal=Nm[i], offset=float(offsets[i]), n_unconverged=int(bad[i])) for i in range(k)]
    for c in curves:
        out[c.plane].curves.append(_section_curve(c, Nm[c.plane], fit, scale))
    return out


def _cut_family(point: ArrayLike, point_name: str, direction: ArrayLike, direction_name: str, values: ArrayLike,
                values_name: str, unit: str) -> tuple[Array, Array, Array]:
    """A point, a unit direction (one 3-vector each) and a non-empty 1-D array of finite values:
    the validated inputs of a family of cutting planes."""
    o = vectors(point, point_name)
    d = unit_vectors(direction, direction_name)
    if o.shape != (3,) or d.shape != (3,):
        raise InvalidGeometryError(f"{point_name}, {direction_name}: expected one 3-vector each")
    v = np.atleast_1d(np.asarray(values, dtype=float))
    if v.ndim != 1 or v.size == 0 or not np.all(np.isfinite(v)):
        raise InvalidGeometryError(f"{values_name}: expected a non-empty 1-D array of finite {unit}, got {values!r}")
    return o, d, v


def plane_sections(faces: Sequence[SectionFace], origin: ArrayLike, normal: ArrayLike, offsets: ArrayLike, *,
                   tol: float | None = None, fit: bool = False, scale: float | None = None) -> list[Section]:
    """Cut faces with the parallel planes ``(x - origin - offset * normal)·normal = 0``.

    Parameters
    ----------
    faces : list of BSplineSurface / HierarchicalSurface, or of (surface, mask) pairs
        ``mask(u, v) -> bool array`` tells which parameters lie inside a trimmed face; seed cells
        with no corner inside are skipped, refined points outside are dropped, and a cut that leaves
        the trim is marched on from its last point inside to the trim boundary (bisection along the
        exact intersection, to within ``tol`` of the boundary the mask draws).
    origin, normal : array_like, shape (3,)
    offsets : array_like, shape (k,)
        Model units along the unit ``normal``.
    tol : float, optional
        Largest distance of a refined point to its plane (model units); default
        :data:`~occsurf.algorithms.tolerances.QUALITY_SECTION_TOL` times the model size.
    fit : bool
        Also interpolate every polyline by a cubic B-spline (:attr:`SectionCurve.spline`).
    scale : float, optional
        Comb scale (spine length per unit curvature); default per curve (see :func:`curvature_comb`).

    Returns
    -------
    list of Section
        One per offset, in the given order.
    """
    o, n, off = _cut_family(origin, "origin", normal, "normal", offsets, "offsets", "numbers")
    O = o + off[:, None] * n
    return _sections(faces, O, np.broadcast_to(n, O.shape).copy(), off, None, tol, fit, scale)


def axial_sections(faces: Sequence[SectionFace], axis_origin: ArrayLike, axis_direction: ArrayLike, angles: ArrayLike, *,
                   tol: float | None = None, fit: bool = False, scale: float | None = None) -> list[Section]:
    """Cut faces with half-planes through an axis (meridian sections of a turned or revolved part).

    The half-plane at ``angle`` contains the axis and the direction ``cos(angle) e1 + sin(angle) e2``
    (``e1``, ``e2`` a right-handed frame perpendicular to the axis, ``e1`` the coordinate axis least
    parallel to it, made perpendicular; ``e2 = axis x e1``); the plane normal is
    ``axis x (cos(angle) e1 + sin(angle) e2)``. Only the half on the radial side is kept. Other
    arguments as :func:`plane_sections`; :attr:`Section.offset` holds the angle.
    """
    o, a, ang = _cut_family(axis_origin, "axis_origin", axis_direction, "axis_direction", angles, "angles",
                            "radians")
    e1 = np.eye(3)[np.argmin(np.abs(a))]
    e1 = e1 - np.dot(e1, a) * a
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(a, e1)
    radial = np.cos(ang)[:, None] * e1 + np.sin(ang)[:, None] * e2
    Nm = np.cross(a, radial)
    O = np.broadcast_to(o, Nm.shape).copy()
    return _sections(faces, O, Nm, ang, radial, tol, fit, scale)
