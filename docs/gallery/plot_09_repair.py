"""
Matching a broken tangent edge
==============================

A two-face model whose shared edge breaks tangency, matched G1 and G2 with zebra stripes before and after. (course ch. 3-4, 9; ``occsurf demo --only repair``.)
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

module, function = DEMOS["repair"].split(":")
render = getattr(importlib.import_module(module), function)
files = render(Path(tempfile.mkdtemp()) / "repair")
print("\n".join(f.name for f in files))
show(files)
