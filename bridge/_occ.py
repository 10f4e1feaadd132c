"""Small shared OCP helpers: message printers, TCol arrays, knots + multiplicities, kernel limits.

Everything in ``bridge`` that builds an OCC array, converts a knot vector or wraps an OCC exception
goes through this module, so each of those conversions exists exactly once.

* NumPy ⇄ ``TColStd``/``TColgp`` arrays (OCC arrays are 1-based, bounds-checked and have no list
  constructor, see ``shared/OCP_NOTES.md`` §0). Values are copied as Python floats, so nothing is
  rounded: the transfer is bit-exact both ways.
* The full knot vector with repeats (ours) ⇄ OCC's distinct knots + multiplicities. The split uses
  ``np.unique(..., return_counts=True)``: exact equality, no tolerance merging, the same as
  ``BSplCLib::Knots``. Two knots that differ in the last bit stay two knots (and OCC may then refuse
  them, see :func:`knots_to_occ`).
* Kernel limits checked *before* calling OCC, so the user gets an :class:`InvalidGeometryError`
  naming the argument instead of an OCC ``Standard_ConstructionError``.
* :func:`kernel_errors` turns any exception raised inside OCC into :class:`KernelError`
  (``raise ... from err``).
* :func:`quiet_messages` keeps OCC's translator banners off stdout *during* a bridge call and gives
  every default message printer its caller's trace level back afterwards (importing the bridge, or
  calling it, never changes a printer's level for the rest of the process). :func:`silence_messages`
  is the explicit, process-wide alternative for scripts that want OCC quiet everywhere.
"""

from __future__ import annotations

import contextlib
import threading
from collections.abc import Iterator
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from OCP.Geom import Geom_BSplineCurve
from OCP.gp import gp_Pnt
from OCP.Message import Message, Message_Gravity
from OCP.TColgp import TColgp_Array1OfPnt, TColgp_Array2OfPnt
from OCP.TColStd import TColStd_Array1OfInteger, TColStd_Array1OfReal, TColStd_Array2OfReal

from occsurf.algorithms.errors import InvalidGeometryError, KernelError

__all__ = [
    "MAX_DEGREE",
    "quiet_messages",
    "silence_messages",
    "real_array",
    "int_array",
    "real_array2",
    "pnt_array",
    "pnt_array2",
    "from_real_array",
    "from_int_array",
    "from_real_array2",
    "from_pnt_array",
    "from_pnt_array2",
    "check_degree",
    "knots_to_occ",
    "knots_from_occ",
    "kernel_errors",
    "is_occ_exception",
]

Array = NDArray[np.float64]

#: OCC's degree limit (``Geom_BSplineCurve::MaxDegree()``, the same for surfaces): 25.
MAX_DEGREE: int = int(Geom_BSplineCurve.MaxDegree_s())


# ---------------------------------------------------------------------------------------- messages
def silence_messages() -> None:
    """Lower every default message printer to ``Message_Fail`` for the rest of the process.

    An explicit, process-wide choice for scripts and benchmarks (OCP_NOTES §0): OCC's STEP/IGES
    translators and some algorithms print statistics banners on stdout; after this only failures
    are printed, inside and outside occsurf. The bridge itself never calls it: it uses
    :func:`quiet_messages`, which restores the caller's levels.
    """
    for printer in Message.DefaultMessenger_s().Printers():
        printer.SetTraceLevel(Message_Gravity.Message_Fail)


_QUIET_LOCK = threading.Lock()
_quiet_depth = 0
_quiet_saved: list[tuple[Any, Any]] = []  # (OCC Message_Printer, Message_Gravity)


@contextlib.contextmanager
def quiet_messages() -> Iterator[None]:
    """Only failures reach OCC's default message printers inside the block; afterwards every printer
    has exactly the trace level it had before.

    Used around each bridge call that runs OCC code which prints (the STEP/IGES translators through
    :func:`occsurf.bridge.exchange.occ_io.statics`, hole filling, sewing). Usable as a decorator.
    Nests, and is safe across threads: the levels are saved by the first block entered and restored
    when the last one is left, so concurrent calls never leave a lowered level behind. A printer
    the caller set to ``Message_Fail`` (or added) stays as the caller set it.

    Examples
    --------
    >>> from OCP.Message import Message, Message_Gravity                     # doctest: +SKIP
    >>> printer = Message.DefaultMessenger_s().Printers().First()            # doctest: +SKIP
    >>> printer.SetTraceLevel(Message_Gravity.Message_Trace)                 # doctest: +SKIP
    >>> occsurf.bridge.read_step("part.step"); printer.GetTraceLevel()       # doctest: +SKIP
    <Message_Gravity.Message_Trace: 0>
    """
    global _quiet_depth
    with _QUIET_LOCK:
        if _quiet_depth == 0:
            _quiet_saved[:] = [(p, p.GetTraceLevel()) for p in Message.DefaultMessenger_s().Printers()]
            for printer, level in _quiet_saved:
                if int(level.value) < int(Message_Gravity.Message_Fail.value):
                    printer.SetTraceLevel(Message_Gravity.Message_Fail)
        _quiet_depth += 1
    try:
        yield
    finally:
        with _QUIET_LOCK:
            _quiet_depth -= 1
            if _quiet_depth == 0:
                for printer, level in _quiet_saved:
                    printer.SetTraceLevel(level)
                _quiet_saved.clear()


# ---------------------------------------------------------------------------------------- errors
def is_occ_exception(err: BaseException) -> bool:
    """True for an exception raised inside OCC (``OCP.Standard.Standard_ConstructionError``, ...).

    OCP's exception classes all derive directly from :class:`Exception` (there is no common
    ``Standard_Failure`` base on the Python side), so they are recognised by their module.
    """
    return type(err).__module__.startswith("OCP")


@contextlib.contextmanager
def kernel_errors(action: str) -> Iterator[None]:
    """Re-raise any OCC exception raised in the block as :class:`KernelError`.

    Parameters
    ----------
    action : str
        What was being done, for the message (``"building Geom_BSplineCurve"``).

    Raises
    ------
    KernelError
        ``from`` the original OCC exception. Other exceptions pass through unchanged.
    """
    try:
        yield
    except Exception as err:  # noqa: BLE001 - filtered just below
        if not is_occ_exception(err):
            raise
        raise KernelError(f"{action}: OpenCascade raised {type(err).__name__}: {err}") from err


# ---------------------------------------------------------------------------------------- arrays
def real_array(values: ArrayLike) -> TColStd_Array1OfReal:
    """``TColStd_Array1OfReal(1, n)`` holding ``values`` (shape ``(n,)``), bit-exact."""
    v = np.asarray(values, dtype=float).reshape(-1)
    arr = TColStd_Array1OfReal(1, v.shape[0])
    for i, x in enumerate(v.tolist(), 1):
        arr.SetValue(i, x)
    return arr


def int_array(values: ArrayLike) -> TColStd_Array1OfInteger:
    """``TColStd_Array1OfInteger(1, n)`` holding ``values`` (shape ``(n,)``)."""
    v = np.asarray(values).reshape(-1)
    arr = TColStd_Array1OfInteger(1, v.shape[0])
    for i, x in enumerate(v.tolist(), 1):
        arr.SetValue(i, int(x))
    return arr


def real_array2(values: ArrayLike) -> TColStd_Array2OfReal:
    """``TColStd_Array2OfReal(1, nu, 1, nv)`` from shape ``(nu, nv)``; rows are the first index (u)."""
    w = np.asarray(values, dtype=float)
    nu, nv = w.shape
    arr = TColStd_Array2OfReal(1, nu, 1, nv)
    rows = w.tolist()
    for i in range(nu):
        row = rows[i]
        for j in range(nv):
            arr.SetValue(i + 1, j + 1, row[j])
    return arr


def pnt_array(points: ArrayLike) -> TColgp_Array1OfPnt:
    """``TColgp_Array1OfPnt(1, n)`` from shape ``(n, 3)``, bit-exact."""
    P = np.asarray(points, dtype=float)
    arr = TColgp_Array1OfPnt(1, P.shape[0])
    for i, (x, y, z) in enumerate(P.tolist(), 1):
        arr.SetValue(i, gp_Pnt(x, y, z))
    return arr


def pnt_array2(points: ArrayLike) -> TColgp_Array2OfPnt:
    """``TColgp_Array2OfPnt(1, nu, 1, nv)`` from shape ``(nu, nv, 3)``; rows are u (OCC's pole rows)."""
    P = np.asarray(points, dtype=float)
    nu, nv = P.shape[:2]
    arr = TColgp_Array2OfPnt(1, nu, 1, nv)
    rows = P.tolist()
    for i in range(nu):
        row = rows[i]
        for j in range(nv):
            x, y, z = row[j]
            arr.SetValue(i + 1, j + 1, gp_Pnt(x, y, z))
    return arr


def from_real_array(arr: Any) -> Array:
    """A 1-D OCC real array (``Array1``/``HArray1``, any lower bound) as an ndarray ``(n,)``."""
    return np.array([arr.Value(i) for i in range(arr.Lower(), arr.Upper() + 1)], dtype=float)


def from_int_array(arr: Any) -> NDArray[np.intp]:
    """A 1-D OCC integer array as an ndarray ``(n,)``."""
    return np.array([arr.Value(i) for i in range(arr.Lower(), arr.Upper() + 1)], dtype=np.intp)


def from_real_array2(arr: Any) -> Array:
    """A 2-D OCC real array as an ndarray ``(rows, cols)``."""
    r0, r1, c0, c1 = arr.LowerRow(), arr.UpperRow(), arr.LowerCol(), arr.UpperCol()
    return np.array([[arr.Value(i, j) for j in range(c0, c1 + 1)] for i in range(r0, r1 + 1)], dtype=float)


def from_pnt_array(arr: Any) -> Array:
    """A 1-D OCC point array as an ndarray ``(n, 3)``."""
    return np.array([arr.Value(i).Coord() for i in range(arr.Lower(), arr.Upper() + 1)], dtype=float)


def from_pnt_array2(arr: Any) -> Array:
    """A 2-D OCC point array as an ndarray ``(rows, cols, 3)``."""
    r0, r1, c0, c1 = arr.LowerRow(), arr.UpperRow(), arr.LowerCol(), arr.UpperCol()
    return np.array([[arr.Value(i, j).Coord() for j in range(c0, c1 + 1)] for i in range(r0, r1 + 1)],
                    dtype=float)


# ---------------------------------------------------------------------------------------- knots
def check_degree(degree: int, name: str = "degree") -> int:
    """The degree as an int, if OCC accepts it (1 to :data:`MAX_DEGREE`).

    Raises
    ------
    InvalidGeometryError
        Naming ``name``; e.g. a degree-30 spline built with ``BSplineCurve._trusted``.
    """
    d = int(degree)
    if not 1 <= d <= MAX_DEGREE:
        raise InvalidGeometryError(f"{name}: OpenCascade accepts degrees 1 to {MAX_DEGREE}, got {d}")
    return d


def knots_to_occ(knots: ArrayLike, degree: int, name: str = "knots") -> tuple[TColStd_Array1OfReal, TColStd_Array1OfInteger]:
    """Split a full knot vector into OCC's distinct knots and multiplicities (non-periodic).

    The split is exact (``np.unique``); no knots are merged. The two checks below are OCC's own
    ``CheckCurveData``/``CheckSurfaceData`` rules, done first so the error names the knot.

    Parameters
    ----------
    knots : array_like, shape (n + degree + 1,)
        Full non-decreasing knot vector with repeats.
    degree : int
    name : str
        Argument name for messages (``"knots[0] (U)"``).

    Returns
    -------
    occ_knots : TColStd_Array1OfReal, length k
    occ_mults : TColStd_Array1OfInteger, length k

    Raises
    ------
    InvalidGeometryError
        Knots decreasing or not finite (only possible through ``_trusted``). An interior distinct knot (neither the first nor the last value of the vector) has
        multiplicity above ``degree``: OCC allows ``degree + 1`` only at the ends of a non-periodic
        spline. Or two distinct knots are closer than OCC's ``Epsilon(|k|)`` (one unit in the last
        place), which OCC refuses as "Knots interval values too close".
    """
    t = np.asarray(knots, dtype=float)
    if not np.all(np.isfinite(t)):
        raise InvalidGeometryError(f"{name}: expected finite knots, got {float(t[~np.isfinite(t)][0])!r}")
    d = np.diff(t)
    if np.any(d < 0):
        i = int(np.argmax(d < 0))
        raise InvalidGeometryError(f"{name}: expected non-decreasing knots, got {float(t[i])!r} then {float(t[i + 1])!r}")
    vals, mults = np.unique(t, return_counts=True)
    interior = mults[1:-1]
    if np.any(interior > degree):
        i = int(np.argmax(interior > degree)) + 1
        raise InvalidGeometryError(
            f"{name}: interior knot {float(vals[i])!r} has multiplicity {int(mults[i])}; OpenCascade allows at most "
            f"the degree {degree} inside a non-periodic knot vector (degree + 1 only at the ends)"
        )
    gaps = np.diff(vals)
    close = gaps <= np.spacing(np.abs(vals[:-1]))
    if np.any(close):
        i = int(np.argmax(close))
        raise InvalidGeometryError(
            f"{name}: knots {float(vals[i])!r} and {float(vals[i + 1])!r} are distinct but adjacent floats; "
            "OpenCascade refuses knots closer than Epsilon(|k|)"
        )
    return real_array(vals), int_array(mults)


def knots_from_occ(occ_knots: Any, occ_mults: Any) -> Array:
    """The full knot vector (shape ``(sum(mults),)``) from OCC's distinct knots and multiplicities.

    For a non-periodic spline this equals OCC's ``KnotSequence()``; periodic splines use
    ``KnotSequence()`` directly (see ``convert``).
    """
    return np.repeat(from_real_array(occ_knots), from_int_array(occ_mults))
