"""Tensor-product B-spline and NURBS surfaces (course §2, §6, §12).

:class:`BSplineSurface` is a frozen value; every operation returns a new surface. The control net
is ``(n_u, n_v, d)`` with the first index along u (OCC's pole rows); weights are ``(n_u, n_v)``.
Every knot operation is the curve kernel applied to the net's rows or columns at once.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import partial
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import _numba_kernels as _nk
from .. import _validate as V
from .. import tolerances
from ..errors import InvalidGeometryError, ParameterError, ToleranceError
from ._common import ARRAY_PAIR, PAIR, ControlPointValue
from ._poles import HomogeneousPoles
from .basis import band_product, basis_derivatives, basis_functions, find_span, greville, span_groups
from .blossom import blossom_basis
from .degree import elevate_poles
from .knots import (
    bezier_poles,
    check_rescaled,
    clamp_poles,
    insert_knot_boehm,
    merge_knots,
    most_repeated,
    multiplicity,
    refine_poles,
    remove_knot_lsq,
    rescale_knots,
    snap_knot,
    snap_knots,
    split_poles,
)
from .rational import pole_deviation, surface_quotient_rule

__all__ = ["BSplineSurface"]

Array = NDArray[np.float64]
Direction = Literal["u", "v"]
_CHUNK = 1 << 15  # scattered evaluation works on blocks of this many points (bounded memory)


def _axis(direction: Direction) -> int:
    if direction not in ("u", "v"):
        raise InvalidGeometryError(f"direction: expected 'u' or 'v', got {direction!r}")
    return 0 if direction == "u" else 1


@dataclass(frozen=True, eq=False)
class BSplineSurface(HomogeneousPoles, ControlPointValue):
    """A tensor-product B-spline (or NURBS) surface.

    Parameters
    ----------
    degree : (int, int)
        ``(p, q)``, each 1 to 25.
    knots : (array_like, array_like)
        Full knot vectors ``U`` of length ``n_u + p + 1`` and ``V`` of length ``n_v + q + 1``.
    control_points : array_like, shape (n_u, n_v, d)
        The control net; first index along u.
    weights : array_like, shape (n_u, n_v), optional
        Positive weights for a rational surface.

    Raises
    ------
    InvalidGeometryError
        Naming the argument at fault.

    Notes
    -----
    **One rule for directional operations.** A method that works along one parameter direction
    (:meth:`insert_knot`, :meth:`remove_knot`, :meth:`refine`, :meth:`elevate_degree`,
    :meth:`split`, :meth:`reverse`) takes the same leading arguments, with the same names and
    defaults, as the :class:`~.curve.BSplineCurve` method of the same name, then ``direction``
    (``"u"`` or ``"v"``) as a *required keyword-only* argument::

        c.insert_knot(0.5, times=2)                  # curve
        s.insert_knot(0.5, times=2, direction="v")   # surface, along v
        s.elevate_degree(direction="u")              # times=1, as c.elevate_degree()

    ``direction`` has no default: a surface has no preferred direction, a default would turn a
    forgotten argument into a silent operation along u, and a keyword cannot be mistaken for a
    positional count or knot. Every call site says which direction it means. Methods acting on
    both directions at once take no ``direction``: :meth:`clamp`, :meth:`to_bezier`,
    :meth:`reparametrize` (one range per direction), :meth:`swap_uv`, :meth:`transform`.
    ``tests/algorithms/test_surface.py`` checks the rule on the signatures.

    ``to_dict``, ``from_dict``, ``transform`` and ``==`` come from
    :class:`._common.ControlPointValue` (dict type ``"BSplineSurface"``, header ``degree``,
    ``knots``).
    """

    _DICT_TYPE = "BSplineSurface"
    _HEADER = (("degree", PAIR), ("knots", ARRAY_PAIR))

    degree: tuple[int, int]
    knots: tuple[Array, Array]
    control_points: Array
    weights: Array | None = None
    _hpoles: Array = field(init=False, repr=False, compare=False)

    if TYPE_CHECKING:  # the generated __init__ takes array_like; __post_init__ stores float arrays

        def __init__(
            self,
            degree: Sequence[int],
            knots: Sequence[ArrayLike],
            control_points: ArrayLike,
            weights: ArrayLike | None = None,
        ) -> None: ...

    def __post_init__(self) -> None:
        deg = self.degree
        if not isinstance(deg, (tuple, list)) or len(deg) != 2:
            raise InvalidGeometryError(f"degree: expected a pair (p, q), got {deg!r}")
        p = V.as_degree(deg[0], "degree[0] (u)")
        q = V.as_degree(deg[1], "degree[1] (v)")
        P = V.as_finite_array(self.control_points, "control_points")
        if P.ndim != 3 or P.shape[2] < 1:
            raise InvalidGeometryError(f"control_points: expected shape (n_u, n_v, d), got {P.shape}")
        nu, nv = P.shape[:2]
        if nu < p + 1 or nv < q + 1:
            raise InvalidGeometryError(
                f"control_points: degree ({p}, {q}) needs at least ({p + 1}, {q + 1}) poles, got ({nu}, {nv})"
            )
        kn = self.knots
        if not isinstance(kn, (tuple, list)) or len(kn) != 2:
            raise InvalidGeometryError("knots: expected a pair (U, V) of full knot vectors")
        U = V.check_knots(kn[0], p, nu, "knots[0] (U)")
        Vk = V.check_knots(kn[1], q, nv, "knots[1] (V)")
        w = None if self.weights is None else V.check_weights(self.weights, (nu, nv))
        V.check_homogeneous(P, w)
        self._set((p, q), (U, Vk), P, w)

    def _set(self, deg: Sequence[int], kn: Sequence[Array], P: Array, w: Array | None) -> None:
        object.__setattr__(self, "degree", (int(deg[0]), int(deg[1])))
        object.__setattr__(self, "knots", (V.readonly(kn[0]), V.readonly(kn[1])))
        self._set_poles(P, w)

    @classmethod
    def _trusted(
        cls, degree: Sequence[int], knots: Sequence[ArrayLike], control_points: ArrayLike, weights: ArrayLike | None = None
    ) -> BSplineSurface:
        """Fast constructor for internal results that are valid by construction (no checks)."""
        obj = object.__new__(cls)
        obj._set(degree, (np.asarray(knots[0], float), np.asarray(knots[1], float)),
                 np.asarray(control_points, float), None if weights is None else np.asarray(weights, float))
        return obj

    def _rebuild(self, degree: Sequence[int], knots: Sequence[Array], hpoles: Array) -> BSplineSurface:
        return BSplineSurface._from_homogeneous(degree, knots, hpoles, self.is_rational)

    # ------------------------------------------------------------------ properties
    @property
    def n_poles(self) -> tuple[int, int]:
        return self.control_points.shape[0], self.control_points.shape[1]

    @property
    def dim(self) -> int:
        return self.control_points.shape[2]

    @property
    def domain(self) -> tuple[tuple[float, float], tuple[float, float]]:
        """``((u0, u1), (v0, v1))``."""
        (p, q), (U, Vk), (nu, nv) = self.degree, self.knots, self.n_poles
        return (float(U[p]), float(U[nu])), (float(Vk[q]), float(Vk[nv]))

    @property
    def homogeneous_points(self) -> Array:
        """``(n_u, n_v, d + 1)`` homogeneous net ``(w P, w)`` (the net itself if not rational)."""
        return self._hpoles

    def greville(self) -> tuple[Array, Array]:
        return greville(self.knots[0], self.degree[0]), greville(self.knots[1], self.degree[1])

    def __repr__(self) -> str:
        kind = "rational " if self.is_rational else ""
        return (f"BSplineSurface({kind}degree={self.degree}, poles={self.n_poles}, dim={self.dim}, "
                f"domain={self.domain})")

    # ------------------------------------------------------------------ evaluation
    def _uv(self, u: ArrayLike, v: ArrayLike) -> tuple[Array, Array, tuple[int, ...]]:
        # per point: the flattened u, v and the homogeneous result with its rational quotient
        return V.check_uv(u, v, self.domain, per_point=2 + 2 * self._hpoles.shape[-1])

    def _kernel_args(self) -> tuple[Any, ...]:
        """Knots, degrees, span bounds and homogeneous net, as the numba kernels take them; made
        once per surface (:meth:`_kept`)."""
        args: tuple[Any, ...] = self._kept("kernel_args", lambda: _nk.surface_args(self))
        return args

    def _scattered(self, u: Array, v: Array, order: int) -> Array:
        """Homogeneous partials ``(m, r+1, r+1, k)`` at scattered points, in bounded-memory chunks.

        The NumPy path (span-and-gather); :meth:`evaluate` and :meth:`derivatives` use the numba
        kernels instead when they apply (see :mod:`._numba_kernels`).
        """
        (p, q), (U, Vk), (nu, nv) = self.degree, self.knots, self.n_poles
        H = self._hpoles
        k = H.shape[2]
        Hflat = H.reshape(nu * nv, k)
        m = u.shape[0]
        out = np.empty((m, order + 1, order + 1, k))
        ar_p = np.arange(p + 1)
        ar_q = np.arange(q + 1)
        for s in range(0, m, _CHUNK):
            uu, vv = u[s : s + _CHUNK], v[s : s + _CHUNK]
            su = find_span(U, p, nu, uu)
            sv = find_span(Vk, q, nv, vv)
            idx = ((su[:, None] - p + ar_p)[:, :, None] * nv + (sv[:, None] - q + ar_q)[:, None, :])
            G = Hflat[idx]  # (c, p+1, q+1, k)
            if order == 0:
                Nu = basis_functions(U, p, su, uu)
                Nv = basis_functions(Vk, q, sv, vv)
                out[s : s + _CHUNK, 0, 0] = np.einsum("ci,cj,cijk->ck", Nu, Nv, G, optimize=True)
            else:
                Du = basis_derivatives(U, p, su, uu, order)
                Dv = basis_derivatives(Vk, q, sv, vv, order)
                out[s : s + _CHUNK] = np.einsum("cai,cbj,cijk->cabk", Du, Dv, G, optimize=True)
        return out

    def evaluate(self, u: ArrayLike, v: ArrayLike) -> Array:
        """Points at broadcastable parameters ``u``, ``v`` (scattered: span-and-gather).

        Returns
        -------
        ndarray, shape (broadcast(u, v).shape + (d,))

        Raises
        ------
        ParameterError
            A parameter outside the domain, not finite, or shapes that do not broadcast.

        Notes
        -----
        From ``tolerances.NUMBA_MIN_POINTS`` points on, an optional numba kernel computes the same
        values (to round-off) when numba is installed; ``OCCSURF_NO_NUMBA=1`` turns it off.
        """
        a, b, shape = self._uv(u, v)
        if _nk.applies(a.shape[0]):
            out = np.empty((a.shape[0], self.dim))
            if _nk.run("surface_points", *self._kernel_args(), a, b, self.is_rational, out):
                return out.reshape(shape + (self.dim,))
        H = self._scattered(a, b, 0)[:, 0, 0]
        if self.is_rational:
            H = H[:, :-1] / H[:, -1:]
        return H.reshape(shape + (self.dim,))

    __call__ = evaluate

    def derivatives(self, u: ArrayLike, v: ArrayLike, order: int = 1) -> Array:
        """Point and all partials ``d^{k+l} S / du^k dv^l`` for ``k, l <= order``.

        Returns
        -------
        ndarray, shape (..., order + 1, order + 1, d)
            ``[..., k, l, :]``; rational surfaces by the quotient rule (A4.4).

        Notes
        -----
        From ``tolerances.NUMBA_MIN_POINTS`` points on, an optional numba kernel computes the same
        values (to round-off) when numba is installed; ``OCCSURF_NO_NUMBA=1`` turns it off.
        """
        order = V.check_order(order)
        a, b, shape = self._uv(u, v)
        V.check_size((a.shape[0], order + 1, order + 1, self.dim + 1), f"derivatives of order {order} at "
                     f"{a.shape[0]} points")
        if _nk.applies(a.shape[0]):
            out = np.empty((a.shape[0], order + 1, order + 1, self.dim))
            if _nk.run("surface_derivatives", *self._kernel_args(), a, b, order, self.is_rational, out):
                return out.reshape(shape + (order + 1, order + 1, self.dim))
        H = self._scattered(a, b, order)
        if self.is_rational:
            H = surface_quotient_rule(H)
        return H.reshape(shape + (order + 1, order + 1, self.dim))

    def _grid_params(self, us: ArrayLike, vs: ArrayLike) -> tuple[Array, Array]:
        (u0, u1), (v0, v1) = self.domain
        a = V.check_parameters(us, u0, u1, "us").reshape(-1)
        b = V.check_parameters(vs, v0, v1, "vs").reshape(-1)
        return a, b

    def _grid_basis(self, ax: int, x: Array, order: int) -> tuple[NDArray[np.intp], Array]:
        """Spans ``(m,)`` and basis derivatives ``(m, order+1, degree+1)`` along one direction."""
        p, t, n = self.degree[ax], self.knots[ax], self.n_poles[ax]
        span = find_span(t, p, n, x)
        if order == 0:
            return span, basis_functions(t, p, span, x)[:, None, :]
        return span, basis_derivatives(t, p, span, x, order)

    def _grid_v(self, b: Array, order: int) -> Array:
        """The net contracted along v: ``G[I, b, j, c] = sum_J N_J^(j)(v_b) H[I, J, c]``.

        Returns
        -------
        ndarray, shape (n_u, m_v, order + 1, k), C-contiguous
        """
        nu, nv = self.n_poles
        H = self._hpoles
        k = H.shape[2]
        sv, Dv = self._grid_basis(1, b, order)
        Ht = np.ascontiguousarray(H.transpose(1, 0, 2)).reshape(nv, nu * k)
        R = band_product(Dv, sv, self.degree[1], Ht)  # (m_v, r+1, n_u * k): [b, j, I, c]
        return np.ascontiguousarray(R.reshape(b.shape[0], order + 1, nu, k).transpose(2, 0, 1, 3))

    def _grid_u(self, su: int, Du: Array, G: Array, sel: slice | NDArray[np.intp]) -> Array:
        """Homogeneous partials ``(g, m_v, r+1, r+1, k)`` of the grid rows ``sel`` sharing one u-span.

        ``G`` is :meth:`_grid_v`; rows of ``sel`` must all lie in the u-span ``su``.
        """
        p = self.degree[0]
        nu, mv, r1, k = G.shape
        D = Du[sel]
        g = D.shape[0]
        T = D.reshape(g * r1, p + 1) @ G.reshape(nu, mv * r1 * k)[su - p : su + 1]  # [a, i, b, j, c]
        return T.reshape(g, r1, mv, r1, k).transpose(0, 2, 1, 3, 4)

    def _grid_rows(self, su: NDArray[np.intp], Du: Array, G: Array, out: Array) -> Array:
        """``out`` (m_u, m_v, r+1, r+1, k) filled with the grid's homogeneous partials (NumPy path):
        one product per group of u-parameters sharing a span (:meth:`_grid_u`), ``su`` and ``Du``
        their spans and basis rows (:meth:`_grid_basis`), ``G`` :meth:`_grid_v`."""
        for sel, s in span_groups(su):
            out[sel] = self._grid_u(s, Du, G, sel)
        return out

    def evaluate_grid(self, us: ArrayLike, vs: ArrayLike) -> Array:
        """Points on the grid ``us x vs`` by two banded basis-matrix products.

        Each product uses only the ``degree + 1`` non-zeros of a basis-matrix row (one small
        matrix product per group of parameters sharing a knot span, :func:`.basis.band_product`).

        Returns
        -------
        ndarray, shape (len(us), len(vs), d), C-contiguous
        """
        a, b = self._grid_params(us, vs)
        mu, mv = a.shape[0], b.shape[0]
        V.check_size((mu, mv, self._hpoles.shape[-1]), f"evaluate_grid of {mu} x {mv} points")
        G = self._grid_v(b, 0)  # (n_u, m_v, 1, k)
        su, Nu = self._grid_basis(0, a, 0)
        k = G.shape[3]
        H = band_product(Nu, su, self.degree[0], G.reshape(G.shape[0], mv * k)).reshape(mu, mv, k)
        if self.is_rational:
            H = H[..., :-1] / H[..., -1:]
        return H

    def derivatives_grid(self, us: ArrayLike, vs: ArrayLike, order: int = 1) -> Array:
        """All partials up to ``order`` on the grid ``us x vs``.

        The net is contracted with the v-basis once (:meth:`_grid_v`), then with the u-basis
        row by row, only over the ``p + 1`` non-zero basis functions of each row.

        Returns
        -------
        ndarray, shape (len(us), len(vs), order + 1, order + 1, d), C-contiguous

        Notes
        -----
        From ``tolerances.NUMBA_MIN_POINTS`` points on, an optional numba kernel computes the same
        values (to round-off) when numba is installed; ``OCCSURF_NO_NUMBA=1`` turns it off.
        """
        order = V.check_order(order)
        if order == 0:
            return self.evaluate_grid(us, vs)[:, :, None, None, :]
        a, b = self._grid_params(us, vs)
        mu, mv, r1, d = a.shape[0], b.shape[0], order + 1, self.dim
        V.check_size((mu, mv, r1, r1, d + 1), f"derivatives_grid of order {order} on {mu} x {mv} points")
        G = self._grid_v(b, order)  # (n_u, m_v, r+1, k)
        k = G.shape[3]
        su, Du = self._grid_basis(0, a, order)
        p = self.degree[0]
        out = np.empty((mu, mv, r1, r1, d))
        G3 = G.reshape(G.shape[0], mv, r1 * k)
        if _nk.applies(mu * mv):
            if self.is_rational:
                done = _nk.run("grid_partials_rational", Du, su, p, G3, k, out.reshape(mu * mv, r1, r1, d))
            else:
                done = _nk.run("grid_partials", Du, su, p, G3, out.reshape(mu, mv, r1, r1 * k))
            if done:
                return out
        if not self.is_rational:
            return self._grid_rows(su, Du, G, out)
        # the quotient rule once over the whole grid (point by point: the values it gave per span group)
        out[...] = surface_quotient_rule(self._grid_rows(su, Du, G, np.empty((mu, mv, r1, r1, d + 1))))
        return out

    def normal(self, u: ArrayLike, v: ArrayLike) -> Array:
        """Unit normal ``S_u x S_v / |S_u x S_v|`` (3-D surfaces); NaN where it is degenerate."""
        if self.dim != 3:
            raise InvalidGeometryError(f"normal: needs a 3-D surface, this one has dim {self.dim}")
        d = self.derivatives(u, v, 1)
        n = np.cross(d[..., 1, 0, :], d[..., 0, 1, :])
        ln = np.linalg.norm(n, axis=-1, keepdims=True)
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(ln > 0, n / ln, np.nan)

    def blossom(self, args_u: ArrayLike, args_v: ArrayLike, span: tuple[float, float] | None = None) -> Array:
        """Tensor-product blossom of one polynomial patch (course §2-3 applied in u and v).

        Parameters
        ----------
        args_u : array_like, shape (..., p)
        args_v : array_like, shape (..., q)
        span : (float, float), optional
            A parameter pair selecting the patch; default the patch holding the argument means.

        Returns
        -------
        ndarray, shape (..., d)
        """
        (p, q), (U, Vk), (nu, nv) = self.degree, self.knots, self.n_poles
        au = V.as_finite_array(args_u, "args_u")
        av = V.as_finite_array(args_v, "args_v")
        if au.shape[-1:] != (p,) or av.shape[-1:] != (q,) or au.shape[:-1] != av.shape[:-1]:
            raise InvalidGeometryError(f"args_u, args_v: expected shapes (..., {p}) and (..., {q}), got {au.shape}, {av.shape}")
        shape = au.shape[:-1]
        au, av = au.reshape(-1, p), av.reshape(-1, q)
        (u0, u1), (v0, v1) = self.domain
        if span is None:
            cu, cv = np.clip(au.mean(1), u0, u1), np.clip(av.mean(1), v0, v1)
        else:
            cu = np.full(au.shape[0], float(V.check_parameters(span[0], u0, u1, "span[0]")))
            cv = np.full(av.shape[0], float(V.check_parameters(span[1], v0, v1, "span[1]")))
        mu, mv = find_span(U, p, nu, cu), find_span(Vk, q, nv, cv)
        A = blossom_basis(U, p, mu, au)
        B = blossom_basis(Vk, q, mv, av)
        iu = mu[:, None] - p + np.arange(p + 1)
        iv = mv[:, None] - q + np.arange(q + 1)
        G = self._hpoles[iu[:, :, None], iv[:, None, :]]
        H = np.einsum("ci,cj,cijk->ck", A, B, G)
        if self.is_rational:
            H = H[:, :-1] / H[:, -1:]
        return H.reshape(shape + (self.dim,))

    # ------------------------------------------------------------------ knot operations
    def _apply(self, direction: Direction, fn: Callable[[Array, int, Array], tuple[Array, Array]], new_degree: int | None = None) -> BSplineSurface:
        """Run a curve kernel ``fn(knots, degree, poles) -> (knots, poles)`` along ``direction``; the
        surface itself where the kernel returns its input as it was (``clamp_poles`` of clamped
        knots: as :meth:`BSplineCurve.clamp`, no rebuild through ``P = H / w`` and back)."""
        ax = _axis(direction)
        H = self._hpoles if ax == 0 else self._hpoles.transpose(1, 0, 2)
        t, H2 = fn(self.knots[ax], self.degree[ax], H)
        if t is self.knots[ax] and H2 is H and new_degree in (None, self.degree[ax]):
            return self
        if ax == 1:
            H2 = H2.transpose(1, 0, 2)
        deg = list(self.degree)
        kn = list(self.knots)
        kn[ax] = t
        if new_degree is not None:
            deg[ax] = new_degree
        return self._rebuild(tuple(deg), tuple(kn), np.ascontiguousarray(H2))

    def _interior(self, value: float, ax: int, name: str) -> float:
        lo, hi = self.domain[ax]
        x = float(V.check_parameters(value, lo, hi, name))
        if x <= lo or x >= hi:
            raise ParameterError(f"{name}: {x!r} must lie strictly inside the {'uv'[ax]} domain ({lo!r}, {hi!r})")
        snapped = snap_knot(self.knots[ax], x)
        if snapped <= lo or snapped >= hi:  # within the knot tolerance of an end: a piece would be empty
            raise ParameterError(f"{name}: {x!r} is within the knot tolerance of the {'uv'[ax]} domain end {snapped!r} "
                                 f"(domain ({lo!r}, {hi!r})); no interior knot can be placed there")
        return snapped

    def insert_knot(self, knot: float, times: int = 1, *, direction: Direction) -> BSplineSurface:
        """Insert ``knot`` in u or v, ``times`` times (Boehm, course §2-10). The surface is unchanged.

        As :meth:`BSplineCurve.insert_knot` on every row (``direction="u"``) or column of the net.
        """
        ax = _axis(direction)
        times = V.check_times(times)
        x = self._interior(knot, ax, "knot")
        s = multiplicity(self.knots[ax], x)
        if s + times > self.degree[ax]:
            raise InvalidGeometryError(
                f"times: {direction}-knot {x!r} has multiplicity {s}; {times} more exceeds the degree {self.degree[ax]}"
            )
        return self._apply(direction, lambda t, p, H: insert_knot_boehm(t, p, H, x, times))

    def refine(self, knots: ArrayLike, *, direction: Direction) -> BSplineSurface:
        """Insert many knots at once in one direction (Oslo refinement, course §2-10).

        As :meth:`BSplineCurve.refine`; ``knots`` (k,) strictly inside that direction's domain.
        """
        ax = _axis(direction)
        x = V.as_finite_array(knots, "knots", ndim=1)
        if x.size == 0:
            return self
        n, other = self._hpoles.shape[ax], self._hpoles.shape[1 - ax]
        what = f"refine with {x.size} {direction}-knots"
        V.check_size((n + x.size, n), what)  # the Oslo matrix (dense: new poles x old poles)
        V.check_size((n + x.size, other, self._hpoles.shape[-1] + 4), what)
        lo, hi = self.domain[ax]
        if x.min() <= lo or x.max() >= hi:
            bad = float(x.min() if x.min() <= lo else x.max())
            raise ParameterError(f"knots: {bad!r} must lie strictly inside the {direction} domain ({lo!r}, {hi!r})")
        x = snap_knots(self.knots[ax], x)
        tau = merge_knots(self.knots[ax], x)
        excess = most_repeated(tau, self.degree[ax] + 1)
        if excess is not None:
            raise InvalidGeometryError(
                f"knots: {direction}-knot {excess[0]!r} would get multiplicity {excess[1]} > degree + 1"
            )
        return self._apply(direction, lambda t, p, H: (tau, refine_poles(t, p, H, tau)))

    def elevate_degree(self, times: int = 1, *, direction: Direction) -> BSplineSurface:
        """Raise the degree in one direction (blossom form, course §2-6). Unclamped: clamped first."""
        ax = _axis(direction)
        times = V.check_times(times)
        if self.degree[ax] + times > tolerances.MAX_DEGREE:
            raise InvalidGeometryError(
                f"times: degree {self.degree[ax]} + {times} exceeds the maximum {tolerances.MAX_DEGREE}"
            )
        return self._apply(direction, lambda t, p, H: elevate_poles(t, p, H, times), self.degree[ax] + times)

    def remove_knot(self, knot: float, times: int = 1, tol: float | None = None, *,
                    direction: Direction) -> BSplineSurface:
        """Remove a u- or v-knot if no pole of the refined net moves more than ``tol``.

        See :meth:`BSplineCurve.remove_knot`; every row (column) of the net is solved at once.

        Raises
        ------
        ToleranceError
            Not removable within ``tol``; the message gives the deviation needed.
        """
        ax = _axis(direction)
        times = V.check_times(times)
        tol = V.check_tol(tolerances.KNOT_REMOVAL if tol is None else tol)
        x = self._interior(knot, ax, "knot")
        s = multiplicity(self.knots[ax], x)
        if s < times:
            raise InvalidGeometryError(f"knot: {x!r} is a {direction}-knot of multiplicity {s}, cannot remove it {times} times")
        dev_box: list[float] = []

        def kernel(t: Array, p: int, H: Array) -> tuple[Array, Array]:
            t2, H2, dev = remove_knot_lsq(t, p, H, x, times, partial(pole_deviation, rational=self.is_rational))
            dev_box.append(dev)
            return t2, H2

        result = self._apply(direction, kernel)
        if dev_box[0] > tol:
            raise ToleranceError(
                f"remove_knot: {direction}-knot {x!r} (x{times}) cannot be removed within tol={tol:g}; "
                f"the surface would move by up to {dev_box[0]:.3g}"
            )
        return result

    def clamp(self) -> BSplineSurface:
        """The same surface with clamped knot vectors in both directions: the surface itself where
        both already are (``clamp_poles`` returns clamped knots as they are, and :meth:`_apply` the
        surface then; a hole's neighbours were rebuilt five times a side before)."""
        return self._apply("u", clamp_poles)._apply("v", clamp_poles)

    def to_bezier(self) -> list[list[BSplineSurface]]:
        """Bézier patches (course §2-11): ``patches[i][j]`` covers u-span ``i`` and v-span ``j``."""
        (p, q) = self.degree
        bu, Hu = bezier_poles(self.knots[0], p, self._hpoles)  # (nsu, p+1, nv, k)
        out: list[list[BSplineSurface]] = []
        for i in range(Hu.shape[0]):
            bv, Hv = bezier_poles(self.knots[1], q, Hu[i].transpose(1, 0, 2))  # (nsv, q+1, p+1, k)
            Ku = np.r_[np.full(p + 1, bu[i]), np.full(p + 1, bu[i + 1])]
            row = []
            for j in range(Hv.shape[0]):
                Kv = np.r_[np.full(q + 1, bv[j]), np.full(q + 1, bv[j + 1])]
                row.append(self._rebuild((p, q), (Ku, Kv), np.ascontiguousarray(Hv[j].transpose(1, 0, 2))))
            out.append(row)
        return out

    def split(self, param: float, *, direction: Direction) -> tuple[BSplineSurface, BSplineSurface]:
        """Split at an interior u or v value ``param`` into two clamped surfaces (low side first)."""
        ax = _axis(direction)
        x = self._interior(param, ax, "param")
        left = self._apply(direction, lambda t, p, H: split_poles(t, p, H, x)[0])
        right = self._apply(direction, lambda t, p, H: split_poles(t, p, H, x)[1])
        return left, right

    def reverse(self, *, direction: Direction) -> BSplineSurface:
        """Reverse the parametrisation in u or v (flips the normal). Poles and weights are copied
        exactly (not rebuilt from homogeneous form)."""
        ax = _axis(direction)
        lo, hi = self.domain[ax]
        kn = list(self.knots)
        kn[ax] = (lo + hi) - kn[ax][::-1]
        P = np.flip(self.control_points, axis=ax)
        w = None if self.weights is None else np.flip(self.weights, axis=ax)
        return BSplineSurface._trusted(self.degree, tuple(kn), P, w)

    def swap_uv(self) -> BSplineSurface:
        """Exchange the roles of u and v (transpose the net)."""
        H = np.ascontiguousarray(self._hpoles.transpose(1, 0, 2))
        return self._rebuild(self.degree[::-1], self.knots[::-1], H)

    def reparametrize(self, u_range: tuple[float, float], v_range: tuple[float, float]) -> BSplineSurface:
        """The same surface on the domain ``u_range x v_range`` (affine changes of parameter).

        Only the knots change; poles and weights are shared unchanged."""
        kn = []
        for ax, (a, b) in enumerate((u_range, v_range)):
            a, b = float(a), float(b)
            if not (np.isfinite(a) and np.isfinite(b) and a < b):
                raise ParameterError(f"reparametrize: expected finite start < end in {'uv'[ax]}, got {a!r}, {b!r}")
            kn.append(check_rescaled(rescale_knots(self.knots[ax], self.domain[ax], (a, b)), self.knots[ax], (a, b),
                                     f"reparametrize ({'uv'[ax]})"))
        return BSplineSurface._trusted(self.degree, tuple(kn), self.control_points, self.weights)
