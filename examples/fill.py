"""Pictures, a comparison table and a STEP file for n-sided hole filling (course §8-3).

:func:`render_fill_demo` fills a 5-sided hole in a multi-span bicubic-derived shell with our G1
fill (:func:`occsurf.algorithms.topology.nsided.fill_hole`), pictures the fill with mean-curvature colouring beside
the ring of neighbours (the colours run smoothly across the joins: G1, and here even curvature-
continuous looking), runs OCC's ``BRepOffsetAPI_MakeFilling`` on the same hole and writes the
comparison table (OCC ``LocalAnalysis_SurfaceContinuity`` G0 gap and G1 angle, time) as markdown
and as a PNG, plus the filled model as STEP.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from occsurf.bridge.conversion.splines import make_face
from occsurf.bridge.exchange.files import write_figure, write_text
from occsurf.bridge.exchange.step_iges import write_step
from occsurf.bridge.modeling.fill import fill_model, sew_faces
from occsurf.bridge.rendering.surfaces import render_surfaces

from ._common import output_folder

__all__ = ["render_fill_demo"]


def _table_png(path: Path, rows: Sequence[tuple[str, ...]], title: str) -> Path:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(9.6, 1.1 + 0.42 * len(rows)), dpi=110)
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(111)
    ax.axis("off")
    tab = ax.table(cellText=[list(r) for r in rows[1:]], colLabels=list(rows[0]), loc="center", cellLoc="center")
    tab.auto_set_font_size(False)
    tab.set_fontsize(10)
    tab.auto_set_column_width(list(range(len(rows[0]))))  # headers such as "ours G1 angle" fit their cells
    tab.scale(1.0, 1.6)
    for (r, _), cell in tab.get_celld().items():
        if r == 0:
            cell.set_facecolor("#dde6f3")
            cell.set_text_props(weight="bold")
    ax.set_title(title, fontsize=11)
    write_figure(fig, path)
    return path


def render_fill_demo(out_dir: Path) -> list[Path]:
    """Write ``fill_5sided.png``, ``fill_comparison.png``, ``fill_comparison.md`` and
    ``filled_model.step`` into ``out_dir``; returns the paths."""
    from .hole_models import ring_model

    out = output_folder(out_dir)
    files: list[Path] = []
    model = ring_model(5, bump=0.6)
    shell = sew_faces([make_face(f, 1e-7) for f in model.faces])
    res = fill_model(shell)
    hole = next(h for h in res.holes if h.status == "filled")
    fill = next(f for f in res.fills if f is not None)
    boundary = [s.curve for s in fill.sides]
    files.append(render_surfaces(
        out / "fill_5sided.png", [*model.faces, *fill.patches], color="mean",
        title="5-sided hole filled with 5 G1 patches (course §8-3), mean curvature",
        subtitle=(f"hole sides: multi-span degree-6 B-splines; G0 gap {hole.g0:.1e}, G1 angle {hole.g1:.1e} deg "
                  f"(OCC LocalAnalysis); OCC's filler: {hole.occ_g0:.1e}, {hole.occ_g1:.2f} deg"),
        curves=boundary, views=((35.0, -60.0), (70.0, -100.0)), panel_titles=("fill and neighbours", "from above"),
        resolution=40))
    # the comparison table over n = 3..8 on the same kind of holes
    rows = [("n", "ours G0 gap", "ours G1 angle", "ours time", "OCC G0 gap", "OCC G1 angle", "OCC time")]
    for n in range(3, 9):
        m = ring_model(n)
        r = fill_model(sew_faces([make_face(f, 1e-7) for f in m.faces]))
        h = next(h for h in r.holes if h.status != "outer")
        occ = ((f"{h.occ_g0:.1e}", f"{h.occ_g1:.2f} deg", f"{h.occ_seconds:.3f} s") if h.occ_status == "ok"
               else (f"failed: {h.occ_reason}", "-", f"{h.occ_seconds:.3f} s"))
        ours = ((f"{h.g0:.1e}", f"{h.g1:.1e} deg", f"{h.seconds:.3f} s") if h.status == "filled"
                else (f"failed: {h.reason}", "-", "-"))
        rows.append((str(n), *ours, *occ))
    md = out / "fill_comparison.md"
    write_text(md, "# Hole filling: occsurf vs BRepOffsetAPI_MakeFilling (cadquery defaults)\n\n"
               "Max along each hole's boundary, measured by OCC LocalAnalysis_SurfaceContinuity (order G1).\n\n"
               + "| " + " | ".join(rows[0]) + " |\n|" + "---|" * len(rows[0]) + "\n"
               + "\n".join("| " + " | ".join(r) + " |" for r in rows[1:]) + "\n")
    files.append(md)
    files.append(_table_png(out / "fill_comparison.png", rows,
                            "G1 hole filling: occsurf (G1 by construction) vs OCC BRepOffsetAPI_MakeFilling"))
    files.append(write_step(out / "filled_model.step", res.shape, names="filled_5sided"))
    return files
