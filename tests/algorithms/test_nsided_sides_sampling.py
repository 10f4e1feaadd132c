"""``side_from_normals`` on a side curve whose knots are denser than the neighbour's normal samples
(algorithms/topology/nsided_sides.py, ``_sampled_knots``).

A side curve re-fitted by arc length (refill's ``_even_speed``) can carry far more knots than the
fit has samples of the neighbour's normal: on the lens's face 2, side 0 had 60 spans (1/256 wide,
1/512 at the end) for 96 samples, 8 spans held none and the least squares had rank 58 of 63.
``lstsq``'s minimum-norm field then sagged between the samples: 0.003 deg from the neighbour's
plane at every sample, 2.66 deg between them (the fill followed the field exactly and folded,
20 folded cells). The field's knots now keep only spans holding at least two samples.

Here: a straight side with spans of 1/64, then 1/256 from s = 0.75 and 1/512 at the end (112 spans,
as an arc-length refit leaves them), the neighbour's plane turning about the side by 20 s^2 degrees
(smooth), 41 uniform samples plus the end clusters refill uses. The field is judged on 4001 points
between the samples. Bound: 0.05 deg, five times the fit target ``FILL_FIT_ANGLE`` (0.01 deg, met
at the samples); measured 1e-6 deg (24 spans kept); with every curve knot kept (before) 0.47 deg,
1.42 deg for a turn of 60 s^2 degrees.
"""

from __future__ import annotations

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from occsurf.algorithms import tolerances
from occsurf.algorithms.kernel.basis import basis_matrix, greville
from occsurf.algorithms.kernel.curve import BSplineCurve
from occsurf.algorithms.topology.nsided_sides import _sampled_knots, plane_angle, side_from_normals
from tests.algorithms.strategies import test_settings


def _dense_line(length: float = 13.5) -> BSplineCurve:
    inner = np.r_[np.arange(1, 48) / 64, np.arange(193, 256) / 256, 511 / 512]  # 1/64, then 1/256, 1/512 at the end
    knots = np.r_[[0.0] * 4, inner, [1.0] * 4]
    g = greville(knots, 3)
    poles = np.c_[length * g, np.zeros_like(g), np.zeros_like(g)]  # x = length * s exactly (linear precision)
    return BSplineCurve(3, knots, poles)


def _normals(s: np.ndarray, turn_deg: float = 20.0) -> np.ndarray:
    """The neighbour's normal: +z turned about the side (x axis) by ``turn_deg * s^2``."""
    t = np.radians(turn_deg) * s ** 2
    return np.c_[np.zeros_like(s), -np.sin(t), np.cos(t)]


def _samples() -> np.ndarray:
    ends = np.geomspace(1e-4, 5e-2, 8)
    return np.unique(np.r_[np.linspace(0.0, 1.0, 41), ends, 1.0 - ends])


def test_field_between_sparse_samples_follows_the_neighbour():
    curve = _dense_line()
    s = _samples()
    fit = side_from_normals(curve, s, _normals(s))
    assert fit.angle <= tolerances.FILL_FIT_ANGLE
    u = np.linspace(0.0, 1.0, 4001)
    T = curve.derivatives(u, 1)[:, 1]
    between = plane_angle(_normals(u), T, fit.side.cross.evaluate(u)[:, :3])
    assert between.max() <= 0.05, f"field {between.max():.3f} deg off the neighbour between samples"


def test_sampled_knots_give_full_rank():
    curve = _dense_line()
    s = _samples()
    inner = np.unique(curve.knots[4:-4])
    kept = _sampled_knots(inner, s, 0.0, 1.0)
    knots = np.r_[[0.0] * 4, kept, [1.0] * 4]
    A = basis_matrix(knots, 3, len(knots) - 4, s)[0]
    assert np.linalg.matrix_rank(A) == A.shape[1]
    full = np.r_[[0.0] * 4, inner, [1.0] * 4]
    assert np.linalg.matrix_rank(basis_matrix(full, 3, len(full) - 4, s)[0]) < len(full) - 4  # the case exists


@test_settings(40)
@given(st.lists(st.floats(0.001, 0.999), min_size=0, max_size=40), st.lists(st.floats(0.0, 1.0), min_size=4,
                                                                           max_size=60), st.integers(1, 4))
def test_sampled_knots_every_span_holds_enough(inner, s, least):
    inner, s = np.unique(inner), np.asarray(s)
    kept = _sampled_knots(inner, s, 0.0, 1.0, least)
    assert np.isin(kept, inner).all() and np.all(np.diff(kept) > 0)
    breaks = np.r_[0.0, kept, 1.0]
    counts = np.bincount(np.clip(np.searchsorted(breaks, s, side="right") - 1, 0, len(breaks) - 2),
                         minlength=len(breaks) - 1)
    if len(kept):
        assert counts.min() >= least
    full = np.r_[0.0, inner, 1.0]  # knots whose spans all hold enough samples are all kept
    per = np.bincount(np.clip(np.searchsorted(full, s, side="right") - 1, 0, len(full) - 2), minlength=len(full) - 1)
    if per.min() >= least:
        np.testing.assert_array_equal(kept, inner)
