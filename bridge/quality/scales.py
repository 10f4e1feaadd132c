"""The colour range of a quality indicator over several faces, shared by the report's pictures
(:mod:`.pictures`), its page's 3-D view (:mod:`.html`) and the coloured meshes it exports
(:mod:`.export`): one range per indicator, so a colour means the same value on every face and in
every view (course §9-8, graphical representation).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

__all__ = ["FLAT_SCALE", "value_range"]

#: Smallest half-range of a curvature colour scale, times the model size (1/unit; squared for
#: Gaussian curvature): a flat face's round-off (1e-14) is drawn as zero, not as a full scale.
FLAT_SCALE = 1e-6


def value_range(values: Sequence[np.ndarray], kind: str, size: float = 1.0) -> tuple[float, float]:
    """Common colour range ``(lo, hi)`` of several faces' values of the indicator ``kind``.

    Signed curvatures (``mean``, ``gaussian``, ``max``, ``min``) get a range symmetric about 0,
    the others a clipped one (:func:`occsurf.algorithms.quality.color_scale`), never narrower than
    :data:`FLAT_SCALE` (over ``size``, the model's size; squared for Gaussian curvature). Stripes
    have fixed ranges: ``zebra`` [0, 1], ``isophote`` [-1, 1], ``draft`` [-90, 90] degrees.

    Parameters
    ----------
    values : sequence of ndarray
        Each face's values (any shape; NaN and infinite values are left out).
    kind : str
        The indicator.
    size : float, default 1
        The model's size.

    Returns
    -------
    (float, float)
    """
    from occsurf.algorithms.quality import color_scale

    if kind == "zebra":
        return 0.0, 1.0
    if kind == "isophote":
        return -1.0, 1.0
    if kind == "draft":
        return -90.0, 90.0
    allv = np.concatenate([np.asarray(v, float).ravel() for v in values]) if values else np.zeros(1)
    finite = allv[np.isfinite(allv)]
    floor = FLAT_SCALE / size ** (2 if kind == "gaussian" else 1)
    if finite.size == 0:
        return -floor, floor
    mode = "symmetric" if kind in ("mean", "gaussian", "max", "min") else "clipped"
    sc = color_scale(finite, mode)
    lo, hi = float(sc.lo), float(sc.hi)
    if hi - lo < 2 * floor:
        mid = 0.0 if mode == "symmetric" else (lo + hi) / 2
        lo, hi = mid - floor, mid + floor
    return lo, hi
