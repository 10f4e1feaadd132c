"""Error paths: every validation rule raises the documented class with a message that starts
with the name of the argument at fault; failed operations leave their object untouched; spline
objects are immutable."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from numpy.testing import assert_array_equal

from occsurf.algorithms import (
    BSplineCurve,
    BSplineSurface,
    InvalidGeometryError,
    OccsurfError,
    ParameterError,
    ToleranceError,
    tolerances,
)
from occsurf.algorithms._validate import check_knots

# A valid cubic: 5 poles, one interior knot.
P = np.array([[0.0, 0.0], [1.0, 2.0], [2.0, -1.0], [3.0, 2.0], [4.0, 0.0]])
T = np.array([0, 0, 0, 0, 0.5, 1, 1, 1, 1], float)
W = np.array([1.0, 2.0, 0.5, 1.0, 1.0])


def curve(**kw):
    args = dict(degree=3, knots=T, control_points=P, weights=None)
    args.update(kw)
    return BSplineCurve(args["degree"], args["knots"], args["control_points"], args["weights"])


K2 = [0, 0, 0, 1, 1, 1]
NET = np.arange(27, dtype=float).reshape(3, 3, 3)


def surface(**kw):
    args = dict(degree=(2, 2), knots=(K2, K2), control_points=NET, weights=None)
    args.update(kw)
    return BSplineSurface(args["degree"], args["knots"], args["control_points"], args["weights"])


def test_hierarchy():
    assert issubclass(InvalidGeometryError, ValueError) and issubclass(InvalidGeometryError, OccsurfError)
    assert issubclass(ParameterError, InvalidGeometryError)
    assert issubclass(ToleranceError, ValueError) and issubclass(ToleranceError, OccsurfError)
    assert not issubclass(ToleranceError, InvalidGeometryError)


def test_valid_reference_objects_construct():
    # The error cases below differ from these in one argument only.
    assert curve().n_poles == 5 and curve(weights=W).is_rational
    assert surface().n_poles == (3, 3)
    assert curve(degree=np.int64(3)).degree == 3  # NumPy integers are integers


# ------------------------------------------------------------------------------------- knots
@pytest.mark.parametrize(
    "knots, match",
    [
        ([0, 0, 0, 0, 0.7, 0.5, 1, 1, 1], r"^knots: must be non-decreasing, but knot 5 = 0.5 < knot 4 = 0.7"),
        ([0, 0, 0, 0, 1, 1, 1, 1], r"^knots: expected 9 values \(poles 5 \+ degree 3 \+ 1\), got 8"),
        ([0, 0, 0, 0, 0.5, 0.5, 1, 1, 1, 1], r"^knots: expected 9 values"),
        ([0, 0, 0, 0, 0, 1, 1, 1, 1], r"^knots: multiplicity of knot 0.0 is 5, more than degree \+ 1 = 4"),
        ([0, 0, 0, 0.5, 0.5, 0.5, 0.5, 0.5, 1], r"^knots: multiplicity of knot 0.5 is 5"),
        ([[0, 0, 0, 0, 0.5, 1, 1, 1, 1]], r"^knots: expected a 1-D array"),
        ("abc", r"^knots: expected an array of real numbers"),
    ],
)
def test_bad_knots(knots, match):
    with pytest.raises(InvalidGeometryError, match=match):
        curve(knots=knots)



def _knots_reference(t: np.ndarray, degree: int) -> str | None:
    """check_knots' order and multiplicity rules as first written (np.diff, np.unique's counts)."""
    d = np.diff(t)
    if np.any(d < 0):
        i = int(np.argmax(d < 0))
        return f"must be non-decreasing, but knot {i + 1} = {float(t[i + 1])!r} < knot {i} = {float(t[i])!r}"
    vals, counts = np.unique(t, return_counts=True)
    if np.any(counts > degree + 1):
        i = int(np.argmax(counts))
        return f"multiplicity of knot {float(vals[i])!r} is {counts[i]}, more than degree + 1 = {degree + 1}"
    return None


@given(degree=st.integers(1, 6), runs=st.lists(st.tuples(st.sampled_from([-1.0, -0.0, 0.0, 0.25, 0.5, 1.0, 2.0]),
                                                          st.integers(1, 8)), min_size=1, max_size=8),
       ordered=st.booleans())
@settings(max_examples=300, deadline=None)
def test_knot_order_and_multiplicity_rules_as_first_written(degree, runs, ordered):
    """The order test compares neighbours and the multiplicity test ``t[i] == t[i + p + 1]`` (no sort):
    on knot vectors of any runs (unsorted ones, signed zeros), the same verdict and message as
    np.diff and np.unique's counts give."""
    if ordered:  # the runs in increasing order: valid vectors, or too many repeats of one knot
        runs = sorted(runs, key=lambda r: r[0])
    t = np.array([v for v, k in runs for _ in range(k)])
    assume(t.size >= 2 * degree + 2)  # at least degree + 1 poles, as every caller has
    want = _knots_reference(t, degree)
    try:
        check_knots(t, degree, t.size - degree - 1)
        got = None
    except InvalidGeometryError as err:
        got = str(err).removeprefix("knots: ")
    if want is None:  # the later checks (length, empty domain) may still refuse
        assert got is None or not got.startswith(("must be non-decreasing", "multiplicity"))
    else:
        assert got == want


def test_empty_domain():
    # Degree 2, 3 poles: domain [t_2, t_3] = [1, 1].
    with pytest.raises(InvalidGeometryError, match=r"^knots: the domain \[knot\[2\], knot\[3\]\] = \[1.0, 1.0\] is empty"):
        BSplineCurve(2, [0, 0.5, 1, 1, 1.5, 2], [[0, 0], [1, 1], [2, 0]])


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
@pytest.mark.parametrize("field", ["knots", "control_points", "weights"])
def test_non_finite_values(field, bad):
    arrays = {"knots": T.copy(), "control_points": P.copy(), "weights": W.copy()}
    arrays[field].flat[4] = bad
    with pytest.raises(InvalidGeometryError, match=rf"^{field}: expected finite values"):
        curve(**arrays)


@pytest.mark.parametrize("bad", [np.nan, np.inf])
@pytest.mark.parametrize("field", ["knots", "control_points", "weights"])
def test_non_finite_values_surface(field, bad):
    args = {"knots": ([0, 0, 0, 1, 1, 1], [0, 0, 0, bad, 1, 1]) if field == "knots" else (K2, K2),
            "control_points": NET.copy(), "weights": np.ones((3, 3))}
    if field != "knots":
        args[field].flat[4] = bad
    match = r"^knots\[1\] \(V\): expected finite" if field == "knots" else rf"^{field}: expected finite"
    with pytest.raises(InvalidGeometryError, match=match):
        surface(**args)


# ----------------------------------------------------------------------------------- weights
@pytest.mark.parametrize("w, match", [
    ([1, 1, 0, 1, 1], r"^weights: weights must be > 0, got 0.0 at index \(2,\)"),
    ([1, 1, 1, -2, 1], r"^weights: weights must be > 0, got -2.0 at index \(3,\)"),
    ([1, 1, 1, 1], r"^weights: expected shape \(5,\) \(one weight per control point\), got \(4,\)"),
    ([[1, 1, 1, 1, 1]], r"^weights: expected shape \(5,\)"),
])
def test_bad_weights(w, match):
    with pytest.raises(InvalidGeometryError, match=match):
        curve(weights=w)


def test_bad_weights_surface():
    with pytest.raises(InvalidGeometryError, match=r"^weights: expected shape \(3, 3\)"):
        surface(weights=np.ones((3, 2)))
    with pytest.raises(InvalidGeometryError, match=r"^weights: weights must be > 0"):
        surface(weights=np.zeros((3, 3)))


# ------------------------------------------------------------------------- degree and shape
@pytest.mark.parametrize("degree", [0, -1, 26, 100])
def test_degree_out_of_range(degree):
    with pytest.raises(InvalidGeometryError, match=rf"^degree: expected 1 <= degree <= 25.*got {degree}"):
        curve(degree=degree)


@pytest.mark.parametrize("degree", [3.0, 2.5, "3", None, True, False, np.bool_(True)])
def test_degree_not_an_integer(degree):
    with pytest.raises(InvalidGeometryError, match=r"^degree: expected an integer from 1 to 25"):
        curve(degree=degree)


def test_degree_25_is_accepted_and_26_is_not():
    n = 26
    c = BSplineCurve(25, [0] * 26 + [1] * 26, np.zeros((n, 2)))
    assert c.degree == 25
    with pytest.raises(InvalidGeometryError, match=r"^times: degree 25 \+ 1 exceeds the maximum 25"):
        c.elevate_degree()


@pytest.mark.parametrize("cp, match", [
    (np.zeros(5), r"^control_points: expected shape \(n, d\), got \(5,\)"),
    (np.zeros((5, 2, 1)), r"^control_points: expected shape \(n, d\), got \(5, 2, 1\)"),
    (np.zeros((5, 0)), r"^control_points: expected shape \(n, d\), got \(5, 0\)"),
    ("abc", r"^control_points: expected an array of real numbers"),
])
def test_control_point_shape(cp, match):
    with pytest.raises(InvalidGeometryError, match=match):
        curve(control_points=cp)


def test_too_few_poles():
    with pytest.raises(InvalidGeometryError, match=r"^control_points: a degree-3 curve needs at least 4 poles, got 3"):
        BSplineCurve(3, [0, 0, 0, 0.5, 1, 1, 1], P[:3])
    with pytest.raises(InvalidGeometryError, match=r"^control_points: degree \(2, 3\) needs at least \(3, 4\) poles"):
        BSplineSurface((2, 3), (K2, [0, 0, 0, 0, 1, 1, 1]), NET)


@pytest.mark.parametrize("kw, match", [
    (dict(degree=2), r"^degree: expected a pair \(p, q\)"),
    (dict(degree=(2, 0)), r"^degree\[1\] \(v\): expected 1 <= degree <= 25"),
    (dict(degree=(26, 2)), r"^degree\[0\] \(u\): expected 1 <= degree <= 25"),
    (dict(degree=(2.0, 2)), r"^degree\[0\] \(u\): expected an integer"),
    (dict(degree=(2, True)), r"^degree\[1\] \(v\): expected an integer"),
    (dict(knots=(K2,)), r"^knots: expected a pair \(U, V\)"),
    (dict(knots=(K2, [0, 0, 0, 1, 1])), r"^knots\[1\] \(V\): expected 6 values"),
    (dict(knots=([0, 0, 1, 0, 1, 1], K2)), r"^knots\[0\] \(U\): must be non-decreasing"),
    (dict(control_points=NET[0]), r"^control_points: expected shape \(n_u, n_v, d\)"),
])
def test_bad_surface_arguments(kw, match):
    with pytest.raises(InvalidGeometryError, match=match):
        surface(**kw)


# -------------------------------------------------------------------------------- parameters
@pytest.mark.parametrize("u", [np.nan, np.inf, -0.01, 1.01, [0.5, 2.0], [[0.2], [np.nan]]])
@pytest.mark.parametrize("method", ["evaluate", "derivatives"])
def test_parameters_outside_the_domain_or_not_finite(method, u):
    with pytest.raises(ParameterError, match=r"^u: "):
        getattr(curve(), method)(u)


def test_parameter_a_hair_outside_is_snapped_onto_the_domain():
    c = curve()
    eps = 0.1 * tolerances.PARAMETER
    assert_array_equal(c.evaluate([-eps, 1 + eps]), c.evaluate([0.0, 1.0]))


def test_surface_parameters():
    s = surface()
    with pytest.raises(ParameterError, match=r"^v: parameter 2.0 is outside the domain"):
        s.evaluate(0.5, 2.0)
    with pytest.raises(ParameterError, match=r"^u: parameters must be finite"):
        s.derivatives(np.nan, 0.5)
    with pytest.raises(ParameterError, match=r"^u, v: shapes \(2,\) and \(3,\) do not broadcast"):
        s.evaluate([0.1, 0.2], [0.1, 0.2, 0.3])
    with pytest.raises(ParameterError, match=r"^us: "):
        s.evaluate_grid([0.5, 1.5], [0.5])
    with pytest.raises(InvalidGeometryError, match=r"^direction: expected 'u' or 'v', got 'w'"):
        s.insert_knot(0.5, direction="w")


@pytest.mark.parametrize("call, exc, match", [
    (lambda c: c.insert_knot(0.0), ParameterError, r"^knot: 0.0 must lie strictly inside the domain"),
    (lambda c: c.insert_knot(1.0), ParameterError, r"^knot: 1.0 must lie strictly inside"),
    (lambda c: c.insert_knot(np.nan), ParameterError, r"^knot: parameters must be finite"),
    (lambda c: c.split(1.0), ParameterError, r"^param: 1.0 must lie strictly inside"),
    (lambda c: c.refine([0.2, 1.5]), ParameterError, r"^knots: .*must lie strictly inside"),
    (lambda c: c.refine([np.nan]), InvalidGeometryError, r"^knots: expected finite values"),
    (lambda c: c.blossom([0.5, 0.5, 0.5], span=2.0), ParameterError, r"^span: parameter 2.0 is outside"),
    (lambda c: c.blossom([0.5, 0.5]), InvalidGeometryError, r"^args: expected last axis of length degree = 3"),
    (lambda c: c.blossom([0.5, np.nan, 0.5]), InvalidGeometryError, r"^args: expected finite values"),
    (lambda c: c.derivatives(0.5, -1), InvalidGeometryError, r"^order: expected a non-negative integer, got -1"),
    (lambda c: c.derivatives(0.5, 1.0), InvalidGeometryError, r"^order: expected a non-negative integer"),
    (lambda c: c.insert_knot(0.3, 0), InvalidGeometryError, r"^times: expected a positive integer, got 0"),
    (lambda c: c.insert_knot(0.3, True), InvalidGeometryError, r"^times: expected a positive integer, got True"),
    (lambda c: c.reparametrize(1.0, 0.0), ParameterError, r"^reparametrize: expected finite start < end"),
    (lambda c: c.reparametrize(0.0, np.inf), ParameterError, r"^reparametrize: expected finite start < end"),
    (lambda c: c.segment(0.6, 0.6), ParameterError, r"^segment: expected u0 < u1"),
    (lambda c: c.transform(np.eye(3)), InvalidGeometryError, r"^matrix: expected shape \(2, 2\), got \(3, 3\)"),
    (lambda c: c.transform(np.eye(2), [np.nan, 0]), InvalidGeometryError, r"^translation: expected finite"),
])
def test_operation_arguments(call, exc, match):
    c = curve()
    with pytest.raises(exc, match=match):
        call(c)


# ------------------------------------------------------------------------- knot multiplicity
def test_insert_beyond_multiplicity():
    c = curve()
    with pytest.raises(InvalidGeometryError, match=r"^times: knot 0.5 has multiplicity 1; inserting 3 more exceeds the degree 3"):
        c.insert_knot(0.5, 3)
    c2 = c.insert_knot(0.5, 2)  # up to the degree is fine
    with pytest.raises(InvalidGeometryError, match=r"^times: knot 0.5 has multiplicity 3"):
        c2.insert_knot(0.5)
    with pytest.raises(InvalidGeometryError, match=r"^knots: knot .*would get multiplicity 5, above degree \+ 1 = 4"):
        c.refine([0.5] * 4)
    with pytest.raises(InvalidGeometryError, match=r"^times: v-knot 0.5 has multiplicity 0; 3 more exceeds"):
        surface().insert_knot(0.5, 3, direction="v")
    with pytest.raises(InvalidGeometryError, match=r"^knots: u-knot 0.25 would get multiplicity 5 > degree \+ 1"):
        surface().refine([0.25] * 5, direction="u")
    c.refine([0.25] * 3)  # multiplicity 3, at the limit of a cubic's interior knots: fine


def test_elevate_above_25():
    with pytest.raises(InvalidGeometryError, match=r"^times: degree 3 \+ 23 exceeds the maximum 25"):
        curve().elevate_degree(23)
    with pytest.raises(InvalidGeometryError, match=r"^times: degree 2 \+ 24 exceeds the maximum 25"):
        surface().elevate_degree(24, direction="v")
    with pytest.raises(InvalidGeometryError, match=r"^times: expected a positive integer"):
        curve().elevate_degree(0)


# ------------------------------------------------------------------------------ knot removal
def corner() -> BSplineCurve:
    """A polyline with a real corner at u = 1: the knot is not removable."""
    return BSplineCurve(1, [0, 0, 1, 2, 2], [[0.0, 0.0], [1.0, 1.0], [2.0, 0.0]])


def test_non_removable_knot_raises_and_leaves_the_curve_unchanged():
    c = corner()
    before = (c.knots.copy(), c.control_points.copy())
    with pytest.raises(ToleranceError, match=r"^remove_knot: knot 1.0 \(x1\) cannot be removed within tol=1e-09; "
                                             r"the curve would move by up to 0.667"):
        c.remove_knot(1.0)
    assert_array_equal(c.knots, before[0])
    assert_array_equal(c.control_points, before[1])
    assert c.weights is None
    # The least-squares line through the three poles moves the middle one by 2/3.
    assert c.remove_knot(1.0, tol=0.7).n_poles == 2
    with tolerances.override(KNOT_REMOVAL=0.7):
        assert c.remove_knot(1.0).n_poles == 2
    with pytest.raises(ToleranceError):
        c.remove_knot(1.0)  # the override ended with its block


def test_non_removable_knot_surface():
    net = np.zeros((3, 2, 3))
    net[:, 0, 0] = net[:, 1, 0] = [0, 1, 2]
    net[:, 1, 1] = 1.0
    net[1, :, 2] = 1.0  # a ridge along u = 1
    s = BSplineSurface((1, 1), ([0, 0, 1, 2, 2], [0, 0, 1, 1]), net)
    before = s.control_points.copy()
    with pytest.raises(ToleranceError, match=r"^remove_knot: u-knot 1.0 \(x1\) cannot be removed"):
        s.remove_knot(1.0, direction="u")
    assert_array_equal(s.control_points, before)


@pytest.mark.parametrize("call, match", [
    (lambda c: c.remove_knot(0.3), r"^knot: 0.3 is a knot of multiplicity 0, cannot remove it 1 times"),
    (lambda c: c.remove_knot(0.5, 2), r"^knot: 0.5 is a knot of multiplicity 1, cannot remove it 2 times"),
    (lambda c: c.remove_knot(0.0), r"^knot: 0.0 must lie strictly inside"),
])
def test_remove_knot_arguments(call, match):
    with pytest.raises(InvalidGeometryError, match=match):
        call(curve())


# --------------------------------------------------------------------------- (de)serialisation
@pytest.mark.parametrize("data, match", [
    ({"type": "BSplineSurface"}, r"^from_dict: expected a dict with type 'BSplineCurve'"),
    ([1, 2], r"^from_dict: expected a dict with type 'BSplineCurve', got list"),
    ({"type": "BSplineCurve", "version": 99}, r"^from_dict: format version 99 is newer than 1"),
    ({"type": "BSplineCurve", "degree": 3, "knots": list(T)}, r"^from_dict: missing key 'control_points'"),
    ({"type": "BSplineCurve", "degree": 3, "knots": list(T), "control_points": P.tolist(), "weights": [1, 1]},
     r"^weights: expected shape \(5,\)"),
])
def test_from_dict_errors(data, match):
    with pytest.raises(InvalidGeometryError, match=match):
        BSplineCurve.from_dict(data)


def test_surface_from_dict_errors():
    with pytest.raises(InvalidGeometryError, match=r"^from_dict: expected a dict with type 'BSplineSurface'"):
        BSplineSurface.from_dict(curve().to_dict())
    d = surface().to_dict()
    d["knots"][0][2] = 5.0
    with pytest.raises(InvalidGeometryError, match=r"^knots\[0\] \(U\): must be non-decreasing"):
        BSplineSurface.from_dict(d)


# -------------------------------------------------------------------------------- immutability
@pytest.mark.parametrize("make", [lambda: curve(weights=W), lambda: surface(weights=np.ones((3, 3)))])
def test_objects_are_immutable(make):
    obj = make()
    for name in ("degree", "knots", "control_points", "weights"):
        with pytest.raises(dataclasses.FrozenInstanceError):
            setattr(obj, name, None)
    arrays = [obj.control_points, obj.weights, obj.homogeneous_points]
    arrays += list(obj.knots) if isinstance(obj.knots, tuple) else [obj.knots]
    for a in arrays:
        assert not a.flags.writeable
        with pytest.raises(ValueError, match="read-only"):
            a.flat[0] = 42.0


def test_constructor_copies_its_inputs():
    knots, cp, w = T.copy(), P.copy(), W.copy()
    c = curve(knots=knots, control_points=cp, weights=w)
    ref = c.evaluate([0.25, 0.75])
    knots[:] = 0
    cp[:] = 7.0
    w[:] = 3.0
    assert_array_equal(c.evaluate([0.25, 0.75]), ref)
    assert knots.flags.writeable and cp.flags.writeable  # the caller's arrays are not frozen


def test_operations_return_new_objects_and_leave_the_original():
    c = curve(weights=W)
    snapshot = c.to_dict()
    results = [c.insert_knot(0.25), c.refine([0.1, 0.9]), c.elevate_degree(), *c.split(0.3),
               c.reverse(), c.reparametrize(2, 3), c.transform(2 * np.eye(2)), c.segment(0.1, 0.9),
               c.insert_knot(0.5).remove_knot(0.5), *c.to_bezier()]
    assert all(r is not c for r in results)
    assert c.clamp() == c  # already clamped: the same curve (possibly the same object: it is frozen)
    assert c.to_dict() == snapshot
    s = surface(weights=np.ones((3, 3)))
    snap = s.to_dict()
    for op in (lambda x: x.insert_knot(0.5, direction="v"), lambda x: x.elevate_degree(direction="u"), lambda x: x.swap_uv(),
               lambda x: x.reverse(direction="v"), lambda x: x.split(0.5, direction="u")[0]):
        assert op(s) is not s
    assert s.to_dict() == snap
