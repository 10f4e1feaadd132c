"""Surface construction (course ch. 6): extrusion, ruled surfaces, revolution, translational,
rotational and general sweeps (§6-26..6-33), Coons patches (§6-20, 6-21) and Gordon surfaces
(§6-22..6-25).

Public names: :func:`extrude`, :func:`ruled`, :func:`revolve`, :func:`translational_sweep`,
:func:`rotational_sweep`, :func:`sweep`, :func:`exact_sweep`, :class:`SweepResult`, :func:`coons`,
:func:`coons_bicubic`, :func:`polynomial_approximation`, :func:`gordon`, :func:`network_parameters`.
"""

from .coons_patches import coons, coons_bicubic
from .generation import extrude, revolve, rotational_sweep, ruled, translational_sweep
from .gordon_surfaces import gordon, network_parameters
from .rational_approximation import polynomial_approximation
from .sweeping import SweepResult, exact_sweep, sweep

__all__ = [
    "extrude",
    "revolve",
    "rotational_sweep",
    "ruled",
    "translational_sweep",
    "SweepResult",
    "exact_sweep",
    "sweep",
    "coons",
    "coons_bicubic",
    "polynomial_approximation",
    "gordon",
    "network_parameters",
]
