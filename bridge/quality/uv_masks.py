"""A face's parameter plane masked by its mesh: what the sections and the flags use on faces the
reader gave no exact trim (OCC's triangulation, mapped to our parameters), and how many such masks
are kept at once.

A mask is a triangle finder (matplotlib's trapezoid map) over the face's triangles in ``(u, v)``:
up to ~7 MB each (a fillet torus of 4191 vertices), in C++ (invisible to ``tracemalloc``). The
sections of a large model reach most of its faces (a 1089-face plate: 477 finders, 1.36 GB held
at once when every face kept its own), yet each face needs its finder only while that face is
cut. :class:`MeshMask` builds its finder on the first call and gives it up once
:data:`MESH_MASKS_KEPT` other masks were used after it (rebuilt, the same, if called again): the
masks' memory is bounded whatever the model's size.
"""

from __future__ import annotations

import threading
import weakref
from collections import OrderedDict
from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from ..rendering.tessellation import FaceMesh

__all__ = ["uv_mask", "MeshMask", "MESH_MASKS_KEPT"]

#: Mesh masks holding their triangle finder at once (the most recently used). A model's sections
#: cut one face after another (each face with every plane at once), and a face's own sections come
#: after the model's; 16 finders are at most ~120 MB (16 fillet tori of 4191 vertices).
MESH_MASKS_KEPT = 16

_recent: OrderedDict[int, weakref.ref[MeshMask]] = OrderedDict()
_lock = threading.Lock()


def uv_mask(mesh: FaceMesh) -> Callable[[np.ndarray, np.ndarray], np.ndarray]:
    """``mask(u, v) -> bool array``: parameters inside the trimmed face, i.e. inside a triangle of
    its mesh in our parameter space (OCC's trimmed triangulation; matplotlib's triangle finder)."""
    from matplotlib.tri import TrapezoidMapTriFinder, Triangulation

    uv = mesh.uv
    tris = mesh.triangles[:, ::-1] if mesh.reversed else mesh.triangles
    a, b, c = uv[tris[:, 0]], uv[tris[:, 1]], uv[tris[:, 2]]
    area = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
    span = float(np.ptp(uv, axis=0).prod()) or 1.0
    tris = tris[np.abs(area) > 1e-14 * span]  # collapsed triangles (poles, seams) confuse the finder
    tris = np.where((area[np.abs(area) > 1e-14 * span] < 0)[:, None], tris[:, ::-1], tris)
    try:
        # the finder itself, not Triangulation.get_trifinder(): that one is kept on the triangulation,
        # a reference cycle that outlives the mask until a full garbage collection (100 finders of a
        # fillet, four held at a time: 391-721 MB of RSS that way, 36 MB so)
        finder = TrapezoidMapTriFinder(Triangulation(uv[:, 0], uv[:, 1], tris))
    except (RuntimeError, ValueError):  # overlapping triangles in the parameter plane (a face across its seam)
        return _triangle_mask(uv, tris)

    def mask(u: np.ndarray, v: np.ndarray) -> np.ndarray:
        u, v = np.broadcast_arrays(np.asarray(u, float), np.asarray(v, float))
        return np.asarray(finder(u.ravel(), v.ravel())).reshape(u.shape) >= 0

    return mask


def _triangle_mask(uv: np.ndarray, tris: np.ndarray) -> Callable[[np.ndarray, np.ndarray], np.ndarray]:
    """The same mask by brute force: a point is inside when it is inside one triangle
    (barycentric test, vectorised over points in blocks against every triangle)."""
    a, b, c = uv[tris[:, 0]], uv[tris[:, 1]], uv[tris[:, 2]]
    det = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])

    def mask(u: np.ndarray, v: np.ndarray) -> np.ndarray:
        u, v = np.broadcast_arrays(np.asarray(u, float), np.asarray(v, float))
        q = np.column_stack([u.ravel(), v.ravel()])
        out = np.zeros(len(q), bool)
        for s in range(0, len(q), 256):
            dx = q[s:s + 256, None, 0] - a[None, :, 0]
            dy = q[s:s + 256, None, 1] - a[None, :, 1]
            l1 = (dx * (c[:, 1] - a[:, 1]) - dy * (c[:, 0] - a[:, 0])) / det
            l2 = (dy * (b[:, 0] - a[:, 0]) - dx * (b[:, 1] - a[:, 1])) / det
            out[s:s + 256] = np.any((l1 >= -1e-12) & (l2 >= -1e-12) & (l1 + l2 <= 1 + 1e-12), axis=1)
        return out.reshape(u.shape)

    return mask


class MeshMask:
    """:func:`uv_mask` of one face's mesh, built on the first call and held while it is among the
    :data:`MESH_MASKS_KEPT` masks used last (then given up, and built again if called again: the
    same finder on the same mesh, so the same answers)."""

    def __init__(self, mesh: FaceMesh) -> None:
        self.mesh = mesh
        self._finder: Callable[[np.ndarray, np.ndarray], np.ndarray] | None = None

    @property
    def built(self) -> bool:
        """Whether the triangle finder is held now."""
        return self._finder is not None

    def __call__(self, u: np.ndarray, v: np.ndarray) -> np.ndarray:
        finder = self._finder
        if finder is None:
            finder = self._finder = uv_mask(self.mesh)
        _used(self)
        return finder(u, v)

    def release(self) -> None:
        """Give the triangle finder up (the next call builds it again)."""
        self._finder = None


def _used(mask: MeshMask) -> None:
    """``mask`` is the most recently used; the least recently used beyond :data:`MESH_MASKS_KEPT`
    give their finders up (masks no longer referenced anywhere drop out by themselves)."""
    key = id(mask)
    with _lock:  # masks may be called from several threads (a notebook's, a server's)
        _recent[key] = weakref.ref(mask)
        _recent.move_to_end(key)
        while len(_recent) > max(int(MESH_MASKS_KEPT), 1):
            _, ref = _recent.popitem(last=False)
            old = ref()
            if old is not None:
                old.release()
