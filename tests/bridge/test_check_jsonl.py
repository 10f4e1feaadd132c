"""``occsurf check --jsonl`` (issue 16): one JSON line per file as soon as it is checked, the file's object
of the summary ``report.json``; Ctrl-C keeps the lines done (exit 130), a closed pipe ends it quietly.
The streaming is ``_common.InOrder``, shared with ``occsurf inspect --jsonl``.

Subprocess tests of the installed console script (as tests/bridge/test_process_hygiene.py does for
inspect); the models are a filleted box (10 faces, checked in about a second with --no-pictures) and
20 random bicubic patches (about a minute: the file still being checked when the box's line is out).
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from occsurf.algorithms import BSplineSurface
from occsurf.bridge.cli._common import InOrder
from occsurf.bridge.exchange.step_iges import write_step

SCRIPT = Path(sys.executable).parent / "occsurf"
posix = pytest.mark.skipif(os.name != "posix", reason="POSIX signals and pipes")
needs_script = pytest.mark.skipif(not SCRIPT.is_file(), reason=f"no console script at {SCRIPT}")


@pytest.fixture(scope="module")
def box(tmp_path_factory) -> bytes:
    cq = pytest.importorskip("cadquery")
    shape = cq.Workplane().box(1, 2, 3).edges("|Z").fillet(0.2).val().wrapped
    return write_step(tmp_path_factory.mktemp("box") / "box.step", [shape]).read_bytes()


def _folder(tmp_path: Path, box: bytes, names: list[str]) -> Path:
    folder = tmp_path / "models"
    folder.mkdir()
    for name in names:
        (folder / name).write_bytes(box)
    return folder


def _check(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run([str(SCRIPT), "check", *args, "--no-pictures"], cwd=cwd, capture_output=True, timeout=600)


def test_in_order_hands_on_each_item_once_every_earlier_one_is_there():
    out: list[tuple[int, str]] = []
    stream = InOrder(4, lambda k, x: out.append((k, x)))
    stream.put(1, "b")
    assert out == [] and stream.emitted == []
    stream.put(0, "a")
    assert out == [(0, "a"), (1, "b")]
    stream.put(3, "d")
    assert stream.count == 2
    stream.put(2, "c")
    assert out == [(0, "a"), (1, "b"), (2, "c"), (3, "d")] and stream.emitted == ["a", "b", "c", "d"]


@pytest.mark.slow
@needs_script
def test_jsonl_lines_are_the_files_of_report_json(tmp_path: Path, box: bytes) -> None:
    """One line per file, in the order of report.json's files (a dangling link among them: its row is
    'unreadable', exit 2), each line equal to that file's object; nothing else on stdout."""
    folder = _folder(tmp_path, box, ["a.step", "b.step"])
    (folder / "c.step").symlink_to(tmp_path / "nowhere.step")
    proc = _check(str(folder), "--out", str(tmp_path / "out"), "--jsonl", cwd=tmp_path)
    assert proc.returncode == 2 and b"Traceback" not in proc.stderr, proc.stderr
    lines = [json.loads(line) for line in proc.stdout.decode().splitlines()]
    summary = json.loads((tmp_path / "out" / "report.json").read_text())
    assert lines == summary["files"] and len(lines) == 3
    assert [r["status"] for r in lines][2] == "unreadable" and lines[0]["n_faces"] == 10
    assert (tmp_path / "out" / lines[0]["data"]).is_file()  # paths relative to --out


@pytest.mark.slow
@needs_script
def test_jsonl_of_one_file_is_one_line(tmp_path: Path, box: bytes) -> None:
    folder = _folder(tmp_path, box, ["a.step"])
    proc = _check(str(folder / "a.step"), "--out", str(tmp_path / "out"), "--jsonl", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    [line] = proc.stdout.decode().splitlines()
    row = json.loads(line)
    assert row["status"] in ("ok", "failed") and row["n_faces"] == 10 and row["data"] == "./report.json"
    assert json.loads((tmp_path / "out" / "report.json").read_text())["n_faces"] == 10
    both = _check(str(folder / "a.step"), "--json", "--jsonl", cwd=tmp_path)
    assert both.returncode == 2 and b"not allowed with" in both.stderr


@pytest.mark.slow
@posix
@needs_script
def test_lines_come_as_files_finish_and_ctrl_c_keeps_them(tmp_path: Path, box: bytes) -> None:
    """The box's line is out while the slow file is still being checked; Ctrl-C then: exit 130, the line
    kept whole, 'occsurf: interrupted' last on stderr, no traceback."""
    folder = _folder(tmp_path, box, ["a.step"])
    rng = np.random.default_rng(5)
    write_step(folder / "z_slow.step",
               [BSplineSurface((3, 3), ([0.0] * 4 + [1.0] * 4,) * 2, rng.random((4, 4, 3))) for _ in range(20)])
    proc = subprocess.Popen([str(SCRIPT), "check", str(folder), "--out", str(tmp_path / "out"), "--jsonl",
                             "--no-pictures"], cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    try:
        first = proc.stdout.readline()
        running = proc.poll() is None  # the slow file is still being checked
        time.sleep(0.5)
        proc.send_signal(signal.SIGINT)
        rest, err = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert running, "the first line came only at the end"
    assert json.loads(first)["path"].endswith("a.step") and json.loads(first)["n_faces"] == 10
    assert rest == b""  # the slow file's line never started
    assert proc.returncode == 130, err
    assert err.decode().strip().splitlines()[-1] == "occsurf: interrupted" and b"Traceback" not in err


@pytest.mark.slow
@posix
@needs_script
def test_jsonl_into_head_ends_quietly(tmp_path: Path, box: bytes) -> None:
    folder = _folder(tmp_path, box, [f"{k}.step" for k in range(4)])
    proc = subprocess.run(f"'{SCRIPT}' check '{folder}' --out out --jsonl --no-pictures | head -1; "
                          "exit ${PIPESTATUS[0]}", shell=True, executable="/bin/bash", cwd=tmp_path,
                          capture_output=True, timeout=600)
    lines = proc.stdout.splitlines()
    assert len(lines) == 1 and json.loads(lines[0])["path"].endswith("0.step")
    assert b"Traceback" not in proc.stderr and b"Broken pipe" not in proc.stderr, proc.stderr
    assert proc.returncode in (0, 2)  # 2 when it still had lines to print
