"""``occsurf fill --jobs N``: holes filled in several worker processes, sewn once
(:mod:`occsurf.bridge.audit.fill_file`)."""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

from occsurf.bridge import cli
from occsurf.bridge.audit import fill_file as ff
from occsurf.bridge.audit.reader import Reader

REPO = Path(__file__).resolve().parents[2]
DOME = REPO / "step_samples" / "holes" / "dome_holes.step"
SCREW = REPO.parent / "shared" / "realdata" / "build123d__M6-1x12-countersunk-screw.step"


def _item(src: Path, out: Path, faces: list[int] | None = None) -> dict:
    return {"input": str(src), "output": str(out), "all_loops": False, "compare_occ": False,
            "faces": faces or [], "strict": False, "pictures": False}


def _data(step: Path) -> str:
    """A STEP file's DATA section (its header holds the time of writing)."""
    text = step.read_text()
    return text[text.index("DATA;"):]


@pytest.mark.slow
def test_two_processes_fill_the_faces_one_process_fills(tmp_path: Path) -> None:
    """dome_holes' four holes through two workers: two processes did the work, and every hole's faces
    are byte for byte (OCC binary BRep) those one process makes. Which worker fills which hole is a
    race (the eight loops include the four outer ones, reported without a fill): both readers start with
    one of the first two loops, so both pids are among all the results; the four filled ones may
    all come from one of them (seen once under load, 2026-12-07)."""
    item = _item(DOME, tmp_path / "o.step")
    plan = ff.plan_job(item)
    ff._cached = None  # plan_job ran here, not in a worker: keep nothing of it
    assert plan["holes"] == 8 and sorted(plan["sides"]) == [3, 3, 4, 4, 5, 5, 6, 6]  # each ring: hole and outer loop
    results = ff._fill_holes(item, plan, [Reader(ff.PRELOAD), Reader(ff.PRELOAD)], timeout=None)
    filled = [r for r in results if r["faces"] is not None]
    assert len(filled) == 4
    assert all("pid" in r for r in results), [r["report"] for r in results if "pid" not in r]  # none lost
    pids = {r["pid"] for r in results}
    assert len(pids) == 2 and os.getpid() not in pids
    ctx = ff._context(item, keep=False)
    for k, r in enumerate(results):
        here = ff._fill_one(ctx, k, item)
        assert r["report"]["status"] == here.status
        if r["faces"] is not None:
            assert r["faces"] == ff._faces_to_text(here._fill_faces)
            assert len(ff._faces_from_text(r["faces"])) == len(here._fill_faces) == here.sides


@pytest.mark.slow
@pytest.mark.skipif(not SCREW.is_file(), reason=f"{SCREW} is absent (public real models)")
def test_jobs_2_writes_what_jobs_1_writes(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    """Two faces of the real screw removed and refilled (two holes), in one worker and in two: the
    same report (but the times) and the same STEP data."""
    docs, data = [], []
    for jobs in ("1", "2"):
        out = tmp_path / f"s{jobs}.step"
        code = cli.main(["fill", str(SCREW), "--faces", "9", "24", "--out", str(out), "--no-occ", "--no-pictures",
                         "--json", "--jobs", jobs])
        stdout, err = capsys.readouterr()
        assert code == 0, err
        doc = json.loads(stdout)
        assert [h["status"] for h in doc["holes"]] == ["filled", "filled"] and doc["holes"][0]["valid"]
        for h in doc["holes"]:
            h.pop("seconds")
        doc.pop("output")
        docs.append(doc)
        data.append(_data(out))
    assert docs[0] == docs[1]
    assert data[0] == data[1]


_HOOK = """\
import importlib.abc, importlib.util, os, signal, sys, time

class _Patch(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path, target=None):
        if name != "occsurf.bridge.modeling.fill":
            return None
        sys.meta_path.remove(self)
        spec = importlib.util.find_spec(name)
        run = spec.loader.exec_module

        def exec_module(module):
            run(module)
            fill_loop = module.fill_loop

            def patched(holes, k, **kw):
                if k == 2:  # the four-sided hole
                    if {mode!r} == "crash":
                        os.kill(os.getpid(), signal.SIGSEGV)
                    time.sleep(600)
                return fill_loop(holes, k, **kw)

            module.fill_loop = patched

        spec.loader.exec_module = exec_module
        return spec

sys.meta_path.insert(0, _Patch())
"""


@pytest.mark.slow
@pytest.mark.skipif(os.name != "posix", reason="needs POSIX signals")
@pytest.mark.parametrize("mode", ["crash", "hang"])
def test_a_worker_lost_on_one_hole_costs_that_hole_only(capsys: pytest.CaptureFixture[str], tmp_path: Path,
                                                        monkeypatch: pytest.MonkeyPatch, mode: str) -> None:
    """A segmentation fault (or a hang past --timeout) while one hole is filled: that hole fails with
    the reason, the three others are filled, sewn and written; exit 2. The fault comes from a hook
    (``sitecustomize`` on the workers' path) around ``fill_loop``, not from a real OCC defect."""
    hook = tmp_path / "hook"
    hook.mkdir()
    (hook / "sitecustomize.py").write_text(_HOOK.format(mode=mode))
    monkeypatch.setenv("PYTHONPATH", str(hook))  # the workers' environment (isolation.worker_env)
    out = tmp_path / "o.step"
    code = cli.main(["fill", str(DOME), "--out", str(out), "--no-occ", "--no-pictures", "--json", "--jobs", "2",
                     "--timeout", "8"])
    stdout, err = capsys.readouterr()
    assert code == 2
    holes = {h["index"]: h for h in json.loads(stdout)["holes"] if h["status"] != "outer"}
    assert sorted(holes) == [0, 2, 4, 6]
    assert [holes[k]["status"] for k in (0, 4, 6)] == ["filled"] * 3 and holes[2]["status"] == "failed"
    why = ("the worker process crashed while filling this hole (killed by SIGSEGV; a fault inside OpenCascade)"
           if mode == "crash" else
           "filling this hole took longer than 8 s; its worker process was stopped (--timeout)")
    assert holes[2]["reason"] == why
    assert err == f"occsurf: {DOME}: hole 2 (4 sides) not filled: {why}\n"
    assert out.is_file() and "ADVANCED_FACE" in _data(out)


@pytest.mark.parametrize("value", ["0", "-2", "1.5", "many", ""])
def test_bad_jobs_is_one_line_exit_2(capsys: pytest.CaptureFixture[str], tmp_path: Path, value: str) -> None:
    code = cli.main(["fill", str(DOME), "--out", str(tmp_path / "o.step"), "--jobs", value])
    out, err = capsys.readouterr()
    assert code == 2 and out == "" and err.count("\n") == 1 and "--jobs" in err and "Traceback" not in err
    assert not (tmp_path / "o.step").exists()


def test_fill_file_refuses_bad_jobs() -> None:
    for jobs in (0, -1, 1.5, True):
        with pytest.raises(ValueError, match="jobs: expected a positive number of worker processes"):
            ff.fill_file(_item(DOME, Path("o.step")), jobs=jobs)  # type: ignore[arg-type]
