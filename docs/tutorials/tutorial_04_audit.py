"""
Audit a folder of STEP files on a Dask cluster
==============================================

A corpus of thousands of files: which ones read, which crash OpenCascade, how far our evaluation of
each face is from OCC's, and does each round-trip through STEP? ``occsurf audit`` runs one task per
file on a Dask cluster (a ``LocalCluster`` here; ``--scheduler tcp://HOST:8786`` for a real one) and
writes Parquet results as they finish.
"""

# %%
# Audit the sample files with two local workers.
import subprocess
import sys
import tempfile
from pathlib import Path

import occsurf.step_samples

samples = Path(next(iter(occsurf.step_samples.__path__)))  # the sample files shipped with occsurf
results = Path(tempfile.mkdtemp()) / "results"
OCCSURF = [sys.executable, "-m", "occsurf.bridge.cli"]  # the `occsurf` command of this environment
proc = subprocess.run([*OCCSURF, "audit", str(samples), "--out", str(results), "--workers", "2"],
                      capture_output=True, text=True)
print(proc.stdout[-1500:])
print("exit status", proc.returncode)

# %%
# The results are Parquet datasets (read them at any moment, also while the audit runs): one row
# per file and one per face.
import pyarrow.dataset as ds  # noqa: E402

files = ds.dataset(results / "files").to_table(columns=["path", "status", "n_faces", "seconds"]).to_pylist()
for row in sorted(files, key=lambda r: r["path"]):
    print(f"{Path(row['path']).name:28s} {row['status']:8s} {row['n_faces']!s:>5} faces {row['seconds']:6.2f} s")
faces = ds.dataset(results / "faces").to_table(columns=["max_dev"]).column("max_dev").to_pylist()
worst = max((d for d in faces if d is not None), default=float("nan"))
print(f"{len(faces)} faces; largest deviation from OCC's evaluation: {worst:.2e}")
