"""``occsurf check --jobs N``: several files checked by N reader processes at once
(:func:`occsurf.bridge.audit.check_pool.check_files`), each taking the next file when it is free; the
lines and reports as with one worker, in the order of the arguments; Ctrl-C stops every reader at once.

The worker jobs of the isolation tests (``isolation_jobs.py``: a segmentation fault, an hour's
sleep) stand in for files where the behaviour of the pool, not of the checker, is tested.
"""

from __future__ import annotations

import json
import os
import signal
import threading
import time
from pathlib import Path

import pytest

from occsurf.bridge.audit import check_pool
from occsurf.bridge.cli import main
from occsurf.bridge.isolation import CRASHED, OK, Outcome

SAMPLES = Path(__file__).resolve().parents[2] / "step_samples"
JOB = "tests.bridge.isolation_jobs:behave"


def _items(tmp_path: Path, *specs: str | tuple[str, str], **extra) -> list[dict]:
    """Items for ``behave`` with what check_files reads of a check item (an empty ``trace`` file: a
    crash names no piece to leave out, so the item is not run again)."""
    trace = tmp_path / "trace"
    trace.write_text("")
    out = []
    for spec in specs:
        name, do = (spec, None) if isinstance(spec, str) else spec
        out.append({"name": name, "do": do, "log": str(tmp_path / "log"), "trace": str(trace), "skip": {}, **extra})
    return out


@pytest.mark.skipif(os.name != "posix", reason="needs POSIX signals")
def test_two_readers_run_every_item_once_and_report_each_in_its_place(tmp_path: Path) -> None:
    """Five items, two readers: each item run once, a crash costs its item only (its reader starts
    again for the next), the outcomes in the order of the items and each reported once, as it came,
    under its own index; a reader takes the next item when it is free, so the one that sleeps
    through its item leaves the rest to the other."""
    items = _items(tmp_path, ("a", "sleep"), "b", ("c", "segv"), "d", "e", seconds=8)
    seen: dict[int, Outcome] = {}
    lock_free = threading.Lock()

    def on_outcome(k: int, o: Outcome) -> None:
        assert lock_free.acquire(blocking=False), "on_outcome called from two threads at once"
        try:
            assert k not in seen
            seen[k] = o
            time.sleep(0.05)  # widen the window in which a second call would overlap
        finally:
            lock_free.release()

    outcomes = check_pool.check_files(items, jobs=2, timeout=60, on_outcome=on_outcome, job=JOB)
    assert [o.status for o in outcomes] == [OK, OK, CRASHED, OK, OK] and [o.index for o in outcomes] == [0, 1, 2, 3, 4]
    assert outcomes[2].exit_reason == "killed by SIGSEGV"
    assert sorted(seen) == [0, 1, 2, 3, 4] and all(seen[k] is outcomes[k] for k in seen)
    assert sorted((tmp_path / "log").read_text().split()) == ["a", "b", "c", "d", "e"]
    assert [o.value["name"] for o in outcomes if o.ok] == ["a", "b", "d", "e"]
    pids = {o.value["name"]: o.value["pid"] for o in outcomes if o.ok}
    # a sleeps 8 s in one reader; b, c (crash), d, e all go to the other (restarted after c)
    assert pids["a"] not in (pids["b"], pids["d"], pids["e"]) and pids["d"] == pids["e"] != pids["b"]
    assert seen[0] is outcomes[0] and list(seen)[-1] == 0  # a finished last


def test_a_crash_is_checked_again_without_the_piece_at_fault(tmp_path: Path) -> None:
    """As run_checks: a reader that dies with a piece named in the item's trace file runs the item
    again with that piece in ``skip`` (the caller's list gets the grown item)."""
    items = _items(tmp_path, "a", ("b", "segv_once"), "c")
    (tmp_path / "trace").write_text("face 3\n")
    outcomes = check_pool.check_files(items, jobs=2, timeout=60, job=JOB)
    assert [o.status for o in outcomes] == [OK, OK, OK]
    assert "not evaluated" in items[1]["skip"]["faces"]["3"] and items[0]["skip"] == {} == items[2]["skip"]


@pytest.mark.skipif(os.name != "posix", reason="needs POSIX signals")
def test_ctrl_c_stops_every_worker_at_once(tmp_path: Path) -> None:
    """Ctrl-C reaches the main thread only (here: SIGINT to this process, not to the readers): the
    pool starts no more items and kills the readers instead of waiting for their items (40 s of
    sleep each)."""
    items = _items(tmp_path, ("a", "sleep"), ("b", "sleep"), "c", "d", seconds=40)
    log = tmp_path / "log"

    def interrupt_when_both_sleep() -> None:
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and not (log.exists() and len(log.read_text().split()) >= 2):
            time.sleep(0.05)
        os.kill(os.getpid(), signal.SIGINT)

    watcher = threading.Thread(target=interrupt_when_both_sleep, daemon=True)
    t0 = time.monotonic()
    watcher.start()
    readers: list = []
    real = check_pool.Reader

    class Kept(real):  # type: ignore[misc, valid-type]
        def __init__(self, *args, **kwargs) -> None:
            super().__init__(*args, **kwargs)
            readers.append(self)

    check_pool.Reader = Kept
    try:
        with pytest.raises(KeyboardInterrupt):
            check_pool.check_files(items, jobs=2, timeout=None, job=JOB)
    finally:
        check_pool.Reader = real
    assert time.monotonic() - t0 < 20  # not the 40 s of the sleeps: the readers were killed
    assert sorted(log.read_text().split()) == ["a", "b"]  # c and d never started
    assert len(readers) == 2 and all(r.proc is None for r in readers)  # both stopped and reaped


def test_cli_jobs_two_writes_what_one_writes_in_the_same_order(tmp_path: Path, capsys) -> None:
    """Three sample models with ``--jobs 2`` and ``--jobs 1``: the same lines in the order of the
    arguments (the seconds aside), the same summary, the same per-file report (the numbers that are
    round-off of zero aside: whether a worker had loaded numba for an earlier file changes them)."""
    files = [str(SAMPLES / n) for n in ("swept_tube.step", "nurbs_torus.step", "periodic_vase.step")]
    runs = {}
    for jobs in (1, 2):
        out = tmp_path / f"j{jobs}"
        assert main(["check", *files, "--out", str(out), "--pictures", "none", "--jobs", str(jobs)]) == 0
        text = capsys.readouterr().out
        lines = [ln.rsplit(",", 1)[0].split(": worst G1")[0] for ln in text.splitlines() if ln.startswith("/")]
        runs[jobs] = (lines, text.splitlines()[-3], json.loads((out / "report.json").read_text()), out)
    assert runs[1][0] == runs[2][0] and [ln.split(":")[0] for ln in runs[2][0]] == files
    assert runs[1][1] == runs[2][1] == "3 files: 2 break catia, 1 ok"
    s1, s2 = runs[1][2], runs[2][2]
    assert [(r["path"], r["status"], r["n_faces"], r["n_edges"]) for r in s1["files"]] == \
           [(r["path"], r["status"], r["n_faces"], r["n_edges"]) for r in s2["files"]]
    for r in s1["files"]:
        d1 = json.loads((runs[1][3] / r["data"]).read_text())
        d2 = json.loads((runs[2][3] / r["data"]).read_text())
        assert [f["flags"] for f in d1["faces"]] == [f["flags"] for f in d2["faces"]]
        assert [e["faces"] for e in d1["edges"]] == [e["faces"] for e in d2["edges"]]


@pytest.mark.parametrize("bad", ["0", "-1", "two", "1.5", ""])
def test_cli_bad_jobs_is_one_line(bad: str, tmp_path: Path, capsys) -> None:
    code = main(["check", str(SAMPLES / "nurbs_torus.step"), "--out", str(tmp_path / "o"), "--jobs", bad])
    out, err = capsys.readouterr()
    assert code == 2 and out == "" and err.count("\n") == 1 and "--jobs" in err and "Traceback" not in err
    assert not (tmp_path / "o").exists()


def test_check_files_refuses_bad_jobs() -> None:
    for jobs in (0, -1, 1.5, True):
        with pytest.raises(ValueError, match="jobs: expected a positive number of worker processes"):
            check_pool.check_files([], jobs=jobs, timeout=None)  # type: ignore[arg-type]
