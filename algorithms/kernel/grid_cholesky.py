"""Sparse Cholesky factorisation of positive definite systems on a tensor-product grid.

The normal equations of a tensor-product B-spline fit (the G1 plate fill's ``A^T A + eps E``, course
§8-3) couple the coefficient ``(i, j)`` with ``(k, l)`` only where ``|i - k| <= p`` and ``|j - l| <= p``
(two basis functions overlap). Their unknowns are the points of an ``nu x nv`` grid and the matrix a
``(2 p + 1)^2``-point stencil on it. Such a matrix is factored here by the multifrontal method in the
order of George's nested dissection of the grid:

* the grid is cut recursively across its longer side by a separator ``p`` lines wide (which leaves
  the two halves uncoupled), down to boxes of at most ``leaf`` points;
* the boxes' points are eliminated first, each separator after both halves, every front (the
  points eliminated at a node of the tree and the ring ``p`` wide around its box that they still
  couple with) as a dense matrix: LAPACK's ``dpotrf`` on its own points, ``dtrsm`` for the ring's
  rows, ``dsyrk`` for the update that the parent adds to its front (George, *Nested dissection of a
  regular finite element mesh*, SIAM J. Numer. Anal. 10, 1973; Duff & Reid, *The multifrontal
  solution of indefinite sparse symmetric linear equations*, ACM TOMS 9, 1983; Liu, *The
  multifrontal method for sparse matrix solution: theory and practice*, SIAM Review 34, 1992).

Why not a library: SciPy's only sparse direct solver is SuperLU, an LU factorisation (twice the
work of Cholesky and its memory) whose orderings do not know the grid; the fast Cholesky codes
(CHOLMOD, through scikit-sparse or cvxopt) are GPL or ship without wheels, and QDLDL (Apache) is
slower than SuperLU here. On the 17 161-unknown plate of linkrods face 35 (bicubic, a 131 x 131
grid): SuperLU in symmetric mode 0.29-0.42 s, this factorisation 0.11-0.13 s; QDLDL 0.52 s; the
solves take as long as SuperLU's (8-9 ms). Where it loses: thin grids with a wide stencil (the
central split's degree-6 fairing systems, 38 x 363 or 108 x 568: 2.5-3.5x slower than SuperLU's
minimum degree, which finds the band there), which therefore stay with SuperLU.

Each front is held as the three blocks LAPACK works on (own x own, ring x own, ring x ring), each a
Fortran array factored in place: one array per front in C order cost a transposing copy of each
block into LAPACK and of each child's update into the front (2026-12-07: a 131 x 131 grid of reach 3
factored in 80 ms against 100-110 ms, the factors bit for bit the same). A solve reads the factors
twice (52 MB on that grid): 7-8 ms.

The order of the arithmetic differs from SuperLU's, so the solutions agree to the system's round-off
(its conditioning times the machine epsilon), not bit for bit.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray
from scipy.linalg import blas, lapack

from ..errors import InvalidGeometryError
from ..threads import blas_threads

__all__ = ["GridCholesky", "NotPositiveDefinite", "grid_stencil", "LEAF_POINTS"]

Array = NDArray[np.float64]
Index = NDArray[np.intp]

#: Largest box of the dissection that is not cut further (points). Measured on linkrods face 35's
#: plate (131 x 131, reach 3): 128 and 256 points factor alike, 64 and 512 are 10-60 % slower.
LEAF_POINTS = 256


class NotPositiveDefinite(InvalidGeometryError):
    """The matrix has a pivot <= 0 in the factorisation (it is not positive definite to working
    precision: indefinite, or semi-definite with round-off on the wrong side)."""


@dataclass(frozen=True)
class _Node:
    """One front of the elimination tree (indices in the eliminated order, see :class:`_Plan`).

    The front's matrix ``F`` (its own points first, then the ring) is held as three Fortran arrays,
    the blocks LAPACK works on in place: ``F11`` (own x own), ``F21`` (ring x own) and ``F22``
    (ring x ring, the children's updates and then the update to the parent)."""

    start: int  # its own points are start:stop of the eliminated order
    stop: int
    ring: Index  # the ring's points (eliminated later), in the order of the parent's front
    children: tuple[int, ...]
    child_runs: tuple[tuple[tuple[int, int, int], ...], ...]  # each child's ring in this front, as runs of
    # consecutive positions (start in this front, start in the child's ring, length), increasing, none
    # across the boundary between the own points and the ring
    own_flat: NDArray[np.integer]  # assembly: F11.T.flat[own_flat] = stencil[own_stencil] (F11 = K[own, own])
    own_stencil: NDArray[np.integer]
    ring_flat: NDArray[np.integer]  # F21.T.flat[ring_flat] = stencil[ring_stencil] (F21 = K[ring, own])
    ring_stencil: NDArray[np.integer]
    size: int  # own points + ring


@dataclass(frozen=True)
class _Plan:
    """The symbolic factorisation of a grid's stencil: the elimination order and the fronts."""

    order: Index  # order[k]: the grid point eliminated k-th (row-major index i * nv + j)
    nodes: tuple[_Node, ...]  # in elimination (post-)order: children before parents


def _box(i0: int, i1: int, j0: int, j1: int, nv: int) -> Index:
    """Row-major indices of the points of the box ``[i0, i1) x [j0, j1)``."""
    return (np.arange(i0, i1)[:, None] * nv + np.arange(j0, j1)[None, :]).ravel()


def _ring(box: tuple[int, int, int, int], nu: int, nv: int, reach: int) -> Index:
    """Row-major indices of the grid points within ``reach`` of the box (each index apart), outside it."""
    i0, i1, j0, j1 = box
    ii = np.arange(max(i0 - reach, 0), min(i1 + reach, nu))[:, None]
    jj = np.arange(max(j0 - reach, 0), min(j1 + reach, nv))
    return (ii * nv + jj)[(ii < i0) | (ii >= i1) | (jj < j0) | (jj >= j1)]


def _runs(pos: Index, cut: int) -> tuple[tuple[int, int, int], ...]:
    """Increasing positions as runs of consecutive ones, none across ``cut`` (one run ends below it,
    the next starts at it): ``(first position, its index in pos, length)``."""
    starts = np.flatnonzero(np.concatenate(([True], (np.diff(pos) != 1) | (pos[1:] == cut))))
    lengths = np.diff(np.append(starts, pos.size))
    return tuple(zip(pos[starts].tolist(), starts.tolist(), lengths.tolist()))


@lru_cache(maxsize=4)
def _plan(nu: int, nv: int, reach: int, leaf: int) -> _Plan:
    """Nested dissection of the ``nu x nv`` grid with separators ``reach`` wide, and its fronts.

    Kept for the last four grids only: a plate's stages seldom repeat a grid (linkrods face 35's 29
    stages made 29 plans, 2-26 ms each), and a plan's assembly maps take ~16 bytes per stencil entry,
    11 MB for a 131 x 131 grid of reach 3 (as int32 half of it, but the conversion to NumPy's index
    type on every factorisation cost more than the plan's build saved)."""
    boxes: list[tuple[int, int, int, int]] = []
    owns: list[Index] = []
    kids: list[tuple[int, ...]] = []

    def cut(i0: int, i1: int, j0: int, j1: int) -> int:
        ni, nj = i1 - i0, j1 - j0
        children: tuple[int, ...]
        if ni * nj <= leaf or max(ni, nj) <= 2 * reach + 1:
            own, children = _box(i0, i1, j0, j1, nv), ()
        elif ni >= nj:
            m = i0 + (ni - reach) // 2
            children = (cut(i0, m, j0, j1), cut(m + reach, i1, j0, j1))
            own = _box(m, m + reach, j0, j1, nv)
        else:
            m = j0 + (nj - reach) // 2
            children = (cut(i0, i1, j0, m), cut(i0, i1, m + reach, j1))
            own = _box(i0, i1, m, m + reach, nv)
        boxes.append((i0, i1, j0, j1))
        owns.append(own)
        kids.append(children)
        return len(owns) - 1

    root = cut(0, nu, 0, nv)
    order = np.concatenate(owns)
    rank = np.empty_like(order)
    rank[order] = np.arange(order.size)
    bounds = np.cumsum([0] + [o.size for o in owns])
    width = 2 * reach + 1
    # positions in the front are looked up on the grid padded by ``reach`` (-1 in the padding and
    # outside the front): a point's stencil neighbours are then its padded index plus fixed offsets
    pv = nv + 2 * reach
    di, dj = (a.ravel() for a in np.meshgrid(np.arange(-reach, reach + 1), np.arange(-reach, reach + 1), indexing="ij"))
    offsets = di * pv + dj

    gi, gj = np.divmod(np.arange(nu * nv), nv)
    padded = (gi + reach) * pv + gj + reach  # padded[index]: a grid point's index on the padded grid
    count = np.arange(nu * nv)
    rings: list[Index] = [np.zeros(0, np.intp)] * len(owns)
    nodes: list[_Node | None] = [None] * len(owns)
    where = np.full((nu + 2 * reach) * pv, -1, np.intp)
    for k in range(root, -1, -1):  # parents before children: a child's ring takes its parent's front order
        own = owns[k]
        front = np.concatenate((own, rings[k]))
        front_p = padded[front]
        where[front_p] = count[:front.size]
        pos = []
        for c in kids[k]:
            ring = _ring(boxes[c], nu, nv, reach)
            at = where[padded[ring]]  # every ring point of a child is in this front (the tree's invariant)
            if at.size and at.min() < 0:
                raise RuntimeError(f"grid_cholesky: a ring point of box {boxes[c]} is not in its parent's front")
            sort = np.argsort(at)
            rings[c], at = ring[sort], at[sort]
            pos.append(_runs(at, own.size))
        # F[:, :own] = K[front, own]: each own point's stencil neighbours that are in the front (the
        # others, in the box below the separator, were eliminated in the children's fronts)
        at = where[front_p[:own.size, None] + offsets]
        inside = at >= 0
        a, s = np.nonzero(inside)  # own point a, stencil offset s
        at, sten = at[inside], own[a] * (width * width) + s
        mine = at < own.size  # F11's entries, the rest F21's (blocks in Fortran order: column a)
        ring_rows = front.size - own.size
        nodes[k] = _Node(int(bounds[k]), int(bounds[k + 1]), rank[rings[k]], kids[k], tuple(pos),
                         a[mine] * own.size + at[mine], sten[mine],
                         a[~mine] * ring_rows + at[~mine] - own.size, sten[~mine],
                         int(front.size))
        where[front_p] = -1
    return _Plan(order, tuple(n for n in nodes if n is not None))


def grid_stencil(K: sp.spmatrix, shape: tuple[int, int], reach: int) -> Array:
    """``K``'s rows as a stencil on the ``nu x nv`` grid of its unknowns (:meth:`GridCholesky.from_stencil`'s
    layout): ``out[i, j, di + reach, dj + reach] = K[(i, j), (i + di, j + dj)]``, zero where ``K`` has no
    entry or the point leaves the grid; repeated entries of a non-canonical ``K`` are summed.

    An entry's offset ``d = c - r = di nv + dj`` is split by rounding ``d / nv`` (exact where
    ``|dj| <= reach < nv / 2``; an entry beyond the stencil either splits with an offset beyond
    ``reach`` or with a column that leaves the grid, which are refused alike), which saves the
    integer divisions of every entry; narrower grids divide.

    Raises
    ------
    InvalidGeometryError
        An entry couples points more than ``reach`` apart.
    """
    nu, nv = (int(x) for x in shape)
    reach = int(reach)
    C = K if sp.issparse(K) and K.format in ("csr", "csc") else sp.csr_matrix(K)
    counts = np.diff(C.indptr)
    lines = np.repeat(np.arange(C.shape[0], dtype=np.intp), counts)
    other = C.indices.astype(np.intp)
    row, col = (lines, other) if C.format == "csr" else (other, lines)
    width = 2 * reach + 1
    if nv > 2 * reach:
        d = col - row
        di = np.rint(d / nv).astype(np.intp)
        dj = d - di * nv
        j = np.repeat(np.arange(C.shape[0], dtype=np.intp) % nv, counts)  # the line's grid column
        j = j + dj if C.format == "csr" else j - dj  # the other point's: it must stay on the grid
        bad = (np.abs(di) > reach) | (np.abs(dj) > reach) | (j < 0) | (j >= nv)
    else:
        ri, rj = np.divmod(row, nv)
        ci, cj = np.divmod(col, nv)
        di, dj = ci - ri, cj - rj
        bad = (np.abs(di) > reach) | (np.abs(dj) > reach)
    if bad.any():
        k = int(np.argmax(bad))
        raise InvalidGeometryError(f"K: entry ({row[k]}, {col[k]}) couples grid points more than {reach} apart "
                                   f"on a {nu} x {nv} grid")
    # summed per entry (a matrix that is not canonical repeats some); an entry's single value is itself
    out = np.bincount((row * width + di + reach) * width + dj + reach, C.data, minlength=nu * nv * width * width)
    return np.asarray(out, dtype=np.float64).reshape(nu, nv, width, width)  # float64 already (weights)


def _jacobi(diag: Array, nu: int, nv: int) -> Array:
    """``1 / sqrt(diag)``; a diagonal entry <= 0 is :class:`NotPositiveDefinite` (naming its grid point)."""
    if not (diag > 0).all():
        bad = int(np.argmin(diag > 0))
        raise NotPositiveDefinite(f"K: not positive definite (diagonal {float(diag[bad])!r} at grid point "
                                  f"{divmod(bad, nv)} of a {nu} x {nv} grid)")
    return 1.0 / np.sqrt(diag)


class GridCholesky:
    """The Cholesky factor of a symmetric positive definite matrix whose unknowns are the points of an
    ``nu x nv`` grid, each coupled only with points at most ``reach`` apart in either index (see the
    module: multifrontal, nested dissection).

    Parameters
    ----------
    K : sparse matrix, shape (nu * nv, nu * nv)
        Symmetric positive definite; unknown ``i * nv + j`` is grid point ``(i, j)`` (the order of
        ``scipy.sparse.kron(A_u, A_v)``). Only the rows' entries below and on the diagonal of each
        front are read: ``K`` is taken to be symmetric.
    shape : (int, int)
        ``(nu, nv)``.
    reach : int
        The stencil's half-width (the degree ``p`` of a tensor-product B-spline basis).
    jacobi : bool, optional
        Factor ``D^-1/2 K D^-1/2`` (``D`` the diagonal; the solutions are unchanged) instead of
        ``K`` (default): a plate's diagonal spans 13 decades, and the scaled pivots keep the
        factorisation's round-off small (the plate fill's systems are scaled so).
    leaf : int, optional
        Largest box not cut further (default :data:`LEAF_POINTS`).

    Raises
    ------
    InvalidGeometryError
        ``K``'s shape is not the grid's, or an entry couples points further apart than ``reach``.
    NotPositiveDefinite
        ``K`` is not positive definite to working precision (a pivot <= 0; the message names the
        grid point).
    """

    def __init__(self, K: sp.spmatrix, shape: tuple[int, int], reach: int, *, jacobi: bool = True,
                 leaf: int = LEAF_POINTS) -> None:
        nu, nv = (int(x) for x in shape)
        reach = int(reach)
        if nu < 1 or nv < 1 or reach < 0 or K.shape != (nu * nv, nu * nv):
            raise InvalidGeometryError(f"K: expected shape ({nu * nv}, {nu * nv}) for a {nu} x {nv} grid "
                                       f"and a reach >= 0, got {K.shape} and reach {reach}")
        reach = max(reach, 1)  # a diagonal K is cut by separators one line wide, as a reach-1 stencil
        self._setup(grid_stencil(K, (nu, nv), reach), jacobi, int(leaf))

    @classmethod
    def from_stencil(cls, stencil: Array, *, jacobi: bool = True, leaf: int = LEAF_POINTS) -> GridCholesky:
        """The factor of the matrix given as stencil rows (:func:`.sparse_kron.kron_stencil`'s layout):
        ``stencil[i, j, di + reach, dj + reach]`` is the entry ``((i, j), (i + di, j + dj))``, zero
        where that leaves the grid; shape ``(nu, nv, w, w)``, ``w = 2 reach + 1 >= 3``. The same factor
        as from the sparse matrix of these entries, bit for bit, without building it.

        Raises
        ------
        InvalidGeometryError
            Not such an array.
        NotPositiveDefinite
            As the constructor.
        """
        S = np.asarray(stencil, float)
        if S.ndim != 4 or S.shape[2] != S.shape[3] or S.shape[2] % 2 == 0 or S.shape[2] < 3 or min(S.shape[:2]) < 1:
            raise InvalidGeometryError(f"stencil: expected shape (nu, nv, w, w) with w odd and >= 3, got {S.shape}")
        self = object.__new__(cls)
        self._setup(S, jacobi, int(leaf))
        return self

    def _setup(self, S: Array, jacobi: bool, leaf: int) -> None:
        """Scale the stencil rows ``S`` (shape ``(nu, nv, w, w)``) to a unit diagonal where asked
        (``scale[row] K scale[col]``) and factor them."""
        nu, nv, w = S.shape[0], S.shape[1], S.shape[2]
        reach = w // 2
        self._scale = _jacobi(S[:, :, reach, reach].ravel(), nu, nv) if jacobi else None
        if self._scale is not None:
            sc = self._scale.reshape(nu, nv)
            pad = np.zeros((nu + 2 * reach, nv + 2 * reach))
            pad[reach:reach + nu, reach:reach + nv] = sc
            S = (sc[:, :, None, None] * S) * np.lib.stride_tricks.sliding_window_view(pad, (w, w))
        with blas_threads():  # fronts of tens to a few thousand unknowns: one thread (see .threads)
            self._factor(S.ravel(), nu, nv, reach, leaf)

    def _factor(self, stencil: Array, nu: int, nv: int, reach: int, leaf: int) -> None:
        """Factor the (scaled) stencil rows, front by front."""
        plan = _plan(nu, nv, reach, leaf)
        factors: list[tuple[Array, Array]] = []
        updates: dict[int, Array] = {}
        for k, nd in enumerate(plan.nodes):
            own = nd.stop - nd.start
            ring = nd.size - own
            # the front's blocks in Fortran order (LAPACK's, worked on in place: no copies)
            F11, F21, F22 = np.zeros((own, own)).T, np.zeros((own, ring)).T, np.zeros((ring, ring)).T
            F11.T.ravel()[nd.own_flat] = stencil[nd.own_stencil]  # (views: the transposes are C arrays)
            F21.T.ravel()[nd.ring_flat] = stencil[nd.ring_stencil]
            for c, runs in zip(nd.children, nd.child_runs):
                U = updates.pop(c)
                for a, (fa, ua, na) in enumerate(runs):  # the lower triangle is what counts: the blocks
                    for fb, ub, nb in runs[:a + 1]:  # on and below the diagonal (the positions increase)
                        block = U[ua:ua + na, ub:ub + nb]
                        if fa >= own:  # runs never cross from the own points to the ring
                            if fb >= own:
                                F22[fa - own:fa - own + na, fb - own:fb - own + nb] += block
                            else:
                                F21[fa - own:fa - own + na, fb:fb + nb] += block
                        else:
                            F11[fa:fa + na, fb:fb + nb] += block
            L11, info = lapack.dpotrf(F11, lower=1, clean=1, overwrite_a=1)
            if info != 0:
                bad = int(plan.order[nd.start + abs(int(info)) - 1])
                raise NotPositiveDefinite(f"K: not positive definite (pivot at grid point {divmod(bad, nv)} "
                                          f"of a {nu} x {nv} grid)")
            if ring:
                L21 = blas.dtrsm(1.0, L11, F21, side=1, lower=1, trans_a=1, overwrite_b=1)
                updates[k] = blas.dsyrk(-1.0, L21, beta=1.0, c=F22, lower=1, overwrite_c=1)
            else:
                L21 = np.zeros((0, own))
            factors.append((L11, L21))
        self._plan, self._factors, self.shape = plan, factors, (nu, nv)

    def solve(self, b: Array) -> Array:
        """``K^-1 b`` for a vector ``b`` of ``nu * nv`` values (forward and back substitution by fronts)."""
        with blas_threads():
            return self._solve(b)

    def _solve(self, b: Array) -> Array:
        plan = self._plan
        y = np.array(b, float)
        if self._scale is not None:
            y = self._scale * y
        y = y[plan.order]
        for nd, (L11, L21) in zip(plan.nodes, self._factors):
            yo = blas.dtrsv(L11, y[nd.start:nd.stop], lower=1, overwrite_x=1)  # in place (a contiguous view)
            if nd.ring.size:
                y[nd.ring] -= L21 @ yo
        for nd, (L11, L21) in zip(reversed(plan.nodes), reversed(self._factors)):
            yo = y[nd.start:nd.stop]
            if nd.ring.size:
                yo -= L21.T @ y[nd.ring]
            blas.dtrsv(L11, yo, lower=1, trans=1, overwrite_x=1)
        x = np.empty_like(y)
        x[plan.order] = y
        return x if self._scale is None else self._scale * x
