"""Rigid motions and their blending for control points bound to a skeleton (course §5-43, §5-45).

A control vertex attached to one segment moves rigidly with it; a vertex of a *multi-segment
joint* (§5-45) is bound to several segments with weights ``w_j`` (non-negative, summing to 1), and
its motion blends the segments' rigid motions ``M_j = W_j(pose) W_j(rest)^{-1}``. Two blends are
provided:

``"dual_quaternion"`` (the default; Kavan, Collins, Žára, O'Sullivan 2008)
    The unit dual quaternions ``q_j`` of the motions are averaged with the weights (each taken on
    the same hemisphere as the most heavily weighted one) and normalised. The result is again a
    rigid motion for every vertex: a vertex between two segments that turn about a common hinge
    moves on a circle about the hinge by the weighted angle, so the joint keeps its cross-section.
    It is equivariant: composing every motion with a rigid ``G`` composes the blend with ``G``
    exactly, so a rigid motion of the whole skeleton moves the surface rigidly.
``"linear"``
    ``sum_j w_j M_j p`` (linear blend skinning). A blend of rotations is not a rotation: at a joint
    bent by ``theta`` the vertices halfway between the segments are pulled towards the hinge by the
    factor ``cos(theta / 2)`` — the "collapsing elbow" (and, for twists, the "candy wrapper").
    Kept as the baseline that the tests and the demo measure against.

Why dual quaternions rather than the course's own joint scheme: Forsey's multi-segment joints
(course §5-45) place the vertices around a joint by interpolating between the segments' frames,
which is what a weighted dual-quaternion average does with a closed form, for any number of
segments per vertex and without a special case per joint type; linear blending is what the
course warns against (the collapse at a bent joint).

References
----------
L. Kavan, S. Collins, J. Žára, C. O'Sullivan, "Geometric skinning with approximate dual quaternion
blending", ACM TOG 27(4), 2008; D. R. Forsey, "A surface model for skeleton-based character
animation", Second Eurographics Workshop on Animation and Simulation, 1991; course notes C25,
SIGGRAPH 1991, §5-42..5-45.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import _validate as V
from ..errors import InvalidGeometryError

__all__ = [
    "BLENDS",
    "twist_angle",
    "rigid_transform",
    "check_rigid",
    "invert_rigid",
    "rotation_about",
    "quaternions_from_matrices",
    "matrices_from_quaternions",
    "dual_quaternions",
    "blend_motions",
]

Array = NDArray[np.float64]

#: The blends :func:`blend_motions` knows (see the module notes).
BLENDS: tuple[str, ...] = ("dual_quaternion", "linear")

#: A 4 x 4 matrix is accepted as rigid when its rotation block is orthonormal with determinant +1 to
#: this absolute tolerance (round-off of composed rotations stays far below it).
RIGID_TOL = 1e-9


def rigid_transform(rotation: ArrayLike | None = None, translation: ArrayLike | None = None) -> Array:
    """The 4 x 4 homogeneous matrix of ``x -> R x + t`` (identity parts where omitted)."""
    M = np.eye(4)
    if rotation is not None:
        M[:3, :3] = V.as_finite_array(rotation, "rotation")
    if translation is not None:
        t = V.as_finite_array(translation, "translation")
        if t.shape != (3,):
            raise InvalidGeometryError(f"translation: expected 3 numbers, got shape {t.shape}")
        M[:3, 3] = t
    return check_rigid(M, "transform")


def check_rigid(matrix: ArrayLike, name: str) -> Array:
    """``matrix`` as a float (4, 4) rigid motion (a proper rotation and a translation), or an
    :class:`InvalidGeometryError` naming ``name`` and what is wrong.

    A rotation block within :data:`RIGID_TOL` of orthonormal (e.g. printed with few digits) is
    replaced by the nearest rotation (polar decomposition, ``U V^T`` of its SVD), so that the
    motions built from it are rigid to round-off, not to the input's precision."""
    M = V.as_finite_array(matrix, name)
    if M.shape == (3, 3):
        M = np.block([[M, np.zeros((3, 1))], [np.zeros((1, 3)), np.ones((1, 1))]])
    if M.shape != (4, 4):
        raise InvalidGeometryError(f"{name}: expected a 4 x 4 rigid transform (or a 3 x 3 rotation), got shape {M.shape}")
    if not np.array_equal(M[3], [0.0, 0.0, 0.0, 1.0]):
        raise InvalidGeometryError(f"{name}: the last row of a rigid transform must be (0, 0, 0, 1), got {M[3].tolist()}")
    R = M[:3, :3]
    err = float(np.abs(R.T @ R - np.eye(3)).max())
    if err > RIGID_TOL or np.linalg.det(R) < 0:
        raise InvalidGeometryError(f"{name}: the rotation block is not a proper rotation (|R^T R - I| = {err:.3g}, "
                                   f"det = {np.linalg.det(R):.6g}); scaling, shear and mirroring are not rigid")
    if err > 1e-13:  # beyond round-off (which is kept bit for bit, so that stored frames read back equal)
        U, _, Vt = np.linalg.svd(R)
        M = M.copy()
        M[:3, :3] = U @ Vt
    return M


def invert_rigid(M: Array) -> Array:
    """The inverse of a rigid 4 x 4 motion (``R^T``, ``-R^T t``), exact up to round-off."""
    out = np.eye(4)
    out[:3, :3] = M[:3, :3].T
    out[:3, 3] = -M[:3, :3].T @ M[:3, 3]
    return out


def rotation_about(axis: ArrayLike, angle: float) -> Array:
    """The 3 x 3 rotation by ``angle`` (radians, right-handed) about the unit ``axis`` (Rodrigues)."""
    a = np.asarray(axis, float)
    a = a / np.linalg.norm(a)
    K = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
    return np.eye(3) + np.sin(angle) * K + (1.0 - np.cos(angle)) * (K @ K)


def twist_angle(R: ArrayLike, axis: ArrayLike) -> float:
    """The signed angle of the *twist* of rotation ``R`` about the unit ``axis``, in (-pi, pi].

    Swing-twist decomposition ``R = swing * twist`` with ``twist`` a rotation about ``axis``: for
    the unit quaternion ``(w, v)`` of ``R`` the twist angle is ``2 atan2(v . axis, w)``. A rotation
    about ``axis`` gives its own angle; one about a perpendicular axis gives 0.
    """
    q = quaternions_from_matrices(np.asarray(R, float)[None])[0]
    a = 2.0 * np.arctan2(float(q[1:] @ np.asarray(axis, float)), float(q[0]))
    return float(a - 2.0 * np.pi if a > np.pi else a)


def quaternions_from_matrices(R: Array) -> Array:
    """Unit quaternions ``(w, x, y, z)`` of rotations ``R`` of shape (..., 3, 3), ``w >= 0``.

    Shepperd's method: the largest of the four squared components is taken from the diagonal, the
    others from the off-diagonal sums, so no division by a small number occurs.
    """
    R = np.asarray(R, float)
    m00, m11, m22 = R[..., 0, 0], R[..., 1, 1], R[..., 2, 2]
    tr = m00 + m11 + m22
    cand = np.stack([1.0 + tr, 1.0 + m00 - m11 - m22, 1.0 - m00 + m11 - m22, 1.0 - m00 - m11 + m22], -1)
    k = np.argmax(cand, axis=-1)
    s = np.sqrt(np.maximum(np.take_along_axis(cand, k[..., None], -1)[..., 0], 0.0)) * 2.0  # 4 |q_k|
    d21, d02, d10 = R[..., 2, 1] - R[..., 1, 2], R[..., 0, 2] - R[..., 2, 0], R[..., 1, 0] - R[..., 0, 1]
    s01, s02, s12 = R[..., 0, 1] + R[..., 1, 0], R[..., 0, 2] + R[..., 2, 0], R[..., 1, 2] + R[..., 2, 1]
    q = np.stack([
        np.select([k == 0, k == 1, k == 2, k == 3], [0.25 * s, d21 / s, d02 / s, d10 / s]),
        np.select([k == 0, k == 1, k == 2, k == 3], [d21 / s, 0.25 * s, s01 / s, s02 / s]),
        np.select([k == 0, k == 1, k == 2, k == 3], [d02 / s, s01 / s, 0.25 * s, s12 / s]),
        np.select([k == 0, k == 1, k == 2, k == 3], [d10 / s, s02 / s, s12 / s, 0.25 * s]),
    ], -1)
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    return np.where(q[..., :1] < 0, -q, q)


def _qmul(a: Array, b: Array) -> Array:
    """Hamilton products of quaternions ``(w, x, y, z)``, broadcast over leading axes."""
    aw, av = a[..., :1], a[..., 1:]
    bw, bv = b[..., :1], b[..., 1:]
    w = aw * bw - np.sum(av * bv, -1, keepdims=True)
    v = aw * bv + bw * av + np.cross(av, bv)
    return np.concatenate([w, v], -1)


def matrices_from_quaternions(q: Array) -> Array:
    """Rotation matrices (..., 3, 3) of unit quaternions (..., 4)."""
    w, x, y, z = (q[..., i] for i in range(4))
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
        np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
        np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
    ], -2)


def dual_quaternions(motions: Array) -> tuple[Array, Array]:
    """Unit dual quaternions ``(q_r, q_d)`` of rigid motions (k, 4, 4): ``q_d = 1/2 (0, t) q_r``."""
    qr = quaternions_from_matrices(motions[:, :3, :3])
    t = np.concatenate([np.zeros((motions.shape[0], 1)), motions[:, :3, 3]], -1)
    return qr, 0.5 * _qmul(t, qr)


def blend_motions(points: ArrayLike, motions: ArrayLike, weights: ArrayLike, blend: str = "dual_quaternion") -> Array:
    """Move ``points`` by the weighted blend of rigid ``motions`` (course §5-45, see the module notes).

    Parameters
    ----------
    points : array_like, shape (m, 3)
        Rest positions.
    motions : array_like, shape (k, 4, 4)
        Rigid motions of the ``k`` segments (posed world frame times inverse rest world frame).
    weights : array_like, shape (m, k)
        Per point, non-negative weights that sum to 1 (not checked here: :class:`Binding` checks).
    blend : {"dual_quaternion", "linear"}

    Returns
    -------
    ndarray, shape (m, 3)
        The moved points. A point with a single weight 1 moves exactly by that motion (to round-off)
        under either blend.
    """
    P = np.asarray(points, float)
    Ms = np.asarray(motions, float)
    W = np.asarray(weights, float)
    if blend == "linear":
        moved = np.einsum("kij,mj->mki", Ms[:, :3, :3], P) + Ms[None, :, :3, 3]  # (m, k, 3)
        return np.einsum("mk,mki->mi", W, moved)
    if blend != "dual_quaternion":
        raise InvalidGeometryError(f"blend: expected one of {', '.join(BLENDS)}, got {blend!r}")
    qr, qd = dual_quaternions(Ms)
    pivot = np.argmax(W, axis=1)  # the heaviest segment sets the hemisphere (shortest arcs)
    sign = np.sign(qr @ qr.T)[pivot]  # (m, k)
    sign[sign == 0] = 1.0
    Ws = W * sign
    br, bd = Ws @ qr, Ws @ qd
    norm = np.linalg.norm(br, axis=1, keepdims=True)
    cr, cd = br / norm, bd / norm
    # translation 2 (c_r.w c_d.v - c_d.w c_r.v + c_r.v x c_d.v), valid for the unnormalised dual part
    t = 2.0 * (cr[:, :1] * cd[:, 1:] - cd[:, :1] * cr[:, 1:] + np.cross(cr[:, 1:], cd[:, 1:]))
    R = matrices_from_quaternions(cr)
    return np.einsum("mij,mj->mi", R, P) + t
