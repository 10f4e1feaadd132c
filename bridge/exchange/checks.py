"""Reading checks of :mod:`occsurf.bridge.exchange.step_iges`: what OCC's readers accept silently or die on.

Before OCC parses a file (no OCC here: NumPy and SciPy only)
--------------------------------------------------------------
:func:`scan_step` reads the DATA section of an ISO 10303-21 file as a graph of entity instances (strings
and comments masked first) and

* refuses, with :class:`ExchangeError` naming the entity, what crashes OCC's parser: parentheses nested
  deeper than :data:`MAX_NESTING` (100000 of them overflow its stack), unbalanced parentheses, and
  references that form a cycle (``#20 = ORIENTED_EDGE('',*,*,#20,.T.)``);
* refuses what crashes OCC's transfer although every reference has an acceptable type (found by swapping
  references of clean files, each case read in a child process): a ``PCURVE`` whose
  ``DEFINITIONAL_REPRESENTATION`` holds something else than a curve first (an edge, a vertex, a point:
  OCC casts it to a curve without checking), and a ``VERTEX_POINT`` on a ``CARTESIAN_POINT`` of fewer
  than 3 coordinates (a point of a 2-D p-curve);
* warns about B-spline curves and surfaces whose poles mix 2 and 3 coordinates (OCC reads them without a
  word: a 3-D point among a p-curve's poles);
* finds the references to instances the file does not define (a deleted line, a file cut at an entity
  boundary with its trailer put back). OCC would leave a null handle there and crash on transfer (or
  drop a face without a word), so the text OCC sees is *pruned*: a dangling reference inside a list is
  removed from the list, an instance with a dangling attribute is removed, and so on up the graph. Each
  removal is a warning; the partial model is read and reported as partial;
* counts the face instances (``ADVANCED_FACE``, ``FACE_SURFACE``) and notes the ``CLOSED_SHELL`` ones,
  which :func:`.read_warnings.model_warnings` compares with what OCC built.

:func:`~.iges_checks.scan_iges` (:mod:`.iges_checks`) does the same for IGES files.

After OCC has read the file: :mod:`.read_warnings`
--------------------------------------------------
:func:`~.read_warnings.occ_check_warnings` turns OCC's own check messages (``Interface_CheckTool``) into warnings: wrong
arity, a text where a real is expected (read as 0), more than 3 coordinates (cut to 3), a reference of
the wrong type. :func:`~.read_warnings.model_warnings` compares the model with the file: fewer faces than face instances,
and shells the file calls closed (STEP ``CLOSED_SHELL``, IGES shell 514 of form 1) that have free edges.

Warnings are one line each, prefixed by what they concern (``#16 CLOSED_SHELL: ...``); at most
:data:`MAX_WARNINGS_PER_KIND` of one kind are listed, then a count of the rest.
"""

from __future__ import annotations

import re
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from occsurf.algorithms.errors import ExchangeError

from .step_splines import spline_problems

__all__ = ["StepScan", "scan_step", "largest_cycle", "limited_lines", "MAX_NESTING", "MAX_WARNINGS_PER_KIND", "STEP_FACE_TYPES",
           "STEP_CURVE_TYPES"]

#: Deepest nesting of parentheses accepted in one STEP instance (real files nest 3 to 6 deep; OCC's
#: parser recurses per level and dies of a stack overflow long before 100000).
MAX_NESTING: int = 64
#: Warnings of one kind listed individually before the rest are counted in one line.
MAX_WARNINGS_PER_KIND: int = 10
#: STEP instance types that become one face each.
STEP_FACE_TYPES: tuple[str, ...] = ("ADVANCED_FACE", "FACE_SURFACE")

_MASK = re.compile(rb"'(?:[^']|'')*'|/\*.*?\*/", re.S)
_COORDS = re.compile(rb"CARTESIAN_POINT\s*\(\s*'[^']*'\s*,\s*\(([^()]*)\)")

#: STEP entity types that are curves (ISO 10303-42): what a p-curve's representation must hold.
STEP_CURVE_TYPES: frozenset[str] = frozenset({
    "CURVE", "LINE", "CONIC", "CIRCLE", "ELLIPSE", "PARABOLA", "HYPERBOLA", "BOUNDED_CURVE", "POLYLINE",
    "B_SPLINE_CURVE", "B_SPLINE_CURVE_WITH_KNOTS", "BEZIER_CURVE", "UNIFORM_CURVE", "QUASI_UNIFORM_CURVE",
    "RATIONAL_B_SPLINE_CURVE", "TRIMMED_CURVE", "COMPOSITE_CURVE", "COMPOSITE_CURVE_ON_SURFACE",
    "OFFSET_CURVE_2D", "OFFSET_CURVE_3D", "CURVE_REPLICA", "PCURVE", "SURFACE_CURVE", "SEAM_CURVE",
    "INTERSECTION_CURVE", "BOUNDED_PCURVE", "BOUNDED_SURFACE_CURVE",
})
_SPLINE_WORDS = (b"B_SPLINE_CURVE", b"B_SPLINE_SURFACE", b"BEZIER_CURVE", b"BEZIER_SURFACE")
_DEF = re.compile(rb"\s*#(\d+)\s*=\s*")
_REF = re.compile(rb"#(\d+)")
_TYPE = re.compile(rb"([A-Za-z_][A-Za-z0-9_]*)\s*\(")
_DATA = re.compile(rb"\bDATA\b\s*(?:\([^)]*\))?\s*;")
_END = re.compile(rb"END-ISO-10303-21\s*;")


def _masked(data: bytes) -> bytes:
    """``data`` with string contents replaced by ``_`` and comments by blanks: same length, same offsets."""
    def hide(m: re.Match[bytes]) -> bytes:
        s = m.group(0)
        return b"'" + b"_" * (len(s) - 2) + b"'" if s[:1] == b"'" else b" " * len(s)

    return _MASK.sub(hide, data)


def limited_lines(kind_lines: list[str], what: str) -> list[str]:
    """``kind_lines`` (warnings of one kind), the first :data:`MAX_WARNINGS_PER_KIND` of them and a
    count of the rest."""
    if len(kind_lines) <= MAX_WARNINGS_PER_KIND:
        return kind_lines
    rest = len(kind_lines) - MAX_WARNINGS_PER_KIND
    return kind_lines[:MAX_WARNINGS_PER_KIND] + [f"... and {rest} more {what}"]


# ---------------------------------------------------------------------------------------- STEP
@dataclass
class StepScan:
    """What :func:`scan_step` found.

    Attributes
    ----------
    data : bytes
        The text to give OCC: the file itself, or its pruned form when references dangle.
    warnings : list of str
    n_instances : int
    face_instances : int
        ``ADVANCED_FACE`` and ``FACE_SURFACE`` instances in ``data``.
    closed_shells : list of int
        Ids of the ``CLOSED_SHELL`` instances in ``data``.
    ids : list of int
        The instance ids of ``data`` in file order (OCC numbers the instances in this order).
    """

    data: bytes
    warnings: list[str] = field(default_factory=list)
    n_instances: int = 0
    face_instances: int = 0
    closed_shells: list[int] = field(default_factory=list)
    ids: list[int] = field(default_factory=list)


def _records(masked: bytes, start: int, stop: int) -> tuple[list[int], list[int], list[bytes]]:
    """``(starts, ends, texts)`` of the ``;``-terminated records of ``masked[start:stop]``."""
    region = masked[start:stop]
    semis = np.flatnonzero(np.frombuffer(region, np.uint8) == ord(";"))
    starts = np.concatenate([[0], semis[:-1] + 1]) if len(semis) else np.zeros(0, int)
    return ([start + int(a) for a in starts], [start + int(b) for b in semis],
            [region[a:b] for a, b in zip(starts.tolist(), semis.tolist())])


def _check_parentheses(p: Path, masked: bytes, start: int, stop: int, semis: list[int], ids_at: Any) -> None:
    region = np.frombuffer(masked, np.uint8)[start:stop]
    step = (region == ord("(")).astype(np.int32) - (region == ord(")")).astype(np.int32)
    depth = np.cumsum(step)
    if len(depth) == 0:
        return
    deepest = int(depth.max())
    if deepest > MAX_NESTING:
        at = int(np.argmax(depth > MAX_NESTING)) + start
        raise ExchangeError(f"{p}: damaged STEP file ({ids_at(at)}: parentheses nested {deepest} deep, more than "
                            f"{MAX_NESTING}; OCC's parser would overflow its stack)")
    at_semis = depth[np.asarray(semis, dtype=np.int64) - start] if semis else np.zeros(0, np.int32)
    bad = np.flatnonzero(at_semis != 0)
    if len(bad) or int(depth.min()) < 0:
        where = semis[int(bad[0])] if len(bad) else int(np.argmax(depth < 0)) + start
        raise ExchangeError(f"{p}: damaged STEP file ({ids_at(where)}: unbalanced parentheses)")


def largest_cycle(n: int, rows: np.ndarray, cols: np.ndarray) -> np.ndarray | None:
    """The nodes of the largest cycle of the directed graph ``rows[i] -> cols[i]`` on ``n`` nodes (its
    largest strongly connected component of two or more), or ``None`` when it has none."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    if n == 0 or len(rows) == 0:
        return None
    graph = coo_matrix((np.ones(len(rows), np.int8), (rows, cols)), shape=(n, n)).tocsr()
    n_comp, labels = connected_components(graph, directed=True, connection="strong")
    if n_comp == n:
        return None
    return np.flatnonzero(labels == int(np.argmax(np.bincount(labels))))


def _cycle_error(p: Path, ids: np.ndarray, rows: np.ndarray, cols: np.ndarray, types: list[str]) -> None:
    """Refuse a reference graph with a cycle (OCC's parser recurses round it until it dies)."""
    self_loops = rows[rows == cols]
    if len(self_loops):
        k = int(self_loops[0])
        raise ExchangeError(f"{p}: damaged STEP file (#{ids[k]} {types[k]} refers to itself)")
    members = largest_cycle(len(ids), rows, cols)
    if members is None:
        return
    shown = ", ".join(f"#{ids[k]} {types[k]}" for k in members[:6]) + (" ..." if len(members) > 6 else "")
    raise ExchangeError(f"{p}: damaged STEP file (a cycle of references through {len(members)} instances: "
                        f"{shown})")


def _entity_type(text: bytes, at: int) -> str:
    m = _TYPE.match(text, at)
    if m is not None:
        return m.group(1).decode("ascii").upper()
    return "complex instance" if text[at:at + 1] == b"(" else "?"


def scan_step(p: Path, data: bytes, broken: dict[int, str] | None = None) -> StepScan:
    """Check the DATA section of a STEP file and prune dangling references (see the module docstring).

    ``broken`` names instances to remove as well (id -> why), with the same propagation: those OCC's
    parser could not read (:func:`occ_broken_ids`: a reference of the wrong type leaves a null field
    that its transfer dereferences).

    Raises
    ------
    ExchangeError
        Parentheses nested too deep or unbalanced, a cycle of references, no DATA section.
    """
    masked = _masked(data)
    m = _DATA.search(masked)
    ends = list(_END.finditer(masked))
    end = ends[-1] if ends else None  # the last END-ISO-10303-21;
    if m is None or end is None:
        raise ExchangeError(f"{p}: damaged STEP file (no DATA section)")
    start, stop = m.end(), end.start()
    starts, semis, texts = _records(masked, start, stop)
    ids_list: list[int] = []
    rec_of: list[int] = []
    body_at: list[int] = []  # per instance: where its record's text after ``#id =`` starts
    types: list[str] = []
    for k, text in enumerate(texts):
        d = _DEF.match(text)
        if d is None:
            continue
        ids_list.append(int(d.group(1)))
        rec_of.append(k)
        body_at.append(d.end())
        types.append(_entity_type(text, d.end()))
    ids = np.asarray(ids_list, dtype=np.int64)

    def ids_at(offset: int) -> str:
        k = int(np.searchsorted(np.asarray(semis), offset))
        d = _DEF.match(texts[k]) if k < len(texts) else None
        return f"#{int(d.group(1))}" if d is not None else f"byte {offset}"

    _check_parentheses(p, masked, start, stop, semis, ids_at)
    scan = StepScan(data=data, n_instances=len(ids))
    counts = Counter(ids_list)
    dups = sorted(i for i, c in counts.items() if c > 1)
    if dups:
        scan.warnings += limited_lines([f"#{i}: defined {counts[i]} times (OCC keeps one)" for i in dups],
                                  "instances defined more than once")
    order = np.argsort(ids, kind="stable")
    sorted_ids = ids[order]
    refs_per = [[int(x) for x in _REF.findall(texts[rec_of[j]], body_at[j])] for j in range(len(ids))]
    lengths = np.fromiter((len(r) for r in refs_per), dtype=np.int64, count=len(refs_per))
    flat = np.fromiter((x for r in refs_per for x in r), dtype=np.int64, count=int(lengths.sum()))
    rows = np.repeat(np.arange(len(ids)), lengths)
    pos = np.searchsorted(sorted_ids, flat)
    pos_c = np.minimum(pos, max(len(ids) - 1, 0))
    found = (len(ids) > 0) & (sorted_ids[pos_c] == flat) if len(ids) else np.zeros(len(flat), bool)
    cols = order[pos_c[found]] if len(ids) else np.zeros(0, np.int64)
    _cycle_error(p, ids, rows[found], cols, types)
    scan.warnings += _transfer_crashes(p, ids_list, types, [texts[k] for k in rec_of], refs_per)
    scan.warnings += limited_lines(spline_problems(ids_list, types, [texts[k] for k in rec_of], body_at, refs_per),
                              "B-spline instances OCC cannot build")
    broken = {i: why for i, why in (broken or {}).items() if i in counts}
    if not found.all() or broken:
        scan.data, lines = _prune(data, starts, semis, rec_of, ids, types, refs_per,
                                  set(flat[~found].tolist()), broken)
        scan.warnings += lines
        kept = _kept_types(scan.data)
        scan.face_instances = sum(kept[t] for t in STEP_FACE_TYPES)
        scan.closed_shells = kept.closed_shells
        scan.ids = kept.ids
    else:
        scan.face_instances = sum(t in STEP_FACE_TYPES for t in types)
        scan.closed_shells = [int(ids[j]) for j, t in enumerate(types) if t == "CLOSED_SHELL"]
        scan.ids = ids_list
    return scan


def _transfer_crashes(p: Path, ids: list[int], types: list[str], texts: list[bytes],
                      refs_per: list[list[int]]) -> list[str]:
    """Refuse the structures that crash OCC's transfer (see the module docstring); return the warnings
    about poles of mixed dimension. ``texts`` are the masked records, one per instance."""
    at = {i: j for j, i in reversed(list(enumerate(ids)))}  # an id defined twice: its first record

    def coords(j: int) -> int | None:
        m = _COORDS.search(texts[j]) if types[j] == "CARTESIAN_POINT" else None
        return None if m is None else len([x for x in m.group(1).split(b",") if x.strip()])

    def dims_of(refs: list[int]) -> set[int]:
        """The numbers of coordinates of the points among ``refs``."""
        return {n for r in refs if (k := at.get(r)) is not None and (n := coords(k)) is not None}

    def is_curve(j: int) -> bool:
        if types[j] == "complex instance":
            return any(re.search(rb"\b" + t.encode() + rb"\s*\(", texts[j]) for t in STEP_CURVE_TYPES)
        return types[j] in STEP_CURVE_TYPES

    mixed: list[str] = []
    for j, kind in enumerate(types):
        refs = refs_per[j]
        if kind == "PCURVE" and len(refs) >= 2 and (d := at.get(refs[1])) is not None \
                and types[d] == "DEFINITIONAL_REPRESENTATION" and len(refs_per[d]) >= 2:
            item = at.get(refs_per[d][0])
            if item is not None and not is_curve(item):
                raise ExchangeError(f"{p}: damaged STEP file (#{ids[j]} PCURVE: its representation #{ids[d]} holds "
                                    f"#{ids[item]} {types[item]}, not a curve; refused: OCC's reader crashes on "
                                    "such p-curves)")
            if item is None:
                continue
            dims = dims_of(refs_per[item]) - {2}
            if dims:
                mixed.append(f"#{ids[j]} PCURVE: its curve #{ids[item]} {types[item]} has points of "
                             f"{' and '.join(map(str, sorted(dims)))} coordinates, not 2 (OCC reads it without a word)")
        elif kind == "VERTEX_POINT" and refs and (q := at.get(refs[0])) is not None:
            n = coords(q)
            if n is not None and n < 3:
                raise ExchangeError(f"{p}: damaged STEP file (#{ids[j]} VERTEX_POINT: its point #{ids[q]} has {n} "
                                    "coordinates, not 3; refused: OCC's reader crashes on such vertices)")
        elif (word := next((w for w in _SPLINE_WORDS if w in texts[j]), None)) is not None:
            dims = dims_of(refs)
            if len(dims) > 1:
                mixed.append(f"#{ids[j]} {word.decode()}: its poles mix points of {' and '.join(map(str, sorted(dims)))} "
                             "coordinates (OCC reads them without a word)")
    return limited_lines(mixed, "curves with points of the wrong dimension")


class _TypeCount(Counter[str]):
    closed_shells: list[int]
    ids: list[int]


def _kept_types(data: bytes) -> _TypeCount:
    masked = _masked(data)
    out = _TypeCount()
    out.closed_shells, out.ids = [], []
    for m in re.finditer(rb"#(\d+)\s*=\s*(?:([A-Za-z_][A-Za-z0-9_]*)\s*)?\(", masked):
        out.ids.append(int(m.group(1)))
        t = (m.group(2) or b"").decode("ascii").upper()
        out[t] += 1
        if t == "CLOSED_SHELL":
            out.closed_shells.append(int(m.group(1)))
    return out


def _attribute_depth(text: bytes, at: int) -> int:
    """Paren depth of an instance's own attributes: 1, or 2 in a complex instance ``( A(..) B(..) )``."""
    return 2 if text[at:at + 1] == b"(" else 1


def _remove_refs(text: bytes, body_at: int, gone: set[int]) -> tuple[list[tuple[int, int]] | None, list[int],
                                                                   int | None]:
    """Where the references to ``gone`` sit in the lists of one (masked) record.

    Returns ``(spans to cut, or None if the record itself must go, ids removed from lists, the id of an
    attribute that dangles)``."""
    top = _attribute_depth(text, body_at)
    depth = 0
    cut: list[tuple[int, int]] = []
    removed: list[int] = []
    i = body_at
    n = len(text)
    while i < n:
        c = text[i]
        if c == 40:
            depth += 1
        elif c == 41:
            depth -= 1
        elif c == 35:
            j = i + 1
            while j < n and 48 <= text[j] <= 57:
                j += 1
            ref = int(text[i + 1:j]) if j > i + 1 else None
            if ref is not None and ref in gone:
                if depth <= top:
                    return None, removed, ref
                a, b = i, j  # drop the element with one neighbouring comma
                k = b
                while k < n and text[k] in b" \t\r\n":
                    k += 1
                if k < n and text[k] == 44:
                    b = k + 1
                else:
                    k = a - 1
                    while k > body_at and text[k] in b" \t\r\n":
                        k -= 1
                    if text[k] == 44:
                        a = k
                cut.append((a, b))
                removed.append(ref)
            i = j
            continue
        i += 1
    return cut, removed, None


def _cut(text: bytes, spans: list[tuple[int, int]]) -> bytes:
    out = bytearray()
    last = 0
    for a, b in spans:
        out += text[last:a]
        last = b
    out += text[last:]
    return bytes(out)


def _prune(data: bytes, starts: list[int], semis: list[int], rec_of: list[int], ids: np.ndarray, types: list[str],
           refs_per: list[list[int]], missing: set[int], broken: dict[int, str]) -> tuple[bytes, list[str]]:
    """The file without its dangling references and ``broken`` instances (see the module docstring),
    and a warning per removal."""
    users: dict[int, list[int]] = {}
    for j, refs in enumerate(refs_per):
        for r in set(refs):
            users.setdefault(r, []).append(j)
    gone = set(missing) | set(broken)
    todo = sorted({j for r in gone for j in users.get(r, ())})
    new_text: dict[int, bytes | None] = {}
    dangling: list[str] = []
    dropped: list[str] = []
    for j, ident in enumerate(ids.tolist()):
        if ident in broken:
            new_text[j] = None
            dropped.append(f"#{ident} {types[j]}: removed, {broken[ident]}")
    while todo:
        nxt: set[int] = set()
        for j in todo:
            k = rec_of[j]
            current = new_text.get(j, data[starts[k]:semis[k]])
            if current is None:  # removed already
                continue
            masked_current = _masked(current)
            d = _DEF.match(masked_current)
            if d is None:  # cannot happen: the record matched _DEF when read, and cuts leave its ``#id =`` alone
                raise AssertionError(f"#{ids[j]}: record lost its '#id =' head while pruning")
            body_at = d.end()
            spans, removed, attr = _remove_refs(masked_current, body_at, gone)
            label = f"#{ids[j]} {types[j]}"
            if spans is None:
                new_text[j] = None
                why = "undefined" if attr in missing else "removed"
                dropped.append(f"{label}: removed, its attribute refers to #{attr} ({why})")
                if int(ids[j]) not in gone:
                    gone.add(int(ids[j]))
                    nxt.update(users.get(int(ids[j]), ()))
                continue
            new_text[j] = _cut(current, spans)  # masking keeps offsets: the spans hold in the real text
            for r in removed:
                why = "undefined in the file" if r in missing else "removed"
                dangling.append(f"{label}: reference to #{r} ({why}) dropped from its list")
        todo = sorted(nxt)
    out = bytearray(data[:starts[0]] if starts else data)
    last = starts[0] if starts else len(data)
    for j, text in sorted(new_text.items(), key=lambda kv: starts[rec_of[kv[0]]]):
        k = rec_of[j]
        out += data[last:starts[k]]
        if text is not None:
            out += text
            last = semis[k]
        else:
            last = semis[k] + 1
    out += data[last:]
    head = [f"{len(missing)} referenced instances are not defined in the file (truncated or edited?): "
            + ", ".join(f"#{r}" for r in sorted(missing)[:8]) + (" ..." if len(missing) > 8 else "")] if missing else []
    return bytes(out), head + limited_lines(dropped, "instances removed") + limited_lines(dangling, "references dropped")
