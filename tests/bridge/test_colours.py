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
