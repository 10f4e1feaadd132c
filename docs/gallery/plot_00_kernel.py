"""
The kernel: B-spline curves and surfaces, checked against OpenCascade
=====================================================================

Course ch. 2 and 12: a cubic B-spline curve with its control polygon; knot insertion and degree
elevation change the representation, never the curve; a NURBS surface evaluated by occsurf and by
OCC's ``Geom_BSplineSurface`` at the same points.
"""

# %%
# A clamped cubic with non-uniform knots, refined by inserting knots (Oslo algorithm, course §2-10)
# and raised to degree 5 (§2-6): three control polygons, one curve.
import matplotlib.pyplot as plt
import numpy as np

from occsurf.algorithms import BSplineCurve, BSplineSurface

P = np.array([[0, 0], [1, 2], [3, 2.5], [4, 0.5], [6, 1], [7, 3]], float)
c = BSplineCurve(3, [0, 0, 0, 0, 0.3, 0.5, 1, 1, 1, 1], P)
refined = c.refine([0.15, 0.4, 0.75, 0.9])
raised = c.elevate_degree(2)
u = np.linspace(0, 1, 400)
fig, ax = plt.subplots(figsize=(8, 4))
ax.plot(*c.evaluate(u).T, "k", lw=2.5, label="the curve")
for curve, style, name in ((c, "o-", "cubic, 6 poles"), (refined, "s--", "knots inserted, 10 poles"),
                           (raised, "^:", "degree 5, 12 poles")):
    ax.plot(*curve.control_points.T, style, ms=4, lw=1, label=name)
ax.set_aspect("equal")
ax.legend(loc="lower right")
ax.set_title("one curve, three representations")
print("max |refined - original| =", np.abs(refined.evaluate(u) - c.evaluate(u)).max())
print("max |raised - original|  =", np.abs(raised.evaluate(u) - c.evaluate(u)).max())

# %%
# A rational surface (a torus patch with weights) evaluated by occsurf and by OpenCascade.
from occsurf.bridge import to_occ  # noqa: E402

rng = np.random.default_rng(1)
g = np.linspace(0, 1, 6)
X, Y = np.meshgrid(g, g, indexing="ij")
S = BSplineSurface((3, 2), ([0, 0, 0, 0, 0.4, 0.7, 1, 1, 1, 1], [0, 0, 0, 0.3, 0.6, 0.8, 1, 1, 1]),
                   np.stack([X, Y, 0.3 * np.sin(3 * X) * np.cos(2 * Y)], -1), 1 + 0.5 * rng.random((6, 6)))
occ = to_occ(S)
uu, vv = rng.random(2000), rng.random(2000)
ours = S.evaluate(uu, vv)
theirs = np.array([occ.Value(float(a), float(b)).Coord() for a, b in zip(uu, vv)])
print(f"2000 random points: max |occsurf - OCC| = {np.abs(ours - theirs).max():.2e}")
