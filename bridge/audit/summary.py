"""``summary.json`` and ``summary.html`` of RESULTS: counts, worst files and faces, distributions.

Computed from the Parquet datasets (so a resumed run summarises every file of its input, audited
now or before), restricted to the input's content hashes. The HTML page is self-contained: the
charts (matplotlib, Agg) are embedded PNGs.
"""

from __future__ import annotations

import base64
import html
import io
import json
import math
import time
from collections import Counter
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc

from ..exchange.files import atomic_write
from .store import read_faces, read_files

if TYPE_CHECKING:
    from .corpus import Entry

__all__ = ["write_summary", "summarize"]

TOP = 20


def _finite(x: Any) -> float | None:
    return None if x is None or not math.isfinite(float(x)) else float(x)


def summarize(out: str | Path, hashes: list[str], n_input: int | None = None,
              unreadable: Sequence[Entry] = ()) -> dict[str, Any]:
    """The summary document (JSON-safe) of the files with content hash in ``hashes``."""
    wanted = pa.array(sorted(set(hashes)), pa.string())
    files = read_files(out)
    files = files.filter(pc.is_in(files["sha256"], value_set=wanted))
    # one row per hash (duplicated content under several paths shares its result)
    seen: set[str] = set()
    rows = []
    for r in files.to_pylist():
        if r["sha256"] not in seen:
            seen.add(r["sha256"])
            rows.append(r)
    faces = read_faces(out)
    faces = faces.filter(pc.is_in(faces["sha256"], value_set=wanted))
    path_of = {r["sha256"]: r["path"] for r in rows}
    by_hash_status = {r["sha256"]: r["status"] for r in rows}
    status = Counter(by_hash_status[h] for h in hashes if h in by_hash_status)
    status.update("timeout" if e.timed_out else "error" for e in unreadable)  # hashing passed --timeout, or unreadable
    counts = {s: int(status.get(s, 0)) for s in ("ok", "error", "crashed", "timeout")}
    n_input = len(hashes) + len(unreadable) if n_input is None else n_input
    counts["missing"] = n_input - sum(counts.values())
    ok = [r for r in rows if r["status"] == "ok"]
    secs = np.array([r["seconds"] for r in ok if r["seconds"] is not None], float)
    fd = faces.to_pylist()
    devs = [f for f in fd if _finite(f["max_dev"]) is not None]
    rts = [f for f in fd if _finite(f["roundtrip_dev"]) is not None]
    doc = {
        "generated": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
        "n_input": n_input, "counts": counts,
        "n_unique_contents": len(rows), "n_faces": len(fd),
        "face_types": dict(Counter(f["type"] for f in fd).most_common()),
        "seconds": {"total_in_readers": float(secs.sum()) if secs.size else 0.0,
                    "median_per_file": float(np.median(secs)) if secs.size else None,
                    "max_per_file": float(secs.max()) if secs.size else None},
        "max_dev": {"max": max((f["max_dev"] for f in devs), default=None),
                    "median": float(np.median([f["max_dev"] for f in devs])) if devs else None,
                    "n_measured": len(devs)},
        "roundtrip": {"n_faces": len(rts), "n_inexact": sum(f["roundtrip_exact"] is False for f in fd),
                      "max_dev": max((f["roundtrip_dev"] for f in rts), default=None)},
        "worst_faces": [{"path": path_of.get(f["sha256"]), "sha256": f["sha256"], "face": f["face"], "type": f["type"],
                         "max_dev": f["max_dev"]} for f in sorted(devs, key=lambda f: -f["max_dev"])[:TOP]],
        "worst_files": [{"path": r["path"], "sha256": r["sha256"], "max_dev": r["max_dev"], "n_faces": r["n_faces"]}
                        for r in sorted((r for r in ok if r["max_dev"] is not None), key=lambda r: -r["max_dev"])[:TOP]],
        "slowest_files": [{"path": r["path"], "seconds": r["seconds"], "n_faces": r["n_faces"]}
                          for r in sorted(ok, key=lambda r: -(r["seconds"] or 0))[:TOP]],
        "failures": [{"path": r["path"], "status": r["status"], "error": r["error"], "signal": r["signal"]}
                     for r in rows if r["status"] != "ok"][:200]
                    + [{"path": e.path, "status": "timeout" if e.timed_out else "error", "error": e.error, "signal": None}
                       for e in unreadable][:200],
    }
    return doc


def _charts(out: Path, doc: dict[str, Any], hashes: list[str]) -> list[tuple[str, str]]:
    # Figures of their own on Agg canvases: no pyplot, so an audit called from a notebook or a GUI
    # leaves the caller's backend and figures alone (``matplotlib.use("Agg")`` switched them), and
    # pyplot's import is not paid (~0.1 s of a one-file audit's 5 s)
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    def subplots() -> tuple[Any, Any]:
        fig = Figure(figsize=(6, 3.2))
        FigureCanvasAgg(fig)
        return fig, fig.subplots()

    wanted = pa.array(sorted(set(hashes)), pa.string())
    faces = read_faces(out, ["sha256", "max_dev", "roundtrip_dev"])
    faces = faces.filter(pc.is_in(faces["sha256"], value_set=wanted))
    files = read_files(out, ["sha256", "status", "seconds", "n_faces"])
    files = files.filter(pc.is_in(files["sha256"], value_set=wanted))
    files = files.filter(pc.equal(files["status"], "ok"))
    charts = []

    def png(fig: Any, title: str) -> None:
        buf = io.BytesIO()
        fig.tight_layout()
        fig.savefig(buf, format="png", dpi=90)
        charts.append((title, base64.b64encode(buf.getvalue()).decode()))

    fig, ax = subplots()
    c = doc["counts"]
    ax.bar(list(c), list(c.values()), color=["#4a4", "#c84", "#c44", "#888", "#ccc"][: len(c)])
    ax.set_ylabel("files")
    ax.set_title("status")
    png(fig, "Files by status")
    for col, title in (("max_dev", "our evaluation vs OCC's, per free-form face"),
                       ("roundtrip_dev", "STEP round trip, per face")):
        v = np.array([x for x in faces[col].to_pylist() if x is not None], float)
        fig, ax = subplots()
        if v.size:
            ax.hist(np.log10(np.maximum(v, 1e-18)), bins=40, color="#47a")
        ax.set_xlabel(f"log10 {col} (relative; 0 shown at -18)")
        ax.set_ylabel("faces")
        ax.set_title(title)
        png(fig, title)
    secs = np.array([x for x in files["seconds"].to_pylist() if x is not None], float)
    nf = np.array([x or 0 for x in files["n_faces"].to_pylist()], float)
    fig, ax = subplots()
    if secs.size:
        ax.loglog(np.maximum(nf, 1), np.maximum(secs, 1e-4), ".", alpha=0.6)
    ax.set_xlabel("faces per file")
    ax.set_ylabel("seconds per file")
    ax.set_title("time per file")
    png(fig, "Time per file against faces per file")
    return charts


def _table(rows: list[dict[str, Any]], cols: list[str]) -> str:
    if not rows:
        return "<p>none</p>"
    head = "".join(f"<th>{html.escape(c)}</th>" for c in cols)

    def cell(v: Any) -> str:
        if isinstance(v, float):
            return f"{v:.3g}"
        return html.escape("" if v is None else str(v))

    body = "".join("<tr>" + "".join(f"<td>{cell(r.get(c))}</td>" for c in cols) + "</tr>" for r in rows)
    return f"<table><tr>{head}</tr>{body}</table>"


def write_summary(out: str | Path, hashes: list[str], n_input: int | None = None,
                  unreadable: Sequence[Entry] = ()) -> dict[str, Any]:
    """Write ``summary.json`` and ``summary.html`` into RESULTS ``out`` (atomically); returns the document."""
    out = Path(out)
    doc = summarize(out, hashes, n_input, unreadable)
    atomic_write(out / "summary.json", (json.dumps(doc, indent=1, allow_nan=False) + "\n").encode())
    charts = _charts(out, doc, hashes)
    imgs = "".join(f'<figure><img alt="{html.escape(t)}" src="data:image/png;base64,{b}"><figcaption>{html.escape(t)}'
                   "</figcaption></figure>" for t, b in charts)
    c = doc["counts"]
    page = f"""<!doctype html><html><head><meta charset="utf-8"><title>occsurf audit</title>
<style>body{{font-family:sans-serif;margin:2em}}table{{border-collapse:collapse;font-size:90%}}
td,th{{border:1px solid #ccc;padding:2px 6px;text-align:left}}figure{{display:inline-block;margin:0 1em 1em 0}}</style>
</head><body><h1>occsurf audit</h1>
<p>{doc['n_input']} input files: {c['ok']} ok, {c['error']} failed, {c['crashed']} crashed, {c['timeout']} timed out
({c['missing']} not audited); {doc['n_faces']} faces; generated {doc['generated']}.</p>
{imgs}
<h2>Worst faces (our evaluation vs OCC's)</h2>{_table(doc['worst_faces'], ['path', 'face', 'type', 'max_dev'])}
<h2>Worst files</h2>{_table(doc['worst_files'], ['path', 'max_dev', 'n_faces'])}
<h2>Slowest files</h2>{_table(doc['slowest_files'], ['path', 'seconds', 'n_faces'])}
<h2>Failures</h2>{_table(doc['failures'], ['path', 'status', 'signal', 'error'])}
</body></html>
"""
    atomic_write(out / "summary.html", page.encode())
    return doc
