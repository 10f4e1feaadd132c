"""Validation of user input, once, at public entry points. Messages name the argument."""

from __future__ import annotations

import numbers

import numpy as np
from numpy.typing import ArrayLike, NDArray

from . import tolerances
from .errors import InvalidGeometryError, ParameterError


def as_degree(value: object, name: str = "degree") -> int:
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise InvalidGeometryError(f"{name}: expected an integer from 1 to {tolerances.MAX_DEGREE}, got {value!r}")
    d = int(value)
    if not 1 <= d <= tolerances.MAX_DEGREE:
        raise InvalidGeometryError(
            f"{name}: expected 1 <= degree <= {tolerances.MAX_DEGREE} (OpenCascade's limit), got {d}"
        )
    return d


def as_finite_array(value: ArrayLike, name: str, ndim: int | None = None) -> NDArray[np.float64]:
    if np.iscomplexobj(value) or (isinstance(value, (list, tuple)) and _holds_complex(value)):
        raise InvalidGeometryError(f"{name}: expected real numbers, got complex values (the imaginary parts would "
                                   "be dropped)")
    try:
        a = np.array(value, dtype=float)
    except (TypeError, ValueError) as err:
        raise InvalidGeometryError(f"{name}: expected an array of real numbers, got {type(value).__name__}") from err
    if ndim is not None and a.ndim != ndim:
        raise InvalidGeometryError(f"{name}: expected a {ndim}-D array, got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        bad = np.argwhere(~np.isfinite(a))[0]
        raise InvalidGeometryError(f"{name}: expected finite values, got {a[tuple(bad)]} at index {tuple(int(i) for i in bad)}")
    return a


def check_knots(knots: ArrayLike, degree: int, n_poles: int, name: str = "knots") -> NDArray[np.float64]:
    """A full knot vector: finite, non-decreasing, length n+p+1, multiplicities <= p+1, non-empty domain."""
    t = as_finite_array(knots, name, ndim=1)
    expected = n_poles + degree + 1
    if t.shape[0] != expected:
        raise InvalidGeometryError(
            f"{name}: expected {expected} values (poles {n_poles} + degree {degree} + 1), got {t.shape[0]}"
        )
    if (t[1:] < t[:-1]).any():
        i = int(np.argmax(t[1:] < t[:-1]))
        raise InvalidGeometryError(f"{name}: must be non-decreasing, but knot {i + 1} = {float(t[i + 1])!r} < knot {i} = {float(t[i])!r}")
    # non-decreasing: a knot repeats more than degree + 1 times exactly where t[i] == t[i + degree + 1]
    # (one comparison instead of np.unique's sort; the counts are made only for the message)
    if degree + 1 < t.shape[0] and (t[degree + 1:] == t[:-degree - 1]).any():
        vals, counts = np.unique(t, return_counts=True)
        i = int(np.argmax(counts))
        raise InvalidGeometryError(
            f"{name}: multiplicity of knot {float(vals[i])!r} is {counts[i]}, more than degree + 1 = {degree + 1}"
        )
    if not t[degree] < t[n_poles]:
        raise InvalidGeometryError(
            f"{name}: the domain [knot[{degree}], knot[{n_poles}]] = [{float(t[degree])!r}, {float(t[n_poles])!r}] is empty"
        )
    check_domain_length(t, degree, n_poles, name)
    return t


def knot_tol(knots: NDArray[np.float64]) -> float:
    """Absolute knot-equality tolerance for this knot vector: ``KNOT_EQUALITY`` times its range (at least 1)."""
    return tolerances.KNOT_EQUALITY * max(float(knots[-1] - knots[0]), 1.0)


def check_domain_length(t: NDArray[np.float64], degree: int, n_poles: int, name: str) -> None:
    """Refuse a domain no longer than the knot tolerance (``KNOT_EQUALITY`` times the knot range, at
    least 1): its ends count as one knot, and the basis functions divide by spans that round to
    nothing (a domain of 1e-320 evaluates to NaN)."""
    length = float(t[n_poles] - t[degree])
    tol = knot_tol(t)
    if length <= tol:
        raise InvalidGeometryError(
            f"{name}: the domain [{float(t[degree])!r}, {float(t[n_poles])!r}] is {length:.3g} long, no longer than the "
            f"knot tolerance {tol:.3g} (tolerances.KNOT_EQUALITY): its ends count as one knot"
        )


def check_weights(weights: ArrayLike, shape: tuple[int, ...], name: str = "weights") -> NDArray[np.float64]:
    w = as_finite_array(weights, name)
    if w.shape != shape:
        raise InvalidGeometryError(f"{name}: expected shape {shape} (one weight per control point), got {w.shape}")
    if np.any(w <= 0):
        bad = np.argwhere(w <= 0)[0]
        raise InvalidGeometryError(
            f"{name}: weights must be > 0, got {float(w[tuple(bad)])!r} at index {tuple(int(i) for i in bad)}"
        )
    return w


def readonly(a: NDArray) -> NDArray:
    a = np.ascontiguousarray(a)
    a.flags.writeable = False
    return a


def check_parameters(u: ArrayLike, lo: float, hi: float, name: str = "u") -> NDArray[np.float64]:
    """Finite parameters inside ``[lo, hi]``; values a hair outside (round-off) are snapped in."""
    try:
        a = np.asarray(u, dtype=float)
    except (TypeError, ValueError) as err:
        raise ParameterError(f"{name}: expected real parameters, got {type(u).__name__}") from err
    if not a.size:
        return a.copy()
    # min and max carry a NaN or an infinity through: one pass each decides finiteness and range
    amin, amax = a.min(), a.max()
    if not (np.isfinite(amin) and np.isfinite(amax)):
        raise ParameterError(f"{name}: parameters must be finite, got {float(a[~np.isfinite(a)].ravel()[0])!r}")
    if amin >= lo and amax <= hi:
        return a.copy()  # what np.clip returns here (signed zeros kept), without its wrapper's ~4 us
    slack = tolerances.PARAMETER * max(hi - lo, 1.0)
    if amin < lo - slack or amax > hi + slack:
        bad = float(amin if amin < lo - slack else amax)
        raise ParameterError(f"{name}: parameter {bad!r} is outside the domain [{lo!r}, {hi!r}]")
    return np.clip(a, lo, hi)


def check_uv(u: ArrayLike, v: ArrayLike, domain: tuple[tuple[float, float], tuple[float, float]],
             per_point: int = 8) -> tuple[NDArray[np.float64], NDArray[np.float64], tuple[int, ...]]:
    """Surface parameters ``u, v`` checked against ``domain``, broadcast together and flattened;
    returns ``(u, v, shape)`` with ``shape`` the broadcast shape. The broadcast shape times
    ``per_point`` floats (what the caller allocates per point) is checked by :func:`check_size`
    before the flattened copies are made."""
    (u0, u1), (v0, v1) = domain
    a = check_parameters(u, u0, u1, "u")
    b = check_parameters(v, v0, v1, "v")
    check_broadcast(a, b, per_point)
    a, b = np.broadcast_arrays(a, b)
    return a.reshape(-1), b.reshape(-1), a.shape


def check_broadcast(u: ArrayLike, v: ArrayLike, per_point: int, what: str = "") -> tuple[int, ...]:
    """The shape ``u`` and ``v`` broadcast to, refused before anything of that shape is made when
    ``per_point`` floats per point would exceed ``tolerances.MAX_ARRAY_BYTES`` (``u`` of shape
    ``(n, 1)`` and ``v`` of shape ``(1, n)`` ask for ``n**2`` points). ``what`` is added to the
    message (the request, e.g. " for derivatives of order 9")."""
    try:
        shape = np.broadcast_shapes(np.shape(u), np.shape(v))
    except ValueError as err:
        raise ParameterError(f"u, v: shapes {np.shape(u)} and {np.shape(v)} do not broadcast") from err
    check_size(shape + (per_point,), f"u, v broadcast to shape {shape}{what} ({per_point} floats per point)")
    return shape


def check_parameter(u: ArrayLike, lo: float, hi: float, name: str = "u") -> float:
    """One finite parameter inside ``[lo, hi]`` (:func:`check_parameters` for a scalar)."""
    a = check_parameters(u, lo, hi, name)
    if a.ndim != 0:
        raise ParameterError(f"{name}: expected one parameter, got an array of shape {a.shape}")
    return float(a)


def _holds_complex(value: object) -> bool:
    try:
        return bool(np.iscomplexobj(np.asarray(value)))
    except (TypeError, ValueError):
        return False


def check_tol(tol: object, name: str = "tol") -> float:
    """A tolerance: a finite, non-negative real (a NaN would pass every ``dev > tol`` check)."""
    if isinstance(tol, bool) or not isinstance(tol, numbers.Real):
        raise InvalidGeometryError(f"{name}: expected a non-negative real number, got {tol!r}")
    x = float(tol)
    if not (np.isfinite(x) and x >= 0):
        raise InvalidGeometryError(f"{name}: expected a finite, non-negative number, got {tol!r}")
    return x


def check_size(shape: tuple[int, ...], what: str, itemsize: int = 8) -> None:
    """Refuse before allocating: an array of ``shape`` (``itemsize`` bytes per element) may not exceed
    ``tolerances.MAX_ARRAY_BYTES``. The message names the request and its size."""
    n = 1
    for k in shape:
        n *= int(k)
    size = n * itemsize
    limit = tolerances.MAX_ARRAY_BYTES
    if size > limit:
        raise InvalidGeometryError(f"{what}: needs an array of shape {tuple(int(k) for k in shape)} "
                                   f"({size / 2**30:.3g} GiB), more than MAX_ARRAY_BYTES = {limit / 2**30:.3g} GiB; "
                                   "ask for less (or raise the limit with tolerances.override(MAX_ARRAY_BYTES=...))")


def check_count(value: object, name: str, per_item: int, minimum: int = 1) -> int:
    """A count the user sets (samples, levels, ticks): an integer ``>= minimum`` whose arrays,
    ``per_item`` floats for each, fit ``tolerances.MAX_ARRAY_BYTES`` (refused before they exist)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or int(value) < minimum:
        raise InvalidGeometryError(f"{name}: expected an integer >= {minimum}, got {value!r}")
    k = int(value)
    check_size((k, per_item), f"{name} = {k}")
    return k


def check_homogeneous(points: NDArray[np.float64], weights: NDArray[np.float64] | None) -> None:
    """Rational poles whose homogeneous form ``w P`` overflows (poles 1e150, weights 1e200) would
    evaluate to inf or NaN: refused. Evaluation is a convex combination of ``w P`` and ``w``, so
    finite products cannot overflow later."""
    if weights is None:
        return
    with np.errstate(over="ignore", invalid="ignore"):
        wp = points * weights[..., None]
    if not np.all(np.isfinite(wp)):
        bad = tuple(int(i) for i in np.argwhere(~np.isfinite(wp))[0][:-1])
        raise InvalidGeometryError(f"control_points, weights: the weighted pole at index {bad} overflows "
                                   f"(|P| {float(np.abs(points[bad]).max()):.3g} x w {float(weights[bad]):.3g}); "
                                   "scale the model or the weights down")


def check_times(times: object, name: str = "times") -> int:
    if isinstance(times, bool) or not isinstance(times, numbers.Integral) or int(times) < 1:
        raise InvalidGeometryError(f"{name}: expected a positive integer, got {times!r}")
    return int(times)


def check_order(order: object) -> int:
    if isinstance(order, bool) or not isinstance(order, numbers.Integral) or int(order) < 0:
        raise InvalidGeometryError(f"order: expected a non-negative integer, got {order!r}")
    return int(order)


def affine_map(matrix: ArrayLike, translation: ArrayLike | None, dim: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Validated ``(M, b)`` of an affine map ``x -> M x + b`` acting on ``dim``-D points."""
    M = as_finite_array(matrix, "matrix", ndim=2)
    if M.shape != (dim, dim):
        raise InvalidGeometryError(f"matrix: expected shape {(dim, dim)}, got {M.shape}")
    b = np.zeros(dim) if translation is None else as_finite_array(translation, "translation", ndim=1)
    if b.shape != (dim,):
        raise InvalidGeometryError(f"translation: expected shape {(dim,)}, got {b.shape}")
    return M, b
