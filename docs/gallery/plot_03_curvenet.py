"""
Curve networks: Coons and Gordon
================================

Coons patches (bilinear and cubic blend) from four boundaries, and a Gordon surface through a network of curves, with their input curves. (course §6-20..6-25; ``occsurf demo --only curvenet``.)
"""

# %%
# The demo function writes the pictures and STEP files; the pictures are shown below.
import importlib
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path.cwd()))
from _show import show  # noqa: E402

from occsurf.examples.gallery import DEMOS  # noqa: E402

module, function = DEMOS["curvenet"].split(":")
render = getattr(importlib.import_module(module), function)
files = render(Path(tempfile.mkdtemp()) / "curvenet")
print("\n".join(f.name for f in files))
show(files)
