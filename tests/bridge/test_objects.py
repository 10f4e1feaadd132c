"""Imported models as build123d / cadquery objects, and those objects accepted by every bridge function
(issue 16, "Python objects users already hold").

Oracles: build123d's own ``import_step`` and cadquery's ``Assembly.importStep`` on the same files
(global face positions, areas, colours), the objects the tests build themselves (labels, colours,
placements), and OCC's ``GProp`` areas. Colours are compared within 1e-6: OCC keeps colours as
32-bit floats (``Quantity_Color``), so a channel moves by up to 6e-8 through a file.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

bd = pytest.importorskip("build123d")
cq = pytest.importorskip("cadquery")

from occsurf.algorithms import BSplineSurface  # noqa: E402
from occsurf.algorithms.errors import InvalidGeometryError  # noqa: E402
from occsurf.bridge import read_iges, read_step  # noqa: E402
from occsurf.bridge.exchange.object_import import model_from_object  # noqa: E402
from occsurf.bridge.exchange.objects import shape_object, to_build123d, to_cadquery  # noqa: E402

SAMPLES = Path(__file__).resolve().parents[2] / "step_samples"
RED, BLUE, GREEN = (1.0, 0.0, 0.0, 1.0), (0.0, 0.0, 1.0, 1.0), (0.0, 1.0, 0.0, 0.5)
COLOUR_ATOL = 1e-6  # OCC stores colour channels as float32


# ------------------------------------------------------------------------------------------ models
def _plate() -> bd.Part:
    """A 10 x 20 x 2 plate with two through holes (two inner wires on its big faces)."""
    plate = bd.Box(10, 20, 2) - bd.Pos(0, 5, 0) * bd.Cylinder(2, 2) - bd.Pos(0, -5, 0) * bd.Cylinder(1.5, 2)
    return plate.solids()[0]


def _two_plates() -> bd.Compound:
    """An assembly: two instances of one plate (same TShape), labelled and coloured per instance."""
    plate = _plate()
    a = plate.moved(bd.Location((0, 0, 0)))
    a.label, a.color = "plate_a", bd.Color(*RED)
    b = plate.moved(bd.Location((30, 0, 5), (0, 0, 90)))
    b.label, b.color = "plate_b", bd.Color(*BLUE)
    assert a.wrapped.IsPartner(b.wrapped)
    return bd.Compound(label="assembly", children=[a, b])


@pytest.fixture(scope="module")
def plates_step(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("objects") / "plates.step"
    assert bd.export_step(_two_plates(), str(path))
    return path


@pytest.fixture(scope="module")
def metres_step(tmp_path_factory) -> Path:
    """The plate written in millimetres, then declared in metres (the same numbers): a plate 1000x as large."""
    path = tmp_path_factory.mktemp("objects") / "plate_m.step"
    part = _plate()
    part.label, part.color = "plate", bd.Color(*GREEN)
    assert bd.export_step(part, str(path))
    text = path.read_text()
    assert text.count("SI_UNIT(.MILLI.,.METRE.)") == 1
    path.write_text(text.replace("SI_UNIT(.MILLI.,.METRE.)", "SI_UNIT($,.METRE.)"))
    return path


@pytest.fixture(scope="module")
def cq_faces_step(tmp_path_factory) -> Path:
    """A cadquery assembly whose part has one face of another colour and a named face."""
    path = tmp_path_factory.mktemp("objects") / "faces.step"
    box = cq.Workplane().box(4, 5, 6)
    assy = cq.Assembly(name="top")
    assy.add(box, name="block", color=cq.Color(*BLUE[:3], 1.0, False))
    top = box.faces(">Z").val()
    assy["block"].addSubshape(top, name="lid", color=cq.Color(*RED[:3], 1.0, False))
    assy.export(str(path))
    return path


def _face_signature(faces) -> np.ndarray:
    """Per face (wire count, area, centre x, y, z), sorted: what a placement, a copy or a reader must
    keep. Computed by OCC on the wrapped faces (build123d or cadquery alike)."""
    from OCP.BRepGProp import BRepGProp
    from OCP.GProp import GProp_GProps
    from OCP.TopAbs import TopAbs_WIRE
    from OCP.TopExp import TopExp
    from OCP.TopTools import TopTools_IndexedMapOfShape

    rows = []
    for f in faces:
        props = GProp_GProps()
        BRepGProp.SurfaceProperties_s(f.wrapped, props)
        wires = TopTools_IndexedMapOfShape()
        TopExp.MapShapes_s(f.wrapped, TopAbs_WIRE, wires)
        rows.append((wires.Extent(), props.Mass(), *props.CentreOfMass().Coord()))
    rows.sort(key=lambda r: (r[0], round(r[1], 3), *(round(x, 3) for x in r[2:])))
    return np.array(rows)


def _assert_same_faces(a, b, rtol: float = 1e-9) -> None:
    """Same faces: wire counts exactly, areas and centres within ``rtol`` of the model's size (the
    files keep 13-17 digits)."""
    sa, sb = _face_signature(a), _face_signature(b)
    assert sa.shape == sb.shape
    np.testing.assert_array_equal(sa[:, 0], sb[:, 0])
    scale = float(np.abs(sa[:, 2:]).max() + 1.0)
    np.testing.assert_allclose(sa[:, 1], sb[:, 1], rtol=rtol)
    np.testing.assert_allclose(sa[:, 2:], sb[:, 2:], atol=rtol * scale)


def _loc(location) -> tuple[float, ...]:
    """Position and orientation (degrees) of a build123d Location."""
    return (*location.position, *location.orientation)


def _leaves_b3d(node, out=None):
    out = [] if out is None else out
    if node.children:
        for c in node.children:
            _leaves_b3d(c, out)
    else:
        out.append(node)
    return out


# ------------------------------------------------------------------------------------ build123d
def test_assembly_as_build123d_keeps_instances_names_colours_placements(plates_step):
    original = _two_plates()
    ours = read_step(plates_step, as_="build123d")
    assert isinstance(ours, bd.Compound) and ours.label == "assembly"
    assert [c.label for c in ours.children] == ["plate_a", "plate_b"]
    for mine, theirs in zip(ours.children, original.children):
        assert isinstance(mine, bd.Solid)
        np.testing.assert_allclose(tuple(mine.color), tuple(theirs.color), atol=COLOUR_ATOL)
        np.testing.assert_allclose(_loc(mine.global_location), _loc(theirs.global_location), atol=1e-12)
    # instances reference one prototype, as in the file (one product, two occurrences)
    a, b = ours.children
    assert a.wrapped.IsPartner(b.wrapped) and not a.wrapped.IsSame(b.wrapped)
    # per face: area, wire count (the holes), position
    _assert_same_faces(ours.faces(), original.faces())
    assert sorted(len(f.wires()) for f in ours.faces()).count(3) == 4  # 2 big faces x 2 instances


def test_build123d_matches_build123ds_own_importer(plates_step):
    """Same geometry, placements and colours as ``bd.import_step``; our labels are the instances'
    (build123d 0.12's importer labels every instance with the part's name: 'plate_b' twice)."""
    ours = read_step(plates_step, as_="build123d")
    theirs = bd.import_step(str(plates_step))
    _assert_same_faces(ours.faces(), theirs.faces())
    for mine, ref in zip(ours.children, theirs.children):
        np.testing.assert_allclose(tuple(mine.color), tuple(ref.color), atol=COLOUR_ATOL)
        np.testing.assert_allclose(_loc(mine.location), _loc(ref.location), atol=1e-12)
        assert mine.wrapped.IsPartner(ref.wrapped) or abs(mine.volume - ref.volume) < 1e-9 * ref.volume
    assert [c.label for c in theirs.children] == ["plate_b", "plate_b"]
    assert [c.label for c in ours.children] == ["plate_a", "plate_b"]


def test_units_flat_file_as_build123d(metres_step):
    model = read_step(metres_step)
    assert (model.unit, model.unit_scale) == ("m", 1000.0)
    ours = read_step(metres_step, as_="build123d")
    assert isinstance(ours, bd.Compound) and ours.label == "plate_m"  # flat: labelled with the file's stem
    (child,) = ours.children
    assert isinstance(child, bd.Solid) and child.label == "plate"
    np.testing.assert_allclose(tuple(child.color), GREEN, atol=COLOUR_ATOL)
    # geometry in millimetres, as build123d's importer gives it
    _assert_same_faces(ours.faces(), bd.import_step(str(metres_step)).faces())
    assert abs(child.volume - 1e9 * _plate().volume) < 1e-9 * child.volume


# ------------------------------------------------------------------------------------ cadquery
def test_assembly_as_cadquery(plates_step):
    assy = read_step(plates_step, as_="cadquery")
    assert isinstance(assy, cq.Assembly) and assy.name == "assembly"
    assert [c.name for c in assy.children] == ["plate_a", "plate_b"]
    np.testing.assert_allclose(assy.children[0].color.toTuple(), RED, atol=COLOUR_ATOL)
    np.testing.assert_allclose(assy.children[1].color.toTuple(), BLUE, atol=COLOUR_ATOL)
    assert assy.children[0].obj.wrapped.IsSame(assy.children[1].obj.wrapped)  # one prototype
    np.testing.assert_allclose(assy.children[1].loc.toTuple()[0], (30, 0, 5), atol=1e-12)
    placed = [f for f in assy.toCompound().Faces()]
    original = _two_plates().faces()
    _assert_same_faces(placed, original)


def test_cadquery_keeps_face_colours_and_names_like_cadquerys_importer(cq_faces_step):
    model = read_step(cq_faces_step)
    lid = [f for f in model.faces if f.color is not None and np.allclose(f.color, RED, atol=COLOUR_ATOL)]
    assert len(lid) == 1
    ours = read_step(cq_faces_step, as_="cadquery")
    theirs = cq.Assembly.importStep(str(cq_faces_step))
    ours_block = next(a for _, a in ours.traverse() if a.obj is not None)
    theirs_block = next(a for _, a in theirs.traverse() if a.obj is not None)
    np.testing.assert_allclose(ours_block.color.toTuple(), theirs_block.color.toTuple(), atol=COLOUR_ATOL)
    (ours_sub, ours_col), = ours_block._subshape_colors.items()
    (theirs_sub, theirs_col), = theirs_block._subshape_colors.items()
    np.testing.assert_allclose(ours_col.toTuple(), theirs_col.toTuple(), atol=COLOUR_ATOL)
    assert abs(ours_sub.Area() - theirs_sub.Area()) < 1e-12 and abs(ours_sub.Area() - 20.0) < 1e-12
    assert list(ours_block._subshape_names.values()) == ["lid"]
    # back to a model: the face colours come back from the cadquery objects
    back = model_from_object(ours)
    assert sorted(tuple(np.round(f.color, 6)) for f in back.faces) == sorted(tuple(np.round(f.color, 6))
                                                                          for f in model.faces)


def test_cadquery_names_are_made_unique_among_siblings(plates_step):
    import dataclasses

    model = read_step(plates_step)
    twin = [dataclasses.replace(c, name="plate") for c in model.assembly.children]
    same = dataclasses.replace(model, assembly=dataclasses.replace(model.assembly, children=tuple(twin)))
    assy = to_cadquery(same)
    assert [c.name for c in assy.children] == ["plate", "plate_2"]
    assert [c.label for c in to_build123d(same).children] == ["plate", "plate"]  # build123d allows equal labels


# ------------------------------------------------------------------------------------ IGES, flat
def test_iges_as_objects_hold_every_face():
    path = SAMPLES / "mixed.igs"
    model = read_iges(path)
    ours = read_iges(path, as_="build123d")
    assert isinstance(ours, bd.Compound) and ours.label == "mixed"
    assert len(ours.faces()) == len(model.faces)
    assy = read_iges(path, as_="cadquery")
    assert len(assy.toCompound().Faces()) == len(model.faces)
    areas = sorted(f.area for f in ours.faces())
    ref = sorted(bd.Face(f.face).area for f in model.faces)
    np.testing.assert_allclose(areas, ref, rtol=1e-12)


def test_as_with_isolated_reader(plates_step):
    ours = read_step(plates_step, as_="build123d", isolated=True, timeout=120)
    assert [c.label for c in ours.children] == ["plate_a", "plate_b"]
    _assert_same_faces(ours.faces(), _two_plates().faces())


@pytest.mark.parametrize("bad", ["b3d", "OCC", 1, "Build123d"])
def test_bad_as_is_refused_naming_it(plates_step, bad):
    with pytest.raises(InvalidGeometryError, match="as_"):
        read_step(plates_step, as_=bad)
    with pytest.raises(InvalidGeometryError, match="as_"):
        read_iges(SAMPLES / "mixed.igs", as_=bad)


# ------------------------------------------------------------------------------------ objects -> model
def test_model_from_build123d_tree_carries_labels_colours_instances():
    model = model_from_object(_two_plates())
    assert model.format == "build123d" and len(model.faces) == 2 * len(_plate().faces())
    by_instance = {}
    for f in model.faces:
        by_instance.setdefault(f.instance, set()).add((f.name, f.color))
    assert by_instance == {"assembly/plate_a": {("plate_a", RED)}, "assembly/plate_b": {("plate_b", BLUE)}}
    assert all(isinstance(f.surface, BSplineSurface) for f in model.faces)


def test_model_from_object_refuses_what_it_cannot_use():
    with pytest.raises(InvalidGeometryError, match="model"):
        model_from_object(42)
    with pytest.raises(InvalidGeometryError, match="empty"):
        model_from_object(bd.Compound())
    with pytest.raises(InvalidGeometryError, match="no shapes"):
        model_from_object(cq.Workplane())


def test_shape_object_makes_a_solid_of_a_closed_shell():
    from occsurf.bridge.modeling.fill import sew_faces

    shell = sew_faces([f.wrapped for f in bd.Box(1, 2, 3).faces()])
    solid = shape_object(shell, "build123d")
    assert isinstance(solid, bd.Solid) and solid.is_valid and abs(solid.volume - 6.0) < 1e-12
    open_shell = sew_faces([f.wrapped for f in bd.Box(1, 2, 3).faces()[:5]])
    assert isinstance(shape_object(open_shell, "cadquery"), cq.Shell)


# ------------------------------------------------------------------------------------ objects -> STEP -> objects
def test_build123d_tree_through_occsurfs_writer_and_back(tmp_path):
    """build123d assembly -> model_from_object -> write_step (XCAF, 17 digits) -> read_step(as_=...):
    labels, colours, placements, the shared part and every face (area, wires, position) survive."""
    from occsurf.bridge import write_step

    original = _two_plates()
    model = model_from_object(original)
    tree = model.assembly
    assert tree.name == "assembly" and [c.name for c in tree.children] == ["plate_a", "plate_b"]
    assert tree.children[0].part == tree.children[1].part  # one part, two instances
    np.testing.assert_allclose(tree.children[1].location[:3, 3], (30, 0, 5), atol=1e-12)
    path = write_step(tmp_path / "plates.step", model)
    back = read_step(path)
    assert back.assembly is not None and back.assembly.children[0].part == back.assembly.children[1].part
    ours = read_step(path, as_="build123d")
    assert ours.label == "assembly" and [c.label for c in ours.children] == ["plate_a", "plate_b"]
    for mine, theirs in zip(ours.children, original.children):
        np.testing.assert_allclose(tuple(mine.color), tuple(theirs.color), atol=COLOUR_ATOL)
        np.testing.assert_allclose(_loc(mine.global_location), _loc(theirs.global_location), atol=1e-12)
    assert ours.children[0].wrapped.IsPartner(ours.children[1].wrapped)
    _assert_same_faces(ours.faces(), original.faces(), rtol=1e-14)


def test_cadquery_assembly_through_occsurfs_writer_keeps_face_colours(tmp_path):
    from occsurf.bridge import write_step

    box = cq.Workplane().box(4, 5, 6)
    assy = cq.Assembly(name="top")
    assy.add(box, name="block", color=cq.Color(*BLUE[:3], 1.0, False), loc=cq.Location((1, 2, 3)))
    assy["block"].addSubshape(box.faces(">Z").val(), name="lid", color=cq.Color(*RED[:3], 1.0, False))
    model = model_from_object(assy)
    lid = [f for f in model.faces if f.name == "lid"]
    assert len(lid) == 1 and lid[0].color == RED and lid[0].instance == "top/block"
    path = write_step(tmp_path / "block.step", model)
    back = read_step(path, as_="cadquery")
    block = next(a for _, a in back.traverse() if a.obj is not None)
    assert block.name == "block"
    np.testing.assert_allclose(block.color.toTuple(), BLUE, atol=COLOUR_ATOL)
    (sub, col), = block._subshape_colors.items()
    np.testing.assert_allclose(col.toTuple(), RED, atol=COLOUR_ATOL)
    assert list(block._subshape_names.values()) == ["lid"]
    _assert_same_faces(back.toCompound().Faces(), assy.toCompound().Faces(), rtol=1e-14)


def test_write_step_and_iges_take_assemblies_with_their_structure(tmp_path):
    """write_step / write_iges of a build123d tree or a cadquery Assembly keep names and colours."""
    from occsurf.bridge import write_iges, write_step

    plates = _two_plates()
    ours = read_step(write_step(tmp_path / "p.step", plates), as_="build123d")
    assert [c.label for c in ours.children] == ["plate_a", "plate_b"]
    assert ours.children[0].wrapped.IsPartner(ours.children[1].wrapped)
    np.testing.assert_allclose([tuple(c.color) for c in ours.children], [RED, BLUE], atol=COLOUR_ATOL)
    model = read_iges(write_iges(tmp_path / "p.igs", plates))  # IGES: placed copies, names and colours kept
    by_name = {}
    for f in model.faces:
        by_name.setdefault(f.name, set()).add(tuple(np.round(f.color, 6)))
    assert by_name == {"plate_a": {RED}, "plate_b": {BLUE}}
    _assert_same_faces([bd.Face(f.face) for f in model.faces], plates.faces(), rtol=1e-8)  # ~10 digits
    unnamed = read_step(write_step(tmp_path / "n.step", plates, names="both"))
    assert unnamed.assembly is None or not any(c.name == "plate_a" for c in unnamed.assembly.children)


def test_face_layers_reach_cadquery_subshape_layers(tmp_path):
    box = cq.Workplane().box(1, 2, 3)
    assy = cq.Assembly(name="top").add(box, name="part")
    assy["part"].addSubshape(box.faces("<X").val(), layer="datum")
    path = tmp_path / "layers.step"
    assy.export(str(path))
    model = read_step(path)
    assert [f.layer for f in model.faces].count("datum") == 1
    part = next(a for _, a in read_step(path, as_="cadquery").traverse() if a.obj is not None)
    (face, layer), = part._subshape_layers.items()
    assert layer == "datum" and abs(face.Area() - 6.0) < 1e-12
    back = model_from_object(part)
    assert sorted(str(f.layer) for f in back.faces) == ["None"] * 5 + ["datum"]


def test_synthetic_root_paths_and_colours_from_faces(plates_step):
    """A file with several free shapes gets a synthetic root (no part) whose faces' instance paths
    start below it; nodes without a colour take their largest face's colour found by that path."""
    import dataclasses

    model = read_step(plates_step)
    kids = tuple(dataclasses.replace(c, color=None) for c in model.assembly.children)
    root = dataclasses.replace(model.assembly, part=None, name="file", children=kids)
    faces = [dataclasses.replace(f, instance=f.instance.split("/", 1)[1]) for f in model.faces]
    synthetic = dataclasses.replace(model, assembly=root, faces=faces)
    ours = to_build123d(synthetic)
    assert ours.label == "file" and [c.label for c in ours.children] == ["plate_a", "plate_b"]
    np.testing.assert_allclose([tuple(c.color) for c in ours.children], [RED, BLUE], atol=COLOUR_ATOL)
    assy = to_cadquery(synthetic)
    np.testing.assert_allclose([c.color.toTuple() for c in assy.children], [RED, BLUE], atol=COLOUR_ATOL)


def test_nested_build123d_assembly_round_trip(tmp_path):
    """Two levels: placements compose (a moved sub-assembly of two instances), as written by
    build123d and by occsurf, read back with the same global positions, labels and shared part."""
    from occsurf.bridge import write_step

    plate = _plate()
    a = plate.moved(bd.Location((0, 0, 0)))
    a.label, a.color = "plate_a", bd.Color(*RED)
    b = plate.moved(bd.Location((30, 0, 5), (0, 0, 90)))
    b.label, b.color = "plate_b", bd.Color(*BLUE)
    inner = bd.Compound(label="pair", children=[a, b])
    inner.move(bd.Location((0, 50, 0), (90, 0, 0)))
    lone = plate.moved(bd.Location((-40, 0, 0)))
    lone.label, lone.color = "plate_c", bd.Color(*GREEN)
    top = bd.Compound(label="top", children=[inner, lone])
    for writer in ("build123d", "occsurf"):
        path = tmp_path / f"{writer}.step"
        if writer == "build123d":
            assert bd.export_step(top, str(path))
        else:
            write_step(path, top)
        ours = read_step(path, as_="build123d")
        assert [c.label for c in ours.children] == ["pair", "plate_c"]
        assert [c.label for c in ours.children[0].children] == ["plate_a", "plate_b"]
        leaves = _leaves_b3d(ours)
        assert len({id(x) for x in leaves}) == 3
        assert leaves[0].wrapped.IsPartner(leaves[1].wrapped) and leaves[0].wrapped.IsPartner(leaves[2].wrapped)
        for mine, theirs in zip(leaves, _leaves_b3d(top)):
            np.testing.assert_allclose(_loc(mine.global_location), _loc(theirs.global_location), atol=1e-9)
        _assert_same_faces(ours.faces(), top.faces(), rtol=1e-12)
        colours = [tuple(np.round(tuple(x.color), 6)) for x in leaves]
        assert colours == [RED, BLUE, GREEN]


def test_nested_cadquery_assembly_round_trip(tmp_path):
    """cadquery: a sub-assembly that holds an object and children, placed twice over; through
    cadquery's writer and occsurf's, back as an Assembly with the same placed faces and colours."""
    from occsurf.bridge import write_step

    box = cq.Workplane().box(2, 3, 4)
    rod = cq.Workplane().cylinder(6, 0.5)
    sub = cq.Assembly(box, name="base", color=cq.Color(*RED[:3], 1.0, False))
    sub.add(rod, name="rod", loc=cq.Location((0, 0, 5)), color=cq.Color(*BLUE[:3], 1.0, False))
    top = cq.Assembly(name="top")
    top.add(sub, name="left", loc=cq.Location((-5, 0, 0)))
    top.add(sub, name="right", loc=cq.Location((5, 0, 0), (0, 0, 1), 30))
    for writer in ("cadquery", "occsurf"):
        path = tmp_path / f"{writer}.step"
        top.export(str(path)) if writer == "cadquery" else write_step(path, top)
        back = read_step(path, as_="cadquery")
        _assert_same_faces(back.toCompound().Faces(), top.toCompound().Faces(), rtol=1e-12)
        coloured = sorted((round(a.toCompound().Area(), 9), tuple(np.round(a.color.toTuple(), 6)))
                          for _, a in back.traverse() if a.obj is not None and a.color is not None)
        box_area, rod_area = round(box.val().Area(), 9), round(rod.val().Area(), 9)
        assert rod_area < box_area
        assert coloured == [(rod_area, BLUE)] * 2 + [(box_area, RED)] * 2  # each instance of each part
