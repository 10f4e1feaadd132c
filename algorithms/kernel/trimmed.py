"""Trimmed surfaces: a B-spline surface restricted to a region of its parameter plane bounded by
loops of p-curves (course §2 and §6-0; the faces of every B-rep modeller).

A CAD face is rarely a whole tensor-product patch: a hole, a fillet or an intersection cuts it,
and the cut is kept as *trimming curves in the parameter plane* (p-curves). The course builds
surfaces as whole patches (§2, §6); its assessment chapters (§9-§11) evaluate and interrogate
them on a domain, and a trimmed face is that domain made explicit. :class:`TrimmedSurface` is the
value: the surface, one outer loop, any number of inner loops (holes), and the face's
orientation. Everything that asks "is this parameter on the face?" goes through one vectorised
point-in-domain classification (:meth:`TrimmedSurface.classify`): the crossing-number rule
(Jordan curve theorem; Shimrat 1962, "Algorithm 112: position of point relative to polygon",
CACM 5(8)) on the p-curves refined to polylines within ``tolerances.TRIM_POLYLINE`` of the curves,
with the points within ``tolerances.TRIM_ON`` of a polyline reported *on* the boundary.

The area is ``integral over D of |S_u x S_v| du dv`` turned into a boundary integral by Green's
theorem, ``A = closed integral of F(u, v) dv`` with ``F(u, v) = integral from u0 to u of
|S_u x S_v|(t, v) dt``, both integrals by composite Gauss-Legendre quadrature on the knot spans
(the scheme OCC's ``BRepGProp_Face`` uses), refined until two levels agree to
``tolerances.TRIM_AREA_RTOL``; the quadrature is :mod:`.trimmed_area`'s.

Conventions
-----------
* P-curves are 2-D :class:`~.curve.BSplineCurve` values ``c(s) = (u(s), v(s))`` in the surface's
  parameter plane. A loop is a tuple of them, each starting where the previous one ends (gaps up
  to ``tolerances.TRIM_LOOP_GAP`` of the parameter box's diagonal are closed by a straight
  segment in the polylines).
* The constructor orients the loops: the outer loop counter-clockwise in ``(u, v)``, holes
  clockwise, so the face lies on the left of every p-curve. ``reversed=True`` records that the
  face's outward normal is ``-S_u x S_v`` (OCC's ``TopAbs_REVERSED``); the loops are not changed
  by it.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import _validate as V
from .. import tolerances
from ..errors import InvalidGeometryError, ParameterError
from ._common import FORMAT_VERSION
from .curve import BSplineCurve
from .point_in_loops import (
    INSIDE,
    ON,
    OUTSIDE,
    classify_points,
    loop_polyline,
    segment_bands,
    signed_area,
    span_samples,
)
from .surface import BSplineSurface
from .trimmed_area import green_area

if TYPE_CHECKING:
    from ..geometry.surface_differential import SurfaceCurvatures

__all__ = ["TrimmedSurface", "INSIDE", "ON", "OUTSIDE", "classify_points"]

Array = NDArray[np.float64]
Loop = tuple[BSplineCurve, ...]
Outside = Literal["raise", "nan"]

# ============================================================================ the value
@dataclass(frozen=True, eq=False)
class TrimmedSurface:
    """A B-spline surface restricted to the region bounded by loops of p-curves.

    Parameters
    ----------
    surface : BSplineSurface
        The underlying surface (any dimension; :meth:`area` and normals need 3-D).
    outer : sequence of BSplineCurve
        The outer loop: 2-D p-curves in the surface's parameter plane, head to tail.
    inner : sequence of sequences of BSplineCurve, optional
        Holes, each a loop like ``outer``, inside it and disjoint.
    reversed : bool, optional
        The face's outward normal is ``-S_u x S_v`` (OCC's ``TopAbs_REVERSED``).

    Raises
    ------
    InvalidGeometryError
        ``surface`` is not a :class:`BSplineSurface`, a p-curve is not a 2-D
        :class:`BSplineCurve`, a loop is empty or open by more than ``tolerances.TRIM_LOOP_GAP``,
        or a p-curve leaves the surface's domain by more than that.

    Notes
    -----
    Loops are stored oriented (outer counter-clockwise, holes clockwise in ``(u, v)``), reversed
    here when given the other way; their p-curves are otherwise kept bit for bit. The polylines
    behind :meth:`classify` are computed once, on first use, per tolerance.

    Examples
    --------
    A 4 x 4 square with a round hole of radius 1 (0.25 in parameters):

    >>> import numpy as np
    >>> from occsurf.algorithms import BSplineCurve, BSplineSurface, TrimmedSurface, circle
    >>> P = np.zeros((2, 2, 3)); P[1, :, 0] = 4; P[:, 1, 1] = 4
    >>> s = BSplineSurface((1, 1), ([0, 0, 1, 1], [0, 0, 1, 1]), P)
    >>> side = lambda a, b: BSplineCurve(1, [0, 0, 1, 1], [a, b])
    >>> outer = [side((0, 0), (1, 0)), side((1, 0), (1, 1)), side((1, 1), (0, 1)), side((0, 1), (0, 0))]
    >>> c = circle([0.5, 0.5, 0], 0.25)
    >>> hole = BSplineCurve(c.degree, c.knots, c.control_points[:, :2], c.weights)
    >>> face = TrimmedSurface(s, outer, [[hole]])
    >>> bool(abs(face.area() - (16 - np.pi)) < 1e-12)
    True
    >>> face.classify([0.1, 0.5], [0.1, 0.5])
    array([ 1, -1], dtype=int8)
    """

    surface: BSplineSurface
    outer: Loop
    inner: tuple[Loop, ...] = ()
    reversed: bool = False
    _cache: dict[Any, Any] = field(default_factory=dict, init=False, repr=False, compare=False)

    if TYPE_CHECKING:  # the generated __init__ takes any sequences; __post_init__ stores tuples

        def __init__(
            self,
            surface: BSplineSurface,
            outer: Sequence[BSplineCurve],
            inner: Sequence[Sequence[BSplineCurve]] = (),
            reversed: bool = False,
        ) -> None: ...

    def __post_init__(self) -> None:
        if not isinstance(self.surface, BSplineSurface):
            raise InvalidGeometryError(f"surface: expected a BSplineSurface, got {type(self.surface).__name__}")
        if not isinstance(self.reversed, (bool, np.bool_)):
            raise InvalidGeometryError(f"reversed: expected a bool, got {self.reversed!r}")
        inner = self.inner
        if isinstance(inner, BSplineCurve) or not isinstance(inner, (tuple, list)):
            raise InvalidGeometryError(f"inner: expected a sequence of loops (sequences of BSplineCurve), "
                                       f"got {type(inner).__name__}")
        outer = self._check_loop(self.outer, "outer", +1)
        holes = tuple(self._check_loop(loop, f"inner[{i}]", -1) for i, loop in enumerate(inner))
        object.__setattr__(self, "outer", outer)
        object.__setattr__(self, "inner", holes)
        object.__setattr__(self, "reversed", bool(self.reversed))

    def _check_loop(self, loop: Any, name: str, sign: int) -> Loop:
        if isinstance(loop, BSplineCurve) or not isinstance(loop, (tuple, list)) or len(loop) == 0:
            raise InvalidGeometryError(f"{name}: expected a non-empty sequence of 2-D BSplineCurve p-curves, "
                                       f"got {type(loop).__name__}")
        for j, c in enumerate(loop):
            if not isinstance(c, BSplineCurve) or c.dim != 2:
                got = f"a {c.dim}-D curve" if isinstance(c, BSplineCurve) else type(c).__name__
                raise InvalidGeometryError(f"{name}[{j}]: expected a 2-D BSplineCurve (u, v), got {got}")
        diag = self._diag()
        gap_tol = tolerances.TRIM_LOOP_GAP * diag
        samples = [c.evaluate(span_samples(c, 4)) for c in loop]  # one evaluation per p-curve
        ends = np.array([[pts[0], pts[-1]] for pts in samples])  # (k, 2, 2)
        gaps = np.linalg.norm(ends[:, 1] - np.roll(ends[:, 0], -1, axis=0), axis=1)
        if np.any(gaps > gap_tol):
            j = int(np.argmax(gaps))
            raise InvalidGeometryError(
                f"{name}: the loop is open: p-curve {j} ends {gaps[j]:.3g} from the start of p-curve "
                f"{(j + 1) % len(loop)} (allowed {gap_tol:.3g}, tolerances.TRIM_LOOP_GAP of the domain diagonal)")
        (u0, u1), (v0, v1) = self.surface.domain
        lo, hi = np.array([u0, v0]) - gap_tol, np.array([u1, v1]) + gap_tol
        for j, c in enumerate(loop):
            if np.any(c.control_points.min(axis=0) < lo) or np.any(c.control_points.max(axis=0) > hi):
                c0, c1 = c.domain
                pts = c.evaluate(np.linspace(c0, c1, 65))
                if np.any(pts < lo) or np.any(pts > hi):
                    raise InvalidGeometryError(
                        f"{name}[{j}]: the p-curve leaves the surface's domain [{u0!r}, {u1!r}] x [{v0!r}, {v1!r}]")
        loop = tuple(loop)
        if sign * signed_area(np.concatenate(samples)) < 0:
            loop = tuple(c.reverse() for c in loop[::-1])
        return loop

    def _diag(self) -> float:
        (u0, u1), (v0, v1) = self.surface.domain
        return float(np.hypot(u1 - u0, v1 - v0))

    # ------------------------------------------------------------------ properties
    @property
    def loops(self) -> tuple[Loop, ...]:
        """``(outer, *inner)``."""
        return (self.outer, *self.inner)

    @property
    def domain(self) -> tuple[tuple[float, float], tuple[float, float]]:
        """The surface's parameter box ``((u0, u1), (v0, v1))``."""
        return self.surface.domain

    @property
    def dim(self) -> int:
        return self.surface.dim

    @property
    def n_edges(self) -> tuple[int, ...]:
        """Number of p-curves per loop, outer first."""
        return tuple(len(loop) for loop in self.loops)

    def __repr__(self) -> str:
        return (f"TrimmedSurface({self.surface!r}, loops={len(self.loops)}, p-curves={self.n_edges}"
                f"{', reversed' if self.reversed else ''})")

    def on_surface(self, surface: BSplineSurface) -> TrimmedSurface:
        """The same trim on another ``surface`` of this one's parameter domain.

        The loops are kept as checked and oriented, and so is what was drawn from them: their
        polylines and binned segments depend on the loops and the domain only, and are shared with
        this face (a surface refitted in one domain again and again, as the stages of a plate fill
        are, classifies its points without redrawing its loops: 17 % of a bearing plate's time).

        Raises
        ------
        InvalidGeometryError
            ``surface`` is not a BSplineSurface or has another parameter domain.
        """
        if not isinstance(surface, BSplineSurface):
            raise InvalidGeometryError(f"surface: expected a BSplineSurface, got {type(surface).__name__}")
        if surface.domain != self.surface.domain:
            raise InvalidGeometryError(f"surface: expected the domain {self.surface.domain} of the trim's surface, got "
                                       f"{surface.domain}")
        obj = _trusted(surface, self.outer, self.inner, self.reversed)
        object.__setattr__(obj, "_cache", self._cache)
        return obj

    # ------------------------------------------------------------------ polylines
    def polylines(self, tol: float | None = None) -> tuple[Array, ...]:
        """The loops as closed polylines in ``(u, v)``, within ``tol`` of the p-curves.

        Parameters
        ----------
        tol : float, optional
            Largest distance (parameter units) between a p-curve and its polyline; default
            ``tolerances.TRIM_POLYLINE`` times the diagonal of the parameter box.

        Returns
        -------
        tuple of ndarray, shape (k_i, 2)
            One per loop (outer first), oriented as the loops, first point repeated last; read-only
            views of the points the classification uses (copy one to change it).
        """
        t = self._tol(tol, tolerances.TRIM_POLYLINE, "tol")
        key = ("polylines", t)
        if key not in self._cache:
            pts, ends = self._points(t)
            self._cache[key] = tuple(np.split(pts, ends[:-1]))
        return self._cache[key]

    def _points(self, tol: float) -> tuple[Array, NDArray[np.intp]]:
        """The loops' polylines (:meth:`polylines`) laid end to end in one array, and where each
        ends: the polylines and the classification's segments (:meth:`_segments`) are views of it.
        (Each held its own copy before: three copies of 1.5 million points, ~72 MB, on a face
        with 361 holes.) Read-only: the classification reads the same points, so a polyline
        changed in place would change what is inside."""
        key = ("points", tol)
        if key not in self._cache:
            lines = [loop_polyline(loop, tol) for loop in self.loops]
            pts = np.concatenate(lines)
            pts.flags.writeable = False
            self._cache[key] = (pts, np.cumsum([len(p) for p in lines]))
        return self._cache[key]

    def _tol(self, tol: float | None, default_rel: float, name: str) -> float:
        if tol is None:
            return default_rel * self._diag()
        return V.check_tol(tol, name)

    def _segments(self, tol: float) -> tuple[Array, Array, NDArray[np.bool_]]:
        """The polylines' segments ``A[i] -> B[i]`` (views of :meth:`_points`) and which of them
        are the loops' (not the step from one loop's last point to the next one's first)."""
        pts, ends = self._points(tol)
        keep = np.ones(max(pts.shape[0] - 1, 0), bool)
        keep[ends[:-1] - 1] = False
        return pts[:-1], pts[1:], keep

    # ------------------------------------------------------------------ classification
    def classify(self, u: ArrayLike, v: ArrayLike, *, tol: float | None = None) -> NDArray[np.int8]:
        """Where parameters lie: :data:`INSIDE` (1), :data:`ON` the boundary (0) or :data:`OUTSIDE` (-1).

        Parameters
        ----------
        u, v : array_like, broadcastable to shape S
            Any finite parameters (outside the surface's domain is :data:`OUTSIDE`).
        tol : float, optional
            Width of the boundary band (parameter units): points within ``tol`` of a loop are
            :data:`ON`. Default ``tolerances.TRIM_ON`` times the parameter box's diagonal. The
            polylines are refined to ``min(tol, TRIM_POLYLINE x diagonal)``.

        Returns
        -------
        ndarray of int8, shape S

        Notes
        -----
        Crossing-number rule on all loops at once (even-odd: holes need no special case), against
        the polylines of :meth:`polylines`, vectorised: segments are binned into horizontal bands
        and each point is tested against the segments of its band only
        (:func:`classify_points`).
        """
        a, b, shape = _finite_uv(u, v, per_point=8 + 2 * self.dim + 2 * (self.surface.dim + 1))
        on_tol = self._tol(tol, tolerances.TRIM_ON, "tol")
        line_tol = min(on_tol, tolerances.TRIM_POLYLINE * self._diag()) if on_tol > 0 else \
            tolerances.TRIM_POLYLINE * self._diag()
        key = ("bands", line_tol, on_tol)  # the segments binned once per tolerance (many calls: sections)
        if key not in self._cache:
            A, B, keep = self._segments(line_tol)
            self._cache[key] = segment_bands(A, B, on_tol, keep=keep)
        state = classify_points(np.column_stack([a, b]), bands=self._cache[key])
        (u0, u1), (v0, v1) = self.domain
        out_box = (a < u0 - on_tol) | (a > u1 + on_tol) | (b < v0 - on_tol) | (b > v1 + on_tol)
        state[out_box] = OUTSIDE
        return state.reshape(shape)

    def contains(self, u: ArrayLike, v: ArrayLike, *, tol: float | None = None) -> NDArray[np.bool_]:
        """``classify(u, v) >= ON``: parameters on the face, boundary included (shape S)."""
        return self.classify(u, v, tol=tol) >= ON

    def _inside(self, u: ArrayLike, v: ArrayLike, outside: Outside, what: str) -> tuple[Array, Array, NDArray[np.bool_], tuple[int, ...]]:
        if outside not in ("raise", "nan"):
            raise InvalidGeometryError(f"outside: expected 'raise' or 'nan', got {outside!r}")
        a, b, shape = _finite_uv(u, v)
        ok = self.contains(a, b)
        if outside == "raise" and not ok.all():
            i = int(np.flatnonzero(~ok)[0])
            raise ParameterError(
                f"{what}: {int((~ok).sum())} of {ok.size} parameter points lie outside the trimmed face, the first "
                f"at (u, v) = ({a[i]!r}, {b[i]!r}); pass outside='nan' to get NaN there")
        return a, b, ok, shape

    # ------------------------------------------------------------------ evaluation
    def evaluate(self, u: ArrayLike, v: ArrayLike, *, outside: Outside = "raise") -> Array:
        """Points of the face (course §2-9 on the trimmed domain).

        Parameters
        ----------
        u, v : array_like, broadcastable to shape S
        outside : {"raise", "nan"}
            What to do with parameters outside the trimmed face: raise :class:`ParameterError`
            naming how many and the first, or return NaN rows for them. Never evaluated silently.

        Returns
        -------
        ndarray, shape S + (d,)
        """
        a, b, ok, shape = self._inside(u, v, outside, "evaluate")
        out = np.full((a.size, self.dim), np.nan)
        if ok.any():
            out[ok] = self.surface.evaluate(a[ok], b[ok])
        return out.reshape(shape + (self.dim,))

    __call__ = evaluate

    def derivatives(self, u: ArrayLike, v: ArrayLike, order: int = 1, *, outside: Outside = "raise") -> Array:
        """Partial derivatives up to ``order`` on the face (layout of :meth:`BSplineSurface.derivatives`).

        Returns
        -------
        ndarray, shape S + (order + 1, order + 1, d)
            NaN blocks at parameters outside the face when ``outside="nan"``.
        """
        order = V.check_order(order)
        # per point: the result and the surface's derivatives at the points on the face
        u, v, shape = _finite_uv(u, v, 8 + 2 * (order + 1) ** 2 * (self.surface.dim + 1),
                                 f" for derivatives of order {order}")
        a, b, ok, _ = self._inside(u, v, outside, "derivatives")
        out = np.full((a.size, order + 1, order + 1, self.dim), np.nan)
        if ok.any():
            out[ok] = self.surface.derivatives(a[ok], b[ok], order)
        return out.reshape(shape + out.shape[1:])

    def normal(self, u: ArrayLike, v: ArrayLike, *, outside: Outside = "raise") -> Array:
        """Unit *outward* normal of the face, ``S_u x S_v`` negated when :attr:`reversed` (shape S + (3,))."""
        self._need_3d("normal")
        D = self.derivatives(u, v, 1, outside=outside)
        n = np.cross(D[..., 1, 0, :], D[..., 0, 1, :])
        ln = np.linalg.norm(n, axis=-1, keepdims=True)
        with np.errstate(invalid="ignore", divide="ignore"):
            n = np.where(ln > 0, n / ln, np.nan)
        return -n if self.reversed else n

    def curvatures(self, u: ArrayLike, v: ArrayLike, *, outside: Outside = "raise") -> SurfaceCurvatures:
        """Principal, Gaussian and mean curvatures on the face (course §6-8 .. §6-12).

        As :func:`occsurf.algorithms.surface_curvatures` of :attr:`surface` (signs against
        ``S_u x S_v``, OCC's ``GeomLProp`` convention, whatever :attr:`reversed` says), every
        field NaN at parameters outside the face when ``outside="nan"``.

        Returns
        -------
        SurfaceCurvatures
        """
        from ..geometry.surface_differential import curvatures_from_derivatives

        self._need_3d("curvatures")
        D = self.derivatives(u, v, 2, outside=outside)
        with np.errstate(invalid="ignore", divide="ignore"):
            return curvatures_from_derivatives(D)

    def _need_3d(self, what: str) -> None:
        if self.dim != 3:
            raise InvalidGeometryError(f"{what}: needs a 3-D surface, this one has dim {self.dim}")

    # ------------------------------------------------------------------ area
    def area(self, *, rtol: float | None = None) -> float:
        """Area of the face: ``integral over the trimmed domain of |S_u x S_v| du dv``.

        Parameters
        ----------
        rtol : float, optional
            Relative agreement of two successive refinements; default ``tolerances.TRIM_AREA_RTOL``.

        Returns
        -------
        float

        Raises
        ------
        InvalidGeometryError
            Not a 3-D surface.
        ToleranceError
            ``rtol`` not reached in ``tolerances.TRIM_AREA_LEVELS`` refinements. When
            ``|S_u x S_v|`` falls below ``tolerances.TRIM_AREA_SINGULAR`` of its largest value inside
            the face (a near-singular parametrisation, as on two blend faces of OCC's linkrods
            sample: 1e-6 against 0.27), the message says so and where: the integrand has a kink
            there and uniform Gauss refinement converges only algebraically (2e-10 at level 7).

        Notes
        -----
        Green's theorem on the oriented loops: ``A = sum over p-curves of integral F(c(s)) v'(s) ds``
        with ``F(u, v) = integral_{u0}^{u} |S_u x S_v|(t, v) dt``. Both integrals are 8-point
        Gauss-Legendre on every knot span (of the p-curve, of the surface in u), each span cut in
        ``2^level`` pieces; the level rises until two successive values agree to ``rtol``.
        """
        from ..errors import ToleranceError

        self._need_3d("area")
        rt = tolerances.TRIM_AREA_RTOL if rtol is None else V.check_tol(rtol, "rtol")
        prev, anchor = None, self._area_anchor()
        for level in range(int(tolerances.TRIM_AREA_LEVELS) + 1):
            value = sum(green_area(self.surface, c, 1 << level, anchor) for loop in self.loops for c in loop)
            if prev is not None and abs(value - prev) <= rt * max(abs(value), np.finfo(float).tiny):
                return float(value)
            prev = value
        jmin, jmax, (u, v) = self._jacobian_range()
        why = (f"; |S_u x S_v| falls to {jmin:.3g} at (u, v) = ({u:.6g}, {v:.6g}) inside the face (largest "
               f"{jmax:.3g}): a near-singular parametrisation, where the integrand has a kink that Gauss "
               "quadrature on knot spans converges to only algebraically; pass a larger rtol"
               if jmin < tolerances.TRIM_AREA_SINGULAR * jmax else "")
        raise ToleranceError(f"area: two refinements still differ by more than rtol={rt:g} after "
                             f"{int(tolerances.TRIM_AREA_LEVELS)} levels (tolerances.TRIM_AREA_LEVELS; "
                             f"last {prev!r}){why}")

    def _area_anchor(self) -> float:
        """Where Green's ``F(u, v) = integral_{anchor}^{u} |S_u x S_v| dt`` starts (any constant
        anchor gives the same closed integral). The surface's ``u0``, unless ``|S_u x S_v|`` falls
        below ``tolerances.TRIM_AREA_SINGULAR`` of its largest value somewhere in the parameter box
        (a near-singular point, usually outside the face): then the end of the loops' u range
        farther from that point, so the inner integrals do not cross its kink."""
        (u0, u1), (v0, v1) = self.surface.domain
        gu, gv = np.linspace(u0, u1, 129), np.linspace(v0, v1, 129)
        # the partials on the grid (the basis once per row and column: ~7x faster than point by
        # point, the same to round-off; where two minima tie within round-off, e.g. poles at both
        # ends of u, the first found may change, and the anchor with it: any anchor gives the area)
        D = self.surface.derivatives_grid(gu, gv, 1)
        J = np.linalg.norm(np.cross(D[..., 1, 0, :], D[..., 0, 1, :]), axis=-1).ravel()
        if J.min() >= tolerances.TRIM_AREA_SINGULAR * J.max():
            return float(u0)
        us = np.concatenate([P[:, 0] for P in self.polylines()])
        lo, hi, u_star = float(us.min()), float(us.max()), float(gu[np.argmin(J) // gv.size])
        return lo if abs(lo - u_star) > abs(hi - u_star) else hi

    def _jacobian_range(self) -> tuple[float, float, tuple[float, float]]:
        """Smallest and largest ``|S_u x S_v|`` on a 129 x 129 grid of the face (for messages), and
        where the smallest is."""
        (u0, u1), (v0, v1) = self.surface.domain
        U, W = np.meshgrid(np.linspace(u0, u1, 129), np.linspace(v0, v1, 129), indexing="ij")
        inside = self.classify(U, W) != OUTSIDE
        D = self.surface.derivatives(U[inside], W[inside], 1)
        J = np.linalg.norm(np.cross(D[:, 1, 0], D[:, 0, 1]), axis=-1)
        if J.size == 0:
            return 0.0, 0.0, (float("nan"), float("nan"))
        k = int(np.argmin(J))
        return float(J[k]), float(J.max()), (float(U[inside][k]), float(W[inside][k]))

    # ------------------------------------------------------------------ value semantics
    def transform(self, matrix: ArrayLike, translation: ArrayLike | None = None) -> TrimmedSurface:
        """The face under ``x -> M x + b`` (the surface's control points mapped, loops unchanged).

        A map with ``det M < 0`` (a mirror) turns ``S_u x S_v`` against the mapped outward
        normal, so :attr:`reversed` flips with it.
        """
        s = self.surface.transform(matrix, translation)
        M, _ = V.affine_map(matrix, translation, self.dim)
        flip = self.dim == 3 and float(np.linalg.det(M)) < 0
        return _trusted(s, self.outer, self.inner, self.reversed ^ flip)

    def to_dict(self) -> dict[str, Any]:
        """JSON-safe dict: ``{"type": "TrimmedSurface", "version": 1, "surface": {...},
        "outer": [{...}, ...], "inner": [[{...}, ...], ...], "reversed": bool}``."""
        return {"type": "TrimmedSurface", "version": FORMAT_VERSION, "surface": self.surface.to_dict(),
                "outer": [c.to_dict() for c in self.outer],
                "inner": [[c.to_dict() for c in loop] for loop in self.inner], "reversed": self.reversed}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> TrimmedSurface:
        """Inverse of :meth:`to_dict`, validated by the constructor.

        Raises
        ------
        InvalidGeometryError
            Not a ``TrimmedSurface`` dict, newer version, missing key, or a bad value.
        """
        if not isinstance(data, dict) or data.get("type") != "TrimmedSurface":
            raise InvalidGeometryError(f"from_dict: expected a dict with type 'TrimmedSurface', got {type(data).__name__}")
        if data.get("version", 1) > FORMAT_VERSION:
            raise InvalidGeometryError(f"from_dict: format version {data['version']} is newer than {FORMAT_VERSION}")
        try:
            inner = data.get("inner", [])
            if not isinstance(inner, list) or not isinstance(data["outer"], list):
                raise InvalidGeometryError("from_dict: 'outer' must be a list of curves and 'inner' a list of loops")
            return cls(BSplineSurface.from_dict(data["surface"]),
                       tuple(BSplineCurve.from_dict(c) for c in data["outer"]),
                       tuple(tuple(BSplineCurve.from_dict(c) for c in loop) for loop in inner),
                       bool(data.get("reversed", False)))
        except KeyError as err:
            raise InvalidGeometryError(f"from_dict: missing key {err}") from err

    def __eq__(self, other: object) -> bool:
        """Exact equality of surface, loops (p-curve by p-curve) and orientation."""
        if not isinstance(other, TrimmedSurface):
            return NotImplemented
        return (self.reversed == other.reversed and self.surface == other.surface
                and self.n_edges == other.n_edges
                and all(a == b for la, lb in zip(self.loops, other.loops) for a, b in zip(la, lb)))

    __hash__ = None  # type: ignore[assignment]


def _trusted(surface: BSplineSurface, outer: Loop, inner: tuple[Loop, ...], rev: bool) -> TrimmedSurface:
    """A TrimmedSurface from parts already validated and oriented (no checks)."""
    obj = object.__new__(TrimmedSurface)
    for name, value in (("surface", surface), ("outer", outer), ("inner", inner), ("reversed", bool(rev)),
                        ("_cache", {})):
        object.__setattr__(obj, name, value)
    return obj


# ============================================================================ kernels
def _finite_uv(u: ArrayLike, v: ArrayLike, per_point: int = 8, what: str = "") -> tuple[Array, Array, tuple[int, ...]]:
    """``u, v`` broadcast and flattened; the broadcast shape with ``per_point`` floats per point is
    refused above ``tolerances.MAX_ARRAY_BYTES`` before the flattened copies are made."""
    try:
        a, b = np.asarray(u, dtype=float), np.asarray(v, dtype=float)
        np.broadcast_shapes(a.shape, b.shape)
    except (TypeError, ValueError) as err:
        raise ParameterError(f"u, v: expected real parameters that broadcast together ({err})") from err
    V.check_broadcast(a, b, per_point, what)
    a, b = np.broadcast_arrays(a, b)
    if not (np.all(np.isfinite(a)) and np.all(np.isfinite(b))):
        raise ParameterError("u, v: parameters must be finite")
    return a.reshape(-1), b.reshape(-1), a.shape
