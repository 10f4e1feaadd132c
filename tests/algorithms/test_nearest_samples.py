"""The nearest sample of each point (``topology.nsided_loops.nearest_samples``, the start of
:func:`closest_parameters`' Newton iteration): a k-d tree's few candidates rescored, against every
sample compared (the way it was done before, kept here as the oracle). The index must be the same,
bit for bit, also where samples repeat (a closed curve's ends, a degenerate side, all samples one
point) and for points that are not finite."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from occsurf.algorithms.kernel.curve import BSplineCurve
from occsurf.algorithms.topology.nsided_loops import closest_parameters, nearest_samples


def _every_sample(P: np.ndarray, dense: np.ndarray) -> np.ndarray:
    diff = P[:, None] - dense[None]
    return np.argmin(np.einsum("mkd,mkd->mk", diff, diff), axis=1)


@settings(max_examples=80, deadline=None)
@given(seed=st.integers(0, 2 ** 31), dim=st.sampled_from([2, 3, 4]), k=st.sampled_from([3, 5, 60, 401]),
       m=st.sampled_from([1, 7, 300]), kind=st.sampled_from(["random", "repeats", "one point", "closed", "walk"]))
def test_the_nearest_sample_is_the_one_every_sample_compared_gives(seed: int, dim: int, k: int, m: int,
                                                                   kind: str) -> None:
    rng = np.random.default_rng(seed)
    if kind == "random":
        dense = rng.standard_normal((k, dim))
    elif kind == "repeats":
        dense = np.repeat(rng.standard_normal((k, dim)), 3, axis=0)[:k]
    elif kind == "one point":
        dense = np.tile(rng.standard_normal(dim), (k, 1))
    elif kind == "closed":
        th = np.linspace(0.0, 2 * np.pi, k)
        dense = np.c_[np.cos(th), np.sin(th), np.zeros((k, dim - 2))]
    else:
        dense = np.cumsum(rng.standard_normal((k, dim)) * 1e-3, axis=0)
    # random points, points on samples and halfway between neighbours (ties), one not finite
    j = min(5, k - 1)
    P = np.r_[rng.standard_normal((m, dim)), dense[rng.integers(0, k, 5)], 0.5 * (dense[:j] + dense[1:j + 1])]
    P[0, 0] = np.nan if seed % 3 == 0 else P[0, 0]
    np.testing.assert_array_equal(nearest_samples(P, dense), _every_sample(P, dense))
    # points in any memory layout are taken as float64 rows: the same index
    np.testing.assert_array_equal(nearest_samples(np.asfortranarray(P), dense), nearest_samples(P, dense))


def test_closest_parameters_on_a_closed_curve_start_at_the_first_end() -> None:
    """A full circle's first and last samples are the same point: a point nearest to both starts at
    the first (as comparing every sample picks it), on a trace long enough for the k-d tree."""
    w = np.sqrt(0.5)
    circle = BSplineCurve(2, [0, 0, 0, 1, 1, 2, 2, 3, 3, 4, 4, 4],
                          [[1, 0], [1, 1], [0, 1], [-1, 1], [-1, 0], [-1, -1], [0, -1], [1, -1], [1, 0]],
                          [1, w, 1, w, 1, w, 1, w, 1])
    th = np.linspace(-0.3, 0.3, 2000)
    P = 1.5 * np.c_[np.cos(th), np.sin(th)]
    t, d = closest_parameters(circle, P, iterations=0)
    grid = np.linspace(0.0, 4.0, 401)
    np.testing.assert_array_equal(t, grid[_every_sample(P, circle.evaluate(grid))])
    assert t[1000] == 0.0 and np.allclose(d, 0.5, atol=1e-3)  # a sample's distance (no Newton step)


def test_ties_the_tree_cannot_see_and_distances_that_overflow() -> None:
    """Where the k-d tree's own arithmetic cannot order the candidates: shells of samples at one
    distance from the origin up to round-off (the permutations of random coordinates, shuffled:
    sums of the same squares in other orders, which the tree and the scoring round differently),
    samples that repeat one point at shuffled indices, and squared distances that overflow (the
    tree then finds fewer than four neighbours). Each point's index is the one comparing every
    sample gives."""
    import itertools

    rng = np.random.default_rng(7)
    for _ in range(60):
        d = int(rng.integers(3, 5))
        shell = np.array(list(itertools.permutations(rng.uniform(0.1, 3.0, d))))
        dense = np.r_[shell[rng.permutation(len(shell))], rng.uniform(5.0, 9.0, (401 - len(shell), d))]
        P = np.zeros((60, d))
        np.testing.assert_array_equal(nearest_samples(P, dense), _every_sample(P, dense))
    same = rng.permutation(np.r_[np.tile([[5.0, -1.0, 2.0]], (9, 1)), rng.standard_normal((400, 3)) * 30 + 60])
    P = np.tile([[5.0, -1.0, 2.1]], (100, 1))
    np.testing.assert_array_equal(nearest_samples(P, same), _every_sample(P, same))
    far = np.r_[[[0.0, 0.0], [1.0, 0.0]], np.tile([[2e154, 0.0]], (399, 1))]
    P = np.zeros((100, 2))
    np.testing.assert_array_equal(nearest_samples(P, far), np.zeros(100, dtype=np.intp))
