"""Direct manipulation of tensor-product surfaces: drag a point, turn its tangent plane.

The curve method of course ch. 4 (Bartels & Beatty 1989) carried over to surfaces: every
position or partial-derivative property at ``(u, v)`` is linear in the net, so the edit is the
minimum-norm change of the movable poles that satisfies the requested properties (a window in the
u and v pole indices keeps it local, as OCC's ``Geom_BSplineSurface::MovePoint`` does).

:func:`drag_surface_point` runs in steps, each a private function with its own contract: the
basis rows at ``(u, v)`` (:func:`_surface_basis_rows`), the window (:func:`_window_ranges`), the
poles of the window that act there (:func:`_active_poles`), the linear conditions
(:func:`_edit_conditions`), their minimum-norm solution, checked (:func:`_min_norm_change`), and
for a requested normal the orientation of the result (:func:`_check_orientation`).

References
----------
R. H. Bartels, J. C. Beatty, "A technique for the direct manipulation of spline curves",
Graphics Interface '89 (1989); course notes C25, SIGGRAPH 1991, §4-4 and §4-7.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import _validate as V
from .. import tolerances
from ..errors import InvalidGeometryError
from ..kernel.basis import basis_derivatives, find_span
from ..kernel.rational import surface_quotient_rule
from ..kernel.surface import BSplineSurface
from .constraints import as_parameter, pole_index, pole_weights
from .linalg import ConstraintError, ConstraintFactor

__all__ = ["drag_surface_point"]

Array = NDArray[np.float64]


def _surface_basis_rows(surface: BSplineSurface, u: float, v: float) -> Array:
    """Rows of ``S, S_u, S_v`` at ``(u, v)`` over the flattened net, shape ``(3, n_u * n_v)``."""
    (p, q), (U, Vk), (nu, nv) = surface.degree, surface.knots, surface.n_poles
    ua, va = np.array([u]), np.array([v])
    su, sv = find_span(U, p, nu, ua), find_span(Vk, q, nv, va)
    Du = basis_derivatives(U, p, su, ua, 1)[0]  # (2, p+1)
    Dv = basis_derivatives(Vk, q, sv, va, 1)[0]  # (2, q+1)
    iu = su[0] - p + np.arange(p + 1)
    iv = sv[0] - q + np.arange(q + 1)
    T = np.einsum("ai,bj->abij", Du, Dv)  # (2, 2, p+1, q+1)
    if surface.weights is not None:
        A = (T * surface.weights[np.ix_(iu, iv)]).reshape(2, 2, -1)
        T = surface_quotient_rule(np.concatenate([A, A.sum(-1, keepdims=True)], -1)[None])[0]
    T = T.reshape(2, 2, p + 1, q + 1)
    G = np.zeros((3, nu, nv))
    G[0][np.ix_(iu, iv)] = T[0, 0]
    G[1][np.ix_(iu, iv)] = T[1, 0]
    G[2][np.ix_(iu, iv)] = T[0, 1]
    return G.reshape(3, nu * nv)


def _window_ranges(window: tuple[tuple[int, int], tuple[int, int]] | None,
                   n_poles: tuple[int, int]) -> tuple[tuple[int, int], tuple[int, int]]:
    """Validated inclusive pole ranges ``((i1, i2), (j1, j2))`` of ``window``; the whole net if ``None``.

    Parameters
    ----------
    window : ((int, int), (int, int)) or None
        0-based inclusive pole ranges in u and v, as :func:`drag_surface_point` takes them.
    n_poles : (int, int)
        ``(n_u, n_v)`` of the net.

    Raises
    ------
    InvalidGeometryError
        Naming ``window`` (or the offending entry ``window[a][b]``): not a pair of pairs, an index
        that is not an int or out of range, or an empty range (``i1 > i2`` or ``j1 > j2``).
    """
    nu, nv = n_poles
    if window is None:
        return (0, nu - 1), (0, nv - 1)
    try:
        (i1, i2), (j1, j2) = window
    except (TypeError, ValueError) as err:
        raise InvalidGeometryError(f"window: expected ((i1, i2), (j1, j2)), got {window!r}") from err
    i1, i2 = pole_index(i1, "window[0][0]", nu), pole_index(i2, "window[0][1]", nu)
    j1, j2 = pole_index(j1, "window[1][0]", nv), pole_index(j2, "window[1][1]", nv)
    if i1 > i2 or j1 > j2:
        raise InvalidGeometryError(f"window: empty window (({i1}, {i2}), ({j1}, {j2}))")
    return (i1, i2), (j1, j2)


def _active_poles(G: Array, n_poles: tuple[int, int], ranges: tuple[tuple[int, int], tuple[int, int]],
                  rows: list[int], label: str) -> NDArray[np.intp]:
    """Flat indices (u-major) of the window's poles that act on the requested properties at ``(u, v)``.

    A pole acts when its basis row is non-zero in one of ``rows`` of ``G`` (``0``: position,
    ``1``: ``S_u``, ``2``: ``S_v``); only these poles move, so the minimum-norm change is computed
    on the smallest system (the others would get a zero change anyway).

    Parameters
    ----------
    G : ndarray, shape (3, n_u * n_v)
        Rows of ``S, S_u, S_v`` from :func:`_surface_basis_rows`.
    n_poles : (int, int)
    ranges : ((int, int), (int, int))
        The window from :func:`_window_ranges`.
    rows : list of int
        The rows of ``G`` that the request constrains.
    label : str
        ``"(u=..., v=...)"`` for the error message.

    Returns
    -------
    ndarray of int, shape (k,), sorted, ``k >= 1``

    Raises
    ------
    ConstraintError
        No pole of the window acts at ``(u, v)``.
    """
    (i1, i2), (j1, j2) = ranges
    mask = np.zeros(n_poles, bool)
    mask[i1:i2 + 1, j1:j2 + 1] = True
    mov = np.nonzero(mask.ravel())[0]
    acts = np.any(G[np.ix_(np.asarray(rows, dtype=np.intp), mov)] != 0.0, axis=0)
    if not np.any(acts):
        raise ConstraintError(f"drag_surface_point: no pole of the window (({i1}, {i2}), ({j1}, {j2})) acts at {label}")
    return mov[acts]


def _edit_conditions(Ga: Array, inv_sw: Array, D0: Array, target: ArrayLike | None, du: ArrayLike | None,
                     dv: ArrayLike | None, normal: ArrayLike | None,
                     label: str) -> tuple[Array, Array, list[str], Array | None]:
    """The linear conditions ``J y = r`` of a surface edit, in the scaled unknowns ``y``.

    The change of the active poles is ``dP = y * inv_sw`` (pole-major, ``vec(dP)``), so that the
    minimum-norm ``y`` is the weighted minimum-norm ``dP``. Conditions, in this order: the position
    ``S(u, v) = target`` (``d`` rows; ``target=None`` keeps the point), ``S_u = du`` and
    ``S_v = dv`` (``d`` rows each, if given), then ``n . S_u = 0`` and ``n . S_v = 0`` for the unit
    ``normal`` (one row each, if given).

    Parameters
    ----------
    Ga : ndarray, shape (3, k)
        Rows of ``S, S_u, S_v`` restricted to the ``k`` active poles.
    inv_sw : ndarray, shape (k,)
        ``1 / sqrt(w)`` of the active poles' norm weights (ones without weights).
    D0 : ndarray, shape (3, d)
        ``S, S_u, S_v`` of the surface before the edit.
    target, du, dv : array_like, shape (d,), or None
    normal : array_like, shape (3,), or None
    label : str
        ``"(u=..., v=...)"``, part of every row name.

    Returns
    -------
    J : ndarray, shape (m, k * d)
    r : ndarray, shape (m,)
        The required change of each property.
    names : list of str, length m
        One name per row, for :class:`ConstraintError`.
    normal : ndarray, shape (3,), or None
        The unit normal requested.

    Raises
    ------
    InvalidGeometryError
        A vector of the wrong shape or not finite, a zero normal, or a normal on a surface that
        is not 3-D.
    """
    d = D0.shape[1]
    I = np.eye(d)
    blocks: list[Array] = []
    rhs: list[Array] = []
    names: list[str] = []

    def add(k: int, M: Array, r: Array, what: str) -> None:
        blocks.append(np.kron(Ga[k] * inv_sw, M))  # rows acting on vec(dP) (pole-major)
        rhs.append(r)
        names.extend(f"{what} [{j}]" for j in range(M.shape[0]))

    def vec(x: ArrayLike, name: str) -> Array:
        a = V.as_finite_array(x, name)
        if a.shape != (d,):
            raise InvalidGeometryError(f"{name}: expected shape ({d},), got {a.shape}")
        return a

    tgt = D0[0] if target is None else vec(target, "target")
    add(0, I, tgt - D0[0], f"position {label}")
    if du is not None:
        add(1, I, vec(du, "du") - D0[1], f"du {label}")
    if dv is not None:
        add(2, I, vec(dv, "dv") - D0[2], f"dv {label}")
    nrm = None
    if normal is not None:
        if d != 3:
            raise InvalidGeometryError(f"normal: needs a 3-D surface, this one has dim {d}")
        nrm = vec(normal, "normal")
        ln = np.linalg.norm(nrm)
        if not ln > 0:
            raise InvalidGeometryError("normal: expected a non-zero vector")
        nrm = nrm / ln
        add(1, nrm[None, :], -np.array([nrm @ D0[1]]), f"normal.S_u {label}")
        add(2, nrm[None, :], -np.array([nrm @ D0[2]]), f"normal.S_v {label}")
    return np.vstack(blocks), np.concatenate(rhs), names, nrm


def _min_norm_change(J: Array, r: Array, names: list[str], D0: Array) -> Array:
    """The minimum-norm ``y`` with ``J y = r``, checked to satisfy the conditions.

    Solved by :class:`ConstraintFactor` (pivoted QR, conflicts named by ``names``); the residual
    ``max |J y - r|`` must then be at most ``tolerances.LINEAR_CHECK_RTOL`` times
    ``max(1, max |D0|, max |r|)``.

    Parameters
    ----------
    J : ndarray, shape (m, k * d)
    r : ndarray, shape (m,)
    names : list of str, length m
    D0 : ndarray, shape (3, d)
        ``S, S_u, S_v`` before the edit (the scale of the residual check).

    Returns
    -------
    ndarray, shape (k * d,)

    Raises
    ------
    ConstraintError
        Conflicting or too many conditions for the active poles (the message counts both), or a
        solve too ill-conditioned to meet the conditions.
    """
    d = D0.shape[1]
    try:
        y = ConstraintFactor(J, names).solve(r)
    except ConstraintError as err:
        raise ConstraintError(
            f"drag_surface_point: {err} ({J.shape[0]} conditions, {J.shape[1] // d} active poles x {d})",
            err.rows, err.labels) from err
    res = np.abs(J @ y - r).max()
    if res > tolerances.LINEAR_CHECK_RTOL * max(1.0, float(np.abs(D0).max()), float(np.abs(r).max())):
        raise ConstraintError(f"drag_surface_point: the constraints are too ill-conditioned (residual {res:.3g})")
    return y


def _check_orientation(D1: Array, normal: Array, label: str) -> None:
    """Refuse an edit whose surface normal ``S_u x S_v`` is degenerate or opposite to ``normal``.

    The conditions ``n . S_u = n . S_v = 0`` only make the tangent plane perpendicular to
    ``normal``; they cannot tell ``n`` from ``-n``.

    Parameters
    ----------
    D1 : ndarray, shape (3, 3)
        ``S, S_u, S_v`` after the edit.
    normal : ndarray, shape (3,)
        The unit normal requested.
    label : str

    Raises
    ------
    ConstraintError
        ``S_u x S_v`` is zero or has a non-positive dot product with ``normal``.
    """
    n_new = np.cross(D1[1], D1[2])
    ln = np.linalg.norm(n_new)
    if not ln > 0 or n_new @ normal <= 0:
        raise ConstraintError(
            f"drag_surface_point: the tangent plane at {label} can be turned to the normal {normal.round(6)}, but the "
            f"surface normal would then be {'degenerate' if not ln > 0 else (n_new / ln).round(6)} (reversed or "
            "degenerate); give du/dv as well, or a normal within 90 degrees of the current one")


def drag_surface_point(surface: BSplineSurface, u: float, v: float, target: ArrayLike | None, *,
                       du: ArrayLike | None = None, dv: ArrayLike | None = None, normal: ArrayLike | None = None,
                       window: tuple[tuple[int, int], tuple[int, int]] | None = None,
                       weights: ArrayLike | None = None) -> BSplineSurface:
    """Drag a surface point, optionally setting its partials or tangent plane (course §4, on surfaces).

    The same minimum-norm principle as for curves on the net ``P_ij``: with the tensor-product
    (rational, weights fixed) basis ``R_ij(u, v)``,

    .. math::

        \\min \\sum_{ij \\in \\text{window}} w_{ij} \\|\\Delta P_{ij}\\|^2 \\quad \\text{s.t.} \\quad
        S(u, v) = \\text{target},\\; [S_u = du],\\; [S_v = dv],\\; [n \\cdot S_u = n \\cdot S_v = 0],

    all linear in the poles; the tangent-plane condition makes ``normal`` perpendicular to both
    partials (the plane turns, the parametrisation is otherwise free).

    Parameters
    ----------
    surface : BSplineSurface
    u, v : float
        Parameters in the domain.
    target : array_like, shape (d,), or None
        New position of ``S(u, v)``; ``None`` keeps the point where it is.
    du, dv : array_like, shape (d,), optional
        New partial derivatives ``S_u``, ``S_v``.
    normal : array_like, shape (3,), optional
        New normal direction (3-D surfaces). The result's normal ``S_u x S_v`` must point the same
        way (not reversed), else :class:`ConstraintError`.
    window : ((int, int), (int, int)), optional
        0-based inclusive pole ranges ``((i1, i2), (j1, j2))`` in u and v that may move (OCC's
        ``MovePoint(u, v, P, i1 + 1, i2 + 1, j1 + 1, j2 + 1)``). Default the whole net.
    weights : array_like, shape (n_u, n_v), optional
        Positive per-pole weights of the norm.

    Returns
    -------
    BSplineSurface

    Raises
    ------
    ParameterError
        ``u`` or ``v`` outside the domain.
    ConstraintError
        Conflicting requests (e.g. ``du`` not perpendicular to ``normal``), too many for the window,
        no pole of the window acting at ``(u, v)``, or a reversed normal.
    InvalidGeometryError
        Bad vectors, window or weights.
    """
    if not isinstance(surface, BSplineSurface):
        raise InvalidGeometryError(f"surface: expected a BSplineSurface, got {type(surface).__name__}")
    (u0, u1), (v0, v1) = surface.domain
    uu = float(V.check_parameters(as_parameter(u, "drag_surface_point"), u0, u1, "u"))
    vv = float(V.check_parameters(as_parameter(v, "drag_surface_point"), v0, v1, "v"))
    nu, nv = surface.n_poles
    d = surface.dim
    ranges = _window_ranges(window, (nu, nv))
    w = pole_weights(weights, (nu, nv))
    G = _surface_basis_rows(surface, uu, vv)  # (3, nu*nv)
    Pflat = surface.control_points.reshape(nu * nv, d)
    D0 = G @ Pflat  # S, S_u, S_v
    rows = [0] + ([1] if du is not None or normal is not None else []) + (
        [2] if dv is not None or normal is not None else [])
    label = f"(u={uu:.6g}, v={vv:.6g})"
    active = _active_poles(G, (nu, nv), ranges, rows, label)
    inv_sw = np.ones(active.size) if w is None else 1.0 / np.sqrt(w.ravel()[active])
    J, r, names, nrm = _edit_conditions(G[:, active], inv_sw, D0, target, du, dv, normal, label)
    y = _min_norm_change(J, r, names, D0)
    P = np.array(Pflat)
    P[active] += y.reshape(-1, d) * inv_sw[:, None]
    if nrm is not None:
        _check_orientation(G @ P, nrm, label)
    return BSplineSurface._trusted(surface.degree, surface.knots, P.reshape(nu, nv, d), surface.weights)
