"""Warn's lights, the surface material and a lighting setup: small frozen, validated dataclasses.

Course ch. 10 (D. R. Warn, "Lighting Controls for Synthetic Images", SIGGRAPH '83), §10-2 .. §10-4.
A :class:`WarnLight` is a point light at ``position`` aimed along ``direction`` with Warn's
controls: concentration (a reflector, ``cos^n``), flaps (barn doors: up to six planes of the
light's own frame) and a cone with a soft edge, plus a distance fall-off. A ``position`` of
``None`` is a directional light (at infinity, shining along ``direction``).

Validation happens once, in ``__post_init__``; every error is an
:class:`~occsurf.algorithms.errors.InvalidGeometryError` whose message names the field
(``lights[0].flaps.x``, ``material.shininess``...), what was expected and what was received.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from .. import tolerances
from ..errors import InvalidGeometryError

__all__ = ["WarnLight", "Material", "LightingSetup", "FALLOFFS", "light_frame"]

#: Distance fall-off laws: ``'none'`` (Warn's default: a studio light does not dim over the model),
#: ``'inverse'`` ``(d0 / max(d, d0))`` and ``'inverse_square'`` ``(d0 / max(d, d0))**2`` with
#: ``d0 = falloff_distance``: full intensity up to ``d0`` from the light, then the law.
FALLOFFS = ("none", "inverse", "inverse_square")

_INF = math.inf


# ---------------------------------------------------------------------------------------- checks
def _real(value: Any, name: str, *, lo: float | None = None, hi: float | None = None, lo_open: bool = False,
          hi_open: bool = False) -> float:
    """A finite real number within the given bounds, else an error naming ``name``."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not math.isfinite(float(value)):
        raise InvalidGeometryError(f"{name}: expected a finite number, got {value!r}")
    x = float(value)
    below = lo is not None and (x <= lo if lo_open else x < lo)
    above = hi is not None and (x >= hi if hi_open else x > hi)
    if below or above:
        left = "" if lo is None else f"{lo:g} {'<' if lo_open else '<='} "
        right = "" if hi is None else f" {'<' if hi_open else '<='} {hi:g}"
        raise InvalidGeometryError(f"{name}: expected {left}{name.rsplit('.', 1)[-1]}{right}, got {x:g}")
    return x


def _vec3(value: Any, name: str) -> tuple[float, float, float]:
    """Three finite numbers, else an error naming ``name``."""
    try:
        a = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise InvalidGeometryError(f"{name}: expected 3 numbers [x, y, z], got {value!r}") from None
    if a.shape != (3,):
        raise InvalidGeometryError(f"{name}: expected 3 numbers [x, y, z], got {value!r}")
    if not np.all(np.isfinite(a)):
        raise InvalidGeometryError(f"{name}: expected finite numbers, got {value!r}")
    return (float(a[0]), float(a[1]), float(a[2]))


def _unit(value: Any, name: str) -> tuple[float, float, float]:
    """A direction scaled to unit length; a (near-)zero vector cannot be."""
    v = np.array(_vec3(value, name))
    length = float(np.linalg.norm(v))
    if length <= tolerances.LIGHT_DIRECTION_ZERO:
        raise InvalidGeometryError(f"{name}: expected a non-zero direction (it is made a unit vector), "
                                   f"got {list(map(float, v))} of length {length:g}")
    v = v / length
    return (float(v[0]), float(v[1]), float(v[2]))


def _color(value: Any, name: str) -> tuple[float, float, float]:
    """An RGB triple of non-negative numbers (1 is full; more over-exposes)."""
    c = _vec3(value, name)
    if min(c) < 0:
        raise InvalidGeometryError(f"{name}: expected non-negative RGB components, got {list(c)}")
    return c


#: Flaps as stored: per axis x, y, z of the light's frame ``(lo, hi)``, ``-inf``/``inf`` for an open side.
Flaps = tuple[tuple[float, float], tuple[float, float], tuple[float, float]]
#: Flaps as :class:`WarnLight` takes them: ``{"x": [lo, hi], ...}`` (any subset, ``None`` for an open
#: side) or three pairs (``None`` for an open axis); ``None``: no flaps.
FlapsInput = Mapping[str, Sequence[float | None] | None] | Sequence[Sequence[float | None] | None] | None


def _flaps(value: Any, name: str) -> Flaps:
    """``{"x": [lo, hi], "y": ..., "z": ...}`` (any subset; ``None`` for an open side) or three pairs."""
    if value is None:
        return ((-_INF, _INF),) * 3
    if isinstance(value, dict):
        unknown = sorted(set(value) - {"x", "y", "z"})
        if unknown:
            raise InvalidGeometryError(f"{name}: expected keys among x, y, z, got {unknown[0]!r}")
        pairs = [value.get(k) for k in "xyz"]
    elif isinstance(value, (list, tuple)) and len(value) == 3:
        pairs = list(value)
    else:
        raise InvalidGeometryError(f"{name}: expected {{'x': [lo, hi], 'y': [lo, hi], 'z': [lo, hi]}}, got {value!r}")
    out = []
    for axis, pair in zip("xyz", pairs):
        if pair is None:
            out.append((-_INF, _INF))
            continue
        if not isinstance(pair, (list, tuple)) or len(pair) != 2:
            raise InvalidGeometryError(f"{name}.{axis}: expected [lo, hi] (null for an open side), got {pair!r}")
        lo = -_INF if pair[0] is None or pair[0] == -_INF else _real(pair[0], f"{name}.{axis}[0]")
        hi = _INF if pair[1] is None or pair[1] == _INF else _real(pair[1], f"{name}.{axis}[1]")
        if lo > hi:
            raise InvalidGeometryError(f"{name}.{axis}: the min flap {lo:g} lies above the max flap {hi:g}")
        out.append((lo, hi))
    return (out[0], out[1], out[2])


def light_frame(direction: Sequence[float]) -> np.ndarray:
    """The light's frame, rows ``x, y, z`` ``(3, 3)``: ``z`` the unit direction, ``x`` the model's
    +x projected onto the plane normal to ``z`` (+y where +x is within
    :data:`~occsurf.algorithms.tolerances.LIGHT_FRAME_DEGENERATE` of parallel), ``y = z x x``.

    Flaps are planes of constant x, y or z in this frame (course §10-4), measured from the light.
    """
    z = np.asarray(direction, float)
    z = z / np.linalg.norm(z)
    for axis in (np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0])):
        p = axis - (axis @ z) * z
        s = float(np.linalg.norm(p))
        if s > tolerances.LIGHT_FRAME_DEGENERATE:
            x = p / s
            break
    y = np.cross(z, x)
    return np.stack([x, y, z])


# ---------------------------------------------------------------------------------------- classes
@dataclass(frozen=True)
class WarnLight:
    """One of Warn's studio lights (course §10-3, §10-4).

    Parameters
    ----------
    position : (3,) floats or None
        Where the light is, model units; ``None``: a directional light at infinity (then
        concentration and cone, which need a position, must stay off).
    direction : (3,) floats
        The light's axis (where it points), made a unit vector; the ``z`` axis of its frame.
    color : (3,) floats, default white
        RGB of the light, each >= 0. Lights of different colours blend additively, per channel,
        on the surface (course §10-7).
    intensity : float, default 1
        Scale of ``color``, >= 0.
    concentration : float, default 0
        Warn's reflector exponent ``n >= 0``: the light's intensity towards a point at angle
        ``gamma`` from the axis is ``cos(gamma)**n`` (nothing behind the light for ``n > 0``);
        ``n = 0`` is a plain point light, uniform in every direction. The same control counted
        so that 1 is the plain light is :attr:`concentration_ratio` ``C = n + 1``
        (:meth:`with_concentration_ratio`; ``"concentration_ratio"`` in a lights file).
    cone_angle_deg : float or None
        Half-angle of the light's cone, in ``(0, 90]`` degrees; ``None``: no cone.
    cone_edge_deg : float, default 0
        Width of the cone's soft edge, in ``[0, cone_angle_deg]``: full light up to
        ``angle - edge``, none from ``angle`` on, and a smoothstep ``3t^2 - 2t^3`` in the angle
        between.
    flaps : ((lo, hi), (lo, hi), (lo, hi))
        Barn doors: the light reaches only points whose coordinates in the light's frame
        (:func:`light_frame`, origin at ``position``, model units) lie within these bounds
        (``-inf``/``inf`` for an open side). Accepts ``{"x": [lo, hi], ...}`` too.
    flap_edge : float, default 0
        Width of the flaps' soft edge, model units, >= 0: the light rises from 0 at a flap to full
        at ``flap_edge`` inside it, by the same smoothstep as the cone (0: a sharp cut, as barn
        doors close to the light give; a soft edge keeps a narrow band from aliasing).
    falloff : str, default 'none'
        One of :data:`FALLOFFS`.
    falloff_distance : float or None
        ``d0 > 0``, required by the ``'inverse'`` and ``'inverse_square'`` laws.
    name : str
        A label (``'key'``, ``'fill'``...).
    """

    position: tuple[float, float, float] | None
    direction: tuple[float, float, float]
    color: tuple[float, float, float] = (1.0, 1.0, 1.0)
    intensity: float = 1.0
    concentration: float = 0.0
    cone_angle_deg: float | None = None
    cone_edge_deg: float = 0.0
    if TYPE_CHECKING:  # as stored by __post_init__ (open sides +-inf)
        flaps: Flaps = ((-_INF, _INF), (-_INF, _INF), (-_INF, _INF))
    else:
        flaps: Any = None
    flap_edge: float = 0.0
    falloff: str = "none"
    falloff_distance: float | None = None
    name: str = ""

    if TYPE_CHECKING:  # the generated __init__ takes sequences and the flap forms; __post_init__ normalises them

        def __init__(
            self,
            position: Sequence[float] | None,
            direction: Sequence[float],
            color: Sequence[float] = (1.0, 1.0, 1.0),
            intensity: float = 1.0,
            concentration: float = 0.0,
            cone_angle_deg: float | None = None,
            cone_edge_deg: float = 0.0,
            flaps: FlapsInput = None,
            flap_edge: float = 0.0,
            falloff: str = "none",
            falloff_distance: float | None = None,
            name: str = "",
        ) -> None: ...

    def __post_init__(self) -> None:
        self._check("light")

    def _check(self, where: str) -> None:
        """Validate and normalise every field; ``where`` prefixes field names in messages."""
        put = object.__setattr__
        if self.position is not None:
            put(self, "position", _vec3(self.position, f"{where}.position"))
        put(self, "direction", _unit(self.direction, f"{where}.direction"))
        put(self, "color", _color(self.color, f"{where}.color"))
        put(self, "intensity", _real(self.intensity, f"{where}.intensity", lo=0.0))
        put(self, "concentration", _real(self.concentration, f"{where}.concentration", lo=0.0))
        if self.cone_angle_deg is not None:
            put(self, "cone_angle_deg", _real(self.cone_angle_deg, f"{where}.cone.angle_deg", lo=0.0, hi=90.0,
                                              lo_open=True))
            put(self, "cone_edge_deg", _real(self.cone_edge_deg, f"{where}.cone.edge_deg", lo=0.0,
                                             hi=self.cone_angle_deg))
        else:
            put(self, "cone_edge_deg", _real(self.cone_edge_deg, f"{where}.cone.edge_deg", lo=0.0))
        put(self, "flaps", _flaps(self.flaps, f"{where}.flaps"))
        put(self, "flap_edge", _real(self.flap_edge, f"{where}.flaps.edge", lo=0.0))
        if self.falloff not in FALLOFFS:
            raise InvalidGeometryError(f"{where}.falloff: expected one of {', '.join(FALLOFFS)}, got {self.falloff!r}")
        if self.falloff != "none" or self.falloff_distance is not None:
            if self.falloff_distance is None:
                raise InvalidGeometryError(f"{where}.falloff_distance: the {self.falloff!r} fall-off needs a "
                                           "distance d0 > 0 (full intensity up to d0 from the light)")
            put(self, "falloff_distance", _real(self.falloff_distance, f"{where}.falloff_distance", lo=0.0,
                                                lo_open=True))
        if self.position is None and (self.concentration > 0 or self.cone_angle_deg is not None):
            raise InvalidGeometryError(f"{where}.position: a directional light (position null) has no concentration "
                                       "or cone: they need a position to measure angles from")
        if not isinstance(self.name, str):
            raise InvalidGeometryError(f"{where}.name: expected a string, got {self.name!r}")

    @property
    def concentration_ratio(self) -> float:
        """Warn's concentration counted from 1: ``C = n + 1`` (``n`` = :attr:`concentration`).

        ``C`` is the light's intensity on its axis over its mean intensity across the directions
        it lights: a plain light (``n = 0``) lights every direction evenly, ``C = 1``; a reflector
        ``cos^n`` lights the half-space in front of it, where the mean of ``cos^n`` is
        ``1 / (n + 1)``, so ``C = n + 1``: 2 is a Lambertian reflector (``cos``), 41 Warn's
        spotlight ``cos^40``. Only the counting differs from Warn's exponent; the light is his.
        """
        return self.concentration + 1.0

    @classmethod
    def with_concentration_ratio(cls, concentration_ratio: float, **fields: Any) -> WarnLight:
        """A light given its :attr:`concentration_ratio` ``C >= 1`` (``C = 1``: a plain light)
        instead of Warn's exponent ``n = C - 1``; ``fields`` are the other constructor arguments.

        Raises
        ------
        InvalidGeometryError
            ``C`` is not a finite number >= 1 (message names ``light.concentration_ratio``), or
            ``fields`` also gives ``concentration``.
        """
        if "concentration" in fields:
            raise InvalidGeometryError("light.concentration_ratio: give either concentration (Warn's exponent n) or "
                                       "concentration_ratio (C = n + 1), not both")
        ratio = _real(concentration_ratio, "light.concentration_ratio", lo=1.0)
        return cls(concentration=ratio - 1.0, **fields)

    @property
    def frame(self) -> np.ndarray:
        """Rows ``x, y, z`` of the light's frame ``(3, 3)`` (:func:`light_frame`)."""
        return light_frame(self.direction)

    @property
    def origin(self) -> np.ndarray:
        """Origin of the flap frame: the position (the model's origin for a directional light)."""
        return np.zeros(3) if self.position is None else np.asarray(self.position, float)

    @property
    def rgb(self) -> np.ndarray:
        """``intensity * color`` ``(3,)``."""
        return self.intensity * np.asarray(self.color, float)

    @property
    def has_flaps(self) -> bool:
        return any(math.isfinite(b) for pair in self.flaps for b in pair)


@dataclass(frozen=True)
class Material:
    """A plastic-like surface: Lambert diffuse plus Phong specular (Warn's lighting model, §10-2).

    Parameters
    ----------
    color : (3,) floats
        Diffuse RGB reflectance, each in [0, 1]; also scales the ambient light.
    diffuse : float
        ``k_d >= 0``.
    specular : float
        ``k_s >= 0``.
    shininess : float
        Phong exponent ``s >= 0`` of ``(R . V)**s``.
    specular_color : (3,) floats
        RGB of the highlight, in [0, 1] (white: the highlight takes the light's colour, as on
        paint and plastic).
    """

    color: tuple[float, float, float] = (0.75, 0.77, 0.80)
    diffuse: float = 0.8
    specular: float = 0.35
    shininess: float = 40.0
    specular_color: tuple[float, float, float] = (1.0, 1.0, 1.0)

    def __post_init__(self) -> None:
        self._check("material")

    def _check(self, where: str) -> None:
        put = object.__setattr__
        for key in ("color", "specular_color"):
            c = _color(getattr(self, key), f"{where}.{key}")
            if max(c) > 1:
                raise InvalidGeometryError(f"{where}.{key}: expected RGB components in [0, 1], got {list(c)}")
            put(self, key, c)
        put(self, "diffuse", _real(self.diffuse, f"{where}.diffuse", lo=0.0))
        put(self, "specular", _real(self.specular, f"{where}.specular", lo=0.0))
        put(self, "shininess", _real(self.shininess, f"{where}.shininess", lo=0.0))


@dataclass(frozen=True)
class LightingSetup:
    """Lights, ambient light and material: everything :func:`~.shading.shade` and the renderer need.

    Parameters
    ----------
    lights : sequence of WarnLight
        At most :data:`~occsurf.algorithms.tolerances.LIGHT_MAX_COUNT`; may be empty (ambient only).
    ambient : float or (3,) floats
        Ambient light (RGB >= 0; a number is grey), multiplied by the material's colour.
    material : Material
    two_sided : bool, default True
        Normals facing away from the viewer are turned towards it (a single face seen from
        behind is lit like its front); ``False`` leaves them (back faces get ambient only).
    """

    lights: tuple[WarnLight, ...] = ()
    if TYPE_CHECKING:  # as stored by __post_init__
        ambient: tuple[float, float, float] = (0.05, 0.05, 0.05)
    else:
        ambient: Any = 0.05
    material: Material = field(default_factory=Material)
    two_sided: bool = True

    if TYPE_CHECKING:  # the generated __init__ takes any of these; __post_init__ stores tuples

        def __init__(
            self,
            lights: Sequence[WarnLight] = (),
            ambient: float | Sequence[float] = 0.05,
            material: Material = ...,
            two_sided: bool = True,
        ) -> None: ...

    def __post_init__(self) -> None:
        put = object.__setattr__
        lights = tuple(self.lights) if isinstance(self.lights, (list, tuple)) else self.lights
        if not isinstance(lights, tuple):
            raise InvalidGeometryError(f"lights: expected a list of WarnLight, got {type(self.lights).__name__}")
        for k, light in enumerate(lights):
            if not isinstance(light, WarnLight):
                raise InvalidGeometryError(f"lights[{k}]: expected a WarnLight, got {type(light).__name__}")
        if len(lights) > int(tolerances.LIGHT_MAX_COUNT):
            raise InvalidGeometryError(f"lights: expected at most {int(tolerances.LIGHT_MAX_COUNT)} lights, "
                                       f"got {len(lights)}")
        put(self, "lights", lights)
        amb = self.ambient
        if isinstance(amb, numbers.Real) and not isinstance(amb, bool):
            g = _real(amb, "ambient", lo=0.0)
            put(self, "ambient", (g, g, g))
        else:
            put(self, "ambient", _color(amb, "ambient"))
        if not isinstance(self.material, Material):
            raise InvalidGeometryError(f"material: expected a Material, got {type(self.material).__name__}")
        if not isinstance(self.two_sided, bool):
            raise InvalidGeometryError(f"two_sided: expected true or false, got {self.two_sided!r}")

    def replace(self, **changes: Any) -> LightingSetup:
        """A copy with some fields changed (validated again)."""
        import dataclasses

        return dataclasses.replace(self, **changes)
