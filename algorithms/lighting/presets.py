"""Lighting setups a user can start from, placed around a model's bounding box (course ch. 10).

Every preset takes the model's centre and size (its bounding-box diagonal) so that the same setup
lights a 10 mm bracket and a 4 m car body alike; the model's +z is up, and the front is seen from
-y (the ``front`` view).

* :func:`studio_three_point` - the photographer's key, fill and rim lights.
* :func:`key_light_with_flaps` - one concentrated key light with flaps, the course's car-body
  figures (§10-5): a band of light laid across the body, so the highlight sits where the
  designer wants to read the surface.
* :func:`highlight_check` - parallel bands of light cut by flaps: light-section stripes whose
  edges are plane sections of the surface (their bends show its shape, as a light tunnel does).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..errors import InvalidGeometryError
from .model import LightingSetup, Material, WarnLight

__all__ = ["PRESETS", "preset", "studio_three_point", "key_light_with_flaps", "highlight_check"]


def _frame(center: Sequence[float], size: float) -> tuple[np.ndarray, float]:
    c = np.asarray(center, float)
    if c.shape != (3,) or not np.all(np.isfinite(c)):
        raise InvalidGeometryError(f"center: expected 3 finite numbers, got {center!r}")
    if not (np.isfinite(size) and size > 0):
        raise InvalidGeometryError(f"size: expected a positive model size (bounding-box diagonal), got {size!r}")
    return c, float(size)


def _aimed(name: str, center: np.ndarray, offset: Sequence[float], size: float, **kw: object) -> WarnLight:
    """A light at ``center + size * offset`` pointing at ``center``."""
    pos = center + size * np.asarray(offset, float)
    return WarnLight(position=tuple(pos), direction=tuple(center - pos), name=name, **kw)  # type: ignore[arg-type]


def studio_three_point(center: Sequence[float], size: float) -> LightingSetup:
    """Key (front left, high, concentrated), fill (front right, low, soft) and rim (behind, high).

    Parameters
    ----------
    center : (3,) floats
        Centre of the model's bounding box.
    size : float
        The bounding box's diagonal, > 0.
    """
    c, s = _frame(center, size)
    key = _aimed("key", c, (-1.2, -1.6, 1.4), s, intensity=0.85, concentration=2.0, color=(1.0, 0.97, 0.92))
    fill = _aimed("fill", c, (1.6, -1.2, 0.5), s, intensity=0.35, color=(0.92, 0.95, 1.0))
    rim = _aimed("rim", c, (0.4, 1.8, 1.2), s, intensity=0.55, concentration=4.0)
    return LightingSetup(lights=(key, fill, rim), ambient=0.06)


def key_light_with_flaps(center: Sequence[float], size: float, *, concentration: float = 6.0,
                         width: float = 0.6, height: float = 0.16) -> LightingSetup:
    """One concentrated key light from above the front, with flaps: a band of light across the model.

    The flaps are ``x`` in ``[-width/2, width/2]`` and ``y`` in ``[-height/2, height/2]`` times
    ``size`` in the light's frame (its x axis is the model's +x projected, so the band runs along
    the model's x).
    """
    c, s = _frame(center, size)
    key = _aimed("key", c, (0.0, -1.2, 1.6), s, intensity=1.0, concentration=concentration,
                 flaps={"x": [-width * s / 2, width * s / 2], "y": [-height * s / 2, height * s / 2]})
    return LightingSetup(lights=(key,), ambient=0.08,
                         material=Material(color=(0.62, 0.08, 0.06), diffuse=0.85, specular=0.5, shininess=60))


def highlight_check(center: Sequence[float], size: float, *, count: int = 9, pitch: float = 0.08,
                    width: float = 0.025) -> LightingSetup:
    """Parallel bands of light cut by flaps: light-section stripes across the model.

    ``count`` lights share one position above the front of the model, each with ``y`` flaps
    ``pitch * size`` apart and ``width * size`` wide (light's frame). A flap is a plane through
    the light, so each band's edges on the surface are plane sections of it: on a fair surface
    the stripes bend smoothly and evenly; a kink, a flat spot or a wave shows as a kink, a
    straight run or a wobble of the stripes, from any view (the stripes stay on the surface).
    """
    c, s = _frame(center, size)
    if isinstance(count, bool) or not isinstance(count, int) or not 1 <= count <= 12:
        raise InvalidGeometryError(f"count: expected an integer from 1 to 12, got {count!r}")
    for name, value in (("pitch", pitch), ("width", width)):
        if not (np.isfinite(value) and value > 0):
            raise InvalidGeometryError(f"{name}: expected a positive fraction of the model size, got {value!r}")
    offsets = (np.arange(count) - (count - 1) / 2) * pitch * s
    lights = tuple(_aimed(f"stripe {k}", c, (0.0, -0.9, 1.6), s, intensity=1.0,
                          flaps={"y": [float(o - width * s / 2), float(o + width * s / 2)]},
                          flap_edge=0.15 * width * s)  # soft edges: the stripes do not alias
                   for k, o in enumerate(offsets))
    return LightingSetup(lights=lights, ambient=0.05,
                         material=Material(color=(0.80, 0.80, 0.82), diffuse=0.8, specular=0.4, shininess=60))


#: Preset name -> function(center, size) -> LightingSetup.
PRESETS = {
    "studio": studio_three_point,
    "key-flaps": key_light_with_flaps,
    "highlight-check": highlight_check,
}


def preset(name: str, center: Sequence[float], size: float) -> LightingSetup:
    """The preset ``name`` (a key of :data:`PRESETS`) around a model."""
    if name not in PRESETS:
        raise InvalidGeometryError(f"preset: expected one of {', '.join(PRESETS)}, got {name!r}")
    return PRESETS[name](center, size)
