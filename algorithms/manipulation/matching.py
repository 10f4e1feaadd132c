"""Match a surface to another along an edge, G0 to G3, by the least change of its poles.

Rhino's ``MatchSrf``, CATIA's Match Surface and NX's Matching Edge, done the course's way (ch. 3-4):
every continuity condition at a point of the side is a condition on the surface's cross-boundary
derivatives there, and those are linear in the poles (the weights of a rational surface held),
so the change is the minimum-norm solution of the conditions at samples along the side (course
§4-4, §4-7..4-12: ``dP = pinv(J) r``), over the pole rows the order needs (row ``j`` from the side
carries the ``j``-th cross derivative).

The conditions (``S_j`` the ``j``-th cross derivative of the surface at a point of its side;
``P, N, (e1, e2), H2, H3`` the target's point, normal, tangent frame and height-function
derivatives there, :mod:`.match_targets`; ``xi_j = (e1, e2) . S_j``):

====  ============================================================================
G0    ``S_0 = P``
G1    ``N . S_1 = 0``                                    (the tangent planes agree)
G2    ``N . S_2 = H2(xi_1, xi_1)``                       (the normal curvatures agree)
G3    ``N . S_3 = H3(xi_1, xi_1, xi_1) + 3 H2(xi_1, xi_2)`` (their derivatives agree)
====  ============================================================================

G0 and G1 are linear in the poles, and one solve gives the exact minimum-norm change; G2 and G3 are
quadratic in the lower rows and are solved by Gauss-Newton steps that keep the change minimal
(``x <- pinv(J) (J x - F)``). Each condition row is divided by its norm (the solution of a
consistent system does not change; an inconsistent one is then solved in pole-displacement units).
The point ``P`` is the foot of the surface's current side point on the target's edge, re-found at
each step, so the side may slide along the edge.

With ``refine=True`` knots are inserted (Oslo, course §2-10) along the side until the tolerances
hold: first the target side's own knots where they fall (a target of the same degree is then
matched exactly), then the midpoints of the spans that still miss, up to
``tolerances.MATCH_MAX_ROUNDS`` rounds and ``MATCH_MAX_POLES`` poles. Rows the order needs that
would touch the rows ``preserve_opposite`` holds (Rhino's "Preserve other end") are made by
inserting knots across the side.

References
----------
R. Bartels, course notes C25 (SIGGRAPH 1991), §3-12 and §4-4..4-12; R. H. Bartels, J. C. Beatty,
"A technique for the direct manipulation of spline curves", Graphics Interface '89.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TypeAlias

import numpy as np
from numpy.typing import NDArray

from .. import tolerances
from ..errors import ArgumentTypeError, InvalidGeometryError, UnknownNameError
from ..kernel.curve import BSplineCurve
from ..kernel.surface import BSplineSurface
from .linalg import ConstraintError
from .match_solve import min_norm_change
from .match_targets import Jets, MatchTarget, SampledCurve, SurfaceSide, height_jets

__all__ = ["MatchResult", "MatchTarget", "match_surface", "side_along", "surface_change", "pole_size",
           "SIDES", "CONTINUITIES"]

Array = NDArray[np.float64]
_Target: TypeAlias = "SurfaceSide | SampledCurve | _AverageSide"

#: The sides of a surface, as ``match_surface`` names them.
SIDES: tuple[str, ...] = ("u0", "u1", "v0", "v1")
#: Continuity orders by name.
CONTINUITIES: dict[str, int] = {"G0": 0, "G1": 1, "G2": 2, "G3": 3}
_PRESERVE: dict[str, int] = {"none": -1, "G0": 0, "G1": 1, "G2": 2}


@dataclass(frozen=True)
class MatchResult:
    """What :func:`match_surface` did.

    Attributes
    ----------
    surface : BSplineSurface
        The changed surface (same degrees and weights; knots added where ``knots_added > 0``).
    target : BSplineSurface or MatchTarget
        The target, changed only with ``average=True``.
    g0_max : float
        Largest distance between the side and the target's edge (model units), over dense samples.
    g1_max_deg : float
        Largest angle between the tangent planes across the edge (degrees); 0 for G0 matches too
        (measured, not asked).
    g2_max_rel : float
        Largest relative jump of the normal curvature across the edge, ``|k1 - k2| / max(|k1|,
        |k2|)`` as a fraction (CATIA's G2 % / 100); 0 where both are below
        ``tolerances.CONTINUITY_CURVATURE_FLOOR`` / size; NaN if the target carries no curvature.
    g3_max_rel : float
        The same for the derivative of that curvature across the edge (G3 matches only; else NaN).
    max_change : float
        Largest distance between the surface before and after, on a dense grid (model units); with
        ``average=True`` the larger of the two surfaces' changes.
    max_pole_change : float
        Largest pole displacement (bounds ``max_change`` for non-rational surfaces; both surfaces
        with ``average=True``).
    knots_added : int
        Knots inserted (both directions, both surfaces with ``average=True``).
    met : bool
        Whether every tolerance asked for holds.
    """

    surface: BSplineSurface
    target: BSplineSurface | MatchTarget
    g0_max: float
    g1_max_deg: float
    g2_max_rel: float
    g3_max_rel: float
    max_change: float
    max_pole_change: float
    knots_added: int
    met: bool


# ---- orientation: every side becomes side u0 of a clamped surface ---------------------------------

def _canonical(s: BSplineSurface, side: str) -> BSplineSurface:
    s = s.clamp()
    if side == "u1":
        return s.reverse(direction="u")
    if side == "v0":
        return s.swap_uv()
    if side == "v1":
        return s.swap_uv().reverse(direction="u")
    return s


def _restore(s: BSplineSurface, side: str) -> BSplineSurface:
    if side == "u1":
        return s.reverse(direction="u")
    if side == "v0":
        return s.swap_uv()
    if side == "v1":
        return s.reverse(direction="u").swap_uv()
    return s


def _unit(v: Array) -> Array:
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    return v / np.where(n > 0, n, 1.0)


# ---- sampling and measuring -----------------------------------------------------------------------

def _spans(S: BSplineSurface) -> Array:
    q, Vk = S.degree[1], S.knots[1]
    k = np.unique(Vk[q: len(Vk) - q])
    return k


def _solve_params(S: BSplineSurface) -> Array:
    k = _spans(S)
    # n . S_u is a polynomial of degree ~3q along a span of a polynomial pair: 3q + 3 points pin it
    x, _ = np.polynomial.legendre.leggauss(3 * S.degree[1] + 3)
    inner = (0.5 * (k[:-1, None] + k[1:, None]) + 0.5 * (k[1:, None] - k[:-1, None]) * x[None]).ravel()
    return np.sort(np.concatenate([k, inner]))


def _check_params(S: BSplineSurface) -> tuple[Array, NDArray[np.intp]]:
    k = _spans(S)
    n = 4 * S.degree[1] + 5
    t = np.linspace(0.0, 1.0, n)
    v = (k[:-1, None] + (k[1:, None] - k[:-1, None]) * t[None]).ravel()
    return v, np.repeat(np.arange(len(k) - 1), n)


@dataclass
class _Measures:
    g0: Array
    g1: Array
    g2: Array
    g3: Array
    fold: bool


def _angle(a: Array, b: Array) -> Array:
    """Angles between unit vectors (degrees), by atan2: exact near 0 where arccos loses 1e-8 rad."""
    return np.degrees(np.arctan2(np.linalg.norm(np.cross(a, b), axis=-1), np.einsum("mc,mc->m", a, b)))


def _rel(a: Array, b: Array, floor: float) -> Array:
    big = np.maximum(np.abs(a), np.abs(b))
    return np.where(big > floor, np.abs(a - b) / np.where(big > floor, big, 1.0), 0.0)


def _measure(S: BSplineSurface, target: _Target, v: Array, r: int, size: float,
             before: BSplineSurface | None = None) -> _Measures:
    """G0 distance, G1 angle (deg), relative G2 and G3 jumps across the side at parameters ``v``."""
    u0 = S.knots[0][S.degree[0]]
    D = S.derivatives(np.full_like(v, u0), v, 3 if r >= 3 else 2)
    tg = target.at_near(D[:, 0, 0], S, v) if isinstance(target, SurfaceSide) else target.at(D[:, 0, 0])
    Su, Sv = D[:, 1, 0], D[:, 0, 1]
    tau = _unit(Sv)
    nS = _unit(np.cross(Su, Sv))
    bS = _unit(Su - np.einsum("mc,mc->m", Su, tau)[:, None] * tau)
    if tg.inward is not None:
        bT = _unit(tg.inward - np.einsum("mc,mc->m", tg.inward, tau)[:, None] * tau)
        g1 = _angle(bS, -bT)
        fold = bool(np.any(g1 > 90.0))
    else:
        g1 = _angle(nS, tg.N)
        g1 = np.minimum(g1, 180.0 - g1)
        fold = False
        if before is not None:
            Db = before.derivatives(np.full_like(v, u0), v, 1)
            tb = _unit(Db[:, 0, 1])
            b0 = Db[:, 1, 0] - np.einsum("mc,mc->m", Db[:, 1, 0], tb)[:, None] * tb
            fold = bool(np.any(np.einsum("mc,mc->m", b0, bS) < 0))
    g2 = g3 = np.full_like(v, np.nan)
    if tg.H2 is not None:
        sgn = np.where(np.einsum("mc,mc->m", nS, tg.N) < 0, -1.0, 1.0)[:, None]
        nO = nS * sgn
        E = np.stack([tau, np.cross(nO, tau)], axis=1)
        H2, H3 = height_jets(D, nO, E)
        floor = tolerances.CONTINUITY_CURVATURE_FLOOR / size
        g2 = _rel(H2[:, 1, 1], tg.H2[:, 1, 1], floor)
        if r >= 3 and H3 is not None and tg.H3 is not None:
            # the cross direction of the target's frame may be the opposite of ours: h''' is odd
            s3 = np.sign(np.einsum("mc,mc->m", tg.E[:, 1], E[:, 1]))
            g3 = _rel(H3[:, 1, 1, 1], s3 * tg.H3[:, 1, 1, 1], floor / size)
    return _Measures(np.linalg.norm(D[:, 0, 0] - tg.P, axis=1), g1, g2, g3, fold)


def _max(a: Array) -> float:
    return float(np.max(a)) if a.size and np.any(np.isfinite(a)) and not np.all(np.isnan(a)) else float("nan")


# ---- the match ------------------------------------------------------------------------------------

@dataclass(frozen=True)
class _Tols:
    g0: float
    g1: float
    g2: float


def _bad(m: _Measures, r: int, tol: _Tols) -> NDArray[np.bool_]:
    bad = m.g0 > tol.g0
    if r >= 1:
        bad |= m.g1 > tol.g1
    if r >= 2:
        bad |= np.nan_to_num(m.g2) > tol.g2
    return bad


def _rows_for_preserve(S: BSplineSurface, r: int, o: int, refine: bool, side: str) -> tuple[BSplineSurface, int]:
    """Insert u-knots until the rows the match moves (``0..r``) and the rows ``preserve_opposite``
    holds (the last ``o + 1``) are apart."""
    need = r + o + 2
    added = 0
    while S.n_poles[0] < need:
        if not refine:
            raise ConstraintError(
                f"match on side {side!r}: G{r} moves {r + 1} pole rows and preserve_opposite holds {o + 1}, "
                f"but the surface has only {S.n_poles[0]} rows across the side; allow refine=True or "
                f"preserve less")
        k = np.unique(S.knots[0][S.degree[0]: len(S.knots[0]) - S.degree[0]])
        i = int(np.argmax(np.diff(k)))
        S = S.insert_knot(0.5 * (k[i] + k[i + 1]), direction="u")
        added += 1
    return S, added


def _target_knots(S: BSplineSurface, target: _Target) -> Array:
    """Parameters on the side of ``S`` that correspond to the target side's interior knots."""
    if isinstance(target, _AverageSide):
        return target.knots(S)
    if not isinstance(target, SurfaceSide):
        return np.empty(0)
    c = target.curve
    kn = np.unique(c.knots[c.degree + 1: len(c.knots) - c.degree - 1])
    return target.to_side(S, kn) if kn.size else kn


def _new_knots(S: BSplineSurface, cand: Array) -> Array:
    k = _spans(S)
    span = k[-1] - k[0]
    cand = np.unique(cand[(cand > k[0] + 1e-9 * span) & (cand < k[-1] - 1e-9 * span)])
    if cand.size == 0:
        return cand
    near = np.min(np.abs(cand[:, None] - k[None]), axis=1) > 1e-9 * span
    return cand[near]


def _match_canonical(S: BSplineSurface, target: _Target, r: int, o: int, tol: _Tols,
                     refine: bool, size: float, side: str, max_poles: int = 0) -> tuple[BSplineSurface, BSplineSurface, int, _Measures, bool]:
    """Match side u0 of the clamped surface ``S``; returns (changed, refined original, knots added,
    measures at the check samples, met)."""
    p = S.degree[0]
    if p < r:
        raise ConstraintError(
            f"match on side {side!r}: G{r} needs degree >= {r} across the side, the surface has degree {p}; "
            f"raise it first (elevate_degree)")
    S, added = _rows_for_preserve(S, r, o, refine, side)
    rounds = tolerances.MATCH_MAX_ROUNDS
    for rnd in range(rounds + 1):
        x = min_norm_change(S, target, r, _solve_params(S), size)
        P = S.control_points.copy()
        P[: r + 1] += x
        new = BSplineSurface._trusted(S.degree, S.knots, P, S.weights)
        vc, span_of = _check_params(new)
        meas = _measure(new, target, vc, r, size, before=S)
        bad = _bad(meas, r, tol)
        if not bad.any() or not refine or rnd == rounds:
            break
        cand = _target_knots(S, target) if rnd == 0 else np.empty(0)
        ins = _new_knots(S, cand)
        if ins.size == 0:
            k = _spans(S)
            spans = np.unique(span_of[bad])
            ins = _new_knots(S, 0.5 * (k[spans] + k[spans + 1]))
        if ins.size == 0 or S.n_poles[1] + ins.size > (max_poles or tolerances.MATCH_MAX_POLES):
            break
        S = S.refine(ins, direction="v")
        added += int(ins.size)
    if meas.fold:
        raise ConstraintError(
            f"match on side {side!r}: the matched surface folds back over the target (its side runs into the "
            f"target instead of away from it); the two surfaces overlap rather than meet")
    return new, S, added, meas, not bool(_bad(meas, r, tol).any())


def _check_choice(value: object, choices: dict[str, int] | tuple[str, ...], name: str) -> str:
    if not isinstance(value, str):
        raise ArgumentTypeError(f"{name}: expected one of {', '.join(choices)}, got {type(value).__name__}")
    if value not in choices:
        raise UnknownNameError(f"{name}: expected one of {', '.join(choices)}, got {value!r}")
    return value


def _check_tol(value: object, name: str, default: float) -> float:
    if value is None:
        return default
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)):
        raise ArgumentTypeError(f"{name}: expected a number, got {type(value).__name__}")
    x = float(value)
    if not (np.isfinite(x) and x > 0):
        raise InvalidGeometryError(f"{name}: expected a finite number > 0, got {value!r}")
    return x


def pole_size(*surfaces: BSplineSurface) -> float:
    """The diagonal of the poles' bounding box of ``surfaces`` together (1 where it is 0): the size
    that the matches' relative tolerances scale with."""
    P = np.concatenate([s.control_points.reshape(-1, s.dim) for s in surfaces])
    return float(np.linalg.norm(P.max(axis=0) - P.min(axis=0))) or 1.0


def _sides_by_bound(surface: BSplineSurface, points: Array) -> list[tuple[float, int, str, SurfaceSide]]:
    """The sides of ``surface`` as ``(bound, index in SIDES, side, SurfaceSide)``, in the order of
    ``bound``: a lower bound of the largest distance from ``points`` to the side, their largest
    distance to the bounding box of the side's poles (the side lies in their convex hull; 0 where
    a weight is not positive). A side whose bound exceeds the best distance found need not be
    searched: it cannot be nearer."""
    out = []
    for k, side in enumerate(SIDES):
        ss = SurfaceSide(_canonical(surface, side))
        C, w = ss.curve.control_points, ss.curve.weights
        if w is not None and np.any(w <= 0):
            bound = 0.0
        else:
            lo, hi = C.min(axis=0), C.max(axis=0)
            bound = float(np.max(np.linalg.norm(np.maximum(lo - points, 0.0) + np.maximum(points - hi, 0.0), axis=1)))
        out.append((bound, k, side, ss))
    return sorted(out, key=lambda x: (x[0], x[1]))


def _nearest_side(surface: BSplineSurface, points: Array, samples: int) -> tuple[str, float, Array, SurfaceSide]:
    """The side with the smallest largest distance to ``points`` (ties: the first in ``SIDES``),
    that distance, the points' feet on it and the side; sides ruled out by their bound are not
    searched."""
    best: tuple[float, int] = (np.inf, len(SIDES))
    found: tuple[str, Array, SurfaceSide] | None = None
    for bound, k, side, ss in _sides_by_bound(surface, points):
        if bound > best[0] * (1.0 + 1e-9):
            break
        t, d = ss.feet(points, samples=samples)
        key = (float(np.max(d)), k)
        if key < best:
            best, found = key, (side, t, ss)
    assert found is not None
    return found[0], best[0], found[1], found[2]


def _find_side(target: BSplineSurface, points: Array) -> str:
    """The side of ``target`` nearest to ``points`` (the largest distance, smallest over the sides)."""
    return _nearest_side(target, np.asarray(points, float), 65)[0]


def side_along(surface: BSplineSurface, points: Array, tol: float) -> tuple[str | None, float, float]:
    """The side of ``surface`` that ``points`` (m, 3) lie along, within ``tol``, and how well.

    Returns the side (``'u0'``, ``'u1'``, ``'v0'``, ``'v1'``) whose boundary curve has the smallest
    largest distance to the points, that distance, and the fraction of the side's parameter range
    the points' feet span (1: the points run from one end of the side to the other); the side is
    ``None`` where the distance is above ``tol`` (an edge that crosses the surface's interior, as a
    trimmed face's may).
    """
    best, best_d, t, ss = _nearest_side(surface, np.asarray(points, float), 401)
    lo, hi = ss.curve.domain
    return (best if best_d <= tol else None), best_d, float((t.max() - t.min()) / (hi - lo))


def surface_change(before: BSplineSurface, after: BSplineSurface) -> float:
    """How far ``after`` lies from ``before``: the largest distance at equal parameters on a grid of
    ``8 n + 1`` values per direction over ``after``'s domain (``n`` its poles), the measure of
    :attr:`MatchResult.max_change`. ``after``'s domain must lie in ``before``'s (the same surface
    changed, refined, or cut to a piece)."""
    (u0, u1), (v0, v1) = after.domain
    (a0, a1), (b0, b1) = before.domain
    us = np.clip(np.linspace(u0, u1, 8 * after.n_poles[0] + 1), a0, a1)
    vs = np.clip(np.linspace(v0, v1, 8 * after.n_poles[1] + 1), b0, b1)
    return float(np.max(np.linalg.norm(after.evaluate_grid(us, vs) - before.evaluate_grid(us, vs), axis=-1)))


class _AverageSide:
    """The mean of two surfaces' jets along their common edge, as a target for either of them.

    ``own`` is side u0 of the original surface, ``other`` the target's side; their parameters are
    paired as :meth:`SurfaceSide.corresponding` pairs them. At a parameter ``v`` of ``own``: the
    mean point, the normalised mean normal (the target's turned to agree), and both surfaces'
    ``H2`` and ``H3`` re-expressed in one frame perpendicular to that normal and averaged. With
    ``for_own=False`` the parameters asked about are ``other``'s."""

    def __init__(self, own: SurfaceSide, other: SurfaceSide, S: BSplineSurface, for_own: bool) -> None:
        self.own, self.other, self.S, self.for_own = own, other, S, for_own
        self.curve = own.curve if for_own else other.curve

    def _mean(self, v: Array) -> Jets:
        a = self.own._jets(v)
        b = self.other.corresponding(self.S, v)
        flip = np.where(np.einsum("mc,mc->m", a.N, b.N) < 0, -1.0, 1.0)
        N = _unit(a.N + b.N * flip[:, None])
        e1 = _unit(a.E[:, 0] - np.einsum("mc,mc->m", a.E[:, 0], N)[:, None] * N)
        E = np.stack([e1, np.cross(N, e1)], axis=1)
        forms = []
        for j, f in ((a, 1.0), (b, flip)):
            assert j.H2 is not None and j.H3 is not None
            M = np.einsum("mic,mjc->mij", E, j.E)  # new e_i . old e_j
            sg = np.asarray(f, float).reshape(-1, 1, 1)
            forms.append((np.einsum("mij,mjk,mlk->mil", M, j.H2 * sg, M),
                          np.einsum("mia,mjb,mkc,mabc->mijk", M, M, M, j.H3 * sg[..., None])))
        return Jets(0.5 * (a.P + b.P), N, E, 0.5 * (forms[0][0] + forms[1][0]), 0.5 * (forms[0][1] + forms[1][1]))

    def corresponding(self, X: BSplineSurface, v: Array) -> Jets:
        if self.for_own:
            return self._mean(v)
        return self._mean(self.other.to_side(self.S, v))

    def at(self, points: Array) -> Jets:
        return self._mean(self.own.feet(points)[0])

    def knots(self, X: BSplineSurface) -> Array:
        """Both sides' interior knots, as parameters of the surface being matched."""
        def interior(c: BSplineCurve) -> Array:
            return np.unique(c.knots[c.degree + 1: len(c.knots) - c.degree - 1])

        v = np.concatenate([interior(self.own.curve), self.other.to_side(self.S, interior(self.other.curve))])
        return v if self.for_own else self.other_param(v)

    def other_param(self, v: Array) -> Array:
        """``own``'s parameters ``v`` as parameters of ``other``'s side (the inverse pairing)."""
        lo, hi = self.other.curve.domain
        t = np.linspace(lo, hi, 2)
        a, b = self.other.to_side(self.S, t)
        return lo + (hi - lo) * (v - a) / (b - a)


def match_surface(surface: BSplineSurface, target: BSplineSurface | MatchTarget, side: str,
                  continuity: str = "G1", *, preserve_opposite: str = "G1", average: bool = False,
                  tol_g0: float | None = None, tol_g1_deg: float = 0.01, tol_g2_rel: float = 0.01,
                  refine: bool = True, max_poles: int | None = None) -> MatchResult:
    """Match ``surface`` along ``side`` to ``target`` with G0, G1, G2 or G3 continuity.

    Parameters
    ----------
    surface : BSplineSurface
        The surface to change (3-D; rational surfaces keep their weights).
    target : BSplineSurface or MatchTarget
        A surface one of whose sides runs along ``side`` (the nearest side is taken), or samples along
        a curve (:class:`MatchTarget`, for trimmed targets; G3 and ``average`` need a surface).
    side : {'u0', 'u1', 'v0', 'v1'}
        The side of ``surface``: ``'u0'`` is ``u = u_min``, and so on.
    continuity : {'G0', 'G1', 'G2', 'G3'}
        The order to reach; the surface's degree across the side must be at least the order.
    preserve_opposite : {'none', 'G0', 'G1', 'G2'}
        Keep the opposite side's position, tangent plane or curvature (its last 1, 2 or 3 pole rows
        are held; knots are inserted across the side when the rows would overlap).
    average : bool
        Move both surfaces to the mean of their positions, normals and curvatures along the edge.
    tol_g0 : float, optional
        Largest gap (model units); default ``tolerances.MATCH_G0_RTOL`` times the size of the pair.
    tol_g1_deg, tol_g2_rel : float
        Largest angle between the tangent planes (degrees) and relative curvature jump (fraction).
    refine : bool
        Insert knots until the tolerances hold (Rhino's "Refine match").
    max_poles : int, optional
        The most poles along the side refinement may reach (default
        ``tolerances.MATCH_MAX_POLES``); the match is returned as it stands there, ``met`` saying
        whether it holds.

    Returns
    -------
    MatchResult
        ``met`` says whether the tolerances hold; the measures say by how much.

    Raises
    ------
    ConstraintError
        The degree cannot carry the order, the rows cannot be moved without touching the preserved
        ones (``refine=False``), or the match folds the surface back over the target.
    InvalidGeometryError
        Bad arguments, named.
    """
    if not isinstance(surface, BSplineSurface):
        raise ArgumentTypeError(f"surface: expected a BSplineSurface, got {type(surface).__name__}")
    if not isinstance(target, (BSplineSurface, MatchTarget)):
        raise ArgumentTypeError(f"target: expected a BSplineSurface or a MatchTarget, got {type(target).__name__}")
    for s, name in ((surface, "surface"), (target, "target")):
        if isinstance(s, BSplineSurface) and s.dim != 3:
            raise InvalidGeometryError(f"{name}: needs a 3-D surface, this one has dim {s.dim}")
    side = _check_choice(side, SIDES, "side")
    r = CONTINUITIES[_check_choice(continuity, CONTINUITIES, "continuity")]
    o = _PRESERVE[_check_choice("none" if preserve_opposite is None else preserve_opposite, _PRESERVE,
                                "preserve_opposite")]
    if isinstance(target, MatchTarget):
        if average:
            raise InvalidGeometryError("average=True needs a surface target, not a MatchTarget")
        if r >= 3:
            raise InvalidGeometryError("continuity='G3' needs a surface target: a MatchTarget carries curvature only")
        if r >= 2 and target.cross_curvatures is None:
            raise InvalidGeometryError("continuity='G2' needs MatchTarget.cross_curvatures")
    size = pole_size(surface, *([target] if isinstance(target, BSplineSurface) else []))
    if isinstance(target, MatchTarget):
        P = target.points
        size = max(size, float(np.linalg.norm(P.max(axis=0) - P.min(axis=0))))
    tol = _Tols(_check_tol(tol_g0, "tol_g0", tolerances.MATCH_G0_RTOL * size),
                _check_tol(tol_g1_deg, "tol_g1_deg", 0.01), _check_tol(tol_g2_rel, "tol_g2_rel", 0.01))
    cap = 0
    if max_poles is not None:
        if isinstance(max_poles, bool) or not isinstance(max_poles, (int, np.integer)) or int(max_poles) < 1:
            raise InvalidGeometryError(f"max_poles: expected an integer >= 1, got {max_poles!r}")
        cap = int(max_poles)
    Sc = _canonical(surface, side)
    if isinstance(target, MatchTarget):
        tgt: SurfaceSide | SampledCurve = target._curve  # type: ignore[assignment]
        new, ref, added, meas, met = _match_canonical(Sc, tgt, r, o, tol, refine, size, side, cap)
        out_target: BSplineSurface | MatchTarget = target
    else:
        tside = _find_side(target, Sc.evaluate(np.full(17, Sc.knots[0][Sc.degree[0]]),
                                                 np.linspace(*Sc.domain[1], 17)))
        Tc = _canonical(target, tside)
        if not average:
            new, ref, added, meas, met = _match_canonical(Sc, SurfaceSide(Tc), r, o, tol, refine, size, side, cap)
            out_target = target
        else:
            own, other = SurfaceSide(Sc), SurfaceSide(Tc)
            new, ref, added, _, _ = _match_canonical(Sc, _AverageSide(own, other, Sc, True), r, o, tol, refine,
                                                     size, side, cap)
            tnew, tref, tadded, _, _ = _match_canonical(Tc, _AverageSide(own, other, Sc, False), r, o, tol,
                                                        refine, size, tside, cap)
            added += tadded
            meas = _measure(new, SurfaceSide(tnew), _check_params(new)[0], r, size)
            met = not bool(_bad(meas, r, tol).any())
            out_target = _restore(tnew, tside)
            # the target moves too: its change counts as much as ours
            t_change = surface_change(tref, tnew)
            t_pole_change = float(np.max(np.linalg.norm(tnew.control_points - tref.control_points, axis=-1)))
    result = _restore(new, side)
    refined = _restore(ref, side)
    change = surface_change(refined, result)
    pole_change = float(np.max(np.linalg.norm(result.control_points - refined.control_points, axis=-1)))
    if average and not isinstance(target, MatchTarget):
        change, pole_change = max(change, t_change), max(pole_change, t_pole_change)
    return MatchResult(
        surface=result, target=out_target, g0_max=_max(meas.g0), g1_max_deg=_max(meas.g1),
        g2_max_rel=_max(meas.g2), g3_max_rel=_max(meas.g3), max_change=change, max_pole_change=pole_change,
        knots_added=added, met=met)
