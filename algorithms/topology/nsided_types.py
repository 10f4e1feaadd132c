"""The data of an n-sided hole fill (course §8-3): its input sides, its result and their measurement.

:class:`HoleSide` is one side of the hole (the boundary curve and the neighbour's cross-boundary
derivative), :func:`side_from_surface` makes one from an iso-boundary of a neighbour surface;
:class:`HoleFill` is what :func:`~occsurf.algorithms.topology.nsided.fill_hole` returns and
:class:`FillQuality` what :func:`~occsurf.algorithms.topology.nsided_measure.measure_fill` finds.
All four are re-exported by :mod:`occsurf.algorithms.topology.nsided`, where the construction is
described.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidGeometryError
from ..kernel.curve import BSplineCurve
from ..kernel.surface import BSplineSurface
from .nsided_loops import closest_parameters

__all__ = ["HoleSide", "HoleFill", "FillQuality", "side_from_surface", "boundary_curve"]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class HoleSide:
    """One side of a hole: the boundary curve and the neighbour's cross-boundary derivative.

    Parameters
    ----------
    curve : BSplineCurve
        The boundary, 3-D, oriented along the loop (side ``i`` ends where side ``i+1`` starts).
    cross : BSplineCurve
        Non-rational, on the same domain as ``curve``: the derivative of the neighbour surface
        across the boundary, pointing *into the neighbour* (away from the hole). For a polynomial
        ``curve`` it is 3-D; for a rational one it is the 4-D derivative of the neighbour's
        homogeneous surface ``(w x, w y, w z, w)`` (what :func:`side_from_surface` returns).
    cross2 : BSplineCurve, optional
        The second derivative of the neighbour across the boundary, along the same parameter as
        ``cross`` (3-D, or 4-D homogeneous for a rational ``curve``): the neighbour's curvature
        across the side, which a curvature-continuous (G2) fill matches
        (:func:`.plate_fill.fill_plate` with ``g2``). ``None``: the side carries G1 data only.
    """

    curve: BSplineCurve
    cross: BSplineCurve
    cross2: BSplineCurve | None = None


@dataclass(frozen=True)
class HoleFill:
    """The result of :func:`.nsided.fill_hole`.

    Attributes
    ----------
    patches : list of BSplineSurface
        ``n`` four-sided patches; patch ``i`` has corner ``(0, 0)`` at the start of side ``i``, its
        ``v = 0`` edge on side ``i`` (parameters ``[0, split[i]]``), its ``u = 0`` edge on side
        ``i-1`` (``[split[i-1], 1]`` reversed), its ``u = 1`` edge on internal edge ``i`` and its
        ``(1, 1)`` corner at the centre.
    sides : list of HoleSide
        The input sides reparametrised to ``[0, 1]``.
    split : ndarray, shape (n,)
        Parameter on each side where the internal edge starts (1/2 unless a knot of low continuity
        sits there).
    center : ndarray, shape (3,)
    corner_residual : ndarray, shape (n,)
        At each hole corner: how far (relative) the adjacent side's tangent lies out of the
        neighbour's tangent plane. Zero when the neighbours are G1 to each other at the corner.
    twist_mismatch : ndarray, shape (n,)
        At each hole corner: relative size of the twist incompatibility (0 when the neighbours are
        G2-compatible there; see :mod:`.nsided`, Known limits).
    flat : ndarray of bool, shape (n,)
        Hole corners where the two sides meet tangentially (within
        ``tolerances.FILL_MIN_CORNER_ANGLE`` of 180 degrees): the corner patch has a degenerate
        (180 degree) corner there, its normal defined by continuity (see :func:`.nsided.fill_hole`).
    source : ndarray, shape (n, 3)
        Per side of the fill: ``(input side, t0, t1)``, the part ``[t0, t1]`` (on ``[0, 1]``) of the
        input side it is. The identity unless the input had fewer than 3 sides and was split
        (:func:`.nsided.fill_hole`).
    folds : int or None
        The patches' fold count (:func:`.nsided_measure.fill_folds`), counted while the fill was
        chosen and kept so that it is not counted again; ``None``: not counted yet.
    """

    patches: list[BSplineSurface]
    sides: list[HoleSide]
    split: Array
    center: Array
    corner_residual: Array
    twist_mismatch: Array
    size: float = field(default=1.0)

    method: str = field(default="quads")
    flat: Array = field(default_factory=lambda: np.zeros(0, bool))
    source: Array = field(default_factory=lambda: np.zeros((0, 3)))
    folds: int | None = None

    def locate_input(self, side: int, points: Array) -> tuple[NDArray[np.intp], Array, Array, Array]:
        """:meth:`locate` for points of *input* side ``side`` (the same unless the loop was split):
        each point goes to the nearest of the fill sides that side was split into."""
        rows = np.flatnonzero(self.source[:, 0] == side) if len(self.source) else np.array([side])
        best = self.locate(int(rows[0]), points)
        for r in rows[1:]:
            cand = self.locate(int(r), points)
            take = cand[3] < best[3]
            best = tuple(np.where(take, c, b) for c, b in zip(cand, best))  # type: ignore[assignment]
        return best[0].astype(np.intp), best[1], best[2], best[3]

    def locate(self, side: int, points: Array) -> tuple[NDArray[np.intp], Array, Array, Array]:
        """Which patch, at which ``(u, v)``, carries the points ``(m, 3)`` of side ``side``.

        The side parameter of each point comes from :func:`closest_parameters` (vectorised); patch
        ``side`` covers ``[0, split]`` of the side on its ``v = 0`` edge, patch ``side + 1`` the rest
        on its ``u = 0`` edge (reversed).

        Returns
        -------
        patch : ndarray of intp, shape (m,)
        u, v : ndarray, shape (m,)
        distance : ndarray, shape (m,)
            Distance of each point from the side curve (the caller judges it).
        """
        n = len(self.patches)
        s, dist = closest_parameters(self.sides[side].curve, points)
        sp = float(self.split[side])
        first = s <= sp
        patch = np.where(first, side, (side + 1) % n)
        u = np.where(first, s / sp, 0.0)
        v = np.where(first, 0.0, (1.0 - s) / (1.0 - sp))
        return patch.astype(np.intp), u, v, dist


@dataclass(frozen=True)
class FillQuality:
    """Dense measurements of a fill (:func:`.nsided_measure.measure_fill`).

    Attributes
    ----------
    boundary_gap : ndarray, shape (n,)
        Largest distance between the fill and side ``i`` (model units).
    boundary_angle : ndarray, shape (n,)
        Largest angle (degrees) between the fill's and the neighbour's tangent planes along side ``i``.
    internal_gap, internal_angle : ndarray, shape (n,)
        The same between patches ``i`` and ``i+1`` along internal edge ``i``.
    center_angle : float
        Largest angle (degrees) between the patches' normals at the centre.
    folds : ndarray of intp, shape (n,)
        Per patch, the neighbouring pairs of a 41 x 41 parameter grid whose normals ``S_u x S_v``
        point in opposite directions: a fold (the patch turning back over itself, as the central
        split does on long curved holes such as a crescent or a helical strip). 0 for a sound fill.
    """

    boundary_gap: Array
    boundary_angle: Array
    internal_gap: Array
    internal_angle: Array
    center_angle: float
    folds: NDArray[np.intp] = field(default_factory=lambda: np.zeros(0, np.intp))


def side_from_surface(surface: BSplineSurface, edge: str, reverse: bool = False) -> HoleSide:
    """The hole side along one iso-boundary of a neighbour surface, with its exact cross derivative.

    Parameters
    ----------
    surface : BSplineSurface
        The neighbour (3-D, polynomial or rational; unclamped knots are clamped first).
    edge : {'u0', 'u1', 'v0', 'v1'}
        Which boundary lies on the hole: ``'v0'`` is the curve ``S(u, v_min)``, etc.
    reverse : bool
        Reverse the curve (and field) so that the side runs the right way around the loop.

    Returns
    -------
    HoleSide
        The boundary curve (the row of poles, bit-exact) and the derivative across it pointing into
        the surface (homogeneous for a rational surface), The NURBS Book eq. (3.17) applied to the
        first two rows of homogeneous poles.
    """
    s, H, (p, Kb), (q, Kc) = _boundary_net(surface, edge)
    with np.errstate(over="ignore", invalid="ignore"):  # checked below, by name
        row, cross, cross2 = _start_jet(H, Kc, q)
    curve = _row_curve(s, p, Kb, row)
    if not (np.isfinite(cross).all() and np.isfinite(cross2).all()):  # what the checked constructor refused
        raise InvalidGeometryError(f"surface: the derivatives across its {edge} side overflow (knots too close for "
                                   "its poles)")
    X = BSplineCurve._trusted(p, Kb, cross)  # the surface's own knots and degree: valid as it is
    X2 = BSplineCurve._trusted(p, Kb, cross2)
    if reverse:
        curve, X, X2 = curve.reverse(), X.reverse(), X2.reverse()
    return HoleSide(curve, X, X2)


def boundary_curve(surface: BSplineSurface, edge: str) -> BSplineCurve:
    """The curve of :func:`side_from_surface` (``reverse=False``) alone: the same poles, knots and
    weights, without the cross derivatives (a caller choosing among a surface's four boundaries)."""
    s, H, (p, Kb), _ = _boundary_net(surface, edge)
    return _row_curve(s, p, Kb, H[:, 0])


def _boundary_net(surface: BSplineSurface, edge: str) -> tuple[BSplineSurface, Array, tuple[int, Array],
                                                                 tuple[int, Array]]:
    """``surface`` clamped, its homogeneous net turned so that ``edge`` is the first row of the second
    index (the far rows first and the parameter reflected for ``'u1'``, ``'v1'``), and the degree and
    knots along the edge and across it."""
    if not isinstance(surface, BSplineSurface):
        raise InvalidGeometryError(f"surface: expected a BSplineSurface, got {type(surface).__name__}")
    if edge not in ("u0", "u1", "v0", "v1"):
        raise InvalidGeometryError(f"edge: expected one of 'u0', 'u1', 'v0', 'v1', got {edge!r}")
    if surface.dim != 3:
        raise InvalidGeometryError(f"surface: expected 3-D control points, got dimension {surface.dim}")
    s = surface.clamp()
    H = s.homogeneous_points
    if edge[0] == "u":  # make the boundary direction the first index
        H = np.swapaxes(H, 0, 1)
        (q, p), (Kc, Kb) = s.degree, s.knots
    else:
        (p, q), (Kb, Kc) = s.degree, s.knots
    if edge[1] == "1":  # the far rows first, the parameter reflected: derivatives into the surface
        H, Kc = H[:, ::-1], -Kc[::-1]
    return s, H, (p, Kb), (q, Kc)


def _row_curve(s: BSplineSurface, p: int, Kb: Array, row: Array) -> BSplineCurve:
    """The boundary curve of the homogeneous pole row ``row`` of ``s`` (valid as ``s`` is: its knots
    and degree along the row, its finite poles and positive weights; built unchecked)."""
    if s.is_rational:
        return BSplineCurve._trusted(p, Kb, row[:, :3] / row[:, 3:], row[:, 3])
    return BSplineCurve._trusted(p, Kb, row)


def _start_jet(H: Array, K: Array, q: int) -> tuple[Array, Array, Array]:
    """Rows of poles ``(n, w)`` of ``S(., v0)``, ``S_v(., v0)`` and ``S_vv(., v0)`` of the
    (homogeneous) net ``H`` (n, m, w) of degree ``q`` in ``v`` on the clamped knots ``K``, at their
    start: the derivative poles of The NURBS Book eq. (3.8), applied twice (zero for ``q < 2``)."""
    d1 = q / (K[q + 1] - K[1]) * (H[:, 1] - H[:, 0])
    if q < 2:
        return H[:, 0], d1, np.zeros_like(d1)
    d1b = q / (K[q + 2] - K[2]) * (H[:, 2] - H[:, 1])
    return H[:, 0], d1, (q - 1) / (K[q + 1] - K[2]) * (d1b - d1)
