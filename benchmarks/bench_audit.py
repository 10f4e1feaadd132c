"""``occsurf audit`` throughput on Dask against today's sequential ``occsurf inspect``.

The corpus is ``step_samples/`` (7 files) plus ``../shared/realdata/`` (4 public models) repeated
until it holds at least ``--files`` files (default 200); every copy gets distinct bytes (a STEP
comment, or the IGES start section's free text) so that the content hashes differ and nothing is
deduplicated. Measured in one run:

* sequential ``occsurf inspect FILES --json --samples 11`` (one reader process, one file after the other);
* ``occsurf audit --checks inspect`` on 1 and 2 local workers (the same per-file work as inspect);
* ``occsurf audit`` with the default checks (inspect + STEP round trip) on 2 workers;
* files/s and faces/s for each; peak RSS of a Dask worker process and of a reader process;
* scheduler overhead per task: a no-op task submitted through the same bounded window;
* client-side SHA-256 rate (the resume key).

From these: a projection of 1M files on N workers, and which bound applies (reader time per
file, scheduler tasks/s, client hashing). Run: ``python benchmarks/bench_audit.py [--files 200]``.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))
REALDATA = REPO.parent / "shared" / "realdata"


def build_corpus(folder: Path, n_files: int) -> list[Path]:
    """Samples + realdata repeated to >= n_files files, each copy with distinct bytes."""
    sources = sorted((REPO / "step_samples").rglob("*.st*p")) + sorted((REPO / "step_samples").rglob("*.ig*s"))
    if REALDATA.is_dir():
        sources += sorted(p for p in REALDATA.iterdir() if p.suffix.lower() in (".step", ".stp", ".igs", ".iges"))
    out, k = [], 0
    while len(out) < n_files:
        for src in sources:
            data = src.read_bytes()
            if src.suffix.lower() in (".step", ".stp"):
                data = data.replace(b"ISO-10303-21;", f"ISO-10303-21;\n/* bench copy {k} */".encode(), 1)
            else:  # IGES: the first start-section line is free text in columns 1-72
                first, rest = data.split(b"\n", 1)
                tag = f"bench copy {k}".encode()
                first = tag + first[len(tag):] if len(first) >= 80 else first
                data = first + b"\n" + rest
            dst = folder / f"{k:04d}-{src.name}"
            dst.write_bytes(data)
            out.append(dst)
        k += 1
    return out


def _tree_rss(root: int, stop: threading.Event, peaks: dict[str, int]) -> None:
    import psutil

    try:
        me = psutil.Process(root)
    except psutil.Error:
        return
    while not stop.is_set():
        try:
            for p in me.children(recursive=True):
                try:
                    cmd = " ".join(p.cmdline())
                    rss = p.memory_info().rss
                except psutil.Error:
                    continue
                kind = ("reader" if "occsurf.bridge.audit.reader" in cmd or "occsurf.bridge.isolation" in cmd
                        else "worker" if "multiprocessing" in cmd or "spawn" in cmd else "other")
                peaks[kind] = max(peaks.get(kind, 0), rss)
        except psutil.Error:
            pass
        time.sleep(0.25)


def timed(cmd: list[str]) -> tuple[float, subprocess.CompletedProcess[str], dict[str, int]]:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(x for x in (str(REPO), env.get("PYTHONPATH")) if x)
    t0 = time.perf_counter()
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    peaks: dict[str, int] = {}
    stop = threading.Event()
    watcher = threading.Thread(target=_tree_rss, args=(proc.pid, stop, peaks), daemon=True)
    watcher.start()
    out, err = proc.communicate()
    stop.set()
    return time.perf_counter() - t0, subprocess.CompletedProcess(cmd, proc.returncode, out, err), peaks


def scheduler_overhead(n_tasks: int = 2000) -> tuple[float, float]:
    """No-op tasks on a LocalCluster of 2 workers (one thread each), driven like the audit drives
    its tasks (as_completed, one new task per finished one): ``(seconds per task with one task in
    flight: the round trip client -> scheduler -> worker -> client, tasks/s with 512 in flight:
    what the scheduler can dispatch)``."""
    import logging

    from distributed import Client, LocalCluster, as_completed

    def noop(x: int) -> int:
        return x

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
                      silence_logs=logging.ERROR) as cluster, Client(cluster) as client:
        client.submit(noop, -1).result()  # warm
        rates = []
        for window, n in ((1, n_tasks // 10), (512, n_tasks)):
            pending = iter(range(n))
            t0 = time.perf_counter()
            ac = as_completed([client.submit(noop, next(pending), pure=False) for _ in range(window)], loop=client.loop)
            for fut in ac:
                fut.result()
                fut.release()
                nxt = next(pending, None)
                if nxt is not None:
                    ac.add(client.submit(noop, nxt, pure=False))
            rates.append((time.perf_counter() - t0) / n)
    return rates[0], 1.0 / rates[1]


def hash_rate(files: list[Path]) -> float:
    from occsurf.bridge.audit.corpus import Entry, hash_entries

    size = sum(p.stat().st_size for p in files)
    t0 = time.perf_counter()
    hash_entries([Entry(str(p)) for p in files])
    return size / (time.perf_counter() - t0) / 1e6


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--files", type=int, default=200)
    ap.add_argument("--skip-inspect", action="store_true")
    ap.add_argument("--overhead-only", action="store_true", help="only the scheduler and hashing numbers")
    args = ap.parse_args()
    py = sys.executable
    tmp = Path(tempfile.mkdtemp(prefix="bench-audit-"))
    try:
        files = build_corpus(tmp / "corpus", args.files) if (tmp / "corpus").mkdir() is None else []
        size_mb = sum(p.stat().st_size for p in files) / 1e6
        print(f"corpus: {len(files)} files, {size_mb:.1f} MB (step_samples + realdata, repeated); "
              f"{os.cpu_count()} cores, load average {os.getloadavg()[0]:.2f} at the start")
        if args.overhead_only:
            per_task, tps = scheduler_overhead()
            print(f"scheduler: {per_task * 1e3:.1f} ms round trip with one task in flight; {tps:.0f} tasks/s with 512")
            print(f"client SHA-256: {hash_rate(files):.0f} MB/s")
            return
        rows = []
        n_faces = None
        if not args.skip_inspect:
            dt, proc, peaks = timed([py, "-m", "occsurf.bridge.cli", "inspect", *map(str, files), "--json",
                                     "--samples", "11"])
            doc = json.loads(proc.stdout)
            n_faces = sum(f["n_faces"] for f in doc["files"])
            bad = sum(f["error"] is not None for f in doc["files"])
            rows.append(("sequential occsurf inspect", dt, n_faces, bad, peaks))
        for label, extra in (("audit --workers 1 --checks inspect", ["--workers", "1", "--checks", "inspect"]),
                             ("audit --workers 2 --checks inspect", ["--workers", "2", "--checks", "inspect"]),
                             ("audit --workers 2 (inspect + roundtrip)", ["--workers", "2"])):
            out = tmp / ("out-" + label.replace(" ", "_").replace("-", ""))
            dt, proc, peaks = timed([py, "-m", "occsurf.bridge.cli", "audit", str(tmp / "corpus"), "--out", str(out),
                                     *extra])
            summary = json.loads((out / "summary.json").read_text())
            rows.append((label, dt, summary["n_faces"], len(files) - summary["counts"]["ok"], peaks))
            last_summary = summary
        base = rows[0][1]
        print("\n| run | wall s | files/s | faces/s | vs sequential | files not ok | peak RSS worker / reader (MB) |")
        print("|---|---|---|---|---|---|---|")
        for label, dt, nf, bad, peaks in rows:
            print(f"| {label} | {dt:.1f} | {len(files) / dt:.2f} | {nf / dt:.1f} | {base / dt:.2f}x | {bad} | "
                  f"{peaks.get('worker', 0) / 1e6:.0f} / {peaks.get('reader', 0) / 1e6:.0f} |")
        per_task, tps = scheduler_overhead()
        mb_s = hash_rate(files)
        reader_s = last_summary["seconds"]["total_in_readers"] / len(files)
        print(f"\nscheduler: {per_task * 1e3:.1f} ms round trip per no-op task with one in flight; "
              f"{tps:.0f} no-op tasks/s with 512 in flight (2 workers): {1e3 / tps:.2f} ms of scheduler per task")
        print(f"client SHA-256: {mb_s:.0f} MB/s; reader time per file (inspect + roundtrip): {reader_s:.3f} s mean, "
              f"{last_summary['seconds']['median_per_file']:.3f} s median")
        mean_mb = size_mb / len(files)
        for n in (2, 16, 64, 256):
            hours = 1e6 * reader_s / n / 3600
            bound_sched = 1e6 / tps / 3600
            bound_hash = 1e6 * mean_mb / mb_s / 3600
            which = max((hours, "reader time (OCC read + checks)"), (bound_sched, "scheduler"), (bound_hash, "client hashing"))
            print(f"projection 1M files on {n:>3} workers: reader {hours:7.1f} h, scheduler floor {bound_sched:.2f} h, "
                  f"hashing floor {bound_hash:.2f} h -> bound by {which[1]}")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
