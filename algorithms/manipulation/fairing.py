"""Fair a region of a surface: remove wiggles by the least curvature variation within a tolerance.

:func:`fair_surface` is the correction ``face_flags`` suggests for a wiggle (course ch. 9: a fair
surface's iso-lines and sections have no inflections the design does not ask for; ch. 3: the
change as a constrained least-squares problem). The poles whose supports lie in the region move,
the others are held (and with them the region's boundary: a pole whose support ends inside the
region leaves position and derivatives up to order ``p - 1`` unchanged where it ends; on the
surface's own boundary ``hold`` keeps the outermost 1, 2 or 3 pole rows: position, tangent plane,
curvature). Each movable pole moves along the surface's normal at its Greville point,
``P_i = P0_i + t_i n_i`` (a tangential move lowers the energy by re-parametrising the surface, not
by making it fairer), by the ``t`` that minimises

    E(t) + lambda ||t||^2,   E = integral over the region of sum_a C(3, a) (n0 . d^3 S / du^a dv^(3-a))^2

(the curvature variation of the surface's normal part, ``n0`` the unit normal of the surface
being faired; the thin-plate energy with second derivatives where a degree is below 3. A cylinder
or a sphere has no curvature variation and stays, where the thin-plate energy would flatten any
curved surface held at its boundary. The parametrisation's own derivatives, large on any real net,
do not count; quadratic in ``t``,
by Gauss-Legendre quadrature per knot span with sparse Kronecker basis matrices), a sparse linear
solve for each ``lambda``; ``lambda`` is the
stiffest (the least change) that leaves no iso-line of the region with two or more sign changes of
its normal curvature (the wiggles ``face_flags`` reports), or the fewest, while the surface moves
by at most ``tol`` on a 64 x 64 grid of the region: a scan by factors of 10, then bisection on
``log lambda``. Fairing more than that would only trade the region's shape for its held boundary
(a cylinder held at its edges and faired hard sags between them). A surface without wiggles is
returned unchanged. Rational surfaces keep their weights;
the energy is then that of the poles' non-rational surface (a fairness measure, not the exact one).

References
----------
R. Bartels, course notes C25 (SIGGRAPH 1991), §3-12 (constrained least squares) and D. Warn, ibid.
ch. 9 (fairness); G. Greiner, "Variational design and fairing of spline surfaces", Computer Graphics
Forum 13 (1994) (the thin-plate energy on spline spaces).
"""

from __future__ import annotations

from dataclasses import dataclass
from math import comb

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from numpy.typing import NDArray

from .. import _validate as V
from ..errors import ArgumentTypeError, InvalidGeometryError, UnknownNameError
from ..kernel.basis import basis_derivatives, find_span
from ..kernel.surface import BSplineSurface
from .linalg import ConstraintError

__all__ = ["FairResult", "fair_surface"]

Array = NDArray[np.float64]
_HOLD = {"G0": 0, "G1": 1, "G2": 2}
#: Rounds of fairing, each measuring the energy along the normals of the previous result.
FAIR_ROUNDS = 3


@dataclass(frozen=True)
class FairResult:
    """What :func:`fair_surface` did.

    Attributes
    ----------
    surface : BSplineSurface
        The faired surface (same knots, degrees and weights).
    max_deviation : float
        Largest distance from the original on a dense grid of the region (``<= tol``).
    energy_before, energy_after : float
        Curvature variation (or thin-plate energy, degree < 3) of the region.
    wiggles_before, wiggles_after : int
        Iso-lines of the region (64 per direction) whose normal curvature changes sign twice or more.
    weight : float
        The ``lambda`` used.
    moved_poles : int
    met : bool
        ``wiggles_after == 0``; otherwise ``reason`` says what is left.
    reason : str or None
    """

    surface: BSplineSurface
    max_deviation: float
    energy_before: float
    energy_after: float
    wiggles_before: int
    wiggles_after: int
    weight: float
    moved_poles: int
    met: bool
    reason: str | None = None


def _basis(knots: Array, p: int, n: int, lo: float, hi: float) -> tuple[list[sp.csr_matrix], Array, Array]:
    """Gauss-Legendre points of ``[lo, hi]`` (p + 1 per knot span) as sparse basis matrices
    ``B[d][k, i] = N_i^(d)(t_k)``, d = 0..3, and their weights."""
    k = np.unique(knots[p: n + 1])
    k = np.unique(np.clip(np.concatenate([k, [lo, hi]]), lo, hi))
    x, w = np.polynomial.legendre.leggauss(p + 1)
    a, b = k[:-1], k[1:]
    keep = b - a > 0
    a, b = a[keep], b[keep]
    t = (0.5 * (a + b)[:, None] + 0.5 * (b - a)[:, None] * x[None]).ravel()
    wt = (0.5 * (b - a)[:, None] * w[None]).ravel()
    span = find_span(knots, p, n, t)
    D = basis_derivatives(knots, p, span, t, 3)  # (m, 4, p+1); zero above the degree
    rows = np.repeat(np.arange(t.size), p + 1)
    cols = (span[:, None] - p + np.arange(p + 1)).ravel()
    return [sp.csr_matrix((D[:, d, :].ravel(), (rows, cols)), shape=(t.size, n)) for d in range(4)], t, wt


def _movable(knots: Array, p: int, n: int, lo: float, hi: float, hold: int) -> NDArray[np.intp]:
    """Poles whose support lies in ``[lo, hi]``, less the ``hold + 1`` outermost rows of the surface."""
    eps = 1e-12 * (knots[n] - knots[p])
    i = np.arange(n)
    inside = (knots[i] >= lo - eps) & (knots[i + p + 1] <= hi + eps)
    inside &= (i > hold) & (i < n - 1 - hold)
    return np.flatnonzero(inside)


def _wiggle_lines(s: BSplineSurface, us: Array, vs: Array, size: float) -> int:
    """Iso-lines (along u and along v) whose normal curvature changes sign twice or more."""
    from .. import tolerances
    from ..quality.flags import sign_changes

    D = s.derivatives_grid(us, vs, 2)
    n = np.cross(D[..., 1, 0, :], D[..., 0, 1, :])
    n /= np.maximum(np.linalg.norm(n, axis=-1, keepdims=True), 1e-300)
    zero = tolerances.QUALITY_WIGGLE_CURVATURE / size
    with np.errstate(invalid="ignore", divide="ignore"):
        ku = np.einsum("...i,...i", D[..., 2, 0, :], n) / np.einsum("...i,...i", D[..., 1, 0, :], D[..., 1, 0, :])
        kv = np.einsum("...i,...i", D[..., 0, 2, :], n) / np.einsum("...i,...i", D[..., 0, 1, :], D[..., 0, 1, :])
    return int((sign_changes(ku.T, zero).sum(-1) >= 2).sum() + (sign_changes(kv, zero).sum(-1) >= 2).sum())


def fair_surface(surface: BSplineSurface, region: tuple[tuple[float, float], tuple[float, float]] | None = None, *,
                 hold: str = "G1", tol: float) -> FairResult:
    """Fair ``surface`` over ``region`` by the least curvature variation that moves it at most ``tol``.

    Parameters
    ----------
    surface : BSplineSurface
        3-D.
    region : ((u0, u1), (v0, v1)), optional
        Parameter box to fair (default the whole domain).
    hold : {'G0', 'G1', 'G2'}
        What the surface's own boundary keeps where the region reaches it (1, 2 or 3 pole rows).
    tol : float
        Largest allowed deviation from the original (model units).

    Returns
    -------
    FairResult

    Raises
    ------
    ConstraintError
        No pole can move (the region is narrower than the poles' supports, or ``hold`` takes them
        all): insert knots in the region first.
    InvalidGeometryError
        Bad arguments, named.
    """
    if not isinstance(surface, BSplineSurface):
        raise ArgumentTypeError(f"surface: expected a BSplineSurface, got {type(surface).__name__}")
    if surface.dim != 3:
        raise InvalidGeometryError(f"surface: needs a 3-D surface, this one has dim {surface.dim}")
    if not isinstance(hold, str) or hold not in _HOLD:
        raise UnknownNameError(f"hold: expected one of G0, G1, G2, got {hold!r}")
    tol = V.check_tol(tol, "tol")
    dom = surface.domain
    if region is None:
        region = dom
    try:
        (u0, u1), (v0, v1) = ((float(a), float(b)) for a, b in region)
    except (TypeError, ValueError) as err:
        raise InvalidGeometryError(f"region: expected ((u0, u1), (v0, v1)), got {region!r}") from err
    if not (dom[0][0] <= u0 < u1 <= dom[0][1] and dom[1][0] <= v0 < v1 <= dom[1][1]):
        raise InvalidGeometryError(f"region: {region!r} is empty or outside the domain {dom!r}")
    (p, q), (U, Vk), (nu, nv) = surface.degree, surface.knots, surface.n_poles
    k = _HOLD[hold]
    mi, mj = _movable(U, p, nu, u0, u1, k), _movable(Vk, q, nv, v0, v1, k)
    if mi.size == 0 or mj.size == 0:
        raise ConstraintError(
            f"fair_surface: no pole can move in region {region!r} holding {hold}: the region is narrower than the "
            f"poles' supports; insert knots in it first")
    Bu, tu, wu = _basis(U, p, nu, u0, u1)
    Bv, tv, wv = _basis(Vk, q, nv, v0, v1)
    P0 = surface.control_points.reshape(-1, 3)
    mov = (mi[:, None] * nv + mj[None, :]).ravel()
    gu, gv = surface.greville()
    gu, gv = gu[mi][:, None].repeat(mj.size, 1).ravel(), gv[mj][None, :].repeat(mi.size, 0).ravel()
    us = np.linspace(u0, u1, 64)
    vs = np.linspace(v0, v1, 64)
    before = surface.evaluate_grid(us, vs)
    size = float(np.linalg.norm(np.ptp(P0, axis=0))) or 1.0
    w = np.outer(wu, wv).ravel()
    W = np.sqrt(w)
    # curvature variation (third derivatives, binomial weights) where both degrees carry it: a
    # cylinder or a sphere has none and stays; the thin-plate energy (second derivatives) would
    # flatten any curved surface held at its boundary, wiggles or not
    order = 3 if min(p, q) >= 3 else 2
    FORMS = tuple(((a, order - a), float(comb(order, a))) for a in range(order + 1))

    def normals(s: BSplineSurface) -> tuple[Array, Array, Array]:
        D = s.derivatives_grid(tu, tv, order)
        n0 = np.cross(D[..., 1, 0, :], D[..., 0, 1, :]).reshape(-1, 3)
        n0 /= np.linalg.norm(n0, axis=1)[:, None]
        Nrm = s.normal(gu, gv)
        if not (np.all(np.isfinite(Nrm)) and np.all(np.isfinite(n0))):
            raise ConstraintError("fair_surface: the surface has no normal at some point of the region")
        return D, n0, Nrm

    def energy(s: BSplineSurface, n0: Array) -> float:
        D = s.derivatives_grid(tu, tv, order)
        return float(sum(f * np.sum(w * np.einsum("kc,kc->k", n0, D[..., a, b, :].reshape(-1, 3)) ** 2)
                         for (a, b), f in FORMS))

    D0 = surface.derivatives_grid(tu, tv, order)  # the original's partials: the same every round

    def system(s: BSplineSurface) -> tuple[sp.csc_matrix, Array, Array]:
        """The normal equations of ``E(t)`` for moves ``t`` along ``s``'s normals from the original
        poles, with ``n0`` the normals of ``s`` (the current iterate)."""
        _, n0, Nrm = normals(s)
        H = None
        g = np.zeros(mov.size)
        for (a, b), f in FORMS:
            M = sp.kron(Bu[a], Bv[b]).tocsr()[:, mov].tocoo()  # (quadrature points, movable poles)
            vals = M.data * np.einsum("kc,kc->k", n0[M.row], Nrm[M.col]) * np.sqrt(f) * W[M.row]
            Mn = sp.csr_matrix((vals, (M.row, M.col)), shape=M.shape)
            base = np.sqrt(f) * W * np.einsum("kc,kc->k", n0, D0[..., a, b, :].reshape(-1, 3))
            H = Mn.T @ Mn if H is None else H + Mn.T @ Mn
            g -= Mn.T @ base
        assert H is not None
        return sp.csc_matrix(H), g, Nrm

    def trial(H: sp.csc_matrix, g: Array, Nrm: Array, lam: float) -> tuple[BSplineSurface, float]:
        t = spla.splu((H + lam * sp.identity(mov.size, format="csc")).tocsc()).solve(g)
        P = P0.copy()
        P[mov] += t[:, None] * Nrm
        s = BSplineSurface._trusted(surface.degree, surface.knots, P.reshape(nu, nv, 3), surface.weights)
        return s, float(np.max(np.linalg.norm(s.evaluate_grid(us, vs) - before, axis=-1)))

    def search(H: sp.csc_matrix, g: Array, Nrm: Array) -> tuple[BSplineSurface, float, float]:
        """The stiffest ``lambda`` (the least change) whose surface has the fewest wiggles and
        stays within ``tol``: a scan down from ``1e8`` times the system's scale by factors of 10,
        then bisection on ``log lambda`` between the last two values scanned."""
        scale = float(H.diagonal().mean()) or 1.0
        w_best, best, dev, lam = wiggles0, surface, 0.0, float("inf")
        prev = None
        for e in range(8, -11, -1):
            x = float(np.log(scale) + e * np.log(10.0))
            s, d = trial(H, g, Nrm, float(np.exp(x)))
            if d > tol:
                break
            w_s = _wiggle_lines(s, us, vs, size)
            if w_s < w_best:
                w_best, best, dev, lam = w_s, s, d, float(np.exp(x))
                if w_s == 0:
                    if prev is not None:  # the stiffest lambda still without wiggles, between prev and x
                        hi, lo = prev, x
                        for _ in range(12):
                            mid = 0.5 * (hi + lo)
                            s2, d2 = trial(H, g, Nrm, float(np.exp(mid)))
                            if d2 <= tol and _wiggle_lines(s2, us, vs, size) == 0:
                                best, dev, lam, lo = s2, d2, float(np.exp(mid)), mid
                            else:
                                hi = mid
                    break
            prev = x
        return best, dev, lam

    # the energy is measured along the normals of the surface being faired: those of the original
    # carry its wiggles and make the parametrisation's second derivatives count; a few rounds with
    # the normals of the last result take them out
    _, n_orig, _ = normals(surface)
    wiggles0 = _wiggle_lines(surface, us, vs, size)
    best, dev, lam = surface, 0.0, float("inf")
    if wiggles0:
        for _ in range(FAIR_ROUNDS):
            H, g, Nrm = system(best)
            cand, d, l_ = search(H, g, Nrm)
            if not np.isfinite(l_):
                break
            best, dev, lam = cand, d, l_
            if _wiggle_lines(best, us, vs, size) == 0:
                break

    w0, w1 = wiggles0, _wiggle_lines(best, us, vs, size)
    met = w1 == 0
    reason = None if met else (f"{w1} iso-lines of the region still change curvature sign twice or more within "
                               f"tol={tol:g} ({w0} before)")
    _, n_new, _ = normals(best)
    return FairResult(best, dev, energy(surface, n_orig), energy(best, n_new), w0, w1, lam, int(mov.size), met,
                      reason)
