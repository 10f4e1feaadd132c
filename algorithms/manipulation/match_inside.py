"""Match a surface G0 or G1 to a target along a curve inside it (a trimmed face's edge).

:func:`~occsurf.algorithms.manipulation.match_surface` matches a side of a surface. The faces of
solid modellers' STEP files are mostly trimmed across their surfaces: the edge between two faces is
a curve in the interior of each surface's parameter domain, and no pole row carries it. The
conditions are the same (course §4-7..4-12), written at the edge's parameters ``(u_k, v_k)`` on the
surface instead of on a side, and linear in the poles at fixed weights:

====  ===================================================================
G0    ``S(u_k, v_k) = P_k``                       (the target's points)
G1    ``N_k . S_u(u_k, v_k) = 0``, ``N_k . S_v(u_k, v_k) = 0``   (both partials in the target's tangent plane)
====  ===================================================================

The unknowns are the poles whose basis functions do not vanish at some ``(u_k, v_k)``; the change
is the minimum-norm solution of the conditions (each row divided by its norm, the same two
cut-offs as the side match). The poles beyond the curve move too: that part of the surface lies
outside the face's trim. With ``refine=True`` knots are inserted (Oslo, course §2-10) at the
middle of the u- and v-spans that hold a sample still outside the tolerances, for
``tolerances.MATCH_MAX_ROUNDS`` rounds and up to ``max_poles`` poles per direction; a span is
halved only while it holds ``2 (p + 1)`` samples, so that every basis function keeps conditions
(refined past the samples, the minimum-norm change leaves the poles between them where they were
and the surface kinks between the samples). The caller samples densely: a face's edge is checked
by OCC afterwards at points among the samples (:func:`occsurf.bridge.modeling.joints.assess_joint`).

G2 and G3 are not offered here (``match_surface`` carries them along sides). Posed at every sample
they fail: a tensor-product spline restricted to a curve that crosses its cells diagonally has the
freedom of a spline of degree ``p + q`` along it, so dense position and tangent-plane conditions pin
nearly every pole of the band that reaches the curve (rank 510 of 543 on a 36 x 36 bicubic with 161
samples), and a change of the curvature across it is left only directions that hardly reach the
samples (pole moves of 1e5). G2 needs its conditions posed in a spline space along the curve.

References
----------
R. Bartels, course notes C25 (SIGGRAPH 1991), §4-4..4-12 (minimum-norm change of the poles under
linear conditions at parameters).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import _validate as V
from .. import tolerances
from ..errors import ArgumentTypeError, InvalidGeometryError
from ..kernel.basis import basis_derivatives, find_span
from ..kernel.surface import BSplineSurface
from .linalg import ConstraintError
from .match_targets import MatchTarget
from .matching import CONTINUITIES, MatchResult, pole_size, surface_change
from .min_norm import robust_min_norm

__all__ = ["match_along"]

Array = NDArray[np.float64]


def _rows(S: BSplineSurface, uv: Array) -> tuple[NDArray[np.intp], Array, Array, Array]:
    """Per sample, the flat indices ``i * n_v + j`` of the ``(p+1)(q+1)`` poles that act there and
    their (rational) basis values and u-, v-derivatives, each shape ``(m, (p+1)(q+1))``."""
    (p, q), (U, Vk), (nu, nv) = S.degree, S.knots, S.n_poles
    u, v = uv[:, 0], uv[:, 1]
    su, sv = find_span(U, p, nu, u), find_span(Vk, q, nv, v)
    Du, Dv = basis_derivatives(U, p, su, u, 1), basis_derivatives(Vk, q, sv, v, 1)
    N = Du[:, 0, :, None] * Dv[:, 0, None, :]
    Nu = Du[:, 1, :, None] * Dv[:, 0, None, :]
    Nv = Du[:, 0, :, None] * Dv[:, 1, None, :]
    ii = su[:, None] - p + np.arange(p + 1)
    jj = sv[:, None] - q + np.arange(q + 1)
    flat = ii[:, :, None] * nv + jj[:, None, :]
    if S.weights is not None:
        w = S.weights[ii[:, :, None], jj[:, None, :]]
        W = np.einsum("kab,kab->k", N, w)[:, None, None]
        Wu = np.einsum("kab,kab->k", Nu, w)[:, None, None]
        Wv = np.einsum("kab,kab->k", Nv, w)[:, None, None]
        R = N * w / W
        N, Nu, Nv = R, (Nu * w - R * Wu) / W, (Nv * w - R * Wv) / W
    m = uv.shape[0]
    return flat.reshape(m, -1), N.reshape(m, -1), Nu.reshape(m, -1), Nv.reshape(m, -1)


def _dense(flat: NDArray[np.intp], vals: Array, cols: NDArray[np.intp]) -> Array:
    """The rows ``vals`` at the flat pole indices ``flat`` as a dense ``(m, len(cols))`` matrix over
    the poles ``cols`` (sorted)."""
    A = np.zeros((flat.shape[0], cols.size))
    A[np.arange(flat.shape[0])[:, None], np.searchsorted(cols, flat)] = vals
    return A


def _normals(S: BSplineSurface, uv: Array) -> tuple[Array, Array]:
    D = S.derivatives(uv[:, 0], uv[:, 1], 1)
    n = np.cross(D[:, 1, 0], D[:, 0, 1])
    return D[:, 0, 0], n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)


def _solve(S: BSplineSurface, uv: Array, P: Array, N: Array, r: int) -> tuple[NDArray[np.intp], Array]:
    """The poles that act at ``uv`` and their minimum-norm change ``(n_active, 3)`` for G0 (and G1
    when ``r == 1``) at those samples."""
    flat, R, Ru, Rv = _rows(S, uv)
    cols = np.unique(flat)
    A0, Au, Av = (_dense(flat, x, cols) for x in (R, Ru, Rv))
    D = S.derivatives(uv[:, 0], uv[:, 1], r)
    m, n = uv.shape[0], cols.size
    F = [(D[:, 0, 0] - P).ravel()]
    J = [np.einsum("ka,cd->kcad", A0, np.eye(3)).reshape(3 * m, 3 * n)]
    if r >= 1:
        F += [np.einsum("kc,kc->k", N, D[:, 1, 0]), np.einsum("kc,kc->k", N, D[:, 0, 1])]
        J += [np.einsum("ka,kc->kac", Au, N).reshape(m, 3 * n), np.einsum("ka,kc->kac", Av, N).reshape(m, 3 * n)]
    x = robust_min_norm(np.concatenate(J), -np.concatenate(F))
    return cols, x.reshape(n, 3)


def _mid_knots(knots: Array, degree: int, n_poles: int, t: Array, bad: NDArray[np.bool_]) -> Array:
    """Midpoints of the spans holding a sample ``t[bad]`` that hold at least ``2 (degree + 1)``
    samples of ``t``: each half keeps about ``degree + 1`` conditions, so that no basis function is
    left without a sample (it would stay where it was while its neighbours move)."""
    s = find_span(knots, degree, n_poles, t)
    count = np.bincount(s, minlength=n_poles)
    cand = np.unique(s[bad])
    cand = cand[count[cand] >= 2 * (degree + 1)]
    span = knots[n_poles] - knots[degree]
    cand = cand[(knots[cand + 1] - knots[cand]) > 1e-9 * span]
    return 0.5 * (knots[cand] + knots[cand + 1])


def match_along(surface: BSplineSurface, target: MatchTarget, uv: ArrayLike, continuity: str = "G1", *,
                tol_g0: float | None = None, tol_g1_deg: float = 0.01, refine: bool = True,
                max_poles: int | None = None) -> MatchResult:
    """Match ``surface`` to ``target`` along a curve inside it, G0 or G1, by the least pole change.

    Parameters
    ----------
    surface : BSplineSurface
        The surface to change (3-D; a rational one keeps its weights).
    target : MatchTarget
        The target's points and normals along the curve (``cross_curvatures`` are not used).
    uv : array_like, shape (m, 2)
        The curve's parameters on ``surface`` at the target's points, in the same order (for a
        face's edge: its p-curve on the face at the parameters where the target was sampled).
    continuity : {'G0', 'G1'}
    tol_g0 : float, optional
        Largest distance between the surface and the target's points (model units); default
        ``tolerances.MATCH_G0_RTOL`` times the size of the surface.
    tol_g1_deg : float
        Largest angle between the surface's normal and the target's (degrees).
    refine : bool
        Insert knots near the samples that miss (both directions) until the tolerances hold.
    max_poles : int, optional
        The most poles per direction refinement may reach (default ``tolerances.MATCH_MAX_POLES``).

    Returns
    -------
    MatchResult
        ``g2_max_rel`` and ``g3_max_rel`` are NaN; ``target`` is ``target``.

    Raises
    ------
    ConstraintError
        The change would turn the surface's normal over at a sample (the surface folds onto the
        other side of the target).
    InvalidGeometryError
        Bad arguments (named), or G2/G3 asked.
    """
    if not isinstance(surface, BSplineSurface):
        raise ArgumentTypeError(f"surface: expected a BSplineSurface, got {type(surface).__name__}")
    if not isinstance(target, MatchTarget):
        raise ArgumentTypeError(f"target: expected a MatchTarget, got {type(target).__name__}")
    if surface.dim != 3:
        raise InvalidGeometryError(f"surface: needs a 3-D surface, this one has dim {surface.dim}")
    if continuity not in CONTINUITIES:
        raise InvalidGeometryError(f"continuity: expected one of {', '.join(CONTINUITIES)}, got {continuity!r}")
    r = CONTINUITIES[continuity]
    if r >= 2:
        raise InvalidGeometryError(f"continuity={continuity!r} along a curve inside the surface is not supported "
                                   "(G0 and G1 are; G2 and G3 need the curve along a side: match_surface)")
    P, N = np.asarray(target.points), np.asarray(target.normals)
    UV = V.as_finite_array(uv, "uv")
    if UV.shape != (P.shape[0], 2):
        raise InvalidGeometryError(f"uv: expected shape ({P.shape[0]}, 2), one pair per target point, got {UV.shape}")
    (u0, u1), (v0, v1) = surface.domain
    UV = np.stack([V.check_parameters(UV[:, 0], u0, u1, "uv[:, 0]"), V.check_parameters(UV[:, 1], v0, v1, "uv[:, 1]")], 1)
    size = max(pole_size(surface), float(np.linalg.norm(np.ptp(P, axis=0))))
    t0 = tolerances.MATCH_G0_RTOL * size if tol_g0 is None else float(tol_g0)
    if not (np.isfinite(t0) and t0 > 0) or not (np.isfinite(tol_g1_deg) and tol_g1_deg > 0):
        raise InvalidGeometryError(f"tol_g0, tol_g1_deg: expected positive numbers, got {tol_g0!r}, {tol_g1_deg!r}")
    cap = tolerances.MATCH_MAX_POLES if max_poles is None else int(max_poles)
    if cap < 1:
        raise InvalidGeometryError(f"max_poles: expected an integer >= 1, got {max_poles!r}")
    _, n_before = _normals(surface, UV)
    side = np.where(np.einsum("kc,kc->k", n_before, N) < 0, -1.0, 1.0)  # the target's normals turned to ours
    S, added = surface, 0
    for rnd in range(tolerances.MATCH_MAX_ROUNDS + 1):
        cols, x = _solve(S, UV, P, N, r)
        Q = S.control_points.reshape(-1, 3).copy()
        Q[cols] += x
        new = BSplineSurface._trusted(S.degree, S.knots, Q.reshape(S.control_points.shape), S.weights)
        X, n = _normals(new, UV)
        g0 = np.linalg.norm(X - P, axis=1)
        c = side * np.einsum("kc,kc->k", n, N)
        g1 = np.degrees(np.arctan2(np.linalg.norm(np.cross(n, N), axis=1), c)) if r >= 1 else np.zeros(len(P))
        bad = (g0 > t0) | (g1 > tol_g1_deg)
        if not bad.any() or not refine or rnd == tolerances.MATCH_MAX_ROUNDS:
            break
        (p, q), (U, Vk), (nu, nv) = S.degree, S.knots, S.n_poles
        ku, kv = _mid_knots(U, p, nu, UV[:, 0], bad), _mid_knots(Vk, q, nv, UV[:, 1], bad)
        if (ku.size == 0 and kv.size == 0) or nu + ku.size > cap or nv + kv.size > cap:
            break
        if ku.size:
            S = S.refine(ku, direction="u")
        if kv.size:
            S = S.refine(kv, direction="v")
        added += int(ku.size + kv.size)
    if np.any(c <= 0.0):
        raise ConstraintError("match along the curve: the change turns the surface's normal over at "
                              f"{int(np.sum(c <= 0.0))} samples (it would fold onto the other side of the target)")
    pole_change = float(np.max(np.linalg.norm(new.control_points - S.control_points, axis=-1)))
    return MatchResult(surface=new, target=target, g0_max=float(g0.max()), g1_max_deg=float(g1.max()),
                       g2_max_rel=float("nan"), g3_max_rel=float("nan"), max_change=surface_change(S, new),
                       max_pole_change=pole_change, knots_added=added, met=not bool(bad.any()))
