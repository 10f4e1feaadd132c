"""
Warn's lighting controls
========================

One car-body panel under Warn's lights: concentration, flaps, cones and coloured lights, rendered per pixel by VTK. (course ch. 10; ``occsurf demo --only lighting``.)
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

module, function = DEMOS["lighting"].split(":")
render = getattr(importlib.import_module(module), function)
files = render(Path(tempfile.mkdtemp()) / "lighting")
print("\n".join(f.name for f in files))
show(files)
