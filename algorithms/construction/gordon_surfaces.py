r"""Gordon surfaces through networks of u- and v-curves (course §6-22..6-25; W. J. Gordon,
"Spline-blended surface interpolation through curve networks", J. Math. Mech. 18 (1969)).

:func:`gordon` returns ONE tensor-product :class:`BSplineSurface` equal to the Boolean sum
:math:`P_1 \oplus P_2 = P_1 + P_2 - P_1 P_2` of the spline interpolation projector across v (the
loft of the u-curves) and across u (the loft of the v-curves); :math:`P_1 P_2` is the
tensor-product interpolant of the intersection points. Every step is an exact B-spline operation
(degree elevation, knot refinement, adding nets), so the surface interpolates the network to the
round-off of the banded interpolation solves (~1e-13 relative), provided the network is
consistent. Rational networks: see :mod:`occsurf.algorithms.construction.coons_patches` (homogeneous construction when
the curves meet in homogeneous space, else polynomial approximations within ``approx_tol``).
Tolerances: ``NETWORK_TOLERANCE``, ``APPROXIMATION_TOLERANCE``, ``HOMOGENEOUS_WEIGHT_RTOL`` and the
``GORDON_`` limits of :mod:`occsurf.algorithms.tolerances`, read at call time.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import cKDTree

from .. import _validate as V
from .. import tolerances
from ..errors import InvalidGeometryError
from ..fitting.interpolation import averaged_knots, interpolate_values
from ..kernel.compat import make_compatible
from ..kernel.curve import BSplineCurve
from ..kernel.surface import BSplineSurface
from ._common import Net, check_curves, homogeneous_poles, resolve_tolerance, surface_from_net, unify_nets
from .rational_approximation import polynomial_approximation

__all__ = ["gordon", "network_parameters"]

Array = NDArray[np.float64]


def _samples(c: BSplineCurve) -> Array:
    br = np.unique(c.knots[c.degree: c.n_poles + 1])
    k = max(tolerances.GORDON_SAMPLES_PER_SPAN, -(-16 // (br.shape[0] - 1)))
    f = np.linspace(0.0, 1.0, k + 1)[:-1]
    return np.r_[(br[:-1, None] + f * np.diff(br)[:, None]).ravel(), br[-1]]


def network_parameters(u_curves: Sequence[BSplineCurve], v_curves: Sequence[BSplineCurve]) -> tuple[Array, Array, Array]:
    """Closest-point parameters of every u-curve / v-curve pair.

    For each pair ``(i, j)`` the parameters ``(s, t)`` minimising ``|u_curves[i](s) -
    v_curves[j](t)|``: a grid search over samples of both curves, then Gauss-Newton (vectorised
    over all pairs; loops run over curves, not points). With several local minima (closed
    curves, curves crossing twice) the sampled global minimum is refined. The search reads
    ``GORDON_SAMPLES_PER_SPAN``, ``GORDON_STARTS`` and ``GORDON_NEWTON_STEPS`` of
    :mod:`occsurf.algorithms.tolerances`.

    Returns
    -------
    s : ndarray, shape (m, n)
        Parameter on ``u_curves[i]`` (a u value).
    t : ndarray, shape (m, n)
        Parameter on ``v_curves[j]`` (a v value).
    dist : ndarray, shape (m, n)
        The distances at ``(s, t)``.
    """
    A = check_curves(u_curves, "u_curves", 1)
    B = check_curves(v_curves, "v_curves", 1)
    m, n = len(A), len(B)
    sa = [_samples(a) for a in A]
    sb = [_samples(b) for b in B]
    pa = [a.evaluate(x) for a, x in zip(A, sa)]
    pb = [b.evaluate(x) for b, x in zip(B, sb)]
    K = int(tolerances.GORDON_STARTS)
    s = np.empty((m, n, K))
    t = np.empty((m, n, K))
    trees = [cKDTree(p) for p in pb]  # nearest v-curve sample of every u-curve sample: O(N log N) a pair
    for j, tree in enumerate(trees):
        for i in range(m):
            dd, near = tree.query(pa[i])
            best = np.argpartition(dd, K - 1)[:K] if dd.shape[0] > K else np.arange(dd.shape[0])
            best = np.r_[best, np.full(K - best.shape[0], best[0])]
            s[i, j], t[i, j] = sa[i][best], sb[j][near[best]]
    for _ in range(int(tolerances.GORDON_NEWTON_STEPS)):
        Da = np.stack([a.derivatives(s[i], 1) for i, a in enumerate(A)])  # (m, n, K, 2, d)
        Db = np.stack([b.derivatives(t[:, j], 1) for j, b in enumerate(B)], axis=1)
        F = Da[..., 0, :] - Db[..., 0, :]
        J = np.stack([Da[..., 1, :], -Db[..., 1, :]], axis=-1)  # (m, n, K, d, 2)
        JtJ = np.einsum("...ka,...kb->...ab", J, J)
        g = np.einsum("...ka,...k->...a", J, F)
        reg = (1e-14 * np.trace(JtJ, axis1=-2, axis2=-1) + 1e-300)[..., None, None] * np.eye(2)
        step = np.linalg.solve(JtJ + reg, g[..., None])[..., 0]
        s_new = np.stack([np.clip(s[i] - step[i, ..., 0], *a.domain) for i, a in enumerate(A)])
        t_new = np.stack([np.clip(t[:, j] - step[:, j, ..., 1], *b.domain) for j, b in enumerate(B)], axis=1)
        done = np.array_equal(s_new, s) and np.array_equal(t_new, t)
        s, t = s_new, t_new
        if done:
            break
    pa_ = np.stack([a.evaluate(s[i]) for i, a in enumerate(A)])
    pb_ = np.stack([b.evaluate(t[:, j]) for j, b in enumerate(B)], axis=1)
    dist = np.linalg.norm(pa_ - pb_, axis=-1)  # (m, n, K)
    k = np.argmin(dist, axis=-1)[..., None]
    take = lambda x: np.take_along_axis(x, k, axis=-1)[..., 0]  # noqa: E731
    return take(s), take(t), take(dist)


def _closed(c: BSplineCurve, tol: float) -> bool:
    lo, hi = c.domain
    ends = c.evaluate(np.array([lo, hi]))
    return bool(np.linalg.norm(ends[1] - ends[0]) <= tol)


def _unwrap_seam(p: Array, dom: tuple[float, float], closed: bool) -> Array:
    """On closed curves a crossing at the seam has two parameters; the closest-point search may
    return either. The first crossing found at the domain's end belongs at its start, the last
    found at its start belongs at its end (a network closed around a cylinder: the first and last
    curves coincide)."""
    if not closed or p.shape[0] < 2:
        return p
    p = p.copy()
    lo, hi = dom
    eps = 1e-9 * (hi - lo)
    if p[-1] - lo <= eps and p[-2] > p[-1]:
        p[-1] = hi
    if hi - p[0] <= eps and p[1] < p[0]:
        p[0] = lo
    return p


def _increasing(x: Array, name: str, what: str) -> None:
    if np.any(np.diff(x) <= 0):
        raise InvalidGeometryError(
            f"{name}: expected strictly increasing parameters ({what}), got {np.array2string(x, precision=6)}"
        )


def _cross_knots(params: Array, degree: int, domain: tuple[float, float]) -> Array:
    kn = averaged_knots(params, degree)
    kn[: degree + 1], kn[-(degree + 1):] = domain
    return kn


def gordon(u_curves: Sequence[BSplineCurve], v_curves: Sequence[BSplineCurve], *,
           u_params: ArrayLike | None = None, v_params: ArrayLike | None = None,
           degree: tuple[int, int] = (3, 3),
           cross_knots: tuple[ArrayLike | None, ArrayLike | None] = (None, None),
           tol: float | None = None, approx_tol: float | None = None) -> BSplineSurface:
    r"""Gordon surface through a network of u- and v-curves (course §6-22..6-25), exactly.

    The Boolean sum ``P1 + P2 - P12`` where ``P1`` interpolates the u-curves across v, ``P2`` the
    v-curves across u, and ``P12`` the intersection points in both directions, with the same
    spline interpolation operators (degree and knots) across u in ``P2`` and ``P12`` and across
    v in ``P1`` and ``P12``. The three are made compatible (degree elevation, knot refinement)
    and their nets added: one :class:`BSplineSurface` equal to the Boolean sum.

    Parameters
    ----------
    u_curves : sequence of m >= 2 BSplineCurve
        ``u_curves[i](u) = S(u, v_params[i])``, ordered by increasing v; made compatible (their
        common u domain if they share one, else ``[0, 1]``).
    v_curves : sequence of n >= 2 BSplineCurve
        ``v_curves[j](v) = S(u_params[j], v)``, ordered by increasing u; likewise in v.
    u_params : array_like, shape (n,), optional
        The u value of each v-curve, strictly increasing, inside the u-curves' domain. Default:
        computed (:func:`network_parameters`): the parameter where the u-curves cross v-curve j,
        which must be the same on every u-curve (to ``tol`` in space).
    v_params : array_like, shape (m,), optional
        The v value of each u-curve, likewise.
    degree : (int, int)
        Degrees of the interpolation across u (between v-curves) and across v; each lowered to
        the number of curves minus 1.
    cross_knots : (array_like or None, array_like or None)
        Knot vectors of those interpolations (length ``n + degree[0] + 1``, resp. ``m + degree[1]
        + 1``, clamped to the curves' domains). Default: averaging of the parameters (The NURBS
        Book eq. 9.8) with the ends moved to the domain ends.
    tol : float, optional
        Largest distance between ``u_curves[i](u_params[j])`` and ``v_curves[j](v_params[i])``
        (default ``tolerances.NETWORK_TOLERANCE``). The intersection point used is their mean: the
        surface then reproduces each curve up to the interpolant of half the gaps.
    approx_tol : float, optional
        For rational networks that do not meet in homogeneous coordinates: distance within which
        rational curves are replaced by polynomial ones (default ``tolerances.APPROXIMATION_TOLERANCE``).

    Returns
    -------
    BSplineSurface
        ``S(u, v_params[i]) == u_curves[i](u)`` and ``S(u_params[j], v) == v_curves[j](v)`` over
        the whole domains (to ~1e-13 relative on consistent networks). Degree ``(max(p_u,
        degree[0]), max(q_v, degree[1]))``.

    Raises
    ------
    InvalidGeometryError
        Fewer than 2 curves in a family, mixed dimensions, parameters not increasing or outside
        the domain, a u-curve and a v-curve that do not meet within ``tol`` (the message names
        both and the gap), or a network that is not consistent: the crossings of v-curve j lie at
        different u on different u-curves (Gordon surfaces need one parameter per curve).

    Notes
    -----
    **Reproduction.** ``I - P1 ⊕ P2 = (I - P1)(I - P2)``, so a surface ``F`` whose iso-curves
    form the network is reproduced whenever one projector reproduces it: e.g. ``P1 F = F`` when
    F's v spline space (degree, knots) is contained in the interpolation space across v and the
    Schoenberg–Whitney condition holds: pass ``cross_knots=(None, F.knots[1])`` and ``v_params``
    = F's v Greville abscissae, or take F polynomial in v (one v span) of degree <= ``degree[1]``
    with at least ``degree[1] + 1`` u-curves.
    """
    tol = resolve_tolerance(tol, tolerances.NETWORK_TOLERANCE)
    atol = resolve_tolerance(approx_tol, tolerances.APPROXIMATION_TOLERANCE, "approx_tol")
    A, B, pu, qv = _check_network(u_curves, v_curves, degree)
    A, B = make_compatible(A), make_compatible(B)
    params = (u_params, v_params)
    rational = A[0].is_rational or B[0].is_rational
    net = _gordon_net(A, B, params, (pu, qv), cross_knots, tol, rational)
    if net is None:
        # a rational network without an exact NURBS Gordon surface: polynomial approximations
        A, B, tol = _polynomial_network(A, B, tol, atol)
        net = _gordon_net(A, B, params, (pu, qv), cross_knots, tol, False)
        rational = False
        if net is None:  # only a rational network can lack a net
            raise RuntimeError("gordon_surface: no net for the polynomial approximation of the network")
    return surface_from_net(*net, rational, "gordon")


def _check_network(u_curves: object, v_curves: object,
                   degree: object) -> tuple[list[BSplineCurve], list[BSplineCurve], int, int]:
    """The curve families (at least 2 each, one dimension) and the cross degrees ``(pu, qv)``,
    each lowered to the number of curves it interpolates minus 1."""
    A = check_curves(u_curves, "u_curves")
    B = check_curves(v_curves, "v_curves")
    dims = {c.dim for c in A + B}
    if len(dims) != 1:
        raise InvalidGeometryError(f"u_curves, v_curves: all curves must have one dimension, got {sorted(dims)}")
    if not isinstance(degree, (tuple, list)) or len(degree) != 2:
        raise InvalidGeometryError(f"degree: expected a pair (across u, across v), got {degree!r}")
    pu = min(V.as_degree(degree[0], "degree[0]"), len(B) - 1)
    qv = min(V.as_degree(degree[1], "degree[1]"), len(A) - 1)
    return A, B, pu, qv


def _polynomial_network(A: list[BSplineCurve], B: list[BSplineCurve], tol: float,
                        approx_tol: float) -> tuple[list[BSplineCurve], list[BSplineCurve], float]:
    """Polynomial approximations (within ``approx_tol``) of the curves, made compatible again, and
    the crossing tolerance widened by the largest measured errors of both families (each curve
    moves by its error, so the crossings may open by up to their sum)."""
    fa = [polynomial_approximation(c, approx_tol) for c in A]
    fb = [polynomial_approximation(c, approx_tol) for c in B]
    tol += max(e for _, e in fa) + max(e for _, e in fb)
    return make_compatible([c for c, _ in fa]), make_compatible([c for c, _ in fb]), tol


def _gordon_net(A: list[BSplineCurve], B: list[BSplineCurve], params: tuple[ArrayLike | None, ArrayLike | None],
                degrees: tuple[int, int], cross_knots: tuple[ArrayLike | None, ArrayLike | None], tol: float,
                rational: bool) -> Net | None:
    """The net ``P1 + P2 - P12`` of compatible families ``A`` (u-curves) and ``B`` (v-curves),
    homogeneous if ``rational``; ``None`` for a rational network without an exact NURBS form (the
    curves do not meet in homogeneous space, or the homogeneous sum has a weight ``<= 0``)."""
    pu, qv = degrees
    udom, vdom = A[0].domain, B[0].domain
    up, vp = _network_params(A, B, *params, udom, vdom, tol)
    Q = _crossing_points(A, B, up, vp, tol)  # checks that the network is consistent
    if rational:
        Qh = _homogeneous_crossing_points(A, B, up, vp)  # the same points, in homogeneous space
        if Qh is None:
            return None  # the curves do not meet in homogeneous space
        Q = Qh
    Ku = _cross_or_default(cross_knots[0], up, pu, udom, "cross_knots[0]")
    Kv = _cross_or_default(cross_knots[1], vp, qv, vdom, "cross_knots[1]")
    terms = _gordon_terms(A, B, (up, vp), Q, degrees, (Ku, Kv), rational)
    deg, kn, (S1, S2, S12) = unify_nets(terms)
    H = S1 + S2 - S12
    if rational and not np.all(H[..., -1] > 0):
        return None  # the homogeneous Boolean sum has non-positive weights: no exact NURBS form
    return deg, kn, H


def _crossing_points(A: list[BSplineCurve], B: list[BSplineCurve], up: Array, vp: Array, tol: float) -> Array:
    """The intersection points ``(m, n, d)``: the mean of ``A[i](up[j])`` and ``B[j](vp[i])``.

    Raises
    ------
    InvalidGeometryError
        The two are more than ``tol`` apart somewhere (an inconsistent network; the message names
        both curves, the parameters and the gap).
    """
    Pa = np.stack([a.evaluate(up) for a in A])  # (m, n, d): u_curves[i](u_j)
    Pb = np.stack([b.evaluate(vp) for b in B], axis=1)  # (m, n, d): v_curves[j](v_i)
    gap = np.linalg.norm(Pa - Pb, axis=-1)
    if gap.max() > tol:
        i, j = np.unravel_index(int(np.argmax(gap)), gap.shape)
        raise InvalidGeometryError(
            f"u_curves[{i}], v_curves[{j}]: the network is not consistent: u_curves[{i}](u_params[{j}]="
            f"{up[j]:.9g}) and v_curves[{j}](v_params[{i}]={vp[i]:.9g}) are {gap[i, j]:.3g} apart (tol={tol:g}); "
            "a Gordon surface needs every u-curve to cross v-curve j at the same u (and every v-curve "
            "to cross u-curve i at the same v): reparametrise the curves or pass consistent u_params/v_params"
        )
    return (Pa + Pb) / 2


def _homogeneous_crossing_points(A: list[BSplineCurve], B: list[BSplineCurve], up: Array, vp: Array) -> Array | None:
    """The homogeneous intersection points ``(m, n, d + 1)`` (mean of both curves' values), or
    ``None`` where the weights of the two curves differ (relative ``1e3 *
    tolerances.HOMOGENEOUS_WEIGHT_RTOL``): the curves do not meet in homogeneous space."""
    Ha = np.stack([_hnet_eval(a, up) for a in A])
    Hb = np.stack([_hnet_eval(b, vp) for b in B], axis=1)
    rtol = tolerances.HOMOGENEOUS_WEIGHT_RTOL * 1e3
    if not np.all(np.abs(Ha[..., -1] - Hb[..., -1]) <= rtol * np.maximum(Ha[..., -1], Hb[..., -1])):
        return None
    return (Ha + Hb) / 2


def _gordon_terms(A: list[BSplineCurve], B: list[BSplineCurve], params: tuple[Array, Array], Q: Array,
                  degrees: tuple[int, int], knots: tuple[Array, Array], rational: bool) -> list[Net]:
    """The three terms of the Boolean sum, as nets on their own knots: ``[P1, P2, P12]``.

    ``P1`` interpolates the u-curves ``A`` across v (``P1(u, vp[i]) = A[i](u)``), ``P2`` the
    v-curves ``B`` across u (``P2(up[j], v) = B[j](v)``), ``P12`` the intersection points ``Q``
    ``(m, n, k)`` in both directions (``P12(up[j], vp[i]) = Q[i, j]``); degrees ``(pu, qv)`` and
    knots ``(Ku, Kv)`` of the cross interpolation. Homogeneous poles if ``rational``.
    """
    (up, vp), (pu, qv), (Ku, Kv) = params, degrees, knots
    Ra = np.stack([homogeneous_poles(a, rational) for a in A])  # (m, nu, k)
    Rb = np.stack([homogeneous_poles(b, rational) for b in B])  # (n, nv, k)
    X1 = interpolate_values(vp, Ra, qv, Kv).transpose(1, 0, 2)  # (nu, m, k): across v
    X2 = interpolate_values(up, Rb, pu, Ku)  # (n, nv, k): across u
    X12 = interpolate_values(up, interpolate_values(vp, Q, qv, Kv).transpose(1, 0, 2), pu, Ku)  # (n, m, k)
    return [((A[0].degree, qv), (A[0].knots, Kv), X1),
            ((pu, B[0].degree), (Ku, B[0].knots), X2),
            ((pu, qv), (Ku, Kv), X12)]


def _hnet_eval(c: BSplineCurve, x: Array) -> Array:
    """Homogeneous values ``(w C, w)`` of a rational curve at ``x``."""
    return BSplineCurve._trusted(c.degree, c.knots, homogeneous_poles(c, True)).evaluate(x)


def _cross_or_default(kn: ArrayLike | None, params: Array, p: int, domain: tuple[float, float], name: str) -> Array:
    if kn is None:
        return _cross_knots(params, p, domain)
    t = V.check_knots(kn, p, params.shape[0], name)
    if not np.allclose([t[0], t[-1]], domain, rtol=0, atol=1e-12 * max(1.0, domain[1] - domain[0])) or \
            np.any(t[: p + 1] != t[0]) or np.any(t[-(p + 1):] != t[-1]):
        raise InvalidGeometryError(f"{name}: expected a clamped knot vector on the domain {domain}, got [{t[0]!r} .. {t[-1]!r}]")
    t = t.copy()
    t[: p + 1], t[-(p + 1):] = domain
    return t


def _network_params(A: list[BSplineCurve], B: list[BSplineCurve], u_params: ArrayLike | None,
                    v_params: ArrayLike | None, udom: tuple[float, float], vdom: tuple[float, float],
                    tol: float) -> tuple[Array, Array]:
    m, n = len(A), len(B)
    given: list[Array | None] = []
    for x, count, dom, name, what in ((u_params, n, udom, "u_params", "one per v-curve, in order of increasing u"),
                                      (v_params, m, vdom, "v_params", "one per u-curve, in order of increasing v")):
        if x is None:
            given.append(None)
            continue
        a = V.as_finite_array(x, name, ndim=1)
        if a.shape[0] != count:
            raise InvalidGeometryError(f"{name}: expected {count} values ({what}), got {a.shape[0]}")
        a = V.check_parameters(a, *dom, name=name)
        _increasing(a, name, what)
        given.append(a)
    up, vp = given
    if up is None or vp is None:
        s, t, dist = network_parameters(A, B)
        if dist.max() > tol:
            i, j = np.unravel_index(int(np.argmax(dist)), dist.shape)
            raise InvalidGeometryError(
                f"u_curves[{i}], v_curves[{j}]: the curves do not meet: closest distance {dist[i, j]:.3g} "
                f"at u={s[i, j]:.9g}, v={t[i, j]:.9g} (tol={tol:g})"
            )
        if up is None:
            up = _unwrap_seam(np.median(s, axis=0), udom, all(_closed(a, tol) for a in A))
            _increasing(up, "v_curves", "the u values where the v-curves cross the u-curves; order the v-curves by increasing u")
        if vp is None:
            vp = _unwrap_seam(np.median(t, axis=1), vdom, all(_closed(b, tol) for b in B))
            _increasing(vp, "u_curves", "the v values where the u-curves cross the v-curves; order the u-curves by increasing v")
    return up, vp
