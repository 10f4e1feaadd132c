"""Hierarchical surfaces for animated figures (course §5-42..5-46, Forsey 1991).

The course's hierarchical chapter ends with its motivating use: a figure's skin as one
hierarchical B-spline surface whose coarse level follows a skeleton while the details ride along.

* **Extending offset referencing** (§5-42): the skeleton's segment frames become the top of the
  frame hierarchy. The control vertices of a *bound* level are stored relative to the segments
  they are attached to; every finer level keeps its offsets in its parent's local frames
  (:mod:`.offsets`), so details follow the posed surface and their stored offsets never change.
* **Attaching control nodes** (§5-43): a :class:`Binding` gives each vertex of a level one
  segment (rigid) or several with weights (**multi-segment joints**, §5-45), blended as unit dual
  quaternions (:mod:`.skinning`, which also says why). :func:`bind_to_bones` makes the weights
  from the rest geometry.
* **Procedural methods** (§5-46): a :class:`PoseProcedure` adds offsets that are functions of the
  pose to one overlay, through offset referencing; :class:`JointBulge` is a muscle bulge that
  grows with a joint's angle. Others can be registered (:func:`register_procedure`) so that
  :meth:`AttachedSurface.to_dict` stores them.

:meth:`AttachedSurface.at` returns the posed :class:`HierarchicalSurface` (its
:meth:`~HierarchicalSurface.flatten` is the exact NURBS of that pose). The dynamic level (§5-47)
is in :mod:`.dynamics`.

References
----------
D. R. Forsey, "A surface model for skeleton-based character animation", Second Eurographics
Workshop on Animation and Simulation, 1991; D. R. Forsey, R. H. Bartels, "Hierarchical B-spline
refinement", SIGGRAPH '88; course notes C25, SIGGRAPH 1991, §5-42..5-49.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import _validate as V
from ..errors import InvalidGeometryError
from ..kernel.surface import BSplineSurface
from .overlays import Overlay
from .skeleton import Pose, Skeleton
from .skinning import BLENDS, blend_motions
from .surface import HierarchicalSurface

__all__ = [
    "Binding",
    "bind_to_bones",
    "PoseProcedure",
    "JointBulge",
    "register_procedure",
    "attach",
    "AttachedSurface",
    "section_area",
    "set_world_points",
    "set_base_points",
]

Array = NDArray[np.float64]

#: Version of :meth:`AttachedSurface.to_dict`'s format.
ATTACHED_FORMAT = 1
#: Per vertex, the weights of a binding must sum to 1 within this (absolute).
WEIGHT_SUM_TOL = 1e-9


# ------------------------------------------------------------------------------------ bindings
@dataclass(frozen=True, eq=False)
class Binding:
    """The attachment of one level's control vertices to skeleton segments (course §5-43, §5-45).

    Parameters
    ----------
    joints : sequence of str
        The segments (joint names) the weights refer to, one per last-axis entry of ``weights``.
    weights : array_like, shape (n_u, n_v, k)
        Per vertex of the level's net, non-negative weights summing to 1: one weight 1 binds the
        vertex rigidly to that segment, several make a multi-segment joint.
    """

    joints: tuple[str, ...]
    weights: Array

    def __post_init__(self) -> None:
        if isinstance(self.joints, str):
            raise InvalidGeometryError(f"binding: joints must be a sequence of names, got the string {self.joints!r} "
                                       f"(write ({self.joints!r},) for one joint)")
        joints = tuple(self.joints)
        if not joints or not all(isinstance(j, str) for j in joints) or len(set(joints)) != len(joints):
            raise InvalidGeometryError(f"binding: expected distinct joint names, got {self.joints!r}")
        W = V.as_finite_array(self.weights, "binding weights")
        if W.ndim != 3 or W.shape[-1] != len(joints):
            raise InvalidGeometryError(f"binding weights: expected shape (n_u, n_v, {len(joints)}) (one weight per "
                                       f"vertex and joint), got {W.shape}")
        if np.any(W < 0):
            i = np.unravel_index(int(np.argmin(W)), W.shape)
            raise InvalidGeometryError(f"binding weights: vertex {i[:2]} has the negative weight {W[i]:.6g} for joint "
                                       f"{joints[i[2]]!r}")
        s = W.sum(-1)
        bad = np.abs(s - 1.0) > WEIGHT_SUM_TOL
        if np.any(bad):
            iu, iv = (int(x) for x in np.argwhere(bad)[0])
            raise InvalidGeometryError(f"binding weights: the weights of vertex {(iu, iv)} sum to {s[iu, iv]:.12g}, not 1 "
                                       f"({int(bad.sum())} vertices)")
        object.__setattr__(self, "joints", joints)
        object.__setattr__(self, "weights", V.readonly(W))

    @classmethod
    def rigid(cls, joint: str, shape: tuple[int, int]) -> Binding:
        """Every vertex of a net of ``shape`` rigidly to ``joint``."""
        try:
            nu, nv = (int(k) for k in shape)
            ok = (nu, nv) == tuple(shape) and nu > 0 and nv > 0
        except (TypeError, ValueError, OverflowError):
            ok = False
        if not ok:
            raise InvalidGeometryError(f"binding: shape must be two positive integers, got {shape!r}")
        return cls((joint,), np.ones((nu, nv, 1)))

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: the joint names and the weights (nested lists)."""
        return {"joints": list(self.joints), "weights": self.weights.tolist()}


def _smoothstep(x: Array) -> Array:
    x = np.clip(x, 0.0, 1.0)
    return x * x * (3.0 - 2.0 * x)


def bind_to_bones(points: ArrayLike, skeleton: Skeleton, blend_width: float) -> Binding:
    """Weights for points (a level's control net) from the skeleton's rest bones.

    Each point goes to its nearest bone (a joint's segment: ``length`` along its x axis). Within
    ``blend_width`` of the bone's start (its joint with the parent bone) the weight passes from the
    parent to the bone by a smoothstep ``t_p`` of the coordinate along the bone, over
    ``[-blend_width, blend_width]``; likewise near its end towards the nearest child bone (``t_c``
    of the coordinate along the child). A point is thus bound rigidly away from joints and to two
    segments across a joint (§5-45); on a bone shorter than ``2 blend_width`` both zones overlap
    and the point takes ``1 - t_p`` of the parent, ``t_p (1 - t_c)`` of its bone and ``t_p t_c``
    of the child. The children of a bone of length 0 (a pelvis-like root) are not blended with
    each other: each is bound to its own bone.

    Parameters
    ----------
    points : array_like, shape (n_u, n_v, 3)
        Rest positions (e.g. ``surface.base.control_points``).
    skeleton : Skeleton
    blend_width : float
        Half-width of the blend zone across a joint; wide enough that the bend does not fold the
        inner side. Two rigid tubes of radius ``r`` bent by ``theta`` meet ``r tan(theta / 2)``
        from the joint, so the zone must reach past that: on the demo arm 2.4 times the elbow's
        radius keeps a 120 degree bend free of self-intersection, 1.6 times does not (see the
        tests).

    Returns
    -------
    Binding
        Over every joint of the skeleton (columns in :attr:`Skeleton.names` order).
    """
    P = V.as_finite_array(points, "points")
    if P.ndim != 3 or P.shape[-1] != 3:
        raise InvalidGeometryError(f"points: expected a net of shape (n_u, n_v, 3), got {P.shape}")
    h = float(blend_width)
    if not (np.isfinite(h) and h > 0):
        raise InvalidGeometryError(f"blend_width: expected a positive number, got {blend_width!r}")
    names = skeleton.names
    F = np.stack([skeleton.rest_frame(n) for n in names])
    start, axis = F[:, :3, 3], F[:, :3, 0]
    length = np.array([skeleton.joint(n).length for n in names])
    X = P.reshape(-1, 3)
    s = np.einsum("mki,ki->mk", X[:, None, :] - start[None], axis)  # coordinate along each bone
    foot = start[None] + np.clip(s, 0.0, length)[..., None] * axis[None]
    dist = np.linalg.norm(X[:, None, :] - foot, axis=-1)
    near = np.argmin(dist, axis=1)
    W = np.zeros((X.shape[0], len(names)))
    rows = np.arange(X.shape[0])
    W[rows, near] = 1.0
    parent = np.array([names.index(p) if (p := skeleton.joint(n).parent) is not None else -1 for n in names])
    for b in range(len(names)):  # per bone (a handful), vectorised over the points
        idx = np.flatnonzero(near == b)
        if idx.size == 0:
            continue
        t_p = np.ones(idx.size)  # the share kept from the parent side
        t_c = np.zeros(idx.size)  # the share passed to the child
        p = parent[b]
        if p >= 0 and length[p] > 0:
            t_p = _smoothstep((s[idx, b] + h) / (2 * h))
        kids = np.flatnonzero(parent == b)
        c = np.full(idx.size, -1)
        if kids.size and length[b] > 0:
            c = kids[np.argmin(dist[np.ix_(idx, kids)], axis=1)]
            t_c = np.where(s[idx, b] > length[b] - h, _smoothstep((s[idx, c] + h) / (2 * h)), 0.0)
        W[idx, b] = t_p * (1.0 - t_c)
        if p >= 0:
            W[idx, p] += 1.0 - t_p
        has = c >= 0
        W[idx[has], c[has]] += (t_p * t_c)[has]
    return Binding(names, W.reshape(P.shape[:2] + (len(names),)))


# ------------------------------------------------------------------------------------ procedures
_PROCEDURES: dict[str, type[PoseProcedure]] = {}


def register_procedure(cls: type[PoseProcedure]) -> type[PoseProcedure]:
    """Make a :class:`PoseProcedure` subclass known by its ``kind`` (so ``from_dict`` loads it);
    usable as a class decorator."""
    if not (isinstance(cls, type) and issubclass(cls, PoseProcedure)) or not getattr(cls, "kind", ""):
        raise InvalidGeometryError(f"procedure: expected a PoseProcedure subclass with a kind, got {cls!r}")
    _PROCEDURES[cls.kind] = cls
    return cls


class PoseProcedure:
    """Offsets of one overlay that are a function of the pose (course §5-46).

    Subclasses set ``kind``, ``overlay`` (the overlay id) and implement :meth:`offsets`,
    :meth:`to_dict` and :meth:`from_dict`. The offsets are added to the overlay's stored offsets
    (in its offset mapping's coordinates: the parent's frame ``(t, b, n)`` for frame offsets), so
    the procedure acts through offset referencing and its finer levels follow.
    """

    kind: ClassVar[str] = ""
    overlay: int

    def offsets(self, pose: Pose, shape: tuple[int, int]) -> Array:
        """Offsets to add, shape ``shape + (3,)``."""
        raise NotImplementedError

    def check(self, surface: HierarchicalSurface, skeleton: Skeleton) -> None:
        """Refuse a procedure that does not fit the surface or skeleton (one line)."""

    def to_dict(self) -> dict[str, Any]:
        raise NotImplementedError

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> PoseProcedure:
        raise NotImplementedError


@register_procedure
@dataclass(frozen=True, eq=False)
class JointBulge(PoseProcedure):
    """A bulge on one overlay that grows with a joint's angle (a muscle flexing, course §5-46).

    ``offsets = profile * direction * gain * (clip(angle, start, stop) - start)``: zero below
    ``start`` (at rest for the default ``start = 0``), growing linearly to its full size at ``stop``.

    Parameters
    ----------
    overlay : int
        Id of the overlay it acts on.
    joint : str
        The joint whose angle drives it.
    profile : array_like, shape overlay.shape
        Per vertex, the bulge's relative size (e.g. 1 in the middle, 0 at the overlay's border).
    gain : float
        Offset per radian beyond ``start``.
    direction : array_like, shape (3,), default (0, 0, 1)
        In the offset mapping's coordinates: along the parent's normal for frame offsets.
    start, stop : float, default 0 and pi
        The angle range over which it grows.
    """

    kind: ClassVar[str] = "joint_bulge"
    overlay: int
    joint: str
    profile: Any
    gain: float
    direction: Any = (0.0, 0.0, 1.0)
    start: float = 0.0
    stop: float = float(np.pi)
    _profile: Array = field(init=False, repr=False)
    _direction: Array = field(init=False, repr=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "_profile", V.readonly(V.as_finite_array(self.profile, "bulge profile")))
        d = V.as_finite_array(self.direction, "bulge direction")
        if d.shape != (3,):
            raise InvalidGeometryError(f"bulge direction: expected 3 numbers, got shape {d.shape}")
        object.__setattr__(self, "_direction", V.readonly(d))
        for name in ("gain", "start", "stop"):
            x = getattr(self, name)
            if not (isinstance(x, (int, float, np.integer, np.floating)) and not isinstance(x, bool) and np.isfinite(x)):
                raise InvalidGeometryError(f"bulge {name}: expected a finite number, got {x!r}")
        if not self.start < self.stop:
            raise InvalidGeometryError(f"bulge: expected start < stop, got {self.start!r} and {self.stop!r}")

    def check(self, surface: HierarchicalSurface, skeleton: Skeleton) -> None:
        """Refuse an unknown joint or overlay, or a profile not of the overlay's shape."""
        skeleton.joint(self.joint)
        o = next((h for h in surface.overlays if h.id == self.overlay), None)
        if o is None:
            raise InvalidGeometryError(f"bulge: the surface has no overlay {self.overlay!r}")
        if self._profile.shape != o.shape:
            raise InvalidGeometryError(f"bulge profile: expected the overlay's shape {o.shape}, got {self._profile.shape}")

    def offsets(self, pose: Pose, shape: tuple[int, int]) -> Array:
        """``profile * direction * gain * (clip(angle, start, stop) - start)``, shape ``shape + (3,)``."""
        if self._profile.shape != tuple(shape):
            raise InvalidGeometryError(f"bulge profile: expected shape {tuple(shape)}, got {self._profile.shape}")
        amount = self.gain * (min(max(pose.angle(self.joint), self.start), self.stop) - self.start)
        return self._profile[..., None] * (amount * self._direction)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready, with ``kind`` for :func:`register_procedure`'s registry."""
        return {"kind": self.kind, "overlay": self.overlay, "joint": self.joint, "profile": self._profile.tolist(),
                "gain": float(self.gain), "direction": self._direction.tolist(), "start": float(self.start),
                "stop": float(self.stop)}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> JointBulge:
        """The bulge of :meth:`to_dict`."""
        return cls(data["overlay"], data["joint"], data["profile"], data["gain"], data["direction"], data["start"],
                   data["stop"])


# ------------------------------------------------------------------------------------ attaching
def _node_key(key: Any, surface: HierarchicalSurface) -> int:
    if key is None:
        return 0
    if isinstance(key, Overlay):
        key = key.id
    ids = {o.id for o in surface.overlays}
    if isinstance(key, (int, np.integer)) and not isinstance(key, bool) and (key == 0 or int(key) in ids):
        return int(key)
    raise InvalidGeometryError(f"bindings: {key!r} is neither the base (None or 0) nor an overlay of the surface")


def attach(surface: HierarchicalSurface | BSplineSurface, skeleton: Skeleton,
           bindings: Binding | Mapping[Any, Binding], *, blend: str = "dual_quaternion",
           procedures: Sequence[PoseProcedure] = ()) -> AttachedSurface:
    """Attach a surface's control nodes to a skeleton (course §5-42..5-46).

    Parameters
    ----------
    surface : HierarchicalSurface or BSplineSurface
        At rest, in the skeleton's rest frame (copied; a BSplineSurface becomes a hierarchy with
        frame offsets and no overlays).
    skeleton : Skeleton
    bindings : Binding or mapping of level -> Binding
        A single Binding binds the base's vertices. A mapping binds several levels: keys ``None``
        (or 0) for the base and overlays (handles or ids); the bound set must contain the base and,
        with every overlay, its parent. Unbound overlays keep their offsets (offset referencing).
    blend : {"dual_quaternion", "linear"}
        How a multi-segment vertex blends its segments' motions (:mod:`.skinning`).
    procedures : sequence of PoseProcedure

    Raises
    ------
    InvalidGeometryError
        A binding to an unknown joint, weights of the wrong shape or not summing to 1, an unbound
        parent of a bound overlay, an unknown overlay; nothing is attached.
    """
    if isinstance(surface, BSplineSurface):
        surface = HierarchicalSurface(surface)
    if not isinstance(surface, HierarchicalSurface):
        raise InvalidGeometryError(f"surface: expected a HierarchicalSurface or BSplineSurface, got {type(surface).__name__}")
    if not isinstance(skeleton, Skeleton):
        raise InvalidGeometryError(f"skeleton: expected a Skeleton, got {type(skeleton).__name__}")
    if blend not in BLENDS:
        raise InvalidGeometryError(f"blend: expected one of {', '.join(BLENDS)}, got {blend!r}")
    items = {None: bindings} if isinstance(bindings, Binding) else bindings
    if not isinstance(items, Mapping) or not items:
        raise InvalidGeometryError("bindings: expected a Binding or a non-empty mapping of level to Binding")
    bound: dict[int, Binding] = {}
    by_id = {o.id: o for o in surface.overlays}
    for key, b in items.items():
        k = _node_key(key, surface)
        if k in bound:
            raise InvalidGeometryError(f"bindings: level {k} is bound twice ({'None and 0 both name the base' if k == 0 else 'by handle and id'})")
        if not isinstance(b, Binding):
            raise InvalidGeometryError(f"bindings[{key!r}]: expected a Binding, got {type(b).__name__}")
        for j in b.joints:
            if j not in skeleton.names:
                raise InvalidGeometryError(f"bindings[{key!r}]: binds to the unknown joint {j!r}; the skeleton has "
                                           f"{', '.join(skeleton.names)}")
        shape = surface.base.n_poles if k == 0 else by_id[k].shape
        if b.weights.shape[:2] != tuple(shape):
            raise InvalidGeometryError(f"bindings[{key!r}]: weights for a net of {b.weights.shape[:2]}, the level has "
                                       f"{tuple(shape)} vertices")
        bound[k] = b
    if 0 not in bound:
        raise InvalidGeometryError("bindings: the base must be bound (the coarsest level follows the skeleton)")
    for k in bound:
        if k and by_id[k].parent not in bound:
            raise InvalidGeometryError(f"bindings: overlay {k} is bound but its parent {by_id[k].parent} is not")
    try:
        procs = tuple(procedures)
    except TypeError:
        raise InvalidGeometryError(f"procedures: expected a sequence of PoseProcedure, got {type(procedures).__name__}") from None
    for p in procs:
        if not isinstance(p, PoseProcedure):
            raise InvalidGeometryError(f"procedures: expected PoseProcedure objects, got {type(p).__name__}")
        p.check(surface, skeleton)
    return AttachedSurface(surface.copy(), skeleton, dict(sorted(bound.items())), blend, procs)


def _handle(hs: HierarchicalSurface, overlay: int) -> Overlay:
    """The handle of overlay ``overlay`` (an id) of ``hs``."""
    h = next((o for o in hs.overlays if o.id == overlay), None)
    if h is None:
        raise InvalidGeometryError(f"overlay: the surface has no overlay {overlay!r}")
    return h


def set_base_points(hs: HierarchicalSurface, points: Array) -> None:
    """Replace the base's control points of ``hs`` (same knots and weights), in place."""
    b = hs.base
    hs.set_base(BSplineSurface(b.degree, b.knots, points, b.weights))


class AttachedSurface:
    """A hierarchical surface attached to a skeleton (from :func:`attach`); immutable.

    :meth:`at` poses it. The rest surface, skeleton, bindings and procedures are kept as given.
    """

    def __init__(self, surface: HierarchicalSurface, skeleton: Skeleton, bindings: dict[int, Binding],
                 blend: str, procedures: tuple[PoseProcedure, ...]) -> None:
        self._rest = surface
        self.skeleton = skeleton
        self.bindings: Mapping[int, Binding] = MappingProxyType(bindings)
        self.blend = blend
        self.procedures = procedures
        # per bound level: the vertices' rest world positions and the motion columns of its joints
        self._rest_points = {k: (surface.base.control_points if k == 0 else surface.control_points(k)).reshape(-1, 3)
                             for k in bindings}
        self._columns = {k: np.array([skeleton.index(j) for j in b.joints]) for k, b in bindings.items()}

    @property
    def rest(self) -> HierarchicalSurface:
        """A copy of the rest hierarchy."""
        return self._rest.copy()

    def control_targets(self, pose: Pose, level: int = 0) -> Array:
        """World positions of a bound level's vertices in ``pose`` (before procedures), (n_u, n_v, 3)."""
        if level not in self.bindings:
            raise InvalidGeometryError(f"level: {level!r} is not bound (bound: {', '.join(map(str, self.bindings))})")
        b = self.bindings[level]
        moved = blend_motions(self._rest_points[level], pose.motions[self._columns[level]],
                              b.weights.reshape(-1, len(b.joints)), self.blend)
        return moved.reshape(b.weights.shape[:2] + (3,))

    def at(self, pose: Pose) -> HierarchicalSurface:
        """The surface in ``pose`` (course §5-42): bound levels moved with their segments, finer
        levels carried by offset referencing, procedures applied.

        Returns
        -------
        HierarchicalSurface
            A new hierarchy; its overlays' stored offsets equal the rest ones except on bound
            overlays (repositioned with their segments) and procedural ones (offsets added).
            ``flatten()`` gives the exact NURBS of the pose.
        """
        if not isinstance(pose, Pose) or pose.skeleton is not self.skeleton:
            raise InvalidGeometryError("pose: expected a Pose of this surface's skeleton (skeleton.pose(...))")
        hs = self._rest.copy()
        for k in self.bindings:
            target = self.control_targets(pose, k)
            if k == 0:
                set_base_points(hs, target)
            else:
                set_world_points(hs, k, target)
        extra: dict[int, Array] = {}
        for p in self.procedures:
            o = _handle(hs, p.overlay)
            add = p.offsets(pose, (o.shape[0], o.shape[1]))
            extra[p.overlay] = extra[p.overlay] + add if p.overlay in extra else add
        for oid, add in extra.items():
            hs.set_offsets(oid, hs.offsets(oid) + add)
        return hs

    # ------------------------------------------------------------------ storage
    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: the rest hierarchy, skeleton, bindings, blend and procedures."""
        return {"type": "AttachedSurface", "version": ATTACHED_FORMAT, "surface": self._rest.to_dict(),
                "skeleton": self.skeleton.to_dict(), "blend": self.blend,
                "bindings": [{"level": k, **b.to_dict()} for k, b in self.bindings.items()],
                "procedures": [p.to_dict() for p in self.procedures]}

    @classmethod
    def from_dict(cls, data: Any) -> AttachedSurface:
        """The attached surface of :meth:`to_dict`; bad data is one :class:`InvalidGeometryError`."""
        if not isinstance(data, dict) or data.get("type") != "AttachedSurface":
            raise InvalidGeometryError("from_dict: expected a dict with type 'AttachedSurface'")
        if data.get("version") != ATTACHED_FORMAT:
            raise InvalidGeometryError(f"from_dict: AttachedSurface format version {data.get('version')!r} is not supported")
        try:
            surface = HierarchicalSurface.from_dict(data["surface"])
            skeleton = Skeleton.from_dict(data["skeleton"])
            bindings = {int(b["level"]): Binding(tuple(b["joints"]), np.asarray(b["weights"], float))
                        for b in data["bindings"]}
            procs = []
            for p in data["procedures"]:
                kind = p.get("kind")
                if kind not in _PROCEDURES:
                    raise InvalidGeometryError(f"from_dict: unknown procedure kind {kind!r} (register it with "
                                               "register_procedure)")
                procs.append(_PROCEDURES[kind].from_dict(p))
            blend = data["blend"]
        except InvalidGeometryError as err:
            raise InvalidGeometryError(f"from_dict: AttachedSurface: {err}") from err
        except (KeyError, TypeError, ValueError, AttributeError, IndexError) as err:
            raise InvalidGeometryError(f"from_dict: AttachedSurface: missing or bad entry ({type(err).__name__}: {err})") from err
        try:
            return attach(surface, skeleton, bindings, blend=blend, procedures=procs)
        except InvalidGeometryError as err:
            raise InvalidGeometryError(f"from_dict: AttachedSurface: {err}") from err


def set_world_points(hs: HierarchicalSurface, overlay: int, points: Array) -> None:
    """Store offsets of ``overlay`` so that its control vertices lie at world ``points`` over the
    current (posed) parent: ``o = map^{-1}(points - reference, frames)`` (in place)."""
    frames = hs.reference_frames(overlay)
    mapping = hs.offset_mapping
    shape = points.shape
    F = None if frames is None else frames.reshape(-1, 3, 3)
    current = hs.offsets(overlay)
    reference = hs.control_points(overlay).reshape(-1, 3) - np.asarray(mapping(current.reshape(-1, 3), F), float)
    new = np.asarray(mapping.inverse(points.reshape(-1, 3) - reference, F), float)
    hs.set_offsets(overlay, new.reshape(shape))


# ------------------------------------------------------------------------------------ measures
def section_area(surface: HierarchicalSurface | BSplineSurface, origin: ArrayLike, normal: ArrayLike, *,
                 samples: tuple[int, int] = (801, 256)) -> float:
    """Area enclosed by the section of a tube-like surface with a plane.

    Each ``v`` line of the surface (around the tube) is sampled along ``u``; where it crosses the
    plane (the crossing nearest to ``origin`` when it crosses more than once) the point is found
    by linear interpolation between samples, refined by two secant steps on the surface; the area
    of the closed polygon of these points is taken in the plane (shoelace formula). A polygon of
    ``n`` points inscribed in a smooth closed curve misses ``O(1/n^2)`` of its area (1e-4 for 256
    points), so on a closed tube the polygons of all points and of every other point are combined
    by Richardson extrapolation, ``(4 A_n - A_{n/2}) / 3``, whose error is ``O(1/n^4)``: 1.5e-8
    relative on exact rational circles and ellipses, and 7e-6 from OCC's plane section of the test
    arm (OCC approximates its section curves). Used to measure how a bent joint keeps its
    cross-section (course §5-45).

    Parameters
    ----------
    surface : HierarchicalSurface or BSplineSurface
        3-D; ``u`` along the tube, ``v`` around it (closed when its first and last ``v`` lines meet).
    origin, normal : array_like, shape (3,)
        The plane (the normal need not be unit length, but not zero).
    samples : (int, int), default (801, 256)
        Sample lines along ``u`` and points around ``v`` (rounded up to an even count on a closed
        tube), at least 3 each.

    Raises
    ------
    InvalidGeometryError
        Bad arguments, or a ``v`` line that does not cross the plane.
    """
    if not isinstance(surface, (HierarchicalSurface, BSplineSurface)) or surface.dim != 3:
        raise InvalidGeometryError(f"surface: expected a 3-D BSplineSurface or HierarchicalSurface, got "
                                   f"{type(surface).__name__}")
    o = V.as_finite_array(origin, "origin")
    n = V.as_finite_array(normal, "normal")
    if o.shape != (3,) or n.shape != (3,) or not np.linalg.norm(n) > 0:
        raise InvalidGeometryError(f"origin, normal: expected two 3-vectors, the normal non-zero; got {origin!r}, {normal!r}")
    n = n / np.linalg.norm(n)
    try:
        nu, nv = (int(k) for k in samples)
    except (TypeError, ValueError):
        raise InvalidGeometryError(f"samples: expected two integers, got {samples!r}") from None
    if nu < 3 or nv < 3:
        raise InvalidGeometryError(f"samples: expected at least 3 lines each way, got {samples!r}")
    V.check_size((nu, nv, 3), "section_area samples")
    (u0, u1), (v0, v1) = surface.domain
    us = np.linspace(u0, u1, nu)
    ends = surface.evaluate(np.full(2, us[nu // 2]), np.array([v0, v1]))
    closed = bool(np.abs(ends[0] - ends[1]).max() <= 1e-9 * max(1.0, float(np.abs(ends).max())))
    vs = np.linspace(v0, v1, nv + nv % 2 + 1)[:-1] if closed else np.linspace(v0, v1, nv)
    P = surface.evaluate_grid(us, vs)  # (nu, nv, 3)
    d = (P - o) @ n
    cross = np.signbit(d[:-1]) != np.signbit(d[1:])  # (nu-1, nv)
    if not np.all(cross.any(0)):
        raise InvalidGeometryError("section_area: some v lines of the surface do not cross the plane")
    mid = 0.5 * (P[:-1] + P[1:])
    dist = np.where(cross, np.linalg.norm(mid - o, axis=-1), np.inf)
    i = np.argmin(dist, axis=0)
    cols = np.arange(vs.size)
    a, b = us[i], us[i + 1]
    da, db = d[i, cols], d[i + 1, cols]
    for _ in range(2):  # secant steps on the surface itself, bracketed
        t = a - da * (b - a) / (db - da)
        dt = (surface.evaluate(t, vs) - o) @ n
        left = np.signbit(dt) == np.signbit(da)
        a, da = np.where(left, t, a), np.where(left, dt, da)
        b, db = np.where(left, b, t), np.where(left, db, dt)
    t = a - da * (b - a) / (db - da)
    Q = surface.evaluate(t, vs) - o
    Q = Q - np.outer(Q @ n, n)

    def polygon(R: Array) -> float:
        return float(0.5 * abs(np.sum(np.cross(R, np.roll(R, -1, axis=0)) @ n)))

    if not closed:  # an open v range: the plain polygon
        return polygon(Q)
    return (4.0 * polygon(Q) - polygon(Q[::2])) / 3.0
