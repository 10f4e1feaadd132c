"""
Check a model you received
==========================

A supplier sends a STEP file. Before it goes into your assembly you want to know: does it read
cleanly, are its faces smooth, and do neighbouring faces meet as the design intends (tangent where
they should be, curvature-continuous on a class-A surface)? ``occsurf check`` answers with a page
and a JSON report (course ch. 9).
"""

# %%
# Run the check as on the command line. It reads the file in a separate process (a crash inside
# OpenCascade costs that file only), measures every face and every edge between two faces, and
# writes ``index.html`` and ``report.json``. The default pictures are the model's and those of its
# ten worst faces.
import json
import subprocess
import sys
import tempfile
from pathlib import Path

import occsurf.step_samples

samples = Path(next(iter(occsurf.step_samples.__path__)))  # the sample files shipped with occsurf
out = Path(tempfile.mkdtemp()) / "loft_check"
OCCSURF = [sys.executable, "-m", "occsurf.bridge.cli"]  # the `occsurf` command of this environment
proc = subprocess.run([*OCCSURF, "check", str(samples / "loft.step"), "--out", str(out)],
                      capture_output=True, text=True)
print(proc.stdout)
print("exit status", proc.returncode)

# %%
# Read the report. ``passed`` is the verdict against the threshold preset (CATIA's Connect Checker
# defaults: G0 0.001 mm, G1 0.01 degrees, G2 2 %); ``failures`` says what breaks it: faces with
# visible defects (wiggles, curvature spikes) and, in ``violations``, every edge meant to be smooth
# that is not, with the measure, the value and the worst point.
doc = json.loads((out / "report.json").read_text())
print(f"{doc['n_faces']} faces, {doc['n_edges']} edges between faces, passed: {doc['passed']}")
print("\n".join(doc["failures"][:5]))
for v in doc["violations"][:5]:
    print(v["message"])

# %%
# The faces, worst first: flags (wiggles, curvature spikes, near-degenerate normals) with their
# locations and suggested corrections.
for f in sorted(doc["faces"], key=lambda f: -len(f["flags"]))[:3]:
    print(f"face {f['index']} ({f['type']}): k in [{f['k_min']:.3g}, {f['k_max']:.3g}], "
          f"{len(f['flags'])} flags, worst adjacent G1 {f['worst_g1_deg']}")

# %%
# The zebra stripes of the whole model: stripes that break at an edge show a tangent break, a kink
# in the stripes a curvature break. Open ``index.html`` for the interactive 3-D view.
import matplotlib.pyplot as plt  # noqa: E402

img = plt.imread(out / "model_zebra.png")
fig = plt.figure(figsize=(8, 8 * img.shape[0] / img.shape[1]))
ax = fig.add_axes((0, 0, 1, 1))
ax.imshow(img)
ax.set_axis_off()

# %%
# In a CI pipeline, gate on the verdict without pictures: ``occsurf check part.step --json
# --fail-on catia --pictures none`` exits 1 on a violation. In Python, ``check_model`` returns the
# same report; in a notebook it shows itself as the page.
