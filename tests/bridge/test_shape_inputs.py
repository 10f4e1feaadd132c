"""Every bridge function that takes faces or a model takes the objects build123d and cadquery users hold
(issue 16): Solids, Shells, Compounds, Faces, a cadquery Workplane and Assembly, a build123d builder.

One coercion helper does it (:mod:`occsurf.bridge.conversion.shapes`); :data:`CONSUMERS` lists the
functions, and each is fed a build123d and a cadquery object of the same model. The expected values
come from OCC on the underlying ``TopoDS`` shape (face counts, areas) or from the function's own
result on the plain ``TopoDS_Shape``: the object wrapper must change nothing.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

bd = pytest.importorskip("build123d")
cq = pytest.importorskip("cadquery")

from OCP.TopoDS import TopoDS_Shape  # noqa: E402

from occsurf import bridge  # noqa: E402
from occsurf.algorithms import BSplineSurface  # noqa: E402
from occsurf.algorithms.errors import InvalidGeometryError  # noqa: E402
from occsurf.bridge.conversion.shapes import as_faces, as_shape  # noqa: E402
from occsurf.bridge.exchange.object_import import as_model  # noqa: E402

BRIDGE = Path(__file__).resolve().parents[2] / "bridge"


def _b3d_objects():
    box = bd.Box(3, 4, 5)
    solid = box.solids()[0]
    with bd.BuildPart() as builder:
        bd.Box(3, 4, 5)
    return {
        "b3d Part": (box, 6),
        "b3d Solid": (solid, 6),
        "b3d Shell": (bd.Shell(solid.faces()), 6),
        "b3d Face": (solid.faces()[0], 1),
        "b3d Compound": (bd.Compound([solid, solid.moved(bd.Location((10, 0, 0)))]), 12),
        "b3d BuildPart": (builder, 6),
    }


def _cq_objects():
    wp = cq.Workplane().box(3, 4, 5)
    solid = wp.val()
    assy = cq.Assembly(name="top").add(wp, name="a").add(wp, name="b", loc=cq.Location((10, 0, 0)))
    return {
        "cq Workplane": (wp, 6),
        "cq Solid": (solid, 6),
        "cq Shell": (cq.Shell.makeShell(solid.Faces()), 6),
        "cq Face": (solid.Faces()[0], 1),
        "cq Compound": (cq.Compound.makeCompound([solid, solid.moved(cq.Location((10, 0, 0)))]), 12),
        "cq Assembly": (assy, 12),
    }


OBJECTS = {**_b3d_objects(), **_cq_objects()}
IDS = sorted(OBJECTS)


@pytest.fixture(params=IDS)
def obj(request):
    return OBJECTS[request.param]


def test_as_shape_unwraps_every_kind(obj):
    thing, n_faces = obj
    shape = as_shape(thing)
    assert isinstance(shape, TopoDS_Shape) and not shape.IsNull()
    assert len(as_faces(thing)) == n_faces


# ---------------------------------------------------------------------------------- the consumers
def _from_occ(thing, n):
    out = bridge.from_occ(thing)
    surfaces = [out] if n == 1 and isinstance(out, BSplineSurface) else out
    assert len(surfaces) == n and all(isinstance(s, BSplineSurface) for s in surfaces)


def _inspect(thing, n):
    reports = bridge.inspect_model(thing, samples=3)
    assert len(reports) == n and all(r.error is None for r in reports)


def _check_model(thing, n):
    from occsurf.bridge.quality.report import check_model

    report = check_model(thing, samples=5, flags=False, edges=n > 1)
    assert len(report.faces) == n


def _edge_continuity(thing, n):
    result = bridge.edge_continuity(thing, samples=5, loose=False)
    assert len(result) == (0 if n == 1 else 12 * n // 6)  # a box has 12 edges


def _write_read(thing, n, tmp_path, fmt):
    path = tmp_path / f"out.{fmt}"
    (bridge.write_step if fmt == "step" else bridge.write_iges)(path, thing)
    model = (bridge.read_step if fmt == "step" else bridge.read_iges)(path)
    assert len(model.faces) == n
    area = sum(bd.Face(f.face).area for f in model.faces)
    assert abs(area - sum(bd.Face(f).area for f in as_faces(thing))) < 1e-9 * area


def _deviation(thing, n):
    face = as_faces(thing)[0]
    ours = bridge.from_occ(face)
    dev = bridge.surface_deviation(ours, thing if n == 1 else bd.Face(face), samples=5)
    assert dev.max_point_rel < 1e-14


def _mesh(thing, n):
    from occsurf.bridge.rendering.lighting import mesh_of_model

    P, T, N = mesh_of_model(thing)
    assert P.shape[1] == 3 and len(T) >= 2 * n and np.allclose(np.linalg.norm(N, axis=1), 1.0)


def _fill(thing, n):
    result = bridge.fill_model(thing, compare_occ=False)
    if n == 1:  # a lone face: its boundary is the only free loop (filled, or refused with a reason)
        assert len(result.holes) == 1 and (result.holes[0].status == "filled" or result.holes[0].reason)
    else:  # closed boxes: nothing to fill, sewn as they are
        assert result.holes == [] and result.free_loops_after == 0


#: Every bridge function that takes faces or a model, with what it must give.
CONSUMERS = {
    "from_occ": _from_occ,
    "inspect_model": _inspect,
    "check_model": _check_model,
    "edge_continuity": _edge_continuity,
    "write_step": lambda t, n, tmp: _write_read(t, n, tmp, "step"),
    "write_iges": lambda t, n, tmp: _write_read(t, n, tmp, "iges"),
    "surface_deviation": _deviation,
    "mesh_of_model": _mesh,
    "fill_model": _fill,
}


@pytest.mark.parametrize("consumer", sorted(CONSUMERS))
def test_every_consumer_takes_build123d_and_cadquery_objects(consumer, obj, tmp_path):
    thing, n = obj
    fn = CONSUMERS[consumer]
    if consumer.startswith("write_"):
        fn(thing, n, tmp_path)
    else:
        fn(thing, n)


def test_wrapper_changes_nothing_in_inspect():
    """inspect_model on a build123d Solid equals inspect_model on its TopoDS_Shape."""
    solid = bd.Box(3, 4, 5).solids()[0]
    a = bridge.inspect_model(solid, samples=4)
    b = bridge.inspect_model(solid.wrapped, samples=4)
    c = bridge.inspect_model(cq.Solid(solid.wrapped), samples=4)
    assert a == b == c


def _open_ball() -> bd.Shell:
    """A sphere of radius 5 cut into 8 faces (planes x = 0, y = 0, z = 3), without the 4 above z = 3:
    a closed body with one 4-sided hole whose neighbours are smooth."""
    faces = [bd.Sphere(5).faces()[0]]
    for plane in (bd.Plane.XZ, bd.Plane.YZ, bd.Plane.XY.offset(3)):
        faces = [g for f in faces for half in f.split(plane, keep=bd.Keep.BOTH) for g in half.faces()]
    assert len(faces) == 8
    return bd.Shell([f for f in faces if f.center().Z < 3])


def test_fill_model_returns_a_build123d_or_cadquery_solid():
    """The hole filled, the shell closed: a Solid of the user's kind, its volume OCC's of the same shell."""
    from OCP.BRepGProp import BRepGProp
    from OCP.GProp import GProp_GProps

    ball = _open_ball()
    result = bridge.fill_model(ball, compare_occ=False, as_="build123d")
    assert [h.status for h in result.holes] == ["filled"] and result.free_loops_after == 0
    assert isinstance(result.shape, bd.Solid) and result.shape.is_valid
    plain = bridge.fill_model(ball, compare_occ=False)
    assert isinstance(plain.shape, TopoDS_Shape)
    props = GProp_GProps()
    BRepGProp.VolumeProperties_s(bd.Solid(bd.Shell(plain.shape)).wrapped, props)
    assert abs(result.shape.volume - abs(props.Mass())) < 1e-9 * abs(props.Mass())
    # between the sphere without its cap (cut flat: 469.1) and the whole sphere (523.6): a G1 dome
    assert 4 / 3 * np.pi * 125 - np.pi * 4 * 13 / 3 < result.shape.volume < 4 / 3 * np.pi * 125
    cq_result = bridge.fill_model(cq.Shell(ball.wrapped), compare_occ=False, as_="cadquery")
    assert isinstance(cq_result.shape, cq.Solid) and cq_result.shape.isValid()
    assert abs(cq_result.shape.Volume() - result.shape.volume) < 1e-9 * result.shape.volume
    with pytest.raises(InvalidGeometryError, match="as_"):
        bridge.fill_model(ball, as_="occ")


@pytest.mark.slow
def test_refill_takes_build123d_and_cadquery_shells():
    """refill_model / refill_faces on the same sphere as a build123d Shell, a cadquery Shell and a
    TopoDS_Shell: the same faces removed, the same outcome."""
    from occsurf.bridge.modeling.refill import refill_faces, refill_model

    faces = [bd.Sphere(5).faces()[0]]
    for plane in (bd.Plane.XZ, bd.Plane.YZ, bd.Plane.XY.offset(3)):
        faces = [g for f in faces for half in f.split(plane, keep=bd.Keep.BOTH) for g in half.faces()]
    ball = bd.Shell(faces)
    cap = [i for i, f in enumerate(ball.faces()) if f.center().Z > 3]
    assert len(cap) == 4
    outcomes = []
    for thing in (ball, cq.Shell(ball.wrapped), ball.wrapped):
        reports, _ = refill_model(thing, cap, compare_occ=False)
        assert len(reports) == 1 and sorted(reports[0].faces) == cap
        outcomes.append((reports[0].status, reports[0].reason))
    assert outcomes[0] == outcomes[1] == outcomes[2]
    report, _ = refill_faces(cq.Shell(ball.wrapped), cap, compare_occ=False, check=False)
    assert (report.status, report.reason) == outcomes[0]


def test_fill_model_keeps_an_open_result_a_shell():
    """Four side faces of a box: two free loops, one taken as the outer boundary (not filled), so
    the result stays open: a Shell, not a Solid."""
    sides = [f for f in bd.Box(3, 4, 5).faces() if abs(f.normal_at().Z) < 0.5]
    result = bridge.fill_model(bd.Shell(sides), compare_occ=False, as_="build123d")
    assert sorted(h.status for h in result.holes) == ["filled", "outer"] and result.free_loops_after == 1
    assert isinstance(result.shape, bd.Shell)


@pytest.mark.parametrize("bad, match", [
    (42, "shape: expected a TopoDS_Shape"),
    (TopoDS_Shape(), "null"),
    ([], "empty"),
    (cq.Workplane(), "no shapes"),
    (bd.Compound(), "empty"),
])
def test_bad_objects_are_refused_naming_the_argument(bad, match):
    with pytest.raises(InvalidGeometryError, match=match):
        bridge.fill_model(bad)
    with pytest.raises(InvalidGeometryError):
        as_model(bad)
    from occsurf.bridge.modeling.refill import SewnModel

    with pytest.raises(InvalidGeometryError, match=match):
        SewnModel(bad)


def test_sewn_model_takes_what_refill_takes():
    """``SewnModel`` (sewn once for many refills) takes a model as read, not only its ``TopoDS_Shape``."""
    from occsurf.bridge.exchange.step_iges import read_step
    from occsurf.bridge.modeling.refill import SewnModel

    model = read_step(Path(__file__).resolve().parents[2] / "step_samples" / "loft.step")
    assert len(SewnModel(model).faces) == len(SewnModel(model.shape).faces) == len(model.faces) > 0


def test_no_bridge_module_unwraps_objects_itself():
    """Objects are unwrapped in one place, the conversions to and from them (``shapes.py``, and
    ``objects.py`` / ``object_import.py``, one module split in two): no other bridge module reads
    ``.wrapped`` or ``.vals()`` (a new consumer must call ``as_shape`` / ``as_model``)."""
    allowed = {BRIDGE / "conversion" / "shapes.py", BRIDGE / "exchange" / "objects.py",
               BRIDGE / "exchange" / "object_import.py"}
    offenders = []
    for path in BRIDGE.rglob("*.py"):
        if path in allowed:
            continue
        for k, line in enumerate(path.read_text().splitlines(), 1):
            code = line.split("#", 1)[0]
            if re.search(r"""["']wrapped["']|\.wrapped\b|\.vals\(\)""", code) and "``" not in code:
                offenders.append(f"{path.relative_to(BRIDGE)}:{k}: {line.strip()}")
    assert not offenders, "\n".join(offenders)
