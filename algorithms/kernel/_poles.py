"""How spline values store their poles: Cartesian for users, homogeneous for the kernels (STYLE "Data").

:class:`HomogeneousPoles` is the storage shared by :class:`~.curve.BSplineCurve` and
:class:`~.surface.BSplineSurface`: read-only ``control_points`` (Cartesian, last axis the
coordinates) and ``weights`` (or ``None``), and the premultiplied net ``_hpoles`` (weight last)
that the evaluation kernels read (The NURBS Book, 2nd ed., §4.2).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .. import _validate as V
from .rational import from_homogeneous, to_homogeneous

Array = NDArray[np.float64]


class HomogeneousPoles:
    """Mixin of a frozen spline value whose header is ``(degree, knots)``: stores the poles in both
    forms and rebuilds values from homogeneous poles. The subclass provides ``_trusted(degree,
    knots, control_points, weights)``."""

    weights: Array | None

    def _set_poles(self, P: Array, w: Array | None) -> None:
        """Store ``control_points``, ``weights`` and the homogeneous ``_hpoles`` (read-only)."""
        object.__setattr__(self, "control_points", V.readonly(P))
        object.__setattr__(self, "weights", None if w is None else V.readonly(w))
        H = P if w is None else to_homogeneous(P, w)
        object.__setattr__(self, "_hpoles", V.readonly(H))

    def _kept(self, key: str, make: Callable[[], Any]) -> Any:
        """``make()``, a value derived from the spline alone (which never changes), made on first use
        and kept on it (the kernels' span tables: 77 us a time, 8128 times in a check of the bearing);
        left out of pickles (:meth:`__getstate__`)."""
        kept = self.__dict__.get("_derived")
        if kept is None:
            kept = {}
            object.__setattr__(self, "_derived", kept)
        if key not in kept:
            kept[key] = make()
        return kept[key]

    def __getstate__(self) -> dict[str, Any]:
        state = dict(self.__dict__)
        state.pop("_derived", None)  # made again on first use: a pickle stays the size of the spline
        return state

    @property
    def is_rational(self) -> bool:
        return self.weights is not None

    @classmethod
    def _from_homogeneous(cls, degree: Any, knots: Any, hpoles: Array, rational: bool) -> Any:
        """The value with homogeneous poles ``hpoles`` (weight last when ``rational``), unchecked."""
        if rational:
            P, w = from_homogeneous(hpoles)
            return cls._trusted(degree, knots, P, w)  # type: ignore[attr-defined]
        return cls._trusted(degree, knots, hpoles)  # type: ignore[attr-defined]
