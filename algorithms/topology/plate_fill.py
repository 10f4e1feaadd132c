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
solved by ``scipy.sparse`` (one sparse LU per knot vector). The data rows are weighted by the
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

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from numpy.typing import ArrayLike, NDArray

from .. import tolerances
from ..errors import InvalidGeometryError
from ..fitting._common import check_fit_size
from ..kernel.basis import basis_derivatives, find_span
from ..kernel.curve import BSplineCurve
from ..kernel.surface import BSplineSurface
from ..kernel.trimmed import TrimmedSurface
from .nsided import HoleSide, count_folds

__all__ = ["PlateFill", "fill_plate", "plate_plane"]

Array = NDArray[np.float64]

_DEGREE = 3
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
def _side_samples(side: HoleSide, t: Array) -> tuple[Array, Array, Array]:
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


# ===================================================================================== the plane
def _crossings(Q: Array) -> tuple[int, int] | None:
    """A pair of non-adjacent segments of the closed polyline ``Q`` (shape (m, 2)) that cross, or None."""
    A, B = Q, np.roll(Q, -1, axis=0)
    m = len(Q)
    lo, hi = np.minimum(A, B), np.maximum(A, B)
    idx = np.arange(m)

    def orient(p: Array, q: Array, r: Array) -> Array:
        return (q[..., 0] - p[..., 0]) * (r[..., 1] - p[..., 1]) - (q[..., 1] - p[..., 1]) * (r[..., 0] - p[..., 0])

    block = 256
    for s in range(0, m, block):  # blocks of segments against all (memory bound, vectorised inside)
        i = idx[s:s + block]
        box = np.all((lo[i, None] <= hi[None]) & (lo[None] <= hi[i, None]), axis=2)
        gap = np.abs(i[:, None] - idx[None])
        box &= (gap > 1) & (gap < m - 1) & (i[:, None] < idx[None])
        ii, jj = np.nonzero(box)
        if ii.size == 0:
            continue
        a, b = A[i[ii]], B[i[ii]]
        c, d = A[jj], B[jj]
        o1, o2 = orient(a, b, c), orient(a, b, d)
        o3, o4 = orient(c, d, a), orient(c, d, b)
        hit = (o1 * o2 < 0) & (o3 * o4 < 0)
        if hit.any():
            k = int(np.argmax(hit))
            return int(i[ii[k]]), int(jj[k])
    return None


def _widest_cap_axis(M: Array, iterations: int = 400) -> Array:
    """The axis of the smallest spherical cap holding the unit vectors ``M`` (shape (m, 3)): the
    direction that the most-leaning of them leans least from (the minimax plane normal).

    Badoiu and Clarkson's core-set iteration for the smallest enclosing ball ("Smaller core-sets for
    balls", SODA 2003: step towards the farthest point by 1/(k+1)); for points on the unit sphere
    within a hemisphere the ball's centre points along the cap's axis. Error ~ 1/iterations of the
    cap's radius: a candidate plane, judged afterwards like the others."""
    c = M.mean(axis=0)
    for k in range(1, iterations + 1):
        far = M[int(np.argmax(np.einsum("ij,ij->i", M - c, M - c)))]
        c = c + (far - c) / (k + 1)
    return c


def _judge(P: Array, Q: Array, M: Array, g1: NDArray[np.bool_], N: Array, newell: Array
           ) -> tuple[tuple[Array, Array, Array, Array, float] | None, str]:
    """One candidate plane normal ``N``: ``(frame, "")`` when the hole is a height field over it
    (loop simple in projection, every G1 normal leaning less than ``FILL_PLATE_MAX_TILT``), else
    ``(None, why)``."""
    length = float(np.linalg.norm(N))
    if not np.isfinite(length) or length == 0:
        return None, "no direction"
    N = N / length
    if float(newell @ N) < 0:
        N = -N  # the loop runs counter-clockwise about the normal
    e1, e2 = _in_plane_axes(Q, N)
    uv = np.c_[Q @ e1, Q @ e2]
    area = 0.5 * float(np.sum(uv[:, 0] * np.roll(uv[:, 1], -1) - np.roll(uv[:, 0], -1) * uv[:, 1]))
    scale = float(np.ptp(uv, axis=0).max()) or 1.0
    if area <= 1e-9 * scale * scale:
        return None, "the loop encloses no area in projection (it winds back over itself)"
    max_tilt = tolerances.FILL_PLATE_MAX_TILT
    cosines = M[g1] @ N if g1.any() else np.ones(1)
    lean = float(np.degrees(np.arccos(np.clip(cosines.min(), -1.0, 1.0))))
    if lean >= max_tilt:
        k = int(np.flatnonzero(g1)[np.argmin(cosines)])
        return None, (f"a neighbour's tangent plane stands at {lean:.1f} deg to it (at "
                      f"{np.array2string(P[k], precision=4)}; at most {max_tilt:g} deg, "
                      "tolerances.FILL_PLATE_MAX_TILT; beyond 90 it turns back over the hole)")
    hit = _crossings(uv)
    if hit is not None:
        return None, (f"the loop crosses itself in projection (samples {hit[0]} and {hit[1]} of {len(P)}, "
                      f"near {np.array2string(P[hit[0]], precision=4)})")
    return (P.mean(axis=0), e1, e2, N, lean), ""


def plate_plane(points: Array, normals: Array, g1: NDArray[np.bool_] | None = None,
                normal: ArrayLike | None = None) -> tuple[Array, Array, Array, Array, float]:
    """The reference plane of a hole over which its fill is a height field.

    Parameters
    ----------
    points : ndarray, shape (m, 3)
        The loop, densely sampled, in order (closed implicitly).
    normals : ndarray, shape (m, 3)
        Neighbour normals ``cross x tangent`` at the samples (any length; the orientation the
        loop gives: for a loop running counter-clockwise about the fill's normal they point to
        the fill's side).
    g1 : ndarray of bool, shape (m,), optional
        Samples whose neighbour normal must lean less than ``tolerances.FILL_PLATE_MAX_TILT``
        from the plane normal (default: all).

    Returns
    -------
    (origin, e1, e2, normal, lean)
        The frame and the largest lean (degrees) of a G1 normal from ``normal``.

    Notes
    -----
    Candidates, in order: the loop's vector area (Newell), the mean neighbour normal, the principal
    axes' normal; of those that pass, the one with the least lean. Only when none passes, the axis
    of the smallest cap holding the G1 normals (:func:`_widest_cap_axis`: the least lean any plane
    can have) and that axis tilted towards the Newell normal (1/3, 2/3 of the way: a plane between
    the two trades lean for a simpler projection) are tried, in that order (the first that passes
    is kept), so that the holes the first three fill keep their fill.

    Raises
    ------
    InvalidGeometryError
        No candidate plane has the loop project one-to-one with every G1 normal leaning less than
        the limit; the message says why for each candidate.
    """
    P = np.asarray(points, float)
    M = np.asarray(normals, float)
    M = M / np.maximum(np.linalg.norm(M, axis=1, keepdims=True), 1e-300)
    g1 = np.ones(len(P), bool) if g1 is None else np.asarray(g1, bool)
    o = P.mean(axis=0)
    Q = P - o
    newell = 0.5 * np.cross(Q, np.roll(Q, -1, axis=0)).sum(axis=0)
    if normal is not None:
        frame, reason = _judge(P, Q, M, g1, np.asarray(normal, float).ravel(), newell)
        if frame is None:
            raise InvalidGeometryError(f"plate fill: not a height field over the plane asked: {reason}")
        return frame
    mean_n = M.sum(axis=0)
    _, _, Vt = np.linalg.svd(Q, full_matrices=False)
    best, why = None, []
    for name, N in (("vector area", newell), ("mean neighbour normal", mean_n), ("principal axes", Vt[2])):
        frame, reason = _judge(P, Q, M, g1, N, newell)
        if frame is None:
            why.append(f"{name}: {reason}")
        elif best is None or frame[4] < best[4]:
            best = frame
    if best is not None:
        return best
    G = M[g1] if g1.any() else M
    axis = _widest_cap_axis(G)
    nn = newell / max(float(np.linalg.norm(newell)), 1e-300)
    axis = axis / max(float(np.linalg.norm(axis)), 1e-300)
    for name, N in (("widest-cap axis", axis), ("cap axis 1/3 towards the vector area", 2 * axis + nn),
                    ("cap axis 2/3 towards the vector area", axis + 2 * nn)):
        frame, reason = _judge(P, Q, M, g1, N, newell)
        if frame is not None:
            return frame
        why.append(f"{name}: {reason}")
    raise InvalidGeometryError("plate fill: not a height field over any plane tried (" + "; ".join(why) + ")")


# ===================================================================================== the fit
def _knots(lo: float, hi: float, spans: int, degree: int) -> Array:
    inner = np.linspace(lo, hi, spans + 1)[1:-1]
    return np.r_[np.full(degree + 1, lo), inner, np.full(degree + 1, hi)]


def _rows(ku: Array, kv: Array, p: int, u: Array, v: Array) -> tuple[Array, Array, Array, Array]:
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


def _gram(knots: Array, p: int) -> list[sp.csr_matrix]:
    """``G_k[i, j] = integral N_i^(k) N_j^(k)`` for k = 0, 1, 2 (exact: p+1 Gauss points per span)."""
    n = knots.size - p - 1
    brk = np.unique(knots)
    x, w = np.polynomial.legendre.leggauss(p + 1)
    a, b = brk[:-1, None], brk[1:, None]
    t = (0.5 * (a + b) + 0.5 * (b - a) * x).ravel()
    wt = (0.5 * (b - a) * w).ravel()
    span = find_span(knots, p, n, t)
    D = basis_derivatives(knots, p, span, t, 2)  # (m, 3, p+1)
    cols = span[:, None] - p + np.arange(p + 1)
    out = []
    for k in range(3):
        B = sp.csr_matrix((D[:, k].ravel(), cols.ravel(), np.arange(0, t.size * (p + 1) + 1, p + 1)), shape=(t.size, n))
        out.append((B.T @ sp.diags(wt) @ B).tocsr())
    return out


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


def _angle(gu: Array, gv: Array, m: Array) -> Array:
    """Angle (degrees, sign-free) between the normal ``(-gu, -gv, 1)`` and ``m`` (local frame)."""
    n = np.c_[-gu, -gv, np.ones_like(gu)]
    c = np.abs(np.einsum("ij,ij->i", n, m))
    s = np.linalg.norm(np.cross(n, m), axis=1)
    return np.degrees(np.arctan2(s, c))


def fill_plate(sides: Sequence[HoleSide], *, g1: Sequence[bool] | NDArray[np.bool_] | None = None, g0_tol: float | None = None,
               angle_tol: float | None = None, max_spans: int | None = None, size: float | None = None,
               normal: ArrayLike | None = None) -> PlateFill:
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
    max_spans = int(tolerances.FILL_PLATE_MAX_SPANS if max_spans is None else max_spans)
    if max_spans < 1:
        raise InvalidGeometryError(f"max_spans: expected a positive integer, got {max_spans}")
    # the largest plate the refinement may reach, (max_spans + p)^2 poles: its sparse normal equations
    # and their LU factors (as a scattered fit's, :func:`~..fitting._common.check_fit_size`)
    check_fit_size((max_spans + _DEGREE,) * 2, (_DEGREE, _DEGREE), "max_spans: a plate of up to n_poles")
    angle_tol = float(tolerances.FILL_FIT_ANGLE if angle_tol is None else angle_tol)
    # ---- the plane, from a dense polyline of the loop
    per = _CHECK_POINTS // len(sides) + 2
    dense = [_side_samples(s, np.linspace(*s.curve.domain, per)[:-1]) for s in sides]
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
    p = _DEGREE
    start = [max(2, int(round(8 * e / ext.max()))) for e in ext]
    lengths = np.array([np.linalg.norm(np.diff(d[0], axis=0), axis=1).sum() for d in dense]) / L
    tol0 = g0_tol / L
    tol1 = np.radians(angle_tol)
    best = None  # (score, c, knots, g0 per side, g1 per side, folds): the best stage is returned
    rippled = False
    for held in (False, True):  # the energy's weight: per stage (of the traces); held (after a ripple)
        if held and not rippled:
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
            data = [_local_data(s, t, o, R, L) for s, t in zip(sides, fit_t)]
            sid = np.concatenate([np.full(len(t), i) for i, t in enumerate(fit_t)])
            X = np.concatenate([d[0] for d in data])
            Mn = np.concatenate([d[1] for d in data])
            val, du, dv, cols = _rows(ku, kv, p, X[:, 0], X[:, 1])
            n = nu * nv
            gsel = flags[sid] & (np.abs(Mn[:, 2]) > 0)
            gx, gy = -Mn[gsel, 0] / Mn[gsel, 2], -Mn[gsel, 1] / Mn[gsel, 2]
            w1 = 1.0 / (tol1 * (1.0 + gx ** 2 + gy ** 2))  # a gradient error of 1/w1 tilts the normal ~1 target angle
            rows_v = np.vstack([val / tol0, du[gsel] * w1[:, None], dv[gsel] * w1[:, None]])
            cols_all = np.vstack([cols, cols[gsel], cols[gsel]])
            rhs = np.r_[X[:, 2] / tol0, gx * w1, gy * w1]
            k = rows_v.shape[1]
            A = sp.csr_matrix((rows_v.ravel(), cols_all.ravel(), np.arange(0, rows_v.shape[0] * k + 1, k)),
                              shape=(rows_v.shape[0], n))
            Gu, Gv = _gram(ku, p), _gram(kv, p)
            E = sp.kron(Gu[2], Gv[0]) + 2.0 * sp.kron(Gu[1], Gv[1]) + sp.kron(Gu[0], Gv[2])
            AtA = (A.T @ A).tocsc()
            eps = tolerances.FILL_PLATE_SMOOTHING * AtA.diagonal().sum() / max(E.diagonal().sum(), 1e-300)
            eps0 = (eps, len(X)) if eps0 is None else eps0
            if held:  # the first stage's weight, grown with the sample count only (see the module)
                eps = eps0[0] * len(X) / eps0[1]
            lu = spla.splu((AtA + eps * E).tocsc())
            ev = _Evaluation(sides, flags, [np.r_[a, b] for a, b in zip(fit_t, chk_t)], ku, kv, p, o, R, L)
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
            folds = count_folds(_build(c, ku, kv, p, o, e1, e2, N, L, sides)[1])
            rippled |= folds > 0
            stalled = stalled + 1 if stage[0] > 0.9 * top else 0
            top = min(top, stage[0])
            if best is None or (folds > 0, stage[0]) < (best[6] > 0, best[0]):  # a ripple loses to any fill without
                best = (stage[0], c, ku, kv, g0_side, g1_side, folds)
            if stage[0] <= 1.0 or stalled >= 4:  # met, or four refinements gained < 10 % (a target the
                break  # data cannot meet, e.g. neighbours without a common tangent plane at a corner)
            ku2, kv2 = _bisect(ku, p, bu, max_spans), _bisect(kv, p, bv, max_spans)
            if ku2.size == ku.size and kv2.size == kv.size:
                break
            ku, kv = ku2, kv2
    if best is None:  # the first stage of the first pass always sets it
        raise RuntimeError("fill_plate: no stage was fitted")
    score, c, ku, kv, g0_side, g1_side, _ = best
    met = score <= 1.0
    surf, trimmed = _build(c, ku, kv, p, o, e1, e2, N, L, sides)
    return PlateFill(surf, trimmed, sides, flags, g0_side, g1_side, o, e1, e2, N,
                     (ku.size - 2 * p - 1, kv.size - 2 * p - 1), bool(met), g0_tol, angle_tol, lean)


def _build(c: Array, ku: Array, kv: Array, p: int, o: Array, e1: Array, e2: Array, N: Array, L: float,
           sides: list[HoleSide]) -> tuple[BSplineSurface, TrimmedSurface]:
    """The height field of coefficients ``c`` in model units (``u``, ``v``: lengths along ``e1``, ``e2``
    from ``o``) and its face trimmed by the sides' p-curves."""
    nu, nv = ku.size - p - 1, kv.size - p - 1
    gu, gv = _greville(ku, p), _greville(kv, p)
    U, V = np.meshgrid(gu, gv, indexing="ij")
    poles = o + L * (U[..., None] * e1 + V[..., None] * e2 + c.reshape(nu, nv)[..., None] * N)
    surf = BSplineSurface((p, p), (ku * L, kv * L), poles)
    pcurves = []
    for s in sides:
        cp = (s.curve.control_points - o) @ np.c_[e1, e2]
        pcurves.append(BSplineCurve(s.curve.degree, s.curve.knots, cp, s.curve.weights))
    return surf, TrimmedSurface(surf, pcurves)


class _Evaluation:
    """Boundary samples (the fit's and those between them) with their basis rows: what a coefficient
    vector achieves there (vectorised over all samples)."""

    def __init__(self, sides: list[HoleSide], flags: NDArray[np.bool_], ts: list[Array], ku: Array, kv: Array,
                 p: int, o: Array, R: Array, L: float) -> None:
        data = [_local_data(s, t, o, R, L) for s, t in zip(sides, ts)]
        self.sid = np.concatenate([np.full(len(t), i) for i, t in enumerate(ts)])
        self.X = np.concatenate([d[0] for d in data])
        self.M = np.concatenate([d[1] for d in data])
        self.g1 = flags[self.sid]
        self.val, self.du, self.dv, self.cols = _rows(ku, kv, p, self.X[:, 0], self.X[:, 1])
        self.L, self.n = L, len(sides)

    def errors(self, c: Array) -> tuple[Array, Array]:
        """Per sample: distance (model units) and angle (degrees; nan on G0-only sides)."""
        cc = c[self.cols]
        e0 = np.abs(np.einsum("ij,ij->i", self.val, cc) - self.X[:, 2]) * self.L
        ang = np.full(e0.shape, np.nan)
        g = self.g1
        ang[g] = _angle(np.einsum("ij,ij->i", self.du[g], cc[g]), np.einsum("ij,ij->i", self.dv[g], cc[g]), self.M[g])
        return e0, ang

    def score(self, c: Array, g0_tol: float, angle_tol: float) -> float:
        """The worst sample in units of the targets (<= 1: both met everywhere)."""
        e0, ang = self.errors(c)
        worst = float(e0.max()) / g0_tol
        if self.g1.any():
            worst = max(worst, float(np.nanmax(ang)) / angle_tol)
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
        return g0, g1, self.X[miss, 0], self.X[miss, 1]


def _local_data(side: HoleSide, t: Array, o: Array, R: Array, L: float) -> tuple[Array, Array]:
    """Boundary points (local frame, units of ``L``) and neighbour normals (local frame) at ``t``."""
    P, T, X = _side_samples(side, t)
    m = np.cross(X, T)
    m /= np.maximum(np.linalg.norm(m, axis=1, keepdims=True), 1e-300)
    return (P - o) @ R / L, m @ R


def _in_plane_axes(Q: Array, N: Array) -> tuple[Array, Array]:
    """``e1``: the principal axis of the points ``Q`` projected onto the plane of normal ``N`` (the
    bounding box then hugs the loop, and the frame turns with the data: rigid motions commute with
    the fill); ``e2 = N x e1``."""
    F = Q - np.outer(Q @ N, N)
    _, _, Vt = np.linalg.svd(F, full_matrices=False)
    e1 = Vt[0] - (Vt[0] @ N) * N
    e1 /= np.linalg.norm(e1)
    return e1, np.cross(N, e1)


def _greville(knots: Array, p: int) -> Array:
    n = knots.size - p - 1
    idx = np.arange(n)[:, None] + 1 + np.arange(p)[None, :]
    return knots[idx].mean(axis=1)
