"""Making B-spline curves compatible: one degree, one knot vector, one domain.

Ruled surfaces, Coons patches, lofts and Gordon surfaces combine the control points of several
curves row by row, which is only meaningful when the curves share a degree and a knot vector.
Compatibility is reached without changing any curve's geometry: a common parameter domain by an
affine reparametrisation, a common degree by degree elevation (course §2-6), and a common knot
vector by knot refinement (course §2-10, Oslo algorithm). See also The NURBS Book, 2nd ed., §10.3.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from .. import tolerances
from ..errors import InvalidGeometryError, ParameterError
from .curve import BSplineCurve
from .degree import elevate_poles
from .knots import check_rescaled, clamp_poles, refine_poles, refinement_knots, rescale_knots
from .rational import from_homogeneous, to_homogeneous

__all__ = ["make_compatible", "common_knots", "missing_knots"]


def _check_curves(curves: Sequence[BSplineCurve], name: str = "curves") -> list[BSplineCurve]:
    try:
        items = list(curves)
    except TypeError as err:
        raise InvalidGeometryError(f"{name}: expected a sequence of BSplineCurve, got {type(curves).__name__}") from err
    if not items:
        raise InvalidGeometryError(f"{name}: expected at least one curve, got none")
    for i, c in enumerate(items):
        if not isinstance(c, BSplineCurve):
            raise InvalidGeometryError(f"{name}[{i}]: expected a BSplineCurve, got {type(c).__name__}")
    dims = {c.dim for c in items}
    if len(dims) != 1:
        raise InvalidGeometryError(f"{name}: all curves must have the same dimension, got {sorted(dims)}")
    return items


def _clusters(values: np.ndarray, eps: float) -> tuple[np.ndarray, np.ndarray]:
    """Sorted representatives of ``values`` merged within ``eps``, and each value's cluster index."""
    order = np.argsort(values, kind="stable")
    v = values[order]
    new = np.concatenate(([True], v[1:] - v[:-1] > eps))  # np.diff's values without its wrapper
    label_sorted = np.cumsum(new) - 1
    labels = np.empty_like(label_sorted)
    labels[order] = label_sorted
    return v[new], labels


def common_knots(knot_vectors: Sequence[np.ndarray], tol: float | None = None) -> np.ndarray:
    """The smallest knot vector that contains every given one (same domain assumed).

    Distinct values closer than ``tol`` (relative to the knot range; default
    ``tolerances.KNOT_EQUALITY``) are one knot; its multiplicity is the largest among the inputs.

    Parameters
    ----------
    knot_vectors : sequence of ndarray, each shape (n_k + p + 1,)
        Full knot vectors of curves of one degree on one domain.

    Returns
    -------
    ndarray, shape (N,)
        The merged full knot vector; each knot takes the smallest value of its cluster.
    """
    eps = tolerances.KNOT_EQUALITY if tol is None else float(tol)
    vecs = [np.asarray(k, float) for k in knot_vectors]
    allk = np.concatenate(vecs)
    span = float(allk.max() - allk.min()) or 1.0
    reps, labels = _clusters(allk, eps * span)
    owner = np.repeat(np.arange(len(vecs)), [k.size for k in vecs])
    # each input's count per cluster (np.add.at's counts, by one bincount of the (input, cluster) pairs)
    counts = np.bincount(owner * reps.size + labels, minlength=len(vecs) * reps.size).reshape(len(vecs), reps.size)
    return np.repeat(reps, counts.max(axis=0))


def _target(target: np.ndarray, tol: float | None) -> tuple[np.ndarray, np.ndarray]:
    """The clusters of a target knot vector (:func:`missing_knots`): representatives and counts."""
    eps = tolerances.KNOT_EQUALITY if tol is None else float(tol)
    T = np.asarray(target, float)
    reps, labels = _clusters(T, eps * (float(T[-1] - T[0]) or 1.0))
    return reps, np.bincount(labels, minlength=reps.size)


def _missing(knots: np.ndarray, reps: np.ndarray, want: np.ndarray) -> np.ndarray:
    """:func:`missing_knots` given the target's clusters (:func:`_target`)."""
    K = np.asarray(knots, float)
    idx = np.minimum(np.searchsorted(reps, K), reps.size - 1)  # searchsorted is never negative
    near = np.where((idx > 0) & (np.abs(reps[idx - 1] - K) < np.abs(reps[idx] - K)), idx - 1, idx)
    have = np.bincount(near, minlength=reps.size)
    return np.repeat(reps, np.maximum(want - have, 0))


def missing_knots(knots: np.ndarray, target: np.ndarray, tol: float | None = None) -> np.ndarray:
    """The values to insert into ``knots`` so that it becomes ``target`` (a superset of it).

    Values of ``knots`` match values of ``target`` within ``tol`` (relative to the target's
    range; default ``tolerances.KNOT_EQUALITY``), multiplicities counted.

    Returns
    -------
    ndarray, shape (k,)
        Sorted, with repeats; empty when ``knots`` already holds all of ``target``.
    """
    return _missing(knots, *_target(target, tol))


class _Work:
    """A curve on its way through :func:`make_compatible`, as arrays: degree, knots, Cartesian poles,
    weights and the homogeneous poles the kernels take. Each step stores its result exactly as the
    :class:`BSplineCurve` that the curve's own method returns would hold it (homogeneous poles split
    into poles and weights and multiplied back), so the poles are those of the method calls, bit for
    bit, without a curve object per step."""

    __slots__ = ("degree", "knots", "P", "w", "H")

    def __init__(self, c: BSplineCurve) -> None:
        self.degree, self.knots, self.P, self.w, self.H = c.degree, c.knots, c.control_points, c.weights, c._hpoles

    def _poles(self, knots: np.ndarray, H: np.ndarray) -> None:
        """As ``BSplineCurve._from_homogeneous(degree, knots, H, rational)`` stores them."""
        self.knots = knots
        if self.w is None:
            self.P = self.H = H
        else:
            self.P, self.w = from_homogeneous(H)
            self.H = to_homogeneous(self.P, self.w)

    def clamp(self) -> None:
        """:meth:`BSplineCurve.clamp`."""
        t, H = clamp_poles(self.knots, self.degree, self.H)
        if t is not self.knots:
            self._poles(t, H)

    def domain(self) -> tuple[float, float]:
        return float(self.knots[self.degree]), float(self.knots[self.P.shape[0]])

    def reparametrize(self, lo: float, hi: float) -> None:
        """:meth:`BSplineCurve.reparametrize` (the poles stay as they are)."""
        self.knots = check_rescaled(rescale_knots(self.knots, self.domain(), (lo, hi)), self.knots, (lo, hi),
                                    "reparametrize")

    def elevate(self, times: int) -> None:
        """:meth:`BSplineCurve.elevate_degree`."""
        t, H = elevate_poles(self.knots, self.degree, self.H, times)
        self.degree += times
        self._poles(t, H)

    def refine(self, x: np.ndarray) -> None:
        """:meth:`BSplineCurve.refine` with interior values ``x`` (its checks and errors)."""
        tau = refinement_knots(self.knots, self.degree, self.P.shape[0], self.H.shape[-1], x)
        self._poles(tau, refine_poles(self.knots, self.degree, self.H, tau))


def make_compatible(
    curves: Sequence[BSplineCurve], *, domain: tuple[float, float] | None = None
) -> list[BSplineCurve]:
    """Give curves one degree, one knot vector and one domain without changing their shapes.

    Parameters
    ----------
    curves : sequence of BSplineCurve
        Curves of one dimension; clamped or not, rational or not.
    domain : (float, float), optional
        The common parameter domain. ``None`` keeps the curves' domain when they all share one
        (to ``tolerances.KNOT_EQUALITY``) and uses ``(0, 1)`` otherwise.

    Returns
    -------
    list of BSplineCurve
        In the input order. All clamped, with the highest input degree, the same knot vector
        (bit-identical arrays) and, if any input is rational, all rational (polynomial curves get
        unit weights). Each equals its input curve up to round-off (affine reparametrisation,
        degree elevation and knot insertion are exact operations).

    Raises
    ------
    InvalidGeometryError
        An empty sequence, a non-curve, or mixed dimensions.
    ParameterError
        ``domain`` not a finite increasing pair.

    Notes
    -----
    Course §2-10 (knot refinement) and §2-6 (degree raising); The NURBS Book, 2nd ed., §10.3
    ("making curves compatible" for skinning).
    """
    items = _check_curves(curves)
    if domain is None:
        doms = np.array([c.domain for c in items])
        span = float(np.ptp(doms)) or 1.0
        same = np.all(np.abs(doms - doms[0]) <= tolerances.KNOT_EQUALITY * max(span, float(np.abs(doms).max())))
        lo, hi = (float(doms[0, 0]), float(doms[0, 1])) if same else (0.0, 1.0)
    else:
        try:
            lo, hi = (float(x) for x in domain)
        except (TypeError, ValueError) as err:
            raise ParameterError(f"domain: expected a pair (start, end), got {domain!r}") from err
        if not (np.isfinite(lo) and np.isfinite(hi) and lo < hi):
            raise ParameterError(f"domain: expected finite start < end, got {domain!r}")
    p = max(c.degree for c in items)
    rational = any(c.is_rational for c in items)
    # the steps of c.clamp(), c.reparametrize(lo, hi), c.elevate_degree(k) and c.refine(missing) on
    # arrays (_Work): the same poles, bit for bit, without the five intermediate curves and their checks
    work = []
    for c in items:
        wk = _Work(c)
        wk.clamp()
        if wk.domain() != (lo, hi):
            wk.reparametrize(lo, hi)
        if wk.degree < p:
            wk.elevate(p - wk.degree)
        work.append(wk)
    T = common_knots([wk.knots for wk in work])
    T[: p + 1] = lo
    T[-(p + 1):] = hi
    reps, want = _target(T, None)  # the target's clusters, once for every curve
    out = []
    for wk in work:
        missing = _missing(wk.knots, reps, want)
        if missing.size:
            wk.refine(missing)
        w = wk.w if wk.w is not None else (np.ones(wk.P.shape[0]) if rational else None)
        # wk.knots equals T up to the knot-equality tolerance; use T itself so the vectors are identical
        out.append(BSplineCurve._trusted(p, T.copy(), wk.P, w))
    return out
