"""S-patches as rational tensor-product surfaces, for OpenCascade and STEP (course §8-2).

An S-patch is not a tensor product, so kernels that only know tensor-product B-splines get it in
pieces: the regular ``n``-gon domain is split into ``n`` quadrilaterals, each mapped bilinearly
from ``[0, 1]²``, and the S-patch restricted to a quadrilateral is written as a rational
tensor-product Bézier surface.

The split
---------
Piece ``k`` (``k = 0 .. n-1``) has the corners, in the order ``(s, t) = (0,0), (1,0), (1,1), (0,1)``,

* ``v_k``, domain vertex ``k``;
* ``m_k = (v_k + v_{k+1}) / 2``, the midpoint of side ``k``;
* ``0``, the centre of the polygon;
* ``m_{k-1}``, the midpoint of side ``k-1``;

so ``t = 0`` is the first half of side ``k``, ``s = 0`` the second half of side ``k-1`` (run
backwards), and the spokes ``s = 1`` / ``t = 1`` are shared with pieces ``k+1`` / ``k-1``. The
corners are counter-clockwise, so ``S_s × S_t`` of every piece points the way ``S_x × S_y`` of the
patch does. Each piece is a kite (a parallelogram only for ``n = 4``). This is the split of the
course's §8 figures and of Loop & DeRose §6; every piece touches exactly one corner of the patch,
so no piece carries more than one corner singularity of the parametrisation.

Exact bidegree
--------------
With ``x(s, t)`` bilinear, each edge function ``L_j(x(s, t))`` is of bidegree ``(1, 1)``, with
Bernstein coefficients its values at the four corners. Wachspress' ``w_k = ∏_{j∉{k-1,k}} L_j`` is of
bidegree ``(n-2, n-2)``, and since ``λ^I = w^I / W^d`` and ``Σ_I B_I(λ) = 1``,

.. math::

    S = \\frac{\\sum_I ω_I P_I \\frac{d!}{I!} w^I}{\\sum_I ω_I \\frac{d!}{I!} w^I}

is a rational tensor-product Bézier surface of bidegree ``(D, D)``, ``D = d (n - 2)`` (``ω_I = 1``
for a polynomial S-patch, whose denominator is then ``W^d``, of true degree ``d (n-3)``, raised to
``D``). Its homogeneous Bernstein coefficients are computed **exactly** (to round-off) by the
simplex de Casteljau algorithm run in the ring of bivariate polynomials: ``Q_J = Σ_k w_k Q_{J+e_k}``,
with products done in the *scaled* Bernstein basis ``C(p,i) C(q,j) B^p_i B^q_j``, in which a product
of polynomials is the 2-D convolution of their coefficient arrays (Farouki & Rajan 1988,
"Algorithms for polynomials in Bernstein form", §4). All the coefficients involved are positive
(every ``L_j`` is non-negative on the closed polygon and ``w_k`` is positive on piece ``k``'s
corners), so the sums are free of cancellation and the weights are positive.

For ``n = 4`` the bidegree can be lowered exactly: the pieces are squares aligned with the
parallelogram, on which the Wachspress coordinates are the bilinear products, so the patch is of
bidegree ``(d, d)`` there (``W`` is constant). Those pieces are degree-reduced to ``(d, d)``, and
the reduction is verified (re-elevation reproduces the coefficients within
``tolerances.SPATCH_REDUCTION_TOL``).
For ``n >= 5`` nothing is reduced: the leading Bernstein components of the exact pieces are
genuinely non-zero, though they can be tiny (~1e-13 of the coefficients for ``D = 25``), so a
tolerance-driven reduction would silently turn the exact conversion into an approximation.

Beyond OpenCascade's limit
--------------------------
When ``D > 25`` (:data:`occsurf.algorithms.tolerances.MAX_DEGREE`) a piece cannot be handed to OCC exactly.
It is then approximated by a non-rational B-spline of bidegree ``tolerances.SPATCH_APPROX_DEGREE``
(bi-quintic by default): a tensor-product least-squares fit
(:func:`occsurf.algorithms.fitting.interpolation.fit_surface`, ends interpolated) to a Chebyshev–Lobatto grid of exact
S-patch values, with uniform knots, refined until the maximum deviation, measured on a denser grid
offset from the fitting grid, is below ``tol``. The measured deviation is reported. Because the
fit interpolates the ends, a piece's boundary curve depends only on the samples on that boundary:
two pieces sharing a spoke get the same edge curve (to round-off).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from math import comb

import numpy as np
from numpy.typing import NDArray

from .. import tolerances
from ..errors import InvalidGeometryError, ToleranceError
from ..fitting.interpolation import fit_surface
from ..kernel.surface import BSplineSurface
from ._common import edge_normals, index_tuples
from .spatch import SPatch, domain_vertices

__all__ = [
    "SPatchConversion",
    "convert_spatch",
    "spatch_to_surfaces",
    "piece_corners",
    "piece_domain_points",
    "exact_bidegree",
]

Array = NDArray[np.float64]

# The approximation's tolerance, degree and pole limit, the reduction check and the number of
# check samples are tolerances.SPATCH_APPROX_TOL, SPATCH_APPROX_DEGREE, SPATCH_APPROX_MAX_POLES,
# SPATCH_REDUCTION_TOL and SPATCH_CHECK_SAMPLES, read at call time.


@dataclass(frozen=True)
class SPatchConversion:
    """Result of :func:`convert_spatch`.

    Attributes
    ----------
    surfaces : list of BSplineSurface
        ``sides`` pieces, piece ``k`` on ``[0, 1]²`` as in the module notes.
    exact : bool
        True if the pieces are the exact rational representation (bidegree <= 25).
    degree : (int, int)
        Bidegree of the pieces.
    max_deviation : float
        Largest distance between the pieces and ``SPatch.evaluate``, measured on
        ``SPATCH_CHECK_SAMPLES²`` parameters per piece (denser and offset for approximations).
    method : str
        ``'exact'``, ``'exact-reduced'`` (exact, then exactly degree-reduced) or ``'lsq-fit'``.
    """

    surfaces: list[BSplineSurface]
    exact: bool
    degree: tuple[int, int]
    max_deviation: float
    method: str


def exact_bidegree(sides: int, depth: int) -> int:
    """``D = depth * (sides - 2)``: the bidegree of the exact rational pieces (before reduction)."""
    return int(depth) * (int(sides) - 2)


def piece_corners(sides: int) -> Array:
    """Corners of the ``sides`` quadrilateral pieces, shape ``(sides, 2, 2, 2)``.

    ``[k, a, b]`` is the domain point of piece ``k`` at ``(s, t) = (a, b)``: ``[k, 0, 0] = v_k``,
    ``[k, 1, 0] = m_k``, ``[k, 1, 1] = 0``, ``[k, 0, 1] = m_{k-1}``.
    """
    v = domain_vertices(sides)
    n = v.shape[0]
    mids = 0.5 * (v + np.roll(v, -1, axis=0))  # mids[k] = midpoint of side k
    out = np.zeros((n, 2, 2, 2))
    out[:, 0, 0] = v
    out[:, 1, 0] = mids
    out[:, 0, 1] = np.roll(mids, 1, axis=0)
    return out


def piece_domain_points(sides: int, k: int, s: Array, t: Array) -> Array:
    """Domain points ``x(s, t)`` of piece ``k`` (bilinear in ``s, t``), shape ``broadcast(s, t) + (2,)``."""
    q = piece_corners(sides)[k]
    s = np.asarray(s, float)[..., None]
    t = np.asarray(t, float)[..., None]
    return (1 - s) * (1 - t) * q[0, 0] + s * (1 - t) * q[1, 0] + s * t * q[1, 1] + (1 - s) * t * q[0, 1]


# ---------------------------------------------------------------------------- exact pieces
def _conv2(a: Array, b: Array) -> Array:
    """2-D convolution of ``a`` (..., p+1, q+1, c) with a small scalar array ``b`` (r+1, s+1)."""
    p1, q1 = a.shape[-3], a.shape[-2]
    r1, s1 = b.shape
    out = np.zeros(a.shape[:-3] + (p1 + r1 - 1, q1 + s1 - 1) + a.shape[-1:])
    for i in range(r1):
        for j in range(s1):
            out[..., i : i + p1, j : j + q1, :] += b[i, j] * a
    return out


@functools.lru_cache(maxsize=64)
def _children(sides: int, depth: int, level: int) -> tuple[NDArray[np.intp], ...]:
    """For each multi-index J with |J| = level - 1, the rows of J + e_k among |I| = level (per k)."""
    upper = {ix: r for r, ix in enumerate(index_tuples(sides, level))}
    lower = index_tuples(sides, level - 1)
    out = []
    for k in range(sides):
        rows = []
        for J in lower:
            J1 = list(J)
            J1[k] += 1
            rows.append(upper[tuple(J1)])
        out.append(np.array(rows, dtype=np.intp))
    return tuple(out)


def _scaled_w(sides: int, k: int) -> list[Array]:
    """Scaled Bernstein coefficients of Wachspress' w_j on piece k, for every j, shape (n-1, n-1)."""
    q = piece_corners(sides)[k]  # (2, 2, 2)
    nrm = edge_normals(sides)
    h = np.cos(np.pi / sides)
    Lc = h - np.einsum("abx,jx->jab", q, nrm)  # (n, 2, 2): L_j at the corners = (1,1)-Bernstein coefs
    Lc = np.maximum(Lc, 0.0)  # zero on the sides through a corner; clears -1e-17 round-off
    out = []
    for j in range(sides):
        others = [i for i in range(sides) if i not in ((j - 1) % sides, j)]
        acc = Lc[others[0]][:, :, None]
        for i in others[1:]:
            acc = _conv2(acc, Lc[i])
        out.append(acc[:, :, 0])
    return out


def _exact_piece(patch: SPatch, k: int) -> Array:
    """Homogeneous Bernstein coefficients (D+1, D+1, dim+1) of piece k (weights last)."""
    n, d = patch.sides, patch.depth
    H = patch.homogeneous_points if patch.is_rational else np.c_[patch.control_points, np.ones(patch.n_control_points)]
    w = _scaled_w(n, k)
    Q = H[:, None, None, :]  # (m, 1, 1, dim+1): constant polynomials
    for level in range(d, 0, -1):
        ch = _children(n, d, level)
        acc = None
        for j in range(n):
            term = _conv2(Q[ch[j]], w[j])
            acc = term if acc is None else acc + term
        Q = acc
    C = Q[0]
    D = C.shape[0] - 1
    b = np.array([comb(D, i) for i in range(D + 1)], dtype=float)
    return C / (b[:, None, None] * b[None, :, None])


def _reduce_axis(C: Array, axis: int, rtol: float) -> Array | None:
    """Bernstein coefficients of degree p-1 along ``axis`` whose elevation is C, or None.

    Inverse of degree elevation (The NURBS Book, 2nd ed., §5.6, eq. 5.41-5.43): the left and
    right recursions, joined in the middle; accepted only if re-elevating reproduces C within
    ``rtol`` of its largest coefficient.
    """
    C = np.moveaxis(C, axis, 0)
    p = C.shape[0] - 1
    if p < 2:
        return None
    B = np.empty((p,) + C.shape[1:])
    r = (p - 1) // 2
    B[0] = C[0]
    for i in range(1, r + 1):
        a = i / p
        B[i] = (C[i] - a * B[i - 1]) / (1 - a)
    B[p - 1] = C[p]
    for i in range(p - 2, r, -1):
        a = (i + 1) / p
        B[i] = (C[i + 1] - (1 - a) * B[i + 1]) / a
    E = np.empty_like(C)
    E[0], E[p] = B[0], B[p - 1]
    ii = np.arange(1, p).reshape((-1,) + (1,) * (C.ndim - 1))
    E[1:p] = (ii / p) * B[:-1] + (1 - ii / p) * B[1:]
    scale = float(np.max(np.abs(C)))
    if float(np.max(np.abs(E - C))) > rtol * scale:
        return None
    return np.moveaxis(B, 0, axis)


def _reduce(C: Array, rtol: float) -> Array:
    for axis in (0, 1):
        while True:
            R = _reduce_axis(C, axis, rtol)
            if R is None:
                break
            C = R
    return C


def _bezier_surface(C: Array, rational: bool) -> BSplineSurface:
    p, q = C.shape[0] - 1, C.shape[1] - 1
    ku = np.r_[np.zeros(p + 1), np.ones(p + 1)]
    kv = np.r_[np.zeros(q + 1), np.ones(q + 1)]
    w = C[..., -1]
    if not rational and np.allclose(w, w.flat[0], rtol=1e-14, atol=0):
        return BSplineSurface._trusted((p, q), (ku, kv), C[..., :-1] / w[..., None])
    return BSplineSurface._trusted((p, q), (ku, kv), C[..., :-1] / w[..., None], w / w.max())


# ---------------------------------------------------------------------------- approximation
def _uniform_knots(n_poles: int, p: int) -> Array:
    inner = np.linspace(0.0, 1.0, n_poles - p + 1)[1:-1]
    return np.r_[np.zeros(p + 1), inner, np.ones(p + 1)]


def _fit_piece(patch: SPatch, k: int, tol: float, p: int) -> tuple[BSplineSurface, float]:
    """Least-squares bi-``p`` B-spline of piece ``k``, refined until within ``tol`` (measured)."""
    n_poles = p + 1
    check = _check_params(int(tolerances.SPATCH_CHECK_SAMPLES) * 2)
    sc, tc = np.meshgrid(check, check, indexing="ij")
    ref = patch.evaluate(piece_domain_points(patch.sides, k, sc, tc))
    while True:
        knots = _uniform_knots(n_poles, p)
        m = 2 * n_poles + 2  # twice the poles: an overdetermined, well-conditioned fit
        x = 0.5 - 0.5 * np.cos(np.pi * np.arange(m) / (m - 1))  # Chebyshev–Lobatto: clustered at the ends
        S, T = np.meshgrid(x, x, indexing="ij")
        Z = patch.evaluate(piece_domain_points(patch.sides, k, S, T))  # (m, m, dim)
        # ends interpolated: each boundary row of poles is the curve fit of that boundary's samples
        # only, so pieces sharing a spoke (same samples) get the same edge curve
        surf = fit_surface(Z, (n_poles, n_poles), (p, p), u_params=x, v_params=x, knots=(knots, knots))
        dev = float(np.max(np.linalg.norm(surf.evaluate(sc, tc) - ref, axis=-1)))
        if dev <= tol:
            return surf, dev
        max_poles = int(tolerances.SPATCH_APPROX_MAX_POLES)
        if n_poles >= max_poles:
            raise ToleranceError(
                f"spatch_to_surfaces: piece {k} of the S-patch could not be approximated within tol={tol:.3g} "
                f"with {max_poles}x{max_poles} poles of degree {p} (deviation {dev:.3g})"
            )
        n_poles = min(max_poles, 2 * n_poles - p)


def _check_params(count: int) -> Array:
    """Check parameters: the ends plus interior points offset from every fitting grid."""
    inner = (np.arange(count - 2) + 0.5 + 0.137) / (count - 1)
    return np.r_[0.0, np.clip(inner, 0, 1), 1.0]


# ---------------------------------------------------------------------------- public
def convert_spatch(patch: SPatch, *, tol: float | None = None, reduce: bool = True) -> SPatchConversion:
    """Split an S-patch into ``sides`` rational tensor-product pieces (exact when possible).

    Parameters
    ----------
    patch : SPatch
        A 3-D (or any dimension) S-patch.
    tol : float, optional
        Absolute maximum deviation allowed for approximated pieces; default
        ``tolerances.SPATCH_APPROX_TOL`` times the diagonal of the control points' bounding box.
        Unused on the exact path.
    reduce : bool, default True
        For ``sides == 4``, lower the exact bidegree ``2d`` to ``d`` (exact; module notes).

    Returns
    -------
    SPatchConversion

    Raises
    ------
    InvalidGeometryError
        ``patch`` is not an SPatch, or ``tol`` is not a positive number.
    ToleranceError
        An approximation did not reach ``tol`` with ``tolerances.SPATCH_APPROX_MAX_POLES`` poles per
        direction.

    Notes
    -----
    Exact when ``depth * (sides - 2) <= 25`` (course §8-2; Loop & DeRose 1989, §6): the
    Bernstein coefficients come from exact polynomial arithmetic (module notes), not from sampling.
    """
    if not isinstance(patch, SPatch):
        raise InvalidGeometryError(f"patch: expected an SPatch, got {type(patch).__name__}")
    P = patch.control_points
    size = float(np.linalg.norm(np.ptp(P, axis=0))) or 1.0
    if tol is None:
        tol_abs = tolerances.SPATCH_APPROX_TOL * size
    else:
        try:
            tol_abs = float(tol)
        except (TypeError, ValueError) as err:
            raise InvalidGeometryError(f"tol: expected a positive number, got {tol!r}") from err
        if not (np.isfinite(tol_abs) and tol_abs > 0):
            raise InvalidGeometryError(f"tol: expected a positive number, got {tol!r}")
    n = patch.sides
    D = exact_bidegree(n, patch.depth)
    surfaces: list[BSplineSurface] = []
    if D <= tolerances.MAX_DEGREE:
        method = "exact"
        for k in range(n):
            C = _exact_piece(patch, k)
            if reduce and n == 4:
                R = _reduce(C, tolerances.SPATCH_REDUCTION_TOL)
                if R.shape != C.shape:
                    method = "exact-reduced"
                C = R
            surfaces.append(_bezier_surface(C, patch.is_rational))
        exact = True
        params = np.linspace(0.0, 1.0, int(tolerances.SPATCH_CHECK_SAMPLES))
    else:
        method, exact = "lsq-fit", False
        for k in range(n):
            surfaces.append(_fit_piece(patch, k, tol_abs, int(tolerances.SPATCH_APPROX_DEGREE))[0])
        params = _check_params(int(tolerances.SPATCH_CHECK_SAMPLES) * 2)
    S, T = np.meshgrid(params, params, indexing="ij")
    dev = 0.0
    for k, surf in enumerate(surfaces):
        ref = patch.evaluate(piece_domain_points(n, k, S, T))
        dev = max(dev, float(np.max(np.linalg.norm(surf.evaluate(S, T) - ref, axis=-1))))
    degree = surfaces[0].degree
    return SPatchConversion(surfaces=surfaces, exact=exact, degree=degree, max_deviation=dev, method=method)


def spatch_to_surfaces(patch: SPatch, *, tol: float | None = None) -> list[BSplineSurface]:
    """The ``sides`` tensor-product pieces of ``patch`` (see :func:`convert_spatch`).

    Returns
    -------
    list of BSplineSurface
        Piece ``k`` on ``[0, 1]²``; rational Bézier (exact) when ``depth * (sides - 2) <= 25``,
        otherwise a bi-quintic B-spline within ``tol``.
    """
    return convert_spatch(patch, tol=tol).surfaces
