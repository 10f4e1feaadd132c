"""``occsurf demo --only repair``: a two-face model with a broken tangent edge, matched (issue 29).

Two bicubic patches share an edge along which the tangent planes meet at 1 degree (the second
pole row of one turned about the edge). :func:`occsurf.bridge.modeling.matching.match_faces`
matches it G2 to its neighbour by the least change of its poles (course ch. 3-4); the picture
shows zebra stripes across the edge before (broken where the stripes kink) and after (continuous,
and curvature-continuous: the stripes' direction and spacing carry across).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from OCP.BRepBuilderAPI import BRepBuilderAPI_Sewing

from occsurf.algorithms.kernel.surface import BSplineSurface
from occsurf.bridge.conversion.splines import make_face
from occsurf.bridge.exchange.step_iges import write_step
from occsurf.bridge.modeling.fill_pictures import zebra_before_after
from occsurf.bridge.modeling.matching import match_faces
from occsurf.bridge.modeling.refill_loop import model_faces

from ._common import output_folder

__all__ = ["kinked_pair", "render_repair_demo"]


def kinked_pair(kink_deg: float = 1.0) -> tuple[BSplineSurface, BSplineSurface]:
    """Patches T (x <= 0) and S (x >= 0) sharing the edge x = 0, S's second row turned by ``kink_deg``."""
    ys = np.linspace(0, 1, 5)
    kv = np.concatenate([[0.0] * 4, [0.5], [1.0] * 4])
    T = np.zeros((4, 5, 3))
    S = np.zeros((6, 5, 3))
    for i in range(4):
        T[i, :, 0], T[i, :, 1] = -i / 3, ys
        T[i, :, 2] = 0.25 * np.sin(1.2 * T[i, :, 0] + 2.0 * ys)
    for i in range(6):
        S[i, :, 0], S[i, :, 1] = i / 3, ys
        S[i, :, 2] = 0.25 * np.sin(1.2 * S[i, :, 0] + 2.0 * ys) + 0.05 * (i / 5) ** 2
    S[0] = T[0]
    S[1, :, 2] = 2 * T[0, :, 2] - T[1, :, 2] + np.tan(np.radians(kink_deg)) / 3
    ku = np.concatenate([[0.0] * 4, [1 / 3, 2 / 3], [1.0] * 4])
    return (BSplineSurface((3, 3), ([0, 0, 0, 0, 1, 1, 1, 1], kv), T),
            BSplineSurface((3, 3), (ku, kv), S))


def render_repair_demo(out_dir: Path) -> list[Path]:
    """Write ``repair_zebra.png`` and ``repaired_pair.step`` into ``out_dir``; returns the paths."""
    out = output_folder(out_dir)
    T, S = kinked_pair(1.0)
    sew = BRepBuilderAPI_Sewing(1e-6)
    for s in (T, S):
        sew.Add(make_face(s))
    sew.Perform()
    shape = sew.SewedShape()
    rep, fixed = match_faces(shape, 1, 0, "G2")
    before, after = model_faces(shape), model_faces(fixed)
    a, b = rep.faces_out or (1, 0)
    files = [zebra_before_after(
        out / "repair_zebra.png", [before[1]], [before[0]], [after[a]],
        label=f"before: tangent planes {rep.g1_before_deg:.2f} deg apart",
        after_label=(f"after match G2: G1 {rep.g1_max_deg:.1e} deg (OCC), curvature jump "
                     f"{100 * rep.g2_max_rel:.1e} %, change {rep.max_change:.1e}"))]
    files.append(write_step(out / "repaired_pair.step", fixed, names="repaired_pair"))
    return files
