"""Surface generation cross-validated with OpenCascade on the same inputs, and STEP round trips.

Each case builds our surface and OCC's (``tests.bridge.generation_occ``) from the same curves and
reports the largest distance both ways: our points (dense grid) projected onto OCC's face, and
OCC's face points projected onto ours (``GeomAPI_ProjectPointOnSurf``, BRepExtrema fallback).

Tolerances (measured values in brackets, geometry of size ~5):

* exact constructions (revolution, extrusion, ruled, translational and rotational sweeps) against
  OCC's exact surfaces: ``EXACT = 1e-11`` absolute [2e-15 .. 2.5e-14]: round-off of two
  evaluations plus the projection's convergence;
* generalised sweeps against ``BRepOffsetAPI_MakePipeShell``: ours is within ``tol = 1e-7`` of the
  exact sweep, OCC's within its ``SetTolerance(1e-8)`` approximation, so ``SWEEP = 2e-7``
  [5.2e-8 frames, 5.7e-8 with a scaling law, with the boundary-refined sampling of max_distance];
* rotation-minimising frames against OCC's ``GeomFill_DiscreteTrihedron`` on a 3-D (helical)
  path: OCC's discrete trihedron itself drifts from the true RMF by up to 2.7e-3 rad there (our
  frame matches an ODE solution to 8e-12, ``tests/algorithms/test_sweeping.py``), so ``DISCRETE =
  5e-3`` [2.2e-3 for a section of radius 0.7]. OCC's default corrected Frenet drifts by 0.17 rad on
  the same path: a strict xfail records it.

STEP round trips use ``write_step(..., precision_digits=17)``, which is bit-exact: poles, knots and
weights compared with ``np.array_equal``.

The distances are printed as a table at the end of the module, and written as Markdown to
``$OCCSURF_REPORT_DIR/generation_vs_occ.md`` when that variable is set.
"""

from __future__ import annotations

import contextlib
import os
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("OCP")

from occsurf.algorithms import BSplineCurve, arc, circle, ellipse  # noqa: E402
from occsurf.algorithms.construction.generation import extrude, revolve, rotational_sweep, ruled, translational_sweep  # noqa: E402
from occsurf.algorithms.construction.sweeping import sweep  # noqa: E402
from occsurf.algorithms.fitting.interpolation import interpolate_curve  # noqa: E402

EXACT = 1e-11
SWEEP = 2e-7
DISCRETE = 5e-3
SWEEP_TOL = 1e-7
TABLE: list[tuple[str, str, float, float, float]] = []


def G():
    import tests.bridge.generation_occ as mod

    return mod


@pytest.fixture(scope="module", autouse=True)
def report_table(request):
    """Print the distances at the end of the module (and write them if asked)."""
    yield
    if not TABLE:
        return
    lines = ["| construction | OCC reference | ours -> OCC | OCC -> ours | asserted |", "|---|---|---|---|---|"]
    lines += [f"| {a} | {b} | {f:.3g} | {g:.3g} | {t:.0e} |" for a, b, f, g, t in TABLE]
    text = "\n".join(["# Surface generation vs OCC: max distance (projection, both ways)", ""] + lines) + "\n"
    out = os.environ.get("OCCSURF_REPORT_DIR")
    if out:
        Path(out).mkdir(parents=True, exist_ok=True)
        (Path(out) / "generation_vs_occ.md").write_text(text)
    tr = request.config.pluginmanager.get_plugin("terminalreporter")
    cap = request.config.pluginmanager.get_plugin("capturemanager")
    if tr is not None:
        with cap.global_and_fixture_disabled() if cap is not None else contextlib.nullcontext():
            tr.write_line("")
            for line in lines:
                tr.write_line(line)


def check(name: str, ref: str, ours, occ, tol: float, samples: int = 31, accept: float = 0.0) -> None:
    fwd, bwd = G().max_distance(ours, occ, samples, accept)
    TABLE.append((name, ref, fwd, bwd, tol))
    assert fwd <= tol and bwd <= tol, f"{name} vs {ref}: {fwd:.3g}, {bwd:.3g} > {tol:g}"


# ------------------------------------------------------------------------------------------ inputs
def profile() -> BSplineCurve:
    """A rational, non-planar cubic profile."""
    return BSplineCurve(3, [0, 0, 0, 0, 0.5, 1, 1, 1, 1],
                        [[1, 0, 0], [2, 0.3, 1], [1.5, 0, 2], [2.5, -0.2, 3], [1, 0, 4]], [1, 2, 1, 0.5, 1])


def planar_profile() -> BSplineCurve:
    """A cubic in the xz half-plane x > 0."""
    return BSplineCurve(3, [0, 0, 0, 0, 0.5, 1, 1, 1, 1], [[1, 0, 0], [2, 0, 1], [1.5, 0, 2], [2.5, 0, 3], [1, 0, 4]])


def helix() -> BSplineCurve:
    th = np.linspace(0, 3 * np.pi, 12)
    return interpolate_curve(np.c_[3 * np.cos(th), 3 * np.sin(th), 0.8 * th])


def planar_path() -> BSplineCurve:
    return BSplineCurve(3, [0, 0, 0, 0, 0.4, 1, 1, 1, 1], [[0, 0, 0], [2, 0.5, 0], [4, 2.5, 0], [5, 5, 0], [5.5, 8, 0]])


def section(path: BSplineCurve) -> BSplineCurve:
    """An off-centre ellipse in the normal plane at the path start (no symmetry hides a rotation).
    The plane must contain the path start: MakePipeShell attaches the section where the spine
    meets its plane."""
    d = path.derivatives(path.domain[0], 1)
    p0, t0 = d[0], d[1] / np.linalg.norm(d[1])
    n0 = np.cross(t0, [0, 0, 1.0]) if abs(t0[2]) < 0.9 else np.cross(t0, [1.0, 0, 0])
    n0 /= np.linalg.norm(n0)
    return ellipse(p0 + 0.3 * n0, 0.6, 0.3, normal=t0, xaxis=n0 + 0.5 * np.cross(t0, n0))


# ------------------------------------------------------------------------------------------ exact
AXES = [((0, 0, 0), (0, 0, 1)), ((0.2, -0.1, 0.3), (0.1, 0.2, 1.0)), ((-3, 1, 0), (1, -1, 0.5))]


@pytest.mark.slow
@pytest.mark.parametrize("angle", [2 * np.pi, 2.0, np.pi, 4.5, -1.3])
@pytest.mark.parametrize("axis", range(len(AXES)))
def test_revolve_vs_occ(angle, axis):
    o, a = AXES[axis]
    c = profile()
    s = revolve(c, o, a, angle)
    check(f"revolve {angle:.3g} rad, axis {axis}", "Geom_SurfaceOfRevolution", s,
          G().revolution_surface(c, o, a, angle), EXACT)
    face = G().revolution_face(c, o, a, angle)
    check(f"revolve {angle:.3g} rad, axis {axis}", "BRepPrimAPI_MakeRevol", s, face, EXACT)
    if axis == 1:
        check(f"revolve {angle:.3g} rad, axis {axis}", "MakeRevol + NurbsConvert", s, G().nurbs_face(face), EXACT)


def test_revolve_semicircle_sphere_vs_occ():
    semi = arc([0, 0, 0], 2.5, -np.pi / 2, np.pi / 2, normal=[0, -1, 0], xaxis=[1, 0, 0])
    s = revolve(semi, [0, 0, 0], [0, 0, 1])
    check("revolve semicircle (sphere)", "BRepPrimAPI_MakeRevol", s, G().revolution_face(semi, [0, 0, 0], [0, 0, 1], 2 * np.pi), EXACT)


@pytest.mark.parametrize("vector", [(0.3, -1, 2), (0, 0, 5), (-2, 0.5, 0.1)])
def test_extrude_vs_occ(vector):
    c = profile()
    s = extrude(c, vector)
    check(f"extrude {vector}", "Geom_SurfaceOfLinearExtrusion", s, G().extrusion_surface(c, vector), EXACT)
    check(f"extrude {vector}", "BRepPrimAPI_MakePrism", s, G().prism_face(c, vector), EXACT)


@pytest.mark.parametrize("rational", [False, True])
def test_ruled_vs_occ(rational):
    c1 = profile() if rational else planar_profile()
    c2 = BSplineCurve(2, [0, 0, 0, 1, 2, 2, 2], [[0, 5, 0], [1, 6, 1], [2, 5, 2], [3, 6, 0]])
    s = ruled(c1, c2)
    check(f"ruled (rational={rational})", "GeomFill::Surface", s, G().ruled_surface(c1, c2), EXACT)
    check(f"ruled (rational={rational})", "BRepFill::Face", s, G().ruled_face(c1, c2), EXACT)


@pytest.mark.parametrize("path", ["helix", "planar"])
def test_translational_sweep_vs_occ(path):
    q = helix() if path == "helix" else planar_path()
    c = section(q)
    s = translational_sweep(c, q)
    check(f"translational sweep ({path})", "MakePipeShell, fixed trihedron", s, G().pipe_shell_face(c, q, mode="fixed"), EXACT)


def test_rotational_sweep_vs_occ():
    prof = planar_profile()
    s = rotational_sweep(prof, circle([0, 0, 2], 3.0))
    check("rotational sweep, circle trajectory", "BRepPrimAPI_MakeRevol", s,
          G().revolution_face(prof, (0, 0, 0), (0, 0, 1), 2 * np.pi), EXACT)
    s = rotational_sweep(prof, ellipse([0, 0, 2], 3.0, 1.8))
    check("rotational sweep, ellipse trajectory", "MakeRevol + GTransform (y x 0.6)", s,
          G().stretched_revolution_face(prof, (0, 0, 0), 0.6), EXACT)


# ------------------------------------------------------------------------------------------ sweeps
@pytest.mark.slow
@pytest.mark.parametrize(("path", "frame", "mode", "tol"), [
    ("planar", "rmf", "corrected_frenet", SWEEP),
    ("planar", "frenet", "frenet", SWEEP),
    ("helix", "frenet", "frenet", SWEEP),
    ("helix", "rmf", "discrete", DISCRETE),
])
def test_sweep_vs_pipe_shell(path, frame, mode, tol):
    q = helix() if path == "helix" else planar_path()
    c = section(q)
    s = sweep(c, q, frame=frame, tol=SWEEP_TOL)
    check(f"sweep {frame} ({path})", f"MakePipeShell {mode}", s, G().pipe_shell_face(c, q, mode=mode), tol, samples=21, accept=tol / 10)


@pytest.mark.slow
@pytest.mark.parametrize("path", ["helix", "planar"])
def test_sweep_scaling_law_vs_pipe_shell(path):
    q = helix() if path == "helix" else planar_path()
    c = section(q)
    law = lambda t: 1 + 0.5 * np.sin(3 * t)  # noqa: E731
    frame, mode = ("frenet", "frenet") if path == "helix" else ("rmf", "corrected_frenet")
    s = sweep(c, q, frame=frame, scale=law, tol=SWEEP_TOL)
    check(f"sweep {frame} + scale law ({path})", f"MakePipeShell {mode} + SetLaw", s,
          G().pipe_shell_face(c, q, mode=mode, scale=law), SWEEP, samples=21, accept=SWEEP / 10)


@pytest.mark.xfail(strict=True, reason="OCC's GeomFill_CorrectedFrenet is not rotation-minimising on a helix: "
                   "it drifts 0.17 rad from the RMF over 1.5 turns (0.1 in distance here)")
def test_corrected_frenet_is_rmf_on_helix():
    q = helix()
    c = section(q)
    s = sweep(c, q, frame="rmf", tol=SWEEP_TOL)
    fwd, bwd = G().max_distance(s, G().pipe_shell_face(c, q, mode="corrected_frenet"), 9)
    assert max(fwd, bwd) <= 1e-3


# ------------------------------------------------------------------------------------------ STEP
def generated():
    c, q = profile(), helix()
    sec = section(q)
    return {
        "revolve": revolve(c, (0.2, -0.1, 0.3), (0.1, 0.2, 1.0), 2 * np.pi),
        "revolve partial": revolve(c, (0, 0, 0), (0, 0, 1), -2.0),
        "extrude": extrude(c, (0.3, -1, 2)),
        "ruled": ruled(c, planar_profile().transform(np.eye(3), (0, 5, 0))),
        "translational": translational_sweep(sec, q),
        "rotational": rotational_sweep(planar_profile(), ellipse([0, 0, 2], 3.0, 1.8)),
        "sweep": sweep(sec, q, twist=lambda t: 2 * t, scale=lambda t: 1 + t, tol=1e-5),
    }


def test_step_round_trip_is_bit_exact(tmp_path):
    from occsurf.bridge.exchange.step_iges import read_step, write_step

    items = generated()
    path = write_step(tmp_path / "generation.step", list(items.values()), names=list(items), precision_digits=17)
    model = read_step(path)
    assert len(model.faces) == len(items)
    faces = {f.name: f for f in model.faces}
    for name, s in items.items():
        face = faces[name]
        back = face.surface
        assert back is not None, name
        assert back.degree == s.degree, name
        for k, periodic in enumerate((face.u_periodic, face.v_periodic)):
            # OCC's reader makes closed directions (full turn, closed profile) periodic; bridge
            # converts those back with OCC's flat knots, whose first and last values (which no
            # basis function on the domain uses) differ from our clamped ends. Everything else is
            # bit-exact.
            inner = slice(1, -1) if periodic else slice(None)
            assert np.array_equal(back.knots[k][inner], s.knots[k][inner]), (name, k)
        assert np.array_equal(back.control_points, s.control_points), name
        if s.weights is None:
            assert back.weights is None or np.all(back.weights == 1.0), name
        else:
            assert np.array_equal(back.weights, s.weights), name
        (a, b), (c, d) = s.domain
        u, v = np.linspace(a, b, 23), np.linspace(c, d, 23)
        # the outer knots enter no evaluation on the domain: the same points to round-off
        assert np.abs(back.evaluate_grid(u, v) - s.evaluate_grid(u, v)).max() <= 1e-13, name
