"""``occsurf audit`` without a cluster: corpus expansion and hashing, the reader process (a real
OCC segmentation fault, a hang, a bad file), the per-file job against ``inspect_model``, the
Parquet store (atomic parts, resume, refusals), the summary, and the command line's bad input.
The Dask runs are in ``test_audit_cluster.py``.
"""

from __future__ import annotations

import hashlib
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

pa = pytest.importorskip("pyarrow")
pytest.importorskip("distributed")

from occsurf.bridge.audit import corpus, store  # noqa: E402
from occsurf.bridge.audit.reader import Reader  # noqa: E402
from occsurf.bridge.audit.tasks import JOB, PRELOAD, audit_job, make_item  # noqa: E402

from .audit_fixtures import SAMPLES, bad_files, free_port, good_files, hook_env, run_cli  # noqa: E402


# ------------------------------------------------------------------------------------ corpus
def test_paths_files_folders_globs_and_lists(tmp_path: Path) -> None:
    good = good_files(tmp_path / "a" / "deep")
    (tmp_path / "a" / "notes.txt").write_text("not cad")
    no_suffix = tmp_path / "b" / "model_without_suffix"
    no_suffix.parent.mkdir()
    no_suffix.write_bytes((SAMPLES / "loft.step").read_bytes())
    listing = tmp_path / "list.txt"
    listing.write_text(f"# a comment\n\nb/model_without_suffix\n{good[0]}\nmissing.step\n")
    entries = corpus.expand_paths([str(tmp_path / "a"), str(listing), str(tmp_path / "a" / "deep" / "*.step"),
                                   str(good[1])])
    paths = [e.path for e in entries]
    assert len(paths) == len(set(paths))  # each file once, however often it was named
    assert set(paths) == {str(p) for p in good} | {str(no_suffix), str(tmp_path / "missing.step")}
    missing = next(e for e in entries if e.path.endswith("missing.step"))
    assert missing.error.startswith("no such file") and str(listing) in missing.error
    # ** globs recurse
    assert {e.path for e in corpus.expand_paths([str(tmp_path / "**" / "*.igs")])} == {str(p) for p in good
                                                                                        if p.suffix == ".igs"}


@pytest.mark.parametrize("args, message", [
    (["{tmp}/nothing-here"], "no such file or directory"),
    (["{tmp}/empty"], "no STEP/IGES files"),
    (["{tmp}/empty/*.step"], "no STEP/IGES files"),
])
def test_bad_corpus_is_refused(tmp_path: Path, args: list[str], message: str) -> None:
    (tmp_path / "empty").mkdir()
    with pytest.raises(corpus.CorpusError, match=message):
        corpus.expand_paths([a.format(tmp=tmp_path) for a in args])


def test_sha256_and_sniffing(tmp_path: Path) -> None:
    data = os.urandom(3 << 20)  # three blocks
    p = tmp_path / "x.bin"
    p.write_bytes(data)
    assert corpus.sha256_of(str(p)) == (hashlib.sha256(data).hexdigest(), len(data))
    assert corpus.sniff_cad(SAMPLES / "mixed.igs") == "iges"
    q = tmp_path / "noext"
    q.write_bytes((SAMPLES / "mixed.igs").read_bytes())
    assert corpus.sniff_cad(q) == "iges"
    q.write_bytes(b"\xef\xbb\xbf  ISO-10303-21;\n")
    assert corpus.sniff_cad(q) == "step"
    q.write_bytes(b"hello")
    assert corpus.sniff_cad(q) is None
    entries = corpus.hash_entries([corpus.Entry(str(p)), corpus.Entry(str(tmp_path / "gone"))])
    # a file gone by the time it is hashed: the path check before opening says so (issue 34)
    assert entries[0].sha256 == hashlib.sha256(data).hexdigest() and entries[1].error == "no such file"


def test_hashing_respects_the_timeout(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Issue 34: the corpus was hashed before ``--timeout`` applied. A read that keeps returning
    blocks is stopped between two of them; one that blocks inside the system call (a hung network
    share, simulated) is recorded ``timeout`` at its deadline while the other files are hashed, and
    its stuck thread holds up nothing."""
    import threading
    import time

    data = os.urandom(3 << 20)
    files = [tmp_path / f"{k}.step" for k in range(4)]
    for f in files:
        f.write_bytes(data)
    slow = corpus.hash_entries([corpus.Entry(str(files[0]))], timeout=1e-9)[0]  # past it after the first block
    assert slow.timed_out and slow.sha256 is None and slow.error == (
        "reading it to hash its contents took more than 1e-09 s (--timeout); not audited")
    release = threading.Event()
    real = corpus.sha256_of

    def hung(path: str, deadline: float | None = None) -> tuple[str, int]:
        if path.endswith("1.step"):
            release.wait(60)  # a read(2) that does not return
        return real(path, deadline)

    monkeypatch.setattr(corpus, "sha256_of", hung)
    t0 = time.monotonic()
    entries = corpus.hash_entries([corpus.Entry(str(f)) for f in files], threads=1, timeout=0.5)
    took = time.monotonic() - t0
    release.set()
    assert 0.5 <= took < 3.0, took
    assert [e.timed_out for e in entries] == [False, True, False, False]
    assert all(e.sha256 == hashlib.sha256(data).hexdigest() for e in entries if not e.timed_out)
    assert "more than 0.5 s (--timeout)" in (entries[1].error or "")
    assert corpus.hash_entries([corpus.Entry(str(files[2]))], timeout=None)[0].sha256 is not None


# ------------------------------------------------------------------------------------ reader
@pytest.mark.slow
@pytest.mark.skipif(os.name != "posix", reason="needs POSIX signals")
def test_reader_survives_a_real_occ_segfault_and_a_hang(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    env = hook_env(tmp_path)
    monkeypatch.setenv("PYTHONPATH", env["PYTHONPATH"])  # the reader inherits it (worker_env)
    crash, hang = tmp_path / "crash-me.step", tmp_path / "hang-me.step"
    for p in (crash, hang):
        p.write_bytes((SAMPLES / "loft.step").read_bytes())
    reader = Reader(PRELOAD)
    item = lambda p: make_item(str(p), "x", ("inspect",), 5, None)  # noqa: E731
    try:
        ok = reader.run(JOB, item(SAMPLES / "loft.step"), 60)
        assert ok.status == "ok" and ok.value["n_faces"] == 11
        first = reader.pid
        r = reader.run(JOB, item(crash), 60)
        assert (r.status, r.signal, r.exit_code) == ("crashed", "SIGSEGV", -11)
        assert reader.pid is None  # recycled: the next file gets a new reader
        r = reader.run(JOB, item(hang), 2.0)
        assert r.status == "timeout" and 2.0 <= r.seconds < 10 and "recycled" in r.error
        ok = reader.run(JOB, item(SAMPLES / "nurbs_torus.step"), 60)
        assert ok.status == "ok" and reader.pid != first and reader.starts == 3
        bad = reader.run(JOB, "not a dict", 60)  # a job that raises: an error, the reader stays
        assert bad.status == "error" and reader.pid is not None
    finally:
        reader.stop()


# ------------------------------------------------------------------------------------ the job
@pytest.mark.slow
def test_job_matches_inspect_model_and_round_trips_exactly() -> None:
    from occsurf.bridge import read_step
    from occsurf.bridge.validation.inspect import inspect_model

    path = SAMPLES / "loft.step"
    got = audit_job(make_item(str(path), "x", ("inspect", "roundtrip", "quality"), 7, None))
    want = inspect_model(read_step(path), samples=7)
    assert got["error"] is None and got["format"] == "step" and got["n_faces"] == len(want) == 11
    for row, rep in zip(got["faces"], want):
        assert (row["face"], row["type"], row["continuity"]) == (rep.index, rep.surface_type, rep.continuity)
        assert (row["degree_u"], row["degree_v"]) == (rep.degree or (None, None))
        assert (row["poles_u"], row["poles_v"]) == (rep.poles or (None, None))
        assert row["max_dev"] == rep.max_deviation
        # our STEP writer prints 17 digits: every B-spline face comes back bit-exact
        assert row["roundtrip_exact"] is True and row["roundtrip_dev"] == 0.0
    assert got["roundtrip_status"] == "ok"
    # the quality hook (occsurf.bridge.quality.summarize_model) is there: its summary is stored
    assert got["quality_status"] == "ok"
    assert set(got["quality"]) == {"worst_g1_deg", "curvature_spikes", "flags"}
    assert got["quality"]["worst_g1_deg"] < 1e-6 and got["quality"]["curvature_spikes"] == 0


@pytest.mark.parametrize("name, message", [("truncated.step", "truncated STEP"), ("empty.step", "empty file"),
                                           ("random.step", "not a STEP file"), ("truncated.igs", "IGES")])
def test_job_reports_bad_files(tmp_path: Path, name: str, message: str) -> None:
    path = bad_files(tmp_path)[name]
    got = audit_job(make_item(str(path), "x", ("inspect", "roundtrip"), 5, None))
    assert message in got["error"] and got["faces"] == [] and str(path) not in got["error"]


def test_quality_hook_is_called_when_present(monkeypatch: pytest.MonkeyPatch) -> None:
    from occsurf.bridge.audit import tasks

    monkeypatch.setattr(tasks, "QUALITY_HOOK", "tests.bridge.test_audit:_fake_quality")
    got = audit_job(make_item(str(SAMPLES / "nurbs_torus.step"), "x", ("quality",), 5, None))
    assert got["quality_status"] == "ok"
    assert got["quality"] == {"worst_g1_deg": 1.5, "curvature_spikes": 1, "flags": ["faces=1"]}
    assert "roundtrip_dev" not in got["faces"][0] and "max_dev" not in got["faces"][0]  # checks not asked


def _fake_quality(model):  # the hook's contract: summarize(model) -> dict
    return {"worst_g1_deg": 1.5, "curvature_spikes": 1, "flags": [f"faces={len(model.faces)}"]}


# ------------------------------------------------------------------------------------ store
def _row(h: str, status: str = "ok") -> dict:
    return {"path": f"/x/{h}.step", "sha256": h, "status": status, "n_faces": 1, "seconds": 0.1}


def test_store_parts_are_atomic_and_resume_by_hash(tmp_path: Path) -> None:
    out = tmp_path / "r"
    s = store.ResultStore(out, flush_seconds=3600, flush_rows=2)
    s.add(_row("a"), [{"face": 0, "type": "Plane"}])
    assert store.read_files(out).num_rows == 0  # buffered, not yet a part
    s.add(_row("b", "crashed"))
    assert store.read_files(out).num_rows == 2  # flush_rows reached: one files part, one faces part
    (out / "files" / ".part-x.parquet.123.tmp").write_bytes(b"half a parquet file")  # a killed writer
    # a faces part whose files part never landed (killed between the two renames)
    (out / "faces" / "part-orphan.parquet").write_bytes(b"whatever")
    assert store.read_files(out).num_rows == 2  # hidden temporaries are never read
    with pytest.raises(store.StoreError, match="--resume"):
        store.ResultStore(out)
    s2 = store.ResultStore(out, resume=True)
    assert s2.done == {"a": "ok", "b": "crashed"}
    assert not (out / "faces" / "part-orphan.parquet").exists()
    assert not list((out / "files").glob(".*.tmp"))
    s2.add(_row("c"))
    s2.flush()
    t = store.read_files(out)
    assert sorted(t.column("sha256").to_pylist()) == ["a", "b", "c"]
    assert store.read_faces(out).column("type").to_pylist() == ["Plane"]
    assert t.schema == store.FILES_SCHEMA



def test_summary_leaves_the_caller_s_matplotlib_alone(tmp_path: Path) -> None:
    """An audit called from a notebook or a GUI draws its charts on figures of its own: the caller's
    backend stays what it chose and pyplot's figures are not touched (``matplotlib.use("Agg")`` in
    the summary switched the backend of the calling process)."""
    out = tmp_path / "r"
    s = store.ResultStore(out)
    s.add({**_row("a"), "max_dev": 1e-15}, [{"face": 0, "type": "BSplineSurface", "max_dev": 1e-15,
                                            "roundtrip_dev": 0.0, "roundtrip_exact": True}])
    s.flush()
    code = ("import sys, matplotlib; matplotlib.use('svg'); import matplotlib.pyplot as plt; plt.figure(7); "
            "from occsurf.bridge.audit.summary import write_summary; "
            f"doc = write_summary({str(out)!r}, ['a']); "
            "assert matplotlib.get_backend() == 'svg', matplotlib.get_backend(); "
            "assert plt.get_fignums() == [7], plt.get_fignums(); print(doc['counts']['ok'])")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0 and proc.stdout.strip() == "1", proc.stderr[-2000:]
    assert (out / "summary.html").read_text().count("data:image/png;base64,") == 4

def test_store_refuses_an_unwritable_out(tmp_path: Path) -> None:
    blocker = tmp_path / "file"
    blocker.write_text("x")
    with pytest.raises(store.StoreError, match="cannot write there"):
        store.ResultStore(blocker / "results")
    with pytest.raises(store.StoreError, match="not a folder"):
        store.ResultStore(blocker)


def test_summary_counts_and_worst(tmp_path: Path) -> None:
    from occsurf.bridge.audit.summary import write_summary

    out = tmp_path / "r"
    s = store.ResultStore(out)
    s.add({**_row("a"), "max_dev": 1e-15}, [{"face": 0, "type": "BSplineSurface", "max_dev": 1e-15, "roundtrip_dev": 0.0,
                                            "roundtrip_exact": True}])
    s.add({**_row("b"), "max_dev": 1e-9}, [{"face": 3, "type": "BSplineSurface", "max_dev": 1e-9, "roundtrip_dev": 1e-13,
                                           "roundtrip_exact": False}])
    s.add({**_row("c", "timeout"), "n_faces": None})
    s.add({**_row("old", "ok")})  # not in this input: not summarised
    s.flush()
    doc = write_summary(out, ["a", "b", "c"], n_input=4, unreadable=[corpus.Entry("/x/gone", error="cannot read")])
    assert doc["counts"] == {"ok": 2, "error": 1, "crashed": 0, "timeout": 1, "missing": 0}
    assert doc["worst_faces"][0]["face"] == 3 and doc["worst_faces"][0]["path"] == "/x/b.step"
    assert doc["roundtrip"] == {"n_faces": 2, "n_inexact": 1, "max_dev": 1e-13}
    assert json.loads((out / "summary.json").read_text()) == doc
    assert (out / "summary.html").read_text().count("data:image/png;base64,") == 4
    # a file whose hashing passed --timeout is counted and listed as a timeout, not an error
    hung = corpus.Entry("/x/hung.step", error="reading it to hash its contents took more than 5 s", timed_out=True)
    doc = write_summary(out, ["a", "b", "c"], n_input=5, unreadable=[corpus.Entry("/x/gone", error="cannot read"), hung])
    assert doc["counts"] == {"ok": 2, "error": 1, "crashed": 0, "timeout": 2, "missing": 0}
    assert {"path": "/x/hung.step", "status": "timeout", "error": hung.error, "signal": None} in doc["failures"]


# ------------------------------------------------------------------------------------ CLI
def _one_line_exit_2(proc) -> str:
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.count("\n") == 1 and proc.stderr.startswith("occsurf: "), proc.stderr
    assert "Traceback" not in proc.stderr
    return proc.stderr


# The client waits open_client's connect_timeout (10 s) for a scheduler nobody runs; 2 s here, the
# same refusal (nothing listens on the port: the connection cannot succeed however long it waits).
_SHORT_CONNECT = """
import sys
if "occsurf.bridge.cli" in " ".join(getattr(sys, "orig_argv", [])):
    from occsurf.bridge.audit import cluster
    _open_client = cluster.open_client
    def _short(scheduler=None, workers=None, connect_timeout=10.0):
        return _open_client(scheduler, workers, min(connect_timeout, 2.0))
    cluster.open_client = _short
"""


@pytest.mark.slow
def test_cli_bad_input_is_one_line_exit_2(tmp_path: Path) -> None:
    env = hook_env(tmp_path)
    (tmp_path / "empty").mkdir()
    blocker = tmp_path / "file"
    blocker.write_text("x")
    sample = str(SAMPLES / "loft.step")
    assert "no STEP/IGES files" in _one_line_exit_2(run_cli("audit", str(tmp_path / "empty"), "--out", str(tmp_path / "o"), env=env))
    assert "cannot write there" in _one_line_exit_2(run_cli("audit", sample, "--out", str(blocker / "o"), env=env))
    hook = tmp_path / "short_connect"  # first on the path: this sitecustomize, not hook_env's (no reader runs)
    hook.mkdir()
    (hook / "sitecustomize.py").write_text(_SHORT_CONNECT)
    short = {**env, "PYTHONPATH": os.pathsep.join((str(hook), env["PYTHONPATH"]))}
    err = _one_line_exit_2(run_cli("audit", sample, "--out", str(tmp_path / "o2"), "--scheduler",
                                   f"tcp://127.0.0.1:{free_port()}", env=short))
    assert "cannot connect" in err
    assert "no such file" in _one_line_exit_2(run_cli("audit", str(tmp_path / "nope.step"), "--out", str(tmp_path / "o3"),
                                                       env=env))
    # argparse's own refusals: exit 2 too
    for bad in (["--checks", "inspect,zebra"], ["--workers", "0"], ["--timeout", "-1"]):
        proc = run_cli("audit", sample, "--out", str(tmp_path / "o4"), *bad, env=env)
        assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert not (tmp_path / "o4").exists()


def _audit_signalled_where_the_store_is_made(tmp_path: Path, *body: str) -> subprocess.CompletedProcess[str]:
    """``occsurf audit`` of the good STEP files with ``body`` (lines of Python; ``os``, ``signal`` imported)
    run in its main thread, from an audit hook, as the store creates RESULTS/files."""
    hook = tmp_path / "signal_hook"  # hook_env's own folder is tmp_path / "hook"
    hook.mkdir()
    out = tmp_path / "results"
    (hook / "sitecustomize.py").write_text(
        "import os, sys, signal\n"
        "if 'audit' in sys.argv or 'audit' in getattr(sys, 'orig_argv', []):\n"
        "    def _term(event, args):\n"
        f"        if event == 'os.mkdir' and str(args[0]) == {str(out / 'files')!r}:\n"
        + "".join(f"            {line}\n" for line in body) +
        "    sys.addaudithook(_term)\n")
    env = hook_env(tmp_path)
    env["PYTHONPATH"] = os.pathsep.join((str(hook), env["PYTHONPATH"]))
    corpus_dir = tmp_path / "corpus"
    good_files(corpus_dir, iges=False)
    return run_cli("audit", str(corpus_dir), "--out", str(out), "--workers", "1", env=env, timeout=120)


def test_sigterm_handled_inside_a_string_exec_still_exits_143(tmp_path: Path) -> None:
    """The CI flake of ``test_signals_at_random_moments_end_the_run_promptly`` (-2 instead of 143 under
    SIGTERM): CPython remembers a ``KeyboardInterrupt`` that ended a string ``exec``/``eval`` (the
    generated methods of dataclasses and namedtuples, made while modules import) even once it is
    caught, and under ``python -m`` then kills the process with SIGINT whatever status it returned.
    Here the SIGTERM is handled, deterministically, inside such an exec in the command's main thread
    (when it creates RESULTS/files): the run must still say so and end with 143."""
    proc = _audit_signalled_where_the_store_is_made(
        tmp_path, "exec('import os, signal\\nos.kill(os.getpid(), signal.SIGTERM)\\nfor _ in range(100): pass')")
    assert proc.returncode == 143, (proc.returncode, proc.stderr)
    assert "occsurf: interrupted; what finished is in" in proc.stderr and "Traceback" not in proc.stderr


@pytest.mark.parametrize("turned_into", ["RuntimeError('the store could not be made')",
                                         "PermissionError(13, 'Permission denied')"])
def test_an_interrupt_a_library_turned_into_another_error_still_exits_143(tmp_path: Path, turned_into: str) -> None:
    """A SIGTERM whose ``KeyboardInterrupt`` a library caught and turned into an error of its own
    (here: where the store creates RESULTS/files; an OSError there is the store's ``StoreError``, as
    the cluster's start-up makes any error its ``ClusterError``) is still the interrupt: one line
    saying so and 143, not "audit failed" / "cannot write there" and 2 (an exit 2 then went through
    the interpreter's finalization, where a Dask thread aborted the process: -6 in CI's
    ``test_signals_at_random_moments_end_the_run_promptly`` on 12-06)."""
    proc = _audit_signalled_where_the_store_is_made(
        tmp_path, "try:", "    os.kill(os.getpid(), signal.SIGTERM)", "    for _ in range(10**6): pass",
        "except KeyboardInterrupt:", f"    raise {turned_into} from None")
    assert proc.returncode == 143, (proc.returncode, proc.stderr)
    assert "occsurf: interrupted; what finished is in" in proc.stderr, proc.stderr
    assert "audit failed" not in proc.stderr and "cannot write" not in proc.stderr and "Traceback" not in proc.stderr


def test_cli_imports_no_dask_numpy_or_occ_at_module_level() -> None:
    import subprocess

    code = ("import sys; import occsurf.bridge.cli.audit, occsurf.bridge.audit; "
            "print(sorted(m for m in ('numpy', 'dask', 'distributed', 'pyarrow', 'OCP') if m in sys.modules))")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert proc.stdout.strip() == "[]"


def test_a_task_dask_gave_up_on_is_recorded_crashed_not_dropped() -> None:
    from distributed import KilledWorker

    from occsurf.bridge.audit.run import _failure, _rows

    entry = corpus.Entry("/x/a.step", sha256="a", size=3)
    from types import SimpleNamespace

    res = _failure(entry, KilledWorker("occsurf-audit-a", SimpleNamespace(address="tcp://127.0.0.1:1"), 3))
    row, faces = _rows(entry, res, "run")
    assert row["status"] == "crashed" and "KilledWorker" in row["error"] and faces == []
    row, _ = _rows(entry, _failure(entry, RuntimeError("lost")), "run")
    assert row["status"] == "error" and "RuntimeError: lost" in row["error"]


def test_dashboard_link_is_asked_of_the_scheduler() -> None:
    """A link only when the scheduler serves a dashboard page (whatever is installed here): its HTTP
    service without the page (--no-dashboard) gives none, a page that cannot be reached from here
    is still reported, a scheduler that does not answer gives no link rather than an error."""
    import http.server
    import threading
    from types import SimpleNamespace

    from occsurf.bridge.audit.cluster import dashboard_link

    requests: list[str] = []

    class Page(http.server.BaseHTTPRequestHandler):
        def do_GET(self):  # noqa: N802 - http.server's name
            requests.append(self.path)
            self.send_response(200 if self.path == "/status" else 404)
            self.end_headers()

        def log_message(self, *args):
            pass

    server = http.server.HTTPServer(("127.0.0.1", 0), Page)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    base = f"http://127.0.0.1:{server.server_address[1]}"

    def client(services, link):
        return SimpleNamespace(scheduler_info=lambda: {"services": services}, dashboard_link=link)

    try:
        assert dashboard_link(client({"dashboard": 1}, base + "/status")) == base + "/status"
        assert dashboard_link(client({"dashboard": 1}, base + "/nothing")) is None  # HTTP service, no page
        assert dashboard_link(client({}, base + "/status")) is None
        # not probed (the local cluster started here): its page is there exactly when bokeh is, no
        # request made; without bokeh the scheduler still lists its HTTP service as "dashboard"
        from occsurf.bridge.audit import cluster

        seen = len(requests)
        with pytest.MonkeyPatch.context() as mp:
            mp.setattr(cluster, "dashboard_available", lambda: True)
            assert dashboard_link(client({"dashboard": 1}, base + "/nothing"), probe=False) == base + "/nothing"
            assert dashboard_link(client({}, base + "/status"), probe=False) is None
            mp.setattr(cluster, "dashboard_available", lambda: False)
            assert dashboard_link(client({"dashboard": 1}, base + "/status"), probe=False) is None
        assert len(requests) == seen
    finally:
        server.shutdown()
    far = f"http://127.0.0.1:{free_port()}/status"  # nothing listens there: reported as the scheduler says
    assert dashboard_link(client({"dashboard": 1}, far), probe_timeout=2) == far

    def no_answer():
        raise OSError("connection closed")

    assert dashboard_link(SimpleNamespace(scheduler_info=no_answer)) is None
