"""Line curvature plots (course ch. 9): curvature combs ("porcupines") with inflection points, for
B-spline curves, sampled curves with derivatives (section cuts) and exact iso-parameter curves.

A comb draws at each sample ``x(t)`` a spine ``x - scale * kappa_s * n`` perpendicular to the curve,
its length proportional to the curvature; ``n = m x T`` is the in-plane normal for the plane normal
``m`` and ``kappa_s`` the signed curvature, so the spines change side at an inflection (Rhino's
curvature graph, CATIA's porcupine analysis). A fair curve has a smooth comb outline; bumps,
kinks and extra sign changes of the outline are the defects a designer looks for.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from .. import _validate as V
from .. import tolerances
from ..errors import InvalidGeometryError
from ..hierarchical.surface import HierarchicalSurface
from ..kernel.basis import basis_functions, find_span
from ..kernel.curve import BSplineCurve
from ..kernel.surface import BSplineSurface
from ._common import Array, dot, unit_vectors, vectors

__all__ = ["Comb", "SampledCurve", "curvature_comb", "iso_curves", "signed_curvature", "find_sign_changes"]


@dataclass(frozen=True)
class SampledCurve:
    """A curve known by samples with derivatives (a section cut, a polyline from a solver).

    Attributes
    ----------
    params : ndarray, shape (k,)
        Increasing parameters of the samples.
    points, d1, d2 : ndarray, shape (k, 3)
        Point and first and second derivatives with respect to ``params``.
    derivatives : callable, optional
        ``derivatives(t) -> (m, 3, 3)``: point, first and second derivative of the exact curve at
        parameters ``t (m,)`` inside ``[params[0], params[-1]]``. When given, inflections are
        root-found on it; without it, on the quintic Hermite interpolant of the samples (which
        matches their points, first and second derivatives).
    """

    params: Array
    points: Array
    d1: Array
    d2: Array
    derivatives: Callable[[Array], Array] | None = None


@dataclass(frozen=True)
class Comb:
    """A curvature comb.

    Attributes
    ----------
    params : ndarray, shape (k,)
    points, tips : ndarray, shape (k, 3)
        Curve points and spine tips ``points - scale * kappa_s * n`` (unsigned: ``- scale * kappa * N``
        with the Frenet normal ``N``, i.e. spines on the convex side).
    curvature : ndarray, shape (k,)
        Unsigned curvature (1/model units).
    signed : ndarray, shape (k,) or None
        Signed curvature in the plane (positive: turning to the left of ``T`` about the plane normal);
        None without a plane.
    inflection_params : ndarray, shape (j,)
        Parameters where ``signed`` changes sign (empty without a plane).
    inflection_points : ndarray, shape (j, 3)
    scale : float
        Spine length per unit curvature (model units squared).
    plane_normal : ndarray, shape (3,) or None
    """

    params: Array
    points: Array
    tips: Array
    curvature: Array
    signed: Array | None
    inflection_params: Array
    inflection_points: Array
    scale: float
    plane_normal: Array | None

    @property
    def n_inflections(self) -> int:
        return int(self.inflection_params.size)


def signed_curvature(d1: Array, d2: Array, m: Array | None) -> tuple[Array, Array | None, Array]:
    """Unsigned and (with a plane normal ``m``) signed curvature and the spine direction.

    .. math:: \\kappa = \\frac{|x' \\times x''|}{|x'|^3}, \\qquad
              \\kappa_s = \\frac{(x' \\times x'') \\cdot m}{|x'|^3}

    Returns ``(kappa, kappa_s, spine)`` where ``spine`` (k, 3) is the unit vector the spine of
    a positive value points along (``-(m x T)`` with a plane, ``-N`` without).
    """
    c = np.cross(d1, d2)
    s = np.linalg.norm(d1, axis=-1)
    with np.errstate(invalid="ignore", divide="ignore"):
        kappa = np.linalg.norm(c, axis=-1) / s**3
        T = d1 / s[..., None]
        if m is not None:
            ks = dot(c, m) / s**3
            return kappa, ks, -np.cross(m, T)
        B = c / np.linalg.norm(c, axis=-1)[..., None]
        N = np.cross(B, T)
    return kappa, None, -np.nan_to_num(N)


def find_sign_changes(f: Callable[[Array], Array], t: Array, values: Array, zero: float, tol: float,
                      max_steps: int = 200) -> Array:
    """Roots of ``f`` between samples ``t`` (increasing) whose ``values`` change sign.

    Values with ``|value| <= zero`` count as 0 and are skipped (a straight piece between two
    opposite bends is one inflection, not a cluster); each bracket ``[t_i, t_j]`` between
    consecutive non-zero samples of opposite sign is shrunk by vectorised bisection (all brackets
    at once) until shorter than ``tol``.
    """
    nz = np.flatnonzero(np.abs(values) > zero)
    if nz.size < 2:
        return np.empty(0)
    sv = np.sign(values[nz])
    k = np.flatnonzero(sv[1:] != sv[:-1])
    a, b = t[nz[k]].astype(float), t[nz[k + 1]].astype(float)
    fa = sv[k]
    for _ in range(max_steps):
        if a.size == 0 or np.all(b - a <= tol):
            break
        mid = 0.5 * (a + b)
        fm = np.asarray(f(mid), float)
        left = np.sign(fm) == fa  # root in [mid, b]
        zero_at = fm == 0
        a = np.where(left & ~zero_at, mid, a)
        b = np.where(~left | zero_at, mid, b)
        a = np.where(zero_at, mid, a)
    return 0.5 * (a + b)


def _plane_of(curve_dim: int, plane_normal: ArrayLike | None) -> Array | None:
    if plane_normal is not None:
        m = unit_vectors(plane_normal, "plane_normal")
        if m.ndim != 1:
            raise InvalidGeometryError(f"plane_normal: expected one 3-vector, got shape {m.shape}")
        return m
    return np.array([0.0, 0.0, 1.0]) if curve_dim == 2 else None


def _pad3(a: Array) -> Array:
    return a if a.shape[-1] == 3 else np.concatenate((a, np.zeros(a.shape[:-1] + (3 - a.shape[-1],))), -1)


def _bracket_params(curve: BSplineCurve, n: int) -> Array:
    """Dense sampling for root bracketing: at least 16 samples in every non-empty knot span."""
    kn = np.unique(curve.knots[curve.degree: curve.n_poles + 1])
    per = np.linspace(0.0, 1.0, 17)[:-1]
    dense = (kn[:-1, None] + np.diff(kn)[:, None] * per).ravel()
    lo, hi = curve.domain
    return np.unique(np.concatenate((dense, np.linspace(lo, hi, n), [hi])))


def _finish(params: Array, P: Array, kappa: Array, ks: Array | None, spine: Array, scale: float | None,
            m: Array | None, infl_t: Array, infl_p: Array) -> Comb:
    P = _pad3(P)
    size = float(np.linalg.norm(np.ptp(P, axis=0))) if P.size else 0.0
    if scale is None:
        kmax = float(np.nanmax(kappa)) if np.any(np.isfinite(kappa)) else 0.0
        # a straight curve (a cut of a plane) has round-off curvature only: no spines, not a full-size
        # comb of noise
        scale = 0.2 * size / kmax if kmax * size > tolerances.QUALITY_FLAT_CURVATURE else 0.0
    elif not np.isfinite(float(scale)):
        raise InvalidGeometryError(f"scale: expected a finite number, got {scale!r}")
    amount = kappa if ks is None else ks
    tips = P + float(scale) * np.nan_to_num(amount)[:, None] * spine
    return Comb(params=params, points=P, tips=tips, curvature=kappa, signed=ks, inflection_params=infl_t,
                inflection_points=_pad3(infl_p), scale=float(scale), plane_normal=m)


def curvature_comb(curve: BSplineCurve | SampledCurve, n: int = 200, *, scale: float | None = None,
                   plane_normal: ArrayLike | None = None) -> Comb:
    """Curvature comb of a curve with its inflection points (course ch. 9, line curvature plots).

    Parameters
    ----------
    curve : BSplineCurve or SampledCurve
        2-D or 3-D B-spline / NURBS curve (evaluated exactly), or samples with derivatives.
    n : int
        Number of spines (B-spline curves: equally spaced parameters; sampled curves: their samples).
    scale : float, optional
        Spine length per unit curvature; default: the longest spine is 20 % of the curve's extent.
    plane_normal : array_like, shape (3,), optional
        Plane of the curve (of the section cut) for the signed curvature and the inflections;
        2-D curves default to ``(0, 0, 1)``.

    Returns
    -------
    Comb

    Notes
    -----
    Inflections of a B-spline curve are the sign changes of ``(C' x C'') . m``, bracketed on at
    least 16 samples per knot span and located by vectorised bisection on the exact curve to
    :data:`~occsurf.algorithms.tolerances.QUALITY_INFLECTION_TOL` of the parameter range. Those of a
    sampled curve are root-found the same way, on its exact ``derivatives`` when it has them, else on
    the piecewise quintic Hermite interpolant of its samples (points, first and second derivatives
    matched at every sample; the signed curvature's numerator ``(x' x x'') . m`` of each piece is
    a polynomial, bisected to the same tolerance);
    :func:`~occsurf.algorithms.quality.plane_sections` refines its own on the exact surface.
    """
    if isinstance(curve, SampledCurve):
        return _sampled_comb(curve, scale, plane_normal)
    if not isinstance(curve, BSplineCurve):
        raise InvalidGeometryError(f"curve: expected a BSplineCurve or SampledCurve, got {type(curve).__name__}")
    if curve.dim not in (2, 3):
        raise InvalidGeometryError(f"curve: needs a 2-D or 3-D curve, this one has dim {curve.dim}")
    # per sample: its derivatives to order 2, the comb's fields and the inflection brackets
    n = V.check_count(n, "n", 24 * (curve.degree + 4), minimum=2)
    m = _plane_of(curve.dim, plane_normal)
    lo, hi = curve.domain
    t = np.linspace(lo, hi, int(n))
    D = _pad3(curve.derivatives(t, 2))
    kappa, ks, spine = signed_curvature(D[:, 1], D[:, 2], m)
    infl = np.empty(0)
    if m is not None:
        def f(u: Array) -> Array:
            E = _pad3(curve.derivatives(u, 2))
            return dot(np.cross(E[:, 1], E[:, 2]), m)

        tb = _bracket_params(curve, int(n))
        Eb = _pad3(curve.derivatives(tb, 2))
        fb = dot(np.cross(Eb[:, 1], Eb[:, 2]), m)
        zero = tolerances.CURVATURE_ZERO * np.max(np.linalg.norm(Eb[:, 1], axis=1) * np.linalg.norm(Eb[:, 2], axis=1))
        infl = find_sign_changes(f, tb, fb, zero, tolerances.QUALITY_INFLECTION_TOL * (hi - lo))
    pts = curve.evaluate(infl) if infl.size else np.empty((0, curve.dim))
    return _finish(t, D[:, 0], kappa, ks, spine, scale, m, infl, pts)


def _sampled_comb(c: SampledCurve, scale: float | None, plane_normal: ArrayLike | None) -> Comb:
    t = V.as_finite_array(c.params, "curve.params", ndim=1)
    P, d1, d2 = (vectors(x, f"curve.{name}") for x, name in ((c.points, "points"), (c.d1, "d1"), (c.d2, "d2")))
    if not (P.shape == d1.shape == d2.shape == (t.size, 3)):
        raise InvalidGeometryError(f"curve: points, d1, d2 must all have shape ({t.size}, 3)")
    if t.size < 2 or np.any(np.diff(t) <= 0):
        raise InvalidGeometryError("curve.params: expected at least 2 increasing parameters")
    m = _plane_of(3, plane_normal)
    kappa, ks, spine = signed_curvature(d1, d2, m)
    infl_t, infl_p = np.empty(0), np.empty((0, 3))
    if m is not None and ks is not None:  # ks (the signed curvature) is None exactly when m is
        zero = tolerances.CURVATURE_ZERO * float(np.nanmax(kappa, initial=0.0))
        if c.derivatives is not None:
            exact = c.derivatives

            def deriv(x: Array) -> Array:
                D = np.asarray(exact(x), float)
                if D.shape != (x.size, 3, 3):
                    raise InvalidGeometryError(f"curve.derivatives: expected an array of shape ({x.size}, 3, 3) "
                                               f"(point, first, second derivative), got {D.shape}")
                return D
        else:
            def deriv(x: Array) -> Array:
                return _hermite5(t, P, d1, d2, x)

        def f(x: Array) -> Array:
            D = deriv(x)
            return dot(np.cross(D[:, 1], D[:, 2]), m)

        infl_t = find_sign_changes(f, t, ks, zero, tolerances.QUALITY_INFLECTION_TOL * float(t[-1] - t[0]))
        infl_p = deriv(infl_t)[:, 0] if infl_t.size else np.empty((0, 3))
    return _finish(t, P, kappa, ks, spine, scale, m, infl_t, infl_p)


def _hermite5(t: Array, P: Array, d1: Array, d2: Array, x: Array) -> Array:
    """Point, first and second derivative ``(m, 3, 3)`` at ``x (m,)`` of the piecewise quintic
    Hermite interpolant of samples ``(t, P, d1, d2)``: on ``[t_i, t_i+1]``, with ``s = (x - t_i) / h``,
    ``p(s) = sum_k c_k s^k`` where ``c0 = P_i``, ``c1 = h d1_i``, ``c2 = h^2 d2_i / 2`` and
    ``c3, c4, c5`` solve the three conditions at ``s = 1`` in closed form."""
    i = np.clip(np.searchsorted(t, x, side="right") - 1, 0, t.size - 2)
    h = (t[i + 1] - t[i])[:, None]
    s = ((x - t[i]) / h[:, 0])[:, None]
    p0, v0, a0 = P[i], h * d1[i], h * h * d2[i]
    p1, v1, a1 = P[i + 1], h * d1[i + 1], h * h * d2[i + 1]
    r0, r1, r2 = p1 - p0 - v0 - 0.5 * a0, v1 - v0 - a0, a1 - a0
    c3 = 10 * r0 - 4 * r1 + 0.5 * r2
    c4 = -15 * r0 + 7 * r1 - r2
    c5 = 6 * r0 - 3 * r1 + 0.5 * r2
    c2 = 0.5 * a0
    pt = p0 + s * (v0 + s * (c2 + s * (c3 + s * (c4 + s * c5))))
    dp = v0 + s * (2 * c2 + s * (3 * c3 + s * (4 * c4 + s * 5 * c5)))
    ddp = 2 * c2 + s * (6 * c3 + s * (12 * c4 + s * 20 * c5))
    return np.stack((pt, dp / h, ddp / (h * h)), axis=1)


def iso_curves(surface: BSplineSurface | HierarchicalSurface, direction: str, values: ArrayLike) -> list[BSplineCurve]:
    """Exact iso-parameter curves of a tensor-product surface.

    ``direction="u"``: the curves ``v -> S(u_k, v)`` at constant ``u = values[k]`` (OCC's
    ``UIso``); ``"v"``: ``u -> S(u, v_k)``. Each is the surface's homogeneous net contracted with
    the basis functions at the constant parameter, ``Q_j = sum_i N_{i,p}(u_k) P^w_{ij}`` (the pole
    row that knot insertion to full multiplicity would expose), so it is exact, rational included.

    Parameters
    ----------
    surface : BSplineSurface or HierarchicalSurface
        A hierarchical surface is flattened first (exact).
    direction : {"u", "v"}
    values : array_like, shape (k,)

    Returns
    -------
    list of BSplineCurve
    """
    if isinstance(surface, HierarchicalSurface):
        surface = surface.flatten()
    if not isinstance(surface, BSplineSurface):
        raise InvalidGeometryError(f"surface: expected a BSplineSurface or HierarchicalSurface, got {type(surface).__name__}")
    if direction not in ("u", "v"):
        raise InvalidGeometryError(f"direction: expected 'u' or 'v', got {direction!r}")
    ax = 0 if direction == "u" else 1
    lo, hi = surface.domain[ax]
    x = V.check_parameters(values, lo, hi, "values").reshape(-1)
    p, t, npol = surface.degree[ax], surface.knots[ax], surface.n_poles[ax]
    span = find_span(t, p, npol, x)
    N = basis_functions(t, p, span, x)  # (k, p+1)
    H = surface.homogeneous_points if ax == 0 else surface.homogeneous_points.transpose(1, 0, 2)
    idx = span[:, None] - p + np.arange(p + 1)  # (k, p+1)
    rows = np.einsum("kr,krjc->kjc", N, H[idx])  # (k, n_other, d+1)
    q, kn = surface.degree[1 - ax], surface.knots[1 - ax]
    return [BSplineCurve._from_homogeneous(q, kn, r, surface.is_rational) for r in rows]

