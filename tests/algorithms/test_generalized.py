"""Generalized biquadratic B-spline surfaces from S-patches (occsurf.algorithms.topology.generalized; course §8-6, 8-7).

Oracles: the tensor-product biquadratic B-spline on regular grids (BSplineSurface, independent
code), curvature of that B-spline (occsurf.algorithms.geometry.surface_differential), the Bézier net's closed forms
(corners at face centroids, quadratic boundaries, Varignon corner planes). Invariants: G1 between
all neighbouring patches measured densely, C1 between regular ones, affine invariance.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from numpy.testing import assert_allclose

from occsurf.algorithms.errors import InvalidGeometryError
from occsurf.algorithms.geometry.surface_differential import surface_curvatures
from occsurf.algorithms.kernel.surface import BSplineSurface
from occsurf.algorithms.topology.generalized import (
    BIQUADRATIC_DEPTH,
    GeneralizedSurface,
    biquadratic_patch,
    generalized_biquadratic,
    spatch_curvatures,
)
from occsurf.algorithms.topology.mesh import Mesh, catmull_clark, read_obj
from occsurf.algorithms.topology.spatch import domain_vertices
from tests.algorithms.strategies import test_settings

FIXTURES = Path(__file__).resolve().parents[1] / "fixtures" / "meshes"
SAMPLES = 101  # points per shared side for the continuity measurements

# Tolerances. The construction is exact: the patches' boundary and tangent planes equal those of
# the Bézier strips identically, so what is measured is round-off of evaluating depth-5 S-patches
# (Wachspress quotient + ~100-term Bernstein sums): measured G0 gaps <= 6e-15 and normal angles
# <= 2e-14 rad on unit-size meshes. The bounds leave ~100x room for other BLAS/CPU round-off.
G0_TOL = 1e-12   # absolute, meshes of size ~1..3
G1_TOL = 1e-11   # radians
EXACT_TOL = 1e-12  # identities evaluated two ways (measured <= 3e-15)


def grid(nu: int, nv: int, rng: np.random.Generator) -> tuple[Mesh, np.ndarray]:
    X, Y = np.meshgrid(np.arange(nu, dtype=float), np.arange(nv, dtype=float), indexing="ij")
    P = np.stack([X + 0.2 * rng.standard_normal(X.shape), Y + 0.2 * rng.standard_normal(X.shape),
                  rng.standard_normal(X.shape)], -1)
    vid = lambda i, j: i * nv + j  # noqa: E731
    F = [[vid(i, j), vid(i + 1, j), vid(i + 1, j + 1), vid(i, j + 1)] for i in range(nu - 1) for j in range(nv - 1)]
    return Mesh(P.reshape(-1, 3), F), P


def ngon_with_skirt(n: int, rng: np.random.Generator) -> Mesh:
    """An n-gon on top of a ring of n quads: after Catmull-Clark, an interior vertex of valence n
    (the n-gon's centre) and n of valence 3 (its corners)."""
    a = 2 * np.pi * np.arange(n) / n
    top = np.c_[np.cos(a), np.sin(a), np.full(n, 1.0)]
    low = np.c_[1.8 * np.cos(a), 1.8 * np.sin(a), np.zeros(n)]
    P = np.vstack((top, low)) + 0.1 * rng.standard_normal((2 * n, 3))
    F = [list(range(n))] + [[(i + 1) % n, i, n + i, n + (i + 1) % n] for i in range(n)]
    return Mesh(P, F)


def jittered_prism(seed: int) -> Mesh:
    """The pentagonal prism fixture with every vertex moved by 0.3 N(0, 1): an irregular mesh."""
    rng = np.random.default_rng(seed)
    m = read_obj(FIXTURES / "pentagonal_prism.obj")
    return m.with_vertices(m.vertices + 0.3 * rng.standard_normal(m.vertices.shape))


def assert_c1_joins(g, n_pairs: int) -> None:
    """``g`` has ``n_pairs`` shared sides and along each the two patches' cross-boundary
    derivatives are opposite (C1; both domains are the same regular polygon, so scales match)."""
    t = np.linspace(0, 1, SAMPLES)
    pairs = g.shared_sides()
    assert len(pairs) == n_pairs
    for i, k, j, l_ in pairs:
        da = g.patches[i].cross_boundary_derivative(k, t)
        db = g.patches[j].cross_boundary_derivative(l_, 1 - t)
        assert_allclose(da, -db, atol=EXACT_TOL * 10)


def assert_affine_invariant(build, seed: int) -> None:
    """``build(A m + b)`` has the poles ``A (build m) + b`` (every rule is an affine combination)."""
    rng = np.random.default_rng(seed)
    m = read_obj(FIXTURES / "pentagonal_prism.obj")
    A, b = rng.standard_normal((3, 3)) + 2 * np.eye(3), rng.standard_normal(3)
    g1 = build(m.with_vertices(m.vertices @ A.T + b))
    g2 = build(m)
    for p1, p2 in zip(g1.patches, g2.patches):
        assert_allclose(p1.control_points, p2.control_points @ A.T + b, atol=1e-12)


def grid_domain_map(m: Mesh, nv: int, v: int, uv: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Domain points of the patch of grid vertex v at bilinear (s, t), and the matching B-spline
    parameters: corner k of the patch is the centroid of fan face k, whose lower-left grid vertex
    (a, b) puts it at B-spline parameter (a + 2, b + 2) (knots 0, 1, 2, ...)."""
    s, t = uv[:, 0], uv[:, 1]
    lam = np.stack([(1 - s) * (1 - t), s * (1 - t), s * t, (1 - s) * t], -1)  # Wachspress of the square
    ab = np.array([divmod(min(m.faces[f]), nv) for f in m.vertex_faces(v)], float) + 2.0
    return lam @ domain_vertices(4), lam @ ab[:, 0], lam @ ab[:, 1]


# ---------------------------------------------------------------------------- regular grid
@test_settings(max_examples=10)
@given(nu=st.integers(3, 7), nv=st.integers(3, 7), seed=st.integers(0, 2**31 - 1))
def test_regular_grid_equals_tensor_product_biquadratic(nu, nv, seed):
    """On a regular grid the surface IS the uniform biquadratic B-spline with the mesh as control
    net (course §8-7): compared at 150 random points per patch."""
    rng = np.random.default_rng(seed)
    m, P = grid(nu, nv, rng)
    bs = BSplineSurface((2, 2), (np.arange(nu + 3.0), np.arange(nv + 3.0)), P)
    g = generalized_biquadratic(m)
    assert len(g) == (nu - 2) * (nv - 2)
    assert all(p.sides == 4 and p.depth == 2 for p in g.patches)
    for i, v in enumerate(g.vertices):
        x, u, w = grid_domain_map(m, nv, v, rng.random((150, 2)))
        assert_allclose(g.evaluate(i, x), bs.evaluate(u, w), atol=EXACT_TOL)


def test_regular_grid_curvature_matches_bspline():
    """spatch_curvatures (from SPatch second derivatives) against occsurf.algorithms.geometry.surface_differential on the
    same surface in the B-spline's parametrisation: curvature does not depend on it."""
    rng = np.random.default_rng(7)
    m, P = grid(5, 5, rng)
    bs = BSplineSurface((2, 2), (np.arange(8.0), np.arange(8.0)), P)
    g = generalized_biquadratic(m)
    for i, v in enumerate(g.vertices):
        x, u, w = grid_domain_map(m, 5, v, 0.05 + 0.9 * rng.random((40, 2)))
        K, H, N = spatch_curvatures(g.patches[i], x)
        ref = surface_curvatures(bs, u, w)
        # curvatures are ratios of O(1) quantities: relative round-off ~1e-14; scale ~1
        assert_allclose(K, ref.gaussian, rtol=1e-9, atol=1e-10)
        assert_allclose(H, ref.mean, rtol=1e-9, atol=1e-10)
        assert_allclose(N, ref.normal, atol=1e-10)


def test_regular_neighbours_are_c1():
    """Between two valence-4 patches the join is C1: the cross-boundary derivatives along the
    shared side are opposite (both domains are the same diamond, so the scales match)."""
    m, _ = grid(6, 5, np.random.default_rng(3))
    assert_c1_joins(generalized_biquadratic(m), 2 * 4 * 3 - 4 - 3)  # interior-vertex grid 4 x 3: edges between them


# ---------------------------------------------------------------------------- irregular meshes
def _assert_g1(g: GeneralizedSurface) -> tuple[float, float]:
    gap, ang = g.continuity(SAMPLES)
    assert gap < G0_TOL, gap
    assert ang < G1_TOL, ang
    assert g.consistency < EXACT_TOL
    return gap, ang


def test_cube():
    g = generalized_biquadratic(read_obj(FIXTURES / "cube.obj"))
    assert len(g) == 8 and all(p.sides == 3 and p.depth == BIQUADRATIC_DEPTH for p in g.patches)
    assert len(g.shared_sides()) == 12
    _assert_g1(g)
    # symmetry of the cube: every patch passes through the same distance from the centre at its
    # domain centre, and the corners are the face centres
    c = np.array([p.evaluate([0.0, 0.0]) for p in g.patches]) - 0.5
    r = np.linalg.norm(c, axis=1)
    assert_allclose(r, r[0], rtol=1e-13)
    corners = np.array([p.evaluate(domain_vertices(3)) for p in g.patches]).reshape(-1, 3)
    assert_allclose(np.sort(np.abs(corners - 0.5).max(axis=1)), 0.5, atol=1e-15)


def test_valence_3_and_5_prism():
    m = read_obj(FIXTURES / "pentagonal_prism.obj")
    g = generalized_biquadratic(m)  # one Catmull-Clark step (pentagons)
    sides = sorted({p.sides for p in g.patches})
    assert sides == [3, 4, 5]
    _assert_g1(g)


def test_genus_one_frame():
    m = read_obj(FIXTURES / "frame.obj")
    g = generalized_biquadratic(m, refine="never")
    assert len(g) == 32 and sorted({p.sides for p in g.patches}) == [3, 4, 5]
    assert len(g.shared_sides()) == m.n_edges  # closed: every mesh edge is a shared side
    _assert_g1(g)


@pytest.mark.parametrize("n", [3, 5, 6, 7, 8])
def test_valence_n_vertex(n):
    g = generalized_biquadratic(ngon_with_skirt(n, np.random.default_rng(n)))
    assert n in {p.sides for p in g.patches}
    _assert_g1(g)


@test_settings(max_examples=8)
@given(seed=st.integers(0, 2**31 - 1))
def test_g1_on_random_irregular_meshes(seed):
    """G1 holds for any vertex positions (not a property of symmetric input)."""
    _assert_g1(generalized_biquadratic(jittered_prism(seed)))


# ---------------------------------------------------------------------------- closed forms
def test_boundaries_corners_and_corner_planes():
    """Side k is the quadratic Bézier (c_k, m_{k+1}, c_{k+1}) degree-raised; the corner's tangent
    plane is the plane of the quad's Varignon parallelogram (edge midpoints)."""
    mesh = catmull_clark(read_obj(FIXTURES / "pentagonal_prism.obj"))
    g = generalized_biquadratic(mesh)
    t = np.linspace(0, 1, 33)
    B2 = np.stack([(1 - t) ** 2, 2 * t * (1 - t), t**2], -1)
    for i, v in enumerate(g.vertices):
        p, n = g.patches[i], g.patches[i].sides
        fan, ring = mesh.vertex_faces(v), mesh.one_ring(v)
        c = np.array([mesh.vertices[list(mesh.faces[f])].mean(0) for f in fan])
        mids = (mesh.vertices[v] + mesh.vertices[list(ring)]) / 2
        for k in range(n):
            ref = B2 @ np.array([c[k], mids[(k + 1) % n], c[(k + 1) % n]])
            assert_allclose(p.boundary_curve(k).evaluate(t), ref, atol=EXACT_TOL)
            q = mesh.vertices[list(mesh.faces[fan[k]])]
            e = (q + np.roll(q, -1, axis=0)) / 2
            nrm = np.cross(e[2] - e[0], e[3] - e[1])
            nrm /= np.linalg.norm(nrm)
            assert abs(np.dot(p.normal(domain_vertices(n)[k]), nrm)) == pytest.approx(1.0, abs=1e-13)


@test_settings(max_examples=6)
@given(seed=st.integers(0, 2**31 - 1))
def test_affine_invariance(seed):
    """Every rule is an affine combination of mesh points: building from A m + b equals A (build m) + b."""
    assert_affine_invariant(generalized_biquadratic, seed)


def test_open_mesh_has_patches_only_at_interior_vertices():
    m, _ = grid(4, 4, np.random.default_rng(0))
    g = generalized_biquadratic(m)
    assert sorted(g.vertices) == [5, 6, 9, 10]
    assert g.patch_of_vertex(0) == -1 and g.patch_of_vertex(5) >= 0


def test_biquadratic_patch_valence_4_is_the_bezier_patch():
    rng = np.random.default_rng(2)
    v, mids, corners = rng.standard_normal(3), rng.standard_normal((4, 3)), rng.standard_normal((4, 3))
    p, cons = biquadratic_patch(v, mids, corners)
    assert (p.sides, p.depth, cons) == (4, 2, 0.0)
    # centre of the diamond = (s, t) = (1/2, 1/2): the biquadratic Bezier value there
    ref = (corners.sum(0) + 2 * mids.sum(0) + 4 * v) / 16
    assert_allclose(p.evaluate([0.0, 0.0]), ref, atol=1e-15)


# ---------------------------------------------------------------------------- errors
def test_errors():
    quad = Mesh([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], [[0, 1, 2, 3]])
    with pytest.raises(InvalidGeometryError, match="no interior vertex"):
        generalized_biquadratic(quad)
    with pytest.raises(InvalidGeometryError, match="mesh: expected a Mesh"):
        generalized_biquadratic("cube")
    with pytest.raises(InvalidGeometryError, match="refine"):
        generalized_biquadratic(quad, refine="sometimes")
    with pytest.raises(InvalidGeometryError, match="face 0 has 5 sides"):
        generalized_biquadratic(read_obj(FIXTURES / "pentagonal_prism.obj"), refine="never")
    g = generalized_biquadratic(read_obj(FIXTURES / "cube.obj"))
    with pytest.raises(InvalidGeometryError, match="patch: expected"):
        g.evaluate(8, [0.0, 0.0])
    with pytest.raises(InvalidGeometryError, match="mids, corners"):
        biquadratic_patch(np.zeros(3), np.zeros((2, 3)), np.zeros((2, 3)))


def test_non_finite_net_and_too_high_valence():
    """Review: a NaN in the vertex net used to pass the consistency check (NaN > tol is False) and
    return a NaN patch; a valence beyond MAX_VALENCE used to build a dense C(n+4, 5)^2 matrix
    (8 GB at n = 16) before failing."""
    from occsurf.algorithms import tolerances

    MAX_VALENCE = tolerances.MAX_VALENCE

    n = 5
    rng = np.random.default_rng(0)
    v, m, c = np.zeros(3), rng.normal(size=(n, 3)), rng.normal(size=(n, 3))
    for arr in (m, c):
        bad = arr.copy()
        bad[2, 1] = np.nan
        args = (v, bad, c) if arr is m else (v, m, bad)
        with pytest.raises(InvalidGeometryError, match="finite"):
            biquadratic_patch(*args)
    k = MAX_VALENCE + 1
    a = 2 * np.pi * np.arange(k) / k
    fan = Mesh(np.vstack(([0.0, 0.0, 0.0], np.column_stack((np.cos(a), np.sin(a), np.zeros(k))))),
               [[0, 1 + i, 1 + (i + 1) % k] for i in range(k)])
    with pytest.raises(InvalidGeometryError, match=f"vertex 0 has valence {k}"):
        generalized_biquadratic(fan, refine="never" if fan.is_quad else "auto")


def test_generalized_tolerances_are_read_at_call_time():
    """MAX_VALENCE and GENERALIZED_CONSISTENCY_TOL come from occsurf.algorithms.tolerances at
    call time (a zero consistency tolerance refuses even round-off)."""
    from occsurf.algorithms import tolerances

    rng = np.random.default_rng(4)
    v, m, c = np.zeros(3), rng.normal(size=(5, 3)), rng.normal(size=(5, 3))
    with tolerances.override(MAX_VALENCE=4):
        with pytest.raises(InvalidGeometryError, match=r"mids: valence 5 exceeds MAX_VALENCE = 4"):
            biquadratic_patch(v, m, c)
        with pytest.raises(InvalidGeometryError, match=r"valence 5, more than MAX_VALENCE = 4"):
            generalized_biquadratic(catmull_clark(ngon_with_skirt(5, rng)), refine="never")
    with tolerances.override(GENERALIZED_CONSISTENCY_TOL=0.0):
        with pytest.raises(InvalidGeometryError, match="more than GENERALIZED_CONSISTENCY_TOL = 0.0"):
            biquadratic_patch(v, m, c)
    assert biquadratic_patch(v, m, c)[0].sides == 5
