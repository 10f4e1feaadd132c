"""
Surface quality: curvature, zebra, sections with combs
======================================================

Course ch. 9: the pictures ``occsurf check`` draws for a model (here a sample loft of eleven
B-spline faces): mean curvature, zebra stripes per pixel, and planar sections with their curvature
combs. A kink in the zebra stripes is a curvature break, a jump a tangent break.
"""

# %%
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt

import occsurf.step_samples
from occsurf.bridge.quality.check_files import check_file

samples = Path(next(iter(occsurf.step_samples.__path__)))
out = Path(tempfile.mkdtemp())
result = check_file(samples / "loft.step", out)  # the library side of `occsurf check`
doc = result["report"]
print(f"{doc['n_faces']} faces, worst G1 {doc['worst_g1_deg']:.3g} deg; flags:",
      sorted({g['kind'] for f in doc["faces"] for g in f["flags"]}))
for kind in ("mean", "zebra", "sections"):
    img = plt.imread(out / result["pictures"][kind])
    fig = plt.figure(figsize=(8, 8 * img.shape[0] / img.shape[1]))
    ax = fig.add_axes((0, 0, 1, 1))
    ax.imshow(img)
    ax.set_axis_off()
