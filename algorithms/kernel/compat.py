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
    new = np.concatenate(([True], np.diff(v) > eps))
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
    counts = np.zeros((len(vecs), reps.size), dtype=np.intp)
    np.add.at(counts, (owner, labels), 1)
    return np.repeat(reps, counts.max(axis=0))


def missing_knots(knots: np.ndarray, target: np.ndarray, tol: float | None = None) -> np.ndarray:
    """The values to insert into ``knots`` so that it becomes ``target`` (a superset of it).

    Values of ``knots`` match values of ``target`` within ``tol`` (relative to the target's
    range; default ``tolerances.KNOT_EQUALITY``), multiplicities counted.

    Returns
    -------
    ndarray, shape (k,)
        Sorted, with repeats; empty when ``knots`` already holds all of ``target``.
    """
    eps = tolerances.KNOT_EQUALITY if tol is None else float(tol)
    T = np.asarray(target, float)
    K = np.asarray(knots, float)
    reps, labels = _clusters(T, eps * (float(T[-1] - T[0]) or 1.0))
    want = np.bincount(labels, minlength=reps.size)
    idx = np.minimum(np.searchsorted(reps, K), reps.size - 1)  # searchsorted is never negative
    near = np.where((idx > 0) & (np.abs(reps[idx - 1] - K) < np.abs(reps[idx] - K)), idx - 1, idx)
    have = np.bincount(near, minlength=reps.size)
    return np.repeat(reps, np.maximum(want - have, 0))


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
    work = []
    for c in items:
        c = c.clamp()
        if c.domain != (lo, hi):
            c = c.reparametrize(lo, hi)
        if c.degree < p:
            c = c.elevate_degree(p - c.degree)
        work.append(c)
    T = common_knots([c.knots for c in work])
    T[: p + 1] = lo
    T[-(p + 1):] = hi
    out = []
    for c in work:
        missing = missing_knots(c.knots, T)
        if missing.size:
            c = c.refine(missing)
        w = c.weights if c.weights is not None else (np.ones(c.n_poles) if rational else None)
        # c.knots equals T up to the knot-equality tolerance; use T itself so the vectors are identical
        out.append(BSplineCurve._trusted(p, T.copy(), c.control_points, w))
    return out
