"""The one exception hierarchy of occsurf.

Every error that occsurf raises on purpose derives from :class:`OccsurfError`, so a caller can catch
all of them at once, or catch the narrower class it cares about. The classes also derive from the
built-in exception a Python user would reach for first (``ValueError`` for bad input, ``OSError``
for files), so ``except ValueError`` keeps working in code that does not know occsurf.

This module is pure Python: ``occsurf.bridge`` raises the same classes, so ``occsurf.algorithms`` and ``occsurf.bridge``
share one hierarchy without ``occsurf.algorithms`` importing anything from OCC.

::

    OccsurfError
    ├── InvalidGeometryError (ValueError)    bad knots, shapes, weights, degrees, NaN
    │   ├── ParameterError                   a parameter outside the domain
    │   ├── UnknownNameError (KeyError)      a name that is none of the known ones (a tolerance)
    │   └── ArgumentTypeError (TypeError)    an argument of the wrong type
    ├── ToleranceError (ValueError)          an operation impossible within the tolerance asked
    ├── KernelError (RuntimeError)           OCC refused or failed (raised by bridge only)
    └── ExchangeError (OSError)              STEP/IGES read or write failed
"""

from __future__ import annotations

__all__ = [
    "OccsurfError",
    "InvalidGeometryError",
    "ParameterError",
    "UnknownNameError",
    "ArgumentTypeError",
    "ToleranceError",
    "KernelError",
    "ExchangeError",
]


class OccsurfError(Exception):
    """Base class of every error raised by occsurf."""


class InvalidGeometryError(OccsurfError, ValueError):
    """A spline's data is not valid: knot vector, shape, weights, degree or non-finite values.

    The message names the argument, what was expected and what was received.
    """


class ParameterError(InvalidGeometryError):
    """A parameter lies outside the domain of the curve or surface, or is not finite."""


class UnknownNameError(InvalidGeometryError, KeyError):
    """A name that is none of the known ones (``tolerances.override(NOPE=1.0)``); the message lists them.

    Also a ``KeyError``, as a lookup of an unknown key is; shown as its message (``KeyError`` alone
    would quote it).
    """

    __str__ = Exception.__str__


class ArgumentTypeError(InvalidGeometryError, TypeError):
    """An argument of the wrong type (a string where a number is expected); also a ``TypeError``."""


class ToleranceError(OccsurfError, ValueError):
    """An operation cannot be done within the requested tolerance (e.g. knot removal).

    The object the operation was applied to is never modified; the message states the deviation
    that would have been needed.
    """


class KernelError(OccsurfError, RuntimeError):
    """OpenCascade refused an operation or failed inside it (raised by ``bridge`` only)."""


class ExchangeError(OccsurfError, OSError):
    """A STEP or IGES file could not be read or written: missing, empty, truncated, garbage or
    unwritable. A failed write never leaves a partial file behind."""
