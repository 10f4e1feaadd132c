"""Constraint-based direct manipulation of spline curves and surfaces (course ch. 4).

The user does not move control points: they drag a *point of the curve*, or set its tangent or its
curvature at a parameter, and the control points change by the smallest amount that makes the
curve obey (Bartels & Beatty 1989; Fowler & Bartels 1993). With ``C(u) = sum_i B_i(u) P_i`` every
property of order ``k`` at ``u`` is ``C^(k)(u) = sum_i B_i^(k)(u) P_i``, linear in the poles, so a
set of position / derivative constraints is an underdetermined linear system ``J dP = r`` whose
minimum-norm solution ``dP = J^+ r`` is the edit (course §4-4). Curvature is not linear in the
poles; it is reached by Newton's method on the optimality conditions of the same minimum-norm
problem, whose first step is the Gauss–Newton minimum-norm step of §4-12.

* :func:`constrain`: any mix of :class:`Position`, :class:`Tangent`, :class:`Derivative` and
  :class:`Curvature` at one or several parameters (§4-7 .. §4-12);
* :func:`drag_point`: one point, poles ``first..last`` movable (OCC's ``MovePoint`` window);
* :class:`Dragger`: preprocessing for interactive dragging (§4-6): factor once, then each new
  target costs one small matrix product;
* :func:`drag_surface_point` (from :mod:`occsurf.algorithms.manipulation.surfaces`): a surface point,
  optionally its partials and tangent plane.

The constraint objects and their residuals live in :mod:`occsurf.algorithms.manipulation.constraints`.

Conventions
-----------
* **Minimum norm.** The change ``dP`` minimises ``sum_i w_i |dP_i|^2`` (Frobenius norm of the
  change of poles, optionally weighted per pole with ``weights``) over the *movable* poles; the
  other poles are not touched. Position and derivative constraints act on every coordinate with
  the same basis row, so the problem separates per coordinate; direction constraints and curvature
  couple coordinates, and everything is solved as one system in ``vec(dP)`` (Kronecker form).
* **Rational curves** keep their weights: the Cartesian poles are edited and
  ``C(u) = sum_i R_i(u) P_i`` with the rational basis ``R_i = w_i N_i / sum_j w_j N_j``, so the
  position constraint stays linear. (Editing homogeneous poles would also change the weights.)
* **Immutability.** Curves and surfaces are frozen; a failed request raises and returns nothing,
  so no half-edited object can exist.
* **Parameters at knots** use the derivative from the right (left at the domain end), as
  :meth:`BSplineCurve.derivatives` and OCC do.

Course sections: §4-2 curve and constraint notation, §4-4 underdetermined systems, §4-6
preprocessing and iterative evaluation, §4-7 applying property constraints, §4-8 single, §4-9
double and §4-11 triple constraint systems, §4-12 manipulating curvature.

References
----------
R. H. Bartels, J. C. Beatty, "A technique for the direct manipulation of spline curves",
Graphics Interface '89, 33-39 (1989). B. Fowler, R. Bartels, "Constraint-based curve
manipulation", IEEE Computer Graphics and Applications 13(5), 43-49 (1993). Course notes C25,
SIGGRAPH 1991, ch. 3 and 4.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import _validate as V
from .. import tolerances
from ..errors import InvalidGeometryError
from ..kernel.basis import basis_derivatives, find_span
from ..kernel.curve import BSplineCurve
from ..kernel.rational import curve_quotient_rule
from .constraints import (
    Constraint,
    Curvature,
    Derivative,
    Position,
    Rows,
    Tangent,
    bind,
    movable_indices,
    pole_index,
    pole_weights,
)
from .linalg import ConstraintError, ConstraintFactor, ConvergenceError, lstsq
from .surfaces import drag_surface_point

__all__ = [
    "Position",
    "Tangent",
    "Derivative",
    "Curvature",
    "Constraint",
    "constrain",
    "drag_point",
    "Dragger",
    "PreparedConstraints",
    "drag_surface_point",
    "ConstraintError",
    "ConvergenceError",
]

Array = NDArray[np.float64]

# Tolerances and limits, read at call time from :mod:`occsurf.algorithms.tolerances`: NEWTON_TOL,
# DRAG_MAX_ITERATIONS, DRAG_NEWTON_STEPS, MIN_CONTINUATION_STEP, KKT_RTOL, LINEAR_CHECK_RTOL.


# ============================================================================ basis rows
def _curve_basis_rows(curve: BSplineCurve, us: Array, order: int) -> Array:
    """Dense rows ``G[m, k, i] = d^k R_i / du^k (us[m])`` of the (rational) basis, ``(m, order+1, n)``.

    For a rational curve with fixed weights, ``R_i = w_i N_i / W`` and its derivatives follow from
    the quotient rule applied to the one-hot homogeneous poles (The NURBS Book, A4.2).
    """
    p, t, n = curve.degree, curve.knots, curve.n_poles
    span = find_span(t, p, n, us)
    D = basis_derivatives(t, p, span, us, order)  # (m, order+1, p+1)
    idx = span[:, None] - p + np.arange(p + 1)
    if curve.weights is not None:
        A = D * curve.weights[idx][:, None, :]
        D = curve_quotient_rule(np.concatenate([A, A.sum(axis=-1, keepdims=True)], axis=-1))
    m = us.shape[0]
    G = np.zeros((m, n, order + 1))
    G[np.arange(m)[:, None], idx] = D.transpose(0, 2, 1)
    return np.ascontiguousarray(G.transpose(0, 2, 1))


# ============================================================================ the solver
def _reraise(err: ConstraintError, owner: Array, rows: Sequence[Rows], extra: str = "") -> ConstraintError:
    """The linear-algebra error restated in terms of the constraints (indices and labels)."""
    idx = sorted({int(owner[r]) for r in err.rows})
    return ConstraintError(f"{err}{extra}", [rows[k].index for k in idx], [rows[k].label for k in idx])


def _describe(idx: NDArray[np.intp]) -> str:
    if idx.size and idx[-1] - idx[0] + 1 == idx.size:
        return f"{idx[0]}..{idx[-1]}"
    return ", ".join(str(int(i)) for i in idx[:12]) + (" ..." if idx.size > 12 else "")


class _Problem:
    """Constraints bound to a curve, restricted to the active movable poles (internal).

    Unknowns are ``y = vec(sqrt(w) dP[active])`` (pole-major, coordinate-minor), so that the
    weighted minimum-norm change is the plain minimum-norm ``y``.
    """

    def __init__(self, curve: BSplineCurve, constraints: Sequence[Constraint] | Constraint, movable: object,
                 weights: ArrayLike | None) -> None:
        if isinstance(constraints, (Position, Tangent, Derivative, Curvature)):
            constraints = [constraints]
        try:
            constraints = list(constraints)
        except TypeError as err:
            raise InvalidGeometryError(
                f"constraints: expected a sequence of constraints, got {type(constraints).__name__}") from err
        if not constraints:
            raise InvalidGeometryError("constraints: expected at least one constraint, got none")
        n, d = curve.n_poles, curve.dim
        self.curve = curve
        self.rows = [bind(c, i, d, curve.degree, curve.domain) for i, c in enumerate(constraints)]
        mov = movable_indices(movable, n)
        w = pole_weights(weights, (n,))
        self.K = max(max(r.orders) for r in self.rows)
        us = np.array([r.u for r in self.rows])
        G = _curve_basis_rows(curve, us, self.K)  # (m, K+1, n)
        self.D0 = np.einsum("mkn,nd->mkd", G, curve.control_points)
        Gm = G[:, :, mov]
        used = np.zeros((len(self.rows), self.K + 1), bool)
        for k, r in enumerate(self.rows):
            used[k, list(r.orders)] = True
        acts = np.any((Gm != 0.0) & used[:, :, None], axis=(0, 1))
        if not np.any(acts):
            where = ", ".join(f"u={u:.6g}" for u in us)
            raise ConstraintError(
                f"no movable pole acts on the curve at {where}: poles {_describe(mov)} have no influence there "
                "(widen the window)", [r.index for r in self.rows], [r.label for r in self.rows])
        self.active = mov[acts]
        self.G = np.ascontiguousarray(Gm[:, :, acts])  # (m, K+1, na)
        self.inv_sw = np.ones(self.active.size) if w is None else 1.0 / np.sqrt(w[self.active])
        self.col_scale = np.repeat(self.inv_sw, d)
        self.d = d
        self.names = [s for r in self.rows for s in r.names]
        self.lin = [k for k, r in enumerate(self.rows) if r.linear]
        self.nl = [k for k, r in enumerate(self.rows) if not r.linear]
        self.extra = (f" ({len(self.names)} scalar conditions, {self.col_scale.size} free coordinates = "
                      f"{self.active.size} active poles {_describe(self.active)} x {d})")

    def derivs(self, y: Array) -> Array:
        """``D[m] = (C, C', .., C^(K))`` at every constraint for the change ``y``, ``(m, K+1, d)``."""
        dP = (y * self.col_scale).reshape(-1, self.d)
        return self.D0 + np.einsum("mkn,nd->mkd", self.G, dP)

    def system(self, which: Sequence[int], D: Array) -> tuple[Array, Array]:
        """Residuals and Jacobian (in ``y``) of the constraints ``which``: ``F (R,)``, ``J (R, na*d)``."""
        if not which:
            return np.zeros(0), np.zeros((0, self.col_scale.size))
        Fs, Js = [], []
        for k in which:  # one block per constraint (a handful), each vectorised
            F, dF = self.rows[k].residual(D[k], self.K)
            Fs.append(F)
            Js.append(np.einsum("rkd,kn->rnd", dF, self.G[k]).reshape(F.shape[0], -1) * self.col_scale)
        return np.concatenate(Fs), np.vstack(Js)

    def hessian(self, which: Sequence[int], D: Array, lam: Array) -> Array:
        """``sum_k d^2 (lam_k . F_k) / dy^2`` over the constraints ``which``, ``(na*d, na*d)``."""
        N = self.col_scale.size
        H = np.zeros((N, N))
        s = 0
        for k in which:
            r = self.rows[k]
            lk = lam[s : s + r.size]
            s += r.size
            if r.linear:
                continue
            B = np.kron(self.G[k], np.eye(self.d)) * self.col_scale  # dD_k / dy, ((K+1) d, N)
            H += B.T @ r.hessian(D[k], lk, self.K) @ B
        return H

    def names_of(self, which: Sequence[int]) -> list[str]:
        return [s for k in which for s in self.rows[k].names]

    def owners_of(self, which: Sequence[int]) -> Array:
        return np.concatenate([np.full(self.rows[k].size, k) for k in which]) if which else np.zeros(0, int)

    def merit(self, y: Array) -> float:
        """Largest nonlinear residual relative to ``max(1, |target|)``."""
        D = self.derivs(y)
        return max((float(np.max(np.abs(self.rows[k].residual(D[k], self.K)[0]))) / self.rows[k].scale
                    for k in self.nl), default=0.0)

    def result(self, y: Array) -> BSplineCurve:
        c = self.curve
        P = np.array(c.control_points)
        P[self.active] += (y * self.col_scale).reshape(-1, self.d)
        return BSplineCurve._trusted(c.degree, c.knots, P, c.weights)


def _solve(prob: _Problem, tol: float, max_iter: int) -> Array:
    """The scaled change ``y`` meeting every constraint with minimum ``||y||`` (course §4-4, §4-12).

    Linear constraints alone: one minimum-norm solve, exact (course §4-4). With nonlinear ones the
    problem ``min ||y||^2 / 2`` s.t. ``F(y) = 0`` is solved inside the affine set of the linear
    constraints (``y = y_c + Z z``, null-space method, course §3-12) by Newton's method on its
    first-order (KKT) conditions,

    .. math::

        \\begin{bmatrix} Z^T H Z & (J Z)^T \\\\ J Z & 0 \\end{bmatrix}
        \\begin{bmatrix} \\delta z \\\\ \\delta\\lambda \\end{bmatrix} =
        -\\begin{bmatrix} Z^T (y + J^T \\lambda) \\\\ F(y) - (1 - t) F(y_c) \\end{bmatrix},
        \\qquad H = I + \\sum_i \\lambda_i \\nabla^2 F_i,

    whose first step from ``lambda = 0`` is the Gauss–Newton minimum-norm step of course §4-12.
    The targets are approached by continuation in ``t`` from 0 (the linear solution ``y_c``,
    trivially optimal) to 1, the step in ``t`` halved whenever Newton fails to converge in a few
    iterations and doubled after a success: the edit follows the branch of minimal changes a user
    would trace by dragging the curvature gradually, and each stage converges quadratically.
    Convergence at ``t = 1``: every nonlinear residual ``<= tol * max(1, |target|)`` and the
    reduced Lagrangian gradient ``<= tolerances.KKT_RTOL * ||y||``.
    """
    lin, nl = prob.lin, prob.nl
    D = prob.derivs(np.zeros(prob.col_scale.size))
    F_lin, J_lin = prob.system(lin, D)
    try:
        fac = ConstraintFactor(J_lin, prob.names_of(lin), full=bool(nl))
        y_c = fac.solve(-F_lin)
    except ConstraintError as err:
        raise _reraise(err, prob.owners_of(lin), prob.rows, prob.extra) from err
    if not nl:
        return y_c
    Z = fac.null_basis
    if Z is None:  # full=True (nl is not empty) computes it
        raise RuntimeError("constrain: the constraint factor has no null-space basis")
    y, merit, t, used = _continuation(prob, y_c, Z, tol, max_iter)
    if merit <= tol:
        return y
    # The branch of minimal changes folded (or Newton could not follow it): fall back to a globally
    # convergent SQP (SciPy's SLSQP, exact Jacobians) from y_c, then polish with Newton-KKT.
    y2, merit2 = _slsqp(prob, y_c, Z, tol, max_iter)
    if merit2 <= tol:
        return y2
    y = y if merit <= merit2 else y2
    _diagnose(prob, y)
    raise ConvergenceError(
        f"constrain: the nonlinear constraints {', '.join(prob.rows[k].label for k in nl)} could not be met: the "
        f"continuation stopped at t = {t:.4g} of 1 after {used} Newton steps and SLSQP reached a scaled residual of "
        f"{min(merit, merit2):.3g} > tol {tol:.3g}; the request is too far from the curve for the movable "
        f"poles{prob.extra}")


def _slsqp(prob: _Problem, y_c: Array, Z: Array, tol: float, max_iter: int) -> tuple[Array, float]:
    """Fallback of :func:`_solve`: SLSQP on ``min ||z||^2 / 2`` s.t. ``F(y_c + Z z) = 0``, then Newton-KKT."""
    nl = prob.nl
    scales = np.concatenate([np.full(prob.rows[k].size, prob.rows[k].scale) for k in nl])
    if not Z.shape[1]:
        return y_c, np.inf

    def system(z: Array) -> tuple[Array, Array]:
        with np.errstate(all="ignore"):
            F, J = prob.system(nl, prob.derivs(y_c + Z @ z))
        return F, J @ Z

    from scipy.optimize import minimize  # heavy import, needed only on this fallback path

    try:
        res = minimize(lambda z: 0.5 * float(z @ z), np.zeros(Z.shape[1]), jac=lambda z: z, method="SLSQP",
                       constraints=[{"type": "eq", "fun": lambda z: system(z)[0], "jac": lambda z: system(z)[1]}],
                       options={"ftol": 1e-15, "maxiter": max(max_iter, 100)})
    except (ValueError, ConstraintError, np.linalg.LinAlgError):
        return y_c, np.inf
    y = y_c + Z @ res.x
    if not np.all(np.isfinite(y)):
        return y_c, np.inf
    # Newton-KKT polish at t = 1 (quadratic from here); multipliers from least squares.
    F, J = prob.system(nl, prob.derivs(y))
    lam = -lstsq((J @ Z).T, Z.T @ y).x
    ok, y_new, _, _ = _newton_kkt(prob, y, lam, Z, np.zeros(scales.size), scales, tol,
                                  int(tolerances.DRAG_NEWTON_STEPS))
    if ok:
        y = y_new
    with np.errstate(all="ignore"):
        F, _ = prob.system(nl, prob.derivs(y))
    merit = float(np.max(np.abs(F) / scales))
    return y, (merit if np.isfinite(merit) else np.inf)


def _continuation(prob: _Problem, y_c: Array, Z: Array, tol: float, max_iter: int) -> tuple[Array, float, float, int]:
    """Continuation + Newton–KKT of :func:`_solve`: ``(y, merit at t = 1, t reached, steps used)``."""
    nl = prob.nl
    scales = np.concatenate([np.full(prob.rows[k].size, prob.rows[k].scale) for k in nl])
    F0, _ = prob.system(nl, prob.derivs(y_c))
    y, lam = y_c, np.zeros(scales.size)
    t, dt, used = 0.0, 1.0, 0
    while t < 1.0 and used < max_iter and Z.shape[1]:
        t_new = min(1.0, t + dt)
        ok, y_new, lam_new, steps = _newton_kkt(prob, y, lam, Z, (1.0 - t_new) * F0, scales, tol,
                                                min(int(tolerances.DRAG_NEWTON_STEPS), max_iter - used))
        used += steps
        if ok:
            t, y, lam, dt = t_new, y_new, lam_new, 2.0 * dt
        else:
            dt *= 0.5
            if dt < tolerances.MIN_CONTINUATION_STEP:
                break
    with np.errstate(all="ignore"):
        F, _ = prob.system(nl, prob.derivs(y))
    merit = float(np.max(np.abs(F) / scales))
    return y, (merit if np.isfinite(merit) else np.inf), t, used


def _newton_kkt(prob: _Problem, y: Array, lam: Array, Z: Array, offset: Array, scales: Array, tol: float,
                max_steps: int) -> tuple[bool, Array, Array, int]:
    """Newton on the KKT conditions of ``min ||y||`` s.t. ``F(y) = offset``; ``(ok, y, lam, steps)``."""
    nz = Z.shape[1]
    R = scales.size
    for step in range(max_steps + 1):
        with np.errstate(all="ignore"):
            D = prob.derivs(y)
            F, J = prob.system(prob.nl, D)
        F = F - offset
        if not (np.isfinite(F).all() and np.isfinite(J).all()):
            return False, y, lam, step
        A = J @ Z
        g = Z.T @ y + A.T @ lam
        merit = float(np.max(np.abs(F) / scales))
        if merit <= tol and np.linalg.norm(g) <= tolerances.KKT_RTOL * max(float(np.linalg.norm(y)), 1.0):
            return True, y, lam, step
        if step == max_steps:
            break
        with np.errstate(all="ignore"):
            Hz = Z.T @ (np.eye(y.size) + prob.hessian(prob.nl, D, lam)) @ Z
        if not np.isfinite(Hz).all():
            return False, y, lam, step
        K = np.block([[Hz, A.T], [A, np.zeros((R, R))]])
        delta = lstsq(K, -np.concatenate([g, F])).x
        y = y + Z @ delta[:nz]
        lam = lam + delta[nz:]
    return False, y, lam, max_steps


def _diagnose(prob: _Problem, y: Array) -> None:
    """At a non-converged iterate, name conflicting constraints through the linearised system."""
    order = prob.lin + prob.nl
    F, J = prob.system(order, prob.derivs(y))
    try:
        ConstraintFactor(J, prob.names_of(order)).check(-F)
    except ConstraintError as err:
        raise _reraise(err, prob.owners_of(order), prob.rows, prob.extra) from err


def _reversed_directions(prob: _Problem, y: Array) -> list[tuple[int, Tangent]]:
    """Direction-only tangents that ended reversed or cancelled (their speed must be kept), with
    their row numbers."""
    D = prob.derivs(y)
    bad = []
    for k, r in enumerate(prob.rows):
        src = r.source
        if r.kind == "direction" and isinstance(src, Tangent):  # bind makes direction rows of tangents only
            e = src.vector / np.linalg.norm(src.vector)
            a = D[k, 1]
            if not e @ a > 1e-9 * max(np.linalg.norm(prob.D0[k, 1]), np.linalg.norm(a), np.finfo(float).tiny):
                bad.append((k, src))
    return bad


def _verify(prob: _Problem, y: Array, tol: float) -> None:
    """Every constraint holds for the result (guards against ill-conditioned systems)."""
    D = prob.derivs(y)
    for k, r in enumerate(prob.rows):
        F, _ = r.residual(D[k], prob.K)
        if r.linear:
            limit = tolerances.LINEAR_CHECK_RTOL * max(r.scale, float(np.abs(prob.D0[k]).max()))
        else:
            limit = 10 * tol * r.scale
        if np.max(np.abs(F)) > limit:
            raise ConstraintError(
                f"{r.label}: not met after the solve (residual {np.max(np.abs(F)):.3g}); the constraints are too "
                "ill-conditioned for the movable poles (parameters too close together?)", [r.index], [r.label])


def constrain(curve: BSplineCurve, constraints: Sequence[Constraint] | Constraint, movable: object = None,
              weights: ArrayLike | None = None, *, tol: float | None = None,
              max_iter: int | None = None) -> BSplineCurve:
    """Edit a curve by constraints on its points, tangents and curvature (course §4-7 .. §4-12).

    Finds the change of the movable control points with the least (weighted) Frobenius norm

    .. math::

        \\min_{\\Delta P} \\sum_{i \\in \\text{movable}} w_i \\|\\Delta P_i\\|^2
        \\quad\\text{s.t.}\\quad \\text{every constraint holds for } P + \\Delta P.

    Linear constraints (:class:`Position`, :class:`Derivative`, full and direction-only
    :class:`Tangent`) are solved exactly in one step by the pivoted-QR minimum-norm solver
    (course §4-4); single (§4-8), double (§4-9) and triple (§4-11) constraint systems and mixes on
    several parameters are all the same call. Nonlinear ones (:class:`Curvature`, tangent
    magnitude, §4-12) are solved by Newton's method on the first-order (KKT) conditions of the
    minimum-norm problem, inside the affine set of the linear constraints, with continuation from
    the current values to the targets (the edit a gradual drag would produce); if that branch
    folds, SciPy's SLSQP from the linear solution takes over and Newton polishes its answer. The
    result meets every constraint (nonlinear ones to ``tol``) and is first-order optimal: its
    change of poles lies in the row space of the constraint Jacobian. See :func:`_solve`.

    Parameters
    ----------
    curve : BSplineCurve
        Polynomial or rational; rational weights stay fixed (the Cartesian poles move).
    constraints : constraint or sequence of constraints
        :class:`Position`, :class:`Tangent`, :class:`Derivative`, :class:`Curvature`, at any
        parameters in the domain (several at one parameter make a double/triple system).
    movable : None, slice, sequence of int or bool mask, optional
        The poles allowed to move (0-based). Default all. A window keeps the edit local.
    weights : array_like, shape (n,), optional
        Positive per-pole weights of the norm (a heavy pole moves little). Not the rational weights.
    tol : float, optional
        Nonlinear residual tolerance, relative to ``max(1, |target|)``; default
        :data:`~occsurf.algorithms.tolerances.NEWTON_TOL`.
    max_iter : int, optional
        Default :data:`~occsurf.algorithms.tolerances.DRAG_MAX_ITERATIONS`.

    Returns
    -------
    BSplineCurve
        A new curve (same degree, knots and weights); ``curve`` is unchanged.

    Raises
    ------
    ParameterError
        A constraint parameter outside the domain.
    ConstraintError
        Conflicting constraints (named, e.g. two positions at one parameter, a curvature vector
        not perpendicular to a prescribed tangent), more independent conditions than the movable
        poles can satisfy, no movable pole acting at a constrained parameter.
    ConvergenceError
        The nonlinear constraints could not be met by the movable poles and no conflict among
        the constraints could be identified (e.g. a radius far below what the window can bend).
    InvalidGeometryError
        Bad arguments: wrong vector size, empty or out-of-range window, weights ``<= 0``.

    Examples
    --------
    >>> c = BSplineCurve(3, [0, 0, 0, 0, .5, 1, 1, 1, 1], [[0, 0], [1, 1], [2, 1], [3, 1], [4, 0]])
    >>> c2 = constrain(c, [Position(0.5, [2, 2]), Tangent(0.5, [4, 0])])
    >>> np.allclose(c2.evaluate(0.5), [2, 2]) and np.allclose(c2.derivatives(0.5, 1)[1], [4, 0])
    True
    """
    if not isinstance(curve, BSplineCurve):
        raise InvalidGeometryError(f"curve: expected a BSplineCurve, got {type(curve).__name__}")
    tol = tolerances.NEWTON_TOL if tol is None else float(tol)
    if not tol > 0:
        raise InvalidGeometryError(f"tol: expected > 0, got {tol!r}")
    max_iter = int(tolerances.DRAG_MAX_ITERATIONS) if max_iter is None else V.check_times(max_iter, "max_iter")
    prob = _Problem(curve, constraints, movable, weights)
    y = _solve(prob, tol, max_iter)
    bad = _reversed_directions(prob, y)
    if bad:
        fixed = [r.source for r in prob.rows]
        for k, src in bad:
            speed = float(np.linalg.norm(prob.D0[k, 1]))
            if not speed > 0:
                raise ConstraintError(f"{prob.rows[k].label}: the tangent vanishes at u="
                                      f"{src.u:.6g}; give the tangent vector, not only its direction",
                                      [prob.rows[k].index], [prob.rows[k].label])
            fixed[k] = Tangent(src.u, speed * src.vector / np.linalg.norm(src.vector))
        prob = _Problem(curve, fixed, movable, weights)
        y = _solve(prob, tol, max_iter)
    _verify(prob, y, tol)
    return prob.result(y)


def drag_point(curve: BSplineCurve, u: float, target: ArrayLike, first: int | None = None, last: int | None = None,
               *, weights: ArrayLike | None = None) -> BSplineCurve:
    """Move the curve through ``target`` at ``u`` changing only poles ``first..last`` (course §4-8).

    The single constraint system: with ``r = target - C(u)`` and the basis row ``R_i(u)``,

    .. math:: \\Delta P_i = \\frac{R_i(u)}{\\sum_{j=f}^{l} R_j(u)^2}\\, r, \\qquad f \\le i \\le l,

    the minimum-norm change (Bartels & Beatty 1989). The window means what OCC's
    ``Geom_BSplineCurve::MovePoint(u, P, first + 1, last + 1)`` means (OCC counts from 1), but OCC
    moves the poles by a heuristic whose change is never smaller than this one.

    Parameters
    ----------
    curve : BSplineCurve
    u : float
        Parameter in the domain.
    target : array_like, shape (d,)
    first, last : int, optional
        0-based inclusive window of movable poles, default the whole curve.
    weights : array_like, shape (n,), optional
        Per-pole weights of the norm, see :func:`constrain`.

    Returns
    -------
    BSplineCurve

    Raises
    ------
    InvalidGeometryError
        ``first > last`` (empty window) or an index out of ``0..n-1``.
    ConstraintError
        No pole of the window acts at ``u`` (OCC then reports ``first > last``, or even fills the
        poles with NaN).
    ParameterError
        ``u`` outside the domain.
    """
    if not isinstance(curve, BSplineCurve):
        raise InvalidGeometryError(f"curve: expected a BSplineCurve, got {type(curve).__name__}")
    n = curve.n_poles
    f = 0 if first is None else pole_index(first, "first", n)
    l = n - 1 if last is None else pole_index(last, "last", n)
    if f > l:
        raise InvalidGeometryError(f"first, last: the window {f}..{l} is empty (first > last)")
    return constrain(curve, [Position(u, target)], movable=slice(f, l + 1), weights=weights)


# ============================================================================ preprocessing
class Dragger:
    """Constraints at fixed parameters, factored once for interactive dragging (course §4-6).

    For position and derivative constraints the minimum-norm change is linear in the targets:

    .. math:: \\Delta P = W^{-1/2} (G W^{-1/2})^+ (T - T_0),

    where ``G`` (``m x n_active``) holds the basis rows at the constraint parameters, ``T_0`` the
    curve's current values and ``T`` the new targets (one row per constraint, every coordinate at
    once). The pseudo-inverse is computed once here by pivoted QR; :meth:`apply` costs one
    ``(n_active x m) @ (m x d)`` product, a copy of the poles and the construction of the result.

    Parameters
    ----------
    curve : BSplineCurve
    constraints : sequence of Position, Tangent (full vector) or Derivative
        Their parameters and kinds are fixed; their targets are the default of :meth:`apply`.
        Curvature, direction-only and magnitude-only tangents are nonlinear or
        direction-dependent: use :func:`constrain` for those.
    movable, weights
        As in :func:`constrain`.

    Attributes
    ----------
    active : ndarray of int
        Poles that can move (movable and acting at some constraint parameter).
    operator : ndarray, shape (n_active, m)
        ``dP[active] = operator @ (T - T_0)``.
    current : ndarray, shape (m, d)
        ``T_0``, the constrained quantities of the original curve.

    Raises
    ------
    InvalidGeometryError
        A nonlinear constraint, bad window or weights.
    ConstraintError
        Constraints that can never hold together for the movable poles (e.g. more derivative
        conditions at one parameter than the poles acting there).

    Examples
    --------
    >>> c = BSplineCurve(3, [0, 0, 0, 0, .5, 1, 1, 1, 1], [[0, 0], [1, 1], [2, 1], [3, 1], [4, 0]])
    >>> drag = Dragger(c, [Position(0.3, c.evaluate(0.3)), Tangent(0.3, c.derivatives(0.3, 1)[1])])
    >>> c2 = drag.apply([[1.5, 1.5], [6.0, 0.0]])
    >>> np.allclose(c2.evaluate(0.3), [1.5, 1.5])
    True
    """

    def __init__(self, curve: BSplineCurve, constraints: Sequence[Constraint], movable: object = None,
                 weights: ArrayLike | None = None) -> None:
        if not isinstance(curve, BSplineCurve):
            raise InvalidGeometryError(f"curve: expected a BSplineCurve, got {type(curve).__name__}")
        if isinstance(constraints, (Position, Tangent, Derivative, Curvature)):
            constraints = [constraints]
        constraints = list(constraints)
        for i, c in enumerate(constraints):
            if isinstance(c, Curvature) or (isinstance(c, Tangent) and (c.direction_only or c.magnitude_only)):
                raise InvalidGeometryError(
                    f"constraints[{i}]: {c!r} is not a vector-valued linear constraint; Dragger takes Position, "
                    "Tangent (full vector) and Derivative; use constrain() for the others")
        prob = _Problem(curve, constraints, movable, weights)
        self.curve = curve
        self.constraints = tuple(constraints)
        m = len(prob.rows)
        G = np.stack([prob.G[k, r.order] for k, r in enumerate(prob.rows)])  # (m, na)
        labels = [r.label for r in prob.rows]
        self._factor = ConstraintFactor(G * prob.inv_sw, labels)
        self.active = prob.active
        self.operator = V.readonly(self._factor.operator * prob.inv_sw[:, None])
        self.current = V.readonly(np.stack([prob.D0[k, r.order] for k, r in enumerate(prob.rows)]))
        self.targets = V.readonly(np.stack([r.target for r in prob.rows]))
        self._base = np.array(curve.control_points)
        self._redundant = self._factor.rank < m
        self._shape = (m, curve.dim)
        self._factor.check(self.targets - self.current)

    def apply(self, targets: ArrayLike | None = None) -> BSplineCurve:
        """The curve meeting the constraints with new ``targets`` (one row per constraint).

        Parameters
        ----------
        targets : array_like, shape (m, d), optional
            Default: the targets the constraints were built with.

        Returns
        -------
        BSplineCurve

        Raises
        ------
        InvalidGeometryError
            Wrong shape or non-finite targets.
        ConstraintError
            Targets that contradict a dependency among the constraints.
        """
        T = self.targets if targets is None else np.asarray(targets, dtype=float)
        if T.shape != self._shape:
            raise InvalidGeometryError(f"targets: expected shape {self._shape} (one row per constraint), got {T.shape}")
        R = T - self.current
        if not np.isfinite(R).all():
            raise InvalidGeometryError("targets: expected finite values")
        if self._redundant:
            self._factor.check(R)
        P = self._base.copy()
        P[self.active] += self.operator @ R
        c = self.curve
        return BSplineCurve._trusted(c.degree, c.knots, P, c.weights)


#: Alias: the course calls this step "preprocessing" (§4-6).
PreparedConstraints = Dragger
