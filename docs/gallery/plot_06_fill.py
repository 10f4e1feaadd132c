"""
n-sided hole filling
====================

A five-sided hole filled G1 by S-patches and by a plate, compared with OpenCascade's filler. (course §8-3; ``occsurf demo --only fill``.)
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

module, function = DEMOS["fill"].split(":")
render = getattr(importlib.import_module(module), function)
files = render(Path(tempfile.mkdtemp()) / "fill")
print("\n".join(f.name for f in files))
show(files)
