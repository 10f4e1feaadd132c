"""Hierarchical B-splines (course ch. 5, Forsey and Bartels): overlays, offset referencing (§5-15),
editing at any level, flattening; and their use for animated figures (§5-42..5-47): skeletons,
control nodes attached to segments, multi-segment joints, procedural offsets, dynamic levels.

Public names: :class:`HierarchicalSurface`, :class:`HierarchicalCurve`, :class:`Overlay`,
:class:`OffsetMapping`, :data:`FRAME_OFFSETS`, :data:`ADDITIVE_OFFSETS`,
:func:`register_offset_mapping`; for figures :class:`Joint`, :class:`Skeleton`, :class:`Pose`,
:class:`Binding`, :func:`bind_to_bones`, :func:`attach`, :class:`AttachedSurface`,
:class:`PoseProcedure`, :class:`JointBulge`, :func:`register_procedure`, :func:`blend_motions`,
:func:`section_area` and :class:`SoftTissue`.
"""

from .curve import HierarchicalCurve
from .dynamics import SoftTissue
from .figures import (
    AttachedSurface,
    Binding,
    JointBulge,
    PoseProcedure,
    attach,
    bind_to_bones,
    register_procedure,
    section_area,
)
from .offsets import ADDITIVE_OFFSETS, FRAME_OFFSETS, OffsetMapping, register_offset_mapping
from .overlays import Overlay
from .skeleton import Joint, Pose, Skeleton
from .skinning import blend_motions
from .surface import HierarchicalSurface

__all__ = [
    "HierarchicalSurface",
    "Overlay",
    "HierarchicalCurve",
    "ADDITIVE_OFFSETS",
    "FRAME_OFFSETS",
    "OffsetMapping",
    "register_offset_mapping",
    "Joint",
    "Skeleton",
    "Pose",
    "Binding",
    "bind_to_bones",
    "attach",
    "AttachedSurface",
    "PoseProcedure",
    "JointBulge",
    "register_procedure",
    "blend_motions",
    "section_area",
    "SoftTissue",
]
