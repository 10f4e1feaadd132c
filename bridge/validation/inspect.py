"""Inspect an imported model face by face: what each face is, and our evaluation against OCC's.

:func:`inspect_model` takes an :class:`~occsurf.bridge.exchange.step_iges.ImportedModel` (from
:func:`~occsurf.bridge.exchange.step_iges.read_step` or ``read_iges``) and returns one
:class:`FaceReport` per face: the surface type, degrees, poles, rational and periodic flags, OCC's
continuity class and the largest distance between our evaluation of the converted surface and
OCC's evaluation of the original one on an ``N x N`` grid, relative to the diagonal of the sampled
points' bounding box (:func:`~occsurf.bridge.validation.deviation.surface_deviation`,
``max_point_rel``). ``occsurf inspect`` prints these reports.

The deviation is measured for free-form faces only (B-spline and Bézier, :data:`FREE_FORM`):
their poles are the face's own data, so ours must reproduce OCC's surface to round-off. Analytic
faces (planes, cylinders, ...) convert to a different parametrisation; their reports leave the
spline fields ``None``.

Only the standard library is imported at module level (the command line reads
:class:`FaceReport` back from its worker process without loading NumPy or OCC); the deviation
module is loaded when a face is measured.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

from ..messages import error_line, one_line

if TYPE_CHECKING:
    from ..exchange.step_iges import ImportedFace, ImportedModel

__all__ = ["FaceReport", "inspect_model", "FREE_FORM", "DEFAULT_SAMPLES"]

#: Surface types whose poles are the face's own data (the deviation is measured only for these).
FREE_FORM: tuple[str, ...] = ("BSplineSurface", "BezierSurface")
#: Default grid size ``N`` of the deviation check (``N x N`` points per face).
DEFAULT_SAMPLES: int = 25


@dataclass(frozen=True)
class FaceReport:
    """One face as :func:`inspect_model` reports it (JSON-safe values only).

    Attributes
    ----------
    index : int
        The face's :attr:`ImportedFace.index` (``TopExp_Explorer`` order).
    name : str or None
        The name the file carries for the face (or its product), ``None`` if none.
    surface_type : str
        ``'BSplineSurface'``, ``'BezierSurface'``, ``'Plane'``, ... as :attr:`ImportedFace.surface_type`.
    degree : (int, int) or None
        ``(p, q)`` of a free-form face; ``None`` for analytic faces and unconverted ones.
    poles : (int, int) or None
        Number of poles ``(n_u, n_v)``, likewise.
    rational : bool or None
        Likewise.
    periodic : (bool, bool)
        OCC's ``IsUPeriodic``, ``IsVPeriodic``.
    continuity : str or None
        OCC's continuity class (``'C0'`` ... ``'CN'``); ``None`` only if the face could not be
        inspected at all (``error`` says why).
    max_deviation : float or None
        ``max |S_ours - S_occ|`` over the grid, relative to the bounding-box diagonal; ``None``
        for analytic faces, and when it could not be measured (``error`` says why).
    max_d1_deviation, max_d2_deviation : float or None
        The same for first and second partial derivatives (relative, see
        :class:`~occsurf.bridge.validation.deviation.SurfaceDeviation`).
    max_normal_angle : float or None
        Largest angle between our normal and OCC's, radians.
    error : str or None
        Why the face did not convert, or why its deviation was not measured; one line.
    """

    index: int
    name: str | None
    surface_type: str
    degree: tuple[int, int] | None
    poles: tuple[int, int] | None
    rational: bool | None
    periodic: tuple[bool, bool]
    continuity: str | None
    max_deviation: float | None
    max_d1_deviation: float | None = None
    max_d2_deviation: float | None = None
    max_normal_angle: float | None = None
    error: str | None = None

    @property
    def free_form(self) -> bool:
        """True for B-spline and Bézier faces (:data:`FREE_FORM`)."""
        return self.surface_type in FREE_FORM

    def to_json(self) -> dict[str, Any]:
        """The fields as a dict of JSON values (pairs as lists), in declaration order."""
        return {
            "index": self.index,
            "name": self.name,
            "surface_type": self.surface_type,
            "degree": None if self.degree is None else list(self.degree),
            "poles": None if self.poles is None else list(self.poles),
            "rational": self.rational,
            "periodic": list(self.periodic),
            "continuity": self.continuity,
            "max_deviation": self.max_deviation,
            "max_d1_deviation": self.max_d1_deviation,
            "max_d2_deviation": self.max_d2_deviation,
            "max_normal_angle": self.max_normal_angle,
            "error": self.error,
        }

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> FaceReport:
        """The inverse of :meth:`to_json` (unknown keys are ignored)."""

        def pair(x: Any) -> Any:
            return None if x is None else tuple(x)

        return cls(
            index=data["index"], name=data.get("name"), surface_type=data["surface_type"],
            degree=pair(data.get("degree")), poles=pair(data.get("poles")), rational=data.get("rational"),
            periodic=tuple(data.get("periodic", (False, False))), continuity=data.get("continuity"),
            max_deviation=data.get("max_deviation"), max_d1_deviation=data.get("max_d1_deviation"),
            max_d2_deviation=data.get("max_d2_deviation"), max_normal_angle=data.get("max_normal_angle"),
            error=data.get("error"),
        )


def inspect_model(model: ImportedModel, samples: int = DEFAULT_SAMPLES) -> list[FaceReport]:
    """One :class:`FaceReport` per face of ``model``, with our evaluation checked against OCC's.

    Never raises for a bad face: a face that does not convert, or whose deviation cannot be
    measured, gets ``error`` set and the other faces are still reported.

    Parameters
    ----------
    model : ImportedModel, or a build123d / cadquery / OCC shape
        From :func:`~occsurf.bridge.exchange.step_iges.read_step` or ``read_iges``; any other object
        :func:`~occsurf.bridge.exchange.object_import.as_model` accepts (a Solid, Shell, Compound, Face...).
    samples : int, default 25
        Grid size ``N`` of the deviation check (``N x N`` parameters per free-form face), >= 2.

    Returns
    -------
    list of FaceReport
        In the order of ``model.faces``.

    Raises
    ------
    InvalidGeometryError
        ``samples`` is not an integer >= 2.

    Examples
    --------
    >>> from occsurf.bridge import read_step, inspect_model          # doctest: +SKIP
    >>> [r.max_deviation for r in inspect_model(read_step("loft.step"), samples=11)]  # doctest: +SKIP
    [2.3e-16, ...]
    """
    n = _check_samples(samples)
    from ..exchange.object_import import as_model  # not at module level: the CLI reads FaceReport without OCC

    return [_inspect_face_guarded(face, n) for face in as_model(model).faces]


def _check_samples(samples: Any) -> int:
    if isinstance(samples, bool) or not isinstance(samples, numbers.Integral) or samples < 2:
        from occsurf.algorithms.errors import InvalidGeometryError

        raise InvalidGeometryError(f"samples: expected an integer >= 2, got {samples!r}")
    return int(samples)


def _finite_or_none(x: float | None) -> float | None:
    if x is None:
        return None
    x = float(x)
    return x if math.isfinite(x) else None


def _inspect_face_guarded(face: ImportedFace, samples: int) -> FaceReport:
    """:func:`_inspect_face`, or a report carrying the error: one bad face must not hide the others."""
    try:
        return _inspect_face(face, samples)
    except Exception as err:  # noqa: BLE001
        return FaceReport(index=face.index, name=None, surface_type=face.surface_type, degree=None, poles=None,
                          rational=None, periodic=(False, False), continuity=None, max_deviation=None,
                          error=error_line(err))


def _inspect_face(face: ImportedFace, samples: int) -> FaceReport:
    """The report of one face: its own fields, then (free-form faces) the deviation from OCC's."""
    error = None if face.error is None else one_line(face.error)
    common = FaceReport(index=face.index, name=face.name or None, surface_type=face.surface_type, degree=None,
                        poles=None, rational=None, periodic=(face.u_periodic, face.v_periodic),
                        continuity=face.continuity, max_deviation=None, error=error)
    if face.surface_type not in FREE_FORM:  # analytic or derived: no poles of its own, nothing exact to compare
        return common
    surf = face.surface
    if surf is None:
        return replace(common, error=error or "the free-form face was not converted")
    spline = replace(common, degree=(int(surf.degree[0]), int(surf.degree[1])),
                     poles=(int(surf.n_poles[0]), int(surf.n_poles[1])), rational=bool(surf.is_rational))
    try:
        from . import deviation  # looked up at call time: the module's function, not a copy

        dev = deviation.surface_deviation(surf, face.occ_surface, samples=samples)
    except Exception as err:  # noqa: BLE001 - one bad face must not hide the others
        return replace(spline, error=f"deviation not measured: {error_line(err)}")
    max_deviation = _finite_or_none(dev.max_point_rel)
    if max_deviation is None and error is None:
        error = "the deviation is not finite"
    return replace(spline, max_deviation=max_deviation, max_d1_deviation=_finite_or_none(dev.max_d1_rel),
                   max_d2_deviation=_finite_or_none(dev.max_d2_rel),
                   max_normal_angle=_finite_or_none(dev.max_normal_angle), error=error)
