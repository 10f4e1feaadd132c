"""Hierarchical B-splines (course ch. 5, Forsey and Bartels): overlays, offset referencing (§5-15),
editing at any level, flattening.

Public names: :class:`HierarchicalSurface`, :class:`HierarchicalCurve`, :class:`Overlay`,
:class:`OffsetMapping`, :data:`FRAME_OFFSETS`, :data:`ADDITIVE_OFFSETS`,
:func:`register_offset_mapping`.
"""

from .core import Overlay
from .curve import HierarchicalCurve
from .offsets import ADDITIVE_OFFSETS, FRAME_OFFSETS, OffsetMapping, register_offset_mapping
from .surface import HierarchicalSurface

__all__ = [
    "HierarchicalSurface",
    "Overlay",
    "HierarchicalCurve",
    "ADDITIVE_OFFSETS",
    "FRAME_OFFSETS",
    "OffsetMapping",
    "register_offset_mapping",
]
