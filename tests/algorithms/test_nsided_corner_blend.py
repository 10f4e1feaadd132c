"""Tests of the corner treatment of fitted hole sides (``blend_normals``, algorithms/topology/nsided_sides.py).

Where a hole corner's plane (spanned by the two side tangents: the only plane a fill can have there)
differs from a neighbour's tangent plane, the neighbour's normal field is turned into the corner
plane near that corner. The G1 error this leaves is the corner's incompatibility and no more: the
field must keep its own turning (a curved neighbour's normal turns along the side). Blending the
field with the constant corner normal moved it by its own turn over the blend span instead (0.92 deg
on the bearing's face 172 for corners 0.02 deg apart; G1 0.56 deg against OCC's 0.12).

Tolerances: the blend is a rotation per sample, so the end normals are met and the field beyond the
span is untouched to round-off (1e-12); the largest deviation from the field is the larger of the
two end angles, bound with a relative 1e-9 (arctan2 and the Rodrigues formula in float64).
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from occsurf.algorithms.errors import InvalidGeometryError
from occsurf.algorithms.topology.nsided_sides import blend_normals
from tests.algorithms.strategies import test_settings


def _deg(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Angles (degrees) between rows (or a row and rows)."""
    a, b = np.broadcast_arrays(np.atleast_2d(a), np.atleast_2d(b))
    return np.degrees(np.arctan2(np.linalg.norm(np.cross(a, b), axis=1), np.einsum("ij,ij->i", a, b)))


def _rotate(v: np.ndarray, axis: np.ndarray, deg: float) -> np.ndarray:
    k = np.asarray(axis, float) / np.linalg.norm(axis)
    t = np.radians(deg)
    return v * np.cos(t) + np.cross(k, v) * np.sin(t) + k * (k @ v) * (1 - np.cos(t))


def _turning_field(s: np.ndarray, turn: float, axis=(0.0, 1.0, 0.0), n0=(0.0, 0.0, 1.0)) -> np.ndarray:
    """A neighbour's normals along a side: ``n0`` turned about ``axis`` by ``turn * s`` radians
    (a cylinder crossed obliquely by the side, for instance)."""
    k = np.asarray(axis, float) / np.linalg.norm(axis)
    n0 = np.asarray(n0, float)
    t = turn * s[:, None]
    return n0 * np.cos(t) + np.cross(k, n0) * np.sin(t) + np.outer(np.ones_like(s), k * (k @ n0)) * (1 - np.cos(t))


def test_a_turning_field_moves_by_the_corner_angle_only() -> None:
    s = np.linspace(0.0, 1.0, 401)
    N = _turning_field(s, 1.0)  # 57 deg over the side: 5.7 deg over a blend span of 0.1
    start = _rotate(N[0], [1.0, 0.0, 0.0], 0.02)  # the corner plane 0.02 deg off the neighbour's
    end = _rotate(N[-1], [0.3, 0.0, 1.0], 0.05)
    out = blend_normals(s, N, start, end, 0.1)
    dev = _deg(out, N)
    assert dev.max() <= 0.05 * (1 + 1e-9)  # the old constant blend: 2.9 deg
    assert dev[s < 0.5].max() <= 0.02 * (1 + 1e-9)  # each corner's angle stays at its own end
    np.testing.assert_allclose(out[0], start, atol=1e-12)
    np.testing.assert_allclose(out[-1], end / np.linalg.norm(end), atol=1e-12)
    inside = (s >= 0.1) & (s <= 0.9)
    np.testing.assert_allclose(out[inside], N[inside], atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(out, axis=1), 1.0, atol=1e-12)


def test_end_normals_are_sign_free_and_an_end_already_met_is_left() -> None:
    s = np.linspace(0.0, 1.0, 101)
    N = _turning_field(s, 0.7)
    start = _rotate(N[0], [1.0, 0.0, 0.0], 0.3)
    a = blend_normals(s, N, start, N[-1], 0.2)
    b = blend_normals(s, N, -start, -3.0 * N[-1], 0.2)  # any length, either sign
    np.testing.assert_allclose(a, b, atol=1e-14)
    np.testing.assert_allclose(a[s > 0.2], N[s > 0.2], atol=1e-14)  # the end needing nothing: untouched
    with pytest.raises(InvalidGeometryError, match="span"):
        blend_normals(s, N, start, N[-1], 0.0)


@test_settings(max_examples=40)
@given(turn=st.floats(0.0, 2.0), ax=st.tuples(*[st.floats(-1, 1)] * 3), a0=st.floats(0.0, 30.0),
       a1=st.floats(0.0, 30.0), r0=st.tuples(*[st.floats(-1, 1)] * 3), r1=st.tuples(*[st.floats(-1, 1)] * 3),
       span=st.floats(0.01, 0.5))
def test_blend_moves_the_field_by_at_most_the_larger_end_angle(turn, ax, a0, a1, r0, r1, span) -> None:
    s = np.linspace(0.0, 1.0, 257)
    axis = np.asarray(ax) if np.linalg.norm(ax) > 1e-3 else np.array([0.0, 1.0, 0.0])
    N = _turning_field(s, turn, axis, n0=np.cross(axis, [0.3, -0.5, 0.8]) + 0.2 * axis)
    N /= np.linalg.norm(N, axis=1, keepdims=True)
    k0 = np.cross(N[0], r0) if np.linalg.norm(np.cross(N[0], r0)) > 1e-3 else np.cross(N[0], [1.0, 0.0, 0.0])
    k1 = np.cross(N[-1], r1) if np.linalg.norm(np.cross(N[-1], r1)) > 1e-3 else np.cross(N[-1], [0.0, 0.0, 1.0])
    start, end = _rotate(N[0], k0 + 1e-300, a0), _rotate(N[-1], k1 + 1e-300, a1)
    out = blend_normals(s, N, start, end, span)
    dev = _deg(out, N)
    assert dev.max() <= max(a0, a1) * (1 + 1e-9) + 1e-9
    assert _deg(out[0], start)[0] <= 1e-9 and _deg(out[-1], end)[0] <= 1e-9
    # smooth: neighbouring samples no farther apart than the field's own step plus the blend's
    step = _deg(out[1:], out[:-1]).max()
    assert step <= np.degrees(turn) / 256 + max(a0, a1) * 1.9 / (span * 256) + 1e-9
