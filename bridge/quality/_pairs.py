"""Which faces meet along which edge: shared edges of a shell, and edges matched geometrically.

A shell's faces share their edges (``TopExp.MapShapesAndAncestors_s``): that is the *topology* of
the model. IGES files and many STEP exports carry loose faces instead, each with its own copy of a
common boundary; like Rhino's ``GlobalEdgeContinuity``, :func:`match_free_edges` pairs such edges
by geometry: an edge ``a`` of face ``A`` is matched to an edge ``b`` of another face when every
sample of ``a`` (ends included) lies within ``tol`` of ``b`` (``a`` is contained in ``b``; equal
edges are matched once). Partial overlaps (``a`` and ``b`` each sticking out of the other) are not
matched.

Each pair is described by two :class:`Side` records: the face, its evaluator, the p-curve of the
edge on it, and the orientation of the edge in the face (orientation of the face composed), from
which a normal flip between the faces is detected.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray
from OCP.BRep import BRep_Tool
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_FORWARD, TopAbs_REVERSED
from OCP.TopExp import TopExp_Explorer
from OCP.TopoDS import TopoDS
from OCP.TopTools import TopTools_IndexedMapOfShape

from ..conversion.occ_evaluators import PCurveEvaluator, SurfaceEvaluator, pcurve_evaluator, surface_evaluator
from ..messages import one_line

if TYPE_CHECKING:
    from ._batch import CurveBatch, SurfaceBatch

Array = NDArray[np.float64]

__all__ = ["FaceData", "Side", "Pair", "collect_faces", "topology_pairs", "match_free_edges", "project_batch"]


@dataclass
class FaceData:
    """One face: its index (as ``occsurf inspect`` numbers it), evaluator or the reason it has none."""

    index: int
    face: Any = field(repr=False)
    reversed: bool
    evaluator: SurfaceEvaluator | None = field(repr=False)
    kind: str
    error: str | None = None


@dataclass
class Side:
    """One face of a pair along the edge.

    ``sense`` is +1 when the edge runs along its curve's parameter in this face's boundary (edge
    orientation composed with the face's), -1 otherwise. ``pcurve`` is ``None`` when the edge has
    no p-curve on the face (its ``(u, v)`` are then found by projection).
    """

    face: int
    edge: Any = field(repr=False)
    sense: int
    pcurve: PCurveEvaluator | None = field(repr=False)


@dataclass
class Pair:
    """Two faces meeting along an edge. For ``matched == 'geometry'`` side 2 belongs to another edge,
    whose parameter ``s`` at a parameter ``t`` of side 1 is found by projection, starting from the
    table ``(t_table, s_table)``."""

    side1: Side
    side2: Side
    matched: str
    seam: bool = False
    degenerate: bool = False
    t_table: Array | None = field(default=None, repr=False)
    s_table: Array | None = field(default=None, repr=False)
    match_distance: float | None = None
    note: str | None = None

    @property
    def first(self) -> float:
        return self.side1.pcurve.first if self.side1.pcurve is not None else 0.0

    @property
    def last(self) -> float:
        return self.side1.pcurve.last if self.side1.pcurve is not None else 1.0


# ------------------------------------------------------------------------------------ faces
def collect_faces(model: Any) -> tuple[Any, list[FaceData]]:
    """The shape and its faces in ``TopExp_Explorer`` order (the numbering of ``occsurf inspect``).

    ``model`` is an :class:`~occsurf.bridge.ImportedModel` (its converted B-spline surfaces are
    reused) or any OCC / build123d / cadquery shape.
    """
    imported = getattr(model, "faces", None)
    if isinstance(imported, list) and hasattr(model, "shape"):
        shape = model.shape
        pairs = [(f.face, f.surface if f.surface_type in ("BSplineSurface", "BezierSurface") else None)
                 for f in imported]
    else:
        from ..conversion.shapes import as_shape

        shape = as_shape(model, "model")
        fmap = TopTools_IndexedMapOfShape()
        ex = TopExp_Explorer(shape, TopAbs_FACE)
        while ex.More():
            fmap.Add(ex.Current())
            ex.Next()
        pairs = [(TopoDS.Face_s(fmap.FindKey(i)), None) for i in range(1, fmap.Extent() + 1)]
    faces = []
    for i, (face, ours) in enumerate(pairs):
        rev = face.Orientation() == TopAbs_REVERSED
        try:
            occ_surface = BRep_Tool.Surface_s(face)
            if occ_surface is None:
                raise ValueError("the face has no surface")
            ev = surface_evaluator(occ_surface, ours)
            faces.append(FaceData(i, face, rev, ev, ev.kind))
        except Exception as err:  # noqa: BLE001 - one bad face must not stop the model
            faces.append(FaceData(i, face, rev, None, "none", f"face {i} cannot be evaluated: {one_line(err)}"))
    return shape, faces


def _pcurve(edge: Any, face: Any) -> PCurveEvaluator | None:
    first, last = BRep_Tool.Range_s(edge)
    c2d = BRep_Tool.CurveOnSurface_s(edge, face, 0.0, 0.0)
    if c2d is None:
        return None
    return pcurve_evaluator(c2d, float(first), float(last))


def _sense(edge: Any) -> int:
    return 1 if edge.Orientation() == TopAbs_FORWARD else -1


# ------------------------------------------------------------------------------------ topology
def topology_pairs(faces: list[FaceData]) -> tuple[list[Pair], list[Side], list[str]]:
    """Pairs of faces sharing an edge, seams (an edge twice in one face), and the free edges.

    Returns
    -------
    pairs : list of Pair
        ``matched == 'topology'``; an edge of ``k > 2`` faces (non-manifold) gives ``k - 1`` pairs
        with the first face.
    free : list of Side
        Edges bounding one face only (candidates for :func:`match_free_edges`).
    warnings : list of str
    """
    emap = TopTools_IndexedMapOfShape()
    occurrences: dict[int, list[tuple[int, Any]]] = {}
    for fd in faces:
        ex = TopExp_Explorer(fd.face, TopAbs_EDGE)
        while ex.More():
            e = TopoDS.Edge_s(ex.Current())
            k = emap.Add(e)
            occurrences.setdefault(k, []).append((fd.index, e))
            ex.Next()
    pairs: list[Pair] = []
    free: list[Side] = []
    warnings: list[str] = []
    for k in sorted(occurrences):
        occ = occurrences[k]
        edge0 = occ[0][1]
        degenerated = bool(BRep_Tool.Degenerated_s(edge0))
        sides = [_side(faces, fi, e) for fi, e in occ]
        if len(occ) == 1:
            if degenerated:
                pairs.append(Pair(sides[0], sides[0], "topology", degenerate=True,
                                  note="degenerated edge (a collapsed side or a pole): nothing to measure"))
            else:
                free.append(sides[0])
            continue
        if len(occ) > 2 and len({fi for fi, _ in occ}) > 2:
            warnings.append(f"non-manifold edge shared by faces {sorted({fi for fi, _ in occ})}")
        for s in sides[1:]:
            seam = s.face == sides[0].face
            first, second = (s, sides[0]) if sides[0].pcurve is None and s.pcurve is not None else (sides[0], s)
            pairs.append(Pair(first, second, "topology", seam=seam, degenerate=degenerated,
                              note="degenerated edge (a collapsed side or a pole): nothing to measure"
                              if degenerated else None))
    return pairs, free, warnings


def _side(faces: list[FaceData], fi: int, edge: Any) -> Side:
    pc = None
    try:
        pc = _pcurve(edge, faces[fi].face)
    except Exception:  # noqa: BLE001 - a missing/bad p-curve is handled by projection
        pc = None
    return Side(fi, edge, _sense(edge), pc)


# ------------------------------------------------------------------------------------ geometry
def _range(side: Side) -> tuple[float, float]:
    """``(first, last)`` of the side's p-curve (the sides matched here all have one)."""
    if side.pcurve is None:
        raise ValueError(f"face {side.face}: this edge has no p-curve on the face")
    return side.pcurve.first, side.pcurve.last


def _samples(curves: CurveBatch, surfaces: SurfaceBatch, fids: NDArray[np.intp], sides: list[Side], n: NDArray[np.intp]
             ) -> tuple[Array, Array, NDArray[np.intp]]:
    """Uniform samples of many edges at once: parameters, 3-D points, owner index."""
    owner = np.repeat(np.arange(len(sides)), n)
    ranges = [_range(s) for s in sides]
    first = np.array([r[0] for r in ranges])
    last = np.array([r[1] for r in ranges])
    start = np.r_[0, np.cumsum(n)[:-1]]
    frac = (np.arange(owner.size) - start[owner]) / (n[owner] - 1)
    t = first[owner] + (last - first)[owner] * frac
    uv, _ = curves.evaluate(owner, t)
    D, _ = surfaces.derivatives(fids[owner], uv[:, 0], uv[:, 1], 0)
    return t, D[:, 0, 0], owner


def project_batch(curves: CurveBatch, surfaces: SurfaceBatch, cid: NDArray[np.intp], fid: NDArray[np.intp], lo: Array, hi: Array,
                  X: Array, s0: Array, iterations: int) -> tuple[Array, Array]:
    """Gauss-Newton projection of points ``X (m, 3)`` onto edge curves ``S_f(pcurve_c(s))``, all at once.

    Returns ``(s, distance)``, ``s`` clipped to ``[lo, hi]``.
    """
    s = np.clip(s0, lo, hi)
    for _ in range(iterations):
        uv, duv = curves.evaluate(cid, s)
        D, _ = surfaces.derivatives(fid, uv[:, 0], uv[:, 1], 1)
        dC = D[:, 1, 0] * duv[:, :1] + D[:, 0, 1] * duv[:, 1:]
        den = np.einsum("ij,ij->i", dC, dC)
        ok = np.isfinite(den) & (den > 0)
        step = np.where(ok, -np.einsum("ij,ij->i", dC, D[:, 0, 0] - X) / np.where(ok, den, 1.0), 0.0)
        s = np.clip(s + step, lo, hi)
    uv, _ = curves.evaluate(cid, s)
    D, _ = surfaces.derivatives(fid, uv[:, 0], uv[:, 1], 0)
    return s, np.linalg.norm(D[:, 0, 0] - X, axis=1)


def match_free_edges(faces: list[FaceData], free: list[Side], tol: float, spacing: float, surfaces: SurfaceBatch,
                     iterations: int = 6) -> list[Pair]:
    """Pair free edges of different faces that coincide within ``tol`` (see the module docstring).

    Parameters
    ----------
    faces : list of FaceData
    free : list of Side
        Edges that bound one face only.
    tol : float
        Largest distance (model units) of a sample of one edge from the other edge.
    spacing : float
        Target distance between the samples that locate candidates (a KD-tree of all samples).
    surfaces : SurfaceBatch
        The faces' batch evaluator.
    """
    from scipy.spatial import cKDTree

    from ._batch import CurveBatch

    usable = [s for s in free if s.pcurve is not None and faces[s.face].evaluator is not None]
    if len(usable) < 2:
        return []
    curves = CurveBatch([s.pcurve for s in usable])
    fids = np.array([s.face for s in usable], dtype=np.intp)
    K = 9
    t_probe, probes, _ = _samples(curves, surfaces, fids, usable, np.full(len(usable), K))
    probes3 = probes.reshape(len(usable), K, 3)
    lengths = np.linalg.norm(np.diff(probes3, axis=1), axis=2).sum(axis=1)
    n = np.clip(np.ceil(np.nan_to_num(lengths) / spacing).astype(np.intp) + 1, K, 400)
    t_dense, dense, owner = _samples(curves, surfaces, fids, usable, n)
    finite = np.all(np.isfinite(dense), axis=1)
    tree = cKDTree(np.where(finite[:, None], dense, 1e300))
    steps = np.linalg.norm(np.diff(dense, axis=0), axis=1)
    steps[np.diff(owner) != 0] = 0.0
    radius = tol + 0.5 * float(np.nanmax(steps)) + 1e-12
    hits = tree.query_ball_point(np.nan_to_num(probes, nan=1e300), radius)
    near = [_containing(hits, owner, a, K) for a in range(len(usable))]  # each edge's candidates, once
    cand_a, cand_b = [], []
    for a in range(len(usable)):
        for b in sorted(near[a]):
            if b < a and a in near[b]:  # equal edges: matched once
                continue
            if usable[b].face != usable[a].face:
                cand_a.append(a)
                cand_b.append(b)
    if not cand_a:
        return []
    ca, cb = np.array(cand_a, dtype=np.intp), np.array(cand_b, dtype=np.intp)
    X = probes3[ca].reshape(-1, 3)
    rb = np.repeat(cb, K)
    # start on b at its nearest dense sample
    start = np.r_[0, np.cumsum(n)[:-1]]
    s0 = np.empty(X.shape[0])
    for j, b in enumerate(cb):
        seg = dense[start[b]:start[b] + n[b]]
        d2 = ((X[j * K:(j + 1) * K, None, :] - seg[None]) ** 2).sum(axis=2)
        s0[j * K:(j + 1) * K] = t_dense[start[b] + d2.argmin(axis=1)]
    lo = np.array([_range(usable[b])[0] for b in rb])
    hi = np.array([_range(usable[b])[1] for b in rb])
    s, dist = project_batch(curves, surfaces, rb, fids[rb], lo, hi, X, s0, iterations)
    dist = dist.reshape(-1, K)
    s = s.reshape(-1, K)
    t_a = t_probe.reshape(-1, K)
    pairs = []
    for j, (a, b) in enumerate(zip(ca, cb)):
        if np.all(dist[j] <= tol):
            pairs.append(Pair(usable[a], usable[b], "geometry", t_table=t_a[a], s_table=s[j],
                              match_distance=float(dist[j].max())))
    return pairs


def _containing(hits: list, owner: NDArray[np.intp], a: int, K: int) -> set[int]:
    """Edges near every probe of edge ``a`` (its candidates); the intersection stops at the first
    probe that leaves none (it stays empty)."""
    common: set[int] | None = None
    for h in hits[a * K:(a + 1) * K]:
        owners = set(owner[h].tolist()) if len(h) else set()
        common = owners if common is None else common & owners
        if not common:
            break
    return common or set()
