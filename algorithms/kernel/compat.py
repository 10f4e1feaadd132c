"""Making B-spline curves compatible: one degree, one knot vector, one domain.

Ruled surfaces, Coons patches, lofts and Gordon surfaces combine the control points of several
curves row by row, which is only meaningful when the curves share a degree and a knot vector.
Compatibility is reached without changing any curve's geometry: a common parameter domain by an
affine reparametrisation, a common degree by degree elevation (course §2-6), and a common knot
vector by knot refinement (course §2-10, Oslo algorithm). See also The NURBS Book, 2nd ed., §10.3.

The last two are one step here: every pole of a result is a blossom of the input at consecutive
knots of its refined knot vector, and the blossom of a degree raised from ``q`` to ``p`` is the
mean of the degree-``q`` blossom over the ways to choose ``q`` of its ``p`` arguments (Ramshaw
1989). The curves of one degree go through one blossom recurrence together. (Before 2026-12-07
each curve was raised, then refined, one knot vector at a time: the same poles to a few ulps,
twice the time on a ruled surface of two small curves, where the cost is the number of NumPy
calls, not arithmetic.)
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import lru_cache
from itertools import accumulate, combinations
from math import comb

import numpy as np

from .. import tolerances
from .._validate import check_size
from ..errors import InvalidGeometryError, ParameterError
from .blossom import blossom_rows
from .curve import BSplineCurve
from .degree import elevate_poles
from .knots import check_rescaled, clamp_poles, distinct_knots, rescale_knots
from .rational import from_homogeneous

__all__ = ["make_compatible", "compatible_poles", "compatible_sets", "common_knots", "missing_knots"]

#: Above this many argument choices (``C(p, q)``, degree ``q`` raised to ``p``) the degree is raised
#: one step at a time first (:func:`~.degree.elevate_poles`); ``C(3, 2) = 3``, ``C(9, 4) = 126``.
_MAX_SUBSETS = 64


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


def _common_runs(values: Sequence[np.ndarray], counts: Sequence[np.ndarray]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`common_knots` of knot vectors given as runs (distinct values, multiplicities), as
    clusters: each cluster's value (the smallest in it), its multiplicity (the most copies one
    input has in it) and each input value's cluster, in the order of ``np.concatenate(values)``.
    The merged knot vector is ``np.repeat(value, multiplicity)``."""
    allv = np.concatenate(values)
    allc = np.concatenate(counts)
    order = np.argsort(allv, kind="stable")
    v = allv[order]
    new = np.empty(v.shape[0], dtype=bool)
    new[0] = True
    np.greater(v[1:] - v[:-1], tolerances.KNOT_EQUALITY * (float(v[-1] - v[0]) or 1.0), out=new[1:])
    starts = np.flatnonzero(new)
    labels = np.empty(v.shape[0], dtype=np.intp)
    labels[order] = np.cumsum(new) - 1
    # Each input's runs are sorted and its last value (the domain's end) is never in the cluster of
    # the next input's first: equal neighbour labels mean two runs of one input in one cluster.
    if not np.any(labels[1:] == labels[:-1]):
        return v[starts], np.maximum.reduceat(allc[order], starts), labels  # the most copies of a value
    # an input with two values closer than the tolerance: its knots in that cluster add up
    k = len(values)
    owner = np.repeat(np.arange(k), [x.size for x in values])
    per = np.bincount(owner * starts.size + labels, weights=allc, minlength=k * starts.size)
    return v[starts], per.reshape(k, starts.size).max(axis=0).astype(np.intp), labels


def _knot_vector(value: np.ndarray, mult: np.ndarray, p: int, lo: float, hi: float) -> np.ndarray:
    """``np.repeat(value, mult)`` with the ``p + 1`` copies at each end exactly ``lo`` and ``hi``."""
    T = np.repeat(value, mult)
    T[: p + 1] = lo
    T[-(p + 1):] = hi
    return T


def _own_knots(vals: np.ndarray, m: np.ndarray, lab: np.ndarray, value: np.ndarray, mult: np.ndarray, p: int,
               lo: float, hi: float) -> np.ndarray:
    """A curve's knot vector (distinct ``vals``, multiplicities ``m`` at degree ``p``, clusters
    ``lab``) refined to as many knots per cluster as the merged vector (cluster values ``value``,
    multiplicities ``mult``): the added copies at the curve's own value in that cluster (its first,
    as knot refinement snaps a value to the nearest knot), at the cluster's value elsewhere. Index
    for index it has the merged vector's structure: a cluster's copies in the same places."""
    if not np.any(lab[1:] == lab[:-1]):  # one value per cluster: its copies all take it
        own = value.copy()
        own[lab] = vals
        return _knot_vector(own, mult, p, lo, hi)
    # two values of the curve in one cluster: both kept with their own multiplicities
    have = np.bincount(lab, weights=m, minlength=value.shape[0]).astype(np.intp)
    at = value.copy()
    first = np.empty(lab.shape[0], dtype=bool)  # the first of the curve's values in each cluster
    first[0] = True
    np.not_equal(lab[1:], lab[:-1], out=first[1:])
    at[lab[first]] = vals[first]
    tau = np.sort(np.concatenate((np.repeat(vals, m), np.repeat(at, mult - have))))
    tau[: p + 1] = lo
    tau[-(p + 1):] = hi
    return tau


@lru_cache(maxsize=64)
def _subsets(p: int, q: int) -> np.ndarray:
    """The ``C(p, q)`` ways to pick ``q`` of ``p`` blossom arguments, as column indices (read-only)."""
    S = np.array(list(combinations(range(p), q)), dtype=np.intp).reshape(-1, q)
    S.flags.writeable = False
    return S


def _check_clusters(value: np.ndarray, mult: np.ndarray, p: int, lo: float, hi: float) -> None:
    """The merged knot vector's checks (clusters ``value``, multiplicities ``mult``), as knot
    refinement made them (:func:`~.knots.refinement_knots`): interior knots strictly inside the
    domain, none above multiplicity ``p + 1``. Knots closer than the knot tolerance (or chained
    by such gaps) are one knot, their copies counted together, so a curve with an interior knot
    that close to a domain end, or with knots that close to each other whose copies add up beyond
    ``p + 1``, is refused here. Every curve ends in ``p + 1`` copies of ``lo`` and of ``hi``, so
    an end cluster with more holds an interior knot."""
    for end, m in ((lo, int(mult[0])), (hi, int(mult[-1]))):
        if m > p + 1:
            raise ParameterError(
                f"knots: an interior knot lies within the knot tolerance (tolerances.KNOT_EQUALITY of the range) "
                f"of the domain end {end!r}: merged with it, that end would have {m} copies, above degree + 1 = {p + 1}")
    k = int(np.argmax(mult))
    if mult[k] > p + 1:
        raise InvalidGeometryError(
            f"knots: knot {float(value[k])!r} would get multiplicity {int(mult[k])}, above degree + 1 = {p + 1} "
            "(knots within the knot tolerance of each other count as one)")


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
        degree elevation and knot insertion are exact operations), where no two curves have knots
        that differ by less than the knot tolerance (Notes).

    Raises
    ------
    InvalidGeometryError
        An empty sequence, a non-curve, or mixed dimensions; knots (of one curve or of several)
        within ``tolerances.KNOT_EQUALITY`` of each other whose copies together exceed
        ``degree + 1``.
    ParameterError
        ``domain`` not a finite increasing pair; an interior knot within that tolerance of a
        domain end.

    Notes
    -----
    Course §2-10 (knot refinement) and §2-6 (degree raising); The NURBS Book, 2nd ed., §10.3
    ("making curves compatible" for skinning). :func:`compatible_poles` gives the same as arrays.
    Knots of different curves equal within the knot tolerance become one (the smallest value):
    each curve is first refined exactly on its own knots, then takes the common vector, which
    moves it by about the knots' difference times its poles' differences over the spans there.
    """
    p, T, poles = compatible_poles(curves, domain=domain)
    # every curve holds T itself (a copy each), not its own knots equal to it within the tolerance
    return [BSplineCurve._trusted(p, T.copy(), P, w) for P, w in poles]


def _common_domain(items: list[BSplineCurve], domain: tuple[float, float] | None) -> tuple[float, float]:
    """The domain of :func:`make_compatible`: ``domain`` checked, or the curves' own when they share
    one (to ``tolerances.KNOT_EQUALITY`` of the largest of their span and end values), else (0, 1)."""
    if domain is None:
        doms = [c.domain for c in items]
        ends = [x for d in doms for x in d]  # a few floats: Python's arithmetic, NumPy's results
        span = (max(ends) - min(ends)) or 1.0
        ref = tolerances.KNOT_EQUALITY * max(span, max(abs(x) for x in ends))
        (a0, b0) = doms[0]
        same = all(abs(a - a0) <= ref and abs(b - b0) <= ref for a, b in doms)
        return (a0, b0) if same else (0.0, 1.0)
    try:
        lo, hi = (float(x) for x in domain)
    except (TypeError, ValueError) as err:
        raise ParameterError(f"domain: expected a pair (start, end), got {domain!r}") from err
    if not (np.isfinite(lo) and np.isfinite(hi) and lo < hi):
        raise ParameterError(f"domain: expected finite start < end, got {domain!r}")
    return lo, hi


Compatible = tuple[int, np.ndarray, list[tuple[np.ndarray, np.ndarray | None]]]


def compatible_poles(curves: Sequence[BSplineCurve], *, domain: tuple[float, float] | None = None) -> Compatible:
    """:func:`make_compatible` as arrays: the common degree, the common knot vector and each curve's
    poles and weights (``None`` when no input is rational), without a curve object per result.

    The constructions that combine the curves' poles row by row (ruled, Coons, Gordon, loft) take
    these; the checks, errors and values are those of :func:`make_compatible`.
    """
    return compatible_sets([(curves, domain)])[0]


def compatible_sets(sets: Sequence[tuple[Sequence[BSplineCurve], tuple[float, float] | None]]) -> list[Compatible]:
    """:func:`compatible_poles` of several independent sets of curves (each with its ``domain``), e.g.
    the u and the v boundaries of a Coons patch: the same results, with the blossom evaluations of
    all the sets' curves of one degree in one recurrence."""
    out: list[Compatible] = []
    # per blossom pass (curve degree, pole width, target degree): (set, curve, knots, poles, blossom
    # arguments, points picking the pieces) of its curves
    passes: dict[tuple[int, int, int], list[tuple[int, int, np.ndarray, np.ndarray, np.ndarray, np.ndarray]]] = {}
    rational_sets = []
    for si, (curves, domain) in enumerate(sets):
        items = _check_curves(curves)
        lo, hi = _common_domain(items, domain)
        p = max(c.degree for c in items)
        rational_sets.append(any(c.is_rational for c in items))
        # Each curve clamped and its knots moved onto [lo, hi] (the poles stay: an affine change of
        # parameter), then the merged knot vector of the curves raised to degree p.
        prepared = []
        for c in items:
            t, H = clamp_poles(c.knots, c.degree, c._hpoles)
            dom = (float(t[c.degree]), float(t[-1]))
            if dom != (lo, hi):
                t = check_rescaled(rescale_knots(t, dom, (lo, hi)), t, (lo, hi), "reparametrize")
            prepared.append((c.degree, t, H))
        runs = [distinct_knots(t) for _, t, _ in prepared]
        value, mult, label = _common_runs([v for v, _ in runs], [m + (p - q) for (q, _, _), (_, m) in zip(prepared, runs)])
        _check_clusters(value, mult, p, lo, hi)
        T = _knot_vector(value, mult, p, lo, hi)
        n2 = T.shape[0] - p - 1
        at = np.arange(n2)[:, None] + 1 + np.arange(p)  # pole i of the result is the blossom at T[i+1 .. i+p]
        # the first non-empty span of T in each pole's support (support_span's first half, shared by
        # the set's curves): the piece of a curve whose blossom gives the pole is the one over it
        k = np.minimum(np.searchsorted(T, T[:n2], side="right") - 1, T.shape[0] - 2)
        args, mid = T[at], 0.5 * (T[k] + T[k + 1])
        poles: list[tuple[np.ndarray, np.ndarray | None]] = []
        first = 0
        for j, (c, (q, t, H), (vals, m)) in enumerate(zip(items, prepared, runs)):
            start, first = first, first + vals.shape[0]  # the curve's values among `label`'s
            poles.append((c.control_points, c.weights))
            if q == p and t.shape[0] == T.shape[0]:  # same length and degree: no knot of T is missing
                if H is not c._hpoles:  # clamped: its new poles
                    poles[j] = _split(H, c.dim)
                continue
            m = m + (p - q)  # the multiplicities of the curve's knots at degree p
            if q < p and comb(p, q) > _MAX_SUBSETS:  # raise the degree first (few curves reach here)
                t, H = elevate_poles(t, q, H, p - q)
                q = p
            lab = label[start:first]
            if (vals == value[lab]).all():
                passes.setdefault((q, H.shape[-1], p), []).append((si, j, t, H, args, mid))
                continue
            # Knots equal to T's within the knot tolerance but not bit for bit (an ulp from a
            # rescaling, a near-duplicate in another curve): the blossoms are taken at the curve's
            # own knots refined by T's others, where the blossom identity is exact (at T's values
            # a short piece's blossom, extrapolated to its pole's far arguments, would multiply the
            # difference by (1 / its length)^degree). The poles then go with T, as the refinement on
            # the curve's own knots followed by T did before.
            tau = _own_knots(vals, m, lab, value, mult, p, lo, hi)
            passes.setdefault((q, H.shape[-1], p), []).append((si, j, t, H, tau[at], 0.5 * (tau[k] + tau[k + 1])))
        out.append((p, T, poles))
    for (q, _, p), members in passes.items():
        new = _blossom_poles(q, p, [(t, H, a, m) for _, _, t, H, a, m in members])
        for (si, j, *_), Hj in zip(members, new):
            out[si][2][j] = _split(Hj, out[si][2][j][0].shape[-1])  # the entry holds the input's poles
    for (p, T, poles), rational in zip(out, rational_sets):
        if rational:  # polynomial curves of a set with a rational one get unit weights
            n2 = T.shape[0] - p - 1
            poles[:] = [(P, np.ones(n2) if w is None else w) for P, w in poles]
    return out


def _split(H: np.ndarray, dim: int) -> tuple[np.ndarray, np.ndarray | None]:
    """Poles and weights of poles that are homogeneous (``dim + 1`` columns) or Cartesian."""
    return (H, None) if H.shape[-1] == dim else from_homogeneous(H)


def _blossom_poles(q: int, p: int, members: list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]]
                   ) -> list[np.ndarray]:
    """The poles of degree-``q`` splines written with degree ``p >= q`` on new knot vectors: for each
    member ``(t, H, args, mid)`` (knots, poles of one width for all members, the new poles' blossom
    arguments and a point inside the first non-empty new span of each new pole's support), pole
    ``i`` is the degree-``p`` blossom at ``args[i]`` of the piece over ``mid[i]``.

    Degree raising and knot refinement in one step (course §2-6, §2-10): the degree-``p`` blossom of
    a degree-``q`` polynomial is the mean of its degree-``q`` blossom over the ``C(p, q)`` choices of
    ``q`` of the ``p`` arguments (L. Ramshaw, "Blossoms are polar forms", CAGD 6, 1989, §6), so the
    weights of the ``q + 1`` poles of the piece are summed over the choices before one contraction.
    With ``q == p`` this is the Oslo algorithm (discrete B-splines). The arguments are a refinement
    of the member's own knots, so all weights are non-negative (discrete B-splines are): each new
    pole is a convex combination of old ones and its round-off is a few ulps of their size.

    The members go through one recurrence: their knot vectors end to end, each span index shifted by
    the knots before it (the recurrence reads ``t[mu - q + 1 .. mu + q]``, inside the member's own
    vector for a span of its domain), each pole index by the poles before it.
    """
    k_off = p_off = 0
    mus, cols, sizes = [], [], []
    for t, H, _, mid in members:
        mu = np.searchsorted(t, mid, side="right") - 1
        mus.append(mu + k_off)
        cols.append(mu + (p_off - q))
        sizes.append(mu.shape[0])
        k_off += t.shape[0]
        p_off += H.shape[0]

    def joined(arrays: list[np.ndarray]) -> np.ndarray:
        return np.concatenate(arrays) if len(arrays) > 1 else arrays[0]

    kn, H, a = joined([m[0] for m in members]), joined([m[1] for m in members]), joined([m[2] for m in members])
    mu_all, first = joined(mus), joined(cols)  # first: each new pole's first old pole
    m = mu_all.shape[0]
    if q == p:
        A = blossom_rows(kn, q, mu_all, a)
    else:
        S = _subsets(p, q)
        check_size((m * S.shape[0], q + 1), f"raise the degree from {q} to {p}")
        A = blossom_rows(kn, q, np.repeat(mu_all, S.shape[0]), a[:, S].reshape(-1, q))
        A = A.reshape(q + 1, m, S.shape[0]).sum(axis=2) / S.shape[0]
    out = np.einsum("km,mk...->m...", A, np.take(H, first[:, None] + np.arange(q + 1), axis=0))
    ends = list(accumulate(sizes))
    return [out[e - n:e] for e, n in zip(ends, sizes)]  # np.split's views, without its wrapper
