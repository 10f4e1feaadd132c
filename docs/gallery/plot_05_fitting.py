"""
Adaptive hierarchical fitting
=============================

Data fitted to a tolerance with overlays only where the data needs them: level by level, with the error picture. (course §7-10; ``occsurf demo --only fitting``.)
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

module, function = DEMOS["fitting"].split(":")
render = getattr(importlib.import_module(module), function)
files = render(Path(tempfile.mkdtemp()) / "fitting")
print("\n".join(f.name for f in files))
show(files)
