r"""Generalised sweep of a profile along a path with a moving frame and scaling / twist laws
(course §6-26 .. §6-33, "Sweeping"; course §6-6 for the frames; The NURBS Book, 2nd ed., §10.4).

The exact sweep
---------------
Let ``C(v)`` be the path on ``[v0, v1]``, ``F(v) = [T N B]`` a moving orthonormal frame (columns),
``t = (v - v0) / (v1 - v0)`` the normalised path parameter, ``s(t)`` a scaling law and ``φ(t)`` a
twist law (radians, about the tangent). The profile ``P(u)`` is given where it should sit at the
path start, and is carried along in the coordinates of the start frame:

.. math:: E(u, v) = C(v) + s(t)\, F(v)\, R_T(φ(t))\, F(v_0)^\top \big(P(u) - C(v_0)\big),

``R_T(φ)`` the rotation by ``φ`` about the first (tangent) axis. With ``s ≡ 1`` and ``φ ≡ 0`` the
start section is the profile itself. For every ``v`` the map ``P -> E`` is affine, so the section
``E(·, v)`` is *exactly* the profile with its poles ``P_i`` mapped (weights unchanged, rational
profiles included): only the dependence on ``v`` needs approximating.

Frames (``frame=``)
-------------------
* ``"rmf"`` — rotation-minimising frames (no twist about the tangent; Wang et al. 2008 double
  reflection, :func:`occsurf.algorithms.geometry.differential.rotation_minimizing_frames`). The frames come from a
  fixed reference chain of ``SWEEP_RMF_STEPS`` steps per path span, plus one double-reflection step
  from the nearest reference sample to each query, so every query sees the same frame field.
  The start normal does not matter: the profile is carried in start-frame coordinates.
  OCC's closest mode is ``GeomFill_IsCorrectedFrenet``. On a *closed*, tangent-continuous path
  (ends within ``SWEEP_CLOSE_TOL``) the RMF returns turned about the tangent by its holonomy angle
  ``α`` (zero only for planar paths), so the surface would not close; the sweep then adds the
  twist ``-α t`` (``t`` the normalised path parameter), the minimal uniform correction, and the
  surface closes (as Rhino and CATIA close sweeps along closed rails).
* ``"frenet"`` — the Frenet frame (course §6-2); undefined where the path's curvature vanishes (an
  error), and it flips at inflections. OCC: ``GeomFill_IsFrenet``.
* ``"fixed"`` — the start frame throughout (a translational sweep, with the laws applied).

Approximation and error report
------------------------------
The sweep is approximated by a spline of degree ``degree`` in v whose pole rows interpolate the
mapped profile poles ``P_i(v)`` at the Greville abscissae of the v knot vector (course §7-5;
:func:`occsurf.algorithms.fitting.interpolation.interpolate_values`). The initial v knots are the path's knots (with
multiplicities matching the continuity of the frame field there) with each span cut in
``SWEEP_INITIAL_PIECES``; a span whose error exceeds ``tol`` is cut into as many pieces as the
``h^(degree+1)`` error model asks for (``SWEEP_SPLIT_SAFETY``), until no span exceeds ``tol``. Because the
sections are affine images of one profile with fixed weights, the surface error at ``(u, v)`` is a
convex combination of the pole-row errors, so

.. math:: \max_u |S(u, v) - E(u, v)| \le \max_i |Q_i(v) - P_i(v)|,

the *pole bound*, which the refinement drives below ``tol`` at ``SWEEP_CHECKS_PER_SPAN`` points per
span. Interpolation is linear and ``P_i(v) = C(v) + A(v) (P_i - C(v_0))`` is linear in the 12
numbers of the map ``(C(v), A(v))``, so the refinement interpolates those 12 functions and maps
the resulting poles (the same pole rows, whatever the number of profile poles); each parameter's
map is computed once per sweep. The final report then measures ``max |S - E|`` directly on a
dense grid (every profile span and ``SWEEP_VERIFY_PER_SPAN`` v values per v span, all off the
interpolation sites). Both numbers are parametric deviations, upper bounds of the distance between
the surfaces.

Every tolerance and limit named here (``SWEEP_...``) is in :mod:`occsurf.algorithms.tolerances`,
read at call time, so :func:`occsurf.algorithms.tolerances.override` changes it.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal, overload

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import _validate as V
from .. import tolerances
from ..errors import InvalidGeometryError, ToleranceError
from ..fitting.interpolation import interpolate_values
from ..kernel.basis import greville
from ..kernel.curve import BSplineCurve
from ..kernel.knots import distinct_knots
from ..kernel.surface import BSplineSurface
from ._common import check_curve
from .sweep_frames import PathFrames

__all__ = [
    "SweepResult",
    "sweep",
    "exact_sweep",
]

Array = NDArray[np.float64]
Law = float | Callable[[Array], ArrayLike] | None

_FRAMES = ("rmf", "frenet", "fixed")


def _check_fractions() -> Array:
    """Where in each v span (fractions of its length, off the fitting sites) the pole bound is
    checked during refinement: ``tolerances.SWEEP_CHECKS_PER_SPAN`` points."""
    n = int(tolerances.SWEEP_CHECKS_PER_SPAN)
    return (np.arange(n) + 0.5) / n * 0.96 + 0.013


def _verify_fractions() -> Array:
    """Where in each v span the final verification and the report look:
    ``tolerances.SWEEP_VERIFY_PER_SPAN`` points, off the fitting and check sites."""
    n = int(tolerances.SWEEP_VERIFY_PER_SPAN)
    return (np.arange(n) + 0.5) / n * 0.97 + 0.011


@dataclass(frozen=True)
class SweepResult:
    """A generalised sweep and its measured error.

    Attributes
    ----------
    surface : BSplineSurface
        u: the profile's parameter (its knots and degree, exact); v: the path's domain.
    max_error : float
        ``max |S(u, v) - E(u, v)|`` over the dense verification grid (off the fitting sites),
        ``E`` the exact sweep (module notes). A sampled maximum: on a 7x denser grid the true
        supremum measured up to 1.7 % above it.
    pole_bound : float
        ``max_i |Q_i(v) - P_i(v)|`` at the same v values: an upper bound of the error over all u
        at those v, and at most ``tol`` (refinement continues until it is); it bounded the true
        supremum over (u, v) in every case measured (``tests/algorithms/test_sweeping.py``,
        true / pole_bound <= 0.81).
    tol : float
        The absolute tolerance the refinement met (``pole_bound <= tol`` at the check points).
    n_sections : int
        Pole rows in v.
    iterations : int
        Refinement passes.
    n_checked : int
        Surface points compared in ``max_error``.
    frame : str
    """

    surface: BSplineSurface
    max_error: float
    pole_bound: float
    tol: float
    n_sections: int
    iterations: int
    n_checked: int
    frame: str


# ------------------------------------------------------------------------------------- inputs
def _check_curve(curve: object, name: str) -> BSplineCurve:
    return check_curve(curve, name, dim=3)


def _law(law: Law, name: str, default: float, nonnegative: bool) -> Callable[[Array], Array]:
    if law is None:
        law = default
    if not callable(law):
        try:
            c = float(law)
        except (TypeError, ValueError) as err:
            raise InvalidGeometryError(f"{name}: expected a number or a callable of t in [0, 1], got {law!r}") from err
        if not math.isfinite(c) or (nonnegative and c < 0):
            raise InvalidGeometryError(f"{name}: expected a finite{' non-negative' if nonnegative else ''} number, got {law!r}")
        return lambda t: np.full(t.shape, c)

    fn = law

    def evaluate(t: Array) -> Array:
        try:
            out = np.asarray(fn(t), dtype=float)
        except (TypeError, ValueError) as err:
            raise InvalidGeometryError(f"{name}: the law must map an array t of shape (m,) to m real numbers ({err})") from err
        try:
            out = np.broadcast_to(out.reshape(-1) if out.size == t.size else out, t.shape).astype(float)
        except ValueError as err:
            raise InvalidGeometryError(f"{name}: expected {t.shape[0]} values for t of shape {t.shape}, got shape {out.shape}") from err
        if not np.all(np.isfinite(out)):
            k = int(np.argmax(~np.isfinite(out)))
            raise InvalidGeometryError(f"{name}: the law is not finite at t = {float(t[k])!r}")
        if nonnegative and np.any(out < 0):
            k = int(np.argmax(out < 0))
            raise InvalidGeometryError(f"{name}: expected a non-negative scale, got {float(out[k])!r} at t = {float(t[k])!r}")
        return out

    return evaluate


class _Sweep:
    """The exact sweep: ``E = C(v) + A(v) (X - C(v0))`` for points or poles ``X``."""

    def __init__(self, profile: BSplineCurve, path: BSplineCurve, frame: str, scale: Law, twist: Law) -> None:
        self.profile, self.path = profile, path
        self.frames = PathFrames(path, frame)
        self.scale = _law(scale, "scale", 1.0, nonnegative=True)
        self.twist = _law(twist, "twist", 0.0, nonnegative=False)
        self.v0, self.v1 = path.domain
        self.c0 = path.evaluate(self.v0)
        self.start_T = np.ascontiguousarray(self.frames.start.T)
        self.xc = np.ascontiguousarray((profile.control_points - self.c0).T)  # (3, n_u)
        # memo of affine(): the parameters met so far (sorted) and their rows
        self._memo_v, self._memo_g = np.empty(0), np.empty((0, 12))

    def maps(self, v: Array) -> tuple[Array, Array]:
        """``C(v)`` (m, 3) and ``A(v)`` (m, 3, 3)."""
        t = (v - self.v0) / (self.v1 - self.v0)
        D = self.path.derivatives(v, self.frames.order)  # position and the frame's derivatives at once
        F = self.frames(v, D)
        phi, s = self.twist(t) - self.frames.holonomy * t, self.scale(t)
        c, sn = np.cos(phi), np.sin(phi)
        # F R_T(phi) without forming R: the first column stays, columns 2 and 3 rotate.
        FR = np.empty_like(F) if F.flags.writeable else np.empty(F.shape)
        FR[:, :, 0] = F[:, :, 0]
        FR[:, :, 1] = c[:, None] * F[:, :, 1] + sn[:, None] * F[:, :, 2]
        FR[:, :, 2] = c[:, None] * F[:, :, 2] - sn[:, None] * F[:, :, 1]
        A = s[:, None, None] * (FR.reshape(-1, 3) @ self.start_T).reshape(-1, 3, 3)
        return D[:, 0], A

    def place(self, v: Array, X: Array) -> Array:
        """``E`` for the points ``X`` (n, 3) at each ``v``: shape (m, n, 3)."""
        C, A = self.maps(v)
        return _apply(C, A, np.ascontiguousarray((X - self.c0).T))

    def affine(self, v: Array) -> Array:
        """The map at each ``v`` as 12 numbers, ``C(v)`` then ``A(v)`` row by row: shape (m, 12).

        Each parameter is computed once per sweep and looked up after: a span that a refinement
        pass leaves whole keeps its check points and most Greville sites (90 % of the third pass's
        parameters on the helix benchmark).
        """
        memo = self._memo_v
        k = np.minimum(np.searchsorted(memo, v), max(memo.shape[0] - 1, 0))
        known = memo[k] == v if memo.shape[0] else np.zeros(v.shape[0], dtype=bool)
        if np.all(known):
            return self._memo_g[k]
        out = np.empty((v.shape[0], 12))
        out[known] = self._memo_g[k[known]]
        new_v = v[~known]
        C, A = self.maps(new_v)
        out[~known] = new = np.concatenate((C, A.reshape(-1, 9)), axis=1)
        all_v = np.concatenate((memo, new_v))
        order = np.argsort(all_v, kind="stable")
        self._memo_v, self._memo_g = all_v[order], np.concatenate((self._memo_g, new))[order]
        return out

    def poles(self, g: Array) -> Array:
        """The profile poles under the maps ``g`` (m, 12) of :meth:`affine`: shape (m, n_u, 3).

        Linear in ``g``: the poles of a spline of maps are the maps of its poles, and the pole
        errors of an approximate map ``g~`` are ``poles(g~ - g)``."""
        return _apply(g[:, :3], g[:, 3:].reshape(-1, 3, 3), self.xc)


def _apply(C: Array, A: Array, Xt: Array) -> Array:
    """``C[m] + A[m] X[n]`` for ``Xt = X.T`` (3, n): shape (m, n, 3), by one (3m, 3) x (3, n)
    product (a batch of m small products is 3-5x slower)."""
    m, n = C.shape[0], Xt.shape[1]
    return C[:, None, :] + (A.reshape(3 * m, 3) @ Xt).reshape(m, 3, n).transpose(0, 2, 1)


# ------------------------------------------------------------------------------------- public
def exact_sweep(
    profile: BSplineCurve,
    path: BSplineCurve,
    u: ArrayLike,
    v: ArrayLike,
    *,
    frame: str = "rmf",
    scale: Law = None,
    twist: Law = None,
) -> Array:
    """Points ``E(u_a, v_b)`` of the exact sweep (module notes) on the grid ``u x v``.

    Parameters
    ----------
    profile, path : BSplineCurve
        3-D.
    u, v : array_like, shapes (a,), (b,)
        Parameters of the profile and of the path.
    frame, scale, twist
        As in :func:`sweep`.

    Returns
    -------
    ndarray, shape (a, b, 3)
    """
    c = _check_curve(profile, "profile")
    q = _check_curve(path, "path")
    frame = _check_frame(frame)
    ex = _Sweep(c, q, frame, scale, twist)
    uu = V.check_parameters(np.atleast_1d(u), *c.domain, name="u").reshape(-1)
    vv = V.check_parameters(np.atleast_1d(v), *q.domain, name="v").reshape(-1)
    return ex.place(vv, c.evaluate(uu)).transpose(1, 0, 2)


def _check_frame(frame: object) -> str:
    if frame not in _FRAMES:
        raise InvalidGeometryError(f"frame: expected one of {', '.join(map(repr, _FRAMES))}, got {frame!r}")
    return str(frame)


def _initial_knots(path: BSplineCurve, frame: str, q: int) -> Array:
    """v knots: the path's breaks with multiplicities matching the frame field's continuity there,
    every span cut in ``tolerances.SWEEP_INITIAL_PIECES``."""
    v0, v1 = path.domain
    vals, mults = distinct_knots(path.knots)
    inside = (vals > v0) & (vals < v1)
    loss = {"fixed": 0, "rmf": 1, "frenet": 2}[frame]  # derivatives lost by T, resp. N, B
    brk = np.concatenate(([v0], vals[inside], [v1]))
    cont = np.maximum(path.degree - mults[inside] - loss, 0)
    mult = np.clip(q - cont, 1, q)
    parts = [np.full(q + 1, v0)]
    f = np.linspace(0, 1, int(tolerances.SWEEP_INITIAL_PIECES) + 1)[1:-1]
    for k, (a, b) in enumerate(zip(brk[:-1], brk[1:])):
        parts.append(a + (b - a) * f)
        if k < mult.shape[0]:
            parts.append(np.full(int(mult[k]), b))
    parts.append(np.full(q + 1, v1))
    return np.concatenate(parts)


def _spans(K: Array, q: int) -> tuple[Array, Array]:
    d = np.unique(K[q : K.shape[0] - q])
    return d[:-1], d[1:]


def _check_joints(path: BSplineCurve, frame: str, size: float) -> None:
    """Reject a path that jumps, or (moving frames) turns abruptly, at a joint of multiplicity >= degree."""
    v0, v1 = path.domain
    vals, mults = distinct_knots(path.knots)
    for u in vals[(vals > v0) & (vals < v1) & (mults >= path.degree)]:  # a few joints, not points
        left, right = path.split(float(u))
        dl, dr = left.derivatives(left.domain[1], 1), right.derivatives(right.domain[0], 1)
        gap = float(np.linalg.norm(dl[0] - dr[0]))
        if gap > 1e-12 * size:
            raise InvalidGeometryError(f"path: not continuous at v = {float(u)!r} (the two sides are {gap:.3g} apart)")
        if frame == "fixed":
            continue
        nl, nr = float(np.linalg.norm(dl[1])), float(np.linalg.norm(dr[1]))
        if nl == 0 or nr == 0:
            raise InvalidGeometryError(f"path: C'(v) = 0 at v = {float(u)!r}; the frame is undefined")
        angle = math.atan2(float(np.linalg.norm(np.cross(dl[1], dr[1]))), float(dl[1] @ dr[1]))
        if angle > tolerances.SWEEP_KINK_ANGLE:
            raise InvalidGeometryError(
                f"path: not tangent-continuous at v = {float(u)!r} (the tangent turns by "
                f"{math.degrees(angle):.3g} degrees); a moving frame would turn abruptly there and tear the "
                "sweep: sweep the pieces separately (path.split(v)) or use frame='fixed'"
            )


def _span_errors(ex: _Sweep, maps: BSplineCurve, exact: Array, v: Array, n_spans: int) -> Array:
    """Largest pole-row distance ``max_i |Q_i(v) - P_i(v)|`` per span, from the spline of maps
    ``maps`` and the exact maps ``exact`` (m, 12) at ``v`` (an equal number of points per span,
    span by span): ``Q_i - P_i = poles(maps(v) - exact)`` (:meth:`_Sweep.poles`)."""
    diff = ex.poles(maps.evaluate(v) - exact)
    # the largest square first, one square root per span (sqrt is monotone: the same numbers)
    return np.sqrt(np.einsum("mij,mij->mi", diff, diff).reshape(n_spans, -1).max(axis=1))


def _off_sites(a: Array, b: Array, fractions: Array) -> Array:
    return (a[:, None] + (b - a)[:, None] * fractions[None, :]).reshape(-1)


@overload
def sweep(profile: BSplineCurve, path: BSplineCurve, *, frame: str = ..., scale: Law = ..., twist: Law = ...,
          tol: float | None = ..., degree: int = ..., return_report: Literal[False] = ...) -> BSplineSurface: ...
@overload
def sweep(profile: BSplineCurve, path: BSplineCurve, *, frame: str = ..., scale: Law = ..., twist: Law = ...,
          tol: float | None = ..., degree: int = ..., return_report: Literal[True]) -> SweepResult: ...


def sweep(
    profile: BSplineCurve,
    path: BSplineCurve,
    *,
    frame: str = "rmf",
    scale: Law = None,
    twist: Law = None,
    tol: float | None = None,
    degree: int = 3,
    return_report: bool = False,
) -> BSplineSurface | SweepResult:
    """Generalised sweep of a profile along a path, approximated to a tolerance (course §6-26 ..
    §6-33; The NURBS Book, 2nd ed., §10.4). See the module notes for the exact sweep it approximates.

    Parameters
    ----------
    profile : BSplineCurve
        3-D, rational or not, placed where it should be at the path start (usually in the plane
        normal to the path there, but any placement works).
    path : BSplineCurve
        3-D, regular (``C' != 0``) and tangent-continuous; rational or not.
    frame : {"rmf", "frenet", "fixed"}
        The moving frame (module notes).
    scale : float or callable, optional
        ``s(t)``, ``t`` the normalised path parameter in ``[0, 1]``: uniform scaling of the section
        about the path point. A callable receives an array ``t`` of shape (m,) and returns m values
        ``>= 0``. Default 1.
    twist : float or callable, optional
        ``φ(t)`` in radians: rotation of the section about the tangent, on top of the frame.
        Default 0.
    tol : float, optional
        Absolute bound on the pole-row error (hence on ``|S - E|``); default
        ``tolerances.SWEEP_TOLERANCE`` times ``max(1, largest |coordinate|)`` of the inputs.
    degree : int, default 3
        Degree in v.
    return_report : bool, default False
        Return a :class:`SweepResult` (surface plus measured errors) instead of the surface.

    Returns
    -------
    BSplineSurface or SweepResult
        u: the profile's knots and degree (exact for every v); v: the path's domain, degree
        ``degree``, knots refined adaptively. ``S(u, v_j) = E(u, v_j)`` at the fitting sites.

    Raises
    ------
    InvalidGeometryError
        Not 3-D curves; an unknown frame; a law that is not finite (or a negative scale); a
        Frenet frame that is undefined (zero curvature) at some sample; ``C' = 0`` on the path;
        a path that jumps at a joint, or (``frame`` "rmf"/"frenet") turns abruptly there by more
        than ``tolerances.SWEEP_KINK_ANGLE``; ``tol`` not a positive number.
    ToleranceError
        ``tol`` not reached with ``tolerances.SWEEP_MAX_SECTIONS`` pole rows, or an error that
        does not fall as spans shrink towards ``tolerances.SWEEP_MIN_SPAN`` (a law that jumps, a
        cusp of the path: the message gives the error reached and where).
    """
    c = _check_curve(profile, "profile")
    q_path = _check_curve(path, "path")
    frame = _check_frame(frame)
    q = V.as_degree(degree, "degree")
    size = max(1.0, float(np.abs(c.control_points).max()), float(np.abs(q_path.control_points).max()))
    tol_abs = _absolute_tolerance(tol, size)
    _check_joints(q_path, frame, size)
    ex = _Sweep(c, q_path, frame, scale, twist)
    fit = _refine(ex, _initial_knots(q_path, frame, q), q, tol_abs)
    surface = _surface_from_rows(c, fit.rows)
    if not return_report:
        return surface
    return _report(ex, surface, fit, tol_abs, frame)


def _absolute_tolerance(tol: object, size: float) -> float:
    """``tol`` as a positive finite float, or ``tolerances.SWEEP_TOLERANCE * size`` for ``None``."""
    if tol is None:
        return tolerances.SWEEP_TOLERANCE * size
    try:
        tol_abs = float(tol)  # type: ignore[arg-type]
    except (TypeError, ValueError) as err:
        raise InvalidGeometryError(f"tol: expected a positive finite number, got {tol!r}") from err
    if not (math.isfinite(tol_abs) and tol_abs > 0):
        raise InvalidGeometryError(f"tol: expected a positive finite number, got {tol!r}")
    return tol_abs


@dataclass(frozen=True)
class _Fit:
    """The pole rows that met the tolerance, and what the last pass measured."""

    #: The pole rows as one curve in v: poles ``(n_sections, 3 n_u)``, degree q, the v knots.
    rows: BSplineCurve
    #: Refinement passes.
    iterations: int
    #: The verification parameters ``(m,)`` (``_verify_fractions`` of every v span) ...
    verify_v: Array
    #: ... and the pole bound per v span measured at them (each ``<= tol``).
    span_errors: Array


def _fit_maps(ex: _Sweep, K: Array, q: int) -> tuple[BSplineCurve, Array]:
    """The spline of maps (:meth:`_Sweep.affine`, 12-D) of degree ``q`` on the v knots ``K``
    interpolating the exact maps at the Greville abscissae, and its pole bound per v span at the
    check points. Its poles mapped by :meth:`_Sweep.poles` are the pole rows interpolating the
    exact mapped profile poles there (interpolation is linear): 12 columns, whatever the profile."""
    a, b = _spans(K, q)
    sites = greville(K, q)
    vc = _off_sites(a, b, _check_fractions())
    g = ex.affine(np.concatenate((sites, vc)))  # at the fitting sites and the check points at once
    maps = BSplineCurve._trusted(q, K, interpolate_values(sites, g[: sites.shape[0]], q, K))
    return maps, _span_errors(ex, maps, g[sites.shape[0]:], vc, a.shape[0])


def _rows(ex: _Sweep, maps: BSplineCurve) -> BSplineCurve:
    """The pole rows (poles ``(n_sections, 3 n_u)``) of the spline of maps ``maps``."""
    P = maps.control_points
    return BSplineCurve._trusted(maps.degree, maps.knots, ex.poles(P).reshape(P.shape[0], -1))


def _verify_maps(ex: _Sweep, maps: BSplineCurve) -> tuple[Array, Array]:
    """The verification parameters ``vv`` (``_verify_fractions`` of every v span) and the pole
    bound per v span measured there."""
    a, b = _spans(maps.knots, maps.degree)
    vv = _off_sites(a, b, _verify_fractions())
    return vv, _span_errors(ex, maps, ex.affine(vv), vv, a.shape[0])


def _refine(ex: _Sweep, K: Array, q: int, tol_abs: float) -> _Fit:
    """Fit pole rows on ``K``, cut the spans whose pole bound exceeds ``tol_abs`` (at the check
    points, then at the denser verification points), and repeat until none does."""
    iterations = 0
    while True:
        iterations += 1
        maps, err = _fit_maps(ex, K, q)
        if not np.any(err > tol_abs):
            # the denser verification points of the report must meet tol too (the check points
            # alone let pole_bound exceed tol by up to 3 %)
            vv, err = _verify_maps(ex, maps)
            if not np.any(err > tol_abs):
                return _Fit(_rows(ex, maps), iterations, vv, err)
        K = _split_spans(maps, err, tol_abs, ex.path.domain)


def _split_spans(rows: BSplineCurve, err: Array, tol_abs: float, domain: tuple[float, float]) -> Array:
    """The v knots of ``rows`` (the spline fitted last: of maps, or of pole rows) with every span
    whose error ``err`` (one per span) exceeds ``tol_abs`` cut in as many equal pieces as the
    ``O(h^(q+1))`` error model asks for.

    Raises
    ------
    ToleranceError
        A piece would be shorter than ``tolerances.SWEEP_MIN_SPAN`` of the path's ``domain`` (the
        error does not fall as spans shrink), or there would be more than
        ``tolerances.SWEEP_MAX_SECTIONS`` pole rows.
    """
    K, q = rows.knots, rows.degree
    a, b = _spans(K, q)
    bad = err > tol_abs
    pieces = np.clip(np.ceil(tolerances.SWEEP_SPLIT_SAFETY * (err[bad] / tol_abs) ** (1.0 / (q + 1))),
                     2, tolerances.SWEEP_MAX_SPLIT).astype(int)
    narrow = (b[bad] - a[bad]) / pieces < tolerances.SWEEP_MIN_SPAN * (domain[1] - domain[0])
    if np.any(narrow):
        k = int(np.flatnonzero(bad)[np.argmax(narrow)])
        raise ToleranceError(
            f"sweep: tolerance {tol_abs:.3g} not reached: the error ({float(err[k]):.3g}) does not fall as the "
            f"sections near v = {float(a[k]):.6g} get closer; a scale or twist law that jumps there, or a "
            "path with a cusp (C'(v) = 0) or an abrupt turn there?"
        )
    max_sections = tolerances.SWEEP_MAX_SECTIONS
    if rows.n_poles + int((pieces - 1).sum()) > max_sections:
        raise ToleranceError(
            f"sweep: tolerance {tol_abs:.3g} not reached with {max_sections} sections; error reached "
            f"{float(err.max()):.3g} (a non-smooth law or a nearly singular frame?)"
        )
    n_new = pieces - 1
    j = np.arange(int(n_new.sum())) - np.repeat(np.cumsum(n_new) - n_new, n_new) + 1   # 1 .. pieces-1
    new = np.repeat(a[bad], n_new) + np.repeat(b[bad] - a[bad], n_new) * j / np.repeat(pieces, n_new)
    return np.sort(np.concatenate((K, new)))


def _surface_from_rows(profile: BSplineCurve, rows: BSplineCurve) -> BSplineSurface:
    """The swept surface: u the profile's knots, degree and weights; v the pole rows' knots."""
    n_u = profile.n_poles
    net = rows.control_points.reshape(rows.n_poles, n_u, 3).transpose(1, 0, 2)
    W = None if profile.weights is None else np.repeat(profile.weights[:, None], rows.n_poles, axis=1)
    return BSplineSurface._trusted((profile.degree, rows.degree), (profile.knots.copy(), rows.knots),
                                   np.ascontiguousarray(net), W)


def _report(ex: _Sweep, surface: BSplineSurface, fit: _Fit, tol_abs: float, frame: str) -> SweepResult:
    """Measure ``max |S - E|`` on the dense grid (every profile span sampled 8 times and the
    domain ends, times the v values the refinement verified last) and assemble the report."""
    c = ex.profile
    ua, ub = _spans(c.knots, c.degree)
    uu = np.concatenate((_off_sites(ua, ub, (np.arange(8) + 0.5) / 8), c.domain))
    S = surface.evaluate_grid(uu, fit.verify_v)
    g = ex.affine(fit.verify_v)  # the maps the verification computed, looked up
    E = _apply(g[:, :3], g[:, 3:].reshape(-1, 3, 3), np.ascontiguousarray((c.evaluate(uu) - ex.c0).T)).transpose(1, 0, 2)
    max_error = float(np.linalg.norm(S - E, axis=-1).max())
    return SweepResult(surface=surface, max_error=max_error, pole_bound=float(fit.span_errors.max()), tol=tol_abs,
                       n_sections=fit.rows.n_poles, iterations=fit.iterations, n_checked=int(S.shape[0] * S.shape[1]),
                       frame=frame)
