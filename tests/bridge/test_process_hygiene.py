"""Issue 16, process hygiene: workers that a folder in the current directory cannot shadow, quiet
broken pipes, Ctrl-C that keeps what was done (``inspect --jsonl`` / ``--json``), ``occsurf --version``.

The command-line cases run the installed console script (``occsurf``, next to this interpreter) in
a subprocess, from a current directory holding a folder named ``occsurf``: the console script's own
``sys.path`` does not contain the current directory, so only a worker started with ``-m`` (which
puts it first) could import the impostor.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
import tomllib
from pathlib import Path

import numpy as np
import pytest

import occsurf
from occsurf.algorithms import BSplineSurface
from occsurf.bridge.exchange.step_iges import write_step
from occsurf.bridge.isolation import OK, run_jobs, worker_command, worker_env

from . import corrupt_files as C

REPO = Path(__file__).resolve().parents[2]
SAMPLES = REPO / "step_samples"
JOB = "tests.bridge.isolation_jobs:behave"
SCRIPT = Path(sys.executable).parent / "occsurf"
posix = pytest.mark.skipif(os.name != "posix", reason="POSIX signals and pipes")
needs_script = pytest.mark.skipif(not SCRIPT.is_file(), reason=f"no console script at {SCRIPT}")


@pytest.fixture()
def shadow(tmp_path: Path) -> Path:
    """A folder holding ``occsurf/`` and ``tests/`` packages that fail on import, as a user's project might."""
    for name in ("occsurf", "tests"):
        pkg = tmp_path / name
        pkg.mkdir()
        (pkg / "__init__.py").write_text(f"raise ImportError('the {name} folder of the current directory was imported')\n")
    return tmp_path


def _occsurf(*args: str, cwd: Path, **kw) -> subprocess.CompletedProcess:
    return subprocess.run([str(SCRIPT), *args], cwd=cwd, capture_output=True, timeout=600, **kw)


@pytest.fixture(scope="module")
def box(tmp_path_factory) -> bytes:
    """A box with filleted edges (10 planar and cylindrical faces: no deviation grid, read at once)."""
    import cadquery as cq

    shape = cq.Workplane().box(1, 2, 3).edges("|Z").fillet(0.2).val().wrapped
    return write_step(tmp_path_factory.mktemp("box") / "box.step", [shape]).read_bytes()


def _slow_step(folder: Path) -> Path:
    """20 free-form faces: inspecting them on 1000 x 1000 grids takes minutes."""
    rng = np.random.default_rng(5)
    surfaces = [BSplineSurface((3, 3), ([0.0] * 4 + [1.0] * 4,) * 2, rng.random((4, 4, 3))) for _ in range(20)]
    return write_step(folder / "z_slow.step", surfaces)


# ---------------------------------------------------------------------------------------- shadowing
def test_the_worker_command_keeps_the_current_directory_off_sys_path() -> None:
    cmd = worker_command("occsurf.bridge.isolation")
    assert cmd[:3] == [sys.executable, "-P", "-m"] and cmd[3] == "occsurf.bridge.isolation"
    env = worker_env()
    root = str(Path(occsurf.__file__).resolve().parent.parent)
    assert env["PYTHONPATH"].split(os.pathsep)[0] == root
    old = os.environ.get("PYTHONPATH")
    os.environ["PYTHONPATH"] = os.pathsep.join(["", "/somewhere", ""])  # empty entries mean the cwd
    try:
        assert worker_env()["PYTHONPATH"].split(os.pathsep) == [root, "/somewhere"]
    finally:
        if old is None:
            del os.environ["PYTHONPATH"]
        else:
            os.environ["PYTHONPATH"] = old


def test_run_jobs_from_a_directory_with_an_occsurf_folder(shadow: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(shadow)
    [outcome] = run_jobs(JOB, [{"name": "a"}], timeout=120)
    assert outcome.status == OK, outcome
    assert outcome.value["occsurf"] == occsurf.__file__ and outcome.value["pid"] != os.getpid()


def test_the_audit_reader_from_a_directory_with_an_occsurf_folder(shadow: Path,
                                                                    monkeypatch: pytest.MonkeyPatch) -> None:
    from occsurf.bridge.audit.reader import Reader

    monkeypatch.chdir(shadow)
    reader = Reader(preload=())
    try:
        reply = reader.run(JOB, {"name": "a"}, timeout=120)
    finally:
        reader.stop()
    assert reply.status == "ok", reply
    assert reply.value["occsurf"] == occsurf.__file__


@needs_script
def test_occsurf_inspect_from_a_directory_with_an_occsurf_folder(shadow: Path) -> None:
    proc = _occsurf("inspect", str(SAMPLES / "loft.step"), "--json", "--samples", "3", cwd=shadow)
    assert proc.returncode == 0, proc.stderr.decode()[-2000:]
    [f] = json.loads(proc.stdout)["files"]
    assert f["error"] is None and f["n_faces"] == 11


# ---------------------------------------------------------------------------------------- --jsonl
def test_jsonl_streams_one_line_per_file_equal_to_json(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    from occsurf.bridge import cli

    (tmp_path / "missing.step").symlink_to(tmp_path / "nowhere.step")
    args = [str(SAMPLES), str(tmp_path), "--samples", "3", "--in-process"]
    assert cli.main(["inspect", *args, "--jsonl"]) == 2  # the dangling link is an error
    lines = capsys.readouterr().out.splitlines()
    assert cli.main(["inspect", *args, "--json"]) == 2
    doc = json.loads(capsys.readouterr().out)
    assert doc["interrupted"] is False
    streamed = [json.loads(line) for line in lines]
    assert len(streamed) == len(doc["files"]) == len(list(SAMPLES.glob("*.st*p"))) + 2  # + mixed.igs + the link
    for a, b in zip(streamed, doc["files"]):
        a.pop("seconds"), b.pop("seconds")
        assert a == b
    assert "dangling" in streamed[-1]["error"]


@posix
@needs_script
def test_jsonl_into_head_ends_quietly(tmp_path: Path, box: bytes) -> None:
    folder = tmp_path / "d"
    folder.mkdir()
    for k in range(6):
        (folder / f"{k}.step").write_bytes(box)
    proc = subprocess.run(f"'{SCRIPT}' inspect '{folder}' --jsonl --samples 3 | head -1; exit ${{PIPESTATUS[0]}}",
                          shell=True, executable="/bin/bash", cwd=tmp_path, capture_output=True, timeout=600)
    lines = proc.stdout.splitlines()
    assert len(lines) == 1 and json.loads(lines[0])["path"].endswith("0.step")
    assert b"Traceback" not in proc.stderr and b"Broken pipe" not in proc.stderr, proc.stderr
    assert proc.returncode in (0, 2)  # 2 when it still had files to print


# ---------------------------------------------------------------------------------------- Ctrl-C
def _interrupt_after(proc: subprocess.Popen, ready: callable, limit: float = 300) -> None:
    deadline = time.time() + limit
    while not ready() and time.time() < deadline and proc.poll() is None:
        time.sleep(0.1)
    assert proc.poll() is None, "finished before it could be interrupted"
    proc.send_signal(signal.SIGINT)


@posix
@needs_script
def test_ctrl_c_with_jsonl_keeps_the_lines_done(tmp_path: Path, box: bytes) -> None:
    folder = tmp_path / "d"
    folder.mkdir()
    for name in ("a.step", "b.step"):
        (folder / name).write_bytes(box)
    _slow_step(folder)
    out = tmp_path / "out.jsonl"
    with open(out, "wb") as fh:
        proc = subprocess.Popen([str(SCRIPT), "inspect", str(folder), "--jsonl", "--samples", "1000"], cwd=tmp_path,
                                stdout=fh, stderr=subprocess.PIPE)
        _interrupt_after(proc, lambda: out.read_bytes().count(b"\n") >= 2)
        _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    assert err.decode().strip().splitlines()[-1] == "occsurf: interrupted" and b"Traceback" not in err
    lines = out.read_bytes().decode().splitlines()
    assert [Path(json.loads(line)["path"]).name for line in lines] == ["a.step", "b.step"]  # whole lines only
    assert all(json.loads(line)["n_faces"] == 10 for line in lines)


@posix
@needs_script
def test_ctrl_c_with_json_prints_the_files_done(tmp_path: Path, box: bytes) -> None:
    folder = tmp_path / "d"
    folder.mkdir()
    st = C.StepText.parse(box)
    face = next(i for i, r in enumerate(st.records) if b"ADVANCED_FACE" in r)
    (folder / "a.step").write_bytes(C.step_delete(st, face))  # a warning on stderr once it is read
    _slow_step(folder)
    err_log = tmp_path / "err"
    with open(err_log, "wb") as fh:
        proc = subprocess.Popen([str(SCRIPT), "inspect", str(folder), "--json", "--samples", "1000"], cwd=tmp_path,
                                stdout=subprocess.PIPE, stderr=fh)
        _interrupt_after(proc, lambda: b": warning: " in err_log.read_bytes())
        out, _ = proc.communicate(timeout=120)
    err = err_log.read_text()
    assert proc.returncode == 130 and err.strip().splitlines()[-1] == "occsurf: interrupted" and "Traceback" not in err
    doc = json.loads(out)
    assert doc["interrupted"] is True
    assert [Path(f["path"]).name for f in doc["files"]] == ["a.step"] and doc["files"][0]["warnings"]


@posix
@needs_script
def test_ctrl_c_with_tables_says_how_far_it_got(tmp_path: Path, box: bytes) -> None:
    folder = tmp_path / "d"
    folder.mkdir()
    (folder / "a.step").write_bytes(box)
    _slow_step(folder)
    out_log = tmp_path / "out"
    with open(out_log, "wb") as fh:
        proc = subprocess.Popen([str(SCRIPT), "inspect", str(folder), "--samples", "1000"], cwd=tmp_path,
                                stdout=fh, stderr=subprocess.PIPE)
        _interrupt_after(proc, lambda: b"worst deviation" in out_log.read_bytes())
        _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130 and b"Traceback" not in err
    text = out_log.read_text()
    assert "a.step (STEP)" in text and "1 of 2 files read before the interruption" in text


# ---------------------------------------------------------------------------------------- --version
@needs_script
def test_version(tmp_path: Path) -> None:
    declared = tomllib.loads((REPO / "pyproject.toml").read_text(encoding="utf-8"))["project"]["version"]
    assert occsurf.__version__ == declared
    t0 = time.perf_counter()
    proc = _occsurf("--version", cwd=tmp_path)
    assert proc.returncode == 0 and proc.stdout.decode().strip() == f"occsurf {declared}"
    assert time.perf_counter() - t0 < 10  # no OCC, no NumPy
