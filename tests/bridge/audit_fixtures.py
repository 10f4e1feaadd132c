"""Shared pieces of the ``occsurf audit`` tests: a corpus with bad files, and the fault hook.

The fault hook is a ``sitecustomize`` module put first on ``PYTHONPATH``. It acts only inside
audit *reader* processes (``python -m occsurf.bridge.audit.reader``), when they open a file:

* ``*crash-me*``: a real segmentation fault inside OCC, the one of ``shared/OCP_NOTES.md`` §7
  (``STEPControl_Reader.TransferRoots()`` after a failed ``ReadFile``);
* ``*hang-me*``: sleeps for an hour (a reader that never returns);
* ``*slow-*``: sleeps ``OCCSURF_TEST_SLOW`` seconds (default 1) before reading: a file that takes
  long enough to interrupt or to kill its worker mid-run.

The client (which hashes the files) and the Dask workers are not affected.
"""

from __future__ import annotations

import os
import shutil
import socket
import subprocess
import sys
import textwrap
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
SAMPLES = REPO / "step_samples"
REALDATA = REPO.parent / "shared" / "realdata"
SAMPLE_FILES = ["loft.step", "mixed.igs", "nurbs_torus.step", "periodic_vase.step", "swept_tube.step"]

HOOK = textwrap.dedent('''
    import os, sys, time
    if "occsurf.bridge.audit.reader" in " ".join(getattr(sys, "orig_argv", sys.argv)):
        def _fault(event, args):
            if event != "open" or not isinstance(args[0], str):
                return
            name = os.path.basename(args[0])
            if "crash-me" in name:
                import tempfile
                from OCP.STEPControl import STEPControl_Reader
                garbage = tempfile.NamedTemporaryFile(suffix=".step", delete=False)
                garbage.write(b"not a step file"); garbage.close()
                r = STEPControl_Reader()
                r.ReadFile(garbage.name)   # RetFail
                r.TransferRoots()          # OCP_NOTES.md section 7: segmentation fault inside OCC
            elif "hang-me" in name:
                time.sleep(3600)
            elif "slow-" in name:
                time.sleep(float(os.environ.get("OCCSURF_TEST_SLOW", "1")))
        sys.addaudithook(_fault)
''')


def hook_env(tmp: Path, **extra: str) -> dict[str, str]:
    """An environment whose Python processes load the fault hook (and this checkout of occsurf)."""
    hook_dir = tmp / "hook"
    hook_dir.mkdir(exist_ok=True)
    (hook_dir / "sitecustomize.py").write_text(HOOK)
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(x for x in (str(hook_dir), str(REPO), env.get("PYTHONPATH")) if x)
    env.update(extra)
    return env


def bad_files(folder: Path) -> dict[str, Path]:
    """Corrupt, truncated, empty and not-CAD files made from the samples, by name."""
    folder.mkdir(parents=True, exist_ok=True)
    torus = (SAMPLES / "nurbs_torus.step").read_bytes()
    iges = (SAMPLES / "mixed.igs").read_bytes()
    files = {
        "truncated.step": torus[: len(torus) // 2],
        "truncated.igs": iges[: len(iges) // 3],
        "empty.step": b"",
        "random.step": bytes(range(256)) * 40,
        "garbled.step": torus.replace(b"B_SPLINE_SURFACE_WITH_KNOTS", b"B_SPLINE_SURFAZE_WITH_KNOTZ"),
    }
    out = {}
    for name, data in files.items():
        (folder / name).write_bytes(data)
        out[name] = folder / name
    return out


def good_files(folder: Path, n_copies: int = 1, prefix: str = "", iges: bool = True) -> list[Path]:
    """The sample files copied into ``folder`` (``n_copies`` distinct contents each: a comment
    line makes each copy's SHA-256 differ, the geometry is the same); ``iges=False``: STEP only."""
    folder.mkdir(parents=True, exist_ok=True)
    out = []
    for k in range(n_copies):
        for name in SAMPLE_FILES if iges else [n for n in SAMPLE_FILES if n.endswith(".step")]:
            src = SAMPLES / name
            dst = folder / f"{prefix}{k:03d}-{name}"
            data = src.read_bytes()
            if name.endswith(".step"):
                data = data.replace(b"ISO-10303-21;", f"ISO-10303-21;\n/* copy {k} */".encode(), 1)
                dst.write_bytes(data)
            elif k == 0:  # IGES has no comment syntax outside its fixed columns: one copy only
                shutil.copyfile(src, dst)
            else:
                continue
            out.append(dst)
    return [p for p in out if p.exists()]


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def run_cli(*args: str, env: dict[str, str], timeout: float = 300) -> subprocess.CompletedProcess[str]:
    """``python -m occsurf.bridge.cli ARGS`` in a fresh process."""
    return subprocess.run([sys.executable, "-m", "occsurf.bridge.cli", *args], capture_output=True, text=True,
                          env=env, timeout=timeout, cwd=REPO)
