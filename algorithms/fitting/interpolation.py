"""Interpolation and least-squares fitting of curves and gridded surfaces, and lofting.

Course ch. 7 (§7-2 data fitting, §7-4 Kronecker products, §7-5 interpolation and least squares)
and §6-17 (curve nets). A tensor-product fit of gridded data separates: with collocation
matrices ``A`` (along u) and ``B`` (along v) the system ``(A ⊗ B) vec(P) = vec(Q)`` is solved as
``A P Bᵀ = Q``, one direction at a time, never forming the Kronecker product. Parameters and knots
follow The NURBS Book, 2nd ed., §9.2 (eqs. 9.4-9.8) and §9.4.1 (eqs. 9.63-9.69).

All fits are linear in the data, so each routine builds a small operator matrix once and applies it
to every coordinate (and, for surfaces and lofts, to every row) in one matrix product.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, TypeVar, cast, overload

import numpy as np
import scipy.linalg
from numpy.typing import ArrayLike, NDArray

from .. import _validate as V
from .. import tolerances
from ..errors import InvalidGeometryError, ParameterError
from ..kernel.basis import basis_functions, basis_matrix, find_span
from ..kernel.compat import make_compatible
from ..kernel.curve import BSplineCurve
from ..kernel.rational import from_homogeneous, to_homogeneous
from ..kernel.surface import BSplineSurface

__all__ = [
    "parametrize",
    "averaged_knots",
    "approximation_knots",
    "interpolate_values",
    "interpolate_curve",
    "fit_curve",
    "interpolate_surface",
    "fit_surface",
    "loft",
]

Array = NDArray[np.float64]
_T = TypeVar("_T")

_METHODS = ("centripetal", "chord", "uniform")


# ----------------------------------------------------------------------------- parameters, knots
def parametrize(points: ArrayLike, method: str = "centripetal") -> Array:
    """Parameter values in [0, 1] for data points (The NURBS Book, eqs. 9.4-9.6).

    Parameters
    ----------
    points : array_like, shape (m, d) or (m, k, d)
        ``m`` points in a row, or ``m`` rows of ``k`` points each (the parameters of the rows are
        then the average over the ``k`` columns, as for gridded surface data; columns of zero
        length are left out of the average).
    method : {"centripetal", "chord", "uniform"}
        Square root of the chord lengths (Lee 1989; the default, robust at sharp turns), chord
        lengths, or equal spacing.

    Returns
    -------
    ndarray, shape (m,)
        Strictly increasing, ``0`` first and ``1`` last.

    Raises
    ------
    InvalidGeometryError
        Fewer than 2 points, non-finite values, or consecutive coincident points (every column has
        a zero-length step somewhere, so no increasing parameters exist).
    ParameterError
        An unknown ``method``.
    """
    Q = V.as_finite_array(points, "points")
    if Q.ndim not in (2, 3) or Q.shape[0] < 2:
        raise InvalidGeometryError(f"points: expected shape (m, d) or (m, k, d) with m >= 2, got {Q.shape}")
    if method not in _METHODS:
        raise ParameterError(f"method: expected one of {', '.join(_METHODS)}, got {method!r}")
    m = Q.shape[0]
    if method == "uniform":
        return np.linspace(0.0, 1.0, m)
    if Q.ndim == 2:
        Q = Q[:, None, :]
    steps = np.linalg.norm(np.diff(Q, axis=0), axis=-1)  # (m-1, k)
    if method == "centripetal":
        steps = np.sqrt(steps)
    total = steps.sum(axis=0)  # (k,)
    scale = float(np.abs(Q).max()) or 1.0
    ok = total > 1e-14 * scale
    if not np.any(ok):
        raise InvalidGeometryError("points: all points coincide; parameters cannot be assigned")
    cum = np.vstack([np.zeros((1, int(ok.sum()))), np.cumsum(steps[:, ok], axis=0) / total[ok]])
    t = cum.mean(axis=1)
    t[-1] = 1.0
    if np.any(np.diff(t) <= 0):
        i = int(np.argmax(np.diff(t) <= 0))
        raise InvalidGeometryError(f"points: points {i} and {i + 1} coincide; parameters would not increase")
    return t


def _check_params(params: ArrayLike, m: int, name: str) -> Array:
    t = V.as_finite_array(params, name, ndim=1)
    if t.shape[0] != m:
        raise InvalidGeometryError(f"{name}: expected {m} values (one per data point), got {t.shape[0]}")
    if np.any(np.diff(t) <= 0):
        i = int(np.argmax(np.diff(t) <= 0))
        raise ParameterError(f"{name}: must be strictly increasing, but {name}[{i + 1}] = {t[i + 1]!r} <= {t[i]!r}")
    return t


def averaged_knots(params: ArrayLike, degree: int) -> Array:
    """Clamped knots for interpolation by knot averaging (The NURBS Book, eq. 9.8).

    Parameters
    ----------
    params : array_like, shape (m,)
        Strictly increasing data parameters.
    degree : int
        ``1 <= degree <= m - 1``.

    Returns
    -------
    ndarray, shape (m + degree + 1,)
        Interior knot ``j`` is the mean of ``degree`` consecutive parameters, which satisfies the
        Schoenberg–Whitney condition for any increasing parameters.
    """
    p = V.as_degree(degree)
    t = V.as_finite_array(params, "params", ndim=1)
    m = t.shape[0]
    if m < p + 1:
        raise InvalidGeometryError(f"params: a degree-{p} interpolant needs at least {p + 1} points, got {m}")
    c = np.concatenate(([0.0], np.cumsum(t)))
    inner = (c[p + 1:m] - c[1:m - p]) / p  # mean of t[j..j+p-1], j = 1..m-p-1
    return np.concatenate((np.full(p + 1, t[0]), inner, np.full(p + 1, t[-1])))


def approximation_knots(params: ArrayLike, n_poles: int, degree: int) -> Array:
    """Clamped knots for a least-squares fit with ``n_poles`` poles (The NURBS Book, eqs. 9.68-9.69
    and 9.8 combined).

    Work in *index space*: ``T(x)`` is the piecewise-linear interpolant of the ``m`` parameters over
    their index (``T(k) = t_k``), as eq. 9.69 interpolates them. Eq. 9.69 spreads the ``n - p``
    knot spans evenly over the data, ``D = (m - 1) / (n - p)`` index units each. Here the ``n``
    Greville abscissae ``g_i`` of that even clamped knot vector serve as *virtual sites*, pushed
    apart to at least one data step where the clamped ends crowd them,

    .. math::

        s_i = \\min\\big(\\max(g_i,\\, i),\\; m - n + i\\big), \\qquad i = 0, \\ldots, n - 1,

    and the interior knots are the averages (eq. 9.8) of ``p`` consecutive virtual sites:

    .. math::

        u_{p+j} = T\\Big(\\frac{1}{p} \\sum_{k=j}^{j+p-1} s_k\\Big), \\qquad j = 1, \\ldots, n - p - 1.

    With many data per span (``D >= p``) no site is moved and the knots are those of eq. 9.69 up to
    the averaging, so the fits are as good; as ``n`` approaches ``m`` the sites become the data
    indices themselves and the knots those of interpolation (eq. 9.8). For any increasing
    parameters and every ``p + 1 <= n <= m``, because ``s_0 = 0``, ``s_{n-1} = m - 1`` and
    ``s_{i+1} - s_i >= 1``:

    * every knot span contains at least one parameter (interior spans are at least one index unit
      long), the design goal of eqs. 9.68-9.69;
    * the Schoenberg–Whitney condition holds with a margin, also with both end points
      interpolated: the data site ``k_i = round(s_i)`` (strictly increasing, ``1 <= k_i <= m - 2``
      for ``0 < i < n - 1``) lies at least half a data step inside the support of ``N_i``, which
      reaches from ``<= s_{i-1}`` to ``>= s_{i+1}``. The least-squares matrix has full column rank
      and stays well conditioned.

    For ``n = m`` the averaged knots of :func:`averaged_knots` (interpolation) are returned.

    Parameters
    ----------
    params : array_like, shape (m,)
        Strictly increasing data parameters.
    n_poles : int
        ``degree + 1 <= n_poles <= m``.
    degree : int

    Returns
    -------
    ndarray, shape (n_poles + degree + 1,)
        Clamped at ``params[0]`` and ``params[-1]``; the interior knots are simple and strictly
        inside ``(params[0], params[-1])``.

    Raises
    ------
    InvalidGeometryError
        ``n_poles`` out of range.

    Notes
    -----
    Eq. 9.69 itself (``u_{p+j} = T(j d - 1)``, ``d = m / (n - p)``) also puts a parameter in every
    span, but that does not make the system well conditioned: its basis functions next to the
    clamped ends have Greville abscissae ``D/p, 2D/p, ...`` apart, closer than the data once
    ``D < p``, so as ``n`` approaches ``m`` the only data site left to each basis function falls
    near the end of its support. The matrix keeps full rank in exact arithmetic, but its condition
    number grows exponentially with ``n``. Measured on the interior (end-constrained) matrix,
    centripetal parameters of random points, ``8 <= m <= 60``, ``p = 3``: 7e4 at ``n = 0.8 m``,
    6e12 at ``0.9 m``, 1e20 at ``n = m - 1`` (up to 2e22 for ``p = 5`` and uniformly random
    parameters), so that :func:`fit_curve` had to refuse e.g. ``m = 39, n = 38, p = 4`` as rank
    deficient. With the knots above the same scan stays below 40 (``p <= 5``; below 1e5 on
    uniformly random parameters) for every ``n``, and a cubic fit of a sampled helix
    (``m = 400``, ``n = 10 .. 200``) deviates as much as with eq. 9.69, within 10 %.
    """
    p = V.as_degree(degree)
    t = V.as_finite_array(params, "params", ndim=1)
    m = t.shape[0]
    n = int(n_poles)
    if not p + 1 <= n <= m:
        raise InvalidGeometryError(f"n_poles: expected {p + 1} <= n_poles <= {m} (number of points), got {n_poles}")
    if n == m:
        return averaged_knots(t, p)
    # Greville abscissae of the clamped knot vector with n - p even spans over [0, m - 1].
    D = (m - 1) / (n - p)
    even = np.concatenate((np.zeros(p), D * np.arange(n - p + 1), np.full(p, m - 1.0)))
    g = sum(even[r + 1:r + 1 + n] for r in range(p)) / p  # (n,)
    i = np.arange(n)
    sites = np.minimum(np.maximum(g, i), m - n + i)  # at least one data step apart
    # Averages of p consecutive sites, summed directly: integer sites give integer knots exactly.
    x = sum(sites[r + 1:r + n - p] for r in range(p)) / p  # (n - p - 1,)
    k = np.minimum(np.floor(x).astype(int), m - 2)
    a = x - k
    inner = (1 - a) * t[k] + a * t[k + 1]
    return np.concatenate((np.full(p + 1, t[0]), inner, np.full(p + 1, t[-1])))


# ----------------------------------------------------------------------------- operators
def _collocation(params: Array, degree: int, knots: Array, n: int, name: str = "points", copies: int = 1) -> Array:
    """The dense ``(m, n)`` collocation matrix, refused above ``tolerances.MAX_ARRAY_BYTES`` (with
    ``copies`` matrices of its size alive at once) before it exists: ``name`` holds the data."""
    m = params.shape[0]
    V.check_size((copies * m, n), f"{name}: {m} data points need {copies} dense {m} x {n} matrices")
    return basis_matrix(knots, degree, n, params)[0]


def _check_sw(B: Array, name: str) -> None:
    _check_sw_diagonal(np.diagonal(B), name)


def _check_sw_diagonal(d: Array, name: str) -> None:
    # Schoenberg–Whitney margin: refused when some basis function is smaller than
    # tolerances.SCHOENBERG_WHITNEY at its own data site (the matrix is then singular or nearly so,
    # and the "interpolant" would be meaningless). Relative to the basis' maximum of 1.
    margin = tolerances.SCHOENBERG_WHITNEY
    if np.any(d < margin):
        i = int(np.argmax(d < margin))
        raise InvalidGeometryError(
            f"{name}: the data parameters and knots violate the Schoenberg–Whitney condition at "
            f"basis function {i} (no data site where it is non-zero); the interpolation system is singular"
        )


def _banded_interpolation(u: Array, degree: int, knots: Array, rhs: Array, name: str) -> Array:
    """Solve ``B P = rhs`` for the square collocation matrix ``B[i, j] = N_j(u_i)`` in LAPACK's
    banded storage, built from the ``degree + 1`` non-zero basis functions per row: ``O(m p)``
    memory (a dense ``B`` for 20 000 points took 3.2 GB)."""
    m, p = u.shape[0], degree
    span = find_span(knots, p, m, u)
    N = basis_functions(knots, p, span, u)  # (m, p + 1)
    rows = np.broadcast_to(np.arange(m)[:, None], N.shape)
    cols = span[:, None] - p + np.arange(p + 1)
    diag = np.where(rows == cols, N, 0.0).sum(axis=1)
    _check_sw_diagonal(diag, name)
    nz = N != 0
    off = (cols - rows)[nz]
    lo, up = int(max(0, -off.min())), int(max(0, off.max()))
    ab = np.zeros((lo + up + 1, m))
    ab[up + rows[nz] - cols[nz], cols[nz]] = N[nz]
    flat = rhs.reshape(m, -1)
    return scipy.linalg.solve_banded((lo, up), ab, flat, check_finite=False).reshape(rhs.shape)


def interpolate_values(params: ArrayLike, values: ArrayLike, degree: int, knots: ArrayLike) -> Array:
    """Poles of the spline that takes ``values[i]`` at ``params[i]`` (course §7-5).

    Parameters
    ----------
    params : array_like, shape (m,)
    values : array_like, shape (m, ...)
        Any trailing shape: coordinates, homogeneous coordinates, rows of a net.
    degree : int
    knots : array_like, shape (m + degree + 1,)

    Returns
    -------
    ndarray, shape (m, ...)
        Solved as one banded system with all trailing columns as right-hand sides.

    Raises
    ------
    InvalidGeometryError
        Shape mismatches, or the Schoenberg–Whitney condition fails.
    """
    p = V.as_degree(degree)
    Y = V.as_finite_array(values, "values")
    m = Y.shape[0]
    t = V.check_knots(knots, p, m)
    u = _check_params(params, m, "params")
    lo, hi = t[p], t[m]
    if u[0] < lo - 1e-12 * (hi - lo) or u[-1] > hi + 1e-12 * (hi - lo):
        raise ParameterError(f"params: must lie in the knot domain [{lo!r}, {hi!r}], got [{u[0]!r}, {u[-1]!r}]")
    return _banded_interpolation(np.clip(u, lo, hi), p, t, Y, "params")


def _lsq_operator(params: Array, degree: int, knots: Array, n: int) -> Array:
    """The (n, m) matrix mapping data to least-squares poles with both end points interpolated."""
    m = params.shape[0]
    if n == m:  # the matrix, the identity and the inverse
        B = _collocation(params, degree, knots, n, copies=3)
        _check_sw(B, "params")
        return cast(Array, np.linalg.solve(B, np.eye(m)))  # numpy's stubs type linalg of float64 as floating[Any]
    # in units of m x n: N, X, F and lstsq's copy of A; S (m x m) and lstsq's copy of it
    N = _collocation(params, degree, knots, n, copies=4 + -(-2 * m // n))
    A = N[1:-1, 1:-1]  # interior data against interior poles
    S = np.zeros((m - 2, m))
    S[:, 1:-1] = np.eye(m - 2)
    S[:, 0] = -N[1:-1, 0]
    S[:, -1] = -N[1:-1, -1]
    X, _, rank, _ = np.linalg.lstsq(A, S, rcond=None)
    if rank < n - 2:
        raise InvalidGeometryError(
            f"n_poles: {n} poles are not determined by the data (rank {rank + 2}); the data parameters do not "
            "interlace with the knots (Schoenberg–Whitney) — use fewer poles or approximation_knots"
        )
    F = np.zeros((n, m))
    F[0, 0] = 1.0
    F[-1, -1] = 1.0
    F[1:-1] = X
    return F


def _resolve(points: Array, axis_len: int, degree: int, params: ArrayLike | None, method: str,
             knots: ArrayLike | None, n_poles: int | None, name: str) -> tuple[Array, Array, int]:
    p = V.as_degree(degree, f"{name}degree")
    m = axis_len
    n = m if n_poles is None else int(n_poles)
    if m < p + 1:
        raise InvalidGeometryError(f"{name}points: a degree-{p} fit needs at least {p + 1} points, got {m}")
    if params is None:
        u = parametrize(points, method)
    else:
        u = _check_params(params, m, f"{name}params")
    if knots is None:
        t = averaged_knots(u, p) if n == m else approximation_knots(u, n, p)
    else:
        t = V.check_knots(knots, p, n, f"{name}knots")
        if params is None:  # map the default [0, 1] parameters onto the given domain
            u = t[p] + u * (t[n] - t[p])
    return u, t, p


# ----------------------------------------------------------------------------- curves
def _points(points: ArrayLike, ndim: int, name: str = "points") -> Array:
    Q = V.as_finite_array(points, name)
    if Q.ndim != ndim:
        shape = "(m, d)" if ndim == 2 else "(m, n, d)"
        raise InvalidGeometryError(f"{name}: expected shape {shape}, got {Q.shape}")
    return Q


def interpolate_curve(points: ArrayLike, degree: int = 3, *, params: ArrayLike | None = None,
                      method: str = "centripetal", knots: ArrayLike | None = None) -> BSplineCurve:
    """The B-spline curve through ``points`` (The NURBS Book, A9.1; course §7-5).

    Parameters
    ----------
    points : array_like, shape (m, d)
    degree : int
        At most ``m - 1``.
    params : array_like, shape (m,), optional
        Data parameters; by default from ``method``, on [0, 1] or on the domain of ``knots``.
    method : {"centripetal", "chord", "uniform"}
    knots : array_like, shape (m + degree + 1,), optional
        By default averaged knots (eq. 9.8).

    Returns
    -------
    BSplineCurve
        ``c(params[i]) == points[i]`` to round-off.
    """
    Q = _points(points, 2)
    u, t, p = _resolve(Q, Q.shape[0], degree, params, method, knots, None, "")
    P = interpolate_values(u, Q, p, t)
    return BSplineCurve(p, t, P)


def fit_curve(points: ArrayLike, n_poles: int, degree: int = 3, *, params: ArrayLike | None = None,
              method: str = "centripetal", knots: ArrayLike | None = None) -> BSplineCurve:
    """Least-squares B-spline curve with ``n_poles`` poles, end points interpolated.

    The NURBS Book, 2nd ed., §9.4.1 (eqs. 9.63-9.67); course §7-5. Solved with an orthogonal
    (SVD-based) least-squares solver, not the normal equations.

    Parameters
    ----------
    points : array_like, shape (m, d)
    n_poles : int
        ``degree + 1 <= n_poles <= m``; ``n_poles == m`` interpolates.
    degree, params, method, knots
        As for :func:`interpolate_curve`; default knots from eq. 9.69.

    Returns
    -------
    BSplineCurve
    """
    Q = _points(points, 2)
    m = Q.shape[0]
    p = V.as_degree(degree)
    if not isinstance(n_poles, (int, np.integer)) or not p + 1 <= int(n_poles) <= m:
        raise InvalidGeometryError(f"n_poles: expected an integer {p + 1} <= n_poles <= {m}, got {n_poles!r}")
    u, t, p = _resolve(Q, m, p, params, method, knots, int(n_poles), "")
    F = _lsq_operator(u, p, t, int(n_poles))
    return BSplineCurve(p, t, F @ Q)


# ----------------------------------------------------------------------------- surfaces
@overload
def _pair(x: None, name: str) -> tuple[None, None]: ...
@overload
def _pair(x: tuple[_T, _T], name: str) -> tuple[_T, _T]: ...
def _pair(x: Any, name: str) -> tuple[Any, Any]:
    if x is None:
        return None, None
    try:
        a, b = x
    except (TypeError, ValueError) as err:
        raise InvalidGeometryError(f"{name}: expected a pair (u, v), got {x!r}") from err
    return a, b


def _surface_fit(points: ArrayLike, degree: int | tuple[int, int], u_params: ArrayLike | None,
                 v_params: ArrayLike | None, method: str, knots: tuple[ArrayLike | None, ArrayLike | None] | None,
                 n_poles: tuple[int, int] | None) -> BSplineSurface:
    Q = _points(points, 3)
    m, k = Q.shape[:2]
    if isinstance(degree, (int, np.integer)):
        degree = (int(degree), int(degree))
    pu, pv = _pair(degree, "degree")
    ku, kv = _pair(knots, "knots") if knots is not None else (None, None)
    nu, nv = _pair(n_poles, "n_poles") if n_poles is not None else (None, None)
    uu, tu, pu = _resolve(Q, m, pu, u_params, method, ku, nu, "u_")
    vv, tv, pv = _resolve(Q.transpose(1, 0, 2), k, pv, v_params, method, kv, nv, "v_")
    Fu = _lsq_operator(uu, pu, tu, m if nu is None else int(nu))
    Fv = _lsq_operator(vv, pv, tv, k if nv is None else int(nv))
    # A P B^T = Q solved direction by direction (course §7-4, Kronecker products)
    P = np.einsum("im,mkd,jk->ijd", Fu, Q, Fv, optimize=True)
    return BSplineSurface((pu, pv), (tu, tv), P)


def interpolate_surface(points: ArrayLike, degree: int | tuple[int, int] = (3, 3), *,
                        u_params: ArrayLike | None = None, v_params: ArrayLike | None = None,
                        method: str = "centripetal",
                        knots: tuple[ArrayLike | None, ArrayLike | None] | None = None) -> BSplineSurface:
    """The tensor-product surface through a grid of points (The NURBS Book, A9.4; course §7-4).

    Parameters
    ----------
    points : array_like, shape (m, n, d)
        ``points[i, j]`` is taken at ``(u_params[i], v_params[j])``.
    degree : int or (int, int)
    u_params, v_params : array_like, optional
        Default: ``method`` parameters averaged over the grid lines (eq. 9.6 on each line).
    knots : (array_like or None, array_like or None), optional

    Returns
    -------
    BSplineSurface
        Through every grid point to round-off.
    """
    return _surface_fit(points, degree, u_params, v_params, method, knots, None)


def fit_surface(points: ArrayLike, n_poles: tuple[int, int], degree: int | tuple[int, int] = (3, 3), *,
                u_params: ArrayLike | None = None, v_params: ArrayLike | None = None,
                method: str = "centripetal",
                knots: tuple[ArrayLike | None, ArrayLike | None] | None = None) -> BSplineSurface:
    """Least-squares tensor-product surface of gridded data (course §7-4, §7-5).

    The fit is the tensor product of two curve fits with ends interpolated, so the four corner
    points are interpolated and the boundary rows are least-squares fits of the boundary data.

    Parameters
    ----------
    points : array_like, shape (m, n, d)
    n_poles : (int, int)
        ``degree + 1 <= n_poles <= data count`` in each direction.
    degree, u_params, v_params, method, knots
        As for :func:`interpolate_surface`.

    Returns
    -------
    BSplineSurface
    """
    Q = _points(points, 3)
    a, b = _pair(n_poles, "n_poles")
    for name, n, m in (("n_poles[0]", a, Q.shape[0]), ("n_poles[1]", b, Q.shape[1])):
        if not isinstance(n, (int, np.integer)) or not 2 <= int(n) <= m:
            raise InvalidGeometryError(f"{name}: expected an integer between 2 and {m} (the data count), got {n!r}")
    return _surface_fit(Q, degree, u_params, v_params, method, knots, (int(a), int(b)))


# ----------------------------------------------------------------------------- lofting
def loft(curves: Sequence[BSplineCurve], degree: int = 3, *, params: ArrayLike | None = None,
         method: str = "centripetal") -> BSplineSurface:
    """Skinned surface through a sequence of section curves (course §6-17; The NURBS Book §10.3).

    Parameters
    ----------
    curves : sequence of BSplineCurve, length K >= 2
        Section curves, made compatible first (:func:`make_compatible`). Rational sections are
        lofted in homogeneous coordinates, which interpolates them exactly.
    degree : int
        Degree across the sections; lowered to ``K - 1`` when there are fewer sections.
    params : array_like, shape (K,), optional
        The v parameter of each section; by default ``method`` parameters of the sections'
        control polygons (eq. 9.6 averaged over the pole columns), on [0, 1].

    Returns
    -------
    BSplineSurface
        ``u`` runs along the curves (their common domain), ``v`` across; ``S(u, params[k]) ==
        curves[k](u)`` to round-off.

    Raises
    ------
    InvalidGeometryError
        Fewer than two curves, mixed dimensions, or (rational sections) interpolated weights that
        are not positive.
    """
    cc = make_compatible(curves)
    K = len(cc)
    if K < 2:
        raise InvalidGeometryError(f"curves: a loft needs at least 2 sections, got {K}")
    q = min(V.as_degree(degree), K - 1)
    rational = cc[0].is_rational
    P = np.stack([c.control_points for c in cc])  # (K, n, d)
    v = parametrize(P, method) if params is None else _check_params(params, K, "params")
    tv = averaged_knots(v, q)
    if rational:
        sections = []
        for c in cc:
            if c.weights is None:  # make_compatible makes every section rational if one is
                raise InvalidGeometryError("curves: rational and polynomial sections were not made compatible")
            sections.append(to_homogeneous(c.control_points, c.weights))
        H = np.stack(sections)
        X = interpolate_values(v, H, q, tv)
        if np.any(X[..., -1] <= 0):
            raise InvalidGeometryError(
                "curves: lofting the rational sections gives non-positive weights between them; "
                "rescale the sections' weights or use degree 1"
            )
        Pc, w = from_homogeneous(X)
        return BSplineSurface((cc[0].degree, q), (cc[0].knots, tv), Pc.transpose(1, 0, 2), w.T)
    X = interpolate_values(v, P, q, tv)
    return BSplineSurface((cc[0].degree, q), (cc[0].knots, tv), X.transpose(1, 0, 2))
