"""Curvature-continuous (G2) refills of a model's hole (issue 31; course §8-3, ch. 9): which edges the
removed faces met curvature continuously, the neighbours' second cross derivative along the fitted
sides, and the G2 plate.

A refill asked ``continuity='G2'`` (:func:`occsurf.bridge.modeling.refill.refill_faces`) keeps, per
edge, the continuity the removed faces had: an edge whose removed face met its neighbour within
``G2_REL`` (CATIA's 2 % curvature jump, the check's ``catia`` preset) is asked G2
(:func:`original_g2`), the others G1 as before. A side's neighbour is known from OCC only along the
edge (the fitted sides of :mod:`.refill_sides`: a boundary curve and a cross field ``X`` fitted to
the neighbour's normals), so its second cross derivative is sampled (:func:`with_cross2`): at each
sample the direction ``d`` in the neighbour's parameter plane with ``S_u d_1 + S_v d_2 = X`` is
solved, and ``G_tt = S_uu d_1^2 + 2 S_uv d_1 d_2 + S_vv d_2^2`` is the second derivative of
``S(pcurve + t d)``, the parametrisation whose first cross derivative is the fitted field; these
are fitted by a cubic spline along the side (least squares). The fill is then the plate with G2 on
those sides (:func:`occsurf.algorithms.topology.plate_fill.fill_plate`).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from OCP.BRep import BRep_Tool
from OCP.gp import gp_Pnt, gp_Vec

from occsurf.algorithms.errors import InvalidGeometryError
from occsurf.algorithms.kernel.curve import BSplineCurve
from occsurf.algorithms.topology.nsided import HoleSide, closest_parameters

from .joints import assess_curvature, edge_samples

__all__ = ["G2_REL", "original_g2", "with_cross2", "g2_fill", "edge_classes", "shortfall"]

#: An edge the removed face met within this relative curvature jump is refilled G2 (CATIA's
#: Connect Checker default, 2 %: the check's ``catia`` preset).
G2_REL: float = 0.02
_SAMPLES_PER_EDGE = 64


def edge_classes(side_g1: list[float | None], side_g2: list[float | None]) -> list[str]:
    """Per edge, the continuity a fill reached (``'G2'``, ``'G1'`` or ``'G0'``), by the rules that
    classify the original model's joints for a refill: G1 within :data:`.refill_loop.G1_EDGE_DEG`
    (1 deg) of the neighbour's tangent plane, G2 also within :data:`G2_REL` (2 %) in curvature.
    ``side_g1``/``side_g2`` are OCC's measures per edge; ``None`` where not measured (an edge asked
    less), which claims nothing beyond what was asked."""
    from .refill_loop import G1_EDGE_DEG

    g2s = list(side_g2) + [None] * (len(side_g1) - len(side_g2))
    out = []
    for a, b in zip(side_g1, g2s):
        tangent = a is not None and a <= G1_EDGE_DEG
        out.append("G2" if tangent and b is not None and b <= G2_REL else "G1" if tangent else "G0")
    return out


def shortfall(asked: list[str], got: list[str], side_g2: list[float | None]) -> str | None:
    """One line naming the edges whose fill reached less than was asked (``None`` when none did):
    ``'edges 0, 2 asked G2 got G1 (jump 5.2 %, 8.4 %)'``, grouped by what was asked and got."""
    groups: dict[tuple[str, str], list[int]] = {}
    for k, (a, g) in enumerate(zip(asked, got)):
        if g < a:  # 'G0' < 'G1' < 'G2'
            groups.setdefault((a, g), []).append(k)
    parts = []
    for (a, g), ks in groups.items():
        jumps = [j for j in (side_g2[k] for k in ks if k < len(side_g2)) if j is not None]
        extra = f" (jump {', '.join(f'{100 * j:.2g} %' for j in jumps)})" if a == "G2" and jumps else ""
        parts.append(f"edge{'s' if len(ks) > 1 else ''} {', '.join(map(str, ks))} asked {a} got {g}{extra}")
    return "; ".join(parts) or None


def original_g2(edge: Any, nb: Any, owner: Any | None, floor: float, samples: int) -> tuple[bool, float]:
    """Whether the removed face ``owner`` met the neighbour ``nb`` curvature continuously along ``edge``
    (within :data:`G2_REL`), and the jump: OCC's principal curvatures on both sides at the same
    edge parameters (:func:`.joints.assess_curvature`). No owner (a hole of the model): ``(False, nan)``."""
    if owner is None:
        return False, float("nan")
    _, uvs, _ = edge_samples(edge, owner, samples)
    u = np.array([uv.X() for uv in uvs])
    v = np.array([uv.Y() for uv in uvs])

    def locate(points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return np.zeros(len(points), int), u, v

    jump, _ = assess_curvature(edge, nb, [BRep_Tool.Surface_s(owner)], floor, samples, locate=locate, gap=False)
    return jump <= G2_REL, jump


def with_cross2(side: HoleSide, edges: list[Any], nbs: list[Any]) -> HoleSide:
    """``side`` with ``cross2``: the neighbours' second derivative across it, sampled along its
    ``edges`` (their neighbours ``nbs``) and fitted (see the module).

    Raises
    ------
    InvalidGeometryError
        The neighbour's parametrisation is degenerate at a sample (a pole: ``S_u x S_v = 0``).
    """
    from scipy.interpolate import make_lsq_spline  # here: not at the start of every fill worker

    c, X = side.curve, side.cross
    s_all, G_all = [], []
    for e, nb in zip(edges, nbs):
        surf = BRep_Tool.Surface_s(nb)
        _, uvs, pts = edge_samples(e, nb, _SAMPLES_PER_EDGE)
        s, _ = closest_parameters(c, pts)
        Xc = X.evaluate(s)
        if c.is_rational:  # the field is homogeneous (w X, 0): its Cartesian cross derivative is X
            Xc = Xc[:, :3] / _weights(c, s)[:, None]
        p, su, sv, suu, svv, suv = gp_Pnt(), gp_Vec(), gp_Vec(), gp_Vec(), gp_Vec(), gp_Vec()
        for k, uv in enumerate(uvs):
            surf.D2(uv.X(), uv.Y(), p, su, sv, suu, svv, suv)
            J = np.c_[su.Coord(), sv.Coord()]
            if float(np.linalg.norm(np.cross(J[:, 0], J[:, 1]))) <= 1e-12 * max(float(np.linalg.norm(J)) ** 2, 1e-300):
                raise InvalidGeometryError("a neighbour's parametrisation is degenerate along the hole (a pole): "
                                           "its curvature across the edge is unknown there")
            d = np.linalg.lstsq(J, Xc[k], rcond=None)[0]
            G_all.append(np.array(suu.Coord()) * d[0] ** 2 + 2 * np.array(suv.Coord()) * d[0] * d[1]
                         + np.array(svv.Coord()) * d[1] ** 2)
        s_all.append(s)
    s = np.concatenate(s_all)
    G = np.array(G_all)
    order = np.argsort(s, kind="stable")
    s, G = s[order], G[order]
    keep = np.r_[True, np.diff(s) > 1e-12 * max(1.0, float(np.ptp(s)))]
    s, G = s[keep], G[keep]
    lo, hi = c.domain
    spans = max(1, min(len(s) // 8, 32))
    t = np.r_[[lo] * 4, np.linspace(lo, hi, spans + 1)[1:-1], [hi] * 4]
    fit = make_lsq_spline(np.clip(s, lo, hi), G, t, k=3)
    coef = fit.c
    if c.is_rational:  # homogeneous (w G_tt, 0): w_t = w_tt = 0 along a field (w X, 0)
        W = BSplineCurve(3, t, coef)
        ts = np.linspace(lo, hi, 4 * (spans + 3))
        hom = np.c_[W.evaluate(ts) * _weights(c, ts)[:, None], np.zeros(len(ts))]
        coef = make_lsq_spline(ts, hom, t, k=3).c
    return HoleSide(c, X, BSplineCurve(3, t, coef))


def _weights(curve: BSplineCurve, s: np.ndarray) -> np.ndarray:
    """The weight function ``w(s)`` of a rational curve (its homogeneous last coordinate)."""
    hc = BSplineCurve(curve.degree, curve.knots, curve.homogeneous_points)
    return hc.evaluate(s)[:, 3]


def g2_fill(edges: list[Any], nbs: list[Any], owners: list[Any], size: float, g2_edges: list[bool],
            samples: int) -> tuple[list[Any], list[bool], list[float], list[float], list[float | None],
                                   list[float | None], Any]:
    """The hole refilled by the G2 plate: G2 on every side all of whose edges are in ``g2_edges``,
    G1 where the original joint was tangent, G0 elsewhere; measured per edge by OCC.

    Returns
    -------
    (faces, g1 per edge, fitted angles per side, side G0, side G1, side G2 jump, fill)
        ``side G2`` per edge: the relative curvature jump where G2 was asked, else ``None``.

    Raises
    ------
    OccsurfError
        The sides cannot be fitted, or the hole is not a height field over any plane (the plate's
        reason).
    """
    from occsurf.algorithms import tolerances

    from .joints import SEW_TOLERANCE, assess_joint
    from .plate import plate_fill_faces
    from .refill_sides import refill_sides

    sides, side_of_edge, g1, fit = refill_sides(edges, nbs, owners, size, True)
    n = len(sides)
    on = [[k for k in range(len(edges)) if side_of_edge[k] == j] for j in range(n)]
    g2_side = [bool(ks) and all(g2_edges[k] for k in ks) for ks in on]
    sides = [with_cross2(sd, [edges[k] for k in ks], [nbs[k] for k in ks]) if want else sd
             for sd, ks, want in zip(sides, on, g2_side)]
    g1_side = [any(g1[k] for k in ks) or want for ks, want in zip(on, g2_side)]
    g0_tol = min(tolerances.FILL_FIT_G0 * size, tolerances.FILL_PLATE_SEW_SHARE * SEW_TOLERANCE)
    fill, faces = plate_fill_faces(sides, g1_side, g0_tol, gap=max(BRep_Tool.Tolerance_s(e) for e in edges),
                                   g2=g2_side)
    surfs = [BRep_Tool.Surface_s(f) for f in faces]
    floor = tolerances.CONTINUITY_CURVATURE_FLOOR / size
    s0: list[float] = []
    s1: list[float | None] = []
    s2: list[float | None] = []
    for k, (e, nb) in enumerate(zip(edges, nbs)):
        j = side_of_edge[k]

        def locate(pts: np.ndarray, j: int = j) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
            return fill.locate_input(j, pts)[:3]

        a, b = assess_joint(e, nb, surfs, samples, locate=locate)
        s0.append(a)
        s1.append(b if g1_side[j] else None)
        s2.append(assess_curvature(e, nb, surfs, floor, samples, locate=locate, gap=False)[0] if g2_side[j] else None)
    g1_edges = [g1_side[side_of_edge[k]] for k in range(len(edges))]
    return faces, g1_edges, fit, s0, s1, s2, fill
