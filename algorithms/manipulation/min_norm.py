"""The minimum-norm solve behind surface matching: one SVD of the row-equilibrated conditions,
noise directions dropped (course §4-4: ``dP = pinv(J) r``), and that SVD kept for solving with the
same matrix again.

:func:`robust_min_norm` is what :mod:`.matching` (G0-G3 along an edge, the Gauss-Newton steps of
G2 and G3) and :mod:`.match_inside` (G0, G1 along a trimmed face's edge) solve with; :func:`row_svd`
takes the factorisation (:class:`RowSVD`), through a QR factorisation first on tall matrices.

References
----------
R. Bartels, course notes C25 (SIGGRAPH 1991), §4-4; G. H. Golub, C. F. Van Loan, *Matrix
Computations*, 4th ed., §5.4.5 (R-bidiagonalisation: the SVD of a tall matrix through its QR).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
from numpy.typing import NDArray
from scipy.linalg.lapack import dormqr as _dormqr

from .. import tolerances
from ..errors import InvalidGeometryError, KernelError

__all__ = ["RowSVD", "row_svd", "robust_min_norm"]

Array = NDArray[np.float64]

#: :func:`row_svd` takes a QR factorisation first when ``J`` has at least this many times as many rows
#: as columns (and at least :data:`_QR_MIN_COLUMNS` columns): the SVD of the square ``R`` then, and
#: ``U^T b`` as ``U_R^T (Q^T b)`` with ``Q^T`` applied by its Householder reflectors (LAPACK's
#: ``dormqr``), never forming ``U``. LAPACK's ``gesdd`` takes a QR first on such matrices too, so the
#: singular values agree (bit for bit in 400 random draws with this build's LAPACK; the test asks
#: 1e-13 of the largest, and 1e-10 of the minimum-norm solution, whose largest difference there was
#: 2.2e-14); what it saves is forming ``U = Q U_R`` (m x n) and multiplying by it. On the bearing's
#: repair (the G2 matches' Gauss-Newton steps, J up to 2410 x 306) 1.4-1.8x faster per
#: factorisation (1940 x 336: 38.7 ms against 68.1 ms). Below it (near-square, small) the plain SVD
#: is faster.
_QR_ROWS_PER_COLUMN = 2
_QR_MIN_COLUMNS = 32


@dataclass(frozen=True, eq=False)
class RowSVD:
    """The SVD :func:`robust_min_norm` takes of ``J`` with its rows divided by their norms,
    ``J / s[:, None] = U diag(sv) Vt`` (made by :func:`row_svd`).

    ``U`` is held either as the SVD gave it, or, for a tall ``J``, as ``Q U_R``: ``Q`` in LAPACK's
    Householder form (``qr``, ``tau``) and ``U_R`` the left singular vectors of ``J``'s ``R``.

    Attributes
    ----------
    s : ndarray, shape (m,)
        The row norms of ``J`` (1 for a zero row).
    sv : ndarray, shape (k,)
        Singular values, decreasing (``k = min(m, n)``).
    Vt : ndarray, shape (k, n)
        Right singular vectors, as rows.
    U : ndarray, shape (m, k), or None
        Left singular vectors (the plain SVD); ``None`` on the QR path.
    qr, tau : ndarray, shapes (m, n) and (n,), or None
        The QR factorisation's reflectors (LAPACK's ``geqrf`` layout, Fortran order).
    U_R : ndarray, shape (n, n), or None
        Left singular vectors of ``R``.
    """

    s: Array
    sv: Array
    Vt: Array
    U: Array | None = None
    qr: Array | None = None
    tau: Array | None = None
    U_R: Array | None = None

    def __post_init__(self) -> None:
        qr_path = (self.qr is not None, self.tau is not None, self.U_R is not None)
        if (self.U is None) != all(qr_path) or (self.U is not None and any(qr_path)):
            raise InvalidGeometryError("RowSVD: give either U, or qr, tau and U_R (the QR path)")

    def project(self, b: Array) -> Array:
        """``U^T b``.

        Parameters
        ----------
        b : ndarray, shape (m,) or (m, r)

        Returns
        -------
        ndarray, shape (k,) or (k, r)
        """
        if self.U is not None:
            return self.U.T @ b
        qr, tau, U_R = self.qr, self.tau, self.U_R
        assert qr is not None and tau is not None and U_R is not None  # __post_init__
        n = qr.shape[1]
        b2 = np.asfortranarray(b.reshape(b.shape[0], -1))
        # lwork = the number of right-hand sides: LAPACK's unblocked dorm2r (the reflectors one by
        # one), which for the one to three right-hand sides of the matches is what blocking would do
        cq, _, info = _dormqr("L", "T", qr, tau, b2, max(1, b2.shape[1]))
        if info != 0:
            raise KernelError(f"dormqr: LAPACK info {info}")
        return U_R.T @ cq[:n].reshape((n,) + b.shape[1:])


def row_svd(J: Array) -> RowSVD:
    """The SVD :func:`robust_min_norm` takes of ``J`` (:class:`RowSVD`), its rows divided by their
    norms (a zero row by 1); tall matrices through their QR factorisation first (see
    :data:`_QR_ROWS_PER_COLUMN`)."""
    s = np.linalg.norm(J, axis=1)
    s = np.where(s > 0, s, 1.0)
    m, n = J.shape
    if n >= _QR_MIN_COLUMNS and m >= _QR_ROWS_PER_COLUMN * n:
        Jn = np.divide(J, s[:, None], order="F")  # LAPACK's layout: factored in place, no copy
        (qr, tau), R = sla.qr(Jn, mode="raw", overwrite_a=True)  # R: (n, n), upper triangular
        U_R, sv, Vt = sla.svd(R, full_matrices=False, lapack_driver="gesdd")
        return RowSVD(s, sv, Vt, qr=qr, tau=tau, U_R=U_R)
    U, sv, Vt = sla.svd(J / s[:, None], full_matrices=False, lapack_driver="gesdd")
    return RowSVD(s, sv, Vt, U=U)


def robust_min_norm(J: Array, rhs: Array, svd: RowSVD | None = None) -> Array:
    """Minimum-norm least-squares solution, rows divided by their norms, noise directions dropped
    (``rhs`` one vector, or one column per right-hand side).

    Two cut-offs of one SVD: singular values above ``1e-12`` of the largest (the exact minimum-norm
    solution of a consistent system) and above ``tolerances.MATCH_RCOND`` of it. The first is kept
    unless it is more than twice as long as the second: then it buys its smaller residual by
    fitting noise, such as the collapse ``S_u -> 0`` that homogeneous G1 conditions reach on
    data consistent only to interpolation error. ``svd``: :func:`row_svd` of this ``J``, where the
    caller solves with the same matrix again (the same solution, bit for bit)."""
    f = row_svd(J) if svd is None else svd
    s, sv, Vt = f.s, f.sv, f.Vt
    if sv.size == 0 or sv[0] == 0:
        return np.zeros((J.shape[1],) + rhs.shape[1:])
    c = f.project(rhs / (s if rhs.ndim == 1 else s[:, None]))
    exact = sv > 1e-12 * sv[0]
    robust = sv > tolerances.MATCH_RCOND * sv[0]
    inv = np.divide(1.0, sv, out=np.zeros_like(sv), where=sv > 0)  # zeros are cut off below anyway
    inv = inv if rhs.ndim == 1 else inv[:, None]
    xa = Vt[exact].T @ (c[exact] * inv[exact])
    xb = Vt[robust].T @ (c[robust] * inv[robust])
    return xa if np.linalg.norm(xa) <= 2.0 * np.linalg.norm(xb) + 1e-300 else xb
