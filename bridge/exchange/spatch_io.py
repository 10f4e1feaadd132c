"""S-patches to and from STEP (course §8-2; issue 4, "Export to OCC and STEP").

:func:`write_spatches_step` writes the sewn shell of :func:`occsurf.bridge.conversion.spatch_export.export_spatches`
through :func:`occsurf.bridge.exchange.step_iges.write_step` (atomic, 17 significant digits, so the pieces'
poles and weights come back bit-identical); :func:`read_spatches_step` reads it back through
:func:`occsurf.bridge.exchange.step_iges.read_step`. (The conversion lives in ``conversion``, the files
here: ``exchange`` is the layer above ``conversion``.)
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

from occsurf.algorithms.topology.spatch import SPatch

from ..conversion.spatch_export import export_spatches
from .step_iges import ImportedModel, read_step, write_step

__all__ = ["write_spatches_step", "read_spatches_step"]


def write_spatches_step(path: str | os.PathLike[str], patches: SPatch | Sequence[SPatch], *,
                        tol: float | None = None, name: str | None = None) -> Path:
    """Write S-patches to a STEP file as one sewn shell (atomically; see :func:`occsurf.bridge.exchange.step_iges.write_step`).

    Parameters
    ----------
    path : str or path-like
    patches : SPatch or sequence of SPatch
    tol : float, optional
        As in :func:`~occsurf.bridge.conversion.spatch_export.export_spatches`.
    name : str, optional
        Product name written to the file.

    Returns
    -------
    pathlib.Path

    Raises
    ------
    InvalidGeometryError, ToleranceError, KernelError
        As :func:`~occsurf.bridge.conversion.spatch_export.export_spatches`.
    ExchangeError
        The file could not be written; no partial file is left behind.
    """
    shape = export_spatches(patches, tol=tol).shape
    return write_step(path, shape, name)


def read_spatches_step(path: str | os.PathLike[str]) -> ImportedModel:
    """Read back a STEP file written by :func:`write_spatches_step` (:func:`occsurf.bridge.exchange.step_iges.read_step`).

    Returns
    -------
    ImportedModel
        One face per piece, each ``surface`` the piece as a :class:`BSplineSurface` (bit-exact).
    """
    return read_step(path)
