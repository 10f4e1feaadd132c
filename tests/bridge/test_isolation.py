"""Tests of :mod:`occsurf.bridge.isolation` on its own: jobs that crash, hang, raise or chatter.

The jobs are in ``isolation_jobs.py`` (the worker imports them by name). Each test starts real
worker processes (no OCC: the jobs import nothing heavy), so each takes a fraction of a second, but
for the time-outs.
"""

from __future__ import annotations

import json
import math
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

import occsurf
from occsurf.bridge.isolation import CRASHED, ERROR, FAILED, MARK, OK, TIMEOUT, Outcome, describe_exit, run_jobs

JOB = "tests.bridge.isolation_jobs:behave"
REPO = Path(__file__).resolve().parents[2]


def items(*specs: str | tuple[str, str], log: Path | None = None, **extra) -> list[dict]:
    """``items("a", ("b", "segv"), "c")``: named items, some with an action."""
    out = []
    for spec in specs:
        name, do = (spec, None) if isinstance(spec, str) else spec
        out.append({"name": name, "do": do, "log": str(log) if log else None, **extra})
    return out


def logged(log: Path) -> list[str]:
    return log.read_text().split() if log.exists() else []


@pytest.mark.skipif(os.name != "posix", reason="needs POSIX signals")
def test_a_segfault_costs_one_item_and_the_others_run_once(tmp_path: Path) -> None:
    log = tmp_path / "log"
    seen: list[Outcome] = []
    outcomes = run_jobs(JOB, items("a", ("b", "segv"), "c", "d", log=log), timeout=60, on_outcome=seen.append)
    assert seen == outcomes  # reported as they came, in order
    assert [o.index for o in outcomes] == [0, 1, 2, 3]
    assert [o.status for o in outcomes] == [OK, CRASHED, OK, OK]
    crash = outcomes[1]
    assert crash.signal == "SIGSEGV" and crash.exit_code == -signal.SIGSEGV
    assert crash.exit_reason == "killed by SIGSEGV" and crash.value is None and not crash.ok
    assert logged(log) == ["a", "b", "c", "d"]  # every item run exactly once
    a, c, d = (outcomes[k].value for k in (0, 2, 3))
    assert [a["name"], c["name"], d["name"]] == ["a", "c", "d"]
    assert a["pid"] != c["pid"] == d["pid"] != os.getpid()  # a new worker after the crash


def test_a_hanging_item_times_out_and_the_rest_still_run(tmp_path: Path) -> None:
    log = tmp_path / "log"
    t0 = time.perf_counter()
    outcomes = run_jobs(JOB, items("a", ("b", "sleep"), "c", log=log), timeout=2.0)
    assert time.perf_counter() - t0 < 60  # the hour-long sleep was cut short
    assert [o.status for o in outcomes] == [OK, TIMEOUT, OK]
    hung = outcomes[1]
    assert hung.seconds >= 2.0 and hung.error is None and hung.value is None
    assert hung.exit_code == -signal.SIGKILL  # killed by the watchdog
    assert logged(log) == ["a", "b", "c"]


@pytest.mark.slow
def test_start_up_does_not_count_against_the_timeout(monkeypatch: pytest.MonkeyPatch) -> None:
    """The worker imports the job (and ``preload``) before it announces its first item."""
    monkeypatch.setenv("OCCSURF_TEST_IMPORT_DELAY", "3")
    outcomes = run_jobs(JOB, items("a", "b"), timeout=1.5, preload=["tests.bridge.isolation_jobs"])
    assert [o.status for o in outcomes] == [OK, OK]
    assert all(o.seconds < 1.5 for o in outcomes)


def test_an_exception_is_an_error_of_its_item_only() -> None:
    outcomes = run_jobs(JOB, items("a", ("b", "raise"), "c", ("d", "unserialisable")))
    assert [o.status for o in outcomes] == [OK, ERROR, OK, ERROR]
    b = outcomes[1]
    assert b.error == "RuntimeError: boom second line" and b.error_type == "RuntimeError"
    assert b.exit_code is None and b.signal is None and b.exit_reason is None
    assert outcomes[3].error_type == "TypeError"
    assert outcomes[0].value["pid"] == outcomes[2].value["pid"]  # no restart after an exception


def test_values_round_trip_and_native_chatter_stays_out() -> None:
    outcomes = run_jobs(JOB, items(("a", "chatter"), ("b", "nan"), "c"))
    assert [o.status for o in outcomes] == [OK, OK, OK]
    assert math.isnan(outcomes[1].value["value"])
    # the worker imports occsurf from the same place as this process
    assert Path(outcomes[2].value["occsurf"]).resolve() == Path(occsurf.__file__).resolve()


def test_in_process_gives_the_same_outcomes() -> None:
    specs = ("a", ("b", "raise"), ("c", "nan"))
    here = run_jobs(JOB, items(*specs), isolate=False)
    there = run_jobs(JOB, items(*specs))
    assert [o.status for o in here] == [o.status for o in there] == [OK, ERROR, OK]
    assert here[0].value["pid"] == os.getpid() != there[0].value["pid"]
    assert here[1].error == there[1].error == "RuntimeError: boom second line"
    assert math.isnan(here[2].value["value"])


def test_an_unimportable_job_fails_every_item() -> None:
    outcomes = run_jobs("tests.bridge.no_such_module:job", [1, 2])
    assert [o.status for o in outcomes] == [FAILED, FAILED]
    assert outcomes[0].exit_code == 1 and "No module named" in outcomes[0].error


def test_no_items_starts_no_worker() -> None:
    assert run_jobs(JOB, []) == []


@pytest.mark.parametrize(("kwargs", "match"), [
    (dict(job="no colon"), "job"),
    (dict(job="a:b:c"), "job"),
    (dict(timeout=0), "timeout"),
    (dict(timeout=float("nan")), "timeout"),
    (dict(timeout=True), "timeout"),
])
def test_bad_arguments_name_the_argument(kwargs: dict, match: str) -> None:
    args = dict(job=JOB, items=[1]) | kwargs
    with pytest.raises(ValueError, match=match):
        run_jobs(args.pop("job"), args.pop("items"), **args)


def test_unserialisable_items_are_refused() -> None:
    with pytest.raises(TypeError, match="items"):
        run_jobs(JOB, [object()])


def test_describe_exit() -> None:
    assert describe_exit(-signal.SIGSEGV) == "killed by SIGSEGV"
    assert describe_exit(3) == "exit status 3"


@pytest.mark.slow
def test_the_hidden_inspect_worker_command_speaks_the_same_protocol() -> None:
    """``occsurf _inspect-worker`` (kept for compatibility) runs the inspect job on its old input."""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(x for x in (str(REPO), env.get("PYTHONPATH")) if x)
    torus = REPO / "step_samples" / "nurbs_torus.step"
    job = {"samples": 4, "files": [["t", str(torus)], ["m", str(REPO / "missing.step")]]}
    proc = subprocess.run([sys.executable, "-m", "occsurf.bridge.cli", "_inspect-worker"], input=json.dumps(job),
                          capture_output=True, text=True, env=env, timeout=600)
    assert proc.returncode == 0, proc.stderr
    # split("\n"), not splitlines(): MARK starts with \x1e, a line boundary for str.splitlines
    msgs = [json.loads(line[len(MARK):]) for line in proc.stdout.split("\n") if line.startswith(MARK)]
    assert [list(m)[:1] for m in msgs] == [["start"], ["report"], ["start"], ["report"]]
    first, second = msgs[1]["data"], msgs[3]["data"]
    assert first["path"] == "t" and first["error"] is None and first["n_faces"] == 1
    assert first["faces"][0]["degree"] == [2, 2] and first["faces"][0]["max_deviation"] <= 1e-12
    assert second["path"] == "m" and second["error"] and second["faces"] == []
