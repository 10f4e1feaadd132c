"""Skeletons for animated hierarchical surfaces (course §5-42..5-45).

A :class:`Skeleton` is a tree of :class:`Joint` s. Each joint has a *rest* transform relative to its
parent's frame (the root's: relative to the world), a hinge ``axis`` in its own frame for posing by
an angle, and a bone ``length`` along its own x axis (the segment it carries, used by
:func:`~occsurf.algorithms.hierarchical.figures.bind_to_bones` and the pictures). The segment of a
joint is rigid; its frame is the joint's world frame.

:meth:`Skeleton.pose` turns joint angles or local transforms into a :class:`Pose`: the world frame
of every segment (``W_j = W_parent L_j P_j`` with the rest transform ``L_j`` and the pose's local
motion ``P_j``, the whole tree optionally placed by a rigid ``placement``), and the rigid motion
``M_j = W_j(pose) W_j(rest)^{-1}`` that carries a point bound to segment ``j`` from its rest place
(course §5-43: control nodes stored in their segment's frame follow it).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import _validate as V
from ..errors import InvalidGeometryError
from .skinning import check_rigid, invert_rigid, rotation_about, twist_angle

__all__ = ["Joint", "Skeleton", "Pose"]

Array = NDArray[np.float64]

#: Version of the ``to_dict`` format of skeletons.
SKELETON_FORMAT = 1


def _name(value: object, what: str) -> str:
    if not isinstance(value, str) or not value or value != value.strip():
        raise InvalidGeometryError(f"{what}: expected a non-empty name without surrounding blanks, got {value!r}")
    return value


@dataclass(frozen=True, eq=False)
class Joint:
    """One joint of a :class:`Skeleton` and the segment (bone) it carries.

    Parameters
    ----------
    name : str
        Unique within the skeleton.
    parent : str or None
        The parent joint's name; ``None`` for the root (exactly one).
    rest : array_like, shape (4, 4) or (3,), default identity
        The rest transform relative to the parent's frame (a translation if 3 numbers).
    axis : array_like, shape (3,), default (0, 0, 1)
        Hinge axis in the joint's frame for angle poses.
    length : float, default 0
        The bone's length along the joint's x axis.
    """

    name: str
    parent: str | None = None
    rest: Any = None
    axis: Any = (0.0, 0.0, 1.0)
    length: float = 0.0
    _rest: Array = field(init=False, repr=False)
    _axis: Array = field(init=False, repr=False)

    def __post_init__(self) -> None:
        _name(self.name, "joint name")
        if self.parent is not None:
            _name(self.parent, f"joint {self.name!r}: parent")
        if self.rest is None:
            rest = np.eye(4)
        else:
            r = V.as_finite_array(self.rest, f"joint {self.name!r}: rest")
            if r.shape == (3,):
                rest = np.eye(4)
                rest[:3, 3] = r
            else:
                rest = check_rigid(r, f"joint {self.name!r}: rest")
        ax = V.as_finite_array(self.axis, f"joint {self.name!r}: axis")
        if ax.shape != (3,) or not np.linalg.norm(ax) > 0:
            raise InvalidGeometryError(f"joint {self.name!r}: axis must be a non-zero 3-vector, got {self.axis!r}")
        try:
            length = float(self.length)
        except (TypeError, ValueError):
            raise InvalidGeometryError(f"joint {self.name!r}: length must be a number, got {self.length!r}") from None
        if isinstance(self.length, bool) or not (math.isfinite(length) and length >= 0):
            raise InvalidGeometryError(f"joint {self.name!r}: length must be finite and >= 0, got {self.length!r}")
        object.__setattr__(self, "_rest", V.readonly(rest))
        object.__setattr__(self, "_axis", V.readonly(ax / np.linalg.norm(ax)))
        object.__setattr__(self, "length", length)

    @property
    def rest_matrix(self) -> Array:
        """The rest transform (4, 4) relative to the parent (read-only)."""
        return self._rest

    @property
    def unit_axis(self) -> Array:
        """The hinge axis, unit length, in the joint's frame (read-only)."""
        return self._axis

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: name, parent, rest (4 x 4 rows), axis, length."""
        return {"name": self.name, "parent": self.parent, "rest": self._rest.tolist(),
                "axis": self._axis.tolist(), "length": self.length}


class Skeleton:
    """A tree of joints (course §5-42): rest frames, posing, rigid motions of the segments.

    Parameters
    ----------
    joints : sequence of Joint
        In any order; names unique, exactly one root, every parent known, no cycles.

    Raises
    ------
    InvalidGeometryError
        Naming the joint: duplicate names, an unknown parent, no root or several, a cycle.
    """

    def __init__(self, joints: Sequence[Joint]) -> None:
        joints = list(joints)
        if not joints or not all(isinstance(j, Joint) for j in joints):
            raise InvalidGeometryError("skeleton: expected a non-empty sequence of Joint")
        by_name: dict[str, Joint] = {}
        for j in joints:
            if j.name in by_name:
                raise InvalidGeometryError(f"skeleton: the joint name {j.name!r} is used twice")
            by_name[j.name] = j
        roots = [j.name for j in joints if j.parent is None]
        for j in joints:
            if j.parent is not None and j.parent not in by_name:
                raise InvalidGeometryError(f"skeleton: joint {j.name!r} has the unknown parent {j.parent!r}")
        # topological order from the roots; joints never reached lie on a cycle
        children: dict[str | None, list[str]] = {}
        for j in joints:
            children.setdefault(j.parent, []).append(j.name)
        order: list[str] = []
        stack = list(reversed(roots))
        while stack:
            n = stack.pop()
            order.append(n)
            stack.extend(reversed(children.get(n, [])))
        if len(order) < len(joints):
            cyc = sorted(set(by_name) - set(order))
            raise InvalidGeometryError(f"skeleton: the joints {', '.join(map(repr, cyc))} form a cycle (no path to a root)")
        if len(roots) != 1:
            raise InvalidGeometryError(f"skeleton: expected exactly one root joint (parent None), got {len(roots)}: {roots}")
        self._joints = by_name
        self._order = tuple(order)
        self._index = {n: i for i, n in enumerate(order)}
        self._rest_world = self._world({})[0]
        self._rest_inverse = np.stack([invert_rigid(R) for R in self._rest_world])

    # ------------------------------------------------------------------ structure
    @property
    def names(self) -> tuple[str, ...]:
        """Joint names, parents before children (the order of :attr:`Pose.motions`)."""
        return self._order

    @property
    def root(self) -> str:
        """The root joint's name."""
        return self._order[0]

    def joint(self, name: str) -> Joint:
        """The joint called ``name`` (:class:`InvalidGeometryError` naming the known ones if none)."""
        try:
            return self._joints[name]
        except (KeyError, TypeError):
            raise InvalidGeometryError(f"joint: unknown joint {name!r}; the skeleton has {', '.join(self._order)}") from None

    def index(self, name: str) -> int:
        """Position of ``name`` in :attr:`names`."""
        self.joint(name)
        return self._index[name]

    def children(self, name: str) -> list[str]:
        """Names of the joints whose parent is ``name``."""
        self.joint(name)
        return [n for n in self._order if self._joints[n].parent == name]

    def rest_frame(self, name: str) -> Array:
        """World frame (4, 4) of ``name``'s segment at rest."""
        return self._rest_world[self.index(name)].copy()

    # ------------------------------------------------------------------ posing
    def _local_motion(self, name: str, value: Any) -> tuple[Array, float]:
        j = self._joints[name]
        if isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool):
            a = float(value)
            if not math.isfinite(a):
                raise InvalidGeometryError(f"pose: the angle of joint {name!r} is not finite ({value!r})")
            M = np.eye(4)
            M[:3, :3] = rotation_about(j.unit_axis, a)
            return M, a
        if value is None or isinstance(value, (str, bool)):
            raise InvalidGeometryError(f"pose: joint {name!r}: expected an angle or a rigid transform, got {value!r}")
        M = check_rigid(value, f"pose: joint {name!r}")
        return M, twist_angle(M[:3, :3], j.unit_axis)

    def _world(self, local: Mapping[str, Array], placement: Array | None = None) -> tuple[Array, NDArray[np.bool_]]:
        """World frames, and which joints moved from rest (own motion, an ancestor's, or a placement)."""
        W = np.empty((len(self._order), 4, 4))
        moved = np.zeros(len(self._order), bool)
        for i, n in enumerate(self._order):
            j = self._joints[n]
            M = j.rest_matrix if n not in local else j.rest_matrix @ local[n]
            if j.parent is None:
                W[i] = placement @ M if placement is not None else M
                moved[i] = placement is not None or n in local
            else:
                k = self._index[j.parent]
                W[i] = W[k] @ M
                moved[i] = moved[k] or n in local
        return W, moved

    def pose(self, values: Mapping[str, Any] | None = None, *, placement: ArrayLike | None = None) -> Pose:
        """The skeleton posed by joint angles or local transforms.

        Parameters
        ----------
        values : mapping of joint name -> float or (4, 4) / (3, 3) array, optional
            An angle (radians) turns the joint about its ``axis``; a matrix is the joint's local
            rigid motion in its own frame (after its rest transform). Joints not named stay at rest
            and move by exactly the identity (with their ancestors). :attr:`Pose.angles` keeps a
            given angle as given; for a matrix it is the twist about the axis, in (-pi, pi].
        placement : array_like, shape (4, 4), optional
            A rigid motion of the whole skeleton in world coordinates.

        Raises
        ------
        InvalidGeometryError
            An unknown joint, a NaN or infinite angle, a matrix that is not a rigid motion; nothing
            is posed.
        """
        values = {} if values is None else values
        if not isinstance(values, Mapping):
            raise InvalidGeometryError(f"pose: expected a mapping of joint name to angle or transform, got "
                                       f"{type(values).__name__}")
        local: dict[str, Array] = {}
        angles: dict[str, float] = {}
        for name, value in values.items():
            self.joint(name)
            local[name], angles[name] = self._local_motion(name, value)
        G = None if placement is None else check_rigid(placement, "pose: placement")
        W, moved = self._world(local, G)
        motions = np.broadcast_to(np.eye(4), W.shape).copy()  # joints at rest move by exactly I
        motions[moved] = W[moved] @ self._rest_inverse[moved]
        return Pose(self, V.readonly(W), V.readonly(motions),
                    MappingProxyType({n: angles.get(n, 0.0) for n in self._order}))

    # ------------------------------------------------------------------ storage
    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: the joints, parents first (:meth:`from_dict` reads it back)."""
        return {"type": "Skeleton", "version": SKELETON_FORMAT, "joints": [self._joints[n].to_dict() for n in self._order]}

    @classmethod
    def from_dict(cls, data: Any) -> Skeleton:
        """The skeleton of :meth:`to_dict`; bad data is one :class:`InvalidGeometryError`."""
        if not isinstance(data, dict) or data.get("type") != "Skeleton":
            raise InvalidGeometryError("skeleton.from_dict: expected a dict with type 'Skeleton'")
        if data.get("version") != SKELETON_FORMAT:
            raise InvalidGeometryError(f"skeleton.from_dict: format version {data.get('version')!r} is not supported")
        items = data.get("joints")
        if not isinstance(items, list):
            raise InvalidGeometryError("skeleton.from_dict: 'joints' must be a list")
        joints = []
        for k, item in enumerate(items):
            try:
                joints.append(Joint(item["name"], item["parent"], item["rest"], item["axis"], item["length"]))
            except (KeyError, TypeError, ValueError) as err:
                raise InvalidGeometryError(f"skeleton.from_dict: joint {k}: missing or bad entry ({err})") from err
            except InvalidGeometryError as err:
                raise InvalidGeometryError(f"skeleton.from_dict: joint {k}: {err}") from err
        return cls(joints)

    def __repr__(self) -> str:
        return f"Skeleton({', '.join(f'{n}<-{self._joints[n].parent}' for n in self._order)})"


@dataclass(frozen=True, eq=False)
class Pose:
    """A posed :class:`Skeleton` (from :meth:`Skeleton.pose`).

    Attributes
    ----------
    skeleton : Skeleton
    frames : ndarray, shape (k, 4, 4)
        World frame of every segment, in :attr:`Skeleton.names` order (read-only).
    motions : ndarray, shape (k, 4, 4)
        ``frames[j] @ rest_frames[j]^{-1}``: the rigid motion of segment ``j`` from rest; exactly
        the identity for segments that did not move (read-only).
    angles : mapping of str -> float (read-only)
        Per joint, the signed rotation angle about its hinge axis (0 at rest; for a joint posed
        by a matrix, the angle of its rotation measured about the axis).
    """

    skeleton: Skeleton
    frames: Array
    motions: Array
    angles: Mapping[str, float]

    def angle(self, name: str) -> float:
        """The signed angle (radians) of joint ``name`` about its hinge axis."""
        self.skeleton.joint(name)
        return self.angles[name]

    def frame(self, name: str) -> Array:
        """World frame (4, 4) of ``name``'s segment in this pose."""
        return self.frames[self.skeleton.index(name)].copy()

    def bones(self) -> Array:
        """Segments as world points: (k, 2, 3) start (the joint) and end (``length`` along x)."""
        lengths = np.array([self.skeleton.joint(n).length for n in self.skeleton.names])
        start = self.frames[:, :3, 3]
        return np.stack([start, start + self.frames[:, :3, 0] * lengths[:, None]], 1)
