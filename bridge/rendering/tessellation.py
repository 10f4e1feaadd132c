"""Triangle meshes of imported faces, with the parameters of *our* converted surface at every vertex.

OCC's ``BRepMesh_IncrementalMesh`` triangulates each face inside its trimming loops (holes and
outer boundary respected, neighbouring faces sharing their edge nodes). Every vertex then gets the
parameters ``(u, v)`` of the face's converted :class:`~occsurf.algorithms.BSplineSurface`
(:attr:`ImportedFace.surface`), so that the quality indicators (course ch. 9) are computed by our
own evaluation at exactly the rendered vertices:

* B-spline and Bézier faces are converted whole, bit-exactly: OCC's UV nodes are our parameters.
* Other faces (planes, cylinders, cones, spheres, tori, revolutions, ...) are converted through
  ``GeomConvert`` on the face's UV box, which reparametrises the angular directions (a rational
  arc is not parametrised by angle). Their nodes are mapped by a vectorised Newton point inversion
  onto our surface, started from the linear rescaling of the UV box; a vertex whose inversion does
  not converge keeps OCC's point and is reported in :attr:`FaceMesh.unmapped`.

Positions and normals are our evaluation at those parameters; normals are turned outwards by the
face's orientation (``TopAbs_REVERSED`` flips them and the triangles' winding).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from itertools import chain
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from occsurf.algorithms import BSplineSurface

    from ..exchange.step_iges import ImportedFace, ImportedModel

__all__ = ["FaceMesh", "mesh_model", "mesh_shape", "mesh_face", "grid_mesh", "model_size"]

#: Linear deflection of OCC's mesher, relative to the model's bounding-box diagonal.
LINEAR_DEFLECTION = 4e-4
#: Angular deflection of OCC's mesher, radians (about 6 degrees: zebra stripes stay smooth).
ANGULAR_DEFLECTION = 0.1
#: Newton iterations of the point inversion, and its acceptance bound relative to the model size:
#: OCC's mesh nodes lie within the linear deflection of the surface, not on it (9e-5 of a 5.7
#: diagonal measured on a cylinder of occt__linkrods.step), so a node's closest point on our
#: surface is accepted within twice that deflection.
NEWTON_STEPS = 12
INVERSION_TOL = 2 * LINEAR_DEFLECTION
#: A node whose Newton step moved it by at most this fraction of the parameter box has converged
#: (the next step, quadratic, would be below round-off) and is not iterated further.
NEWTON_STILL = 1e-13


@dataclass
class FaceMesh:
    """A triangulated face.

    Attributes
    ----------
    index : int
        The face's index (as ``occsurf inspect`` numbers faces).
    uv : ndarray, shape (n, 2)
        Parameters of every vertex on the face's converted surface (ours).
    points : ndarray, shape (n, 3)
        Vertices (our evaluation at ``uv``).
    normals : ndarray, shape (n, 3)
        Unit normals, outward by the face's orientation; NaN rows where the surface is degenerate.
    triangles : ndarray, shape (m, 3), int32
        Vertex indices, counter-clockwise seen from outside. 32 bits, as OCC's ``Poly_Triangle``
        holds them: half the memory of 64-bit indices (3.6 million triangles, 41 MiB less, on
        the 1089-face plate of ``benchmarks/bench_check.py``).
    reversed : bool
        The face is ``TopAbs_REVERSED`` in the model (normals and winding already flipped).
    unmapped : int
        Vertices whose parameters could not be found on our surface (OCC's point kept).
    source : str
        ``'brepmesh'`` (trimmed by OCC's mesher) or ``'grid'`` (the untrimmed parameter box).
    """

    index: int
    uv: np.ndarray
    points: np.ndarray
    normals: np.ndarray
    triangles: np.ndarray
    reversed: bool = False
    unmapped: int = 0
    source: str = "brepmesh"
    notes: list[str] = field(default_factory=list)

    @property
    def n_vertices(self) -> int:
        return int(self.points.shape[0])


def model_size(model: ImportedModel) -> float:
    """The diagonal of the model's bounding box (1.0 for an empty or degenerate box)."""
    from OCP.Bnd import Bnd_Box
    from OCP.BRepBndLib import BRepBndLib

    box = Bnd_Box()
    BRepBndLib.Add_s(model.shape, box, False)
    if box.IsVoid():
        return 1.0
    x0, y0, z0, x1, y1, z1 = box.Get()
    d = float(np.linalg.norm([x1 - x0, y1 - y0, z1 - z0]))
    return d if np.isfinite(d) and d > 0 else 1.0


def mesh_model(model: ImportedModel, *, linear: float | None = None, angular: float | None = None) -> float:
    """Triangulate every face of ``model.shape`` in place with ``BRepMesh_IncrementalMesh``.

    Parameters
    ----------
    linear : float, optional
        Linear deflection in model units (default :data:`LINEAR_DEFLECTION` x diagonal).
    angular : float, optional
        Angular deflection, radians (default :data:`ANGULAR_DEFLECTION`).

    Returns
    -------
    float
        The model's bounding-box diagonal.
    """
    size = model_size(model)
    mesh_shape(model.shape, LINEAR_DEFLECTION * size if linear is None else float(linear),
               ANGULAR_DEFLECTION if angular is None else float(angular))
    return size


def _mesh_parameters(linear: float, angular: float, delabella: bool) -> Any:
    """``BRepMesh_IncrementalMesh``'s parameters: those its ``(shape, linear, False, angular, False)``
    constructor sets (the default algorithm: Watson's, unless OCC's ``CSF_MeshAlgo`` says otherwise),
    with Delabella's triangulation instead where asked."""
    from OCP.IMeshTools import IMeshTools_MeshAlgoType_DEFAULT, IMeshTools_MeshAlgoType_Delabella, IMeshTools_Parameters

    p = IMeshTools_Parameters()
    p.Deflection, p.Angle, p.Relative, p.InParallel = float(linear), float(angular), False, False
    p.MeshAlgo = IMeshTools_MeshAlgoType_Delabella if delabella else IMeshTools_MeshAlgoType_DEFAULT
    return p


def is_plane(face: Any) -> bool:
    """The face's surface is a plane (``GeomAbs_Plane``)."""
    from OCP.BRepAdaptor import BRepAdaptor_Surface
    from OCP.GeomAbs import GeomAbs_Plane

    return bool(BRepAdaptor_Surface(face, False).GetType() == GeomAbs_Plane)


def mesh_shape(shape: Any, linear: float, angular: float) -> None:
    """Triangulate every face of ``shape`` in place with ``BRepMesh_IncrementalMesh`` (deflections
    in model units): the curved faces together, with OCC's default (Watson) triangulation, then the
    planar ones with Delabella's.

    On a plane with many holes Watson's Delaunay takes time and memory out of all proportion: a
    200 x 200 plate face with 361 filleted holes took 12.6 s and 820 MB for 45 490 nodes, Delabella
    0.4 s and 12 MB for the same nodes (a plane's nodes are its edges' and the interior nodes the
    mesher adds; only the triangles joining them differ). Meshing the curved faces together and the
    planes apart leaves the curved faces' triangles and every face's nodes exactly as one call on the
    whole shape makes them: measured on every face of the samples, the four realdata models and the
    1089-face plate of ``benchmarks/bench_check.py``; tested (tests/bridge/test_tessellation.py) on
    the samples and realdata models with planes and a plate with 9 holes. A plane Delabella leaves
    without a triangulation is meshed by the default algorithm.
    """
    from OCP.BRepMesh import BRepMesh_IncrementalMesh

    from ..conversion.shapes import as_faces, compound

    faces = as_faces(shape)
    plane = [is_plane(face) for face in faces]
    if not any(plane):
        BRepMesh_IncrementalMesh(shape, _mesh_parameters(linear, angular, False))
        return
    for delabella in (False, True):
        group = [face for face, p in zip(faces, plane, strict=True) if p == delabella]
        if group:
            BRepMesh_IncrementalMesh(compound(group), _mesh_parameters(linear, angular, delabella))
            if delabella:
                for face in group:
                    _default_if_unmeshed(face, linear, angular)


def mesh_one_face(face: Any, linear: float, angular: float) -> None:
    """Triangulate one face in place as :func:`mesh_shape` would (Delabella on a plane)."""
    from OCP.BRepMesh import BRepMesh_IncrementalMesh

    plane = is_plane(face)
    BRepMesh_IncrementalMesh(face, _mesh_parameters(linear, angular, plane))
    if plane:
        _default_if_unmeshed(face, linear, angular)


def _default_if_unmeshed(face: Any, linear: float, angular: float) -> None:
    """Mesh ``face`` with the default algorithm where Delabella's left it without a triangulation."""
    from OCP.BRep import BRep_Tool
    from OCP.BRepMesh import BRepMesh_IncrementalMesh
    from OCP.TopLoc import TopLoc_Location

    if BRep_Tool.Triangulation_s(face, TopLoc_Location()) is None:
        BRepMesh_IncrementalMesh(face, _mesh_parameters(linear, angular, False))


def _occ_triangulation(occ_face: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """``(uv (n, 2), xyz (n, 3), triangles (m, 3) 0-based)`` of a meshed face, or ``None``.

    OCC hands nodes out one by one (no array view through OCP); this is the one loop over vertices.
    """
    from OCP.BRep import BRep_Tool
    from OCP.TopLoc import TopLoc_Location

    loc = TopLoc_Location()
    tri = BRep_Tool.Triangulation_s(occ_face, loc)
    if tri is None or tri.NbTriangles() == 0 or not tri.HasUVNodes():
        return None
    n, m = tri.NbNodes(), tri.NbTriangles()
    # straight into the arrays (np.fromiter over the coordinates), without a list of tuples first:
    # that held about 145 bytes a node and 170 a triangle (each tuple and its numbers) beside the
    # arrays, and took longer (the bearing's 213 faces, alternately: 0.59-0.64 s, now 0.31-0.51 s)
    node, uv_node, triangle = tri.Node, tri.UVNode, tri.Triangle
    if loc.IsIdentity():  # gp_Pnt::Transform leaves a point as it is under the identity
        xyz_rows = (node(i).Coord() for i in range(1, n + 1))
    else:
        trsf = loc.Transformation()
        xyz_rows = (node(i).Transformed(trsf).Coord() for i in range(1, n + 1))
    xyz = np.fromiter(chain.from_iterable(xyz_rows), float, 3 * n).reshape(n, 3)
    uv = np.fromiter(chain.from_iterable(uv_node(i).Coord() for i in range(1, n + 1)), float, 2 * n).reshape(n, 2)
    tris = np.fromiter(chain.from_iterable(triangle(i).Get() for i in range(1, m + 1)), np.int32, 3 * m).reshape(m, 3)
    tris -= 1
    return uv, xyz, tris


def _invert(surface: BSplineSurface, target: np.ndarray, uv0: np.ndarray, tol: float) -> tuple[np.ndarray, np.ndarray]:
    """Newton point inversion ``S(u, v) = target`` (least squares, clamped to the domain), vectorised.

    At most :data:`NEWTON_STEPS` steps; a node stops once a step moved it by at most
    :data:`NEWTON_STILL` of the parameter box (converged: its further steps only change round-off).

    Returns ``(uv (n, 2), ok (n,) bool)``.
    """
    (u0, u1), (v0, v1) = surface.domain
    lo, hi = np.array([u0, v0]), np.array([u1, v1])
    uv = np.clip(uv0, lo, hi)
    still = NEWTON_STILL * float(max(u1 - u0, v1 - v0))
    live = np.arange(len(uv))  # nodes still moving: a converged node's further steps are round-off
    for _ in range(NEWTON_STEPS):
        if live.size == 0:
            break
        D = surface.derivatives(uv[live, 0], uv[live, 1], 1)
        r = D[:, 0, 0] - target[live]
        J = np.stack([D[:, 1, 0], D[:, 0, 1]], axis=-1)  # (n, 3, 2)
        JtJ = np.einsum("nki,nkj->nij", J, J)
        Jtr = np.einsum("nki,nk->ni", J, r)
        det = JtJ[:, 0, 0] * JtJ[:, 1, 1] - JtJ[:, 0, 1] ** 2
        good = np.abs(det) > 1e-300
        inv = np.zeros_like(JtJ)
        inv[good, 0, 0], inv[good, 1, 1] = JtJ[good, 1, 1] / det[good], JtJ[good, 0, 0] / det[good]
        inv[good, 0, 1] = inv[good, 1, 0] = -JtJ[good, 0, 1] / det[good]
        new = np.clip(uv[live] - np.einsum("nij,nj->ni", inv, Jtr), lo, hi)
        moved = np.abs(new - uv[live]).max(axis=1)
        uv[live] = new
        live = live[moved > still]
    err = np.linalg.norm(surface.evaluate(uv[:, 0], uv[:, 1]) - target, axis=-1)
    return uv, err <= tol


def _normals(surface: BSplineSurface, uv: np.ndarray, flip: bool) -> np.ndarray:
    return _unit_normals(surface.derivatives(uv[:, 0], uv[:, 1], 1), flip)


def _unit_normals(D: np.ndarray, flip: bool) -> np.ndarray:
    """Unit normals ``S_u x S_v`` (flipped with ``flip``) from first partials ``D`` ``(n, 2, 2, 3)``;
    NaN where the cross product vanishes (to 1e-14 of the largest)."""
    n = np.cross(D[:, 1, 0], D[:, 0, 1])
    length = np.linalg.norm(n, axis=-1, keepdims=True)
    with np.errstate(all="ignore"):
        n = np.where(length > 1e-14 * max(1.0, float(np.nanmax(length, initial=0.0))), n / length, np.nan)
    return -n if flip else n


def mesh_face(face: ImportedFace, size: float) -> FaceMesh:
    """The mesh of one face of a model triangulated by :func:`mesh_model`.

    Falls back to :func:`grid_mesh` (the untrimmed parameter box of our surface, noted) when OCC
    left the face without a triangulation.

    Raises
    ------
    InvalidGeometryError
        The face has no converted surface (``face.error`` says why).
    """
    from OCP.TopAbs import TopAbs_REVERSED

    from occsurf.algorithms.errors import InvalidGeometryError

    surface = face.surface
    if surface is None:
        raise InvalidGeometryError(f"face {face.index}: no converted surface ({face.error or 'conversion failed'})")
    flip = face.face.Orientation() == TopAbs_REVERSED
    occ = _occ_triangulation(face.face)
    if occ is None:
        mesh = grid_mesh(surface, 41, index=face.index, flip=flip)
        mesh.notes.append("OCC's mesher gave no triangulation: the untrimmed parameter box is shown")
        return mesh
    uv_occ, xyz, tris = occ
    if face.surface_type in ("BSplineSurface", "BezierSurface"):
        (u0, u1), (v0, v1) = surface.domain  # OCC's nodes may overshoot the domain by round-off
        uv, ok = np.clip(uv_occ, [u0, v0], [u1, v1]), np.ones(len(uv_occ), bool)
    else:
        from OCP.BRepTools import BRepTools

        a0, a1, b0, b1 = BRepTools.UVBounds_s(face.face)
        (u0, u1), (v0, v1) = surface.domain
        guess = np.column_stack([u0 + (uv_occ[:, 0] - a0) / max(a1 - a0, 1e-300) * (u1 - u0),
                                 v0 + (uv_occ[:, 1] - b0) / max(b1 - b0, 1e-300) * (v1 - v0)])
        uv, ok = _invert(surface, xyz, guess, INVERSION_TOL * size)
    pts = surface.evaluate(uv[:, 0], uv[:, 1])
    pts[~ok] = xyz[~ok]
    if flip:
        tris = tris[:, ::-1]
    return FaceMesh(index=face.index, uv=uv, points=pts, normals=_normals(surface, uv, flip), triangles=tris,
                    reversed=flip, unmapped=int((~ok).sum()))


def grid_mesh(surface: BSplineSurface, n: int = 41, *, index: int = -1, flip: bool = False,
              mask: np.ndarray | None = None) -> FaceMesh:
    """An ``n x n`` grid over the parameter box of ``surface``, two triangles per cell.

    ``mask`` (``(n, n)`` bool, optional) keeps only cells whose four corners are inside.

    Points and normals come from the grid evaluation (:meth:`~occsurf.algorithms.BSplineSurface.evaluate_grid`,
    ``derivatives_grid``: the basis once per row and per column), not point by point: a 181 x 181
    grid 10-30x faster, the same values to round-off (points within 2e-15, partials within 2e-14
    relative to the net's size; tested).
    """
    (u0, u1), (v0, v1) = surface.domain
    us, vs = np.linspace(u0, u1, n), np.linspace(v0, v1, n)
    U, V = np.meshgrid(us, vs, indexing="ij")
    uv = np.column_stack([U.ravel(), V.ravel()])
    k = np.arange(n * n, dtype=np.int32).reshape(n, n)
    a, b, c, d = k[:-1, :-1].ravel(), k[1:, :-1].ravel(), k[1:, 1:].ravel(), k[:-1, 1:].ravel()
    if mask is not None:
        m = np.asarray(mask, bool)
        keep = (m[:-1, :-1] & m[1:, :-1] & m[1:, 1:] & m[:-1, 1:]).ravel()
        a, b, c, d = a[keep], b[keep], c[keep], d[keep]
    tris = np.concatenate([np.column_stack([a, b, c]), np.column_stack([a, c, d])])
    if flip:
        tris = tris[:, ::-1]
    pts = surface.evaluate_grid(us, vs).reshape(n * n, -1)
    normals = _unit_normals(surface.derivatives_grid(us, vs, 1).reshape(n * n, 2, 2, -1), flip)
    return FaceMesh(index=index, uv=uv, points=pts, normals=normals, triangles=tris, reversed=flip, source="grid")
