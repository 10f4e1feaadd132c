"""A hole filled by one trimmed surface: a thin-plate height field over the hole's mean plane
(course §8-3, the alternative to the central split; the construction of OCC's GeomPlate).

The central split (:func:`.nsided.fill_hole`) builds ``n`` four-sided patches meeting at a centre;
it needs every corner convex and a hole round enough that the patches do not fold. A plate needs
neither: when the hole's boundary projects one-to-one onto a plane and no neighbour's tangent
plane stands vertical over it, the fill is a *height field*

.. math::

    S(u, v) = o + u\\, e_1 + v\\, e_2 + h(u, v)\\, N

over the projected loop's bounding box, ``(e_1, e_2, N)`` an orthonormal frame of the plane. The
surface is a tensor-product B-spline whose ``u`` and ``v`` coordinates are the Greville abscissae
(linear precision: they are reproduced *exactly*), so only the scalar ``h`` is fitted. Its
coefficients minimise

.. math::

    \\sum_i w_0 (h(p_i) - z_i)^2 + \\sum_{i \\in G1} w_1 |\\nabla h(p_i) - g_i|^2
    + \\varepsilon \\iint h_{uu}^2 + 2 h_{uv}^2 + h_{vv}^2 \\, du\\, dv

(G0 at boundary samples ``p_i`` of height ``z_i``; G1, linear in ``h``, where the neighbour's
tangent plane has gradient ``g_i = -(m_1, m_2) / m_3`` for its normal ``m``; the thin-plate
energy of Duchon's thin-plate splines, "Splines minimizing rotation-invariant semi-norms in
Sobolev spaces", 1977, which OCC's ``GeomPlate_BuildPlateSurface`` also minimises), with the Gram
matrices of the energy exact (Gauss quadrature per knot span) and the sparse normal equations
solved by a sparse Cholesky factorisation in nested-dissection order of the plate's grid (one per knot
vector: :class:`_SPDFactor`, :class:`~occsurf.algorithms.kernel.grid_cholesky.GridCholesky`). The data rows are weighted by the
targets (``g0_tol``, ``angle_tol``), so a residual of 1 is "just met"; the energy weight
``tolerances.FILL_PLATE_SMOOTHING`` (of the data term's trace) decides the coefficients no sample
reaches (the plate's inside), and its bias on the data is taken off by iterated Tikhonov
regularisation (``c += K^{-1} A^T (b - A c)``, at most ``tolerances.FILL_PLATE_ITERATIONS``
steps, the best iterate kept as judged on samples *between* the fit's, so that a basis function
grazing the loop is not blown up to fit round-off). Every knot span (in ``u`` and in ``v``)
holding a sample that misses a target is bisected and the fit repeated, until both targets are
met, ``max_spans`` is reached or four refinements in a row gain less than 10 %; the best stage is
returned and what it achieved is reported per side (:class:`PlateFill`). Ripples: the energy's weight, taken per stage from the traces, falls with
every refinement (the finest spans dominate the energy's trace), and where data that cannot be met
keep a fit refining (linkrods' faces [13, 22]: neighbours leaning 67.5 deg, 128 spans) the plate
rippled a span inside its boundary, its normal turning by more than 90 deg between grid points
(:func:`.nsided.count_folds` on the trimmed face: 6 folds). Every stage is therefore checked for
folds; when one folds, the fit is redone from the first knots with the first stage's weight held
(grown with the sample count only, so the balance per boundary sample stays), and a fold-free
stage beats any that folds (then the least miss). Fits that never fold are unchanged.

Why a height field: it cannot fold (``S_u x S_v = N - h_u e_1 - h_v e_2`` has a positive ``N``
component everywhere), its trimming curves are exact (the p-curve of a (rational) B-spline side
is the side with its poles projected onto the plane, weights unchanged, since affine maps commute
with B-splines), and points of the boundary are located by projection, exactly. Which plane: the
loop's vector-area (Newell) normal, the mean neighbour normal and the principal-axes (PCA)
normal are tried; a plane passes when the loop projects onto it to a simple (non-self-intersecting)
polygon and every G1 side's neighbour normal leans less than ``tolerances.FILL_PLATE_MAX_TILT``
from its normal (with the orientation the loop gives); of those that pass, the one with the least
lean is kept. When none passes, the axis of the smallest cap holding the neighbour normals (the
least lean any plane can have) and two planes between it and the Newell plane are tried
(:func:`plate_plane`). Holes that are not graphs over any of them (a thread strip, a hole whose
neighbour turns vertical) are refused with the reason per plane: a plate fill of them would miss
the boundary (OCC's ``MakeFilling`` on a ten-turn thread strip of an M6 screw misses it by 0.8 mm).

References: course §8-3 (filling n-sided holes); Duchon 1977; OCC's GeomPlate (Plate_Plate,
"thin plate" energy with G0/G1 point constraints).
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from numpy.typing import ArrayLike, NDArray

from .. import tolerances
from ..errors import InvalidGeometryError
from ..fitting._common import check_fit_size
from ..kernel.basis import gram_band_index, gram_bands
from ..kernel.curve import BSplineCurve
from ..kernel.grid_cholesky import GridCholesky, NotPositiveDefinite, grid_stencil
from ..kernel.sparse_kron import kron_stencil, kron_sum
from ..kernel.surface import BSplineSurface
from ..kernel.trimmed import TrimmedSurface
from ..threads import blas_threads
from .nsided_measure import count_folds
from .nsided_types import HoleSide
from .plate_measure import Evaluation, corner_g2, curvature_rows, side_samples
from .plate_plane import plate_plane

__all__ = ["PlateFill", "fill_plate", "plate_plane"]

Array = NDArray[np.float64]

_DEGREE = 3
_DEGREE_G2 = 4  # a G2 plate: curvature C2 across knots, approximated to O(h^3)
_CHECK_POINTS = 2048  # polyline points of the loop for the one-to-one (simple projection) test


@dataclass(frozen=True, eq=False)
class PlateFill:
    """The result of :func:`fill_plate`.

    Attributes
    ----------
    surface : BSplineSurface
        The height field over the projected loop's bounding box (polynomial, degree 3 x 3); its
        parameters are lengths along ``e1`` and ``e2`` from ``origin``.
    trimmed : TrimmedSurface
        ``surface`` trimmed by the sides' p-curves (the outer loop; one p-curve per side).
    sides : list of HoleSide
        The input.
    g1 : ndarray of bool, shape (n,)
        Sides on which G1 was asked.
    side_g0 : ndarray, shape (n,)
        Largest distance (model units) between each side and the fill, at the check samples.
    side_g1 : ndarray, shape (n,)
        Largest angle (degrees) between the fill's and the neighbour's tangent planes on each G1
        side (``nan`` on G0-only sides).
    origin, e1, e2, normal : ndarray, shape (3,)
        The reference plane's frame (``normal = e1 x e2``; the loop runs counter-clockwise about it).
    spans : tuple of int
        Knot spans of ``surface`` in ``u`` and ``v``.
    met : bool
        Both targets met on every side.
    g0_tol, angle_tol : float
        The targets.
    lean : float
        Largest angle (degrees) between a G1 side's neighbour normal and ``normal``.
    g2 : ndarray of bool, shape (n,)
        Sides on which curvature continuity (G2) was asked (empty: none).
    side_g2 : ndarray, shape (n,)
        Largest relative jump of the normal curvature across each G2 side (CATIA's G2 ratio
        ``|k1 - k2| / max(|k1|, |k2|)``, a fraction; :func:`.side_jets.relative_jump`), ``nan`` on
        the others.
    g2_tol : float
        The G2 target (a fraction; ``tolerances.FILL_FIT_G2_REL``).
    corner_g2 : ndarray, shape (n,)
        At the corner where side ``i`` ends (and side ``i + 1`` begins), when both are G2: how far the
        two neighbours' curvatures disagree there, ``|H_i - H_(i+1)| / max |H|`` of their Hessians as
        heights over the plate's plane (0 where the neighbours are curvature continuous to each
        other at the corner; no fill is G2 to both beyond it). ``nan`` elsewhere.
    folds : int or None
        Folds of ``trimmed`` (:func:`.nsided_measure.count_folds`), counted when its stage was
        fitted and kept so that :func:`.nsided_measure.fill_folds` does not count them again;
        ``None``: not counted (a plate made otherwise, e.g. mapped back from an unrolled one).
    """

    surface: BSplineSurface
    trimmed: TrimmedSurface
    sides: list[HoleSide]
    g1: NDArray[np.bool_]
    side_g0: Array
    side_g1: Array
    origin: Array
    e1: Array
    e2: Array
    normal: Array
    spans: tuple[int, int]
    met: bool
    g0_tol: float
    angle_tol: float
    lean: float = 0.0
    method: str = field(default="plate")
    g2: NDArray[np.bool_] = field(default_factory=lambda: np.zeros(0, bool))
    side_g2: Array = field(default_factory=lambda: np.zeros(0))
    g2_tol: float = 0.01
    corner_g2: Array = field(default_factory=lambda: np.zeros(0))
    folds: int | None = None

    @property
    def patches(self) -> list[BSplineSurface]:
        """``[surface]`` (so that code counting folds over a fill's patches takes a plate as well)."""
        return [self.surface]

    def locate(self, side: int, points: ArrayLike) -> tuple[Array, Array]:
        """Parameters ``(u, v)`` on :attr:`surface` of points on (or near) side ``side``: their
        projection onto the plane (exact for points of the boundary: the surface reproduces ``u``
        and ``v``). ``side`` is accepted for symmetry with :meth:`.nsided.HoleFill.locate`."""
        if not 0 <= int(side) < len(self.sides):
            raise InvalidGeometryError(f"side: expected 0..{len(self.sides) - 1}, got {side}")
        P = np.asarray(points, float).reshape(-1, 3) - self.origin
        return P @ self.e1, P @ self.e2

    def locate_input(self, side: int, points: ArrayLike) -> tuple[NDArray[np.intp], Array, Array, Array]:
        """``(patch index, u, v, distance)`` as :meth:`.nsided.HoleFill.locate_input` returns them (one
        patch: index 0; ``distance`` from each point to the surface point at its ``(u, v)``)."""
        P = np.asarray(points, float).reshape(-1, 3)
        u, v = self.locate(side, P)
        return np.zeros(u.shape, np.intp), u, v, np.linalg.norm(self.surface.evaluate(u, v) - P, axis=1)


# ===================================================================================== sides
def _params(curve: BSplineCurve, count: int) -> Array:
    """About ``count`` parameters on ``curve``, evenly spread in every knot span (ends included)."""
    k = np.unique(curve.knots[curve.degree:curve.n_poles + 1])
    per = max(2, int(np.ceil(count / max(k.size - 1, 1))))
    f = np.linspace(0.0, 1.0, per + 1)[:-1]
    t = (k[:-1, None] + f[None, :] * np.diff(k)[:, None]).ravel()
    return np.r_[t, k[-1]]


def _validate(sides: Sequence[HoleSide],
              g1: Sequence[bool] | NDArray[np.bool_] | None) -> tuple[list[HoleSide], NDArray[np.bool_]]:
    sides = list(sides)
    if len(sides) < 1:
        raise InvalidGeometryError("sides: expected at least one HoleSide, got none")
    for i, s in enumerate(sides):
        if not isinstance(s, HoleSide):
            raise InvalidGeometryError(f"sides[{i}]: expected a HoleSide, got {type(s).__name__}")
        if s.curve.dim != 3:
            raise InvalidGeometryError(f"sides[{i}].curve: expected a 3-D curve, got {s.curve.dim}-D")
        want = 4 if s.curve.is_rational else 3
        if s.cross.dim != want:
            raise InvalidGeometryError(f"sides[{i}].cross: expected a {want}-D field for a "
                                       f"{'rational' if want == 4 else 'polynomial'} side, got {s.cross.dim}-D")
    flags = np.ones(len(sides), bool) if g1 is None else np.asarray(g1, bool).ravel()
    if flags.shape != (len(sides),):
        raise InvalidGeometryError(f"g1: expected {len(sides)} flags (one per side), got {flags.shape[0]}")
    ends = np.array([[s.curve.evaluate(s.curve.domain[0]), s.curve.evaluate(s.curve.domain[1])] for s in sides])
    # the loop's extent from the poles (the ends alone span nothing for a one-sided loop: a circle)
    size = float(np.ptp(np.concatenate([s.curve.control_points for s in sides]), axis=0).max()) or 1.0
    gaps = np.linalg.norm(ends[:, 1] - np.roll(ends[:, 0], -1, axis=0), axis=1)
    if np.any(gaps > tolerances.FILL_CLOSURE_TOL * size):
        j = int(np.argmax(gaps))
        raise InvalidGeometryError(f"sides: the loop is open: side {j} ends {gaps[j]:.3g} from the start of side "
                                   f"{(j + 1) % len(sides)} (allowed {tolerances.FILL_CLOSURE_TOL:g} of the loop's size)")
    return sides, flags


# ===================================================================================== the fit
def _fit_rows(fit_t: list[Array], chk_t: list[Array]) -> NDArray[np.bool_]:
    """Which samples of an :class:`Evaluation` made on ``[np.r_[f, c] for f, c in zip(fit_t, chk_t)]``
    are the fit's (each side's ``fit_t`` then its ``chk_t``)."""
    return np.concatenate([np.r_[np.ones(len(f), bool), np.zeros(len(c), bool)] for f, c in zip(fit_t, chk_t)])


def _knots(lo: float, hi: float, spans: int, degree: int) -> Array:
    inner = np.linspace(lo, hi, spans + 1)[1:-1]
    return np.r_[np.full(degree + 1, lo), inner, np.full(degree + 1, hi)]


def _gram(knots: Array, p: int, top: int = 2) -> tuple[sp.csr_matrix, ...]:
    """``G_k[i, j] = integral N_i^(k) N_j^(k)`` for k = 0 .. ``top`` (exact: p+1 Gauss points per span).

    Kept per knot vector (:func:`_gram_cached`): a refinement that splits spans in one direction
    only keeps the other's knots, and the held pass starts again from the first stage's (bearing
    faces 163, 65 and 197 asked 98 times for 0.42 s). The matrices are shared: never change them."""
    return _gram_cached(np.ascontiguousarray(knots, float).tobytes(), int(p), int(top))


@functools.lru_cache(maxsize=64)
def _gram_cached(knots_key: bytes, p: int, top: int) -> tuple[sp.csr_matrix, ...]:
    """:func:`_gram` for knots given as bytes: the bands of :func:`~..kernel.basis.gram_bands` (the
    sparse product ``B^T diag(w) B``'s entries, bit for bit: tests/algorithms/test_plate_gram.py)
    as CSR matrices, exact zeros dropped."""
    bands = gram_bands(np.frombuffer(knots_key), p, top)
    n, h = bands.shape[1], bands.shape[2]
    _, col, inside = gram_band_index(n, p)
    out = []
    for band in bands.reshape(top + 1, n * h):
        keep = inside & (band != 0)
        indptr = np.r_[0, np.cumsum(keep.reshape(n, h).sum(axis=1))]
        out.append(sp.csr_matrix((band[keep], col[keep], indptr), shape=(n, n)))
    return tuple(out)


def _bisect(knots: Array, p: int, x: Array, limit: int) -> Array:
    """``knots`` with every span holding one of ``x`` bisected (at most ``limit`` spans in all)."""
    brk = np.unique(knots)
    if brk.size - 1 >= limit:
        return knots
    idx = np.unique(np.clip(np.searchsorted(brk, x, side="right") - 1, 0, brk.size - 2))
    room = limit - (brk.size - 1)
    if idx.size > room:  # the spans with the most offending points first
        counts = np.bincount(np.clip(np.searchsorted(brk, x, side="right") - 1, 0, brk.size - 2), minlength=brk.size - 1)
        idx = np.sort(idx[np.argsort(-counts[idx], kind="stable")][:room])
    new = 0.5 * (brk[idx] + brk[idx + 1])
    return np.sort(np.r_[knots, new])


def fill_plate(sides: Sequence[HoleSide], *, g1: Sequence[bool] | NDArray[np.bool_] | None = None, g0_tol: float | None = None,
               angle_tol: float | None = None, max_spans: int | None = None, size: float | None = None,
               normal: ArrayLike | None = None, g2: Sequence[bool] | NDArray[np.bool_] | None = None,
               g2_tol: float | None = None) -> PlateFill:
    """Fill a hole with one trimmed thin-plate height field (see the module; course §8-3, GeomPlate).

    Parameters
    ----------
    sides : sequence of HoleSide
        As for :func:`.nsided.fill_hole`: the boundary curves around the loop, each with the
        neighbour's cross derivative pointing into the neighbour (4-D homogeneous for rational sides).
    g1 : sequence of bool, shape (n,), optional
        Per side, whether the fill must be G1 to the neighbour there (default all); G0-only sides
        contribute positions only.
    g0_tol : float, optional
        Target distance from the boundary (model units); default ``tolerances.FILL_FIT_G0 * size``.
    angle_tol : float, optional
        Target angle (degrees) to the neighbours' tangent planes; default ``tolerances.FILL_FIT_ANGLE``.
    max_spans : int, optional
        Most knot spans per direction; default ``tolerances.FILL_PLATE_MAX_SPANS``. A value whose
        largest plate would pass ``tolerances.MAX_ARRAY_BYTES`` is refused before any work.
    size : float, optional
        Model size for the default ``g0_tol``; default the loop's diameter about its centroid
        (twice the largest distance of a boundary point from it: invariant under rigid motions).
    normal : array_like, shape (3,), optional
        The plane's normal, when the caller knows it (:func:`plate_plane`); default: the candidates.
    g2 : sequence of bool, shape (n,), optional
        Per side, whether the fill must also be curvature continuous (G2) to the neighbour there
        (default none; a G2 side is a G1 side too). Such a side must carry the neighbour's second
        cross derivative (``HoleSide.cross2``). The neighbour's curvature is fitted as the Hessian
        of its height over the plate's plane (:func:`.side_jets.graph_jet`) at the same samples
        as its position and tangent plane, and the relative jump of the normal curvature across
        the side (CATIA's G2 ratio) is the third target.
    g2_tol : float, optional
        Target relative curvature jump (a fraction) on G2 sides; default ``tolerances.FILL_FIT_G2_REL``
        (1 %).

    Returns
    -------
    PlateFill
        The surface, the trimmed face and what was achieved per side (``met`` says whether both
        targets were; the fill is returned either way).

    Raises
    ------
    InvalidGeometryError
        The input is not a closed loop of sides, or the hole is not a height field over any plane
        tried (:func:`plate_plane`: the reason is named).
    """
    sides, flags = _validate(sides, g1)
    g2f = _g2_flags(sides, g2)
    flags = flags | g2f
    g2_tol = float(tolerances.FILL_FIT_G2_REL if g2_tol is None else g2_tol)
    if not g2_tol > 0:
        raise InvalidGeometryError(f"g2_tol: expected a positive relative curvature jump, got {g2_tol}")
    max_spans = int(tolerances.FILL_PLATE_MAX_SPANS if max_spans is None else max_spans)
    if max_spans < 1:
        raise InvalidGeometryError(f"max_spans: expected a positive integer, got {max_spans}")
    # the largest plate the refinement may reach, (max_spans + p)^2 poles: its sparse normal equations
    # and their LU factors (as a scattered fit's, :func:`~..fitting._common.check_fit_size`)
    check_fit_size((max_spans + _DEGREE,) * 2, (_DEGREE, _DEGREE), "max_spans: a plate of up to n_poles")
    angle_tol = float(tolerances.FILL_FIT_ANGLE if angle_tol is None else angle_tol)
    # ---- the plane, from a dense polyline of the loop
    per = _CHECK_POINTS // len(sides) + 2
    dense = [side_samples(s, np.linspace(*s.curve.domain, per)[:-1]) for s in sides]
    P = np.concatenate([d[0] for d in dense])
    M = np.concatenate([np.cross(d[2], d[1]) for d in dense])
    Gm = np.concatenate([np.full(len(d[0]), f) for d, f in zip(dense, flags)])
    diag = 2.0 * float(np.linalg.norm(P - P.mean(axis=0), axis=1).max()) or 1.0  # rotation-invariant size
    size = diag if size is None else float(size)
    g0_tol = float(tolerances.FILL_FIT_G0 * size if g0_tol is None else g0_tol)
    if not (g0_tol > 0 and angle_tol > 0):
        raise InvalidGeometryError(f"g0_tol, angle_tol: expected positive targets, got {g0_tol}, {angle_tol}")
    o, e1, e2, N, lean = plate_plane(P, M, Gm, normal)
    R = np.c_[e1, e2, N]  # world = o + R @ local
    L = diag  # internal unit: the fit runs on coordinates / L (scale-free)
    loc = (P - o) @ R / L
    lo, hi = loc[:, :2].min(axis=0), loc[:, :2].max(axis=0)
    margin = 0.02 * float(np.max(hi - lo))
    lo, hi = lo - margin, hi + margin
    ext = hi - lo
    p = _DEGREE_G2 if g2f.any() else _DEGREE
    start = [max(2, int(round(8 * e / ext.max()))) for e in ext]
    lengths = np.array([np.linalg.norm(np.diff(d[0], axis=0), axis=1).sum() for d in dense]) / L
    tol0 = g0_tol / L
    tol1 = np.radians(angle_tol)
    kfloor = tolerances.CONTINUITY_CURVATURE_FLOOR / size * L  # curvatures below it count as flat (local units)
    best = None  # (score, c, knots, g0 per side, g1 per side, folds): the best stage is returned
    trim: TrimmedSurface | None = None  # the first stage's face: its loops (and their polylines) serve every stage
    rippled = False
    for held in (False, True):  # the energy's weight: per stage (of the traces); held (after a ripple)
        if held and not rippled:
            break
        if held and g2f.any() and best is not None and best[6] == 0:
            # a G2 plate redoes the refinement with the weight held only when its best stage folds:
            # its coarse first stages may fold where the finer ones do not (bump rings: 8 x 7, 16 x 14),
            # and the held pass then only repeated the costliest stages (half of the time) to lose
            break
        ku = _knots(lo[0], hi[0], min(start[0], max_spans), p)
        kv = _knots(lo[1], hi[1], min(start[1], max_spans), p)
        stalled, eps0, top = 0, None, np.inf  # top: this pass's best score (for the stall test)
        while True:
            nu, nv = ku.size - p - 1, kv.size - p - 1
            spans = max(nu, nv) - p
            fit_t, chk_t = [], []
            for s, ln in zip(sides, lengths):
                t = _params(s.curve, max(24, int(np.ceil(6 * spans * ln / ext.max()))))
                fit_t.append(t)
                chk_t.append(0.5 * (t[1:] + t[:-1]))
            # the samples of the fit and those between them (the stopping rule's), each side's fit
            # samples first: the fit's rows are the evaluation's (per sample: one side evaluation and
            # one basis row each)
            ev = Evaluation(sides, flags, [np.r_[a, b] for a, b in zip(fit_t, chk_t)], ku, kv, p, o, R, L,
                            g2=g2f, kfloor=kfloor, g2_tol=g2_tol)
            fit = _fit_rows(fit_t, chk_t)
            sid, X, Mn = ev.sid[fit], ev.X[fit], ev.M[fit]
            val, du, dv, cols = ev.val[fit], ev.du[fit], ev.dv[fit], ev.cols[fit]
            n = nu * nv
            gsel = flags[sid] & (np.abs(Mn[:, 2]) > 0)
            gx, gy = -Mn[gsel, 0] / Mn[gsel, 2], -Mn[gsel, 1] / Mn[gsel, 2]
            w1 = 1.0 / (tol1 * (1.0 + gx ** 2 + gy ** 2))  # a gradient error of 1/w1 tilts the normal ~1 target angle
            rows_v = np.vstack([val / tol0, du[gsel] * w1[:, None], dv[gsel] * w1[:, None]])
            cols_all = np.vstack([cols, cols[gsel], cols[gsel]])
            rhs = np.r_[X[:, 2] / tol0, gx * w1, gy * w1]
            if g2f.any():  # the neighbour's Hessian as a height over the plane, where G2 is asked
                r2, c2, b2 = curvature_rows(sides, g2f, fit_t, ku, kv, p, o, R, L, g2_tol, kfloor)
                rows_v, cols_all, rhs = np.vstack([rows_v, r2]), np.vstack([cols_all, c2]), np.r_[rhs, b2]
            k = rows_v.shape[1]
            A = sp.csr_matrix((rows_v.ravel(), cols_all.ravel(), np.arange(0, rows_v.shape[0] * k + 1, k)),
                              shape=(rows_v.shape[0], n))
            if g2f.any():  # the curvature-variation energy (Moreton & Sequin's MVS, on a height): zero on quadrics
                Gu, Gv = _gram(ku, p, 3), _gram(kv, p, 3)
                terms = [(1, Gu[3], Gv[0]), (3.0, Gu[2], Gv[1]), (3.0, Gu[1], Gv[2]), (1, Gu[0], Gv[3])]
            else:
                Gu, Gv = _gram(ku, p), _gram(kv, p)
                terms = [(1, Gu[2], Gv[0]), (2.0, Gu[1], Gv[1]), (1, Gu[0], Gv[2])]
            # G1: the energy's rows on the coefficient grid (nu, nv, 2p+1, 2p+1) for the grid Cholesky;
            # G2: the sparse matrix for SuperLU's LU (see _SPDFactor)
            E = kron_sum(terms) if g2f.any() else kron_stencil(terms, p)
            AtA = (A.T @ A).tocsc()
            eps = tolerances.FILL_PLATE_SMOOTHING * AtA.diagonal().sum() / max(_diagonal(E).sum(), 1e-300)
            eps0 = (eps, len(X)) if eps0 is None else eps0
            if held:  # the first stage's weight, grown with the sample count only (see the module)
                eps = eps0[0] * len(X) / eps0[1]
            if g2f.any():
                lu = _SPDFactor(None, functools.partial(_sparse_sum, AtA, eps, E))
            else:
                lu = _SPDFactor(grid_stencil(AtA, (nu, nv), p) + eps * E,
                                functools.partial(_sparse_system, AtA, eps, terms))
            c = lu.solve(A.T @ rhs)
            stage = (ev.score(c, g0_tol, angle_tol), c)
            for _ in range(int(tolerances.FILL_PLATE_ITERATIONS)):
                # iterated Tikhonov (the energy's bias leaves the data, not what no sample pins: a basis
                # function grazing the loop), stopped by the samples between the fit's (validation)
                if stage[0] <= 1.0:
                    break
                c = c + lu.solve(A.T @ (rhs - A @ c))
                sc = ev.score(c, g0_tol, angle_tol)
                if sc < stage[0]:
                    stage = (sc, c)
                elif sc > 2.0 * stage[0]:
                    break
            c = stage[1]
            g0_side, g1_side, bu, bv = ev.measure(c, g0_tol, angle_tol)
            g2_side = ev.side_g2(c)
            stage_trim = _build(c, ku, kv, p, o, e1, e2, N, L, sides, trim)[1]
            trim = trim or stage_trim
            folds = count_folds(stage_trim)
            rippled |= folds > 0
            stalled = stalled + 1 if stage[0] > 0.9 * top else 0
            top = min(top, stage[0])
            if best is None or (folds > 0, stage[0]) < (best[6] > 0, best[0]):  # a ripple loses to any fill without
                best = (stage[0], c, ku, kv, g0_side, g1_side, folds, g2_side)
            if stage[0] <= 1.0 or stalled >= 4:  # met, or four refinements gained < 10 % (a target the
                break  # data cannot meet, e.g. neighbours without a common tangent plane at a corner)
            ku2, kv2 = _bisect(ku, p, bu, max_spans), _bisect(kv, p, bv, max_spans)
            if ku2.size == ku.size and kv2.size == kv.size:
                break
            ku, kv = ku2, kv2
    if best is None:  # the first stage of the first pass always sets it
        raise RuntimeError("fill_plate: no stage was fitted")
    score, c, ku, kv, g0_side, g1_side, folds, g2_side = best
    met = score <= 1.0
    surf, trimmed = _build(c, ku, kv, p, o, e1, e2, N, L, sides, trim)
    return PlateFill(surf, trimmed, sides, flags, g0_side, g1_side, o, e1, e2, N,
                     (ku.size - 2 * p - 1, kv.size - 2 * p - 1), bool(met), g0_tol, angle_tol, lean,
                     g2=g2f, side_g2=g2_side, g2_tol=g2_tol, corner_g2=corner_g2(sides, g2f, o, R, L, kfloor),
                     folds=int(folds))


class _SPDFactor:
    """The plate's system ``K = A^T A + eps E`` on its ``nu x nv`` grid of coefficients, factored once
    for the solves of a stage.

    ``K`` is symmetric positive definite (``E`` is positive semi-definite with the linear functions
    as its null space, on which the G0 rows of ``A`` are positive definite), but badly scaled: its
    diagonal spans 13 decades (basis functions outside the loop are held by ``eps E`` alone). It is
    scaled symmetrically to a unit diagonal (Jacobi: ``D^-1/2 K D^-1/2``, which leaves the solution
    unchanged) and factored by Cholesky in the nested-dissection order of the grid
    (:class:`~occsurf.algorithms.kernel.grid_cholesky.GridCholesky`: a coefficient couples with
    those at most ``p`` apart in each index). Before 2026-12-06 it was SuperLU's LU in its symmetric
    mode (minimum degree on ``K + K^T``, diagonal pivots; 6-7x faster than SuperLU's default, which
    the G1 plate used until 2026-12-05): 0.29-0.46 s against 0.15-0.22 s on linkrods face 35's
    17 161 unknowns, with solutions that agree within the system's round-off (3.5e-10 of the largest
    coefficient there; its condition number ~1e8). The unscaled default LU differed from the scaled
    factorisations by up to 4.5e-3 in the directions the data hardly pin: the scaling is what makes
    the plate reproducible.

    The G2 plate's systems stay with the symmetric-mode LU. Its curvature-variation energy holds the
    coefficients far outside the loop so loosely that two exact factorisations agree only to 7e-3 of
    the largest coefficient, one stage of the 3-sided bump ring is even indefinite to working
    precision (119 x 104: the LU meets three negative pivots, the least -0.25 against a unit
    diagonal), and the refinement's choices follow that round-off: with Cholesky the G2 refills of
    the bearing's 90-degree fillets (faces 4, 8, 23) came out with jumps of 8.3, 10.8 and 11.1 %
    where the LU gives 8.0, 8.94 and 9.49 % (and 2-3x faster, by taking other stages). A speed-up
    must not change the fills, so G2 plates are factored as they were; the synthetic G2 holes of
    ``bench_fill_g2.py`` had not shown it. Where Cholesky meets a pivot <= 0 on a G1 plate (none
    seen), the LU is used as well.
    """

    def __init__(self, stencil: Array | None, sparse: Callable[[], sp.spmatrix]) -> None:
        """``stencil``: ``K``'s rows on the grid (:meth:`GridCholesky.from_stencil`), ``None`` for the
        LU (a G2 plate); ``sparse()``: the same ``K`` as a sparse matrix (made only for the LU)."""
        self.chol: GridCholesky | None = None
        if stencil is not None:
            try:
                self.chol = GridCholesky.from_stencil(stencil)
            except NotPositiveDefinite:
                pass  # the LU below
        if self.chol is None:
            K = sp.csc_matrix(sparse())
            self.s = 1.0 / np.sqrt(K.diagonal())
            S = sp.diags(self.s)
            with blas_threads():
                self.lu = spla.splu((S @ K @ S).tocsc(), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                                    options={"SymmetricMode": True})

    def solve(self, b: Array) -> Array:
        """``K^-1 b``."""
        if self.chol is not None:
            return self.chol.solve(b)
        with blas_threads():
            return self.s * self.lu.solve(self.s * b)


def _diagonal(E: Array | sp.spmatrix) -> Array:
    """The diagonal of a sparse matrix or of a system given as stencil rows (contiguous, in the
    unknowns' order: the same array either way)."""
    if sp.issparse(E):
        return np.asarray(E.diagonal())
    r = E.shape[2] // 2
    return np.ascontiguousarray(E[:, :, r, r]).ravel()


def _sparse_system(AtA: sp.spmatrix, eps: float, terms: list) -> sp.spmatrix:
    """The plate's ``K = A^T A + eps E`` as a sparse matrix (the stencil's entries, the same values)."""
    return _sparse_sum(AtA, eps, kron_sum(terms))


def _sparse_sum(AtA: sp.spmatrix, eps: float, E: sp.spmatrix) -> sp.spmatrix:
    """``A^T A + eps E``."""
    return AtA + eps * E


def _build(c: Array, ku: Array, kv: Array, p: int, o: Array, e1: Array, e2: Array, N: Array, L: float,
           sides: list[HoleSide], trim: TrimmedSurface | None = None) -> tuple[BSplineSurface, TrimmedSurface]:
    """The height field of coefficients ``c`` in model units (``u``, ``v``: lengths along ``e1``, ``e2``
    from ``o``) and its face trimmed by the sides' p-curves. ``trim``: an earlier stage's face (the
    same p-curves, the same domain ``[lo, hi]``), whose loops and their polylines are reused
    (:meth:`~occsurf.algorithms.kernel.trimmed.TrimmedSurface.on_surface`)."""
    nu, nv = ku.size - p - 1, kv.size - p - 1
    gu, gv = _greville(ku, p), _greville(kv, p)
    U, V = np.meshgrid(gu, gv, indexing="ij")
    poles = o + L * (U[..., None] * e1 + V[..., None] * e2 + c.reshape(nu, nv)[..., None] * N)
    surf = BSplineSurface((p, p), (ku * L, kv * L), poles)
    if trim is not None and trim.surface.domain == surf.domain:
        return surf, trim.on_surface(surf)
    pcurves = []
    for s in sides:
        cp = (s.curve.control_points - o) @ np.c_[e1, e2]
        pcurves.append(BSplineCurve(s.curve.degree, s.curve.knots, cp, s.curve.weights))
    return surf, TrimmedSurface(surf, pcurves)


def _g2_flags(sides: list[HoleSide], g2: Sequence[bool] | NDArray[np.bool_] | None) -> NDArray[np.bool_]:
    """The G2 flags, one per side, each G2 side checked to carry its neighbour's second cross derivative."""
    flags = np.zeros(len(sides), bool) if g2 is None else np.asarray(g2, bool).ravel()
    if flags.shape != (len(sides),):
        raise InvalidGeometryError(f"g2: expected {len(sides)} flags (one per side), got {flags.shape[0]}")
    for i in np.flatnonzero(flags):
        x2 = sides[i].cross2
        if x2 is None:
            raise InvalidGeometryError(f"sides[{i}]: G2 asked but the side has no second cross derivative (cross2)")
        want = 4 if sides[i].curve.is_rational else 3
        if x2.dim != want:
            raise InvalidGeometryError(f"sides[{i}].cross2: expected a {want}-D field, got {x2.dim}-D")
    return flags


def _greville(knots: Array, p: int) -> Array:
    n = knots.size - p - 1
    idx = np.arange(n)[:, None] + 1 + np.arange(p)[None, :]
    return knots[idx].mean(axis=1)
