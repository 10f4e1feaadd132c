"""Direct manipulation of tensor-product surfaces: drag a point, turn its tangent plane.

The curve method of course ch. 4 (Bartels & Beatty 1989) carried over to surfaces: every
position or partial-derivative property at ``(u, v)`` is linear in the net, so the edit is the
minimum-norm change of the movable poles that satisfies the requested properties (a window in the
u and v pole indices keeps it local, as OCC's ``Geom_BSplineSurface::MovePoint`` does).

References
----------
R. H. Bartels, J. C. Beatty, "A technique for the direct manipulation of spline curves",
Graphics Interface '89 (1989); course notes C25, SIGGRAPH 1991, §4-4 and §4-7.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import _validate as V
from ..kernel.basis import basis_derivatives, find_span
from .constraints import _param, pole_index, pole_weights
from ..errors import InvalidGeometryError
from .linalg import ConstraintError, ConstraintFactor
from ..kernel.rational import surface_quotient_rule
from ..kernel.surface import BSplineSurface

__all__ = ["drag_surface_point"]

Array = NDArray[np.float64]

#: The edit must meet its linear conditions to this relative accuracy (else: ill-conditioned).
LINEAR_CHECK_RTOL: float = 1e-9


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
    uu = float(V.check_parameters(_param(u, "drag_surface_point"), u0, u1, "u"))
    vv = float(V.check_parameters(_param(v, "drag_surface_point"), v0, v1, "v"))
    nu, nv = surface.n_poles
    d = surface.dim
    if window is None:
        (i1, i2), (j1, j2) = (0, nu - 1), (0, nv - 1)
    else:
        try:
            (i1, i2), (j1, j2) = window
        except (TypeError, ValueError) as err:
            raise InvalidGeometryError(f"window: expected ((i1, i2), (j1, j2)), got {window!r}") from err
        i1, i2 = pole_index(i1, "window[0][0]", nu), pole_index(i2, "window[0][1]", nu)
        j1, j2 = pole_index(j1, "window[1][0]", nv), pole_index(j2, "window[1][1]", nv)
        if i1 > i2 or j1 > j2:
            raise InvalidGeometryError(f"window: empty window (({i1}, {i2}), ({j1}, {j2}))")
    w = pole_weights(weights, (nu, nv))
    G = _surface_basis_rows(surface, uu, vv)  # (3, nu*nv)
    Pflat = surface.control_points.reshape(nu * nv, d)
    D0 = G @ Pflat  # S, S_u, S_v
    mask = np.zeros((nu, nv), bool)
    mask[i1:i2 + 1, j1:j2 + 1] = True
    mov = np.nonzero(mask.ravel())[0]
    used = [0] + ([1] if du is not None or normal is not None else []) + ([2] if dv is not None or normal is not None else [])
    acts = np.any(G[np.ix_(used, mov)] != 0.0, axis=0)
    label = f"(u={uu:.6g}, v={vv:.6g})"
    if not np.any(acts):
        raise ConstraintError(f"drag_surface_point: no pole of the window (({i1}, {i2}), ({j1}, {j2})) acts at {label}")
    active = mov[acts]
    Ga = G[:, active]
    inv_sw = np.ones(active.size) if w is None else 1.0 / np.sqrt(w.ravel()[active])
    I = np.eye(d)
    blocks, rhs, names = [], [], []

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
    J = np.vstack(blocks)
    r = np.concatenate(rhs)
    try:
        y = ConstraintFactor(J, names).solve(r)
    except ConstraintError as err:
        raise ConstraintError(f"drag_surface_point: {err} ({J.shape[0]} conditions, {active.size} active poles x {d})",
                              err.rows, err.labels) from err
    dP = (y.reshape(-1, d)) * inv_sw[:, None]
    P = np.array(Pflat)
    P[active] += dP
    D1 = G @ P
    res = np.abs(J @ y - r).max()
    if res > LINEAR_CHECK_RTOL * max(1.0, float(np.abs(D0).max()), float(np.abs(r).max())):
        raise ConstraintError(f"drag_surface_point: the constraints are too ill-conditioned (residual {res:.3g})")
    if nrm is not None:
        n_new = np.cross(D1[1], D1[2])
        ln = np.linalg.norm(n_new)
        if not ln > 0 or n_new @ nrm <= 0:
            raise ConstraintError(
                f"drag_surface_point: the tangent plane at {label} can be turned to the normal {nrm.round(6)}, but the "
                f"surface normal would then be {'degenerate' if not ln > 0 else (n_new / ln).round(6)} (reversed or "
                "degenerate); give du/dv as well, or a normal within 90 degrees of the current one")
    return BSplineSurface._trusted(surface.degree, surface.knots, P.reshape(nu, nv, d), surface.weights)
