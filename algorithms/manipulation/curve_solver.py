"""The solver behind constraint-based manipulation of curves (course §4-4 .. §4-12): the constraint
problem on the movable poles (:class:`CurveProblem`: the (rational) basis rows at the constraint
parameters and the minimum-norm change), solved in one step where every constraint is linear and by
Newton's method on the optimality conditions otherwise (:func:`solve_problem`), then checked
(:func:`verify_problem`). :mod:`.curves` holds what users call (:func:`~.curves.constrain`,
:func:`~.curves.drag_point`, :class:`~.curves.Dragger`) and states the conventions.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

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
    pole_weights,
)
from .linalg import ConstraintError, ConstraintFactor, ConvergenceError, lstsq

__all__ = ["CurveProblem", "solve_problem", "verify_problem", "reversed_directions"]

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


class CurveProblem:
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


def solve_problem(prob: CurveProblem, tol: float, max_iter: int) -> Array:
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


def _slsqp(prob: CurveProblem, y_c: Array, Z: Array, tol: float, max_iter: int) -> tuple[Array, float]:
    """Fallback of :func:`solve_problem`: SLSQP on ``min ||z||^2 / 2`` s.t. ``F(y_c + Z z) = 0``, then Newton-KKT."""
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


def _continuation(prob: CurveProblem, y_c: Array, Z: Array, tol: float, max_iter: int) -> tuple[Array, float, float, int]:
    """Continuation + Newton–KKT of :func:`solve_problem`: ``(y, merit at t = 1, t reached, steps used)``."""
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


def _newton_kkt(prob: CurveProblem, y: Array, lam: Array, Z: Array, offset: Array, scales: Array, tol: float,
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


def _diagnose(prob: CurveProblem, y: Array) -> None:
    """At a non-converged iterate, name conflicting constraints through the linearised system."""
    order = prob.lin + prob.nl
    F, J = prob.system(order, prob.derivs(y))
    try:
        ConstraintFactor(J, prob.names_of(order)).check(-F)
    except ConstraintError as err:
        raise _reraise(err, prob.owners_of(order), prob.rows, prob.extra) from err


def reversed_directions(prob: CurveProblem, y: Array) -> list[tuple[int, Tangent]]:
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


def verify_problem(prob: CurveProblem, y: Array, tol: float) -> None:
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
