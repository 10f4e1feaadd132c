"""Helpers shared by the constructions of course ch. 6, above all the transfinite ones: Coons
patches (:mod:`.coons_patches`, §6-20, §6-21) and Gordon surfaces (:mod:`.gordon_surfaces`,
§6-22..6-25); :mod:`.generation` and :mod:`.sweeping` check their curves here too.

Argument checking (:func:`resolve_tolerance`, :func:`check_curve`, :func:`check_curves`), the
(homogeneous) pole arrays of curves (:func:`homogeneous_poles`), and tensor-product nets: bringing
several to one pair of degrees and knot vectors (:func:`unify_nets`) and turning the sum back into
a surface (:func:`surface_from_net`). A *net* here is ``((p, q), (U, V), H)``: degrees, clamped
knot vectors and poles ``H`` of shape ``(n_u, n_v, k)``, homogeneous (weight last, coordinates
premultiplied) for rational nets.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidGeometryError
from ..kernel.compat import common_knots, missing_knots
from ..kernel.curve import BSplineCurve
from ..kernel.degree import elevate_poles
from ..kernel.knots import merge_knots, refine_poles, snap_knots
from ..kernel.rational import from_homogeneous, to_homogeneous
from ..kernel.surface import BSplineSurface

__all__ = [
    "Net",
    "resolve_tolerance",
    "check_curve",
    "check_curves",
    "homogeneous_poles",
    "unify_nets",
    "surface_from_net",
]

Array = NDArray[np.float64]

#: A tensor-product net: degrees ``(p, q)``, knot vectors ``(U, V)`` and poles ``(n_u, n_v, k)``.
Net = tuple[tuple[int, int], tuple[Array, Array], Array]


def resolve_tolerance(value: float | None, default: float, name: str = "tol") -> float:
    """The tolerance a caller passed, or ``default`` when it passed ``None``.

    Parameters
    ----------
    value : float or None
        The caller's argument.
    default : float
        The value to use for ``None``; callers read it from :mod:`occsurf.algorithms.tolerances`
        at call time.
    name : str
        The argument's name, for the error message.

    Returns
    -------
    float

    Raises
    ------
    InvalidGeometryError
        ``value`` is not a finite number ``>= 0`` (the message names ``name``).
    """
    if value is None:
        return default
    t = float(value)
    if not np.isfinite(t) or t < 0:
        raise InvalidGeometryError(f"{name}: expected a finite value >= 0, got {value!r}")
    return t


def check_curve(curve: object, name: str, dim: int | None = None) -> BSplineCurve:
    """``curve`` itself if it is a :class:`BSplineCurve` (of dimension ``dim``, if given).

    Raises
    ------
    InvalidGeometryError
        Otherwise; the message names the argument ``name``.
    """
    if not isinstance(curve, BSplineCurve):
        raise InvalidGeometryError(f"{name}: expected a BSplineCurve, got {type(curve).__name__}")
    if dim is not None and curve.dim != dim:
        raise InvalidGeometryError(
            f"{name}: expected a {dim}-D curve (poles of shape (n, {dim})), got dimension {curve.dim}"
        )
    return curve


def check_curves(items: object, name: str, minimum: int = 2) -> list[BSplineCurve]:
    """The curves of a sequence argument, as a list.

    Parameters
    ----------
    items : sequence of BSplineCurve
        The argument.
    name : str
        Its name, for error messages (an item is named ``name[i]``).
    minimum : int
        Fewest curves accepted.

    Returns
    -------
    list of BSplineCurve

    Raises
    ------
    InvalidGeometryError
        ``items`` is not iterable, has fewer than ``minimum`` items, or an item is not a curve.
    """
    try:
        out = list(items)  # type: ignore[call-overload]
    except TypeError as err:
        raise InvalidGeometryError(f"{name}: expected a sequence of BSplineCurve, got {type(items).__name__}") from err
    if len(out) < minimum:
        raise InvalidGeometryError(f"{name}: expected at least {minimum} curves, got {len(out)}")
    return [check_curve(c, f"{name}[{i}]") for i, c in enumerate(out)]


def homogeneous_poles(curve: BSplineCurve, rational: bool) -> Array:
    """Poles of a curve, homogeneous if ``rational``.

    Parameters
    ----------
    curve : BSplineCurve
        With ``n`` poles in dimension ``d``.
    rational : bool
        Whether the caller works in homogeneous coordinates (a polynomial curve then gets weights 1).

    Returns
    -------
    ndarray, shape (n, d) or (n, d + 1)
        The Cartesian poles, or ``(w P, w)`` when ``rational``.
    """
    if not rational:
        return np.asarray(curve.control_points, float)
    w = np.ones(curve.n_poles) if curve.weights is None else curve.weights
    return to_homogeneous(np.asarray(curve.control_points, float), w)


def unify_nets(nets: list[Net]) -> tuple[tuple[int, int], tuple[Array, Array], list[Array]]:
    """Bring tensor-product nets to one pair of degrees and knot vectors (exact operations).

    Each item is ``((p, q), (U, V), H)`` with ``H`` of shape ``(n_u, n_v, k)`` (homogeneous
    coordinates for rational nets: the kernels are linear, so no weight is ever divided by); all
    are clamped on one domain. Per direction: degree elevation to the highest degree, then knot
    refinement to the union of the knot vectors, as
    :func:`occsurf.algorithms.kernel.compat.make_compatible` does for curves. The surfaces the
    nets describe do not change.

    Parameters
    ----------
    nets : list of Net

    Returns
    -------
    degrees : (int, int)
    knots : (ndarray, ndarray)
        The common knot vectors, shapes ``(N_u + p + 1,)`` and ``(N_v + q + 1,)``.
    poles : list of ndarray, each shape (N_u, N_v, k)
        The nets on those knots, in the order given (C-contiguous), ready to be added.
    """
    items = [(list(d), list(kn), np.asarray(H, float)) for d, kn, H in nets]
    for ax in (0, 1):
        top = max(d[ax] for d, _, _ in items)
        elevated = []
        for d, kn, H in items:
            if d[ax] < top:
                kn = list(kn)
                kn[ax], Hx = elevate_poles(kn[ax], d[ax], np.moveaxis(H, ax, 0), top - d[ax])
                H = np.moveaxis(Hx, 0, ax)
                d = list(d)
                d[ax] = top
            elevated.append((d, kn, H))
        items = elevated
        T = common_knots([kn[ax] for _, kn, _ in items])
        lo, hi = float(T[0]), float(T[-1])
        T[: top + 1], T[-(top + 1):] = lo, hi
        out = []
        for d, kn, H in items:
            missing = missing_knots(kn[ax], T)
            if missing.size:
                tau = merge_knots(kn[ax], snap_knots(kn[ax], missing))
                H = np.moveaxis(refine_poles(kn[ax], top, np.moveaxis(H, ax, 0), tau), 0, ax)
            kn = list(kn)
            kn[ax] = T
            out.append((d, kn, H))
        items = out
    d, kn, _ = items[0]
    return (d[0], d[1]), (kn[0], kn[1]), [np.ascontiguousarray(H) for _, _, H in items]


def surface_from_net(degrees: tuple[int, int], knots: tuple[Array, Array], H: Array, rational: bool,
                     what: str) -> BSplineSurface:
    """The surface of a net, dividing out the weights if ``rational``.

    Parameters
    ----------
    degrees : (int, int)
    knots : (ndarray, ndarray)
    H : ndarray, shape (n_u, n_v, k)
        Cartesian poles, or homogeneous ones (weight last) if ``rational``.
    rational : bool
    what : str
        The public function building the surface, for the error message.

    Returns
    -------
    BSplineSurface

    Raises
    ------
    InvalidGeometryError
        A homogeneous net with a weight ``<= 0`` (no NURBS surface has it).
    """
    if not rational:
        return BSplineSurface._trusted(degrees, knots, np.ascontiguousarray(H))
    if np.any(H[..., -1] <= 0):
        raise InvalidGeometryError(
            f"{what}: the homogeneous construction gives non-positive weights "
            f"(min {float(H[..., -1].min()):.3g}); rescale the curves' weights"
        )
    P, w = from_homogeneous(np.ascontiguousarray(H))
    return BSplineSurface._trusted(degrees, knots, P, w)
