"""``occsurf convert``: STEP <-> IGES <-> STEP keeping structure, names, colours, units; saying what is lost.

The command runs in a fresh process (:func:`run_cli`), reading its input in a worker; bad input gives
exit status 2 and one line on stderr, never a traceback, and never an output file.
"""

from __future__ import annotations

import copy
import json
import os
import re
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from occsurf.algorithms.errors import ExchangeError, InvalidGeometryError
from occsurf.bridge.cli import convert as cli_convert
from occsurf.bridge.exchange import xcaf
from occsurf.bridge.exchange.convert import convert
from occsurf.bridge.exchange.step_iges import read_iges, read_step

bd = pytest.importorskip("build123d")

REPO = Path(__file__).resolve().parents[2]
REALDATA = REPO.parent / "shared" / "realdata"


def run_cli(*args: str, env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    full_env = dict(os.environ)
    full_env["PYTHONPATH"] = os.pathsep.join(x for x in (str(REPO), full_env.get("PYTHONPATH")) if x)
    full_env.update(env or {})
    return subprocess.run([sys.executable, "-m", "occsurf.bridge.cli", "convert", *args], capture_output=True,
                          text=True, cwd=REPO, env=full_env, timeout=600)


@pytest.fixture(scope="module")
def assembly(tmp_path_factory) -> Path:
    """Two instances (red, blue) of one plate with two holes, and a half-transparent green post."""
    plate = bd.Box(40, 20, 2) - bd.Cylinder(3, 5) - bd.Pos(10, 0, 0) * bd.Cylinder(2, 5)
    a, b = copy.copy(plate), copy.copy(plate)
    a.label, a.color = "plate_a", bd.Color(1, 0, 0)
    b.label, b.color, b.location = "plate_b", bd.Color(0, 0, 1), bd.Location((0, 0, 10))
    post = bd.Pos(30, 0, 0) * bd.Cylinder(5, 10)
    post.label, post.color = "post", bd.Color(0, 1, 0, 0.5)
    path = tmp_path_factory.mktemp("convert") / "assembly.step"
    bd.export_step(bd.Compound(label="assembly", children=[a, b, post]), path)
    return path


def _props(model) -> list[tuple]:
    return [(f.name, f.color, f.layer, f.instance) for f in model.faces]


@pytest.mark.slow
def test_step_to_step_keeps_everything(tmp_path, assembly):
    out = tmp_path / "out.stp"
    proc = run_cli(str(assembly), str(out))
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"{assembly} (STEP) -> {out} (STEP, mm): 19 faces, 0 free curves")
    assert proc.stderr == ""
    assert _props(read_step(out)) == _props(read_step(assembly))
    assert re.search(rb"CARTESIAN_POINT\('',\(-?\d\.\d{16}E[+-]\d\d", out.read_bytes())  # 17 digits


@pytest.mark.slow
def test_step_to_iges_says_what_is_lost(tmp_path, assembly):
    out = tmp_path / "out.igs"
    proc = run_cli(str(assembly), str(out))
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.splitlines()[1:]
    assert "IGES has no assembly instances: 2 instances of 'plate_b' written as copies" in lines
    assert "IGES has no transparency: the alpha of 3 faces is dropped (their colour is kept)" in lines
    assert any(line.startswith("IGES keeps 10 significant digits") for line in lines)
    assert not any("names of" in line or "colours of" in line for line in lines)  # measured: carried
    iges = read_iges(out)
    assert [f.name for f in iges.faces] == [f.name for f in read_step(assembly).faces]
    back = tmp_path / "back.step"
    proc = run_cli(str(out), str(back))
    assert proc.returncode == 0 and proc.stdout.splitlines()[1:] == [], proc.stdout
    assert [f.name for f in read_step(back).faces] == [f.name for f in iges.faces]


@pytest.mark.slow
def test_unit_and_digits(tmp_path, assembly):
    out = tmp_path / "m.step"
    proc = run_cli(str(assembly), str(out), "--unit", "m", "--digits", "13")
    assert proc.returncode == 0, proc.stderr
    assert "(STEP, m)" in proc.stdout
    text = out.read_bytes()
    assert b"SI_UNIT($,.METRE.)" in text
    assert re.search(rb"CARTESIAN_POINT\('',\(-?\d\.\d{12}E[+-]\d\d,", text)
    model = read_step(out)
    assert (model.unit, model.unit_scale) == ("m", 1000.0)
    again = tmp_path / "m.igs"  # the input's unit by default
    assert run_cli(str(out), str(again)).returncode == 0
    assert read_iges(again).unit == "m"


def test_library_call_and_lost_layer_names(tmp_path, assembly):
    """The command's work is a library call; layer names survive IGES (named levels)."""
    import dataclasses

    model = read_step(assembly)
    tree = model.assembly
    named = dataclasses.replace(tree, children=tuple(dataclasses.replace(c, layer="parts") for c in tree.children))
    from occsurf.bridge.exchange.step_iges import write_step

    src = write_step(tmp_path / "layers.step", named)
    report = convert(src, tmp_path / "layers.igs", isolated=False)
    assert report.n_faces == 19 and report.target_format == "iges"
    # IGES levels are numbers; occsurf names the level 'parts' with a 406-3 property and reads it back
    assert not any(line.startswith("layers") for line in report.not_carried), report.not_carried
    assert {f.layer for f in read_iges(tmp_path / "layers.igs").faces} == {"parts"}
    report = convert(src, tmp_path / "layers2.step", isolated=False)
    assert report.not_carried == []


def test_face_names_and_layers_through_iges(tmp_path, assembly):
    """Faces named and layered on their own: STEP -> IGES -> STEP reports nothing lost but digits."""
    import dataclasses

    from occsurf.bridge.exchange.step_iges import write_step

    model = read_step(assembly)
    faces = list(model.faces)
    for i, name, layer in ((0, "bottom", "7"), (5, "bore", "holes"), (18, "top cap", "holes")):
        faces[i] = dataclasses.replace(faces[i], name=name, layer=layer)
    src = write_step(tmp_path / "named.step", dataclasses.replace(model, faces=faces))
    report = convert(src, tmp_path / "named.igs", isolated=False)
    assert [line for line in report.not_carried if not line.startswith("IGES ")] == [], report.not_carried
    # a face of a part is named in the part: both plate instances carry 'bottom' and layer '7'
    want = [(f.name, f.layer) for f in read_step(src).faces]
    assert want[0] == want[8] == ("bottom", "7") and want[18] == ("top cap", "holes")
    assert [(f.name, f.layer) for f in read_iges(tmp_path / "named.igs").faces] == want
    report = convert(tmp_path / "named.igs", tmp_path / "named_back.step", isolated=False)
    assert report.not_carried == []
    assert [(f.name, f.layer) for f in read_step(tmp_path / "named_back.step").faces] == want


@pytest.mark.slow
@pytest.mark.parametrize("case", ["missing", "truncated", "garbage", "directory"])
def test_bad_input_one_line_exit_2(tmp_path, assembly, case):
    src = tmp_path / "in.step"
    if case == "truncated":
        src.write_bytes(assembly.read_bytes()[:3000])
    elif case == "garbage":
        src.write_bytes(os.urandom(4000))
    elif case == "directory":
        src.mkdir()
    out = tmp_path / "out.igs"
    proc = run_cli(str(src), str(out))
    assert proc.returncode == 2
    assert "Traceback" not in proc.stderr
    assert len(proc.stderr.splitlines()) == 1 and proc.stderr.startswith(f"occsurf: {src}: "), proc.stderr
    assert not out.exists()


@pytest.mark.slow
def test_bad_arguments(tmp_path, assembly):
    for args in ([str(assembly), str(tmp_path / "x.txt")], [str(assembly), str(tmp_path / "x.step"), "--unit", "furlong"],
                 [str(assembly), str(tmp_path / "x.step"), "--digits", "30"], [str(assembly), str(tmp_path)]):
        proc = run_cli(*args)
        assert proc.returncode == 2, args
        assert "Traceback" not in proc.stderr
    assert not list(tmp_path.glob("x.*"))
    with pytest.raises(InvalidGeometryError, match="unit"):
        convert(assembly, tmp_path / "x.step", unit="furlong")
    with pytest.raises(InvalidGeometryError, match="target"):
        convert(assembly, tmp_path / "x.txt")
    with pytest.raises(ExchangeError, match="no such file"):
        convert(tmp_path / "none.step", tmp_path / "x.step")


@pytest.mark.slow
def test_crash_in_reader_is_isolated(tmp_path, assembly):
    hook = tmp_path / "hook"
    hook.mkdir()
    (hook / "sitecustomize.py").write_text(textwrap.dedent("""
        import os, signal, sys
        def _crash(event, args):
            if event == "open" and str(args[0]).endswith("crash-me.step"):
                os.kill(os.getpid(), signal.SIGSEGV)
        sys.addaudithook(_crash)
    """))
    src = tmp_path / "crash-me.step"
    src.write_bytes(assembly.read_bytes())
    out = tmp_path / "out.step"
    proc = run_cli(str(src), str(out), env={"PYTHONPATH": os.pathsep.join([str(hook), str(REPO)])})
    assert proc.returncode == 2
    assert proc.stderr.splitlines() == [f"occsurf: {src}: the reader process crashed while reading the file "
                                        "(killed by SIGSEGV; a fault inside OpenCascade)"]
    assert not out.exists()


def test_cli_units_match_library():
    assert cli_convert.UNITS == xcaf.WRITE_UNITS


def test_inspect_json_reports_unit(tmp_path, assembly):
    from occsurf.bridge.exchange.step_iges import write_step

    metres = write_step(tmp_path / "m.step", bd.Box(1, 2, 3), names="box", unit="inch")
    proc = subprocess.run([sys.executable, "-m", "occsurf.bridge.cli", "inspect", "--json", "--samples", "3",
                           str(metres), str(assembly)], capture_output=True, text=True, cwd=REPO, timeout=600,
                          env={**os.environ, "PYTHONPATH": str(REPO)})
    assert proc.returncode == 0, proc.stderr
    assert [f["unit"] for f in json.loads(proc.stdout)["files"]] == ["inch", "mm"]


@pytest.mark.slow
@pytest.mark.parametrize("name", ["occt__linkrods.step", "pythonocc-core__sunglasses_lens.igs"])
def test_real_files_convert(tmp_path, name):
    src = REALDATA / name
    if not src.exists():
        pytest.skip(f"{src} not present (public CAD files in ../shared/realdata)")
    target = tmp_path / ("out.igs" if name.endswith(".step") else "out.step")
    proc = run_cli(str(src), str(target))
    assert proc.returncode == 0, proc.stderr
    lost = proc.stdout.splitlines()[1:]
    assert all(line.startswith("IGES keeps 10") for line in lost), lost  # nothing else lost
