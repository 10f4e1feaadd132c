"""Measuring an n-sided fill (course §8-3): gaps, tangent-plane angles and folds.

:func:`measure_fill` samples every joint of a :class:`~.nsided_types.HoleFill` densely (the hole
sides against the neighbours' tangent planes, the internal edges between patches, the centre);
:func:`count_folds` counts the neighbouring grid points whose normals point in opposite directions
(a patch turning back over itself), on a surface or on a trimmed face; :func:`fill_folds` sums them
over a fill. Re-exported by :mod:`occsurf.algorithms.topology.nsided`.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from .. import _validate as Val
from .. import tolerances
from ..errors import InvalidGeometryError
from ..kernel.curve import BSplineCurve
from ..kernel.surface import BSplineSurface
from ..kernel.trimmed import TrimmedSurface
from .nsided_poly import angle_deg
from .nsided_types import FillQuality, HoleFill, HoleSide

__all__ = ["measure_fill", "count_folds", "fill_folds"]

Array = NDArray[np.float64]


def _point_normal(surface: BSplineSurface, u: Array, v: Array) -> tuple[Array, Array]:
    """Points and (unnormalised) normals ``S_u x S_v`` from one derivative evaluation.

    Where ``S_u`` and ``S_v`` are parallel (the degenerate corner of a flat hole corner) the normal
    is the limit, taken ``tolerances.FILL_NORMAL_STEP`` (1e-7) of the domain into the patch (angle
    error ~1e-5 deg); a normal still degenerate there is NaN (as :meth:`BSplineSurface.normal`), so
    that it fails every angle check. Degenerate: ``|S_u x S_v|`` at most
    ``tolerances.FILL_DEGENERATE_NORMAL`` times ``|S_u| |S_v|``."""
    degenerate, step = tolerances.FILL_DEGENERATE_NORMAL, tolerances.FILL_NORMAL_STEP
    D = surface.derivatives(u, v, 1)
    nrm = np.cross(D[:, 1, 0], D[:, 0, 1])
    scale = np.linalg.norm(D[:, 1, 0], axis=1) * np.linalg.norm(D[:, 0, 1], axis=1)
    bad = np.linalg.norm(nrm, axis=1) <= degenerate * scale
    if bad.any():
        (u0, u1), (v0, v1) = surface.domain
        ub, vb = np.broadcast_to(u, bad.shape)[bad], np.broadcast_to(v, bad.shape)[bad]
        ub = ub + np.where(ub < 0.5 * (u0 + u1), step, -step) * (u1 - u0)
        vb = vb + np.where(vb < 0.5 * (v0 + v1), step, -step) * (v1 - v0)
        Db = surface.derivatives(ub, vb, 1)
        nb = np.cross(Db[:, 1, 0], Db[:, 0, 1])
        sb = np.linalg.norm(Db[:, 1, 0], axis=1) * np.linalg.norm(Db[:, 0, 1], axis=1)
        nb[~(np.linalg.norm(nb, axis=1) > degenerate * sb)] = np.nan
        nrm[bad] = nb
    return D[:, 0, 0], nrm


def _neighbour_normal(side: HoleSide, s: Array) -> Array:
    """The neighbour's (unnormalised) normals ``B' x X`` along ``side`` at ``s`` (Cartesian ``X`` for a
    rational side, from its homogeneous field)."""
    c = side.curve
    D = c.derivatives(s, 1)
    X = side.cross.evaluate(s)
    if c.is_rational:
        Hs = BSplineCurve._trusted(c.degree, c.knots, c.homogeneous_points).evaluate(s)
        X = (X[:, :3] - X[:, 3:] * (Hs[:, :3] / Hs[:, 3:])) / Hs[:, 3:]
    return np.cross(D[:, 1], X)


def measure_fill(fill: HoleFill, samples: int = 201) -> FillQuality:
    """Measure a fill densely: positional gap and tangent-plane angle along every joint.

    Parameters
    ----------
    fill : HoleFill
    samples : int
        Points per half side / internal edge (plus every knot of the patches' edges).

    Returns
    -------
    FillQuality
    """
    if not isinstance(fill, HoleFill):
        raise InvalidGeometryError(f"fill: expected a HoleFill, got {type(fill).__name__}")
    P, sd, n = fill.patches, fill.sides, len(fill.patches)
    # per sample of a joint: parameters, points, derivatives and normals of the sides and both patches
    t = np.linspace(0.0, 1.0, max(Val.check_count(samples, "samples", 64), 3))
    bg, ba, ig, ia = (np.zeros(n) for _ in range(4))
    for i in range(n):
        k = (i + 1) % n
        tu = np.unique(np.r_[t, P[i].knots[0]])
        tv = np.unique(np.r_[t, P[k].knots[1]])
        s1, s2 = fill.split[i] * tu, 1.0 - (1.0 - fill.split[i]) * tv
        c1, c2 = sd[i].curve.evaluate(s1), sd[i].curve.evaluate(s2)
        (f1, n1), (f2, n2) = _point_normal(P[i], tu, 0.0 * tu), _point_normal(P[k], 0.0 * tv, tv)
        bg[i] = max(np.linalg.norm(f1 - c1, axis=1).max(), np.linalg.norm(f2 - c2, axis=1).max())
        ba[i] = max(angle_deg(n1, _neighbour_normal(sd[i], s1)).max(), angle_deg(n2, _neighbour_normal(sd[i], s2)).max())
        te = np.unique(np.r_[t, P[i].knots[1], P[k].knots[0]])
        (e1, m1), (e2, m2) = _point_normal(P[i], 1.0 + 0 * te, te), _point_normal(P[k], te, 1.0 + 0 * te)
        ig[i] = np.linalg.norm(e1 - e2, axis=1).max()
        ia[i] = angle_deg(m1, m2).max()
    nc = np.array([p.normal(1.0, 1.0) for p in P])
    ca = float(max(angle_deg(nc[0], nc[i]) for i in range(n)))
    return FillQuality(bg, ba, ig, ia, ca, np.array([count_folds(p) for p in P], np.intp))


def count_folds(surface: BSplineSurface | TrimmedSurface, grid: int = 41) -> int:
    """Neighbouring pairs of a ``grid`` x ``grid`` parameter grid of ``surface`` whose normals
    ``S_u x S_v`` point in opposite directions (:attr:`FillQuality.folds`); a degenerate normal (a
    flat hole corner) counts as neither.

    Parameters
    ----------
    surface : BSplineSurface or TrimmedSurface
        For a trimmed surface (a plate fill's :attr:`~.plate_fill.PlateFill.trimmed`) the grid
        spans the trimming loops' parameter box and only pairs with both points on the face
        (:meth:`~occsurf.algorithms.kernel.trimmed.TrimmedSurface.contains`, boundary included)
        count: outside its trim the surface is not part of the face (a plate's height field can
        be steep there, beyond the hole, and those slopes are no fold of the fill). Its grid has
        at least two points per knot span of the box in each direction: one surface spans the
        whole hole there (a plate of 127 x 51 spans), where the central split has ``n`` patches
        of ``grid`` x ``grid`` each, and a ripple a span wide turned its normal by more than 90
        degrees between samples 2e-3 apart on linkrods' faces [22, 26] (10 to 13 pairs on grids of
        121 to 201, none on 41 x 41).
    grid : int
        Grid points per direction (the least, for a trimmed surface).

    Returns
    -------
    int
    """
    trimmed = surface if isinstance(surface, TrimmedSurface) else None
    base: BSplineSurface = surface.surface if isinstance(surface, TrimmedSurface) else surface
    if trimmed is not None:
        uv = np.concatenate([np.asarray(c.evaluate(np.linspace(*c.domain, 65)), float)[:, :2] for c in trimmed.outer])
        (u0, v0), (u1, v1) = uv.min(axis=0), uv.max(axis=0)
        (a0, a1), (b0, b1) = base.domain
        u0, u1, v0, v1 = max(u0, a0), min(u1, a1), max(v0, b0), min(v1, b1)
        ku, kv = (np.unique(k) for k in base.knots)  # at least two grid points per span
        gu = max(grid, 2 * int(np.count_nonzero((ku > u0) & (ku < u1))) + 3)
        gv = max(grid, 2 * int(np.count_nonzero((kv > v0) & (kv < v1))) + 3)
    else:
        (u0, u1), (v0, v1) = base.domain
        gu = gv = grid
    # per grid point: meshgrids, derivatives (homogeneous, flattened, result), normals and the trim test
    Val.check_size((gu, gv, 40), f"grid = {grid}: a {gu} x {gv} grid")
    us, vs = np.linspace(u0, u1, gu), np.linspace(v0, v1, gv)
    D = base.derivatives_grid(us, vs, 1)  # tensor-product partials: ~30x cheaper than scattered
    N = np.cross(D[:, :, 1, 0], D[:, :, 0, 1])
    length = np.linalg.norm(N, axis=2)
    # a degenerate point (flat hole corner) has no side
    N[length <= tolerances.FILL_FOLD_DEGENERATE * np.median(length)] = 0.0
    du = np.einsum("ijk,ijk->ij", N[1:], N[:-1]) < 0
    dv = np.einsum("ijk,ijk->ij", N[:, 1:], N[:, :-1]) < 0
    if trimmed is not None and (du.any() or dv.any()):  # only pairs on the face (none to sort: 0 either way)
        inside = trimmed.contains(*np.meshgrid(us, vs, indexing="ij"))
        du &= inside[1:] & inside[:-1]
        dv &= inside[:, 1:] & inside[:, :-1]
    return int(du.sum() + dv.sum())


def fill_folds(fill: Any) -> int:
    """Folds of a fill (:func:`count_folds`): summed over a :class:`HoleFill`'s patches; for a fill
    that is one trimmed surface (a :class:`~.plate_fill.PlateFill`: its ``trimmed`` attribute),
    counted on the face only, inside its trim."""
    kept = getattr(fill, "folds", None)
    if kept is not None:  # counted as the fill was made (the same count_folds on the same surfaces)
        return int(kept)
    trimmed = getattr(fill, "trimmed", None)
    if isinstance(trimmed, TrimmedSurface):
        return count_folds(trimmed)
    return sum(count_folds(p) for p in fill.patches)
