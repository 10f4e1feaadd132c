"""Continuity thresholds of ``occsurf check`` (course ch. 9): the presets (CATIA's Connect Checker
defaults, class-A, mechanical), a custom :class:`Thresholds`, and how a measured edge is classified
against them. Measuring is :mod:`.continuity`'s (:func:`~.continuity.edge_continuity`), as is
listing the violations (:func:`~.continuity.check_edges`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

from occsurf.algorithms.errors import InvalidGeometryError

if TYPE_CHECKING:
    from ._pairs import Pair

__all__ = ["Thresholds", "PRESETS", "resolve_thresholds", "limits", "classify_edge", "worst_measure"]


@dataclass(frozen=True)
class Thresholds:
    """Tolerances an edge is checked against (model units: millimetres for STEP/IGES).

    Attributes
    ----------
    g0 : float
        Largest gap.
    g1_deg : float
        Largest angle between the normals, degrees.
    g2_rel : float or None
        Largest curvature jump in percent (CATIA's Connect Checker); ``None``: not checked.
    g2_abs : float or None
        Largest absolute curvature jump, 1/model units; ``None``: not checked.
    g3 : float or None
        Largest jump of the curvature derivative, 1/model units^2; needs ``g3=True``.
    sharp_deg : float
        Angles from this on are creases by design: classified ``'sharp'`` and not G1 violations.
    name : str
    """

    g0: float = 0.001
    g1_deg: float = 0.01
    g2_rel: float | None = 2.0
    g2_abs: float | None = None
    g3: float | None = None
    sharp_deg: float = 0.5
    name: str = "custom"

    def __post_init__(self) -> None:
        for key in ("g0", "g1_deg", "g2_rel", "g2_abs", "g3", "sharp_deg"):
            value = getattr(self, key)
            if value is None and key in ("g2_rel", "g2_abs", "g3"):
                continue
            if not isinstance(value, (int, float)) or not math.isfinite(value) or value < 0:
                raise InvalidGeometryError(f"Thresholds.{key}: expected a finite number >= 0, got {value!r}")

    def replace(self, **changes: Any) -> Thresholds:
        """A copy with some values changed (``name`` becomes ``'<name>+custom'`` unless given)."""
        changes.setdefault("name", f"{self.name}+custom")
        return replace(self, **changes)


#: CATIA's relative curvature jump (percent): also what tells G1 from G2 in a report when the
#: thresholds do not check relative jumps (``g2_rel=None``).
_CATIA_G2_REL = 2.0
#: ``'catia'``: CATIA V5 Connect Checker's defaults (G0 0.001 mm, G1 0.01 deg, G2 2 %).
#: ``'class-a'``: visible automotive/consumer surfaces: half CATIA's angle and curvature jumps
#: (0.005 deg, 1 %), as class-A reviews ask for joints that look seamless in highlight lines, and a
#: G3 check when requested (1e-3 per mm^2).
#: ``'mechanical'``: machined parts: 0.01 mm gap (a typical machining tolerance, and above IGES's
#: 10-digit round-off on metre-sized parts), 0.5 deg tangency (below what shows on a part; also
#: NX's default angle tolerance), no curvature check (a fillet meets its plane with a 100 %
#: curvature jump by design), creases from 5 deg on.
PRESETS: dict[str, Thresholds] = {
    "catia": Thresholds(0.001, 0.01, _CATIA_G2_REL, None, None, 0.5, "catia"),
    "class-a": Thresholds(0.001, 0.005, 1.0, None, 1e-3, 0.5, "class-a"),
    "mechanical": Thresholds(0.01, 0.5, None, None, None, 5.0, "mechanical"),
}


def resolve_thresholds(preset: str | Thresholds) -> Thresholds:
    """``preset`` itself when it is a :class:`Thresholds`, else the :data:`PRESETS` entry of that name."""
    if isinstance(preset, Thresholds):
        return preset
    if isinstance(preset, str) and preset in PRESETS:
        return PRESETS[preset]
    raise InvalidGeometryError(f"preset: expected one of {sorted(PRESETS)} or a Thresholds, got {preset!r}")


def limits(th: Thresholds) -> dict[str, float | None]:
    """Each measure's limit under ``th`` (``None``: not checked)."""
    return {"g0": th.g0, "g1": th.g1_deg, "g2": th.g2_abs, "g2_rel": th.g2_rel, "g3": th.g3}


def classify_edge(p: Pair, val: dict[str, float], th: Thresholds) -> str:
    """The edge's class (one of :data:`~.continuity.CLASSES` but ``'degenerate'``) from its worst
    measures ``val`` under ``th``."""
    if p.seam:
        return "seam"
    g2_rel = th.g2_rel if th.g2_rel is not None else _CATIA_G2_REL
    if not val["g0"] <= th.g0:
        return "gap"
    if not val["g1"] < th.sharp_deg:
        return "sharp"
    if not val["g1"] <= th.g1_deg:
        return "G0"
    if not val["g2_rel"] <= g2_rel or (th.g2_abs is not None and not val["g2"] <= th.g2_abs):
        return "G1"
    return "G2"


def worst_measure(val: dict[str, float], th: Thresholds, cls: str) -> str:
    """The measure furthest beyond its limit (relative), among G0 and G1 alone across a crease."""
    lim = limits(th)
    if lim["g2_rel"] is None:
        lim["g2_rel"] = _CATIA_G2_REL
    ratios = {m: val[m] / limit for m in val if (limit := lim.get(m)) and math.isfinite(val[m])}
    if cls in ("gap", "sharp", "G0"):  # curvature is meaningless across a crease
        ratios = {m: r for m, r in ratios.items() if m in ("g0", "g1")}
    return max(ratios, key=ratios.__getitem__) if ratios else "g0"
