"""
Refill a face of a STEP model from build123d
============================================

A build123d part has a face you want smoother, or a face whose surface is broken. Remove it and
fill the hole with a G1 patch that meets its neighbours tangent-continuously (course §8-3),
measured against OpenCascade's own filler.
"""

# %%
# A part: a box whose top edges are rounded. Its top face is bounded by four fillets.
import json
import subprocess
import sys
import tempfile
from pathlib import Path

import build123d as bd

part = bd.fillet(bd.Box(40, 30, 12).edges().group_by(bd.Axis.Z)[-1], 4.0)
work = Path(tempfile.mkdtemp())
bd.export_step(part, str(work / "part.step"))

# %%
# Number the faces as occsurf does (``occsurf inspect``) and pick the top face.
from occsurf.bridge import read_step  # noqa: E402

model = read_step(str(work / "part.step"))
def height(face) -> float:
    (u0, u1), (v0, v1) = face.surface.domain
    return float(face.surface.evaluate(0.5 * (u0 + u1), 0.5 * (v0 + v1))[2])


top = max((f for f in model.faces if f.surface is not None), key=height)
print(f"{len(model.faces)} faces; the top face is face {top.index} ({top.surface_type})")

# %%
# Remove it and fill the hole. ``occsurf fill`` reports per hole the construction, the gaps (G0)
# and angles (G1) to the neighbours, and the same numbers for OpenCascade's
# ``BRepOffsetAPI_MakeFilling`` on the same hole.
OCCSURF = [sys.executable, "-m", "occsurf.bridge.cli"]  # the `occsurf` command of this environment
proc = subprocess.run([*OCCSURF, "fill", str(work / "part.step"), "--out", str(work / "refilled.step"),
                       "--faces", str(top.index), "--json"], capture_output=True, text=True)
print("exit status", proc.returncode)
report = json.loads(proc.stdout)
print(json.dumps(report, indent=1)[:1500])

# %%
# The refilled model reads back as one valid shell, and the zebra picture of the hole (written
# beside the output) shows the stripes running through the new patch's boundary.
import matplotlib.pyplot as plt  # noqa: E402

back = read_step(str(work / "refilled.step"))
print(f"refilled model: {len(back.faces)} faces")
for png in sorted(work.glob("refilled*.png"))[:1]:
    img = plt.imread(png)
    fig = plt.figure(figsize=(9, 9 * img.shape[0] / img.shape[1]))
    ax = fig.add_axes((0, 0, 1, 1))
    ax.imshow(img)
    ax.set_axis_off()
