"""Lighting controls for shaded images of surfaces (course ch. 10: D. R. Warn, "Lighting Controls
for Synthetic Images", SIGGRAPH '83).

Warn lit car bodies the way a photographer lights a clay model, so that a designer sees the
highlights where they are expected. This subpackage is the NumPy reference of his model; the
renderer (:mod:`occsurf.bridge.rendering.lighting`) implements the same formulas per pixel.

Public names
------------
Model (§10-2 .. §10-4, :mod:`.model`): :class:`WarnLight` (position, direction, colour, intensity,
concentration ``cos^n`` - Warn's exponent, 0 a plain light - or the same counted from 1 as
``WarnLight.concentration_ratio = n + 1``, cone with a soft edge, flaps in the light's frame,
distance fall-off),
:class:`Material` (Lambert diffuse + **Phong** specular), :class:`LightingSetup` (lights, ambient,
material), :func:`light_frame`, :data:`FALLOFFS`.

Shading (:mod:`.shading`): :func:`shade` ``(points, normals, view_point, lights, material) ->
(..., 3)`` linear RGB, vectorised; :func:`light_factor` (one light's concentration x cone x flaps x
fall-off). Several lights add; coloured lights blend per channel (§10-7). Large inputs go through
an optional numba kernel (:mod:`._kernels`) that repeats the NumPy path's operations.

Presets (:mod:`.presets`): :func:`studio_three_point`, :func:`key_light_with_flaps` (the course's
car-body figures), :func:`highlight_check`; :data:`PRESETS`, :func:`preset`.

Lights files (:mod:`.files`): :func:`load_lights`, :func:`dump_lights`, :func:`loads_lights`,
:func:`dumps_lights`, :func:`setup_from_dict`, :func:`setup_to_dict` (the JSON format of
``occsurf render --lights``).

Tolerances: the ``LIGHT_...`` entries of :mod:`occsurf.algorithms.tolerances`.
"""

from .files import dump_lights, dumps_lights, load_lights, loads_lights, setup_from_dict, setup_to_dict
from .model import FALLOFFS, LightingSetup, Material, WarnLight, light_frame
from .presets import PRESETS, highlight_check, key_light_with_flaps, preset, studio_three_point
from .shading import light_factor, shade

__all__ = [
    "FALLOFFS",
    "LightingSetup",
    "Material",
    "WarnLight",
    "light_frame",
    "shade",
    "light_factor",
    "PRESETS",
    "preset",
    "studio_three_point",
    "key_light_with_flaps",
    "highlight_check",
    "load_lights",
    "dump_lights",
    "loads_lights",
    "dumps_lights",
    "setup_from_dict",
    "setup_to_dict",
]
