"""STEP/IGES exchange (occsurf.bridge.exchange.step_iges): lossless STEP round trips, the IGES error bound, names,
millimetres, atomic writes, corrupt files, and the public CAD files of ../shared/realdata.

Every file is generated in ``tmp_path``; nothing is kept under tests/.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given
from hypothesis import strategies as st

from occsurf.algorithms import BSplineCurve, BSplineSurface
from occsurf.algorithms.errors import ExchangeError, InvalidGeometryError
from occsurf.bridge.exchange.step_iges import (
    IGES_RELATIVE_ERROR,
    STEP_DEFAULT_RELATIVE_ERROR,
    ImportedEdge,
    ImportedFace,
    ImportedModel,
    read_iges,
    read_step,
    write_iges,
    write_step,
)
from tests.algorithms.strategies import curves, surfaces, test_settings

REALDATA = Path(__file__).resolve().parents[2].parent / "shared" / "realdata"

# Hypothesis: each example writes and reads a file (a few ms); keep the suite well under a minute.
ROUND_TRIP = test_settings(30, suppress=[HealthCheck.function_scoped_fixture])


# ------------------------------------------------------------------------------------ helpers
def _surface(rational: bool = True, seed: int = 0) -> BSplineSurface:
    rng = np.random.default_rng(seed)
    U = [0, 0, 0, 0, 0.3, 0.7, 1, 1, 1, 1]
    V = [-1.5, -1.5, -1.5, 0.1, 2.0, 2.0, 2.0]
    P = rng.normal(size=(6, 4, 3)) * [3.0, 0.7, 0.013]
    w = rng.uniform(0.3, 3.0, size=(6, 4)) if rational else None
    return BSplineSurface((3, 2), (U, V), P, w)


def _curve(rational: bool = False, seed: int = 1) -> BSplineCurve:
    rng = np.random.default_rng(seed)
    P = rng.normal(size=(7, 3)) * 5.0
    w = rng.uniform(0.5, 2.0, size=7) if rational else None
    return BSplineCurve(3, [0, 0, 0, 0, 0.1, 0.2, 0.7, 1.3, 1.3, 1.3, 1.3], P, w)


def _same_weights(got: np.ndarray | None, want: np.ndarray | None) -> bool:
    """Bit-identical weights. OCC's Geom_BSpline* constructors drop weights that are all equal to
    within rounding (a spread of an ulp, as clamp() can leave), and the spline is then the same
    polynomial one: ``None`` matches such weights (and to_occ alone does the same)."""
    if want is None or got is None:
        return got is None and (want is None or float(np.ptp(want)) <= 1e-15 * float(np.max(want)))
    return np.array_equal(got, want)


def _same_surface(a: BSplineSurface, b: BSplineSurface) -> bool:
    """``a`` (read back) bit-identical to ``b`` (written)."""
    return (
        a.degree == b.degree
        and all(np.array_equal(x, y) for x, y in zip(a.knots, b.knots))
        and np.array_equal(a.control_points, b.control_points)
        and _same_weights(a.weights, b.weights)
    )


def _same_curve(a: BSplineCurve, b: BSplineCurve) -> bool:
    return (
        a.degree == b.degree
        and np.array_equal(a.knots, b.knots)
        and np.array_equal(a.control_points, b.control_points)
        and _same_weights(a.weights, b.weights)
    )


def _extent(points: np.ndarray) -> float:
    pts = np.asarray(points).reshape(-1, 3)
    return float(np.max(pts.max(axis=0) - pts.min(axis=0)))


def _is_clamped(knots: np.ndarray, degree: int) -> bool:
    return bool(np.all(knots[: degree + 1] == knots[0]) and np.all(knots[-degree - 1 :] == knots[-1]))


def _as_written(x):
    """What the writers put in the file: the spline itself, or its clamp() if unclamped."""
    if isinstance(x, BSplineSurface):
        ok = _is_clamped(x.knots[0], x.degree[0]) and _is_clamped(x.knots[1], x.degree[1])
    else:
        ok = _is_clamped(x.knots, x.degree)
    return x if ok else x.clamp()


def _closed(x) -> bool:
    """Closed as written (end poles, or end pole rows/columns, within 1e-7): OCC's readers turn
    such a spline into a periodic one (StepToTopoDS_TranslateFace via ShapeCustom for surfaces,
    the closed_curve flag for curves). Same geometry, another representation: tested apart."""
    P = _as_written(x).control_points
    if isinstance(x, BSplineCurve):
        return bool(np.linalg.norm(P[0] - P[-1]) <= 1e-7)
    return bool(np.max(np.linalg.norm(P[0] - P[-1], axis=-1)) <= 1e-7
                or np.max(np.linalg.norm(P[:, 0] - P[:, -1], axis=-1)) <= 1e-7)


def _proper(s: BSplineSurface) -> bool:
    """A net without coincident neighbouring poles, not on a line. OCC's STEP writer drops a face
    whose boundary is degenerate (write_step then raises), and its reader drops some faces of
    nets that collapse to a point over most of the patch (hypothesis shrinks towards all-zero
    nets); neither is a round-trip case."""
    P = _as_written(s).control_points
    flat = P.reshape(-1, 3) - P.reshape(-1, 3).mean(axis=0)
    gaps = min(np.linalg.norm(np.diff(P, axis=0), axis=-1).min(), np.linalg.norm(np.diff(P, axis=1), axis=-1).min())
    return bool(gaps > 1e-3 and np.linalg.matrix_rank(flat, tol=1e-3) >= 2)


@st.composite
def generic_surfaces(draw) -> BSplineSurface:
    """tests.algorithms.strategies.surfaces (any degree, knots, weights, clamped or not) with a
    fixed non-planar lattice added to the poles: hypothesis' arrays repeat values, and nets that
    collapse to a point or a line are not round-trip cases (see _proper)."""
    s = draw(surfaces(dims=st.just(3)))
    i, j = np.meshgrid(np.arange(s.n_poles[0]), np.arange(s.n_poles[1]), indexing="ij")
    lattice = np.stack([3.0 * i, 3.0 * j, np.sin(i + 2.0 * j)], axis=-1)
    return BSplineSurface(s.degree, s.knots, s.control_points + lattice, s.weights)


def _within_iges_bound(got: np.ndarray, want: np.ndarray) -> bool:
    """Per value |got - want| <= IGES_RELATIVE_ERROR |want| (+ one ulp of parsing)."""
    got, want = np.asarray(got), np.asarray(want)
    return got.shape == want.shape and bool(np.all(np.abs(got - want) <= (IGES_RELATIVE_ERROR + 1e-15) * np.abs(want)))


def _iges_weights_ok(got: np.ndarray | None, want: np.ndarray | None) -> bool:
    """Within the IGES bound; ``None`` (OCC dropped them) only for weights that are equal once
    printed with 10 digits."""
    if got is None:
        return want is None or float(np.ptp(want)) <= 2 * IGES_RELATIVE_ERROR * float(np.max(want))
    return want is not None and _within_iges_bound(got, want)


def _rel_error(got: np.ndarray, want: np.ndarray) -> float:
    want = np.asarray(want)
    nz = want != 0
    err = np.abs(np.asarray(got) - want)
    assert np.all(err[~nz] == 0)
    return float(np.max(err[nz] / np.abs(want[nz]))) if nz.any() else 0.0


@pytest.fixture
def step_file(tmp_path: Path) -> Path:
    return write_step(tmp_path / "valid.step", [_surface(), _curve()], ["skin", "rail"])


@pytest.fixture
def iges_file(tmp_path: Path) -> Path:
    return write_iges(tmp_path / "valid.igs", [_surface(), _curve()], ["skin", "rail"])


# ------------------------------------------------------------------------- STEP: lossless
class TestStepRoundTrip:
    def test_surface_and_curve_bit_exact(self, tmp_path):
        s, c = _surface(), _curve(rational=True)
        path = write_step(tmp_path / "a.step", [s, c])
        assert isinstance(path, Path) and path == tmp_path / "a.step"
        model = read_step(path)
        assert isinstance(model, ImportedModel) and model.format == "step" and model.path == str(path)
        assert len(model.faces) == 1 and len(model.edges) == 1
        face, edge = model.faces[0], model.edges[0]
        assert isinstance(face, ImportedFace) and isinstance(edge, ImportedEdge)
        assert face.index == 0 and face.surface_type == "BSplineSurface" and face.error is None
        assert edge.index == 0 and edge.curve_type == "BSplineCurve" and edge.error is None
        assert _same_surface(face.surface, s)
        assert _same_curve(edge.curve, c)
        assert (face.u_periodic, face.v_periodic) == (False, False) and face.continuity == "C1"
        assert edge.periodic is False and edge.continuity == "C2"
        assert edge.parameter_range == c.domain

    @ROUND_TRIP
    @given(s=generic_surfaces())
    def test_random_surfaces_bit_exact(self, tmp_path, s):
        assume(_proper(s) and not _closed(s))
        model = read_step(write_step(tmp_path / "s.step", s))
        assert len(model.faces) == 1
        assert model.faces[0].error is None, model.faces[0].error
        got, want = model.faces[0].surface, _as_written(s)
        assert _same_surface(got, want), (got.weights, want.weights, s.weights)

    @ROUND_TRIP
    @given(c=curves(dims=st.just(3)))
    def test_random_curves_bit_exact(self, tmp_path, c):
        assume(_extent(c.control_points) > 1e-3 and not _closed(c))
        model = read_step(write_step(tmp_path / "c.step", c))
        assert len(model.faces) == 0 and len(model.edges) == 1
        assert model.edges[0].error is None, model.edges[0].error
        assert _same_curve(model.edges[0].curve, _as_written(c))

    def test_unclamped_written_as_clamp(self, tmp_path):
        """OCC's STEP writer drops some unclamped rational faces and its reader trims others, so
        write_step writes clamp(): the same geometry, and exactly clamp()'s numbers come back."""
        rng = np.random.default_rng(7)
        s = BSplineSurface((3, 2), (np.arange(10.0), [0, 0, 0, 1, 2, 3, 3, 3]), rng.normal(size=(6, 5, 3)),
                           rng.uniform(0.5, 2, size=(6, 5)))
        got = read_step(write_step(tmp_path / "u.step", s)).faces[0].surface
        assert _same_surface(got, s.clamp())
        (u0, u1), (v0, v1) = s.domain
        us, vs = np.linspace(u0, u1, 6), np.linspace(v0, v1, 6)
        np.testing.assert_allclose(got.evaluate_grid(us, vs), s.evaluate_grid(us, vs), rtol=0, atol=1e-12)

    def test_closed_splines_come_back_periodic(self, tmp_path):
        """OCC's reader makes a closed B-spline periodic (a curve through STEP's closed_curve flag,
        a face in StepToTopoDS_TranslateFace): the geometry is the same, the representation (the
        unrolled periodic spline) is not the one written."""
        inner = list(np.arange(1, 7) / 7.0)  # a degree-2 closed "tube": first and last pole rows coincide
        ring = np.array([[np.cos(a), np.sin(a)] for a in 2 * np.pi * np.r_[0:8] / 8])
        ring = np.vstack([ring, ring[:1]])
        net = np.array([[[x, y, z] for x, y in ring] for z in (0.0, 1.0, 2.5)])
        s = BSplineSurface((2, 2), ([0, 0, 0, 1, 1, 1], [0, 0, 0, *inner, 1, 1, 1]), net)
        c = BSplineCurve(2, [0, 0, 0, *inner, 1, 1, 1], net[0])
        model = read_step(write_step(tmp_path / "closed.step", [s, c]))
        face, edge = model.faces[0], model.edges[0]
        assert face.v_periodic and not face.u_periodic and edge.periodic
        assert not _same_surface(face.surface, s)
        us, vs = np.linspace(0, 1, 5), np.linspace(0, 1, 9)
        np.testing.assert_allclose(face.surface.evaluate_grid(us, vs), s.evaluate_grid(us, vs), rtol=0, atol=1e-14)
        np.testing.assert_allclose(edge.curve.evaluate(vs), c.evaluate(vs), rtol=0, atol=1e-14)

    def test_reals_printed_with_17_digits(self, tmp_path):
        path = write_step(tmp_path / "a.step", _surface())
        text = path.read_text()
        assert "E+00" in text and "1.0000000000000000E+00" in text  # %.16E, no zero suppression
        short = write_step(tmp_path / "b.step", _surface(), precision_digits=6).read_text()
        assert "1.00000E+00" in short and len(short) < len(text)

    def test_fewer_digits_lose_precision(self, tmp_path):
        s = _surface()
        got = read_step(write_step(tmp_path / "a.step", s, precision_digits=8)).faces[0].surface
        err = _rel_error(got.control_points, s.control_points)
        assert 0 < err <= 5e-8  # %.7E: half a unit in the 8th significant digit

    def test_occ_default_writer_is_not_lossless(self, tmp_path):
        """OCC's own Write() keeps 13 significant digits (12 decimals near 0.1): this is why
        write_step prints the model itself. The measured error stays within the documented bound."""
        from OCP.STEPControl import STEPControl_StepModelType, STEPControl_Writer

        from occsurf.bridge.conversion.splines import to_face

        s = _surface()
        writer = STEPControl_Writer()
        writer.Transfer(to_face(s).wrapped, STEPControl_StepModelType.STEPControl_AsIs)
        path = tmp_path / "occ.step"
        writer.Write(str(path))
        got = read_step(path).faces[0].surface
        err = max(_rel_error(got.control_points, s.control_points), _rel_error(got.weights, s.weights))
        assert 0 < err <= STEP_DEFAULT_RELATIVE_ERROR
        assert not _same_surface(got, s)

    @pytest.mark.parametrize("digits", [1, 18, 2.5, True, "17"])
    def test_precision_digits_validated(self, tmp_path, digits):
        with pytest.raises(InvalidGeometryError, match="precision_digits"):
            write_step(tmp_path / "a.step", _surface(), precision_digits=digits)
        assert not (tmp_path / "a.step").exists()


# ------------------------------------------------------------------------------ IGES: bound
class TestIgesRoundTrip:
    """OCC writes IGES reals as %11.9E, or %11.9f for 0.1 <= |x| < 1000: at most 5e-10 absolute
    in that range (5e-9 relative at |x| = 0.1) and 10 significant digits elsewhere (5e-10
    relative). Hence the per-value bound IGES_RELATIVE_ERROR = 5e-9 |x|, and no more."""

    def test_surface_and_curve_within_bound(self, tmp_path):
        s, c = _surface(), _curve(rational=True)
        model = read_iges(write_iges(tmp_path / "a.igs", [s, c]))
        assert model.format == "iges" and len(model.faces) == 1 and len(model.edges) == 1
        got_s, got_c = model.faces[0].surface, model.edges[0].curve
        assert model.faces[0].surface_type == "BSplineSurface" and model.edges[0].curve_type == "BSplineCurve"
        assert got_s.degree == s.degree and got_c.degree == c.degree
        for got, want in [(got_s.control_points, s.control_points), (got_s.weights, s.weights),
                          (got_s.knots[0], s.knots[0]), (got_s.knots[1], s.knots[1]),
                          (got_c.control_points, c.control_points), (got_c.weights, c.weights),
                          (got_c.knots, c.knots)]:
            assert _within_iges_bound(got, want)
        # ... and IGES is really lossy: the bound is not vacuous.
        assert _rel_error(got_s.control_points, s.control_points) > 1e-12

    def test_bound_is_attained_near_one_tenth(self, tmp_path):
        """A coordinate just above 0.1 keeps only 9 significant digits."""
        P = np.zeros((2, 2, 3))
        P[..., 0] = [[0.0, 1.0], [0.0, 1.0]]
        P[..., 1] = [[0.0, 0.0], [1.0, 1.0]]
        P[0, 0, 2] = 0.1000000004999  # printed "0.100000000": error 5.0e-10, relative 5.0e-9
        s = BSplineSurface((1, 1), ([0, 0, 1, 1], [0, 0, 1, 1]), P)
        got = read_iges(write_iges(tmp_path / "a.igs", s)).faces[0].surface
        err = _rel_error(got.control_points[0, 0, 2:], P[0, 0, 2:])
        assert 4.9e-9 < err <= IGES_RELATIVE_ERROR

    @ROUND_TRIP
    @given(s=generic_surfaces())
    def test_random_surfaces_within_bound(self, tmp_path, s):
        assume(_proper(s) and not _closed(s))
        s = _as_written(s)
        got = read_iges(write_iges(tmp_path / "s.igs", s)).faces[0].surface
        assert got.degree == s.degree and got.n_poles == s.n_poles
        assert _within_iges_bound(got.control_points, s.control_points)
        assert _within_iges_bound(got.knots[0], s.knots[0]) and _within_iges_bound(got.knots[1], s.knots[1])
        assert _iges_weights_ok(got.weights, s.weights)

    @ROUND_TRIP
    @given(c=curves(dims=st.just(3)))
    def test_random_curves_within_bound(self, tmp_path, c):
        assume(_extent(c.control_points) > 1e-3 and not _closed(c))
        c = _as_written(c)
        model = read_iges(write_iges(tmp_path / "c.igs", c))
        assert len(model.edges) == 1
        got = model.edges[0].curve
        assert got.degree == c.degree and got.n_poles == c.n_poles
        assert _within_iges_bound(got.control_points, c.control_points)
        assert _within_iges_bound(got.knots, c.knots)
        assert _iges_weights_ok(got.weights, c.weights)


# ------------------------------------------------------------------------------------ units
class TestUnits:
    def test_step_written_in_mm_whatever_the_session_says(self, tmp_path):
        from OCP.Interface import Interface_Static

        s = _surface(rational=False)
        write_step(tmp_path / "probe.step", s)  # initialises the STEP controller
        old = Interface_Static.CVal_s("write.step.unit")
        Interface_Static.SetCVal_s("write.step.unit", "M")
        try:
            path = write_step(tmp_path / "a.step", s)
            assert Interface_Static.CVal_s("write.step.unit") == "M"  # restored
        finally:
            Interface_Static.SetCVal_s("write.step.unit", old)
        text = path.read_text()
        assert "SI_UNIT(.MILLI.,.METRE.)" in text and ".METRE.)" in text
        assert _same_surface(read_step(path).faces[0].surface, s)  # values unchanged

    def test_iges_written_in_mm(self, tmp_path):
        s = _surface(rational=False)
        path = write_iges(tmp_path / "a.igs", s)
        glob = "".join(line[:72] for line in path.read_text().splitlines() if line[72:73] == "G")
        assert ",2,2HMM," in glob  # unit flag 2 = millimetres, unit name MM
        got = read_iges(path).faces[0].surface
        assert _within_iges_bound(got.control_points, s.control_points)

    def test_values_in_another_unit_converted_to_mm(self, tmp_path):
        """A STEP file in metres (written by OCC with write.step.unit = M) reads in millimetres."""
        from OCP.Interface import Interface_Static
        from OCP.STEPControl import STEPControl_StepModelType, STEPControl_Writer

        from occsurf.bridge.conversion.splines import to_face

        s = _surface(rational=False)
        writer = STEPControl_Writer()
        old = Interface_Static.CVal_s("write.step.unit")
        Interface_Static.SetCVal_s("write.step.unit", "M")
        try:
            writer.Transfer(to_face(s).wrapped, STEPControl_StepModelType.STEPControl_AsIs)
            writer.Write(str(tmp_path / "m.step"))
        finally:
            Interface_Static.SetCVal_s("write.step.unit", old)
        assert ".METRE." in (tmp_path / "m.step").read_text()
        got = read_step(tmp_path / "m.step").faces[0].surface
        np.testing.assert_allclose(got.control_points, s.control_points, rtol=1e-11, atol=1e-12)


# ------------------------------------------------------------------------------------ names
class TestNames:
    def test_step_names_round_trip(self, tmp_path):
        names = ["skin", "rail: ünïcode ∑, 'quoted' \\ back", "a" * 200]
        path = write_step(tmp_path / "a.step", [_surface(), _curve(), _curve(seed=5)], names)
        model = read_step(path)
        assert [f.name for f in model.faces] == ["skin"]
        assert [e.name for e in model.edges] == names[1:]
        text = path.read_text(encoding="utf-8")
        assert "PRODUCT('skin','skin'" in text and "ADVANCED_FACE('skin'" in text

    def test_step_shape_name_goes_to_all_its_faces(self, tmp_path):
        import build123d as bd

        box = bd.Solid.make_box(1, 2, 3)
        model = read_step(write_step(tmp_path / "a.step", [box, _surface()], ["box", None]))
        assert len(model.faces) == 7
        assert [f.name for f in model.faces] == ["box"] * 6 + [None]
        assert [f.surface_type for f in model.faces] == ["Plane"] * 6 + ["BSplineSurface"]
        assert all(f.surface is not None and f.error is None for f in model.faces)

    def test_step_without_names(self, tmp_path):
        model = read_step(write_step(tmp_path / "a.step", [_surface(), _curve()]))
        assert model.faces[0].name is None and model.edges[0].name is None

    def test_iges_names_round_trip(self, tmp_path):
        names = ["a long surface name", "rail ∑", None]
        path = write_iges(tmp_path / "a.igs", [_surface(), _curve(), _curve(seed=5)], names)
        model = read_iges(path)
        assert [f.name for f in model.faces] == ["a long surface name"]
        assert [e.name for e in model.edges] == ["rail ∑", None]
        text = path.read_bytes()
        assert b"19Ha long surface name;" in text  # 406-15 name property, full length
        assert b"a long s" in text  # 8-character entity label in the directory entry

    @pytest.mark.parametrize("names", [["a", "b"], [3], 7])
    def test_bad_names(self, tmp_path, names):
        with pytest.raises(InvalidGeometryError, match="names"):
            write_step(tmp_path / "a.step", [_surface()], names)

    def test_single_str_name(self, tmp_path):
        model = read_step(write_step(tmp_path / "a.step", _surface(), "only"))
        assert model.faces[0].name == "only"


# ----------------------------------------------------------------------- objects accepted
class TestObjects:
    def test_build123d_cadquery_and_topods(self, tmp_path):
        import build123d as bd
        import cadquery as cq

        objs = [bd.Solid.make_sphere(1.0), cq.Workplane().box(1, 1, 1), cq.Solid.makeCylinder(1, 2).wrapped]
        # IGES 5.3 (faces mode) has no sphere or cylinder entity: OCC writes surfaces of revolution.
        for writer, reader, types in [(write_step, read_step, {"Sphere", "Plane", "Cylinder"}),
                                      (write_iges, read_iges, {"SurfaceOfRevolution", "Plane"})]:
            model = reader(writer(tmp_path / f"a.{writer.__name__[-4:]}", objs))
            assert {f.surface_type for f in model.faces} == types
            assert len(model.faces) == 1 + 6 + 3
            assert all(f.surface is not None for f in model.faces), [f.error for f in model.faces]
            assert model.edges == []  # all edges bound faces

    @pytest.mark.parametrize("bad", ["text", 3.0, None, [], [_surface(), object()]])
    def test_unsupported_objects(self, tmp_path, bad):
        with pytest.raises(InvalidGeometryError, match="objects"):
            write_step(tmp_path / "a.step", bad)
        with pytest.raises(InvalidGeometryError, match="objects"):
            write_iges(tmp_path / "a.igs", bad)
        assert list(tmp_path.iterdir()) == []

    def test_two_dimensional_and_null(self, tmp_path):
        from OCP.TopoDS import TopoDS_Shape

        c2 = BSplineCurve(2, [0, 0, 0, 1, 1, 1], [[0, 0], [1, 1], [2, 0]])
        with pytest.raises(InvalidGeometryError, match="3-D curve"):
            write_step(tmp_path / "a.step", c2)
        with pytest.raises(InvalidGeometryError, match="null"):
            write_iges(tmp_path / "a.igs", TopoDS_Shape())
        assert list(tmp_path.iterdir()) == []


# ---------------------------------------------------------------------------- reading faces
class TestReading:
    def test_conversion_failure_is_per_face(self, tmp_path, monkeypatch):
        import build123d as bd

        import occsurf.bridge.conversion.splines

        path = write_step(tmp_path / "a.step", [bd.Solid.make_box(1, 1, 1), _surface()])
        real = occsurf.bridge.conversion.splines.from_occ

        def flaky(obj, *args, **kwargs):
            from OCP.BRep import BRep_Tool
            from OCP.Geom import Geom_Plane

            if isinstance(BRep_Tool.Surface_s(obj), Geom_Plane):
                raise RuntimeError("synthetic\nfailure")
            return real(obj, *args, **kwargs)

        monkeypatch.setattr(occsurf.bridge.conversion.splines, "from_occ", flaky)
        model = read_step(path)
        assert len(model.faces) == 7
        planes = [f for f in model.faces if f.surface_type == "Plane"]
        assert len(planes) == 6
        assert all(f.surface is None and f.error == "RuntimeError: synthetic failure" for f in planes)
        assert _same_surface(model.faces[-1].surface, _surface())

    def test_face_fields(self, tmp_path):
        import build123d as bd
        from OCP.Geom import Geom_Surface
        from OCP.TopoDS import TopoDS_Face

        model = read_step(write_step(tmp_path / "a.step", bd.Solid.make_cylinder(1, 2)))
        cyl = [f for f in model.faces if f.surface_type == "Cylinder"]
        assert len(cyl) == 1 and [f.index for f in model.faces] == list(range(len(model.faces)))
        f = cyl[0]
        assert isinstance(f.face, TopoDS_Face) and isinstance(f.occ_surface, Geom_Surface)
        assert f.u_periodic and not f.v_periodic and f.continuity == "CN"
        # the exact rational image of the cylinder: every sample on the unit circle
        (u0, u1), (v0, v1) = f.surface.domain
        pts = f.surface.evaluate_grid(np.linspace(u0, u1, 7), np.linspace(v0, v1, 3))
        np.testing.assert_allclose(np.hypot(pts[..., 0], pts[..., 1]), 1.0, atol=1e-12)

    def test_read_accepts_str_and_pathlike(self, step_file):
        assert len(read_step(str(step_file)).faces) == len(read_step(step_file).faces) == 1


# ------------------------------------------------------------------------------ corrupt files
def _assert_exchange_error(reader, path: Path, *words: str) -> None:
    with pytest.raises(ExchangeError) as info:
        reader(path)
    msg = str(info.value)
    assert str(path) in msg and "\n" not in msg, msg
    for w in words:
        assert w in msg, msg


class TestCorruptFiles:
    @pytest.mark.parametrize("fraction", [0.0005, 0.1, 0.5, 0.9, 0.999])
    def test_truncated_step(self, step_file, tmp_path, fraction):
        data = step_file.read_bytes()
        bad = tmp_path / "cut.step"
        bad.write_bytes(data[: int(len(data) * fraction)])
        _assert_exchange_error(read_step, bad)

    @pytest.mark.parametrize("cut", [3, 10, 17, 30])
    def test_truncated_step_end(self, step_file, tmp_path, cut):
        data = step_file.read_bytes().rstrip()
        bad = tmp_path / "cut.step"
        bad.write_bytes(data[:-cut])
        _assert_exchange_error(read_step, bad, "truncated")

    @pytest.mark.parametrize("fraction", [0.001, 0.1, 0.5, 0.9, 0.999])
    def test_truncated_iges(self, iges_file, tmp_path, fraction):
        data = iges_file.read_bytes()
        bad = tmp_path / "cut.igs"
        bad.write_bytes(data[: int(len(data) * fraction)])
        _assert_exchange_error(read_iges, bad)

    def test_truncated_iges_at_a_line_end_inside_the_poles(self, iges_file, tmp_path):
        """The dangerous case: OCC alone reads it as RetDone with a face of wrong poles."""
        lines = iges_file.read_bytes().splitlines(keepends=True)
        p_lines = [i for i, line in enumerate(lines) if line[72:73] == b"P"]
        bad = tmp_path / "cut.igs"
        bad.write_bytes(b"".join(lines[: p_lines[len(p_lines) // 2]]))
        _assert_exchange_error(read_iges, bad, "truncated")
        bad.write_bytes(b"".join(lines[:-1]))  # only the Terminate line missing
        _assert_exchange_error(read_iges, bad, "truncated")

    def test_iges_with_a_line_removed(self, iges_file, tmp_path):
        lines = iges_file.read_bytes().splitlines(keepends=True)
        p_lines = [i for i, line in enumerate(lines) if line[72:73] == b"P"]
        del lines[p_lines[1]]
        bad = tmp_path / "holed.igs"
        bad.write_bytes(b"".join(lines))
        _assert_exchange_error(read_iges, bad, "declares")

    @pytest.mark.parametrize("reader,suffix", [(read_step, ".step"), (read_iges, ".igs")])
    @pytest.mark.parametrize("seed", [0, 1, 2])
    def test_random_bytes(self, tmp_path, reader, suffix, seed):
        bad = tmp_path / f"random{suffix}"
        bad.write_bytes(np.random.default_rng(seed).bytes(5000))
        _assert_exchange_error(reader, bad)

    @pytest.mark.parametrize("reader,suffix", [(read_step, ".step"), (read_iges, ".igs")])
    @pytest.mark.parametrize("content,word", [(b"", "empty"), (b"  \n\n\t ", "blank"),
                                              (b"just a text file\nwith two lines\n", "not a")])
    def test_empty_blank_and_text(self, tmp_path, reader, suffix, content, word):
        bad = tmp_path / f"file{suffix}"
        bad.write_bytes(content)
        _assert_exchange_error(reader, bad, word)

    @pytest.mark.parametrize("reader", [read_step, read_iges])
    def test_directory_and_missing(self, tmp_path, reader):
        _assert_exchange_error(reader, tmp_path, "directory")
        _assert_exchange_error(reader, tmp_path / "missing.step", "no such file")

    def test_step_garbage_between_valid_frame(self, tmp_path):
        bad = tmp_path / "garbage.step"
        bad.write_bytes(b"ISO-10303-21;\nHEADER;\nthis is not STEP (;\nENDSEC;\nDATA;\n#1=FOO(#2,;\n"
                        b"#2 = ???\nENDSEC;\nEND-ISO-10303-21;\n")
        _assert_exchange_error(read_step, bad)

    def test_step_and_iges_without_geometry(self, tmp_path):
        from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeVertex
        from OCP.gp import gp_Pnt

        vertex = BRepBuilderAPI_MakeVertex(gp_Pnt(1, 2, 3)).Vertex()
        for writer, reader, name in [(write_step, read_step, "v.step"), (write_iges, read_iges, "v.igs")]:
            _assert_exchange_error(reader, writer(tmp_path / name, vertex))
        empty = tmp_path / "empty_data.step"
        empty.write_bytes(b"ISO-10303-21;\nHEADER;\nFILE_DESCRIPTION(('x'),'2;1');\n"
                          b"FILE_NAME('x','2024-01-01T00:00:00',(''),(''),'','','');\n"
                          b"FILE_SCHEMA(('AUTOMOTIVE_DESIGN'));\nENDSEC;\nDATA;\nENDSEC;\nEND-ISO-10303-21;\n")
        _assert_exchange_error(read_step, empty)

    def test_iges_with_scrambled_parameters(self, iges_file, tmp_path):
        """Structure intact, parameter data garbage: an error or a model, never a crash; a model
        returned must not be empty."""
        lines = iges_file.read_bytes().splitlines(keepends=True)
        out = []
        for line in lines:
            if line[72:73] == b"P":
                line = b"X" * 64 + line[64:]
            out.append(line)
        bad = tmp_path / "scrambled.igs"
        bad.write_bytes(b"".join(out))
        try:
            model = read_iges(bad)
        except ExchangeError as err:
            assert str(bad) in str(err)
        else:
            assert model.faces or model.edges

    def test_crlf_iges_reads(self, iges_file, tmp_path):
        crlf = tmp_path / "crlf.igs"
        crlf.write_bytes(iges_file.read_bytes().replace(b"\n", b"\r\n"))
        assert len(read_iges(crlf).faces) == 1

    def test_wrong_reader(self, step_file, iges_file):
        _assert_exchange_error(read_iges, step_file, "not an IGES")
        _assert_exchange_error(read_step, iges_file, "not a STEP")


# ------------------------------------------------------------------------------ atomic writes
def _listing(directory: Path) -> list[str]:
    return sorted(p.name for p in directory.iterdir())


class TestAtomicWrite:
    @pytest.mark.parametrize("writer", [write_step, write_iges])
    def test_no_leftovers_and_permissions(self, tmp_path, writer):
        path = writer(tmp_path / "a.out", _surface())
        assert _listing(tmp_path) == ["a.out"]
        umask = os.umask(0)
        os.umask(umask)
        assert stat.S_IMODE(path.stat().st_mode) == 0o666 & ~umask
        path.chmod(0o640)
        writer(path, _curve())
        assert stat.S_IMODE(path.stat().st_mode) == 0o640  # replacing keeps the mode
        assert _listing(tmp_path) == ["a.out"]

    @pytest.mark.parametrize("writer", [write_step, write_iges])
    def test_failed_write_never_clobbers(self, tmp_path, writer, monkeypatch):
        path = writer(tmp_path / "keep.out", _surface())
        before = path.read_bytes()
        with pytest.raises(InvalidGeometryError):  # bad object: fails before any file work
            writer(path, [_surface(), "junk"])
        assert path.read_bytes() == before and _listing(tmp_path) == ["keep.out"]

        def no_replace(src, dst):
            raise OSError(28, "No space left on device")

        monkeypatch.setattr(os, "replace", no_replace)
        with pytest.raises(ExchangeError, match="No space left"):
            writer(path, _curve())
        assert path.read_bytes() == before and _listing(tmp_path) == ["keep.out"]
        monkeypatch.undo()

        def broken_fsync(fd):
            raise OSError(5, "Input/output error")

        monkeypatch.setattr(os, "fsync", broken_fsync)
        with pytest.raises(ExchangeError, match="Input/output"):
            writer(tmp_path / "new.out", _curve())
        assert _listing(tmp_path) == ["keep.out"]

    def test_occ_print_failure_leaves_nothing(self, tmp_path, monkeypatch):
        from OCP.StepData import StepData_StepWriter

        path = write_step(tmp_path / "keep.step", _surface())
        before = path.read_bytes()
        monkeypatch.setattr(StepData_StepWriter, "Print", lambda self, stream: False)
        with pytest.raises(ExchangeError, match="printing the STEP model failed"):
            write_step(path, _curve())
        with pytest.raises(ExchangeError):
            write_step(tmp_path / "new.step", _curve())
        assert path.read_bytes() == before and _listing(tmp_path) == ["keep.step"]

    @pytest.mark.parametrize("writer", [write_step, write_iges])
    def test_unwritable_paths(self, tmp_path, writer):
        blocker = tmp_path / "file.txt"
        blocker.write_text("x")
        for target, word in [(tmp_path, "directory"), (tmp_path / "missing" / "a.out", "does not exist"),
                             (blocker / "a.out", "is not a directory")]:
            with pytest.raises(ExchangeError, match=word) as info:
                writer(target, _surface())
            assert str(target) in str(info.value)
        with pytest.raises(ExchangeError, match="cannot write"):
            writer(Path("/proc/occsurf-exchange-test.out"), _surface())  # a read-only file system
        assert _listing(tmp_path) == ["file.txt"]

    @pytest.mark.skipif(os.name != "posix" or os.geteuid() == 0, reason="root ignores directory permissions")
    def test_read_only_directory(self, tmp_path):
        ro = tmp_path / "ro"
        ro.mkdir()
        ro.chmod(0o555)
        try:
            with pytest.raises(ExchangeError, match="cannot write"):
                write_step(ro / "a.step", _surface())
            assert _listing(ro) == []
        finally:
            ro.chmod(0o755)


# ---------------------------------------------------------------------------------- real data
REAL_FILES = [
    # file, reader, faces, B-spline faces
    ("occt__bearing.iges", read_iges, 213, 213),
    ("occt__linkrods.step", read_step, 37, 18),
    ("pythonocc-core__sunglasses_lens.igs", read_iges, 9, 9),
    ("build123d__M6-1x12-countersunk-screw.step", read_step, 28, 6),
]


@pytest.mark.skipif(not REALDATA.is_dir(), reason=f"public CAD files not present at {REALDATA}")
@pytest.mark.parametrize("name,reader,n_faces,n_bspline", REAL_FILES, ids=[f[0] for f in REAL_FILES])
def test_real_files(name, reader, n_faces, n_bspline):
    """Every face read and typed; every B-spline face converted, our evaluation matching OCC's on a
    5 x 5 grid to 1e-12 of the face's control-net diagonal."""
    model = reader(REALDATA / name)
    assert len(model.faces) == n_faces
    assert [f.index for f in model.faces] == list(range(n_faces))
    bspline = [f for f in model.faces if f.surface_type == "BSplineSurface"]
    assert len(bspline) == n_bspline
    worst = 0.0
    for f in bspline:
        assert f.error is None and f.surface is not None, f.error
        s = f.surface
        (u0, u1), (v0, v1) = s.domain
        us, vs = np.linspace(u0, u1, 5), np.linspace(v0, v1, 5)
        ours = s.evaluate_grid(us, vs)
        theirs = np.array([[f.occ_surface.Value(u, v).Coord() for v in vs] for u in us])
        pts = s.control_points.reshape(-1, 3)
        diag = float(np.linalg.norm(pts.max(axis=0) - pts.min(axis=0)))
        worst = max(worst, float(np.max(np.linalg.norm(ours - theirs, axis=-1))) / diag)
    assert worst <= 1e-12, worst
    # Other faces: converted or carrying a one-line reason.
    for f in model.faces:
        assert (f.surface is None) == (f.error is not None)
        assert f.error is None or "\n" not in f.error
