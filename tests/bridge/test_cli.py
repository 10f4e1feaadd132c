"""Tests of the ``occsurf`` command line (``bridge/cli/``) and of the files in ``step_samples/``.

Most tests call :func:`occsurf.bridge.cli.main` with ``--in-process`` (OCC is loaded once, in pytest); the
ones that need a real process boundary (``python -m occsurf.bridge.cli``, crash isolation, ``--help``
without OCC, the public files of ``../shared/realdata``) run it with :mod:`subprocess`.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from occsurf.bridge import cli
from occsurf.bridge.cli import _common as cli_common

REPO = Path(__file__).resolve().parents[2]
SAMPLES = REPO / "step_samples"
REALDATA = REPO.parent / "shared" / "realdata"

#: Our evaluation of a B-spline face vs OCC's on the *same* (bit-exact) data: only round-off
#: differs. Relative to the bbox diagonal, the sample faces (degree <= 10, near the origin) stay
#: below 1e-14; 1e-12 leaves a margin of 100.
SAMPLE_TOL = 1e-12

#: The public files have degree-13 thread faces, up to 286 poles per direction and coordinates far
#: from the origin compared with small faces, which amplifies round-off in both evaluators (observed
#: <= 1e-13). 1e-9 still catches any real disagreement (a wrong knot, weight or pole moves a point
#: by a visible fraction of the face), while tolerating other BLAS/compilers.
REALDATA_TOL = 1e-9

#: Face counts as OCC 7.9.3 loads them (checked by hand; SOURCES.md of the folder says the same).
REALDATA_FACES = {
    "build123d__M6-1x12-countersunk-screw.step": 28,
    "occt__bearing.iges": 213,
    "occt__linkrods.step": 37,
    "pythonocc-core__sunglasses_lens.igs": 9,
}
REALDATA_FREE_FORM = {
    "build123d__M6-1x12-countersunk-screw.step": 6,
    "occt__bearing.iges": 213,
    "occt__linkrods.step": 18,
    "pythonocc-core__sunglasses_lens.igs": 9,
}

SAMPLE_FILES = ["loft.step", "mixed.igs", "nurbs_torus.step", "periodic_vase.step", "swept_tube.step"]


def run_cli(*args: str, cwd: Path | None = None, env: dict[str, str] | None = None,
            timeout: float = 600) -> subprocess.CompletedProcess[str]:
    """``python -m occsurf.bridge.cli ARGS`` in a fresh process."""
    full_env = dict(os.environ)
    full_env["PYTHONPATH"] = os.pathsep.join(x for x in (str(REPO), full_env.get("PYTHONPATH")) if x)
    if env:
        full_env.update(env)
    return subprocess.run([sys.executable, "-m", "occsurf.bridge.cli", *args], capture_output=True, text=True,
                          cwd=cwd or REPO, env=full_env, timeout=timeout)


def run_main(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    code = cli.main(list(args))
    out, err = capsys.readouterr()
    return code, out, err


def check_schema(doc: dict) -> None:
    """The JSON fields promised to machines, with their types."""
    assert isinstance(doc["files"], list)
    for f in doc["files"]:
        assert isinstance(f["path"], str)
        assert f["error"] is None or isinstance(f["error"], str)
        assert isinstance(f["faces"], list)
        for face in f["faces"]:
            assert isinstance(face["index"], int)
            assert isinstance(face["surface_type"], str)
            assert isinstance(face["periodic"], list) and len(face["periodic"]) == 2
            assert all(isinstance(x, bool) for x in face["periodic"])
            assert face["continuity"] in ("C0", "G1", "C1", "G2", "C2", "C3", "CN")
            free_form = face["surface_type"] in ("BSplineSurface", "BezierSurface")
            if free_form and face["error"] is None:
                assert [type(x) for x in face["degree"]] == [int, int]
                assert [type(x) for x in face["poles"]] == [int, int]
                assert isinstance(face["rational"], bool)
                assert isinstance(face["max_deviation"], float)
            if not free_form:
                assert face["degree"] is None and face["poles"] is None and face["max_deviation"] is None


# ------------------------------------------------------------------------------------ samples
@pytest.fixture(scope="module")
def samples_doc() -> dict:
    """``inspect --json`` over step_samples/, in this process."""
    import contextlib
    import io

    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        code = cli.main(["inspect", str(SAMPLES), "--json", "--samples", "11", "--in-process"])
    assert code == 0, buf.getvalue()
    return json.loads(buf.getvalue())


def test_samples_json_schema_and_exit_status(samples_doc: dict) -> None:
    check_schema(samples_doc)
    assert [Path(f["path"]).name for f in samples_doc["files"]] == SAMPLE_FILES
    for f in samples_doc["files"]:
        assert f["error"] is None
        assert [face["index"] for face in f["faces"]] == list(range(len(f["faces"])))
        assert all(face["error"] is None for face in f["faces"]), f["path"]


def test_samples_free_form_deviation(samples_doc: dict) -> None:
    devs = [face["max_deviation"] for f in samples_doc["files"] for face in f["faces"]
            if face["surface_type"] in ("BSplineSurface", "BezierSurface")]
    assert len(devs) == 13
    assert max(devs) <= SAMPLE_TOL


def test_samples_cover_the_required_kinds(samples_doc: dict) -> None:
    """The samples hold a loft, a rational face, a periodic face and an IGES file."""
    files = {Path(f["path"]).name: f for f in samples_doc["files"]}
    loft = files["loft.step"]["faces"]
    assert sum(face["surface_type"] == "BSplineSurface" for face in loft) >= 3
    free = [face for f in files.values() for face in f["faces"] if face["surface_type"] == "BSplineSurface"]
    assert any(face["rational"] for face in free)
    assert any(face["periodic"][0] or face["periodic"][1] for face in free)
    torus = files["nurbs_torus.step"]["faces"]
    assert [(t["degree"], t["poles"], t["rational"]) for t in torus] == [([2, 2], [9, 9], True)]
    vase = files["periodic_vase.step"]["faces"]
    assert vase[0]["periodic"] == [True, False] and vase[0]["rational"] is False
    assert files["mixed.igs"]["format"] == "iges"
    assert {face["name"] for face in files["mixed.igs"]["faces"]} == {"bicubic patch", "filleted block"}


def test_sample_files_are_small() -> None:
    for name in SAMPLE_FILES:
        assert (SAMPLES / name).stat().st_size < 300_000, name


@pytest.mark.slow
def test_make_samples_is_reproducible(tmp_path: Path) -> None:
    """Rebuilding gives the committed files byte for byte (time stamps are fixed)."""
    proc = subprocess.run([sys.executable, str(SAMPLES / "make_samples.py"), str(tmp_path)],
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    for name in SAMPLE_FILES:
        assert (tmp_path / name).read_bytes() == (SAMPLES / name).read_bytes(), name


def test_table_output(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err = run_main(capsys, "inspect", str(SAMPLES / "swept_tube.step"), "--samples", "5", "--in-process")
    assert code == 0 and err == ""
    lines = out.splitlines()
    assert lines[0].endswith("swept_tube.step (STEP)")
    header = next(ln for ln in lines if ln.strip().startswith("face"))
    for col in ("type", "degree", "poles", "rational", "periodic", "continuity", "max dev"):
        assert col in header
    row0 = next(ln.split() for ln in lines if ln.split()[:1] == ["0"])
    assert row0[1:7] == ["BSplineSurface", "3x9", "12x24", "no", "u", "C2"]
    assert float(row0[7]) <= SAMPLE_TOL
    plane = next(ln.split() for ln in lines if ln.split()[:1] == ["1"])
    assert plane[1] == "Plane" and plane[2:5] == ["-", "-", "-"] and plane[7] == "-"
    summary = lines[-1]
    assert "3 faces, 1 free-form, worst deviation" in summary and summary.endswith(" s")


# ------------------------------------------------------------------------------------ errors
@pytest.mark.slow
def test_bad_and_missing_files_beside_a_good_one(tmp_path: Path) -> None:
    """Run as ``python -m occsurf.bridge.cli``: exit 2, the good file still reported, one line per bad file."""
    garbage = tmp_path / "garbage.step"
    garbage.write_bytes(bytes(range(256)) * 8)  # binary junk, fixed
    empty = tmp_path / "empty.igs"
    empty.write_bytes(b"")
    missing = tmp_path / "missing.stp"
    good = SAMPLES / "nurbs_torus.step"
    proc = run_cli("inspect", str(garbage), str(good), str(missing), str(empty), "--json", "--samples", "5")
    assert proc.returncode == 2
    assert "Traceback" not in proc.stderr and "Traceback" not in proc.stdout
    err_lines = proc.stderr.splitlines()
    assert len(err_lines) == 3, proc.stderr
    for line, bad in zip(err_lines, (garbage, missing, empty)):
        assert line.startswith(f"occsurf: {bad}: ") and len(line) > len(f"occsurf: {bad}: ")
    doc = json.loads(proc.stdout)
    check_schema(doc)
    files = {Path(f["path"]).name: f for f in doc["files"]}
    assert list(files) == ["garbage.step", "nurbs_torus.step", "missing.stp", "empty.igs"]
    assert files["nurbs_torus.step"]["error"] is None and len(files["nurbs_torus.step"]["faces"]) == 1
    assert files["nurbs_torus.step"]["faces"][0]["max_deviation"] <= SAMPLE_TOL
    for name in ("garbage.step", "missing.stp", "empty.igs"):
        assert files[name]["error"] and files[name]["faces"] == []
    assert "no such file" in files["missing.stp"]["error"]


def test_truncated_file_is_an_error(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    data = (SAMPLES / "mixed.igs").read_bytes()
    bad = tmp_path / "cut.igs"
    bad.write_bytes(data[: len(data) // 2])
    code, out, err = run_main(capsys, "inspect", str(bad), "--in-process")
    assert code == 2
    assert err.count("\n") == 1 and err.startswith(f"occsurf: {bad}: ")
    assert "error:" in out


def test_empty_folder_and_unknown_suffix(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    empty_dir = tmp_path / "nothing"
    empty_dir.mkdir()
    renamed = tmp_path / "torus.dat"  # content decides when the suffix does not
    renamed.write_bytes((SAMPLES / "nurbs_torus.step").read_bytes())
    text = tmp_path / "notes.txt"
    text.write_text("hello\n")
    code, out, err = run_main(capsys, "inspect", str(empty_dir), str(renamed), str(text), "--json", "--in-process")
    assert code == 2
    files = json.loads(out)["files"]
    assert [f["error"] is None for f in files] == [False, True, False]
    assert files[1]["format"] == "step" and len(files[1]["faces"]) == 1
    assert "no STEP/IGES files" in files[0]["error"] and "not a STEP or IGES" in files[2]["error"]
    assert len(err.splitlines()) == 2


def test_unexpected_exception_is_reported_not_raised(monkeypatch: pytest.MonkeyPatch,
                                                     capsys: pytest.CaptureFixture[str]) -> None:
    from occsurf.bridge.exchange import step_iges as exchange

    def broken(path):
        raise RuntimeError("boom\nsecond line")

    monkeypatch.setattr(exchange, "read_step", broken)
    code, out, err = run_main(capsys, "inspect", str(SAMPLES / "loft.step"), str(SAMPLES / "mixed.igs"),
                              "--json", "--in-process")
    assert code == 2
    assert err == f"occsurf: {SAMPLES / 'loft.step'}: RuntimeError: boom second line\n"
    files = json.loads(out)["files"]
    assert files[0]["error"] == "RuntimeError: boom second line"
    assert files[1]["error"] is None and len(files[1]["faces"]) == 27


def test_face_failure_stays_with_the_face(monkeypatch: pytest.MonkeyPatch,
                                          capsys: pytest.CaptureFixture[str]) -> None:
    from occsurf.bridge.validation import deviation as validate

    def broken(*args, **kwargs):
        raise ValueError("no grid today")

    monkeypatch.setattr(validate, "surface_deviation", broken)
    code, out, err = run_main(capsys, "inspect", str(SAMPLES / "periodic_vase.step"), "--json", "--in-process")
    assert code == 0 and err == ""  # the file was read; the face says what went wrong
    face = json.loads(out)["files"][0]["faces"][0]
    assert face["max_deviation"] is None and "no grid today" in face["error"]
    assert face["degree"] == [3, 3]


@pytest.mark.slow
@pytest.mark.skipif(os.name != "posix", reason="needs POSIX signals")
def test_crash_inside_the_reader_is_isolated(tmp_path: Path) -> None:
    """A segmentation fault while reading one file: that file is an error, the others are read."""
    hook_dir = tmp_path / "hook"
    hook_dir.mkdir()
    (hook_dir / "sitecustomize.py").write_text(textwrap.dedent("""
        import os, signal, sys
        def _crash(event, args):
            if event == "open" and str(args[0]).endswith("crash-me.step"):
                os.kill(os.getpid(), signal.SIGSEGV)
        sys.addaudithook(_crash)
    """))
    crash = tmp_path / "crash-me.step"
    crash.write_bytes((SAMPLES / "nurbs_torus.step").read_bytes())
    good = [SAMPLES / "periodic_vase.step", SAMPLES / "nurbs_torus.step"]
    proc = run_cli("inspect", str(good[0]), str(crash), str(good[1]), "--json", "--samples", "5",
                   env={"PYTHONPATH": os.pathsep.join([str(hook_dir), str(REPO)])})
    assert proc.returncode == 2, proc.stderr
    assert "Traceback" not in proc.stderr
    assert proc.stderr.splitlines() == [
        f"occsurf: {crash}: the reader process crashed while reading this file "
        "(killed by SIGSEGV; a fault inside OpenCascade)"
    ]
    files = json.loads(proc.stdout)["files"]
    assert [f["error"] is None for f in files] == [True, False, True]
    assert [len(f["faces"]) for f in files] == [1, 0, 1]


@pytest.mark.slow
def test_a_hanging_file_times_out_and_the_others_are_read(tmp_path: Path) -> None:
    """A reader that never returns on one file: that file is reported after --timeout, the others are read."""
    hook_dir = tmp_path / "hook"
    hook_dir.mkdir()
    (hook_dir / "sitecustomize.py").write_text(textwrap.dedent("""
        import sys, time
        def _hang(event, args):
            if event == "open" and str(args[0]).endswith("hang-me.step"):
                time.sleep(3600)
        sys.addaudithook(_hang)
    """))
    hang = tmp_path / "hang-me.step"
    hang.write_bytes((SAMPLES / "nurbs_torus.step").read_bytes())
    good = [SAMPLES / "periodic_vase.step", SAMPLES / "nurbs_torus.step"]
    t0 = time.perf_counter()
    proc = run_cli("inspect", str(good[0]), str(hang), str(good[1]), "--json", "--samples", "5", "--timeout", "4",
                   env={"PYTHONPATH": os.pathsep.join([str(hook_dir), str(REPO)])})
    assert time.perf_counter() - t0 < 120  # the hour-long sleep was cut short
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.splitlines() == [
        f"occsurf: {hang}: reading this file took longer than 4 s; the reader process was stopped (--timeout)"
    ]
    files = json.loads(proc.stdout)["files"]
    assert [f["error"] is None for f in files] == [True, False, True]


@pytest.mark.parametrize("value", ["0", "-1", "nan", "soon"])
def test_bad_timeout_is_rejected(capsys: pytest.CaptureFixture[str], value: str) -> None:
    code, out, err = run_main(capsys, "inspect", "--timeout", value)
    assert code == 2 and "--timeout" in err and "Traceback" not in err


def test_bad_arguments(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err = run_main(capsys, "inspect", "--samples", "1")
    assert code == 2 and "--samples" in err and "Traceback" not in err
    code, out, err = run_main(capsys)
    assert code == 2 and "a command is required" in err
    code, out, err = run_main(capsys, "frobnicate")
    assert code == 2 and "invalid choice" in err


# ------------------------------------------------------------------------------------ defaults
@pytest.mark.slow
def test_default_is_step_samples_from_cwd_or_package(tmp_path: Path) -> None:
    proc = run_cli("inspect", "--samples", "3", cwd=tmp_path)  # no step_samples/ here: the package's
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr == ""
    import occsurf.step_samples

    shipped = Path(occsurf.step_samples.__path__[0])  # the installed copy (the repository's folder if editable)
    for name in SAMPLE_FILES:
        assert f"{shipped / name} (" in proc.stdout
    assert proc.stdout.rstrip().splitlines()[-1].startswith("5 files (0 unreadable), 43 faces, 13 free-form")

    local = tmp_path / "step_samples"  # the current directory's folder wins
    local.mkdir()
    (local / "vase.step").write_bytes((SAMPLES / "periodic_vase.step").read_bytes())
    proc = run_cli("inspect", "--samples", "3", "--json", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert [Path(f["path"]).resolve() for f in json.loads(proc.stdout)["files"]] == [(local / "vase.step").resolve()]


def test_no_samples_folder(monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]) -> None:
    monkeypatch.setattr(cli_common, "find_samples_dir", lambda cwd=None: None)
    code, out, err = run_main(capsys, "inspect")
    assert code == 2 and out == ""
    assert err.startswith("occsurf: no step_samples/ folder found") and err.count("\n") == 1


def test_help_is_fast_and_does_not_load_occ() -> None:
    code = ("import sys, contextlib, io\n"
            "from occsurf.bridge.cli import main\n"
            "with contextlib.redirect_stdout(io.StringIO()) as buf:\n"
            "    assert main(['--help']) == 0 and main(['inspect', '--help']) == 0\n"
            "assert 'inspect' in buf.getvalue() and '--samples' in buf.getvalue()\n"
            "print(sorted(m for m in ('OCP', 'numpy', 'build123d', 'cadquery') if m in sys.modules))\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=REPO, timeout=60)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "[]"


#: Commands that read an untrusted STEP/IGES file (in a worker): each offers --timeout in its usage line.
READING_COMMANDS = ("inspect", "fill", "fit", "render", "check", "convert")
#: ... and --strict (warnings, i.e. damage read around, become exit status 2; nothing written).
STRICT_COMMANDS = ("inspect", "fill", "fit", "render", "convert", "check")


def _usage(command: str) -> str | None:
    import argparse

    parser = cli.build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return sub.choices[command].format_usage() if command in sub.choices else None


@pytest.mark.parametrize("command", READING_COMMANDS)
def test_every_reading_command_offers_timeout_and_strict(command: str) -> None:
    usage = _usage(command)
    if usage is None:
        pytest.skip(f"occsurf {command} is not registered in this tree")
    assert "--timeout" in usage and "--in-process" in usage, usage
    if command in STRICT_COMMANDS:
        assert "--strict" in usage, usage


def test_version(capsys: pytest.CaptureFixture[str]) -> None:
    import occsurf

    assert cli.main(["--version"]) == 0
    assert capsys.readouterr().out.strip() == f"occsurf {occsurf.__version__}"


# ------------------------------------------------------------------------------------ real data
@pytest.mark.slow
@pytest.mark.skipif(not REALDATA.is_dir(), reason=f"public CAD files not present at {REALDATA}")
def test_realdata_all_files() -> None:
    files = sorted(p for p in REALDATA.iterdir() if p.suffix.lower() in (".step", ".stp", ".iges", ".igs"))
    assert sorted(p.name for p in files) == sorted(REALDATA_FACES)
    proc = run_cli("inspect", *map(str, files), "--json", "--samples", "5")
    assert proc.returncode in (0, 2), f"the process crashed: {proc.returncode}\n{proc.stderr[-2000:]}"
    assert "Traceback" not in proc.stderr
    assert proc.returncode == 0, proc.stderr
    doc = json.loads(proc.stdout)
    check_schema(doc)
    for f in doc["files"]:
        name = Path(f["path"]).name
        assert f["error"] is None, (name, f["error"])
        assert [face["index"] for face in f["faces"]] == list(range(REALDATA_FACES[name])), name
        free = [face for face in f["faces"] if face["surface_type"] in ("BSplineSurface", "BezierSurface")]
        assert len(free) == REALDATA_FREE_FORM[name], name
        for face in free:
            assert face["error"] is None, (name, face["index"], face["error"])
            assert face["max_deviation"] <= REALDATA_TOL, (name, face["index"], face["max_deviation"])


@pytest.mark.parametrize("code", [130, 143, 0, 2])
def test_console_ends_a_handled_interrupt_without_finalization(tmp_path: Path, code: int) -> None:
    """Issue 34: an audit that handled SIGTERM (its cluster closed, its rows flushed) returned 143 and
    then died in the interpreter's finalization (exit -6, "Fatal Python error ... finalizing") when a
    library's daemon thread was still inside a C call. ``console`` ends such a run by ``os._exit``
    after flushing stdout and stderr: the status stands, the output is all there, and nothing of the
    finalization runs (an atexit hook here stands for it). Other statuses exit normally."""
    marker = tmp_path / "finalized"
    script = textwrap.dedent(f"""
        import atexit, sys
        import occsurf.bridge.cli as c
        atexit.register(lambda: open({str(marker)!r}, "w").close())
        def fake(argv=None):
            print("rows written", flush=False); print("interrupted", file=sys.stderr, flush=False)
            return {code}
        c.main = fake
        c.console([])
    """)
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    assert proc.returncode == code, proc.stderr
    assert proc.stdout == "rows written\n" and proc.stderr == "interrupted\n", (proc.stdout, proc.stderr)
    assert marker.exists() == (code not in cli.INTERRUPTED)
