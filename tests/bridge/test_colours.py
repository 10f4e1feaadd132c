"""Colours are the file's numbers (sRGB), read and written, STEP and IGES, models and build123d/cadquery objects.

STEP ``COLOUR_RGB`` and IGES 314 (percentages) hold sRGB, as build123d's and cadquery's ``Color(r, g, b)``
take it; OCC's ``Quantity_Color`` holds linear RGB in float32 (the file's 0.2 is 0.0331 there). occsurf
reads ``Values(Quantity_TOC_sRGB)`` rounded to ``xcaf.COLOR_DECIMALS`` (7) decimals and writes
``Quantity_Color(r, g, b, Quantity_TOC_sRGB)``.

Tolerances: OCC rounds the linear value ``l`` to float32 (``|dl| <= 2**-24 l``); on the sRGB curve's
power branch ``s = 1.055 l**(1/2.4) - 0.055`` that moves ``s`` by ``1.055 / 2.4 * l**(1/2.4) * 2**-24 <=
2.62e-8`` (on the linear branch, ``s < 0.04045``, by < 0.04045 * 2**-24), so a value written by OCC's STEP
writer (``Values(sRGB)`` printed with 17 digits) is within ``SRGB_ATOL`` = 3e-8 of the number given
(measured: at most 1.93e-8 over 20 000 random values); IGES prints the percentage with 10 significant
digits (a further 5e-11 after dividing by 100).
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from occsurf.bridge.exchange import xcaf
from occsurf.bridge.exchange.step_iges import read_iges, read_step, write_iges, write_step

bd = pytest.importorskip("build123d")

#: Largest distance between a colour component given to OCC and the one its writers print (see above).
SRGB_ATOL = 3e-8
#: What each part of the hand-edited file says, by label: 0.2/0.5/0.8, a pure red, 9-decimal values.
FILE_TEXT = {"p1": "0.2,0.5,0.8", "p2": "1.,0.,0.", "p3": "0.123456789,0.987654321,0.0004"}
FILE_VALUES = {"p1": (0.2, 0.5, 0.8), "p2": (1.0, 0.0, 0.0), "p3": (0.123456789, 0.987654321, 0.0004)}
#: The placeholder grey each part is written with first, replaced in the text by FILE_TEXT.
PLACEHOLDER = {"p1": 0.1, "p2": 0.3, "p3": 0.6}
_COLOUR_RGB = re.compile(r"COLOUR_RGB\('[^']*',\s*([^,]+),\s*([^,]+),\s*([^)]+)\)")


def _step_colours(path: Path) -> list[tuple[float, float, float]]:
    """The ``COLOUR_RGB`` numbers of a STEP file's text."""
    text = path.read_text()
    return [tuple(float(x.strip()) for x in m.groups()) for m in _COLOUR_RGB.finditer(text)]  # type: ignore[misc]


def _iges_colours(path: Path) -> list[tuple[float, float, float]]:
    """The percentages / 100 of a IGES file's 314 entities (parameter data section, one record each here)."""
    out = []
    for line in path.read_text().splitlines():
        if len(line) >= 73 and line[72] == "P" and line.startswith("314,"):
            r, g, b = line[:64].split(",")[1:4]
            out.append((float(r) / 100, float(g) / 100, float(b) / 100))
    return out


@pytest.fixture(scope="module")
def file_step(tmp_path_factory) -> Path:
    """Three boxes 'p1', 'p2', 'p3' whose ``COLOUR_RGB`` texts are FILE_TEXT (written with placeholder
    greys, which the text then replaces)."""
    parts = []
    for k, (label, grey) in enumerate(PLACEHOLDER.items(), start=1):
        box = bd.Box(k, k, k)
        box.label, box.color = label, bd.Color(grey, grey, grey)
        parts.append(box)
    path = tmp_path_factory.mktemp("colours") / "hand.step"
    write_step(path, bd.Compound(label="top", children=parts))
    text = path.read_text()

    def swap(m: re.Match[str]) -> str:
        grey = float(m.group(1))
        label = next(k for k, v in PLACEHOLDER.items() if abs(v - grey) < 1e-6)
        return f"COLOUR_RGB('',{FILE_TEXT[label]})"

    text, n = _COLOUR_RGB.subn(swap, text)
    assert n >= 3
    path.write_text(text)
    assert set(_step_colours(path)) == set(FILE_VALUES.values())
    return path


def _by_part(model) -> dict[str, set]:
    out: dict[str, set] = {}
    for f in model.faces:
        out.setdefault(f.instance.split("/")[-1] if f.instance else f.name, set()).add(f.color)
    return out


def test_error_bound_behind_color_decimals():
    """OCC's sRGB -> linear float32 -> sRGB moves every 8-bit value and percentage by <= SRGB_ATOL;
    percentages read back exactly, 8-bit values (not 7-decimal numbers) within half the 7th decimal
    + SRGB_ATOL (43/255 = 0.16862745098 reads 0.1686274: OCC's 0.168627449... rounds down)."""
    from OCP.Quantity import Quantity_TypeOfColor

    for values, exact in ((np.arange(256) / 255, False), (np.arange(101) / 100, True)):
        for v in values:
            c = xcaf.occ_color((v, v, v, 1.0))
            raw = c.GetRGB().Values(Quantity_TypeOfColor.Quantity_TOC_sRGB)[0]
            assert abs(raw - v) <= SRGB_ATOL
            if exact:
                assert xcaf.rgba_from_occ(c)[0] == round(v, xcaf.COLOR_DECIMALS)
            else:
                assert abs(xcaf.rgba_from_occ(c)[0] - v) <= 5e-8 + SRGB_ATOL


@settings(max_examples=300, deadline=None)
@given(st.integers(0, 10**7), st.integers(0, 10**7), st.integers(0, 10**7), st.sampled_from([0.25, 0.5, 1.0]))
def test_seven_decimals_round_trip(r, g, b, a):
    rgba = (r / 1e7, g / 1e7, b / 1e7, a)
    assert xcaf.rgba_from_occ(xcaf.occ_color(rgba)) == rgba


def test_step_reads_the_files_numbers(file_step):
    model = read_step(file_step)
    colours = _by_part(model)
    assert colours["p1"] == {(0.2, 0.5, 0.8, 1.0)}
    assert colours["p2"] == {(1.0, 0.0, 0.0, 1.0)}
    (p3,) = colours["p3"]
    # 9 decimals in the file: within half the 7th decimal + SRGB_ATOL
    np.testing.assert_allclose(p3[:3], FILE_VALUES["p3"], rtol=0, atol=5e-8 + SRGB_ATOL)
    assert [(n.name, n.color) for n in model.assembly.children] == [
        ("p1", (0.2, 0.5, 0.8, 1.0)), ("p2", (1.0, 0.0, 0.0, 1.0)), ("p3", p3)]


def test_step_write_gives_the_file_the_numbers(tmp_path, file_step):
    model = read_step(file_step)
    out = write_step(tmp_path / "again.step", model)
    written = _step_colours(out)
    expected = {tuple(c[:3]) for cs in _by_part(model).values() for c in cs}
    assert len(written) >= 3
    for values in written:
        # measured: 0.2 is written 0.19999999868206275 (1.3e-9), 0.8 as 0.80000001087748585 (1.1e-8)
        assert min(np.abs(np.subtract(values, e)).max() for e in expected) <= SRGB_ATOL, values
    assert {v for cs in _by_part(read_step(out)).values() for v in cs} == \
        {v for cs in _by_part(model).values() for v in cs}


def test_iges_writes_and_reads_the_files_numbers(tmp_path, file_step):
    model = read_step(file_step)
    out = write_iges(tmp_path / "hand.igs", model)
    written = _iges_colours(out)
    # 0.2/0.5/0.8 and p3 as 314 percentages; the pure red as IGES's predefined colour number 2
    assert len(written) == 2
    for values, label in zip(sorted(written), ("p3", "p1")):
        np.testing.assert_allclose(values, np.round(FILE_VALUES[label], 7), rtol=0, atol=SRGB_ATOL + 5e-11)
    # directory entry field 13 (second record, columns 17-24): > 0 a predefined colour, < 0 a 314 pointer
    numbers = {int(line[16:24]) for line in out.read_text().splitlines()
               if len(line) >= 80 and line[72] == "D" and int(line[73:80]) % 2 == 0 and line[:8].strip() == "144"}
    assert {k for k in numbers if k > 0} == {2}  # IGES colour number 2: red
    iges = read_iges(out)
    assert sorted({f.color for f in iges.faces}) == sorted({f.color for f in model.faces})
    # an IGES file saying 20 %, 50 %, 80 % reads 0.2, 0.5, 0.8
    text = out.read_text()
    lines = text.splitlines()
    for i, line in enumerate(lines):
        if line.startswith("314,") and line[72] == "P" and line.split(",")[1].startswith("19.9999"):
            body = "314,20.,50.,80.," + line[:64].split(",", 4)[4]
            lines[i] = body.ljust(64) + line[64:]
    edited = tmp_path / "percent.igs"
    edited.write_text("\n".join(lines) + "\n")
    assert (0.2, 0.5, 0.8) in _iges_colours(edited)
    assert (0.2, 0.5, 0.8, 1.0) in {f.color for f in read_iges(edited).faces}


def test_objects_carry_the_files_numbers(file_step):
    b3d = read_step(file_step, as_="build123d")
    got = {c.label: tuple(c.color) for c in b3d.children}
    assert got["p1"] == (0.2, 0.5, 0.8, 1.0) and got["p2"] == (1.0, 0.0, 0.0, 1.0)
    assy = read_step(file_step, as_="cadquery")
    got = {c.name: c.color.toTuple() for c in assy.children}
    for label in ("p1", "p2"):
        np.testing.assert_allclose(got[label], (*FILE_VALUES[label], 1.0), rtol=0, atol=SRGB_ATOL)


@pytest.mark.parametrize("kind", ["build123d", "cadquery"])
def test_objects_give_the_file_their_numbers(tmp_path, kind):
    given = [(0.2, 0.5, 0.8), (0.123, 0.456, 0.789)]
    if kind == "build123d":
        parts = []
        for k, rgb in enumerate(given, start=1):
            box = bd.Box(k, k, k)
            box.label, box.color = f"p{k}", bd.Color(*rgb)
            parts.append(box)
        obj = bd.Compound(label="top", children=parts)
    else:
        cq = pytest.importorskip("cadquery")
        obj = cq.Assembly(name="top")
        for k, rgb in enumerate(given, start=1):
            obj.add(cq.Workplane().box(k, k, k).val(), name=f"p{k}", color=cq.Color(*rgb))
    out = write_step(tmp_path / f"{kind}.step", obj)
    written = _step_colours(out)
    assert written
    for values in written:
        assert min(np.abs(np.subtract(values, g)).max() for g in given) <= SRGB_ATOL, values
    assert {tuple(np.round(v, 7)) for v in written} == set(given)
    assert {f.color for f in read_step(out).faces} == {(*g, 1.0) for g in given}


# ------------------------------------------------------------------ moved instances (issue 16)
#: Colours of the placed parts below, by name.
PLACED = {"a": (1.0, 0.0, 0.0, 1.0), "b": (0.2, 0.5, 0.8, 1.0), "c": (0.1, 0.7, 0.3, 1.0),
          "r": (0.9, 0.6, 0.1, 1.0), "s1": (0.3, 0.3, 0.9, 1.0), "s2": (0.8, 0.2, 0.6, 1.0)}
#: Their world bounding boxes, by hand: a centred box moved by its placement (the rotated one: 90°
#: about z swaps its x and y extents), the sub-assembly moved by 10 along z.
BOXES = {"a": ((-0.5, -0.5, -0.5), (0.5, 0.5, 0.5)), "b": ((2.0, -0.5, -0.5), (4.0, 0.5, 0.5)),
         "c": ((-0.5, 3.0, -0.5), (0.5, 5.0, 0.5)), "r": ((-0.5, -1.0, 4.5), (0.5, 1.0, 5.5)),
         "s1": ((-0.5, -0.5, 9.5), (0.5, 0.5, 10.5)), "s2": ((1.5, -0.5, 9.5), (2.5, 0.5, 10.5))}
#: Bounding boxes are compared within 1e-9: STEP and IGES keep >= 10 significant digits of
#: coordinates <= 10.5 (OCP_NOTES §7), and the boxes are taken without OCC's enlargement (optimal, no gap).
BOX_ATOL = 1e-9


def _placed_tree(kind: str):
    """Moved leaves (b, c), a rotated leaf (r) and a moved sub-assembly (sub: s1, s2) beside an
    unmoved leaf (a): build123d (leaves are compounds holding a located solid) or cadquery (``loc=``)."""
    sizes = {"a": (1, 1, 1), "b": (2, 1, 1), "c": (1, 2, 1), "r": (2, 1, 1), "s1": (1, 1, 1), "s2": (1, 1, 1)}
    moves = {"a": ((0, 0, 0), 0), "b": ((3, 0, 0), 0), "c": ((0, 4, 0), 0), "r": ((0, 0, 5), 90),
             "s1": ((0, 0, 0), 0), "s2": ((2, 0, 0), 0)}
    if kind == "build123d":
        def leaf(name):
            (x, y, z), angle = moves[name]
            part = bd.Pos(x, y, z) * bd.Rot(0, 0, angle) * bd.Box(*sizes[name])
            part.label, part.color = name, bd.Color(*PLACED[name][:3])
            return part
        sub = bd.Compound(label="sub", children=[leaf("s1"), leaf("s2")])
        sub.location = bd.Location((0, 0, 10))
        return bd.Compound(label="top", children=[leaf(n) for n in ("a", "b", "c", "r")] + [sub])
    cq = pytest.importorskip("cadquery")

    def add(assy, name):
        (x, y, z), angle = moves[name]
        assy.add(cq.Workplane().box(*sizes[name]).val(), name=name, color=cq.Color(*PLACED[name][:3]),
                 loc=cq.Location((x, y, z), (0, 0, 1), angle))
    top = cq.Assembly(name="top")
    for n in ("a", "b", "c", "r"):
        add(top, n)
    sub = cq.Assembly(name="sub")
    for n in ("s1", "s2"):
        add(sub, n)
    top.add(sub, loc=cq.Location((0, 0, 10)))
    return top


def _box(shapes) -> tuple[tuple[float, ...], tuple[float, ...]]:
    from OCP.Bnd import Bnd_Box
    from OCP.BRepBndLib import BRepBndLib

    box = Bnd_Box()
    for s in shapes:
        BRepBndLib.AddOptimal_s(s, box, False, False)
    box.SetGap(0.0)
    x0, y0, z0, x1, y1, z1 = box.Get()
    return (x0, y0, z0), (x1, y1, z1)


def _leaves(model, key) -> dict[str, tuple[Any, Any]]:
    """Per leaf name (the last name of ``key(face)``): (its faces' colours, its world bounding box)."""
    groups: dict[str, list[Any]] = {}
    for f in model.faces:
        groups.setdefault(key(f).split("/")[-1], []).append(f)
    return {name: ({f.color for f in fs}, _box([f.face for f in fs])) for name, fs in groups.items()}


def _occ_leaves(path: Path) -> dict[str, tuple[Any, Any]]:
    """What OCC's own XCAF reader gives each part occurrence (``XCAFPrs_DocumentExplorer``: the style
    and world placement of each leaf node), by instance name: (surface colour, world bounding box)."""
    from OCP.Quantity import Quantity_TypeOfColor
    from OCP.STEPCAFControl import STEPCAFControl_Reader
    from OCP.TCollection import TCollection_ExtendedString
    from OCP.TDataStd import TDataStd_Name
    from OCP.TDocStd import TDocStd_Document
    from OCP.XCAFDoc import XCAFDoc_ShapeTool
    from OCP.XCAFPrs import XCAFPrs_DocumentExplorer, XCAFPrs_DocumentExplorerFlags_None

    reader = STEPCAFControl_Reader()
    reader.SetColorMode(True)
    reader.SetNameMode(True)
    assert reader.ReadFile(str(path)) == 1  # IFSelect_RetDone
    doc = TDocStd_Document(TCollection_ExtendedString("XCAF"))
    assert reader.Transfer(doc)
    out = {}
    explorer = XCAFPrs_DocumentExplorer(doc, XCAFPrs_DocumentExplorerFlags_None)
    while explorer.More():
        node = explorer.Current()
        if not node.IsAssembly:
            attr = TDataStd_Name()
            name = node.Label.FindAttribute(TDataStd_Name.GetID_s(), attr) and attr.Get().ToExtString()
            style = node.Style
            srgb = Quantity_TypeOfColor.Quantity_TOC_sRGB
            rgb = style.GetColorSurf().Values(srgb) if style.IsSetColorSurf() else None
            color = None if rgb is None else (*np.round(rgb, xcaf.COLOR_DECIMALS), 1.0)
            shape = XCAFDoc_ShapeTool.GetShape_s(node.RefLabel).Moved(node.Location)
            out[name] = (color, _box([shape]))
        explorer.Next()
    return out


def _assert_placed(got: dict[str, tuple[Any, Any]], faces: bool = True) -> None:
    assert sorted(got) == sorted(PLACED)
    for name, (color, (lo, hi)) in got.items():
        assert color == ({PLACED[name]} if faces else PLACED[name]), name
        np.testing.assert_allclose(lo, BOXES[name][0], rtol=0, atol=BOX_ATOL, err_msg=name)
        np.testing.assert_allclose(hi, BOXES[name][1], rtol=0, atol=BOX_ATOL, err_msg=name)


@pytest.mark.parametrize("kind", ["build123d", "cadquery"])
def test_moved_instances_keep_their_colours(tmp_path, kind):
    """Issue 16: the colour of a moved build123d leaf was not written (OCC's STEP writer finds the item
    of a coloured instance's member only at the member's own location or the identity, and every
    build123d primitive is a compound holding a located solid). Moved, rotated and sub-assembly
    leaves keep colour, name and placement through write_step -> read_step, for occsurf's reader
    and OCC's, and through write_iges -> read_iges (placed copies named after the instance)."""
    from occsurf.bridge.exchange.object_import import model_from_object

    obj = _placed_tree(kind)
    model = model_from_object(obj)
    _assert_placed(_leaves(model, lambda f: f.instance))  # the model holds what the object says
    out = write_step(tmp_path / f"{kind}.step", obj)
    back = read_step(out)
    _assert_placed(_leaves(back, lambda f: f.instance))
    _assert_placed(_occ_leaves(out), faces=False)
    nodes = {path.split("/")[-1]: (n.color, n.location) for path, n in xcaf.iter_nodes(back.assembly)}
    for path, n in xcaf.iter_nodes(model.assembly):
        color, location = nodes[path.split("/")[-1]]
        assert color == n.color, path
        np.testing.assert_allclose(location, n.location, rtol=0, atol=BOX_ATOL, err_msg=path)
    iges = read_iges(write_iges(tmp_path / f"{kind}.igs", obj))
    _assert_placed(_leaves(iges, lambda f: f.name))


def test_unlocated_items_keeps_a_part_without_located_members():
    """The written part is the part itself unless a member inside a compound is located; then every
    member is unplaced, the faces in the same order and at the same place."""
    from OCP.TopLoc import TopLoc_Location

    from occsurf.bridge.exchange.xcaf_write import _explore_faces, _unlocated_items

    plain = bd.Box(1, 1, 1).solids()[0].wrapped.Located(TopLoc_Location())
    assert _unlocated_items(plain).IsSame(plain)
    part = (bd.Pos(3, 0, 0) * bd.Rot(0, 0, 30) * bd.Box(2, 1, 1)).wrapped
    written = _unlocated_items(part)
    assert written.Location().IsEqual(part.Location())  # the part's own placement stays
    before, after = _explore_faces(part), _explore_faces(written)
    assert len(after) == len(before) == 6
    assert all(f.Location().IsIdentity() for f in _explore_faces(written.Located(TopLoc_Location())))
    for f, g in zip(before, after):
        np.testing.assert_allclose(np.ravel(_box([g])), np.ravel(_box([f])), rtol=0, atol=1e-12)
