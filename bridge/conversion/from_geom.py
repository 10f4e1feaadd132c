"""OCC's curves and surfaces as ours: the conversions behind :func:`.splines.from_occ`.

Every ``Geom_Curve`` / ``Geom_Surface`` that has an exact B-spline form is converted exactly
(``GeomConvert``; Bezier and B-spline geometry pole for pole, periodic splines as their unclamped
equivalent, checked against OCC's own evaluation); offsets are approximated within a tolerance
(``GeomConvert_ApproxCurve`` / ``_ApproxSurface``). Periodic trimming ranges that overshoot a period by
round-off are snapped first (:func:`snap_periodic_range`): ``GeomConvert`` crashes on them.
"""

from __future__ import annotations

import numpy as np
from OCP.Geom import (
    Geom_BezierCurve,
    Geom_BezierSurface,
    Geom_BSplineCurve,
    Geom_BSplineSurface,
    Geom_Curve,
    Geom_OffsetCurve,
    Geom_OffsetSurface,
    Geom_RectangularTrimmedSurface,
    Geom_Surface,
    Geom_TrimmedCurve,
)
from OCP.GeomAbs import GeomAbs_Shape
from OCP.GeomConvert import GeomConvert, GeomConvert_ApproxCurve, GeomConvert_ApproxSurface

from occsurf.algorithms import BSplineCurve, BSplineSurface
from occsurf.algorithms.errors import InvalidGeometryError, KernelError, ToleranceError

from .. import _occ

__all__ = ["from_geom_curve", "from_geom_surface", "snap_periodic_range", "PERIOD_SNAP"]

#: Limits handed to the approximators: highest degree and number of spans.
_APPROX_MAX_DEGREE = 14
_APPROX_MAX_SEGMENTS = 100

#: ``Precision::IsInfinite``: parameters of magnitude >= 1e100 mean "unbounded".
_INFINITE = 1e100


# --------------------------------------------------------------------------------- curves
#: A trimming bound within ``PERIOD_SNAP * period`` of a multiple of the period (or a range within
#: that of one whole period) is snapped onto it before OCC converts a periodic curve or surface:
#: ``GeomConvert`` crashes the process (segfault) or returns a spline with no poles for ranges
#: that overshoot a period by round-off, e.g. a cylinder face trimmed to [-8.9e-16, 6.28318530718].
PERIOD_SNAP: float = 1e-9


def snap_periodic_range(a: float, b: float, period: float) -> tuple[float, float]:
    """Snap ``[a, b]`` onto multiples of ``period`` and onto one whole period within
    :data:`PERIOD_SNAP`; a range longer than one period is refused."""
    tol = PERIOD_SNAP * period
    ka, kb = round(a / period), round(b / period)
    if abs(a - ka * period) <= tol:
        a = ka * period
    if abs(b - kb * period) <= tol:
        b = kb * period
    if abs((b - a) - period) <= tol:
        b = a + period
    if b - a > period:
        raise InvalidGeometryError(
            f"from_occ: bounds [{a!r}, {b!r}] span more than one period ({period!r}) of a periodic geometry"
        )
    return float(a), float(b)


def from_geom_curve(occ_curve: Geom_Curve, bounds: tuple[float, ...] | None, tol: float) -> BSplineCurve:
    if bounds is None and isinstance(occ_curve, Geom_BSplineCurve):
        return _curve_from_bspline(occ_curve)
    if bounds is None and isinstance(occ_curve, Geom_BezierCurve):
        return _curve_from_bezier(occ_curve)
    if bounds is None:
        t0, t1 = occ_curve.FirstParameter(), occ_curve.LastParameter()
        if abs(t0) >= _INFINITE or abs(t1) >= _INFINITE:
            raise InvalidGeometryError(
                f"from_occ: {type(occ_curve).__name__} is unbounded; pass bounds=(t0, t1)"
            )
    if bounds is not None and occ_curve.IsPeriodic():
        bounds = snap_periodic_range(float(bounds[0]), float(bounds[1]), occ_curve.Period())
    with _occ.kernel_errors(f"from_occ: converting {type(occ_curve).__name__}"):
        c = occ_curve if bounds is None else Geom_TrimmedCurve(occ_curve, bounds[0], bounds[1])
        if _is_offset_curve(c):
            occ_b = _approx_curve(c, tol)
        else:
            occ_b = GeomConvert.CurveToBSplineCurve_s(c)
    return _curve_from_bspline(occ_b)


def _is_offset_curve(c: Geom_Curve) -> bool:
    while isinstance(c, Geom_TrimmedCurve):
        c = c.BasisCurve()
    return isinstance(c, Geom_OffsetCurve)


def _approx_curve(c: Geom_Curve, tol: float) -> Geom_BSplineCurve:
    ap = GeomConvert_ApproxCurve(c, tol, GeomAbs_Shape.GeomAbs_C2, _APPROX_MAX_SEGMENTS, _APPROX_MAX_DEGREE)
    if not ap.HasResult():
        raise KernelError(f"from_occ: GeomConvert_ApproxCurve gave no result for {type(c).__name__}")
    if not ap.IsDone() or ap.MaxError() > tol:
        raise ToleranceError(
            f"from_occ: the offset curve could not be approximated within tol={tol:g} "
            f"(best {ap.MaxError():.3g})"
        )
    return ap.Curve()


def _curve_from_bezier(occ_curve: Geom_BezierCurve) -> BSplineCurve:
    p = occ_curve.Degree()
    P = _occ.from_pnt_array(occ_curve.Poles())
    w = occ_curve.Weights()
    knots = np.r_[np.zeros(p + 1), np.ones(p + 1)]
    return BSplineCurve(p, knots, P, None if w is None else _occ.from_real_array(w))


def _curve_from_bspline(occ_curve: Geom_BSplineCurve) -> BSplineCurve:
    p = occ_curve.Degree()
    P = _occ.from_pnt_array(occ_curve.Poles())
    occ_w = occ_curve.Weights()  # None if polynomial (IsRational is reliable for curves, this is too)
    w = None if occ_w is None else _occ.from_real_array(occ_w)
    flat = _occ.from_real_array(occ_curve.KnotSequence())
    rebuilt = False
    if occ_curve.IsPeriodic():
        occ_flat = flat
        flat = _periodic_flat(flat, _occ.from_real_array(occ_curve.Knots()),
                              _occ.from_int_array(occ_curve.Multiplicities()), p, P.shape[0])
        rebuilt = flat is not occ_flat
        idx = np.arange(flat.shape[0] - p - 1) % P.shape[0]
        P = P[idx]
        w = None if w is None else w[idx]
    c = BSplineCurve(p, flat, P, w)
    if rebuilt:
        u = np.linspace(*c.domain, 17)
        ref = np.array([occ_curve.Value(float(x)).Coord() for x in u])
        _check_rebuilt_periodic(c.evaluate(u), ref, c.control_points, P.shape[0], p)
    return c


def _check_rebuilt_periodic(ours: np.ndarray, ref: np.ndarray, poles: np.ndarray, n: int, p: int) -> None:
    """A rebuilt periodic flat knot vector must reproduce OCC's own evaluation (it does for
    ``n_poles == degree``, OCC's periodic circles; OCC's evaluation is not the periodic extension
    for fewer poles)."""
    scale = max(1.0, float(np.max(np.abs(poles))))
    dev = float(np.max(np.abs(ours - ref)))
    if dev > 1e-9 * scale:
        raise InvalidGeometryError(
            f"from_occ: periodic spline with {n} poles and degree {p} is not supported: with fewer than "
            f"degree + 1 poles OCC's own evaluation is not the periodic extension (differs by {dev:.2g})"
        )


def _periodic_flat(occ_flat: np.ndarray, knots: np.ndarray, mults: np.ndarray, degree: int, n_poles: int) -> np.ndarray:
    """The flat knot vector of the unclamped equivalent of a periodic spline.

    OCC's ``KnotSequence()`` is used as it is when valid (bit-exact). It is invalid (not
    non-decreasing) when the spline has fewer than ``degree + 1`` poles, e.g. OCC's periodic circle
    of degree 6 with 6 poles that every build123d sweep of a circular profile contains. Then the
    sequence is built here with OCC's own convention, checked against ``KnotSequence`` on valid
    splines: the periodic knot sequence ``s_j = b_(j mod n) + T floor(j / n)`` (``b`` the distinct
    knots but the last, repeated by their multiplicities; ``T`` the period) read from
    ``j = M_0 - 1 - degree``, so that pole ``j`` belongs to flat index ``j`` in both.
    """
    if n_poles >= degree + 1 and not np.any(np.diff(occ_flat) < 0):
        return occ_flat
    n, p = n_poles, degree
    base = np.repeat(knots[:-1], mults[:-1])
    if base.shape[0] != n:
        raise InvalidGeometryError(
            f"from_occ: periodic spline with {n} poles but multiplicities summing to {base.shape[0]}"
        )
    period = knots[-1] - knots[0]
    j = np.arange(n + 2 * p + 1) + (int(mults[0]) - 1 - p)
    flat = base[np.mod(j, n)] + period * np.floor_divide(j, n)
    flat[p], flat[n + p] = knots[0], knots[-1]  # the domain ends exactly
    return flat


# --------------------------------------------------------------------------------- surfaces
def from_geom_surface(occ_surface: Geom_Surface, bounds: tuple[float, ...] | None, tol: float) -> BSplineSurface:
    if bounds is None and isinstance(occ_surface, Geom_BSplineSurface):
        return _surface_from_bspline(occ_surface)
    if bounds is None and isinstance(occ_surface, Geom_BezierSurface):
        return _surface_from_bezier(occ_surface)
    if bounds is None:
        if any(abs(x) >= _INFINITE for x in occ_surface.Bounds()):
            raise InvalidGeometryError(
                f"from_occ: {type(occ_surface).__name__} is unbounded; pass bounds=(u0, u1, v0, v1)"
            )
    if bounds is not None:
        u0, u1, v0, v1 = (float(x) for x in bounds)
        if occ_surface.IsUPeriodic():
            u0, u1 = snap_periodic_range(u0, u1, occ_surface.UPeriod())
        if occ_surface.IsVPeriodic():
            v0, v1 = snap_periodic_range(v0, v1, occ_surface.VPeriod())
        bounds = (u0, u1, v0, v1)
    with _occ.kernel_errors(f"from_occ: converting {type(occ_surface).__name__}"):
        s = occ_surface if bounds is None else Geom_RectangularTrimmedSurface(occ_surface, *bounds)
        if _needs_surface_approx(s):
            occ_b = _approx_surface(s, tol)
        else:
            occ_b = GeomConvert.SurfaceToBSplineSurface_s(s)
    return _surface_from_bspline(occ_b)


def _needs_surface_approx(s: Geom_Surface) -> bool:
    """An offset surface (possibly trimmed) without an analytic equivalent (``Surface()`` is null)."""
    while isinstance(s, Geom_RectangularTrimmedSurface):
        s = s.BasisSurface()
    return isinstance(s, Geom_OffsetSurface) and s.Surface() is None


def _approx_surface(s: Geom_Surface, tol: float) -> Geom_BSplineSurface:
    C2 = GeomAbs_Shape.GeomAbs_C2
    ap = GeomConvert_ApproxSurface(s, tol, C2, C2, _APPROX_MAX_DEGREE, _APPROX_MAX_DEGREE, _APPROX_MAX_SEGMENTS, 1)
    if not ap.HasResult():
        raise KernelError(f"from_occ: GeomConvert_ApproxSurface gave no result for {type(s).__name__}")
    if not ap.IsDone() or ap.MaxError() > tol:
        raise ToleranceError(
            f"from_occ: the offset surface could not be approximated within tol={tol:g} (best {ap.MaxError():.3g})"
        )
    return ap.Surface()


def _surface_from_bezier(occ_surface: Geom_BezierSurface) -> BSplineSurface:
    p, q = occ_surface.UDegree(), occ_surface.VDegree()
    P = _occ.from_pnt_array2(occ_surface.Poles())
    occ_w = occ_surface.Weights()
    w = None if occ_w is None else _occ.from_real_array2(occ_w)
    U = np.r_[np.zeros(p + 1), np.ones(p + 1)]
    V = np.r_[np.zeros(q + 1), np.ones(q + 1)]
    return BSplineSurface((p, q), (U, V), P, w)


def _surface_from_bspline(occ_surface: Geom_BSplineSurface) -> BSplineSurface:
    p, q = occ_surface.UDegree(), occ_surface.VDegree()
    P = _occ.from_pnt_array2(occ_surface.Poles())
    occ_w = occ_surface.Weights()  # not IsURational(): it is False when weights vary only along u
    w = None if occ_w is None else _occ.from_real_array2(occ_w)
    U = _occ.from_real_array(occ_surface.UKnotSequence())
    V = _occ.from_real_array(occ_surface.VKnotSequence())
    occ_U, occ_V = U, V
    if occ_surface.IsUPeriodic():
        U = _periodic_flat(U, _occ.from_real_array(occ_surface.UKnots()),
                           _occ.from_int_array(occ_surface.UMultiplicities()), p, P.shape[0])
        idx = np.arange(U.shape[0] - p - 1) % P.shape[0]
        P = P[idx]
        w = None if w is None else w[idx]
    if occ_surface.IsVPeriodic():
        V = _periodic_flat(V, _occ.from_real_array(occ_surface.VKnots()),
                           _occ.from_int_array(occ_surface.VMultiplicities()), q, P.shape[1])
        idx = np.arange(V.shape[0] - q - 1) % P.shape[1]
        P = P[:, idx]
        w = None if w is None else w[:, idx]
    s = BSplineSurface((p, q), (U, V), P, w)
    if U is not occ_U or V is not occ_V:
        (u0, u1), (v0, v1) = s.domain
        uu, vv = (x.ravel() for x in np.meshgrid(np.linspace(u0, u1, 7), np.linspace(v0, v1, 7), indexing="ij"))
        ref = np.array([occ_surface.Value(float(a), float(b)).Coord() for a, b in zip(uu, vv)])
        _check_rebuilt_periodic(s.evaluate(uu, vv), ref, s.control_points, max(P.shape[:2]), max(p, q))
    return s


# ================================================================================= topology
