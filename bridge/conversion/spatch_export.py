"""S-patches to OpenCascade faces and shells (course §8-2; issue 4, "Export to OCC and STEP").

Each S-patch is split by :func:`occsurf.algorithms.topology.spatch_convert.convert_spatch` into ``sides``
tensor-product pieces, exact rational Bézier surfaces where the bidegree ``depth * (sides - 2)``
is at most 25, else least-squares bi-quintic B-splines within ``tol`` (measured deviation reported).
Every piece becomes a face over its whole ``[0, 1]²`` domain; all faces of all patches are sewn
with ``BRepBuilderAPI_Sewing`` (pieces of one patch share their spokes exactly, so they always sew;
patches sew with each other where their boundary curves agree within the sewing tolerance) and the
result is checked with ``BRepCheck_Analyzer``.

The STEP files are :mod:`occsurf.bridge.exchange.spatch_io`'s (:func:`~occsurf.bridge.exchange.spatch_io.write_spatches_step`,
:func:`~occsurf.bridge.exchange.spatch_io.read_spatches_step`): exchange is the layer above conversion.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace, BRepBuilderAPI_Sewing
from OCP.BRepCheck import BRepCheck_Analyzer
from OCP.TopoDS import TopoDS_Shape

from occsurf.algorithms.errors import InvalidGeometryError, KernelError
from occsurf.algorithms.topology.spatch import SPatch
from occsurf.algorithms.topology.spatch_convert import SPatchConversion, convert_spatch

from .. import _occ
from .splines import FACE_TOLERANCE, to_occ

__all__ = [
    "SPatchExport",
    "export_spatches",
    "spatch_faces",
    "SEWING_TOLERANCE",
]

#: Sewing tolerance in model units (millimetres): the largest gap between two boundary edges that
#: ``BRepBuilderAPI_Sewing`` merges. The pieces of one patch share their spokes to round-off
#: (~1e-15); this is what two *patches* may differ by along a common boundary. Raised to
#: ``10 * max_deviation`` automatically when a patch had to be approximated.
SEWING_TOLERANCE: float = 1e-6


@dataclass(frozen=True)
class SPatchExport:
    """Result of :func:`export_spatches`.

    Attributes
    ----------
    shape : TopoDS_Shape
        The sewn shape: a ``TopoDS_Shell`` when all faces connect, else a compound of shells/faces.
    conversions : list of SPatchConversion
        One per patch: the pieces, ``exact``, ``degree``, ``max_deviation`` (vs ``SPatch.evaluate``).
    faces : list of list of TopoDS_Face
        The unsewn faces, per patch and piece (the sewn shape holds their sewn copies).
    sewing_tolerance : float
    """

    shape: Any = field(repr=False)
    conversions: list[SPatchConversion]
    faces: list[list[Any]] = field(repr=False)
    sewing_tolerance: float

    @property
    def exact(self) -> bool:
        return all(c.exact for c in self.conversions)

    @property
    def max_deviation(self) -> float:
        return max(c.max_deviation for c in self.conversions)


def _as_patches(patches: SPatch | Sequence[SPatch]) -> list[SPatch]:
    seq = [patches] if isinstance(patches, SPatch) else list(patches) if isinstance(patches, (list, tuple)) else None
    if seq is None:
        raise InvalidGeometryError(f"patches: expected an SPatch or a list of SPatch, got {type(patches).__name__}")
    if not seq:
        raise InvalidGeometryError("patches: expected at least one SPatch, got an empty sequence")
    for i, p in enumerate(seq):
        if not isinstance(p, SPatch):
            raise InvalidGeometryError(f"patches[{i}]: expected an SPatch, got {type(p).__name__}")
        if p.dim != 3:
            raise InvalidGeometryError(f"patches[{i}]: expected a 3-D S-patch, got dimension {p.dim}")
    return seq


def _face(surface: Any, label: str) -> Any:
    with _occ.kernel_errors(f"building the face of {label} (BRepBuilderAPI_MakeFace)"):
        maker = BRepBuilderAPI_MakeFace(to_occ(surface), FACE_TOLERANCE)
        if not maker.IsDone():
            raise KernelError(f"{label}: BRepBuilderAPI_MakeFace failed with status {maker.Error()}")
        return maker.Face()


def export_spatches(patches: SPatch | Sequence[SPatch], *, tol: float | None = None,
                    sewing_tolerance: float | None = None) -> SPatchExport:
    """Convert S-patches to faces, sew them and check the result.

    Parameters
    ----------
    patches : SPatch or sequence of SPatch
        3-D S-patches.
    tol : float, optional
        Maximum deviation of approximated pieces (see :func:`convert_spatch`); exact pieces ignore it.
    sewing_tolerance : float, optional
        Default :data:`SEWING_TOLERANCE`, raised to ten times the largest approximation deviation.

    Returns
    -------
    SPatchExport

    Raises
    ------
    InvalidGeometryError
        Not S-patches, not 3-D, or an empty sequence.
    ToleranceError
        A piece could not be approximated within ``tol``.
    KernelError
        OCC failed to build a face or to sew, or ``BRepCheck_Analyzer`` finds the result invalid.
    """
    seq = _as_patches(patches)
    conversions = [convert_spatch(p, tol=tol) for p in seq]
    faces = [[_face(s, f"patch {i} piece {k}") for k, s in enumerate(c.surfaces)] for i, c in enumerate(conversions)]
    sew_tol = SEWING_TOLERANCE if sewing_tolerance is None else float(sewing_tolerance)
    if not (np.isfinite(sew_tol) and sew_tol > 0):
        raise InvalidGeometryError(f"sewing_tolerance: expected a positive number, got {sewing_tolerance!r}")
    sew_tol = max(sew_tol, 10.0 * max(c.max_deviation for c in conversions))
    with _occ.kernel_errors("sewing the S-patch faces (BRepBuilderAPI_Sewing)"):
        sewing = BRepBuilderAPI_Sewing(sew_tol)
        for row in faces:
            for f in row:
                sewing.Add(f)
        sewing.Perform()
        shape = sewing.SewedShape()
    if shape is None or shape.IsNull():
        raise KernelError("BRepBuilderAPI_Sewing returned a null shape for the S-patch faces")
    with _occ.kernel_errors("checking the sewn S-patch shape (BRepCheck_Analyzer)"):
        valid = BRepCheck_Analyzer(shape).IsValid()
    if not valid:
        raise KernelError("BRepCheck_Analyzer: the sewn S-patch shape is not valid")
    return SPatchExport(shape=shape, conversions=conversions, faces=faces, sewing_tolerance=sew_tol)


def spatch_faces(patches: SPatch | Sequence[SPatch], *, tol: float | None = None) -> TopoDS_Shape:
    """The sewn, checked shape of ``patches`` (a shell when connected); see :func:`export_spatches`."""
    return export_spatches(patches, tol=tol).shape
