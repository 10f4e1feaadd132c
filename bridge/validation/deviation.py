r"""Our evaluation measured against OpenCascade's, and round trips measured against the original.

:func:`surface_deviation` and :func:`curve_deviation` sample a grid over the domain, evaluate our
spline (vectorised: ``derivatives_grid`` / ``derivatives``) and the OCC geometry (``D2``/``D3`` and
``GeomLProp_SLProps``, necessarily one parameter at a time) at the same parameters, and report the
largest differences, absolute and relative. :func:`roundtrip_deviation` compares two of our splines
(e.g. before and after a STEP write/read) by their arrays and by sampled points.

Relative errors
---------------
For the derivative ``D = d^{a+b} S / du^a dv^b`` (``a + b = k``) the error is divided by the scale

.. math::

    \sigma_{ab} = \max\Big(\max_{\text{samples}} |D_\text{ours}|,\;
                 \max_{\text{samples}} |D_\text{occ}|,\;
                 R \big(\tfrac{p}{h_u}\big)^a \big(\tfrac{q}{h_v}\big)^b\Big)

where ``R`` is the largest distance of one of our control points from the origin and ``h_u``,
``h_v`` the shortest non-empty knot spans in the domain (curves alike, in one direction). The first
two terms are the size of that derivative over the whole sample set, so a derivative that merely
vanishes somewhere does not blow the ratio up. The last is the size of the derivative's control
polygon (each differentiation multiplies pole differences by about ``p / h``), which is what the
round-off of *any* evaluation scales with: it keeps derivatives that vanish identically (``S_uu``
of a bilinear patch, every derivative of a spline whose poles coincide) from being compared with
pure round-off noise. Points are relative to the bounding-box diagonal of all sampled points (ours
and OCC's); note that round-off grows with the magnitude of the coordinates, not with the bounding
box, so a small patch far from the origin shows larger relative numbers for the same arithmetic.

Samples closer than 4 ulps to a knot are moved onto it: OCC already evaluates a parameter one ulp
below a knot as the knot (derivatives from the right), we take it literally (from the left); on a
spline that is not smooth at that knot the two would differ by O(1) for no fault of either.

The normal angle is measured where both normals exist: ours is ``S_u x S_v`` normalised and is
left out where ``|S_u x S_v|`` is below ``1e-8 max|S_u| max|S_v|`` (singular points such as a
sphere's poles, where the cross product is round-off noise; OCC falls back on higher derivatives
there); OCC's where ``GeomLProp_SLProps.IsNormalDefined()``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray
from OCP.GeomLProp import GeomLProp_SLProps
from OCP.gp import gp_Pnt, gp_Vec

from occsurf.algorithms import BSplineCurve, BSplineSurface
from occsurf.algorithms._validate import check_size
from occsurf.algorithms.errors import InvalidGeometryError

from .. import _occ
from ..conversion.splines import to_occ

__all__ = [
    "SurfaceDeviation",
    "CurveDeviation",
    "RoundTripDeviation",
    "surface_deviation",
    "curve_deviation",
    "roundtrip_deviation",
]

Array = NDArray[np.float64]

#: Resolution handed to ``GeomLProp_SLProps`` (a vector shorter than this counts as zero).
_LPROP_RESOLUTION = 1e-12

#: Samples where ``|S_u x S_v|`` is below this fraction of ``max|S_u| * max|S_v|`` are singular
#: (a sphere's poles): their normal is a limit that ``S_u x S_v`` only gives as round-off noise,
#: so they are left out of ``max_normal_angle``.
_SINGULAR = 1e-8


@dataclass(frozen=True)
class SurfaceDeviation:
    """Largest differences between our surface and OCC's on a ``n_samples`` point grid.

    Attributes
    ----------
    max_point, max_point_rel : float
        ``max |S_ours - S_occ|``, and divided by ``bbox_diagonal``.
    max_d1, max_d1_rel : float
        Over ``S_u`` and ``S_v``; relative as in the module docstring.
    max_d2, max_d2_rel : float
        Over ``S_uu``, ``S_uv``, ``S_vv``.
    max_normal_angle : float
        Radians, over samples where both normals are defined.
    bbox_diagonal : float
        Of all sampled points.
    n_samples : int
        Number of grid points (``samples ** 2``).
    normal_angle_bound : float
        What the first derivatives' differences alone can turn a normal by (radians, to first
        order): the largest over those samples of ``max_d1 (|S_u| + |S_v|) / |S_u x S_v|``. Near a
        singular point (``|S_u x S_v|`` small against ``|S_u| |S_v|``) round-off in the
        derivatives turns the normal by far more than elsewhere: 1.6e-6 rad at a sample where
        ``|S_u x S_v|`` was 1.8e-8 of the area scale, on a degree-9 patch whose derivatives agreed
        with OCC's to 1e-13.
    """

    max_point: float
    max_point_rel: float
    max_d1: float
    max_d1_rel: float
    max_d2: float
    max_d2_rel: float
    max_normal_angle: float
    bbox_diagonal: float
    n_samples: int
    normal_angle_bound: float = 0.0


@dataclass(frozen=True)
class CurveDeviation:
    """Largest differences between our curve and OCC's at ``n_samples`` parameters.

    ``max_dk`` is over ``d^k C / du^k``; ``*_rel`` as in the module docstring.
    """

    max_point: float
    max_point_rel: float
    max_d1: float
    max_d1_rel: float
    max_d2: float
    max_d2_rel: float
    max_d3: float
    max_d3_rel: float
    bbox_diagonal: float
    n_samples: int


@dataclass(frozen=True)
class RoundTripDeviation:
    """How far ``after`` is from ``before`` (two of our splines).

    Attributes
    ----------
    max_pole : float
        Largest distance between corresponding poles (``inf`` if ``same_structure`` is False).
    max_knot : float
        Largest absolute knot difference (``inf`` if not ``same_structure``).
    max_weight : float
        Largest absolute weight difference, a missing weight array counting as all ones (``inf``
        if not ``same_structure``).
    max_point : float
        Largest distance between sampled points (always measured, see :func:`roundtrip_deviation`).
    same_structure : bool
        Same class, degree(s), pole-array shape (including the dimension) and knot-vector lengths.
    """

    max_pole: float
    max_knot: float
    max_weight: float
    max_point: float
    same_structure: bool


# ------------------------------------------------------------------------------------ helpers
def _bbox_diagonal(*point_sets: Array) -> float:
    pts = np.concatenate([p.reshape(-1, p.shape[-1]) for p in point_sets])
    return float(np.linalg.norm(pts.max(axis=0) - pts.min(axis=0)))


def _rel(diff: Array, ours: Array, occ: Array, floor: float) -> tuple[float, float]:
    """``(max |diff|, max |diff| / scale)`` with ``scale = max(sup|ours|, sup|occ|, floor)``."""
    err = float(np.max(np.linalg.norm(diff, axis=-1)))
    scale = max(float(np.max(np.linalg.norm(ours, axis=-1))), float(np.max(np.linalg.norm(occ, axis=-1))), floor)
    return err, (err / scale if scale > 0 else (0.0 if err == 0 else np.inf))


def _snap_to_knots(params: Array, knots: Array) -> Array:
    """Move parameters within 4 ulps of a knot onto the knot.

    At a knot both OCC and we take derivatives from the right; but OCC's span search already counts
    a parameter one ulp *below* a knot as the knot, we do not. On a spline that is not smooth there
    (e.g. degree 1) the two derivatives then differ by O(1) for no fault of either; uniform samples
    land that close to "round" knots easily.
    """
    k = np.unique(knots)
    i = np.clip(np.searchsorted(k, params), 1, k.size - 1)
    near = np.where(np.abs(params - k[i - 1]) <= np.abs(k[i] - params), k[i - 1], k[i])
    tol = 4 * np.spacing(np.maximum(np.abs(near), np.abs(params)))
    return np.where(np.abs(near - params) <= tol, near, params)


def _min_span(knots: Array, lo: float, hi: float) -> float:
    """Shortest non-empty knot span inside ``[lo, hi]``."""
    k = np.unique(knots[(knots >= lo) & (knots <= hi)])
    return float(np.min(np.diff(k)))


def _pole_radius(obj: BSplineCurve | BSplineSurface) -> float:
    P = obj.control_points
    return float(np.max(np.linalg.norm(P.reshape(-1, P.shape[-1]), axis=-1)))


def _vec(v: gp_Vec) -> tuple[float, float, float]:
    return v.X(), v.Y(), v.Z()


def _occ_normal(props: GeomLProp_SLProps) -> tuple[float, float, float]:
    """OCC's unit normal, or NaNs where it is undefined.

    ``IsNormalDefined()`` raises ``Standard_ConstructionError`` ("gp_Dir() - input vector has zero
    norm") instead of answering False where every derivative it tries vanishes (e.g. all poles
    equal); that counts as undefined too.
    """
    try:
        if props.IsNormalDefined():
            return props.Normal().Coord()
    except Exception as err:  # noqa: BLE001 - filtered just below
        if not _occ.is_occ_exception(err):
            raise
    return (np.nan, np.nan, np.nan)


def _check(obj: Any, cls: type, name: str) -> None:
    if not isinstance(obj, cls):
        raise InvalidGeometryError(f"{name}: expected a {cls.__name__}, got {type(obj).__name__}")


def _occ_surface_of(obj: Any) -> Any:
    """A ``Geom_Surface`` as it is; the surface of a face-like object with exactly one face."""
    from OCP.BRep import BRep_Tool
    from OCP.Geom import Geom_Surface

    from ..conversion.shapes import as_faces, is_shape_like

    if isinstance(obj, Geom_Surface):
        return obj
    if not is_shape_like(obj):
        raise InvalidGeometryError(f"occ_surface: expected a Geom_Surface or a face, got {type(obj).__name__}")
    faces = as_faces(obj, "occ_surface")
    if len(faces) != 1:
        raise InvalidGeometryError(f"occ_surface: expected a shape with exactly one face, got {len(faces)} faces")
    surface = BRep_Tool.Surface_s(faces[0])
    if surface is None:
        raise InvalidGeometryError("occ_surface: the face has no surface")
    return surface


def _occ_curve_of(obj: Any) -> Any:
    """A ``Geom_Curve`` as it is; the 3-D curve of an edge-like object with exactly one edge."""
    from ..conversion.shapes import as_curve, is_edge_like

    if not is_edge_like(obj):
        raise InvalidGeometryError(f"occ_curve: expected a Geom_Curve or an edge (TopoDS_Edge, build123d/cadquery "
                                   f"Edge, a Wire of one edge), got {type(obj).__name__}")
    return as_curve(obj, "occ_curve")


def _check_samples(samples: Any, minimum: int = 2) -> int:
    if isinstance(samples, bool) or not isinstance(samples, (int, np.integer)) or samples < minimum:
        raise InvalidGeometryError(f"samples: expected an integer >= {minimum}, got {samples!r}")
    return int(samples)


# ------------------------------------------------------------------------------------ surfaces
def surface_deviation(ours: BSplineSurface, occ_surface: Any = None, samples: int = 25) -> SurfaceDeviation:
    """Compare our points, first and second partials and normals with OCC's on a grid.

    Parameters
    ----------
    ours : BSplineSurface
        3-D.
    occ_surface : Geom_Surface, or a face, optional
        Evaluated at the same ``(u, v)``; default ``to_occ(ours)`` (which checks our evaluator
        against OCC's on identical data). A face (``TopoDS_Face``, build123d / cadquery ``Face``, or
        a Shell, Solid, Compound holding exactly one face) stands for its surface
        (``BRep_Tool.Surface_s``, the face's location applied).
    samples : int
        Grid of ``samples x samples`` parameters, uniform over ``ours.domain``, ends included
        (those within 4 ulps of a knot moved onto it, see the module docstring). A grid whose
        arrays would exceed ``tolerances.MAX_ARRAY_BYTES`` is refused (InvalidGeometryError).

    Returns
    -------
    SurfaceDeviation
    """
    _check(ours, BSplineSurface, "ours")
    m = _check_samples(samples)
    # ours (3x3 partials), OCC's 6 vectors and normals per grid point: refused before allocating
    check_size((m, m, 9 * 3 + 6 * 3 + 3), f"surface_deviation with samples={m} ({m} x {m} grid)")
    occ_s = to_occ(ours) if occ_surface is None else _occ_surface_of(occ_surface)
    (u0, u1), (v0, v1) = ours.domain
    us = _snap_to_knots(np.linspace(u0, u1, m), ours.knots[0])
    vs = _snap_to_knots(np.linspace(v0, v1, m), ours.knots[1])
    D = ours.derivatives_grid(us, vs, 2)  # (m, m, 3, 3, 3)

    occ_D = np.empty((m, m, 6, 3))  # S, Su, Sv, Suu, Svv, Suv
    occ_n = np.full((m, m, 3), np.nan)
    p, du, dv, duu, dvv, duv = gp_Pnt(), gp_Vec(), gp_Vec(), gp_Vec(), gp_Vec(), gp_Vec()
    with _occ.kernel_errors("surface_deviation: evaluating the OCC surface"):
        props = GeomLProp_SLProps(occ_s, 1, _LPROP_RESOLUTION)
        for i, u in enumerate(us.tolist()):
            for j, v in enumerate(vs.tolist()):
                occ_s.D2(u, v, p, du, dv, duu, dvv, duv)
                occ_D[i, j] = (p.Coord(), _vec(du), _vec(dv), _vec(duu), _vec(dvv), _vec(duv))
                props.SetParameters(u, v)
                occ_n[i, j] = _occ_normal(props)

    pts = D[:, :, 0, 0]
    diag = _bbox_diagonal(pts, occ_D[:, :, 0])
    max_point = float(np.max(np.linalg.norm(pts - occ_D[:, :, 0], axis=-1)))
    R = _pole_radius(ours)
    gu = ours.degree[0] / _min_span(ours.knots[0], u0, u1)
    gv = ours.degree[1] / _min_span(ours.knots[1], v0, v1)
    pairs = {(1, 0): 1, (0, 1): 2, (2, 0): 3, (0, 2): 4, (1, 1): 5}
    errs: dict[int, list[tuple[float, float]]] = {1: [], 2: []}
    for (a, b), k in pairs.items():
        ours_ab, occ_ab = D[:, :, a, b], occ_D[:, :, k]
        errs[a + b].append(_rel(ours_ab - occ_ab, ours_ab, occ_ab, R * gu**a * gv**b))

    Su, Sv = D[:, :, 1, 0], D[:, :, 0, 1]
    n_ours = np.cross(Su, Sv)
    ln = np.linalg.norm(n_ours, axis=-1, keepdims=True)
    area_scale = float(np.max(np.linalg.norm(Su, axis=-1)) * np.max(np.linalg.norm(Sv, axis=-1)))
    with np.errstate(invalid="ignore", divide="ignore"):
        n_ours = np.where(ln > _SINGULAR * area_scale, n_ours / ln, np.nan)
    ok = np.all(np.isfinite(n_ours), axis=-1) & np.all(np.isfinite(occ_n), axis=-1)
    max_d1 = max(e for e, _ in errs[1])
    if np.any(ok):
        a, b = n_ours[ok], occ_n[ok]
        angle = float(np.max(np.arctan2(np.linalg.norm(np.cross(a, b), axis=-1), np.sum(a * b, axis=-1))))
        speeds = np.linalg.norm(Su[ok], axis=-1) + np.linalg.norm(Sv[ok], axis=-1)
        bound = float(np.max(max_d1 * speeds / ln[ok][:, 0]))
    else:
        angle = bound = 0.0

    return SurfaceDeviation(
        max_point=max_point,
        max_point_rel=max_point / diag if diag > 0 else (0.0 if max_point == 0 else np.inf),
        max_d1=max_d1,
        max_d1_rel=max(r for _, r in errs[1]),
        max_d2=max(e for e, _ in errs[2]),
        max_d2_rel=max(r for _, r in errs[2]),
        max_normal_angle=angle,
        bbox_diagonal=diag,
        n_samples=m * m,
        normal_angle_bound=bound,
    )


# ------------------------------------------------------------------------------------ curves
def curve_deviation(ours: BSplineCurve, occ_curve: Any = None, samples: int = 101) -> CurveDeviation:
    """Compare our points and first to third derivatives with OCC's ``D3``.

    Parameters
    ----------
    ours : BSplineCurve
        3-D.
    occ_curve : Geom_Curve, or an edge, optional
        Evaluated at the same parameters; default ``to_occ(ours)``. An edge (``TopoDS_Edge``,
        build123d / cadquery ``Edge``, or a ``Wire`` or other shape holding exactly one edge) stands
        for its 3-D curve (``BRep_Tool.Curve_s``: the edge's location applied, its own
        parametrisation kept), see :func:`occsurf.bridge.conversion.shapes.as_curve`.
    samples : int
        Uniform parameters over ``ours.domain``, ends included (snapped onto knots within 4 ulps).

    Returns
    -------
    CurveDeviation
    """
    _check(ours, BSplineCurve, "ours")
    m = _check_samples(samples)
    # per sample: both curves' derivatives to order 3 (our homogeneous work, OCC's, differences)
    check_size((m, 4 * 4 * 3 + 8), f"curve_deviation with samples={m}")
    occ_c = to_occ(ours) if occ_curve is None else _occ_curve_of(occ_curve)
    t0, t1 = ours.domain
    ts = _snap_to_knots(np.linspace(t0, t1, m), ours.knots)
    D = ours.derivatives(ts, 3)  # (m, 4, 3)
    occ_D = np.empty((m, 4, 3))
    p, v1, v2, v3 = gp_Pnt(), gp_Vec(), gp_Vec(), gp_Vec()
    with _occ.kernel_errors("curve_deviation: evaluating the OCC curve"):
        for i, t in enumerate(ts.tolist()):
            occ_c.D3(t, p, v1, v2, v3)
            occ_D[i] = (p.Coord(), _vec(v1), _vec(v2), _vec(v3))
    diag = _bbox_diagonal(D[:, 0], occ_D[:, 0])
    max_point = float(np.max(np.linalg.norm(D[:, 0] - occ_D[:, 0], axis=-1)))
    R = _pole_radius(ours)
    g = ours.degree / _min_span(ours.knots, t0, t1)
    r = [_rel(D[:, k] - occ_D[:, k], D[:, k], occ_D[:, k], R * g**k) for k in (1, 2, 3)]
    return CurveDeviation(
        max_point=max_point,
        max_point_rel=max_point / diag if diag > 0 else (0.0 if max_point == 0 else np.inf),
        max_d1=r[0][0],
        max_d1_rel=r[0][1],
        max_d2=r[1][0],
        max_d2_rel=r[1][1],
        max_d3=r[2][0],
        max_d3_rel=r[2][1],
        bbox_diagonal=diag,
        n_samples=m,
    )


# ------------------------------------------------------------------------------------ round trips
def roundtrip_deviation(before: BSplineCurve | BSplineSurface, after: BSplineCurve | BSplineSurface,
                        samples: int = 25) -> RoundTripDeviation:
    """Compare two of our splines (same kind) array by array and point by point.

    Points are sampled uniformly over ``before.domain`` (``samples`` per direction) and at the
    corresponding parameters of ``after``: if its domain differs, the parameters are mapped
    affinely onto it (a knot shift then shows in ``max_knot``, not in ``max_point``).

    Parameters
    ----------
    before, after : BSplineCurve or BSplineSurface
        Both curves or both surfaces, of the same dimension.
    samples : int

    Returns
    -------
    RoundTripDeviation
        ``max_pole``, ``max_knot`` and ``max_weight`` are ``inf`` when the structures differ
        (e.g. a different number of poles); ``max_point`` is always measured.

    Raises
    ------
    InvalidGeometryError
        Not two curves or two surfaces, or dimensions that differ.
    """
    m = _check_samples(samples)

    def check_dims() -> None:
        if before.dim != after.dim:
            raise InvalidGeometryError(f"roundtrip_deviation: dimensions differ ({before.dim} and {after.dim})")

    if isinstance(before, BSplineCurve) and isinstance(after, BSplineCurve):
        check_dims()
        check_size((m, 4 * (before.dim + 1) + 4), f"roundtrip_deviation with samples={m}")
        kb, ka = [before.knots], [after.knots]
        (b0, b1), (a0, a1) = before.domain, after.domain
        s = np.linspace(0.0, 1.0, m)
        pb = before.evaluate(b0 + s * (b1 - b0))
        pa = after.evaluate(np.clip(a0 + s * (a1 - a0), a0, a1))
    elif isinstance(before, BSplineSurface) and isinstance(after, BSplineSurface):
        check_dims()
        # per grid point: both surfaces' homogeneous grids and points, and their difference
        check_size((m, m, 4 * (before.dim + 1) + 4), f"roundtrip_deviation with samples={m} ({m} x {m} grid)")
        kb, ka = list(before.knots), list(after.knots)
        s = np.linspace(0.0, 1.0, m)
        grids = []
        for obj in (before, after):
            (u0, u1), (v0, v1) = obj.domain
            grids.append(obj.evaluate_grid(np.clip(u0 + s * (u1 - u0), u0, u1), np.clip(v0 + s * (v1 - v0), v0, v1)))
        pb, pa = grids
    else:
        raise InvalidGeometryError(
            f"roundtrip_deviation: expected two BSplineCurves or two BSplineSurfaces, got "
            f"{type(before).__name__} and {type(after).__name__}"
        )
    max_point = float(np.max(np.linalg.norm(pb - pa, axis=-1)))

    same = (
        before.degree == after.degree
        and before.control_points.shape == after.control_points.shape
        and all(x.shape == y.shape for x, y in zip(kb, ka))
    )
    if not same:
        return RoundTripDeviation(np.inf, np.inf, np.inf, max_point, False)
    max_pole = float(np.max(np.linalg.norm(before.control_points - after.control_points, axis=-1)))
    max_knot = max(float(np.max(np.abs(x - y))) for x, y in zip(kb, ka))
    shape = before.control_points.shape[:-1]
    wb = np.ones(shape) if before.weights is None else before.weights
    wa = np.ones(shape) if after.weights is None else after.weights
    max_weight = float(np.max(np.abs(wb - wa)))
    return RoundTripDeviation(max_pole, max_knot, max_weight, max_point, True)
