"""Filling an n-sided hole with G1 continuity (course §8-3, the n-sided hole problem).

Given ``n >= 3`` boundary curves forming a closed loop (the free edges of the faces around a hole)
and, along each, the neighbour face's cross-boundary derivative, :func:`fill_hole` builds ``n``
tensor-product (rational) B-spline patches that

* interpolate every boundary curve exactly (the boundary row of poles *is* the curve, refined and
  degree-raised: round-off only), multi-span and rational curves included;
* are G1 to the neighbour along the whole boundary, by a polynomial identity (below), not at samples;
* are G1 to each other along the internal edges, again by a polynomial identity, and share one
  tangent plane at the centre.

The choice: a central split into four-sided patches
---------------------------------------------------
A single S-patch (Loop & DeRose 1989) has Bézier sides of one degree, while CAD boundaries are
multi-span, often rational B-splines. Splitting the sides at their knots into extra (straight)
sides makes the S-patch singular at every straight corner (its tangent plane there is spanned by
two collinear edge tangents) and the number of control points explodes (``C(d+N-1, N-1)`` for ``N``
spans). We therefore decompose the hole, as the course suggests for n-sided regions (§8-3, the
Sabin/Gregory "central split" into n quadrilaterals; also the NURBS Book §10 on G1 joins): the
centre ``C`` is joined to a point ``m_i`` on every side, giving ``n`` four-sided patches; patch
``i`` covers hole corner ``V_i`` and is bounded by the first part of side ``i``, the last part of
side ``i-1`` and the internal edges ``E_i`` (``m_i -> C``) and ``E_{i-1}``. A four-sided patch is
a four-sided S-patch (a tensor product; for one span a Bézier patch of bidegree ``(d, d)``), and a
tensor product carries a multi-span rational boundary exactly: its u-knots are the side's knots.

Boundary G1 by construction. Work in homogeneous coordinates (``R^4`` for rational data, ``R^3``
otherwise). Along side ``i`` with boundary ``B(s)`` and neighbour cross-derivative ``X(s)`` the
patch's cross-boundary derivative is set to::

    F_v(u, 0) = sum_f c_f(u) f(s(u)),   f in {X, B', B (rational only)}

with cubic polynomials ``c_f``. Its poles are computed exactly in the patch's knot space (the
product of a spline and a polynomial is a spline on the same knots, multiplicity raised). Then
``span(F, F_u, F_v) = span(B, B', X)`` identically in ``u``: the projected tangent planes coincide
at every point of the boundary (provided ``c_X != 0``; it is checked to stay negative, pointing into
the hole). This is the classical ribbon (G1 "transversal vector field") construction.

Internal G1 by construction. Along ``E_i`` the two cross derivatives ``L`` (patch ``i``) and
``R`` (patch ``i+1``) satisfy ``a(t) L + b(t) R = r(t) E'(t)`` with ``a, b`` linear, ``r``
quadratic, taken from a *domain picture*: a regular n-gon split into kites, whose bilinear
parametrisations satisfy the same relation exactly. ``L = b Z + l E'``, ``R = -a Z + m E'`` with
``a l + b m = r`` make it a polynomial identity. Corner compatibility (the twists at ``V_i``,
``m_i`` and ``C``) fixes the end derivatives of the ``c_f``; the centre data come from one affine
map of the domain, so the ``n`` twists there agree. The remaining interior poles minimise the
thin-plate energy ``int |F_uu|^2 + 2|F_uv|^2 + |F_vv|^2``.

Flat corners, round holes, slivers. A corner where the two sides are tangent (180 degrees, within
``tolerances.FILL_MIN_CORNER_ANGLE``) gets a corner patch with a degenerate corner: the ribbon's
cross-field coefficient is 0 there and grows linearly (the twist is solved for the rest), so the
normal tends to the neighbour's and G1 holds up to that one point. This lets a loop of one side (a
round hole) or two (a slot end) be cut at arc-length points into four sides (S-patch-style central
split of a smooth loop). Where the midpoints' mean lies outside the hole (a crescent, a tapering
sliver), the centre is moved to the preimage of the domain's centre under a harmonic map of the hole
onto the domain (the point farthest from the boundary if that map cannot be built) and internal
edges that would leave the hole leave their side at 30 degrees (``tolerances.FILL_MIN_EDGE_ANGLE``)
instead. A fill that folds (:func:`count_folds`, :attr:`FillQuality.folds`: a long curved hole, a
sliver) is rebuilt on the harmonic layout (:func:`.nsided_centre.harmonic_layout`): centre,
internal-edge directions and lengths at the midpoints, and the centre's tangent map all from that
one-to-one map, so the internal edges follow the hole instead of cutting across it; the fill with
fewer folds is kept. Very long thin curved holes (a sector whose middle arc is more than ~12 times
its width) still fold near their internal edges, and :func:`measure_fill` says so.

Known limits (reported, never hidden): at a hole corner the twist is over-determined when the two
neighbours are only G1 (not G2) to each other there (Gregory's twist incompatibility): its normal
component is then averaged and G1 holds up to :attr:`HoleFill.twist_mismatch` near that corner.
A side with a C0 knot (a kink, no tangent) is refused; split the side there. A reflex corner
(interior angle above 180 degrees) would fold the corner patch and is refused, as is a cusp and a
loop that crosses or touches itself.

Where the parts are
-------------------
This module holds :func:`fill_hole`, which runs the steps, and re-exports the public names. The
data (:class:`HoleSide`, :func:`side_from_surface`, :class:`HoleFill`, :class:`FillQuality`) are in
:mod:`.nsided_types`; step 0, the sides checked and in working coordinates, in
:mod:`.nsided_prepare`; the kite domain picture and the internal edges (steps 1 and 4) in
:mod:`.nsided_edges`; the hole corners (step 2) in :mod:`.nsided_corners`; the midpoints, the
centre and the harmonic layout (step 3) in :mod:`.nsided_centre`; the corner patches and their
fairing (step 5) in :mod:`.nsided_patches`; the measurements (:func:`measure_fill`,
:func:`count_folds`, :func:`fill_folds`) in :mod:`.nsided_measure`. :mod:`.nsided_poly` has the
polynomials and exact spline representations they share, :mod:`.nsided_loops` the checks and maps
of the hole's boundary loop, :mod:`.nsided_sides` the sides of trimmed neighbours. Tolerances and
limits are read at call time from :mod:`occsurf.algorithms.tolerances` (the ``FILL_`` names).

References
----------
Course C25 §8-3 (n-sided holes), §8-5 (Sabin nets). C. Loop, T. DeRose, "A multisided
generalization of Bézier surfaces", ACM ToG 8 (1989). J. Gregory, "N-sided surface patches" (1986).
L. Piegl, W. Tiller, The NURBS Book, 2nd ed., 1997, A2.3 (derivatives), §10 (G1 joins).
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from typing import Literal, overload

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidGeometryError
from ..kernel.surface import BSplineSurface
from .nsided_centre import centre, centre_map, harmonic_boundary, harmonic_layout, midpoints, outward_ribbons
from .nsided_corners import CornerFit, check_inward, corner_analysis
from .nsided_edges import domain_picture, internal_edge
from .nsided_loops import closest_parameters
from .nsided_measure import count_folds, fill_folds, measure_fill
from .nsided_patches import FairSystems, corner_patch, patch_poles
from .nsided_poly import cart
from .nsided_prepare import choose_split, split_short_loop, working_sides
from .nsided_types import FillQuality, HoleFill, HoleSide, boundary_curve, side_from_surface
from .plate_fill import PlateFill, fill_plate

__all__ = [
    "HoleSide",
    "HoleFill",
    "FillQuality",
    "side_from_surface",
    "boundary_curve",
    "closest_parameters",
    "fill_hole",
    "fold_free_fill",
    "CONTINUITIES",
    "measure_fill",
    "count_folds",
    "fill_folds",
]

Array = NDArray[np.float64]

#: The continuities :func:`fill_hole` (and the bridge's fills and refills) take: tangent (``'G1'``)
#: or curvature (``'G2'``) continuous to the neighbours.
CONTINUITIES: tuple[str, ...] = ("G1", "G2")


@overload
def fill_hole(sides: Sequence[HoleSide], continuity: Literal["G1"] = ...) -> HoleFill: ...
@overload
def fill_hole(sides: Sequence[HoleSide], continuity: Literal["G2"]) -> PlateFill: ...
@overload
def fill_hole(sides: Sequence[HoleSide], continuity: str) -> HoleFill | PlateFill: ...


def fill_hole(sides: Sequence[HoleSide], continuity: str = "G1") -> HoleFill | PlateFill:
    """Fill an n-sided hole: G1 with n four-sided patches, G1 to the neighbours and to each other;
    G2 with one curvature-continuous plate.

    Parameters
    ----------
    sides : sequence of HoleSide, length n (1 to ``tolerances.FILL_MAX_SIDES``)
        The hole's boundary in loop order, each with the neighbour's cross derivative
        (:func:`side_from_surface` builds them from neighbour surfaces). One closed side (a round
        hole) is cut at the quarters of its arc length, two sides (a slot end) at their halves
        (:attr:`HoleFill.source` maps the fill's sides back).
    continuity : {'G1', 'G2'}
        ``'G1'`` (default): the central split below. ``'G2'`` (issue 31; course §8-3): curvature
        continuous to the neighbour on every side, by the thin plate with second-order boundary
        data (:func:`.plate_fill.fill_plate` with ``g2`` on every side): each side must then carry
        the neighbour's second cross derivative (``HoleSide.cross2``; :func:`side_from_surface`
        gives it exactly), and the hole must be a height field over some plane. The plate's
        :attr:`~.plate_fill.PlateFill.side_g2` holds the relative curvature jump reached per side.

    Returns
    -------
    HoleFill or PlateFill
        G1: the patches (rational if any side is) and the corner diagnostics. G2: the plate, its
        trimmed face and what it reached per side (G0, G1, G2, the corners' curvature mismatch).

    Raises
    ------
    InvalidGeometryError
        ``continuity`` not one of :data:`CONTINUITIES`; with ``'G2'``, a side without ``cross2`` or a
        hole that is no height field over any plane tried (the plate's reasons). G1: no side, a loop that is not closed (``tolerances.FILL_CLOSURE_TOL``), a degenerate cross
        field (``tolerances.FILL_MIN_CORNER_ANGLE``; a neighbour's pole at a corner), neighbours
        meeting at a sharp edge at a corner
        (``tolerances.FILL_CORNER_PLANE_TOL``), a kink inside a side, or a fill that would turn back
        over the neighbour (cross field pointing into the hole).

    Notes
    -----
    Flat corners (the sides tangent there, within ``tolerances.FILL_MIN_CORNER_ANGLE``: the cuts of
    a round hole, or sides a caller did not merge) get a corner patch whose corner is degenerate
    (its two boundary tangents opposite): the ribbon's cross-field coefficient is 0 there and grows
    linearly into the side (its derivative is set to the midpoint's value, the twist solved for the
    rest), so the patch's normal tends to the neighbour's as the corner is approached and G1 holds
    along the whole side; OCC's LocalAnalysis reports no normal at that one point.

    Construction in the module docstring (course §8-3; central split with G1 ribbons). The steps:
    the sides in working coordinates (:func:`.nsided_prepare.working_sides`), where each is split
    (:func:`.nsided_prepare.choose_split`), the kite domain picture
    (:func:`.nsided_edges.domain_picture`), the ribbon coefficients at the hole corners
    (:func:`.nsided_corners.corner_analysis`), the side midpoints and the centre
    (:func:`.nsided_centre.midpoints`, :func:`.nsided_centre.centre`), the centre's tangent map
    (:func:`.nsided_centre.centre_map`), the internal edges with their cross fields
    (:func:`.nsided_edges.internal_edge`) and, last, one patch per hole corner
    (:func:`.nsided_patches.corner_patch`).
    """
    if continuity not in CONTINUITIES:
        raise InvalidGeometryError(f"continuity: expected one of {', '.join(CONTINUITIES)}, got {continuity!r}")
    if continuity == "G2":
        sides = list(sides)
        missing = [i for i, sd in enumerate(sides) if isinstance(sd, HoleSide) and sd.cross2 is None]
        if missing:
            raise InvalidGeometryError(
                f"sides{missing}: continuity 'G2' needs each side's second cross derivative (cross2), "
                "e.g. from side_from_surface; these have none")
        return fill_plate(sides, g2=[True] * len(sides))
    fill = _central_split(sides, stop_at_fold=False)
    assert fill is not None  # only a search stopped at a fold gives none
    return fill


def fold_free_fill(sides: Sequence[HoleSide]) -> HoleFill | None:
    """:func:`fill_hole`'s G1 fill where it has no folds, else ``None``: for a caller that has other
    candidates and prefers any fold-free fill to a folding one (the refill's choice,
    :func:`occsurf.bridge.modeling.refill_candidates.fitted_fill`), which then need not be built.

    The same construction as :func:`fill_hole` (the same patches bit for bit, the same exceptions),
    but each layout's patches are built smallest first and a layout is given up at its first
    folding patch: a fill is returned only when one layout has no fold, which is when
    :func:`fill_hole` returns a fold-free fill. The layouts share their patches' fairing factors
    (:class:`.nsided_patches.FairSystems`). Rational sides build every patch, as :func:`fill_hole`
    does: a later patch may still refuse with a non-positive weight.

    Linkrods face 20's trace-following sides (patches of 15 000 to 65 000 poles) fold in the smallest
    patch of both layouts: 0.17 s where :func:`fill_hole` takes 3.1 s (its layouts sharing their
    factors) for the same answer; faces 22, 35 and 33: 1.4, 1.2, 0.3 s against 5.1, 5.7, 2.3 s.

    Raises
    ------
    InvalidGeometryError
        As :func:`fill_hole` with ``continuity='G1'``.
    """
    return _central_split(sides, stop_at_fold=True)


def _central_split(sides: Sequence[HoleSide], stop_at_fold: bool) -> HoleFill | None:
    """The central split of :func:`fill_hole` (G1); with ``stop_at_fold`` :func:`fold_free_fill`."""
    unit, S, rational, size, origin = working_sides(sides)
    source = np.array([(k, 0.0, 1.0) for k in range(len(unit))])
    if len(unit) < 3:  # a round hole or a slot end: four sides meeting at flat corners
        split, source = split_short_loop(unit)
        unit, S, rational, size, origin = working_sides(split)
    n = len(S)
    sig = np.array([choose_split(sd) for sd in S])
    for sd, t in zip(S, sig):  # the corners and the split point: asked about by every layout
        sd.prime(np.array([0.0, t, 1.0]))
    vdom, pdom = domain_picture(sig)
    mid = midpoints(S, sig, rational)

    @functools.cache
    def loop_picture() -> tuple[Array, tuple[Array, Array]]:
        """The loop's points and its harmonic picture, for a hole that may not be convex (the
        centre) or whose plain layout folds: made only then (1 ms of a 3-sided fill's ~30)."""
        loop = np.concatenate([cart(sd.B.evaluate(np.linspace(0.0, 1.0, 49)[:-1]), rational) for sd in S])
        return loop, harmonic_boundary(S, sig, vdom, pdom, rational)

    systems = FairSystems()  # the layouts' patches share their spaces, so their fairing factors
    stop = stop_at_fold and not rational  # a rational patch may refuse (its weights) after a fold

    def build(C: Array, c1: Array, DPhi: Array) -> tuple[list[BSplineSurface], CornerFit, int] | None:
        """The layout's patches, corners and folds; ``None`` at the first fold when stopping."""
        corners = corner_analysis(S, sig, rational, c1)
        check_inward(corners, c1)
        Ch = np.r_[C, 1.0] if rational else C
        edges = [internal_edge(i, vdom, pdom, sig[i], mid, c1[i], Ch, DPhi) for i in range(n)]
        order = sorted(range(n), key=lambda i: patch_poles(i, S, sig, corners)) if stop else range(n)
        patches: list[BSplineSurface | None] = [None] * n
        folds = 0
        for i in order:
            patch = patches[i] = corner_patch(i, S, sig, corners, c1, edges, rational, origin, systems)
            folds += count_folds(patch)
            if stop and folds:
                return None
        return [p for p in patches if p is not None], corners, folds

    # The plain layout first (midpoints' mean; a convex hole keeps its fill), then, if it folds or is
    # refused, the harmonic layout (a long curved hole, a sliver); the fill with fewer folds is kept.
    C, c1 = centre(mid, rational)  # the midpoints' mean: kept where every ribbon points into the hole
    if outward_ribbons(c1):  # centre's own test of a hole that may not be convex: its loop decides
        loop, hb = loop_picture()
        C, c1 = centre(mid, rational, loop, hb)
    err: InvalidGeometryError | None = None
    best: tuple[list[BSplineSurface], CornerFit, int, Array] | None = None
    folded = False  # a layout given up at its first fold (stop_at_fold; it would have been a folding fill)
    try:
        plain = build(C, c1, centre_map(C, mid.cart, pdom, rational))
        folded = plain is None
        best = None if plain is None else (*plain, C)
    except InvalidGeometryError as e:
        err = e
    if best is None or best[2] > 0:
        layout = harmonic_layout(mid, rational, loop_picture()[1], pdom)
        if layout is not None:
            try:
                harmonic = build(*layout)
                folded = folded or harmonic is None
                if harmonic is not None and (best is None or harmonic[2] < best[2]):
                    best = (*harmonic, layout[0])
            except InvalidGeometryError:
                pass
    if best is None:
        if folded:  # fill_hole would return a layout that folds
            return None
        raise err if err is not None else InvalidGeometryError("sides: no layout of the central split could be built")
    patches, corners, folds, C = best
    if stop_at_fold and folds:  # rational sides: every patch was built
        return None
    return HoleFill(patches, unit, sig, C + origin, corners.residual, corners.twist, size, flat=corners.flat,
                    source=source, folds=int(folds))
