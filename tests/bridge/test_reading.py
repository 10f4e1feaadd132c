"""The one rule for the format of a STEP/IGES input (:mod:`occsurf.bridge.exchange.reading`, issue 26).

The command line and :func:`occsurf.bridge.exchange.convert.convert` each had their own: the CLI trusted
``.step/.stp/.iges/.igs`` and otherwise required a STEP header or an IGES start line; convert also trusted
``.p21``, read anything unrecognised as IGES and an unreadable file as STEP. The stricter one is kept for
both: a suffix decides, else the first bytes, else the file is refused with a message naming the problem;
content that contradicts a trusted suffix is refused by the reader's framing checks before OCC parses it.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from occsurf.algorithms.errors import ExchangeError, InvalidGeometryError
from occsurf.bridge.exchange import reading
from occsurf.bridge.exchange.convert import convert, source_format
from occsurf.bridge.exchange.reading import (
    SUFFIXES,
    TARGET_SUFFIXES,
    expand,
    read_model,
    sniff_format,
    target_format,
)

SAMPLES = Path(__file__).resolve().parents[2] / "step_samples"
STEP_HEAD = b"ISO-10303-21;\nHEADER;\n"
IGES_START = b"a start line".ljust(72) + b"S      1\n"


@pytest.mark.parametrize(("name", "fmt"), [("a.step", "step"), ("a.stp", "step"), ("a.STEP", "step"),
                                           ("a.Stp", "step"), ("a.iges", "iges"), ("a.igs", "iges"),
                                           ("a.IGS", "iges"), ("dir.v2/a.IGES", "iges")])
def test_a_known_suffix_decides_without_reading(tmp_path: Path, name: str, fmt: str) -> None:
    assert sniff_format(tmp_path / name) == fmt  # the file does not exist: nothing is read
    assert sniff_format(str(tmp_path / name)) == fmt


@pytest.mark.parametrize("head", [STEP_HEAD, b"\xef\xbb\xbf \r\n" + STEP_HEAD, b"iso-10303-21;\n"])
@pytest.mark.parametrize("name", ["model.p21", "model.dat", "model"])
def test_other_suffixes_go_by_a_step_header(tmp_path: Path, name: str, head: bytes) -> None:
    path = tmp_path / name
    path.write_bytes(head + b"DATA;\nENDSEC;\nEND-ISO-10303-21;\n")
    assert sniff_format(path) == "step"


@pytest.mark.parametrize("name", ["model.p21", "model.dat", "model"])
def test_other_suffixes_go_by_an_iges_start_line(tmp_path: Path, name: str) -> None:
    path = tmp_path / name
    path.write_bytes(IGES_START + b"G line".ljust(72) + b"G      1\n")
    assert sniff_format(path) == "iges"


@pytest.mark.parametrize(("name", "shown"), [("notes.txt", "'.txt'"), ("model.p21", "'.p21'"), ("README", "'none'")])
def test_anything_else_is_refused_naming_the_suffix(tmp_path: Path, name: str, shown: str) -> None:
    path = tmp_path / name
    path.write_bytes(b"hello, this is not CAD\n")
    with pytest.raises(ExchangeError, match=f"not a STEP or IGES file \\(suffix {shown}, unrecognised header\\)"):
        sniff_format(path)
    path.write_bytes(b"")
    with pytest.raises(ExchangeError, match="not a STEP or IGES file"):
        sniff_format(path)


def test_an_unreadable_file_without_a_known_suffix_is_refused(tmp_path: Path) -> None:
    with pytest.raises(ExchangeError, match="^cannot read: "):
        sniff_format(tmp_path / "missing.dat")
    with pytest.raises(ExchangeError, match="^cannot read: "):
        sniff_format(tmp_path)  # a folder


def test_content_that_contradicts_the_suffix_is_refused_by_the_reader(tmp_path: Path) -> None:
    iges_as_step = tmp_path / "really_iges.step"
    iges_as_step.write_bytes((SAMPLES / "mixed.igs").read_bytes())
    assert sniff_format(iges_as_step) == "step"  # the suffix is trusted...
    with pytest.raises(ExchangeError, match=r"really_iges\.step: not a STEP file"):
        read_model(iges_as_step)  # ...and the STEP reader's framing check refuses the content
    step_as_iges = tmp_path / "really_step.igs"
    step_as_iges.write_bytes((SAMPLES / "loft.step").read_bytes())
    assert sniff_format(step_as_iges) == "iges"
    with pytest.raises(ExchangeError, match=r"really_step\.igs: not an IGES file"):
        read_model(step_as_iges)


def test_read_model_sniffs_an_unknown_suffix(tmp_path: Path) -> None:
    renamed = tmp_path / "loft.p21"
    renamed.write_bytes((SAMPLES / "loft.step").read_bytes())
    assert len(read_model(renamed).faces) == len(read_model(SAMPLES / "loft.step").faces) == 11


def test_target_format_by_suffix_only() -> None:
    assert [target_format(f"out{s}") for s in (".step", ".STP", ".p21", ".iges", ".Igs")] == \
        ["step", "step", "step", "iges", "iges"]
    with pytest.raises(InvalidGeometryError, match=r"expected a file name ending in \.step, \.stp, \.p21, \.iges, "
                                                   r"\.igs, got 'out\.txt'"):
        target_format("out.txt")


def test_folders_are_searched_by_the_trusted_suffixes(tmp_path: Path) -> None:
    for name in ("a.STEP", "b.igs", "c.p21", "d.txt", "e.stp"):
        (tmp_path / name).write_bytes(STEP_HEAD)
    assert [Path(p).name for _, p, err in expand([str(tmp_path)]) if p is not None and err is None] == \
        ["a.STEP", "b.igs", "e.stp"]
    assert SUFFIXES == (".step", ".stp", ".iges", ".igs")


def test_convert_and_the_command_line_use_the_one_rule(tmp_path: Path) -> None:
    from occsurf.bridge.cli import _common
    from occsurf.bridge.cli import convert as cli_convert

    assert _common.sniff_format is reading.sniff_format and _common.SUFFIXES is reading.SUFFIXES
    assert cli_convert._OUT_SUFFIXES == tuple(s for suffixes in TARGET_SUFFIXES.values() for s in suffixes)
    garbage = tmp_path / "garbage.dat"
    garbage.write_bytes(b"hello\n")
    # convert used to read this as IGES; now it is refused before any reader, naming the file
    with pytest.raises(ExchangeError, match=r"garbage\.dat: not a STEP or IGES file \(suffix '\.dat'"):
        source_format(garbage)
    with pytest.raises(ExchangeError, match=r"garbage\.dat: not a STEP or IGES file"):
        convert(garbage, tmp_path / "out.step", isolated=False)
    assert not (tmp_path / "out.step").exists()
    with pytest.raises(ExchangeError, match=r"missing\.dat: cannot read: "):
        source_format(tmp_path / "missing.dat")
    iges_p21 = tmp_path / "model.p21"
    iges_p21.write_bytes(IGES_START)
    assert source_format(iges_p21) == "iges"  # convert used to take any .p21 for STEP
