"""The per-vertex values of a meshed face (:attr:`.report.FaceField.values`): the curvatures and
the draft held, the zebra phase and the isophote intensity computed on each access.

The report's views draw zebra stripes and isophotes per pixel from the interpolated normals (VTK's
shaders and the page's); the per-vertex phase and intensity serve only callers that ask for them
(:func:`.export.reflection_lines`, :func:`.export.colored_mesh` with ``"zebra"`` or
``"isophote"``, scripts). Held for every face they were two arrays of 8 bytes a
vertex: 28 MB of the check's peak on the 1.8 million vertices of the 1089-face plate of
``benchmarks/bench_check.py``. Computed from the same mesh by the same functions, they are the
values that were held, bit for bit.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from ..rendering.tessellation import FaceMesh

__all__ = ["FaceValues", "ZEBRA_DISTANCE", "ZEBRA_WIDTH", "ISOPHOTE_LEVELS", "VALUE_NAMES"]

#: Zebra set-up for the per-vertex fields (view along the iso camera, light lines along z): the
#: light plane stands ZEBRA_DISTANCE model sizes behind the viewer, one light/dark pair every
#: ZEBRA_WIDTH of that distance, so a pair is about 24 degrees of reflected direction near the
#: middle, as CAD zebra environments are; finer stripes would be undersampled by the mesh's
#: vertices (about 6 degrees of normal, 12 of reflected ray, apart).
ZEBRA_DISTANCE = 10.0
ZEBRA_WIDTH = 0.45
ISOPHOTE_LEVELS = 12
#: The values of a face, in the order a :class:`FaceValues` lists them.
VALUE_NAMES: tuple[str, ...] = ("mean", "gaussian", "max", "min", "absolute", "zebra", "isophote", "draft")
_COMPUTED = ("zebra", "isophote")


class FaceValues(Mapping[str, np.ndarray]):
    """A face's per-vertex values by indicator name, read-only, some computed when asked.

    Each value has shape ``(n,)``. The ``held`` ones are returned as given. ``'zebra'`` (the phase
    in [0, 1), :func:`occsurf.algorithms.quality.zebra`) and ``'isophote'`` (the intensity
    ``n.l``, :func:`occsurf.algorithms.quality.isophotes`) are computed from ``mesh`` on each
    access, with the light from ``-view_dir`` and the zebra plane :data:`ZEBRA_DISTANCE` model
    sizes (``size``) away.

    Parameters
    ----------
    held : dict of str -> ndarray
        The curvatures and the draft (every name but the computed two).
    mesh : FaceMesh
        The face's mesh (its points and normals).
    view_dir : sequence of 3 floats
        The viewing direction of the report's iso camera.
    size : float
        The model's size.
    """

    __slots__ = ("_held", "_mesh", "_view_dir", "_size")

    def __init__(self, held: dict[str, np.ndarray], mesh: FaceMesh, view_dir: Sequence[float], size: float) -> None:
        self._held = dict(held)
        self._mesh = mesh
        self._view_dir = np.asarray(view_dir, float)
        self._size = float(size)

    def __getitem__(self, key: str) -> np.ndarray:
        held = self._held.get(key)
        if held is not None:
            return held
        if key == "zebra":
            from occsurf.algorithms.quality import zebra

            distance = ZEBRA_DISTANCE * self._size
            return np.asarray(zebra(self._mesh.points, self._mesh.normals, self._view_dir, width=ZEBRA_WIDTH * distance,
                                    distance=distance).phase, float)
        if key == "isophote":
            from occsurf.algorithms.quality import isophotes

            return np.asarray(isophotes(self._mesh.normals, -self._view_dir, ISOPHOTE_LEVELS).intensity, float)
        raise KeyError(key)

    def __contains__(self, key: object) -> bool:
        # Mapping's would call __getitem__: compute the values only to say they are there
        return key in self._held or key in _COMPUTED

    def __iter__(self) -> Iterator[str]:
        names = [k for k in VALUE_NAMES if k in self._held or k in _COMPUTED]
        return iter(names + [k for k in self._held if k not in names])

    def __len__(self) -> int:
        return len(set(self._held) | set(_COMPUTED))

    def __repr__(self) -> str:
        return f"FaceValues({list(self)}, {self._mesh.n_vertices} vertices)"
