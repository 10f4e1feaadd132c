"""Vectorised evaluation of OCC faces and p-curves in OCC's own parametrisation.

Shared by the quality rooms (the continuity check) and the modeling rooms (the refill's traces of a
hole's neighbours). The continuity check evaluates both faces of an edge at the ``(u, v)`` that the edge's p-curves
give, so every evaluator here must use exactly OCC's parameters (not those of a conversion that
re-parametrises). Three kinds, chosen per face by :func:`surface_evaluator`:

``'bspline'``
    B-spline and Bézier surfaces (also under a ``Geom_RectangularTrimmedSurface``): our
    :class:`~occsurf.algorithms.BSplineSurface` from :func:`~occsurf.bridge.from_occ` (bit-exact,
    same parameters; periodic directions are wrapped into the period).
``'analytic'``
    Planes, cylinders, cones, spheres and tori in closed form. All but the plane are
    ``P(u, v) = C + A(v) (cos u X + sin u Y) + B(v) Z`` (OCC's ``ElSLib``), so every partial is
    ``d^{i+j}P/du^i dv^j = A^(j)(v) (cos(u + i pi/2) X + sin(u + i pi/2) Y) + [i = 0] B^(j)(v) Z``.
    (``from_occ`` of these is the exact *image* but not OCC's parametrisation, OCP_NOTES §2.)
``'occ'``
    Anything else (surfaces of revolution and extrusion, offsets, ...): OCC's ``D2``/``D3`` point
    by point, slow but exact; counted in the report so a user sees where the time goes.

P-curves (``Geom2d``) likewise: lines in closed form, B-spline/Bézier p-curves with our
:class:`~occsurf.algorithms.BSplineCurve` (2-D poles), anything else through OCC's ``D1``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray
from OCP.Geom import (
    Geom_BezierSurface,
    Geom_BSplineSurface,
    Geom_ConicalSurface,
    Geom_CylindricalSurface,
    Geom_Plane,
    Geom_RectangularTrimmedSurface,
    Geom_SphericalSurface,
    Geom_Surface,
    Geom_ToroidalSurface,
)
from OCP.Geom2d import Geom2d_BezierCurve, Geom2d_BSplineCurve, Geom2d_Curve, Geom2d_Line, Geom2d_TrimmedCurve
from OCP.gp import gp_Pnt, gp_Pnt2d, gp_Vec, gp_Vec2d

from occsurf.algorithms import BSplineCurve, BSplineSurface

from .. import _occ
from .splines import from_occ

Array = NDArray[np.float64]

__all__ = ["SurfaceEvaluator", "PCurveEvaluator", "surface_evaluator", "pcurve_evaluator"]


# ============================================================================== surfaces
@dataclass(frozen=True)
class SurfaceEvaluator:
    """Partials of one face's surface at OCC parameters.

    Attributes
    ----------
    kind : str
        ``'bspline'``, ``'analytic'`` or ``'occ'`` (see the module docstring).
    fn : callable
        ``fn(u, v, order) -> ndarray (m, order + 1, order + 1, 3)``; ``u, v`` of shape ``(m,)``.
    occ_surface : Geom_Surface
        The located surface (``BRep_Tool.Surface_s``), for the OCC oracle.
    """

    kind: str
    fn: Callable[[Array, Array, int], Array] = field(repr=False)
    occ_surface: Any = field(repr=False)
    spline: BSplineSurface | None = field(default=None, repr=False)
    periodic: tuple[bool, bool] = (False, False)

    def derivatives(self, u: Array, v: Array, order: int) -> Array:
        """``D[m, i, j, :] = d^{i+j} S / du^i dv^j`` at ``(u[m], v[m])``, ``i, j <= order``."""
        u = np.asarray(u, dtype=float).reshape(-1)
        v = np.asarray(v, dtype=float).reshape(-1)
        if u.size == 0:
            return np.zeros((0, order + 1, order + 1, 3))
        return self.fn(u, v, order)


def surface_evaluator(occ_surface: Geom_Surface, surface: BSplineSurface | None = None) -> SurfaceEvaluator:
    """The fastest exact evaluator of ``occ_surface`` in OCC's parametrisation.

    Parameters
    ----------
    occ_surface : Geom_Surface
        Located (``BRep_Tool.Surface_s(face)``).
    surface : BSplineSurface, optional
        ``from_occ`` of it when already known (``ImportedFace.surface`` of a B-spline face).
    """
    basis = occ_surface
    while isinstance(basis, Geom_RectangularTrimmedSurface):
        basis = basis.BasisSurface()
    if isinstance(basis, (Geom_BSplineSurface, Geom_BezierSurface)):
        ours = surface if surface is not None and basis is occ_surface else from_occ(basis)
        if not isinstance(ours, BSplineSurface):  # from_occ of a Geom B-spline or Bézier surface is one
            raise TypeError(f"from_occ gave a {type(ours).__name__} for a {type(basis).__name__}")
        periodic = (bool(basis.IsUPeriodic()), bool(basis.IsVPeriodic())) if isinstance(basis, Geom_BSplineSurface) \
            else (False, False)
        return SurfaceEvaluator("bspline", _bspline_fn(ours, basis), occ_surface, ours, periodic)
    analytic = _analytic_fn(basis)
    if analytic is not None:
        return SurfaceEvaluator("analytic", analytic, occ_surface)
    return SurfaceEvaluator("occ", _occ_fn(occ_surface), occ_surface)


def _bspline_fn(ours: BSplineSurface, occ_basis: Any) -> Callable[[Array, Array, int], Array]:
    (u0, u1), (v0, v1) = ours.domain
    up = bool(occ_basis.IsUPeriodic()) if isinstance(occ_basis, Geom_BSplineSurface) else False
    vp = bool(occ_basis.IsVPeriodic()) if isinstance(occ_basis, Geom_BSplineSurface) else False

    def fn(u: Array, v: Array, order: int) -> Array:
        u = _wrap(u, u0, u1) if up else np.clip(u, u0, u1)
        v = _wrap(v, v0, v1) if vp else np.clip(v, v0, v1)
        return ours.derivatives(u, v, order)

    return fn


def _wrap(x: Array, a: float, b: float) -> Array:
    """Into ``[a, b]`` by whole periods; values already inside are kept bit for bit."""
    period = b - a
    inside = (x >= a) & (x <= b)
    return np.where(inside, x, a + np.mod(x - a, period))


def _frame(pos: Any) -> tuple[Array, Array, Array, Array]:
    c = np.array(pos.Location().Coord())
    return c, np.array(pos.XDirection().Coord()), np.array(pos.YDirection().Coord()), np.array(pos.Direction().Coord())


def _analytic_fn(s: Any) -> Callable[[Array, Array, int], Array] | None:
    """Closed-form partials of planes, cylinders, cones, spheres and tori (OCC's ElSLib forms)."""
    if isinstance(s, Geom_Plane):
        C, X, Y, _ = _frame(s.Position())

        def plane(u: Array, v: Array, order: int) -> Array:
            D = np.zeros((u.shape[0], order + 1, order + 1, 3))
            D[:, 0, 0] = C + u[:, None] * X + v[:, None] * Y
            if order >= 1:
                D[:, 1, 0], D[:, 0, 1] = X, Y
            return D

        return plane
    # A^(j)(v), B^(j)(v) of the revolution form, per kind
    if isinstance(s, Geom_CylindricalSurface):
        r = s.Radius()
        A = lambda v, j: np.full_like(v, r) if j == 0 else np.zeros_like(v)  # noqa: E731
        B = lambda v, j: v.copy() if j == 0 else (np.ones_like(v) if j == 1 else np.zeros_like(v))  # noqa: E731
    elif isinstance(s, Geom_ConicalSurface):
        r, a = s.RefRadius(), s.SemiAngle()
        sa, ca = np.sin(a), np.cos(a)
        A = lambda v, j: r + v * sa if j == 0 else (np.full_like(v, sa) if j == 1 else np.zeros_like(v))  # noqa: E731
        B = lambda v, j: v * ca if j == 0 else (np.full_like(v, ca) if j == 1 else np.zeros_like(v))  # noqa: E731
    elif isinstance(s, Geom_SphericalSurface):
        r = s.Radius()
        A = lambda v, j: r * np.cos(v + j * np.pi / 2)  # noqa: E731
        B = lambda v, j: r * np.sin(v + j * np.pi / 2)  # noqa: E731
    elif isinstance(s, Geom_ToroidalSurface):
        R, r = s.MajorRadius(), s.MinorRadius()
        A = lambda v, j: (R if j == 0 else 0.0) + r * np.cos(v + j * np.pi / 2)  # noqa: E731
        B = lambda v, j: r * np.sin(v + j * np.pi / 2)  # noqa: E731
    else:
        return None
    C, X, Y, Z = _frame(s.Position())

    def revolution(u: Array, v: Array, order: int) -> Array:
        D = np.empty((u.shape[0], order + 1, order + 1, 3))
        for i in range(order + 1):
            radial = np.cos(u + i * np.pi / 2)[:, None] * X + np.sin(u + i * np.pi / 2)[:, None] * Y
            for j in range(order + 1):
                D[:, i, j] = A(v, j)[:, None] * radial
                if i == 0:
                    D[:, i, j] += B(v, j)[:, None] * Z
        D[:, 0, 0] += C
        return D

    return revolution


def _occ_fn(s: Any) -> Callable[[Array, Array, int], Array]:
    """OCC's ``D1``/``D2``/``D3`` point by point (surfaces with no vectorised form here)."""

    def fn(u: Array, v: Array, order: int) -> Array:
        D = np.zeros((u.shape[0], order + 1, order + 1, 3))
        P = gp_Pnt()
        vs = [gp_Vec() for _ in range(9)]
        with _occ.kernel_errors(f"evaluating {type(s).__name__}"):
            for m, (a, b) in enumerate(zip(u.tolist(), v.tolist())):
                if order <= 1:
                    s.D1(a, b, P, vs[0], vs[1])
                    idx = [(1, 0), (0, 1)]
                elif order == 2:
                    s.D2(a, b, P, vs[0], vs[1], vs[2], vs[3], vs[4])
                    idx = [(1, 0), (0, 1), (2, 0), (0, 2), (1, 1)]
                else:
                    s.D3(a, b, P, *vs)
                    idx = [(1, 0), (0, 1), (2, 0), (0, 2), (1, 1), (3, 0), (0, 3), (2, 1), (1, 2)]
                D[m, 0, 0] = P.Coord()
                for (i, j), w in zip(idx, vs):
                    if i <= order and j <= order:
                        D[m, i, j] = w.Coord()
        return D

    return fn


# ============================================================================== p-curves
@dataclass(frozen=True)
class PCurveEvaluator:
    """A p-curve ``t -> (u, v)`` and its derivative, vectorised.

    Attributes
    ----------
    kind : str
        ``'line'``, ``'bspline'`` or ``'occ'``.
    fn : callable
        ``fn(t) -> (uv (m, 2), duv (m, 2))``.
    first, last : float
        The edge's parameter range on this p-curve.
    """

    kind: str
    fn: Callable[[Array], tuple[Array, Array]] = field(repr=False)
    first: float
    last: float
    spline: BSplineCurve | None = field(default=None, repr=False)
    line: tuple[Array, Array] | None = field(default=None, repr=False)

    def __call__(self, t: Array) -> tuple[Array, Array]:
        return self.fn(np.asarray(t, dtype=float).reshape(-1))


def pcurve_evaluator(occ_curve: Geom2d_Curve, first: float, last: float) -> PCurveEvaluator:
    """Vectorised evaluator of a ``Geom2d`` p-curve on ``[first, last]``."""
    basis = occ_curve
    while isinstance(basis, Geom2d_TrimmedCurve):
        basis = basis.BasisCurve()
    if isinstance(basis, Geom2d_Line):
        pos = basis.Position()
        o = np.array(pos.Location().Coord())
        d = np.array(pos.Direction().Coord())
        return PCurveEvaluator("line", lambda t: (o + t[:, None] * d, np.broadcast_to(d, (t.shape[0], 2))),
                               first, last, line=(o, d))
    if isinstance(basis, (Geom2d_BSplineCurve, Geom2d_BezierCurve)) and not (
        isinstance(basis, Geom2d_BSplineCurve) and basis.IsPeriodic()
    ):
        ours = _curve2d(basis)
        a, b = ours.domain

        def spline(t: Array) -> tuple[Array, Array]:
            D = ours.derivatives(np.clip(t, a, b), 1)
            return D[:, 0], D[:, 1]

        return PCurveEvaluator("bspline", spline, first, last, spline=ours)
    return PCurveEvaluator("occ", _occ_curve2d_fn(occ_curve), first, last)


def _curve2d(c: Any) -> BSplineCurve:
    P = np.array([p.Coord() for p in c.Poles()])
    occ_w = c.Weights()
    w = None if occ_w is None else _occ.from_real_array(occ_w)
    p = c.Degree()
    if isinstance(c, Geom2d_BezierCurve):
        knots = np.r_[np.zeros(p + 1), np.ones(p + 1)]
    else:
        knots = _occ.from_real_array(c.KnotSequence())
    return BSplineCurve(p, knots, P, w)


def _occ_curve2d_fn(c: Any) -> Callable[[Array], tuple[Array, Array]]:
    def fn(t: Array) -> tuple[Array, Array]:
        uv = np.empty((t.shape[0], 2))
        duv = np.empty((t.shape[0], 2))
        P, V = gp_Pnt2d(), gp_Vec2d()
        with _occ.kernel_errors(f"evaluating p-curve {type(c).__name__}"):
            for m, x in enumerate(t.tolist()):
                c.D1(x, P, V)
                uv[m] = P.Coord()
                duv[m] = V.Coord()
        return uv, duv

    return fn
