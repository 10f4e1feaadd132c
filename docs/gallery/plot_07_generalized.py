"""
Generalized B-splines of arbitrary topology
===========================================

Biquadratic and bicubic surfaces over control meshes with extraordinary vertices. (course §8-6, 8-7; ``occsurf demo --only generalized``.)
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

module, function = DEMOS["generalized"].split(":")
render = getattr(importlib.import_module(module), function)
files = render(Path(tempfile.mkdtemp()) / "generalized")
print("\n".join(f.name for f in files))
show(files)
