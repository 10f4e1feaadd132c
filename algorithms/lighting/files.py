"""The lights file: JSON load and dump of a :class:`~.model.LightingSetup`, validated field by field.

Format (``occsurf render --lights FILE``; every key but ``lights[].direction`` is optional)::

    {
      "ambient": 0.05,                      # grey, or [r, g, b]
      "two_sided": true,                    # light the back of open faces like their front
      "material": {"color": [0.75, 0.77, 0.8], "diffuse": 0.8, "specular": 0.35,
                   "shininess": 40, "specular_color": [1, 1, 1]},
      "lights": [
        {"name": "key",
         "position": [x, y, z],             # null: a directional light at infinity
         "direction": [dx, dy, dz],         # where the light points (made unit)
         "color": [r, g, b], "intensity": 1.0,
         "concentration": 0,                # Warn's cos^n reflector, n >= 0 (0: a plain light) ...
         "concentration_ratio": 1,          # ... or the same as C = n + 1 >= 1 (1: a plain light)
         "cone": {"angle_deg": 30, "edge_deg": 2},
         "flaps": {"x": [lo, hi], "y": [lo, hi], "z": [lo, hi],    # light's frame, model units;
                   "edge": 0.0},                                   # null for an open side; soft edge
         "falloff": "none",                 # or "inverse", "inverse_square" ...
         "falloff_distance": 100.0}         # ... with full intensity up to this distance
      ]
    }

A light gives at most one of ``concentration`` (Warn's exponent ``n``, the intensity at angle
``gamma`` from the axis is ``cos(gamma)**n``) and ``concentration_ratio`` (``C = n + 1``: the
intensity on the axis over the mean over the directions lit, so 1 is a plain light; see
:attr:`~.model.WarnLight.concentration_ratio`). Files are written with ``concentration``.

The flaps are given in the light's frame: ``z`` along its direction, ``x`` the projection of the
model's +x onto the plane normal to it (+y where +x is parallel to the direction), ``y = z x x``,
origin at the light's position. Unknown keys are errors (a typo must not silently drop a
control); every error is an :class:`~occsurf.algorithms.errors.InvalidGeometryError` naming the
field (``lights[1].cone.angle_deg: expected 0 < angle_deg <= 90, got 120``).
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path
from typing import Any

from ..errors import ExchangeError, InvalidGeometryError
from .model import LightingSetup, Material, WarnLight

__all__ = ["setup_from_dict", "setup_to_dict", "load_lights", "dump_lights", "loads_lights", "dumps_lights"]

_TOP_KEYS = {"ambient", "two_sided", "material", "lights", "comment"}
_LIGHT_KEYS = {"name", "position", "direction", "color", "intensity", "concentration", "concentration_ratio", "cone",
               "flaps", "falloff", "falloff_distance", "comment"}
_CONE_KEYS = {"angle_deg", "edge_deg"}
_MATERIAL_KEYS = {"color", "diffuse", "specular", "shininess", "specular_color"}


def _keys(obj: Any, allowed: set[str], where: str, required: tuple[str, ...] = ()) -> dict[str, Any]:
    if not isinstance(obj, dict):
        raise InvalidGeometryError(f"{where}: expected a JSON object, got {type(obj).__name__}")
    unknown = sorted(set(obj) - allowed)
    if unknown:
        raise InvalidGeometryError(f"{where}.{unknown[0]}: unknown key (expected one of {', '.join(sorted(allowed))})")
    for key in required:
        if key not in obj:
            raise InvalidGeometryError(f"{where}.{key}: missing (required)")
    return obj


def _renamed(err: InvalidGeometryError, old: str, new: str) -> InvalidGeometryError:
    """The same error with the field path ``old...`` reported as ``new...``."""
    msg = str(err)
    return InvalidGeometryError(new + msg[len(old):] if msg.startswith(old) else f"{new}: {msg}")


def _light(obj: Any, where: str) -> WarnLight:
    d = _keys(obj, _LIGHT_KEYS, where, required=("direction",))
    cone = d.get("cone")
    angle = cone_edge = None
    if cone is not None:
        c = _keys(cone, _CONE_KEYS, f"{where}.cone", required=("angle_deg",))
        angle, cone_edge = c["angle_deg"], c.get("edge_deg", 0.0)
    flaps = d.get("flaps")
    edge = 0.0
    if isinstance(flaps, dict) and "edge" in flaps:
        flaps = dict(flaps)
        edge = flaps.pop("edge")
    fields = dict(position=d.get("position"), direction=d["direction"], color=d.get("color", (1.0, 1.0, 1.0)),
                  intensity=d.get("intensity", 1.0), cone_angle_deg=angle,
                  cone_edge_deg=0.0 if cone_edge is None else cone_edge, flaps=flaps, flap_edge=edge,
                  falloff=d.get("falloff", "none"), falloff_distance=d.get("falloff_distance"), name=d.get("name", ""))
    try:
        if "concentration_ratio" in d:
            if "concentration" in d:
                raise InvalidGeometryError("light.concentration_ratio: give either concentration (Warn's exponent n) "
                                           "or concentration_ratio (C = n + 1), not both")
            return WarnLight.with_concentration_ratio(d["concentration_ratio"], **fields)
        return WarnLight(concentration=d.get("concentration", 0.0), **fields)
    except InvalidGeometryError as err:
        raise _renamed(err, "light", where) from None


def setup_from_dict(data: Any) -> LightingSetup:
    """A validated :class:`LightingSetup` from the parsed JSON document (format in the module docstring)."""
    d = _keys(data, _TOP_KEYS, "lights file")
    lights_in = d.get("lights", [])
    if not isinstance(lights_in, list):
        raise InvalidGeometryError(f"lights: expected a list of lights, got {type(lights_in).__name__}")
    lights = tuple(_light(obj, f"lights[{k}]") for k, obj in enumerate(lights_in))
    material = Material()
    if "material" in d:
        m = _keys(d["material"], _MATERIAL_KEYS, "material")
        try:
            material = Material(**m)
        except InvalidGeometryError as err:
            raise _renamed(err, "material", "material") from None
    two_sided = d.get("two_sided", True)
    return LightingSetup(lights=lights, ambient=d.get("ambient", 0.05), material=material, two_sided=two_sided)


def _bound(x: float) -> float | None:
    return None if math.isinf(x) else x


def setup_to_dict(setup: LightingSetup) -> dict[str, Any]:
    """The JSON document of ``setup`` (open flaps and absent cones left out; loads back equal)."""
    lights = []
    for light in setup.lights:
        d: dict[str, Any] = {}
        if light.name:
            d["name"] = light.name
        d["position"] = None if light.position is None else list(light.position)
        d["direction"] = list(light.direction)
        d["color"] = list(light.color)
        d["intensity"] = light.intensity
        d["concentration"] = light.concentration
        if light.cone_angle_deg is not None:
            d["cone"] = {"angle_deg": light.cone_angle_deg, "edge_deg": light.cone_edge_deg}
        flaps: dict[str, list[float | None] | float] = {
            axis: [_bound(lo), _bound(hi)] for axis, (lo, hi) in zip("xyz", light.flaps)
            if not (math.isinf(lo) and math.isinf(hi))}
        if flaps:
            d["flaps"] = flaps
            if light.flap_edge:
                flaps["edge"] = light.flap_edge
        if light.falloff != "none":
            d["falloff"] = light.falloff
            d["falloff_distance"] = light.falloff_distance
        lights.append(d)
    m = setup.material
    amb = setup.ambient
    return {"ambient": amb[0] if amb[0] == amb[1] == amb[2] else list(amb), "two_sided": setup.two_sided,
            "material": {"color": list(m.color), "diffuse": m.diffuse, "specular": m.specular,
                         "shininess": m.shininess, "specular_color": list(m.specular_color)},
            "lights": lights}


def loads_lights(text: str) -> LightingSetup:
    """Parse a lights document; bad JSON is reported with its line and column."""
    try:
        data = json.loads(text)
    except json.JSONDecodeError as err:
        raise InvalidGeometryError(f"lights file: not valid JSON ({err.msg} at line {err.lineno}, "
                                   f"column {err.colno})") from None
    return setup_from_dict(data)


def dumps_lights(setup: LightingSetup) -> str:
    """The lights document of ``setup`` as indented JSON text."""
    return json.dumps(setup_to_dict(setup), indent=2, allow_nan=False) + "\n"


def load_lights(path: str | os.PathLike[str]) -> LightingSetup:
    """Read a lights file (format in the module docstring).

    Raises
    ------
    ExchangeError
        The file cannot be read.
    InvalidGeometryError
        Not JSON, or a field is wrong (the message names it).
    """
    try:
        text = Path(path).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as err:
        raise ExchangeError(f"{path}: cannot read the lights file: {getattr(err, 'strerror', None) or err}") from err
    return loads_lights(text)


def dump_lights(setup: LightingSetup, path: str | os.PathLike[str]) -> Path:
    """Write ``setup`` as a lights file, atomically; returns the path."""
    from .._files import atomic_write

    p = Path(path)
    atomic_write(p, dumps_lights(setup).encode("utf-8"))
    return p
