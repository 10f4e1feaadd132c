"""XCAF reading and writing: names, colours, layers, units and assemblies survive STEP and IGES.

Models are built here with build123d (two instances of one part with two holes, colours, labels,
a file in metres) and read from ../shared/realdata. Per property the round trips are measured face by
face: name, colour, layer, instance path, area (``BRepGProp``, 1e-9) and wire count. STEP keeps 17
digits, so areas agree to round-off (1e-12 relative); IGES keeps 10 digits, so areas agree to 1e-7
relative (a value moves by up to 5e-10 of itself; an area sums many such moves, and a trimmed face's
area also depends on its p-curves' 10-digit values).
"""

from __future__ import annotations

import copy
import dataclasses
from pathlib import Path

import numpy as np
import pytest

from occsurf.algorithms.errors import ExchangeError, InvalidGeometryError
from occsurf.bridge.exchange import xcaf
from occsurf.bridge.exchange.convert import face_area as _area
from occsurf.bridge.exchange.convert import trim_band as _trim_band
from occsurf.bridge.exchange.convert import wire_count as _n_wires
from occsurf.bridge.exchange.step_iges import ImportedModel, read_iges, read_step, write_iges, write_step

bd = pytest.importorskip("build123d")

REALDATA = Path(__file__).resolve().parents[2].parent / "shared" / "realdata"
RED, BLUE, GREEN = (1.0, 0.0, 0.0, 1.0), (0.0, 0.0, 1.0, 1.0), (0.0, 1.0, 0.0, 0.5)
STEP_AREA_RTOL = 1e-12
IGES_AREA_RTOL = 1e-7
#: Real files written by other systems: the screw's faces move by 4.5e-8 of their area through a STEP
#: round trip with OCC's own STEPControl_Writer too (measured: the same value with and without XCAF), so
#: this is OCC's re-reading of that file's edges, not a loss in the written values.
REAL_STEP_AREA_RTOL = 1e-7


# ------------------------------------------------------------------------------------ fixtures
@pytest.fixture(scope="module")
def assembly_step(tmp_path_factory) -> Path:
    """'assembly': plate_a (red) and plate_b (blue, 10 mm up) instances of one plate with two holes,
    and a half-transparent green post."""
    plate = bd.Box(40, 20, 2) - bd.Cylinder(3, 5) - bd.Pos(10, 0, 0) * bd.Cylinder(2, 5)
    a = copy.copy(plate)
    a.label, a.color = "plate_a", bd.Color(*RED)
    b = copy.copy(plate)
    b.label, b.color, b.location = "plate_b", bd.Color(*BLUE), bd.Location((0, 0, 10))
    post = bd.Pos(30, 0, 0) * bd.Cylinder(5, 10)
    post.label, post.color = "post", bd.Color(*GREEN)
    path = tmp_path_factory.mktemp("xcaf") / "assembly.step"
    bd.export_step(bd.Compound(label="assembly", children=[a, b, post]), path)
    return path


def _assert_same_faces(before: ImportedModel, after: ImportedModel, *, rtol: float, instances: bool = True,
                       alpha: bool = True, trim_band: bool = False) -> None:
    """Per face: name, colour, layer, (instance), area (within ``rtol``, or the trimming band of real
    files' faces with ``trim_band``), wire count."""
    assert len(after.faces) == len(before.faces)
    for f, g in zip(before.faces, after.faces):
        assert g.name == f.name, f.index
        if f.color is None:
            assert g.color is None, f.index
        else:
            n = 4 if alpha else 3
            np.testing.assert_allclose(g.color[:n], f.color[:n], atol=1e-9, err_msg=str(f.index))
        assert g.layer == f.layer, f.index
        if instances:
            assert g.instance == f.instance, f.index
        assert _n_wires(g.face) == _n_wires(f.face), f.index
        atol = _trim_band(f.face) if trim_band else 0.0
        np.testing.assert_allclose(_area(g.face), _area(f.face), rtol=rtol, atol=atol, err_msg=str(f.index))


# ------------------------------------------------------------------------------------ reading
def test_assembly_read(assembly_step):
    model = read_step(assembly_step)
    assert (model.unit, model.unit_scale) == ("mm", 1.0)
    root = model.assembly
    assert root is not None and root.name == "assembly" and root.part is not None
    assert [c.name for c in root.children] == ["plate_a", "plate_b", "post"]
    a, b, post = root.children
    assert a.part == b.part != post.part  # one prototype, two instances
    assert a.shape.IsSame(b.shape)
    np.testing.assert_array_equal(b.location[:3, 3], [0, 0, 10])
    np.testing.assert_array_equal(a.location, np.eye(4))
    assert (a.color, b.color, post.color) == (RED, BLUE, GREEN)
    by_instance: dict[str, list] = {}
    for f in model.faces:
        by_instance.setdefault(f.instance, []).append(f)
    assert sorted(by_instance) == ["assembly/plate_a", "assembly/plate_b", "assembly/post"]
    assert len(by_instance["assembly/plate_a"]) == len(by_instance["assembly/plate_b"]) == 8  # 6 sides + 2 holes
    for path, color in (("assembly/plate_a", RED), ("assembly/plate_b", BLUE), ("assembly/post", GREEN)):
        assert {f.color for f in by_instance[path]} == {color}
        assert {f.name for f in by_instance[path]} == {path.rsplit("/", 1)[1]}  # the instance's, not the root's
    # the face with holes: 3 wires
    top = max(by_instance["assembly/plate_a"], key=lambda f: _area(f.face))
    assert _n_wires(top.face) == 3


def test_isolated_read_keeps_structure(assembly_step):
    here, there = read_step(assembly_step), read_step(assembly_step, isolated=True)
    assert [(f.name, f.color, f.layer, f.instance) for f in there.faces] == \
           [(f.name, f.color, f.layer, f.instance) for f in here.faces]
    a, b, _ = there.assembly.children
    assert a.part == b.part and a.shape.IsSame(b.shape)  # still one shared prototype
    assert [p for p, _ in xcaf.iter_nodes(there.assembly)] == [p for p, _ in xcaf.iter_nodes(here.assembly)]


def test_flat_file_has_no_assembly(tmp_path):
    path = write_step(tmp_path / "box.step", bd.Box(1, 2, 3), names="box")
    model = read_step(path)
    assert model.assembly is None
    assert {f.instance for f in model.faces} == {None}
    assert {f.name for f in model.faces} == {"box"}
    assert {f.color for f in model.faces} == {None}


# ------------------------------------------------------------------------------------ units
@pytest.mark.parametrize(("unit", "scale", "text"), [("m", 1000.0, b"SI_UNIT($,.METRE.)"),
                                                     ("inch", 25.4, b"CONVERSION_BASED_UNIT('INCH'"),
                                                     ("cm", 10.0, b"SI_UNIT(.CENTI.,.METRE.)"),
                                                     ("mm", 1.0, b"SI_UNIT(.MILLI.,.METRE.)")])
def test_unit_reported_geometry_in_mm(tmp_path, unit, scale, text):
    path = write_step(tmp_path / f"box_{unit}.step", bd.Box(1000, 2000, 3000), names="box", unit=unit)
    assert text in path.read_bytes()
    model = read_step(path)
    assert (model.unit, model.unit_scale) == (unit, scale)
    total = sum(_area(f.face) for f in model.faces)
    np.testing.assert_allclose(total, 2 * (2e6 + 3e6 + 6e6), rtol=1e-12)  # still millimetres
    iges = write_iges(tmp_path / f"box_{unit}.igs", model)  # the model's unit by default
    back = read_iges(iges)
    assert (back.unit, back.unit_scale) == (unit, scale)
    np.testing.assert_allclose(sum(_area(f.face) for f in back.faces), total, rtol=IGES_AREA_RTOL)


def test_build123d_metres_file(tmp_path):
    """build123d's ``unit=Unit.M`` scales the model but writes a file in millimetres: reported as such."""
    path = tmp_path / "bd_m.step"
    bd.export_step(bd.Box(1, 2, 3), path, unit=bd.Unit.M)
    assert read_step(path).unit == "mm"


def test_bad_unit(tmp_path, assembly_step):
    with pytest.raises(InvalidGeometryError, match="unit"):
        write_step(tmp_path / "x.step", bd.Box(1, 1, 1), unit="furlong")
    with pytest.raises(InvalidGeometryError, match="names"):
        write_step(tmp_path / "x.step", read_step(assembly_step), names=["a"])
    assert not (tmp_path / "x.step").exists()


# ------------------------------------------------------------------------------------ round trips
def test_step_round_trip(tmp_path, assembly_step):
    model = read_step(assembly_step)
    out = write_step(tmp_path / "again.step", model)
    text = out.read_bytes()
    assert text.count(b"NEXT_ASSEMBLY_USAGE_OCCURRENCE") == 3
    assert text.count(b"MANIFOLD_SOLID_BREP") == 2  # the plate once, the post once: instances are references
    again = read_step(out)
    _assert_same_faces(model, again, rtol=STEP_AREA_RTOL)
    assert [(p, n.part, n.color, n.location.tolist()) for p, n in xcaf.iter_nodes(again.assembly)] == \
           [(p, n.part, n.color, n.location.tolist()) for p, n in xcaf.iter_nodes(model.assembly)]


def test_step_round_trip_in_metres(tmp_path, assembly_step):
    model = read_step(assembly_step)
    again = read_step(write_step(tmp_path / "m.step", model, unit="m"))
    assert again.unit == "m"
    _assert_same_faces(model, again, rtol=1e-12)
    np.testing.assert_allclose(again.assembly.children[1].location[:3, 3], [0, 0, 10], rtol=1e-15)


def test_face_colour_and_layer_round_trip(tmp_path, assembly_step):
    """A face's own colour and layer (over its instance's) survive; so does a face's own name."""
    model = read_step(assembly_step)
    k = next(f.index for f in model.faces if f.instance == "assembly/post")
    faces = list(model.faces)
    faces[k] = dataclasses.replace(faces[k], color=(0.2, 0.4, 0.6, 1.0), layer="cap", name="top cap")
    edited = dataclasses.replace(model, faces=faces)
    again = read_step(write_step(tmp_path / "face.step", edited))
    assert (again.faces[k].layer, again.faces[k].name) == ("cap", "top cap")
    # the file's sRGB numbers: OCC's linear float32 moves them by < 2e-8, undone by xcaf.COLOR_DECIMALS
    assert again.faces[k].color == (0.2, 0.4, 0.6, 1.0)
    edited.faces[k] = dataclasses.replace(edited.faces[k], color=again.faces[k].color)
    _assert_same_faces(edited, again, rtol=STEP_AREA_RTOL)
    iges = read_iges(write_iges(tmp_path / "face.igs", edited))
    np.testing.assert_allclose(iges.faces[k].color[:3], (0.2, 0.4, 0.6), atol=1e-7)
    # the face's own name (406-15 name property of its 144 entity inside the part's 402 group), which
    # OCC's reader does not report, is found from the face side; the other faces keep their instance's
    assert iges.faces[k].name == "top cap"
    assert [f.name for f in iges.faces if f.index != k] == [f.name for f in model.faces if f.index != k]
    back = read_step(write_step(tmp_path / "face_back.step", iges))  # STEP -> IGES -> STEP
    assert back.faces[k].name == "top cap"
    # IGES levels are numbers: OCC writes the layer 'cap' as level 1, occsurf names the level (406-3)
    assert iges.faces[k].layer == back.faces[k].layer == "cap"
    assert {f.layer for f in iges.faces if f.index != k} == {None}


def test_iges_level_names(tmp_path, assembly_step):
    """Layer names through IGES: a numeric layer is that level; a named one is the level OCC numbers
    it with, named by a Level Function property (406 form 3) on it, which OCC's reader ignores."""
    model = read_step(assembly_step)
    faces = list(model.faces)
    layers = {0: "7", 1: "cap", 2: "cap", 9: "Top, side; 5H"}  # delimiters and a Hollerith look-alike
    for i, layer in layers.items():
        faces[i] = dataclasses.replace(faces[i], layer=layer)
    edited = dataclasses.replace(model, faces=faces)
    path = write_iges(tmp_path / "levels.igs", edited)
    iges = read_iges(path)
    assert [f.layer for f in iges.faces] == [layers.get(i) for i in range(len(faces))]
    text = path.read_text()
    assert text.count("406,2,0,3Hcap;") == 1 and "13HTop, side; 5H;" in text
    assert xcaf.iges_level_names(path.read_bytes()) == {8: "cap", 9: "Top, side; 5H"}  # above the largest, 7
    back = read_step(write_step(tmp_path / "levels.step", iges))
    assert [f.layer for f in back.faces] == [f.layer for f in iges.faces]
    # a damaged property (Hollerith count past the record) leaves the bare level number, nothing else
    broken = tmp_path / "broken.igs"
    broken.write_text(text.replace("3Hcap;", "9Hcap;"))
    assert [f.layer for f in read_iges(broken).faces][:3] == ["7", "8", "8"]


def test_iges_uncoloured_face_names_and_layers(tmp_path):
    """Faces without a colour: OCC's XCAF reader does not find their labels, so their names (406-15 /
    label of the 144 entity) and levels are read from the face side; the others keep the part's."""
    model = read_step(write_step(tmp_path / "box.step", bd.Box(1, 2, 3), names="box"))
    assert {f.color for f in model.faces} == {None}
    faces = [dataclasses.replace(f, name=f"side {f.index}", layer="odd") if f.index % 2 else f for f in model.faces]
    iges = read_iges(write_iges(tmp_path / "box.igs", dataclasses.replace(model, faces=faces)))
    assert [(f.name, f.layer) for f in iges.faces] == [(f.name, f.layer) for f in faces]
    again = read_step(write_step(tmp_path / "box_back.step", iges))
    assert [(f.name, f.layer) for f in again.faces] == [(f.name, f.layer) for f in faces]


def test_step_iges_step(tmp_path, assembly_step):
    model = read_step(assembly_step)
    iges = read_iges(write_iges(tmp_path / "a.igs", model))
    assert iges.assembly is None  # IGES has no instances: copies
    assert [f.name for f in iges.faces] == [f.name for f in model.faces]
    _assert_same_faces(model, iges, rtol=IGES_AREA_RTOL, instances=False, alpha=False)
    assert {f.color[3] for f in iges.faces} == {1.0}  # IGES has no transparency
    back = read_step(write_step(tmp_path / "b.step", iges))
    _assert_same_faces(iges, back, rtol=STEP_AREA_RTOL)


def test_tree_written_with_layers(tmp_path, assembly_step):
    """An AssemblyNode tree written directly: names, layers, colours, placements, shared parts."""
    root = read_step(assembly_step).assembly
    a, b, post = root.children
    tree = dataclasses.replace(root, children=(dataclasses.replace(a, layer="plates"),
                                               dataclasses.replace(b, layer="plates", name="lifted"),
                                               dataclasses.replace(post, layer="posts")))
    again = read_step(write_step(tmp_path / "tree.step", tree))
    names = [(p, n.layer, n.color) for p, n in xcaf.iter_nodes(again.assembly)]
    assert names == [("assembly", None, None), ("assembly/plate_a", "plates", RED),
                     ("assembly/lifted", "plates", BLUE), ("assembly/post", "posts", GREEN)]
    assert {f.layer for f in again.faces if f.instance == "assembly/lifted"} == {"plates"}
    a2, b2, _ = again.assembly.children
    assert a2.part == b2.part and a2.shape.IsSame(b2.shape)


def _centroid(face) -> np.ndarray:
    from OCP.BRepGProp import BRepGProp
    from OCP.GProp import GProp_GProps

    props = GProp_GProps()
    BRepGProp.SurfaceProperties_s(face, props, 1e-9)
    return np.array(props.CentreOfMass().Coord())


def test_nested_tree_placements(tmp_path, assembly_step):
    """A sub-assembly instanced twice (one translated, one rotated): shared once, placements composed."""
    root = read_step(assembly_step).assembly
    plate, _, post = root.children
    sub_shape = xcaf.compound([plate.shape, post.shape])
    turn = np.array([[0.0, -1, 0, 5], [1, 0, 0, 100], [0, 0, 1, 0], [0, 0, 0, 1]])
    shift = np.eye(4)
    shift[:3, 3] = [0, -50, 7]
    sub = xcaf.AssemblyNode("sub", None, None, np.eye(4), "sub", sub_shape, (plate, post))
    top = xcaf.AssemblyNode("top", None, None, np.eye(4), "top", None,
                            (dataclasses.replace(sub, name="sub_1", location=shift),
                             dataclasses.replace(sub, name="sub_2", location=turn)))
    model = read_step(write_step(tmp_path / "nested.step", top))
    paths = [p for p, _ in xcaf.iter_nodes(model.assembly)]
    assert paths == ["top", "top/sub_1", "top/sub_1/plate_a", "top/sub_1/post",
                     "top/sub_2", "top/sub_2/plate_a", "top/sub_2/post"]
    s1, s2 = model.assembly.children
    assert s1.part == s2.part and s1.shape.IsSame(s2.shape)  # the sub-assembly is written once
    np.testing.assert_allclose(s1.location, shift, atol=1e-15)
    np.testing.assert_allclose(s2.location, turn, atol=1e-15)
    assert len(model.faces) == 2 * (8 + 3)
    first = [f for f in model.faces if f.instance == "top/sub_1/plate_a"]
    second = [f for f in model.faces if f.instance == "top/sub_2/plate_a"]
    assert len(first) == len(second) == 8
    for f, g in zip(first, second):  # the same part face, placed by each instance's composed placement
        c = _centroid(f.face) - shift[:3, 3]
        np.testing.assert_allclose(_centroid(g.face), turn[:3, :3] @ c + turn[:3, 3], atol=1e-9)
        assert (f.color, g.color) == (RED, RED)


def test_assembly_node_rejects_bad_location():
    with pytest.raises(InvalidGeometryError, match="location"):
        xcaf.AssemblyNode("x", None, None, np.eye(3), None, None)


def test_damaged_file_is_an_exchange_error(tmp_path, assembly_step):
    bad = tmp_path / "cut.step"
    bad.write_bytes(assembly_step.read_bytes()[:2000])
    with pytest.raises(ExchangeError, match="truncated"):
        read_step(bad)


# ------------------------------------------------------------------------------------ real data
def _real(name: str) -> Path:
    path = REALDATA / name
    if not path.exists():
        pytest.skip(f"{path} not present (public CAD files in ../shared/realdata)")
    return path


@pytest.mark.slow
@pytest.mark.parametrize("name", ["build123d__M6-1x12-countersunk-screw.step", "occt__linkrods.step"])
def test_real_step_round_trips(tmp_path, name):
    model = read_step(_real(name))
    again = read_step(write_step(tmp_path / "again.step", model))
    assert again.unit == model.unit
    _assert_same_faces(model, again, rtol=REAL_STEP_AREA_RTOL)
    iges = read_iges(write_iges(tmp_path / "again.igs", model))
    _assert_same_faces(model, iges, rtol=IGES_AREA_RTOL, instances=False, alpha=False)


@pytest.mark.parametrize("name", ["occt__bearing.iges", "pythonocc-core__sunglasses_lens.igs"])
def test_real_iges_to_step(tmp_path, name):
    model = read_iges(_real(name))
    step = read_step(write_step(tmp_path / "x.step", model))
    assert step.unit == model.unit
    _assert_same_faces(model, step, rtol=REAL_STEP_AREA_RTOL, trim_band=True)
