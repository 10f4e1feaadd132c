"""
Direct manipulation with constraints
====================================

A surface dragged through points, with positions, tangents and curvatures held: the minimum-norm change of the control points (constrained least squares). (course ch. 3 and 4; ``occsurf demo --only manipulation``.)
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

module, function = DEMOS["manipulation"].split(":")
render = getattr(importlib.import_module(module), function)
files = render(Path(tempfile.mkdtemp()) / "manipulation")
print("\n".join(f.name for f in files))
show(files)
