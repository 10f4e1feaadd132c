"""
Surface generation: extrude, ruled, revolve, sweeps
===================================================

Profiles turned into surfaces: extrusion, ruled surfaces, revolution, translational and rotational sweeps, and the generalised sweep along a helix with a rotation-minimising frame. (course §6-26..6-33; ``occsurf demo --only generation``.)
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

module, function = DEMOS["generation"].split(":")
render = getattr(importlib.import_module(module), function)
files = render(Path(tempfile.mkdtemp()) / "generation")
print("\n".join(f.name for f in files))
show(files)
