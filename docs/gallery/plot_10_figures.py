"""
Animated figures: a skinned hierarchical arm
============================================

Course §5-42..5-47 (Forsey 1991): a tube of 30 x 30 poles with four overlays, its base bound to a
two-segment skeleton with a dual-quaternion multi-segment joint at the elbow, a biceps that flexes
with the elbow angle (a pose procedure) and the forearm's flesh as a dynamic level.
"""

# %%
# The demo poses the arm at five angles (and the linear-blend baseline at 120 degrees, whose elbow
# collapses), writes the exact NURBS of each pose as STEP and draws the joint's cross-section area.
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path.cwd()))
from _show import show  # noqa: E402

from occsurf.examples.figures import render_figures_demo  # noqa: E402

files = render_figures_demo(Path(tempfile.mkdtemp()) / "figures")
print("\n".join(f.name for f in files))
show([f for f in files if f.name in ("contact_sheet.png", "cross_section.png")])
