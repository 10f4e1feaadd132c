"""
Hierarchical B-splines
======================

Details at three levels ride along when the base is bent: offset referencing in the parent's frames, against plain additive offsets. (course ch. 5, Forsey and Bartels; ``occsurf demo --only hierarchical``.)
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

module, function = DEMOS["hierarchical"].split(":")
render = getattr(importlib.import_module(module), function)
files = render(Path(tempfile.mkdtemp()) / "hierarchical")
print("\n".join(f.name for f in files))
show(files)
