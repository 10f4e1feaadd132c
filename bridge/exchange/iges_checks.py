"""Reading checks of IGES files before OCC parses them (no OCC here: NumPy and SciPy only), as
:mod:`.checks` does for STEP files.

:func:`scan_iges` checks the Directory and Parameter sections of an IGES file: every entity's parameter
lines exist and start with the entity type of its directory entry (swapped type fields made OCC's reader
hang until the time-out), the pointer fields form no cycle, and the B-spline curves (126) and surfaces (128)
have non-negative upper indices, positive degrees and as many parameters as their counts imply (a negative
upper index crashes OCC's reader). What OCC reports after reading is in :mod:`.read_warnings`.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from occsurf.algorithms.errors import ExchangeError

from .checks import largest_cycle

__all__ = ["IgesScan", "scan_iges", "IGES_SURFACE_TYPES", "IGES_CLOSED_SHELL_FORM"]

#: IGES surfaces that OCC makes a face of when they stand alone (not physically dependent).
IGES_SURFACE_TYPES = frozenset({114, 118, 120, 122, 128, 140, 190, 192, 194, 196, 198})


#: Form number of a closed shell entity (514); form 2 is an open shell (IGES 5.3, section 4.151).
IGES_CLOSED_SHELL_FORM = 1


@dataclass
class IgesScan:
    """What :func:`scan_iges` found: ``warnings``, the number of entities per type, the number of
    faces the file describes (``face_instances``: faces 510, else trimmed or bounded surfaces 144/143
    and stand-alone surfaces that are not physically dependent) and the closed shells (``closed_shells``:
    the first directory line ``D<n>`` of every shell entity 514 of form 1)."""

    warnings: list[str] = field(default_factory=list)
    types: Counter[int] = field(default_factory=Counter)
    face_instances: int = 0
    closed_shells: list[int] = field(default_factory=list)


def _iges_numbers(text: str, delim: str, count: int) -> list[str]:
    return [t.strip() for t in text.split(delim)[:count]]


def scan_iges(p: Path, data: bytes) -> IgesScan:
    """Check the Directory and Parameter sections of a fixed-format IGES file (framing checked before).

    Raises
    ------
    ExchangeError
        A Directory entry whose parameter lines are missing, or a B-spline curve (126) or surface (128)
        with a negative upper index, a degree below 1 or fewer parameters than its counts imply.
    """
    lines = data.decode("latin-1").splitlines()
    by_sec: dict[str, list[str]] = {"S": [], "G": [], "D": [], "P": []}
    for line in lines:
        sec = line[72:73]
        if sec in by_sec:
            by_sec[sec].append(line)
    glob = "".join(x[:72] for x in by_sec["G"])
    delim = ","
    if glob[:2] == "1H" and len(glob) > 2:
        delim = glob[2]
    rec_end = ";"
    scan = IgesScan()
    loose = 0
    refs: list[tuple[int, int, int]] = []  # pointers (from D line, to D line, type) of _IGES_POINTERS' types
    axes: list[tuple[int, int]] = []  # surfaces of revolution 120: (D line, their axis's D line)
    d, par = by_sec["D"], by_sec["P"]
    for k in range(0, len(d) - 1, 2):
        a, b = d[k], d[k + 1]
        seq = 2 * (k // 2) + 1
        try:
            etype = int(a[0:8])
            ptr = int(a[8:16])
            nlines = int(b[24:32])
        except ValueError:
            raise ExchangeError(f"{p}: damaged IGES file (directory entry D{seq}: unreadable type or parameter "
                                "pointer)") from None
        scan.types[etype] += 1
        if etype == 514 and b[32:40].strip() == str(IGES_CLOSED_SHELL_FORM):
            scan.closed_shells.append(seq)
        dependent = a[66:68] in ("01", "03")  # physically dependent: part of another entity
        if etype in (143, 144) or (etype in IGES_SURFACE_TYPES and not dependent):
            loose += not dependent
        if ptr < 1 or nlines < 1 or ptr - 1 + nlines > len(par):
            raise ExchangeError(f"{p}: damaged IGES file (directory entry D{seq}, type {etype}: parameter lines "
                                f"{ptr}..{ptr + nlines - 1} not in the {len(par)} of the P section)")
        text = "".join(x[:64] for x in par[ptr - 1:ptr - 1 + nlines]).split(rec_end)[0]
        head = text.split(delim, 1)[0].strip()
        if head != str(etype):  # OCC parses the data as the directory's type: it hung on such files
            raise ExchangeError(f"{p}: damaged IGES file (directory entry D{seq} is of type {etype}, its parameter "
                                f"data P{ptr} of type {head or '(none)'!s})")
        if etype in _IGES_POINTERS:
            targets = _IGES_POINTERS[etype](_iges_numbers(text, delim, 10**6)[1:])
            refs.extend((seq, target, etype) for target in targets)
            if etype == 120:
                axes.append((seq, targets[0] if targets else 0))
        if etype not in (126, 128):
            continue
        fields = _iges_numbers(text, delim, 10**9)
        _check_bspline(p, seq, etype, fields)
    _iges_cycle_error(p, refs, len(d) // 2)
    _iges_axis_error(p, axes, d)
    scan.face_instances = scan.types[510] if scan.types[510] else loose
    return scan


def _ints(fields: list[str], a: int, b: int) -> list[int]:
    """``fields[a:b]`` as integers (a field that is not one ends the list: no pointers are read past it)."""
    out = []
    for x in fields[a:b]:
        try:
            out.append(int(x))
        except ValueError:
            break
    return out


def _count(fields: list[str], i: int) -> int:
    got = _ints(fields, i, i + 1)
    return max(0, min(got[0], len(fields))) if got else 0


def _boundary_curves(f: list[str]) -> list[int]:
    """141's model-space curves and their parameter-space curves: TYPE, PREF, SPTR, N, then per curve
    CRVPT, SENSE, K, PSCPT1..K."""
    out, i = _ints(f, 2, 3), 4
    for _ in range(_count(f, 3)):
        head = _ints(f, i, i + 3)
        if len(head) < 3:
            break
        k = max(0, min(head[2], len(f)))
        out += [head[0]] + _ints(f, i + 3, i + 3 + k)
        i += 3 + k
    return out


#: Per IGES entity type, the pointer fields of its parameter data (after the type number) by the IGES
#: 5.3 schema: the references a reader follows to build it. A cycle through them (a trimmed surface
#: whose base surface is itself, after one swapped pointer) sends OCC's transfer round it until its
#: stack overflows (SIGSEGV), so :func:`scan_iges` refuses it first.
_IGES_POINTERS: dict[int, Callable[[list[str]], list[int]]] = {
    102: lambda f: _ints(f, 1, 1 + _count(f, 0)),  # composite curve: N, its curves
    118: lambda f: _ints(f, 0, 2),  # ruled surface: its two curves
    120: lambda f: _ints(f, 0, 2),  # surface of revolution: axis, generatrix
    122: lambda f: _ints(f, 0, 1),  # tabulated cylinder: directrix
    140: lambda f: _ints(f, 4, 5),  # offset surface: NX, NY, NZ, D, the surface
    141: _boundary_curves,
    142: lambda f: _ints(f, 1, 4),  # curve on surface: CRTN, the surface, the parameter and model curves
    143: lambda f: _ints(f, 1, 2) + _ints(f, 3, 3 + _count(f, 2)),  # bounded surface: TYPE, surface, N, boundaries
    144: lambda f: _ints(f, 0, 1) + _ints(f, 3, 4 + _count(f, 2)),  # trimmed surface: surface, N1, N2, outer, inner
    510: lambda f: _ints(f, 0, 1) + _ints(f, 3, 3 + _count(f, 1)),  # face: surface, N, OF, its loops
}


def _iges_cycle_error(p: Path, refs: list[tuple[int, int, int]], n: int) -> None:
    """Refuse pointers (``refs``: from directory line, to directory line, the pointing entity's type)
    that form a cycle; pointers to no entry (0, or out of range) are left to the reader."""
    edges = [(a, b, t) for a, b, t in refs if b > 0 and b % 2 == 1 and (b - 1) // 2 < n]
    for a, b, t in edges:
        if a == b:
            raise ExchangeError(f"{p}: damaged IGES file (directory entry D{a}, type {t}, points to itself)")
    members = largest_cycle(n, np.array([(a - 1) // 2 for a, _, _ in edges], dtype=np.int64),
                             np.array([(b - 1) // 2 for _, b, _ in edges], dtype=np.int64))
    if members is None:
        return
    type_of = {(a - 1) // 2: t for a, _, t in edges}
    shown = ", ".join(f"D{2 * k + 1} type {type_of.get(int(k), '?')}" for k in members[:6]) + \
        (" ..." if len(members) > 6 else "")
    raise ExchangeError(f"{p}: damaged IGES file (a cycle of pointers through {len(members)} entities: {shown})")


def _iges_axis_error(p: Path, axes: list[tuple[int, int]], d: list[str]) -> None:
    """Refuse a surface of revolution (120) whose axis is not a line (110), as IGES 5.3 (section 4.18)
    requires: OCC's transfer takes the axis as a line unchecked and the reading process died of
    SIGSEGV where it was a composite curve, no entry (0) or a directory entry's second line (the
    mutation fuzz's ``swap`` 1, 8194 on a filleted box, CI of 2026-12-05)."""
    for seq, axis in axes:
        k = axis - 1
        kind = d[k][0:8].strip() if axis > 0 and axis % 2 == 1 and k < len(d) else None
        if kind != "110":
            what = f"D{axis}, of type {kind}" if kind else (f"D{axis}, not the start of a directory entry" if axis
                                                            else "none")
            raise ExchangeError(f"{p}: damaged IGES file (surface of revolution 120 at D{seq}: its axis is {what}; "
                                "it must be a line, type 110)")


def _check_bspline(p: Path, seq: int, etype: int, fields: list[str]) -> None:
    head = 7 if etype == 126 else 10  # the type, then 6 (126) or 9 (128) integers
    where = f"{p}: damaged IGES file (B-spline {'curve' if etype == 126 else 'surface'} {etype} at D{seq}"
    try:
        ints = [int(x) for x in fields[1:head]]
    except ValueError:
        raise ExchangeError(f"{where}: its counts are not integers)") from None
    if len(ints) < head - 1:
        raise ExchangeError(f"{where}: {len(fields)} parameters, too few)")
    if etype == 126:
        k, m = ints[0], ints[1]
        if k < 0 or m < 1 or k < m:
            raise ExchangeError(f"{where}: upper index K={k}, degree M={m}; need M >= 1 and K >= M)")
        need = 1 + 6 + (k + m + 2) + (k + 1) + 3 * (k + 1) + 2
    else:
        k1, k2, m1, m2 = ints[:4]
        if min(k1, k2) < 0 or min(m1, m2) < 1 or k1 < m1 or k2 < m2:
            raise ExchangeError(f"{where}: upper indices K1={k1}, K2={k2}, degrees M1={m1}, M2={m2}; need M >= 1 "
                                "and K >= M)")
        c = (k1 + 1) * (k2 + 1)
        need = 1 + 9 + (k1 + m1 + 2) + (k2 + m2 + 2) + 4 * c + 4
    if len(fields) < need:
        raise ExchangeError(f"{where}: {len(fields) - 1} parameters, its counts need {need - 1})")
