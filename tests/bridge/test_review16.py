"""Regressions found by reviewing issue 16 as a user: the command line's one-line errors and Ctrl-C.

* A usage error (``occsurf convert IN OUT --unit furlong``, ``--digits 40``, a missing argument, an
  unknown command) printed argparse's usage block and then its message: several lines, where the
  README promises ``one line`` for a bad unit or digit count.
* Ctrl-C while ``occsurf convert`` imported OCP in the command's own process came out as
  ``ImportError: initialization failed`` with a traceback and exit status 1 (OCP's module
  initialisation turns the ``KeyboardInterrupt`` into an ``ImportError``).
"""

from __future__ import annotations

import os
import signal

import pytest

from occsurf.bridge import cli
from occsurf.bridge.cli._common import EXIT_ERROR, EXIT_INTERRUPTED, guarded


@pytest.mark.parametrize(("args", "start"), [
    (["convert", "in.step", "out.igs", "--unit", "furlong"], "occsurf: convert: argument --unit: invalid choice: 'furlong'"),
    (["convert", "in.step", "out.step", "--digits", "40"], "occsurf: convert: argument --digits: expected an integer"),
    (["convert", "in.step"], "occsurf: convert: the following arguments are required: OUT"),
    (["fill", "in.step"], "occsurf: fill: the following arguments are required: --out"),
    (["inspect", "--samples", "x"], "occsurf: inspect: argument --samples"),
    (["no-such-command"], "occsurf: argument COMMAND: invalid choice: 'no-such-command'"),
])
def test_usage_error_is_one_line(capsys, monkeypatch, tmp_path, args, start):
    monkeypatch.chdir(tmp_path)
    code = cli.main(args)
    out, err = capsys.readouterr()
    assert code == EXIT_ERROR and out == ""
    assert len(err.splitlines()) == 1 and err.startswith(start), err
    assert not list(tmp_path.iterdir())  # nothing written


def test_help_still_prints_usage(capsys):
    assert cli.main(["convert", "--help"]) == 0
    assert capsys.readouterr().out.startswith("usage: occsurf convert")


def _import_interrupted_by_ctrl_c(ns):
    """What OCP's import does when Ctrl-C arrives during its initialisation."""
    try:
        os.kill(os.getpid(), signal.SIGINT)
        for _ in range(1000):  # the handler runs between bytecodes
            pass
    except KeyboardInterrupt:
        raise ImportError("initialization failed") from None
    raise AssertionError("SIGINT was not delivered")


def test_ctrl_c_turned_into_import_error_is_an_interruption(capsys):
    before = signal.getsignal(signal.SIGINT)
    if before is not signal.default_int_handler:
        pytest.skip("SIGINT is not Python's default handler here")
    assert guarded(_import_interrupted_by_ctrl_c, None) == EXIT_INTERRUPTED
    assert capsys.readouterr().err == "occsurf: interrupted\n"
    assert signal.getsignal(signal.SIGINT) is before  # the command's handler is removed again


def test_import_error_without_ctrl_c_is_not_hidden():
    def broken(ns):
        raise ImportError("a real one")

    with pytest.raises(ImportError, match="a real one"):
        guarded(broken, None)
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_ctrl_c_while_reading_back_says_the_output_was_written(capsys, monkeypatch, tmp_path):
    """Ctrl-C after ``convert`` replaced OUT (while it reads OUT back to compare) says so: OUT is whole
    and new, but nothing was compared; before that point OUT is untouched (atomic write)."""
    bd = pytest.importorskip("build123d")
    from occsurf.bridge.exchange import convert as convert_module
    from occsurf.bridge.exchange.step_iges import write_step

    src = write_step(tmp_path / "box.step", bd.Box(1, 2, 3), names="box")
    out = tmp_path / "out.igs"
    out.write_text("old")

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(convert_module, "compare", interrupted)
    assert cli.main(["convert", str(src), str(out), "--in-process"]) == EXIT_INTERRUPTED
    err = capsys.readouterr().err.splitlines()
    assert err == [f"occsurf: {out}: written, but interrupted while reading it back: nothing was compared",
                   "occsurf: interrupted"]
    assert out.read_bytes().rstrip().endswith(b"T0000001")  # the whole new IGES file

    monkeypatch.setattr("occsurf.bridge.exchange.step_iges.write_iges", interrupted)
    out.write_text("old")
    assert cli.main(["convert", str(src), str(out), "--in-process"]) == EXIT_INTERRUPTED
    assert capsys.readouterr().err.splitlines() == ["occsurf: interrupted"]
    assert out.read_text() == "old"


def _plates(path, x_b: float):
    bd = pytest.importorskip("build123d")
    plate = bd.Box(10, 20, 2) - bd.Cylinder(2, 2)
    a = plate.moved(bd.Location((0, 0, 0)))
    a.label, a.color = "plate_a", bd.Color("red")
    b = plate.moved(bd.Location((x_b, 0, 0)))
    b.label, b.color = "plate_b", bd.Color("blue")
    bd.export_step(bd.Compound(label="plates", children=[a, b]), str(path))
    return path


def test_compare_reports_a_moved_instance(tmp_path):
    """An instance placed elsewhere keeps its faces' names, colours, areas and wires: ``convert``'s
    comparison missed it. The faces' centroids show it (beyond POSITION_RTOL of the model's size)."""
    from occsurf.bridge.exchange.convert import POSITION_RTOL, compare
    from occsurf.bridge.exchange.step_iges import read_step

    here = read_step(_plates(tmp_path / "here.step", 30.0))
    there = read_step(_plates(tmp_path / "there.step", 45.0))
    assert compare(here, read_step(tmp_path / "here.step"), "step", "mm") == []
    lines = compare(here, there, "step", "mm")
    assert len(lines) == 1 and lines[0].startswith("positions of 7 of 14 faces not carried"), lines
    assert ": 15, model diagonal 44.8)" in lines[0]  # plate_b's faces moved by 15 mm; x -5..35, y 20, z 2
    assert 15.0 / 44.8 > 1000 * POSITION_RTOL  # far above the tolerance (noise measured: <= 1.2e-5)


def test_compare_reports_assembly_structure(tmp_path):
    """STEP -> STEP: part names and which instances share a part are compared too (a face names its
    instance path, not its part)."""
    import dataclasses

    from occsurf.bridge.exchange.convert import compare
    from occsurf.bridge.exchange.step_iges import read_step

    model = read_step(_plates(tmp_path / "plates.step", 30.0))
    again = read_step(tmp_path / "plates.step")
    assert compare(model, again, "step", "mm") == []
    root = again.assembly
    a, b = root.children
    renamed = dataclasses.replace(again, assembly=dataclasses.replace(
        root, children=(a, dataclasses.replace(b, part="plate_c"))))
    assert compare(model, renamed, "step", "mm") == [
        "part names of 1 of 3 assembly nodes not carried (plates/plate_b: 'plate_b' read back as 'plate_c')"]
    one = dataclasses.replace(again, assembly=dataclasses.replace(root, children=(a,)))
    assert compare(model, one, "step", "mm") == [
        "assembly structure not carried: 3 nodes written, 2 read back ('plates': 2 children read back as 1)"]
    flat = dataclasses.replace(again, assembly=None)
    assert compare(model, flat, "step", "mm") == ["assembly structure not carried: the file read back has none (flat)"]


def test_build123d_colours_come_back_as_set(tmp_path):
    """``read_step(..., as_="build123d")`` gave ``bd.Color(*linear_rgba)``: build123d takes sRGB there, so
    a part coloured ``Color(0.2, 0.4, 0.6, 0.5)`` came back as ``(0.033, 0.133, 0.319, 0.5)`` (pure
    red and blue, as in the README, hide it). Written back, the file's colour is the original's."""
    bd = pytest.importorskip("build123d")
    from occsurf.bridge.exchange.step_iges import read_step, write_step

    part = bd.Box(5, 5, 5)
    part.label, part.color = "part", bd.Color(0.2, 0.4, 0.6, 0.5)
    path = tmp_path / "grey_blue.step"
    bd.export_step(bd.Compound(label="top", children=[part]), str(path))
    obj = read_step(path, as_="build123d")
    # 1e-6: OCC keeps colours as linear float32; build123d's tuple gives sRGB rounded to 7 decimals
    assert tuple(obj.children[0].color) == pytest.approx((0.2, 0.4, 0.6, 0.5), abs=1e-6)
    again = read_step(write_step(tmp_path / "again.step", obj))
    before = {f.color for f in read_step(path).faces}
    after = {f.color for f in again.faces}
    assert len(before) == len(after) == 1
    assert after.pop() == pytest.approx(before.pop(), abs=1e-7)


def test_fewer_step_digits_are_reported(tmp_path):
    """``--digits N`` below 17 is a loss by construction (as IGES's 10 digits): said even when the
    read-back comparison finds nothing (the plates' values are all exact in 5 digits)."""
    from occsurf.bridge.exchange.convert import convert, format_losses
    from occsurf.bridge.exchange.step_iges import read_step

    src = _plates(tmp_path / "plates.step", 30.0)
    report = convert(src, tmp_path / "d5.step", digits=5, isolated=False)
    assert report.not_carried == ["STEP written with 5 significant digits (--digits): values move by up to "
                                  "5e-5 of their size"]
    model = read_step(src)
    assert format_losses(model, "step", None) == format_losses(model, "step", 17) == []
