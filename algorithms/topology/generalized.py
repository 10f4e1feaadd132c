"""Generalized biquadratic B-spline surfaces of arbitrary topology from S-patches (course §8-6, 8-7).

Loop & DeRose 1990, "Generating C1 surfaces of arbitrary topology using S-patches" (SIGGRAPH '90),
as outlined in the course (§8-6 generalized B-spline schemes, §8-7 generalized biquadratic scheme):
a control mesh of any topology (vertices of any valence, faces of any side count) gives one
``n``-sided S-patch per mesh vertex of valence ``n``; where the mesh is a regular grid the patches
*are* the biquadratic B-spline patches that have the mesh as control net, and everywhere the
patches meet with tangent-plane (G1) continuity.

The construction, derived here step by step
-------------------------------------------
**Quadrilateral mesh.** Patches correspond to vertices, patch corners to faces. The scheme needs
every face to be a quadrilateral (course §8-7): a mesh with other faces is first refined by one
Catmull–Clark step (:func:`occsurf.algorithms.topology.mesh.catmull_clark`), after which every face is a quad and the
irregularities are vertices of valence ``n != 4``. Only interior vertices get a patch (as a
tensor-product B-spline has no span for its boundary control points).

**The biquadratic Bézier net of a vertex** (the Sabin net of course §8-5). Around vertex ``v`` of
valence ``n`` take its faces ``F_k = (v, e_k, f_k, e_{k+1})`` counter-clockwise
(:meth:`Mesh.vertex_faces`). Converting a uniform biquadratic B-spline patch to Bézier form with the
matrix ``[[1/2, 1/2, 0], [0, 1, 0], [0, 1/2, 1/2]]`` in each direction gives the Bézier net

* corners ``c_k`` = centroid of face ``F_k``;
* boundary mid-points ``m_k = (v + e_k) / 2`` (edge midpoints);
* centre ``v``.

Side ``k`` of the patch (domain vertex ``k`` to ``k + 1``) crosses mesh edge ``(v, e_{k+1})``; its
boundary is the quadratic Bézier curve ``(c_k, m_{k+1}, c_{k+1})``, and the two Bézier rows
``row0 = (c_k, m_{k+1}, c_{k+1})`` and ``row1 = (m_k, v, m_{k+2})`` define the cross-boundary
derivative ``D(t) = 2 Σ_j B²_j(t) (row1_j - row0_j)``. The patch of the neighbour ``e_{k+1}`` has
the mirrored ``row1' = 2 row0 - row1`` (each ``c`` is the midpoint of two edge midpoints of its
quad, each ``m`` the midpoint of ``v`` and ``e_{k+1}``), so the two strips join C1: **a patch that
reproduces, along each side, the boundary of its strip and a tangent plane spanned by ``T(t)`` and
``D(t)`` meets every neighbour G1.** At a corner the tangent plane is that of the quad's Varignon
parallelogram, common to the four patches there.

**Valence 4.** With Wachspress coordinates on the square (bilinear), the biquadratic Bézier patch
is exactly the 4-sided S-patch of depth 2 with ``P_{2e_k} = c_k``, ``P_{e_k+e_{k+1}} = m_{k+1}`` and
``P_{e_0+e_2} = P_{e_1+e_3} = v`` (``λ_0 λ_2 = λ_1 λ_3``; course §8-2, "n = 4 gives tensor products").
So regular regions are the tensor-product biquadratic B-spline, C1 between patches.

**Valence n != 4: the affine-image rule.** Write the S-patch of depth ``d`` near side ``k``. Let
``α`` run over the ``d`` multi-indices with ``|α| = d - 1`` supported on ``{k, k+1}`` and suppose that
for each the ``n`` control points ``P_{α + e_j}`` are the images ``L_α(p_j)`` of the domain vertices
under one affine map ``L_α``. Wachspress coordinates reproduce linear functions
(``Σ_j λ_j p_j = x``), so the first derivative of the patch at the side point ``x(t)`` in any domain
direction ``w`` is the *polynomial* ``d Σ_a B^{d-1}_a(t) Lin(L_a) w`` (Loop & DeRose 1990 §4: this is
how an S-patch is made to carry prescribed cross-boundary data). ``L_a`` is fixed by the boundary
(``L_a(p_k) = b_a``, ``L_a(p_{k+1}) = b_{a+1}``, the degree-``d`` boundary points) and one vector
``N_a = Lin(L_a) ν``, ``ν`` the inward normal of the side scaled to the side length; the first map
of a side is the last map of the previous side (the corner map), and consecutive sides share one
"twist" control point ``P_{(d-2)e_k + e_{k-1} + e_{k+1}}``.

**The G1 condition.** Require, in the domain direction ``ν``,

.. math::

    d \\sum_a B^{d-1}_a(t) N_a = ρ(t) D(t) + λ(t) T(t), \\qquad
    ρ(t) = \\frac{1 + 2 \\cos θ\\, t (1 - t)}{\\sin θ}, \\quad λ(t) = \\cot θ\\, (2 t - 1),

with ``θ = π (n - 2) / n`` the interior angle of the domain polygon and ``T`` the boundary
derivative. Then the patch's tangent plane along the side is ``span(T, D)`` (``ρ > 0``): G1 to the
strip, hence to the neighbour. ``ρ`` and ``λ`` are the lowest-degree choice that is consistent at
both corners: at ``t = 0`` the derivative along the adjacent domain side
``p_{k-1} - p_k = cos θ u + sin θ ν`` becomes ``D(0) = 2 (m_k - c_k)``, the tangent of the previous
side, so the corner map is one affine map; and the mixed derivative (the twist point) computed from
side ``k`` and from side ``k - 1`` agree, which needs ``sin θ ρ'(0) = sin θ λ'(1)`` and
``sin θ λ'(0) = -sin θ ρ'(1)``. The right-hand side has degree 4, so ``d = 5``
(:data:`BIQUADRATIC_DEPTH`). Control points fixed twice (corner maps, twist points) are computed
from both sides; their agreement is measured (:attr:`GeneralizedSurface.consistency`).

**Free control points.** Indices with at most ``d - 2`` units on every pair of adjacent sides do not
touch the boundary data. They are set by discrete harmonic averaging over the index lattice (each
the mean of its neighbours ``I - e_i + e_j``), a sparse linear solve; none exist for ``n = 3``.

Comparison with the published construction
------------------------------------------
The text of Loop & DeRose 1990 was not available to us. Salvi 2020 ("G1 hole filling with S-patches
made easy", arXiv:2002.11109, §2-3) summarises it: from a Sabin net of boundary degree ``d`` the
S-patch is raised to depth ``d + 3`` (here ``2 + 3 = 5``, as derived above) and each side carries
``d`` "panels" of control points that are affine images of the regular ``n``-gon (the maps
``L_α`` above), with closed-form panel points involving ``cos(2π/n)``. So the structure (depth,
affine panels, twist compatibility) agrees with ours; not verified: that our ``ρ(t), λ(t)`` give
the same panel points as the paper's formula (both satisfy the same G1 and corner conditions, and
the lowest-degree choice need not be unique). Known difference: Loop & DeRose place the interior
control points only for depths up to 3 (Salvi), we use the discrete harmonic fill for all
(it changes the shape inside the patch, never the G1 joins).

The generalized bicubic scheme (§8-7, one patch per face after a Doo–Sabin step) is in
:mod:`occsurf.algorithms.topology.generalized_bicubic`; it builds its irregular patches with :func:`ribbon_patch`,
the side construction above written for boundary Bézier rows of any degree ``q`` (depth ``q + 3``).
"""

from __future__ import annotations

from dataclasses import dataclass
from math import comb

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import sparse
from scipy.sparse.linalg import spsolve

from .. import _validate as V
from .. import tolerances
from ..errors import InvalidGeometryError
from ..kernel.surface import BSplineSurface
from .mesh import Mesh, catmull_clark
from .spatch import SPatch, domain_vertices, spatch_indices

__all__ = [
    "GeneralizedSurface",
    "generalized_biquadratic",
    "biquadratic_patch",
    "ribbon_patch",
    "spatch_curvatures",
    "BIQUADRATIC_DEPTH",
]

Array = NDArray[np.float64]

#: Depth of the S-patch of an irregular vertex (valence != 4): the G1 cross-boundary condition
#: ``ρ D + λ T`` has degree 4 in the side parameter, so ``d - 1 = 4``. Regular vertices use depth 2.
BIQUADRATIC_DEPTH: int = 5

# The largest vertex valence and the consistency check of the control points fixed by two sides
# are tolerances.MAX_VALENCE and tolerances.GENERALIZED_CONSISTENCY_TOL, read at call time.


# ---------------------------------------------------------------------------- one vertex
def _vertex_net(mesh: Mesh, v: int) -> tuple[Array, Array, Array]:
    """Centre ``v``, edge midpoints ``m`` (n, 3) and face centroids ``c`` (n, 3) of vertex ``v``."""
    P = mesh.vertices
    fan = mesh.vertex_faces(v)
    ring = mesh.one_ring(v)
    m = (P[v] + P[list(ring)]) / 2.0
    c = np.array([P[list(mesh.faces[f])].mean(axis=0) for f in fan])
    return P[v], m, c


def _bernstein(deg: int, t: Array) -> Array:
    t = np.asarray(t, float)[..., None]
    i = np.arange(deg + 1)
    return np.array([comb(deg, k) for k in i]) * t**i * (1.0 - t) ** (deg - i)


def _elevate(b: Array, deg: int) -> Array:
    """Bézier points ``b`` (p+1, dim) raised to degree ``deg``."""
    p = b.shape[0] - 1
    while p < deg:
        nb = np.empty((p + 2, b.shape[1]))
        nb[0], nb[-1] = b[0], b[-1]
        i = np.arange(1, p + 1)[:, None]
        nb[1:-1] = (i / (p + 1)) * b[:-1] + (1 - i / (p + 1)) * b[1:]
        b, p = nb, p + 1
    return b


def biquadratic_patch(centre: ArrayLike, mids: ArrayLike, corners: ArrayLike) -> tuple[SPatch, float]:
    """The generalized biquadratic S-patch of one vertex from its Bézier net (module notes).

    Parameters
    ----------
    centre : array_like, shape (3,)
        The mesh vertex ``v``.
    mids : array_like, shape (n, 3)
        ``m_k = (v + e_k) / 2``, the midpoints of the edges at ``v`` counter-clockwise; ``m_{k+1}``
        is the middle Bézier point of side ``k``.
    corners : array_like, shape (n, 3)
        ``c_k``, the centroid of the quad face between edges ``k`` and ``k + 1``.

    Returns
    -------
    patch : SPatch
        Depth 2 for ``n = 4`` (the biquadratic Bézier patch exactly), depth
        :data:`BIQUADRATIC_DEPTH` otherwise.
    consistency : float
        Largest disagreement between two computations of one control point (0 for ``n = 4``).
    """
    v = V.as_finite_array(centre, "centre")
    m = V.as_finite_array(mids, "mids")
    c = V.as_finite_array(corners, "corners")
    n = m.shape[0] if m.ndim == 2 else 0
    max_valence = tolerances.MAX_VALENCE
    if n > max_valence:
        raise InvalidGeometryError(f"mids: valence {n} exceeds MAX_VALENCE = {max_valence}")
    if m.ndim != 2 or n < 3 or c.shape != m.shape or v.shape != m.shape[1:]:
        raise InvalidGeometryError(f"mids, corners: expected (n, dim) arrays with n >= 3 and a centre (dim,); "
                                   f"got {m.shape}, {c.shape}, {v.shape}")
    E = np.eye(n, dtype=int)
    if n == 4:
        pts: dict[tuple[int, ...], Array] = {}
        for k in range(4):
            pts[tuple(2 * E[k])] = c[k]
            pts[tuple(E[k] + E[(k + 1) % 4])] = m[(k + 1) % 4]
        pts[(1, 0, 1, 0)] = v
        pts[(0, 1, 0, 1)] = v
        return SPatch(4, 2, pts), 0.0
    rows0 = np.array([[c[k], m[(k + 1) % n], c[(k + 1) % n]] for k in range(n)])
    rows1 = np.array([[m[k], v, m[(k + 2) % n]] for k in range(n)])
    scale = float(np.ptp(np.vstack((c, m, v[None])), axis=0).max()) or 1.0
    return ribbon_patch(rows0, rows1, scale, name="biquadratic_patch")


def ribbon_patch(rows0: ArrayLike, rows1: ArrayLike, scale: float = 1.0, *, name: str = "ribbon_patch") -> tuple[SPatch, float]:
    """The ``n``-sided S-patch of depth ``q + 3`` that carries prescribed G1 ribbons (module notes).

    Side ``k`` (domain vertex ``k`` to ``k + 1``) gets the boundary Bézier curve ``rows0[k]`` of degree
    ``q`` and the tangent plane spanned by its derivative ``T`` and the cross derivative
    ``D(t) = q Σ_j B^q_j(t) (rows1[k, j] - rows0[k, j])``: the affine-image rule with
    ``d Σ_a B^{d-1}_a N_a = ρ D + λ T`` (degree ``q + 2``, hence ``d = q + 3``).

    Parameters
    ----------
    rows0, rows1 : array_like, shape (n, q + 1, dim)
        The first two Bézier rows of each side's strip, ``n >= 3``, ``n != 4`` meaningful (a 4-sided
        tensor-product net is represented exactly by a depth-``q`` S-patch instead). The rows of
        consecutive sides must share their corner blocks as the rows of a Bézier net do:
        ``rows0[k, q] = rows0[k + 1, 0]``, ``rows0[k, q - 1] = rows1[k + 1, 0]``,
        ``rows1[k, q] = rows0[k + 1, 1]`` and ``rows1[k, q - 1] = rows1[k + 1, 1]`` (corner
        point, tangents and twist; the biquadratic and bicubic nets satisfy them by construction).
    scale : float
        Size of the data, for the relative ``tolerances.GENERALIZED_CONSISTENCY_TOL`` check.

    Returns
    -------
    patch : SPatch
        Depth ``q + 3``; free interior control points by discrete harmonic averaging.
    consistency : float
        Largest relative disagreement between two computations of one control point.

    Raises
    ------
    InvalidGeometryError
        Control points fixed by two sides disagree by more than
        ``tolerances.GENERALIZED_CONSISTENCY_TOL``.
    """
    R0 = np.asarray(rows0, float)
    R1 = np.asarray(rows1, float)
    n, q1, dim = R0.shape
    q = q1 - 1
    d = q + 3
    E = np.eye(n, dtype=int)
    theta = np.pi * (n - 2) / n
    sin, cos = np.sin(theta), np.cos(theta)
    p = domain_vertices(n)
    cand: dict[tuple[int, ...], list[Array]] = {}
    tc = (np.arange(d) + 0.5) / d  # collocation parameters for the degree d-1 Bernstein fit
    Bc = _bernstein(d - 1, tc)
    t = tc[:, None]
    rho = (1.0 + 2.0 * cos * t * (1.0 - t)) / sin
    lam = (cos / sin) * (2.0 * t - 1.0)
    for k in range(n):
        k1 = (k + 1) % n
        row0, row1 = R0[k], R1[k]
        b = _elevate(row0, d)
        D = q * (_bernstein(q, tc) @ (row1 - row0))
        T = q * (_bernstein(q - 1, tc) @ (row0[1:] - row0[:-1]))
        N = np.linalg.solve(Bc, rho * D + lam * T) / d  # (d, dim)
        u = p[k1] - p[k]
        nu = np.array([-u[1], u[0]])  # inward (the polygon is counter-clockwise), |nu| = |u|
        sr = np.linalg.solve(np.column_stack((u, nu)), (p - p[k]).T).T  # p_j - p_k = s u + r nu
        for a in range(d):
            alpha = (d - 1 - a) * E[k] + a * E[k1]
            img = b[a] + sr[:, :1] * (b[a + 1] - b[a]) + sr[:, 1:] * N[a]
            for j in range(n):
                cand.setdefault(tuple(alpha + E[j]), []).append(img[j])
    idx = spatch_indices(n, d)
    pos = {tuple(int(x) for x in row): i for i, row in enumerate(idx)}
    P = np.zeros((idx.shape[0], dim))
    fixed = np.zeros(idx.shape[0], dtype=bool)
    worst = 0.0
    for key, vals in cand.items():
        arr = np.array(vals)
        P[pos[key]] = arr.mean(axis=0)
        fixed[pos[key]] = True
        worst = max(worst, float(np.max(np.abs(arr - arr[0]))) / scale)
    consistency_tol = tolerances.GENERALIZED_CONSISTENCY_TOL
    if worst > consistency_tol:
        raise InvalidGeometryError(
            f"{name}: control points fixed by two sides disagree by {worst:.3g} (relative), "
            f"more than GENERALIZED_CONSISTENCY_TOL = {consistency_tol}; the net is degenerate"
        )
    free = np.flatnonzero(~fixed)
    if free.size:
        P[free] = _harmonic_fill(idx, pos, P, free)
    return SPatch._trusted(n, d, P), worst


def _harmonic_fill(idx: NDArray[np.intp], pos: dict[tuple[int, ...], int], P: Array, free: NDArray[np.intp]) -> Array:
    """Free control points as the discrete harmonic extension of the fixed ones: each free point is
    the mean of its lattice neighbours ``I - e_i + e_j`` (``i != j``)."""
    m, n = idx.shape
    rows, cols = [], []
    for r in range(m):  # sparse: at most d (n - 1) neighbours per index (dense was O(m^2) memory)
        I = idx[r]
        for i in np.flatnonzero(I > 0):
            for j in range(n):
                if j != i:
                    J = I.copy()
                    J[i] -= 1
                    J[j] += 1
                    rows.append(r)
                    cols.append(pos[tuple(int(x) for x in J)])
    A = sparse.csr_matrix((np.ones(len(rows)), (rows, cols)), shape=(m, m))
    A = sparse.diags(1.0 / np.asarray(A.sum(axis=1)).ravel()) @ A
    fixed = np.setdiff1d(np.arange(m), free)
    lhs = sparse.identity(free.size, format="csc") - A[free][:, free].tocsc()
    rhs = A[free][:, fixed] @ P[fixed]
    return np.asarray(spsolve(lhs, rhs)).reshape(free.size, -1)


# ---------------------------------------------------------------------------- the surface
@dataclass(frozen=True, eq=False)
class GeneralizedSurface:
    """A generalized B-spline surface: S-patches joined G1 over a control mesh.

    Attributes
    ----------
    mesh : Mesh
        The control mesh the patches were built from (the input, or its Catmull–Clark refinement
        for the biquadratic scheme, its Doo–Sabin refinement for the bicubic one).
    patches : tuple of SPatch
        One per mesh element of :attr:`elements`.
    vertices : tuple of int
        Biquadratic scheme: the mesh vertex of each patch (empty for the bicubic scheme).
    consistency : float
        Largest relative disagreement between two computations of one control point.
    scheme : {"biquadratic", "bicubic"}
        Patches per interior vertex (:func:`generalized_biquadratic`) or per interior face
        (:func:`occsurf.algorithms.topology.generalized_bicubic.generalized_bicubic`).
    elements : tuple of int
        The mesh vertex (biquadratic) or face (bicubic) of each patch; side ``k`` of a face's patch
        runs along the face's edge from corner ``k`` to corner ``k + 1``.
    """

    mesh: Mesh
    patches: tuple[SPatch, ...]
    vertices: tuple[int, ...]
    consistency: float
    scheme: str = "biquadratic"
    elements: tuple[int, ...] = ()

    def __post_init__(self) -> None:
        if self.scheme == "biquadratic" and not self.elements:
            object.__setattr__(self, "elements", tuple(self.vertices))

    def __len__(self) -> int:
        return len(self.patches)

    def patch_of_vertex(self, v: int) -> int:
        """Index of the patch of mesh vertex ``v``, or -1 (boundary vertex)."""
        try:
            return self.vertices.index(int(v))
        except ValueError:
            return -1

    def evaluate(self, patch: int, points: ArrayLike) -> Array:
        """Points of patch ``patch`` at domain points ``(..., 2)`` of its regular n-gon: ``(..., 3)``."""
        return self.patches[self._patch(patch)].evaluate(points)

    def normal(self, patch: int, points: ArrayLike) -> Array:
        """Unit normals of patch ``patch`` at domain points ``(..., 2)``: ``(..., 3)``."""
        return self.patches[self._patch(patch)].normal(points)

    def _patch(self, i: object) -> int:
        if isinstance(i, bool) or not isinstance(i, (int, np.integer)) or not 0 <= int(i) < len(self.patches):
            raise InvalidGeometryError(f"patch: expected a patch index from 0 to {len(self.patches) - 1}, got {i!r}")
        return int(i)

    def shared_sides(self) -> list[tuple[int, int, int, int]]:
        """Pairs of patch sides that meet: ``(i, k, j, l)`` with side ``k`` of patch ``i`` equal to side
        ``l`` of patch ``j`` traversed backwards (parameter ``t`` on one is ``1 - t`` on the other);
        each pair once, ``i < j``."""
        out = []
        if self.scheme == "bicubic":
            patch_of = {f: i for i, f in enumerate(self.elements)}
            for i, fi in enumerate(self.elements):
                f = self.mesh.faces[fi]
                for k in range(len(f)):
                    g = self.mesh.face_of_edge(f[(k + 1) % len(f)], f[k])
                    j = patch_of.get(g, -1)
                    if j > i:
                        out.append((i, k, j, self.mesh.faces[g].index(f[(k + 1) % len(f)])))
            return out
        for i, v in enumerate(self.vertices):
            ring = self.mesh.one_ring(v)
            n = len(ring)
            for k in range(n):
                w = ring[(k + 1) % n]
                j = self.patch_of_vertex(w)
                if j > i:
                    ring_w = self.mesh.one_ring(w)
                    l_ = (ring_w.index(v) - 1) % len(ring_w)
                    out.append((i, k, j, l_))
        return out

    def continuity(self, samples: int = 65) -> tuple[float, float]:
        """Largest G0 gap and normal angle (radians) over all shared sides, measured at ``samples``
        points per side (course §9, quality assessment).

        Returns
        -------
        (gap, angle) : (float, float)
        """
        # per sample of a side: its domain points, points, derivatives and normals on both patches
        t = np.linspace(0.0, 1.0, V.check_count(samples, "samples", 64, minimum=2))
        gap = ang = 0.0
        for i, k, j, l_ in self.shared_sides():
            a, b = self.patches[i], self.patches[j]
            xa, xb = a.edge_points(k, t), b.edge_points(l_, 1.0 - t)
            gap = max(gap, float(np.max(np.linalg.norm(a.evaluate(xa) - b.evaluate(xb), axis=-1))))
            na, nb = a.normal(xa), b.normal(xb)  # angle by atan2: arccos loses half the digits near 0
            sin_ = np.linalg.norm(np.cross(na, nb), axis=-1)
            ang = max(ang, float(np.max(np.arctan2(sin_, np.einsum("...i,...i->...", na, nb)))))
        return gap, ang

    def to_surfaces(self, tol: float | None = None) -> list[list[BSplineSurface]]:
        """Each patch as its ``n`` rational tensor-product pieces (:func:`occsurf.algorithms.topology.spatch_convert.spatch_to_surfaces`)."""
        from .spatch_convert import spatch_to_surfaces

        return [spatch_to_surfaces(p, tol=tol) for p in self.patches]


def check_scheme_args(mesh: object, refine: object) -> None:
    """The arguments every generalized scheme takes: a :class:`Mesh` and a refinement policy."""
    if not isinstance(mesh, Mesh):
        raise InvalidGeometryError(f"mesh: expected a Mesh, got {type(mesh).__name__}")
    if refine not in ("auto", "always", "never"):
        raise InvalidGeometryError(f"refine: expected 'auto', 'always' or 'never', got {refine!r}")


def generalized_biquadratic(mesh: Mesh, *, refine: str = "auto") -> GeneralizedSurface:
    """The generalized biquadratic B-spline surface of a control mesh (course §8-7; Loop & DeRose 1990).

    Parameters
    ----------
    mesh : Mesh
        Control mesh of any topology (oriented 2-manifold, possibly with boundary).
    refine : {"auto", "always", "never"}
        One Catmull–Clark step first: ``"auto"`` when some face is not a quadrilateral (the scheme
        needs quads), ``"always"``, or ``"never"`` (then non-quad faces raise).

    Returns
    -------
    GeneralizedSurface
        One S-patch per interior vertex, in vertex order: depth 2 (= the biquadratic B-spline patch)
        at valence 4, depth :data:`BIQUADRATIC_DEPTH` elsewhere; G1 everywhere, C1 between
        valence-4 patches.

    Raises
    ------
    InvalidGeometryError
        If ``mesh`` is not a Mesh, ``refine`` is unknown, non-quad faces remain with
        ``refine="never"``, or the mesh has no interior vertex.
    """
    check_scheme_args(mesh, refine)
    if refine == "always" or (refine == "auto" and not mesh.is_quad):
        mesh = catmull_clark(mesh)
    elif not mesh.is_quad:
        bad = next(i for i, f in enumerate(mesh.faces) if len(f) != 4)
        raise InvalidGeometryError(
            f"mesh: the generalized biquadratic scheme needs quadrilateral faces; face {bad} has "
            f"{len(mesh.faces[bad])} sides (use refine='auto' for a Catmull-Clark step)"
        )
    patches, verts, worst = [], [], 0.0
    for v in range(mesh.n_vertices):
        if mesh.is_boundary_vertex(v) or not mesh.vertex_faces(v):
            continue
        if mesh.valence(v) > tolerances.MAX_VALENCE:
            raise InvalidGeometryError(
                f"mesh: vertex {v} has valence {mesh.valence(v)}, more than MAX_VALENCE = {tolerances.MAX_VALENCE} "
                f"(its S-patch would have C({mesh.valence(v) + 4}, 5) control points)"
            )
        centre, mids, corners = _vertex_net(mesh, v)
        patch, cons = biquadratic_patch(centre, mids, corners)
        patches.append(patch)
        verts.append(v)
        worst = max(worst, cons)
    if not patches:
        raise InvalidGeometryError("mesh: no interior vertex, so the surface has no patch")
    return GeneralizedSurface(mesh, tuple(patches), tuple(verts), worst)


# ---------------------------------------------------------------------------- curvature
def spatch_curvatures(patch: SPatch, points: ArrayLike) -> tuple[Array, Array, Array]:
    """Gaussian and mean curvature and unit normal of a 3-D S-patch (course §6-12), from its exact
    first and second derivatives (:meth:`SPatch.derivatives`).

    Returns
    -------
    gaussian, mean : ndarray, shape (...)
        ``K = (LN - M²) / (EG - F²)``, ``H = (EN - 2FM + GL) / (2 (EG - F²))``, signed with the normal
        ``S_x × S_y`` (outward sphere: ``H < 0``, as OCC's GeomLProp).
    normal : ndarray, shape (..., 3)
    """
    D = patch.derivatives(points, 2)
    Su, Sv = D[..., 1, 0, :], D[..., 0, 1, :]
    Suu, Suv, Svv = D[..., 2, 0, :], D[..., 1, 1, :], D[..., 0, 2, :]
    nrm = np.cross(Su, Sv)
    nrm = nrm / np.linalg.norm(nrm, axis=-1, keepdims=True)
    E, F, G = (np.einsum("...i,...i->...", a, b) for a, b in ((Su, Su), (Su, Sv), (Sv, Sv)))
    L, M, N = (np.einsum("...i,...i->...", a, nrm) for a in (Suu, Suv, Svv))
    det = E * G - F * F
    return (L * N - M * M) / det, (E * N - 2 * F * M + G * L) / (2 * det), nrm
