"""Polygon meshes: adjacency, manifold validation, Catmull–Clark, OBJ read/write (occsurf.algorithms.topology.mesh)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from numpy.testing import assert_allclose, assert_array_equal

from occsurf.algorithms.errors import ExchangeError, InvalidGeometryError
from occsurf.algorithms.topology.mesh import Mesh, catmull_clark, read_obj, write_obj
from tests.algorithms.strategies import test_settings

FIXTURES = Path(__file__).resolve().parents[1] / "fixtures" / "meshes"

CUBE_V = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]]
CUBE_F = [[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7]]


def grid_mesh(nu: int, nv: int, z: np.ndarray | None = None) -> Mesh:
    X, Y = np.meshgrid(np.arange(nu, dtype=float), np.arange(nv, dtype=float), indexing="ij")
    Z = np.zeros_like(X) if z is None else z
    P = np.stack([X, Y, Z], -1).reshape(-1, 3)
    vid = lambda i, j: i * nv + j  # noqa: E731
    F = [[vid(i, j), vid(i + 1, j), vid(i + 1, j + 1), vid(i, j + 1)] for i in range(nu - 1) for j in range(nv - 1)]
    return Mesh(P, F)


def _check_fans(m: Mesh) -> None:
    """Invariants of the ordered fan: face k holds v -> ring[k]; face k+1 holds v -> prev of v in face k."""
    for v in range(m.n_vertices):
        fan, ring = m.vertex_faces(v), m.one_ring(v)
        for k, f in enumerate(fan):
            face = m.faces[f]
            i = face.index(v)
            assert face[(i + 1) % len(face)] == ring[k]
            if k + 1 < len(fan):
                assert m.faces[fan[k + 1]][(m.faces[fan[k + 1]].index(v) + 1) % len(m.faces[fan[k + 1]])] == face[i - 1]
        assert len(set(ring)) == len(ring)


# ---------------------------------------------------------------------------- adjacency
def test_cube_counts_and_adjacency():
    m = Mesh(CUBE_V, CUBE_F)
    assert (m.n_vertices, m.n_edges, m.n_faces) == (8, 12, 6)
    assert m.euler_characteristic == 2 and m.genus() == 0 and m.is_closed and m.is_quad
    assert [m.valence(v) for v in range(8)] == [3] * 8
    assert set(m.one_ring(0)) == {1, 3, 4}
    _check_fans(m)
    for f in range(6):  # face adjacency is symmetric and every cube face touches 4 others
        nb = m.face_neighbours(f)
        assert len(set(nb)) == 4 and all(f in m.face_neighbours(g) for g in nb)
    assert m.boundary_edges.shape == (0, 2) and m.boundary_vertices.size == 0


def test_open_grid_boundary():
    m = grid_mesh(4, 5)
    assert m.n_faces == 12 and not m.is_closed and m.euler_characteristic == 1
    # boundary: 2*(3+4) = 14 edges, all vertices except the (4-2)*(5-2) = 6 interior ones
    assert m.boundary_edges.shape == (14, 2)
    assert m.boundary_vertices.size == 20 - 6
    assert m.valence(0) == 2 and m.valence(1) == 3 and m.valence(6) == 4
    assert m.is_boundary_vertex(1) and not m.is_boundary_vertex(6)
    # the boundary fan starts after the boundary edge leaving the vertex: corner 0 has one face
    assert m.vertex_faces(0) == (0,) and m.one_ring(0) == (5, 1)
    _check_fans(m)
    # boundary edges run in their face's direction
    for a, b in m.boundary_edges:
        assert m.face_of_edge(a, b) >= 0 and m.face_of_edge(b, a) == -1


def test_fixture_frame_is_genus_one_with_valence_3_and_5():
    m = read_obj(FIXTURES / "frame.obj")
    assert m.is_closed and m.is_quad and m.genus() == 1
    val = np.array([m.valence(v) for v in range(m.n_vertices)])
    assert (val == 3).sum() == 8 and (val == 5).sum() == 8
    _check_fans(m)


def test_components_and_genus_errors():
    two = Mesh(np.vstack((CUBE_V, np.array(CUBE_V) + 3)), CUBE_F + [[v + 8 for v in f] for f in CUBE_F])
    assert len(two.components()) == 2
    with pytest.raises(InvalidGeometryError, match="2 components"):
        two.genus()
    with pytest.raises(InvalidGeometryError, match="boundary"):
        grid_mesh(3, 3).genus()


# ---------------------------------------------------------------------------- validation
@pytest.mark.parametrize(
    "faces, match",
    [
        ([[0, 1]], "at least 3"),
        ([[0, 1, 9]], "out of range"),
        ([[0, 1, 1]], "repeated vertex"),
        ([[0, 1, 2.5]], "integers"),
        ([], "at least one face"),
        ("abc", "sequence"),
    ],
)
def test_bad_faces(faces, match):
    with pytest.raises(InvalidGeometryError, match=match):
        Mesh([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], faces)


def test_bad_vertices():
    with pytest.raises(InvalidGeometryError, match="vertices"):
        Mesh([[0, 0, 0, 0]] * 4, [[0, 1, 2]])
    with pytest.raises(InvalidGeometryError, match="finite"):
        Mesh([[0, 0, np.nan], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]])


def test_inconsistent_orientation_is_refused():
    faces = [list(f) for f in CUBE_F]
    faces[3] = faces[3][::-1]
    with pytest.raises(InvalidGeometryError, match="same direction"):
        Mesh(CUBE_V, faces)


def test_edge_with_three_faces_is_refused():
    P = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1]]
    # three faces on edge (0, 1): two of them necessarily use it in the same direction
    with pytest.raises(InvalidGeometryError, match="edge \\(1, 0\\).*non-manifold"):
        Mesh(P, [[0, 1, 2], [1, 0, 3], [1, 0, 4]])


def test_bow_tie_vertex_is_refused():
    P = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [-1, 0, 0], [-1, -1, 0]]
    with pytest.raises(InvalidGeometryError, match="vertex 0 is non-manifold"):
        Mesh(P, [[0, 1, 2], [0, 3, 4]])


def test_query_errors():
    m = Mesh(CUBE_V, CUBE_F)
    with pytest.raises(InvalidGeometryError, match="v: expected"):
        m.valence(8)
    with pytest.raises(InvalidGeometryError, match="f: expected"):
        m.face_neighbours(-1)
    with pytest.raises(InvalidGeometryError, match="shape"):
        m.with_vertices(np.zeros((7, 3)))


# ---------------------------------------------------------------------------- Catmull-Clark
def test_catmull_clark_counts_and_topology():
    m = read_obj(FIXTURES / "pentagonal_prism.obj")
    r = catmull_clark(m)
    assert r.is_quad and r.is_closed
    assert r.n_vertices == m.n_vertices + m.n_faces + m.n_edges
    assert r.n_faces == sum(len(f) for f in m.faces)
    assert r.euler_characteristic == m.euler_characteristic
    val = sorted({r.valence(v) for v in range(r.n_vertices)})
    assert val == [3, 4, 5]  # old corners 3, pentagon centres 5, the rest 4


def test_catmull_clark_linear_precision_on_a_flat_grid():
    """On a planar regular grid every Catmull–Clark rule reproduces affine functions: interior
    vertices stay, face points are centroids, edge points midpoints (closed form)."""
    m = grid_mesh(5, 4)
    r = catmull_clark(m)
    interior = [v for v in range(m.n_vertices) if not m.is_boundary_vertex(v)]
    assert_allclose(r.vertices[interior], m.vertices[interior], atol=1e-15)
    assert_allclose(r.vertices[m.n_vertices : m.n_vertices + m.n_faces], m.face_centroids(), atol=1e-15)
    E = m.edges
    assert_allclose(r.vertices[m.n_vertices + m.n_faces :], m.vertices[E].mean(axis=1), atol=1e-15)


@test_settings(max_examples=15)
@given(seed=st.integers(0, 2**31 - 1))
def test_catmull_clark_affine_invariance(seed):
    """CC(A m + b) = A CC(m) + b: every rule is an affine combination (weights sum to 1)."""
    rng = np.random.default_rng(seed)
    m = read_obj(FIXTURES / "pentagonal_prism.obj")
    m = m.with_vertices(m.vertices + 0.1 * rng.standard_normal(m.vertices.shape))
    A, b = rng.standard_normal((3, 3)), rng.standard_normal(3)
    lhs = catmull_clark(m.with_vertices(m.vertices @ A.T + b)).vertices
    rhs = catmull_clark(m).vertices @ A.T + b
    # round-off of a few affine combinations of O(1) coordinates times |A| ~ 3: 1e-13 is ample
    assert_allclose(lhs, rhs, atol=1e-13)


# ---------------------------------------------------------------------------- OBJ
@test_settings(max_examples=15)
@given(nu=st.integers(2, 6), nv=st.integers(2, 6), seed=st.integers(0, 2**31 - 1))
def test_obj_round_trip_is_bit_exact(tmp_path_factory, nu, nv, seed):
    rng = np.random.default_rng(seed)
    m = grid_mesh(nu, nv, rng.standard_normal((nu, nv)) * 1e3)
    p = tmp_path_factory.mktemp("obj") / "grid.obj"
    write_obj(m, p, comment="round trip\nsecond line")
    back = read_obj(p)
    assert_array_equal(back.vertices, m.vertices)  # repr() of floats round-trips exactly
    assert back.faces == m.faces


def test_read_obj_record_forms(tmp_path):
    p = tmp_path / "forms.obj"
    p.write_text(
        "# comment\nmtllib x.mtl\no thing\nv 0 0 0\nv 2 0 0 2\nv 1 1 0   # trailing comment\nv 9 9 9\n"
        "vt 0 0\nvn 0 0 1\ng grp\ns off\nusemtl m\nf -4/1/1 2//1 \\\n 3/1\n"
    )
    m = read_obj(p)
    assert_allclose(m.vertices, [[0, 0, 0], [1, 0, 0], [1, 1, 0]])  # w divides; unused vertex dropped
    assert m.faces == ((0, 1, 2),)


@pytest.mark.parametrize(
    "text, match",
    [
        ("v 0 0\nf 1 1 1\n", r"bad\.obj:1: a 'v' record needs 3"),
        ("v 0 0 x\n", r"bad\.obj:1: non-numeric"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", r"bad\.obj:4: face refers to vertex 4"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", "index 0"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n", "at least 3 vertices"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 a 2\n", "bad vertex reference 'a'"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nbogus 1\n", "unknown record 'bogus'"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\n", "no faces"),
        ("v 0 0 inf\n", "finite"),
        ("", "no faces"),
    ],
)
def test_read_obj_malformed(tmp_path, text, match):
    p = tmp_path / "bad.obj"
    p.write_text(text)
    with pytest.raises(ExchangeError, match=match):
        read_obj(p)


def test_read_obj_missing_and_binary(tmp_path):
    with pytest.raises(ExchangeError, match="no such file"):
        read_obj(tmp_path / "none.obj")
    p = tmp_path / "bin.obj"
    p.write_bytes(b"\xff\xfe\x00garbage")
    with pytest.raises(ExchangeError, match="cannot read"):
        read_obj(p)
    with pytest.raises(ExchangeError):  # a directory
        read_obj(tmp_path)


def test_read_obj_non_manifold_is_a_geometry_error(tmp_path):
    p = tmp_path / "flip.obj"
    p.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 3 4\n")
    with pytest.raises(InvalidGeometryError, match="same direction"):
        read_obj(p)


def test_write_obj_errors(tmp_path):
    m = Mesh(CUBE_V, CUBE_F)
    with pytest.raises(ExchangeError, match="cannot write"):
        write_obj(m, tmp_path / "no" / "dir" / "x.obj")
    assert not list(tmp_path.iterdir())  # no partial file left
    with pytest.raises(InvalidGeometryError, match="Mesh"):
        write_obj("cube", tmp_path / "x.obj")


@pytest.mark.parametrize("name", ["cube", "pentagonal_prism", "frame"])
def test_fixtures_read(name):
    m = read_obj(FIXTURES / f"{name}.obj")
    assert m.is_closed
    _check_fans(m)


def test_read_obj_ignores_vertex_colours(tmp_path):
    """Review: 'v x y z r g b' (MeshLab, scanners) was refused; the colour is ignored."""
    p = tmp_path / "col.obj"
    p.write_text("v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 1 1 0 0 0 1\nv 0 1 0 0.5 0.5 0.5\nf 1 2 3 4\n")
    m = read_obj(p)
    assert_allclose(m.vertices, [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], atol=0)
    p.write_text("v 0 0 0 1 2\nv 1 0 0\nv 1 1 0\nf 1 2 3\n")
    with pytest.raises(ExchangeError, match="optionally followed by an r g b colour, got 5"):
        read_obj(p)
