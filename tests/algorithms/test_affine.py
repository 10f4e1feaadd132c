"""Tests of occsurf.algorithms.geometry.affine: DeRose's coordinate-free types (course ch. 1, §1-5..1-30).

Kinds of test: type rules (allowed operations and TypeErrors), closed forms (frames, normals under
shear), invariants driven by hypothesis (frame round trips, composition/inverse, affine invariance
of B-splines, projective images of rational splines), error paths, vectorisation.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import assume, given
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from numpy.testing import assert_allclose

from occsurf.algorithms import BSplineCurve, BSplineSurface, InvalidGeometryError, tolerances
from occsurf.algorithms.geometry import AffineMap, Frame, Normal, Point, ProjectiveMap, Vector, affine_combination
from occsurf.algorithms.geometry.affine import vector_combination
from tests.algorithms.strategies import affine_maps, curves, parameters, surfaces, test_settings

RTOL = 1e-12  # exact identities, up to round-off

_f = dict(allow_nan=False, allow_infinity=False, allow_subnormal=False, width=64)


def coord_arrays(dim: int, max_n: int = 6) -> st.SearchStrategy[np.ndarray]:
    return st.integers(1, max_n).flatmap(lambda n: arrays(np.float64, (n, dim), elements=st.floats(-10, 10, **_f)))


def maps(dim: int) -> st.SearchStrategy[tuple[np.ndarray, np.ndarray]]:
    """The shared ``affine_maps`` bounds only cond(M); it can draw M ~ 1e-80 with t ~ 1, for which
    ``M p + t == t`` in floating point and no inverse can recover ``p``. Keep ||M|| >= 0.1 here."""
    return affine_maps(dim).filter(lambda Mb: np.linalg.norm(Mb[0], 2) >= 0.1)


def _close(a: np.ndarray, b: np.ndarray, scale: float | np.ndarray | None = None, rtol: float = RTOL) -> None:
    """``|a - b| <= rtol * scale`` with scale the size of the data (relative to the geometry)."""
    s = max(1.0, float(np.max(np.abs(b)))) if scale is None else scale
    assert_allclose(a, b, rtol=0, atol=rtol * s)


# ---------------------------------------------------------------------------------------- type rules
class TestTypeRules:
    p = Point([1.0, 2.0, 3.0])
    q = Point([4.0, 6.0, 3.0])
    v = Vector([1.0, 0.0, 0.0])
    n = Normal([0.0, 0.0, 1.0])

    def test_allowed(self):
        d = self.q - self.p
        assert isinstance(d, Vector)
        assert_allclose(d.coords, [3, 4, 0])
        assert_allclose(d.norm(), 5.0)
        assert isinstance(self.p + self.v, Point) and isinstance(self.v + self.p, Point)
        assert isinstance(self.p - self.v, Point)
        assert_allclose((self.p + self.v).coords, [2, 2, 3])
        assert isinstance(self.v + d, Vector) and isinstance(self.v - d, Vector)
        for s in (2, 2.0, np.float64(2.0), np.array(2.0)):
            assert_allclose((s * self.v).coords, [2, 0, 0])
            assert_allclose((self.v * s).coords, [2, 0, 0])
        assert_allclose((self.v / 2).coords, [0.5, 0, 0])
        assert_allclose((-self.v).coords, [-1, 0, 0])
        assert float(self.v.dot(d)) == 3.0
        assert_allclose(self.v.cross(Vector([0.0, 1.0, 0.0])).coords, [0, 0, 1])
        assert float(self.n.dot(self.v)) == 0.0
        assert isinstance(self.n + self.n, Normal) and isinstance(2 * self.n, Normal)
        assert isinstance(self.n - self.n, Normal) and isinstance(-self.n, Normal)
        assert_allclose((self.n / 2).coords, [0, 0, 0.5])
        s = np.array([1.0, 2.0])
        assert_allclose((s * Vector([[1.0, 0, 0], [0, 1.0, 0]])).coords, [[1, 0, 0], [0, 2, 0]])
        assert_allclose(self.p.distance(self.q), 5.0)
        assert isinstance(Normal.from_tangents(self.v, Vector([0.0, 1.0, 0.0])), Normal)

    @pytest.mark.parametrize(
        "op, text",
        [
            (lambda p, q, v, n: p + q, "point + point"),
            (lambda p, q, v, n: 2.0 * p, "scalar * point"),
            (lambda p, q, v, n: p * 2.0, "point * scalar"),
            (lambda p, q, v, n: np.float64(2.0) * p, "scalar * point"),
            (lambda p, q, v, n: p / 2.0, "point / scalar"),
            (lambda p, q, v, n: -p, "-point"),
            (lambda p, q, v, n: v - p, "vector - point"),
            (lambda p, q, v, n: p + np.ones(3), "point + scalar"),
            (lambda p, q, v, n: np.ones(3) + p, "scalar + point"),
            (lambda p, q, v, n: v * v, "vector * vector"),
            (lambda p, q, v, n: v + n, "vector + normal"),
            (lambda p, q, v, n: n + p, "normal + point"),
            (lambda p, q, v, n: p @ q, "point @ point"),
        ],
    )
    def test_forbidden(self, op, text):
        with pytest.raises(TypeError, match=text.replace("+", r"\+").replace("*", r"\*")):
            op(self.p, self.q, self.v, self.n)

    def test_forbidden_named_methods(self):
        with pytest.raises(TypeError):
            self.v.dot(self.p)
        with pytest.raises(TypeError):
            self.n.dot(self.n)
        with pytest.raises(TypeError):
            self.v.cross(self.n)
        with pytest.raises(TypeError, match="ambiguous"):
            bool(self.p)

    def test_cross_needs_3d(self):
        with pytest.raises(InvalidGeometryError, match="3-D"):
            Vector([1.0, 0.0]).cross(Vector([0.0, 1.0]))

    def test_mismatched_dimension_and_shapes(self):
        with pytest.raises(InvalidGeometryError, match="other: expected dimension 3"):
            self.p - Point([1.0, 2.0])
        with pytest.raises(InvalidGeometryError, match="other"):
            Point(np.zeros((4, 3))) - Point(np.zeros((5, 3)))
        with pytest.raises(InvalidGeometryError, match="scalar"):
            np.ones(5) * Vector(np.zeros((4, 3)))

    def test_construction_validation(self):
        with pytest.raises(InvalidGeometryError, match="coords"):
            Point([1.0, np.nan, 0.0])
        with pytest.raises(InvalidGeometryError, match="coords"):
            Vector(3.0)
        with pytest.raises(InvalidGeometryError, match="coords"):
            Point("abc")

    def test_readonly_and_frozen(self):
        p = Point(np.zeros((3, 3)))
        with pytest.raises(ValueError):
            p.coords[0, 0] = 1.0
        with pytest.raises(AttributeError):
            p.coords = np.ones(3)

    def test_input_not_aliased(self):
        a = np.zeros(3)
        p = Point(a)
        a[0] = 5.0
        assert p.coords[0] == 0.0


# ---------------------------------------------------------------------------------------- vectorisation
class TestVectorisation:
    def test_broadcasting(self):
        rng = np.random.default_rng(0)
        P = Point(rng.normal(size=(4, 5, 3)))
        o = Point(rng.normal(size=3))
        v = P - o
        assert v.shape == (4, 5) and v.dim == 3
        assert_allclose(v.coords, P.coords - o.coords)
        s = rng.normal(size=(4, 5))
        assert_allclose((s * v).coords, s[..., None] * v.coords)
        assert v.dot(v).shape == (4, 5)
        assert v.cross(Vector([0.0, 0.0, 1.0])).shape == (4, 5)
        Q = Point(rng.normal(size=(5, 3)))
        assert (P - Q).shape == (4, 5)

    def test_indexing_and_reshape(self):
        P = Point(np.arange(24.0).reshape(2, 4, 3))
        assert P[1].shape == (4,)
        assert_allclose(P[1, 2].coords, [18, 19, 20])
        assert P[:, ::2].shape == (2, 2)
        assert P[..., 0].shape == (2,)
        assert P.reshape(8).shape == (8,) and len(P) == 2
        assert isinstance(P[0], Point)

    def test_million_points_one_call(self):
        P = Point(np.random.default_rng(1).normal(size=(1_000_000, 3)))
        A = AffineMap(np.diag([1.0, 2.0, 3.0]), [1.0, 0.0, 0.0])
        Q = A(P)
        assert Q.shape == (1_000_000,)
        assert_allclose(Q.coords[:, 1], 2 * P.coords[:, 1])

    def test_2d(self):
        p, q = Point([0.0, 0.0]), Point([3.0, 4.0])
        assert float((q - p).norm()) == 5.0
        F = Frame(Point([1.0, 1.0]), [[2.0, 0.0], [1.0, 1.0]])
        assert_allclose(F.from_coordinates(F.coordinates_of(q)).coords, q.coords, rtol=RTOL)


# ---------------------------------------------------------------------------------------- combinations
class TestAffineCombination:
    def test_midpoint_and_barycentric(self):
        a, b, c = Point([0.0, 0.0, 0.0]), Point([2.0, 0.0, 0.0]), Point([0.0, 2.0, 0.0])
        assert_allclose(affine_combination([a, b], [0.5, 0.5]).coords, [1, 0, 0])
        assert_allclose(affine_combination([a, b, c], [1 / 3, 1 / 3, 1 / 3]).coords, [2 / 3, 2 / 3, 0], rtol=RTOL)
        assert_allclose(vector_combination([a, b], [-1, 1]).coords, (b - a).coords)

    def test_weights_must_sum_to_one(self):
        a, b = Point([0.0, 0.0, 0.0]), Point([2.0, 0.0, 0.0])
        with pytest.raises(InvalidGeometryError, match="summing to 1"):
            affine_combination([a, b], [0.5, 0.6])
        with pytest.raises(InvalidGeometryError, match="summing to 1"):
            affine_combination([a, b], [1.0, 1.0])  # "point + point" in disguise
        with pytest.raises(InvalidGeometryError, match="summing to 0"):
            vector_combination([a, b], [1.0, 1.0])
        # Within tolerance (scaled by sum |w|) passes; explicit tol overrides the module constant.
        affine_combination([a, b], [0.5, 0.5 + 1e-14])
        affine_combination([a, b], [0.5, 0.6], tol=0.2)
        with tolerances.override(WEIGHT_SUM=0.2):
            affine_combination([a, b], [0.5, 0.6])

    def test_shapes(self):
        P = Point(np.random.default_rng(2).normal(size=(7, 4, 3)))
        w = np.full((7, 4), 0.25)
        assert affine_combination(P, w).shape == (7,)
        assert affine_combination(P, [0.25] * 4).shape == (7,)
        with pytest.raises(InvalidGeometryError, match="weights"):
            affine_combination(P, [0.5, 0.5])
        with pytest.raises(TypeError, match="points"):
            affine_combination([Vector([1.0, 0, 0])], [1.0])
        bad = np.full((7, 4), 0.25)
        bad[3, 1] = 0.3
        with pytest.raises(InvalidGeometryError, match=r"index \(3,\)"):
            affine_combination(P, bad)

    @given(coord_arrays(3), st.data())
    @test_settings()
    def test_origin_independence(self, X, data):
        """sum w_i P_i computed after translating all points equals the translated result."""
        k = X.shape[0]
        w = np.array(data.draw(st.lists(st.floats(-2, 2, **_f), min_size=k, max_size=k)))
        w = np.append(w, 1.0 - w.sum())
        pts = [Point(x) for x in X] + [Point(X[0] * 0.5)]
        t = Vector(data.draw(arrays(np.float64, 3, elements=st.floats(-10, 10, **_f))))
        lhs = affine_combination([p + t for p in pts], w)
        rhs = affine_combination(pts, w) + t
        _close(lhs.coords, rhs.coords, scale=50 * (1 + np.abs(w).sum()))


# ---------------------------------------------------------------------------------------- frames
class TestFrame:
    def test_orthonormal_closed_form(self):
        F = Frame.orthonormal([1.0, 2.0, 3.0], [1.0, 1.0, 0.0], [0.0, 0.0, 2.0])
        s = np.sqrt(0.5)
        assert_allclose(F.basis, [[s, -s, 0], [s, s, 0], [0, 0, 1]], atol=1e-15)
        assert_allclose(F.coordinates_of(Point([1.0, 2.0, 4.0])), [0, 0, 1], atol=1e-15)
        assert_allclose(F.coordinates_of(Vector([1.0, 1.0, 0.0])), [2 * s, 0, 0], atol=1e-15)
        assert np.isclose(np.linalg.det(F.basis), 1.0)

    def test_orthonormal_errors(self):
        with pytest.raises(InvalidGeometryError, match="parallel"):
            Frame.orthonormal([0.0, 0, 0], [0.0, 0, 3], [0.0, 0, 1])
        with pytest.raises(InvalidGeometryError, match="z_dir"):
            Frame.orthonormal([0.0, 0, 0], [1.0, 0, 0], [0.0, 0, 0])
        with pytest.raises(InvalidGeometryError, match="x_dir"):
            Frame.orthonormal([0.0, 0, 0], [1.0, 0], [0.0, 0, 1])

    def test_invalid(self):
        with pytest.raises(InvalidGeometryError, match="basis"):
            Frame(Point([0.0, 0, 0]), [[1, 0, 0], [0, 1, 0], [1, 1, 0]])
        with pytest.raises(InvalidGeometryError, match="basis"):
            Frame(Point([0.0, 0, 0]), np.eye(2))
        with pytest.raises(InvalidGeometryError, match="origin"):
            Frame(Point(np.zeros((2, 3))), np.eye(3))
        with pytest.raises(TypeError, match="origin"):
            Frame(Vector([0.0, 0, 0]), np.eye(3))
        F = Frame.standard()
        with pytest.raises(TypeError, match="kind"):
            F.from_coordinates([1.0, 0, 0], "scalar")
        with pytest.raises(InvalidGeometryError, match="coords"):
            F.from_coordinates([1.0, 0], Point)

    @given(maps(3), coord_arrays(3), coord_arrays(3))
    @test_settings()
    def test_round_trips(self, Mb, X, Y):
        """World -> frame -> world is the identity for points, vectors and normals; the pairing
        n · v is the same in world and frame coordinates (normals are covariant)."""
        M, b = Mb
        F = Frame(Point(b), M)
        P, V, N = Point(X), Vector(Y), Normal(X)
        scale = 100 * np.linalg.cond(M) * max(1.0, np.abs(X).max(), np.abs(Y).max(), np.abs(b).max())
        for elem, kind in ((P, Point), (V, Vector), (N, Normal)):
            back = F.from_coordinates(F.coordinates_of(elem), kind)
            assert isinstance(back, kind)
            _close(back.coords, elem.coords, scale=scale)
        cp = F.coordinates_of(P)
        _close(F.from_coordinates(cp, "point").coords, P.coords, scale=scale)
        _close(F.to_world()(Point(cp)).coords, P.coords, scale=scale)
        _close(F.from_world()(P).coords, cp, scale=scale)
        k = min(X.shape[0], Y.shape[0])
        pair = np.einsum("...i,...i", F.coordinates_of(N[:k]), F.coordinates_of(V[:k]))
        _close(pair, N[:k].dot(V[:k]), scale=scale * 100)

    def test_mapped_frame(self):
        F = Frame(Point([1.0, 0, 0]), np.diag([1.0, 2.0, 3.0]))
        A = AffineMap([[0.0, -1, 0], [1, 0, 0], [0, 0, 1]], [0.0, 0, 5])
        G = A(F)
        c = np.array([0.3, -0.2, 0.7])
        _close(G.from_coordinates(c).coords, A(F.from_coordinates(c)).coords)


# ---------------------------------------------------------------------------------------- affine maps
def _shears_and_scales():
    yield np.diag([1.0, 5.0, 0.2])
    yield np.array([[1.0, 3.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
    yield np.array([[2.0, 1.0, -1.0], [0.5, 3.0, 0.0], [0.0, -2.0, 0.25]])


class TestAffineMap:
    @pytest.mark.parametrize("M", list(_shears_and_scales()))
    def test_normal_closed_form(self, M):
        """The normal of the plane x + y - z = 0 under a shear/non-uniform scale stays
        perpendicular to the images of its tangents; transforming it like a vector does not."""
        A = AffineMap(M, [1.0, 2.0, 3.0])
        tx, ty = Vector([1.0, 0.0, 1.0]), Vector([0.0, 1.0, 1.0])
        n = Normal.from_tangents(tx, ty)
        assert_allclose(n.coords, [-1, -1, 1])
        n2 = A(n, normalize=True)
        assert_allclose(n2.norm(), 1.0, rtol=RTOL)
        assert abs(float(n2.dot(A(tx)))) < 1e-13 and abs(float(n2.dot(A(ty)))) < 1e-13
        expected = np.cross(M @ tx.coords, M @ ty.coords)
        assert_allclose(n2.coords, expected / np.linalg.norm(expected), rtol=RTOL, atol=1e-15)
        naive = M @ n.coords  # the classic mistake
        assert abs(naive @ (M @ tx.coords)) + abs(naive @ (M @ ty.coords)) > 1e-3

    @given(maps(3), coord_arrays(3), coord_arrays(3), coord_arrays(3))
    @test_settings()
    def test_normals_stay_perpendicular(self, Mb, X, Y, Z):
        M, b = Mb
        A = AffineMap(M, b)
        k = min(len(X), len(Y), len(Z))
        t1, t2 = Vector(X[:k]), Vector(Y[:k])
        n = Normal.from_tangents(t1, t2)
        assume(np.all(n.norm() > 1e-3))
        n2 = A(n, normalize=True)
        scale = 1e3 * np.linalg.cond(M) * max(1.0, np.abs(X).max(), np.abs(Y).max())
        _close(n2.dot(A(t1)), np.zeros(k), scale=scale)
        _close(n2.dot(A(t2)), np.zeros(k), scale=scale)
        # Pairing invariance: (M^{-T} n) · (M v) = n · v for every v.
        v = Vector(Z[:k])
        _close(A(n).dot(A(v)), n.dot(v), scale=scale * max(1.0, np.abs(Z).max()) * 10)

    @given(maps(3), maps(3), coord_arrays(3))
    @test_settings()
    def test_composition_and_inverse(self, ab, cd, X):
        A, B = AffineMap(*ab), AffineMap(*cd)
        P, V = Point(X), Vector(X)
        scale = 1e3 * max(1.0, np.abs(X).max()) * 100
        _close((A @ B)(P).coords, A(B(P)).coords, scale=scale * 10)
        _close((A @ B)(V).coords, A(B(V)).coords, scale=scale * 10)
        scale_inv = scale * np.linalg.cond(ab[0])
        _close(A.inverse()(A(P)).coords, P.coords, scale=scale_inv)
        _close((A.inverse() @ A).homogeneous, np.eye(4), scale=scale_inv)
        _close(A.inverse()(A(V)).coords, V.coords, scale=scale_inv)
        _close(A.homogeneous @ B.homogeneous, (A @ B).homogeneous, scale=scale)
        _close(AffineMap.from_homogeneous(A.homogeneous).matrix, A.matrix, scale=1)

    def test_normalize_robust(self):
        s = np.sqrt(0.5)
        assert_allclose(Normal([1e300, 1e300, 0.0]).normalized().coords, [s, s, 0], rtol=RTOL)
        assert_allclose(Vector([1e-300, 0.0, 1e-300]).normalized().coords, [s, 0, s], rtol=RTOL)
        with pytest.raises(InvalidGeometryError, match="zero normal"):
            Normal(np.array([[1.0, 0, 0], [0, 0, 0]])).normalized()
        with pytest.raises(InvalidGeometryError, match="zero vector"):
            Vector([0.0, 0.0, 0.0]).normalized()

    def test_points_vs_vectors(self):
        A = AffineMap.translate(Vector([1.0, 2.0, 3.0]))
        assert_allclose(A(Point([0.0, 0, 0])).coords, [1, 2, 3])
        assert_allclose(A(Vector([1.0, 0, 0])).coords, [1, 0, 0])
        assert_allclose(A(Normal([1.0, 0, 0])).coords, [1, 0, 0])

    def test_errors(self):
        A = AffineMap(np.eye(3))
        with pytest.raises(TypeError, match="wrap arrays"):
            A(np.zeros(3))
        with pytest.raises(InvalidGeometryError, match="x: expected dimension 3"):
            A(Point([0.0, 0]))
        with pytest.raises(InvalidGeometryError, match="translation"):
            AffineMap(np.eye(3), [1.0, 2])
        with pytest.raises(InvalidGeometryError, match="matrix"):
            AffineMap(np.ones((2, 3)))
        P = AffineMap(np.diag([1.0, 1.0, 0.0]))  # projection onto z = 0: a valid affine map
        assert_allclose(P(Point([1.0, 2, 3])).coords, [1, 2, 0])
        with pytest.raises(InvalidGeometryError, match="invertible"):
            P.inverse()
        with pytest.raises(InvalidGeometryError, match="invertible"):
            P(Normal([0.0, 0, 1]))
        with pytest.raises(InvalidGeometryError, match="matrix"):
            AffineMap.from_homogeneous(np.ones((4, 4)))
        with pytest.raises(TypeError):
            A @ Point([0.0, 0, 0])
        with pytest.raises(TypeError, match="spline"):
            A.apply_to(Point([0.0, 0, 0]))


# ---------------------------------------------------------------------------------------- splines
def _rel_scale(*arrays_: np.ndarray) -> float:
    return max(1.0, *(float(np.max(np.abs(a))) for a in arrays_))


def _assert_image(A: AffineMap, spline, kind: type, params: tuple) -> object:
    """``A.apply_to(spline)`` is a ``kind`` as rational as ``spline`` whose values at ``params`` are
    ``A`` of the spline's values (affine invariance); returns it."""
    img = A.apply_to(spline)
    assert isinstance(img, kind) and img.is_rational == spline.is_rational
    rhs = A(Point(spline.evaluate(*params))).coords
    _close(img.evaluate(*params), rhs, scale=_rel_scale(rhs, spline.control_points))
    return img


class TestAffineInvariance:
    def test_rational_circle_to_ellipse(self):
        """Closed form: diag(a, b) maps the rational unit quarter circle onto x²/a² + y²/b² = 1."""
        s = np.sqrt(0.5)
        c = BSplineCurve(2, [0, 0, 0, 1, 1, 1], [[1.0, 0.0], [1.0, 1.0], [0.0, 1.0]], [1.0, s, 1.0])
        a, b = 3.0, 0.5
        e = AffineMap(np.diag([a, b]), [1.0, -2.0]).apply_to(c)
        assert e.is_rational
        x = e.evaluate(np.linspace(0, 1, 41)) - [1.0, -2.0]
        assert_allclose((x[:, 0] / a) ** 2 + (x[:, 1] / b) ** 2, 1.0, rtol=RTOL)

    @given(st.data())
    @test_settings(30)
    def test_curves(self, data):
        c = data.draw(curves(max_extra_poles=4, degrees=st.integers(1, 6)))
        M, b = data.draw(maps(c.dim))
        A = AffineMap(M, b)
        u = data.draw(parameters(c.domain, knots=c.knots))
        img = _assert_image(A, c, BSplineCurve, (u,))
        _close(A(c).control_points, img.control_points, scale=1)

    @given(st.data())
    @test_settings(20)
    def test_surfaces(self, data):
        s = data.draw(surfaces(max_extra_poles=2, degrees=st.integers(1, 4)))
        M, b = data.draw(maps(s.dim))
        A = AffineMap(M, b)
        (u0, u1), (v0, v1) = s.domain
        f = np.array(data.draw(st.lists(st.tuples(st.floats(0, 1), st.floats(0, 1)), min_size=1, max_size=6)))
        u, v = u0 + f[:, 0] * (u1 - u0), v0 + f[:, 1] * (v1 - v0)
        _assert_image(A, s, BSplineSurface, (u, v))


def _projective_maps(dim: int) -> st.SearchStrategy[np.ndarray]:
    """A well-conditioned (d+1)x(d+1) matrix with a mild perspective row."""
    return st.tuples(
        maps(dim),
        arrays(np.float64, dim, elements=st.floats(-0.02, 0.02, **_f)),
        st.floats(0.5, 2.0, **_f),
    ).map(lambda a: np.block([[a[0][0], a[0][1][:, None]], [a[1][None, :], np.array([[a[2]]])]])
          ).filter(lambda H: np.linalg.cond(H) <= 1e4)


class TestProjective:
    def test_closed_form_perspective(self):
        """Perspective division (pinhole camera at the origin): (x, y, z) -> (x/z, y/z, 1/z)."""
        H = np.array([[1.0, 0, 0, 0], [0, 1, 0, 0], [0, 0, 0, 1], [0, 0, 1, 0]])
        P = ProjectiveMap(H)
        x = Point([[2.0, 4.0, 2.0], [1.0, 1.0, 4.0]])
        out = P(x).coords
        assert_allclose(out, np.c_[x.coords[:, :2] / x.coords[:, 2:], 1 / x.coords[:, 2]], rtol=RTOL)
        assert P.dim == 3 and not P.is_affine
        with pytest.raises(InvalidGeometryError, match="infinity"):
            P(Point([1.0, 1.0, 0.0]))
        inf = P(Point([[1.0, 1.0, 0.0], [1.0, 1.0, 1.0]]), at_infinity="inf").coords
        assert np.all(np.isinf(inf[0, :2])) and np.all(np.isfinite(inf[1]))

    def test_errors(self):
        P = ProjectiveMap(np.eye(4))
        with pytest.raises(TypeError, match="vector"):
            P(Vector([1.0, 0, 0]))
        with pytest.raises(TypeError, match="normal"):
            P(Normal([1.0, 0, 0]))
        with pytest.raises(InvalidGeometryError, match="dimension 3"):
            P(Point([1.0, 0]))
        with pytest.raises(InvalidGeometryError, match="matrix"):
            ProjectiveMap(np.zeros((4, 4)))
        with pytest.raises(InvalidGeometryError, match="matrix"):
            ProjectiveMap(np.eye(3)[:2])
        # A map sending a control point beyond infinity: new weight <= 0.
        H = np.eye(3)
        H[2] = [1.0, 0.0, 0.5]  # w = x + 1/2
        c = BSplineCurve(2, [0, 0, 0, 1, 1, 1], [[1.0, 0.0], [-1.0, 1.0], [2.0, 0.0]])
        with pytest.raises(InvalidGeometryError, match="weight"):
            ProjectiveMap(H).apply_to(c)

    def test_affine_stays_polynomial(self):
        c = BSplineCurve(2, [0, 0, 0, 1, 1, 1], [[0.0, 0.0], [1.0, 1.0], [2.0, 0.0]])
        A = AffineMap([[2.0, 1.0], [0.0, 1.0]], [1.0, -1.0])
        img = ProjectiveMap(A.homogeneous).apply_to(c)
        assert not img.is_rational
        _close(img.control_points, A.apply_to(c).control_points)

    def test_circle_to_ellipse_exact(self):
        """A rational quadratic quarter circle mapped by a perspective map: every evaluated
        point is the map of the circle's point (closed form x^2 + y^2 = 1 before)."""
        s = np.sqrt(0.5)
        c = BSplineCurve(2, [0, 0, 0, 1, 1, 1], [[1.0, 0.0], [1.0, 1.0], [0.0, 1.0]], [1.0, s, 1.0])
        H = np.array([[1.0, 0.2, 0.1], [0.0, 1.5, -0.3], [0.1, 0.2, 1.0]])
        P = ProjectiveMap(H)
        u = np.linspace(0, 1, 33)
        pts = c.evaluate(u)
        assert_allclose(np.hypot(pts[:, 0], pts[:, 1]), 1.0, rtol=RTOL)
        _close(P.apply_to(c).evaluate(u), P(Point(pts)).coords)

    @given(st.data())
    @test_settings(30)
    def test_curves(self, data):
        c = data.draw(curves(max_extra_poles=4, degrees=st.integers(1, 6)))
        H = data.draw(_projective_maps(c.dim))
        P = ProjectiveMap(H)
        hP = c.control_points @ H[-1, :-1] + H[-1, -1]
        assume(np.all(hP > 0.05))
        u = data.draw(parameters(c.domain, knots=c.knots))
        img = P.apply_to(c)
        assert img.is_rational or not c.is_rational
        rhs = P(Point(c.evaluate(u))).coords
        _close(img.evaluate(u), rhs, scale=_rel_scale(rhs, img.control_points))

    @given(st.data())
    @test_settings(20)
    def test_surfaces(self, data):
        s = data.draw(surfaces(max_extra_poles=2, degrees=st.integers(1, 4)))
        H = data.draw(_projective_maps(s.dim))
        P = ProjectiveMap(H)
        assume(np.all(s.control_points @ H[-1, :-1] + H[-1, -1] > 0.05))
        (u0, u1), (v0, v1) = s.domain
        f = np.array(data.draw(st.lists(st.tuples(st.floats(0, 1), st.floats(0, 1)), min_size=1, max_size=6)))
        u, v = u0 + f[:, 0] * (u1 - u0), v0 + f[:, 1] * (v1 - v0)
        img = P.apply_to(s)
        rhs = P(Point(s.evaluate(u, v))).coords
        _close(img.evaluate(u, v), rhs, scale=_rel_scale(rhs, img.control_points))

    @given(_projective_maps(3), _projective_maps(3), coord_arrays(3))
    @test_settings()
    def test_composition_and_inverse(self, H1, H2, X):
        P, Q = ProjectiveMap(H1), ProjectiveMap(H2)
        pts = Point(X)
        assume(np.all(X @ H2[-1, :-1] + H2[-1, -1] > 0.05))
        mid = Q(pts)
        assume(np.all(np.abs(mid.coords @ H1[-1, :-1] + H1[-1, -1]) > 0.05))
        scale = 1e4 * _rel_scale(X, mid.coords)
        _close((P @ Q)(pts).coords, P(mid).coords, scale=scale)
        _close(Q.inverse()(mid).coords, X, scale=scale * np.linalg.cond(H2))
        A = AffineMap(H1[:3, :3], H1[:3, 3])
        _close((A @ Q)(pts).coords, A(mid).coords, scale=scale)
        _close((Q @ A)(pts).coords, Q(A(pts)).coords, scale=scale * 10)


def test_projective_map_conditioning_is_unit_free_and_sign_free():
    """Review: a plain translation by 1e6 composed with the identity looked singular (the condition
    number of the homogeneous matrix grows like |t|^2), and -H (the same map as H) was refused on
    splines although it maps points correctly."""
    from occsurf.algorithms import circle
    from occsurf.algorithms.geometry import ProjectiveMap

    for t in (1e6, 1e9):
        M = AffineMap(np.eye(3), [t, 0, 0]) @ ProjectiveMap(np.eye(4))
        assert_allclose(M(Point([1.0, 2, 3])).coords, [1 + t, 2, 3], rtol=1e-15)
    c = circle([0, 0, 0], 1.0)
    d = ProjectiveMap(-np.eye(4)).apply_to(c)
    assert_allclose(d.control_points, c.control_points, atol=0)
    assert_allclose(d.weights, c.weights, atol=0)
    with pytest.raises(InvalidGeometryError, match="singular|invertible"):
        ProjectiveMap(np.diag([1.0, 1.0, 1.0, 0.0]))


def test_vector_scaling_by_zero_division_or_nan_is_refused():
    """Review: Vector / 0 gave inf/nan silently although constructors refuse non-finite values."""
    v = Vector([1.0, 0.0, 0.0])
    with pytest.raises(InvalidGeometryError, match="division by zero"):
        v / 0
    with pytest.raises(InvalidGeometryError, match="finite scalars"):
        v * float("nan")
    assert_allclose((v / 4).coords, [0.25, 0, 0])


def test_geometry_modules_share_helpers_through_common_without_a_cycle():
    """affine.py (elements) and affine_maps.py (frames, maps) take their shared helpers from
    geometry/_common.py: no module imports another's private names, and affine.py does not import
    affine_maps (which imports affine), so there is no import cycle."""
    import ast
    from pathlib import Path

    import occsurf.algorithms.geometry as G

    root = Path(G.__file__).parent
    for path in root.glob("*.py"):
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom) and node.level and node.module:  # not `from .. import _validate`
                private = [a.name for a in node.names if a.name.startswith("_")]
                assert not private, f"{path.name} imports private names {private} from {node.module}"
                if path.name == "affine.py":
                    assert node.module != "affine_maps", "affine.py imports affine_maps: a cycle"
