"""Show the PNG pictures a demo wrote, one figure each (sphinx-gallery keeps matplotlib figures)."""

from __future__ import annotations

from pathlib import Path


def show(files: list[Path], limit: int = 4) -> None:
    import matplotlib.pyplot as plt

    for f in [f for f in files if f.suffix == ".png"][:limit]:
        img = plt.imread(f)
        h, w = img.shape[:2]
        fig = plt.figure(figsize=(8, 8 * h / w), dpi=100)
        ax = fig.add_axes((0, 0, 1, 1))
        ax.imshow(img)
        ax.set_axis_off()
