"""Constrained and smoothed least-squares fitting of gridded data (course §7-4, §7-5, §7-7).

Data on a grid, ``Q[i, j]`` at ``(u_i, v_j)``, fitted by a tensor-product spline with collocation
matrices ``A`` (``m x N_u``, along u) and ``B`` (``n x N_v``): the least-squares problem
``min ||A P B^T - Q||`` separates (course §7-4), its normal equations are
``G_u P G_v = A^T Q B`` with ``G_u = A^T A``, ``G_v = B^T B``, and the ``(mn x N_u N_v)`` matrix
``A ⊗ B`` is never formed. Everything below keeps that structure:

Smoothing
    The tensor-product difference penalty (P-splines, Eilers–Marx)
    ``λ (R_u ⊗ G_v + G_u ⊗ R_v)``, ``R = c D^T D`` with second differences ``D`` of the poles
    scaled by ``c = trace(G) / (2 trace(D^T D))`` so that ``λ = 1`` weighs data and penalty alike.
    With the generalised eigenvectors ``X^T G X = I``, ``X^T R X = diag(μ)`` of each direction the
    normal matrix is diagonal: ``P = X_u [(X_u^T A^T Q B X_v) / (1 + λ(μ_i + ν_j))] X_v^T``.
    The influence matrix has trace ``Σ 1 / (1 + λ(μ_i + ν_j))``, so generalised cross-validation
    (Craven and Wahba 1979) ``GCV(λ) = mn RSS / (mn - tr)^2`` costs one small product per λ.
Separable constraints (null-space method, course §3-12)
    Boundary curves (a pole row or column fixed), cross-boundary pole rows (a C1 join) and mirror
    symmetry are constraints ``C_u P = D_u`` and ``P C_v^T = D_v`` that act on one index only.
    Every solution is ``P = P_c + Z_u Y Z_v^T`` with ``Z`` orthonormal null-space bases (from the
    pivoted QR of :class:`~occsurf.algorithms.manipulation.linalg.ConstraintFactor`), and the
    reduced problem in ``Y`` has the same Kronecker form with ``A Z_u``, ``B Z_v``.
Point-wise constraints
    Points ``S(u, v) = X`` and tangent planes ``n . S_u(u_0, v_k) = 0`` (G1 to a neighbour at the
    sites ``v_k``) are rows ``w^T (α^T P β)`` with coordinate weights ``w``: they are added to the
    reduced problem through its Schur complement ``C N^{-1} C^T`` (``K x K``), where ``N^{-1}``
    applies in the eigenbasis above, so again only ``N_u x N_v`` matrices appear.
Missing data
    NaN cells break the grid: the problem is then solved as one sparse KKT system over the valid
    cells (:mod:`._missing`), with the same smoothing term (its Gram matrices those of the complete
    grid), a small λ by default keeping poles without data defined.
GCV with constraints
    Point-wise rows make the fit ``f = K (N^{-1} - N^{-1} C^T S^{-1} C N^{-1}) K^T y + const``, so
    the influence trace loses ``tr(S^{-1} C N^{-1} G N^{-1} C^T)``, a ``K x K`` product computed in
    the eigenbasis (``N^{-1} G N^{-1} = X W^2 X^T``) beside ``S`` itself. Separable constraints
    only reduce the problem (the trace is that of the reduced one).

References
----------
Course notes C25 (SIGGRAPH 1991) §7-4 Kronecker products, §7-5, §7-7 constraints; P. Dierckx,
*Curve and Surface Fitting with Splines* (1993) §5.2 (gridded data); Eilers, Currie and Durbán,
"Fast and compact smoothing on large multidimensional grids", CSDA 50 (2006).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
from numpy.typing import ArrayLike, NDArray

from .. import _validate as V
from .. import tolerances
from ..errors import InvalidGeometryError, ParameterError
from ..kernel.basis import basis_matrix
from ..kernel.surface import BSplineSurface
from ..manipulation.linalg import ConstraintError, ConstraintFactor
from ._common import difference_penalty
from ._missing import SparseGrid
from .grid_constraints import (
    BoundaryCurve,
    Constraint,
    CrossDerivative,
    FixedPoint,
    Rows,
    Space,
    Symmetry,
    TangentPlane,
    build_rows,
    stack_rows,
)
from .interpolation import approximation_knots, parametrize

__all__ = [
    "BoundaryCurve",
    "CrossDerivative",
    "FixedPoint",
    "TangentPlane",
    "Symmetry",
    "GridFit",
    "fit_grid",
]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class GridFit:
    """Result of :func:`fit_grid`.

    Attributes
    ----------
    surface : BSplineSurface
        3-D (a height grid gives ``x = u``, ``y = v`` exactly: poles at the Greville abscissae).
    u_params, v_params : ndarray, shapes (m,) and (n,)
    residual : ndarray, shape (m, n)
        ``|Q[i, j] - S(u_i, v_j)|`` (NaN on missing cells): the deviation at the data parameters
        (vertical for height grids), an upper bound of the distance to the surface.
    max_error, rms_error : float
        Of ``residual`` over the valid cells.
    smoothing : float
        The λ used (chosen by GCV when asked).
    gcv : float or None
        The GCV score at that λ (when computed).
    method : str
        ``"kronecker"`` or ``"sparse"`` (missing data).
    """

    surface: BSplineSurface
    u_params: Array
    v_params: Array
    residual: Array
    max_error: float
    rms_error: float
    smoothing: float
    gcv: float | None = None
    method: str = "kronecker"
    extras: dict = field(default_factory=dict)


# ----------------------------------------------------------------------------- data
def _grid_data(data: ArrayLike, x: ArrayLike | None, y: ArrayLike | None) -> tuple[Array, bool, Array | None, Array | None]:
    try:
        Q = np.asarray(data, dtype=float)
    except (TypeError, ValueError) as err:
        raise InvalidGeometryError(f"data: expected an (m, n) or (m, n, d) array of numbers, got {type(data).__name__}") from err
    if Q.ndim == 2:
        heights = True
        Q = Q[..., None]
    elif Q.ndim == 3 and Q.shape[2] >= 1:
        heights = False
    else:
        raise InvalidGeometryError(f"data: expected shape (m, n) heights or (m, n, d) points, got {Q.shape}")
    if np.any(np.isinf(Q)):
        raise InvalidGeometryError("data: expected finite values or NaN (missing), got infinity")
    m, n = Q.shape[:2]
    xs = ys = None
    if heights:
        xs = np.linspace(0.0, 1.0, m) if x is None else V.as_finite_array(x, "x", ndim=1)
        ys = np.linspace(0.0, 1.0, n) if y is None else V.as_finite_array(y, "y", ndim=1)
        for name, t, k in (("x", xs, m), ("y", ys, n)):
            if t.shape[0] != k or np.any(np.diff(t) <= 0):
                raise InvalidGeometryError(f"{name}: expected {k} strictly increasing grid coordinates, got shape {t.shape}")
    elif x is not None or y is not None:
        raise InvalidGeometryError("x, y: grid coordinates are for (m, n) height data; (m, n, d) points carry their own")
    return Q, heights, xs, ys


def _params(Q: Array, heights: bool, xs: Array | None, ys: Array | None, u_params: ArrayLike | None,
            v_params: ArrayLike | None, method: str) -> tuple[Array, Array]:
    m, n = Q.shape[:2]
    if heights:
        if xs is None or ys is None:  # _data gives height data its grid coordinates
            raise InvalidGeometryError("x, y: height data needs grid coordinates")
        u = xs if u_params is None else V.as_finite_array(u_params, "u_params", ndim=1)
        v = ys if v_params is None else V.as_finite_array(v_params, "v_params", ndim=1)
    else:
        filled = np.where(np.isnan(Q), np.nanmean(Q, axis=(0, 1)), Q) if np.isnan(Q).any() else Q
        u = parametrize(filled, method) if u_params is None else V.as_finite_array(u_params, "u_params", ndim=1)
        v = (parametrize(filled.transpose(1, 0, 2), method) if v_params is None
             else V.as_finite_array(v_params, "v_params", ndim=1))
    for name, t, k in (("u_params", u, m), ("v_params", v, n)):
        if t.shape[0] != k or np.any(np.diff(t) <= 0):
            raise InvalidGeometryError(f"{name}: expected {k} strictly increasing values, got shape {t.shape}")
    return u, v


def _knots(params: Array, n: int, p: int, knots: ArrayLike | None, name: str) -> Array:
    m = params.shape[0]
    if knots is None:
        if not p + 1 <= n <= m:
            raise InvalidGeometryError(f"n_poles: expected {p + 1} <= {name} poles <= {m} (data count) for degree {p}, got {n}")
        return approximation_knots(params, n, p)
    t = V.check_knots(knots, p, n, f"knots ({name})")
    if params[0] < t[p] - 1e-12 * (t[n] - t[p]) or params[-1] > t[n] + 1e-12 * (t[n] - t[p]):
        raise ParameterError(f"knots ({name}): the domain [{t[p]!r}, {t[n]!r}] does not hold the data parameters "
                             f"[{params[0]!r}, {params[-1]!r}]")
    return t


# ----------------------------------------------------------------------------- the diagonalised system
class _Direction:
    """One direction of the (reduced) Kronecker system of one coordinate.

    ``G = A^T A`` and ``R = c D^T D`` on the full poles; ``Gz = Z^T G Z``, ``Rz = Z^T R Z`` on the
    null space of the separable constraints (``Z = None``: no constraint); ``X``, ``mu`` the
    generalised eigenpairs ``X^T Gz X = I``, ``X^T Rz X = diag(mu)``.
    """

    def __init__(self, A: Array, Z: Array | None) -> None:
        n = A.shape[1]
        self.Z = Z
        self.G = A.T @ A
        Dp = difference_penalty(n, 2)
        tr = float(np.trace(Dp))
        self.R = (np.trace(self.G) / (2.0 * tr)) * Dp if tr > 0 else np.zeros((n, n))
        self.Gz = self.G if Z is None else Z.T @ self.G @ Z
        self.Rz = self.R if Z is None else Z.T @ self.R @ Z
        if self.Gz.shape[0] == 0:
            self.mu, self.X = np.zeros(0), np.zeros((0, 0))
            return
        try:
            mu, X = sla.eigh(self.Rz, self.Gz, check_finite=False)
        except np.linalg.LinAlgError as err:
            raise InvalidGeometryError(
                "n_poles: the data do not determine every pole (a knot span without data: the Schoenberg–Whitney "
                "condition fails); use fewer poles, the default knots, or smoothing") from err
        self.mu, self.X = np.maximum(mu, 0.0), X

    def reduce(self, M: Array, axis: int) -> Array:
        return M if self.Z is None else np.moveaxis(np.tensordot(self.Z.T, M, axes=(1, axis)), 0, axis)

    def expand(self, M: Array, axis: int) -> Array:
        return M if self.Z is None else np.moveaxis(np.tensordot(self.Z, M, axes=(1, axis)), 0, axis)


class _Coordinate:
    """The separable part of one coordinate's problem: particular solution ``Pc`` and the two
    reduced directions (null-space method, course §3-12)."""

    def __init__(self, A: Array, B: Array, cu: tuple[Array, Array] | None, cv: tuple[Array, Array] | None,
                 cache: dict[tuple[bytes | None, ...], tuple[_Direction, _Direction]]) -> None:
        Nu, Nv = A.shape[1], B.shape[1]
        Pc = np.zeros((Nu, Nv))
        Zs: list[Array | None] = []
        Fs: list[ConstraintFactor | None] = []
        for C in (cu, cv):
            if C is None or C[0].shape[0] == 0:
                Zs.append(None)
                Fs.append(None)
                continue
            F = ConstraintFactor(C[0], full=True)
            Zs.append(F.null_basis)
            Fs.append(F)
        Fu, Fv = Fs  # a factor exactly where the direction has constraints
        if Fv is not None and cv is not None:  # P Cv^T = Dv, i.e. Cv P^T = Dv^T (the targets, kv x Nu)
            Pc = Fv.solve(cv[1]).T
        if Fu is not None and cu is not None:  # then Cu P = Du without disturbing the columns: Pc += Ku (Du - Cu Pc)
            Pc = Pc + Fu.solve(cu[1] - cu[0] @ Pc)
        if Fv is not None and Fu is not None and cu is not None and cv is not None:
            gap = float(np.abs(cv[0] @ Pc.T - cv[1]).max())
            scale = max(1.0, float(np.abs(cv[1]).max()), float(np.abs(cu[1]).max()))
            if gap > tolerances.CONSISTENCY_RTOL * scale:
                raise ConstraintError(f"constraints: the u-side and v-side constraints disagree at a corner by {gap:.3g} "
                                      "(boundary curves must meet at the corners)")
        self.Pc = Pc
        key = tuple(None if Z is None else Z.tobytes() for Z in Zs)
        if key not in cache:
            cache[key] = (_Direction(A, Zs[0]), _Direction(B, Zs[1]))
        self.du, self.dv = cache[key]
        self.constrained = cu is not None or cv is not None

    def weights(self, lam: float) -> Array:
        return 1.0 / (1.0 + lam * (self.du.mu[:, None] + self.dv.mu[None, :]))

    def normal(self, P: Array, lam: float) -> Array:
        """``N P = G_u P G_v + λ (R_u P G_v + G_u P R_v)`` on the full poles."""
        du, dv = self.du, self.dv
        return (du.G + lam * du.R) @ P @ dv.G + lam * (du.G @ P @ dv.R)

    def reduced_rhs(self, AtQB: Array, lam: float) -> Array:
        r = AtQB - self.normal(self.Pc, lam) if self.constrained else AtQB
        return self.du.reduce(self.dv.reduce(r, 1), 0)

    def inverse(self, M: Array, W: Array) -> Array:
        """``N_z^{-1} M`` in the reduced coordinates (M of shape (nz_u, nz_v))."""
        Xu, Xv = self.du.X, self.dv.X
        return Xu @ ((Xu.T @ M @ Xv) * W) @ Xv.T

    def full(self, Y: Array) -> Array:
        return self.Pc + self.du.expand(self.dv.expand(Y, 1), 0)


def choose_smoothing(score: Callable[[float], float]) -> tuple[float, float]:
    """λ minimising ``score(λ)`` (GCV): a scan of log10 λ over [FIT_GCV_MIN_LOG10, FIT_GCV_MAX_LOG10]
    (27 values), then Brent's bounded search between the neighbours of the best; returns
    ``(λ, score)``."""
    lo, hi = float(tolerances.FIT_GCV_MIN_LOG10), float(tolerances.FIT_GCV_MAX_LOG10)
    grid = np.linspace(lo, hi, 27)
    vals = np.array([score(10.0 ** g) for g in grid])
    i = int(np.argmin(vals))
    a, b = grid[max(i - 1, 0)], grid[min(i + 1, grid.size - 1)]
    if not b > a:
        return 10.0 ** float(grid[i]), float(vals[i])
    import scipy.optimize  # here: ~50 ms at every process's start otherwise

    res = scipy.optimize.minimize_scalar(lambda g: score(10.0 ** g), bounds=(a, b), method="bounded",
                                         options={"xatol": 1e-3})
    best = (float(res.x), float(res.fun)) if res.fun < vals[i] else (float(grid[i]), float(vals[i]))
    return 10.0 ** best[0], best[1]


def _rss(A: Array, B: Array, Q: Array, valid_all: bool, P: Array) -> float:
    F = np.einsum("ia,abk,jb->ijk", A, P, B, optimize=True)
    return float(np.sum((F - Q) ** 2))


def _plain(A: Array, B: Array, Q: Array) -> Array:
    """Unconstrained, unsmoothed: ``P = G_u^{-1} A^T Q B G_v^{-1}`` (Cholesky of the small Gram
    matrices; ``A^T Q`` as a sparse product, the collocation rows having ``degree + 1`` entries)."""
    m, n, d = Q.shape
    As, Bs = sp.csr_matrix(A), sp.csr_matrix(B)
    T = np.asarray(As.T @ Q.reshape(m, n * d)).reshape(-1, n, d)  # (Nu, n, d)
    T = np.asarray(Bs.T @ T.transpose(1, 0, 2).reshape(n, -1)).reshape(-1, T.shape[0], d)  # (Nv, Nu, d)
    try:
        cu = sla.cho_factor(A.T @ A, check_finite=False)
        cv = sla.cho_factor(B.T @ B, check_finite=False)
    except np.linalg.LinAlgError as err:
        raise InvalidGeometryError(
            "n_poles: the data do not determine every pole (a knot span without data: the Schoenberg–Whitney "
            "condition fails); use fewer poles, the default knots, or smoothing") from err
    Nv, Nu = T.shape[:2]
    T = sla.cho_solve(cv, T.reshape(Nv, -1), check_finite=False).reshape(Nv, Nu, d)
    T = sla.cho_solve(cu, T.transpose(1, 0, 2).reshape(Nu, -1), check_finite=False)
    return T.reshape(Nu, Nv, d)


class _Kronecker:
    """The constrained, smoothed problem of every coordinate on the Kronecker structure."""

    def __init__(self, A: Array, B: Array, Q: Array, rows: Rows) -> None:
        self.A, self.B, self.Q = A, B, Q
        cache: dict = {}
        self.coords = [_Coordinate(A, B, stack_rows(rows.cu[c]), stack_rows(rows.cv[c]), cache) for c in range(Q.shape[2])]
        self.AtQB = [A.T @ Q[..., c] @ B for c in range(Q.shape[2])]
        self.rows = rows

    def separable(self, lam: float) -> tuple[list[Array], list[Array]]:
        Ys, Ws = [], []
        for co, r in zip(self.coords, self.AtQB):
            W = co.weights(lam)
            Ys.append(co.inverse(co.reduced_rhs(r, lam), W))
            Ws.append(W)
        return Ys, Ws

    def poles(self, Ys: list[Array]) -> Array:
        return np.stack([co.full(Y) for co, Y in zip(self.coords, Ys)], -1)

    def trace(self, lam: float) -> float:
        """``tr H`` of the influence matrix at λ (module notes): ``Σ_c Σ W_c`` for the separable
        problem, less ``tr(S^+ C N^{-1} G N^{-1} C^T)`` for the point-wise rows."""
        Ys, Ws = self.separable(lam)
        tr = float(sum(W.sum() for W in Ws))
        if self.rows.alpha:
            tr -= self._pointwise(Ys, Ws)[1]
        return tr

    def gcv(self, lam: float) -> float:
        """``nobs RSS / (nobs - tr H)^2`` with every constraint in force."""
        Ys, Ws = self.separable(lam)
        tr = float(sum(W.sum() for W in Ws))
        if self.rows.alpha:
            Ys, corr = self._pointwise(Ys, Ws)
            tr -= corr
        P = self.poles(Ys)
        rss = _rss(self.A, self.B, self.Q, True, P)
        nobs = self.Q.size
        return nobs * rss / max(nobs - tr, 1e-300) ** 2

    def choose(self) -> tuple[float, float]:
        return choose_smoothing(self.gcv)

    def solve(self, lam: float) -> Array:
        Ys, Ws = self.separable(lam)
        r = self.rows
        if r.alpha:
            Ys = self._pointwise(Ys, Ws)[0]
        return self.poles(Ys)

    def _pointwise(self, Ys: list[Array], Ws: list[Array]) -> tuple[list[Array], float]:
        """Point-wise rows through the Schur complement ``S = C N^{-1} C^T`` of the reduced problem.

        Returns the corrected reduced solutions and the influence-trace correction
        ``tr(S^+ C N^{-1} G N^{-1} C^T)`` (in the eigenbasis ``N^{-1} G N^{-1} = X W^2 X^T``)."""
        r = self.rows
        K = len(r.alpha)
        Al, Be, Wt = np.stack(r.alpha), np.stack(r.beta), np.stack(r.w)  # (K, Nu), (K, Nv), (K, d)
        target = np.asarray(r.target)
        S = np.zeros((K, K))
        S2 = np.zeros((K, K))
        ab = []
        viol = -target.copy()
        for c, (co, Y, W) in enumerate(zip(self.coords, Ys, Ws)):
            P0 = co.full(Y)
            viol += Wt[:, c] * np.einsum("ki,ij,kj->k", Al, P0, Be)
            a = co.du.reduce(Al.T, 0).T @ co.du.X  # (K, nz_u)
            b = co.dv.reduce(Be.T, 0).T @ co.dv.X  # (K, nz_v)
            ab.append((a, b))
            TW = np.einsum("ki,li->kli", a, a) @ W  # (K, K, nz_v)
            S += np.outer(Wt[:, c], Wt[:, c]) * np.einsum("klj,kj,lj->kl", TW, b, b)
            TW2 = np.einsum("ki,li->kli", a, a) @ (W * W)
            S2 += np.outer(Wt[:, c], Wt[:, c]) * np.einsum("klj,kj,lj->kl", TW2, b, b)
        lam_k = sla.lstsq(S, viol, lapack_driver="gelsy", check_finite=False)[0]
        corr = float(np.trace(sla.lstsq(S, S2, lapack_driver="gelsy", check_finite=False)[0]))
        out = []
        for c, (co, Y, W) in enumerate(zip(self.coords, Ys, Ws)):
            a, b = ab[c]
            M = np.einsum("k,ki,kj->ij", lam_k * Wt[:, c], a, b) * W
            out.append(Y - co.du.X @ M @ co.dv.X.T)
        P = self.poles(out)
        res = np.einsum("kc,ki,ijc,kj->k", Wt, Al, P, Be) - target
        scale = max(1.0, float(np.abs(target).max()), float(np.abs(self.Q[np.isfinite(self.Q)]).max()))
        bad = np.flatnonzero(np.abs(res) > tolerances.LINEAR_CHECK_RTOL * scale)
        if bad.size:
            names = [r.labels[i] for i in bad]
            raise ConstraintError(f"constraints: {', '.join(names[:4])}{' ...' if len(names) > 4 else ''} cannot hold "
                                  f"together with the others (residual up to {np.abs(res).max():.3g}); they conflict "
                                  "or act on no free pole", bad, names)
        return out, corr


# ----------------------------------------------------------------------------- entry point
def _pair_of(x: int | Sequence[int], name: str) -> tuple[int, int]:
    if isinstance(x, bool):  # (unpacking a bool fails: the message below)
        raise InvalidGeometryError(f"{name}: expected an integer or a pair, got {x!r}")
    if isinstance(x, (int, np.integer)):
        return int(x), int(x)
    try:
        a, b = x
    except (TypeError, ValueError) as err:
        raise InvalidGeometryError(f"{name}: expected an integer or a pair, got {x!r}") from err
    if not all(isinstance(k, (int, np.integer)) and not isinstance(k, bool) for k in (a, b)):
        raise InvalidGeometryError(f"{name}: expected integers, got {x!r}")
    return int(a), int(b)


def fit_grid(data: ArrayLike, n_poles: int | tuple[int, int], degree: int | tuple[int, int] = 3, *,
             x: ArrayLike | None = None, y: ArrayLike | None = None,
             u_params: ArrayLike | None = None, v_params: ArrayLike | None = None, method: str = "centripetal",
             knots: tuple[ArrayLike | None, ArrayLike | None] | None = None,
             smoothing: float | str = 0.0, constraints: Sequence[Constraint] = (),
             fix_boundary: bool = False, measure: bool = True) -> GridFit:
    """Least-squares tensor-product surface of gridded data, with smoothing and constraints.

    Course §7-4 (Kronecker separation), §7-5 (least squares), §7-7 (constraints); see the module
    notes for the method. Without smoothing or constraints this is the plain least-squares fit
    (no end interpolation): the same coefficients as scipy's ``make_lsq_spline`` applied along u,
    then along v, with the same knots.

    Parameters
    ----------
    data : array_like, shape (m, n, d) or (m, n)
        Points ``Q[i, j]`` at ``(u_i, v_j)``, or heights ``z[i, j]`` over ``(x_i, y_j)``. NaN marks a
        missing cell (the fit then uses a sparse solve).
    n_poles : int or (int, int)
        Poles per direction, ``degree + 1 <= n_poles <= data count`` with the default knots.
    degree : int or (int, int)
    x, y : array_like, shapes (m,) and (n,), optional
        Grid coordinates of height data (default the unit square); they are the parameters.
    u_params, v_params : array_like, optional
        Data parameters; default ``method`` parameters averaged over grid lines (point data).
    method : {"centripetal", "chord", "uniform"}
    knots : (array_like or None, array_like or None), optional
        Full knot vectors; default :func:`~.interpolation.approximation_knots` (every span holds data).
    smoothing : float or "gcv"
        λ of the difference penalty (module notes), ``>= 0``; ``"gcv"`` chooses it by generalised
        cross-validation, with every constraint in force and over the valid cells of data with
        missing ones (the influence trace of :mod:`._missing`); ``extras["trace"]`` then holds
        the influence matrix's trace at the chosen λ.
    constraints : sequence of BoundaryCurve, CrossDerivative, FixedPoint, TangentPlane, Symmetry
    fix_boundary : bool
        Shorthand for :class:`BoundaryCurve` on all four sides, fitted to the boundary data rows.
    measure : bool
        Compute the residual at every data point (default). ``False`` skips it (``residual`` is
        empty, ``max_error``/``rms_error`` NaN): the fit alone, for callers that measure otherwise.

    Returns
    -------
    GridFit

    Raises
    ------
    InvalidGeometryError
        Bad shapes, too few data for the degree, poles not determined by the data.
    ConstraintError
        Conflicting constraints (named).
    """
    Q, heights, xs, ys = _grid_data(data, x, y)
    m, n = Q.shape[:2]
    pu, pv = (V.as_degree(k) for k in _pair_of(degree, "degree"))
    if m < pu + 1 or n < pv + 1:
        raise InvalidGeometryError(f"data: a degree ({pu}, {pv}) fit needs at least {pu + 1} x {pv + 1} points, got {m} x {n}")
    Nu, Nv = _pair_of(n_poles, "n_poles")
    u, v = _params(Q, heights, xs, ys, u_params, v_params, method)
    ku, kv = (None, None) if knots is None else knots
    tu, tv = _knots(u, Nu, pu, ku, "u"), _knots(v, Nv, pv, kv, "v")
    lam_given = smoothing
    if isinstance(smoothing, str):
        if smoothing != "gcv":
            raise ParameterError(f"smoothing: expected a number >= 0 or 'gcv', got {smoothing!r}")
    elif not (np.isfinite(float(smoothing)) and float(smoothing) >= 0):
        raise ParameterError(f"smoothing: expected a number >= 0 or 'gcv', got {smoothing!r}")
    space = Space(Q, heights, u, v, (pu, pv), tu, tv)
    A = basis_matrix(tu, pu, Nu, np.clip(u, tu[pu], tu[Nu]))[0]
    B = basis_matrix(tv, pv, Nv, np.clip(v, tv[pv], tv[Nv]))[0]
    rows = build_rows(space, constraints, fix_boundary)
    missing = bool(np.isnan(Q).any())
    gcv = None
    extras: dict = {}
    if missing:
        sg = SparseGrid(A, B, Q, rows)
        if lam_given == "gcv":
            lam, gcv = choose_smoothing(sg.gcv)
            extras["trace"] = sg.trace(lam)
        else:
            lam = float(lam_given) or float(tolerances.FIT_MISSING_SMOOTHING)
        P = sg.solve(lam)
    elif lam_given == 0 and not any(rows.cu) and not any(rows.cv) and not rows.alpha:
        lam = 0.0
        P = _plain(A, B, Q)
    else:
        kr = _Kronecker(A, B, Q, rows)
        if lam_given == "gcv":
            lam, gcv = kr.choose()
            extras["trace"] = kr.trace(lam)
        else:
            lam = float(lam_given)
        P = kr.solve(lam)
    fit = _result(space, A, B, P, lam, gcv, "sparse" if missing else "kronecker", measure)
    fit.extras.update(extras)
    return fit


def _result(space: Space, A: Array, B: Array, P: Array, lam: float, gcv: float | None, how: str,
            measure: bool) -> GridFit:
    if measure:
        m, n, d = space.Q.shape
        F = (A @ P.reshape(A.shape[1], -1)).reshape(m, -1, d)  # (m, Nv, d)
        err = np.zeros((m, n))
        for c in range(d):  # one GEMM per coordinate, the squares summed in place
            r = F[:, :, c] @ B.T
            r -= space.Q[..., c]
            r *= r
            err += r
        np.sqrt(err, out=err)
        with np.errstate(invalid="ignore"):
            mx, rms = float(np.nanmax(err)), float(np.sqrt(np.nanmean(err * err)))
    else:
        err, mx, rms = np.zeros((0, 0)), float("nan"), float("nan")
    if space.heights:
        Px, Py = space.fixed_poles()
        P = np.stack([Px, Py, P[..., 0]], -1)
    surf = BSplineSurface(space.deg, space.knots, np.ascontiguousarray(P))
    return GridFit(surf, space.u, space.v, err, mx, rms, lam, gcv, how)
