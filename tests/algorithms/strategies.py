"""Hypothesis strategies for random *valid* B-spline / NURBS curves and surfaces.

Reusable by any test module::

    from tests.algorithms.strategies import curves, surfaces, knot_vectors, parameters

What is generated
-----------------
- degrees 1..9 (configurable), dimensions 2..3;
- knot vectors clamped at both ends, at one end, or at neither (OCC-style "unclamped": the domain
  is ``[t_p, t_n]``), with repeated interior knots (multiplicity up to ``degree`` by default, so the
  spline stays continuous); distinct knots are at least ``MIN_GAP`` apart, so every non-empty span
  has a sane length and derivative magnitudes stay bounded;
- control points with coordinates in ``[-COORD, COORD]``; optional weights in ``[W_MIN, W_MAX]``.

Everything here builds objects through the public, validating constructors, so a strategy that
produced invalid data would fail loudly instead of silently testing garbage.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from hypothesis import HealthCheck, assume, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from occsurf.algorithms import BSplineCurve, BSplineSurface

__all__ = [
    "COORD",
    "MIN_GAP",
    "W_MIN",
    "W_MAX",
    "coords",
    "knot_vectors",
    "poles",
    "weights",
    "curves",
    "surfaces",
    "fractions",
    "parameters",
    "affine_maps",
    "test_settings",
]


#: Health checks that every property test of the suite suppresses unless told otherwise.
SUITE_SUPPRESSED = (HealthCheck.too_slow, HealthCheck.filter_too_much)


def test_settings(max_examples: int = 40, *,
                  suppress: Sequence[HealthCheck] | None = SUITE_SUPPRESSED) -> settings:
    """Hypothesis settings of one test (or one module) of this suite, the only place they are built.

    Parameters
    ----------
    max_examples : int
        The test's count at scale 1; it runs ``max(1, int(max_examples * scale))`` examples, where
        ``scale`` is the active profile's ``max_examples`` over 100, Hypothesis' default: 1 for the
        ``default`` and ``ci`` profiles, 25 for ``thorough`` (the profiles live in tests/conftest.py;
        e.g. ``HYPOTHESIS_PROFILE=thorough pytest tests/algorithms``).
    suppress : sequence of HealthCheck or None
        Health checks to suppress (default ``too_slow`` and ``filter_too_much``); ``None`` keeps
        the active profile's.

    Returns
    -------
    settings
        No deadline (machines vary); everything else (derandomization, database) from the profile.
    """
    scale = settings().max_examples / settings.get_profile("default").max_examples
    extra = {} if suppress is None else {"suppress_health_check": list(suppress)}
    return settings(max_examples=max(1, int(max_examples * scale)), deadline=None, **extra)


test_settings.__test__ = False  # a helper, not a pytest test

#: Coordinates of control points lie in [-COORD, COORD].
COORD = 10.0
#: Smallest distance between two distinct knots, and largest; knot values start in [-KNOT0, KNOT0].
MIN_GAP, MAX_GAP, KNOT0 = 0.25, 4.0, 10.0
#: Weights of rational splines lie in [W_MIN, W_MAX] (ratio 16: realistic, not ill-conditioned).
W_MIN, W_MAX = 0.25, 4.0

_float = dict(allow_nan=False, allow_infinity=False, allow_subnormal=False, width=64)
coords = st.floats(-COORD, COORD, **_float)
_gaps = st.floats(MIN_GAP, MAX_GAP, **_float)


def _flatten(values: list[float], mults: list[int], length: int) -> list[float]:
    out: list[float] = []
    for v, m in zip(values, mults):
        out.extend([v] * m)
    return out[:length]


@st.composite
def knot_vectors(
    draw,
    degree: int,
    n_poles: int,
    *,
    clamped: bool | None = None,
    max_multiplicity: int | None = None,
) -> np.ndarray:
    """A full valid knot vector of length ``n_poles + degree + 1``.

    Parameters
    ----------
    degree, n_poles : int
        ``n_poles >= degree + 1``.
    clamped : bool, optional
        ``True``: both ends of multiplicity ``degree + 1``; ``False``: neither end forced (the ends
        carry ordinary multiplicities); ``None``: each end drawn independently.
    max_multiplicity : int, optional
        Largest multiplicity of a knot not forced by clamping; default ``degree`` (C^0 at worst).
        At most ``degree + 1`` (the validator's limit; ``degree + 1`` inside makes a jump).

    Returns
    -------
    ndarray, shape (n_poles + degree + 1,)
    """
    p, n = degree, n_poles
    if n < p + 1:
        raise ValueError(f"n_poles must be >= degree + 1, got {n} for degree {p}")
    mmax = p if max_multiplicity is None else max_multiplicity
    if not 1 <= mmax <= p + 1:
        raise ValueError(f"max_multiplicity must be in 1..{p + 1}, got {mmax}")
    left = draw(st.booleans()) if clamped is None else clamped
    right = draw(st.booleans()) if clamped is None else clamped
    length = n + p + 1
    free = length - (p + 1) * (left + right)
    # Enough distinct values for the free part even if every multiplicity is 1.
    k = free + 2
    gaps = draw(st.lists(_gaps, min_size=k, max_size=k))
    start = draw(st.floats(-KNOT0, KNOT0, **_float))
    values = list(start + np.cumsum(gaps))
    mults = draw(st.lists(st.integers(1, mmax), min_size=k, max_size=k))
    a, b = values[0], values[-1]
    middle = _flatten(values[1:-1], mults, free)
    # Free values fill the middle; values[1:-1] has `free` entries, so `middle` is long enough.
    t = ([a] * (p + 1) if left else []) + middle + ([b] * (p + 1) if right else [])
    t = np.array(t, dtype=float)
    # The domain [t_p, t_n] must be non-empty (can fail only with a free end): else redraw.
    assume(t[p] < t[n])
    return t


def poles(shape: tuple[int, ...]) -> st.SearchStrategy[np.ndarray]:
    """Control points (or a net) of the given shape, coordinates in ``[-COORD, COORD]``."""
    return arrays(np.float64, shape, elements=coords)


def weights(shape: tuple[int, ...]) -> st.SearchStrategy[np.ndarray]:
    """Positive weights in ``[W_MIN, W_MAX]``."""
    return arrays(np.float64, shape, elements=st.floats(W_MIN, W_MAX, **_float))


@st.composite
def curves(
    draw,
    *,
    degrees: st.SearchStrategy[int] = st.integers(1, 9),
    dims: st.SearchStrategy[int] = st.integers(2, 3),
    rational: bool | None = None,
    clamped: bool | None = None,
    max_extra_poles: int = 6,
    max_multiplicity: int | None = None,
) -> BSplineCurve:
    """A valid :class:`BSplineCurve` (``degree + 1`` to ``degree + 1 + max_extra_poles`` poles).

    ``rational`` / ``clamped``: ``None`` draws either.
    """
    p = draw(degrees)
    d = draw(dims)
    n = p + 1 + draw(st.integers(0, max_extra_poles))
    t = draw(knot_vectors(p, n, clamped=clamped, max_multiplicity=max_multiplicity))
    P = draw(poles((n, d)))
    is_rat = draw(st.booleans()) if rational is None else rational
    w = draw(weights((n,))) if is_rat else None
    return BSplineCurve(p, t, P, w)


@st.composite
def surfaces(
    draw,
    *,
    degrees: st.SearchStrategy[int] = st.integers(1, 9),
    dims: st.SearchStrategy[int] = st.integers(2, 3),
    rational: bool | None = None,
    clamped: bool | None = None,
    max_extra_poles: int = 3,
    max_multiplicity: int | None = None,
) -> BSplineSurface:
    """A valid :class:`BSplineSurface`; each direction is drawn like :func:`curves`."""
    p, q = draw(degrees), draw(degrees)
    d = draw(dims)
    nu = p + 1 + draw(st.integers(0, max_extra_poles))
    nv = q + 1 + draw(st.integers(0, max_extra_poles))
    U = draw(knot_vectors(p, nu, clamped=clamped, max_multiplicity=max_multiplicity))
    Vk = draw(knot_vectors(q, nv, clamped=clamped, max_multiplicity=max_multiplicity))
    P = draw(poles((nu, nv, d)))
    is_rat = draw(st.booleans()) if rational is None else rational
    w = draw(weights((nu, nv))) if is_rat else None
    return BSplineSurface((p, q), (U, Vk), P, w)


#: Fractions of a domain, endpoints included (hypothesis hits 0 and 1 often).
fractions = st.floats(0.0, 1.0, **_float)


@st.composite
def parameters(draw, domain: tuple[float, float], *, min_size: int = 1, max_size: int = 8,
               knots: np.ndarray | None = None) -> np.ndarray:
    """Parameters inside ``domain``; with ``knots`` given, some are exactly knot values (the
    places where the one-sided conventions of evaluation matter)."""
    lo, hi = domain
    f = np.array(draw(st.lists(fractions, min_size=min_size, max_size=max_size)))
    u = np.clip(lo + f * (hi - lo), lo, hi)
    if knots is not None:
        inside = np.unique(knots[(knots >= lo) & (knots <= hi)])
        picks = draw(st.lists(st.sampled_from(list(inside)), max_size=3))
        u = np.concatenate((u, picks))
    return u


@st.composite
def affine_maps(draw, dim: int) -> tuple[np.ndarray, np.ndarray]:
    """A well-conditioned affine map ``x -> M x + b`` of moderate scale.

    ``cond(M) <= 100`` and every singular value in [0.05, 3 d]: without the lower bound a tiny
    (e.g. 1e-200-scaled) but well-conditioned matrix would pass, and absolute tolerances of the
    tests that use it would be meaningless.
    """
    M = draw(arrays(np.float64, (dim, dim), elements=st.floats(-3, 3, **_float)))
    assume(np.linalg.cond(M) <= 100)
    assume(np.linalg.svd(M, compute_uv=False).min() >= 0.05)
    b = draw(arrays(np.float64, (dim,), elements=coords))
    return M, b
