"""Linear algebra for splines and constraint-based direct manipulation (course ch. 3 and 4).

Public names: the constraints :class:`Position`, :class:`Tangent`, :class:`Derivative`,
:class:`Curvature`; :func:`constrain`, :func:`drag_point`, :class:`Dragger`,
:class:`PreparedConstraints` for curves and :func:`drag_surface_point` for surfaces;
:func:`match_surface` (G0-G3 along an edge, :class:`MatchTarget`, :class:`MatchResult`) and
:func:`match_along` (G0, G1 along a curve inside a surface: a trimmed face's edge);
:func:`fair_surface` (wiggles out by the least curvature variation within a tolerance); the solvers of
:mod:`.linalg` (least squares, minimum norm, equality-constrained; dense) and :mod:`.sparse_linalg`
(their sparse forms) and their errors :class:`ConstraintError`, :class:`ConvergenceError`.
"""

from .constraints import Curvature, Derivative, Position, Tangent
from .curves import Dragger, PreparedConstraints, constrain, drag_point
from .fairing import FairResult, fair_surface
from .linalg import ConstraintError, ConvergenceError
from .match_inside import match_along
from .match_targets import MatchTarget
from .matching import MatchResult, match_surface
from .surfaces import drag_surface_point

__all__ = [
    "Curvature",
    "Derivative",
    "Position",
    "Tangent",
    "Dragger",
    "PreparedConstraints",
    "constrain",
    "drag_point",
    "drag_surface_point",
    "match_surface",
    "match_along",
    "fair_surface",
    "FairResult",
    "MatchResult",
    "MatchTarget",
    "ConstraintError",
    "ConvergenceError",
]
