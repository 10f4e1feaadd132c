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
from ..kernel.curve import BSplineCurve
from .constraints import (
    Constraint,
    Curvature,
    Derivative,
    Position,
    Tangent,
    pole_index,
)
from .curve_solver import CurveProblem, reversed_directions, solve_problem, verify_problem
from .linalg import ConstraintError, ConstraintFactor, ConvergenceError
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

# Tolerances and limits (read at call time from :mod:`occsurf.algorithms.tolerances`): those of the
# solver, :mod:`.curve_solver`.


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
    change of poles lies in the row space of the constraint Jacobian. See :func:`~.curve_solver.solve_problem`.

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
    prob = CurveProblem(curve, constraints, movable, weights)
    y = solve_problem(prob, tol, max_iter)
    bad = reversed_directions(prob, y)
    if bad:
        fixed = [r.source for r in prob.rows]
        for k, src in bad:
            speed = float(np.linalg.norm(prob.D0[k, 1]))
            if not speed > 0:
                raise ConstraintError(f"{prob.rows[k].label}: the tangent vanishes at u="
                                      f"{src.u:.6g}; give the tangent vector, not only its direction",
                                      [prob.rows[k].index], [prob.rows[k].label])
            fixed[k] = Tangent(src.u, speed * src.vector / np.linalg.norm(src.vector))
        prob = CurveProblem(curve, fixed, movable, weights)
        y = solve_problem(prob, tol, max_iter)
    verify_problem(prob, y, tol)
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
        prob = CurveProblem(curve, constraints, movable, weights)
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
