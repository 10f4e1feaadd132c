"""The multifrontal Cholesky factorisation on a tensor-product grid (``kernel.grid_cholesky``):
against a dense Cholesky on random positive definite stencil matrices, the refusals, and the
elimination tree's invariants."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla
import scipy.sparse as sp
from hypothesis import given, settings
from hypothesis import strategies as st

from occsurf.algorithms.errors import InvalidGeometryError
from occsurf.algorithms.kernel.grid_cholesky import GridCholesky, NotPositiveDefinite, _plan


def _stencil_spd(nu: int, nv: int, reach: int, seed: int, spread: float = 0.0) -> sp.csr_matrix:
    """``D (A^T A + 0.1 I) D``: the rows of ``A`` each touch a ``(reach + 1)^2`` block of grid points
    (as a B-spline sample row does), ``D`` a diagonal of ``10^U(-spread, spread)``."""
    rng = np.random.default_rng(seed)
    rows = 2 * nu * nv
    w = reach + 1
    i0 = rng.integers(0, max(nu - w, 0) + 1, rows)
    j0 = rng.integers(0, max(nv - w, 0) + 1, rows)
    di, dj = (a.ravel() for a in np.meshgrid(np.arange(min(w, nu)), np.arange(min(w, nv)), indexing="ij"))
    cols = (i0[:, None] + di[None, :]) * nv + (j0[:, None] + dj[None, :])
    A = sp.csr_matrix((rng.standard_normal(cols.shape).ravel(), cols.ravel(),
                       np.arange(0, cols.size + 1, cols.shape[1])), shape=(rows, nu * nv))
    D = sp.diags(10.0 ** rng.uniform(-spread, spread, nu * nv))
    return (D @ (A.T @ A + 0.1 * sp.identity(nu * nv)) @ D).tocsr()


@settings(max_examples=60, deadline=None)
@given(nu=st.integers(1, 40), nv=st.integers(1, 40), reach=st.integers(0, 5), leaf=st.sampled_from([1, 8, 64, 256]),
       spread=st.sampled_from([0.0, 4.0]), seed=st.integers(0, 2 ** 31))
def test_solves_as_a_dense_cholesky_does(nu: int, nv: int, reach: int, leaf: int, spread: float, seed: int) -> None:
    """On random positive definite stencil matrices (also with a diagonal spread over 8 decades,
    which the Jacobi scaling takes out) the solution equals a dense Cholesky's of the same scaled
    system within 1e-9 of its largest entry (the systems' condition numbers after scaling are
    below ~1e4: round-off ~1e-12)."""
    K = _stencil_spd(nu, nv, reach, seed, spread)
    b = np.random.default_rng(seed + 1).standard_normal(nu * nv)
    x = GridCholesky(K, (nu, nv), reach, leaf=leaf).solve(b)
    d = 1.0 / np.sqrt(K.diagonal())
    ref = d * sla.cho_solve(sla.cho_factor(K.toarray() * d[:, None] * d[None, :]), d * b)
    assert np.abs(x - ref).max() <= 1e-9 * np.abs(ref).max()
    unscaled = GridCholesky(K, (nu, nv), reach, jacobi=False, leaf=leaf).solve(b)
    if spread == 0.0:
        assert np.abs(unscaled - ref).max() <= 1e-9 * np.abs(ref).max()


@settings(max_examples=40, deadline=None)
@given(nu=st.integers(1, 60), nv=st.integers(1, 60), reach=st.integers(1, 6), leaf=st.sampled_from([1, 8, 64, 256]))
def test_the_dissection_eliminates_every_point_once_and_each_ring_comes_later(nu: int, nv: int, reach: int,
                                                                              leaf: int) -> None:
    """The elimination order is a permutation of the grid; every front's ring is eliminated after
    its own points, and no grid point within ``reach`` of a node's own points that is eliminated
    later is missing from its front (else its coupling would be dropped)."""
    plan = _plan(nu, nv, reach, leaf)
    assert np.array_equal(np.sort(plan.order), np.arange(nu * nv))
    rank = np.empty(nu * nv, np.intp)
    rank[plan.order] = np.arange(nu * nv)
    for nd in plan.nodes:
        assert (nd.ring >= nd.stop).all()
        # each child's update lands on its ring's places in this front, in runs that stay either
        # among the own points or in the ring (the front's blocks are separate arrays)
        front = np.r_[np.arange(nd.start, nd.stop), nd.ring]
        own_size = nd.stop - nd.start
        for c, runs in zip(nd.children, nd.child_runs):
            at = np.concatenate([np.arange(f, f + n) for f, _, n in runs])
            assert np.array_equal(front[at], plan.nodes[c].ring)
            assert np.array_equal(np.concatenate([np.arange(u, u + n) for _, u, n in runs]),
                                  np.arange(plan.nodes[c].ring.size))
            assert all(f >= own_size or f + n <= own_size for f, _, n in runs)
        own = plan.order[nd.start:nd.stop]
        oi, oj = np.divmod(own, nv)
        ring = set(plan.order[nd.ring].tolist())
        for a, b in zip(oi, oj):
            for i in range(max(a - reach, 0), min(a + reach + 1, nu)):
                for j in range(max(b - reach, 0), min(b + reach + 1, nv)):
                    if rank[i * nv + j] >= nd.stop:
                        assert i * nv + j in ring


def test_refusals_name_the_problem() -> None:
    """Not positive definite (a negative diagonal, an indefinite matrix): ``NotPositiveDefinite``
    naming the grid point; an entry outside the stencil or the wrong shape: InvalidGeometryError."""
    with pytest.raises(NotPositiveDefinite, match=r"diagonal -1.0 at grid point \(0, 0\) of a 3 x 4 grid"):
        GridCholesky(-sp.identity(12, format="csr"), (3, 4), 1)
    K = sp.identity(12, format="lil")
    K[0, 1] = K[1, 0] = 2.0  # [[1, 2], [2, 1]]: indefinite
    with pytest.raises(NotPositiveDefinite, match=r"pivot at grid point \(0, [01]\) of a 3 x 4 grid"):
        GridCholesky(K.tocsr(), (3, 4), 1)
    K = sp.identity(25, format="lil")
    K[0, 24] = K[24, 0] = 0.1  # grid points (0, 0) and (4, 4) of a 5 x 5 grid: 4 apart
    with pytest.raises(InvalidGeometryError, match=r"couples grid points more than 3 apart on a 5 x 5 grid"):
        GridCholesky(K.tocsr(), (5, 5), 3)
    with pytest.raises(InvalidGeometryError, match=r"expected shape \(12, 12\) for a 3 x 4 grid"):
        GridCholesky(sp.identity(10, format="csr"), (3, 4), 1)


@settings(max_examples=30, deadline=None)
@given(nu=st.integers(1, 30), nv=st.integers(1, 30), reach=st.integers(1, 4), spread=st.sampled_from([0.0, 4.0]),
       seed=st.integers(0, 2 ** 31))
def test_the_stencil_form_gives_the_same_factor_bit_for_bit(nu: int, nv: int, reach: int, spread: float,
                                                             seed: int) -> None:
    """``from_stencil`` on ``grid_stencil(K)`` (the plate gives its system so, without the sparse
    matrix) solves exactly as the factor of ``K`` itself, byte for byte (the constructor goes through
    the stencil: one scaling for both)."""
    from occsurf.algorithms.kernel.grid_cholesky import grid_stencil

    K = _stencil_spd(nu, nv, reach, seed, spread)
    b = np.random.default_rng(seed + 2).standard_normal(nu * nv)
    want = GridCholesky(K, (nu, nv), reach).solve(b)
    got = GridCholesky.from_stencil(grid_stencil(K, (nu, nv), reach)).solve(b)
    assert got.tobytes() == want.tobytes()
    with pytest.raises(InvalidGeometryError, match=r"expected shape \(nu, nv, w, w\) with w odd"):
        GridCholesky.from_stencil(np.zeros((nu, nv, 2, 2)))


def test_fronts_are_factored_and_solved_on_one_blas_thread() -> None:
    """OpenBLAS's threads spin while they wait: beside one busy process on the 2-core machine the
    bearing's refill of faces 171 and 185 (42 factorisations) took 266-349 s with the default two
    threads against 4.8 s with one. Every LAPACK / BLAS call of the factor and of the solve runs with
    one thread, whatever the process allows outside, and the process's limit is as it was after."""
    from threadpoolctl import threadpool_info, threadpool_limits

    import occsurf.algorithms.kernel.grid_cholesky as G

    def blas_counts() -> set[int]:
        return {int(i["num_threads"]) for i in threadpool_info() if i["user_api"] == "blas"}

    seen: list[set[int]] = []
    K = _stencil_spd(30, 30, 3, seed=7)
    b = np.arange(900.0)
    with pytest.MonkeyPatch.context() as mp:
        for name, lib in (("dpotrf", G.lapack), ("dtrsm", G.blas), ("dsyrk", G.blas), ("dtrsv", G.blas)):
            f = getattr(lib, name)
            mp.setattr(lib, name, lambda *a, _f=f, **k: seen.append(blas_counts()) or _f(*a, **k))
        with threadpool_limits(limits=2, user_api="blas"):
            x = GridCholesky(K, (30, 30), 3).solve(b)
            after = blas_counts()
    assert seen and all(s == {1} for s in seen), seen
    assert after == {2}  # the limit outside, back
    assert np.allclose(K @ x, b, rtol=0, atol=1e-8 * np.abs(b).max())


def test_without_threadpoolctl_the_factor_runs_on_the_libraries_own_threads() -> None:
    """``occsurf.algorithms`` needs NumPy and SciPy alone: without threadpoolctl ``blas_threads``
    limits nothing, and the factor and its solve work as before."""
    import subprocess
    import sys

    code = ("import sys; sys.modules['threadpoolctl'] = None\n"
            "import numpy as np\n"
            "from occsurf.algorithms.kernel.grid_cholesky import GridCholesky\n"
            "from occsurf.algorithms.threads import blas_threads\n"
            "import scipy.sparse as sp\n"
            "T = sp.diags([-1.0, 2.0, -1.0], [-1, 0, 1], shape=(5, 5))\n"
            "K = (sp.kron(T, sp.identity(5)) + sp.kron(sp.identity(5), T) + sp.identity(25)).tocsr()\n"
            "with blas_threads(): pass\n"
            "x = GridCholesky(K, (5, 5), 1).solve(np.ones(25))\n"
            "assert np.allclose(K @ x, 1.0), x\n"
            "assert 'threadpoolctl' not in sys.modules or sys.modules['threadpoolctl'] is None\n")
    subprocess.run([sys.executable, "-c", code], check=True)
