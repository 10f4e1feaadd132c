"""Code shared by the frozen spline values: serialisation, equality and affine maps.

:class:`ControlPointValue` is a mixin for the frozen dataclasses that are defined by a few header
values (a degree and knots, or a number of sides and a depth), control points and optional
weights: :class:`~.curve.BSplineCurve`, :class:`~.surface.BSplineSurface` and
:class:`~occsurf.algorithms.topology.spatch.SPatch`. It writes :meth:`~ControlPointValue.to_dict`,
:meth:`~ControlPointValue.from_dict`, :meth:`~ControlPointValue.transform` and ``==`` once, driven
by the class attributes ``_DICT_TYPE`` and ``_HEADER``.

The dict format (version :data:`FORMAT_VERSION`) is, in this key order::

    {"type": _DICT_TYPE, "version": 1, <header fields>, "control_points": [...], "weights": [...] | None}

with floats as Python floats (``json`` writes them so that they read back exactly).
"""

from __future__ import annotations

import operator
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, ClassVar, TypeVar

import numpy as np
from numpy.typing import ArrayLike

from .. import _validate as V
from ..errors import InvalidGeometryError

__all__ = ["FORMAT_VERSION", "Codec", "SCALAR", "PAIR", "ARRAY", "ARRAY_PAIR", "ControlPointValue"]

#: Version of the dict format written by :meth:`ControlPointValue.to_dict`; every version up to it loads.
FORMAT_VERSION = 1

_T = TypeVar("_T", bound="ControlPointValue")


@dataclass(frozen=True)
class Codec:
    """How one header attribute is written to a dict, read back and compared.

    Attributes
    ----------
    encode : callable
        Attribute value -> JSON-safe value.
    decode : callable
        JSON value -> the constructor's argument (validated by the constructor).
    equal : callable
        ``equal(a, b) -> bool`` on two attribute values (exact).
    """

    encode: Callable[[Any], Any]
    decode: Callable[[Any], Any]
    equal: Callable[[Any, Any], bool]


def _identity(x: Any) -> Any:
    return x


def _tolist(a: np.ndarray) -> Any:
    return a.tolist()


def _tolists(arrays: tuple[np.ndarray, ...]) -> list[Any]:
    return [a.tolist() for a in arrays]


def _arrays_equal(a: tuple[np.ndarray, ...], b: tuple[np.ndarray, ...]) -> bool:
    return all(np.array_equal(x, y) for x, y in zip(a, b))


#: An ``int`` (a curve's degree, an S-patch's sides or depth).
SCALAR = Codec(_identity, _identity, operator.eq)
#: A pair of ints (a surface's degrees): a list in the dict, a tuple for the constructor.
PAIR = Codec(list, tuple, operator.eq)
#: A float array (a curve's knot vector): a (nested) list in the dict.
ARRAY = Codec(_tolist, _identity, np.array_equal)
#: A pair of float arrays (a surface's knot vectors): a list of two lists in the dict.
ARRAY_PAIR = Codec(_tolists, tuple, _arrays_equal)


class ControlPointValue:
    """Mixin: ``to_dict``, ``from_dict``, ``transform`` and ``==`` of a frozen spline value.

    A subclass (a frozen dataclass with ``eq=False``) declares

    - ``_DICT_TYPE``: the ``"type"`` written to and required from a dict;
    - ``_HEADER``: ``(attribute, codec)`` pairs naming the constructor's leading arguments, in
      order; ``control_points`` and ``weights`` follow them;

    and provides ``control_points``, ``weights`` (or ``None``), ``dim`` and a classmethod
    ``_trusted(*header, control_points, weights)`` that builds a value without validation.
    Values are not hashable (their arrays are compared by value).
    """

    _DICT_TYPE: ClassVar[str]
    _HEADER: ClassVar[tuple[tuple[str, Codec], ...]]

    def _header(self) -> tuple[Any, ...]:
        """The header attributes, in constructor order."""
        return tuple(getattr(self, name) for name, _ in self._HEADER)

    def transform(self: _T, matrix: ArrayLike, translation: ArrayLike | None = None) -> _T:
        """Apply the affine map ``x -> M x + b`` to the control points (affine invariance).

        B-splines, NURBS and S-patches are affinely invariant: the mapped value is the one with
        mapped control points. Weights are kept.

        Parameters
        ----------
        matrix : array_like, shape (d, d)
            ``M``, with ``d`` the dimension of the control points.
        translation : array_like, shape (d,), optional
            ``b``; default zero.

        Returns
        -------
        Same type as ``self``.

        Raises
        ------
        InvalidGeometryError
            ``matrix`` or ``translation`` of the wrong shape or not finite.
        """
        M, b = V.affine_map(matrix, translation, self.dim)  # type: ignore[attr-defined]
        P = self.control_points @ M.T + b  # type: ignore[attr-defined]
        w = self.weights  # type: ignore[attr-defined]
        return self._trusted(*self._header(), P, None if w is None else w.copy())  # type: ignore[attr-defined]

    def to_dict(self) -> dict[str, Any]:
        """JSON-safe dict (lists of Python floats: ``json`` writes and reads them back exactly).

        Control points keep the order and nesting of ``control_points``; see :mod:`._common`
        for the format.
        """
        out: dict[str, Any] = {"type": self._DICT_TYPE, "version": FORMAT_VERSION}
        for name, codec in self._HEADER:
            out[name] = codec.encode(getattr(self, name))
        w = self.weights  # type: ignore[attr-defined]
        out["control_points"] = self.control_points.tolist()  # type: ignore[attr-defined]
        out["weights"] = None if w is None else w.tolist()
        return out

    @classmethod
    def from_dict(cls: type[_T], data: dict[str, Any]) -> _T:
        """Inverse of :meth:`to_dict`, validated by the constructor.

        Raises
        ------
        InvalidGeometryError
            ``data`` is not a dict of this type, its version is newer than :data:`FORMAT_VERSION`,
            a key is missing, or the constructor rejects a value.
        """
        kind = cls._DICT_TYPE
        if not isinstance(data, dict) or data.get("type") != kind:
            raise InvalidGeometryError(f"from_dict: expected a dict with type '{kind}', got {type(data).__name__}")
        if data.get("version", 1) > FORMAT_VERSION:
            raise InvalidGeometryError(f"from_dict: format version {data['version']} is newer than {FORMAT_VERSION}")
        try:
            header = [codec.decode(data[name]) for name, codec in cls._HEADER]
            return cls(*header, data["control_points"], data.get("weights"))  # type: ignore[call-arg]
        except KeyError as err:
            raise InvalidGeometryError(f"from_dict: missing key {err}") from err

    def __eq__(self, other: object) -> bool:
        """Exact equality of the header, the control points and the weights."""
        if not isinstance(other, ControlPointValue) or other._DICT_TYPE != self._DICT_TYPE:
            return NotImplemented
        w, wo = self.weights, other.weights  # type: ignore[attr-defined]
        return (
            all(codec.equal(getattr(self, name), getattr(other, name)) for name, codec in self._HEADER)
            and np.array_equal(self.control_points, other.control_points)  # type: ignore[attr-defined]
            and (w is None) == (wo is None)
            and (w is None or np.array_equal(w, wo))
        )

    __hash__ = None  # type: ignore[assignment]
