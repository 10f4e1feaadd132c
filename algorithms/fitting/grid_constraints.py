"""Constraints of a gridded fit (course §7-7, §3-12): what they are and their matrix rows.

The constraint types of :func:`.gridded.fit_grid` (:class:`BoundaryCurve`, :class:`CrossDerivative`,
:class:`Symmetry`: separable, acting on one pole index; :class:`FixedPoint`, :class:`TangentPlane`:
point-wise rows ``w^T (α^T P β)``), and :func:`build_rows`, which turns a list of them into
:class:`Rows` over the fit's spline space (:class:`Space`). How they are solved is in
:mod:`.gridded`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import _validate as V
from ..errors import InvalidGeometryError, ParameterError
from ..kernel.basis import basis_matrix, greville
from ..kernel.curve import BSplineCurve
from .interpolation import _lsq_operator

__all__ = ["BoundaryCurve", "CrossDerivative", "FixedPoint", "TangentPlane", "Symmetry", "Constraint", "SIDES",
           "Rows", "Space", "build_rows", "stack_rows"]

Array = NDArray[np.float64]
#: The four sides of a fit, as the constraints name them.
SIDES = ("u0", "u1", "v0", "v1")


# ----------------------------------------------------------------------------- constraints
def _side(side: str) -> str:
    if side not in SIDES:
        raise ParameterError(f"side: expected one of {', '.join(SIDES)}, got {side!r}")
    return side


@dataclass(frozen=True)
class BoundaryCurve:
    """The surface's boundary on ``side`` equals ``curve`` exactly (separable: one pole row fixed).

    ``curve`` must lie in the surface's spline space along that side (same degree; its knots are
    those of the fit, or a subset that is refined to them). ``None``: the boundary data row is
    fitted first (least squares with both ends interpolated, so the four boundary curves meet at
    the data corners), then held.
    """

    side: str
    curve: BSplineCurve | None = None


@dataclass(frozen=True)
class CrossDerivative:
    """The first two pole rows at ``side`` are ``rows`` (shape ``(2, N, d)``): the surface joins a
    neighbour with the same knots C1 (separable). ``rows[0]`` is the boundary row."""

    side: str
    rows: ArrayLike


@dataclass(frozen=True)
class FixedPoint:
    """``S(u, v) = point`` (a point-wise constraint, ``d`` rows)."""

    u: float
    v: float
    point: ArrayLike


@dataclass(frozen=True)
class TangentPlane:
    """Tangent planes along a boundary: ``normals[k]·dS/dn(params[k]) = 0`` where ``dS/dn`` is the
    derivative across ``side`` (G1 to a neighbour whose normals these are, at the sites). Where
    ``normals[k]`` is also perpendicular to the boundary's tangent (a neighbour's normal along a
    shared boundary held by :class:`BoundaryCurve`), the surface's normal equals it there."""

    side: str
    params: ArrayLike
    normals: ArrayLike


@dataclass(frozen=True)
class Symmetry:
    """Mirror symmetry across the middle of ``direction``: ``S(lo + hi - u, v) = M S(u, v)`` for
    ``direction="u"``, ``M`` the reflection in the plane ``x[axis] = offset`` (``axis=None``: the
    identity, e.g. for a symmetric height field). Needs knots symmetric about the middle."""

    direction: str = "u"
    axis: int | None = None
    offset: float = 0.0


Constraint = BoundaryCurve | CrossDerivative | FixedPoint | TangentPlane | Symmetry


# ----------------------------------------------------------------------------- building the constraints
@dataclass
class Rows:
    """Constraints in matrix form: per coordinate the separable rows, and the point-wise rows."""

    cu: list[list[tuple[Array, Array]]]  # per coordinate: (row on the u index (Nu,), target over v (Nv,))
    cv: list[list[tuple[Array, Array]]]
    alpha: list[Array] = field(default_factory=list)  # point-wise: (Nu,)
    beta: list[Array] = field(default_factory=list)  # (Nv,)
    w: list[Array] = field(default_factory=list)  # (d,) weights of the free coordinates
    target: list[float] = field(default_factory=list)
    labels: list[str] = field(default_factory=list)


class Space:
    """The fit's spline space and data layout, shared by the constraint builders."""

    def __init__(self, Q: Array, heights: bool, u: Array, v: Array, deg: tuple[int, int], tu: Array, tv: Array):
        self.Q, self.heights, self.u, self.v = Q, heights, u, v
        self.deg, self.knots = deg, (tu, tv)
        self.n = (tu.shape[0] - deg[0] - 1, tv.shape[0] - deg[1] - 1)
        self.d = Q.shape[2]
        self.greville = (greville(tu, deg[0]), greville(tv, deg[1]))

    def basis(self, ax: int, x: float, order: int = 0) -> Array:
        t, p, n = self.knots[ax], self.deg[ax], self.n[ax]
        lo, hi = t[p], t[n]
        xx = V.check_parameter(x, lo, hi, "uv"[ax])
        return basis_matrix(t, p, n, np.array([xx]), order)[order, 0]

    def fixed_poles(self) -> list[Array]:
        """Height grids: the x and y pole arrays (Greville abscissae), which reproduce ``x = u``, ``y = v``."""
        gu, gv = self.greville
        Nu, Nv = self.n
        return [np.broadcast_to(gu[:, None], (Nu, Nv)), np.broadcast_to(gv[None, :], (Nu, Nv))]

    def free(self, vec: ArrayLike, name: str) -> Array:
        """The free coordinates of a 3-D (or d-D) point: z of a height grid."""
        a = V.as_finite_array(vec, name, ndim=1)
        if self.heights:
            if a.shape[0] not in (1, 3):
                raise InvalidGeometryError(f"{name}: expected 1 value (z) or 3 (x, y, z) for height data, got {a.shape[0]}")
            return a[-1:]
        if a.shape[0] != self.d:
            raise InvalidGeometryError(f"{name}: expected {self.d} coordinates, got {a.shape[0]}")
        return a


def _side_axis(side: str) -> tuple[int, int]:
    """(axis of the index the side fixes: 0 = a u-row, 1 = a v-column; 0 at the start, -1 at the end)."""
    return (0 if side[0] == "u" else 1), (0 if side[1] == "0" else -1)


def _curve_poles(space: Space, curve: BSplineCurve, ax_along: int, name: str) -> Array:
    p, t = space.deg[ax_along], space.knots[ax_along]
    if not isinstance(curve, BSplineCurve) or curve.is_rational:
        raise InvalidGeometryError(f"{name}: expected a non-rational BSplineCurve, got {type(curve).__name__}")
    if curve.degree != p:
        raise InvalidGeometryError(f"{name}: expected degree {p} (the surface's along that side), got {curve.degree}")
    c = curve
    if c.knots.shape != t.shape or not np.allclose(c.knots, t, rtol=0, atol=1e-12 * (t[-1] - t[0])):
        extra = np.setdiff1d(np.round(t, 12), np.round(c.knots, 12))
        try:
            c = c.refine(t[np.isin(np.round(t, 12), extra)]) if extra.size else c
        except InvalidGeometryError as err:
            raise InvalidGeometryError(f"{name}: its knots are not a subset of the fit's knots along that side") from err
        if c.knots.shape != t.shape or not np.allclose(c.knots, t, rtol=0, atol=1e-12 * (t[-1] - t[0])):
            raise InvalidGeometryError(f"{name}: its knots are not a subset of the fit's knots along that side")
    P = np.asarray(c.control_points)
    if space.heights:
        return P[:, -1:]
    if P.shape[1] != space.d:
        raise InvalidGeometryError(f"{name}: expected a {space.d}-D curve, got {P.shape[1]}-D")
    return P


def _boundary_row(space: Space, side: str) -> Array:
    """Poles of the boundary curve fitted to the data row on ``side`` (ends interpolated)."""
    ax, end = _side_axis(side)
    along = 1 - ax
    row = space.Q[end] if ax == 0 else space.Q[:, end]
    if np.isnan(row).any():
        raise InvalidGeometryError(f"fix_boundary: the data row on side {side} has missing (NaN) cells")
    t = space.u if along == 0 else space.v
    F = _lsq_operator(t, space.deg[along], space.knots[along], space.n[along])
    return F @ row


def _separable(space: Space, c: Constraint, rows: Rows, k: int) -> None:
    Nu, Nv = space.n
    if isinstance(c, (BoundaryCurve, CrossDerivative)):
        side = _side(c.side)
        ax, end = _side_axis(side)
        N = space.n[ax]
        if isinstance(c, BoundaryCurve):
            targets = [_boundary_row(space, side) if c.curve is None else
                       _curve_poles(space, c.curve, 1 - ax, f"constraints[{k}].curve")]
        else:
            R = V.as_finite_array(c.rows, f"constraints[{k}].rows")
            want = (2, space.n[1 - ax], 3 if space.heights else space.d)
            if R.shape != want:
                raise InvalidGeometryError(f"constraints[{k}].rows: expected shape {want}, got {R.shape}")
            targets = [r[:, -1:] if space.heights else r for r in R]
        for depth, tgt in enumerate(targets):
            e = np.zeros(N)
            e[depth if end == 0 else N - 1 - depth] = 1.0
            for co in range(space.d):
                (rows.cu if ax == 0 else rows.cv)[co].append((e, tgt[:, co]))
    elif isinstance(c, Symmetry):
        if c.direction not in ("u", "v"):
            raise ParameterError(f"constraints[{k}].direction: expected 'u' or 'v', got {c.direction!r}")
        ax = 0 if c.direction == "u" else 1
        t, p, N = space.knots[ax], space.deg[ax], space.n[ax]
        if not np.allclose(t[::-1], t[p] + t[N] - t, rtol=0, atol=1e-9 * (t[N] - t[p])):
            raise InvalidGeometryError(f"constraints[{k}]: symmetry in {c.direction} needs knots symmetric about the "
                                       "middle of the domain (symmetric data parameters)")
        if c.axis is not None and (space.heights or not 0 <= int(c.axis) < space.d):
            raise InvalidGeometryError(f"constraints[{k}].axis: expected None for height data or 0..{space.d - 1}, "
                                       f"got {c.axis!r}")
        other = space.n[1 - ax]
        for co in range(space.d):
            s = -1.0 if (c.axis is not None and co == int(c.axis)) else 1.0
            for i in range(N // 2 + (N % 2 if s < 0 else 0)):
                e = np.zeros(N)
                e[N - 1 - i] += 1.0
                e[i] -= s
                (rows.cu if ax == 0 else rows.cv)[co].append((e, np.full(other, (1 - s) * float(c.offset))))


def _pointwise(space: Space, c: Constraint, rows: Rows, k: int) -> None:
    fixed = space.fixed_poles() if space.heights else []
    if isinstance(c, FixedPoint):
        a, b = space.basis(0, c.u), space.basis(1, c.v)
        pt = space.free(c.point, f"constraints[{k}].point")
        for co in range(space.d):
            w = np.zeros(space.d)
            w[co] = 1.0
            rows.alpha.append(a)
            rows.beta.append(b)
            rows.w.append(w)
            rows.target.append(float(pt[co]))
            rows.labels.append(f"constraints[{k}] (point at u={c.u:g}, v={c.v:g}, coordinate {co})")
    elif isinstance(c, TangentPlane):
        side = _side(c.side)
        ax, end = _side_axis(side)
        t = V.as_finite_array(c.params, f"constraints[{k}].params", ndim=1)
        nrm = V.as_finite_array(c.normals, f"constraints[{k}].normals")
        if nrm.shape != (t.shape[0], 3) or (not space.heights and space.d != 3):
            raise InvalidGeometryError(f"constraints[{k}].normals: expected shape ({t.shape[0]}, 3) on a 3-D fit, "
                                       f"got {nrm.shape}")
        kn, p, n = space.knots[ax], space.deg[ax], space.n[ax]
        x0 = kn[p] if end == 0 else kn[n]
        for s, nv in zip(t, nrm):
            cross = space.basis(ax, x0, 1)
            along = space.basis(1 - ax, s, 0)
            a, b = (cross, along) if ax == 0 else (along, cross)
            tgt = 0.0
            if space.heights:  # x = u, y = v are fixed: their share moves to the target
                tgt -= nv[0] * float(a @ fixed[0] @ b) + nv[1] * float(a @ fixed[1] @ b)
                w = nv[2:3].copy()
            else:
                w = nv.copy()
            rows.alpha.append(a)
            rows.beta.append(b)
            rows.w.append(w)
            rows.target.append(tgt)
            rows.labels.append(f"constraints[{k}] (tangent plane on side {side} at {s:g})")


def build_rows(space: Space, constraints: Sequence[Constraint], fix_boundary: bool) -> Rows:
    rows = Rows([[] for _ in range(space.d)], [[] for _ in range(space.d)])
    items = list(constraints)
    if fix_boundary:
        items = [BoundaryCurve(s) for s in SIDES] + items
    for k, c in enumerate(items):
        if isinstance(c, (BoundaryCurve, CrossDerivative, Symmetry)):
            _separable(space, c, rows, k)
        elif isinstance(c, (FixedPoint, TangentPlane)):
            _pointwise(space, c, rows, k)
        else:
            raise InvalidGeometryError(f"constraints[{k}]: expected BoundaryCurve, CrossDerivative, FixedPoint, "
                                       f"TangentPlane or Symmetry, got {type(c).__name__}")
    return rows


def stack_rows(items: list[tuple[Array, Array]]) -> tuple[Array, Array] | None:
    if not items:
        return None
    return np.stack([r for r, _ in items]), np.stack([t for _, t in items])


# ----------------------------------------------------------------------------- solvers
