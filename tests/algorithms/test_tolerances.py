"""The tolerances of the geometry, manipulation, hierarchical and fitting families and of the numba
switch are read from :mod:`occsurf.algorithms.tolerances` at call time.

Each test overrides one value with ``tolerances.override`` and checks that the behaviour changes
accordingly (and is back to normal after the block); the frozen module copies these values used
to have are gone. The overrides live in a ContextVar: two threads holding different values at
the same time each see their own.
"""

from __future__ import annotations

import ast
import threading
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

import occsurf.algorithms as A
from occsurf.algorithms import BSplineCurve, BSplineSurface, InvalidGeometryError, ToleranceError, tolerances
from occsurf.algorithms.fitting.interpolation import interpolate_curve
from occsurf.algorithms.geometry import Frame, Point
from occsurf.algorithms.geometry.differential import arc_length, curve_frenet
from occsurf.algorithms.geometry.surface_differential import is_umbilic, surface_curvatures
from occsurf.algorithms.hierarchical.offsets import frames_from_partials, surface_frames
from occsurf.algorithms.manipulation import (
    ConstraintError,
    ConvergenceError,
    Curvature,
    Position,
    constrain,
    drag_surface_point,
)
from occsurf.algorithms.manipulation.linalg import ConstraintFactor
from occsurf.algorithms.manipulation.sparse_linalg import sparse_lstsq

ALGORITHMS = Path(A.__file__).parent

# A degree-5 Bézier arc whose speed varies wildly: one 16-point rule per half is far from the
# default arc-length tolerance, so the adaptive rule needs several halvings.
HARD = BSplineCurve(5, [0] * 6 + [1] * 6, [[0, 0], [10, -8], [-9, 12], [11, 9], [-7, -10], [1, 0]])


def bump(height: float = 0.5) -> BSplineSurface:
    g = np.linspace(0, 3, 4)
    net = np.concatenate([np.stack(np.meshgrid(g, g, indexing="ij"), -1), np.zeros((4, 4, 1))], -1)
    net[1:3, 1:3, 2] = height
    U = [0, 0, 0, 0, 1, 1, 1, 1]
    return BSplineSurface((3, 3), (U, U), net)


# ---------------------------------------------------------------------------------------- registry
REMOVED = {
    "geometry/differential.py": ["CURVATURE_ZERO", "NORMAL_ZERO", "ARC_LENGTH", "UMBILIC", "_MAX_LEVELS"],
    "geometry/surface_differential.py": ["CURVATURE_ZERO", "NORMAL_ZERO", "ARC_LENGTH", "UMBILIC", "_MAX_LEVELS"],
    "geometry/affine.py": ["MAX_CONDITION"],
    "manipulation/linalg.py": ["RANK_RTOL", "CONSISTENCY_RTOL", "SPARSE_TOL"],
    "manipulation/sparse_linalg.py": ["RANK_RTOL", "CONSISTENCY_RTOL", "SPARSE_TOL"],
    "manipulation/linalg_args.py": ["RANK_RTOL", "CONSISTENCY_RTOL", "SPARSE_TOL"],
    "manipulation/curves.py": ["NEWTON_TOL", "MAX_ITERATIONS", "NEWTON_STEPS", "MIN_CONTINUATION_STEP", "KKT_RTOL",
                               "LINEAR_CHECK_RTOL"],
    "manipulation/curve_solver.py": ["NEWTON_TOL", "MAX_ITERATIONS", "NEWTON_STEPS", "MIN_CONTINUATION_STEP",
                                     "KKT_RTOL", "LINEAR_CHECK_RTOL"],
    "manipulation/surfaces.py": ["LINEAR_CHECK_RTOL"],
    "hierarchical/offsets.py": ["FRAME_DEGENERACY", "FRAME_NUDGE"],
    "hierarchical/surface.py": ["EDIT_POINT_RTOL", "EDIT_POINT_MAX_ITER"],
    "fitting/interpolation.py": ["SCHOENBERG_WHITNEY"],
    "_numba_kernels.py": ["MIN_POINTS"],
}


@pytest.mark.parametrize("path", sorted(REMOVED))
def test_no_frozen_copies_of_tolerances(path):
    """No module constant shadows a registry value, and nothing imports a value by name (which
    would freeze it): tolerances are read as ``tolerances.NAME`` at call time."""
    tree = ast.parse((ALGORITHMS / path).read_text())
    assigned = {t.id for node in tree.body if isinstance(node, (ast.Assign, ast.AnnAssign))
                for t in (node.targets if isinstance(node, ast.Assign) else [node.target]) if isinstance(t, ast.Name)}
    assert not assigned & set(REMOVED[path])
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module and node.module.endswith("tolerances"):
            pytest.fail(f"{path}: 'from {node.module} import ...' freezes the values; use tolerances.NAME")


def test_every_renamed_name_is_in_the_registry():
    names = {"CURVATURE_ZERO", "NORMAL_ZERO", "ARC_LENGTH", "ARC_LENGTH_MAX_LEVELS", "UMBILIC", "MAX_CONDITION",
             "RANK_RTOL", "CONSISTENCY_RTOL", "SPARSE_TOL", "NEWTON_TOL", "DRAG_MAX_ITERATIONS", "DRAG_NEWTON_STEPS",
             "MIN_CONTINUATION_STEP", "KKT_RTOL", "LINEAR_CHECK_RTOL", "FRAME_DEGENERACY", "FRAME_NUDGE",
             "EDIT_POINT_RTOL", "EDIT_POINT_MAX_ITER", "SCHOENBERG_WHITNEY", "NUMBA_MIN_POINTS"}
    assert names <= set(tolerances.defaults())


# ---------------------------------------------------------------------------------------- geometry
def test_arc_length_max_levels_is_read_at_call_time():
    ref = arc_length(HARD, 0.0, 1.0)
    with tolerances.override(ARC_LENGTH_MAX_LEVELS=1):
        with pytest.raises(ToleranceError, match="not reached after 1 halvings"):
            arc_length(HARD, 0.0, 1.0)
        # A loose default tolerance is met within the one level allowed.
        with tolerances.override(ARC_LENGTH=1e-1):
            loose = arc_length(HARD, 0.0, 1.0)
    assert abs(loose - ref) <= 1e-1 * np.sum(np.linalg.norm(np.diff(HARD.control_points, axis=0), axis=1))
    assert arc_length(HARD, 0.0, 1.0) == ref  # the block left nothing behind


def test_curvature_zero_is_read_at_call_time():
    u = np.linspace(0.1, 0.9, 5)
    f = curve_frenet(HARD, u)
    assert np.all(f.curvature > 0) and np.all(np.isfinite(f.normal))
    with tolerances.override(CURVATURE_ZERO=1.0):  # |C' x C''| <= |C'| |C''| always: "straight" everywhere
        g = curve_frenet(HARD, u)
    assert np.all(g.curvature == 0) and np.all(np.isnan(g.normal))


def test_normal_zero_and_umbilic_are_read_at_call_time():
    s = bump()
    k = surface_curvatures(s, 0.3, 0.4)
    assert np.isfinite(k.gaussian) and not is_umbilic(s, 0.3, 0.4)
    with tolerances.override(NORMAL_ZERO=1.0):
        assert np.isnan(surface_curvatures(s, 0.3, 0.4).gaussian)
    with tolerances.override(UMBILIC=1e6):
        assert is_umbilic(s, 0.3, 0.4)
    assert is_umbilic(s, 0.3, 0.4, tol=1e6) and not is_umbilic(s, 0.3, 0.4)


def test_max_condition_is_read_at_call_time():
    basis = np.diag([1.0, 1.0, 1e-8])  # condition 1e8
    Frame(Point([0.0, 0.0, 0.0]), basis)
    with tolerances.override(MAX_CONDITION=1e6), pytest.raises(InvalidGeometryError, match=r"basis: .*1e\+06"):
        Frame(Point([0.0, 0.0, 0.0]), basis)


# ---------------------------------------------------------------------------------------- manipulation
def test_rank_and_consistency_tolerances_are_read_at_call_time():
    C = np.array([[1.0, 0.0, 0.0], [1.0, 1e-8, 0.0]])  # the second row is the first to ~1e-8
    assert ConstraintFactor(C).rank == 2
    with tolerances.override(RANK_RTOL=1e-6):
        F = ConstraintFactor(C)
        assert F.rank == 1
        F.solve([1.0, 1.0])  # consistent: the targets agree
        with pytest.raises(ConstraintError):
            F.solve([1.0, 1.0 + 1e-6])  # dependent row, target off by 1e-6 > CONSISTENCY_RTOL
        with tolerances.override(CONSISTENCY_RTOL=1e-3):
            F.solve([1.0, 1.0 + 1e-6])


def test_sparse_tol_is_read_at_call_time():
    rng = np.random.default_rng(2)
    A = sp.random(60, 20, density=0.3, random_state=3, format="csr") + sp.eye(60, 20)
    b = rng.normal(size=60)
    exact = np.linalg.lstsq(A.toarray(), b, rcond=None)[0]
    tight = sparse_lstsq(A, b)
    with tolerances.override(SPARSE_TOL=1e-2):
        loose = sparse_lstsq(A, b)
    assert np.abs(tight - exact).max() < 1e-10
    assert np.abs(loose - exact).max() > 1e3 * np.abs(tight - exact).max()


def _curve() -> BSplineCurve:
    poles = np.c_[np.linspace(0, 6, 7), np.zeros(7), np.zeros(7)]
    return BSplineCurve(3, [0, 0, 0, 0, 0.25, 0.5, 0.75, 1, 1, 1, 1], poles)


def test_newton_tolerances_and_limits_are_read_at_call_time(monkeypatch):
    c = _curve()
    request = [Position(0.3, [1.8, 0.1, 0.0]), Curvature(0.5, [0.0, 0.4, 0.0])]
    constrain(c, request)
    with tolerances.override(NEWTON_TOL=0.0), pytest.raises(InvalidGeometryError, match="tol: expected > 0"):
        constrain(c, request)  # the default tol is the registry's, checked like an explicit one
    with tolerances.override(LINEAR_CHECK_RTOL=0.0), pytest.raises(ConstraintError, match="not met after the solve"):
        constrain(c, request)  # a zero limit refuses every linear residual (round-off is never 0 here)

    import occsurf.algorithms.manipulation.curve_solver as CS
    import occsurf.algorithms.manipulation.curves as MC

    limits, steps, converged = [], [], []
    real_solve, real_newton = CS.solve_problem, CS._newton_kkt

    def newton(*args):
        steps.append(args[-1])
        out = real_newton(*args)
        converged.append(out[0])
        return out

    def solve(prob, tol, max_iter):
        limits.append(max_iter)
        return real_solve(prob, tol, max_iter)

    monkeypatch.setattr(MC, "solve_problem", solve)  # where constrain looks it up
    monkeypatch.setattr(CS, "_newton_kkt", newton)
    with tolerances.override(DRAG_MAX_ITERATIONS=17, DRAG_NEWTON_STEPS=3):
        constrain(c, request)
    assert limits == [17] and max(steps) == 3 and any(converged)
    converged.clear()
    with tolerances.override(KKT_RTOL=0.0):  # no iterate is ever optimal enough
        try:
            constrain(c, request)
        except (ConstraintError, ConvergenceError):
            pass
    assert converged and not any(converged)

    def continuation_stages(min_step: float) -> int:
        steps.clear()
        with tolerances.override(DRAG_NEWTON_STEPS=0, MIN_CONTINUATION_STEP=min_step):
            try:  # no Newton step allowed: every stage fails and is halved until the step is too small
                constrain(c, request)
            except (ConstraintError, ConvergenceError):
                pass
        return len(steps)

    assert continuation_stages(2.0**-14) - continuation_stages(2.0**-3) == 11


def test_linear_check_rtol_of_surface_edits_is_read_at_call_time():
    s = bump()
    target = s.evaluate(0.37, 0.61) + [0.1, -0.2, 0.3]
    plane = {"normal": [0.1, 0.2, 1.0]}  # with a tangent-plane condition the solve leaves round-off
    drag_surface_point(s, 0.37, 0.61, target, **plane)
    with tolerances.override(LINEAR_CHECK_RTOL=0.0), pytest.raises(ConstraintError, match="too ill-conditioned"):
        drag_surface_point(s, 0.37, 0.61, target, **plane)  # a zero limit refuses every nonzero residual


# ---------------------------------------------------------------------------------------- hierarchical
def test_frame_degeneracy_and_nudge_are_read_at_call_time():
    su, sv = np.array([[1.0, 0.0, 0.0]]), np.array([[0.0, 1.0, 0.0]])
    assert not frames_from_partials(su, sv)[1][0]
    with tolerances.override(FRAME_DEGENERACY=1.0):  # |S_u x S_v| = 1 <= 1 * (1 + 1): degenerate
        assert frames_from_partials(su, sv)[1][0]
    # A sphere-like cap collapsed at u = 0: the frame there is taken FRAME_NUDGE inside.
    g = np.linspace(0, 2 * np.pi, 6, endpoint=False)
    r = np.array([0.0, 1.0, 2.0, 3.0])
    P = np.stack([np.outer(r, np.cos(g)), np.outer(r, np.sin(g)), np.outer(3 - r, np.ones(6))], -1)
    tv = np.r_[[0.0] * 4, 1 / 3, 2 / 3, [1.0] * 4]
    s = BSplineSurface((3, 3), ([0, 0, 0, 0, 1, 1, 1, 1], tv), P)
    vs = np.array([0.5])
    F_default = surface_frames(s, np.array([0.0]), vs)
    with tolerances.override(FRAME_NUDGE=1e-2):
        F_far = surface_frames(s, np.array([0.0]), vs)
    # The normal column is the surface normal at the nudged parameters (u and v move towards the
    # centre by FRAME_NUDGE times the domain size; v = 0.5 is the centre and moves down).
    n_default = s.normal(1e-6, 0.5 - 1e-6)
    n_far = s.normal(1e-2, 0.5 - 1e-2)
    np.testing.assert_allclose(F_default[0, 0, :, 2], n_default, atol=1e-12)
    np.testing.assert_allclose(F_far[0, 0, :, 2], n_far, atol=1e-12)
    assert np.linalg.norm(F_far[0, 0, :, 2] - F_default[0, 0, :, 2]) > 1e-4


# ---------------------------------------------------------------------------------------- fitting
def test_schoenberg_whitney_margin_is_read_at_call_time():
    Q = np.random.default_rng(4).random((9, 3))
    interpolate_curve(Q, 3)
    with tolerances.override(SCHOENBERG_WHITNEY=0.99), pytest.raises(InvalidGeometryError, match="Schoenberg"):
        interpolate_curve(Q, 3)


# ---------------------------------------------------------------------------------------- threads
def test_two_threads_each_see_their_own_override():
    """The overrides live in a ContextVar: two threads inside different ``override`` blocks at the
    same time (a barrier makes them overlap) each read and use their own values, and the main
    thread, which set nothing, keeps the defaults."""
    barrier = threading.Barrier(2, timeout=30)
    seen: dict[int, tuple] = {}
    errors: list[BaseException] = []

    def work(levels: int) -> None:
        try:
            with tolerances.override(ARC_LENGTH_MAX_LEVELS=levels, NUMBA_MIN_POINTS=levels):
                barrier.wait()  # both blocks are open now
                try:
                    result: object = float(arc_length(HARD, 0.0, 1.0))
                except ToleranceError as err:
                    result = err
                seen[levels] = (tolerances.ARC_LENGTH_MAX_LEVELS, tolerances.get("NUMBA_MIN_POINTS"), result)
                barrier.wait()  # neither block closes before both have read
        except BaseException as err:  # noqa: BLE001
            errors.append(err)
            barrier.abort()

    threads = [threading.Thread(target=work, args=(k,)) for k in (1, 40)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors
    assert seen[1][:2] == (1, 1) and isinstance(seen[1][2], ToleranceError)
    assert seen[40][:2] == (40, 40) and seen[40][2] == arc_length(HARD, 0.0, 1.0)
    assert tolerances.ARC_LENGTH_MAX_LEVELS == tolerances.defaults()["ARC_LENGTH_MAX_LEVELS"]
    assert tolerances.NUMBA_MIN_POINTS == tolerances.defaults()["NUMBA_MIN_POINTS"]
