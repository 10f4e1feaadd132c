"""Generalized bicubic B-spline surfaces (occsurf.algorithms.topology.generalized_bicubic; course §8-7) and the
Doo–Sabin step that prepares their meshes (occsurf.algorithms.topology.mesh.doo_sabin).

Oracles: the uniform bicubic B-spline (BSplineSurface, independent code) on regular grids, and its
Bézier corner rules. Invariants: G1 between all neighbouring patches measured densely, C1 between
quadrilateral patches, twist consistency, affine invariance, Doo–Sabin valence and face counts.

Tolerances. The construction is exact (patch boundaries and tangent planes equal the shared Bézier
strips identically), so what is measured is round-off of evaluating depth-6 S-patches: measured
G0 gaps <= 6e-15 and normal angles <= 2.9e-14 rad on the unit-size fixtures, twist consistency
<= 2e-15. The bounds leave ~100x room for other BLAS/CPU round-off.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from numpy.testing import assert_allclose

from occsurf.algorithms.errors import InvalidGeometryError
from occsurf.algorithms.kernel.surface import BSplineSurface
from occsurf.algorithms.topology.generalized_bicubic import BICUBIC_DEPTH, generalized_bicubic
from occsurf.algorithms.topology.mesh import Mesh, doo_sabin, read_obj
from occsurf.algorithms.topology.spatch import domain_vertices
from tests.algorithms.strategies import test_settings
from tests.algorithms.test_generalized import (
    _assert_g1,
    assert_affine_invariant,
    assert_c1_joins,
    grid,
    jittered_prism,
    ngon_with_skirt,
)

FIXTURES = Path(__file__).resolve().parents[1] / "fixtures" / "meshes"
EXACT_TOL = 1e-12
# G1 is measured by test_generalized._assert_g1: 101 samples per shared side, G0 < 1e-12 absolute
# (meshes of size ~1..3), normal angles < 1e-11 rad, twist consistency < 1e-12.


# ---------------------------------------------------------------------------- Doo-Sabin
@pytest.mark.parametrize("name", ["cube", "pentagonal_prism", "frame"])
def test_doo_sabin_makes_every_vertex_valence_4(name):
    m = read_obj(FIXTURES / f"{name}.obj")
    r = doo_sabin(m)
    assert {r.valence(v) for v in range(r.n_vertices)} == {4}
    # one face per old face, edge and vertex; corners become vertices; topology kept
    assert r.n_faces == m.n_faces + m.n_edges + m.n_vertices
    assert r.n_vertices == sum(len(f) for f in m.faces)
    assert r.euler_characteristic == m.euler_characteristic and r.is_closed
    assert sorted(len(f) for f in r.faces[: m.n_faces]) == sorted(len(f) for f in m.faces)


def test_doo_sabin_on_a_grid_is_the_biquadratic_rule():
    m, P = grid(4, 4, np.random.default_rng(1))
    r = doo_sabin(m)
    f = m.faces[4]  # the middle face, corner 0
    x = P.reshape(-1, 3)[list(f)]
    assert_allclose(r.vertices[4 * 4], (9 * x[0] + 3 * x[1] + x[2] + 3 * x[3]) / 16, atol=1e-15)
    assert r.n_faces == 9 + 12 + 4  # faces, interior edges, interior vertices


# ---------------------------------------------------------------------------- regular grid
def _grid_domain_map(face: tuple[int, ...], nv: int, uv: np.ndarray):
    """Domain points of the patch of grid face ``face`` at bilinear (s, t), and the B-spline
    parameters: corner k of the face, grid vertex (a, b), sits at parameter (a + 2, b + 2)."""
    s, t = uv[:, 0], uv[:, 1]
    lam = np.stack([(1 - s) * (1 - t), s * (1 - t), s * t, (1 - s) * t], -1)
    ab = np.array([divmod(v, nv) for v in face], float) + 2.0
    return lam @ domain_vertices(4), lam @ ab[:, 0], lam @ ab[:, 1]


@test_settings(max_examples=10)
@given(nu=st.integers(4, 7), nv=st.integers(4, 7), seed=st.integers(0, 2**31 - 1))
def test_regular_grid_equals_tensor_product_bicubic(nu, nv, seed):
    """On a regular grid the surface IS the uniform bicubic B-spline with the mesh as control net."""
    rng = np.random.default_rng(seed)
    m, P = grid(nu, nv, rng)
    bs = BSplineSurface((3, 3), (np.arange(nu + 4.0), np.arange(nv + 4.0)), P)
    g = generalized_bicubic(m)
    assert g.scheme == "bicubic" and g.vertices == ()
    assert len(g) == (nu - 3) * (nv - 3)
    assert all(p.sides == 4 and p.depth == 3 for p in g.patches)
    for i, fi in enumerate(g.elements):
        x, u, w = _grid_domain_map(m.faces[fi], nv, rng.random((120, 2)))
        assert_allclose(g.evaluate(i, x), bs.evaluate(u, w), atol=EXACT_TOL)


def test_quad_patches_join_c1():
    m, _ = grid(7, 6, np.random.default_rng(3))
    assert_c1_joins(generalized_bicubic(m), 2 * 4 * 3 - 4 - 3)  # 4 x 3 interior faces: edges between them


# ---------------------------------------------------------------------------- irregular meshes
def test_cube():
    m = read_obj(FIXTURES / "cube.obj")
    g = generalized_bicubic(m)  # one Doo-Sabin step: 6 + 12 quads, 8 triangles
    assert len(g) == 26
    assert sorted({(p.sides, p.depth) for p in g.patches}) == [(3, BICUBIC_DEPTH), (4, 3)]
    assert len(g.shared_sides()) == g.mesh.n_edges  # closed: every edge joins two patches
    _assert_g1(g)
    # the cube's symmetry: every triangle's centre at one distance from the cube's centre
    tri = np.array([p.evaluate([0.0, 0.0]) for p in g.patches if p.sides == 3]) - 0.5
    r = np.linalg.norm(tri, axis=1)
    assert_allclose(r, r[0], rtol=1e-13)


def test_valence_3_and_5_prism():
    g = generalized_bicubic(read_obj(FIXTURES / "pentagonal_prism.obj"))
    assert sorted({p.sides for p in g.patches}) == [3, 4, 5]
    _assert_g1(g)


def test_genus_one_frame():
    m = read_obj(FIXTURES / "frame.obj")
    g = generalized_bicubic(m)
    assert g.mesh.genus() == m.genus() == 1 and len(g) == g.mesh.n_faces
    _assert_g1(g)


@pytest.mark.parametrize("n", [3, 5, 6, 7, 8])
def test_n_sided_faces(n):
    # the n-gon of the skirt mesh is a face already; its corners have valence 3, so a Doo-Sabin
    # step runs and the n-gon's face keeps n sides
    g = generalized_bicubic(ngon_with_skirt(n, np.random.default_rng(n)))
    assert n in {p.sides for p in g.patches}
    _assert_g1(g)


def test_valence_4_mesh_with_ngon_faces_needs_no_refinement():
    m = doo_sabin(read_obj(FIXTURES / "pentagonal_prism.obj"))
    g = generalized_bicubic(m, refine="never")
    assert g.mesh is m and len(g) == m.n_faces
    _assert_g1(g)


@test_settings(max_examples=8)
@given(seed=st.integers(0, 2**31 - 1))
def test_g1_on_random_irregular_meshes(seed):
    _assert_g1(generalized_bicubic(jittered_prism(seed)))


def test_corner_is_the_bicubic_limit_point():
    """At a vertex whose four faces are quads the patch corner is the bicubic B-spline limit point
    (v: 16/36, edge neighbours 4/36, diagonals 1/36), whatever the rest of the mesh."""
    m = doo_sabin(doo_sabin(read_obj(FIXTURES / "pentagonal_prism.obj")))  # all-quad fans exist now
    g = generalized_bicubic(m)
    P = m.vertices
    checked = 0
    for i, fi in enumerate(g.elements):
        f = m.faces[fi]
        for k, v in enumerate(f):
            fan = m.vertex_faces(v)
            if any(len(m.faces[h]) != 4 for h in fan):
                continue
            diag = [m.faces[h][(m.faces[h].index(v) + 2) % 4] for h in fan]
            ref = (16 * P[v] + 4 * P[list(m.one_ring(v))].sum(0) + P[diag].sum(0)) / 36
            assert_allclose(g.evaluate(i, domain_vertices(len(f))[k]), ref, atol=EXACT_TOL)
            checked += 1
    assert checked > 0


@test_settings(max_examples=6)
@given(seed=st.integers(0, 2**31 - 1))
def test_affine_invariance(seed):
    assert_affine_invariant(generalized_bicubic, seed)


def test_open_mesh_has_patches_only_at_interior_faces():
    m, _ = grid(5, 5, np.random.default_rng(0))
    g = generalized_bicubic(m)
    interior = {i * 5 + j for i in range(1, 4) for j in range(1, 4)}
    expected = [fi for fi, f in enumerate(m.faces) if set(f) <= interior]
    assert list(g.elements) == expected and len(expected) == 4


# ---------------------------------------------------------------------------- errors
def test_errors():
    quad = Mesh([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], [[0, 1, 2, 3]])
    with pytest.raises(InvalidGeometryError, match="no face with all its vertices interior"):
        generalized_bicubic(quad)
    with pytest.raises(InvalidGeometryError, match="mesh: expected a Mesh"):
        generalized_bicubic("cube")
    with pytest.raises(InvalidGeometryError, match="refine: expected"):
        generalized_bicubic(quad, refine="sometimes")
    with pytest.raises(InvalidGeometryError, match=r"vertex \d+ has valence 3 .*Doo-Sabin"):
        generalized_bicubic(read_obj(FIXTURES / "cube.obj"), refine="never")
    g = generalized_bicubic(read_obj(FIXTURES / "cube.obj"))
    with pytest.raises(InvalidGeometryError, match="patch: expected"):
        g.evaluate(26, [0.0, 0.0])


def test_max_valence_is_read_at_call_time():
    from occsurf.algorithms import tolerances

    m = doo_sabin(read_obj(FIXTURES / "pentagonal_prism.obj"))
    with tolerances.override(MAX_VALENCE=4):
        with pytest.raises(InvalidGeometryError, match=r"face \d+ has 5 sides, more than MAX_VALENCE = 4"):
            generalized_bicubic(m, refine="never")
