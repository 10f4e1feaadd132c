"""Trimmed faces through the bridge: from_occ(face) keeps the loops, make_face / to_face rebuild
the same face (area, wires, edges per wire, validity, orientation), checked against OCC's own
area (BRepGProp) and point classification (BRepClass_FaceClassifier)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

bd = pytest.importorskip("build123d")

from OCP.BRep import BRep_Tool  # noqa: E402
from OCP.BRepCheck import BRepCheck_Analyzer  # noqa: E402
from OCP.BRepClass import BRepClass_FaceClassifier  # noqa: E402
from OCP.BRepGProp import BRepGProp  # noqa: E402
from OCP.BRepTools import BRepTools  # noqa: E402
from OCP.gp import gp_Pnt2d  # noqa: E402
from OCP.GProp import GProp_GProps  # noqa: E402
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FORWARD, TopAbs_IN, TopAbs_ON, TopAbs_OUT, TopAbs_WIRE  # noqa: E402
from OCP.TopExp import TopExp_Explorer  # noqa: E402
from OCP.TopoDS import TopoDS  # noqa: E402

from occsurf.algorithms import BSplineSurface, TrimmedSurface  # noqa: E402
from occsurf.algorithms.errors import ToleranceError  # noqa: E402
from occsurf.algorithms.kernel.trimmed import INSIDE, ON, OUTSIDE  # noqa: E402
from occsurf.bridge import from_occ, to_face  # noqa: E402
from occsurf.bridge.conversion.splines import make_face  # noqa: E402
from occsurf.bridge.conversion.trimming import angle_to_parameter, parameter_maps  # noqa: E402
from tests.algorithms.strategies import test_settings  # noqa: E402

REALDATA = Path(__file__).resolve().parents[2].parent / "shared" / "realdata"

#: Area agreement demanded of a rebuilt face (the issue's bound), relative.
AREA_RTOL = 1e-9

#: ``BRepGProp.SurfaceProperties_s(face, props, eps)`` (OCC's adaptive area integration) as the tests
#: call it by default: exact to ~1e-15 on analytic faces and on B-spline faces whose parameters are kept.
OCC_AREA_EPS = 1e-13

#: ... and where it must be precise: on a face whose analytic surface (cylinder, cone, sphere) is now the
#: rational B-spline GeomConvert makes of it, with p-curves that are not iso-lines, OCC's adaptive
#: quadrature stops early, and by steps: measured against closed forms (test_rebuilt_rational_faces_
#: have_the_exact_area), eps = 1e-13 leaves it 0.7-1.2e-9 off, 1e-14 5e-11, 1e-17 3e-12, 1e-19 2-3e-13
#: (the error it returns claims 1e-16 at every step), at ~10x the time (2 -> 20 ms per face).
OCC_PRECISE_EPS = 1e-19


def occ_area(face, eps: float | None = OCC_AREA_EPS) -> float:
    """OCC's area of a face: ``BRepGProp.SurfaceProperties_s`` adaptive with ``eps``, its default
    (non-adaptive Gauss) quadrature with ``eps=None``."""
    props = GProp_GProps()
    if eps is None:
        BRepGProp.SurfaceProperties_s(getattr(face, "wrapped", face), props)
    else:
        BRepGProp.SurfaceProperties_s(getattr(face, "wrapped", face), props, eps)
    return props.Mass()


def edges_per_wire(face) -> list[int]:
    out = []
    wires = TopExp_Explorer(getattr(face, "wrapped", face), TopAbs_WIRE)
    while wires.More():
        n, edges = 0, TopExp_Explorer(wires.Current(), TopAbs_EDGE)
        while edges.More():
            n, _ = n + 1, edges.Next()
        out.append(n)
        wires.Next()
    return sorted(out)


def max_edge_tolerance(face) -> float:
    tol, edges = 0.0, TopExp_Explorer(face, TopAbs_EDGE)
    while edges.More():
        tol = max(tol, BRep_Tool.Tolerance_s(TopoDS.Edge_s(edges.Current())))
        edges.Next()
    return tol


def check_round_trip(face, rtol: float = AREA_RTOL, stats: dict | None = None,
                     ours_rtol: float | None = AREA_RTOL) -> TrimmedSurface | BSplineSurface:
    """from_occ then make_face: the same face, or the untrimmed surface of an untrimmed face."""
    ours = from_occ(face)
    if isinstance(ours, BSplineSurface):
        assert edges_per_wire(face)[:1] == edges_per_wire(face) and len(edges_per_wire(face)) == 1
        return ours
    occ = getattr(face, "wrapped", face)
    rebuilt = make_face(ours)
    a0, a1 = occ_area(occ), occ_area(rebuilt)
    back = from_occ(rebuilt)  # the same surface (bit for bit) and the same loops came back
    assert back.surface == ours.surface and sorted(back.n_edges) == sorted(ours.n_edges)
    (u0, u1), (v0, v1) = ours.domain
    grid = np.meshgrid(np.linspace(u0, u1, 37), np.linspace(v0, v1, 41), indexing="ij")
    a, b = ours.classify(*grid), back.classify(*grid)
    assert np.array_equal(a[(a != 0) & (b != 0)], b[(a != 0) & (b != 0)])
    try:
        area = ours.area()
    except ToleranceError:
        area = ours.area(rtol=1e-7)  # reported below as not converged to 1e-12
        if stats is not None:
            stats["unconverged"] = True
    if ours_rtol is not None:
        assert abs(area - a0) <= ours_rtol * a0, (a0, area)
    mapped = any(parameter_maps(ours.surface, BRep_Tool.Surface_s(occ), BRepTools.UVBounds_s(occ)))
    if mapped:  # a rational surface now: OCC's quadrature must be pushed (OCC_PRECISE_EPS)
        a1 = occ_area(rebuilt, OCC_PRECISE_EPS)
    assert abs(a1 - a0) <= rtol * a0, (a0, a1)
    if stats is not None:
        stats.update(ours=abs(area - a0) / a0, occ=abs(a1 - a0) / a0, mapped=mapped)
    assert edges_per_wire(rebuilt) == edges_per_wire(occ)
    assert len(ours.loops) == len(edges_per_wire(occ))
    assert BRepCheck_Analyzer(rebuilt).IsValid()
    assert rebuilt.Orientation() == occ.Orientation()
    assert max_edge_tolerance(rebuilt) <= 1e-5 * max(1.0, np.sqrt(a0))
    return ours


@pytest.fixture(scope="module")
def machined():
    """Holes through a box, a spherical pocket (poles, seams, intersection p-curves on analytic
    surfaces), a boss: planes, cylinders and a sphere, FORWARD and REVERSED faces."""
    part = bd.Box(10, 8, 6) - bd.Cylinder(2, 20) - bd.Pos(3, 0, 0) * bd.Sphere(2.5)
    return part + bd.Pos(0, 0, 3) * bd.Cylinder(3, 3)


@pytest.mark.slow
def test_every_face_of_a_machined_part_round_trips(machined):
    kinds = {"trimmed": 0, "untrimmed": 0}
    for face in machined.faces():
        ours = check_round_trip(face)
        kinds["trimmed" if isinstance(ours, TrimmedSurface) else "untrimmed"] += 1
    assert kinds["trimmed"] >= 8 and kinds["untrimmed"] >= 3, kinds


def test_reversed_faces_keep_their_orientation(machined):
    reversed_faces = [f for f in machined.faces() if f.wrapped.Orientation().name == "TopAbs_REVERSED"]
    assert reversed_faces
    for face in reversed_faces:
        ours = from_occ(face)
        if isinstance(ours, TrimmedSurface):
            assert ours.reversed
            assert to_face(ours).wrapped.Orientation() == face.wrapped.Orientation()


def test_sphere_pocket_keeps_poles_and_seam(machined):
    sphere = next(f for f in machined.faces() if f.geom_type.name == "SPHERE")
    ours = check_round_trip(sphere)
    rebuilt = make_face(ours)
    degenerated, edges = 0, TopExp_Explorer(rebuilt, TopAbs_EDGE)
    while edges.More():
        degenerated += BRep_Tool.Degenerated_s(TopoDS.Edge_s(edges.Current()))
        edges.Next()
    original, edges = 0, TopExp_Explorer(sphere.wrapped, TopAbs_EDGE)
    while edges.More():
        original += BRep_Tool.Degenerated_s(TopoDS.Edge_s(edges.Current()))
        edges.Next()
    assert degenerated == original >= 2


def test_issue_example_face_with_one_hole_survives():
    """The issue: a face with one hole came back untrimmed (area of the whole patch)."""
    pts = [[bd.Vector(x, y, 0.3 * np.sin(x) * np.cos(y)) for y in np.linspace(0, 4.4, 5)] for x in np.linspace(0, 4.3, 5)]
    patch = bd.Face.make_surface_from_array_of_points(pts)
    holed = patch - bd.Pos(2.2, 2.1, 0) * bd.Cylinder(0.86, 4)
    face = holed.faces()[0] if hasattr(holed, "faces") else holed
    untrimmed = occ_area(patch.wrapped)
    ours = check_round_trip(face)
    assert isinstance(ours, TrimmedSurface) and len(ours.inner) == 1
    assert occ_area(to_face(ours).wrapped) < untrimmed - 2.0  # the hole (pi 0.86^2 = 2.3) is there
    plain = from_occ(face, trims=False)
    assert isinstance(plain, BSplineSurface) and plain == ours.surface


def test_untrimmed_faces_still_give_the_surface():
    box = bd.Box(2, 3, 4)
    for face in box.faces():
        assert isinstance(from_occ(face), BSplineSurface)
    cyl = bd.Cylinder(1, 2)
    side = [f for f in cyl.faces() if f.geom_type.name == "CYLINDER"]
    caps = [f for f in cyl.faces() if f.geom_type.name == "PLANE"]
    assert isinstance(from_occ(side[0]), BSplineSurface)  # seam + two circles: the whole UV box
    for cap in caps:  # a disc is a plane trimmed by a circle
        disc = check_round_trip(cap)
        assert isinstance(disc, TrimmedSurface) and disc.n_edges == (1,)
        assert disc.area() == pytest.approx(np.pi, rel=1e-13)
    assert all(isinstance(from_occ(f), BSplineSurface) for f in bd.Sphere(1).faces())


def test_step_round_trip_of_a_rebuilt_face(tmp_path, machined):
    from occsurf.bridge import read_step

    face = max(machined.faces(), key=lambda f: len(edges_per_wire(f)))
    rebuilt = to_face(from_occ(face))
    path = tmp_path / "rebuilt.step"
    bd.export_step(rebuilt, str(path))
    model = read_step(str(path))
    assert len(model.faces) == 1
    back = model.faces[0].face
    assert abs(occ_area(back) - occ_area(face.wrapped)) <= AREA_RTOL * occ_area(face.wrapped)
    assert edges_per_wire(back) == edges_per_wire(face)
    assert isinstance(from_occ(back), TrimmedSurface)


def _occ_state(face, u: float, v: float, tol: float):
    return BRepClass_FaceClassifier(face, gp_Pnt2d(u, v), tol).State()


@given(st.lists(st.tuples(st.floats(0, 1), st.floats(0, 1)), min_size=5, max_size=40), st.integers(0, 11))
@test_settings(30)
def test_classification_agrees_with_occ(machined_faces, pts, which):
    face, ours = machined_faces[which % len(machined_faces)]
    occ = face.wrapped
    u0, u1, v0, v1 = BRepTools.UVBounds_s(occ)
    P = np.array(pts)
    uu, vv = u0 + P[:, 0] * (u1 - u0), v0 + P[:, 1] * (v1 - v0)
    mu, mv = parameter_maps(ours.surface, BRep_Tool.Surface_s(occ), (u0, u1, v0, v1))
    s = ours.surface
    a = angle_to_parameter(uu, s.knots[0], s.degree[0], s.n_poles[0]) if mu else uu
    b = angle_to_parameter(vv, s.knots[1], s.degree[1], s.n_poles[1]) if mv else vv
    diag = float(np.hypot(u1 - u0, v1 - v0))
    state = ours.classify(a, b, tol=1e-6 * diag)  # a wide band: OCC's own tolerance is coarser
    fwd = TopoDS.Face_s(occ.Oriented(TopAbs_FORWARD))
    for x, y, s_ in zip(uu, vv, state):
        occ_s = _occ_state(fwd, float(x), float(y), 1e-9)
        if s_ == ON or occ_s == TopAbs_ON:
            continue
        assert (s_ == INSIDE) == (occ_s == TopAbs_IN), (x, y, s_, occ_s)
        assert (s_ == OUTSIDE) == (occ_s == TopAbs_OUT)


@pytest.fixture(scope="module")
def machined_faces(machined):
    pairs = [(f, from_occ(f)) for f in machined.faces()]
    return [(f, t) for f, t in pairs if isinstance(t, TrimmedSurface)]


def _realdata_files():
    if not REALDATA.is_dir():
        return []
    return sorted(p for p in REALDATA.iterdir() if p.suffix.lower() in (".step", ".stp", ".iges", ".igs"))


@pytest.mark.slow
@pytest.mark.skipif(not _realdata_files(), reason=f"no real data at {REALDATA}")
@pytest.mark.parametrize("path", _realdata_files(), ids=lambda p: p.name)
def test_every_real_face_round_trips(path):
    """Every face of the public models: from_occ, make_face, the same face (see check_round_trip);
    the numbers are printed (pytest -s) for the README."""
    from occsurf.bridge import read_iges, read_step

    model = (read_step if path.suffix.lower() in (".step", ".stp") else read_iges)(str(path))
    n_trimmed, n_wires, ours_err, occ_err, failures = 0, 0, 0.0, {False: 0.0, True: 0.0}, []
    off, unconverged = [], 0
    for f in model.faces:
        stats: dict = {}
        try:
            ours = check_round_trip(f.face, stats=stats, ours_rtol=None)
        except Exception as err:  # noqa: BLE001 - collected and reported together
            failures.append(f"face {f.index} ({f.surface_type}): {type(err).__name__}: {err}")
            continue
        if isinstance(ours, BSplineSurface):
            n_wires += 1
            assert f.trimmed is None
            continue
        n_trimmed += 1
        n_wires += len(ours.loops)
        ours_err = max(ours_err, stats["ours"])
        unconverged += stats.get("unconverged", False)
        if stats["ours"] > AREA_RTOL:
            off.append(f"{f.index}: {stats['ours']:.1e}")
        occ_err[stats["mapped"]] = max(occ_err[stats["mapped"]], stats["occ"])
        assert f.trimmed is not None and f.trimmed.n_edges == ours.n_edges  # ImportedFace.trimmed
    print(f"\n{path.name}: {len(model.faces)} faces, {n_trimmed} trimmed, {n_wires} wires; area error max: "
          f"ours {ours_err:.1e}, OCC's of the rebuilt face {occ_err[False]:.1e} (same parameters), "
          f"{occ_err[True]:.1e} (converted circular directions, OCC_PRECISE_EPS); {len(failures)} failures; our area beyond "
          f"1e-9 of OCC's on {len(off)} faces ({', '.join(off)}), not converged to 1e-12 on {unconverged}")
    assert not failures, "\n".join(failures[:20])
    # Our area against OCC's BRepGProp of the original: on linkrods' blend faces (B-splines of degree
    # 6 x 10 with 81 poles) the two part by up to 4e-6, and OCC's is the unconverged one there: on face
    # 13 OCC gives 0.0400099398 / 0.0400098648 / 0.0400106913 for eps = 1e-6 / 1e-9 / 1e-12 (2e-5 apart),
    # ours 0.0400106767 agrees with itself to 1e-15 from 1 to 128 Gauss pieces per span. Elsewhere
    # (the screw, the bearing but one tiny face) the two agree to 1e-12.
    assert ours_err <= 1e-5


def _straight_trim_face(surface, corners):
    """A face of ``surface`` bounded by straight p-curves through the ``(u, v)`` corners (exact edges:
    no boolean, no approximated intersection), so that its area has a closed form."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeEdge, BRepBuilderAPI_MakeFace, BRepBuilderAPI_MakeWire
    from OCP.BRepLib import BRepLib
    from OCP.GCE2d import GCE2d_MakeSegment

    wire = BRepBuilderAPI_MakeWire()
    for a, b in zip(corners, corners[1:] + corners[:1]):
        seg = GCE2d_MakeSegment(gp_Pnt2d(*a), gp_Pnt2d(*b)).Value()
        wire.Add(BRepBuilderAPI_MakeEdge(seg, surface, seg.FirstParameter(), seg.LastParameter()).Edge())
    face = BRepBuilderAPI_MakeFace(surface, wire.Wire(), True).Face()
    BRepLib.BuildCurves3d_s(face)
    assert BRepCheck_Analyzer(face).IsValid()
    return face


def _closed_form_faces():
    """``{name: (face, area)}``: a cylinder, a sphere and a cone (tilted frame) each trimmed by a
    p-curve that is a slanted line in (u, v) -- resampled by the conversion, as intersection curves
    are -- with the area integrated by hand. Cylinder ``dA = r du dv``, sphere ``R^2 cos v du dv``,
    cone ``(R + v sin a) du dv`` (OCC's parametrisations); ``u`` in ``[0, D]``, ``v`` from the
    straight bottom side to ``h0 + s u``."""
    import math

    from OCP.Geom import Geom_ConicalSurface, Geom_CylindricalSurface, Geom_SphericalSurface
    from OCP.gp import gp_Ax3, gp_Dir, gp_Pnt

    ax = gp_Ax3(gp_Pnt(0.3, -0.2, 0.1), gp_Dir(0.2, 0.1, 1.0))
    D, h0, s = 2.0, 1.5, 0.8
    r = 2.0
    cyl = _straight_trim_face(Geom_CylindricalSurface(ax, r), [(0, 0), (D, 0), (D, h0 + s * D), (0, h0)])
    R, v0, ss = 2.5, -0.6, 0.5
    sph = _straight_trim_face(Geom_SphericalSurface(ax, R), [(0, v0), (D, v0), (D, v0 + ss * D)])
    Rc, half = 1.2, 0.35
    cone = _straight_trim_face(Geom_ConicalSurface(ax, half, Rc), [(0, 0), (D, 0), (D, h0 + s * D), (0, h0)])
    H0, H1 = h0, h0 + s * D
    return {
        "cylinder": (cyl, r * (h0 * D + s * D * D / 2)),
        "sphere": (sph, R * R * ((math.cos(v0) - math.cos(v0 + ss * D)) / ss - D * math.sin(v0))),
        "cone": (cone, (Rc * (H1**2 - H0**2) / 2 + math.sin(half) * (H1**3 - H0**3) / 6) / s),
    }


@pytest.mark.parametrize("name", ["cylinder", "sphere", "cone"])
def test_rebuilt_rational_faces_have_the_exact_area(name):
    """The issue's 1e-9 area criterion on faces converted from cylinders, spheres and cones holds to
    1e-12 when the area is measured precisely: against the closed form, our Green + Gauss-Legendre
    area of the converted face (which make_face rebuilds bit for bit) is within 3e-14, and OCC's
    adaptive BRepGProp of the rebuilt face with OCC_PRECISE_EPS within 3e-13 (at OCC_AREA_EPS it is
    0.7-1.0e-9 off: its quadrature, test_occ_area_quadrature_of_rational_faces_is_biased). Bound:
    1e-12, the criterion asked of a precise measurement; OCC's area of the analytic original is exact
    (~1e-16: 1e-13 bound)."""
    face, exact = _closed_form_faces()[name]
    ours = from_occ(face)
    assert isinstance(ours, TrimmedSurface)
    assert any(parameter_maps(ours.surface, BRep_Tool.Surface_s(face), BRepTools.UVBounds_s(face)))  # resampled
    rebuilt = make_face(ours)
    assert abs(occ_area(face) - exact) <= 1e-13 * exact
    assert abs(ours.area() - exact) <= 1e-12 * exact
    assert abs(occ_area(rebuilt, OCC_PRECISE_EPS) - exact) <= 1e-12 * exact


@pytest.mark.slow
def test_rebuilt_machined_faces_keep_their_area_to_1e12(machined):
    """The machined part's faces on converted cylinders and the sphere (intersection p-curves, no
    closed form): our area and OCC's precise area of the rebuilt face both equal OCC's area of the
    analytic original to 1e-12 (measured 3.6e-13 and 7.4e-13 at worst), where OCC's default
    adaptive measure of the rebuilt face was 1.0-1.2e-9 off."""
    n = 0
    for f in machined.faces():
        ours = from_occ(f)
        occ = f.wrapped
        if not (isinstance(ours, TrimmedSurface)
                and any(parameter_maps(ours.surface, BRep_Tool.Surface_s(occ), BRepTools.UVBounds_s(occ)))):
            continue
        n += 1
        a0 = occ_area(occ)
        assert abs(occ_area(occ, OCC_PRECISE_EPS) - a0) <= 1e-14 * a0  # the analytic original: converged
        assert abs(ours.area() - a0) <= 1e-12 * a0, (f.geom_type, ours.area(), a0)
        assert abs(occ_area(make_face(ours), OCC_PRECISE_EPS) - a0) <= 1e-12 * a0, f.geom_type
    assert n >= 3


@pytest.mark.parametrize("eps", [None, OCC_AREA_EPS], ids=["default", "eps=1e-13"])
@pytest.mark.xfail(strict=True, raises=AssertionError, reason="OCC's area quadrature (BRepGProp.SurfaceProperties_s: its default Gauss "
                   "scheme, and the adaptive one at eps=1e-13) under-integrates rational B-spline faces whose "
                   "p-curves are not iso-lines: 1.0-1.2e-9 (eps=1e-13) and up to 1.9e-3 (default) off the same "
                   "face measured with eps=1e-19, while the error estimate it returns says 1e-16")
def test_occ_area_quadrature_of_rational_faces_is_biased(machined, eps):
    """The rebuilt faces of the machined part and the closed-form faces, OCC's area at its default
    settings against its precise one: within the issue's 1e-9 if OCC's quadrature were converged."""
    faces = [v[0] for v in _closed_form_faces().values()] + [f.wrapped for f in machined.faces()]
    worst = 0.0
    for face in faces:
        ours = from_occ(face)
        if not isinstance(ours, TrimmedSurface):
            continue
        rebuilt = make_face(ours)
        precise = occ_area(rebuilt, OCC_PRECISE_EPS)
        worst = max(worst, abs(occ_area(rebuilt, eps) - precise) / precise)
    assert worst <= AREA_RTOL, worst


def test_bad_input_is_refused_by_the_bridge():
    from occsurf.algorithms import BSplineCurve
    from occsurf.algorithms.errors import InvalidGeometryError

    P = np.zeros((2, 2, 2))
    P[1, :, 0] = 1
    P[:, 1, 1] = 1
    flat = BSplineSurface((1, 1), ([0, 0, 1, 1], [0, 0, 1, 1]), P)  # 2-D: no OCC face
    corners = [(0, 0), (1, 0), (1, 1), (0, 1)]
    loop = [BSplineCurve(1, [0, 0, 1, 1], [corners[i], corners[(i + 1) % 4]]) for i in range(4)]
    with pytest.raises(InvalidGeometryError, match="3-D"):
        make_face(TrimmedSurface(flat, loop))
    with pytest.raises(InvalidGeometryError, match="tol"):
        make_face(TrimmedSurface(flat, loop), tol=-1.0)


def test_write_step_and_iges_of_trimmed_surfaces(tmp_path, machined):
    """write_step / write_iges take TrimmedSurface objects; read back, each face has the area and
    wires it had (the sphere pocket is left out of the STEP check: OCC's STEP round trip of the
    *original* analytic face loses 45 % of it too, see test_occ_step_round_trip_of_sphere_pocket)."""
    from occsurf.bridge import read_iges, read_step, write_iges, write_step

    faces = [f for f in machined.faces() if isinstance(from_occ(f), TrimmedSurface)]
    ours = [from_occ(f) for f in faces]
    for writer, reader, name, rtol in ((write_step, read_step, "t.step", AREA_RTOL),
                                       (write_iges, read_iges, "t.igs", 1e-8)):  # IGES: ~10 digits
        path = tmp_path / name
        writer(str(path), ours)
        model = reader(str(path))
        assert len(model.faces) == len(ours)
        for f, t, back in zip(faces, ours, model.faces):
            if writer is write_step and f.geom_type.name == "SPHERE":
                continue
            a0 = occ_area(f.wrapped)
            a1 = occ_area(back.face, OCC_PRECISE_EPS)  # rational B-spline faces now (OCC_PRECISE_EPS)
            assert abs(a1 - a0) <= rtol * a0, (name, f.geom_type, a0, a1)
            assert edges_per_wire(back.face) == edges_per_wire(f.wrapped)
            assert back.trimmed is not None and sorted(back.trimmed.n_edges) == sorted(t.n_edges)


@pytest.mark.xfail(strict=True, reason="OCC defect: the sphere pocket (poles, seam, intersection edges) "
                   "loses 45 % of its area through STEP write + read, for the analytic original too")
def test_occ_step_round_trip_of_sphere_pocket(tmp_path, machined):
    from occsurf.bridge import read_step

    sphere = next(f for f in machined.faces() if f.geom_type.name == "SPHERE")
    path = tmp_path / "sphere.step"
    bd.export_step(sphere, str(path))
    back = read_step(str(path)).faces[0].face
    assert abs(occ_area(back) - occ_area(sphere.wrapped)) <= AREA_RTOL * occ_area(sphere.wrapped)


@pytest.mark.slow
def test_imported_face_trimmed_is_lazy_cached_and_right(tmp_path, machined, monkeypatch):
    """ImportedFace.trimmed is built on first access (reading converts no loops), once per face,
    shared by dataclasses.replace copies, pickles as its value, and equals the eager conversion; the
    same through read_step(isolated=True), which rebuilds the faces from the worker's BRep."""
    import dataclasses
    import pickle

    from occsurf.bridge import read_step
    from occsurf.bridge.exchange import model as imported  # where ImportedFace builds its trims

    path = tmp_path / "machined.step"
    bd.export_step(machined, str(path))
    calls = []
    build = imported._build_trimmed
    monkeypatch.setattr(imported, "_build_trimmed", lambda *a: calls.append(1) or build(*a))
    for isolated in (False, True):
        calls.clear()
        model = read_step(str(path), isolated=isolated)
        assert calls == [] and len(model.faces) == len(machined.faces())
        copies = [dataclasses.replace(f, color=(1.0, 0.0, 0.0, 1.0)) for f in model.faces]
        n_trimmed = 0
        for f, copy in zip(model.faces, copies):
            t = f.trimmed
            assert copy.trimmed is t and f.trimmed is t  # cached, shared with the copy
            assert (t, f.natural) == build(f.face, f.surface, f.occ_surface)  # what reading used to build eagerly
            assert isinstance(from_occ(f.face), TrimmedSurface) == (t is not None)
            assert f.natural is (t is None) and copy.natural is f.natural  # every loop converts here
            if t is not None:
                n_trimmed += 1
                a0 = occ_area(f.face)
                assert abs(t.area() - a0) <= AREA_RTOL * a0, (f.index, t.area(), a0)
                assert pickle.loads(pickle.dumps(f._trimmed)) == t
        assert len(calls) == len(model.faces) - sum(f.surface is None for f in model.faces)
        assert n_trimmed >= 5
    fresh = read_step(str(path)).faces  # pickled before any access: converted then
    k = next(i for i, f in enumerate(fresh) if isinstance(from_occ(f.face), TrimmedSurface))
    assert pickle.loads(pickle.dumps(fresh[k]._trimmed)) == fresh[k].trimmed
    manual = dataclasses.replace(fresh[k], _trimmed=None)  # a value given by hand is kept as is
    assert manual.trimmed is None and fresh[k].trimmed is not None


@pytest.mark.slow
@pytest.mark.skipif(not (REALDATA / "occt__linkrods.step").is_file(), reason=f"no occt__linkrods.step in {REALDATA}")
def test_area_converges_beside_a_near_singular_point():
    """linkrods' blend faces 25 and 26: |S_u x S_v| falls to ~1e-6 (of 0.27) in the parameter box,
    outside the face. Green's inner integrals anchored at u0 crossed that kink and area() raised
    ToleranceError at rtol 1e-12; anchored at the far end of the loops' u range they converge. The
    value agrees with the u0-anchored quadrature at 64 pieces per span, and with OCC's
    BRepGProp to its own (unconverged there, see test_every_real_face_round_trips) 1e-4."""
    from occsurf.algorithms import tolerances
    from occsurf.bridge import read_step

    model = read_step(str(REALDATA / "occt__linkrods.step"))
    for face in (model.faces[25], model.faces[26]):
        t = face.trimmed
        a = t.area()  # raised ToleranceError before
        assert abs(a - occ_area(face.face)) <= 1e-4 * a
        (u0, _), _ = t.surface.domain
        assert t._area_anchor() != u0
        if face.index == 25:  # u0-anchored, 64 pieces per span (level 6): 5e-10 from ours, moving by 2e-10
            from occsurf.algorithms.kernel import trimmed  # (levels 2-3 agree to 9e-10, 3e-8 off)

            u0 = t.surface.domain[0][0]
            seen: dict[tuple[int, float], float] = {}  # (pieces, anchor) -> sum over the loops' p-curves
            green = trimmed.green_area

            def recorded(surface, c, pieces, anchor, seen=seen, green=green):
                value = green(surface, c, pieces, anchor)
                seen[pieces, anchor] = seen.get((pieces, anchor), 0.0) + value
                return value

            with tolerances.override(TRIM_AREA_SINGULAR=0.0), pytest.raises(ToleranceError, match="TRIM_AREA_LEVELS"), \
                    pytest.MonkeyPatch.context() as mp:
                mp.setattr(trimmed, "green_area", recorded)  # where area() looks it up
                t.area()  # the override turns the anchor choice off (u0): the old failure
            # its last level is the u0-anchored quadrature at 64 pieces per span (computed once, not twice)
            assert int(tolerances.TRIM_AREA_LEVELS) == 6 and set(seen) == {(1 << k, u0) for k in range(7)}
            uniform = seen[64, u0]
            assert abs(uniform - a) <= 1e-9 * a, (uniform, a)



@pytest.mark.skipif(not (REALDATA / "occt__linkrods.step").is_file(), reason=f"no occt__linkrods.step in {REALDATA}")
def test_the_area_anchor_from_grid_partials_is_the_point_by_point_one():
    """``_area_anchor`` takes |S_u x S_v| on its 129 x 129 grid from ``derivatives_grid`` (~7x faster
    than point by point): on every trimmed spline face of linkrods, faces 25 and 26 among them (anchored away
    from u0), the anchor is the one the point-by-point partials give, bit for bit."""
    from occsurf.algorithms import tolerances
    from occsurf.bridge import read_step

    model = read_step(str(REALDATA / "occt__linkrods.step"))
    moved = 0
    faces = [f for f in model.faces if f.trimmed is not None]  # (planes and such: no trimmed spline)
    assert len(faces) == 28
    for face in faces:
        t = face.trimmed
        (u0, u1), (v0, v1) = t.surface.domain
        U, W = np.meshgrid(np.linspace(u0, u1, 129), np.linspace(v0, v1, 129), indexing="ij")
        D = t.surface.derivatives(U.ravel(), W.ravel(), 1)
        J = np.linalg.norm(np.cross(D[:, 1, 0], D[:, 0, 1]), axis=-1)
        if J.min() >= tolerances.TRIM_AREA_SINGULAR * J.max():
            expected = float(u0)
        else:
            us = np.concatenate([P[:, 0] for P in t.polylines()])
            lo, hi, u_star = float(us.min()), float(us.max()), float(U.ravel()[np.argmin(J)])
            expected = lo if abs(lo - u_star) > abs(hi - u_star) else hi
            moved += 1
        assert t._area_anchor() == expected, face.index
    assert moved >= 2  # faces 25 and 26 at least

@pytest.mark.skipif(not (REALDATA / "occt__linkrods.step").is_file(), reason=f"no occt__linkrods.step in {REALDATA}")
def test_a_face_on_a_rectangle_of_its_surface_is_trimmed_by_it():
    """linkrods' faces 19, 23 and 36 have one loop on the sides of their UV box, but the box is a
    rectangle inside their B-spline surface's domain (face 19: u in [-0.53, 0.53] of [-pi/2, pi/2]).
    ``from_occ(face)`` returned the whole surface for them (and ``ImportedFace.trimmed`` was None):
    now a TrimmedSurface on that rectangle, ``natural`` False. Its area equals OCC's adaptive
    quadrature (eps 1e-12) to 1e-12 relative (OCC's default scheme is 5.7e-4 off on face 19), and
    classification keeps the rectangle. The faces that are natural span their surface's domain."""
    from occsurf.bridge import read_step

    model = read_step(REALDATA / "occt__linkrods.step")
    for k in (19, 23, 36):
        f = model.faces[k]
        u0, u1, v0, v1 = BRepTools.UVBounds_s(f.face)
        (s0, s1), (t0, t1) = f.surface.domain
        assert max(u0 - s0, s1 - u1, v0 - t0, t1 - v1) > 1e-3 * (s1 - s0), k  # a rectangle inside
        t = f.trimmed
        assert isinstance(t, TrimmedSurface) and f.natural is False and isinstance(from_occ(f.face), TrimmedSurface)
        props = GProp_GProps()
        BRepGProp.SurfaceProperties_s(f.face, props, 1e-12)
        assert abs(t.area() - props.Mass()) <= 1e-12 * props.Mass(), (k, t.area(), props.Mass())
        du, dv = 1e-3 * (u1 - u0), 1e-3 * (v1 - v0)
        uu = np.array([0.5 * (u0 + u1), u0 - du, u1 + du, 0.5 * (u0 + u1)])
        vv = np.array([0.5 * (v0 + v1), 0.5 * (v0 + v1), 0.5 * (v0 + v1), v1 + dv])
        assert t.classify(uu, vv).tolist() == [INSIDE, OUTSIDE, OUTSIDE, OUTSIDE]
    natural = [f for f in model.faces if f.natural]
    assert len(natural) >= 5
    for f in natural:
        box = BRepTools.UVBounds_s(f.face)
        (a0, a1), (b0, b1) = f.surface.domain
        assert np.allclose(box, (a0, a1, b0, b1), rtol=0, atol=1e-9 * max(1.0, np.hypot(a1 - a0, b1 - b0)))
