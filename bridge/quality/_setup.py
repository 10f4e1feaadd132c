"""The measuring set-up of :func:`~occsurf.bridge.quality.continuity.edge_continuity`: a model's
faces, the model's size, the face pairs across every shared or matched edge, and the
:class:`~._engine.Engine` that evaluates them.

One builder for the check, the continuity benchmark and the tests that drive the engine directly,
so that a change of the set-up (the size the tolerances are relative to, the matching spacing)
reaches all three.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any

from occsurf.algorithms import tolerances
from occsurf.algorithms.errors import InvalidGeometryError

from ..messages import one_line
from ._batch import SurfaceBatch
from ._engine import Engine
from ._pairs import FaceData, Pair, collect_faces, match_free_edges, topology_pairs

__all__ = ["shape_size", "EngineSetup", "build_engine"]


def shape_size(shape: Any) -> float:
    """The diagonal of OCC's bounding box of ``shape`` (``BRepBndLib.Add``: of its triangulation
    where its faces are meshed) that
    :func:`~occsurf.bridge.quality.continuity.edge_continuity`'s tolerances are relative to."""
    from OCP.Bnd import Bnd_Box
    from OCP.BRepBndLib import BRepBndLib

    box = Bnd_Box()
    BRepBndLib.Add_s(shape, box)
    if box.IsVoid():
        return 1.0
    x0, y0, z0, x1, y1, z1 = box.Get()
    d = math.sqrt((x1 - x0) ** 2 + (y1 - y0) ** 2 + (z1 - z0) ** 2)
    return d if d > 0 and math.isfinite(d) else 1.0


def _check_face_pairs(face_pairs: Any, n_faces: int) -> set[tuple[int, int]]:
    try:
        chosen = {(min(i, j), max(i, j)) for i, j in ((int(a), int(b)) for a, b in face_pairs)}
    except (TypeError, ValueError) as err:
        raise InvalidGeometryError(f"face_pairs: expected pairs of face indices, got {face_pairs!r}") from err
    bad = sorted(i for pair in chosen for i in pair if not 0 <= i < n_faces)
    if bad:
        raise InvalidGeometryError(f"face_pairs: face indices must be in [0, {n_faces - 1}], got {bad}")
    return chosen


@dataclass
class EngineSetup:
    """What :func:`build_engine` made: the engine (its ``pairs``: topology pairs first, then the
    geometric matches), the faces, the free edges, the set-up's warnings (pairing and face errors),
    how many pairs are topology pairs, the matching tolerance (``None`` without matching), the
    model's size and the seconds the matching took."""

    engine: Engine
    faces: list[FaceData]
    free: list[Any]
    warnings: list[str]
    n_topology: int
    match_tol: float | None
    size: float
    seconds_matching: float

    @property
    def pairs(self) -> list[Pair]:
        return self.engine.pairs


def build_engine(model: Any, *, g3: bool = False, loose: bool = True, match_tol: float | None = None,
                 face_pairs: Any = None, model_size: float | None = None) -> EngineSetup:
    """The faces of ``model``, their pairs across shared edges (and, if ``loose``, across free edges
    matched within ``match_tol``, default ``tolerances.CONTINUITY_MATCH_RTOL`` times the size) and
    the :class:`~._engine.Engine` measuring them (third derivatives if ``g3``).

    ``face_pairs`` (pairs of face indices, either order) keeps only the pairs between those faces;
    ``model_size`` replaces :func:`shape_size` of the shape. The arguments are those of
    :func:`~occsurf.bridge.quality.continuity.edge_continuity`, which checks the others.

    Raises
    ------
    InvalidGeometryError
        ``model`` is not a shape; ``face_pairs`` not pairs of face indices of the model.
    """
    try:
        shape, faces = collect_faces(model)
    except Exception as err:  # noqa: BLE001
        raise InvalidGeometryError(f"model: expected an ImportedModel or an OCC/build123d/cadquery shape, "
                                   f"got {type(model).__name__} ({one_line(err)})") from err
    size = shape_size(shape) if model_size is None else float(model_size)
    surfaces = SurfaceBatch([f.evaluator for f in faces])
    pairs, free, warnings = topology_pairs(faces)
    warnings += [f.error for f in faces if f.error]
    n_topology = len(pairs)
    tol = None
    clock = time.perf_counter()
    if loose:
        tol = match_tol if match_tol is not None else tolerances.CONTINUITY_MATCH_RTOL * size
        pairs += match_free_edges(faces, free, tol, spacing=size / 200.0, surfaces=surfaces)
    seconds = time.perf_counter() - clock
    if face_pairs is not None:
        chosen = _check_face_pairs(face_pairs, len(faces))
        pairs = [p for p in pairs if tuple(sorted((p.side1.face, p.side2.face))) in chosen]
        n_topology = sum(p.matched == "topology" for p in pairs)
    engine = Engine(faces, pairs, g3, tolerances.CONTINUITY_CURVATURE_FLOOR / size, surfaces)
    return EngineSetup(engine, faces, free, warnings, n_topology, tol, size, seconds)
