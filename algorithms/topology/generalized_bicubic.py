"""Generalized bicubic B-spline surfaces of arbitrary topology from S-patches (course §8-6, 8-7).

The companion of :func:`occsurf.algorithms.topology.generalized.generalized_biquadratic` (Loop & DeRose 1990, as
outlined in course §8-7, "generalized bicubic scheme"): one ``n``-sided S-patch per face of a mesh
whose interior vertices all have valence 4, reached from any mesh by one Doo–Sabin step
(:func:`occsurf.algorithms.topology.mesh.doo_sabin`); where the mesh is a regular quadrilateral grid the patches *are*
the uniform bicubic B-spline patches that have the mesh as control net, and everywhere the patches
meet with tangent-plane (G1) continuity.

The construction
----------------
**Patches and corners.** A uniform bicubic B-spline patch belongs to a face of its control net; its
corner at a face vertex ``v`` depends only on the 3 x 3 grid of control points around ``v``. With
valence 4 that grid exists around every interior vertex of any mesh: ``v``, its four neighbours
(ccw: ``w`` after ``v`` in face ``F``, ``u`` before it, then the two opposite ones) and one
*diagonal* point per face of ``v``: the vertex opposite ``v`` in a quadrilateral, and for a face
``Φ`` with ``k != 4`` sides the virtual point ``δ = 4 c_Φ - v - a - b`` (``c_Φ`` the centroid, ``a, b``
the neighbours of ``v`` in ``Φ``): the point that makes the face point of the virtual quad
``(v, a, δ, b)`` the centroid of ``Φ``, as in the Catmull–Clark and biquadratic rules. For a
quadrilateral the formula gives the opposite vertex.

**The corner blocks** (the Sabin net of course §8-5). Converting the uniform cubic B-spline to
Bézier form, the corner block of the patch of face ``F`` at ``v`` is

.. math::

    b_{αβ} = \\sum_{i, j \\in \\{-1, 0, 1\\}} w_α(i)\\, w_β(j)\\, G_{ij}, \\qquad
    w_0 = (1, 4, 1) / 6, \\quad w_1 = (0, 2, 1) / 3,

``G_{ij}`` the grid with ``i`` along the edge ``v → w`` and ``j`` along ``v → u``: ``b_00`` the
corner point, ``b_10`` and ``b_01`` the next Bézier points along the two sides, ``b_11`` the twist
point. All faces at ``v`` read the same grid (turned), so the patches at ``v`` share the corner
point, the tangent plane and the twist.

**Sides.** Side ``k`` of the patch of face ``F = (f_0 .. f_{n-1})`` runs from ``f_k`` to ``f_{k+1}``; its
first two Bézier rows are ``rows0 = (b_00, b_10 | b_01', b_00')`` and ``rows1 = (b_01, b_11 | b_11',
b_10')``, unprimed from the block at ``f_k``, primed from the block at ``f_{k+1}`` (whose own side
direction points along side ``k + 1``). The face across the edge builds the same boundary curve
and the opposite cross derivative from the same two blocks, so the strips join C1.

**Patches.** A quadrilateral face gives its bicubic Bézier net directly, represented exactly as the
4-sided S-patch of depth 3 (``P_I = b_{i_1 + i_2,\\, i_2 + i_3}``; Wachspress coordinates on the
square are bilinear, course §8-2). A face with ``n != 4`` sides gets the S-patch of depth 6 that
carries the ribbons ``(rows0, rows1)`` of its sides with G1 continuity
(:func:`occsurf.algorithms.topology.generalized.ribbon_patch`: the cross-boundary condition ``ρ D + λ T`` has degree
``2 + 3``, so ``d - 1 = 5``). Hence the surface is C1 between quadrilateral patches, G1 everywhere.

Notes
-----
Loop & DeRose build the bicubic scheme from S-patches too; their text was not available to us,
so the virtual diagonal rule and the harmonic interior of the depth-6 patches are our choices
(they never affect the joins, which the construction makes G1 exactly, and the regular case, which
it makes the bicubic B-spline). Only faces whose vertices are all interior get a patch (a bicubic
B-spline has no patch for the outermost ring of its net either).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from .. import tolerances
from ..errors import InvalidGeometryError
from .generalized import GeneralizedSurface, check_scheme_args, ribbon_patch
from .mesh import Mesh, doo_sabin
from .spatch import SPatch, spatch_indices

__all__ = ["generalized_bicubic", "BICUBIC_DEPTH"]

Array = NDArray[np.float64]

#: Depth of the S-patch of a face with ``n != 4`` sides (quadrilaterals use depth 3).
BICUBIC_DEPTH: int = 6

_W = np.array([[1.0, 4.0, 1.0], [0.0, 4.0, 2.0]]) / 6.0  # w_0, w_1 at i = -1, 0, 1


def _diagonal(mesh: Mesh, face: int, v: int) -> Array:
    """The point diagonal to ``v`` in ``face``: the opposite vertex of a quad, else ``4 c - v - a - b``."""
    f = mesh.faces[face]
    i = f.index(v)
    P = mesh.vertices
    if len(f) == 4:
        return P[f[(i + 2) % 4]]
    a, b = f[(i + 1) % len(f)], f[i - 1]
    return 4.0 * P[list(f)].mean(axis=0) - P[v] - P[a] - P[b]


def _corner_block(mesh: Mesh, face: int, v: int) -> Array:
    """``b[α, β]`` (2, 2, 3) of the patch of ``face`` at its corner ``v`` (module notes)."""
    fan = mesh.vertex_faces(v)
    ring = mesh.one_ring(v)
    k0 = fan.index(face)
    P = mesh.vertices
    r = [ring[(k0 + s) % 4] for s in range(4)]      # w, u, opposite w, opposite u
    fs = [fan[(k0 + s) % 4] for s in range(4)]      # F, across (v, u), diagonal, across (v, w)
    G = np.empty((3, 3, 3))                         # G[i + 1, j + 1]: i along v -> w, j along v -> u
    G[1, 1] = P[v]
    G[2, 1], G[1, 2], G[0, 1], G[1, 0] = P[r[0]], P[r[1]], P[r[2]], P[r[3]]
    G[2, 2] = _diagonal(mesh, fs[0], v)
    G[0, 2] = _diagonal(mesh, fs[1], v)
    G[0, 0] = _diagonal(mesh, fs[2], v)
    G[2, 0] = _diagonal(mesh, fs[3], v)
    return np.einsum("ai,bj,ijd->abd", _W, _W, G)


def _quad_patch(blocks: list[Array]) -> SPatch:
    """The bicubic Bézier net of a quadrilateral face from its four corner blocks, as a depth-3 S-patch."""
    net = np.empty((4, 4, 3))
    # corner k at net corner (0,0), (3,0), (3,3), (0,3); its side direction and inward direction
    for (a0, b0), (sa, sb), (ia, ib), blk in zip(
        ((0, 0), (3, 0), (3, 3), (0, 3)), ((1, 0), (0, 1), (-1, 0), (0, -1)), ((0, 1), (-1, 0), (0, -1), (1, 0)), blocks
    ):
        for al in (0, 1):
            for be in (0, 1):
                net[a0 + al * sa + be * ia, b0 + al * sb + be * ib] = blk[al, be]
    idx = spatch_indices(4, 3)
    return SPatch._trusted(4, 3, net[idx[:, 1] + idx[:, 2], idx[:, 2] + idx[:, 3]])


def _face_patch(mesh: Mesh, face: int) -> tuple[SPatch, float]:
    f = mesh.faces[face]
    n = len(f)
    blocks = [_corner_block(mesh, face, v) for v in f]
    if n == 4:
        return _quad_patch(blocks), 0.0
    rows0 = np.empty((n, 4, 3))
    rows1 = np.empty((n, 4, 3))
    for k in range(n):
        b, e = blocks[k], blocks[(k + 1) % n]
        rows0[k] = (b[0, 0], b[1, 0], e[0, 1], e[0, 0])
        rows1[k] = (b[0, 1], b[1, 1], e[1, 1], e[1, 0])
    pts = np.concatenate([blk.reshape(-1, 3) for blk in blocks])
    scale = float(np.ptp(pts, axis=0).max()) or 1.0
    return ribbon_patch(rows0, rows1, scale, name=f"generalized_bicubic: face {face}")


def _needs_refinement(mesh: Mesh) -> int:
    """An interior vertex of valence != 4, or -1."""
    for v in range(mesh.n_vertices):
        if mesh.vertex_faces(v) and not mesh.is_boundary_vertex(v) and mesh.valence(v) != 4:
            return v
    return -1


def generalized_bicubic(mesh: Mesh, *, refine: str = "auto") -> GeneralizedSurface:
    """The generalized bicubic B-spline surface of a control mesh (course §8-7; module notes).

    Parameters
    ----------
    mesh : Mesh
        Control mesh of any topology (oriented 2-manifold, possibly with boundary).
    refine : {"auto", "always", "never"}
        One Doo–Sabin step first: ``"auto"`` when some interior vertex has a valence other than 4
        (the scheme needs valence 4; faces may have any number of sides), ``"always"``, or
        ``"never"`` (then such a vertex raises).

    Returns
    -------
    GeneralizedSurface
        ``scheme == "bicubic"``: one S-patch per face whose vertices are all interior, in face order
        (:attr:`GeneralizedSurface.elements`); depth 3 (= the bicubic B-spline patch where the
        neighbourhood is a regular grid) for quadrilaterals, :data:`BICUBIC_DEPTH` otherwise; G1
        everywhere, C1 between quadrilateral patches.

    Raises
    ------
    InvalidGeometryError
        ``mesh`` not a Mesh, ``refine`` unknown, an interior vertex of valence != 4 with
        ``refine="never"``, a face with more than ``tolerances.MAX_VALENCE`` sides,
        or no face with all vertices interior.
    """
    check_scheme_args(mesh, refine)
    bad = _needs_refinement(mesh)
    if refine == "always" or (refine == "auto" and bad >= 0):
        mesh = doo_sabin(mesh)
    elif bad >= 0:
        raise InvalidGeometryError(
            f"mesh: the generalized bicubic scheme needs interior vertices of valence 4; vertex {bad} has "
            f"valence {mesh.valence(bad)} (use refine='auto' for a Doo-Sabin step)"
        )
    patches, faces, worst = [], [], 0.0
    for fi, f in enumerate(mesh.faces):
        if any(mesh.is_boundary_vertex(v) for v in f):
            continue
        if len(f) > tolerances.MAX_VALENCE:
            raise InvalidGeometryError(
                f"mesh: face {fi} has {len(f)} sides, more than MAX_VALENCE = {tolerances.MAX_VALENCE}")
        patch, cons = _face_patch(mesh, fi)
        patches.append(patch)
        faces.append(fi)
        worst = max(worst, cons)
    if not patches:
        raise InvalidGeometryError("mesh: no face with all its vertices interior, so the surface has no patch")
    return GeneralizedSurface(mesh, tuple(patches), (), worst, scheme="bicubic", elements=tuple(faces))
